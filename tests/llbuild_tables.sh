#!/bin/sh
# llbuild --format measured: the table file written instead of the .bsdf
# (byte for byte what llconvert makes of the .bsdf of the same build), the
# grid options, --dry-run's size of the tables, transmissive stacks (RGB
# tables of every lobe), the refusal of spectral transmissive and of swept
# stacks before any build, and that a failed or interrupted run
# leaves neither the output nor a temporary beside it.
# Run by `make test` from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
llconvert="$BUILD/bin/llconvert"
. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin llbuild_tables_test

# only_layers DESCRIPTION: the work folder holds nothing but the inputs
only_layers() {
    left=$(ls "$tmp/w" | grep -v '\.layers$')
    if [ -z "$left" ]; then ok; else bad "$1 left: $left"; fi
}

tool_test_need llbuild_tables.sh "$llbuild" "$llconvert"

mkdir -p "$tmp/w"
printf 'conductor eta=Au alpha=0.3\n' >"$tmp/w/gold.layers"
small="--nodes 40 --orders 20 --threads 1"
grid="--theta-i 4 --vndf 16 --sample 8"

# --- the table file: what llconvert writes from the .bsdf of the same build
expect 0 "--format measured" -- "$llbuild" --format measured $grid $small \
    "$tmp/w/gold.layers" -o "$tmp/w/gold.tab"
contains "$tmp/out" "(format measured)" "summary names the format"
contains "$tmp/out" "4 incident elevations x 16^2 visible-normal x 8^2 sample grid" "summary grid"
contains "$tmp/out" "file         $(wc -c <"$tmp/w/gold.tab" | tr -d ' ') bytes" \
    "summary size is the file's"
# one bar over the run: the tables after the build, not from 0% again
contains "$tmp/err" "% tables" "progress names the tables"
if grep -Eq '^llbuild: +([0-9]|[0-7][0-9]|8[0-4])% (ndf|tables)' "$tmp/err"; then
    bad "the tables' progress starts the bar again:"; grep -E '% (ndf|tables)' "$tmp/err" | head -3
else ok; fi
if [ "$(head -c 11 "$tmp/w/gold.tab")" = "tensor_file" ]; then ok; else
    bad "gold.tab does not start with tensor_file"; fi
expect 0 "--format bsdf" -- "$llbuild" -q --format bsdf $small "$tmp/w/gold.layers" \
    -o "$tmp/gold.bsdf"
expect 0 "the default format" -- "$llbuild" -q $small "$tmp/w/gold.layers" -o "$tmp/default.bsdf"
if cmp -s "$tmp/gold.bsdf" "$tmp/default.bsdf"; then ok; else
    bad "--format bsdf differs from the default"; fi
expect 0 "llconvert of the .bsdf" -- "$llconvert" --quiet $grid "$tmp/gold.bsdf" \
    -o "$tmp/conv.tab"
if cmp -s "$tmp/w/gold.tab" "$tmp/conv.tab"; then ok; else
    bad "llbuild --format measured differs from llconvert of the same build"; fi
# A swept material: a table set per basis, as llconvert makes them from
# the textured .bsdf of the same build.
printf 'conductor eta=Au alpha=[0.2 0.3]\n' >"$tmp/w/swept2.layers"
expect 0 "a swept stack" -- "$llbuild" --format measured $grid $small "$tmp/w/swept2.layers" \
    -o "$tmp/swept2.tab"
contains "$tmp/out" "textured: a set per basis, 2 bases of 1 parameters" "swept summary"
expect 0 "the swept .bsdf" -- "$llbuild" -q $small "$tmp/w/swept2.layers" -o "$tmp/swept2.bsdf"
expect 0 "llconvert of the swept .bsdf" -- "$llconvert" --quiet $grid "$tmp/swept2.bsdf" \
    -o "$tmp/swept2conv.tab"
if cmp -s "$tmp/swept2.tab" "$tmp/swept2conv.tab"; then ok; else
    bad "llbuild --format measured of a sweep differs from llconvert of the same build"; fi
rm -f "$tmp/w/gold.tab"
only_layers "a finished build"

