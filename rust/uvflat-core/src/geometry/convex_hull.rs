//! Convex hulls in the plane: of one point set ([`convex_hull`]), and of every island of a
//! per-corner UV map at once ([`island_hulls`]), which is what an island packer needs.
//!
//! Algorithm: Andrew's monotone chain (A. M. Andrew, "Another efficient algorithm for convex
//! hulls in two dimensions", Information Processing Letters 9(5), 1979): sort the points
//! lexicographically, then build the lower and upper chains keeping only left turns.
//! `O(n log n)`, exact orientation signs up to floating-point rounding of one cross product.
//!
//! Preconditions: finite points. Failures: none; a set with no area (fewer than three distinct
//! points, or all collinear) has an empty hull, and an island holding a non-finite UV is
//! reported with an empty hull too (the caller cannot pack it by its hull).

use rayon::prelude::*;

use super::cross2;
use crate::error::{Result, UvError};

/// The convex hull of `points`, counter-clockwise, without repeated or collinear vertices,
/// starting at the lexicographically smallest point; empty when the points span no area.
/// `points` is sorted in place.
pub fn convex_hull(points: &mut [[f64; 2]]) -> Vec<[f64; 2]> {
    let kept = discard_interior(points);
    let points = &mut points[..kept];
    points.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| cross2([a[0] - o[0], a[1] - o[1]], [b[0] - o[0], b[1] - o[1]]);
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(n.min(64) + 1);
    for &p in points.iter() {
        while hull.len() >= 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in points.iter().rev().skip(1) {
        while hull.len() >= lower && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop(); // the first point again
    if hull.len() < 3 {
        hull.clear();
    }
    hull
}

/// Akl–Toussaint heuristic (S. G. Akl and G. T. Toussaint, "A fast convex hull algorithm",
/// Information Processing Letters 7(5), 1978): the extreme points in eight directions span a
/// convex polygon inside the hull; points strictly inside it cannot be hull vertices. Moves
/// the other points to the front and returns their count (all of them for small sets).
fn discard_interior(points: &mut [[f64; 2]]) -> usize {
    if points.len() < 64 {
        return points.len();
    }
    // directions counter-clockwise: +x, +x+y, +y, −x+y, −x, −x−y, −y, +x−y
    const DIRS: [[f64; 2]; 8] = [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, 0.0], [-1.0, -1.0], [0.0, -1.0], [1.0, -1.0]];
    let mut best = [points[0]; 8];
    let mut score = [f64::NEG_INFINITY; 8];
    for &p in points.iter() {
        for (k, d) in DIRS.iter().enumerate() {
            let s = d[0] * p[0] + d[1] * p[1];
            if s > score[k] {
                score[k] = s;
                best[k] = p;
            }
        }
    }
    let mut poly: Vec<[f64; 2]> = Vec::with_capacity(8);
    for &p in &best {
        if poly.last() != Some(&p) && poly.first() != Some(&p) {
            poly.push(p);
        }
    }
    if poly.len() < 3 {
        return points.len();
    }
    let inside = |p: [f64; 2]| {
        (0..poly.len()).all(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            cross2([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]) > 0.0
        })
    };
    let mut kept = 0;
    for i in 0..points.len() {
        if !inside(points[i]) {
            points.swap(kept, i);
            kept += 1;
        }
    }
    kept
}

/// Convex hulls of the islands of a per-corner UV map, in one compressed list.
#[derive(Debug, Clone, PartialEq)]
pub struct IslandHulls {
    /// `offsets[k]..offsets[k + 1]` are island `k`'s hull vertices in `points`
    /// (`n_islands + 1` entries); an island whose hull is empty has no area (or holds a
    /// non-finite UV).
    pub offsets: Vec<usize>,
    /// Hull vertices, counter-clockwise per island (see [`convex_hull`]).
    pub points: Vec<[f64; 2]>,
}

