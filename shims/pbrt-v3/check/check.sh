#!/bin/sh
# `make pbrt-check`: two pbrt-v3 programs that the user already has, one
# built with the shim (PBRT) and one without (PBRT_STOCK), on the scene of
# shims/pbrt-v3/README.md. It builds no renderer: it only runs them.
#
#  1. checks that the shimmed pbrt links liblayerlab and the stock one
#     does not;
#  2. renders the scene with both on the golden file and on coated gold as
#     `llbuild` makes it from examples/coated-gold.layers, and prints their
#     image difference;
#  3. renders it with both on eight damaged copies of the golden file
#     (damage.py) and prints what each program does with each;
#  4. renders a textured coated gold with the shim: constant and
#     image-textured coat roughness (section 4 says what it checks).
#
# It passes when both programs render the intact files, their images of
# each intact file agree to RMSE/mean < PBRT_TOLERANCE, and the shim meets
# every damaged file with exactly one error and a black sphere (an image
# bit-identical to the scene with a black sphere). What stock pbrt-v3 does
# is reported, not judged.
#
# usage: sh check.sh PBRT PBRT_STOCK WORK GOLDEN.bsdf LAYERLAB_PREFIX
# environment: PBRT_THREADS (pbrt --nthreads, 2), PBRT_TIMEOUT (seconds per
#   render, 900), PBRT_TOLERANCE (2e-3)
set -u
here=$(cd "$(dirname "$0")" && pwd)
shim_dir=$(dirname "$here")
top=$(dirname "$(dirname "$shim_dir")")
threads=${PBRT_THREADS:-2}
limit=${PBRT_TIMEOUT:-900}
tolerance=${PBRT_TOLERANCE:-2e-3}

