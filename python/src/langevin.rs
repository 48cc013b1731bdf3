//! `coagula.Langevin`: a batch of Langevin trajectories (core's `langevin`, Maftei et
//! al. 2016) on the verbs of a `Simulation` — advance with the interpreter detached,
//! a work limit and Ctrl-C, positions and velocities as arrays, means with their
//! standard errors, the checkpoint envelope, pickling — as the C ABI's
//! `coag_langevin` has them.

use crate::kernel::Raised;
use crate::{CoagulaError, py_err};
use coagula_core::langevin::{Batch, BuiltinDrift, Config, Drift, Friction, VelocityBound, Wall};
use coagula_core::observe::Replicas;
use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use std::sync::{Arc, Mutex, TryLockError};

/// A drift: one of core's built-ins, or a Python callable `b(t, x, u)` returning
/// `dim` floats.
#[derive(Clone, Debug)]
enum PyDrift {
    Builtin(BuiltinDrift),
    Callable(Arc<(Py<PyAny>, Raised)>),
}

impl PyDrift {
    fn fingerprint(&self) -> u64 {
        match self {
            PyDrift::Builtin(b) => b.fingerprint(),
            PyDrift::Callable(_) => 0x4341_4c4c, // "CALL", as the C ABI's callbacks
        }
    }
}

impl<const D: usize> Drift<D> for PyDrift {
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        match self {
            PyDrift::Builtin(b) => b.drift(t, x, u),
            PyDrift::Callable(f) => Python::attach(|py| {
                let got =
                    f.0.call1(py, (t, x.to_vec(), u.to_vec()))
                        .and_then(|v| v.extract::<Vec<f64>>(py));
                match got {
                    Ok(v) if v.len() == D => core::array::from_fn(|k| v[k]),
                    Ok(v) => {
                        f.1.keep(PyValueError::new_err(format!(
                            "the drift returned {} values: the batch has dimension {D}",
                            v.len()
                        )));
                        [f64::NAN; D]
                    }
                    Err(e) => {
                        f.1.keep(e);
                        [f64::NAN; D]
                    }
                }
            }),
        }
    }
}

enum Inner {
    D1(Batch<1, PyDrift>),
    D2(Batch<2, PyDrift>),
    D3(Batch<3, PyDrift>),
}

/// Runs `$e` with `$b` bound to the batch of whichever dimension.
macro_rules! with_batch {
    ($h:expr, $b:ident => $e:expr) => {
        match $h {
            Inner::D1($b) => $e,
            Inner::D2($b) => $e,
            Inner::D3($b) => $e,
        }
    };
}

/// What a batch is built from (kept for pickling and clones).
#[derive(Clone, Debug)]
struct Spec {
    n: usize,
    dim: usize,
    dt: f64,
    sigma: f64,
    wall: String,
    radius: f64,
    period: f64,
    bound: Option<(String, f64)>,
    friction: f64,
    x0: Vec<f64>,
    u0: Vec<f64>,
    seed: u64,
}

