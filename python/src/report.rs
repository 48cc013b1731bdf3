//! `coagula.StepReport`: what a call did (the core's `StepReport`), read as attributes
//! or as a dict.

use coagula_core::scheme::StepReport;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What a call did (or every call so far: `Simulation.totals`): its fields are
/// attributes, and it reads like a dict (`report["events"]`, `dict(report)`).
#[pyclass(module = "coagula", name = "StepReport", frozen)]
#[derive(Clone, Debug)]
pub struct Report(pub(crate) StepReport);

/// The report's fields, in order.
const FIELDS: [&str; 10] = [
    "time",
    "events",
    "proposals",
    "rejections",
    "bound_violations",
    "clipped",
    "doublings",
    "removed",
    "bounces",
    "interrupted",
];

impl Report {
    fn field<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.0;
        Ok(match name {
            "time" => r.time.into_pyobject(py)?.into_any(),
            "events" => r.events.into_pyobject(py)?.into_any(),
            "proposals" => r.proposals.into_pyobject(py)?.into_any(),
            "rejections" => r.rejections.into_pyobject(py)?.into_any(),
            "bound_violations" => r.bound_violations.into_pyobject(py)?.into_any(),
            "clipped" => r.clipped.into_pyobject(py)?.into_any(),
            "doublings" => r.doublings.into_pyobject(py)?.into_any(),
            "removed" => r.removed.into_pyobject(py)?.into_any(),
            "bounces" => r.bounces.into_pyobject(py)?.into_any(),
            "interrupted" => r.interrupted.into_pyobject(py)?.to_owned().into_any(),
            _ => {
                return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                    "{name}: a step report has {}",
                    FIELDS.join(", ")
                )));
            }
        })
    }
}

#[pymethods]
impl Report {
    /// The time reached.
    #[getter]
    fn time(&self) -> f64 {
        self.0.time
    }
    /// Coagulation (and break-up) events.
    #[getter]
    fn events(&self) -> u64 {
        self.0.events
    }
    /// Proposals drawn (event-driven schemes).
    #[getter]
    fn proposals(&self) -> u64 {
        self.0.proposals
    }
    /// Proposals rejected.
    #[getter]
    fn rejections(&self) -> u64 {
        self.0.rejections
    }
    /// Proposals whose rate exceeded the bound (counted, or an error when strict).
    #[getter]
    fn bound_violations(&self) -> u64 {
        self.0.bound_violations
    }
    /// Probabilities clipped to 1 (time-stepped schemes).
    #[getter]
    fn clipped(&self) -> u64 {
        self.0.clipped
    }
    /// Particle doublings.
    #[getter]
    fn doublings(&self) -> u64 {
        self.0.doublings
    }
    /// Particles removed.
    #[getter]
    fn removed(&self) -> u64 {
        self.0.removed
    }
    /// Collisions that bounced (temperature and gas schemes).
    #[getter]
    fn bounces(&self) -> u64 {
        self.0.bounces
    }
    /// Whether a work limit or Ctrl-C stopped the call before its time.
    #[getter]
    fn interrupted(&self) -> bool {
        self.0.interrupted
    }
    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, key)
    }
    fn keys(&self) -> Vec<&'static str> {
        FIELDS.to_vec()
    }
    fn __len__(&self) -> usize {
        FIELDS.len()
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<Report>().is_ok_and(|o| o.get().0 == self.0)
    }
    /// The fields as a dict.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for f in FIELDS {
            d.set_item(f, self.field(py, f)?)?;
        }
        Ok(d)
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("coagula.StepReport({})", self.as_dict(py)?.repr()?))
    }
}
