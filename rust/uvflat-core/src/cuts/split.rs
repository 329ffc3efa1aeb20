//! Last-resort segmentation: halve a chart that cones and cuts could not make valid, along a
//! smooth loop of cheap edges.
//!
//! Precedent: spectral mesh segmentation (Liu & Zhang 2004, Zhang et al. 2010's survey) for
//! where to cut, and graph-cut refinement of a segment boundary inside a fuzzy band (Katz &
//! Tal 2003) for how: xatlas and PartUV split until valid, with planar or greedy cuts.
//!
//! 1. `f`: the chart's Fiedler vector ([`super::fiedler`]); each polygon takes the mean of its
//!    corners. Polygons sorted by `f` (ties by id) and weighed by area give each polygon its
//!    area quantile.
//! 2. For each candidate level `q` of [`LEVELS`] (area quantiles 0.5, 0.4, 0.6, 0.3, 0.7): the
//!    polygons below `q − BAND/2` are one side, those above `q + BAND/2` the other, and the
//!    polygons between form a band (narrower on a chart of more than five times
//!    [`BAND_POLYGONS`] polygons, so it holds about that many). The seam is the minimum cut
//!    of the band's dual graph ([`super::min_cut`]) with the cut cost of each edge as
//!    capacity (the caller's costs: length, cheaper along creases, infinite on edges that
//!    touch an avoided vertex): the cheapest loop (or path, on a chart with a boundary) that
//!    separates the two sides within the band. A level set snapped to polygons would zig-zag
//!    across triangle strips; the cut follows the straightest, cheapest edges near it instead.
//! 3. Among levels, one that leaves exactly two connected parts is preferred, then the least
//!    `cost × (1 + |a − ½|)`, `a` the area share of one side (a mild preference for halves);
//!    ties keep the earlier level.
//!
//! Parts ([`halve_into_parts`]: a piece halved only so that its halves are solved side by
//! side) weigh polygons by their triangles instead of their area, and among clean halvings
//! prefer a level that leaves both sides under a triangle limit.
//!
//! Fallback: [`super::planar_split::halve_planar`] (a plane through the principal axis) when
//! the chart has fewer than [`SPECTRAL_MIN_POLYGONS`] polygons, the Fiedler vector cannot be
//! computed, or every level's band is closed off by edges that must not be cut.
//!
//! Preconditions: `cost` has one entry per edge of `graph` (non-negative; infinite where a cut
//! is forbidden). Failures: an empty seam list when the chart has fewer than two polygons or
//! nothing can be split without touching an avoided vertex. Deterministic: sorts break ties
//! by ids, the Fiedler vector and the flow have no randomness.

use super::fiedler::fiedler_vector;
use super::graph::ChartGraph;
use super::min_cut::min_cut;
use super::planar_split::halve_planar;
use crate::charts::Chart;
use crate::geometry::norm;

/// Candidate levels (area quantiles of the Fiedler order), in order of preference.
pub const LEVELS: [f64; 5] = [0.5, 0.4, 0.6, 0.3, 0.7];
/// The first levels of [`LEVELS`], those within a band of the middle ([`halve_into_parts`]).
const INNER_LEVELS: usize = 3;
/// Area share of the band around a level in which the seam may move.
pub const BAND: f64 = 0.2;
/// Most polygons a band holds, about: on a chart of more than five times as many, the band's
/// share shrinks to hold this many. On 3holes subdivided three times (460k triangles) a band
/// of a fifth of the chart held 95k polygons and its minimum cut took 1–3.8 s; one of 25k
/// polygons took 0.04–0.06 s, but on the lion subdivided twice (267k) its seams left halves
/// that took three more splits (5 islands against 2). From 50k, charts up to 250k polygons
/// keep the band of a fifth.
pub const BAND_POLYGONS: usize = 50_000;
/// A halving into parts ([`halve_into_parts`]) whose larger side holds at most this share of
/// the triangles is balanced: the parts are solved side by side, so the larger one sets the
/// time. On the camel's head subdivided twice (363k triangles) under `slim`, the cheapest level
/// under the parts' size made parts of 227k and 136k triangles (solves of 3.0 and 1.8 s side by
/// side, 6.1 s in all); the balanced level, of 201k and 162k (2.4 and 2.3 s, 5.2 s in all), with
/// a seam 4% longer.
pub const BALANCED_SHARE: f64 = 0.6;
/// Charts with fewer polygons are split by a plane.
pub const SPECTRAL_MIN_POLYGONS: usize = 8;

