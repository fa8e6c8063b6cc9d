"""The ctypes layouts of the size-tagged structs against the C compiler's.

python/tests/struct_layout.c, compiled here against include/, prints each
struct's sizeof, the bytes of its INIT macro and every field's offsetof and
sizeof; each ctypes Structure in layerlab._native must have the same fields
in the same places, the same size, and a default-constructed instance the
same bytes as the C INIT value (so Python callers pass what C callers pass).
"""

import ctypes
import os
import pathlib
import shlex
import shutil
import subprocess

import pytest

from layerlab import _native

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]

STRUCTS = {
    "ll_bsdf_write_options": _native.BsdfWriteOptions,
    "ll_bsdf_info": _native.BsdfInfo,
    "ll_build_options": _native.BuildOptions,
    "ll_build_estimate": _native.BuildEstimate,
    "ll_microfacet": _native.Microfacet,
    "ll_monitor": _native.Monitor,
}
try:
    # The traced Mitsuba path's view of ll_bsdf_tables (it needs Mitsuba 3).
    from layerlab.mitsuba_traced import Tables
    STRUCTS["ll_bsdf_tables"] = Tables
    # and the table path's view of ll_tables_options (tables made on load)
    from layerlab.mitsuba_tables import TablesOptions
    STRUCTS["ll_tables_options"] = TablesOptions
except ImportError:
    pass


@pytest.fixture(scope="module")
def c_layout(tmp_path_factory):
    cc = shlex.split(os.environ.get("CC") or "cc")
    if shutil.which(cc[0]) is None:
        pytest.skip("no C compiler (%s) to read the C layouts with" % cc[0])
    exe = tmp_path_factory.mktemp("layout") / "struct_layout"
    subprocess.run(cc + ["-std=c99", "-I", str(ROOT / "include"), "-o", str(exe),
                         str(HERE / "struct_layout.c")], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    structs, fields = {}, {}
    for line in out.splitlines():
        words = line.split()
        if words[0] == "struct":
            structs[words[1]] = (int(words[2]), bytes.fromhex(words[3]))
            fields[words[1]] = []
        else:
            fields[words[1]].append((words[2], int(words[3]), int(words[4])))
    return structs, fields


@pytest.mark.parametrize("name", sorted(STRUCTS))
def test_fields_in_the_same_places(c_layout, name):
    structs, fields = c_layout
    cls = STRUCTS[name]
    py = [(f[0], getattr(cls, f[0]).offset, getattr(cls, f[0]).size) for f in cls._fields_]
    assert py == fields[name], "%s: ctypes (name, offset, size) differ from C" % name
    assert ctypes.sizeof(cls) == structs[name][0], "%s: sizeof differs" % name


@pytest.mark.parametrize("name", sorted(STRUCTS))
def test_defaults_are_the_init_macro(c_layout, name):
    structs, _ = c_layout
    assert bytes(STRUCTS[name]()) == structs[name][1], \
        "%s: a new ctypes instance differs from the C INIT macro" % name
