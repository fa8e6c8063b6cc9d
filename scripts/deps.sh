#!/bin/sh
# Install the Debian packages layerlab needs, only those that are missing.
# Run by `make deps` (and so by `make`, `make test` and the README's commands).
# Set LL_SKIP_DEPS=1 to skip the check (e.g. on a non-Debian system).
set -eu
[ "${LL_SKIP_DEPS:-0}" = 1 ] && exit 0

packages="build-essential pkg-config libopenblas-openmp-dev liblapacke-dev libcmocka-dev
libopenexr-dev libcairo2-dev clang"

command -v dpkg-query >/dev/null 2>&1 || {
    echo "deps: not a Debian system; install OpenBLAS, LAPACKE, cmocka, OpenEXR, cairo yourself and set LL_SKIP_DEPS=1" >&2
    exit 0
}

missing=""
for p in $packages; do
    status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    case "$status" in
        *"install ok installed"*) ;;
        *) missing="$missing $p" ;;
    esac
done
[ -z "$missing" ] && exit 0

echo "deps: installing$missing" >&2
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q >&2
# shellcheck disable=SC2086
$sudo apt-get install -y -q --no-install-recommends $missing >&2
