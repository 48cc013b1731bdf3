//! Kernels as Python objects: `Kernel` (core's built-in table by name and
//! parameters), `UserKernel` (Python callables with the bounds the scheme needs) and
//! `Fragmentation` (binary uniform, or Python callables).
//!
//! A Python callable is called with the interpreter attached, once per evaluation
//! (about 0.2-0.5 µs each on top of what the function itself costs: see the package
//! docs); an exception it raises stops the call at that event and is raised again
//! from `advance_to`, the sim as before the event.

use crate::py_err;
use coagula_core::checkpoint::fingerprint;
use coagula_core::kernel::builtin::{self, BUILTINS, Builtin};
use coagula_core::kernel::{
    BinaryUniform, Coagulation, CoagulationKernel, FragmentationKernel, MAX_RANK,
};
use coagula_core::scheme::facade::Model;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::Arc;

/// What `__reduce__` returns: the callable that rebuilds the object, and its
/// arguments.
type Reduced<'py, A> = PyResult<(Bound<'py, PyAny>, A)>;

std::thread_local! {
    /// The first exception a Python callback raised during the current call on this
    /// thread (callbacks run on the thread that makes the call, detached or not).
    static RAISED: std::cell::RefCell<Option<PyErr>> = const { std::cell::RefCell::new(None) };
}

/// Where a callback's exception waits for the call that invoked it: this thread's slot,
/// so sims, clones and threads sharing a kernel never see each other's exceptions.
#[derive(Debug, Default)]
pub(crate) struct Raised;

impl Raised {
    /// Keeps `e` unless an earlier exception of this call is kept.
    pub(crate) fn keep(&self, e: PyErr) {
        RAISED.with(|r| {
            let mut r = r.borrow_mut();
            if r.is_none() {
                *r = Some(e);
            }
        });
    }

    /// The kept exception, if any (cleared).
    pub(crate) fn take(&self) -> Option<PyErr> {
        take_raised()
    }
}

/// Clears this thread's slot: what a call does before it may invoke callbacks.
pub(crate) fn clear_raised() {
    drop(take_raised());
}

/// This thread's kept exception, if any (cleared).
pub(crate) fn take_raised() -> Option<PyErr> {
    RAISED.with(|r| r.borrow_mut().take())
}

/// `e`, or the exception a callback raised that caused it (chained as its cause).
pub(crate) fn with_raised(py: Python<'_>, e: PyErr, what: &str) -> PyErr {
    match take_raised() {
        None => e,
        Some(cause) => {
            let err =
                crate::CoagulaError::new_err(format!("a Python callback raised {what}: {cause}"));
            err.set_cause(py, Some(cause));
            err
        }
    }
}

/// Calls `f(args)` with the interpreter attached and reads a float; NaN (which core
/// refuses as a rate) when it raises or returns something else, the exception kept.
pub(crate) fn call_f64<'py, A>(f: &Py<PyAny>, raised: &Raised, args: A) -> f64
where
    A: for<'a> pyo3::call::PyCallArgs<'a>,
{
    Python::attach(
        |py| match f.call1(py, args).and_then(|v| v.extract::<f64>(py)) {
            Ok(v) => v,
            Err(e) => {
                raised.keep(e);
                f64::NAN
            }
        },
    )
}

/// The Python side of a user kernel.
#[derive(Debug)]
pub(crate) struct UserFns {
    rate: Py<PyAny>,
    majorant: Option<Py<PyAny>>,
    factors: Option<Py<PyAny>>,
    rank: usize,
    exact: bool,
    sup: Option<Py<PyAny>>,
    sup_block: Option<Py<PyAny>>,
    loose: bool,
    pub(crate) raised: Raised,
}

/// A coagulation kernel as a Python sim holds it.
#[derive(Clone, Debug)]
pub(crate) enum PyCoag {
    Builtin(Coagulation),
    User(Arc<UserFns>),
}

