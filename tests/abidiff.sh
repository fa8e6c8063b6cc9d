#!/bin/sh
# The ABI held by a tool: abidiff (Debian's abigail-tools) compares each
# shared library just built with its committed baseline abi/<lib>.abi
# (written by `make abi-baseline`, see abi/README.md):
#   - a removed function or variable, or one whose symbol version changed
#     (abidiff's "incompatible change", exit bit 8), fails;
#   - any other change that abidiff reports (a type changed: a field added,
#     removed or retyped, a parameter changed) fails too, with the report:
#     review it, and only if it is compatible (a field appended to a
#     size-tagged struct) rewrite the baseline with `make abi-baseline`;
#   - added functions pass (they are listed);
#   - functions of the experimental version nodes (*EXPERIMENTAL*, declared
#     under LL_EXPERIMENTAL) are left out of the comparison
#     (abi/experimental.suppr): they may change in a minor release.
# Both sides are abidw's description of the public types (--headers-dir
# include/layerlab --drop-private-types: the structs behind the opaque
# handles ll_bsdf, ll_layer, ll_material are internal and left out), without
# paths and locations, so that a baseline written twice from the same
# sources is the same file.
# First the checks of the check: an edited copy of a baseline without one
# function must be reported as incompatible, unless the function is an
# experimental one.
# Run by `make test` with BUILD set; prints one line per check and
# "N passed, N failed"; exits non-zero when a check fails.
#   sh tests/abidiff.sh --write-baseline   (make abi-baseline) rewrites abi/*.abi
set -u

BUILD=${BUILD:-build}
SRC=$(cd "$(dirname "$0")/.." && pwd)
case $BUILD in
    /*) BUILD_DIR=$BUILD ;;
    *) BUILD_DIR=$SRC/$BUILD ;;
esac
ABI_VERSION=$(sed -n 's/^#define LL_ABI_VERSION \([0-9][0-9]*\).*/\1/p' \
    "$SRC/include/layerlab/ll_common.h")

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
show() { sed -n "1,${2:-40}p" "$1" | sed 's/^/    /'; }

LIBS="liblayerlab liblayerlab_reader"
SUPPRESS=$SRC/abi/experimental.suppr
# abidw of one library, run in the source tree (the DWARF names the headers
# relative to it).
describe() {
    (cd "$SRC" && abidw --no-corpus-path --no-comp-dir-path --no-show-locs --exported-interfaces-only \
        --headers-dir include/layerlab --drop-private-types --out-file "$2" "$1")
}

if [ "${1:-}" = --write-baseline ]; then
    mkdir -p "$SRC/abi" || exit 1
    for lib in $LIBS; do
        so=$BUILD_DIR/lib/$lib.so.$ABI_VERSION
        describe "$so" "$SRC/abi/$lib.abi" || exit 1
        echo "abidiff.sh: wrote abi/$lib.abi from $BUILD/lib/$lib.so.$ABI_VERSION"
    done
    exit 0
fi

tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-abidiff.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM

if ! command -v abidiff > /dev/null 2>&1; then
    fail "abidiff is not installed (abigail-tools; make deps installs it)"
    echo "$passed passed, $failed failed"
    exit 1
fi

# The summary lines ("Functions changes summary: ...") of a report.
summary() { grep 'changes summary' "$1" | sed 's/^ *//' | tr '\n' ' '; }

# Copy $1 to $3 without function $2: its ELF symbol and its (multi-line)
# declaration.
drop_function() {
    awk "/<elf-symbol name='$2'/ { next }
         /<function-decl name='$2'/ { skip = 1 }
         skip { if (/<\/function-decl>/ || /\/>\$/ && /<function-decl/) skip = 0; next }
         { print }" "$1" > "$3"
}

# ---------------------------------------------------- the check of the check
baseline=$SRC/abi/liblayerlab_reader.abi
if [ -f "$baseline" ]; then
    drop_function "$baseline" ll_bsdf_nodes "$tmp/edited.abi"
    abidiff --no-show-locs --suppressions "$SUPPRESS" "$baseline" "$tmp/edited.abi" \
        > "$tmp/self.log" 2>&1
    rc=$?
    if [ $((rc & 8)) -ne 0 ] && grep -q 'll_bsdf_nodes' "$tmp/self.log"; then
        pass "abidiff reports a removed function as incompatible (exit $rc on an edited baseline)"
    else
        fail "abidiff does not report a function removed from a baseline (exit $rc)"
        show "$tmp/self.log"
    fi
