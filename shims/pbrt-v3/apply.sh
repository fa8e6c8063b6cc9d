#!/bin/sh
# Apply the layerlab shim to a pbrt-v3 source checkout (see README.md):
# copies three files into src/materials/, points the "fourier" material of
# src/core/api.cpp at them, and links liblayerlab through pkg-config in
# CMakeLists.txt. It edits files only (it builds nothing) and is idempotent.
# Usage: sh apply.sh /path/to/pbrt-v3
set -eu
here=$(cd "$(dirname "$0")" && pwd)
pbrt=${1:?usage: sh apply.sh /path/to/pbrt-v3}
api=$pbrt/src/core/api.cpp
cmake=$pbrt/CMakeLists.txt
for f in "$api" "$cmake" "$pbrt/src/materials/fourier.h"; do
    [ -f "$f" ] || { echo "apply.sh: $f not found: is $pbrt a pbrt-v3 checkout?" >&2; exit 1; }
done

cp "$here/layerlab_pbrt_adapter.h" "$here/layerlabfourier.h" "$here/layerlabfourier.cpp" \
   "$pbrt/src/materials/"

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

# CMakeLists.txt: link the pbrt library (and so every program) to liblayerlab.
if ! grep -q 'PkgConfig::LAYERLAB' "$cmake"; then
    cat >> "$cmake" <<'CMAKE'

# layerlab: the "fourier" material reads .bsdf files through liblayerlab
FIND_PACKAGE ( PkgConfig REQUIRED )
PKG_CHECK_MODULES ( LAYERLAB REQUIRED IMPORTED_TARGET layerlab )
TARGET_LINK_LIBRARIES ( pbrt PkgConfig::LAYERLAB )
CMAKE
fi
echo "apply.sh: shim applied to $pbrt"
