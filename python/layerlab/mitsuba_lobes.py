"""A transmissive table file (layerlab's extension of the `measured`
format, docs/formats.md "Extended table files": a table set per lobe
and side, reflect_top., reflect_bottom., transmit_top., transmit_bottom.)
evaluated and sampled in Dr.Jit operations, as the C reader does it
(src/reader/tables_lobes.c, tables_refract.c), for the Mitsuba plugin's
"tables" mode. Each set is a layerlab.mitsuba_tables.TracedTables over
its prefixed fields.

A direction pair goes to the set of its lobe -- reflection or
transmission, by the sides of the two directions -- and of the side of
the fixed direction wi (si.wi), in that set's own frame, where wi lies
above: a bottom set sees both directions with z negated. A transmitted
set with `warp_eta` > 0 is warped about the refraction half vector of
that relative index; with 0 (a stack of eta 1, a pane) it is a
reflection set of the z-flipped direction. A reflected set with
`fresnel_eta` holds its values over the Fresnel reflectance of its half
vector, a refracted set with `transmittance_eta` over the Fresnel
transmittance times the refraction's d omega_m / d omega_o at its
refraction half vector (transmittance_at); both are multiplied back.
A transmitted set is read between two incident elevations at the pair
turned with wi to each (TracedTables.refract_eval_pdf, refract_sample;
flipped_eval_pdf, flipped_sample for the z-flipped direction's warp,
which turns wo at turn_rate and takes D / (4 sigma) at each elevation's
own pair).
Sampling picks the reflected
or the transmitted lobe of wi's side in proportion to their stored
luminance albedos (`<set>.albedo`, per incident elevation, interpolated
linearly) by sample2.x, rescaled into the chosen share; the pdf is the
share times the lobe's.

Values are the stored f (importance transport) times |cos theta_o|; in
radiance transport a transmitted value takes the eta^2 of the interface it
crosses (1 / eta^2 going down from above, eta^2 going up), as the C
reader's ll_bsdf_eval_dir does.

Set by set (TracedLobes), in the JIT variants each of the four sets is
traced once under its lane mask (a packet's lanes may be on different
sides and lobes): a call costs the arithmetic of the sets it could reach,
not one. The files the writer makes are read stacked instead
(traced_lobes, mitsuba_lobes_stacked): one set's look-ups per lane.
"""

import numpy as np

import drjit as dr
import mitsuba as mi

from .mitsuba_tables import TracedTables, blend_elevation, _elevation, _flip, _fresnel_at, \
    _fresnel_eta, _fresnel_floor, _fresnel_floor_at, _masked_call, _ndf_point, _phi_to_u, \
    _refraction_half, _refraction_jacobian, _theta_to_u, _turn
from .tensor_file import TensorFileError

# (prefix, side of wi: bottom, lobe: transmit) in the C reader's order.
SETS = (("reflect_top.", False, False), ("reflect_bottom.", True, False),
        ("transmit_top.", False, True), ("transmit_bottom.", True, True))


def layout_names(fields):
    """The names in the file's "layerlab_layout" (separated by spaces or
    commas), or None for a plain file."""
    if "layerlab_layout" not in fields:
        return None
    text = bytes(np.asarray(fields["layerlab_layout"], dtype=np.uint8)).decode("utf-8",
                                                                                "replace")
    return [n for n in text.replace(",", " ").split(" ") if n]


def transmittance_eta(fields, prefix, warp_eta, name):
    """A refracted set's "transmittance_eta" (> 0: its values are stored
    over transmittance_at of that relative index, its warp_eta), or 0 where
    the set has none (as the C reader's checks)."""
    key = prefix + "transmittance_eta"
    if key not in fields:
        return 0.0
    value = np.asarray(fields[key], dtype=np.float32).ravel()
    if value.shape != (1,) or value[0] == 0.0 or float(value[0]) != warp_eta:
        raise TensorFileError("%s: field `%s` is not one value equal to the set's warp_eta "
                              "(a refraction's relative index)" % (name, key))
    return float(value[0])


def transmittance_at(wi, wo, m, eta):
    """The factor a refracted set stored over its refraction's
    transmittance is multiplied by: 1 - F(wi.m) times d omega_m / d omega_o
    (wi above, wo below, m their refraction half vector), as the C
    reader's ll_tables_transmittance_pair."""
    return (1.0 - _fresnel_at(wi, m, eta)) * _refraction_jacobian(wi, wo, m, eta)


