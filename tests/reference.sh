#!/bin/sh
# Independent references: layerlab's media against S. Prahl's adding-doubling
# (iadpython) and DISORT (PythonicDISORT), installed from PyPI when missing.
set -eu
BUILD=${BUILD:-build}
PYTHON=${PYTHON:-python3}
if ! "$PYTHON" -c "import numpy, iadpython, PythonicDISORT" 2>/dev/null; then
    "$PYTHON" -m pip install -q --disable-pip-version-check numpy scipy iadpython PythonicDISORT >&2
fi
case "$BUILD" in
    build-san) echo "reference: skipped under the sanitizer build (Python loads the plain library)"; exit 0 ;;
esac
LAYERLAB_LIBRARY="$BUILD/lib/liblayerlab.so" exec "$PYTHON" tests/reference/media_vs_rt_codes.py
