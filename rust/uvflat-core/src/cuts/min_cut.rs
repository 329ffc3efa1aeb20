//! Minimum s–t cut of an undirected graph with real capacities (Dinic's max-flow).
//!
//! Precedent: Dinic 1970 (blocking flows on BFS level graphs); the cut is read off the
//! residual graph (Ford & Fulkerson 1956): the source side is every node still reachable from
//! `s` through arcs with capacity left. On the dual graph of a band of polygons, with the cut
//! cost of each shared edge as capacity, the minimum cut is the cheapest seam that separates
//! the band's two sides (Boykov & Kolmogorov 2004 use the same duality for geodesic
//! segmentation).
//!
//! An undirected edge of capacity `c` is a pair of opposite arcs each of capacity `c`, each
//! the other's residual. Depth-first search is iterative (no recursion on large graphs).
//! Capacities below `1e-12 ×` the largest finite capacity count as saturated.
//!
//! Preconditions: capacities `≥ 0` (negative and NaN ones are read as 0); `f64::INFINITY`
//! allowed (an edge that must not be cut). Failures: `None` if `s == t`, a node index is out
//! of range, or every `s`–`t` separation crosses an infinite edge. Deterministic: arcs are
//! visited in the order the edges are given.

/// The result of [`min_cut`].
#[derive(Debug, Clone)]
pub struct MinCut {
    /// Total capacity of the cut edges (the maximum flow).
    pub value: f64,
    /// Per node: on the source side.
    pub source_side: Vec<bool>,
}

