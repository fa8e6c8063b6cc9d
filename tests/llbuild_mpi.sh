#!/bin/sh
# llbuild-mpi across 1 to 4 ranks on one machine (oversubscribed): its files
# are llbuild's byte for byte; bad input exits 1 with one message; a budget
# refusal names the rank and its estimate; a rank killed with SIGKILL, or an
# interrupt to mpirun, leaves no file and no temporary.
# Run by `make test` from the checkout with BUILD set; skipped (with a
# message, exit 0) where OpenMPI is not installed (make deps installs it).
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
mpi="$BUILD/bin/llbuild-mpi"
if ! command -v mpirun >/dev/null 2>&1 || [ ! -x "$mpi" ]; then
    echo "llbuild_mpi.sh: skipped: needs mpirun and $mpi (OpenMPI: make deps)"
    echo "0 passed, 0 failed"
    exit 0
fi
. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin llbuild_mpi_test
# CI runs as root, which OpenMPI refuses unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Under `make test SANITIZE=1`: OpenMPI keeps allocations past MPI_Finalize,
# which LeakSanitizer would report on every rank; the library's side of a
# distributed build is leak-checked by test_material_distributed instead.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
# No MPI warnings about the transport on a machine without a network card.
export OMPI_MCA_btl=self,vader OMPI_MCA_btl_base_warn_component_unused=0

run() { n=$1; shift; mpirun --oversubscribe -n "$n" "$mpi" "$@"; }

# --- byte-identical to llbuild for every N: a medium between rough
# interfaces (RGB from the named metal, and mono), and a transmissive stack.
cat >"$tmp/medium.layers" <<'LAYERS'
dielectric  eta=1.5 alpha=0.2
medium      albedo=0.8,0.5,0.9 g=0.6 tau=1.5
conductor   eta=Au alpha=0.15
set nodes=40 orders=60
LAYERS
cat >"$tmp/glass.layers" <<'LAYERS'
dielectric  eta=1.5 alpha=0.3
medium      albedo=0.95 g=0.3 tau=0.5
dielectric  eta=0.8 alpha=0.1
set nodes=30 orders=40
LAYERS
for case in "medium --rgb" "medium --mono" "glass --mono"; do
    set -- $case
    "$llbuild" -q --threads 1 "$2" "$tmp/$1.layers" -o "$tmp/$1$2.ref.bsdf" ||
        bad "llbuild $case failed"
    for n in 1 2 3 4; do
        out="$tmp/$1$2.$n.bsdf"
        if run "$n" -q --threads 1 "$2" "$tmp/$1.layers" -o "$out" >"$tmp/out" 2>"$tmp/err"; then
            if cmp -s "$tmp/$1$2.ref.bsdf" "$out"; then ok; else
                bad "$case on $n ranks: the file differs from llbuild's"; fi
        else
            bad "$case on $n ranks failed"; sed 's/^/  | /' "$tmp/err" | head -5
        fi
    done
done
# A textured material (bases across the ranks, shared words, the streaming
# writer): byte-identical too, and no spill left beside the output.
cat >"$tmp/tex.layers" <<'LAYERS'
dielectric  eta=1.5 alpha=[0.1..0.4:3]
medium      albedo=0.8,0.6,0.4 g=0.5 tau=0.5
conductor   eta=Au alpha=[0.1 0.2]
set nodes=30 orders=40
LAYERS
"$llbuild" -q --threads 1 "$tmp/tex.layers" -o "$tmp/tex.ref.bsdf" || bad "llbuild textured failed"
for n in 1 2 3 4; do
    if run "$n" -q --threads 1 "$tmp/tex.layers" -o "$tmp/tex.$n.bsdf" >"$tmp/out" 2>"$tmp/err"
    then
        if cmp -s "$tmp/tex.ref.bsdf" "$tmp/tex.$n.bsdf"; then ok; else
            bad "textured on $n ranks: the file differs from llbuild's"; fi
    else
        bad "textured on $n ranks failed"; sed 's/^/  | /' "$tmp/err" | head -5
    fi
done
[ "$(ls -A "$tmp" | grep -c '\.tmp$')" -eq 0 ] && ok || bad "a textured build left a temporary"
# The summary is llbuild's, from rank 0 only.
run 2 --threads 1 "$tmp/medium.layers" -o "$tmp/summary.bsdf" >"$tmp/out" 2>/dev/null
if [ "$(grep -c '^resolution' "$tmp/out")" -eq 1 ] && grep -q '^ranks        2' "$tmp/out"; then
    ok; else bad "summary: expected one from rank 0"; sed 's/^/  | /' "$tmp/out"; fi

# --- bad input: exit 1 on every rank, one message with file:line:column
printf 'dielectric eta=1.5 alpha=0.1\nmedium albedo=2 tau=1\n' >"$tmp/bad.layers"
run 3 "$tmp/bad.layers" -o "$tmp/bad.bsdf" >"$tmp/out" 2>"$tmp/err"
code=$?
[ "$code" -eq 1 ] && ok || bad "bad material: exit $code, expected 1"
lines=$(grep -c '^llbuild: ' "$tmp/err")
[ "$lines" -eq 1 ] && ok || { bad "bad material: $lines messages, expected 1"; cat "$tmp/err"; }
grep -q 'bad.layers:2:15: albedo=2 is out of range' "$tmp/err" && ok ||
    bad "bad material: no file:line:column in the message"
