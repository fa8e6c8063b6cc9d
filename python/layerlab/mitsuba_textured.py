"""A textured table file (layerlab's extension of the `measured` format,
docs/formats.md "Extended table files": a set of table fields per basis of
a textured .bsdf, "basis<k>." + the format's names, and the .bsdf's
parameter block) evaluated and sampled in Dr.Jit operations, as the C
reader does it (src/reader/tables_textured.c), for the Mitsuba plugin's
"tables" mode. Each basis is a layerlab.mitsuba_tables.TracedTables over
its own fields (the writer chooses each basis' grid by the tolerance, so
the grids may differ between bases).

The weights w_k of a lane are those of its parameter values
(layerlab.mitsuba_basis.BasisCorners, the Fourier path's): 2^P bases of
non-zero weight, the corners of its cell. With them:
- eval: sum_k w_k f_k;
- pdf: the mixture sum_k |w_k| pdf_k / sum_k |w_k|;
- sample: basis k picked with probability |w_k| / sum_j |w_j| by
  sample2.x, visiting the bases in the order of their index as the C
  reader does, sample2.x rescaled into the picked basis' share and passed
  on with sample2.y; wo sampled from that basis; the value and pdf of the
  blend there (every basis of non-zero weight evaluated at wo).

In the JIT variants each basis is traced once, under a symbolic
conditional whose mask is the lanes that weigh it (dr.if_stmt): a packet
of lanes runs the look-ups of the bases its lanes weigh (up to 2^P per lane
when the lanes agree), and skips the others. In the scalar variants only
the bases of non-zero weight are called.

Plain (opaque) bases only, as the writer makes them: one-sided glossy
reflection, zero unless both directions are above the surface.
"""

import numpy as np

import drjit as dr
import mitsuba as mi

from .mitsuba_basis import BasisCorners
from .mitsuba_tables import TracedTables, _masked_call
from .tensor_file import TensorFileError


def _basis_fields(fields, prefix):
    """Basis k's fields with their prefix removed: a plain table file's."""
    return {key[len(prefix):]: value for key, value in fields.items()
            if key.startswith(prefix)}


def is_textured(fields):
    """Whether the fields are a textured table file's ("textured" in its
    layerlab_layout)."""
    from .mitsuba_lobes import layout_names
    return "textured" in (layout_names(fields) or [])


