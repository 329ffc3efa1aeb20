//! Analytic and property tests of every method through the public `unwrap` API.

mod common;

use common::*;
use uvflat_core::{metrics, unwrap, BoundaryShape, ChartKind, ChartStatus, Method, SpectralOptions, UnwrapOptions};

fn opts(method: Method) -> UnwrapOptions {
    UnwrapOptions { method, ..Default::default() }
}

/// The method alone on the chart as given: automatic seams off (nothing is cut).
fn uncut(method: Method) -> UnwrapOptions {
    let mut o = opts(method);
    o.auto_seams.enabled = false;
    o
}

fn all_methods() -> Vec<Method> {
    vec![
        Method::Tutte { boundary: BoundaryShape::Circle },
        Method::Tutte { boundary: BoundaryShape::Square },
        Method::Harmonic { boundary: BoundaryShape::Circle },
        Method::MeanValue { boundary: BoundaryShape::Circle },
        Method::Lscm,
        Method::Spectral(SpectralOptions::default()),
    ]
}

#[test]
fn planar_disk_conformal_methods_are_exact_similarities() {
    let s = planar_disk(8, 7);
    for m in [Method::Lscm, Method::Spectral(SpectralOptions::default())] {
        let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
        assert_eq!(r.charts.len(), 1);
        let c = &r.charts[0];
        assert_eq!(c.status, ChartStatus::Solved, "{m:?}: {:?}", c.reason);
        assert_eq!(c.kind, ChartKind::Disk);
        assert_eq!(c.flips, 0);
        assert!(!c.overlap);
        // A planar chart has an exact conformal map (the identity): all measures reach 1.
        for d in [c.distortion.conformal, c.distortion.area, c.distortion.symmetric_dirichlet] {
            assert!((d - 1.0).abs() < 1e-9, "{m:?}: {:?}", c.distortion);
        }
    }
}

#[test]
fn cut_cylinder_is_developable_for_lscm_and_spectral() {
    let (s, seams) = cut_cylinder(48, 12, 2.0);
    let mut input = s.input();
    input.seams = &seams;
    for m in [Method::Lscm, Method::Spectral(SpectralOptions::default())] {
        let r = unwrap(&input, &uncut(m.clone())).unwrap();
        assert_eq!(r.charts.len(), 1);
        let c = &r.charts[0];
        assert_eq!(c.kind, ChartKind::Disk, "the seam opens the cylinder into a disk");
        assert_eq!(c.flips, 0);
        for d in [c.distortion.conformal, c.distortion.area, c.distortion.symmetric_dirichlet] {
            assert!((d - 1.0).abs() < 1e-9, "{m:?}: {:?}", c.distortion);
        }
    }
    // Without the seam the cylinder is an annulus: LSCM still maps it (two loops).
    let r = unwrap(&s.input(), &uncut(Method::Lscm)).unwrap();
    assert_eq!(r.charts[0].kind, ChartKind::DiskWithHoles);
    assert_eq!(r.charts[0].status, ChartStatus::Solved);
}

#[test]
fn fixed_boundary_methods_never_flip_on_a_planar_disk_and_land_on_the_circle() {
    let s = planar_disk(6, 6);
    for m in all_methods() {
        let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
        assert_eq!(r.charts[0].status, ChartStatus::Solved, "{m:?}");
        let promises_no_flip = !matches!(m, Method::Harmonic { .. });
        if promises_no_flip {
            assert_eq!(r.charts[0].flips, 0, "{m:?}");
        }
        // Independent re-measurement agrees with the report.
        let mm = metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
        assert_eq!(mm.charts, 1);
        assert_eq!(mm.flips, r.charts[0].flips);
        assert!((mm.distortion.conformal - r.charts[0].distortion.conformal).abs() < 1e-9);
    }
}

fn rigid(s: &Soup) -> Soup {
    let (a, b) = (0.7f64, -0.4f64);
    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
    let positions = s
        .positions
        .iter()
        .map(|p| {
            let x = [ca * p[0] - sa * p[1], sa * p[0] + ca * p[1], p[2]];
            let y = [x[0], cb * x[1] - sb * x[2], sb * x[1] + cb * x[2]];
            [y[0] + 3.0, y[1] - 1.0, y[2] + 0.5]
        })
        .collect();
    Soup { positions, corner_verts: s.corner_verts.clone(), face_sizes: s.face_sizes.clone() }
}

