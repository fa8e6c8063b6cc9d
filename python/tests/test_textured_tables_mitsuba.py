"""Textured table files (a table set per basis of a textured .bsdf) in Mitsuba 3.

Mitsuba's own {"type": "measured"} refuses such a file (it has no plain table fields: a
renderer that knows only `measured` cannot render a part of it as if it were the whole). The
`layerlab` plugin renders it in its default "tables" mode (layerlab.mitsuba_textured), with one
property per textured parameter exactly as for the textured .bsdf it was made from: values
close to the .bsdf's (the tables' grid is small here) and, on the same table file, the C
reader's (ll_bsdf_eval_dir, ll_bsdf_pdf_dir, ll_bsdf_sample_dir with the weights of
ll_bsdf_basis_coefficients) to float32 rounding, at random pairs and random per-lane parameter
values (a bitmap of random values looked up at random texels), in llvm_ad_rgb and scalar_rgb.
A textured .bsdf renders from its tables made on load within the noise of its Fourier path.
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


def test_plugin_textured_tables_default_and_fourier(files):
    """A textured table file and a textured .bsdf take "tables" by default; the .bsdf's
    Fourier path stays selectable."""
    for variant in ("scalar_rgb", "llvm_ad_rgb"):
        for path in files:
            text = str(_plugin(variant, path, 0.2))
            assert "mode=tables" in text and "3 bases" in text, text
        assert "mode=batch" in str(_plugin(variant, files[0], 0.2, mode="batch"))
    assert "mode=traced" in str(_plugin("llvm_ad_rgb", files[0], 0.2, mode="traced"))


def test_plugin_needs_the_parameter(files):
    mi.set_variant("scalar_rgb")
    import layerlab.mitsuba as llmi
    llmi.register()
    with pytest.raises(Exception, match="alpha"):
        mi.load_dict({"type": "layerlab", "filename": files[1]})


# A material of two textured parameters (2 x 3 bases: 4 corners of non-zero weight per lane),
# its tables on a small grid (their values are not the .bsdf's question here: the C reader's
# on the same file are).
TWO = ("set nodes=40 orders=40\n"
       "dielectric name=coat eta=1.5 alpha=[0.05 0.2]\n"
       "conductor  name=gold eta=Au alpha=[0.1 0.2 0.3]\n")
RANGES = ((0.05, 0.2), (0.1, 0.3))


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    import layerlab as ll
    d = tmp_path_factory.mktemp("textured-two")
    bsdf = str(d / "two.bsdf")
    ll.Material.parse(TWO).build(bsdf)
    tab = str(d / "two.tab")
    lib = ctypes.CDLL(os.environ["LAYERLAB_LIBRARY"])
    src = ctypes.c_void_p()
    opts = _TablesOptions(ctypes.sizeof(_TablesOptions), 16, 48, 32)
    assert lib.ll_bsdf_open(bsdf.encode(), None, ctypes.byref(src)) == 0
    try:
        assert lib.ll_tables_write_from_bsdf(src, tab.encode(), ctypes.byref(opts), None) == 0
    finally:
        lib.ll_bsdf_release(src)
    return tab


TEXELS = 32


def _parameter_bitmaps(rng):
    """Per parameter a TEXELS^2 bitmap of random values in (beyond, by 0.02) its range
    (clamped there, as ll_bsdf_basis_coefficients does), float32."""
    return [rng.uniform(lo - 0.02, hi + 0.02, size=(TEXELS, TEXELS)).astype(np.float32)
            for lo, hi in RANGES]


def _two_plugin(variant, path, maps):
    mi.set_variant(variant)
    import layerlab.mitsuba as llmi
    llmi.register()
    props = {"type": "layerlab", "filename": path}
    for name, m in zip(("coat_alpha", "gold_alpha"), maps):
        props[name] = {"type": "bitmap", "bitmap": mi.Bitmap(m[..., None]), "raw": True,
                       "filter_type": "nearest"}
    return mi.load_dict(props)


def _pairs(rng, n):
    """n (wi, wo) pairs above the surface (cos theta >= 0.05), half about the mirror
    direction of a normal drawn about the surface's; float32 values in float64."""
    def unit(k):
        c = rng.uniform(0.05, 1.0, k)
        phi = rng.uniform(0, 2 * np.pi, k)
        s = np.sqrt(1 - c * c)
        return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1)
    wi, wo = unit(n), unit(n)
    m = np.stack([rng.normal(0, 0.25, n), rng.normal(0, 0.25, n), np.ones(n)], axis=1)
    m /= np.linalg.norm(m, axis=1)[:, None]
    mirror = 2 * np.sum(wi * m, axis=1)[:, None] * m - wi
    half = (np.arange(n) % 2 == 1) & (mirror[:, 2] >= 0.05)
    wo[half] = mirror[half]
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    return wi.astype(np.float32).astype(np.float64), wo.astype(np.float32).astype(np.float64)


