//! Minimum s–t cut of an undirected graph with real capacities (Boykov–Kolmogorov max-flow).
//!
//! Precedent: Boykov & Kolmogorov 2004 (two search trees, from `s` and from `t`, kept between
//! augmentations: on the grid-like graphs of vision and of mesh bands it beats methods that
//! search afresh each phase; Dinic 1970's blocking flows, which this replaced, are kept in the
//! tests as the reference). The cut is read off the residual graph (Ford & Fulkerson 1956):
//! the source side is every node still reachable from `s` through arcs with capacity left. On
//! the dual graph of a band of polygons, with the cut cost of each shared edge as capacity, the
//! minimum cut is the cheapest seam that separates the band's two sides (Boykov & Kolmogorov
//! use the same duality for geodesic segmentation).
//!
//! An undirected edge of capacity `c` is a pair of opposite arcs each of capacity `c`, each
//! the other's residual. No recursion (queues and parent arcs). Capacities below `1e-12 ×` the
//! largest finite capacity count as saturated.
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
    let g = Residual::new(n, edges, s, t)?;
    g.max_flow()
}

/// The residual graph: CSR of arcs, arc `2k` goes `a→b` and `2k+1` `b→a` for edge `k`, each
/// the other's residual.
struct Residual {
    n: usize,
    s: usize,
    t: usize,
    to: Vec<u32>,
    cap: Vec<f64>,
    start: Vec<usize>,
    arcs: Vec<u32>,
    eps: f64,
}

/// No parent arc.
const NONE: u32 = u32::MAX;
/// A node's parent arc leads straight to its terminal.
const TERMINAL: u32 = u32::MAX - 1;
/// Search tree of a node: none, the source's, the sink's.
const FREE: u8 = 0;
const SRC: u8 = 1;
const SNK: u8 = 2;

impl Residual {
    fn new(n: usize, edges: &[(u32, u32, f64)], s: u32, t: u32) -> Option<Residual> {
        let (s, t) = (s as usize, t as usize);
        if s == t || s >= n || t >= n || edges.iter().any(|e| e.0 as usize >= n || e.1 as usize >= n) {
            return None;
        }
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
        Some(Residual { n, s, t, to, cap, start, arcs, eps: 1e-12 * largest.max(f64::MIN_POSITIVE) })
    }

    /// Tail of `arc`.
    fn from(&self, arc: u32) -> usize {
        self.to[(arc ^ 1) as usize] as usize
    }

    /// The parent a node of tree `side` reaches through its parent arc `arc`.
    fn up(&self, arc: u32, side: u8) -> usize {
        if side == SRC { self.from(arc) } else { self.to[arc as usize] as usize }
    }

    /// The neighbours `q` of `p` in tree `side`, each with the arc that would make it `p`'s
    /// parent (`q → p` in the source tree, `p → q` in the sink tree) and the arc that makes
    /// `p` its parent.
    fn same_tree<'t>(&'t self, p: usize, side: u8, tree: &'t [u8]) -> impl Iterator<Item = (usize, u32, u32)> + 't {
        self.arcs[self.start[p]..self.start[p + 1]].iter().filter_map(move |&a| {
            let q = self.to[a as usize] as usize;
            (tree[q] == side).then(|| if side == SRC { (q, a ^ 1, a) } else { (q, a, a ^ 1) })
        })
    }

