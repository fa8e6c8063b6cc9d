#!/bin/sh
# llconvert, the command: help, version, exit codes (0 done, 1 bad input,
# 2 I/O), --dry-run, a conversion to the `measured` tables that reads back
# as such, transmissive sources (a set of tables per lobe), textured
# sources (a table set per basis), and the refusal, with the reason, of
# transmissive and textured table files (built here by llbuild on a tiny
# grid).
# Run by `make test` from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llconvert="$BUILD/bin/llconvert"
llbuild="$BUILD/bin/llbuild"
gold=tests/data/roughgold_alpha_0.2.bsdf
. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin llconvert_test

expect 0 "help" -- "$llconvert" --help
contains "$tmp/out" "usage: llconvert" "help text"
expect 0 "version" -- "$llconvert" --version
contains "$tmp/out" "llconvert (layerlab)" "version text"
expect 1 "no input" -- "$llconvert"
expect 1 "no output" -- "$llconvert" "$gold"
expect 1 "unknown format" -- "$llconvert" "$gold" -o "$tmp/x" --format pbrt
contains "$tmp/err" "unknown format" "unknown format message"
expect 1 "bad grid size" -- "$llconvert" "$gold" -o "$tmp/x" --sample 1
expect 2 "missing input" -- "$llconvert" "$tmp/none.bsdf" -o "$tmp/x"

expect 0 "dry run" -- "$llconvert" "$gold" --dry-run --theta-i 4 --vndf 16 --sample 8
contains "$tmp/out" "4 x 16^2 x 8^2 tables, about" "dry-run size"
[ ! -e "$tmp/x" ] && ok || bad "dry run wrote a file"

expect 0 "conversion" -- "$llconvert" "$gold" -o "$tmp/gold.tab" --theta-i 4 --vndf 16 --sample 8
contains "$tmp/out" "gold.tab: 4 x 16^2 x 8^2 tables" "conversion summary"
head -c 11 "$tmp/gold.tab" | grep -q tensor_file && ok || bad "no tensor_file magic"
# llplot draws a table file as it draws a .bsdf (it tells them by their first bytes).
if [ -x "$BUILD/bin/llplot" ]; then
    # fontconfig (under cairo's text) keeps its configuration until exit, as
    # tests/llplot.sh says; leaks of our own code are still reported.
    printf 'leak:libfontconfig.so\n' > "$tmp/lsan.supp"
    LSAN_OPTIONS="suppressions=$tmp/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
    export LSAN_OPTIONS
    expect 0 "llplot draws a table" -- "$BUILD/bin/llplot" --polar "$tmp/gold.tab" -o "$tmp/polar.png"
    [ -s "$tmp/polar.png" ] && ok || bad "llplot wrote no picture of the table"
fi
# A table converts again (it is an opaque untextured file too).
expect 0 "table to table" -- "$llconvert" "$tmp/gold.tab" -o "$tmp/again.tab" --quiet

if [ -x "$llbuild" ]; then
    printf 'set nodes=12 orders=6\ndielectric eta=1.5 alpha=0.3\n' >"$tmp/glass.layers"
    printf 'set nodes=12 orders=6\ndielectric name=coat eta=1.5 alpha=[0.1 0.2]\nconductor eta=2+3i alpha=0.2\n' \
        >"$tmp/textured.layers"
    # A medium alone: eta 1, but light goes through.
    printf 'set nodes=12 orders=6\nmedium albedo=0.9 tau=1 g=0.5\n' >"$tmp/medium.layers"
    if "$llbuild" --quiet "$tmp/medium.layers" -o "$tmp/medium.bsdf"; then
        # transmissive: every lobe's tables (the warp of the z-flipped
        # direction: eta 1), read back as a transmissive file
        expect 0 "transmitting source of eta 1" -- "$llconvert" "$tmp/medium.bsdf" \
            -o "$tmp/m.tab" --theta-i 4 --vndf 16 --sample 8
        expect 1 "a transmissive table converts from its .bsdf only" -- "$llconvert" \
            "$tmp/m.tab" -o "$tmp/m2.tab"
        contains "$tmp/err" "transmissive table file" "transmissive table refusal says why"
    else
        bad "llbuild could not build the medium"
    fi
    if "$llbuild" --quiet "$tmp/glass.layers" -o "$tmp/glass.bsdf" &&
       "$llbuild" --quiet "$tmp/textured.layers" -o "$tmp/textured.bsdf"; then
        expect 0 "transmissive source" -- "$llconvert" "$tmp/glass.bsdf" -o "$tmp/glass.tab" \
            --theta-i 4 --vndf 16 --sample 8
        expect 0 "llplot draws a transmissive table" -- "$BUILD/bin/llplot" --polar \
            "$tmp/glass.tab" -o "$tmp/glass-polar.png"
        rm -f "$tmp/glass.tab"
        # A textured source: a table set per basis.
        expect 0 "textured source" -- "$llconvert" "$tmp/textured.bsdf" -o "$tmp/tex.tab" \
            --theta-i 6 --vndf 16 --sample 12
        contains "$tmp/out" "textured tables, 2 bases of 1 parameters" "textured summary"
        # Made from its .bsdf, not converted again.
        expect 1 "textured table source" -- "$llconvert" "$tmp/tex.tab" -o "$tmp/tex2.tab"
        contains "$tmp/err" "textured table file" "textured table refusal says why"
        [ ! -e "$tmp/tex2.tab" ] && ok || bad "a refused file exists"
    else
        bad "llbuild could not build the refusal sources"
    fi
else
    bad "no $llbuild"
fi

tool_test_end
