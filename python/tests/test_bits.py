"""Same seed, same bits: a Python Simulation against the CLI library's run (the Rust
facade, replica 0: what `coagula run` gives) and against the C ABI (`libcoagula`,
through ctypes: the library scripts/test.sh builds, found by $COAGULA_LIB)."""

import ctypes
import os
import struct

import numpy as np
import pytest

import coagula
from coagula import Initial, Kernel, Simulation


def scenario(scheme, initial, **scheme_options):
    return {
        "kernel": {"kind": "additive"},
        "initial": initial,
        "scheme": {"name": scheme, **scheme_options},
        "output": {"times": [0.5, 1.0], "observables": ["M0", "M2", "N"]},
        "run": {"replicas": 1, "seed": 7},
    }


@pytest.mark.parametrize(
    "scheme, initial, init, opts",
    [
        ("lowrank", {"kind": "monodisperse", "size": 1, "particles": 4096}, Initial.monodisperse(1, particles=4096), {}),
        ("inverse", {"kind": "monodisperse", "size": 1, "particles": 512}, Initial.monodisperse(1, particles=512), {}),
        # (count schemes run a built-in kernel's bound from size 1: core's rule, which
        # the CLI and Python both apply: SchemeInfo::runs; dsa-counts differed before)
        ("dsa-counts", {"kind": "monodisperse", "size": 1, "particles": 1024}, Initial.monodisperse(1, particles=1024), {}),
        ("lowrank-tree", {"kind": "monodisperse", "size": 1, "particles": 1024}, Initial.monodisperse(1, particles=1024), {}),
        ("dsa", {"kind": "exponential", "mean": 1.0, "particles": 2048}, Initial.exponential(1.0, particles=2048), {}),
        ("massflow", {"kind": "exponential", "mean": 1.0, "particles": 1024}, Initial.exponential(1.0, particles=1024), {"dt": 0.05}),
    ],
)
def test_python_gives_the_bits_of_coagula_run(scheme, initial, init, opts):
    ds = coagula.run(scenario(scheme, initial, **opts), as_xarray=False)
    sim = Simulation(scheme, Kernel("additive"), init, seed=7, **opts)
    for i, t in enumerate([0.5, 1.0]):
        sim.advance_to(t)
        got = [sim.moment(0), sim.moment(2), float(sim.particles)]
        assert got == list(ds["mean"][i]), (scheme, t)


def _lib():
    path = os.environ.get("COAGULA_LIB")
    if not path:
        root = os.path.join(os.path.dirname(__file__), "..", "..", "target")
        for profile in ("debug", "release"):
            p = os.path.join(root, profile, "libcoagula.so")
            if os.path.exists(p):
                path = p
                break
    if not path or not os.path.exists(path):
        # scripts/test.sh always sets it: only a bare `pytest` without a built
        # library gets here
        pytest.fail("libcoagula.so not found: run scripts/test.sh, or set COAGULA_LIB")
    return ctypes.CDLL(path)


def _c_sim(c, kernel, params, seed, counts, volume):
    """A C ABI sim of `lowrank` from `counts` in `volume`, built-in `kernel`, `seed`."""
    vp, d = ctypes.c_void_p, ctypes.c_double
    k, o, s = vp(), vp(), vp()
    assert c.coag_kernel_new(kernel, (d * len(params))(*params), len(params), ctypes.byref(k)) == 0
    assert c.coag_options_new(ctypes.byref(o)) == 0
    assert c.coag_options_set_count(o, b"seed", ctypes.c_uint64(seed)) == 0
    n = (ctypes.c_uint64 * len(counts))(*counts)
    assert c.coag_sim_new_counts(b"lowrank", k, None, o, n, len(counts), d(volume), ctypes.byref(s)) == 0
    c.coag_options_free(o)
    c.coag_kernel_free(k)
    return s


def _c_checkpoint(c, s):
    n = ctypes.c_size_t()
    c.coag_sim_checkpoint_size(s, ctypes.byref(n))
    buf = (ctypes.c_uint8 * n.value)()
    assert c.coag_sim_checkpoint(s, buf, n, None) == 0
    return bytes(buf)