impl CoagulationKernel for PyCoag {
    fn rate(&self, x: f64, y: f64) -> f64 {
        match self {
            PyCoag::Builtin(k) => k.rate(x, y),
            PyCoag::User(u) => call_f64(&u.rate, &u.raised, (x, y)),
        }
    }
    fn majorant(&self, x: f64) -> Option<f64> {
        match self {
            PyCoag::Builtin(k) => k.majorant(x),
            PyCoag::User(u) => u.majorant.as_ref().map(|f| call_f64(f, &u.raised, (x,))),
        }
    }
    fn rank(&self) -> usize {
        match self {
            PyCoag::Builtin(k) => k.rank(),
            PyCoag::User(u) => u.rank,
        }
    }
    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        match self {
            PyCoag::Builtin(k) => k.factors(x, a, b),
            PyCoag::User(u) => {
                let Some(f) = &u.factors else { return };
                let r = u.rank.min(a.len()).min(b.len());
                // NaN factors (which core refuses) unless the callback returns two
                // sequences of `rank` floats
                a[..r].fill(f64::NAN);
                b[..r].fill(f64::NAN);
                Python::attach(|py| {
                    let got = f
                        .call1(py, (x,))
                        .and_then(|v| v.extract::<(Vec<f64>, Vec<f64>)>(py));
                    match got {
                        Ok((fa, fb)) if fa.len() == u.rank && fb.len() == u.rank => {
                            a[..r].copy_from_slice(&fa[..r]);
                            b[..r].copy_from_slice(&fb[..r]);
                        }
                        Ok((fa, fb)) => u.raised.keep(PyValueError::new_err(format!(
                            "UserKernel factors({x}) returned {} and {} values: rank is {}",
                            fa.len(),
                            fb.len(),
                            u.rank
                        ))),
                        Err(e) => u.raised.keep(e),
                    }
                });
            }
        }
    }
    fn low_rank_is_exact(&self) -> bool {
        match self {
            PyCoag::Builtin(k) => k.low_rank_is_exact(),
            PyCoag::User(u) => u.exact,
        }
    }
    fn low_rank_floor(&self) -> f64 {
        match self {
            PyCoag::Builtin(k) => k.low_rank_floor(),
            PyCoag::User(u) => f64::from(u8::from(u.exact)),
        }
    }
    fn sup_rate(&self, lo: f64, hi: f64) -> Option<f64> {
        match self {
            PyCoag::Builtin(k) => k.sup_rate(lo, hi),
            PyCoag::User(u) => u.sup.as_ref().map(|f| call_f64(f, &u.raised, (lo, hi))),
        }
    }
    fn sup_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        match self {
            PyCoag::Builtin(k) => k.sup_block(x0, x1, y0, y1),
            PyCoag::User(u) => match &u.sup_block {
                Some(f) => Some(call_f64(f, &u.raised, (x0, x1, y0, y1))),
                // the supremum over the square around the block
                None => self.sup_rate(x0.min(y0), x1.max(y1)),
            },
        }
    }
    fn inf_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        match self {
            PyCoag::Builtin(k) => k.inf_block(x0, x1, y0, y1),
            // (no squeeze for a user kernel: it changes the cost, never the draws)
            PyCoag::User(..) => 0.0,
        }
    }
    fn low_rank_is_loose(&self) -> bool {
        match self {
            PyCoag::Builtin(k) => k.low_rank_is_loose(),
            PyCoag::User(u) => u.loose,
        }
    }
    fn log_linear_blocks(&self) -> bool {
        match self {
            PyCoag::Builtin(k) => k.log_linear_blocks(),
            PyCoag::User(_) => false,
        }
    }
    fn integer_sizes(&self) -> bool {
        match self {
            PyCoag::Builtin(k) => k.integer_sizes(),
            PyCoag::User(_) => false,
        }
    }
    fn min_size(&self) -> f64 {
        match self {
            PyCoag::Builtin(k) => k.min_size(),
            PyCoag::User(_) => 0.0,
        }
    }
    fn monotone_factors(&self) -> bool {
        match self {
            PyCoag::Builtin(k) => k.monotone_factors(),
            PyCoag::User(_) => false,
        }
    }
    /// A built-in kernel's parameters; for a user kernel what it declares (its code
    /// is not stored: a checkpoint restores under any user kernel of the same shape).
    fn fingerprint(&self) -> u64 {
        match self {
            PyCoag::Builtin(k) => k.fingerprint(),
            PyCoag::User(u) => fingerprint([
                0x5553_4552, // "USER", as the C ABI's
                u.rank as u64,
                u64::from(u.exact),
                u64::from(u.majorant.is_some()),
                u64::from(u.factors.is_some()),
                u64::from(u.sup.is_some()),
                u64::from(u.sup_block.is_some()),
                u64::from(u.loose),
            ]),
        }
    }
}

