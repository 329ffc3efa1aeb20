//! Repair: cones and cuts, then splits, until every piece of a chart keeps the atlas rule.
//!
//! Precedents: xatlas's piecewise parameterization and PartUV's split-until-valid. Round 0
//! cuts the chart as planned by [`crate::cuts::ChartCutter`] (cones on the scale factor, handle
//! loops, holes joined to the outline), with the cones [`super::predict::plan`] added where the
//! predicted flattening breaks Max Stretch (for methods that do not balance area, and for
//! those that do with `same_seams` on; when the prediction cannot keep the rule, round 0 is
//! the only round before the split, except under a method that balances area, which often
//! keeps the rule where the conformal prediction breaks it); each further
//! round adds a cone in each of the
//! largest crushed regions of the first piece that breaks the rule (up to
//! `CONES_PER_ROUND`; a flip or zero-area triangle counts as crushed), and re-cuts. A round
//! that does not bring the chart clearly nearer the rule (`PROGRESS`) is not built on: after
//! several cones at once, the rounds go back to the best attempt and add one cone at a time;
//! after one cone, they end and the chart is split (each round is a whole solve). A first
//! map far from a plan whose prediction keeps the rule ([`FAR_FROM_PLAN`]) gets no cone
//! rounds, nor does the first map of a large chart under a conformal method that folds or
//! breaks the density bound ([`CONE_ROUNDS_BELOW`]): the chart is split (`Phases::far_splits`). An
//! attempt whose only problem is an outline that crosses itself gets one more round with one
//! cone at most (several cones rarely uncross an outline; a split does), except on a large chart
//! (`OUTLINE_RETRY_BELOW`), where that round is a costly solve that did not help. The
//! best attempt is kept (fewest failures, flips, overlaps, non-disks, then the least area
//! beyond the density bound, then the fewest pieces). When no round keeps the rule, the chart
//! is halved ([`crate::cuts::split`], along the cheapest loop by the cutter's edge costs) and
//! each half goes through the pipeline again, to a bounded depth; the halves replace the chart
//! only when they are better. At the last split level the planar split is tried too when the
//! spectral one leaves a piece that breaks the rule. A chart that keeps the rule but whose
//! mean area distortion stays above [`MEAN_AREA_LIMIT`] after its rounds (the stretch sits
//! where cones do not relieve it, such as the saddles between handles) is split the same way;
//! its halves replace it only when they keep the rule and take the mean down by
//! [`MEAN_AREA_GAIN`]. Disks solved as they are that keep the rule are not split for it.
//! When the prediction's mean is above [`MEAN_AREA_LIMIT`] (the method's map would be solved
//! only to be split, for the mean or for the rule), the split comes before any solve of the
//! chart: its halves are kept when they keep the rule and lower the predicted mean by
//! [`MEAN_AREA_GAIN`]; otherwise the rounds solve the chart and the same halves are weighed
//! against it at the split stage (counted in `Phases::predicted_splits`).
//! Pieces that still break the rule when every split level has had its try are mapped by the
//! method's flip-free kin or `scaffold` ([`super::last_resort`]); a piece that folds at a few
//! faces and that the last resort leaves beyond the rule is peeled there instead
//! ([`super::peel`]). A large piece (from [`super::peel::FLIPS_PEEL_FROM`] triangles) that
//! folds at a few faces is peeled after any solve of a round, before more cones or a split.
//! Under an area-balancing method (SLIM, ARAP, scaffold) an outline that
//! crosses itself is handed to `scaffold` before the split, on charts below
//! [`super::last_resort::BEFORE_SPLIT_BELOW`] triangles.
//!
//! Bounded: at most `1 + REPAIR_ROUNDS` solves per chart and level, `MAX_SPLIT_DEPTH` levels.
//! `Phases` counts them (`benchmark.py --phases`).
//! Deterministic: every choice breaks ties by ids.

use super::solve::solve_chart;
use super::{Context, Piece};
use crate::charts::{build_charts_with, Chart};
use crate::cuts::{self, cones::ScaleSolver, ChartCutter};
use crate::mesh::PolyMesh;

/// The cutting state of `chart` for [`repair`]: graph, costs and the scale system's analysis,
/// made once (each round refactors numerically).
pub fn cutter<'a>(ctx: &'a Context<'_, '_>, chart: &'a Chart) -> ChartCutter<'a> {
    with_proxy_beside(ctx, chart, || {
        ChartCutter::with_cache(ctx.mesh, chart, &ctx.options.auto_seams, ctx.avoid, Some(&ctx.visibility))
    })
}

/// [`cutter`] with the chart's scale system built already.
pub fn cutter_with<'a>(ctx: &'a Context<'_, '_>, chart: &'a Chart, solver: Option<ScaleSolver>) -> ChartCutter<'a> {
    with_proxy_beside(ctx, chart, || {
        ChartCutter::with_solver(ctx.mesh, chart, &ctx.options.auto_seams, ctx.avoid, Some(&ctx.visibility), solver)
    })
}

/// The cutter `make` builds, with the chart's coarse proxy ([`cuts::coarse::Proxy`]) decimated
/// beside it when the plan will read it: a chart that has one ([`cuts::coarse::wants_proxy`]),
/// planned on the prediction, with no mirror asked for (the proxy serves no mirrored
/// chart). The decimation (0.4–0.5 s at 446k–576k triangles, on one thread) was otherwise the
/// first round's, after the cutting state.
fn with_proxy_beside<'a>(
    ctx: &Context<'_, '_>,
    chart: &'a Chart,
    make: impl FnOnce() -> ChartCutter<'a> + Send,
) -> ChartCutter<'a> {
    let beside = (cuts::coarse::wants_proxy(chart) && ctx.plans_on_prediction() || super::parts::wanted(ctx, chart))
        && ctx.options.auto_seams.symmetry == cuts::symmetry::Symmetry::None;
    if !beside {
        return make();
    }
    match rayon::join(make, || cuts::coarse::Proxy::new(chart)) {
        (cutter, Some(proxy)) => cutter.with_proxy(proxy),
        (cutter, None) => cutter,
    }
}

