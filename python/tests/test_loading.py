"""Finding the library (LAYERLAB_LIBRARY, pkg-config, system path), the
version check, and `pip install ./python` giving a working package. Each
case runs in a fresh interpreter with its own environment."""

import os
import pathlib
import shutil
import subprocess
import sys
import textwrap

import pytest

import layerlab as ll

PACKAGE_DIR = pathlib.Path(ll.__file__).resolve().parents[1]  # python/


def run_python(code, env_changes, cwd="/", pythonpath=str(PACKAGE_DIR)):
    env = {k: v for k, v in os.environ.items() if k not in ("LAYERLAB_LIBRARY", "PYTHONPATH")}
    env.update({k: v for k, v in env_changes.items() if v is not None})
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=120)


def test_relative_library_path_still_finds_the_spectra_after_chdir(tmp_path):
    # The library looks for its metal spectra beside the file it was loaded
    # from; a relative LAYERLAB_LIBRARY must not lose them when the program
    # changes directory afterwards.
    library = pathlib.Path(ll.libraryPath()).resolve()
    relative = os.path.relpath(str(library), str(library.parents[2]))
    code = textwrap.dedent("""
        import os, layerlab as ll
        os.chdir(%r)
        ll.Material.parse("conductor eta=Au alpha=0.2\\n")
        print("found Au")
    """ % str(tmp_path))
    out = run_python(code, {"LAYERLAB_LIBRARY": relative, "LAYERLAB_IOR_DIR": ""},
                     cwd=str(library.parents[2]))
    assert out.returncode == 0, out.stderr
    assert "found Au" in out.stdout


def test_explicit_path_that_does_not_load_says_so():
    out = run_python("import layerlab", {"LAYERLAB_LIBRARY": "/nonexistent/liblayerlab.so"})
    assert out.returncode != 0
    assert "ImportError" in out.stderr
    assert "LAYERLAB_LIBRARY: /nonexistent/liblayerlab.so" in out.stderr
    assert "Tried:" in out.stderr


def test_nothing_found_lists_every_place_tried(tmp_path):
    # No LAYERLAB_LIBRARY, a pkg-config search path without layerlab, and
    # no system copy expected in CI.
    if shutil.which("pkg-config") is None:
        pytest.skip("pkg-config is not installed")
    probe = run_python("import ctypes.util; print(ctypes.util.find_library('layerlab'))", {})
    if probe.stdout.strip() != "None":
        pytest.skip("a system-wide liblayerlab is installed")
    out = run_python("import layerlab", {"PKG_CONFIG_PATH": str(tmp_path),
                                         "PKG_CONFIG_LIBDIR": str(tmp_path)})
    assert out.returncode != 0
    assert "pkg-config" in out.stderr and "system library path" in out.stderr
    assert "LAYERLAB_LIBRARY" in out.stderr  # the hint


def test_found_through_pkg_config(tmp_path):
    if shutil.which("pkg-config") is None:
        pytest.skip("pkg-config is not installed")
    libdir = pathlib.Path(ll.libraryPath()).resolve().parent
    (tmp_path / "layerlab.pc").write_text(textwrap.dedent("""\
        libdir=%s
        Name: layerlab
        Description: test
        Version: 1.0.0
        Libs: -L${libdir} -llayerlab
        """ % libdir))
    out = run_python("import layerlab as ll; print(ll.libraryPath())",
                     {"PKG_CONFIG_PATH": str(tmp_path), "PKG_CONFIG_LIBDIR": str(tmp_path)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str(libdir / "liblayerlab.so.1")


def test_wrong_version_is_refused(tmp_path):
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        pytest.skip("no C compiler")
    source = tmp_path / "fake.c"
    source.write_text("int ll_version_number(void) { return 20304; }\n")
    library = tmp_path / "libfake.so"
    subprocess.run([cc, "-shared", "-fPIC", "-o", str(library), str(source)], check=True)
    out = run_python("import layerlab", {"LAYERLAB_LIBRARY": str(library)})
    assert out.returncode != 0
    assert "version 2.3.4" in out.stderr and "needs 1.x" in out.stderr


def test_not_a_layerlab_library_is_refused():
    libm = "libm.so.6"
    out = run_python("import layerlab", {"LAYERLAB_LIBRARY": libm})
    assert out.returncode != 0 and "not liblayerlab" in out.stderr


def test_pip_install_gives_a_working_package(tmp_path):
    # Exactly what a new user runs, `pip install ./python` (into a private
    # target directory, with pip's usual isolated build), then an import of
    # the installed copy from elsewhere, not of the source tree.
    # The build works in its source directory, so build a copy of python/.
    source, target = tmp_path / "src", tmp_path / "site"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(PACKAGE_DIR / name, source / name)
    shutil.copytree(PACKAGE_DIR / "layerlab", source / "layerlab",
                    ignore=shutil.ignore_patterns("__pycache__"))
    install = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q",
                              "--disable-pip-version-check", "--target", str(target),
                              str(source)],
                             capture_output=True, text=True, timeout=300, cwd=str(tmp_path))
    assert install.returncode == 0, install.stderr
    code = ("import layerlab as ll; print(ll.__file__); "
            "mu, w = ll.quad.gaussLegendre(4); print(ll.Layer(mu, w))")
    out = run_python(code, {"LAYERLAB_LIBRARY": ll.libraryPath()}, pythonpath=str(target))
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith(str(target))
    assert lines[1] == "Layer[resolution=4x4, fourierOrders=1, nonZeros=4/16 (25%)]"
