#!/bin/sh
# ABI and header checks (see docs/style.md, items 1-4):
#   (a) every public header compiles alone as pedantic C99 and as C++11,
#       with and without LL_EXPERIMENTAL (the tier that may change in a
#       minor release), includes only <stddef.h>/<stdint.h> and other
#       layerlab headers;
#       a C++ program links against the library (extern "C" guards work);
#   (b) the shared library exports ll_* symbols only;
#   (c) its soname is liblayerlab.so.<LL_ABI_VERSION>;
#   (d) `make install PREFIX=<tmp>` works and a program built with
#       `$(pkg-config --cflags --libs layerlab)` runs against the installed copy;
#   (e) the reader library liblayerlab_reader.so.<LL_ABI_VERSION>: its soname,
#       NEEDED without OpenBLAS, LAPACKE or OpenMP, exports ll_* only and no
#       ll_layer_*, every function of ll_bsdf.h; ll_bsdf.h includes only
#       ll_common.h; a program that includes only <layerlab/ll_bsdf.h> builds
#       with `$(pkg-config --cflags --libs layerlab-reader)` after the install
#       and runs against the installed reader alone.
# Run by `make test` with BUILD, CC and CXX set; prints one line per check and
# "N passed, N failed"; exits non-zero when a check fails.
set -u

