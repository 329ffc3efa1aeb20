//! Parts: under a method that balances area, a piece of a cut too large to solve well as one
//! is cut into parts along cheap seams before the solve, and the parts are solved side by side.
//!
//! A scan of half a million triangles comes out of its cones and cut as one or two pieces;
//! SLIM's solve of a piece that size is most of the unwrap's time (12.0 s of 14.1 s on
//! fertility subdivided three times, one piece of 568k triangles) and, as one solve, uses one
//! core. Cut into parts of under [`PART_FROM`] triangles, each part's system costs less than
//! its share (a sparse factorization costs more than linearly), and parts are solved in
//! parallel: 3.1 s there, 7.8 s in all (docs/performance.md).
//!
//! A piece is halved along the level of the chart's Fiedler vector (read on its coarse proxy,
//! once per chart: [`crate::cuts::ChartCutter::fiedler`]) at half its triangles, moved within
//! a band to the cheapest loop or path by a minimum cut ([`crate::cuts::split::halve_into_parts`]),
//! so the seams run along creases and hidden places like every other seam. The parts are solved
//! side by side, so their sizes matter, not their areas, and a level that leaves both halves
//! under [`PART_FROM`] triangles comes first: halved at half its area and at its cheapest
//! level, the bunny subdivided three times (446k triangles) came out in parts of 123k and
//! 323k triangles, and the second was halved again (4 islands, 8.5–9.0 s; now 3 islands,
//! 7.3 s); the lion subdivided twice in parts of 224k and 43k triangles (7.8 s; now 192k and
//! 74k, 5.7 s). A half still of [`PART_FROM`] triangles or more is halved again, at most
//! [`MAX_PASSES`] times in all. A level that closes
//! around inside its piece leaves a ring: it is opened like a hole ([`open_rings`]). The parts
//! are cut once per chart: every repair round adds the same seams to its cut. A level that
//! crosses its piece's outline more than twice can cut off a sliver besides the two halves (on
//! fertility subdivided three times, a part of 420 triangles): a part under [`SLIVER_BELOW`]
//! triangles gives back the seams it shares with the neighbour it shares the most of them with
//! ([`sliver_seams`]), and joins it.
//!
//! A part holds its own share of its piece's stretch, measured against its own density, so it
//! can break the rule where the piece solved whole would not: a round whose parts break it is
//! solved again whole, and no parts are cut for that chart from then on. Parts whose outlines
//! cross are peeled like large pieces ([`super::peel`], from an eighth of [`PART_FROM`]).
//! Counted in `Phases::parts`. Deterministic: the seams depend on the chart and the round's
//! cut only; parts are solved in piece order.
//!
//! A chart that will be cut into parts is planned cheaply: its first round's cones are placed
//! on its coarse proxy ([`crate::cuts::ChartCutter::plan_cut`]; the chart's own scale system
//! is factored only if a later round needs it: the bunny subdivided three times, 7.6 → 6.4 s),
//! and a disk of [`PART_FROM`] triangles or more whose conformal flattening is predicted to
//! break Max Stretch by far ([`super::triage::PREDICTED_BREAK`]) goes to the parts before any
//! solve instead of being solved whole first (the camel's head subdivided twice: its whole
//! solve, 7.6 s, was thrown away when it broke the rule; 14.7 → 5.5 s, the same islands). A
//! disk that flattens well (a terrain patch) is solved whole, one island.

use super::Context;
use crate::charts::{build_charts_with, Chart};
use crate::cuts::{self, ChartCutter};

/// Pieces of at least this many triangles are cut into parts: fertility subdivided three
/// times (one piece of 568k triangles under SLIM) comes out in 6 islands in 7.8 s, against 7
/// islands in 7.7 s from 150,000, and 2 islands in 14.1 s without parts.
pub const PART_FROM: usize = 250_000;

/// Most passes of cutting parts (each halves the parts the one before left too large).
pub const MAX_PASSES: usize = 3;

/// Whether the pieces of `chart` are cut into parts: a chart of [`PART_FROM`] triangles or
/// more, under a method that balances area ([`crate::Method::balances_area`]: SLIM, ARAP,
/// scaffold). A conformal method's map puts a piece's stretch where its curvature is, so a
/// part could hold more than 5% of its own area outside the bound where the whole piece held
/// less (the bunny subdivided three times under `abf`: a part at 6.5%, the piece at 4.2%);
/// their pieces are solved whole.
pub fn wanted(ctx: &Context<'_, '_>, chart: &Chart) -> bool {
    chart.triangles.len() >= PART_FROM && ctx.options.method.balances_area()
}

