"""The inversion and evaluation of the `measured` format's 2D warp
(docs/formats.md, "The 2D warp": a density bilinear over a grid of the
unit square, sampled by its marginal along y and the conditional along x)
one slice at a time, for the stacked lobe sets of a transmissive table
(mitsuba_lobes_stacked), and behind Mitsuba's interface for the warps of
one parameter (ParamWarp: a table set of one incident azimuth,
mitsuba_tables.TracedTables).

Mitsuba's warps (mi.MarginalContinuous2D1) find the slices of a parameter
themselves and read both neighbours at one point. A refracted lane reads
its two incident elevations each at its own point, one slice each
(TracedTables.refract_eval_pdf), which through Mitsuba's warps costs two
look-ups of two slices. Here the caller names the slice and the point:
every lane reads two slices, each at its own cell -- a reflected lane both
at the same point (and mixes them, as an interpolation over the
parameter does), a refracted lane each at its own -- so that a packet of
mixed lanes pays for one look-up.

The arithmetic is the warp's definition (the C reader's
src/reader/tables_warp.c computes the same): each slice normalised to
integrate to 1 over the square; at a point in cell (c, r) with fractions
(tx, ty) the density is bilinear in the cell's nodes, the marginal
integral u_y = (rows' integral up to row r) + the integral of the row
totals, linear in y, over [r, y]; u_x the conditional integral up to x of
the density along x at y (the rows r and r + 1 mixed by ty) over that
row's total. The per-slice tables are built here from the stored values
in double precision, as the writer's and Mitsuba's are.

Sampling searches the marginal for the row and the conditional for the
column. A halving over all nodes is a chain of reads, each waiting on the
one before (7 for 96 nodes, in each of two warps a sample); here each
search starts from a guide table (_guides) that leaves a lane a few
nodes, mostly one or two, and finds in them the node the full search
finds.

A sample's mixture reads slices k and k + 1 at the same rows and nodes;
in the JIT variants each slice's entries (rows, guide steps and, while
the tables stay small, nodes) hold the next slice's beside their own, so
that both are one read of one cache line. The arithmetic is the same:
the slice of weight 0 adds its value times 0 where it used to add the 0
of a read left out.
"""

import numpy as np

import drjit as dr
import mitsuba as mi