/// Repair `chart` (already cut along `base_seams`). `first`: the chart solved as it is, if it
/// was (it is one of the attempts); `cutter`: its [`cutter`], if made already. Returns the
/// best pieces found.
pub fn repair<'a>(
    ctx: &'a Context<'_, '_>,
    chart: &'a Chart,
    base_seams: &[[u32; 2]],
    depth: usize,
    first: Option<Piece>,
    cutter: Option<ChartCutter<'a>>,
) -> Vec<Piece> {
    let t = std::time::Instant::now();
    let mask = face_mask(ctx.mesh.n_faces(), chart);
    let mut cutter = cutter.unwrap_or_else(|| self::cutter(ctx, chart));
    ctx.clock.add(|p| p.plan(t, |p| &mut p.cut_state));
    let mut seed: Vec<u32> = Vec::new();
    let mut best: Vec<Piece> = Vec::new();
    if let Some(p) = first {
        if let Some(v) = worst_vertex(chart, &p, cutter.allowed(), &[]) {
            seed.push(v);
        }
        best.push(p);
    }
    // The cones of the best attempt, the cones its crushed regions would add, and whether
    // rounds add one cone each (after several at once did not help).
    let mut best_cones: Vec<u32> = Vec::new();
    let mut best_next: Vec<u32> = seed.clone();
    let mut single = false;
    // The cones planned on the prediction ([`super::predict`]); when the prediction could not
    // keep the rule, more cones will not either: one solve of the best plan, then the split.
    // Unless `same_seams` is on, methods that balance area (SLIM, ARAP, scaffold), which
    // often keep the rule where the conformal prediction breaks it, start from the cutter's
    // cones as they are.
    let mut plan = if !ctx.plans_on_prediction() {
        None
    } else {
        let t = std::time::Instant::now();
        let may_split = depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2;
        let plan = || super::predict::plan(ctx, chart, &cutter, &seed, may_split);
        let plan = if may_split && cutter.proxy().is_some() {
            // The Fiedler vector a split would follow ([`ChartCutter::fiedler`], on the proxy)
            // is made beside the plan, whose factorizations run on one core: 0.17–0.37 s of
            // the split's candidates at 267k–446k triangles; the lion subdivided twice under
            // `abf`, 3.9 → 3.6 s. A chart that is not split throws it away.
            rayon::join(plan, || cutter.fiedler()).0
        } else {
            plan()
        };
        ctx.clock.add(|p| p.plan(t, |p| &mut p.cone_placement));
        Some(plan)
    };
    let predicted_mean = plan.as_ref().map_or(f64::NAN, |p| p.mean_area);
    // The split's candidates, once made, and the halves along the first made before any solve.
    // Only the last split level tries more than the first candidate.
    let mut candidates: Option<Vec<Vec<[u32; 2]>>> = None;
    let last_level = depth + 1 == cuts::MAX_SPLIT_DEPTH;
    let mut presplit: Option<(Vec<[u32; 2]>, Vec<Piece>)> = None;
    if predicted_mean > MEAN_AREA_LIMIT && depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
        // The plan's predicted mean area distortion is above [`MEAN_AREA_LIMIT`]: the chart
        // would be solved (and its outline checked) only to be split, for the mean or, when
        // the plan breaks the rule too, for the rule. The prediction is close to the method's
        // map there (bunny subdivided twice, `abf`: 1.367 predicted, 1.365 solved), so the
        // split comes first; its halves are kept when they keep the rule and lower the
        // predicted mean by [`MEAN_AREA_GAIN`], else the rounds solve the chart and the split
        // stage weighs the same halves against it. (A plan that breaks the rule by a hair
        // with a mean above the limit, the bunny subdivided twice as the Rust examples make
        // it: its whole-chart solve, 1.2 s, was solved to be split.)
        let keep = |out: &[Piece]| all_valid(ctx, out) && mean_area(out) <= predicted_mean - MEAN_AREA_GAIN;
        match split_first(ctx, chart, &mut cutter, base_seams, &mask, depth, None, keep) {
            Ok(out) => return out,
            Err((list, pre)) => (candidates, presplit) = (Some(list), pre),
        }
    }
    if let Some(plan) = plan.as_mut().filter(|p| p.on_proxy) {
        // Read on the chart's proxy, left to here by the split that came first.
        let t = std::time::Instant::now();
        super::predict::confirm(ctx, &cutter, plan);
        ctx.clock.add(|p| p.plan(t, |p| &mut p.cone_placement));
    }
    let breaks = plan.as_ref().is_some_and(|p| p.cut.is_some() && !p.keeps_rule) && !ctx.options.method.balances_area();
    if breaks && presplit.is_none() && depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
        // The best plan is predicted to break the rule, and the flattening predicted is the
        // conformal map of least area distortion: the one solve of that plan that would come
        // next broke the rule in every case measured (8 of 8: `abf` on the camel's head
        // subdivided twice, 3.6 s; `lscm` on scans of 88k–267k triangles). The chart is split
        // first; its halves are kept when they keep the rule, else the solve follows and the
        // split stage weighs the same halves against it.
        let made = candidates.take();
        match split_first(ctx, chart, &mut cutter, base_seams, &mask, depth, made, |out| all_valid(ctx, out)) {
            Ok(out) => return out,
            Err((list, pre)) => (candidates, presplit) = (Some(list), pre),
        }
    }
    let rounds = plan.as_ref().map_or(cuts::REPAIR_ROUNDS, |p| {
        if p.keeps_rule || ctx.options.method.balances_area() {
            cuts::REPAIR_ROUNDS
        } else {
            0
        }
    });
    let plan_kept = plan.as_ref().is_some_and(|p| p.keeps_rule);
    let mut planned = plan.and_then(|p| p.cut);
    // The parts of a large chart's pieces ([`super::parts`]), cut in the first round and kept.
    let mut parts: Option<Vec<[u32; 2]>> = None;
    // One more round when a round cut into parts is solved again whole.
    let mut again = 0;
    for round in 0..=rounds + 1 {
        if round > rounds + again {
            break;
        }
        if crate::progress::cancelled() {
            // The unwrap is discarded: no more solves.
            return best;
        }
        let t = std::time::Instant::now();
        let mut cut = match planned.take() {
            Some(cut) => cut,
            // A chart cut into parts places its first cones on its proxy ([`super::parts`]).
            // The Fiedler vector its parts follow ([`super::parts::part_seams`]) is made beside
            // the cut, whose cones are placed on the proxy on one core.
            None if round == 0 && super::parts::wanted(ctx, chart) => {
                rayon::join(|| cutter.plan_cut(&seed, round), || cutter.fiedler()).0
            }
            None => cutter.cut(&seed, round),
        };
        if cut.seams.is_empty() && !best.is_empty() {
            break;
        }
        let mut all: Vec<[u32; 2]> = base_seams.to_vec();
        all.extend_from_slice(&cut.seams);
        // The round's cut as planned, before any parts.
        let uncut = cut.clone();
        let mut with_parts = false;
        let mut sub = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
        if super::parts::wanted(ctx, chart) {
            // Pieces too large to solve well as one are cut into parts (once per chart, the
            // same parts every round), and parts that came out rings opened.
            let mut built = None;
            let parts = parts.get_or_insert_with(|| {
                let (seams, pieces) = super::parts::part_seams(ctx, chart, &cutter, &all, &mask, &sub);
                built = pieces;
                seams
            });
            if !parts.is_empty() {
                let mut extra = parts.clone();
                all.extend_from_slice(&extra);
                sub = built.unwrap_or_else(|| build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render));
                let rings = super::parts::open_rings(ctx, &sub);
                if !rings.is_empty() {
                    all.extend_from_slice(&rings);
                    extra.extend_from_slice(&rings);
                    sub = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
                }
                ctx.clock.add(|p| p.parts += 1);
                cut.length += split_length(ctx.mesh, &extra);
                cut.seams.extend_from_slice(&extra);
                with_parts = true;
            }
        }
        for c in &sub {
            c.inherit_vertex_order(chart);
        }
        if chart.triangles.len() >= SEQUENTIAL_HALVES_FROM {
            // The scale system's factor (0.2 GB at 576k triangles) would sit beside the
            // method's during the solve; a later round factors it again (about 0.7 s there).
            cutter.release_factors();
        }
        ctx.clock.add(|p| p.plan(t, |p| &mut p.cut_graphs));
        let t = std::time::Instant::now();
        let n_pieces = sub.len();
        let mut pieces: Vec<Piece> = Vec::with_capacity(sub.len());
        // Parts side by side (the unwrap's progress goes with them, so a cancel reaches their
        // solves); other pieces in turn.
        let solve = |c: Chart| {
            let r = solve_chart(&c, ctx.pins, ctx.options, &ctx.rule);
            (c, r)
        };
        let solved: Vec<_> = if with_parts {
            use rayon::prelude::*;
            let progress = crate::progress::current();
            sub.into_par_iter()
                .map(|c| {
                    let _guard = progress.as_ref().map(|p| p.enter());
                    solve(c)
                })
                .collect()
        } else {
            sub.into_iter().map(solve).collect()
        };
        for (k, (c, (mut report, uv, face_flips))) in solved.into_iter().enumerate() {
            // A piece the cut did not open (it should not happen) breaks the rule and is
            // repaired or split like any other.
            let seams = if k == 0 {
                report.cones = cut.cones.len();
                report.cut_length = cut.length;
                cut.seams.clone()
            } else {
                Vec::new()
            };
            pieces.push(Piece::new(Some(c), report, uv, face_flips, seams));
        }
        // A large piece whose outline crosses itself at a few places keeps its map: the
        // faces there become islands of their own ([`super::peel`]); parts of a chart cut
        // into parts count as large.
        let peel_from = if with_parts { super::parts::PART_FROM / 8 } else { super::peel::PEEL_FROM };
        super::peel::apply_from(ctx, chart, base_seams, &mut pieces, peel_from);
        // So does a large piece that folds at a few faces (its outline may cross itself too):
        // `arap` on the bunny subdivided twice folded 2–8 faces of its 111k-triangle chart in
        // every round, each a 100-iteration solve (2.3 s), before splits took 22 s in all.
        // (Parts count as large from the overlap peel's size.)
        super::peel::apply_flips(ctx, chart, base_seams, &mut pieces, peel_from.min(super::peel::FLIPS_PEEL_FROM));
        ctx.clock.add(|p| {
            p.repair_solve += t.elapsed().as_secs_f64();
            p.repair_pieces += n_pieces;
            p.repair_rounds += 1;
        });
        let valid = all_valid(ctx, &pieces);
        let ((_, flips, _, _), excess) = badness(ctx, &pieces);
        let only_outline = flips == 0 && excess <= 0.0;
        let next: Vec<u32> = pieces
            .iter()
            .find(|p| ctx.rule.broken(&p.report).is_some() || !p.report.status.mapped())
            .map(|p| crushed_vertices(chart, p, cutter.allowed(), &cut.cones, ctx.rule.max_stretch))
            .unwrap_or_default();
        // A round that leaves the chart no nearer the rule than the best attempt by a clear
        // margin is not built on: when it added several cones, the next round goes back to
        // the best attempt and adds one (at its most crushed region); otherwise the rounds end
        // (more cones where they did not help cost a whole solve each; the chart is split).
        let far = round == 0 && plan_kept && far_from_plan(&pieces);
        // A large chart under a method whose cuts are planned on the prediction, whose first map
        // folds or breaks the density bound: see [`CONE_ROUNDS_BELOW`].
        let balances = ctx.options.method.balances_area();
        let large = round == 0 && no_cone_rounds(chart.triangles.len(), balances, badness(ctx, &pieces));
        let progress = best.is_empty() || clearly_better(ctx, &pieces, &best);
        if best.is_empty() || better(ctx, &pieces, &best) {
            best = pieces;
            best_cones = cut.cones.clone();
            best_next = next.clone();
        }
        if valid {
            break;
        }
        if with_parts {
            // A part broke the rule where its piece, solved whole, may keep it (the rule
            // weighs each island's density against its own mean): the same cut again, solved
            // whole, and no parts from here on.
            parts = Some(Vec::new());
            planned = Some(uncut);
            again = 1;
            continue;
        }
        if far || large {
            // The plan's flattening keeps the rule and the method's map is far from it (a
            // linear conformal map's free boundary crushing a region the prediction does
            // not): cones placed on the prediction do not bring it back, a split does
            // (`lscm` on the camel head: 13 whole solves, against 26 with the cone rounds).
            // On a large chart a cone round is a whole solve that did not help where measured.
            if depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
                ctx.clock.add(|p| p.far_splits += 1);
            }
            break;
        }
        if only_outline && (single || chart.triangles.len() >= OUTLINE_RETRY_BELOW) {
            // Still only an outline that crosses itself after a one-cone round (or at once on
            // a large chart, [`OUTLINE_RETRY_BELOW`]): more cones do not uncross it, a split
            // does.
            break;
        }
        if progress && !next.is_empty() && !only_outline {
            seed = cut.cones.clone();
            seed.extend(next.into_iter().take(if single { 1 } else { CONES_PER_ROUND }));
        } else if !single && !best_next.is_empty() {
            // Several cones at once made it worse (typically an outline that now crosses
            // itself): from here on, one cone per round.
            single = true;
            seed = best_cones.clone();
            seed.push(best_next[0]);
        } else {
            break;
        }
    }
    if !all_valid(ctx, &best)
        && ctx.options.method.balances_area()
        && chart.triangles.len() < super::last_resort::BEFORE_SPLIT_BELOW
        && only_overlaps(ctx, &best)
    {
        // An outline that crosses itself under an area-balancing method: scaffold minimises
        // the same kind of energy with the outline held apart, one island instead of a split.
        super::last_resort::apply(ctx, chart, &mut best, "its cones");
    }
    // A chart that keeps the rule but whose mean area distortion is above
    // [`MEAN_AREA_LIMIT`] (cones no longer relieve it: typically saddles between handles) is
    // split too; its halves replace it only when they keep the rule and lower the mean
    // ([`lowers_mean_area`]).
    let soft = all_valid(ctx, &best) && mean_area(&best) > MEAN_AREA_LIMIT;
    if (soft || !all_valid(ctx, &best)) && depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
        // The spectral split; at the last split level, where the halves cannot be split again,
        // also the planar one when the first leaves a piece that breaks the rule (one more
        // attempt per chart of that level, so the work stays bounded).
        let t = std::time::Instant::now();
        let candidates =
            candidates.take().unwrap_or_else(|| cutter.split_candidates(ctx.avoid, last_level));
        // The chart's cutting state (its graph, costs and the scale system's factor: 0.3 GB
        // on a 576k-triangle chart) is not needed by the halves, which make their own.
        drop(cutter);
        ctx.clock.add(|p| p.plan(t, |p| &mut p.split_plans));
        let tries = if last_level { candidates.len() } else { 1 };
        for split in candidates.into_iter().take(tries).filter(|s| !s.is_empty()) {
            let out = match presplit.take() {
                Some((seams, out)) if seams == split => out,
                _ => halves(ctx, chart, base_seams, &mask, depth, &split),
            };
            let take = if soft { all_valid(ctx, &out) && lowers_mean_area(&out, &best) } else { better(ctx, &out, &best) };
            if take {
                best = out;
            }
            if all_valid(ctx, &best) {
                break;
            }
        }
    }
    if depth == 0 && !all_valid(ctx, &best) {
        // Only once every split level has had its try with the method (a half fixed by the
        // last resort would end the search for a split the method maps within the rule).
        last_resort(ctx, chart, base_seams, &mut best, "its cones and splits");
        // A piece of any size whose outline still crosses itself (the last resort's
        // `scaffold` stalled, as on surface folded in 3D) is peeled: its map is kept, the
        // faces where it crosses become islands of their own.
        super::peel::apply_from(ctx, chart, base_seams, &mut best, 0);
    }
    best
}

