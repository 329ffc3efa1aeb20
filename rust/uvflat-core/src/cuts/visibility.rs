//! Per-vertex ambient occlusion: how hidden each vertex of a chart is, as a proxy for where an
//! artist would hide a seam (inside the legs, under the belly, behind the ears).
//!
//! Precedent: ambient occlusion (Zhukov, Iones & Kronin 1998; Landis 2002), baked per vertex as
//! in mesh-processing tools (MeshLab's "ambient occlusion per vertex", libigl's
//! `ambient_occlusion`); seam placement by visibility as in Zhang et al. 2005 ("Feature-based
//! surface parameterization and texture mapping") and the "hidden seams" cost of
//! Liu, Ferguson et al.'s Seamless (2017) and PartUV-style segmenters.
//!
//! For every vertex: [`RAYS`] directions of a spherical Fibonacci set on the hemisphere of the
//! vertex normal (angle-weighted normal of its triangles), cosine-distributed (Marques et al.
//! 2013), rotated into a frame built from the normal alone (Duff et al. 2017); each ray leaves
//! the vertex a hair's breadth along the normal and is tested against the chart's triangles
//! up to a distance of [`RANGE`] × the chart's bounding-box diagonal. The occlusion is the
//! share of rays that hit something; the visibility is `1 − occlusion`. A convex vertex sees
//! nothing of its own surface (0 occlusion); the bottom of a deep groove is mostly occluded.
//!
//! The triangles sit in a bounding volume hierarchy ([`Bvh`]: axis-aligned boxes, split at
//! the median of the triangle centroids along the longest axis of their bounds, leaves of at
//! most 4 triangles); a ray stops at its first hit (an occlusion query needs no nearest hit).
//! (A binned surface-area-heuristic split measured no faster here: rays leave the surface, and
//! their time goes to the boxes around their origin either way.)
//!
//! Occluders: every triangle of the mesh near the chart (within the rays' range of its
//! bounding box), so other parts of the mesh shade it too.
//!
//! Orientation: normals follow the triangles' winding. A mesh wound inwards (negative signed
//! volume) is read as if wound outwards, so its cavities still face out.
//!
//! Preconditions: finite positions. Failures: none; a vertex without a usable normal (all its
//! triangles degenerate) gets occlusion 0. Deterministic and identical across thread counts:
//! fixed directions, a tree built serially, each vertex computed on its own (rayon over
//! vertices, results in vertex order).

use rayon::prelude::*;

use crate::charts::Chart;
use crate::geometry::{bounds, cross, dot, norm, sub};
use crate::mesh::PolyMesh;

/// Rays per vertex.
pub const RAYS: usize = 32;
/// Longest ray, as a share of the chart's bounding-box diagonal.
pub const RANGE: f64 = 0.3;
/// Most triangles in a leaf of the tree.
const LEAF: usize = 4;

/// A bounding volume hierarchy over triangles, for occlusion queries.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    triangles: Vec<[[f64; 3]; 3]>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: first triangle; inner node: index of its first child (the second is next).
    start: u32,
    /// Leaf: number of triangles; inner node: 0.
    count: u32,
}

