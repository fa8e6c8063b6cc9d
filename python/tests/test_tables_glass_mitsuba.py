"""Transmissive table files (a set of tables per lobe and side, docs/formats.md "Extended
table files") in the Mitsuba plugin's "tables" mode (layerlab.mitsuba_lobes,
mitsuba_lobes_stacked) against the C reader (ll_bsdf_eval_dir, ll_bsdf_pdf_dir,
ll_bsdf_sample_dir through layerlab.BSDFStorage) on the same file, and a render of rough glass
from its tables against Mitsuba's native roughdielectric.

Files: rough glass (eta 1.5, alpha 0.3, compensate=0: the refraction half vector's warp), a
frosted pane (the same interface and its inverse, eta 1 overall: the z-flipped direction's
warp) and frosted glass (examples/frosted-glass.layers, the glass compensated: the z-flipped
direction's warp across a net interface, which turns wo between elevations slower than wi
from above and faster from below), written by `llbuild --format measured`.

Pairs: 10^4 per file, wi on either side, wo on either side, half of them about the lobe (wi
reflected or refracted about a normal drawn about the surface's), both with |cos theta| in
[0.05, 1] (as test_tables_mitsuba.py: nearer the horizon the elevation of a float32 direction
moves the warps' look-up by more than 1e-4); as float32, the precision Mitsuba hands the
plugin. Values (f |cos theta_o|, radiance transport: a transmitted value takes eta^2 as the C
reader gives it) and pdfs within 1e-4 relative where f |cos theta_o| is above 1e-3 of its
largest (1e-3 within POLE of the warp's pole, below); the sampled direction for the same two
random numbers within 1e-3 (the plugin's warps work in float32, the C reader's in double), its
pdf and weight within 1e-4 of the C reader's pdf and f |cos| / pdf at that direction where
above 1e-3 of their largest (against the C sampler's own pdf, at its own slightly different
direction, the refraction's change of variables amplifies the direction's difference: that
figure is printed, not checked), and Mitsuba's bookkeeping of the sample (transmission or
reflection, the relative index crossed).
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

ETA = 1.5
GLASS = "dielectric eta=1.5 alpha=0.3 compensate=0\n"
PANE = "set nodes=60 orders=60\ndielectric eta=1.5 alpha=0.3\ndielectric eta=0.6666667 alpha=0.3\n"
FROSTED = "dielectric eta=1.5 alpha=0.3\n"
# A coat over a medium without a base: its reflection from below is stored over F with a
# floor ("fresnel_floor").
COAT = "dielectric eta=1.5 alpha=0.3\nmedium albedo=0.8,0.6,0.4 g=0.5 tau=0.5\n"
# Each file's relative index, and whether its transmitted sets take the z-flipped direction's
# warp (the writer's choice: the refraction half vector reaches too little of a compensated
# interface's transmitted lobe).
ETA_OF = {"glass": ETA, "pane": 1.0, "frosted": ETA, "coat": ETA}
FLIPPED = {"glass": False, "pane": True, "frosted": True, "coat": True}


def _llbuild(text, out, *grid):
    """`llbuild --format measured` of the material text (grid: --theta-i N --vndf N --sample N
    or nothing: the tolerance's choice), the llbuild of the library under test."""
    lib = pathlib.Path(os.environ["LAYERLAB_LIBRARY"]).resolve()
    tool = lib.parent.parent / "bin" / "llbuild"
    if not tool.exists():
        pytest.skip("%s not built" % tool)
    src = out.with_suffix(".layers")
    src.write_text(text)
    subprocess.run([str(tool), "--format", "measured", *grid, str(src), "-o", str(out)],
                   check=True, capture_output=True)
    return str(out)


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    d = tmp_path_factory.mktemp("glass-tables")
    grid = ("--theta-i", "24", "--vndf", "48", "--sample", "32")
    return {"glass": _llbuild(GLASS, d / "glass.tab", *grid),
            "pane": _llbuild(PANE, d / "pane.tab", *grid),
            "frosted": _llbuild(FROSTED, d / "frosted.tab", *grid),
            "coat": _llbuild(COAT, d / "coat.tab", *grid)}


def _plugin(variant, path, **props):
    try:
        mi.set_variant(variant)
    except Exception as error:  # pragma: no cover - depends on the Mitsuba build
        pytest.skip("%s: %s" % (variant, error))
    import layerlab.mitsuba as llmi
    llmi.register()
    return mi.load_dict(dict({"type": "layerlab", "filename": path}, **props))


def _unit_cos(rng, n):
    """n unit vectors with cos theta uniform in [0.05, 1], on a random side."""
    c = rng.uniform(0.05, 1.0, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    s = np.sqrt(1 - c * c)
    side = np.where(rng.uniform(size=n) < 0.5, 1.0, -1.0)
    return np.stack([s * np.cos(phi), s * np.sin(phi), c * side], axis=1)


def _pairs(rng, n, eta):
    """n (wi, wo) pairs as float32 values in float64: half uniform, half about the lobe
    (reflected or, for eta != 1, refracted about a normal drawn about the surface's;
    for eta 1 the straight-through direction about it)."""
    wi, wo = [], []
    while len(wi) < n:
        a = _unit_cos(rng, 1)[0]
        if len(wi) % 2:
            m = np.array([rng.normal(0, 0.3), rng.normal(0, 0.3), 1.0])
            m /= np.linalg.norm(m)
            m = m if a[2] > 0 else -m
            c = np.dot(a, m)
            if rng.uniform() < 0.5:
                b = 2 * c * m - a
            elif eta == 1.0:
                # a pane's transmitted peak: the mirror direction, z flipped
                b = (2 * c * m - a) * np.array([1.0, 1.0, -1.0])
            else:
                e = ETA if a[2] > 0 else 1.0 / ETA
                k = 1 - (1 - c * c) / (e * e)
                if k <= 0:
                    continue
                b = (c / e - np.sqrt(k)) * m - a / e
        else:
            b = _unit_cos(rng, 1)[0]
        if not 0.05 <= abs(b[2]) <= 1.0:
            continue
        b /= np.linalg.norm(b)
        wi.append(a.astype(np.float32).astype(np.float64))
        wo.append(b.astype(np.float32).astype(np.float64))
    return np.array(wi), np.array(wo)


def _warp_elevation(wi, wo, eta, flipped):
    """The elevation of the half vector the file's warp reads for each pair (in wi's side's
    frame: reflection's, the refraction's, or with flipped the z-flipped direction's)."""
    flip = np.where(wi[:, 2:3] < 0, np.array([1.0, 1.0, -1.0]), 1.0)
    w, o = wi * flip, wo * flip
    transmitted = o[:, 2] < 0
    if flipped:
        h = w + o * np.where(transmitted[:, None], np.array([1.0, 1.0, -1.0]), 1.0)
    else:
        e = np.where(wi[:, 2] > 0, eta, 1.0 / eta)[:, None]
        h = np.where(transmitted[:, None], -(w + e * o), w + o)
    h = h / np.linalg.norm(h, axis=1)[:, None]
    return np.arccos(np.clip(np.abs(h[:, 2]), -1.0, 1.0))


# Within this of the warp's pole (theta_m, radians) the format's u_theta = sqrt(theta_m)
# parametrisation is singular and a float32 look-up moves by more than 1e-4 (worst measured:
# 7.3e-4 at theta_m = 1.9e-4, a pane's pair 0.011 degrees from its transmitted peak); such
# pairs are checked to 1e-3.
POLE = 1e-3


def _sampled_direction_close(name, swo, cwo, spdf):
    """The sampled directions within 1e-3 of the C reader's; for frosted glass where the pdf
    is above 1e-3 of its largest, and within 1e-2 elsewhere: its z-flipped sets' D is narrow
    (alpha 0.05-0.07), and in the lobe's far tail at grazing wi (pdf 3e-4 of the largest) the
    float32 warps' inverse CDF moves the direction by up to 4e-3 (measured: 2.6e-4 where
    strong), the pdf there agreeing within 2e-5 at the direction sampled."""
    dist = np.linalg.norm(swo - cwo, axis=1)
    if name != "frosted":
        assert dist.max() < 1e-3, dist.max()
        return dist.max()
    strong = spdf > 1e-3 * spdf.max()
    assert np.count_nonzero(strong) > 0.9 * len(dist)
    assert dist[strong].max() < 1e-3, dist[strong].max()
    assert dist.max() < 1e-2, dist.max()
    return dist[strong].max()


def _close_where_strong(ours, theirs, strong, rtol, what):
    err = np.abs(ours[strong] - theirs[strong]) / theirs[strong]
    worst = float(err.max()) if err.size else 0.0
    assert worst <= rtol, (what, worst)
    return worst


@pytest.mark.parametrize("name", ["glass", "pane", "frosted", "coat"])
def test_tables_are_the_c_reader_llvm(tables, name, timings):
    """eval, pdf and sample of the plugin's "tables" mode (llvm_ad_rgb, 10^4 pairs) against the
    C reader on the same transmissive table file, radiance transport."""
    import layerlab as ll
    path = tables[name]
    bsdf = _plugin("llvm_ad_rgb", path)
    assert "mode=tables" in str(bsdf) and "stacked" in str(bsdf), str(bsdf)
    assert bsdf.flags() & mi.BSDFFlags.GlossyTransmission
    assert bsdf.flags() & mi.BSDFFlags.BackSide
    c = ll.BSDFStorage(path)
    rng = np.random.default_rng({"glass": 17, "pane": 19, "frosted": 29, "coat": 31}[name])
    n = 10000
    wi, wo = _pairs(rng, n, ETA_OF[name])
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(wi.T)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(wo.T))
    value = np.array(value).reshape(3, -1).T
    pdf = np.array(pdf)
    only_value = np.array(bsdf.eval(ctx, si, mi.Vector3f(wo.T))).reshape(3, -1).T
    only_pdf = np.array(bsdf.pdf(ctx, si, mi.Vector3f(wo.T)))
    want = np.array([c.evalDir(a, b) * abs(b[2]) for a, b in zip(wi, wo)])
    want_pdf = np.array([c.pdfDir(a, b) for a, b in zip(wi, wo)])
    strong = want[:, 1] > 1e-3 * want[:, 1].max()
    transmitted = wi[:, 2] * wo[:, 2] < 0
    # both sides, both lobes, enough of each
    for side in (wi[:, 2] > 0, wi[:, 2] < 0):
        for lobe in (transmitted, ~transmitted):
            assert np.count_nonzero(strong & side & lobe) > 200
    pole = _warp_elevation(wi, wo, ETA_OF[name], FLIPPED[name]) < POLE
    worst_value = max(_close_where_strong(value[:, k], want[:, k], strong & ~pole, 1e-4,
                                          "eval") for k in range(3))
    worst_pdf = _close_where_strong(pdf, want_pdf, strong & ~pole, 1e-4, "pdf")
    near_pole = max([_close_where_strong(value[:, k], want[:, k], strong & pole, 1e-3,
                                         "eval at the pole") for k in range(3)] +
                    [_close_where_strong(pdf, want_pdf, strong & pole, 1e-3, "pdf at the pole")])
    timings["glass tables (%s) vs C reader: pairs within %g rad of the warp's pole"
            % (name, POLE)] = (float(np.count_nonzero(strong & pole)), "")
    timings["glass tables (%s) vs C reader: worst there" % name] = (near_pole * 1e6, "x 1e-6")
    np.testing.assert_array_equal(only_value, value)
    np.testing.assert_array_equal(only_pdf, pdf)
    # zero where the C reader has nothing (within float32 rounding of the tail); a coloured
    # lobe (the coat's) may have a channel above that where green is weak, and there no more
    # than the C reader's own value of it
    weak = ~strong
    assert np.all(value[weak] <= np.maximum(want[weak], 1e-3 * want[:, 1].max()) * 1.01)

    u = rng.uniform(size=(n, 2))
    bs, weight = bsdf.sample(ctx, si, mi.Float(0.5), mi.Point2f(u.T))
    swo = np.array(bs.wo).reshape(3, -1).T
    spdf = np.array(bs.pdf)
    sw = np.array(weight).reshape(3, -1).T
    seta = np.array(bs.eta)
    stype = np.array(bs.sampled_type)
    res = [c.sampleDir(a, b) for a, b in zip(wi, u)]
    cf = np.array([r[0] for r in res])
    cwo = np.array([r[1] for r in res])
    cpdf = np.array([r[2] for r in res])
    found = cpdf > 0
    assert np.count_nonzero(found) > 0.9 * n
    assert np.array_equal(found, spdf > 0)
    dist = np.linalg.norm(swo[found] - cwo[found], axis=1)
    _sampled_direction_close(name, swo[found], cwo[found], spdf[found])
    # The pdf and weight of our sample: the C reader's pdf and f |cos| / pdf at our sampled
    # direction (the same direction: the C sampler's own differs by the float32 warps' rounding
    # of the direction, which the refraction's change of variables amplifies in the pdf).
    ours_wo = swo[found].astype(np.float32).astype(np.float64)
    ours_wi = wi[found]
    at_pdf = np.array([c.pdfDir(a, b) for a, b in zip(ours_wi, ours_wo)])
    at_f = np.array([c.evalDir(a, b) * abs(b[2]) for a, b in zip(ours_wi, ours_wo)])
    strong_pdf = at_pdf > 1e-3 * at_pdf.max()
    worst_spdf = _close_where_strong(spdf[found], at_pdf, strong_pdf, 1e-4, "sample pdf")
    at_w = at_f[:, 1] / np.where(at_pdf > 0, at_pdf, 1.0)
    strong_w = strong_pdf & (at_f[:, 1] > 1e-3 * at_f[:, 1].max())
    worst_w = _close_where_strong(sw[found, 1], at_w, strong_w, 1e-4, "sample weight")
    # and against the C sampler's own pdf for the same random numbers
    direct = np.abs(spdf[found] - cpdf[found]) / cpdf[found]
    direct_strong = cpdf[found] > 1e-3 * cpdf[found].max()
    timings["glass tables (%s): sample pdf vs the C sampler's, worst where above 1e-3 of the "
            "largest" % name] = (float(direct[direct_strong].max()) * 1e6, "x 1e-6")
    crossed = found & (wi[:, 2] * cwo[:, 2] < 0)
    assert np.any(crossed) and np.any(found & ~crossed)
    glossy_t = int(mi.BSDFFlags.GlossyTransmission)
    glossy_r = int(mi.BSDFFlags.GlossyReflection)
    assert np.all(stype[crossed] == glossy_t) and np.all(stype[found & ~crossed] == glossy_r)
    eta = ETA_OF[name]
    want_eta = np.where(wi[:, 2] > 0, eta, 1.0 / eta)
    np.testing.assert_allclose(seta[crossed], want_eta[crossed], rtol=1e-6)
    assert np.all(seta[found & ~crossed] == 1.0)
    timings["glass tables (%s) vs C reader: worst eval, pdf, sample pdf, weight" % name] = (
        max(worst_value, worst_pdf, worst_spdf, worst_w) * 1e6, "x 1e-6")
    timings["glass tables (%s) vs C reader: worst sampled direction" % name] = (
        float(dist.max()) * 1e6, "x 1e-6")


@pytest.mark.parametrize("name", ["glass", "pane", "frosted", "coat"])
def test_tables_are_the_c_reader_scalar(tables, name):
    """The same in scalar_rgb (500 pairs), and importance transport (no eta^2)."""
    import layerlab as ll
    path = tables[name]
    bsdf = _plugin("scalar_rgb", path)
    assert "mode=tables" in str(bsdf)
    c = ll.BSDFStorage(path)
    rng = np.random.default_rng(23)
    wi, wo = _pairs(rng, 500, ETA_OF[name])
    rows = []
    for mode, ctx in (("radiance", mi.BSDFContext()),
                      ("importance", mi.BSDFContext(mi.TransportMode.Importance))):
        for a, b in zip(wi, wo):
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*a)
            si.n = mi.Normal3f(0, 0, 1)
            si.sh_frame = mi.Frame3f(si.n)
            v = bsdf.eval(ctx, si, mi.Vector3f(*b))
            rows.append((mode, np.array([v[0], v[1], v[2]]), bsdf.pdf(ctx, si, mi.Vector3f(*b)),
                         c.evalDir(a, b, mode) * abs(b[2]), c.pdfDir(a, b)))
    top = max(r[3][1] for r in rows)
    kept = [r for r in rows if r[3][1] > 1e-3 * top]
    assert len(kept) > 200
    for mode, v, p, want, want_pdf in kept:
        assert np.all(np.abs(v - want) <= 1e-4 * want), (mode, v, want)
        assert abs(p - want_pdf) <= 1e-4 * want_pdf, (mode, p, want_pdf)
    # radiance is importance times the eta^2 of the interface crossed: 1 / eta^2 from above
    if name == "glass":
        half = len(wi)
        crossed = 0
        for k in range(half):
            rad, imp = rows[k][1][1], rows[half + k][1][1]
            if wi[k][2] * wo[k][2] < 0 and imp > 1e-3 * top:
                want = 1.0 / ETA ** 2 if wi[k][2] > 0 else ETA ** 2
                assert abs(rad / imp - want) <= 1e-5 * want, (rad, imp, want)
                crossed += 1
        assert crossed > 50


