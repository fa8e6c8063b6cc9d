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
