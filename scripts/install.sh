#!/usr/bin/env bash
# Installs libcoagula for C, C++ and Fortran users:
#   PREFIX/lib/libcoagula.{a,so}, PREFIX/include/coagula.{h,hpp,f90},
#   PREFIX/lib/pkgconfig/coagula.pc
# Usage: scripts/install.sh [PREFIX]   (default /usr/local)
set -euo pipefail
cd "$(dirname "$0")/.."
prefix=${1:-/usr/local}
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
cargo build --release -q -p coagula-ffi
install -d "$prefix/lib/pkgconfig" "$prefix/include"
install -m 644 target/release/libcoagula.a "$prefix/lib/"
install -m 755 target/release/libcoagula.so "$prefix/lib/"
install -m 644 include/coagula.h include/coagula.hpp include/coagula.f90 "$prefix/include/"
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