/// The convex hull of every island's corner UVs.
///
/// `uv` has one row per corner (faces' corners in order, `face_sizes` corners each);
/// `face_island[f]` is face `f`'s island in `0..n_islands`, or negative for a face in no
/// island. Island indices must be below the number of faces (a dense numbering always is);
/// an index no face uses gets an empty hull. Islands are independent and run in parallel.
///
/// Errors: [`UvError::Shape`] when the lengths disagree or an island index is out of range
/// (naming the face).
pub fn island_hulls(uv: &[[f64; 2]], face_sizes: &[u32], face_island: &[i64]) -> Result<IslandHulls> {
    if face_island.len() != face_sizes.len() {
        return Err(UvError::Shape {
            what: "face_island",
            detail: format!("has {} entries, the mesh has {} faces", face_island.len(), face_sizes.len()),
        });
    }
    let n_corners: usize = face_sizes.iter().map(|&s| s as usize).sum();
    if uv.len() != n_corners {
        return Err(UvError::Shape { what: "uv", detail: format!("has {} rows, the faces have {n_corners} corners", uv.len()) });
    }
    let n_islands = face_island.iter().copied().max().map_or(0, |m| (m + 1).max(0) as usize);
    if n_islands > face_sizes.len() {
        let face = face_island.iter().position(|&k| k >= face_sizes.len() as i64).unwrap_or(0);
        return Err(UvError::Shape {
            what: "face_island",
            detail: format!("face {face}: island {} out of range (islands are numbered below the face count)", face_island[face]),
        });
    }
    // corners grouped by island (counting sort)
    let mut start = vec![0usize; n_islands + 1];
    for (&k, &s) in face_island.iter().zip(face_sizes) {
        if k >= 0 {
            start[k as usize + 1] += s as usize;
        }
    }
    for k in 0..n_islands {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut grouped = vec![[0.0f64; 2]; start[n_islands]];
    let mut corner = 0usize;
    for (&k, &s) in face_island.iter().zip(face_sizes) {
        let s = s as usize;
        if k >= 0 {
            let at = &mut fill[k as usize];
            grouped[*at..*at + s].copy_from_slice(&uv[corner..corner + s]);
            *at += s;
        }
        corner += s;
    }
    let mut pieces: Vec<&mut [[f64; 2]]> = Vec::with_capacity(n_islands);
    let mut rest: &mut [[f64; 2]] = &mut grouped;
    for k in 0..n_islands {
        let (head, tail) = rest.split_at_mut(start[k + 1] - start[k]);
        pieces.push(head);
        rest = tail;
    }
    let hulls: Vec<Vec<[f64; 2]>> = pieces
        .into_par_iter()
        .map(|points| {
            if points.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
                return Vec::new();
            }
            convex_hull(points)
        })
        .collect();
    let mut offsets = Vec::with_capacity(n_islands + 1);
    offsets.push(0);
    let mut points = Vec::with_capacity(hulls.iter().map(Vec::len).sum());
    for h in hulls {
        points.extend_from_slice(&h);
        offsets.push(points.len());
    }
    Ok(IslandHulls { offsets, points })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(h: &[[f64; 2]]) -> f64 {
        (0..h.len()).map(|i| cross2(h[i], h[(i + 1) % h.len()])).sum::<f64>() / 2.0
    }

    #[test]
    fn square_with_inner_and_edge_points() {
        let mut p = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [0.5, 0.0], [1.0, 0.5], [0.0, 0.0]];
        let h = convex_hull(&mut p);
        assert_eq!(h, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert!((area(&h) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn collinear_and_tiny_sets_have_no_hull() {
        assert!(convex_hull(&mut [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.5, 0.5]]).is_empty());
        assert!(convex_hull(&mut [[0.0, 0.0], [1.0, 1.0]]).is_empty());
        assert!(convex_hull(&mut [[3.0, 3.0]; 5]).is_empty());
    }
}
