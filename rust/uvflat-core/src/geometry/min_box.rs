//! The rotation that turns a convex polygon to its bounding box of least area
//! ([`min_box_angle`]), and that of every island's hull at once ([`island_box_angles`]): an
//! island packer that packs islands by their boxes, or may not rotate them, turns each island
//! that way first.
//!
//! Algorithm: rotating calipers. The least-area rectangle enclosing a convex polygon has a side
//! collinear with an edge of the polygon (H. Freeman and R. Shapira, "Determining the
//! minimum-area encasing rectangle for an arbitrary closed curve", Communications of the ACM
//! 18(7), 1975), so only the H boxes with a side along an edge are candidates. G. T. Toussaint
//! ("Solving geometric problems with the rotating calipers", Proc. IEEE MELECON '83, 1983)
//! measures them all in `O(H)`: walking the edges counter-clockwise, the vertex farthest along
//! the edge, the one farthest from it and the one farthest back along it only move forward, so
//! three pointers that each go round the polygon once give every edge's box. The polygon is
//! first moved and scaled to unit size ([`bounding_frame`]), so no area overflows or
//! underflows; the box of the angle chosen is measured again directly, and the polygon is left
//! as it lies unless that box is smaller than the one it has by more than [`KEEP_FACTOR`].
//!
//! Preconditions: a convex polygon, counter-clockwise (as [`convex_hull`](super::convex_hull::convex_hull)
//! returns it; a clockwise one is read backwards); repeated and collinear vertices are allowed.
//! A polygon that is not convex gets a finite angle, not necessarily the best one.
//!
//! Failures: none, and never a non-finite angle. A polygon of fewer than three points, of no
//! area (within rounding) or with a non-finite coordinate gets the angle 0 (it is left as it
//! is).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use rayon::prelude::*;

use super::convex_hull::IslandHulls;
use super::{bounding_frame, cross2, to_unit_frame};

/// A polygon whose axis-aligned box is within this factor of the least area is not turned:
/// turning it would save (almost) nothing.
pub const KEEP_FACTOR: f64 = 1.0 + 1e-6;

/// Boxes whose areas differ by less than this relative amount are ties: the smaller turn wins.
const TIE: f64 = 1e-12;

/// The rotation (radians, counter-clockwise) that turns the convex counter-clockwise polygon
/// `hull` to its bounding box of least area, in `[-π/4, π/4)` (a quarter turn more or less gives
/// the same box on its side; of boxes of equal area the smallest turn is taken).
///
/// Exactly `0.0` when the box `hull` has as it lies is within [`KEEP_FACTOR`] of the least, and
/// for fewer than three points, no area or a non-finite coordinate. `O(H)`.
pub fn min_box_angle(hull: &[[f64; 2]]) -> f64 {
    if hull.len() < 3 || hull.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
        return 0.0;
    }
    let (centre, size) = bounding_frame(hull);
    let mut p = to_unit_frame(hull, centre, size);
    p.dedup();
    while p.len() > 1 && p.first() == p.last() {
        p.pop();
    }
    let n = p.len();
    if n < 3 {
        return 0.0;
    }
    // twice the signed area; its rounding error is below a few ε per vertex (|coordinates| ≤ 1)
    let twice_area: f64 = (0..n).map(|i| cross2(p[i], p[(i + 1) % n])).sum();
    if !(twice_area.abs() > 8.0 * n as f64 * f64::EPSILON) {
        return 0.0;
    }
    if twice_area < 0.0 {
        p.reverse();
    }
    let Some(angle) = calipers(&p) else { return 0.0 };
    let turned = box_area(&p, angle);
    let as_is = box_area(&p, 0.0);
    if !(turned.is_finite() && as_is.is_finite()) || as_is <= turned * KEEP_FACTOR {
        return 0.0;
    }
    angle
}

