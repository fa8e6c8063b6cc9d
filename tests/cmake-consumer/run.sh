#!/bin/sh
# The CMake build as a renderer's build uses it (make cmake-check, CI):
#   1. CMakeLists.txt configured in $CMAKE_BUILD (default build-cmake), built
#      and installed into $CMAKE_BUILD/prefix;
#   2. its reader file list equal to the Makefile's (make print-reader-src);
#   3. this folder's project configured against the installed package alone
#      (find_package(layerlab) through CMAKE_PREFIX_PATH), built, and its
#      four programs run (shared and static, whole library and reader).
# Prints one line per check and "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root" || exit 1
CMAKE_BUILD=${CMAKE_BUILD:-build-cmake}
case $CMAKE_BUILD in /*) build=$CMAKE_BUILD ;; *) build=$root/$CMAKE_BUILD ;; esac
prefix=$build/prefix
consumer=$build/consumer
jobs=${CMAKE_JOBS:-2}
passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
finish() { echo "$passed passed, $failed failed"; [ "$failed" -eq 0 ]; exit $?; }

rm -rf "$prefix" "$consumer"
mkdir -p "$build" || exit 1
log=$build/check
if cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$prefix" \
        >"$log-configure.log" 2>&1 &&
   cmake --build "$build" -j "$jobs" >"$log-build.log" 2>&1 &&
   cmake --install "$build" >"$log-install.log" 2>&1; then
    pass "CMakeLists.txt configures, builds and installs into $prefix"
else
    fail "the CMake build (logs: $log-*.log)"
    tail -20 "$log-configure.log" "$log-build.log" "$log-install.log" 2>/dev/null | sed 's/^/    /'
    finish
fi

for f in lib/liblayerlab.so.1 lib/liblayerlab.a lib/liblayerlab_reader.so.1 lib/liblayerlab_reader.a \
         include/layerlab.h include/layerlab/ll_bsdf.h share/layerlab/ior/Au.eta.spd \
         lib/cmake/layerlab/layerlabConfig.cmake lib/cmake/layerlab/layerlabConfigVersion.cmake; do
    [ -e "$prefix/$f" ] || fail "not installed: $f"
done
[ "$failed" -eq 0 ] && pass "installed: both libraries (shared and static), headers, spectra, package files"

make_list=$(make -s --no-print-directory print-reader-src)
cmake_list=$(cat "$build/reader-sources.txt")
if [ "$make_list" = "$cmake_list" ]; then
    pass "the reader's sources are the Makefile's ($(echo "$make_list" | wc -w) files)"
else
    fail "the reader's sources differ: make: $make_list; cmake: $cmake_list"
fi

# The sonames and the reader's dependencies, as tests/abi.sh holds them for the Makefile's.
if readelf -d "$prefix/lib/liblayerlab.so.1" | grep -q 'SONAME.*\[liblayerlab.so.1\]' &&
   readelf -d "$prefix/lib/liblayerlab_reader.so.1" | grep -q 'SONAME.*\[liblayerlab_reader.so.1\]'; then
    pass "sonames liblayerlab.so.1 and liblayerlab_reader.so.1"
else
    fail "sonames"
fi
others=$(for l in liblayerlab.so.1 liblayerlab_reader.so.1; do
             nm -D --defined-only "$prefix/lib/$l" | awk '$2 != "A" && $3 != "" && $3 !~ /^ll_/ { print $3 }'
         done)
if [ -z "$others" ]; then
    pass "both export ll_* symbols only (their version scripts)"
else
    fail "symbols exported besides ll_*: $others"
fi
if readelf -d "$prefix/lib/liblayerlab_reader.so.1" | grep NEEDED | grep -q -E 'blas|lapack|gomp'; then
    fail "the reader needs OpenBLAS, LAPACKE or OpenMP"
else
    pass "the reader needs none of OpenBLAS, LAPACKE, OpenMP"
fi

if cmake -S tests/cmake-consumer -B "$consumer" -DCMAKE_PREFIX_PATH="$prefix" \
        >"$log-consumer-configure.log" 2>&1 &&
   cmake --build "$consumer" -j "$jobs" >"$log-consumer-build.log" 2>&1; then
    pass "tests/cmake-consumer builds with find_package(layerlab)"
else
    fail "tests/cmake-consumer (logs: $log-consumer-*.log)"
    tail -20 "$log-consumer-configure.log" "$log-consumer-build.log" 2>/dev/null | sed 's/^/    /'
    finish
fi
for p in uses_layerlab uses_layerlab_static uses_reader uses_reader_static; do
    if out=$("$consumer/$p" 2>&1); then
        pass "$p: $out"
    else
        fail "$p: $out"
    fi
done
finish
