//! A coarse proxy of a large chart's scale system: the prediction rounds of
//! [`crate::pipeline::predict`] (cone placement, and the flattening predicted after each cut)
//! on a chart of about [`PROXY_VERTICES`] vertices instead of the chart's own.
//!
//! Precedent: the coarse level of a multigrid (Hoppe 1996, progressive meshes; Garland &
//! Heckbert 1997 for edge collapses): the conformal scale factor `u` solves a Poisson equation
//! whose source, the angle defect, is topological in total (Gauss–Bonnet), so a coarse mesh of
//! the same surface and topology carries the same curvature, gathered on fewer vertices, and
//! its `u` is the chart's at a coarser resolution.
//!
//! Decimation by half-edge collapses: the removed vertex joins a neighbour, which keeps its
//! position, so every vertex of the proxy is a vertex of the chart (a cone placed on the proxy
//! is a cone of the chart, no projection). In passes, like the levels of a multigrid: each
//! pass takes the shorter half of the edges in triangle order (neighbours in memory; in order
//! of length the collapses would jump across the chart, a cache miss each), and a vertex that
//! took another in does not take a second in the same pass, so the chart coarsens evenly and
//! the proxy's triangles stay about even in size. A collapse is refused when:
//! * the removed vertex is on the chart's boundary (the outline, where `u = 0`, stays exact);
//! * it breaks the link condition (the two ends share a neighbour other than the two opposite
//!   vertices of the edge): the topology, genus and boundary loops are kept;
//! * a triangle it moves turns by more than 60° or keeps less than 2% of its area;
//! * the survivor would be left with fewer than 3 triangles.
//!
//! Each vertex of the chart is represented by the proxy vertex it was collapsed into
//! ([`Proxy::rep`]); a value on the proxy is read back on the chart through it (piecewise
//! constant over each vertex's region). The proxy's scale factor is a little smoother than the
//! chart's, so its prediction reads a little optimistic (at most 0.016 less area outside the
//! bound and a mean area distortion 0.002–0.03 lower near the limits, on four scans;
//! [`crate::pipeline::predict::PROXY_MARGIN`]).
//!
//! Preconditions: a chart without defects. Failures: `None` when the chart is small (below
//! [`PROXY_FROM`] triangles: its own system is cheap) or the proxy's system fails.
//! Deterministic: passes in triangle order, the median by length then vertex ids.

use super::cones::ScaleSolver;
use crate::charts::Chart;
use crate::geometry::{cross, dot, norm, sub};

/// Charts of at least this many triangles plan their cones on a proxy (below it, a
/// prediction round on the chart's own system costs a fraction of a second).
pub const PROXY_FROM: usize = 200_000;

/// Closed charts and charts of one outline plan on a proxy of a third of their vertices from
/// this many triangles: a closed scan of 111k–144k triangles, planned in 16 rounds over the
/// chart and its halves, spent most of its time there (`docs/performance.md`). Charts with
/// many holes keep [`PROXY_FROM`]: on a scan of 141k triangles with 100 holes the smaller
/// proxy read its plans too optimistic, and the repair took 72 rounds instead of 5.
pub const CLOSED_PROXY_FROM: usize = 100_000;

/// Whether `chart` plans on a proxy ([`Proxy::new`]).
pub fn wants_proxy(chart: &Chart) -> bool {
    let n = chart.triangles.len();
    chart.defect.is_none() && (n >= PROXY_FROM || (n >= CLOSED_PROXY_FROM && chart.boundary_loops.len() <= 1))
}

/// Vertices of the proxy (about twice as many triangles): its factorization costs about a
/// tenth of the chart's at 576k triangles, and its regions are a few edges wide on a scan of
/// a million triangles.
pub const PROXY_VERTICES: usize = 50_000;

/// Smallest cosine between a moved triangle's normal and its normal before the collapse (60°).
const MIN_TURN_COS: f64 = 0.5;

/// Smallest area a moved triangle keeps, as a share of its area before the collapse.
const MIN_AREA_SHARE: f64 = 0.02;

/// A coarse proxy of a chart (see the module docs).
pub struct Proxy {
    /// The proxy as a chart (positions, triangles, boundary loops, genus and kind; no input
    /// faces: it is only solved on, [`Chart::proxy`]).
    pub chart: Chart,
    /// Chart vertex of every proxy vertex.
    pub fine_of: Vec<u32>,
    /// Proxy vertex representing every chart vertex.
    pub rep: Vec<u32>,
    /// The proxy's scale system.
    pub solver: ScaleSolver,
}

