//! Fill: the small holes of a surface are filled for the unwrap and joined to the outline by
//! closed seams afterwards, instead of being cut open.
//!
//! A scan loses surface in small holes (under an arm, between the toes, where the scanner saw
//! nothing). Cut open, every hole becomes a bay of the island's outline joined to it by a cut
//! whose two sides are free: on the bunny subdivided twice with 100 holes of 30 faces, the
//! outline ran through all of them, its branches came to lie on each other in the map, and
//! the peel ([`super::peel`]) left 31 islands under `slim` and 17 under `abf`, most of them
//! specks around the holes, with 1,443 and 1,380 new seam edges.
//!
//! Precedent: Blender's own unwrapper fills holes for its solve, and so does this crate's
//! `lscm` when a chart's open map folds ([`crate::methods::fixed_boundary::filled_chart`]).
//! Here the fill is a part of the mesh for the whole unwrap, cuts and repair included:
//! 1. *Plan* ([`Filled::plan`]): in every chart of the input (automatic seams on, a method that
//!    finds the outline itself, no pinned corner), each boundary loop but the longest whose
//!    edges are all edges of the mesh's own boundary (not seams, not the selection's border)
//!    is filled when it is small (3D perimeter at most [`MAX_PERIMETER`] × the square root of
//!    the chart's area, at most [`MAX_CORNERS`] corners) and its fill is sound: the loop
//!    triangulated by ear clipping in its own plane
//!    ([`crate::charts::triangulate_polygon_avoiding`]), no new vertex, every triangle
//!    turned like the loop in that plane with an area of at least [`MIN_FILL_AREA`] of their
//!    mean, and no diagonal already an edge of the mesh. (A fan from a vertex at the loop's
//!    mean is a cone whose apex a conformal method must flatten: on the bunny subdivided twice
//!    with 100 holes (seed 4), `abf` did not converge on the filled scan and fell back to
//!    `slim`.)
//!    The fill's triangles follow the input's faces.
//! 2. The unwrap runs on the filled mesh: to the pipeline a closed scan with small holes is
//!    the closed surface it scanned (one hole kept open: a disk).
//! 3. *Restore* ([`Filled::restore`]): the fill's faces and corners are dropped, and the
//!    seams on the fills' edges. An island that held a fill now has a hole where it was, laid
//!    out as the fill left it; each such hole is joined to the island's outline (or to a hole
//!    joined before it) by the shortest path of edges inside the island, never through an
//!    avoided vertex ([`join_holes`]). Both sides of the path keep the same UVs: a closed
//!    seam, which the rule does not count as an overlap
//!    ([`crate::metrics::closed_seams`]) and which shows no texture seam. The island is
//!    rebuilt and measured again.
//!
//! When an island so rebuilt breaks the rule (or is not one disk, or a hole cannot be
//! reached), the restore gives up and the caller unwraps the mesh as it is, holes cut open:
//! the fill never leaves an island beyond the rule, only a slower unwrap. (It does not
//! promise fewer islands everywhere: the robustness run's *collapsed* `arap` rows gained two.)
//!
//! Deterministic: charts, loops and paths in index order; the path search breaks ties by
//! vertex id.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap, HashSet};

use super::outcome::ChartReport;
use super::rule::AtlasRule;
use super::solve::remeasure;
use crate::charts::{build_charts_with, Chart, ChartKind, FaceTriangulation};
use crate::geometry::{cross, dot, newell_normal, norm, sub};
use crate::mesh::PolyMesh;
use crate::unwrap::{Fit, MeshInput, UnwrapOptions, Unwrapped};

/// A hole is filled when its 3D perimeter is at most this many times the square root of its
/// chart's 3D area: a round hole of up to 8% of the chart's area (a hole of 30 faces in the
/// bunny of 7k faces: 0.36; subdivided twice: 0.09). A larger hole is an opening of the model
/// (a sleeve, a mouth), cut open as it is.
pub const MAX_PERIMETER: f64 = 1.0;

/// Most corners of a filled hole.
pub const MAX_CORNERS: usize = 2_000;

