"""The container of table files (the `measured` format's tensor file,
docs/formats.md) read into numpy arrays: what the Mitsuba plugin's
table path reads after the C reader has opened and validated the file."""

import struct

import numpy as np

_MAGIC = b"tensor_file\0"
_DTYPES = {1: "u1", 2: "i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<u8", 8: "<i8",
           9: "<f2", 10: "<f4", 11: "<f8"}


class TensorFileError(ValueError):
    """A table file that does not parse (it changed after the C reader
    validated it, or it is not one)."""


def read_tensor_file(path):
    """The fields of a tensor file as numpy arrays (copies), by name. The
    container of docs/formats.md: magic, version 1.0, the field
    table (name, rank, type code, offset, extents), dense row-major blocks.
    Bounds are checked here too, though the file was validated by the C
    reader when it was opened: a file replaced in between fails with a
    message rather than reading past its end."""
    with open(path, "rb") as f:
        data = f.read()

    def fail(what):
        raise TensorFileError("%s: %s" % (path, what))

    if len(data) < 18 or data[:12] != _MAGIC:
        fail("not a tensor file (no `tensor_file` magic)")
    major, minor = data[12], data[13]
    if (major, minor) != (1, 0):
        fail("version %d.%d, expected 1.0" % (major, minor))
    (count,) = struct.unpack_from("<I", data, 14)
    pos, fields = 18, {}
    for _ in range(count):
        if pos + 2 > len(data):
            fail("truncated field table")
        (length,) = struct.unpack_from("<H", data, pos)
        pos += 2
        if pos + length + 11 > len(data):
            fail("truncated field table")
        name = data[pos:pos + length].decode("utf-8", "replace")
        pos += length
        rank, code = struct.unpack_from("<HB", data, pos)
        (offset,) = struct.unpack_from("<Q", data, pos + 3)
        pos += 11
        if code not in _DTYPES or pos + 8 * rank > len(data):
            fail("field %s: bad type code or truncated extents" % name)
        shape = struct.unpack_from("<%dQ" % rank, data, pos)
        pos += 8 * rank
        dtype = np.dtype(_DTYPES[code])
        n = int(np.prod(shape, dtype=np.float64)) if rank else 1
        if offset + n * dtype.itemsize > len(data):
            fail("field %s: data block outside the file" % name)
        fields[name] = np.frombuffer(data, dtype=dtype, count=n,
                                     offset=offset).reshape(shape).copy()
    return fields
