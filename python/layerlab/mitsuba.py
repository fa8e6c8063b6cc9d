"""A Mitsuba 3 BSDF plugin for layerlab's .bsdf and table files.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")      # or scalar_rgb, cuda_ad_rgb
    import layerlab.mitsuba            # registers the BSDF "layerlab"
    bsdf = mi.load_dict({"type": "layerlab", "filename": "gold.bsdf"})
    # or a table file (llbuild --format measured, llconvert), or
    # {"type": "layerlab", "filename": "glass.bsdf", "mode": "traced"}

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

Three implementations, chosen with the property "mode":
- "tables" (the default for an RGB table file and a .bsdf, opaque,
  transmissive or textured, in every RGB variant: scalar_rgb,
  llvm_ad_rgb, cuda_ad_rgb): warped
  tables of the `measured` format (docs/formats.md), evaluated and
  sampled as Mitsuba's own {"type": "measured"} does, with Mitsuba's 2D warps
  (mi.MarginalContinuous2D*) and Dr.Jit operations (layerlab.mitsuba_tables),
  so in the JIT variants they trace into the rendering kernel (the symbolic
  megakernel stays on) and nothing runs on the CPU per call. A table file is
  opened by the C reader first (ll_bsdf_open validates it), then its fields
  are read with numpy. A .bsdf is made into tables when it is loaded
  (ll_tables_write_from_bsdf, grid sizes chosen by the table tolerance,
  property "tolerance", default the library's 0.05) and the table file is
  kept in the user's cache directory (layerlab.user_cache_dir(), folder
  "mitsuba-tables", named by a hash of the .bsdf's bytes, the tolerance and
  the library), so only the first load pays for the writer's tolerance search (docs/benchmarks.md has its cost); "cache": false makes it in a
  temporary file instead, removed once read (a transmissive .bsdf whose
  tables the loaded library cannot write takes the Fourier path instead,
  the reason in str(bsdf)). An opaque file's lobe is
  one-sided glossy reflection (FrontSide), as in Mitsuba's `measured`: zero
  unless both directions are above the surface. A transmissive file (a
  .bsdf that transmits gives one; layerlab's extension of the format, a
  table set per lobe and side) has glossy reflection and transmission on
  both sides, evaluated and sampled as the C reader does
  (layerlab.mitsuba_lobes, mitsuba_lobes_stacked). A textured file (a
  textured .bsdf gives one: a table set per basis) blends its bases per
  lane with the weights of the lane's parameter values, as the C reader
  does (layerlab.mitsuba_textured). Values are the C reader's on the same
  table file up to float32 rounding (python/tests/test_tables_mitsuba.py,
  test_tables_glass_mitsuba.py, test_textured_tables_mitsuba.py).
  A spectral table file is not read by this mode (its RGB is the C reader's
  conversion of the spectra): it renders through "batch".
- "traced" (the default in the LLVM variants for a .bsdf whose tables the
  loaded library cannot write, e.g. a textured one whose bases transmit):
  the Fourier series'
  eval, pdf and sample written in Dr.Jit operations (layerlab.mitsuba_traced)
  over the file's tables, uploaded once as Dr.Jit arrays
  (ll_bsdf_get_tables). They trace into Mitsuba's rendering kernel too;
  values and sampled directions are the C reader's up to float32 rounding.
- "batch" (the default for those files in the scalar variants, and for
  spectral table files): one call of the C batch API (ll_bsdf_eval_dir_batch,
  ll_bsdf_pdf_dir_batch, ll_bsdf_sample_dir_batch) per wavefront, through
  numpy copies of the Dr.Jit arrays. That needs evaluated (wavefront) loops
  and calls: symbolic ones hold no values to hand to C. Creating a
  batch-mode BSDF in an LLVM variant therefore turns Dr.Jit's SymbolicLoops
  and SymbolicCalls flags off (a global setting of Dr.Jit; Mitsuba then
  renders in wavefront mode). The scalar variants call the same batch
  functions with one element.
"tables" on a file it cannot hold, and "traced" on a table file (which holds
no Fourier series) are refused with the reason. The CUDA variants take
"tables" only: "batch" would move the directions to the CPU and back at every
bounce, and "traced" is written and tested for LLVM. (No GPU was at hand: the
"tables" mode has run in scalar_rgb and llvm_ad_rgb only; it uses nothing but
Mitsuba's warps and Dr.Jit operations, which exist in the CUDA variants too.)
A textured table file (a table set per basis of a textured .bsdf) takes
the same per-parameter properties as that .bsdf (below). Mitsuba's
`measured` refuses such a file, and a transmissive one (they have no plain
tables).

Textured files (more than one basis function): one property per textured
parameter, by the parameter's name (ll_bsdf_get_parameter_name; a "." in a
name may be written "_"), a float or any Mitsuba texture
(so a bitmap drives the roughness). Its value at the shading point gives the
basis weights: the tensor product of linear hat weights over the
parameter's sample positions (ll_bsdf_basis_coefficients), traced per lane
(layerlab.mitsuba_basis, one code for "tables" and "traced"); only the bases
of non-zero weight are read. In "batch" mode the same weights are computed
per element in numpy and passed with a stride.

Lobes ("traced", "batch", and "tables" on a transmissive file): glossy
reflection on both sides, and glossy transmission when the file transmits
(its eta differs from 1, or it has non-zero transmission values: a probe of
directions across the surface at load time).
"""

