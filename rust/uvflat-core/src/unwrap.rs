//! The one-call pipeline: validate, split into charts, map each chart in parallel, measure.

use std::collections::HashMap;

use crate::charts::{build_charts_counting, build_charts_with, Chart, FaceTriangulation};
use crate::cuts::{self, AutoSeamOptions};
use crate::error::{Result, UvError};
use crate::mesh::PolyMesh;
use crate::methods::{self, ChartFailure, Method};
use crate::metrics::{self, Distortion};
use crate::progress::Progress;

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
    /// given per-corner UVs, i.e. keep islands where they were. Only the corners of selected
    /// faces are read (the others may hold anything, NaN included). A chart whose previous UVs
    /// are degenerate (zero area) or mirrored (no rotation fits: the best one would collapse
    /// the chart) is area-scaled and centred on them instead, and its report says so.
    Previous(Vec<[f64; 2]>),
}

/// Options of [`unwrap`].
#[derive(Debug, Clone, Default)]
pub struct UnwrapOptions {
    /// The parameterization method and its own options. Default: [`Method::Lscm`].
    pub method: Method,
    /// Placement of the solved charts. Default: [`Fit::AreaScaled`].
    pub fit: Fit,
    /// Automatic seams for closed and higher-genus charts (see [`crate::cuts`]). Default: on.
    pub auto_seams: AutoSeamOptions,
    /// Progress callback and cancel flag, polled between charts and between iterations of
    /// the iterative methods. Default: none.
    pub progress: Option<Progress>,
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
    /// Cone singularities placed by automatic seams in this chart (0 when it was not cut).
    pub cones: usize,
    /// Total 3D length of the automatic seams made for this chart (0 when it was not cut).
    pub cut_length: f64,
}

impl ChartReport {
    /// Stable code of the chart's outcome, for programs (the prose `reason` is for people):
    /// `"solved"`, `"solved_with_note"` (e.g. how pins were honoured), `"fallback"`,
    /// `"failed_closed"` (a closed surface: no boundary to open it along), `"failed_genus"`
    /// (handles: seams must cut them), `"failed_defect"` (non-orientable or a non-manifold
    /// vertex inside the chart), `"failed_solver"` (the method could not map a disk-like
    /// chart).
    pub fn reason_code(&self) -> &'static str {
        match (self.status, self.kind) {
            (ChartStatus::Solved, _) if self.reason.is_none() => "solved",
            (ChartStatus::Solved, _) => "solved_with_note",
            (ChartStatus::Fallback, _) => "fallback",
            (ChartStatus::Failed, ChartKind::Closed) => "failed_closed",
            (ChartStatus::Failed, ChartKind::HigherGenus) => "failed_genus",
            (ChartStatus::Failed, _) if self.reason.as_deref().is_some_and(is_defect) => "failed_defect",
            (ChartStatus::Failed, _) => "failed_solver",
        }
    }
}

