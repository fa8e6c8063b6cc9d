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
trap 'exit 130' INT TERM
if [ -n "$san" ]; then
    # fontconfig (under cairo's text) keeps its configuration until exit;
    # leaks of our own code are still reported.
    printf 'leak:libfontconfig.so\n' > "$work/lsan.supp"
    LSAN_OPTIONS="suppressions=$work/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
    export LSAN_OPTIONS
fi
"$checker" "$llplot" "$work"
