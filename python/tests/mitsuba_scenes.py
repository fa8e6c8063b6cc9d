"""Scenes and materials shared by the Mitsuba cross-checks (test_mitsuba.py)
and the full-size measurements of docs/mitsuba.md (python/tests/mitsuba_compare.py).

A unit sphere seen from the front under a small generated environment map, with
Mitsuba's native roughconductor / roughdielectric (Beckmann) or with the
layerlab plugin on a .bsdf of the same interface built from the material
language with compensate=0, i.e. without energy compensation (Mitsuba's
microfacet BSDFs are single-scattering).
"""

import math
import os

import numpy as np

import layerlab as ll

# Gold at the sRGB primaries' wavelengths (about 650, 550, 450 nm): the same
# per-channel values in both BSDFs.
GOLD_ETA = (0.143, 0.374, 1.442)
GOLD_K = (3.983, 2.385, 1.603)
CONDUCTOR_ALPHA = 0.2
DIELECTRIC_ETA = 1.5
DIELECTRIC_ALPHA = 0.3
# The textured file's samples of alpha (rough gold).
TEXTURED_ALPHAS = (0.15, 0.2, 0.3)
EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples")
# A coated diffuse ("roughplastic"-like): examples/plastic.layers.
with open(os.path.join(EXAMPLES, "plastic.layers")) as _f:
    COATED_TEXT = _f.read()


def conductor_text(alpha=CONDUCTOR_ALPHA):
    """Rough gold in the material language, single scattering
    (compensate=0), with the per-channel eta and k of the native BSDF."""
    return "conductor eta=%s k=%s alpha=%g compensate=0" % (
        ",".join("%g" % v for v in GOLD_ETA), ",".join("%g" % v for v in GOLD_K), alpha)


def dielectric_text():
    return "dielectric eta=%g alpha=%g compensate=0" % (DIELECTRIC_ETA, DIELECTRIC_ALPHA)


def build(text, path):
    """What `llbuild` does with the text (ll_material_build), at the
    material's own resolution."""
    if not os.path.exists(path):
        ll.Material.parse(text).build(path)
    return path


def build_conductor(path, alpha=CONDUCTOR_ALPHA):
    return build(conductor_text(alpha), path)


def build_dielectric(path):
    return build(dielectric_text(), path)


def build_table(bsdf_path, path):
    """The table file of the `measured` format (ll_tables_write_from_bsdf,
    grid sizes chosen by the default table tolerance) of an opened .bsdf."""
    import ctypes
    if os.path.exists(path):
        return path
    lib = ctypes.CDLL(os.environ["LAYERLAB_LIBRARY"])
    src = ctypes.c_void_p()
    assert lib.ll_bsdf_open(bsdf_path.encode(), None, ctypes.byref(src)) == 0
    try:
        status = lib.ll_tables_write_from_bsdf(src, path.encode(), None, None)
    finally:
        lib.ll_bsdf_release(src)
    assert status == 0, "ll_tables_write_from_bsdf: status %d" % status
    return path


def native_bsdf(kind):
    if kind == "conductor":
        return {"type": "roughconductor", "distribution": "beckmann",
                "alpha": CONDUCTOR_ALPHA,
                "eta": {"type": "rgb", "value": list(GOLD_ETA)},
                "k": {"type": "rgb", "value": list(GOLD_K)}}
    return {"type": "roughdielectric", "distribution": "beckmann", "alpha": DIELECTRIC_ALPHA,
            "int_ior": DIELECTRIC_ETA, "ext_ior": 1.0}


