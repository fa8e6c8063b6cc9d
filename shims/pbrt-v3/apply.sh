#!/bin/sh
# Apply the layerlab shim to a pbrt-v3 source checkout (see README.md):
# copies three files into src/materials/, points the "fourier" material of
# src/core/api.cpp at them, and links liblayerlab through pkg-config in
# CMakeLists.txt. It edits files only (it builds nothing) and is idempotent.
# With --system-libs it first runs system-libs.sh, which makes a plain
# (non-recursive) checkout build against the system's OpenEXR, glog and zlib.
# Usage: sh apply.sh [--system-libs] /path/to/pbrt-v3
set -eu
here=$(cd "$(dirname "$0")" && pwd)
usage="usage: sh apply.sh [--system-libs] /path/to/pbrt-v3"
system_libs=no
if [ "${1:-}" = --system-libs ]; then system_libs=yes; shift; fi
pbrt=${1:?$usage}
[ $# -eq 1 ] || { echo "$usage" >&2; exit 1; }
api=$pbrt/src/core/api.cpp
cmake=$pbrt/CMakeLists.txt
for f in "$api" "$cmake" "$pbrt/src/materials/fourier.h"; do
    [ -f "$f" ] || { echo "apply.sh: $f not found: is $pbrt a pbrt-v3 checkout?" >&2; exit 1; }
done

[ $system_libs = no ] || sh "$here/system-libs.sh" "$pbrt"

# Copied only when they differ, so that a second run rebuilds nothing.
for f in layerlab_pbrt_adapter.h layerlabfourier.h layerlabfourier.cpp; do
    cmp -s "$here/$f" "$pbrt/src/materials/$f" || cp "$here/$f" "$pbrt/src/materials/"
done

# api.cpp: include the shim's header and create its material for "fourier".
if ! grep -q 'CreateLayerlabFourierMaterial' "$api"; then
    [ "$(grep -c 'material = CreateFourierMaterial(mp);' "$api")" = 1 ] &&
    [ "$(grep -c '^#include "materials/fourier.h"$' "$api")" = 1 ] || {
        echo "apply.sh: $api does not look like pbrt-v3's api.cpp; edit it by hand (README.md)" >&2
        exit 1
    }
    awk '{
        if ($0 == "#include \"materials/fourier.h\"") {
            print; print "#include \"materials/layerlabfourier.h\""; next
        }
        sub(/material = CreateFourierMaterial\(mp\);/,
            "material = CreateLayerlabFourierMaterial(mp);")
        print
    }' "$api" > "$api.layerlab-tmp" && mv "$api.layerlab-tmp" "$api"
fi

# CMakeLists.txt: link the pbrt library (and so every program) to liblayerlab:
# the reader-only library when it is installed (layerlab-reader.pc; the shim
# only reads files), the whole library otherwise. An older application of
# this script linked `layerlab` only; its line is upgraded in place.
search='PKG_SEARCH_MODULE ( LAYERLAB REQUIRED IMPORTED_TARGET layerlab-reader layerlab )'
if grep -q '^PKG_CHECK_MODULES ( LAYERLAB REQUIRED IMPORTED_TARGET layerlab )$' "$cmake"; then
    awk -v search="$search" '
        $0 == "PKG_CHECK_MODULES ( LAYERLAB REQUIRED IMPORTED_TARGET layerlab )" { print search; next }
        { print }' "$cmake" > "$cmake.layerlab-tmp" && mv "$cmake.layerlab-tmp" "$cmake"
fi
if ! grep -q 'PkgConfig::LAYERLAB' "$cmake"; then
    cat >> "$cmake" <<CMAKE

# layerlab: the "fourier" material reads .bsdf files through liblayerlab
FIND_PACKAGE ( PkgConfig REQUIRED )
$search
TARGET_LINK_LIBRARIES ( pbrt PkgConfig::LAYERLAB )
CMAKE
fi
echo "apply.sh: shim applied to $pbrt"