/// Seams (mesh vertex pairs) that cut the pieces of `chart` made by `seams` (the user's and
/// the round's, over faces `mask`; `pieces`: those pieces, as built) into parts of under
/// [`PART_FROM`] triangles, and the pieces cut along them too (when built on the way); no
/// seams when every piece is smaller. A part may come out a ring ([`open_rings`]).
pub fn part_seams(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    cutter: &ChartCutter<'_>,
    seams: &[[u32; 2]],
    mask: &[bool],
    pieces: &[Chart],
) -> (Vec<[u32; 2]>, Option<Vec<Chart>>) {
    if chart.triangles.len() < PART_FROM {
        return (Vec::new(), None);
    }
    let Some(fiedler) = cutter.fiedler() else { return (Vec::new(), None) };
    let mut out: Vec<[u32; 2]> = Vec::new();
    let mut all: Vec<[u32; 2]> = seams.to_vec();
    let mut built: Option<Vec<Chart>> = None;
    for _ in 0..MAX_PASSES {
        let pieces = built.as_deref().unwrap_or(pieces);
        let large: Vec<&Chart> = pieces.iter().filter(|p| p.triangles.len() >= PART_FROM).collect();
        if large.is_empty() {
            break;
        }
        let cuts: Vec<Vec<[u32; 2]>> = {
            use rayon::prelude::*;
            large.par_iter().map(|p| cut_into_parts(ctx, chart, p, fiedler)).collect()
        };
        let before = out.len();
        for c in cuts {
            out.extend_from_slice(&c);
            all.extend_from_slice(&c);
        }
        if out.len() == before {
            break;
        }
        let mut pieces = build_charts_with(ctx.mesh, &all, Some(mask), ctx.render);
        // A halving that cut off a sliver (its level crossed the piece's outline more than
        // twice) gives the sliver back to its largest neighbour across the new seams.
        let drop = sliver_seams(&pieces, &out[before..], SLIVER_BELOW);
        if !drop.is_empty() {
            let gone: std::collections::HashSet<[u32; 2]> = drop.into_iter().collect();
            // Only the halving's own seams are dropped: they run inside the pieces it cut.
            let keep = |s: &[u32; 2]| !gone.contains(&[s[0].min(s[1]), s[0].max(s[1])]);
            let tail: Vec<[u32; 2]> = out.drain(before..).filter(keep).collect();
            out.extend(tail);
            all.retain(keep);
            pieces = build_charts_with(ctx.mesh, &all, Some(mask), ctx.render);
        }
        built = Some(pieces);
    }
    (out, built)
}

/// Parts of fewer triangles than this, cut off by a halving, are given back to a neighbour
/// ([`sliver_seams`]).
pub const SLIVER_BELOW: usize = PART_FROM / 16;

