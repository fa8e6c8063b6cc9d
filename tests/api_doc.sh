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

SRC=$(cd "$(dirname "$0")/.." && pwd)
cd "$SRC" || exit 1

passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-api-doc.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM

# --- the page regenerated into a temporary file, compared
if ! python3 scripts/api_doc.py -o "$tmp/generated" 2>"$tmp/err"; then
    fail "scripts/api_doc.py failed:"
    sed 's/^/    /' "$tmp/err"
elif [ ! -f docs/api.md ]; then
    fail "docs/api.md is missing: run \`make api-doc\` and commit it"
elif cmp -s "$tmp/generated" docs/api.md; then
    pass "docs/api.md is current with the headers"
else
    fail "docs/api.md is not current with the headers: run \`make api-doc\` and commit it"
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
    fail "exported but not declared with a comment in a public header:$missing"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