BUILD=${BUILD:-build}
CC=${CC:-cc}
CXX=${CXX:-c++}
SRC=$(cd "$(dirname "$0")/.." && pwd)
case $BUILD in
    /*) BUILD_DIR=$BUILD ;;
    *) BUILD_DIR=$SRC/$BUILD ;;
esac
LIB=$BUILD_DIR/lib/liblayerlab.so
READER=$BUILD_DIR/lib/liblayerlab_reader.so
HEADER_COMMON=$SRC/include/layerlab/ll_common.h

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
# Indent a file's last lines under a failure.
show() { tail -n "${2:-15}" "$1" | sed 's/^/    /'; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-abi.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM

# A sanitizer build of the library needs the sanitizer runtime in every
# program that loads it.
SAN_FLAGS=
if [ -f "$LIB" ] && nm -D --undefined-only "$LIB" 2>/dev/null | grep -q '__asan_'; then
    SAN_FLAGS="-fsanitize=address,undefined"
fi
# So does a coverage build's static library (make coverage) need gcov's.
if nm "$BUILD_DIR/lib/liblayerlab_reader.a" 2>/dev/null | grep -q ' U __gcov_'; then
    SAN_FLAGS="--coverage"
fi

# ----------------------------------------------------------- (a) headers
for header in "$SRC"/include/layerlab.h "$SRC"/include/layerlab/ll_*.h; do
    name=${header#"$SRC"/include/}
    printf '#include <%s>\n' "$name" > "$tmp/alone.c"
    cp "$tmp/alone.c" "$tmp/alone.cpp"
    for tier in "" -DLL_EXPERIMENTAL; do
        if $CC -std=c99 -pedantic -Wall -Wextra -Werror -Wstrict-prototypes $tier \
            -I"$SRC/include" -c "$tmp/alone.c" -o "$tmp/alone.o" > "$tmp/cc.log" 2>&1; then
            pass "$name compiles alone as C99 ($CC -std=c99 -pedantic -Wall -Wextra -Werror $tier)"
        else
            fail "$name does not compile alone as C99 $tier"
            show "$tmp/cc.log"
        fi
        if $CXX -std=c++11 -pedantic -Wall -Wextra -Werror $tier \
            -I"$SRC/include" -c "$tmp/alone.cpp" -o "$tmp/alone.o" > "$tmp/cxx.log" 2>&1; then
            pass "$name compiles alone as C++11 ($CXX -std=c++11 -pedantic -Wall -Wextra -Werror $tier)"
        else
            fail "$name does not compile alone as C++11 $tier"
            show "$tmp/cxx.log"
        fi
    done
    others=$(grep '^[[:space:]]*#[[:space:]]*include' "$header" |
        grep -v -e '<stddef\.h>' -e '<stdint\.h>' -e '"ll_[a-z_]*\.h"' -e '"layerlab/ll_[a-z_]*\.h"')
    if [ -z "$others" ]; then
        pass "$name includes only <stddef.h>, <stdint.h> and layerlab headers"
    else
        fail "$name includes more than <stddef.h>, <stdint.h> and layerlab headers: $others"
    fi
done

cat > "$tmp/linkage.cpp" <<'EOF'
#include <layerlab.h>
int main() { return ll_version_number() == LL_VERSION_NUMBER ? 0 : 1; }
EOF
if [ ! -f "$LIB" ]; then
    fail "no $LIB (build the library first: make BUILD=$BUILD)"
elif $CXX -std=c++11 $SAN_FLAGS -I"$SRC/include" "$tmp/linkage.cpp" -o "$tmp/linkage" \
        -L"$BUILD_DIR/lib" -Wl,-rpath,"$BUILD_DIR/lib" -llayerlab > "$tmp/link.log" 2>&1 &&
    "$tmp/linkage" >> "$tmp/link.log" 2>&1; then
    pass "a C++ program links against $BUILD/lib/liblayerlab.so and runs (C linkage)"
else
    fail "a C++ program does not link against or run with $BUILD/lib/liblayerlab.so"
    show "$tmp/link.log"
fi

# ------------------------------------------------------ (b) exported symbols
if [ -f "$LIB" ]; then
    # Symbol versions (name@@LAYERLAB_1.0) are stripped; the version nodes
    # themselves are listed as absolute symbols LAYERLAB_[<TIER>_]<n>[.<m>]
    # (LAYERLAB_1.0, LAYERLAB_EXPERIMENTAL_1.0), which are not exports.
    if nm -D --defined-only "$LIB" > "$tmp/nm.txt" 2> "$tmp/nm.log"; then
        stray=$(awk '{ name = $NF; sub(/@.*/, "", name);
                       if ($(NF-1) == "A" && name ~ /^LAYERLAB_([A-Z]+_)*[0-9]+(\.[0-9]+)?$/) next;
                       if (name !~ /^ll_/) print name }' "$tmp/nm.txt" | sort -u)
        count=$(awk '{ name = $NF; sub(/@.*/, "", name); if (name ~ /^ll_/) n++ }
                     END { print n + 0 }' "$tmp/nm.txt")
        if [ -n "$stray" ]; then
            fail "liblayerlab.so exports symbols other than ll_*: $(echo $stray)"
        elif [ "$count" -eq 0 ]; then
            fail "liblayerlab.so exports no ll_* symbol at all"
        else
            pass "liblayerlab.so exports only ll_* symbols ($count of them)"
        fi
    else
        fail "nm -D --defined-only $LIB failed"
        show "$tmp/nm.log"
    fi
    # Every function the headers declare with LL_API is exported (a source
    # file that forgets to include its header defines it hidden).
    declared=$(grep -h '^LL_API ' include/layerlab/*.h |
               sed -n 's/^[^(]*[ *]\(ll_[a-z0-9_]*\)(.*/\1/p' | sort -u)
    missing=""
    for f in $declared; do
        awk -v f="$f" '{ name = $NF; sub(/@.*/, "", name); if (name == f) found = 1 }
                       END { exit !found }' "$tmp/nm.txt" || missing="$missing $f"
    done
    if [ -n "$missing" ]; then
        fail "declared in the headers but not exported:$missing"
    else
        pass "every LL_API function of the headers is exported ($(echo $declared | wc -w))"
    fi
fi

# ----------------------------------------------------------------- (c) soname
abi=$(sed -n 's/^#define LL_ABI_VERSION \([0-9][0-9]*\).*/\1/p' "$HEADER_COMMON")
if [ -f "$LIB" ]; then
    soname=$(readelf -d "$LIB" 2>/dev/null | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
    if [ -z "$abi" ]; then
        fail "no LL_ABI_VERSION in include/layerlab/ll_common.h"
    elif [ "$soname" = "liblayerlab.so.$abi" ] && [ -e "$BUILD_DIR/lib/$soname" ]; then
        pass "soname is liblayerlab.so.$abi (LL_ABI_VERSION $abi) and $BUILD/lib/$soname exists"
    else
        fail "soname is '$soname', expected liblayerlab.so.$abi (LL_ABI_VERSION $abi) with a link in $BUILD/lib"
    fi
fi

# ------------------------------------------------ (d) install and pkg-config
prefix=$tmp/prefix
if ${MAKE:-make} -C "$SRC" install PREFIX="$prefix" BUILD="$BUILD" CC="$CC" CXX="$CXX" \
        > "$tmp/install.log" 2>&1; then
    pass "make install PREFIX=<tmp> BUILD=$BUILD"
    cat > "$tmp/x.c" <<'EOF'
#include <stdio.h>
#include <string.h>
#include <layerlab.h>
int main(void)
{
    if (ll_version_number() != LL_VERSION_NUMBER ||
        strcmp(ll_version_string(), LL_VERSION_STRING) != 0)
        return 1;
    printf("layerlab %s\n", ll_version_string());
    return 0;
}
EOF
    flags=$(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs layerlab 2> "$tmp/pc.log")
    if [ $? -ne 0 ]; then
        fail "pkg-config does not find layerlab.pc in the install prefix"
        show "$tmp/pc.log"
    else
        case $flags in
            *"$prefix/include"*"$prefix/lib"* | *"$prefix/lib"*"$prefix/include"*)
                pass "the installed layerlab.pc points into the install prefix" ;;
            *)
                fail "the installed layerlab.pc does not point into the install prefix (pkg-config gives: $flags; it was generated for another PREFIX)" ;;
        esac
        # shellcheck disable=SC2086
        if $CC $SAN_FLAGS "$tmp/x.c" -o "$tmp/x" $flags > "$tmp/x.log" 2>&1 &&
            "$tmp/x" > "$tmp/x.out" 2>> "$tmp/x.log"; then
            if LD_TRACE_LOADED_OBJECTS=1 "$tmp/x" 2>/dev/null |
                grep -q "liblayerlab\.so\.$abi => $prefix/lib/"; then
                pass "cc x.c \$(pkg-config --cflags --libs layerlab) builds and runs against the installed copy ($(cat "$tmp/x.out"))"
            else
                fail "the program built with pkg-config does not load the installed liblayerlab.so.$abi"
            fi
        else
            fail "cc x.c \$(pkg-config --cflags --libs layerlab) does not build or run"
            show "$tmp/x.log"
        fi
    fi
else
    fail "make install PREFIX=<tmp> BUILD=$BUILD failed"
    show "$tmp/install.log"
fi

# ------------------------------------------------------ (e) the reader library
if grep '^[[:space:]]*#[[:space:]]*include' "$SRC/include/layerlab/ll_bsdf.h" |
        grep -v '"ll_common\.h"' > "$tmp/bsdf_includes.txt"; then
    fail "layerlab/ll_bsdf.h includes more than ll_common.h: $(cat "$tmp/bsdf_includes.txt")"
else
    pass "layerlab/ll_bsdf.h includes only ll_common.h"
fi
if [ ! -f "$READER" ]; then
    fail "no $READER (build the libraries first: make lib BUILD=$BUILD)"
else
    soname=$(readelf -d "$READER" 2>/dev/null | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
    if [ "$soname" = "liblayerlab_reader.so.$abi" ] && [ -e "$BUILD_DIR/lib/$soname" ]; then
        pass "the reader's soname is liblayerlab_reader.so.$abi and $BUILD/lib/$soname exists"
    else
        fail "the reader's soname is '$soname', expected liblayerlab_reader.so.$abi with a link in $BUILD/lib"
    fi
    needed=$(readelf -d "$READER" 2>/dev/null | sed -n 's/.*(NEEDED).*\[\(.*\)\].*/\1/p' | tr '\n' ' ')
    if [ -z "$needed" ]; then
        fail "readelf -d shows no NEEDED entry for the reader (not a shared library?)"
    elif echo "$needed" | grep -q -i -e blas -e lapack -e gomp -e libomp -e libiomp; then
        fail "the reader library needs OpenBLAS, LAPACKE or OpenMP: NEEDED $needed"
    else
        pass "the reader library needs no OpenBLAS, LAPACKE or OpenMP (NEEDED: $needed)"
    fi
    nm -D --defined-only "$READER" > "$tmp/reader_nm.txt" 2> "$tmp/reader_nm.log"
    exported=$(awk '{ name = $NF; sub(/@.*/, "", name);
                      if ($(NF-1) == "A" && name ~ /^LAYERLAB_/) next; print name }' \
               "$tmp/reader_nm.txt" | sort -u)
    stray=$(echo "$exported" | grep -v '^ll_' || true)
    layer=$(echo "$exported" | grep '^ll_layer_' || true)
    if [ -z "$exported" ]; then
        fail "nm -D shows no export of the reader library"
        show "$tmp/reader_nm.log"
    elif [ -n "$stray" ] || [ -n "$layer" ]; then
        fail "the reader library exports more than the reader's ll_* functions: $(echo $stray $layer)"
    else
        pass "the reader library exports only ll_* and no ll_layer_* ($(echo "$exported" | wc -l) functions)"
    fi
    # What a renderer needs: every function of ll_bsdf.h, and versions,
    # status strings and the error message of ll_common.h.
    wanted="$(grep -h '^LL_API ' "$SRC/include/layerlab/ll_bsdf.h" |
              sed -n 's/^[^(]*[ *]\(ll_[a-z0-9_]*\)(.*/\1/p') ll_version_number
              ll_version_string ll_status_string ll_last_error_message"
    missing=""
    for f in $wanted; do
        echo "$exported" | grep -qx "$f" || missing="$missing $f"
    done
    if [ -n "$missing" ]; then
        fail "the reader library does not export:$missing"
    else
        pass "the reader library exports every function of ll_bsdf.h and the versions, status strings and error message ($(echo $wanted | wc -w))"
    fi
fi
if [ -f "$prefix/lib/pkgconfig/layerlab-reader.pc" ]; then
    cat > "$tmp/reader.c" <<'EOF'
#include <stdio.h>
#include <string.h>
#include <layerlab/ll_bsdf.h>
/* A renderer's view: open (here a damaged file, from memory), report. */
int main(void)
{
    static const char junk[] = "not a .bsdf file";
    ll_bsdf *b = NULL;
    ll_status s = ll_bsdf_open_memory(junk, sizeof junk, NULL, &b);
    if (s != LL_ERROR_FORMAT || b != NULL || strlen(ll_last_error_message()) == 0 ||
        ll_version_number() != LL_VERSION_NUMBER)
        return 1;
    ll_bsdf_release(b);
    printf("%s: %s\n", ll_status_string(s), ll_last_error_message());
    return 0;
}
EOF
    rflags=$(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs layerlab-reader 2> "$tmp/rpc.log")
    # shellcheck disable=SC2181,SC2086
    if [ $? -ne 0 ]; then
        fail "pkg-config does not find layerlab-reader.pc in the install prefix"
        show "$tmp/rpc.log"
    elif $CC -std=c99 -pedantic -Wall -Wextra $SAN_FLAGS "$tmp/reader.c" -o "$tmp/reader" $rflags \
            > "$tmp/reader.log" 2>&1 && "$tmp/reader" > "$tmp/reader.out" 2>> "$tmp/reader.log"; then
        loaded=$(LD_TRACE_LOADED_OBJECTS=1 "$tmp/reader" 2>/dev/null)
        if ! echo "$loaded" | grep -q "liblayerlab_reader\.so\.$abi => $prefix/lib/"; then
            fail "the reader program does not load the installed liblayerlab_reader.so.$abi"
        elif echo "$loaded" | grep -q -e 'liblayerlab\.so' -e openblas -e lapacke -e gomp; then
            fail "the reader program loads liblayerlab, OpenBLAS, LAPACKE or OpenMP: $(echo $loaded)"
        else
            pass "a program including only <layerlab/ll_bsdf.h> builds with \$(pkg-config --cflags --libs layerlab-reader) and runs on the installed reader alone ($(cat "$tmp/reader.out"))"
        fi
    else
        fail "cc reader.c \$(pkg-config --cflags --libs layerlab-reader) does not build or run"
        show "$tmp/reader.log"
    fi
    # The static archive needs nothing but libm either.
    # shellcheck disable=SC2086
    if $CC -std=c99 $SAN_FLAGS -I"$prefix/include" "$tmp/reader.c" -o "$tmp/reader_static" \
            "$prefix/lib/liblayerlab_reader.a" -lm > "$tmp/static.log" 2>&1 &&
        "$tmp/reader_static" > /dev/null 2>> "$tmp/static.log"; then
        pass "the same program links with the installed liblayerlab_reader.a and -lm alone, and runs"
    else
        fail "the program does not link with liblayerlab_reader.a -lm alone (or does not run)"
        show "$tmp/static.log"
    fi
else
    fail "make install did not install layerlab-reader.pc"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
