//! numpy arrays and Python sequences in: checked and copied into the vectors core
//! takes, a wrong dtype, shape or value refused with a message that names the
//! argument (never a crash).

use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The dtype and dimensions of a numpy array, for a message.
fn describe(a: &Bound<'_, PyUntypedArray>) -> String {
    format!("a {}-D array of dtype {}", a.ndim(), a.dtype())
}

/// Integers ≥ 0 (counts or integer sizes): a 1-D numpy array of an integer dtype, or
/// a sequence of Python ints.
pub(crate) fn counts_arg(name: &str, x: &Bound<'_, PyAny>) -> PyResult<Vec<u64>> {
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, u64>>() {
        return Ok(a.as_array().iter().copied().collect());
    }
    let signed = |v: Vec<i64>| -> PyResult<Vec<u64>> {
        v.iter()
            .map(|&c| {
                u64::try_from(c)
                    .map_err(|_| PyValueError::new_err(format!("{name}: a negative value ({c})")))
            })
            .collect()
    };
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, i64>>() {
        return signed(a.as_array().to_vec());
    }
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, i32>>() {
        return signed(a.as_array().iter().map(|&v| i64::from(v)).collect());
    }
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, u32>>() {
        return Ok(a.as_array().iter().map(|&v| u64::from(v)).collect());
    }
    if let Ok(a) = x.cast::<PyUntypedArray>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a 1-D array of integers (uint64, int64, int32 or uint32), got {}",
            describe(a)
        )));
    }
    if let Ok(v) = x.extract::<Vec<u64>>() {
        return Ok(v);
    }
    if let Ok(v) = x.extract::<Vec<i64>>() {
        return signed(v);
    }
    Err(PyTypeError::new_err(format!(
        "{name}: expected a 1-D numpy array or a sequence of integers >= 0"
    )))
}

/// Reals: a 1-D numpy array of float64 (or float32, or integers), or a sequence of
/// floats. Their values are checked by core (finite, > 0 where sizes).
pub(crate) fn reals_arg(name: &str, x: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, f64>>() {
        return Ok(a.as_array().to_vec());
    }
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, f32>>() {
        return Ok(a.as_array().iter().map(|&v| f64::from(v)).collect());
    }
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, i64>>() {
        return Ok(a.as_array().iter().map(|&v| v as f64).collect());
    }
    if let Ok(a) = x.cast::<PyUntypedArray>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a 1-D array of floats (float64), got {}",
            describe(a)
        )));
    }
    x.extract::<Vec<f64>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a 1-D numpy array or a sequence of floats"
        ))
    })
}

/// Three components per particle: a float64 array of shape (n, 3), or a flat one.
pub(crate) fn vectors_arg(name: &str, x: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(a) = x.extract::<PyReadonlyArray2<'_, f64>>() {
        let v = a.as_array();
        if v.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape (n, 3), got ({}, {})",
                v.nrows(),
                v.ncols()
            )));
        }
        return Ok(v.iter().copied().collect());
    }
    reals_arg(name, x)
}
