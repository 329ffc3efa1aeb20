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

#[test]
fn every_entry_point_validates_the_same_way() {
    let s = planar_disk(3, 6);
    let short = vec![true; s.face_sizes.len() - 1];
    let mut input = s.input();
    input.selected = Some(&short);
    let is_shape = |e: uvflat_core::UvError| matches!(e, uvflat_core::UvError::Shape { what: "selected", .. });
    assert!(is_shape(unwrap(&input, &opts(Method::Lscm)).unwrap_err()));
    for m in [Method::Lscm, Method::Tutte { boundary: BoundaryShape::Circle }] {
        assert!(is_shape(uvflat_core::factorization_seconds(&input, &m).unwrap_err()));
    }
    let uv = vec![[0.0; 2]; s.corner_verts.len()];
    let e = uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &uv, Some(&short)).unwrap_err();
    assert!(is_shape(e));
    // A bad pin and a bad seam are refused by factorization_seconds too.
    let mut input = s.input();
    let pins = [(10_000u32, [0.0, 0.0])];
    input.pins = &pins;
    assert!(matches!(
        uvflat_core::factorization_seconds(&input, &Method::Lscm).unwrap_err(),
        uvflat_core::UvError::PinIndex { pin: 0, corner: 10_000, .. }
    ));
    let mut input = s.input();
    let seams = [[0u32, 9_999]];
    input.seams = &seams;
    assert!(matches!(
        uvflat_core::factorization_seconds(&input, &Method::Lscm).unwrap_err(),
        uvflat_core::UvError::SeamIndex { seam: 0, vertex: 9_999, .. }
    ));
    // Bad method options are refused before any work.
    let bad = Method::Spectral(uvflat_core::SpectralOptions { max_iterations: 10, tolerance: f64::NAN });
    assert!(matches!(unwrap(&s.input(), &opts(bad.clone())).unwrap_err(), uvflat_core::UvError::Option { .. }));
    // A NaN UV on an unselected face does not block measuring the selected ones.
    let mut uv = vec![[0.0; 2]; s.corner_verts.len()];
    for (i, p) in uv.iter_mut().enumerate() {
        *p = [i as f64, (i * i % 7) as f64];
    }
    let mut sel = vec![true; s.face_sizes.len()];
    *sel.last_mut().unwrap() = false;
    let last = s.corner_verts.len() - 1;
    uv[last] = [f64::NAN, 0.0];
    assert!(uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &uv, Some(&sel)).is_ok());
    assert!(matches!(
        uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &uv, None).unwrap_err(),
        uvflat_core::UvError::NonFiniteUv { corner } if corner == last
    ));
}

fn every_method() -> Vec<Method> {
    common::every_method(20, uvflat_core::SpectralOptions::default().max_iterations)
}

/// Every report is honest: finite UVs on every chart that is not failed, flips as measured by
/// `metrics::measure` (one definition), and a method that promises no flips is never
/// `solved` with flips.
fn check_honest(s: &Soup, r: &uvflat_core::Unwrapped, m: &Method, what: &str) {
    for c in &r.charts {
        if c.status == ChartStatus::Failed {
            assert!(c.reason.is_some(), "{what} {m:?}: failed without a reason");
            continue;
        }
        if c.status == ChartStatus::Solved && m.promises_no_flips(c.kind) {
            assert_eq!(c.flips, 0, "{what} {m:?}: solved with flips: {:?}", c.reason);
        }
        if c.status == ChartStatus::Fallback {
            assert!(c.reason.is_some(), "{what} {m:?}: fallback without a reason");
        }
    }
    let solved: Vec<bool> = (0..s.face_sizes.len()).map(|f| r.face_solved(f)).collect();
    for (f, &ok) in solved.iter().enumerate() {
        if ok {
            let start: usize = s.face_sizes[..f].iter().map(|&k| k as usize).sum();
            for c in start..start + s.face_sizes[f] as usize {
                assert!(r.uv[c][0].is_finite() && r.uv[c][1].is_finite(), "{what} {m:?}: corner {c} not finite");
            }
        }
    }
    if r.charts.len() == 1 && r.charts[0].status != ChartStatus::Failed {
        let mm = uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, Some(&solved)).unwrap();
        assert_eq!(mm.flips, r.charts[0].flips, "{what} {m:?}: report and metrics disagree");
    }
}

