//! `scaffold`: globally bijective maps — no flipped triangle and no boundary self-overlap —
//! by minimising symmetric Dirichlet on the chart plus a scaffold mesh of the free space.
//!
//! Paper: Z. Jiang, S. Schaefer, D. Panozzo, "Simplicial complex augmentation framework for
//! bijective maps", ACM TOG 36(6) (SIGGRAPH Asia), 2017 (SCAF).
//!
//! Every iteration:
//! 1. *Scaffold.* A box around the chart's current UVs (its bounding box grown by
//!    [`BOX_MARGIN`], with points along its sides) and the chart's boundary vertices (all
//!    loops) are triangulated by a constrained Delaunay triangulation (`spade`, bulk loaded)
//!    with the boundary edges as constraints. Triangles inside the chart are dropped; the
//!    rest — between the chart and the box, and inside the holes — is the scaffold. Chart ∪
//!    scaffold is a triangulated square whose boundary (the box) is fixed.
//! 2. *Energy.* Symmetric Dirichlet D(J) = ‖J‖² + ‖J⁻¹‖² on the chart triangles (3D rest
//!    shapes, weighted by 3D area) plus, on every scaffold triangle, D relative to its shape at
//!    the start of the iteration, all scaffold triangles sharing the total weight
//!    [`SCAFFOLD_WEIGHT`] × chart area. D is a barrier: +∞ as any triangle degenerates.
//! 3. *Step.* One SLIM global step (Rabinovich et al. 2017: reweighted proxy
//!    Σ w ‖W (J − R)‖², W from the singular values, R the closest rotation; the local step is
//!    [`super::slim`]'s) on the whole square with the box fixed, then the flip-free line search
//!    over chart *and* scaffold triangles.
//!
//! Linear algebra: the unknowns are the chart's (u, v), interleaved; the box is fixed and goes
//! to the right-hand side. The matrix is the chart's SLIM matrix (same pattern every iteration)
//! plus the scaffold's entries, which between chart vertices are only *chords* (scaffold edges
//! joining two boundary vertices that are not chart edges). One sparse Cholesky symbolic
//! analysis (AMD ordering) is kept while its pattern covers the scaffold's chords — the entries
//! of chords the current scaffold lacks are zero, so the factorisation is exactly that of the
//! current matrix — and each iteration costs one numeric factorisation and one solve, like
//! SLIM's. When a scaffold brings a new chord the analysis is redone for the union of old and
//! new chords.
//!
//! Re-meshing: the paper re-meshes the scaffold every iteration. Here a fresh Delaunay
//! scaffold is taken when it needs no new symbolic analysis, when the previous scaffold
//! limited the last step (its first degenerating triangle bounded the line search below a full
//! step), when the previous one is `STALE_AFTER` (10) iterations old, or on the first
//! iteration; otherwise the previous iteration's scaffold is kept. The
//! kept scaffold is a valid triangulation of the free space (the line search kept its triangles
//! positive and the box is fixed) and its rest shapes are reset to the current ones, so every
//! iteration minimises the same energy — chart symmetric Dirichlet plus scaffold symmetric
//! Dirichlet at its minimum — over a valid scaffold, only not always a Delaunay one. Kept
//! scaffolds get skinnier as the boundary moves, which can only hold the boundary back; that
//! is what the re-mesh triggers undo (on a wavy cone whose isometric flattening overlaps
//! itself, 100 iterations re-meshing at most every 10 end at the energy of re-meshing every
//! iteration to 1e-5, without the age trigger 9 % further from the isometry). (On a 22k-triangle chart with a 56-vertex boundary every
//! Delaunay scaffold has the same chords anyway; on a chart with a 1136-vertex boundary nearly
//! every re-mesh flips a few chords, and keeping the scaffold saves an analysis per
//! iteration.)
//!
//! Start: the valid map with the lower energy among LSCM and the mean value map on a circle
//! (Floater 2003; an embedding by Tutte's theorem), each scaled by the energy-optimal factor.
//! Valid: every triangle positive, no boundary self-overlap, and a scaffold can be built.
//!
//! Quads: the chart energy and the line search also cover the other diagonal's two triangles
//! of every quad ([`super::barrier_triangles`]), so quads stay strictly convex.
//!
//! Guarantee: all chart and scaffold triangles stay positively oriented and the box boundary is
//! fixed, so chart ∪ scaffold stays an embedded triangulation of the box (a locally injective
//! map of a disk onto a convex polygon's interior with the boundary fixed is injective):
//! no chart triangle flips and the chart boundary cannot cross itself or a hole.
//!
//! Monotonicity: the scaffold energy is at its minimum (J = I) at the start of every
//! iteration, and the line search lowers chart + scaffold energy, so the chart's own symmetric
//! Dirichlet energy strictly decreases every iteration ([`solve_with_history`] returns it).
//!
//! Pins: the energy does not see them; the finished map is moved onto the pins by the
//! least-squares similarity (which scales it; exact for one or two pins) and the report says
//! so.
//!
//! Failures: a chart that is not a disk ([`super::require_disk`]). When neither start is valid
//! (degenerate charts in floating point), the mean value map is returned marked as a fallback.
//! When a fresh scaffold cannot be built (a boundary vertex collinear with a boundary edge to
//! round-off, so the triangulation would split the constraint) the previous scaffold is kept;
//! when there is none, the iterations stop and the last map — valid by the guarantee — is
//! returned with a note. A global step whose matrix does not factor (round-off on large charts
//! with many holes) is regularised by a proximal diagonal shift and retried
//! ([`factor_regularised`]); when even that fails the iterations stop likewise. A chart that
//! stops before its first iteration is never reported solved: it keeps its valid start,
//! marked as a fallback to that start's method with the reason and the energy reached.

