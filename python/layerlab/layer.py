"""``Layer``: the discretised scattering of one layer or interface, and the
adding-doubling operations that combine layers (Jakob et al. 2014, sections
4-6), over ``ll_layer`` in ``layerlab/ll_layer.h``."""

import ctypes
import weakref

import numpy as np

from ._errors import InvalidArgumentError
from ._native import (MICROFACET_BECKMANN, MICROFACET_GGX, Microfacet, check, fspath, layer_p,
                      lib)
from ._util import count_argument, double_ptr, real_argument, vector_argument

__all__ = ["Layer", "parameterHeuristicMicrofacet", "parameterHeuristicHG",
           "fresnelDielectric", "fresnelConductor", "fresnelDielectricIntegral",
           "fresnelConductorIntegral", "complex_argument"]


def complex_argument(value, name):
    """(real, imaginary) parts of a complex or real number argument."""
    try:
        z = complex(value)
    except (TypeError, ValueError):
        raise TypeError("%s must be a number, not %r" % (name, value)) from None
    return z.real, z.imag


class Layer:
    """Discretized layer reflection model

    Describes how a layer (or an interface) responds to light arriving along
    a chosen set of zenith angles. The zenith-angle cosines are the nodes of
    a quadrature rule; the azimuthal dependence is an even Fourier series,
    one scattering matrix per order. Layers are combined with the adding
    equations (:meth:`add`, :meth:`addToTop`, :meth:`addToBottom`) and
    thickened by doubling (:meth:`expand`).

    Conventions (the original layerlab's): a cosine ``mu > 0`` travels down
    (light arriving from above), ``mu < 0`` travels up; a layer lit from
    above reflects into ``mu_o < 0`` and transmits into ``mu_o > 0``.

    ``Layer(nodes, weights, fourierOrders=1)`` creates a clear layer (no
    reflection, full transmission); ``Layer(other)`` copies a layer.

    Threads: a layer may be read (eval, matrix, albedo) from many threads at
    once, but a call that changes it (a setter, adding, expand, reverse,
    clear) must not overlap any other call on the same layer. The library
    releases the GIL while it computes and uses its own worker threads
    (see :func:`layerlab.setThreadCount`).

    Parameter ``nodes``:
        The zenith-angle cosines of the discretisation: an even number of
        them, symmetric about 0, none at 0 (e.g. ``quad.gaussLobatto(n)``)

    Parameter ``weights``:
        The integration weight of each node (positive)

    Parameter ``fourierOrders``:
        Number of coefficients of the azimuthal Fourier expansion
        (default: 1). ``nFourierOrders`` is accepted as an alias.
    """

    def __init__(self, nodes, weights=None, fourierOrders=1, nFourierOrders=None):
        out = layer_p()
        if isinstance(nodes, Layer):
            if weights is not None:
                raise TypeError("Layer(other) copies a layer and takes no weights")
            check(lib.ll_layer_clone(nodes._handle, ctypes.byref(out)))
        else:
            if weights is None:
                raise TypeError("Layer() needs nodes and weights (or a Layer to copy)")
            if nFourierOrders is not None:
                fourierOrders = nFourierOrders
            nodes = vector_argument(nodes, "nodes")
            weights = vector_argument(weights, "weights")
            if nodes.size != weights.size:
                raise InvalidArgumentError("Layer: %d nodes but %d weights"
                                           % (nodes.size, weights.size))
            m = count_argument(fourierOrders, "fourierOrders")
            check(lib.ll_layer_create(double_ptr(nodes), double_ptr(weights), nodes.size, m,
                                      ctypes.byref(out)))
        self._adopt(out)

    def _adopt(self, handle):
        self._handle = handle
        self._finalizer = weakref.finalize(self, lib.ll_layer_destroy, handle)

    @property
    def _as_parameter_(self):
        return self._handle

    # ------------------------------------------------------------ copies

    def __copy__(self):
        return Layer(self)

    def __deepcopy__(self, memo):
        return Layer(self)

    copy = __copy__

    def __reduce__(self):
        # The C API reads matrices but cannot set them, so a layer cannot be
        # rebuilt from its data; say so instead of pickling a dead pointer.
        raise TypeError("layerlab.Layer cannot be pickled; write it with "
                        "BSDFStorage.fromLayer() or rebuild it from its recipe")

    # ------------------------------------------------------------ words

    def setDiffuse(self, albedo):
        """Initialize the layer with a diffuse (Lambertian) reflector

        Parameter ``albedo``:
            The layer's diffuse reflectance (in ``[0, 1]``); the BSDF is
            albedo / pi on both sides, with no transmission
        """
        check(lib.ll_layer_set_diffuse(self._handle, real_argument(albedo, "albedo"), None))

    def setIsotropic(self, albedo):
        """Initialize the layer with an isotropic phase function

        The layer then describes an infinitesimally thin medium; give it a
        thickness with :meth:`expand`.

        Parameter ``albedo``:
            The medium's single scattering albedo (in ``[0, 1]``)
        """
        check(lib.ll_layer_set_isotropic(self._handle, real_argument(albedo, "albedo"), None))

    def setHenyeyGreenstein(self, albedo, g):
        """Initialize the layer with a Henyey-Greenstein phase function

        Parameter ``albedo``:
            The medium's single scattering albedo (in ``[0, 1]``)

        Parameter ``g``:
            The asymmetry parameter (in ``(-1, 1)``; 0 is isotropic,
            positive values scatter forward)
        """
        check(lib.ll_layer_set_henyey_greenstein(self._handle, real_argument(albedo, "albedo"),
                                                 real_argument(g, "g"), None))

    def setVonMisesFisher(self, albedo, kappa):
        """Initialize the layer with a von Mises-Fisher phase function

        Parameter ``albedo``:
            The medium's single scattering albedo (in ``[0, 1]``)

        Parameter ``kappa``:
            The concentration (>= 0; 0 is isotropic, larger is more
            forward-peaked)
        """
        check(lib.ll_layer_set_von_mises_fisher(self._handle, real_argument(albedo, "albedo"),
                                                real_argument(kappa, "kappa"), None))

    def setMicrofacet(self, eta, alpha, conserveEnergy=True, fourierOrders=0,
                      distribution="beckmann"):
        """Initialize the layer with a rough interface, dielectric or
        conductor

        Parameter ``eta``:
            Relative index of refraction of the material below over the one
            above. A real number (or zero imaginary part) is a dielectric,
            which reflects and transmits; a complex one ``n + k*1j`` with
            ``k > 0`` is an opaque conductor.

        Parameter ``alpha``:
            Roughness of the distribution (> 0; at least 1e-3)

        Parameter ``conserveEnergy``:
            Add the paper's compensation for the energy that single
            scattering on the microfacets loses. Default: ``True``

        Parameter ``fourierOrders``:
            Number of Fourier orders used internally in the computation.
            Default (0): the layer's own :attr:`fourierOrders`

        Parameter ``distribution``:
            The microfacet distribution: ``"beckmann"`` (the paper's, the
            default) or ``"ggx"`` (Trowbridge-Reitz)
        """
        distributions = {"beckmann": MICROFACET_BECKMANN, "ggx": MICROFACET_GGX}
        if distribution not in distributions:
            raise InvalidArgumentError("setMicrofacet: distribution %r is not 'beckmann' or "
                                       "'ggx'" % (distribution,))
        mf = Microfacet()
        mf.distribution = distributions[distribution]
        mf.eta_re, mf.eta_im = complex_argument(eta, "eta")
        mf.alpha = real_argument(alpha, "alpha")
        mf.compensate = 1 if conserveEnergy else 0
        mf.n_orders_internal = count_argument(fourierOrders, "fourierOrders")
        check(lib.ll_layer_set_microfacet(self._handle, ctypes.byref(mf), None))

    def setMatusik(self, filename, channel, fourierOrders=0):
        """Initialize the layer with a measured BRDF in the MERL (Matusik et
        al. 2003) ``.binary`` format

        Parameter ``filename``:
            Path of the BRDF data file

        Parameter ``channel``:
            Color channel to extract: 0, 1 or 2 (R, G, B)

        Parameter ``fourierOrders``:
            Number of Fourier orders used internally in the computation.
            Default (0): the layer's own :attr:`fourierOrders`
        """
        channel = count_argument(channel, "channel")
        check(lib.ll_layer_set_matusik(self._handle, fspath(filename), min(channel, 2 ** 30),
                                       count_argument(fourierOrders, "fourierOrders"), None))

    # ------------------------------------------------------------ grammar

    @staticmethod
    def add(l1, l2, homogeneous=False):
        """add(l1, l2, homogeneous=False) -> Layer

        Combine two layers using the adding equations: ``l1`` on top of
        ``l2``.

        Parameter ``l1``:
            Input layer 1 (the top)

        Parameter ``l2``:
            Input layer 2 (the bottom)

        Parameter ``homogeneous``:
            Set to ``True`` when both are the same layer and its two sides
            are indistinguishable (R^t = R^b, T^tb = T^bt): that halves the
            work. Default: ``False``

        Returns:
            A new layer holding the combination
        """
        top, bottom = _handle_of(l1, "l1"), _handle_of(l2, "l2")
        out = Layer(l1)
        check(lib.ll_layer_add(top, bottom, out._handle, 1 if homogeneous else 0, None))
        return out

    def addToTop(self, l, homogeneous=False):
        """Put a layer on top of this one (this layer becomes ``l`` stacked
        on itself)

        Parameter ``l``:
            The layer to be put on top

        Parameter ``homogeneous``:
            As in :meth:`add`. Default: ``False``
        """
        check(lib.ll_layer_add(_handle_of(l, "l"), self._handle, self._handle,
                               1 if homogeneous else 0, None))

    def addToBottom(self, l, homogeneous=False):
        """Put a layer below this one

        Parameter ``l``:
            The layer to be put below

        Parameter ``homogeneous``:
            As in :meth:`add`. Default: ``False``
        """
        check(lib.ll_layer_add(self._handle, _handle_of(l, "l"), self._handle,
                               1 if homogeneous else 0, None))

    def expand(self, tau):
        """Turn a phase-function layer (:meth:`setIsotropic`,
        :meth:`setHenyeyGreenstein`, :meth:`setVonMisesFisher`) into a slab of
        the given optical thickness, by doubling

        Parameter ``tau``:
            Optical thickness (>= 0)
        """
        check(lib.ll_layer_expand(self._handle, real_argument(tau, "tau"), None))

    def reverse(self):
        """Turn the layer upside down (swap its top and bottom)"""
        check(lib.ll_layer_reverse(self._handle))

    def clear(self):
        """Reset the layer to a clear, non-scattering one (R = 0, T = I)"""
        check(lib.ll_layer_clear(self._handle))

    # ------------------------------------------------------------ reading

    def eval(self, mu_o, mu_i, phi_d=0.0):
        """eval(mu_o, mu_i, phi_d=0) -> float or numpy array

        Evaluate the BSDF (without the cosine factor) for outgoing and
        incident zenith-angle cosines and the azimuth difference ``phi_d``,
        interpolating between the nodes with Catmull-Rom splines and summing
        the Fourier series. Negative values clamp to 0.

        The arguments may be numbers or numpy arrays of any shapes that
        broadcast together; the result has the broadcast shape (a float for
        three numbers). All points are evaluated in one call into the C
        library, in parallel for large arrays.
        """
        scalar = np.ndim(mu_o) == 0 and np.ndim(mu_i) == 0 and np.ndim(phi_d) == 0
        phi_zero = np.ndim(phi_d) == 0 and phi_d == 0
        if phi_zero:
            mo, mi = np.broadcast_arrays(np.asarray(mu_o, np.float64),
                                         np.asarray(mu_i, np.float64))
            ph = None
        else:
            mo, mi, ph = np.broadcast_arrays(np.asarray(mu_o, np.float64),
                                             np.asarray(mu_i, np.float64),
                                             np.asarray(phi_d, np.float64))
            ph = np.ascontiguousarray(ph).reshape(-1)
        shape = mo.shape
        mo = np.ascontiguousarray(mo).reshape(-1)
        mi = np.ascontiguousarray(mi).reshape(-1)
        out = np.empty(mo.size)
        # (The C call takes the incident cosine first.)
        check(lib.ll_layer_eval_many(self._handle, mo.size, double_ptr(mi), double_ptr(mo),
                                     None if ph is None else double_ptr(ph), double_ptr(out)))
        if scalar:
            return float(out[0])
        return out.reshape(shape)

    def matrix(self, l=0):
        """matrix(l=0) -> numpy array (n x n)

        Return a dense representation of Fourier order ``l``'s scattering
        matrix, rows (outgoing) and columns (incident) in ascending node
        order. Integration weights and cosine factors are removed, so the
        entries are sampled BSDF values of that order. The four h x h blocks
        (h = n/2) are T^bt (top left), R^t (top right), R^b (bottom left)
        and T^tb (bottom right).
        """
        l = count_argument(l, "l")
        n = self.resolution
        out = np.empty((n, n))
        check(lib.ll_layer_matrix(self._handle, l, double_ptr(out)))
        return out

    def albedo(self, mu_i):
        """albedo(mu_i) -> (reflectance, transmittance)

        Directional-hemispherical totals for light travelling along ``mu_i``
        (> 0: arriving from above, < 0: from below): the fractions reflected
        and transmitted (the unscattered transmission included).
        """
        r, t = ctypes.c_double(), ctypes.c_double()
        check(lib.ll_layer_albedo(self._handle, real_argument(mu_i, "mu_i"), ctypes.byref(r),
                                  ctypes.byref(t)))
        return r.value, t.value

    @property
    def resolution(self):
        """The number of nodes (i.e. the number of discretizations in mu)"""
        return lib.ll_layer_node_count(self._handle)

    @property
    def fourierOrders(self):
        """The number of Fourier orders"""
        return lib.ll_layer_order_count(self._handle)

    def _nodes_and_weights(self):
        n = self.resolution
        nodes, weights = np.empty(n), np.empty(n)
        check(lib.ll_layer_get_nodes(self._handle, double_ptr(nodes), double_ptr(weights)))
        return nodes, weights

    @property
    def nodes(self):
        """The integration nodes (ascending; a copy)"""
        return self._nodes_and_weights()[0]

    @property
    def weights(self):
        """The integration weights, in the order of :attr:`nodes` (a copy)"""
        return self._nodes_and_weights()[1]

    def nonZeros(self):
        """Number of matrix entries stored over all orders (the others are
        zero)"""
        return lib.ll_layer_stored_count(self._handle)

    def __repr__(self):
        n, m = self.resolution, self.fourierOrders
        total = n * n * m
        nz = self.nonZeros()
        # The original printed the percentage with two significant digits.
        return "Layer[resolution=%dx%d, fourierOrders=%d, nonZeros=%d/%d (%s%%)]" % (
            n, n, m, nz, total, "%.2g" % (100.0 * nz / total))