def test_transmissive_bsdf_renders_from_tables_made_on_load(tmp_path):
    """A transmissive .bsdf opened in the plugin renders from tables by default: made on load
    by ll_tables_write_from_bsdf (an extended file, a set per lobe and side), kept in the cache
    and read from there by the next load; its values are the C reader's on that file."""
    import layerlab as ll
    source = tmp_path / "glass.bsdf"
    ll.Material.parse("set nodes=40 orders=40\n" + GLASS).build(str(source))
    first = _plugin("scalar_rgb", str(source))
    text = str(first)
    assert "mode=tables" in text and "made and cached in" in text, text
    assert first.flags() & mi.BSDFFlags.GlossyTransmission
    cached = text.split("cached in ")[1].split(")")[0]
    assert "(cached in %s)" % cached in str(_plugin("scalar_rgb", str(source)))
    c = ll.BSDFStorage(cached)
    assert c.format == "tables"
    rng = np.random.default_rng(31)
    wi, wo = _pairs(rng, 200, ETA)
    ctx = mi.BSDFContext()
    got, want = [], []
    for a, b in zip(wi, wo):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*a)
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        v = first.eval(ctx, si, mi.Vector3f(*b))
        got.append([v[0], v[1], v[2]])
        want.append(c.evalDir(a, b) * abs(b[2]))
    got, want = np.array(got), np.array(want)
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-3 * want.max())
    assert np.count_nonzero(want[:, 1] > 1e-3 * want[:, 1].max()) > 50