class SliceWarp:
    """A stack of warp slices ([slices, h, w] stored values) read by slice
    index and point."""

    def __init__(self, data):
        d = np.asarray(data, dtype=np.float64)
        n, h, w = d.shape
        self.w, self.h = int(w), int(h)
        # Running trapezoid integrals along x (from 0 at the first node)
        # and of the row totals along y, both over the unit square.
        cond = np.zeros_like(d)
        cond[:, :, 1:] = np.cumsum((0.5 / (w - 1)) * (d[:, :, :-1] + d[:, :, 1:]), axis=2)
        rows = cond[:, :, -1]
        marg = np.zeros((n, h))
        marg[:, 1:] = np.cumsum((0.5 / (h - 1)) * (rows[:, :-1] + rows[:, 1:]), axis=1)
        total = marg[:, -1]
        # (A slice without mass -- never in a file the C reader opened --
        # is left at 0 rather than divided by 0.)
        norm = np.where(total > 0, 1.0 / np.where(total > 0, total, 1.0), 0.0)[:, None, None]
        # A node's value and its running integral side by side: one read of
        # two floats at each of the cell's nodes; a row's total and the
        # integral before it the same.
        self.node_host = np.stack([d * norm, cond * norm], axis=-1).astype(np.float32)
        self.row_host = np.stack([rows * norm[:, :, 0], marg * norm[:, :, 0]],
                                 axis=-1).astype(np.float32)
        self.jit = dr.is_jit_v(mi.Float)
        if self.jit:
            # A sample reads slices k and k + 1 at the same nodes: each
            # slice's entries hold the next slice's beside their own (the
            # last slice's next is 0), so that a row, a node or a guide's
            # step of both is one read of one cache line (_paired). The
            # rows (and the marginal's guide) are paired always; the nodes
            # (and the conditional's guide) only while the paired tables
            # stay small: pairing doubles them, and a table that no longer
            # fits in the processor's cache then loses more to the misses
            # of its other reads (eval_pdf's at one slice) than a sample
            # gains (docs/benchmarks.md, "Table files", the "tables"
            # mode's paragraph on transmissive table files).
            self.paired = self.node_host.size * 8 <= PAIRED_NODES_BYTES
            self.node = mi.Float((_paired(self.node_host) if self.paired
                                  else self.node_host).ravel())
            self.row = mi.Float(_paired(self.row_host).ravel())
            # Where the searches' answers lie (_guides): per slice for the
            # marginal, per slice and pair of rows for the conditional,
            # paired the same.
            self.bits_row, self.bits_node = _bits(h), _bits(w)
            guide_row, guide_node = _guides(self.node_host, self.row_host)
            self.guide_row = mi.UInt32(_pack(*guide_row, self.bits_row, True))
            self.guide_node = mi.UInt32(_pack(*guide_node, self.bits_node, self.paired))
        else:
            self.node_host = self.node_host.reshape(-1, 2)
            self.row_host = self.row_host.reshape(-1, 2)

    def cell(self, pos):
        """(the cell's first node within a slice, its row, tx, ty) of the
        point pos (clamped into the square)."""
        w, h = self.w, self.h
        px = dr.clip(pos.x, 0.0, 1.0) * float(w - 1)
        py = dr.clip(pos.y, 0.0, 1.0) * float(h - 1)
        if self.jit:
            cx = dr.minimum(mi.UInt32(mi.Int32(px)), w - 2)
            cy = dr.minimum(mi.UInt32(mi.Int32(py)), h - 2)
        else:
            cx, cy = min(int(px), w - 2), min(int(py), h - 2)
        return cy * w + cx, cy, px - cx, py - cy

    def read(self, k, cell, active, cdf=True):
        """The values of slice k at the cell: the four nodes (x, then y
        varying), and with cdf the running integrals at the cell's left
        nodes (rows r, r + 1), the totals of rows r, r + 1 and the
        integral before row r."""
        node, row = cell[0], cell[1]
        base = k * (self.w * self.h) + node
        rbase = k * self.h + row
        if self.jit:
            # (Slice k's floats of its paired entry, 0 and 2: one read of
            # the entry's four.)
            def at(i):
                if not self.paired:
                    return dr.gather(mi.Array2f, self.node, i, active)
                v = dr.gather(mi.Array4f, self.node, i, active)
                return v[0], v[2]

            def at_row(i):
                v = dr.gather(mi.Array4f, self.row, i, active)
                return v[0], v[2]
        elif not active:
            # (A lane that reads nothing: its slice may lie past the last.)
            return [0.0] * (9 if cdf else 4)
        else:
            def at(i):
                v = self.node_host[int(i)]
                return float(v[0]), float(v[1])

            def at_row(i):
                v = self.row_host[int(i)]
                return float(v[0]), float(v[1])
        n00, n10 = at(base), at(base + 1)
        n01, n11 = at(base + self.w), at(base + self.w + 1)
        values = [n00[0], n10[0], n01[0], n11[0]]
        if not cdf:
            return values
        r0, r1 = at_row(rbase), at_row(rbase + 1)
        return values + [n00[1], n01[1], r0[0], r1[0], r0[1]]

    @staticmethod
    def mix(a, b, wa, wb):
        """Two slices' values mixed with weights wa, wb (an interpolation
        over the parameter)."""
        return [dr.fma(x, wa, y * wb) for x, y in zip(a, b)]

    @staticmethod
    def density(values, cell):
        """The density at the point (bilinear in the cell's nodes)."""
        v00, v10, v01, v11 = values[:4]
        tx, ty = cell[2], cell[3]
        return dr.lerp(dr.lerp(v00, v10, tx), dr.lerp(v01, v11, tx), ty)

    def invert(self, values, cell):
        """(the square's point u that the warp maps to the cell's point,
        the density there) from read(..., cdf=True) values."""
        v00, v10, v01, v11, c0, c1, t0, t1, before = values
        tx, ty = cell[2], cell[3]
        uy = before + ty * dr.fma(0.5 * ty, t1 - t0, t0) * (1.0 / (self.h - 1))
        g0, g1 = dr.lerp(v00, v01, ty), dr.lerp(v10, v11, ty)
        ux = dr.lerp(c0, c1, ty) + tx * dr.fma(0.5 * tx, g1 - g0, g0) * (1.0 / (self.w - 1))
        total = dr.lerp(t0, t1, ty)
        ux = ux / dr.select(total > 0, total, 1.0)
        return mi.Point2f(ux, uy), dr.lerp(g0, g1, tx)

    # ------------------------------------------------------------ sampling

    def _search(self, lo, hi, below):
        """The last index i in [lo - 1, hi - 1] with below(i) (below(lo -
        1) holds, below is monotone): a scan (the scalar variants)."""
        i = lo
        while i < hi and below(i):
            i += 1
        return i - 1

    @staticmethod
    def _interval(guide, size, bits, paired, base, u, on0, on1, i0, i1, n):
        """The nodes [first, last] where a search of the integral for u
        answers (_guides; size entries a row, packed by _pack with bits):
        the smallest first and the largest last of the row base + i0 and
        the next slice's same row (their entries side by side), of those
        that are read (on0, on1)."""
        j = dr.minimum(mi.UInt32(mi.Int32(u * float(size))), size - 1)
        mask = (1 << bits) - 1
        e = (base + i0) * size + j
        if not paired:
            def entry(i, on):
                e = (base + i) * size + j
                if bits == 8:
                    # (Two entries a word.)
                    return dr.gather(mi.UInt32, guide, e >> 1, on) >> ((e & 1) << 4)
                return dr.gather(mi.UInt32, guide, e, on)
            g0, g1 = entry(i0, on0), entry(i1, on1)
        elif bits == 8:
            # (The two slices' entries in one word.)
            g0 = dr.gather(mi.UInt32, guide, e, on0 | on1)
            g1 = g0 >> 16
        else:
            g0, g1 = dr.gather(mi.Array2u, guide, e, on0 | on1)
        first = dr.minimum(dr.select(on0, g0 & mask, n - 2), dr.select(on1, g1 & mask, n - 2))
        last = dr.maximum(dr.select(on0, (g0 >> bits) & mask, 0),
                          dr.select(on1, (g1 >> bits) & mask, 0))
        return first, dr.maximum(first, last)

    @staticmethod
    def _halve(first, last, below):
        """The last index i in [first, last] with below(i) (below(first)
        holds, below is monotone): the first SCAN nodes after first tested
        at once, then a halving of what is left, as many steps as the
        lane's interval needs.

        (A search is a chain of reads, each waiting for the one before;
        the guide leaves most intervals a few nodes wide, whose reads,
        side by side in memory, are made together.)"""
        found = first
        for d in range(1, SCAN + 1):
            node = first + d
            found = found + dr.select((node <= last) & below(dr.minimum(node, last)), 1, 0)
        done = (found < first + SCAN) | (last <= first + SCAN)

        def step(lo, hi):
            mid = (lo + hi + 1) >> 1
            b = below(mid)
            return dr.select(b, mid, lo), dr.select(b, hi, mid - 1)
        return dr.while_loop((found, dr.select(done, found, last)), lambda lo, hi: lo < hi,
                             step)[0]

    def sample(self, k0, k1, a0, a1, u, active):
        """(the point the warp maps u in [0, 1]^2 to, the density there) of
        slices k0 and k1 = k0 + 1 mixed with weights a0, a1 (a slice of
        weight 0 is not read): the row from the marginal, then the column
        from the conditional at that y, each inside its interval the root
        of the quadratic that the linear density integrates to."""
        w, h = self.w, self.h
        on0, on1 = active & (a0 > 0), active & (a1 > 0)
        if self.jit:
            k0, k1 = mi.UInt32(k0), mi.UInt32(k1)
            on = on0 | on1

            def pair(arr, i0, i1):
                if arr is self.node and not self.paired:
                    return self.mix(dr.gather(mi.Array2f, arr, i0, on0),
                                    dr.gather(mi.Array2f, arr, i1, on1), a0, a1)
                # (Slice k0's entry holds k1's beside it: one read; a
                # slice of weight 0 adds its value times 0.)
                v = dr.gather(mi.Array4f, arr, i0, on)
                return [dr.fma(v[0], a0, v[1] * a1), dr.fma(v[2], a0, v[3] * a1)]

            def second(arr, i0, i1):
                # (A search reads the running integrals alone.)
                if arr is self.node and not self.paired:
                    return dr.fma(dr.gather(mi.Float, arr, 2 * i0 + 1, on0), a0,
                                  dr.gather(mi.Float, arr, 2 * i1 + 1, on1) * a1)
                v = dr.gather(mi.Array2f, arr, 2 * i0 + 1, on)
                return dr.fma(v[0], a0, v[1] * a1)
            node_arr, row_arr = self.node, self.row
        else:
            def pair(host, i0, i1):
                v0 = host[int(i0)] if on0 else (0.0, 0.0)
                v1 = host[int(i1)] if on1 else (0.0, 0.0)
                return self.mix([float(v0[0]), float(v0[1])], [float(v1[0]), float(v1[1])],
                                a0, a1)

            def second(host, i0, i1):
                return pair(host, i0, i1)[1]
            node_arr, row_arr = self.node_host, self.row_host
        ux, uy = dr.clip(u.x, 0.0, 1.0), dr.clip(u.y, 0.0, 1.0)
        rb0, rb1 = k0 * h, k1 * h
        def above_row(i):
            return second(row_arr, rb0 + i, rb1 + i) <= uy
        if self.jit:
            r = self._halve(*self._interval(self.guide_row, GUIDE_ROW, self.bits_row, True, 0,
                                            uy, on0, on1, k0, k1, h),
                            above_row)
        else:
            r = self._search(1, h - 1, above_row)
        t0, before = pair(row_arr, rb0 + r, rb1 + r)
        t1 = pair(row_arr, rb0 + r + 1, rb1 + r + 1)[0]
        ty = _root(t0, t1, (uy - before) * float(h - 1))
        total = dr.lerp(t0, t1, ty)
        target = ux * total
        nb0, nb1 = k0 * (w * h) + r * w, k1 * (w * h) + r * w

        def column(i):
            return pair(node_arr, nb0 + i, nb1 + i), pair(node_arr, nb0 + w + i, nb1 + w + i)

        def left_of(i):
            return dr.lerp(second(node_arr, nb0 + i, nb1 + i),
                           second(node_arr, nb0 + w + i, nb1 + w + i), ty) <= target

        if self.jit:
            first, last = self._interval(self.guide_node, GUIDE_NODE, self.bits_node,
                                         self.paired, r, ux, on0, on1, k0 * (h - 1),
                                         k1 * (h - 1), w)
            # The guide leaves out the rows without mass; a mixture of
            # (almost) nothing but those -- its rows with mass weighted 0,
            # as at the edge of the support -- is searched over all nodes.
            empty = total < GUIDE_TINY
            c = self._halve(dr.select(empty, 0, first), dr.select(empty, w - 2, last), left_of)
        else:
            c = self._search(1, w - 1, left_of)
        (d00, c00), (d01, c01) = column(c)
        d10, d11 = column(c + 1)[0][0], column(c + 1)[1][0]
        g0, g1 = dr.lerp(d00, d01, ty), dr.lerp(d10, d11, ty)
        tx = _root(g0, g1, (target - dr.lerp(c00, c01, ty)) * float(w - 1))
        if self.jit:
            c, r = mi.Float(c), mi.Float(r)
        return (mi.Point2f((c + tx) * (1.0 / (w - 1)), (r + ty) * (1.0 / (h - 1))),
                dr.lerp(g0, g1, tx))