def _handle_of(layer, name):
    if not isinstance(layer, Layer):
        raise TypeError("%s must be a layerlab.Layer, not %s" % (name, type(layer).__name__))
    return layer._handle


# ------------------------------------------------------------ heuristics

def parameterHeuristicMicrofacet(alpha, eta):
    """parameterHeuristicMicrofacet(alpha, eta) -> (n, m)

    Heuristic to guess a suitable number of parameters (Microfacet model):
    the node count ``n`` and Fourier order count ``m`` that a rough interface
    of Beckmann roughness ``alpha`` and (real or complex) relative index
    ``eta`` needs. Uses the paper's fits, extended to every eta.
    """
    eta_re, eta_im = complex_argument(eta, "eta")
    n, m = ctypes.c_size_t(), ctypes.c_size_t()
    check(lib.ll_heuristic_microfacet(real_argument(alpha, "alpha"), eta_re, eta_im,
                                      ctypes.byref(n), ctypes.byref(m)))
    return n.value, m.value


def parameterHeuristicHG(g):
    """parameterHeuristicHG(g) -> (n, m)

    Heuristic to guess a suitable number of parameters (HG model): the node
    count and Fourier order count that a Henyey-Greenstein medium of
    asymmetry ``g`` needs.
    """
    n, m = ctypes.c_size_t(), ctypes.c_size_t()
    check(lib.ll_heuristic_henyey_greenstein(real_argument(g, "g"), ctypes.byref(n),
                                             ctypes.byref(m)))
    return n.value, m.value


