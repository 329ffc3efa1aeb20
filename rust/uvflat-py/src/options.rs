//! `uvflat.METHOD_OPTIONS`: the core's declared options of every method, as Python data.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use uvflat_core::method_names;
use uvflat_core::methods::options::{method_options, OptionDefault, OptionKind, OptionSpec};

/// One option as a dict: name, type ("int", "float", "choice", "vertex_values"), default,
/// min, max, min_exclusive, choices, doc (absent bounds and choices are None).
fn option_dict<'py>(py: Python<'py>, o: &OptionSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", o.name)?;
    let none = py.None();
    let (ty, min, max, exclusive, choices): (&str, Py<PyAny>, Py<PyAny>, bool, Py<PyAny>) = match o.kind {
        OptionKind::Int { min, max } => ("int", min.into_pyobject(py)?.into_any().unbind(), max.into_pyobject(py)?.into_any().unbind(), false, none.clone_ref(py)),
        OptionKind::Float { min, min_exclusive } => {
            ("float", min.into_pyobject(py)?.into_any().unbind(), none.clone_ref(py), min_exclusive, none.clone_ref(py))
        }
        OptionKind::Choice(c) => ("choice", none.clone_ref(py), none.clone_ref(py), false, PyTuple::new(py, c)?.into_any().unbind()),
        OptionKind::VertexValues => ("vertex_values", none.clone_ref(py), none.clone_ref(py), false, none.clone_ref(py)),
    };
    d.set_item("type", ty)?;
    match o.default {
        OptionDefault::Int(i) => d.set_item("default", i)?,
        OptionDefault::Float(x) => d.set_item("default", x)?,
        OptionDefault::Str(s) => d.set_item("default", s)?,
        OptionDefault::Empty => d.set_item("default", py.None())?,
    }
    d.set_item("min", min)?;
    d.set_item("max", max)?;
    d.set_item("min_exclusive", exclusive)?;
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