def scene(mi, bsdf, size, spp, seed=0, max_depth=8):
    """The unit sphere under the generated environment map."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {
            "type": "perspective", "fov": 30,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1.5, 5], target=[0, 0, 0],
                                                       up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": size, "height": size,
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": environment(mi),
    })


def environment_array(width=64, height=32):
    """A small generated environment (equirectangular, linear RGB): a sky
    from blue at the zenith to white at the horizon, a brown ground and a
    broad warm patch (no small sun, whose fireflies would dominate the
    noise). Varied enough that a wrong lobe shape shows."""
    theta = (np.arange(height) + 0.5) / height * np.pi          # from the zenith
    phi = (np.arange(width) + 0.5) / width * 2.0 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(t)
    sky = np.stack([0.4 + 0.6 * (1 - up), 0.6 + 0.4 * (1 - up), np.ones_like(up)], axis=-1)
    ground = np.broadcast_to(np.array([0.35, 0.25, 0.15]), sky.shape)
    img = np.where((up > 0)[..., None], sky, ground)
    # The warm patch: a smooth bump 40 degrees above the horizon.
    d = np.sin(t) * np.cos(p - 1.0) * np.sin(np.radians(50)) + up * np.cos(np.radians(50))
    img = img + np.exp((d - 1.0) / 0.15)[..., None] * np.array([2.0, 1.5, 0.75])
    return np.ascontiguousarray(img, dtype=np.float32)


def environment(mi):
    return {"type": "envmap", "bitmap": mi.Bitmap(environment_array())}


def render(mi, scn, spp=0, seed=0):
    return np.array(mi.render(scn, spp=spp, seed=seed), dtype=np.float64)


def relative_rmse(a, b):
    """RMSE of a - b over the RMS of b (all pixels and channels)."""
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


def build_textured_conductor(path, alphas, reference_path=None, reference_alpha=None):
    """Rough gold textured over alpha (one basis per value of alphas),
    written with ll_bsdf_write_textured from layers built at those values at
    one common resolution (the sharpest alpha's), with the metadata naming
    the parameter "alpha". With reference_path, also the untextured file of
    the layers at reference_alpha (one of alphas) at the same resolution."""
    import ctypes
    from layerlab import _native
    lib = _native.lib
    sharpest = ll.Material.parse(conductor_text(min(alphas)))
    n, m, _ = sharpest.resolution()
    handles, keep, header = [], [], None
    for alpha in alphas:
        layers, header = ll.Material.parse(conductor_text(alpha)).build_layers(nodes=n, orders=m)
        keep.append(layers)
        handles.extend(layer._handle for layer in layers)
        if reference_path and alpha == reference_alpha:
            ll.Material.parse(conductor_text(alpha)).write(reference_path, layers)
    opts = _native.BsdfWriteOptions()
    opts.eta = header["eta"]
    opts.alpha[0], opts.alpha[1] = header["alpha"]
    opts.metadata = b'{"generator": "python/tests/mitsuba_scenes.py", "parameters": ["alpha"]}'
    array = (_native.layer_p * len(handles))(*handles)
    counts = (ctypes.c_size_t * 1)(len(alphas))
    positions = (ctypes.c_double * len(alphas))(*alphas)
    _native.check(lib.ll_bsdf_write_textured(os.fsencode(path), array, len(keep[0]), 1, counts,
                                             positions, ctypes.byref(opts), None))
    return path


def _sq_stats(a, b, scale):
    """Mean of the squared differences over scale, and the standard error
    of that mean (pixels are independent samples)."""
    sq = ((a - b) ** 2).ravel()
    return np.mean(sq) / scale, np.std(sq) / math.sqrt(sq.size) / scale


# Standard errors of the excess that the check allows. The per-pixel
# formula underestimates the spread of squared differences of rendered
# pixels, whose distribution has a heavy tail (rare bright paths through
# the glass): at 16 spp over 4 seed sets the glass's excess spread about 2.7
# times its formula error. 10 leaves room for that: the matching BSDFs stay
# below 0.15 of the threshold (gold over 3 seed sets at 64 spp, glass over 6
# at 32 spp), and the check keeps its power (gold at alpha 0.35 for 0.2
# lands at 1.5-1.6 times the threshold over 3 seed sets, alpha 0.4 at 1.7).
SIGMAS = 10
BIAS_ALLOWANCE = 0.015  # relative RMS of discretisation error tolerated


def check_within_noise(native, ours, native2, ours2):
    """D^2 = mean (ours - native)^2 estimates noise_native + noise_ours +
    bias^2; the two same-BSDF pairs estimate 2 noise_native and
    2 noise_ours. The excess E = D^2 - (N_native^2 + N_ours^2) / 2 (all
    relative to the native image's mean square) estimates bias^2. Pass when
    E < SIGMAS standard errors + BIAS_ALLOWANCE^2. Returns (relative RMSE,
    noise-only RMSE, E, threshold)."""
    scale = np.mean(native ** 2)
    d2, sd = _sq_stats(ours, native, scale)
    n2, sn = _sq_stats(native2, native, scale)
    l2, sl = _sq_stats(ours2, ours, scale)
    excess = d2 - (n2 + l2) / 2
    sigma = math.sqrt(sd ** 2 + (sn ** 2 + sl ** 2) / 4)
    return (math.sqrt(d2), math.sqrt((n2 + l2) / 2), excess,
            SIGMAS * sigma + BIAS_ALLOWANCE ** 2)
