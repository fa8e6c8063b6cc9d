#!/bin/sh
# llbuild under SIGINT / SIGTERM at every stage of a build: quadrature,
# diffuse, interface, phase function, doubling, adding, writing. Each input sits in
# its stage for seconds; once llbuild's progress names the stage the test
# signals it and checks the exit status (130 for SIGINT, 143 for SIGTERM:
# death by the signal), the message, that no file and no temporary is left,
# and that the exit came within a generous 3 s of the signal (the library
# polls inside every long loop; the measured times are far shorter, but
# tests must not be timing-flaky on a loaded machine).
# Run by `make test` from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
tmp=$(mktemp -d /tmp/llbuild_signals.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
LIMIT_MS=3000

ok() { passed=$((passed + 1)); }
bad() { failed=$((failed + 1)); echo "FAIL: $*"; }

if [ ! -x "$llbuild" ]; then
    echo "llbuild_signals.sh: $llbuild is not built"
    echo "0 passed, 1 failed"
    exit 1
fi

now_ms() { echo $(($(date +%s%N) / 1000000)); }

# interrupt NAME SIGNAL STAGE MATERIAL: build MATERIAL, signal it 0.3 s into STAGE.
# Does the latest progress line of file $1 name stage $2?
in_stage() { case $(grep '%' "$1" 2>/dev/null | tail -1) in *"% $2"*) return 0 ;; esac; return 1; }

interrupt() {
    name=$1 sig=$2 stage=$3 text=$4
    case $sig in INT) want=130 ;; TERM) want=143 ;; esac
    dir="$tmp/$name"
    mkdir -p "$dir/out"
    printf '%b' "$text" >"$dir/in.layers"
    "$llbuild" "$dir/in.layers" -o "$dir/out/built.bsdf" >/dev/null 2>"$dir/err" &
    pid=$!
    # A watchdog: a build that ignores the signal must not run on.
    ( sleep 60; kill -9 $pid 2>/dev/null ) &
    dog=$!
    i=0
    # Wait until the latest progress line names the stage (a stage's name
    # can show before a sub-stage of it, e.g. "medium" before its "phase
    # function": the signal must come while the stage itself runs).
    while [ $i -lt 1200 ] && ! in_stage "$dir/err" "$stage" && kill -0 $pid 2>/dev/null; do
        sleep 0.05; i=$((i + 1))
    done
    if ! in_stage "$dir/err" "$stage"; then
        bad "$name: llbuild never reached '$stage'"; sed 's/^/  | /' "$dir/err" | tail -5
        kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null; kill $dog 2>/dev/null
        return
    fi
    sleep 0.1
    if ! kill -0 $pid 2>/dev/null; then
        bad "$name: the build ended before the signal (make the input slower)"
        wait $pid 2>/dev/null; kill $dog 2>/dev/null
        return
    fi
    t0=$(now_ms)
    kill -s "$sig" $pid
    wait $pid 2>/dev/null
    status=$?
    t1=$(now_ms)
    kill $dog 2>/dev/null
    wait $dog 2>/dev/null
    last=$(grep '%' "$dir/err" | tail -1)
    if [ "$status" -eq "$want" ]; then ok; else bad "$name: SIG$sig gave exit $status, expected $want"; fi
    if grep -q "^llbuild: interrupted; no file written$" "$dir/err"; then ok; else
        bad "$name: no 'interrupted; no file written' in:"; sed 's/^/  | /' "$dir/err" | tail -5
    fi
    left=$(ls -A "$dir/out")
    if [ -z "$left" ]; then ok; else bad "$name: left files behind: $left"; fi
    if [ $((t1 - t0)) -le $LIMIT_MS ]; then ok; else
        bad "$name: exit $((t1 - t0)) ms after SIG$sig (limit $LIMIT_MS ms)"
    fi
    case $last in *"% $stage"*) ok ;; *) bad "$name: interrupted in '$last', not in '$stage'" ;; esac
    echo "  $name: SIG$sig in '$stage', exit $status after $((t1 - t0)) ms"
}

# O(n^2) Gauss-Lobatto rule: seconds at 16000 nodes.
interrupt quadrature INT quadrature 'set nodes=16000 orders=1\ndiffuse albedo=0.5\n'
# The diffuse word is O(n^2) in one thread.
interrupt diffuse TERM diffuse 'set nodes=12000 orders=1\ndiffuse albedo=0.5\n'
# A rough dielectric resolved on many orders: seconds of series per column.
interrupt interface TERM "dielectric interface" \
    'set nodes=800 orders=250\ndielectric eta=1.5 alpha=0.05\n'
# A strongly forward-scattering medium: n x n x K products for 40 orders.
interrupt phase INT "phase function" 'set nodes=800 orders=40\nmedium albedo=0.9 g=0.99 tau=1\n'
# A very thick medium: 45 doublings of every order.
interrupt doubling TERM medium 'set nodes=400 orders=20\nmedium albedo=0.99 g=0.9 tau=1e9\n'
# Two isotropic media: their doublings are quick (orders > 0 are diagonal),
# adding them is dense work for every order.
interrupt adding INT adding \
    'set nodes=800 orders=80\nmedium albedo=0.5 phase=isotropic tau=0.001\nmedium albedo=0.9 phase=isotropic tau=0.002\n'
# Writing: 3000 nodes make a 125 MB file.
interrupt writing TERM writing 'set nodes=3000 orders=1\ndiffuse albedo=0.5\n'
# A swept material (a textured file): in the second basis's interface, and
# in the streaming writer's commit at the end (2 bases of 2400 nodes).
interrupt basis INT "basis 2/3: dielectric interface" \
    'set nodes=800 orders=250\ndielectric eta=1.5 alpha=[0.05 0.06 0.07]\n'
interrupt textured-writing TERM writing 'set nodes=2400 orders=1\ndiffuse albedo=[0.3 0.5]\n'

echo "llbuild_signals.sh: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
