"""make pbrt4-check PBRT4=/path/to/pbrt: our spectral table files rendered
by a pbrt-v4 binary the user has (it builds no renderer).

1. The furnace (furnace.py): pbrt-v4's image of a sphere under a uniform
   light, one bounce, against the directional albedo of our layers of the
   same material per wavelength, turned into the film's RGB; calibrated by
   pbrt-v4's own white diffuse sphere.
2. The peers (peer.py): our table file in `measured` against pbrt-v4's
   `coatedconductor` / `coateddiffuse` of the same parameters.
Prints both tables; writes the pictures with --pictures DIR."""

import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import furnace  # noqa: E402
import materials  # noqa: E402
import pbrt4  # noqa: E402
import peer  # noqa: E402
import spectra  # noqa: E402


def build_table(llbuild, material, wavelengths, work, threads):
    layers = os.path.join(work, material.name + ".layers")
    out = os.path.join(work, material.name + ".spectral.bsdf")
    with open(layers, "w") as f:
        f.write(material.layers_text)
    command = [llbuild, "--format", "measured", "--wavelengths", wavelengths, layers, "-o", out]
    if threads:
        command[1:1] = ["--threads", str(threads)]
    start = time.perf_counter()
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    if run.returncode != 0:
        raise RuntimeError("llbuild failed on %s:\n%s" % (layers, run.stdout.decode()))
    return out, time.perf_counter() - start


def measured_line(path):
    return 'Material "measured" "string filename" [ %s ]' % pbrt4.quote(path)


def save_png(path, images, exposure=1.0):
    from PIL import Image
    row = np.concatenate(images, axis=1) * exposure
    srgb = np.where(row <= 0.0031308, 12.92 * row, 1.055 * np.power(np.clip(row, 0, None), 1 / 2.4) - 0.055)
    Image.fromarray((np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8)).save(path, optimize=True)


def run_furnace(args, ll, wavelengths_nm):
    print("\n## Furnace: pbrt-v4 `measured` on our spectral tables against our layers' albedo\n")
    res, spp = args.furnace_resolution, args.furnace_spp
    white, _, _ = pbrt4.render(args.pbrt, furnace.scene(
        'Material "diffuse" "rgb reflectance" [ 1 1 1 ]', res, spp, "white.pfm"),
        args.work, "white", seed=1, threads=args.threads)
    mus = np.linspace(0.02, 1.0, 99)
    ones = np.ones((len(mus), 2))
    white_rgb = spectra.film_rgb(np.array([300.0, 900.0]), ones)
    expected_white, inside, view = furnace.expected_image(mus, white_rgb, res)
    sel = inside & (view < 80)
    white_scale = (white[sel] / expected_white[sel]).mean(axis=0)
    print("white diffuse sphere: pbrt-v4 / expected film RGB = %.4f %.4f %.4f "
          "(one scale for the three channels: the conversion agrees)" % tuple(white_scale))
    white_scale = white_scale.mean()
    results = []
    for m in materials.furnace_materials():
        table, seconds = build_table(args.llbuild, m, args.wavelengths, args.work, args.threads)
        image, wall, _ = pbrt4.render(args.pbrt, furnace.scene(measured_line(table), res, spp,
                                                               m.name + "-furnace.pfm"),
                                      args.work, m.name + "-furnace", seed=2, threads=args.threads)
        rgb = furnace.expected_rgb(lambda lam: materials.layers_at(ll, m, lam, args.nodes),
                                   wavelengths_nm, mus)
        expected, inside, view = furnace.expected_image(mus, rgb, res)
        rows = furnace.compare(image, expected, inside, view, white_scale)
        results.append((m, rows, os.path.getsize(table), seconds))
    print("| material | viewing angle | pixels | expected R G B | pbrt-v4 - expected (R, G, B) | "
          "noise (1 sigma) |")
    print("|---|---|---|---|---|---|")
    worst = 0.0
    for m, rows, size, seconds in results:
        for r in rows:
            worst = max(worst, float(np.max(np.abs(r["diff"]) - 3 * r["stderr"])))
            print("| %s | %d-%d | %d | %.4f %.4f %.4f | %+.2f%% %+.2f%% %+.2f%% | %.2f%% |"
                  % ((m.name, r["bin"][0], r["bin"][1], r["pixels"]) + tuple(r["expected"]) +
                     tuple(100 * r["diff"]) + (100 * float(r["stderr"].max()),)))
    for m, rows, size, seconds in results:
        print("%s: table file %.2f MB, llbuild %.1f s" % (m.name, size / 1e6, seconds))
    ok = worst <= 0.01
    print("furnace: %s (largest |difference| beyond 3 sigma of noise: %.2f%%; the bound is 1%%)"
          % ("PASS" if ok else "FAIL", 100 * max(worst, 0.0)))
    return ok


