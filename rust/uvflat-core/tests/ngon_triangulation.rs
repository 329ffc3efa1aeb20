//! Triangulation of n-gons without a render triangulation: k corners give k − 2 triangles,
//! every one positively oriented in the polygon's plane, together covering exactly the
//! polygon's area (so they neither overlap nor leave gaps), deterministically; and faces of
//! thousands of corners triangulate (the time of a 4,000-corner face is printed, not asserted).
//!
//! Polygons: random star-shaped ones (random angles and radii around a centre), spirals and
//! combs (not star-shaped), rectangles with collinear runs of corners along their sides, each
//! laid into a tilted 3D plane with a random rigid motion.

use uvflat_core::charts::{triangulate_polygon, triangulate_polygon_avoiding};

/// xorshift64*: deterministic pseudo-random numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A star-shaped polygon of `k` corners, counter-clockwise: sorted random angles, radii in
/// [0.15, 1].
fn star(k: usize, rng: &mut Rng) -> Vec<[f64; 2]> {
    let mut angles: Vec<f64> = (0..k).map(|i| (i as f64 + 0.8 * rng.next()) / k as f64 * std::f64::consts::TAU).collect();
    angles.sort_by(f64::total_cmp);
    angles.iter().map(|&a| {
        let r = 0.15 + 0.85 * rng.next();
        [r * a.cos(), r * a.sin()]
    }).collect()
}

/// A thick spiral band of `k` corners (half on the outer arc going out, half on the inner
/// arc coming back), counter-clockwise; not star-shaped for more than one turn.
fn spiral(k: usize, turns: f64) -> Vec<[f64; 2]> {
    let half = k / 2;
    let arm = |t: f64, off: f64| {
        let a = t * turns * std::f64::consts::TAU;
        let r = 1.0 + 2.0 * a + off;
        [r * a.cos(), r * a.sin()]
    };
    let mut out: Vec<[f64; 2]> = (0..half).map(|i| arm(i as f64 / (half - 1) as f64, 0.0)).collect();
    out.extend((0..k - half).map(|i| arm(1.0 - i as f64 / (k - half - 1) as f64, 2.5)));
    // The outer arc runs at larger radius than the inner one at each angle: reverse if clockwise.
    if signed_area(&out) < 0.0 {
        out.reverse();
    }
    out
}

/// A comb of `teeth` teeth of random depths (4 corners per tooth plus the back), counter-clockwise.
fn comb(teeth: usize, rng: &mut Rng) -> Vec<[f64; 2]> {
    let mut out = vec![[teeth as f64, -1.0]];
    for i in (0..teeth).rev() {
        let x = i as f64;
        let depth = 0.5 + 3.0 * rng.next();
        out.extend([[x + 0.9, 0.0], [x + 0.9, depth], [x + 0.1, depth], [x + 0.1, 0.0]]);
    }
    out.push([0.0, -1.0]);
    out
}

/// A w × h rectangle with `per_side` corners on each side (collinear runs), counter-clockwise.
fn rectangle_with_runs(per_side: usize, w: f64, h: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let side = |a: [f64; 2], b: [f64; 2], out: &mut Vec<[f64; 2]>| {
        for i in 0..per_side {
            let t = i as f64 / per_side as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    };
    side([0.0, 0.0], [w, 0.0], &mut out);
    side([w, 0.0], [w, h], &mut out);
    side([w, h], [0.0, h], &mut out);
    side([0.0, h], [0.0, 0.0], &mut out);
    out
}

fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1]).sum::<f64>()
}

