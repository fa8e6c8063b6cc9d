"""Argument conversion shared by the modules: Python values to what the C
prototypes take, checked before they reach C (a negative count would wrap
around to a huge size_t)."""

import operator

import numpy as np

from ._errors import InvalidArgumentError
from ._native import c_double_p


def count_argument(value, name):
    """A non-negative integer argument (size_t in C)."""
    try:
        n = operator.index(value)
    except TypeError:
        raise TypeError("%s must be an integer, not %s" % (name, type(value).__name__)) from None
    if n < 0:
        raise InvalidArgumentError("%s = %d is negative" % (name, n))
    return n


def real_argument(value, name):
    """A real number argument (double in C); complex values are refused."""
    if isinstance(value, (complex, np.complexfloating)):
        raise TypeError("%s must be real, not complex (%r)" % (name, value))
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TypeError("%s must be a real number, not %r" % (name, value)) from None


def vector_argument(values, name):
    """A one-dimensional float64 array, C-contiguous (a copy when needed)."""
    a = np.ascontiguousarray(values, dtype=np.float64)
    if a.ndim != 1:
        raise InvalidArgumentError("%s must be one-dimensional (got shape %s)" % (name, a.shape))
    return a


def double_ptr(a):
    """Pointer to the data of a contiguous float64 array."""
    return a.ctypes.data_as(c_double_p)
