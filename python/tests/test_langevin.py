"""Langevin batches from Python: the scheme's own exact moments (Euler steps with
linear friction away from the wall, as core's tests), split = unbroken, pickling,
errors."""

import pickle

import numpy as np
import pytest

import coagula
from coagula import CoagulaError, Langevin
from conftest import z_max


def euler_moments(x0, u0, gamma, sigma, h, steps):
    """[E x, E u, Var u] of x' = x + h u, u' = (1 - gamma h) u + sigma sqrt(h) Z."""
    mx, mu, vxx, vxu, vuu = x0, u0, 0.0, 0.0, 0.0
    a = 1.0 - gamma * h
    for _ in range(steps):
        vxx, vxu, vuu = vxx + 2 * h * vxu + h * h * vuu, a * (vxu + h * vuu), a * a * vuu + sigma**2 * h
        mx, mu = mx + h * mu, a * mu
    return mx, mu, vuu


def test_friction_matches_the_schemes_exact_moments():
    n, h, steps = 20_000, 0.01, 100
    b = Langevin(n, dt=h, sigma=1.0, drift="friction", friction=1.0, x0=[50.0], u0=[1.0], seed=3)
    rep = b.advance_to(h * steps)
    assert rep["time"] == pytest.approx(1.0) and not rep["interrupted"]
    ex, eu, vu = euler_moments(50.0, 1.0, 1.0, 1.0, h, steps)
    z = z_max(n)
    for f, want in [(lambda x, u: x[0], ex), (lambda x, u: u[0], eu), (lambda x, u: (u[0] - eu) ** 2, vu)]:
        m, se = b.mean(f)
        assert abs(m - want) <= z * se, (m, se, want)
    # a factor 2 in the noise doubles Var u: ~100 SE
    assert b.positions().shape == (n, 1) and b.velocities().shape == (n, 1)


def test_split_equals_unbroken_and_pickles():
    kw = dict(dim=2, radius=1.0, dt=0.01, sigma=1.0, x0=[1.5, 0.0], u0=[0.0, 1.0], seed=9)
    a, b = Langevin(500, **kw), Langevin(500, **kw)
    a.advance_to(1.0)
    b.advance_to(0.37)
    c = pickle.loads(pickle.dumps(b))
    while b.advance_to(1.0, work_limit=777)["interrupted"]:
        pass
    c.advance_to(1.0)
    assert a.save() == b.save() == c.save()
    assert np.array_equal(a.hits()[0], c.hits()[0])


def test_a_callable_drift_and_errors():
    b = Langevin(200, drift=lambda t, x, u: [-u[0]], x0=[5.0], u0=[0.0], seed=1)
    f = Langevin(200, drift="friction", friction=1.0, x0=[5.0], u0=[0.0], seed=1)
    b.advance_to(0.5)
    f.advance_to(0.5)
    assert np.array_equal(b.positions(), f.positions())
    bad = Langevin(10, drift=lambda t, x, u: [1.0, 2.0], x0=[1.0], u0=[0.0])
    with pytest.raises(CoagulaError):
        bad.advance_to(1.0)
    for kw, exc in [
        (dict(dim=4, x0=[1.0] * 4, u0=[0.0] * 4), ValueError),
        (dict(x0=[-1.0], u0=[0.0]), ValueError),
        (dict(dt=0.0, x0=[1.0], u0=[0.0]), ValueError),
        (dict(wall="sticky", x0=[1.0], u0=[0.0]), ValueError),
        (dict(drift="maftei2016", dim=2, radius=1.0, x0=[2.0, 0.0], u0=[0.0, 0.0]), ValueError),
        (dict(x0=[1.0, 2.0], u0=[0.0]), ValueError),
        (dict(period=0.0, x0=[1.0], u0=[0.0]), ValueError),
    ]:
        with pytest.raises(exc):
            Langevin(10, **kw)
    one = Langevin(1, x0=[1.0], u0=[0.0])
    with pytest.raises(ValueError, match="at least 2"):
        one.mean()