fn build<const D: usize>(s: &Spec, drift: PyDrift) -> PyResult<Batch<D, PyDrift>> {
    let wall = match s.wall.as_str() {
        "specular" => Wall::Specular,
        "absorbing" => Wall::Absorbing,
        w => {
            return Err(PyValueError::new_err(format!(
                "wall {w:?}: \"specular\" or \"absorbing\""
            )));
        }
    };
    let cfg = if D == 1 {
        if s.radius != 0.0 {
            return Err(PyValueError::new_err(
                "radius must be 0 in one dimension (the wall is at 0)",
            ));
        }
        let line = Config::<D>::half_line(s.dt, s.sigma, wall).map_err(py_err)?;
        if s.period != 0.0 {
            line.with_period(s.period).map_err(py_err)?
        } else {
            line
        }
    } else {
        if s.period != 0.0 {
            return Err(PyValueError::new_err("a periodic border is for dim 1 only"));
        }
        Config::<D>::ball(s.radius, s.dt, s.sigma, wall).map_err(py_err)?
    };
    let bound = match &s.bound {
        None => VelocityBound::None,
        Some((k, b)) if k == "clamp" => VelocityBound::Clamp(*b),
        Some((k, b)) if k == "reflect" => VelocityBound::Reflect(*b),
        Some((k, _)) => {
            return Err(PyValueError::new_err(format!(
                "velocity_bound {k:?}: (\"clamp\", b) or (\"reflect\", b)"
            )));
        }
    };
    let cfg = cfg.with_velocity_bound(bound).map_err(py_err)?;
    if let PyDrift::Builtin(b) = &drift {
        b.check(D).map_err(py_err)?;
    }
    if s.x0.len() != D || s.u0.len() != D {
        return Err(PyValueError::new_err(format!(
            "x0 and u0: {D} values each (the dimension), got {} and {}",
            s.x0.len(),
            s.u0.len()
        )));
    }
    let x: [f64; D] = core::array::from_fn(|k| s.x0[k]);
    let u: [f64; D] = core::array::from_fn(|k| s.u0[k]);
    cfg.check_start(&x, &u).map_err(py_err)?;
    if s.n == 0 {
        return Err(PyValueError::new_err("trajectories must be at least 1"));
    }
    Batch::with_starts(cfg, drift, s.n, s.seed, 0, |_| (x, u)).map_err(py_err)
}

/// A batch of Langevin trajectories (Maftei et al. 2016): `dim` 1 (the half-line
/// x ≥ 0, wall at 0, optionally periodic at `period`) or 2, 3 (outside the ball of
/// `radius`), time step `dt`, noise `sigma`, a `"specular"` or `"absorbing"` wall, a
/// velocity bound (`("clamp", b)`, `("reflect", b)`), and a drift: None, `"friction"`
/// (rate `friction`), `"maftei2016"` (the paper's test drift, dim 1) or a callable
/// `b(t, x, u) -> dim floats`. Every trajectory starts at `(x0, u0)`; `seed` keys the
/// trajectories' streams (the same seed gives the C ABI's bits).
///
/// >>> import coagula
/// >>> b = coagula.Langevin(1000, dt=0.01, x0=[1.0], u0=[0.0], seed=1)
/// >>> _ = b.advance_to(1.0)
/// >>> mean, se = b.mean(lambda x, u: x[0])
#[pyclass(module = "coagula", name = "Langevin", frozen)]
pub struct Langevin {
    inner: Mutex<Inner>,
    spec: Spec,
    drift: PyDrift,
    drift_obj: Py<PyAny>,
}

impl Langevin {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Inner>> {
        match self.inner.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(CoagulaError::new_err(
                "this Langevin batch is already in a call (a drift stepping its own batch, or another thread)",
            )),
            Err(TryLockError::Poisoned(_)) => Err(CoagulaError::new_err(
                "this Langevin batch was left in an unknown state; build a new one",
            )),
        }
    }

    fn make(spec: Spec, drift_obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        let drift = if drift_obj.is_none() {
            PyDrift::Builtin(BuiltinDrift::Zero)
        } else if let Ok(name) = drift_obj.extract::<String>() {
            match name.as_str() {
                "friction" => PyDrift::Builtin(BuiltinDrift::Friction(Friction {
                    rate: spec.friction,
                })),
                "maftei2016" => PyDrift::Builtin(BuiltinDrift::Paper),
                d => {
                    return Err(PyValueError::new_err(format!(
                        "drift {d:?}: None, \"friction\", \"maftei2016\" or a callable b(t, x, u)"
                    )));
                }
            }
        } else if drift_obj.is_callable() {
            PyDrift::Callable(Arc::new((drift_obj.clone().unbind(), Raised)))
        } else {
            return Err(PyValueError::new_err(
                "drift: None, \"friction\", \"maftei2016\" or a callable b(t, x, u)",
            ));
        };
        let inner = match spec.dim {
            1 => Inner::D1(build::<1>(&spec, drift.clone())?),
            2 => Inner::D2(build::<2>(&spec, drift.clone())?),
            3 => Inner::D3(build::<3>(&spec, drift.clone())?),
            d => return Err(PyValueError::new_err(format!("dim {d}: 1, 2 or 3"))),
        };
        Ok(Langevin {
            inner: Mutex::new(inner),
            spec,
            drift,
            drift_obj: drift_obj.clone().unbind(),
        })
    }

    fn rows<'py>(&self, py: Python<'py>, velocities: bool) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self.spec.dim;
        let mut v = Vec::with_capacity(self.spec.n * d);
        {
            let g = self.lock()?;
            with_batch!(&*g, b => {
                if velocities {
                    b.velocities().for_each(|p| v.extend_from_slice(&p));
                } else {
                    b.positions().for_each(|p| v.extend_from_slice(&p));
                }
            });
        }
        let rows: Vec<Vec<f64>> = v.chunks(d).map(<[f64]>::to_vec).collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
    }
}