/// The Python side of a user fragmentation kernel.
#[derive(Debug)]
pub(crate) struct UserFrag {
    rate: Py<PyAny>,
    inverse_piece: Py<PyAny>,
    sup_rate: Option<f64>,
    pub(crate) raised: Raised,
}

/// A fragmentation kernel as a Python sim holds it.
#[derive(Clone, Debug)]
pub(crate) enum PyFrag {
    None,
    Binary(BinaryUniform),
    User(Arc<UserFrag>),
}

impl FragmentationKernel for PyFrag {
    fn total_rate(&self, x: f64) -> f64 {
        match self {
            PyFrag::None => 0.0,
            PyFrag::Binary(b) => b.total_rate(x),
            PyFrag::User(u) => call_f64(&u.rate, &u.raised, (x,)),
        }
    }
    fn inverse_piece(&self, x: f64, v: f64) -> f64 {
        match self {
            PyFrag::None => x,
            PyFrag::Binary(b) => b.inverse_piece(x, v),
            PyFrag::User(u) => call_f64(&u.inverse_piece, &u.raised, (x, v)),
        }
    }
    fn sup_rate(&self) -> Option<f64> {
        match self {
            PyFrag::None => Some(0.0),
            PyFrag::Binary(b) => b.sup_rate(),
            PyFrag::User(u) => u.sup_rate,
        }
    }
    fn is_none(&self) -> bool {
        matches!(self, PyFrag::None)
    }
    fn fingerprint(&self) -> u64 {
        match self {
            PyFrag::None => 0,
            PyFrag::Binary(b) => b.fingerprint(),
            PyFrag::User(u) => {
                fingerprint([0x5553_4552, u.sup_rate.map_or(u64::MAX, f64::to_bits)])
            }
        }
    }
}

/// A built-in kernel of core's table: a coagulation kernel, a temperature model or a
/// gas, by name and parameters (`coagula.kernels()` lists them with their units).
///
/// >>> import coagula
/// >>> k = coagula.Kernel("additive", coefficient=1.5)
/// >>> k.rate(1.0, 3.0)
/// 6.0
#[pyclass(module = "coagula", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Kernel {
    name: &'static str,
    params: Vec<(&'static str, f64)>,
    pub(crate) built: Builtin,
}