import ctypes
import math

import numpy as np

from . import _native
from ._native import c_double_p, c_float_p, lib
from .storage import BSDFStorage

try:
    import drjit as dr
    import mitsuba as mi
except ImportError as error:  # pragma: no cover - depends on the environment
    raise ImportError("layerlab.mitsuba needs Mitsuba 3: pip install 'layerlab[mitsuba]' "
                      "(or pip install mitsuba)") from error

from .mitsuba_lobes import layout_names, traced_lobes  # noqa: E402
from .mitsuba_tables import TracedTables, tables_from_bsdf  # noqa: E402
from .mitsuba_textured import TexturedTables, is_textured  # noqa: E402
from .tensor_file import TensorFileError, read_tensor_file  # noqa: E402
from .mitsuba_traced import TracedBSDF  # noqa: E402

_LL_OK = 0
_LL_INVALID_ARGUMENT_ELEMENT = 1  # an element's zero/non-finite direction: zeros, as scalar


def wavefront_mode():
    """Turn Dr.Jit's symbolic loops and calls off on the calling thread
    (Mitsuba then renders in wavefront mode): what the "batch" mode needs in
    the LLVM variants, whose arrays must be evaluated to be handed to C.
    Dr.Jit's flags belong to a thread, and Mitsuba builds a scene's objects
    on worker threads, so the flags a BSDF sets while it is built may not be
    those of the thread that renders: call this on that thread."""
    dr.set_flag(dr.JitFlag.SymbolicLoops, False)
    dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _require_wavefront_mode():
    """The batch mode inside a symbolic region (a render whose thread has
    the symbolic modes on) cannot read its arrays (Dr.Jit fails with
    "Variable ... remains dirty"): say what to do instead."""
    if dr.flag(dr.JitFlag.SymbolicScope):
        raise RuntimeError(
            'layerlab: "mode": "batch" needs Dr.Jit\'s wavefront mode on the thread '
            "that renders: call layerlab.mitsuba.wavefront_mode() (or turn "
            "dr.JitFlag.SymbolicLoops and SymbolicCalls off) before mi.render, or use "
            'the default "traced" mode')


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


def _fptr(a):
    return None if a is None else a.ctypes.data_as(c_float_p)


