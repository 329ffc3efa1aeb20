//! Result and report classes returned to Python (immutable).

use numpy::{PyArray1, PyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use uvflat_core::metrics::{ChartMetrics, DensitySpread, MeshMetrics};
use uvflat_core::{ChartReport, Distortion};

fn fmt_f(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else {
        format!("{x:.6}")
    }
}

/// Report of one chart (island) of an unwrap: topology, outcome and quality.
#[pyclass(frozen, get_all, module = "uvflat", name = "ChartReport")]
#[derive(Debug, Clone)]
pub struct PyChartReport {
    /// Chart id, as in `UnwrapResult.chart`.
    pub id: usize,
    /// Method that produced the UVs (the fallback's name when status is "fallback").
    pub method: String,
    /// Number of input faces (polygons).
    pub faces: usize,
    /// Number of triangles after n-gon triangulation.
    pub triangles: usize,
    /// Number of chart vertices (a vertex split by a seam counts once per side).
    pub vertices: usize,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Genus.
    pub genus: usize,
    /// "disk", "disk_with_holes", "closed" or "higher_genus".
    pub kind: String,
    /// "solved", "fallback", "invalid" (UVs written, but the chart breaks its rule:
    /// `reason_code` says which) or "failed".
    pub status: String,
    /// Why the chart failed or fell back, or a note on pins; None otherwise.
    pub reason: Option<String>,
    /// Iterations of an iterative method (0 for direct solves).
    pub iterations: usize,
    /// Final residual reported by the method (0 for direct solves).
    pub residual: f64,
    /// Flipped or zero-area UV triangles.
    pub flips: usize,
    /// Whether the chart's UV boundary crosses or touches itself (the two sides of one cut lying
    /// on each other, triangles apart, do not count).
    pub overlap: bool,
    /// Conformal distortion (area-weighted mean of sigma1/sigma2; 1 is perfect; NaN if failed).
    pub conformal: f64,
    /// Area distortion (1 is perfect; NaN if failed).
    pub area: f64,
    /// Symmetric Dirichlet energy (1 is perfect; NaN if failed).
    pub symmetric_dirichlet: f64,
    /// Wall-clock seconds spent on this chart.
    pub seconds: f64,
    /// Cone singularities placed by automatic seams in this chart (0 if it was not cut).
    pub cones: usize,
    /// Total 3D length of the automatic seams made for this chart (0 if it was not cut).
    pub cut_length: f64,
    /// Stable code of the outcome beside the prose `reason` (see `ChartReport::reason_code`).
    pub reason_code: String,
    /// Area-weighted 5th percentile of the texel-density ratio (triangle density over the
    /// island's; NaN if failed).
    pub density_p5: f64,
    /// Area-weighted 95th percentile of the texel-density ratio (NaN if failed).
    pub density_p95: f64,
    /// Share of the island's 3D area (0 to 1) whose density ratio is outside
    /// [1/max_stretch, max_stretch] (NaN if failed).
    pub density_outside: f64,
}

impl From<&ChartReport> for PyChartReport {
    fn from(r: &ChartReport) -> Self {
        PyChartReport {
            id: r.id,
            method: r.method.to_string(),
            faces: r.faces,
            triangles: r.triangles,
            vertices: r.vertices,
            boundary_loops: r.boundary_loops,
            genus: r.genus,
            kind: r.kind.name().to_string(),
            status: r.status.name().to_string(),
            reason: r.reason.clone(),
            iterations: r.iterations,
            residual: r.residual,
            flips: r.flips,
            overlap: r.overlap,
            conformal: r.distortion.conformal,
            area: r.distortion.area,
            symmetric_dirichlet: r.distortion.symmetric_dirichlet,
            seconds: r.seconds,
            cones: r.cones,
            cut_length: r.cut_length,
            reason_code: r.reason_code().to_string(),
            density_p5: r.density.p5,
            density_p95: r.density.p95,
            density_outside: r.density.outside,
        }
    }
}

impl PyChartReport {
    fn dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("id", self.id)?;
        d.set_item("method", &self.method)?;
        d.set_item("faces", self.faces)?;
        d.set_item("triangles", self.triangles)?;
        d.set_item("vertices", self.vertices)?;
        d.set_item("boundary_loops", self.boundary_loops)?;
        d.set_item("genus", self.genus)?;
        d.set_item("kind", &self.kind)?;
        d.set_item("status", &self.status)?;
        d.set_item("reason", &self.reason)?;
        d.set_item("iterations", self.iterations)?;
        d.set_item("residual", self.residual)?;
        d.set_item("flips", self.flips)?;
        d.set_item("overlap", self.overlap)?;
        d.set_item("conformal", self.conformal)?;
        d.set_item("area", self.area)?;
        d.set_item("symmetric_dirichlet", self.symmetric_dirichlet)?;
        d.set_item("reason_code", &self.reason_code)?;
        d.set_item("seconds", self.seconds)?;
        d.set_item("cones", self.cones)?;
        d.set_item("cut_length", self.cut_length)?;
        d.set_item("density_p5", self.density_p5)?;
        d.set_item("density_p95", self.density_p95)?;
        d.set_item("density_outside", self.density_outside)?;
        Ok(d)
    }
}