#[pymethods]
impl Kernel {
    #[new]
    #[pyo3(signature = (name, **params))]
    fn new(name: &str, params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let info = builtin::find(name).ok_or_else(|| {
            py_err(coagula_core::Error::UnknownName {
                what: "kernel",
                known: &builtin::NAMES,
            })
        })?;
        let mut values: Vec<(&'static str, f64)> = Vec::new();
        if let Some(d) = params {
            for (k, v) in d.iter() {
                let key: String = k.extract()?;
                let key = key.replace('_', "-");
                let p = info.params.iter().find(|p| p.name == key).ok_or_else(|| {
                    let names: Vec<String> = info
                        .params
                        .iter()
                        .map(|p| p.name.replace('-', "_"))
                        .collect();
                    PyValueError::new_err(format!(
                        "kernel {}: {} is not a parameter of this kernel (it takes {})",
                        info.name,
                        key.replace('-', "_"),
                        if names.is_empty() {
                            "none".into()
                        } else {
                            names.join(", ")
                        }
                    ))
                })?;
                let x: f64 = v.extract().map_err(|_| {
                    PyValueError::new_err(format!(
                        "kernel {}: {} must be a real number",
                        info.name,
                        p.name.replace('-', "_")
                    ))
                })?;
                values.push((p.name, x));
            }
        }
        let built = builtin::make(info.name, &values).map_err(py_err)?;
        Ok(Kernel {
            name: info.name,
            params: values,
            built,
        })
    }

    /// The name in core's table.
    #[getter]
    fn name(&self) -> &'static str {
        self.name
    }

    /// The parameters given (the others take their defaults).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.params {
            d.set_item(k.replace('-', "_"), v)?;
        }
        Ok(d)
    }

    /// `K(x, y)` of a coagulation kernel (`ValueError` for a temperature model or a
    /// gas, which have no single rate).
    fn rate(&self, x: f64, y: f64) -> PyResult<f64> {
        match self.built {
            Builtin::Coagulation(k) => Ok(k.rate(x, y)),
            _ => Err(PyValueError::new_err(format!(
                "kernel {}: a temperature model or a gas has no single rate K(x, y)",
                self.name
            ))),
        }
    }

    fn __repr__(&self) -> String {
        let p: Vec<String> = self
            .params
            .iter()
            .map(|(k, v)| format!(", {}={v:?}", k.replace('-', "_")))
            .collect();
        format!("coagula.Kernel({:?}{})", self.name, p.concat())
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let me = slf.get();
        let f = py.import("coagula._coagula")?.getattr("_kernel")?;
        let params: Vec<(String, f64)> =
            me.params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        Ok((
            f,
            PyTuple::new(
                py,
                [
                    me.name.into_pyobject(py)?.into_any(),
                    params.into_pyobject(py)?.into_any(),
                ],
            )?,
        ))
    }
}

/// Unpickles a `Kernel`.
#[pyfunction]
fn _kernel(name: &str, params: Vec<(String, f64)>) -> PyResult<Kernel> {
    let info = builtin::find(name).ok_or_else(|| PyValueError::new_err("unknown kernel"))?;
    let mut values = Vec::new();
    for (k, v) in params {
        let p = info
            .params
            .iter()
            .find(|p| p.name == k)
            .ok_or_else(|| PyValueError::new_err("unknown kernel parameter"))?;
        values.push((p.name, v));
    }
    let built = builtin::make(info.name, &values).map_err(py_err)?;
    Ok(Kernel {
        name: info.name,
        params: values,
        built,
    })
}

/// A coagulation kernel from Python callables: `rate(x, y) -> float` (symmetric,
/// ≥ 0) and the bounds the chosen scheme needs — `majorant(x)` with
/// `K(x, y) ≤ h(x) h(y)` (mass flow, MFA, DSA), `factors(x) -> (a, b)` of a rank-`rank`
/// bound `K ≤ A + Aᵀ`, `A(x, y) = Σ a_k(x) b_k(y)` (the low-rank schemes; `exact=True`
/// when it is an equality), `sup(lo, hi)` of K on a square (acceptance–rejection),
/// `sup_block(x0, x1, y0, y1)` of K over `x0 ≤ x ≤ x1`, `y0 ≤ y ≤ y1` (block
/// majorants: `lowrank-blocks`, and `lowrank` when it picks them; without it they use
/// `sup` on the square around a block), and `low_rank_loose=True` when the low-rank bound
/// is far above the kernel somewhere (`lowrank` then picks block majorants if it has
/// `sup_block` or `sup`; docs/design/block-majorants.md). A bound the kernel exceeds at
/// run time is a `CoagulaError`.
///
/// >>> import coagula
/// >>> # x + y = A + Aᵀ with A(x, y) = x · 1: rank 1, exact
/// >>> k = coagula.UserKernel(lambda x, y: x + y, rank=1,
/// ...                        factors=lambda x: ([x], [1.0]), exact=True)
/// >>> k.rank
/// 1
#[pyclass(module = "coagula", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct UserKernel {
    pub(crate) fns: Arc<UserFns>,
}