/// The last resort ([`super::last_resort::apply`]) for the pieces of `pieces` that break the
/// rule; a piece that folds at a few faces ([`super::peel::folds_at_few`]) and that the last
/// resort leaves beyond the rule is peeled instead ([`super::peel::apply_flips`]) when that
/// keeps it: its map by the method is kept, the faces that fold become an island of their own
/// (`arap` on the camel's head with a vertex collapsed onto a neighbour in 1% of its
/// triangles: a piece of 2,568 faces with one zero-area UV triangle, which `scaffold` mapped
/// with 35.5% of its area outside the density bound; peeled, pieces of 2,555 and 13 faces that
/// keep the rule).
fn last_resort(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]], pieces: &mut Vec<Piece>, tried: &str) {
    let mut out: Vec<Piece> = Vec::with_capacity(pieces.len());
    for mut piece in pieces.drain(..) {
        if !super::peel::folds_at_few(ctx, &piece) {
            super::last_resort::apply(ctx, chart, std::slice::from_mut(&mut piece), tried);
            out.push(piece);
            continue;
        }
        let mut resorted = vec![piece.clone()];
        super::last_resort::apply(ctx, chart, &mut resorted, tried);
        if !all_valid(ctx, &resorted) {
            let mut peeled = vec![piece];
            super::peel::apply_flips(ctx, chart, base_seams, &mut peeled, 0);
            if all_valid(ctx, &peeled) {
                resorted = peeled;
            }
        }
        out.extend(resorted);
    }
    *pieces = out;
}

