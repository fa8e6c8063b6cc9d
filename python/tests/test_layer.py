"""Layer through the C ABI: construction, vectorised eval, matrix, repr,
copies, the adding equations, and errors. Nodes come from numpy's own
Gauss-Legendre rule so these tests do not depend on ll.quad."""

import copy
import pickle

import numpy as np
import pytest
from numpy.polynomial import legendre

import layerlab as ll


def make_layer(n=16, m=1):
    x, w = legendre.leggauss(n)
    return ll.Layer(x, w, m)


def test_new_layer_is_clear():
    layer = make_layer(8, 3)
    assert layer.resolution == 8 and layer.fourierOrders == 3
    np.testing.assert_allclose(layer.nodes, legendre.leggauss(8)[0], atol=0)
    np.testing.assert_allclose(layer.weights, legendre.leggauss(8)[1], atol=0)
    assert layer.albedo(0.5) == pytest.approx((0.0, 1.0), abs=1e-12)
    assert layer.eval(-0.3, 0.5) == 0.0


def test_keyword_arguments_of_the_original():
    x, w = legendre.leggauss(6)
    assert ll.Layer(nodes=x, weights=w, fourierOrders=4).fourierOrders == 4
    assert ll.Layer(x, w, nFourierOrders=5).fourierOrders == 5
    layer = ll.Layer(x, w)
    layer.setDiffuse(albedo=0.25)
    layer.setHenyeyGreenstein(albedo=0.9, g=0.5)
    layer.setIsotropic(albedo=0.3)
    layer.setVonMisesFisher(albedo=0.8, kappa=2.0)
    layer.expand(0.5)


def test_repr_like_the_original():
    layer = make_layer(10, 1)
    layer.setDiffuse(0.5)
    # Order 0's two 5x5 reflection blocks are full, the rest zero.
    assert repr(layer) == "Layer[resolution=10x10, fourierOrders=1, nonZeros=50/100 (50%)]"
    layer = make_layer(10, 3)
    layer.setDiffuse(0.5)
    assert repr(layer) == "Layer[resolution=10x10, fourierOrders=3, nonZeros=50/300 (17%)]"


def test_eval_diffuse_is_albedo_over_pi_on_reflection():
    layer = make_layer(12)
    layer.setDiffuse(albedo=0.7)
    assert layer.eval(-0.4, 0.8) == pytest.approx(0.7 / np.pi, rel=1e-12)
    assert layer.eval(0.4, -0.8, 1.0) == pytest.approx(0.7 / np.pi, rel=1e-12)
    assert layer.eval(0.4, 0.8) == 0.0  # no transmission
    assert isinstance(layer.eval(-0.4, 0.8), float)


def test_eval_broadcasts_any_shapes_and_matches_pointwise():
    layer = make_layer(20, 1)
    layer.setHenyeyGreenstein(albedo=0.9, g=0.6)
    layer.expand(1.0)
    rng = np.random.default_rng(1)
    mu_o = rng.uniform(-1, 1, size=(4, 1, 3))
    mu_i = rng.uniform(-1, 1, size=(5, 1))
    phi = np.array(0.7)
    out = layer.eval(mu_o, mu_i, phi)
    assert out.shape == (4, 5, 3)
    for idx in np.ndindex(out.shape):
        expect = layer.eval(float(mu_o[idx[0], 0, idx[2]]), float(mu_i[idx[1], 0]), 0.7)
        assert out[idx] == expect
    # Lists, non-contiguous views and integer dtypes are accepted too.
    grid = np.linspace(-1, 1, 9)[::2]
    assert layer.eval(list(grid), 0.5).shape == (5,)
    assert layer.eval(grid, np.array([1])).shape == (5,)
    assert layer.eval(np.empty((0, 3)), 0.5).shape == (0, 3)
    # phi_d as an array with phi_d = 0 entries matches the default
    zero = layer.eval(grid, 0.5, np.zeros(5))
    np.testing.assert_array_equal(zero, layer.eval(grid, 0.5))


def test_eval_of_a_200x200_meshgrid_is_one_fast_call():
    layer = make_layer(64, 1)
    layer.setIsotropic(0.9)
    layer.expand(2.0)
    t = np.linspace(-1, 1, 200)
    mu_i, mu_o = np.meshgrid(t, t)
    values = layer.eval(mu_o, mu_i)
    assert values.shape == (200, 200) and np.isfinite(values).all() and values.max() > 0


