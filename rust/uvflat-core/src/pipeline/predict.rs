//! Plan a chart's cones on a prediction, before any solve: the conformal flattening that keeps
//! each piece's outline lengths.
//!
//! Precedent: Sawhney & Crane 2017 (boundary first flattening): on a disk, the log scale
//! factor `u` of the conformal flattening with `u = 0` on the boundary solves `L u = −K`
//! inside (the same system as cone placement, [`crate::cuts::cones`]), and the area ratio of
//! a triangle is `e^{2u}`. It is the conformal map of least area distortion, a close lower
//! bound for LSCM and ABF (their outline is free), and it costs one sparse factorization
//! where a method's solve costs several.
//!
//! Rounds, like [`super::repair`]'s but each one a factorization instead of a solve: cut the
//! chart with the cones so far, predict every piece's share of area outside `[1/s, s]`
//! ([`crate::cuts::predicted_outside`]) and its mean area distortion; when a piece is
//! predicted to break Max Stretch or to exceed [`MEAN_AREA_TARGET`], add a
//! cone in each of its largest predicted crushed regions (up to
//! [`super::repair::CONES_PER_ROUND`]) and cut again. The excess of a piece is its 3D area
//! times the share outside beyond the allowed one plus the mean area distortion beyond the
//! target. A round that does not bring the predicted excess to at most
//! [`PROGRESS`] of the best is not built on
//! (as in repair: back to the best plan one cone at a time, then stop). At most
//! [`PREDICTED_ROUNDS`] rounds; they stop early once the plan keeps the rule and its excess
//! over the mean target is within [`NEAR_TARGET`] of the chart's area. A round's pieces are
//! predicted without building them: the chart's flattening with the cut's vertices held is
//! each piece's with its outline's lengths kept, one refactorization of the chart's system for
//! every piece at once, the pieces told apart by their triangles' labels
//! ([`crate::cuts::ChartCutter::triangle_pieces`], [`crate::cuts::ChartCutter::predicted_ratios_after`];
//! a cut into two pieces cost 1.2–1.3 s at 220k–240k triangles with a system per piece, 0.45 s
//! so).
//!
//! On a chart of [`crate::cuts::coarse::PROXY_FROM`] triangles or more, the cones and every
//! round's prediction come from the chart's coarse proxy ([`crate::cuts::coarse`]: its
//! factorization costs a few hundredths of a second where the chart's own costs about a second
//! at 576k triangles), the cut from the chart; the proxy reads a little optimistic, so the best
//! plan's rule and mean come from the chart's own system ([`confirm`]) unless the proxy's
//! reading is clear of both limits by [`PROXY_MARGIN`]. A proxy's mean above the split's limit
//! is left unconfirmed (the chart's own is higher still, and the split comes first): the
//! caller confirms it only when the chart is not split before any solve.
//!
//! The plan is the same whatever the method (the prediction does not depend on it), so the
//! method's own solve, check and repair start from the same cuts: the seams differ between
//! methods only where a method breaks the rule on the predicted plan.
//!
//! Deterministic: the cut, the regions and their order break ties by ids.

use super::Context;
use crate::charts::Chart;
use crate::cuts::{ChartCutter, ChartCuts};

/// `(density ratio, 3D area)` per triangle.
type Ratios = Vec<(f64, f64)>;

/// Most prediction rounds per chart and split level.
pub const PREDICTED_ROUNDS: usize = 6;

/// A prediction round must leave at most this share of the best plan's excess to earn
/// another round (as in repair: cones where they no longer help lengthen the seams).
pub const PROGRESS: f64 = 0.9;

/// The predicted mean area distortion (area-weighted `max(r, 1/r)`, `r` the density ratio)
/// a plan aims at besides the rule: 1.3, a margin under the 1.35 the atlas benchmark holds
/// (`blender_scripts/closed_benchmark.py`), as the prediction is a little optimistic.
pub const MEAN_AREA_TARGET: f64 = 1.3;

/// A plan that keeps the rule is good enough when its pieces' mean area distortion beyond
/// [`MEAN_AREA_TARGET`], area-weighted, is at most this share of the chart's area (a mean of
/// 1.31 on a chart in one piece).
pub const NEAR_TARGET: f64 = 0.01;

/// How optimistic a plan read on a chart's proxy may be: `(share of area outside, mean area
/// distortion)`. Over 37 prediction rounds on four closed scans of 204k–576k triangles
/// (fertility subdivided three times, the bunny three times, the cow three times, 3holes
/// three times), the proxy read 0–0.016 less area outside than the chart's own system, never
/// more, and a mean area distortion up to 0.07 lower where it was above 1.5, 0.002–0.03 lower
/// between 1.27 and 1.47.
pub const PROXY_MARGIN: (f64, f64) = (0.02, 0.06);

/// The area-weighted mean of `max(r, 1/r)` over `(density ratio, 3D area)` samples.
fn mean_area(ratios: &[(f64, f64)]) -> f64 {
    let total: f64 = ratios.iter().map(|x| x.1).sum();
    ratios.iter().map(|&(x, a)| a * x.max(1.0 / x)).sum::<f64>() / total.max(f64::MIN_POSITIVE)
}

