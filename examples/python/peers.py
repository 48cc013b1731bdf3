"""The same problem in coagula, PySDM and PyPartMC, when they are installed.

Golovin's additive kernel (b = 1) from the exponential start (mean 1) to t = 2:
M0 and M2 of each against the exact solution, with the CPU time of each. PySDM and
PyPartMC are optional (pip install PySDM PyPartMC): a peer that is not installed is
skipped with a message. docs/results/peers-golovin.md has the measured table of the
same comparison at 2^12-2^20 particles.

    python examples/python/peers.py [particles]
"""

import sys
import time

import numpy as np

import coagula
from coagula.exact import Solution

n = int(sys.argv[1]) if len(sys.argv) > 1 else 1 << 14
t_end = 2.0
exact = Solution("golovin")
want = (exact.moment(0, t_end), exact.moment(2, t_end))


def row(name, m0, m2, cpu):
    print(f"{name:10s} M0 {m0:.5f} ({100 * (m0 / want[0] - 1):+.2f} %)  "
          f"M2 {m2:.4f} ({100 * (m2 / want[1] - 1):+.2f} %)  CPU {cpu:.3f} s")


c0 = time.process_time()
sim = coagula.Simulation("lowrank-sizes", "additive",
                         coagula.Initial.exponential(1.0, particles=n), seed=1)
sim.advance_to(t_end)
row("coagula", sim.moment(0), sim.moment(2), time.process_time() - c0)

try:
    from PySDM import Builder, Formulae
    from PySDM.backends import CPU
    from PySDM.dynamics import Coalescence
    from PySDM.environments import Box
    from PySDM.initialisation.sampling.spectral_sampling import ConstantMultiplicity
    from PySDM.initialisation.spectra import Exponential
    from PySDM.dynamics.collisions.collision_kernels import Golovin
    from PySDM.products import ParticleVolumeVersusRadiusLogarithmSpectrum  # noqa: F401
except ImportError:
    print("PySDM is not installed: skipped (pip install PySDM)")
else:
    # dimensionless problem in PySDM's units: volume unit v0 = 1 m^3 would be
    # unphysical; use its Golovin kernel K = b (v1 + v2) with b chosen so that
    # b * n0 * v0 = 1 (time in units of 1/(b c0 v0))
    v0, n0, dv = 1e-12, 1e6, 1.0
    b = 1.0 / (n0 * v0)
    c0 = time.process_time()
    builder = Builder(n_sd=n, backend=CPU(Formulae()), environment=Box(dt=t_end / 100, dv=dv))
    attrs = {}
    attrs["volume"], attrs["multiplicity"] = ConstantMultiplicity(
        Exponential(norm_factor=n0 * dv, scale=v0)).sample(n)
    builder.add_dynamic(Coalescence(collision_kernel=Golovin(b=b)))
    particulator = builder.build(attrs)
    particulator.run(100)
    vol = particulator.attributes["volume"].to_ndarray()
    mult = particulator.attributes["multiplicity"].to_ndarray()
    row("PySDM", mult.sum() / (n0 * dv), (mult * (vol / v0) ** 2).sum() / (n0 * dv),
        time.process_time() - c0)

try:
    import PyPartMC  # noqa: F401
except ImportError:
    print("PyPartMC is not installed: skipped (pip install PyPartMC)")
else:
    print("PyPartMC: see docs/results/peers-golovin.md for its rows (its Golovin set-up "
          "runs through its own scenario files; bench peers drives it)")
