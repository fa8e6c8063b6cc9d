#!/bin/sh
# The Python package's tests, run by `make test` (target test-python) with
# BUILD=<build dir>. Tests the package in python/ against $BUILD's library;
# installs numpy, matplotlib, pytest and mitsuba quietly when they are missing.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
BUILD=${BUILD:-build}
case $BUILD in /*) build_dir=$BUILD ;; *) build_dir=$root/$BUILD ;; esac
PYTHON=${PYTHON:-python3}
if ! command -v "$PYTHON" >/dev/null 2>&1; then
  echo "python/tests/run.sh: $PYTHON not found; the Python package needs Python 3.8 or later" >&2
  exit 1
fi

LAYERLAB_LIBRARY=$build_dir/lib/liblayerlab.so
export LAYERLAB_LIBRARY
if [ ! -e "$LAYERLAB_LIBRARY" ]; then
  echo "python/tests/run.sh: $LAYERLAB_LIBRARY does not exist (run make first)" >&2
  exit 1
fi

missing=
for module in numpy matplotlib pytest; do
  "$PYTHON" -c "import $module" 2>/dev/null || missing="$missing $module"
done
if [ -n "$missing" ]; then
  echo "python/tests/run.sh: installing$missing"
  "$PYTHON" -m pip install -q --disable-pip-version-check $missing
fi

# Mitsuba 3 for the plugin's tests (test_mitsuba.py); its LLVM variants need
# LLVM 19 (scripts/deps.sh test installs libllvm19).
if ! "$PYTHON" -c "import mitsuba" 2>/dev/null; then
  echo "python/tests/run.sh: installing mitsuba==3.9.1"
  "$PYTHON" -m pip install -q --disable-pip-version-check "mitsuba==3.9.1"
fi

# pip install ./python in a fresh virtual environment (no LAYERLAB_LIBRARY).
sh "$here/pip_install.sh"

# Test the source tree, not some installed copy; PNGs go to out/python/.
PYTHONPATH=$root/python${PYTHONPATH:+:$PYTHONPATH}
export PYTHONPATH
cd "$root/python"
exec "$PYTHON" -m pytest -q -p no:cacheprovider tests
