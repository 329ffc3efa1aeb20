//! Python exception classes and the mapping from [`UvError`] to them.
//!
//! The classes need multiple inheritance (`InputError(UvflatError, ValueError)`), which
//! `create_exception!` cannot express, so they are built once with the builtin `type()`
//! and cached. Every raised instance carries the offending element as attributes
//! (`err.face`, `err.vertex`, `err.corner`, ...); the class holds `None` defaults for them.

use pyo3::conversion::IntoPyObjectExt;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use uvflat_core::UvError;

/// Which exception class to raise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Uvflat,
    Input,
    Mesh,
    VertexIndex,
    NonFinite,
    FaceSize,
    RepeatedVertex,
    Seam,
    Pin,
    Option,
    AngleSum,
    Cancelled,
    Triangle,
}

/// (kind, class name, parent kind (None: Exception), also a ValueError, attribute names, doc)
type Spec = (Kind, &'static str, Option<Kind>, bool, &'static [&'static str], &'static str);

const SPECS: &[Spec] = &[
    (Kind::Uvflat, "UvflatError", None, false, &[], "Base class of every error raised by uvflat."),
    (
        Kind::Input,
        "InputError",
        Some(Kind::Uvflat),
        true,
        &["argument", "shape", "corner"],
        "An argument has the wrong type, dtype, shape or length, or a UV is not finite.\n\n\
         Attributes: argument (name of the argument), shape (shape received, if relevant), \
         corner (corner of a non-finite UV, if relevant).",
    ),
    (
        Kind::Mesh,
        "MeshError",
        Some(Kind::Uvflat),
        true,
        &[],
        "The mesh itself is malformed; the subclass says how.",
    ),
    (
        Kind::VertexIndex,
        "VertexIndexError",
        Some(Kind::Mesh),
        false,
        &["face", "corner", "vertex", "n_vertices"],
        "A corner refers to a vertex index outside 0..n_vertices.\n\n\
         Attributes: face, corner, vertex (the bad index), n_vertices.",
    ),
    (
        Kind::NonFinite,
        "NonFiniteError",
        Some(Kind::Mesh),
        false,
        &["vertex", "value"],
        "A vertex position is NaN or infinite.\n\nAttributes: vertex, value.",
    ),
    (
        Kind::FaceSize,
        "FaceSizeError",
        Some(Kind::Mesh),
        false,
        &["face", "size"],
        "A face has fewer than three corners (or an impossible size).\n\nAttributes: face, size.",
    ),
    (
        Kind::RepeatedVertex,
        "RepeatedVertexError",
        Some(Kind::Mesh),
        false,
        &["face", "vertex"],
        "A face uses the same vertex more than once.\n\nAttributes: face, vertex.",
    ),
    (
        Kind::Seam,
        "SeamError",
        Some(Kind::Mesh),
        false,
        &["seam", "vertex", "n_vertices"],
        "A seam refers to a vertex index outside 0..n_vertices.\n\n\
         Attributes: seam (row of `seams`), vertex (the bad index), n_vertices.",
    ),
    (
        Kind::Triangle,
        "TriangleError",
        Some(Kind::Mesh),
        false,
        &["triangle", "corners", "reason"],
        "A row of `triangles` (the render triangulation) names a corner that does not exist, \
         corners of different faces or one corner twice, or a face is not triangulated by \
         exactly corners - 2 of its rows.\n\n\
         Attributes: triangle (row of `triangles`), corners (the row), reason.",
    ),
    (
        Kind::Pin,
        "PinError",
        Some(Kind::Uvflat),
        true,
        &["pin", "corner", "n_corners"],
        "A pin refers to a corner that does not exist, or its UV is not finite.\n\n\
         Attributes: pin (row of `pins`), corner, n_corners (None for a non-finite UV).",
    ),
    (
        Kind::Option,
        "OptionError",
        Some(Kind::Uvflat),
        true,
        &["option", "reason"],
        "Unknown method, unknown option, or an option value outside its domain.\n\n\
         Attributes: option (name of the option, or 'method'), reason.",
    ),
    (
        Kind::AngleSum,
        "AngleSumError",
        Some(Kind::Option),
        false,
        &["entry", "vertex", "value"],
        "A prescribed angle sum (abf's angle_sums) names a vertex that does not exist, is not \
         used by a face or is listed twice, or its sum is not finite, not positive, or not \
         below 2*pi times the vertex's number of face corners.\n\n\
         Attributes: option ('angle_sums'), reason, entry (position in the arrays), vertex, \
         value (the sum, None when the index itself could not be read).",
    ),
    (
        Kind::Cancelled,
        "Cancelled",
        Some(Kind::Uvflat),
        false,
        &["charts_done", "charts_total"],
        "The unwrap was cancelled by its progress callback (it returned False); no UVs.\n\n\
         Attributes: charts_done, charts_total.",
    ),
];

/// The built classes, in `SPECS` order.
static CLASSES: PyOnceLock<Vec<Py<PyType>>> = PyOnceLock::new();

fn build(py: Python<'_>) -> PyResult<Vec<Py<PyType>>> {
    let type_fn = py.import("builtins")?.getattr("type")?;
    let mut built: Vec<Py<PyType>> = Vec::with_capacity(SPECS.len());
    for (i, &(kind, name, parent, value_error, attrs, doc)) in SPECS.iter().enumerate() {
        debug_assert_eq!(SPECS[i].0, kind);
        let mut bases: Vec<Bound<'_, PyAny>> = Vec::new();
        match parent {
            Some(p) => {
                let idx = SPECS.iter().position(|s| s.0 == p).expect("parent precedes child");
                bases.push(built[idx].bind(py).clone().into_any());
            }
            None => bases.push(py.get_type::<PyException>().into_any()),
        }
        if value_error {
            bases.push(py.get_type::<PyValueError>().into_any());
        }
        let dict = PyDict::new(py);
        dict.set_item("__module__", "uvflat")?;
        dict.set_item("__doc__", doc)?;
        for a in attrs {
            dict.set_item(*a, py.None())?;
        }
        let cls = type_fn.call1((name, PyTuple::new(py, bases)?, dict))?;
        built.push(cls.cast_into::<PyType>()?.unbind());
    }
    Ok(built)
}

fn classes(py: Python<'_>) -> PyResult<&Vec<Py<PyType>>> {
    CLASSES.get_or_try_init(py, || build(py))
}

/// Add every exception class to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    for (spec, cls) in SPECS.iter().zip(classes(py)?) {
        m.add(spec.1, cls.clone_ref(py))?;
    }
    Ok(())
}

