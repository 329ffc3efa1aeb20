//! The atlas rule: what every chart must satisfy to be reported solved.
//!
//! With automatic seams on, every chart of every mesh is held to the full rule: the island is
//! a disk (χ = 1, one boundary loop), no UV triangle is flipped or has zero area (on the
//! triangles Blender renders; a quad counts when either diagonal split folds), its outline
//! does not cross itself, and at most [`MAX_OUTSIDE_SHARE`] of its 3D area has a texel density
//! outside `[1/s, s]` × the island's own (`s` = Max Stretch; [`crate::metrics::density`]).
//! Charts that break it are cut or split ([`super::repair`]).
//!
//! With automatic seams off nothing is cut, and a chart is held to the promise every method
//! makes to a user: no flipped triangle and an outline that does not cross itself. Density is
//! reported but not held.
//!
//! The rule is measured on the map itself ([`crate::metrics`]), never inferred from a
//! linearised estimate.

use super::outcome::{ChartReport, Problem};
use crate::charts::ChartKind;

/// Largest share of an island's 3D area allowed outside `[1/s, s]` of its own density.
pub const MAX_OUTSIDE_SHARE: f64 = 0.05;

/// The rule one chart is held to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtlasRule {
    /// Max Stretch `s`: density ratios must lie in `[1/s, s]` (> 1).
    pub max_stretch: f64,
    /// Whether density and disk topology are held (automatic seams on).
    pub full: bool,
}

impl AtlasRule {
    /// The first rule a mapped chart breaks, by severity (flips, overlap, not a disk,
    /// stretch), or `None`. Failed charts break nothing here (their problem is set already).
    pub fn broken(&self, report: &ChartReport) -> Option<Problem> {
        if !report.status.mapped() {
            return None;
        }
        if report.flips > 0 {
            return Some(Problem::Flips);
        }
        if report.overlap {
            return Some(Problem::Overlap);
        }
        if self.full {
            if report.kind != ChartKind::Disk {
                return Some(Problem::NotDisk);
            }
            if !(report.density.outside <= MAX_OUTSIDE_SHARE) {
                return Some(Problem::Stretch);
            }
        }
        None
    }

    /// How far `report` is from the rule, to compare two attempts at one chart (smaller is
    /// better): failed, then flips, overlap, topology, then the 3D area outside the density
    /// bound beyond the allowed share.
    pub fn badness(&self, report: &ChartReport, area: f64) -> (usize, usize, usize, usize, f64) {
        if !report.status.mapped() {
            return (1, 0, 0, 0, 0.0);
        }
        let excess = if self.full {
            let o = report.density.outside;
            if o.is_finite() { (o - MAX_OUTSIDE_SHARE).max(0.0) * area } else { area }
        } else {
            0.0
        };
        let not_disk = (self.full && report.kind != ChartKind::Disk) as usize;
        (0, report.flips, report.overlap as usize, not_disk, excess)
    }
}