fail() { echo "pbrt-check: $*" >&2; exit 1; }
[ $# -eq 5 ] || fail "usage: sh check.sh PBRT PBRT_STOCK WORK GOLDEN.bsdf LAYERLAB_PREFIX"
[ -n "$1" ] && [ -x "$1" ] || fail "give PBRT=/path/to/pbrt, a pbrt-v3 built with the shim"
[ -n "$2" ] && [ -x "$2" ] || fail "give PBRT_STOCK=/path/to/pbrt, an unmodified pbrt-v3"
[ -f "$4" ] || fail "golden file $4 not found (PBRT_GOLDEN=...)"
pbrt_shim=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
pbrt_stock=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
mkdir -p "$3" || exit 1
work=$(cd "$3" && pwd)
golden=$(cd "$(dirname "$4")" && pwd)/$(basename "$4")
prefix=$5
[ -f "$prefix/lib/pkgconfig/layerlab.pc" ] && [ -x "$prefix/bin/llbuild" ] ||
    fail "no installed layerlab in $prefix (make pbrt-check installs it there)"
for tool in python3 timeout; do
    command -v $tool > /dev/null || fail "$tool is needed"
done
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
# cpu_mark sets $cpu to the CPU seconds (user + system) of this shell's
# finished children: the second line of the `times` builtin, "XmY.Zs XmY.Zs",
# run in this shell (not in a $(...) subshell, which has children of its own).
# Render times are compared in CPU seconds because the wall time of a shared
# machine varies with its load.
cpu_mark() {
    times > "$work/times.txt"
    cpu=$(awk 'NR == 2 {
        t = 0
        for (k = 1; k <= 2; k++) { split($k, p, "m"); t += 60 * p[1] + p[2] }
        printf "%.2f", t
    }' "$work/times.txt")
}
# The program of each variant (stock, shim).
pbrt_of() { if [ "$1" = shim ]; then echo "$pbrt_shim"; else echo "$pbrt_stock"; fi; }

# ---------------------------------------------------------------- 1. programs
linked=$(ldd "$pbrt_shim" 2>/dev/null | grep -o 'liblayerlab[a-z_]*\.so[.0-9]*' | head -n 1)
[ -n "$linked" ] || fail "$pbrt_shim links no liblayerlab: not a pbrt-v3 built with the shim"
if ldd "$pbrt_stock" | grep -q liblayerlab; then
    fail "$pbrt_stock links liblayerlab: not an unmodified pbrt-v3"
fi
echo "pbrt-check: shim $pbrt_shim (links $linked), stock $pbrt_stock"

# ---------------------------------------------------------------- 2. scenes
scenes=$work/scenes
out=$work/out
rm -rf "$scenes" "$out"
mkdir -p "$scenes" "$out" || exit 1
cp "$golden" "$scenes/golden.bsdf"
"$prefix/bin/llbuild" "$top/examples/coated-gold.layers" -o "$scenes/coated-gold.bsdf" \
    > "$work/llbuild.log" 2>&1 || { cat "$work/llbuild.log" >&2; fail "llbuild of coated gold failed"; }
coated=$(python3 -c '
import struct, sys
h = struct.unpack_from("<7sB9I", open(sys.argv[1], "rb").read(48))
print("file header: %d nodes, nMaxOrder %d, %d coefficients" % (h[3], h[5], h[4]))
' "$scenes/coated-gold.bsdf")
echo "pbrt-check: coated gold from llbuild: $(sed -n 's/^resolution *//p' "$work/llbuild.log"); $coated"
python3 "$here/damage.py" "$golden" "$scenes" > "$work/cases.txt" || fail "damage.py failed"

# The scene of README.md ("Try it"), with the sphere's material as $2.
scene() {
    cat > "$scenes/$1.pbrt" <<EOF
LookAt 0 -6 2.2   0 0 0.8   0 0 1
Camera "perspective" "float fov" [ 28 ]
Film "image" "integer xresolution" [ 320 ] "integer yresolution" [ 240 ]
     "string filename" [ "$1.pfm" ]
Sampler "halton" "integer pixelsamples" [ 64 ]
Integrator "path" "integer maxdepth" [ 5 ]
WorldBegin
LightSource "infinite" "rgb L" [ 0.35 0.42 0.55 ]
LightSource "distant" "point from" [ -3 -4 6 ] "point to" [ 0 0 0 ] "rgb L" [ 2.5 2.4 2.2 ]
AttributeBegin
  $2
  Translate 0 0 1
  Shape "sphere" "float radius" [ 1 ]
AttributeEnd
AttributeBegin
  Texture "checks" "spectrum" "checkerboard" "float uscale" [ 10 ] "float vscale" [ 10 ]
          "rgb tex1" [ 0.08 0.08 0.08 ] "rgb tex2" [ 0.7 0.7 0.7 ]
  Material "matte" "texture Kd" "checks"
  Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ]
        "point P" [ -8 -8 0  8 -8 0  8 8 0  -8 8 0 ]
        "float uv" [ 0 0 1 0 1 1 0 1 ]
AttributeEnd
WorldEnd
EOF
}
fourier() { scene "$1" "Material \"fourier\" \"string bsdffile\" [ \"$1.bsdf\" ]"; }

# render BUILD NAME: out/BUILD-NAME.{pfm,log,rc,time}
render() {
    rm -f "$out/$1-$2.pfm"
    cpu_mark
    start=$cpu
    # An inner shell waits for pbrt, so that its "Aborted" or "Segmentation
    # fault" notice goes to /dev/null (the table says what happened); it
    # exits with pbrt's status (128 + signal after a crash).
    (cd "$scenes" && sh -c 'timeout "$1" "$2" --nthreads "$3" --quiet "$4.pbrt" \
        --outfile "$5.pfm" > "$5.log" 2>&1; exit $?' sh "$limit" "$(pbrt_of "$1")" \
        "$threads" "$2" "$out/$1-$2" 2> /dev/null)
    echo $? > "$out/$1-$2.rc"
    cpu_mark
    elapsed "$start" "$cpu" > "$out/$1-$2.time"
}

scene black 'Material "matte" "rgb Kd" [ 0 0 0 ]'
fourier golden
fourier coated-gold
cut -f 1 "$work/cases.txt" | while read -r name; do fourier "$name"; done
names="golden coated-gold black $(cut -f 1 "$work/cases.txt" | tr '\n' ' ')"
echo "pbrt-check: rendering $(echo $names | wc -w) scenes with each build (320 x 240, 64 spp, --nthreads $threads)"
for name in $names; do
    for v in stock shim; do render $v "$name"; done
done

diffs() { python3 "$here/imgdiff.py" "$out/$1.pfm" "$out/$2.pfm"; }
for name in golden coated-gold black; do
    for v in stock shim; do
        [ "$(cat "$out/$v-$name.rc")" = 0 ] && [ -f "$out/$v-$name.pfm" ] ||
            { tail -n 5 "$out/$v-$name.log" >&2; fail "$v pbrt did not render $name.pbrt"; }
    done
done
# Failures are listed after the tables, which stay whole.
status=0
problems=$work/problems.txt
: > "$problems"
problem() { echo "pbrt-check: FAIL: $*" >> "$problems"; status=1; }

# ------------------------------------------------- 3. the two builds compared
echo
echo "Intact files, stock pbrt-v3 against the shim (whole RGB image, 320 x 240, 64 spp):"
echo
echo "| file | mean (stock) | mean abs diff | RMSE | RMSE/mean | bit-identical pixels | render CPU s, stock / shim |"
echo "|---|---|---|---|---|---|---|"
for name in golden coated-gold; do
    set -- $(diffs "stock-$name" "shim-$name")
    pct=$(awk -v f="$6" 'BEGIN { printf "%.0f %%", 100 * f }')
    echo "| $name | $1 | $3 | $4 | $5 | $pct | $(cat "$out/stock-$name.time") / $(cat "$out/shim-$name.time") |"
    awk -v r="$5" -v t="$tolerance" 'BEGIN { exit !(r < t) }' ||
        problem "$name: RMSE/mean $5 is not below $tolerance"
done

# look BUILD CASE: what the image shows (black sphere, as intact, wrong)
look() {
    set -- $(diffs "$1-black" "$1-$2") "$1" "$2"
    if [ "$4" = 0 ] && [ "$6" = 1.000 ]; then
        echo "black sphere"
        return
    fi
    set -- $(diffs "$7-golden" "$7-$8")
    if [ "$4" = 0 ]; then
        echo "image identical to the intact file's"
    else
        echo "renders wrongly: RMSE/mean $5 against the intact file"
    fi
}

# what BUILD CASE: one table cell
what() {
    rc=$(cat "$out/$1-$2.rc")
    log=$out/$1-$2.log
    if [ "$rc" = 124 ]; then
        echo "still running after $limit s (stopped)"
        return
    fi
    errors=$(grep -c 'Error:' "$log")
    case $errors in 0) said="no message" ;; 1) said="one error" ;; *) said="$errors errors" ;; esac
    image=
    [ -f "$out/$1-$2.pfm" ] && image=$(look "$1" "$2")
    if [ "$rc" -gt 128 ]; then
        # (glog's "F<date> <time> <thread> " prefix of a failed CHECK left out)
        message=$(grep -m 1 -E 'free\(\)|double free|corrupted|malloc|Assertion|Check failed|terminate|stack smashing' "$log" |
            sed 's/^F[0-9]\{8\} [0-9:.]* *[0-9]* //; s/ *$//')
        crash="crash, SIG$(kill -l $((rc - 128)))${message:+: \`$message\`}"
        if [ -n "$image" ]; then
            echo "$said, $image, then $crash"
        else
            echo "$said, no image: $crash"
        fi
        return
    fi
    if [ "$rc" != 0 ] || [ -z "$image" ]; then
        echo "$said, exit status $rc, no image"
        return
    fi
    ratio=$(awk -v a="$(cat "$out/$1-$2.time")" -v b="$(cat "$out/$1-golden.time")" \
        'BEGIN { if (a > 1.5 * b) printf ", %.1f x the intact file'"'"'s CPU time", a / b }')
    echo "$said, $image$ratio"
}

