#!/bin/sh
# The API reference is current: docs/api.md is what scripts/api_doc.py
# makes from the comments of include/layerlab/*.h now, so a changed
# declaration or comment that was not followed by `make api-doc` fails
# here, with the difference and the command that fixes it. The script
# itself fails on an exported function without a comment. And every
# function the version scripts export (src/*.map) is on the page: a
# function exported but declared in no public header would be missing.
# Run by `make test`; prints one line per check and "N passed, N failed";
# exits non-zero when a check fails. Needs python3 (standard library only).
set -u

. "$(dirname "$0")/lib/tool_test.sh"
SRC=$(cd "$(dirname "$0")/.." && pwd)
cd "$SRC" || exit 1

tool_test_begin layerlab-api-doc
trap 'exit 1' HUP INT TERM

# --- the page regenerated into a temporary file, compared
if ! python3 scripts/api_doc.py -o "$tmp/generated" 2>"$tmp/err"; then
    bad "scripts/api_doc.py failed:"
    sed 's/^/    /' "$tmp/err"
elif [ ! -f docs/api.md ]; then
    bad "docs/api.md is missing: run \`make api-doc\` and commit it"
elif cmp -s "$tmp/generated" docs/api.md; then
    pass "docs/api.md is current with the headers"
else
    bad "docs/api.md is not current with the headers: run \`make api-doc\` and commit it"
    diff -u docs/api.md "$tmp/generated" | head -n 40 | sed 's/^/    /'
fi

# --- every exported function is on the page
missing=""
for f in $(sed -n 's/^[[:space:]]*\(ll_[a-z0-9_]*\);[[:space:]]*$/\1/p' src/*.map | sort -u); do
    grep -q "<a id=\"$f\"></a>" "$tmp/generated" 2>/dev/null || missing="$missing $f"
done
if [ -z "$missing" ]; then
    pass "every function of src/*.map is documented on the page"
else
    bad "exported but not declared with a comment in a public header:$missing"
fi

tool_test_end
