"""The .bsdf evaluation and sampling written in Dr.Jit operations, so that in
Mitsuba's default (symbolic, megakernel) mode they trace into the rendering
kernel instead of breaking it into one C call per wavefront.

The tables come from the C reader (ll_bsdf_get_tables: validated once, never
parsed here) and are uploaded once as Dr.Jit arrays. The algorithm is the C
reader's (src/reader/bsdf_eval.c, bsdf_sample.c, bsdf_fourier.c; Jakob et
al. 2014, sec. 7), i.e. pbrt-v3's FourierBSDF, in the layer convention of
ll_bsdf.h (mu_i > 0: light arriving from above; mu_o the outgoing cosine):

- eval: the node interval of mu_i and of mu_o (a binary search over the
  nodes), their Catmull-Rom weights (4 each: a 4 x 4 stencil of stored
  series), and sum_k a_k cos(k phi) over the 16 series in one symbolic loop
  (dr.while_loop) over lines of orders (LINE below), cos(k phi) from
  interleaved Chebyshev chains x_{k+P} = 2 cos(P phi) x_k - x_{k-P} (the
  C reader's recurrence, there with P = 4);
- pdf: the luminance of that sum over the albedo 2 pi CDF[n-1] of the
  interpolated row;
- sample: mu_o by inverting the Catmull-Rom CDF of the interpolated row
  (binary search for the segment, Newton-bisection on the segment's quartic
  integral), then phi by a bracketed root search on the series' integral
  a_0 phi + sum_k a_k sin(k phi) / k (Halley steps, bisection when a step
  leaves the bracket), from the same wrapped-Cauchy first guess as the C
  reader, u[0] >= 1/2 picking the mirrored half. The same u gives the C
  reader's direction up to float32 rounding (the arithmetic here is in the
  variant's Float, float32 in llvm_ad_rgb, where C uses double; the
  tolerances of the loops are set for float32 accordingly).

Textured files: the basis weights for per-lane parameter values are the
tensor product of 1-D linear (hat) weights over each parameter's sample
positions, as ll_bsdf_basis_coefficients computes them; only the 2 (per
parameter) bases of non-zero weight around each lane's values are read, so
the cost grows with 2^P, not with the number of bases.
"""

import ctypes
import math
import sys

import numpy as np

from . import _native
from ._native import lib
from .mitsuba_basis import BasisCorners

import drjit as dr
import mitsuba as mi

# pbrt-v3's reconstruction of green from the stored Y, R, B (ll_bsdf.h).
G_FROM_Y, G_FROM_B, G_FROM_R = 1.39829, -0.100913, -0.297375
MU_FLOOR = 1e-6          # LL_BSDF_MU_FLOOR of bsdf_internal.h
PI = math.pi
# Bounds of the root searches. The C reader stops at 1e-12 in double. In
# float32 a bracket or step of 1e-7 is below one ulp of phi near pi (2.4e-7)
# or of t near 1 (1.2e-7), and rounding noise in F keeps the steps from
# settling closer, so such a bound can only be met by luck and those lanes
# run to the iteration cap (measured on the gold file, 20000 lanes, with
# 2e-7: the slowest phi searches at the cap of 32 steps, mean 4.5; with
# 1e-6: at most 23, mean 4.2; a 16-lane packet runs as long as its slowest
# lane). 1e-6 (radians, or of the unit segment) is a few ulps and far below
# any visible change of direction.
MU_ITERATIONS = 32
PHI_ITERATIONS = 32
T_TOLERANCE = 1e-6
PHI_TOLERANCE = 1e-6
# The last Halley step on phi is taken without another pass over the series
# when it and the Newton step F / f are both at most this (radians): Halley
# converges cubically, so the error left after a step of size s is of order
# s^3 times the series' curvature, far below float32's noise here; requiring
# the Newton step to agree keeps a small Halley step where f is near zero
# (far from the root) from stopping the search. Measured on 2^18 random
# samples of the gold file against the C reader (double, 1e-12): the
# sampled phi's 99.9th-percentile difference 9.3e-6 rad with 1e-3 as with
# 1e-6 (largest 9.65e-4 with both, a lane in a flat tail of the CDF; the
# golden file 3.0e-5 and 7.4e-2 likewise, the glass 1.3e-5 and 9.9e-4
# against 1.1e-5 and 7.8e-4), while the passes a 16-lane packet runs (its
# slowest lane's, 16 lanes sharing mu_i as one pixel's samples) fell from
# 4.98 to 3.72 on average (mean per lane 3.40 -> 2.65). Without the Newton
# condition, 1e-4 already sent some lanes 0.5 rad off.
PHI_STEP_TOLERANCE = 1e-3
# Halley steps on the luminance series truncated to its first 16 orders
# that refine the wrapped-Cauchy first guess of phi before the search over
# the whole series (sample_phi). Measured on 2^16 samples of the gold file
# (16 lanes sharing mu_i): passes over the series 2.65 -> 1.50 per lane on
# average, 3.72 -> 2.84 per 16-lane packet (1 step: 1.83 and 3.18; 3: 1.49
# and 2.76); the render's CPU time 4 % (gold) and 11 % (glass) lower.
GUESS_STEPS = 2
# The coefficients are re-laid in lines of 16 floats (64 bytes, a cache
# line): one line holds the next orders of every channel of a series (16
# orders of a one-channel file; 4 orders of Y, R, B and 4 zeros of a
# three-channel one), read by one packet gather (Dr.Jit bundles gathers of a
# power of two of contiguous floats into packet loads), so that a lane reads
# one cache line per series and step instead of one gather per order and
# channel. Measured on the gold file (llvm_ad_rgb, AVX-512, 1M near-specular
# evaluations, all three channels): 0.5 us per lane when every lane has the
# same direction, 3.8-4.8 us for independent directions, with this layout or
# with packets of 4 orders per channel alike (the differences were within
# the noise of the shared machine): the lanes' scattered memory accesses and
# their different series lengths set the speed, not the arithmetic.
LINE = 16


