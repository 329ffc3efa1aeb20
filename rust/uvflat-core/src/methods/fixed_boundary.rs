//! The shared machinery of the barycentric (fixed-boundary) methods: place the outer boundary
//! on a convex shape by arc length, fill holes virtually, and solve Σ_j w_ij (x_i − x_j) = 0 at
//! every other vertex with the quadratic-with-fixed-values solver.
//!
//! Holes (every boundary loop but the longest) are filled with a virtual fan: one extra vertex
//! at the hole's 3D centroid joined to each hole vertex. The virtual vertex is solved like any
//! interior vertex and dropped afterwards, so the chart stays a disk and Tutte/Floater's
//! guarantee (positive weights + convex boundary ⇒ no flips) covers its real triangles.
//!
//! Virtual boundary ([`BoundaryShape::Virtual`]; Y. Lee, H. S. Kim, S. Lee, "Mesh
//! parameterization with a virtual boundary", Computers & Graphics 26(5), 2002): the outer loop
//! is surrounded by a band of virtual triangles (rings of new vertices offset outward in the
//! local tangent plane, see [`add_virtual_band`]); the band's outer ring goes to the circle and
//! the real boundary moves freely inside it, so it is no longer forced onto a convex shape.
//! With mean value weights (positive on any triangle) the extended disk still has a convex
//! boundary and positive weights, so Floater's no-flip guarantee covers the real triangles.
//!
//! Pins: the chart is first solved without them; its boundary shape is then moved by the
//! least-squares similarity onto the pins, and pinned vertices are fixed at their pinned UVs
//! together with the boundary (the report notes this). Pins far from the similarity can flip
//! triangles; the report counts them.

use super::{chart_angles, ChartFailure, ChartSolution};
use crate::charts::{Chart, Polygon};
use crate::geometry::{norm, sub};
use crate::methods::BoundaryShape;
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};

/// Edge weights of a barycentric method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weights {
    /// w_ij = 1 (Tutte).
    Uniform,
    /// w_ij = ½ (cot α_ij + cot β_ij) (harmonic; can be negative).
    Cotangent,
    /// w_ij = (tan(γ/2) + tan(δ/2)) / |x_j − x_i| (Floater's mean value; positive, not symmetric).
    MeanValue,
}

/// A chart extended by virtual hole fans.
pub struct Extended {
    /// Positions: chart vertices then one virtual vertex per hole.
    pub positions: Vec<[f64; 3]>,
    /// Triangles: chart triangles then the virtual fans.
    pub triangles: Vec<[u32; 3]>,
    /// The outer loop (longest boundary loop).
    pub outer: Vec<u32>,
}

/// Extend a chart by filling every boundary loop but the longest with a virtual fan.
pub fn fill_holes(chart: &Chart) -> Extended {
    let outer_i = chart.outer_loop().expect("a disk chart has a boundary loop");
    let mut positions = chart.positions.clone();
    let mut triangles = chart.triangles.clone();
    for (li, lp) in chart.boundary_loops.iter().enumerate() {
        if li == outer_i {
            continue;
        }
        let n = lp.len() as f64;
        let mut c = [0.0; 3];
        for &v in lp {
            for d in 0..3 {
                c[d] += chart.positions[v as usize][d] / n;
            }
        }
        let cv = positions.len() as u32;
        positions.push(c);
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            // The chart lies left of a → b, so the fill uses b → a.
            triangles.push([b, a, cv]);
        }
    }
    Extended { positions, triangles, outer: chart.boundary_loops[outer_i].clone() }
}

/// The chart with every hole (boundary loop but the outer one) filled by a virtual fan
/// ([`fill_holes`]): a disk whose first triangles and vertices are the chart's, so the
/// chart's results are the first entries of the filled chart's. Positions, triangles,
/// boundary loops and kind describe the filled disk; the virtual vertices and triangles map
/// to no mesh vertex or face (`u32::MAX`).
///
/// Preconditions: a chart with at least one boundary loop.
pub fn filled_chart(chart: &Chart) -> Chart {
    let ext = fill_holes(chart);
    let mut c = chart.clone();
    c.mesh_vertex.resize(ext.positions.len(), u32::MAX);
    c.triangle_face.resize(ext.triangles.len(), u32::MAX);
    c.positions = ext.positions;
    c.triangles = ext.triangles;
    c.boundary_loops = vec![ext.outer];
    c.kind = crate::charts::ChartKind::Disk;
    c
}