/// Every triangle of a hole's fill has at least this share of the fill's mean triangle area
/// (its area along the loop's Newell normal).
pub const MIN_FILL_AREA: f64 = 0.01;

/// The input with its small holes filled, and what is needed to take the fill out again.
#[derive(Debug, Clone)]
pub struct Filled {
    corner_verts: Vec<u32>,
    face_sizes: Vec<u32>,
    selected: Option<Vec<bool>>,
    /// The input's render triangles and one per fill face, when the input gives them.
    triangles: Vec<[u32; 3]>,
    /// Vertices, faces and corners of the input (the fills' faces and corners come after
    /// them; they add no vertex).
    n_vertices: usize,
    n_faces: usize,
    n_corners: usize,
    /// Edges of the filled loops and the fills' diagonals (sorted mesh vertex pairs): no seam
    /// is reported on them.
    loop_edges: HashSet<[u32; 2]>,
    /// Holes filled.
    pub holes: usize,
}

impl Filled {
    /// The fill of `input` (validated as `mesh`), or `None` when no hole is filled.
    pub fn plan(
        mesh: &PolyMesh<'_>,
        input: &MeshInput<'_>,
        options: &UnwrapOptions,
        render: Option<&FaceTriangulation>,
    ) -> Option<Filled> {
        if !options.auto_seams.enabled || !options.method.free_boundary() {
            return None;
        }
        // Undirected edge uses over the whole mesh: a hole's edges are used once.
        let mut uses: HashMap<[u32; 2], u32> = HashMap::new();
        for f in 0..mesh.n_faces() {
            for c in mesh.face_corners(f) {
                let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f, c)));
                *uses.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
            }
        }
        if !uses.values().any(|&k| k == 1) {
            // A closed mesh: no hole.
            return None;
        }
        let pinned: HashSet<u32> = input.pins.iter().map(|&(c, _)| c).collect();
        let charts = build_charts_with(mesh, input.seams, input.selected, render);
        let mut fills: Vec<Vec<[u32; 3]>> = Vec::new();
        let mut loop_edges = HashSet::new();
        for chart in &charts {
            if chart.defect.is_some() || chart.boundary_loops.len() < 2 {
                continue;
            }
            if chart.corner_vertex.iter().any(|(c, _)| pinned.contains(c)) {
                continue;
            }
            let area = super::chart_area(chart);
            let lengths: Vec<f64> = chart.boundary_loops.iter().map(|l| loop_length(&chart.positions, l)).collect();
            let longest = |&a: &usize, &b: &usize| lengths[a].total_cmp(&lengths[b]).then(b.cmp(&a));
            let Some(outer) = (0..lengths.len()).max_by(longest) else {
                continue;
            };
            for (k, lp) in chart.boundary_loops.iter().enumerate() {
                let small = lengths[k] <= MAX_PERIMETER * area.sqrt();
                if k == outer || lp.len() < 3 || lp.len() > MAX_CORNERS || !small {
                    continue;
                }
                let verts: Vec<u32> = lp.iter().map(|&v| chart.mesh_vertex[v as usize]).collect();
                let mut distinct = verts.clone();
                distinct.sort_unstable();
                distinct.dedup();
                let on_mesh_boundary = (0..verts.len()).all(|i| {
                    let (a, b) = (verts[i], verts[(i + 1) % verts.len()]);
                    uses.get(&[a.min(b), a.max(b)]) == Some(&1)
                });
                if distinct.len() != verts.len() || !on_mesh_boundary {
                    continue;
                }
                let is_edge = |a: u32, b: u32| uses.contains_key(&[a.min(b), a.max(b)]);
                let Some(fill) = fill_triangles(input.positions, &verts, is_edge) else { continue };
                for i in 0..verts.len() {
                    let (a, b) = (verts[i], verts[(i + 1) % verts.len()]);
                    loop_edges.insert([a.min(b), a.max(b)]);
                }
                for t in &fill {
                    for i in 0..3 {
                        let (a, b) = (t[i], t[(i + 1) % 3]);
                        loop_edges.insert([a.min(b), a.max(b)]);
                    }
                }
                fills.push(fill);
            }
        }
        if fills.is_empty() {
            return None;
        }
        let (n_vertices, n_faces) = (input.positions.len(), input.face_sizes.len());
        let n_corners = input.corner_verts.len();
        let mut corner_verts = input.corner_verts.to_vec();
        let mut face_sizes = input.face_sizes.to_vec();
        for t in fills.iter().flatten() {
            corner_verts.extend_from_slice(t);
            face_sizes.push(3);
        }
        let added = face_sizes.len() - n_faces;
        // Render triangles cover every face when given: the fills' are their own corners.
        let triangles = if input.triangles.is_empty() {
            Vec::new()
        } else {
            let fill_corners =
                (n_corners..corner_verts.len()).step_by(3).map(|c| [c as u32, c as u32 + 1, c as u32 + 2]);
            input.triangles.iter().copied().chain(fill_corners).collect()
        };
        let selected = input.selected.map(|s| s.iter().copied().chain(std::iter::repeat_n(true, added)).collect());
        Some(Filled {
            corner_verts,
            face_sizes,
            selected,
            triangles,
            n_vertices,
            n_faces,
            n_corners,
            loop_edges,
            holes: fills.len(),
        })
    }

    /// The filled input: `input`'s seams and pins, its render triangles and the fills'.
    pub fn input<'a>(&'a self, input: &MeshInput<'a>) -> MeshInput<'a> {
        MeshInput {
            positions: input.positions,
            corner_verts: &self.corner_verts,
            face_sizes: &self.face_sizes,
            seams: input.seams,
            selected: self.selected.as_deref(),
            pins: input.pins,
            triangles: &self.triangles,
        }
    }

    /// `options` for the filled input: the previous UVs (read by [`Fit::Previous`]) of the
    /// fills' corners are those of their vertices' first corners, so an island is placed as
    /// it was.
    pub fn options(&self, options: &UnwrapOptions) -> UnwrapOptions {
        let mut out = options.clone();
        if let Fit::Previous(prev) = &options.fit {
            let mut at: HashMap<u32, [f64; 2]> = HashMap::new();
            for (c, &v) in self.corner_verts[..self.n_corners].iter().enumerate() {
                at.entry(v).or_insert(prev[c]);
            }
            let mut uv = prev.clone();
            uv.extend(self.corner_verts[self.n_corners..].iter().map(|v| at.get(v).copied().unwrap_or([0.0, 0.0])));
            out.fit = Fit::Previous(uv);
        }
        out
    }

    /// `r` (the unwrap of the filled input) for `input` (validated as `mesh`): the fills taken
    /// out, their holes joined to the islands' outlines by closed seams, the islands measured
    /// again. `None` when an island so rebuilt breaks the rule, is not one disk, or a hole
    /// cannot be reached (the caller then unwraps the input as it is).
    pub fn restore(
        &self,
        mesh: &PolyMesh<'_>,
        render: Option<&FaceTriangulation>,
        input: &MeshInput<'_>,
        options: &UnwrapOptions,
        mut r: Unwrapped,
    ) -> Option<Unwrapped> {
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: options.auto_seams.enabled };
        let mut avoid = vec![false; self.n_vertices];
        for &v in &options.auto_seams.avoid_vertices {
            avoid[v as usize] = true;
        }
        let mut affected: Vec<i32> = r.face_chart[self.n_faces..].iter().copied().filter(|&k| k >= 0).collect();
        affected.sort_unstable();
        affected.dedup();
        r.uv.truncate(self.n_corners);
        r.face_chart.truncate(self.n_faces);
        r.face_distortion.truncate(self.n_faces);
        r.face_flips.truncate(self.n_faces);
        r.new_seams.retain(|&[a, b]| !self.loop_edges.contains(&[a.min(b), a.max(b)]));
        let mut faces_of: HashMap<i32, Vec<usize>> = affected.iter().map(|&k| (k, Vec::new())).collect();
        for (f, k) in r.face_chart.iter().enumerate() {
            if let Some(list) = faces_of.get_mut(k) {
                list.push(f);
            }
        }
        let mut removed: Vec<bool> = vec![false; r.charts.len()];
        for &k in &affected {
            let faces = &faces_of[&k];
            if faces.is_empty() {
                // An island of fill faces only.
                removed[k as usize] = true;
                continue;
            }
            let old = r.charts[k as usize].clone();
            if !old.status.mapped() {
                return None;
            }
            let mut mask = vec![false; self.n_faces];
            for &f in faces {
                mask[f] = true;
            }
            let seams: Vec<[u32; 2]> = input.seams.iter().chain(&r.new_seams).copied().collect();
            // Without its fills an island may fall apart (a patch of faces that only its fills
            // joined to the rest): each part is an island.
            for (j, part) in build_charts_with(mesh, &seams, Some(&mask), render).into_iter().enumerate() {
                let island = Island::rebuild(mesh, render, &seams, part, &r.uv, &avoid, &rule, &old)?;
                let id = if j == 0 {
                    k
                } else {
                    removed.push(false);
                    r.charts.push(old.clone());
                    r.charts.len() as i32 - 1
                };
                for (&f, &n) in island.chart.faces.iter().zip(&island.face_flips) {
                    r.face_flips[f as usize] = n;
                    r.face_chart[f as usize] = id;
                }
                for (f, d) in crate::metrics::face_distortion(&island.chart, &island.uv) {
                    r.face_distortion[f as usize] = d;
                }
                r.charts[id as usize] = island.report;
                r.new_seams.extend_from_slice(&island.joins);
                r.closed_seams.extend(island.joins);
            }
        }
        // Islands of fill faces only are gone: number the rest again.
        let mut id_of = vec![-1i32; removed.len()];
        let mut kept = Vec::with_capacity(r.charts.len());
        for (k, report) in std::mem::take(&mut r.charts).into_iter().enumerate() {
            if !removed[k] {
                id_of[k] = kept.len() as i32;
                kept.push(ChartReport { id: kept.len(), ..report });
            }
        }
        r.charts = kept;
        for k in &mut r.face_chart {
            if *k >= 0 {
                *k = id_of[*k as usize];
            }
        }
        r.new_seams.sort_unstable();
        r.new_seams.dedup();
        r.closed_seams.sort_unstable();
        r.closed_seams.dedup();
        Some(r)
    }
}