impl Proxy {
    /// The proxy of `chart` when it has at least [`PROXY_FROM`] triangles, or
    /// [`CLOSED_PROXY_FROM`] with at most one outline ([`wants_proxy`]; see the module docs):
    /// about [`PROXY_VERTICES`] vertices, a third of the chart's below [`PROXY_FROM`], more
    /// where collapses are refused.
    pub fn new(chart: &Chart) -> Option<Proxy> {
        if !wants_proxy(chart) {
            return None;
        }
        let target = if chart.triangles.len() >= PROXY_FROM { PROXY_VERTICES } else { chart.positions.len() / 3 };
        Self::with_target(chart, target.min(PROXY_VERTICES))
    }

    /// [`Self::new`] at any size, down to about `target` vertices.
    pub fn with_target(chart: &Chart, target: usize) -> Option<Proxy> {
        let (triangles, into) = decimate(chart, target);
        let n = chart.positions.len();
        // Proxy ids of the surviving vertices, in chart order.
        let mut coarse = vec![u32::MAX; n];
        let mut fine_of = Vec::new();
        for v in 0..n {
            if into[v] == v as u32 {
                coarse[v] = fine_of.len() as u32;
                fine_of.push(v as u32);
            }
        }
        let rep: Vec<u32> = (0..n).map(|v| coarse[root(&into, v as u32) as usize]).collect();
        let triangles: Vec<[u32; 3]> =
            triangles.iter().map(|t| [coarse[t[0] as usize], coarse[t[1] as usize], coarse[t[2] as usize]]).collect();
        let boundary_loops: Vec<Vec<u32>> =
            chart.boundary_loops.iter().map(|l| l.iter().map(|&v| coarse[v as usize]).collect()).collect();
        let proxy = Chart::proxy(
            fine_of.iter().map(|&v| chart.positions[v as usize]).collect(),
            triangles,
            fine_of.iter().map(|&v| chart.mesh_vertex[v as usize]).collect(),
            boundary_loops,
            chart.genus,
            chart.kind,
        );
        let solver = ScaleSolver::new(&proxy)?;
        Some(Proxy { chart: proxy, fine_of, rep, solver })
    }

    /// `u` on the proxy read back on the chart ([`Proxy::rep`]), with `held` chart vertices
    /// (and the boundary, which the proxy keeps) at zero.
    pub fn to_chart(&self, u: &[f64], held: &[u32]) -> Vec<f64> {
        let mut out: Vec<f64> = self.rep.iter().map(|&c| u[c as usize]).collect();
        for &v in held {
            out[v as usize] = 0.0;
        }
        out
    }
}

/// The proxy vertex `v` was collapsed into, following the collapses.
fn root(into: &[u32], mut v: u32) -> u32 {
    while into[v as usize] != v {
        v = into[v as usize];
    }
    v
}

/// Collapse `chart`'s edges until about `target` vertices remain (see the module docs).
/// Returns the surviving triangles (over chart vertex ids) and, per chart vertex, the vertex
/// it was collapsed into (itself if it survives).
fn decimate(chart: &Chart, target: usize) -> (Vec<[u32; 3]>, Vec<u32>) {
    let n = chart.positions.len();
    let p = &chart.positions;
    let boundary = chart.boundary_mask();
    let mut mesh = Collapses::new(chart);
    let length = |a: u32, b: u32| norm(sub(p[a as usize], p[b as usize]));
    let mut into: Vec<u32> = (0..n as u32).collect();
    let mut remaining = n;
    // Passes (see the module docs): a vertex that took another in does not take a second in
    // the same pass. Lengths order like their bits (they are not negative), then ids.
    let mut edges: Vec<(u64, u32, u32)> = Vec::new();
    let mut took = vec![false; n];
    while remaining > target {
        edges.clear();
        for (tri, _) in mesh.tris.iter().zip(&mesh.alive).filter(|(_, &a)| a) {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                // Every edge with an end inside the chart is on two triangles: once each way.
                if a < b && !(boundary[a as usize] && boundary[b as usize]) {
                    edges.push((length(a, b).to_bits(), a, b));
                }
            }
        }
        if edges.is_empty() {
            break;
        }
        // The shorter half of the edges, in triangle order.
        let mid = edges.len() / 2;
        let cut_off = *edges.clone().select_nth_unstable(mid).1;
        edges.retain(|e| *e <= cut_off);
        took.iter_mut().for_each(|t| *t = false);
        let before = remaining;
        for &(_, a, b) in &edges {
            if remaining <= target {
                break;
            }
            if into[a as usize] != a || into[b as usize] != b || took[a as usize] || took[b as usize] {
                continue;
            }
            // Remove an end inside the chart; the other way if the first is refused.
            for (u, v) in [(a, b), (b, a)] {
                if !boundary[u as usize] && mesh.collapse(u, v) {
                    into[u as usize] = v;
                    took[v as usize] = true;
                    remaining -= 1;
                    break;
                }
            }
        }
        if remaining == before {
            break;
        }
    }
    let out: Vec<[u32; 3]> = mesh.tris.iter().zip(&mesh.alive).filter(|(_, &a)| a).map(|(t, _)| *t).collect();
    (out, into)
}