/// Number of rings of virtual vertices of [`add_virtual_band`].
pub const VIRTUAL_RINGS: usize = 6;
/// Ratio of the widths of consecutive rings of [`add_virtual_band`].
pub const VIRTUAL_GROWTH: f64 = 1.5;

/// Surround the outer loop of `ext` by a band of virtual triangles and make the band's outer
/// ring the new outer loop (Lee, Kim, Lee 2002, "virtual boundary").
///
/// Ring k (k = 1..=[`VIRTUAL_RINGS`]) puts one vertex beside every outer-loop vertex, offset
/// outward in the loop's mean plane (outward = loop tangent × the chart's vector area; the
/// vertex normal where the two are parallel) by h (1 + g + … + g^(k−1)), h the mean loop edge
/// length and g = [`VIRTUAL_GROWTH`]. Consecutive rings are joined by two triangles per
/// loop edge with the chart's orientation. The band may fold in 3D at concave boundary
/// corners; that does not matter for mean value weights, which are positive on any
/// non-degenerate triangle.
///
/// Preconditions: `ext.outer` is a boundary loop of `ext.triangles` with the chart on its left
/// and at least 3 vertices. Never fails; degenerate normals fall back to the direction away
/// from the loop's centroid.
pub fn add_virtual_band(ext: &mut Extended) {
    let outer = ext.outer.clone();
    let m = outer.len();
    if m < 3 {
        return;
    }
    let pos = &ext.positions;
    // Area-weighted normals of the loop vertices.
    let mut slot = vec![u32::MAX; pos.len()];
    for (k, &v) in outer.iter().enumerate() {
        slot[v as usize] = k as u32;
    }
    let mut normal = vec![[0.0f64; 3]; m];
    for t in &ext.triangles {
        let nrm = crate::geometry::cross(
            sub(pos[t[1] as usize], pos[t[0] as usize]),
            sub(pos[t[2] as usize], pos[t[0] as usize]),
        );
        for &v in t {
            let k = slot[v as usize];
            if k != u32::MAX {
                for d in 0..3 {
                    normal[k as usize][d] += nrm[d];
                }
            }
        }
    }
    let mut length = 0.0;
    let mut centroid = [0.0; 3];
    for i in 0..m {
        length += norm(sub(pos[outer[(i + 1) % m] as usize], pos[outer[i] as usize]));
        for d in 0..3 {
            centroid[d] += pos[outer[i] as usize][d] / m as f64;
        }
    }
    if !(length > 0.0) {
        return;
    }
    // The chart's vector area (for a disk, the vector area of the outer loop by Stokes): the
    // band is a flange in the loop's mean plane, which keeps its triangles well shaped (the
    // tangent plane of a tube-like rim would extend the tube instead).
    let mut area_normal = [0.0; 3];
    for t in &ext.triangles {
        let nrm = crate::geometry::cross(sub(pos[t[1] as usize], pos[t[0] as usize]), sub(pos[t[2] as usize], pos[t[0] as usize]));
        for d in 0..3 {
            area_normal[d] += nrm[d];
        }
    }
    let mut dirs = Vec::with_capacity(m);
    for i in 0..m {
        let p = pos[outer[(i + m - 1) % m] as usize];
        let q = pos[outer[(i + 1) % m] as usize];
        let t = sub(q, p);
        let mut d = crate::geometry::cross(t, area_normal);
        if !(norm(d) > 1e-12 * norm(t) * norm(area_normal)) {
            // Loop tangent parallel to the mean normal: use the vertex's own tangent plane.
            d = crate::geometry::cross(t, normal[i]);
        }
        let mut l = norm(d);
        if !(l > 1e-300) || !l.is_finite() {
            d = sub(pos[outer[i] as usize], centroid);
            l = norm(d);
        }
        dirs.push(if l > 0.0 && l.is_finite() { [d[0] / l, d[1] / l, d[2] / l] } else { [0.0; 3] });
    }
    // Ring k sits h (1 + g + … + g^(k−1)) outward, h the mean loop edge length.
    let h = length / m as f64;
    let mut prev: Vec<u32> = outer.clone();
    let mut offset = 0.0;
    let mut step = h;
    let growth = VIRTUAL_GROWTH;
    for _ in 0..VIRTUAL_RINGS {
        offset += step;
        step *= growth;
        let ring: Vec<u32> = (0..m)
            .map(|i| {
                let b = outer[i] as usize;
                let p = ext.positions[b];
                ext.positions.push([p[0] + offset * dirs[i][0], p[1] + offset * dirs[i][1], p[2] + offset * dirs[i][2]]);
                (ext.positions.len() - 1) as u32
            })
            .collect();
        for i in 0..m {
            let j = (i + 1) % m;
            ext.triangles.push([prev[j], prev[i], ring[i]]);
            ext.triangles.push([prev[j], ring[i], ring[j]]);
        }
        prev = ring;
    }
    ext.outer = prev;
}

