"""The seed's notebook, cell by cell, on our library.

The cells run in order and share their state as a notebook does (module-
scoped fixtures). Each test checks what the cell showed: the printed
Gauss-Lobatto arrays, help(ll.quad), the pictures of plot_layer (written as
PNG files), and the repr of the written .bsdf file.
"""

import os
import pydoc
import subprocess
import sys
import time

import matplotlib.pyplot as plt
import numpy as np
import pytest
from numpy.polynomial import legendre

import layerlab as ll


# ---------------------------------------------------------------- the seed's helper

def plot_layer(layer, phi_d=0.0, title=None, filename=None, resolution=200):
    """The seed's plot_layer: the four blocks of a layer laid out as in its
    scattering matrix (T^bt, R^t over R^b, T^tb), each an image over
    (mu_i, mu_o) of the BSDF times |mu_i mu_o| at azimuth phi_d, with a colour
    bar whose scale is clipped at the 99th percentile."""
    ranges = {-1: np.linspace(-1, 0, resolution), +1: np.linspace(0, 1, resolution)}
    fig, axes = plt.subplots(2, 2, figsize=(9, 8))
    # (sign of mu_i, sign of mu_o, name): rows are outgoing (mu_o < 0, light
    # leaving upwards, on top), columns incident (mu_i < 0, from below, left).
    blocks = [(-1, -1, "$T^{bt}$"), (+1, -1, "$R^{t}$"),
              (-1, +1, "$R^{b}$"), (+1, +1, "$T^{tb}$")]
    data = {}
    for ax, (si, so, name) in zip(axes.flat, blocks):
        mu_i, mu_o = np.meshgrid(ranges[si], ranges[so])
        values = layer.eval(mu_o, mu_i, phi_d) * np.abs(mu_i * mu_o)
        vmax = np.percentile(values, 99)
        extent = (ranges[si][0], ranges[si][-1], ranges[so][-1], ranges[so][0])
        image = ax.imshow(values, extent=extent, aspect="auto", vmin=0,
                          vmax=vmax if vmax > 0 else 1, cmap="inferno")
        ax.set_title(name)
        ax.set_xlabel(r"$\mu_i$")
        ax.set_ylabel(r"$\mu_o$")
        fig.colorbar(image, ax=ax)
        data[name] = (mu_i, mu_o, values)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if filename is not None:
        fig.savefig(filename, dpi=80)
    plt.close(fig)
    return data


