//! ABF / ABF++: angle constraints, developable surfaces, flips, convex boundary, solver
//! agreement, exact reconstruction. Analytic and property checks only (no snapshot numbers).

mod common;

use std::f64::consts::PI;

use common::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::methods::abf::{self, AbfBoundary, AbfOptions, AbfSolver};
use uvflat_core::methods::{chart_angles, lscm};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::{unwrap, AutoSeamOptions, ChartKind, ChartStatus, Method, OptionValue, UnwrapOptions};

fn charts_of(s: &Soup, seams: &[[u32; 2]]) -> Vec<Chart> {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, seams, None)
        .into_iter()
        .filter(|c| c.defect.is_none() && matches!(c.kind, ChartKind::Disk | ChartKind::DiskWithHoles))
        .collect()
}

/// Largest violation of the ABF constraints, computed here independently of the solver:
/// triangle sums, interior vertex sums, wheel (sine law, product form via logs).
fn constraint_violation(chart: &Chart, alpha: &[[f64; 3]]) -> f64 {
    let interior: Vec<bool> = chart.boundary_mask().iter().map(|b| !b).collect();
    let n = chart.positions.len();
    let (mut sum, mut wheel) = (vec![0.0; n], vec![0.0; n]);
    let mut worst: f64 = 0.0;
    for (t, a) in chart.triangles.iter().zip(alpha) {
        worst = worst.max((a[0] + a[1] + a[2] - PI).abs());
        for k in 0..3 {
            let v = t[k] as usize;
            sum[v] += a[k];
            // In triangle (v, p, q): |vp| / |vq| = sin α_q / sin α_p.
            wheel[v] += a[(k + 2) % 3].sin().ln() - a[(k + 1) % 3].sin().ln();
        }
    }
    for v in 0..n {
        if interior[v] {
            worst = worst.max((sum[v] - 2.0 * PI).abs()).max(wheel[v].abs());
        }
    }
    worst
}

fn abf_method(boundary: AbfBoundary) -> Method {
    Method::Abf(AbfOptions { boundary, ..Default::default() })
}

#[test]
fn parse_and_name() {
    let m = Method::parse("abf", &[]).unwrap();
    assert_eq!(m, Method::Abf(AbfOptions::default()));
    assert_eq!(m.name(), "abf");
    assert!(uvflat_core::method_names().contains(&"abf"));
    let opts = vec![
        ("solver".to_string(), OptionValue::Str("abf".into())),
        ("max_iterations".to_string(), OptionValue::Int(12)),
        ("tolerance".to_string(), OptionValue::Float(1e-10)),
        ("boundary".to_string(), OptionValue::Str("convex".into())),
    ];
    let m = Method::parse("abf", &opts).unwrap();
    assert_eq!(
        m,
        Method::Abf(AbfOptions {
            solver: AbfSolver::Plain,
            max_iterations: 12,
            tolerance: 1e-10,
            boundary: AbfBoundary::Convex,
            ..Default::default()
        })
    );
    for bad in [
        ("solver", OptionValue::Str("lu".into())),
        ("boundary", OptionValue::Str("circle".into())),
        ("tolerance", OptionValue::Float(0.0)),
        ("max_iterations", OptionValue::Int(0)),
        ("pins", OptionValue::Bool(true)),
    ] {
        assert!(Method::parse("abf", &[(bad.0.to_string(), bad.1.clone())]).is_err(), "{bad:?}");
    }
}

#[test]
fn angle_constraints_hold_on_the_shared_meshes() {
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        for chart in charts_of(&s, &[]) {
            let t = std::time::Instant::now();
            // a tolerance far below the default: the solver must be able to reach it
            let a = abf::solve_angles(&chart, &AbfOptions { tolerance: 1e-9, ..Default::default() }).unwrap();
            let secs = t.elapsed().as_secs_f64();
            eprintln!(
                "{f:>16}: {} triangles, {} iterations, residual {:.1e}, stationarity {:.1e}, {secs:.3} s",
                chart.triangles.len(),
                a.iterations,
                a.residual,
                a.stationarity
            );
            assert!(a.converged, "{f}: residual {} after {} iterations", a.residual, a.iterations);
            assert!(a.residual < 1e-9, "{f}");
            let v = constraint_violation(&chart, &a.alpha);
            assert!(v < 1e-9, "{f}: independent constraint check {v}");
            assert!(a.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI), "{f}");
        }
    }
}

