//! Last resort: a piece that still breaks the atlas rule after its repair (cones, cuts and
//! every split level) is mapped by the method's flip-free kin when flips or stretch broke it,
//! and by `scaffold`, which is globally bijective, when that does not keep the rule either.
//!
//! The kin ([`kin`]): a map of the same kind as the method's that never flips a triangle, so
//! the island keeps the look the artist chose where it can: MIPS for the conformal methods
//! (LSCM, spectral, ABF: MIPS minimises angle distortion only, from a flip-free start with a
//! flip-free line search, [`crate::methods::mips`]) and SLIM for ARAP (both keep lengths).
//! Neither holds the outline apart, so the kin is tried only on flips and stretch (the linear
//! maps, LSCM above all, crush regions far from where their free boundary is held, where the
//! nonlinear ones spread the same kind of distortion evenly).
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
//! top of each other and they cross), linear maps that promise no flips (LSCM, spectral,
//! ARAP: a few flipped triangles where quads or slivers meet), and linear conformal maps
//! whose free boundary shrinks a region far more than the conformal prediction the cuts were
//! planned on, so that no split at the bounded depth keeps the rule.
//!
//! Preconditions: automatic seams on (the full rule); a method that finds the outline itself
//! (Tutte, mean value and harmonic keep the outline shape the user chose, and their islands
//! are reported as they are); the piece is a disk, unpinned (pins never move, and a pinned
//! chart is never cut), mapped, and not solved by `scaffold` already.
//! A replacement is kept only when it is better by the rule's order
//! ([`super::rule::AtlasRule::badness`]); it is reported [`super::outcome::ChartStatus::Fallback`]
//! with the method's own problem in the reason, so an artist who chose the method sees that
//! this island is not its map.
//!
//! Deterministic: pieces in order, at most two solves each (the kin, then `scaffold`).

use super::outcome::{ChartStatus, Problem};
use super::solve::solve_chart;
use super::{Context, Piece};
use crate::charts::{Chart, ChartKind};
use crate::methods::{scaffold::ScaffoldOptions, Method};

/// The method's flip-free kin (module docs): MIPS for LSCM, spectral, bff and ABF, SLIM for ARAP;
/// `None` for the methods that promise no flips already.
pub fn kin(method: &Method) -> Option<Method> {
    match method {
        Method::Lscm | Method::Spectral(_) | Method::Bff | Method::Abf(_) => Some(Method::Mips(Default::default())),
        Method::Arap(_) => Some(Method::Slim(Default::default())),
        _ => None,
    }
}

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
/// the rule by its method's [`kin`] (on flips and stretch) or by `scaffold`: the first that
/// keeps the rule, else the one that comes nearest if it is better than the piece (see the
/// module docs).
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
        let mut candidates: Vec<Method> = Vec::with_capacity(2);
        if matches!(broken, Some(Problem::Flips | Problem::Stretch)) {
            candidates.extend(kin(&ctx.options.method));
        }
        candidates.push(Method::Scaffold(ScaffoldOptions { tolerance: TOLERANCE, ..ScaffoldOptions::default() }));
        let mut found = None;
        let mut least = ctx.rule.badness(&piece.report, piece.area);
        for method in candidates {
            let t = std::time::Instant::now();
            let name = method.name();
            let what = if matches!(method, Method::Scaffold(_)) {
                "is globally bijective"
            } else {
                "never flips a triangle"
            };
            let options = crate::unwrap::UnwrapOptions { method, ..ctx.options.clone() };
            let (report, uv, face_flips) = solve_chart(chart, ctx.pins, &options, &ctx.rule);
            ctx.clock.add(|p| {
                p.repair_solve += t.elapsed().as_secs_f64();
                p.repair_pieces += 1;
                p.last_resort += 1;
            });
            // Only the candidate's own map (not a fallback of its solve) replaces the piece.
            let badness = ctx.rule.badness(&report, piece.area);
            if uv.is_none() || report.method != name || badness >= least {
                continue;
            }
            least = badness;
            let keeps = report.status != ChartStatus::Invalid;
            found = Some((name, what, report, uv, face_flips));
            if keeps {
                break;
            }
        }
        let Some((name, what, mut report, uv, face_flips)) = found else {
            continue;
        };
        let why = piece.report.reason.clone().unwrap_or_default();
        let own = if report.status == ChartStatus::Invalid { report.reason.clone() } else { None };
        report.reason = Some(format!(
            "{} broke the atlas rule after {tried} ({why}); {}, which {}, was used instead{}",
            ctx.options.method.name(),
            name,
            what,
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
