# The pytest tests of the Python module: run by ctest (label python) with PYTHONPATH pointing at
# BUILD/python and PP5SIM at the build's pp5sim executable.
import os
import subprocess

import pytest

# A small machine: 200 x 100 pixels in 64 x 64 regions (4 x 2, the right and bottom ones cut
# by the screen's edge), and a coarse torus, so that a frame takes a fraction of a second.
SMALL = {"screen.width": 200, "screen.height": 100, "renderer.region_width": 64,
         "renderer.region_height": 64}
TESSELLATION = (24, 8)


def cli_sets(config):
    out = []
    for k, v in config.items():
        out += ["--set", f"{k}={v}"]
    return out


@pytest.fixture(scope="session")
def pp5sim_exe():
    exe = os.environ.get("PP5SIM")
    if not exe or not os.path.exists(exe):
        pytest.skip("PP5SIM does not name the pp5sim executable")
    return exe


def run_cli(exe, *args, check=True):
    r = subprocess.run([exe, *args], capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if check and r.returncode != 0:
        raise AssertionError(f"pp5sim {' '.join(args)} failed: {r.stderr}")
    return r
