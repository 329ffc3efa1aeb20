//! Flip-free starting maps of the barrier methods (SLIM, MIPS, scaffold) and the choice among
//! them.
//!
//! Candidates: LSCM (Lévy et al. 2002; it minimises a conformal energy, so when it is
//! flip-free it starts next to the minimiser) and the mean value map with the boundary on a
//! circle (Floater 2003; flip-free by Tutte's theorem, quads convex on the polygon graph).
//! [`pick`] ranks the valid candidates by their number of non-convex quads (no barrier can make
//! a quad convex again), then by energy. [`pick_staged`] computes LSCM first and the mean value
//! map only when LSCM is not already good enough ([`LSCM_GOOD_ENOUGH`]).
//!
//! Preconditions: a disk chart, possibly with holes. Failures: a candidate whose solve fails
//! is reported by name with the reason; [`flip_free_start`] fails like
//! [`crate::methods::fixed_boundary::solve`].

use crate::charts::Chart;
use crate::methods::fixed_boundary::{self, Weights};
use crate::methods::{chart_angles, lscm, mean_value, nonconvex_quads, BoundaryShape, ChartFailure, ChartSolution};

/// A starting map: its UVs and the name of the method that made it.
pub type Candidate = (Vec<[f64; 2]>, &'static str);

/// The mean value map with the boundary on a circle: the flip-free start of last resort.
pub fn flip_free_start(chart: &Chart) -> Result<Vec<[f64; 2]>, ChartFailure> {
    Ok(mean_value_start(chart, &[])?.uv)
}

/// Charts of at least this many triangles compute their candidate starts one after the other,
/// and the mean value start without a general LU ([`mean_value_start`]).
pub const SEQUENTIAL_STARTS_FROM: usize = 100_000;

/// Charts of fewer triangles compute their starts one after the other.
const PARALLEL_STARTS_FROM: usize = 64;

/// The mean value map on a circle honouring `start_pins`: on charts of at least
/// [`SEQUENTIAL_STARTS_FROM`] triangles by [`mean_value::solve_start`] (the same map without
/// the general sparse LU, whose factors would set the method's peak memory, solved to the
/// accuracy a start needs and checked flip-free), else by the LU solve of
/// [`fixed_boundary::solve`].
pub fn mean_value_start(chart: &Chart, start_pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    if chart.triangles.len() >= SEQUENTIAL_STARTS_FROM {
        mean_value::solve_start(chart, start_pins)
    } else {
        fixed_boundary::solve(chart, start_pins, BoundaryShape::Circle, Weights::MeanValue)
    }
}

/// The LSCM start honouring `start_pins`, or why it could not be computed ("lscm: …"). Without
/// pins, LSCM's two automatic pins, not the free map fixed on the boundary
/// ([`lscm::solve_free`]): a start need only be flip-free and SLIM evens out the crush the
/// pins leave, while the free map's extra solves cost more than they save (the fertility
/// statue subdivided three times under `slim`: 6 → 7 islands and 8.8 → 10.0 s with it, the
/// lion subdivided twice the same islands and 6.3 → 7.3 s).
fn lscm_candidate(chart: &Chart, start_pins: &[(u32, [f64; 2])]) -> Result<Candidate, String> {
    let angles = chart_angles(&chart.positions, &chart.triangles);
    match lscm::solve_with_angles(chart, &angles, start_pins) {
        Ok((uv, _)) => Ok((uv, "lscm")),
        Err(e) => Err(format!("lscm: {}", e.0)),
    }
}

/// The mean value start honouring `start_pins` ([`mean_value_start`]), or why it could not
/// be computed ("mean_value: …").
fn mean_value_candidate(chart: &Chart, start_pins: &[(u32, [f64; 2])]) -> Result<Candidate, String> {
    match mean_value_start(chart, start_pins) {
        Ok(s) => Ok((s.uv, "mean_value")),
        Err(e) => Err(format!("mean_value: {}", e.0)),
    }
}

/// The computed candidates of `results` in order, the reasons of the others pushed to
/// `rejected`.
fn sorted_out(results: impl IntoIterator<Item = Result<Candidate, String>>, rejected: &mut Vec<String>) -> Vec<Candidate> {
    let mut candidates = Vec::new();
    for r in results {
        match r {
            Ok(c) => candidates.push(c),
            Err(why) => rejected.push(why),
        }
    }
    candidates
}

/// The candidate starting maps, computed side by side (independent solves): LSCM (if
/// `with_lscm`) and the mean value map on a circle, both honouring `start_pins`. Returns the
/// maps that could be computed and why the others could not.
pub fn candidate_starts(chart: &Chart, start_pins: &[(u32, [f64; 2])], with_lscm: bool) -> (Vec<Candidate>, Vec<String>) {
    let lscm_start = || with_lscm.then(|| lscm_candidate(chart, start_pins));
    let mean_value_start = || mean_value_candidate(chart, start_pins);
    // Side by side on two threads, except on large charts, where the two factorizations
    // alive at once would set the peak memory (about 1.3 KB per triangle more), and on tiny
    // ones, where a task costs more than the solve (the scheduler runs them in batches).
    // The mean value map (a general LU, about twice LSCM's time) runs on this thread at once;
    // LSCM waits to be taken by a free thread, which may first finish other work (the
    // analysis of [`super::pattern::analysed_beside`]).
    let n = chart.triangles.len();
    let (lscm_start, mean_value_start) = if (PARALLEL_STARTS_FROM..SEQUENTIAL_STARTS_FROM).contains(&n) {
        let (m, l) = rayon::join(mean_value_start, lscm_start);
        (l, m)
    } else {
        (lscm_start(), mean_value_start())
    };
    let mut rejected = Vec::new();
    let candidates = sorted_out(lscm_start.into_iter().chain([mean_value_start]), &mut rejected);
    (candidates, rejected)
}

/// A valid LSCM start (no non-convex quad) whose energy is at most this, in the normalised
/// symmetric Dirichlet energy the barrier methods minimise (1 is an isometry and its lower
/// bound), is taken without computing the mean value map, which costs about two LSCM solves
/// (a general sparse LU). Measured on the charts of Suzanne subdivided twice with her seams,
/// of camelhead, beetle and 3holes cut by Smart UV Project (284 charts: LSCM at most 1.013 on
/// all but two) and of bunny, fertility, lion and 3holes cut by automatic seams: wherever
/// LSCM was at most 2 the mean value map on a circle was worse (Suzanne's largest chart 1.950
/// against 1.928, bunny 1.873 against 1.805; on the Smart UV charts 2.6 to 660), and the one
/// chart where the mean value map won had LSCM at 9.7 (9.5 against it). Either start reaches
/// the same minimum; the choice only moves the number of iterations.
pub const LSCM_GOOD_ENOUGH: f64 = 2.0;

/// Charts with at least this many triangles (and fewer than [`SEQUENTIAL_STARTS_FROM`])
/// compute both candidates side by side on two threads ([`candidate_starts`]) in
/// [`pick_staged`]: one large chart is the whole job, and its mean value map would wait for
/// LSCM. Smaller charts share the threads with other charts, so they skip work instead.
pub const SIDE_BY_SIDE_FROM: usize = 20_000;

/// The start of [`pick`] among LSCM (if `with_lscm`) and the mean value map on a circle, both
/// honouring `start_pins`, computed in stages: LSCM first, taken alone when it is valid,
/// without non-convex quads and at most [`LSCM_GOOD_ENOUGH`] after `prepare`; the mean value map
/// otherwise, and the better of the two wins as in [`pick`]. Charts from
/// [`SIDE_BY_SIDE_FROM`] to [`SEQUENTIAL_STARTS_FROM`] triangles compute both side by side
/// instead.
///
/// `beside`, when given, runs on the calling thread beside the mean value map (after LSCM: a
/// large chart's LSCM factorization is the start's largest allocation, see
/// [`super::pattern::ANALYSE_BESIDE_FROM`]), or after the start when that map is not computed;
/// its result is returned with the start.
#[allow(clippy::too_many_arguments)]
pub fn pick_staged<X: Send>(
    chart: &Chart,
    start_pins: &[(u32, [f64; 2])],
    with_lscm: bool,
    rejected: &mut Vec<String>,
    mut prepare: impl FnMut(&mut Vec<[f64; 2]>),
    mut assess: impl FnMut(&[[f64; 2]]) -> Result<f64, String>,
    beside: Option<impl FnOnce() -> X + Send>,
) -> (Option<(Vec<[f64; 2]>, f64, &'static str)>, Option<X>) {
    let n = chart.triangles.len();
    if !with_lscm || (SIDE_BY_SIDE_FROM..SEQUENTIAL_STARTS_FROM).contains(&n) {
        let ((candidates, more), x) = next_to(|| candidate_starts(chart, start_pins, with_lscm), beside);
        rejected.extend(more);
        return (pick(chart, candidates, rejected, prepare, assess), x);
    }
    let lscm_start = sorted_out([lscm_candidate(chart, start_pins)], rejected);
    let first = pick(chart, lscm_start, rejected, &mut prepare, &mut assess);
    if let Some((uv, e, _)) = &first {
        if *e <= LSCM_GOOD_ENOUGH && nonconvex_quads(chart, uv) == 0 {
            return (first, beside.map(|b| b()));
        }
    }
    let (mean_value, x) = next_to(|| mean_value_candidate(chart, start_pins), beside);
    let mean_value = sorted_out([mean_value], rejected);
    let second = pick(chart, mean_value, rejected, &mut prepare, &mut assess);
    let best = match (first, second) {
        (Some(a), Some(b)) => {
            let rank = |s: &(Vec<[f64; 2]>, f64, &'static str)| (nonconvex_quads(chart, &s.0), s.1);
            // as `pick`: the first (LSCM) wins a tie
            Some(if rank(&b) < rank(&a) { b } else { a })
        }
        (a, b) => a.or(b),
    };
    (best, x)
}

/// `work()` and, when given, `beside()` at the same time: `beside` on the calling thread, also
/// outside rayon's pool (so that it sees this thread's settings), `work` on whichever thread
/// of the pool is free. Without `beside`, `work()` alone on this thread.
pub fn next_to<W: Send, X: Send>(
    work: impl FnOnce() -> W + Send,
    beside: Option<impl FnOnce() -> X + Send>,
) -> (W, Option<X>) {
    let Some(beside) = beside else {
        return (work(), None);
    };
    let mut done = None;
    let x = rayon::in_place_scope(|scope| {
        scope.spawn(|_| done = Some(work()));
        beside()
    });
    (done.expect("the scope ran the work"), Some(x))
}

/// The best of `candidates`: each is first changed by `prepare` (e.g. scaled optimally), then
/// `assess` gives its energy or why it is not a valid start (pushed to `rejected` as
/// "name: why"). The valid one with the fewest non-convex quads of `chart`, then the lowest
/// energy, wins (the first on a tie). Returns its UVs, energy and name.
pub fn pick(
    chart: &Chart,
    candidates: Vec<Candidate>,
    rejected: &mut Vec<String>,
    mut prepare: impl FnMut(&mut Vec<[f64; 2]>),
    mut assess: impl FnMut(&[[f64; 2]]) -> Result<f64, String>,
) -> Option<(Vec<[f64; 2]>, f64, &'static str)> {
    let mut best: Option<(Vec<[f64; 2]>, f64, &'static str, usize)> = None;
    for (mut uv, name) in candidates {
        prepare(&mut uv);
        let e = match assess(&uv) {
            Ok(e) => e,
            Err(why) => {
                rejected.push(format!("{name}: {why}"));
                continue;
            }
        };
        let bad = nonconvex_quads(chart, &uv);
        if best.as_ref().is_none_or(|b| (bad, e) < (b.3, b.1)) {
            best = Some((uv, e, name, bad));
        }
    }
    best.map(|(uv, e, name, _)| (uv, e, name))
}
