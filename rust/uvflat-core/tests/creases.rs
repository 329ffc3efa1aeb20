//! Hard surfaces cut along their creases (`pipeline/creases.rs`): a cylinder with n-gon caps
//! comes out as two caps and an unrolled side, undistorted, with the same seams under every
//! method; charts the cones already unfold, organic charts, and charts where the creases
//! touch an avoided vertex keep the road they had.

use std::collections::BTreeSet;

use uvflat_core::{unwrap, ChartStatus, Method, UnwrapOptions};

mod common;

use common::Soup;

/// A closed cylinder of radius 1 and height `h`: `n`-gon caps on the side of `rings` rows of
/// `n` quads ([`common::cut_cylinder`], its seam left out), wound outwards.
fn capped_cylinder(n: usize, rings: usize, h: f64) -> Soup {
    let (mut s, _) = common::cut_cylinder(n, rings, h);
    let at = |j: usize, i: usize| (j * n + i % n) as u32;
    s.corner_verts.extend((0..n).rev().map(|i| at(0, i)));
    s.face_sizes.push(n as u32);
    s.corner_verts.extend((0..n).map(|i| at(rings, i)));
    s.face_sizes.push(n as u32);
    s
}

fn abf() -> Method {
    Method::parse("abf", &[]).unwrap()
}

fn run(s: &Soup, method: Method, f: impl FnOnce(&mut UnwrapOptions)) -> uvflat_core::Unwrapped {
    let mut o = UnwrapOptions { method, ..Default::default() };
    f(&mut o);
    unwrap(&s.input(), &o).expect("unwrap")
}

/// The cylinder's rim edges (both caps' outlines) as sorted vertex pairs.
fn rims(n: usize, rings: usize) -> BTreeSet<[u32; 2]> {
    let mut out = BTreeSet::new();
    for j in [0, rings] {
        for i in 0..n {
            let (a, b) = ((j * n + i) as u32, (j * n + (i + 1) % n) as u32);
            out.insert([a.min(b), a.max(b)]);
        }
    }
    out
}

#[test]
fn a_capped_cylinder_is_two_caps_and_an_unrolled_side_under_every_method() {
    let (n, rings) = (32, 3);
    let s = capped_cylinder(n, rings, 2.0);
    let rim = rims(n, rings);
    laid_flat_by_every_method(&s, 3, |name, seams| {
        // Both rims, and one line of `rings` edges down the side.
        assert!(rim.is_subset(seams), "{name}");
        let side: Vec<_> = seams.difference(&rim).collect();
        assert_eq!(side.len(), rings, "{name}: {side:?}");
        for e in side {
            let (a, b) = (e[0] as usize, e[1] as usize);
            assert_eq!(a % n, b % n, "{name}: a side seam runs along the height: {e:?}");
        }
    });
}

/// `s` under `abf`, `slim`, `lscm` and `mips`: cut along its creases once, into `islands`
/// islands, each solved by the method itself and laid flat without distortion; `check` sees
/// every method's new seams, which are the same for every method.
fn laid_flat_by_every_method(s: &Soup, islands: usize, check: impl Fn(&str, &BTreeSet<[u32; 2]>)) {
    let mut seams_of = Vec::new();
    for method in ["abf", "slim", "lscm", "mips"].map(|m| Method::parse(m, &[]).unwrap()) {
        let name = method.name();
        let r = run(s, method, |_| {});
        assert_eq!(r.phases.crease_cuts, 1, "{name}");
        assert_eq!(r.charts.len(), islands, "{name}: {:?}", r.charts.iter().map(|c| c.triangles).collect::<Vec<_>>());
        for c in &r.charts {
            assert_eq!(c.status, ChartStatus::Solved, "{name}: {:?}", c.reason);
            assert_eq!(c.method, name);
            // Laid flat as they are: caps, sides and sectors without distortion.
            let d = c.distortion;
            assert!(d.conformal < 1.0 + 1e-6 && d.area < 1.0 + 1e-6, "{name}: {d:?}");
        }
        let seams: BTreeSet<[u32; 2]> = r.new_seams.iter().copied().collect();
        check(name, &seams);
        seams_of.push(seams);
    }
    assert!(seams_of.windows(2).all(|w| w[0] == w[1]), "the same seams whatever the method");
}

#[test]
fn charts_the_cones_unfold_or_that_are_curved_keep_their_road() {
    // A cube: 8 curved corners, no more than Max Cones: its cones unfold it in one net.
    let r = run(&common::cube(4), abf(), |_| {});
    assert_eq!(r.phases.crease_cuts, 0);
    assert_eq!(r.charts.len(), 1);
    // A sphere has no creases; a cube projected on the sphere has curvature everywhere.
    let r = run(&common::cube_sphere(8), abf(), |_| {});
    assert_eq!(r.phases.crease_cuts, 0);
    // With room for every curved vertex as a cone, the cylinder keeps the cones' road too.
    let s = capped_cylinder(16, 1, 1.0);
    let r = run(&s, abf(), |o| o.auto_seams.max_cones = 64);
    assert_eq!(r.phases.crease_cuts, 0);
    // Creases touching an avoided vertex are not cut wholesale.
    let r = run(&s, abf(), |o| o.auto_seams.avoid_vertices = vec![0]);
    assert_eq!(r.phases.crease_cuts, 0);
    assert!(r.new_seams.iter().all(|e| e[0] != 0 && e[1] != 0));
    // A pinned chart keeps its road, and its pin.
    let pins = [(0u32, [0.25, 0.5])];
    let input = uvflat_core::MeshInput { pins: &pins, ..s.input() };
    let r = unwrap(&input, &UnwrapOptions { method: abf(), ..Default::default() }).expect("unwrap");
    assert_eq!(r.phases.crease_cuts, 0);
    assert_eq!(r.uv[0], [0.25, 0.5]);
    // Without automatic seams nothing is cut.
    let r = run(&s, abf(), |o| o.auto_seams.enabled = false);
    assert_eq!(r.phases.crease_cuts, 0);
    assert!(r.new_seams.is_empty());
}