class Tables(ctypes.Structure):
    """``ll_bsdf_tables`` (size-tagged; include/layerlab/ll_bsdf.h)."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("n_nodes", ctypes.c_size_t),
                ("n_channels", ctypes.c_size_t),
                ("n_bases", ctypes.c_size_t),
                ("max_order", ctypes.c_size_t),
                ("n_coeffs", ctypes.c_size_t),
                ("n_parameters", ctypes.c_size_t),
                ("n_parameter_values", ctypes.c_size_t),
                ("eta", ctypes.c_double),
                ("nodes", ctypes.POINTER(ctypes.c_float)),
                ("pairs", ctypes.POINTER(ctypes.c_uint32)),
                ("coeffs", ctypes.POINTER(ctypes.c_float)),
                ("cdf", ctypes.POINTER(ctypes.c_double)),
                ("a0", ctypes.POINTER(ctypes.c_double)),
                ("parameter_counts", ctypes.POINTER(ctypes.c_uint32)),
                ("parameter_positions", ctypes.POINTER(ctypes.c_float))]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(Tables)


def _array(pointer, count, dtype):
    """A numpy copy of count values at a const pointer of the tables."""
    if count == 0:
        return np.zeros(0, dtype=dtype)
    return np.ctypeslib.as_array(pointer, shape=(count,)).astype(dtype, copy=True)


def read_tables(handle):
    """The file's tables as numpy arrays (copies), from ll_bsdf_get_tables."""
    # Declared here rather than in _native's table, which the rest of the
    # package shares: only the traced path needs it.
    try:
        fn = getattr(lib._cdll, "ll_bsdf_get_tables")
    except AttributeError:
        raise _native.UnsupportedError(
            "ll_bsdf_get_tables is not exported by the loaded liblayerlab (%s); the traced "
            "Mitsuba path needs a newer library (or use the BSDF's \"mode\": \"batch\")"
            % lib.path, 6) from None
    fn.restype = ctypes.c_int
    fn.argtypes = [_native.bsdf_p, ctypes.POINTER(Tables)]
    t = Tables()
    _native.check(fn(handle, ctypes.byref(t)))
    n = t.n_nodes
    pairs = _array(t.pairs, 2 * n * n, np.uint32).reshape(n * n, 2)
    return {
        "n_nodes": n, "n_channels": t.n_channels, "n_bases": t.n_bases,
        "max_order": t.max_order, "eta": t.eta,
        "nodes": _array(t.nodes, n, np.float32),
        "offsets": np.ascontiguousarray(pairs[:, 0]),
        "lengths": np.ascontiguousarray(pairs[:, 1]),
        "coeffs": _array(t.coeffs, t.n_coeffs, np.float32),
        "cdf": _array(t.cdf, n * n * t.n_bases, np.float64),
        "a0": _array(t.a0, n * n * t.n_bases, np.float64),
        "parameter_counts": [int(c) for c in _array(t.parameter_counts, t.n_parameters,
                                                    np.uint32)],
        "parameter_positions": _array(t.parameter_positions, t.n_parameter_values,
                                      np.float64),
    }