class TexturedTables:
    """The bases of a textured table file, and eval / pdf / sample in
    Mitsuba's convention for per-lane parameter values."""

    def __init__(self, fields, name=""):
        for key in ("layerlab_parameter_counts", "layerlab_parameter_positions"):
            if key not in fields:
                raise TensorFileError("%s: no field `%s` (a textured table file has it)"
                                      % (name, key))
        counts = [int(c) for c in np.asarray(fields["layerlab_parameter_counts"]).ravel()]
        flat = np.asarray(fields["layerlab_parameter_positions"], dtype=np.float32).ravel()
        positions, first = [], 0
        for c in counts:
            positions.append(flat[first:first + c])
            first += c
        self.basis = BasisCorners(counts, positions)
        self.jit = dr.is_jit_v(mi.Float)
        self.sets = []
        for k in range(self.basis.n_bases):
            prefix = "basis%d." % k
            sub = _basis_fields(fields, prefix)
            if "layerlab_layout" in sub:
                raise TensorFileError("%s: basis %d has lobe sets of its own (a transmissive "
                                      "basis); the traced tables read opaque bases"
                                      % (name, k))
            if "wavelengths" in sub or "rgb" not in sub:
                raise TensorFileError("%s: basis %d is spectral (no field `%srgb`); the traced "
                                      "tables read RGB files" % (name, k, prefix))
            self.sets.append(TracedTables(sub, "%s (%s)" % (name, prefix[:-1])))
        grids = sorted(set(t.describe() for t in self.sets))
        self.grid_text = "%d bases (%s) of %s" % (len(self.sets),
                                                  " x ".join(str(c) for c in counts),
                                                  "; ".join(grids))

    def describe(self):
        return self.grid_text

    # ------------------------------------------------------------ helpers

    def _weights(self, params):
        """Per basis its lanes' weight (0 where a lane does not weigh it),
        and the sum of the weights' magnitudes."""
        corners = self.basis.corners(params)
        total = 0.0
        for _, w in corners:
            total = total + dr.abs(w)
        weights = []
        for k in range(len(self.sets)):
            w = 0.0
            for index, wc in corners:
                w = dr.select(index == k, wc, w)
            weights.append(w)
        return weights, total

    def _branch(self, mask, fn, args, zeros):
        # (a packet of lanes none of which needs the basis skips its code)
        return _masked_call(self.jit, mask, fn, args, zeros)

    @staticmethod
    def _zero_eval():
        return (mi.Float(0.0),) * 3, mi.Float(0.0)

    def _eval_basis(self, t, wi, wo, mask, want_value, want_pdf):
        def run(wi, wo, mask):
            v, p = t.eval_pdf(wi, wo, mask, want_value, want_pdf)
            return (tuple(mi.Float(x) for x in v) if want_value else (mi.Float(0.0),) * 3,
                    mi.Float(p) if want_pdf else mi.Float(0.0))
        return self._branch(mask, run, (wi, wo, mask), self._zero_eval)

    # ------------------------------------------------------ the three calls

    def eval_pdf(self, wi, wo, params, active, want_value=True, want_pdf=True):
        """(f cos theta_o as a list of 3 Float, or None; the pdf per solid
        angle of wo, or None) of the blend for the lanes' parameter values
        params (a list of Float, one per parameter)."""
        active = active & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        weights, total = self._weights(params)
        value = [0.0, 0.0, 0.0]
        pdf = 0.0
        for t, w in zip(self.sets, weights):
            mask = active & (w != 0)
            if not self.jit and not mask:
                continue
            v, p = self._eval_basis(t, wi, wo, mask, want_value, want_pdf)
            if want_value:
                value = [dr.fma(w, v[c], value[c]) for c in range(3)]
            if want_pdf:
                pdf = dr.fma(dr.abs(w), p, pdf)
        if want_value:
            value = [dr.select(active, v, 0.0) for v in value]
        if want_pdf:
            pdf = dr.select(active & (total > 0), pdf / dr.select(total > 0, total, 1.0), 0.0)
        return (value if want_value else None), (pdf if want_pdf else None)

    def sample(self, wi, sample2, params, active):
        """(wo, pdf, f cos theta_o / pdf as a list of 3 Float, ok) for the
        two random numbers sample2 and the lanes' parameter values."""
        Float, UInt32 = (mi.Float, mi.UInt32) if self.jit else (float, int)
        active = active & (mi.Frame3f.cos_theta(wi) > 0)
        corners = self.basis.corners(params, ascending=True)
        total = 0.0
        for _, w in corners:
            total = total + dr.abs(w)
        active = active & (total > 0) & dr.isfinite(total)
        # The basis whose share of [0, total) holds sample2.x total, in the
        # order of the basis index; the last of non-zero weight takes what
        # rounding leaves over (tables_textured.c).
        target = sample2.x * total
        before = Float(0.0)
        pick, pick_before, pick_weight = UInt32(0), Float(0.0), Float(0.0)
        last, last_weight = UInt32(0), Float(0.0)
        found = False if not self.jit else mi.Bool(False)
        for index, w in corners:
            a = dr.abs(w)
            nonzero = a != 0
            take = nonzero & ~found & (target < before + a) if self.jit else \
                (nonzero and not found and target < before + a)
            pick = dr.select(take, index, pick)
            pick_before = dr.select(take, before, pick_before)
            pick_weight = dr.select(take, w, pick_weight)
            found = found | take
            last = dr.select(nonzero, index, last)
            last_weight = dr.select(nonzero, w, last_weight)
            before = before + a
        pick = dr.select(found, pick, last)
        pick_weight = dr.select(found, pick_weight, last_weight)
        pick_before = dr.select(found, pick_before, total - dr.abs(last_weight))
        a_pick = dr.abs(pick_weight)
        u0 = (target - pick_before) / dr.select(a_pick > 0, a_pick, 1.0)
        # [0, 1): the largest float below 1 at most.
        u0 = dr.clip(u0, 0.0, float(np.nextafter(np.float32(1.0), np.float32(0.0))))
        u = mi.Point2f(u0, sample2.y)
        # The picked basis' sample: its direction alone.
        wo = mi.Vector3f(0.0, 0.0, 1.0)
        ok = active & False
        for k, t in enumerate(self.sets):
            mask = active & (pick == k)
            if not self.jit and not mask:
                continue

            def run(wi, u, mask, t=t):
                o, _, _, f = t.reflect_sample(wi, u, mask)
                return mi.Vector3f(o), mi.Bool(f)

            o, f = self._branch(mask, run, (wi, u, mask),
                                lambda: (mi.Vector3f(0.0, 0.0, 1.0), mi.Bool(False)))
            wo = dr.select(mask, o, wo)
            ok = dr.select(mask, f, ok)
        # The blend at wo, as eval_pdf() gives it: every basis of non-zero
        # weight evaluated there, the picked one too, through the inverse
        # warps rather than from its sampler's float32 products along the
        # forward warps, so that a sample's pdf and weight are eval_pdf()'s
        # at its direction, as the C reader's are (the sampler's parted
        # from them by up to 1.2e-4 on bases of float16 grids: coat 0.05
        # over gold 0.3).
        value, pdf = self.eval_pdf(wi, wo, params, ok)
        ok = ok & (pdf > 0)
        weight = [dr.select(ok, v / dr.select(ok, pdf, 1.0), 0.0) for v in value]
        return wo, dr.select(ok, pdf, 0.0), weight, ok
