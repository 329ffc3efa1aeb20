//! Python bindings of `uvflat-core` (native module `uvflat._uvflat`).
//!
//! A thin layer: it checks argument shapes and dtypes, copies numpy inputs into owned Rust
//! buffers, runs the core without the GIL (`Python::detach`) and inside `catch_unwind`, maps
//! every [`UvError`] to its Python exception and returns numpy arrays. No numerics here.

mod alloc;
mod convert;

/// mimalloc for small blocks (an unwrap of thousands of small charts makes millions of small
/// allocations across the worker threads: glibc's allocator measured 1.3–1.6× slower end to
/// end on a 47k-chart mesh), the system allocator for blocks of 1 MiB or more, which it
/// returns to the system as soon as they are freed (see [`alloc`]).
#[global_allocator]
static ALLOCATOR: alloc::SplitAllocator = alloc::SplitAllocator;

mod errors;
mod options;
mod results;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString, PyTuple};
use uvflat_core::methods::options::OptionKind;
use uvflat_core::methods::{method_names, Method, OptionValue};
use uvflat_core::{auto_seam_options, AutoSeamOptions, Fit, MeshInput, Progress, UnwrapOptions, UvError};

use convert::{floats, indices, Layout};
use errors::{attrs, error, internal_error, map_uv_error, Kind};
use results::{PyChartReport, PyMetrics, PyUnwrapResult};

/// Run `f` without the GIL; a panic becomes `UvflatError`, a core error its exception.
fn run_core<T: Send>(
    py: Python<'_>,
    uv_argument: &str,
    f: impl FnOnce() -> Result<T, UvError> + Send,
) -> PyResult<T> {
    match py.detach(move || catch_unwind(AssertUnwindSafe(f))) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(map_uv_error(py, e, uv_argument)),
        Err(payload) => Err(internal_error(py, payload)),
    }
}

/// The polygon soup shared by `unwrap` and `metrics`, converted and index-checked.
struct Soup {
    positions: Vec<[f64; 3]>,
    corner_verts: Vec<u32>,
    face_sizes: Vec<u32>,
}

impl Soup {
    /// The core's view of this soup with the given seams, selection and pins.
    fn input<'a>(&'a self, seams: &'a [[u32; 2]], selected: Option<&'a [bool]>, pins: &'a [(u32, [f64; 2])]) -> MeshInput<'a> {
        MeshInput {
            positions: &self.positions,
            corner_verts: &self.corner_verts,
            face_sizes: &self.face_sizes,
            seams,
            selected,
            pins,
            ..Default::default()
        }
    }
}

fn read_soup(
    positions: &Bound<'_, PyAny>,
    corner_verts: &Bound<'_, PyAny>,
    face_sizes: &Bound<'_, PyAny>,
) -> PyResult<Soup> {
    let py = positions.py();
    let positions = convert::float_rows::<3>(positions, "positions", "V")?;
    let n_vertices = positions.len();
    let (face_sizes, _) = indices(face_sizes, "face_sizes", Layout::Vector("F"), |face, size| {
        let msg = if size < 0 {
            format!("face {face}: has {size} corners, at least 3 are needed")
        } else {
            format!("face {face}: size {size} is larger than any mesh can have")
        };
        error(py, Kind::FaceSize, msg, attrs![py; "face" => face, "size" => size])
    })?;
    // Corner -> face only matters for the error message of a bad index.
    let face_of_corner = |corner: usize| -> Option<usize> {
        let mut end = 0usize;
        for (f, &s) in face_sizes.iter().enumerate() {
            end += s as usize;
            if corner < end {
                return Some(f);
            }
        }
        None
    };
    let (corner_verts, _) = indices(corner_verts, "corner_verts", Layout::Vector("C"), |corner, vertex| {
        let face = face_of_corner(corner);
        let at = match face {
            Some(f) => format!("face {f}, corner {corner}"),
            None => format!("corner {corner}"),
        };
        error(
            py,
            Kind::VertexIndex,
            format!("{at}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)"),
            attrs![py; "face" => face, "corner" => corner, "vertex" => vertex, "n_vertices" => n_vertices],
        )
    })?;
    Ok(Soup { positions, corner_verts, face_sizes })
}

