//! Last resort: a piece that still breaks the atlas rule after its repair (cones, cuts and
//! every split level) is mapped by `scaffold`, which is globally bijective.
//!
//! Paper: Z. Jiang, S. Schaefer, D. Panozzo, "Simplicial complex augmentation framework for
//! bijective maps", ACM TOG 36(6), 2017 ([`crate::methods::scaffold`]): symmetric Dirichlet on
//! the chart plus a scaffold mesh of the free space around it, from a start that is already
//! bijective (Tutte's embedding onto a circle at worst), so the result has no flipped triangle
//! and an outline that does not cross itself, and its area-balancing energy keeps texel
//! density even.
//!
//! Where it is needed: cuts whose two sides a method does not open (a cut joining a hole to
//! the outline across nearly flat surface: LSCM, ABF, SLIM, ARAP or MIPS lay its two sides on
//! top of each other and they cross), and linear conformal maps (LSCM, spectral) whose free
//! boundary shrinks a region far more than the conformal prediction the cuts were planned on,
//! so that no split at the bounded depth keeps the rule.
//!
//! Preconditions: automatic seams on (the full rule); a method that finds the outline itself
//! (Tutte, mean value and harmonic keep the outline shape the user chose, and their islands
//! are reported as they are); the piece is a disk, unpinned (pins never move, and a pinned
//! chart is never cut), mapped, and not solved by `scaffold` already.
//! The replacement is kept only when it is better by the rule's order
//! ([`super::rule::AtlasRule::badness`]); it is reported [`super::outcome::ChartStatus::Fallback`]
//! with the method's own problem in the reason, so an artist who chose the method sees that
//! this island is not its map.
//!
//! Deterministic: pieces in order, one solve each.

use super::outcome::{ChartStatus, Problem};
use super::solve::solve_chart;
use super::{Context, Piece};
use crate::charts::{Chart, ChartKind};
use crate::methods::{scaffold::ScaffoldOptions, Method};

/// Charts below this many triangles whose area-balancing method's outline crosses itself
/// go to `scaffold` before the split ([`super::repair`]): it minimises the same kind of
/// energy with the outline held apart, so the chart stays one island. Larger charts are split
/// first: `scaffold` costs a factorization per iteration on the whole chart.
/// (fertility, 9,000 triangles: `scaffold` 1.3 s for one island where `slim`'s split took
/// 0.4 s for two).
pub const BEFORE_SPLIT_BELOW: usize = 20_000;

/// `scaffold`'s stopping tolerance here (relative change of its energy per iteration), looser
/// than its default 1e-4: every iterate is bijective already, and what the last resort needs
/// is the rule, not the last fraction of a percent of the energy.
pub const TOLERANCE: f64 = 1e-3;

/// Replace, in `pieces` (the outcome of one input chart, `original`), every piece that breaks
/// the rule by `scaffold`'s map when that keeps the rule better (see the module docs).
/// `tried`: what the method was given before ("its cones", "its cones and splits"), for the
/// report.
pub fn apply(ctx: &Context<'_, '_>, original: &Chart, pieces: &mut [Piece], tried: &str) {
    if !ctx.rule.full || !ctx.options.method.free_boundary() || matches!(ctx.options.method, Method::Scaffold(_)) {
        return;
    }
    for piece in pieces.iter_mut() {
        if crate::progress::cancelled() {
            return;
        }
        let broken = match piece.report.status {
            ChartStatus::Invalid => piece.report.problem,
            _ => None,
        };
        if !matches!(broken, Some(Problem::Flips | Problem::Overlap | Problem::Stretch)) {
            continue;
        }
        if piece.report.method == "scaffold" {
            continue;
        }
        let chart = piece.chart.as_ref().unwrap_or(original);
        if chart.kind != ChartKind::Disk || super::pinned(ctx, chart) {
            continue;
        }
        let t = std::time::Instant::now();
        let options = crate::unwrap::UnwrapOptions {
            method: Method::Scaffold(ScaffoldOptions { tolerance: TOLERANCE, ..ScaffoldOptions::default() }),
            ..ctx.options.clone()
        };
        let (mut report, uv, face_flips) = solve_chart(chart, ctx.pins, &options, &ctx.rule);
        ctx.clock.add(|p| {
            p.repair_solve += t.elapsed().as_secs_f64();
            p.repair_pieces += 1;
            p.last_resort += 1;
        });
        if uv.is_none() || ctx.rule.badness(&report, piece.area) >= ctx.rule.badness(&piece.report, piece.area) {
            continue;
        }
        let why = piece.report.reason.clone().unwrap_or_default();
        let own = if report.status == ChartStatus::Invalid { report.reason.clone() } else { None };
        report.reason = Some(format!(
            "{} broke the atlas rule after {tried} ({why}); scaffold, which is globally bijective, was used instead{}",
            ctx.options.method.name(),
            own.map(|r| format!(": {r}")).unwrap_or_default()
        ));
        if report.status != ChartStatus::Invalid {
            report.status = ChartStatus::Fallback;
            report.problem = Some(Problem::FellBack);
        }
        report.cones = piece.report.cones;
        report.cut_length = piece.report.cut_length;
        piece.report = report;
        piece.uv = uv;
        piece.face_flips = face_flips;
    }
}