[ ! -e "$tmp/bad.bsdf" ] && ok || bad "bad material left a file"

# --- a budget refusal: each rank's share is checked; the message names
# the rank and its estimate; exit 1 as llbuild's.
run 2 -q --threads 1 --nodes 60 --orders 120 --max-memory 1M "$tmp/medium.layers" \
    -o "$tmp/budget.bsdf" >"$tmp/out" 2>"$tmp/err"
code=$?
[ "$code" -eq 1 ] && ok || bad "over budget: exit $code, expected 1"
grep -q '^llbuild: rank 0 of 2: .*estimated peak of this rank' "$tmp/err" && ok ||
    { bad "over budget: no rank and estimate in the message"; cat "$tmp/err"; }

# --- a rank killed (SIGKILL, no chance to clean up) and an interrupt to
# mpirun: no file, no temporary. The kill and the interrupt follow rank 0's
# progress line naming a stage (tests/lib/stage_wait.sh), not a sleep: the
# first layer's ("conductor interface", the build's first stage; mpirun
# takes up to a second to pass an interrupt on, so the build runs several
# seconds on 3 ranks of a 2-core machine: at 300 nodes and 600 orders one
# can finish in about a second, and the interrupt then lands after the
# file is committed), and for the textured build its first line ("choosing the
# resolution": its shared words take 5 s before the first basis is written,
# and the 8 bases then follow within 1.3 s, too close to the end for a
# kill to land before the file is committed).
mkdir -p "$tmp/run"
cat >"$tmp/long.layers" <<'LAYERS'
dielectric  eta=1.5 alpha=0.1
medium      albedo=0.9 g=0.8 tau=4
conductor   eta=Au alpha=0.1
set nodes=500 orders=1500
LAYERS
# start_until LAYERS PATTERN: start a build of LAYERS on 3 ranks; return
# once rank 0's progress matches PATTERN (1: it never did).
start_until() {
    rm -f "${1%.layers}.bsdf"
    stage_start "$tmp/run" mpirun --oversubscribe -n 3 "$mpi" --threads 1 "$1" \
        -o "${1%.layers}.bsdf"
    launcher=$stage_pid
    stage_wait "$2" && return 0
    bad "$1: the build never reported '$2'"
    sed 's/^/  | /' "$stage_log" | tail -5
    return 1
}
leftovers() { ls -A "$tmp" | grep -c "$1\.bsdf"; }
# No rank outlives mpirun: wait (bounded) until none is left.
ranks_gone() {
    tries=0
    while pgrep -f "$1" >/dev/null && [ $tries -lt 300 ]; do
        sleep 0.1
        tries=$((tries + 1))
    done
    ! pgrep -f "$1" >/dev/null
}
if start_until "$tmp/long.layers" "*% conductor interface (*"; then
    victim=$(pgrep -P "$launcher" | sed -n 2p)
    [ -n "$victim" ] && kill -9 "$victim"
fi
stage_finish
[ "$stage_status" -ne 0 ] && ok || bad "a killed rank: mpirun exited 0"
[ "$(leftovers long)" -eq 0 ] && ok || { bad "a killed rank left:"; ls -A "$tmp"; }
start_until "$tmp/long.layers" "*% conductor interface (*" && kill -INT "$launcher"
stage_finish
[ "$stage_status" -ne 0 ] && ok || bad "interrupted mpirun exited 0"
[ "$(leftovers long)" -eq 0 ] && ok || { bad "an interrupt left:"; ls -A "$tmp"; }
ranks_gone "$tmp/long.layers" && ok || bad "ranks still running after the interrupt"

# A textured build with a worker killed, and with an interrupt: no file and
# no temporary (the writer's spill is unlinked once open; rank 0 aborts it).
cat >"$tmp/longtex.layers" <<'LAYERS'
dielectric  eta=1.5 alpha=[0.1..0.4:4]
medium      albedo=0.9 g=0.8 tau=4
conductor   eta=Au alpha=[0.1 0.2]
set nodes=200 orders=400
LAYERS
if start_until "$tmp/longtex.layers" "*% choosing the resolution (*"; then
    victim=$(pgrep -P "$launcher" | sed -n 3p)
    [ -n "$victim" ] && kill -9 "$victim"
fi
stage_finish
[ "$stage_status" -ne 0 ] && ok || bad "textured, a killed rank: mpirun exited 0"
[ "$(leftovers longtex)" -eq 0 ] && ok ||
    { bad "textured, a killed rank left:"; ls -A "$tmp"; }
start_until "$tmp/longtex.layers" "*% choosing the resolution (*" && kill -INT "$launcher"
stage_finish
[ "$(leftovers longtex)" -eq 0 ] && ok ||
    { bad "textured, an interrupt left:"; ls -A "$tmp"; }

tool_test_end
