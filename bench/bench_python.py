#!/usr/bin/env python3
"""The Python module's cost over the command line's, measured in one run (ratios, never an
assertion: a timed test would fail on a loaded machine).

For the default torus (1280 x 1024, phong, the default machine) at the same thread count, like
is compared with like, each side's parts read from its own statistics:
  - set-up: host.setup_seconds, making the scene and assembling the program (pp5sim render's;
    the Python session's, reported by its first frame);
  - frame: host.seconds, the machine's elaboration and the frame, timing and pixels;
  - compute: set-up + frame, the command line's whole work for the frame (not the process
    start, the configuration, the PNG or stats.json);
  - Python's call: wall time from before pp5sim.Session(...) to the frame's image as a NumPy
    array (the configuration, set-up, frame, the image copied into the array; the session is
    freed after the clock stops), against the command line's compute. What lies outside the
    set-up and the frame is Python's own (the binding, the configuration, the copy): printed.
  - the same call with the z field read from pixel memory as well.
Runs alternate; each figure is the fastest of RUNS, and each ratio is also taken run by run
(median and range). NumPy's import and the module's first frame are paid once before the runs.
Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [build/pp5sim] [runs=5] [threads=2]
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import pp5sim


def spread(ratios):
    r = sorted(ratios)
    return f"median {r[len(r) // 2]:.3f} (from {r[0]:.3f} to {r[-1]:.3f})"


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "build/pp5sim"
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    threads = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    cli = {"setup": [], "frame": []}
    py = {"setup": [], "frame": [], "call": [], "z": []}
    # Once per process, not per frame: NumPy's import and the first array.
    pp5sim.Session(config={"screen.width": 128, "screen.height": 128}).frame()
    with tempfile.TemporaryDirectory(prefix="pp5-bench-python-") as scratch:
        for run in range(runs):
            out = os.path.join(scratch, f"cli{run}")
            subprocess.run([exe, "render", "--threads", str(threads), "--out", out], check=True,
                           stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
            with open(os.path.join(out, "stats.json")) as f:
                host = json.load(f)["host"]
            cli["setup"].append(host["setup_seconds"])
            cli["frame"].append(host["seconds"])
            # The session is freed after the clock stops, as the command line's figures leave
            # out its own exit.
            t0 = time.perf_counter()
            session = pp5sim.Session(threads=threads)
            frame = session.frame()
            image = frame.image
            py["call"].append(time.perf_counter() - t0)
            py["setup"].append(frame.stat("host.setup_seconds"))
            py["frame"].append(frame.stat("host.seconds"))
            assert image.shape == (1024, 1280, 3)
            del session, frame, image
            t0 = time.perf_counter()
            session = pp5sim.Session(threads=threads)
            frame = session.frame(fields=["z"])
            z = frame.fields["z"]
            py["z"].append(time.perf_counter() - t0)
            del session, frame, z
    cli["compute"] = [a + b for a, b in zip(cli["setup"], cli["frame"])]
    py["compute"] = [a + b for a, b in zip(py["setup"], py["frame"])]
    py["outside"] = [c - s for c, s in zip(py["call"], py["compute"])]
    best = {k: min(v) for k, v in cli.items()}
    pbest = {k: min(v) for k, v in py.items()}

    def row(label, c, p, key_c, key_p):
        paired = [b / a for a, b in zip(cli[key_c], py[key_p])]
        print(f"  {label:<34} {c:7.3f} s {p:7.3f} s  {p / c:6.3f}   {spread(paired)}")

    print(f"torus 1280x1024, phong, {threads} threads, fastest of {runs} (run by run: the ratio's")
    print("median and range):")
    print(f"  {'':<34} {'CLI':>9} {'Python':>9}  {'ratio':>6}")
    row("set-up (host.setup_seconds)", best["setup"], pbest["setup"], "setup", "setup")
    row("frame (host.seconds)", best["frame"], pbest["frame"], "frame", "frame")
    row("compute (set-up + frame)", best["compute"], pbest["compute"], "compute", "compute")
    row("Python's call / CLI compute", best["compute"], pbest["call"], "compute", "call")
    row("  with the z field", best["compute"], pbest["z"], "compute", "z")
    print(f"  Python's own, outside set-up and frame: {pbest['outside'] * 1e3:.1f} ms at fastest "
          f"({pbest['outside'] / best['compute'] * 100:.1f}% of the CLI's compute)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
