//! Fuzzing of the whole pipeline with random meshes (proptest): perturbed triangle and quad
//! grids and random Delaunay disks, at scales from 1e-6 to 1e6, with random seams, selections,
//! pins and degenerate perturbations (vertices collapsed onto a line or onto each other), for
//! every method. Properties:
//! * `unwrap` never panics and accepts every valid input;
//! * every chart that is not failed has finite UVs, and a failed one has a reason;
//! * a method that promises no flips ([`Method::promises_no_flips`]) on an unpinned chart is
//!   never `solved` with a flipped triangle;
//! * each chart's reported flips equal what `metrics::measure` finds on its UVs.
//!
//! The default run is bounded (2,000 cases, a few seconds in release);
//! `UVFLAT_FUZZ_CASES=100000 cargo test --release -p uvflat-core --test fuzz` runs longer.

mod common;

use proptest::prelude::*;
use uvflat_core::{metrics, unwrap, ChartStatus, MeshInput, Method, UnwrapOptions};

/// splitmix64: the meshes are generated from one seed, so a failing case is a few integers.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

struct Mesh {
    positions: Vec<[f64; 3]>,
    corner_verts: Vec<u32>,
    face_sizes: Vec<u32>,
}

/// An nx × ny grid, quads or triangles (random diagonals), jittered in the plane and in z.
fn grid(rng: &mut Rng, nx: usize, ny: usize, quads: bool, jitter: f64) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f64 + jitter * (rng.unit() - 0.5), j as f64 + jitter * (rng.unit() - 0.5));
            positions.push([x, y, jitter * (rng.unit() - 0.5) + 0.2 * (0.7 * x).sin() * (0.5 * y).cos()]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let (mut corner_verts, mut face_sizes) = (Vec::new(), Vec::new());
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if quads {
                corner_verts.extend([a, b, c, d]);
                face_sizes.push(4);
            } else if rng.unit() < 0.5 {
                corner_verts.extend([a, b, c, a, c, d]);
                face_sizes.extend([3, 3]);
            } else {
                corner_verts.extend([a, b, d, b, c, d]);
                face_sizes.extend([3, 3]);
            }
        }
    }
    Mesh { positions, corner_verts, face_sizes }
}

/// Random points in the unit disk (a ring on the boundary), Delaunay-triangulated, lifted
/// to a bump.
fn delaunay_disk(rng: &mut Rng, n: usize) -> Mesh {
    use spade::{DelaunayTriangulation, Point2, Triangulation};
    let mut pts = Vec::new();
    let ring = 8 + n / 4;
    for k in 0..ring {
        let a = std::f64::consts::TAU * k as f64 / ring as f64;
        pts.push((a.cos(), a.sin()));
    }
    while pts.len() < ring + n {
        let (x, y) = (2.0 * rng.unit() - 1.0, 2.0 * rng.unit() - 1.0);
        if x * x + y * y < 0.9 {
            pts.push((x, y));
        }
    }
    let mut t: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut handle_of = Vec::new();
    for &(x, y) in &pts {
        handle_of.push(t.insert(Point2::new(x, y)).expect("finite point"));
    }
    let index: std::collections::HashMap<_, u32> = handle_of.iter().enumerate().map(|(i, h)| (*h, i as u32)).collect();
    let positions: Vec<[f64; 3]> = pts.iter().map(|&(x, y)| [x, y, 0.5 * (1.0 - x * x - y * y)]).collect();
    let mut corner_verts = Vec::new();
    for f in t.inner_faces() {
        let [a, b, c] = f.vertices();
        corner_verts.extend([index[&a.fix()], index[&b.fix()], index[&c.fix()]]);
    }
    let face_sizes = vec![3; corner_verts.len() / 3];
    Mesh { positions, corner_verts, face_sizes }
}

fn methods() -> Vec<Method> {
    common::every_method(10, 50)
}

/// One random case: everything follows from these integers.
#[derive(Debug, Clone)]
struct Case {
    seed: u64,
    shape: u8,
    size: usize,
    method: usize,
    log_scale: f64,
    seams: u8,
    unselected: u8,
    pins: usize,
    degenerate: u8,
}

fn case() -> impl Strategy<Value = Case> {
    (any::<u64>(), 0u8..3, 2usize..9, 0..methods().len(), -6.0f64..6.0, 0u8..3, 0u8..3, 0usize..4, 0u8..4).prop_map(
        |(seed, shape, size, method, log_scale, seams, unselected, pins, degenerate)| Case {
            seed,
            shape,
            size,
            method,
            log_scale,
            seams,
            unselected,
            pins,
            degenerate,
        },
    )
}

