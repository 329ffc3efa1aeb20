//! Splitting selected faces into charts.
//!
//! Two selected faces belong to the same chart when they share an edge that is
//! * not a seam,
//! * used by exactly two selected faces (a non-manifold edge is a cut), and
//! * traversed in opposite directions by them (an inconsistently oriented edge is a cut).
//!
//! Chart vertices are classes of corners: the corners of one mesh vertex that are connected
//! through such edges around it. A vertex on a seam therefore becomes one chart vertex per
//! side, a seam that ends inside a chart becomes a slit, and a "bow-tie" vertex shared by two
//! fans becomes two chart vertices.

mod render;
mod triangulate;

pub use render::FaceTriangulation;
pub use triangulate::{convex_quad, triangulate_polygon, triangulate_polygon_avoiding, triangulate_polygon_with};

use std::collections::{HashMap, HashSet};

use crate::mesh::PolyMesh;

/// Topological class of a chart, from its Euler characteristic and boundary loops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChartKind {
    /// One boundary loop, genus 0.
    Disk,
    /// Several boundary loops, genus 0.
    DiskWithHoles,
    /// No boundary, genus 0 (a sphere).
    Closed,
    /// Genus ≥ 1, with or without boundary.
    HigherGenus,
}

impl ChartKind {
    /// Stable lower-case name used by the Python layer.
    pub fn name(self) -> &'static str {
        match self {
            ChartKind::Disk => "disk",
            ChartKind::DiskWithHoles => "disk_with_holes",
            ChartKind::Closed => "closed",
            ChartKind::HigherGenus => "higher_genus",
        }
    }
}

/// One chart: a connected, triangulated piece of the selection with its own vertices.
#[derive(Debug, Clone)]
pub struct Chart {
    /// Input faces of the chart, ascending.
    pub faces: Vec<u32>,
    /// `(input corner, chart vertex)` for every corner of the chart's faces.
    pub corner_vertex: Vec<(u32, u32)>,
    /// Mesh vertex of every chart vertex.
    pub mesh_vertex: Vec<u32>,
    /// Position of every chart vertex.
    pub positions: Vec<[f64; 3]>,
    /// Triangles over chart vertices, oriented like the input faces.
    pub triangles: Vec<[u32; 3]>,
    /// Input face of every triangle.
    pub triangle_face: Vec<u32>,
    /// The chart's quad faces: a quad is flip-free only if it is strictly convex in UV, i.e.
    /// positive on both of its diagonal splits (exporters and engines pick their own). Quads
    /// with a corner at a vertex inside the chart shared by only two faces are left out (one
    /// of its two corner angles is at least π, so convexity is impossible), and so are quads
    /// not clearly convex in 3D ([`convex_quad`]: a concave or folded quad has a
    /// split turned over on the surface itself): they count as their own two triangles.
    pub quads: Vec<Quad>,
    /// Render triangles (the given triangulation) of the n-gons of five or more corners that
    /// keep the core's own split because a render diagonal is already an edge of the chart:
    /// not solved on, but measured, so a fold on what Blender shows is counted as a flip.
    pub shown: Vec<[u32; 3]>,
    /// Input face of every [`Chart::shown`] triangle.
    pub shown_face: Vec<u32>,
    /// Faces of four or more corners as polygons (quads included, with the same exception):
    /// the polygon graph of the barycentric methods, on which faces come out convex.
    pub polygons: Vec<Polygon>,
    /// Boundary loops, each oriented with the chart on its left (counter-clockwise for the
    /// outer loop of a well-oriented map).
    pub boundary_loops: Vec<Vec<u32>>,
    /// Genus from the Euler characteristic (0 when `defect` is set).
    pub genus: usize,
    /// Topological class.
    pub kind: ChartKind,
    /// Why the chart cannot be mapped at all (non-orientable, non-manifold vertex), if so.
    pub defect: Option<String>,
    /// [`Chart::vertex_order`], computed at its first use.
    vertex_order: VertexOrder,
}

/// The cache of [`Chart::vertex_order`]. A clone starts empty: a cloned chart's triangles
/// may be changed (holes filled, a unit frame), and its order would then be computed anew.
#[derive(Debug, Default)]
struct VertexOrder(std::sync::OnceLock<Vec<u32>>);

