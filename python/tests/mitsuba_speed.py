"""Render times of the layerlab Mitsuba plugin against Mitsuba's native
roughconductor / roughdielectric, side by side in one run, and the per-lane
cost of its calls: the "Speed" section of docs/mitsuba.md. Not part of
`make test` (minutes); run by hand:

    python3 python/tests/mitsuba_speed.py OUTDIR [SIZE [SPP,SPP...]] [--tables] [--pictures]
        [--only=MATERIAL] [--grids=TxVxS,...] [--calls]

(SIZE 256, SPP 64 by default.) For each spp and material: native and the
Fourier series traced ("mode": "traced") in Mitsuba's default (symbolic,
megakernel) mode, alternating, two renders each after a 1-spp warm-up that
compiles the kernels (the smaller time counts); then, in wavefront mode (set
on this thread, as the batch mode needs), native and the batch plugin once
each. Each render's wall time and the process's CPU time (all threads; on a
shared machine the CPU-time ratio is the steadier figure). Prints the
system's load before and after, to show how busy the machine was.

--tables measures the table path instead (and only it): rough gold (the
.bsdf of the scene's gold, compensate=0, and its table file written by
ll_tables_write_from_bsdf with the default tolerance) as native
roughconductor, our "tables" mode and Mitsuba's own `measured` on the same
table file; and examples/coated-gold.layers, its table file in "tables" mode
against its .bsdf in "traced" mode. Renders alternate within each material
(REPS rounds, LAYERLAB_SPEED_REPS, default 2; the smallest CPU time counts)
and the ratios are of CPU times in this run. --pictures also writes the
last renders as PNGs into OUTDIR (gold native and ours, coated gold Fourier
and tables); --only=gold or --only=coated-gold measures one material.
Besides the smallest CPU time, each entry's ratio to the first entry is
also given per round (the median and range of the rounds' ratios: both
renders of a round saw much the same load). After the rounds, each gold
entry renders once more (seed 1) against a native render (seed 2): the
relative RMSE between them against that of two native renders (seeds 1
and 2, the noise), and the difference of the mean.

--grids=TxVxS[,TxVxS...] adds to the gold Mitsuba's `measured` on table
files of the same .bsdf at those grids (T incident elevations, VNDF side V,
sample side S; ll_tables_write_from_bsdf with the three sizes given),
rendered in the same rounds: what the grid does to `measured`'s time.

--calls (with --tables) renders nothing: it gives the CPU time per lane of
eval, pdf, sample and eval_pdf on a wavefront of 2^20 lanes (wi, wo and u
uniform, directions on the upper hemisphere) for native roughconductor, our
"tables" mode and `measured` on the gold's table file (and on the --grids
files), alternating round by round (REPS rounds, the smallest counting);
then the parts `measured`'s calls are made of, run alone on the same lanes:
Mitsuba's own 2D warps built from the file's fields as `measured` builds
them (the VNDF and luminance warps over the parameters (phi_i, theta_i),
the RGB values over (phi_i, theta_i, channel), D and sigma without one),
and the VNDF warp's inversion over theta_i alone.
"""

import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import ctypes  # noqa: E402

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
from layerlab.mitsuba_tables import TablesOptions  # noqa: E402
import mitsuba_compare as C  # noqa: E402
import mitsuba_scenes as S  # noqa: E402


def timed(scene, spp, seed):
    """(wall, CPU) seconds of one render, after a 1-spp warm-up that
    compiles the kernels."""
    S.render(mi, scene, spp=1, seed=99)
    wall, cpu = time.perf_counter(), time.process_time()
    S.render(mi, scene, spp=spp, seed=seed)
    return time.perf_counter() - wall, time.process_time() - cpu


def _fmt(times):
    return "/".join("%.2f" % t for t in times)


def _picture(path, image):
    """The render as an sRGB PNG (Mitsuba's own tonemapping: clamp, sRGB
    curve)."""
    mi.util.write_bitmap(path, image[..., :3].astype(np.float32))


def grid_table(bsdf_path, grid, path):
    """The table file of bsdf_path at grid (T, V, S): T incident elevations,
    VNDF side V, sample side S (ll_tables_write_from_bsdf with the three
    sizes given, so nothing is searched)."""
    if os.path.exists(path):
        return path
    lib = ctypes.CDLL(os.environ["LAYERLAB_LIBRARY"])
    src = ctypes.c_void_p()
    assert lib.ll_bsdf_open(bsdf_path.encode(), None, ctypes.byref(src)) == 0
    opts = TablesOptions()
    opts.n_theta_i, opts.vndf_size, opts.sample_size = grid
    try:
        status = lib.ll_tables_write_from_bsdf(src, path.encode(), ctypes.byref(opts), None)
    finally:
        lib.ll_bsdf_release(src)
    assert status == 0, "ll_tables_write_from_bsdf: status %d" % status
    return path