#[pymethods]
impl PyChartReport {
    /// All fields as a plain dict.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.dict(py)
    }

    fn __repr__(&self) -> String {
        let mut s = format!(
            "ChartReport(id={}, status='{}', method='{}', kind='{}', faces={}, flips={}, overlap={}, conformal={}",
            self.id,
            self.status,
            self.method,
            self.kind,
            self.faces,
            self.flips,
            if self.overlap { "True" } else { "False" },
            fmt_f(self.conformal),
        );
        if let Some(r) = &self.reason {
            s.push_str(&format!(", reason={r:?}"));
        }
        s.push(')');
        s
    }
}

/// Result of `uvflat.unwrap`: per-corner UVs, per-face charts and one report per chart.
#[pyclass(frozen, module = "uvflat", name = "UnwrapResult")]
pub struct PyUnwrapResult {
    pub uv: Py<PyArray2<f64>>,
    pub chart: Py<PyArray1<i32>>,
    pub face_solved: Py<PyArray1<bool>>,
    pub charts: Vec<Py<PyChartReport>>,
    pub seconds: f64,
    pub method: String,
    pub new_seams: Py<PyArray2<u32>>,
    pub closed_seams: Py<PyArray2<u32>>,
    pub non_manifold_edges: usize,
    pub inconsistent_edges: usize,
    pub face_conformal: Py<PyArray1<f64>>,
    pub face_area: Py<PyArray1<f64>>,
    pub face_flips: Py<PyArray1<u32>>,
    pub phases: uvflat_core::Phases,
}

impl PyUnwrapResult {
    fn reports<'a>(&'a self, py: Python<'a>) -> impl Iterator<Item = &'a PyChartReport> + 'a {
        self.charts.iter().map(move |c| c.bind(py).get())
    }
}

