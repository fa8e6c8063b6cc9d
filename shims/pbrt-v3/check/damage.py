"""Write the eight damaged copies of an intact .bsdf file that `make pbrt-check`
renders (shims/pbrt-v3/check/check.sh), and print one line per case:
`NAME<TAB>what was damaged`. The layout and field offsets are those of the
SCATFUN format (the 64-byte header, then nodes, parameter counts and values,
the CDF, the (offset, length) table and the coefficients).

usage: python3 damage.py INTACT.bsdf OUTDIR
"""
import os
import struct
import sys

HEADER = struct.Struct("<7sB9I5f")  # identifier, version, 9 x uint32, eta, alpha[2], unused[2]
FIELDS = ("flags", "nNodes", "nCoeffs", "nMaxOrder", "nChannels", "nBases",
          "nMetadataBytes", "nParameters", "nParameterValues")


def header_of(data):
    values = HEADER.unpack_from(data, 0)
    if values[0] != b"SCATFUN" or values[1] != 1:
        sys.exit("damage.py: not a SCATFUN version 1 file")
    return dict(zip(FIELDS, values[2:11]))


def table_start(h):
    """Byte offset of the (offset, length) table."""
    return (HEADER.size + 4 * h["nNodes"] + 4 * h["nParameters"] + 4 * h["nParameterValues"]
            + 4 * h["nNodes"] * h["nNodes"] * h["nBases"])


def pairs_of(data, h):
    start = table_start(h)
    count = h["nNodes"] * h["nNodes"]
    flat = struct.unpack_from("<%dI" % (2 * count), data, start)
    return [(k, flat[2 * k], flat[2 * k + 1]) for k in range(count)]


def with_u32(data, byte_offset, value):
    out = bytearray(data)
    struct.pack_into("<I", out, byte_offset, value)
    return bytes(out)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip().splitlines()[-1])
    intact, outdir = sys.argv[1], sys.argv[2]
    with open(intact, "rb") as f:
        data = f.read()
    h = header_of(data)
    per_pair = h["nChannels"] * h["nBases"]  # series stored per (o, i) pair
    pairs = [p for p in pairs_of(data, h) if p[2] > 0]
    if not pairs:
        sys.exit("damage.py: no stored series")
    entry = lambda k: table_start(h) + 8 * k  # byte offset of pair k's offset field
    # The damaged series: the longest one (a specular peak) between two
    # directions 37..53 degrees off the normal, which the sphere shows over a
    # wide ring, so that a wrong series is visible in the image.
    n = h["nNodes"]
    nodes = struct.unpack_from("<%df" % n, data, HEADER.size)
    central = [p for p in pairs
               if 0.6 <= abs(nodes[p[0] % n]) <= 0.8 and 0.6 <= abs(nodes[p[0] // n]) <= 0.8]
    if not central:
        sys.exit("damage.py: no stored series between cosines 0.6 and 0.8")
    early = max(central, key=lambda p: (p[2], -p[1]))
    if early[1] + per_pair * (h["nMaxOrder"] + 1) > h["nCoeffs"]:
        sys.exit("damage.py: the over-long series of pair %d would end past the coefficients"
                 % early[0])
    last = max(pairs, key=lambda p: p[1])  # the series stored last
    cases = [
        ("missing", None, "no file at all"),
        ("header-cut", data[:40], "cut to 40 bytes (inside the header)"),
        ("cut-100000", data[:100000], "cut to 100,000 of %d bytes" % len(data)),
        ("offset-2p30", with_u32(data, entry(early[0]), 1 << 30),
         "offset of pair %d (length %d) set to 2^30" % (early[0], early[2])),
        ("offset-ncoeffs", with_u32(data, entry(early[0]), h["nCoeffs"]),
         "offset of pair %d set to nCoeffs = %d" % (early[0], h["nCoeffs"])),
        ("length-over-max", with_u32(data, entry(early[0]) + 4, h["nMaxOrder"] + 1),
         "length of pair %d set to nMaxOrder + 1 = %d (inside the coefficients)"
         % (early[0], h["nMaxOrder"] + 1)),
        ("length-past-end", with_u32(data, entry(last[0]) + 4, h["nMaxOrder"]),
         "length of the last stored pair %d set to nMaxOrder = %d (past the end)"
         % (last[0], h["nMaxOrder"])),
        ("maxorder-100000", with_u32(data, 20, 100000),
         "header nMaxOrder %d set to 100000" % h["nMaxOrder"]),
    ]
    os.makedirs(outdir, exist_ok=True)
    for name, content, what in cases:
        path = os.path.join(outdir, name + ".bsdf")
        if os.path.exists(path):
            os.remove(path)
        if content is not None:
            with open(path, "wb") as f:
                f.write(content)
        print("%s\t%s" % (name, what))


if __name__ == "__main__":
    main()
