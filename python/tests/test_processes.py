"""Sources, removal and growth beside coagulation (issue 42) from Python: the books
balance, refusals leave the simulation as it was, pickles and clones continue bit for
bit, a scenario's [source] and [sink] tables run with their closed form."""

import pickle

import numpy as np
import pytest
import scipy.stats

import coagula
from coagula import Initial, Kernel, Simulation
from conftest import z_max


def sim_with_processes(seed=3):
    sim = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=2000), seed=seed)
    sim.set_processes(
        source={"rate": 0.5, "kind": "exponential", "mean": 2.0},
        removal=(0.05, 1.0 / 3.0),
        growth=(0.02, 1.0),
    )
    return sim


def test_the_books_balance():
    sim = sim_with_processes()
    sim.advance_to(3.0)
    b = sim.books
    assert b["injected_number"] > 0 and b["removed_number"] > 0 and b["grown_mass"] > 0
    sizes, counts = sim.pairs()
    assert b["initial_number"] + b["injected_number"] - b["removed_number"] - b["merged"] == counts.sum()
    mass = b["initial_mass"] + b["injected_mass"] - b["removed_mass"] + b["grown_mass"]
    assert mass == float((sizes * counts).sum())  # exact on integer sizes
    assert sim.processes == {
        "source": {"rate": 0.5, "kind": "exponential", "mean": 2.0},
        "removal": (0.05, 1.0 / 3.0),
        "growth": (0.02, 1.0),
    }
    sim.set_processes()
    assert sim.processes is None and sim.books is None


def test_refusals_leave_the_simulation_as_it_was():
    sim = sim_with_processes()
    sim.advance_to(1.0)
    before = sim.save()
    for kw, exc in [
        ({"removal": (1.0, 2.0)}, ValueError),
        ({"growth": "fast"}, ValueError),
        ({"source": {"rate": -1.0}}, ValueError),
        ({"source": {"rate": 1.0, "kind": "counts"}}, ValueError),
        ({"source": {"rate": 1.0, "colour": 3}}, ValueError),
        ({"source": [1.0]}, ValueError),
    ]:
        with pytest.raises(exc):
            sim.set_processes(**kw)
        assert sim.save() == before, kw
    sizes = Simulation("lowrank-sizes", Kernel("constant"), Initial.sizes(np.ones(64), 1.0), seed=1)
    with pytest.raises(ValueError, match="growth step"):
        sizes.set_processes(growth=0.1)
    for step in (0.0, -1.0, float("nan"), "short"):
        with pytest.raises(ValueError, match="growth"):
            sizes.set_processes(growth=0.1, growth_step=step)
    mfa = Simulation("mfa", Kernel("constant"), Initial.sizes(np.ones(64), 1.0), seed=1)
    with pytest.raises(ValueError, match="massflow"):
        mfa.set_processes(removal=0.1)
    mf = Simulation("massflow", Kernel("constant"), Initial.sizes(np.ones(64), 1.0), dt=0.01, seed=1)
    with pytest.raises(ValueError, match="own step"):
        mf.set_processes(growth=0.1, growth_step=0.1)


def test_the_mass_flow_runs_processes_in_its_steps():
    """A source, removal and growth inside massflow's own steps: the books balance with
    the mass it carries; M1 under a monomer source and dilution follows
    M1' = S - lambda M1 (deterministic in the mass flow, to O(dt))."""
    sim = Simulation("massflow", Kernel("constant"), Initial.sizes(np.ones(1024), 1.0), dt=0.01, seed=1)
    sim.set_processes(source={"rate": 0.5, "kind": "monodisperse", "size": 1.0}, removal=0.25)
    sim.advance_to(2.0)
    b = sim.books
    m1 = sim.moment(1.0)
    assert abs(b["initial_mass"] + b["injected_mass"] - b["removed_mass"] + b["grown_mass"] - m1) < 1e-12 * m1
    exact = 2.0 + (1.0 - 2.0) * np.exp(-0.25 * 2.0)
    assert abs(m1 - exact) < 2e-3 * exact, (m1, exact)
    twin = Simulation("massflow", Kernel("constant"), Initial.sizes(np.ones(1024), 1.0), dt=0.01, seed=1)
    twin.set_processes(source={"rate": 0.5, "kind": "monodisperse", "size": 1.0}, removal=0.25)
    twin.advance_to(2.0)
    assert twin.save() == sim.save()


