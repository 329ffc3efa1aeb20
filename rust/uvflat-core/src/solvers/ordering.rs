//! Fill-reducing orderings for sparse Cholesky: faer's approximate minimum degree (AMD) for
//! small systems, nested dissection above [`ND_MIN_SIZE`] unknowns.
//!
//! Which one pays depends on how often the system is factored. Nested dissection takes
//! 1.4–3.4× longer to compute than AMD and stores up to ~10 % fewer factor entries on large irregular
//! charts (none fewer on regular ones), so it pays only when that saving is collected on many
//! numeric factorizations: [`OrderingKind::Auto`] is for those systems (SLIM, MIPS, scaffold,
//! ABF++'s reduced system). A system factored once (LSCM, Tutte, harmonic, mean value) or
//! factored once and solved many times (ARAP, the spectral inverse iteration) uses
//! [`OrderingKind::Amd`] at every size.
//!
//! Nested dissection (George 1973; the graph form of Liu 1989 / George & Liu's "automatic
//! nested dissection"): find a small vertex separator `S` that splits the graph of the matrix
//! into two parts `A` and `B` with no edge between them, order `A`, then `B`, then `S` last,
//! and recurse into `A` and `B`. Eliminating `A` creates no fill in `B`, so the factor of a
//! planar mesh's Laplacian has `O(n log n)` nonzeros. Separators here are levels of a
//! breadth-first level structure rooted at a pseudo-peripheral vertex (Gibbs, Poole &
//! Stockmeyer 1976), the level minimising the ratio cut |S|·n / (|A|·|B|), then
//! thinned: a separator vertex with no neighbour on the `B` side joins `A`. Parts of at most
//! [`ND_LEAF_SIZE`] vertices are ordered by AMD. Meshes are nearly planar graphs whose BFS
//! levels are short closed curves, which makes these separators `O(√n)` — what a geometric
//! bisection would give, without needing positions. The two sides of a large part (from
//! `ND_PARALLEL_MIN` vertices) are dissected in parallel; each side's order depends only on
//! its own vertices, so the result is the same on any number of threads.
//!
//! Preconditions: a square pattern (any triangle, or both; the diagonal is ignored).
//! Failures: only faer's allocation / index overflow errors from AMD.

use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicU32, AtomicU64};

use faer::sparse::FaerError;

/// Systems with at least this many unknowns use nested dissection in
/// [`OrderingKind::Auto`]; smaller ones AMD. Measured with `examples/ordering.rs`: see the
/// README's performance section.
pub const ND_MIN_SIZE: usize = 40_000;

/// Parts of at most this many vertices stop the dissection and are ordered by AMD.
pub const ND_LEAF_SIZE: usize = 256;

/// Which fill-reducing ordering to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OrderingKind {
    /// AMD below [`ND_MIN_SIZE`] unknowns, nested dissection from there on. Default.
    #[default]
    Auto,
    /// faer's approximate minimum degree.
    Amd,
    /// Nested dissection with BFS level-structure separators.
    NestedDissection,
}

impl OrderingKind {
    /// The ordering actually used for a system of `n` unknowns.
    pub fn resolve(self, n: usize) -> OrderingKind {
        match self {
            OrderingKind::Auto if n >= ND_MIN_SIZE => OrderingKind::NestedDissection,
            OrderingKind::Auto => OrderingKind::Amd,
            other => other,
        }
    }
}

/// The ordering a solver uses: computed, or derived from an elimination order of the mesh
/// vertices that the system's unknowns belong to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ordering<'a> {
    /// Compute one of this kind from the system's pattern.
    Kind(OrderingKind),
    /// Derive it from `order` (vertices in elimination order, e.g. [`crate::charts::Chart::vertex_order`],
    /// an AMD ordering of the chart's vertex graph, or a nested dissection of it on large
    /// charts): the unknowns of vertex `v` are `k·v .. k·v + k` for `k` = unknowns / vertices
    /// (1 or 2), taken in that order, fixed ones skipped. Several systems over one chart (a
    /// start's LSCM, the method's own) then share one ordering instead of computing it each.
    /// Used where `kind` would compute AMD for the free unknowns (a nested dissection for a
    /// large system refactored at every iteration is computed for it, see [`vertex_order`]),
    /// and when the order covers every vertex once.
    Vertices { order: &'a [u32], kind: OrderingKind },
}

impl From<OrderingKind> for Ordering<'_> {
    fn from(kind: OrderingKind) -> Self {
        Ordering::Kind(kind)
    }
}

impl Ordering<'_> {
    /// The kind this ordering computes, or stands in for.
    pub fn kind(&self) -> OrderingKind {
        match *self {
            Ordering::Kind(kind) | Ordering::Vertices { kind, .. } => kind,
        }
    }

    /// The permutation of the free unknowns of an `n`-unknown system (`free_pos[u]`: free
    /// index of unknown `u`, `u32::MAX` when fixed; `nf` free) that a vertex order gives
    /// ([`Ordering::Vertices`]), or `None` when it does not apply.
    pub fn of_vertices(&self, n: usize, free_pos: &[u32], nf: usize) -> Option<Permutation> {
        let Ordering::Vertices { order, kind } = *self else {
            return None;
        };
        if order.is_empty() || n % order.len() != 0 || !(1..=2).contains(&(n / order.len())) || kind.resolve(nf) != OrderingKind::Amd {
            return None;
        }
        let k = n / order.len();
        let mut seen = vec![false; order.len()];
        let mut fwd = Vec::with_capacity(nf);
        for &v in order {
            let v = v as usize;
            if v >= seen.len() || std::mem::replace(&mut seen[v], true) {
                return None;
            }
            for u in k * v..k * v + k {
                if free_pos[u] != u32::MAX {
                    fwd.push(free_pos[u] as usize);
                }
            }
        }
        (fwd.len() == nf).then(|| Permutation { blocks: k == 2, ..Permutation::from_fwd(fwd) })
    }
}

