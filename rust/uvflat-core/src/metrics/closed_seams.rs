//! Closed seams: an outline that meets itself only where the two sides of one cut lie on each
//! other is not an overlap.
//!
//! A cut copies its vertices: each copy keeps the 3D position of the vertex it was cut from.
//! Where a map lays the two sides of a cut exactly on each other (the exact unfolding of flat
//! surface does, for a cut that joins a hole to the outline: a flat face with a hole comes
//! out as it is, its seam closed), the outline touches itself, yet every texel there belongs
//! to one surface point: the same point, reached from either side of the seam. Such a
//! contact is benign, and [`outline_overlap`] does not count it, when:
//!
//! * the two segments are copies of one 3D edge on the same UV segment (their ends, matched
//!   by 3D position, at the same UVs), or they meet only at one point where two copies of one
//!   3D vertex sit on the same UV (and do not run along each other from there); "the same
//!   UV" within [`TWIN_TOLERANCE`] of the outline's extent, as an unfolding reaches the two
//!   copies along different strips of triangles; and
//! * the triangles around the two copies at each such point do not overlap (their interiors
//!   are disjoint to within the same tolerance, by separating axes): the two sides of the
//!   seam lie on either side of it.
//!
//! A crack in the mesh is laid closed the same way: a T-junction (an outline vertex lying on
//! an outline edge in 3D, as where two contours of a font's glyph or of a CAD export touch)
//! or a slit of zero width (two outline edges folding back onto each other). The exact map of
//! flat surface puts the vertex on the edge in UV too. Such a contact is benign when:
//!
//! * every end of either segment that lies on the other in UV (within [`CRACK_TOLERANCE`] of
//!   the outline's extent) is the same 3D point as the place it touches (the point of the other
//!   segment at the same share of its length, within [`CRACK_TOLERANCE`] of the outline's 3D
//!   extent: rounding to single precision moves a T-junction's vertex off its edge by about
//!   1e-7), and at least one does (segments whose interiors cross are no crack); and
//! * the triangles around the touching end do not overlap those around the other segment's
//!   ends by more than that tolerance; and
//! * the touching end is no copy of either end of the other segment (the two sides of a cut
//!   are held to the closed seam's tighter tolerance above).
//!
//! Every other contact counts as in [`super::boundary_self_overlap`]: crossings, touches of
//! different surface points, a seam's sides lying on each other only nearly (its copies
//! further apart than the tolerance). Flips are counted apart ([`super::flipped_triangles`]).
//!
//! Preconditions: `positions`, `triangles`, `uv` and `loops` of one chart (copies of a cut
//! vertex carry identical positions, as [`crate::charts`] makes them). Deterministic.

use super::{boundary_crossings_except, orient, BRUTE_FORCE_SEGMENTS};

/// Whether the outline of the chart crosses or touches itself other than along closed seams
/// (see the module docs).
pub fn outline_overlap(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &[[f64; 2]], loops: &[Vec<u32>]) -> bool {
    !outline_crossings(positions, triangles, uv, loops, 1).is_empty()
}

/// The pairs of outline segments that cross or touch other than along closed seams, as
/// [`super::boundary_crossings`] lists them, up to `limit` pairs.
pub fn outline_crossings(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uv: &[[f64; 2]],
    loops: &[Vec<u32>],
    limit: usize,
) -> Vec<[[u32; 2]; 2]> {
    let twins = Twins::new(positions, triangles, uv, loops);
    boundary_crossings_except(uv, loops, BRUTE_FORCE_SEGMENTS, limit, &|s, t| twins.benign(s, t))
}