# --- --dry-run: the table's size for the grid (32 x 128^2 x 64^2 floats
# and the small tables: 4 198 532 bytes, 4.00 MiB), no file
expect 0 "--dry-run" -- "$llbuild" --format measured --dry-run --theta-i 32 --vndf 128 \
    --sample 64 $small "$tmp/w/gold.layers"
contains "$tmp/out" "32 incident elevations x 128^2 visible-normal x 64^2 sample grid: about 4.00 MiB" \
    "--dry-run table size"
# sizes left to the tolerance: the range of the library's ladders
expect 0 "--dry-run by tolerance" -- "$llbuild" --format measured --dry-run \
    --table-tolerance 0.1 $small "$tmp/w/gold.layers"
contains "$tmp/out" "sized by the tolerance 0.1, known once measured: from 16 x 64^2 x 32^2" \
    "--dry-run by tolerance names the range"
expect 1 "a bad table tolerance" -- "$llbuild" --format measured --dry-run \
    --table-tolerance 3 $small "$tmp/w/gold.layers"
expect 0 "--dry-run, another grid" -- "$llbuild" --format measured --dry-run --vndf 64 \
    --sample 32 --theta-i 16 $small "$tmp/w/gold.layers"
contains "$tmp/out" "16 incident elevations x 64^2 visible-normal x 32^2 sample grid: about 0.50 MiB" \
    "--dry-run size follows the grid"
only_layers "--dry-run"

# --- refused before building, saying why
printf 'dielectric eta=1.5 alpha=0.1\n' >"$tmp/w/glass.layers"
expect 1 "a transmissive stack, spectral" -- "$llbuild" --format measured \
    --wavelengths 400:700:100 "$tmp/w/glass.layers" -o "$tmp/w/glass.tab"
contains "$tmp/err" "transmissive stack" "transmissive refusal names it"
contains "$tmp/err" "RGB tables only" "transmissive refusal says what is written"
if grep -q "%" "$tmp/err"; then bad "a transmissive stack was built before its refusal"; else ok; fi
printf 'conductor eta=Au alpha=[0.1 0.2]\n' >"$tmp/w/swept.layers"
expect 1 "a swept stack, spectral" -- "$llbuild" --format measured --wavelengths 400:700:100 \
    "$tmp/w/swept.layers" -o "$tmp/w/swept.tab"
contains "$tmp/err" "swept (textured) material" "swept spectral refusal names it"
expect 1 "a transmissive stack, spectral, --dry-run" -- "$llbuild" --format measured \
    --dry-run --wavelengths 400:700:100 "$tmp/w/glass.layers"
expect 1 "grid options without measured" -- "$llbuild" --vndf 16 "$tmp/w/gold.layers" \
    -o "$tmp/w/x.bsdf"
contains "$tmp/err" "size the tables of --format measured" "grid option message"
expect 1 "unknown format" -- "$llbuild" --format exr "$tmp/w/gold.layers" -o "$tmp/w/x"
expect 1 "a grid size out of range" -- "$llbuild" --format measured --sample 1 \
    "$tmp/w/gold.layers" -o "$tmp/w/x"
contains "$tmp/err" "--sample wants a whole number in 2..4096" "grid range message"
only_layers "refusals"

# --- a transmissive stack: RGB tables of every lobe, read back transmissive
expect 0 "--dry-run, a transmissive stack" -- "$llbuild" --format measured --dry-run \
    --vndf 64 --sample 32 --theta-i 16 $small "$tmp/w/glass.layers"
# (four sets of float16 grids: 1 065 284 bytes)
contains "$tmp/out" "16 incident elevations x 64^2 visible-normal x 32^2 sample grid: about 1.02 MiB" \
    "--dry-run size counts every lobe's set"
expect 0 "a transmissive stack" -- "$llbuild" --format measured $grid $small \
    "$tmp/w/glass.layers" -o "$tmp/w/glass.tab"
contains "$tmp/out" "(format measured)" "transmissive: summary names the format"
expect 0 "llconvert of a transmissive table" -- "$llconvert" --dry-run "$tmp/w/glass.tab"
rm -f "$tmp/w/glass.tab"