fi

# An experimental function of the reader just built, removed from its
# description: the suppression must leave it out.
reader_so=$BUILD_DIR/lib/liblayerlab_reader.so.$ABI_VERSION
if [ -e "$reader_so" ] && describe "$reader_so" "$tmp/fresh.abi" > /dev/null 2>&1; then
    experimental=$(sed -n "s/.*<elf-symbol name='\(ll_[a-z0-9_]*\)' version='[A-Z_]*EXPERIMENTAL[^']*'.*/\1/p" \
        "$tmp/fresh.abi" | head -n 1)
    if [ -z "$experimental" ]; then
        fail "liblayerlab_reader.so.$ABI_VERSION has no function in an *EXPERIMENTAL* version node to check the suppression with"
    else
        drop_function "$tmp/fresh.abi" "$experimental" "$tmp/fresh-edited.abi"
        abidiff --no-show-locs --suppressions "$SUPPRESS" "$tmp/fresh.abi" "$tmp/fresh-edited.abi" \
            > "$tmp/self-experimental.log" 2>&1
        rc=$?
        if [ "$rc" -eq 0 ]; then
            pass "abidiff ignores a removed experimental function ($experimental; abi/experimental.suppr)"
        else
            fail "abidiff reports a change to the experimental function $experimental (exit $rc)"
            show "$tmp/self-experimental.log"
        fi
    fi
fi

# ------------------------------------------------------- the libraries
for lib in $LIBS; do
    baseline=$SRC/abi/$lib.abi
    so=$BUILD_DIR/lib/$lib.so.$ABI_VERSION
    if [ ! -f "$baseline" ]; then
        fail "no baseline abi/$lib.abi (make abi-baseline writes it)"
        continue
    fi
    if [ ! -e "$so" ]; then
        fail "no $BUILD/lib/$lib.so.$ABI_VERSION (build the libraries first: make lib BUILD=$BUILD)"
        continue
    fi
    if ! describe "$so" "$tmp/$lib.abi" > "$tmp/$lib.abidw.log" 2>&1; then
        fail "abidw cannot read $BUILD/lib/$lib.so.$ABI_VERSION"
        show "$tmp/$lib.abidw.log"
        continue
    fi
    # Additions are allowed: left out of the verdict, counted below.
    abidiff --no-added-syms --no-show-locs --suppressions "$SUPPRESS" "$baseline" "$tmp/$lib.abi" \
        > "$tmp/$lib.log" 2>&1
    rc=$?
    if [ $((rc & 3)) -ne 0 ]; then
        fail "abidiff could not compare abi/$lib.abi with $BUILD/lib/$lib.so.$ABI_VERSION (exit $rc)"
        show "$tmp/$lib.log"
    elif [ $((rc & 8)) -ne 0 ]; then
        fail "$lib: incompatible ABI change against abi/$lib.abi (a function or variable removed or its symbol version changed): $(summary "$tmp/$lib.log")"
        show "$tmp/$lib.log"
    elif [ $((rc & 4)) -ne 0 ]; then
        fail "$lib: ABI change against abi/$lib.abi; if it is compatible (a field appended to a size-tagged struct), run make abi-baseline: $(summary "$tmp/$lib.log")"
        show "$tmp/$lib.log"
    else
        abidiff --no-show-locs --suppressions "$SUPPRESS" "$baseline" "$tmp/$lib.abi" \
            > "$tmp/$lib.added.log" 2>&1
        added=$(sed -n 's/^Functions changes summary:.* \([0-9][0-9]*\) Added.*/\1/p' \
            "$tmp/$lib.added.log")
        pass "$lib.so.$ABI_VERSION has the ABI of abi/$lib.abi (abidiff: no removal, no change; ${added:-0} function(s) added)"
    fi
done

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
