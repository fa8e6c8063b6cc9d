"""Warped tables (the `measured` format of Dupuy & Jakob 2018,
docs/formats.md) evaluated and sampled in Dr.Jit operations, as
Mitsuba 3's own `measured` BSDF does, so that in Mitsuba's default
(symbolic, megakernel) mode the calls trace into the rendering kernel; in
the scalar variants the same code runs on scalars.

What is read: the `rgb` field of an RGB table file, opened first by the C
reader (ll_bsdf_open validates every field, shape and value; the fields are
then read with numpy, layerlab.tensor_file). Isotropic files only (one or two
incident azimuths), as the C reader. A spectral file (`spectra`,
`wavelengths`) is not read here: the C reader turns its spectra into linear
sRGB (docs/formats.md, "Spectral files"), which this module would
have to repeat; the plugin renders such a file through the C reader.

The 2D warps are those that Mitsuba's `measured` plugin builds from the same
fields (the Marginal2D<Float, Dim, true> of mi.MarginalContinuous2D0/1/2): the
VNDF and luminance warps normalised, the NDF and sigma tables evaluated as
stored. Where the file has one incident azimuth the VNDF and luminance warps
take the elevation as their only parameter (Mitsuba's take the azimuth too and
give it the weights 1 and 0 over one slice, the same values with twice the
memory reads), and are mitsuba_warp.ParamWarp: Mitsuba's interface and points
to float32 rounding, read with guided searches and both slices in one look-up
(half a sample's time); with two azimuths they are Mitsuba's own
(mi.MarginalContinuous2D2). A stacked table (stack_sets) is read by its own warps
instead (mitsuba_warp.SliceWarp, D and sigma per set as _StackedGrid). The values (`rgb`) are interpolated here, all three channels
of a node in one 4-float read (the layout below), with the same arithmetic
as Mitsuba's interpolation per channel: per corner of the sample's cell
fma(v0, w0, v1 w1) over the two incident elevations, then bilinear in the
cell (which is what Mitsuba's three separate look-ups over channel, azimuth
and elevation reduce to at a channel's own index).

Conventions (Mitsuba's, which the C reader's renderer convention follows):
wi = si.wi is the direction held fixed (the viewer on a camera path), wo the
one evaluated or sampled; both in the shading frame; one-sided: zero unless
both are above the surface.
"""

import ctypes
import hashlib
import math
import os
import tempfile

import numpy as np

from . import _native
from ._native import lib
from .mitsuba_warp import ParamWarp
from .tensor_file import TensorFileError, read_tensor_file

import drjit as dr
import mitsuba as mi

PI = math.pi
# Mitsuba's square coordinates of a direction: u_theta = sqrt(theta / (pi/2)),
# u_phi = (phi + pi) / (2 pi).
TWO_OVER_PI = 2.0 / PI
INV_TWO_PI = 1.0 / (2.0 * PI)
TWO_PI_SQUARED = 2.0 * PI * PI

def _elevation(d):
    """The elevation of a unit vector, 2 asin(|d - n| / 2): stable at the
    pole (Mitsuba's `measured` computes it so)."""
    dist = dr.sqrt(dr.square(d.x) + dr.square(d.y) + dr.square(d.z - 1.0))
    return 2.0 * dr.safe_asin(0.5 * dist)


def _theta_to_u(theta):
    return dr.sqrt(theta * TWO_OVER_PI)


def _phi_to_u(phi):
    return (phi + PI) * INV_TWO_PI


def stack_sets(fields, prefixes):
    """The fields of the sets named by prefixes (at most four, each with
    the same grids) as the fields of one table of their slices one after
    the other, each set's slices with its incident elevations: a lane
    reads its own set's slices by index
    (mitsuba_warp.SliceWarp for the VNDF and luminance, the values by
    gather; two neighbouring slices of one set, never of two); D and sigma
    become one grid per kind, [set, y, x]. None if the sets' grids
    differ."""
    theta = np.asarray(fields["theta_i"], dtype=np.float32)
    if len(prefixes) > 4:
        return None
    shapes = set()
    for p in prefixes:
        shapes.add(tuple(tuple(np.shape(fields[p + k])) for k in
                         ("ndf", "sigma", "vndf", "luminance", "rgb")))
    if len(shapes) != 1:
        return None
    out = {"theta_i": np.concatenate([theta] * len(prefixes)),
           "phi_i": fields["phi_i"], "jacobian": fields["jacobian"]}
    for key in ("vndf", "luminance", "rgb"):
        out[key] = np.concatenate([np.asarray(fields[p + key], dtype=np.float32)
                                   for p in prefixes], axis=1)
    for key in ("ndf", "sigma"):
        out[key] = np.stack([np.asarray(fields[p + key], dtype=np.float32) for p in prefixes])
    return out


