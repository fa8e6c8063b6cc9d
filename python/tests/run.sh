#!/bin/sh
# The Python package's tests against $BUILD's library, in the tests' own
# virtual environment (scripts/venv.sh: build/venv, never the system's
# site-packages).
#   sh python/tests/run.sh             `make test`: every test but the
#                                      Mitsuba renders, and pip_install.sh
#   sh python/tests/run.sh --mitsuba   `make check`: what needs Mitsuba 3:
#                                      the plugin's renders (test_mitsuba.py)
#                                      our tables against its `measured`
#                                      (test_tables_mitsuba.py), transmissive
#                                      tables against the C reader and
#                                      roughdielectric
#                                      (test_tables_glass_mitsuba.py) and GGX
#                                      files against its roughconductor and
#                                      roughdielectric (test_ggx_mitsuba.py)
# Nothing is downloaded once the environment holds its packages: pip is
# pointed at the environment's wheel folder (PIP_NO_INDEX, PIP_FIND_LINKS),
# for the tests that run `pip install` themselves.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
BUILD=${BUILD:-build}
case $BUILD in /*) build_dir=$BUILD ;; *) build_dir=$root/$BUILD ;; esac
VENV=${VENV:-$root/build/venv}
export VENV

LAYERLAB_LIBRARY=$build_dir/lib/liblayerlab.so
export LAYERLAB_LIBRARY
if [ ! -e "$LAYERLAB_LIBRARY" ]; then
  echo "python/tests/run.sh: $LAYERLAB_LIBRARY does not exist (run make first)" >&2
  exit 1
fi

mitsuba=0
[ "${1:-}" = --mitsuba ] && mitsuba=1
if [ $mitsuba = 1 ]; then
  # Mitsuba 3's LLVM variants need LLVM 19 (scripts/deps.sh test installs libllvm19).
  sh "$root/scripts/venv.sh" base mitsuba
else
  sh "$root/scripts/venv.sh" base
fi
PYTHON=$VENV/bin/python
PIP_NO_INDEX=1
PIP_FIND_LINKS=$VENV/wheels
PIP_DISABLE_PIP_VERSION_CHECK=1
export PIP_NO_INDEX PIP_FIND_LINKS PIP_DISABLE_PIP_VERSION_CHECK

if [ $mitsuba = 0 ]; then
  # pip install ./python in a fresh virtual environment (no LAYERLAB_LIBRARY).
  PYTHON=$PYTHON sh "$here/pip_install.sh"
fi

# Test the source tree, not some installed copy; PNGs go to out/python/.
PYTHONPATH=$root/python${PYTHONPATH:+:$PYTHONPATH}
export PYTHONPATH
cd "$root/python"
if [ $mitsuba = 1 ]; then
  exec "$PYTHON" -m pytest -q -p no:cacheprovider tests/test_mitsuba.py \
    tests/test_tables_mitsuba.py tests/test_tables_glass_mitsuba.py tests/test_ggx_mitsuba.py
fi
exec "$PYTHON" -m pytest -q -p no:cacheprovider --ignore=tests/test_mitsuba.py \
  --ignore=tests/test_tables_mitsuba.py --ignore=tests/test_tables_glass_mitsuba.py \
  --ignore=tests/test_ggx_mitsuba.py tests