/// Newton with the exact (diagonal) Lagrangian Hessian converges quadratically: on the smooth
/// disk meshes a handful of factorizations reach 1e-9. (With the energy Hessian 2/β² alone
/// the convergence is linear: camelhead needed 5 factorizations and 9 steps.)
#[test]
fn newton_converges_in_few_factorizations_on_smooth_disks() {
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off"] {
        let s = load(&dir.join(f));
        let chart = &charts_of(&s, &[])[0];
        let a = abf::solve_angles(chart, &AbfOptions { tolerance: 1e-9, ..Default::default() }).unwrap();
        eprintln!("{f:>14}: {} iterations, {} factorizations", a.iterations, a.factorizations);
        assert!(a.converged, "{f}");
        assert!(a.factorizations <= 4, "{f}: {} factorizations", a.factorizations);
        assert!(a.iterations <= 8, "{f}: {} iterations", a.iterations);
        assert!(constraint_violation(chart, &a.alpha) < 1e-9, "{f}");
    }
}

#[test]
fn developable_surfaces_keep_their_angles_and_flatten_isometrically() {
    let (cyl, seams) = cut_cylinder(48, 12, 2.0);
    let disk = planar_disk(8, 7);
    for (name, s, seams) in [("cut cylinder", &cyl, &seams[..]), ("planar disk", &disk, &[][..])] {
        let charts = charts_of(s, seams);
        assert_eq!(charts.len(), 1);
        let c = &charts[0];
        let a = abf::solve_angles(c, &AbfOptions::default()).unwrap();
        assert!(a.converged);
        let exact = chart_angles(&c.positions, &c.triangles);
        for (x, y) in a.alpha.iter().flatten().zip(exact.iter().flatten()) {
            assert!((x - y).abs() < 1e-9, "{name}: {x} vs {y}");
        }
        let mut input = s.input();
        input.seams = seams;
        for boundary in [AbfBoundary::Free, AbfBoundary::Convex] {
            let r = unwrap(&input, &UnwrapOptions { method: abf_method(boundary), ..Default::default() }).unwrap();
            let rc = &r.charts[0];
            if boundary == AbfBoundary::Free {
                assert_eq!(rc.status, ChartStatus::Solved, "{name}: {:?}", rc.reason);
                assert_eq!(rc.method, "abf");
                for d in [rc.distortion.conformal, rc.distortion.area, rc.distortion.symmetric_dirichlet] {
                    assert!((d - 1.0).abs() < 1e-9, "{name}: {:?}", rc.distortion);
                }
            }
            assert_eq!(rc.flips, 0, "{name} {boundary:?}");
            assert!(!rc.overlap, "{name} {boundary:?}");
        }
    }
}

/// Angle sum at every chart vertex, computed here from the angles.
fn vertex_sums(chart: &Chart, alpha: &[[f64; 3]]) -> Vec<f64> {
    let mut sum = vec![0.0; chart.positions.len()];
    for (t, al) in chart.triangles.iter().zip(alpha) {
        for k in 0..3 {
            sum[t[k] as usize] += al[k];
        }
    }
    sum
}

#[test]
fn no_flips_on_the_disk_meshes_free() {
    // Disks and disks with holes (beetle, halftunnel). Open holes are not constrained to close
    // up: on halftunnel that layout folds two triangles and its outline crosses itself, so the
    // angles are solved again with the holes filled by virtual fans (the note says so).
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        let r = unwrap(&s.input(), &UnwrapOptions { method: abf_method(AbfBoundary::Free), auto_seams: AutoSeamOptions { enabled: false, ..Default::default() }, ..Default::default() }).unwrap();
        assert_eq!(r.charts.len(), 1, "{f}");
        let c = &r.charts[0];
        assert_eq!(c.status, ChartStatus::Solved, "{f}: {:?}", c.reason);
        assert!(c.residual < AbfOptions::default().tolerance, "{f}: residual {}", c.residual);
        assert_eq!(c.flips, 0, "{f}");
        assert!(!c.overlap, "{f}");
        let filled = c.reason.as_deref().is_some_and(|n| n.starts_with("holes filled by virtual fans"));
        assert_eq!(filled, f == "halftunnel.off", "{f}: {:?}", c.reason);
    }
}

