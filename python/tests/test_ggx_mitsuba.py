"""GGX interfaces against Mitsuba 3's own `roughconductor` and
`roughdielectric` with `distribution: "ggx"` (scalar_rgb), point by point.

Our side is the `.bsdf` file `build/bin/llbuild` writes from the material
language with `dist=ggx compensate=0` (single scattering, as Mitsuba's) at
the resolution the tolerance search chooses (the default 1%, |mu| >= 0.1).
Gold is given to both as the same explicit complex index per channel
(mitsuba_scenes.GOLD_ETA, GOLD_K), so no spectra are compared; the
dielectric is eta 1.5, seen from above and from below (Mitsuba's
roughdielectric with int_ior 1.5 and si.wi below the surface).

Conventions: Mitsuba's eval(si, wo) is f |cos theta_o| with si.wi toward the
viewer; ours is ll_bsdf_eval_dir(si.wi, wo) (the renderer convention: f
alone), times |wo.z|, radiance transport in both.

Per case (material, alpha, side, lobe R or T), at incident |mu| 0.1 .. 1:
- point values at outgoing directions Mitsuba's sampler picks in that lobe
  and uniform ones, |mu_o| >= 0.1, where Mitsuba's f is above 1% of its
  peak over that incident direction's points: median relative difference
  <= 0.1%, 99th percentile <= 2%. A GGX transmission value whose spline
  stencils in the file (its nodes in mu_i and mu_o) hold nodes on both
  sides of GGX's jump (eta |mu_o| = |mu_i|) is counted apart (column
  `band`, with the 99th percentile of all values, `p99 all`), not in these
  two: f is discontinuous there in both models (Walter et al. 2007's
  refraction half vector turns horizontal, where GGX's D is alpha^2 / pi),
  and a spline through fixed nodes interpolates across a jump whatever the
  node count, so its error inside the stencils that straddle it stays O(1)
  as the band narrows like 1 / n: no resolution meets a pointwise bound
  there, and the tolerance the file is built to leaves the same band out
  (src/search/probe_jump.c). What the band does to the energy is held by
  the albedos, which count every direction;
- directional albedos of each lobe at four incident directions: within 1%.
  Each albedo is a deterministic quadrature of f |cos| over the lobe's
  hemisphere, the same directions for Mitsuba's f and ours: Gauss-Legendre
  on panels of the outgoing cosine and azimuth that shrink geometrically
  towards the lobe's peak (so a narrow lobe is resolved at any alpha), with
  a panel edge on GGX's jump in the transmitted cosine. The quadrature's
  own change of the ratio ours / Mitsuba's (QUAD points per panel against
  QUAD / 2) is held below ALBEDO_QUADRATURE, so the comparison measures the
  file, not the quadrature. The grids go through Mitsuba's llvm_ad_rgb
  variant and ll_bsdf_eval_dir_batch, a whole grid per call.
Prints the table by alpha.

`python tests/test_ggx_mitsuba.py beckmann` (from python/, with
LAYERLAB_LIBRARY set) prints the same table for Beckmann files against
Mitsuba's `distribution: "beckmann"`: the like-for-like reference of the
misses.
"""

import ctypes
import os
import subprocess

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

import mitsuba_scenes as S  # noqa: E402
from test_tables_mitsuba import _interaction, _unit  # noqa: E402

ALPHAS = (0.05, 0.1, 0.2, 0.4, 0.8)
N_WI = 24          # incident directions per case
N_SAMPLED = 48     # outgoing directions from Mitsuba's sampler, per incident one
N_UNIFORM = 24     # uniform outgoing directions, per incident one
ALBEDO_WI = (0, 6, 12, 18)  # the incident directions (of N_WI) whose albedos are compared
QUAD = 32          # Gauss-Legendre points per panel of an albedo's quadrature
ALBEDO_QUADRATURE = 2.5e-3  # the quadrature's change of the albedos' ratio, at most
#                            (QUAD against QUAD / 2): a quarter of the 1% bound
NO_LOBE = 1e-6     # an albedo below this is no lobe (compared absolutely)
D3 = ctypes.c_double * 3


def _llbuild():
    lib = os.environ["LAYERLAB_LIBRARY"]
    return os.path.join(os.path.dirname(os.path.dirname(lib)), "bin", "llbuild")


def _text(kind, alpha, dist):
    if kind == "conductor":
        return S.conductor_text(alpha) + " dist=" + dist
    return "dielectric eta=%g alpha=%g dist=%s compensate=0" % (S.DIELECTRIC_ETA, alpha, dist)


