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
  <= 0.1%, 99th percentile <= 2%;
- directional albedos of each lobe (Mitsuba's sampler restricted to the lobe,
  the mean of its weights, and our f |cos| / Mitsuba's pdf at the same
  directions): within 1%.
Prints the table by alpha.
"""

import ctypes
import os
import subprocess

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

import mitsuba_scenes as S  # noqa: E402
from test_tables_mitsuba import _interaction, _unit  # noqa: E402

ALPHAS = (0.05, 0.1, 0.2, 0.4, 0.8)
N_WI = 24          # incident directions per case
N_SAMPLED = 48     # outgoing directions from Mitsuba's sampler, per incident one
N_UNIFORM = 24     # uniform outgoing directions, per incident one
N_ALBEDO = 4000    # samples of a directional albedo
D3 = ctypes.c_double * 3


def _llbuild():
    lib = os.environ["LAYERLAB_LIBRARY"]
    return os.path.join(os.path.dirname(os.path.dirname(lib)), "bin", "llbuild")


def _conductor_text(alpha):
    return S.conductor_text(alpha) + " dist=ggx"


def _dielectric_text(alpha):
    return "dielectric eta=%g alpha=%g dist=ggx compensate=0" % (S.DIELECTRIC_ETA, alpha)


def _mitsuba_bsdf(kind, alpha):
    if kind == "conductor":
        return {"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                "eta": {"type": "rgb", "value": list(S.GOLD_ETA)},
                "k": {"type": "rgb", "value": list(S.GOLD_K)}}
    return {"type": "roughdielectric", "distribution": "ggx", "alpha": alpha,
            "int_ior": S.DIELECTRIC_ETA, "ext_ior": 1.0}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Every (kind, alpha) built by llbuild at the tolerance's resolution:
    ten processes of one thread each, started together (about 90 CPU
    seconds in all)."""
    d = tmp_path_factory.mktemp("ggx")
    llbuild = _llbuild()
    out, procs = {}, []
    for kind, text in (("conductor", _conductor_text), ("dielectric", _dielectric_text)):
        for alpha in ALPHAS:
            src = d / ("%s-%g.layers" % (kind, alpha))
            src.write_text(text(alpha) + "\n")
            path = str(d / ("%s-%g.bsdf" % (kind, alpha)))
            procs.append(subprocess.Popen([llbuild, "--quiet", "--threads", "1", str(src),
                                           "-o", path]))
            out[kind, alpha] = path
    for p in procs:
        assert p.wait() == 0
    return out


def _our_eval(lib, h, wi, wo):
    f = D3()
    assert lib.ll_bsdf_eval_dir(h, D3(*wi), D3(*wo), 0, None, f) == 0
    return np.array(f[:]) * abs(wo[2])


def _case(lib, h, bsdf, side, lobe, rng):
    """Relative differences where f is above 1% of its peak, and the albedo
    pairs (Mitsuba, ours), of one side (+1 above, -1 below) and lobe."""
    mask = mi.BSDFFlags.GlossyReflection if lobe == "R" else mi.BSDFFlags.GlossyTransmission
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, mask)
    full = mi.BSDFContext(mi.TransportMode.Radiance)
    rel, albedos = [], []
    mus = np.linspace(0.1, 1.0, N_WI)
    for k, mu in enumerate(mus):
        wi = _unit(mu, rng.uniform(0, 2 * np.pi)) * np.array([1, 1, side])
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
        rel.append(np.abs(ours[keep] / theirs[keep] - 1))
        if k % 6 == 0:
            # the lobe's albedo, both from the same directions of Mitsuba's
            # (unrestricted) sampler: f |cos| / pdf where they fall in the lobe
            a_mi, a_ll = np.zeros(3), np.zeros(3)
            for _ in range(N_ALBEDO):
                bs, _ = bsdf.sample(full, si, float(rng.uniform()),
                                    mi.Point2f(*rng.uniform(size=2)))
                w = np.array(bs.wo)
                if not bs.pdf > 0 or w[2] * want_side <= 0:
                    continue
                a_mi += np.array(bsdf.eval(full, si, mi.Vector3f(*w))) / float(bs.pdf)
                a_ll += _our_eval(lib, h, wi, w) / float(bs.pdf)
            albedos.append((mu, a_mi / N_ALBEDO, a_ll / N_ALBEDO))
    return np.concatenate(rel), albedos


# The cases that miss the bounds today (docs/method.md, "Rough interfaces",
# the comparison with Mitsuba 3: transmission at the jump |mu_o| = |mu_i| /
# eta, reflection from below at grazing incidence, the conductor's median at
# alpha 0.05). Held both ways: any other case that misses fails the test, and
# so does one of these that starts to pass (then it leaves this list).
KNOWN_MISSES = {
    ("conductor above R", 0.05),
    ("dielectric below T", 0.1),
    ("dielectric below R", 0.2),
    ("dielectric below R", 0.4),
    ("dielectric above T", 0.8),
    ("dielectric below R", 0.8),
    ("dielectric below T", 0.8),
}


def test_ggx_matches_mitsuba(files, timings):
    import layerlab as ll
    from layerlab import _native
    mi.set_variant("scalar_rgb")
    lib = _native.lib
    rng = np.random.default_rng(11)
    rows, failures = [], []
    for kind in ("conductor", "dielectric"):
        for alpha in ALPHAS:
            storage = ll.BSDFStorage(files[kind, alpha])
            h = storage._live()
            bsdf = mi.load_dict(_mitsuba_bsdf(kind, alpha))
            sides = ((1, "R"),) if kind == "conductor" else \
                ((1, "R"), (1, "T"), (-1, "R"), (-1, "T"))
            for side, lobe in sides:
                rel, albedos = _case(lib, h, bsdf, side, lobe, rng)
                a_err = max(np.max(np.abs(a_ll / a_mi - 1)) for _, a_mi, a_ll in albedos)
                name = "%s %s %s" % (kind, "above" if side > 0 else "below", lobe)
                med, p99 = np.median(rel), np.percentile(rel, 99)
                rows.append((name, alpha, storage.nodeCount, storage.maxOrder, len(rel), med,
                             p99, a_err))
                if not (med <= 1e-3 and p99 <= 2e-2 and a_err <= 1e-2):
                    failures.append(rows[-1])
            storage.close()
    print("\nGGX against Mitsuba 3 %s (scalar_rgb), llbuild's resolution, compensate=0" %
          mi.__version__)
    print("%-22s %5s %10s %6s %8s %7s %7s" % ("case", "alpha", "n x m", "points", "median",
                                             "p99", "albedo"))
    for name, alpha, n, m, count, med, p99, a_err in rows:
        print("%-22s %5g %10s %6d %7.3f%% %6.2f%% %6.2f%%" % (
            name, alpha, "%d x %d" % (n, m), count, 100 * med, 100 * p99, 100 * a_err))
    timings["GGX vs Mitsuba: worst median relative difference"] = (
        100 * max(r[5] for r in rows), "%")
    missed = {(row[0], row[1]) for row in failures}
    assert missed <= KNOWN_MISSES, [row for row in failures if (row[0], row[1]) not in
                                    KNOWN_MISSES]
    assert KNOWN_MISSES <= missed, "now within the bounds, remove from KNOWN_MISSES: %s" % (
        sorted(KNOWN_MISSES - missed),)
