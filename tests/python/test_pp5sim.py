"""The Python module against the command line, the pixel memory and itself."""
import os
import signal
import threading
import time

import numpy as np
import pandas as pd
import pytest

import pp5sim
from conftest import SMALL, TESSELLATION, cli_sets, run_cli


def small_session(**kw):
    config = dict(SMALL)
    config.update(kw.pop("config", {}))
    kw.setdefault("tessellation", TESSELLATION)
    return pp5sim.Session(kw.pop("scene", "torus"), config=config, **kw)


@pytest.fixture(scope="module")
def torus_frame():
    return small_session(threads=2).frame(fields=["z", "red", "green", "blue", "covered", "nx"])


@pytest.fixture(scope="module")
def cli_torus(tmp_path_factory, pp5sim_exe):
    out = tmp_path_factory.mktemp("cli") / "torus"
    run_cli(pp5sim_exe, "render", "--scene", "torus", "--tessellation", *map(str, TESSELLATION),
            *cli_sets(SMALL), "--threads", "2", "--out", str(out))
    return out


def test_image_is_the_command_lines(torus_frame, cli_torus):
    import matplotlib.image

    png = matplotlib.image.imread(str(cli_torus / "frame.png"))
    png = np.round(png[..., :3] * 255).astype(np.uint8)
    assert torus_frame.image.shape == (100, 200, 3)
    assert torus_frame.image.dtype == np.uint8
    assert np.array_equal(torus_frame.image, png)


def test_statistics_are_the_command_lines(torus_frame, cli_torus):
    import json

    with open(cli_torus / "stats.json") as f:
        cli = json.load(f)
    ours = torus_frame.stats
    assert ours["frame"] == cli["frame"]
    assert ours["timing"] == cli["timing"]
    assert torus_frame.stat("frame.simulated_seconds") == cli["frame"]["simulated_seconds"]


def test_output_fields_from_pixel_memory_are_the_image(torus_frame):
    # red, green and blue are phong's output fields: read from pixel memory region by region,
    # they must give the frame buffer's image, region edges and the cut last column included.
    for channel, name in enumerate(["red", "green", "blue"]):
        field = torus_frame.fields[name]
        assert field.shape == (100, 200)
        assert field.dtype == np.uint8
        assert np.array_equal(field, torus_frame.image[..., channel]), name


def test_z_and_flags(torus_frame):
    z = torus_frame.field("z")
    covered = torus_frame.field("covered")
    assert z.dtype == np.uint32  # 24 bits
    assert covered.dtype == np.uint8
    assert set(np.unique(covered)) == {0, 1}
    # Uncovered pixels keep clear's depth, the farthest; covered ones are nearer.
    far = z[covered == 0]
    assert far.min() == far.max()
    assert z[covered == 1].max() < far.max()
    assert 0.05 < covered.mean() < 0.95
    # A signed field comes out signed, with negative values where normals point left.
    nx = torus_frame.field("nx")
    assert nx.dtype == np.int8
    assert nx[covered == 1].min() < 0 < nx[covered == 1].max()


def test_a_narrow_signed_field_is_sign_extended():
    # gouraud with a 5-bit signed field that clear sets to -3 (bits 11101): an int8 of -3, not 29.
    with open(pp5sim._c.resolve_firmware("gouraud")) as fh:
        text = fh.read()
    assert "field blue    8" in text and "  mov blue, background_blue\n" in text
    text = text.replace("field blue    8", "field blue    8\nfield s       5 signed")
    text = text.replace("  mov blue, background_blue\n", "  mov blue, background_blue\n  mov s, -3\n", 1)
    s = small_session(firmware=text).frame(fields=["s"]).fields["s"]
    assert s.dtype == np.int8
    assert (s == -3).all()


