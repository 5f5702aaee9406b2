//! Values between Rust and Python without JSON text: serde values become dicts, lists and
//! numbers (arrays of numbers become numpy arrays), Python documents become serde values, and
//! numpy arrays cross as little-endian bytes.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

/// numpy, imported once per call that needs it.
pub fn numpy(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    py.import("numpy")
}

/// A numpy array of `shape` from little-endian values (writable: it owns a bytearray).
pub fn array<'py, T: Copy>(
    py: Python<'py>,
    values: &[T],
    dtype: &str,
    shape: &[usize],
    to_le: impl Fn(T, &mut [u8]),
) -> PyResult<Bound<'py, PyAny>> {
    let width = std::mem::size_of::<T>();
    let bytes = PyByteArray::new_with(py, std::mem::size_of_val(values), |buf| {
        for (v, chunk) in values.iter().zip(buf.chunks_exact_mut(width)) {
            to_le(*v, chunk);
        }
        Ok(())
    })?;
    let np = numpy(py)?;
    let flat = np.call_method1("frombuffer", (bytes, dtype))?;
    flat.call_method1("reshape", (PyTuple::new(py, shape)?,))
}

/// float64 values as an array of `shape`.
pub fn f64_array<'py>(
    py: Python<'py>,
    values: &[f64],
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    array(py, values, "<f8", shape, |v, b| {
        b.copy_from_slice(&v.to_le_bytes())
    })
}

/// int64 values as an array of `shape`.
pub fn i64_array<'py>(
    py: Python<'py>,
    values: &[i64],
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    array(py, values, "<i8", shape, |v, b| {
        b.copy_from_slice(&v.to_le_bytes())
    })
}

/// bool values as an array.
pub fn bool_array<'py>(py: Python<'py>, values: &[bool]) -> PyResult<Bound<'py, PyAny>> {
    array(py, values, "?", &[values.len()], |v, b| b[0] = u8::from(v))
}

/// What an array of JSON values is, for turning it into numpy.
enum Numbers {
    Ints(Vec<i64>),
    Floats(Vec<f64>),
    Bools(Vec<bool>),
}

/// The values as one typed column, when they are all integers, all numbers or all booleans
/// (NaN travels as JSON null in a float column: a column of numbers and nulls is floats).
fn column(values: &[&Value]) -> Option<Numbers> {
    if values.is_empty() {
        return None;
    }
    if values.iter().all(|v| v.is_boolean()) {
        return Some(Numbers::Bools(
            values
                .iter()
                .map(|v| v.as_bool().unwrap_or(false))
                .collect(),
        ));
    }
    if values.iter().all(|v| v.is_i64() || v.is_u64()) {
        let ints: Option<Vec<i64>> = values
            .iter()
            .map(|v| {
                v.as_i64()
                    .or_else(|| v.as_u64().and_then(|u| i64::try_from(u).ok()))
            })
            .collect();
        if let Some(ints) = ints {
            return Some(Numbers::Ints(ints));
        }
    }
    let numbers = values.iter().filter(|v| v.is_number()).count();
    if numbers > 0 && values.iter().all(|v| v.is_number() || v.is_null()) {
        return Some(Numbers::Floats(
            values
                .iter()
                .map(|v| v.as_f64().unwrap_or(f64::NAN))
                .collect(),
        ));
    }
    None
}

fn numbers<'py>(py: Python<'py>, n: Numbers, shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    match n {
        Numbers::Ints(v) => i64_array(py, &v, shape),
        Numbers::Floats(v) => f64_array(py, &v, shape),
        Numbers::Bools(v) => {
            bool_array(py, &v)?.call_method1("reshape", (PyTuple::new(py, shape)?,))
        }
    }
}

/// A serde value as Python: objects as dicts, arrays of numbers (or of equal-length arrays of
/// numbers) as numpy arrays, other arrays as lists; the keys in `tables` hold arrays of
/// objects, which become dicts of columns (see [`table`]).
pub fn to_py<'py>(py: Python<'py>, v: &Value, tables: &[&str]) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let refs: Vec<&Value> = items.iter().collect();
            array_to_py(py, &refs, tables)?
        }
        Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, v) in map {
                let item = match v {
                    Value::Array(rows) if tables.contains(&k.as_str()) => {
                        let refs: Vec<&Value> = rows.iter().collect();
                        table(py, &refs, tables)?
                    }
                    _ => to_py(py, v, tables)?,
                };
                d.set_item(k, item)?;
            }
            d.into_any()
        }
    })
}