/// UV of every outer-loop vertex on the boundary shape, spaced by 3D arc length,
/// counter-clockwise (the chart is left of the loop, so triangles come out positive). Every
/// gap is at least 1/1000 of the uniform spacing, so coincident 3D boundary vertices still get
/// distinct points.
pub fn boundary_positions(positions: &[[f64; 3]], outer: &[u32], shape: BoundaryShape) -> Vec<[f64; 2]> {
    let n = outer.len();
    let mut s = Vec::with_capacity(n);
    let mut acc = 0.0;
    for i in 0..n {
        s.push(acc);
        acc += norm(sub(positions[outer[(i + 1) % n] as usize], positions[outer[i] as usize]));
    }
    let total = acc;
    let t: Vec<f64> = if total > 0.0 {
        // Every gap is at least 1/1000 of the uniform spacing, so coincident or nearly
        // coincident boundary vertices still get distinct points (and triangles of area > 0).
        let min_gap = 1e-3 / n as f64;
        let mut gaps: Vec<f64> = (0..n).map(|i| (if i + 1 < n { s[i + 1] } else { total } - s[i]) / total).collect();
        for g in gaps.iter_mut() {
            *g = g.max(min_gap);
        }
        let sum: f64 = gaps.iter().sum();
        let mut acc = 0.0;
        gaps.iter()
            .map(|g| {
                let x = acc;
                acc += g / sum;
                x
            })
            .collect()
    } else {
        (0..n).map(|i| i as f64 / n as f64).collect()
    };
    match shape {
        BoundaryShape::Circle | BoundaryShape::Virtual => t
            .iter()
            .map(|&x| {
                let a = std::f64::consts::TAU * x;
                [a.cos(), a.sin()]
            })
            .collect(),
        BoundaryShape::Square if n >= 4 => {
            // Snap the vertices nearest to the quarter parameters to the corners.
            let mut corners = [0usize; 4];
            for (k, c) in corners.iter_mut().enumerate() {
                let target = k as f64 / 4.0;
                *c = (0..n)
                    .min_by(|&a, &b| (t[a] - target).abs().total_cmp(&(t[b] - target).abs()))
                    .unwrap();
            }
            corners[0] = 0;
            for k in 1..4 {
                let lo = corners[k - 1] + 1;
                let hi = n - (4 - k);
                corners[k] = corners[k].clamp(lo, hi);
            }
            let corner_uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            let mut out = vec![[0.0; 2]; n];
            for k in 0..4 {
                let (a, b) = (corners[k], if k == 3 { n } else { corners[k + 1] });
                let ta = t[a];
                let tb = if k == 3 { 1.0 } else { t[b] };
                let (p, q) = (corner_uv[k], corner_uv[(k + 1) % 4]);
                for i in a..b {
                    let f = if tb > ta { (t[i] - ta) / (tb - ta) } else { (i - a) as f64 / (b - a) as f64 };
                    out[i] = [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])];
                }
            }
            out
        }
        BoundaryShape::Square => boundary_positions(positions, outer, BoundaryShape::Circle),
    }
}

/// Triplets of the weighted Laplacian `L` (rows: Σ_j w_ij (x_i − x_j)): the lower triangle
/// for the symmetric weights (uniform, cotangent), every entry for mean value.
pub fn laplacian_triplets(positions: &[[f64; 3]], triangles: &[[u32; 3]], weights: Weights) -> Vec<(u32, u32, f64)> {
    laplacian_triplets_with_polygons(positions, triangles, &[], weights)
}

