"""One coagulation simulation per grid cell, stepped from a Python host loop: the
protocol of examples/c/cells.c, so that the two can be compared side by side.

NCELLS low-rank sims (Brownian kernel, PARTICLES monomers each, seed 2026, one stream
per cell) advanced one host time step at a time by a Python loop. Prints the memory
per cell, the cost of one call (a step to the time the cell already has, an idle
step too short for any event, a read of M0), then 10 real steps to t = 1 on this
thread and on THREADS threads (advance_to releases the interpreter lock, so threads
step their cells in parallel).

    python examples/python/cells.py [cells=10000] [particles=1000] [threads=2]
"""

import sys
import time
from concurrent.futures import ThreadPoolExecutor

import coagula


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


ncells = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
particles = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
nthreads = int(sys.argv[3]) if len(sys.argv) > 3 else 2

k = coagula.Kernel("brownian")
init = coagula.Initial.counts([particles], float(particles))  # volume = particles: M0 = 1
rss0 = rss_bytes()
cells = [coagula.Simulation("lowrank", k, init, seed=2026, stream=c) for c in range(ncells)]
per_cell = (rss_bytes() - rss0) / ncells
print(f"{ncells} cells x {particles} particles (Brownian kernel, low-rank bucketed)")
print(f"memory per cell at the start: {per_cell / 1024:.1f} KiB")

t = 0.0
for c in cells:  # a first call builds each cell's proposal tables
    c.advance_to(t)
same = idle = read = 1e30
idle_events = 0
for _ in range(5):
    w = time.perf_counter()
    for c in cells:
        c.advance_to(t)
    same = min(same, (time.perf_counter() - w) / ncells)
    t += 1e-7
    w = time.perf_counter()
    for c in cells:
        idle_events += c.advance_to(t)["events"]
    idle = min(idle, (time.perf_counter() - w) / ncells)
    w = time.perf_counter()
    for c in cells:
        c.moment(0)
    read = min(read, (time.perf_counter() - w) / ncells)
print(f"one call (fastest of 5 passes): step to the current time {same * 1e9:.0f} ns, "
      f"idle step {idle * 1e9:.0f} ns ({idle_events} events in {5 * ncells} idle cell steps), "
      f"moment(0) {read * 1e9:.0f} ns")


def step_all(chunk, until):
    return sum(c.advance_to(until)["events"] for c in chunk)


for threads in (1, nthreads):
    # each pass starts from a copy, so both runs step the same states
    work = [c.clone() for c in cells]
    chunks = [work[i::threads] for i in range(threads)]
    events = 0
    w = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        for step in range(1, 11):
            events += sum(pool.map(step_all, chunks, [t + 0.1 * step] * threads))
    busy = time.perf_counter() - w
    m0 = sum(c.moment(0) for c in work) / ncells
    print(f"{threads} thread(s), 10 steps to t = 1: {busy:.3f} s, {events} events, "
          f"{events / busy / 1e6:.2f} M events/s, {10 * ncells / busy:.0f} cell steps/s; "
          f"mean M0 {m0:.4f}")
