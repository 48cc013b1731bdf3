//! Processes beside coagulation (core's `process` module) as Python values: a source as
//! a dict (`rate`, `kind` and the distribution's keys, as a scenario's `[source]`),
//! removal and growth as `(coefficient, exponent)` or a coefficient alone (exponent 0),
//! the books as a dict. The rules stay in core.

use crate::py_err;
use coagula_core::initial::Distribution;
use coagula_core::process::{Books, Processes, Source, UserRate};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

fn number(d: &Bound<'_, PyDict>, key: &str) -> PyResult<Option<f64>> {
    match d.get_item(key)? {
        None => Ok(None),
        Some(v) => Ok(Some(v.extract::<f64>().map_err(|_| {
            PyValueError::new_err(format!("source[{key:?}]: a number"))
        })?)),
    }
}

fn source_of(d: &Bound<'_, PyDict>) -> PyResult<Source> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if ![
            "rate", "kind", "size", "mean", "median", "gsd", "sizes", "times", "rates", "bound",
        ]
        .contains(&k.as_str())
        {
            return Err(PyValueError::new_err(format!(
                "source: unknown key {k:?} (rate, kind, size, mean, median, gsd, sizes, times, rates, bound)"
            )));
        }
    }
    // a rate that is a callable of the time, with its bound
    let function = match d.get_item("rate")?.filter(|f| f.is_callable()) {
        Some(f) => Some(host_rate("source", f.unbind(), d)?),
        None => None,
    };
    if function.is_none() && d.contains("bound")? {
        return Err(PyValueError::new_err(
            "source: \"bound\" goes with a callable \"rate\"",
        ));
    }
    let rate = match function {
        Some(_) => 0.0,
        None => {
            number(d, "rate")?.ok_or_else(|| PyValueError::new_err("source: missing \"rate\""))?
        }
    };
    let kind: String = match d.get_item("kind")? {
        Some(k) => k.extract()?,
        None => "monodisperse".into(),
    };
    let need = |key: &str| -> PyResult<f64> {
        number(d, key)?.ok_or_else(|| PyValueError::new_err(format!("source: missing {key:?}")))
    };
    let sizes = match kind.as_str() {
        "monodisperse" => Distribution::Monodisperse {
            size: number(d, "size")?.unwrap_or(1.0),
        },
        "exponential" => Distribution::Exponential {
            mean: need("mean")?,
        },
        "lognormal" => Distribution::Lognormal {
            median: need("median")?,
            gsd: need("gsd")?,
        },
        "sizes" => {
            let v = d
                .get_item("sizes")?
                .ok_or_else(|| PyValueError::new_err("source: missing \"sizes\""))?;
            Distribution::Sizes(crate::arrays::reals_arg("source[\"sizes\"]", &v)?)
        }
        k => {
            return Err(PyValueError::new_err(format!(
                "source: kind {k:?} (monodisperse, exponential, lognormal or sizes)"
            )));
        }
    };
    let mut source = Source::new(rate, sizes).map_err(py_err)?;
    if let Some(f) = function {
        source = source.with_rate_function(f).map_err(py_err)?;
    }
    match (d.get_item("times")?, d.get_item("rates")?) {
        (None, None) => Ok(source),
        (Some(t), Some(r)) => {
            let t = crate::arrays::reals_arg("source[\"times\"]", &t)?;
            let r = crate::arrays::reals_arg("source[\"rates\"]", &r)?;
            source.with_schedule(&t, &r).map_err(py_err)
        }
        _ => Err(PyValueError::new_err(
            "source: a schedule takes both \"times\" and \"rates\"",
        )),
    }
}

fn power_of(what: &str, v: &Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    if let Ok(c) = v.extract::<f64>() {
        return Ok((c, 0.0));
    }
    v.extract::<(f64, f64)>().map_err(|_| {
        PyValueError::new_err(format!(
            "{what}: a coefficient, (coefficient, exponent) or {{\"rate\": callable, \"bound\": b}}"
        ))
    })
}

/// A removal or growth rate given as `{"rate": callable, "bound": b}`: the callable of
/// a size, called with the interpreter attached (an exception it raises stops the call
/// that invoked it and is raised there), at most `b` at every size.
fn user_rate_of(what: &str, d: &Bound<'_, PyDict>) -> PyResult<UserRate> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if k != "rate" && k != "bound" {
            return Err(PyValueError::new_err(format!(
                "{what}: unknown key {k:?} (rate, bound)"
            )));
        }
    }
    let f = d
        .get_item("rate")?
        .filter(|f| f.is_callable())
        .ok_or_else(|| PyValueError::new_err(format!("{what}: \"rate\" a callable of the size")))?
        .unbind();
    host_rate(what, f, d)
}

/// The host's callable `f` with the dict's `"bound"`, as core's rate with a bound.
fn host_rate(what: &str, f: Py<PyAny>, d: &Bound<'_, PyDict>) -> PyResult<UserRate> {
    let bound: f64 = d
        .get_item("bound")?
        .ok_or_else(|| PyValueError::new_err(format!("{what}: missing \"bound\"")))?
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{what}: \"bound\" a number")))?;
    UserRate::new(
        move |x| crate::kernel::call_f64(&f, &crate::kernel::Raised, (x,)),
        bound,
        0,
    )
    .map_err(py_err)
}

/// What core cannot give back as Python objects: the dicts of a host's removal and
/// growth, and a source dict whose rate is a callable, as given (for `processes` and
/// pickling).
pub(crate) type Kept = [Option<Py<PyAny>>; 3];

