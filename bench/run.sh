#!/bin/sh
# Benchmarks: run by `make bench` and `make bench-full` after they have
# built the library and tools with -O3 -march=x86-64-v2 into $BUILD
# (build-bench). Compiles the programs of bench/ against that library, runs
# the driver (which runs each measuring program in its own process), prints
# the table and writes the results (JSON). See docs/benchmarks.md.
#
# usage: sh bench/run.sh [--full]
#   (none)  the headline figures, under 10 minutes on a 2-core machine: the
#           original's three recipes at their resolutions, the dust on gold
#           at (400, 1600), adding against dgemm, evaluation and sampling
#           per call, on .bsdf files and on table files made from them, and
#           the build of a GGX interface against a Beckmann one by alpha
#   --full  also the dust on gold at (400, 800) and at its own (1098, 4194),
#           the slab against doubling, coated gold at 1, 2, ... threads,
#           batched evaluation, the tolerance's cost, the textured build,
#           llbuild-mpi's scaling, and bench/convergence.c's modes (the
#           whole convergence grid, docs/method.md's resolution table, the
#           dense scan and a sweep): hours
#
# Environment:
#   BUILD               build directory of the library (default build-bench)
#   CC                  C compiler (default cc)
#   LL_BENCH_RUNS       runs per figure, >= 3 (default 3)
#   LL_BENCH_JSON       output file (default $BUILD/bench/results.json)
#   LL_BENCH_ORIGINAL   optional directory of executables named after the
#                       recipes, timed side by side (docs/benchmarks.md)
#   LL_BENCH_TEXTURED_RUNS  --full: separate builds of the textured section
#   LL_BENCH_CONVERGENCE    --full: 0 skips bench/convergence.c's modes
set -eu

cd "$(dirname "$0")/.."
FULL=0
case "${1:-}" in
"") ;;
--full) FULL=1 ;;
*)
    echo "usage: sh bench/run.sh [--full]" >&2
    exit 2
    ;;
esac
BUILD=${BUILD:-build-bench}
CC=${CC:-cc}
RUNS=${LL_BENCH_RUNS:-3}
JSON=${LL_BENCH_JSON:-$BUILD/bench/results.json}
ORIGINAL=${LL_BENCH_ORIGINAL:-}

if [ ! -f "$BUILD/lib/liblayerlab.so" ]; then
    echo "bench: $BUILD/lib/liblayerlab.so is missing; run 'make bench'" >&2
    exit 1
fi
LIBDIR=$(cd "$BUILD/lib" && pwd)
BIN="$BUILD/bench"
WORK="$BUILD/bench/work"
mkdir -p "$BIN" "$WORK" "$(dirname "$JSON")"

# The same OpenBLAS as the library: the Makefile's BLAS_LIBS and the
# include folder of that build (pkg-config's answer, as the Makefile asks).
BLAS_LIBS=$(make -s --no-print-directory print-blas-libs 2>/dev/null || echo "-llapacke -lopenblas")
BLAS_CFLAGS=$(pkg-config --cflags openblas 2>/dev/null || true)

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
build recipe bench/recipe.c bench/bench_util.c tools/llbuild/time_model.c -Itools/llbuild
# shellcheck disable=SC2086
build adding bench/adding.c bench/bench_util.c -fopenmp $BLAS_CFLAGS $BLAS_LIBS
build eval bench/eval.c bench/calls.c bench/bench_util.c
build tables bench/tables.c bench/calls.c bench/bench_util.c
build ggx_speed bench/ggx_speed.c bench/bench_util.c
build driver bench/driver.c bench/child.c bench/metrics.c bench/targets.c \
    bench/report_table.c bench/report_json.c bench/bench_util.c
