//! Hard surfaces: a chart that is flat or rolled everywhere but along its creases is cut along
//! its creases first, and each region takes the road on its own.
//!
//! Precedent: the "seams from hard edges" habit of hard-surface modelling (the edges where
//! faces meet at a sharp angle hide a seam and bound pieces that unroll without distortion),
//! and the developable charts of Julius, Kraevoy & Sheffer 2005 ("D-charts"): a piece whose
//! Gaussian curvature is zero inside (flat, cylindrical, conical) flattens isometrically.
//!
//! The cones of [`crate::cuts`] relieve curvature at a few points (at most
//! [`crate::cuts::AutoSeamOptions::max_cones`] per chart), which suits organic surfaces, where
//! curvature is spread, and polyhedra with few corners (a cube's eight corners become its
//! cones and it unfolds as one net). A CAD part or an extruded letter has its curvature on
//! its creases instead, at many vertices: the 64 rim vertices of a cylinder with n-gon caps,
//! the rims of a bore. A few cones leave such a chart in one island whose flat faces are bent
//! (a cylinder: a conformal distortion of 1.2–1.5). Cutting its creases gives pieces with no
//! curvature inside: a cap, a side that unrolls (its two outlines joined by one cut), a face
//! with a hole (the hole joined to the outline), each laid flat as it is.
//!
//! A chart is cut along its creases when (otherwise it takes the road as before):
//! * it has fewer than [`CREASES_BELOW`] triangles (a scan is not a hard surface, and the
//!   test costs an edge graph);
//! * its creases are the interior edges whose two faces' normals differ by [`CREASE_ANGLE`]
//!   or more, none touching a vertex where seams must not go, and they divide it into two or
//!   more regions;
//! * more of its inner vertices are curved (an angle defect above [`CURVED_DEFECT`]) than
//!   [`crate::cuts::AutoSeamOptions::max_cones`]: with fewer, its cones unfold it already;
//! * the regions are developable but for a few apexes: the angle defects of the inner
//!   vertices no crease touches add up, in absolute value, to at most [`FLAT_TOLERANCE`] once
//!   up to Max Cones apexes (defect above [`APEX_DEFECT`], a cone's tip) are left out; the
//!   apexes are cut to their region's outline by the shortest path, so a cone's side is cut
//!   from its tip to its rim and unrolls into a sector.
//!
//! The regions then take the pipeline's road at the same split depth (a region that is a
//! disk is solved as it is, a rolled side or a face with holes is cut first, and every piece
//! is held to the atlas rule and repaired as any other). The creases are new seams, reported
//! with the first region.
//!
//! Preconditions: automatic seams on, a chart without a defect and without pinned corners (the
//! caller's check: a pinned chart keeps the road it had). Deterministic: edges and regions in
//! id order.

use super::{Context, Piece};
use crate::charts::Chart;
use crate::cuts::graph::ChartGraph;

/// Charts of at least this many triangles are not tested (scans are not hard surfaces; a
/// tessellated CAD part of this size keeps the cones' road).
pub const CREASES_BELOW: usize = 100_000;

/// Smallest angle between the normals of two faces across an edge for the edge to be a crease
/// (50°: the 90° edges of boxes, bores and extrusions, the 60° edges of a hexagonal prism; not
/// the 45° edges of an octagonal one, whose side then unrolls as one piece).
pub const CREASE_ANGLE: f64 = 50.0 * std::f64::consts::PI / 180.0;

/// An inner vertex whose angle defect (2π minus its angle sum) exceeds this, in radians, is
/// curved.
pub const CURVED_DEFECT: f64 = 1e-3;

/// Most total absolute angle defect, in radians, over the inner vertices that no crease
/// touches, for the regions to count as developable (about 1°: rounding in single-precision
/// coordinates leaves far less; a sphere holds 4π).
pub const FLAT_TOLERANCE: f64 = 0.02;

/// Smallest angle defect, in radians, of an apex: a vertex no crease touches whose curvature
/// is a cone's tip (a cone twice as high as wide: 3.5; a quarter of a cube's corner: 0.39),
/// not curvature spread over a patch.
pub const APEX_DEFECT: f64 = 0.5;

