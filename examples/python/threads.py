"""Two simulations stepped on two threads: Simulation.advance_to releases the
interpreter lock, so large cells run in parallel from plain Python threads.

Two cells of 2 * 10^6 monomers (additive kernel) to t = 1, one after the other and
then on two threads (three rounds, fastest of each); prints the ratio (about 0.5 on
two idle cores).

    python examples/python/threads.py
"""

import threading
import time

import coagula


def cell(seed):
    return coagula.Simulation("lowrank", coagula.Kernel("additive"),
                              coagula.Initial.monodisperse(1, particles=2_000_000), seed=seed)


best_seq = best_par = float("inf")
for _ in range(3):
    a, b = cell(1), cell(2)
    t = time.perf_counter()
    a.advance_to(1.0)
    b.advance_to(1.0)
    best_seq = min(best_seq, time.perf_counter() - t)
    a, b = cell(1), cell(2)
    threads = [threading.Thread(target=s.advance_to, args=(1.0,)) for s in (a, b)]
    t = time.perf_counter()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    best_par = min(best_par, time.perf_counter() - t)
print(f"two cells of 2e6 monomers to t = 1: one after the other {best_seq:.3f} s, "
      f"on two threads {best_par:.3f} s (ratio {best_par / best_seq:.2f})")