/// The split's candidates, and the halves along the first with the seams they were cut along.
type SplitTried = (Vec<Vec<[u32; 2]>>, Option<(Vec<[u32; 2]>, Vec<Piece>)>);

/// A split of `chart` before any solve: the split's candidates (`made`, or made here from
/// `cutter`, whose factors are freed: the halves make their own cutting state), and the
/// halves along the first, each taken through the pipeline. `Ok` with the halves when `keep`
/// takes them; otherwise the candidates and the halves tried, for the split stage to weigh
/// after the chart's own solve.
#[allow(clippy::too_many_arguments)]
fn split_first(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    cutter: &mut ChartCutter<'_>,
    base_seams: &[[u32; 2]],
    mask: &[bool],
    depth: usize,
    made: Option<Vec<Vec<[u32; 2]>>>,
    keep: impl Fn(&[Piece]) -> bool,
) -> Result<Vec<Piece>, SplitTried> {
    let t = std::time::Instant::now();
    let last_level = depth + 1 == cuts::MAX_SPLIT_DEPTH;
    let list = made.unwrap_or_else(|| cutter.split_candidates(ctx.avoid, last_level));
    cutter.release_factors();
    ctx.clock.add(|p| p.plan(t, |p| &mut p.split_plans));
    let Some(split) = list.first().filter(|s| !s.is_empty()).cloned() else { return Err((list, None)) };
    let out = halves(ctx, chart, base_seams, mask, depth, &split);
    ctx.clock.add(|p| p.predicted_splits += 1);
    if keep(&out) {
        return Ok(out);
    }
    Err((list, Some((split, out))))
}