/// Largest distance between two per-corner UV sets after the best similarity of the first
/// onto the second, relative to the second's size.
fn similarity_gap(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let mut x = a.to_vec();
    assert!(metrics::fit_similarity_points(&mut x, b));
    let size = b.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max);
    x.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max) / size
}

#[test]
fn rigid_motions_of_the_input_do_not_change_the_map() {
    let (cyl, seams) = cut_cylinder(24, 6, 1.5);
    let moved = rigid(&cyl);
    for m in all_methods() {
        let mut i1 = cyl.input();
        i1.seams = &seams;
        let mut i2 = moved.input();
        i2.seams = &seams;
        let r1 = unwrap(&i1, &uncut(m.clone())).unwrap();
        let r2 = unwrap(&i2, &uncut(m.clone())).unwrap();
        let gap = similarity_gap(&r2.uv, &r1.uv);
        assert!(gap < 1e-7, "{m:?}: gap {gap}");
        let (d1, d2) = (r1.charts[0].distortion, r2.charts[0].distortion);
        // A square boundary can make a triangle with three vertices on one side degenerate
        // (infinite distortion); then it must be so on both.
        assert!(
            (d1.conformal - d2.conformal).abs() < 1e-8 || (d1.conformal.is_infinite() && d2.conformal.is_infinite()),
            "{m:?}: {d1:?} vs {d2:?}"
        );
    }
}

#[test]
fn permuting_faces_permutes_the_output() {
    let s = planar_disk(5, 6);
    let nf = s.face_sizes.len();
    // A fixed pseudo-random permutation.
    let mut perm: Vec<usize> = (0..nf).collect();
    let mut state = 12345u64;
    for i in (1..nf).rev() {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        perm.swap(i, (state >> 33) as usize % (i + 1));
    }
    let mut cv = Vec::new();
    for &f in &perm {
        cv.extend_from_slice(&s.corner_verts[3 * f..3 * f + 3]);
    }
    let p = Soup { positions: s.positions.clone(), corner_verts: cv, face_sizes: s.face_sizes.clone() };
    for m in all_methods() {
        let r1 = unwrap(&s.input(), &opts(m.clone())).unwrap();
        let r2 = unwrap(&p.input(), &opts(m.clone())).unwrap();
        let mut back = vec![[0.0; 2]; r1.uv.len()];
        for (new_f, &old_f) in perm.iter().enumerate() {
            for k in 0..3 {
                back[3 * old_f + k] = r2.uv[3 * new_f + k];
            }
        }
        let gap = similarity_gap(&back, &r1.uv);
        assert!(gap < 1e-9, "{m:?}: gap {gap}");
    }
}

#[test]
fn selection_pins_and_failures() {
    let s = planar_disk(4, 6);
    let nf = s.face_sizes.len();
    let sel: Vec<bool> = (0..nf).map(|f| f % 5 != 0).collect();
    let mut input = s.input();
    input.selected = Some(&sel);
    let r = unwrap(&input, &opts(Method::Lscm)).unwrap();
    for f in 0..nf {
        assert_eq!(r.face_chart[f] < 0, !sel[f]);
    }
    // Pins: two pinned corners keep their UVs exactly.
    let pins = [(0u32, [0.25, 0.5]), (10u32, [0.9, 0.1])];
    let mut input = s.input();
    input.pins = &pins;
    for m in [Method::Lscm, Method::Tutte { boundary: BoundaryShape::Circle }, Method::Spectral(SpectralOptions::default())] {
        let r = unwrap(&input, &opts(m.clone())).unwrap();
        for &(c, uv) in &pins {
            assert_eq!(r.uv[c as usize], uv, "{m:?}");
        }
    }
}

