"""pp5sim from Python: the Pixel-Planes 5 simulator as sessions, frames, sweeps and programs.

    import pp5sim
    frame = pp5sim.Session("torus", config={"screen.width": 256, "screen.height": 256}).frame(fields=["z"])
    frame.image            # (height, width, 3) uint8, from the frame buffer
    frame.fields["z"]      # (height, width), read from the simulated pixel memory
    frame.stats["frame"]   # the statistics, nested as stats.json nests them
    frame.rates            # projected rates and the bottleneck

docs/guides/python.md documents every part with an example.
"""

import json as _json
import os as _os

from . import _pp5sim as _c

__all__ = [
    "Session",
    "Frame",
    "Program",
    "sweep",
    "read_sweep",
    "assemble",
    "describe_statistics",
    "describe_config",
    "scenes",
    "programs",
]

Program = _c.Program


def _sets(config):
    """A configuration dict as --set assignments (KEY, VALUE text), in the dict's order."""
    if config is None:
        return []
    if not isinstance(config, dict):
        raise TypeError("config: expected a dict of KEY: VALUE, e.g. {'gp.count': 8}")
    out = []
    for key, value in config.items():
        if not isinstance(key, str):
            raise TypeError(f"config: key {key!r} is not a string")
        out.append((key, _text(value)))
    return out


def _firmware(firmware):
    return "" if firmware is None else str(firmware)


def scenes():
    """The built-in scene names."""
    return list(_c.builtin_scenes())


def programs():
    """The built-in firmware programs' names."""
    return list(_c.builtin_programs())


def describe_config():
    """Every configuration key: unit, default, range, calibration and description (a DataFrame)."""
    import pandas as pd

    return pd.DataFrame(_c.describe_config()).set_index("key")


def describe_statistics(firmware="phong", fidelity=""):
    """What every statistic is: {pattern: {kind, unit, description}}, indices written N."""
    return _c.describe_statistics(firmware, _c.fidelity_assignments(fidelity) if fidelity else [])


def assemble(firmware, config=None, scene="torus", config_file=""):
    """Assembles a program (a built-in name, a .pp5 path, or program text holding a newline)
    for the machine `config` describes; its cycles are priced with `scene`'s frame parameters."""
    return _c.assemble(_firmware(firmware), config_file, _sets(config), scene)


class Frame:
    """One simulated frame: image, pixel-memory fields, statistics, bit budget, rates."""

    def __init__(self, raw):
        self._raw = raw
        self._stats = None

    index = property(lambda self: self._raw.index, doc="The frame's number in its session (0 first)")
    image = property(lambda self: self._raw.image,
                     doc="(height, width, 3) uint8 RGB from the frame buffer; None when timing only")
    fields = property(lambda self: self._raw.fields,
                      doc="{name: (height, width) array} of the fields asked for, from pixel memory")

    def field(self, name):
        """One field asked for with Session.frame(fields=[...])."""
        try:
            return self._raw.fields[name]
        except KeyError:
            raise KeyError(f"field '{name}' was not read; ask for it: session.frame(fields=['{name}'])") from None

    @property
    def stats(self):
        """The statistics as nested dicts (stats.json's document)."""
        if self._stats is None:
            self._stats = self._raw.stats_json
        return self._stats

    @property
    def statistics(self):
        """Every statistic by its full name, typed (int, float, str), in registration order."""
        return self._raw.statistics

    @property
    def info(self):
        """{full name: {kind, unit, description}} for every statistic of the frame."""
        return self._raw.statistics_info

    def stat(self, name):
        """One statistic by name, e.g. frame.stat('timing.bottleneck')."""
        return self._raw.stat(name)

    frame_seconds = property(lambda self: self._raw.frame_seconds, doc="Simulated frame time")
    triangles_per_second = property(lambda self: self._raw.triangles_per_second,
                                    doc="The real machine's projected rate")
    bottleneck = property(lambda self: self._raw.stat("timing.bottleneck"), doc="gp, ring or renderer")
    rates = property(lambda self: self._raw.rates,
                     doc="The projected rates, unit times and bottleneck (sweep.csv's columns)")
    bit_budget = property(lambda self: self._raw.bit_budget, doc="The program's pixel-memory bits")
    bit_budget_table = property(lambda self: self._raw.bit_budget_table,
                                doc="The bit-budget table pp5sim render prints")
    summary = property(lambda self: self._raw.summary, doc="The summary pp5sim render prints")

    def __repr__(self):
        return (f"<pp5sim.Frame {self.index}: {self.frame_seconds * 1e3:.3f} ms, "
                f"{self.triangles_per_second:,.0f} triangles/s, bottleneck {self.bottleneck}>")


