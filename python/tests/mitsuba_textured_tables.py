"""A textured material rendered from its table file ("tables" mode) against
its .bsdf through the Fourier path ("traced" mode), both traced into
Mitsuba's kernel (default symbolic mode), llvm_ad_rgb: the seed's grid
(examples/seed-two-roughnesses.layers, coat alpha x gold alpha) on the
sphere of mitsuba_scenes.py, a bitmap (stripes and a ramp over the
sphere's uv) driving the coat's alpha, the gold's fixed. Not part of
`make test` (minutes); run by hand:

    python3 python/tests/mitsuba_textured_tables.py SEED.bsdf SEED.tab OUT.png [SIZE [SPP [ROUNDS [FOURIER]]]]

SEED.tab: `llconvert SEED.bsdf -o SEED.tab` (or the slow test
test_tables_textured_seed with LL_TEXTURED_SEED_KEEP=DIR). FOURIER: the
.bsdf's mode, "traced" (default) or "batch" (its renders in wavefront
mode, which it needs, after all the tables' renders in symbolic mode: a
symbolic render traces every BSDF alive, and a batch-mode one refuses to
be traced, so its scene is made once the tables' are done; then the table
file also renders through "batch", the C reader, with the tables' seed:
the relative RMSE between that and the traced tables is their float32
rounding). The two alternate, ROUNDS (default 3) renders each after one to compile; prints
each render's CPU time (the process's, all threads: on a shared machine
the steadier figure) and wall time, the ratio of the smallest CPU times,
the relative RMSE between the two, and the noise: the relative RMSE
between two renders of the Fourier path with different seeds. Then the
within-noise test of mitsuba_scenes.check_within_noise (ours and the
Fourier path each rendered with two seeds) over the whole image and by
the coat's alpha at each pixel (rendered as a diffuse albedo under a
constant white sky, which returns it exactly): the example's 80 nodes and
200 orders do not resolve its sharpest coats, whose .bsdf reflects more
light than it receives (llbuild's summary says so), and the bands show
where the two paths part. Writes the pair side by side (Fourier left,
tables right; sRGB, clipped) to OUT.png.
"""

import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba as llmi  # noqa: E402
import mitsuba_scenes as S  # noqa: E402

GOLD_ALPHA = 0.1


def coat_alpha_bitmap(n=64):
    """Coat alpha over uv: eight stripes along u alternating 0.02 / 0.2,
    and a ramp from 0.02 to 0.2 along v blended in (values between the
    grid's nodes)."""
    u = (np.arange(n) + 0.5) / n
    uu, vv = np.meshgrid(u, u, indexing="xy")
    stripes = np.where(np.floor(uu * 8) % 2 == 0, 0.02, 0.2)
    ramp = 0.02 + 0.18 * vv
    return np.ascontiguousarray((0.5 * stripes + 0.5 * ramp)[..., None], dtype=np.float32)


def bsdf(path, mode):
    return {"type": "layerlab", "filename": path, "mode": mode,
            "coat_alpha": {"type": "bitmap", "bitmap": mi.Bitmap(coat_alpha_bitmap()),
                           "raw": True, "filter_type": "bilinear"},
            "gold_alpha": GOLD_ALPHA}


# The bands of the coat's alpha the images are compared over.
ALPHA_BANDS = ((0.0, 1.0), (0.05, 1.0), (0.0, 0.05))


def coat_alpha_image(size):
    """The coat's alpha at each pixel of the sphere (NaN off it): the
    bitmap as a diffuse albedo under a constant sky of radiance 1, which a
    convex sphere returns as its albedo, noise-free."""
    albedo = {"type": "diffuse",
              "reflectance": {"type": "bitmap", "bitmap": mi.Bitmap(coat_alpha_bitmap()),
                              "raw": True, "filter_type": "bilinear"}}
    base = S.scene(mi, albedo, size, 4)
    scn = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2},
                        "sensor": base.sensors()[0], "sphere": base.shapes()[0],
                        "light": {"type": "constant", "radiance": 1.0}})
    img = S.render(mi, scn, spp=4, seed=0)[..., 0]
    return np.where(img < 0.999, img, np.nan)