class _StackedGrid:
    """Grids of the same size, one per stacked set ([sets, y, x]), read as
    Mitsuba's Marginal2D::eval reads a grid evaluated as stored: bilinear
    over the nodes spread evenly over [0, 1]^2, the cell clamped to the
    last."""

    def __init__(self, grids):
        grids = np.ascontiguousarray(grids, dtype=np.float32)
        self.ny, self.nx = int(grids.shape[1]), int(grids.shape[2])
        self.jit = dr.is_jit_v(mi.Float)
        if self.jit:
            self.data = mi.Float(grids.ravel())
        else:
            self.host = grids.reshape(grids.shape[0], -1)

    def eval(self, pos, k, active):
        """The value at pos of grid k (a whole number per lane)."""
        nx, ny = self.nx, self.ny
        px, py = pos.x * float(nx - 1), pos.y * float(ny - 1)
        if self.jit:
            UInt32, Int32 = mi.UInt32, mi.Int32
            ox = dr.minimum(UInt32(Int32(px)), nx - 2)
            oy = dr.minimum(UInt32(Int32(py)), ny - 2)
            base = UInt32(k) * (nx * ny) + oy * nx + ox

            def at(offset):
                return dr.gather(mi.Float, self.data, base + offset, active)
        else:
            ox = min(max(int(px), 0), nx - 2)
            oy = min(max(int(py), 0), ny - 2)
            row = self.host[int(k)]
            base = oy * nx + ox

            def at(offset):
                return float(row[base + offset])
        wx1, wy1 = px - ox, py - oy
        wx0, wy0 = 1.0 - wx1, 1.0 - wy1
        return dr.fma(wy0, dr.fma(wx0, at(0), wx1 * at(1)),
                      wy1 * dr.fma(wx0, at(nx), wx1 * at(nx + 1)))


def _normal_area(u_theta_m, sin_theta_m):
    """The area of the normal's square per steradian of normals, 2 pi^2
    u_theta sin theta_m, kept from 0 (the pole) so that a pdf stays
    finite."""
    return dr.maximum(TWO_PI_SQUARED * u_theta_m * sin_theta_m, 1e-6)


def _normal_at(u_m, phi_i):
    """(m, sin theta_m): the microfacet normal at the warp's point u_m (theta
    as u squared, phi about wi's azimuth phi_i), as the writer places them."""
    phi_m = (2.0 * u_m.y - 1.0) * PI + phi_i
    theta_m = dr.square(u_m.x) * (0.5 * PI)
    sin_phi, cos_phi = dr.sincos(phi_m)
    sin_theta, cos_theta = dr.sincos(theta_m)
    return mi.Vector3f(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta), sin_theta


def _refraction_half(wi, wo, eta):
    """The refraction half vector of Walter et al. 2007 (sec. 5.2) of wi
    above and wo below, -(wi + eta wo) normalised and turned above the
    surface, and whether the pair is a refraction through it (wi.m > 0 >
    wo.m)."""
    h = -(wi + eta * wo)
    length = dr.norm(h)
    m = h / dr.select(h.z < 0, -length, length)
    ok = (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) < 0) & (length > 0) & \
        (dr.dot(wi, m) > 0) & (dr.dot(wo, m) < 0)
    return m, ok


def _refraction_jacobian(wi, wo, m, eta):
    """d omega_m / d omega_o of the refraction (Walter et al. eq. 16):
    eta^2 |wo.m| / (wi.m + eta wo.m)^2."""
    om = dr.dot(wo, m)
    d = dr.fma(eta, om, dr.dot(wi, m))
    # (0 where d is: no refraction, as the C reader's 0 for a jacobian that
    # is not finite.)
    nonzero = d != 0
    return dr.select(nonzero, eta * eta * dr.abs(om) / dr.select(nonzero, d * d, 1.0), 0.0)


def _flip(v):
    """v with its z negated: a direction as seen from the other side."""
    return mi.Vector3f(v.x, v.y, -v.z)


def _turn(axis, c, s, v):
    """v rotated about the axis (axis[0], axis[1], 0) by the angle whose
    cosine and sine are c and s (Rodrigues' formula, as the C reader's
    turn_apply)."""
    ax, ay = axis
    k = (ax * v.x + ay * v.y) * (1.0 - c)
    return mi.Vector3f(v.x * c + ay * v.z * s + ax * k,
                       v.y * c - ax * v.z * s + ay * k,
                       v.z * c + (ax * v.y - ay * v.x) * s)


def blend_elevation(value, pdf, reading, weight):
    """The blend of a set read at wi's two elevations, one more: the
    elevation's (values, density, where it has them) added with its weight
    to value and pdf (each None if not wanted)."""
    v, p, ok = reading
    if value is not None:
        value = [dr.select(ok, dr.fma(v[i], weight, value[i]), value[i]) for i in range(3)]
    if pdf is not None:
        pdf = dr.select(ok, dr.fma(p, weight, pdf), pdf)
    return value, pdf


def _masked_call(jit, mask, fn, args, zeros):
    """fn(*args) where mask holds, zeros() elsewhere. In the JIT variants a
    symbolic conditional (dr.if_stmt), so that a packet of lanes none of
    which needs the code skips it; in the scalar variants a plain call (the
    mask is a bool there)."""
    if not jit:
        return fn(*args) if mask else zeros()
    return dr.if_stmt(args, mask, fn, lambda *_: zeros())


def _fresnel(c, eta):
    """The unpolarised Fresnel reflectance of a smooth interface for light
    at cosine c (> 0) to its normal on the side of index 1, the far side of
    relative index eta; 1 under total internal reflection (as the C
    reader's ll_tables_fresnel)."""
    s2 = (1.0 - c * c) / (eta * eta)
    refracts = s2 < 1.0
    # (Under total internal reflection the quotients are not formed: both
    # denominators may vanish there, which the scalar variants raise on.)
    ct = dr.select(refracts, dr.safe_sqrt(1.0 - s2), 1.0)
    c = dr.select(refracts, c, 1.0)
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return dr.select(refracts, 0.5 * (rs * rs + rp * rp), 1.0)