if [ "$FULL" = 1 ]; then
    # The slab against doubling needs the internal method choice: the
    # static library (the same objects).
    # shellcheck disable=SC2086
    build slab bench/slab.c bench/bench_util.c -Isrc "$BUILD/lib/liblayerlab.a" -fopenmp $BLAS_LIBS
    build batch bench/batch.c bench/calls.c bench/bench_util.c
    build tolerance bench/tolerance.c bench/bench_util.c
    build textured bench/textured.c bench/child.c bench/metrics.c bench/bench_util.c
    # The convergence modes share tests/convergence_util.h with
    # tests/test_convergence.c (cmocka's assertions, internal headers); each
    # case runs in cmocka's runner, and the metals' spectra are found in
    # $BUILD/share/layerlab/ior from $BIN (bench/convergence.c).
    # shellcheck disable=SC2086
    build convergence bench/convergence.c -DLL_EXPERIMENTAL -Isrc -Itests "$BUILD/lib/liblayerlab.a" -fopenmp \
        $BLAS_CFLAGS $BLAS_LIBS -lcmocka -lpthread
fi

[ -x "$BIN/driver" ] || exit 1

# The textured build against separate builds (bench/textured.c): its own
# table, before the driver's; LL_BENCH_TEXTURED_RUNS (1..64, default 64)
# separate builds, extrapolated to 64 when fewer.
if [ "$FULL" = 1 ] && [ -x "$BIN/textured" ]; then
    "$BIN/textured" "$BUILD/bin/llbuild" "$WORK" "${LL_BENCH_TEXTURED_RUNS:-64}" ||
        echo "bench: textured failed" >&2
fi
# The dust on gold as a material, built by llbuild (the path users take:
# the medium gets its thickness in one pass with its phase matrices), with
# bench/recipe.c's gold indices (the RGB values the original computes for
# gold), so that no IOR folder is needed. The driver names each file and
# its text in the report.
GOLD="0.14317534881908534+3.9826674681176435i,0.37309576813050427+2.3874442318808597i"
GOLD="$GOLD,1.4438276243071315+1.6024561077023662i"
for dust in "dust-on-gold-400x1600 400 1600" "dust-on-gold-400 400 800" "dust-on-gold 1098 4194"; do
    # shellcheck disable=SC2086
    set -- $dust
    printf 'set nodes=%s orders=%s channels=3\nmedium albedo=0.9 g=0.9 tau=4\nconductor eta=%s alpha=0.02\n' \
        "$2" "$3" "$GOLD" > "$WORK/$1.layers"
done

COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ "$COMMIT" != unknown ] && [ -n "$(git status --porcelain -- src include 2>/dev/null)" ]; then
    COMMIT="$COMMIT+local-changes"
fi
COMPILER=$($CC --version 2>/dev/null | head -n 1)

# llbuild-mpi's section (skipped without OpenMPI), before the driver's table.
if [ "$FULL" = 1 ]; then
    sh bench/mpi.sh "$BUILD" || echo "bench: the MPI section failed" >&2
fi

status=0
"$BIN/driver" --bin "$BIN" --work "$WORK" --testdata tests/data --json "$JSON" \
    --runs "$RUNS" --full "$FULL" --original "$ORIGINAL" \
    --llbuild "$BUILD/bin/llbuild" --commit "$COMMIT" \
    --compiler "$COMPILER -O3 -march=x86-64-v2" || status=$?

# GGX against Beckmann at the same resolution (bench/ggx_speed.c): its own
# table, by alpha, after the driver's (about 15 s of CPU).
echo
if [ -x "$BIN/ggx_speed" ]; then
    "$BIN/ggx_speed" 200 3 || status=1
else
    echo "bench: bench/ggx_speed.c did not build" >&2
    status=1
fi

# bench/convergence.c's modes: the resolution's convergence beyond the
# test's subset (docs/method.md). Each prints the materials it checks.
if [ "$FULL" = 1 ] && [ "${LL_BENCH_CONVERGENCE:-1}" != 0 ]; then
    if [ -x "$BIN/convergence" ]; then
        echo
        echo "convergence: docs/method.md's resolution table"
        "$BIN/convergence" table || status=1
        echo "convergence: the search's own error against n (eta 1.5, alpha 0.5, 59 orders)"
        "$BIN/convergence" sweep 1.5 0 0.5 59 150 700 || status=1
        echo "convergence: the dense scan of every interface case"
        "$BIN/convergence" dense || status=1
        echo "convergence: the whole grid (interfaces, media, slabs) at the tolerance 1%"
        LL_CONVERGENCE_VERBOSE=1 "$BIN/convergence" full || status=1
    else
        echo "bench: bench/convergence.c did not build" >&2
        status=1
    fi
fi
exit "$status"
