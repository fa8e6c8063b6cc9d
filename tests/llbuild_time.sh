#!/bin/sh
# llbuild --dry-run's time against the build's: for each example the README
# shows, the dry run's CPU figure (the model's building plus the choice of
# the resolution as it ran) is within 2x of the CPU the build then takes,
# both on one thread and with no remembered choice (each searches). Slow
# tier (`make check`): it builds the three examples.
# Run from the checkout with BUILD set.
set -u
BUILD=${BUILD:-build}
llbuild="$BUILD/bin/llbuild"
. "$(dirname "$0")/lib/tool_test.sh"
# Hermetic: nothing in the user's cache (and --no-cache below anyway).
tool_test_begin llbuild_time

if [ ! -x "$llbuild" ] || [ ! -x /usr/bin/time ]; then
    echo "llbuild_time.sh: needs $llbuild and /usr/bin/time"
    echo "0 passed, 1 failed"
    exit 1
fi

for ex in coated-gold plastic coated-gold-with-scatmedium; do
    if ! "$llbuild" --threads 1 --no-cache --dry-run "examples/$ex.layers" >"$tmp/dry" 2>&1; then
        bad "$ex: --dry-run failed"; cat "$tmp/dry"; continue
    fi
    estimate=$(sed -n 's/^time .* s on 1 thread, \([0-9.]*\) s of CPU: .*/\1/p' "$tmp/dry")
    if ! /usr/bin/time -f '%U %S' -o "$tmp/cpu" "$llbuild" --threads 1 --no-cache --quiet \
            "examples/$ex.layers" -o "$tmp/$ex.bsdf" 2>"$tmp/err"; then
        bad "$ex: the build failed"; cat "$tmp/err"; continue
    fi
    cpu=$(awk '{ print $1 + $2 }' "$tmp/cpu")
    if [ -n "$estimate" ] &&
       awk -v e="$estimate" -v c="$cpu" 'BEGIN { exit !(e <= 2 * c && c <= 2 * e) }'; then
        ok
        echo "PASS: $ex: --dry-run says $estimate s of CPU, the build took $cpu s"
    else
        bad "$ex: --dry-run says '$estimate' s of CPU, the build took $cpu s (not within 2x)"
        grep '^time' "$tmp/dry"
    fi
done
tool_test_end llbuild_time.sh