def _fresnel_at(wi, m, eta):
    """That reflectance at the normal m of a reflection of wi (the factor a
    reflected set stored over it, field "fresnel_eta", is multiplied by);
    1 where wi does not face m."""
    c = dr.minimum(dr.dot(wi, m), 1.0)
    return dr.select(c > 0, _fresnel(dr.maximum(c, 0.0), eta), 1.0)


def _fresnel_eta(fields, prefix, transmit, name):
    """A reflected set's "fresnel_eta" (> 0: its values are stored over the
    Fresnel reflectance of their half vector at that relative index, which
    eval and sample multiply back), or 0 where the set has none."""
    key = prefix + "fresnel_eta"
    if transmit or key not in fields:
        return 0.0
    value = np.asarray(fields[key], dtype=np.float32).ravel()
    if value.shape != (1,) or not (0.001 <= float(value[0]) <= 1000.0) or value[0] == 1.0:
        raise TensorFileError("%s: field `%s` is not one relative index in [0.001, 1000] "
                              "other than 1" % (name, key))
    return float(value[0])


def _fresnel_floor(fields, prefix, transmit, fresnel_eta, name):
    """A reflected set's "fresnel_floor" k (only with its fresnel_eta: its
    values are then stored over (F + q) / (1 + q), q = k D(0) / D(m),
    _fresnel_floor_at, as the C reader's tables_lobes.c reads them), or 0
    where the set has none."""
    key = prefix + "fresnel_floor"
    if transmit or key not in fields:
        return 0.0
    value = np.asarray(fields[key], dtype=np.float32).ravel()
    if fresnel_eta <= 0.0 or value.shape != (1,) or not (0.0 <= float(value[0]) <= 1000.0):
        raise TensorFileError("%s: field `%s` is not one value in [0, 1000] in a set with "
                              "fresnel_eta" % (name, key))
    return float(value[0])


# The largest share of a Fresnel floor, also where D(m) is 0 (the C
# reader's LL_TABLES_FLOOR_SHARE_MAX).
FLOOR_SHARE_MAX = 1e6


def _ndf_point(m):
    """The point of a set's (isotropic) normal distribution at m's elevation,
    read at u_phi 0.5 as the C reader's floor reads it."""
    return mi.Point2f(_theta_to_u(_elevation(m)), 0.5)


def _fresnel_floor_at(wi, m, eta, floor, d_pole, d_m):
    """The factor of a set stored over F with the floor k: (F + q) / (1 + q),
    q = k D(0) / D(m) with d_pole and d_m the set's normal distribution at
    the pole and at m (F itself for k = 0; the C reader's
    tables_refract.h)."""
    share = dr.select(d_m > 0, floor * d_pole / dr.select(d_m > 0, d_m, 1.0),
                      dr.select(floor > 0, FLOOR_SHARE_MAX, 0.0))
    share = dr.minimum(share, FLOOR_SHARE_MAX)
    return (_fresnel_at(wi, m, eta) + share) / (1.0 + share)