use super::mips::{flip_free_start, honour_pins_by_similarity, RestTriangle};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, max_flip_free_step, LineSearchOptions};
use rayon::prelude::*;

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaffoldOptions {
    /// Most iterations (one scaffold rebuild and one global step each). Default 100.
    pub max_iterations: usize,
    /// Stop when the chart energy changes by less than this, relative to the energy.
    /// Default 1e-4, SLIM's: on every disk mesh of the test set and on Suzanne with her seams
    /// the symmetric Dirichlet reached is below that of Blender's MINIMUM_STRETCH unwrap
    /// (further iterations lower it by under 0.5 %).
    pub tolerance: f64,
}

impl Default for ScaffoldOptions {
    fn default() -> Self {
        ScaffoldOptions { max_iterations: 100, tolerance: 1e-4 }
    }
}

/// The box around the chart is its UV bounding box grown by this fraction of its larger side
/// on every side.
pub const BOX_MARGIN: f64 = 0.5;
/// Total weight of the scaffold triangles relative to the chart's 3D area.
pub const SCAFFOLD_WEIGHT: f64 = 0.01;
/// A scaffold kept this many iterations is re-meshed (see the module docs).
const STALE_AFTER: usize = 10;
/// Points per side of the box (corners included once).
const BOX_POINTS_PER_SIDE: usize = 8;

/// Symmetric Dirichlet density ‖J‖² (1 + 1/det²) of a row-major Jacobian (+∞ unless
/// det J > 0); 4 for a rotation. The same density as SLIM's ([`super::slim`]).
#[inline]
pub fn symmetric_dirichlet_density(j: [f64; 4]) -> f64 {
    super::slim::density([[j[0], j[1]], [j[2], j[3]]])
}

/// Weighted symmetric Dirichlet Σ w_t D(J_t) of a set of triangles (+∞ on a non-positive one).
fn weighted_energy(rest: &[RestTriangle], weight: &[f64], triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    rest.par_iter()
        .zip(weight.par_iter())
        .zip(triangles.par_iter())
        .with_min_len(2048)
        .map(|((r, &w), t)| {
            if w == 0.0 {
                return 0.0;
            }
            w * symmetric_dirichlet_density(r.jacobian([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]))
        })
        .sum()
}

/// The SLIM proxy of one triangle (row-major Jacobian): K = W² (symmetric 2×2, as
/// [k00, k01, k11]) and P = K R, exactly SLIM's local step ([`super::slim`]).
fn slim_proxy(j: [f64; 4]) -> ([f64; 3], [f64; 4]) {
    let (k, p) = super::slim::reweight([[j[0], j[1]], [j[2], j[3]]]);
    (k, [p[0][0], p[0][1], p[1][0], p[1][1]])
}

/// The scaffold of one iteration.
struct Scaffold {
    /// Box points (appended after the chart vertices).
    box_points: Vec<[f64; 2]>,
    /// Scaffold triangles over chart vertex ids and box point ids (n + k), counter-clockwise.
    triangles: Vec<[u32; 3]>,
}

/// Triangulate the free space of the box around the chart's boundary loops.
fn build_scaffold(chart: &Chart, uv: &[[f64; 2]]) -> Result<Scaffold, String> {
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
    let n = uv.len();
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in uv {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err("non-finite UV".into());
        }
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let side = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(side > 0.0) {
        return Err("the chart collapsed to a point".into());
    }
    let grow = BOX_MARGIN * side;
    let (x0, y0, x1, y1) = (lo[0] - grow, lo[1] - grow, hi[0] + grow, hi[1] + grow);
    let k = BOX_POINTS_PER_SIDE;
    let mut box_points = Vec::with_capacity(4 * k);
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x0 + f * (x1 - x0), y0]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x1, y0 + f * (y1 - y0)]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x1 - f * (x1 - x0), y1]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x0, y1 - f * (y1 - y0)]);
    }
    // CDT vertices: boundary vertices of all loops, then the box points.
    let mut ids: Vec<u32> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    let mut edges: Vec<[usize; 2]> = Vec::new();
    for lp in &chart.boundary_loops {
        for &v in lp {
            if slot[v as usize] == usize::MAX {
                slot[v as usize] = ids.len();
                ids.push(v);
            }
        }
        for i in 0..lp.len() {
            edges.push([slot[lp[i] as usize], slot[lp[(i + 1) % lp.len()] as usize]]);
        }
    }
    let nb = ids.len();
    let mut points: Vec<Point2<f64>> = ids.iter().map(|&v| Point2::new(uv[v as usize][0], uv[v as usize][1])).collect();
    points.extend(box_points.iter().map(|p| Point2::new(p[0], p[1])));
    let total = points.len();
    let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut conflicts = 0usize;
        let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(points, edges.clone(), |_| conflicts += 1);
        (cdt, conflicts)
    }));
    let (cdt, conflicts) = built.map_err(|_| "the constrained triangulation panicked".to_string())?;
    let cdt = cdt.map_err(|e| format!("constrained triangulation failed: {e:?}"))?;
    if conflicts > 0 || cdt.num_vertices() != total {
        return Err("the chart boundary touches itself at round-off level".into());
    }
    // Label faces: left of a loop edge is chart, right is scaffold; flood fill across
    // non-constraint edges.
    let nf = cdt.all_faces().len();
    let mut label = vec![0u8; nf]; // 0 unknown, 1 chart, 2 scaffold
    let mut stack = Vec::new();
    for e in &edges {
        let (a, b) = (spade::handles::FixedVertexHandle::from_index(e[0]), spade::handles::FixedVertexHandle::from_index(e[1]));
        let Some(de) = cdt.get_edge_from_neighbors(a, b) else {
            return Err("a boundary edge is missing from the constrained triangulation".into());
        };
        stack.push((de.face().fix(), 1));
        stack.push((de.rev().face().fix(), 2));
    }
    while let Some((fixed_face, l)) = stack.pop() {
        let f = fixed_face.index();
        if label[f] == l {
            continue;
        }
        if label[f] != 0 {
            return Err("the chart boundary does not separate the chart from the free space".into());
        }
        label[f] = l;
        let fh = cdt.face(fixed_face);
        let Some(inner) = fh.as_inner() else {
            return Err("the chart reaches the outside of the box".into());
        };
        for de in inner.adjacent_edges() {
            let other = de.rev().face();
            if !de.is_constraint_edge() && !other.is_outer() {
                stack.push((other.fix(), l));
            }
        }
    }
    let mut triangles = Vec::new();
    for f in cdt.inner_faces() {
        let i = f.fix().index();
        match label[i] {
            1 => {}
            _ => {
                // Unlabelled faces cannot exist (every region touches a loop); treat as scaffold.
                let vs = f.vertices();
                let map = |k: usize| {
                    if k < nb {
                        ids[k]
                    } else {
                        (n + k - nb) as u32
                    }
                };
                triangles.push([map(vs[0].fix().index()), map(vs[1].fix().index()), map(vs[2].fix().index())]);
            }
        }
    }
    Ok(Scaffold { box_points, triangles })
}

