"""Reference data from scipy's unscrambled Sobol' (Joe-Kuo new-joe-kuo-6.21201).

Writes
  sobol_scipy_points.txt : first 4096 points (random_base2(12), bits=30, scipy's
                           Gray-code order) of a 1111-dimensional generator, for the
                           selected coordinates DIMS, as value*2^30 in hex.
  sobol_scipy_dirnum64.txt : the 64-bit direction numbers (scipy `_sv`, bits=64)
                           of the selected coordinates: one line per coordinate,
                           64 hex words (column r = image of index bit r).
"""
import sys
import numpy as np
import scipy
from scipy.stats import qmc

DIMS = list(range(1, 21)) + [50, 100, 500, 1000, 1111]
D = max(DIMS)
out = sys.argv[1] if len(sys.argv) > 1 else "."

s = qmc.Sobol(D, scramble=False)  # bits=30 by default
x = s.random_base2(12)
ints = x * 2.0**30
assert np.all(ints == np.floor(ints))
ints = ints.astype(np.uint64)
with open(f"{out}/sobol_scipy_points.txt", "w") as f:
    f.write(f"# scipy {scipy.__version__} qmc.Sobol(d={D}, scramble=False).random_base2(12), "
            f"value*2^30 hex, scipy (Gray-code) order; columns = dims {','.join(map(str, DIMS))}\n")
    for row in ints:
        f.write(" ".join(f"{int(row[d - 1]):08x}" for d in DIMS) + "\n")

s64 = qmc.Sobol(D, scramble=False, bits=64)
sv = s64._sv
with open(f"{out}/sobol_scipy_dirnum64.txt", "w") as f:
    f.write(f"# scipy {scipy.__version__} qmc.Sobol(d={D}, scramble=False, bits=64)._sv; "
            f"one line per dim: dim then 64 hex columns (index bit 0 first)\n")
    for d in DIMS:
        f.write(f"{d} " + " ".join(f"{int(v):016x}" for v in sv[d - 1]) + "\n")
