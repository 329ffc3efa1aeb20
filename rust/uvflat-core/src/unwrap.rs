//! The one-call pipeline: validate, fill small holes, split into charts, map each chart in
//! parallel, measure.

use std::collections::HashMap;

pub use crate::charts::ChartKind;
use crate::charts::{build_charts_counting, Chart, FaceTriangulation};
use crate::cuts::AutoSeamOptions;
use crate::error::{Result, UvError};
use crate::methods::Method;
use crate::metrics;
use crate::pipeline::{self, Context, Piece};
pub use crate::pipeline::outcome::{ChartReport, ChartStatus, Problem};
pub use crate::pipeline::phases::Phases;
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
    /// The parameterization method and its own options. Default: [`Method::Abf`].
    pub method: Method,
    /// Placement of the solved charts. Default: [`Fit::AreaScaled`].
    pub fit: Fit,
    /// Automatic seams: every chart held to the atlas rule and cut where it breaks it (see
    /// [`crate::pipeline`]). Default: on.
    pub auto_seams: AutoSeamOptions,
    /// Progress callback and cancel flag, polled between charts and between iterations of
    /// the iterative methods. Default: none.
    pub progress: Option<Progress>,
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
    /// Of `new_seams`, those whose two sides keep the same UVs (closed seams): the paths that
    /// join filled holes to their islands' outlines ([`crate::pipeline::fill`]), sorted. They
    /// make each island a disk but show no texture seam.
    pub closed_seams: Vec<[u32; 2]>,
    /// Edges of the selection used by three or more selected faces; each was treated as a
    /// seam (a mesh with many of them is shredded into many small charts).
    pub non_manifold_edges: usize,
    /// Edges of two selected faces whose normals point to opposite sides (the faces traverse
    /// the edge in the same direction); each was treated as a seam. Recalculating the normals
    /// in Blender joins them again, except on a one-sided surface.
    pub inconsistent_edges: usize,
    /// `[conformal, area]` distortion of every face that received UVs, as
    /// [`crate::metrics::MeshMetrics::per_face`] defines it (3D-area-weighted over the face's
    /// triangles, the chart's UVs area-normalised); NaN elsewhere. Measured on the returned
    /// UVs, so a caller needs no second pass to colour faces by quality.
    pub face_distortion: Vec<[f64; 2]>,
    /// Flipped or zero-area UV triangles of every face, as its chart's report counts them
    /// ([`crate::metrics::face_flips`]: Blender's render triangles, a quad counting the flips
    /// of its worse diagonal split); 0 for faces without UVs. Each report's `flips` is the sum
    /// over its chart's faces.
    pub face_flips: Vec<u32>,
    /// Seconds per pipeline step and the repair counts.
    pub phases: Phases,
}

impl Unwrapped {
    /// Whether face `f` received UVs (its chart was solved or fell back).
    pub fn face_solved(&self, f: usize) -> bool {
        let c = self.face_chart[f];
        c >= 0 && self.charts[c as usize].status.mapped()
    }
}

/// Unwrap the selected faces of a polygon mesh.
///
/// With automatic seams, small holes are filled for the unwrap and joined to their islands'
/// outlines by closed seams after it ([`crate::pipeline::fill`]); when an island then breaks
/// the rule, the mesh is unwrapped again as it is (a progress callback then counts its charts
/// from zero again).
///
/// Preconditions: none beyond the types; every input is validated.
///
/// Errors: a [`crate::UvError`] naming the offending face, corner, vertex, seam or pin for malformed
/// input. Charts that cannot be mapped (closed, higher genus, singular systems) are *not*
/// errors: they come back with [`ChartStatus::Failed`] and a reason.
pub fn unwrap(input: &MeshInput<'_>, options: &UnwrapOptions) -> Result<Unwrapped> {
    let started = std::time::Instant::now();
    let mesh = crate::validate::validate_input(input, Some(&options.fit), Some(&options.method))?;
    options.auto_seams.validate(input.positions.len())?;
    // Charts run in parallel; inside one chart the sparse factorizations of the sizes met in
    // practice are faster sequential than split across threads.
    faer::set_global_parallelism(faer::Par::Seq);

    let render = if input.triangles.is_empty() { None } else { Some(FaceTriangulation::new(&mesh, input.triangles)?) };
    // Small holes are filled for the unwrap and joined to the outlines by closed seams after it
    // (`pipeline::fill`); when that leaves an island beyond the rule, the mesh is unwrapped as
    // it is.
    if let Some(filled) = pipeline::fill::Filled::plan(&mesh, input, options, render.as_ref()) {
        let filled_input = filled.input(input);
        let filled_options = filled.options(options);
        let fit = Some(&filled_options.fit);
        let filled_mesh = crate::validate::validate_input(&filled_input, fit, Some(&options.method))?;
        let filled_render = match render {
            Some(_) => Some(FaceTriangulation::new(&filled_mesh, filled_input.triangles)?),
            None => None,
        };
        let r = unwrap_mesh(&filled_mesh, filled_render.as_ref(), &filled_input, &filled_options, started)?;
        if let Some(mut r) = filled.restore(&mesh, render.as_ref(), input, options, r) {
            r.phases.holes_filled = filled.holes;
            return Ok(r);
        }
        let undone = started.elapsed().as_secs_f64();
        let mut r = unwrap_mesh(&mesh, render.as_ref(), input, options, std::time::Instant::now())?;
        r.phases.fill_undone = undone;
        return Ok(r);
    }
    unwrap_mesh(&mesh, render.as_ref(), input, options, started)
}