#[test]
fn every_method_is_scale_and_translation_invariant_from_1e_minus_6_to_1e150() {
    let base = planar_disk(4, 6);
    for m in every_method() {
        let mut reference: Option<f64> = None;
        for scale in [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e150] {
            let mut s = Soup { positions: base.positions.clone(), corner_verts: base.corner_verts.clone(), face_sizes: base.face_sizes.clone() };
            for (i, p) in s.positions.iter_mut().enumerate() {
                // A bumpy disk far from the origin.
                let z = 0.3 * ((i as f64) * 0.7).sin();
                *p = [scale * (p[0] + 1e3), scale * (p[1] - 5e2), scale * z];
            }
            let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
            let c = &r.charts[0];
            assert_ne!(c.status, ChartStatus::Failed, "{m:?} at {scale}: {:?}", c.reason);
            check_honest(&s, &r, &m, &format!("scale {scale}"));
            assert!(c.distortion.conformal.is_finite(), "{m:?} at {scale}: {:?}", c.distortion);
            // The map does not depend on the scale: the same distortion everywhere.
            match reference {
                None => reference = Some(c.distortion.conformal),
                Some(d) => assert!((c.distortion.conformal - d).abs() < 1e-6 * d, "{m:?} at {scale}: {} vs {d}", c.distortion.conformal),
            }
        }
    }
}

#[test]
fn coordinates_near_1e155_give_finite_uvs() {
    let base = planar_disk(3, 6);
    let s = Soup {
        positions: base.positions.iter().map(|p| [1e155 * p[0], 1e155 * p[1], 1e155 * 0.1 * p[0] * p[1]]).collect(),
        corner_verts: base.corner_verts.clone(),
        face_sizes: base.face_sizes.clone(),
    };
    for m in every_method() {
        let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
        assert_ne!(r.charts[0].status, ChartStatus::Failed, "{m:?}: {:?}", r.charts[0].reason);
        check_honest(&s, &r, &m, "1e155");
    }
}

#[test]
fn degenerate_3d_input_is_never_solved_with_promised_flips() {
    // A disk whose interior vertices are collapsed onto a line, and one with coincident
    // vertices: the geometry gives zero-area triangles.
    let base = planar_disk(3, 6);
    let collinear = Soup {
        positions: base.positions.iter().map(|p| [p[0], 0.0, 0.0]).collect(),
        corner_verts: base.corner_verts.clone(),
        face_sizes: base.face_sizes.clone(),
    };
    let coincident = Soup {
        positions: base.positions.iter().enumerate().map(|(i, p)| if i < 7 { [0.0; 3] } else { *p }).collect(),
        corner_verts: base.corner_verts.clone(),
        face_sizes: base.face_sizes.clone(),
    };
    let point = Soup {
        positions: vec![[1.0, 2.0, 3.0]; base.positions.len()],
        corner_verts: base.corner_verts.clone(),
        face_sizes: base.face_sizes.clone(),
    };
    for (what, s) in [("collinear", &collinear), ("coincident", &coincident), ("point", &point)] {
        for m in every_method() {
            let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
            check_honest(s, &r, &m, what);
        }
    }
}

#[test]
fn one_flip_definition_catches_zero_area_and_minority_triangles() {
    use uvflat_core::metrics::{count_flips, flipped_triangles};
    let tris = [[0u32, 1, 2], [0, 2, 3], [0, 3, 4]];
    // Two positive triangles and one exactly degenerate (3 on the segment 0–2... collinear).
    let uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [2.0, 2.0], [-1.0, 1.0]];
    assert_eq!(flipped_triangles(&tris, &uv), vec![false, true, false]);
    // The same at a scale of 1e-200 and 1e200: the tolerance is relative.
    for k in [1e-200, 1e200] {
        let scaled: Vec<[f64; 2]> = uv.iter().map(|p| [k * p[0], k * p[1]]).collect();
        assert_eq!(count_flips(&tris, &scaled), 1);
    }
    // Mirror everything: the majority is negative, the degenerate one still counts.
    let mirrored: Vec<[f64; 2]> = uv.iter().map(|p| [-p[0], p[1]]).collect();
    assert_eq!(count_flips(&tris, &mirrored), 1);
    // One triangle against the majority.
    let uv2 = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 2.0], [-1.0, 1.0]];
    let tris2 = [[0u32, 1, 2], [0, 2, 3], [0, 4, 3]];
    assert_eq!(flipped_triangles(&tris2, &uv2), vec![false, false, true]);
}

