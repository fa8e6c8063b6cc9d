#!/bin/sh
# Fuzz the .bsdf reader: `make fuzz FUZZ_SECONDS=N` (default 60 seconds).
#
# Builds tests/fuzz/fuzz_bsdf.c with clang's libFuzzer, AddressSanitizer and
# UndefinedBehaviorSanitizer against the reader's sources only (every
# src/bsdf_*.c but the writer, plus spline.c and support.c: the reader
# needs no layer code), then runs it from the seed corpus tests/fuzz/corpus
# and the golden file in tests/data. New interesting inputs go to
# $BUILD/fuzz/corpus, findings to $BUILD/fuzz/crash-* (add a finding to
# tests/fuzz/corpus once fixed: the cmocka suite replays that directory).
# Exit status: libFuzzer's (non-zero on a finding).
set -eu
cd "$(dirname "$0")/../.."
seconds=${1:-60}
[ -n "$seconds" ] || seconds=60
BUILD=${BUILD:-build}
CLANG=${CLANG:-clang}
out=$BUILD/fuzz
mkdir -p "$out/corpus"

sources=$(ls src/storage/bsdf_*.c | grep -v -e bsdf_write.c -e bsdf_file_out.c)
# shellcheck disable=SC2086  # lists of flags and files
$CLANG -std=c99 -g -O1 -D_POSIX_C_SOURCE=200809L -Iinclude -Isrc -Itests/fuzz \
    -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=undefined \
    tests/fuzz/fuzz_bsdf.c $sources src/numerics/spline.c src/support/error.c src/support/alloc.c -lm -o "$out/fuzz_bsdf"

seeds="tests/fuzz/corpus"
seeds="$seeds tests/data"
echo "fuzz: running for $seconds s (seeds: $seeds; new inputs: $out/corpus)"
# shellcheck disable=SC2086
exec "$out/fuzz_bsdf" -max_total_time="$seconds" -artifact_prefix="$out/" \
    -print_final_stats=1 "$out/corpus" $seeds