/// A split of a chart's polygons into two sides.
#[derive(Debug, Clone)]
pub struct Split {
    /// Seam edges as mesh vertex pairs `[a, b]`, `a < b`, sorted.
    pub seams: Vec<[u32; 2]>,
    /// Seam edges as edge ids of the chart graph, ascending.
    pub edges: Vec<u32>,
    /// Per polygon of the graph: on the first side.
    pub side: Vec<bool>,
    /// Total cut cost of the seam.
    pub cost: f64,
    /// Area share of the first side (its share of the triangles for [`halve_into_parts`]).
    pub area_share: f64,
    /// Connected parts left (2 for a clean halving).
    pub parts: usize,
    /// The level (area quantile) it was cut at.
    pub level: f64,
}

/// Seams (mesh vertex pairs) that split `chart` in two (see the module docs): the spectral
/// split, or the planar one when that fails. `avoid`: per mesh vertex, whether seams must stay
/// away from it (the planar fallback checks it; `cost` is infinite there already).
pub fn halve(graph: &ChartGraph, cost: &[f64], chart: &Chart, avoid: &[bool]) -> Vec<[u32; 2]> {
    if graph.polygons.len() < 2 {
        return Vec::new();
    }
    if let Some(split) = spectral_halve(graph, cost, chart) {
        return split.seams;
    }
    halve_planar(graph, chart, avoid)
}

/// Candidate seams for halving `chart`, in order of preference: the spectral split, then the
/// planar one (when it differs); empty seam lists are left out. The pipeline tries the second
/// when the halves of the first do not keep the atlas rule.
pub fn candidates(graph: &ChartGraph, cost: &[f64], chart: &Chart, avoid: &[bool]) -> Vec<Vec<[u32; 2]>> {
    candidates_with(graph, cost, chart, avoid, None, true)
}

/// [`candidates`] with the chart's Fiedler vector given (`None`: computed here), as a large
/// chart reads it from its coarse proxy ([`super::ChartCutter::split_candidates`]). With
/// `all` false, only the first candidate: the planar split is not made when the spectral one
/// exists.
pub fn candidates_with(
    graph: &ChartGraph,
    cost: &[f64],
    chart: &Chart,
    avoid: &[bool],
    fiedler: Option<Vec<f64>>,
    all: bool,
) -> Vec<Vec<[u32; 2]>> {
    let mut out = Vec::new();
    if graph.polygons.len() < 2 {
        return out;
    }
    let split = match fiedler {
        Some(f) => spectral_halve_of(graph, cost, chart, &f, None),
        None => spectral_halve(graph, cost, chart),
    };
    if let Some(split) = split {
        out.push(split.seams);
        if !all {
            return out;
        }
    }
    let mut planar = halve_planar(graph, chart, avoid);
    planar.sort_unstable();
    planar.dedup();
    if !planar.is_empty() && out.first() != Some(&planar) {
        out.push(planar);
    }
    out
}

/// The spectral split of `chart` (steps 1–3 of the module docs), or `None`.
pub fn spectral_halve(graph: &ChartGraph, cost: &[f64], chart: &Chart) -> Option<Split> {
    if graph.polygons.len() < SPECTRAL_MIN_POLYGONS || cost.len() != graph.edges.len() {
        return None;
    }
    spectral_halve_of(graph, cost, chart, &fiedler_vector(chart)?, None)
}

/// Seams that halve `chart` into two parts to be solved side by side
/// ([`crate::pipeline::parts`]): the spectral split along `f` (a Fiedler vector of the chart,
/// per vertex) that prefers, after a clean halving, a level whose two sides each hold fewer
/// than `max_triangles` triangles (a larger side would be halved again: another pass, and
/// parts of unequal size, the largest setting the time of the solves side by side), and among
/// those a level whose larger side holds at most [`BALANCED_SHARE`] of the triangles; the
/// planar split when the spectral one fails. Empty when the chart cannot be halved.
pub fn halve_into_parts(
    graph: &ChartGraph,
    cost: &[f64],
    chart: &Chart,
    avoid: &[bool],
    f: &[f64],
    max_triangles: usize,
) -> Vec<[u32; 2]> {
    if graph.polygons.len() < 2 {
        return Vec::new();
    }
    match spectral_halve_of(graph, cost, chart, f, Some(max_triangles)) {
        Some(split) => split.seams,
        None => halve_planar(graph, chart, avoid),
    }
}