def test_pickles_and_clones_continue_bit_for_bit():
    sim = sim_with_processes()
    sim.advance_to(1.5)
    copy = pickle.loads(pickle.dumps(sim))
    twin = sim.clone()
    assert copy.processes == sim.processes and copy.books == sim.books
    for s in (sim, copy, twin):
        s.advance_to(3.0)
    assert sim.save() == copy.save() == twin.save()
    assert sim.books == copy.books == twin.books
    # a checkpoint with processes restores only into a sim that has them
    bare = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=2000), seed=3)
    with pytest.raises(coagula.CoagulaError, match="processes"):
        bare.restore(sim.save())


def test_a_scenario_with_a_source_and_a_sink_meets_its_closed_form():
    r = coagula.run(
        "processes-source-dilution", replicas=8, set={"initial.particles": 1000}, as_xarray=False
    )
    assert r["observables"] == ["M0", "M1", "M2"]
    exact, mean, hw = r["exact"], r["mean"], r["half_width"]
    assert np.all(np.isfinite(exact))
    # M1 = S/λ + (1 − S/λ) e^{−λt}, the closed form the table shows
    assert np.allclose(exact[:, 1], 2.0 - np.exp(-0.25 * r["time"]), rtol=1e-12)
    # the suite's threshold (1e-6 per comparison) in standard errors: hw / t_{0.975, 7}
    se = hw / scipy.stats.t.ppf(0.975, 7)
    assert np.all(np.abs(mean - exact) < z_max(8) * se)


def test_a_listed_source_round_trips_and_pickles():
    import pickle

    sim = Simulation("dsa", Kernel("constant"), Initial.sizes(np.ones(500), 1.0), capacity=4000, seed=2)
    sim.set_processes(source={"rate": 0.5, "kind": "sizes", "sizes": [1.0, 2.5, 2.5]}, removal=0.1)
    assert sim.processes["source"] == {"rate": 0.5, "kind": "sizes", "sizes": [1.0, 2.5, 2.5]}
    sim.advance_to(2.0)
    copy = pickle.loads(pickle.dumps(sim))
    sim.advance_to(4.0)
    copy.advance_to(4.0)
    assert sim.save() == copy.save()
    sizes = set(np.unique(sim.sizes()))
    assert {2.5} <= sizes
    with pytest.raises(ValueError):
        sim.set_processes(source={"rate": 0.5, "kind": "sizes"})
    with pytest.raises(ValueError):
        sim.set_processes(source={"rate": 0.5, "kind": "sizes", "sizes": [1.0, -2.0]})


def test_a_scheduled_source_switches_on_and_off():
    sim = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=1000), seed=4)
    src = {"rate": 0.0, "kind": "monodisperse", "size": 1.0, "times": [1.0, 2.0], "rates": [3.0, 0.0]}
    sim.set_processes(source=src)
    assert sim.processes["source"]["times"] == [1.0, 2.0]
    sim.advance_to(1.0)
    assert sim.books["injected_number"] == 0
    sim.advance_to(2.0)
    on = sim.books["injected_number"]
    # 3 per unit volume and time in volume 1000 over one time unit: 3000 ± 55
    assert abs(on - 3000) < 6 * 55
    sim.advance_to(5.0)
    assert sim.books["injected_number"] == on
    copy = pickle.loads(pickle.dumps(sim))
    assert copy.processes == sim.processes
    for bad in [{"times": [1.0]}, {"times": [2.0, 1.0], "rates": [1.0, 1.0]}, {"times": [1.0], "rates": [-1.0]}]:
        with pytest.raises(ValueError):
            sim.set_processes(source={"rate": 0.1, **bad})


def _half_below_ten(x):
    return 0.3 if x < 10 else 0.15


