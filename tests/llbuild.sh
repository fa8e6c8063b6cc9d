#!/bin/sh
# llbuild, the command: help, version, exit codes (0 done, 1 bad input,
# 2 I/O, 3 numerical), --dry-run, the summary, and that an interrupted
# build (SIGINT / SIGTERM) leaves no output file.
# Run by `make test` from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin llbuild_test

tool_test_need llbuild.sh "$llbuild"

# --- help and version
expect 0 "--help" -- "$llbuild" --help
contains "$tmp/out" "conductor eta=NAME" "--help shows the language"
contains "$tmp/out" "exit codes" "--help lists the exit codes"
expect 0 "--version" -- "$llbuild" --version
contains "$tmp/out" "llbuild (layerlab) [0-9]" "--version"

# --- the docs' synopsis (docs/material-language.md) names every option
# --help prints
synopsis=$(sed -n '/^llbuild \[options\] MATERIAL.layers/,/^```/p' docs/material-language.md)
for opt in $("$llbuild" --help | sed -n 's/^  \(-[a-z], \)\{0,1\}\(--[a-z-]*\).*/\2/p'); do
    case "$synopsis" in *"$opt "*|*"$opt
"*) ok ;; *) bad "docs/material-language.md's llbuild synopsis lacks $opt" ;; esac
done
# and no doc has an empty code span (a name lost in an edit)
if grep -n ' `` ' docs/*.md README.md; then bad "an empty code span in the docs"; else ok; fi

# --- bad input: 1
expect 1 "no arguments" -- "$llbuild"
expect 1 "unknown option" -- "$llbuild" --frobnicate examples/plastic.layers -o "$tmp/x.bsdf"
expect 1 "no output" -- "$llbuild" examples/plastic.layers
expect 1 "odd nodes" -- "$llbuild" --nodes 15 examples/plastic.layers -o "$tmp/x.bsdf"
printf 'dielectric eta=1.5 alpha=0.1\nconductor eta=Au alpha=0.1\ndiffuse albedo=0.5\n' >"$tmp/bad.layers"
expect 1 "parse error" -- "$llbuild" "$tmp/bad.layers" -o "$tmp/x.bsdf"
contains "$tmp/err" "bad.layers:2:1: conductor is opaque" "parse error names file:line:column"
printf 'diffuse albedo=1.5\n' >"$tmp/bad2.layers"
expect 1 "value error" -- "$llbuild" "$tmp/bad2.layers" -o "$tmp/x.bsdf"
contains "$tmp/err" "bad2.layers:1:16: albedo=1.5 is out of range" "value error position"
printf 'conductor eta=Unobtainium alpha=0.1\n' >"$tmp/bad3.layers"
expect 1 "unknown metal" -- "$llbuild" "$tmp/bad3.layers" -o "$tmp/x.bsdf"
contains "$tmp/err" "unknown metal 'Unobtainium'" "unknown metal"
[ ! -e "$tmp/x.bsdf" ] && ok || bad "a failed build left $tmp/x.bsdf"

# --- --ior-dir: a metal of one's own
mkdir -p "$tmp/spectra"
printf '400 0.5\n700 0.5\n' >"$tmp/spectra/Fakium.eta.spd"
printf '400 3\n700 3\n' >"$tmp/spectra/Fakium.k.spd"
printf 'conductor eta=Fakium alpha=0.3\n' >"$tmp/fake.layers"
expect 1 "metal outside the search list" -- "$llbuild" --dry-run "$tmp/fake.layers"
expect 0 "--ior-dir" -- "$llbuild" --dry-run --ior-dir "$tmp/spectra" "$tmp/fake.layers"
contains "$tmp/out" "3 channels" "a named metal is RGB"
mkdir -p "$tmp/ior"
cp "$tmp/spectra/"Fakium.* "$tmp/ior/"
expect 0 "spectra in ior/ beside the material" -- "$llbuild" --dry-run "$tmp/fake.layers"
rm -rf "$tmp/ior"

# --- I/O: 2
expect 2 "missing material" -- "$llbuild" "$tmp/none.layers" -o "$tmp/x.bsdf"
expect 2 "unwritable output" -- "$llbuild" --nodes 10 --orders 2 examples/frosted-glass.layers \
    -o "$tmp/no/such/dir/x.bsdf"

# --- mistakes found before any work: each refusal comes before the first
# progress line (no "NN% " on stderr) and names the problem in the user's
# words; the run builds nothing, so it leaves no file.
# refused_early CODE DESCRIPTION TEXT -- command...
refused_early() {
    code=$1; what=$2; text=$3; shift 4
    expect "$code" "$what" -- "$@"
    contains "$tmp/err" "$text" "$what names the problem"
    if grep -q '% ' "$tmp/err"; then bad "$what: refused after work began:"; sed 's/^/  | /' "$tmp/err" | head -3; else ok; fi
}
mkdir -p "$tmp/outdir"
# the messages say the real rule: even and at least the minimum (with the
# nearest counts), which count is too large (no "0 orders"), did you mean
refused_early 1 "--nodes 101" "must be even, from 10 to 100000 (--nodes 100 or 102)" -- \
    "$llbuild" --nodes 101 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
refused_early 1 "--nodes 1000000" "--nodes 1000000: the node count must be even, from 10 to 100000" -- \
    "$llbuild" --nodes 1000000 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
if grep -q "0 orders" "$tmp/err"; then bad "--nodes 1000000 speaks of 0 orders"; else ok; fi
printf 'dielectirc eta=1.5 alpha=0.1\ndiffuse albedo=0.5\n' >"$tmp/typo.layers"
expect 1 "a mistyped word" -- "$llbuild" --dry-run "$tmp/typo.layers"
contains "$tmp/err" "typo.layers:1:1: unknown word 'dielectirc'; did you mean 'dielectric'?" \
    "a mistyped word gets a suggestion"
refused_early 2 "output directory missing" "the output directory '$tmp/nowhere/' does not exist" -- \
    "$llbuild" examples/coated-gold.layers -o "$tmp/nowhere/x.bsdf"
refused_early 2 "-o names a directory" "names a directory; name the file to write" -- \
    "$llbuild" examples/coated-gold.layers -o "$tmp/outdir"
refused_early 2 "-o ends in a slash" "names a directory" -- \
    "$llbuild" examples/coated-gold.layers -o "$tmp/outdir/"
printf 'x' >"$tmp/afile"
refused_early 2 "output directory is a file" "'$tmp/afile/' is not a directory" -- \
    "$llbuild" examples/coated-gold.layers -o "$tmp/afile/x.bsdf"
mkdir -p "$tmp/readonly"
chmod 555 "$tmp/readonly"
if [ -w "$tmp/readonly" ]; then
    : # root writes anywhere: nothing to refuse
else
    refused_early 2 "output directory not writable" "'$tmp/readonly/' is not writable" -- \
        "$llbuild" examples/coated-gold.layers -o "$tmp/readonly/x.bsdf"
fi
chmod 755 "$tmp/readonly"
refused_early 1 "--nodes 4" "--nodes 4: the node count must be even, from 10 to 100000" -- \
    "$llbuild" --nodes 4 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
refused_early 1 "--nodes 200000" "from 10 to 100000" -- \
    "$llbuild" --nodes 200000 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
refused_early 1 "--orders 0" "--orders 0: the order count must be from 1 to 100000" -- \
    "$llbuild" --orders 0 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
refused_early 1 "--orders 200000" "from 1 to 100000" -- \
    "$llbuild" --orders 200000 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
refused_early 1 "--nodes 20000 over the budget" "20000 nodes x 1 order (the fewest orders) needs about" -- \
    "$llbuild" --nodes 20000 examples/coated-gold.layers -o "$tmp/outdir/x.bsdf"
contains "$tmp/err" "more than the memory budget" "the early budget refusal names the budget"
[ -z "$(ls "$tmp/outdir")" ] && ok || bad "an early refusal left $(ls "$tmp/outdir")"

# --- out of memory: 3. A diffuse layer on 12000 nodes needs 576 MB for its
# order 0; with the address space capped at 400 MB the build fails cleanly.
# (Not under AddressSanitizer, which reserves terabytes of address space.)
printf 'diffuse albedo=0.5\n' >"$tmp/big.layers"
case "$BUILD" in
*san*) ;;
*)
    expect 3 "out of memory" -- sh -c "ulimit -v 400000; exec '$llbuild' --nodes 12000 \
        --orders 1 --quiet '$tmp/big.layers' -o '$tmp/big.bsdf'"
    contains "$tmp/err" "out of memory" "out-of-memory message"
    [ ! -e "$tmp/big.bsdf" ] && ok || bad "a failed build left big.bsdf"
    ;;
esac

# --- the memory budget: an absurd resolution is refused before anything is
# allocated (exit 1, no file); --max-memory sets the budget, in K/M/G/T or
# bytes, and a bad size is an error naming the option.
expect 1 "absurd resolution refused" -- "$llbuild" --nodes 100000 --orders 100000 \
    examples/plastic.layers -o "$tmp/absurd.bsdf"
contains "$tmp/err" "more than the memory budget" "refusal names the budget"
contains "$tmp/err" "max-memory" "refusal says how to raise the budget"
[ ! -e "$tmp/absurd.bsdf" ] && ok || bad "a refused build left a file"
expect 1 "--dry-run over the budget" -- "$llbuild" --dry-run --nodes 100000 --orders 100000 \
    examples/plastic.layers
contains "$tmp/err" "would be refused" "--dry-run says the build would be refused"
expect 1 "--max-memory 1M refuses plastic" -- "$llbuild" --max-memory 1M \
    examples/plastic.layers -o "$tmp/small.bsdf"
contains "$tmp/err" "budget of 1 MiB" "--max-memory 1M is the budget"
[ ! -e "$tmp/small.bsdf" ] && ok || bad "a refused build left small.bsdf"
expect 0 "--max-memory 1.5G" -- "$llbuild" --quiet --max-memory 1.5G --nodes 16 --orders 8 \
    examples/plastic.layers -o "$tmp/budget.bsdf"
expect 0 "--max-memory in bytes" -- "$llbuild" --dry-run --max-memory 500000000 \
    examples/plastic.layers
contains "$tmp/out" "budget 477 MiB" "--max-memory in bytes"
expect 1 "--max-memory 12Q" -- "$llbuild" --max-memory 12Q examples/plastic.layers -o "$tmp/x.bsdf"
contains "$tmp/err" "--max-memory" "a bad size names the option"
expect 1 "--max-memory -1G" -- "$llbuild" --max-memory -1G examples/plastic.layers -o "$tmp/x.bsdf"
expect 1 "--max-memory missing" -- "$llbuild" examples/plastic.layers -o "$tmp/x.bsdf" --max-memory
# --- an unreadable material: the reason (strerror)
expect 2 "missing material" -- "$llbuild" "$tmp/missing.layers" -o "$tmp/x.bsdf"
contains "$tmp/err" "No such file or directory" "the material's open error says why"

# --- dry run: resolution, memory, time; no file
expect 0 "--dry-run" -- "$llbuild" --dry-run examples/coated-gold.layers -o "$tmp/dry.bsdf"
contains "$tmp/out" "^resolution" "--dry-run resolution"
contains "$tmp/out" "^memory" "--dry-run memory"
contains "$tmp/out" "^time" "--dry-run time"
[ ! -e "$tmp/dry.bsdf" ] && ok || bad "--dry-run wrote a file"
expect 0 "--dry-run --mono" -- "$llbuild" --dry-run --mono --nodes 30 --orders 7 examples/coated-gold.layers
contains "$tmp/out" "30 nodes x 7 Fourier orders, 1 channel" "--dry-run honours options"

# --- the resolutions chosen are remembered (--cache-dir, --no-cache, the
# user's directory from LAYERLAB_CACHE_DIR); a dry run adds the choice's
# measured time to the model's; the progress counts the searches left
# seconds CMD...: the wall seconds CMD took (its output in $tmp/out, $tmp/err)
seconds() {
    s0=$(date +%s.%N); "$@" >"$tmp/out" 2>"$tmp/err"; s1=$(date +%s.%N)
    echo "$s0 $s1" | awk '{ printf "%.3f", $2 - $1 }'
}
# below VALUE LIMIT DESCRIPTION
below() {
    if awk -v a="$1" -v b="$2" 'BEGIN { exit !(a < b) }'; then ok; else
        bad "$3: $1 s, expected < $2 s"; fi
}
contains "$tmp/out" "+ choosing the resolution [0-9.]* s of CPU (measured now)" \
    "--dry-run adds the choice's time (coated gold, cold cache)"
t=$(seconds "$llbuild" --dry-run examples/coated-gold.layers)
below "$t" 0.5 "--dry-run of coated gold with its choice in the cache"
contains "$tmp/out" "choosing the resolution 0.0[0-9] s of CPU" "a remembered choice costs nothing"
t=$(seconds "$llbuild" --dry-run --no-cache --nodes 442 --orders 328 examples/coated-gold.layers)
below "$t" 0.5 "--dry-run with --nodes --orders"
printf 'conductor eta=0.2+3i alpha=0.5\n' >"$tmp/metal.layers"
expect 0 "--dry-run --cache-dir" -- "$llbuild" --dry-run --cache-dir "$tmp/c" "$tmp/metal.layers"
cp "$tmp/out" "$tmp/cold.txt"
contains "$tmp/out" "^resolution   112 nodes x 68" "the metal's resolution"
[ "$(ls "$tmp/c" | wc -l)" -eq 1 ] && ok || bad "--cache-dir: not one entry in $tmp/c"
entry=$(ls "$tmp/c"/*)
cp "$entry" "$tmp/entry.good"
printf 'layerlab resolution cache 1\ngarbage\n' >"$entry"
expect 0 "--dry-run over a damaged entry" -- "$llbuild" --dry-run --cache-dir "$tmp/c" "$tmp/metal.layers"
[ "$(grep '^resolution' "$tmp/out")" = "$(grep '^resolution' "$tmp/cold.txt")" ] && ok ||
    bad "a damaged entry changed the resolution"
cmp -s "$entry" "$tmp/entry.good" && ok || bad "a damaged entry was not rewritten"
LAYERLAB_CACHE_DIR="$tmp/never" "$llbuild" --dry-run --no-cache "$tmp/metal.layers" >"$tmp/out" 2>&1
[ ! -e "$tmp/never" ] && ok || bad "--no-cache wrote $tmp/never"
LAYERLAB_CACHE_DIR="$tmp/user" "$llbuild" --dry-run "$tmp/metal.layers" >"$tmp/out" 2>&1
[ "$(ls "$tmp/user" | wc -l)" -eq 1 ] && ok || bad "LAYERLAB_CACHE_DIR was not used"
expect 0 "a build that searches" -- "$llbuild" --no-cache "$tmp/metal.layers" -o "$tmp/metal.bsdf"
contains "$tmp/err" "% resolution 1/1 " "the progress shows the search's own count"

# --- a build: summary on stdout, plain progress lines on stderr (no TTY)
expect 0 "build" -- "$llbuild" --nodes 16 --orders 8 examples/plastic.layers -o "$tmp/plastic.bsdf"
[ -s "$tmp/plastic.bsdf" ] && ok || bad "no plastic.bsdf"
contains "$tmp/out" "^orders kept" "summary: orders kept"
contains "$tmp/out" "^file  *[0-9]* bytes" "summary: file size"
contains "$tmp/out" "^albedo" "summary: albedo"
contains "$tmp/out" "^albedo .*reflected$" "an opaque stack shows reflection only"
contains "$tmp/out" "^wall time" "summary: wall time"
contains "$tmp/err" "llbuild: .*% " "plain progress lines"
# A pane of frosted glass in air: the header's eta is 1 but the stack has
# no opaque word, so the summary shows what it transmits beside what it
# reflects (reflected + transmitted = 1 at normal incidence).
printf 'dielectric eta=1.5 alpha=0.3\ndielectric eta=0.6666667 alpha=0.3\n' >"$tmp/pane.layers"
expect 0 "a frosted pane" -- "$llbuild" --nodes 40 --orders 20 "$tmp/pane.layers" -o "$tmp/pane.bsdf"
contains "$tmp/out" "^header       eta 1," "the pane's header has eta 1"
contains "$tmp/out" "reflected | transmitted" "the pane's summary shows transmission"
contains "$tmp/out" "0 deg   0.07[0-9]*  | 0.9[0-9]*$" "the pane transmits what it does not reflect"
expect 0 "--quiet" -- "$llbuild" --quiet --nodes 16 --orders 8 examples/plastic.layers -o "$tmp/q.bsdf"
if [ -s "$tmp/out" ] || [ -s "$tmp/err" ]; then bad "--quiet printed something"; else ok; fi
expect 0 "--mono --threads 1" -- "$llbuild" --mono --threads 1 --nodes 16 --orders 8 \
    examples/coated-gold.layers -o "$tmp/mono.bsdf"
contains "$tmp/out" "16 nodes x 8 Fourier orders, 1 channel" "--mono"

# --- a file that reflects and transmits more light than it receives: a
# coat of alpha 0.02 on 80 nodes (its spline overshoots the peak at normal
# incidence) is built, and llbuild says so and how to resolve it; a
# textured file names the basis; a lossless glass with its energy
# compensation at the tolerance's resolution (R + T = 1 up to quadrature)
# is not warned about.
printf 'set nodes=80 orders=200\ndielectric eta=1.5 alpha=0.02\nconductor eta=Au alpha=0.2\n' \
    >"$tmp/sharp.layers"
expect 0 "an unresolved coat" -- "$llbuild" "$tmp/sharp.layers" -o "$tmp/sharp.bsdf"
contains "$tmp/err" "warning: .*sharp.bsdf reflects and transmits more light than it receives: R + T = 15.2 at 0 degrees from above. Its resolution does not resolve" \
    "the unresolved coat's warning"
contains "$tmp/err" "without a given resolution .* the tolerance chooses one that does" \
    "the warning says how to resolve it"
printf 'set nodes=80 orders=200\ndielectric name=coat eta=1.5 alpha=[0.02 0.2]\nconductor eta=Au alpha=0.2\n' \
    >"$tmp/sharpsweep.layers"
expect 0 "an unresolved basis" -- "$llbuild" "$tmp/sharpsweep.layers" -o "$tmp/sharpsweep.bsdf"
contains "$tmp/err" "R + T = 15.2 at 0 degrees from above at coat.alpha = 0.02 (1 of its 2 bases exceed 1)" \
    "the textured warning names the basis"
expect 0 "frosted glass" -- "$llbuild" examples/frosted-glass.layers -o "$tmp/frosted.bsdf"
if grep -q "warning" "$tmp/err"; then bad "a lossless glass warned: $(grep warning "$tmp/err")"; else ok; fi

# --- interrupted builds leave no file. A thick forward-scattering medium
# (about 0.5 s of doubling on 300 nodes, idle): signalled as soon as its
# progress names the medium (tests/lib/stage_wait.sh), not after a sleep.
printf 'medium albedo=0.99 g=0.9 tau=1e9\n' >"$tmp/slow.layers"
mkdir -p "$tmp/slow"
for sig in INT TERM; do
    rm -f "$tmp/slow.bsdf"
    stage_start "$tmp/slow" "$llbuild" --nodes 300 --orders 40 "$tmp/slow.layers" \
        -o "$tmp/slow.bsdf"
    signal_in_stage $sig "*% medium (*" "the medium" "SIG$sig" || continue
    if ls "$tmp" | grep -q '^slow\.bsdf'; then bad "SIG$sig left $(ls "$tmp" | grep slow.bsdf)"; else ok; fi
    contains "$stage_log" "interrupted; no file written" "SIG$sig message"
done

# --- a swept material: --dry-run names the axes, the bases and the file's
# size; the build writes one textured file and says so; a bad sweep is bad
# input with its position
printf 'set nodes=12 orders=6\ndielectric name=coat eta=1.5 alpha=[0.1 0.2 0.3]\nconductor eta=2+3i alpha=[0.1..0.3:2]\n' \
    >"$tmp/sweep.layers"
expect 0 "--dry-run of a sweep" -- "$llbuild" --dry-run "$tmp/sweep.layers"
contains "$tmp/out" "axis 0       coat.alpha: 3 values, 0.1 to 0.3" "--dry-run axis 0"
contains "$tmp/out" "axis 1       1.alpha: 2 values, 0.1 to 0.3" "--dry-run axis 1"
contains "$tmp/out" "bases        6 (one textured file)" "--dry-run bases"
contains "$tmp/out" "file         about" "--dry-run file size"
expect 0 "a textured build" -- "$llbuild" "$tmp/sweep.layers" -o "$tmp/sweep.bsdf"
contains "$tmp/out" "bases        6 (textured file, 2 parameters)" "textured summary"
contains "$tmp/err" "basis 6/6" "progress per basis"
printf 'conductor eta=Au alpha=[0.3 0.2]\n' >"$tmp/badsweep.layers"
expect 1 "a decreasing sweep" -- "$llbuild" "$tmp/badsweep.layers" -o "$tmp/x.bsdf"
contains "$tmp/err" "badsweep.layers:1:29: alpha: the values of a sweep must be strictly increasing" \
    "decreasing sweep message"

tool_test_end llbuild.sh