class ParamWarp:
    """A warp of slices over one parameter (the incident elevation) with
    the calls of Mitsuba's mi.MarginalContinuous2D1 -- eval(pos, params),
    invert(u, params), sample(u, params) -- read through SliceWarp. Its
    params are [(j, w0, w1)]: the two slices j, j + 1 about the parameter
    and their weights, as Mitsuba's interpolation over a parameter finds
    them (TracedTables._params, which finds them once for both warps and
    the values); each slice is read at the point and the two mixed as
    fma(v0, w0, v1 w1), Mitsuba's order. The searches of a sample
    start from SliceWarp's guides and read both slices in one look-up
    where Mitsuba's halve the whole marginal and row; the points agree
    with Mitsuba's warp to float32 rounding (test_tables_mitsuba.py, against
    Mitsuba's `measured` on the same file)."""

    def __init__(self, data):
        self.warp = SliceWarp(data)

    def _read(self, params, cell, active, cdf):
        j, w0, w1 = params[0]
        # (A slice of weight 0 is not read: it adds 0 times its value.)
        a = self.warp.read(j, cell, active & (w0 > 0), cdf)
        b = self.warp.read(j + 1, cell, active & (w1 > 0), cdf)
        return self.warp.mix(a, b, w0, w1)

    def eval(self, pos, params, active=True):
        """The density at the point pos of the square."""
        cell = self.warp.cell(pos)
        return self.warp.density(self._read(params, cell, active, False), cell)

    def invert(self, pos, params, active=True):
        """(the square's point that the warp maps to pos, the density)."""
        cell = self.warp.cell(pos)
        return self.warp.invert(self._read(params, cell, active, True), cell)

    def sample(self, u, params, active=True):
        """(the point the warp maps u to, the density there)."""
        j, w0, w1 = params[0]
        return self.warp.sample(j, j + 1, w0, w1, u, active)


