//! The cut graph: handle loops by tree–cotree, joined to the cones and the boundary by an
//! approximate Steiner tree, dangling branches pruned.
//!
//! * Handle loops (genus g > 0): Eppstein 2003 tree–cotree decomposition with the short-loop
//!   weighting of Erickson & Whittlesey 2005: the primal tree `T` is a shortest-path tree from a
//!   root, the dual tree `C` a maximum spanning tree of the dual graph weighted by the length
//!   of the loop each edge closes with `T`; each of the 2g edges in neither closes one loop.
//!   Boundary loops are treated as filled (one extra dual node each), so only handles yield
//!   loops.
//! * Joining (Mehlhorn 1988's 2-approximation of the Steiner tree): multi-source Dijkstra from
//!   every terminal group (each cone; the handle loops together; each boundary loop) labels
//!   every vertex with its nearest group; the edges between two labels are candidate bridges of
//!   cost d(a) + c(ab) + d(b); Kruskal over them with union-find on the groups keeps the
//!   cheapest bridges that join everything, and each kept bridge adds its two shortest paths.
//! * Pruning: branches ending at a vertex that is neither a cone nor on the boundary are
//!   removed, repeatedly.
//!
//! Edge costs come from the caller (length, cheaper on sharp edges, far dearer where seams
//! must be avoided). Ties break by edge id, so the result is deterministic.

use super::graph::{multi_source_dijkstra, other, ChartGraph};
use crate::charts::UnionFind;

/// Edges (ids) of 2g loops that cut every handle of a chart of genus `genus`, or none.
pub fn handle_loops(graph: &ChartGraph, cost: &[f64], root: u32, boundary_loops: &[Vec<u32>]) -> Vec<bool> {
    let ne = graph.edges.len();
    let mut in_cut = vec![false; ne];
    let (dist, parent, _) = multi_source_dijkstra(graph, cost, &[(root, 0)]);
    let mut in_tree = vec![false; ne];
    for &p in &parent {
        if p != u32::MAX {
            in_tree[p as usize] = true;
        }
    }
    // Dual nodes: polygons, then one per boundary loop (filled).
    let np = graph.polygons.len();
    let mut loop_of_vertex = vec![u32::MAX; graph.n_vertices];
    for (l, lp) in boundary_loops.iter().enumerate() {
        for &v in lp {
            loop_of_vertex[v as usize] = l as u32;
        }
    }
    let dual_ends = |e: usize| -> [u32; 2] {
        let p = graph.edge_polygons[e];
        if p[1] != u32::MAX {
            p
        } else {
            let l = loop_of_vertex[graph.edges[e][0] as usize];
            [p[0], np as u32 + l]
        }
    };
    let n_dual = np + boundary_loops.len();
    let loop_len = |e: usize| dist[graph.edges[e][0] as usize] + dist[graph.edges[e][1] as usize] + cost[e];
    let mut candidates: Vec<usize> = (0..ne).filter(|&e| !in_tree[e] && dist[graph.edges[e][0] as usize].is_finite()).collect();
    // Maximum spanning tree: longest loops first.
    candidates.sort_by(|&a, &b| loop_len(b).total_cmp(&loop_len(a)).then(a.cmp(&b)));
    let mut uf = UnionFind::new(n_dual);
    let mut generators = Vec::new();
    for e in candidates {
        let [p, q] = dual_ends(e);
        if p == u32::MAX || q == u32::MAX {
            continue;
        }
        if !uf.union(p, q) {
            generators.push(e);
        }
    }
    for e in generators {
        in_cut[e] = true;
        for &start in &graph.edges[e] {
            let mut v = start;
            while parent[v as usize] != u32::MAX {
                let pe = parent[v as usize];
                in_cut[pe as usize] = true;
                v = other(graph, pe, v);
            }
        }
    }
    in_cut
}

