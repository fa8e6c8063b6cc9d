"""layerlab.tensor_file: the container of table files read back into numpy
arrays as written (fields by name, types, shapes, values), and a file that
does not parse (truncated, wrong magic or version, a block past the end)
is an error that names the file and what is wrong, never a crash or a read
past its end."""

import struct

import numpy as np
import pytest

from layerlab.tensor_file import TensorFileError, read_tensor_file


def write_tensor_file(path, fields):
    """A tensor file of the given numpy arrays (the container of docs/formats.md):
    the field table, then each block at the next multiple of 8."""
    codes = {np.dtype(np.uint8): 1, np.dtype(np.float32): 10, np.dtype(np.float64): 11}
    names = list(fields)
    table = b""
    for name in names:
        table += struct.pack("<H", len(name)) + name.encode() + struct.pack("<HB", 0, 0) + \
            b"\0" * 8 + b"\0" * 8 * fields[name].ndim
    offset = 18 + len(table)
    header, blocks = b"", b""
    for name in names:
        a = np.ascontiguousarray(fields[name])
        offset = (offset + 7) // 8 * 8
        blocks += b"\0" * (offset - 18 - len(table) - len(blocks))
        header += struct.pack("<H", len(name)) + name.encode() + \
            struct.pack("<HBQ", a.ndim, codes[a.dtype], offset) + \
            struct.pack("<%dQ" % a.ndim, *a.shape)
        blocks += a.tobytes()
        offset += a.nbytes
    with open(path, "wb") as f:
        f.write(b"tensor_file\0" + bytes([1, 0]) + struct.pack("<I", len(names)) + header +
                blocks)


def _fields():
    return {"description": np.frombuffer(b"a test", dtype=np.uint8).copy(),
            "theta_i": np.linspace(0, 1.5, 5, dtype=np.float32),
            "rgb": np.arange(2 * 3 * 4, dtype=np.float32).reshape(2, 3, 4),
            "scale": np.array([0.25], dtype=np.float64)}


def test_round_trip(tmp_path):
    path = str(tmp_path / "t.tab")
    fields = _fields()
    write_tensor_file(path, fields)
    back = read_tensor_file(path)
    assert sorted(back) == sorted(fields)
    for name, value in fields.items():
        assert back[name].dtype == value.dtype and back[name].shape == value.shape
        np.testing.assert_array_equal(back[name], value)


@pytest.mark.parametrize("damage, message", [
    (lambda b: b[:10], "not a tensor file"),
    (lambda b: b"tensor_filx\0" + b[12:], "not a tensor file"),
    (lambda b: b[:12] + bytes([2, 0]) + b[14:], "version 2.0"),
    (lambda b: b[:40], "truncated|outside the file"),
    (lambda b: b[:-8], "outside the file"),
])
def test_damaged_files_are_errors(tmp_path, damage, message):
    path = tmp_path / "t.tab"
    write_tensor_file(str(path), _fields())
    path.write_bytes(damage(path.read_bytes()))
    with pytest.raises(TensorFileError, match=message):
        read_tensor_file(str(path))