fn read_selected(selected: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<bool>>> {
    selected.filter(|s| !s.is_none()).map(|s| convert::bools(s, "selected", Layout::Vector("F"))).transpose()
}

/// Convert keyword options to the core's option list.
fn read_options(py: Python<'_>, options: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, OptionValue)>> {
    let mut out = Vec::new();
    let Some(options) = options else { return Ok(out) };
    for (k, v) in options.iter() {
        let name: String = k.extract()?;
        let value = if v.is_instance_of::<PyBool>() {
            OptionValue::Bool(v.extract()?)
        } else if v.is_instance_of::<PyString>() {
            OptionValue::Str(v.extract()?)
        } else if v.is_instance_of::<PyFloat>() {
            OptionValue::Float(v.extract()?)
        } else if v.is_instance_of::<PyInt>() {
            OptionValue::Int(v.extract().map_err(|_| {
                let reason = format!("integer {v} does not fit in 64 bits");
                error(
                    py,
                    Kind::Option,
                    format!("option {name}: {reason}"),
                    attrs![py; "option" => name.clone(), "reason" => reason],
                )
            })?)
        } else if let Ok(pair) = v.cast::<PyTuple>() {
            // A pair of arrays: values at chosen mesh vertices (abf's angle_sums).
            OptionValue::VertexValues(read_vertex_values(py, &name, pair)?)
        } else if let Ok(i) = v.extract::<i64>() {
            // Integer-like objects (numpy integers) via __index__.
            OptionValue::Int(i)
        } else if let Ok(x) = v.extract::<f64>() {
            // Float-like objects (numpy float32) via __float__.
            OptionValue::Float(x)
        } else {
            let ty = v.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
            let reason = format!("unsupported value of type {ty} (use bool, int, float or str)");
            return Err(error(
                py,
                Kind::Option,
                format!("option {name}: {reason}"),
                attrs![py; "option" => name.clone(), "reason" => reason],
            ));
        };
        out.push((name, value));
    }
    Ok(out)
}

/// An option given as a pair `(vertex indices (K,), values (K,))`: typed errors naming the
/// entry (an index that is negative or too large for u32 is an `AngleSumError`; its range
/// against the mesh is checked by the core).
fn read_vertex_values(py: Python<'_>, name: &str, pair: &Bound<'_, PyTuple>) -> PyResult<Vec<(u32, f64)>> {
    if pair.len() != 2 {
        let reason = format!("expected a pair (vertex indices, values), got a tuple of {} items", pair.len());
        return Err(error(py, Kind::Option, format!("option {name}: {reason}"), attrs![py; "option" => name.to_string(), "reason" => reason]));
    }
    let (idx, _) = indices(&pair.get_item(0)?, name, Layout::Vector("K"), |entry, vertex| {
        let reason = format!("vertex index {vertex} out of range");
        error(
            py,
            Kind::AngleSum,
            format!("option {name}, entry {entry}: {reason}"),
            attrs![py; "option" => name.to_string(), "reason" => reason, "entry" => entry, "vertex" => vertex],
        )
    })?;
    let (vals, n_vals) = floats(&pair.get_item(1)?, name, Layout::Vector("K"))?;
    if n_vals != idx.len() {
        return Err(error(
            py,
            Kind::Input,
            format!("{name}: {} vertex indices but {n_vals} values", idx.len()),
            attrs![py; "argument" => name.to_string()],
        ));
    }
    Ok(idx.into_iter().zip(vals).collect())
}

/// Seam vertex pairs `(E, 2)`, typed errors naming the seam.
fn read_seams(py: Python<'_>, seams: Option<&Bound<'_, PyAny>>, n_vertices: usize) -> PyResult<Vec<[u32; 2]>> {
    Ok(match seams.filter(|s| !s.is_none()) {
        None => Vec::new(),
        Some(s) => {
            let (flat, _) = indices(s, "seams", Layout::Rows("E", 2), |i, vertex| {
                let seam = i / 2;
                error(
                    py,
                    Kind::Seam,
                    format!("seam {seam}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)"),
                    attrs![py; "seam" => seam, "vertex" => vertex, "n_vertices" => n_vertices],
                )
            })?;
            convert::rows::<2, u32>(&flat)
        }
    })
}

/// An automatic-seams option of the wrong type: an `OptionError` naming it.
fn option_type_error(py: Python<'_>, name: &str, expected: &str, value: &Bound<'_, PyAny>) -> PyErr {
    let ty = value.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    let reason = format!("expected {expected}, got a value of type {ty}");
    error(py, Kind::Option, format!("option {name}: {reason}"), attrs![py; "option" => name.to_string(), "reason" => reason])
}

/// The automatic-seams keywords of `unwrap` as `(name, value)`, in the order of
/// `uvflat.AUTO_SEAM_OPTIONS` (None means the default): each value is type-checked here by
/// its declared kind (an `OptionError` naming it), parsed by the core (negative `max_cones`,
/// unknown `symmetry`) and range-checked by the core's validation in `unwrap`.
fn read_auto_seams(py: Python<'_>, given: &[(&str, Option<&Bound<'_, PyAny>>)], n_vertices: usize) -> PyResult<AutoSeamOptions> {
    let mut o = AutoSeamOptions::default();
    for spec in auto_seam_options() {
        let Some(&(name, value)) = given.iter().find(|(n, _)| *n == spec.name) else {
            // a declared option `unwrap` does not take: a bug, caught by the tests
            return Err(error(py, Kind::Uvflat, format!("unwrap takes no keyword {}", spec.name), attrs![py;]));
        };
        let Some(v) = value.filter(|v| !v.is_none()) else { continue };
        let value = match spec.kind {
            OptionKind::Bool => {
                if !v.is_instance_of::<PyBool>() {
                    return Err(option_type_error(py, name, "a bool", v));
                }
                OptionValue::Bool(v.extract()?)
            }
            OptionKind::Int { .. } => {
                if v.is_instance_of::<PyBool>() {
                    return Err(option_type_error(py, name, "an integer", v));
                }
                OptionValue::Int(v.extract().map_err(|_| option_type_error(py, name, "an integer", v))?)
            }
            OptionKind::Float { .. } => {
                if v.is_instance_of::<PyBool>() || v.is_instance_of::<PyString>() {
                    return Err(option_type_error(py, name, "a number", v));
                }
                OptionValue::Float(v.extract().map_err(|_| option_type_error(py, name, "a number", v))?)
            }
            OptionKind::Choice(choices) => {
                let expected = format!("a str, one of {choices:?}");
                OptionValue::Str(v.extract().map_err(|_| option_type_error(py, name, &expected, v))?)
            }
            OptionKind::Vertices => {
                let (idx, _) = indices(v, name, Layout::Vector("K"), |entry, vertex| {
                    let reason = format!("entry {entry}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)");
                    error(py, Kind::Option, format!("option {name}: {reason}"), attrs![py; "option" => name.to_string(), "reason" => reason])
                })?;
                OptionValue::Vertices(idx)
            }
            OptionKind::VertexValues => {
                return Err(error(py, Kind::Uvflat, format!("option {name}: per-vertex values are not read here"), attrs![py;]))
            }
        };
        o.set(name, &value).map_err(|e| map_uv_error(py, e, "fit_to"))?;
    }
    Ok(o)
}

