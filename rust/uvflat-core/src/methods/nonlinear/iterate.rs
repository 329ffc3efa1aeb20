//! The iterate-and-report bookkeeping shared by the nonlinear methods: the energy history,
//! the relative-change tolerance test, the cancel hook ([`crate::progress::cancelled`], polled
//! before every iteration), and the notes of the final report.
//!
//! A method owns its step; [`Iteration`] owns when to stop: after `max_iterations`, when the
//! unwrap is cancelled, when a step is rejected ([`Iteration::stalled`]), or when the relative
//! change of the energy falls below `tolerance` ([`Iteration::record`]), or, for a method that
//! asks for it ([`Iteration::extrapolating`], SLIM), when the next change predicted from the
//! last two decreases would. The relative change is
//! measured against the previous energy ([`Change::OfPrevious`], ARAP and SLIM) or the new one
//! ([`Change::OfNew`], MIPS and scaffold). Whether a result counts as solved (no flips from a
//! method that promises none) is checked after the method, in [`crate::methods::solve`].
//!
//! Preconditions: finite energies for [`Iteration::record`] (a barrier method's line search
//! only accepts finite ones). Failures: none.

/// What the relative change of an iteration is divided by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    /// `|E_prev − E| / E_prev`.
    OfPrevious,
    /// `(E_prev − E) / |E|`.
    OfNew,
}

/// The state of an iteration (see the module docs).
#[derive(Debug, Clone)]
pub struct Iteration {
    /// Energy of the start and after every accepted iteration.
    pub history: Vec<f64>,
    /// Iterations done (a stalled one included).
    pub iterations: usize,
    /// Relative change of the last iteration (0 after a stalled step); the report's residual.
    pub change: f64,
    max_iterations: usize,
    tolerance: f64,
    measure: Change,
    extrapolate: bool,
}

impl Iteration {
    /// Start from `energy`; `change` is what [`Iteration::change`] reports before the first
    /// iteration (0 or ∞, as the method documents).
    pub fn new(energy: f64, max_iterations: usize, tolerance: f64, measure: Change, change: f64) -> Self {
        Iteration { history: vec![energy], iterations: 0, change, max_iterations, tolerance, measure, extrapolate: false }
    }

    /// Also stop when the next iteration's change, extrapolated from the last two, is below
    /// the tolerance ([`Iteration::record`]): for methods whose energy converges linearly
    /// near the end (SLIM's projected Newton steps shrink each decrease to about a fifth of
    /// the previous one on camelhead), this saves the one iteration that would change the
    /// energy by less than the tolerance.
    pub fn extrapolating(mut self) -> Self {
        self.extrapolate = true;
        self
    }

    /// The current energy.
    pub fn energy(&self) -> f64 {
        *self.history.last().expect("the history starts with the start's energy")
    }

    /// Whether another iteration may run: fewer than `max_iterations` done and not cancelled.
    pub fn go_on(&self) -> bool {
        self.iterations < self.max_iterations && !crate::progress::cancelled()
    }

    /// An iteration whose step was rejected (zero line-search step): counted, change 0, stop.
    pub fn stalled(&mut self) {
        self.iterations += 1;
        self.change = 0.0;
    }

    /// An iteration that took no step, after which the method tries another kind of step
    /// (SLIM after a failed Newton step): counted, nothing else changes.
    pub fn counted(&mut self) {
        self.iterations += 1;
    }

    /// An iteration reached `energy`: counted and recorded; returns whether to stop: the
    /// relative change is below the tolerance or, when [`Iteration::extrapolating`], the last
    /// two decreases `d₁ > 2 d₂ > 0` predict a next one `d₂² / d₁` (geometric convergence)
    /// whose relative change is below it.
    pub fn record(&mut self, energy: f64) -> bool {
        let prev = self.energy();
        self.iterations += 1;
        self.change = self.relative(prev, energy);
        self.history.push(energy);
        if self.change < self.tolerance {
            return true;
        }
        match (self.extrapolate, self.history.len()) {
            (true, len @ 3..) => {
                let (d1, d2) = (self.history[len - 3] - prev, prev - energy);
                d2 > 0.0 && d1 > 2.0 * d2 && self.relative(energy, energy - d2 * d2 / d1) < self.tolerance
            }
            _ => false,
        }
    }