def test_glass_tables_render_as_roughdielectric(tmp_path, timings):
    """Rough glass from its tables (`llbuild --format measured`, the grid the tolerance
    chooses) in the default "tables" mode against Mitsuba's native roughdielectric (Beckmann,
    the material's own distribution), 64^2, llvm_ad_rgb, default symbolic mode: within the
    noise of two renders of different seeds (mitsuba_scenes.check_within_noise)."""
    import drjit as dr
    import mitsuba_scenes as S
    path = _llbuild(GLASS, tmp_path / "glass-default.tab")
    _plugin("llvm_ad_rgb", path)
    # (a batch-mode test before may have left the symbolic modes off)
    dr.set_flag(dr.JitFlag.SymbolicLoops, True)
    dr.set_flag(dr.JitFlag.SymbolicCalls, True)
    spp = 64
    ours = S.scene(mi, {"type": "layerlab", "filename": path}, 64, spp)
    assert "mode=tables" in str(ours.shapes()[0].bsdf())
    native = S.scene(mi, S.native_bsdf("dielectric"), 64, spp)
    a = [S.render(mi, ours, spp, s) for s in (1, 2)]
    b = [S.render(mi, native, spp, s) for s in (3, 4)]
    d, noise, excess, limit = S.check_within_noise(b[0], a[0], b[1], a[1])
    timings["glass tables vs roughdielectric 64^2 %d spp: relative RMSE" % spp] = (d, "")
    timings["glass tables vs roughdielectric: squared-bias estimate / limit"] = (
        excess / limit, "")
    assert excess < limit, ("glass tables vs roughdielectric: relative RMSE %.4f vs %.4f from "
                            "noise" % (d, noise))
    assert abs(np.mean(a[0]) / np.mean(b[0]) - 1) < 0.03


