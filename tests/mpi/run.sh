#!/usr/bin/env bash
# MPI ensembles (the coagula-mpi binary, Open MPI): `mpirun -n 2 coagula-mpi run` gives
# the bits of one process (a run and a sweep), and an ensemble whose rank is killed
# mid-way resumes from its checkpoints with the bits of an unbroken run.
# Needs mpirun and libclang (Debian: openmpi-bin libopenmpi-dev libclang-dev).
set -euo pipefail
cd "$(dirname "$0")/../.."
# the CI machine runs as root; Open MPI refuses root without these
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
root=$PWD
# cargo's output directory (CARGO_TARGET_DIR when set, relative to the workspace)
target=${CARGO_TARGET_DIR:-target}
case $target in /*) ;; *) target="$root/$target" ;; esac
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# the reference: the default build (no MPI) that the README's test command made (CI
# runs this after it; `cargo test --no-run` with its crates is a no-op then, and here
# makes sure the binary is that build's)
cargo test --workspace --exclude coagula-python --exclude coagula-mpi --lib --bins --tests --no-run -q
cp "$target/debug/coagula" "$work/coagula-plain"
# the MPI build: the coagula-mpi binary (its own crate), over the cli library the test
# build compiled (mpi/Cargo.toml names the dev-dependencies' features so that the two
# builds resolve that library's tree alike: only rsmpi and coagula-mpi compile here)
cargo build --profile test -p coagula-mpi --message-format=json-render-diagnostics \
    > "$work/build.json"
if grep '"reason":"compiler-artifact"' "$work/build.json" | grep '"name":"coagula_cli"' |
    grep -q '"fresh":false'; then
    echo "note: the MPI build compiled the cli library again: its dependencies' features"
    echo "      differ from the test build's (compare cargo tree -e features; mpi/Cargo.toml)"
fi
bin="$target/debug/coagula-mpi"
plain="$work/coagula-plain"
cd "$work"

same() { # same FILE1 FILE2 WHAT
    if cmp -s "$1" "$2"; then
        echo "ok: $3 ($(wc -l < "$1") CSV lines, identical)"
    else
        echo "FAILED: $3"; diff "$1" "$2" | head -n 5; exit 1
    fi
}

run=(run quickstart-constant --replicas 40 --particles 20000 --quiet)
"$plain" "${run[@]}" --csv one.csv > /dev/null
mpirun -n 2 "$bin" "${run[@]}" --threads 1 --csv two.csv > two.txt
grep -q "5 blocks of up to 8 replicas over 2 processes" two.txt
same one.csv two.csv "mpirun -n 2 vs one process of the default (MPI-less) build, 40 replicas"

cat > sweep.toml <<'TOML'
[kernel]
kind = "constant"
[initial]
kind = "monodisperse"
particles = 1000
[scheme]
name = "lowrank"
[output]
t-end = 4.0
count = 4
observables = ["M0", "M2", "n1"]
[run]
replicas = 20
[sweep]
initial.particles = [1000, 4000]
kernel.coefficient = [0.5, 1.0, 2.0]
TOML
"$plain" run sweep.toml --quiet --csv sweep1.csv > /dev/null
mpirun -n 2 "$bin" run sweep.toml --quiet --threads 1 --csv sweep2.csv > /dev/null
same sweep1.csv sweep2.csv "mpirun -n 2 vs one process, a sweep of 6 points x 20 replicas"

# kill a rank once a few blocks are saved, then resume
long=(run quickstart-constant --replicas 320 --particles 200000 --quiet)
"$plain" "${long[@]}" --threads 2 --csv whole.csv > /dev/null
mpirun -n 2 "$bin" "${long[@]}" --threads 1 --checkpoint ckpt --csv killed.csv > /dev/null 2>&1 &
job=$!
for _ in $(seq 1 6000); do
    [ "$(ls ckpt 2>/dev/null | grep -c '\.bin$')" -ge 4 ] && break
    sleep 0.02
done
# one rank dies (mpirun's own command line does not start with the binary)
victim=$(pgrep -f "^$bin run quickstart-constant --replicas 320" | head -n 1 || true)
[ -n "$victim" ] && kill -9 "$victim"
wait "$job" || true
saved=$(ls ckpt | grep -c '\.bin$')
echo "killed rank process $victim with $saved of 40 blocks saved; mpirun ended the job"
[ "$saved" -ge 4 ] && [ "$saved" -lt 40 ] || { echo "FAILED: the kill did not land mid-way"; exit 1; }
mpirun -n 2 "$bin" "${long[@]}" --threads 1 --checkpoint ckpt --csv resumed.csv > resumed.txt
grep "; $saved resumed from checkpoints" resumed.txt || { echo "FAILED: not $saved blocks resumed"; cat resumed.txt; exit 1; }
same whole.csv resumed.csv "killed and resumed over 2 ranks vs unbroken"
