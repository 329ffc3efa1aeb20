//! The one-call pipeline: validate, split into charts, map each chart in parallel, measure.

use rayon::prelude::*;

use crate::charts::{build_charts_with, Chart, FaceTriangulation};
use crate::error::{Result, UvError};
use crate::mesh::PolyMesh;
use crate::methods::{self, ChartFailure, Method};
use crate::metrics::{self, Distortion};

/// Polygon soup with everything an unwrap reads from the user's mesh.
///
/// UVs are per corner (Blender's "loop"): corner `c` of the flat `corner_verts` array.
#[derive(Debug, Clone, Copy)]
pub struct MeshInput<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 3]],
    /// Vertex index of every corner, faces one after another.
    pub corner_verts: &'a [u32],
    /// Number of corners of every face (each ≥ 3); sums to `corner_verts.len()`.
    pub face_sizes: &'a [u32],
    /// Seam edges as vertex pairs (either order). Default: none.
    pub seams: &'a [[u32; 2]],
    /// Faces to unwrap; `None` means all faces.
    pub selected: Option<&'a [bool]>,
    /// Pinned corners with the UV they must keep. Default: none.
    pub pins: &'a [(u32, [f64; 2])],
    /// Render triangulation: corner index triples (Blender's `mesh.loop_triangles`), which
    /// faces of four or more corners are split by (see [`FaceTriangulation`]). Default: none
    /// (the core splits n-gons itself). Quads are kept and measured convex either way.
    pub triangles: &'a [[u32; 3]],
}

impl Default for MeshInput<'_> {
    /// An empty mesh with no seams, pins or render triangles and every face selected.
    fn default() -> Self {
        MeshInput { positions: &[], corner_verts: &[], face_sizes: &[], seams: &[], selected: None, pins: &[], triangles: &[] }
    }
}

/// Where each solved chart is placed in UV space.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Fit {
    /// Default. Charts with pins keep the pinned coordinates; every other chart is scaled so
    /// its UV area equals its 3D area (ready for packing), centred at the origin.
    #[default]
    AreaScaled,
    /// Fit every unpinned chart (uniform scale, rotation, translation; least squares) onto the
    /// given per-corner UVs, i.e. keep islands where they were. A chart whose previous UVs are
    /// degenerate (zero area) is area-scaled and centred on their centroid instead.
    Previous(Vec<[f64; 2]>),
}

/// Options of [`unwrap`].
#[derive(Debug, Clone, Default)]
pub struct UnwrapOptions {
    /// The parameterization method and its own options. Default: [`Method::Lscm`].
    pub method: Method,
    /// Placement of the solved charts. Default: [`Fit::AreaScaled`].
    pub fit: Fit,
}

/// Topological class of a chart, from its Euler characteristic and boundary loops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChartKind {
    /// One boundary loop, genus 0.
    Disk,
    /// Several boundary loops, genus 0.
    DiskWithHoles,
    /// No boundary, genus 0 (a sphere).
    Closed,
    /// Genus ≥ 1, with or without boundary.
    HigherGenus,
}

impl ChartKind {
    /// Stable lower-case name used by the Python layer.
    pub fn name(self) -> &'static str {
        match self {
            ChartKind::Disk => "disk",
            ChartKind::DiskWithHoles => "disk_with_holes",
            ChartKind::Closed => "closed",
            ChartKind::HigherGenus => "higher_genus",
        }
    }
}

/// Outcome of one chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChartStatus {
    /// Mapped by the requested method.
    Solved,
    /// Mapped, but by a fallback method; the report's `reason` says why.
    Fallback,
    /// Not mapped; the chart's corners carry no UVs and the report's `reason` says why.
    Failed,
}

impl ChartStatus {
    /// Stable lower-case name used by the Python layer.
    pub fn name(self) -> &'static str {
        match self {
            ChartStatus::Solved => "solved",
            ChartStatus::Fallback => "fallback",
            ChartStatus::Failed => "failed",
        }
    }
}

