//! n-gon triangulation by ear clipping in the polygon's own plane (concave polygons too).

use crate::geometry::{cross, dot, norm};

/// Triangulate a simple polygon given by its 3D corner positions, in order.
///
/// Returns triangles as triples of corner positions `0..n`, oriented like the polygon.
/// The polygon is projected onto the plane of its Newell normal and ears are clipped,
/// among the valid ears the one with the best
/// (largest) minimum angle is cut, which keeps quads split along the better diagonal.
/// Degenerate or self-intersecting input never fails: when no valid ear exists the rest is
/// fanned, so the result always has exactly `n - 2` triangles covering every corner.
pub fn triangulate_polygon(pts: &[[f64; 3]]) -> Vec<[usize; 3]> {
    triangulate_polygon_avoiding(pts, |_, _| false)
}

/// [`triangulate_polygon`], preferring ears whose new diagonal `(i, j)` (corner positions) is
/// not `taken`: a diagonal that already exists as an edge elsewhere would make two triangles
/// share a directed edge (two quads around a valence-2 vertex split along the same diagonal).
/// A taken diagonal is used only when no other valid ear exists.
pub fn triangulate_polygon_avoiding(pts: &[[f64; 3]], taken: impl FnMut(usize, usize) -> bool) -> Vec<[usize; 3]> {
    triangulate_polygon_with(pts, taken, None)
}

/// [`triangulate_polygon_avoiding`] where a quad may be asked to split through one corner
/// (`through`): used for a vertex shared by only two faces (a cone point with a small angle
/// sum, as around a valence-2 vertex), which flattening opens up to a full turn — the other
/// diagonal would leave a sliver with an angle near π there.
pub fn triangulate_polygon_with(
    pts: &[[f64; 3]],
    mut taken: impl FnMut(usize, usize) -> bool,
    through: Option<usize>,
) -> Vec<[usize; 3]> {
    let n = pts.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return vec![[0, 1, 2]];
    }
    // Newell normal and a 2D basis of its plane.
    let mut nrm = [0.0f64; 3];
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    let ln = norm(nrm);
    let p2: Vec<[f64; 2]> = if ln > 0.0 {
        let z = [nrm[0] / ln, nrm[1] / ln, nrm[2] / ln];
        let helper = if z[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
        let x = cross(helper, z);
        let lx = norm(x);
        let x = [x[0] / lx, x[1] / lx, x[2] / lx];
        let y = cross(z, x);
        pts.iter().map(|p| [dot(*p, x), dot(*p, y)]).collect()
    } else {
        return (1..n - 1).map(|i| [0, i, i + 1]).collect();
    };

    if n == 4 {
        // Quads: pick the diagonal whose two triangles have the larger minimum angle (both
        // must be positively oriented), so a corner of ~180° never ends up in a sliver.
        let area2 = |a: usize, b: usize, c: usize| {
            let (pa, pb, pc) = (p2[a], p2[b], p2[c]);
            (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0])
        };
        let mut best: Option<(f64, [[usize; 3]; 2])> = None;
        for (d0, d1) in [(0usize, 2usize), (1, 3)] {
            let tris = if d0 == 0 { [[0, 1, 2], [0, 2, 3]] } else { [[0, 1, 3], [1, 2, 3]] };
            if tris.iter().any(|t| area2(t[0], t[1], t[2]) <= 0.0) {
                continue;
            }
            let q = tris
                .iter()
                .map(|t| min_angle_2d(p2[t[0]], p2[t[1]], p2[t[2]]))
                .fold(f64::INFINITY, f64::min)
                - if taken(d0, d1) { 10.0 } else { 0.0 }
                - if through.is_some_and(|k| k != d0 && k != d1) { 5.0 } else { 0.0 };
            if best.is_none_or(|(bq, _)| q > bq + 1e-9 * bq.abs() + 1e-300) {
                best = Some((q, tris));
            }
        }
        if let Some((_, tris)) = best {
            return tris.to_vec();
        }
    }
    let mut idx: Vec<usize> = (0..n).collect();
    let mut out = Vec::with_capacity(n - 2);
    while idx.len() > 3 {
        let m = idx.len();
        let mut best: Option<(usize, f64)> = None;
        for k in 0..m {
            let (a, b, c) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (pa, pb, pc) = (p2[a], p2[b], p2[c]);
            let area2 = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
            if area2 <= 0.0 {
                continue; // reflex or degenerate corner
            }
            // No other remaining vertex inside the ear.
            let inside = idx.iter().any(|&o| {
                o != a && o != b && o != c && point_in_triangle(p2[o], pa, pb, pc)
            });
            if inside {
                continue;
            }
            // A taken diagonal ranks below every free one.
            let q = min_angle_2d(pa, pb, pc) - if idx.len() > 3 && taken(a, c) { 10.0 } else { 0.0 };
            // Strictly better by a relative margin: ties (rectangles) resolve the same way
            // under rigid motions and round-off.
            if best.is_none_or(|(_, bq)| q > bq + 1e-9 * bq.abs() + 1e-300) {
                best = Some((k, q));
            }
        }
        let k = match best {
            Some((k, _)) => k,
            None => {
                // No valid ear (degenerate / self-intersecting): fan the rest.
                for i in 1..idx.len() - 1 {
                    out.push([idx[0], idx[i], idx[i + 1]]);
                }
                return out;
            }
        };
        let m = idx.len();
        out.push([idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]]);
        idx.remove(k);
    }
    out.push([idx[0], idx[1], idx[2]]);
    out
}

fn point_in_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let s = |u: [f64; 2], v: [f64; 2], w: [f64; 2]| (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0]);
    let d1 = s(a, b, p);
    let d2 = s(b, c, p);
    let d3 = s(c, a, p);
    d1 >= 0.0 && d2 >= 0.0 && d3 >= 0.0
}

fn min_angle_2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let ang = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let u = [q[0] - p[0], q[1] - p[1], 0.0];
        let v = [r[0] - p[0], r[1] - p[1], 0.0];
        crate::geometry::angle_between(u, v)
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area2(p: &[[f64; 3]], t: [usize; 3]) -> f64 {
        let a = p[t[0]];
        let b = p[t[1]];
        let c = p[t[2]];
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn concave_l_shape_is_covered_without_flips() {
        let p = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 4);
        let total: f64 = t.iter().map(|&t| area2(&p, t)).sum();
        assert!((total - 6.0).abs() < 1e-12, "twice the L area is 6, got {total}");
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }

    #[test]
    fn a_quad_splits_through_the_requested_corner() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for k in 0..4 {
            let t = triangulate_polygon_with(&p, |_, _| false, Some(k));
            assert!(t.iter().all(|tri| tri.contains(&k)), "{k}: {t:?}");
        }
    }

    #[test]
    fn a_taken_diagonal_is_avoided() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for (a, b) in [(0, 2), (1, 3)] {
            let t = triangulate_polygon_avoiding(&p, |i, j| (i.min(j), i.max(j)) == (a, b));
            assert!(t.iter().all(|tri| !(tri.contains(&a) && tri.contains(&b))), "{t:?}");
        }
    }

    #[test]
    fn kite_is_split_along_the_diagonal_with_the_larger_minimum_angle() {
        // Diagonal 0-2 would give two slivers of angle ~0.05 rad; 1-3 gives a minimum of ~0.1.
        let p = [[0.0, 0.0, 0.0], [1.0, -0.05, 0.0], [2.0, 0.0, 0.0], [1.0, 0.05, 0.0]];
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 2);
        assert!(t.iter().all(|&t| t.contains(&1) && t.contains(&3)), "{t:?}");
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }
}
