"""Render times of the layerlab Mitsuba plugin against Mitsuba's native
roughconductor / roughdielectric, side by side in one run, and the per-lane
cost of its calls: the "Speed" section of docs/mitsuba.md. Not part of
`make test` (minutes); run by hand:

    python3 python/tests/mitsuba_speed.py OUTDIR [SIZE [SPP,SPP...]]   (256, 64)

For each spp and material: native and the traced plugin in Mitsuba's
default (symbolic, megakernel) mode, alternating, two renders each after a
1-spp warm-up that compiles the kernels (the smaller time counts); then, in
wavefront mode (set on this thread, as the batch mode needs), native and the
batch plugin once each. Each render's wall time and the process's CPU time
(all threads; on a shared machine the CPU-time ratio is the steadier
figure). Prints the system's load before and after, to show how busy the
machine was.
"""

import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import mitsuba as mi  # noqa: E402

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


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    spps = [int(s) for s in sys.argv[3].split(",")] if len(sys.argv) > 3 else [64]
    skip_batch = os.environ.get("LAYERLAB_SPEED_SKIP_BATCH") == "1"
    os.makedirs(out, exist_ok=True)
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
            ours = S.scene(mi, {"type": "layerlab", "filename": path}, size, spp)
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