impl Clone for VertexOrder {
    fn clone(&self) -> Self {
        VertexOrder::default()
    }
}

/// A quad face of a chart: its chart vertices in face order and its two triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Quad {
    /// Chart vertices in the face's winding order.
    pub vertices: [u32; 4],
    /// Indices into [`Chart::triangles`] of the quad's own split.
    pub triangles: [u32; 2],
}

/// A face of four or more corners: its chart vertices in face order and its triangles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Polygon {
    /// Chart vertices in the face's winding order.
    pub vertices: Vec<u32>,
    /// Indices into [`Chart::triangles`] of the face's triangles.
    pub triangles: std::ops::Range<u32>,
}

impl Quad {
    /// The two triangles of the split the chart does not use (the other diagonal), oriented
    /// like the face. `own` is the chart's triangle list.
    pub fn other_split(&self, own: &[[u32; 3]]) -> [[u32; 3]; 2] {
        let [a, b, c, d] = self.vertices;
        let t = own[self.triangles[0] as usize];
        if t.contains(&a) && t.contains(&c) {
            [[a, b, d], [b, c, d]]
        } else {
            [[a, b, c], [a, c, d]]
        }
    }

    /// Both splits' four triangles: `(a, b, c), (a, c, d), (a, b, d), (b, c, d)`; all four are
    /// positive exactly when the quad is strictly convex with the chart's orientation.
    pub fn all_splits(&self) -> [[u32; 3]; 4] {
        let [a, b, c, d] = self.vertices;
        [[a, b, c], [a, c, d], [a, b, d], [b, c, d]]
    }
}

impl Chart {
    /// An elimination order of the chart's vertices (AMD of the graph of its triangles, a
    /// nested dissection from [`crate::solvers::ordering::ND_MIN_SIZE`] vertices),
    /// computed once and shared by the sparse systems solved over the chart (a start's LSCM,
    /// the method's own system, ABF++'s reduced system and its LSCM reconstruction): see
    /// [`crate::solvers::ordering::Ordering::Vertices`].
    pub fn vertex_order(&self) -> &[u32] {
        self.vertex_order.0.get_or_init(|| crate::solvers::ordering::vertex_order(self.positions.len(), &self.triangles))
    }

    /// A chart made of bare triangles, of no input face (`faces` and `corner_vertex` empty,
    /// `triangle_face` all 0): the coarse proxy a large chart's cones are planned on
    /// ([`crate::cuts::coarse`]), only solved on.
    pub(crate) fn proxy(
        positions: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        mesh_vertex: Vec<u32>,
        boundary_loops: Vec<Vec<u32>>,
        genus: usize,
        kind: ChartKind,
    ) -> Chart {
        Chart {
            faces: Vec::new(),
            corner_vertex: Vec::new(),
            mesh_vertex,
            positions,
            triangle_face: vec![0; triangles.len()],
            triangles,
            quads: Vec::new(),
            shown: Vec::new(),
            shown_face: Vec::new(),
            polygons: Vec::new(),
            boundary_loops,
            genus,
            kind,
            defect: None,
            vertex_order: VertexOrder::default(),
        }
    }

    /// A copy of the chart with its vertices moved to `positions` (the same triangles, so
    /// [`Chart::vertex_order`] carries over when known: a method's unit frame of a large
    /// piece would otherwise order it anew, about a second at 300k vertices).
    pub fn with_positions(&self, positions: Vec<[f64; 3]>) -> Chart {
        debug_assert_eq!(positions.len(), self.positions.len());
        let mut moved = self.clone();
        moved.positions = positions;
        if let Some(order) = self.vertex_order.0.get() {
            let _ = moved.vertex_order.0.set(order.clone());
        }
        moved
    }

