//! Cone placement's scale factor by the capacitance method (one factor per chart) agrees with
//! a factorization per cone set, on closed and open charts, with the ground vertex among the
//! cones and without it (then on a second factor grounded at the first cone).

mod common;

use common::{load, shared_meshes, subdivide, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::cones::ScaleSolver;
use uvflat_core::mesh::PolyMesh;

/// An icosphere-like closed mesh: an octahedron subdivided and pushed to an ellipsoid.
fn ellipsoid(levels: usize) -> Soup {
    let positions = vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    let faces: [[u32; 3]; 8] = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    let mut s = Soup { positions, corner_verts: faces.iter().flatten().copied().collect(), face_sizes: vec![3; 8] };
    for _ in 0..levels {
        s = subdivide(&s);
    }
    for p in &mut s.positions {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        *p = [2.0 * p[0] / n, p[1] / n, 0.5 * p[2] / n];
    }
    s
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