impl Bvh {
    /// Build the tree over `triangles` (corner positions). Median splits along the longest
    /// axis of the centroids' box (ties by triangle id); each triangle's centroid and box sit
    /// beside its id, so a split reads one contiguous slice (no lookups scattered over the
    /// triangle list: at 576k triangles the build took a second that way).
    pub fn new(triangles: Vec<[[f64; 3]; 3]>) -> Bvh {
        #[derive(Clone, Copy)]
        struct Item {
            centroid: [f64; 3],
            lo: [f64; 3],
            hi: [f64; 3],
            id: u32,
        }
        let n = triangles.len();
        let mut items: Vec<Item> = triangles
            .iter()
            .enumerate()
            .map(|(id, t)| {
                let (lo, hi) = bounds(t.iter());
                let centroid = [(t[0][0] + t[1][0] + t[2][0]) / 3.0, (t[0][1] + t[1][1] + t[2][1]) / 3.0, (t[0][2] + t[1][2] + t[2][2]) / 3.0];
                Item { centroid, lo, hi, id: id as u32 }
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * n.div_ceil(LEAF).max(1));
        if n > 0 {
            // Explicit stack of (node index, range) to fill.
            nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
            let mut stack: Vec<(usize, usize, usize)> = vec![(0, 0, n)];
            while let Some((id, a, b)) = stack.pop() {
                let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for it in &items[a..b] {
                    for k in 0..3 {
                        lo[k] = lo[k].min(it.lo[k]);
                        hi[k] = hi[k].max(it.hi[k]);
                        clo[k] = clo[k].min(it.centroid[k]);
                        chi[k] = chi[k].max(it.centroid[k]);
                    }
                }
                nodes[id].lo = lo;
                nodes[id].hi = hi;
                if b - a <= LEAF {
                    nodes[id].start = a as u32;
                    nodes[id].count = (b - a) as u32;
                    continue;
                }
                let axis = (0..3).max_by(|&i, &j| (chi[i] - clo[i]).total_cmp(&(chi[j] - clo[j])).then(j.cmp(&i))).unwrap_or(0);
                if !(chi[axis] - clo[axis] > 0.0) {
                    nodes[id].start = a as u32;
                    nodes[id].count = (b - a) as u32;
                    continue;
                }
                let mid = (a + b) / 2;
                items[a..b].select_nth_unstable_by(mid - a, |x, y| x.centroid[axis].total_cmp(&y.centroid[axis]).then(x.id.cmp(&y.id)));
                let left = nodes.len();
                nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
                let right = nodes.len();
                nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
                debug_assert_eq!(left, right - 1);
                nodes[id].start = left as u32;
                nodes[id].count = 0;
                stack.push((right, mid, b));
                stack.push((left, a, mid));
            }
        }
        let triangles = items.iter().map(|it| triangles[it.id as usize]).collect();
        Bvh { nodes, triangles }
    }

    /// Whether the ray `origin + t·dir`, `0 < t < t_max`, hits a triangle.
    pub fn occluded(&self, origin: [f64; 3], dir: [f64; 3], t_max: f64) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv = [1.0 / dir[0], 1.0 / dir[1], 1.0 / dir[2]];
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !hits_box(node, origin, inv, t_max) {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                for t in &self.triangles[s..s + node.count as usize] {
                    if hits_triangle(t, origin, dir, t_max) {
                        return true;
                    }
                }
            } else if top + 2 <= stack.len() {
                // Children: the first is the node after the parent's slot in `start`.
                stack[top] = node.start + 1;
                stack[top + 1] = node.start;
                top += 2;
            }
        }
        false
    }
}

