//! Triage: which road a chart takes through the pipeline.

use crate::charts::{Chart, ChartKind};

/// The road of one chart (see [`triage`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Triage {
    /// Solve as it is and report (automatic seams off, a defect, no triangles, or a pinned
    /// disk: pins are the user's layout and are never cut).
    Solve,
    /// Solve as it is; repair (cones, cuts, splits) only if the result breaks the rule, or
    /// before any solve when it is predicted to break it ([`PREDICTED_BREAK_PLANNED`], by far
    /// under a method that balances area: [`PREDICTED_BREAK`]).
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