class TracedTables:
    """An RGB table file's fields as Mitsuba warps and Dr.Jit arrays of the
    current variant, and eval / pdf / sample in Mitsuba's convention."""

    def __init__(self, fields, name="", prefix=""):
        """prefix: the set's (an extended file's "reflect_top." ...,
        layerlab.mitsuba_lobes); theta_i, phi_i and jacobian are shared."""
        for key in ("theta_i", "phi_i", "jacobian"):
            if key not in fields:
                raise TensorFileError("%s: no field `%s` (an RGB table file has it)"
                                      % (name, key))
        for key in ("ndf", "sigma", "vndf", "luminance", "rgb"):
            if prefix + key not in fields:
                raise TensorFileError("%s: no field `%s` (an RGB table file has it)"
                                      % (name, prefix + key))
        theta = np.asarray(fields["theta_i"], dtype=np.float32)
        phi = np.asarray(fields["phi_i"], dtype=np.float32)
        vndf = np.asarray(fields[prefix + "vndf"], dtype=np.float32)
        lum = np.asarray(fields[prefix + "luminance"], dtype=np.float32)
        rgb = np.asarray(fields[prefix + "rgb"], dtype=np.float32)
        n_pi, n_ti = len(phi), len(theta)
        if n_pi > 2:
            raise TensorFileError("%s: %d incident azimuths (anisotropic); the traced path "
                                  "reads isotropic files" % (name, n_pi))
        if rgb.ndim != 5 or rgb.shape[:3] != (n_pi, n_ti, 3):
            raise TensorFileError("%s: field `rgb` of shape %s" % (name, rgb.shape))
        self.jacobian = bool(int(fields["jacobian"].ravel()[0]))
        self.jit = dr.is_jit_v(mi.Float)
        # One azimuth: the elevation is the warps' one parameter.
        self.use_phi = n_pi > 1
        self.theta_host = theta.astype(np.float64)
        self.phi_host = phi.astype(np.float64)
        ndf = np.ascontiguousarray(fields[prefix + "ndf"], dtype=np.float32)
        sigma = np.ascontiguousarray(fields[prefix + "sigma"], dtype=np.float32)
        # Sets stacked (stack_sets): D and sigma per set, the set's index
        # their parameter (whole numbers: one slice exactly).
        self.stacked = ndf.ndim == 3
        if self.stacked:
            # (Their reader, mitsuba_lobes_stacked, reads the VNDF and
            # luminance slice by slice through its own warps.)
            self.vndf = self.luminance = None
        elif self.use_phi:
            params = [phi.tolist(), theta.tolist()]
            self.vndf = mi.MarginalContinuous2D2(np.ascontiguousarray(vndf), params)
            self.luminance = mi.MarginalContinuous2D2(np.ascontiguousarray(lum), params)
        else:
            # One parameter: the warps of mitsuba_warp.ParamWarp, Mitsuba's
            # calls and points, over slices read with guided searches.
            self.vndf = ParamWarp(vndf[0])
            self.luminance = ParamWarp(lum[0])
        if self.stacked:
            # Bilinear look-ups of the lane's set's grid (_grid_eval):
            # what Mitsuba's warps evaluated as stored compute, without
            # their interpolation over a parameter.
            self.ndf = _StackedGrid(ndf)
            self.sigma = _StackedGrid(sigma)
        else:
            self.ndf = mi.MarginalContinuous2D0(ndf, [], False, False)
            self.sigma = mi.MarginalContinuous2D0(sigma, [], False, False)
        # The values: per slice (azimuth, elevation), node (y, x), the three
        # channels and a zero, so that a node is one aligned 4-float read.
        self.size = int(rgb.shape[4]), int(rgb.shape[3])   # (x, y) as Mitsuba's warps
        # A grey file (the three channels equal, as a one-channel .bsdf
        # gives them: a glass, a pane) keeps one float per node: a quarter
        # of the memory the look-ups walk through.
        self.grey = bool(np.array_equal(rgb[:, :, 0], rgb[:, :, 1]) and
                         np.array_equal(rgb[:, :, 0], rgb[:, :, 2]))
        if self.grey:
            packed = np.ascontiguousarray(rgb[:, :, 0])
            self.values_host = packed.reshape(-1, 1)
        else:
            packed = np.zeros((n_pi, n_ti, rgb.shape[3], rgb.shape[4], 4), dtype=np.float32)
            packed[..., :3] = np.moveaxis(rgb, 2, -1)
            self.values_host = packed.reshape(-1, 4)
        if self.jit:
            self.values = mi.Float(packed.ravel())
            self.theta = mi.Float(theta)
            # The elevations' sines and cosines (_elevations: read, not
            # computed per lane), rounded from double.
            self.theta_sin = mi.Float(np.sin(self.theta_host).astype(np.float32))
            self.theta_cos = mi.Float(np.cos(self.theta_host).astype(np.float32))
            self.phi = mi.Float(phi)
        self.grid_text = "%d x %dx%d x %dx%d" % (n_ti, vndf.shape[2], vndf.shape[3],
                                                rgb.shape[3], rgb.shape[4])
        self.name = name

    # ------------------------------------------------------------ helpers

    def _params(self, phi_i, theta_i, slices=None):
        """The warps' parameters for the incident direction: Mitsuba's
        [phi_i, theta_i] for a file of two azimuths; else ParamWarp's
        [(j, w0, w1)], the slices and weights of theta_i (slices, where the
        caller reads one slice it knows), found once for both warps and
        the values (rgb's theta_weights)."""
        if self.use_phi:
            return [phi_i, theta_i]
        if slices is None:
            slices = self._weights(self.theta_host, self.theta if self.jit else None, theta_i)
        return [slices]

    def _theta_weights(self, params):
        """rgb's theta_weights from _params' result (None: rgb finds them)."""
        return None if self.use_phi else params[0]

    def _weights(self, values_host, values, x):
        """Mitsuba's interpolation over one parameter (Distribution2D's
        interpolate_weights): the interval [j, j + 1] by binary search
        (values[j] < x) and the weights (1 - t, t), t clamped to [0, 1]."""
        n = len(values_host)
        if n == 1:
            return 0, 1.0, 0.0
        if self.jit:
            Float, UInt32 = mi.Float, mi.UInt32
            j = dr.binary_search(1, n - 1, lambda i: dr.gather(Float, values, i) < x) - 1
            j = UInt32(j)
            p0 = dr.gather(Float, values, j)
            p1 = dr.gather(Float, values, j + 1)
        else:
            # the first index in [1, n - 1] whose value is not below x, minus 1
            k = 1
            while k < n - 1 and values_host[k] < x:
                k += 1
            j = k - 1
            p0, p1 = float(np.float32(values_host[j])), float(np.float32(values_host[j + 1]))
        t = dr.clip((x - p0) / (p1 - p0), 0.0, 1.0)
        return j, 1.0 - t, t

    def _gather(self, index, active):
        """The 4 floats (R, G, B, 0) of a node: one packet read (of a grey
        file: its one value, for each channel)."""
        if self.grey:
            if self.jit:
                v = dr.gather(mi.Float, self.values, index, active)
            else:
                v = float(self.values_host[int(index)][0])
            return [v, v, v]
        if self.jit:
            return dr.gather(mi.Vector4f, self.values, index, active)
        row = self.values_host[int(index)]
        return [float(row[0]), float(row[1]), float(row[2])]

    def _cell(self, sample):
        """The cell of the sample grid that holds the point sample of the
        square (its lower corner's column and row) and the point's place
        in it (fx, fy in [0, 1])."""
        nx, ny = self.size
        px = dr.clip(sample.x, 0.0, 1.0) * float(nx - 1)
        py = dr.clip(sample.y, 0.0, 1.0) * float(ny - 1)
        if self.jit:
            UInt32, Int32 = mi.UInt32, mi.Int32
            ox = dr.minimum(UInt32(Int32(px)), nx - 2)
            oy = dr.minimum(UInt32(Int32(py)), ny - 2)
        else:
            ox = min(int(px), nx - 2)
            oy = min(int(py), ny - 2)
        return ox, oy, px - ox, py - oy

    def rgb(self, sample, phi_i, theta_i, active, theta_weights=None):
        """The stored values (R, G, B) at the point sample of the sample
        square for the incident direction (phi_i, theta_i): Mitsuba's
        Marginal2D::eval per channel, with all channels at once.
        theta_weights: the elevation's slice and weights, if the caller has
        them (stacked sets), else found here."""
        nx, ny = self.size
        n_ti = len(self.theta_host)
        if theta_weights is not None:
            jt, wt0, wt1 = theta_weights
        else:
            jt, wt0, wt1 = self._weights(self.theta_host, self.theta if self.jit else None,
                                         theta_i)
        if self.use_phi:
            jp, wp0, wp1 = self._weights(self.phi_host, self.phi if self.jit else None, phi_i)
        ox, oy, fx, fy = self._cell(sample)
        node = oy * nx + ox
        size = nx * ny

        def at(theta_index, offset):
            # Mitsuba's nesting: the azimuth innermost, fma(v0, w0, v1 w1).
            if not self.use_phi:
                return self._gather(theta_index * size + node + offset, active)
            v0 = self._gather((jp * n_ti + theta_index) * size + node + offset, active)
            v1 = self._gather(((jp + 1) * n_ti + theta_index) * size + node + offset, active)
            return [dr.fma(v0[c], wp0, v1[c] * wp1) for c in range(3)]

        def corner(offset):
            v0, v1 = at(jt, offset), at(jt + 1, offset)
            return [dr.fma(v0[c], wt0, v1[c] * wt1) for c in range(3)]

        v00, v10 = corner(0), corner(1)
        v01, v11 = corner(nx), corner(nx + 1)
        return [dr.lerp(dr.lerp(v00[c], v10[c], fx), dr.lerp(v01[c], v11[c], fx), fy)
                for c in range(3)]

    def rgb_slice(self, sample, j, active):
        """The stored values (R, G, B) of the one slice j (of an isotropic
        file: an incident elevation) at the point sample of the sample
        square, bilinear in its cell: what rgb gives with the weights 1
        and 0 on that slice, without reading the next."""
        if not self.jit and not active:
            return [0.0, 0.0, 0.0]   # (its slice may lie past the last)
        nx, ny = self.size
        ox, oy, fx, fy = self._cell(sample)
        base = j * (nx * ny) + oy * nx + ox
        v00, v10 = self._gather(base, active), self._gather(base + 1, active)
        v01, v11 = self._gather(base + nx, active), self._gather(base + nx + 1, active)
        return [dr.lerp(dr.lerp(v00[c], v10[c], fx), dr.lerp(v01[c], v11[c], fx), fy)
                for c in range(3)]

    def _incident(self, wi):
        """wi's elevation (the slices' parameter), its azimuth and square
        coordinates."""
        theta_i = _elevation(wi)
        phi_i = dr.atan2(wi.y, wi.x)
        u_wi = mi.Point2f(_theta_to_u(theta_i), _phi_to_u(phi_i))
        return theta_i, phi_i, u_wi

    def _jacobian_scale(self, u_m, u_wi, active, stack=None):
        """D(m) / (4 sigma(wi)): the factor of values stored with the
        jacobian rule (docs/formats.md)."""
        if stack is not None:
            return self.ndf.eval(u_m, stack[0], active) / \
                (4.0 * self.sigma.eval(u_wi, stack[0], active))
        return self.ndf.eval(u_m, active=active) / (4.0 * self.sigma.eval(u_wi, active=active))

    # ------------------------------------------------------ the three calls

    def _at_normal(self, wi, m, active, want_value, want_pdf):
        """The lobe at the half vector m (of either warp): (f cos theta_o
        as a list of 3 Float, or None; the density of m per steradian of
        normals, from the two squares' densities, or None)."""
        theta_i, phi_i, u_wi = self._incident(wi)
        theta_m = _elevation(m)
        phi_m = dr.atan2(m.y, m.x)
        u_phi = _phi_to_u(phi_m - phi_i)
        u_m = mi.Point2f(_theta_to_u(theta_m), u_phi - dr.floor(u_phi))
        params = self._params(phi_i, theta_i)
        sample, vndf_pdf = self.vndf.invert(u_m, params, active)
        value = density = None
        if want_value:
            value = self.rgb(sample, phi_i, theta_i, active, self._theta_weights(params))
            if self.jacobian:
                scale = self._jacobian_scale(u_m, u_wi, active)
                value = [v * scale for v in value]
        if want_pdf:
            lum = self.luminance.eval(sample, params, active)
            density = vndf_pdf * lum / _normal_area(u_m.x, mi.Frame3f.sin_theta(m))
        return value, density

    def eval_pdf(self, wi, wo, active, want_value=True, want_pdf=True):
        """(f cos theta_o as a list of 3 Float, or None; the pdf per solid
        angle of wo, or None), zero where not active or below the surface."""
        active = active & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        m = dr.normalize(wo + wi)
        value, density = self._at_normal(wi, m, active, want_value, want_pdf)
        pdf = None
        if want_value:
            value = [dr.select(active, v, 0.0) for v in value]
        if want_pdf:
            pdf = dr.select(active, density / (4.0 * dr.dot(wi, m)), 0.0)
        return value, pdf

    def _elevations(self, wi, stack=None):
        """wi's two incident elevations of the file, as the C reader's
        tables_refract.c takes them: for wi's slice and the next, its
        weight, wi turned to that elevation in its plane of incidence (the
        turn's cosine and sine), the warps' parameter there and the slice
        weights that read that elevation alone; the turns' axis and wi's
        azimuth (the turned wi's too, at the pole as well). stack:
        a stacked set's (the lane's set, its slice and weights over the
        stacked elevations)."""
        theta = _elevation(wi)
        if stack is None:
            j, w0, w1 = self._weights(self.theta_host, self.theta if self.jit else None, theta)
        else:
            j, w0, w1 = stack[1]
        last = len(self.theta_host) - 1
        if self.jit:
            at = [j, dr.minimum(j + 1, last)]
            params = [dr.gather(mi.Float, self.theta, i) for i in at]
            sines = [dr.gather(mi.Float, self.theta_sin, i) for i in at]
            cosines = [dr.gather(mi.Float, self.theta_cos, i) for i in at]
        else:
            at = [self.theta_host[int(j)], self.theta_host[min(int(j) + 1, last)]]
            params = [float(np.float32(t)) for t in at]
            sines = [float(np.float32(np.sin(t))) for t in at]
            cosines = [float(np.float32(np.cos(t))) for t in at]
        r = dr.sqrt(dr.square(wi.x) + dr.square(wi.y))
        has = r > 0
        phi_i = dr.atan2(wi.y, wi.x)
        # (At the pole the turn goes towards the azimuth atan2 gives.)
        sin_p, cos_p = dr.sincos(phi_i)
        cp = dr.select(has, wi.x / dr.select(has, r, 1.0), cos_p)
        sp = dr.select(has, wi.y / dr.select(has, r, 1.0), sin_p)
        # The turns' angles, elevation minus wi's, by the difference
        # formulas from the elevations' sines and cosines and wi's.
        sin_t, cos_t = dr.sincos(theta)
        out = []
        for k, (weight, slices) in enumerate(((w0, (j, 1.0, 0.0)), (w1, (j, 0.0, 1.0)))):
            sin_n, cos_n = sines[k], cosines[k]
            sin_d = dr.fma(sin_n, cos_t, -cos_n * sin_t)
            cos_d = dr.fma(cos_n, cos_t, sin_n * sin_t)
            out.append((weight, mi.Vector3f(sin_n * cp, sin_n * sp, cos_n), cos_d, sin_d,
                        params[k], slices))
        return out, (-sp, cp), phi_i

    def read_at_normal(self, m, phi_i, param, slices, active, want_value, want_pdf):
        """The set at the half vector m for an incident elevation (param the
        warps' parameter there, slices the weights that read it alone, wi's
        azimuth phi_i): (m's point of the VNDF square; the stored values
        there, or None; the density of m per steradian of normals, or
        None)."""
        u_phi = _phi_to_u(dr.atan2(m.y, m.x) - phi_i)
        u_m = mi.Point2f(_theta_to_u(_elevation(m)), u_phi - dr.floor(u_phi))
        params = self._params(phi_i, param, slices)
        sample, vndf_pdf = self.vndf.invert(u_m, params, active)
        value = density = None
        if want_value:
            value = self.rgb(sample, phi_i, param, active, slices)
        if want_pdf:
            lum = self.luminance.eval(sample, params, active)
            density = vndf_pdf * lum / _normal_area(u_m.x, mi.Frame3f.sin_theta(m))
        return u_m, value, density

    def _stored_at(self, wi, phi_i, param, slices, wo, eta, active, want_value, want_pdf):
        """At one of the file's elevations (wi's own, param the warps'
        parameter there, slices the weights that read it alone): the
        stored values of the refracted pair (without the factors they are
        multiplied by), the elevation's density per solid angle of wo, and
        whether the pair refracts."""
        m, ok = _refraction_half(wi, wo, eta)
        active = active & ok
        _, value, density = self.read_at_normal(m, phi_i, param, slices, active, want_value,
                                                want_pdf)
        if want_pdf:
            density = density * _refraction_jacobian(wi, wo, m, eta)
            density = dr.select(active & dr.isfinite(density), density, 0.0)
        return value, density, active

    def refract_eval_pdf(self, wi, wo, eta, active, want_value=True, want_pdf=True):
        """eval_pdf of a transmitted lobe warped about the refraction half
        vector (docs/formats.md, "Extended table files"; the C reader's
        tables_refract.c): wi above, wo below, eta the far side's index over
        wi's side. Between two incident elevations the pair is turned with
        wi to each, the stored values read there are blended with the
        elevations' weights and multiplied by D / (4 sigma) at the pair
        itself; the pdf is the mixture of the elevations' densities, each
        with the refraction's d omega_m / d omega_o."""
        m, ok = _refraction_half(wi, wo, eta)
        active = active & ok
        value = [0.0, 0.0, 0.0] if want_value else None
        pdf = 0.0 if want_pdf else None
        elevations, axis, phi_i = self._elevations(wi)
        for weight, wi_k, c, s, param, slices in elevations:
            o = _turn(axis, c, s, wo)
            reading = self._stored_at(wi_k, phi_i, param, slices, o, eta,
                                      active & (weight > 0), want_value, want_pdf)
            value, pdf = blend_elevation(value, pdf, reading, weight)
        if want_value:
            if self.jacobian:
                u_wi = mi.Point2f(_theta_to_u(_elevation(wi)), _phi_to_u(phi_i))
                u_phi = _phi_to_u(dr.atan2(m.y, m.x) - phi_i)
                u_m = mi.Point2f(_theta_to_u(_elevation(m)), u_phi - dr.floor(u_phi))
                scale = self._jacobian_scale(u_m, u_wi, active)
                value = [v * scale for v in value]
            value = [dr.select(active, dr.maximum(v, 0.0), 0.0) for v in value]
        if want_pdf:
            pdf = dr.select(active & dr.isfinite(pdf) & (pdf > 0), pdf, 0.0)
        return value, pdf

    def _sample_normal(self, wi, sample2, active):
        """The normal m drawn from the two warps for the random numbers
        sample2 (Mitsuba's `measured` takes them as (sample2.y, sample2.x)
        into the luminance warp), its density per steradian of normals and
        f cos theta_o there (3 Float)."""
        theta_i, phi_i, u_wi = self._incident(wi)
        params = self._params(phi_i, theta_i)
        sample, lum_pdf = self.luminance.sample(mi.Point2f(sample2.y, sample2.x), params,
                                                active)
        u_m, vndf_pdf = self.vndf.sample(sample, params, active)
        m, sin_theta = _normal_at(u_m, phi_i)
        density = vndf_pdf * lum_pdf / _normal_area(u_m.x, sin_theta)
        value = self.rgb(sample, phi_i, theta_i, active, self._theta_weights(params))
        if self.jacobian:
            scale = self._jacobian_scale(u_m, u_wi, active)
            value = [v * scale for v in value]
        return m, density, value

    def reflect_sample(self, wi, sample2, active):
        """(wo, pdf, f cos theta_o as a list of 3 Float, ok) for the two
        random numbers sample2: wi reflected about the sampled normal."""
        active = active & (mi.Frame3f.cos_theta(wi) > 0)
        m, density, value = self._sample_normal(wi, sample2, active)
        dot = dr.dot(wi, m)
        wo = dr.fma(m, 2.0 * dot, -wi)
        pdf = density / (4.0 * dot)
        ok = active & (mi.Frame3f.cos_theta(wo) > 0) & (pdf > 0)
        return wo, dr.select(ok, pdf, 0.0), value, ok

    def sample(self, wi, sample2, active):
        """(wo, pdf, f cos theta_o / pdf as a list of 3 Float, ok) for the
        two random numbers sample2."""
        wo, pdf, value, ok = self.reflect_sample(wi, sample2, active)
        weight = [dr.select(ok, v / dr.select(ok, pdf, 1.0), 0.0) for v in value]
        return wo, pdf, weight, ok

    def sample_turned_normal(self, wi, sample2, active):
        """The normal of a set read at wi's two elevations (refracted or
        z-flipped), drawn as their samplers draw it: one of the
        elevations picked by sample2.x with its weight (sample2.x rescaled
        and passed on), m from that elevation's two warps. (the turns'
        axis, the picked elevation's (wi turned to it, the turn's cosine
        and sine, the warps' parameter), m, whether both warps gave it a
        density.)"""
        (e0, e1), axis, phi_i = self._elevations(wi)
        w0 = e0[0]
        second = sample2.x >= w0
        u0 = dr.select(second, (sample2.x - w0) / dr.select(e1[0] > 0, e1[0], 1.0),
                       sample2.x / dr.select(w0 > 0, w0, 1.0))
        pick = [dr.select(second, b, a) for a, b in zip(e0[1:5], e1[1:5])]
        params = self._params(phi_i, pick[3])
        sample, lum_pdf = self.luminance.sample(
            mi.Point2f(sample2.y, dr.clip(u0, 0.0, 1.0)), params, active)
        u_m, vndf_pdf = self.vndf.sample(sample, params, active)
        m, _ = _normal_at(u_m, phi_i)
        return axis, pick, m, (lum_pdf > 0) & (vndf_pdf > 0)

    def refract_sample(self, wi, sample2, eta, active):
        """sample of a transmitted lobe warped about the refraction half
        vector (as refract_eval_pdf): one of wi's two elevations picked by
        sample2.x with its weight (sample2.x rescaled and passed on), m
        from that elevation's warps, wi turned to it refracted through m
        (none under total internal reflection) and turned back; the pdf
        and value are refract_eval_pdf's there. (wo, pdf, f cos theta_o as
        a list of 3 Float, ok)."""
        active = active & (mi.Frame3f.cos_theta(wi) > 0)
        axis, (wi_k, c_k, s_k, _), m, drawn = self.sample_turned_normal(wi, sample2, active)
        inv = 1.0 / eta
        c = dr.dot(wi_k, m)
        k = 1.0 - inv * inv * (1.0 - c * c)
        o = (inv * c - dr.safe_sqrt(k)) * m - inv * wi_k
        wo = _turn(axis, c_k, -s_k, o)
        ok = active & (c > 0) & (k > 0) & (o.z < 0) & (wo.z < 0) & drawn
        value, pdf = self.refract_eval_pdf(wi, wo, eta, ok, True, True)
        ok = ok & (pdf > 0)
        value = [dr.select(ok, v, 0.0) for v in value]
        return wo, dr.select(ok, pdf, 0.0), value, ok

    def describe(self):
        """The grid: incident elevations x VNDF grid x sample grid."""
        return self.grid_text


