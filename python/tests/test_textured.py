"""Textured files from Python: BSDFStorage.fromLayerGeneral (layers built by
hand, one per basis and channel, through ll_bsdf_write_textured), the axes
(names from the metadata, sample positions), basisCoefficients and
evaluation / sampling by parameter value (params=)."""

import json
import math

import numpy as np
import pytest

import layerlab as ll


def diffuse_albedo(a, d):
    """The albedo of the Lambertian test file at (albedo, dim) = (a, d):
    bases 0.2 / 0.8 at a = 0 / 1, halved at d = 1; the file's linear
    weights make it exactly this bilinear function."""
    return (0.2 + 0.6 * a) * (1.0 - 0.5 * d)


@pytest.fixture(scope="module")
def lambertian(tmp_path_factory):
    mu, w = ll.quad.gaussLobatto(20)
    layers = []
    for d in (0.0, 1.0):           # parameter 1, slow
        for a in (0.0, 1.0):       # parameter 0, fast
            layer = ll.Layer(mu, w, 1)
            layer.setDiffuse(diffuse_albedo(a, d))
            layers.append(layer)
    path = tmp_path_factory.mktemp("textured") / "lambertian.bsdf"
    return ll.BSDFStorage.fromLayerGeneral(path, layers, paramSamplePositions=[[0, 1], [0, 1]],
                                           paramNames=["albedo", "dim"])


def rough_conductor(mu, w, alpha):
    layer = ll.Layer(mu, w, 80)
    layer.setMicrofacet(eta=0.2 + 3j, alpha=alpha)
    return layer


def test_axes_names_and_positions(lambertian):
    assert lambertian.basisCount == 4 and lambertian.parameterCount == 2
    assert lambertian.parameterNames == ["albedo", "dim"]
    axes = lambertian.axes
    assert [name for name, _ in axes] == ["albedo", "dim"]
    for _, positions in axes:
        np.testing.assert_array_equal(positions, [0.0, 1.0])
    assert json.loads(lambertian.metadata)["parameters"] == ["albedo", "dim"]


def test_basis_coefficients(lambertian):
    c = lambertian.basisCoefficients([0.25, 0.5])
    assert c.dtype == np.float32 and c.shape == (4,)
    np.testing.assert_allclose(c, [0.375, 0.125, 0.375, 0.125], rtol=1e-7)
    np.testing.assert_array_equal(c, lambertian.basisCoefficients({"dim": 0.5, "albedo": 0.25}))
    # Outside the samples: clamped to the nearest corner.
    np.testing.assert_array_equal(lambertian.basisCoefficients([-3, 7]), [0, 0, 1, 0])
    assert math.isclose(float(np.sum(lambertian.basisCoefficients([0.7, 0.1]))), 1.0,
                        rel_tol=1e-6)


def test_eval_by_parameter_value(lambertian):
    for a, d in [(0, 0), (1, 1), (0.25, 0.5), (0.9, 0.3), (2.0, -1.0)]:
        want = diffuse_albedo(min(max(a, 0), 1), min(max(d, 0), 1)) / math.pi
        f = lambertian.eval(0.6, -0.4, 0.3, params=[a, d])
        np.testing.assert_allclose(f, [want] * 3, rtol=2e-6)
        fd = lambertian.evalDir([0.1, 0.2, 0.9], [-0.3, 0.1, 0.8], params={"albedo": a, "dim": d})
        np.testing.assert_allclose(fd, [want] * 3, rtol=1e-3)
    # Arrays broadcast as with basisCoeffs.
    assert lambertian.eval(np.linspace(0.1, 0.9, 5), -0.5, params=[0.5, 0.5]).shape == (5, 3)


def test_sampling_by_parameter_value(lambertian):
    params = {"albedo": 0.3, "dim": 0.6}
    for u in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)]:
        weight, mu_o, phi_d, pdf = lambertian.sample(0.7, u, params=params)
        assert pdf > 0
        assert math.isclose(pdf, lambertian.pdf(0.7, mu_o, phi_d, params=params), rel_tol=1e-3)
        f, wi, pdf_dir = lambertian.sampleDir([0.2, 0.1, 0.9], u, params=params)
        assert math.isclose(pdf_dir, lambertian.pdfDir([0.2, 0.1, 0.9], wi, params=params),
                            rel_tol=1e-3)
        np.testing.assert_allclose(f, lambertian.evalDir([0.2, 0.1, 0.9], wi, params=params),
                                   rtol=1e-3)


def test_sample_point_equals_the_untextured_file(tmp_path):
    """A textured file over alpha evaluated at a sample equals the untextured
    file of that sample's layer. Both keep every non-zero order (errorGoal
    0): with truncation the textured file's series are the longest over its
    bases, so it keeps terms the untextured one cuts."""
    mu, w = ll.quad.gaussLobatto(40)
    alphas = [0.2, 0.3, 0.5]
    layers = [rough_conductor(mu, w, a) for a in alphas]
    textured = ll.BSDFStorage.fromLayerGeneral(tmp_path / "t.bsdf", layers,
                                               paramSamplePositions=[alphas],
                                               paramNames=["alpha"], errorGoal=0)
    plain = ll.BSDFStorage.fromLayer(tmp_path / "p.bsdf", layers[1], errorGoal=0)
    mu_i = np.linspace(0.2, 0.95, 7)[:, None]
    mu_o = -np.linspace(0.2, 0.95, 7)[None, :]
    a = textured.eval(mu_i, mu_o, 0.4, params=[0.3])[..., 1]
    b = plain.eval(mu_i, mu_o, 0.4)[..., 1]
    significant = b > 0.01 * b.max()
    np.testing.assert_allclose(a[significant], b[significant], rtol=1e-6)
    # Between samples: between the neighbouring samples' values (a convex blend).
    lo = textured.eval(mu_i, mu_o, 0.4, params=[0.2])[..., 1]
    hi = textured.eval(mu_i, mu_o, 0.4, params=[0.3])[..., 1]
    mid = textured.eval(mu_i, mu_o, 0.4, params=[0.25])[..., 1]
    np.testing.assert_allclose(mid, 0.5 * (lo + hi), rtol=1e-6, atol=1e-12)