class Session:
    """A simulation that persists across frames: one machine, one scene, one program.

    scene: a built-in name, a mesh or scene file; or geometry as arrays: vertices (N, 3) with
    triangles (M, 3) and colors (N, 3) in [0, 1], and/or sphere_centers (K, 3) with
    sphere_radii (K,) and sphere_colors (K, 3). firmware: a built-in name, a .pp5 path or
    program text (it holds a newline); default the scene's, else phong. config: {KEY: VALUE}
    with the keys, ranges and messages of --set (a bad one raises ValueError). fidelity: as
    --fidelity ('bit', 'word', 'timing', 'analytic', or items). threads: host threads (0: all).
    animation=True: frame k draws frame k of the scene's animation, as `pp5sim animate` does
    (the torus turning in 4-space, another built-in turning, a scene file's keyframes); frames
    and fps as its --frames and --fps; session.frames() then iterates over them.
    """

    def __init__(self, scene="torus", *, firmware=None, config=None, config_file="", fidelity="",
                 threads=0, tessellation=None, vertices=None, triangles=None, colors=None,
                 sphere_centers=None, sphere_radii=None, sphere_colors=None, animation=False,
                 frames=None, fps=None):
        if not isinstance(scene, (str, _os.PathLike)):
            raise TypeError("scene: expected a built-in name or a file path; give arrays as "
                            "vertices=..., triangles=... or sphere_centers=..., sphere_radii=...")
        self._s = _c.Session(
            _os.fspath(scene), vertices, triangles, colors, sphere_centers, sphere_radii,
            sphere_colors, list(tessellation or []), _firmware(firmware), config_file,
            fidelity or "", _sets(config), int(threads), bool(animation), int(frames or 0),
            float(fps or 0))

    def frame(self, fields=(), pixels=True):
        """Simulates the next frame. fields: pixel-memory fields to read over the whole screen
        (e.g. ['z']); pixels=False simulates its timing only."""
        if isinstance(fields, str):
            fields = [fields]
        return Frame(self._s.frame(list(fields), bool(pixels)))

    def frames(self, n=None, fields=(), pixels=True):
        """Iterates over the next n frames (without n, until the loop stops; an animation's, to
        its last frame). Ctrl-C raises KeyboardInterrupt. An animated session that has run no
        frame yet runs all its frames overlapped, as `pp5sim animate` does (the GPs set up
        frame n + 1 while the Renderers draw frame n; summary then holds the sustained
        figures), unless fields are asked for or n is fewer than its frames."""
        if n is None and self.animation is not None:
            n = self.animation["frames"] - self.frames_run
        if (self.animation is not None and self.frames_run == 0 and not fields
                and n == self.animation["frames"]):
            for f in self._s.run_animation(bool(pixels)):
                yield Frame(f)
            return
        count = 0
        while n is None or count < n:
            yield self._next_frame(fields, pixels)
            count += 1

    def _next_frame(self, fields, pixels):
        # One frame of the sequence; an animated session's C++ half gives it its frame's scene.
        return self.frame(fields, pixels)

    def __iter__(self):
        return self.frames()

    def why(self, x, y):
        """Simulates a frame recording pixel (x, y) and explains its final value, as
        `pp5sim trace why` does (needs the bit level)."""
        return self._s.why(int(x), int(y))

    def close(self):
        """Frees the machine now (it is made again if another frame is asked for)."""
        self._s.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    frames_run = property(lambda self: self._s.frames, doc="Frames simulated so far")
    summary = property(lambda self: self._s.summary, doc="The run's summary over its frames")
    config = property(lambda self: self._s.config, doc="The whole configuration (config.json)")
    program = property(lambda self: self._s.program, doc="The assembled Program")
    scene_name = property(lambda self: self._s.scene_name)
    threads = property(lambda self: self._s.threads)
    animation = property(lambda self: self._s.animation,
                         doc="{name, motion, frames, fps} of an animated session, else None")

    def __repr__(self):
        return (f"<pp5sim.Session scene {self.scene_name}, program {self.program.name}, "
                f"{self.frames_run} frames>")


def _text(value):
    """One configuration value as --set text: Python's and NumPy's bools as true/false, NumPy
    scalars as their Python values."""
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:
        value = value.item()  # a NumPy scalar or 0-d array
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _values(key, values):
    """A key's values in a grid: a list, tuple, range, 1-D NumPy array or pandas Series, or
    one value."""
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        return [_text(values)]
    if getattr(values, "ndim", 1) == 0:
        return [_text(values)]
    if getattr(values, "ndim", 1) != 1:
        raise ValueError(f"grid: the values of '{key}' are an array of shape "
                         f"{tuple(values.shape)}; expected one dimension")
    return [_text(v) for v in values]


