#!/bin/sh
# llbuild under SIGINT / SIGTERM at every stage of a build: quadrature,
# diffuse, interface, phase function, doubling, adding, writing. The test
# reads llbuild's progress as it is written (tests/lib/stage_wait.sh) and
# signals it as soon as a line names the stage, then checks the exit status
# (130 for SIGINT, 143 for SIGTERM: death by the signal), the message, that
# no file and no temporary is left, and that the last progress line is
# still the stage: the library polls inside every long loop, so the build
# stops within the stage it was signalled in, whatever the machine's speed.
# Each input keeps its stage busy for a fraction of a second, far longer
# than the test takes to answer a line (a read from a pipe and a kill).
# Run by `make check` from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin llbuild_signals

tool_test_need llbuild_signals.sh "$llbuild"

# interrupt NAME SIGNAL STAGE MATERIAL: build MATERIAL, signal it as soon as
# a progress line names STAGE. (A stage's name can show before a sub-stage
# of it, e.g. "medium" before its "phase function": the line must name the
# stage itself, so "% STAGE (".)
interrupt() {
    name=$1 sig=$2 stage=$3 text=$4
    case $sig in INT) want=130 ;; TERM) want=143 ;; esac
    dir="$tmp/$name"
    mkdir -p "$dir/out"
    printf '%b' "$text" >"$dir/in.layers"
    stage_start "$dir" "$llbuild" "$dir/in.layers" -o "$dir/out/built.bsdf"
    if ! stage_wait "*% $stage (*"; then
        stage_finish
        bad "$name: llbuild never reported '$stage' (exit $stage_status)"
        sed 's/^/  | /' "$stage_log" | tail -5
        return
    fi
    if ! kill -s "$sig" "$stage_pid" 2>/dev/null; then
        stage_finish
        bad "$name: llbuild ended before the signal"
        return
    fi
    stage_finish
    status=$stage_status
    last=$(grep '%' "$stage_log" | tail -1)
    if [ "$status" -eq "$want" ]; then ok; else bad "$name: SIG$sig gave exit $status, expected $want"; fi
    if grep -q "^llbuild: interrupted; no file written$" "$stage_log"; then ok; else
        bad "$name: no 'interrupted; no file written' in:"; sed 's/^/  | /' "$stage_log" | tail -5
    fi
    left=$(ls -A "$dir/out")
    if [ -z "$left" ]; then ok; else bad "$name: left files behind: $left"; fi
    if [ "$stage_timed_out" -eq 0 ]; then ok; else bad "$name: SIG$sig did not stop the build"; fi
    case $last in *"% $stage ("*) ok ;; *) bad "$name: interrupted in '$last', not in '$stage'" ;; esac
    echo "  $name: SIG$sig in '$stage', exit $status"
}

# The quadrature: an O(n^2) Gauss-Lobatto rule (8000 nodes: about 0.4 s
# idle on one core).
interrupt quadrature INT quadrature 'set nodes=8000 orders=1\ndiffuse albedo=0.5\n'
# The diffuse word is O(n^2) in one thread (6000 nodes: about 0.4 s).
interrupt diffuse TERM diffuse 'set nodes=6000 orders=1\ndiffuse albedo=0.5\n'
# A rough dielectric resolved on many orders: series per column.
interrupt interface TERM "dielectric interface" \
    'set nodes=500 orders=150\ndielectric eta=1.5 alpha=0.05\n'
# A strongly forward-scattering medium: n x n x K products for 40 orders
# (so thin that it is doubled: a thicker one gets its phase matrices and
# its slab in one pass, the "medium" stage below).
interrupt phase INT "phase function" 'set nodes=600 orders=40\nmedium albedo=0.9 g=0.99 tau=1e-4\n'
# A very thick medium: the slab of every order (one eigendecomposition of
# h = 250 each) in one pass with its phase matrices.
interrupt doubling TERM medium 'set nodes=500 orders=40\nmedium albedo=0.99 g=0.9 tau=1e9\n'
# Two thin forward-scattering media: quick to double (two doublings each),
# adding them is dense work for every order (isotropic media would not do:
# their orders > 0 only transmit straight through, added without dense work).
interrupt adding INT adding \
    'set nodes=600 orders=60\nmedium albedo=0.5 g=0.9 tau=0.0001\nmedium albedo=0.9 g=0.9 tau=0.0002\n'
# Writing: 2000 nodes make a 32 MB file.
interrupt writing TERM writing 'set nodes=2000 orders=1\ndiffuse albedo=0.5\n'
# A swept material (a textured file): in the second basis's interface, and
# in the streaming writer's commit at the end (2 bases of 2000 nodes).
interrupt basis INT "basis 2/3: dielectric interface" \
    'set nodes=500 orders=150\ndielectric eta=1.5 alpha=[0.05 0.06 0.07]\n'
interrupt textured-writing TERM writing 'set nodes=2000 orders=1\ndiffuse albedo=[0.3 0.5]\n'

tool_test_end llbuild_signals.sh