# The largest paired node table (bytes) that SliceWarp keeps (above it
# its nodes are stored one slice at a time): a fraction of a current
# processor's last-level cache, between the tables measured in
# docs/benchmarks.md.
PAIRED_NODES_BYTES = 16 << 20
# A guide's entries per unit of the normalised integral (_guides): of the
# marginal's (a slice's, few) and of the conditional's (a pair of rows').
GUIDE_ROW = 256
GUIDE_NODE = 128
# How far a guide's interval reaches past its ends, in the normalised
# integral: well above the float32 rounding of the mixtures that the
# searches compare (a few units in 2^-24 of their total), well below a
# guide step, so that rounding never puts an answer outside its interval.
GUIDE_MARGIN = 1e-5
# The nodes of an interval that a search tests at once (SliceWarp._halve).
SCAN = 1
# A mixed row total below which the conditional's search ignores its guide:
# above it, the float32 products of the mixture (flushed to 0 below 2^-126)
# are still rounded within a tiny part of GUIDE_MARGIN of the total.
GUIDE_TINY = 1e-30


def _last_at_most(cdf, q):
    """For each row of cdf ([m, n], non-decreasing, within [0, 1]) and each
    threshold of q ([t]): the last node i in [0, n - 2] with cdf[i] <= q,
    node 0 counting always (the answer of SliceWarp._search); [m, t]."""
    m, n = cdf.shape
    # The rows one after the other, 4 apart, are one sorted array: one
    # searchsorted for all of them.
    offset = 4.0 * np.arange(m, dtype=np.float64)[:, None]
    inner = (np.clip(cdf[:, 1:n - 1], -1.0, 2.0) + offset).ravel()
    query = np.clip(np.asarray(q, dtype=np.float64), -1.0, 2.0)[None, :] + offset
    found = np.searchsorted(inner, query.ravel(), side="right").reshape(m, -1)
    return found - (n - 2) * np.arange(m)[:, None]


