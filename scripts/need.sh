#!/bin/sh
# Checks that what a build step needs is on this machine, and installs
# nothing: a missing piece stops the build with the Debian package that
# provides it and `make deps` (which installs it: scripts/deps.sh).
#   sh scripts/need.sh lib|tools|test|check|coverage|cmake ...
# Run by the Makefile before it compiles (lib: the library, tools: the
# programs, test: the fast tier, check: the slow tier, coverage:
# `make coverage`, cmake: the CMake build). CC, MPICC and PYTHON are
# taken from the environment. Exit status 1 names every missing piece.
set -u
CC=${CC:-cc}
PYTHON=${PYTHON:-python3}
missing=0

miss() { # what, Debian package
    echo "layerlab: $1 is missing (Debian package $2); \`make deps\` installs it" >&2
    missing=1
}

# A header the compiler finds on its own search path.
has_header() {
    # shellcheck disable=SC2086  # CC may carry flags (CC='gcc -m32')
    printf '#include <%s>\n' "$1" | $CC -E -x c - >/dev/null 2>&1
}

# A library the linker finds on its own search path (or through $2's flags).
has_lib() {
    printf 'int main(void) { return 0; }\n' |
        $CC -x c - -o /dev/null $2 -l"$1" >/dev/null 2>&1
}

need_lib() {
    command -v "${CC%% *}" >/dev/null 2>&1 || { miss "the C compiler $CC" build-essential; return; }
    command -v pkg-config >/dev/null 2>&1 || miss pkg-config pkg-config
    has_header cblas.h || miss "OpenBLAS's cblas.h" libopenblas-openmp-dev
    blas_dir=$(pkg-config --variable=libdir openblas 2>/dev/null || true)
    has_lib openblas "${blas_dir:+-L$blas_dir}" || miss "OpenBLAS (-lopenblas)" libopenblas-openmp-dev
    has_header lapacke.h || miss "LAPACKE's lapacke.h" liblapacke-dev
    has_lib lapacke "" || miss "LAPACKE (-llapacke)" liblapacke-dev
}

need_tools() {
    pkg-config --exists cairo 2>/dev/null || miss "cairo (llplot)" libcairo2-dev
    pkg-config --exists OpenEXR 2>/dev/null || miss "the OpenEXR C API (llplot)" libopenexr-dev
}

need_test() {
    has_header cmocka.h || miss "cmocka" libcmocka-dev
    command -v abidiff >/dev/null 2>&1 || miss "abidiff (tests/abidiff.sh)" abigail-tools
    command -v "$PYTHON" >/dev/null 2>&1 || { miss "$PYTHON" python3; return; }
    # python3 -m venv needs ensurepip, which Debian ships apart.
    "$PYTHON" -c 'import venv, ensurepip' >/dev/null 2>&1 ||
        miss "$PYTHON's venv module (ensurepip)" python3-venv
}

need_check() {
    command -v mpirun >/dev/null 2>&1 || miss "mpirun (tests/llbuild_mpi.sh)" openmpi-bin
    command -v "${MPICC:-mpicc}" >/dev/null 2>&1 || miss "mpicc (llbuild-mpi)" libopenmpi-dev
    cxx=${CXX:-c++}
    command -v "${cxx%% *}" >/dev/null 2>&1 || miss "a C++ compiler (tests/pbrt_shim.sh)" build-essential
    # Mitsuba 3.9's LLVM variants load LLVM 19 (Debian 12's default 14 aborts them).
    llvm=
    for f in /usr/lib/*/libLLVM.so.19* /usr/lib/*/libLLVM-19.so* /usr/lib/libLLVM-19.so*; do
        [ -e "$f" ] && llvm=$f
    done
    [ -n "$llvm" ] || miss "LLVM 19 (Mitsuba's LLVM variants)" libllvm19
}

need_coverage() {
    command -v gcovr >/dev/null 2>&1 || miss "gcovr (make coverage)" gcovr
}

need_cmake() {
    command -v cmake >/dev/null 2>&1 || miss "cmake" cmake
}

[ $# -gt 0 ] || set -- lib
for what in "$@"; do
    case $what in
        lib) need_lib ;;
        tools) need_tools ;;
        test) need_test ;;
        check) need_check ;;
        coverage) need_coverage ;;
        cmake) need_cmake ;;
        *) echo "need.sh: unknown need '$what'" >&2; exit 2 ;;
    esac
done
exit $missing
