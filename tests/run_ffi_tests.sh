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

# the header alone under C89 and C++ (no `//` comments, extern "C" guards), twice
printf '#include "coagula.h"\n#include "coagula.h"\nint main(void) { return 0; }\n' > "$out/header.c"
gcc -std=c89 -pedantic -Wall -Wextra -Werror -I"$root/include" -c "$out/header.c" -o "$out/header89.o"
g++ -x c++ -std=c++11 -Wall -Wextra -Werror -I"$root/include" -c "$out/header.c" -o "$out/headerxx.o"

# the C tests, longest first (the runs go two at a time: see run_all)
c_tests="test_hostile test_dsmc test_temperature test_review test_schemes test_langevin test_processes test_classes test_misuse test_regressions test_cells"

jobs_max=${COAG_TEST_JOBS:-2}
case $jobs_max in
    '' | *[!0-9]* | 0) echo "COAG_TEST_JOBS=$jobs_max: not a positive integer, using 2"; jobs_max=2 ;;
esac

# run_all PREFIX COMMAND...: runs COMMAND $out/PREFIX$t for every C test, jobs_max at a
# time, each one's output kept and printed in the list's order (all of it on failure);
# exits 1 when any failed
run_all() {
    local prefix=$1
    shift
    for t in $c_tests; do
        while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
        (
            rc=0
            "$@" "$out/$prefix$t" || rc=$?
            echo "$rc" > "$out/$prefix$t.rc"
        ) > "$out/$prefix$t.log" 2>&1 &
    done
    wait
    local failed=""
    for t in $c_tests; do
        local rc
        rc=$(cat "$out/$prefix$t.rc" 2>/dev/null || echo "no status")
        if [ "$rc" = 0 ]; then
            tail -n 1 "$out/$prefix$t.log"
        else
            cat "$out/$prefix$t.log"
            echo "$prefix$t: exit status $rc"
            failed="$failed $t"
        fi
    done
    if [ -n "$failed" ]; then
        echo "failed:$failed"
        exit 1
    fi
}

# build_all PREFIX FLAGS...: compiles every C test to $out/PREFIX$t, jobs_max at a time
build_all() {
    local prefix=$1
    shift
    for t in $c_tests; do
        while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
        gcc -std=c11 -O1 -g -Wall -Wextra -Wpedantic -Werror "$@" -I"$root/include" \
            "tests/c/$t.c" "$lib" $libs -o "$out/$prefix$t" &
    done
    wait
    for t in $c_tests; do
        [ -x "$out/$prefix$t" ] || { echo "$prefix$t did not compile"; exit 1; }
    done
}

# the C++ client compiles beside the C tests (alone, its g++ run was 12 s of CI)
(
    rc=0
    g++ -std=c++17 -O1 -g -Wall -Wextra -Wpedantic -Werror $san -I"$root/include" \
        tests/cpp/test_cpp.cpp "$lib" $libs -o "$out/test_cpp" || rc=$?
    echo "$rc" > "$out/test_cpp.rc"
) &
build_all "" $san
run_all ""

# the many-cells host example (OpenMP), small: it runs and its cells evolve
gcc -std=c11 -O2 -fopenmp -Wall -Wextra -Werror -I"$root/include" examples/c/cells.c "$lib" $libs \
    -o "$out/cells"
"$out/cells" 500 1000 2 | tail -n 2

# the worked plug-flow host: its books balance exactly and its cells meet core's
# sectional reference (exit status 0)
gcc -std=c11 -O2 -Wall -Wextra -Wpedantic -Werror -I"$root/include" examples/c/plug_flow.c "$lib" $libs \
    -o "$out/plug_flow"
"$out/plug_flow" | tail -n 8

[ "$(cat "$out/test_cpp.rc" 2>/dev/null)" = 0 ] || { echo "test_cpp did not compile"; exit 1; }
"$out/test_cpp"

gfortran -std=f2008 -O1 -g -Wall -Wextra -Werror -fcheck=all -J "$out" \
    include/coagula_types.f90 include/coagula.f90 tests/fortran/test_callbacks.f90 tests/fortran/test_fortran.f90 "$lib" $libs -o "$out/test_fortran"
"$out/test_fortran"

# The C tests again without sanitizers, under valgrind's memcheck (leaks, uninitialised
# reads, invalid accesses the sanitizers' instrumentation does not see in the Rust
# library), in their quick mode (COAG_TEST_QUICK: fewer particles and replicas in the
# statistical checks, at the thresholds of their degrees of freedom; smaller work limits
# and fewer crafted checkpoints in test_hostile: the same code paths). Two at a time
# (COAG_TEST_JOBS): memcheck runs one thread per program.
if [ "${COAG_VALGRIND:-0}" = 1 ]; then
    build_all vg_
    export COAG_TEST_QUICK=1
    run_all vg_ valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect
fi
