"""Render times of the layerlab Mitsuba plugin against Mitsuba's native
roughconductor / roughdielectric, side by side in one run, and the per-lane
cost of its calls: the "Speed" section of docs/mitsuba.md. Not part of
`make test` (minutes); run by hand:

    python3 python/tests/mitsuba_speed.py OUTDIR [SIZE [SPP,SPP...]] [--tables] [--pictures]

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
"""

import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
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
                 ("Mitsuba measured", {"type": "measured", "filename": gold_table})],
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
                print("%4d spp %-12s %-24s wall %s s, CPU %s s; CPU / %s %.2f (wall %.2f)"
                      % (spp, material, name, _fmt(t[0] for t in times[name]),
                         _fmt(t[1] for t in times[name]), base, cpu[name] / cpu[base],
                         wall[name] / wall[base]), flush=True)
            if pictures:
                for k, (name, scn) in enumerate(scenes):
                    if material == "gold" and name == "Mitsuba measured":
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
