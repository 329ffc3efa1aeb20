//! The chart pipeline: the one road every chart of an unwrap takes.
//!
//! ```text
//! triage ──► plan cuts ──► solve ──► check the rule ──► repair ──┐
//!   │        (cuts/)      (solve)      (rule)          (repair) │
//!   └──── solve as it is ───────────────►│◄──────── bounded ─────┘
//! ```
//!
//! 1. [`triage`]: with automatic seams on, closed charts, charts with handles and charts with
//!    holes are cut first; disks are solved as they are and repaired only if they break the
//!    rule; pinned disks and charts with a defect are never cut. With automatic seams off
//!    every chart is solved as it is.
//!    A disk is cut first when its predicted flattening ([`crate::cuts::predicted_outside`])
//!    breaks Max Stretch ([`triage::predicted_limit`]: [`triage::PREDICTED_BREAK_PLANNED`];
//!    under a method that balances area, with [`crate::cuts::AutoSeamOptions::same_seams`]
//!    off, only a disk of [`triage::PREDICT_FROM`] triangles or more, and only by far:
//!    [`triage::PREDICTED_BREAK`] for one it would cut into parts, [`triage::PREDICTED_FAR`]
//!    for the others, nearly closed surfaces).
//!    A hard surface (flat or rolled everywhere but along its creases, with more curved
//!    vertices than cones) is first cut along its creases ([`creases`]), each region taking
//!    the road on its own.
//! 2. Plan cuts: [`crate::cuts::ChartCutter`] (cones on the conformal scale factor, handle
//!    loops, holes and cones joined to the outline by a Steiner tree of low-cost edges), and
//!    [`predict::plan`]: more cones while the predicted flattening of a piece breaks Max
//!    Stretch, one factorization per round instead of a solve. The plan does not depend on the
//!    method; methods that balance area start from the cutter's cones as they are unless
//!    [`crate::cuts::AutoSeamOptions::same_seams`] is on.
//! 3. Solve: [`solve::solve_chart`] maps a piece with the user's method, places and measures
//!    it.
//! 4. Check: [`rule::AtlasRule`] (a disk, no flips, an outline that does not cross itself,
//!    at most 5% of the area outside `[1/s, s]` of the island's density).
//! 5. Repair: [`repair::repair`] adds a cone at the worst region and re-cuts, then halves the
//!    chart, each half taking the road again. On a large piece whose only problem is an
//!    outline that crosses itself at a few places, [`peel::apply`] first makes the faces
//!    there islands of their own, keeping the rest's map.
//! 6. Last resort: [`last_resort::apply`] maps a piece that still breaks the rule after its
//!    repair by the method's flip-free kin or by `scaffold` (globally bijective), reported as
//!    a fallback.
//! 7. Glue: [`glue::apply`] lays the faces of small islands left by the steps above on the
//!    islands around them where they fit, keeping those islands' maps.
//!
//! Around the whole road, at the level of the mesh: [`fill`] fills the mesh's small holes
//! before it and joins them to the islands' outlines by closed seams after it.
//!
//! A new step is one file here; the outcome of every chart is a typed value
//! ([`outcome::ChartStatus`], [`outcome::Problem`]).

pub mod creases;
pub mod fill;
pub mod glue;
pub mod last_resort;
pub mod outcome;
pub mod parts;
pub mod peel;
pub mod phases;
pub mod predict;
pub mod repair;
pub mod rule;
pub mod solve;
pub mod triage;

use std::collections::HashMap;

use crate::charts::{Chart, FaceTriangulation};
use crate::mesh::PolyMesh;
use crate::unwrap::UnwrapOptions;
use outcome::ChartReport;
use rule::AtlasRule;
use triage::Triage;

/// What the pipeline reads from the unwrap.
pub struct Context<'a, 'm> {
    /// The validated mesh.
    pub mesh: &'a PolyMesh<'m>,
    /// The render triangulation, so rebuilt pieces split n-gons like the input charts.
    pub render: Option<&'a FaceTriangulation>,
    /// Pinned corners and their UVs.
    pub pins: &'a HashMap<u32, [f64; 2]>,
    /// The unwrap's options.
    pub options: &'a UnwrapOptions,
    /// Per mesh vertex: whether new seams must stay away from it.
    pub avoid: &'a [bool],
    /// The rule every chart is held to.
    pub rule: AtlasRule,
    /// Seconds per step, summed over charts.
    pub clock: phases::PhaseClock,
    /// Occlusion rays cast so far, per corner (a chart's pieces reuse its rays).
    pub visibility: crate::cuts::visibility::VisibilityCache,
}

