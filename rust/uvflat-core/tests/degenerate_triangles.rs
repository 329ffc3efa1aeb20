//! Scans carry degenerate triangles (a vertex collapsed onto a neighbour leaves triangles with
//! two coincident corners and no area). The barrier methods' energy must still hold them
//! (`methods/nonlinear/jacobian.rs::TriangleOperators::local_frames`): with no area they
//! carried no energy, `scaffold` and `mips` let them fold, and their islands were reported
//! invalid, and so was every island whose last resort is `scaffold`.

mod common;

use common::{assert_islands_keep_the_rule, load, octahedron_sphere, shared_meshes, subdivide, Soup};
use uvflat_core::{unwrap, Method, UnwrapOptions};

/// `s` with the second corner of every `step`-th triangle moved onto its first.
fn collapsed(mut s: Soup, step: usize) -> Soup {
    for k in (0..s.face_sizes.len()).step_by(step) {
        let (a, b) = (s.corner_verts[3 * k] as usize, s.corner_verts[3 * k + 1] as usize);
        s.positions[b] = s.positions[a];
    }
    s
}

/// A bumpy closed mesh (a sphere with ridges, 8,192 triangles) with a vertex collapsed in
/// every 29th triangle (6–7% of the triangles without area).
fn bumpy_collapsed() -> Soup {
    let mut s = subdivide(&octahedron_sphere(4));
    for p in &mut s.positions {
        let r = 1.0 + 0.25 * (5.0 * p[0]).sin() * (4.0 * p[1]).cos() + 0.3 * p[2] * p[2];
        *p = [p[0] * r, p[1] * r, p[2] * r * 1.6];
    }
    collapsed(s, 29)
}

fn keeps_the_rule(s: &Soup, what: &str, methods: &[(&str, Method)]) {
    for (name, method) in methods {
        let options = UnwrapOptions { method: method.clone(), ..Default::default() };
        let r = unwrap(&s.input(), &options).unwrap();
        assert_islands_keep_the_rule(s, &format!("{what} {name}"), &r);
        assert!(r.uv.iter().flatten().all(|x| x.is_finite()), "{what} {name}");
    }
}

#[test]
fn barrier_methods_keep_the_rule_with_collapsed_vertices() {
    let s = bumpy_collapsed();
    let zero = (0..s.face_sizes.len())
        .filter(|&k| {
            let c = &s.corner_verts[3 * k..3 * k + 3];
            let p = |i: usize| s.positions[c[i] as usize];
            let (a, b, c) = (p(0), p(1), p(2));
            let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
            let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            n.iter().all(|x| *x == 0.0)
        })
        .count();
    assert!(zero >= 400, "{zero} triangles without area");
    keeps_the_rule(
        &s,
        "bumpy sphere",
        &[("scaffold", Method::Scaffold(Default::default())), ("mips", Method::Mips(Default::default()))],
    );
}

/// The bunny with a vertex collapsed in every 97th triangle: `scaffold` and `mips` left a
/// folded island each, and `lscm`'s last resort (`scaffold`) failed on one.
#[test]
fn a_scan_with_collapsed_vertices_keeps_the_rule() {
    let Some(dir) = shared_meshes() else {
        eprintln!("skipped: ../shared/meshes is absent");
        return;
    };
    let s = collapsed(load(&dir.join("bunny.off")), 97);
    keeps_the_rule(
        &s,
        "bunny",
        &[
            ("scaffold", Method::Scaffold(Default::default())),
            ("mips", Method::Mips(Default::default())),
            ("lscm", Method::Lscm),
        ],
    );
}

/// The beetle with a vertex collapsed in every 89th or 79th triangle: `abf` leaves one island
/// of 38,656 faces whose outline crosses itself where the surface folds, and the last
/// resort's `scaffold` stalls on it. The repair's last step peels it at any size
/// (`pipeline/peel.rs`): the faces where the outline crosses become islands of their own.
/// (Every 79th: with three of its small holes filled for the unwrap, `pipeline/fill.rs`, the
/// last resort maps the beetle whole within the rule, one island by another method, and no
/// peel is needed.)
#[test]
fn a_folded_island_is_peeled_at_any_size() {
    let Some(dir) = shared_meshes() else {
        eprintln!("skipped: ../shared/meshes is absent");
        return;
    };
    for step in [89, 79] {
        let s = collapsed(load(&dir.join("beetle.off")), step);
        let options = UnwrapOptions { method: Method::Abf(Default::default()), ..Default::default() };
        let r = unwrap(&s.input(), &options).unwrap();
        assert!(s.face_sizes.len() < uvflat_core::pipeline::peel::PEEL_FROM);
        assert!(step != 89 || r.phases.peels >= 1, "step {step}: {:?}", r.phases);
        assert_islands_keep_the_rule(&s, &format!("beetle, step {step}"), &r);
        // The peel keeps the piece's map: one island keeps almost every face.
        let largest = r.charts.iter().map(|c| c.faces).max().unwrap_or(0);
        assert!(largest * 10 >= 9 * s.face_sizes.len(), "step {step}: largest island {largest}");
    }
}