fn run_case(c: &Case, stats: &Stats) -> Result<(), TestCaseError> {
    let mut rng = Rng(c.seed);
    let mut mesh = match c.shape {
        0 => grid(&mut rng, c.size, c.size + 1, false, 0.4),
        1 => grid(&mut rng, c.size + 1, c.size, true, 0.3),
        _ => delaunay_disk(&mut rng, 6 * c.size),
    };
    let nv = mesh.positions.len();
    // Degenerate perturbations: a few vertices onto a line, onto another vertex, or all of
    // them onto a line.
    match c.degenerate {
        1 => {
            for _ in 0..1 + nv / 8 {
                let v = rng.below(nv);
                mesh.positions[v][1] = mesh.positions[0][1];
                mesh.positions[v][2] = mesh.positions[0][2];
            }
        }
        2 => {
            for _ in 0..1 + nv / 8 {
                let (v, w) = (rng.below(nv), rng.below(nv));
                mesh.positions[v] = mesh.positions[w];
            }
        }
        3 => {
            for p in mesh.positions.iter_mut() {
                *p = [p[0] + 0.5 * p[1], 0.0, 0.0];
            }
        }
        _ => {}
    }
    let scale = 10f64.powf(c.log_scale);
    let shift = [rng.unit() * 100.0, -rng.unit() * 50.0, 7.0];
    for p in mesh.positions.iter_mut() {
        *p = [scale * (p[0] + shift[0]), scale * (p[1] + shift[1]), scale * (p[2] + shift[2])];
    }
    let n_faces = mesh.face_sizes.len();
    let n_corners = mesh.corner_verts.len();
    // Seams: a random share of the face edges.
    let mut seams = Vec::new();
    let mut start = 0usize;
    for &k in &mesh.face_sizes {
        for i in 0..k as usize {
            if (rng.below(10) as u8) < 2 * c.seams {
                seams.push([mesh.corner_verts[start + i], mesh.corner_verts[start + (i + 1) % k as usize]]);
            }
        }
        start += k as usize;
    }
    let selected: Vec<bool> = (0..n_faces).map(|_| rng.below(10) as u8 >= 2 * c.unselected).collect();
    let pins: Vec<(u32, [f64; 2])> = (0..c.pins)
        .map(|_| (rng.below(n_corners) as u32, [10.0 * rng.unit() - 5.0, 10.0 * rng.unit() - 5.0]))
        .collect();
    let input = MeshInput {
        positions: &mesh.positions,
        corner_verts: &mesh.corner_verts,
        face_sizes: &mesh.face_sizes,
        seams: &seams,
        selected: Some(&selected),
        pins: &pins,
        triangles: &[],
    };
    let method = methods()[c.method].clone();
    let r = unwrap(&input, &UnwrapOptions { method: method.clone(), ..Default::default() });
    let r = r.map_err(|e| TestCaseError::fail(format!("valid input refused: {e}")))?;

    let mut face_start = vec![0usize; n_faces + 1];
    for f in 0..n_faces {
        face_start[f + 1] = face_start[f] + mesh.face_sizes[f] as usize;
    }
    let mut pinned_chart = vec![false; r.charts.len()];
    for &(corner, _) in &pins {
        let f = face_start.partition_point(|&s| s <= corner as usize) - 1;
        if r.face_chart[f] >= 0 {
            pinned_chart[r.face_chart[f] as usize] = true;
        }
    }
    stats.record(&method, &r);
    for rep in &r.charts {
        let faces: Vec<usize> = (0..n_faces).filter(|&f| r.face_chart[f] == rep.id as i32).collect();
        if rep.status == ChartStatus::Failed {
            prop_assert!(rep.reason.is_some(), "chart {} failed without a reason", rep.id);
            continue;
        }
        for &f in &faces {
            for corner in face_start[f]..face_start[f + 1] {
                let q = r.uv[corner];
                prop_assert!(q[0].is_finite() && q[1].is_finite(), "chart {} ({:?}): corner {corner} has UV {q:?}", rep.id, rep.status);
            }
        }
        if rep.status == ChartStatus::Solved && !pinned_chart[rep.id] && method.promises_no_flips(rep.kind) {
            prop_assert_eq!(rep.flips, 0, "{} promises no flips but chart {} is solved with flips: {:?}", method.name(), rep.id, rep.reason);
        }
        // The report agrees with measuring the chart's UVs on their own.
        let mut only = vec![false; n_faces];
        for &f in &faces {
            only[f] = true;
        }
        let m = metrics::measure(&mesh.positions, &mesh.corner_verts, &mesh.face_sizes, &r.uv, Some(&only))
            .map_err(|e| TestCaseError::fail(format!("measure refused the UVs: {e}")))?;
        if m.charts == 1 {
            prop_assert_eq!(m.flips, rep.flips, "chart {}: report and metrics disagree ({:?})", rep.id, rep.reason);
        }
    }
    Ok(())
}

fn cases() -> u32 {
    std::env::var("UVFLAT_FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(2000)
}

/// What the cases produced: charts per method and status, and the first words of every
/// fallback and failure reason (printed at the end, to see what a long run exercised).
#[derive(Default)]
struct Stats(std::sync::Mutex<std::collections::BTreeMap<String, usize>>);

impl Stats {
    fn record(&self, method: &Method, r: &uvflat_core::Unwrapped) {
        let mut m = self.0.lock().unwrap();
        let n = m.entry("cases".into()).or_default();
        *n += 1;
        if *n % 20_000 == 0 {
            eprintln!("{n} cases");
        }
        for c in &r.charts {
            *m.entry(format!("{} {}", method.name(), c.status.name())).or_default() += 1;
            if c.status != ChartStatus::Solved {
                if let Some(reason) = &c.reason {
                    let head: String = reason.split([':', '(', ';']).next().unwrap_or("").chars().take(60).collect();
                    *m.entry(format!("  {} {}: {}", method.name(), c.status.name(), head.trim())).or_default() += 1;
                }
            }
        }
    }
}

#[test]
fn random_meshes_keep_every_promise() {
    let config = ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() };
    // The default (CI) run is reproducible: a fixed seed. A long run (UVFLAT_FUZZ_CASES set)
    // draws a fresh seed every time, so repeated long runs explore new cases.
    let mut runner = if std::env::var_os("UVFLAT_FUZZ_CASES").is_some() {
        proptest::test_runner::TestRunner::new(config)
    } else {
        let rng = proptest::test_runner::TestRng::deterministic_rng(config.rng_algorithm);
        proptest::test_runner::TestRunner::new_with_rng(config, rng)
    };
    let stats = Stats::default();
    let outcome = runner.run(&case(), |c| run_case(&c, &stats));
    for (k, v) in stats.0.lock().unwrap().iter() {
        eprintln!("{v:>8}  {k}");
    }
    if let Err(e) = outcome {
        panic!("{e}");
    }
}