/// The outline's vertices grouped by 3D position, and the triangles around each vertex
/// (made on first use: most outlines never touch themselves).
struct Twins<'a> {
    positions: &'a [[f64; 3]],
    triangles: &'a [[u32; 3]],
    uv: &'a [[f64; 2]],
    /// Per chart vertex on the outline: the lowest outline vertex at the same 3D position
    /// (`u32::MAX` off the outline).
    key: Vec<u32>,
    /// Triangles around each vertex (CSR: starts, then triangle ids).
    around: std::sync::OnceLock<(Vec<u32>, Vec<u32>)>,
    /// How far apart two copies' UVs may be and still count as one point: [`TWIN_TOLERANCE`]
    /// of the outline's extent.
    tolerance: f64,
    /// [`CRACK_TOLERANCE`] of the outline's extent in UV and in 3D.
    crack: [f64; 2],
}

/// Copies of one vertex count as one UV point within this share of the outline's extent (an
/// exact unfolding reaches them along different strips of triangles, a few units in the last
/// place apart).
pub const TWIN_TOLERANCE: f64 = 1e-9;

/// A crack's sides count as laid on each other, and its points as one, within this share of
/// the outline's extent (in UV and in 3D): a T-junction rounded to single precision is off its
/// edge by about 1e-7 of the part's size; the flatness a chart is laid as it is within is 1e-6
/// ([`crate::methods::planar`]).
pub const CRACK_TOLERANCE: f64 = 1e-6;

impl<'a> Twins<'a> {
    fn new(positions: &'a [[f64; 3]], triangles: &'a [[u32; 3]], uv: &'a [[f64; 2]], loops: &[Vec<u32>]) -> Self {
        let mut key = vec![u32::MAX; positions.len()];
        let mut outline: Vec<u32> =
            loops.iter().flatten().copied().filter(|&v| (v as usize) < positions.len()).collect();
        let bits = |v: u32| positions[v as usize].map(f64::to_bits);
        outline.sort_unstable_by(|&a, &b| bits(a).cmp(&bits(b)).then(a.cmp(&b)));
        outline.dedup();
        for run in outline.chunk_by(|&a, &b| bits(a) == bits(b)) {
            for &v in run {
                key[v as usize] = run[0];
            }
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let (mut lo3, mut hi3) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &v in &outline {
            let p = uv[v as usize];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
            let q = positions[v as usize];
            lo3 = std::array::from_fn(|k| lo3[k].min(q[k]));
            hi3 = std::array::from_fn(|k| hi3[k].max(q[k]));
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0.0);
        let extent3 = (0..3).map(|k| hi3[k] - lo3[k]).fold(0.0, f64::max);
        let tolerance = TWIN_TOLERANCE * extent;
        let crack = [CRACK_TOLERANCE * extent, CRACK_TOLERANCE * extent3];
        Twins { positions, triangles, uv, key, around: std::sync::OnceLock::new(), tolerance, crack }
    }

    /// Two different copies of one 3D vertex at the same UV (within the tolerance).
    fn twins(&self, a: u32, b: u32) -> bool {
        let (ka, kb) = (self.key[a as usize], self.key[b as usize]);
        let (p, q) = (self.uv[a as usize], self.uv[b as usize]);
        a != b && ka != u32::MAX && ka == kb && (p[0] - q[0]).abs().max((p[1] - q[1]).abs()) <= self.tolerance
    }

    /// Whether segments `s` and `t` (they cross or touch, or follow each other and fold back)
    /// meet only along a closed seam or a crack (see the module docs).
    fn benign(&self, s: [u32; 2], t: [u32; 2]) -> bool {
        self.closed_seam(s, t) || self.crack(s, t)
    }

    /// Whether `s` and `t` touch only where the mesh has a crack laid closed (module docs).
    fn crack(&self, s: [u32; 2], t: [u32; 2]) -> bool {
        let [tol_uv, tol_3d] = self.crack;
        let mut touches = false;
        for (x, y) in [(s, t), (t, s)] {
            for e in x {
                if y.contains(&e) {
                    continue;
                }
                let key = self.key[e as usize];
                if key != u32::MAX && y.iter().any(|&w| self.key[w as usize] == key) {
                    // Copies of one cut vertex: a seam, held to [`TWIN_TOLERANCE`].
                    return false;
                }
                let (p, a, b) = (self.uv[e as usize], self.uv[y[0] as usize], self.uv[y[1] as usize]);
                let d = [b[0] - a[0], b[1] - a[1]];
                let len2 = d[0] * d[0] + d[1] * d[1];
                if !(len2 > 0.0) {
                    return false;
                }
                let share = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0);
                let off = (a[0] + share * d[0] - p[0]).hypot(a[1] + share * d[1] - p[1]);
                if off > tol_uv {
                    continue;
                }
                let q = self.positions[e as usize];
                let (qa, qb) = (self.positions[y[0] as usize], self.positions[y[1] as usize]);
                let apart = (0..3).map(|k| qa[k] + share * (qb[k] - qa[k]) - q[k]).map(|x| x * x).sum::<f64>().sqrt();
                if !(apart <= tol_3d) {
                    return false;
                }
                touches = true;
                if y.iter().any(|&w| self.fans_overlap_by(e, w, tol_uv)) {
                    return false;
                }
            }
        }
        touches
    }