#[pymethods]
impl UserKernel {
    #[new]
    #[pyo3(signature = (rate, *, majorant=None, rank=0, factors=None, exact=false, sup=None,
        sup_block=None, low_rank_loose=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rate: Bound<'_, PyAny>,
        majorant: Option<Bound<'_, PyAny>>,
        rank: usize,
        factors: Option<Bound<'_, PyAny>>,
        exact: bool,
        sup: Option<Bound<'_, PyAny>>,
        sup_block: Option<Bound<'_, PyAny>>,
        low_rank_loose: bool,
    ) -> PyResult<Self> {
        let callable = |name: &str, f: &Bound<'_, PyAny>| {
            if f.is_callable() {
                Ok(f.clone().unbind())
            } else {
                Err(PyValueError::new_err(format!(
                    "UserKernel: {name} must be callable"
                )))
            }
        };
        if rank > MAX_RANK {
            return Err(PyValueError::new_err(format!(
                "UserKernel: rank {rank} is above the largest, {MAX_RANK}"
            )));
        }
        if (rank > 0) != factors.is_some() {
            return Err(PyValueError::new_err(
                "UserKernel: give factors with a rank > 0, or neither",
            ));
        }
        if exact && rank == 0 {
            return Err(PyValueError::new_err(
                "UserKernel: exact=True says the rank-R bound equals the kernel: give rank and factors",
            ));
        }
        Ok(UserKernel {
            fns: Arc::new(UserFns {
                rate: callable("rate", &rate)?,
                majorant: majorant.map(|f| callable("majorant", &f)).transpose()?,
                factors: factors.map(|f| callable("factors", &f)).transpose()?,
                rank,
                exact,
                sup: sup.map(|f| callable("sup", &f)).transpose()?,
                sup_block: sup_block.map(|f| callable("sup_block", &f)).transpose()?,
                loose: low_rank_loose,
                raised: Raised,
            }),
        })
    }

    /// The rank of the declared low-rank bound (0: none).
    #[getter]
    fn rank(&self) -> usize {
        self.fns.rank
    }

    /// `K(x, y)` (calls `rate`).
    fn rate(&self, py: Python<'_>, x: f64, y: f64) -> PyResult<f64> {
        self.fns.rate.call1(py, (x, y))?.extract(py)
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> Reduced<'py, (Bound<'py, PyAny>, Bound<'py, PyDict>)> {
        let cls = py.import("coagula._coagula")?.getattr("_user_kernel")?;
        let u = &self.fns;
        let kw = PyDict::new(py);
        kw.set_item("majorant", u.majorant.as_ref().map(|f| f.bind(py)))?;
        kw.set_item("rank", u.rank)?;
        kw.set_item("factors", u.factors.as_ref().map(|f| f.bind(py)))?;
        kw.set_item("exact", u.exact)?;
        kw.set_item("sup", u.sup.as_ref().map(|f| f.bind(py)))?;
        kw.set_item("sup_block", u.sup_block.as_ref().map(|f| f.bind(py)))?;
        kw.set_item("low_rank_loose", u.loose)?;
        Ok((cls, (u.rate.bind(py).clone(), kw)))
    }
}