/// [`spectral_halve`] along the levels of `f`, a Fiedler vector of the chart (per vertex);
/// with `max_triangles`, a level whose sides both hold fewer triangles comes first after a
/// clean halving ([`halve_into_parts`]).
fn spectral_halve_of(
    graph: &ChartGraph,
    cost: &[f64],
    chart: &Chart,
    f: &[f64],
    max_triangles: Option<usize>,
) -> Option<Split> {
    if cost.len() != graph.edges.len() {
        return None;
    }
    let (quantile, area, total) = quantiles(graph, chart, f, max_triangles.is_some())?;
    let neighbours = dual_adjacency(graph);
    let np = graph.polygons.len();
    let band = BAND.min(BAND_POLYGONS as f64 / np as f64);
    // The levels' cuts are independent: computed in parallel, compared in level order.
    let cut = |levels: &[f64]| -> Vec<Option<Split>> {
        use rayon::prelude::*;
        let at = |&q: &f64| cut_at_level(graph, cost, chart, &quantile, &area, total, &neighbours, q, band);
        levels.par_iter().map(at).collect()
    };
    // Triangles per polygon, for the sides' sizes.
    let triangles: Vec<usize> = graph.polygons.iter().map(|p| p.len().saturating_sub(2)).collect();
    let all: usize = triangles.iter().sum();
    let larger = |split: &Split| {
        let first: usize = split.side.iter().zip(&triangles).filter(|x| *x.0).map(|x| *x.1).sum();
        first.max(all - first)
    };
    // With `max_triangles`: too large (a side at or over it), else unbalanced (the larger side
    // above [`BALANCED_SHARE`]).
    let sizes = |split: &Split| {
        max_triangles.map_or((false, false), |m| {
            let n = larger(split);
            (n >= m, n < m && n as f64 > BALANCED_SHARE * all as f64)
        })
    };
    let key = |split: &Split| {
        let (too_large, unbalanced) = sizes(split);
        (split.parts != 2, too_large, unbalanced, split.cost * (1.0 + (split.area_share - 0.5).abs()))
    };
    // A split with its rank (smaller is better).
    type Ranked = ((bool, bool, bool, f64), Split);
    let mut best: Option<Ranked> = None;
    let take = |best: &mut Option<Ranked>, splits: Vec<Option<Split>>| {
        for split in splits.into_iter().flatten() {
            let k = key(&split);
            if best.as_ref().is_none_or(|b| k < b.0) {
                *best = Some((k, split));
            }
        }
    };
    if max_triangles.is_some() {
        // Parts: the outer levels (their sides hold at least 1 − their level + half the band
        // of the triangles, so they are never balanced) only when no inner level gives a
        // clean, balanced halving under the limit: two rounds of minimum cuts on two cores
        // instead of three (the camel's head subdivided twice, 0.75 → 0.5 s).
        let (inner, outer) = LEVELS.split_at(INNER_LEVELS);
        take(&mut best, cut(inner));
        if best.as_ref().is_none_or(|b| b.0 .0 || b.0 .1 || b.0 .2) {
            take(&mut best, cut(outer));
        }
    } else {
        take(&mut best, cut(&LEVELS));
    }
    best.map(|b| b.1)
}

/// Per polygon of `graph`, its area quantile in the order of `f` (the mean over its corners;
/// step 1 of the module docs), with the polygons' areas and their total; `None` when the chart
/// is too small, `f`'s length does not match, or the area is not positive.
fn quantiles(graph: &ChartGraph, chart: &Chart, f: &[f64], by_triangles: bool) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let np = graph.polygons.len();
    if np < SPECTRAL_MIN_POLYGONS || f.len() != chart.positions.len() {
        return None;
    }
    let value: Vec<f64> = graph
        .polygons
        .iter()
        .map(|poly| poly.iter().map(|&v| f[v as usize]).sum::<f64>() / poly.len().max(1) as f64)
        .collect();
    let area: Vec<f64> = if by_triangles {
        graph.polygons.iter().map(|poly| poly.len().saturating_sub(2) as f64).collect()
    } else {
        graph.polygons.iter().map(|poly| polygon_area(chart, poly)).collect()
    };
    let total: f64 = area.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut order: Vec<usize> = (0..np).collect();
    order.sort_by(|&a, &b| value[a].total_cmp(&value[b]).then(a.cmp(&b)));
    let mut quantile = vec![0.0f64; np];
    let mut below = 0.0;
    for &p in &order {
        quantile[p] = (below + 0.5 * area[p]) / total;
        below += area[p];
    }
    Some((quantile, area, total))
}

