#!/bin/sh
# Every allocation in src/ goes through the one allocator (src/support/alloc.c:
# ll_malloc, ll_calloc, ll_realloc, ll_free, ll_strdup, ll_getline and the
# checked *_array forms), so that tests/test_alloc_failure.c can fail any of
# them. This fails when a C library call that allocates or frees heap memory
# appears in src/ outside support/alloc.c. Comment lines are skipped.
# Run by `make test`; prints PASS/FAIL lines and "N passed, N failed".
set -u

SRC=$(cd "$(dirname "$0")/.." && pwd)
passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# Calls that allocate (or free) through the C library's heap.
CALLS='malloc|calloc|realloc|reallocarray|free|strdup|strndup|getline|getdelim|asprintf|vasprintf|posix_memalign|aligned_alloc|memalign|valloc|realpath|open_memstream|scandir'
PATTERN="(^|[^A-Za-z0-9_.>])($CALLS)[[:space:]]*\\("

# Lines of stdin (file:line:text) that call one of them, comment lines removed.
raw_calls() {
    grep -E "$PATTERN" | grep -vE '^[^:]*:[0-9]+:[[:space:]]*(/\*|\*|//)'
}

# The pattern itself must catch a raw call and pass the wrappers.
probe=$(printf '%s\n' 'x.c:1:    p = malloc(n);' 'x.c:2:    ll_free(p);' \
                      'x.c:3:    b->data = realloc (b->data, n);' 'x.c:4:     * free(p) in a comment' |
        raw_calls | cut -d: -f2 | tr '\n' ' ')
if [ "$probe" = "1 3 " ]; then
    pass "the check finds raw calls and passes ll_* wrappers and comments"
else
    fail "the check's pattern is broken (matched lines: $probe, expected 1 3)"
fi

found=$(cd "$SRC" && find src -name '*.[ch]' ! -path src/support/alloc.c | sort |
        xargs grep -nE "$PATTERN" /dev/null | raw_calls)
if [ -z "$found" ]; then
    pass "no raw allocation call in src/ outside support/alloc.c"
else
    fail "raw allocation calls in src/ (use ll_malloc/ll_calloc/ll_realloc/ll_free/ll_strdup from support/support.h):"
    printf '%s\n' "$found" | sed 's/^/    /'
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