impl<'a, 'm> Context<'a, 'm> {
    /// The context of an unwrap of `mesh` with `options`: the rule from the options (the full
    /// rule with automatic seams on), no time spent yet, no ray cast yet.
    pub fn new(
        mesh: &'a PolyMesh<'m>,
        render: Option<&'a FaceTriangulation>,
        pins: &'a HashMap<u32, [f64; 2]>,
        options: &'a UnwrapOptions,
        avoid: &'a [bool],
    ) -> Self {
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: options.auto_seams.enabled };
        let visibility = crate::cuts::visibility::VisibilityCache::new(mesh.n_corners());
        Context { mesh, render, pins, options, avoid, rule, clock: Default::default(), visibility }
    }
}

impl Context<'_, '_> {
    /// Whether cuts are planned on the prediction ([`predict::plan`]): always, unless
    /// [`crate::cuts::AutoSeamOptions::same_seams`] is off and the method balances area (SLIM,
    /// ARAP, scaffold), which then starts from the cutter's cones as they are.
    pub fn plans_on_prediction(&self) -> bool {
        self.options.auto_seams.same_seams || !self.options.method.balances_area()
    }
}

/// One solved piece of the output: an input chart as built, or a piece of it made by cuts.
#[derive(Clone)]
pub struct Piece {
    /// The rebuilt chart, or `None` for the input chart itself.
    pub chart: Option<Chart>,
    /// Its report.
    pub report: ChartReport,
    /// UV per chart vertex (`None` when the chart failed).
    pub uv: Option<Vec<[f64; 2]>>,
    /// Flipped triangles of every face of the piece (aligned with its chart's `faces`; empty
    /// without UVs): the report's `flips` is their sum.
    pub face_flips: Vec<u32>,
    /// Seams added for this piece (mesh vertex pairs).
    pub seams: Vec<[u32; 2]>,
    /// 3D area of the piece.
    pub area: f64,
}

impl Piece {
    /// A piece of `chart` (its 3D area measured here).
    pub fn new(
        chart: Option<Chart>,
        report: ChartReport,
        uv: Option<Vec<[f64; 2]>>,
        face_flips: Vec<u32>,
        seams: Vec<[u32; 2]>,
    ) -> Piece {
        let area = chart.as_ref().map_or(0.0, chart_area);
        Piece { chart, report, uv, face_flips, seams, area }
    }
}

fn chart_area(chart: &Chart) -> f64 {
    chart
        .triangles
        .iter()
        .map(|t| {
            crate::geometry::triangle_area([
                chart.positions[t[0] as usize],
                chart.positions[t[1] as usize],
                chart.positions[t[2] as usize],
            ])
        })
        .sum()
}

/// Take one input chart through the pipeline (`base_seams`: the user's seams). A piece that
/// is the chart itself, uncut, carries `chart: None`.
pub fn run_chart(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]]) -> Vec<Piece> {
    let mut pieces = road(ctx, chart, base_seams, 0);
    glue::apply(ctx, chart, &mut pieces);
    pieces
}

/// [`run_chart`] for an owned piece (a half of a split) at split depth `depth`: every piece
/// carries its chart.
pub(crate) fn run(ctx: &Context<'_, '_>, chart: Chart, base_seams: &[[u32; 2]], depth: usize) -> Vec<Piece> {
    let mut out = road(ctx, &chart, base_seams, depth);
    if let Some(p) = out.iter_mut().find(|p| p.chart.is_none()) {
        p.chart = Some(chart);
    }
    out
}