def test_matrix_blocks():
    layer = make_layer(8, 2)
    layer.setDiffuse(0.4)
    M = layer.matrix(0)
    assert M.shape == (8, 8)
    h = 4
    np.testing.assert_allclose(M[:h, h:], 0.4 / np.pi, rtol=1e-12)  # R^t
    np.testing.assert_allclose(M[h:, :h], 0.4 / np.pi, rtol=1e-12)  # R^b
    assert np.all(M[:h, :h] == 0) and np.all(M[h:, h:] == 0)
    assert np.all(layer.matrix(l=1) == 0)
    with pytest.raises(ValueError, match="order 2"):
        layer.matrix(2)


def test_copies_are_independent():
    layer = make_layer(8)
    layer.setDiffuse(0.5)
    for other in (ll.Layer(layer), layer.copy(), copy.copy(layer), copy.deepcopy(layer)):
        other.clear()
        assert other.eval(-0.5, 0.5) == 0.0
    assert layer.eval(-0.5, 0.5) == pytest.approx(0.5 / np.pi)
    with pytest.raises(TypeError):
        pickle.dumps(layer)


def test_adding_follows_stokes_for_two_plates():
    # Two identical isotropic slabs: adding two slabs of tau must give the
    # slab of 2 tau (doubling is adding), from both entry points.
    a = make_layer(24)
    a.setIsotropic(0.95)
    a.expand(0.5)
    whole = make_layer(24)
    whole.setIsotropic(0.95)
    whole.expand(1.0)
    stacked = ll.Layer.add(a, a)
    on_top = ll.Layer(a)
    on_top.addToTop(a, homogeneous=True)
    below = ll.Layer(a)
    below.addToBottom(a)
    for layer in (stacked, on_top, below):
        for mu in (0.2, 0.6, 1.0):
            assert layer.albedo(mu) == pytest.approx(whole.albedo(mu), abs=1e-9)
    # Non-absorbing: R + T = 1.
    c = make_layer(24)
    c.setIsotropic(1.0)
    c.expand(3.0)
    r, t = c.albedo(0.5)
    assert r + t == pytest.approx(1.0, abs=1e-6)


def test_ggx_interface_by_name():
    # The distribution is chosen by name; GGX's longer tails reflect more
    # light far from the mirror direction than Beckmann's of the same alpha,
    # and a compensated, non-absorbing GGX dielectric conserves energy: to
    # the node quadrature's error at its transmission jump (docs/method.md,
    # "Rough interfaces"; at 40 nodes up to 8.3e-3 from 0.7, -0.7, 0.3,
    # 0.95, -0.3), where single scattering alone loses 7.7% from 0.7.
    beckmann, ggx = make_layer(40, 40), make_layer(40, 40)
    beckmann.setMicrofacet(eta=0.2 + 3j, alpha=0.2)
    ggx.setMicrofacet(eta=0.2 + 3j, alpha=0.2, distribution="ggx")
    far = (0.9, -0.3, 0.0)  # mu_o, mu_i (the original's order), phi
    assert ggx.eval(*far) > 2.0 * beckmann.eval(*far) > 0.0
    glass = make_layer(40, 40)
    glass.setMicrofacet(eta=1.5, alpha=0.5, distribution="ggx")
    r, t = glass.albedo(0.7)
    assert r + t == pytest.approx(1.0, abs=1e-2)
    single = make_layer(40, 40)
    single.setMicrofacet(eta=1.5, alpha=0.5, conserveEnergy=False, distribution="ggx")
    assert sum(single.albedo(0.7)) < 0.95
    with pytest.raises(ll.InvalidArgumentError, match="distribution"):
        glass.setMicrofacet(eta=1.5, alpha=0.5, distribution="phong")


def test_reverse_swaps_sides():
    clear = make_layer(10)
    diffuse = make_layer(10)
    diffuse.setDiffuse(0.5)
    medium = make_layer(10)
    medium.setIsotropic(0.5)
    medium.expand(0.3)
    diffuse.addToTop(medium)
    # Lit from above: the stack reflects more than its thin medium alone ...
    up = diffuse.albedo(0.7)[0]
    diffuse.reverse()
    # ... and reversed, light from below meets the same stack.
    assert diffuse.albedo(-0.7)[0] == pytest.approx(up, rel=1e-12)
    clear.reverse()
    assert clear.albedo(0.5) == pytest.approx((0.0, 1.0))