def _grids():
    """The grids of --grids=TxVxS,...: a list of (T, V, S)."""
    grids = []
    for a in sys.argv:
        if a.startswith("--grids="):
            grids += [tuple(int(n) for n in g.split("x")) for g in a.split("=", 1)[1].split(",")]
    return grids


def _images(entries, scenes, spp):
    """Each entry's render (seed 1) against native's (seed 2), and native's
    own two seeds: the relative RMSE and the mean's difference."""
    native = S.render(mi, scenes[0][1], spp, 2)
    for k, (name, scn) in enumerate(scenes):
        image = S.render(mi, scn, spp, 1)
        print("     image %-36s relative RMSE against native %.4f%s; mean %+.2f%%"
              % (name, S.relative_rmse(image, native),
                 " (the noise: native's two seeds)" if k == 0 else "",
                 100.0 * (image[..., :3].mean() / native[..., :3].mean() - 1.0)), flush=True)


def _lanes(rng, n):
    """n directions uniform on the upper hemisphere."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    v[:, 2] = np.abs(v[:, 2])
    return mi.Vector3f(*[mi.Float(np.ascontiguousarray(v[:, i], dtype=np.float32))
                         for i in range(3)])


def _per_lane(fn, n):
    """CPU nanoseconds per lane of one evaluation of fn() (its kernel
    compiled by an earlier call)."""
    import drjit as dr
    cpu = time.process_time()
    dr.eval(fn())
    dr.sync_thread()
    return (time.process_time() - cpu) / n * 1e9


def calls(out, reps):
    """--calls: see the module's docstring."""
    import drjit as dr
    from layerlab.tensor_file import read_tensor_file
    n = 1 << 20
    gold_bsdf = S.build_conductor(os.path.join(out, "gold-alpha0.2.bsdf"))
    gold_table = S.build_table(gold_bsdf, os.path.join(out, "gold-alpha0.2.tab"))
    tabs = [("", gold_table)] + [(" %dx%dx%d" % g, grid_table(
        gold_bsdf, g, os.path.join(out, "gold-%dx%dx%d.tab" % g))) for g in _grids()]
    bsdfs = [("native roughconductor", mi.load_dict(S.native_bsdf("conductor"))),
             ("layerlab tables", mi.load_dict({"type": "layerlab", "filename": gold_table}))]
    bsdfs += [("Mitsuba measured" + g, mi.load_dict({"type": "measured", "filename": t}))
              for g, t in tabs]
    rng = np.random.default_rng(1)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi, wo = _lanes(rng, n), _lanes(rng, n)
    u = mi.Point2f(*[mi.Float(rng.uniform(size=n).astype(np.float32)) for _ in range(2)])
    dr.eval(si, wo, u)
    ctx = mi.BSDFContext()
    kinds = {"eval": lambda b: b.eval(ctx, si, wo),
             "pdf": lambda b: b.pdf(ctx, si, wo),
             "sample": lambda b: b.sample(ctx, si, mi.Float(0.5), u)[1],
             "eval_pdf": lambda b: b.eval_pdf(ctx, si, wo)[0]}
    # The parts of `measured`'s calls, its warps built as it builds them.
    f = read_tensor_file(gold_table)
    params = [f["phi_i"].tolist(), f["theta_i"].tolist()]
    vndf = mi.MarginalContinuous2D2(np.ascontiguousarray(f["vndf"]), params)
    lum = mi.MarginalContinuous2D2(np.ascontiguousarray(f["luminance"]), params)
    rgb = mi.MarginalContinuous2D3(np.ascontiguousarray(f["rgb"]), params + [[0.0, 1.0, 2.0]],
                                   False, False)
    # The same VNDF warp without the azimuth's axis (the file has one
    # azimuth): what that axis costs Mitsuba's warps.
    vndf1 = mi.MarginalContinuous2D1(np.ascontiguousarray(f["vndf"][0]), params[1:])
    ndf = mi.MarginalContinuous2D0(np.ascontiguousarray(f["ndf"]), [], False, False)
    sigma = mi.MarginalContinuous2D0(np.ascontiguousarray(f["sigma"]), [], False, False)
    theta = mi.Float(rng.uniform(0, np.pi / 2, size=n).astype(np.float32))
    lane = [dr.zeros(mi.Float, n), theta]
    dr.eval(lane)
    parts = {"VNDF invert": lambda: vndf.invert(u, lane),
             "VNDF invert, theta_i its only parameter": lambda: vndf1.invert(u, lane[1:]),
             "VNDF sample": lambda: vndf.sample(u, lane),
             "luminance sample": lambda: lum.sample(u, lane),
             "luminance eval": lambda: lum.eval(u, lane),
             "RGB eval, 3 channels": lambda: sum(rgb.eval(u, lane + [mi.Float(c)])
                                                 for c in range(3)),
             "D and sigma eval": lambda: ndf.eval(u) + sigma.eval(u)}
    jobs = [(name, k, (lambda b=b, k=k: kinds[k](b))) for name, b in bsdfs for k in kinds]
    jobs += [("measured's parts", k, fn) for k, fn in parts.items()]
    for _, _, fn in jobs:
        _per_lane(fn, n)
    times = {}
    for r in range(reps):
        for name, kind, fn in jobs:
            times.setdefault((name, kind), []).append(_per_lane(fn, n))
    print("calls: %d lanes, %s, Mitsuba %s, %d rounds, the smallest; load average %s"
          % (n, mi.variant(), mi.__version__, reps, os.getloadavg()))
    for name in dict.fromkeys(j[0] for j in jobs):
        print("%-32s %s" % (name, ", ".join("%s %.0f ns" % (k, min(t)) for (nm, k), t
                                             in times.items() if nm == name)), flush=True)
    print("load average %s" % (os.getloadavg(),))


