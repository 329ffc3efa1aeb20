//! The scaffold triangulation of one iteration (Jiang, Schaefer, Panozzo 2017): a box around
//! the chart's current UVs and the chart's boundary loops, triangulated by a constrained
//! Delaunay triangulation (`spade`), minus the chart's inside.
//!
//! Preconditions: finite UVs; boundary loops of the chart. Failures (as a message): the chart
//! collapsed to a point, its boundary touches itself at round-off level (the triangulation
//! would split a constraint), or the labelling of inside and outside is inconsistent.

use super::BOX_MARGIN;
use crate::charts::Chart;

/// Points per side of the box (corners included once).
const BOX_POINTS_PER_SIDE: usize = 8;

/// The scaffold of one iteration.
pub(super) struct Scaffold {
    /// Box points (appended after the chart vertices).
    pub(super) box_points: Vec<[f64; 2]>,
    /// Scaffold triangles over chart vertex ids and box point ids (n + k), counter-clockwise.
    pub(super) triangles: Vec<[u32; 3]>,
}

/// Triangulate the free space of the box around the chart's boundary loops.
pub(super) fn build_scaffold(chart: &Chart, uv: &[[f64; 2]]) -> Result<Scaffold, String> {
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