/// Elimination order of the vertex graph of `triangles` over `n` vertices (vertices in
/// elimination order), for [`Ordering::Vertices`]: AMD, or nested dissection from
/// [`ND_MIN_SIZE`] vertices ([`vertex_order_is_nested`]), for the systems the chart factors
/// once (the LSCM and mean value starts, ABF's LSCM reconstruction). On fertility subdivided
/// three times the vertex graph factored in 0.46 s with nested dissection against 0.55 s with
/// AMD (`examples/ordering.rs`), and ABF's LSCM reconstruction of the chart cut by automatic
/// seams in 0.84 s against 1.92 s. The systems refactored at every iteration still compute
/// their own nested dissection: a piece's order is its parent's restricted to it
/// ([`crate::charts::Chart::inherit_vertex_order`]), and SLIM's system on that chart stored
/// 76.6M factor values with the restricted order against 65.2M with its own, each
/// factorization 1.1–1.4 s against 0.7–0.85 s. The identity when the ordering fails.
pub fn vertex_order(n: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    // Neighbours of every vertex (with repeats), then each list sorted and made unique.
    let mut start = vec![0usize; n + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 2;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut at = start.clone();
    let mut all = vec![0usize; start[n]];
    for t in triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            all[at[v]] = t[(k + 1) % 3] as usize;
            all[at[v] + 1] = t[(k + 2) % 3] as usize;
            at[v] += 2;
        }
    }
    drop(at);
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::with_capacity(all.len() / 2);
    for v in 0..n {
        let seg = &mut all[start[v]..start[v + 1]];
        seg.sort_unstable();
        let first = row_idx.len();
        for &u in seg.iter() {
            if row_idx.len() == first || row_idx[row_idx.len() - 1] != u {
                row_idx.push(u);
            }
        }
        col_ptr.push(row_idx.len());
    }
    drop(all);
    let order = if vertex_order_is_nested(n) {
        // The strict lower triangle, the form in which `fill_reducing` hands a 2×2-block
        // system's block graph to the dissection.
        let mut lower_ptr = Vec::with_capacity(n + 1);
        lower_ptr.push(0usize);
        let mut lower = Vec::with_capacity(row_idx.len() / 2);
        for v in 0..n {
            lower.extend(row_idx[col_ptr[v]..col_ptr[v + 1]].iter().filter(|&&u| u > v));
            lower_ptr.push(lower.len());
        }
        drop((col_ptr, row_idx));
        nested_dissection(&Graph::from_pattern(n, &lower_ptr, &lower))
    } else {
        amd(n, &col_ptr, &row_idx)
    };
    match order {
        Ok(p) => p.fwd.into_iter().map(|v| v as u32).collect(),
        Err(_) => (0..n as u32).collect(),
    }
}

/// Whether a vertex order of `n` vertices from [`vertex_order`] (or one restricted from a
/// larger chart's, [`crate::charts::Chart::inherit_vertex_order`]) is a nested dissection:
/// from [`ND_MIN_SIZE`] vertices on.
pub fn vertex_order_is_nested(n: usize) -> bool {
    OrderingKind::Auto.resolve(n) == OrderingKind::NestedDissection
}

/// A symmetric permutation as faer takes it: `fwd[new] = old`, `inv[old] = new`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Permutation {
    /// Old index at every new position (elimination order).
    pub fwd: Vec<usize>,
    /// New position of every old index.
    pub inv: Vec<usize>,
    /// Every node the ordering was computed on stands for two or more unknowns, kept together
    /// (interleaved 2×2 blocks; ABF++'s two rows per interior vertex), so the factor's
    /// supernodes are at least two columns wide ([`symbolic_params`] then picks the
    /// supernodal factorization).
    pub blocks: bool,
}

impl Permutation {
    fn from_fwd(fwd: Vec<usize>) -> Self {
        let mut inv = vec![0usize; fwd.len()];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        Permutation { fwd, inv, blocks: false }
    }
}

/// 2×2-block systems of at least this many unknowns are factored supernodally
/// ([`symbolic_params`]).
pub const SUPERNODAL_BLOCKS_FROM: usize = 256;

/// The symbolic Cholesky parameters for a system ordered by `perm`: faer's supernodal
/// factorization for block systems ([`Permutation::blocks`]: SLIM, MIPS, scaffold, ABF++'s
/// reduced system) of at least [`SUPERNODAL_BLOCKS_FROM`] unknowns, faer's own choice
/// otherwise. faer picks by flops per factor entry, which keeps
/// these systems simplicial up to about 20k unknowns, although every supernode of a block
/// system is at least two columns wide. Numeric factorization, the block pattern of SLIM with
/// AMD, simplicial against supernodal: the 128 charts of camelhead cut by Smart UV Project
/// (the largest 4,708 unknowns) 9.9 against 5.5 ms in all; Suzanne subdivided twice with her
/// seams, largest chart 10,442 unknowns, 14.2 against 4.4 ms; at 422 unknowns 71 against
/// 59 µs, from about 100 unknowns down the same. On scalar systems (one unknown per vertex)
/// faer's choice was within 10 % of the better one.
pub fn symbolic_params(perm: &Permutation) -> faer::sparse::linalg::cholesky::CholeskySymbolicParams<'static> {
    let mut params = faer::sparse::linalg::cholesky::CholeskySymbolicParams::default();
    if perm.blocks && perm.fwd.len() >= SUPERNODAL_BLOCKS_FROM {
        params.supernodal_flop_ratio_threshold = faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL;
    }
    params
}

