"""Exceptions raised by layerlab, and the mapping from the C library's status
codes (``ll_status`` in ``layerlab/ll_common.h``) to them.

Every exception derives from :class:`Error` and from the built-in exception a
Python user would expect, so ``except ValueError`` catches a bad argument and
``except OSError`` an unreadable file. The text is the C library's own message
(``ll_last_error_message()``), which names the function and the offending value.
"""


class Error(Exception):
    """Base class of every error reported by liblayerlab.

    Attributes:
        status: the numeric ``ll_status`` code (see ``layerlab/ll_common.h``).
    """

    status = None

    def __init__(self, message, status=None):
        super().__init__(message)
        if status is not None:
            self.status = status


class InvalidArgumentError(Error, ValueError):
    """An argument is outside its domain (LL_ERROR_INVALID_ARGUMENT)."""

    status = 1


class OutOfMemoryError(Error, MemoryError):
    """An allocation failed or its size would overflow (LL_ERROR_OUT_OF_MEMORY)."""

    status = 2


class FileError(Error, OSError):
    """A file could not be read or written (LL_ERROR_IO)."""

    status = 3

    def __str__(self):
        # OSError formats (errno, strerror) pairs; ours carries one message.
        return str(self.args[0]) if self.args else ""


class FormatError(Error, ValueError):
    """A file's contents are malformed, e.g. a damaged .bsdf (LL_ERROR_FORMAT)."""

    status = 4


class NumericalError(Error, ArithmeticError):
    """A factorisation or series failed to converge (LL_ERROR_NUMERICAL)."""

    status = 5


class UnsupportedError(Error, NotImplementedError):
    """Valid, but not supported by the loaded library (LL_ERROR_UNSUPPORTED)."""

    status = 6


class ParseError(Error, ValueError):
    """A material description has an error; the message gives
    ``file:line:column`` (LL_ERROR_PARSE)."""

    status = 7


class CancelledError(Error):
    """A build was cancelled through its cancel flag or progress callback
    (LL_ERROR_CANCELLED)."""

    status = 8


_BY_STATUS = {
    cls.status: cls
    for cls in (InvalidArgumentError, OutOfMemoryError, FileError, FormatError,
                NumericalError, UnsupportedError, ParseError, CancelledError)
}


def error_for_status(status, message):
    """The exception object for a nonzero ll_status and its message."""
    cls = _BY_STATUS.get(status, Error)
    return cls(message, status)


# Show the public name (layerlab.FormatError) in tracebacks and reprs.
for _cls in (Error,) + tuple(_BY_STATUS.values()):
    _cls.__module__ = "layerlab"
del _cls