fn road(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]], depth: usize) -> Vec<Piece> {
    let is_pinned = pinned(ctx, chart);
    let road = triage::triage(chart, ctx.options.auto_seams.enabled, is_pinned);
    if road != Triage::Solve && !is_pinned {
        // A hard surface is cut along its creases first; its regions take the road anew (a
        // pinned chart keeps its road: its pins are the user's layout).
        let t = std::time::Instant::now();
        let creases = creases::crease_seams(ctx, chart);
        ctx.clock.add(|p| p.plan(t, |p| &mut p.cut_state));
        if let Some(creases) = creases {
            return creases::regions(ctx, chart, base_seams, depth, &creases);
        }
    }
    if road == Triage::Cut {
        return repair::repair(ctx, chart, base_seams, depth, None, None);
    }
    // The scale system of the prediction, kept for the cutter if the disk is cut.
    let mut solver = None;
    let limit = if road == Triage::SolveThenRepair { triage::predicted_limit(ctx, chart) } else { None };
    if let Some(limit) = limit {
        // A disk whose conformal flattening is predicted to break Max Stretch is cut before
        // any solve (the solve as it is would be thrown away; see the bounds). Only the
        // scale system is built here: the cutter's graph, costs and occlusion rays wait until
        // a cut is due.
        // Under a method that balances area this is asked of large disks only, by far
        // (an open scan, the camel's head subdivided twice under `slim`: 7.6 s of 12.9 s,
        // thrown away; a closed scan with one small hole).
        let t = std::time::Instant::now();
        let s = crate::cuts::cones::ScaleSolver::new(chart);
        let predicted = s.as_ref().and_then(|s| crate::cuts::predicted_outside(chart, s, ctx.rule.max_stretch));
        ctx.clock.add(|p| p.plan(t, |p| &mut p.cut_state));
        if predicted.is_some_and(|o| o > limit) {
            let cutter = repair::cutter_with(ctx, chart, s);
            return repair::repair(ctx, chart, base_seams, depth, None, Some(cutter));
        }
        solver = Some(s);
    }
    let t = std::time::Instant::now();
    let (report, uv, face_flips) = solve::solve_chart(chart, ctx.pins, ctx.options, &ctx.rule);
    ctx.clock.add(|p| p.solve += t.elapsed().as_secs_f64());
    let broken = !report.status.mapped() || ctx.rule.broken(&report).is_some();
    let first = Piece { chart: None, report, uv, face_flips, seams: Vec::new(), area: chart_area(chart) };
    if road == Triage::SolveThenRepair && broken {
        // A large disk whose outline crosses itself at a few places keeps its map: the faces
        // there become islands of their own.
        let mut peeled = vec![first];
        peel::apply(ctx, chart, base_seams, &mut peeled);
        // A peel replaces the chart's own solve (`chart: None`) by rebuilt pieces.
        if peeled.len() != 1 || peeled[0].chart.is_some() {
            return peeled;
        }
        let first = peeled.pop().expect("one piece");
        let cutter = solver.map(|s| repair::cutter_with(ctx, chart, s));
        repair::repair(ctx, chart, base_seams, depth, Some(first), cutter)
    } else {
        vec![first]
    }
}

#[cfg(test)]
pub(crate) mod test_mesh {
    /// A flat grid of `cols × rows` cells of `w × h`, two triangles each (cell `(i, j)` holds
    /// faces `2 (j cols + i)` and the next): positions, corners, face sizes.
    pub fn grid(cols: usize, rows: usize, w: f64, h: f64) -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
        let mut positions = Vec::new();
        for j in 0..=rows {
            for i in 0..=cols {
                positions.push([w * i as f64, h * j as f64, 0.0]);
            }
        }
        let id = |i: usize, j: usize| (j * (cols + 1) + i) as u32;
        let mut corners = Vec::new();
        for j in 0..rows {
            for i in 0..cols {
                corners.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                corners.extend([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let sizes = vec![3u32; corners.len() / 3];
        (positions, corners, sizes)
    }
}

/// The mesh vertex pairs (sorted) of every side of `chart`'s outline, slits included.
pub(crate) fn outline_pairs(chart: &Chart) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    for l in &chart.boundary_loops {
        for i in 0..l.len() {
            let (a, b) = (chart.mesh_vertex[l[i] as usize], chart.mesh_vertex[l[(i + 1) % l.len()] as usize]);
            out.push([a.min(b), a.max(b)]);
        }
    }
    out
}

/// Whether any corner of `chart` is pinned.
pub(crate) fn pinned(ctx: &Context<'_, '_>, chart: &Chart) -> bool {
    !ctx.pins.is_empty() && chart.corner_vertex.iter().any(|(c, _)| ctx.pins.contains_key(c))
}
