//! numpy input conversion: dtype and shape checks, copies into owned Rust buffers.
//!
//! Inputs are copied (not borrowed) so the core can run without the GIL while Python code
//! in other threads is free to mutate the caller's arrays.

use numpy::prelude::*;
use numpy::{PyArrayDyn, PyUntypedArray};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::errors::{attrs, error, Kind};

/// Expected layout of an array argument.
#[derive(Debug, Clone, Copy)]
pub enum Layout {
    /// `(N,)`, `N` named by the label in messages (e.g. `"C"`).
    Vector(&'static str),
    /// `(N, k)`; an empty `(0,)` array is accepted as `(0, k)`.
    Rows(&'static str, usize),
}

impl Layout {
    fn describe(self) -> String {
        match self {
            Layout::Vector(n) => format!("({n},)"),
            Layout::Rows(n, k) => format!("({n}, {k})"),
        }
    }
}

/// What element type an argument holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Family {
    Float,
    Int,
    Bool,
}

impl Family {
    fn accepts(self, kind: u8) -> bool {
        match self {
            Family::Float => matches!(kind, b'f' | b'i' | b'u'),
            Family::Int => matches!(kind, b'i' | b'u'),
            Family::Bool => matches!(kind, b'b' | b'i' | b'u'),
        }
    }
    fn describe(self) -> &'static str {
        match self {
            Family::Float => "a float (or integer) array",
            Family::Int => "an integer array",
            Family::Bool => "a bool array",
        }
    }
}

fn shape_str(shape: &[usize]) -> String {
    match shape.len() {
        1 => format!("({},)", shape[0]),
        _ => format!("({})", shape.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

fn shape_error(py: Python<'_>, name: &str, layout: Layout, shape: &[usize]) -> PyErr {
    let tuple = PyTuple::new(py, shape).map(|t| t.into_any()).unwrap_or_else(|_| py.None().into_bound(py));
    error(
        py,
        Kind::Input,
        format!("{name}: expected shape {}, got {}", layout.describe(), shape_str(shape)),
        attrs![py; "argument" => name, "shape" => tuple],
    )
}

/// `numpy.asarray(obj)` checked for element family and layout; returns the array and its
/// number of rows.
fn checked<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    layout: Layout,
    family: Family,
) -> PyResult<(Bound<'py, PyUntypedArray>, usize)> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
        error(
            py,
            Kind::Input,
            format!("{name}: cannot be read as an array ({})", e.value(py)),
            attrs![py; "argument" => name],
        )
    })?;
    let arr = arr.cast_into::<PyUntypedArray>().map_err(|_| {
        error(py, Kind::Input, format!("{name}: cannot be read as an array"), attrs![py; "argument" => name])
    })?;
    let shape = arr.shape().to_vec();
    let size: usize = shape.iter().product();
    let rows = match (layout, shape.as_slice()) {
        (Layout::Vector(_), [n]) => *n,
        (Layout::Rows(_, k), [n, m]) if *m == k => *n,
        (Layout::Rows(..), [0]) => 0,
        _ => return Err(shape_error(py, name, layout, &shape)),
    };
    let kind = arr.dtype().kind();
    // Empty arrays default to float64 in numpy; their dtype carries no information.
    if size > 0 && !family.accepts(kind) {
        let dtype = arr.dtype().str().map(|s| s.to_string()).unwrap_or_else(|_| "?".into());
        return Err(error(
            py,
            Kind::Input,
            format!("{name}: expected {}, got dtype {dtype}", family.describe()),
            attrs![py; "argument" => name],
        ));
    }
    Ok((arr, rows))
}

/// `arr` as a C-contiguous array of numpy dtype `dtype` (the same array, without a copy, when
/// it already is one), read as a slice of `T` by `read`.
fn with_slice<T: numpy::Element + Copy, R>(
    arr: &Bound<'_, PyUntypedArray>,
    dtype: &str,
    read: impl FnOnce(&[T]) -> PyResult<R>,
) -> PyResult<R> {
    let py = arr.py();
    let np = py.import("numpy")?;
    let conv = np.call_method1("ascontiguousarray", (arr, dtype))?;
    let typed = conv.cast_into::<PyArrayDyn<T>>()?;
    let ro = typed.readonly();
    read(ro.as_slice()?)
}