/// Convex boundary on every disk and disk-with-holes mesh: the angle solve converges to 1e-9,
/// the angles satisfy the ABF constraints of the hole-filled disk and lie in (0, π), every
/// outer-loop vertex has angle sum ≤ π (in fact ≤ the cap π − π/n), every hole closes (its
/// turning is −2π: Σ over its vertices of (π − sum) = −2π), and the UV map has no flipped
/// triangle and no boundary self-overlap.
#[test]
fn convex_boundary_is_bijective_on_every_disk_mesh() {
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        let opts = AbfOptions { boundary: AbfBoundary::Convex, tolerance: 1e-9, ..Default::default() };
        let t = std::time::Instant::now();
        let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(opts.clone()), auto_seams: AutoSeamOptions { enabled: false, ..Default::default() }, ..Default::default() }).unwrap();
        let secs = t.elapsed().as_secs_f64();
        assert_eq!(r.charts.len(), 1, "{f}");
        let c = &r.charts[0];
        eprintln!("{f:>16} convex: unwrap {secs:.3} s, {} iterations, flips {}, overlap {}, conformal {:.4}", c.iterations, c.flips, c.overlap, c.distortion.conformal);
        assert_eq!(c.status, ChartStatus::Solved, "{f}: {:?}", c.reason);
        assert_eq!(c.flips, 0, "{f}");
        assert!(!c.overlap, "{f}");
        assert!(c.residual < 1e-9, "{f}: residual {}", c.residual);

        let chart = &charts_of(&s, &[])[0];
        let a = abf::solve_angles(chart, &opts).unwrap();
        assert!(a.converged && a.residual < 1e-9, "{f}: residual {}", a.residual);
        assert!(a.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI), "{f}");
        for t in &a.alpha {
            assert!((t[0] + t[1] + t[2] - PI).abs() < 1e-9, "{f}: triangle sum");
        }
        let sum = vertex_sums(chart, &a.alpha);
        let outer_i = chart.outer_loop().unwrap();
        let outer = &chart.boundary_loops[outer_i];
        let cap = abf::convex_cap(outer.len());
        for &v in outer {
            assert!(sum[v as usize] <= PI + 1e-9, "{f}: outer vertex {v} angle sum {}", sum[v as usize]);
            assert!(sum[v as usize] <= cap + 1e-9, "{f}: outer vertex {v} above the cap");
        }
        // Outer turning 2π (a closed convex outline), every hole's turning −2π.
        let turning = |lp: &Vec<u32>| lp.iter().map(|&v| PI - sum[v as usize]).sum::<f64>();
        assert!((turning(outer) - 2.0 * PI).abs() < 1e-8, "{f}: outer turning {}", turning(outer));
        for (l, lp) in chart.boundary_loops.iter().enumerate() {
            if l != outer_i {
                assert!((turning(lp) + 2.0 * PI).abs() < 1e-8, "{f}: hole {l} turning {}", turning(lp));
            }
        }
        // Interior vertices of the chart: planarity and wheel hold (holes filled or not).
        assert!(constraint_violation(chart, &a.alpha) < 1e-9, "{f}");
        // The outline in the UV map turns left at every outer vertex: strictly convex.
        let sol = abf::solve(chart, &[], &opts).unwrap();
        assert!(sol.fallback.is_none(), "{f}");
        let m = outer.len();
        for i in 0..m {
            let (p, q, n) = (sol.uv[outer[(i + m - 1) % m] as usize], sol.uv[outer[i] as usize], sol.uv[outer[(i + 1) % m] as usize]);
            let cross = (q[0] - p[0]) * (n[1] - q[1]) - (q[1] - p[1]) * (n[0] - q[0]);
            assert!(cross > 0.0, "{f}: outline turns right at outer vertex {}", outer[i]);
        }
    }
}