/// Minimum cut between `s` and `t` of the undirected graph on `n` nodes with `edges`
/// `(a, b, capacity)` (see the module docs).
pub fn min_cut(n: usize, edges: &[(u32, u32, f64)], s: u32, t: u32) -> Option<MinCut> {
    let (s, t) = (s as usize, t as usize);
    if s == t || s >= n || t >= n || edges.iter().any(|e| e.0 as usize >= n || e.1 as usize >= n) {
        return None;
    }
    // CSR of arcs: arc 2k goes a→b, arc 2k+1 b→a (each the other's residual).
    let m = edges.len();
    let mut to = vec![0u32; 2 * m];
    let mut cap = vec![0.0f64; 2 * m];
    let mut largest = 0.0f64;
    for (k, &(a, b, c)) in edges.iter().enumerate() {
        let c = if c > 0.0 { c } else { 0.0 };
        if c.is_finite() {
            largest = largest.max(c);
        }
        to[2 * k] = b;
        to[2 * k + 1] = a;
        cap[2 * k] = c;
        cap[2 * k + 1] = c;
    }
    let eps = 1e-12 * largest.max(f64::MIN_POSITIVE);
    let mut start = vec![0usize; n + 1];
    for &(a, b, _) in edges {
        start[a as usize + 1] += 1;
        start[b as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut arcs = vec![0u32; 2 * m];
    for (k, &(a, b, _)) in edges.iter().enumerate() {
        arcs[fill[a as usize]] = (2 * k) as u32;
        fill[a as usize] += 1;
        arcs[fill[b as usize]] = (2 * k + 1) as u32;
        fill[b as usize] += 1;
    }
    let from = |arc: usize| to[arc ^ 1] as usize;

    let mut value = 0.0f64;
    let mut level = vec![u32::MAX; n];
    let mut queue = Vec::with_capacity(n);
    let mut next = vec![0usize; n];
    let mut path: Vec<usize> = Vec::new();
    loop {
        // Level graph by BFS from s.
        level.iter_mut().for_each(|l| *l = u32::MAX);
        queue.clear();
        level[s] = 0;
        queue.push(s);
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for &arc in &arcs[start[v]..start[v + 1]] {
                let w = to[arc as usize] as usize;
                if level[w] == u32::MAX && cap[arc as usize] > eps {
                    level[w] = level[v] + 1;
                    queue.push(w);
                }
            }
        }
        if level[t] == u32::MAX {
            break;
        }
        // Blocking flow: iterative DFS with current-arc pointers.
        next.copy_from_slice(&start[..n]);
        path.clear();
        let mut v = s;
        loop {
            if v == t {
                let f = path.iter().map(|&a| cap[a]).fold(f64::INFINITY, f64::min);
                if !f.is_finite() {
                    return None;
                }
                for &a in &path {
                    cap[a] -= f;
                    cap[a ^ 1] += f;
                }
                value += f;
                // Back up to the tail of the first saturated arc.
                let cut_at = path.iter().position(|&a| cap[a] <= eps).unwrap_or(0);
                v = from(path[cut_at]);
                path.truncate(cut_at);
                continue;
            }
            let mut advanced = false;
            while next[v] < start[v + 1] {
                let arc = arcs[next[v]] as usize;
                let w = to[arc] as usize;
                if cap[arc] > eps && level[w] != u32::MAX && level[w] == level[v] + 1 {
                    path.push(arc);
                    v = w;
                    advanced = true;
                    break;
                }
                next[v] += 1;
            }
            if advanced {
                continue;
            }
            // Dead end: retreat.
            level[v] = u32::MAX;
            match path.pop() {
                Some(arc) => {
                    v = from(arc);
                    next[v] += 1;
                }
                None => break,
            }
        }
    }
    // Source side: reachable from s through arcs with capacity left.
    let mut source_side = vec![false; n];
    source_side[s] = true;
    queue.clear();
    queue.push(s);
    let mut head = 0;
    while head < queue.len() {
        let v = queue[head];
        head += 1;
        for &arc in &arcs[start[v]..start[v + 1]] {
            let w = to[arc as usize] as usize;
            if !source_side[w] && cap[arc as usize] > eps {
                source_side[w] = true;
                queue.push(w);
            }
        }
    }
    if source_side[t] {
        return None;
    }
    Some(MinCut { value, source_side })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_parallel_paths_cut_at_their_cheapest_edges() {
        // s=0 — 1 — t=3 and s — 2 — t: the cheapest edge of each path is cut.
        let edges = [(0, 1, 5.0), (1, 3, 2.0), (0, 2, 1.0), (2, 3, 4.0)];
        let c = min_cut(4, &edges, 0, 3).unwrap();
        assert!((c.value - 3.0).abs() < 1e-12);
        assert_eq!(c.source_side, vec![true, true, false, false]);
    }

    #[test]
    fn an_infinite_path_has_no_cut() {
        let edges = [(0, 1, f64::INFINITY), (1, 2, f64::INFINITY), (0, 2, 1.0)];
        assert!(min_cut(3, &edges, 0, 2).is_none());
        // An infinite edge beside a finite one is never cut.
        let edges = [(0, 1, f64::INFINITY), (1, 2, 2.0)];
        let c = min_cut(3, &edges, 0, 2).unwrap();
        assert_eq!(c.source_side, vec![true, true, false]);
        assert!((c.value - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_grid_is_cut_along_its_cheap_column() {
        // 4 × 3 grid of nodes, s left column merged, t right column merged via infinite edges;
        // horizontal edges between columns 1 and 2 are cheap.
        let id = |i: u32, j: u32| j * 4 + i;
        let mut edges = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                edges.push((id(i, j), id(i + 1, j), if i == 1 { 0.5 } else { 3.0 }));
            }
        }
        for j in 0..2 {
            for i in 0..4 {
                edges.push((id(i, j), id(i, j + 1), 10.0));
            }
        }
        // Super source 12 and sink 13.
        for j in 0..3 {
            edges.push((12, id(0, j), f64::INFINITY));
            edges.push((id(3, j), 13, f64::INFINITY));
        }
        let c = min_cut(14, &edges, 12, 13).unwrap();
        assert!((c.value - 1.5).abs() < 1e-12, "{}", c.value);
        for j in 0..3 {
            assert!(c.source_side[id(0, j) as usize] && c.source_side[id(1, j) as usize]);
            assert!(!c.source_side[id(2, j) as usize] && !c.source_side[id(3, j) as usize]);
        }
    }

    #[test]
    fn bad_arguments_are_refused() {
        assert!(min_cut(2, &[(0, 1, 1.0)], 0, 0).is_none());
        assert!(min_cut(2, &[(0, 5, 1.0)], 0, 1).is_none());
    }
}