class _Table:
    """The opened file, its parameters, and the three batch calls over numpy
    arrays (coeffs: None, or per-element basis weights (n, n_bases) float32)."""

    def __init__(self, path):
        self.storage = BSDFStorage(path)
        self.handle = self.storage._live()
        info = _native.BsdfInfo()
        _native.check(lib.ll_bsdf_get_info(self.handle, ctypes.byref(info)))
        self.eta = info.eta
        self.n_bases = info.n_bases
        self.n_parameters = info.n_parameters
        self.n_channels = info.n_channels
        self.n_wavelengths = info.n_wavelengths
        # "fourier" (a .bsdf) or "tables" (the `measured` format): only the
        # first has the series the traced path reads.
        self.format = self.storage.format
        self.metadata = info.metadata.decode("utf-8", "replace") if info.metadata else ""
        self.positions = []
        for p in range(self.n_parameters):
            count = ctypes.c_size_t()
            pos = c_float_p()
            _native.check(lib.ll_bsdf_get_parameter(self.handle, p, ctypes.byref(count),
                                                    ctypes.byref(pos)))
            self.positions.append(np.array(pos[:count.value], dtype=np.float64))
        self.names = self._parameter_names()

    def _parameter_names(self):
        """The parameters' names (ll_bsdf_get_parameter_name: the metadata's,
        else p0, p1, ...)."""
        names = []
        for p in range(self.n_parameters):
            name = ctypes.c_char_p()
            _native.check(lib.ll_bsdf_get_parameter_name(self.handle, p, ctypes.byref(name)))
            names.append(name.value.decode("utf-8"))
        return names

    def coefficients(self, params):
        """Per-element basis weights for parameter values params (list of
        arrays, one per parameter): the tensor product of linear hat weights
        (ll_bsdf_basis_coefficients, vectorised), (n, n_bases) float32."""
        width = max(len(v) for v in params)
        coeffs = np.ones((width, 1))
        for p, pos in enumerate(self.positions):
            x = np.clip(np.broadcast_to(params[p], (width,)), pos[0], pos[-1])
            w = np.zeros((width, len(pos)))
            if len(pos) == 1:
                w[:, 0] = 1.0
            else:
                j = np.clip(np.searchsorted(pos, x, side="right") - 1, 0, len(pos) - 2)
                t = (x - pos[j]) / (pos[j + 1] - pos[j])
                w[np.arange(width), j] = 1.0 - t
                w[np.arange(width), j + 1] = t
            # parameter 0 fastest in the basis index
            coeffs = (w[:, :, None] * coeffs[:, None, :]).reshape(width, -1)
        return np.ascontiguousarray(coeffs, dtype=np.float32)

    @staticmethod
    def _check(status):
        # The batch returns the first invalid element's status after doing
        # every element; such an element (a degenerate direction in a masked
        # lane) has zeros, as in Mitsuba's own BSDFs. Anything else raises.
        if status not in (_LL_OK, _LL_INVALID_ARGUMENT_ELEMENT):
            _native.check(status)

    def _stride(self, coeffs):
        return 0 if coeffs is None else (self.n_bases if coeffs.shape[0] > 1 else 0)

    def eval(self, wo, wi, mode, coeffs=None):
        n = wo.shape[0]
        rgb = np.zeros((n, 3))
        self._check(lib.ll_bsdf_eval_dir_batch(self.handle, n, _ptr(wo), _ptr(wi), mode,
                                               _fptr(coeffs), self._stride(coeffs), _ptr(rgb)))
        return rgb

    def pdf(self, wo, wi, coeffs=None):
        n = wo.shape[0]
        pdf = np.zeros(n)
        self._check(lib.ll_bsdf_pdf_dir_batch(self.handle, n, _ptr(wo), _ptr(wi), _fptr(coeffs),
                                              self._stride(coeffs), _ptr(pdf)))
        return pdf

    def sample(self, wo, u, mode, coeffs=None):
        n = wo.shape[0]
        wi = np.zeros((n, 3))
        pdf = np.zeros(n)
        rgb = np.zeros((n, 3))
        self._check(lib.ll_bsdf_sample_dir_batch(self.handle, n, _ptr(wo), _ptr(u), mode,
                                                 _fptr(coeffs), self._stride(coeffs), _ptr(wi),
                                                 _ptr(pdf), _ptr(rgb)))
        return wi, pdf, rgb

    def transmits(self):
        """Whether any transmitted value is non-zero, on a grid of direction
        pairs across the surface (both ways), or eta differs from 1. A
        textured file is probed with every basis weighted equally (f >= 0
        per basis, so the sum transmits if any basis does)."""
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
        coeffs = None
        if self.n_bases > 1:
            coeffs = np.full((1, self.n_bases), 1.0 / self.n_bases, dtype=np.float32)
        importance = 1
        down = self.eval(wo, wi, importance, coeffs)
        up = self.eval(np.ascontiguousarray(-wo), np.ascontiguousarray(-wi), importance, coeffs)
        return bool(down.max() > 0.0 or up.max() > 0.0)