/// Slab test of a ray against a node's box.
#[inline]
fn hits_box(node: &Node, o: [f64; 3], inv: [f64; 3], t_max: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for k in 0..3 {
        let a = (node.lo[k] - o[k]) * inv[k];
        let b = (node.hi[k] - o[k]) * inv[k];
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        // NaN (0 · ∞ on a slab's plane) keeps the interval as it is.
        if a > t0 {
            t0 = a;
        }
        if b < t1 {
            t1 = b;
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Möller–Trumbore: whether the ray hits triangle `t` at `0 < s < t_max` (both sides count).
#[inline]
fn hits_triangle(t: &[[f64; 3]; 3], o: [f64; 3], d: [f64; 3], t_max: f64) -> bool {
    let e1 = sub(t[1], t[0]);
    let e2 = sub(t[2], t[0]);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-300 {
        return false;
    }
    let inv = 1.0 / det;
    let s = sub(o, t[0]);
    let u = dot(s, p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let dist = dot(e2, q) * inv;
    dist > 0.0 && dist < t_max
}

/// Angle-weighted vertex normals of `triangles` over `positions` (unit, or zero where every
/// triangle at the vertex is degenerate).
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0f64; 3]; positions.len()];
    for t in triangles {
        let p = [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
        let fnorm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        let l = norm(fnorm);
        if !(l > 0.0) {
            continue;
        }
        let angles = crate::geometry::raw_angles(p);
        for k in 0..3 {
            if !angles[k].is_finite() {
                continue;
            }
            for c in 0..3 {
                n[t[k] as usize][c] += angles[k] * fnorm[c] / l;
            }
        }
    }
    for v in &mut n {
        let l = norm(*v);
        *v = if l > 0.0 { [v[0] / l, v[1] / l, v[2] / l] } else { [0.0; 3] };
    }
    n
}

/// Signed volume enclosed by `triangles` (positive for a closed surface wound outwards).
pub fn signed_volume(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| dot(positions[t[0] as usize], cross(positions[t[1] as usize], positions[t[2] as usize])) / 6.0)
        .sum()
}

/// `count` unit directions around +z, cosine-distributed on the upper hemisphere (a
/// spherical Fibonacci set: area-uniform on the unit disk, lifted to the hemisphere).
pub fn hemisphere_directions(count: usize) -> Vec<[f64; 3]> {
    let golden = (5.0f64.sqrt() - 1.0) / 2.0;
    (0..count)
        .map(|i| {
            let u = (i as f64 + 0.5) / count as f64;
            let r = u.sqrt();
            let phi = std::f64::consts::TAU * (i as f64 * golden).fract();
            [r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt()]
        })
        .collect()
}

/// An orthonormal frame `(t, b)` completing unit `n` (Duff et al. 2017).
fn frame(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let sign = if n[2] >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n[2]);
    let b = n[0] * n[1] * a;
    ([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]], [b, sign + n[1] * n[1] * a, -n[1]])
}

/// Ambient occlusion (share of blocked rays, in `[0, 1]`) of every vertex of the surface
/// `triangles` over `positions`, the surface its own occluder (see the module docs; `rays` per
/// vertex, rays up to `range` long). A closed surface wound inwards is read as wound outwards.
pub fn ambient_occlusion(positions: &[[f64; 3]], triangles: &[[u32; 3]], rays: usize, range: f64) -> Vec<f64> {
    let mut normals = vertex_normals(positions, triangles);
    if is_closed(triangles) && signed_volume(positions, triangles) < 0.0 {
        for v in &mut normals {
            *v = [-v[0], -v[1], -v[2]];
        }
    }
    let bvh = Bvh::new(triangles.iter().map(|t| [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]]).collect());
    occlusion_at(&bvh, positions, &normals, rays, range)
}

/// Share of `rays` blocked by `bvh` within `range`, from each point along the hemisphere of its
/// unit normal (0 where the normal is zero).
pub fn occlusion_at(bvh: &Bvh, points: &[[f64; 3]], normals: &[[f64; 3]], rays: usize, range: f64) -> Vec<f64> {
    let n = points.len();
    if rays == 0 || !(range > 0.0 && range.is_finite()) {
        return vec![0.0; n];
    }
    let dirs = hemisphere_directions(rays);
    let lift = 1e-6 * range;
    (0..n)
        .into_par_iter()
        .with_min_len(64)
        .map(|v| {
            let nv = normals[v];
            if nv == [0.0; 3] {
                return 0.0;
            }
            let (t, b) = frame(nv);
            let p = points[v];
            let origin = [p[0] + lift * nv[0], p[1] + lift * nv[1], p[2] + lift * nv[2]];
            let hits = dirs
                .iter()
                .filter(|d| {
                    let dir = [
                        d[0] * t[0] + d[1] * b[0] + d[2] * nv[0],
                        d[0] * t[1] + d[1] * b[1] + d[2] * nv[1],
                        d[0] * t[2] + d[1] * b[2] + d[2] * nv[2],
                    ];
                    bvh.occluded(origin, dir, range)
                })
                .count();
            hits as f64 / rays as f64
        })
        .collect()
}

/// Whether every edge of `triangles` is shared by exactly two of them.
fn is_closed(triangles: &[[u32; 3]]) -> bool {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    !edges.is_empty() && edges.chunk_by(|x, y| x == y).all(|run| run.len() == 2)
}