/// The `method` argument as a `str` (`None` or absent: `"lscm"`), or an `OptionError` naming its type.
fn read_method_name(py: Python<'_>, method: Option<&Bound<'_, PyAny>>) -> PyResult<String> {
    let Some(method) = method.filter(|m| !m.is_none()) else { return Ok("lscm".into()) };
    method.extract::<String>().map_err(|_| {
        let ty = method.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
        let reason = format!("expected a str, one of {:?}, got a value of type {ty}", method_names());
        error(py, Kind::Option, format!("option method: {reason}"), attrs![py; "option" => "method", "reason" => reason])
    })
}

/// Seconds of one sparse factorization (symbolic analysis + numeric) of each chart's own
/// linear system for a linear method, summed over the mappable charts; `None` for methods
/// that are not one linear solve. The yardstick for the linear methods' unwrap time.
#[pyfunction]
#[pyo3(signature = (positions, corner_verts, face_sizes, *, method = None, seams = None, selected = None, **options))]
fn factorization_seconds(
    py: Python<'_>,
    positions: &Bound<'_, PyAny>,
    corner_verts: &Bound<'_, PyAny>,
    face_sizes: &Bound<'_, PyAny>,
    method: Option<&Bound<'_, PyAny>>,
    seams: Option<&Bound<'_, PyAny>>,
    selected: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Option<f64>> {
    let opts = read_options(py, options)?;
    let method = Method::parse(&read_method_name(py, method)?, &opts).map_err(|e| map_uv_error(py, e, "fit_to"))?;
    let soup = read_soup(positions, corner_verts, face_sizes)?;
    let seams = read_seams(py, seams, soup.positions.len())?;
    let selected = read_selected(selected)?;
    run_core(py, "fit_to", || {
        uvflat_core::factorization_seconds(&soup.input(&seams, selected.as_deref(), &[]), &method)
    })
}

/// Render triangulation `(T, 3)` of corner indices (Blender's `loop_triangles`), typed errors
/// naming the row; its fit to the faces is checked by the core.
fn read_triangles(py: Python<'_>, triangles: Option<&Bound<'_, PyAny>>, n_corners: usize) -> PyResult<Vec<[u32; 3]>> {
    Ok(match triangles.filter(|t| !t.is_none()) {
        None => Vec::new(),
        Some(t) => {
            let (flat, _) = indices(t, "triangles", Layout::Rows("T", 3), |i, corner| {
                let (row, reason) = (i / 3, format!("corner {corner} out of range (mesh has {n_corners} corners)"));
                error(
                    py,
                    Kind::Triangle,
                    format!("triangles[{row}]: {reason}"),
                    attrs![py; "triangle" => row, "reason" => reason],
                )
            })?;
            convert::rows::<3, u32>(&flat)
        }
    })
}

/// Unwrap the selected faces of a polygon mesh into per-corner UVs.
///
/// See the package documentation (`uvflat.unwrap`) for the arguments.
#[pyfunction]
#[pyo3(signature = (positions, corner_verts, face_sizes, *, method = None, seams = None, selected = None,
                    pins = None, pin_uvs = None, fit_to = None, triangles = None, auto_seams = None,
                    max_stretch = None, max_cones = None, avoid_vertices = None, sharp_angle = None,
                    visibility_weight = None, symmetry = None, same_seams = None, progress = None,
                    **options))]
