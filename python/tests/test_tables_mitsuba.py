"""Table files of the `measured` format against Mitsuba 3's own `measured` plugin.

A table written by ll_tables_write_from_bsdf from tests/data/roughgold_alpha_0.2.bsdf is
evaluated by our reader (ll_bsdf_eval_dir, ll_bsdf_pdf_dir, ll_bsdf_sample_dir through ctypes)
and by Mitsuba's `measured` in scalar_rgb on the same file: values (f cos for Mitsuba, our f
times the cosine) and pdfs agree to 1e-4 relative where f cos is above 1e-3 of its maximum, and
sampling picks the same direction for the same random numbers (our u[0], u[1] are Mitsuba's
sample2 as given).
"""

import ctypes
import os

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

D3 = ctypes.c_double * 3


class _TablesOptions(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("n_theta_i", ctypes.c_size_t),
                ("vndf_size", ctypes.c_size_t), ("sample_size", ctypes.c_size_t),
                ("format", ctypes.c_int), ("description", ctypes.c_char_p)]


@pytest.fixture(scope="module")
def table(tmp_path_factory, testdata_dir):
    lib = ctypes.CDLL(os.environ["LAYERLAB_LIBRARY"])
    src, tab = ctypes.c_void_p(), ctypes.c_void_p()
    path = str(tmp_path_factory.mktemp("tables") / "gold.tab")
    opts = _TablesOptions(ctypes.sizeof(_TablesOptions), 16, 64, 32, 0, None)
    assert lib.ll_bsdf_open(str(testdata_dir / "roughgold_alpha_0.2.bsdf").encode(), None,
                            ctypes.byref(src)) == 0
    assert lib.ll_tables_write_from_bsdf(src, path.encode(), ctypes.byref(opts), None) == 0
    assert lib.ll_bsdf_open(path.encode(), None, ctypes.byref(tab)) == 0
    yield lib, tab, path
    lib.ll_bsdf_release(tab)
    lib.ll_bsdf_release(src)


def test_storage_opens_tables(table):
    import layerlab as ll
    _, _, path = table
    storage = ll.BSDFStorage(path)
    assert storage.format == "tables"
    assert storage.channelCount == 3
    assert storage.nodeCount == 0
    assert '"theta_i": 16' in storage.metadata
    storage.close()


def _interaction(wi):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def _unit(cos_theta, phi):
    s = np.sqrt(1 - cos_theta * cos_theta)
    return np.array([s * np.cos(phi), s * np.sin(phi), cos_theta])


def test_eval_and_pdf_match_mitsuba(table):
    mi.set_variant("scalar_rgb")
    lib, tab, path = table
    bsdf = mi.load_dict({"type": "measured", "filename": path})
    ctx = mi.BSDFContext()
    rng = np.random.default_rng(7)
    rows = []
    while len(rows) < 10000:
        wi = _unit(rng.uniform(0.05, 1), rng.uniform(0, 2 * np.pi))
        if len(rows) % 2:
            m = np.array([rng.normal(0, 0.2), rng.normal(0, 0.2), 1.0])
            m /= np.linalg.norm(m)
            wo = 2 * np.dot(wi, m) * m - wi
            if wo[2] <= 0.01:
                continue
        else:
            wo = _unit(rng.uniform(0.05, 1), rng.uniform(0, 2 * np.pi))
        si = _interaction(wi)
        value = bsdf.eval(ctx, si, mi.Vector3f(*wo))
        pdf = bsdf.pdf(ctx, si, mi.Vector3f(*wo))
        f, our_pdf = D3(), ctypes.c_double()
        assert lib.ll_bsdf_eval_dir(tab, D3(*wi), D3(*wo), 0, None, f) == 0
        assert lib.ll_bsdf_pdf_dir(tab, D3(*wi), D3(*wo), None, ctypes.byref(our_pdf)) == 0
        rows.append((np.array([value[0], value[1], value[2]]), np.array(list(f)) * wo[2],
                     float(pdf), our_pdf.value))
    top = max(r[0][1] for r in rows)
    kept = [r for r in rows if r[0][1] > 1e-3 * top]
    assert len(kept) > 3000
    value_err = max(np.max(np.abs(o - m) / m) for m, o, _, _ in kept)
    pdf_err = max(abs(op - mp) / mp for _, _, mp, op in kept)
    assert value_err < 1e-4, value_err
    assert pdf_err < 1e-4, pdf_err


