"""The lobe sets of a transmissive table file (layerlab.mitsuba_lobes) in
one table: the sets' slices stacked (mitsuba_tables.stack_sets), so that
every lane evaluates or samples its own set in one pass of the same code,
the per-lane differences (the set's slices, the half vector and change
of variables of reflection, refraction or the z-flipped direction) being
selects. A packet of lanes on different sides and lobes -- most of them
at a glass surface, where sampling picks the lobe per lane by a random
number -- costs one set's look-ups instead of those of every set it
reaches. The VNDF and luminance are read through mitsuba_warp.SliceWarp,
which takes the slice and the point per lane: a reflected lane reads the
two slices about wi's elevation at one point, a refracted lane (which
reads two elevations, at the pair turned with wi to each:
TracedTables.refract_eval_pdf; a lane of the z-flipped direction's warp
likewise, mitsuba_lobes.flipped_eval_pdf) one slice at each elevation's
own point,
so that either is one look-up of two slices; sampling reads the picked
elevation's slice alone. For files whose four sets share their grids and
have one incident azimuth (what the writer makes); the others use
mitsuba_lobes.TracedLobes, set by set, over Mitsuba's warps.

The same arithmetic as TracedLobes and the C reader (tables_lobes.c,
tables_refract.c). The sets are stacked in the order ORDER (of SETS in
mitsuba_lobes).
"""

import numpy as np

import drjit as dr
import mitsuba as mi

from .mitsuba_tables import TracedTables, _elevation, _flip, _fresnel_eta, _fresnel_floor, \
    _fresnel_floor_at, _ndf_point, _normal_area, _normal_at, _phi_to_u, _refraction_half, \
    _refraction_jacobian, _theta_to_u, _turn
from .mitsuba_warp import SliceWarp
from .mitsuba_lobes import transmittance_at, transmittance_eta, turn_rate
from .tensor_file import TensorFileError