/// Per-chart report: what was done and how good the result is.
#[derive(Debug, Clone)]
pub struct ChartReport {
    /// Chart id, as in [`Unwrapped::face_chart`].
    pub id: usize,
    /// Method that produced the UVs (the fallback's name when `status` is `Fallback`).
    pub method: &'static str,
    /// Number of input faces (polygons) in the chart.
    pub faces: usize,
    /// Number of triangles after n-gon triangulation.
    pub triangles: usize,
    /// Number of chart vertices (a vertex split by a seam counts once per side).
    pub vertices: usize,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Genus from the Euler characteristic.
    pub genus: usize,
    /// Topological class.
    pub kind: ChartKind,
    /// Solved, fallback or failed.
    pub status: ChartStatus,
    /// Why the chart failed or fell back, or a note on how pins were honoured.
    pub reason: Option<String>,
    /// Iterations of an iterative method (0 for direct solves).
    pub iterations: usize,
    /// Final residual or energy change reported by the method (0 for direct solves).
    pub residual: f64,
    /// Flipped or zero-area UV triangles (see `metrics`). 0 for failed charts.
    pub flips: usize,
    /// Whether the chart's UV boundary crosses itself. `false` for failed charts.
    pub overlap: bool,
    /// Distortion of the solved map (all 1.0 is perfect); NaN for failed charts.
    pub distortion: Distortion,
    /// Wall-clock seconds spent mapping this chart.
    pub seconds: f64,
}

/// Result of [`unwrap`].
#[derive(Debug, Clone)]
pub struct Unwrapped {
    /// UV of every input corner; `[0, 0]` where the face was not unwrapped (unselected or in a
    /// failed chart).
    pub uv: Vec<[f64; 2]>,
    /// Chart id of every face, `-1` for unselected faces.
    pub face_chart: Vec<i32>,
    /// One report per chart, indexed by chart id.
    pub charts: Vec<ChartReport>,
}

impl Unwrapped {
    /// Whether face `f` received UVs (its chart was solved or fell back).
    pub fn face_solved(&self, f: usize) -> bool {
        let c = self.face_chart[f];
        c >= 0 && self.charts[c as usize].status != ChartStatus::Failed
    }
}

/// Unwrap the selected faces of a polygon mesh.
///
/// Preconditions: none beyond the types; every input is validated.
///
/// Errors: a [`UvError`] naming the offending face, corner, vertex, seam or pin for malformed
/// input. Charts that cannot be mapped (closed, higher genus, singular systems) are *not*
/// errors: they come back with [`ChartStatus::Failed`] and a reason.
pub fn unwrap(input: &MeshInput<'_>, options: &UnwrapOptions) -> Result<Unwrapped> {
    let mesh = PolyMesh::new(input.positions, input.corner_verts, input.face_sizes)?;
    let n_corners = mesh.n_corners();
    mesh.validate_seams(input.seams)?;
    if let Some(sel) = input.selected {
        if sel.len() != mesh.n_faces() {
            return Err(UvError::Shape {
                what: "selected",
                detail: format!("has {} entries, mesh has {} faces", sel.len(), mesh.n_faces()),
            });
        }
    }
    for (i, &(c, uv)) in input.pins.iter().enumerate() {
        if c as usize >= n_corners {
            return Err(UvError::PinIndex { pin: i, corner: c as u64, n_corners });
        }
        if !uv[0].is_finite() || !uv[1].is_finite() {
            return Err(UvError::NonFinitePin { pin: i, corner: c as usize });
        }
    }
    if let Fit::Previous(prev) = &options.fit {
        if prev.len() != n_corners {
            return Err(UvError::Shape {
                what: "fit_to",
                detail: format!("has {} UVs, mesh has {} corners", prev.len(), n_corners),
            });
        }
        if let Some(c) = prev.iter().position(|p| !p[0].is_finite() || !p[1].is_finite()) {
            return Err(UvError::NonFiniteUv { corner: c });
        }
    }
    options.method.validate()?;
    if let crate::methods::Method::Abf(o) = &options.method {
        if !o.angle_sums.is_empty() {
            let mut corners = vec![0u32; input.positions.len()];
            for &v in input.corner_verts {
                corners[v as usize] += 1;
            }
            crate::methods::abf::validate_angle_sums(&o.angle_sums, &corners)?;
        }
    }
    // Charts run in parallel; inside one chart the sparse factorizations of the sizes met in
    // practice are faster sequential than split across threads.
    faer::set_global_parallelism(faer::Par::Seq);

    let render = if input.triangles.is_empty() { None } else { Some(FaceTriangulation::new(&mesh, input.triangles)?) };
    let charts = build_charts_with(&mesh, input.seams, input.selected, render.as_ref());
    let mut pin_of_corner: Vec<Option<[f64; 2]>> = vec![None; n_corners];
    for &(c, uv) in input.pins {
        pin_of_corner[c as usize] = Some(uv);
    }

    let solved: Vec<(ChartReport, Option<Vec<[f64; 2]>>)> = charts
        .par_iter()
        .enumerate()
        .map(|(id, chart)| solve_chart(id, chart, &pin_of_corner, options))
        .collect();

    let mut uv = vec![[0.0, 0.0]; n_corners];
    let mut face_chart = vec![-1i32; mesh.n_faces()];
    let mut reports = Vec::with_capacity(charts.len());
    for (chart, (report, vuv)) in charts.iter().zip(solved) {
        for &f in &chart.faces {
            face_chart[f as usize] = report.id as i32;
        }
        if let Some(vuv) = vuv {
            for &(c, v) in chart.corner_vertex.iter() {
                uv[c as usize] = vuv[v as usize];
            }
        }
        reports.push(report);
    }
    Ok(Unwrapped { uv, face_chart, charts: reports })
}