/// [`laplacian_triplets`] on the polygon graph: the triangles of each of `polygons` (by
/// their [`Polygon::triangles`]) are replaced by the polygon, whose diagonals are not edges.
/// Uniform weights count each polygon edge once; mean value weights use the polygon's corner
/// angle (the 3D angle between its two edges at the corner, in (0, π), so the weights stay
/// positive). Cotangent weights ignore `polygons` (they are defined on triangles).
///
/// With positive weights on the polygon graph and a convex boundary, every interior vertex
/// is a convex combination of its polygon neighbours and every face comes out convex
/// (Tutte 1963 for uniform weights; Floater 2003 and Gortler, Gotsman & Thurston, "Discrete
/// one-forms on meshes and applications to 3D mesh parameterization", CAGD 23(2), 2006, for
/// positive weights on polygon meshes): quads and n-gons are then positive under any
/// triangulation, which a map on the triangulated graph does not promise.
pub fn laplacian_triplets_with_polygons(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    polygons: &[Polygon],
    weights: Weights,
) -> Vec<(u32, u32, f64)> {
    if polygons.is_empty() || weights == Weights::Cotangent {
        return laplacian_triplets_triangles(positions, triangles, weights);
    }
    let mut in_polygon = vec![false; triangles.len()];
    for p in polygons {
        for t in p.triangles.clone() {
            in_polygon[t as usize] = true;
        }
    }
    let rest: Vec<[u32; 3]> = triangles.iter().zip(&in_polygon).filter(|(_, &q)| !q).map(|(t, _)| *t).collect();
    let mut out = laplacian_triplets_triangles(positions, &rest, weights);
    match weights {
        Weights::Uniform => {
            // Polygon edges not already edges of a triangle.
            let mut have: std::collections::HashSet<(u32, u32)> = rest
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
                .collect();
            for p in polygons {
                let m = p.vertices.len();
                for k in 0..m {
                    let (i, j) = (p.vertices[k], p.vertices[(k + 1) % m]);
                    if have.insert((i.min(j), i.max(j))) {
                        out.extend([(i, i, 1.0), (j, j, 1.0), (i.max(j), i.min(j), -1.0)]);
                    }
                }
            }
        }
        Weights::MeanValue => {
            let floor = 1e-12 * mean_edge(positions, triangles);
            for p in polygons {
                let m = p.vertices.len();
                for k in 0..m {
                    let i = p.vertices[k];
                    let (j, l) = (p.vertices[(k + 1) % m], p.vertices[(k + m - 1) % m]);
                    let x = positions[i as usize];
                    let (a, b) = (sub(positions[j as usize], x), sub(positions[l as usize], x));
                    let theta = crate::geometry::angle_between(a, b).clamp(1e-12, std::f64::consts::PI - 1e-9);
                    let th = (0.5 * theta).tan();
                    for (n, e) in [(j, a), (l, b)] {
                        let w = th / norm(e).max(floor);
                        out.push((i, i, w));
                        out.push((i, n, -w));
                    }
                }
            }
        }
        Weights::Cotangent => unreachable!("handled above"),
    }
    out
}

fn mean_edge(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for t in triangles {
        for k in 0..3 {
            s += norm(sub(positions[t[(k + 1) % 3] as usize], positions[t[k] as usize]));
            n += 1;
        }
    }
    if n > 0 && s > 0.0 { s / n as f64 } else { 1.0 }
}

/// Lower-triangle triplets of the cotangent Laplacian from the triangles' corner angles
/// (weights ½(cot α + cot β); [`laplacian_triplets`] with [`Weights::Cotangent`] computes the
/// angles itself).
pub fn cotangent_triplets(triangles: &[[u32; 3]], angles: &[[f64; 3]]) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::with_capacity(triangles.len() * 9);
    for (t, a) in triangles.iter().zip(angles) {
        for k in 0..3 {
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            let w = 0.5 / a[k].tan();
            out.extend([(i, i, w), (j, j, w), (i.max(j), i.min(j), -w)]);
        }
    }
    out
}

fn laplacian_triplets_triangles(positions: &[[f64; 3]], triangles: &[[u32; 3]], weights: Weights) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::with_capacity(triangles.len() * 12);
    let push_sym = |i: u32, j: u32, w: f64, out: &mut Vec<(u32, u32, f64)>| {
        out.extend([(i, i, w), (j, j, w), (i.max(j), i.min(j), -w)]);
    };
    match weights {
        Weights::Uniform => {
            let mut edges: Vec<(u32, u32)> = triangles
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
                .collect();
            edges.sort_unstable();
            edges.dedup();
            for (i, j) in edges {
                push_sym(i, j, 1.0, &mut out);
            }
        }
        Weights::Cotangent => return cotangent_triplets(triangles, &chart_angles(positions, triangles)),
        Weights::MeanValue => {
            let angles = chart_angles(positions, triangles);
            let mean_len = mean_edge(positions, triangles);
            let floor = 1e-12 * mean_len;
            for (t, a) in triangles.iter().zip(&angles) {
                for k in 0..3 {
                    let i = t[k];
                    let th = (0.5 * a[k]).tan();
                    for j in [t[(k + 1) % 3], t[(k + 2) % 3]] {
                        let l = norm(sub(positions[j as usize], positions[i as usize])).max(floor);
                        let w = th / l;
                        out.push((i, i, w));
                        out.push((i, j, -w));
                    }
                }
            }
        }
    }
    out
}