# --- --wavelengths: a spectral file (the material at each wavelength), no
# temporary left; the range checked before any work, saying what is wrong
expect 0 "--wavelengths" -- "$llbuild" --format measured --wavelengths 400:700:100 $grid \
    $small "$tmp/w/gold.layers" -o "$tmp/w/gold_s.tab"
contains "$tmp/out" "spectra      4 wavelengths, 400..700 nm" "summary of a spectral file"
contains "$tmp/out" "file         $(wc -c <"$tmp/w/gold_s.tab" | tr -d ' ') bytes" \
    "spectral summary size is the file's"
contains "$tmp/w/gold_s.tab" "wavelengths" "the file has wavelengths"
contains "$tmp/w/gold_s.tab" "spectra" "the file has spectra"
rm -f "$tmp/w/gold_s.tab"
only_layers "a spectral build"
expect 0 "--wavelengths --dry-run" -- "$llbuild" --format measured --dry-run \
    --theta-i 32 --vndf 128 --sample 64 --wavelengths 360:830:10 $small "$tmp/w/gold.layers"
contains "$tmp/out" "x 48 wavelengths (360..830 nm): about 26.50 MiB" "--dry-run spectral size"
for bad_range in 300:700:10 400:900:10 700:400:10 400:700:0 400:700:-5 400:700 \
    400:700:x 360:830:0.5; do
    expect 1 "--wavelengths $bad_range" -- "$llbuild" --format measured \
        --wavelengths "$bad_range" "$tmp/w/gold.layers" -o "$tmp/w/x.tab"
    contains "$tmp/err" "--wavelengths" "the message of $bad_range names the option"
    if grep -q "%" "$tmp/err"; then bad "$bad_range: built before the refusal"; else ok; fi
done
contains "$tmp/err" "at most 471" "the count limit is said"
printf 'conductor eta=0.2+3i,0.4+2.5i,1.2+1.8i alpha=0.2\n' >"$tmp/w/rgbk.layers"
expect 1 "--wavelengths of an index given as R,G,B" -- "$llbuild" --format measured \
    --wavelengths 400:700:100 $grid $small "$tmp/w/rgbk.layers" -o "$tmp/w/x.tab"
contains "$tmp/err" "eta is given as R,G,B" "an R,G,B index has no spectrum: said"
if grep -q "% building\|% adding\|% spectra" "$tmp/err"; then
    bad "an R,G,B index was built before its refusal"; else ok; fi
expect 1 "--wavelengths without measured" -- "$llbuild" --wavelengths 400:700:10 \
    "$tmp/w/gold.layers" -o "$tmp/w/x.bsdf"
contains "$tmp/err" "spectral table file of --format measured" "--wavelengths needs measured"
only_layers "--wavelengths refusals"

# --- an output that cannot be written: I/O, nothing left
expect 2 "no such folder" -- "$llbuild" --format measured $grid $small "$tmp/w/gold.layers" \
    -o "$tmp/w/missing/gold.tab"
only_layers "an unwritable output"

# --- interrupted while the tables are made: ends by the signal, leaves
# neither the table file nor the .bsdf it was being made from
mkdir -p "$tmp/run"
for sig in INT TERM; do
    stage_start "$tmp/run" "$llbuild" --format measured --vndf 1024 --sample 512 $small \
        "$tmp/w/gold.layers" -o "$tmp/w/big.tab"
    signal_in_stage $sig "*% tables (*" "the tables" "SIG$sig" || continue
    contains "$stage_log" "interrupted; no file written" "SIG$sig message"
    only_layers "SIG$sig"
done

# --- interrupted while the wavelengths are built: the same, no temporary
# .bsdf of a wavelength left beside the output
stage_start "$tmp/run" "$llbuild" --format measured --wavelengths 360:830:1 $grid $small \
    "$tmp/w/gold.layers" -o "$tmp/w/spectral.tab"
if signal_in_stage INT "*% spectra (*" "the spectra" "SIGINT in the spectra"; then
    contains "$stage_log" "interrupted; no file written" "SIGINT in the spectra: message"
    only_layers "SIGINT in the spectra"
fi

tool_test_end