# ------------------------------------------------------- tables made on load


class TablesOptions(ctypes.Structure):
    """``ll_tables_options`` (size-tagged; include/layerlab/ll_tables.h,
    experimental); a new instance is LL_TABLES_OPTIONS_INIT."""

    _fields_ = [("struct_size", ctypes.c_size_t), ("n_theta_i", ctypes.c_size_t),
                ("vndf_size", ctypes.c_size_t), ("sample_size", ctypes.c_size_t),
                ("format", ctypes.c_int), ("description", ctypes.c_char_p),
                ("wavelengths", ctypes.POINTER(ctypes.c_double)),
                ("n_wavelengths", ctypes.c_size_t), ("spectrum", ctypes.c_void_p),
                ("spectrum_user", ctypes.c_void_p), ("tolerance", ctypes.c_double)]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(TablesOptions)


def _write_tables(handle, path, tolerance, description):
    """ll_tables_write_from_bsdf(handle, path): an RGB file, every grid size
    chosen by the tolerance (0: the library's default)."""
    try:
        fn = getattr(lib._cdll, "ll_tables_write_from_bsdf")
    except AttributeError:
        raise _native.UnsupportedError(
            "ll_tables_write_from_bsdf is not exported by the loaded liblayerlab (%s); the "
            "Mitsuba plugin's \"tables\" mode on a .bsdf needs a newer library (or give "
            "\"mode\": \"traced\")" % lib.path, 6) from None
    fn.restype = ctypes.c_int
    fn.argtypes = [_native.bsdf_p, ctypes.c_char_p, ctypes.POINTER(TablesOptions),
                   ctypes.c_void_p]
    opts = TablesOptions()
    opts.tolerance = tolerance
    opts.description = description.encode("utf-8")
    _native.check(fn(handle, os.fsencode(path), ctypes.byref(opts), None))


