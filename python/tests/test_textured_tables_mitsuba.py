"""Textured table files (a table set per basis of a textured .bsdf) in Mitsuba 3.

Mitsuba's own {"type": "measured"} refuses such a file (it has no plain table fields: a
renderer that knows only `measured` cannot render a part of it as if it were the whole). The
`layerlab` plugin renders it through its "batch" mode, with one property per textured
parameter exactly as for the textured .bsdf it was made from; its values are the C reader's,
and close to the .bsdf's (the tables' grid is small here).
"""

import ctypes
import os

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

import mitsuba_scenes as S  # noqa: E402


class _TablesOptions(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("n_theta_i", ctypes.c_size_t),
                ("vndf_size", ctypes.c_size_t), ("sample_size", ctypes.c_size_t)]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("textured-tables")
    bsdf = S.build_textured_conductor(str(d / "gold-textured.bsdf"), S.TEXTURED_ALPHAS)
    tab = str(d / "gold-textured.tab")
    lib = ctypes.CDLL(os.environ["LAYERLAB_LIBRARY"])
    src = ctypes.c_void_p()
    # The leading fields of ll_tables_options (an older, smaller struct:
    # the library reads those its struct_size covers).
    opts = _TablesOptions(ctypes.sizeof(_TablesOptions), 16, 64, 48)
    assert lib.ll_bsdf_open(bsdf.encode(), None, ctypes.byref(src)) == 0
    try:
        status = lib.ll_tables_write_from_bsdf(src, tab.encode(), ctypes.byref(opts), None)
    finally:
        lib.ll_bsdf_release(src)
    assert status == 0
    return bsdf, tab


def _plugin(variant, path, alpha, mode=None):
    mi.set_variant(variant)
    import layerlab.mitsuba as llmi
    llmi.register()
    d = {"type": "layerlab", "filename": path, "alpha": alpha}
    if mode:
        d["mode"] = mode
    return mi.load_dict(d)


def test_measured_refuses(files):
    mi.set_variant("scalar_rgb")
    with pytest.raises(RuntimeError, match="theta_i"):
        mi.load_dict({"type": "measured", "filename": files[1]})


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_plugin_textured_tables(files, variant, request):
    bsdf_path, tab_path = files
    rng = np.random.default_rng(3)
    for alpha in (0.15, 0.17, 0.26):
        errors = []
        tab = _plugin(variant, tab_path, alpha)
        four = _plugin(variant, bsdf_path, alpha, mode="batch")
        ctx = mi.BSDFContext()
        for _ in range(40):
            v = rng.normal(size=3)
            wi = np.abs(v) / np.linalg.norm(v)
            wo = np.array([-wi[0], -wi[1], wi[2]]) + 0.15 * rng.normal(size=3)
            wo[2] = abs(wo[2]) + 0.05
            wo /= np.linalg.norm(wo)
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(*(float(x) for x in wi))
            w = mi.Vector3f(*(float(x) for x in wo))
            ft = np.array(tab.eval(ctx, si, w)).ravel()
            ff = np.array(four.eval(ctx, si, w)).ravel()
            pt = float(np.array(tab.pdf(ctx, si, w)).ravel()[0])
            assert np.all(np.isfinite(ft)) and pt >= 0.0
            if ff.max() > 0.05:
                errors.append(np.max(np.abs(ft / ff - 1.0)))
        # This small grid (16 x 64^2 x 48^2) is no tolerance's: its median
        # error is a few tenths of a percent.
        assert len(errors) > 10 and np.median(errors) < 0.02
    if variant.startswith("llvm"):
        dr.set_flag(dr.JitFlag.SymbolicLoops, True)
        dr.set_flag(dr.JitFlag.SymbolicCalls, True)


def test_plugin_needs_the_parameter(files):
    mi.set_variant("scalar_rgb")
    import layerlab.mitsuba as llmi
    llmi.register()
    with pytest.raises(Exception, match="alpha"):
        mi.load_dict({"type": "layerlab", "filename": files[1]})
