//! `coagula._coagula`: the Python extension module. It translates: every scheme,
//! kernel, option and exact solution is core's registry and tables, every scenario
//! run is the CLI library's, and this crate turns them into Python objects, numpy
//! arrays and exceptions (the pure-Python part of the package, `python/coagula`,
//! adds the xarray view of a run).

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyMemoryError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod arrays;
mod exact;
mod initial;
mod kernel;
mod langevin;
mod process;
mod report;
mod scenario;
mod sim;

use coagula_core::Error;
use coagula_core::scheme::facade::{KEYS, Kind};
use coagula_core::scheme::registry;

create_exception!(
    coagula,
    CoagulaError,
    PyException,
    "A failure of a run that is not a bad argument or a lack of memory: a rate that is NaN or negative, a declared bound the kernel exceeded, a checkpoint that does not restore, a call that re-entered its simulation."
);

/// Core's error as a Python exception with core's message: `MemoryError` for a
/// capacity, `ValueError` for a bad or unsupported argument, `CoagulaError` for the
/// rest.
pub(crate) fn py_err(e: Error) -> PyErr {
    let msg = e.to_string();
    match e {
        // (as the C ABI's COAG_CAPACITY: a size or count past what memory holds)
        Error::Capacity { .. } | Error::Overflow { .. } => PyMemoryError::new_err(msg),
        Error::InvalidRate { .. }
        | Error::BoundExceeded { .. }
        | Error::Checkpoint { .. }
        | Error::CheckpointOption { .. } => CoagulaError::new_err(msg),
        _ => PyValueError::new_err(msg),
    }
}

/// Runs `f` under a budget of `work_limit` units (none: unlimited) whose cancellation
/// poll checks for Ctrl-C, with this thread's callback slot cleared first (a detached
/// call's stepping: `Simulation` and `Langevin`). Returns `f`'s result and the signal's
/// exception if one stopped it.
pub(crate) fn with_signals<R>(
    work_limit: Option<u64>,
    f: impl FnOnce(&mut coagula_core::scheme::Budget<'_>) -> R,
) -> (R, Option<PyErr>) {
    let mut signal: Option<PyErr> = None;
    let mut cancel = || {
        Python::attach(|py| match py.check_signals() {
            Ok(()) => false,
            Err(e) => {
                signal = Some(e);
                true
            }
        })
    };
    let mut budget =
        coagula_core::scheme::Budget::work(work_limit.unwrap_or(u64::MAX)).with_cancel(&mut cancel);
    kernel::clear_raised();
    let out = f(&mut budget);
    (out, signal)
}

/// Every scheme of the registry with what it takes, as dicts: `name`, `paper`,
/// `summary`, `model` (`coagulation`, `temperature` or `gas`), `inits` (the initial
/// states it builds from), `samples` (what a list of sizes is samples of),
/// `fragmentation`, `options` (besides the general ones), `memory` (`fixed` or
/// `growing`), `observables` (named ones besides the moments) and `law`.
///
/// >>> import coagula
/// >>> [s["name"] for s in coagula.schemes()][:2]
/// ['massflow', 'lowrank']
#[pyfunction]
fn schemes(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    registry::SCHEMES
        .iter()
        .map(|s| {
            let d = PyDict::new(py);
            d.set_item("name", s.name)?;
            d.set_item("paper", s.paper)?;
            d.set_item("summary", s.summary)?;
            d.set_item("model", format!("{:?}", s.model).to_lowercase())?;
            let inits: Vec<String> = s
                .inits
                .iter()
                .map(|k| format!("{k:?}").to_lowercase())
                .collect();
            d.set_item("inits", inits)?;
            d.set_item("samples", format!("{:?}", s.sizes).to_lowercase())?;
            d.set_item("fragmentation", s.fragmentation)?;
            let opts: Vec<String> = s.options.iter().map(|o| o.replace('-', "_")).collect();
            d.set_item("options", opts)?;
            d.set_item("memory", format!("{:?}", s.memory).to_lowercase())?;
            d.set_item("observables", s.observables.to_vec())?;
            d.set_item("law", format!("{:?}", s.law))?;
            Ok(d)
        })
        .collect()
}

/// Every option a `Simulation` takes as a keyword, as dicts: `name` (the keyword:
/// core's key with `_` for `-`), `kind` (`real`, `count`, `flag` or the names it
/// takes), `default` and `doc`.
#[pyfunction]
fn options(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    KEYS.iter()
        .map(|k| {
            let d = PyDict::new(py);
            d.set_item("name", k.name.replace('-', "_"))?;
            match k.kind {
                Kind::Real => d.set_item("kind", "real")?,
                Kind::Count => d.set_item("kind", "count")?,
                Kind::Flag => d.set_item("kind", "flag")?,
                Kind::Name(names) => d.set_item("kind", names.to_vec())?,
            }
            d.set_item("default", k.default)?;
            d.set_item("doc", k.doc)?;
            Ok(d)
        })
        .collect()
}

/// The Student t threshold (in standard errors) of a two-sided test at false-alarm
/// probability `alpha` with `dof` degrees of freedom (core's
/// `observe::student_t_threshold`): what the tests compare replica means with, at
/// core's `TEST_ALPHA` (docs/design/statistical-tests.md).
#[pyfunction]
#[pyo3(signature = (dof, alpha=coagula_core::observe::TEST_ALPHA))]
fn _student_t_threshold(dof: u64, alpha: f64) -> f64 {
    coagula_core::observe::student_t_threshold(alpha, dof)
}

#[pymodule]
fn _coagula(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("CoagulaError", m.py().get_type::<CoagulaError>())?;
    m.add_function(wrap_pyfunction!(schemes, m)?)?;
    m.add_function(wrap_pyfunction!(options, m)?)?;
    m.add_function(wrap_pyfunction!(_student_t_threshold, m)?)?;
    kernel::register(m)?;
    initial::register(m)?;
    sim::register(m)?;
    langevin::register(m)?;
    exact::register(m)?;
    scenario::register(m)?;
    Ok(())
}
