"""coagula.exact.Sectional, core's fixed-pivot reference, from Python: the closed
forms it must meet (as core's unit tests) and its refusals."""

import math

import numpy as np
import pytest

from coagula import CoagulaError
from coagula.exact import Sectional, Solution


def test_constant_kernel_with_a_source_and_dilution():
    s = Sectional("constant", dense=32, largest=1e5, ratio=1.1, source=(0.7, 1.0))
    s.advance_to(3.0, dt=1e-2)
    m0 = math.sqrt(2 * 0.7) * math.tanh(3.0 * math.sqrt(0.7 / 2))
    assert abs(s.moment(0) - m0) < 1e-8
    b = s.books()
    assert abs(b["injected_mass"] - 2.1) < 1e-10
    d = Sectional("constant", dense=32, largest=1e5, ratio=1.1, removal=lambda x: 0.4)
    d.set_number(0, 1.0)
    d.advance_to(2.5, dt=1e-2)
    inv = (1 + 0.5 / 0.4) * math.exp(0.4 * 2.5) - 0.5 / 0.4
    assert abs(d.moment(0) - 1 / inv) < 1e-8
    x, n = d.state()
    assert x[0] == 1.0 and len(x) == len(n) and np.all(n >= 0)


def test_growth_and_the_mass_books():
    s = Sectional("constant", dense=32, largest=1e5, ratio=1.05, growth=lambda x: 0.3 * x)
    s.set_number(0, 1.0)
    s.advance_to(2.0, dt=1e-2)
    assert abs(s.moment(0) - Solution("constant").moment(0, 2.0)) < 1e-8
    assert abs(s.moment(1) - math.exp(0.6)) < 1e-8
    b = s.books()
    assert abs(s.moment(1) - (1 + b["grown_mass"] - b["lost_mass"])) < 1e-12


def test_refusals():
    with pytest.raises(ValueError):
        Sectional("constant", ratio=1.0)
    with pytest.raises(CoagulaError, match="removal rate"):
        Sectional("constant", removal=lambda x: float("nan"))
    with pytest.raises(ZeroDivisionError):
        Sectional("constant", growth=lambda x: 1 / 0)
    with pytest.raises(ValueError):
        Sectional("temperature-ballistic")
    s = Sectional("constant")
    with pytest.raises(ValueError):
        s.set_number(10**6, 1.0)
    with pytest.raises(ValueError):
        s.advance_to(-1.0, dt=0.1)