@pytest.mark.parametrize("name", ["glass", "pane", "frosted", "coat"])
def test_set_by_set_lobes_are_the_c_reader(tables, name):
    """The set-by-set evaluation (layerlab.mitsuba_lobes.TracedLobes, which the plugin uses
    for files whose sets' grids differ, so cannot be stacked) on the same files, llvm_ad_rgb,
    2000 pairs: as the stacked one, the C reader's values and pdfs within 1e-4 and sampled
    directions within 1e-3."""
    import layerlab as ll
    _plugin("llvm_ad_rgb", tables[name])
    from layerlab.mitsuba_lobes import TracedLobes
    from layerlab.tensor_file import read_tensor_file
    path = tables[name]
    lobes = TracedLobes(read_tensor_file(path), path)
    c = ll.BSDFStorage(path)
    rng = np.random.default_rng(37)
    wi, wo = _pairs(rng, 2000, ETA_OF[name])
    value, pdf = lobes.eval_pdf(mi.Vector3f(wi.T), mi.Vector3f(wo.T), mi.Bool(True), True)
    value = np.array([np.array(v) for v in value]).T
    pdf = np.array(pdf)
    want = np.array([c.evalDir(a, b) * abs(b[2]) for a, b in zip(wi, wo)])
    want_pdf = np.array([c.pdfDir(a, b) for a, b in zip(wi, wo)])
    strong = (want[:, 1] > 1e-3 * want[:, 1].max()) & \
        (_warp_elevation(wi, wo, ETA_OF[name], FLIPPED[name]) >= POLE)
    assert np.count_nonzero(strong) > 300
    for k in range(3):
        _close_where_strong(value[:, k], want[:, k], strong, 1e-4, "eval")
    _close_where_strong(pdf, want_pdf, strong, 1e-4, "pdf")
    u = rng.uniform(size=(2000, 2))
    swo, spdf, _, ok, _ = lobes.sample(mi.Vector3f(wi.T), mi.Point2f(u.T), mi.Bool(True), True)
    swo = np.array(swo).reshape(3, -1).T
    spdf = np.array(spdf)
    res = [c.sampleDir(a, b) for a, b in zip(wi, u)]
    cwo = np.array([r[1] for r in res])
    cpdf = np.array([r[2] for r in res])
    found = cpdf > 0
    assert np.count_nonzero(found) > 1800
    assert np.array_equal(found, spdf > 0)
    _sampled_direction_close(name, swo[found], cwo[found], spdf[found])


