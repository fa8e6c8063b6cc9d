"""Rough glass (eta 1.5, alpha 0.3, compensate=0) rendered by the layerlab
Mitsuba plugin from its table file (a transmissive, extended table file)
against Mitsuba's native roughdielectric, in the scene of mitsuba_speed.py:
CPU time of each render and whether the images agree within noise. Not
part of `make test` (minutes); run by hand:

    python3 python/tests/mitsuba_glass_tables.py OUTDIR [SIZE [SPP]]   (256, 64)

First in Mitsuba's default (symbolic, megakernel) mode: native and our
"tables" mode, alternating, REPS rounds (LAYERLAB_SPEED_REPS, default 3),
each render after a 1-spp warm-up that compiles the kernels; the smallest
CPU time of each counts. Then, for comparison, in wavefront mode (which
the "batch" mode needs): native and "batch" on the same table file, once
each. Noise: two native renders of different seeds give the native-vs-
native relative RMSE; ours against the first native render is compared
with it (mitsuba_scenes.check_within_noise). Writes OUTDIR/glass-tables-
vs-native.png (left native, right ours).
"""

import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
import mitsuba_compare as C  # noqa: E402
import mitsuba_scenes as S  # noqa: E402


def timed(scene, spp, seed):
    S.render(mi, scene, spp=1, seed=99)
    wall, cpu = time.perf_counter(), time.process_time()
    img = S.render(mi, scene, spp=spp, seed=seed)
    return img, time.perf_counter() - wall, time.process_time() - cpu


def _fmt(times):
    return "/".join("%.2f" % t for t in times)


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 64
    reps = int(os.environ.get("LAYERLAB_SPEED_REPS", "3"))
    os.makedirs(out, exist_ok=True)
    bsdf = S.build_dielectric(os.path.join(out, "glass-alpha0.3.bsdf"))
    table = S.build_table(bsdf, os.path.join(out, "glass-alpha0.3.tab"))
    print("size %dx%d, %d spp, variant %s, Mitsuba %s, table %.1f MB, load %s"
          % (size, size, spp, mi.variant(), mi.__version__, os.path.getsize(table) / 1e6,
             os.getloadavg()), flush=True)
    native = S.scene(mi, S.native_bsdf("dielectric"), size, spp)
    ours = S.scene(mi, {"type": "layerlab", "filename": table}, size, spp)
    assert "mode=tables" in str(ours.shapes()[0].bsdf())
    cn, cl, images = [], [], {}
    for r in range(reps):
        img, _, c = timed(native, spp, 2 * r)
        cn.append(c)
        images.setdefault("native", []).append(img)
        img, _, c = timed(ours, spp, 2 * r + 1)
        cl.append(c)
        images.setdefault("ours", []).append(img)
    print("symbolic mode, CPU s: native %s, tables %s: ratio of the smallest %.2f"
          % (_fmt(cn), _fmt(cl), min(cl) / min(cn)), flush=True)
    n0, n1 = images["native"][0], images["native"][1 % reps]
    l0, l1 = images["ours"][0], images["ours"][1 % reps]
    rmse, noise, excess, threshold = S.check_within_noise(n0, l0, n1, l1)
    print("relative RMSE: native vs native %.4f, tables vs native %.4f; mean ratio %.4f; "
          "bias excess %.2e (threshold %.2e): %s"
          % (S.relative_rmse(n1, n0), S.relative_rmse(l0, n0), float(np.mean(l0) / np.mean(n0)),
             excess, threshold, "within noise" if excess < threshold else "BEYOND NOISE"),
          flush=True)
    C.save_png(os.path.join(out, "glass-tables-vs-native.png"), np.concatenate([n0, l0], axis=1))
    layerlab.mitsuba.wavefront_mode()
    native_w = S.scene(mi, S.native_bsdf("dielectric"), size, spp)
    batch = S.scene(mi, {"type": "layerlab", "filename": table, "mode": "batch"}, size, spp)
    _, _, cnw = timed(native_w, spp, 0)
    _, _, cb = timed(batch, spp, 1)
    print("wavefront mode, CPU s: native %.2f, batch %.2f (%.2f times the symbolic native)"
          % (cnw, cb, cb / min(cn)), flush=True)


if __name__ == "__main__":
    main()
