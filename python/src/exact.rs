//! Core's exact solutions (`coagula_core::exact`) as `coagula.exact.Solution`, the
//! time argument a float or a numpy array.

use crate::py_err;
use coagula_core::exact::{Exact, NAMES};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

/// An exact solution of the Smoluchowski equation by name (`coagula.exact.NAMES`),
/// for kernel coefficient `coefficient` from unit concentration (Eibeck & Wagner
/// 2000 §6; Lécot et al. 2019 §4; see `coagula exact`): moments, number densities
/// `c_k(t)` over integer sizes, densities `c(x, t)` over real sizes, gel time and gel
/// mass. A time argument may be an array; the result is then an array.
///
/// >>> from coagula.exact import Solution
/// >>> round(Solution("golovin").moment(0, 1.0), 6)   # exp(-1)
/// 0.367879
#[pyclass(module = "coagula.exact", name = "Solution", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Solution {
    name: String,
    coefficient: f64,
    e: Exact,
}

/// `f(t)` for a float, or elementwise for a 1-D array of times.
fn over_t<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    f: impl Fn(f64) -> coagula_core::Result<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    if let Ok(x) = t.extract::<f64>() {
        return Ok(f(x).map_err(py_err)?.into_pyobject(py)?.into_any());
    }
    let ts: Vec<f64> = match t.extract::<PyReadonlyArray1<'_, f64>>() {
        Ok(a) => a.as_array().to_vec(),
        Err(_) => crate::arrays::reals_arg("t", t)?,
    };
    let v = ts
        .iter()
        .map(|&x| f(x))
        .collect::<coagula_core::Result<Vec<f64>>>()
        .map_err(py_err)?;
    Ok(PyArray1::from_vec(py, v).into_any())
}

#[pymethods]
impl Solution {
    #[new]
    #[pyo3(signature = (name, coefficient=1.0))]
    fn new(name: &str, coefficient: f64) -> PyResult<Self> {
        let e = Exact::named(name)
            .and_then(|e| e.with_coefficient(coefficient))
            .map_err(py_err)?;
        Ok(Solution {
            name: name.to_string(),
            coefficient,
            e,
        })
    }

    /// The moment `M_m(t)` (m = 0..3).
    fn moment<'py>(
        &self,
        py: Python<'py>,
        m: u32,
        t: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        over_t(py, t, |x| self.e.moment(m, x))
    }

    /// `c_k(t)`, the concentration of size k (solutions over integer sizes).
    fn number_density<'py>(
        &self,
        py: Python<'py>,
        k: u64,
        t: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        over_t(py, t, |x| self.e.number_density(k, x))
    }

    /// `c(x, t)` (solutions over real sizes).
    fn density<'py>(
        &self,
        py: Python<'py>,
        x: f64,
        t: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        over_t(py, t, |s| self.e.density(x, s))
    }

    /// The gel mass (0 before the gel time).
    fn gel_mass<'py>(&self, py: Python<'py>, t: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        over_t(py, t, |x| self.e.gel_mass(x))
    }

    /// The gel time, or None for a solution that does not gel.
    #[getter]
    fn gel_time(&self) -> Option<f64> {
        self.e.gel_time()
    }

    /// Whether its sizes are real (`density`) rather than integers (`number_density`).
    #[getter]
    fn continuous(&self) -> bool {
        self.e.is_continuous()
    }

    fn __repr__(&self) -> String {
        format!(
            "coagula.exact.Solution({:?}, coefficient={:?})",
            self.name, self.coefficient
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, f64))> {
        let cls = py.import("coagula._coagula")?.getattr("Solution")?;
        Ok((cls, (self.name.clone(), self.coefficient)))
    }
}

/// The closed-form temperature family of Osinsky 2023 §4 (collision rate
/// `c (i j)^{γ}`-type, docs/design/temperature.md) from monomers at number
/// concentration `n0` and temperature `t0`: `(number, mean_temperature)` at time `t`.
#[pyfunction]
#[pyo3(signature = (t, *, c=1.0, gamma=0.5, n0=1.0, t0=1.0))]
fn temperature_closed_form(t: f64, c: f64, gamma: f64, n0: f64, t0: f64) -> PyResult<(f64, f64)> {
    let m = coagula_core::kernel::temperature::ClosedForm::new(c, gamma).map_err(py_err)?;
    for (name, v) in [("t", t), ("n0", n0), ("t0", t0)] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{name} must be finite and >= 0 (got {v})"
            )));
        }
    }
    let e = m.exact(n0, t0, t);
    Ok((e.number(), e.mean_temperature()))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Solution>()?;
    m.add_class::<PySectional>()?;
    m.add_function(wrap_pyfunction!(temperature_closed_form, m)?)?;
    m.add("EXACT_NAMES", NAMES.to_vec())?;
    Ok(())
}

/// The fixed-pivot sectional reference of core (Kumar & Ramkrishna 1996; see
/// docs/design/processes.md): numbers per unit volume at pivots 1..`dense`, then a
/// geometric grid of ratio `ratio` to `largest`, under `kernel`, with an optional
/// source (`source=(rate, size)`), removal `removal(x)` and growth `growth(x)` (Python
/// callables evaluated once per pivot). RK4 in time with steps of at most `dt`.
///
/// >>> from coagula.exact import Sectional, Solution
/// >>> s = Sectional("constant", dense=32, largest=1e5, ratio=1.1)
/// >>> s.set_number(0, 1.0)
/// >>> s.advance_to(2.0, dt=1e-3)
/// >>> abs(s.moment(0) - Solution("constant").moment(0, 2.0)) < 1e-10
/// True
#[pyclass(module = "coagula.exact", name = "Sectional", frozen)]
pub struct PySectional {
    s: std::sync::Mutex<coagula_core::exact::Sectional<crate::kernel::PyCoag>>,
}