echo
echo "Damaged copies of the golden file:"
echo
echo "| file | damage | stock pbrt-v3 | shim |"
echo "|---|---|---|---|"
while IFS="$(printf '\t')" read -r name damage; do
    echo "| \`$name.bsdf\` | $damage | $(what stock "$name") | $(what shim "$name") |"
    [ "$(what shim "$name" | cut -d , -f 1-2)" = "one error, black sphere" ] ||
        problem "the shim on $name.bsdf: $(what shim "$name")"
done < "$work/cases.txt"

echo
echo "The shim's messages:"
while IFS="$(printf '\t')" read -r name damage; do
    grep -m 1 'Error:' "$out/shim-$name.log" | sed 's/^/    /'
done < "$work/cases.txt"

# ------------------------------------------------------- 4. textured files
# A textured coated gold (coat alpha sampled at 0.1, 0.2, 0.3, 0.4 over gold
# of alpha 0.1), built basis by basis with the public API
# (tests/textured_grid.c) and rendered by the shim only (stock pbrt-v3's
# "fourier" material takes no parameters): with "float coat.alpha" 0.1 and
# 0.4, with an imagemap whose upper half is 0.4 and lower half 0.1, with a
# striped roughness map (textures.py), and without the parameter. It passes
# when the constant 0.1 renders as the untextured coated gold above (the
# same material at the same resolution: RMSE/mean < PBRT_TOLERANCE), the
# textured sphere's upper half renders as the constant 0.4 and its lower
# half as 0.1 (of the pixels that the two constants render differently, at
# least 90 % closer to the constant of their half), and the scene without
# the parameter renders, with one warning naming it.
echo
echo "Textured coated gold through the shim (coat.alpha sampled at 0.1, 0.2, 0.3, 0.4):"
tg=$work/textured_grid
# shellcheck disable=SC2046
cc -std=c99 -O2 -o "$tg" "$top/tests/textured_grid.c" \
    $(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs layerlab) -lm \
    > "$work/textured_grid.log" 2>&1 ||
    { cat "$work/textured_grid.log" >&2; fail "cannot compile tests/textured_grid.c"; }
