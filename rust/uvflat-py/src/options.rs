//! `uvflat.METHOD_OPTIONS` and `uvflat.AUTO_SEAM_OPTIONS`: the core's declared options of
//! every method and of automatic seams, as Python data.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use uvflat_core::methods::options::{method_options, OptionDefault, OptionKind, OptionSpec};
use uvflat_core::{auto_seam_options, method_names};

/// One option as a dict: name, type ("bool", "int", "float", "choice", "vertices",
/// "vertex_values"), default, min, max, min_exclusive, max_exclusive, choices, doc (absent
/// bounds and choices are None; a default of None means the option is off or empty).
fn option_dict<'py>(py: Python<'py>, o: &OptionSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", o.name)?;
    let none = || py.None();
    let (ty, min, max, min_exclusive, max_exclusive, choices): (&str, Py<PyAny>, Py<PyAny>, bool, bool, Py<PyAny>) = match o.kind {
        OptionKind::Int { min, max } => {
            ("int", min.into_pyobject(py)?.into_any().unbind(), max.into_pyobject(py)?.into_any().unbind(), false, false, none())
        }
        OptionKind::Float { min, min_exclusive, max, max_exclusive } => {
            let max = if max.is_finite() { max.into_pyobject(py)?.into_any().unbind() } else { none() };
            ("float", min.into_pyobject(py)?.into_any().unbind(), max, min_exclusive, max_exclusive, none())
        }
        OptionKind::Choice(c) => ("choice", none(), none(), false, false, PyTuple::new(py, c)?.into_any().unbind()),
        OptionKind::VertexValues => ("vertex_values", none(), none(), false, false, none()),
        OptionKind::Bool => ("bool", none(), none(), false, false, none()),
        OptionKind::Vertices => ("vertices", none(), none(), false, false, none()),
    };
    d.set_item("type", ty)?;
    match o.default {
        OptionDefault::Bool(b) => d.set_item("default", b)?,
        OptionDefault::Int(i) => d.set_item("default", i)?,
        OptionDefault::Float(x) => d.set_item("default", x)?,
        OptionDefault::Str(s) => d.set_item("default", s)?,
        OptionDefault::Empty => d.set_item("default", py.None())?,
    }
    d.set_item("min", min)?;
    d.set_item("max", max)?;
    d.set_item("min_exclusive", min_exclusive)?;
    d.set_item("max_exclusive", max_exclusive)?;
    d.set_item("choices", choices)?;
    d.set_item("doc", o.doc)?;
    Ok(d)
}

/// `{method: (option dict, ...)}` for every method.
pub fn method_options_dict(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for &name in method_names() {
        let items = method_options(name).iter().map(|o| option_dict(py, o)).collect::<PyResult<Vec<_>>>()?;
        out.set_item(name, PyTuple::new(py, items)?)?;
    }
    Ok(out)
}

/// `(option dict, ...)` of automatic seams, in the order front ends show them.
pub fn auto_seam_options_tuple(py: Python<'_>) -> PyResult<Bound<'_, PyTuple>> {
    let items = auto_seam_options().iter().map(|o| option_dict(py, o)).collect::<PyResult<Vec<_>>>()?;
    PyTuple::new(py, items)
}