/// Compute a fill-reducing ordering of the `n × n` symmetric pattern given in compressed
/// column form (`col_ptr`, `row_idx`; either triangle or both, unsorted allowed).
pub fn fill_reducing(kind: OrderingKind, n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Permutation, FaerError> {
    if n <= 2 {
        // No ordering can change the fill of a 1×1 or 2×2 factor (one-triangle charts).
        return Ok(Permutation::from_fwd((0..n).collect()));
    }
    // The u and v of one vertex (unknowns 2k and 2k + 1 with the same neighbours) are ordered
    // as one node: a quarter of the entries, the same elimination.
    if let Some((bp, bi)) = interleaved_blocks(n, col_ptr, row_idx) {
        let block = match kind.resolve(n) {
            OrderingKind::Amd => amd(n / 2, &bp, &bi)?,
            _ => nested_dissection(&Graph::from_pattern(n / 2, &bp, &bi))?,
        };
        let fwd = block.fwd.iter().flat_map(|&k| [2 * k, 2 * k + 1]).collect();
        return Ok(Permutation { blocks: true, ..Permutation::from_fwd(fwd) });
    }
    if kind.resolve(n) == OrderingKind::Amd {
        return amd(n, col_ptr, row_idx);
    }
    let graph = Graph::from_pattern(n, col_ptr, row_idx);
    // Unknowns with identical closed neighbourhoods (the u and v of one vertex in a 2×2-block
    // system) are one supervariable: dissect the smaller quotient graph.
    let Some((quotient, members)) = graph.compress() else {
        return nested_dissection(&graph);
    };
    drop(graph);
    let order = nested_dissection(&quotient)?;
    let fwd = order.fwd.iter().flat_map(|&sv| members.list[members.ptr[sv]..members.ptr[sv + 1]].iter().copied()).collect();
    Ok(Permutation::from_fwd(fwd))
}

/// faer's AMD of the pattern of `A + Aᵀ` (either triangle or both, unsorted, diagonal
/// ignored): no adjacency copy is needed.
fn amd(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Permutation, FaerError> {
    let a = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
    let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
    let mut mem = faer::dyn_stack::MemBuffer::try_new(faer::sparse::linalg::amd::order_maybe_unsorted_scratch::<usize>(n, row_idx.len()))
        .map_err(|_| FaerError::OutOfMemory)?;
    faer::sparse::linalg::amd::order_maybe_unsorted(&mut fwd, &mut inv, a, Default::default(), faer::dyn_stack::MemStack::new(&mut mem))?;
    Ok(Permutation { fwd, inv, blocks: false })
}

/// The pattern of the `n/2 × n/2` block graph when the lower-triangle pattern (`col_ptr`,
/// sorted `row_idx`) is made of full 2×2 blocks over interleaved unknowns (`2k`, `2k + 1`):
/// the SLIM, MIPS and scaffold systems over (u, v) per vertex. `None` otherwise (an
/// odd size, a pin fixing only one of a vertex's unknowns, any other pattern). Checked in one
/// pass over the entries: column `2k`'s and column `2k + 1`'s rows name the same blocks, and
/// column `2k` holds row `2k + 1`.
fn interleaved_blocks(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Option<(Vec<usize>, Vec<usize>)> {
    if n < 4 || n % 2 != 0 {
        return None;
    }
    let m = n / 2;
    let mut bp = Vec::with_capacity(m + 1);
    bp.push(0usize);
    let mut bi = Vec::with_capacity(row_idx.len() / 4 + m);
    for k in 0..m {
        let (a, b) = (&row_idx[col_ptr[2 * k]..col_ptr[2 * k + 1]], &row_idx[col_ptr[2 * k + 1]..col_ptr[2 * k + 2]]);
        // lower triangle: column 2k is {2k, 2k+1, rest}, column 2k+1 is {2k+1, rest}, and rest
        // covers every block it touches in both unknowns
        if a.len() != b.len() + 1 || a.first() != Some(&(2 * k)) || a.get(1) != Some(&(2 * k + 1)) || a[1..] != *b {
            return None;
        }
        let rest = &b[1..];
        if rest.len() % 2 != 0 {
            return None;
        }
        for pair in rest.chunks_exact(2) {
            if pair[0] % 2 != 0 || pair[1] != pair[0] + 1 {
                return None;
            }
            bi.push(pair[0] / 2);
        }
        bp.push(bi.len());
    }
    Some((bp, bi))
}

/// The members of every supervariable of [`Graph::compress`], compressed: supervariable `s`
/// is `list[ptr[s]..ptr[s + 1]]`.
struct Supervariables {
    ptr: Vec<usize>,
    list: Vec<usize>,
}

/// Undirected adjacency without self loops or duplicate edges.
struct Graph {
    ptr: Vec<usize>,
    adj: Vec<usize>,
}

impl Graph {
    fn from_pattern(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Graph {
        let mut deg = vec![0usize; n + 1];
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if r != c {
                    deg[r] += 1;
                    deg[c] += 1;
                }
            }
        }
        let mut ptr = vec![0usize; n + 1];
        for v in 0..n {
            ptr[v + 1] = ptr[v] + deg[v];
        }
        let mut fill = ptr.clone();
        let mut adj = vec![0usize; ptr[n]];
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if r != c {
                    adj[fill[r]] = c;
                    fill[r] += 1;
                    adj[fill[c]] = r;
                    fill[c] += 1;
                }
            }
        }
        // Remove duplicates (an entry given in both triangles, or repeated).
        let mut mark = vec![usize::MAX; n];
        let mut out_ptr = vec![0usize; n + 1];
        let mut k = 0;
        for v in 0..n {
            let (a, b) = (ptr[v], ptr[v + 1]);
            for i in a..b {
                let w = adj[i];
                if mark[w] != v {
                    mark[w] = v;
                    adj[k] = w;
                    k += 1;
                }
            }
            out_ptr[v + 1] = k;
        }
        adj.truncate(k);
        Graph { ptr: out_ptr, adj }
    }

    fn n(&self) -> usize {
        self.ptr.len() - 1
    }

    /// Merge vertices whose closed neighbourhoods (neighbours and the vertex itself) are
    /// equal into supervariables. Returns the quotient graph and the members of each
    /// supervariable (`members[ptr[s]..ptr[s + 1]]`), or `None` when merging would leave more
    /// than three quarters of the vertices (nothing worth a smaller graph).
    ///
    /// Candidates are found by an order-independent hash of the closed neighbourhood (a sum
    /// of mixed indices, no sorting and no allocation per vertex); only vertices with equal
    /// hashes are compared exactly.
    fn compress(&self) -> Option<(Graph, Supervariables)> {
        let n = self.n();
        let mix = |w: usize| {
            let mut z = (w as u64).wrapping_add(0x9e3779b97f4a7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            z ^ (z >> 31)
        };
        let mut keys: Vec<(u64, usize)> = (0..n)
            .map(|v| {
                let nb = self.neighbours(v);
                let h = nb.iter().fold(mix(v).wrapping_add(nb.len() as u64), |h, &w| h.wrapping_add(mix(w)));
                (h, v)
            })
            .collect();
        keys.sort_unstable();
        let twins = keys.windows(2).filter(|k| k[0].0 == k[1].0).count();
        if (n - twins) * 4 > n * 3 {
            return None;
        }
        // Representative (smallest member) of every vertex's supervariable. `keys` is sorted
        // by (hash, vertex), so the first unassigned vertex of a hash bucket is the smallest
        // of its group; equality of closed neighbourhoods is tested by marking one of them.
        let mut rep: Vec<usize> = (0..n).collect();
        let mut mark = vec![usize::MAX; n];
        let mut i = 0;
        while i < n {
            let mut j = i + 1;
            while j < n && keys[j].0 == keys[i].0 {
                j += 1;
            }
            for a in i..j {
                let va = keys[a].1;
                if rep[va] != va {
                    continue;
                }
                let na = self.neighbours(va);
                mark[va] = va;
                for &w in na {
                    mark[w] = va;
                }
                for &(_, vb) in &keys[a + 1..j] {
                    let nb = self.neighbours(vb);
                    if rep[vb] == vb && nb.len() == na.len() && mark[vb] == va && nb.iter().all(|&w| mark[w] == va) {
                        rep[vb] = va;
                    }
                }
            }
            i = j;
        }
        // Supervariables numbered by their smallest member; members in increasing order.
        let mut id = vec![usize::MAX; n];
        let mut m = 0;
        for v in 0..n {
            if rep[v] == v {
                id[v] = m;
                m += 1;
            }
        }
        if m * 4 > n * 3 {
            return None;
        }
        let mut members = Supervariables { ptr: vec![0usize; m + 1], list: vec![0usize; n] };
        for v in 0..n {
            members.ptr[id[rep[v]] + 1] += 1;
        }
        for s in 0..m {
            members.ptr[s + 1] += members.ptr[s];
        }
        let mut fill = members.ptr.clone();
        for v in 0..n {
            let s = id[rep[v]];
            members.list[fill[s]] = v;
            fill[s] += 1;
        }
        // Quotient graph.
        let mut ptr = vec![0usize; m + 1];
        let mut adj = Vec::new();
        let mut seen = vec![usize::MAX; m];
        for sv in 0..m {
            let first = members.list[members.ptr[sv]];
            seen[sv] = sv;
            for &w in self.neighbours(first) {
                let sw = id[rep[w]];
                if seen[sw] != sv {
                    seen[sw] = sv;
                    adj.push(sw);
                }
            }
            ptr[sv + 1] = adj.len();
        }
        Some((Graph { ptr, adj }, members))
    }

    fn neighbours(&self, v: usize) -> &[usize] {
        &self.adj[self.ptr[v]..self.ptr[v + 1]]
    }
}

/// AMD ordering of the subgraph induced by `verts`; returns `verts` reordered. `local` is a
/// scratch map (all `usize::MAX` on entry and on return).
fn amd_of_subset(g: &Graph, verts: &[usize], local: &mut [usize]) -> Result<Vec<usize>, FaerError> {
    let m = verts.len();
    if m <= 2 {
        return Ok(verts.to_vec());
    }
    for (i, &v) in verts.iter().enumerate() {
        local[v] = i;
    }
    // Upper triangle (row < column) of the induced subgraph, by columns.
    let mut col_ptr = Vec::with_capacity(m + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::new();
    for &v in verts {
        let j = local[v];
        for &w in g.neighbours(v) {
            let i = local[w];
            if i < j {
                row_idx.push(i);
            }
        }
        let c0 = *col_ptr.last().expect("starts with 0");
        row_idx[c0..].sort_unstable();
        col_ptr.push(row_idx.len());
    }
    for &v in verts {
        local[v] = usize::MAX;
    }
    let a = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
    let (mut fwd, mut inv) = (vec![0usize; m], vec![0usize; m]);
    let mut mem =
        faer::dyn_stack::MemBuffer::try_new(faer::sparse::linalg::amd::order_maybe_unsorted_scratch::<usize>(m, row_idx.len()))
            .map_err(|_| FaerError::OutOfMemory)?;
    faer::sparse::linalg::amd::order_maybe_unsorted(&mut fwd, &mut inv, a, Default::default(), faer::dyn_stack::MemStack::new(&mut mem))?;
    Ok(fwd.into_iter().map(|i| verts[i]).collect())
}

/// Nested dissection of the whole graph.
fn nested_dissection(g: &Graph) -> Result<Permutation, FaerError> {
    let n = g.n();
    let d = Dissector { g, state: (0..n).map(|_| AtomicU64::new(0)).collect(), next_region: AtomicU32::new(1), next_stamp: AtomicU32::new(0) };
    let out = d.dissect((0..n).collect(), 0, &mut Scratch::new(n))?;
    debug_assert_eq!(out.len(), n);
    Ok(Permutation::from_fwd(out))
}

/// Parts with at least this many vertices have their two sides dissected in parallel (each
/// side's order depends only on its own vertices, so the result does not depend on threads).
const ND_PARALLEL_MIN: usize = 20_000;

/// The state shared by the parallel dissection of one graph.
struct Dissector<'g> {
    g: &'g Graph,
    /// Per vertex, its region (the sub-problem it belongs to: searches stay inside one) in the
    /// high 32 bits and its breadth-first search visit stamp in the low 32, in one word: one
    /// memory access per neighbour. Only the task that owns a region writes its vertices;
    /// others read them only to see that they are not theirs (region ids are never reused).
    state: Vec<AtomicU64>,
    next_region: AtomicU32,
    next_stamp: AtomicU32,
}

/// One task's buffers.
struct Scratch {
    /// Level structures of finished searches, whose buffers the next searches reuse.
    spare: Vec<Levels>,
    /// Scratch for [`amd_of_subset`].
    local: Vec<usize>,
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        Scratch { spare: Vec::new(), local: vec![usize::MAX; n] }
    }
}

