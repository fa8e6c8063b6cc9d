"""BSDFStorage: Python -> .bsdf (ll_bsdf_write) -> C reader (ll_bsdf_open)
round trips, the golden file of the original tools with pbrt-v3's numbers,
and errors for missing and damaged files."""

import math

import numpy as np
import pytest
from numpy.polynomial import legendre

import layerlab as ll

LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def gauss_layer(n, m):
    x, w = legendre.leggauss(n)
    return ll.Layer(x, w, m)


def build_stack(kind):
    mu, w = ll.quad.gaussLobatto(60)
    base = ll.Layer(mu, w, 60)
    top = ll.Layer(mu, w, 60)
    if kind == "rough":  # a rough conductor under a rough coat
        top.setMicrofacet(eta=1.5, alpha=0.3)
        base.setMicrofacet(eta=0.2 + 3j, alpha=0.3)
    else:  # a forward-scattering medium over a diffuse base
        top.setHenyeyGreenstein(albedo=0.95, g=0.8)
        top.expand(0.5)
        base.setDiffuse(0.5)
    base.addToTop(top)
    return base


@pytest.fixture(scope="module", params=["medium", "rough"])
def rough_stack(request):
    return build_stack(request.param)


def test_mem_string_formats_like_the_original():
    from layerlab.storage import mem_string
    assert mem_string(512) == "512 B"
    assert mem_string(1024) == "1024 B"
    assert mem_string(1536) == "1.5 KiB"
    assert mem_string(int(3.3 * 1024 * 1024)) == "3.3 MiB"
    assert mem_string(5 * 1024 ** 3) == "5.0 GiB"


def test_round_trip_of_a_diffuse_layer(tmp_path):
    layer = gauss_layer(10, 1)
    layer.setDiffuse(0.5)
    path = tmp_path / "diffuse.bsdf"
    storage = ll.BSDFStorage.fromLayer(path, layer)
    assert storage.nodeCount == 12 and storage.channelCount == 1 and storage.basisCount == 1
    assert storage.maxOrder == 1 and storage.eta == 1.0
    assert storage.size == path.stat().st_size
    nodes = storage.nodes
    assert nodes.shape == (12,) and nodes[5] == 0 and nodes[6] == 0
    np.testing.assert_allclose(nodes[7:], legendre.leggauss(10)[0][5:], rtol=1e-7)
    # Reflection from above: f = albedo / pi, the same in R, G and B.
    rgb = storage.eval(0.6, -0.3)
    assert rgb.shape == (3,)
    np.testing.assert_allclose(rgb, 0.5 / math.pi, rtol=1e-5)
    np.testing.assert_allclose(storage.eval(0.6, 0.3), 0.0, atol=1e-7)  # no transmission


def test_round_trip_matches_layer_eval(rough_stack, tmp_path):
    storage = ll.BSDFStorage.fromLayer(tmp_path / "stack.bsdf", rough_stack, alpha=(0.3, 0.3))
    assert storage.alpha(0) == pytest.approx(0.3) and storage.alpha(1) == pytest.approx(0.3)
    with pytest.raises(IndexError):
        storage.alpha(2)
    rng = np.random.default_rng(7)
    # Away from the horizon: the file adds two nodes at mu = 0 (format), so
    # its splines differ from the layer's between 0 and the third node.
    mu_i = rng.uniform(0.15, 1.0, 400)
    mu_o = -rng.uniform(0.15, 1.0, 400)
    phi = rng.uniform(0, 2 * math.pi, 400)
    from_layer = rough_stack.eval(mu_o, mu_i, phi)
    from_file = storage.eval(mu_i, mu_o, phi)
    assert from_file.shape == (400, 3)
    peak = from_layer.max()
    # float32 storage and series cut at 1e-3 of the first coefficient.
    err = np.abs(from_file[:, 0] - from_layer)
    assert np.all(err <= 5e-3 * peak + 1e-3 * from_layer), err.max() / peak


def test_pdf_and_sample_are_consistent(rough_stack, tmp_path):
    storage = ll.BSDFStorage.fromLayer(tmp_path / "stack.bsdf", rough_stack)
    rng = np.random.default_rng(3)
    for _ in range(20):
        u = rng.uniform(0, 1, 2)
        weight, mu_o, phi_d, pdf = storage.sample(0.7, u)
        if pdf == 0:
            continue
        assert mu_o < 0  # an opaque stack reflects
        assert storage.pdf(0.7, mu_o, phi_d) == pytest.approx(pdf, rel=1e-3)
        f = storage.eval(0.7, mu_o, phi_d)
        np.testing.assert_allclose(weight, f * abs(mu_o) / pdf, rtol=1e-3)
    pdfs = storage.pdf(0.7, np.array([-0.2, -0.5]), 0.0)
    assert pdfs.shape == (2,) and np.all(pdfs > 0)