#[pymethods]
impl PyUnwrapResult {
    /// Where the time went, as a dict: ``build_charts``, ``plan_cuts``, ``solve``,
    /// ``repair_solve``, ``measure`` (seconds; the steps of different charts run in parallel,
    /// so ``plan_cuts``, ``solve`` and ``repair_solve`` are summed over threads), the parts of
    /// ``plan_cuts``: ``cut_state`` (each chart's edge graph, costs, occlusion rays and scale
    /// system, and the predicted flattening of disks), ``cone_placement`` (the rounds that
    /// place cones on a predicted flattening), ``split_plans`` (the split's candidate loops)
    /// and ``cut_graphs`` (every round's cones and cut graph, with the pieces rebuilt), and the
    /// counts ``predicted_rounds`` (cones planned on a predicted flattening, nothing solved),
    /// ``repair_rounds``, ``repair_pieces``, ``splits``, ``crease_cuts`` (hard-surface charts
    /// cut along their creases first), ``predicted_splits`` (splits made
    /// before any solve, the chart's predicted mean area distortion being too high),
    /// ``far_splits`` (charts split after one solve, the method's map being far from a plan
    /// predicted to keep the rule, or a large chart's map beyond the rule under a method that
    /// does not balance area), ``parts`` (repair rounds whose pieces of 250,000 triangles or more were cut
    /// into parts solved side by side),
    /// ``peels`` (pieces whose outline crossed itself, or that folded at a few faces, made
    /// valid by making the faces there islands of their own), ``last_resort`` (solves of the last
    /// resort, the method's flip-free kin then ``scaffold``, for pieces whose repair still broke
    /// the atlas rule), ``glued`` (small islands whose faces were laid on the islands around
    /// them), ``glue`` (its seconds, summed over threads), ``holes_filled`` (small holes
    /// filled for the unwrap and joined to the outlines by closed seams after it) and
    /// ``fill_undone`` (seconds of an unwrap with holes filled that was undone, an island
    /// breaking the rule without its fills).
    #[getter]
    fn phases<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.phases;
        let d = PyDict::new(py);
        d.set_item("build_charts", p.build_charts)?;
        d.set_item("plan_cuts", p.plan_cuts)?;
        d.set_item("cut_state", p.cut_state)?;
        d.set_item("cone_placement", p.cone_placement)?;
        d.set_item("split_plans", p.split_plans)?;
        d.set_item("cut_graphs", p.cut_graphs)?;
        d.set_item("solve", p.solve)?;
        d.set_item("repair_solve", p.repair_solve)?;
        d.set_item("measure", p.measure)?;
        d.set_item("predicted_rounds", p.predicted_rounds)?;
        d.set_item("repair_rounds", p.repair_rounds)?;
        d.set_item("repair_pieces", p.repair_pieces)?;
        d.set_item("splits", p.splits)?;
        d.set_item("crease_cuts", p.crease_cuts)?;
        d.set_item("predicted_splits", p.predicted_splits)?;
        d.set_item("far_splits", p.far_splits)?;
        d.set_item("parts", p.parts)?;
        d.set_item("peels", p.peels)?;
        d.set_item("last_resort", p.last_resort)?;
        d.set_item("glue", p.glue)?;
        d.set_item("glued", p.glued)?;
        d.set_item("holes_filled", p.holes_filled)?;
        d.set_item("fill_undone", p.fill_undone)?;
        Ok(d)
    }

    /// UV of every corner, shape (C, 2), float64; (0, 0) where a face got no UVs.
    #[getter]
    fn uv<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.uv.bind(py).clone()
    }

    /// Chart id of every face, shape (F,), int32; -1 for unselected faces.
    #[getter]
    fn chart<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        self.chart.bind(py).clone()
    }

    /// Whether every face received UVs, shape (F,), bool.
    #[getter]
    fn face_solved<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.face_solved.bind(py).clone()
    }

    /// One ChartReport per chart, indexed by chart id.
    #[getter]
    fn charts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.charts.iter().map(|c| c.clone_ref(py)))
    }

    /// Wall-clock seconds of the whole unwrap (validation, charting, solving, measuring).
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Name of the requested method.
    #[getter]
    fn method(&self) -> &str {
        &self.method
    }

    /// Seams added by automatic seams, shape (K, 2), uint32 vertex pairs (a < b), sorted.
    #[getter]
    fn new_seams<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        self.new_seams.bind(py).clone()
    }

    /// Of ``new_seams``, those whose two sides keep the same UVs, shape (J, 2), uint32, sorted:
    /// the paths that join small holes (filled for the unwrap) to their islands' outlines. They
    /// make each island a disk but show no texture seam.
    #[getter]
    fn closed_seams<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        self.closed_seams.bind(py).clone()
    }

    /// Edges of the selection used by three or more selected faces; each was treated as a
    /// seam. Many of them shred a mesh into many small charts.
    #[getter]
    fn non_manifold_edges(&self) -> usize {
        self.non_manifold_edges
    }

    /// Edges of two selected faces whose normals point to opposite sides (both faces run the
    /// edge in the same direction); each was treated as a seam. Recalculating the normals joins
    /// them again, except on a one-sided surface such as a Möbius strip.
    #[getter]
    fn inconsistent_edges(&self) -> usize {
        self.inconsistent_edges
    }

    /// Conformal distortion (σ1/σ2, 1 is perfect) of every face that received UVs, shape (F,),
    /// float64, NaN elsewhere: the same per-face measure as ``uvflat.metrics(...).face_conformal``,
    /// on the returned UVs and the triangulation the unwrap used.
    #[getter]
    fn face_conformal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.face_conformal.bind(py).clone()
    }

    /// Area distortion (max(J, 1/J) of the area-normalised map) of every face that received
    /// UVs, shape (F,), float64, NaN elsewhere (as ``face_conformal``).
    #[getter]
    fn face_area<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.face_area.bind(py).clone()
    }

    /// Flipped or zero-area UV triangles of every face, shape (F,), uint32, exactly as the
    /// chart reports count them (Blender's render triangles when ``triangles`` was given; a
    /// quad counts the flips of its worse diagonal split): each report's ``flips`` is the sum
    /// over its faces, ``face_flips > 0`` marks the flipped faces. 0 for faces without UVs.
    #[getter]
    fn face_flips<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        self.face_flips.bind(py).clone()
    }

    /// All fields as a plain dict (arrays included, reports as dicts).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("method", &self.method)?;
        d.set_item("face_conformal", self.face_conformal.bind(py))?;
        d.set_item("face_area", self.face_area.bind(py))?;
        d.set_item("face_flips", self.face_flips.bind(py))?;
        d.set_item("uv", self.uv.bind(py))?;
        d.set_item("chart", self.chart.bind(py))?;
        d.set_item("face_solved", self.face_solved.bind(py))?;
        let reports = self.reports(py).map(|r| r.dict(py)).collect::<PyResult<Vec<_>>>()?;
        d.set_item("charts", PyList::new(py, reports)?)?;
        d.set_item("seconds", self.seconds)?;
        d.set_item("new_seams", self.new_seams.bind(py))?;
        d.set_item("closed_seams", self.closed_seams.bind(py))?;
        d.set_item("non_manifold_edges", self.non_manifold_edges)?;
        d.set_item("inconsistent_edges", self.inconsistent_edges)?;
        Ok(d)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let (mut solved, mut fallback, mut failed, mut flips) = (0usize, 0usize, 0usize, 0usize);
        for r in self.reports(py) {
            match r.status.as_str() {
                "solved" => solved += 1,
                "fallback" => fallback += 1,
                _ => failed += 1,
            }
            flips += r.flips;
        }
        format!(
            "UnwrapResult(method='{}', corners={}, faces={}, charts={} (solved {}, fallback {}, failed {}), flips={}, seconds={:.4})",
            self.method,
            self.uv.bind(py).shape()[0],
            self.chart.bind(py).len(),
            self.charts.len(),
            solved,
            fallback,
            failed,
            flips,
            self.seconds
        )
    }
}


