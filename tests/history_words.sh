#!/bin/sh
# The tree says what is, not how it came to be: no text in it refers to the
# project's own tracker ("issue 7", "#18"), to the machine's load, the
# development machine a figure was taken on or its working folders ("load
# 7-8", "load average 9", "/work/wt-..."), to dates of work ("2026-11-22",
# "2 December 2026"), or to the sessions it was written in.
# The past is in git; a figure belongs in docs/benchmarks.md with the
# machine and method stated, or in a test that checks it.
# Each hit is printed as file:line: text. Then the check is run on a
# temporary tree of planted lines, where it must find each one (so a broken
# pattern cannot pass silently).
# Exempt, and why:
#   - this file, which has to spell the patterns;
#   - release headings of CHANGELOG.md ("## 1.0.0 - 2026-..."): a release
#     date is what a changelog is for;
#   - pytest's scope="session", an API word, not a working session (a
#     user's Python session is not flagged either);
#   - the code that measures the load (getloadavg, the benchmark report's
#     "load average" fields): it records the load of the run being
#     reported, not of a past one;
#   - a citation of another project's tracker as owner/repo#N (e.g.
#     mmp/pbrt-v4#80): a stable external reference, like a paper's.
# Run by `make test`; prints one line per check and "N passed, N failed";
# exits non-zero when a check fails.
#   sh tests/history_words.sh [PATH...]   checks these files or folders only
#                                         (relative to the top of the tree)
set -u

. "$(dirname "$0")/lib/tool_test.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cd "$SRC" || exit 1

tool_test_begin layerlab-history
trap 'exit 1' HUP INT TERM

# What is checked by default: every text file of the project (data/ holds
# measured spectra and test inputs, which are not prose).
TREE="src include tools shims python scripts tests bench examples docs cmake abi .ci
      README.md CONTRIBUTING.md CHANGELOG.md Makefile CMakeLists.txt"

# One extended regular expression per kind of word.
P_ISSUE='(^|[^A-Za-z0-9_])[Ii]ssues? #?[0-9]+'
P_HASH='(^|[^A-Za-z0-9_/&#$%.-])#[0-9]{1,5}([^0-9A-Za-z_]|$)'
P_LOAD='(^|[^A-Za-z0-9_])[Ll]oad (average )?(of |at |around |about |near |~ ?)?[0-9]|[Aa]t loads [0-9]|[Ll]oad average'
P_MACHINE='[Dd]evelopment machine|[Dd]ev machine|[Mm]y machine|/work/(wt-|main)'
MONTH='(January|February|March|April|May|June|July|August|September|October|November|December)'
P_DATE="(^|[^0-9])20[0-9][0-9]-[01][0-9]([^0-9]|\$)|[0-9] $MONTH 20[0-9][0-9]|$MONTH [0-9]{1,2}, 20[0-9][0-9]"

# A working session, not a user's Python or notebook session.
P_SESSION='([Tt]his|[Tt]hat|[Pp]revious|[Ll]ast|[Nn]ext|[Ee]arlier|[Ll]ater|[Aa]nother|[Oo]ther|[Bb]y a|[Ii]n a|of the) sessions?([^A-Za-z0-9_]|$)|[Ss]ession [0-9]|[Ss]essions? (found|wrote|added|filed|made|fixed|measured)([^A-Za-z0-9_]|$)'
PATTERN="$P_ISSUE|$P_HASH|$P_LOAD|$P_MACHINE|$P_DATE|$P_SESSION"

# The exemptions above, as file:line:text filters (extended expressions).
EXEMPT='^CHANGELOG\.md:[0-9]+:## \[?[0-9]+\.[0-9]+\.[0-9]+|scope="session"|getloadavg|load\.(start|end)|"load average \(1/5/15 min\)|load average %s"|[A-Za-z0-9_.-]+/[A-Za-z0-9_.-]+#[0-9]+'

# scan DIR PATH...: the hits under DIR, as path:line: text.
scan() {
    dir=$1
    shift
    (cd "$dir" && for p in "$@"; do
        [ -e "$p" ] || continue
        grep -rnHIE --exclude=history_words.sh --exclude-dir=__pycache__ \
            --exclude-dir=.pytest_cache --exclude='*.egg-info' "$PATTERN" "$p"
    done) | grep -vE "$EXEMPT"
}

# --- the tree (or the paths given)
if [ $# -gt 0 ]; then
    paths="$*"
else
    paths=$TREE
fi
# shellcheck disable=SC2086
scan "$SRC" $paths >"$tmp/hits"
if [ -s "$tmp/hits" ]; then
    bad "history or workplace words ($(wc -l <"$tmp/hits") lines; say what is, or move the figure to docs/benchmarks.md):"
    cut -c1-200 "$tmp/hits" | sed 's/^/    /'
else
    pass "no issue numbers, machine loads, dates of work or session words in: $(echo $paths)"
fi

# --- the patterns on planted lines: each must be found, the exempt ones not.
# The words are assembled here so that this file reads as clean as the rest.
mkdir -p "$tmp/plant/docs" "$tmp/plant/src"
iss="Iss""ue"
{
    echo "fixed in $iss 18"
    echo "see issues 7 and 18"
    echo "as in #12, the"
    echo "(median of 3, lo""ad ~3 on 2 cores)"
    echo "69 s wall at lo""ad 9"
    echo "at a lo""ad of 10"
    echo "runs at lo""ads 7-8"
    echo "lo""ad average 7.5"
    echo "on the develop""ment machine"
    echo "scenes in /wo""rk/wt-pbrt/build"
    echo "second pass (20""26-12-02)"
    echo "results-20""26-11-22.json"
    echo "rendered on 2 Dece""mber 20""26"
    echo "run on Decem""ber 1, 20""26"
    echo "this ses""sion found"
    echo "filed by a ses""sion"
    echo "first run of the ses""sion"
    echo "missed only under other ses""sions' load"
    echo "measured in ses""sion 4"
} >"$tmp/plant/docs/bad.txt"
{
    echo '    color = "#000000"  /* a colour, not a reference */'
    echo '    printf("%#0x", v);'
    echo '@pytest.fixture(scope="ses''sion")'
    echo 'see mmp/pbrt-v4#80 upstream'
    echo 'A first ses''sion: the seed notebook, in a Python ses''sion'
    echo 'loads 64 entries; 1999-12 is not a date of work; issued 3 times'
} >"$tmp/plant/src/good.c"
scan "$tmp/plant" docs src >"$tmp/planted"
want=$(wc -l <"$tmp/plant/docs/bad.txt")
got=$(grep -c '^docs/bad\.txt:' "$tmp/planted")
if [ "$got" -eq "$want" ]; then
    pass "every planted word is found ($got lines)"
else
    bad "the patterns found $got of $want planted lines:"
    sed 's/^/    /' "$tmp/planted"
fi
if grep -q '^src/good\.c:' "$tmp/planted"; then
    bad "the patterns flag lines that are fine:"
    grep '^src/good\.c:' "$tmp/planted" | sed 's/^/    /'
else
    pass "colours, format flags, pytest scopes and external citations are not flagged"
fi

tool_test_end
