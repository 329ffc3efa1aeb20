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
    /// Planning cuts (summed over charts): the sum of the four parts below.
    pub plan_cuts: f64,
    /// Of `plan_cuts`: each chart's cutting state (edge graph, costs, occlusion rays, the
    /// scale system), the triage's predicted flattening of disks and the test for creases.
    pub cut_state: f64,
    /// Of `plan_cuts`: cone placement on the prediction ([`crate::pipeline::predict`]).
    pub cone_placement: f64,
    /// Of `plan_cuts`: the split candidates (spectral and planar loops).
    pub split_plans: f64,
    /// Of `plan_cuts`: every round's cones and cut graph, with the rebuilt pieces.
    pub cut_graphs: f64,
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
    /// Hard-surface charts cut along their creases before anything else
    /// ([`crate::pipeline::creases`]).
    pub crease_cuts: usize,
    /// Of `splits`, those made before any solve of the chart, because the prediction kept
    /// the rule with a mean area distortion above
    /// [`crate::pipeline::repair::MEAN_AREA_LIMIT`].
    pub predicted_splits: usize,
    /// Charts sent to the split after their first solve, the method's map being far from a
    /// plan whose prediction kept the rule ([`crate::pipeline::repair::FAR_FROM_PLAN`]), or
    /// folding or beyond the density bound on a large chart under a method that does not balance
    /// area ([`crate::pipeline::repair::CONE_ROUNDS_BELOW`]).
    pub far_splits: usize,
    /// Repair rounds whose large pieces were cut into parts before the solve
    /// ([`crate::pipeline::parts`]; the part seams' time is in `cut_graphs`).
    pub parts: usize,
    /// Pieces made valid by peeling the faces where their outline crossed itself or where
    /// they folded into islands of their own ([`crate::pipeline::peel`]).
    pub peels: usize,
    /// Solves of the last resort for pieces that still broke the rule after repair: the
    /// method's flip-free kin, then `scaffold` ([`crate::pipeline::last_resort`]; each also
    /// counted in `repair_pieces`).
    pub last_resort: usize,
    /// Laying small islands' faces on their neighbours ([`crate::pipeline::glue`]), summed
    /// over charts.
    pub glue: f64,
    /// Small islands glued whole onto their neighbours ([`crate::pipeline::glue`]).
    pub glued: usize,
    /// Per-face quality of the result (wall clock).
    pub measure: f64,
    /// Small holes filled for the unwrap and joined to the outlines by closed seams after it
    /// ([`crate::pipeline::fill`]).
    pub holes_filled: usize,
    /// Seconds (wall clock) of an unwrap with small holes filled that was undone, an island
    /// it left breaking the rule without its fills: the mesh was then unwrapped as it is.
    pub fill_undone: f64,
}

impl Phases {
    /// Add the seconds since `t` to `plan_cuts` and to its part `part`.
    pub fn plan(&mut self, t: std::time::Instant, part: impl FnOnce(&mut Phases) -> &mut f64) {
        let s = t.elapsed().as_secs_f64();
        self.plan_cuts += s;
        *part(self) += s;
    }
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