def test_transmissive_bsdf_without_tables_stays_on_the_fourier_path(tmp_path, monkeypatch):
    """Where the loaded library cannot write a transmissive .bsdf's tables (an older one, or a
    material its writer refuses), the default is the Fourier path with the reason in
    str(bsdf); asked for "tables", the load fails with that reason."""
    import layerlab as ll
    source = tmp_path / "glass.bsdf"
    ll.Material.parse("set nodes=40 orders=40\n" + GLASS).build(str(source))
    _plugin("scalar_rgb", str(source), mode="batch")
    import layerlab.mitsuba as llmi
    from layerlab import _native

    def refuse(*args, **kwargs):
        raise _native.UnsupportedError("ll_tables_write_from_bsdf: not in this library", 6)

    monkeypatch.setattr(llmi, "tables_from_bsdf", refuse)
    bsdf = _plugin("scalar_rgb", str(source))
    text = str(bsdf)
    assert "mode=batch" in text and "no tables: ll_tables_write_from_bsdf" in text, text
    assert bsdf.flags() & mi.BSDFFlags.GlossyTransmission
    with pytest.raises(Exception, match="not in this library"):
        _plugin("scalar_rgb", str(source), mode="tables")
    assert "mode=traced" in str(_plugin("llvm_ad_rgb", str(source)))


