"""``BSDFStorage``: ``.bsdf`` files ("SCATFUN" v1, the format pbrt-v3's
``fourier`` material reads) written from layers, opened, evaluated and
sampled, over ``ll_bsdf`` in ``layerlab/ll_bsdf.h``."""

import ctypes
import json
import math
import os
import weakref

import numpy as np

from ._errors import InvalidArgumentError, UnsupportedError
from ._native import (BsdfInfo, BsdfWriteOptions, bsdf_p, c_double_p, c_float_p, check, fspath,
                      layer_p, lib)
from ._util import count_argument, real_argument
from .layer import Layer

__all__ = ["BSDFStorage", "mem_string"]

_TRANSPORT = {"radiance": 0, "importance": 1}


def mem_string(size):
    """A byte count as the original layerlab printed it: "3.3 MiB", "512 B"."""
    value = float(size)
    suffixes = ("B", "KiB", "MiB", "GiB", "TiB", "PiB")
    k = 0
    while k < len(suffixes) - 1 and value > 1024.0:
        value /= 1024.0
        k += 1
    return "%.*f %s" % (0 if k == 0 else 1, value, suffixes[k])


def _alpha_pair(alpha):
    """Header roughness (top, bottom); one number sets both."""
    if np.ndim(alpha) == 0:
        a = real_argument(alpha, "alpha")
        return a, a
    values = [real_argument(a, "alpha") for a in alpha]
    if len(values) != 2:
        raise InvalidArgumentError("alpha must be one number or a (top, bottom) pair, got %d "
                                   "values" % len(values))
    return values[0], values[1]


def _write(filename, layers, eta, alpha, metadata, errorGoal):
    for k, layer in enumerate(layers):
        if not isinstance(layer, Layer):
            raise TypeError("layer %d must be a layerlab.Layer, not %s" % (k, type(layer).__name__))
    opts = BsdfWriteOptions()
    opts.eta = real_argument(eta, "eta")
    opts.alpha[0], opts.alpha[1] = _alpha_pair(alpha)
    opts.metadata = None if metadata is None else str(metadata).encode("utf-8")
    opts.error_goal = real_argument(errorGoal, "errorGoal")
    handles = (layer_p * len(layers))(*[layer._handle for layer in layers])
    check(lib.ll_bsdf_write(fspath(filename), handles, len(layers), ctypes.byref(opts), None))


def _parameter_grid(nBases, nParameters, paramSampleCounts, paramSamplePositions):
    """The textured writer's parameter arrays from fromLayerGeneral's
    arguments: counts (size_t[]) and positions (double[], parameter 0's
    first). Positions may be one flat list (with paramSampleCounts, as the
    original layerlab takes them) or one list per parameter."""
    if paramSamplePositions is None:
        positions = []
    else:
        positions = list(paramSamplePositions)
    nested = any(np.ndim(p) > 0 for p in positions)
    if nested:
        per_parameter = [[real_argument(v, "paramSamplePositions") for v in p] for p in positions]
        counts = [len(p) for p in per_parameter]
        if paramSampleCounts is not None and list(paramSampleCounts) != counts:
            raise InvalidArgumentError("paramSampleCounts %s disagree with the lists of "
                                       "paramSamplePositions %s" % (list(paramSampleCounts),
                                                                    counts))
        flat = [v for p in per_parameter for v in p]
    else:
        counts = [count_argument(c, "paramSampleCounts") for c in (paramSampleCounts or [])]
        flat = [real_argument(v, "paramSamplePositions") for v in positions]
        if sum(counts) != len(flat):
            raise InvalidArgumentError("paramSampleCounts %s add up to %d, but %d "
                                       "paramSamplePositions are given"
                                       % (counts, sum(counts), len(flat)))
    if nParameters is None:
        nParameters = len(counts)
    nParameters = count_argument(nParameters, "nParameters")
    if nParameters != len(counts):
        raise InvalidArgumentError("nParameters = %d, but %d parameters have sample positions"
                                   % (nParameters, len(counts)))
    product = 1
    for c in counts:
        product *= c
    if nBases is None:
        nBases = product
    nBases = count_argument(nBases, "nBases")
    if nBases != product:
        raise InvalidArgumentError("nBases = %d, but the parameters' sample counts %s make %d"
                                   % (nBases, counts, product))
    return nBases, counts, flat