/// The angle of least box area over the boxes with a side along an edge of the convex
/// counter-clockwise polygon `p` (no repeated consecutive vertices), normalised by
/// [`quarter_turn`]; `None` when no edge gives a finite area.
fn calipers(p: &[[f64; 2]]) -> Option<f64> {
    let n = p.len();
    let next = |j: usize| if j + 1 == n { 0 } else { j + 1 };
    let along = |j: usize, e: [f64; 2]| p[j][0] * e[0] + p[j][1] * e[1];
    // the pointers: farthest along the edge, farthest from it, farthest back along it
    let (mut ahead, mut above, mut behind) = (0usize, 0usize, 0usize);
    let mut started = false;
    let mut least = f64::INFINITY;
    let mut chosen: Option<(f64, f64)> = None; // (area, angle)
    for i in 0..n {
        let a = p[i];
        let e = [p[next(i)][0] - a[0], p[next(i)][1] - a[1]];
        let length2 = e[0] * e[0] + e[1] * e[1];
        if !(length2 > 0.0) {
            continue; // an edge too short to have a direction
        }
        if !started {
            ahead = next(i);
        }
        ahead = advance(ahead, n, |j| along(j, e));
        if !started {
            above = ahead;
        }
        above = advance(above, n, |j| cross2(e, p[j]));
        if !started {
            behind = above;
            started = true;
        }
        behind = advance(behind, n, |j| -along(j, e));
        // width and height are both |e| times their length
        let width = along(ahead, e) - along(behind, e);
        let height = cross2(e, [p[above][0] - a[0], p[above][1] - a[1]]);
        let area = width * height / length2;
        if !area.is_finite() {
            continue;
        }
        // turning the edge onto the u axis is a rotation by minus its direction
        let angle = quarter_turn(-e[1].atan2(e[0]));
        least = least.min(area);
        let better = match chosen {
            None => true,
            Some((best, best_angle)) => {
                area < best * (1.0 - TIE)
                    || (area <= best * (1.0 + TIE) && area <= least * (1.0 + TIE) && angle.abs() < best_angle.abs())
            }
        };
        if better {
            chosen = Some((area, angle));
        }
    }
    chosen.map(|(_, angle)| angle)
}

/// Move pointer `j` forward round a polygon of `n` vertices while `value` does not decrease
/// (along a convex polygon it rises to its maximum, then falls), at most once round.
fn advance(mut j: usize, n: usize, value: impl Fn(usize) -> f64) -> usize {
    let mut here = value(j);
    for _ in 0..n {
        let k = if j + 1 == n { 0 } else { j + 1 };
        let there = value(k);
        if !(there >= here) {
            break;
        }
        (j, here) = (k, there);
    }
    j
}

/// The same rotation as `angle` up to quarter turns, in `[-π/4, π/4)`.
fn quarter_turn(angle: f64) -> f64 {
    let mut a = angle - FRAC_PI_2 * ((angle + FRAC_PI_4) / FRAC_PI_2).floor();
    if a < -FRAC_PI_4 {
        a += FRAC_PI_2;
    }
    if a >= FRAC_PI_4 {
        a -= FRAC_PI_2; // exact (Sterbenz): the result is at least −π/4
    }
    a
}

/// Area of the axis-aligned bounding box of `points` turned by `angle` (counter-clockwise).
fn box_area(points: &[[f64; 2]], angle: f64) -> f64 {
    let (s, c) = angle.sin_cos();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        let q = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        for d in 0..2 {
            lo[d] = lo[d].min(q[d]);
            hi[d] = hi[d].max(q[d]);
        }
    }
    (hi[0] - lo[0]) * (hi[1] - lo[1])
}

/// [`min_box_angle`] of every island's hull, one angle per island (`hulls.offsets.len() − 1`
/// of them; an empty hull gets 0, as does an island whose offsets do not fit `hulls.points`).
/// Islands are independent and run in parallel.
pub fn island_box_angles(hulls: &IslandHulls) -> Vec<f64> {
    let IslandHulls { offsets, points } = hulls;
    (0..offsets.len().saturating_sub(1))
        .into_par_iter()
        .with_min_len(64)
        .map(|k| points.get(offsets[k]..offsets[k + 1]).map_or(0.0, min_box_angle))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turns_land_in_the_half_open_range() {
        for a in [-FRAC_PI_4, FRAC_PI_4, 0.0, 3.0 * FRAC_PI_4, -3.0 * FRAC_PI_4, std::f64::consts::PI, 1e-300] {
            let b = quarter_turn(a);
            assert!((-FRAC_PI_4..FRAC_PI_4).contains(&b), "{a} -> {b}");
            let k = ((a - b) / FRAC_PI_2).round();
            assert!((a - b - k * FRAC_PI_2).abs() < 1e-15, "{a} -> {b}");
        }
    }

    #[test]
    fn advance_stops_at_the_maximum_and_after_one_round() {
        let v = [0.0, 1.0, 3.0, 3.0, 2.0, -1.0];
        assert_eq!(advance(0, v.len(), |j| v[j]), 3);
        assert_eq!(advance(0, 4, |_| 1.0), 0); // constant: once round, back where it began
    }
}