    /// The relative change from `prev` to `energy` as measured by this iteration.
    fn relative(&self, prev: f64, energy: f64) -> f64 {
        match self.measure {
            Change::OfPrevious => (prev - energy).abs() / prev.max(f64::MIN_POSITIVE),
            Change::OfNew => (prev - energy) / energy.abs().max(f64::MIN_POSITIVE),
        }
    }
}

/// The report's note for quads whose other-diagonal triangles were not positive at the start
/// (`None` when there are none).
pub fn quads_left_out_note(left_out: usize) -> Option<String> {
    (left_out > 0).then(|| {
        format!("{left_out} quad triangle(s) of the other diagonal were not positive at the start, so those quads may stay non-convex")
    })
}

/// The report's note for a global step that failed and ended the iterations.
pub fn stopped_early_note(reason: &str) -> String {
    format!("stopped early, the global step failed: {reason}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tolerance_stops_on_small_relative_changes_and_the_history_records_them() {
        let mut it = Iteration::new(10.0, 5, 1e-2, Change::OfPrevious, 0.0);
        assert!(it.go_on());
        assert!(!it.record(5.0));
        assert!((it.change - 0.5).abs() < 1e-15);
        assert!(it.record(4.99));
        assert_eq!(it.history, vec![10.0, 5.0, 4.99]);
        assert_eq!(it.iterations, 2);
        let mut it = Iteration::new(2.0, 5, 0.0, Change::OfNew, f64::INFINITY);
        assert_eq!(it.change, f64::INFINITY);
        assert!(!it.record(1.0));
        assert!((it.change - 1.0).abs() < 1e-15);
        it.stalled();
        assert_eq!((it.iterations, it.change, it.energy()), (2, 0.0, 1.0));
        let mut it = Iteration::new(1.0, 2, 0.0, Change::OfNew, 0.0);
        it.record(0.5);
        it.record(0.25);
        assert!(!it.go_on(), "max_iterations reached");
        assert!(quads_left_out_note(0).is_none() && quads_left_out_note(2).unwrap().contains('2'));
    }

    /// Extrapolation stops one iteration early on a geometric tail, never on a slow or
    /// growing one, and never before two decreases are known.
    #[test]
    fn extrapolation_stops_only_on_a_contracting_tail() {
        // Decreases shrinking tenfold: the plain test stops on the decrease 0.0005 (relative
        // 3.5e-4 < 1e-3); extrapolation stops one earlier, after 0.005, which predicts it.
        let run = |extrapolate: bool, decreases: &[f64], tol: f64| {
            let mut it = Iteration::new(2.0, 50, tol, Change::OfPrevious, 0.0);
            if extrapolate {
                it = it.extrapolating();
            }
            let mut e = 2.0;
            for d in decreases {
                e -= d;
                if it.record(e) {
                    break;
                }
            }
            it.iterations
        };
        let geometric = [0.5, 0.05, 0.005, 0.0005, 0.00005];
        assert_eq!(run(false, &geometric, 1e-3), 4);
        assert_eq!(run(true, &geometric, 1e-3), 3);
        // A slow tail (each decrease more than half the previous) is not extrapolated.
        let slow = [0.5, 0.4, 0.3, 0.2, 0.1, 0.0001];
        assert_eq!(run(true, &slow, 1e-3), run(false, &slow, 1e-3));
        // Nor a tail whose decrease grew again.
        let grew = [0.5, 0.3, 0.4, 0.0001];
        assert_eq!(run(true, &grew, 1e-3), run(false, &grew, 1e-3));
        // One decrease alone predicts nothing.
        let mut it = Iteration::new(2.0, 5, 0.1, Change::OfPrevious, 0.0).extrapolating();
        assert!(!it.record(1.0));
    }
}