/// Whether a failure reason is a chart defect found while building charts.
fn is_defect(reason: &str) -> bool {
    reason.contains("non-orientable") || reason.contains("non-manifold")
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
    /// Seams added by automatic seams, as mesh vertex pairs `[a, b]` with `a < b`, sorted.
    pub new_seams: Vec<[u32; 2]>,
    /// Edges of the selection used by three or more selected faces; each was treated as a
    /// seam (a mesh with many of them is shredded into many small charts).
    pub non_manifold_edges: usize,
    /// `[conformal, area]` distortion of every face that received UVs, as
    /// [`crate::metrics::MeshMetrics::per_face`] defines it (3D-area-weighted over the face's
    /// triangles, the chart's UVs area-normalised); NaN elsewhere. Measured on the returned
    /// UVs, so a caller needs no second pass to colour faces by quality.
    pub face_distortion: Vec<[f64; 2]>,
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
/// Errors: a [`crate::UvError`] naming the offending face, corner, vertex, seam or pin for malformed
/// input. Charts that cannot be mapped (closed, higher genus, singular systems) are *not*
/// errors: they come back with [`ChartStatus::Failed`] and a reason.
pub fn unwrap(input: &MeshInput<'_>, options: &UnwrapOptions) -> Result<Unwrapped> {
    let mesh = crate::validate::validate_input(input, Some(&options.fit), Some(&options.method))?;
    let n_corners = mesh.n_corners();
    options.auto_seams.validate(input.positions.len())?;
    // Charts run in parallel; inside one chart the sparse factorizations of the sizes met in
    // practice are faster sequential than split across threads.
    faer::set_global_parallelism(faer::Par::Seq);

    let render = if input.triangles.is_empty() { None } else { Some(FaceTriangulation::new(&mesh, input.triangles)?) };
    let (charts, non_manifold_edges) = build_charts_counting(&mesh, input.seams, input.selected, render.as_ref());
    // Pinned corners only (a later pin of the same corner wins): nothing per corner when
    // there are no pins.
    let pin_of_corner: HashMap<u32, [f64; 2]> = input.pins.iter().copied().collect();

    let mut avoid = vec![false; input.positions.len()];
    for &v in &options.auto_seams.avoid_vertices {
        avoid[v as usize] = true;
    }
    let ctx = Context { mesh: &mesh, render: render.as_ref(), pins: &pin_of_corner, options, avoid: &avoid };
    // With a Progress: charts after a cancel are skipped (None), and the unwrap is an error.
    let total = charts.len();
    if let Some(p) = &options.progress {
        p.start(total);
    }
    let run = |chart: &Chart| -> Vec<Piece> {
        if options.auto_seams.enabled && cuts::needs_cut(chart) {
            auto_cut(&ctx, chart, input.seams, 0)
        } else {
            let (report, uv) = solve_chart(0, chart, &pin_of_corner, options);
            vec![Piece { chart: None, report, uv, seams: Vec::new() }]
        }
    };
    // Largest charts first, one per task; results in chart order (see `schedule`).
    let pieces: Vec<Option<Vec<Piece>>> = crate::schedule::solve_charts_scheduled(&charts, |_, chart| match &options.progress {
        None => Some(run(chart)),
        Some(p) if p.is_cancelled() => None,
        Some(p) => {
            let out = {
                let _guard = p.enter();
                run(chart)
            };
            p.chart_done();
            Some(out)
        }
    });
    if let Some(p) = options.progress.as_ref().filter(|p| p.is_cancelled()) {
        return Err(UvError::Cancelled { charts_done: p.charts_done(), charts_total: total });
    }
    let pieces: Vec<Vec<Piece>> = pieces.into_iter().map(|p| p.unwrap_or_default()).collect();
    // Per-face quality of every mapped piece, in parallel.
    let distortion: Vec<Vec<Vec<(u32, [f64; 2])>>> = {
        use rayon::prelude::*;
        charts
            .par_iter()
            .zip(pieces.par_iter())
            .map(|(original, list)| {
                list.iter()
                    .map(|piece| match &piece.uv {
                        Some(vuv) if piece.report.status != ChartStatus::Failed => {
                            metrics::face_distortion(piece.chart.as_ref().unwrap_or(original), vuv)
                        }
                        _ => Vec::new(),
                    })
                    .collect()
            })
            .collect()
    };
    let mut face_distortion = vec![[f64::NAN; 2]; mesh.n_faces()];
    for (f, d) in distortion.into_iter().flatten().flatten() {
        face_distortion[f as usize] = d;
    }

    let mut uv = vec![[0.0, 0.0]; n_corners];
    let mut face_chart = vec![-1i32; mesh.n_faces()];
    let mut reports = Vec::with_capacity(charts.len());
    let mut new_seams = Vec::new();
    for (original, list) in charts.iter().zip(pieces) {
        for piece in list {
            let chart = piece.chart.as_ref().unwrap_or(original);
            let mut report = piece.report;
            report.id = reports.len();
            for &f in &chart.faces {
                face_chart[f as usize] = report.id as i32;
            }
            if let Some(vuv) = piece.uv {
                for &(c, v) in chart.corner_vertex.iter() {
                    uv[c as usize] = vuv[v as usize];
                }
            }
            new_seams.extend(piece.seams);
            reports.push(report);
        }
    }
    new_seams.sort_unstable();
    new_seams.dedup();
    Ok(Unwrapped { uv, face_chart, charts: reports, new_seams, non_manifold_edges, face_distortion })
}

fn solve_chart(
    id: usize,
    chart: &Chart,
    pin_of_corner: &HashMap<u32, [f64; 2]>,
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
        cones: 0,
        cut_length: 0.0,
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
        if let Some(note) = place_chart(chart, &mut solution.uv, &options.fit) {
            report.reason = Some(match report.reason.take() {
                Some(r) => format!("{r}; {note}"),
                None => note,
            });
        }
    }
    let m = metrics::chart_metrics_with_quads(&chart.positions, &chart.triangles, &chart.quads, &solution.uv, &chart.boundary_loops);
    if !(m.area_3d > 0.0) {
        // Every face is degenerate (collinear or coincident corners): no UV map can match a
        // surface without area, so the chart keeps its UVs and says why.
        report.status = ChartStatus::Failed;
        report.method = options.method.name();
        report.reason = Some("the chart has no 3D area (every face is degenerate): its UVs are left as they were".into());
        report.seconds = start.elapsed().as_secs_f64();
        return (report, None);
    }
    report.flips = m.flips;
    report.overlap = m.overlap;
    report.distortion = m.distortion;
    report.seconds = start.elapsed().as_secs_f64();
    (report, Some(solution.uv))
}