def test_statistics_info_rates_and_budget(torus_frame):
    info = torus_frame.info
    assert info["frame.simulated_seconds"]["unit"] == "simulated seconds"
    assert info["frame.simulated_seconds"]["description"]
    flat = torus_frame.statistics
    assert flat["frame.simulated_seconds"] == torus_frame.stats["frame"]["simulated_seconds"]
    assert isinstance(flat["timing.bottleneck"], str)
    assert torus_frame.bottleneck in ("gp", "ring", "renderer", "GPs", "Renderers", "ring")
    rates = torus_frame.rates
    assert rates["triangles_per_second"] == torus_frame.triangles_per_second > 0
    assert rates["bottleneck"] == torus_frame.bottleneck
    budget = torus_frame.bit_budget
    program = pp5sim.assemble("phong")
    assert budget["bits_used"] == program.bit_budget["bits_used"]
    assert budget["field_bits"] + budget["scratch_bits"] + budget["spilled_bits"] == sum(
        f["width"] for f in program.fields)
    assert "bits" in torus_frame.bit_budget_table


def test_bad_key_is_a_value_error_with_the_command_lines_message(pp5sim_exe):
    for config in ({"foo.bar": 1}, {"gp.count": 0}):
        cli = run_cli(pp5sim_exe, "render", *cli_sets(config), "--out", "/nonexistent/x",
                      check=False)
        assert cli.returncode != 0
        message = cli.stderr.strip().splitlines()[-1].removeprefix("pp5sim: error: ")
        with pytest.raises(ValueError) as e:
            pp5sim.Session(config=config)
        assert str(e.value) == message
        key = next(iter(config))
        assert key in str(e.value)


def test_other_errors():
    with pytest.raises(ValueError, match="no field 'nonesuch'"):
        small_session().frame(fields=["nonesuch"])
    with pytest.raises(ValueError, match="timing-only"):
        small_session(fidelity="timing").frame(fields=["z"])
    with pytest.raises(RuntimeError, match="no built-in program"):
        pp5sim.Session(firmware="nonesuch")
    with pytest.raises(ValueError, match="unknown"):
        pp5sim.Session("nonesuch-scene")
    with pytest.raises(ValueError, match="triangles: row 0 has vertex index 5"):
        pp5sim.Session(vertices=np.zeros((3, 3)), triangles=[[0, 1, 5]])
    with pytest.raises(ValueError, match=r"vertices: expected an array of shape \(N, 3\)"):
        pp5sim.Session(vertices=np.zeros((3, 2)), triangles=[[0, 1, 2]])


def test_frames_in_sequence():
    s = small_session()
    frames = list(s.frames(3))
    assert [f.index for f in frames] == [0, 1, 2]
    assert s.frames_run == 3
    for f in frames[1:]:
        assert np.array_equal(f.image, frames[0].image)
        assert f.frame_seconds == frames[0].frame_seconds
    summary = s.summary
    assert summary["frames"] == 3
    assert summary["simulated_seconds"] == pytest.approx(3 * frames[0].frame_seconds)
    it = iter(s)
    assert next(it).index == 3


def test_sessions_interleave_each_on_its_own_kernel():
    a = small_session()
    b = small_session(firmware="gouraud")
    fa = a.frame()
    fb = b.frame()
    fa2 = a.frame()  # on a's machine, made once: its frame 1
    fb2 = b.frame()
    assert np.array_equal(fa.image, fa2.image)
    assert fa.frame_seconds == fa2.frame_seconds
    assert np.array_equal(fb.image, fb2.image)
    assert fb.stats["frame"] == fb2.stats["frame"]
    assert not np.array_equal(fa.image, fb.image)
    assert a.summary["frames"] == 2
    # A session freed while another lives; a sweep and a one-frame description between frames.
    c = small_session()
    c.frame()
    del c
    pp5sim.sweep({"gp.count": [2]}, config=SMALL, tessellation=TESSELLATION)
    pp5sim.describe_statistics()
    fa3 = a.frame()
    assert fa3.index == 2
    assert np.array_equal(fa3.image, fa.image)
    assert fa3.stats["frame"] == fa.stats["frame"]
    # A session that is replaced, then a new one: sequential use as in a notebook.
    s = small_session()
    s.frame()
    s = small_session()
    assert np.array_equal(s.frame().image, fa.image)