def sweep(points, scene="torus", *, firmware=None, config=None, config_file="", fidelity="",
          threads=0, tessellation=None):
    """Simulates one frame per point and returns a pandas DataFrame: one row per point with
    the swept keys, sweep.csv's columns and every statistic by name, typed.

    points: a grid {KEY: values} whose product is swept (the first key varying slowest, as
    pp5sim sweep), each key's values a list, range, NumPy array or pandas Series (or one
    value); or a pandas DataFrame (or a list of dicts) whose rows are the points, in order,
    its columns the keys. Keys and values are checked as pp5sim sweep checks --grid: a bad
    one raises ValueError naming the key. Ctrl-C stops the sweep within milliseconds."""
    import pandas as pd

    if isinstance(points, list) and points and all(isinstance(p, dict) for p in points):
        points = pd.DataFrame(points)
    if isinstance(points, pd.DataFrame):
        if points.empty or len(points.columns) == 0:
            raise ValueError("points: the DataFrame has no rows or no columns")
        keys = list(points.columns)
        for key in keys:
            if not isinstance(key, str):
                raise TypeError(f"points: column {key!r} is not a configuration key")
        rows = [[_text(v) for v in row] for row in points.itertuples(index=False, name=None)]
        axes = []
        for k, key in enumerate(keys):
            distinct = list(dict.fromkeys(row[k] for row in rows))  # in order, once each
            axes.append((key, distinct))
    elif isinstance(points, dict) and points:
        axes = []
        for key, values in points.items():
            if not isinstance(key, str):
                raise TypeError(f"grid: key {key!r} is not a string")
            axes.append((key, _values(key, values)))
        rows = []
    else:
        raise ValueError("points: expected a dict {KEY: [values]} (e.g. {'gp.count': [1, 2, 4]})"
                         " or a DataFrame with a column per key and a row per point")
    u, v = (tessellation or (0, 0))
    out = _c.sweep(_os.fspath(scene), int(u), int(v), _firmware(firmware), config_file,
                   fidelity or "", _sets(config), axes, rows, int(threads))
    return pd.DataFrame(out)


def read_sweep(path):
    """A sweep run by the command line (locally or on Slurm) as a DataFrame: a sweep.csv
    (`pp5sim sweep aggregate`) gives its columns; a sweep's folder gives what sweep() gives,
    every statistic included, from each run's config.json and stats.json."""
    import pandas as pd

    path = _os.fspath(path)
    if not _os.path.isdir(path):
        return pd.read_csv(path)
    with open(_os.path.join(path, "sweep.json")) as f:
        spec = _json.load(f)
    keys = spec["order"]
    grid = spec["grid"]
    import itertools

    rows = []
    for values in itertools.product(*(grid[k] for k in keys)):
        run = _os.path.join(path, "_".join(f"{k}-{v}" for k, v in zip(keys, values)))
        stats_path = _os.path.join(run, "stats.json")
        if not _os.path.exists(stats_path):
            raise FileNotFoundError(f"{stats_path}: no stats.json (not run yet?)")
        with open(_os.path.join(run, "config.json")) as f:
            config = _json.load(f)
        with open(stats_path) as f:
            stats = _c.statistics_from_json(f.read(), stats_path)
        row = {}
        for k in keys:
            section, name = k.split(".", 1)
            row[k] = config[section][name]
        for column, name in _CSV_COLUMNS:
            row[column] = stats[name]
        row["fidelity_pixels"] = config.get("fidelity", {}).get("pixels", "bit")
        row["fidelity_timing"] = config.get("fidelity", {}).get("timing", "event")
        for name, value in stats.items():
            row.setdefault(name, value)
        rows.append(row)
    return pd.DataFrame(rows)


# sweep.csv's metric columns and the statistics they hold (pp5sim sweep aggregate).
_CSV_COLUMNS = [
    ("frame_seconds", "frame.simulated_seconds"),
    ("triangles_per_second", "frame.projected_triangles_per_second"),
    ("pipelined_triangles_per_second", "frame.pipelined_triangles_per_second"),
    ("gp_clocks_per_triangle", "frame.gp_clocks_per_triangle"),
    ("bottleneck", "timing.bottleneck"),
    ("gp_seconds", "timing.gp_seconds"),
    ("ring_seconds", "timing.ring_seconds"),
    ("renderer_seconds", "timing.renderer_seconds"),
    ("gp_utilisation", "timing.gp_utilisation_mean"),
    ("ring_utilisation", "timing.ring_utilisation"),
    ("renderer_utilisation", "timing.renderer_utilisation_mean"),
]
