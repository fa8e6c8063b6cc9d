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


def per_lane_costs(path, n=1 << 18):
    """Cost per element of the C batch calls (one call of n elements, wall
    time, the library's threads) and per lane of the traced code (one kernel
    of n lanes, Dr.Jit's threads), on random directions around the mirror
    direction (where the series are long), best of 3."""
    import drjit as dr
    import layerlab as ll
    from layerlab import _native
    from layerlab.mitsuba_traced import TracedBSDF
    lib, P = _native.lib, _native.c_double_p
    storage = ll.BSDFStorage(path)
    h = storage._live()
    rng = np.random.default_rng(1)
    mu_i = rng.uniform(0.05, 1, n)
    mu_o = -np.clip(mu_i + rng.normal(0, 0.3, n), -1, 1)
    phi = rng.normal(0, 0.5, n)
    u = np.ascontiguousarray(rng.uniform(0, 1, (n, 2)))
    wo = np.ascontiguousarray(np.stack([np.sqrt(1 - mu_i ** 2), 0 * mu_i, mu_i], 1))
    s = np.sqrt(1 - mu_o ** 2)
    wi = np.ascontiguousarray(np.stack([-s * np.cos(phi), -s * np.sin(phi), -mu_o], 1))
    rgb, pdf, wout = np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3))

    def best(fn):
        times = []
        for _ in range(3):
            t = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t)
        return min(times) / n * 1e9
    out = {
        "C eval batch": best(lambda: lib.ll_bsdf_eval_dir_batch(
            h, n, wo.ctypes.data_as(P), wi.ctypes.data_as(P), 0, None, 0,
            rgb.ctypes.data_as(P))),
        "C pdf batch": best(lambda: lib.ll_bsdf_pdf_dir_batch(
            h, n, wo.ctypes.data_as(P), wi.ctypes.data_as(P), None, 0,
            pdf.ctypes.data_as(P))),
        "C sample batch": best(lambda: lib.ll_bsdf_sample_dir_batch(
            h, n, wo.ctypes.data_as(P), u.ctypes.data_as(P), 0, None, 0,
            wout.ctypes.data_as(P), pdf.ctypes.data_as(P), rgb.ctypes.data_as(P))),
    }
    traced = TracedBSDF(h)
    corners = traced.basis_corners([])
    a, b, c = mi.Float(mu_i), mi.Float(mu_o), mi.Float(np.cos(phi))
    u0, u1 = mi.Float(u[:, 0]), mi.Float(u[:, 1])
    dr.eval(a, b, c, u0, u1)

    def run_eval():
        f, p = traced.eval_pdf(a, b, c, corners, True)
        dr.eval(f, p)
        np.asarray(p)

    def run_sample():
        r = traced.sample(a, u0, u1, corners, True)
        dr.eval(*r)
        np.asarray(r[2])
    run_eval()
    run_sample()  # compile
    out["traced eval_pdf"] = best(run_eval)
    out["traced sample"] = best(run_sample)
    return out


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 128
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    os.makedirs(out, exist_ok=True)
    files = {"conductor": S.build_conductor(os.path.join(out, "gold-alpha0.2.bsdf")),
             "dielectric": S.build_dielectric(os.path.join(out, "glass-alpha0.3.bsdf"))}
    print("size %dx%d, %d spp, variant %s, Mitsuba %s" % (size, size, spp, mi.variant(),
                                                          mi.__version__))
    golden = os.path.join(os.path.dirname(os.path.dirname(HERE)), "tests", "data",
                          "roughgold_alpha_0.2.bsdf")
    for name, path in (("golden file", golden), ("gold alpha 0.2", files["conductor"])):
        costs = per_lane_costs(path)
        print("%s: ns per element: %s" % (name, ", ".join("%s %.0f" % kv for kv in costs.items())))
    # Mitsuba's default (symbolic) mode: native and the traced plugin, in
    # alternation (the machine is shared; the smaller of two times).
    symbolic, traced = {}, {}
    for kind, path in files.items():
        native = S.scene(mi, S.native_bsdf(kind), size, spp)
        ours = S.scene(mi, {"type": "layerlab", "filename": path}, size, spp)
        tn, tl = [], []
        for r in range(2):
            n_img, t = timed(native, spp, r)
            tn.append(t)
            l_img, t = timed(ours, spp, r + 2)
            tl.append(t)
            if r == 0:
                n0, l0 = n_img, l_img
            else:
                n1, l1 = n_img, l_img
        symbolic[kind], traced[kind] = min(tn), min(tl)
        d = S.relative_rmse(l0, n0)
        nn = S.relative_rmse(n1, n0)
        nl = S.relative_rmse(l1, l0)
        expected = np.sqrt((nn ** 2 + nl ** 2) / 2)
        bias = np.sqrt(max(0.0, d ** 2 - expected ** 2))
        mean_diff = float(np.mean(l0 + l1) / np.mean(n0 + n1) - 1)
        print("%-10s relative RMSE layerlab (traced) vs native %.4f; noise alone %.4f "
              "(native %.4f, layerlab %.4f); bias estimate %.4f; mean ratio - 1 %+.4f"
              % (kind, d, expected, nn, nl, bias, mean_diff))
        d2 = S.relative_rmse((l0 + l1) / 2, (n0 + n1) / 2)
        print("%-10s relative RMSE of the two-render averages (%d spp each) %.4f"
              % (kind, 2 * spp, d2))
        print("%-10s symbolic mode: native %s s, traced %s s: ratio %.2f"
              % (kind, "/".join("%.2f" % t for t in tn), "/".join("%.2f" % t for t in tl),
                 traced[kind] / symbolic[kind]))
        save_png(os.path.join(out, "%s-native.png" % kind), (n0 + n1) / 2)
        save_png(os.path.join(out, "%s-layerlab.png" % kind), (l0 + l1) / 2)
    # The example material, built by llbuild, and a textured file whose
    # roughness a bitmap drives (traced path, still symbolic mode).
    root = os.path.dirname(os.path.dirname(HERE))
    llbuild = os.path.join(root, "build", "bin", "llbuild")
    coated = os.path.join(out, "coated-gold-with-scatmedium.bsdf")
    if not os.path.exists(coated):
        subprocess.run([llbuild, "--quiet", os.path.join(root, "examples",
                                                         "coated-gold-with-scatmedium.layers"),
                        "-o", coated], check=True)
    img, t = timed(S.scene(mi, {"type": "layerlab", "filename": coated}, size, spp), spp, 0)
    save_png(os.path.join(out, "coated-gold-with-scatmedium.png"), img)
    print("coated-gold-with-scatmedium: %.2f s (traced)" % t)
    textured = os.path.join(out, "gold-textured-alpha.bsdf")
    if not os.path.exists(textured):
        S.build_textured_conductor(textured, S.TEXTURED_ALPHAS)
    stripes = np.repeat(np.linspace(0.15, 0.3, 8)[None, :, None], 8, axis=0)
    alpha_map = {"type": "bitmap", "bitmap": mi.Bitmap(stripes.astype(np.float32)),
                 "raw": True, "filter_type": "nearest"}
    img, t = timed(S.scene(mi, {"type": "layerlab", "filename": textured, "alpha": alpha_map},
                           size, spp), spp, 0)
    save_png(os.path.join(out, "gold-textured-alpha.png"), img)
    print("textured gold, alpha from a bitmap (0.15 .. 0.3 in 8 stripes over u): %.2f s" % t)
    # Wavefront mode last, set on this thread (the batch mode needs it; the
    # flags a BSDF sets while Mitsuba builds it on a loader thread may miss
    # this one).
    import drjit as dr
    import layerlab.mitsuba
    layerlab.mitsuba.wavefront_mode()
    for kind, path in files.items():
        ours = S.scene(mi, {"type": "layerlab", "filename": path, "mode": "batch"}, size, spp)
        _, t_batch = timed(ours, spp, 2)
        _, t_native = timed(S.scene(mi, S.native_bsdf(kind), size, spp), spp, 0)
        print("%-10s wavefront mode: native %.2f s, batch %.2f s: ratio %.2f; batch / native "
              "symbolic %.2f (SymbolicLoops %s)"
              % (kind, t_native, t_batch, t_batch / t_native, t_batch / symbolic[kind],
                 dr.flag(dr.JitFlag.SymbolicLoops)))


if __name__ == "__main__":
    main()
