//! ABF on charts whose reduced ABF++ matrix is not positive definite in floating point: the
//! factorization is regularised instead of giving up, and whatever ABF cannot map is mapped
//! by a fallback that does not flip.
//!
//! Cases: a disk with three needles (interior vertices pulled far out of the plane, so their
//! 3D angle sums are tiny and the targets scaled to 2π force near-degenerate corners), and
//! the shared cow cut along a ring (its halves are far from developable; skipped when the
//! shared meshes are absent). Before regularisation both made the angle solve fail with "the
//! linear system is not positive definite", and the LSCM fallback folded or shrank parts of
//! the chart by 10⁷.

mod common;

use common::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::abf::{self, AbfOptions};
use uvflat_core::methods::{self, Fallback};
use uvflat_core::metrics::{chart_metrics, count_flips};
use uvflat_core::{ChartKind, Method};

/// A ring disk (`rings` rings of 6 r vertices) with `spikes` interior vertices raised to
/// heights `h`, `1.3 h`, `1.6 h`, …
fn needles(rings: usize, h: f64, spikes: usize) -> Chart {
    let mut s = planar_disk(rings, 6);
    let n = s.positions.len();
    for k in 0..spikes {
        s.positions[(1 + 5 * k) % n][2] = h * (1.0 + 0.3 * k as f64);
    }
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, &[], None).remove(0)
}

/// What every ABF result must satisfy on a disk: finite UVs, no flipped triangle, and no
/// "not positive definite" left in the report.
fn check_abf_map(name: &str, chart: &Chart) -> (Vec<[f64; 2]>, Option<Fallback>) {
    let sol = methods::solve(&Method::Abf(AbfOptions::default()), chart, &[]).unwrap_or_else(|e| panic!("{name}: {}", e.0));
    assert!(sol.uv.iter().all(|p| p[0].is_finite() && p[1].is_finite()), "{name}: non-finite UV");
    let flips = count_flips(&chart.triangles, &sol.uv);
    assert_eq!(flips, 0, "{name}: {flips} flipped triangle(s); fallback {:?}", sol.fallback);
    for text in [sol.note.as_deref(), sol.fallback.as_ref().map(|f| f.reason.as_str())].into_iter().flatten() {
        assert!(!text.contains("not positive definite"), "{name}: {text}");
    }
    (sol.uv, sol.fallback)
}

#[test]
fn needles_regularise_the_reduced_system_and_never_flip() {
    let mut regularised = 0;
    for (rings, h, spikes) in [(4, 20.0, 3), (4, 100.0, 3), (6, 20.0, 3), (6, 100.0, 7)] {
        let name = format!("{rings} rings, {spikes} needles of height {h}");
        let chart = needles(rings, h, spikes);
        // The angle solve no longer fails: the indefinite factorizations are regularised.
        let a = abf::solve_angles(&chart, &AbfOptions::default()).unwrap_or_else(|e| panic!("{name}: angle solve failed: {}", e.0));
        assert!(a.alpha.iter().flatten().all(|x| x.is_finite()), "{name}");
        if a.regularised > 0 {
            assert!(a.largest_shift > 0.0 && a.largest_shift <= 1e-2, "{name}: shift {}", a.largest_shift);
        }
        regularised += a.regularised;
        let (uv, fallback) = check_abf_map(&name, &chart);
        eprintln!(
            "{name}: {} regularised factorization(s), converged {}, residual {:.2e}; map by {}",
            a.regularised,
            a.converged,
            a.residual,
            fallback.as_ref().map_or("abf", |f| f.method)
        );
        if let Some(f) = fallback {
            // A fallback is as good as SLIM can make it: area distortion in the tens at most.
            let area = chart_metrics(&chart.positions, &chart.triangles, &uv, &chart.boundary_loops).distortion.area;
            assert!(area < 50.0, "{name}: fallback {} has area distortion {area}", f.method);
        }
    }
    // The cases reproduce the failure: some factorizations were not positive definite.
    assert!(regularised > 0, "no case needed regularising: the test no longer reproduces the failure");
}

/// The faces of `s` on either side of the plane `x[axis] = c`, split by seams along it.
fn cut_by_plane(s: &Soup, axis: usize, frac: f64) -> Vec<Chart> {
    let nf = s.face_sizes.len();
    assert!(s.face_sizes.iter().all(|&k| k == 3));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &s.positions {
        lo = lo.min(p[axis]);
        hi = hi.max(p[axis]);
    }
    let c = lo + frac * (hi - lo);
    let below: Vec<bool> = (0..nf)
        .map(|f| s.corner_verts[3 * f..3 * f + 3].iter().map(|&v| s.positions[v as usize][axis]).sum::<f64>() / 3.0 < c)
        .collect();
    let mut sides: std::collections::BTreeMap<(u32, u32), Vec<bool>> = Default::default();
    for f in 0..nf {
        let t = &s.corner_verts[3 * f..3 * f + 3];
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            sides.entry((a.min(b), a.max(b))).or_default().push(below[f]);
        }
    }
    let seams: Vec<[u32; 2]> = sides.iter().filter(|(_, v)| v.len() == 2 && v[0] != v[1]).map(|(e, _)| [e.0, e.1]).collect();
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, &seams, None)
}

#[test]
fn cow_cut_along_a_ring_is_regularised_and_falls_back_without_flips() {
    let Some(dir) = shared_meshes() else { return };
    let cow = load(&dir.join("cow.off"));
    let charts = cut_by_plane(&cow, 2, 0.5);
    let disks: Vec<&Chart> = charts.iter().filter(|c| c.kind == ChartKind::Disk).collect();
    assert!(disks.len() >= 2, "the ring cut gives {} disk(s)", disks.len());
    let mut regularised = 0;
    for (i, chart) in disks.iter().enumerate() {
        let name = format!("cow half {i} ({} triangles)", chart.triangles.len());
        let a = abf::solve_angles(chart, &AbfOptions::default()).unwrap_or_else(|e| panic!("{name}: angle solve failed: {}", e.0));
        regularised += a.regularised;
        let (uv, fallback) = check_abf_map(&name, chart);
        let area = chart_metrics(&chart.positions, &chart.triangles, &uv, &chart.boundary_loops).distortion.area;
        eprintln!("{name}: {} regularised, converged {}; area distortion {area:.3} by {}", a.regularised, a.converged, fallback.map_or("abf", |f| f.method));
        assert!(area < 10.0, "{name}: area distortion {area}");
    }
    assert!(regularised > 0, "no half needed regularising: the test no longer reproduces the failure");
}
