#!/bin/sh
# The house plan held by a check: the folders of src/ are layers,
#   support < numerics < layer < words < search < grammar < reader <
#   writer < distribution < material,
# and a file includes only from its own folder or one below
# (`#include "layer/order.h"` in src/grammar/ is fine, in src/numerics/ it
# is not). The reader library's files (READER_SRC, from the Makefile) must
# not reach layer/, words/, search/, grammar/, writer/, distribution/ or
# material/ at all, directly or through a header of theirs: the reader is
# linked without them.
# Each problem is printed as file:line. Then the check is run on a
# temporary bad tree, where it must fail and name the right lines.
# Run by `make test` (with READER_SRC set); prints one line per check and
# "N passed, N failed"; exits non-zero when a check fails.
#   sh tests/layering.sh --tree DIR READER_FILES...   checks DIR only
set -u

ORDER="support numerics layer words search grammar reader writer distribution material"
READER_FORBIDDEN="layer words search grammar writer distribution material"

rank() {
    r=0
    for f in $ORDER; do
        [ "$f" = "$1" ] && { echo $r; return; }
        r=$((r + 1))
    done
    echo -1
}

# The quoted includes with a folder of every file of src/*/:
# "path line folder target" (path relative to the tree).
edges() {
    (cd "$1" && for f in src/*/*.c src/*/*.h; do
        [ -f "$f" ] || continue
        awk -v path="$f" '
            /^[ \t]*#[ \t]*include[ \t]*"[A-Za-z0-9_]+\/[^"]*"/ {
                t = $0; sub(/^[^"]*"/, "", t); sub(/".*$/, "", t)
                dir = t; sub(/\/.*$/, "", dir)
                print path, FNR, dir, t
            }' "$f"
    done)
}

# Print every violation in tree $1, the reader's files being $2...; the
# exit status is the number of violations (0: the plan holds).
check_tree() {
    root=$1
    shift
    edges "$root" > "$scratch/edges"
    count=0
    # Folders of src/ that are not in the order have no place in the plan.
    for d in "$root"/src/*/; do
        d=${d%/}
        d=${d##*/}
        if [ "$(rank "$d")" -lt 0 ]; then
            echo "src/$d/: folder not in the layer order ($ORDER)"
            count=$((count + 1))
        fi
    done
    # No include upward.
    while read -r path line dir target; do
        from=${path#src/}
        from=${from%%/*}
        [ -d "$root/src/$dir" ] || continue # e.g. "layerlab/ll_bsdf.h": public headers
        rf=$(rank "$from")
        rt=$(rank "$dir")
        if [ "$rf" -ge 0 ] && [ "$rt" -gt "$rf" ]; then
            echo "$path:$line: includes \"$target\": $dir/ is above $from/ ($ORDER)"
            count=$((count + 1))
        fi
    done < "$scratch/edges"
    # The reader's files, and every src/ header they reach, stay out of the
    # builder's folders.
    for reader in "$@"; do
        seen=" $reader "
        todo=$reader
        while [ -n "$todo" ]; do
            set -- $todo
            file=$1
            shift
            todo=$*
            while read -r path line dir target; do
                [ "$path" = "$file" ] || continue
                forbidden=0
                for bad in $READER_FORBIDDEN; do
                    [ "$dir" = "$bad" ] && forbidden=1
                done
                if [ $forbidden = 1 ]; then
                    via=
                    [ "$file" != "$reader" ] && via=" (reached from the reader file $reader)"
                    echo "$path:$line: includes \"$target\": the reader library does not link $dir/$via"
                    count=$((count + 1))
                    continue # one line per way in, not the whole of $dir/
                fi
                case $seen in
                    *" src/$target "*) ;;
                    *) if [ -f "$root/src/$target" ]; then
                           seen="$seen src/$target "
                           todo="$todo src/$target"
                       fi ;;
                esac
            done < "$scratch/edges"
        done
    done
    [ $count -gt 255 ] && count=255 # an exit status has 8 bits
    return $count
}

scratch=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-layering.XXXXXX") || exit 1
trap 'rm -rf "$scratch"' EXIT
trap 'exit 1' HUP INT TERM

if [ "${1:-}" = --tree ]; then
    shift
    tree=$1
    shift
    check_tree "$tree" "$@"
    exit $?
fi

SRC=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${READER_SRC:-}" ]; then
    READER_SRC=$(${MAKE:-make} -s --no-print-directory -C "$SRC" print-reader-src 2>/dev/null)
fi
passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }

# ------------------------------------------------------------ the tree itself
# shellcheck disable=SC2086  # READER_SRC is a list of paths
check_tree "$SRC" $READER_SRC > "$scratch/report"
n=$?
if [ -z "$READER_SRC" ]; then
    fail "no reader files (READER_SRC is empty and make print-reader-src gave none)"
elif [ "$n" -eq 0 ]; then
    pass "src/ includes only from its own folder or below ($ORDER), and the $(echo $READER_SRC | wc -w) reader files reach no layer/, words/, search/, grammar/, writer/, distribution/ or material/"
else
    fail "$n layering violation(s):"
    sed 's/^/    /' "$scratch/report"
fi

# ------------------------------------------------- the check of the check
bad=$scratch/bad
mkdir -p "$bad/src/support" "$bad/src/numerics" "$bad/src/layer" "$bad/src/grammar" \
    "$bad/src/reader" "$bad/src/writer" "$bad/src/extras"
printf '#include "support/support.h"\n' > "$bad/src/support/support.h"
printf '#include "support/support.h"\n#include <math.h>\n' > "$bad/src/numerics/fine.c"
printf '/* upward */\n#include "layer/layer.h"\n' > "$bad/src/numerics/upward.c"
printf '#include "numerics/x.h"\n' > "$bad/src/layer/layer.h"
printf '#include "layer/layer.h"\n' > "$bad/src/grammar/grammar.h"
printf '#include "support/support.h"\n\n#include "grammar/grammar.h"\n' > "$bad/src/reader/reader.h"
printf '#include "reader/reader.h"\n#include "writer/writer.h"\n' > "$bad/src/reader/reader.c"
printf '#include "reader/reader.h"\n' > "$bad/src/writer/writer.h"
printf '#include "layer/layer.h"\n#include "writer/writer.h"\n' > "$bad/src/writer/writer.c"
sh "$0" --tree "$bad" src/reader/reader.c > "$scratch/bad.report"
n=$?
ok=1
for want in "src/extras/: folder not in the layer order" \
            'src/numerics/upward.c:2: includes "layer/layer.h"' \
            'src/reader/reader.h:3: includes "grammar/grammar.h": the reader library does not link grammar/ (reached from the reader file src/reader/reader.c)' \
            'src/reader/reader.c:2: includes "writer/writer.h": writer/ is above reader/' \
            'src/reader/reader.c:2: includes "writer/writer.h": the reader library does not link writer/'; do
    grep -qF "$want" "$scratch/bad.report" || ok=0
done
# The writer may include layer/ and reader/, a file may include its own
# folder and below.
if grep -q -e 'writer\.[ch]:' -e 'fine\.c' -e 'grammar\.h:' -e 'layer\.h:' "$scratch/bad.report"; then
    ok=0
fi
if [ "$n" -eq 5 ] && [ "$ok" = 1 ]; then
    pass "on a bad tree the check fails and names the 5 problems (a folder outside the order, an upward include at its line, a reader header reaching grammar/, a reader file including writer/: upward and not linked)"
else
    fail "on a bad tree the check gave status $n (expected 5) or the wrong lines:"
    sed 's/^/    /' "$scratch/bad.report"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