def _metadata_with_names(metadata, names, nParameters):
    """The metadata text that carries the parameter names ("parameters": a
    JSON array, what ll_bsdf_get_parameter_name reads); None keeps the
    library's default JSON (names p0, p1, ...)."""
    if names is None:
        return metadata
    names = [str(n) for n in names]
    if len(names) != nParameters:
        raise InvalidArgumentError("paramNames has %d names for %d parameters"
                                   % (len(names), nParameters))
    if len(set(names)) != len(names) or any(not n or len(n.encode("utf-8")) > 255 for n in names):
        raise InvalidArgumentError("paramNames must be distinct, non-empty and at most 255 "
                                   "bytes each: %r" % (names,))
    if metadata is None:
        document = {"generator": "layerlab (Python, BSDFStorage.fromLayerGeneral)"}
    else:
        try:
            document = json.loads(str(metadata))
        except ValueError:
            document = None
        if not isinstance(document, dict):
            raise InvalidArgumentError("paramNames are stored in the metadata's JSON object; "
                                       "metadata must then be one (or None)")
    document["parameters"] = names
    return json.dumps(document, indent=2)


def _vector3(v, name):
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,):
        raise InvalidArgumentError("%s must be a 3-vector, got shape %s" % (name, a.shape))
    return (ctypes.c_double * 3)(*a)


def _uniform_pair(sample):
    a = np.asarray(sample, dtype=np.float64)
    if a.shape != (2,):
        raise InvalidArgumentError("sample must be two uniform numbers in [0, 1], got shape %s"
                                   % (a.shape,))
    return (ctypes.c_double * 2)(*a)


def _broadcast_points(*arrays):
    """The broadcast shape of the arguments and their values as flat lists
    (plain floats: the cheapest thing to hand to ctypes point by point)."""
    arrays = np.broadcast_arrays(*[np.asarray(a, np.float64) for a in arrays])
    return arrays[0].shape, [a.reshape(-1).tolist() for a in arrays]


def _transport(mode):
    try:
        return _TRANSPORT[mode]
    except (KeyError, TypeError):
        raise InvalidArgumentError("mode must be 'radiance' or 'importance', not %r"
                                   % (mode,)) from None