def _square(m, phi_i):
    """The point of the normal m in the VNDF's square, its azimuth about
    wi's phi_i (as TracedTables._at_normal places it)."""
    u_phi = _phi_to_u(dr.atan2(m.y, m.x) - phi_i)
    return mi.Point2f(_theta_to_u(_elevation(m)), u_phi - dr.floor(u_phi))


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
        # The VNDF and luminance, read and sampled slice by slice at a
        # point each (the table keeps D, sigma and the values).
        self.vndf = SliceWarp(np.asarray(stacked["vndf"], dtype=np.float32)[0])
        self.lum = SliceWarp(np.asarray(stacked["luminance"], dtype=np.float32)[0])
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
        # Their fresnel_floor k (top, bottom): values over (F + q) / (1 + q),
        # q = k D(0) / D(m) (_fresnel_floor_at).
        self.fresnel_floor = [_fresnel_floor(fields, p, transmit, e, name)
                              for (p, _, transmit), e in
                              zip([x for x in sets if not x[2]], self.fresnel_eta)]
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
        """The lane's set as stacked: (its index in ORDER, its slice and
        weights over the stacked elevations)."""
        def pick(values):
            v = [values[ORDER.index(k)] for k in range(4)]   # by SETS index
            return dr.select(bottom, dr.select(transmit, v[3], v[1]),
                             dr.select(transmit, v[2], v[0]))
        k = pick([float(k) for k in range(4)])
        j, w0, w1 = weights
        j = (mi.UInt32(k) if self.jit else int(k)) * self.n_ti + j
        return k, (j, w0, w1)

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

    def _wo_turns(self, w, bottom, flipped, elevations):
        """The turns of wo to each of wi's two elevations (cosine, sine):
        wi's own, or for a lane of the z-flipped direction's warp wi's at
        its side's turn_rate (mitsuba_lobes.flipped_eval_pdf)."""
        (_, _, c0, s0, p0, _), (_, _, c1, s1, p1, _) = elevations
        if self.eta == 1.0:
            return (c0, s0), (c1, s1)
        theta = _elevation(w)
        rate = dr.select(bottom, turn_rate(theta, 1.0 / self.eta), turn_rate(theta, self.eta))
        s0r, c0r = dr.sincos(rate * (p0 - theta))
        s1r, c1r = dr.sincos(rate * (p1 - theta))
        return ((dr.select(flipped, c0r, c0), dr.select(flipped, s0r, s0)),
                (dr.select(flipped, c1r, c1), dr.select(flipped, s1r, s1)))

    def _fresnel(self, w, m, bottom, reflected):
        """The factor of a reflected lane's value: the Fresnel reflectance
        at m where its side's set is stored over it (with its floor k:
        _fresnel_floor_at, D that set's stacked ndf), else 1."""
        top_e, bottom_e = self.fresnel_eta
        if top_e <= 0.0 and bottom_e <= 0.0:
            return 1.0
        top_k, bottom_k = self.fresnel_floor
        e = dr.select(bottom, bottom_e, top_e)
        k = dr.select(bottom, bottom_k, top_k)
        stored = reflected & (e > 0)
        if top_k <= 0.0 and bottom_k <= 0.0:
            d_pole = d_m = 1.0
        else:
            # The side's reflected set in the stack (ORDER: by SETS index).
            j = dr.select(bottom, float(ORDER.index(1)), float(ORDER.index(0)))
            j = mi.UInt32(j) if self.jit else int(j)
            d_pole = self.table.ndf.eval(mi.Point2f(0.0, 0.5), j, stored)
            d_m = self.table.ndf.eval(_ndf_point(m), j, stored)
        return dr.select(stored, _fresnel_floor_at(w, m, dr.select(e > 0, e, 1.5), k, d_pole,
                                                   d_m), 1.0)

    def _transmittance(self, w, o, m, bottom, refract):
        """The factor of a refracted lane's value: transmittance_at where
        its side's set is stored over it, else 1."""
        top_e, bottom_e = self.transmittance_eta
        if top_e <= 0.0 and bottom_e <= 0.0:
            return 1.0
        e = dr.select(bottom, bottom_e, top_e)
        stored = refract & (e > 0)
        return dr.select(stored, transmittance_at(w, o, m, dr.select(e > 0, e, 1.5)), 1.0)

    def _slice_at(self, wi, phi_i, k, wo, eta, flipped, param, stack, active):
        """A transmitted pair at one of wi's elevations (param), read from
        its one slice k (TracedTables._stored_at without the neighbour's
        weight 0): the stored values (a z-flipped lane's times D / (4 sigma)
        at the pair, mitsuba_lobes._flipped_at), the density per solid
        angle of wo, and whether the pair is one of the lobe."""
        m_t, ok_t = _refraction_half(wi, wo, eta)
        m_f = dr.normalize(wi + _flip(wo))
        ok_f = (wi.z > 0) & (wo.z < 0)
        m = dr.select(flipped, m_f, m_t)
        active = active & dr.select(flipped, ok_f, ok_t)
        u = _square(m, phi_i)
        cell = self.vndf.cell(u)
        sample, vndf_pdf = self.vndf.invert(self.vndf.read(k, cell, active), cell)
        value = self.table.rgb_slice(sample, k, active)
        if self.table.jacobian:
            u_wi = mi.Point2f(_theta_to_u(param), _phi_to_u(phi_i))
            jac = self.table._jacobian_scale(u, u_wi, active & flipped, stack)
            value = [dr.select(flipped, v * jac, v) for v in value]
        lum_cell = self.lum.cell(sample)
        lum = self.lum.density(self.lum.read(k, lum_cell, active, cdf=False), lum_cell)
        density = vndf_pdf * lum / _normal_area(u.x, mi.Frame3f.sin_theta(m)) * \
            dr.select(flipped, 1.0 / (4.0 * dr.dot(wi, m)), _refraction_jacobian(wi, wo, m, eta))
        return value, dr.select(active & dr.isfinite(density), density, 0.0), active

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
        flipped = transmits & ~refracts if self.jit else (transmits and not refracts)
        # Reflection and the z-flipped direction: the reflection half vector.
        o2 = dr.select(flipped, _flip(o), o)
        m_r = dr.normalize(w + o2)
        ok_r = (w.z > 0) & (o2.z > 0)
        e_safe = dr.select(refracts, e, 1.0)
        m_t, ok_t = _refraction_half(w, o, e_safe)
        m = dr.select(refract, m_t, m_r)
        active = active & dr.select(refract, ok_t, ok_r)
        # A transmitted lane reads its two elevations at the pair turned to
        # each (TracedTables.refract_eval_pdf, mitsuba_lobes.flipped_eval_pdf),
        # one slice each; a reflected lane reads the two slices around wi's
        # elevation at one point. Either way slice j at one point and slice
        # j + 1 at another: one look-up of two slices for every lane
        # (mitsuba_warp).
        elevations, axis, phi_w = self.table._elevations(w, stack)
        (w0, wi0, c0, s0, p0, _), (w1, wi1, c1, s1, p1, _) = elevations
        (c0o, s0o), (c1o, s1o) = self._wo_turns(w, bottom, flipped, elevations)
        o0, o1 = _turn(axis, c0o, s0o, o), _turn(axis, c1o, s1o, o)
        m0, ok0 = _refraction_half(wi0, o0, e_safe)
        m1, ok1 = _refraction_half(wi1, o1, e_safe)
        m0 = dr.select(flipped, dr.normalize(wi0 + _flip(o0)), m0)
        m1 = dr.select(flipped, dr.normalize(wi1 + _flip(o1)), m1)
        ok0 = dr.select(flipped, (wi0.z > 0) & (o0.z < 0), ok0) & (w0 > 0)
        ok1 = dr.select(flipped, (wi1.z > 0) & (o1.z < 0), ok1) & (w1 > 0)
        j, a0, a1 = stack[1]
        m_a, m_b = dr.select(transmits, m0, m), dr.select(transmits, m1, m)
        read_a = active & dr.select(transmits, ok0, True)
        read_b = active & dr.select(transmits, ok1, a1 > 0)
        # (A reflected lane's mixture; a transmitted lane's slice j alone.)
        mix_a = (dr.select(transmits, 1.0, a0), dr.select(transmits, 0.0, a1))
        u_a, u_b = _square(m_a, phi_w), _square(m_b, phi_w)
        cell_a, cell_b = self.vndf.cell(u_a), self.vndf.cell(u_b)
        va = self.vndf.read(j, cell_a, read_a)
        vb = self.vndf.read(j + 1, cell_b, read_b)
        sample_a, pdf_a = self.vndf.invert(self.vndf.mix(va, vb, *mix_a), cell_a)
        sample_b, pdf_b = self.vndf.invert(vb, cell_b)
        sample_b = dr.select(transmits, sample_b, sample_a)
        value = pdf = None
        if want_value:
            ra = self.table.rgb_slice(sample_a, j, read_a)
            rb = self.table.rgb_slice(sample_b, j + 1, read_b)
            # D / (4 sigma): at the pair itself (reflected and refracted
            # lanes, after the blend), or at each elevation's own pair (a
            # z-flipped lane: ja, jb).
            ja = jb = jp = 1.0
            if self.table.jacobian:
                u_m = dr.select(refract, _square(m, phi_w), u_a)
                u_wi = mi.Point2f(_theta_to_u(_elevation(w)), _phi_to_u(phi_w))
                u_wi0 = mi.Point2f(_theta_to_u(p0), _phi_to_u(phi_w))
                u_wi1 = mi.Point2f(_theta_to_u(p1), _phi_to_u(phi_w))
                jac = self.table._jacobian_scale(u_m, dr.select(flipped, u_wi0, u_wi), active,
                                                 stack)
                jac_b = self.table._jacobian_scale(u_b, u_wi1, active & flipped, stack)
                ja, jb = dr.select(flipped, jac, 1.0), dr.select(flipped, jac_b, 1.0)
                jp = dr.select(flipped, 1.0, jac)
            value = [dr.select(transmits,
                               dr.select(ok0, x * w0 * ja, 0.0) + dr.select(ok1, y * w1 * jb, 0.0),
                               dr.fma(x, a0, y * a1)) * jp for x, y in zip(ra, rb)]
            scale = dr.select(transmits, self._transport(wi, radiance) *
                              self._transmittance(w, o, m, bottom, refract),
                              self._fresnel(w, m, bottom, ~transmits if self.jit
                                            else not transmits))
            value = [dr.select(active, dr.maximum(v, 0.0) * scale, 0.0) for v in value]
            value = [dr.select(dr.isfinite(v) & (v > 0), v, 0.0) for v in value]
        if want_pdf:
            lum_cell_a, lum_cell_b = self.lum.cell(sample_a), self.lum.cell(sample_b)
            la = self.lum.read(j, lum_cell_a, read_a, cdf=False)
            lb = self.lum.read(j + 1, lum_cell_b, read_b, cdf=False)
            lum_a = self.lum.density(self.lum.mix(la, lb, *mix_a), lum_cell_a)
            lum_b = self.lum.density(lb, lum_cell_b)
            density_a = pdf_a * lum_a / _normal_area(u_a.x, mi.Frame3f.sin_theta(m_a))
            density_b = pdf_b * lum_b / _normal_area(u_b.x, mi.Frame3f.sin_theta(m_b))
            # (The refraction's d omega_m / d omega_o is the same at the
            # pair turned to either elevation: a turn keeps the dots.)
            lobe = dr.select(refract,
                             (dr.select(ok0, density_a * w0, 0.0) +
                              dr.select(ok1, density_b * w1, 0.0)) *
                             _refraction_jacobian(w, o, m, e_safe),
                             dr.select(flipped,
                                       dr.select(ok0, density_a * w0 / (4.0 * dr.dot(wi0, m0)),
                                                 0.0) +
                                       dr.select(ok1, density_b * w1 / (4.0 * dr.dot(wi1, m1)),
                                                 0.0),
                                       density_a / (4.0 * dr.dot(w, m))))
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
        flipped = transmitted & ~refracts if self.jit else (transmitted and not refracts)
        # A transmitted lane samples one of its two elevations, picked by v.x
        # with its weight and rescaled (TracedTables.refract_sample,
        # mitsuba_lobes.flipped_sample), in the one pair of warp look-ups
        # every lane makes, at wi turned to it.
        e_safe = dr.select(refracts, e, 1.0)
        elevations, axis, phi_w = self.table._elevations(w, stack)
        (w0, wi0, c0, s0, p0, _), (w1, wi1, c1, s1, p1, _) = elevations
        (c0o, s0o), (c1o, s1o) = self._wo_turns(w, bottom, flipped, elevations)
        second = transmitted & (v.x >= w0)
        u_el = dr.select(second, (v.x - w0) / dr.select(w1 > 0, w1, 1.0),
                         v.x / dr.select(w0 > 0, w0, 1.0))
        v_s = mi.Point2f(dr.select(transmitted, dr.clip(u_el, 0.0, 1.0), v.x), v.y)
        # The slices j, j + 1 mixed as wi's elevation weighs them; a
        # transmitted lane's picked one alone (the other is not read).
        j, a0, a1 = stack[1]
        b0 = dr.select(transmitted, dr.select(second, 0.0, 1.0), a0)
        b1 = dr.select(transmitted, dr.select(second, 1.0, 0.0), a1)
        w_k = dr.select(transmitted, dr.select(second, wi1, wi0), w)
        # (Mitsuba's `measured` takes the numbers as (y, x) into the
        # luminance warp, as TracedTables._sample_normal.)
        sample, lum_pdf = self.lum.sample(j, j + 1, b0, b1, mi.Point2f(v_s.y, v_s.x), active)
        u_m, vndf_pdf = self.vndf.sample(j, j + 1, b0, b1, sample, active)
        m, sin_theta = _normal_at(u_m, phi_w)
        density = vndf_pdf * lum_pdf / _normal_area(u_m.x, sin_theta)
        raw_j = self.table.rgb_slice(sample, j, active & (b0 > 0))
        raw_j1 = self.table.rgb_slice(sample, j + 1, active & (b1 > 0))
        raw = [dr.fma(x, b0, y * b1) for x, y in zip(raw_j, raw_j1)]
        c = dr.dot(w_k, m)
        # Reflected about m (reflection; the z-flipped direction then flips
        # and turns back).
        wo_r = dr.fma(m, 2.0 * c, -w_k)
        pdf_r = density / (4.0 * c)
        ok_r = wo_r.z > 0
        wo_f = _turn(axis, dr.select(second, c1o, c0o), -dr.select(second, s1o, s0o),
                     _flip(wo_r))
        ok_f = (c > 0) & ok_r & (wo_f.z < 0) & (density > 0)
        # Refracted through m at wi turned to the elevation, turned back.
        inv = 1.0 / e_safe
        k = 1.0 - inv * inv * (1.0 - c * c)
        wo_k = (inv * c - dr.safe_sqrt(k)) * m - inv * w_k
        wo_t = _turn(axis, dr.select(second, c1, c0), -dr.select(second, s1, s0), wo_k)
        m_t, ok_m = _refraction_half(w, wo_t, e_safe)
        ok_t = (c > 0) & (k > 0) & (wo_k.z < 0) & (wo_t.z < 0) & ok_m & (density > 0)
        # The other elevation at the pair turned to it.
        wo_x = dr.select(flipped, wo_f, wo_t)
        ok_x = dr.select(flipped, ok_f, ok_t)
        w_o = dr.select(second, w0, w1)
        o_o = _turn(axis, dr.select(second, c0o, c1o), dr.select(second, s0o, s1o), wo_x)
        raw_o, density_o, ok_o = self._slice_at(
            dr.select(second, wi0, wi1), phi_w, dr.select(second, j, j + 1), o_o, e_safe,
            flipped, dr.select(second, p0, p1), stack, active & transmitted & ok_x & (w_o > 0))
        w_s = dr.select(second, w1, w0)
        pdf_t = w_s * density * dr.select(flipped, 1.0 / (4.0 * c),
                                          _refraction_jacobian(w, wo_t, m_t, e_safe)) + \
            w_o * density_o
        # D / (4 sigma) at the sampled normal (a reflected lane; a z-flipped
        # lane's at its elevation's wi, before the blend), or at a refracted
        # pair's own refraction half vector: one look-up for either.
        js = jp = 1.0
        if self.table.jacobian:
            u_j = dr.select(refract, _square(m_t, phi_w), u_m)
            u_wi = mi.Point2f(_theta_to_u(_elevation(w)), _phi_to_u(phi_w))
            u_wi_s = mi.Point2f(_theta_to_u(dr.select(second, p1, p0)), _phi_to_u(phi_w))
            jac = self.table._jacobian_scale(u_j, dr.select(flipped, u_wi_s, u_wi), active,
                                             stack)
            js, jp = dr.select(flipped, jac, 1.0), dr.select(flipped, 1.0, jac)
        value = [dr.select(transmitted, w_s * v_k * js + dr.select(ok_o, w_o * v_o, 0.0), v_k) *
                 jp for v_k, v_o in zip(raw, raw_o)]
        wo = dr.select(refract, wo_t, dr.select(flipped, wo_f, wo_r))
        pdf = dr.select(transmitted, pdf_t, pdf_r)
        ok = active & dr.select(refract, ok_t, dr.select(flipped, ok_f, ok_r)) & \
            dr.isfinite(pdf) & (pdf > 0)
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