/// Unpickles a `UserKernel` (the rate and the other arguments as a dict).
#[pyfunction]
#[pyo3(signature = (rate, kw))]
fn _user_kernel(rate: Bound<'_, PyAny>, kw: &Bound<'_, PyDict>) -> PyResult<UserKernel> {
    let get = |k: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        Ok(kw.get_item(k)?.filter(|v| !v.is_none()))
    };
    UserKernel::new(
        rate.clone(),
        get("majorant")?,
        get("rank")?.map(|v| v.extract()).transpose()?.unwrap_or(0),
        get("factors")?,
        get("exact")?
            .map(|v| v.extract())
            .transpose()?
            .unwrap_or(false),
        get("sup")?,
        get("sup_block")?,
        get("low_rank_loose")?
            .map(|v| v.extract())
            .transpose()?
            .unwrap_or(false),
    )
}

/// A fragmentation kernel: `Fragmentation.binary_uniform(rate)` (`F(x, y) = 2λ/(x+y)`,
/// Lécot et al. 2019 §4) or Python callables `rate(x)` (the total break-up rate) and
/// `inverse_piece(x, u)` (the followed piece's size for a uniform u in (0, 1]), with
/// `sup_rate` the supremum of the rate if known (checked: a rate above it is a
/// `CoagulaError`). Only massflow, mfa and dsa break particles.
#[pyclass(module = "coagula", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Fragmentation {
    pub(crate) f: PyFrag,
}

#[pymethods]
impl Fragmentation {
    #[new]
    #[pyo3(signature = (rate, inverse_piece, *, sup_rate=None))]
    fn new(
        rate: Bound<'_, PyAny>,
        inverse_piece: Bound<'_, PyAny>,
        sup_rate: Option<f64>,
    ) -> PyResult<Self> {
        if !rate.is_callable() || !inverse_piece.is_callable() {
            return Err(PyValueError::new_err(
                "Fragmentation: rate and inverse_piece must be callable",
            ));
        }
        if let Some(s) = sup_rate
            && !(s >= 0.0 && s.is_finite())
        {
            return Err(PyValueError::new_err(format!(
                "Fragmentation: sup_rate must be finite and >= 0 (got {s})"
            )));
        }
        Ok(Fragmentation {
            f: PyFrag::User(Arc::new(UserFrag {
                rate: rate.unbind(),
                inverse_piece: inverse_piece.unbind(),
                sup_rate,
                raised: Raised,
            })),
        })
    }

    /// Binary uniform break-up at rate λ: `F(x, y) = 2λ/(x + y)`.
    #[staticmethod]
    fn binary_uniform(rate: f64) -> PyResult<Self> {
        Ok(Fragmentation {
            f: PyFrag::Binary(BinaryUniform::new(rate).map_err(py_err)?),
        })
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        match &self.f {
            PyFrag::Binary(b) => {
                let f = py
                    .import("coagula._coagula")?
                    .getattr("Fragmentation")?
                    .getattr("binary_uniform")?;
                Ok((f, PyTuple::new(py, [b.lambda()])?))
            }
            PyFrag::User(u) => {
                let f = py
                    .import("coagula._coagula")?
                    .getattr("_user_fragmentation")?;
                let args =
                    (u.rate.bind(py), u.inverse_piece.bind(py), u.sup_rate).into_pyobject(py)?;
                Ok((f, args))
            }
            PyFrag::None => Err(PyValueError::new_err("no fragmentation")),
        }
    }
}

/// Unpickles a user `Fragmentation`.
#[pyfunction]
fn _user_fragmentation(
    rate: Bound<'_, PyAny>,
    inverse_piece: Bound<'_, PyAny>,
    sup_rate: Option<f64>,
) -> PyResult<Fragmentation> {
    Fragmentation::new(rate, inverse_piece, sup_rate)
}

