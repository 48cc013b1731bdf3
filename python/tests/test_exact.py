"""Every registry scheme, reached from Python, against an exact solution of its law
(as core's conformance suite: 32 replicas, Student t on their own standard error at
false-alarm 1e-6 per comparison). A factor 2 in a rate moves M0(1) from 2/3 to 1/2
and M2(1) from 2 to 3 (~150 SE); an O(1/N) error at N = 4096 is below the SE and is
the Rust suite's finite-N reference's to catch."""

import math

import numpy as np
import pytest

import coagula
from coagula.exact import Solution, temperature_closed_form
from conftest import mean_se, z_max

REPLICAS = 32
SCHEMES = [s["name"] for s in coagula.schemes()]


def physics(s):
    if s["model"] == "temperature":
        return coagula.Kernel("temperature-closed-form", c=1.0, gamma=0.5)
    return coagula.Kernel("constant")


def options(s):
    # the time-driven scheme on Monte Carlo points with dt = 1/100, as core's suite
    return {"dt": 0.01, "points": "mc"} if "dt" in s["options"] else {}


@pytest.mark.parametrize("name", [n for n in SCHEMES if not n.startswith("dsmc")])
def test_scheme_matches_the_exact_solution(name, monomers):
    s = next(x for x in coagula.schemes() if x["name"] == name)
    n0 = 20_000 if s["model"] == "temperature" else 4096
    t = 1.0
    m0, m2, temp = [], [], []
    for r in range(REPLICAS):
        sim = coagula.Simulation(name, physics(s), monomers(name, n0), seed=100 + r, **options(s))
        rep = sim.advance_to(t)
        assert rep["time"] == t and sim.time == t
        m0.append(sim.moment(0))
        m2.append(sim.moment(2))
        if s["model"] == "temperature":
            temp.append(sim.observable("mean-temperature"))
    z = z_max(REPLICAS)
    checks = []
    if s["model"] == "temperature":
        number, mean_t = temperature_closed_form(t, c=1.0, gamma=0.5)
        checks += [("N", m0, number), ("mean temperature", temp, mean_t)]
    else:
        e = Solution("constant")
        checks.append(("M2", m2, e.moment(2, t)))
        if s["law"] != "TimeStepped":
            checks.append(("M0", m0, e.moment(0, t)))
    for q, values, want in checks:
        m, se = mean_se(values)
        assert abs(m - want) <= z * se, f"{name} {q}: {m} +- {se} vs {want}"


@pytest.mark.parametrize("name", [n for n in SCHEMES if n.startswith("dsmc")])
def test_a_gas_collides_first_at_the_exact_rate(name):
    """From 24 particles with fixed velocities, the first collision comes after an
    exponential time of rate sum pi (R_k + R_l)^2 |V_k - V_l| / V (core's conformance
    suite's test, here through Python's Simulation and work_limit)."""
    rng = np.random.default_rng(3)
    sizes = np.repeat([1, 2, 3], [12, 8, 4]).astype(np.uint64)
    vel = rng.normal(size=(24, 3)) / np.sqrt(sizes)[:, None]
    volume = 500.0
    rate = 0.0
    for a in range(24):
        for b in range(a + 1, 24):
            rr = (sizes[a] ** (1 / 3) + sizes[b] ** (1 / 3)) / 2
            rate += math.pi * rr * rr * np.linalg.norm(vel[a] - vel[b]) / volume
    init = coagula.Initial.velocities(sizes, vel, volume)
    k = coagula.Kernel("hard-spheres", restitution=0.9)
    reps = 20_000
    times = np.empty(reps)
    for r in range(reps):
        sim = coagula.Simulation(name, k, init, seed=r)
        while sim.advance_to(1e12, work_limit=1)["events"] == 0:
            pass
        times[r] = sim.time
    m, se = mean_se(times)
    assert abs(m - 1 / rate) <= z_max(reps) * se, (m, se, 1 / rate)
