#!/usr/bin/env bash
# Every function of the C ABI (include/coagula.h) has its C++ binding (coagula.hpp)
# and its Fortran interface (coagula.f90); tests/cpp and tests/fortran call them.
set -euo pipefail
cd "$(dirname "$0")/.."
missing=0
for f in $(grep -o 'coag_[a-z0-9_]*(' include/coagula.h | tr -d '(' | sort -u); do
    for b in include/coagula.hpp include/coagula.f90; do
        if ! grep -qw "$f" "$b"; then
            echo "$b does not bind $f"
            missing=1
        fi
    done
    for t in tests/cpp/test_cpp.cpp tests/fortran/test_fortran.f90; do
        # the C++ test calls the wrapper's methods; the Fortran test the functions
        if [ "$t" = tests/fortran/test_fortran.f90 ] && ! grep -qw "$f" "$t"; then
            echo "$t does not call $f"
            missing=1
        fi
    done
done
n=$(grep -o 'coag_[a-z0-9_]*(' include/coagula.h | sort -u | wc -l)
[ "$missing" = 0 ] && echo "bindings: all $n C functions bound in C++ and Fortran"
exit $missing
