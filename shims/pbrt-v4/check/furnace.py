"""The furnace: a sphere under a uniform, spectrally flat environment, one
bounce, an orthographic camera. Each pixel of pbrt-v4's image is then the
directional albedo of the material at the pixel's viewing angle, in the
film's RGB; the expected value is computed here, per wavelength, from our
layers (the Python package over the library: the same words the table file
was built from, at a resolution where the albedo has converged), and turned
into the film's RGB as pbrt-v4 does (spectra.film_rgb)."""

import numpy as np

import pbrt4
import spectra

# Viewing-angle bins of the report, in degrees (the check stops at 80).
BINS = [(0, 10), (10, 20), (20, 30), (30, 40), (40, 50), (50, 60), (60, 70), (70, 80)]


def scene(material_line, resolution, spp, image_name, light=None):
    """The furnace; with light (a LightSource line) in place of the uniform
    environment, e.g. a distant light at the camera, each pixel is f cos
    for light and view along the same direction."""
    return """# The furnace (shims/pbrt-v4/check/furnace.py)
LookAt 0 0 10  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [ -1 1 -1 1 ]
%sWorldBegin
%s
%s
Shape "sphere" "float radius" [ 1 ]
""" % (pbrt4.film(resolution, spp, image_name),
       light or 'LightSource "infinite" "spectrum L" [ 300 1  900 1 ]', material_line)


# A distant light at the camera (light and view along the same direction).
RETRO_LIGHT = ('LightSource "distant" "point3 from" [ 0 0 10 ] "point3 to" [ 0 0 0 ]\n'
               '    "spectrum L" [ 300 1  900 1 ]')


def pixel_cosines(resolution, supersample=4):
    """Per pixel, the viewing cosines at supersample^2 points of its area
    (NaN off the sphere), and a mask of pixels wholly on the sphere."""
    step = 2.0 / resolution
    offsets = (np.arange(supersample) + 0.5) / supersample
    centre = -1.0 + step * (np.arange(resolution)[:, None] + offsets[None, :])  # (res, ss)
    x = centre[None, :, None, :]          # columns
    y = -centre[:, None, :, None]         # rows, top first
    r2 = x * x + y * y                    # (res, res, ss, ss)
    mu = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    inside = (r2 < 1.0).all(axis=(2, 3))
    return np.where(r2 < 1.0, mu, np.nan).reshape(resolution, resolution, -1), inside


def expected_image(mu_table, rgb_table, resolution):
    """Each pixel's expected RGB: the albedo's RGB averaged over its area."""
    mu, inside = pixel_cosines(resolution)
    out = np.zeros((resolution, resolution, 3))
    for c in range(3):
        values = np.interp(np.nan_to_num(mu, nan=1.0), mu_table, rgb_table[:, c])
        out[..., c] = values.mean(axis=2)
    centre = np.where(inside, np.nan_to_num(mu, nan=0.0).mean(axis=2), 0.0)
    view = np.where(inside, np.degrees(np.arccos(np.clip(centre, 0, 1))), 90.0)
    return out, inside, view


def compare(image, expected, inside, view, white_scale):
    """Per bin of viewing angle: mean relative difference of pbrt-v4's pixels
    from the expected ones (per channel), its standard error, pixel count."""
    rows = []
    for lo, hi in BINS:
        sel = inside & (view >= lo) & (view < hi)
        count = int(sel.sum())
        ratio = image[sel] / (expected[sel] * white_scale)
        mean = ratio.mean(axis=0) - 1.0
        err = ratio.std(axis=0, ddof=1) / np.sqrt(max(count, 1))
        rows.append({"bin": (lo, hi), "pixels": count, "diff": mean, "stderr": err,
                     "expected": (expected[sel] * white_scale).mean(axis=0)})
    return rows


def albedo_spectra(layers_of, wavelengths, mus):
    """(len(mus), len(wavelengths)) reflected albedo of the stack that
    layers_of(wavelength) returns, at viewing cosines mus."""
    out = np.zeros((len(mus), len(wavelengths)))
    for j, lam in enumerate(wavelengths):
        stack = layers_of(lam)
        for i, mu in enumerate(mus):
            out[i, j] = stack.albedo(mu)[0]
    return out


def expected_rgb(layers_of, wavelengths, mus):
    a = albedo_spectra(layers_of, wavelengths, mus)
    return spectra.film_rgb(wavelengths, a)
