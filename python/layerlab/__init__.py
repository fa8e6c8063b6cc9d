"""layerlab: layered material reflectance (Jakob, d'Eon, Jakob, Marschner,
"A Comprehensive Framework for Rendering Layered Materials", SIGGRAPH 2014).

A Python interface to the C library liblayerlab through its stable C ABI
(ctypes; no compiled extension), with numpy arrays in and out. The names and
keyword arguments are those of the original layerlab's Python module:

    import layerlab as ll
    mu, w = ll.quad.gaussLobatto(200)
    coating = ll.Layer(mu, w, 200)
    coating.setMicrofacet(eta=1.5, alpha=0.1)
    base = ll.Layer(mu, w, 200)
    base.setMicrofacet(eta=0+1j, alpha=0.1)
    base.addToTop(coating)
    ll.BSDFStorage.fromLayer("output.bsdf", base)

The library is found through the environment variable LAYERLAB_LIBRARY (a
path), else an installed prefix (pkg-config), else the system's library path.
Errors raise subclasses of :class:`layerlab.Error` that are also the
matching built-in exceptions (ValueError, OSError, MemoryError, ...).
"""

from . import quad
from ._errors import (CancelledError, Error, FileError, FormatError, InvalidArgumentError,
                      NumericalError, OutOfMemoryError, ParseError, UnsupportedError)
from ._native import check as _check
from ._native import lib as _lib
from ._util import count_argument as _count_argument
from .layer import (Layer, fresnelConductor, fresnelConductorIntegral, fresnelDielectric,
                    fresnelDielectricIntegral, parameterHeuristicHG,
                    parameterHeuristicMicrofacet)
from .material import CancelFlag, Material, user_cache_dir
from .storage import BSDFStorage

__version__ = "1.0.0"

__all__ = ["quad", "Layer", "BSDFStorage", "Material", "CancelFlag", "user_cache_dir",
           "parameterHeuristicMicrofacet", "parameterHeuristicHG",
           "fresnelDielectric", "fresnelConductor", "fresnelDielectricIntegral",
           "fresnelConductorIntegral", "libraryVersion", "libraryPath",
           "setThreadCount", "threadCount",
           "Error", "InvalidArgumentError", "OutOfMemoryError", "FileError", "FormatError",
           "NumericalError", "UnsupportedError", "ParseError", "CancelledError"]


def libraryVersion():
    """The version string of the loaded liblayerlab, e.g. "1.0.0"."""
    return _lib.ll_version_string().decode("ascii")


def libraryPath():
    """The path or name liblayerlab was loaded from."""
    return _lib.path


def setThreadCount(n):
    """Number of worker threads that layerlab calls made from the calling
    thread may use (0: all processors, the default). Results do not depend
    on it."""
    _check(_lib.ll_set_thread_count(_count_argument(n, "n")))


def threadCount():
    """The effective worker-thread count of the calling thread."""
    return _lib.ll_get_thread_count()
