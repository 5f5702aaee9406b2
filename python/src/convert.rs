//! Values between Rust and Python without JSON text: serde values become dicts, lists and
//! numbers (arrays of numbers become numpy arrays), Python documents become serde values, and
//! numpy arrays cross as little-endian bytes.

use pyo3::exceptions::PyTypeError;
use std::collections::HashMap;

use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

/// numpy, imported once per call that needs it.
pub fn numpy(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    py.import("numpy")
}

/// numpy's `frombuffer`, looked up once per conversion.
fn frombuffer(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    numpy(py)?.getattr(intern!(py, "frombuffer"))
}

/// A numpy array of `shape` from little-endian values (writable: it owns a bytearray), made by
/// `frombuffer`.
fn le_array<'py, T: Copy>(
    frombuffer: &Bound<'py, PyAny>,
    values: &[T],
    dtype: &Bound<'py, PyString>,
    shape: &[usize],
    to_le: fn(T, &mut [u8]),
) -> PyResult<Bound<'py, PyAny>> {
    let py = frombuffer.py();
    let width = std::mem::size_of::<T>();
    let bytes = PyByteArray::new_with(py, std::mem::size_of_val(values), |buf| {
        for (v, chunk) in values.iter().zip(buf.chunks_exact_mut(width)) {
            to_le(*v, chunk);
        }
        Ok(())
    })?;
    let flat = frombuffer.call1((bytes, dtype))?;
    if shape.len() == 1 {
        return Ok(flat);
    }
    flat.call_method1(intern!(py, "reshape"), (PyTuple::new(py, shape)?,))
}

fn f64_le(v: f64, b: &mut [u8]) {
    b.copy_from_slice(&v.to_le_bytes())
}

fn i64_le(v: i64, b: &mut [u8]) {
    b.copy_from_slice(&v.to_le_bytes())
}

fn bool_le(v: bool, b: &mut [u8]) {
    b[0] = u8::from(v)
}

/// float64 values as an array of `shape`.
pub fn f64_array<'py>(
    py: Python<'py>,
    values: &[f64],
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    le_array(&frombuffer(py)?, values, intern!(py, "<f8"), shape, f64_le)
}

/// int64 values as an array of `shape`.
pub fn i64_array<'py>(
    py: Python<'py>,
    values: &[i64],
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    le_array(&frombuffer(py)?, values, intern!(py, "<i8"), shape, i64_le)
}

/// bool values as an array.
pub fn bool_array<'py>(py: Python<'py>, values: &[bool]) -> PyResult<Bound<'py, PyAny>> {
    le_array(
        &frombuffer(py)?,
        values,
        intern!(py, "?"),
        &[values.len()],
        bool_le,
    )
}

/// What an array of JSON values is, for turning it into numpy.
enum Numbers {
    Ints(Vec<i64>),
    Floats(Vec<f64>),
    Bools(Vec<bool>),
}

/// The values as one typed column, when they are all integers, all numbers or all booleans
/// (NaN travels as JSON null in a float column: a column of numbers and nulls is floats).
fn column<'a>(values: impl Iterator<Item = &'a Value> + Clone) -> Option<Numbers> {
    let mut all_bool = true;
    let mut any_bool = false;
    let mut all_int = true;
    let mut any_number = false;
    let mut len = 0;
    for v in values.clone() {
        len += 1;
        match v {
            Value::Bool(_) => {
                any_bool = true;
                all_int = false;
            }
            Value::Number(n) => {
                all_bool = false;
                any_number = true;
                all_int &= n.as_i64().is_some();
            }
            Value::Null => {
                all_bool = false;
                all_int = false;
            }
            _ => return None,
        }
    }
    if len == 0 {
        return None;
    }
    if all_bool {
        return Some(Numbers::Bools(
            values.map(|v| v.as_bool().unwrap_or(false)).collect(),
        ));
    }
    if all_int {
        return Some(Numbers::Ints(
            values.map(|v| v.as_i64().unwrap_or(0)).collect(),
        ));
    }
    if any_bool || !any_number {
        return None;
    }
    Some(Numbers::Floats(
        values.map(|v| v.as_f64().unwrap_or(f64::NAN)).collect(),
    ))
}

/// Converting one report: numpy's `frombuffer` looked up once, and each key's Python string
/// made once (reports repeat the same few keys thousands of times).
struct Conv<'a, 'py> {
    py: Python<'py>,
    tables: &'a [&'a str],
    frombuffer: Bound<'py, PyAny>,
    keys: HashMap<&'a str, Bound<'py, PyString>>,
}