    /// Take [`Chart::vertex_order`] from `parent`, a chart this one is a piece of (they share
    /// corners: a piece cut from it, or a half of a split), when the parent's is known and this
    /// chart is large (at least [`crate::solvers::ordering::ND_MIN_SIZE`] vertices, where an
    /// ordering costs about a second): the parent's order restricted to the piece, a vertex
    /// that the cut split in two taking its original's place (both copies together). Does
    /// nothing when the order of this chart is known already.
    pub fn inherit_vertex_order(&self, parent: &Chart) {
        let Some(order) = parent.vertex_order.0.get() else { return };
        let n = self.positions.len();
        let large = crate::solvers::ordering::OrderingKind::Auto.resolve(n) == crate::solvers::ordering::OrderingKind::NestedDissection;
        if self.vertex_order.0.get().is_some() || !large || order.len() != parent.positions.len() {
            return;
        }
        let mut rank = vec![u32::MAX; parent.positions.len()];
        for (r, &v) in order.iter().enumerate() {
            rank[v as usize] = r as u32;
        }
        let corners = parent.corner_vertex.iter().map(|&(c, _)| c as usize + 1).max().unwrap_or(0);
        let mut corner_rank = vec![u32::MAX; corners];
        for &(c, v) in &parent.corner_vertex {
            corner_rank[c as usize] = rank[v as usize];
        }
        drop(rank);
        // A vertex no corner of the parent reaches (none, for a piece) goes last.
        let mut key = vec![u32::MAX; n];
        for &(c, v) in &self.corner_vertex {
            if let Some(&r) = corner_rank.get(c as usize) {
                key[v as usize] = key[v as usize].min(r);
            }
        }
        let mut own: Vec<u32> = (0..n as u32).collect();
        own.sort_unstable_by_key(|&v| (key[v as usize], v));
        let _ = self.vertex_order.0.set(own);
    }

    /// The ordering for a sparse system over the chart's vertices that would compute one of
    /// `kind`: [`Chart::vertex_order`], shared, except on charts so small that their systems
    /// are factored dense (no ordering at all) and on charts with quads, whose systems differ
    /// in their graphs (the barrier methods couple both diagonals of a quad: an order of one
    /// split's graph gave SLIM's factor 4.6 times the fill on Suzanne's largest chart, and an
    /// order of both splits LSCM's 15% more).
    pub fn ordering(&self, kind: crate::solvers::ordering::OrderingKind) -> crate::solvers::ordering::Ordering<'_> {
        if !self.shares_ordering() {
            return kind.into();
        }
        crate::solvers::ordering::Ordering::Vertices { order: self.vertex_order(), kind }
    }

    /// [`Chart::ordering`] when the shared order was already computed (a method that shares
    /// it asked for it first), else `kind` computed for the system itself: a system solved
    /// alone (the `lscm` method) pays no more for the shared order than for its own.
    pub fn ordering_if_known(&self, kind: crate::solvers::ordering::OrderingKind) -> crate::solvers::ordering::Ordering<'_> {
        match self.vertex_order.0.get() {
            Some(order) if self.shares_ordering() => crate::solvers::ordering::Ordering::Vertices { order, kind },
            _ => kind.into(),
        }
    }

    /// Whether [`Chart::ordering`] shares the vertex order (see there).
    fn shares_ordering(&self) -> bool {
        self.quads.is_empty() && self.positions.len() > crate::solvers::DENSE_MAX / 2
    }

    /// The chart's triangles followed by the other diagonal's two triangles of every quad,
    /// and a weight per triangle (1, or ½ for the four triangles of a quad, so each quad
    /// weighs its area once): what a barrier method keeps positive so that quads stay
    /// strictly convex. Without quads, the chart's triangles with weight 1.
    pub fn triangles_both_splits(&self) -> (Vec<[u32; 3]>, Vec<f64>) {
        let mut tris = self.triangles.clone();
        let mut w = vec![1.0; tris.len()];
        for q in &self.quads {
            for &t in &q.triangles {
                w[t as usize] = 0.5;
            }
            for t in q.other_split(&self.triangles) {
                tris.push(t);
                w.push(0.5);
            }
        }
        (tris, w)
    }

    /// Average pinned UV per chart vertex that has a pinned corner. `pins` maps input corners
    /// to their pinned UV (only the pinned corners are in it, so an unwrap without pins costs
    /// nothing per corner).
    pub fn vertex_pins(&self, pins: &HashMap<u32, [f64; 2]>) -> Vec<(u32, [f64; 2])> {
        if pins.is_empty() {
            return Vec::new();
        }
        let mut acc: HashMap<u32, ([f64; 2], u32)> = HashMap::new();
        for &(c, v) in &self.corner_vertex {
            if let Some(&p) = pins.get(&c) {
                let e = acc.entry(v).or_insert(([0.0, 0.0], 0));
                e.0[0] += p[0];
                e.0[1] += p[1];
                e.1 += 1;
            }
        }
        let mut out: Vec<(u32, [f64; 2])> =
            acc.into_iter().map(|(v, (s, n))| (v, [s[0] / n as f64, s[1] / n as f64])).collect();
        out.sort_by_key(|p| p.0);
        out
    }

    /// Index of the longest boundary loop (3D length), the "outer" one.
    pub fn outer_loop(&self) -> Option<usize> {
        (0..self.boundary_loops.len()).max_by(|&a, &b| self.loop_length(a).total_cmp(&self.loop_length(b)))
    }

    /// 3D length of boundary loop `l`.
    pub fn loop_length(&self, l: usize) -> f64 {
        let lp = &self.boundary_loops[l];
        (0..lp.len())
            .map(|i| {
                let a = self.positions[lp[i] as usize];
                let b = self.positions[lp[(i + 1) % lp.len()] as usize];
                crate::geometry::norm(crate::geometry::sub(b, a))
            })
            .sum()
    }

    /// Whether each chart vertex lies on a boundary loop.
    pub fn boundary_mask(&self) -> Vec<bool> {
        let mut m = vec![false; self.positions.len()];
        for lp in &self.boundary_loops {
            for &v in lp {
                m[v as usize] = true;
            }
        }
        m
    }

    /// Check the chart's invariants; used by tests. Panics with a message on violation.
    pub fn sanity_check(&self) {
        let n = self.positions.len() as u32;
        assert_eq!(self.mesh_vertex.len(), self.positions.len());
        assert_eq!(self.triangles.len(), self.triangle_face.len());
        assert_eq!(self.shown.len(), self.shown_face.len());
        for t in &self.triangles {
            assert!(t.iter().all(|&v| v < n), "triangle vertex out of range");
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "degenerate triangle {t:?}");
        }
        if self.defect.is_none() {
            let mut directed = HashSet::new();
            for t in &self.triangles {
                for k in 0..3 {
                    assert!(directed.insert((t[k], t[(k + 1) % 3])), "directed edge twice");
                }
            }
            let mut seen = HashSet::new();
            for lp in &self.boundary_loops {
                assert!(lp.len() >= 2, "a boundary loop has at least two edges");
                for i in 0..lp.len() {
                    let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
                    assert!(directed.contains(&(a, b)), "loop edge is not a triangle edge");
                    assert!(seen.insert(a), "boundary loops share vertex {a}");
                }
            }

        }
    }
}