def test_python_gives_the_bits_of_the_c_abi():
    c = _lib()
    vp = ctypes.c_void_p
    k, o, s = vp(), vp(), vp()
    # coefficient 1, min-size 1: what the CLI and Python run a built-in kernel with on
    # an integer-size scheme (core's SchemeInfo::runs); a C caller sets it itself
    assert c.coag_kernel_new(b"additive", (ctypes.c_double * 2)(1.0, 1.0), 2, ctypes.byref(k)) == 0
    assert c.coag_options_new(ctypes.byref(o)) == 0
    assert c.coag_options_set_count(o, b"seed", ctypes.c_uint64(11)) == 0
    counts = (ctypes.c_uint64 * 1)(3000)
    assert c.coag_sim_new_counts(b"lowrank", k, None, o, counts, 1, ctypes.c_double(3000.0), ctypes.byref(s)) == 0
    py = Simulation("lowrank", Kernel("additive", coefficient=1.0), Initial.counts([3000], 3000.0), seed=11)
    for t in (0.25, 1.0, 1.5):
        assert c.coag_sim_advance_to(s, ctypes.c_double(t), None) == 0
        py.advance_to(t)
        for m in (0.0, 2.0, 3.0):
            out = ctypes.c_double()
            assert c.coag_sim_moment(s, ctypes.c_double(m), ctypes.byref(out)) == 0
            assert struct.pack("d", out.value) == struct.pack("d", py.moment(m))
    # and the whole state: the checkpoint envelopes are the same bytes
    n = ctypes.c_size_t()
    c.coag_sim_checkpoint_size(s, ctypes.byref(n))
    buf = (ctypes.c_uint8 * n.value)()
    assert c.coag_sim_checkpoint(s, buf, n, None) == 0
    assert bytes(buf) == py.save()
    c.coag_sim_free(s)
    c.coag_options_free(o)
    c.coag_kernel_free(k)


def test_processes_give_the_same_bits_in_python_the_c_abi_and_coagula_run():
    """A source and a sink: the CLI's scenario tables, Python's set_processes and the
    C ABI's setters are one process in core."""
    sc = {
        "kernel": {"kind": "constant"},
        "initial": {"kind": "monodisperse", "size": 1, "particles": 1000},
        "source": {"rate": 0.5, "kind": "monodisperse", "size": 1},
        "sink": {"rate": 0.25},
        "scheme": {"name": "lowrank"},
        "output": {"times": [1.0, 2.0], "observables": ["M0", "M1", "N"]},
        "run": {"replicas": 1, "seed": 7},
    }
    ds = coagula.run(sc, as_xarray=False)
    py = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=1000), seed=7)
    py.set_processes(source={"rate": 0.5, "kind": "monodisperse", "size": 1.0}, removal=0.25)
    c = _lib()
    vp = ctypes.c_void_p
    k, o, s = vp(), vp(), vp()
    assert c.coag_kernel_new(b"constant", (ctypes.c_double * 1)(1.0), 1, ctypes.byref(k)) == 0
    assert c.coag_options_new(ctypes.byref(o)) == 0
    assert c.coag_options_set_count(o, b"seed", ctypes.c_uint64(7)) == 0
    counts = (ctypes.c_uint64 * 1)(1000)
    assert c.coag_sim_new_counts(b"lowrank", k, None, o, counts, 1, ctypes.c_double(1000.0), ctypes.byref(s)) == 0
    d = ctypes.c_double
    assert c.coag_sim_set_source(s, d(0.5), 0, d(1.0), d(0.0)) == 0
    assert c.coag_sim_set_removal(s, d(0.25), d(0.0)) == 0
    for i, t in enumerate([1.0, 2.0]):
        py.advance_to(t)
        assert c.coag_sim_advance_to(s, d(t), None) == 0
        got = [py.moment(0), py.moment(1), float(py.particles)]
        assert got == list(ds["mean"][i]), t
        out = d()
        assert c.coag_sim_moment(s, d(1.0), ctypes.byref(out)) == 0
        assert struct.pack("d", out.value) == struct.pack("d", py.moment(1))
    n = ctypes.c_size_t()
    c.coag_sim_checkpoint_size(s, ctypes.byref(n))
    buf = (ctypes.c_uint8 * n.value)()
    assert c.coag_sim_checkpoint(s, buf, n, None) == 0
    assert bytes(buf) == py.save()
    c.coag_sim_free(s)
    c.coag_options_free(o)
    c.coag_kernel_free(k)


def test_classes_give_the_same_bits_in_python_and_the_c_abi():
    """set_classes draws its rounding from the sim's own stream: Python's and the C
    ABI's give the same population, projection and checkpoint bytes."""
    pivots = [1.0, 2.0, 3.0, 5.0, 8.0, 13.0, 21.0]
    numbers = [0.11, 0.037, 0.0213, 0.0101, 0.0057, 0.0011, 0.0003]
    py = Simulation("lowrank", Kernel("constant"), Initial.monodisperse(1, particles=1000), seed=5)
    py.set_classes(pivots, numbers)
    py.advance_to(1.0)
    c = _lib()
    d = ctypes.c_double
    s = _c_sim(c, b"constant", [1.0], 5, [1000], 1000.0)
    m = len(pivots)
    assert c.coag_sim_set_classes(s, (d * m)(*pivots), (d * m)(*numbers), m) == 0
    assert c.coag_sim_advance_to(s, d(1.0), None) == 0
    out = (d * m)()
    assert c.coag_sim_project(s, (d * m)(*pivots), m, out, None) == 0
    mine, _ = py.project(pivots)
    assert struct.pack(f"{m}d", *out) == struct.pack(f"{m}d", *mine)
    assert _c_checkpoint(c, s) == py.save()
    c.coag_sim_free(s)
