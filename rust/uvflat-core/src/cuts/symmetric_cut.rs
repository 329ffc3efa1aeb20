//! A mirror-symmetric cut of a closed genus-0 chart: plan on one half, mirror it.
//!
//! Precedent: symmetric seams of character modelling (an artist unwraps one half and mirrors
//! it; Blender's and Maya's symmetric selection tools); the cut graph is built like
//! [`super::cut_graph::join_and_prune`] (Mehlhorn's Steiner tree), on half of the chart.
//!
//! With the mirror `σ` ([`super::symmetry`]) and a symmetric set of cones, every vertex is on
//! the plane (`σ(v) = v`), on the positive side or on the negative side. Then:
//! 1. the attachment: the plane cone nearest the positive cones if there is a plane cone;
//!    otherwise the plane vertex, or the edge `(u, σ(u))` across the plane, nearest them (by
//!    shortest paths through the positive side; ties by id);
//! 2. `H`: the Steiner tree joining the positive cones and the attachment through positive
//!    vertices only (edges touching the plane or the other side are closed);
//! 3. the plane cones joined to the attachment by shortest paths along edges of the plane;
//! 4. the cut: `H ∪ σ(H)` ∪ those paths (∪ the crossing edge), pruned to the cones.
//!
//! `H` and `σ(H)` meet only at the attachment, and the plane paths form a tree from it, so the
//! cut is a tree through every cone: it opens the closed genus-0 chart into one disk, and it
//! is its own mirror image.
//!
//! Preconditions: a closed chart of genus 0; `cones` closed under `σ`; `cost` symmetric
//! (`cost[σ(e)] = cost[e]`). Failures: `None` when there are no cones, a positive cone cannot
//! reach the plane, or a plane cone cannot be reached along the plane; the caller then plans
//! an ordinary cut.

use super::cut_graph::{join_and_prune, prune};
use super::graph::{multi_source_dijkstra, other, ChartGraph};
use super::symmetry::Mirror;

/// Where a vertex lies with respect to the mirror plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Plane,
    Positive,
    Negative,
}

/// Cut edges (flags per graph edge) of the symmetric cut (see the module docs).
pub fn symmetric_cut(graph: &ChartGraph, cost: &[f64], positions: &[[f64; 3]], mirror: &Mirror, cones: &[u32]) -> Option<Vec<bool>> {
    let n = graph.n_vertices;
    if cones.is_empty() || mirror.vertex.len() != n || cost.len() != graph.edges.len() {
        return None;
    }
    let side: Vec<Side> = (0..n)
        .map(|v| {
            let m = mirror.vertex[v] as usize;
            if m == v {
                return Side::Plane;
            }
            // Of a pair, the one farther on the normal's side (ties: the lower id) is positive,
            // so exactly one of the two is, even for a pair closer to the plane than the
            // matching tolerance.
            let (d, dm) = (mirror.side(positions[v]), mirror.side(positions[m]));
            if d > dm || (d == dm && v < m) {
                Side::Positive
            } else {
                Side::Negative
            }
        })
        .collect();
    let positive: Vec<u32> = cones.iter().copied().filter(|&c| side[c as usize] == Side::Positive).collect();
    let mut plane_cones: Vec<u32> = cones.iter().copied().filter(|&c| side[c as usize] == Side::Plane).collect();
    plane_cones.sort_unstable();
    // Paths through the positive side only.
    let inside: Vec<f64> = (0..graph.edges.len())
        .map(|e| {
            let [a, b] = graph.edges[e];
            if side[a as usize] == Side::Positive && side[b as usize] == Side::Positive {
                cost[e]
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let sources: Vec<(u32, u32)> = positive.iter().map(|&c| (c, 0)).collect();
    let (dist, _, _) = multi_source_dijkstra(graph, &inside, &sources);
    // 1. The attachment: (cost, plane vertex, crossing edge).
    let mut attach: Option<(f64, u32, Option<u32>)> = None;
    let mut consider = |c: f64, v: u32, e: Option<u32>| {
        if c.is_finite() && attach.is_none_or(|a| (c, v) < (a.0, a.1)) {
            attach = Some((c, v, e));
        }
    };
    if positive.is_empty() {
        // Cones closed under the mirror: none positive means all on the plane.
        consider(0.0, *plane_cones.first()?, None);
    } else {
        for (e, &[a, b]) in graph.edges.iter().enumerate() {
            let (sa, sb) = (side[a as usize], side[b as usize]);
            for (u, w, su, sw) in [(a, b, sa, sb), (b, a, sb, sa)] {
                if su != Side::Positive {
                    continue;
                }
                let through = dist[u as usize] + cost[e];
                if sw == Side::Plane && (plane_cones.is_empty() || plane_cones.binary_search(&w).is_ok()) {
                    consider(through, w, None);
                } else if sw == Side::Negative && plane_cones.is_empty() && mirror.vertex[u as usize] == w {
                    // The crossing edge counts from its positive end.
                    consider(dist[u as usize], u, Some(e as u32));
                }
            }
        }
    }
    let (_, anchor, crossing) = attach?;
    // 2. H through the positive side, with the anchor's edges to it open.
    let mut cut = vec![false; graph.edges.len()];
    if !positive.is_empty() {
        let half: Vec<f64> = (0..graph.edges.len())
            .map(|e| {
                let [a, b] = graph.edges[e];
                let ok = |v: u32| side[v as usize] == Side::Positive || v == anchor;
                if ok(a) && ok(b) {
                    cost[e]
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        let mut terminals = positive.clone();
        if !terminals.contains(&anchor) {
            terminals.push(anchor);
        }
        let h = join_and_prune(graph, &half, vec![false; graph.edges.len()], &terminals, &[]);
        // Every positive cone must be joined: H is one tree through all terminals.
        if !spans(graph, &h, &terminals) {
            return None;
        }
        for (e, &c) in h.iter().enumerate() {
            if c {
                cut[e] = true;
                cut[mirror.edge[e] as usize] = true;
            }
        }
    }
    if let Some(e) = crossing {
        cut[e as usize] = true;
    }
    // 3. Plane cones joined to the anchor along the plane.
    if !plane_cones.is_empty() {
        let along: Vec<f64> = (0..graph.edges.len())
            .map(|e| {
                let [a, b] = graph.edges[e];
                if side[a as usize] == Side::Plane && side[b as usize] == Side::Plane {
                    cost[e]
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        let (d, parent, _) = multi_source_dijkstra(graph, &along, &[(anchor, 0)]);
        for &z in &plane_cones {
            if !d[z as usize].is_finite() {
                return None;
            }
            let mut v = z;
            while parent[v as usize] != u32::MAX {
                let e = parent[v as usize];
                cut[e as usize] = true;
                v = other(graph, e, v);
            }
        }
    }
    prune(graph, &mut cut, cones);
    Some(cut)
}

/// Whether the cut edges join all `terminals` into one connected piece.
fn spans(graph: &ChartGraph, cut: &[bool], terminals: &[u32]) -> bool {
    if terminals.len() <= 1 {
        return true;
    }
    let mut seen = vec![false; graph.n_vertices];
    let mut stack = vec![terminals[0]];
    seen[terminals[0] as usize] = true;
    while let Some(v) = stack.pop() {
        for &(w, e) in graph.neighbours(v) {
            if cut[e as usize] && !seen[w as usize] {
                seen[w as usize] = true;
                stack.push(w);
            }
        }
    }
    terminals.iter().all(|&t| seen[t as usize])
}