def _mitsuba_bsdf(kind, alpha, dist="ggx"):
    if kind == "conductor":
        return {"type": "roughconductor", "distribution": dist, "alpha": alpha,
                "eta": {"type": "rgb", "value": list(S.GOLD_ETA)},
                "k": {"type": "rgb", "value": list(S.GOLD_K)}}
    return {"type": "roughdielectric", "distribution": dist, "alpha": alpha,
            "int_ior": S.DIELECTRIC_ETA, "ext_ior": 1.0}


def _build(d, dist):
    """Every (kind, alpha) of a distribution built by llbuild at the
    tolerance's resolution: ten processes of one thread each, started
    together (about 90 CPU seconds in all for GGX)."""
    llbuild = _llbuild()
    out, procs = {}, []
    for kind in ("conductor", "dielectric"):
        for alpha in ALPHAS:
            src = os.path.join(str(d), "%s-%s-%g.layers" % (kind, dist, alpha))
            with open(src, "w") as f:
                f.write(_text(kind, alpha, dist) + "\n")
            path = os.path.join(str(d), "%s-%s-%g.bsdf" % (kind, dist, alpha))
            procs.append(subprocess.Popen([llbuild, "--quiet", "--threads", "1", src,
                                           "-o", path]))
            out[kind, alpha] = path
    for p in procs:
        assert p.wait() == 0
    return out


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return _build(tmp_path_factory.mktemp("ggx"), "ggx")


def _our_eval(lib, h, wi, wo):
    f = D3()
    assert lib.ll_bsdf_eval_dir(h, D3(*wi), D3(*wo), 0, None, f) == 0
    return np.array(f[:]) * abs(wo[2])


def _sides(kind):
    return ((1, "R"),) if kind == "conductor" else ((1, "R"), (1, "T"), (-1, "R"), (-1, "T"))


def _lobe_flags(lobe):
    return mi.BSDFFlags.GlossyReflection if lobe == "R" else mi.BSDFFlags.GlossyTransmission


def _incident(mu, side, azimuth):
    return _unit(mu, azimuth) * np.array([1, 1, side])


def _panels(breaks, lo, hi, order):
    """Gauss-Legendre nodes and weights of `order` points on each panel
    between the sorted breakpoints (those inside (lo, hi), and lo, hi)."""
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.unique(np.clip(np.concatenate(([lo, hi], breaks)), lo, hi))
    a, b = edges[:-1], edges[1:]
    nodes = (0.5 * (b - a)[:, None] * x[None, :] + 0.5 * (a + b)[:, None]).ravel()
    weights = (0.5 * (b - a)[:, None] * w[None, :]).ravel()
    return nodes, weights


def _albedo_grid(lib, h, bsdf, mu_i, side, lobe, alpha, order):
    """Mitsuba's and our albedo of one lobe (llvm_ad_rgb), the integral of
    f |cos| over the lobe's hemisphere, incident direction at azimuth 0:
    Gauss-Legendre of `order` points per panel in the outgoing cosine and
    azimuth (over 0 .. pi, twice: both are even in the azimuth). The panels
    shrink geometrically (by 2, from alpha / 1000) towards the lobe's peak
    (the mirror or the Snell cosine, azimuth pi), whatever its width, and
    one edge lies on GGX's jump in the transmitted cosine (eta |mu_o| =
    |mu_i|). The same directions for both: ours is counted wherever it is
    not 0, also where Mitsuba's f is."""
    from layerlab._util import double_ptr
    eta = S.DIELECTRIC_ETA if side > 0 else 1.0 / S.DIELECTRIC_ETA
    scales = alpha * 1e-3 * 2.0 ** np.arange(16)
    breaks = []
    if lobe == "R":
        peak = mu_i
    else:
        sin_t = np.sqrt(1.0 - mu_i * mu_i) / eta
        peak = np.sqrt(max(0.0, 1.0 - sin_t * sin_t))
        breaks.append(mu_i / eta)                        # the jump
    breaks += list(peak - scales) + list(peak + scales)
    mus, w_mu = _panels(np.array(breaks), 0.0, 1.0, order)
    phis, w_phi = _panels(np.pi - scales, 0.0, np.pi, order)
    mu_o, phi_o = (a.ravel() for a in np.meshgrid(mus, phis))
    weight = (w_mu[None, :] * w_phi[:, None]).ravel() * 2.0
    want_side = side if lobe == "R" else -side
    sin_o = np.sqrt(1.0 - mu_o * mu_o)
    wo = np.ascontiguousarray(np.stack((sin_o * np.cos(phi_o), sin_o * np.sin(phi_o),
                                        want_side * mu_o), axis=1))
    wi = _incident(mu_i, side, 0.0)
    count = len(wo)
    F = mi.Float
    si = dr.zeros(mi.SurfaceInteraction3f, count)
    si.wi = mi.Vector3f(*[F(np.full(count, c)) for c in wi])
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    full = mi.BSDFContext(mi.TransportMode.Radiance)
    theirs = np.array(bsdf.eval(full, si, mi.Vector3f(*[F(wo[:, k]) for k in range(3)])),
                      dtype=np.float64).T
    wis = np.ascontiguousarray(np.tile(wi, (count, 1)))
    ours = np.zeros((count, 3))
    assert lib.ll_bsdf_eval_dir_batch(h, count, double_ptr(wis), double_ptr(wo), 0, None, 0,
                                      double_ptr(ours)) == 0
    ours *= mu_o[:, None]
    return weight @ theirs, weight @ ours