/// The triangles of a chart under collapses.
struct Collapses<'a> {
    chart: &'a Chart,
    /// Every triangle of the chart, its corners moved by the collapses.
    tris: Vec<[u32; 3]>,
    /// Whether each triangle is still there (a collapse removes the two on its edge).
    alive: Vec<bool>,
    /// Triangles around each vertex (some may be dead: pruned when the vertex is touched).
    around: Vec<Vec<u32>>,
    /// Scratch: the neighbours of the two ends of an edge.
    ring_u: Vec<u32>,
    ring_v: Vec<u32>,
}

impl<'a> Collapses<'a> {
    fn new(chart: &'a Chart) -> Self {
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); chart.positions.len()];
        for (t, tri) in chart.triangles.iter().enumerate() {
            for &v in tri {
                around[v as usize].push(t as u32);
            }
        }
        let tris = chart.triangles.clone();
        let alive = vec![true; tris.len()];
        Collapses { chart, tris, alive, around, ring_u: Vec::new(), ring_v: Vec::new() }
    }

    /// The neighbours of `x` into `out`.
    fn ring(&self, x: u32, out: &mut Vec<u32>) {
        out.clear();
        for &t in &self.around[x as usize] {
            for &w in &self.tris[t as usize] {
                if w != x && !out.contains(&w) {
                    out.push(w);
                }
            }
        }
    }

    /// The (unnormalised) normal of `t` with corners at the chart's positions.
    fn normal(&self, t: [u32; 3]) -> [f64; 3] {
        let p = &self.chart.positions;
        let a = p[t[0] as usize];
        cross(sub(p[t[1] as usize], a), sub(p[t[2] as usize], a))
    }

    /// Collapse `u` (inside the chart) into `v` when allowed (see the module docs).
    fn collapse(&mut self, u: u32, v: u32) -> bool {
        let alive = &self.alive;
        self.around[u as usize].retain(|&t| alive[t as usize]);
        self.around[v as usize].retain(|&t| alive[t as usize]);
        let (mut ring_u, mut ring_v) = (std::mem::take(&mut self.ring_u), std::mem::take(&mut self.ring_v));
        self.ring(u, &mut ring_u);
        self.ring(v, &mut ring_v);
        let allowed = self.allowed(u, v, &ring_u, &ring_v);
        (self.ring_u, self.ring_v) = (ring_u, ring_v);
        if !allowed {
            return false;
        }
        for t in std::mem::take(&mut self.around[u as usize]) {
            let tri = &mut self.tris[t as usize];
            if tri.contains(&v) {
                self.alive[t as usize] = false;
            } else {
                for w in tri.iter_mut().filter(|w| **w == u) {
                    *w = v;
                }
                self.around[v as usize].push(t);
            }
        }
        true
    }

    /// Whether `u` may collapse into `v` (`ring_u`, `ring_v`: their neighbours).
    fn allowed(&self, u: u32, v: u32, ring_u: &[u32], ring_v: &[u32]) -> bool {
        // The triangles on the edge (two: `u` is inside the chart), and their opposite vertices.
        let mut opposite = [u32::MAX; 2];
        let mut shared = 0;
        for &t in &self.around[u as usize] {
            let tri = self.tris[t as usize];
            if tri.contains(&v) {
                if shared == 2 {
                    return false;
                }
                opposite[shared] = tri.iter().copied().find(|&w| w != u && w != v).unwrap_or(u);
                shared += 1;
            }
        }
        // Link condition: the only common neighbours are the edge's opposite vertices.
        let common = ring_u.iter().filter(|w| ring_v.contains(w)).count();
        if shared != 2 || common != 2 || opposite[0] == opposite[1] {
            return false;
        }
        // At least 3 triangles left around the survivor.
        if self.around[u as usize].len() + self.around[v as usize].len() < 2 * shared + 3 {
            return false;
        }
        // Every moved triangle keeps its area and turns by at most 60° (measured against its
        // shape before this collapse: against the chart's original triangle, the refusals
        // left a proxy on which a 363k-triangle disk was planned worse).
        self.around[u as usize].iter().all(|&t| {
            let now = self.tris[t as usize];
            if now.contains(&v) {
                return true;
            }
            let was = self.normal(now);
            let new = self.normal(now.map(|w| if w == u { v } else { w }));
            let (lw, ln) = (norm(was), norm(new));
            ln > MIN_AREA_SHARE * lw && dot(was, new) > MIN_TURN_COS * lw * ln
        })
    }
}