def test_sessions_on_two_threads_at_once():
    # Two Python threads run frames of two sessions at the same time (each call releases the
    # GIL): SystemC runs one at a time, and each gives its frames' bits.
    expected = {name: small_session(firmware=name).frame() for name in ("phong", "gouraud")}
    sessions = {name: small_session(firmware=name) for name in expected}
    got = {name: [] for name in expected}
    errors = []

    def run(name):
        try:
            for _ in range(3):
                got[name].append(sessions[name].frame())
        except Exception as e:  # reported below, not lost on the thread
            errors.append(e)

    threads = [threading.Thread(target=run, args=(name,)) for name in expected]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for name, frames in got.items():
        assert [f.index for f in frames] == [0, 1, 2]
        for f in frames:
            assert np.array_equal(f.image, expected[name].image), name
            assert f.stats["frame"] == expected[name].stats["frame"], name


def test_threads_do_not_change_results():
    one = small_session(threads=1).frame(fields=["z"])
    two = small_session(threads=2).frame(fields=["z"])
    assert np.array_equal(one.image, two.image)
    assert np.array_equal(one.fields["z"], two.fields["z"])
    assert one.stats["frame"] == two.stats["frame"]


def test_word_level_fields_are_the_bit_levels():
    bit = small_session().frame(fields=["z", "nx"])
    word = small_session(fidelity="word").frame(fields=["z", "nx"])
    for name in ("z", "nx"):
        assert np.array_equal(bit.fields[name], word.fields[name])


def test_geometry_from_arrays():
    # One triangle over the middle of the screen, in pure red.
    vertices = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], dtype=np.float32)
    s = pp5sim.Session(vertices=vertices, triangles=[[0, 1, 2]], colors=[[1, 0, 0]] * 3,
                       config=SMALL)
    f = s.frame(fields=["covered"])
    covered = f.fields["covered"] == 1
    assert covered.sum() > 100
    img = f.image[covered].astype(int)
    assert (img[:, 0] > img[:, 1]).all()  # red dominates where the triangle is
    assert s.summary["frames"] == 1


def test_spheres_from_arrays():
    s = pp5sim.Session(sphere_centers=[[0, 0, 0], [1.5, 0, 0]], sphere_radii=[1, 0.5],
                       sphere_colors=[[0, 0, 1], [0, 1, 0]], config=SMALL)
    f = s.frame()
    assert s.summary["frames"] == 1
    background = f.image[0, 0]
    assert (np.abs(f.image.astype(int) - background).sum(axis=2) > 30).mean() > 0.05


def test_program_text_is_assembled():
    with open(pp5sim._c.resolve_firmware("phong")) as fh:
        text = fh.read()
    by_text = small_session(firmware=text).frame()
    by_name = small_session(firmware="phong").frame()
    assert np.array_equal(by_text.image, by_name.image)


def test_assembler_is_pp5sim_asm(pp5sim_exe):
    program = pp5sim.assemble("phong")
    cli = run_cli(pp5sim_exe, "asm", "phong").stdout
    assert program.listing == cli
    # Every procedure's total cycles, as the listing prints them.
    for name, proc in program.cycles.items():
        assert f"proc {name}\n" in cli
        assert proc["total"] == sum(c for _, _, c, _ in proc["instructions"])
        assert f"  total {proc['total']} cycles" in cli
    z = next(f for f in program.fields if f["name"] == "z")
    assert (z["width"], z["signed"], z["lo"]) == (24, False, 0)


def test_why_is_trace_why(tmp_path, pp5sim_exe):
    x, y = 100, 50
    ours = small_session().why(x, y)
    trace = tmp_path / "t.pp5t"
    run_cli(pp5sim_exe, "trace", "record", "--scene", "torus", "--tessellation",
            *map(str, TESSELLATION), *cli_sets(SMALL), "--pixel", f"{x},{y}", "--out", str(trace))
    cli = run_cli(pp5sim_exe, "trace", "why", str(trace)).stdout
    assert ours == cli
    with pytest.raises(ValueError, match="needs per-bit state"):
        small_session(fidelity="word").why(x, y)


GRID = {"gp.count": [1, 4], "renderer.count": [2, 8]}


