//! Hostile input: every promise of the public API holds (no panic, finite UVs, honest status).

mod common;

use common::*;
use uvflat_core::{unwrap, BoundaryShape, ChartStatus, Method, UnwrapOptions};

fn opts(method: Method) -> UnwrapOptions {
    UnwrapOptions { method, ..Default::default() }
}

fn finite(uv: &[[f64; 2]]) -> bool {
    uv.iter().all(|p| p[0].is_finite() && p[1].is_finite())
}

#[test]
fn virtual_boundary_honours_pins() {
    let s = planar_disk(5, 6);
    let last = s.corner_verts.len() as u32 - 1;
    let pins = [(0u32, [0.25, -0.5]), (last, [3.0, 2.0])];
    for m in [
        Method::Tutte { boundary: BoundaryShape::Virtual },
        Method::Harmonic { boundary: BoundaryShape::Virtual },
        Method::MeanValue { boundary: BoundaryShape::Virtual },
    ] {
        for n_pins in [1, 2] {
            let mut input = s.input();
            input.pins = &pins[..n_pins];
            let r = unwrap(&input, &opts(m.clone())).unwrap();
            let c = &r.charts[0];
            assert_eq!(c.status, ChartStatus::Solved, "{m:?}: {:?}", c.reason);
            assert!(finite(&r.uv));
            for &(corner, p) in &pins[..n_pins] {
                let q = r.uv[corner as usize];
                assert!((q[0] - p[0]).abs() < 1e-9 && (q[1] - p[1]).abs() < 1e-9, "{m:?}: pin {corner} at {q:?}, wanted {p:?}");
            }
        }
    }
}