#[test]
fn fit_to_a_mirrored_target_does_not_collapse_the_chart() {
    use uvflat_core::Fit;
    let s = planar_disk(4, 6);
    let flat: Vec<[f64; 2]> = s.corner_verts.iter().map(|&v| [s.positions[v as usize][0], s.positions[v as usize][1]]).collect();
    // Previous UVs: the chart itself, mirrored, moved and scaled.
    let mirrored: Vec<[f64; 2]> = flat.iter().map(|p| [10.0 - 2.0 * p[0], 5.0 + 2.0 * p[1]]).collect();
    let o = UnwrapOptions { method: Method::Lscm, fit: Fit::Previous(mirrored.clone()), ..Default::default() };
    let r = unwrap(&s.input(), &o).unwrap();
    let c = &r.charts[0];
    assert_eq!(c.status, ChartStatus::Solved);
    assert_eq!(c.flips, 0);
    assert!(c.reason.as_deref().unwrap_or("").contains("area-scaled"), "{:?}", c.reason);
    // Area-scaled (UV area = 3D area) and centred on the target's bounding box.
    let mm = uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
    assert!((mm.distortion.area - 1.0).abs() < 1e-9);
    let bbox = |uv: &[[f64; 2]]| {
        uv.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        })
    };
    let ((lo, hi), (tlo, thi)) = (bbox(&r.uv), bbox(&mirrored));
    let width = hi[0] - lo[0];
    let twidth = (thi[0] - tlo[0]) / 2.0;
    assert!((width - twidth).abs() < 1e-6 * twidth, "chart width {width}, expected {twidth}");
    for d in 0..2 {
        assert!(((lo[d] + hi[d]) - (tlo[d] + thi[d])).abs() < 1e-9);
    }
    // A rotated (proper) target is fitted exactly.
    let (cs, sn) = (0.4f64.cos(), 0.4f64.sin());
    let rotated: Vec<[f64; 2]> = flat.iter().map(|p| [1.0 + 3.0 * (cs * p[0] - sn * p[1]), -2.0 + 3.0 * (sn * p[0] + cs * p[1])]).collect();
    let o = UnwrapOptions { method: Method::Lscm, fit: Fit::Previous(rotated.clone()), ..Default::default() };
    let r = unwrap(&s.input(), &o).unwrap();
    assert_eq!(r.charts[0].reason, None);
    for (a, b) in r.uv.iter().zip(&rotated) {
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
    }
}

#[test]
fn fit_to_reads_only_the_selected_faces() {
    use uvflat_core::Fit;
    let s = planar_disk(4, 6);
    let mut prev: Vec<[f64; 2]> = s.corner_verts.iter().map(|&v| [s.positions[v as usize][0], s.positions[v as usize][1]]).collect();
    let mut selected = vec![true; s.face_sizes.len()];
    let f = s.face_sizes.len() - 1;
    selected[f] = false;
    let corner = 3 * f;
    prev[corner] = [f64::NAN, f64::INFINITY];
    let mut input = s.input();
    input.selected = Some(&selected);
    let o = UnwrapOptions { method: Method::Lscm, fit: Fit::Previous(prev.clone()), ..Default::default() };
    let r = unwrap(&input, &o).unwrap();
    assert!(r.charts.iter().all(|c| c.status == ChartStatus::Solved));
    assert!(finite(&r.uv));
    // The same NaN on a selected face is an error naming the corner.
    selected[f] = true;
    let mut input = s.input();
    input.selected = Some(&selected);
    assert_eq!(unwrap(&input, &o).unwrap_err(), uvflat_core::UvError::NonFiniteUv { corner });
}

/// A `n × n` grid of quads with z noise, and a selection that punches `(n / spacing)²` square
/// holes of 2 × 2 faces.
fn holey_grid(n: usize, spacing: usize, noise: f64) -> (Soup, Vec<bool>) {
    let mut positions = Vec::new();
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    for j in 0..=n {
        for i in 0..=n {
            positions.push([i as f64 + noise * rnd(), j as f64 + noise * rnd(), noise * rnd()]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut corner_verts = Vec::new();
    let mut selected = Vec::new();
    for j in 0..n {
        for i in 0..n {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            let hole = i % spacing >= spacing - 2 && j % spacing >= spacing - 2 && i + 2 < n && j + 2 < n;
            selected.push(!hole);
        }
    }
    (Soup { positions, corner_verts, face_sizes: vec![4; n * n] }, selected)
}

#[test]
fn scaffold_on_a_chart_with_many_holes_converges_or_honestly_falls_back() {
    use uvflat_core::methods::scaffold::ScaffoldOptions;
    let (s, selected) = holey_grid(48, 6, 0.3);
    let holes = selected.iter().filter(|&&x| !x).count() / 4;
    assert!(holes >= 30, "{holes} holes");
    let mut input = s.input();
    input.selected = Some(&selected);
    let m = Method::Scaffold(ScaffoldOptions { max_iterations: 30, ..Default::default() });
    // The chart with its holes, uncut (automatic seams would join the holes to the outline).
    let mut o = opts(m.clone());
    o.auto_seams.enabled = false;
    let r = unwrap(&input, &o).unwrap();
    assert_eq!(r.charts.len(), 1);
    let c = &r.charts[0];
    eprintln!("{:?} {} iterations: {:?}", c.status, c.iterations, c.reason);
    assert_eq!(c.boundary_loops, holes + 1);
    match c.status {
        ChartStatus::Solved => {
            assert!(c.iterations > 0, "solved after 0 iterations: {:?}", c.reason);
            assert!(!c.reason.as_deref().unwrap_or("").contains("stopped early"), "{:?}", c.reason);
        }
        ChartStatus::Fallback => assert!(c.reason.as_deref().unwrap_or("").contains("symmetric Dirichlet"), "{:?}", c.reason),
        other => panic!("{other:?}: {:?}", c.reason),
    }
    assert_eq!(c.flips, 0);
    assert!(!c.overlap);
    assert!(finite(&r.uv));
}