def _albedos(lib, h, kind, alpha, dist):
    """{(side, lobe): [(mu, Mitsuba's albedo, ours, the quadrature's
    change of their ratio)]} at the incident directions ALBEDO_WI, each
    with the quadrature's convergence checked: the ratio of the two
    albedos with QUAD points per panel against QUAD / 2."""
    mi.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict(_mitsuba_bsdf(kind, alpha, dist))
    mus = np.linspace(0.1, 1.0, N_WI)
    out = {}
    for side, lobe in _sides(kind):
        rows = []
        for k in ALBEDO_WI:
            a_mi, a_ll = _albedo_grid(lib, h, bsdf, mus[k], side, lobe, alpha, QUAD)
            if np.all(a_mi < NO_LOBE):
                # no light takes this lobe (Beckmann's transmission from
                # below at grazing incidence and small alpha): none in ours
                assert np.all(np.abs(a_ll) < NO_LOBE), (kind, alpha, side, lobe, mus[k], a_ll)
                continue
            c_mi, c_ll = _albedo_grid(lib, h, bsdf, mus[k], side, lobe, alpha, QUAD // 2)
            change = np.max(np.abs(a_ll / a_mi - c_ll / c_mi))
            assert change <= ALBEDO_QUADRATURE, (kind, alpha, side, lobe, mus[k], a_ll / a_mi,
                                                 c_ll / c_mi)
            rows.append((mus[k], a_mi, a_ll, change))
        out[side, lobe] = rows
    mi.set_variant("scalar_rgb")
    return out


def _stencil_range(half, mu):
    """The smallest and largest node of the Catmull-Rom stencil that the
    reader interpolates |mu| with (numerics/spline.c: the interval holding
    it and one node either side), half: the file's nodes >= 0."""
    k = int(np.clip(np.searchsorted(half, mu, side="right") - 1, 0, len(half) - 2))
    return half[max(k - 1, 0)], half[min(k + 2, len(half) - 1)]


def _straddles_jump(half, side, mu_i, mu_o):
    """Whether the stencils of (|mu_o|, |mu_i|) hold node pairs on both
    sides of GGX's transmission jump |mu_i| = e |mu_o|, e the relative
    index ahead of the light (the rule of search/probe_jump.c)."""
    e = S.DIELECTRIC_ETA if side > 0 else 1.0 / S.DIELECTRIC_ETA
    o_lo, o_hi = _stencil_range(half, mu_o)
    i_lo, i_hi = _stencil_range(half, mu_i)
    return i_hi - e * o_lo > 0.0 and i_lo - e * o_hi < 0.0


def _case(lib, h, bsdf, side, lobe, rng, half=None):
    """Relative differences where f is above 1% of its peak, of one side
    (+1 above, -1 below) and lobe: those clear of GGX's transmission jump
    and those whose stencils straddle it (half: the file's nodes >= 0 for
    GGX transmission, else None and no value is set apart)."""
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, _lobe_flags(lobe))
    full = mi.BSDFContext(mi.TransportMode.Radiance)
    rel, band = [], []
    mus = np.linspace(0.1, 1.0, N_WI)
    for mu in mus:
        wi = _incident(mu, side, rng.uniform(0, 2 * np.pi))
        si = _interaction(wi)
        want_side = side if lobe == "R" else -side
        wos = []
        for _ in range(N_SAMPLED):
            bs, _ = bsdf.sample(ctx, si, float(rng.uniform()), mi.Point2f(*rng.uniform(size=2)))
            wos.append(np.array(bs.wo))
        v = rng.normal(size=(N_UNIFORM, 3))
        wos += list(v / np.linalg.norm(v, axis=1)[:, None])
        wos = [w for w in wos if w[2] * want_side >= 0.1]
        if not wos:
            continue
        theirs = np.array([np.array(bsdf.eval(full, si, mi.Vector3f(*w))) for w in wos])
        ours = np.array([_our_eval(lib, h, wi, w) for w in wos])
        peak = theirs.max(axis=0)
        keep = theirs > 0.01 * peak[None, :]
        apart = np.zeros(len(wos), dtype=bool)
        if half is not None:
            apart = np.array([_straddles_jump(half, side, mu, abs(w[2])) for w in wos])
        diff = np.abs(np.divide(ours, theirs, out=np.ones_like(ours), where=keep) - 1)
        rel.append(diff[keep & ~apart[:, None]])
        band.append(diff[keep & apart[:, None]])
    return np.concatenate(rel), np.concatenate(band)