/// Contiguous copy of `arr` converted to `T`.
fn to_vec<T: numpy::Element + Copy>(arr: &Bound<'_, PyUntypedArray>, dtype: &str) -> PyResult<Vec<T>> {
    with_slice(arr, dtype, |s: &[T]| Ok(s.to_vec()))
}

/// A float array of layout `layout`, as f64 values (row-major) and its row count.
pub fn floats(obj: &Bound<'_, PyAny>, name: &str, layout: Layout) -> PyResult<(Vec<f64>, usize)> {
    let (arr, rows) = checked(obj, name, layout, Family::Float)?;
    Ok((to_vec::<f64>(&arr, "float64")?, rows))
}

/// A float array `(N, K)` (`label` names `N` in messages) as `N` rows of `K` f64 values: one
/// copy straight from the caller's array when it is C-contiguous float64.
pub fn float_rows<const K: usize>(obj: &Bound<'_, PyAny>, name: &str, label: &'static str) -> PyResult<Vec<[f64; K]>> {
    let (arr, _) = checked(obj, name, Layout::Rows(label, K), Family::Float)?;
    with_slice(&arr, "float64", |s: &[f64]| Ok(s.as_chunks::<K>().0.to_vec()))
}

/// A bool (or 0/1 integer) vector.
pub fn bools(obj: &Bound<'_, PyAny>, name: &str, layout: Layout) -> PyResult<Vec<bool>> {
    let (arr, _) = checked(obj, name, layout, Family::Bool)?;
    to_vec::<bool>(&arr, "bool")
}

/// Checked `u32` copies of a slice of integers of any width.
fn to_u32<T: Copy + TryInto<u32> + Into<i128>>(
    s: &[T],
    on_bad: &mut impl FnMut(usize, i128) -> PyErr,
) -> PyResult<Vec<u32>> {
    let mut out = Vec::with_capacity(s.len());
    for (i, &x) in s.iter().enumerate() {
        out.push(x.try_into().map_err(|_| on_bad(i, x.into()))?);
    }
    Ok(out)
}

/// An integer array, converted to `u32`. `on_bad(i, value)` builds the error for the flat
/// element `i` whose value is negative or does not fit in `u32`. 32- and 64-bit arrays are
/// read in place (no intermediate widened copy); narrower ones are widened to 32 bits first.
pub fn indices(
    obj: &Bound<'_, PyAny>,
    name: &str,
    layout: Layout,
    mut on_bad: impl FnMut(usize, i128) -> PyErr,
) -> PyResult<(Vec<u32>, usize)> {
    let (arr, rows) = checked(obj, name, layout, Family::Int)?;
    let dtype = arr.dtype();
    let unsigned = dtype.kind() == b'u';
    let out = match (unsigned, dtype.itemsize() > 4) {
        (false, false) => with_slice(&arr, "int32", |s: &[i32]| to_u32(s, &mut on_bad))?,
        (false, true) => with_slice(&arr, "int64", |s: &[i64]| to_u32(s, &mut on_bad))?,
        (true, false) => with_slice(&arr, "uint32", |s: &[u32]| Ok(s.to_vec()))?,
        (true, true) => with_slice(&arr, "uint64", |s: &[u64]| to_u32(s, &mut on_bad))?,
    };
    Ok((out, rows))
}

/// A signed integer vector (any integer width; unsigned values above `i64::MAX` are refused),
/// as `i64`.
pub fn signed(obj: &Bound<'_, PyAny>, name: &str, layout: Layout) -> PyResult<Vec<i64>> {
    let (arr, _) = checked(obj, name, layout, Family::Int)?;
    if arr.dtype().kind() == b'u' && arr.dtype().itemsize() >= 8 {
        return with_slice(&arr, "uint64", |s: &[u64]| {
            s.iter()
                .enumerate()
                .map(|(i, &x)| {
                    i64::try_from(x).map_err(|_| {
                        error(arr.py(), Kind::Input, format!("{name}[{i}]: {x} is too large"), attrs![arr.py(); "argument" => name])
                    })
                })
                .collect()
        });
    }
    with_slice(&arr, "int64", |s: &[i64]| Ok(s.to_vec()))
}

/// Pair up a flat row-major buffer into fixed-size rows.
pub fn rows<const K: usize, T: Copy + Default>(flat: &[T]) -> Vec<[T; K]> {
    flat.chunks_exact(K)
        .map(|c| {
            let mut r = [T::default(); K];
            r.copy_from_slice(c);
            r
        })
        .collect()
}