/// Scale/place an unpinned chart's UVs per [`Fit`]. Returns a note for the report when the
/// fit onto the previous UVs was degenerate and the chart was area-scaled instead.
fn place_chart(chart: &Chart, uv: &mut [[f64; 2]], fit: &Fit) -> Option<String> {
    let tris = &chart.triangles;
    match fit {
        Fit::AreaScaled => metrics::area_normalize(&chart.positions, tris, uv, [0.0, 0.0]),
        Fit::Previous(prev) => {
            // Previous UV per chart vertex: the first corner seen for that vertex (a chart
            // holds only corners of selected faces, so nothing else is read).
            let mut target = vec![[f64::NAN; 2]; uv.len()];
            for &(c, v) in chart.corner_vertex.iter() {
                if target[v as usize][0].is_nan() {
                    target[v as usize] = prev[c as usize];
                }
            }
            if !metrics::fit_similarity(uv, &target, tris) {
                let seen: Vec<[f64; 2]> = target.iter().copied().filter(|p| !p[0].is_nan()).collect();
                let (centre, _) = crate::geometry::bounding_frame(&seen);
                metrics::area_normalize(&chart.positions, tris, uv, centre);
                return Some(
                    "the previous UVs admit no rotation-and-scale fit (collapsed or mirrored): area-scaled and centred on them instead".into(),
                );
            }
        }
    }
    None
}

/// One solved chart of the output: an input chart as built, or a piece of it made by
/// automatic seams.
struct Piece {
    /// The rebuilt chart, or `None` for the input chart itself.
    chart: Option<Chart>,
    report: ChartReport,
    uv: Option<Vec<[f64; 2]>>,
    /// Seams added for this piece (mesh vertex pairs).
    seams: Vec<[u32; 2]>,
}

/// What automatic cutting needs from the unwrap.
struct Context<'a, 'm> {
    mesh: &'a PolyMesh<'m>,
    /// The render triangulation, so rebuilt pieces split n-gons like the input charts.
    render: Option<&'a FaceTriangulation>,
    pins: &'a HashMap<u32, [f64; 2]>,
    options: &'a UnwrapOptions,
    avoid: &'a [bool],
}

