"""Render times of the layerlab Mitsuba plugin against Mitsuba's native
roughconductor / roughdielectric, side by side in one run, and the per-lane
cost of its calls: the "Speed" section of docs/mitsuba.md. Not part of
`make test` (minutes); run by hand:

    python3 python/tests/mitsuba_speed.py OUTDIR [SIZE [SPP,SPP...]]   (256, 64)

For each spp and material: native and the traced plugin in Mitsuba's
default (symbolic, megakernel) mode, alternating, two renders each after a
1-spp warm-up that compiles the kernels (the smaller time counts); then, in
wavefront mode (set on this thread, as the batch mode needs), native and the
batch plugin once each. Prints the load average before and after, since the
machine is shared.
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
                tn.append(C.timed(native, spp, r)[1])
                tl.append(C.timed(ours, spp, r + 2)[1])
            symbolic[kind, spp] = min(tn)
            print("%4d spp %-10s symbolic mode: native %s s, traced %s s: ratio %.2f"
                  % (spp, kind, "/".join("%.2f" % t for t in tn),
                     "/".join("%.2f" % t for t in tl), min(tl) / min(tn)), flush=True)
    if not skip_batch:
        layerlab.mitsuba.wavefront_mode()
        for spp in spps:
            for kind, path in files.items():
                ours = S.scene(mi, {"type": "layerlab", "filename": path, "mode": "batch"},
                               size, spp)
                t_batch = C.timed(ours, spp, 2)[1]
                t_native = C.timed(S.scene(mi, S.native_bsdf(kind), size, spp), spp, 0)[1]
                print("%4d spp %-10s wavefront mode: native %.2f s, batch %.2f s: ratio %.2f; "
                      "batch / native symbolic %.2f"
                      % (spp, kind, t_native, t_batch, t_batch / t_native,
                         t_batch / symbolic[kind, spp]), flush=True)
    print("load average %s" % (os.getloadavg(),))


if __name__ == "__main__":
    main()