#[test]
fn a_bent_cylinder_is_not_developable_and_keeps_the_cones_road() {
    // The same cylinder with its side bulged: the side's inner vertices are curved, so
    // cutting the creases would leave curved regions; the chart is planned with cones.
    let mut s = capped_cylinder(32, 6, 2.0);
    for p in &mut s.positions {
        let bulge = 1.0 + 0.3 * (std::f64::consts::PI * p[2] / 2.0).sin();
        p[0] *= bulge;
        p[1] *= bulge;
    }
    let r = run(&s, abf(), |_| {});
    assert_eq!(r.phases.crease_cuts, 0);
    for c in &r.charts {
        assert!(c.flips == 0 && !c.overlap && c.density.outside <= 0.05 + 1e-9, "{c:?}");
    }
}

/// A closed cone of radius 1 and height `h`: a fan of `n` triangles around the tip and an
/// `n`-gon base, wound outwards.
fn capped_cone(n: usize, h: f64) -> Soup {
    let mut positions = vec![[0.0, 0.0, h]];
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        positions.push([a.cos(), a.sin(), 0.0]);
    }
    let ring = |i: usize| (1 + i % n) as u32;
    let mut corner_verts = Vec::new();
    for i in 0..n {
        corner_verts.extend([0, ring(i), ring(i + 1)]);
    }
    corner_verts.extend((0..n).rev().map(ring));
    let mut face_sizes = vec![3; n];
    face_sizes.push(n as u32);
    Soup { positions, corner_verts, face_sizes }
}

/// A cone's tip is curved where no crease touches it: the regions' own cones relieve it. The
/// base comes off along its rim, the side is cut from the tip to the rim and unrolls into a
/// sector: two islands without distortion, the same seams under every method.
#[test]
fn a_capped_cone_is_its_base_and_an_unrolled_side() {
    let n = 32;
    let s = capped_cone(n, 2.0);
    let rim: BTreeSet<[u32; 2]> = (0..n).map(|i| {
        let (a, b) = ((1 + i) as u32, (1 + (i + 1) % n) as u32);
        [a.min(b), a.max(b)]
    }).collect();
    laid_flat_by_every_method(&s, 2, |name, seams| {
        assert!(rim.is_subset(seams), "{name}: the rim is cut");
        let inside: Vec<_> = seams.difference(&rim).collect();
        assert_eq!(inside.len(), 1, "{name}: one cut from the tip to the rim: {inside:?}");
        assert_eq!(inside[0][0], 0, "{name}: the cut starts at the tip");
    });

    // With the tip avoided no cut may end there: the cone keeps the cones' road, and no new
    // seam touches the tip.
    let r = run(&s, abf(), |o| o.auto_seams.avoid_vertices = vec![0]);
    assert_eq!(r.phases.crease_cuts, 0);
    assert!(r.new_seams.iter().all(|e| e[0] != 0 && e[1] != 0), "{:?}", r.new_seams);
}

/// A gear of `teeth` teeth and height `h`, extruded from a polygon whose radius steps between
/// 1 and 0.85 every two corners (each tooth's sides at right angles to its top): n-gon caps
/// and one quad per side face, every side face meeting its neighbours at a crease.
fn gear(teeth: usize, h: f64) -> Soup {
    let n = 4 * teeth;
    let mut positions = Vec::new();
    for z in [0.0, h] {
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let r = if (k / 2) % 2 == 0 { 1.0 } else { 0.85 };
            positions.push([r * a.cos(), r * a.sin(), z]);
        }
    }
    let mut corner_verts: Vec<u32> = (0..n as u32).rev().collect();
    let mut face_sizes = vec![n as u32];
    corner_verts.extend((0..n as u32).map(|k| k + n as u32));
    face_sizes.push(n as u32);
    for k in 0..n as u32 {
        let next = (k + 1) % n as u32;
        corner_verts.extend([k, next, next + n as u32, k + n as u32]);
        face_sizes.push(4);
    }
    Soup { positions, corner_verts, face_sizes }
}

/// The gear's side faces meet at creases along its axis, each joining two faces: its side is
/// one band, unrolled as one strip (cut once, along the axis), beside its two caps, instead
/// of an island per face; the rims stay cut.
#[test]
fn an_extrusion_s_side_is_one_strip_beside_its_caps() {
    let (teeth, n) = (12, 48);
    let s = gear(teeth, 0.3);
    let rim = rims(n, 1);
    laid_flat_by_every_method(&s, 3, |name, seams| {
        assert!(rim.is_subset(seams), "{name}: the rims are cut");
        let side: Vec<_> = seams.difference(&rim).collect();
        assert_eq!(side.len(), 1, "{name}: one cut down the side: {side:?}");
        assert_eq!(side[0][0] as usize % n, side[0][1] as usize % n, "{name}: along the axis");
    });
}
