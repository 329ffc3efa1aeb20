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
//! The side faces of an extrusion (a gear's teeth, a box around a bore) meet at creases
//! too, all along its axis; those creases are left uncut where the side stays a strip or a
//! ring that unrolls ([`join_developable`]), so the side is one island, not one per face.
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
    let mut crease: Vec<bool> = (0..graph.edges.len())
        .map(|e| graph.edge_polygons[e][1] != u32::MAX && graph.dihedral[e] >= CREASE_ANGLE)
        .collect();
    if !crease.iter().any(|&c| c) {
        return None;
    }
    join_developable(chart, &graph, &mut crease, &|v| inner(v), &|v| defect(v).abs() <= CURVED_DEFECT);
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
    Some(graph.mesh_seams(chart, &cut))
}

/// Leave uncut the creases that join the side faces of an extrusion into one band, so its
/// side unrolls as one strip instead of one island per face (a gear of 24 teeth: 98 islands,
/// now 3: the band and its two caps).
///
/// Chains are tried the flattest first (a hexagonal bore's 60° walls before the 90° rims
/// where they meet the part's faces), then along the directions most creases share (an
/// extrusion's side edges share its axis while its rims turn), so a part with bores or
/// extrusions along several axes gets one strip per wall (a cube with a bore along x and one
/// along y: 11 islands when only the commonest direction was joined, now 5).
/// The unit is a chain: crease edges joined at flat inner vertices (`flat(v)`) with no other
/// crease (points along one straight crease line), taken from its lowest edge, in passes
/// until none more is left uncut. A chain is left uncut when:
/// * each of its two ends is on the chart's outline, keeps at least two other creases (it
///   stays on a cut running through it, as a rim does), or keeps none and is flat (it becomes
///   an inner vertex of a region, which must unroll); an end that would keep one crease would
///   be the tip of a slit;
/// * the regions on both sides are planar with their normal across the chain, or bands whose
///   axis is the chain's direction (a cap, whose normal is the axis, never joins);
/// * each of those regions takes part in at most two joins in all, so the joined regions make
///   strips and rings, which unroll side by side: a plate joined to its edge and to the wall
///   of a notch behind it, and to its underside through both, would unroll onto itself.
fn join_developable(
    chart: &Chart,
    graph: &ChartGraph,
    crease: &mut [bool],
    inner: &dyn Fn(usize) -> bool,
    flat: &dyn Fn(usize) -> bool,
) {
    use crate::geometry::{cross, dot, norm, sub, unit};
    let normals = crate::cuts::graph::polygon_normals(chart, &graph.polygons);
    // The regions between the creases and the shape of each: all its faces in one plane, all
    // their normals across one axis (a band: a prism's or cylinder's side), or neither.
    let mut regions = crate::charts::UnionFind::new(graph.polygons.len());
    for (e, p) in graph.edge_polygons.iter().enumerate() {
        if !crease[e] && p[1] != u32::MAX {
            regions.union(p[0], p[1]);
        }
    }
    let n_polygons = graph.polygons.len();
    // Region (its root polygon) of every polygon before any join, and its faces.
    let first_region: Vec<u32> = (0..n_polygons as u32).map(|p| regions.find(p)).collect();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n_polygons];
    for (f, &r) in first_region.iter().enumerate() {
        members[r as usize].push(f);
    }
    // Shape of every region, by its current root polygon.
    let mut shape: Vec<Shape> = members
        .iter()
        .map(|faces| {
            let Some(&f0) = faces.first() else { return Shape::Other };
            let n0 = normals[f0];
            match faces.iter().map(|&f| normals[f]).find(|n| norm(cross(n0, *n)) > AXIS_TOLERANCE) {
                None => Shape::Planar(n0),
                Some(n1) => {
                    let axis = unit(cross(n0, n1));
                    if faces.iter().all(|&f| dot(normals[f], axis).abs() <= AXIS_TOLERANCE) {
                        Shape::Band(axis)
                    } else {
                        Shape::Other
                    }
                }
            }
        })
        .collect();
    // Joins each region before any join takes part in.
    let mut joins = vec![0usize; n_polygons];
    // Whether a region of shape `s` may join across a crease along unit direction `d`.
    let across = |s: &Shape, d: [f64; 3]| match *s {
        Shape::Planar(n) => dot(n, d).abs() <= AXIS_TOLERANCE,
        Shape::Band(a) => dot(a, d).abs() >= 1.0 - AXIS_TOLERANCE,
        Shape::Other => false,
    };
    let mut creases_at = vec![0u32; graph.n_vertices];
    for (e, &c) in crease.iter().enumerate() {
        if c {
            for v in graph.edges[e] {
                creases_at[v as usize] += 1;
            }
        }
    }
    // A vertex a chain runs through: inner, flat, on exactly two creases.
    let through = |v: usize, at: &[u32]| inner(v) && flat(v) && at[v] == 2;
    // The creases' directions (an extrusion's side edges share its axis; its rims turn).
    let direction = |e: usize| {
        let [a, b] = graph.edges[e];
        let d = unit(sub(chart.positions[b as usize], chart.positions[a as usize]));
        let k = (0..3).find(|&k| d[k].abs() > 1e-9).unwrap_or(0);
        let d = if d[k] < 0.0 { [-d[0], -d[1], -d[2]] } else { d };
        d.map(|x| (x / AXIS_TOLERANCE).round() as i64)
    };
    let creases: Vec<(usize, [i64; 3])> = (0..crease.len()).filter(|&e| crease[e]).map(|e| (e, direction(e))).collect();
    let mut parallel: std::collections::HashMap<[i64; 3], usize> = Default::default();
    for &(_, d) in &creases {
        *parallel.entry(d).or_default() += 1;
    }
    // The flattest creases first (a hexagonal bore's 60° walls before the 90° rims where it
    // meets a face), then along the directions most creases share (an extrusion's axis, where
    // its side edges run, before its rims, which turn; ties to the least direction), then by
    // id. A region joined along one direction is a band along it and joins no other way.
    let mut order: Vec<(i64, std::cmp::Reverse<usize>, [i64; 3], usize)> = creases
        .iter()
        .map(|&(e, d)| ((graph.dihedral[e] / ANGLE_STEP).round() as i64, std::cmp::Reverse(parallel[&d]), d, e))
        .collect();
    order.sort_unstable();
    let order: Vec<usize> = order.into_iter().map(|x| x.3).collect();
    loop {
        let mut changed = false;
        for &e0 in &order {
            if !crease[e0] {
                continue;
            }
            // The chain through e0: walk both ways through vertices the chain runs through.
            let mut chain = vec![e0 as u32];
            let mut ends = [0u32; 2];
            for (side, &start) in graph.edges[e0].iter().enumerate() {
                let (mut v, mut from) = (start, e0 as u32);
                while through(v as usize, &creases_at) && chain.len() <= crease.len() {
                    let range = graph.adj_start[v as usize]..graph.adj_start[v as usize + 1];
                    let Some(&(w, e)) = graph.adj[range].iter().find(|&&(_, e)| e != from && crease[e as usize]) else {
                        break;
                    };
                    if e as usize == e0 {
                        break; // a closed loop of straight crease points
                    }
                    chain.push(e);
                    (v, from) = (w, e);
                }
                ends[side] = v;
            }
            chain.sort_unstable();
            chain.dedup();
            if chain[0] as usize != e0 {
                continue; // taken from its lowest edge
            }
            let ok = |v: u32, left: u32| !inner(v as usize) || left >= 2 || (left == 0 && flat(v as usize));
            let keeps = if ends[0] == ends[1] {
                ok(ends[0], creases_at[ends[0] as usize].saturating_sub(2))
            } else {
                ends.iter().all(|&v| ok(v, creases_at[v as usize] - 1))
            };
            if !keeps {
                continue;
            }
            // The regions on both sides stay a plane or a band along the chain.
            let [a, b] = graph.edges[e0];
            let d = unit(sub(chart.positions[b as usize], chart.positions[a as usize]));
            let sides: Vec<u32> = chain
                .iter()
                .flat_map(|&e| graph.edge_polygons[e as usize])
                .filter(|&p| p != u32::MAX)
                .map(|p| regions.find(p))
                .collect();
            if !sides.iter().all(|&r| across(&shape[r as usize], d)) {
                continue;
            }
            // Each region between the creases takes part in at most two joins: strips and
            // rings, which unroll side by side.
            let mut initial: Vec<u32> = chain
                .iter()
                .flat_map(|&e| graph.edge_polygons[e as usize])
                .filter(|&p| p != u32::MAX)
                .map(|p| first_region[p as usize])
                .collect();
            initial.sort_unstable();
            initial.dedup();
            if initial.iter().any(|&r| joins[r as usize] >= 2) {
                continue;
            }
            for &r in &initial {
                joins[r as usize] += 1;
            }
            changed = true;
            for &e in &chain {
                crease[e as usize] = false;
                for v in graph.edges[e as usize] {
                    creases_at[v as usize] -= 1;
                }
            }
            let first = sides[0];
            for &r in &sides[1..] {
                regions.union(first, r);
            }
            let root = regions.find(first) as usize;
            shape[root] = Shape::Band(d);
        }
        if !changed {
            break;
        }
    }
}

/// The shape of a region between creases ([`join_developable`]).
enum Shape {
    /// Every face in one plane, of this unit normal.
    Planar([f64; 3]),
    /// Every face's normal across this unit axis: the side of a prism or a cylinder.
    Band([f64; 3]),
    /// Neither.
    Other,
}

/// Largest `|cos|` between a face's normal and a band's axis (or a crease along it) for the
/// face to count as parallel to the axis, and smallest cross product for two normals to differ.
const AXIS_TOLERANCE: f64 = 1e-3;

/// Creases whose dihedral angles round to the same multiple of this step count as equally
/// sharp when [`join_developable`] orders them (5°).
const ANGLE_STEP: f64 = 5.0 * std::f64::consts::PI / 180.0;

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