def _line_layout(t, channels=None):
    """The coefficients in cache lines (LINE above): series (pair, basis)
    is lq = ceil(length / orders) consecutive lines from the pair's first
    line + basis lq; in line q, channel c's order orders q + j is at
    c orders + j (zero past the series' length). Returns the flat float32
    array and per pair its first line and lq (0: f is zero there). With
    channels = 1, the luminance alone (16 orders a line) of any file."""
    lengths = t["lengths"].astype(np.int64)
    offsets = t["offsets"].astype(np.int64)
    nc, nb = t["n_channels"], t["n_bases"]
    stored = nc
    nc = nc if channels is None else channels
    orders = LINE if nc == 1 else LINE // 4
    lq = (lengths + orders - 1) // orders
    starts = np.zeros(len(lengths), dtype=np.int64)
    np.cumsum(lq[:-1] * nb, out=starts[1:])
    total = int(starts[-1] + lq[-1] * nb) if len(lengths) else 0
    if total >= 2 ** 32 // LINE:
        raise ValueError("layerlab: the file's coefficients exceed 2^32 floats once laid out")
    out = np.zeros((max(total, 1), LINE), dtype=np.float32)
    coeffs = t["coeffs"]
    for p in np.nonzero(lengths)[0]:
        L, q = int(lengths[p]), int(lq[p])
        block = coeffs[offsets[p]:offsets[p] + stored * nb * L].reshape(stored, nb, L)[:nc]
        padded = np.zeros((nc, nb, q * orders), dtype=np.float32)
        padded[:, :, :L] = block
        # (c, b, q, j) -> line (b, q), slot c orders + j
        lines = padded.reshape(nc, nb, q, orders).transpose(1, 2, 0, 3).reshape(nb * q, nc * orders)
        out[starts[p]:starts[p] + nb * q, :nc * orders] = lines
    return out.ravel(), orders, starts.astype(np.uint32), lq.astype(np.uint32)


def _harmonics_start(c, s, sine, size):
    """x_0 .. x_{size-1} and x_{-size} .. x_{-1} of cos(k phi) (sine False)
    or sin(k phi) for size interleaved chains x_{k+size} = 2 cos(size phi)
    x_k - x_{k-size} (the C reader's ll_bsdf_harmonics_start, there with 4
    chains), and 2 cos(size phi). Like the three-term recurrence, the chains'
    error grows linearly with the number of steps."""
    c2 = 2.0 * c
    x = [mi.Float(0.0 if sine else 1.0), s if sine else c]
    for _ in range(size - 1):
        x.append(c2 * x[-1] - x[-2])
    sign = -1.0 if sine else 1.0
    # x_{-j} = sign x_j: cos is even, sin odd
    prev = [sign * x[size - j] for j in range(size)]
    # cos(size phi) by doubling from cos(phi)
    cm = c
    m = 1
    while m < size:
        cm = 2.0 * cm * cm - 1.0
        m *= 2
    return x[:size], prev, 2.0 * cm


