#!/usr/bin/env bash
# Every test of the repository: the Rust workspace's (`cargo test --workspace`), then
# the Python package's (built into a scratch venv under target/, with pytest).
# The README's test command; .ci/run calls it. Needs cargo and python3 (>= 3.9, with
# venv and pip); the pip packages (maturin, pytest, numpy, xarray, scipy) are
# installed into the venv from PyPI.
set -euo pipefail
cd "$(dirname "$0")/.."
# cargo's output directory (CARGO_TARGET_DIR when set, relative to the workspace)
target=${CARGO_TARGET_DIR:-target}
case $target in /*) ;; *) target="$PWD/$target" ;; esac

# (the Python crate has no Rust tests: it is built below as the wheel a user installs,
# not a second time in the test profile; coagula-mpi has none and needs an MPI
# library, tests/mpi/run.sh runs it; the examples are not tests — clippy checks that
# they build — and compiling them was 35 of the test build's 695 unit-seconds).
# `--tests` takes the targets whose manifest sets `test = true`: not libcoagula's
# (coagula-ffi's lib has no unit tests; `--lib` would compile it a second time with
# cfg(test) for nothing, 54 of the build's unit-seconds on 2026-12-07).
cargo_test=(cargo test --workspace --exclude coagula-python --exclude coagula-mpi)
"${cargo_test[@]}" --tests --no-run
"${cargo_test[@]}" --doc

# The C library the Python tests compare bits with (the test profile's build, which
# `cargo test` has compiled most of).
cargo build -q -p coagula-ffi --profile test
export COAGULA_LIB="$target/debug/libcoagula.so"

# The Python package is built while the Rust tests run: the release build of the wheel
# compiles one large crate at a time, and the tests leave a core idle while one long
# test finishes (side by side: docs/results/ci-time.md). Cargo locks each profile's
# output directory, so the wheel's release build does not wait for the tests' run.
venv=target/pyvenv
wheel_log="$target/wheel-build.log"
(
    if [ ! -x "$venv/bin/python" ]; then
        python3 -m venv "$venv"
    fi
    "$venv/bin/python" -m pip install -q --disable-pip-version-check \
        'maturin>=1.9,<2' 'pytest>=7' 'numpy>=1.21' 'xarray>=2022.3' scipy
    # The package as a user installs it: a release wheel (without the command line's
    # plotting and argument parsing, which the package does not link)
    rm -rf target/wheels
    "$venv/bin/maturin" build -q --release -m python/Cargo.toml -o target/wheels \
        --interpreter "$venv/bin/python"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check --force-reinstall \
        --no-deps target/wheels/coagula-*.whl
) > "$wheel_log" 2>&1 &
wheel=$!

# (every test program, even after one fails; nothing compiles here any more)
tests=0
"${cargo_test[@]}" --tests --no-fail-fast || tests=$?

status=0
wait "$wheel" || status=$?
if [ "$status" != 0 ]; then
    cat "$wheel_log"
    echo "building or installing the Python package failed (exit status $status)"
fi
if [ "$tests" != 0 ] || [ "$status" != 0 ]; then
    exit 1
fi
# from outside the source tree, so that the installed package is the one imported
(cd target && ../"$venv/bin/python" -m pytest -q -p no:cacheprovider ../python/tests)