    /// Whether `s` and `t` (no chart vertex in common) meet only along a closed seam.
    fn closed_seam(&self, s: [u32; 2], t: [u32; 2]) -> bool {
        if s.iter().any(|v| t.contains(v)) {
            return false;
        }
        let meet: Vec<(u32, u32)> =
            s.iter().flat_map(|&a| t.iter().map(move |&b| (a, b))).filter(|&(a, b)| self.twins(a, b)).collect();
        let contact = match meet.len() {
            // Copies of one 3D edge on the same UV segment.
            2 if meet[0].0 != meet[1].0 && meet[0].1 != meet[1].1 => true,
            // One shared point: the segments must leave it in different directions.
            1 => {
                let (a, b) = meet[0];
                let p = self.uv[a as usize];
                let s_other = self.uv[if s[0] == a { s[1] } else { s[0] } as usize];
                let t_other = self.uv[if t[0] == b { t[1] } else { t[0] } as usize];
                let (u, v) = ([s_other[0] - p[0], s_other[1] - p[1]], [t_other[0] - p[0], t_other[1] - p[1]]);
                orient(p, s_other, t_other) != 0.0 || u[0] * v[0] + u[1] * v[1] < 0.0
            }
            _ => false,
        };
        contact && meet.iter().all(|&(a, b)| !self.fans_overlap(a, b))
    }

    /// Whether a triangle around `a` and one around `b` overlap (interiors, by separating
    /// axes; triangles that share only an edge or a point do not).
    fn fans_overlap(&self, a: u32, b: u32) -> bool {
        self.fans_overlap_by(a, b, self.tolerance)
    }

    /// [`Self::fans_overlap`] by more than `tol`.
    fn fans_overlap_by(&self, a: u32, b: u32, tol: f64) -> bool {
        let (start, ids) = self.around.get_or_init(|| {
            let n = self.uv.len();
            let mut start = vec![0u32; n + 1];
            for t in self.triangles {
                for &v in t {
                    start[v as usize + 1] += 1;
                }
            }
            for v in 0..n {
                start[v + 1] += start[v];
            }
            let mut fill = start.clone();
            let mut ids = vec![0u32; start[n] as usize];
            for (k, t) in self.triangles.iter().enumerate() {
                for &v in t {
                    ids[fill[v as usize] as usize] = k as u32;
                    fill[v as usize] += 1;
                }
            }
            (start, ids)
        });
        let fan = |v: u32| &ids[start[v as usize] as usize..start[v as usize + 1] as usize];
        let corners = |k: u32| self.triangles[k as usize].map(|v| self.uv[v as usize]);
        fan(a).iter().any(|&x| fan(b).iter().any(|&y| x != y && interiors_overlap(corners(x), corners(y), tol)))
    }
}