#[allow(clippy::too_many_arguments)]
fn unwrap(
    py: Python<'_>,
    positions: &Bound<'_, PyAny>,
    corner_verts: &Bound<'_, PyAny>,
    face_sizes: &Bound<'_, PyAny>,
    method: Option<&Bound<'_, PyAny>>,
    seams: Option<&Bound<'_, PyAny>>,
    selected: Option<&Bound<'_, PyAny>>,
    pins: Option<&Bound<'_, PyAny>>,
    pin_uvs: Option<&Bound<'_, PyAny>>,
    fit_to: Option<&Bound<'_, PyAny>>,
    triangles: Option<&Bound<'_, PyAny>>,
    auto_seams: Option<&Bound<'_, PyAny>>,
    max_stretch: Option<&Bound<'_, PyAny>>,
    max_cones: Option<&Bound<'_, PyAny>>,
    avoid_vertices: Option<&Bound<'_, PyAny>>,
    sharp_angle: Option<&Bound<'_, PyAny>>,
    visibility_weight: Option<&Bound<'_, PyAny>>,
    symmetry: Option<&Bound<'_, PyAny>>,
    same_seams: Option<&Bound<'_, PyAny>>,
    progress: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyUnwrapResult> {
    let opts = read_options(py, options)?;
    let method = Method::parse(&read_method_name(py, method)?, &opts).map_err(|e| map_uv_error(py, e, "fit_to"))?;
    let soup = read_soup(positions, corner_verts, face_sizes)?;
    let n_vertices = soup.positions.len();
    let n_corners = soup.corner_verts.len();

    let seams = read_seams(py, seams, n_vertices)?;
    let selected = read_selected(selected)?;
    let triangles = read_triangles(py, triangles, n_corners)?;

    let pins = pins.filter(|p| !p.is_none());
    let pin_uvs = pin_uvs.filter(|p| !p.is_none());
    let pins: Vec<(u32, [f64; 2])> = match (pins, pin_uvs) {
        (None, None) => Vec::new(),
        (Some(_), None) => return Err(errors::input_error(py, "pin_uvs", "pin_uvs: required when pins is given")),
        (None, Some(_)) => return Err(errors::input_error(py, "pins", "pins: required when pin_uvs is given")),
        (Some(p), Some(u)) => {
            let (corners, n_pins) = indices(p, "pins", Layout::Vector("P"), |pin, corner| {
                error(
                    py,
                    Kind::Pin,
                    format!("pin {pin}: corner index {corner} out of range (mesh has {n_corners} corners)"),
                    attrs![py; "pin" => pin, "corner" => corner, "n_corners" => n_corners],
                )
            })?;
            let uvs = convert::float_rows::<2>(u, "pin_uvs", "P")?;
            let n_uvs = uvs.len();
            if n_uvs != n_pins {
                return Err(error(
                    py,
                    Kind::Input,
                    format!("pin_uvs: has {n_uvs} rows, pins has {n_pins} entries"),
                    attrs![py; "argument" => "pin_uvs"],
                ));
            }
            corners.into_iter().zip(uvs).collect()
        }
    };
    let fit = match fit_to.filter(|f| !f.is_none()) {
        None => Fit::AreaScaled,
        Some(f) => Fit::Previous(convert::float_rows::<2>(f, "fit_to", "C")?),
    };

    let given = [
        ("auto_seams", auto_seams),
        ("max_stretch", max_stretch),
        ("max_cones", max_cones),
        ("avoid_vertices", avoid_vertices),
        ("sharp_angle", sharp_angle),
        ("visibility_weight", visibility_weight),
        ("symmetry", symmetry),
        ("same_seams", same_seams),
    ];
    let auto_seams = read_auto_seams(py, &given, n_vertices)?;
    let method_name = method.name().to_string();
    let raised: Arc<Mutex<Option<PyErr>>> = Arc::new(Mutex::new(None));
    let progress = match progress.filter(|p| !p.is_none()) {
        None => None,
        Some(p) if !p.is_callable() => {
            return Err(errors::input_error(py, "progress", "progress: must be callable (charts_done, charts_total) -> bool | None"))
        }
        Some(p) => Some(python_progress(p.clone().unbind(), raised.clone())),
    };
    let unwrap_options = UnwrapOptions { method, fit, auto_seams, progress };
    let outcome = run_core(py, "fit_to", || {
        let start = Instant::now();
        let input = MeshInput { triangles: &triangles, ..soup.input(&seams, selected.as_deref(), &pins) };
        let r = uvflat_core::unwrap(&input, &unwrap_options)?;
        Ok((r, start.elapsed().as_secs_f64()))
    });
    // An exception raised by the progress callback wins over the Cancelled it caused.
    if let Some(e) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(e);
    }
    let (result, seconds) = outcome?;

    let n_faces = result.face_chart.len();
    let n_new = result.new_seams.len();
    let new_seams = PyArray1::from_vec(py, result.new_seams.iter().flatten().copied().collect::<Vec<u32>>()).reshape([n_new, 2])?;
    let n_closed = result.closed_seams.len();
    let closed_seams =
        PyArray1::from_vec(py, result.closed_seams.iter().flatten().copied().collect::<Vec<u32>>()).reshape([n_closed, 2])?;
    let face_solved: Vec<bool> = (0..n_faces).map(|f| result.face_solved(f)).collect();
    // The core's UVs become the array's buffer without a copy (`[f64; 2]` rows flatten in place).
    let n_uv = result.uv.len();
    let uv = PyArray1::from_vec(py, result.uv.into_flattened()).reshape([n_uv, 2])?;
    let charts = result
        .charts
        .iter()
        .map(|r| Py::new(py, PyChartReport::from(r)))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PyUnwrapResult {
        uv: uv.unbind(),
        chart: PyArray1::from_vec(py, result.face_chart).unbind(),
        face_solved: PyArray1::from_vec(py, face_solved).unbind(),
        charts,
        seconds,
        method: method_name,
        new_seams: new_seams.unbind(),
        closed_seams: closed_seams.unbind(),
        non_manifold_edges: result.non_manifold_edges,
        inconsistent_edges: result.inconsistent_edges,
        face_conformal: PyArray1::from_iter(py, result.face_distortion.iter().map(|d| d[0])).unbind(),
        face_area: PyArray1::from_iter(py, result.face_distortion.iter().map(|d| d[1])).unbind(),
        face_flips: PyArray1::from_vec(py, result.face_flips).unbind(),
        phases: result.phases,
    })
}

