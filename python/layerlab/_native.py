"""Loading liblayerlab and describing its C ABI to ctypes.

The package has no compiled extension: every call goes through the library's
stable C ABI (``include/layerlab.h``), so one pure-Python package serves every
Python version. This module finds the shared library, checks its version,
declares the prototypes of the functions the package uses, and turns a
failing ``ll_status`` into a Python exception carrying the library's message.

Search order (the first that loads wins):
  1. the path in the environment variable ``LAYERLAB_LIBRARY``;
  2. an installed prefix named by ``PKG_CONFIG_PATH`` (set: an explicit choice):
     ``$(pkg-config --variable=libdir layerlab)``;
  3. the copy bundled in the package by ``pip install`` (``_lib/liblayerlab.so.1``,
     with the metals' spectra in ``share/layerlab/ior`` beside it; see setup.py);
  4. pkg-config's default search, then the system's library path
     (``ctypes.util.find_library`` and the soname).
"""

import ctypes
import ctypes.util
import os
import subprocess

from ._errors import UnsupportedError, error_for_status

# The soname tracks the ABI (liblayerlab.so.ABI_VERSION); the package speaks
# ABI 1 and needs at least the release that introduced every function below.
ABI_VERSION = 1
REQUIRED_MAJOR = 1
MINIMUM_VERSION = (1, 0, 0)

# ------------------------------------------------------------ C types

c_double_p = ctypes.POINTER(ctypes.c_double)
c_float_p = ctypes.POINTER(ctypes.c_float)
c_size_t_p = ctypes.POINTER(ctypes.c_size_t)
status_t = ctypes.c_int32


class LayerStruct(ctypes.Structure):
    """Opaque ``ll_layer``."""


class BsdfStruct(ctypes.Structure):
    """Opaque ``ll_bsdf``."""


class MaterialStruct(ctypes.Structure):
    """Opaque ``ll_material``."""


layer_p = ctypes.POINTER(LayerStruct)
bsdf_p = ctypes.POINTER(BsdfStruct)
material_p = ctypes.POINTER(MaterialStruct)


class BsdfWriteOptions(ctypes.Structure):
    """``ll_bsdf_write_options`` (size-tagged)."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("eta", ctypes.c_double),
                ("alpha", ctypes.c_double * 2),
                ("metadata", ctypes.c_char_p),
                ("error_goal", ctypes.c_double)]

    def __init__(self):
        # The values of LL_BSDF_WRITE_OPTIONS_INIT.
        super().__init__(ctypes.sizeof(BsdfWriteOptions), 1.0, (0.0, 0.0), None, 1e-3)


class BsdfInfo(ctypes.Structure):
    """``ll_bsdf_info`` (size-tagged)."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("n_nodes", ctypes.c_size_t),
                ("max_order", ctypes.c_size_t),
                ("n_channels", ctypes.c_size_t),
                ("n_bases", ctypes.c_size_t),
                ("n_parameters", ctypes.c_size_t),
                ("n_coeffs", ctypes.c_size_t),
                ("eta", ctypes.c_double),
                ("alpha", ctypes.c_double * 2),
                ("metadata", ctypes.c_char_p),
                ("metadata_size", ctypes.c_size_t),
                ("file_size", ctypes.c_size_t),
                ("flags", ctypes.c_uint32),
                ("format", ctypes.c_uint32),
                ("n_wavelengths", ctypes.c_size_t)]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(BsdfInfo)


# int (*)(void *user, double fraction, const char *stage): 0 continues.
monitor_fn = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_char_p)


class Monitor(ctypes.Structure):
    """``ll_monitor`` (size-tagged): the last argument of every long call."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("progress", monitor_fn),
                ("user", ctypes.c_void_p)]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(Monitor)


monitor_p = ctypes.POINTER(Monitor)

# ll_microfacet_distribution
MICROFACET_BECKMANN = 0
MICROFACET_GGX = 1


class Microfacet(ctypes.Structure):
    """``ll_microfacet`` (size-tagged): a rough interface."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("eta_re", ctypes.c_double),
                ("eta_im", ctypes.c_double),
                ("alpha", ctypes.c_double),
                ("distribution", ctypes.c_int),
                ("compensate", ctypes.c_int),
                ("n_orders_internal", ctypes.c_size_t)]

    def __init__(self):
        # The values of LL_MICROFACET_INIT.
        super().__init__(ctypes.sizeof(Microfacet), 1.5, 0.0, 0.1, MICROFACET_BECKMANN, 1, 0)


