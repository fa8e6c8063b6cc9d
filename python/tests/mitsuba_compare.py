"""Full-size cross-check of the layerlab Mitsuba plugin against Mitsuba's
own roughconductor and roughdielectric, the speed ratio, and the pictures
of docs/mitsuba.md. Not part of `make test` (minutes); run by hand:

    python3 python/tests/mitsuba_compare.py OUTDIR [SIZE [SPP]]   (128, 256)

Writes OUTDIR/*.png (tonemapped, sRGB) and prints, per material, the
relative RMSE of layerlab vs native, the RMSE that Monte Carlo noise alone
gives (from a second render of each with another seed), the estimated bias
sqrt(max(0, D^2 - (N_native^2 + N_layerlab^2) / 2)), and render times.
"""

import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
import mitsuba_scenes as S  # noqa: E402


def save_png(path, img):
    mi.util.write_bitmap(path, mi.TensorXf(np.ascontiguousarray(img, dtype=np.float32)))


def timed(scene, spp, seed):
    S.render(mi, scene, spp=1, seed=99)  # compile the kernels once
    t = time.perf_counter()
    img = S.render(mi, scene, spp=spp, seed=seed)
    return img, time.perf_counter() - t


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 128
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    os.makedirs(out, exist_ok=True)
    files = {"conductor": S.build_conductor(os.path.join(out, "gold-alpha0.2.bsdf")),
             "dielectric": S.build_dielectric(os.path.join(out, "glass-alpha0.3.bsdf"))}
    print("size %dx%d, %d spp, variant %s, Mitsuba %s" % (size, size, spp, mi.variant(),
                                                          mi.__version__))
    # The native BSDFs in Mitsuba's default (symbolic) mode, before a
    # layerlab BSDF switches Dr.Jit to wavefront mode.
    symbolic = {}
    for kind in files:
        _, symbolic[kind] = timed(S.scene(mi, S.native_bsdf(kind), size, spp), spp, 0)
    for kind, path in files.items():
        native = S.scene(mi, S.native_bsdf(kind), size, spp)
        ours = S.scene(mi, {"type": "layerlab", "filename": path}, size, spp)
        n0, t_native = timed(native, spp, 0)
        n1, _ = timed(native, spp, 1)
        l0, t_ours = timed(ours, spp, 2)
        l1, _ = timed(ours, spp, 3)
        d = S.relative_rmse(l0, n0)
        nn = S.relative_rmse(n1, n0)
        nl = S.relative_rmse(l1, l0)
        expected = np.sqrt((nn ** 2 + nl ** 2) / 2)
        bias = np.sqrt(max(0.0, d ** 2 - expected ** 2))
        mean_diff = float(np.mean(l0 + l1) / np.mean(n0 + n1) - 1)
        print("%-10s relative RMSE layerlab vs native %.4f; noise alone %.4f "
              "(native %.4f, layerlab %.4f); bias estimate %.4f; mean ratio - 1 %+.4f"
              % (kind, d, expected, nn, nl, bias, mean_diff))
        print("%-10s render time native %.2f s (symbolic mode %.2f s), layerlab %.2f s, "
              "ratio %.2f (%.2f to symbolic)" % (kind, t_native, symbolic[kind], t_ours,
                                                 t_ours / t_native, t_ours / symbolic[kind]))
        # Reference-vs-ours at double the samples: the average of two renders.
        d2 = S.relative_rmse((l0 + l1) / 2, (n0 + n1) / 2)
        print("%-10s relative RMSE of the two-render averages (%d spp each) %.4f"
              % (kind, 2 * spp, d2))
        save_png(os.path.join(out, "%s-native.png" % kind), (n0 + n1) / 2)
        save_png(os.path.join(out, "%s-layerlab.png" % kind), (l0 + l1) / 2)
    # The example material, built by llbuild.
    root = os.path.dirname(os.path.dirname(HERE))
    llbuild = os.path.join(root, "build", "bin", "llbuild")
    coated = os.path.join(out, "coated-gold-with-scatmedium.bsdf")
    if not os.path.exists(coated):
        subprocess.run([llbuild, "--quiet", os.path.join(root, "examples",
                                                         "coated-gold-with-scatmedium.layers"),
                        "-o", coated], check=True)
    img, t = timed(S.scene(mi, {"type": "layerlab", "filename": coated}, size, spp), spp, 0)
    save_png(os.path.join(out, "coated-gold-with-scatmedium.png"), img)
    print("coated-gold-with-scatmedium: %.2f s" % t)


if __name__ == "__main__":
    main()
