//! Python values to the crates' inputs and back: arrays checked and copied, settings spelled as overrides,
//! rasters as 2D arrays, and results (anything `serde` writes) as Python dicts, lists and numbers.

use std::path::Path;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyMemoryError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};

/// The items of `values` in a vector allocated up front, or `MemoryError` (naming `name`) when the memory is not
/// there: a large array never aborts the interpreter.
pub(crate) fn collected<T>(name: &str, values: impl ExactSizeIterator<Item = T>) -> PyResult<Vec<T>> {
    let mut out = Vec::new();
    out.try_reserve_exact(values.len()).map_err(|_| {
        PyMemoryError::new_err(format!(
            "{name}: {} values of {} bytes do not fit in memory",
            values.len(),
            size_of::<T>()
        ))
    })?;
    out.extend(values);
    Ok(out)
}

/// Refuses a path that does not exist with `FileNotFoundError`, before the crates are asked.
pub(crate) fn existing(path: &Path) -> PyResult<()> {
    if path.exists() {
        Ok(())
    } else {
        Err(PyFileNotFoundError::new_err(format!(
            "{}: no such file or folder",
            path.display()
        )))
    }
}

/// A Python value as a TOML value in an override (`KEY=VALUE`), as the scenario files spell it.
pub(crate) fn toml_literal(key: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_instance_of::<PyBool>() {
        Ok(value.extract::<bool>()?.to_string())
    } else if value.is_instance_of::<PyInt>() {
        Ok(value.extract::<i64>()?.to_string())
    } else if value.is_instance_of::<PyFloat>() {
        let v = value.extract::<f64>()?;
        if !v.is_finite() {
            return Err(PyValueError::new_err(format!(
                "{key}: {v} is not a finite number"
            )));
        }
        Ok(format!("{v:?}"))
    } else if value.is_instance_of::<PyString>() {
        Ok(serde_json::Value::String(value.extract::<String>()?).to_string())
    } else {
        Err(PyTypeError::new_err(format!(
            "{key}: expected a bool, int, float or str, got {}",
            value.get_type().name()?
        )))
    }
}

/// `--set` overrides from a dict of dotted keys, each under `prefix` when given (`robot`).
pub(crate) fn overrides_of(prefix: Option<&str>, table: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let mut out = Vec::new();
    if let Some(table) = table {
        for (k, v) in table.iter() {
            let k = k.extract::<String>()?;
            let key = prefix.map_or_else(|| k.clone(), |p| format!("{p}.{k}"));
            out.push(format!("{key}={}", toml_literal(&key, &v)?));
        }
    }
    Ok(out)
}

/// The overrides of a map's `model` argument: a preset's name, or a dict in the scenario file's spelling
/// (`preset` and `traversability` of `[map]`, every other key of `[map.model]`).
pub(crate) fn model_overrides(model: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(model) = model else {
        return Ok(Vec::new());
    };
    if let Ok(name) = model.extract::<String>() {
        return Ok(vec![format!("map.preset={}", serde_json::Value::String(name))]);
    }
    let table = model.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err("model: expected a preset's name (str) or a dict of [map.model] keys")
    })?;
    let mut out = Vec::new();
    for (k, v) in table.iter() {
        let k = k.extract::<String>()?;
        let key = if k == "preset" || k == "traversability" {
            format!("map.{k}")
        } else {
            format!("map.model.{k}")
        };
        out.push(format!("{key}={}", toml_literal(&key, &v)?));
    }
    Ok(out)
}

/// The settings of `oeg map` for these overrides (one resolver, one set of errors).
pub(crate) fn settings(
    resolution_m: f64,
    overrides: &[String],
) -> PyResult<oeg_eval::settings::MapJobSettings> {
    oeg_eval::settings::map_settings(resolution_m, overrides)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A float array of shape `(n, cols)` (or `(n,)` when `cols` is `None`), `float32` or `float64`, as f64 rows.
pub(crate) fn float_rows(name: &str, array: &Bound<'_, PyAny>, cols: Option<usize>) -> PyResult<Vec<f64>> {
    let shape_error = |dtype: String, shape: Vec<usize>| {
        PyTypeError::new_err(format!(
            "{name}: expected a float32 or float64 numpy array of shape {}, got dtype {dtype} and shape {shape:?}",
            cols.map_or("(n,)".to_string(), |c| format!("(n, {c})"))
        ))
    };
    let ndim = cols.map_or(1, |_| 2);
    macro_rules! rows_of {
        ($t:ty) => {
            if let Ok(a) = array.cast::<numpy::PyArrayDyn<$t>>() {
                let shape = a.shape().to_vec();
                if shape.len() != ndim || cols.is_some_and(|c| shape[1] != c) {
                    return Err(shape_error(stringify!($t).replace("f", "float"), shape));
                }
                let ro = a.readonly();
                // A C-contiguous array is read in place; any other layout is copied once.
                return collected(name, ro.as_array().iter().map(|v| f64::from(*v)));
            }
        };
    }
    rows_of!(f64);
    rows_of!(f32);
    let (dtype, shape) = match array.cast::<numpy::PyUntypedArray>() {
        Ok(a) => (a.dtype().to_string(), a.shape().to_vec()),
        Err(_) => (array.get_type().name()?.to_string(), Vec::new()),
    };
    Err(shape_error(dtype, shape))
}

/// An optional per-ray array of `bool` of length `n`.
pub(crate) fn bool_column(name: &str, array: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<Vec<bool>> {
    let Some(array) = array else {
        return Ok(vec![false; n]);
    };
    let a = array.cast::<PyArray1<bool>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a numpy array of dtype bool and shape ({n},)"
        ))
    })?;
    let values: Vec<bool> = collected(name, a.readonly().as_array().iter().copied())?;
    if values.len() != n {
        return Err(PyValueError::new_err(format!(
            "{name}: {} values for {n} points",
            values.len()
        )));
    }
    Ok(values)
}

