#!/bin/sh
# The project stands alone: it owns every file it needs.
#   (a) nothing in the project refers to a folder beside or above the
#       checkout (the old shared folder with its ior, testdata and docs);
#   (b) every document the code cites by name exists in docs/, and every
#       section cited as `name.md, "Section"` is a heading there (alone or
#       followed by a parenthesis), every
#       numbered item cited as `style.md, items N-M` / `rule N` exists;
#   (c) the data files are there: both spectra of each metal in data/ior,
#       the golden file in tests/data with its 207,354 bytes;
#   (d) the build tree holds a copy of data/ior at $BUILD/share/layerlab/ior
#       (where the library looks: ../share/layerlab/ior from $BUILD/lib);
#   (e) an installed copy finds its spectra through the same rule, from
#       wherever the prefix is moved to, whatever the working directory, and
#       names the metal when they are missing.
# Run by `make test` with BUILD set; prints one line per check and
# "N passed, N failed"; exits non-zero when a check fails.
set -u

BUILD=${BUILD:-build}
SRC=$(cd "$(dirname "$0")/.." && pwd)
case $BUILD in
    /*) BUILD_DIR=$BUILD ;;
    *) BUILD_DIR=$SRC/$BUILD ;;
esac

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
show() { tail -n "${2:-15}" "$1" | sed 's/^/    /'; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-standalone.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
# Hermetic: the resolutions chosen are remembered in a scratch directory,
# never the user's cache.
LAYERLAB_CACHE_DIR="$tmp/cache"
export LAYERLAB_CACHE_DIR
trap 'exit 1' HUP INT TERM

cd "$SRC" || exit 1
# What the project is made of (this script excepted: it names the pattern).
project="Makefile README.md src include tools tests python scripts docs bench shims examples"

# --- (a) no folder outside the project
# The pattern is assembled so that this line does not match itself.
outside='\.\./'shared'|'shared'/(ior|testdata|docs)'
grep -rnE --exclude=standalone.sh --exclude-dir=__pycache__ "$outside" $project >"$tmp/refs" 2>/dev/null
if [ -s "$tmp/refs" ]; then
    fail "files refer to a shared/ folder outside the project:"
    show "$tmp/refs" 20
else
    pass "no file refers to a shared/ folder outside the project"
fi

# --- (b) cited documents and sections
# Comments wrap, so each file is read as one line with comment leaders removed.
flatten() { tr '\n' ' ' <"$1" | sed -e 's|[[:space:]]\*[[:space:]]| |g' -e 's|[[:space:]]#[[:space:]]| |g' -e 's|[[:space:]][[:space:]]*| |g'; }
: >"$tmp/cites"
: >"$tmp/sections"
: >"$tmp/items"
for f in $(find $project -type f \( -name '*.[ch]' -o -name '*.cpp' -o -name '*.py' -o -name '*.sh' \
        -o -name '*.md' -o -name Makefile \) ! -name standalone.sh | sort); do
    flatten "$f" >"$tmp/flat"
    grep -oE '(^|[^A-Za-z0-9_/.-])([A-Za-z0-9_.-]+/)*[a-z][a-z-]*\.md' "$tmp/flat" |
        sed 's|^[^A-Za-z0-9_./-]||' | sed "s|^|$f |" >>"$tmp/cites"
    grep -oE '[a-z][a-z-]*\.md, "[^"]+"' "$tmp/flat" | sed "s|^|$f |" >>"$tmp/sections"
    grep -oE 'style\.md,? (items?|rule) [0-9]+(-[0-9]+)?' "$tmp/flat" | sed "s|^|$f |" >>"$tmp/items"
done
missing=0
while read -r file doc; do
    case $doc in
        */*) [ -f "$doc" ] || [ -f "$(dirname "$file")/$doc" ] ;;
        *) [ -f "docs/$doc" ] || [ -f "$(dirname "$file")/$doc" ] ;;
    esac || { echo "    $file cites $doc, which does not exist"; missing=1; }
done <"$tmp/cites" >"$tmp/missing-docs"
if [ "$missing" -eq 0 ] && [ -s "$tmp/cites" ]; then
    pass "every document cited by name exists ($(cut -d' ' -f2 "$tmp/cites" | sort -u | wc -l) documents)"
else
    fail "cited documents are missing:"
    cat "$tmp/missing-docs"