/// An island of the filled unwrap without its fills: rebuilt, its holes joined, measured.
struct Island {
    chart: Chart,
    uv: Vec<[f64; 2]>,
    report: ChartReport,
    face_flips: Vec<u32>,
    /// The closed seams that join its holes (sorted mesh vertex pairs).
    joins: Vec<[u32; 2]>,
}

impl Island {
    /// `part` (a chart of the input cut along `seams`, its faces' UVs in the per-corner `uv`)
    /// with its holes joined and measured again (`old`: the report of the filled island it
    /// was part of), or `None` when it is not one disk once joined or breaks `rule`.
    #[allow(clippy::too_many_arguments)]
    fn rebuild(
        mesh: &PolyMesh<'_>,
        render: Option<&FaceTriangulation>,
        seams: &[[u32; 2]],
        part: Chart,
        uv: &[[f64; 2]],
        avoid: &[bool],
        rule: &AtlasRule,
        old: &ChartReport,
    ) -> Option<Island> {
        let (chart, joins) = if part.boundary_loops.len() > 1 {
            let joins = join_holes(mesh, &part, &chart_uv(&part, uv)?, avoid)?;
            let mut mask = vec![false; mesh.n_faces()];
            for &f in &part.faces {
                mask[f as usize] = true;
            }
            let all: Vec<[u32; 2]> = seams.iter().chain(&joins).copied().collect();
            (one_chart(mesh, &all, &mask, render)?, joins)
        } else {
            (part, Vec::new())
        };
        if chart.kind != ChartKind::Disk {
            return None;
        }
        let uv = chart_uv(&chart, uv)?;
        let (mut report, face_flips) = remeasure(&chart, &uv, old, rule)?;
        if rule.broken(&report).is_some() {
            return None;
        }
        let positions = mesh.positions();
        let length = |&[a, b]: &[u32; 2]| norm(sub(positions[a as usize], positions[b as usize]));
        report.cut_length += joins.iter().map(length).sum::<f64>();
        Some(Island { chart, uv, report, face_flips, joins })
    }
}