/// The halves of `chart` split along `split` (mesh vertex pairs), each taken through the
/// pipeline's road again at `depth + 1`, in half order; the split's seams go with the first.
fn halves(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    base_seams: &[[u32; 2]],
    mask: &[bool],
    depth: usize,
    split: &[[u32; 2]],
) -> Vec<Piece> {
    ctx.clock.add(|p| p.splits += 1);
    take_apart(ctx, chart, base_seams, mask, depth + 1, split)
}

/// The pieces of `chart` (faces `mask`) cut along `split` (mesh vertex pairs), each taken
/// through the pipeline's road again at split depth `depth`, in piece order; the cut's seams
/// go with the first.
pub(crate) fn take_apart(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    base_seams: &[[u32; 2]],
    mask: &[bool],
    depth: usize,
    split: &[[u32; 2]],
) -> Vec<Piece> {
    let mut all: Vec<[u32; 2]> = base_seams.to_vec();
    all.extend_from_slice(split);
    let halves = build_charts_with(ctx.mesh, &all, Some(mask), ctx.render);
    for h in &halves {
        h.inherit_vertex_order(chart);
    }
    // Each half takes the pipeline's road again (cut, or solve then repair), the halves
    // in parallel (in turn on a large chart under a method that balances area,
    // [`SEQUENTIAL_HALVES_FROM`]); results in half order, so the outcome does not depend on
    // threads. The unwrap's progress goes with them, so a cancel reaches their solves.
    let progress = crate::progress::current();
    let in_turn = chart.triangles.len() >= SEQUENTIAL_HALVES_FROM && ctx.options.method.balances_area();
    let lists: Vec<Vec<Piece>> = if in_turn {
        // Large halves of SLIM, ARAP or scaffold one after the other: two of their solves
        // at once raised the peak memory.
        halves.into_iter().map(|h| super::run(ctx, h, &all, depth)).collect()
    } else {
        use rayon::prelude::*;
        halves
            .into_par_iter()
            .map(|h| {
                let _guard = progress.as_ref().map(|p| p.enter());
                super::run(ctx, h, &all, depth)
            })
            .collect()
    };
    let mut out = Vec::new();
    for (k, mut list) in lists.into_iter().enumerate() {
        if k == 0 {
            if let Some(p) = list.first_mut() {
                p.seams.extend_from_slice(split);
                p.report.cut_length += split_length(ctx.mesh, split);
            }
        }
        out.extend(list);
    }
    out
}

/// Whether every piece of `pieces` that breaks the rule breaks it only by an outline that
/// crosses itself.
fn only_overlaps(ctx: &Context<'_, '_>, pieces: &[Piece]) -> bool {
    pieces.iter().all(|p| {
        p.report.status.mapped() && matches!(ctx.rule.broken(&p.report), None | Some(super::outcome::Problem::Overlap))
    })
}

/// A piece with more than this share of its area outside the density bound is far from a plan
/// whose prediction keeps the rule (at most 5% outside): see [`repair`].
pub const FAR_FROM_PLAN: f64 = 0.25;

/// Whether a mapped piece of `pieces` has more than [`FAR_FROM_PLAN`] of its area outside
/// the density bound.
fn far_from_plan(pieces: &[Piece]) -> bool {
    pieces.iter().any(|p| p.report.status.mapped() && p.report.density.outside > FAR_FROM_PLAN)
}