fi
missing=0
while read -r file doc section; do
    doc=${doc%,}
    section=$(printf '%s' "$section" | sed 's/^"//; s/"$//')
    # A heading matches when it is the section's name, alone or followed by
    # a parenthesis ("Estimates" is "### Estimates (`--dry-run`)").
    found=0
    grep -E '^#+ ' "docs/$doc" 2>/dev/null | sed 's/^#* //' >"$tmp/headings"
    while IFS= read -r heading; do
        case $heading in "$section" | "$section ("*) found=1 ;; esac
    done <"$tmp/headings"
    if [ "$found" -eq 0 ]; then
        echo "    $file cites section \"$section\" of $doc, which has no such heading"
        missing=1
    fi
done <"$tmp/sections" >"$tmp/missing-sections"
if [ "$missing" -eq 0 ] && [ -s "$tmp/sections" ]; then
    pass "every cited section exists ($(wc -l <"$tmp/sections") citations)"
else
    fail "cited sections are missing:"
    cat "$tmp/missing-sections"
fi
missing=0
while read -r file doc word range; do
    first=${range%-*}
    last=${range#*-}
    k=$first
    while [ "$k" -le "$last" ]; do
        grep -qE "^$k\. " docs/style.md || { echo "    $file cites style.md item $k"; missing=1; }
        k=$((k + 1))
    done
done <"$tmp/items" >"$tmp/missing-items"
if [ "$missing" -eq 0 ]; then
    pass "every cited item of docs/style.md exists ($(wc -l <"$tmp/items") citations)"
else
    fail "cited items of docs/style.md are missing:"
    cat "$tmp/missing-items"
fi

# --- (c) the data files
metals=0
bad=
for eta in data/ior/*.eta.spd; do
    name=${eta%.eta.spd}
    metals=$((metals + 1))
    [ -s "$name.k.spd" ] || bad="$bad ${name#data/ior/}"
done
if [ "$metals" -ge 21 ] && [ -z "$bad" ] && [ -f data/ior/README.md ]; then
    pass "data/ior holds n and k of $metals metals and its README"
else
    fail "data/ior: $metals metals, without k:${bad:- none}, README: $([ -f data/ior/README.md ] && echo yes || echo no)"
fi
golden=tests/data/roughgold_alpha_0.2.bsdf
size=$(wc -c <"$golden" 2>/dev/null | tr -d ' ')
if [ "${size:-0}" = 207354 ] && [ "$(head -c 7 "$golden")" = SCATFUN ] && [ -f tests/data/README.md ]; then
    pass "tests/data holds the golden file (207354 bytes, SCATFUN) and its README"
else
    fail "tests/data: the golden file is ${size:-missing} bytes (207354 expected), or its README is missing"
fi

# --- (d) the build tree's copy
copy=$BUILD_DIR/share/layerlab/ior
differ=
for f in data/ior/*.spd; do
    cmp -s "$f" "$copy/$(basename "$f")" || differ="$differ $(basename "$f")"
done
if [ -z "$differ" ]; then
    pass "$BUILD/share/layerlab/ior is a copy of data/ior"
else
    fail "$BUILD/share/layerlab/ior differs from data/ior:$differ"
fi

# --- (e) an installed copy, moved elsewhere
if make -C "$SRC" --no-print-directory install PREFIX="$tmp/prefix" BUILD="$BUILD" \
        >"$tmp/install.log" 2>&1; then
    mv "$tmp/prefix" "$tmp/moved"
    printf 'conductor eta=Au alpha=0.2\n' >"$tmp/gold.layers"
    if (cd / && env -u LAYERLAB_IOR_DIR "$tmp/moved/bin/llbuild" --dry-run "$tmp/gold.layers") \
            >"$tmp/run.log" 2>&1; then
        pass "an installed llbuild, its prefix moved, finds Au in PREFIX/share/layerlab/ior"
    else
        fail "an installed llbuild, its prefix moved, does not find Au:"
        show "$tmp/run.log"
    fi
    rm -rf "$tmp/moved/share/layerlab/ior"
    if (cd / && env -u LAYERLAB_IOR_DIR "$tmp/moved/bin/llbuild" --dry-run "$tmp/gold.layers") \
            >"$tmp/run.log" 2>&1; then
        fail "with PREFIX/share/layerlab/ior removed, Au was still found somewhere:"
        show "$tmp/run.log"
    elif grep -q "unknown metal 'Au'" "$tmp/run.log"; then
        pass "without PREFIX/share/layerlab/ior, Au is an unknown metal (no other place is searched)"
    else
        fail "without PREFIX/share/layerlab/ior, llbuild fails for another reason:"
        show "$tmp/run.log"
    fi
else
    fail "make install PREFIX=<tmp> BUILD=$BUILD failed"
    show "$tmp/install.log"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