def test_rgb_round_trip_and_header(tmp_path):
    layers = []
    for albedo in (0.2, 0.5, 0.8):
        layer = gauss_layer(12, 1)
        layer.setDiffuse(albedo)
        layers.append(layer)
    storage = ll.BSDFStorage.fromLayerRGB(tmp_path / "rgb.bsdf", *layers, eta=1.33, alpha=0.05,
                                          metadata="made by the Python tests")
    assert storage.channelCount == 3
    assert "%g" % storage.eta == "1.33"
    assert storage.alpha(0) == pytest.approx(0.05)
    assert storage.metadata == "made by the Python tests"
    np.testing.assert_allclose(storage.eval(0.5, -0.5), np.array([0.2, 0.5, 0.8]) / math.pi,
                               rtol=1e-4)
    text = repr(storage)
    assert text.startswith('BSDFStorage[mmap = MemoryMappedFile[filename="')
    assert text.endswith("nNodes = 14, nMaxOrder = 1, nChannels = 3, nBases = 1, eta = 1.33]")
    storage.close()
    assert repr(storage).endswith(", closed]")
    with pytest.raises(ValueError, match="closed"):
        storage.eval(0.5, -0.5)


def test_write_errors_leave_no_file(tmp_path):
    layer = gauss_layer(8, 1)
    layer.setDiffuse(0.5)
    with pytest.raises(OSError) as e:
        ll.BSDFStorage.fromLayer(tmp_path / "no" / "such" / "dir" / "x.bsdf", layer)
    assert isinstance(e.value, ll.FileError) and "x.bsdf" in str(e.value)
    other = gauss_layer(10, 1)
    with pytest.raises(ValueError):
        ll.BSDFStorage.fromLayerRGB(tmp_path / "mixed.bsdf", layer, other, layer)
    with pytest.raises(TypeError):
        ll.BSDFStorage.fromLayer(tmp_path / "x.bsdf", "not a layer")
    assert list(tmp_path.iterdir()) == []


def test_open_errors(tmp_path):
    with pytest.raises(OSError) as e:
        ll.BSDFStorage(tmp_path / "missing.bsdf")
    assert "missing.bsdf" in str(e.value)
    bad = tmp_path / "bad.bsdf"
    bad.write_bytes(b"SCATFUN\x01" + b"\x00" * 20)
    with pytest.raises(ll.FormatError) as e:
        ll.BSDFStorage(bad)
    assert isinstance(e.value, ValueError) and e.value.status == 4
    with pytest.raises(ll.FormatError):
        ll.BSDFStorage.fromBytes(b"not a bsdf file at all")


# ---------------------------------------------------------------- golden file

@pytest.fixture(scope="module")
def golden(testdata_dir):
    return ll.BSDFStorage(testdata_dir / "roughgold_alpha_0.2.bsdf")


def test_golden_header(golden):
    assert (golden.nodeCount, golden.maxOrder, golden.channelCount, golden.basisCount) == \
        (58, 172, 3, 1)
    assert golden.coefficientCount == 41502 and golden.size == 207354
    assert golden.eta == 1.0 and golden.parameterCount == 0 and not golden.extrapolated
    assert len(golden.metadata) == 682 and "0.2" in golden.metadata
    assert repr(golden).endswith('size=202.5 KiB], nNodes = 58, nMaxOrder = 172, '
                                 'nChannels = 3, nBases = 1, eta = 1]')


def test_golden_matches_pbrt_v3(golden):
    # pbrt-v3's FourierBSDF on this file (tests/data/README.md).
    wo = np.array([-0.5, -0.5, 0.8]) / np.linalg.norm([-0.5, -0.5, 0.8])
    wi = np.array([0.4, 0.52, 0.7]) / np.linalg.norm([0.4, 0.52, 0.7])
    f = golden.evalDir(wo, wi, mode="importance")
    assert LUMINANCE @ f == pytest.approx(2.679294, rel=1e-3)
    assert golden.pdfDir(wo, wi) == pytest.approx(2.438230, rel=1e-3)
    assert golden.pdfDir(wi, wo) == pytest.approx(2.503326, rel=1e-3)
    f, sampled, pdf = golden.sampleDir(wo, (0.1, 0.8), mode="importance")
    assert LUMINANCE @ f == pytest.approx(2.596391, rel=1e-3)
    assert pdf == pytest.approx(1.855472, rel=1e-3)
    np.testing.assert_allclose(sampled, [0.539052, 0.617347, 0.572980], rtol=1e-3)
    with pytest.raises(ValueError, match="radiance"):
        golden.evalDir(wo, wi, mode="photons")


def test_golden_from_bytes_and_damage(golden, testdata_dir):
    data = (testdata_dir / "roughgold_alpha_0.2.bsdf").read_bytes()
    copy = ll.BSDFStorage.fromBytes(data)
    np.testing.assert_array_equal(copy.eval(0.5, -0.4, 0.3), golden.eval(0.5, -0.4, 0.3))
    for cut in (10, 64, 1000, len(data) - 1):
        with pytest.raises(ll.FormatError):
            ll.BSDFStorage.fromBytes(data[:cut])


def test_golden_albedo_is_the_sample_weight_mean(golden):
    # A grid of cell midpoints in u (u[1] picks mu_o, u[0] phi).
    for mu_i in (0.9, 0.4):
        reflected, transmitted = golden.albedo(mu_i)
        assert transmitted.tolist() == [0.0, 0.0, 0.0]
        mean = np.zeros(3)
        n_mu, n_phi = 500, 64
        for a in range(n_phi):
            for b in range(n_mu):
                weight, _mu_o, _phi, _pdf = golden.sample(mu_i, ((a + 0.5) / n_phi,
                                                                 (b + 0.5) / n_mu))
                mean += weight
        mean /= n_mu * n_phi
        np.testing.assert_allclose(reflected, mean, atol=1e-3)
        assert 0.1 < reflected[0] < 1.0
