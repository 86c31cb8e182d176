#!/usr/bin/env python3
"""`cmake --install` of the build into a scratch prefix, then the installed module from a
scratch folder with PYTHONPATH at PREFIX/lib/python3.X/dist-packages only: it must import, find
the installed firmware programs and mesh reader (not the source tree's or the build's), and
render a small frame. Usage: run_install.py BUILD_DIR"""
import os
import subprocess
import sys
import tempfile

CHECK = r"""
import os, sys, pp5sim
prefix = sys.argv[1]
assert pp5sim.__file__.startswith(prefix), pp5sim.__file__
phong = pp5sim._c.resolve_firmware("phong")
assert phong == os.path.join(prefix, "share/pp5sim/programs/phong.pp5"), phong
mesh = os.path.join(prefix, "share/pp5sim/examples/meshes/knot.obj")
f = pp5sim.Session(mesh, config={"screen.width": 128, "screen.height": 128}).frame()
assert f.image.shape == (128, 128, 3) and f.image.any()
loaded = [l.split()[-1] for l in open("/proc/self/maps") if "libpp5_assimp" in l]
assert loaded and loaded[0].startswith(prefix), loaded
print("installed module:", pp5sim.__file__)
"""


def main():
    build = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="pp5-install-") as scratch:
        prefix = os.path.join(scratch, "prefix")
        subprocess.run(["cmake", "--install", build, "--prefix", prefix], check=True,
                       stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        site = os.path.join(prefix, "lib", f"python{sys.version_info.major}.{sys.version_info.minor}",
                            "dist-packages")
        env = dict(os.environ, PYTHONPATH=site)
        env.pop("PP5_ASSIMP_MODULE", None)
        r = subprocess.run([sys.executable, "-c", CHECK, prefix], cwd=scratch, env=env,
                           stdin=subprocess.DEVNULL)
        return r.returncode


if __name__ == "__main__":
    sys.exit(main())
