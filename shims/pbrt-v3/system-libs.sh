#!/bin/sh
# Make a plain (non-recursive) pbrt-v3 checkout build against the system's
# libraries instead of its four git submodules (OpenEXR 2, glog, ptex, zlib),
# e.g. Debian 12's libopenexr-dev (3.1), libimath-dev, libgoogle-glog-dev and
# zlib1g-dev. It edits pbrt-v3's CMakeLists.txt and replaces
# src/textures/ptex.cpp (Ptex is not packaged there) by a file that reports
# "ptex" textures as unavailable. It edits files only and is idempotent.
# The shim itself is apply.sh; `apply.sh --system-libs` runs this first.
# Usage: sh system-libs.sh /path/to/pbrt-v3
set -eu
here=$(cd "$(dirname "$0")" && pwd)
pbrt=${1:?usage: sh system-libs.sh /path/to/pbrt-v3}
cmake=$pbrt/CMakeLists.txt
ptex=$pbrt/src/textures/ptex.cpp
for f in "$cmake" "$ptex" "$pbrt/src/textures/ptex.h"; do
    [ -f "$f" ] || { echo "system-libs.sh: $f not found: is $pbrt a pbrt-v3 checkout?" >&2; exit 1; }
done

# src/textures/ptex.cpp is replaced after CMakeLists.txt is known to be
# pbrt-v3's (copied only when it differs, so that a second run rebuilds nothing).
replace_ptex() {
    cmp -s "$here/system-libs/ptex-unavailable.cpp" "$ptex" ||
        cp "$here/system-libs/ptex-unavailable.cpp" "$ptex"
}

marker='# layerlab system-libs:'
if grep -q "^$marker" "$cmake"; then
    replace_ptex
    echo "system-libs.sh: $cmake already edited"
    exit 0
fi

# The edits, keyed on pbrt-v3's own lines (commit 13d871f and its neighbours):
#  - the four "submodule directory is missing" checks go;
#  - the bodies of the "# OpenEXR", "# glog" and "# ptex" sections (up to the
#    next line of #'s) become FIND_PACKAGE of the installed packages;
#  - in the ALL_PBRT_LIBS list, glog becomes the imported target and
#    Ptex_static goes;
#  - the pbrt library links both imported targets, which gives its sources
#    their include directories (pbrt adds include paths globally, but links
#    only the programs).
# Every edit is counted; a CMakeLists.txt that does not have all of them
# exactly once is left untouched.
awk -v marker="$marker" '
    BEGIN { skip = ""; checks = 0; exr = 0; glog = 0; ptex = 0; libs = 0; inlibs = 0 }
    skip == "check" { if ($0 ~ /^endif\(\)/) skip = ""; next }
    skip == "section" {
        if ($0 !~ /^###/) next
        skip = ""
    }
    /^if\(NOT IS_DIRECTORY "\$\{CMAKE_CURRENT_SOURCE_DIR\}\/src\/ext\// {
        checks++; skip = "check"; next
    }
    $0 == "# OpenEXR" {
        exr++; print; skip = "section"
        print marker " Debian 12 libopenexr-dev 3.1 (with libimath-dev)"
        print "FIND_PACKAGE ( OpenEXR REQUIRED )"
        print "SET ( OPENEXR_LIBS OpenEXR::OpenEXR )"
        print ""
        next
    }
    $0 == "# glog" {
        glog++; print; skip = "section"
        print marker " Debian 12 libgoogle-glog-dev"
        print "FIND_PACKAGE ( glog REQUIRED )"
        print ""
        next
    }
    $0 == "# ptex" {
        ptex++; print; skip = "section"
        print marker " no Ptex library; src/textures/ptex.cpp reports \"ptex\" textures"
        print "# as unavailable"
        print ""
        next
    }
    $0 == "SET(ALL_PBRT_LIBS" { inlibs = 1 }
    inlibs && $0 == ")" { inlibs = 0 }
    inlibs && $0 == "  glog" { libs++; print "  glog::glog"; next }
    inlibs && $0 == "  Ptex_static" { libs++; next }
    { print }
    END {
        print ""
        print marker " the pbrt library compiles with the packages"
        print "# include directories (pbrt adds include paths globally, links only programs)"
        print "TARGET_LINK_LIBRARIES ( pbrt OpenEXR::OpenEXR glog::glog )"
        if (checks != 4 || exr != 1 || glog != 1 || ptex != 1 || libs != 2) {
            printf "found %d of 4 submodule checks, %d/%d/%d of the OpenEXR/glog/ptex sections, %d of 2 library entries\n", \
                checks, exr, glog, ptex, libs > "/dev/stderr"
            exit 1
        }
    }' "$cmake" > "$cmake.layerlab-tmp" || {
    rm -f "$cmake.layerlab-tmp"
    echo "system-libs.sh: $cmake is not the CMakeLists.txt this script knows; edit it by hand (README.md)" >&2
    exit 1
}
mv "$cmake.layerlab-tmp" "$cmake"
replace_ptex
echo "system-libs.sh: $pbrt now builds against the system's OpenEXR, Imath, glog and zlib"