/// Disjoint sets over `0..n` with path halving; the smaller root wins a union, so roots (and
/// everything built on them) do not depend on the order of unions.
pub(crate) struct UnionFind(Vec<u32>);

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        UnionFind((0..n as u32).collect())
    }
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    /// Join the sets of `a` and `b`; whether they were apart.
    pub(crate) fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.0[hi as usize] = lo;
        true
    }
}

#[inline]
fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    ((lo as u64) << 32) | hi as u64
}

/// Split the selected faces of `mesh` into charts (see the module docs for the rules).
///
/// Charts are numbered by their smallest face index. Never fails: problems of a single chart
/// (non-orientable, non-manifold vertex) are recorded in [`Chart::defect`].
pub fn build_charts(mesh: &PolyMesh<'_>, seams: &[[u32; 2]], selected: Option<&[bool]>) -> Vec<Chart> {
    build_charts_with(mesh, seams, selected, None)
}

/// [`build_charts`] with the render triangulation of the faces (see [`FaceTriangulation`]):
/// faces of four or more corners are split the way it says instead of by ear clipping, except
/// where its diagonal already is an edge of the chart (two faces around a vertex shared by
/// only two faces), which would make the chart fold onto itself; such a face keeps the core's
/// own split (for quads the metrics and methods look at both diagonals anyway).
pub fn build_charts_with(
    mesh: &PolyMesh<'_>,
    seams: &[[u32; 2]],
    selected: Option<&[bool]>,
    render: Option<&FaceTriangulation>,
) -> Vec<Chart> {
    build_charts_counting(mesh, seams, selected, render).0
}

/// Edges of the selection that [`build_charts_counting`] cut although they are not seams.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CutEdges {
    /// Edges used by three or more selected faces.
    pub non_manifold: usize,
    /// Edges of two selected faces that traverse them in the same direction: the faces'
    /// normals point to opposite sides (one face is flipped, or the surface is one-sided
    /// like a Möbius strip).
    pub inconsistent: usize,
}