/// The outcome of [`plan`].
#[derive(Debug, Clone)]
pub struct Plan {
    /// The best plan's cut (its cones seed the method's rounds), `None` if no round ran.
    pub cut: Option<ChartCuts>,
    /// Whether every piece of that plan is predicted to keep Max Stretch.
    pub keeps_rule: bool,
    /// The predicted mean area distortion of that plan (area-weighted `max(r, 1/r)` over its
    /// pieces), `NaN` when a piece could not be predicted.
    pub mean_area: f64,
    /// Whether `keeps_rule` and `mean_area` are the chart's proxy's reading (a little
    /// optimistic), left for [`confirm`] to read on the chart's own system.
    pub on_proxy: bool,
}

/// Plan the cones of `chart` (cut by `cutter`) from `seed` (see the module docs). `may_split`:
/// whether the caller splits the chart before any solve when the plan's mean stays above
/// [`super::repair::MEAN_AREA_LIMIT`] (then no one-cone rounds are spent on a plan far above
/// it).
pub fn plan(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    cutter: &ChartCutter<'_>,
    seed: &[u32],
    may_split: bool,
) -> Plan {
    let s = ctx.rule.max_stretch;
    let allowed = cutter.allowed();
    let mut seeds = seed.to_vec();
    // Best plan: its cut, predicted excess area and the cones its crushed regions would add.
    let mut best: Option<(ChartCuts, f64, Vec<u32>)> = None;
    let mut best_mean = f64::NAN;
    let mut single = false;
    let mut best_keeps_rule = false;
    // The best plan's largest predicted share outside of a piece.
    let mut best_outside = f64::NAN;
    let chart_area = super::chart_area(chart);
    for round in 0..=PREDICTED_ROUNDS {
        if crate::progress::cancelled() {
            break;
        }
        let cut = cutter.plan_cut(&seeds, round);
        // Every piece at once: the chart's flattening with the cut held (on its own system or
        // its proxy's) is each piece's with its outline's lengths kept; the pieces are told
        // apart by their triangles' labels.
        let (labels, n_pieces) = cutter.triangle_pieces(&cut);
        let pieces = by_piece(cutter.predicted_ratios_after(&cut), &labels, n_pieces);
        // Predicted excess area of every piece beyond the allowed share, and the crushed
        // regions of the worst one.
        let mut excess = 0.0;
        let mut rule_excess = 0.0;
        // Area-weighted sum of the pieces' predicted mean area distortion (`NaN` once a piece
        // is not predicted).
        let mut mean_sum = 0.0;
        // The largest predicted share outside of a piece.
        let mut max_outside: f64 = 0.0;
        let mut worst: Option<(f64, usize)> = None;
        for (k, ratios) in pieces.iter().enumerate() {
            let (over, soft) = match ratios {
                Some(r) => {
                    let area: f64 = r.iter().map(|x| x.1).sum();
                    let o = crate::metrics::density::spread_of(r.clone(), s).outside;
                    let mean = mean_area(r);
                    max_outside = max_outside.max(o);
                    let soft = if mean.is_finite() { (mean - MEAN_AREA_TARGET).max(0.0) * area } else { area };
                    mean_sum += mean * area;
                    ((o - super::rule::MAX_OUTSIDE_SHARE).max(0.0) * area, soft)
                }
                // Not a disk, or the system failed: the method's rounds will tell.
                None => {
                    mean_sum = f64::NAN;
                    (0.0, 0.0)
                }
            };
            rule_excess += over;
            let over = over + soft;
            excess += over;
            if over > 0.0 && worst.as_ref().is_none_or(|w| over > w.0) {
                worst = Some((over, k));
            }
        }
        let next: Vec<u32> = worst
            .map(|(_, k)| {
                // The worst piece's ratios in the chart's triangle order (the others' at 1).
                let ratios = in_chart_order(&pieces, &labels, k);
                let regions = super::repair::crushed_regions(chart, chart, &ratios, allowed, &cut.cones, s);
                if regions.is_empty() {
                    // Within the bound but above the mean target: the most crushed place.
                    super::repair::crushed_regions(chart, chart, &ratios, allowed, &cut.cones, 1.0)
                        .into_iter()
                        .take(1)
                        .collect()
                } else {
                    regions
                }
            })
            .unwrap_or_default();
        ctx.clock.add(|p| p.predicted_rounds += 1);
        let progress = best.as_ref().is_none_or(|b| excess <= PROGRESS * b.1);
        if best.as_ref().is_none_or(|b| excess < b.1) {
            best = Some((cut.clone(), excess, next.clone()));
            best_keeps_rule = rule_excess <= 0.0;
            best_mean = mean_sum / chart_area;
            best_outside = max_outside;
        }
        // Done when every piece is predicted to keep the rule and the mean area distortion
        // is within [`NEAR_TARGET`] of its target over the chart (another round would cost a
        // factorization for a change the method's own solve blurs).
        if excess <= 0.0 || (rule_excess <= 0.0 && excess <= NEAR_TARGET * chart_area) {
            break;
        }
        // A plan whose predicted mean stays above the split's limit by more than the gain a
        // split must bring is split before any solve (when the chart `may_split`): rounds of
        // one cone after a round that did not help would only polish cones the halves plan
        // afresh (the bunny subdivided three times, `abf`: two rounds of 0.18 s on its whole
        // chart at a mean of 1.41–1.45, one on a half; the same islands without them).
        let split_follows = may_split && best_mean > super::repair::MEAN_AREA_LIMIT + super::repair::MEAN_AREA_GAIN;
        if progress && !next.is_empty() {
            seeds = cut.cones.clone();
            seeds.extend(next.into_iter().take(if single { 1 } else { super::repair::CONES_PER_ROUND }));
        } else if split_follows {
            break;
        } else if let (false, Some(b)) = (single, best.as_ref().filter(|b| !b.2.is_empty())) {
            single = true;
            seeds = b.0.cones.clone();
            seeds.push(b.2[0]);
        } else {
            break;
        }
    }
    let Some((cut, _, _)) = best else {
        return Plan { cut: None, keeps_rule: false, mean_area: f64::NAN, on_proxy: false };
    };
    // Planned on the chart's proxy ([`crate::cuts::coarse`]), which reads a little optimistic:
    // the best plan's rule and mean, which decide the method's rounds and the split before
    // any solve, come from the chart's own system (one factorization, [`confirm`]), unless
    // the proxy's reading is clear of both limits by [`PROXY_MARGIN`]. When the proxy reads a
    // mean above [`super::repair::MEAN_AREA_LIMIT`] already, the chart's own is higher still
    // and the split comes first: the caller confirms only if it keeps the chart whole.
    let unclear = best_outside + PROXY_MARGIN.0 > super::rule::MAX_OUTSIDE_SHARE
        || !(best_mean + PROXY_MARGIN.1 <= super::repair::MEAN_AREA_LIMIT);
    let on_proxy = cutter.proxy().is_some() && unclear;
    let mut plan = Plan { cut: Some(cut), keeps_rule: best_keeps_rule, mean_area: best_mean, on_proxy };
    if on_proxy && !(best_mean > super::repair::MEAN_AREA_LIMIT) {
        confirm(ctx, cutter, &mut plan);
    }
    plan
}