def _intervals(cdf, size):
    """Per row of cdf (normalised, [m, n]) and guide entry j < size: the
    first and last possible answer of a search for u in [j / size, (j +
    1) / size] (widened by GUIDE_MARGIN); [m, size] each."""
    j = np.arange(size, dtype=np.float64)
    return (_last_at_most(cdf, j / size - GUIDE_MARGIN),
            _last_at_most(cdf, (j + 1) / size + GUIDE_MARGIN))


def _bits(n):
    """The bits of a node index of a warp of n nodes a side in a guide's
    entry: 8 (two entries a 32-bit word) while they fit."""
    return 8 if n - 2 < 256 else 16


def _paired(a):
    """A per-slice table ([slices, ..., 2]: a value and an integral) with
    each slice's entries followed by the next slice's, [slices, ..., 4]:
    (value, next slice's value, integral, next slice's integral); the last
    slice's next is 0."""
    nxt = np.zeros_like(a)
    nxt[:-1] = a[1:]
    return np.ascontiguousarray(np.stack([a[..., 0], nxt[..., 0], a[..., 1], nxt[..., 1]],
                                         axis=-1), dtype=np.float32)


def _pack(first, last, bits, paired):
    """The entries first | last << bits of a guide ([slices, ...,
    entries]), each slice's entry paired with the next slice's same entry
    (the last slice's next 0), flat, in 32-bit words: with 8 bits both in
    one word (the slice's in the low half), with 16 bits in two words one
    after the other."""
    e = first.astype(np.uint32) | (last.astype(np.uint32) << bits)
    if not paired:
        e = e.ravel()
        if bits == 8:
            e = e.reshape(-1, 2)   # (every row has an even number of entries)
            e = e[:, 0] | (e[:, 1] << 16)
        return np.ascontiguousarray(e, dtype=np.uint32)
    nxt = np.zeros_like(e)
    nxt[:-1] = e[1:]
    if bits == 8:
        e = e | (nxt << 16)
    else:
        e = np.stack([e, nxt], axis=-1)
    return np.ascontiguousarray(e.ravel(), dtype=np.uint32)