def print_bands(img_f, img_f2, img_t, img_t2, alpha):
    """check_within_noise over the pixels of each band, ours (seed 3)
    against the Fourier path (seed 1), the noise from each one's own pair
    of seeds."""
    for lo, hi in ALPHA_BANDS:
        m = (alpha >= lo) & (alpha < hi) if (lo, hi) != (0.0, 1.0) else np.ones(alpha.shape, bool)
        name = "whole image" if (lo, hi) == (0.0, 1.0) else "coat alpha in [%g, %g)" % (lo, hi)
        rmse, noise, excess, threshold = S.check_within_noise(img_f[m], img_t2[m], img_f2[m],
                                                              img_t[m])
        print("%s (%d pixels): relative RMSE %.4f, noise %.4f, bias excess %.2e (threshold "
              "%.2e): %s" % (name, int(m.sum()), rmse, noise, excess, threshold,
                             "within noise" if excess < threshold else "BEYOND NOISE"))


def timed(scene, spp, seed):
    # The batch mode needs wavefront mode on this thread; the others render
    # in Mitsuba's default symbolic mode.
    symbolic = "mode=batch" not in str(scene.shapes()[0].bsdf())
    dr.set_flag(dr.JitFlag.SymbolicLoops, symbolic)
    dr.set_flag(dr.JitFlag.SymbolicCalls, symbolic)
    wall, cpu = time.perf_counter(), time.process_time()
    img = S.render(mi, scene, spp=spp, seed=seed)
    return img, time.perf_counter() - wall, time.process_time() - cpu


def to_png(images, path):
    img = np.concatenate(images, axis=1)
    img = np.clip(img[..., :3], 0.0, 1.0)
    img = np.where(img <= 0.0031308, 12.92 * img, 1.055 * img ** (1 / 2.4) - 0.055)
    mi.Bitmap((img * 255 + 0.5).astype(np.uint8)).write(path)


def main():
    bsdf_path, tab_path, out = sys.argv[1:4]
    size = int(sys.argv[4]) if len(sys.argv) > 4 else 256
    spp = int(sys.argv[5]) if len(sys.argv) > 5 else 64
    rounds = int(sys.argv[6]) if len(sys.argv) > 6 else 3
    mode = sys.argv[7] if len(sys.argv) > 7 else "traced"
    llmi.register()
    print("size %dx%d, spp %d, variant %s, Mitsuba %s, load average %s"
          % (size, size, spp, mi.variant(), mi.__version__, os.getloadavg()), flush=True)
    tables = S.scene(mi, bsdf(tab_path, "tables"), size, spp)
    print(tables.shapes()[0].bsdf(), flush=True)
    fourier = None if mode == "batch" else S.scene(mi, bsdf(bsdf_path, mode), size, spp)
    cpu_t, cpu_f = [], []

    def run(name, scn, times):
        img, wall, cpu = timed(scn, spp, 1)
        if times is None:
            name += " (compiling)"
        else:
            times.append(cpu)
        print("%s: wall %.1f s, CPU %.1f s" % (name, wall, cpu), flush=True)
        return img

    # One render each to compile the kernels, then alternating rounds.
    run("tables", tables, None)
    if fourier is not None:
        run("fourier", fourier, None)
    for r in range(rounds):
        img_t = run("tables", tables, cpu_t)
        if fourier is not None:
            img_f = run("fourier (%s)" % mode, fourier, cpu_f)
    img_t2 = timed(tables, spp, 3)[0]
    if fourier is None:
        del tables
        fourier = S.scene(mi, bsdf(bsdf_path, mode), size, spp)
        run("fourier", fourier, None)
        for r in range(rounds):
            img_f = run("fourier (%s)" % mode, fourier, cpu_f)
    img_f2 = timed(fourier, spp, 2)[0]
    print("smallest CPU time: tables %.2f s, fourier %.2f s; ratio fourier / tables %.2f"
          % (min(cpu_t), min(cpu_f), min(cpu_f) / min(cpu_t)))
    print("relative RMSE tables vs fourier: %.4f; fourier vs fourier (other seed, the noise): "
          "%.4f" % (S.relative_rmse(img_t, img_f), S.relative_rmse(img_f2, img_f)))
    print("mean (R G B): tables %s, fourier %s" % (img_t[..., :3].mean(axis=(0, 1)),
                                                   img_f[..., :3].mean(axis=(0, 1))))
    if mode == "batch":
        img_c = timed(S.scene(mi, bsdf(tab_path, "batch"), size, spp), spp, 1)[0]
        print("relative RMSE tables vs the C reader on the table file (batch, same seed): %.3g"
              % S.relative_rmse(img_t, img_c))
    print_bands(img_f[..., :3], img_f2[..., :3], img_t[..., :3], img_t2[..., :3],
                coat_alpha_image(size))
    print("load average %s" % (os.getloadavg(),))
    to_png([img_f, img_t], out)


if __name__ == "__main__":
    main()