/// [`unwrap`] of `input`, validated as `mesh` (`render`: its render triangulation), timed from
/// `started`.
fn unwrap_mesh(
    mesh: &crate::mesh::PolyMesh<'_>,
    render: Option<&FaceTriangulation>,
    input: &MeshInput<'_>,
    options: &UnwrapOptions,
    started: std::time::Instant,
) -> Result<Unwrapped> {
    let n_corners = mesh.n_corners();
    let (charts, cut_edges) = build_charts_counting(mesh, input.seams, input.selected, render);
    // Pinned corners only (a later pin of the same corner wins): nothing per corner when
    // there are no pins.
    let pin_of_corner: HashMap<u32, [f64; 2]> = input.pins.iter().copied().collect();

    let mut avoid = vec![false; input.positions.len()];
    for &v in &options.auto_seams.avoid_vertices {
        avoid[v as usize] = true;
    }
    let ctx = Context::new(mesh, render, &pin_of_corner, options, &avoid);
    ctx.clock.add(|p| p.build_charts = started.elapsed().as_secs_f64());
    // With a Progress: charts after a cancel are skipped (None), and the unwrap is an error.
    let total = charts.len();
    if let Some(p) = &options.progress {
        p.start(total);
    }
    let run = |chart: &Chart| -> Vec<Piece> { pipeline::run_chart(&ctx, chart, input.seams) };
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
    let measured = std::time::Instant::now();
    let distortion: Vec<Vec<Vec<(u32, [f64; 2])>>> = {
        use rayon::prelude::*;
        charts
            .par_iter()
            .zip(pieces.par_iter())
            .map(|(original, list)| {
                list.iter()
                    .map(|piece| match &piece.uv {
                        Some(vuv) if piece.report.status.mapped() => {
                            metrics::face_distortion(piece.chart.as_ref().unwrap_or(original), vuv)
                        }
                        _ => Vec::new(),
                    })
                    .collect()
            })
            .collect()
    };
    ctx.clock.add(|p| p.measure = measured.elapsed().as_secs_f64());
    let mut face_distortion = vec![[f64::NAN; 2]; mesh.n_faces()];
    for (f, d) in distortion.into_iter().flatten().flatten() {
        face_distortion[f as usize] = d;
    }

    let mut uv = vec![[0.0, 0.0]; n_corners];
    let mut face_chart = vec![-1i32; mesh.n_faces()];
    let mut face_flips = vec![0u32; mesh.n_faces()];
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
            for (&f, &n) in chart.faces.iter().zip(&piece.face_flips) {
                face_flips[f as usize] = n;
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
    Ok(Unwrapped { uv, face_chart, charts: reports, new_seams, closed_seams: Vec::new(),
        non_manifold_edges: cut_edges.non_manifold,
        inconsistent_edges: cut_edges.inconsistent, face_distortion, face_flips, phases: ctx.clock.get() })
}


/// The seams automatic seams would add to the selected faces, without writing UVs: the
/// *Mark Seams Only* mode, so an artist can review and edit them before unwrapping.
///
/// Exactly the `new_seams` of [`unwrap`] with the same input and options (the pieces are
/// solved to check the rule, so the plan is the one an unwrap would cut).
///
/// Errors: those of [`unwrap`].
pub fn plan_seams(input: &MeshInput<'_>, options: &UnwrapOptions) -> Result<Vec<[u32; 2]>> {
    Ok(unwrap(input, options)?.new_seams)
}
