#!/bin/sh
# Install the Debian packages layerlab needs, only those that are missing.
#   sh scripts/deps.sh [lib] [tools] [test] [fuzz]     (no argument: all four)
# Run by the Makefile for what each target builds: `make lib` installs the
# library's needs only (no cairo, OpenEXR or clang), `make` the tools' too,
# `make test` the tests', `make fuzz` the fuzzer's; `make deps` all of them.
# Set LL_SKIP_DEPS=1 to skip the check (e.g. on a non-Debian system).
set -eu
[ "${LL_SKIP_DEPS:-0}" = 1 ] && exit 0

# The library: a C99 compiler, OpenBLAS (its OpenMP build) and LAPACKE.
lib_packages="build-essential pkg-config libopenblas-openmp-dev liblapacke-dev"
# The tools' pictures (llplot): cairo, the OpenEXR C API; llbuild-mpi:
# OpenMPI's headers and mpicc.
tools_packages="libopenexr-dev libcairo2-dev libopenmpi-dev"
# The tests: cmocka, abidiff/abidw (tests/abidiff.sh), Python with pip for
# the Python package and the cross-checks (they pip-install the rest),
# venv for python/tests/pip_install.sh, LLVM 19 for Mitsuba 3.9's LLVM
# variants (Dr.Jit finds it; Debian 12's default LLVM 14/15 aborts them);
# mpirun for llbuild-mpi's tests (tests/llbuild_mpi.sh).
test_packages="libcmocka-dev abigail-tools python3 python3-pip python3-venv libllvm19 openmpi-bin"
# The fuzzer: clang with its libFuzzer runtime.
fuzz_packages="clang libclang-rt-14-dev"

[ $# -eq 0 ] && set -- lib tools test fuzz
packages=""
for need in "$@"; do
    case $need in
        lib) packages="$packages $lib_packages" ;;
        tools) packages="$packages $tools_packages" ;;
        test) packages="$packages $test_packages" ;;
        fuzz) packages="$packages $fuzz_packages" ;;
        *) echo "deps: unknown need '$need' (lib, tools, test or fuzz)" >&2; exit 2 ;;
    esac
done

command -v dpkg-query >/dev/null 2>&1 || {
    echo "deps: not a Debian system; install OpenBLAS, LAPACKE (library), cairo, OpenEXR (tools), cmocka, abigail-tools (tests) yourself and set LL_SKIP_DEPS=1" >&2
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