/// A chart of at least this many triangles has its split's halves go through the pipeline
/// one after the other under a method that balances area (SLIM, ARAP, scaffold; smaller
/// charts, and every chart under the other methods, in parallel). On fertility split 1→4
/// three times (576k triangles), `slim`'s halves of 231k and 344k triangles peaked at 1.71 GB
/// solved in turn against 2.03 GB in parallel, in the same time (115.6 s and 118.9 s, one run
/// each). The other methods' halves spend most of their time planning cuts, mostly on one
/// thread, and their solves need less memory: `abf` on 3holes subdivided three times (460,800
/// triangles, halves of 241k and 220k) took 10.7 s with its halves in parallel against 14.1 s
/// in turn, at a peak of 0.93 GB against 0.64 GB (2.0 KB per triangle); on the bunny
/// subdivided three times (445,824) 9.0 s against 11.4 s (1.03 GB against 0.91 GB); on
/// fertility subdivided three times 10.3 s against 11.6 s at the same 1.10 GB (one run each,
/// `examples/scan_phases.rs` on the meshes of `blender_scripts/scan_benchmark.py`).
pub const SEQUENTIAL_HALVES_FROM: usize = 100_000;

/// A chart of at least this many triangles, under a method whose cuts are planned on the
/// prediction (not one that balances area), whose first map folds or breaks the density bound
/// (an outline that only crosses itself has its own rule, [`OUTLINE_RETRY_BELOW`]) gets no
/// cone rounds: it is split (counted in `Phases::far_splits`). Each round is a whole solve of
/// the chart, and on the charts measured from this size none kept the rule: 10 rounds on 4
/// charts (`lscm` on the camel's head subdivided twice, 363k triangles with a flip and 22% of
/// it outside the bound, then 28%, 30% and 28% with more cones, 8.5 s of solves; on the lion
/// subdivided twice, a half of 170k with two flips and 16.6% outside, then 18.7%, 18.2% and
/// 18.2%; on the beetle subdivided twice, a half of 324k at 8.2% three times, 5.9 s; `abf` on
/// the camel's head subdivided twice by Blender, a half of 211k at 5.5%, then 6.1% and 8.6%,
/// 2.7 s). Three of them kept their first attempt as their best, so their split is the one
/// made before; the lion's half kept a later one, and its split now leaves the same islands
/// with seams 4% shorter. Below this size rounds do help: `lscm` on a quarter of 113k of that
/// camel's head, 11% then 0.1% with one more cone; `abf` on the lion's half of 97k, 6.0%,
/// 6.3%, then 1.7% (`examples/scan_phases.rs`).
pub const CONE_ROUNDS_BELOW: usize = 150_000;

/// Whether a chart of `triangles` whose first map has `badness` ([`badness`]) goes to the split
/// without cone rounds ([`CONE_ROUNDS_BELOW`]; `balances_area`: the method's).
fn no_cone_rounds(triangles: usize, balances_area: bool, badness: ((usize, usize, usize, usize), f64)) -> bool {
    let ((failed, flips, _, not_disk), excess) = badness;
    triangles >= CONE_ROUNDS_BELOW && !balances_area && failed == 0 && not_disk == 0 && (flips > 0 || excess > 0.0)
}

/// A chart of at least this many triangles whose only problem is an outline that crosses
/// itself goes straight to the split, without the one-cone round smaller charts get: that
/// round is a whole solve of the chart (24.8 s for `slim` on fertility split 1→4 three times,
/// 576k triangles, where it did not uncross the outline and the split followed anyway). On
/// smaller charts the round sometimes uncrosses it and saves the split's islands: that
/// fertility's 231k-triangle half with `slim` (one island instead of four when the round
/// was skipped there too), the cow's and the beetle's last pieces with `abf`.
pub const OUTLINE_RETRY_BELOW: usize = 300_000;

/// A chart that keeps the rule with a mean area distortion above this (area-weighted
/// `max(r, 1/r)` over its pieces, [`crate::metrics::Distortion::area`]) is split once more
/// (see [`repair`]): the atlas benchmark's bound (`blender_scripts/closed_benchmark.py`).
pub const MEAN_AREA_LIMIT: f64 = 1.35;

/// The halves of a split for the mean area distortion must take it down by at least this
/// much (less is not worth the island).
pub const MEAN_AREA_GAIN: f64 = 0.05;

/// Area-weighted mean area distortion of `pieces` (infinite if one is not mapped).
pub fn mean_area(pieces: &[Piece]) -> f64 {
    let total: f64 = pieces.iter().map(|p| p.area).sum();
    if !(total > 0.0) {
        return f64::INFINITY;
    }
    let sum: f64 = pieces
        .iter()
        .map(|p| if p.report.status.mapped() && p.report.distortion.area.is_finite() { p.area * p.report.distortion.area } else { f64::INFINITY })
        .sum();
    sum / total
}

/// Whether `a` has a mean area distortion lower than `b`'s by [`MEAN_AREA_GAIN`].
fn lowers_mean_area(a: &[Piece], b: &[Piece]) -> bool {
    mean_area(a) <= mean_area(b) - MEAN_AREA_GAIN
}

/// Whether every piece is mapped and keeps the rule.
pub fn all_valid(ctx: &Context<'_, '_>, pieces: &[Piece]) -> bool {
    pieces.iter().all(|p| p.report.status.mapped() && ctx.rule.broken(&p.report).is_none())
}

/// Summed [`super::rule::AtlasRule::badness`] of a set of pieces.
fn badness(ctx: &Context<'_, '_>, pieces: &[Piece]) -> ((usize, usize, usize, usize), f64) {
    let mut t = ((0usize, 0usize, 0usize, 0usize), 0.0f64);
    for p in pieces {
        let x = ctx.rule.badness(&p.report, p.area);
        t = ((t.0 .0 + x.0, t.0 .1 + x.1, t.0 .2 + x.2, t.0 .3 + x.3), t.1 + x.4);
    }
    t
}

