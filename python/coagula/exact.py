"""Exact solutions of the Smoluchowski equation (the Rust core's ``exact`` module).

``Solution(name, coefficient=1.0)`` for a name of ``NAMES``: moments ``M_m(t)``,
``number_density(k, t)`` over integer sizes, ``density(x, t)`` over real sizes, the
gel time and mass; the time may be a numpy array. The solutions are for unit
initial concentration of unit monomers (or the exponential start where the name
says so); a kernel ``b K`` at time t is ``K`` at time ``b t``.

``Sectional`` is the fixed-pivot sectional reference for combinations without a
closed form (a source at one size, removal lambda(x), growth G(x)).

>>> from coagula.exact import Solution
>>> import numpy as np
>>> Solution("constant").moment(0, np.array([0.0, 2.0]))   # 2/(2 + t)
array([1. , 0.5])
"""

from ._coagula import EXACT_NAMES as _NAMES
from ._coagula import Sectional, Solution, temperature_closed_form

NAMES = tuple(_NAMES)

__all__ = ["NAMES", "Sectional", "Solution", "temperature_closed_form"]