/// A curved (non-developable) disk: the planar disk lifted onto a saddle and a bump.
fn curved_disk() -> Soup {
    let mut s = planar_disk(6, 6);
    for p in s.positions.iter_mut() {
        p[2] = 0.08 * (p[0] * p[0] - p[1] * p[1]) + 1.5 * (-(p[0] * p[0] + p[1] * p[1]) / 8.0).exp();
    }
    s
}

#[test]
fn plain_abf_and_abf_plus_plus_reach_the_same_angles() {
    let mut cases: Vec<(String, Soup)> = vec![("curved disk".into(), curved_disk())];
    if let Some(dir) = shared_meshes() {
        cases.push(("halftunnel".into(), load(&dir.join("halftunnel.off"))));
    }
    for (name, s) in &cases {
        for chart in charts_of(s, &[]) {
            for boundary in [AbfBoundary::Free, AbfBoundary::Convex] {
                let o = AbfOptions { tolerance: 1e-12, boundary, ..Default::default() };
                let pp = abf::solve_angles(&chart, &AbfOptions { solver: AbfSolver::AbfPlusPlus, ..o.clone() }).unwrap();
                let plain = abf::solve_angles(&chart, &AbfOptions { solver: AbfSolver::Plain, ..o.clone() }).unwrap();
                assert!(pp.converged && plain.converged, "{name}");
                assert!(pp.iterations > 0, "{name}: not a trivial case");
                let diff = pp.alpha.iter().flatten().zip(plain.alpha.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                eprintln!("{name:>12} {:>6}: abf++ {} it, abf {} it, max |Δα| {diff:.1e}", boundary.name(), pp.iterations, plain.iterations);
                assert!(diff < 1e-6, "{name}: {diff}");
                assert!(constraint_violation(&chart, &pp.alpha) < 1e-9);
            }
        }
    }
}

#[test]
fn consistent_angles_are_reconstructed_exactly() {
    let s = planar_disk(8, 7);
    let c = &charts_of(&s, &[])[0];
    let angles = chart_angles(&c.positions, &c.triangles);
    assert!(constraint_violation(c, &angles) < 1e-12);
    let (uv, _) = lscm::solve_with_angles(c, &angles, &[]).unwrap();
    for (t, a) in c.triangles.iter().zip(&angles) {
        let q = [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
        let p = q.map(|x| [x[0], x[1], 0.0]);
        let b = uvflat_core::geometry::raw_angles(p);
        assert!(uvflat_core::geometry::signed_area_2d(q) > 0.0);
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-9, "{a:?} vs {b:?}");
        }
    }
    // And ABF returns the disk's own angles, whose reconstruction is the same map.
    let a = abf::solve_angles(c, &AbfOptions::default()).unwrap();
    assert_eq!(a.iterations, 0);
}

#[test]
fn a_chart_that_does_not_converge_falls_back_to_lscm_and_says_so() {
    let s = curved_disk();
    let m = Method::Abf(AbfOptions { max_iterations: 1, ..Default::default() });
    let r = unwrap(&s.input(), &UnwrapOptions { method: m, ..Default::default() }).unwrap();
    let c = &r.charts[0];
    assert_eq!(c.status, ChartStatus::Fallback);
    assert_eq!(c.method, "lscm");
    let reason = c.reason.as_deref().unwrap();
    assert!(reason.starts_with("abf did not converge: residual") && reason.contains("after 1 iterations"), "{reason}");
}

