"""Cross-check layerlab's media against independent radiative-transfer codes.

- iadpython (S. Prahl's adding-doubling, Python port): slab totals.
- PythonicDISORT (DISORT, discrete ordinates with delta-M and Nakajima-Tanaka
  corrections): slab totals and the angular distribution of reflected light.

Uses the C library directly through ctypes so that it checks the C ABI and
nothing else. Prints one line per check and 'N passed, N failed'.
"""
import ctypes
import os
import sys
import warnings

import numpy as np
from numpy.polynomial import legendre

warnings.simplefilter("ignore")

LIB = os.environ.get("LAYERLAB_LIBRARY") or os.path.join(
    os.environ.get("BUILD", "build"), "lib", "liblayerlab.so")
lib = ctypes.CDLL(LIB)
D, P, S = ctypes.c_double, ctypes.c_void_p, ctypes.c_size_t
lib.ll_layer_create.argtypes = [P, P, S, S, ctypes.POINTER(P)]
lib.ll_layer_destroy.argtypes = [P]
lib.ll_layer_set_henyey_greenstein.argtypes = [P, D, D, P]
lib.ll_layer_expand.argtypes = [P, D, P]
lib.ll_layer_eval.argtypes = [P, D, D, D, ctypes.POINTER(D)]
lib.ll_layer_albedo.argtypes = [P, D, ctypes.POINTER(D), ctypes.POINTER(D)]
lib.ll_quad_gauss_lobatto.argtypes = [S, P, P, P]

results = []


def check(name, ok, detail):
    results.append(ok)
    print("%s %s: %s" % ("ok  " if ok else "FAIL", name, detail))


def slab(n, albedo, g, tau):
    x = np.zeros(n)
    w = np.zeros(n)
    assert lib.ll_quad_gauss_lobatto(n, x.ctypes.data, w.ctypes.data, None) == 0
    layer = P()
    assert lib.ll_layer_create(x.ctypes.data, w.ctypes.data, n, n, ctypes.byref(layer)) == 0
    assert lib.ll_layer_set_henyey_greenstein(layer, albedo, g, None) == 0
    assert lib.ll_layer_expand(layer, tau, None) == 0
    return layer


def totals(layer, mu):
    r, t = D(), D()
    assert lib.ll_layer_albedo(layer, mu, ctypes.byref(r), ctypes.byref(t)) == 0
    return r.value, t.value


def main():
    import iadpython
    from PythonicDISORT import pydisort

    cases = [(0.99, 0.0, 1.0), (1.0, 0.9, 4.0), (0.8, 0.5, 0.5), (0.95, 0.9, 4.0),
             (0.9, -0.3, 2.0), (0.999, 0.7, 10.0)]
    for albedo, g, tau in cases:
        layer = slab(128, albedo, g, tau)
        r, t = totals(layer, 1.0)
        # Prahl's code is reliable at 16 quadrature points (it breaks at 64+).
        ref = iadpython.Sample(a=albedo, b=tau, g=g, n=1.0, n_above=1.0, n_below=1.0,
                               quad_pts=16).rt()
        err = max(abs(r - ref[0]), abs(t - ref[1]))
        check("totals vs iadpython a=%g g=%g tau=%g" % (albedo, g, tau), err < 1e-4,
              "R %.6f/%.6f T %.6f/%.6f" % (r, ref[0], t, ref[1]))
        if albedo < 1.0:
            for mu0 in (1.0, 0.5):
                legendre_moments = g ** np.arange(160)
                mu, flux_up, flux_down, _ = pydisort(
                    np.array([tau]), np.array([albedo]), 64, legendre_moments[None, :], mu0,
                    1.0, 0.0, NLeg=64, f_arr=legendre_moments[64], only_flux=True)
                rd = flux_up(0.0) / mu0
                td = sum(flux_down(tau)) / mu0
                r, t = totals(layer, mu0)
                err = max(abs(r - rd), abs(t - td))
                check("totals vs DISORT a=%g g=%g tau=%g mu0=%g" % (albedo, g, tau, mu0),
                      err < 1e-4, "R %.6f/%.6f T %.6f/%.6f" % (r, rd, t, td))
        lib.ll_layer_destroy(layer)

    # Angular distribution of reflected radiance (the original is off by a
    # quarter at normal incidence on a g = 0.9 slab).
    for albedo, g, tau, mu0 in [(0.95, 0.9, 1.0, 1.0), (0.95, 0.9, 4.0, 1.0),
                                (0.9, 0.9, 1.0, 0.6), (0.99, 0.5, 2.0, 0.8)]:
        layer = slab(200, albedo, g, tau)
        legendre_moments = g ** np.arange(300)
        mu, _, _, _, u = pydisort(np.array([tau]), np.array([albedo]), 64,
                                  legendre_moments[None, :], mu0, 1.0, 0.0, NLeg=64,
                                  f_arr=legendre_moments[64], NT_cor=True)
        worst = 0.0
        for phi in (0.0, 1.0, 2.5):
            ref = np.asarray(u(0.0, phi)).ravel()
            for j in range(32):
                if mu[j] < 0.05:
                    continue  # grazing: below the layer's first nodes, extrapolated
                f = D()
                assert lib.ll_layer_eval(layer, mu0, -mu[j], phi, ctypes.byref(f)) == 0
                ours = f.value * mu0
                worst = max(worst, abs(ours / ref[j] - 1.0))
        check("reflected radiance vs DISORT a=%g g=%g tau=%g mu0=%g" % (albedo, g, tau, mu0),
              worst < 0.005, "largest relative deviation %.2e" % worst)
        lib.ll_layer_destroy(layer)

    passed = sum(results)
    print("%d passed, %d failed" % (passed, len(results) - passed))
    return 0 if passed == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())