/// The minimum cut of the band (of area share `band`) around level `q` (step 2), or `None` if
/// a side is empty or the band cannot be cut at a finite cost.
#[allow(clippy::too_many_arguments)]
fn cut_at_level(
    graph: &ChartGraph,
    cost: &[f64],
    chart: &Chart,
    quantile: &[f64],
    area: &[f64],
    total: f64,
    neighbours: &[Vec<u32>],
    q: f64,
    band: f64,
) -> Option<Split> {
    let np = quantile.len();
    let (lo, hi) = (q - 0.5 * band, q + 0.5 * band);
    // Nodes: 0 the low side, 1 the high side, 2.. the band's polygons.
    let mut node = vec![0u32; np];
    let mut n_nodes = 2u32;
    let (mut any_lo, mut any_hi) = (false, false);
    for p in 0..np {
        node[p] = if quantile[p] < lo {
            any_lo = true;
            0
        } else if quantile[p] > hi {
            any_hi = true;
            1
        } else {
            n_nodes += 1;
            n_nodes - 1
        };
    }
    if !(any_lo && any_hi) {
        return None;
    }
    let mut arcs: Vec<(u32, u32, f64)> = Vec::new();
    for (e, pp) in graph.edge_polygons.iter().enumerate() {
        if pp[1] == u32::MAX || pp[0] == pp[1] {
            continue;
        }
        let (a, b) = (node[pp[0] as usize], node[pp[1] as usize]);
        if a == b {
            continue;
        }
        if a.max(b) == 1 {
            // The two sides touch: the edge is cut whatever the band does.
            if !cost[e].is_finite() {
                return None;
            }
            continue;
        }
        arcs.push((a, b, cost[e]));
    }
    let cut = min_cut(n_nodes as usize, &arcs, 0, 1)?;
    let side: Vec<bool> = node.iter().map(|&n| cut.source_side[n as usize]).collect();
    let mut edges = Vec::new();
    let mut seams = Vec::new();
    let mut cut_cost = 0.0;
    for (e, pp) in graph.edge_polygons.iter().enumerate() {
        if pp[1] != u32::MAX && side[pp[0] as usize] != side[pp[1] as usize] {
            edges.push(e as u32);
            cut_cost += cost[e];
            let [a, b] = graph.edges[e];
            let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
            seams.push([ma.min(mb), ma.max(mb)]);
        }
    }
    if seams.is_empty() || !cut_cost.is_finite() {
        return None;
    }
    seams.sort_unstable();
    seams.dedup();
    let first: f64 = (0..np).filter(|&p| side[p]).map(|p| area[p]).sum();
    let parts = count_parts(neighbours, &side);
    Some(Split { seams, edges, side, cost: cut_cost, area_share: first / total, parts, level: q })
}

/// 3D area of a polygon (half the length of Newell's normal).
fn polygon_area(chart: &Chart, poly: &[u32]) -> f64 {
    0.5 * norm(crate::geometry::newell_normal(poly.len(), |i| chart.positions[poly[i] as usize]))
}

/// Polygons sharing an interior edge, per polygon.
fn dual_adjacency(graph: &ChartGraph) -> Vec<Vec<u32>> {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); graph.polygons.len()];
    for p in &graph.edge_polygons {
        if p[1] != u32::MAX && p[0] != p[1] {
            nb[p[0] as usize].push(p[1]);
            nb[p[1] as usize].push(p[0]);
        }
    }
    nb
}

/// Connected parts of the polygons when edges between the two sides are cut.
fn count_parts(neighbours: &[Vec<u32>], side: &[bool]) -> usize {
    let n = side.len();
    let mut seen = vec![false; n];
    let mut parts = 0;
    let mut stack = Vec::new();
    for s in 0..n {
        if seen[s] {
            continue;
        }
        parts += 1;
        seen[s] = true;
        stack.push(s);
        while let Some(p) = stack.pop() {
            for &q in &neighbours[p] {
                let q = q as usize;
                if !seen[q] && side[q] == side[p] {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
    }
    parts
}
