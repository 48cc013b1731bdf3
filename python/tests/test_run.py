"""coagula.run: scenarios as data, the xarray view, NetCDF, and the exact columns."""

import math

import numpy as np
import pytest

import coagula

xr = pytest.importorskip("xarray")  # scripts/test.sh installs it: never skipped there


def test_run_returns_a_dataset_with_the_exact_solution():
    ds = coagula.run("quickstart-golovin", replicas=4, set={"initial.particles": 2048})
    assert isinstance(ds, xr.Dataset)
    assert ds["mean"].dims == ("time", "observable")
    m0 = ds.sel(observable="M0")
    # Golovin from the exponential start: M0 = exp(-t)
    assert np.allclose(m0.exact, np.exp(-ds.time), rtol=1e-12)
    assert np.all(np.abs(m0["mean"] - m0.exact) < 8 * m0.half_width + 1e-12)
    assert ds.attrs["scheme"] == "lowrank" and "Golovin" in ds.attrs["title"]


def test_a_dict_scenario_and_a_sweep():
    sc = {
        "kernel": {"kind": "constant"},
        "initial": {"kind": "monodisperse", "size": 1, "particles": 1000},
        "scheme": {"name": "lowrank"},
        "output": {"times": [1.0], "observables": ["M0"]},
        "run": {"replicas": 3, "seed": 2},
        "sweep": {"initial": {"particles": [500, 1000]}},
    }
    out = coagula.run(sc)
    assert isinstance(out, list) and len(out) == 2
    assert out[0].attrs["sweep.initial.particles"] == "500"
    d = coagula.run(sc, as_xarray=False, set={"sweep": {}})
    assert isinstance(d, dict) and d["mean"].shape == (1, 1)
    assert math.isclose(d["exact"][0, 0], 2 / 3, rel_tol=1e-12)


def test_run_is_the_same_for_any_number_of_threads():
    a = coagula.run("quickstart-constant", replicas=6, threads=1, as_xarray=False)
    b = coagula.run("quickstart-constant", replicas=6, threads=2, as_xarray=False)
    assert np.array_equal(a["mean"], b["mean"]) and np.array_equal(a["half_width"], b["half_width"])


def test_netcdf_round_trip(tmp_path):
    pytest.importorskip("scipy")  # xarray's NetCDF3 writer without netCDF4
    ds = coagula.run("quickstart-constant", replicas=2)
    p = tmp_path / "run.nc"
    ds.to_netcdf(p)
    back = xr.open_dataset(p)
    assert np.array_equal(back["mean"].values, ds["mean"].values)
    assert back.time.attrs["standard_name"] == "time"


def test_exact_module():
    from coagula.exact import NAMES, Solution

    assert "golovin" in NAMES
    e = Solution("constant", coefficient=2.0)
    t = np.array([0.0, 1.0])
    assert np.allclose(e.moment(0, t), 2 / (2 + 2 * t))
    assert Solution("multiplicative").gel_time == 1.0
    with pytest.raises(ValueError):
        e.moment(0, -1.0)