def _cache_key(source, tolerance):
    """What the tables made from source depend on: its bytes, the tolerance
    and the library that writes them (its version and, when it is a file
    here, its size and time, so that a rebuilt writer is not served the
    tables of the old one)."""
    digest = hashlib.sha256()
    with open(source, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    digest.update(lib.ll_version_string())
    digest.update(repr(float(tolerance)).encode())
    try:
        st = os.stat(lib.path)
        digest.update(("%d %d" % (st.st_size, st.st_mtime_ns)).encode())
    except (OSError, TypeError):
        pass
    return digest.hexdigest()[:40]


def tables_from_bsdf(handle, source, tolerance=0.0, cache=True):
    """The fields of the table file made from the opened .bsdf handle (its
    path source) by ll_tables_write_from_bsdf (for a transmissive one an
    extended file, a set per lobe and side; for a textured one a set per
    basis), with grid
    sizes chosen by the tolerance, and where they came from. With cache,
    the file is kept in the user's cache directory (layerlab.user_cache_dir(),
    subfolder "mitsuba-tables", named by a hash of the source's bytes, the
    tolerance and the library) and read from there by later loads: the
    tolerance search measures each grid it tries against the source and
    takes seconds (docs/benchmarks.md, "Rendering in Mitsuba 3"), which a
    scene load should pay once, not at every load. Without cache, or when the cache cannot be
    written, a temporary file, removed once read. Every table file read is
    opened by the C reader first (ll_bsdf_open validates it)."""
    from ._errors import InvalidArgumentError
    from .material import user_cache_dir
    from .storage import BSDFStorage
    description = "layerlab: tables of %s" % os.path.basename(source)
    folder = None
    if cache:
        try:
            folder = os.path.join(user_cache_dir(), "mitsuba-tables")
            os.makedirs(folder, exist_ok=True)
        except (OSError, InvalidArgumentError):
            folder = None  # (no cache directory: a temporary file below)
    if folder is not None:
        path = os.path.join(folder, _cache_key(source, tolerance) + ".tab")
        try:
            made = False
            if not os.path.exists(path):
                _write_tables(handle, path, tolerance, description)
                made = True
            BSDFStorage(path).close()
            return read_tensor_file(path), ("made and cached in %s" if made else
                                            "cached in %s") % path
        except OSError:
            pass  # (the cache cannot be written or read: a temporary file below)
    with tempfile.TemporaryDirectory(prefix="layerlab-tables-") as scratch:
        path = os.path.join(scratch, "tables.tab")
        _write_tables(handle, path, tolerance, description)
        BSDFStorage(path).close()
        return read_tensor_file(path), "made on load"