def test_sweep_is_a_typed_frame_matching_the_command_lines(tmp_path, pp5sim_exe):
    df = pp5sim.sweep(GRID, tessellation=TESSELLATION, config=SMALL, fidelity="timing")
    assert len(df) == 4
    assert list(df.columns[:3]) == ["gp.count", "renderer.count", "frame_seconds"]
    assert df["gp.count"].tolist() == [1, 1, 4, 4]
    assert df["renderer.count"].tolist() == [2, 8, 2, 8]
    assert str(df["gp.count"].dtype) == "int64"
    assert str(df["frame.simulated_seconds"].dtype) == "float64"
    assert df["bottleneck"].dtype == object
    assert (df["frame_seconds"] == df["frame.simulated_seconds"]).all()
    # One point against a session of its own.
    f = small_session(config={"gp.count": 4, "renderer.count": 2}, fidelity="timing").frame(
        pixels=False)
    assert df.loc[2, "triangles_per_second"] == f.triangles_per_second
    # The command line's sweep and its sweep.csv load into the same columns and values.
    out = tmp_path / "sweep"
    run_cli(pp5sim_exe, "sweep", "--grid", "gp.count=1,4", "--grid", "renderer.count=2,8",
            "--tessellation", *map(str, TESSELLATION), *cli_sets(SMALL), "--fidelity", "timing",
            "--out", str(out))
    run_cli(pp5sim_exe, "sweep", "aggregate", str(out), "-o", str(tmp_path / "sweep.csv"))
    csv = pp5sim.read_sweep(tmp_path / "sweep.csv")
    folder = pp5sim.read_sweep(out)
    for other in (csv, folder):
        key = ["gp.count", "renderer.count"]
        a = df.set_index(key).sort_index()
        b = other.set_index(key).sort_index()
        for column in ("triangles_per_second", "frame_seconds", "bottleneck"):
            if a[column].dtype == object:
                assert a[column].tolist() == b[column].tolist()
            else:
                assert np.allclose(a[column], b[column], rtol=1e-8), column
    # The folder gives every statistic, as sweep() does (in stats.json's order), with the same
    # values but the host's times.
    assert set(folder.columns) == set(df.columns)
    a = df.set_index(["gp.count", "renderer.count"]).sort_index()
    b = folder.set_index(["gp.count", "renderer.count"]).sort_index()
    for column in a.columns:
        if not column.startswith("host."):
            pd.testing.assert_series_equal(a[column], b[column], check_dtype=False)


def test_bad_grid_value_names_the_key():
    with pytest.raises(ValueError, match="gp.count"):
        pp5sim.sweep({"gp.count": [1, 0]}, config=SMALL)


def test_sweep_takes_arrays_and_dataframes():
    kw = dict(config=SMALL, tessellation=TESSELLATION, fidelity="analytic")
    # A product of NumPy arrays and lists, the first key varying slowest: the lists' sweep.
    arrays = pp5sim.sweep({"gp.count": np.arange(1, 4), "renderer.count": np.array([2, 8])}, **kw)
    lists = pp5sim.sweep({"gp.count": [1, 2, 3], "renderer.count": [2, 8]}, **kw)
    pd.testing.assert_frame_equal(arrays.drop(columns=[c for c in arrays if c.startswith("host.")]),
                                  lists.drop(columns=[c for c in lists if c.startswith("host.")]))
    assert arrays["gp.count"].tolist() == [1, 1, 2, 2, 3, 3]
    assert arrays["renderer.count"].tolist() == [2, 8] * 3
    # A DataFrame's rows are the points, in order; a list of dicts is the same.
    points = pd.DataFrame({"gp.count": np.array([3, 1]), "renderer.count": [8, 2]})
    rows = pp5sim.sweep(points, **kw)
    assert rows["gp.count"].tolist() == [3, 1]
    assert rows["renderer.count"].tolist() == [8, 2]
    by_point = lists.set_index(["gp.count", "renderer.count"])
    for _, row in rows.iterrows():
        expected = by_point.loc[(row["gp.count"], row["renderer.count"])]
        assert row["triangles_per_second"] == expected["triangles_per_second"]
    dicts = pp5sim.sweep([{"gp.count": 3, "renderer.count": 8}], **kw)
    assert dicts.loc[0, "triangles_per_second"] == rows.loc[0, "triangles_per_second"]
    with pytest.raises(ValueError, match="one dimension"):
        pp5sim.sweep({"gp.count": np.ones((2, 2), dtype=int)}, **kw)