/// Breadth-first level structure: vertices in visit order and the start of every level.
struct Levels {
    order: Vec<usize>,
    start: Vec<usize>,
}

impl Levels {
    fn depth(&self) -> usize {
        self.start.len() - 1
    }
    fn level(&self, k: usize) -> &[usize] {
        &self.order[self.start[k]..self.start[k + 1]]
    }
}

impl Dissector<'_> {
    fn region(&self, v: usize) -> u32 {
        (self.state[v].load(Relaxed) >> 32) as u32
    }

    fn new_region(&self, verts: &[usize]) -> u32 {
        let r = self.next_region.fetch_add(1, Relaxed);
        for &v in verts {
            self.state[v].store((r as u64) << 32, Relaxed);
        }
        r
    }

    /// Level structure from `root` inside `root`'s region.
    fn bfs(&self, root: usize, scratch: &mut Scratch) -> (Levels, u32) {
        let s = self.next_stamp.fetch_add(1, Relaxed) + 1;
        let r = self.region(root);
        let tag = ((r as u64) << 32) | s as u64;
        let Levels { mut order, mut start } = scratch.spare.pop().unwrap_or(Levels { order: Vec::new(), start: Vec::new() });
        order.clear();
        start.clear();
        order.push(root);
        start.push(0);
        self.state[root].store(tag, Relaxed);
        let mut head = 0;
        while head < order.len() {
            // Visit the whole current level, appending the next one.
            let end = order.len();
            while head < end {
                let v = order[head];
                head += 1;
                for &w in self.g.neighbours(v) {
                    let st = self.state[w].load(Relaxed);
                    if (st >> 32) as u32 == r && st != tag {
                        self.state[w].store(tag, Relaxed);
                        order.push(w);
                    }
                }
            }
            start.push(end);
        }
        (Levels { order, start }, s)
    }

    /// An elimination order of `verts` (all in one fresh region).
    fn dissect(&self, verts: Vec<usize>, depth: usize, scratch: &mut Scratch) -> Result<Vec<usize>, FaerError> {
        if verts.len() <= ND_LEAF_SIZE || depth > 64 {
            return amd_of_subset(self.g, &verts, &mut scratch.local);
        }
        self.new_region(&verts);
        // Pseudo-peripheral root: repeat the search from a narrowest vertex of the last level
        // while the depth grows.
        let (mut levels, first_stamp) = self.bfs(verts[0], scratch);
        if levels.order.len() < verts.len() {
            return self.split_components(verts, levels, first_stamp, depth, scratch);
        }
        for _ in 0..4 {
            let last = levels.level(levels.depth() - 1);
            let root = *last.iter().min_by_key(|&&v| self.g.neighbours(v).len()).expect("levels are non-empty");
            let (next, _) = self.bfs(root, scratch);
            if next.depth() <= levels.depth() {
                scratch.spare.push(next);
                break;
            }
            scratch.spare.push(std::mem::replace(&mut levels, next));
        }
        let m = levels.depth();
        if m < 3 {
            return amd_of_subset(self.g, &verts, &mut scratch.local);
        }
        // Separator level k in 1..m-1 minimising |S|·n / (|A|·|B|).
        let n = verts.len();
        let mut best = (f64::INFINITY, (m - 1) / 2);
        for k in 1..m - 1 {
            let a = levels.start[k];
            let b = n - levels.start[k + 1];
            let s = levels.start[k + 1] - levels.start[k];
            // Ratio cut: separator size over the product of the sides' fractions.
            let cost = s as f64 * n as f64 / (a as f64 * b as f64);
            if cost < best.0 {
                best = (cost, k);
            }
        }
        let k = best.1;
        let mut part_a: Vec<usize> = levels.order[..levels.start[k]].to_vec();
        let part_b: Vec<usize> = levels.order[levels.start[k + 1]..].to_vec();
        // Thin the separator: a level-k vertex with no neighbour in B separates nothing.
        let rb = self.new_region(&part_b);
        let mut sep = Vec::new();
        for &v in levels.level(k) {
            if self.g.neighbours(v).iter().any(|&w| self.region(w) == rb) {
                sep.push(v);
            } else {
                part_a.push(v);
            }
        }
        scratch.spare.push(levels);
        let (a, b) = if n >= ND_PARALLEL_MIN {
            rayon::join(|| self.dissect(part_a, depth + 1, scratch), || self.dissect(part_b, depth + 1, &mut Scratch::new(self.g.n())))
        } else {
            (self.dissect(part_a, depth + 1, scratch), self.dissect(part_b, depth + 1, scratch))
        };
        let mut out = a?;
        out.extend(b?);
        out.extend(sep);
        Ok(out)
    }

    /// `verts` is disconnected: order each connected component on its own.
    fn split_components(&self, verts: Vec<usize>, first: Levels, first_stamp: u32, depth: usize, scratch: &mut Scratch) -> Result<Vec<usize>, FaerError> {
        // Vertices reached by the first search carry its stamp, those of later searches
        // larger ones; unreached vertices the region's fresh 0.
        let mut components = vec![first.order];
        for &v in &verts {
            if ((self.state[v].load(Relaxed) & 0xFFFF_FFFF) as u32) < first_stamp {
                let comp = self.bfs(v, scratch).0.order;
                components.push(comp);
            }
        }
        let mut out = Vec::with_capacity(verts.len());
        for comp in components {
            out.extend(self.dissect(comp, depth + 1, scratch)?);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pattern (lower triangle with diagonal) of the 5-point Laplacian on a `k × k` grid.
    fn grid(k: usize) -> (usize, Vec<usize>, Vec<usize>) {
        let n = k * k;
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for j in 0..k {
            for i in 0..k {
                let v = j * k + i;
                row_idx.push(v);
                if i + 1 < k {
                    row_idx.push(v + 1);
                }
                if j + 1 < k {
                    row_idx.push(v + k);
                }
                col_ptr.push(row_idx.len());
            }
        }
        (n, col_ptr, row_idx)
    }

    /// The lower-triangle pattern with every vertex expanded to a 2×2 block over interleaved
    /// unknowns (u, v of one vertex).
    fn two_by_two(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> (Vec<usize>, Vec<usize>) {
        let (mut bp, mut br) = (vec![0usize], Vec::new());
        for c in 0..n {
            for bc in 0..2 {
                for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                    for b in 0..2 {
                        if 2 * r + b >= 2 * c + bc {
                            br.push(2 * r + b);
                        }
                    }
                }
                bp.push(br.len());
            }
        }
        (bp, br)
    }

    /// Number of nonzeros of the Cholesky factor of the permuted pattern (symbolic).
    fn nnz_l(n: usize, col_ptr: &[usize], row_idx: &[usize], p: &Permutation) -> usize {
        let a = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let perm = faer::perm::PermRef::new_checked(&p.fwd, &p.inv, n);
        let s = faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(
            a,
            faer::Side::Lower,
            faer::sparse::linalg::cholesky::SymmetricOrdering::Custom(perm),
            Default::default(),
        )
        .unwrap();
        s.len_val()
    }

    fn assert_permutation(p: &Permutation, n: usize) {
        assert_eq!(p.fwd.len(), n);
        let mut seen = vec![false; n];
        for (new, &old) in p.fwd.iter().enumerate() {
            assert!(!seen[old], "{old} twice");
            seen[old] = true;
            assert_eq!(p.inv[old], new);
        }
    }

    #[test]
    fn every_ordering_is_a_permutation_also_of_disconnected_graphs() {
        let (n, mut col_ptr, mut row_idx) = grid(40);
        // Append 300 isolated vertices and 50 disjoint edges.
        let mut m = n;
        for e in 0..350 {
            row_idx.push(m);
            if e >= 300 && e % 2 == 0 {
                row_idx.push(m + 1);
            }
            col_ptr.push(row_idx.len());
            m += 1;
        }
        for kind in [OrderingKind::Amd, OrderingKind::NestedDissection, OrderingKind::Auto] {
            let p = fill_reducing(kind, m, &col_ptr, &row_idx).unwrap();
            assert_permutation(&p, m);
        }
        for n in [0, 1, 2, 3] {
            let (col_ptr, row_idx): (Vec<usize>, Vec<usize>) = ((0..=n).collect(), (0..n).collect());
            let p = fill_reducing(OrderingKind::NestedDissection, n, &col_ptr, &row_idx).unwrap();
            assert_permutation(&p, n);
        }
    }

    /// Large parts are dissected in parallel: the order is the same on one thread as on
    /// several, also with disconnected pieces (a grid beside a cut-up copy).
    #[test]
    fn nested_dissection_does_not_depend_on_threads() {
        let k = 160;
        let (n, mut col_ptr, mut row_idx) = grid(k);
        assert!(n >= ND_PARALLEL_MIN, "parallel dissection is exercised");
        // A second grid whose columns 40 and 41 are not joined (two components).
        for j in 0..k {
            for i in 0..k {
                let v = n + j * k + i;
                row_idx.push(v);
                if i + 1 < k && i != 40 {
                    row_idx.push(v + 1);
                }
                if j + 1 < k {
                    row_idx.push(v + k);
                }
                col_ptr.push(row_idx.len());
            }
        }
        let m = 2 * n;
        let order = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| fill_reducing(OrderingKind::NestedDissection, m, &col_ptr, &row_idx).unwrap())
        };
        let one = order(1);
        assert_permutation(&one, m);
        for threads in [2, 4] {
            assert_eq!(order(threads).fwd, one.fwd, "{threads} threads");
        }
    }

    #[test]
    fn nested_dissection_of_a_grid_has_n_log_n_fill_and_beats_the_natural_order() {
        // Natural (banded) order of a k × k grid fills ~k³; nested dissection O(k² log k).
        let k = 120;
        let (n, col_ptr, row_idx) = grid(k);
        let nd = fill_reducing(OrderingKind::NestedDissection, n, &col_ptr, &row_idx).unwrap();
        assert_permutation(&nd, n);
        let natural = Permutation::from_fwd((0..n).collect());
        let amd = fill_reducing(OrderingKind::Amd, n, &col_ptr, &row_idx).unwrap();
        let (f_nd, f_nat, f_amd) =
            (nnz_l(n, &col_ptr, &row_idx, &nd), nnz_l(n, &col_ptr, &row_idx, &natural), nnz_l(n, &col_ptr, &row_idx, &amd));
        assert!(f_nd * 2 < f_nat, "nd {f_nd} natural {f_nat}");
        // Within a small factor of AMD, and below c · n log2 n.
        assert!((f_nd as f64) < 1.5 * f_amd as f64, "nd {f_nd} amd {f_amd}");
        assert!((f_nd as f64) < 4.0 * n as f64 * (n as f64).log2(), "nd {f_nd}");
    }

    #[test]
    fn two_by_two_blocks_are_dissected_as_one_supervariable_per_vertex() {
        // Expand the grid pattern to 2×2 blocks (u, v of one vertex): the two unknowns of a
        // vertex have equal closed neighbourhoods and stay next to each other in the order.
        let k = 60;
        let (n, col_ptr, row_idx) = grid(k);
        let (bp, br) = two_by_two(n, &col_ptr, &row_idx);
        let m = 2 * n;
        let nd = fill_reducing(OrderingKind::NestedDissection, m, &bp, &br).unwrap();
        assert_permutation(&nd, m);
        for pair in nd.fwd.chunks(2) {
            assert_eq!(pair[0] / 2, pair[1] / 2, "{pair:?}");
        }
        let amd = fill_reducing(OrderingKind::Amd, m, &bp, &br).unwrap();
        let (f_nd, f_amd) = (nnz_l(m, &bp, &br, &nd), nnz_l(m, &bp, &br, &amd));
        assert!((f_nd as f64) < 1.5 * f_amd as f64, "nd {f_nd} amd {f_amd}");
    }

    /// Block systems from [`SUPERNODAL_BLOCKS_FROM`] unknowns get the supernodal factorization
    /// (faer alone keeps this one simplicial), smaller ones and scalar systems faer's choice.
    #[test]
    fn block_systems_are_factored_supernodally() {
        use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholeskyRaw, SymmetricOrdering};
        let simplicial_by_faer = |n: usize, col_ptr: &[usize], row_idx: &[usize], p: &Permutation, params| {
            let a = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
            let perm = faer::perm::PermRef::new_checked(&p.fwd, &p.inv, n);
            let sym = factorize_symbolic_cholesky(a, faer::Side::Lower, SymmetricOrdering::Custom(perm), params).unwrap();
            matches!(sym.raw(), SymbolicCholeskyRaw::Simplicial(_))
        };
        for k in [8, 30] {
            let (n, col_ptr, row_idx) = grid(k);
            let (bp, br) = two_by_two(n, &col_ptr, &row_idx);
            let m = 2 * n;
            let blocks = fill_reducing(OrderingKind::Amd, m, &bp, &br).unwrap();
            assert!(blocks.blocks, "{k}: 2×2 blocks not recognised");
            let faer_alone = simplicial_by_faer(m, &bp, &br, &blocks, Default::default());
            let ours = simplicial_by_faer(m, &bp, &br, &blocks, symbolic_params(&blocks));
            assert_eq!(ours, m < SUPERNODAL_BLOCKS_FROM, "{k}: {m} unknowns");
            if m >= SUPERNODAL_BLOCKS_FROM {
                assert!(faer_alone, "{k}: faer alone already picks supernodal; the test shows nothing");
            }
            let scalar = fill_reducing(OrderingKind::Amd, n, &col_ptr, &row_idx).unwrap();
            assert!(!scalar.blocks);
            assert_eq!(
                simplicial_by_faer(n, &col_ptr, &row_idx, &scalar, symbolic_params(&scalar)),
                simplicial_by_faer(n, &col_ptr, &row_idx, &scalar, Default::default())
            );
        }
    }

    #[test]
    fn amd_orders_interleaved_two_by_two_blocks_by_their_vertex_graph() {
        // The same 2×2 expansion of a grid: recognised, ordered as the vertex graph (the u, v
        // of a vertex adjacent), as little fill as AMD on every unknown; and refused when a
        // vertex loses one unknown (a pin on u only) or a block its u-v coupling.
        let k = 30;
        let (n, col_ptr, row_idx) = grid(k);
        let (bp, br) = two_by_two(n, &col_ptr, &row_idx);
        let m = 2 * n;
        let (qp, qi) = interleaved_blocks(m, &bp, &br).expect("a 2×2-block pattern");
        // the block graph is the vertex graph (off the diagonal, which AMD ignores)
        let (mut gp, mut gi) = (vec![0usize], Vec::new());
        for c in 0..n {
            gi.extend(row_idx[col_ptr[c]..col_ptr[c + 1]].iter().copied().filter(|&r| r != c));
            gp.push(gi.len());
        }
        assert!(qp == gp && qi == gi, "the block graph is not the vertex graph");
        let blocks = fill_reducing(OrderingKind::Amd, m, &bp, &br).unwrap();
        assert_permutation(&blocks, m);
        for pair in blocks.fwd.chunks(2) {
            assert_eq!((pair[0] % 2, pair[1]), (0, pair[0] + 1), "{pair:?}");
        }
        let plain = amd(m, &bp, &br).unwrap();
        let (f_blocks, f_plain) = (nnz_l(m, &bp, &br, &blocks), nnz_l(m, &bp, &br, &plain));
        assert!((f_blocks as f64) <= 1.02 * f_plain as f64, "blocks {f_blocks} plain {f_plain}");
        // drop unknown 0 (u of vertex 0): odd size and shifted pairs
        let (mut dp, mut dr) = (vec![0usize], Vec::new());
        for c in 1..m {
            dr.extend(br[bp[c]..bp[c + 1]].iter().map(|&r| r - 1));
            dp.push(dr.len());
        }
        assert!(interleaved_blocks(m - 1, &dp, &dr).is_none());
        // drop the u-v coupling of vertex 3 (row 7 of column 6)
        let (mut cp, mut cr) = (vec![0usize], Vec::new());
        for c in 0..m {
            cr.extend(br[bp[c]..bp[c + 1]].iter().copied().filter(|&r| !(c == 6 && r == 7)));
            cp.push(cr.len());
        }
        assert!(interleaved_blocks(m, &cp, &cr).is_none());
        assert_permutation(&fill_reducing(OrderingKind::Amd, m, &cp, &cr).unwrap(), m);
    }

    #[test]
    fn supervariables_are_exactly_the_vertices_with_equal_closed_neighbourhoods() {
        // Expand every vertex of a grid into 1, 2 or 3 copies (a pseudo-random count): the
        // copies are adjacent to each other and to every copy of the vertex's neighbours, so
        // they, and only they, have equal closed neighbourhoods.
        let k = 30;
        let (n, col_ptr, row_idx) = grid(k);
        let copies: Vec<usize> = (0..n).map(|v| 1 + (v * 7919 + v / 13) % 3).collect();
        let mut first = vec![0usize; n + 1];
        for v in 0..n {
            first[v + 1] = first[v] + copies[v];
        }
        let m = first[n];
        let mut edges = Vec::new();
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                for a in first[c]..first[c + 1] {
                    for b in first[r]..first[r + 1] {
                        if a != b {
                            edges.push((a.max(b), a.min(b)));
                        }
                    }
                }
            }
        }
        edges.sort_unstable_by_key(|&(r, c)| (c, r));
        let (mut cp, mut ri) = (vec![0usize; m + 1], Vec::new());
        for &(r, c) in &edges {
            cp[c + 1] += 1;
            ri.push(r);
        }
        for c in 0..m {
            cp[c + 1] += cp[c];
        }
        let g = Graph::from_pattern(m, &cp, &ri);
        let (quotient, members) = g.compress().expect("about two copies per vertex");
        assert_eq!(quotient.n(), n);
        for v in 0..n {
            let group = &members.list[members.ptr[v]..members.ptr[v + 1]];
            assert_eq!(group, (first[v]..first[v + 1]).collect::<Vec<_>>().as_slice(), "vertex {v}");
        }
        // The quotient of the expanded grid is the grid itself.
        let grid_graph = Graph::from_pattern(n, &col_ptr, &row_idx);
        for v in 0..n {
            let mut a = quotient.neighbours(v).to_vec();
            let mut b = grid_graph.neighbours(v).to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b, "vertex {v}");
        }
        // A graph without twins is not compressed.
        assert!(grid_graph.compress().is_none());
    }

    /// A shared vertex order gives every free unknown once, in its vertex's place (both
    /// unknowns of a vertex together, fixed ones skipped), and is declined where it does not
    /// fit: a size that is not one or two unknowns per vertex, an order that repeats or misses
    /// a vertex, and a system large enough for nested dissection.
    #[test]
    fn vertex_orders_expand_to_the_free_unknowns_or_are_declined() {
        let order = [2u32, 0, 3, 1];
        let shared = Ordering::Vertices { order: &order, kind: OrderingKind::Auto };
        // Two unknowns per vertex; vertex 3's unknowns fixed: free numbering 0..6.
        let mut free_pos = vec![u32::MAX; 8];
        let mut k = 0;
        for u in 0..8 {
            if u / 2 != 3 {
                free_pos[u] = k;
                k += 1;
            }
        }
        let p = shared.of_vertices(8, &free_pos, 6).expect("applies");
        assert_eq!(p.fwd, vec![4, 5, 0, 1, 2, 3]);
        assert!(p.blocks);
        for (new, &old) in p.fwd.iter().enumerate() {
            assert_eq!(p.inv[old], new);
        }
        // One unknown per vertex, none fixed.
        let ident: Vec<u32> = (0..4).collect();
        let p = shared.of_vertices(4, &ident, 4).expect("applies");
        assert_eq!(p.fwd, vec![2, 0, 3, 1]);
        assert!(!p.blocks);
        // Declined.
        assert!(shared.of_vertices(12, &[0; 12], 12).is_none(), "three unknowns per vertex");
        let repeated = [2u32, 0, 2, 1];
        assert!(Ordering::Vertices { order: &repeated, kind: OrderingKind::Auto }.of_vertices(4, &ident, 4).is_none());
        let big: Vec<u32> = (0..ND_MIN_SIZE as u32).collect();
        let pos: Vec<u32> = (0..ND_MIN_SIZE as u32).collect();
        assert!(Ordering::Vertices { order: &big, kind: OrderingKind::Auto }.of_vertices(ND_MIN_SIZE, &pos, ND_MIN_SIZE).is_none());
        assert!(Ordering::Vertices { order: &big, kind: OrderingKind::Amd }.of_vertices(ND_MIN_SIZE, &pos, ND_MIN_SIZE).is_some());
        assert!(Ordering::from(OrderingKind::Amd).of_vertices(4, &ident, 4).is_none());
    }

    /// The vertex order of a triangulated grid is a permutation whose fill is close to AMD's
    /// on the same graph given as a matrix pattern (the orders differ only in tie-breaking);
    /// from `ND_MIN_SIZE` vertices on it is a nested dissection (the same on one thread and
    /// two, with a fill close to AMD's on this regular graph).
    #[test]
    fn the_vertex_order_of_a_mesh_is_an_amd_order_of_its_graph() {
        for k in [30usize, 201] {
            let n = k * k;
            assert_eq!(vertex_order_is_nested(n), k == 201);
            the_vertex_order_of_a_grid_is_a_good_order(k);
        }
    }

    fn the_vertex_order_of_a_grid_is_a_good_order(k: usize) {
        let id = |i: usize, j: usize| (j * k + i) as u32;
        let mut tris = Vec::new();
        for j in 0..k - 1 {
            for i in 0..k - 1 {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let n = k * k;
        let order = vertex_order(n, &tris);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let one_thread = pool.install(|| vertex_order(n, &tris));
        assert_eq!(order, one_thread, "the order depends on the threads");
        let mut seen = vec![false; n];
        for &v in &order {
            assert!(!std::mem::replace(&mut seen[v as usize], true), "vertex {v} twice");
        }
        assert!(seen.iter().all(|&s| s));
        // Lower pattern of the triangle graph, for the symbolic factorization.
        let mut edges: Vec<(usize, usize)> = tris.iter().flat_map(|t| (0..3).map(move |a| (t[a].max(t[(a + 1) % 3]) as usize, t[a].min(t[(a + 1) % 3]) as usize))).collect();
        edges.extend((0..n).map(|v| (v, v)));
        edges.sort_unstable_by_key(|&(r, c)| (c, r));
        edges.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(_, c) in &edges {
            col_ptr[c + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = edges.iter().map(|e| e.0).collect();
        let a = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let fill = |fwd: Vec<usize>| {
            let p = Permutation::from_fwd(fwd);
            let perm = faer::perm::PermRef::new_checked(&p.fwd, &p.inv, n);
            faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(a, faer::Side::Lower, faer::sparse::linalg::cholesky::SymmetricOrdering::Custom(perm), Default::default()).unwrap().len_val()
        };
        let shared = fill(order.iter().map(|&v| v as usize).collect());
        let own = fill(fill_reducing(OrderingKind::Amd, n, &col_ptr, &row_idx).unwrap().fwd);
        let natural = fill((0..n).collect());
        let bound = if vertex_order_is_nested(n) { 1.25 } else { 1.1 };
        assert!((shared as f64) < bound * own as f64, "{k}×{k}: shared {shared}, own {own}");
        assert!(shared < natural, "{k}×{k}: shared {shared}, natural {natural}");
    }
}
