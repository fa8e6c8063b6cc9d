#!/bin/sh
# Fuzz the .bsdf reader and the material language:
#   make fuzz FUZZ_SECONDS=N [FUZZ_TARGET=bsdf|material|all]   (default 60 s each, all)
#   (or sh tests/fuzz/run.sh SECONDS [TARGET])
#
# Builds with clang's libFuzzer, AddressSanitizer and
# UndefinedBehaviorSanitizer:
#   fuzz_bsdf      tests/fuzz/fuzz_bsdf.c against the reader's sources only
#                  (src/reader/, numerics/spline.c, support/):
#                  a renderer that reads files links none of the layer code;
#   fuzz_material  tests/fuzz/fuzz_material.c against every source of the
#                  library (parse, resolution, estimate), single-threaded.
# Each runs from its seed corpus (tests/fuzz/corpus, tests/fuzz/material_corpus)
# with a time limit per input (-timeout=5 s) and a memory limit
# (-rss_limit_mb=2048): a slow or greedy input is a finding like a crash.
# New interesting inputs go to $BUILD/fuzz/<target>-corpus, findings to
# $BUILD/fuzz/<target>-crash-* / -timeout-* / -oom-* (add a finding to the
# seed corpus once fixed: the cmocka suite replays both directories).
# Exit status: non-zero on a finding.
set -eu
cd "$(dirname "$0")/../.."
seconds=${1:-60}
[ -n "$seconds" ] || seconds=60
target=${2:-${FUZZ_TARGET:-all}}
BUILD=${BUILD:-build}
CLANG=${CLANG:-clang}
out=$BUILD/fuzz
mkdir -p "$out"

# libFuzzer's runtime is a separate Debian package from clang itself
# (libclang-rt-N-dev): install it when clang cannot link a fuzzer.
probe=$out/probe.c
printf '%s\n' '#include <stdint.h>' '#include <stddef.h>' \
    'int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);' \
    'int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }' \
    > "$probe"
if ! command -v "$CLANG" >/dev/null 2>&1 ||
   ! "$CLANG" -fsanitize=fuzzer "$probe" -o "$out/probe" 2>/dev/null; then
    version=$("$CLANG" --version 2>/dev/null | sed -n 's/.*clang version \([0-9]*\).*/\1/p' | head -n 1)
    pkgs="libclang-rt-${version:-14}-dev"
    command -v "$CLANG" >/dev/null 2>&1 || pkgs="clang $pkgs"
    echo "fuzz: clang cannot link a fuzzer; installing $pkgs"
    if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
    $SUDO apt-get install -y $pkgs
    "$CLANG" -fsanitize=fuzzer "$probe" -o "$out/probe" || {
        echo "fuzz: clang still cannot link -fsanitize=fuzzer (install $pkgs)" >&2; exit 1; }
fi

# FUZZ_CFLAGS: extra compiler flags for both fuzzers (e.g. -O2)
FLAGS="${FUZZ_CFLAGS:-} -std=c99 -g -O1 -D_POSIX_C_SOURCE=200809L -DLL_EXPERIMENTAL -Iinclude -Isrc -Itests/fuzz \
    -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined"
LIMITS="-timeout=5 -rss_limit_mb=2048 -print_final_stats=1"

build_bsdf() {
    # shellcheck disable=SC2086  # lists of flags and files
    $CLANG $FLAGS tests/fuzz/fuzz_bsdf.c src/reader/*.c src/numerics/spline.c src/support/*.c \
        -lm -o "$out/fuzz_bsdf"
}

build_material() {
    # The library without OpenMP (clang's libomp is not installed; the
    # fuzzer runs one thread): its omp_* calls come from GCC's libgomp,
    # whose header is GCC's (copied alone: GCC's include folder also holds
    # intrinsics headers that clang cannot read).
    omp_dir=$out/omp-include
    mkdir -p "$omp_dir"
    cp "$(gcc -print-file-name=include/omp.h)" "$omp_dir/omp.h"
    blas=$(ls -d /usr/lib/*/openblas-openmp 2>/dev/null | head -n 1)
    # shellcheck disable=SC2086
    $CLANG $FLAGS -Wno-unknown-pragmas -isystem "$omp_dir" -DLL_BUILDING_LIBRARY \
        tests/fuzz/fuzz_material.c src/*/*.c ${blas:+-L$blas -Wl,-rpath,$blas} \
        -llapacke -lopenblas -lgomp -lpthread -lm -ldl -o "$out/fuzz_material"
}

run() { # name seed-dir...
    name=$1; shift
    mkdir -p "$out/$name-corpus"
    echo "fuzz: $name for $seconds s (seeds: $*; new inputs: $out/$name-corpus)"
    # shellcheck disable=SC2086
    "$out/fuzz_$name" -max_total_time="$seconds" $LIMITS -artifact_prefix="$out/$name-" \
        "$out/$name-corpus" "$@"
}

status=0
case $target in
bsdf|all) build_bsdf ;;
esac
case $target in
material|all) build_material ;;
esac
case $target in
bsdf|all)
    # the golden file too, where the project has it
    if [ -d tests/data ]; then run bsdf tests/fuzz/corpus tests/data || status=$?
    else run bsdf tests/fuzz/corpus || status=$?; fi ;;
esac
case $target in
material|all) run material tests/fuzz/material_corpus || status=$? ;;
esac
exit $status