/// The creases of `chart` as mesh vertex pairs (sorted) when it is a hard surface cut along
/// them (see the module docs), else `None`.
pub fn crease_seams(ctx: &Context<'_, '_>, chart: &Chart) -> Option<Vec<[u32; 2]>> {
    if chart.triangles.len() >= CREASES_BELOW || chart.defect.is_some() || chart.faces.len() < 2 {
        return None;
    }
    let n = chart.positions.len();
    // The angle sums first: a chart with few curved vertices needs no edge graph.
    let boundary = chart.boundary_mask();
    let mut angle_sum = vec![0.0f64; n];
    for t in &chart.triangles {
        let p = t.map(|v| chart.positions[v as usize]);
        let a = crate::geometry::raw_angles(p);
        for k in 0..3 {
            if a[k].is_finite() {
                angle_sum[t[k] as usize] += a[k];
            }
        }
    }
    let inner = |v: usize| !boundary[v];
    let defect = |v: usize| std::f64::consts::TAU - angle_sum[v];
    let curved = (0..n).filter(|&v| inner(v) && defect(v).abs() > CURVED_DEFECT).count();
    if curved <= ctx.options.auto_seams.max_cones {
        return None;
    }
    let graph = ChartGraph::new(ctx.mesh, chart);
    let crease: Vec<bool> = (0..graph.edges.len())
        .map(|e| graph.edge_polygons[e][1] != u32::MAX && graph.dihedral[e] >= CREASE_ANGLE)
        .collect();
    if !crease.iter().any(|&c| c) {
        return None;
    }
    let mut on_crease = vec![false; n];
    for (e, &c) in crease.iter().enumerate() {
        if c {
            let [a, b] = graph.edges[e];
            if ctx.avoid[chart.mesh_vertex[a as usize] as usize] || ctx.avoid[chart.mesh_vertex[b as usize] as usize] {
                return None;
            }
            on_crease[a as usize] = true;
            on_crease[b as usize] = true;
        }
    }
    // Inner vertices no crease touches, most curved first (ties by id): up to Max Cones of them
    // may be apexes (a cone's tip); the rest must be flat.
    let mut unrelieved: Vec<(f64, u32)> =
        (0..n).filter(|&v| inner(v) && !on_crease[v]).map(|v| (defect(v).abs(), v as u32)).collect();
    unrelieved.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let apexes = unrelieved.iter().take(ctx.options.auto_seams.max_cones).filter(|x| x.0 > APEX_DEFECT).count();
    let rest: f64 = unrelieved[apexes..].iter().map(|x| x.0).sum();
    if !(rest <= FLAT_TOLERANCE) {
        return None;
    }
    let mut regions = crate::charts::UnionFind::new(graph.polygons.len());
    let mut count = graph.polygons.len();
    for (e, p) in graph.edge_polygons.iter().enumerate() {
        if !crease[e] && p[1] != u32::MAX && regions.union(p[0], p[1]) {
            count -= 1;
        }
    }
    if count < 2 {
        return None;
    }
    // Each apex is cut to its region's outline by the shortest path (3D length, avoided vertices
    // left out), so the region unrolls: a cone's side becomes a sector.
    let mut cut = crease.clone();
    if apexes > 0 {
        let cost: Vec<f64> = (0..graph.edges.len())
            .map(|e| {
                let [a, b] = graph.edges[e];
                let avoided = |v: u32| ctx.avoid[chart.mesh_vertex[v as usize] as usize];
                if avoided(a) || avoided(b) { f64::INFINITY } else { graph.length[e] }
            })
            .collect();
        let outline = |v: u32| on_crease[v as usize] || !inner(v as usize);
        let sources: Vec<(u32, u32)> = (0..n as u32).filter(|&v| outline(v)).map(|v| (v, 0)).collect();
        let (dist, parent, _) = crate::cuts::graph::multi_source_dijkstra(&graph, &cost, &sources);
        for &(_, apex) in &unrelieved[..apexes] {
            if !dist[apex as usize].is_finite() {
                return None;
            }
            let mut v = apex;
            while !outline(v) {
                let e = parent[v as usize];
                cut[e as usize] = true;
                v = crate::cuts::graph::other(&graph, e, v);
            }
        }
    }
    let mut seams: Vec<[u32; 2]> = (0..graph.edges.len())
        .filter(|&e| cut[e])
        .map(|e| {
            let [a, b] = graph.edges[e];
            let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
            [ma.min(mb), ma.max(mb)]
        })
        .collect();
    seams.sort_unstable();
    seams.dedup();
    Some(seams)
}

/// The regions of `chart` cut along `creases` ([`crease_seams`]), each taken through the
/// pipeline's road at split depth `depth`; the creases go with the first region's piece.
pub fn regions(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    base_seams: &[[u32; 2]],
    depth: usize,
    creases: &[[u32; 2]],
) -> Vec<Piece> {
    ctx.clock.add(|p| p.crease_cuts += 1);
    let mask = super::repair::face_mask(ctx.mesh.n_faces(), chart);
    super::repair::take_apart(ctx, chart, base_seams, &mask, depth, creases)
}