def test_errors_carry_the_library_message():
    x, w = legendre.leggauss(6)
    with pytest.raises(ll.InvalidArgumentError, match=r"albedo 1\.5 is outside \[0, 1\]") as e:
        ll.Layer(x, w).setDiffuse(1.5)
    assert isinstance(e.value, ValueError) and isinstance(e.value, ll.Error)
    assert e.value.status == 1
    with pytest.raises(ValueError, match="even"):
        ll.Layer(*legendre.leggauss(5))  # odd count, with a node at 0
    with pytest.raises(ValueError, match="3 nodes but 2 weights"):
        ll.Layer([-0.5, 0.1, 0.5], [1, 1])
    with pytest.raises(ValueError, match="negative"):
        ll.Layer(x, w, -1)
    with pytest.raises(ValueError, match="Fourier order"):
        ll.Layer(x, w, 0)
    with pytest.raises(ValueError, match="one-dimensional"):
        ll.Layer(np.ones((2, 2)), np.ones((2, 2)))
    with pytest.raises(TypeError):
        ll.Layer(x)
    with pytest.raises(TypeError):
        ll.Layer(x, w).addToTop("not a layer")
    with pytest.raises(TypeError):
        ll.Layer(x, w).setDiffuse(0.5j)
    with pytest.raises(ValueError):
        ll.Layer.add(make_layer(6), make_layer(8))  # mismatched layers


def test_failed_setter_leaves_layer_unchanged():
    layer = make_layer(8)
    layer.setDiffuse(0.5)
    with pytest.raises(ValueError):
        layer.setHenyeyGreenstein(0.5, 1.5)
    assert layer.eval(-0.5, 0.5) == pytest.approx(0.5 / np.pi)


def test_exception_hierarchy():
    assert issubclass(ll.FormatError, ValueError) and issubclass(ll.ParseError, ValueError)
    assert issubclass(ll.FileError, OSError) and issubclass(ll.OutOfMemoryError, MemoryError)
    assert issubclass(ll.UnsupportedError, NotImplementedError)
    assert issubclass(ll.NumericalError, ArithmeticError)
    for cls in (ll.InvalidArgumentError, ll.FileError, ll.FormatError, ll.OutOfMemoryError,
                ll.NumericalError, ll.UnsupportedError, ll.ParseError, ll.CancelledError):
        assert issubclass(cls, ll.Error)
        assert str(cls("message text")) == "message text"
    assert ll.FormatError.__module__ == "layerlab"


def test_thread_count_is_per_thread_and_results_do_not_depend_on_it():
    layer = make_layer(32, 4)
    layer.setHenyeyGreenstein(0.8, 0.3)
    before = ll.threadCount()
    try:
        ll.setThreadCount(1)
        assert ll.threadCount() == 1
        one = ll.Layer(layer)
        one.expand(1.0)
        ll.setThreadCount(0)
        many = ll.Layer(layer)
        many.expand(1.0)
        np.testing.assert_array_equal(one.matrix(1), many.matrix(1))
        with pytest.raises(ValueError):
            ll.setThreadCount(10 ** 6)
    finally:
        ll.setThreadCount(0 if before > 1 else 1)


def test_heuristics_and_fresnel():
    n, m = ll.parameterHeuristicHG(g=0.5)
    assert n > 0 and m > 0 and n % 2 == 0
    n, m = ll.parameterHeuristicMicrofacet(alpha=0.1, eta=1.5)
    assert n % 2 == 0 and m > 0
    n2, m2 = ll.parameterHeuristicMicrofacet(alpha=0.1, eta=0.2 + 3j)
    assert n2 % 2 == 0 and m2 > 0
    f, cos_t = ll.fresnelDielectric(1.0, 1.5)
    # The refracted cosine has the sign of the side it leaves into: the
    # other side, so the opposite sign (the original's convention).
    assert f == pytest.approx(0.04, abs=1e-12) and cos_t == pytest.approx(-1.0)
    f, cos_t = ll.fresnelDielectric(-0.9, 1.5)  # from inside: Snell with 1.5 / 1
    assert 0 < f < 1 and cos_t == pytest.approx(np.sqrt(1 - 1.5 ** 2 * (1 - 0.9 ** 2)))
    assert ll.fresnelDielectric(0.1, 1 / 1.5)[0] == pytest.approx(1.0)  # total internal reflection
    assert ll.fresnelConductor(1.0, 0 + 1j) == pytest.approx(1.0)
    # |(n - 1 + ik) / (n + 1 + ik)|^2 at normal incidence
    eta = 0.2 + 3j
    assert ll.fresnelConductor(1.0, eta) == pytest.approx(abs((eta - 1) / (eta + 1)) ** 2)
    assert 0.09 < ll.fresnelDielectricIntegral(1.5) < 0.1
    assert ll.fresnelConductorIntegral(1j) == pytest.approx(1.0, abs=1e-6)