fn distortion_items(d: &Bound<'_, PyDict>, dist: &Distortion) -> PyResult<()> {
    d.set_item("conformal", dist.conformal)?;
    d.set_item("area", dist.area)?;
    d.set_item("symmetric_dirichlet", dist.symmetric_dirichlet)?;
    Ok(())
}

fn density_items(d: &Bound<'_, PyDict>, s: &DensitySpread) -> PyResult<()> {
    d.set_item("density_p5", s.p5)?;
    d.set_item("density_p95", s.p95)?;
    d.set_item("density_outside", s.outside)?;
    Ok(())
}

/// Quality of a given UV map, from `uvflat.metrics`.
#[pyclass(frozen, module = "uvflat", name = "Metrics")]
pub struct PyMetrics {
    charts: usize,
    flips: usize,
    overlapping_charts: usize,
    distortion: Distortion,
    density: DensitySpread,
    per_chart: Vec<ChartMetrics>,
    per_face: Vec<[f64; 2]>,
    face_flips: Vec<u32>,
}

impl From<MeshMetrics> for PyMetrics {
    fn from(m: MeshMetrics) -> Self {
        PyMetrics {
            charts: m.charts,
            flips: m.flips,
            overlapping_charts: m.overlapping_charts,
            distortion: m.distortion,
            density: m.density,
            per_chart: m.per_chart,
            per_face: m.per_face,
            face_flips: m.face_flips,
        }
    }
}