# ------------------------------------------------------------ Fresnel

def fresnelDielectric(cosThetaI, eta):
    """fresnelDielectric(cosThetaI, eta) -> (F, cosThetaT)

    Unpolarized Fresnel reflectance of a smooth dielectric boundary of
    relative index ``eta`` (transmitted side over incident side), and the
    cosine of the refracted direction, whose sign is that of the side it
    leaves into, i.e. opposite to ``cosThetaI`` (0 under total internal
    reflection). ``cosThetaI < 0`` means light arriving from the other side,
    where the relative index is ``1/eta``.
    """
    f, cos_t = ctypes.c_double(), ctypes.c_double()
    check(lib.ll_fresnel_dielectric(real_argument(cosThetaI, "cosThetaI"),
                                    real_argument(eta, "eta"), ctypes.byref(f),
                                    ctypes.byref(cos_t)))
    return f.value, cos_t.value


def fresnelConductor(cosThetaI, eta):
    """fresnelConductor(cosThetaI, eta) -> float

    Unpolarized Fresnel reflectance of a conductor with complex relative
    index ``eta`` (``n + k*1j``), for ``cosThetaI`` in [0, 1].
    """
    eta_re, eta_im = complex_argument(eta, "eta")
    f = ctypes.c_double()
    check(lib.ll_fresnel_conductor(real_argument(cosThetaI, "cosThetaI"), eta_re, eta_im,
                                   ctypes.byref(f)))
    return f.value


def fresnelDielectricIntegral(eta):
    """fresnelDielectricIntegral(eta) -> float

    Fraction of uniformly diffuse light that a smooth dielectric boundary
    reflects: 2 * integral of F(mu) mu over [0, 1].
    """
    average = ctypes.c_double()
    check(lib.ll_fresnel_dielectric_average(real_argument(eta, "eta"), ctypes.byref(average)))
    return average.value


def fresnelConductorIntegral(eta):
    """fresnelConductorIntegral(eta) -> float

    Fraction of uniformly diffuse light that a smooth conductor of complex
    index ``eta`` reflects: 2 * integral of F(mu) mu over [0, 1].
    """
    eta_re, eta_im = complex_argument(eta, "eta")
    average = ctypes.c_double()
    check(lib.ll_fresnel_conductor_average(eta_re, eta_im, ctypes.byref(average)))
    return average.value