class BuildOptions(ctypes.Structure):
    """``ll_build_options`` (size-tagged)."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("n_nodes", ctypes.c_size_t),
                ("n_orders", ctypes.c_size_t),
                ("n_channels", ctypes.c_size_t),
                ("threads", ctypes.c_size_t),
                ("tolerance", ctypes.c_double),
                ("mu_min", ctypes.c_double),
                ("error_goal", ctypes.c_double),
                ("max_memory_bytes", ctypes.c_size_t),
                # void (*)(void *user, size_t channel, const ll_layer *layer)
                ("channel_done", ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_size_t,
                                                  ctypes.c_void_p)),
                ("channel_done_user", ctypes.c_void_p),
                ("cache_dir", ctypes.c_char_p)]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(BuildOptions)


class BuildEstimate(ctypes.Structure):
    """``ll_build_estimate`` (size-tagged; experimental in C)."""

    _fields_ = [("struct_size", ctypes.c_size_t),
                ("n_nodes", ctypes.c_size_t),
                ("n_orders", ctypes.c_size_t),
                ("n_channels", ctypes.c_size_t),
                ("n_bases", ctypes.c_size_t),
                ("threads", ctypes.c_size_t),
                ("resolution_error", ctypes.c_double),
                ("peak_bytes", ctypes.c_double),
                ("file_bytes", ctypes.c_double),
                ("max_memory_bytes", ctypes.c_size_t),
                ("over_budget", ctypes.c_int),
                ("layers_built", ctypes.c_size_t),
                ("additions", ctypes.c_size_t),
                ("doublings", ctypes.c_size_t),
                ("dielectric_pairs", ctypes.c_double),
                ("conductor_pairs", ctypes.c_double),
                ("pair_orders", ctypes.c_double),
                ("measured_lookups", ctypes.c_double),
                ("measured_files", ctypes.c_double),
                ("phase_entries", ctypes.c_double),
                ("diffuse_entries", ctypes.c_double),
                ("add_entries", ctypes.c_double),
                ("add_empty_entries", ctypes.c_double),
                ("stored_values", ctypes.c_double)]

    def __init__(self):
        super().__init__()
        self.struct_size = ctypes.sizeof(BuildEstimate)


_S, _D, _Z, _I = status_t, ctypes.c_double, ctypes.c_size_t, ctypes.c_int
_P3 = ctypes.c_double * 3

# name: (return type, argument types), exactly as declared in include/layerlab/.
PROTOTYPES = {
    # ll_common.h
    "ll_version_number": (_I, []),
    "ll_version_string": (ctypes.c_char_p, []),
    "ll_status_string": (ctypes.c_char_p, [_S]),
    "ll_last_error_message": (ctypes.c_char_p, []),
    "ll_set_thread_count": (_S, [_Z]),
    "ll_get_thread_count": (_Z, []),
    # ll_quad.h
    "ll_quad_gauss_legendre": (_S, [_Z, c_double_p, c_double_p, monitor_p]),
    "ll_quad_gauss_lobatto": (_S, [_Z, c_double_p, c_double_p, monitor_p]),
    "ll_quad_composite_simpson": (_S, [_Z, c_double_p, c_double_p]),
    "ll_quad_composite_simpson38": (_S, [_Z, c_double_p, c_double_p]),
    # ll_layer.h
    "ll_layer_create": (_S, [c_double_p, c_double_p, _Z, _Z, ctypes.POINTER(layer_p)]),
    "ll_layer_clone": (_S, [layer_p, ctypes.POINTER(layer_p)]),
    "ll_layer_destroy": (None, [layer_p]),
    "ll_layer_node_count": (_Z, [layer_p]),
    "ll_layer_order_count": (_Z, [layer_p]),
    "ll_layer_get_nodes": (_S, [layer_p, c_double_p, c_double_p]),
    "ll_layer_stored_count": (_Z, [layer_p]),
    "ll_layer_set_diffuse": (_S, [layer_p, _D, monitor_p]),
    "ll_layer_set_isotropic": (_S, [layer_p, _D, monitor_p]),
    "ll_layer_set_henyey_greenstein": (_S, [layer_p, _D, _D, monitor_p]),
    "ll_layer_set_von_mises_fisher": (_S, [layer_p, _D, _D, monitor_p]),
    "ll_layer_set_microfacet": (_S, [layer_p, ctypes.POINTER(Microfacet), monitor_p]),
    "ll_layer_set_matusik": (_S, [layer_p, ctypes.c_char_p, _I, _Z, monitor_p]),
    "ll_layer_add": (_S, [layer_p, layer_p, layer_p, _I, monitor_p]),
    "ll_layer_add_to_top": (_S, [layer_p, layer_p]),
    "ll_layer_add_to_bottom": (_S, [layer_p, layer_p]),
    "ll_layer_expand": (_S, [layer_p, _D, monitor_p]),
    "ll_layer_reverse": (_S, [layer_p]),
    "ll_layer_clear": (_S, [layer_p]),
    # (mu_i, mu_o, phi_d): the known direction first
    "ll_layer_eval": (_S, [layer_p, _D, _D, _D, c_double_p]),
    "ll_layer_eval_many": (_S, [layer_p, _Z, c_double_p, c_double_p, c_double_p, c_double_p]),
    "ll_layer_matrix": (_S, [layer_p, _Z, c_double_p]),
    "ll_layer_albedo": (_S, [layer_p, _D, c_double_p, c_double_p]),
    "ll_heuristic_henyey_greenstein": (_S, [_D, c_size_t_p, c_size_t_p]),
    "ll_heuristic_microfacet": (_S, [_D, _D, _D, c_size_t_p, c_size_t_p]),
    "ll_resolution_search_henyey_greenstein": (_S, [_D, _D, _D, monitor_p, c_size_t_p, c_size_t_p,
                                                    c_double_p]),
    "ll_resolution_search_microfacet": (_S, [ctypes.POINTER(Microfacet), _D, _D, monitor_p,
                                             c_size_t_p, c_size_t_p, c_double_p]),
    "ll_fresnel_dielectric": (_S, [_D, _D, c_double_p, c_double_p]),
    "ll_fresnel_conductor": (_S, [_D, _D, _D, c_double_p]),
    "ll_fresnel_dielectric_average": (_S, [_D, c_double_p]),
    "ll_fresnel_conductor_average": (_S, [_D, _D, c_double_p]),
    # ll_bsdf.h
    "ll_bsdf_write": (_S, [ctypes.c_char_p, ctypes.POINTER(layer_p), _Z,
                           ctypes.POINTER(BsdfWriteOptions), monitor_p]),
    # options: const ll_open_options * (None: the default limits)
    "ll_bsdf_open": (_S, [ctypes.c_char_p, ctypes.c_void_p, ctypes.POINTER(bsdf_p)]),
    "ll_bsdf_open_memory": (_S, [ctypes.c_void_p, _Z, ctypes.c_void_p, ctypes.POINTER(bsdf_p)]),
    "ll_bsdf_release": (None, [bsdf_p]),
    "ll_bsdf_get_info": (_S, [bsdf_p, ctypes.POINTER(BsdfInfo)]),
    "ll_bsdf_get_parameter": (_S, [bsdf_p, _Z, c_size_t_p, ctypes.POINTER(c_float_p)]),
    "ll_bsdf_get_parameter_name": (_S, [bsdf_p, _Z, ctypes.POINTER(ctypes.c_char_p)]),
    "ll_bsdf_basis_coefficients": (_S, [bsdf_p, c_double_p, c_float_p]),
    "ll_bsdf_write_textured": (_S, [ctypes.c_char_p, ctypes.POINTER(layer_p), _Z, _Z, c_size_t_p,
                                    c_double_p, ctypes.POINTER(BsdfWriteOptions), monitor_p]),
    "ll_bsdf_nodes": (c_float_p, [bsdf_p]),
    "ll_bsdf_eval": (_S, [bsdf_p, _D, _D, _D, c_float_p, _P3]),
    "ll_bsdf_pdf": (_S, [bsdf_p, _D, _D, _D, c_float_p, c_double_p]),
    "ll_bsdf_albedo": (_S, [bsdf_p, _D, c_float_p, _P3, _P3]),
    "ll_bsdf_sample": (_S, [bsdf_p, _D, ctypes.c_double * 2, c_float_p, c_double_p, c_double_p,
                            c_double_p, _P3]),
    "ll_bsdf_eval_dir": (_S, [bsdf_p, _P3, _P3, _I, c_float_p, _P3]),
    "ll_bsdf_pdf_dir": (_S, [bsdf_p, _P3, _P3, c_float_p, c_double_p]),
    "ll_bsdf_sample_dir": (_S, [bsdf_p, _P3, ctypes.c_double * 2, _I, c_float_p, _P3,
                                c_double_p, _P3]),
    # batch calls of the renderer convention (arrays of packed 3- and 2-vectors)
    "ll_bsdf_eval_dir_batch": (_S, [bsdf_p, _Z, c_double_p, c_double_p, _I, c_float_p, _Z,
                                    c_double_p]),
    "ll_bsdf_pdf_dir_batch": (_S, [bsdf_p, _Z, c_double_p, c_double_p, c_float_p, _Z,
                                   c_double_p]),
    "ll_bsdf_sample_dir_batch": (_S, [bsdf_p, _Z, c_double_p, c_double_p, _I, c_float_p, _Z,
                                      c_double_p, c_double_p, c_double_p]),
    # ll_material.h
    "ll_material_parse": (_S, [ctypes.c_char_p, ctypes.c_char_p, ctypes.POINTER(material_p)]),
    "ll_material_parse_file": (_S, [ctypes.c_char_p, ctypes.POINTER(material_p)]),
    "ll_material_destroy": (None, [material_p]),
    "ll_material_resolution": (_S, [material_p, ctypes.POINTER(BuildOptions), monitor_p,
                                    c_size_t_p, c_size_t_p, c_size_t_p]),
    "ll_material_build": (_S, [material_p, ctypes.POINTER(BuildOptions), monitor_p,
                               ctypes.c_char_p]),
    "ll_material_build_layers": (_S, [material_p, ctypes.POINTER(BuildOptions), monitor_p,
                                      layer_p * 3, c_size_t_p, ctypes.POINTER(BsdfWriteOptions)]),
    "ll_material_write": (_S, [material_p, ctypes.POINTER(BuildOptions), ctypes.POINTER(layer_p),
                               _Z, ctypes.c_char_p, monitor_p]),
    "ll_material_word_count": (_Z, [material_p]),
    "ll_material_cache_dir": (_S, [ctypes.c_char_p, _Z]),
    # experimental in C (LL_EXPERIMENTAL)
    "ll_material_estimate": (_S, [material_p, ctypes.POINTER(BuildOptions),
                                  ctypes.POINTER(BuildEstimate), monitor_p]),
}


class Library:
    """The loaded liblayerlab. Functions are declared on first use, so a
    library that lacks one (an older build) still serves everything else and
    the missing one fails with a clear :class:`UnsupportedError`."""

    def __init__(self, cdll, path, how):
        self._cdll = cdll
        self.path = path
        self.how = how

    def __getattr__(self, name):
        if name not in PROTOTYPES:
            raise AttributeError(name)
        try:
            fn = getattr(self._cdll, name)
        except AttributeError:
            fn = _missing(name, self.path)
        else:
            fn.restype, fn.argtypes = PROTOTYPES[name]
        setattr(self, name, fn)  # cache: later lookups skip __getattr__
        return fn


def _missing(name, path):
    def fail(*_args):
        raise UnsupportedError(
            "%s is not exported by the loaded liblayerlab (%s); this build of the library "
            "predates the function, rebuild or reinstall it" % (name, path), 6)
    return fail


def _candidates():
    """(description, path or name) pairs in search order; LAYERLAB_LIBRARY is
    handled by the caller because a wrong explicit path must not fall through."""
    found = []
    bundled = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_lib",
                           "liblayerlab.so.%d" % ABI_VERSION)
    if os.path.exists(bundled) and not os.environ.get("PKG_CONFIG_PATH"):
        found.append(("the package's bundled copy", bundled))
    try:
        libdir = subprocess.run(["pkg-config", "--variable=libdir", "layerlab"],
                                capture_output=True, text=True, timeout=30)
        if libdir.returncode == 0 and libdir.stdout.strip():
            found.append(("pkg-config libdir",
                          os.path.join(libdir.stdout.strip(), "liblayerlab.so.%d" % ABI_VERSION)))
        else:
            found.append(("pkg-config", None))
    except (OSError, subprocess.SubprocessError):
        found.append(("pkg-config (not installed)", None))
    if os.path.exists(bundled) and os.environ.get("PKG_CONFIG_PATH"):
        found.append(("the package's bundled copy", bundled))
    name = ctypes.util.find_library("layerlab")
    if name:
        found.append(("ctypes.util.find_library('layerlab')", name))
    found.append(("system library path", "liblayerlab.so.%d" % ABI_VERSION))
    return found


def _version_problem(cdll):
    """None if the library's version suits this package, else why not."""
    fn = cdll.ll_version_number
    fn.restype, fn.argtypes = ctypes.c_int, []
    number = fn()
    major, minor, patch = number // 10000, number // 100 % 100, number % 100
    if major != REQUIRED_MAJOR or (major, minor, patch) < MINIMUM_VERSION:
        return ("is version %d.%d.%d; this package needs %d.x, at least %d.%d.%d (ABI %d)"
                % ((major, minor, patch, REQUIRED_MAJOR) + MINIMUM_VERSION + (ABI_VERSION,)))
    return None


