#!/bin/sh
# Benchmarks: run by `make bench` after it has built the library and tools
# with -O3 -march=x86-64-v2 into $BUILD (build-bench). Compiles the
# programs of bench/ against that shared library, runs the driver (which
# runs everything else in separate processes), prints the table and writes
# bench/results.json. See docs/benchmarks.md.
#
# Environment:
#   BUILD               build directory of the library (default build-bench)
#   CC                  C compiler (default cc)
#   LL_BENCH_RUNS       runs per figure, >= 3 (default 3)
#   LL_BENCH_JSON       output file (default bench/results.json)
#   LL_BENCH_ORIGINAL   optional directory of executables named after the
#                       recipes, timed side by side (docs/benchmarks.md)
set -eu

cd "$(dirname "$0")/.."
BUILD=${BUILD:-build-bench}
CC=${CC:-cc}
RUNS=${LL_BENCH_RUNS:-3}
JSON=${LL_BENCH_JSON:-bench/results.json}
ORIGINAL=${LL_BENCH_ORIGINAL:-}

if [ ! -f "$BUILD/lib/liblayerlab.so" ]; then
    echo "bench: $BUILD/lib/liblayerlab.so is missing; run 'make bench'" >&2
    exit 1
fi
LIBDIR=$(cd "$BUILD/lib" && pwd)
BIN="$BUILD/bench"
WORK="$BUILD/bench/work"
mkdir -p "$BIN" "$WORK"

# The same OpenBLAS as the library (the Makefile's BLAS_LIBS).
MULTIARCH=$($CC -print-multiarch 2>/dev/null || true)
BLAS_DIR=/usr/lib/$MULTIARCH/openblas-openmp
BLAS_INC=/usr/include/$MULTIARCH/openblas-openmp
if [ -n "$MULTIARCH" ] && [ -d "$BLAS_DIR" ]; then
    BLAS_LIBS="-L$BLAS_DIR -Wl,-rpath,$BLAS_DIR -llapacke -lopenblas"
else
    BLAS_LIBS="-llapacke -lopenblas"
fi
BLAS_CFLAGS=""
[ -n "$MULTIARCH" ] && [ -d "$BLAS_INC" ] && BLAS_CFLAGS="-I$BLAS_INC"

CFLAGS="-std=c99 -O3 -march=x86-64-v2 -g -Wall -Wextra -pedantic -Werror -D_DEFAULT_SOURCE -Iinclude"
LIBS="-L$LIBDIR -Wl,-rpath,$LIBDIR -llayerlab -lm"

# A measuring program that does not build (a part of the library still
# missing) is reported by the driver as a failed figure; the rest still runs.
build() { # name, sources and extra flags
    name=$1
    shift
    echo "bench: cc $name" >&2
    rm -f "$BIN/$name"
    # shellcheck disable=SC2086
    $CC $CFLAGS -o "$BIN/$name" "$@" $LIBS || echo "bench: $name did not build" >&2
}
build recipe bench/recipe.c bench/bench_util.c
# shellcheck disable=SC2086
build adding bench/adding.c bench/bench_util.c -fopenmp $BLAS_CFLAGS $BLAS_LIBS
build eval bench/eval.c bench/bench_util.c
build batch bench/batch.c bench/bench_util.c
build driver bench/driver.c bench/child.c bench/metrics.c bench/targets.c \
    bench/report_table.c bench/report_json.c bench/bench_util.c

[ -x "$BIN/driver" ] || exit 1

# The textured build against separate builds (bench/textured.c): its own
# table, before the driver's; LL_BENCH_TEXTURED_RUNS (1..64, default 64)
# separate builds, extrapolated to 64 when fewer.
build textured bench/textured.c bench/child.c bench/metrics.c bench/bench_util.c
if [ -x "$BIN/textured" ]; then
    "$BIN/textured" "$BUILD/bin/llbuild" "$WORK" "${LL_BENCH_TEXTURED_RUNS:-64}" ||
        echo "bench: textured failed" >&2
fi

COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ "$COMMIT" != unknown ] && [ -n "$(git status --porcelain -- src include 2>/dev/null)" ]; then
    COMMIT="$COMMIT+local-changes"
fi
COMPILER=$($CC --version 2>/dev/null | head -n 1)

# llbuild-mpi's section (skipped without OpenMPI), before the driver's table.
sh bench/mpi.sh "$BUILD" || echo "bench: the MPI section failed" >&2

exec "$BIN/driver" --bin "$BIN" --work "$WORK" --testdata tests/data --json "$JSON" \
    --runs "$RUNS" --original "$ORIGINAL" --commit "$COMMIT" \
    --compiler "$COMPILER -O3 -march=x86-64-v2"
