#!/bin/sh
# bench/convergence.c (`make bench-full`'s convergence modes, not part of the
# tests otherwise) reports a failed check with its case and its message and
# goes on, instead of ending with cmocka's bare status 255: its cmocka
# assertions run inside cmocka's runner. Built as bench/run.sh builds it,
# against $BUILD/lib/liblayerlab.a, but into a scratch directory: linked
# statically, the program looks for the metals' spectra in
# ../share/layerlab/ior from its own folder (src/material/ior.c), which
# there does not exist, so `conductor eta=Au` fails to parse; with
# LAYERLAB_IOR_DIR the same row is measured. Its table row of gold at alpha
# 0.5 takes about a second. Run by `make test` with BUILD and CC set.
set -u
BUILD=${BUILD:-build}
CC=${CC:-cc}

. "$(dirname "$0")/lib/tool_test.sh"
root=$(cd "$(dirname "$0")/.." && pwd)
case "$BUILD" in
    /*) build="$BUILD" ;;
    *) build="$root/$BUILD" ;;
esac

tool_test_begin bench-convergence
if [ ! -f "$build/lib/liblayerlab.a" ]; then
    bad "$build/lib/liblayerlab.a is not built"
    tool_test_end bench_convergence.sh
    exit 1
fi

# A sanitizer's or coverage build of the library needs the program built
# the same way.
san=""
if nm "$build/lib/liblayerlab.a" 2>/dev/null | grep -q __asan_init; then
    san="-fsanitize=address,undefined"
elif nm "$build/lib/liblayerlab.a" 2>/dev/null | grep -q __tsan_init; then
    san="-fsanitize=thread"
elif nm "$build/lib/liblayerlab.a" 2>/dev/null | grep -q __gcov_init; then
    san="--coverage"
fi
blas_libs=$(make -s --no-print-directory -C "$root" print-blas-libs 2>/dev/null ||
    echo "-llapacke -lopenblas")
blas_cflags=$(pkg-config --cflags openblas 2>/dev/null || true)
# shellcheck disable=SC2086
if $CC -std=c99 -O2 -Wall -Wextra -pedantic -Werror -D_DEFAULT_SOURCE $san \
        -I"$root/include" -I"$root/src" -I"$root/tests" -DLL_EXPERIMENTAL \
        -o "$tmp/convergence" "$root/bench/convergence.c" "$build/lib/liblayerlab.a" \
        -fopenmp $blas_cflags $blas_libs -lcmocka -lpthread -lm >"$tmp/cc.log" 2>&1; then
    pass "bench/convergence.c builds as bench/run.sh builds it"
else
    bad "bench/convergence.c does not build:"
    sed 's/^/  | /' "$tmp/cc.log" | head -20
    tool_test_end bench_convergence.sh
    exit 1
fi

# No ior folder beside the program: the row fails, saying which and why.
(unset LAYERLAB_IOR_DIR
 LL_CONVERGENCE_CASES="Au alpha=0.5" "$tmp/convergence" table >"$tmp/no-ior.out" 2>&1)
status=$?
if [ "$status" -eq 1 ]; then
    pass "a row that fails a check: exit 1"
else
    bad "a row that fails a check: exit $status, expected 1"
    sed 's/^/  | /' "$tmp/no-ior.out" | head -20
fi
contains "$tmp/no-ior.out" "FAILED  \] gold, alpha 0.5" "the failed row is named"
contains "$tmp/no-ior.out" "unknown metal 'Au'" "the library's message is printed"
contains "$tmp/no-ior.out" "ll_material_parse" "the failed call is named"
contains "$tmp/no-ior.out" "1 row failed" "the table says a row failed"

# With the spectra: the row is measured, once as it comes and once in the table.
LAYERLAB_IOR_DIR="$root/data/ior" LL_CONVERGENCE_CASES="Au alpha=0.5" \
    "$tmp/convergence" table >"$tmp/ior.out" 2>&1
status=$?
if [ "$status" -eq 0 ]; then
    pass "with LAYERLAB_IOR_DIR the row is measured: exit 0"
else
    bad "with LAYERLAB_IOR_DIR: exit $status, expected 0"
    sed 's/^/  | /' "$tmp/ior.out" | head -20
fi
rows=$(grep -c '^| gold, alpha 0.5 | [0-9]* x [0-9]*, .*% | [0-9]* x [0-9]*, .*% |$' "$tmp/ior.out")
if [ "$rows" -eq 2 ]; then
    pass "the row, as measured and in the table"
else
    bad "the row appears $rows times, expected 2:"
    sed 's/^/  | /' "$tmp/ior.out" | head -20
fi
tool_test_end bench_convergence.sh