/// Read `plan`'s rule and mean on the chart's own system when they come from its proxy
/// ([`Plan::on_proxy`]; one factorization of the chart), every piece of its cut at once.
pub fn confirm(ctx: &Context<'_, '_>, cutter: &ChartCutter<'_>, plan: &mut Plan) {
    let Some(cut) = plan.cut.as_ref().filter(|_| plan.on_proxy) else { return };
    plan.on_proxy = false;
    let (labels, n) = cutter.triangle_pieces(cut);
    let pieces = by_piece(cutter.predicted_ratios_on_chart(cut), &labels, n);
    if pieces.iter().any(Option::is_none) {
        // Not predicted on the chart: the proxy's reading stands.
        return;
    }
    let (mut sum, mut total, mut keeps) = (0.0, 0.0, true);
    for r in pieces.into_iter().flatten() {
        let area: f64 = r.iter().map(|x| x.1).sum();
        sum += mean_area(&r) * area;
        total += area;
        keeps &= crate::metrics::density::spread_of(r, ctx.rule.max_stretch).outside <= super::rule::MAX_OUTSIDE_SHARE;
    }
    plan.mean_area = sum / total;
    plan.keeps_rule = keeps;
}

/// Per piece (`labels`: the piece of each chart triangle, `n` pieces), its triangles'
/// `(density ratio, 3D area)` in triangle order, relative to the piece's own area-weighted
/// mean (`None` without area); `all`: the chart's. One piece: the chart's as they are.
fn by_piece(all: Option<Ratios>, labels: &[u32], n: usize) -> Vec<Option<Ratios>> {
    let Some(all) = all else { return vec![None; n.max(1)] };
    if n <= 1 {
        return vec![Some(all)];
    }
    let mut out: Vec<Ratios> = vec![Vec::new(); n];
    for (x, &l) in all.into_iter().zip(labels) {
        out[l as usize].push(x);
    }
    out.into_iter()
        .map(|mut r| {
            let total: f64 = r.iter().map(|x| x.1).sum();
            let mean = r.iter().map(|x| x.0 * x.1).sum::<f64>() / total;
            (mean > 0.0 && mean.is_finite()).then(|| {
                for x in &mut r {
                    x.0 /= mean;
                }
                r
            })
        })
        .collect()
}

/// Piece `k`'s ratios (from [`by_piece`]) in the chart's triangle order, the other pieces'
/// triangles at ratio 1 (neither crushed nor stretched).
fn in_chart_order(pieces: &[Option<Ratios>], labels: &[u32], k: usize) -> Ratios {
    let Some(Some(mine)) = pieces.get(k) else { return Vec::new() };
    if pieces.len() == 1 {
        return mine.clone();
    }
    let mut at = 0;
    labels
        .iter()
        .map(|&l| {
            if l as usize == k {
                at += 1;
                mine[at - 1]
            } else {
                (1.0, 0.0)
            }
        })
        .collect()
}