/// Least time between two calls of a Python progress callback (the last chart always calls).
const PROGRESS_INTERVAL: Duration = Duration::from_millis(100);

/// The core's [`Progress`] calling the Python `callback(charts_done, charts_total)` with the
/// GIL re-acquired, at most every [`PROGRESS_INTERVAL`]. A false return (`False`, `0`, `\"\"`,
/// `numpy.False_`; `None` goes on) cancels; an exception
/// cancels and is kept in `raised` to be re-raised by `unwrap`.
fn python_progress(callback: Py<PyAny>, raised: Arc<Mutex<Option<PyErr>>>) -> Progress {
    let last: Mutex<Option<Instant>> = Mutex::new(None);
    Progress::with_callback(move |done, total| {
        {
            let mut last = last.lock().unwrap_or_else(|e| e.into_inner());
            let now = Instant::now();
            if done < total && last.is_some_and(|t| now.duration_since(t) < PROGRESS_INTERVAL) {
                return true;
            }
            *last = Some(now);
        }
        Python::attach(|py| match callback.call1(py, (done, total)) {
            // None (no return) goes on; any false value cancels: False, numpy.False_, 0, "".
            Ok(v) => {
                let v = v.bind(py);
                v.is_none() || v.is_truthy().unwrap_or(true)
            }
            Err(e) => {
                raised.lock().unwrap_or_else(|e| e.into_inner()).get_or_insert(e);
                false
            }
        })
    })
}