fn tri_area(p: &[[f64; 2]], t: [usize; 3]) -> f64 {
    let (a, b, c) = (p[t[0]], p[t[1]], p[t[2]]);
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// The polygon laid into a tilted plane by a rotation and a translation (areas and
/// orientation in the plane are those of the 2D polygon).
fn into_3d(p: &[[f64; 2]], rng: &mut Rng) -> Vec<[f64; 3]> {
    let (a, b) = (rng.next() * 6.0, rng.next() * 3.0);
    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
    // Rotation about z by a, then about x by b.
    let rot = |x: f64, y: f64| {
        let (x1, y1) = (ca * x - sa * y, sa * x + ca * y);
        [x1, cb * y1, sb * y1]
    };
    let t = [rng.next() * 10.0 - 5.0, rng.next() * 10.0 - 5.0, rng.next() * 10.0 - 5.0];
    p.iter().map(|q| {
        let r = rot(q[0], q[1]);
        [r[0] + t[0], r[1] + t[1], r[2] + t[2]]
    }).collect()
}

/// The contract on one polygon: k − 2 triangles using every corner index in range, each
/// positively oriented, areas summing to the polygon's, and the same result a second time.
fn check(name: &str, p: &[[f64; 2]], rng: &mut Rng) {
    let k = p.len();
    let area = signed_area(p);
    assert!(area > 0.0, "{name}: the test polygon is not counter-clockwise");
    let pts = into_3d(p, rng);
    let tris = triangulate_polygon(&pts);
    assert_eq!(tris.len(), k - 2, "{name}: {k} corners");
    let mut used = vec![false; k];
    let mut sum = 0.0;
    let scale = p.iter().fold(0.0f64, |m, q| m.max(q[0].abs()).max(q[1].abs()));
    for &t in &tris {
        assert!(t.iter().all(|&i| i < k) && t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "{name}: {t:?}");
        let a = tri_area(p, t);
        assert!(a > 1e-14 * scale * scale, "{name}: triangle {t:?} has area {a:e}");
        sum += a;
        t.iter().for_each(|&i| used[i] = true);
    }
    assert!(used.iter().all(|&u| u), "{name}: a corner is in no triangle");
    assert!((sum - area).abs() <= 1e-9 * area, "{name}: triangles cover {sum}, the polygon {area}");
    assert_eq!(triangulate_polygon(&pts), tris, "{name}: not deterministic");
}

#[test]
fn random_star_shaped_polygons_are_covered_exactly() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for k in [10usize, 11, 37, 100, 513, 1000, 2500, 5000] {
        for case in 0..3 {
            let p = star(k, &mut rng);
            check(&format!("star {k} #{case}"), &p, &mut rng);
        }
    }
}

#[test]
fn spirals_combs_and_collinear_runs_are_covered_exactly() {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    for k in [10usize, 64, 301, 2000, 5000] {
        check(&format!("spiral {k}"), &spiral(k, 1.0 + k as f64 / 400.0), &mut rng);
    }
    for teeth in [2usize, 25, 250, 1249] {
        check(&format!("comb of {teeth} teeth"), &comb(teeth, &mut rng), &mut rng);
    }
    for per_side in [3usize, 10, 250, 1250] {
        check(&format!("rectangle with {per_side} corners per side"), &rectangle_with_runs(per_side, 3.0, 1.0), &mut rng);
    }
}

#[test]
fn a_taken_diagonal_never_breaks_the_cover() {
    // Every diagonal from corner 0 is "taken": the result still covers the polygon.
    let mut rng = Rng(42);
    let p = star(200, &mut rng);
    let pts = into_3d(&p, &mut rng);
    let tris = triangulate_polygon_avoiding(&pts, |i, j| i == 0 || j == 0);
    assert_eq!(tris.len(), 198);
    let sum: f64 = tris.iter().map(|&t| tri_area(&p, t)).sum();
    assert!(tris.iter().all(|&t| tri_area(&p, t) > 0.0));
    assert!((sum - signed_area(&p)).abs() <= 1e-9 * signed_area(&p));
}

#[test]
fn a_face_of_4000_corners_triangulates() {
    let mut rng = Rng(7);
    for (name, p) in [("star", star(4000, &mut rng)), ("spiral", spiral(4000, 11.0)), ("circle", {
        (0..4000).map(|i| {
            let a = i as f64 / 4000.0 * std::f64::consts::TAU;
            [a.cos(), a.sin()]
        }).collect::<Vec<_>>()
    })] {
        let pts = into_3d(&p, &mut rng);
        let t0 = std::time::Instant::now();
        let tris = triangulate_polygon(&pts);
        let seconds = t0.elapsed().as_secs_f64();
        assert_eq!(tris.len(), 3998);
        let sum: f64 = tris.iter().map(|&t| tri_area(&p, t)).sum();
        assert!((sum - signed_area(&p)).abs() <= 1e-9 * signed_area(&p), "{name}");
        eprintln!("4000-corner {name}: triangulated in {seconds:.4} s");
    }
}
