# Sourced by the shell checks of the command-line tools (llbuild.sh,
# llbuild_tables.sh, llbuild_signals.sh, llbuild_time.sh, llbuild_mpi.sh,
# llconvert.sh) and of the tree (api_doc.sh, history_words.sh,
# tool_help.sh); kept out of tests/*.sh, which the suite runs: their scratch
# directory, their counters and the checks they all make, in one place so
# that each script counts and reports the same way. The Makefile and CI read
# the last line a script prints ("N passed, M failed") and its exit status.
#
#   tool_test_begin PREFIX     make the scratch directory $tmp
#                              (/tmp/PREFIX.XXXXXX, removed on exit), point
#                              the resolution cache into it, zero the counters
#   tool_test_need NAME TOOL...  unless every TOOL is built: say so as NAME,
#                              report one failure and exit 1
#   ok / bad TEXT              count a pass / count a failure and print it
#   pass TEXT                  count a pass and print it (for scripts that
#                              print one line per check)
#   expect CODE DESCRIPTION -- command...
#                              the command's exit status must be CODE; its
#                              stdout goes to $tmp/out, stderr to $tmp/err
#   contains FILE TEXT DESCRIPTION
#                              FILE must hold TEXT
#   tool_test_end [NAME]       print "[NAME: ]N passed, M failed"; its status
#                              (the script's, as its last command) is 0 only
#                              when nothing failed
#   signal_in_stage SIG PATTERN NOUN LABEL
#                              after stage_start (stage_wait.sh, sourced
#                              here too) of an llbuild: send SIG as soon as
#                              a progress line matches PATTERN, wait for the
#                              build, and check that the signal ended it
#                              ("LABEL: exit N, expected death by signal");
#                              1, counted as a failure, when the build never
#                              reported NOUN

. "$(dirname "$0")/lib/stage_wait.sh"

tool_test_begin() {
    tmp=$(mktemp -d "/tmp/$1.XXXXXX")
    trap 'rm -rf "$tmp"' EXIT
    # Hermetic: the resolutions chosen are remembered in a scratch
    # directory, never the user's cache.
    LAYERLAB_CACHE_DIR="$tmp/cache"
    export LAYERLAB_CACHE_DIR
    passed=0
    failed=0
}

tool_test_need() {
    need_name=$1
    shift
    need_missing=0
    need_list=
    for need_tool in "$@"; do
        [ -x "$need_tool" ] || need_missing=1
        need_list="${need_list:+$need_list or }$need_tool"
    done
    if [ "$need_missing" -ne 0 ]; then
        echo "$need_name: $need_list is not built"
        echo "0 passed, 1 failed"
        exit 1
    fi
}

ok() { passed=$((passed + 1)); }
pass() { echo "PASS: $*"; ok; }
bad() { failed=$((failed + 1)); echo "FAIL: $*"; }

expect() {
    want=$1; what=$2; shift 3
    "$@" >"$tmp/out" 2>"$tmp/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok; else
        bad "$what: exit $got, expected $want"; sed 's/^/  | /' "$tmp/err" | head -5
    fi
}

contains() {
    if grep -q -- "$2" "$1"; then ok; else bad "$3: no '$2' in:"; sed 's/^/  | /' "$1" | head -8; fi
}

signal_in_stage() {
    if ! stage_wait "$2"; then
        stage_finish
        bad "SIG$1: llbuild never reported $3 (exit $stage_status)"
        return 1
    fi
    kill -s "$1" "$stage_pid" 2>/dev/null || bad "SIG$1: llbuild ended before the signal"
    stage_finish
    if [ "$stage_status" -gt 128 ] && [ "$stage_timed_out" -eq 0 ]; then ok; else
        bad "$4: exit $stage_status, expected death by signal"; fi
    return 0
}

tool_test_end() {
    echo "${1:+$1: }$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}