class TracedBSDF:
    """A .bsdf file's tables as Dr.Jit arrays of the current variant, and
    the layer-convention eval / pdf / sample as traced Dr.Jit code."""

    def __init__(self, handle):
        t = read_tables(handle)
        self.n = t["n_nodes"]
        self.n_channels = t["n_channels"]
        self.n_bases = t["n_bases"]
        self.eta = t["eta"]
        Float, UInt32 = mi.Float, mi.UInt32
        # The variant's dynamic-size float array type (packet gathers).
        self.ArrayXf = sys.modules[Float.__module__].ArrayXf
        self.nodes_host = t["nodes"].astype(np.float64)
        self.nodes = Float(t["nodes"])
        packets, self.orders, offsets, lengths = _line_layout(t)
        self.offsets = UInt32(offsets)
        self.lengths = UInt32(lengths)
        self.coeffs = Float(packets)
        # The luminance alone in lines of 16 orders, for the sampler's passes
        # over the series (sample_phi), which read no colour: a quarter of
        # the lines (and loop steps) of the three-channel layout's 4 orders a
        # line. One-channel files are laid out so already.
        if self.n_channels == 1:
            self.ycoeffs, self.yoffsets, self.ylengths = self.coeffs, self.offsets, self.lengths
        else:
            ypackets, _, yoffsets, ylengths = _line_layout(t, 1)
            self.ycoeffs = Float(ypackets)
            self.yoffsets, self.ylengths = UInt32(yoffsets), UInt32(ylengths)
        self.cdf = Float(t["cdf"].astype(np.float32))
        self.a0 = Float(t["a0"].astype(np.float32))
        counts = t["parameter_counts"]
        positions, first = [], 0
        for c in counts:
            positions.append(t["parameter_positions"][first:first + c])
            first += c
        # The per-lane basis weights (layerlab.mitsuba_basis, shared with the
        # textured tables).
        self.basis = BasisCorners(counts, positions)

    # ------------------------------------------------------------ weights

    def spline_weights(self, mu):
        """Catmull-Rom weights of mu against the nodes (ll_spline_weights,
        pbrt-v3's CatmullRomWeights): the first node index off = idx - 1 of
        the 4-node stencil (Int32) and its 4 weights, all 0 when mu is
        outside the nodes (then the BSDF is 0)."""
        Float, Int32, UInt32 = mi.Float, mi.Int32, mi.UInt32
        n, nodes = self.n, self.nodes
        valid = (mu >= float(self.nodes_host[0])) & (mu <= float(self.nodes_host[-1]))
        # The interval is the last node <= mu, clamped to [0, n - 2]
        # (ll_find_interval); binary_search gives the first node > mu.
        first = dr.binary_search(0, n - 1, lambda i: dr.gather(Float, nodes, i) <= mu)
        idx = dr.clip(Int32(first) - 1, 0, n - 2)
        has_left, has_right = idx > 0, idx + 2 < n
        x0 = dr.gather(Float, nodes, UInt32(idx))
        x1 = dr.gather(Float, nodes, UInt32(idx + 1))
        xm = dr.gather(Float, nodes, UInt32(dr.maximum(idx - 1, 0)))
        xp = dr.gather(Float, nodes, UInt32(dr.minimum(idx + 2, n - 1)))
        width = x1 - x0
        t = dr.select(width > 0, (mu - x0) / width, 0.0)
        t2 = t * t
        t3 = t2 * t
        d0 = t3 - 2 * t2 + t
        d1 = t3 - t2
        f0 = dr.select(has_left, width / (x1 - xm), 0.0)
        f1 = dr.select(has_right, width / (xp - x0), 0.0)
        w0 = dr.select(has_left, -d0 * f0, 0.0)
        w1 = 2 * t3 - 3 * t2 + 1 - dr.select(has_left, 0.0, d0) - \
            dr.select(has_right, d1 * f1, d1)
        w2 = -2 * t3 + 3 * t2 + dr.select(has_left, d0 * f0, d0) + dr.select(has_right, 0.0, d1)
        w3 = dr.select(has_right, d1 * f1, 0.0)
        w = [dr.select(valid, v, 0.0) for v in (w0, w1, w2, w3)]
        return idx - 1, w, valid

    def basis_corners(self, params):
        """The bases of non-zero weight for per-lane parameter values (a list
        of Float, one per textured parameter): [(basis index UInt32, weight
        Float)], the 2^P corners of the lanes' cells
        (mitsuba_basis.BasisCorners). Untextured: [(None, None)]."""
        return self.basis.corners(params)

    # ------------------------------------------------------- row tables

    def row_value(self, table, off_i, w_i, o, corners):
        """The Catmull-Rom interpolation over the incident weights of a
        per-row table (cdf or a0) at outgoing node o, basis-weighted
        (ll_bsdf_row_value)."""
        Float, UInt32 = mi.Float, mi.UInt32
        n, nb = self.n, self.n_bases
        value = Float(0.0)
        for a in range(4):
            active = w_i[a] != 0
            row = UInt32(dr.maximum(off_i + a, 0)) * n + UInt32(o)
            if corners[0][0] is None:
                value = dr.fma(w_i[a], dr.gather(Float, table, row, active), value)
                continue
            s = Float(0.0)
            for basis, weight in corners:
                s = dr.fma(weight, dr.gather(Float, table, row * nb + basis,
                                             active & (weight != 0)), s)
            value = dr.fma(w_i[a], s, value)
        return value

    # ------------------------------------------------------------ series

    def gather_series(self, off_i, w_i, mu_o, corners, luminance=False):
        """The 16 stored series of the stencil at (mu_i, mu_o): per entry its
        weight w_i w_o, length in lines (0 for a zero weight) and per corner
        the index of its first line; and the longest length. With luminance,
        also per entry the same in the luminance layout (ycoeffs), and its
        longest length."""
        Float, UInt32 = mi.Float, mi.UInt32
        n, nb = self.n, self.n_bases
        off_o, w_o, valid_o = self.spline_weights(mu_o)
        entries, longest, ylongest = [], UInt32(0), UInt32(0)
        separate = luminance and self.n_channels > 1
        for a in range(4):
            for c in range(4):
                w = w_i[a] * w_o[c]
                active = w != 0
                pair = UInt32(dr.maximum(off_i + a, 0)) * n + UInt32(dr.maximum(off_o + c, 0))
                offset = dr.gather(UInt32, self.offsets, pair, active)
                length = dr.gather(UInt32, self.lengths, pair, active)
                length = dr.select(active, length, 0)
                longest = dr.maximum(longest, length)
                # series (channel c, basis b) at packet offset + (c nb + b) length
                starts = []
                for basis, weight in corners:
                    if basis is None:
                        starts.append((offset, w))
                    else:
                        starts.append((offset + basis * length, w * weight))
                if not luminance:
                    entries.append((starts, length))
                    continue
                ystarts, ylength = starts, length
                if separate:
                    yoffset = dr.gather(UInt32, self.yoffsets, pair, active)
                    ylength = dr.select(active, dr.gather(UInt32, self.ylengths, pair, active), 0)
                    ystarts = [(yoffset if basis is None else yoffset + basis * ylength, yw)
                               for (basis, _), (_, yw) in zip(corners, starts)]
                ylongest = dr.maximum(ylongest, ylength)
                entries.append((starts, length, ystarts, ylength))
        if luminance:
            return entries, longest, ylongest, valid_o
        return entries, longest, valid_o

    def _packet(self, line, size, active, coeffs=None):
        """The first size floats of a line: one packet gather."""
        index = line if size == LINE else line * (LINE // size)
        return dr.gather(self.ArrayXf, self.coeffs if coeffs is None else coeffs, index, active,
                         shape=(size, dr.width(index)))

    def series_sum(self, entries, longest, cos_phi, channels):
        """sum_k a_k cos(k phi) of the weighted series for the first
        channels channels (a list of Float), one symbolic loop over lines."""
        Float, UInt32 = mi.Float, mi.UInt32
        P = self.orders
        size = P * (1 if channels == 1 else 4)
        cur, prev, twice = _harmonics_start(cos_phi, None, False, P)

        def cond(q, *st):
            return q < longest

        def body(q, *st):
            cur, prev, sums = list(st[:P]), list(st[P:2 * P]), list(st[2 * P:])
            for entry in entries:
                starts, length = entry[0], entry[1]
                m = q < length
                for start, w in starts:
                    h = [w * x for x in cur]
                    a = self._packet(start + q, size, m)
                    for ci in range(channels):
                        acc = sums[ci]
                        for j in range(P):
                            acc = dr.fma(a[ci * P + j], h[j], acc)
                        sums[ci] = acc
            nxt = [dr.fma(twice, x, -y) for x, y in zip(cur, prev)]
            return (q + 1, *nxt, *cur, *sums)

        state = (UInt32(0), *cur, *prev) + tuple(Float(0.0) for _ in range(channels))
        out = dr.while_loop(state, cond, body, label="layerlab_series")
        return list(out[1 + 2 * P:])

    def series_coefficient(self, entries, k):
        """Coefficient k < 16 of the luminance series (k = 0: its mean)."""
        Float = mi.Float
        total = Float(0.0)
        for _, _, ystarts, ylength in entries:
            m = ylength > 0
            for start, w in ystarts:
                total = dr.fma(w, dr.gather(Float, self.ycoeffs, start * LINE + k, m), total)
        return total

    def series_integral(self, entries, ylongest, phi):
        """For the steps on phi, in one symbolic loop over the luminance
        layout's lines (16 orders each): the luminance series' integral
        F(phi) = a_0 phi + sum_{k>=1} a_k sin(k phi) / k, its derivative
        f'(phi) = -sum_k k a_k sin(k phi), and the series f(phi) = sum_k a_k
        cos(k phi). cos(k phi) and sin(k phi) for k = 16 q + j from the
        line's base harmonic cos(16 q phi), sin(16 q phi) (a rotation by
        16 phi per line) and the loop-invariant cos(j phi), sin(j phi), so
        the loop carries two harmonics instead of 4 x 16 chain values."""
        Float, UInt32 = mi.Float, mi.UInt32
        P = LINE
        s, c = dr.sincos(phi)
        cj, sj = [Float(1.0), c], [Float(0.0), s]
        c2 = 2.0 * c
        for _ in range(P - 1):
            cj.append(dr.fma(c2, cj[-1], -cj[-2]))
            sj.append(dr.fma(c2, sj[-1], -sj[-2]))
        cP, sP = cj.pop(), sj.pop()

        def cond(q, cb, sb, F, d, f):
            return q < ylongest

        def body(q, cb, sb, F, d, f):
            a = [Float(0.0)] * P
            for _, _, ystarts, ylength in entries:
                m = q < ylength
                for start, w in ystarts:
                    v = self._packet(start + q, P, m, self.ycoeffs)
                    a = [dr.fma(w, v[j], a[j]) for j in range(P)]
            k0 = Float(P * q)
            for j in range(P):
                ck = dr.fma(cb, cj[j], -sb * sj[j])
                sk = dr.fma(sb, cj[j], cb * sj[j])
                k = k0 + float(j)
                if j == 0:
                    # sin(k phi) / k, with phi itself for k = 0 (a_0 phi)
                    F = dr.fma(a[0], dr.select(q == 0, phi, sk / dr.maximum(k, 1.0)), F)
                else:
                    F = dr.fma(a[j], sk / k, F)
                d = dr.fma(a[j] * k, sk, d)
                f = dr.fma(a[j], ck, f)
            cn = dr.fma(cb, cP, -sb * sP)
            sn = dr.fma(sb, cP, cb * sP)
            return q + 1, cn, sn, F, d, f

        state = (UInt32(0), Float(1.0), Float(0.0), Float(0.0), Float(0.0), Float(0.0))
        out = dr.while_loop(state, cond, body, label="layerlab_integral")
        return out[3], -out[4], out[5]

    # --------------------------------------------------------- to colour

    def to_rgb(self, sums, scale):
        """The stored sums (Y[, R, B]) times scale as clamped (R, G, B)
        (ll_bsdf_to_rgb)."""
        y = dr.maximum(sums[0], 0.0)
        if self.n_channels == 1:
            v = dr.maximum(y * scale, 0.0)
            return mi.Color3f(v, v, v)
        r, b = sums[1], sums[2]
        g = G_FROM_Y * y + G_FROM_B * b + G_FROM_R * r
        return mi.Color3f(dr.maximum(r * scale, 0.0), dr.maximum(g * scale, 0.0),
                          dr.maximum(b * scale, 0.0))

    @staticmethod
    def cosine_scale(mu_o):
        a = dr.abs(mu_o)
        return dr.select(a == 0, 0.0, dr.rcp(dr.maximum(a, MU_FLOOR)))

    def transport_scale(self, mu_i, mu_o, radiance):
        """eta^2 of radiance transport through the interface (ll_bsdf.h)."""
        if not radiance:
            return mi.Float(1.0)
        e = dr.select(mu_o > 0, 1.0 / self.eta, self.eta)
        return dr.select(mu_i * mu_o > 0, e * e, 1.0)

    # ----------------------------------------------------- the three calls

    @staticmethod
    def _masked(w_i, active):
        """Zero stencil weights in inactive lanes: their series then have
        length 0, so a packet's loops run only as long as its longest
        *active* lane needs (a lane the renderer discards, e.g. a light
        sample of a lobe the context disables, costs no pass)."""
        if active is True:
            return w_i
        return [dr.select(active, w, 0.0) for w in w_i]

    def eval_pdf(self, mu_i, mu_o, cos_phi, corners, radiance, want_pdf=True, active=True):
        """f (clamped RGB, without cosine, transport-scaled) and the pdf per
        solid angle of sampling mu_o, phi given mu_i (ll_bsdf_eval_cos and
        ll_bsdf_pdf_cos; one series loop for both); zero where not active."""
        off_i, w_i, valid_i = self.spline_weights(mu_i)
        w_i = self._masked(w_i, active)
        entries, longest, valid_o = self.gather_series(off_i, w_i, mu_o, corners)
        sums = self.series_sum(entries, longest, cos_phi, self.n_channels)
        ok = valid_i & valid_o & (mu_o != 0) & (longest > 0)
        scale = self.transport_scale(mu_i, mu_o, radiance) * self.cosine_scale(mu_o)
        f = self.to_rgb(sums, dr.select(ok, scale, 0.0))
        if not want_pdf:
            return f, None
        rho = 2.0 * PI * self.row_value(self.cdf, off_i, w_i, self.n - 1, corners)
        pdf = dr.select(ok & (rho > 0) & (sums[0] > 0), sums[0] / rho, 0.0)
        pdf = dr.select(dr.isfinite(pdf), pdf, 0.0)
        return f, pdf

    def sample_mu(self, off_i, w_i, corners, u):
        """mu_o from u (SampleCatmullRom2D over the interpolated row; the C
        reader's sample_mu) and its density in mu_o."""
        Float, UInt32, Int32 = mi.Float, mi.UInt32, mi.Int32
        n = self.n
        maximum = self.row_value(self.cdf, off_i, w_i, n - 1, corners)
        target = u * maximum
        # The segment in which the row reaches the target: after the last
        # node below it (for target 0, the last still at 0), as the C reader.

        def below(o):
            v = self.row_value(self.cdf, off_i, w_i, o, corners)
            return (v < target) | (v <= 0.0)

        first = dr.binary_search(0, n - 1, below)
        idx = dr.clip(Int32(first) - 1, 0, n - 2)
        x0 = dr.gather(Float, self.nodes, UInt32(idx))
        x1 = dr.gather(Float, self.nodes, UInt32(idx + 1))
        xm = dr.gather(Float, self.nodes, UInt32(dr.maximum(idx - 1, 0)))
        xp = dr.gather(Float, self.nodes, UInt32(dr.minimum(idx + 2, n - 1)))
        width = x1 - x0
        f0 = self.row_value(self.a0, off_i, w_i, idx, corners)
        f1 = self.row_value(self.a0, off_i, w_i, idx + 1, corners)
        fm = self.row_value(self.a0, off_i, w_i, dr.maximum(idx - 1, 0), corners)
        fp = self.row_value(self.a0, off_i, w_i, dr.minimum(idx + 2, n - 1), corners)
        r = (target - self.row_value(self.cdf, off_i, w_i, idx, corners)) / \
            dr.select(width > 0, width, 1.0)
        d0 = dr.select(idx > 0, width * (f1 - fm) / (x1 - xm), f1 - f0)
        d1 = dr.select(idx + 2 < n, width * (fp - f0) / (xp - x0), f1 - f0)
        # The inverse of the linear interpolant's integral as the start.
        radicand = dr.maximum(f0 * f0 + 2.0 * r * (f1 - f0), 0.0)
        t = dr.select(f0 != f1, (f0 - dr.sqrt(radicand)) / (f0 - f1), r / f0)
        tolerance = 1e-6 * (dr.abs(f0) + dr.abs(f1) + dr.abs(d0) + dr.abs(d1))

        def quartic(t):
            F = t * (f0 + t * (0.5 * d0 + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0 +
                                              t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))))
            f = f0 + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) +
                                    t * (d0 + d1 + 2.0 * (f0 - f1))))
            return F, f

        def cond(it, t, lo, hi, done):
            return ~done

        def body(it, t, lo, hi, done):
            t = dr.select((t >= lo) & (t <= hi), t, 0.5 * (lo + hi))
            F, f = quartic(t)
            stop = (dr.abs(F - r) <= tolerance) | (hi - lo <= T_TOLERANCE) | \
                (it + 1 >= MU_ITERATIONS)
            lo = dr.select(~stop & (F - r < 0), t, lo)
            hi = dr.select(~stop & (F - r >= 0), t, hi)
            t = dr.select(stop, t, t - (F - r) / f)
            return it + 1, t, lo, hi, stop

        go = (maximum > 0) & (width > 0)
        _, t, _, _, _ = dr.while_loop((UInt32(0), Float(t), Float(0.0), Float(1.0), ~go),
                                      cond, body, label="layerlab_mu")
        t = dr.select(go, t, 0.0)
        _, f = quartic(t)
        mu_o = dr.fma(width, t, x0)
        pdf_mu = dr.select(maximum > 0, dr.select(width > 0, f, f0) / maximum, 0.0)
        return mu_o, pdf_mu, maximum > 0

    def sample_phi(self, entries, longest, ylongest, u):
        """phi in [0, 2 pi) from the luminance series as ll_bsdf_series_sample
        (u >= 1/2 the mirrored half, the wrapped-Cauchy first guess, a root
        of F(phi) = u F(pi) kept bracketed), a_0, and the series of every
        channel at phi. The steps are Halley's (F, f = F' and f' from the
        same pass) rather than Newton's: the root is the same (F increases
        where f > 0), reached in fewer passes over the series, and each pass
        is what costs (measured on the gold file, 20000 lanes: mean 4.1
        Newton passes, 3.4 Halley passes; a 16-lane packet runs as long as
        its slowest lane). A step that leaves the bracket is replaced by
        bisection, as in C. (Summing all channels in every pass, to save the
        final one, measured slower: 5.7 against 3.3 us of CPU per sample,
        the three-channel packets' transposes cost more than the pass.)
        The passes read the luminance-only layout (ycoeffs, 16 orders a
        line). (Combining the stencil's 16 series once into per-lane local
        memory, dr.alloc_local, and reading that in every pass made the
        call about twice as fast on its own, measured, but Dr.Jit 1.5.0's
        LLVM backend fails to compile a local buffer inside a symbolic
        call, which a Mitsuba BSDF call is: "use of undefined value
        '%arr_1'", also for a minimal BSDF with an 8-float buffer.)"""
        Float, UInt32 = mi.Float, mi.UInt32
        channels = self.n_channels
        a0 = self.series_coefficient(entries, 0)
        flip = u >= 0.5
        u = dr.clip(dr.select(flip, 2.0 - 2.0 * u, 2.0 * u), 0.0, 1.0)
        target = u * a0 * PI
        r = dr.clip(self.series_coefficient(entries, 1) / (2.0 * a0), -0.99, 0.99)
        phi = 2.0 * dr.atan((1.0 - r) / (1.0 + r) * dr.tan(0.5 * PI * u))
        phi = dr.select((phi > 0) & (phi < PI), phi, 0.5 * PI)
        # A better first guess (GUESS_STEPS): Halley steps on the series
        # truncated to its first 16 orders, combined once from the stencil's
        # first luminance lines and then held in registers, so the steps cost
        # no pass over memory. A step that leaves (0, pi) is not taken; the
        # search below keeps its bracket, so the root is the same.
        head = [Float(0.0)] * LINE
        for _, _, ystarts, ylength in entries:
            m = ylength > 0
            for start, w in ystarts:
                v = self._packet(start, LINE, m, self.ycoeffs)
                head = [dr.fma(w, v[j], head[j]) for j in range(LINE)]
        for _ in range(GUESS_STEPS):
            sin_phi, cos_phi = dr.sincos(phi)
            cj, sj = [Float(1.0), cos_phi], [Float(0.0), sin_phi]
            for _ in range(LINE - 2):
                cj.append(dr.fma(2.0 * cos_phi, cj[-1], -cj[-2]))
                sj.append(dr.fma(2.0 * cos_phi, sj[-1], -sj[-2]))
            F, f, d = head[0] * phi - target, Float(0.0), Float(0.0)
            for j in range(LINE):
                if j:
                    F = dr.fma(head[j], sj[j] / float(j), F)
                    d = dr.fma(head[j] * float(j), sj[j], d)
                f = dr.fma(head[j], cj[j], f)
            # f' = -d here
            step = phi - 2.0 * F * f / (2.0 * f * f + F * d)
            phi = dr.select(dr.isfinite(step) & (step > 0) & (step < PI), step, phi)

        def cond(it, phi, lo, hi, done):
            return ~done

        def body(it, phi, lo, hi, done):
            F, d, f = self.series_integral(entries, ylongest, phi)
            F = F - target
            hi = dr.select(F > 0, phi, hi)
            lo = dr.select(F > 0, lo, phi)
            # Converged at phi: keep it (the C loop's first break).
            converged = (F == 0) | (hi - lo <= PHI_TOLERANCE)
            step = phi - 2.0 * F * f / (2.0 * f * f - F * d)
            inside = (step > lo) & (step < hi)
            # A step that small is taken without another evaluation.
            small = inside & (dr.abs(step - phi) <= PHI_STEP_TOLERANCE) & \
                (dr.abs(F) <= PHI_STEP_TOLERANCE * dr.abs(f))
            phi = dr.select(converged, phi, dr.select(inside, step, 0.5 * (lo + hi)))
            stop = converged | small | (it + 1 >= PHI_ITERATIONS)
            return it + 1, phi, lo, hi, stop

        ok = (a0 > 0) & dr.isfinite(a0)
        state = (UInt32(0), Float(phi), Float(0.0), Float(PI), ~ok)
        phi = dr.while_loop(state, cond, body, label="layerlab_phi")[1]
        # The value and density at the sampled phi from the series itself
        # (as the C reader), so that they equal what eval and pdf give.
        sums = self.series_sum(entries, dr.select(ok, longest, 0), dr.cos(phi), channels)
        phi = dr.select(flip, 2.0 * PI - phi, phi)
        phi = dr.select(phi >= 2.0 * PI, 0.0, phi)
        return phi, a0, ok, sums

    def sample(self, mu_i, u_phi, u_mu, corners, radiance, active=True):
        """(mu_o, phi, pdf, f RGB without cosine, transport-scaled, ok) for
        light arriving along mu_i (ll_bsdf_sample_core); not ok where not
        active."""
        off_i, w_i, valid_i = self.spline_weights(mu_i)
        w_i = self._masked(w_i, active)
        mu_o, pdf_mu, ok_mu = self.sample_mu(off_i, w_i, corners, u_mu)
        entries, longest, ylongest, valid_o = self.gather_series(off_i, w_i, mu_o, corners, True)
        phi, a0, ok_phi, sums = self.sample_phi(entries, longest, ylongest, u_phi)
        pdf = pdf_mu * sums[0] / (2.0 * PI * a0)
        ok = valid_i & ok_mu & valid_o & (longest > 0) & ok_phi & (pdf > 0) & dr.isfinite(pdf)
        for s in sums:
            ok = ok & dr.isfinite(s / pdf)
        scale = self.transport_scale(mu_i, mu_o, radiance) * self.cosine_scale(mu_o)
        f = self.to_rgb(sums, dr.select(ok, scale, 0.0))
        return mu_o, phi, dr.select(ok, pdf, 0.0), f, ok
