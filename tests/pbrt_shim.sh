#!/bin/sh
# The pbrt-v3 shim's adapter (shims/pbrt-v3/layerlab_pbrt_adapter.h) compiled
# as C++11 and linked against the reader library (liblayerlab_reader: a
# renderer needs nothing that builds layers), then its tests
# (tests/test_pbrt_shim.cpp).
# Run by `make check` with BUILD, CC and CXX set; prints "N passed, N failed".
set -u
cd "$(dirname "$0")/.." || exit 1
BUILD=${BUILD:-build}
CXX=${CXX:-c++}
case $BUILD in /*) build_dir=$BUILD ;; *) build_dir=$(pwd)/$BUILD ;; esac
lib=$build_dir/lib/liblayerlab_reader.so
if [ ! -e "$lib" ]; then
    echo "pbrt_shim: $lib is missing (run make first)"
    echo "0 passed, 1 failed"
    exit 1
fi

# A library built with sanitizers needs them in the program too.
san=
if readelf -d "$lib" 2>/dev/null | grep -q 'libasan'; then
    san="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
fi

mkdir -p "$build_dir/tests"
program=$build_dir/tests/test_pbrt_shim
# shellcheck disable=SC2086  # $san is a list of flags
if ! $CXX -std=c++11 -O1 -g -Wall -Wextra -pedantic -Werror $san \
        -Iinclude -Ishims/pbrt-v3 tests/test_pbrt_shim.cpp -o "$program" \
        -L"$build_dir/lib" -Wl,-rpath,"$build_dir/lib" -llayerlab_reader; then
    echo "pbrt_shim: the adapter does not compile as C++11"
    echo "0 passed, 1 failed"
    exit 1
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/pbrt_shim.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM
"$program" "$(pwd)" "$tmp"