/// Whether a solved piece is good enough to stop repairing: mapped, no flips, an outline that
/// does not cross itself, and area distortion within `area_bound` ([`cuts::area_bound`]).
fn piece_valid(report: &ChartReport, area_bound: f64) -> bool {
    report.status != ChartStatus::Failed && report.flips == 0 && !report.overlap && report.distortion.area <= area_bound
}

/// How bad a set of pieces is (lower is better): failures, overlaps, flips, then the
/// face-weighted excess of area distortion over `area_bound`.
fn badness(pieces: &[Piece], area_bound: f64) -> (usize, usize, usize, f64) {
    let failed = pieces.iter().filter(|p| p.report.status == ChartStatus::Failed).count();
    let overlaps = pieces.iter().filter(|p| p.report.overlap).count();
    let flips = pieces.iter().map(|p| p.report.flips).sum();
    let faces: usize = pieces.iter().map(|p| p.report.faces).sum::<usize>().max(1);
    let excess: f64 = pieces
        .iter()
        .map(|p| {
            let a = p.report.distortion.area;
            let e = if a.is_finite() { (a - area_bound).max(0.0) } else { 1e300 };
            e * p.report.faces as f64
        })
        .sum::<f64>()
        / faces as f64;
    (failed, overlaps, flips, excess)
}

/// `badness(a) < badness(b)`.
fn better(a: &[Piece], b: &[Piece], area_bound: f64) -> bool {
    let (x, y) = (badness(a, area_bound), badness(b, area_bound));
    (x.0, x.1, x.2).cmp(&(y.0, y.1, y.2)).then(x.3.total_cmp(&y.3)) == std::cmp::Ordering::Less
}

/// Faces of `chart` as a selection mask over the mesh.
fn face_mask(n_faces: usize, chart: &Chart) -> Vec<bool> {
    let mut mask = vec![false; n_faces];
    for &f in &chart.faces {
        mask[f as usize] = true;
    }
    mask
}

/// The chart vertex of `chart` whose neighbourhood is worst in `uv` of `piece`: a vertex of
/// a flipped triangle, else of the triangle of largest area distortion; mapped back to a
/// vertex of `original` through the shared corners.
fn worst_vertex(original: &Chart, piece: &Chart, uv: &[[f64; 2]]) -> Option<u32> {
    let tris = &piece.triangles;
    if tris.is_empty() {
        return None;
    }
    let area3: f64 = tris.iter().map(|t| tri_area3(piece, t)).sum();
    let area2: f64 = tris.iter().map(|t| tri_area2(uv, t)).sum::<f64>();
    let sign = if area2 < 0.0 { -1.0 } else { 1.0 };
    let scale = if area2.abs() > 0.0 { area3 / area2.abs() } else { 1.0 };
    let mut worst = (f64::NEG_INFINITY, 0usize);
    for (i, t) in tris.iter().enumerate() {
        let a2 = sign * tri_area2(uv, t) * scale;
        let a3 = tri_area3(piece, t);
        let badness = if a2 <= 0.0 { f64::INFINITY } else { (a2 / a3.max(1e-300)).ln().abs() };
        if badness > worst.0 {
            worst = (badness, i);
        }
    }
    let boundary = piece.boundary_mask();
    let t = tris[worst.1];
    // Prefer a vertex inside the piece (a cone on the cut is fine too).
    let v = t.iter().copied().find(|&v| !boundary[v as usize]).unwrap_or(t[0]);
    let corner = piece.corner_vertex.iter().find(|&&(_, pv)| pv == v)?.0;
    original.corner_vertex.iter().find(|&&(c, _)| c == corner).map(|&(_, ov)| ov)
}

fn tri_area3(chart: &Chart, t: &[u32; 3]) -> f64 {
    let p = |k: usize| chart.positions[t[k] as usize];
    crate::geometry::triangle_area([p(0), p(1), p(2)])
}

fn tri_area2(uv: &[[f64; 2]], t: &[u32; 3]) -> f64 {
    crate::geometry::signed_area_2d([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]])
}

