#!/usr/bin/env bash
# Installs coray's C library into PREFIX (default /usr/local):
#   include/coray.h, include/coray.hpp (the C++17 layer)
#   lib/libcoray.a, lib/libcoray.so.X.Y.Z (SONAME libcoray.so.X) and links
#   lib/pkgconfig/coray.pc            pkg-config --cflags --libs coray
#   lib/cmake/coray/corayConfig.cmake find_package(coray): coray::coray, coray::coray_static
# A script rather than cargo-c: it needs nothing beyond cargo and a shell
# (cargo-c is not packaged by Debian and would be built from source on
# every fresh machine), and what it installs fits in this page.
set -euo pipefail
prefix="${1:-/usr/local}"
case "$prefix" in /*) ;; *) prefix="$PWD/$prefix" ;; esac
cd "$(dirname "$0")/.."

version=$(sed -n '/^\[workspace.package\]/,/^\[/s/^version = "\(.*\)"/\1/p' Cargo.toml)
major=${version%%.*}
target_dir="${CARGO_TARGET_DIR:-$PWD/target}"
cargo build --release --quiet -p coray-ffi --lib
out="$target_dir/release"

libdir="$prefix/lib"
incdir="$prefix/include"
install -d "$libdir/pkgconfig" "$libdir/cmake/coray" "$incdir"
install -m 644 include/coray.h "$incdir/coray.h"
install -m 644 include/coray.hpp "$incdir/coray.hpp"
# The static library exports coray's names only: its objects are linked
# into one relocatable object whose every other global symbol (Rust's std,
# compiler builtins) is made local, so that it cannot clash with another
# Rust static library in the same program. The LLVM bitcode sections are
# dropped (no linker reads them; nm would try to).
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
nm -g --defined-only "$out/libcoray_ffi.a" 2>/dev/null \
    | awk 'NF == 3 && $3 ~ /^coray_/ { print $3 }' | sort -u > "$work/keep"
ld -r --whole-archive "$out/libcoray_ffi.a" -o "$work/coray.o"
objcopy --remove-section=.llvmbc --remove-section=.llvmcmd \
    --keep-global-symbols="$work/keep" --strip-debug "$work/coray.o"
rm -f "$libdir/libcoray.a"
ar rcs "$libdir/libcoray.a" "$work/coray.o"
chmod 644 "$libdir/libcoray.a"
install -m 755 "$out/libcoray_ffi.so" "$libdir/libcoray.so.$version"
ln -sf "libcoray.so.$version" "$libdir/libcoray.so.$major"
ln -sf "libcoray.so.$major" "$libdir/libcoray.so"

cat > "$libdir/pkgconfig/coray.pc" <<PC
prefix=$prefix
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: coray
Description: Allocation-free ray shooting: kd-trees, LCTS, hierarchies, projection hierarchies
Version: $version
Libs: -L\${libdir} -lcoray
Libs.private: -lpthread -ldl -lm
Cflags: -I\${includedir}
PC

cat > "$libdir/cmake/coray/corayConfig.cmake" <<CMAKE
# coray $version: find_package(coray) gives coray::coray (the shared
# library) and coray::coray_static (the static one, with its system libraries).
get_filename_component(_coray_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET coray::coray)
  add_library(coray::coray SHARED IMPORTED)
  set_target_properties(coray::coray PROPERTIES
    IMPORTED_LOCATION "\${_coray_prefix}/lib/libcoray.so.$version"
    IMPORTED_SONAME "libcoray.so.$major"
    INTERFACE_INCLUDE_DIRECTORIES "\${_coray_prefix}/include")
  add_library(coray::coray_static STATIC IMPORTED)
  set_target_properties(coray::coray_static PROPERTIES
    IMPORTED_LOCATION "\${_coray_prefix}/lib/libcoray.a"
    INTERFACE_INCLUDE_DIRECTORIES "\${_coray_prefix}/include"
    INTERFACE_LINK_LIBRARIES "pthread;dl;m")
endif()
unset(_coray_prefix)
CMAKE

cat > "$libdir/cmake/coray/corayConfigVersion.cmake" <<CMAKE
# Compatible within one major version, as the C ABI is (docs/c-api.md).
set(PACKAGE_VERSION "$version")
if(PACKAGE_FIND_VERSION_MAJOR STREQUAL "$major" AND NOT PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION)
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
  if(PACKAGE_FIND_VERSION STREQUAL PACKAGE_VERSION)
    set(PACKAGE_VERSION_EXACT TRUE)
  endif()
else()
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
endif()
CMAKE

echo "coray $version installed in $prefix"
