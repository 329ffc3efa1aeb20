//! Triage: which road a chart takes through the pipeline.

use crate::charts::{Chart, ChartKind};

/// The road of one chart (see [`triage`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Triage {
    /// Solve as it is and report (automatic seams off, a defect, no triangles, or a pinned
    /// disk: pins are the user's layout and are never cut).
    Solve,
    /// Solve as it is; repair (cones, cuts, splits) only if the result breaks the rule, or
    /// before any solve when it is predicted to break it ([`predicted_limit`]).
    SolveThenRepair,
    /// Cut before solving: a closed chart, a chart with handles, or a chart with holes
    /// (holes are joined to the outline so the island is a disk).
    Cut,
}

/// Triage `chart` (see [`Triage`]). `pinned`: whether any corner of the chart is pinned.
pub fn triage(chart: &Chart, auto_seams: bool, pinned: bool) -> Triage {
    if !auto_seams || chart.defect.is_some() || chart.triangles.is_empty() {
        return Triage::Solve;
    }
    match chart.kind {
        ChartKind::Closed | ChartKind::HigherGenus => Triage::Cut,
        _ if pinned => Triage::Solve,
        ChartKind::DiskWithHoles => Triage::Cut,
        ChartKind::Disk => Triage::SolveThenRepair,
    }
}

/// A disk that a method which balances area ([`crate::Method::balances_area`], with
/// `same_seams` off) would cut into parts ([`super::parts::wanted`]) is cut before any solve
/// when the conformal flattening that keeps its outline's lengths
/// ([`crate::cuts::predicted_outside`]) leaves more than this share of its area outside Max
/// Stretch: three times what the rule allows ([`super::rule::MAX_OUTSIDE_SHARE`]), so a chart
/// near the bound is still solved as it is. Disks planned on the prediction have their own
/// bound, [`PREDICTED_BREAK_PLANNED`].
pub const PREDICTED_BREAK: f64 = 3.0 * super::rule::MAX_OUTSIDE_SHARE;

/// [`PREDICTED_BREAK`] for a disk whose cuts are planned on the prediction
/// ([`super::Context::plans_on_prediction`]): half as much again as the rule allows. The
/// prediction keeps the outline's lengths, and a free-boundary conformal map did not do better
/// on any disk measured: of 21 disks predicted at 7–15% outside on the shared meshes and the
/// camel's head subdivided twice, every one broke the rule when solved as it is (`abf`: 13.7%
/// and 11.5% predicted, 13.7% and 11.2% measured; `lscm`: 7.3–14.6% predicted, 8.9–40.7%
/// measured), so its solve was thrown away. A method that balances area, asked only about the
/// disks it would cut into parts, keeps the wider margin: SLIM often keeps the rule where the
/// conformal prediction breaks it. The bound does not depend on the method, so the seams do not.
pub const PREDICTED_BREAK_PLANNED: f64 = 1.5 * super::rule::MAX_OUTSIDE_SHARE;

/// Disks of at least this many triangles are asked the prediction before their first solve
/// under a method that balances area, which cuts them first beyond [`PREDICTED_FAR`] (see
/// [`predicted_limit`]).
pub const PREDICT_FROM: usize = 50_000;

/// [`PREDICTED_BREAK`] for a disk of [`PREDICT_FROM`] triangles or more that a method which
/// balances area solves whole (not cut into parts): the disks it cannot flatten within the
/// rule as they are, nearly closed surfaces. Spherical caps of 65k–78k triangles under `slim`,
/// cut by the plane `z = −0.6 … −0.9` of a unit sphere: predicted 60% outside, kept the rule
/// as it was; 68%, 75% and 83% broke it, and so did `arap` and `scaffold` at 75% and 83%. A
/// closed bunny subdivided twice with one hole of 30 faces, 98%: its solve as it was took
/// 6.4 s of 9.2 s, thrown away.
pub const PREDICTED_FAR: f64 = 0.75;

/// The predicted share outside Max Stretch beyond which a disk that [`triage`] solves first
/// is cut before any solve instead, or `None` when it is not predicted before its solve:
/// [`PREDICTED_BREAK_PLANNED`] for a disk planned on the prediction
/// ([`super::Context::plans_on_prediction`]), [`PREDICTED_BREAK`] for one a method that
/// balances area would cut into parts ([`super::parts::wanted`]), [`PREDICTED_FAR`] for any
/// other disk of [`PREDICT_FROM`] triangles or more (the prediction's factorization costs a
/// share of such a method's solve; below that size the solve is short).
pub fn predicted_limit(ctx: &super::Context<'_, '_>, chart: &Chart) -> Option<f64> {
    if ctx.plans_on_prediction() {
        Some(PREDICTED_BREAK_PLANNED)
    } else if super::parts::wanted(ctx, chart) {
        Some(PREDICTED_BREAK)
    } else if chart.triangles.len() >= PREDICT_FROM {
        Some(PREDICTED_FAR)
    } else {
        None
    }
}
