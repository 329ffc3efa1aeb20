//! The real meshes of ../shared/meshes (skipped with a message when the folder is absent).

mod common;

use common::*;
use uvflat_core::{unwrap, AutoSeamOptions, BoundaryShape, ChartKind, ChartStatus, Method, SpectralOptions, UnwrapOptions};

const FILES: &[&str] = &[
    "camelhead.off",
    "lion.off",
    "alligator.obj",
    "beetle.off",
    "halftunnel.off",
    "bunny.off",
    "cow.off",
    "decimated-max.obj",
    "3holes.off",
    "fertility.off",
    "cube_40k.obj",
    "beetle-nonmanifold.obj",
];

fn run(method: Method, check: impl Fn(&str, &uvflat_core::ChartReport)) {
    let Some(dir) = shared_meshes() else { return };
    for f in FILES {
        let s = load(&dir.join(f));
        let t = std::time::Instant::now();
        let r = unwrap(&s.input(), &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
        let solved = r.charts.iter().filter(|c| c.status != ChartStatus::Failed).count();
        let flips: usize = r.charts.iter().map(|c| c.flips).sum();
        eprintln!(
            "{f:>24} {:>10}: {:>5} charts, {solved:>5} solved, {flips} flips, {:.3} s",
            method.name(),
            r.charts.len(),
            t.elapsed().as_secs_f64()
        );
        for c in &r.charts {
            match c.kind {
                ChartKind::Closed | ChartKind::HigherGenus => {
                    // Automatic seams cut every such chart unless it has a defect.
                    assert_eq!(c.status, ChartStatus::Failed, "{f}: chart {} is {:?} and was not cut", c.id, c.kind);
                    assert!(c.reason.as_deref().unwrap_or("").contains("seam"), "{f}: {:?}", c.reason);
                }
                _ => {}
            }
            if c.status != ChartStatus::Failed {
                assert!(c.distortion.conformal >= 1.0 - 1e-9 || c.distortion.conformal.is_nan(), "{f}");
            }
            check(f, c);
        }
    }
}

#[test]
fn tutte_and_mean_value_on_a_circle_never_flip() {
    for m in [Method::Tutte { boundary: BoundaryShape::Circle }, Method::MeanValue { boundary: BoundaryShape::Circle }] {
        run(m, |f, c| {
            if c.status == ChartStatus::Solved {
                assert_eq!(c.flips, 0, "{f}: chart {} ({} faces) flips", c.id, c.faces);
            }
        });
    }
}

#[test]
fn every_disk_solves_with_lscm_and_spectral_and_harmonic() {
    for m in [Method::Lscm, Method::Spectral(SpectralOptions::default()), Method::Harmonic { boundary: BoundaryShape::Circle }] {
        run(m, |f, c| {
            if matches!(c.kind, ChartKind::Disk | ChartKind::DiskWithHoles) {
                assert_ne!(c.status, ChartStatus::Failed, "{f}: chart {}: {:?}", c.id, c.reason);
            }
        });
    }
}

#[test]
fn lscm_has_no_flips_on_the_disk_meshes() {
    // Free-boundary LSCM carries no injectivity guarantee. On halftunnel (quads with two holes)
    // the open-hole map folds a triangle at a hole and its outline crosses itself; the chart
    // is then solved again with its holes filled, which does not fold, and the note says so.
    let Some(dir) = shared_meshes() else { return };
    for f in ["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Lscm, auto_seams: AutoSeamOptions { enabled: false, ..Default::default() }, ..Default::default() }).unwrap();
        assert_eq!(r.charts.len(), 1, "{f}");
        let c = &r.charts[0];
        assert_eq!(c.status, ChartStatus::Solved, "{f}");
        assert_eq!(c.flips, 0, "{f}");
        assert!(!c.overlap, "{f}");
        let filled = c.reason.as_deref().is_some_and(|n| n.starts_with("holes filled by virtual fans"));
        assert_eq!(filled, f == "halftunnel.off", "{f}: {:?}", c.reason);
    }
}

