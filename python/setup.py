"""Build hooks of the layerlab package: bundle the C library and its data.

`pip install ./python` (and `python -m build`) run the project's own
`make lib` on the C sources and put into the package
    layerlab/_lib/liblayerlab.so.1          the library (its soname)
    layerlab/_lib/../share/layerlab/ior/    the metals' spectra,
the layout the library expects: it looks for the spectra in
../share/layerlab/ior from its own folder (src/material/ior.c), so the
bundled copy finds them with no environment variable. _native.py loads the
bundled library unless LAYERLAB_LIBRARY or PKG_CONFIG_PATH says otherwise.

The C sources are the repository around python/ (an in-tree build, what pip
does for a local folder), or the copy under python/_csrc/ that the sdist
carries (python -m build makes the wheel from the sdist). The library links
the system's OpenBLAS and LAPACKE (`make deps` installs them; `make lib`
only checks for them and names the package), so the wheel
is tagged for the platform, not for a Python version: ctypes needs no
compiled extension.

LAYERLAB_SKIP_NATIVE=1 builds a package without the library (it then finds
one as before: LAYERLAB_LIBRARY, pkg-config, the system path).
"""

import os
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist
from setuptools.dist import Distribution

try:
    from setuptools.command.bdist_wheel import bdist_wheel
except ImportError:  # setuptools < 70.1 keeps it in the wheel package
    from wheel.bdist_wheel import bdist_wheel

HERE = os.path.dirname(os.path.abspath(__file__))
SONAME = "liblayerlab.so.1"
# What `make lib` needs of the repository; the sdist copies these to _csrc/.
C_TREE = ["Makefile", "src", "include", "data/ior", "scripts/need.sh"]


def c_root():
    """The folder with the Makefile and src/: the repository (in-tree) or
    the sdist's _csrc/ copy."""
    for root in (os.path.join(HERE, "_csrc"), os.path.dirname(HERE)):
        if all(os.path.exists(os.path.join(root, p)) for p in ("Makefile", "src", "include")):
            return root
    raise RuntimeError("layerlab: no C sources found next to python/ (a checkout of the "
                       "repository) nor in python/_csrc (an sdist); cannot build liblayerlab")


def build_library():
    """Run `make lib` in the C tree; the path of its build folder."""
    root = c_root()
    jobs = os.environ.get("LAYERLAB_MAKE_JOBS", "2")
    cmd = ["make", "-C", root, "-j" + jobs, "lib"]
    print("layerlab: building liblayerlab: " + " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    return os.path.join(root, "build")


class BuildPyWithLibrary(build_py):
    """build_py, then the library and the spectra into the package."""

    def run(self):
        super().run()
        if os.environ.get("LAYERLAB_SKIP_NATIVE") == "1":
            return
        build = build_library()
        package = os.path.join(self.build_lib, "layerlab")
        libdir = os.path.join(package, "_lib")
        ior = os.path.join(package, "share", "layerlab", "ior")
        os.makedirs(libdir, exist_ok=True)
        os.makedirs(ior, exist_ok=True)
        # The real file under its soname (the name the loader records).
        shutil.copyfile(os.path.join(build, "lib", SONAME), os.path.join(libdir, SONAME))
        source_ior = os.path.join(build, "share", "layerlab", "ior")
        for name in sorted(os.listdir(source_ior)):
            if name.endswith(".spd"):
                shutil.copyfile(os.path.join(source_ior, name), os.path.join(ior, name))


class SdistWithSources(sdist):
    """An sdist that carries the C sources (python/_csrc/), so that a wheel
    built from it (python -m build) can compile the library."""

    def make_release_tree(self, base_dir, files):
        super().make_release_tree(base_dir, files)
        root = os.path.dirname(HERE)
        target = os.path.join(base_dir, "_csrc")
        for rel in C_TREE:
            src = os.path.join(root, rel)
            dst = os.path.join(target, rel)
            if not os.path.exists(src):
                raise RuntimeError("layerlab sdist: %s is missing from the repository" % src)
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            if os.path.isdir(src):
                shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.o", "build*"))
            else:
                shutil.copy2(src, dst)


class PlatformWheel(bdist_wheel):
    """py3-none-<platform>: the bundled library is native, the Python is not."""

    def finalize_options(self):
        super().finalize_options()
        self.root_is_pure = False

    def get_tag(self):
        _, _, plat = super().get_tag()
        return "py3", "none", plat


class BinaryDistribution(Distribution):
    def has_ext_modules(self):
        return os.environ.get("LAYERLAB_SKIP_NATIVE") != "1"


setup(distclass=BinaryDistribution,
      cmdclass={"build_py": BuildPyWithLibrary, "sdist": SdistWithSources,
                "bdist_wheel": PlatformWheel})
