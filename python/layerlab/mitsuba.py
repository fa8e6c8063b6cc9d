"""A Mitsuba 3 BSDF plugin for layerlab's .bsdf files.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")      # or scalar_rgb
    import layerlab.mitsuba            # registers the BSDF "layerlab"
    bsdf = mi.load_dict({"type": "layerlab", "filename": "gold.bsdf"})

Conventions: the same as the pbrt-v3 shim (shims/pbrt-v3), i.e. the
renderer convention of ll_bsdf.h, with Mitsuba's names mapped onto pbrt's:
Mitsuba's si.wi (towards the previous vertex, the camera on a camera path)
is pbrt's wo, and Mitsuba's wo (the direction being evaluated or sampled)
is pbrt's wi. Both are in the local shading frame (z = the normal), as
ll_bsdf_eval_dir takes them. Mitsuba's eval includes the cosine factor
|cos theta| of its wo, which ll_bsdf_eval_dir leaves out, so it is applied
here. Radiance mode multiplies transmitted values by the eta^2 of the
interface (Veach's non-symmetric scattering), importance mode does not:
the C library does that (ll_transport).

Vectorised: in the LLVM variants one call of the batch API
(ll_bsdf_eval_dir_batch, ll_bsdf_pdf_dir_batch, ll_bsdf_sample_dir_batch)
evaluates a whole wavefront, through numpy copies of the Dr.Jit arrays.
That needs evaluated (wavefront) loops and calls: symbolic ones hold no
values to hand to C. Creating a layerlab BSDF in an LLVM variant therefore
turns Dr.Jit's SymbolicLoops and SymbolicCalls flags off (a global setting
of Dr.Jit; Mitsuba then renders in wavefront mode). The scalar variants call
the same batch functions with one element. CUDA variants are refused: the
directions would have to travel to the CPU and back at every bounce.

Textured files (more than one basis function) are refused for now: the C
API has no call yet that gives the basis weights for given parameter values
(ll_bsdf_basis_coefficients is planned), and weights made up here would
render something else than the file describes.

Lobes: glossy reflection on both sides, and glossy transmission when the
file transmits (its eta differs from 1, or it has non-zero transmission
values: a probe of directions across the surface at load time).
"""

import ctypes
import math

import numpy as np

from . import _native
from ._native import c_double_p, lib
from .storage import BSDFStorage

try:
    import drjit as dr
    import mitsuba as mi
except ImportError as error:  # pragma: no cover - depends on the environment
    raise ImportError("layerlab.mitsuba needs Mitsuba 3: pip install 'layerlab[mitsuba]' "
                      "(or pip install mitsuba)") from error

_LL_OK = 0
_LL_INVALID_ARGUMENT_ELEMENT = 1  # an element's zero/non-finite direction: zeros, as scalar


def _wavefront_mode():
    """Evaluated loops and calls: what handing Dr.Jit arrays to C needs."""
    dr.set_flag(dr.JitFlag.SymbolicLoops, False)
    dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _packed(values, width, components):
    """A Dr.Jit (or scalar) vector as a C-contiguous (width, components)
    float64 array: the packed layout of the batch calls."""
    if hasattr(values, "numpy") and dr.is_jit_v(values):
        a = np.asarray(values.numpy(), dtype=np.float64)
    else:
        a = np.asarray([float(values[i]) for i in range(components)], dtype=np.float64)
    if a.ndim == 1:
        a = a.reshape(components, 1)
    a = np.broadcast_to(a, (components, width))
    return np.ascontiguousarray(a.T)


def _ptr(a):
    return a.ctypes.data_as(c_double_p)


