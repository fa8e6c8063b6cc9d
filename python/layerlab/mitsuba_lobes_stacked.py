"""The lobe sets of a transmissive table file (layerlab.mitsuba_lobes) in
one table: the sets' slices stacked (mitsuba_tables.stack_sets), so that
every lane evaluates or samples its own set in one pass of the same code,
the per-lane differences (the set's slices, the half vector and change
of variables of reflection, refraction or the z-flipped direction) being
selects. A packet of lanes on different sides and lobes -- most of them
at a glass surface, where sampling picks the lobe per lane by a random
number -- costs one set's look-ups instead of those of every set it
reaches. A refracted lane's first elevation (it reads two, at the pair
turned with wi to each: TracedTables.refract_eval_pdf) rides in that
look-up; its second is one more. For files whose four sets share their
grids (what the writer makes); the others use mitsuba_lobes.TracedLobes,
set by set.

The same arithmetic as TracedLobes and the C reader (tables_lobes.c,
tables_refract.c). The sets are stacked in the order ORDER (of SETS in
mitsuba_lobes), so that the sets seen from above, which a scene mostly
hits, get the parameters nearest 0 (stack_sets).
"""

import numpy as np

import drjit as dr
import mitsuba as mi

from .mitsuba_tables import STACK_SHIFTS, TracedTables, _elevation, _flip, _fresnel_at, \
    _fresnel_eta, _phi_to_u, _refraction_half, _refraction_jacobian, _theta_to_u, _turn
from .mitsuba_lobes import transmittance_at, transmittance_eta
from .tensor_file import TensorFileError

# The stacked sets' order, by their index in SETS: reflect_bottom,
# reflect_top, transmit_top, transmit_bottom.
ORDER = (1, 0, 2, 3)
# The albedos (in SETS order) of a side's reflected and transmitted sets.
SETS_TOP = (0, 2)
SETS_BOTTOM = (1, 3)