/// The 3D length of a closed loop of chart vertices.
fn loop_length(positions: &[[f64; 3]], lp: &[u32]) -> f64 {
    (0..lp.len()).map(|i| norm(sub(positions[lp[(i + 1) % lp.len()] as usize], positions[lp[i] as usize]))).sum()
}

/// The fill of the hole `verts` (a closed loop of mesh vertices, the chart on its left) as
/// triangles over its vertices turned against the loop, so the filled surface keeps the
/// input's orientation; `None` when it is not sound (see the module docs). `edge(a, b)`:
/// whether the mesh has the edge `a–b`.
fn fill_triangles(positions: &[[f64; 3]], verts: &[u32], edge: impl Fn(u32, u32) -> bool) -> Option<Vec<[u32; 3]>> {
    let ring: Vec<u32> = verts.iter().rev().copied().collect();
    let pts: Vec<[f64; 3]> = ring.iter().map(|&v| positions[v as usize]).collect();
    let tris = crate::charts::triangulate_polygon_avoiding(&pts, |i, j| edge(ring[i], ring[j]));
    let normal = newell_normal(pts.len(), |i| pts[i]);
    let turn: Vec<f64> = tris
        .iter()
        .map(|t| 0.5 * dot(cross(sub(pts[t[1]], pts[t[0]]), sub(pts[t[2]], pts[t[0]])), normal) / norm(normal))
        .collect();
    let mean = turn.iter().sum::<f64>() / turn.len() as f64;
    if !(mean.is_finite() && mean > 0.0 && turn.iter().all(|&a| a >= MIN_FILL_AREA * mean)) {
        return None;
    }
    let out: Vec<[u32; 3]> = tris.iter().map(|t| [ring[t[0]], ring[t[1]], ring[t[2]]]).collect();
    // A diagonal (not a loop edge) that is already an edge of the mesh would be used by three
    // faces.
    let n = ring.len();
    let diagonal = |i: usize, j: usize| (i + 1) % n != j && (j + 1) % n != i;
    let clash = tris.iter().any(|t| (0..3).any(|k| {
        let (i, j) = (t[k], t[(k + 1) % 3]);
        diagonal(i, j) && edge(ring[i], ring[j])
    }));
    (!clash).then_some(out)
}

