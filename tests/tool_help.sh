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

. "$(dirname "$0")/lib/tool_test.sh"
tool_test_begin tool-help
trap 'exit 1' HUP INT TERM

: >"$tmp/all-help"
for tool in llbuild llconvert llplot; do
    if ! "$build/bin/$tool" --help >"$tmp/$tool.help" 2>"$tmp/$tool.err"; then
        bad "$tool --help fails (is $build/bin/$tool built?)"
        continue
    fi
    cat "$tmp/$tool.help" >>"$tmp/all-help"
    # The block: after the marker, from the line after its opening fence to
    # the closing fence.
    awk -v marker="<!-- help: $tool -->" '
        $0 == marker { found = 1; next }
        found == 1 && /^```/ { found = 2; next }
        found == 2 && /^```$/ { exit }
        found == 2 { print }' "$page" >"$tmp/$tool.page"
    if ! grep -q "<!-- help: $tool -->" "$page"; then
        bad "docs/material-language.md has no block for $tool --help"
    elif cmp -s "$tmp/$tool.help" "$tmp/$tool.page"; then
        pass "docs/material-language.md shows $tool --help as it prints ($(wc -l <"$tmp/$tool.help") lines)"
    else
        bad "docs/material-language.md differs from $tool --help (- page, + tool):"
        diff "$tmp/$tool.page" "$tmp/$tool.help" | sed 's/^/    /' | head -40
    fi
done

# Options named in the prose, outside the help blocks.
grep -oE -- '--[a-z][a-z-]*' "$tmp/all-help" | sort -u >"$tmp/known"
awk '/^<!-- help: / { skip = 1 } skip && /^```$/ && ++fences == 2 { skip = 0; fences = 0; next }
     !skip' "$page" | grep -oE -- '(^|[^A-Za-z0-9-])--[a-z][a-z-]*' |
    sed 's/^[^-]*//' | sort -u >"$tmp/named"
unknown=$(comm -23 "$tmp/named" "$tmp/known" | tr '\n' ' ')
if [ -z "$unknown" ]; then
    pass "every option the page names ($(wc -l <"$tmp/named")) is in a tool's --help"
else
    bad "the page names options no tool accepts: $unknown"
fi

tool_test_end
