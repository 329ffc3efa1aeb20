//! A flat chart laid as it is: the orthogonal projection onto its plane.
//!
//! Every free-boundary method whose optimum is a similarity of a flat chart (ABF, LSCM, the
//! spectral map, MIPS, SLIM, ARAP, scaffold) reaches that optimum here exactly, without its
//! solve: a flat chart's angles already sum to 2π at every inner vertex, so ABF's angles are
//! the chart's own, LSCM's and the spectral map's conformal energy vanishes on the flat map,
//! and the distortion energies are at their minimum on an isometry.
//!
//! Why not leave it to the methods: a flat face cut by a boolean keeps near-duplicate corners
//! where the cutter touched a grid line (two vertices 1e-7 apart in float32), and the slivers
//! they make have angles near 0 or π. Flattening clamps such angles
//! ([`crate::geometry::MIN_ANGLE`]) so that every method's system stays well posed, and the
//! clamped slivers bend the map around them: on a plate with four bores, cut so each bore
//! joins the outline, the two sides of a cut ended 1e-4 of the plate apart instead of on each
//! other, which reads as an outline crossing itself, and the plate was split. The projection
//! lays the two copies of a cut vertex on one point, exactly (same 3D position, same UV).
//!
//! Preconditions: a chart (any kind; the pipeline only asks for disks, possibly with holes).
//! Returns `None`, and the method solves as usual, when the chart is not flat to
//! [`FLAT_TOLERANCE`] of its size, or when a triangle's projection would count as flipped
//! ([`crate::metrics::face_flips`]: a fold in the plane, or a triangle without 3D area, which
//! would keep none in UV): only a map the report accepts is laid so. Deterministic.

use crate::charts::Chart;
use crate::geometry::{bounds, cross, dot, norm, sub, unit};

/// Largest distance of a vertex from the chart's plane, as a share of its bounding-box
/// diagonal, for the chart to count as flat (float32 coordinates of a tilted plane are off by
/// a few 1e-8).
pub const FLAT_TOLERANCE: f64 = 1e-6;

/// The chart projected onto its plane, turned so its triangles keep their orientation (its
/// centroid at the origin), or `None` when it is not flat or a triangle would count as flipped
/// (module docs).
pub fn project(chart: &Chart) -> Option<Vec<[f64; 2]>> {
    let p = &chart.positions;
    if p.is_empty() || chart.triangles.is_empty() {
        return None;
    }
    // The plane: the area-weighted normal of the triangles through the centroid.
    let mut normal = [0.0; 3];
    for t in &chart.triangles {
        let c = cross(sub(p[t[1] as usize], p[t[0] as usize]), sub(p[t[2] as usize], p[t[0] as usize]));
        normal = [normal[0] + c[0], normal[1] + c[1], normal[2] + c[2]];
    }
    if !(norm(normal) > 0.0) {
        return None;
    }
    let z = unit(normal);
    let n = p.len() as f64;
    let centre = p.iter().fold([0.0; 3], |a, q| [a[0] + q[0] / n, a[1] + q[1] / n, a[2] + q[2] / n]);
    let (lo, hi) = bounds(p.iter());
    let size = norm(sub(hi, lo));
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    if p.iter().any(|q| !(dot(sub(*q, centre), z).abs() <= FLAT_TOLERANCE * size)) {
        return None;
    }
    // A right-handed basis of the plane (x, y, z), so a triangle wound around z is positive;
    // x along the world axis furthest from the normal (ties to the first), so a chart in the
    // ground plane keeps its x and y.
    let k = (0..3).min_by(|&a, &b| z[a].abs().total_cmp(&z[b].abs())).unwrap_or(0);
    let mut axis = [0.0; 3];
    axis[k] = 1.0;
    let x = unit(sub(axis, z.map(|c| c * z[k])));
    let y = cross(z, x);
    let uv: Vec<[f64; 2]> = p.iter().map(|q| sub(*q, centre)).map(|d| [dot(d, x), dot(d, y)]).collect();
    // Positive by the one flip definition, on the chart's triangles, both splits of its quads
    // and the render triangles the report counts on: a triangle without 3D area (three corners
    // on one line) would stay without UV area, and the method's thin rest shape is taken then.
    crate::metrics::face_flips(chart, &uv).iter().all(|&f| f == 0).then_some(uv)
}