/// The one chart of the faces `mask` cut along `seams`, or `None` when they make more than one.
fn one_chart(
    mesh: &PolyMesh<'_>,
    seams: &[[u32; 2]],
    mask: &[bool],
    render: Option<&FaceTriangulation>,
) -> Option<Chart> {
    let mut charts = build_charts_with(mesh, seams, Some(mask), render);
    if charts.len() != 1 {
        return None;
    }
    charts.pop()
}

/// The UV of every vertex of `chart` from the per-corner `uv`, or `None` when two corners of a
/// vertex disagree.
fn chart_uv(chart: &Chart, uv: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let mut out = vec![[f64::NAN; 2]; chart.positions.len()];
    for &(c, v) in &chart.corner_vertex {
        let x = uv[c as usize];
        let slot = &mut out[v as usize];
        if slot[0].is_nan() {
            *slot = x;
        } else if *slot != x {
            return None;
        }
    }
    out.iter().all(|p| p[0].is_finite() && p[1].is_finite()).then_some(out)
}

/// Paths of edges that join every hole of `chart` (laid out as `uv`) to its outline: the loop
/// of largest UV area is the outline; a search grows from it by 3D length over the edges
/// inside the chart, never entering an avoided vertex, and the first vertex it reaches on a
/// hole joins that hole by the path it came along; the hole's vertices then join the
/// search's sources, so each hole is joined once, to the outline or to a hole joined before
/// it. Mesh vertex pairs, sorted; `None` when a hole cannot be reached or a vertex lies on two
/// loops.
pub fn join_holes(mesh: &PolyMesh<'_>, chart: &Chart, uv: &[[f64; 2]], avoid: &[bool]) -> Option<Vec<[u32; 2]>> {
    let n = chart.positions.len();
    let mut loop_of = vec![u32::MAX; n];
    for (k, lp) in chart.boundary_loops.iter().enumerate() {
        for &v in lp {
            if loop_of[v as usize] != u32::MAX {
                return None;
            }
            loop_of[v as usize] = k as u32;
        }
    }
    let signed = |lp: &[u32]| -> f64 {
        (0..lp.len())
            .map(|i| {
                let (a, b) = (uv[lp[i] as usize], uv[lp[(i + 1) % lp.len()] as usize]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum::<f64>()
    };
    let areas: Vec<f64> = chart.boundary_loops.iter().map(|l| signed(l).abs()).collect();
    let outer = (0..areas.len()).max_by(|&a, &b| areas[a].total_cmp(&areas[b]).then(b.cmp(&a)))? as u32;
    // Edges inside the chart: used by two of its faces.
    let polygons = crate::cuts::graph::face_polygons(mesh, chart);
    let mut uses: HashMap<[u32; 2], u32> = HashMap::new();
    for poly in &polygons {
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            *uses.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
        }
    }
    let mut adjacency: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut inner: Vec<[u32; 2]> = uses.into_iter().filter(|&(_, k)| k == 2).map(|(e, _)| e).collect();
    inner.sort_unstable();
    for [a, b] in inner {
        adjacency[a as usize].push(b);
        adjacency[b as usize].push(a);
    }
    let blocked = |v: u32| avoid[chart.mesh_vertex[v as usize] as usize];
    let length = |a: u32, b: u32| norm(sub(chart.positions[a as usize], chart.positions[b as usize]));
    let mut dist = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut joined = vec![false; chart.boundary_loops.len()];
    joined[outer as usize] = true;
    let mut heap = BinaryHeap::new();
    for &v in chart.boundary_loops[outer as usize].iter().filter(|&&v| !blocked(v)) {
        dist[v as usize] = 0.0;
        heap.push(Entry(0.0, v));
    }
    let mut out: Vec<[u32; 2]> = Vec::new();
    let mut left = chart.boundary_loops.len() - 1;
    while let Some(Entry(d, v)) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        let k = loop_of[v as usize];
        if k != u32::MAX && !joined[k as usize] {
            // The path back to a source joins hole k.
            let mut w = v;
            while parent[w as usize] != u32::MAX {
                let p = parent[w as usize];
                let (a, b) = (chart.mesh_vertex[w as usize], chart.mesh_vertex[p as usize]);
                out.push([a.min(b), a.max(b)]);
                w = p;
            }
            joined[k as usize] = true;
            left -= 1;
            if left == 0 {
                break;
            }
            for &u in chart.boundary_loops[k as usize].iter().filter(|&&u| !blocked(u)) {
                if d < dist[u as usize] || u == v {
                    dist[u as usize] = d;
                    parent[u as usize] = u32::MAX;
                    heap.push(Entry(d, u));
                }
            }
            continue;
        }
        for &u in &adjacency[v as usize] {
            if blocked(u) {
                continue;
            }
            // A path does not pass along another vertex of the outline or of a joined hole:
            // those are sources already, nearer.
            let nd = d + length(v, u);
            if nd < dist[u as usize] {
                dist[u as usize] = nd;
                parent[u as usize] = v;
                heap.push(Entry(nd, u));
            }
        }
    }
    if left > 0 {
        return None;
    }
    out.sort_unstable();
    out.dedup();
    Some(out)
}

/// A search entry: distance, then vertex (the smaller first out of the max-heap).
#[derive(Debug, Clone, Copy)]
struct Entry(f64, u32);

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}