    /// Boykov & Kolmogorov 2004: two search trees grown from `s` and `t` over arcs with
    /// capacity left, an augmenting path wherever they touch, and orphaned subtrees adopted
    /// by a node of the same tree still rooted at its terminal (checked with the distance and
    /// time marks of the paper) instead of a fresh search per phase. Deterministic: nodes are
    /// taken first in, first out, arcs in edge order.
    fn max_flow(mut self) -> Option<MinCut> {
        let n = self.n;
        let mut tree = vec![FREE; n];
        // Arc from the parent to the node (source tree) or from the node to the parent (sink
        // tree); TERMINAL at the roots.
        let mut parent = vec![NONE; n];
        let mut dist = vec![0u32; n];
        let mut stamp = vec![0u64; n];
        let mut time: u64 = 1;
        let mut active: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
        let mut is_active = vec![false; n];
        tree[self.s] = SRC;
        tree[self.t] = SNK;
        parent[self.s] = TERMINAL;
        parent[self.t] = TERMINAL;
        stamp[self.s] = time;
        stamp[self.t] = time;
        for v in [self.s, self.t] {
            active.push_back(v);
            is_active[v] = true;
        }
        let mut value = 0.0f64;
        let mut orphans: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
        let mut path: Vec<u32> = Vec::new();
        loop {
            // Growth: the first active node with an arc into the other tree gives the bridge.
            let mut bridge: Option<u32> = None;
            while let Some(&p) = active.front() {
                if tree[p] == FREE {
                    active.pop_front();
                    is_active[p] = false;
                    continue;
                }
                for k in self.start[p]..self.start[p + 1] {
                    let a = self.arcs[k];
                    let q = self.to[a as usize] as usize;
                    // Residual arc in the direction of the tree's growth.
                    let grow = if tree[p] == SRC { a } else { a ^ 1 };
                    if self.cap[grow as usize] <= self.eps {
                        continue;
                    }
                    if tree[q] == FREE {
                        tree[q] = tree[p];
                        parent[q] = grow;
                        dist[q] = dist[p] + 1;
                        stamp[q] = stamp[p];
                        if !is_active[q] {
                            active.push_back(q);
                            is_active[q] = true;
                        }
                    } else if tree[q] != tree[p] {
                        bridge = Some(grow);
                        break;
                    }
                }
                if bridge.is_some() {
                    break;
                }
                active.pop_front();
                is_active[p] = false;
            }
            let Some(bridge) = bridge else { break };
            time += 1;
            // The path: source tree to the bridge's tail, the bridge, sink tree from its head.
            let (tail, head) = (self.from(bridge), self.to[bridge as usize] as usize);
            let (sv, tv) = if tree[tail] == SRC { (tail, head) } else { (head, tail) };
            path.clear();
            path.push(bridge);
            let mut v = sv;
            while parent[v] != TERMINAL {
                path.push(parent[v]);
                v = self.from(parent[v]);
            }
            let mut v = tv;
            while parent[v] != TERMINAL {
                path.push(parent[v]);
                v = self.to[parent[v] as usize] as usize;
            }
            let f = path.iter().map(|&a| self.cap[a as usize]).fold(f64::INFINITY, f64::min);
            if !f.is_finite() {
                return None;
            }
            value += f;
            for &a in &path {
                self.cap[a as usize] -= f;
                self.cap[(a ^ 1) as usize] += f;
            }
            // Saturated tree arcs orphan their lower end.
            for &a in &path[1..] {
                if self.cap[a as usize] <= self.eps {
                    let (x, y) = (self.from(a), self.to[a as usize] as usize);
                    let child = if tree[y] == SRC && parent[y] == a { y } else { x };
                    if parent[child] == a {
                        parent[child] = NONE;
                        orphans.push_back(child);
                    }
                }
            }
            // Adoption.
            while let Some(p) = orphans.pop_front() {
                let side = tree[p];
                let mut best: Option<(u32, u32)> = None; // (arc, distance)
                for (q, link, _) in self.same_tree(p, side, &tree) {
                    if self.cap[link as usize] <= self.eps {
                        continue;
                    }
                    // Is q rooted at its terminal? Walk up until a node checked this time.
                    let mut d = 0u32;
                    let mut x = q;
                    let rooted = loop {
                        if stamp[x] == time {
                            d += dist[x];
                            break true;
                        }
                        match parent[x] {
                            TERMINAL => {
                                stamp[x] = time;
                                dist[x] = 0;
                                break true;
                            }
                            NONE => break false,
                            arc => {
                                d += 1;
                                x = self.up(arc, side);
                            }
                        }
                    };
                    if !rooted {
                        continue;
                    }
                    // Mark the checked chain with its distances.
                    let mut x = q;
                    let mut dd = d;
                    while stamp[x] != time {
                        stamp[x] = time;
                        dist[x] = dd;
                        dd = dd.saturating_sub(1);
                        x = self.up(parent[x], side);
                    }
                    if best.is_none_or(|b| d < b.1) {
                        best = Some((link, d));
                    }
                }
                if let Some((link, d)) = best {
                    parent[p] = link;
                    stamp[p] = time;
                    dist[p] = d + 1;
                    continue;
                }
                // No parent: p leaves its tree; its neighbours in the tree become active, its
                // children orphans.
                for (q, link, child_arc) in self.same_tree(p, side, &tree) {
                    if self.cap[link as usize] > self.eps && !is_active[q] {
                        active.push_back(q);
                        is_active[q] = true;
                    }
                    if parent[q] == child_arc {
                        parent[q] = NONE;
                        orphans.push_back(q);
                    }
                }
                tree[p] = FREE;
            }
        }
        self.cut(value)
    }

    /// The source side: every node still reachable from `s` through arcs with capacity left.
    fn cut(&self, value: f64) -> Option<MinCut> {
        let mut source_side = vec![false; self.n];
        source_side[self.s] = true;
        let mut queue = vec![self.s];
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head];
            head += 1;
            for &arc in &self.arcs[self.start[v]..self.start[v + 1]] {
                let w = self.to[arc as usize] as usize;
                if !source_side[w] && self.cap[arc as usize] > self.eps {
                    source_side[w] = true;
                    queue.push(w);
                }
            }
        }
        if source_side[self.t] {
            return None;
        }
        Some(MinCut { value, source_side })
    }
}

