#!/bin/sh
# Independent references: layerlab's media against S. Prahl's adding-doubling
# (iadpython) and DISORT (PythonicDISORT), run in the tests' own virtual
# environment (scripts/venv.sh installs them there from PyPI, once).
# Run by `make check` with BUILD set.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
case "$BUILD" in
    build-san) echo "reference: skipped under the sanitizer build (Python loads the plain library)"; exit 0 ;;
esac
VENV=${VENV:-$(pwd)/build/venv}
export VENV
sh scripts/venv.sh reference
LAYERLAB_LIBRARY="$BUILD/lib/liblayerlab.so" exec "$VENV/bin/python" tests/reference/media_vs_rt_codes.py