/// Prescribed boundary angle sums: π/2 at four boundary vertices and π at every other one
/// (Gauss–Bonnet: Σ (π − sum) = 2π) flatten a disk onto a rectangle.
#[test]
fn prescribed_boundary_sums_make_a_rectangle() {
    use uvflat_core::charts::build_charts;
    use uvflat_core::mesh::PolyMesh;
    use uvflat_core::methods::abf::{solve_angles_with_sums, solve_with_sums, AbfOptions};
    let s = common::planar_disk(7, 6);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let chart = build_charts(&mesh, &[], None).remove(0);
    let outer = &chart.boundary_loops[chart.outer_loop().unwrap()];
    let m = outer.len();
    let corners: Vec<u32> = (0..4).map(|k| outer[k * m / 4]).collect();
    let prescribed: Vec<(u32, f64)> = outer
        .iter()
        .map(|&v| (v, if corners.contains(&v) { std::f64::consts::FRAC_PI_2 } else { std::f64::consts::PI }))
        .collect();
    let opts = AbfOptions::default();
    let a = solve_angles_with_sums(&chart, &opts, &prescribed).unwrap();
    assert!(a.converged, "residual {}", a.residual);
    // The sums hold (independently of the solver's own residual).
    let mut sum = vec![0.0; chart.positions.len()];
    for (t, al) in chart.triangles.iter().zip(&a.alpha) {
        for k in 0..3 {
            sum[t[k] as usize] += al[k];
        }
    }
    for &(v, target) in &prescribed {
        assert!((sum[v as usize] - target).abs() < 1e-9, "vertex {v}: {} vs {target}", sum[v as usize]);
    }
    // The reconstruction has a rectangular outline: boundary turning angles match.
    let sol = solve_with_sums(&chart, &[], &opts, &prescribed).unwrap();
    assert!(sol.fallback.is_none());
    let uv = &sol.uv;
    for i in 0..m {
        let (p, c, n) = (uv[outer[(i + m - 1) % m] as usize], uv[outer[i] as usize], uv[outer[(i + 1) % m] as usize]);
        let (a1, a2) = ([p[0] - c[0], p[1] - c[1]], [n[0] - c[0], n[1] - c[1]]);
        // Interior angle at c: the chart lies left of p → c → n, i.e. counter-clockwise from
        // the edge towards n round to the edge towards p.
        let ang = (a2[0] * a1[1] - a2[1] * a1[0]).atan2(a1[0] * a2[0] + a1[1] * a2[1]);
        let ang = if ang < 0.0 { ang + std::f64::consts::TAU } else { ang };
        let want = if corners.contains(&outer[i]) { std::f64::consts::FRAC_PI_2 } else { std::f64::consts::PI };
        assert!((ang - want).abs() < 1e-6, "boundary vertex {i}: angle {ang} vs {want}");
    }
}

