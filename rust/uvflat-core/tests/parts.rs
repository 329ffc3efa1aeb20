//! Parts (`pipeline/parts.rs`): under a method that balances area, a piece of a cut of
//! `PART_FROM` triangles or more is cut into parts along cheap seams before the solve, and the
//! parts are solved side by side. Every island keeps the atlas rule and is a disk, none is as
//! large as the threshold, the seams reported are the islands', and the outcome is the same on
//! one thread as on several. Conformal methods solve their pieces whole. A large disk goes to
//! its parts before any solve when it is predicted to break the rule by far, and is solved
//! whole when it flattens well.

mod common;

use common::{assert_islands_keep_the_rule, assert_same_on_one_thread, sphere, Soup};
use uvflat_core::pipeline::parts::PART_FROM;
use uvflat_core::{unwrap, Method, UnwrapOptions};

/// [`large_closed`] with its bottom cap cut off (the faces whose centroid lies below
/// `z = -0.95` on the unit sphere, of a finer sphere): one disk of more than [`PART_FROM`] triangles.
fn large_open() -> Soup {
    ellipsoid_with_bump(sphere(440, 331, |c| c[2] > -0.95))
}

/// A closed UV sphere of 132,400 faces (quads, triangles at the poles: 264,000 triangles),
/// stretched into an ellipsoid with a bump (smooth,
/// its curvature uneven).
fn large_closed() -> Soup {
    ellipsoid_with_bump(sphere(400, 331, |_| true))
}

/// The unit sphere `s` stretched into an ellipsoid with a bump.
fn ellipsoid_with_bump(mut s: Soup) -> Soup {
    for p in &mut s.positions {
        let bump = 1.0 + 0.6 * (-8.0 * ((p[0] - 0.6).powi(2) + p[1].powi(2))).exp();
        *p = [2.0 * bump * p[0], p[1], 0.6 * p[2]];
    }
    s
}

/// `s` (of at least [`PART_FROM`] triangles) unwrapped under `slim`, with its options: cut
/// into parts, every island keeps the rule and is smaller than the threshold.
fn unwrap_in_parts(s: &Soup) -> (UnwrapOptions, uvflat_core::Unwrapped) {
    let triangles: usize = s.face_sizes.iter().map(|&n| n as usize - 2).sum();
    assert!(triangles >= PART_FROM, "{triangles} triangles");
    let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.phases.parts >= 1, "{:?}", r.phases);
    assert_islands_keep_the_rule(s, "slim", &r);
    let largest = r.charts.iter().map(|c| c.triangles).max().unwrap();
    assert!(largest < PART_FROM, "an island of {largest} triangles");
    (options, r)
}

#[test]
fn a_large_closed_chart_is_solved_in_parts_that_keep_the_rule_on_any_number_of_threads() {
    let s = large_closed();
    let (options, r) = unwrap_in_parts(&s);
    assert!(r.charts.len() <= 12, "{} islands", r.charts.len());
    // The same on one thread, to the bit.
    assert_same_on_one_thread(&s, &options, &r);
}

#[test]
fn a_conformal_method_solves_its_pieces_whole() {
    assert_no_parts_under_abf(&large_closed());
}

/// `s` unwrapped under `abf`: no part is cut, and every island keeps the rule.
fn assert_no_parts_under_abf(s: &Soup) {
    let options = UnwrapOptions { method: Method::Abf(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert_eq!(r.phases.parts, 0, "{:?}", r.phases);
    assert_islands_keep_the_rule(s, "abf", &r);
}

#[test]
fn a_large_disk_is_cut_into_parts_before_any_solve() {
    // Its conformal flattening breaks Max Stretch by far. Solved whole first, the disk's own
    // solve was thrown away when it broke the rule (the camel's head subdivided twice: 7.6 s
    // of 12.9 s).
    let s = large_open();
    let (_, r) = unwrap_in_parts(&s);
    assert_eq!(r.phases.solve, 0.0, "the disk was solved whole first: {:?}", r.phases);
    // A conformal method cuts no parts (it solves the disk as it is when it keeps the rule).
    assert_no_parts_under_abf(&s);
}

#[test]
fn a_large_disk_that_flattens_well_is_solved_whole() {
    // A displaced grid of 302,642 triangles (a terrain patch): its conformal flattening keeps
    // Max Stretch, so it is solved as it is, one island, not cut into parts.
    let n = 390;
    let mut positions = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (4.0 * i as f64 / (n - 1) as f64, 4.0 * j as f64 / (n - 1) as f64);
            positions.push([x, y, 0.15 * (3.0 * x).sin() * (2.0 * y).cos() + 0.05 * (11.0 * x + 3.0 * y).sin()]);
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            faces.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            faces.push(vec![id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let s = common::soup_of(positions, faces, |_| true);
    assert!(s.face_sizes.len() >= PART_FROM);
    let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert_eq!(r.charts.len(), 1, "{:?}", r.phases);
    assert_eq!(r.phases.parts, 0, "{:?}", r.phases);
    assert!(r.phases.solve > 0.0, "not solved whole: {:?}", r.phases);
    assert_islands_keep_the_rule(&s, "slim", &r);
}