fn array_to_py<'py>(
    py: Python<'py>,
    items: &[&Value],
    tables: &[&str],
) -> PyResult<Bound<'py, PyAny>> {
    if let Some(n) = column(items) {
        return numbers(py, n, &[items.len()]);
    }
    // Rows of equal length, all numbers: a 2-D array.
    if let Some(width) = items.first().and_then(|v| v.as_array()).map(Vec::len) {
        if width > 0
            && items
                .iter()
                .all(|r| r.as_array().is_some_and(|a| a.len() == width))
        {
            let flat: Vec<&Value> = items
                .iter()
                .flat_map(|r| r.as_array().into_iter().flatten())
                .collect();
            if let Some(n) = column(&flat) {
                return numbers(py, n, &[items.len(), width]);
            }
        }
    }
    let list = PyList::empty(py);
    for v in items {
        list.append(to_py(py, v, tables)?)?;
    }
    Ok(list.into_any())
}

/// Rows (objects) as a dict of columns: each key's values as a numpy array when they are all
/// numbers, booleans or numeric arrays of one length, else as a list (missing keys are None).
/// `lamina.rows` turns it back into a list of dicts.
pub fn table<'py>(
    py: Python<'py>,
    rows: &[&Value],
    tables: &[&str],
) -> PyResult<Bound<'py, PyAny>> {
    if rows.iter().any(|r| !r.is_object()) {
        return array_to_py(py, rows, tables);
    }
    let mut keys: Vec<&str> = Vec::new();
    for r in rows {
        for k in r.as_object().into_iter().flat_map(|m| m.keys()) {
            if !keys.contains(&k.as_str()) {
                keys.push(k);
            }
        }
    }
    let d = PyDict::new(py);
    for k in keys {
        let values: Vec<&Value> = rows
            .iter()
            .map(|r| r.get(k).unwrap_or(&Value::Null))
            .collect();
        let present = rows.iter().all(|r| r.get(k).is_some());
        let col = if present {
            array_to_py(py, &values, tables)?
        } else {
            let list = PyList::empty(py);
            for v in &values {
                list.append(to_py(py, v, tables)?)?;
            }
            list.into_any()
        };
        d.set_item(k, col)?;
    }
    Ok(d.into_any())
}

/// A serializable report as Python (see [`to_py`]).
pub fn report<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
    tables: &[&str],
) -> PyResult<Bound<'py, PyAny>> {
    let v = serde_json::to_value(value)
        .map_err(|e| PyTypeError::new_err(format!("a report that does not serialise: {e}")))?;
    to_py(py, &v, tables)
}

/// A Python document (dicts, lists, numbers, strings, None, numpy arrays and scalars) as a
/// serde value; `what` names it in errors.
pub fn from_py(v: &Bound<'_, PyAny>, what: &str) -> PyResult<Value> {
    if v.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if v.cast::<PyInt>().is_ok() {
        if let Ok(i) = v.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = v.extract::<u64>() {
            return Ok(Value::from(u));
        }
    }
    if v.cast::<PyFloat>().is_ok() {
        let f: f64 = v.extract()?;
        return Ok(serde_json::Number::from_f64(f).map_or(Value::Null, Value::Number));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Value::String(s.extract::<String>()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, item) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{what}: keys must be strings")))?;
            let inner = from_py(&item, what)?;
            map.insert(key, inner);
        }
        return Ok(Value::Object(map));
    }
    // numpy arrays and scalars: as Python lists and numbers first.
    if v.hasattr("tolist")? && !v.is_instance_of::<PyList>() && !v.is_instance_of::<PyTuple>() {
        return from_py(&v.call_method0("tolist")?, what);
    }
    if let Ok(items) = v.try_iter() {
        let mut out = Vec::new();
        for item in items {
            out.push(from_py(&item?, what)?);
        }
        return Ok(Value::Array(out));
    }
    Err(PyTypeError::new_err(format!(
        "{what}: {} is not a value a lamina document holds",
        v.get_type().name()?
    )))
}
