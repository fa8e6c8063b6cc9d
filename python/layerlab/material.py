"""``Material``: the material language (a layer stack described as text, top
to bottom, one word per line) compiled into layers or a ``.bsdf`` file, over
``ll_material`` in ``layerlab/ll_material.h``."""

import ctypes
import weakref

from ._errors import CancelledError, Error
from ._native import (BsdfWriteOptions, BuildEstimate, BuildOptions, Monitor, check, fspath,
                      layer_p, lib, material_p, monitor_fn)
from ._util import count_argument, real_argument
from .layer import Layer
from .storage import BSDFStorage

__all__ = ["Material", "CancelFlag", "user_cache_dir"]

# The cache_dir keywords' default: the user's cache directory.
_USER_CACHE = object()


def user_cache_dir():
    """The user's cache directory for the resolutions the searches chose
    (``ll_material_cache_dir``): ``$LAYERLAB_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/layerlab``, else ``~/.cache/layerlab``. Raises
    :class:`layerlab.InvalidArgumentError` when none can be named."""
    buf = ctypes.create_string_buffer(4096)
    check(lib.ll_material_cache_dir(buf, len(buf)))
    return buf.value.decode("utf-8", "surrogateescape")


class CancelFlag:
    """A flag that stops a running build: pass it as ``cancel=`` to
    :meth:`Material.build` and call :meth:`set` from another thread (the
    library releases the GIL while it builds, and its monitor reads the
    flag at least every 20 ms). The build then raises
    :class:`layerlab.CancelledError` and leaves no output file."""

    def __init__(self):
        self._value = ctypes.c_int(0)

    def set(self):
        self._value.value = 1

    def clear(self):
        self._value.value = 0

    def is_set(self):
        return self._value.value != 0


class _Build:
    """The ll_build_options and the ll_monitor of one build, with the
    Python callback kept alive and any exception it raised kept for
    re-raising. The monitor shows the progress (if asked for) and returns
    the cancel flag, which stops the build."""

    def __init__(self, nodes, orders, channels, threads, error_goal, progress, cancel,
                 tolerance=0.0, mu_min=0.0, cache_dir=None):
        self.opts = BuildOptions()
        if cache_dir is _USER_CACHE:
            try:
                cache_dir = user_cache_dir()
            except Error:
                cache_dir = None  # (no directory to name: nothing remembered)
        # Kept alive with the options that point at it.
        self.cache_dir = fspath(cache_dir) if cache_dir is not None else None
        self.opts.cache_dir = self.cache_dir
        self.opts.tolerance = real_argument(tolerance, "tolerance")
        self.opts.mu_min = real_argument(mu_min, "mu_min")
        self.opts.n_nodes = count_argument(nodes, "nodes")
        self.opts.n_orders = count_argument(orders, "orders")
        self.opts.n_channels = count_argument(channels, "channels")
        self.opts.threads = count_argument(threads, "threads")
        self.opts.error_goal = real_argument(error_goal, "error_goal")
        self.error = None
        # A callback that raises cannot unwind through C: the exception is
        # kept, the cancel flag raised, and the exception re-raised after C
        # returns (so Ctrl-C inside a progress callback stops the build).
        self.flag = cancel if cancel is not None else CancelFlag()

        def trampoline(_user, fraction, stage):
            if progress is not None and self.error is None:
                try:
                    progress(fraction, stage.decode("utf-8", "replace") if stage else "")
                except BaseException as e:  # noqa: B902 - re-raised after the C call
                    self.error = e
                    self.flag.set()
            return 1 if self.flag.is_set() else 0
        self.callback = monitor_fn(trampoline)
        self.monitor = Monitor()
        self.monitor.progress = self.callback

    def run(self, call):
        """call(opts, monitor) -> ll_status"""
        try:
            check(call(ctypes.byref(self.opts), ctypes.byref(self.monitor)))
        except CancelledError:
            if self.error is not None:
                raise self.error from None
            raise
        if self.error is not None:
            raise self.error