def tables(out, size, spps, pictures):
    """The table path (--tables): see the module's docstring."""
    reps = int(os.environ.get("LAYERLAB_SPEED_REPS", "2"))
    gold_bsdf = S.build_conductor(os.path.join(out, "gold-alpha0.2.bsdf"))
    gold_table = S.build_table(gold_bsdf, os.path.join(out, "gold-alpha0.2.tab"))
    with open(os.path.join(S.EXAMPLES, "coated-gold.layers")) as f:
        coated_bsdf = S.build(f.read(), os.path.join(out, "coated-gold.bsdf"))
    coated_table = S.build_table(coated_bsdf, os.path.join(out, "coated-gold.tab"))
    for path in (gold_bsdf, gold_table, coated_bsdf, coated_table):
        print("%s: %.2f MB" % (os.path.basename(path), os.path.getsize(path) / 1e6), flush=True)
    print("tables: size %dx%d, spp %s, variant %s, Mitsuba %s, %d rounds, load average %s"
          % (size, size, spps, mi.variant(), mi.__version__, reps, os.getloadavg()), flush=True)
    materials = {
        "gold": [("native roughconductor", S.native_bsdf("conductor")),
                 ("layerlab tables", {"type": "layerlab", "filename": gold_table}),
                 ("Mitsuba measured", {"type": "measured", "filename": gold_table})]
        + [("Mitsuba measured %dx%dx%d" % g,
            {"type": "measured",
             "filename": grid_table(gold_bsdf, g, os.path.join(out, "gold-%dx%dx%d.tab" % g))})
           for g in _grids()],
        "coated gold": [("layerlab traced Fourier", {"type": "layerlab", "filename": coated_bsdf,
                                                     "mode": "traced"}),
                        ("layerlab tables", {"type": "layerlab", "filename": coated_table})],
    }
    only = [a.split("=", 1)[1] for a in sys.argv if a.startswith("--only=")]
    for spp in spps:
        for material, entries in materials.items():
            if only and material.replace(" ", "-") not in only:
                continue
            scenes = [(name, S.scene(mi, bsdf, size, spp)) for name, bsdf in entries]
            times = {name: [] for name, _ in entries}
            for r in range(reps):
                for k, (name, scn) in enumerate(scenes):
                    times[name].append(timed(scn, spp, 10 * r + k))
            base = entries[0][0]
            cpu = {name: min(t[1] for t in ts) for name, ts in times.items()}
            wall = {name: min(t[0] for t in ts) for name, ts in times.items()}
            for name, _ in entries:
                rounds = sorted(t[1] / b[1] for t, b in zip(times[name], times[base]))
                print("%4d spp %-12s %-26s wall %s s, CPU %s s; CPU / %s %.2f (wall %.2f; "
                      "per round %.2f [%.2f..%.2f])"
                      % (spp, material, name, _fmt(t[0] for t in times[name]),
                         _fmt(t[1] for t in times[name]), base, cpu[name] / cpu[base],
                         wall[name] / wall[base], rounds[len(rounds) // 2], rounds[0],
                         rounds[-1]), flush=True)
            if material == "gold":
                _images(entries, scenes, spp)
            if pictures:
                for k, (name, scn) in enumerate(scenes):
                    if material == "gold" and name.startswith("Mitsuba measured"):
                        continue
                    file = "%s-%s.png" % (material.replace(" ", "-"),
                                          {"native roughconductor": "native",
                                           "layerlab tables": "tables",
                                           "layerlab traced Fourier": "fourier"}[name])
                    _picture(os.path.join(out, file), S.render(mi, scn, spp, 1))
    print("load average %s" % (os.getloadavg(),))


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    out = args[0]
    size = int(args[1]) if len(args) > 1 else 256
    spps = [int(s) for s in args[2].split(",")] if len(args) > 2 else [64]
    skip_batch = os.environ.get("LAYERLAB_SPEED_SKIP_BATCH") == "1"
    os.makedirs(out, exist_ok=True)
    if "--tables" in sys.argv:
        if "--calls" in sys.argv:
            calls(out, int(os.environ.get("LAYERLAB_SPEED_REPS", "2")))
        else:
            tables(out, size, spps, "--pictures" in sys.argv)
        return
    files = {"conductor": S.build_conductor(os.path.join(out, "gold-alpha0.2.bsdf")),
             "dielectric": S.build_dielectric(os.path.join(out, "glass-alpha0.3.bsdf"))}
    print("size %dx%d, spp %s, variant %s, Mitsuba %s, load average %s"
          % (size, size, spps, mi.variant(), mi.__version__, os.getloadavg()), flush=True)
    golden = os.path.join(os.path.dirname(os.path.dirname(HERE)), "tests", "data",
                          "roughgold_alpha_0.2.bsdf")
    for name, path in (("golden file", golden), ("gold alpha 0.2", files["conductor"])):
        costs = C.per_lane_costs(path)
        print("%s: ns per element: %s" % (name, ", ".join("%s %.0f" % kv for kv in costs.items())),
              flush=True)
    symbolic = {}
    for spp in spps:
        for kind, path in files.items():
            native = S.scene(mi, S.native_bsdf(kind), size, spp)
            ours = S.scene(mi, {"type": "layerlab", "filename": path, "mode": "traced"},
                           size, spp)
            tn, tl = [], []
            for r in range(2):
                tn.append(timed(native, spp, r))
                tl.append(timed(ours, spp, r + 2))
            symbolic[kind, spp] = (min(t[0] for t in tn), min(t[1] for t in tn))
            print("%4d spp %-10s symbolic mode: native %s s (CPU %s), traced %s s (CPU %s): "
                  "ratio %.2f, CPU ratio %.2f"
                  % (spp, kind, _fmt(t[0] for t in tn), _fmt(t[1] for t in tn),
                     _fmt(t[0] for t in tl), _fmt(t[1] for t in tl),
                     min(t[0] for t in tl) / min(t[0] for t in tn),
                     min(t[1] for t in tl) / min(t[1] for t in tn)), flush=True)
    if not skip_batch:
        layerlab.mitsuba.wavefront_mode()
        for spp in spps:
            for kind, path in files.items():
                ours = S.scene(mi, {"type": "layerlab", "filename": path, "mode": "batch"},
                               size, spp)
                t_batch = timed(ours, spp, 2)
                t_native = timed(S.scene(mi, S.native_bsdf(kind), size, spp), spp, 0)
                sym = symbolic[kind, spp]
                print("%4d spp %-10s wavefront mode: native %.2f s (CPU %.2f), batch %.2f s "
                      "(CPU %.2f): ratio %.2f, CPU ratio %.2f; batch / native symbolic %.2f, "
                      "CPU %.2f"
                      % (spp, kind, t_native[0], t_native[1], t_batch[0], t_batch[1],
                         t_batch[0] / t_native[0], t_batch[1] / t_native[1],
                         t_batch[0] / sym[0], t_batch[1] / sym[1]), flush=True)
    print("load average %s" % (os.getloadavg(),))


if __name__ == "__main__":
    main()