/// Whether the interiors of two UV triangles overlap by more than `tol`: no edge direction of
/// either separates them to within `tol` (touching along an edge or at a point is no overlap;
/// the tolerance is the one copies of a vertex are matched with, so the two sides of a seam
/// laid within rounding of each other do not overlap).
pub(crate) fn interiors_overlap(p: [[f64; 2]; 3], q: [[f64; 2]; 3], tol: f64) -> bool {
    for tri in [p, q] {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let n = [a[1] - b[1], b[0] - a[0]];
            let len = n[0].hypot(n[1]);
            if !(len > 0.0) {
                continue;
            }
            let span = |t: &[[f64; 2]; 3]| {
                t.iter()
                    .map(|c| (c[0] * n[0] + c[1] * n[1]) / len)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)))
            };
            let ((lo_p, hi_p), (lo_q, hi_q)) = (span(&p), span(&q));
            if hi_p <= lo_q + tol || hi_q <= lo_p + tol {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat 3×3 grid of unit squares whose middle square is a hole, cut from the hole's
    /// corner (1, 1) straight down to the outline at (1, 0): each cut vertex is copied.
    /// Returns positions, triangles, the outline (one loop after the cut) and the copies.
    fn slit_square() -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<Vec<u32>>) {
        // Vertices (x, y) for x, y in 0..=3 at id 4y + x; copies of (1,0) and (1,1) at 16, 17.
        let mut pos: Vec<[f64; 3]> = (0..16).map(|i| [(i % 4) as f64, (i / 4) as f64, 0.0]).collect();
        pos.push([1.0, 0.0, 0.0]); // 16: copy of 1
        pos.push([1.0, 1.0, 0.0]); // 17: copy of 5
        let mut tris = Vec::new();
        for y in 0..3u32 {
            for x in 0..3u32 {
                if (x, y) == (1, 1) {
                    continue; // the hole
                }
                let (mut a, b, c, mut d) = (4 * y + x, 4 * y + x + 1, 4 * (y + 1) + x + 1, 4 * (y + 1) + x);
                // The square right of the cut (x = 1, y = 0) uses the copies on its left side.
                if (x, y) == (1, 0) {
                    a = 16;
                    d = 17;
                }
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        // One outline: along the bottom from the cut's right copy, round the outside, back along
        // the bottom to the cut's left side, up the cut, round the hole, down the cut's right
        // copy.
        let outline = vec![16, 2, 3, 7, 11, 15, 14, 13, 12, 8, 4, 0, 1, 5, 9, 10, 6, 17];
        (pos, tris, vec![outline])
    }

    fn uv_of(pos: &[[f64; 3]]) -> Vec<[f64; 2]> {
        pos.iter().map(|p| [p[0], p[1]]).collect()
    }

    #[test]
    fn a_seam_closed_on_flat_surface_is_no_overlap_but_an_outline_touch() {
        let (pos, tris, loops) = slit_square();
        let uv = uv_of(&pos);
        assert!(super::super::flipped_triangles(&tris, &uv).iter().all(|&f| !f));
        // The plain check sees the two sides of the cut touching.
        assert!(super::super::boundary_self_overlap(&uv, &loops));
        assert!(!outline_overlap(&pos, &tris, &uv, &loops));
    }

    #[test]
    fn copies_apart_or_different_points_touching_still_overlap() {
        let (pos, tris, loops) = slit_square();
        // The cut's right side moved over its left side: copies at different UVs whose
        // triangles overlap along the seam, beyond the tolerance (3e-9 here).
        for shift in [1e-6, 1e-8] {
            let mut uv = uv_of(&pos);
            uv[16][0] -= shift;
            uv[17][0] -= shift;
            assert!(outline_overlap(&pos, &tris, &uv, &loops), "{shift}");
        }
        // Over each other by rounding only, within the tolerance: a closed seam.
        for shift in [1e-15, 1e-10] {
            let mut uv = uv_of(&pos);
            uv[16][0] -= shift;
            uv[17][0] -= shift;
            assert!(!outline_overlap(&pos, &tris, &uv, &loops), "{shift}");
        }
        // The same layout with the copies told apart in 3D (two surface points that touch).
        let mut apart = pos.clone();
        apart[16][2] = 1e-3;
        apart[17][2] = 1e-3;
        assert!(outline_overlap(&apart, &tris, &uv_of(&pos), &loops));
    }

    #[test]
    fn a_closed_seam_whose_sides_fold_onto_each_other_overlaps() {
        let (pos, tris, loops) = slit_square();
        // Fold the square right of the cut over onto the square left of it: the cut's two
        // sides still coincide, but triangles on both sides now cover the same UVs.
        let mut uv = uv_of(&pos);
        uv[2] = [0.0, 0.0];
        uv[6] = [0.0, 1.0];
        assert!(super::super::flipped_triangles(&tris, &uv).iter().any(|&f| f));
        assert!(outline_overlap(&pos, &tris, &uv, &loops));
    }

    /// The square [0, 2]² with a crack of zero width from its top edge down its middle to
    /// (1, 1): the crack's right side is one edge (1, 2)–(1, 1), its left side goes back up to
    /// (1, 1.5) only and leaves for the corner (0, 2) from there: a T-junction at (1, 1.5), as
    /// where a glyph's contours touch. Positions, triangles, the one outline.
    fn cracked_square() -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<Vec<u32>>) {
        let pos = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [1.0, 2.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 1.5, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let tris = vec![[1, 2, 3], [1, 3, 4], [0, 1, 4], [0, 4, 5], [0, 5, 6]];
        (pos, tris, vec![vec![0, 1, 2, 3, 4, 5, 6]])
    }

    #[test]
    fn a_crack_laid_closed_is_no_overlap_unless_its_sides_are_different_points() {
        let (pos, tris, loops) = cracked_square();
        let uv = uv_of(&pos);
        assert!(super::super::flipped_triangles(&tris, &uv).iter().all(|&f| !f));
        // The plain check sees the crack's sides fold back and touch.
        assert!(super::super::boundary_self_overlap(&uv, &loops));
        assert!(!outline_overlap(&pos, &tris, &uv, &loops));
        // The T-junction off its edge by single-precision rounding, in 3D and in UV (to either
        // side): still one point.
        for dx in [1e-8, -1e-8] {
            let (mut p, mut u) = (pos.clone(), uv.clone());
            p[5][0] += dx;
            u[5][0] += dx;
            assert!(!outline_overlap(&p, &tris, &u, &loops), "{dx}");
        }
        // The same UVs with the left side lifted off the right one in 3D: a different surface
        // point touches the edge.
        let mut lifted = pos.clone();
        lifted[5][2] = 1e-3;
        assert!(outline_overlap(&lifted, &tris, &uv, &loops));
        // The T-junction pushed across the edge, in 3D and in UV: the outline crosses itself.
        let (mut p, mut u) = (pos.clone(), uv.clone());
        p[5][0] += 1e-3;
        u[5][0] += 1e-3;
        assert!(outline_overlap(&p, &tris, &u, &loops));
    }

    #[test]
    fn separating_axes_tell_touching_from_overlapping_triangles() {
        let t = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let tol = 1e-9;
        assert!(!interiors_overlap(t, [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], tol)); // a shared edge
        assert!(!interiors_overlap(t, [[0.0, 0.0], [-1.0, 0.0], [0.0, -1.0]], tol)); // a shared point
        // Over the shared edge by less than the tolerance, and by more.
        assert!(!interiors_overlap(t, [[1.0 - 1e-12, 0.0], [0.0, 1.0 - 1e-12], [1.0, 1.0]], tol));
        assert!(interiors_overlap(t, [[1.0 - 1e-6, 0.0], [0.0, 1.0 - 1e-6], [1.0, 1.0]], tol));
        assert!(interiors_overlap(t, [[0.2, 0.2], [2.0, 0.2], [0.2, 2.0]], tol));
        assert!(interiors_overlap(t, t, tol));
    }
}