class Material:
    """A parsed material description (immutable; may be built from several
    threads at once).

    Create one with :meth:`parse` (text) or :meth:`parse_file` (a
    ``.layers`` file); errors raise :class:`layerlab.ParseError` with
    ``file:line:column`` and what was expected. Then :meth:`build` writes a
    ``.bsdf`` file and :meth:`build_layers` returns the layers in memory.

    The build keywords, shared by :meth:`build`, :meth:`build_layers` and
    :meth:`resolution` (0 means "the material's setting, else the
    default"): ``nodes``, ``orders`` (resolution), ``channels`` (1 or 3),
    ``threads`` (0: all processors), ``error_goal`` (series truncation),
    ``tolerance`` and ``mu_min`` (the relative error the chosen resolution
    is within where the BSDF is above 1% of its peak, at |mu| >= mu_min;
    defaults 0.01 and 0.1);
    :meth:`build` and :meth:`build_layers` also take ``progress``, a
    callable ``progress(fraction, stage)``, and ``cancel``, a
    :class:`CancelFlag`.
    """

    def __init__(self, handle):
        if not isinstance(handle, material_p) or not handle:
            raise TypeError("use Material.parse(text) or Material.parse_file(path)")
        self._handle = handle
        self._finalizer = weakref.finalize(self, lib.ll_material_destroy, handle)

    @classmethod
    def parse(cls, text, source_name=None):
        """parse(text, source_name=None) -> Material

        Parse a material description; ``source_name`` names the text in
        error messages.
        """
        handle = material_p()
        name = None if source_name is None else str(source_name).encode("utf-8")
        check(lib.ll_material_parse(str(text).encode("utf-8"), name, ctypes.byref(handle)))
        return cls(handle)

    @classmethod
    def parse_file(cls, path):
        """parse_file(path) -> Material

        Parse a material file; relative ``file=`` paths inside it resolve
        against the file's directory.
        """
        handle = material_p()
        check(lib.ll_material_parse_file(fspath(path), ctypes.byref(handle)))
        return cls(handle)

    def __len__(self):
        """The number of words (layers) in the stack"""
        return lib.ll_material_word_count(self._handle)

    def resolution(self, nodes=0, orders=0, channels=0, threads=0, error_goal=0.0,
                   tolerance=0.0, mu_min=0.0, cache_dir=_USER_CACHE):
        """resolution(...) -> (nodes, orders, channels)

        The node count, Fourier order count and channel count that a build
        with these keywords would use. ``cache_dir`` (every call that may
        search takes it): where the searches' choices are remembered between
        runs, by default :func:`user_cache_dir`; ``None`` remembers nothing.
        """
        build = _Build(nodes, orders, channels, threads, error_goal, None, None,
                       tolerance, mu_min, cache_dir)
        n, m, c = ctypes.c_size_t(), ctypes.c_size_t(), ctypes.c_size_t()
        build.run(lambda opts, monitor: lib.ll_material_resolution(
            self._handle, opts, monitor, ctypes.byref(n), ctypes.byref(m), ctypes.byref(c)))
        return n.value, m.value, c.value

    def estimate(self, nodes=0, orders=0, channels=0, threads=0, error_goal=0.0,
                 tolerance=0.0, mu_min=0.0, cache_dir=_USER_CACHE):
        """estimate(...) -> dict

        What a build with these keywords would take, estimated without
        building (as ``llbuild --dry-run``): ``nodes``, ``orders``,
        ``channels``, ``layers_built``, ``additions``, ``doublings``,
        ``peak_bytes`` (an upper bound), ``file_bytes``, ``resolution_error``
        (the largest relative error the chosen resolution was measured to
        against twice itself; ``inf`` when a word could not be verified, -1
        when the resolution is given) and ``work``, the counts of work by
        kind that a time model multiplies by its machine's rates (the
        library gives no seconds; ``llbuild --dry-run`` has a model).
        """
        build = _Build(nodes, orders, channels, threads, error_goal, None, None,
                       tolerance, mu_min, cache_dir)
        est = BuildEstimate()
        build.run(lambda opts, monitor: lib.ll_material_estimate(self._handle, opts,
                                                                 ctypes.byref(est), monitor))
        work = ("dielectric_pairs", "conductor_pairs", "pair_orders", "measured_lookups",
                "measured_files", "phase_entries", "diffuse_entries", "add_entries",
                "add_empty_entries", "stored_values")
        return {"nodes": est.n_nodes, "orders": est.n_orders, "channels": est.n_channels,
                "layers_built": est.layers_built, "additions": est.additions,
                "doublings": est.doublings, "peak_bytes": est.peak_bytes,
                "file_bytes": est.file_bytes, "resolution_error": est.resolution_error,
                "work": {name: getattr(est, name) for name in work}}

    def build(self, path, nodes=0, orders=0, channels=0, threads=0, error_goal=0.0,
              progress=None, cancel=None, tolerance=0.0, mu_min=0.0, cache_dir=_USER_CACHE):
        """build(path, ...) -> BSDFStorage

        Build the material and write it to ``path`` as a ``.bsdf`` file
        (atomically: a failed or cancelled build leaves no file and does not
        touch an existing one); returns the opened file.
        """
        build = _Build(nodes, orders, channels, threads, error_goal, progress, cancel,
                       tolerance, mu_min, cache_dir)
        target = fspath(path)
        build.run(lambda opts, monitor: lib.ll_material_build(self._handle, opts, monitor,
                                                              target))
        return BSDFStorage(path)

    def build_layers(self, nodes=0, orders=0, channels=0, threads=0, error_goal=0.0,
                     progress=None, cancel=None, tolerance=0.0, mu_min=0.0,
                     cache_dir=_USER_CACHE):
        """build_layers(...) -> (layers, header)

        Build the material in memory: a list of one Layer (monochrome) or
        three (R, G, B), and the header a file of this stack carries, a dict
        with ``eta`` and ``alpha`` (top, bottom) -- the keyword arguments
        :meth:`BSDFStorage.fromLayer` takes.
        """
        build = _Build(nodes, orders, channels, threads, error_goal, progress, cancel,
                       tolerance, mu_min, cache_dir)
        handles = (layer_p * 3)()
        count = ctypes.c_size_t()
        header = BsdfWriteOptions()
        build.run(lambda opts, monitor: lib.ll_material_build_layers(
            self._handle, opts, monitor, handles, ctypes.byref(count), ctypes.byref(header)))
        layers = []
        for k in range(3):
            if not handles[k]:
                continue
            if k < count.value:
                layer = Layer.__new__(Layer)
                layer._adopt(handles[k])
                layers.append(layer)
            else:  # not promised by the header; never leak one
                lib.ll_layer_destroy(handles[k])
        return layers, {"eta": header.eta, "alpha": (header.alpha[0], header.alpha[1])}

    def write(self, path, layers, error_goal=0.0, cancel=None):
        """write(path, layers, error_goal=0, cancel=None) -> BSDFStorage

        Write layers that :meth:`build_layers` returned (1 or 3) to ``path``
        as a ``.bsdf`` file with this material's header (eta, alpha) and
        description; atomic like :meth:`build`. Returns the opened file.
        """
        layers = list(layers)
        for k, layer in enumerate(layers):
            if not isinstance(layer, Layer):
                raise TypeError("layer %d must be a layerlab.Layer, not %s"
                                % (k, type(layer).__name__))
        build = _Build(0, 0, 0, 0, error_goal, None, cancel)
        handles = (layer_p * max(len(layers), 1))(*[layer._handle for layer in layers])
        target = fspath(path)
        build.run(lambda opts, monitor: lib.ll_material_write(self._handle, opts, handles,
                                                              len(layers), target, monitor))
        return BSDFStorage(path)

    def __repr__(self):
        return "Material[words=%d]" % len(self)

