# Sourced (through tool_test.sh) by the tests that signal or kill a running
# build (llbuild.sh, llbuild_tables.sh, llbuild_signals.sh, llbuild_mpi.sh;
# kept out of tests/*.sh, which the suite runs): the signal follows the build's own report of the stage,
# never a sleep. The build's stderr (llbuild's plain progress lines,
# "llbuild:  40% adding (...)") goes to a fifo that this shell reads line
# by line as the lines are written; stage_wait returns as soon as a line
# names the stage. A watchdog ends the build (its children first: an MPI
# build's ranks under mpirun) after STAGE_TIMEOUT seconds (default 300),
# far beyond any of these builds, so that a build that never reports the
# stage, or ignores a signal, fails the test with a message instead of
# hanging it.
#
#   stage_start DIR CMD ARGS...  run CMD in the background, stdout to
#                                DIR/stdout, stderr through DIR/fifo; sets
#                                stage_pid (CMD's process) and stage_log
#                                (DIR/err: every line read so far)
#   stage_wait PATTERN           read lines until one matches the case
#                                pattern (e.g. "*% adding*"): 0, or 1 when
#                                the build ended (or was ended) first
#   stage_finish                 read the rest, wait for the build, stop
#                                the watchdog; sets stage_status (the exit
#                                status; 137 when the watchdog ended it)
#                                and stage_timed_out (1 then)

STAGE_TIMEOUT=${STAGE_TIMEOUT:-300}

stage_start() {
    stage_dir=$1
    shift
    stage_log="$stage_dir/err"
    : >"$stage_log"
    rm -f "$stage_dir/fifo" "$stage_dir/timed_out"
    mkfifo "$stage_dir/fifo" || return 1
    # The build opens the fifo for writing, which waits for the reader
    # below; then both run.
    "$@" >"$stage_dir/stdout" 2>"$stage_dir/fifo" &
    stage_pid=$!
    exec 3<"$stage_dir/fifo"
    # The watchdog's sleep is killed with it (stage_finish), so that no
    # stray sleep outlives the test; its shell's "Terminated" goes nowhere.
    (
        nap=
        trap '[ -n "$nap" ] && kill $nap 2>/dev/null; exit 0' TERM
        sleep "$STAGE_TIMEOUT" &
        nap=$!
        wait $nap
        : >"$stage_dir/timed_out"
        pkill -9 -P "$stage_pid" 2>/dev/null
        kill -9 "$stage_pid" 2>/dev/null
    ) 2>/dev/null &
    stage_dog=$!
}

stage_wait() {
    while IFS= read -r stage_line <&3; do
        printf '%s\n' "$stage_line" >>"$stage_log"
        case $stage_line in
        $1) return 0 ;;
        esac
    done
    return 1
}

stage_finish() {
    # Until every writer is gone (an MPI build's ranks too), bounded.
    timeout "$STAGE_TIMEOUT" cat <&3 >>"$stage_log"
    exec 3<&-
    # (The braces keep the shell's "Terminated" for a signalled job quiet.)
    { wait "$stage_pid"; } 2>/dev/null
    stage_status=$?
    kill "$stage_dog" 2>/dev/null
    { wait "$stage_dog"; } 2>/dev/null
    stage_timed_out=0
    if [ -e "$stage_dir/timed_out" ]; then
        stage_timed_out=1
        echo "  (the watchdog ended the build after ${STAGE_TIMEOUT} s)"
    fi
    rm -f "$stage_dir/fifo" "$stage_dir/timed_out"
}