impl<'a, 'py> Conv<'a, 'py> {
    fn new(py: Python<'py>, tables: &'a [&'a str]) -> PyResult<Self> {
        Ok(Conv {
            py,
            tables,
            frombuffer: frombuffer(py)?,
            keys: HashMap::new(),
        })
    }

    fn key(&mut self, k: &'a str) -> Bound<'py, PyString> {
        let py = self.py;
        self.keys
            .entry(k)
            .or_insert_with(|| PyString::new(py, k))
            .clone()
    }

    fn numbers(&self, n: Numbers, shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
        let (py, fb) = (self.py, &self.frombuffer);
        match n {
            Numbers::Ints(v) => le_array(fb, &v, intern!(py, "<i8"), shape, i64_le),
            Numbers::Floats(v) => le_array(fb, &v, intern!(py, "<f8"), shape, f64_le),
            Numbers::Bools(v) => le_array(fb, &v, intern!(py, "?"), shape, bool_le),
        }
    }

    fn value(&mut self, v: &'a Value) -> PyResult<Bound<'py, PyAny>> {
        let py = self.py;
        Ok(match v {
            Value::Null => py.None().into_bound(py),
            Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
            Value::Number(n) => match (n.as_i64(), n.as_u64()) {
                (Some(i), _) => i.into_pyobject(py)?.into_any(),
                (None, Some(u)) => u.into_pyobject(py)?.into_any(),
                _ => PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any(),
            },
            Value::String(s) => PyString::new(py, s).into_any(),
            Value::Array(items) => self.array_of(items.iter())?,
            Value::Object(map) => {
                let d = PyDict::new(py);
                for (k, v) in map {
                    let item = match v {
                        Value::Array(rows) if self.tables.contains(&k.as_str()) => {
                            self.table(rows)?
                        }
                        _ => self.value(v)?,
                    };
                    d.set_item(self.key(k), item)?;
                }
                d.into_any()
            }
        })
    }

    fn array_of<I>(&mut self, items: I) -> PyResult<Bound<'py, PyAny>>
    where
        I: ExactSizeIterator<Item = &'a Value> + Clone,
    {
        let len = items.len();
        if let Some(n) = column(items.clone()) {
            return self.numbers(n, &[len]);
        }
        // Rows of equal length, all numbers: a 2-D array.
        let first = items
            .clone()
            .next()
            .and_then(|v| v.as_array())
            .map(Vec::len);
        if let Some(width) = first {
            if width > 0
                && items
                    .clone()
                    .all(|r| r.as_array().is_some_and(|a| a.len() == width))
            {
                let flat = items
                    .clone()
                    .flat_map(|r| r.as_array().into_iter().flatten());
                if let Some(n) = column(flat) {
                    return self.numbers(n, &[len, width]);
                }
            }
        }
        let list = PyList::empty(self.py);
        for v in items {
            list.append(self.value(v)?)?;
        }
        Ok(list.into_any())
    }

    /// Rows (objects) as a dict of columns: each key's values as a numpy array when they are
    /// all numbers, booleans or numeric arrays of one length, else as a list (missing keys are
    /// None). `lamina.rows` turns it back into a list of dicts.
    fn table(&mut self, rows: &'a [Value]) -> PyResult<Bound<'py, PyAny>> {
        if rows.iter().any(|r| !r.is_object()) {
            return self.array_of(rows.iter());
        }
        let mut keys: Vec<&'a str> = Vec::new();
        for r in rows {
            for k in r.as_object().into_iter().flat_map(|m| m.keys()) {
                if !keys.contains(&k.as_str()) {
                    keys.push(k);
                }
            }
        }
        let d = PyDict::new(self.py);
        for k in keys {
            let present = rows.iter().all(|r| r.get(k).is_some());
            let col = if present {
                self.array_of(rows.iter().map(|r| &r[k]))?
            } else {
                let list = PyList::empty(self.py);
                for r in rows {
                    list.append(match r.get(k) {
                        Some(v) => self.value(v)?,
                        None => self.py.None().into_bound(self.py),
                    })?;
                }
                list.into_any()
            };
            d.set_item(self.key(k), col)?;
        }
        Ok(d.into_any())
    }
}

/// A serde value as Python: objects as dicts, arrays of numbers (or of equal-length arrays of
/// numbers) as numpy arrays, other arrays as lists; the keys in `tables` hold arrays of
/// objects, which become dicts of columns (`lamina.rows` turns one back into rows).
pub fn to_py<'py>(py: Python<'py>, v: &Value, tables: &[&str]) -> PyResult<Bound<'py, PyAny>> {
    Conv::new(py, tables)?.value(v)
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
