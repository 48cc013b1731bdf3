"""A worked host in Python: a plug-flow aerosol reactor as a row of well-mixed cells
along a pipe — the protocol of examples/c/plug_flow.c, so that the two can be compared.

The gas carries particles from cell to cell (residence time TAU per cell); monomers
nucleate in the first two cells (a source), grow by vapour uptake in the first three
(monomer attachment at G(x) = 0.3 x^(2/3)), and coagulate everywhere (the constant
kernel). Each cell is one coagula.Simulation with its own processes; every host step
DT the host moves each particle on with probability 1 - exp(-DT/TAU) (the last cell's
leave the pipe), reading sim.pairs() and writing sim.set_pairs().

Checked two ways (exit status 0 when both hold):
 - the books balance exactly: particles and mass in the cells = injected - merged
   (number) / + grown (mass) - what left the pipe;
 - against core's sectional reference (coagula.exact.Sectional) of the same cells with
   the same splitting: M0 and M1 of every cell at the end, the particles averaged over
   REPLICAS reactors, within Student t at 1e-7 per check (15 degrees of freedom) times
   the standard error, plus the grid's error (the difference between the solutions at
   pivot ratios 1.05 and 1.10).

    python examples/python/plug_flow.py [particles per unit concentration = 2000]
"""

import math
import sys

import numpy as np

import coagula
from coagula.exact import Sectional

CELLS, REPLICAS = 6, 16
TAU, DT, T_END = 1.0, 0.05, 8.0
SOURCE, GROWTH = 2.0, 0.3  # monomers per unit volume and time; g in g x^(2/3)
STEPS = round(T_END / DT)
LEAVE = 1.0 - math.exp(-DT / TAU)


def processes(sim, c):
    """A cell's processes (set afresh after every set_pairs: the books restart)."""
    source = {"rate": SOURCE, "kind": "monodisperse", "size": 1.0} if c < 2 else None
    growth = (GROWTH, 2.0 / 3.0) if c < 3 else None
    if source or growth:
        sim.set_processes(source=source, growth=growth)


def reactor(volume, seed):
    """One reactor of particles to T_END: (M0, M1) per cell, and whether the books
    balance exactly."""
    rng = np.random.default_rng(seed)
    k = coagula.Kernel("constant")
    sims = [
        coagula.Simulation("lowrank", k, coagula.Initial.counts([], volume), seed=seed, stream=c)
        for c in range(CELLS)
    ]
    for c, s in enumerate(sims):
        processes(s, c)
    injected_n = injected_m = grown_m = out_n = out_m = 0.0

    def read_books(s):
        nonlocal injected_n, injected_m, grown_m
        b = s.books
        if b is not None:
            injected_n += b["injected_number"]
            injected_m += b["injected_mass"]
            grown_m += b["grown_mass"]

    for step in range(1, STEPS + 1):
        for s in sims:
            s.advance_to(step * DT)
        # who leaves, from the states before any transfer
        stay, leave = [], []
        for s in sims:
            sizes, counts = s.pairs()
            gone = rng.binomial(counts.astype(np.int64), LEAVE).astype(np.uint64)
            stay.append((sizes, counts - gone))
            leave.append((sizes, gone))
        out_n += float(leave[-1][1].sum())
        out_m += float((leave[-1][0] * leave[-1][1]).sum())
        for c in range(CELLS):
            sizes, counts = stay[c]
            if c > 0:
                sizes = np.concatenate([sizes, leave[c - 1][0]])
                counts = np.concatenate([counts, leave[c - 1][1]])
            merged, at = np.unique(sizes, return_inverse=True)
            total = np.zeros(len(merged), dtype=np.uint64)
            np.add.at(total, at, counts)
            keep = total > 0
            read_books(sims[c])
            sims[c].set_pairs(merged[keep], total[keep], volume)
            processes(sims[c], c)
    n_in = m_in = merged = 0.0
    m0, m1 = [], []
    for s in sims:
        read_books(s)
        merged += s.totals["events"]  # every call's coagulations (set_pairs keeps them)
        sizes, counts = s.pairs()
        n_in += float(counts.sum())
        m_in += float((sizes * counts).sum())
        m0.append(s.moment(0.0))
        m1.append(s.moment(1.0))
    ok = n_in == injected_n - merged - out_n and m_in == injected_m + grown_m - out_m
    print(
        f"seed {seed}: in the cells {n_in:.0f} particles of mass {m_in:.0f}; injected "
        f"{injected_n:.0f} (mass {injected_m:.0f}), merged {merged:.0f}, grown {grown_m:.0f}, "
        f"left the pipe {out_n:.0f} (mass {out_m:.0f}): "
        + ("balanced exactly" if ok else "NOT BALANCED")
    )
    return np.array(m0), np.array(m1), ok


def sectional(ratio):
    """The same reactor, deterministic: core's sectional reference per cell (integer
    pivots to 64, where attachment's mean is exact, then the ratio to 8192)."""
    cells = [
        Sectional(
            "constant",
            dense=64,
            largest=8192.0,
            ratio=ratio,
            source=(SOURCE, 1.0) if c < 2 else None,
            growth=(lambda x: GROWTH * x ** (2.0 / 3.0)) if c < 3 else None,
        )
        for c in range(CELLS)
    ]
    for step in range(1, STEPS + 1):
        moved = []
        for s in cells:
            s.advance_to(step * DT, dt=1e-2)
            moved.append(LEAVE * s.state()[1])
        for c, s in enumerate(cells):
            n = s.state()[1] - moved[c] + (moved[c - 1] if c > 0 else 0.0)
            for i, v in enumerate(n):
                s.set_number(i, max(float(v), 0.0))
    return np.array([s.moment(0) for s in cells]), np.array([s.moment(1) for s in cells])


def main(volume=2000.0):
    runs = [reactor(volume, 11 + r) for r in range(REPLICAS)]
    p0 = np.array([r[0] for r in runs])
    p1 = np.array([r[1] for r in runs])
    balanced = all(r[2] for r in runs)
    s0, s1 = sectional(1.05)
    c0, c1 = sectional(1.10)
    z = coagula._coagula._student_t_threshold(REPLICAS - 1, 1e-7)
    within = True
    print("cell   M0 particles (±SE)    M0 sectional (grid)      M1 particles (±SE)    M1 sectional (grid)")
    for c in range(CELLS):
        ok = True
        cols = []
        for p, s, g in ((p0, s0, c0), (p1, s1, c1)):
            mean, se = p[:, c].mean(), p[:, c].std(ddof=1) / math.sqrt(REPLICAS)
            grid = abs(s[c] - g[c])
            ok &= abs(mean - s[c]) <= z * se + grid
            cols.append(f"{mean:.5f} (±{se:.5f})   {s[c]:.5f} ({grid:.1e})")
        print(f"{c:4d}   " + "   ".join(cols) + ("   ok" if ok else "   OFF"))
        within &= ok
    passed = balanced and within
    print("plug flow: " + ("balanced and within the sectional reference" if passed else "FAILED"))
    return passed


if __name__ == "__main__":
    sys.exit(0 if main(float(sys.argv[1]) if len(sys.argv) > 1 else 2000.0) else 1)