/// Whether `mesh` is wound inwards: the signed volume of its polygons (fans) about the mean of
/// its vertices is negative. Meaningful for closed or nearly closed meshes; open sheets come
/// out either way, and only the side their normals face is then taken as the outside.
pub fn wound_inward(mesh: &PolyMesh<'_>) -> bool {
    let p = mesh.positions();
    if p.is_empty() {
        return false;
    }
    let mut c = [0.0; 3];
    for q in p {
        for k in 0..3 {
            c[k] += q[k] / p.len() as f64;
        }
    }
    let mut volume = 0.0;
    for f in 0..mesh.n_faces() {
        let corners = mesh.face_corners(f);
        let first = sub(p[mesh.corner_vert(corners.start) as usize], c);
        for k in corners.start + 1..corners.end.saturating_sub(1) {
            let (a, b) = (sub(p[mesh.corner_vert(k) as usize], c), sub(p[mesh.corner_vert(k + 1) as usize], c));
            volume += dot(first, cross(a, b));
        }
    }
    volume < 0.0
}

/// Visibility (`1 −` ambient occlusion) of every vertex of `chart`: [`RAYS`] rays up to
/// [`RANGE`] × the chart's bounding-box diagonal, against every triangle (fan of a polygon) of
/// `mesh` whose box meets the chart's box grown by that range, so nearby parts of the mesh
/// shade the chart too. `inward`: the mesh is wound inwards ([`wound_inward`]), and the
/// outside is behind the triangles' normals.
pub fn chart_visibility(mesh: &PolyMesh<'_>, chart: &Chart, inward: bool) -> Vec<f64> {
    chart_visibility_sampled(mesh, chart, inward, SAMPLES)
}

/// [`chart_visibility`] with rays cast from at most about `max_samples` vertices: on a larger
/// chart, one vertex per cell of a grid sized for that many cells on the chart's surface (the
/// lowest vertex id in the cell), every other vertex taking the value of the sample nearest
/// it in edge hops (a breadth-first search from all samples at once, in sample order).
/// Occlusion varies over the scale of the rays' range, far coarser than a scan's triangles,
/// so the samples lose little while the rays' cost stops growing with the mesh.
pub fn chart_visibility_sampled(mesh: &PolyMesh<'_>, chart: &Chart, inward: bool, max_samples: usize) -> Vec<f64> {
    let n = chart.positions.len();
    let (lo, hi) = bounds(chart.positions.iter());
    let range = RANGE * norm(sub(hi, lo));
    if !(range > 0.0 && range.is_finite()) {
        return vec![1.0; n];
    }
    let (glo, ghi) = ([lo[0] - range, lo[1] - range, lo[2] - range], [hi[0] + range, hi[1] + range, hi[2] + range]);
    let p = mesh.positions();
    let mut occluders = Vec::new();
    for f in 0..mesh.n_faces() {
        let corners = mesh.face_corners(f);
        let first = p[mesh.corner_vert(corners.start) as usize];
        for k in corners.start + 1..corners.end.saturating_sub(1) {
            let t = [first, p[mesh.corner_vert(k) as usize], p[mesh.corner_vert(k + 1) as usize]];
            let (tlo, thi) = bounds(t.iter());
            if (0..3).all(|d| tlo[d] <= ghi[d] && thi[d] >= glo[d]) {
                occluders.push(t);
            }
        }
    }
    let mut normals = vertex_normals(&chart.positions, &chart.triangles);
    if inward {
        for v in &mut normals {
            *v = [-v[0], -v[1], -v[2]];
        }
    }
    let bvh = Bvh::new(occluders);
    let Some(samples) = grid_samples(chart, max_samples) else {
        return occlusion_at(&bvh, &chart.positions, &normals, RAYS, range).into_iter().map(|a| 1.0 - a).collect();
    };
    let points: Vec<[f64; 3]> = samples.iter().map(|&v| chart.positions[v as usize]).collect();
    let sample_normals: Vec<[f64; 3]> = samples.iter().map(|&v| normals[v as usize]).collect();
    let occ = occlusion_at(&bvh, &points, &sample_normals, RAYS, range);
    spread_from_samples(chart, &samples, &occ).into_iter().map(|a| 1.0 - a).collect()
}