def test_stacked_warps_are_mitsubas(tables, monkeypatch):
    """mitsuba_warp.SliceWarp, which the stacked sets read their VNDF and luminance through,
    against Mitsuba's own warp (mi.MarginalContinuous2D1) over the same stacked slices at
    points between two elevations: the inversion and the density to 1e-5 (float32 rounding),
    a sample mapped back by Mitsuba's inversion to within 2e-5 of its random numbers, with
    the density there (to 1e-4 relative: a point on a cell edge may round into the next); and a slice of weight 1 read alone as Mitsuba reads it at its node. Both of its
    layouts (the nodes a slice at a time, and paired with the next slice's)."""
    from layerlab.tensor_file import read_tensor_file
    mi.set_variant("llvm_ad_rgb")
    from layerlab.mitsuba_lobes import SETS
    from layerlab.mitsuba_lobes_stacked import ORDER
    from layerlab.mitsuba_tables import stack_sets
    from layerlab import mitsuba_warp
    from layerlab.mitsuba_warp import SliceWarp
    stacked = stack_sets(read_tensor_file(tables["glass"]), [SETS[k][0] for k in ORDER])
    # Mitsuba's warp takes a rising parameter list: the slices' indices
    # (the stacked sets repeat their elevations; SliceWarp reads by index).
    theta = np.arange(stacked["vndf"].shape[1], dtype=np.float32)
    rng = np.random.default_rng(29)
    n = 20000
    for key, pairs in (("vndf", 0), ("luminance", 0), ("vndf", 1 << 40),
                       ("luminance", 1 << 40)):
        data = np.ascontiguousarray(stacked[key][0])
        theirs = mi.MarginalContinuous2D1(data, [theta.tolist()])
        with monkeypatch.context() as m:
            m.setattr(mitsuba_warp, "PAIRED_NODES_BYTES", pairs)
            ours = SliceWarp(data)
        assert ours.paired == (pairs > 0)
        k = rng.integers(0, len(theta) - 1, n)
        t = rng.uniform(size=n).astype(np.float32)
        param = mi.Float((theta[k] * (1 - t) + theta[k + 1] * t).astype(np.float32))
        # the weights Mitsuba takes from that parameter
        t = mi.Float((np.array(param) - theta[k]) / (theta[k + 1] - theta[k]))
        j = mi.UInt32(k.astype(np.uint32))
        point = mi.Point2f(mi.Float(rng.uniform(size=n).astype(np.float32)),
                           mi.Float(rng.uniform(size=n).astype(np.float32)))
        cell = ours.cell(point)
        values = ours.mix(ours.read(j, cell, True), ours.read(j + 1, cell, True), 1.0 - t, t)
        u, pdf = ours.invert(values, cell)
        u_ref, pdf_ref = theirs.invert(point, [param])
        scale = float(np.max(np.array(pdf_ref)))
        np.testing.assert_allclose(np.array(u.x), np.array(u_ref.x), atol=1e-5)
        np.testing.assert_allclose(np.array(u.y), np.array(u_ref.y), atol=1e-5)
        np.testing.assert_allclose(np.array(pdf), np.array(pdf_ref), atol=1e-5 * scale)
        np.testing.assert_allclose(np.array(ours.density(values, cell)),
                                   np.array(theirs.eval(point, [param])), atol=1e-5 * scale)
        for a0, a1, at in ((1.0 - t, t, param), (mi.Float(0.0), mi.Float(1.0),
                                                 mi.Float(theta[k + 1]))):
            p, p_pdf = ours.sample(j, j + 1, a0, a1, point, True)
            back, back_pdf = theirs.invert(p, [at])
            np.testing.assert_allclose(np.array(back.x), np.array(point.x), atol=2e-5)
            np.testing.assert_allclose(np.array(back.y), np.array(point.y), atol=2e-5)
            np.testing.assert_allclose(np.array(p_pdf), np.array(back_pdf), rtol=1e-4,
                                       atol=1e-6 * scale)