/// Attribute list of a raised exception.
pub type Attrs<'py> = Vec<(&'static str, Bound<'py, PyAny>)>;

/// Build one attribute (helper for [`attrs!`]).
pub fn attr<'py, T>(py: Python<'py>, name: &'static str, value: T) -> (&'static str, Bound<'py, PyAny>)
where
    T: IntoPyObject<'py>,
{
    let v = value.into_bound_py_any(py).unwrap_or_else(|_| py.None().into_bound(py));
    (name, v)
}

/// `attrs![py; "face" => f, "vertex" => v]`
macro_rules! attrs {
    ($py:expr; $($name:literal => $value:expr),* $(,)?) => {
        vec![$($crate::errors::attr($py, $name, $value)),*]
    };
}
pub(crate) use attrs;

/// Create an exception of `kind` with message `msg` and the given attributes.
pub fn error(py: Python<'_>, kind: Kind, msg: impl Into<String>, attrs: Attrs<'_>) -> PyErr {
    let msg = msg.into();
    let make = || -> PyResult<PyErr> {
        let idx = SPECS.iter().position(|s| s.0 == kind).expect("every kind has a spec");
        let cls = classes(py)?[idx].bind(py);
        let inst = cls.call1((msg.clone(),))?;
        for (name, value) in attrs {
            inst.setattr(name, value)?;
        }
        Ok(PyErr::from_value(inst))
    };
    match make() {
        Ok(e) => e,
        // Only reachable if the interpreter is failing (e.g. out of memory): keep the message.
        Err(_) => PyValueError::new_err(msg),
    }
}

/// `InputError` naming the argument.
pub fn input_error(py: Python<'_>, argument: &str, msg: impl Into<String>) -> PyErr {
    error(py, Kind::Input, msg, attrs![py; "argument" => argument])
}

/// Map a core error to its exception. `uv_argument` names the argument whose UVs a
/// [`UvError::NonFiniteUv`] refers to (`"uv"` for metrics, `"fit_to"` for unwrap).
pub fn map_uv_error(py: Python<'_>, err: UvError, uv_argument: &str) -> PyErr {
    let msg = err.to_string();
    match err {
        UvError::Shape { what, detail: _ } => error(py, Kind::Input, msg, attrs![py; "argument" => what]),
        UvError::VertexIndex { face, corner, vertex, n_vertices } => error(
            py,
            Kind::VertexIndex,
            msg,
            attrs![py; "face" => face, "corner" => corner, "vertex" => vertex, "n_vertices" => n_vertices],
        ),
        UvError::NonFinitePosition { vertex, value } => {
            error(py, Kind::NonFinite, msg, attrs![py; "vertex" => vertex, "value" => value])
        }
        UvError::FaceTooSmall { face, size } => {
            error(py, Kind::FaceSize, msg, attrs![py; "face" => face, "size" => size])
        }
        UvError::RepeatedVertex { face, vertex } => {
            error(py, Kind::RepeatedVertex, msg, attrs![py; "face" => face, "vertex" => vertex])
        }
        UvError::SeamIndex { seam, vertex, n_vertices } => error(
            py,
            Kind::Seam,
            msg,
            attrs![py; "seam" => seam, "vertex" => vertex, "n_vertices" => n_vertices],
        ),
        UvError::PinIndex { pin, corner, n_corners } => error(
            py,
            Kind::Pin,
            msg,
            attrs![py; "pin" => pin, "corner" => corner, "n_corners" => n_corners],
        ),
        UvError::NonFinitePin { pin, corner } => {
            error(py, Kind::Pin, msg, attrs![py; "pin" => pin, "corner" => corner])
        }
        UvError::NonFiniteUv { corner } => error(
            py,
            Kind::Input,
            format!("{uv_argument}: {msg}"),
            attrs![py; "argument" => uv_argument, "corner" => corner],
        ),
        UvError::Cancelled { charts_done, charts_total } => error(
            py,
            Kind::Cancelled,
            msg,
            attrs![py; "charts_done" => charts_done, "charts_total" => charts_total],
        ),
        UvError::Option { name, reason } => {
            error(py, Kind::Option, msg, attrs![py; "option" => name, "reason" => reason])
        }
        UvError::RenderTriangle { triangle, corners, reason } => error(
            py,
            Kind::Triangle,
            msg,
            attrs![py; "triangle" => triangle, "corners" => corners.to_vec(), "reason" => reason],
        ),
        UvError::AngleSum { entry, vertex, value, reason } => error(
            py,
            Kind::AngleSum,
            msg,
            attrs![py; "option" => "angle_sums", "reason" => reason, "entry" => entry, "vertex" => vertex, "value" => value],
        ),
    }
}

/// `UvflatError` for a panic caught in the core.
pub fn internal_error(py: Python<'_>, payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let detail = if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    };
    error(
        py,
        Kind::Uvflat,
        format!("internal error in the uvflat core (please report it with the mesh): {detail}"),
        Vec::new(),
    )
}