def test_sampling_matches_mitsuba(table):
    mi.set_variant("scalar_rgb")
    lib, tab, path = table
    bsdf = mi.load_dict({"type": "measured", "filename": path})
    ctx = mi.BSDFContext()
    rng = np.random.default_rng(11)
    compared = 0
    pdfs = []
    for _ in range(2000):
        wi = _unit(rng.uniform(0.05, 1), rng.uniform(0, 2 * np.pi))
        u = rng.uniform(0, 1, 2)
        bs, _ = bsdf.sample(ctx, _interaction(wi), 0.5, mi.Point2f(u[0], u[1]))
        wo, pdf, f = D3(), ctypes.c_double(), D3()
        assert lib.ll_bsdf_sample_dir(tab, D3(*wi), (ctypes.c_double * 2)(*u), 0, None, wo,
                                      ctypes.byref(pdf), f) == 0
        if bs.pdf > 0 and pdf.value > 0:
            compared += 1
            ours = np.array(list(wo))
            theirs = np.array([bs.wo[0], bs.wo[1], bs.wo[2]])
            assert np.linalg.norm(ours - theirs) < 1e-4
            pdfs.append((pdf.value, bs.pdf))
    assert compared > 1800
    # The pdfs, where they matter (above 1e-3 of the largest, as for eval and pdf above: in the
    # far tail float rounding of the two readers' running sums shows at 1e-4).
    top = max(theirs for _, theirs in pdfs)
    for ours, theirs in pdfs:
        if theirs > 1e-3 * top:
            assert abs(ours - theirs) <= 1e-4 * theirs, (ours, theirs)


def _plugin_pairs(rng, n):
    """n (si.wi, wo) pairs above the surface, half of them near the mirror direction."""
    pairs = []
    while len(pairs) < n:
        wi = _unit(rng.uniform(0.05, 1), rng.uniform(0, 2 * np.pi))
        if len(pairs) % 2:
            m = np.array([rng.normal(0, 0.2), rng.normal(0, 0.2), 1.0])
            m /= np.linalg.norm(m)
            wo = 2 * np.dot(wi, m) * m - wi
            if wo[2] <= 0.01:
                continue
        else:
            wo = _unit(rng.uniform(0.05, 1), rng.uniform(0, 2 * np.pi))
        # As float32, the precision Mitsuba hands the plugin, so that the C calls below see
        # the same directions.
        pairs.append((wi.astype(np.float32).astype(np.float64),
                      wo.astype(np.float32).astype(np.float64)))
    return pairs


def _close(ours, theirs, what, atol=1e-30):
    # The plugin hands the C reader's doubles to Mitsuba as float32.
    assert np.allclose(ours, theirs, rtol=2e-6, atol=atol), (what, ours, theirs)


