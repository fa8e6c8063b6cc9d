"""The basis weights of a textured file for per-lane parameter values, in
Dr.Jit operations: the tensor product of 1-D linear (hat) weights over each
parameter's sample positions, as ll_bsdf_basis_coefficients computes them
(values outside a parameter's range clamped to it). Only the 2 bases per
parameter around a lane's values have non-zero weight, so a lane's weights
are its cell's 2^P corners, each a basis index and a weight.

One code path for every mode that traces a textured file: the Fourier
series (layerlab.mitsuba_traced) and the textured tables
(layerlab.mitsuba_textured). In the scalar variants the same arithmetic
runs on Python floats.
"""

import itertools

import numpy as np

import drjit as dr
import mitsuba as mi


class BasisCorners:
    """A textured file's parameters: counts[p] sample positions each
    (positions[p], ascending), basis index = sum_p j_p stride_p with
    parameter 0 fastest (bsdf_basis.c)."""

    def __init__(self, counts, positions):
        self.counts = [int(c) for c in counts]
        self.positions = [[float(x) for x in p] for p in positions]
        self.jit = dr.is_jit_v(mi.Float)
        if self.jit:
            self.arrays = [mi.Float(np.asarray(p, dtype=np.float32)) for p in self.positions]
        self.strides, s = [], 1
        for c in self.counts:
            self.strides.append(s)
            s *= c
        self.n_bases = s

    def _interval(self, p, x):
        """The cell [j, j + 1] of parameter p holding x (clamped to the
        positions) and the weight t of j + 1: the last position <= x,
        clamped to [0, count - 2], as ll_find_interval."""
        count, pos = self.counts[p], self.positions[p]
        if self.jit:
            Float, UInt32 = mi.Float, mi.UInt32
            x = dr.clip(Float(x), pos[0], pos[-1])
            arr = self.arrays[p]
            first = dr.binary_search(0, count - 1, lambda i: dr.gather(Float, arr, i) <= x)
            j = UInt32(dr.clip(mi.Int32(first) - 1, 0, count - 2))
            lo = dr.gather(Float, arr, j)
            hi = dr.gather(Float, arr, j + 1)
        else:
            x = min(max(float(x), pos[0]), pos[-1])
            p32 = np.asarray(pos, dtype=np.float32)
            j = int(np.clip(np.searchsorted(p32, np.float32(x), side="right") - 1, 0,
                            count - 2))
            lo, hi = float(p32[j]), float(p32[j + 1])
        t = dr.clip((x - lo) / (hi - lo), 0.0, 1.0)
        return j, t

    def corners(self, params, ascending=False):
        """The bases of non-zero weight for per-lane parameter values (a
        list, one per parameter): [(basis index, weight)], the 2^P corners
        of the lanes' cells (a parameter of one position adds none). With
        ascending, in the order of increasing basis index in every lane
        (parameter 0's bit fastest), the order in which the C reader visits
        the bases. Untextured (no parameters): [(None, None)]."""
        Float, UInt32 = (mi.Float, mi.UInt32) if self.jit else (float, int)
        if not self.counts:
            return [(None, None)]
        options = []
        for p, count in enumerate(self.counts):
            if count == 1:
                options.append([(UInt32(0), None)])
                continue
            j, t = self._interval(p, params[p])
            options.append([(j, 1.0 - t), (j + 1, t)])
        combos = list(itertools.product(*options))
        if ascending:
            # product() varies the last parameter fastest; the basis index
            # grows fastest with parameter 0.
            combos = [tuple(reversed(c)) for c in
                      itertools.product(*reversed(options))]
        corners = []
        for combo in combos:
            index, weight = UInt32(0), None
            for p, (j, w) in enumerate(combo):
                index = index + j * self.strides[p]
                if w is not None:
                    weight = w if weight is None else weight * w
            # The C weights are floats (ll_bsdf_basis_coefficients).
            corners.append((index, Float(1.0) if weight is None else weight))
        return corners