/// Measure a given per-corner UV map: islands, flips, overlaps, distortion.
///
/// See the package documentation (`uvflat.metrics`) for the arguments.
#[pyfunction]
#[pyo3(signature = (positions, corner_verts, face_sizes, uv, *, selected = None, triangles = None))]
fn metrics(
    py: Python<'_>,
    positions: &Bound<'_, PyAny>,
    corner_verts: &Bound<'_, PyAny>,
    face_sizes: &Bound<'_, PyAny>,
    uv: &Bound<'_, PyAny>,
    selected: Option<&Bound<'_, PyAny>>,
    triangles: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMetrics> {
    let soup = read_soup(positions, corner_verts, face_sizes)?;
    let uv = convert::float_rows::<2>(uv, "uv", "C")?;
    let selected = read_selected(selected)?;
    let triangles = read_triangles(py, triangles, soup.corner_verts.len())?;
    let m = run_core(py, "uv", || {
        uvflat_core::metrics::measure_with_triangles(
            &soup.positions,
            &soup.corner_verts,
            &soup.face_sizes,
            &uv,
            selected.as_deref(),
            &triangles,
        )
    })?;
    Ok(PyMetrics::from(m))
}

/// The arguments of `island_hulls` and `island_box_angles`, converted and checked: the UVs,
/// the face sizes and every face's island (`-1` for a face left out by `selected`).
struct Islands {
    uv: Vec<[f64; 2]>,
    face_sizes: Vec<u32>,
    face_island: Vec<i64>,
}

fn read_islands(
    py: Python<'_>,
    uv: &Bound<'_, PyAny>,
    face_sizes: &Bound<'_, PyAny>,
    face_island: &Bound<'_, PyAny>,
    selected: Option<&Bound<'_, PyAny>>,
) -> PyResult<Islands> {
    let uv = convert::float_rows::<2>(uv, "uv", "C")?;
    let (face_sizes, _) = indices(face_sizes, "face_sizes", Layout::Vector("F"), |face, size| {
        errors::input_error(py, "face_sizes", format!("face_sizes[{face}]: {size} is not a corner count"))
    })?;
    let island = convert::signed(face_island, "face_island", Layout::Vector("F"))?;
    let selected = read_selected(selected)?;
    if let Some(sel) = &selected {
        if sel.len() != island.len() {
            return Err(errors::input_error(
                py,
                "selected",
                format!("selected: has {} entries, face_island has {}", sel.len(), island.len()),
            ));
        }
    }
    let face_island: Vec<i64> = match &selected {
        None => island,
        Some(sel) => island.iter().zip(sel).map(|(&k, &s)| if s { k } else { -1 }).collect(),
    };
    Ok(Islands { uv, face_sizes, face_island })
}

/// Convex hull of every island of a per-corner UV map (for island packing).
///
/// See the package documentation (`uvflat.island_hulls`) for the arguments.
#[pyfunction]
#[pyo3(signature = (uv, face_sizes, face_island, *, selected = None))]
fn island_hulls<'py>(
    py: Python<'py>,
    uv: &Bound<'py, PyAny>,
    face_sizes: &Bound<'py, PyAny>,
    face_island: &Bound<'py, PyAny>,
    selected: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray2<f64>>)> {
    let Islands { uv, face_sizes, face_island } = read_islands(py, uv, face_sizes, face_island, selected)?;
    let hulls = run_core(py, "uv", || uvflat_core::geometry::convex_hull::island_hulls(&uv, &face_sizes, &face_island))?;
    let offsets = PyArray1::from_iter(py, hulls.offsets.iter().map(|&o| o as i64));
    let n = hulls.points.len();
    let points = PyArray1::from_vec(py, hulls.points.into_flattened()).reshape([n, 2])?;
    Ok((offsets, points))
}

