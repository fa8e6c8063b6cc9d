"""Spectral data for the checks: the CIE 1931 observer as the library holds
it (read from its source, one copy in the tree), the measured indices in
data/ior/, and the film RGB pbrt-v4 makes of a reflectance spectrum under
a spectrally flat light."""

import glob
import os
import re

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))

# XYZ -> linear sRGB (IEC 61966-2-1), pbrt-v4's default film colour space.
XYZ_TO_SRGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])


def cie1931():
    """(wavelengths in nm, (n, 3) x y z) at 1 nm, 360..830 nm."""
    pattern = re.compile(r"\{\s*([-0-9.e+]+),\s*([-0-9.e+]+),\s*([-0-9.e+]+)\s*\},\s*/\*\s*(\d+) nm")
    for path in sorted(glob.glob(os.path.join(ROOT, "src", "*", "*.c"))):
        with open(path) as f:
            text = f.read()
        if "ll_cie1931_cmf" not in text:
            continue
        rows = [(int(m.group(4)), float(m.group(1)), float(m.group(2)), float(m.group(3)))
                for m in pattern.finditer(text)]
        if len(rows) > 400:
            table = np.array(rows)
            return table[:, 0], table[:, 1:]
    raise RuntimeError("the CIE 1931 table (ll_cie1931_cmf) was not found under src/")


def measured_index(name):
    """(wavelengths in nm, complex index) of data/ior/NAME.{eta,k}.spd."""
    def read(path):
        rows = []
        with open(path) as f:
            for line in f:
                line = line.split("#")[0].split(";")[0].strip()
                if line:
                    rows.append([float(v) for v in line.split()[:2]])
        return np.array(rows)
    eta = read(os.path.join(ROOT, "data", "ior", name + ".eta.spd"))
    k = read(os.path.join(ROOT, "data", "ior", name + ".k.spd"))
    return eta[:, 0], eta[:, 1] + 1j * np.interp(eta[:, 0], k[:, 0], k[:, 1])


def index_at(name, wavelengths):
    lam, n = measured_index(name)
    return np.interp(wavelengths, lam, n.real) + 1j * np.interp(wavelengths, lam, n.imag)


def film_rgb(wavelengths, values):
    """The linear sRGB that pbrt-v4's RGB film (sensor "cie1931") records of
    a reflectance spectrum sampled at `wavelengths` (piecewise linear, held
    at the ends) under a spectrally flat light, relative to a white
    reflector's: an (..., 3) array whose white is XYZ_TO_SRGB @ (1, 1, 1)
    times a constant that cancels in the ratios the checks take."""
    lam, cmf = cie1931()
    values = np.asarray(values, dtype=np.float64)
    spectrum = np.stack([np.interp(lam, wavelengths, v) for v in values.reshape(-1, values.shape[-1])])
    xyz = spectrum @ cmf / cmf[:, 1].sum()
    return (xyz @ XYZ_TO_SRGB.T).reshape(values.shape[:-1] + (3,))
