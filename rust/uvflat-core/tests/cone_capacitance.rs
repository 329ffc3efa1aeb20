//! Cone placement's scale factor by the capacitance method (one factor per chart) agrees with
//! a factorization per cone set, on closed and open charts, with the ground vertex among the
//! cones and without it (then on a second factor grounded at the first cone).

mod common;

use common::{load, octahedron_sphere, shared_meshes, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::cones::ScaleSolver;
use uvflat_core::mesh::PolyMesh;

/// An icosphere-like closed mesh: an octahedron subdivided and pushed to an ellipsoid.
fn ellipsoid(levels: usize) -> Soup {
    let mut s = octahedron_sphere(levels);
    for p in &mut s.positions {
        *p = [2.0 * p[0], p[1], 0.5 * p[2]];
    }
    s
}

/// The ellipsoid's one (closed) chart, its scale system and its ground vertex (the vertex of
/// largest curvature).
fn ellipsoid_system(levels: usize) -> (uvflat_core::charts::Chart, ScaleSolver, u32) {
    let s = ellipsoid(levels);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let chart = build_charts(&mesh, &[], None).remove(0);
    let solver = ScaleSolver::new(&chart).unwrap();
    let n = chart.positions.len();
    let ground = (0..n).max_by(|&a, &b| solver.defect[a].total_cmp(&solver.defect[b]).then(b.cmp(&a))).unwrap() as u32;
    (chart, solver, ground)
}

/// Cone sets of growing size, deterministic, spread over the vertex ids.
fn cone_sets(n: usize) -> Vec<Vec<u32>> {
    let mut sets = Vec::new();
    let mut cones: Vec<u32> = Vec::new();
    for k in 0..6u32 {
        cones.push(((k as usize * 7919 + 13) % n) as u32);
        sets.push(cones.clone());
    }
    sets
}

fn check(s: &Soup, name: &str) {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    for chart in build_charts(&mesh, &[], None) {
        let Some(solver) = ScaleSolver::new(&chart) else { continue };
        let n = chart.positions.len();
        // The ground of a closed chart: the vertex of largest curvature.
        let ground =
            (0..n).max_by(|&a, &b| solver.defect[a].total_cmp(&solver.defect[b]).then(b.cmp(&a))).unwrap() as u32;
        let closed = !solver.boundary.iter().any(|&b| b);
        for mut cones in cone_sets(n) {
            if closed && !cones.contains(&ground) {
                // Without the ground: on a second base grounded at the first cone (the same
                // cone sets grow from one first cone, so that base serves them all).
                let a = solver.solve(&cones).unwrap();
                let b = solver.solve_refactored(&cones).unwrap();
                let scale = b.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
                let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(err <= 1e-6 * scale, "{name}: without the ground, difference {err:.3e}");
                assert!(cones.iter().all(|&c| a[c as usize] == 0.0));
                cones.insert(0, ground);
            }
            let a = solver.solve(&cones).expect("capacitance solve");
            let b = solver.solve_refactored(&cones).expect("refactored solve");
            let scale = b.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
            let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(err <= 1e-6 * scale, "{name}: {} cones, max |u| {scale:.3e}, difference {err:.3e}", cones.len());
            for &c in &cones {
                assert_eq!(a[c as usize], 0.0, "{name}: a cone keeps u = 0");
            }
        }
    }
}

#[test]
fn capacitance_solve_matches_a_factorization_per_cone_set_on_closed_charts() {
    check(&ellipsoid(4), "ellipsoid");
}

#[test]
fn capacitance_solve_matches_a_factorization_per_cone_set_on_open_charts() {
    // The ellipsoid with its lower cap removed: a disk, the boundary held.
    let s = ellipsoid(4);
    let keep: Vec<bool> = s
        .corner_verts
        .chunks(3)
        .map(|t| t.iter().all(|&v| s.positions[v as usize][2] > -0.3))
        .collect();
    let mut open = Soup { positions: s.positions.clone(), corner_verts: Vec::new(), face_sizes: Vec::new() };
    for (t, k) in s.corner_verts.chunks(3).zip(keep) {
        if k {
            open.corner_verts.extend_from_slice(t);
            open.face_sizes.push(3);
        }
    }
    check(&open, "open ellipsoid");
}

#[test]
fn capacitance_solve_matches_on_shared_meshes() {
    let Some(dir) = shared_meshes() else {
        eprintln!("skipped: the shared meshes folder is absent");
        return;
    };
    for name in ["bunny.off", "cow.off"] {
        check(&load(&dir.join(name)), name);
    }
}

/// Many new cones asked at once (more than one batch of Green's functions solved together)
/// give the scale factor of a factorization per cone set, and the one the same cones give
/// when they are added one at a time.
#[test]
fn cones_asked_at_once_match_cones_added_one_at_a_time() {
    let (chart, at_once, ground) = ellipsoid_system(4);
    let n = chart.positions.len();
    let mut cones = vec![ground];
    cones.extend((0..11u32).map(|k| (k * 4099 + 101) % n as u32).filter(|&c| c != ground));
    assert!(cones.len() >= 10, "more cones than one batch");
    let a = at_once.solve(&cones).expect("all cones at once");
    let one_by_one = ScaleSolver::new(&chart).unwrap();
    let mut b = Vec::new();
    for k in 1..=cones.len() {
        b = one_by_one.solve(&cones[..k]).expect("one cone more");
    }
    let reference = at_once.solve_refactored(&cones).unwrap();
    let scale = reference.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
    for (name, u) in [("at once", &a), ("one at a time", &b)] {
        let err = u.iter().zip(&reference).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(err <= 1e-6 * scale, "{name}: difference {err:.3e} to the refactored solve (max |u| {scale:.3e})");
    }
    let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(err <= 1e-9 * scale, "at once and one at a time differ by {err:.3e}");
}

/// On a chart large enough for single precision (`solvers::refined_llt::MIXED_MIN`
/// vertices), the refactored solve (held vertices eliminated, factored in single precision
/// and refined) gives the capacitance method's scale factor, also with a whole path of
/// vertices held (a cut), against a double-precision penalty-free reference built by hand.
#[test]
fn large_refactored_solves_in_single_precision_match() {
    let (chart, solver, ground) = ellipsoid_system(6);
    let n = chart.positions.len();
    assert!(uvflat_core::solvers::refined_llt::single_pays(n), "{n} vertices: large enough for single precision");
    let cones: Vec<u32> = std::iter::once(ground).chain((0..5u32).map(|k| (k * 7919 + 13) % n as u32)).collect();
    let a = solver.solve(&cones).unwrap();
    let b = solver.solve_refactored(&cones).unwrap();
    let scale = b.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
    let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(err <= 1e-6 * scale, "cones: difference {err:.3e} (max |u| {scale:.3e})");
    // A path of held vertices (every vertex within a slab: a closed loop around the
    // ellipsoid): u is zero on it and solves L u = −K at every other vertex.
    let held: Vec<u32> = (0..n as u32).filter(|&v| chart.positions[v as usize][0].abs() < 0.02).collect();
    assert!(held.len() > 50);
    let u = solver.solve_refactored(&held).unwrap();
    assert!(held.iter().all(|&v| u[v as usize] == 0.0));
    let mut is_held = vec![false; n];
    for &v in &held {
        is_held[v as usize] = true;
    }
    // `L u` and the diagonal of `L` (cotangent weights of clamped angles).
    let mut lu = vec![0.0f64; n];
    let mut diag = vec![0.0f64; n];
    for t in &chart.triangles {
        let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
        let ang = uvflat_core::geometry::clamped_angles(p);
        for k in 0..3 {
            let (i, j) = (t[(k + 1) % 3] as usize, t[(k + 2) % 3] as usize);
            let w = 0.5 / ang[k].tan();
            lu[i] += w * (u[i] - u[j]);
            lu[j] += w * (u[j] - u[i]);
            diag[i] += w;
            diag[j] += w;
        }
    }
    // The documented regularisation: 1e-8 · the mean diagonal added to the diagonal.
    let eps = 1e-8 * diag.iter().map(|d| d.abs()).sum::<f64>() / n as f64;
    let worst = (0..n).filter(|&v| !is_held[v]).map(|v| (lu[v] + eps * u[v] + solver.defect[v]).abs()).fold(0.0f64, f64::max);
    let k_scale = solver.defect.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
    assert!(worst <= 1e-6 * k_scale, "residual of L u = −K off the held vertices: {worst:.3e} (max |K| {k_scale:.3e})");
}

/// Freeing the factors (done before a large chart's pieces are solved) changes no result:
/// the next solve factors again, on a closed chart with and without the ground among the
/// cones.
#[test]
fn solves_after_the_factors_are_freed_are_the_same() {
    let (chart, mut solver, ground) = ellipsoid_system(4);
    let n = chart.positions.len();
    let others: Vec<u32> = (0..4u32).map(|k| (k * 7919 + 13) % n as u32).filter(|&c| c != ground).collect();
    let with_ground: Vec<u32> = std::iter::once(ground).chain(others.iter().copied()).collect();
    let before = [solver.solve(&with_ground).unwrap(), solver.solve(&others).unwrap()];
    solver.release_factors();
    let after = [solver.solve(&with_ground).unwrap(), solver.solve(&others).unwrap()];
    for (a, b) in before.iter().zip(&after) {
        let scale = a.iter().fold(1e-12f64, |m, x| m.max(x.abs()));
        let err = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(err <= 1e-12 * scale, "difference {err:.3e} after the factors were freed");
    }
}