/// Normalised chart energy Σ A D(J) / (4 Σ A): 1 for an isometry (the DESIGN.md symmetric
/// Dirichlet measure).
fn chart_energy(rest: &[RestTriangle], area: &[f64], total: f64, tris: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    weighted_energy(rest, area, tris, uv) / (4.0 * total)
}

/// Scale `uv` about the origin by the factor minimising the chart's symmetric Dirichlet energy
/// ([`super::slim::optimal_scale`]); no-op on a map with a degenerate triangle.
fn scale_optimally(rest: &[RestTriangle], tris: &[[u32; 3]], uv: &mut [[f64; 2]]) {
    let s = super::slim::optimal_scale(tris.len(), |f| {
        let t = tris[f];
        let j = rest[f].jacobian([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]);
        (rest[f].area, [[j[0], j[1]], [j[2], j[3]]])
    });
    super::slim::scale_uv(uv, s);
}

/// The (p, q), p ≥ q, entries of a triangle's 6 × 6 block over the unknowns
/// `(u, v)` of its three corners (local index `2·corner + component`).
const LOCAL: [(usize, usize); 21] = {
    let mut out = [(0, 0); 21];
    let mut k = 0;
    let mut p = 0;
    while p < 6 {
        let mut q = 0;
        while q <= p {
            out[k] = (p, q);
            k += 1;
            q += 1;
        }
        p += 1;
    }
    out
};

/// Lower-triangle sparsity pattern of the global step over the chart's 2n unknowns (u, v
/// interleaved; the box points are fixed and moved to the right-hand side), with its symbolic
/// Cholesky analysis.
///
/// The chart triangles contribute the same entries every iteration; the scaffold adds, between
/// chart vertices, only *chords*: scaffold edges joining two boundary vertices that are not a
/// chart edge (scaffold edges to the box touch fixed unknowns only). The pattern holds a set of
/// chords and serves every scaffold whose chords are among them — entries of absent chords are
/// zero, so the matrix is exactly that scaffold's matrix.
struct StepPattern {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Value slot of every [`LOCAL`] entry of every chart triangle.
    chart_slots: Vec<[u32; 21]>,
    symbolic: faer::sparse::linalg::solvers::SymbolicLlt<usize>,
}

impl StepPattern {
    /// Pattern of the chart (`edges`: its vertex pairs `(a, b)`, `a > b`, sorted) plus
    /// `chords`, and its symbolic analysis (approximate minimum degree ordering).
    fn new(n: usize, tris: &[[u32; 3]], edges: &[(u32, u32)], chords: &[(u32, u32)]) -> Result<StepPattern, String> {
        let n2 = 2 * n;
        // Entries per column: the 2 × 2 diagonal block of every vertex (3 lower entries), the
        // full 2 × 2 block of every chart edge (u and v couple through W²), and the u–u and
        // v–v entries of every chord (a scaffold triangle's weight is a multiple of I).
        let mut count = vec![0usize; n2 + 1];
        for v in 0..n {
            count[2 * v] += 2;
            count[2 * v + 1] += 1;
        }
        for &(_, b) in edges {
            count[2 * b as usize] += 2;
            count[2 * b as usize + 1] += 2;
        }
        for &(_, b) in chords {
            count[2 * b as usize] += 1;
            count[2 * b as usize + 1] += 1;
        }
        let mut col_ptr = vec![0usize; n2 + 1];
        for c in 0..n2 {
            col_ptr[c + 1] = col_ptr[c] + count[c];
        }
        let mut row_idx = vec![0usize; col_ptr[n2]];
        let mut fill = col_ptr[..n2].to_vec();
        let mut put = |r: usize, c: usize| {
            row_idx[fill[c]] = r;
            fill[c] += 1;
        };
        for v in 0..n {
            put(2 * v, 2 * v);
            put(2 * v + 1, 2 * v);
            put(2 * v + 1, 2 * v + 1);
        }
        for &(a, b) in edges {
            let (a, b) = (a as usize, b as usize);
            for s in 0..2 {
                for s2 in 0..2 {
                    put(2 * a + s, 2 * b + s2);
                }
            }
        }
        for &(a, b) in chords {
            let (a, b) = (a as usize, b as usize);
            put(2 * a, 2 * b);
            put(2 * a + 1, 2 * b + 1);
        }
        for c in 0..n2 {
            row_idx[col_ptr[c]..col_ptr[c + 1]].sort_unstable();
        }
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n2, n2, &col_ptr, None, &row_idx);
        let symbolic = faer::sparse::linalg::solvers::SymbolicLlt::try_new(sym, faer::Side::Lower)
            .map_err(|e| format!("symbolic analysis failed: {e:?}"))?;
        let mut pattern = StepPattern { col_ptr, row_idx, chart_slots: Vec::new(), symbolic };
        let slots: Option<Vec<[u32; 21]>> = tris
            .par_iter()
            .with_min_len(2048)
            .map(|t| {
                let mut out = [0u32; 21];
                for (k, &(p, q)) in LOCAL.iter().enumerate() {
                    let gp = 2 * t[p / 2] as usize + p % 2;
                    let gq = 2 * t[q / 2] as usize + q % 2;
                    out[k] = pattern.slot(gp.max(gq), gp.min(gq))? as u32;
                }
                Some(out)
            })
            .collect();
        pattern.chart_slots = slots.ok_or("a chart entry is missing from the pattern")?;
        Ok(pattern)
    }

    /// Value slot of the lower entry `(r, c)`, `r ≥ c`.
    #[inline]
    fn slot(&self, r: usize, c: usize) -> Option<usize> {
        let (lo, hi) = (self.col_ptr[c], self.col_ptr[c + 1]);
        self.row_idx[lo..hi].binary_search(&r).ok().map(|k| lo + k)
    }
}

