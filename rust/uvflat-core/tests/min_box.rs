//! The turn of a convex polygon to its least-area bounding box: known turns come back, and on
//! random hulls no sampled angle and no edge of the hull gives a smaller box.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use proptest::prelude::*;
use uvflat_core::geometry::convex_hull::{convex_hull, island_hulls, IslandHulls};
use uvflat_core::geometry::min_box::{island_box_angles, min_box_angle, KEEP_FACTOR};

fn turn(points: &[[f64; 2]], angle: f64) -> Vec<[f64; 2]> {
    let (s, c) = angle.sin_cos();
    points.iter().map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]]).collect()
}

/// Area of the axis-aligned box of `points` turned by `angle`.
fn box_area(points: &[[f64; 2]], angle: f64) -> f64 {
    let q = turn(points, angle);
    let ext = |d: usize| {
        let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[d]), hi.max(p[d])));
        hi - lo
    };
    ext(0) * ext(1)
}

/// Least box area over `samples` angles of a quarter turn (the box repeats every quarter turn).
fn sampled_least(points: &[[f64; 2]], samples: usize) -> f64 {
    (0..samples).map(|k| box_area(points, FRAC_PI_2 * k as f64 / samples as f64)).fold(f64::INFINITY, f64::min)
}

/// Least box area over the boxes with a side along an edge of `hull`, each measured directly.
fn edge_least(hull: &[[f64; 2]]) -> f64 {
    let n = hull.len();
    (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            box_area(hull, -(b[1] - a[1]).atan2(b[0] - a[0]))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The angle's box is no larger than any of 2,000 sampled angles' or any edge's, nor than the
/// box as it lies; in range; 0 exactly when turning would save at most the keep factor.
fn check_least(hull: &[[f64; 2]]) {
    let angle = min_box_angle(hull);
    assert!((-FRAC_PI_4..FRAC_PI_4).contains(&angle), "angle {angle} out of range");
    let area = box_area(hull, angle);
    let as_is = box_area(hull, 0.0);
    let least = sampled_least(hull, 2000).min(edge_least(hull));
    assert!(area <= as_is * (1.0 + 1e-12), "turned box {area} larger than the box as it lies {as_is}");
    if angle == 0.0 {
        assert!(as_is <= least * KEEP_FACTOR * (1.0 + 1e-9), "not turned, but {as_is} > least {least}");
    } else {
        assert!(area <= least * (1.0 + 1e-9), "box {area} at {angle} larger than least {least}");
        assert!(as_is > area * KEEP_FACTOR * (1.0 - 1e-9), "turned by {angle} to save almost nothing");
    }
}

#[test]
fn rectangles_turned_by_known_angles_come_back() {
    // a 2 by 1 rectangle with extra points along its sides (collinear hull vertices)
    let rect = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.5]];
    let mut turned = 0;
    for k in 0..997 {
        let a = -PI + 2.0 * PI * k as f64 / 997.0 + 1e-3;
        let offset = [3.0 * (k as f64).sin(), -7.0 + (k % 5) as f64];
        let hull: Vec<[f64; 2]> = turn(&rect, a).iter().map(|p| [p[0] + offset[0], p[1] + offset[1]]).collect();
        let angle = min_box_angle(&hull);
        assert!((-FRAC_PI_4..FRAC_PI_4).contains(&angle));
        // the angle undoes the turn, up to quarter turns
        let rest = (angle + a) / FRAC_PI_2;
        assert!((rest - rest.round()).abs() * FRAC_PI_2 < 1e-9, "turned by {a}: got {angle}");
        turned += (angle != 0.0) as usize;
    }
    assert!(turned > 990, "{turned}");
    // a square: every side gives the least box
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for a in [0.3, -0.7, 2.0, 1.0e-3] {
        let angle = min_box_angle(&turn(&square, a));
        let rest = (angle + a) / FRAC_PI_2;
        assert!((rest - rest.round()).abs() * FRAC_PI_2 < 1e-9, "square turned by {a}: got {angle}");
    }
}

#[test]
fn a_box_lying_nearly_right_is_left_as_it_lies() {
    let rect = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
    assert_eq!(min_box_angle(&rect), 0.0);
    assert_eq!(min_box_angle(&turn(&rect, FRAC_PI_2)), 0.0);
    // turning by 1e-9 saves about 2.5e-9 of the area: not worth it
    assert_eq!(min_box_angle(&turn(&rect, 1e-9)), 0.0);
    // by 1e-4 it saves 2.5e-4: turned back
    assert!((min_box_angle(&turn(&rect, 1e-4)) + 1e-4).abs() < 1e-12);
    // clockwise order is read backwards
    let mut cw = turn(&rect, 0.4);
    cw.reverse();
    assert!((min_box_angle(&cw) + 0.4).abs() < 1e-12);
}

