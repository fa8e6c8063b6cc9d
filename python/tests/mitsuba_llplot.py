"""The layerlab Mitsuba plugin against our own renderer, `llplot --sphere`
(tools/llplot/sphere.c), at equal spp: the same lighting (tools/llplot/scene.h:
the studio sky L(w) = G + (S + Z max(w_y, 0)) s(w_y) as an equirectangular
environment map, the key light as Mitsuba's directional emitter of the same
irradiance), the same orthographic camera along -z with the unit sphere at
0.9 of the half-width, one bounce, and llplot's 3 x 3 binomial
reconstruction filter applied to Mitsuba's box-filtered pixels. Not part of
`make test` (a minute); run by hand after `make`:

    python3 python/tests/mitsuba_llplot.py OUTDIR [FILE.layers [SIZE [SPP]]]

Prints the relative RMSE of Mitsuba vs llplot over the pixels inside the
sphere (away from the silhouette), the RMSE that noise alone gives (two
seeds of each), and the bias estimate sqrt(max(0, D^2 - noise^2)).
"""

import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
import mitsuba_scenes as S  # noqa: E402

# tools/llplot/scene.h
GROUND = np.array([0.075, 0.067, 0.058])
SKY = np.array([0.64, 0.62, 0.58])
ZENITH = np.array([-0.14, -0.14, -0.12])
HORIZON = 0.12
KEY_E = [2.70, 2.55, 2.30]
KEY_DIR = np.array([-0.50, 0.65, 0.57]) / np.linalg.norm([-0.50, 0.65, 0.57])
SPHERE_RADIUS = 0.9


def studio_sky(height=2048, width=8):
    """scene.h's sky, a function of w_y alone, as an equirectangular map
    (Mitsuba's envmap: rows from w_y = 1 down to -1, +y up)."""
    theta = (np.arange(height) + 0.5) / height * np.pi
    wy = np.cos(theta)
    t = np.clip((wy + HORIZON) / (2 * HORIZON), 0.0, 1.0)
    s = t * t * (3 - 2 * t)
    rgb = GROUND[None, :] + s[:, None] * (SKY[None, :] + ZENITH[None, :] *
                                          np.maximum(wy, 0.0)[:, None])
    return np.ascontiguousarray(np.broadcast_to(rgb[:, None, :], (height, width, 3)),
                                dtype=np.float32)


def scene(bsdf, size, spp):
    half = 1.0 / SPHERE_RADIUS
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {
            "type": "orthographic",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                       up=[0, 1, 0]) @
            mi.ScalarTransform4f().scale([half, half, 1.0]),
            "film": {"type": "hdrfilm", "width": size, "height": size,
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "sky": {"type": "envmap", "bitmap": mi.Bitmap(studio_sky())},
        "key": {"type": "directional", "direction": (-KEY_DIR).tolist(),
                "irradiance": {"type": "rgb", "value": KEY_E}},
    })


def binomial_filter(img):
    """llplot's reconstruction filter (1 2 1) x (1 2 1) / 16, edges repeated."""
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    rows = 0.25 * p[:, :-2] + 0.5 * p[:, 1:-1] + 0.25 * p[:, 2:]
    return 0.25 * rows[:-2] + 0.5 * rows[1:-1] + 0.25 * rows[2:]


def main():
    out = sys.argv[1]
    layers = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "examples",
                                                                 "plastic.layers")
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 128
    spp = int(sys.argv[4]) if len(sys.argv) > 4 else 64
    os.makedirs(out, exist_ok=True)
    name = os.path.splitext(os.path.basename(layers))[0]
    path = os.path.join(out, name + ".bsdf")
    if not os.path.exists(path):
        subprocess.run([os.path.join(ROOT, "build", "bin", "llbuild"), "--quiet", layers, "-o",
                        path], check=True)
    ours = [binomial_filter(S.render(mi, scene({"type": "layerlab", "filename": path}, size,
                                                spp), spp, seed)) for seed in (0, 1)]
    theirs = []
    for seed in (0, 1):
        exr = os.path.join(out, "%s-llplot-%d.exr" % (name, seed))
        bitmap = mi.Bitmap(llplot_exr(path, exr, size, spp, seed))
        theirs.append(bitmap)
    plots = [rgb_of(b) for b in theirs]
    coverage = alpha_of(theirs[0])
    # inside the sphere, two pixels away from the silhouette
    inside = coverage >= 1.0
    for _ in range(2):
        inside = inside & np.roll(inside, 1, 0) & np.roll(inside, -1, 0) & \
            np.roll(inside, 1, 1) & np.roll(inside, -1, 1)
    m = inside[..., None].repeat(3, axis=2)

    def rel(a, b):
        return float(np.sqrt(np.mean((a[m] - b[m]) ** 2)) / np.sqrt(np.mean(b[m] ** 2)))
    d = rel(ours[0], plots[0])
    d_flip = rel(ours[0][:, ::-1], plots[0])
    n_ours, n_plot = rel(ours[1], ours[0]), rel(plots[1], plots[0])
    noise = np.sqrt((n_ours ** 2 + n_plot ** 2) / 2)
    print("%s %dx%d %d spp: relative RMSE Mitsuba vs llplot %.4f (mirrored image: %.4f); "
          "noise alone %.4f (Mitsuba %.4f, llplot %.4f); bias estimate %.4f; mean ratio - 1 "
          "%+.4f" % (name, size, size, spp, d, d_flip, noise, n_ours, n_plot,
                     np.sqrt(max(0.0, d ** 2 - noise ** 2)),
                     float(np.mean(ours[0][m] + ours[1][m]) /
                           np.mean(plots[0][m] + plots[1][m]) - 1)))
    S_save = os.path.join(out, "%s-mitsuba-vs-llplot.png" % name)
    side = np.concatenate([(ours[0] + ours[1]) / 2, (plots[0] + plots[1]) / 2], axis=1)
    mi.util.write_bitmap(S_save, mi.TensorXf(np.ascontiguousarray(side, dtype=np.float32)))


def llplot_exr(path, exr, size, spp, seed):
    tool = os.path.join(ROOT, "build", "bin", "llplot")
    subprocess.run([tool, "--sphere", path, "-o", exr, "--size", str(size), "--spp", str(spp),
                    "--seed", str(seed)], check=True, stdout=subprocess.DEVNULL)
    return exr


def _channels(bitmap):
    names = [bitmap.struct_()[k].name for k in range(bitmap.channel_count())]
    return names, np.array(bitmap, dtype=np.float64)


def rgb_of(bitmap):
    names, data = _channels(bitmap)
    return np.stack([data[..., names.index(c)] for c in "RGB"], axis=-1)


def alpha_of(bitmap):
    names, data = _channels(bitmap)
    return data[..., names.index("A")]


if __name__ == "__main__":
    main()
