//! A scan with many small holes: every hole is joined to the outline, and on rough surface the
//! two sides of such a cut cross where the surface is saddle-shaped, at dozens of places over
//! the chart. The map of the chart is kept where it is sound: the faces around the crossings
//! are peeled into islands of their own (`pipeline/peel.rs`), each taking the pipeline's road
//! (its holes joined, then the last resort), instead of the chart being split level after
//! level and mapped by another method in the end. The outcome does not depend on threads.

mod common;

use common::{
    assert_islands_keep_the_rule, assert_same_on_one_thread, load, shared_meshes, subdivide, with_holes, Soup,
};
use uvflat_core::{unwrap, ChartStatus, Method, UnwrapOptions, Unwrapped};

/// The bunny subdivided twice (111,456 triangles, above the peel's threshold) with 100 holes
/// of 30 faces.
fn scan(seed: u64) -> Option<Soup> {
    let dir = shared_meshes()?;
    Some(with_holes(&subdivide(&subdivide(&load(&dir.join("bunny.off")))), 100, 30, seed))
}

/// Every island keeps the rule, the seams reported are those of the islands, and the bulk of
/// the scan is one island mapped by `method` itself, without a split.
fn check(s: &Soup, method: &str, r: &Unwrapped) {
    assert_islands_keep_the_rule(s, method, r);
    // The bulk of the scan is mapped by the method asked for, in one island...
    let faces = s.face_sizes.len();
    let main = r.charts.iter().max_by_key(|c| c.faces).unwrap();
    assert_eq!(main.status, ChartStatus::Solved, "{method}: the main island: {:?}", main.reason);
    assert_eq!(main.method, method);
    assert!(main.faces as f64 >= 0.85 * faces as f64, "{method}: the main island has {} of {faces} faces", main.faces);
    // ... by a bounded number of whole solves: no split of the chart was needed.
    assert_eq!(r.phases.splits, 0, "{method}: {:?}", r.phases);
    assert!(r.phases.peels >= 1, "{method}: {:?}", r.phases);
    // The peeled faces stay in a few dozen islands, at most one of them by another method.
    assert!(r.charts.len() <= 50, "{method}: {} islands", r.charts.len());
    let fallbacks = r.charts.iter().filter(|c| c.status == ChartStatus::Fallback).count();
    assert!(fallbacks <= 1, "{method}: {fallbacks} islands by another method");
}

#[test]
fn abf_keeps_its_map_of_a_scan_with_a_hundred_holes_where_it_is_sound() {
    let Some(s) = scan(4) else { return };
    let options = UnwrapOptions { method: Method::Abf(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    check(&s, "abf", &r);
    // The same on one thread, to the bit.
    assert_same_on_one_thread(&s, &options, &r);
}

/// On seed 4 the overlapping sides of `slim`'s map take 21% of the chart: the patch is peeled
/// (at most a quarter of the chart) rather than the chart split eight times and mapped by
/// `scaffold` in sixths.
#[test]
fn slim_peels_a_large_overlap_instead_of_splitting() {
    let Some(s) = scan(4) else { return };
    let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert_islands_keep_the_rule(&s, "slim", &r);
    assert_eq!(r.phases.splits, 0, "{:?}", r.phases);
    assert!(r.phases.peels >= 1, "{:?}", r.phases);
    let faces = s.face_sizes.len();
    let main = r.charts.iter().max_by_key(|c| c.faces).unwrap();
    assert_eq!(main.method, "slim");
    assert!(main.faces as f64 >= 0.5 * faces as f64, "the main island has {} of {faces} faces", main.faces);
    let fallbacks = r.charts.iter().filter(|c| c.status == ChartStatus::Fallback).count();
    assert!(fallbacks <= 1 && r.charts.len() <= 50, "{fallbacks} fallbacks, {} islands", r.charts.len());
}

#[test]
fn slim_keeps_its_map_of_a_scan_with_a_hundred_holes_where_it_is_sound() {
    let Some(s) = scan(3) else { return };
    let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    check(&s, "slim", &unwrap(&s.input(), &options).unwrap());
}