#[test]
fn degenerate_hulls_are_not_turned() {
    let cases: Vec<Vec<[f64; 2]>> = vec![
        vec![],
        vec![[1.0, 2.0]],
        vec![[0.0, 0.0], [1.0, 1.0]],
        vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]],  // collinear
        vec![[0.5, 0.5]; 6],                                   // one point repeated
        vec![[0.0, 0.0], [1.0, 0.3], [1.0, 0.3], [0.0, 0.0]], // a segment, repeated ends
        vec![[0.0, 0.0], [1.0, 0.3], [f64::NAN, 1.0]],
        vec![[0.0, 0.0], [1.0, 0.3], [0.2, f64::INFINITY]],
        vec![[0.0, 0.0], [f64::NEG_INFINITY, 0.3], [0.2, 1.0]],
    ];
    for hull in &cases {
        assert_eq!(min_box_angle(hull), 0.0, "{hull:?}");
    }
}

#[test]
fn huge_tiny_and_far_hulls_turn_like_unit_ones() {
    let unit = turn(&[[0.0, 0.0], [3.0, 0.0], [3.5, 1.0], [0.5, 1.0]], 0.25);
    let reference = min_box_angle(&unit);
    assert!(reference != 0.0);
    for (scale, shift) in [(1e150, 0.0), (1e-150, 0.0), (1.0, 1e6), (1e-3, 1e3), (1e300, 1e300)] {
        let hull: Vec<[f64; 2]> = unit.iter().map(|p| [p[0] * scale + shift, p[1] * scale - shift]).collect();
        let angle = min_box_angle(&hull);
        assert!((angle - reference).abs() < 1e-6, "scale {scale}, shift {shift}: {angle} against {reference}");
    }
}

#[test]
fn a_hull_of_thousands_of_points_gets_its_least_box() {
    // an ellipse of 5,000 vertices, axes 3 and 1, turned by 0.6
    let hull: Vec<[f64; 2]> = (0..5000)
        .map(|k| {
            let t = 2.0 * PI * k as f64 / 5000.0;
            [3.0 * t.cos(), t.sin()]
        })
        .collect();
    let hull = turn(&hull, 0.6);
    check_least(&hull);
    assert!((min_box_angle(&hull) + 0.6).abs() < 1e-3);
}

#[test]
fn island_angles_are_those_of_their_hulls() {
    // island 0: a turned rectangle (two faces); island 1: collinear; island 2: none; island 3: a triangle
    let rect = turn(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]], 0.3);
    let mut uv = vec![rect[0], rect[1], rect[2], rect[0], rect[2], rect[3]];
    uv.extend_from_slice(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]);
    uv.extend_from_slice(&[[0.0, 0.0], [4.0, 1.0], [1.0, 2.0]]);
    let hulls = island_hulls(&uv, &[3, 3, 3, 3], &[0, 0, 1, 3]).unwrap();
    let angles = island_box_angles(&hulls);
    assert_eq!(angles.len(), 4);
    assert!((angles[0] + 0.3).abs() < 1e-12, "{angles:?}");
    assert_eq!((angles[1], angles[2]), (0.0, 0.0));
    assert_eq!(angles[3], min_box_angle(&hulls.points[hulls.offsets[3]..hulls.offsets[4]]));
    assert!(angles[3] != 0.0);
    // offsets that do not fit the points give 0, not a panic
    let bad = IslandHulls { offsets: vec![0, 3, 99, 1], points: rect.clone() };
    assert_eq!(island_box_angles(&bad), vec![min_box_angle(&rect[..3]), 0.0, 0.0]);
    assert!(island_box_angles(&IslandHulls { offsets: vec![], points: vec![] }).is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn random_hulls_get_the_least_box(
        raw in prop::collection::vec((-1000i32..1000, -1000i32..1000), 3..200),
        stretch in 0.05f64..20.0,
        angle in -PI..PI,
        shift in -50.0f64..50.0,
        exponent in -6i32..6,
    ) {
        let scale = 10f64.powi(exponent);
        let points: Vec<[f64; 2]> = raw.iter().map(|&(x, y)| [x as f64 * 1e-3 * stretch, y as f64 * 1e-3]).collect();
        let mut points: Vec<[f64; 2]> =
            turn(&points, angle).iter().map(|p| [(p[0] + shift) * scale, (p[1] - shift) * scale]).collect();
        let hull = convex_hull(&mut points);
        prop_assume!(!hull.is_empty());
        check_least(&hull);
    }

    #[test]
    fn random_round_hulls_get_the_least_box(
        radii in prop::collection::vec(0.5f64..1.0, 3..400),
        aspect in 0.1f64..1.0,
        angle in -PI..PI,
    ) {
        // points on a turned ellipse: many hull vertices, every box nearly as small
        let n = radii.len();
        let mut points: Vec<[f64; 2]> = radii
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let t = 2.0 * PI * k as f64 / n as f64;
                [r * t.cos(), aspect * r * t.sin()]
            })
            .collect();
        points = turn(&points, angle);
        let hull = convex_hull(&mut points);
        prop_assume!(!hull.is_empty());
        check_least(&hull);
    }
}