/// [`build_charts_with`], also returning how many edges that are not seams were cut
/// ([`CutEdges`]).
pub fn build_charts_counting(
    mesh: &PolyMesh<'_>,
    seams: &[[u32; 2]],
    selected: Option<&[bool]>,
    render: Option<&FaceTriangulation>,
) -> (Vec<Chart>, CutEdges) {
    let n_faces = mesh.n_faces();
    let n_corners = mesh.n_corners();
    let is_sel = |f: usize| selected.is_none_or(|s| s[f]);
    let seam_set: HashSet<u64> = seams.iter().map(|s| edge_key(s[0], s[1])).collect();

    // Corner → face.
    let mut corner_face = vec![0u32; n_corners];
    for f in 0..n_faces {
        for c in mesh.face_corners(f) {
            corner_face[c] = f as u32;
        }
    }
    // Edge records (key, corner starting the directed edge), selected faces only.
    let mut recs: Vec<(u64, u32)> = Vec::with_capacity(n_corners);
    for f in 0..n_faces {
        if !is_sel(f) {
            continue;
        }
        for c in mesh.face_corners(f) {
            let cn = mesh.next_corner(f, c);
            recs.push((edge_key(mesh.corner_vert(c), mesh.corner_vert(cn)), c as u32));
        }
    }
    recs.sort_unstable();

    // joined[c]: the polygon edge starting at corner c continues into another face of the chart.
    let mut joined = vec![false; n_corners];
    let mut face_uf = UnionFind::new(n_faces);
    let mut cut = CutEdges::default();
    let mut corner_uf = UnionFind::new(n_corners);
    let mut i = 0;
    while i < recs.len() {
        let mut j = i + 1;
        while j < recs.len() && recs[j].0 == recs[i].0 {
            j += 1;
        }
        if j - i > 2 {
            cut.non_manifold += 1;
        }
        if j - i == 2 && !seam_set.contains(&recs[i].0) {
            let c1 = recs[i].1 as usize;
            let c2 = recs[i + 1].1 as usize;
            let (f1, f2) = (corner_face[c1] as usize, corner_face[c2] as usize);
            let c1n = mesh.next_corner(f1, c1);
            let c2n = mesh.next_corner(f2, c2);
            // Opposite directions: c1 → c1n is c2n ← c2.
            if f1 != f2 && mesh.corner_vert(c1) == mesh.corner_vert(c2n) {
                face_uf.union(f1 as u32, f2 as u32);
                joined[c1] = true;
                joined[c2] = true;
                corner_uf.union(c1 as u32, c2n as u32);
                corner_uf.union(c1n as u32, c2 as u32);
            } else if f1 != f2 {
                cut.inconsistent += 1;
            }
        }
        i = j;
    }

    // Group faces into charts, numbered by smallest face.
    let mut chart_of_root: HashMap<u32, usize> = HashMap::new();
    let mut chart_faces: Vec<Vec<u32>> = Vec::new();
    for f in 0..n_faces {
        if !is_sel(f) {
            continue;
        }
        let r = face_uf.find(f as u32);
        let id = *chart_of_root.entry(r).or_insert_with(|| {
            chart_faces.push(Vec::new());
            chart_faces.len() - 1
        });
        chart_faces[id].push(f as u32);
    }
    let corner_root: Vec<u32> = (0..n_corners as u32).map(|c| corner_uf.find(c)).collect();

    use rayon::prelude::*;
    let charts = chart_faces.into_par_iter().map(|faces| make_chart(mesh, faces, &corner_root, &joined, render)).collect();
    (charts, cut)
}