/// Cut a closed or higher-genus chart into disks and solve them: cones and a cut graph, then
/// repair rounds (one more cone at the worst vertex while a piece flips or overlaps), then,
/// while still invalid and `depth < MAX_SPLIT_DEPTH`, halve the chart and start again on each
/// half. Never fails: the last attempt is returned with its honest report.
fn auto_cut(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]], depth: usize) -> Vec<Piece> {
    let mask = face_mask(ctx.mesh.n_faces(), chart);
    let max_stretch = cuts::area_bound(ctx.options.auto_seams.max_stretch);
    let mut seed: Vec<u32> = Vec::new();
    let mut last: Vec<Piece> = Vec::new();
    // Graph, costs and the scale system's analysis once; each round refactors numerically.
    let cutter = cuts::ChartCutter::new(ctx.mesh, chart, &ctx.options.auto_seams, ctx.avoid);
    for round in 0..=cuts::REPAIR_ROUNDS {
        let cut = cutter.cut(&seed, round);
        let mut all: Vec<[u32; 2]> = base_seams.to_vec();
        all.extend_from_slice(&cut.seams);
        let sub = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
        let mut pieces: Vec<Piece> = Vec::with_capacity(sub.len());
        let mut first = true;
        for c in sub {
            // A piece the cut did not open (it should not happen) fails in the solve with
            // its reason and is then repaired or split like any invalid piece.
            let (mut report, uv) = solve_chart(0, &c, ctx.pins, ctx.options);
            report.cones = if first { cut.cones.len() } else { 0 };
            report.cut_length = if first { cut.length } else { 0.0 };
            let seams = if first { cut.seams.clone() } else { Vec::new() };
            first = false;
            pieces.push(Piece { chart: Some(c), report, uv, seams });
        }
        let valid = pieces.iter().all(|p| piece_valid(&p.report, max_stretch));
        let next = pieces
            .iter()
            .find(|p| !piece_valid(&p.report, max_stretch))
            .and_then(|p| worst_vertex(chart, p.chart.as_ref()?, p.uv.as_ref()?));
        last = pieces;
        if valid {
            break;
        }
        match next {
            Some(v) if !seed.contains(&v) && !cut.cones.contains(&v) && !ctx.avoid[chart.mesh_vertex[v as usize] as usize] => {
                seed = cut.cones.clone();
                seed.push(v);
            }
            _ => break,
        }
    }
    let valid = last.iter().all(|p| piece_valid(&p.report, max_stretch));
    if !valid && depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
        let split = cuts::split::halve(cutter.graph(), chart, ctx.avoid);
        if !split.is_empty() {
            let mut all: Vec<[u32; 2]> = base_seams.to_vec();
            all.extend_from_slice(&split);
            let halves = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
            let mut out = Vec::new();
            let mut first = true;
            for h in halves {
                // Each half is cut again (cones, holes joined to its outline) as needed.
                let mut list = if h.defect.is_none() {
                    auto_cut(ctx, &h, &all, depth + 1)
                } else {
                    let (report, uv) = solve_chart(0, &h, ctx.pins, ctx.options);
                    vec![Piece { chart: Some(h), report, uv, seams: Vec::new() }]
                };
                if first {
                    if let Some(p) = list.first_mut() {
                        p.seams.extend_from_slice(&split);
                        p.report.cut_length += split_length(ctx.mesh, &split);
                    }
                    first = false;
                }
                out.extend(list);
            }
            if better(&out, &last, max_stretch) {
                return out;
            }
        }
    }
    last
}

/// 3D length of mesh edges given as vertex pairs.
fn split_length(mesh: &PolyMesh<'_>, seams: &[[u32; 2]]) -> f64 {
    let p = mesh.positions();
    seams.iter().map(|s| crate::geometry::norm(crate::geometry::sub(p[s[1] as usize], p[s[0] as usize]))).sum()
}
