#!/bin/sh
# llplot: build the checker (it reads pictures back with the OpenEXR C API
# and cairo, which the cmocka rule of the Makefile does not link) and run it
# against $BUILD/bin/llplot. Run by `make test` with BUILD, CC set.
set -eu
BUILD=${BUILD:-build}
CC=${CC:-cc}
root=$(cd "$(dirname "$0")/.." && pwd)
case "$BUILD" in
    /*) build="$BUILD" ;;
    *) build="$root/$BUILD" ;;
esac
llplot="$build/bin/llplot"
checker="$build/tests/check_llplot"

if [ ! -x "$llplot" ]; then
    echo "llplot.sh: $llplot is missing (run make first)" >&2
    exit 1
fi
if ! pkg-config --exists cairo OpenEXR; then
    echo "llplot.sh: cairo or OpenEXR development files are missing (make deps)" >&2
    exit 1
fi

# A sanitizer build of the library needs the checker built the same way.
san=""
if nm -D "$build/lib/liblayerlab.so" 2>/dev/null | grep -q __asan_init; then
    san="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
fi

mkdir -p "$build/tests"
# shellcheck disable=SC2046,SC2086
$CC -std=c99 -O1 -g -Wall -Wextra -pedantic -Werror -D_POSIX_C_SOURCE=200809L $san \
    -I"$root/include" $(pkg-config --cflags cairo OpenEXR) \
    -o "$checker" "$root/tools/llplot/tests/check_llplot.c" \
    -L"$build/lib" -Wl,-rpath,"$build/lib" -llayerlab \
    $(pkg-config --libs cairo OpenEXR) -lcmocka -lm

work=$(mktemp -d "${TMPDIR:-/tmp}/llplot-test.XXXXXX")
trap 'rm -rf "$work"' EXIT
LAYERLAB_CACHE_DIR="$work/cache"
export LAYERLAB_CACHE_DIR
trap 'exit 130' INT TERM
if [ -n "$san" ]; then
    # fontconfig (under cairo's text) keeps its configuration until exit;
    # leaks of our own code are still reported.
    printf 'leak:libfontconfig.so\n' > "$work/lsan.supp"
    LSAN_OPTIONS="suppressions=$work/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
    export LSAN_OPTIONS
fi
"$checker" "$llplot" "$work" || exit 1

# A textured file from a material template (tests/textured_grid.c, on the
# public API: ll_material_build_layers per sample, ll_bsdf_write_textured
# with the names in the metadata), drawn by name: --grid and --vary work on
# what a material build produces, and a wrong name is refused.
grid_tool="$build/tests/textured_grid"
# shellcheck disable=SC2086
$CC -std=c99 -O1 -g -Wall -Wextra -pedantic -Werror -D_POSIX_C_SOURCE=200809L $san \
    -I"$root/include" -o "$grid_tool" "$root/tests/textured_grid.c" \
    -L"$build/lib" -Wl,-rpath,"$build/lib" -llayerlab -lm
failed=0
check() { if "$@" > "$work/step.log" 2>&1; then echo "PASS: $step"; else echo "FAIL: $step"; cat "$work/step.log"; failed=1; fi; }
step="textured_grid builds a 3 x 2 file of a dielectric over a diffuse base"
check "$grid_tool" "$work/tg.bsdf" \
    'dielectric eta=1.5 alpha={0}\ndiffuse albedo={1}\nset nodes=16 orders=8' \
    coat.alpha=0.1,0.2,0.4 base.albedo=0.2,0.8
step="llplot --grid on it writes a PNG and an EXR of 3 x 2 cells of 16 pixels"
check sh -c '"$1" --grid "$2/tg.bsdf" -o "$2/tg.png" --size 16 --spp 2 &&
    "$1" --grid "$2/tg.bsdf" -o "$2/tg.exr" --size 16 --spp 2 &&
    [ -s "$2/tg.png" ] && [ -s "$2/tg.exr" ]' sh "$llplot" "$work"
step="llplot --vary base.albedo --param coat.alpha=0.3 on it"
check "$llplot" --sphere "$work/tg.bsdf" --vary base.albedo --param coat.alpha=0.3 \
    -o "$work/tg-vary.png" --size 24 --spp 2
step="llplot --vary with a name the file does not have exits 1 and names both"
check sh -c '"$1" --sphere "$2/tg.bsdf" --vary alpha -o "$2/bad.png" 2> "$2/err.txt";
    [ $? = 1 ] && grep -q "coat.alpha, base.albedo" "$2/err.txt" && [ ! -e "$2/bad.png" ]' \
    sh "$llplot" "$work"
step="llplot --grid and --vary on a swept material file (compiled to its textured file)"
printf 'dielectric eta=1.5 alpha=[0.1 0.3]\ndiffuse name=base albedo=[0.2 0.8]\nset nodes=16 orders=8\n' \
    > "$work/swept.layers"
check sh -c '"$1" --grid "$2/swept.layers" -o "$2/swept.exr" --size 16 --spp 2 &&
    "$1" --sphere "$2/swept.layers" --vary base.albedo -o "$2/swept.png" --size 16 --spp 2 &&
    [ -s "$2/swept.exr" ] && [ -s "$2/swept.png" ]' sh "$llplot" "$work"
step="textured_grid refuses values that do not increase"
check sh -c '! "$1" "$2/never.bsdf" "diffuse albedo={0}" albedo=0.5,0.2 && [ ! -e "$2/never.bsdf" ]' \
    sh "$grid_tool" "$work"
step="llplot --sphere's PNG has a title by default (the file name): it differs from one titled blank"
check sh -c '"$1" --sphere "$2/tg.bsdf" --param coat.alpha=0.2 --param base.albedo=0.5 \
        -o "$2/titled.png" --size 96 --spp 1 &&
    "$1" --sphere "$2/tg.bsdf" --param coat.alpha=0.2 --param base.albedo=0.5 --title "" \
        -o "$2/blank.png" --size 96 --spp 1 &&
    ! cmp -s "$2/titled.png" "$2/blank.png"' sh "$llplot" "$work"
step="llplot on a material file draws at the preview's 120 x 200, says so, and runs no resolution search (a g = -0.95 medium's, the costliest src/search/resolution.c still runs; < 20 s here)"
printf 'medium albedo=0.9 g=-0.95 tau=1\ndiffuse albedo=0.5\n' > "$work/hg.layers"
check sh -c 'start=$(date +%s); "$1" --sphere "$2/hg.layers" -o "$2/hg.png" --size 16 --spp 1 \
        2> "$2/hg.err" && grep -q "drawing at 120 nodes x 200 orders" "$2/hg.err" &&
    [ $(($(date +%s) - start)) -lt 20 ]' sh "$llplot" "$work"
step="llplot keeps a material's own set nodes= below the cap, and --orders"
printf 'set nodes=60\ndielectric eta=1.5 alpha=0.3\ndielectric eta=0.6666667 alpha=0.3\n' \
    > "$work/set60.layers"
check sh -c '"$1" --sphere "$2/set60.layers" --orders 50 -o "$2/set60.png" --size 16 --spp 1 \
        2> "$2/set60.err" && grep -q "drawing at 60 nodes x 50 orders" "$2/set60.err"' \
    sh "$llplot" "$work"
exit $failed