def load():
    """Find, load and version-check liblayerlab; ImportError says what was tried."""
    explicit = os.environ.get("LAYERLAB_LIBRARY")
    if explicit:
        # A relative path is made absolute now: the library finds its data
        # (the metal spectra in ../share/layerlab/ior) from the path it was
        # loaded by, which must not change meaning when the program changes
        # its working directory. A bare name keeps the loader's search.
        if os.sep in explicit:
            explicit = os.path.abspath(explicit)
        candidates = [("LAYERLAB_LIBRARY", explicit)]
    else:
        candidates = _candidates()
    tried = []
    for how, target in candidates:
        if target is None:
            tried.append("%s: no layerlab package found" % how)
            continue
        try:
            cdll = ctypes.CDLL(target)
        except OSError as e:
            tried.append("%s: %s (%s)" % (how, target, e))
            continue
        try:
            cdll.ll_version_number
        except AttributeError:
            tried.append("%s: %s is not liblayerlab (no ll_version_number)" % (how, target))
            continue
        problem = _version_problem(cdll)
        if problem:  # an old copy earlier in the search order must not hide a good one
            tried.append("%s: %s %s" % (how, target, problem))
            continue
        return Library(cdll, target, how)
    hint = ("set LAYERLAB_LIBRARY to the path of liblayerlab.so, or `make install` the library "
            "so that pkg-config finds it")
    raise ImportError("layerlab: cannot load the C library liblayerlab. Tried:\n  - "
                      + "\n  - ".join(tried) + "\n" + hint)


lib = load()


def last_message(status):
    text = lib.ll_last_error_message()
    message = text.decode("utf-8", "replace") if text else ""
    if not message:
        message = lib.ll_status_string(status).decode("utf-8", "replace")
    return message


def check(status):
    """Raise the exception for a failing ll_status (with the thread's message)."""
    if status != 0:
        raise error_for_status(status, last_message(status))


def fspath(path):
    """A path-like object as the bytes the C library expects."""
    return os.fsencode(os.fspath(path))