_CLASSES = {}


def _file_axes(wi_m, wo_m):
    """Mitsuba's (si.wi, wo) as the file's (mu_i, mu_o, cos phi_d): pbrt's
    wo = si.wi and wi = wo (ll_bsdf.h, renderer convention)."""
    inv_a = dr.rsqrt(dr.squared_norm(wi_m))
    inv_b = dr.rsqrt(dr.squared_norm(wo_m))
    mu_i = dr.clip(wi_m.z * inv_a, -1.0, 1.0)
    mu_o = dr.clip(-wo_m.z * inv_b, -1.0, 1.0)
    xy_a = dr.fma(wi_m.x, wi_m.x, wi_m.y * wi_m.y)
    xy_b = dr.fma(wo_m.x, wo_m.x, wo_m.y * wo_m.y)
    # pbrt-v3's CosDPhi(-wi, wo): 1 when either has no azimuth.
    cos_phi = dr.select((xy_a > 0) & (xy_b > 0),
                        dr.clip(-dr.fma(wo_m.x, wi_m.x, wo_m.y * wi_m.y) *
                                dr.rsqrt(xy_a * xy_b), -1.0, 1.0), 1.0)
    return mu_i, mu_o, cos_phi


def _make_class():
    """The BSDF class for the current Mitsuba variant (mi.BSDF differs per
    variant, so the class is made once per variant)."""
    variant = mi.variant()
    if variant in _CLASSES:
        return _CLASSES[variant]
    Flags = mi.BSDFFlags

    class LayerlabBSDF(mi.BSDF):
        """Mitsuba BSDF "layerlab": {"type": "layerlab", "filename": "x.bsdf"},
        optional "mode": "tables" | "traced" | "batch", "tolerance" and
        "cache" (tables made from a .bsdf), and for a textured file one
        property per parameter name (float or texture)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            current = mi.variant()
            if not current.endswith("_rgb"):
                raise RuntimeError(
                    "layerlab: variant %s is not supported: the plugin renders RGB (files of "
                    "one channel as grey); use scalar_rgb, llvm_ad_rgb or cuda_ad_rgb (a "
                    "spectral table file renders in the spectral variants through Mitsuba's "
                    "own {\"type\": \"measured\"})" % current)
            if "filename" not in props:
                raise ValueError('layerlab: the BSDF needs "filename" (a .bsdf or table file)')
            name = str(props["filename"])
            resolver = mi.file_resolver() if hasattr(mi, "file_resolver") else \
                mi.Thread.thread().file_resolver()
            path = str(resolver.resolve(name))
            self.m_filename = path
            self.m_table = _Table(path)
            self.m_jit = dr.is_jit_v(mi.Float)
            self.m_params = self._parameters(props, path)
            self.m_eta = self.m_table.eta
            tables_file = self.m_table.format == "tables"
            self.m_transmits = self.m_table.transmits()
            mode = self._choose_mode(props, path, current)
            self.m_mode = mode
            self.m_tables = None
            self.m_lobes = False
            self.m_textured = False
            self.m_tables_source = ""
            self.m_fallback = ""
            fields = None
            if mode == "tables" and tables_file:
                fields, self.m_tables_source = read_tensor_file(path), "the file"
            elif mode == "tables":
                tolerance = float(props["tolerance"]) if "tolerance" in props else 0.0
                cache = bool(props["cache"]) if "cache" in props else True
                try:
                    fields, self.m_tables_source = tables_from_bsdf(
                        self.m_table.handle, path, tolerance, cache)
                except _native.UnsupportedError as error:
                    # A transmissive .bsdf whose tables the loaded library
                    # cannot write (or a textured one whose bases transmit:
                    # the writer makes opaque bases) stays on the Fourier
                    # path by default (asked for "tables", it is refused
                    # with the reason).
                    if "mode" in props or not self.m_transmits:
                        raise
                    mode = "traced" if self.m_jit else "batch"
                    self.m_mode = mode
                    self.m_fallback = "no tables: %s" % error
            if fields is not None and is_textured(fields):
                try:
                    self.m_tables = TexturedTables(fields, path)
                except TensorFileError as error:
                    # A textured table file whose bases the traced tables do
                    # not read (spectral, or with lobe sets of their own)
                    # renders through the C reader unless "tables" was asked.
                    if "mode" in props:
                        raise ValueError('layerlab: "mode": "tables" cannot render %s: %s'
                                         % (path, error)) from None
                    mode = "batch"
                    self.m_mode = mode
                    self.m_fallback = "no tables: %s" % error
                    fields = None
                else:
                    self.m_textured = True
                    # One-sided reflection, as an opaque table file.
                    components = [Flags.GlossyReflection | Flags.FrontSide]
            elif fields is not None:
                self.m_lobes = layout_names(fields) is not None
                if self.m_lobes:
                    # A transmissive file: a table set per lobe and side.
                    self.m_tables = traced_lobes(fields, path)
                    both = Flags.FrontSide | Flags.BackSide
                    components = [Flags.GlossyReflection | both,
                                  Flags.GlossyTransmission | both]
                else:
                    self.m_tables = TracedTables(fields, path)
                    # One-sided reflection, as Mitsuba's `measured` (the
                    # format holds the reflection above the surface).
                    components = [Flags.GlossyReflection | Flags.FrontSide]
            if fields is None:
                both = Flags.FrontSide | Flags.BackSide
                components = [Flags.GlossyReflection | both]
                if self.m_transmits:
                    components.append(Flags.GlossyTransmission | both)
            self.m_components = components
            flags = components[0]
            for c in components[1:]:
                flags = flags | c
            self.m_flags = flags
            self.m_traced = TracedBSDF(self.m_table.handle) if mode == "traced" else None
            if self.m_jit and mode == "batch":
                wavefront_mode()  # (enough when the scene is built on this thread)

        def _choose_mode(self, props, path, variant):
            """The mode asked for, or the default, checked against what the
            file holds and the variant."""
            table = self.m_table
            tables_file = table.format == "tables"
            spectral = tables_file and table.n_wavelengths > 0
            # What the traced tables can render: an RGB table file (opaque,
            # transmissive: a set per lobe and side, or textured: a set per
            # basis), or a .bsdf (made into such a file on load).
            if tables_file:
                why_not = ("it is a spectral table file (its RGB is the C reader's "
                           "conversion of the spectra)" if spectral else None)
            else:
                why_not = None
            if why_not is None:
                default = "tables"
            elif self.m_jit and not tables_file:
                default = "traced"
            else:
                default = "batch"
            mode = str(props["mode"]) if "mode" in props else default
            if mode not in ("tables", "traced", "batch"):
                raise ValueError('layerlab: "mode" is "%s"; it must be "tables", "traced" or '
                                 '"batch"' % mode)
            if mode == "tables" and why_not is not None:
                raise ValueError('layerlab: "mode": "tables" cannot render %s: %s; use '
                                 '"mode": "%s"' % (path, why_not, default))
            if mode == "traced" and tables_file:
                raise ValueError(
                    'layerlab: %s is a table file (the `measured` format): "mode": "traced" '
                    "evaluates the Fourier series of a .bsdf, which it does not hold; use "
                    '"mode": "tables" (its default%s) or "batch" (the C reader\'s batch '
                    'calls), or Mitsuba\'s own {"type": "measured"}'
                    % (path, "" if not spectral else ' for RGB table files'))
            if mode == "traced" and not self.m_jit:
                raise ValueError('layerlab: "mode": "traced" needs a JIT variant (llvm_ad_rgb); '
                                 'the scalar variants use "tables" or "batch"')
            if variant.startswith("cuda") and mode != "tables":
                raise RuntimeError(
                    'layerlab: "mode": "%s" is not supported in the CUDA variant %s: "batch" '
                    'evaluates on the CPU (liblayerlab) and "traced" is written for the LLVM '
                    'variants; %s, or use an LLVM variant such as llvm_ad_rgb'
                    % (mode, variant, '"tables" renders this file' if why_not is None else
                       '"tables" cannot render %s (%s)' % (path, why_not)))
            return mode

        def _parameters(self, props, path):
            """One (name, float or texture) per textured parameter."""
            names = self.m_table.names
            values = []
            for p, name in enumerate(names):
                key = name if name in props else name.replace(".", "_")
                if key not in props:
                    raise ValueError(
                        "layerlab: %s is textured over %s; give each parameter's value as a "
                        "property (a float or a texture): missing \"%s\"%s"
                        % (path, ", ".join(names), name,
                           "" if key == name else ' (or "%s")' % key))
                value = props[key]
                if isinstance(value, (int, float)):
                    value = float(value)
                elif not isinstance(value, mi.Texture):
                    raise ValueError('layerlab: parameter "%s" must be a float or a texture, '
                                     'not %r' % (name, value))
                values.append((name, value))
            return values

        # -------------------------------------------------------- helpers

        def _param_values(self, si, active):
            out = []
            for _, v in self.m_params:
                out.append(mi.Float(v) if isinstance(v, float) else v.eval_1(si, active))
            return out

        def _corners(self, si, active):
            return self.m_traced.basis_corners(self._param_values(si, active))

        def _coeffs(self, si, active, width):
            if not self.m_params:
                return None
            values = []
            for v in self._param_values(si, active):
                a = np.asarray(v.numpy() if dr.is_jit_v(v) else [float(v)], dtype=np.float64)
                values.append(np.broadcast_to(a.ravel(), (width,)) if a.size == 1 else a.ravel())
            return self.m_table.coefficients(values)

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
            if self.m_jit:
                _require_wavefront_mode()
            width = max(dr.width(si.wi), dr.width(wo))
            return width, _packed(si.wi, width, 3), _packed(wo, width, 3)

        # ------------------------------------------------------ traced path

        def _traced_eval_pdf(self, ctx, si, wo, active, want_pdf):
            mu_i, mu_o, cos_phi = _file_axes(si.wi, wo)
            radiance = ctx.mode == mi.TransportMode.Radiance
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi), cos_o)
            f, pdf = self.m_traced.eval_pdf(mu_i, mu_o, cos_phi, self._corners(si, active),
                                            radiance, want_pdf, ok)
            f = dr.select(ok, f * dr.abs(cos_o), 0.0)
            return f, (dr.select(ok, pdf, 0.0) if want_pdf else None)

        def _traced_sample(self, ctx, si, sample2, active):
            wi = si.wi
            mu_i = dr.clip(wi.z * dr.rsqrt(dr.squared_norm(wi)), -1.0, 1.0)
            radiance = ctx.mode == mi.TransportMode.Radiance
            u = dr.clip(sample2, 0.0, 1.0)
            mu_o, phi, pdf, f, ok = self.m_traced.sample(mu_i, u.x, u.y,
                                                         self._corners(si, active), radiance,
                                                         active)
            # pbrt-v3's construction of its wi from phi and mu_o about its
            # wo's azimuth (x when wo is the normal), as ll_bsdf_sample_dir.
            sin_o = dr.sqrt(dr.fma(wi.x, wi.x, wi.y * wi.y))
            has = sin_o > 0
            cx = dr.select(has, wi.x / dr.select(has, sin_o, 1.0), 1.0)
            cy = dr.select(has, wi.y / dr.select(has, sin_o, 1.0), 0.0)
            sin_i = dr.safe_sqrt(1.0 - mu_o * mu_o)
            sp, cp = dr.sincos(phi)
            out = dr.normalize(mi.Vector3f(-sin_i * (cp * cx - sp * cy),
                                           -sin_i * (sp * cx + cp * cy), -mu_o))
            return out, pdf, f, ok

        # ---------------------------------------------------- BSDF interface

        def _tables_enabled(self, ctx):
            return ctx.is_enabled(Flags.GlossyReflection, 0)

        def _lobes_eval_pdf(self, ctx, si, wo, active, want_value, want_pdf):
            radiance = ctx.mode == mi.TransportMode.Radiance
            return self.m_tables.eval_pdf(si.wi, wo, active, radiance,
                                          ctx.is_enabled(Flags.GlossyReflection, 0),
                                          ctx.is_enabled(Flags.GlossyTransmission, 1),
                                          want_value, want_pdf)

        def _textured_eval_pdf(self, ctx, si, wo, active, want_value, want_pdf):
            if not self._tables_enabled(ctx):
                return [mi.Float(0.0)] * 3, mi.Float(0.0)
            value, pdf = self.m_tables.eval_pdf(si.wi, wo, self._param_values(si, active),
                                                active, want_value, want_pdf)
            return value, pdf

        def eval(self, ctx, si, wo, active=True):
            if self.m_textured:
                return mi.Color3f(*self._textured_eval_pdf(ctx, si, wo, active, True, False)[0])
            if self.m_lobes:
                return mi.Color3f(*self._lobes_eval_pdf(ctx, si, wo, active, True, False)[0])
            if self.m_tables is not None:
                if not self._tables_enabled(ctx):
                    return mi.Color3f(0.0)
                value, _ = self.m_tables.eval_pdf(si.wi, wo, active, True, False)
                return mi.Color3f(*value)
            if self.m_traced is not None:
                return self._traced_eval_pdf(ctx, si, wo, active, False)[0]
            width, a, b = self._pairs(si, wo)
            coeffs = self._coeffs(si, active, width)
            f = self._out_color(self.m_table.eval(a, b, self._mode(ctx), coeffs))
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi), cos_o)
            return dr.select(ok, f * dr.abs(cos_o), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if self.m_textured:
                return self._textured_eval_pdf(ctx, si, wo, active, False, True)[1]
            if self.m_lobes:
                return self._lobes_eval_pdf(ctx, si, wo, active, False, True)[1]
            if self.m_tables is not None:
                if not self._tables_enabled(ctx):
                    return mi.Float(0.0)
                return self.m_tables.eval_pdf(si.wi, wo, active, False, True)[1]
            if self.m_traced is not None:
                return self._traced_eval_pdf(ctx, si, wo, active, True)[1]
            width, a, b = self._pairs(si, wo)
            coeffs = self._coeffs(si, active, width)
            p = self._out_float(self.m_table.pdf(a, b, coeffs))
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi),
                                          mi.Frame3f.cos_theta(wo))
            return dr.select(ok, p, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            if self.m_textured:
                value, pdf = self._textured_eval_pdf(ctx, si, wo, active, True, True)
                return mi.Color3f(*value), pdf
            if self.m_lobes:
                value, pdf = self._lobes_eval_pdf(ctx, si, wo, active, True, True)
                return mi.Color3f(*value), pdf
            if self.m_tables is not None:
                if not self._tables_enabled(ctx):
                    return mi.Color3f(0.0), mi.Float(0.0)
                # One inversion of the VNDF warp for both (Mitsuba's
                # `measured` evaluates them separately).
                value, pdf = self.m_tables.eval_pdf(si.wi, wo, active, True, True)
                return mi.Color3f(*value), pdf
            if self.m_traced is not None:
                return self._traced_eval_pdf(ctx, si, wo, active, True)
            width, a, b = self._pairs(si, wo)
            coeffs = self._coeffs(si, active, width)
            f = self._out_color(self.m_table.eval(a, b, self._mode(ctx), coeffs))
            p = self._out_float(self.m_table.pdf(a, b, coeffs))
            cos_o = mi.Frame3f.cos_theta(wo)
            ok = active & self._lobe_mask(ctx, mi.Frame3f.cos_theta(si.wi), cos_o)
            return dr.select(ok, f * dr.abs(cos_o), 0.0), dr.select(ok, p, 0.0)

        def _lobes_sample(self, ctx, si, sample2, active):
            bs = dr.zeros(mi.BSDFSample3f)
            radiance = ctx.mode == mi.TransportMode.Radiance
            wo, pdf, weight, ok, transmitted = self.m_tables.sample(
                si.wi, sample2, active, radiance, ctx.is_enabled(Flags.GlossyReflection, 0),
                ctx.is_enabled(Flags.GlossyTransmission, 1))
            bs.wo = wo
            bs.pdf = pdf
            eta = mi.Float(self.m_tables.eta)
            entering = mi.Frame3f.cos_theta(si.wi) > 0
            bs.eta = dr.select(transmitted, dr.select(entering, eta, dr.rcp(eta)), 1.0)
            bs.sampled_type = dr.select(transmitted, mi.UInt32(+Flags.GlossyTransmission),
                                        mi.UInt32(+Flags.GlossyReflection))
            bs.sampled_component = dr.select(transmitted, mi.UInt32(1), mi.UInt32(0))
            return bs, mi.Color3f(*weight)

        def _tables_sample(self, ctx, si, sample2, active):
            bs = dr.zeros(mi.BSDFSample3f)
            if not self._tables_enabled(ctx):
                return bs, mi.Color3f(0.0)
            if self.m_textured:
                wo, pdf, weight, ok = self.m_tables.sample(
                    si.wi, sample2, self._param_values(si, active), active)
            else:
                wo, pdf, weight, ok = self.m_tables.sample(si.wi, sample2, active)
            bs.wo = wo
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+Flags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, mi.Color3f(*weight)

        def sample(self, ctx, si, sample1, sample2, active=True):
            if self.m_lobes:
                return self._lobes_sample(ctx, si, sample2, active)
            if self.m_tables is not None:
                return self._tables_sample(ctx, si, sample2, active)
            bs = dr.zeros(mi.BSDFSample3f)
            if self.m_traced is not None:
                bs.wo, pdf, f, found = self._traced_sample(ctx, si, sample2, active)
                bs.pdf = pdf
            else:
                if self.m_jit:
                    _require_wavefront_mode()
                width = max(dr.width(si.wi), dr.width(sample2))
                a = _packed(si.wi, width, 3)
                u = np.clip(_packed(sample2, width, 2), 0.0, 1.0)
                wi, pdf, rgb = self.m_table.sample(a, u, self._mode(ctx),
                                                   self._coeffs(si, active, width))
                bs.wo = self._out_vector(wi)
                bs.pdf = self._out_float(pdf)
                f = self._out_color(rgb)
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
            weight = f * dr.abs(cos_o) / dr.select(ok, bs.pdf, 1.0)
            return bs, dr.select(ok, weight, 0.0)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            tables = ""
            if self.m_tables is not None:
                tables = ", tables=%s (%s)" % (self.m_tables.describe(), self.m_tables_source)
            if self.m_fallback:
                tables = ", %s" % self.m_fallback
            return ("LayerlabBSDF[filename=\"%s\", format=%s, eta=%g, transmission=%s, mode=%s%s%s]"
                    % (self.m_filename, self.m_table.format, self.m_eta, self.m_transmits,
                       self.m_mode, tables,
                       "".join(", %s=%s" % (n, v) for n, v in self.m_params)))

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
