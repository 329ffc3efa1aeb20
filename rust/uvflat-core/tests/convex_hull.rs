//! Convex hulls of point sets and of UV islands: properties on random input.

use proptest::prelude::*;
use uvflat_core::geometry::convex_hull::{convex_hull, island_hulls};
use uvflat_core::UvError;

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// `hull` is a strictly convex counter-clockwise polygon of input points holding every point.
fn check_hull(points: &[[f64; 2]], hull: &[[f64; 2]]) {
    let n = hull.len();
    assert!(n >= 3);
    for i in 0..n {
        let (a, b, c) = (hull[i], hull[(i + 1) % n], hull[(i + 2) % n]);
        assert!(cross(a, b, c) > 0.0, "not strictly convex at {i}: {hull:?}");
        assert!(points.contains(&a), "hull vertex {a:?} is not an input point");
        for &p in points {
            assert!(cross(a, b, p) >= -1e-12, "point {p:?} outside edge {i}");
        }
    }
}

proptest! {
    #[test]
    fn hull_is_convex_ccw_and_holds_every_point(raw in prop::collection::vec((0u8..40, 0u8..40), 3..300)) {
        // a coarse lattice makes repeated and collinear points common
        let points: Vec<[f64; 2]> = raw.iter().map(|&(x, y)| [x as f64 * 0.25, y as f64 * 0.5]).collect();
        let hull = convex_hull(&mut points.clone());
        let collinear = points.iter().all(|&p| cross(points[0], points.iter().find(|&&q| q != points[0]).copied().unwrap_or(points[0]), p) == 0.0);
        if collinear {
            prop_assert!(hull.is_empty());
        } else {
            check_hull(&points, &hull);
        }
    }

    #[test]
    fn island_hulls_are_the_hulls_of_each_islands_corners(
        faces in prop::collection::vec((3u32..6, -1i64..3), 1..60),
        seed in any::<u64>(),
    ) {
        let face_sizes: Vec<u32> = faces.iter().map(|f| f.0).collect();
        // island numbers below the face count (dense numbering always fits), some unused
        let face_island: Vec<i64> = faces.iter().map(|f| if f.1 < 0 { -1 } else { f.1 % faces.len() as i64 }).collect();
        let n: usize = face_sizes.iter().map(|&s| s as usize).sum();
        let mut state = seed | 1;
        let mut next = || { state ^= state << 13; state ^= state >> 7; state ^= state << 17; (state % 1000) as f64 / 100.0 };
        let uv: Vec<[f64; 2]> = (0..n).map(|_| [next(), next()]).collect();
        let out = island_hulls(&uv, &face_sizes, &face_island).unwrap();
        let n_islands = face_island.iter().copied().max().unwrap().max(-1) + 1;
        prop_assert_eq!(out.offsets.len(), n_islands as usize + 1);
        for k in 0..n_islands {
            let mut members = Vec::new();
            let mut c = 0;
            for (f, &s) in face_sizes.iter().enumerate() {
                if face_island[f] == k {
                    members.extend_from_slice(&uv[c..c + s as usize]);
                }
                c += s as usize;
            }
            let expected = convex_hull(&mut members.clone());
            prop_assert_eq!(&out.points[out.offsets[k as usize]..out.offsets[k as usize + 1]], &expected[..]);
        }
    }
}

#[test]
fn island_with_a_non_finite_uv_has_no_hull_and_bad_shapes_are_named() {
    let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0]];
    let out = island_hulls(&uv, &[3, 3], &[0, 1]).unwrap();
    assert_eq!(out.offsets, vec![0, 3, 3]);
    match island_hulls(&uv, &[3, 3], &[0]) {
        Err(UvError::Shape { what: "face_island", .. }) => {}
        other => panic!("expected a shape error, got {other:?}"),
    }
    match island_hulls(&uv[..5], &[3, 3], &[0, 0]) {
        Err(UvError::Shape { what: "uv", .. }) => {}
        other => panic!("expected a shape error, got {other:?}"),
    }
    match island_hulls(&uv, &[3, 3], &[0, 7]) {
        Err(UvError::Shape { what: "face_island", detail }) => assert!(detail.contains("face 1"), "{detail}"),
        other => panic!("expected a shape error, got {other:?}"),
    }
}