"$tg" "$scenes/textured.bsdf" 'dielectric eta=1.5 alpha={0}\nconductor eta=Au alpha=0.1' \
    coat.alpha=0.1,0.2,0.3,0.4 >> "$work/textured_grid.log" 2>&1 ||
    { cat "$work/textured_grid.log" >&2; fail "textured_grid failed"; }
sed 's/^/    /' "$work/textured_grid.log" | tail -n 1
python3 "$here/textures.py" halves "$scenes/halves.pfm" 0.4 0.1 &&
python3 "$here/textures.py" stripes "$scenes/stripes.pfm" 0.1 0.4 || fail "textures.py failed"
textured() {
    scene "$1" "$2
  Material \"fourier\" \"string bsdffile\" [ \"textured.bsdf\" ] $3"
}
textured tex-0.1 '' '"float coat.alpha" [ 0.1 ]'
textured tex-0.4 '' '"float coat.alpha" [ 0.4 ]'
textured tex-halves 'Texture "halves" "float" "imagemap" "string filename" [ "halves.pfm" ]' \
    '"texture coat.alpha" "halves"'
textured tex-stripes 'Texture "stripes" "float" "imagemap" "string filename" [ "stripes.pfm" ]' \
    '"texture coat.alpha" "stripes"'
textured tex-unset '' ''
for name in tex-0.1 tex-0.4 tex-halves tex-stripes; do
    render shim "$name"
    [ "$(cat "$out/shim-$name.rc")" = 0 ] && [ -f "$out/shim-$name.pfm" ] ||
        { tail -n 5 "$out/shim-$name.log" >&2; fail "the shim did not render $name.pbrt"; }
done
# Without --quiet, which silences pbrt's warnings.
(cd "$scenes" && timeout "$limit" "$pbrt_shim" --nthreads "$threads" tex-unset.pbrt \
    --outfile "$out/shim-tex-unset.pfm" > "$out/shim-tex-unset.log" 2>&1) ||
    problem "the shim did not render tex-unset.pbrt (exit status $?)"
echo
echo "| scene | compared with | result | render CPU s |"
echo "|---|---|---|---|"
set -- $(diffs "shim-coated-gold" "shim-tex-0.1")
pct=$(awk -v f="$6" 'BEGIN { printf "%.0f %%", 100 * f }')
echo "| \"float coat.alpha\" 0.1 | untextured coated gold | RMSE/mean $5, $pct bit-identical pixels | $(cat "$out/shim-tex-0.1.time") |"
awk -v r="$5" -v t="$tolerance" 'BEGIN { exit !(r < t) }' ||
    problem "tex-0.1: RMSE/mean $5 against the untextured coated gold is not below $tolerance"
set -- $(diffs "shim-tex-0.1" "shim-tex-0.4")
echo "| \"float coat.alpha\" 0.4 | \"float coat.alpha\" 0.1 | RMSE/mean $5 | $(cat "$out/shim-tex-0.4.time") |"
# Rows 25 .. 94 show the sphere's upper half, rows 135 .. 174 its lower
# half: this camera puts the equator z = 1 between rows 105 (at the limbs)
# and 123 (in front), the sphere's bottom at row 179.
set -- $(python3 "$here/textures.py" regions "$out/shim-tex-halves.pfm" \
    "$out/shim-tex-0.4.pfm" "$out/shim-tex-0.1.pfm" 25 95 135 175)
echo "| imagemap, upper half 0.4, lower 0.1 | the two constants | upper rows: $1 of $2 differing pixels closer to 0.4; lower rows: $3 of $4 closer to 0.1 | $(cat "$out/shim-tex-halves.time") |"
awk -v a="$1" -v b="$3" 'BEGIN { exit !(a >= 0.9 && b >= 0.9) }' ||
    problem "tex-halves: the halves do not render as their constants ($1 and $3 of the pixels)"
set -- $(diffs "shim-tex-0.1" "shim-tex-stripes")
echo "| imagemap stripes (0.1, and 0.1 .. 0.4 bottom to top) | \"float coat.alpha\" 0.1 | RMSE/mean $5 | $(cat "$out/shim-tex-stripes.time") |"
warnings=$(grep -c 'Warning:.*coat\.alpha' "$out/shim-tex-unset.log")
echo
echo "Without the parameter ($warnings warning naming it):"
grep -m 1 'Warning:.*coat\.alpha' "$out/shim-tex-unset.log" | sed 's/^/    /'
[ "$warnings" = 1 ] || problem "tex-unset: $warnings warnings naming coat.alpha, not 1"

echo
cat "$problems"
if [ $status = 0 ]; then
    echo "pbrt-check: passed (images and logs in $out)"
else
    echo "pbrt-check: FAILED (images and logs in $out)"
fi
exit $status