def test_plugin_renders_tables_scalar(table):
    """The `layerlab` BSDF given a table file (scalar_rgb, the batch path): eval, pdf and
    sample are the C reader's (ll_bsdf_eval_dir times the cosine, ll_bsdf_pdf_dir,
    ll_bsdf_sample_dir), at 500 pairs."""
    mi.set_variant("scalar_rgb")
    import layerlab.mitsuba as llmi
    llmi.register()
    lib, tab, path = table
    bsdf = mi.load_dict({"type": "layerlab", "filename": path})
    assert "format=tables" in str(bsdf) and "mode=batch" in str(bsdf)
    ctx = mi.BSDFContext()
    rng = np.random.default_rng(3)
    nonzero = 0
    for wi, wo in _plugin_pairs(rng, 500):
        si = _interaction(wi)
        value = bsdf.eval(ctx, si, mi.Vector3f(*wo))
        pdf = bsdf.pdf(ctx, si, mi.Vector3f(*wo))
        f, our_pdf = D3(), ctypes.c_double()
        assert lib.ll_bsdf_eval_dir(tab, D3(*wi), D3(*wo), 0, None, f) == 0
        assert lib.ll_bsdf_pdf_dir(tab, D3(*wi), D3(*wo), None, ctypes.byref(our_pdf)) == 0
        expected = np.array(list(f)) * wo[2]
        _close(np.array([value[0], value[1], value[2]]), expected, "eval")
        _close(float(pdf), our_pdf.value, "pdf")
        nonzero += expected[1] > 0
        # (as float32: Mitsuba's Point2f holds them so, and hands that to the plugin)
        u = rng.uniform(0, 1, 2).astype(np.float32).astype(np.float64)
        bs, weight = bsdf.sample(ctx, si, 0.5, mi.Point2f(u[0], u[1]))
        out, spdf, sf = D3(), ctypes.c_double(), D3()
        assert lib.ll_bsdf_sample_dir(tab, D3(*wi), (ctypes.c_double * 2)(*u), 0, None, out,
                                      ctypes.byref(spdf), sf) == 0
        if spdf.value > 0:
            _close(np.array([bs.wo[0], bs.wo[1], bs.wo[2]]), np.array(list(out)), "sample wo",
                   atol=1e-7)
            _close(float(bs.pdf), spdf.value, "sample pdf")
            w = np.array(list(sf)) * abs(out[2]) / spdf.value
            _close(np.array([weight[0], weight[1], weight[2]]), w, "sample weight")
    assert nonzero > 400


def test_plugin_renders_tables_llvm(table):
    """The same in llvm_ad_rgb: a table file takes the batch path by default (the traced
    path reads Fourier series, refused on a table file with the reason); a wavefront of
    pairs matches the C reader, and a small scene renders to finite, non-zero pixels."""
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception as error:  # pragma: no cover - depends on the Mitsuba build
        pytest.skip("llvm_ad_rgb: %s" % error)
    import drjit as dr
    import layerlab.mitsuba as llmi
    llmi.register()
    lib, tab, path = table
    with pytest.raises(Exception, match="table file"):
        mi.load_dict({"type": "layerlab", "filename": path, "mode": "traced"})
    bsdf = mi.load_dict({"type": "layerlab", "filename": path})
    assert "mode=batch" in str(bsdf)
    llmi.wavefront_mode()
    rng = np.random.default_rng(5)
    pairs = _plugin_pairs(rng, 256)
    wi = np.array([p[0] for p in pairs])
    wo = np.array([p[1] for p in pairs])
    si = dr.zeros(mi.SurfaceInteraction3f, len(pairs))
    si.wi = mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2])
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    ctx = mi.BSDFContext()
    value = bsdf.eval(ctx, si, mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2]))
    got = np.stack([value.x.numpy(), value.y.numpy(), value.z.numpy()], axis=1)
    for k, (a, b) in enumerate(pairs):
        f = D3()
        assert lib.ll_bsdf_eval_dir(tab, D3(*a), D3(*b), 0, None, f) == 0
        _close(got[k], np.array(list(f)) * b[2], "llvm eval")
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16},
                   "sampler": {"type": "independent", "sample_count": 4}},
        "sphere": {"type": "sphere", "bsdf": {"type": "layerlab", "filename": path}},
        "light": {"type": "constant"},
    })
    image = np.asarray(mi.render(scene))
    assert np.all(np.isfinite(image))
    centre = image[6:10, 6:10, :3]
    assert centre.mean() > 0.05