/// Most vertices of a chart that cast their own rays ([`chart_visibility_sampled`]).
pub const SAMPLES: usize = 12_000;

/// One vertex per occupied cell of a grid whose cells are sized so the chart's surface meets
/// about `max_samples` of them (the lowest vertex id in each cell, in increasing order), or
/// `None` when the chart has at most `max_samples` vertices.
fn grid_samples(chart: &Chart, max_samples: usize) -> Option<Vec<u32>> {
    let n = chart.positions.len();
    if n <= max_samples.max(1) {
        return None;
    }
    let area: f64 = chart
        .triangles
        .iter()
        .map(|t| {
            let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
            0.5 * norm(cross(sub(p[1], p[0]), sub(p[2], p[0])))
        })
        .sum();
    // A surface crosses about 1.5 cells per cell-face of its area (it runs at a slant).
    let h = (1.5 * area / max_samples as f64).sqrt();
    if !(h > 0.0 && h.is_finite()) {
        return None;
    }
    let (lo, _) = bounds(chart.positions.iter());
    let mut cells: std::collections::HashMap<[i64; 3], u32> = std::collections::HashMap::new();
    for (v, p) in chart.positions.iter().enumerate() {
        let key = [((p[0] - lo[0]) / h) as i64, ((p[1] - lo[1]) / h) as i64, ((p[2] - lo[2]) / h) as i64];
        cells.entry(key).or_insert(v as u32);
    }
    let mut samples: Vec<u32> = cells.into_values().collect();
    samples.sort_unstable();
    Some(samples)
}

