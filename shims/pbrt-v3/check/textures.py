"""Float textures and region comparisons for the textured scenes of
`make pbrt-check` (check.sh, section 4).

  python3 textures.py halves OUT.pfm TOP BOTTOM
      a 64 x 64 grey PFM image whose upper half is TOP and lower half BOTTOM
      (pbrt-v3's imagemap texture flips images so that t = 0 is the bottom
      row; the sphere's v runs from its bottom, z = -r, to its top, so the
      image's upper half lands on the sphere's upper half);
  python3 textures.py stripes OUT.pfm LO HI
      a 256 x 128 grey PFM image: 24 stripes around the sphere (u) that
      alternate between LO and a ramp from LO (bottom) to HI (top) in v;
  python3 textures.py checks OUT.pfm LO HI
      a 256 x 128 grey PFM image: a checkerboard of LO and HI, 16 squares
      around the sphere (u) by 8 from pole to pole (v) (the README's scene);
  python3 textures.py regions TEX.pfm A.pfm B.pfm UP0 UP1 LOW0 LOW1
      over picture rows [UP0, UP1) and [LOW0, LOW1) (row 0 at the top):
      prints "UP N_UP LOW N_LOW": among the pixels that A and B render
      differently, the share in the upper rows where TEX is closer to A
      than to B (and their count), and the share in the lower rows where it
      is closer to B than to A.
"""
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from imgdiff import read_pfm  # noqa: E402


def write_pfm(path, width, height, value):
    """value(x, y) for x in [0, width), y in [0, height), y = 0 the top row;
    PFM stores the bottom row first."""
    rows = []
    for y in range(height - 1, -1, -1):
        row = []
        for x in range(width):
            v = value(x, y)
            row.extend((v, v, v))
        rows.append(struct.pack("<%df" % len(row), *row))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1\n" % (width, height))
        f.write(b"".join(rows))


def closer_fraction(tex, a, b, width, height, rows):
    """Among the pixels of the picture rows `rows` (0 = the top row; a PFM
    file, and read_pfm's array, holds the bottom row first) that A and B
    render differently (their luminances differ by more than 5 % of the
    larger), the share where TEX is closer to A than to B, and their count.
    A share, not an RMSE: the same sample takes other paths under another
    roughness, and a few bright paths (off one half onto the other) would
    dominate an RMSE."""
    closer = count = 0
    for y in rows:
        r = height - 1 - y
        for x in range(width):
            k = 3 * (r * width + x)
            lt, la, lb = (0.212671 * img[k] + 0.715160 * img[k + 1] + 0.072169 * img[k + 2]
                          for img in (tex, a, b))
            if abs(la - lb) > 0.05 * max(la, lb):
                count += 1
                closer += abs(lt - la) < abs(lt - lb)
    return (closer / count if count else 0.0), count


def main():
    args = sys.argv[1:]
    if len(args) == 4 and args[0] == "halves":
        top, bottom = float(args[2]), float(args[3])
        write_pfm(args[1], 64, 64, lambda x, y: top if y < 32 else bottom)
    elif len(args) == 4 and args[0] == "stripes":
        lo, hi = float(args[2]), float(args[3])
        width, height = 256, 128

        def value(x, y):
            ramp = lo + (hi - lo) * (height - 1 - y) / (height - 1)
            return ramp if (x * 24 // width) % 2 else lo
        write_pfm(args[1], width, height, value)
    elif len(args) == 4 and args[0] == "checks":
        lo, hi = float(args[2]), float(args[3])
        write_pfm(args[1], 256, 128, lambda x, y: hi if (x // 16 + y // 16) % 2 else lo)
    elif len(args) == 8 and args[0] == "regions":
        images = [read_pfm(p) for p in args[1:4]]
        width, height = images[0][0], images[0][1]
        if any((w, h) != (width, height) for w, h, _ in images):
            sys.exit("textures.py: the images differ in size")
        tex, a, b = (img[2] for img in images)
        top = range(int(args[4]), int(args[5]))
        bottom = range(int(args[6]), int(args[7]))
        if not (0 <= top.start < top.stop <= height and 0 <= bottom.start < bottom.stop <= height):
            sys.exit("textures.py: the row ranges must lie inside the %d rows" % height)
        up, n_up = closer_fraction(tex, a, b, width, height, top)
        low, n_low = closer_fraction(tex, b, a, width, height, bottom)
        print("%.3f %d %.3f %d" % (up, n_up, low, n_low))
    else:
        sys.exit(__doc__.strip())


if __name__ == "__main__":
    main()