/// `a` is a strictly better set of pieces than `b` (see the module docs).
fn better(ctx: &Context<'_, '_>, a: &[Piece], b: &[Piece]) -> bool {
    let (x, y) = (badness(ctx, a), badness(ctx, b));
    x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)).then(a.len().cmp(&b.len())) == std::cmp::Ordering::Less
}

/// `a` is better than `b` by more than noise: fewer failures, flips, overlaps or non-disks, or
/// (with those equal) at most [`PROGRESS`] of `b`'s area beyond the density bound.
fn clearly_better(ctx: &Context<'_, '_>, a: &[Piece], b: &[Piece]) -> bool {
    let (x, y) = (badness(ctx, a), badness(ctx, b));
    match x.0.cmp(&y.0) {
        std::cmp::Ordering::Less => true,
        std::cmp::Ordering::Greater => false,
        // Nothing beyond the bound in `b` (it breaks the rule otherwise): no progress to make.
        std::cmp::Ordering::Equal => y.1 > 0.0 && x.1 <= PROGRESS * y.1,
    }
}

/// A repair round must leave at most this share of the best attempt's area beyond the
/// density bound to earn another round.
pub const PROGRESS: f64 = 0.9;

/// Most cones one repair round adds.
pub const CONES_PER_ROUND: usize = 4;

/// Cones for the next round: one in each of the largest crushed regions of `piece` (up to
/// [`CONES_PER_ROUND`]). A region is a vertex-connected set of triangles whose density ratio
/// is below `1/s` (flipped and zero-area triangles included); its cone goes at the first
/// allowed corner (not in `exclude`) of its most crushed triangle. Falls back to
/// [`worst_vertex`] when no triangle is crushed (the piece breaks the rule otherwise).
fn crushed_vertices(original: &Chart, piece: &Piece, allowed: &[bool], exclude: &[u32], s: f64) -> Vec<u32> {
    let fallback = || worst_vertex(original, piece, allowed, exclude).into_iter().collect();
    let Some(uv) = piece.uv.as_ref() else { return fallback() };
    let chart = piece.chart.as_ref().unwrap_or(original);
    let ratios = crate::metrics::density::density_ratios(&chart.positions, &chart.triangles, uv);
    let out = crushed_regions(original, chart, &ratios, allowed, exclude, s);
    if out.is_empty() {
        return fallback();
    }
    out
}

/// One cone in each of the largest crushed regions of `chart` (a piece of `original`) by its
/// triangles' `(density ratio, 3D area)`, up to [`CONES_PER_ROUND`], as vertices of
/// `original`: see [`crushed_vertices`]. Empty when no triangle is crushed.
pub(crate) fn crushed_regions(original: &Chart, chart: &Chart, ratios: &[(f64, f64)], allowed: &[bool], exclude: &[u32], s: f64) -> Vec<u32> {
    if ratios.len() != chart.triangles.len() {
        return Vec::new();
    }
    let to_original = piece_to_original(original, chart);
    let low = 1.0 / s;
    // Union-find over the vertices of crushed triangles.
    let mut parent: Vec<u32> = (0..chart.positions.len() as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    let crushed: Vec<usize> = (0..chart.triangles.len()).filter(|&t| ratios[t].0 < low).collect();
    if crushed.is_empty() {
        return Vec::new();
    }
    for &t in &crushed {
        let [a, b, c] = chart.triangles[t];
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (find(&mut parent, x), find(&mut parent, y));
            if rx != ry {
                parent[rx.max(ry) as usize] = rx.min(ry);
            }
        }
    }
    // Per region: area, and its triangles by increasing ratio (ties by id).
    let mut regions: std::collections::BTreeMap<u32, (f64, Vec<(f64, usize)>)> = Default::default();
    for &t in &crushed {
        let root = find(&mut parent, chart.triangles[t][0]);
        let e = regions.entry(root).or_insert((0.0, Vec::new()));
        e.0 += ratios[t].1;
        e.1.push((ratios[t].0, t));
    }
    let mut regions: Vec<(f64, Vec<(f64, usize)>)> = regions.into_values().collect();
    regions.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out: Vec<u32> = Vec::new();
    for (_, mut tris) in regions {
        if out.len() >= CONES_PER_ROUND {
            break;
        }
        tris.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        'region: for (_, t) in tris {
            for &v in &chart.triangles[t] {
                let o = to_original[v as usize];
                if o != u32::MAX && allowed[o as usize] && !exclude.contains(&o) && !out.contains(&o) {
                    out.push(o);
                    break 'region;
                }
            }
        }
    }
    out
}

/// Piece vertex → vertex of `original` through the shared corners (`u32::MAX`: none).
pub(crate) fn piece_to_original(original: &Chart, chart: &Chart) -> Vec<u32> {
    if std::ptr::eq(original, chart) {
        return (0..chart.positions.len() as u32).collect();
    }
    let mut to_original = vec![u32::MAX; chart.positions.len()];
    // Indexed by mesh corner from the chart's first, where its corners span not much more than
    // their number (with a hash map throughout, this function took 2.9% of the CPU time of the
    // bunny subdivided three times under `slim`); a hash map for a chart of few faces
    // scattered over a large mesh.
    let corners = &original.corner_vertex;
    let lo = corners.iter().map(|&(c, _)| c as usize).min().unwrap_or(0);
    let hi = corners.iter().map(|&(c, _)| c as usize + 1).max().unwrap_or(0);
    if hi - lo <= 4 * corners.len() + 64 {
        let mut corner_to_original = vec![u32::MAX; hi - lo];
        for &(c, v) in corners {
            corner_to_original[c as usize - lo] = v;
        }
        for &(c, v) in &chart.corner_vertex {
            let o = (c as usize).checked_sub(lo).and_then(|i| corner_to_original.get(i)).copied();
            if let Some(o) = o.filter(|&o| o != u32::MAX) {
                to_original[v as usize] = o;
            }
        }
    } else {
        let corner_to_original: std::collections::HashMap<u32, u32> = corners.iter().copied().collect();
        for &(c, v) in &chart.corner_vertex {
            if let Some(&o) = corner_to_original.get(&c) {
                to_original[v as usize] = o;
            }
        }
    }
    to_original
}

