#!/bin/sh
# docs/material-language.md shows what `llbuild --help`, `llconvert --help`
# and `llplot --help` print, word for word: each tool's text sits in the
# fenced block after a line `<!-- help: TOOL -->`. This fails when a tool's
# --help and its block differ (and prints the difference, so the block can be
# pasted anew), when a block is missing, and when the page's prose names an
# option (--word) that none of the three tools accepts.
# Run by `make test` with BUILD set; prints PASS/FAIL lines and
# "N passed, N failed".
set -u
BUILD=${BUILD:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
case "$BUILD" in
    /*) build="$BUILD" ;;
    *) build="$root/$BUILD" ;;
esac
page="$root/docs/"material-language.md

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

work=$(mktemp -d "${TMPDIR:-/tmp}/tool-help.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT
trap 'exit 1' HUP INT TERM

: >"$work/all-help"
for tool in llbuild llconvert llplot; do
    if ! "$build/bin/$tool" --help >"$work/$tool.help" 2>"$work/$tool.err"; then
        fail "$tool --help fails (is $build/bin/$tool built?)"
        continue
    fi
    cat "$work/$tool.help" >>"$work/all-help"
    # The block: after the marker, from the line after its opening fence to
    # the closing fence.
    awk -v marker="<!-- help: $tool -->" '
        $0 == marker { found = 1; next }
        found == 1 && /^```/ { found = 2; next }
        found == 2 && /^```$/ { exit }
        found == 2 { print }' "$page" >"$work/$tool.page"
    if ! grep -q "<!-- help: $tool -->" "$page"; then
        fail "docs/material-language.md has no block for $tool --help"
    elif cmp -s "$work/$tool.help" "$work/$tool.page"; then
        pass "docs/material-language.md shows $tool --help as it prints ($(wc -l <"$work/$tool.help") lines)"
    else
        fail "docs/material-language.md differs from $tool --help (- page, + tool):"
        diff "$work/$tool.page" "$work/$tool.help" | sed 's/^/    /' | head -40
    fi
done

# Options named in the prose, outside the help blocks.
grep -oE -- '--[a-z][a-z-]*' "$work/all-help" | sort -u >"$work/known"
awk '/^<!-- help: / { skip = 1 } skip && /^```$/ && ++fences == 2 { skip = 0; fences = 0; next }
     !skip' "$page" | grep -oE -- '(^|[^A-Za-z0-9-])--[a-z][a-z-]*' |
    sed 's/^[^-]*//' | sort -u >"$work/named"
unknown=$(comm -23 "$work/named" "$work/known" | tr '\n' ' ')
if [ -z "$unknown" ]; then
    pass "every option the page names ($(wc -l <"$work/named")) is in a tool's --help"
else
    fail "the page names options no tool accepts: $unknown"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