class _Table:
    """The opened file and the three batch calls over numpy arrays."""

    def __init__(self, path):
        self.storage = BSDFStorage(path)
        self.handle = self.storage._live()
        info = _native.BsdfInfo()
        _native.check(lib.ll_bsdf_get_info(self.handle, ctypes.byref(info)))
        self.eta = info.eta
        self.n_bases = info.n_bases
        self.n_parameters = info.n_parameters
        self.n_channels = info.n_channels

    @staticmethod
    def _check(status):
        # The batch returns the first invalid element's status after doing
        # every element; such an element (a degenerate direction in a masked
        # lane) has zeros, as in Mitsuba's own BSDFs. Anything else raises.
        if status not in (_LL_OK, _LL_INVALID_ARGUMENT_ELEMENT):
            _native.check(status)

    def eval(self, wo, wi, mode):
        n = wo.shape[0]
        rgb = np.zeros((n, 3))
        self._check(lib.ll_bsdf_eval_dir_batch(self.handle, n, _ptr(wo), _ptr(wi), mode, None,
                                               0, _ptr(rgb)))
        return rgb

    def pdf(self, wo, wi):
        n = wo.shape[0]
        pdf = np.zeros(n)
        self._check(lib.ll_bsdf_pdf_dir_batch(self.handle, n, _ptr(wo), _ptr(wi), None, 0,
                                              _ptr(pdf)))
        return pdf

    def sample(self, wo, u, mode):
        n = wo.shape[0]
        wi = np.zeros((n, 3))
        pdf = np.zeros(n)
        rgb = np.zeros((n, 3))
        self._check(lib.ll_bsdf_sample_dir_batch(self.handle, n, _ptr(wo), _ptr(u), mode, None,
                                                 0, _ptr(wi), _ptr(pdf), _ptr(rgb)))
        return wi, pdf, rgb

    def transmits(self):
        """Whether any transmitted value is non-zero, on a grid of direction
        pairs across the surface (both ways), or eta differs from 1."""
        if self.eta != 1.0:
            return True
        cosines = np.linspace(0.05, 1.0, 12)
        pairs = []
        for a in cosines:
            for b in cosines:
                for phi in (0.0, 1.0, math.pi):
                    sa, sb = math.sqrt(1 - a * a), math.sqrt(1 - b * b)
                    pairs.append(((sa, 0.0, a), (sb * math.cos(phi), sb * math.sin(phi), -b)))
        wo = np.ascontiguousarray([p[0] for p in pairs], dtype=np.float64)
        wi = np.ascontiguousarray([p[1] for p in pairs], dtype=np.float64)
        importance = 1
        down = self.eval(wo, wi, importance)
        up = self.eval(np.ascontiguousarray(-wo), np.ascontiguousarray(-wi), importance)
        return bool(down.max() > 0.0 or up.max() > 0.0)


_CLASSES = {}


