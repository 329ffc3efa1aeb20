//! Solve one chart with the user's method, place it, measure it and hold it to its rule.

use std::collections::HashMap;

use super::outcome::{ChartReport, ChartStatus, Problem};
use super::rule::AtlasRule;
use crate::charts::{Chart, ChartKind};
use crate::methods::{self, ChartFailure};
use crate::metrics;
use crate::unwrap::{Fit, UnwrapOptions};

/// Map `chart` with `options.method`, place it per `options.fit` (unpinned charts only),
/// measure it (flips on the render triangles and both splits of every quad, outline overlap,
/// distortion, density spread against `rule.max_stretch`) and set its status and problem.
///
/// Never fails: a chart the method cannot map comes back [`ChartStatus::Failed`] with no UVs.
///
/// Returns the report, the UVs (per chart vertex) and the flipped triangles of every face of
/// the chart (aligned with `chart.faces`; empty without UVs), whose sum is the report's
/// `flips`.
pub fn solve_chart(
    chart: &Chart,
    pin_of_corner: &HashMap<u32, [f64; 2]>,
    options: &UnwrapOptions,
    rule: &AtlasRule,
) -> (ChartReport, Option<Vec<[f64; 2]>>, Vec<u32>) {
    let start = std::time::Instant::now();
    let mut report = ChartReport::new(chart, options.method.name());
    // Pins per chart vertex (average when corners of one vertex disagree).
    let pins = chart.vertex_pins(pin_of_corner);
    let mut solution = match methods::solve(&options.method, chart, &pins) {
        Ok(s) => s,
        Err(ChartFailure(reason)) => {
            report.problem = Some(if chart.defect.is_some() {
                Problem::Defect
            } else {
                match chart.kind {
                    ChartKind::Closed => Problem::ClosedSurface,
                    ChartKind::HigherGenus => Problem::Handles,
                    _ => Problem::Solver,
                }
            });
            report.reason = Some(reason);
            report.seconds = start.elapsed().as_secs_f64();
            return (report, None, Vec::new());
        }
    };
    if let Some(fallback) = solution.fallback.take() {
        report.status = ChartStatus::Fallback;
        report.problem = Some(Problem::FellBack);
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
            append(&mut report.reason, note);
        }
    }
    let Some(face_flips) = measure(chart, &solution.uv, &mut report, rule) else {
        // Every face is degenerate (collinear or coincident corners): no UV map can match a
        // surface without area, so the chart keeps its UVs and says why.
        report.status = ChartStatus::Failed;
        report.problem = Some(Problem::NoArea);
        report.method = options.method.name();
        report.reason = Some("the chart has no 3D area (every face is degenerate): its UVs are left as they were".into());
        report.seconds = start.elapsed().as_secs_f64();
        return (report, None, Vec::new());
    };
    report.seconds = start.elapsed().as_secs_f64();
    (report, Some(solution.uv), face_flips)
}

/// Measure `uv` on `chart` into `report` (flips on the render triangles and both splits of
/// every quad, outline overlap, distortion, density spread against `rule.max_stretch`) and
/// hold it to `rule`. Returns the flipped triangles of every face (aligned with
/// `chart.faces`), or `None` when the chart has no 3D area (nothing is measured).
pub fn measure(chart: &Chart, uv: &[[f64; 2]], report: &mut ChartReport, rule: &AtlasRule) -> Option<Vec<u32>> {
    // Flips are counted below, per face (quads on both splits); the rest measured here.
    let m = metrics::chart_metrics(&chart.positions, &chart.triangles, uv, &chart.boundary_loops);
    if !(m.area_3d > 0.0) {
        return None;
    }
    // Per face (the render triangles of n-gons that kept the core's split count too); the
    // report's count is their sum.
    let face_flips = metrics::face_flips(chart, uv);
    report.flips = face_flips.iter().map(|&n| n as usize).sum();
    report.overlap = m.overlap;
    report.distortion = m.distortion;
    report.density = metrics::density_spread(&chart.positions, &chart.triangles, uv, rule.max_stretch);
    hold_to(rule, report);
    Some(face_flips)
}

/// The report of an island rebuilt as `chart` with `uv` (faces laid on it, holes joined), from
/// `old`, the report of the island it was: the chart's own counts, the status kept (solved, or
/// a fallback, with its reason), measured again against `rule` by [`measure`], with the
/// flips per face. `None` when the island cannot be measured.
pub fn remeasure(
    chart: &Chart,
    uv: &[[f64; 2]],
    old: &ChartReport,
    rule: &AtlasRule,
) -> Option<(ChartReport, Vec<u32>)> {
    let mut report = old.clone();
    let fresh = ChartReport::new(chart, old.method);
    report.faces = fresh.faces;
    report.triangles = fresh.triangles;
    report.vertices = fresh.vertices;
    report.boundary_loops = fresh.boundary_loops;
    report.genus = fresh.genus;
    report.kind = fresh.kind;
    let fell_back = old.status == ChartStatus::Fallback;
    report.status = if fell_back { ChartStatus::Fallback } else { ChartStatus::Solved };
    report.problem = fell_back.then_some(Problem::FellBack);
    let face_flips = measure(chart, uv, &mut report, rule)?;
    Some((report, face_flips))
}

/// What [`hold_to`] appends to the reason of a report whose outline crosses itself.
pub const OVERLAP_NOTE: &str = "the island's outline crosses itself";

/// What [`hold_to`] appends to the reason of a report with `flips` flipped triangles.
pub fn flips_note(flips: usize) -> String {
    format!("{flips} flipped or zero-area UV triangle(s)")
}

/// Mark a mapped report [`ChartStatus::Invalid`] when it breaks `rule`, saying how.
pub fn hold_to(rule: &AtlasRule, report: &mut ChartReport) {
    let Some(problem) = rule.broken(report) else { return };
    let what = match problem {
        Problem::Flips => flips_note(report.flips),
        Problem::Overlap => OVERLAP_NOTE.to_string(),
        Problem::NotDisk => format!(
            "the island is not a disk ({} boundary loop(s), genus {})",
            report.boundary_loops, report.genus
        ),
        Problem::Stretch => format!(
            "{:.1}% of the island has a texel density outside [1/{s}, {s}] of its own (at most {:.0}% allowed; 5th–95th percentile {:.2}–{:.2})",
            100.0 * report.density.outside,
            100.0 * super::rule::MAX_OUTSIDE_SHARE,
            report.density.p5,
            report.density.p95,
            s = report.density.bound,
        ),
        _ => return,
    };
    report.status = ChartStatus::Invalid;
    report.problem = Some(problem);
    append(&mut report.reason, what);
}

/// Append `note` to a report's prose reason.
pub fn append(reason: &mut Option<String>, note: String) {
    *reason = Some(match reason.take() {
        Some(r) => format!("{r}; {note}"),
        None => note,
    });
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