fn solve_chart(
    id: usize,
    chart: &Chart,
    pin_of_corner: &[Option<[f64; 2]>],
    options: &UnwrapOptions,
) -> (ChartReport, Option<Vec<[f64; 2]>>) {
    let start = std::time::Instant::now();
    let mut report = ChartReport {
        id,
        method: options.method.name(),
        faces: chart.faces.len(),
        triangles: chart.triangles.len(),
        vertices: chart.positions.len(),
        boundary_loops: chart.boundary_loops.len(),
        genus: chart.genus,
        kind: chart.kind,
        status: ChartStatus::Failed,
        reason: None,
        iterations: 0,
        residual: 0.0,
        flips: 0,
        overlap: false,
        distortion: Distortion::nan(),
        seconds: 0.0,
    };
    // Pins per chart vertex (average when corners of one vertex disagree).
    let pins = chart.vertex_pins(pin_of_corner);
    let outcome = methods::solve(&options.method, chart, &pins);
    let mut solution = match outcome {
        Ok(s) => s,
        Err(ChartFailure(reason)) => {
            report.reason = Some(reason);
            report.seconds = start.elapsed().as_secs_f64();
            return (report, None);
        }
    };
    if let Some(fallback) = solution.fallback.take() {
        report.status = ChartStatus::Fallback;
        report.method = fallback.method;
        report.reason = Some(fallback.reason);
    } else {
        report.status = ChartStatus::Solved;
        report.reason = solution.note.take();
    }
    report.iterations = solution.iterations;
    report.residual = solution.residual;
    if pins.is_empty() {
        place_chart(chart, &mut solution.uv, &options.fit);
    }
    let m = metrics::chart_metrics_with_quads(&chart.positions, &chart.triangles, &chart.quads, &solution.uv, &chart.boundary_loops);
    report.flips = m.flips;
    report.overlap = m.overlap;
    report.distortion = m.distortion;
    report.seconds = start.elapsed().as_secs_f64();
    (report, Some(solution.uv))
}

/// Scale/place an unpinned chart's UVs per [`Fit`].
fn place_chart(chart: &Chart, uv: &mut [[f64; 2]], fit: &Fit) {
    let tris = &chart.triangles;
    match fit {
        Fit::AreaScaled => metrics::area_normalize(&chart.positions, tris, uv, [0.0, 0.0]),
        Fit::Previous(prev) => {
            // Previous UV per chart vertex: the first corner seen for that vertex.
            let mut target = vec![[f64::NAN; 2]; uv.len()];
            for &(c, v) in chart.corner_vertex.iter() {
                if target[v as usize][0].is_nan() {
                    target[v as usize] = prev[c as usize];
                }
            }
            if !metrics::fit_similarity(uv, &target, tris) {
                let n = target.len().max(1) as f64;
                let cx = target.iter().map(|p| p[0]).sum::<f64>() / n;
                let cy = target.iter().map(|p| p[1]).sum::<f64>() / n;
                metrics::area_normalize(&chart.positions, tris, uv, [cx, cy]);
            }
        }
    }
}