def _make_class():
    """The BSDF class for the current Mitsuba variant (mi.BSDF differs per
    variant, so the class is made once per variant)."""
    variant = mi.variant()
    if variant in _CLASSES:
        return _CLASSES[variant]
    Flags = mi.BSDFFlags

    class LayerlabBSDF(mi.BSDF):
        """Mitsuba BSDF "layerlab": {"type": "layerlab", "filename": "x.bsdf"}."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            current = mi.variant()
            if current.startswith("cuda"):
                raise RuntimeError(
                    "layerlab: the CUDA variant %s is not supported: the .bsdf evaluation runs "
                    "on the CPU (liblayerlab); use an LLVM variant such as llvm_ad_rgb, or "
                    "scalar_rgb" % current)
            if not current.endswith("_rgb"):
                raise RuntimeError(
                    "layerlab: variant %s is not supported: .bsdf files hold RGB (or one "
                    "channel); use llvm_ad_rgb or scalar_rgb" % current)
            if "filename" not in props:
                raise ValueError('layerlab: the BSDF needs "filename" (a .bsdf file)')
            name = str(props["filename"])
            resolver = mi.file_resolver() if hasattr(mi, "file_resolver") else \
                mi.Thread.thread().file_resolver()
            path = str(resolver.resolve(name))
            self.m_filename = path
            self.m_table = _Table(path)
            if self.m_table.n_bases > 1:
                raise ValueError(
                    "layerlab: %s is textured (%d basis functions over %d parameters); the "
                    "Mitsuba plugin cannot give their weights yet (the C API has no "
                    "ll_bsdf_basis_coefficients), so textured files are refused"
                    % (path, self.m_table.n_bases, self.m_table.n_parameters))
            self.m_eta = self.m_table.eta
            self.m_transmits = self.m_table.transmits()
            both = Flags.FrontSide | Flags.BackSide
            components = [Flags.GlossyReflection | both]
            if self.m_transmits:
                components.append(Flags.GlossyTransmission | both)
            self.m_components = components
            flags = components[0]
            for c in components[1:]:
                flags = flags | c
            self.m_flags = flags
            self.m_jit = dr.is_jit_v(mi.Float)
            if self.m_jit:
                _wavefront_mode()

        # -------------------------------------------------------- helpers

        def _out_float(self, values):
            if self.m_jit:
                return mi.Float(np.ascontiguousarray(values, dtype=np.float32))
            return mi.Float(float(values[0]))

        def _out_color(self, rgb):
            return mi.Color3f(self._out_float(rgb[:, 0]), self._out_float(rgb[:, 1]),
                              self._out_float(rgb[:, 2]))

        def _out_vector(self, v):
            return mi.Vector3f(self._out_float(v[:, 0]), self._out_float(v[:, 1]),
                               self._out_float(v[:, 2]))

        @staticmethod
        def _mode(ctx):
            return 0 if ctx.mode == mi.TransportMode.Radiance else 1

        def _lobe_mask(self, ctx, cos_i, cos_o):
            """Mitsuba's enabled lobes: reflection when both directions are
            on the same side, transmission otherwise."""
            reflect = ctx.is_enabled(Flags.GlossyReflection, 0)
            transmit = self.m_transmits and ctx.is_enabled(Flags.GlossyTransmission, 1)
            same = cos_i * cos_o > 0
            return dr.select(same, reflect, transmit)

        def _pairs(self, si, wo):
            width = max(dr.width(si.wi), dr.width(wo))
            return width, _packed(si.wi, width, 3), _packed(wo, width, 3)

        # ---------------------------------------------------- BSDF interface

        def eval(self, ctx, si, wo, active=True):
            width, a, b = self._pairs(si, wo)
            f = self._out_color(self.m_table.eval(a, b, self._mode(ctx)))
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi), cos_o)
            return dr.select(ok, f * dr.abs(cos_o), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            width, a, b = self._pairs(si, wo)
            p = self._out_float(self.m_table.pdf(a, b))
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi),
                                          mi.Frame3f.cos_theta(wo))
            return dr.select(ok, p, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            width, a, b = self._pairs(si, wo)
            f = self._out_color(self.m_table.eval(a, b, self._mode(ctx)))
            p = self._out_float(self.m_table.pdf(a, b))
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi), cos_o)
            return dr.select(ok, f * dr.abs(cos_o), 0.0), dr.select(ok, p, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            width = max(dr.width(si.wi), dr.width(sample2))
            a = _packed(si.wi, width, 3)
            u = np.clip(_packed(sample2, width, 2), 0.0, 1.0)
            wi, pdf, rgb = self.m_table.sample(a, u, self._mode(ctx))
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = self._out_vector(wi)
            bs.pdf = self._out_float(pdf)
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(bs.wo)
            reflected = cos_i * cos_o > 0
            entering = cos_i > 0
            eta = mi.Float(self.m_eta)
            bs.eta = dr.select(reflected, 1.0, dr.select(entering, eta, dr.rcp(eta)))
            bs.sampled_type = dr.select(reflected, mi.UInt32(+Flags.GlossyReflection),
                                        mi.UInt32(+Flags.GlossyTransmission))
            bs.sampled_component = dr.select(reflected, mi.UInt32(0), mi.UInt32(1))
            ok = active & (bs.pdf > 0) & self._lobe_mask(ctx, cos_i, cos_o)
            bs.pdf = dr.select(ok, bs.pdf, 0.0)
            # Weight f |cos| / pdf, with f and pdf of the same direction (the
            # sampler's pdf equals ll_bsdf_pdf_dir there).
            f = self._out_color(rgb)
            weight = f * dr.abs(cos_o) / dr.select(ok, bs.pdf, 1.0)
            return bs, dr.select(ok, weight, 0.0)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return ("LayerlabBSDF[filename=\"%s\", eta=%g, transmission=%s]"
                    % (self.m_filename, self.m_eta, self.m_transmits))

    _CLASSES[variant] = LayerlabBSDF
    return LayerlabBSDF


def register():
    """Register the BSDF "layerlab" for the current Mitsuba variant. Called
    on import; call it again after switching variants with mi.set_variant."""
    if mi.variant() is None:
        raise RuntimeError("layerlab.mitsuba: set a Mitsuba variant first "
                           "(mi.set_variant('llvm_ad_rgb') or 'scalar_rgb'), then import "
                           "layerlab.mitsuba or call layerlab.mitsuba.register()")
    cls = _make_class()
    mi.register_bsdf("layerlab", lambda props: cls(props))
    return cls


if mi.variant() is not None:
    register()