/// Whether the sorted list `a` is a subset of the sorted list `b`.
fn is_subset(a: &[(u32, u32)], b: &[(u32, u32)]) -> bool {
    let mut i = 0;
    for x in a {
        while i < b.len() && b[i] < *x {
            i += 1;
        }
        if i == b.len() || b[i] != *x {
            return false;
        }
    }
    true
}

/// Chart vertex pairs `(a, b)`, `a > b`, of all triangle edges, sorted and unique.
fn chart_edges(tris: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.max(b), a.min(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Chords of a scaffold: its edges between two chart vertices (`< n`) that are not chart
/// edges, as `(a, b)`, `a > b`, sorted and unique.
fn scaffold_chords(n: usize, scaffold: &[[u32; 3]], edges: &[(u32, u32)]) -> Vec<(u32, u32)> {
    let mut c: Vec<(u32, u32)> = scaffold
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| (a as usize) < n && (b as usize) < n)
        .map(|(a, b)| (a.max(b), a.min(b)))
        .filter(|e| edges.binary_search(e).is_err())
        .collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// Map one chart; see the module docs.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &ScaffoldOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
}

/// What [`solve_with_history`] reports beside the map.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScaffoldHistory {
    /// Chart symmetric Dirichlet energy per unit area / 4 of the start and after every
    /// iteration (strictly decreasing).
    pub energy: Vec<f64>,
    /// Seconds per iteration: `[scaffold triangulation, assembly, symbolic analysis, numeric
    /// factorisation, solve, line search]` (symbolic is 0 when the analysis was reused).
    pub seconds: Vec<[f64; 6]>,
    /// Scaffold triangles per iteration.
    pub scaffold_triangles: Vec<usize>,
    /// Per iteration: whether its scaffold was a fresh Delaunay re-mesh (false: the previous
    /// iteration's scaffold, kept).
    pub remeshed: Vec<bool>,
    /// Number of symbolic analyses (at most one per iteration).
    pub analyses: usize,
    /// Name of the starting map ("lscm" or "mean_value").
    pub start: &'static str,
    /// Seconds spent computing and checking the starting maps.
    pub start_seconds: f64,
}

/// The valid start with the lowest energy, each candidate scaled optimally: LSCM and the mean
/// value map on a circle (Floater 2003, an embedding by Tutte's theorem up to round-off). Valid:
/// every chart triangle positive, finite energy, no boundary self-overlap, and a scaffold can
/// be built around it. `None` when no candidate is valid (the reasons are returned).
fn pick_start(
    chart: &Chart,
    rest: &[RestTriangle],
    area: &[f64],
    total: f64,
) -> Result<(Option<(Vec<[f64; 2]>, f64, &'static str)>, Vec<String>), ChartFailure> {
    let tris = &chart.triangles;
    let (candidates, mut rejected) = super::slim::candidate_starts(chart, &[], true);
    let mut best: Option<(Vec<[f64; 2]>, f64, &'static str, usize)> = None;
    for (mut uv, name) in candidates {
        scale_optimally(rest, tris, &mut uv);
        let e = chart_energy(rest, area, total, tris, &uv);
        let why = if !all_positive(tris, &uv) || !e.is_finite() {
            Some("flipped or degenerate triangles".to_string())
        } else if crate::metrics::boundary_self_overlap(&uv, &chart.boundary_loops) {
            Some("the boundary overlaps itself".to_string())
        } else {
            build_scaffold(chart, &uv).err()
        };
        if let Some(why) = why {
            rejected.push(format!("{name}: {why}"));
            continue;
        }
        // Fewer non-convex quads first (the barrier cannot make them convex), then energy.
        let bad = super::nonconvex_quads(chart, &uv);
        if best.as_ref().is_none_or(|b| (bad, e) < (b.3, b.1)) {
            best = Some((uv, e, name, bad));
        }
    }
    Ok((best.map(|(uv, e, name, _)| (uv, e, name)), rejected))
}

/// [`solve`], also returning the chart's normalised symmetric Dirichlet energy before the first
/// iteration and after each iteration (strictly decreasing, see the module docs) and the time
/// split of every iteration.
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ScaffoldOptions,
) -> Result<(ChartSolution, ScaffoldHistory), ChartFailure> {
    run(chart, pins, options, Policy::default())
}

/// How the iterations treat the scaffold and the symbolic analysis (the default is the fast
/// one; the others exist to check it against).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Policy {
    /// Re-mesh the scaffold every iteration, as in the paper (default: keep the previous
    /// scaffold when re-meshing would need a new analysis and the old one did not limit the
    /// step).
    remesh_every_iteration: bool,
    /// Analyse exactly the current pattern every iteration (default: reuse an analysis whose
    /// pattern covers the scaffold's chords).
    exact_pattern: bool,
}

