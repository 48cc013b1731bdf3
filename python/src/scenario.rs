//! `coagula.run`: a scenario (a TOML file, a built-in example, or a dict of the same
//! tables) run by the CLI library — the same plans, replicas, seeds and statistics as
//! `coagula run`, so the same bits — and its results as numpy arrays (the package's
//! Python part turns them into an `xarray.Dataset`).

use coagula_cli::ensemble::{self, Alone};
use coagula_cli::output;
use coagula_cli::plans::{self, Point};
use coagula_cli::scenario::Plan;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// Deepest nesting of tables and arrays a scenario value may have (a scenario has
/// three; a self-referencing dict would otherwise recurse until the stack ends).
const MAX_DEPTH: usize = 32;

/// A Python value as TOML (tables, arrays, booleans, integers, floats, strings).
fn toml_of(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    toml_at(key, v, 0)
}

fn toml_at(key: &str, v: &Bound<'_, PyAny>, depth: usize) -> PyResult<toml::Value> {
    if depth > MAX_DEPTH {
        return Err(PyValueError::new_err(format!(
            "{key}: nested more than {MAX_DEPTH} deep (a dict or list that contains itself?)"
        )));
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            PyValueError::new_err(format!("{key}: an integer outside the 64-bit range"))
        });
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{key}: keys must be strings")))?;
            let path = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            t.insert(k, toml_at(&path, &x, depth + 1)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .map(|x| toml_at(key, &x?, depth + 1))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and other numbers
    if let Ok(x) = v.extract::<i64>() {
        return Ok(toml::Value::Integer(x));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    Err(PyTypeError::new_err(format!(
        "{key}: {} is not a scenario value (tables, lists, bools, ints, floats, strings)",
        v.get_type().name()?
    )))
}

/// One point's results as a dict of arrays and attributes.
fn result<'py>(
    py: Python<'py>,
    set: &[(String, toml::Value)],
    plan: &Plan,
    out: &coagula_cli::runner::Outcome,
) -> PyResult<Bound<'py, PyDict>> {
    let rows = output::rows(plan, out);
    let (nt, no) = (plan.times.len(), plan.observables.len());
    let grid = |pick: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Vec<f64>> {
        rows.iter()
            .map(|r| r.cells.iter().map(pick).collect())
            .collect()
    };
    let arr = |v: Vec<Vec<f64>>| -> PyResult<Bound<'py, PyArray2<f64>>> {
        if nt == 0 || no == 0 {
            return Ok(PyArray2::zeros(py, [nt, no], false));
        }
        PyArray2::from_vec2(py, &v).map_err(|e| PyValueError::new_err(e.to_string()))
    };
    let d = PyDict::new(py);
    d.set_item("title", &plan.title)?;
    d.set_item("scheme", plan.scheme.name)?;
    d.set_item("kernel", &plan.kernel_name)?;
    d.set_item("units", plan.units)?;
    d.set_item("replicas", plan.replicas)?;
    d.set_item("seed", plan.seed)?;
    d.set_item("time", PyArray1::from_vec(py, plan.times.clone()))?;
    let names: Vec<String> = plan.observables.iter().map(|o| o.name()).collect();
    let meanings: Vec<String> = plan.observables.iter().map(|o| o.meaning()).collect();
    d.set_item("observables", names)?;
    d.set_item("meanings", meanings)?;
    d.set_item("mean", arr(grid(&|c| c.0))?)?;
    d.set_item("half_width", arr(grid(&|c| c.1))?)?;
    d.set_item("exact", arr(grid(&|c| c.2))?)?;
    d.set_item(
        "scenario",
        toml::to_string(&plan.scenario).unwrap_or_default(),
    )?;
    let sweep = PyDict::new(py);
    for (k, v) in set {
        sweep.set_item(k, v.to_string())?;
    }
    d.set_item("sweep", sweep)?;
    d.set_item("events", out.events.iter().sum::<u64>())?;
    d.set_item("seconds", out.seconds)?;
    Ok(d)
}

/// Runs a scenario as `coagula run` does and returns one dict per point (one, or one
/// per sweep point): `time`, `observables`, `mean`, `half_width` (of the 95%
/// interval over the replicas; NaN for one replica), `exact` (NaN where no exact
/// value is known), and the scenario as TOML text. `coagula.run` (Python) wraps it.
#[pyfunction]
#[pyo3(signature = (scenario=None, *, replicas=None, threads=None, seed=None, set=None))]
fn _run<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
    replicas: Option<u64>,
    threads: Option<u64>,
    seed: Option<u64>,
    set: Option<&Bound<'py, PyDict>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let mut ov: Vec<(String, toml::Value)> = Vec::new();
    if let Some(d) = set {
        for (k, v) in d.iter() {
            let k: String = k.extract()?;
            let val = toml_of(&k, &v)?;
            ov.push((k, val));
        }
    }
    let int = |name: &str, n: u64| {
        i64::try_from(n)
            .map(toml::Value::Integer)
            .map_err(|_| PyValueError::new_err(format!("{name} = {n} is too large")))
    };
    if let Some(r) = replicas {
        ov.push(("run.replicas".into(), int("replicas", r)?));
    }
    if let Some(t) = threads {
        ov.push(("run.threads".into(), int("threads", t)?));
    }
    if let Some(s) = seed {
        ov.push(("run.seed".into(), int("seed", s)?));
    }
    let (name, text) = match scenario {
        None => plans::resolve(None),
        Some(s) if s.is_none() => plans::resolve(None),
        Some(s) => {
            if let Ok(p) = s.extract::<std::path::PathBuf>() {
                plans::resolve(Some(&p.to_string_lossy()))
            } else if let Ok(d) = s.cast::<PyDict>() {
                let v = toml_of("", d.as_any())?;
                let text = toml::to_string(&v)
                    .map_err(|e| PyValueError::new_err(format!("scenario: {e}")))?;
                Ok(("the scenario dict".to_string(), text))
            } else {
                return Err(PyTypeError::new_err(
                    "scenario must be a path, a built-in example's name, a dict of its tables, or None (the default)",
                ));
            }
        }
    }
    .map_err(PyValueError::new_err)?;
    if coagula_cli::scenario::is_first_hits(&text) {
        return Err(PyValueError::new_err(format!(
            "{name}: a first-hit kernel scenario (Langevin) runs with the coagula CLI, not coagula.run"
        )));
    }
    let points: Vec<Point> =
        plans::points_of(&name, &text, ov, None).map_err(PyValueError::new_err)?;
    let plans: Vec<Plan> = points.iter().map(|(_, p)| p.clone()).collect();
    let done = py
        .detach(|| ensemble::run(&plans, &Alone, None, true))
        .map_err(PyValueError::new_err)?
        .ok_or_else(|| PyValueError::new_err("the run gave no results"))?;
    points
        .iter()
        .zip(&done.outcomes)
        .map(|((set, plan), out)| result(py, set, plan, out))
        .collect()
}

/// The built-in example scenarios' names (`coagula examples`).
#[pyfunction]
fn examples() -> Vec<String> {
    coagula_cli::examples::names()
        .into_iter()
        .map(String::from)
        .collect()
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_run, m)?)?;
    m.add_function(wrap_pyfunction!(examples, m)?)?;
    Ok(())
}
