#!/bin/sh
# The tests' own Python: a virtual environment at $VENV (default
# build/venv of this checkout, whatever BUILD is), made with
# `$PYTHON -m venv`, never the system's site-packages (a stock Debian's
# /usr/bin/python3 is "externally managed": its pip refuses to install).
#   sh scripts/venv.sh SET...      prints nothing but pip's errors
# where each SET is the packages of one group of tests:
#   base       numpy, matplotlib, pytest, setuptools, build: the Python
#              package's tests and `pip install ./python` (or `python -m
#              build`) in a fresh environment (python/tests/run.sh,
#              pip_install.sh)
#   reference  numpy, scipy, iadpython, PythonicDISORT: tests/reference.sh
#   mitsuba    mitsuba 3.9.1: the Mitsuba plugin's renders (make check)
# Every package is first made a wheel in $VENV/wheels and installed from
# there with --no-index, and a set is recorded in $VENV/.stamp-SET with
# its list: a second run with the same lists downloads nothing. The other
# fresh environments the tests make install from the same folder
# (PIP_NO_INDEX=1 PIP_FIND_LINKS=$VENV/wheels), so they download nothing
# either. The Makefile runs it before the tests; the test scripts run it
# too, for when they are run by hand (a set already recorded costs nothing).
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
VENV=${VENV:-$root/build/venv}
PYTHON=${PYTHON:-python3}
wheels=$VENV/wheels

packages_of() {
    case $1 in
        base) echo "numpy matplotlib pytest setuptools>=70.1 build" ;;
        reference) echo "numpy scipy iadpython PythonicDISORT" ;;
        mitsuba) echo "mitsuba==3.9.1" ;;
        *) echo "venv.sh: unknown set '$1' (base, reference, mitsuba)" >&2; exit 2 ;;
    esac
}

# A venv whose interpreter went away (the Python it was made from was
# removed or upgraded) is made again.
if [ -x "$VENV/bin/python" ] && ! "$VENV/bin/python" -c '' >/dev/null 2>&1; then
    rm -rf "$VENV"
fi
if [ ! -x "$VENV/bin/python" ]; then
    if ! command -v "$PYTHON" >/dev/null 2>&1; then
        echo "venv.sh: $PYTHON is missing (Debian package python3); \`make deps\` installs it" >&2
        exit 1
    fi
    echo "venv.sh: making the tests' Python environment $VENV from $(command -v "$PYTHON")"
    if ! "$PYTHON" -m venv "$VENV"; then
        rm -rf "$VENV"
        echo "venv.sh: $PYTHON -m venv failed (Debian package python3-venv); \`make deps\` installs it" >&2
        exit 1
    fi
fi

pip() {
    "$VENV/bin/python" -m pip --disable-pip-version-check -q "$@"
}

for set in "$@"; do
    want=$(packages_of "$set")
    stamp=$VENV/.stamp-$set
    if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
        continue
    fi
    echo "venv.sh: installing $want into $VENV"
    mkdir -p "$wheels"
    # shellcheck disable=SC2086  # $want is a list of requirements
    pip wheel --wheel-dir "$wheels" $want
    # shellcheck disable=SC2086
    pip install --no-index --find-links "$wheels" $want
    echo "$want" > "$stamp"
done