/// The [`Kept`] objects of `set_processes`' arguments.
pub(crate) fn kept(
    source: Option<&Bound<'_, PyAny>>,
    removal: Option<&Bound<'_, PyAny>>,
    growth: Option<&Bound<'_, PyAny>>,
) -> Kept {
    let dict = |a: Option<&Bound<'_, PyAny>>| {
        a.filter(|a| a.cast::<PyDict>().is_ok())
            .map(|a| a.clone().unbind())
    };
    let callable_rate = |a: &&Bound<'_, PyAny>| {
        a.cast::<PyDict>()
            .ok()
            .and_then(|d| d.get_item("rate").ok().flatten())
            .is_some_and(|r| r.is_callable())
    };
    [
        dict(removal),
        dict(growth),
        source.filter(callable_rate).map(|a| a.clone().unbind()),
    ]
}

/// A copy of [`Kept`] objects (the same Python objects).
pub(crate) fn kept_clone(py: Python<'_>, k: &Kept) -> Kept {
    k.each_ref().map(|u| u.as_ref().map(|u| u.clone_ref(py)))
}

/// The processes of `set_processes`' arguments (`None` when all are absent).
pub(crate) fn processes_of(
    source: Option<&Bound<'_, PyAny>>,
    removal: Option<&Bound<'_, PyAny>>,
    growth: Option<&Bound<'_, PyAny>>,
    growth_step: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Processes>> {
    let mut p = Processes::default();
    if let Some(s) = source {
        let d = s
            .cast::<PyDict>()
            .map_err(|_| PyValueError::new_err("source: a dict (rate, kind, ...)"))?;
        p = p.with_source(source_of(d)?);
    }
    if let Some(r) = removal {
        if let Ok(d) = r.cast::<PyDict>() {
            p = p.with_user_removal(user_rate_of("removal", d)?);
        } else {
            let (c, e) = power_of("removal", r)?;
            p = p.with_removal(c, e).map_err(py_err)?;
        }
    }
    if let Some(g) = growth {
        if let Ok(d) = g.cast::<PyDict>() {
            p = p.with_user_growth(user_rate_of("growth", d)?);
        } else {
            let (c, e) = power_of("growth", g)?;
            p = p.with_growth(c, e).map_err(py_err)?;
        }
    }
    if let Some(h) = growth_step {
        let h: f64 = h
            .extract()
            .map_err(|_| PyValueError::new_err("growth_step: a number (a time step)"))?;
        p = p.with_growth_step(h).map_err(py_err)?;
    }
    Ok((!p.is_empty()).then_some(p))
}

/// The processes as the keyword arguments of `set_processes` (a host's functions as
/// the objects `kept` holds).
pub(crate) fn processes_dict<'py>(
    py: Python<'py>,
    p: &Processes,
    kept: &Kept,
) -> PyResult<Bound<'py, PyDict>> {
    let d = processes_values(py, p)?;
    let set = [
        ("removal", p.user_removal.is_some()),
        ("growth", p.user_growth.is_some()),
        (
            "source",
            p.source
                .as_ref()
                .is_some_and(|s| s.rate_function().is_some()),
        ),
    ];
    for ((key, is_set), u) in set.into_iter().zip(kept) {
        if let (Some(u), true) = (u, is_set) {
            d.set_item(key, u.clone_ref(py))?;
        }
    }
    Ok(d)
}

/// The processes' values (a host's function not among them).
fn processes_values<'py>(py: Python<'py>, p: &Processes) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let Some(s) = &p.source {
        let q = PyDict::new(py);
        q.set_item("rate", s.rate())?;
        match s.sizes() {
            Distribution::Monodisperse { size } => {
                q.set_item("kind", "monodisperse")?;
                q.set_item("size", *size)?;
            }
            Distribution::Exponential { mean } => {
                q.set_item("kind", "exponential")?;
                q.set_item("mean", *mean)?;
            }
            Distribution::Lognormal { median, gsd } => {
                q.set_item("kind", "lognormal")?;
                q.set_item("median", *median)?;
                q.set_item("gsd", *gsd)?;
            }
            Distribution::Sizes(x) => {
                q.set_item("kind", "sizes")?;
                q.set_item("sizes", x.clone())?;
            }
            _ => {
                return Err(PyValueError::new_err(
                    "source: a distribution Python cannot name",
                ));
            }
        }
        if !s.schedule().is_empty() {
            let (t, r): (Vec<f64>, Vec<f64>) = s.schedule().iter().copied().unzip();
            q.set_item("times", t)?;
            q.set_item("rates", r)?;
        }
        d.set_item("source", q)?;
    }
    for (key, v) in [("removal", &p.removal), ("growth", &p.growth)] {
        if let Some(v) = v {
            d.set_item(key, PyTuple::new(py, [v.coefficient, v.exponent])?)?;
        }
    }
    if let Some(h) = p.growth_step {
        d.set_item("growth_step", h)?;
    }
    Ok(d)
}

/// The books as a dict.
pub(crate) fn books_dict(py: Python<'_>, b: Books) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("initial_number", b.initial_number)?;
    d.set_item("initial_mass", b.initial_mass)?;
    d.set_item("injected_number", b.injected_number)?;
    d.set_item("injected_mass", b.injected_mass)?;
    d.set_item("removed_number", b.removed_number)?;
    d.set_item("removed_mass", b.removed_mass)?;
    d.set_item("grown_mass", b.grown_mass)?;
    d.set_item("merged", b.merged)?;
    d.set_item("doublings", b.doublings)?;
    Ok(d)
}