def test_sweep_errors_are_the_command_lines(tmp_path, pp5sim_exe):
    # Each bad grid gives the message pp5sim sweep gives for --grid, after the place it names.
    cases = [({"gp.count": [1, 0]}, "gp.count=1,0"),
             ({"gp.nonsense": [1]}, "gp.nonsense=1"),
             ({"gp.count": [2, 2]}, "gp.count=2,2"),
             ({"renderer.count": np.array([4, 999])}, "renderer.count=4,999")]
    for grid, cli in cases:
        with pytest.raises(ValueError) as e:
            pp5sim.sweep(grid, config=SMALL)
        r = run_cli(pp5sim_exe, "sweep", "--grid", cli, "--out", str(tmp_path / "s"), check=False)
        assert r.returncode != 0
        cli_message = r.stderr.strip().split(f"--grid {cli}: ", 1)[1]
        assert str(e.value) == f"grid {cli}: {cli_message}", (str(e.value), r.stderr)
        assert list(grid)[0] in str(e.value)
    # A DataFrame's column is checked the same way, named with its distinct values.
    with pytest.raises(ValueError, match=r"^points gp.count=4,0: .*gp.count"):
        pp5sim.sweep(pd.DataFrame({"gp.count": [4, 0, 4]}), config=SMALL)


def test_setup_seconds_are_reported(pp5sim_exe, tmp_path):
    import json

    s = small_session()
    first, second = s.frame(), s.frame()
    assert first.stat("host.setup_seconds") > 0
    assert second.stat("host.setup_seconds") == 0
    assert first.info["host.setup_seconds"]["unit"] == first.info["host.seconds"]["unit"]
    run_cli(pp5sim_exe, "render", "--tessellation", *map(str, TESSELLATION), *cli_sets(SMALL),
            "--out", str(tmp_path / "r"))
    with open(tmp_path / "r" / "stats.json") as f:
        assert json.load(f)["host"]["setup_seconds"] > 0


def test_frames_release_the_gil():
    # A frame of about a tenth of a second on one host thread, run on another Python thread:
    # this thread runs during it only if the frame released the GIL. Its ticks are counted in
    # the middle half of the frame's call, where a frame holding the GIL would allow none.
    s = pp5sim.Session(config={"screen.width": 512, "screen.height": 512}, threads=1)
    s.frame()
    call = []
    done = threading.Event()
    ticks = []

    def run():
        call.append(time.perf_counter())
        s.frame()
        call.append(time.perf_counter())
        done.set()

    t = threading.Thread(target=run)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    start, end = call
    quarter = (end - start) / 4
    inside = [x for x in ticks if start + quarter < x < end - quarter]
    assert len(inside) >= 3, (len(inside), end - start)


# --- Animations ---------------------------------------------------------------------------

ANIMATION = {"screen.width": 128, "screen.height": 128}
ANIMATION_TESSELLATION = (48, 12)
ANIMATION_FRAMES = 3


def animated_session():
    return pp5sim.Session("torus", animation=True, frames=ANIMATION_FRAMES,
                          tessellation=ANIMATION_TESSELLATION, config=ANIMATION, threads=2)


@pytest.fixture(scope="module")
def cli_animation(tmp_path_factory, pp5sim_exe):
    import json

    import matplotlib.image

    out = tmp_path_factory.mktemp("cli") / "animation"
    run_cli(pp5sim_exe, "animate", "--scene", "torus", "--tessellation",
            *map(str, ANIMATION_TESSELLATION), "--frames", str(ANIMATION_FRAMES),
            *cli_sets(ANIMATION), "--threads", "2", "--no-timeline", "--out", str(out))
    images = []
    for k in range(ANIMATION_FRAMES):
        png = matplotlib.image.imread(str(out / f"frame-{k:04d}.png"))
        images.append(np.round(png[..., :3] * 255).astype(np.uint8))
    with open(out / "stats.json") as f:
        stats = json.load(f)["frames"]
    return images, stats


