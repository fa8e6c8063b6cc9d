#!/bin/sh
# The MPI section of `make bench-full` (docs/mpi.md): llbuild-mpi on this
# machine, oversubscribed where it has fewer cores than ranks.
#  - speed: the coated-gold-with-medium recipe on 1 and 2 ranks of one
#    thread each, against llbuild on 1 and 2 threads (best of LL_BENCH_RUNS),
#    and the 8 x 8 coated-gold grid (a textured file: bases across ranks);
#  - memory: each rank's peak RSS on 1, 2 and 4 ranks for one larger single
#    material (the same recipe at 300 nodes x 600 orders), next to the RSS
#    of a process that builds almost nothing (what is not the layers'), so
#    the 1/N split of the layers shows.
# Usage: sh bench/mpi.sh BUILD (run by bench/run.sh; skipped without mpirun).
set -u
BUILD=${1:-build-bench}
RUNS=${LL_BENCH_RUNS:-3}
mpi="$BUILD/bin/llbuild-mpi"
serial="$BUILD/bin/llbuild"
recipe=examples/coated-gold-with-scatmedium.layers
if ! command -v mpirun >/dev/null 2>&1 || [ ! -x "$mpi" ] || [ ! -x /usr/bin/time ]; then
    echo "bench/mpi.sh: skipped (needs mpirun, $mpi and /usr/bin/time)"
    exit 0
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl=self,vader OMPI_MCA_btl_base_warn_component_unused=0
work=$(mktemp -d /tmp/ll_bench_mpi.XXXXXX)
trap 'rm -rf "$work"' EXIT

# best_wall COMMAND...: the smallest wall time of RUNS runs, seconds.
best_wall() {
    best=""
    i=0
    while [ $i -lt "$RUNS" ]; do
        /usr/bin/time -f "%e" -o "$work/t" "$@" >/dev/null 2>&1 || { echo "failed"; return; }
        t=$(cat "$work/t")
        best=$(awk -v a="$best" -v b="$t" 'BEGIN { print (a == "" || b < a) ? b : a }')
        i=$((i + 1))
    done
    echo "$best"
}

echo
echo "== MPI: $recipe (default resolution), best of $RUNS, load $(cut -d' ' -f1-3 /proc/loadavg)"
s1=$(best_wall "$serial" -q --threads 1 "$recipe" -o "$work/s.bsdf")
s2=$(best_wall "$serial" -q --threads 2 "$recipe" -o "$work/s.bsdf")
m1=$(best_wall mpirun --oversubscribe -n 1 "$mpi" -q --threads 1 "$recipe" -o "$work/m.bsdf")
m2=$(best_wall mpirun --oversubscribe -n 2 "$mpi" -q --threads 1 "$recipe" -o "$work/m.bsdf")
cmp -s "$work/s.bsdf" "$work/m.bsdf" && same="byte-identical" || same="DIFFERENT"
printf '%-34s %8s s\n' "llbuild, 1 thread" "$s1" "llbuild, 2 threads" "$s2" \
    "llbuild-mpi, 1 rank x 1 thread" "$m1" "llbuild-mpi, 2 ranks x 1 thread" "$m2"
awk -v a="$m1" -v b="$m2" -v c="$s2" 'BEGIN {
    printf "speed-up of 2 ranks over 1: %.2fx (over llbuild on 2 threads: %.2fx)\n", a / b, c / b }'
echo "files: llbuild-mpi's and llbuild's are $same"

echo
echo "== MPI: the 8 x 8 coated-gold grid (textured: bases across the ranks), 196 x 267, RGB"
cat >"$work/grid.layers" <<'LAYERS'
set nodes=196 orders=267
dielectric name=coat eta=1.5 alpha=[0.05..0.4:8]
conductor  name=gold eta=Au alpha=[0.05..0.4:8]
LAYERS
g0=$(best_wall "$serial" -q --threads 1 "$work/grid.layers" -o "$work/gs.bsdf")
g1=$(best_wall mpirun --oversubscribe -n 1 "$mpi" -q --threads 1 "$work/grid.layers" -o "$work/gm.bsdf")
g2=$(best_wall mpirun --oversubscribe -n 2 "$mpi" -q --threads 1 "$work/grid.layers" -o "$work/gm.bsdf")
cmp -s "$work/gs.bsdf" "$work/gm.bsdf" && same="byte-identical" || same="DIFFERENT"
printf '%-34s %8s s\n' "llbuild, 1 thread" "$g0" "llbuild-mpi, 1 rank x 1 thread" "$g1" \
    "llbuild-mpi, 2 ranks x 1 thread" "$g2"
awk -v a="$g1" -v b="$g2" 'BEGIN { printf "speed-up of 2 ranks over 1: %.2fx\n", a / b }'
echo "files: llbuild-mpi's and llbuild's are $same"

echo
echo "== MPI: peak RSS per rank, $recipe at 300 nodes x 600 orders"
printf 'diffuse albedo=0.5\nset nodes=10 orders=1\n' >"$work/tiny.layers"
mpirun --oversubscribe -n 1 /usr/bin/time -f "%M" -o "$work/base" "$mpi" -q --threads 1 \
    "$work/tiny.layers" -o "$work/tiny.bsdf" >/dev/null 2>&1
base=$(cat "$work/base")
echo "a rank that builds almost nothing: $((base / 1024)) MiB (libraries, MPI)"
for n in 1 2 4; do
    mpirun --oversubscribe -n "$n" sh -c '/usr/bin/time -f "%M" -o "$0.$OMPI_COMM_WORLD_RANK" "$@"' \
        "$work/rss$n" "$mpi" -q --threads 1 --nodes 300 --orders 600 "$recipe" \
        -o "$work/big$n.bsdf" >/dev/null 2>&1
    line="$n rank(s):"
    r=0
    while [ $r -lt "$n" ]; do
        kib=$(cat "$work/rss$n.$r" 2>/dev/null || echo 0)
        line="$line  rank $r $((kib / 1024)) MiB (layers $(((kib - base) / 1024)))"
        r=$((r + 1))
    done
    echo "$line"
done
echo "(rank 0 also holds the finished stack it gathers for the writer)"