class StackedLobes:
    """eval / pdf / sample of the four lobe sets in Mitsuba's convention on
    both sides, as TracedLobes, over one stacked table."""

    def __init__(self, fields, stacked, sets, name=""):
        """fields: the file's; stacked: stack_sets of the four sets' prefixes
        in the order ORDER; sets: SETS."""
        self.table = TracedTables(stacked, name)
        self.eta = float(np.asarray(fields["eta"], dtype=np.float32).ravel()[0])
        self.jit = dr.is_jit_v(mi.Float)
        n_ti = len(np.asarray(fields["theta_i"]))
        albedo = []
        for prefix, _, _ in sets:  # (SETS order)
            a = np.asarray(fields[prefix + "albedo"], dtype=np.float32)
            if a.shape != (n_ti,):
                raise TensorFileError("%s: field `%salbedo` of shape %s" % (name, prefix,
                                                                          a.shape))
            albedo.append(a)
        self.n_ti = n_ti
        self.albedo_host = np.concatenate(albedo).astype(np.float64)
        self.theta_plain_host = np.asarray(fields["theta_i"], dtype=np.float32).astype(np.float64)
        if self.jit:
            self.albedo = mi.Float(np.concatenate(albedo))
            self.theta_plain = mi.Float(self.theta_plain_host)
        # The transmitted sets' warps: > 0 the refraction's relative index,
        # 0 the z-flipped direction's.
        self.warp_eta = [float(np.asarray(fields[p + "warp_eta"], dtype=np.float32).ravel()[0])
                         for p, _, transmit in sets if transmit]
        # The refracted sets' transmittance_eta (top, bottom): > 0 their
        # values are stored over transmittance_at.
        self.transmittance_eta = [
            transmittance_eta(fields, p, e, name) if e > 0.0 else 0.0
            for (p, _, _), e in zip([x for x in sets if x[2]], self.warp_eta)]
        # The reflected sets' fresnel_eta (top, bottom): > 0 their values are
        # stored over the Fresnel reflectance of the half vector.
        self.fresnel_eta = [_fresnel_eta(fields, p, transmit, name)
                            for p, _, transmit in sets if not transmit]
        self.grid_text = "4 sets of %d x %dx%d x %dx%d, stacked" % (
            n_ti, stacked["vndf"].shape[2], stacked["vndf"].shape[3], stacked["rgb"].shape[3],
            stacked["rgb"].shape[4])

    def describe(self):
        return self.grid_text

    # ------------------------------------------------------------ helpers

    def _elevation_weights(self, w):
        """wi's slice among the incident elevations (one grid for every
        set) and the weights of it and the next: found once per call for
        the albedos and the values (the warps find their own)."""
        return self.table._weights(self.theta_plain_host,
                                   self.theta_plain if self.jit else None, _elevation(w))

    def _share(self, weights, bottom):
        """The reflected lobe's share in sampling on wi's side: the side's
        sets' stored albedos at wi's elevation, interpolated as the slices
        are."""
        j, w0, w1 = weights
        single = self.n_ti == 1

        def albedo(k):
            base = dr.select(bottom, SETS_BOTTOM[k] * self.n_ti, SETS_TOP[k] * self.n_ti)
            if self.jit:
                base = mi.UInt32(base)
                a0 = dr.gather(mi.Float, self.albedo, j + base)
                a1 = a0 if single else dr.gather(mi.Float, self.albedo, j + 1 + base)
            else:
                a0 = self.albedo_host[j + base]
                a1 = a0 if single else self.albedo_host[j + 1 + base]
            return dr.fma(a0, w0, a1 * w1)

        r, tr = albedo(0), albedo(1)
        none = (r <= 0) & (tr <= 0)
        return dr.select(none, 1.0, r / dr.select(none, 1.0, r + tr))

    def _stack(self, bottom, transmit, weights):
        """The lane's set as stacked: (its index in ORDER, its shift, its
        slice and weights over the stacked elevations)."""
        def pick(values):
            v = [values[ORDER.index(k)] for k in range(4)]   # by SETS index
            return dr.select(bottom, dr.select(transmit, v[3], v[1]),
                             dr.select(transmit, v[2], v[0]))
        k = pick([float(k) for k in range(4)])
        j, w0, w1 = weights
        j = (mi.UInt32(k) if self.jit else int(k)) * self.n_ti + j
        return k, pick(STACK_SHIFTS), (j, w0, w1)

    def _transport(self, wi, radiance):
        if not radiance:
            return 1.0
        inv = 1.0 / (self.eta * self.eta)
        return dr.select(mi.Frame3f.cos_theta(wi) > 0, inv, self.eta * self.eta)

    def _side_eta(self, bottom):
        """The transmitted set's warp_eta on the fixed direction's side, and
        whether it refracts (> 0)."""
        top_e, bottom_e = self.warp_eta
        e = dr.select(bottom, bottom_e, top_e)
        return e, e > 0

    def _fresnel(self, w, m, bottom, reflected):
        """The factor of a reflected lane's value: the Fresnel reflectance
        at m where its side's set is stored over it, else 1."""
        top_e, bottom_e = self.fresnel_eta
        if top_e <= 0.0 and bottom_e <= 0.0:
            return 1.0
        e = dr.select(bottom, bottom_e, top_e)
        stored = reflected & (e > 0)
        return dr.select(stored, _fresnel_at(w, m, dr.select(e > 0, e, 1.5)), 1.0)

    def _transmittance(self, w, o, m, bottom, refract):
        """The factor of a refracted lane's value: transmittance_at where
        its side's set is stored over it, else 1."""
        top_e, bottom_e = self.transmittance_eta
        if top_e <= 0.0 and bottom_e <= 0.0:
            return 1.0
        e = dr.select(bottom, bottom_e, top_e)
        stored = refract & (e > 0)
        return dr.select(stored, transmittance_at(w, o, m, dr.select(e > 0, e, 1.5)), 1.0)

    # ------------------------------------------------------ the three calls

    def eval_pdf(self, wi, wo, active, radiance, reflect_on=True, transmit_on=True,
                 want_value=True, want_pdf=True):
        """As TracedLobes.eval_pdf."""
        cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
        bottom = cos_i < 0
        w = mi.Vector3f(wi.x, wi.y, dr.abs(cos_i))
        o = mi.Vector3f(wo.x, wo.y, dr.select(bottom, -cos_o, cos_o))
        transmits = cos_i * cos_o < 0
        on = dr.select(transmits, bool(transmit_on), bool(reflect_on))
        active = active & (cos_i != 0) & (cos_o != 0) & on
        weights = self._elevation_weights(w)
        stack = self._stack(bottom, transmits, weights)
        e, refracts = self._side_eta(bottom)
        refract = transmits & refracts
        # Reflection and the z-flipped direction: the reflection half vector.
        o2 = dr.select(transmits & ~refracts if self.jit else (transmits and not refracts),
                       _flip(o), o)
        m_r = dr.normalize(w + o2)
        ok_r = (w.z > 0) & (o2.z > 0)
        m_t, ok_t = _refraction_half(w, o, dr.select(refracts, e, 1.0))
        m = dr.select(refract, m_t, m_r)
        active = active & dr.select(refract, ok_t, ok_r)
        # A refracted lane reads its two elevations at the pair turned to
        # each (TracedTables.refract_eval_pdf): the first in the one warp
        # look-up every lane makes, the second beside it; its stored values
        # are blended, then D / (4 sigma) is taken at the pair itself.
        e_safe = dr.select(refracts, e, 1.0)
        elevations, axis, phi_w = self.table._elevations(w, stack)
        (w0, wi0, c0, s0, p0, _), (w1, wi1, c1, s1, p1, sl1) = elevations
        o0 = _turn(axis, c0, s0, o)
        m0, ok0 = _refraction_half(wi0, o0, e_safe)
        ok0 = ok0 & (w0 > 0)
        j, a0, a1 = stack[2]
        at = (dr.select(refract, p0, _elevation(w) + stack[1]),
              (j, dr.select(refract, 1.0, a0), dr.select(refract, 0.0, a1)), phi_w)
        raw, density = self.table._at_normal(
            dr.select(refract, wi0, w), dr.select(refract, m0, m),
            active & dr.select(refract, ok0, True), want_value, want_pdf, stack, at)
        o1 = _turn(axis, c1, s1, o)
        raw1, density1, ok1 = self.table._stored_at(
            wi1, phi_w, p1, sl1, o1, e_safe, active & refract & (w1 > 0), want_value, want_pdf)
        value = pdf = None
        if want_value:
            scale = dr.select(transmits, self._transport(wi, radiance) *
                              self._transmittance(w, o, m, bottom, refract),
                              self._fresnel(w, m, bottom, ~transmits if self.jit
                                            else not transmits))
            value = [dr.select(refract, dr.select(ok0, v0 * w0, 0.0) +
                               dr.select(ok1, v1 * w1, 0.0), v0)
                     for v0, v1 in zip(raw, raw1)]
            if self.table.jacobian:
                u_phi = _phi_to_u(dr.atan2(m.y, m.x) - phi_w)
                u_m = mi.Point2f(_theta_to_u(_elevation(m)), u_phi - dr.floor(u_phi))
                u_wi = mi.Point2f(_theta_to_u(_elevation(w)), _phi_to_u(phi_w))
                jac = self.table._jacobian_scale(u_m, u_wi, active, stack)
                value = [v * jac for v in value]
            value = [dr.select(active, dr.maximum(v, 0.0) * scale, 0.0) for v in value]
            value = [dr.select(dr.isfinite(v) & (v > 0), v, 0.0) for v in value]
        if want_pdf:
            lobe = dr.select(refract,
                             dr.select(ok0, density * w0, 0.0) *
                             _refraction_jacobian(w, o, m, e_safe) + w1 * density1,
                             density / (4.0 * dr.dot(w, m)))
            share = self._share(weights, bottom)
            pdf = lobe * dr.select(transmits, 1.0 - share, share)
            pdf = dr.select(active & dr.isfinite(pdf) & (pdf > 0), pdf, 0.0)
        return value, pdf

    def sample(self, wi, sample2, active, radiance, reflect_on=True, transmit_on=True):
        """As TracedLobes.sample."""
        cos_i = mi.Frame3f.cos_theta(wi)
        bottom = cos_i < 0
        active = active & (cos_i != 0)
        w = mi.Vector3f(wi.x, wi.y, dr.abs(cos_i))
        weights = self._elevation_weights(w)
        share = self._share(weights, bottom)
        u0 = sample2.x
        transmitted = u0 >= share
        active = active & dr.select(transmitted, bool(transmit_on), bool(reflect_on))
        # (A share of 0 or 1 leaves the other branch unpicked: its
        # division is kept finite for the scalar variants.)
        v0 = dr.select(transmitted, (u0 - share) / dr.select(share < 1.0, 1.0 - share, 1.0),
                       u0 / dr.select(share > 0.0, share, 1.0))
        v = mi.Point2f(dr.clip(v0, 0.0, 1.0), sample2.y)
        stack = self._stack(bottom, transmitted, weights)
        e, refracts = self._side_eta(bottom)
        refract = transmitted & refracts
        # A refracted lane samples one of its two elevations, picked by v.x
        # with its weight and rescaled (TracedTables.refract_sample), in the
        # one pair of warp look-ups every lane makes, at wi turned to it.
        e_safe = dr.select(refracts, e, 1.0)
        elevations, axis, phi_w = self.table._elevations(w, stack)
        (w0, wi0, c0, s0, p0, _), (w1, wi1, c1, s1, p1, _) = elevations
        second = refract & (v.x >= w0)
        u_el = dr.select(second, (v.x - w0) / dr.select(w1 > 0, w1, 1.0),
                         v.x / dr.select(w0 > 0, w0, 1.0))
        v_s = mi.Point2f(dr.select(refract, dr.clip(u_el, 0.0, 1.0), v.x), v.y)
        j, a0, a1 = stack[2]
        at = (dr.select(refract, dr.select(second, p1, p0), _elevation(w) + stack[1]),
              (j, dr.select(refract, dr.select(second, 0.0, 1.0), a0),
               dr.select(refract, dr.select(second, 1.0, 0.0), a1)), phi_w)
        w_k = dr.select(refract, dr.select(second, wi1, wi0), w)
        m, density, raw, u_m = self.table._sample_normal(w_k, v_s, active, stack, at)
        u_wi = mi.Point2f(_theta_to_u(_elevation(w)), _phi_to_u(phi_w))
        jac_r = self.table._jacobian_scale(u_m, u_wi, active, stack) if self.table.jacobian \
            else 1.0
        c = dr.dot(w_k, m)
        # Reflected about m (reflection; the z-flipped direction then flips).
        wo_r = dr.fma(m, 2.0 * c, -w)
        pdf_r = density / (4.0 * c)
        ok_r = wo_r.z > 0
        # Refracted through m at wi turned to the elevation, turned back.
        inv = 1.0 / e_safe
        k = 1.0 - inv * inv * (1.0 - c * c)
        wo_k = (inv * c - dr.safe_sqrt(k)) * m - inv * w_k
        wo_t = _turn(axis, dr.select(second, c1, c0), -dr.select(second, s1, s0), wo_k)
        m_t, ok_m = _refraction_half(w, wo_t, e_safe)
        ok_t = (c > 0) & (k > 0) & (wo_k.z < 0) & (wo_t.z < 0) & ok_m & (density > 0)
        # The other elevation at the pair turned to it.
        w_o = dr.select(second, w0, w1)
        o_o = _turn(axis, dr.select(second, c0, c1), dr.select(second, s0, s1), wo_t)
        raw_o, density_o, ok_o = self.table._stored_at(
            dr.select(second, wi0, wi1), phi_w, dr.select(second, p0, p1),
            (j, dr.select(second, 1.0, 0.0), dr.select(second, 0.0, 1.0)), o_o, e_safe,
            active & refract & ok_t & (w_o > 0), True, True)
        w_s = dr.select(second, w1, w0)
        pdf_t = w_s * density * _refraction_jacobian(w, wo_t, m_t, e_safe) + w_o * density_o
        if self.table.jacobian:
            u_phi = _phi_to_u(dr.atan2(m_t.y, m_t.x) - phi_w)
            u_mt = mi.Point2f(_theta_to_u(_elevation(m_t)), u_phi - dr.floor(u_phi))
            jac_t = self.table._jacobian_scale(u_mt, u_wi, active, stack)
        else:
            jac_t = 1.0
        value = [dr.select(refract, (w_s * v_k + dr.select(ok_o, w_o * v_o, 0.0)) * jac_t,
                           v_k * jac_r) for v_k, v_o in zip(raw, raw_o)]
        flipped = transmitted & ~refracts if self.jit else (transmitted and not refracts)
        wo = dr.select(refract, wo_t, dr.select(flipped, _flip(wo_r), wo_r))
        pdf = dr.select(refract, pdf_t, pdf_r)
        ok = active & dr.select(refract, ok_t, ok_r) & dr.isfinite(pdf) & (pdf > 0)
        pdf = pdf * dr.select(transmitted, 1.0 - share, share)
        ok = ok & (pdf > 0)
        # (A refracted lane's transmittance at wo's own refraction half
        # vector, as its evaluation takes it.)
        m = dr.select(refract, m_t, m)
        trans = self._transmittance(w, wo, m, bottom, refract)
        wo = dr.select(bottom, _flip(wo), wo)
        scale = dr.select(transmitted, self._transport(wi, radiance) * trans,
                          self._fresnel(w, m, bottom, ~transmitted if self.jit
                                        else not transmitted))
        weight = [dr.maximum(x, 0.0) * scale / dr.select(ok, pdf, 1.0) for x in value]
        weight = [dr.select(ok & dr.isfinite(x) & (x > 0), x, 0.0) for x in weight]
        return (dr.select(ok, wo, mi.Vector3f(0.0, 0.0, 1.0)), dr.select(ok, pdf, 0.0), weight,
                ok, transmitted)