def _texels(rng, n, maps):
    """Random texels: their uv (centres) and each lane's parameter values."""
    i, j = rng.integers(0, TEXELS, n), rng.integers(0, TEXELS, n)
    uv = np.stack([(j + 0.5) / TEXELS, (i + 0.5) / TEXELS], axis=1)
    return uv, [m[i, j].astype(np.float64) for m in maps]


def _c_reader(path):
    import layerlab as ll
    return ll.BSDFStorage(path)


def _check(c, wi, wo, u, params, value, pdf, swo, spdf, sw, timings, what):
    """Our eval, pdf and sample against the C reader's with each lane's
    ll_bsdf_basis_coefficients weights. Returns the worst relative errors."""
    coeffs = [c.basisCoefficients([p[k] for p in params]) for k in range(len(wi))]
    want = np.array([c.evalDir(a, b, basisCoeffs=w) * b[2] for a, b, w in zip(wi, wo, coeffs)])
    want_pdf = np.array([c.pdfDir(a, b, basisCoeffs=w) for a, b, w in zip(wi, wo, coeffs)])
    strong = want[:, 1] > 1e-3 * want[:, 1].max()
    assert np.count_nonzero(strong) > 0.3 * len(wi)
    worst = {}
    worst["eval"] = max(float(np.max(np.abs(value[strong, k] - want[strong, k]) /
                                     want[strong, k])) for k in range(3))
    worst["pdf"] = float(np.max(np.abs(pdf[strong] - want_pdf[strong]) / want_pdf[strong]))
    # everywhere (the weak values too): within 2e-5 of each channel's largest
    worst["eval, absolute"] = float(np.max(np.abs(value - want) / want.max(axis=0)))
    res = [c.sampleDir(a, b, basisCoeffs=w) for a, b, w in zip(wi, u, coeffs)]
    cwo = np.array([r[1] for r in res])
    cpdf = np.array([r[2] for r in res])
    found = cpdf > 0
    assert np.count_nonzero(found) > 0.9 * len(wi)
    assert np.array_equal(found, spdf > 0)
    dist = np.linalg.norm(swo[found] - cwo[found], axis=1)
    worst["direction"] = float(dist.max())
    # The pdf and weight of our sample: the C reader's at our sampled direction (its own
    # direction differs by the float32 warps' rounding, which a sharp lobe's pdf amplifies).
    ours_wo = swo[found].astype(np.float32).astype(np.float64)
    fc = [w for w, f in zip(coeffs, found) if f]
    at_pdf = np.array([c.pdfDir(a, b, basisCoeffs=w) for a, b, w in zip(wi[found], ours_wo, fc)])
    at_f = np.array([c.evalDir(a, b, basisCoeffs=w) * b[2]
                     for a, b, w in zip(wi[found], ours_wo, fc)])
    strong_pdf = at_pdf > 1e-3 * at_pdf.max()
    worst["sample pdf"] = float(np.max(np.abs(spdf[found][strong_pdf] - at_pdf[strong_pdf]) /
                                       at_pdf[strong_pdf]))
    at_w = at_f[:, 1] / np.where(at_pdf > 0, at_pdf, 1.0)
    strong_w = strong_pdf & (at_f[:, 1] > 1e-3 * at_f[:, 1].max())
    worst["sample weight"] = float(np.max(np.abs(sw[found][strong_w, 1] - at_w[strong_w]) /
                                          at_w[strong_w]))
    for key, v in worst.items():
        timings["textured tables (%s) vs C reader: worst %s" % (what, key)] = (v * 1e6, "x 1e-6")
    return worst


def test_textured_tables_are_the_c_reader_llvm(two, timings):
    """eval, pdf and sample of the textured tables (llvm_ad_rgb, 4000 pairs, a random texel of
    random parameter values each) against the C reader on the same file: within 1e-4
    relative where f cos theta_o is above 1e-3 of its largest, sampled directions within
    1e-3, the sample's pdf and weight the C reader's at that direction within 1e-4."""
    rng = np.random.default_rng(41)
    maps = _parameter_bitmaps(rng)
    bsdf = _two_plugin("llvm_ad_rgb", two, maps)
    assert "mode=tables" in str(bsdf) and "6 bases" in str(bsdf), str(bsdf)
    n = 4000
    wi, wo = _pairs(rng, n)
    uv, params = _texels(rng, n, maps)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(wi.T)
    si.uv = mi.Point2f(uv.T)
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(wo.T))
    value = np.array(value).reshape(3, -1).T
    pdf = np.array(pdf)
    only_value = np.array(bsdf.eval(ctx, si, mi.Vector3f(wo.T))).reshape(3, -1).T
    np.testing.assert_array_equal(only_value, value)
    np.testing.assert_array_equal(np.array(bsdf.pdf(ctx, si, mi.Vector3f(wo.T))), pdf)
    u = rng.uniform(size=(n, 2))
    bs, weight = bsdf.sample(ctx, si, mi.Float(0.5), mi.Point2f(u.T))
    stype = np.broadcast_to(np.array(bs.sampled_type), (n,))
    assert np.all(stype[np.array(bs.pdf) > 0] == int(mi.BSDFFlags.GlossyReflection))
    worst = _check(_c_reader(two), wi, wo, u, params, value, pdf,
                   np.array(bs.wo).reshape(3, -1).T, np.array(bs.pdf),
                   np.array(weight).reshape(3, -1).T, timings, "llvm")
    assert worst["eval"] < 1e-4 and worst["pdf"] < 1e-4, worst
    assert worst["eval, absolute"] < 2e-5, worst
    assert worst["direction"] < 1e-3, worst
    assert worst["sample pdf"] < 1e-4 and worst["sample weight"] < 1e-4, worst
    # below the surface: nothing
    si.wi = mi.Vector3f(wi.T * np.array([[1.0], [1.0], [-1.0]]))
    assert np.all(np.array(bsdf.eval(ctx, si, mi.Vector3f(wo.T))) == 0)