/// Faces of `chart` as a selection mask over the mesh.
pub(crate) fn face_mask(n_faces: usize, chart: &Chart) -> Vec<bool> {
    let mut mask = vec![false; n_faces];
    for &f in &chart.faces {
        mask[f as usize] = true;
    }
    mask
}

/// The vertex of `original` (allowed as a cone, not in `exclude`) nearest the most crushed
/// texel density of `piece`: triangles by increasing density ratio (a flipped or zero-area
/// triangle first), the first of their corners that maps to an allowed vertex of `original`.
fn worst_vertex(original: &Chart, piece: &Piece, allowed: &[bool], exclude: &[u32]) -> Option<u32> {
    let uv = piece.uv.as_ref()?;
    let chart = piece.chart.as_ref().unwrap_or(original);
    if chart.triangles.is_empty() {
        return None;
    }
    let to_original = piece_to_original(original, chart);
    let ratios = crate::metrics::density::density_ratios(&chart.positions, &chart.triangles, uv);
    // Crushed triangles first (a flip or zero area, then the smallest ratio): a cone there
    // opens the surface with an angle below 2π. A cone where the density is too high would
    // take more than 2π, and its slit's sides would overlap in UV.
    let mut order: Vec<(f64, usize)> = ratios
        .iter()
        .enumerate()
        .map(|(t, &(r, _))| (if r > 0.0 { -r.ln() } else { f64::INFINITY }, t))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for (_, t) in order {
        for &v in &chart.triangles[t] {
            let o = to_original[v as usize];
            if o != u32::MAX && allowed[o as usize] && !exclude.contains(&o) {
                return Some(o);
            }
        }
    }
    None
}

/// 3D length of mesh edges given as vertex pairs.
pub(crate) fn split_length(mesh: &PolyMesh<'_>, seams: &[[u32; 2]]) -> f64 {
    let p = mesh.positions();
    seams.iter().map(|s| crate::geometry::norm(crate::geometry::sub(p[s[1] as usize], p[s[0] as usize]))).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::build_charts_with;
    use crate::mesh::PolyMesh;

    /// A strip of `n` unit quads along x, listed in the order `order` (quad `i` spans
    /// `[i, i + 1]`): vertices `2i` at y = 0 and `2i + 1` at y = 1.
    fn strip(n: usize, order: &[usize]) -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
        let positions: Vec<[f64; 3]> = (0..=n).flat_map(|i| [[i as f64, 0.0, 0.0], [i as f64, 1.0, 0.0]]).collect();
        let quad = |i: usize| [2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1].map(|v| v as u32);
        let corner_verts: Vec<u32> = order.iter().flat_map(|&i| quad(i)).collect();
        (positions, corner_verts, vec![4; order.len()])
    }

    #[test]
    fn large_charts_that_fold_or_break_the_density_bound_skip_their_cone_rounds() {
        let n = CONE_ROUNDS_BELOW;
        let density = ((0, 0, 0, 0), 0.01);
        let folds = ((0, 3, 1, 0), 0.0);
        let outline = ((0, 0, 1, 0), 0.0);
        assert!(no_cone_rounds(n, false, density));
        assert!(no_cone_rounds(n, false, folds));
        // Smaller charts, area-balancing methods, an outline that only crosses itself (its own
        // rule), a piece not mapped or not a disk, and a map that keeps the rule: rounds as before.
        assert!(!no_cone_rounds(n - 1, false, density));
        assert!(!no_cone_rounds(n, true, density));
        assert!(!no_cone_rounds(n, false, outline));
        assert!(!no_cone_rounds(n, false, ((1, 0, 0, 0), 0.01)));
        assert!(!no_cone_rounds(n, false, ((0, 0, 0, 1), 0.01)));
        assert!(!no_cone_rounds(n, false, ((0, 0, 0, 0), 0.0)));
    }

    /// Every vertex of a piece maps to the vertex of the chart it was cut from that stands for
    /// the same mesh vertex, whether the chart's corners are a run of the mesh's (the dense
    /// map) or two faces far apart in its face list (the hash map).
    #[test]
    fn piece_vertices_map_to_the_chart_vertex_of_the_same_mesh_vertex() {
        let n = 200;
        // Quads 0 and 1 (adjacent) are the first and the last face; the rest lie between.
        let mut order = vec![0];
        order.extend(2..n);
        order.push(1);
        let (positions, corner_verts, face_sizes) = strip(n, &order);
        let mesh = PolyMesh::new(&positions, &corner_verts, &face_sizes).unwrap();
        for faces in [vec![0, n - 1], (0..n).collect::<Vec<_>>()] {
            let mut mask = vec![false; n];
            for &f in &faces {
                mask[f] = true;
            }
            let whole = build_charts_with(&mesh, &[], Some(&mask), None);
            assert_eq!(whole.len(), 1);
            // Cut between quads 0 and 1 (mesh vertices 2 and 3): two pieces.
            let pieces = build_charts_with(&mesh, &[[2, 3]], Some(&mask), None);
            assert!(pieces.len() >= 2);
            let mut mapped = 0;
            for p in &pieces {
                let to = piece_to_original(&whole[0], p);
                for (v, &o) in to.iter().enumerate() {
                    assert_ne!(o, u32::MAX, "piece vertex {v} has no chart vertex");
                    assert_eq!(p.mesh_vertex[v], whole[0].mesh_vertex[o as usize]);
                    mapped += 1;
                }
            }
            assert!(mapped >= whole[0].positions.len());
        }
    }
}
