"""No leak over 10^5 create/step/free cycles (resident memory after a warm-up)."""

import coagula


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def cycles(n):
    init = coagula.Initial.monodisperse(1, particles=64)
    k = coagula.Kernel("additive")
    for i in range(n):
        s = coagula.Simulation("lowrank", k, init, seed=i)
        s.advance_to(0.5)
        s.moment(2)
        del s


def test_no_leak_over_1e5_cycles():
    cycles(20_000)
    before = rss_bytes()
    cycles(100_000)
    grown = rss_bytes() - before
    # a leak of even 64 bytes a cycle is 6.4 MB
    assert grown < 4 << 20, f"resident memory grew {grown} bytes over 1e5 cycles"