/// The seams among `new_seams` (a halving's, sorted mesh vertex pairs or not) to remove so
/// that every piece of `pieces` with fewer than `below` triangles and a border on them joins
/// the neighbour it shares the most of them with (one neighbour each, so two large parts are
/// never joined through a sliver). Sorted vertex pairs; deterministic (pieces in order, ties
/// to the first neighbour).
pub fn sliver_seams(pieces: &[Chart], new_seams: &[[u32; 2]], below: usize) -> Vec<[u32; 2]> {
    use std::collections::{HashMap, HashSet};
    let key = |a: u32, b: u32| [a.min(b), a.max(b)];
    let new: HashSet<[u32; 2]> = new_seams.iter().map(|s| key(s[0], s[1])).collect();
    // The pieces on either side of every new seam edge.
    let mut sides: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    let border = |p: &Chart| -> Vec<[u32; 2]> {
        let mut e: Vec<[u32; 2]> = p
            .boundary_loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |i| (l[i], l[(i + 1) % l.len()])))
            .map(|(a, b)| key(p.mesh_vertex[a as usize], p.mesh_vertex[b as usize]))
            .filter(|e| new.contains(e))
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    };
    let borders: Vec<Vec<[u32; 2]>> = pieces.iter().map(border).collect();
    for (k, b) in borders.iter().enumerate() {
        for e in b {
            sides.entry(*e).or_default().push(k);
        }
    }
    let mut out = Vec::new();
    let mut joined = vec![false; pieces.len()];
    for (k, p) in pieces.iter().enumerate() {
        if p.triangles.len() >= below || borders[k].is_empty() || joined[k] {
            continue;
        }
        let mut shared: Vec<(usize, usize)> = Vec::new();
        for e in &borders[k] {
            for &o in sides[e].iter().filter(|&&o| o != k) {
                match shared.iter_mut().find(|s| s.0 == o) {
                    Some(s) => s.1 += 1,
                    None => shared.push((o, 1)),
                }
            }
        }
        let Some(&(to, _)) = shared.iter().max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0))) else { continue };
        out.extend(borders[k].iter().filter(|e| sides[*e].contains(&to)));
        joined[k] = true;
        joined[to] = joined[to] || pieces[to].triangles.len() < below;
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Seams that open every piece of `pieces` with more than one outline (a part whose level
/// closed around inside its piece: a ring) by the cheapest path between its outlines, as a
/// hole is joined to the outline.
pub fn open_rings(ctx: &Context<'_, '_>, pieces: &[Chart]) -> Vec<[u32; 2]> {
    let rings: Vec<&Chart> = pieces.iter().filter(|p| p.boundary_loops.len() > 1).collect();
    let joins: Vec<Vec<[u32; 2]>> = {
        use rayon::prelude::*;
        rings.par_iter().map(|p| join_outlines(ctx, p)).collect()
    };
    joins.into_iter().flatten().collect()
}

/// The cheapest seams joining the outlines of `piece` into one.
fn join_outlines(ctx: &Context<'_, '_>, piece: &Chart) -> Vec<[u32; 2]> {
    let graph = cuts::graph::ChartGraph::new(ctx.mesh, piece);
    let options = &ctx.options.auto_seams;
    let cost = cuts::edge_costs_cached(ctx.mesh, &graph, piece, options, ctx.avoid, Some(&ctx.visibility));
    let cut = cuts::cut_graph::join_and_prune(&graph, &cost, vec![false; graph.edges.len()], &[], &piece.boundary_loops);
    graph.mesh_seams(piece, &cut)
}

/// The seams that halve `piece` (a piece of `chart`) near the level of `fiedler` (per vertex
/// of `chart`) at half its triangles, both halves under [`PART_FROM`] triangles where a level
/// allows ([`crate::cuts::split::halve_into_parts`]), or none.
fn cut_into_parts(ctx: &Context<'_, '_>, chart: &Chart, piece: &Chart, fiedler: &[f64]) -> Vec<[u32; 2]> {
    let to_chart = super::repair::piece_to_original(chart, piece);
    if to_chart.contains(&u32::MAX) {
        return Vec::new();
    }
    let f: Vec<f64> = to_chart.iter().map(|&v| fiedler[v as usize]).collect();
    let graph = cuts::graph::ChartGraph::new(ctx.mesh, piece);
    let options = &ctx.options.auto_seams;
    let cost = cuts::edge_costs_cached(ctx.mesh, &graph, piece, options, ctx.avoid, Some(&ctx.visibility));
    cuts::split::halve_into_parts(&graph, &cost, piece, ctx.avoid, &f, PART_FROM)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::PolyMesh;

    /// A grid of 10 × 6 quads cut by a halving into a left part, a right part and a sliver of
    /// three quads at the bottom under the cut, two of them on the left: the sliver joins the
    /// left part (three shared seam edges against two), the seam between the two large parts
    /// and the sliver's border with the right one stay, and a sliver limit below its size
    /// keeps everything.
    #[test]
    fn a_sliver_joins_the_neighbour_it_shares_the_most_seam_with() {
        let (w, h) = (10u32, 6u32);
        let id = |i: u32, j: u32| j * (w + 1) + i;
        let positions: Vec<[f64; 3]> = (0..=h).flat_map(|j| (0..=w).map(move |i| [i as f64, j as f64, 0.0])).collect();
        let mut corner_verts = Vec::new();
        for j in 0..h {
            for i in 0..w {
                corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let face_sizes = vec![4u32; (w * h) as usize];
        let mesh = PolyMesh::new(&positions, &corner_verts, &face_sizes).unwrap();
        let key = |a: u32, b: u32| [a.min(b), a.max(b)];
        // The halving: x = 5 from y = 1 up; the sliver (cells 3..6 of the bottom row) closed
        // off by y = 1 from x = 3 to 6 and by x = 3 and x = 6 in the bottom row.
        let mut seams: Vec<[u32; 2]> = (1..h).map(|j| key(id(5, j), id(5, j + 1))).collect();
        let to_left = vec![key(id(3, 1), id(4, 1)), key(id(4, 1), id(5, 1)), key(id(3, 0), id(3, 1))];
        let to_right = vec![key(id(5, 1), id(6, 1)), key(id(6, 0), id(6, 1))];
        seams.extend(to_left.iter().chain(&to_right));
        let pieces = build_charts_with(&mesh, &seams, None, None);
        let mut sizes: Vec<usize> = pieces.iter().map(|p| p.faces.len()).collect();
        sizes.sort_unstable();
        assert_eq!(sizes, vec![3, 28, 29]);
        let mut expected = to_left.clone();
        expected.sort_unstable();
        assert_eq!(sliver_seams(&pieces, &seams, 7), expected);
        assert!(sliver_seams(&pieces, &seams, 6).is_empty(), "a sliver of 6 triangles is not below 6");
        let kept: Vec<[u32; 2]> = seams.iter().copied().filter(|s| !expected.contains(s)).collect();
        let mut sizes: Vec<usize> = build_charts_with(&mesh, &kept, None, None).iter().map(|p| p.faces.len()).collect();
        sizes.sort_unstable();
        assert_eq!(sizes, vec![29, 31], "the sliver joins the left part");
        // Seams not among the halving's are never removed: without the sliver's own seams
        // given as new, nothing is.
        assert!(sliver_seams(&pieces, &seams[..(h - 1) as usize], 7).is_empty());
    }
}