def test_user_rates_run_within_their_bound_and_pickle():
    sim = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=2000), seed=6)
    sim.set_processes(removal={"rate": _half_below_ten, "bound": 0.5}, growth={"rate": _half_below_ten, "bound": 0.3})
    assert sim.processes["removal"] == {"rate": _half_below_ten, "bound": 0.5}
    sim.advance_to(1.0)
    b = sim.books
    assert b["removed_number"] > 0 and b["grown_mass"] > 0
    copy = pickle.loads(pickle.dumps(sim))
    sim.advance_to(2.0)
    copy.advance_to(2.0)
    assert sim.save() == copy.save()
    # a rate above its bound: refused, the sim where it stood
    sim.set_processes(removal={"rate": _half_below_ten, "bound": 0.1})
    with pytest.raises(coagula.CoagulaError):
        sim.advance_to(10.0)
    # (the population and the clock stay; the random stream moves on, as after any
    # refused event)
    before = (sim.time, sim.counts().tobytes())
    with pytest.raises(coagula.CoagulaError):
        sim.advance_to(10.0)
    assert (sim.time, sim.counts().tobytes()) == before
    # a callable that raises: the exception is the cause
    def boom(x):
        raise RuntimeError("no rate here")

    sim.set_processes(removal={"rate": boom, "bound": 1.0})
    with pytest.raises(coagula.CoagulaError) as e:
        sim.advance_to(20.0)
    assert isinstance(e.value.__cause__, RuntimeError)
    for bad in [{"rate": 1.0, "bound": 1.0}, {"rate": boom}, {"rate": boom, "bound": -1.0}, {"rate": boom, "bound": 1.0, "x": 1}]:
        with pytest.raises(ValueError):
            sim.set_processes(removal=bad)


def test_growth_on_real_sizes_is_split_and_pickles():
    """Linear growth with the constant kernel: M1 = M1(0) e^{gt} at the step's
    multiples, exactly (merges keep the mass); a pickle continues bit for bit."""
    sizes = 1.0 + np.arange(256) % 3
    sim = Simulation("dsa", Kernel("constant"), Initial.sizes(sizes, 1.0), seed=5)
    sim.set_processes(growth=(0.2, 1.0), growth_step=0.25)
    assert sim.processes == {"growth": (0.2, 1.0), "growth_step": 0.25}
    m0 = sim.moment(1)
    sim.advance_to(1.0)
    assert sim.moment(1) == pytest.approx(m0 * np.exp(0.2), rel=1e-12)
    copy = pickle.loads(pickle.dumps(sim))
    for s in (sim, copy):
        s.advance_to(2.5)
    assert sim.save() == copy.save() and sim.books == copy.books
    assert sim.moment(1) == pytest.approx(m0 * np.exp(0.5), rel=1e-12)
    assert sim.books["grown_mass"] > 0


def _half(t):
    return 0.5


def test_a_source_rate_function_is_thinned_and_pickles():
    """S(t) = 0.5 drawn against a bound of 2: Poisson(S V t) = 2000 monomers in
    V = 2000 over t = 2 (8000 without the thinning)."""
    sim = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=2000), seed=4)
    src = {"rate": _half, "bound": 2.0, "kind": "monodisperse", "size": 1.0}
    sim.set_processes(source=src, removal=0.1)
    assert sim.processes == {"source": src, "removal": (0.1, 0.0)}
    sim.advance_to(1.0)
    copy = pickle.loads(pickle.dumps(sim))
    for s in (sim, copy):
        s.advance_to(2.0)
    assert sim.save() == copy.save() and sim.books == copy.books
    assert abs(sim.books["injected_number"] - 2000) < 6 * 2000**0.5
    # above its bound: refused, the sim where it stood
    sim.set_processes(source={"rate": _half, "bound": 0.25})
    with pytest.raises(coagula.CoagulaError):
        sim.advance_to(5.0)
    before = (sim.time, sim.counts().tobytes())
    with pytest.raises(coagula.CoagulaError):
        sim.advance_to(5.0)
    assert (sim.time, sim.counts().tobytes()) == before
    for bad in [
        {"rate": _half},
        {"rate": _half, "bound": 0.0},
        {"rate": _half, "bound": 1.0, "times": [1.0], "rates": [0.0]},
        {"rate": 0.5, "bound": 1.0},
    ]:
        with pytest.raises(ValueError):
            sim.set_processes(source=bad)
