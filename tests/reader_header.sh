#!/bin/sh
# The reader header promises only what the reader library has: a program
# that includes <layerlab/ll_bsdf.h> alone and links liblayerlab_reader
# alone links for every function it can see. For the stable header and for
# the header with LL_EXPERIMENTAL defined:
#   - the LL_API functions the header makes visible (its own and those of
#     ll_common.h, which it includes) are read from the preprocessor's
#     output, so exactly what a program sees under those macros;
#   - a C program that takes the address of each one is compiled including
#     only <layerlab/ll_bsdf.h>, linked against $BUILD/lib/liblayerlab_reader.so
#     alone and run with every symbol bound at start (LD_BIND_NOW);
#   - a function the library does not export is named.
# First a check of the check: a copy of the headers that declares one more
# function must fail and name it.
# Run by `make test` with BUILD and CC set; prints one line per check and
# "N passed, N failed"; exits non-zero when a check fails.
set -u

BUILD=${BUILD:-build}
CC=${CC:-cc}
SRC=$(cd "$(dirname "$0")/.." && pwd)
case $BUILD in
    /*) BUILD_DIR=$BUILD ;;
    *) BUILD_DIR=$SRC/$BUILD ;;
esac
READER=$BUILD_DIR/lib/liblayerlab_reader.so

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
show() { sed -n "1,${2:-20}p" "$1" | sed 's/^/    /'; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-reader-header.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM

if [ ! -f "$READER" ]; then
    fail "no $READER (build the libraries first: make lib BUILD=$BUILD)"
    echo "$passed passed, $failed failed"
    exit 1
fi

# A sanitizer build of the library needs the sanitizer runtime in the program.
SAN_FLAGS=
if nm -D --undefined-only "$READER" 2>/dev/null | grep -q '__asan_'; then
    SAN_FLAGS="-fsanitize=address,undefined"
fi

# The LL_API functions that <layerlab/ll_bsdf.h> declares under the
# preprocessor flags $2, with the headers of include directory $1, one per
# line. LL_API is the visibility attribute with GCC and Clang: a declaration
# carrying it is an exported function; the first ll_ name followed by "("
# after the attribute is the function's.
declared() {
    printf '#include <layerlab/ll_bsdf.h>\n' |
        $CC -E -P $2 -I"$1" -x c - 2> "$tmp/cpp.log" |
        tr '\n' ' ' | tr ';' '\n' |
        grep 'visibility *( *"default" *)' |
        sed 's/__attribute__ *(( *visibility *( *"default" *) *))//' |
        sed -n 's/^[^(]*[^a-zA-Z0-9_]\(ll_[a-zA-Z0-9_]*\) *(.*/\1/p' | sort -u
}

# Build and run the program that references every function listed in file
# $3 (declared by the headers in $1 under flags $2) against the reader
# library alone. Prints the functions the link or the run did not find, one
# per line (nothing when all are there); the exit status is 0 only if the
# program built and ran.
link_all() {
    {
        printf '#include <layerlab/ll_bsdf.h>\n#include <stddef.h>\n\n'
        printf 'typedef void (*any_function)(void);\n'
        printf 'static any_function const functions[] = {\n'
        sed 's/.*/    (any_function)\&&,/' "$3"
        printf '};\n\nint main(void)\n{\n    size_t k, n = 0;\n'
        printf '    for (k = 0; k < sizeof functions / sizeof functions[0]; ++k)\n'
        printf '        n += functions[k] != NULL;\n'
        printf '    return n == sizeof functions / sizeof functions[0] ? 0 : 1;\n}\n'
    } > "$tmp/all.c"
    # shellcheck disable=SC2086
    if $CC -std=c99 -pedantic -Wall -Wextra $2 $SAN_FLAGS -I"$1" "$tmp/all.c" -o "$tmp/all" \
            "$READER" -Wl,-rpath,"$(dirname "$READER")" > "$tmp/link.log" 2>&1 &&
        LD_BIND_NOW=1 "$tmp/all" >> "$tmp/link.log" 2>&1; then
        return 0
    fi
    # The names the linker or the loader could not find, else every listed
    # function the library's dynamic symbol table lacks.
    grep -o "ll_[a-zA-Z0-9_]*" "$tmp/link.log" | sort -u > "$tmp/unresolved"
    nm -D --defined-only "$READER" | awk '{ n = $NF; sub(/@.*/, "", n); print n }' |
        sort -u > "$tmp/exported"
    comm -23 "$3" "$tmp/exported" > "$tmp/absent"
    sort -u "$tmp/unresolved" "$tmp/absent" | comm -12 - "$3"
    return 1
}

# One tier of the header: $1 its name, $2 the include directory, $3 flags.
# Prints "ok N" or the missing functions.
check_tier() {
    declared "$2" "$3" > "$tmp/declared"
    if [ ! -s "$tmp/declared" ]; then
        echo "none"
        show "$tmp/cpp.log" >&2
        return 1
    fi
    if link_all "$2" "$3" "$tmp/declared" > "$tmp/missing"; then
        echo "ok $(wc -l < "$tmp/declared")"
        return 0
    fi
    [ -s "$tmp/missing" ] || echo "(the program did not build or run)" > "$tmp/missing"
    tr '\n' ' ' < "$tmp/missing" | sed 's/ *$//'
    echo
    return 1
}

# ---------------------------------------------------- the check of the check
# A copy of the headers whose ll_bsdf.h declares one function more.
mkdir -p "$tmp/include/layerlab"
cp "$SRC"/include/layerlab/*.h "$tmp/include/layerlab/"
awk '/^#ifdef __cplusplus$/ { n++ }
     /^#ifdef __cplusplus$/ && n == 2 {
         print "LL_API ll_status ll_bsdf_reader_header_probe(const ll_bsdf *b);"; print "" }
     { print }' "$SRC/include/layerlab/ll_bsdf.h" > "$tmp/include/layerlab/ll_bsdf.h"
result=$(check_tier probe "$tmp/include" "" 2> "$tmp/probe.log")
case $result in
    *ll_bsdf_reader_header_probe*)
        pass "the check fails on a header that declares a function the reader lacks, and names it" ;;
    *)
        fail "the check does not catch a function declared but missing from the reader (got: $result)"
        show "$tmp/probe.log"
        show "$tmp/link.log" ;;
esac

# ------------------------------------------------------------- the header
for tier in stable experimental; do
    flags=
    [ "$tier" = experimental ] && flags=-DLL_EXPERIMENTAL
    result=$(check_tier "$tier" "$SRC/include" "$flags" 2> "$tmp/tier.log")
    case $result in
        "ok "*)
            pass "<layerlab/ll_bsdf.h> ($tier${flags:+, $flags}): all ${result#ok } LL_API functions it declares link against $BUILD/lib/liblayerlab_reader.so alone and bind at start" ;;
        none)
            fail "<layerlab/ll_bsdf.h> ($tier): no LL_API function found in the preprocessed header"
            show "$tmp/tier.log" ;;
        *)
            fail "<layerlab/ll_bsdf.h> ($tier${flags:+, $flags}) declares functions that liblayerlab_reader.so does not export: $result"
            show "$tmp/link.log" ;;
    esac
done

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
