#!/bin/sh
# The README's main job (`make demo`, which builds everything first):
# compile examples/coated-gold.layers into out/coated-gold.bsdf, print the
# build summary, and draw its picture when llplot exists.
# BUILD selects the build directory (default: build).
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
llplot="$BUILD/bin/llplot"

if [ ! -x "$llbuild" ]; then
    echo "demo: $llbuild is missing; run make first" >&2
    exit 1
fi
mkdir -p out
echo "demo: compiling examples/coated-gold.layers (rough gold under a rough clear coat)"
"$llbuild" examples/coated-gold.layers -o out/coated-gold.bsdf
if [ -x "$llplot" ]; then
    "$llplot" --sphere out/coated-gold.bsdf -o out/coated-gold.png
    echo "demo: picture written to out/coated-gold.png"
else
    echo "demo: $llplot is not built; no picture"
fi
echo "demo: out/coated-gold.bsdf is ready for pbrt-v3's \"fourier\" material:"
echo "      Material \"fourier\" \"string bsdffile\" \"out/coated-gold.bsdf\""
