#!/usr/bin/env python3
"""The Python module's cost over the command line's, measured in one run (a ratio, never an
assertion: a timed test would fail on a loaded machine).

For the default torus (1280 x 1024, phong, the default machine) at the same thread count:
  - CLI: `pp5sim render`'s own host time for the frame (stats.json's host.seconds: the
    machine's elaboration and the frame, timing and pixels; not the process start, the scene's
    construction, the assembly or the PNG);
  - Python: wall time from before pp5sim.Session(...) to the frame's image as a NumPy array
    (scene construction, assembly, elaboration, the frame, the image copied into the array; the
    session is freed after the clock stops), and the same with the z field read from pixel
    memory as well.
Runs alternate; each figure is the fastest of RUNS, and the run-by-run ratio's median.
NumPy's import and the module's first frame are paid once before the runs.
Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [build/pp5sim] [runs=3] [threads=2]
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import pp5sim


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "build/pp5sim"
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    threads = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    cli, py, py_frame_host, py_z = [], [], [], []
    # Once per process, not per frame: NumPy's import and the first array.
    pp5sim.Session(config={"screen.width": 128, "screen.height": 128}).frame()
    with tempfile.TemporaryDirectory(prefix="pp5-bench-python-") as scratch:
        for run in range(runs):
            out = os.path.join(scratch, f"cli{run}")
            subprocess.run([exe, "render", "--threads", str(threads), "--out", out], check=True,
                           stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
            with open(os.path.join(out, "stats.json")) as f:
                cli.append(json.load(f)["host"]["seconds"])
            # The session is freed after the clock stops, as the command line's host.seconds
            # leaves out its own exit.
            t0 = time.perf_counter()
            session = pp5sim.Session(threads=threads)
            frame = session.frame()
            image = frame.image
            py.append(time.perf_counter() - t0)
            py_frame_host.append(frame.stat("host.seconds"))
            assert image.shape == (1024, 1280, 3)
            del session, frame, image
            t0 = time.perf_counter()
            session = pp5sim.Session(threads=threads)
            frame = session.frame(fields=["z"])
            z = frame.fields["z"]
            py_z.append(time.perf_counter() - t0)
            del session, frame, z
    c, p, h, z = min(cli), min(py), min(py_frame_host), min(py_z)
    paired = sorted(b / a for a, b in zip(cli, py))
    print(f"torus 1280x1024, phong, {threads} threads, fastest of {runs}:")
    print(f"  CLI host.seconds (pp5sim render)              {c:.3f} s")
    print(f"  Python Session().frame().image, wall          {p:.3f} s   ratio {p / c:.3f}")
    print(f"  Python frame's own host.seconds               {h:.3f} s   ratio {h / c:.3f}")
    print(f"  Python with the z field from pixel memory     {z:.3f} s   ratio {z / c:.3f}")
    print(f"  Python wall / CLI host.seconds, run by run: median {paired[len(paired) // 2]:.3f} "
          f"(from {paired[0]:.3f} to {paired[-1]:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
