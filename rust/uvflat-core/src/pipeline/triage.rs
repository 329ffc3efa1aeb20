//! Triage: which road a chart takes through the pipeline.

use crate::charts::{Chart, ChartKind};

/// The road of one chart (see [`triage`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Triage {
    /// Solve as it is and report (automatic seams off, a defect, no triangles, or a pinned
    /// disk: pins are the user's layout and are never cut).
    Solve,
    /// Solve as it is; repair (cones, cuts, splits) only if the result breaks the rule, or
    /// before any solve when it is predicted to break it by far ([`PREDICTED_BREAK`]).
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

/// A disk solved by a method planned on the prediction (one that does not balance area,
/// [`crate::Method::balances_area`], or any with `same_seams` on:
/// [`super::Context::plans_on_prediction`]), or one that method would cut into parts
/// ([`super::parts::wanted`]), is cut before any solve when the conformal flattening
/// that keeps its outline's lengths ([`crate::cuts::predicted_outside`]) leaves
/// more than this share of its area outside Max Stretch: three times what the rule allows
/// ([`super::rule::MAX_OUTSIDE_SHARE`]), so a chart near the bound is still solved as it is.
pub const PREDICTED_BREAK: f64 = 3.0 * super::rule::MAX_OUTSIDE_SHARE;
