"""Rough glass (eta 1.5, alpha 0.3, compensate=0) rendered by the layerlab
Mitsuba plugin from its table file (a transmissive, extended table file,
read through the C batch calls) against Mitsuba's native roughdielectric:
CPU time of each render and whether the images agree within noise. Not
part of `make test` (minutes); run by hand:

    python3 python/tests/mitsuba_glass_tables.py OUTDIR [SIZE [SPP]]   (256, 64)

Both render in wavefront mode (which the batch path needs), each after a
1-spp warm-up that compiles the kernels. Noise: two native renders of
different seeds give the native-vs-native relative RMSE; ours against the
first native render is compared with it. Writes OUTDIR/glass-tables-vs-
native.png (left native, right ours).
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


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 64
    os.makedirs(out, exist_ok=True)
    bsdf = S.build_dielectric(os.path.join(out, "glass-alpha0.3.bsdf"))
    table = S.build_table(bsdf, os.path.join(out, "glass-alpha0.3.tab"))
    print("size %dx%d, %d spp, variant %s, Mitsuba %s, table %.1f MB"
          % (size, size, spp, mi.variant(), mi.__version__, os.path.getsize(table) / 1e6),
          flush=True)
    layerlab.mitsuba.wavefront_mode()
    native = S.scene(mi, S.native_bsdf("dielectric"), size, spp)
    ours = S.scene(mi, {"type": "layerlab", "filename": table, "mode": "batch"}, size, spp)
    n0, wn0, cn0 = timed(native, spp, 0)
    l0, wl0, cl0 = timed(ours, spp, 1)
    n1, wn1, cn1 = timed(native, spp, 2)
    print("native: %.2f s, %.2f s (CPU %.2f, %.2f); tables (batch): %.2f s (CPU %.2f): "
          "CPU ratio %.2f" % (wn0, wn1, cn0, cn1, wl0, cl0, cl0 / min(cn0, cn1)), flush=True)
    noise = S.relative_rmse(n1, n0)
    diff = S.relative_rmse(l0, n0)
    mean_ratio = float(np.mean(l0) / np.mean(n0))
    print("relative RMSE: native vs native %.4f, tables vs native %.4f; mean ratio %.4f"
          % (noise, diff, mean_ratio), flush=True)
    C.save_png(os.path.join(out, "glass-tables-vs-native.png"), np.concatenate([n0, l0], axis=1))


if __name__ == "__main__":
    main()