def test_guided_searches_find_what_a_full_search_finds(tables, monkeypatch):
    """SliceWarp.sample's searches, each in the interval of nodes its guide tables give,
    against the same searches over all nodes (the guide replaced by [0, n - 2]): the same
    points and densities, bit for bit, for the VNDF and luminance of the stacked glass and
    for a made-up warp of 300 nodes a row (16-bit guide entries) with rows and runs of
    nodes without mass, at mixtures of two slices (weights 0 and 1 among them) and at
    random numbers that fall on the guides' steps and on the stored marginals' own values
    (ties of the comparison); and the same, bit for bit, with the nodes stored a slice at
    a time and paired with the next slice's (SliceWarp's two layouts)."""
    from layerlab.tensor_file import read_tensor_file
    mi.set_variant("llvm_ad_rgb")
    from layerlab import mitsuba_warp
    from layerlab.mitsuba_lobes import SETS
    from layerlab.mitsuba_lobes_stacked import ORDER
    from layerlab.mitsuba_tables import stack_sets
    stacked = stack_sets(read_tensor_file(tables["glass"]), [SETS[k][0] for k in ORDER])
    rng = np.random.default_rng(37)
    n = 40000
    made_up = rng.uniform(size=(5, 7, 300)) ** 8
    made_up[:, 2:4] = 0.0
    made_up[1, :, 100:250] = 0.0
    made_up[3, 5:, :] = 0.0
    for key, data in (("vndf", stacked["vndf"][0]), ("luminance", stacked["luminance"][0]),
                      ("made-up", made_up)):
        with monkeypatch.context() as m:
            m.setattr(mitsuba_warp, "PAIRED_NODES_BYTES", 0)
            single = mitsuba_warp.SliceWarp(np.ascontiguousarray(data))
        with monkeypatch.context() as m:
            m.setattr(mitsuba_warp, "PAIRED_NODES_BYTES", 1 << 40)
            warp = mitsuba_warp.SliceWarp(np.ascontiguousarray(data))
        assert warp.paired and not single.paired
        slices = warp.node_host.shape[0]
        k = rng.integers(0, slices - 1, n)
        a = rng.uniform(size=n)
        a[: n // 4] = 0.0
        a[n // 4: n // 2] = 1.0
        u = rng.uniform(size=(2, n))
        # On the guides' steps, and on the marginals' node values of either slice.
        u[0, ::3] = rng.integers(0, mitsuba_warp.GUIDE_NODE + 1, n)[::3] / mitsuba_warp.GUIDE_NODE
        u[1, ::3] = rng.integers(0, mitsuba_warp.GUIDE_ROW + 1, n)[::3] / mitsuba_warp.GUIDE_ROW
        node = rng.integers(0, warp.h, n)
        ties = warp.row_host[:, :, 1][k + rng.integers(0, 2, n), node]
        u[1, 1::3] = ties[1::3]
        args = (mi.UInt32(k.astype(np.uint32)), mi.UInt32((k + 1).astype(np.uint32)),
                mi.Float((1.0 - a).astype(np.float32)), mi.Float(a.astype(np.float32)),
                mi.Point2f(mi.Float(u[0].astype(np.float32)), mi.Float(u[1].astype(np.float32))),
                mi.Bool(True))
        guided = [np.array(x) for x in warp.sample(*args)]
        for ours, theirs in zip(guided, [np.array(x) for x in single.sample(*args)]):
            assert np.array_equal(ours, theirs), key
        with monkeypatch.context() as m:
            m.setattr(mitsuba_warp.SliceWarp, "_interval",
                      staticmethod(lambda *args: (mi.UInt32(0), mi.UInt32(args[-1] - 2))))
            full = [np.array(x) for x in warp.sample(*args)]
        assert np.all(np.isfinite(guided[0]))
        for ours, theirs in zip(guided, full):
            assert np.array_equal(ours, theirs), key


def test_scalar_and_llvm_agree_over_the_sphere(tables):
    """eval_pdf and sample of the glass tables in scalar_rgb against llvm_ad_rgb on pairs
    drawn over the whole sphere (the horizon included, which the C reader comparisons leave
    out): every result finite, values and pdfs within 1e-4 where above 1e-3 of their largest,
    the sampled directions within 1e-3 (the scalar variants compute in double)."""
    path = tables["glass"]
    rng = np.random.default_rng(31)
    n = 300
    wi = rng.normal(size=(n, 3))
    wo = rng.normal(size=(n, 3))
    wi = (wi / np.linalg.norm(wi, axis=1)[:, None]).astype(np.float32)
    wo = (wo / np.linalg.norm(wo, axis=1)[:, None]).astype(np.float32)
    u = rng.uniform(size=(n, 2)).astype(np.float32)
    bsdf = _plugin("llvm_ad_rgb", path)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(wi.T)
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(wo.T))
    bs, weight = bsdf.sample(ctx, si, mi.Float(0.5), mi.Point2f(u.T))
    want = np.concatenate([np.array(value).reshape(3, -1), np.array(pdf)[None],
                           np.array(bs.pdf)[None], np.array(weight).reshape(3, -1)])
    want_wo = np.array(bs.wo).reshape(3, -1)
    bsdf = _plugin("scalar_rgb", path)
    got, got_wo = [], []
    for k in range(n):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi[k].tolist())
        v, p = bsdf.eval_pdf(ctx, si, mi.Vector3f(*wo[k].tolist()))
        s, w = bsdf.sample(ctx, si, 0.5, mi.Point2f(*u[k].tolist()))
        got.append([v[0], v[1], v[2], p, s.pdf, w[0], w[1], w[2]])
        got_wo.append([s.wo[0], s.wo[1], s.wo[2]])
    got, got_wo = np.array(got).T, np.array(got_wo).T
    assert np.all(np.isfinite(got)) and np.all(np.isfinite(got_wo))
    for row in range(len(want)):
        strong = want[row] > 1e-3 * want[row].max()
        assert np.count_nonzero(strong) > 30
        _close_where_strong(got[row], want[row], strong, 1e-4, "row %d" % row)
    found = want[4] > 0
    assert np.array_equal(found, got[4] > 0)
    assert np.abs(got_wo[:, found] - want_wo[:, found]).max() < 1e-3
