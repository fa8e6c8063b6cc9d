#!/bin/sh
# The C example of README.md is a program that works: the first ```c block
# is extracted, compiled as C99 with warnings as errors against
# $BUILD/lib/liblayerlab, and run in a scratch directory. It must exit 0,
# print the value it evaluated, write its file, and free everything it
# made: when the compiler has AddressSanitizer, the program is built with it
# and LeakSanitizer fails the run on any leak. Run by `make test` with
# BUILD and CC set; prints PASS/FAIL lines and "N passed, N failed".
set -u
BUILD=${BUILD:-build}
CC=${CC:-cc}
root=$(cd "$(dirname "$0")/.." && pwd)
case "$BUILD" in
    /*) build="$BUILD" ;;
    *) build="$root/$BUILD" ;;
esac

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
finish() { echo "$passed passed, $failed failed"; [ "$failed" -eq 0 ]; exit $?; }

work=$(mktemp -d "${TMPDIR:-/tmp}/readme-example.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT
trap 'exit 1' HUP INT TERM

# The first fenced block opened with ```c, up to its closing fence.
awk '/^```c$/ { inside = 1; next } inside && /^```/ { exit } inside { print }' \
    "$root/README.md" >"$work/example.c"
if grep -q 'int main' "$work/example.c"; then
    pass "README.md has a C example with a main ($(wc -l <"$work/example.c") lines)"
else
    fail "README.md has no \`\`\`c block with a main"
    finish
fi

# A sanitizer build of the library needs the program built the same way;
# otherwise AddressSanitizer when the compiler can link it, for its leak check.
san=""
if nm -D "$build/lib/liblayerlab.so" 2>/dev/null | grep -q __asan_init; then
    san="-fsanitize=address,undefined -fno-omit-frame-pointer"
elif echo 'int main(void) { return 0; }' >"$work/probe.c" &&
     $CC -fsanitize=address -o "$work/probe" "$work/probe.c" 2>/dev/null &&
     "$work/probe" 2>/dev/null; then
    san="-fsanitize=address -fno-omit-frame-pointer"
fi

# shellcheck disable=SC2086
if $CC -std=c99 -Wall -Wextra -pedantic -Werror $san -I"$root/include" \
        -o "$work/example" "$work/example.c" \
        -L"$build/lib" -Wl,-rpath,"$build/lib" -llayerlab -lm >"$work/cc.log" 2>&1; then
    pass "the example compiles with -std=c99 -Wall -Wextra -pedantic -Werror${san:+ ($san)}"
else
    fail "the example does not compile:"
    sed 's/^/    /' "$work/cc.log"
    finish
fi

if (cd "$work" && ASAN_OPTIONS=detect_leaks=1 ./example >out.txt 2>err.txt); then
    pass "the example exits 0${san:+ with no leak}"
else
    fail "the example fails:"
    sed 's/^/    /' "$work/err.txt" | head -30
fi
if grep -qE '^f = [0-9.e+-]+ 1/sr' "$work/out.txt" && [ -s "$work/coated.bsdf" ]; then
    pass "it prints $(cat "$work/out.txt") and writes coated.bsdf"
else
    fail "it printed '$(cat "$work/out.txt")' and wrote $(ls "$work")"
fi
finish