fn estimate(r: &Replicas) -> PyResult<(f64, f64)> {
    if r.count() < 2 {
        return Err(PyValueError::new_err(format!(
            "a mean and its standard error need at least 2 trajectories (the batch has {})",
            r.count()
        )));
    }
    let (m, se) = (r.mean(), r.std_error());
    if !(m.is_finite() && se.is_finite()) {
        return Err(CoagulaError::new_err(format!(
            "the observable's mean over the trajectories is {m} ± {se}: it must return finite values"
        )));
    }
    Ok((m, se))
}

#[pymethods]
impl Langevin {
    #[new]
    #[pyo3(signature = (trajectories, *, dim=1, dt=0.01, sigma=1.0, wall="specular", radius=0.0,
        period=None, velocity_bound=None, drift=None, friction=0.0, x0, u0, seed=0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        trajectories: usize,
        dim: usize,
        dt: f64,
        sigma: f64,
        wall: &str,
        radius: f64,
        period: Option<f64>,
        velocity_bound: Option<(String, f64)>,
        drift: Option<Bound<'_, PyAny>>,
        friction: f64,
        x0: Vec<f64>,
        u0: Vec<f64>,
        seed: u64,
    ) -> PyResult<Self> {
        if let Some(p) = period
            && !(p > 0.0 && p.is_finite())
        {
            return Err(PyValueError::new_err(format!(
                "period = {p}: a periodic border is finite and > 0 (None for none)"
            )));
        }
        let spec = Spec {
            n: trajectories,
            dim,
            dt,
            sigma,
            wall: wall.to_string(),
            radius,
            period: period.unwrap_or(0.0),
            bound: velocity_bound,
            friction,
            x0,
            u0,
            seed,
        };
        let none = py.None().into_bound(py);
        Langevin::make(spec, drift.as_ref().unwrap_or(&none))
    }

    /// Steps every trajectory to `t` with the interpreter detached; `work_limit` (time
    /// steps of single trajectories) and Ctrl-C stop early with `interrupted=True`.
    #[pyo3(signature = (t, *, work_limit=None))]
    fn advance_to<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        work_limit: Option<u64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (out, signal) = py.detach(|| -> PyResult<_> {
            let mut g = self.lock()?;
            // (always polled: Ctrl-C stops a long call; the trajectories' streams are
            // their own, so the bits do not depend on how the work is split)
            let (out, signal) = crate::with_signals(
                work_limit,
                |budget| with_batch!(&mut *g, b => b.advance_within(t, budget)),
            );
            Ok((out, signal))
        })?;
        if let PyDrift::Callable(f) = &self.drift
            && let Some(e) = f.1.take()
        {
            let err =
                CoagulaError::new_err(format!("the drift raised during advance_to({t}): {e}"));
            err.set_cause(py, Some(e));
            return Err(err);
        }
        if let Some(e) = signal {
            return Err(e);
        }
        let r = out.map_err(py_err)?;
        let d = PyDict::new(py);
        d.set_item("time", r.time)?;
        d.set_item("steps", r.proposals)?;
        d.set_item("events", r.events)?;
        d.set_item("interrupted", r.interrupted)?;
        Ok(d)
    }

    /// The time reached.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(with_batch!(&*self.lock()?, b => b.time()))
    }

    /// The dimension.
    #[getter]
    fn dim(&self) -> usize {
        self.spec.dim
    }

    /// Positions, shape (trajectories, dim).
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, false)
    }

    /// Velocities, shape (trajectories, dim).
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, true)
    }

    /// Wall hits per trajectory (uint64) and the first-hit times (inf where none).
    fn hits<'py>(
        &self,
        py: Python<'py>,
    ) -> crate::sim::Columns<'py, numpy::PyArray1<u64>, numpy::PyArray1<f64>> {
        let (h, f): (Vec<u64>, Vec<f64>) = {
            let g = self.lock()?;
            with_batch!(&*g, b => (b.hits().collect(), b.first_hits().collect()))
        };
        Ok((
            numpy::PyArray1::from_vec(py, h),
            numpy::PyArray1::from_vec(py, f),
        ))
    }

    /// The mean of `f(x, u)` over the trajectories (absorbed ones at their hit) and its
    /// standard error; with no `f`, the hits per trajectory. The 95% interval is
    /// mean ± 1.96 se.
    #[pyo3(signature = (f=None))]
    fn mean(&self, py: Python<'_>, f: Option<Bound<'_, PyAny>>) -> PyResult<(f64, f64)> {
        let g = self.lock()?;
        let mut raised: Option<PyErr> = None;
        let r = with_batch!(&*g, b => match &f {
            None => b.hit_statistics(),
            Some(f) => b.statistics(|x, u| {
                match f.call1((x.to_vec(), u.to_vec())).and_then(|v| v.extract::<f64>()) {
                    Ok(v) => v,
                    Err(e) => {
                        raised.get_or_insert(e);
                        f64::NAN
                    }
                }
            }),
        });
        let _ = py;
        if let Some(e) = raised {
            return Err(e);
        }
        estimate(&r)
    }

    /// The batch as bytes (the checkpoint envelope of every front end).
    fn save<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let g = self.lock()?;
        let print = self.drift.fingerprint();
        let mut w = coagula_core::checkpoint::Writer::new(&mut []);
        with_batch!(&*g, b => b.save_envelope(print, &mut w));
        let mut buf = vec![0u8; w.needed()];
        let mut w = coagula_core::checkpoint::Writer::new(&mut buf);
        with_batch!(&*g, b => b.save_envelope(print, &mut w));
        w.finish().map_err(py_err)?;
        Ok(PyBytes::new(py, &buf))
    }

    /// Restores bytes from `save` of a batch of the same dimension, size and drift; on
    /// an error (`CoagulaError`) the batch is unchanged.
    fn restore(&self, data: &[u8]) -> PyResult<()> {
        let mut g = self.lock()?;
        let print = self.drift.fingerprint();
        with_batch!(&mut *g, b => b.restore_envelope(data, print)).map_err(py_err)
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let s = &self.spec;
        let kw = PyDict::new(py);
        kw.set_item("dim", s.dim)?;
        kw.set_item("dt", s.dt)?;
        kw.set_item("sigma", s.sigma)?;
        kw.set_item("wall", &s.wall)?;
        kw.set_item("radius", s.radius)?;
        kw.set_item("period", (s.period != 0.0).then_some(s.period))?;
        kw.set_item("velocity_bound", s.bound.clone())?;
        kw.set_item("drift", self.drift_obj.bind(py))?;
        kw.set_item("friction", s.friction)?;
        kw.set_item("x0", s.x0.clone())?;
        kw.set_item("u0", s.u0.clone())?;
        kw.set_item("seed", s.seed)?;
        let data = self.save(py)?;
        let f = py.import("coagula._coagula")?.getattr("_langevin")?;
        Ok((f, (s.n, kw, data).into_pyobject(py)?))
    }
}

/// Unpickles a `Langevin` batch: built from its arguments, then its state restored.
#[pyfunction]
fn _langevin<'py>(
    py: Python<'py>,
    n: usize,
    kw: &Bound<'py, PyDict>,
    data: &[u8],
) -> PyResult<Bound<'py, PyAny>> {
    let b = py
        .import("coagula._coagula")?
        .getattr("Langevin")?
        .call((n,), Some(kw))?;
    b.cast::<Langevin>()?.get().restore(data)?;
    Ok(b)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Langevin>()?;
    m.add_function(wrap_pyfunction!(_langevin, m)?)?;
    Ok(())
}