def test_textured_tables_are_the_c_reader_scalar(two, timings):
    """The same in scalar_rgb (300 pairs)."""
    rng = np.random.default_rng(43)
    maps = _parameter_bitmaps(rng)
    bsdf = _two_plugin("scalar_rgb", two, maps)
    assert "mode=tables" in str(bsdf)
    n = 300
    wi, wo = _pairs(rng, n)
    uv, params = _texels(rng, n, maps)
    u = rng.uniform(size=(n, 2))
    ctx = mi.BSDFContext()
    rows = []
    for a, b, t, uu in zip(wi, wo, uv, u):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*a)
        si.uv = mi.Point2f(*t)
        v, p = bsdf.eval_pdf(ctx, si, mi.Vector3f(*b))
        bs, w = bsdf.sample(ctx, si, 0.5, mi.Point2f(*uu))
        rows.append(([v[0], v[1], v[2]], p, [bs.wo[0], bs.wo[1], bs.wo[2]], bs.pdf,
                     [w[0], w[1], w[2]]))
    value, pdf, swo, spdf, sw = (np.array([r[k] for r in rows], dtype=np.float64)
                                 for k in range(5))
    worst = _check(_c_reader(two), wi, wo, u, params, value, pdf, swo, spdf, sw, timings,
                   "scalar")
    assert worst["eval"] < 1e-4 and worst["pdf"] < 1e-4, worst
    assert worst["eval, absolute"] < 2e-5, worst
    assert worst["direction"] < 1e-3, worst
    assert worst["sample pdf"] < 1e-4 and worst["sample weight"] < 1e-4, worst


def test_textured_tables_render_as_the_fourier_path(files, timings):
    """The textured gold with a bitmap driving its alpha (stripes between two of its samples
    and beyond), 48^2, 24 spp, llvm_ad_rgb, default symbolic mode: from its table file in
    "tables" mode against its .bsdf in "traced" mode (the Fourier path), within the noise of
    two renders of different seeds (mitsuba_scenes.check_within_noise)."""
    bsdf_path, tab_path = files
    mi.set_variant("llvm_ad_rgb")
    import layerlab.mitsuba as llmi
    llmi.register()
    # (a batch-mode test before may have left the symbolic modes off)
    dr.set_flag(dr.JitFlag.SymbolicLoops, True)
    dr.set_flag(dr.JitFlag.SymbolicCalls, True)
    u = (np.arange(16) + 0.5) / 16
    uu, vv = np.meshgrid(u, u, indexing="xy")
    alpha = np.where(np.floor(uu * 4) % 2 == 0, 0.14, 0.32) * 0.5 + (0.15 + 0.15 * vv) * 0.5
    bitmap = mi.Bitmap(np.ascontiguousarray(alpha[..., None], dtype=np.float32))

    def scene(path, mode):
        return S.scene(mi, {"type": "layerlab", "filename": path, "mode": mode,
                            "alpha": {"type": "bitmap", "bitmap": bitmap, "raw": True,
                                      "filter_type": "bilinear"}}, 48, 24)

    tables, fourier = scene(tab_path, "tables"), scene(bsdf_path, "traced")
    assert "mode=tables" in str(tables.shapes()[0].bsdf())
    a = [S.render(mi, tables, 24, s) for s in (1, 2)]
    b = [S.render(mi, fourier, 24, s) for s in (3, 4)]
    d, noise, excess, limit = S.check_within_noise(b[0], a[0], b[1], a[1])
    timings["textured tables vs Fourier path (48^2, 24 spp): relative RMSE"] = (d, "")
    timings["textured tables vs Fourier path: noise alone"] = (noise, "")
    assert excess < limit, ("textured tables vs Fourier: relative RMSE %.4g, noise %.4g, "
                            "excess %.3g >= %.3g" % (d, noise, excess, limit))