# The C reader's MAX_TURN_RATE (tables_refract.c).
MAX_TURN_RATE = 1.5


def turn_rate(theta, side_eta):
    """How fast a set of the z-flipped direction's warp turns wo with wi
    (at elevation theta) between two elevations, as the C reader's
    turn_rate (tables_refract.c): the refracted direction's d theta_t /
    d theta_i = cos theta / (eta' cos theta_t), at most MAX_TURN_RATE, and
    1 where nothing refracts or side_eta (eta', the far side over wi's) is
    1."""
    if side_eta <= 0.0 or side_eta == 1.0:
        return 1.0
    st = dr.sin(theta) / side_eta
    d = side_eta * dr.safe_sqrt(1.0 - st * st)
    r = dr.cos(theta) / dr.select(d > 0, d, 1.0)
    r = dr.minimum(r, MAX_TURN_RATE)
    return dr.select((st < 1.0) & (d > 0), r, 1.0)


def turned_wo(axis, rate, theta, param, c, s, wo):
    """wo turned with wi from its elevation theta to the file's elevation
    param (wi's own turn: cosine c, sine s) at rate (turn_rate)."""
    if isinstance(rate, float) and rate == 1.0:
        return _turn(axis, c, s, wo)
    s_o, c_o = dr.sincos(rate * (param - theta))
    return _turn(axis, c_o, s_o, wo)


def _flipped_at(t, wi, phi_i, param, slices, wo, active, want_value, want_pdf):
    """At one of the file's elevations (wi's own, param the warps' parameter
    there, slices the weights that read it alone): a z-flipped set's values
    at the pair, times D / (4 sigma) there, the elevation's density per
    solid angle of wo, and whether the pair is one of the lobe (wo below)."""
    active = active & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) < 0)
    m = dr.normalize(wi + _flip(wo))
    u_m, value, density = t.read_at_normal(m, phi_i, param, slices, active, want_value,
                                           want_pdf)
    if want_value and t.jacobian:
        u_wi = mi.Point2f(_theta_to_u(param), _phi_to_u(phi_i))
        scale = t._jacobian_scale(u_m, u_wi, active)
        value = [v * scale for v in value]
    if want_pdf:
        density = density / (4.0 * dr.dot(wi, m))
        density = dr.select(active & dr.isfinite(density), density, 0.0)
    return value, density, active


def flipped_eval_pdf(t, wi, wo, side_eta, active, want_value=True, want_pdf=True):
    """eval_pdf of a transmitted set of the z-flipped direction's warp (wi
    above, wo below), as the C reader's tables_refract.c reads it: between
    two incident elevations the pair turned to each (wo at turn_rate), each
    elevation's values times D / (4 sigma) at its own pair, blended with
    the elevations' weights; the pdf the mixture of their densities."""
    active = active & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) < 0)
    value = [0.0, 0.0, 0.0] if want_value else None
    pdf = 0.0 if want_pdf else None
    elevations, axis, phi_i = t._elevations(wi)
    theta = _elevation(wi)
    rate = turn_rate(theta, side_eta)
    for weight, wi_k, c, s, param, slices in elevations:
        o = turned_wo(axis, rate, theta, param, c, s, wo)
        reading = _flipped_at(t, wi_k, phi_i, param, slices, o, active & (weight > 0),
                              want_value, want_pdf)
        value, pdf = blend_elevation(value, pdf, reading, weight)
    if want_value:
        value = [dr.select(active, dr.maximum(v, 0.0), 0.0) for v in value]
    if want_pdf:
        pdf = dr.select(active & dr.isfinite(pdf) & (pdf > 0), pdf, 0.0)
    return value, pdf