#[test]
fn closed_and_degenerate_inputs_fail_per_chart_or_get_finite_uvs() {
    // Closed tetrahedron: fails with a reason, no UVs.
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let cv = vec![0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
    let fs = vec![3u32; 4];
    let s = Soup { positions: p, corner_verts: cv, face_sizes: fs };
    let no_cuts = UnwrapOptions {
        auto_seams: uvflat_core::AutoSeamOptions { enabled: false, ..Default::default() },
        ..opts(Method::Lscm)
    };
    let r = unwrap(&s.input(), &no_cuts).unwrap();
    assert_eq!(r.charts[0].status, ChartStatus::Failed);
    assert_eq!(r.charts[0].kind, ChartKind::Closed);
    assert!(r.charts[0].reason.as_ref().unwrap().contains("seam"));
    assert!(!r.face_solved(0));
    // With automatic seams (the default) the tetrahedron is cut open and every face solved.
    let r = unwrap(&s.input(), &opts(Method::Lscm)).unwrap();
    assert!((0..4).all(|f| r.face_solved(f)), "{:?}", r.charts);
    assert!(!r.new_seams.is_empty());
    // Zero-area faces (all points on a line, and one fully collapsed) get finite UVs.
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
    let s = Soup { positions: p, corner_verts: vec![0, 1, 3, 1, 2, 3, 0, 2, 1], face_sizes: vec![3, 3, 3] };
    for m in all_methods() {
        if let Ok(r) = unwrap(&s.input(), &opts(m.clone())) {
            assert!(r.uv.iter().all(|q| q[0].is_finite() && q[1].is_finite()), "{m:?}");
        }
    }
}

#[test]
fn spectral_converges_on_developable_charts_in_a_few_steps() {
    // λ = 0 for a planar chart: the stopping test must not rely on relative eigenvalue change.
    let quad = Soup {
        positions: vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        corner_verts: vec![0, 1, 2, 3],
        face_sizes: vec![4],
    };
    let (cyl, seams) = cut_cylinder(32, 8, 1.0);
    let mut cyl_input = cyl.input();
    cyl_input.seams = &seams;
    for input in [quad.input(), cyl_input] {
        let r = unwrap(&input, &opts(Method::Spectral(SpectralOptions::default()))).unwrap();
        let c = &r.charts[0];
        assert_eq!(c.status, ChartStatus::Solved);
        assert!(c.iterations <= 5, "{} iterations", c.iterations);
        assert!(c.residual <= 1e-10, "{}", c.residual);
        assert!(c.reason.is_none(), "{:?}", c.reason);
    }
    // The flat quad is laid as it is by `unwrap` (methods/planar.rs); the solver itself too.
    let mesh = uvflat_core::mesh::PolyMesh::new(&quad.positions, &quad.corner_verts, &quad.face_sizes).unwrap();
    let chart = uvflat_core::charts::build_charts(&mesh, &[], None).remove(0);
    let sol = uvflat_core::methods::spectral::solve(&chart, &[], &SpectralOptions::default()).unwrap();
    assert!(sol.iterations <= 5 && sol.residual <= 1e-10, "{} iterations, residual {}", sol.iterations, sol.residual);
}

/// LSCM's two automatic pins are points, and a point has no capacity in the plane: on the
/// bunny subdivided twice, cut along `abf`'s seams, the pinned map of the largest chart
/// (tens of thousands of triangles) crushes most of it, so half its area falls outside [½, 2]
/// of its density. The free map fixed on the boundary (`methods/lscm.rs::solve_free`) keeps
/// it within the atlas rule. With automatic seams, `lscm` then needs no more than a handful of
/// islands and no fallback (10 or 11 islands, one of them a fallback, with the pins).
#[test]
fn lscm_without_pins_does_not_crush_a_fine_chart() {
    use uvflat_core::charts::build_charts;
    use uvflat_core::mesh::PolyMesh;
    use uvflat_core::methods::{chart_angles, lscm};
    let Some(dir) = shared_meshes() else { return };
    let s = subdivide(&subdivide(&load(&dir.join("bunny.off"))));
    let abf = unwrap(&s.input(), &opts(Method::Abf(Default::default()))).unwrap();
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &abf.new_seams, None);
    let chart = charts.iter().max_by_key(|c| c.triangles.len()).unwrap();
    assert!(chart.triangles.len() > 50_000, "the premise: a fine chart, {} triangles", chart.triangles.len());
    let angles = chart_angles(&chart.positions, &chart.triangles);
    let spread = |uv: &[[f64; 2]]| metrics::density::density_spread(&chart.positions, &chart.triangles, uv, 2.0);
    let pinned = spread(&lscm::solve_with_angles(chart, &angles, &[]).unwrap().0);
    let free = spread(&lscm::solve_free(chart, &angles, &[]).unwrap().0);
    assert!(pinned.outside > 0.3, "the premise: two pins crush the chart, {pinned:?}");
    assert!(free.outside < 0.05 && free.p5 > 0.4, "{free:?}");
    let r = unwrap(&s.input(), &opts(Method::Lscm)).unwrap();
    assert!(r.charts.len() <= 5, "{} islands", r.charts.len());
    let statuses: Vec<ChartStatus> = r.charts.iter().map(|c| c.status).collect();
    assert!(statuses.iter().all(|s| *s == ChartStatus::Solved), "{statuses:?}");
    assert_islands_keep_the_rule(&s, "lscm", &r);
}