/// Solve a fixed-boundary method on a chart.
pub fn solve(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    shape: BoundaryShape,
    weights: Weights,
) -> Result<ChartSolution, ChartFailure> {
    let mut ext = fill_holes(chart);
    if shape == BoundaryShape::Virtual {
        add_virtual_band(&mut ext);
    }
    let n = ext.positions.len();
    // Polygons as polygons (their triangles are the chart's, the first of `ext.triangles`).
    let trip = laplacian_triplets_with_polygons(&ext.positions, &ext.triangles, &chart.polygons, weights);
    let symmetry = if weights == Weights::MeanValue { Symmetry::General } else { Symmetry::Symmetric };
    let bnd = boundary_positions(&ext.positions, &ext.outer, shape);
    let solver = FixedValueSolver::with_ordering(n, &trip, &ext.outer, symmetry, OrderingKind::Amd)?;
    let cols = [bnd.iter().map(|p| p[0]).collect::<Vec<_>>(), bnd.iter().map(|p| p[1]).collect::<Vec<_>>()];
    let x = solver.solve(&cols, &[])?;
    // UVs of every vertex of the extended chart (chart vertices first, then hole centres and
    // the virtual band): pins index chart vertices, the fixed outer loop may be virtual.
    let mut uv: Vec<[f64; 2]> = (0..n).map(|i| [x[0][i], x[1][i]]).collect();
    let mut sol = ChartSolution::direct(Vec::new());
    if !pins.is_empty() {
        // Move the whole solution (hence the boundary) onto the pins, then fix both.
        let (fixed, vals) = onto_pins(&mut uv, &ext.outer, pins);
        let solver = FixedValueSolver::with_ordering(n, &trip, &fixed, symmetry, OrderingKind::Amd)?;
        let cols = [vals.iter().map(|p| p[0]).collect::<Vec<_>>(), vals.iter().map(|p| p[1]).collect::<Vec<_>>()];
        let x = solver.solve(&cols, &[])?;
        uv = (0..n).map(|i| [x[0][i], x[1][i]]).collect();
        sol.note = Some(format!(
            "{} pinned vertex(es) fixed; the boundary {} was moved onto them by a similarity",
            pins.len(),
            match shape {
                BoundaryShape::Circle => "circle",
                BoundaryShape::Square => "square",
                BoundaryShape::Virtual => "virtual circle",
            }
        ));
    }
    uv.truncate(chart.positions.len());
    sol.uv = uv;
    Ok(sol)
}

/// Move the map `uv` onto `pins` (the similarity that fits them when they span more than a
/// point, else the translation onto the first) and return the unknowns to hold for the pinned
/// solve with their values: the `outer` loop where the moved map puts it, and the pins.
pub(crate) fn onto_pins(uv: &mut [[f64; 2]], outer: &[u32], pins: &[(u32, [f64; 2])]) -> (Vec<u32>, Vec<[f64; 2]>) {
    let mut target = vec![[f64::NAN; 2]; uv.len()];
    for &(v, p) in pins {
        target[v as usize] = p;
    }
    let moved = super::lscm::pins_span(pins) && crate::metrics::fit_similarity_points(uv, &target);
    if !moved {
        let (v, p) = pins[0];
        let d = [p[0] - uv[v as usize][0], p[1] - uv[v as usize][1]];
        for q in uv.iter_mut() {
            *q = [q[0] + d[0], q[1] + d[1]];
        }
    }
    let mut fixed: Vec<u32> = outer.to_vec();
    let mut vals: Vec<[f64; 2]> = outer.iter().map(|&v| uv[v as usize]).collect();
    for &(v, p) in pins {
        if let Some(k) = fixed.iter().position(|&f| f == v) {
            vals[k] = p;
        } else {
            fixed.push(v);
            vals.push(p);
        }
    }
    (fixed, vals)
}