/// `angle_sums` through the option parser and `unwrap`: mesh vertices, typed errors naming the
/// entry and vertex, refused by other methods; on a planar disk, π/2 at four boundary vertices
/// and π at the others make the UV outline a rectangle.
#[test]
fn angle_sums_option_through_parse_and_unwrap() {
    use std::f64::consts::FRAC_PI_2;
    use uvflat_core::UvError;
    let s = planar_disk(7, 6);
    let chart = &charts_of(&s, &[])[0];
    let outer = chart.boundary_loops[chart.outer_loop().unwrap()].clone();
    let m = outer.len();
    let corner_idx: Vec<usize> = (0..4).map(|k| k * m / 4).collect();
    // Mesh vertex of each outer chart vertex (no seams: one chart vertex per mesh vertex).
    let sums: Vec<(u32, f64)> = outer
        .iter()
        .enumerate()
        .map(|(i, &v)| (chart.mesh_vertex[v as usize], if corner_idx.contains(&i) { FRAC_PI_2 } else { PI }))
        .collect();
    let opt = |v: Vec<(u32, f64)>| vec![("angle_sums".to_string(), OptionValue::VertexValues(v))];
    let method = Method::parse("abf", &opt(sums.clone())).unwrap();
    let Method::Abf(ref o) = method else { panic!("abf") };
    assert_eq!(o.angle_sums, sums);
    let r = unwrap(&s.input(), &UnwrapOptions { method, auto_seams: AutoSeamOptions { enabled: false, ..Default::default() }, ..Default::default() }).unwrap();
    let c = &r.charts[0];
    assert_eq!(c.status, ChartStatus::Solved, "{:?}", c.reason);
    assert_eq!(c.flips, 0);
    // UV of every mesh vertex (one chart vertex each), from the per-corner UVs.
    let mut uv = vec![[0.0; 2]; s.positions.len()];
    for (c, &v) in s.corner_verts.iter().enumerate() {
        uv[v as usize] = r.uv[c];
    }
    let mv: Vec<usize> = outer.iter().map(|&v| chart.mesh_vertex[v as usize] as usize).collect();
    for i in 0..m {
        let (p, q, n) = (uv[mv[(i + m - 1) % m]], uv[mv[i]], uv[mv[(i + 1) % m]]);
        let (a1, a2) = ([p[0] - q[0], p[1] - q[1]], [n[0] - q[0], n[1] - q[1]]);
        let ang = (a2[0] * a1[1] - a2[1] * a1[0]).atan2(a1[0] * a2[0] + a1[1] * a2[1]);
        let ang = if ang < 0.0 { ang + std::f64::consts::TAU } else { ang };
        let want = if corner_idx.contains(&i) { FRAC_PI_2 } else { PI };
        assert!((ang - want).abs() < 1e-6, "outer vertex {i}: UV angle {ang}, prescribed {want}");
    }
    // Errors.
    assert!(matches!(Method::parse("lscm", &opt(vec![(0, PI)])), Err(UvError::Option { .. })));
    assert!(matches!(
        Method::parse("abf", &[("angle_sums".to_string(), OptionValue::Float(1.0))]),
        Err(UvError::Option { ref name, .. }) if name == "angle_sums"
    ));
    for (bad, entry, vertex) in [
        (vec![(3, PI), (5, f64::NAN)], 1, 5),
        (vec![(4, 0.0)], 0, 4),
        (vec![(4, -1.0)], 0, 4),
        (vec![(2, 1.0), (2, 2.0)], 1, 2),
    ] {
        match Method::parse("abf", &opt(bad.clone())) {
            Err(UvError::AngleSum { entry: e, vertex: v, .. }) => assert_eq!((e, v), (entry, vertex), "{bad:?}"),
            other => panic!("{bad:?}: {other:?}"),
        }
    }
    let n = s.positions.len() as u32;
    let interior = (0..s.positions.len()).find(|&v| !outer.iter().any(|&o| chart.mesh_vertex[o as usize] as usize == v)).unwrap() as u32;
    for (bad, vertex) in [(vec![(n, PI)], n), (vec![(interior, 1000.0)], interior)] {
        let method = Method::parse("abf", &opt(bad.clone())).unwrap();
        match unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }) {
            Err(UvError::AngleSum { vertex: v, .. }) => assert_eq!(v, vertex as u64),
            other => panic!("{bad:?}: {:?}", other.map(|_| ())),
        }
    }
}

/// The default tolerance stops where a UV map can no longer show the difference: every UV is
/// within 1e-6 of the chart's extent of the UVs at 1e-9, and the distortion agrees to 1e-6.
#[test]
fn default_tolerance_gives_the_tight_tolerances_map() {
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off", "beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        let run = |tolerance| {
            let opts = AbfOptions { tolerance, ..Default::default() };
            unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(opts), ..Default::default() }).unwrap()
        };
        let (loose, tight) = (run(AbfOptions::default().tolerance), run(1e-9));
        assert!(AbfOptions::default().tolerance > 1e-9);
        let extent = tight.uv.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        let moved = loose.uv.iter().zip(&tight.uv).fold(0.0f64, |m, (a, b)| m.max((a[0] - b[0]).abs()).max((a[1] - b[1]).abs()));
        eprintln!("{f:>16}: largest UV change {:.1e} of the extent", moved / extent);
        assert!(moved <= 1e-6 * extent, "{f}: UVs moved {moved} (extent {extent})");
        for (a, b) in loose.charts.iter().zip(&tight.charts) {
            assert_eq!((a.status, a.flips, a.overlap), (b.status, b.flips, b.overlap), "{f}");
            assert!((a.distortion.conformal - b.distortion.conformal).abs() < 1e-6 * b.distortion.conformal, "{f}");
        }
    }
}