#[pymethods]
impl PySectional {
    #[new]
    #[pyo3(signature = (kernel, *, dense=32, largest=1e6, ratio=1.1, source=None, removal=None, growth=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        kernel: &Bound<'_, PyAny>,
        dense: u64,
        largest: f64,
        ratio: f64,
        source: Option<(f64, f64)>,
        removal: Option<Bound<'_, PyAny>>,
        growth: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        use coagula_core::exact::Sectional;
        let k = crate::kernel::coagulation_of(kernel, None)?;
        let grid =
            Sectional::<crate::kernel::PyCoag>::grid(dense, largest, ratio).map_err(py_err)?;
        let mut s = Sectional::new(k, grid).map_err(py_err)?;
        if let Some((rate, size)) = source {
            s = s.with_source(rate, size).map_err(py_err)?;
        }
        // a callable per pivot: errors in it come back as NaN, which core refuses
        let call = |f: &Bound<'_, PyAny>, x: f64| f.call1((x,)).and_then(|v| v.extract::<f64>());
        if let Some(f) = removal {
            let mut err = None;
            s = s
                .with_removal(|x| {
                    call(&f, x).unwrap_or_else(|e| {
                        err.get_or_insert(e);
                        f64::NAN
                    })
                })
                .map_err(|e| err.take().unwrap_or_else(|| py_err(e)))?;
        }
        if let Some(f) = growth {
            let mut err = None;
            s = s
                .with_growth(|x| {
                    call(&f, x).unwrap_or_else(|e| {
                        err.get_or_insert(e);
                        f64::NAN
                    })
                })
                .map_err(|e| err.take().unwrap_or_else(|| py_err(e)))?;
        }
        Ok(PySectional {
            s: std::sync::Mutex::new(s),
        })
    }

    /// Sets the number per unit volume at pivot `i`.
    fn set_number(&self, i: usize, number: f64) -> PyResult<()> {
        self.lock()?.set_number(i, number).map_err(py_err)
    }

    /// Adds `number` per unit volume at size `size` (split between the pivots around it).
    fn add_at(&self, size: f64, number: f64) -> PyResult<()> {
        self.lock()?.add_at(size, number).map_err(py_err)
    }

    /// Integrates to `t` (interpreter detached; in pieces of about 1000 steps, between
    /// which Ctrl-C stops it with `KeyboardInterrupt`, the solution at the piece's end).
    #[pyo3(signature = (t, *, dt))]
    fn advance_to(&self, py: Python<'_>, t: f64, dt: f64) -> PyResult<()> {
        let now = self.lock()?.time();
        let pieces = if t > now && dt > 0.0 && t.is_finite() {
            ((t - now) / dt / 1000.0).ceil().clamp(1.0, 1e6)
        } else {
            1.0
        };
        for k in 1..=pieces as u64 {
            let until = if k == pieces as u64 {
                t
            } else {
                now + (t - now) * (k as f64 / pieces)
            };
            py.detach(|| {
                self.lock()
                    .and_then(|mut s| s.advance_to(until, dt).map_err(py_err))
            })?;
            py.check_signals()?;
        }
        Ok(())
    }

    /// `M_k` per unit volume.
    fn moment(&self, k: f64) -> PyResult<f64> {
        Ok(self.lock()?.moment(k))
    }

    /// The number per unit volume at pivots in `[a, b)`.
    fn concentration(&self, a: f64, b: f64) -> PyResult<f64> {
        Ok(self.lock()?.concentration(a, b))
    }

    /// The time.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.lock()?.time())
    }

    /// The pivots and the numbers per unit volume at them.
    fn state<'py>(
        &self,
        py: Python<'py>,
    ) -> crate::sim::Columns<'py, PyArray1<f64>, PyArray1<f64>> {
        let s = self.lock()?;
        Ok((
            PyArray1::from_vec(py, s.pivots().to_vec()),
            PyArray1::from_vec(py, s.numbers().to_vec()),
        ))
    }

    /// What the processes did per unit volume (injected, removed, grown, lost past the
    /// grid), as a dict.
    fn books<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let b = self.lock()?.books();
        let d = pyo3::types::PyDict::new(py);
        d.set_item("injected_number", b.injected_number)?;
        d.set_item("injected_mass", b.injected_mass)?;
        d.set_item("removed_number", b.removed_number)?;
        d.set_item("removed_mass", b.removed_mass)?;
        d.set_item("grown_mass", b.grown_mass)?;
        d.set_item("lost_number", b.lost_number)?;
        d.set_item("lost_mass", b.lost_mass)?;
        Ok(d)
    }
}

impl PySectional {
    fn lock(
        &self,
    ) -> PyResult<std::sync::MutexGuard<'_, coagula_core::exact::Sectional<crate::kernel::PyCoag>>>
    {
        self.s.try_lock().map_err(|_| {
            crate::CoagulaError::new_err("this Sectional is already in a call (another thread)")
        })
    }
}