def test_animation_frames_are_pp5sim_animates(cli_animation):
    images, stats = cli_animation
    session = animated_session()
    assert session.animation["frames"] == ANIMATION_FRAMES
    assert "4-space" in session.animation["motion"]
    frames = list(session.frames())  # to the animation's last frame
    assert [f.index for f in frames] == list(range(ANIMATION_FRAMES))
    for k, f in enumerate(frames):
        assert f.image.shape == (128, 128, 3)
        assert np.array_equal(f.image, images[k]), k
        assert f.stats["frame"] == stats[k]["frame"], k
        assert f.stats["timing"] == stats[k]["timing"], k
    # Overlapped, as pp5sim animate runs them: each frame's set-up began before the frame
    # before had ended.
    assert session.summary["overlapped_frames"] == ANIMATION_FRAMES - 1
    assert session.summary["sustained_frame_seconds"] > 0
    # The torus turns: no two frames alike.
    assert not np.array_equal(frames[0].image, frames[1].image)
    assert not np.array_equal(frames[1].image, frames[2].image)
    with pytest.raises(ValueError, match="has 3 frames"):
        session.frame()


def test_animated_session_rebuilt_mid_run_resumes_at_its_frame(cli_animation):
    images, _ = cli_animation
    session = animated_session()
    first = session.frame()
    # Another session runs between frames (each has its own kernel), and the animated session's
    # machine is freed: made again for frame 1's scene at its next frame.
    small_session().frame()
    session.close()
    rest = list(session.frames())
    assert [f.index for f in [first] + rest] == list(range(ANIMATION_FRAMES))
    for k, f in enumerate([first] + rest):
        assert np.array_equal(f.image, images[k]), k


def test_animation_arguments_are_checked():
    with pytest.raises(ValueError, match="without animation=True"):
        pp5sim.Session("torus", frames=3)
    with pytest.raises(ValueError, match="arrays does not move"):
        pp5sim.Session(vertices=np.zeros((3, 3)), triangles=[[0, 1, 2]], animation=True)


# --- Ctrl-C inside a frame ----------------------------------------------------------------