def test_flat_positions_and_default_names(tmp_path):
    """The original's calling convention: flat positions with counts; no
    names gives p0, p1."""
    mu, w = ll.quad.gaussLobatto(10)
    layers = []
    for k in range(6):
        layer = ll.Layer(mu, w, 1)
        layer.setDiffuse(0.1 + 0.1 * k)
        layers.append(layer)
    s = ll.BSDFStorage.fromLayerGeneral(tmp_path / "flat.bsdf", layers, 1, nBases=6,
                                        nParameters=2, paramSampleCounts=[3, 2],
                                        paramSamplePositions=[0, 1, 2, 10, 20])
    assert s.parameterNames == ["p0", "p1"]
    assert s.parameterSamplePositions(0) == [0, 1, 2]
    assert s.parameterSamplePositions(1) == [10, 20]
    # Basis 5 = (p0 index 2, p1 index 1): albedo 0.6.
    np.testing.assert_allclose(s.eval(0.5, -0.5, params=[2, 20]), [0.6 / math.pi] * 3,
                               rtol=2e-6)


def test_rgb_layers_and_metadata_merge(tmp_path):
    mu, w = ll.quad.gaussLobatto(10)
    layers = []
    for base in (0.2, 0.6):
        for c in range(3):
            layer = ll.Layer(mu, w, 1)
            layer.setDiffuse(base * (1 + 0.25 * c))
            layers.append(layer)
    s = ll.BSDFStorage.fromLayerGeneral(tmp_path / "rgb.bsdf", layers, nChannels=3,
                                        paramSamplePositions=[[0.0, 1.0]], paramNames=["x"],
                                        metadata='{"generator": "test", "note": 1}')
    meta = json.loads(s.metadata)
    assert meta["note"] == 1 and meta["parameters"] == ["x"]
    assert s.channelCount == 3 and s.basisCount == 2
    f = s.eval(0.5, -0.5, params={"x": 0.5})
    np.testing.assert_allclose(f, np.array([0.4, 0.5, 0.6]) / math.pi, rtol=1e-3)


def test_errors(lambertian, tmp_path):
    with pytest.raises(ll.InvalidArgumentError, match="has 2 parameters"):
        lambertian.basisCoefficients([0.5])
    with pytest.raises(ll.InvalidArgumentError, match="unknown"):
        lambertian.basisCoefficients({"albedo": 0.5, "dim": 0.5, "gloss": 1})
    with pytest.raises(ll.InvalidArgumentError, match="missing"):
        lambertian.basisCoefficients({"albedo": 0.5})
    with pytest.raises(ll.InvalidArgumentError, match="not finite"):
        lambertian.basisCoefficients([float("nan"), 0])
    with pytest.raises(ll.InvalidArgumentError, match="not both"):
        lambertian.eval(0.5, -0.5, basisCoeffs=[1, 0, 0, 0], params=[0, 0])
    with pytest.raises(ll.InvalidArgumentError):
        lambertian.eval(0.5, -0.5)  # textured: weights are required

    mu, w = ll.quad.gaussLobatto(10)
    layer = ll.Layer(mu, w, 1)
    layer.setDiffuse(0.5)
    plain = ll.BSDFStorage.fromLayer(tmp_path / "plain.bsdf", layer)
    assert plain.axes == [] and plain.parameterNames == []
    with pytest.raises(ll.InvalidArgumentError, match="not textured"):
        plain.basisCoefficients([0.5])
    with pytest.raises(IndexError):
        plain.parameterName(0)

    out = tmp_path / "never.bsdf"
    with pytest.raises(ll.InvalidArgumentError, match="need 4"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 3, paramSamplePositions=[[0, 1], [0, 1]])
    with pytest.raises(ll.InvalidArgumentError, match="nBases"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 2, nBases=3,
                                        paramSamplePositions=[[0, 1]])
    with pytest.raises(ll.InvalidArgumentError, match="add up"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 2, paramSampleCounts=[3],
                                        paramSamplePositions=[0, 1])
    with pytest.raises(ll.InvalidArgumentError, match="paramNames has 1"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 4, paramSamplePositions=[[0, 1], [0, 1]],
                                        paramNames=["a"])
    with pytest.raises(ll.InvalidArgumentError, match="distinct"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 4, paramSamplePositions=[[0, 1], [0, 1]],
                                        paramNames=["a", "a"])
    with pytest.raises(ll.InvalidArgumentError, match="JSON object"):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 2, paramSamplePositions=[[0, 1]],
                                        paramNames=["a"], metadata="free text")
    with pytest.raises(ll.InvalidArgumentError):  # positions not increasing: the C writer
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 2, paramSamplePositions=[[1, 0]])
    with pytest.raises(ll.UnsupportedError):
        ll.BSDFStorage.fromLayerGeneral(out, [layer] * 2, paramSamplePositions=[[0, 1]],
                                        extrapolate=True)
    assert not out.exists()