class BSDFStorage:
    """An opened ``.bsdf`` file: an isotropic BSDF stored as Catmull-Rom
    splines in the two zenith cosines and a Fourier series in the azimuth.

    ``BSDFStorage(filename)`` opens and fully validates a file (a damaged
    one raises :class:`layerlab.FormatError`, an unreadable one
    :class:`OSError`). Files are created with :meth:`fromLayer` and
    :meth:`fromLayerRGB`. An opened file is immutable; :meth:`close` (or a
    ``with`` block) releases it early.

    Two conventions: :meth:`eval`, :meth:`pdf` and :meth:`sample` take zenith
    cosines as :meth:`Layer.eval` does (``mu_i > 0`` arrives from above,
    reflection goes to ``mu_o < 0``); :meth:`evalDir`, :meth:`pdfDir` and
    :meth:`sampleDir` take a renderer's directions (local frame, z = normal,
    ``wo`` to the viewer, ``wi`` to the light, both pointing away).
    """

    def __init__(self, filename, readOnly=True):
        if not readOnly:
            raise UnsupportedError("BSDFStorage: opened files are immutable; write a new file "
                                   "with fromLayer()/fromLayerRGB()", 6)
        handle = bsdf_p()
        check(lib.ll_bsdf_open(fspath(filename), None, ctypes.byref(handle)))
        self._init(handle, os.fspath(filename))

    @classmethod
    def fromBytes(cls, data, name="<memory>"):
        """Open a ``.bsdf`` file held in memory (``bytes`` or any buffer)."""
        data = bytes(data)
        handle = bsdf_p()
        check(lib.ll_bsdf_open_memory(data, len(data), None, ctypes.byref(handle)))
        self = cls.__new__(cls)
        self._init(handle, name)
        return self

    def _init(self, handle, filename):
        self._handle = handle
        self._finalizer = weakref.finalize(self, lib.ll_bsdf_release, handle)
        self.filename = filename
        info = BsdfInfo()
        check(lib.ll_bsdf_get_info(handle, ctypes.byref(info)))
        self._info = info
        raw = info.metadata or b""
        self._metadata = raw.decode("utf-8", "replace")

    def _live(self):
        if self._handle is None:
            raise ValueError("BSDFStorage %r is closed" % self.filename)
        return self._handle

    def close(self):
        """Release the file now (it is released anyway when the object goes)"""
        self._finalizer()
        self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------ writing

    @classmethod
    def fromLayer(cls, filename, layer, eta=1.0, alpha=0.0, metadata=None, errorGoal=1e-3):
        """fromLayer(filename, layer, eta=1.0, alpha=0.0, metadata=None,
        errorGoal=1e-3) -> BSDFStorage

        Create a BSDF storage file from a Layer (monochromatic) and open it.
        The file is written atomically: on failure an existing file is left
        untouched.

        Parameter ``eta``:
            The header's relative index, eta(bottom) / eta(top); 1 for an
            opaque stack (renderers use it for refraction)

        Parameter ``alpha``:
            The header's Beckmann roughness: one number, or the pair (top
            interface, bottom interface); informational

        Parameter ``metadata``:
            Text stored in the file (default: a JSON description)

        Parameter ``errorGoal``:
            Each Fourier series is cut where the tail's sum falls below this
            fraction of its first coefficient (default 1e-3)
        """
        _write(filename, [layer], eta, alpha, metadata, errorGoal)
        return cls(filename)

    @classmethod
    def fromLayerRGB(cls, filename, layerR, layerG, layerB, eta=1.0, alpha=0.0, metadata=None,
                     errorGoal=1e-3):
        """fromLayerRGB(filename, layerR, layerG, layerB, eta=1.0, alpha=0.0,
        metadata=None, errorGoal=1e-3) -> BSDFStorage

        Create a BSDF storage file from three Layers (RGB; stored as Y, R, B)
        and open it. The layers must share their nodes and order count. The
        keyword arguments are those of :meth:`fromLayer`.
        """
        _write(filename, [layerR, layerG, layerB], eta, alpha, metadata, errorGoal)
        return cls(filename)

    @classmethod
    def fromLayerGeneral(cls, filename, layers, nChannels=1, nBases=None, nParameters=None,
                         paramSampleCounts=None, paramSamplePositions=None, extrapolate=False,
                         metadata=None, paramNames=None, eta=1.0, alpha=0.0, errorGoal=1e-3):
        """fromLayerGeneral(filename, layers, nChannels=1, nBases=None,
        nParameters=None, paramSampleCounts=None, paramSamplePositions=None,
        extrapolate=False, metadata=None, paramNames=None, eta=1.0,
        alpha=0.0, errorGoal=1e-3) -> BSDFStorage

        Create a (possibly textured) BSDF storage file from layers built by
        hand, as the original layerlab's ``fromLayerGeneral``, and open it
        (``ll_bsdf_write_textured``; atomic).

        Parameter ``layers``:
            nBases * nChannels layers, basis-major: ``layers[b * nChannels +
            c]`` is channel c (R, G, B for three) of basis b; the basis index
            runs over parameter 0 fastest. All share nodes and order count.

        Parameter ``paramSamplePositions``:
            One list of strictly increasing sample positions per parameter
            (``[[0.05, 0.1, 0.2], [0.1, 0.3]]``), or the original's flat list
            with ``paramSampleCounts``. ``nBases`` and ``nParameters``
            default to what the positions imply and must agree with them.

        Parameter ``paramNames``:
            The parameters' names (``["coat.alpha", "base.alpha"]``), stored
            as the metadata's JSON key "parameters" (merged into
            ``metadata`` when that is a JSON object); without them the file's
            parameters are called ``p0``, ``p1``, ...

        ``extrapolate=True`` (harmonic extrapolation) is not supported, as
        by the C writer. The other keyword arguments are those of
        :meth:`fromLayer`.
        """
        if extrapolate:
            raise UnsupportedError("fromLayerGeneral: harmonic extrapolation is not supported "
                                   "(the reader refuses such files too)", 6)
        nChannels = count_argument(nChannels, "nChannels")
        if nChannels not in (1, 3):
            raise InvalidArgumentError("nChannels must be 1 or 3, not %d" % nChannels)
        layers = list(layers)
        nBases, counts, positions = _parameter_grid(nBases, nParameters, paramSampleCounts,
                                                    paramSamplePositions)
        if len(layers) != nBases * nChannels:
            raise InvalidArgumentError("%d layers given; %d bases x %d channels need %d"
                                       % (len(layers), nBases, nChannels, nBases * nChannels))
        for k, layer in enumerate(layers):
            if not isinstance(layer, Layer):
                raise TypeError("layer %d must be a layerlab.Layer, not %s"
                                % (k, type(layer).__name__))
        opts = BsdfWriteOptions()
        opts.eta = real_argument(eta, "eta")
        opts.alpha[0], opts.alpha[1] = _alpha_pair(alpha)
        text = _metadata_with_names(metadata, paramNames, len(counts))
        opts.metadata = None if text is None else str(text).encode("utf-8")
        opts.error_goal = real_argument(errorGoal, "errorGoal")
        handles = (layer_p * len(layers))(*[layer._handle for layer in layers])
        c_counts = (ctypes.c_size_t * max(1, len(counts)))(*counts)
        c_positions = (ctypes.c_double * max(1, len(positions)))(*positions)
        check(lib.ll_bsdf_write_textured(fspath(filename), handles, nChannels, len(counts),
                                         c_counts, c_positions, ctypes.byref(opts), None))
        return cls(filename)

    # ------------------------------------------------------------ header

    @property
    def nodeCount(self):
        """The number of zenith-cosine nodes (two of them at mu = 0)"""
        return self._info.n_nodes

    @property
    def maxOrder(self):
        """The length of the longest Fourier series"""
        return self._info.max_order

    @property
    def channelCount(self):
        """The number of color channels (1 or 3)"""
        return self._info.n_channels

    @property
    def basisCount(self):
        """The number of basis functions (1 unless textured)"""
        return self._info.n_bases

    @property
    def parameterCount(self):
        """The number of textured parameters"""
        return self._info.n_parameters

    @property
    def coefficientCount(self):
        """The number of float32 Fourier coefficients stored"""
        return self._info.n_coeffs

    @property
    def size(self):
        """The size of the file in bytes"""
        return self._info.file_size

    @property
    def metadata(self):
        """The metadata text stored in the file"""
        return self._metadata

    @property
    def eta(self):
        """The relative index of refraction, eta(bottom) / eta(top)"""
        return self._info.eta

    @property
    def format(self):
        """Which format the file is in: "fourier" (a .bsdf) or "tables" (the
        `measured` format of Mitsuba 3 and pbrt-v4, docs/formats.md)"""
        return "tables" if self._info.format == 1 else "fourier"

    @property
    def wavelengths(self):
        """The number of wavelengths of a spectral table file (read as linear
        sRGB: D65, CIE 1931; ll_bsdf.h), 0 for RGB tables and .bsdf files"""
        return self._info.n_wavelengths

    @property
    def extrapolated(self):
        """Whether the file uses harmonic extrapolation (header flag 2)"""
        return bool(self._info.flags & 2)

    def alpha(self, i):
        """The Beckmann roughness of interface ``i`` (0: top, 1: bottom)"""
        i = count_argument(i, "i")
        if i >= 2:
            raise IndexError("alpha index %d is not 0 (top) or 1 (bottom)" % i)
        return self._info.alpha[i]

    @property
    def nodes(self):
        """The file's zenith-cosine nodes (ascending; a float32 copy)"""
        ptr = lib.ll_bsdf_nodes(self._live())
        return np.ctypeslib.as_array(ptr, shape=(self.nodeCount,)).copy()

    def _parameter(self, i):
        i = count_argument(i, "i")
        if i >= self.parameterCount:
            raise IndexError("parameter %d is beyond the file's %d" % (i, self.parameterCount))
        count = ctypes.c_size_t()
        positions = c_float_p()
        check(lib.ll_bsdf_get_parameter(self._live(), i, ctypes.byref(count),
                                        ctypes.byref(positions)))
        if count.value == 0:
            return np.empty(0, np.float32)
        return np.ctypeslib.as_array(positions, shape=(count.value,)).copy()

    def parameterSampleCount(self, i):
        """The number of samples of textured parameter ``i``"""
        return self._parameter(i).size

    def parameterSamplePositions(self, i):
        """The sample positions of textured parameter ``i`` (a list)"""
        return [float(x) for x in self._parameter(i)]

    def parameterName(self, i):
        """The name of textured parameter ``i``: from the file's metadata
        (its JSON key "parameters"), else ``"p<i>"``"""
        i = count_argument(i, "i")
        if i >= self.parameterCount:
            raise IndexError("parameter %d is beyond the file's %d" % (i, self.parameterCount))
        name = ctypes.c_char_p()
        check(lib.ll_bsdf_get_parameter_name(self._live(), i, ctypes.byref(name)))
        return name.value.decode("utf-8", "replace")

    @property
    def parameterNames(self):
        """The names of the textured parameters, in the file's order"""
        return [self.parameterName(i) for i in range(self.parameterCount)]

    @property
    def axes(self):
        """The textured parameters as a list of ``(name, positions)`` pairs
        in the file's order (positions: a float64 array of the samples);
        empty for an untextured file. The bases run over the first axis
        fastest."""
        return [(self.parameterName(i), self._parameter(i).astype(np.float64))
                for i in range(self.parameterCount)]

    def basisCoefficients(self, params):
        """basisCoefficients(params) -> numpy float32 array (basisCount,)

        The weights of the file's bases at one point of parameter space
        (``ll_bsdf_basis_coefficients``: products of linear weights, >= 0,
        summing to 1; values outside a parameter's samples are clamped).
        ``params``: one value per parameter in the file's order, or a dict
        {name: value} that names every parameter.
        """
        n = self.parameterCount
        if n == 0:
            raise InvalidArgumentError("%s is not textured: it has no parameters" % self.filename)
        if isinstance(params, dict):
            names = self.parameterNames
            unknown = sorted(set(params) - set(names))
            missing = [name for name in names if name not in params]
            if unknown or missing:
                problems = (["unknown %s" % unknown] if unknown else []) + \
                           (["missing %s" % missing] if missing else [])
                raise InvalidArgumentError("params for %s: %s (the file's parameters are %s)"
                                           % (self.filename, "; ".join(problems), names))
            values = [real_argument(params[name], name) for name in names]
        else:
            values = [real_argument(v, "params") for v in np.ravel(np.asarray(params, dtype=object))]
            if len(values) != n:
                raise InvalidArgumentError("params has %d values; %s has %d parameters (%s)"
                                           % (len(values), self.filename, n,
                                              ", ".join(self.parameterNames)))
        for v in values:
            if not math.isfinite(v):
                raise InvalidArgumentError("params: %r is not finite" % v)
        c_values = (ctypes.c_double * n)(*values)
        coeffs = np.empty(self.basisCount, dtype=np.float32)
        check(lib.ll_bsdf_basis_coefficients(self._live(), ctypes.cast(c_values, c_double_p),
                                             coeffs.ctypes.data_as(c_float_p)))
        return coeffs

    # ------------------------------------------------------------ evaluation

    def _basis(self, basisCoeffs, params=None):
        if params is not None:
            if basisCoeffs is not None:
                raise InvalidArgumentError("give basisCoeffs or params, not both")
            basisCoeffs = self.basisCoefficients(params)
        if basisCoeffs is None:
            return None, None
        coeffs = np.ascontiguousarray(basisCoeffs, dtype=np.float32).reshape(-1)
        if coeffs.size != self.basisCount:
            raise InvalidArgumentError("basisCoeffs has %d values; the file has %d basis "
                                       "functions" % (coeffs.size, self.basisCount))
        return coeffs, coeffs.ctypes.data_as(c_float_p)

    def eval(self, mu_i, mu_o, phi_d=0.0, basisCoeffs=None, params=None):
        """eval(mu_i, mu_o, phi_d=0, basisCoeffs=None, params=None) -> numpy array (..., 3)

        Evaluate the model (the BSDF without cosine factor, R, G, B; three
        equal values for a one-channel file) for the given values of mu_i,
        mu_o and phi_d. Numbers or arrays that broadcast together; the
        result has the broadcast shape plus a last axis of 3.

        A textured file needs its basis weights: ``basisCoeffs`` (basisCount
        values) or ``params``, the point of parameter space
        (:meth:`basisCoefficients`: a value per parameter, or a dict by
        name). The same holds for pdf, sample and the *Dir calls.
        """
        handle = self._live()
        _keep, coeffs = self._basis(basisCoeffs, params)
        shape, points = _broadcast_points(mu_i, mu_o, phi_d)
        out = np.empty((len(points[0]), 3))
        rgb = (ctypes.c_double * 3)()
        fn = lib.ll_bsdf_eval
        for k, (mi, mo, ph) in enumerate(zip(*points)):
            check(fn(handle, mi, mo, ph, coeffs, rgb))
            out[k] = rgb
        return out.reshape(shape + (3,))

    def pdf(self, mu_i, mu_o, phi_d=0.0, basisCoeffs=None, params=None):
        """pdf(mu_i, mu_o, phi_d=0, basisCoeffs=None, params=None) -> float or numpy array

        The probability density per solid angle with which :meth:`sample`
        picks (mu_o, phi_d) given mu_i. Broadcasts like :meth:`eval`.
        """
        handle = self._live()
        _keep, coeffs = self._basis(basisCoeffs, params)
        shape, points = _broadcast_points(mu_i, mu_o, phi_d)
        fn = lib.ll_bsdf_pdf
        out = np.empty(len(points[0]))
        value = ctypes.c_double()
        for k, (mi, mo, ph) in enumerate(zip(*points)):
            check(fn(handle, mi, mo, ph, coeffs, ctypes.byref(value)))
            out[k] = value.value
        out = out.reshape(shape)
        return float(out) if out.ndim == 0 else out

    def albedo(self, mu_i, basisCoeffs=None, params=None):
        """albedo(mu_i, basisCoeffs=None, params=None) -> (reflected, transmitted)

        The directional albedo for light arriving along ``mu_i`` (a number,
        layer convention as :meth:`eval`): two (R, G, B) arrays, the
        fraction reflected and the fraction transmitted, at the file's own
        accuracy (its order-0 series integrated with its own splines; the
        mean of :meth:`sample`'s weights). A table file raises
        :class:`layerlab.UnsupportedError`.
        """
        handle = self._live()
        _keep, coeffs = self._basis(basisCoeffs, params)
        reflected, transmitted = (ctypes.c_double * 3)(), (ctypes.c_double * 3)()
        check(lib.ll_bsdf_albedo(handle, float(mu_i), coeffs, reflected, transmitted))
        return np.array(reflected[:]), np.array(transmitted[:])

    def sample(self, mu_i, sample, basisCoeffs=None, params=None):
        """sample(mu_i, sample, basisCoeffs=None, params=None) -> (weight, mu_o, phi_d, pdf)

        Importance sample the model for light arriving along ``mu_i``, from
        two uniform numbers ``sample`` in [0, 1]. Returns the weight
        f * |mu_o| / pdf (R, G, B array), the sampled mu_o and phi_d, and the
        pdf. A zero weight and pdf mean that no direction was found.
        """
        handle = self._live()
        _keep, coeffs = self._basis(basisCoeffs, params)
        mu_o, phi_d, pdf = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
        f = (ctypes.c_double * 3)()
        check(lib.ll_bsdf_sample(handle, real_argument(mu_i, "mu_i"), _uniform_pair(sample),
                                 coeffs, ctypes.byref(mu_o), ctypes.byref(phi_d),
                                 ctypes.byref(pdf), f))
        # The library returns f; this method keeps the original layerlab's
        # weight.
        weight = np.array(f) * abs(mu_o.value) / pdf.value if pdf.value > 0.0 else np.zeros(3)
        return weight, mu_o.value, phi_d.value, pdf.value

    def evalDir(self, wo, wi, mode="radiance", basisCoeffs=None, params=None):
        """evalDir(wo, wi, mode="radiance", basisCoeffs=None, params=None) -> numpy array (3,)

        The BSDF value f(wo, wi) (no cosine) for renderer directions in the
        local shading frame, as pbrt-v3's ``BxDF::f``. ``mode`` is
        "radiance" (scales by eta^2 across a dielectric, as radiance
        requires) or "importance".
        """
        _keep, coeffs = self._basis(basisCoeffs, params)
        rgb = (ctypes.c_double * 3)()
        check(lib.ll_bsdf_eval_dir(self._live(), _vector3(wo, "wo"), _vector3(wi, "wi"),
                                   _transport(mode), coeffs, rgb))
        return np.array(rgb)

    def pdfDir(self, wo, wi, basisCoeffs=None, params=None):
        """pdfDir(wo, wi, basisCoeffs=None, params=None) -> float

        The density (per solid angle) of sampling ``wi`` given ``wo``, as
        pbrt-v3's ``Pdf(wo, wi)``.
        """
        _keep, coeffs = self._basis(basisCoeffs, params)
        value = ctypes.c_double()
        check(lib.ll_bsdf_pdf_dir(self._live(), _vector3(wo, "wo"), _vector3(wi, "wi"), coeffs,
                                  ctypes.byref(value)))
        return value.value

    def sampleDir(self, wo, sample, mode="radiance", basisCoeffs=None, params=None):
        """sampleDir(wo, sample, mode="radiance", basisCoeffs=None, params=None) -> (f, wi, pdf)

        Sample ``wi`` given ``wo`` as pbrt-v3's ``FourierBSDF::Sample_f``
        does (the same ``sample`` gives the same direction); returns f(wo,
        wi) (R, G, B array), the unit vector ``wi`` and its pdf.
        """
        _keep, coeffs = self._basis(basisCoeffs, params)
        wi = (ctypes.c_double * 3)()
        rgb = (ctypes.c_double * 3)()
        pdf = ctypes.c_double()
        check(lib.ll_bsdf_sample_dir(self._live(), _vector3(wo, "wo"), _uniform_pair(sample),
                                     _transport(mode), coeffs, wi, ctypes.byref(pdf), rgb))
        return np.array(rgb), np.array(wi), pdf.value

    def __repr__(self):
        mmap = 'MemoryMappedFile[filename="%s", size=%s]' % (self.filename,
                                                              mem_string(self.size))
        if self._handle is None:
            return "BSDFStorage[mmap = %s, closed]" % mmap
        return ("BSDFStorage[mmap = %s, nNodes = %d, nMaxOrder = %d, nChannels = %d, "
                "nBases = %d, eta = %s]" % (mmap, self.nodeCount, self.maxOrder,
                                            self.channelCount, self.basisCount,
                                            "%g" % self.eta))