/// Per chart vertex, the value of the sample fewest edges away (`values[k]` belongs to
/// `samples[k]`; ties go to the sample reached first in sample order). A vertex no sample
/// reaches (a chart in several pieces would have one) gets 0.
fn spread_from_samples(chart: &Chart, samples: &[u32], values: &[f64]) -> Vec<f64> {
    let n = chart.positions.len();
    let mut start = vec![0u32; n + 1];
    for t in &chart.triangles {
        for &v in t {
            start[v as usize + 1] += 2;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[n] as usize];
    for t in &chart.triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            for w in [b, c] {
                adj[fill[a as usize] as usize] = w;
                fill[a as usize] += 1;
            }
        }
    }
    let mut out = vec![f64::NAN; n];
    let mut queue = std::collections::VecDeque::with_capacity(n);
    for (k, &s) in samples.iter().enumerate() {
        out[s as usize] = values[k];
        queue.push_back(s);
    }
    while let Some(v) = queue.pop_front() {
        let x = out[v as usize];
        for &w in &adj[start[v as usize] as usize..start[v as usize + 1] as usize] {
            if out[w as usize].is_nan() {
                out[w as usize] = x;
                queue.push_back(w);
            }
        }
    }
    for x in &mut out {
        if x.is_nan() {
            *x = 0.0;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_hits_the_triangle_in_front_and_not_the_one_behind_or_beyond_range() {
        let tri = [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]];
        let bvh = Bvh::new(vec![tri]);
        assert!(bvh.occluded([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 2.0));
        assert!(!bvh.occluded([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5));
        assert!(!bvh.occluded([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 2.0));
        assert!(!bvh.occluded([5.0, 0.0, 0.0], [0.0, 0.0, 1.0], 2.0));
    }

    #[test]
    fn the_tree_answers_like_brute_force() {
        // A strip of 200 triangles in a wave; rays from a grid of points in many directions.
        let mut tris = Vec::new();
        for i in 0..100 {
            let x0 = i as f64 * 0.1;
            let x1 = x0 + 0.1;
            let z = |x: f64| (3.0 * x).sin();
            tris.push([[x0, 0.0, z(x0)], [x1, 0.0, z(x1)], [x0, 1.0, z(x0)]]);
            tris.push([[x1, 0.0, z(x1)], [x1, 1.0, z(x1)], [x0, 1.0, z(x0)]]);
        }
        let bvh = Bvh::new(tris.clone());
        let dirs = hemisphere_directions(16);
        let mut agree = 0;
        for i in 0..20 {
            for d in &dirs {
                let o = [i as f64 * 0.5, 0.5, -2.0 + 0.1 * i as f64];
                let brute = tris.iter().any(|t| hits_triangle(t, o, *d, 3.0));
                assert_eq!(bvh.occluded(o, *d, 3.0), brute, "origin {o:?} dir {d:?}");
                agree += brute as usize;
            }
        }
        assert!(agree > 0, "no ray hit at all: the comparison proves nothing");
    }

    #[test]
    fn directions_are_unit_and_in_the_upper_hemisphere_with_a_cosine_mean() {
        let d = hemisphere_directions(256);
        for v in &d {
            assert!((norm(*v) - 1.0).abs() < 1e-12 && v[2] > 0.0);
        }
        // For a cosine distribution, E[cos θ] = 2/3.
        let mean = d.iter().map(|v| v[2]).sum::<f64>() / d.len() as f64;
        assert!((mean - 2.0 / 3.0).abs() < 0.01, "{mean}");
    }

    #[test]
    fn the_frame_is_orthonormal() {
        for n in [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.6, 0.0, 0.8], [0.0, -0.6, -0.8], [1.0, 0.0, 0.0]] {
            let (t, b) = frame(n);
            assert!((norm(t) - 1.0).abs() < 1e-12 && (norm(b) - 1.0).abs() < 1e-12);
            assert!(dot(t, b).abs() < 1e-12 && dot(t, n).abs() < 1e-12 && dot(b, n).abs() < 1e-12);
        }
    }
}

/// Visibility remembered per mesh corner, so the pieces of a chart (repair's halves and their
/// halves) reuse the rays cast for the chart instead of casting them again.
///
/// Keyed by corner: a corner belongs to one face, so one input chart, and charts solved in
/// parallel never write the same entry (the result does not depend on the thread count). A
/// piece's vertex takes the value of its corners, all cast from the same vertex of the chart
/// the piece came from.
///
/// It also keeps [`wound_inward`] of the mesh, a pass over every face, made once per unwrap
/// rather than once per chart cut.
#[derive(Debug)]
pub struct VisibilityCache(std::sync::Mutex<Vec<f64>>, std::sync::OnceLock<bool>);

impl VisibilityCache {
    /// An empty cache for a mesh of `n_corners` corners.
    pub fn new(n_corners: usize) -> Self {
        VisibilityCache(std::sync::Mutex::new(vec![f64::NAN; n_corners]), std::sync::OnceLock::new())
    }

    /// [`wound_inward`] of `mesh` (the mesh this cache was made for), computed once.
    pub fn inward(&self, mesh: &PolyMesh<'_>) -> bool {
        *self.1.get_or_init(|| wound_inward(mesh))
    }

    /// [`chart_visibility`] of `chart`, from the cache when every corner of the chart is known.
    pub fn chart(&self, mesh: &PolyMesh<'_>, chart: &Chart, inward: bool) -> Vec<f64> {
        {
            let known = self.0.lock().unwrap_or_else(|e| e.into_inner());
            let mut out = vec![f64::NAN; chart.positions.len()];
            let mut all = true;
            for &(c, v) in &chart.corner_vertex {
                match known.get(c as usize) {
                    Some(x) if x.is_finite() => out[v as usize] = *x,
                    _ => {
                        all = false;
                        break;
                    }
                }
            }
            if all && out.iter().all(|x| x.is_finite()) {
                return out;
            }
        }
        let vis = chart_visibility(mesh, chart, inward);
        let mut known = self.0.lock().unwrap_or_else(|e| e.into_inner());
        for &(c, v) in &chart.corner_vertex {
            if let Some(x) = known.get_mut(c as usize) {
                *x = vis[v as usize];
            }
        }
        vis
    }
}
