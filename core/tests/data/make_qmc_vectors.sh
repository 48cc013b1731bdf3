#!/usr/bin/env bash
# Regenerates the QMC reference vectors in this directory.
#
# Needs: a C compiler and GSL (Debian: apt-get install -y libgsl-dev), Python 3 with
# scipy and numpy (pip install scipy). Run from anywhere:
#   bash tests/data/make_qmc_vectors.sh
# Outputs (all in this directory):
#   nied2_gsl.txt            GSL niederreiter_2, dims 1..12, 4096 points (31-bit ints)
#   sobol_scipy_points.txt   scipy Sobol', selected dims, 4096 points (30-bit ints)
#   sobol_scipy_dirnum64.txt scipy Sobol' 64-bit direction numbers, selected dims
# The Rust direction-number table is made separately by make_sobol_table.py.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cc -O2 -o "$tmp/gsl_nied2" "$here/gsl_nied2.c" -lgsl -lgslcblas -lm
"$tmp/gsl_nied2" > "$here/nied2_gsl.txt"
python3 "$here/scipy_sobol.py" "$here"
echo "wrote $here/nied2_gsl.txt $here/sobol_scipy_points.txt $here/sobol_scipy_dirnum64.txt"