/// A scenario's overrides: a dict of dotted keys (values as Python scalars) or a list of `KEY=VALUE`
/// strings, as `--set` takes them.
pub(crate) fn scenario_overrides(overrides: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    match overrides.cast::<PyDict>() {
        Ok(table) => overrides_of(None, Some(table)),
        Err(_) => overrides.extract::<Vec<String>>().map_err(|_| {
            PyTypeError::new_err("overrides: expected a dict of dotted keys or a list of KEY=VALUE strings")
        }),
    }
}

/// A 3-vector of finite floats.
pub(crate) fn xyz(name: &str, value: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected three floats (x, y, z) in metres")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(PyValueError::new_err(format!(
            "{name}: expected three finite floats (x, y, z) in metres, got {v:?}"
        ))),
    }
}

/// `(x_min, x_max, y_min, y_max)` of a region, metres: `matplotlib.pyplot.imshow(extent=...)`.
pub(crate) fn extent(window: &oeg::GridWindow) -> Extent {
    let [x0, x1, y0, y1] = oeg_eval::navigation::external::extent_of(window);
    (x0, x1, y0, y1)
}

/// `(x_min, x_max, y_min, y_max)` in metres.
pub(crate) type Extent = (f64, f64, f64, f64);

/// A layer as a 2D array with its extent.
pub(crate) type Grid<'py, T> = (Bound<'py, PyArray2<T>>, Extent);

/// A 2D array of a raster's values: `num_y` rows from the min-y row, `num_x` columns.
pub(crate) fn grid<'py, T: numpy::Element>(
    py: Python<'py>,
    region: &oeg::CellRegion,
    values: Vec<T>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let shape = (region.num_y as usize, region.num_x as usize);
    let array = Array2::from_shape_vec(shape, values).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}

/// A 2D float64 array of `shape` as its values, or `None`.
pub(crate) fn float_grid(
    name: &str,
    array: Option<&Bound<'_, PyAny>>,
    shape: (usize, usize),
) -> PyResult<Option<Vec<f64>>> {
    let Some(array) = array else { return Ok(None) };
    let a = array
        .cast::<PyArray2<f64>>()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a 2D float64 numpy array")))?;
    let ro = a.readonly();
    let got = (ro.shape()[0], ro.shape()[1]);
    if got != shape {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {got:?}, expected the decisions' shape {shape:?}"
        )));
    }
    Ok(Some(collected(name, ro.as_array().iter().copied())?))
}

/// A result as Python objects: what `serde` writes of `value`, structs as dicts in their fields' order, lists
/// and numbers, with no text to parse again on the Python side. A float without a value (NaN, infinite) is
/// `None`, as the project's JSON files write it (`null`).
pub(crate) fn py_object<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let object = pythonize::pythonize(py, value).map_err(crate::oeg_error)?;
    without_non_finite(py, object)
}

/// `object` with every non-finite float in its dicts and lists replaced by `None`.
fn without_non_finite<'py>(py: Python<'py>, object: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if let Ok(dict) = object.cast::<PyDict>() {
        for (key, value) in dict.iter() {
            dict.set_item(key, without_non_finite(py, value)?)?;
        }
    } else if let Ok(list) = object.cast::<pyo3::types::PyList>() {
        for (k, item) in list.iter().enumerate() {
            list.set_item(k, without_non_finite(py, item)?)?;
        }
    } else if object.is_instance_of::<PyFloat>() && !object.extract::<f64>()?.is_finite() {
        return Ok(py.None().into_bound(py));
    }
    Ok(object)
}