/// The built-in kernels of core's table, as dicts: `name`, `family` (`coagulation`,
/// `temperature` or `gas`), `formula`, `source`, `units` (`""`: dimensionless, time
/// in the kernel's units) and `params` (each `name`, `default` or None when required,
/// `unit` and `doc`).
#[pyfunction]
fn kernels(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    BUILTINS
        .iter()
        .map(|b| {
            let d = PyDict::new(py);
            d.set_item("name", b.name)?;
            d.set_item("family", format!("{:?}", b.family).to_lowercase())?;
            d.set_item("formula", b.formula)?;
            d.set_item("source", b.source)?;
            d.set_item("units", b.units)?;
            let params = b
                .params
                .iter()
                .map(|p| {
                    let q = PyDict::new(py);
                    q.set_item("name", p.name.replace('-', "_"))?;
                    q.set_item("default", p.default)?;
                    q.set_item("unit", p.unit)?;
                    q.set_item("doc", p.doc)?;
                    Ok(q)
                })
                .collect::<PyResult<Vec<_>>>()?;
            d.set_item("params", params)?;
            Ok(d)
        })
        .collect()
}

/// The physics a `kernel=` argument names: a `Kernel`, a `UserKernel` or a built-in
/// kernel's name (its defaults), with the fragmentation.
pub(crate) fn model_of(
    kernel: &Bound<'_, PyAny>,
    frag: PyFrag,
    scheme: Option<&coagula_core::scheme::facade::SchemeInfo>,
) -> PyResult<Model<PyCoag, PyFrag>> {
    // a built-in as the scheme runs it (core's rule, which the CLI applies too)
    let narrow = |b: Builtin| match scheme {
        Some(info) => info.runs(b).map_err(py_err),
        None => Ok(b),
    };
    if let Ok(k) = kernel.cast::<Kernel>() {
        return Model::of_builtin(narrow(k.get().built)?, PyCoag::Builtin, frag).map_err(py_err);
    }
    if let Ok(u) = kernel.cast::<UserKernel>() {
        return Ok(Model::coagulation(PyCoag::User(u.get().fns.clone()), frag));
    }
    if let Ok(name) = kernel.extract::<String>() {
        let b = builtin::make(&name, &[]).map_err(py_err)?;
        return Model::of_builtin(narrow(b)?, PyCoag::Builtin, frag).map_err(py_err);
    }
    Err(PyValueError::new_err(
        "kernel must be a coagula.Kernel, a coagula.UserKernel or a built-in kernel's name (coagula.kernels() lists them)",
    ))
}

/// The coagulation kernel a `set_kernel` argument names.
pub(crate) fn coagulation_of(
    kernel: &Bound<'_, PyAny>,
    scheme: Option<&coagula_core::scheme::facade::SchemeInfo>,
) -> PyResult<PyCoag> {
    match model_of(kernel, PyFrag::None, scheme)? {
        Model::Coagulation { kernel, .. } => Ok(kernel),
        _ => Err(PyValueError::new_err(
            "kernel: a temperature model or a gas is not a coagulation kernel",
        )),
    }
}

/// The fragmentation a `fragmentation=` argument names (None: none).
pub(crate) fn fragmentation_of(frag: Option<&Bound<'_, PyAny>>) -> PyResult<PyFrag> {
    match frag {
        None => Ok(PyFrag::None),
        Some(f) if f.is_none() => Ok(PyFrag::None),
        Some(f) => f
            .cast::<Fragmentation>()
            .map(|f| f.get().f.clone())
            .map_err(|_| {
                PyValueError::new_err("fragmentation must be a coagula.Fragmentation (or None)")
            }),
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Kernel>()?;
    m.add_class::<UserKernel>()?;
    m.add_class::<Fragmentation>()?;
    m.add_function(wrap_pyfunction!(kernels, m)?)?;
    m.add_function(wrap_pyfunction!(_kernel, m)?)?;
    m.add_function(wrap_pyfunction!(_user_kernel, m)?)?;
    m.add_function(wrap_pyfunction!(_user_fragmentation, m)?)?;
    Ok(())
}