def flipped_sample(t, wi, sample2, side_eta, active):
    """sample of a transmitted set of the z-flipped direction's warp (as
    flipped_eval_pdf): one of wi's two elevations picked by sample2.x with
    its weight (rescaled and passed on), wi turned to it reflected about
    the normal its warps give, z negated and turned back at turn_rate; the
    pdf and value are flipped_eval_pdf's there. (wo, pdf, f cos theta_o as
    a list of 3 Float, ok)."""
    active = active & (mi.Frame3f.cos_theta(wi) > 0)
    theta = _elevation(wi)
    rate = turn_rate(theta, side_eta)
    axis, (wi_k, c_k, s_k, param), m, drawn = t.sample_turned_normal(wi, sample2, active)
    c = dr.dot(wi_k, m)
    r = dr.fma(m, 2.0 * c, -wi_k)
    o = _flip(r)
    if isinstance(rate, float) and rate == 1.0:
        wo = _turn(axis, c_k, -s_k, o)
    else:
        s_o, c_o = dr.sincos(rate * (param - theta))
        wo = _turn(axis, c_o, -s_o, o)
    ok = active & (c > 0) & (r.z > 0) & (wo.z < 0) & drawn
    value, pdf = flipped_eval_pdf(t, wi, wo, side_eta, ok, True, True)
    ok = ok & (pdf > 0)
    value = [dr.select(ok, v, 0.0) for v in value]
    return wo, dr.select(ok, pdf, 0.0), value, ok


def _scalar_false(mask):
    """A mask of the scalar variants that is plainly False (its set's code
    is skipped there; the JIT variants trace every set under its mask)."""
    return isinstance(mask, bool) and not mask


def traced_lobes(fields, name=""):
    """The lobes of a transmissive table file: its four sets stacked into
    one table (mitsuba_lobes_stacked.StackedLobes, one pass per call) when
    the file has all four with the same grids and one incident azimuth
    (what the writer makes), else set by set (TracedLobes)."""
    from .mitsuba_lobes_stacked import ORDER, StackedLobes
    from .mitsuba_tables import stack_sets
    names = layout_names(fields) or []
    prefixes = [SETS[k][0] for k in ORDER]
    if all(p[:-1] in names for p in prefixes) and "eta" in fields and \
            np.asarray(fields.get("phi_i", [])).size == 1:
        stacked = stack_sets(fields, prefixes)
        if stacked is not None:
            return StackedLobes(fields, stacked, SETS, name)
    return TracedLobes(fields, name)


def _set_fresnel(t, w, o, active):
    """The factor of the reflected set t stored over F (t.fresnel_eta > 0),
    with its floor: _fresnel_floor_at at the half vector of (w, o)."""
    m = dr.normalize(w + o)
    if t.fresnel_floor <= 0.0:
        return _fresnel_floor_at(w, m, t.fresnel_eta, 0.0, 1.0, 1.0)
    return _fresnel_floor_at(w, m, t.fresnel_eta, t.fresnel_floor,
                             t.ndf.eval(mi.Point2f(0.0, 0.5), active=active),
                             t.ndf.eval(_ndf_point(m), active=active))


