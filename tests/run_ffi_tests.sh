#!/usr/bin/env bash
# Builds libcoagula and runs the C, C++ and Fortran clients against it.
# C programs: -Wall -Wextra -Wpedantic -Werror, AddressSanitizer + UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

cargo build --release -q -p coagula-ffi
# cargo's output directory (CARGO_TARGET_DIR when set; a relative one is relative to
# the workspace root)
target=${CARGO_TARGET_DIR:-target}
case $target in /*) ;; *) target="$root/$target" ;; esac
lib="$target/release/libcoagula.a"
libs="-lpthread -ldl -lm"
san="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

for t in test_schemes test_misuse test_regressions test_hostile test_langevin test_thermal test_dsmc test_cells; do
    gcc -std=c11 -O1 -g -Wall -Wextra -Wpedantic -Werror $san -I"$root/include" \
        "tests/c/$t.c" "$lib" $libs -o "$out/$t"
    "$out/$t"
done

# the many-cells host example (OpenMP), small: it runs and its cells evolve
gcc -std=c11 -O2 -fopenmp -Wall -Wextra -Werror -I"$root/include" examples/c/cells.c "$lib" $libs \
    -o "$out/cells"
"$out/cells" 500 1000 2 | tail -n 2

g++ -std=c++17 -O1 -g -Wall -Wextra -Wpedantic -Werror $san -I"$root/include" \
    tests/cpp/test_cpp.cpp "$lib" $libs -o "$out/test_cpp"
"$out/test_cpp"

gfortran -std=f2008 -O1 -g -Wall -Wextra -Werror -fcheck=all -J "$out" \
    include/coagula.f90 tests/fortran/test_fortran.f90 "$lib" $libs -o "$out/test_fortran"
"$out/test_fortran"

# The C tests again without sanitizers, under valgrind's memcheck (leaks, uninitialised
# reads, invalid accesses the sanitizers' instrumentation does not see in the Rust
# library); test_hostile in its quick mode (smaller work limits, fewer crafted
# checkpoints: the same checks).
if [ "${COAG_VALGRIND:-0}" = 1 ]; then
    for t in test_schemes test_misuse test_regressions test_hostile test_langevin test_thermal test_dsmc test_cells; do
        gcc -std=c11 -O1 -g -Wall -Wextra -Wpedantic -Werror -I"$root/include" \
            "tests/c/$t.c" "$lib" $libs -o "$out/vg_$t"
        COAG_TEST_QUICK=1 valgrind -q --error-exitcode=99 --leak-check=full \
            --errors-for-leak-kinds=definite,indirect "$out/vg_$t" | tail -n 1
    done
fi
