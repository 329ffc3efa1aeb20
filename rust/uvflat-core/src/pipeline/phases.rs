//! Where an unwrap's time goes: seconds per pipeline step and how much repair was needed.
//!
//! Steps of different charts run in parallel, so their seconds are summed over threads (CPU
//! seconds of the step); `build_charts` and `measure` are wall-clock seconds of their single
//! parallel pass.

use std::sync::Mutex;

/// Seconds per step of one unwrap, and the repair counts ([`crate::Unwrapped::phases`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Phases {
    /// Validating the mesh and splitting it into charts (wall clock).
    pub build_charts: f64,
    /// Planning cuts: the cutting state of each chart (edge graph, costs, scale system) and
    /// every round's cones and cut graph, with the rebuilt pieces (summed over charts).
    pub plan_cuts: f64,
    /// Solving, placing and checking charts as they are (the first solve of each chart).
    pub solve: f64,
    /// Solving, placing and checking the pieces of cuts, repair rounds and splits.
    pub repair_solve: f64,
    /// Pieces solved by repair (each counted once per round it was solved in).
    pub repair_pieces: usize,
    /// Repair rounds run (a round: one cut of one chart, all its pieces solved).
    pub repair_rounds: usize,
    /// Prediction rounds run ([`crate::pipeline::predict`]: one cut of one chart, each piece's
    /// flattening predicted by one factorization, nothing solved).
    pub predicted_rounds: usize,
    /// Charts halved by the last-resort split.
    pub splits: usize,
    /// Of `splits`, those made before any solve of the chart, because the prediction kept
    /// the rule with a mean area distortion above
    /// [`crate::pipeline::repair::MEAN_AREA_LIMIT`].
    pub predicted_splits: usize,
    /// Pieces whose outline crossed itself made valid by peeling the faces at the crossings
    /// into islands of their own ([`crate::pipeline::peel`]).
    pub peels: usize,
    /// Solves of the last resort for pieces that still broke the rule after repair: the
    /// method's flip-free kin, then `scaffold` ([`crate::pipeline::last_resort`]; each also
    /// counted in `repair_pieces`).
    pub last_resort: usize,
    /// Per-face quality of the result (wall clock).
    pub measure: f64,
}

/// [`Phases`] shared by the charts of one unwrap.
#[derive(Debug, Default)]
pub struct PhaseClock(Mutex<Phases>);

impl PhaseClock {
    /// Add to the totals.
    pub fn add(&self, f: impl FnOnce(&mut Phases)) {
        let mut p = self.0.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut p);
    }

    /// The totals so far.
    pub fn get(&self) -> Phases {
        *self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}