class TracedLobes:
    """The lobe sets of a transmissive table file, and eval / pdf / sample
    in Mitsuba's convention on both sides."""

    def __init__(self, fields, name=""):
        names = layout_names(fields)
        if names is None or "textured" in names:
            raise TensorFileError("%s: not a transmissive table file (its layerlab_layout "
                                  "names no lobe sets)" % name)
        if "eta" not in fields:
            raise TensorFileError("%s: no field `eta` (an extended table file has it)" % name)
        self.eta = float(np.asarray(fields["eta"], dtype=np.float32).ravel()[0])
        self.jit = dr.is_jit_v(mi.Float)
        self.sets = []
        for prefix, bottom, transmit in SETS:
            if prefix[:-1] not in names:
                self.sets.append(None)
                continue
            t = TracedTables(fields, name, prefix)
            albedo = np.asarray(fields[prefix + "albedo"], dtype=np.float32)
            if albedo.shape != (len(t.theta_host),):
                raise TensorFileError("%s: field `%salbedo` of shape %s" % (name, prefix,
                                                                          albedo.shape))
            t.albedo_host = albedo.astype(np.float64)
            if self.jit:
                t.albedo = mi.Float(albedo)
            t.warp_eta = 0.0
            # (The far side's index over wi's: how a z-flipped set turns wo.)
            t.side_eta = (1.0 / self.eta if bottom else self.eta) if transmit else 0.0
            if transmit:
                t.warp_eta = float(np.asarray(fields[prefix + "warp_eta"],
                                              dtype=np.float32).ravel()[0])
            t.fresnel_eta = _fresnel_eta(fields, prefix, transmit, name)
            t.fresnel_floor = _fresnel_floor(fields, prefix, transmit, t.fresnel_eta, name)
            t.transmittance_eta = transmittance_eta(fields, prefix, t.warp_eta, name) \
                if transmit and t.warp_eta > 0.0 else 0.0
            self.sets.append(t)
        self.grid_text = "; ".join("%s %s" % (p[:-1], t.describe())
                                   for (p, _, _), t in zip(SETS, self.sets) if t is not None)

    def describe(self):
        return self.grid_text

    # ------------------------------------------------------------ helpers

    def _albedo(self, t, theta):
        """The set's stored albedo at the incident elevation theta,
        interpolated as its slices are (0 without the set)."""
        if t is None:
            return 0.0
        j, w0, w1 = t._weights(t.theta_host, t.theta if self.jit else None, theta)
        if self.jit:
            a0 = dr.gather(mi.Float, t.albedo, j)
            a1 = dr.gather(mi.Float, t.albedo, j + 1) if len(t.theta_host) > 1 else a0
        else:
            a0 = t.albedo_host[j]
            a1 = t.albedo_host[j + 1] if len(t.theta_host) > 1 else a0
        return dr.fma(a0, w0, a1 * w1)

    def _reflect_share(self, w, bottom):
        """The reflected lobe's share in sampling on wi's side (w: wi in
        that side's frame)."""
        theta = dr.acos(dr.minimum(w.z, 1.0))
        r, t = (self.sets[1], self.sets[3]) if bottom else (self.sets[0], self.sets[2])
        a, b = self._albedo(r, theta), self._albedo(t, theta)
        none = (a <= 0) & (b <= 0)
        return dr.select(none, 1.0 if r is not None else 0.0, a / dr.select(none, 1.0, a + b))

    def _transport(self, wi, radiance):
        """The factor of a transmitted value: radiance's eta^2 of the
        interface crossed."""
        if not radiance:
            return 1.0
        inv = 1.0 / (self.eta * self.eta)
        return dr.select(mi.Frame3f.cos_theta(wi) > 0, inv, self.eta * self.eta)

    def _branch(self, mask, fn, args, zeros):
        return _masked_call(self.jit, mask, fn, args, zeros)

    def _set_eval_pdf(self, t, transmit, w, o, mask, want_value, want_pdf):
        if not transmit:
            v, p = t.eval_pdf(w, o, mask, want_value, want_pdf)
            if want_value and t.fresnel_eta > 0.0:
                k = _set_fresnel(t, w, o, mask)
                v = [x * k for x in v]
            return v, p
        if t.warp_eta > 0.0:
            v, p = t.refract_eval_pdf(w, o, t.warp_eta, mask, want_value, want_pdf)
            if want_value and t.transmittance_eta > 0.0:
                m, _ = _refraction_half(w, o, t.warp_eta)
                k = transmittance_at(w, o, m, t.warp_eta)
                v = [x * k for x in v]
            return v, p
        return flipped_eval_pdf(t, w, o, t.side_eta, mask, want_value, want_pdf)

    # ------------------------------------------------------ the three calls

    def eval_pdf(self, wi, wo, active, radiance, reflect_on=True, transmit_on=True,
                 want_value=True, want_pdf=True):
        """(f |cos theta_o| as a list of 3 Float, or None; the pdf per solid
        angle of wo, or None); the lobes not on are zero."""
        cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
        bottom, top = cos_i < 0, cos_i > 0
        w = mi.Vector3f(wi.x, wi.y, dr.abs(cos_i))
        o = mi.Vector3f(wo.x, wo.y, dr.select(bottom, -cos_o, cos_o))
        transmits, reflects = cos_i * cos_o < 0, cos_i * cos_o > 0
        active = active & (cos_i != 0) & (cos_o != 0)
        value = [0.0, 0.0, 0.0] if want_value else None
        pdf = 0.0 if want_pdf else None
        shares = {}
        for (prefix, on_bottom, transmit), t in zip(SETS, self.sets):
            if t is None or not (transmit_on if transmit else reflect_on):
                continue
            mask = active & (bottom if on_bottom else top) & \
                (transmits if transmit else reflects)
            if _scalar_false(mask):
                continue

            def run(w, o, mask, t=t, transmit=transmit):
                v, p = self._set_eval_pdf(t, transmit, w, o, mask, want_value, want_pdf)
                return (tuple(v) if want_value else (mi.Float(0.0),) * 3,
                        p if want_pdf else mi.Float(0.0))

            v, p = self._branch(mask, run, (w, o, mask),
                                lambda: ((mi.Float(0.0),) * 3, mi.Float(0.0)))
            if want_value:
                value = [dr.select(mask, v[c], value[c]) for c in range(3)]
            if want_pdf:
                if on_bottom not in shares:
                    shares[on_bottom] = self._reflect_share(w, on_bottom)
                share = shares[on_bottom]
                p = p * (1.0 - share if transmit else share)
                pdf = dr.select(mask, p, pdf)
        if want_value:
            scale = dr.select(transmits, self._transport(wi, radiance), 1.0)
            value = [dr.select(active, v * scale, 0.0) for v in value]
            value = [dr.select(dr.isfinite(v) & (v > 0), v, 0.0) for v in value]
        if want_pdf:
            pdf = dr.select(active, pdf, 0.0)
        return value, pdf

    def sample(self, wi, sample2, active, radiance, reflect_on=True, transmit_on=True):
        """(wo, pdf, f |cos theta_o| / pdf as a list of 3 Float, ok, whether
        wo is transmitted) for the random numbers sample2 (sample2.x picks
        the lobe and is passed on rescaled, as the C reader's u[0])."""
        cos_i = mi.Frame3f.cos_theta(wi)
        bottom, top = cos_i < 0, cos_i > 0
        active = active & (cos_i != 0)
        w = mi.Vector3f(wi.x, wi.y, dr.abs(cos_i))
        share = dr.select(bottom, self._reflect_share(w, True), self._reflect_share(w, False))
        u0 = sample2.x
        reflected = u0 < share
        transmitted = u0 >= share
        # (A share of 0 or 1 leaves the other branch unpicked: its
        # division is kept finite for the scalar variants.)
        v0 = dr.select(transmitted, (u0 - share) / dr.select(share < 1.0, 1.0 - share, 1.0),
                       u0 / dr.select(share > 0.0, share, 1.0))
        v = mi.Point2f(dr.clip(v0, 0.0, 1.0), sample2.y)
        wo = mi.Vector3f(0.0, 0.0, 1.0)
        pdf, value, ok = 0.0, [0.0, 0.0, 0.0], active & False
        for (prefix, on_bottom, transmit), t in zip(SETS, self.sets):
            if t is None or not (transmit_on if transmit else reflect_on):
                continue
            mask = active & (bottom if on_bottom else top) & \
                (transmitted if transmit else reflected)
            if _scalar_false(mask):
                continue

            def run(w, v, mask, t=t, transmit=transmit):
                if not transmit:
                    o, p, val, found = t.reflect_sample(w, v, mask)
                    if t.fresnel_eta > 0.0:
                        k = _set_fresnel(t, w, o, mask)
                        val = [x * k for x in val]
                elif t.warp_eta > 0.0:
                    o, p, val, found = t.refract_sample(w, v, t.warp_eta, mask)
                    if t.transmittance_eta > 0.0:
                        m, _ = _refraction_half(w, o, t.warp_eta)
                        k = transmittance_at(w, o, m, t.warp_eta)
                        val = [x * k for x in val]
                else:
                    o, p, val, found = flipped_sample(t, w, v, t.side_eta, mask)
                return mi.Vector3f(o), mi.Float(p), tuple(val), mi.Bool(found)

            o, p, val, found = self._branch(
                mask, run, (w, v, mask),
                lambda: (mi.Vector3f(0.0, 0.0, 1.0), mi.Float(0.0), (mi.Float(0.0),) * 3,
                         mi.Bool(False)))
            wo = dr.select(mask, o, wo)
            pdf = dr.select(mask, p, pdf)
            value = [dr.select(mask, val[c], value[c]) for c in range(3)]
            ok = dr.select(mask, found, ok)
        pdf = pdf * dr.select(transmitted, 1.0 - share, share)
        wo = dr.select(bottom, _flip(wo), wo)
        ok = ok & (pdf > 0)
        scale = dr.select(transmitted, self._transport(wi, radiance), 1.0)
        weight = [v * scale / dr.select(ok, pdf, 1.0) for v in value]
        weight = [dr.select(ok & dr.isfinite(x) & (x > 0), x, 0.0) for x in weight]
        return wo, dr.select(ok, pdf, 0.0), weight, ok, transmitted