def _table(files, dist):
    """The rows (case, alpha, n, m, points, median, 99th, albedo error, the
    albedo quadrature's change, values in GGX's jump band, the 99th
    percentile with them) of every case, and the printed table."""
    import layerlab as ll
    from layerlab import _native
    lib = _native.lib
    rng = np.random.default_rng(11)
    rows = []
    for kind in ("conductor", "dielectric"):
        for alpha in ALPHAS:
            storage = ll.BSDFStorage(files[kind, alpha])
            h = storage._live()
            albedos = _albedos(lib, h, kind, alpha, dist)
            bsdf = mi.load_dict(_mitsuba_bsdf(kind, alpha, dist))
            nodes = np.asarray(storage.nodes, dtype=np.float64)
            for side, lobe in _sides(kind):
                jump = dist == "ggx" and lobe == "T"
                rel, band = _case(lib, h, bsdf, side, lobe, rng,
                                  nodes[nodes >= 0.0] if jump else None)
                a_err = max((np.max(np.abs(a_ll / a_mi - 1))
                             for _, a_mi, a_ll, _ in albedos[side, lobe]), default=0.0)
                quad = max((change for _, _, _, change in albedos[side, lobe]), default=0.0)
                name = "%s %s %s" % (kind, "above" if side > 0 else "below", lobe)
                rows.append((name, alpha, storage.nodeCount, storage.maxOrder, len(rel),
                             np.median(rel), np.percentile(rel, 99), a_err, quad, len(band),
                             np.percentile(np.concatenate((rel, band)), 99)))
            storage.close()
    print("\n%s against Mitsuba 3 %s (scalar_rgb), llbuild's resolution, compensate=0" %
          ("GGX" if dist == "ggx" else "Beckmann", mi.__version__))
    print("%-22s %5s %10s %6s %8s %7s %7s %7s %5s %7s" % (
        "case", "alpha", "n x m", "points", "median", "p99", "albedo", "quad", "band",
        "p99 all"))
    for name, alpha, n, m, count, med, p99, a_err, quad, n_band, p99_all in rows:
        print("%-22s %5g %10s %6d %7.3f%% %6.2f%% %6.2f%% %6.3f%% %5d %6.2f%%" % (
            name, alpha, "%d x %d" % (n, m), count, 100 * med, 100 * p99, 100 * a_err,
            100 * quad, n_band, 100 * p99_all))
    return rows


def _misses(rows):
    return [row for row in rows if not (row[5] <= 1e-3 and row[6] <= 2e-2 and row[7] <= 1e-2)]


# The cases that miss the bounds today (docs/method.md, "Rough interfaces",
# the comparison with Mitsuba 3). Held both ways: any other case that misses
# fails the test, and so does one of these that starts to pass (then it
# leaves this list).
KNOWN_MISSES = {
    ("conductor above R", 0.05),
    ("dielectric below R", 0.2),
    ("dielectric below R", 0.4),
    ("dielectric below R", 0.8),
    ("dielectric below T", 0.8),
}


def test_ggx_matches_mitsuba(files, timings):
    mi.set_variant("scalar_rgb")
    rows = _table(files, "ggx")
    timings["GGX vs Mitsuba: worst median relative difference"] = (
        100 * max(r[5] for r in rows), "%")
    failures = _misses(rows)
    missed = {(row[0], row[1]) for row in failures}
    assert missed <= KNOWN_MISSES, [row for row in failures if (row[0], row[1]) not in
                                    KNOWN_MISSES]
    assert KNOWN_MISSES <= missed, "now within the bounds, remove from KNOWN_MISSES: %s" % (
        sorted(KNOWN_MISSES - missed),)


if __name__ == "__main__":
    import sys
    import tempfile
    distribution = sys.argv[1] if len(sys.argv) > 1 else "ggx"
    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as tmp:
        for row in _misses(_table(_build(tmp, distribution), distribution)):
            print("misses the bounds: %s, alpha %g" % (row[0], row[1]))