/// The iterations under `policy`.
fn run(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ScaffoldOptions,
    policy: Policy,
) -> Result<(ChartSolution, ScaffoldHistory), ChartFailure> {
    use faer::linalg::solvers::Solve;
    use std::time::Instant;
    super::require_disk(chart)?;
    let tris = &chart.triangles;
    let n = chart.positions.len();
    let rest: Vec<RestTriangle> = tris
        .iter()
        .map(|t| RestTriangle::from_3d([chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]]))
        .collect();
    let area: Vec<f64> = rest.iter().map(|r| r.area).collect();
    let total: f64 = area.iter().sum();
    if !(total > 0.0) {
        return Err(ChartFailure("the chart has zero 3D area".into()));
    }
    let t_start = Instant::now();
    let (start, rejected) = pick_start(chart, &rest, &area, total)?;
    let Some((mut uv, mut energy, start_name)) = start else {
        let mut sol = ChartSolution::direct(flip_free_start(chart)?);
        sol.fallback = Some(super::Fallback {
            method: "mean_value",
            reason: format!("no valid (flip-free, overlap-free) start for the scaffold iterations ({})", rejected.join("; ")),
        });
        return Ok((sol, ScaffoldHistory::default()));
    };
    // The chart energy and the barrier cover both diagonal splits of every quad, so quads stay
    // strictly convex (see `barrier_triangles`).
    let barrier_tris;
    let (tris, rest, area, total, left_out) = if chart.quads.is_empty() {
        (tris, rest, area, total, 0)
    } else {
        let (b, w, left_out) = super::barrier_triangles(chart, &uv);
        barrier_tris = b;
        let rest: Vec<RestTriangle> = barrier_tris
            .iter()
            .map(|t| RestTriangle::from_3d([chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]]))
            .collect();
        let area: Vec<f64> = rest.iter().zip(&w).map(|(r, w)| r.area * w).collect();
        let total: f64 = area.iter().sum();
        energy = chart_energy(&rest, &area, total, &barrier_tris, &uv);
        (&barrier_tris, rest, area, total, left_out)
    };
    let mut history = ScaffoldHistory {
        energy: vec![energy],
        start: start_name,
        start_seconds: t_start.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let edges = chart_edges(tris);
    let mut pattern: Option<StepPattern> = None;
    // Chords the analysis covers (the pattern's chords, tracked apart from the analysis so
    // that `policy.exact_pattern` changes the linear algebra only).
    let mut covered: Vec<(u32, u32)> = Vec::new();
    // The scaffold of the previous iteration: still a valid triangulation of the free space
    // after the step (the line search kept all its triangles positive, the box is fixed).
    let mut kept: Option<Scaffold> = None;
    let mut remesh = true;
    let mut age = 0usize;
    let ls = LineSearchOptions::default();
    let mut change = f64::INFINITY;
    let mut iterations = 0;
    let mut stop_note: Option<String> = None;
    // Global steps that needed a diagonal shift to factor, and the largest relative shift.
    let (mut shifts, mut largest_shift) = (0usize, 0.0f64);
    for _ in 0..options.max_iterations {
        if crate::progress::cancelled() {
            break; // the unwrap discards this chart
        }
        let t0 = Instant::now();
        // Scaffold: the Delaunay re-mesh of the free space around the current map (SCAF), unless
        // it would need a new symbolic analysis while the previous scaffold neither limited the
        // last step nor is stale (then the previous one is kept, see the module docs).
        let fresh = build_scaffold(chart, &uv).and_then(|s| {
            let ok = s.triangles.iter().all(|t| {
                let q = |v: u32| if (v as usize) < n { uv[v as usize] } else { s.box_points[v as usize - n] };
                RestTriangle::from_2d([q(t[0]), q(t[1]), q(t[2])]).area > 0.0
            });
            if ok {
                Ok(s)
            } else {
                Err("a degenerate scaffold triangle".to_string())
            }
        });
        let (scaffold, remeshed) = match (fresh, kept.take()) {
            (Ok(f), None) => (f, true),
            (Ok(f), Some(k)) => {
                let chords = scaffold_chords(n, &f.triangles, &edges);
                if policy.remesh_every_iteration || remesh || is_subset(&chords, &covered) {
                    (f, true)
                } else {
                    (k, false)
                }
            }
            (Err(_), Some(k)) => (k, false),
            (Err(why), None) => {
                stop_note = Some(format!("scaffold iterations stopped early: {why}"));
                break;
            }
        };
        let t1 = Instant::now();
        let big_n = n + scaffold.box_points.len();
        let mut all: Vec<[f64; 2]> = uv.clone();
        all.extend_from_slice(&scaffold.box_points);
        let s_tris = &scaffold.triangles;
        let s_rest: Vec<RestTriangle> = s_tris
            .iter()
            .map(|t| RestTriangle::from_2d([all[t[0] as usize], all[t[1] as usize], all[t[2] as usize]]))
            .collect();
        if s_rest.iter().any(|r| r.area == 0.0) {
            // Cannot happen: fresh scaffolds are checked above, kept ones stayed positive.
            stop_note = Some("scaffold iterations stopped early: a degenerate scaffold triangle".into());
            break;
        }
        let ws = SCAFFOLD_WEIGHT * total / s_tris.len().max(1) as f64;
        let s_weight = vec![ws; s_tris.len()];
        // Symbolic analysis: kept while it covers the scaffold's chords; otherwise redone for
        // the union of the old and new chords (scaffolds of consecutive iterations share most
        // chords, so the union settles), or the new chords alone once the union would be more
        // than twice their number. Entries of chords absent from the scaffold are zero.
        let chords = scaffold_chords(n, s_tris, &edges);
        let mut t_symbolic = 0.0;
        let covers = pattern.is_some() && is_subset(&chords, &covered);
        if !covers || policy.exact_pattern {
            let ts = Instant::now();
            if !covers {
                let mut u = std::mem::take(&mut covered);
                u.extend_from_slice(&chords);
                u.sort_unstable();
                u.dedup();
                covered = if u.len() > 2 * chords.len() + 16 { chords.clone() } else { u };
            }
            let wanted = if policy.exact_pattern { &chords } else { &covered };
            drop(pattern.take());
            match StepPattern::new(n, tris, &edges, wanted) {
                Ok(p) => pattern = Some(p),
                Err(why) => {
                    stop_note = Some(format!("scaffold iterations stopped early: {why}"));
                    break;
                }
            }
            history.analyses += 1;
            t_symbolic = ts.elapsed().as_secs_f64();
        }
        let pat = pattern.as_ref().expect("analysed above");
        let t2 = Instant::now();
        // Assembly: SLIM's proxy on the chart (parallel per triangle), then a scatter into
        // the pattern's value slots; scaffold triangles at rest (J = I: W² = 4 I, W² R = 4 I).
        let blocks: Vec<([f64; 21], [[f64; 2]; 3])> = rest
            .par_iter()
            .zip(tris.par_iter())
            .with_min_len(1024)
            .map(|(r, t)| {
                let mut vals = [0.0; 21];
                let mut rhs = [[0.0; 2]; 3];
                if r.area > 0.0 {
                    let (k, p) = slim_proxy(r.jacobian([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]));
                    let kk = [[k[0], k[1]], [k[1], k[2]]];
                    for (e, &(pp, qq)) in LOCAL.iter().enumerate() {
                        let (a, c) = (pp / 2, qq / 2);
                        let lac = r.g[0][a] * r.g[0][c] + r.g[1][a] * r.g[1][c];
                        vals[e] = r.area * kk[pp % 2][qq % 2] * lac;
                    }
                    for (a, row) in rhs.iter_mut().enumerate() {
                        for (s, x) in row.iter_mut().enumerate() {
                            *x = r.area * (r.g[0][a] * p[2 * s] + r.g[1][a] * p[2 * s + 1]);
                        }
                    }
                }
                (vals, rhs)
            })
            .collect();
        let mut values = vec![0.0; pat.row_idx.len()];
        let mut b = vec![0.0; 2 * n];
        for ((t, slots), (vals, rhs)) in tris.iter().zip(&pat.chart_slots).zip(&blocks) {
            for (&s, &v) in slots.iter().zip(vals) {
                values[s as usize] += v;
            }
            for a in 0..3 {
                b[2 * t[a] as usize] += rhs[a][0];
                b[2 * t[a] as usize + 1] += rhs[a][1];
            }
        }
        let mut missing = false;
        for (t, r) in s_tris.iter().zip(&s_rest) {
            for a in 0..3 {
                let ta = t[a] as usize;
                if ta >= n {
                    continue; // a box point: fixed, no equation
                }
                for s in 0..2 {
                    b[2 * ta + s] += ws * 4.0 * r.g[s][a];
                }
                for c in 0..3 {
                    let tc = t[c] as usize;
                    let v = ws * 4.0 * (r.g[0][a] * r.g[0][c] + r.g[1][a] * r.g[1][c]);
                    if tc >= n {
                        let q = scaffold.box_points[tc - n];
                        b[2 * ta] -= v * q[0];
                        b[2 * ta + 1] -= v * q[1];
                    } else if ta >= tc {
                        for s in 0..2 {
                            match pat.slot(2 * ta + s, 2 * tc + s) {
                                Some(k) => values[k] += v,
                                None => missing = true,
                            }
                        }
                    }
                }
            }
        }
        if missing {
            // Cannot happen: the pattern covers every chord and chart edge.
            stop_note = Some("scaffold iterations stopped early: a scaffold entry is missing from the pattern".into());
            break;
        }
        let t3 = Instant::now();
        let llt = match factor_regularised(pat, &mut values, &mut b, &uv) {
            Ok((f, shift)) => {
                if shift > 0.0 {
                    shifts += 1;
                    largest_shift = largest_shift.max(shift);
                }
                f
            }
            Err(e) => {
                stop_note = Some(format!("scaffold iterations stopped early: the global step could not be factored ({e})"));
                break;
            }
        };
        let t4 = Instant::now();
        let mut x = faer::Mat::<f64>::from_fn(2 * n, 1, |i, _| b[i]);
        llt.solve_in_place(x.as_mut());
        if (0..2 * n).any(|i| !x[(i, 0)].is_finite()) {
            stop_note = Some("scaffold iterations stopped early: the global step is not finite".into());
            break;
        }
        let dir: Vec<[f64; 2]> =
            (0..big_n).map(|i| if i < n { [x[(2 * i, 0)] - all[i][0], x[(2 * i + 1, 0)] - all[i][1]] } else { [0.0, 0.0] }).collect();
        let t5 = Instant::now();
        let mut both: Vec<[u32; 3]> = tris.clone();
        both.extend_from_slice(s_tris);
        let total_energy =
            |q: &[[f64; 2]]| weighted_energy(&rest, &area, tris, q) + weighted_energy(&s_rest, &s_weight, s_tris, q);
        let e0 = total_energy(&all);
        let scaffold_flip = max_flip_free_step(s_tris, &all, &dir);
        let out = flip_free_line_search(&both, &mut all, &dir, e0, total_energy, &ls);
        // The scaffold limited the step when its first degenerating triangle set the bound and
        // the trial started below a full step: re-mesh it next iteration.
        remesh = scaffold_flip <= out.flip_step && ls.safety * scaffold_flip < ls.max_step;
        // A scaffold kept for `STALE_AFTER` iterations is re-meshed too: one that only grows
        // skinnier slows the boundary down without ever bounding the step.
        age = if remeshed { 1 } else { age + 1 };
        remesh |= age >= STALE_AFTER;
        let t6 = Instant::now();
        history.seconds.push([
            (t1 - t0).as_secs_f64(),
            (t3 - t2).as_secs_f64() + (t2 - t1).as_secs_f64() - t_symbolic,
            t_symbolic,
            (t4 - t3).as_secs_f64(),
            (t5 - t4).as_secs_f64(),
            (t6 - t5).as_secs_f64(),
        ]);
        history.scaffold_triangles.push(s_tris.len());
        history.remeshed.push(remeshed);
        iterations += 1;
        if out.step == 0.0 {
            change = 0.0;
            break;
        }
        uv.copy_from_slice(&all[..n]);
        kept = Some(scaffold);
        let e = chart_energy(&rest, &area, total, tris, &uv);
        change = (energy - e) / e.abs().max(f64::MIN_POSITIVE);
        energy = e;
        history.energy.push(energy);
        if change < options.tolerance {
            break;
        }
    }
    let mut sol = ChartSolution::direct(uv);
    sol.iterations = iterations;
    sol.residual = change;
    let pin_note = honour_pins_by_similarity(&mut sol.uv, pins, "scaffold");
    let remeshes = history.remeshed.iter().filter(|&&r| r).count();
    let summary = format!(
        "symmetric Dirichlet {energy:.6} after {iterations} iteration(s), started from {}; scaffold re-meshed {remeshes} time(s), {} symbolic analysis(es)",
        history.start, history.analyses
    );
    let shift_note = (shifts > 0).then(|| {
        format!("{shifts} global step(s) factored with the diagonal shifted by up to {largest_shift:.0e} of its mean")
    });
    let quad_note = (left_out > 0).then(|| {
        format!("{left_out} quad triangle(s) of the other diagonal were not positive at the start, so those quads may stay non-convex")
    });
    let note = [Some(summary), stop_note.clone(), shift_note, pin_note, quad_note].into_iter().flatten().collect::<Vec<_>>().join("; ");
    if iterations == 0 && stop_note.is_some() {
        // Never "solved" without a single iteration: the start is what the chart gets.
        sol.fallback = Some(super::Fallback { method: history.start, reason: note });
    } else {
        sol.note = Some(note);
    }
    Ok((sol, history))
}

