#!/usr/bin/env bash
# Installs libcoagula for C, C++ and Fortran users:
#   PREFIX/lib/libcoagula.a, libcoagula.so.VERSION (SONAME libcoagula.so.MAJOR, links
#   libcoagula.so.MAJOR and libcoagula.so), stripped of debug info;
#   PREFIX/include/coagula.{h,hpp,f90},
#   PREFIX/lib/pkgconfig/coagula.pc
# Usage: scripts/install.sh [PREFIX]   (default /usr/local)
set -euo pipefail
cd "$(dirname "$0")/.."
prefix=${1:-/usr/local}
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
cargo build --release -q -p coagula-ffi
# cargo's output directory (CARGO_TARGET_DIR when set, relative to the workspace)
target=${CARGO_TARGET_DIR:-target}
major=${version%%.*}
install -d "$prefix/lib/pkgconfig" "$prefix/include"
install -m 644 "$target/release/libcoagula.a" "$prefix/lib/"
# libcoagula.so.VERSION, with the SONAME link libcoagula.so.MAJOR and the link-time
# name libcoagula.so
install -m 755 "$target/release/libcoagula.so" "$prefix/lib/libcoagula.so.$version"
ln -sf "libcoagula.so.$version" "$prefix/lib/libcoagula.so.$major"
ln -sf "libcoagula.so.$major" "$prefix/lib/libcoagula.so"
# the release profile keeps line tables for profiling; installed libraries do not
if command -v strip >/dev/null; then
    strip --strip-debug "$prefix/lib/libcoagula.a" "$prefix/lib/libcoagula.so.$version"
fi
install -m 644 include/coagula.h include/coagula.hpp include/coagula_types.f90 include/coagula.f90 "$prefix/include/"
cat > "$prefix/lib/pkgconfig/coagula.pc" <<PC
prefix=$prefix
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: coagula
Description: Stochastic particle simulation of coagulation and fragmentation
Version: $version
Libs: -L\${libdir} -lcoagula
Libs.private: -lpthread -ldl -lm
Cflags: -I\${includedir}
PC
echo "installed libcoagula $version into $prefix"