def test_ctrl_c_stops_a_frame_between_regions():
    # A frame at the bit level with a field read, almost all of it pixel execution (about a
    # fifth of a second on one host thread: 320 regions, the timing part some milliseconds);
    # Ctrl-C (SIGINT) a tenth of the way in. Without the check between regions the frame runs
    # to its end before the KeyboardInterrupt.
    session = pp5sim.Session("molecule", config={"screen.width": 1280, "screen.height": 1024},
                             fidelity="bit", threads=1)
    session.frame(pixels=False)  # the machine made, outside the timed frames
    start = time.perf_counter()
    full = session.frame(fields=["z"])
    full_seconds = time.perf_counter() - start
    timer = threading.Timer(0.1 * full_seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        session.frame(fields=["z"])
    interrupted = time.perf_counter() - start
    timer.cancel()
    assert interrupted < 0.5 * full_seconds, (interrupted, full_seconds)
    # The session is usable: the frame interrupted is run again, whole, on a machine made again.
    assert session.frames_run == 2
    again = session.frame(fields=["z"])
    assert again.index == 2
    assert np.array_equal(again.image, full.image)
    assert np.array_equal(again.fields["z"], full.fields["z"])


# Ctrl-C (SIGINT to the main thread, from a timer thread) a tenth of the way into each kind of
# long call: it must stop well before the call's end. Each test fails when its cancel check is
# removed (the call then runs to its end before KeyboardInterrupt).


def interrupted_seconds(call, after):
    main = threading.main_thread().ident
    timer = threading.Timer(after, signal.pthread_kill, (main, signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
        return time.perf_counter() - start
    finally:
        timer.cancel()
        timer.join()


def seconds(call):
    start = time.perf_counter()
    result = call()
    return time.perf_counter() - start, result


def without_host(stats):
    return {k: v for k, v in stats.items() if k != "host"}


def test_ctrl_c_stops_the_systemc_timing_run():
    # A timing-only frame (the SystemC run is all of it: about a quarter of a second on one
    # host thread for 73,728 triangles).
    session = pp5sim.Session("torus", tessellation=(384, 96), fidelity="timing", threads=1)
    session.frame(pixels=False)  # the machine made, outside the timed frames
    full_seconds, full = seconds(lambda: session.frame(pixels=False))
    interrupted = interrupted_seconds(lambda: session.frame(pixels=False), 0.1 * full_seconds)
    assert interrupted < 0.5 * full_seconds, (interrupted, full_seconds)
    assert session.frames_run == 2
    again = session.frame(pixels=False)
    assert again.index == 2
    assert without_host(again.stats) == without_host(full.stats)


def test_ctrl_c_stops_an_analytic_frame():
    # The analytic level with pixels: the model, then the boards executing its regions (about
    # half a second on one host thread).
    config = {"screen.width": 1280, "screen.height": 1024, "fidelity.timing": "analytic",
              "fidelity.pixels": "bit"}
    session = pp5sim.Session("molecule", config=config, threads=1)
    session.frame(pixels=False)
    full_seconds, full = seconds(lambda: session.frame(fields=["z"]))
    interrupted = interrupted_seconds(lambda: session.frame(fields=["z"]), 0.1 * full_seconds)
    assert interrupted < 0.5 * full_seconds, (interrupted, full_seconds)
    again = session.frame(fields=["z"])
    assert again.index == 2
    assert np.array_equal(again.image, full.image)
    assert np.array_equal(again.fields["z"], full.fields["z"])
    assert without_host(again.stats) == without_host(full.stats)


def test_ctrl_c_stops_a_sweep_inside_a_point():
    # Two points of about a quarter of a second each; Ctrl-C a tenth of the way into the first.
    grid = {"gp.count": [4, 8]}
    kw = dict(tessellation=(384, 96), fidelity="timing", threads=1)
    one_seconds, one = seconds(lambda: pp5sim.sweep({"gp.count": [4]}, **kw))
    interrupted = interrupted_seconds(lambda: pp5sim.sweep(grid, **kw), 0.1 * one_seconds)
    assert interrupted < 0.5 * one_seconds, (interrupted, one_seconds)
    # Usable afterwards, with the same results.
    again = pp5sim.sweep({"gp.count": [4]}, **kw)
    assert again.loc[0, "frame_seconds"] == one.loc[0, "frame_seconds"]


def test_ctrl_c_stops_an_animation_frame():
    # An animation's frames of a fifth of a second each, timing only; Ctrl-C inside frame 1.
    def animation():
        return pp5sim.Session("torus", animation=True, frames=3, tessellation=(384, 96),
                              fidelity="timing", threads=1)

    whole = animation()
    whole.frame(pixels=False)
    frame_seconds, f1 = seconds(lambda: whole.frame(pixels=False))
    f2 = whole.frame(pixels=False)
    session = animation()
    frames = session.frames(2, pixels=False)  # frame by frame (not the whole animation)
    next(frames)
    interrupted = interrupted_seconds(lambda: next(frames), 0.1 * frame_seconds)
    assert interrupted < 0.5 * frame_seconds, (interrupted, frame_seconds)
    assert session.frames_run == 1
    # Resumed, the animation's frames are an uninterrupted run's.
    rest = list(session.frames(pixels=False))
    assert [f.index for f in rest] == [1, 2]
    assert without_host(rest[0].stats) == without_host(f1.stats)
    assert without_host(rest[1].stats) == without_host(f2.stats)


def test_ctrl_c_stops_an_overlapped_animation():
    # The whole animation run overlapped (frames() on a fresh animated session: one
    # Session.run_frames); Ctrl-C a tenth of the way in stops it, keeps no frame, and the
    # animation runs again from its first frame with an uninterrupted run's results.
    def animation():
        return pp5sim.Session("torus", animation=True, frames=3, tessellation=(384, 96),
                              fidelity="timing", threads=1)

    run_seconds, whole = seconds(lambda: list(animation().frames(pixels=False)))
    session = animation()
    interrupted = interrupted_seconds(lambda: list(session.frames(pixels=False)),
                                      0.1 * run_seconds)
    assert interrupted < 0.5 * run_seconds, (interrupted, run_seconds)
    assert session.frames_run == 0
    again = list(session.frames(pixels=False))
    assert [f.index for f in again] == [0, 1, 2]
    for a, b in zip(again, whole):
        assert without_host(a.stats) == without_host(b.stats)
