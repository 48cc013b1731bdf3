"""Shared helpers of the Python tests (run by scripts/test.sh after the Rust tests)."""

import math

import numpy as np
import pytest

import coagula
from coagula._coagula import _student_t_threshold


def z_max(replicas: int) -> float:
    """Core's threshold for a mean of `replicas` replicas (false-alarm 1e-6 per
    comparison, docs/design/statistical-tests.md)."""
    return _student_t_threshold(replicas - 1)


def mean_se(values):
    v = np.asarray(values, dtype=float)
    return v.mean(), v.std(ddof=1) / math.sqrt(len(v))


def info(name):
    return next(s for s in coagula.schemes() if s["name"] == name)


@pytest.fixture
def monomers():
    """The standard start of a scheme: n monomers (counts, sizes, or counts at
    temperature 1), as core's conformance suite builds it."""

    def make(name, n):
        s = info(name)
        if s["model"] == "temperature":
            return coagula.Initial.counts([n], float(n), temperatures=[1.0])
        if "counts" in s["inits"]:
            return coagula.Initial.counts([n], float(n))
        return coagula.Initial.sizes(np.ones(n), 1.0)

    return make
