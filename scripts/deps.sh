#!/bin/sh
# Install the Debian packages layerlab needs, only those that are missing.
#   sh scripts/deps.sh [lib] [tools] [test] [fuzz] [ci]     (no argument: all)
# Run by `make deps` (all) and `make deps-lib`, `deps-tools`, `deps-test`,
# `deps-fuzz`, `deps-ci` (one group each), and by nothing else: a build,
# a test run, `make install` and `pip install` only check what they need
# (scripts/need.sh) and name the package when it is missing.
# Set LL_SKIP_DEPS=1 to skip it (e.g. on a non-Debian system).
set -eu
[ "${LL_SKIP_DEPS:-0}" = 1 ] && exit 0

# The library: a C99 compiler, OpenBLAS (its OpenMP build) and LAPACKE.
lib_packages="build-essential pkg-config libopenblas-openmp-dev liblapacke-dev"
# The tools' pictures (llplot): cairo, the OpenEXR C API; llbuild-mpi:
# OpenMPI's headers and mpicc.
tools_packages="libopenexr-dev libcairo2-dev libopenmpi-dev"
# The tests: cmocka, abidiff/abidw (tests/abidiff.sh), Python with venv
# for the virtual environment under build/ into which the tests install
# their Python packages (scripts/venv.sh), LLVM 19 for Mitsuba 3.9's LLVM
# variants (Dr.Jit finds it; Debian 12's default LLVM 14/15 aborts them),
# mpirun for llbuild-mpi's tests (tests/llbuild_mpi.sh).
test_packages="libcmocka-dev abigail-tools python3 python3-venv libllvm19 openmpi-bin"
# The fuzzer: clang with its libFuzzer runtime.
fuzz_packages="clang libclang-rt-14-dev"
# CI (.ci/run): the clang build (clang and its OpenMP), the line coverage (gcovr) and the
# CMake build with its consumer project (cmake).
ci_packages="clang libomp-14-dev gcovr cmake"

[ $# -eq 0 ] && set -- lib tools test fuzz ci
packages=""
for need in "$@"; do
    case $need in
        lib) packages="$packages $lib_packages" ;;
        tools) packages="$packages $tools_packages" ;;
        test) packages="$packages $test_packages" ;;
        fuzz) packages="$packages $fuzz_packages" ;;
        ci) packages="$packages $ci_packages" ;;
        *) echo "deps: unknown need '$need' (lib, tools, test, fuzz or ci)" >&2; exit 2 ;;
    esac
done

command -v dpkg-query >/dev/null 2>&1 || {
    echo "deps: not a Debian system; install OpenBLAS, LAPACKE (library), cairo, OpenEXR (tools), cmocka, abigail-tools (tests) yourself and set LL_SKIP_DEPS=1" >&2
    exit 0
}

missing=""
checked=" "
for p in $packages; do
    # A package named by two groups (clang) is looked at once.
    case $checked in *" $p "*) continue ;; esac
    checked="$checked$p "
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