/// The turn of every island of a per-corner UV map to the least-area box of its hull.
///
/// See the package documentation (`uvflat.island_box_angles`) for the arguments.
#[pyfunction]
#[pyo3(signature = (uv, face_sizes, face_island, *, selected = None))]
fn island_box_angles<'py>(
    py: Python<'py>,
    uv: &Bound<'py, PyAny>,
    face_sizes: &Bound<'py, PyAny>,
    face_island: &Bound<'py, PyAny>,
    selected: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let Islands { uv, face_sizes, face_island } = read_islands(py, uv, face_sizes, face_island, selected)?;
    let angles = run_core(py, "uv", || {
        let hulls = uvflat_core::geometry::convex_hull::island_hulls(&uv, &face_sizes, &face_island)?;
        Ok(uvflat_core::geometry::min_box::island_box_angles(&hulls))
    })?;
    Ok(PyArray1::from_vec(py, angles))
}

/// Raise the error a panic in the core turns into (lets the test-suite check that a panic
/// never crosses into Python). Not part of the public API.
#[pyfunction]
fn _internal_panic_check(py: Python<'_>) -> PyResult<()> {
    run_core(py, "", || -> Result<(), UvError> { panic!("deliberate panic to check the boundary") })
}

/// Native module of the `uvflat` package.
#[pymodule]
fn _uvflat(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(unwrap, m)?)?;
    m.add_function(wrap_pyfunction!(metrics, m)?)?;
    m.add_function(wrap_pyfunction!(factorization_seconds, m)?)?;
    m.add_function(wrap_pyfunction!(island_hulls, m)?)?;
    m.add_function(wrap_pyfunction!(island_box_angles, m)?)?;
    m.add_function(wrap_pyfunction!(_internal_panic_check, m)?)?;
    m.add_class::<PyUnwrapResult>()?;
    m.add_class::<PyChartReport>()?;
    m.add_class::<PyMetrics>()?;
    m.add("METHODS", PyTuple::new(py, method_names())?)?;
    m.add("METHOD_OPTIONS", options::method_options_dict(py)?)?;
    m.add("AUTO_SEAM_OPTIONS", options::auto_seam_options_tuple(py)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    Ok(())
}