def _check_png(path):
    with open(path, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert os.path.getsize(path) > 10000  # four panels with colour bars, not an empty canvas


# ---------------------------------------------------------------- cells 1-3

def test_cell_import_in_a_fresh_python():
    # `import layerlab as ll` in a new interpreter, from a directory that is
    # not the package's: what a new user's notebook kernel does.
    env = dict(os.environ)
    package_root = os.path.dirname(os.path.dirname(ll.__file__))
    env["PYTHONPATH"] = package_root + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", "import layerlab as ll; print(ll.Layer.__name__)"],
                         cwd="/", env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "Layer"


def test_cell_help_quad():
    text = pydoc.render_doc(ll.quad, renderer=pydoc.plaintext)
    assert "layerlab.quad - Functions for numerical quadrature" in text
    for name in ("gaussLegendre", "gaussLobatto", "compositeSimpson", "compositeSimpson38"):
        assert "    %s(n)" % name in text
        doc = getattr(ll.quad, name).__doc__
        assert "Parameter ``n``:" in doc and "Returns:" in doc
    assert "degree 2n-3" in ll.quad.gaussLobatto.__doc__
    assert "degree 2n-1" in ll.quad.gaussLegendre.__doc__


SEED_PRINT_LEGACY = (
    "[-1.         -0.91953391 -0.73877387 -0.47792495 -0.16527896  0.16527896\n"
    "  0.47792495  0.73877387  0.91953391  1.        ] "
    "[ 0.02222222  0.13330599  0.22488934  0.29204268  0.32753976  0.32753976\n"
    "  0.29204268  0.22488934  0.13330599  0.02222222]\n")

SEED_PRINT_MODERN = (
    "[-1.         -0.91953391 -0.73877387 -0.47792495 -0.16527896  0.16527896\n"
    "  0.47792495  0.73877387  0.91953391  1.        ] "
    "[0.02222222 0.13330599 0.22488934 0.29204268 0.32753976 0.32753976\n"
    " 0.29204268 0.22488934 0.13330599 0.02222222]\n")


def test_cell_gauss_lobatto_10_prints_the_seed_arrays(capsys):
    mu, w = ll.quad.gaussLobatto(10)
    # The seed's notebook ran numpy < 1.14, whose printing is legacy='1.13'.
    with np.printoptions(legacy="1.13"):
        print(mu, w)
    assert capsys.readouterr().out == SEED_PRINT_LEGACY
    # Today's numpy drops the sign column of all-positive arrays; same numbers.
    with np.printoptions(legacy=False):
        print(mu, w)
    assert capsys.readouterr().out == SEED_PRINT_MODERN


def test_gauss_lobatto_10_against_legendre_polynomials():
    # Independent reference: interior nodes are the roots of P_9',
    # weights 2 / (n (n-1) P_9(x)^2).
    n = 10
    p = np.zeros(n)
    p[-1] = 1.0
    x = np.concatenate([[-1.0], np.sort(legendre.legroots(legendre.legder(p))), [1.0]])
    w = 2.0 / (n * (n - 1) * legendre.legval(x, p) ** 2)
    mu, weights = ll.quad.gaussLobatto(n)
    assert mu.dtype == np.float64 and mu.shape == (n,)
    np.testing.assert_allclose(mu, x, rtol=0, atol=1e-14)
    np.testing.assert_allclose(weights, w, rtol=1e-13)


def test_quad_rules_and_their_errors():
    x, w = ll.quad.gaussLegendre(7)
    ref_x, ref_w = legendre.leggauss(7)
    np.testing.assert_allclose(x, ref_x, atol=1e-14)
    np.testing.assert_allclose(w, ref_w, rtol=1e-13)
    for rule, n in ((ll.quad.compositeSimpson, 9), (ll.quad.compositeSimpson38, 10)):
        x, w = rule(n)
        np.testing.assert_allclose(x, np.linspace(-1, 1, n), atol=1e-15)
        # exact for cubics
        assert abs(np.dot(w, x ** 3 + 2 * x ** 2 + 1) - (4.0 / 3 + 2)) < 1e-13
    with pytest.raises(ValueError, match="ll_quad"):
        ll.quad.compositeSimpson(4)
    with pytest.raises(ValueError):
        ll.quad.gaussLobatto(-3)
    with pytest.raises(TypeError):
        ll.quad.gaussLobatto(2.5)


# ---------------------------------------------------------------- cell: diffuse

@pytest.fixture(scope="module")
def mu_w10():
    return ll.quad.gaussLobatto(10)


def test_cell_diffuse_layer(mu_w10, out_dir):
    mu, w = mu_w10
    layer = ll.Layer(mu, w)
    layer.setDiffuse(albedo=0.5)
    assert repr(layer).startswith("Layer[resolution=10x10, fourierOrders=1, nonZeros=")
    data = plot_layer(layer, title="diffuse, albedo 0.5", filename=out_dir / "seed_diffuse.png")
    _check_png(out_dir / "seed_diffuse.png")
    mu_i, mu_o, values = data["$R^{t}$"]
    assert mu_i.min() == 0 and mu_i.max() == 1 and mu_o.min() == -1 and mu_o.max() == 0
    np.testing.assert_allclose(values, 0.5 / np.pi * np.abs(mu_i * mu_o), atol=1e-12)
    mu_i, mu_o, values = data["$R^{b}$"]
    np.testing.assert_allclose(values, 0.5 / np.pi * np.abs(mu_i * mu_o), atol=1e-12)
    assert np.all(data["$T^{tb}$"][2] == 0) and np.all(data["$T^{bt}$"][2] == 0)


# ---------------------------------------------------------------- cells: rough interfaces

@pytest.fixture(scope="module")
def mu_w200():
    return ll.quad.gaussLobatto(200)


@pytest.fixture(scope="module")
def dielectric(mu_w200, timings):
    mu, w = mu_w200
    start = time.perf_counter()
    dielectric = ll.Layer(mu, w, 200)
    dielectric.setMicrofacet(eta=1.5, alpha=0.1)
    timings["seed: dielectric (n=200, m=200) setMicrofacet"] = time.perf_counter() - start
    return dielectric


@pytest.fixture(scope="module")
def conductor(mu_w200, timings):
    mu, w = mu_w200
    start = time.perf_counter()
    conductor = ll.Layer(mu, w, 200)
    conductor.setMicrofacet(eta=0 + 1j, alpha=0.1)
    timings["seed: conductor (n=200, m=200) setMicrofacet"] = time.perf_counter() - start
    return conductor


@pytest.fixture(scope="module")
def coated(dielectric, conductor, timings):
    # The seed stacks in place: conductor.addToTop(dielectric). A copy keeps
    # the bare conductor for its own cell.
    layer = ll.Layer(conductor)
    start = time.perf_counter()
    layer.addToTop(dielectric)
    timings["seed: addToTop (n=200, m=200)"] = time.perf_counter() - start
    timings["seed: 200-node coated-conductor cell, total"] = (
        timings["seed: dielectric (n=200, m=200) setMicrofacet"]
        + timings["seed: conductor (n=200, m=200) setMicrofacet"]
        + timings["seed: addToTop (n=200, m=200)"])
    return layer


# Evaluating a layer of 200 nodes and 200 orders costs tens of microseconds
# per point (every order's 4 x 4 spline neighbours), so the pictures of the
# 200-node layers use 100 x 100 grids to keep the suite fast; the seed's full
# 200 x 200 grid is timed once, for one panel.
def test_one_seed_panel_of_a_200_node_layer(dielectric, timings):
    t = np.linspace(0, 1, 200)
    mu_i, mu_o = np.meshgrid(t, -t)
    start = time.perf_counter()
    values = dielectric.eval(mu_o, mu_i, 0.0)
    timings["Layer.eval of one 200x200 panel (n=200, m=200)"] = time.perf_counter() - start
    assert values.shape == (200, 200) and values.max() > 0


def test_cell_dielectric(dielectric, out_dir):
    assert dielectric.resolution == 200 and dielectric.fourierOrders == 200
    data = plot_layer(dielectric, title="rough dielectric, eta 1.5, alpha 0.1",
                      filename=out_dir / "seed_dielectric.png", resolution=100)
    _check_png(out_dir / "seed_dielectric.png")
    # A dielectric reflects and transmits on both sides ...
    assert all(values.max() > 0 for _, _, values in data.values())
    # ... and, with the energy compensation, loses nothing.
    for mu_i in (0.2, 0.5, 0.9, -0.5):
        r, t = dielectric.albedo(mu_i)
        assert abs(r + t - 1) < 2e-3, (mu_i, r, t)


def test_cell_conductor(conductor, out_dir):
    data = plot_layer(conductor, title="rough conductor, eta 0+1j, alpha 0.1",
                      filename=out_dir / "seed_conductor.png", resolution=100)
    _check_png(out_dir / "seed_conductor.png")
    # Opaque: no transmission anywhere.
    assert np.all(data["$T^{tb}$"][2] == 0) and np.all(data["$T^{bt}$"][2] == 0)
    # eta = i reflects everything (|(c - i)/(c + i)| = 1).
    for mu_i in (0.3, 0.7, 1.0):
        r, t = conductor.albedo(mu_i)
        assert abs(r - 1) < 5e-3 and t == 0, (mu_i, r, t)


def test_cell_coated_conductor(coated, conductor, out_dir):
    data = plot_layer(coated, title="rough conductor under a rough dielectric coat",
                      filename=out_dir / "seed_coated.png", resolution=100)
    _check_png(out_dir / "seed_coated.png")
    assert np.all(data["$T^{tb}$"][2] == 0)
    # Neither part absorbs, so the stack reflects everything too.
    for mu_i in (0.3, 0.7, 1.0):
        r, t = coated.albedo(mu_i)
        assert abs(r - 1) < 1e-2 and abs(t) < 1e-12, (mu_i, r, t)
    # The coat changes the lobe: the stacked layer differs from the bare one.
    assert abs(coated.eval(-0.6, 0.6) - conductor.eval(-0.6, 0.6)) > 1e-3


# The seed printed (one line):
#   BSDFStorage[mmap = MemoryMappedFile[filename="output.bsdf", size=3.3 MiB], nNodes = 202,
#   nMaxOrder = 200, nChannels = 1, nBases = 1, eta = 1]
# Everything but the size follows from the cell; the size depends on how
# compact the layer's Fourier series are (the original's interfaces kept
# more coefficients), so it is checked against the file instead.
SEED_STORAGE_REPR = ('BSDFStorage[mmap = MemoryMappedFile[filename="output.bsdf", size={size}], '
                     'nNodes = 202, nMaxOrder = 200, nChannels = 1, nBases = 1, eta = 1]')


def test_cell_from_layer_repr(coated, tmp_path, monkeypatch, timings):
    monkeypatch.chdir(tmp_path)
    storage = ll.BSDFStorage.fromLayer("output.bsdf", coated)
    size = os.path.getsize(tmp_path / "output.bsdf")
    assert storage.size == size
    text = "%.1f MiB" % (size / 1024.0 ** 2)
    assert repr(storage) == SEED_STORAGE_REPR.format(size=text)
    timings["seed: output.bsdf size (the seed's: 3.3 MiB)"] = (size / 1024.0 ** 2, "MiB")