fn chart_metrics_dict<'py>(py: Python<'py>, c: &ChartMetrics) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("faces", c.faces)?;
    d.set_item("flips", c.flips)?;
    d.set_item("overlap", c.overlap)?;
    distortion_items(&d, &c.distortion)?;
    d.set_item("area_3d", c.area_3d)?;
    density_items(&d, &c.density)?;
    Ok(d)
}

#[pymethods]
impl PyMetrics {
    /// Number of UV islands (faces connected through edges whose UVs agree at both ends).
    #[getter]
    fn charts(&self) -> usize {
        self.charts
    }
    /// Flipped or zero-area UV triangles, over all charts.
    #[getter]
    fn flips(&self) -> usize {
        self.flips
    }
    /// Charts whose UV boundary crosses itself.
    #[getter]
    fn overlapping_charts(&self) -> usize {
        self.overlapping_charts
    }
    /// Conformal distortion (area-weighted mean of sigma1/sigma2; 1 is perfect).
    #[getter]
    fn conformal(&self) -> f64 {
        self.distortion.conformal
    }
    /// Area distortion (area-weighted mean of max(J, 1/J), charts area-normalised; 1 is perfect).
    #[getter]
    fn area(&self) -> f64 {
        self.distortion.area
    }
    /// Symmetric Dirichlet energy (1 is perfect).
    #[getter]
    fn symmetric_dirichlet(&self) -> f64 {
        self.distortion.symmetric_dirichlet
    }
    /// Share of the 3D area (0 to 1) whose texel density is outside [1/2, 2] of its own
    /// island's (per triangle: (UV area / 3D area) over the island's UV area / 3D area).
    #[getter]
    fn density_outside(&self) -> f64 {
        self.density.outside
    }
    /// Area-weighted 5th percentile of the texel-density ratio (each triangle against its
    /// island).
    #[getter]
    fn density_p5(&self) -> f64 {
        self.density.p5
    }
    /// Area-weighted 95th percentile of the texel-density ratio.
    #[getter]
    fn density_p95(&self) -> f64 {
        self.density.p95
    }
    /// One dict per chart: faces, flips, overlap, conformal, area, symmetric_dirichlet, area_3d,
    /// density_p5, density_p95, density_outside.
    #[getter]
    fn per_chart<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items = self.per_chart.iter().map(|c| chart_metrics_dict(py, c)).collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }
    /// Conformal distortion of every face, shape (F,), float64: the 3D-area-weighted mean of
    /// sigma1/sigma2 over its triangles (chart area-normalised). NaN for faces not measured or
    /// without 3D area, inf where a triangle's UV has zero area.
    #[getter]
    fn face_conformal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.per_face.iter().map(|d| d[0]).collect())
    }
    /// Area distortion of every face, shape (F,), float64 (max(J, 1/J), as `face_conformal`).
    #[getter]
    fn face_area<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.per_face.iter().map(|d| d[1]).collect())
    }
    /// Flipped or zero-area UV triangles of every face, shape (F,), uint32, counted as
    /// `flips` counts them (its sum); 0 for faces not measured. ``face_flips > 0`` are the
    /// flipped faces.
    #[getter]
    fn face_flips<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, &self.face_flips)
    }
    /// All fields as a plain dict.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("charts", self.charts)?;
        d.set_item("flips", self.flips)?;
        d.set_item("overlapping_charts", self.overlapping_charts)?;
        distortion_items(&d, &self.distortion)?;
        density_items(&d, &self.density)?;
        d.set_item("per_chart", self.per_chart(py)?)?;
        d.set_item("face_conformal", self.face_conformal(py))?;
        d.set_item("face_area", self.face_area(py))?;
        d.set_item("face_flips", self.face_flips(py))?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        format!(
            "Metrics(charts={}, flips={}, overlapping_charts={}, conformal={}, area={}, symmetric_dirichlet={})",
            self.charts,
            self.flips,
            self.overlapping_charts,
            fmt_f(self.distortion.conformal),
            fmt_f(self.distortion.area),
            fmt_f(self.distortion.symmetric_dirichlet)
        )
    }
}
