"""Compare two PFM images of the same size (pbrt-v3 writes PFM for a
`.pfm` file name) over all pixels and channels, and print on one line:
`mean_a mean_b mean_abs_diff rmse rmse_over_mean identical_fraction`
(rmse_over_mean divides by the mean of the first image; identical_fraction
is the share of pixels whose three channels agree bit for bit).
With one image, prints its mean only.

usage: python3 imgdiff.py A.pfm [B.pfm]
"""
import array
import math
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    # Three whitespace-terminated header tokens: PF, "width height", scale.
    tokens, pos = [], 0
    while len(tokens) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        tokens.append(data[pos:end].decode("ascii"))
        pos = end
    pos += 1  # the single whitespace byte before the pixels
    if tokens[0] != "PF":
        sys.exit("imgdiff.py: %s is not an RGB PFM file" % path)
    width, height, scale = int(tokens[1]), int(tokens[2]), float(tokens[3])
    pixels = array.array("f")
    pixels.frombytes(data[pos:pos + 12 * width * height])
    if len(pixels) != 3 * width * height:
        sys.exit("imgdiff.py: %s is truncated" % path)
    if (scale < 0) != (sys.byteorder == "little"):
        pixels.byteswap()
    return width, height, pixels


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__.strip().splitlines()[-1])
    wa, ha, a = read_pfm(sys.argv[1])
    mean_a = sum(a) / len(a)
    if len(sys.argv) == 2:
        print("%.6g" % mean_a)
        return
    wb, hb, b = read_pfm(sys.argv[2])
    if (wa, ha) != (wb, hb):
        sys.exit("imgdiff.py: %dx%d and %dx%d differ in size" % (wa, ha, wb, hb))
    abs_sum = sq_sum = 0.0
    for x, y in zip(a, b):
        d = x - y
        abs_sum += abs(d)
        sq_sum += d * d
    same = sum(1 for k in range(0, len(a), 3) if a[k:k + 3] == b[k:k + 3])
    rmse = math.sqrt(sq_sum / len(a))
    ratio = rmse / mean_a if mean_a > 0 else float("inf")
    print("%.6g %.6g %.3g %.3g %.3g %.3f" % (mean_a, sum(b) / len(b), abs_sum / len(a), rmse,
                                             ratio, same / (wa * ha)))


if __name__ == "__main__":
    main()