def _guides(node, row):
    """The guide tables of SliceWarp's searches, from its node and row
    tables: for u in [j / size, (j + 1) / size] the interval of nodes
    where the answer lies, (first, last) each (a guide table:
    Devroye, Non-Uniform Random Variate Generation, 1986, II.2.4).

    The searches compare mixtures: of two slices (weights a0, a1), and
    in the conditional of rows r, r + 1 (weights 1 - ty, ty). A mixture's
    integral normalised is a convex combination of its parts' normalised
    integrals (each part weighted by its share of the total), so the last
    node where it is <= u lies between the smallest and the largest of
    the parts' last nodes: the caller takes the smallest first and the
    largest last over the slices it reads; the conditional's entries here
    are already those over the pair of rows r, r + 1. A row without mass
    adds nothing to a mixture and has the empty interval (first n - 2,
    last 0); a mixture of such rows alone is 0 everywhere (its answer the
    last node n - 2), and the caller searches it over all nodes."""
    slices, h, w = node.shape[:3]
    marg = row[:, :, 1].astype(np.float64)
    guide_row = _intervals(marg, GUIDE_ROW)
    totals = row[:, :, 0].astype(np.float64).reshape(-1)
    has = totals > 0
    cond = node[:, :, :, 1].astype(np.float64).reshape(-1, w)
    cond = cond / np.where(has, totals, 1.0)[:, None]
    lo, hi = _intervals(cond, GUIDE_NODE)
    lo = np.where(has[:, None], lo, w - 2).reshape(slices, h, GUIDE_NODE)
    hi = np.where(has[:, None], hi, 0).reshape(slices, h, GUIDE_NODE)
    guide_node = (np.minimum(lo[:, :-1], lo[:, 1:]), np.maximum(hi[:, :-1], hi[:, 1:]))
    return guide_row, guide_node


def _root(f0, f1, mass):
    """t in [0, 1] with t (f0 + t (f1 - f0) / 2) = mass: the integral of the
    density linear from f0 to f1 over [0, t] (the root that stays stable
    as f1 - f0 goes to 0)."""
    disc = dr.maximum(dr.fma(2.0 * (f1 - f0), mass, f0 * f0), 0.0)
    den = f0 + dr.sqrt(disc)
    return dr.clip(2.0 * mass / dr.select(den > 0, den, 1.0), 0.0, 1.0)
