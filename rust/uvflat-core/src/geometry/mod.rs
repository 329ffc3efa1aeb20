//! What needs positions: corner angles (robust, clamped), areas, local 2D frames;
//! [`convex_hull`], planar hulls of point sets and of UV islands; [`min_box`], the turn of
//! a hull (of every island's) to its bounding box of least area; and [`box_grid`], the pairs
//! of 2D boxes that overlap.

pub mod box_grid;
pub mod convex_hull;
pub mod min_box;

/// Smallest corner angle (radians) a triangle is given when its 3D angles are used as
/// targets. Degenerate (zero-area) triangles would otherwise have zero angles, infinite
/// cotangents and NaN UVs; clamping gives them a thin but valid shape instead.
pub const MIN_ANGLE: f64 = 1e-4;

#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
/// `a` scaled to unit length; zero for a zero (or non-finite-length) vector.
#[inline]
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = norm(a);
    if l > 0.0 && l.is_finite() {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0; 3]
    }
}
/// Axis-aligned bounds `(lo, hi)` of points (infinite and reversed when there are none).
pub fn bounds<'p>(points: impl Iterator<Item = &'p [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    points.fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(mut lo, mut hi), p| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    })
}
/// Newell's normal of the polygon `point(0), …, point(n − 1)`: twice its vector area, robust
/// for non-planar polygons (its length is twice the area of a planar one).
pub fn newell_normal(n: usize, point: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
    let mut nrm = [0.0f64; 3];
    for i in 0..n {
        let (a, b) = (point(i), point((i + 1) % n));
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    nrm
}
#[inline]
pub fn cross2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Angle between two vectors, robust for tiny and near-parallel vectors (atan2 form).
/// Returns 0 if either vector is zero.
#[inline]
pub fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = norm(cross(a, b));
    let d = dot(a, b);
    if c == 0.0 && d == 0.0 {
        0.0
    } else {
        c.atan2(d)
    }
}

/// The three corner angles of triangle (p0, p1, p2), exact (unclamped).
pub fn raw_angles(p: [[f64; 3]; 3]) -> [f64; 3] {
    let mut a = [0.0; 3];
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        a[k] = angle_between(sub(p[i], p[k]), sub(p[j], p[k]));
    }
    a
}

/// Corner angles clamped to `[MIN_ANGLE, π − 2·MIN_ANGLE]` and summing to π.
///
/// A triangle whose three points coincide gets π/3 everywhere; a collinear one gets a thin
/// valid shape. Always finite.
pub fn clamped_angles(p: [[f64; 3]; 3]) -> [f64; 3] {
    let a = raw_angles(p);
    let sum: f64 = a.iter().sum();
    if !(sum > 1e-12) || a.iter().any(|x| !x.is_finite()) {
        return [std::f64::consts::FRAC_PI_3; 3];
    }
    normalize_angles(a)
}

/// Clamp three angles to at least [`MIN_ANGLE`] and rescale to sum exactly π.
pub fn normalize_angles(a: [f64; 3]) -> [f64; 3] {
    let pi = std::f64::consts::PI;
    let mut a = a;
    let sum: f64 = a.iter().sum();
    if sum > 0.0 {
        for x in a.iter_mut() {
            *x *= pi / sum;
        }
    }
    let mut deficit = 0.0;
    for x in a.iter_mut() {
        if *x < MIN_ANGLE {
            deficit += MIN_ANGLE - *x;
            *x = MIN_ANGLE;
        }
    }
    if deficit > 0.0 {
        // Take the deficit from the largest angle.
        let k = (0..3).max_by(|&i, &j| a[i].total_cmp(&a[j])).unwrap();
        a[k] -= deficit;
    }
    a
}

/// Area of triangle (p0, p1, p2).
#[inline]
pub fn triangle_area(p: [[f64; 3]; 3]) -> f64 {
    0.5 * norm(cross(sub(p[1], p[0]), sub(p[2], p[0])))
}

/// Signed area of a UV triangle.
#[inline]
pub fn signed_area_2d(q: [[f64; 2]; 3]) -> f64 {
    0.5 * cross2([q[1][0] - q[0][0], q[1][1] - q[0][1]], [q[2][0] - q[0][0], q[2][1] - q[0][1]])
}

/// The triangle in a local orthonormal 2D frame of its plane: q0 = (0,0), q1 = (|e1|, 0),
/// q2 with positive y (for non-degenerate triangles).
pub fn local_frame(p: [[f64; 3]; 3]) -> [[f64; 2]; 3] {
    let e1 = sub(p[1], p[0]);
    let e2 = sub(p[2], p[0]);
    let l1 = norm(e1);
    if l1 == 0.0 {
        let l2 = norm(e2);
        return [[0.0, 0.0], [0.0, 0.0], [l2, 0.0]];
    }
    let x = [e1[0] / l1, e1[1] / l1, e1[2] / l1];
    let n = cross(e1, e2);
    let y = cross(n, x);
    let ly = norm(y);
    let qy = if ly > 0.0 { dot(e2, y) / ly } else { 0.0 };
    [[0.0, 0.0], [l1, 0.0], [dot(e2, x), qy]]
}

/// Centre and size of a point set: the middle of its bounding box and its largest half
/// extent, computed without squaring coordinates (so it never overflows for finite input).
/// Points are brought to unit size by `(p − centre) / size`. The size is 1 for an empty or
/// single-point set or non-finite input.
pub fn bounding_frame<const D: usize>(points: &[[f64; D]]) -> ([f64; D], f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    for p in points {
        for d in 0..D {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let mut centre = [0.0; D];
    let mut size = 0.0f64;
    for d in 0..D {
        if lo[d] <= hi[d] {
            // Halves first: hi − lo of two finite values can overflow, their halves cannot.
            centre[d] = 0.5 * lo[d] + 0.5 * hi[d];
            size = size.max(0.5 * hi[d] - 0.5 * lo[d]);
        }
    }
    if !(size > 0.0 && size.is_finite() && centre.iter().all(|c| c.is_finite())) {
        return (if centre.iter().all(|c| c.is_finite()) { centre } else { [0.0; D] }, 1.0);
    }
    (centre, size)
}

/// Points moved and scaled by a [`bounding_frame`]: `(p − centre) / size`.
pub fn to_unit_frame<const D: usize>(points: &[[f64; D]], centre: [f64; D], size: f64) -> Vec<[f64; D]> {
    points
        .iter()
        .map(|p| {
            let mut q = [0.0; D];
            for d in 0..D {
                q[d] = (p[d] - centre[d]) / size;
            }
            q
        })
        .collect()
}