fn make_chart(
    mesh: &PolyMesh<'_>,
    mut faces: Vec<u32>,
    corner_root: &[u32],
    joined: &[bool],
    render: Option<&FaceTriangulation>,
) -> Chart {
    let positions_in = mesh.positions();
    // A chart lives through the whole solve: its per-corner and per-triangle arrays are
    // allocated at their final size (no growth slack), the others shrunk to fit at the end.
    faces.shrink_to_fit();
    let n_chart_corners: usize = faces.iter().map(|&f| mesh.face_corners(f as usize).len()).sum();
    let n_chart_triangles = n_chart_corners - 2 * faces.len();
    let mut local_of_root: HashMap<u32, u32> = HashMap::new();
    let mut mesh_vertex = Vec::new();
    let mut positions = Vec::new();
    let mut corner_vertex = Vec::with_capacity(n_chart_corners);
    let mut triangles = Vec::with_capacity(n_chart_triangles);
    let mut triangle_face = Vec::with_capacity(n_chart_triangles);
    let mut quads = Vec::new();
    let mut polygons = Vec::new();
    let mut shown: Vec<[u32; 3]> = Vec::new();
    let mut shown_face: Vec<u32> = Vec::new();
    // Boundary half-edges (chart vertex a → b): polygon edges not joined to another face.
    let mut boundary_edges: Vec<(u32, u32)> = Vec::new();
    // First pass: chart vertices of every corner, and the chart's polygon edges.
    let mut edges: HashSet<u64> = HashSet::new();
    let ukey = |a: u32, b: u32| ((a.min(b) as u64) << 32) | a.max(b) as u64;
    let mut face_local: Vec<u32> = Vec::with_capacity(n_chart_corners);
    let has_ngon = faces.iter().any(|&f| mesh.face_corners(f as usize).len() > 3);
    for &f in &faces {
        let r = mesh.face_corners(f as usize);
        let first = face_local.len();
        for c in r.clone() {
            let v = mesh.corner_vert(c);
            let id = *local_of_root.entry(corner_root[c]).or_insert_with(|| {
                mesh_vertex.push(v);
                positions.push(positions_in[v as usize]);
                (mesh_vertex.len() - 1) as u32
            });
            corner_vertex.push((c as u32, id));
            face_local.push(id);
        }
        let m = face_local.len() - first;
        for i in 0..m {
            let (a, b) = (face_local[first + i], face_local[first + (i + 1) % m]);
            if has_ngon {
                edges.insert(ukey(a, b));
            }
            if !joined[r.start + i] {
                boundary_edges.push((a, b));
            }
        }
    }
    // Faces per interior chart vertex (for quads around a vertex shared by only two faces);
    // boundary vertices are marked u32::MAX.
    let mut valence = vec![0u32; positions.len()];
    if has_ngon {
        for &v in &face_local {
            valence[v as usize] += 1;
        }
        for &(a, b) in &boundary_edges {
            valence[a as usize] = u32::MAX;
            valence[b as usize] = u32::MAX;
        }
    }
    // Second pass: triangulate, keeping diagonals off edges that exist already.
    let mut poly_pts: Vec<[f64; 3]> = Vec::new();
    let mut offset = 0usize;
    for &f in &faces {
        let r = mesh.face_corners(f as usize);
        let m = r.len();
        let local = &face_local[offset..offset + m];
        offset += m;
        if m == 3 {
            triangles.push([local[0], local[1], local[2]]);
            triangle_face.push(f);
            continue;
        }
        poly_pts.clear();
        poly_pts.extend(r.map(|c| positions_in[mesh.corner_vert(c) as usize]));
        // A quad at a vertex inside the chart shared by only two faces is split through that
        // vertex whatever the render triangulation says (see `through` below): no flat map
        // keeps the other split positive there.
        let two_face = m == 4 && local.iter().any(|&v| valence[v as usize] == 2);
        let given: Option<Vec<[usize; 3]>> = render.filter(|_| !two_face).and_then(|r| {
            let tris: Vec<[usize; 3]> =
                r.face(f as usize).iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
            let taken = tris.iter().any(|t| {
                (0..3).any(|k| {
                    let (i, j) = (t[k], t[(k + 1) % 3]);
                    (i + 1) % m != j && (j + 1) % m != i && edges.contains(&ukey(local[i], local[j]))
                })
            });
            if taken && m >= 5 {
                shown.extend(tris.iter().map(|t| [local[t[0]], local[t[1]], local[t[2]]]));
                shown_face.extend(std::iter::repeat_n(f, tris.len()));
            }
            (!taken).then_some(tris)
        });
        let tris = given.unwrap_or_else(|| {
            let through = if m == 4 { (0..4).find(|&k| valence[local[k] as usize] == 2) } else { None };
            triangulate_polygon_with(&poly_pts, |i, j| edges.contains(&ukey(local[i], local[j])), through)
        });
        // A vertex inside the chart shared by only two faces has its two corner angles sum to
        // 2π, so one of them is at least π: such quads cannot be strictly convex and keep
        // only their own split (split through that vertex, see above).
        if tris.len() == m - 2 && local.iter().all(|&v| valence[v as usize] != 2) {
            let n = triangles.len() as u32;
            polygons.push(Polygon { vertices: local.to_vec(), triangles: n..n + (m - 2) as u32 });
        }
        // Quads not clearly convex in 3D keep only their own split too (see `convex_quad`).
        if m == 4
            && tris.len() == 2
            && !two_face
            && convex_quad(&[poly_pts[0], poly_pts[1], poly_pts[2], poly_pts[3]])
        {
            let n = triangles.len() as u32;
            quads.push(Quad { vertices: [local[0], local[1], local[2], local[3]], triangles: [n, n + 1] });
        }
        for t in tris {
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                if (i + 1) % m != j && (j + 1) % m != i {
                    edges.insert(ukey(local[i], local[j]));
                }
            }
            triangles.push([local[t[0]], local[t[1]], local[t[2]]]);
            triangle_face.push(f);
        }
    }

    // A directed edge used twice means the chart is non-orientable (or folds onto itself).
    let nv = positions.len();
    let mut keys: Vec<u64> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| ((t[k] as u64) << 32) | t[(k + 1) % 3] as u64))
        .collect();
    keys.sort_unstable();
    let mut defect = keys.windows(2).find(|w| w[0] == w[1]).map(|w| {
        let (a, b) = ((w[0] >> 32) as usize, (w[0] & 0xffff_ffff) as usize);
        format!(
            "chart is non-orientable or folds onto itself at mesh edge {}-{}: add a seam there",
            mesh_vertex[a], mesh_vertex[b]
        )
    });
    drop(keys);
    let mut out_boundary: Vec<u32> = vec![u32::MAX; nv];
    let n_boundary = boundary_edges.len();
    let n_interior_half = 3 * triangles.len() - n_boundary;
    for &(a, b) in &boundary_edges {
        if out_boundary[a as usize] != u32::MAX && defect.is_none() {
            defect = Some(format!(
                "mesh vertex {} is non-manifold inside the chart: add a seam through it",
                mesh_vertex[a as usize]
            ));
        }
        out_boundary[a as usize] = b;
    }
    let mut boundary_loops = Vec::new();
    if defect.is_none() {
        let mut visited = vec![false; nv];
        for s in 0..nv {
            if out_boundary[s] == u32::MAX || visited[s] {
                continue;
            }
            let mut lp = Vec::new();
            let mut v = s as u32;
            while !visited[v as usize] {
                visited[v as usize] = true;
                lp.push(v);
                v = out_boundary[v as usize];
                if v == u32::MAX {
                    break;
                }
            }
            if v != s as u32 {
                defect = Some(format!("boundary at mesh vertex {} does not close", mesh_vertex[s]));
                break;
            }
            // Canonical start: the smallest mesh vertex (independent of face order).
            let k = (0..lp.len()).min_by_key(|&i| (mesh_vertex[lp[i] as usize], lp[i])).unwrap();
            lp.rotate_left(k);
            boundary_loops.push(lp);
        }
    }
    let n_edges = n_interior_half / 2 + n_boundary;
    let chi = nv as i64 - n_edges as i64 + triangles.len() as i64;
    let b = boundary_loops.len() as i64;
    let two_g = 2 - chi - b;
    let genus = if defect.is_none() && two_g > 0 { (two_g / 2) as usize } else { 0 };
    let kind = if genus > 0 {
        ChartKind::HigherGenus
    } else if b == 0 {
        ChartKind::Closed
    } else if b == 1 {
        ChartKind::Disk
    } else {
        ChartKind::DiskWithHoles
    };
    mesh_vertex.shrink_to_fit();
    positions.shrink_to_fit();
    triangles.shrink_to_fit();
    triangle_face.shrink_to_fit();
    Chart {
        faces,
        corner_vertex,
        mesh_vertex,
        positions,
        triangles,
        triangle_face,
        quads,
        shown,
        shown_face,
        polygons,
        boundary_loops,
        genus,
        kind,
        defect,
        vertex_order: VertexOrder::default(),
    }
}

