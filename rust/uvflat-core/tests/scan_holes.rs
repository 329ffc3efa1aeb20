//! A scan with many small holes: the holes are filled for the unwrap and joined to the
//! outline by closed seams after it (`pipeline/fill.rs`), so the scan is unwrapped as the
//! closed surface it scanned. Cut open instead, every hole joined to the outline by a cut whose
//! two sides are free, the outline ran through all of them, crossed itself at dozens of places,
//! and the peel (`pipeline/peel.rs`) left 17–31 islands, most of them specks around the holes.
//! The outcome does not depend on threads.

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

/// Every island keeps the rule, the seams reported are those of the islands, the holes were
/// filled and joined, and the scan is a few islands mapped by `method` itself, without the
/// last resort: at most `islands` of more than one face (a face that only holes bordered is
/// an island of its own, as it is a part of the mesh of its own).
fn check(s: &Soup, method: &str, r: &Unwrapped, islands: usize) {
    assert_islands_keep_the_rule(s, method, r);
    assert!(r.phases.holes_filled >= 90, "{method}: {:?}", r.phases);
    assert_eq!(r.phases.fill_undone, 0.0, "{method}: {:?}", r.phases);
    assert_eq!(r.phases.last_resort, 0, "{method}: {:?}", r.phases);
    let faces = s.face_sizes.len();
    let main = r.charts.iter().max_by_key(|c| c.faces).unwrap();
    assert_eq!(main.status, ChartStatus::Solved, "{method}: the main island: {:?}", main.reason);
    assert_eq!(main.method, method);
    assert!(main.faces as f64 >= 0.5 * faces as f64, "{method}: the main island has {} of {faces} faces", main.faces);
    let large = r.charts.iter().filter(|c| c.faces > 1).count();
    assert!(large <= islands, "{method}: {large} islands of more than one face");
    assert!(r.charts.iter().all(|c| c.status == ChartStatus::Solved), "{method}: an island by another method");
}

#[test]
fn abf_unwraps_a_scan_with_a_hundred_holes_as_the_closed_surface_it_scanned() {
    let Some(s) = scan(4) else { return };
    let options = UnwrapOptions { method: Method::Abf(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    // The closed bunny subdivided twice is 3 islands under `abf`; with its holes cut open, a
    // few dozen.
    check(&s, "abf", &r, 5);
    // The same on one thread, to the bit.
    assert_same_on_one_thread(&s, &options, &r);
}

#[test]
fn slim_unwraps_a_scan_with_a_hundred_holes_as_the_closed_surface_it_scanned() {
    for seed in [3, 4] {
        let Some(s) = scan(seed) else { return };
        let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
        // The closed bunny subdivided twice is 1 island under `slim`; with its holes cut open, a
        // few dozen.
        check(&s, "slim", &unwrap(&s.input(), &options).unwrap(), 4);
    }
}
