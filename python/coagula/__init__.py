"""coagula: stochastic particle simulation of coagulation and fragmentation.

Every scheme of the library's registry behind one class, :class:`Simulation`;
kernels from core's table (:class:`Kernel`) or Python callables
(:class:`UserKernel`); initial states (:class:`Initial`); Langevin trajectory
batches (:class:`Langevin`, Maftei et al. 2016); scenario files run as
``coagula run`` runs them (:func:`run`); exact solutions (:mod:`coagula.exact`).
The numerics are the Rust core's: this package translates.

>>> import coagula
>>> sim = coagula.Simulation("lowrank", "additive",
...                          coagula.Initial.monodisperse(1, particles=4096), seed=1)
>>> _ = sim.advance_to(1.0)
>>> abs(sim.moment(0) - 0.3679) < 0.03    # exact: exp(-1)
True
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import exact
from ._coagula import (
    CoagulaError,
    Fragmentation,
    Initial,
    Kernel,
    Langevin,
    Simulation,
    StepReport,
    UserKernel,
    class_rates,
    examples,
    kernels,
    options,
    schemes,
)
from ._coagula import _run

__all__ = [
    "CoagulaError",
    "Fragmentation",
    "Initial",
    "Kernel",
    "Langevin",
    "Simulation",
    "StepReport",
    "UserKernel",
    "class_rates",
    "examples",
    "exact",
    "kernels",
    "options",
    "run",
    "schemes",
]

Scenario = Union[str, "os.PathLike[str]", Mapping[str, Any], None]


def _dataset(r: Dict[str, Any]) -> Any:
    """One run's results as an xarray.Dataset (time x observable)."""
    import xarray as xr

    names = list(r["observables"])
    coords = {"time": ("time", r["time"]), "observable": ("observable", names)}
    ds = xr.Dataset(
        {
            "mean": (("time", "observable"), r["mean"]),
            "half_width": (("time", "observable"), r["half_width"]),
            "exact": (("time", "observable"), r["exact"]),
        },
        coords=coords,
    )
    units = r["units"]
    ds["time"].attrs.update(
        {
            "standard_name": "time",
            "long_name": "time",
            "units": "s" if units else "1 (kernel time units 1/(K c0))",
        }
    )
    ds["mean"].attrs["long_name"] = "mean over the replicas"
    ds["half_width"].attrs["long_name"] = (
        "half-width of the 95% confidence interval of the mean (replicas only: a "
        "time-stepped scheme's O(dt) bias is not in it; NaN for one replica)"
    )
    ds["exact"].attrs["long_name"] = "exact solution (NaN where none is known)"
    ds["observable"].attrs["meaning"] = "; ".join(
        f"{n}: {m}" for n, m in zip(names, r["meanings"])
    )
    ds.attrs.update(
        {
            "title": r["title"],
            "scheme": r["scheme"],
            "kernel": r["kernel"],
            "replicas": int(r["replicas"]),
            "seed": int(r["seed"]),
            "events": int(r["events"]),
            "seconds": float(r["seconds"]),
            "scenario": r["scenario"],
            "Conventions": "CF-1.8",
            "source": "coagula",
        }
    )
    for k, v in r["sweep"].items():
        ds.attrs[f"sweep.{k}"] = v
    return ds


def run(
    scenario: Scenario = None,
    *,
    replicas: Optional[int] = None,
    threads: Optional[int] = None,
    seed: Optional[int] = None,
    set: Optional[Mapping[str, Any]] = None,
    as_xarray: Optional[bool] = None,
) -> Any:
    """Runs a scenario as ``coagula run`` does (same plans, seeds and statistics:
    the same bits) and returns its results.

    ``scenario`` is a TOML file's path, a built-in example's name
    (:func:`examples`), a dict of the same tables (``{"kernel": {"kind":
    "additive"}, "initial": {...}, "scheme": {"name": "lowrank"}, "output":
    {...}}``), or None for the CLI's default. ``replicas``, ``threads`` and
    ``seed`` override ``[run]``; ``set`` overrides any key by its dotted path
    (``{"initial.particles": 4096}``), as ``--set`` does.

    Returns an ``xarray.Dataset`` (dimensions time x observable; variables mean,
    half_width of the 95% interval, exact; the scenario in the attributes) when
    xarray is installed (``as_xarray=False`` forces the dict), else a dict of
    numpy arrays. A scenario with a ``[sweep]`` gives a list, one per point.

    >>> import coagula
    >>> ds = coagula.run("quickstart-golovin", replicas=2, set={"initial.particles": 1024})
    >>> [str(o) for o in ds.observable.values]
    ['M0', 'M2']
    """
    if isinstance(scenario, os.PathLike):
        scenario = os.fspath(scenario)
    results: List[Dict[str, Any]] = _run(
        scenario,
        replicas=replicas,
        threads=threads,
        seed=seed,
        set=dict(set) if set is not None else None,
    )
    if as_xarray is None:
        try:
            import xarray  # noqa: F401

            as_xarray = True
        except ImportError:
            as_xarray = False
    out = [_dataset(r) if as_xarray else r for r in results]
    sweep = len(out) > 1 or bool(results[0]["sweep"])
    return out if sweep else out[0]