/// Tests only: the one chart of a `k × k` vertex grid over the unit square, each cell split
/// into two triangles, lifted onto a saddle with ripples (not developable).
#[cfg(test)]
pub(crate) fn bumpy_grid_chart(k: u32) -> Chart {
    let mut positions = Vec::new();
    for j in 0..k {
        for i in 0..k {
            let (x, y) = (i as f64 / (k - 1) as f64, j as f64 / (k - 1) as f64);
            positions.push([x, y, 0.3 * (x * x - y * y) + 0.05 * (9.0 * x).sin() * (7.0 * y).cos()]);
        }
    }
    let mut corners = Vec::new();
    for j in 0..k - 1 {
        for i in 0..k - 1 {
            let v = j * k + i;
            corners.extend([v, v + 1, v + k + 1, v, v + k + 1, v + k]);
        }
    }
    let sizes = vec![3u32; corners.len() / 3];
    let mesh = PolyMesh::new(&positions, &corners, &sizes).expect("a valid grid");
    build_charts(&mesh, &[], None).remove(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64, j as f64, 0.0]);
            }
        }
        let mut cv = Vec::new();
        let mut fs = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                cv.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                fs.push(4);
            }
        }
        (p, cv, fs)
    }

    #[test]
    fn quad_grid_is_one_disk() {
        let (p, cv, fs) = grid(4);
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        let charts = build_charts(&m, &[], None);
        assert_eq!(charts.len(), 1);
        let c = &charts[0];
        c.sanity_check();
        assert_eq!(c.kind, ChartKind::Disk);
        assert_eq!(c.positions.len(), 25);
        assert_eq!(c.triangles.len(), 32);
        assert_eq!(c.boundary_loops[0].len(), 16);
    }

    #[test]
    fn seam_across_grid_splits_it_and_a_partial_seam_is_a_slit() {
        let (p, cv, fs) = grid(4);
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        // Full vertical cut at x = 2.
        let full: Vec<[u32; 2]> = (0..4).map(|j| [(j * 5 + 2) as u32, ((j + 1) * 5 + 2) as u32]).collect();
        let charts = build_charts(&m, &full, None);
        assert_eq!(charts.len(), 2);
        // Slit from the bottom edge to the middle: one chart, one loop, vertices duplicated.
        let slit = &full[..2];
        let charts = build_charts(&m, slit, None);
        assert_eq!(charts.len(), 1);
        charts[0].sanity_check();
        assert_eq!(charts[0].kind, ChartKind::Disk);
        assert_eq!(charts[0].positions.len(), 25 + 2);
    }

    #[test]
    fn selection_border_splits_and_unselected_faces_are_ignored() {
        let (p, cv, fs) = grid(3);
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        let mut sel = vec![true; 9];
        sel[4] = false; // centre face out: an annulus
        let charts = build_charts(&m, &[], Some(&sel));
        assert_eq!(charts.len(), 1);
        charts[0].sanity_check();
        assert_eq!(charts[0].kind, ChartKind::DiskWithHoles);
        assert!(!charts[0].faces.contains(&4));
    }

    #[test]
    fn closed_cube_is_closed_and_non_manifold_edges_are_cuts() {
        let p = vec![
            [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0],
        ];
        let cv: Vec<u32> = vec![0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7];
        let fs = vec![4u32; 6];
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        let charts = build_charts(&m, &[], None);
        assert_eq!(charts.len(), 1);
        charts[0].sanity_check();
        assert_eq!(charts[0].kind, ChartKind::Closed);
        // A fin: a third face on edge 0-1 makes it non-manifold; the fin is its own chart.
        let mut p2 = p.clone();
        p2.push([0.5, -1.0, 0.0]);
        let mut cv2 = cv.clone();
        cv2.extend([0, 1, 8]);
        let mut fs2 = fs.clone();
        fs2.push(3);
        let m2 = PolyMesh::new(&p2, &cv2, &fs2).unwrap();
        let charts = build_charts(&m2, &[], None);
        assert_eq!(charts.len(), 2, "the cube stays connected, the fin is alone");
        for c in &charts {
            c.sanity_check();
        }
        // Cutting one edge of a closed cube opens a two-edge slit: a disk.
        assert_eq!(charts[0].kind, ChartKind::Disk);
        assert_eq!(charts[0].boundary_loops[0].len(), 2);
    }
}