def run_retro(args, ll):
    """Where the peers differ most: light and view along the same direction,
    the coat over a Lambertian base, pbrt-v4's `coateddiffuse` and our table
    in its `measured`, each pixel against our layers' f at its angle (the
    retro-reflection of Layer.eval, azimuth pi). The independent walk's f
    at such points is in tests/test_coat_ggx_monte_carlo.c."""
    import spectra as sp
    print("\n## Light and view along the same direction: f against our layers\n")
    print("| material | viewing angle | pbrt-v4's own / our layers | our table in pbrt-v4 / our "
          "layers |")
    print("|---|---|---|---|")
    res, spp = 100, args.peer_spp * 4
    white = sp.film_rgb(np.array([300.0, 900.0]), np.ones((1, 2)))[0].mean()
    for m in materials.peer_materials():
        if not m.name.startswith("coateddiffuse-a"):
            continue
        table, _ = build_table(args.llbuild, m, args.wavelengths, args.work, args.threads)
        images = []
        for who, line in (("theirs", m.pbrt_native), ("ours", measured_line(table))):
            img, _, _ = pbrt4.render(args.pbrt, furnace.scene(
                line, res, spp, "%s-retro-%s.pfm" % (m.name, who), furnace.RETRO_LIGHT),
                args.work, "%s-retro-%s" % (m.name, who), seed=5, threads=args.threads)
            images.append(img.mean(axis=2))
        stack = materials.layers_at(ll, m, 550.0, 400, orders=200)
        mu, inside = furnace.pixel_cosines(res)
        centre = np.where(inside, np.nan_to_num(mu, nan=0.0).mean(axis=2), 0.0)
        view = np.degrees(np.arccos(np.clip(centre, 0, 1)))
        for lo, hi in ((15, 30), (30, 45), (45, 60), (60, 75)):
            sel = inside & (view >= lo) & (view < hi)
            expected = sum(stack.eval(-u, u, np.pi) * u for u in centre[sel]) * white
            print("| %s | %d-%d | %.3f | %.3f |" % (m.name, lo, hi, images[0][sel].sum() / expected,
                                                    images[1][sel].sum() / expected))


def run_peers(args):
    print("\n## Peers: our tables in `measured` against pbrt-v4's layered materials\n")
    res, spp = args.peer_resolution, args.peer_spp
    print("| material | pixels | rel. RMSE | RMSE from noise | bias of mean | noise ours / "
          "theirs | time ours / theirs (s) | spp for equal noise |")
    print("|---|---|---|---|---|---|---|---|")
    for m in materials.peer_materials():
        table, _ = build_table(args.llbuild, m, args.wavelengths, args.work, args.threads)
        ours, theirs, t_ours, t_theirs = [], [], 0.0, 0.0
        for seed in (11, 12):
            img, wall, _ = pbrt4.render(args.pbrt, peer.scene(measured_line(table), res, spp,
                                        "%s-ours-%d.pfm" % (m.name, seed)),
                                        args.work, "%s-ours-%d" % (m.name, seed), seed,
                                        args.threads)
            ours.append(img)
            t_ours += wall / 2
            img, wall, _ = pbrt4.render(args.pbrt, peer.scene(m.pbrt_native, res, spp,
                                        "%s-theirs-%d.pfm" % (m.name, seed)),
                                        args.work, "%s-theirs-%d" % (m.name, seed), seed,
                                        args.threads)
            theirs.append(img)
            t_theirs += wall / 2
        s = peer.statistics(ours, theirs)
        equal = spp * (s["noise_theirs"] / s["noise_ours"]) ** 2
        print("| %s | %d | %.2f%% | %.2f%% | %+.2f%% +- %.2f%% | %.2f%% / %.2f%% | %.1f / %.1f | %d |"
              % (m.name, s["pixels"], 100 * s["rmse"], 100 * s["noise"], 100 * s["bias"],
                 100 * s["bias_err"], 100 * s["noise_ours"], 100 * s["noise_theirs"], t_ours,
                 t_theirs, round(equal)))
        if args.pictures:
            os.makedirs(args.pictures, exist_ok=True)
            save_png(os.path.join(args.pictures, m.name + ".png"),
                     [0.5 * (ours[0] + ours[1]), 0.5 * (theirs[0] + theirs[1])])
    print("(spp: %d per render, %d x %d; 'spp for equal noise' is what pbrt-v4's layered "
          "material needs to match the noise of ours at %d spp)" % (spp, res, res, spp))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--pbrt", required=True, help="a pbrt-v4 binary")
    p.add_argument("--build", required=True, help="layerlab's build folder (bin/, lib/)")
    p.add_argument("--work", required=True, help="folder for scenes, tables and images")
    p.add_argument("--wavelengths", default="360:830:10")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--nodes", type=int, default=300, help="nodes of the expected albedo")
    p.add_argument("--furnace-resolution", type=int, default=200)
    p.add_argument("--furnace-spp", type=int, default=256)
    p.add_argument("--peer-resolution", type=int, default=160)
    p.add_argument("--peer-spp", type=int, default=64)
    p.add_argument("--pictures", default=None, help="write the peer pictures here")
    p.add_argument("--skip-peers", action="store_true")
    args = p.parse_args()
    args.work = os.path.abspath(args.work)
    args.llbuild = os.path.abspath(os.path.join(args.build, "bin", "llbuild"))
    os.environ.setdefault("LAYERLAB_LIBRARY",
                          os.path.abspath(os.path.join(args.build, "lib", "liblayerlab.so")))
    sys.path.insert(0, os.path.join(spectra.ROOT, "python"))
    import layerlab as ll
    start, end, step = (float(v) for v in args.wavelengths.split(":"))
    wavelengths_nm = np.arange(start, end + 0.5 * step, step)
    os.makedirs(args.work, exist_ok=True)
    print("pbrt-v4: %s" % args.pbrt)
    ok = run_furnace(args, ll, wavelengths_nm)
    if not args.skip_peers:
        run_peers(args)
        run_retro(args, ll)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
