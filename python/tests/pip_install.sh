#!/bin/sh
# `pip install ./python` works alone: in a fresh virtual environment, with
# no LAYERLAB_LIBRARY, no PKG_CONFIG_PATH and no `make install`, the package
# builds and bundles liblayerlab (setup.py runs `make lib`) and the metals'
# spectra, imports from the bundled copy, and builds a gold conductor
# (which needs data/ior's Au spectra) into a .bsdf that it opens again.
# LL_TEST_WHEEL=1 also makes a wheel with `python -m build` (sdist, then
# the wheel from the sdist's copy of the C sources: a full compile, so not
# in the default run) and installs it in a second environment.
# The fresh environments are made from the tests' own Python (build/venv,
# scripts/venv.sh) and install from its wheel folder with --no-index
# (PIP_NO_INDEX, PIP_FIND_LINKS): pip's isolated build gets setuptools
# there too, so nothing is downloaded.
# Prints "N passed, N failed"; run by python/tests/run.sh.
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
VENV=${VENV:-$root/build/venv}
export VENV
sh "$root/scripts/venv.sh" base || exit 1
PYTHON=$VENV/bin/python
PIP_NO_INDEX=1
PIP_FIND_LINKS=$VENV/wheels
export PIP_NO_INDEX PIP_FIND_LINKS
passed=0
failed=0
pass() { echo "PASS: $1"; passed=$((passed + 1)); }
fail() { echo "FAIL: $1"; failed=$((failed + 1)); }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/layerlab-pip.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
unset LAYERLAB_LIBRARY PKG_CONFIG_PATH LAYERLAB_IOR_DIR PYTHONPATH

# What the installed package must do, run from a folder outside the tree.
cat > "$tmp/check.py" <<'PY'
import os, sys
import layerlab as ll
from layerlab import _native
want = os.path.join(os.path.dirname(ll.__file__), "_lib", "liblayerlab.so.1")
assert _native.lib.path == want, "loaded %s (%s), not the bundled %s" % (
    _native.lib.path, _native.lib.how, want)
m = ll.Material.parse("conductor eta=Au alpha=0.3")
out = os.path.join(sys.argv[1], "gold.bsdf")
m.build(out, nodes=30, orders=30, channels=3)
b = ll.BSDFStorage(out)
print("ok", _native.lib.how, os.path.getsize(out))
PY

install_and_check() { # label, venv dir, what to pip install
    label=$1
    venv=$2
    shift 2
    if ! "$PYTHON" -m venv "$venv" >"$tmp/venv.log" 2>&1; then
        fail "$label: python -m venv failed"; sed 's/^/    /' "$tmp/venv.log" | tail -5; return
    fi
    if ! "$venv/bin/pip" install -q --disable-pip-version-check "$@" >"$tmp/pip.log" 2>&1; then
        fail "$label: pip install $*"; tail -15 "$tmp/pip.log" | sed 's/^/    /'; return
    fi
    if (cd "$tmp" && "$venv/bin/python" check.py "$tmp") >"$tmp/check.log" 2>&1; then
        pass "$label: imports the bundled library and builds conductor eta=Au ($(tail -n1 "$tmp/check.log"))"
    else
        fail "$label: import and build"; tail -15 "$tmp/check.log" | sed 's/^/    /'
    fi
}

install_and_check "pip install ./python" "$tmp/venv" "$root/python"

if [ "${LL_TEST_WHEEL:-0}" = 1 ]; then
    if "$PYTHON" -m build --outdir "$tmp/dist" "$root/python" >"$tmp/build.log" 2>&1; then
        wheel=$(ls "$tmp"/dist/*.whl)
        pass "python -m build made $(basename "$wheel")"
        install_and_check "the wheel" "$tmp/venv-wheel" "$wheel"
    else
        fail "python -m build"; tail -15 "$tmp/build.log" | sed 's/^/    /'
    fi
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