/// The same cut by Dinic's blocking flows (Dinic 1970): the reference [`min_cut`] is tested
/// against.
#[cfg(test)]
fn min_cut_dinic(n: usize, edges: &[(u32, u32, f64)], s: u32, t: u32) -> Option<MinCut> {
    let mut g = Residual::new(n, edges, s, t)?;
    let (s, t, eps) = (g.s, g.t, g.eps);
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
            for &arc in &g.arcs[g.start[v]..g.start[v + 1]] {
                let w = g.to[arc as usize] as usize;
                if level[w] == u32::MAX && g.cap[arc as usize] > eps {
                    level[w] = level[v] + 1;
                    queue.push(w);
                }
            }
        }
        if level[t] == u32::MAX {
            break;
        }
        // Blocking flow: iterative DFS with current-arc pointers.
        next.copy_from_slice(&g.start[..n]);
        path.clear();
        let mut v = s;
        loop {
            if v == t {
                let f = path.iter().map(|&a| g.cap[a]).fold(f64::INFINITY, f64::min);
                if !f.is_finite() {
                    return None;
                }
                for &a in &path {
                    g.cap[a] -= f;
                    g.cap[a ^ 1] += f;
                }
                value += f;
                // Back up to the tail of the first saturated arc.
                let cut_at = path.iter().position(|&a| g.cap[a] <= eps).unwrap_or(0);
                v = g.from(path[cut_at] as u32);
                path.truncate(cut_at);
                continue;
            }
            let mut advanced = false;
            while next[v] < g.start[v + 1] {
                let arc = g.arcs[next[v]] as usize;
                let w = g.to[arc] as usize;
                if g.cap[arc] > eps && level[w] != u32::MAX && level[w] == level[v] + 1 {
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
                    v = g.from(arc as u32);
                    next[v] += 1;
                }
                None => break,
            }
        }
    }
    g.cut(value)
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

    /// The capacity of the edges `cut` separates.
    fn cut_capacity(edges: &[(u32, u32, f64)], cut: &MinCut) -> f64 {
        edges.iter().filter(|e| cut.source_side[e.0 as usize] != cut.source_side[e.1 as usize]).map(|e| e.2).sum()
    }

    #[test]
    fn the_two_trees_agree_with_blocking_flows_on_random_graphs() {
        // Grids with random capacities (the shape of a band's dual graph) and random sparse
        // graphs; a few infinite edges. Same flow value; each cut's capacity is its value.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..60 {
            let (n, mut edges): (usize, Vec<(u32, u32, f64)>) = if case % 2 == 0 {
                let (w, h) = (3 + case % 11, 2 + case % 7);
                let id = |i: usize, j: usize| (j * w + i) as u32;
                let mut e = Vec::new();
                for j in 0..h {
                    for i in 0..w {
                        if i + 1 < w {
                            e.push((id(i, j), id(i + 1, j), 0.1 + rand()));
                        }
                        if j + 1 < h {
                            e.push((id(i, j), id(i, j + 1), 0.1 + rand()));
                        }
                    }
                }
                (w * h, e)
            } else {
                let n = 4 + case;
                let e = (0..3 * n).map(|_| ((rand() * n as f64) as u32, (rand() * n as f64) as u32, rand() * 3.0)).collect();
                (n, e)
            };
            if case % 5 == 0 && edges.len() > 2 {
                edges[1].2 = f64::INFINITY;
            }
            let (s, t) = (0u32, (n - 1) as u32);
            let (a, b) = (min_cut(n, &edges, s, t), min_cut_dinic(n, &edges, s, t));
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert!((a.value - b.value).abs() <= 1e-9 * b.value.max(1.0), "case {case}: {} vs {}", a.value, b.value);
                    assert!((cut_capacity(&edges, &a) - a.value).abs() <= 1e-9 * a.value.max(1.0), "case {case}");
                    assert!(a.source_side[0] && !a.source_side[n - 1]);
                }
                (None, None) => {}
                (a, b) => panic!("case {case}: {:?} vs {:?}", a.map(|c| c.value), b.map(|c| c.value)),
            }
        }
    }

    #[test]
    fn bad_arguments_are_refused() {
        assert!(min_cut(2, &[(0, 1, 1.0)], 0, 0).is_none());
        assert!(min_cut(2, &[(0, 5, 1.0)], 0, 1).is_none());
    }
}