/// Join `cut` (edge flags, e.g. handle loops), the `cones` and the `boundary_loops` into one
/// connected cut graph, then prune dangling branches. Returns the new edge flags.
pub fn join_and_prune(
    graph: &ChartGraph,
    cost: &[f64],
    mut cut: Vec<bool>,
    cones: &[u32],
    boundary_loops: &[Vec<u32>],
) -> Vec<bool> {
    // Terminal groups: the existing cut graph (all its vertices), each boundary loop, each cone.
    let mut sources: Vec<(u32, u32)> = Vec::new();
    let mut group = 0u32;
    let mut cut_vertices: Vec<u32> = Vec::new();
    for (e, &c) in cut.iter().enumerate() {
        if c {
            cut_vertices.extend(graph.edges[e]);
        }
    }
    cut_vertices.sort_unstable();
    cut_vertices.dedup();
    if !cut_vertices.is_empty() {
        sources.extend(cut_vertices.iter().map(|&v| (v, group)));
        group += 1;
    }
    for lp in boundary_loops {
        sources.extend(lp.iter().map(|&v| (v, group)));
        group += 1;
    }
    for &c in cones {
        if !sources.iter().any(|s| s.0 == c) {
            sources.push((c, group));
            group += 1;
        }
    }
    if group > 1 {
        let (dist, parent, label) = multi_source_dijkstra(graph, cost, &sources);
        let mut bridges: Vec<(f64, usize)> = (0..graph.edges.len())
            .filter_map(|e| {
                let [a, b] = graph.edges[e];
                let (la, lb) = (label[a as usize], label[b as usize]);
                let c = dist[a as usize] + cost[e] + dist[b as usize];
                (la != lb && la != u32::MAX && lb != u32::MAX && c.is_finite()).then_some((c, e))
            })
            .collect();
        bridges.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut uf = UnionFind::new(group as usize);
        let mut joined = 1;
        for (_, e) in bridges {
            if joined == group {
                break;
            }
            let [a, b] = graph.edges[e];
            if uf.union(label[a as usize], label[b as usize]) {
                joined += 1;
                cut[e] = true;
                for start in [a, b] {
                    let mut v = start;
                    while parent[v as usize] != u32::MAX {
                        let pe = parent[v as usize];
                        cut[pe as usize] = true;
                        v = other(graph, pe, v);
                    }
                }
            }
        }
    }
    // Boundary edges are already open: they are never cut edges.
    for (e, c) in cut.iter_mut().enumerate() {
        if graph.is_boundary(e) {
            *c = false;
        }
    }
    prune(graph, &mut cut, cones);
    cut
}

/// Remove, repeatedly, cut edges that end at a vertex of cut degree 1 which is neither a cone
/// nor on the boundary.
pub fn prune(graph: &ChartGraph, cut: &mut [bool], cones: &[u32]) {
    let n = graph.n_vertices;
    let mut keep = vec![false; n];
    for &c in cones {
        keep[c as usize] = true;
    }
    for (e, _) in graph.edges.iter().enumerate() {
        if graph.is_boundary(e) {
            let [a, b] = graph.edges[e];
            keep[a as usize] = true;
            keep[b as usize] = true;
        }
    }
    let mut degree = vec![0u32; n];
    for (e, &c) in cut.iter().enumerate() {
        if c {
            degree[graph.edges[e][0] as usize] += 1;
            degree[graph.edges[e][1] as usize] += 1;
        }
    }
    let mut stack: Vec<u32> = (0..n as u32).filter(|&v| degree[v as usize] == 1 && !keep[v as usize]).collect();
    while let Some(v) = stack.pop() {
        if degree[v as usize] != 1 {
            continue;
        }
        if let Some(&(w, e)) = graph.neighbours(v).iter().find(|&&(_, e)| cut[e as usize]) {
            cut[e as usize] = false;
            degree[v as usize] -= 1;
            degree[w as usize] -= 1;
            if degree[w as usize] == 1 && !keep[w as usize] {
                stack.push(w);
            }
        }
    }
}