/// Relative diagonal shifts tried, in order, when the global step's matrix does not factor.
const SHIFTS: [f64; 6] = [0.0, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4];

/// Cholesky factorisation of the global step, regularised when it fails: the matrix is
/// symmetric positive semi-definite in exact arithmetic, but on large charts with many holes
/// and near-degenerate triangles round-off can make a pivot non-positive. Then a proximal term
/// δ ‖x − x_k‖² is added (δ on the diagonal, δ x_k on the right-hand side, x_k the current
/// map), with δ = shift × the mean diagonal entry, for the shifts of [`SHIFTS`] in turn; the
/// step still lowers the proxy energy, only more cautiously. `values` and `b` keep the shift
/// that worked. Returns the factor and the relative shift used (0 when none was needed).
///
/// Errors: the factorisation's message when every shift fails.
fn factor_regularised(
    pat: &StepPattern,
    values: &mut [f64],
    b: &mut [f64],
    uv: &[[f64; 2]],
) -> Result<(faer::sparse::linalg::solvers::Llt<usize, f64>, f64), String> {
    let n2 = pat.col_ptr.len() - 1;
    let diag: Vec<usize> = (0..n2).map(|i| pat.slot(i, i).expect("every diagonal entry is in the pattern")).collect();
    let mean = diag.iter().map(|&k| values[k].abs()).sum::<f64>() / n2.max(1) as f64;
    let mean = if mean > 0.0 && mean.is_finite() { mean } else { 1.0 };
    let mut applied = 0.0;
    let mut last = String::new();
    for &shift in &SHIFTS {
        let delta = (shift - applied) * mean;
        if delta > 0.0 {
            for (i, &k) in diag.iter().enumerate() {
                values[k] += delta;
                b[i] += delta * uv[i / 2][i % 2];
            }
            applied = shift;
        }
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n2, n2, &pat.col_ptr, None, &pat.row_idx);
        let mat = faer::sparse::SparseColMatRef::new(sym, values);
        match faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(pat.symbolic.clone(), mat, faer::Side::Lower) {
            Ok(f) => return Ok((f, shift)),
            Err(e) => last = format!("{e:?}"),
        }
    }
    Err(format!("{last}, even with the diagonal shifted by {:.0e} of its mean", SHIFTS[SHIFTS.len() - 1]))
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_global_step_that_does_not_factor_is_regularised() {
        // Two triangles; the matrix of the translation-invariant Laplacian alone (no fixed
        // box point) is singular, and with one diagonal entry nudged below zero indefinite.
        let tris = vec![[0u32, 1, 2], [0, 2, 3]];
        let edges = chart_edges(&tris);
        let pat = StepPattern::new(4, &tris, &edges, &[]).unwrap();
        let uv = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut values = vec![0.0; pat.row_idx.len()];
        for &(a, b) in &edges {
            for s in 0..2 {
                let (ia, ib) = (2 * a as usize + s, 2 * b as usize + s);
                values[pat.slot(ia, ia).unwrap()] += 1.0;
                values[pat.slot(ib, ib).unwrap()] += 1.0;
                values[pat.slot(ia, ib).unwrap()] -= 1.0;
            }
        }
        values[pat.slot(0, 0).unwrap()] -= 1e-9;
        let mut b = vec![0.0; 8];
        let before = values.clone();
        let (f, shift) = factor_regularised(&pat, &mut values, &mut b, &uv).unwrap();
        assert!(shift > 0.0 && shift <= 1e-6, "shift {shift}");
        // The shift is a proximal term: the step from the current map solves (A + δI) x = δ x_k,
        // and with b = 0 the current map (a translation-free fit) stays close.
        use faer::linalg::solvers::Solve;
        let mut x = faer::Mat::<f64>::from_fn(8, 1, |i, _| b[i]);
        f.solve_in_place(x.as_mut());
        assert!((0..8).all(|i| x[(i, 0)].is_finite()));
        let diag_shift = values[pat.slot(3, 3).unwrap()] - before[pat.slot(3, 3).unwrap()];
        assert!(diag_shift > 0.0);
        assert!(b[6] == 0.0 && (b[7] - diag_shift * uv[3][1]).abs() < 1e-3 * diag_shift, "{b:?} {diag_shift}");
    }

    #[test]
    fn slim_proxy_of_a_rotation_is_four_identity_and_weights_match_singular_values() {
        let (c, s) = (0.6f64, 0.8f64);
        let (k, p) = slim_proxy([c, -s, s, c]);
        assert!((k[0] - 4.0).abs() < 1e-12 && k[1].abs() < 1e-12 && (k[2] - 4.0).abs() < 1e-12);
        assert!((p[0] - 4.0 * c).abs() < 1e-12 && (p[1] + 4.0 * s).abs() < 1e-12);
        // diag(2, 0.5): w² = (σ+1)(σ²+1)/σ³ on each axis, R = I.
        let (k, p) = slim_proxy([2.0, 0.0, 0.0, 0.5]);
        let w = |x: f64| (x + 1.0) * (x * x + 1.0) / (x * x * x);
        assert!((k[0] - w(2.0)).abs() < 1e-9 && k[1].abs() < 1e-12 && (k[2] - w(0.5)).abs() < 1e-9, "{k:?}");
        assert!((p[0] - w(2.0)).abs() < 1e-9 && (p[3] - w(0.5)).abs() < 1e-9);
        assert!((symmetric_dirichlet_density([c, -s, s, c]) - 4.0).abs() < 1e-12);
    }

    /// A wavy cone ring cut open along one ray (its isometric flattening overlaps itself, so
    /// the scaffold is active): the chart and the number of its triangles.
    fn wavy_cone_chart(nu: usize, nv: usize) -> Chart {
        let mut positions = Vec::new();
        for j in 0..=nv {
            let r = 1.0 + j as f64 / nv as f64;
            for i in 0..nu {
                let a = std::f64::consts::TAU * i as f64 / nu as f64;
                positions.push([r * a.cos(), r * a.sin(), r * 0.35 * (5.0 * a).sin()]);
            }
        }
        let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
        let mut corners = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                corners.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let sizes = vec![3u32; 2 * nu * nv];
        let seams: Vec<[u32; 2]> = (0..nv).map(|j| [id(0, j), id(0, j + 1)]).collect();
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        crate::charts::build_charts(&mesh, &seams, None).pop().unwrap()
    }

    #[test]
    fn a_reused_analysis_with_extra_zero_chords_gives_the_same_steps_as_a_fresh_one() {
        let chart = wavy_cone_chart(60, 4);
        let o = ScaffoldOptions { max_iterations: 12, tolerance: 0.0 };
        let remesh = Policy { remesh_every_iteration: true, exact_pattern: false };
        let exact = Policy { remesh_every_iteration: true, exact_pattern: true };
        let (a, ha) = run(&chart, &[], &o, remesh).unwrap();
        let (b, hb) = run(&chart, &[], &o, exact).unwrap();
        assert_eq!(ha.seconds.len(), 12);
        assert_eq!(hb.analyses, 12, "the exact policy analyses every iteration");
        // The scaffold is re-meshed every iteration and its chords change, yet the union
        // pattern is analysed fewer times.
        assert!(ha.analyses < 12, "{} analyses", ha.analyses);
        let scale = a.uv.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        for (p, q) in a.uv.iter().zip(&b.uv) {
            assert!((p[0] - q[0]).abs() <= 1e-9 * scale && (p[1] - q[1]).abs() <= 1e-9 * scale, "{p:?} vs {q:?}");
        }
        for (x, y) in ha.energy.iter().zip(&hb.energy) {
            assert!((x - y).abs() <= 1e-9 * x, "{x} vs {y}");
        }
    }

    #[test]
    fn keeping_the_scaffold_stays_bijective_and_matches_remeshing_every_iteration() {
        let chart = wavy_cone_chart(60, 4);
        let o = ScaffoldOptions { max_iterations: 40, tolerance: 0.0 };
        let (kept, hk) = run(&chart, &[], &o, Policy::default()).unwrap();
        let (fresh, hf) = run(&chart, &[], &o, Policy { remesh_every_iteration: true, exact_pattern: false }).unwrap();
        for (sol, h) in [(&kept, &hk), (&fresh, &hf)] {
            assert!(all_positive(&chart.triangles, &sol.uv));
            assert!(!crate::metrics::boundary_self_overlap(&sol.uv, &chart.boundary_loops));
            assert!(h.energy.windows(2).all(|w| w[1] < w[0]), "{:?}", h.energy);
        }
        assert!(hk.remeshed.iter().any(|&r| !r), "the default policy never kept a scaffold");
        assert!(hf.remeshed.iter().all(|&r| r));
        // Both minimise the same energy from the same start: the same result to 2 % of the
        // remaining distortion (energy − 1), with fewer analyses.
        let (ek, ef, e0) = (*hk.energy.last().unwrap(), *hf.energy.last().unwrap(), hk.energy[0]);
        eprintln!("kept {ek} ({} analyses) vs re-meshed {ef} ({} analyses), start {e0}", hk.analyses, hf.analyses);
        assert!((ek - ef).abs() < 0.02 * (ef - 1.0), "kept {ek} vs re-meshed {ef} from {e0}");
        assert!(hk.analyses < hf.analyses);
    }
}
