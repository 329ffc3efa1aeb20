//! Progress callback and cancellation of `unwrap` (between charts and between iterations).

mod common;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::*;
use uvflat_core::methods::arap::ArapOptions;
use uvflat_core::{unwrap, Method, MeshInput, Progress, UnwrapOptions, UvError};

/// `n` separate copies of a planar disk, side by side: `n` charts.
fn disks(n: usize) -> Soup {
    let one = planar_disk(4, 12);
    let mut s = Soup { positions: Vec::new(), corner_verts: Vec::new(), face_sizes: Vec::new() };
    for k in 0..n {
        let base = s.positions.len() as u32;
        s.positions.extend(one.positions.iter().map(|p| [p[0] + 3.0 * k as f64, p[1], p[2]]));
        s.corner_verts.extend(one.corner_verts.iter().map(|&v| v + base));
        s.face_sizes.extend(&one.face_sizes);
    }
    s
}

fn with_progress(method: Method, progress: Progress) -> UnwrapOptions {
    UnwrapOptions { method, progress: Some(progress), ..Default::default() }
}

#[test]
fn callback_sees_every_chart_once_and_the_result_is_unchanged() {
    let s = disks(7);
    let calls = Arc::new(Mutex::new(Vec::new()));
    let seen = calls.clone();
    let progress = Progress::with_callback(move |done, total| {
        seen.lock().unwrap().push((done, total));
        true
    });
    let r = unwrap(&s.input(), &with_progress(Method::Lscm, progress)).unwrap();
    let plain = unwrap(&s.input(), &UnwrapOptions { method: Method::Lscm, ..Default::default() }).unwrap();
    assert_eq!(r.uv, plain.uv, "a progress callback must not change the map");
    let mut calls = calls.lock().unwrap().clone();
    calls.sort();
    assert_eq!(calls, (1..=7).map(|d| (d, 7)).collect::<Vec<_>>());
}

#[test]
fn callback_returning_false_cancels() {
    let s = disks(6);
    let progress = Progress::with_callback(|_, _| false);
    match unwrap(&s.input(), &with_progress(Method::Lscm, progress)) {
        Err(UvError::Cancelled { charts_done, charts_total }) => {
            assert_eq!(charts_total, 6);
            assert!((1..=6).contains(&charts_done));
        }
        other => panic!("expected Cancelled, got {other:?}"),
    }
}

#[test]
fn cancel_before_start_solves_nothing() {
    let s = disks(3);
    let progress = Progress::new();
    progress.cancel();
    let err = unwrap(&s.input(), &with_progress(Method::Lscm, progress)).unwrap_err();
    assert!(matches!(err, UvError::Cancelled { charts_done: 0, charts_total: 3 }), "{err:?}");
    assert_eq!(err.to_string(), "cancelled after 0 of 3 charts");
}

#[test]
fn cancel_stops_an_iterative_method_between_iterations() {
    // One curved chart (a dome: ARAP's energy never reaches 0), ARAP with a huge iteration
    // budget and no tolerance: only the cancel flag, polled once per iteration, stops it.
    let mut s = planar_disk(30, 90);
    let r2 = s.positions.iter().map(|p| p[0] * p[0] + p[1] * p[1]).fold(0.0, f64::max);
    for p in &mut s.positions {
        p[2] = 0.5 * (1.0 - (p[0] * p[0] + p[1] * p[1]) / r2);
    }
    let input: MeshInput<'_> = s.input();
    let method = Method::Arap(ArapOptions { max_iterations: 1_000_000, tolerance: 0.0 });
    let progress = Progress::new();
    let canceller = progress.clone();
    let start = Instant::now();
    let handle = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(300));
        canceller.cancel();
    });
    let err = unwrap(&input, &with_progress(method, progress)).unwrap_err();
    handle.join().unwrap();
    assert!(matches!(err, UvError::Cancelled { .. }), "{err:?}");
    assert!(start.elapsed() < Duration::from_secs(20), "cancel was not polled between iterations");
}
