//! The last-resort split of a chart follows a smooth loop: on tubes (straight, bumpy, bent
//! into a U) the seam is one closed loop around the tube, about as long as the tube's
//! circumference there, and it halves the area.

use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{self, split, AutoSeamOptions, ChartGraph};
use uvflat_core::mesh::PolyMesh;

use std::f64::consts::{PI, TAU};

struct Mesh {
    positions: Vec<[f64; 3]>,
    corner_verts: Vec<u32>,
    face_sizes: Vec<u32>,
}

/// A closed surface of revolution about z from rings `(z, radius)` (first and last are the
/// poles, radius 0): `n` vertices per ring, each ring turned half a step from the previous one
/// (an antiprism triangulation, so no ring of edges is where a level set of faces would fall).
fn revolve(rings: &[(f64, f64)], n: usize) -> Mesh {
    let mut positions = vec![[0.0, 0.0, rings[0].0]];
    let inner = &rings[1..rings.len() - 1];
    for (j, &(z, r)) in inner.iter().enumerate() {
        for k in 0..n {
            let a = TAU * (k as f64 + 0.5 * j as f64) / n as f64;
            positions.push([r * a.cos(), r * a.sin(), z]);
        }
    }
    positions.push([0.0, 0.0, rings[rings.len() - 1].0]);
    let top = (positions.len() - 1) as u32;
    let id = |j: usize, k: usize| (1 + j * n + k % n) as u32;
    let mut cv = Vec::new();
    for k in 0..n {
        cv.extend([0, id(0, k + 1), id(0, k)]);
    }
    for j in 0..inner.len() - 1 {
        for k in 0..n {
            cv.extend([id(j, k), id(j, k + 1), id(j + 1, k)]);
            cv.extend([id(j, k + 1), id(j + 1, k + 1), id(j + 1, k)]);
        }
    }
    let last = inner.len() - 1;
    for k in 0..n {
        cv.extend([id(last, k), id(last, k + 1), top]);
    }
    let face_sizes = vec![3; cv.len() / 3];
    Mesh { positions, corner_verts: cv, face_sizes }
}

/// Rings of a capsule: hemispherical caps of radius `radius(0)` and `radius(length)` joined by
/// a tube of radius `radius(z)`, `z ∈ [0, length]`, rings about `step` apart.
fn capsule_rings(length: f64, step: f64, radius: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    let (r0, r1) = (radius(0.0), radius(length));
    let cap = |r: f64| ((0.5 * PI * r / step).round() as usize).max(2);
    let mut rings = Vec::new();
    let m0 = cap(r0);
    for i in 0..m0 {
        let phi = 0.5 * PI * i as f64 / m0 as f64;
        rings.push((-r0 * phi.cos(), r0 * phi.sin()));
    }
    let m = (length / step).round() as usize;
    for i in 0..=m {
        let z = length * i as f64 / m as f64;
        rings.push((z, radius(z)));
    }
    let m1 = cap(r1);
    for i in (0..m1).rev() {
        let phi = 0.5 * PI * i as f64 / m1 as f64;
        rings.push((length + r1 * phi.cos(), r1 * phi.sin()));
    }
    rings
}

struct Outcome {
    /// Seam edges as position pairs.
    seam: Vec<[[f64; 3]; 2]>,
    length: f64,
    split: split::Split,
    /// Vertices of the seam whose seam degree is not 2.
    odd_vertices: usize,
    /// Connected pieces of the seam graph.
    seam_components: usize,
}

fn halve(m: &Mesh) -> Outcome {
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let chart = &charts[0];
    let graph = ChartGraph::new(&mesh, chart);
    let avoid = vec![false; m.positions.len()];
    let cost = cuts::edge_costs(&mesh, &graph, chart, &AutoSeamOptions::default(), &avoid);
    let split = split::spectral_halve(&graph, &cost, chart).expect("the spectral split works on a tube");
    // The pipeline's entry point gives the same seams.
    assert_eq!(split::halve(&graph, &cost, chart, &avoid), split.seams);
    let mut degree = std::collections::BTreeMap::<u32, usize>::new();
    let mut seam = Vec::new();
    let mut length = 0.0;
    let mut uf: Vec<usize> = (0..chart.positions.len()).collect();
    fn find(uf: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while uf[r] != r {
            r = uf[r];
        }
        uf[x] = r;
        r
    }
    for &e in &split.edges {
        let [a, b] = graph.edges[e as usize];
        *degree.entry(a).or_default() += 1;
        *degree.entry(b).or_default() += 1;
        let (pa, pb) = (chart.positions[a as usize], chart.positions[b as usize]);
        length += graph.length[e as usize];
        seam.push([pa, pb]);
        let (ra, rb) = (find(&mut uf, a as usize), find(&mut uf, b as usize));
        uf[ra] = rb;
    }
    let odd_vertices = degree.values().filter(|&&d| d != 2).count();
    let mut roots: Vec<usize> = degree.keys().map(|&v| find(&mut uf, v as usize)).collect();
    roots.sort_unstable();
    roots.dedup();
    // Rebuilt with the seams, the chart falls in two parts.
    let halves = build_charts(&mesh, &split.seams, None);
    assert_eq!(halves.len(), split.parts);
    Outcome { seam, length, split, odd_vertices, seam_components: roots.len() }
}

fn check_loop(name: &str, o: &Outcome, circumference: f64) {
    assert_eq!(o.odd_vertices, 0, "{name}: the seam has vertices of degree ≠ 2 (a zig-zag or a branch)");
    assert_eq!(o.seam_components, 1, "{name}: the seam is not one loop");
    assert_eq!(o.split.parts, 2, "{name}: {} parts", o.split.parts);
    assert!(
        o.length <= 1.3 * circumference,
        "{name}: seam of length {:.3} for a circumference of {:.3} (ratio {:.3})",
        o.length,
        circumference,
        o.length / circumference
    );
    assert!((o.split.area_share - 0.5).abs() <= 0.1 + 1e-9, "{name}: area share {:.3}", o.split.area_share);
}

#[test]
fn a_capsule_is_halved_along_a_loop_around_it() {
    let (length, n) = (8.0, 32);
    let step = TAU / n as f64 * 0.87;
    let m = revolve(&capsule_rings(length, step, |_| 1.0), n);
    let o = halve(&m);
    // The exact ring would be the inscribed polygon; 2π bounds it from above.
    check_loop("capsule", &o, TAU);
    // Around the middle of the tube, not on a cap.
    for [a, b] in &o.seam {
        assert!(a[2] > 0.5 && b[2] < length - 0.5, "seam edge {a:?}–{b:?} is not on the tube");
    }
    // The loop runs around the tube: its edges are nearly horizontal (a staircase climbs).
    let rise: f64 = o.seam.iter().map(|[a, b]| (a[2] - b[2]).abs()).sum();
    assert!(rise < 0.1 * o.length, "the seam climbs {rise:.3} over a length {:.3}", o.length);
}

#[test]
fn a_bumpy_tube_is_halved_near_a_waist_with_a_loop_no_longer_than_its_circumference_there() {
    let (length, n) = (10.0, 40);
    let radius = |z: f64| 1.0 + 0.3 * (TAU * z / 2.5).sin();
    let step = TAU / n as f64 * 0.8;
    let m = revolve(&capsule_rings(length, step, radius), n);
    let o = halve(&m);
    let mean_z = o.seam.iter().map(|[a, b]| a[2] + b[2]).sum::<f64>() / (2 * o.seam.len()) as f64;
    check_loop("bumpy tube", &o, TAU * radius(mean_z));
    // The band around the half-area level holds a waist (radius 0.7, near z = 4.375): the
    // cheapest loop is the waist's, not the one at the half-area level (radius 1 at z = 5).
    assert!(o.length < 1.15 * TAU * 0.7, "length {:.3} at z ≈ {mean_z:.3}", o.length);
}

#[test]
fn a_hairpin_tube_is_halved_across_the_bend_not_across_both_arms() {
    // A capsule bent into a hairpin: two straight arms of length 8 joined by a half circle of
    // radius 2. A plane across the principal axis (along the arms) would cut both arms; the
    // Fiedler vector runs along the tube, and the half-area loop goes around the bend.
    let (arm, bend, n) = (8.0, 2.0, 32);
    let length = 2.0 * arm + PI * bend;
    let step = TAU / n as f64 * 0.87;
    let mut m = revolve(&capsule_rings(length, step, |_| 1.0), n);
    for p in &mut m.positions {
        let [x, y, z] = *p;
        let s = z.clamp(0.0, length);
        let a = ((s - arm) / bend).clamp(0.0, PI);
        let c = if s < arm {
            [bend, s - arm, 0.0]
        } else if s <= arm + PI * bend {
            [bend * a.cos(), bend * a.sin(), 0.0]
        } else {
            [-bend, -(s - arm - PI * bend), 0.0]
        };
        let (t, nrm) = ([-a.sin(), a.cos(), 0.0], [a.cos(), a.sin(), 0.0]);
        let along = z - s;
        *p = [
            c[0] + along * t[0] + x * nrm[0],
            c[1] + along * t[1] + x * nrm[1],
            c[2] + along * t[2] + x * nrm[2] - y,
        ];
    }
    let o = halve(&m);
    check_loop("hairpin", &o, TAU);
    // Every seam vertex lies in the bend (y > 0; the arms are at y ≤ 0), within the band about
    // its middle: a fifth of the area is about 4.5 of the tube's length, ±0.36π of the bend.
    for [a, b] in &o.seam {
        for p in [a, b] {
            let angle = p[1].atan2(p[0]);
            assert!(p[1] > 0.0 && (angle - 0.5 * PI).abs() < 0.4 * PI, "seam vertex {p:?} at angle {angle:.3}");
        }
    }
}

#[test]
fn the_split_is_identical_across_thread_counts() {
    let m = revolve(&capsule_rings(6.0, 0.2, |z| 1.0 + 0.2 * z.sin()), 24);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| halve(&m).split.seams)
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn a_long_fine_tube_is_halved_along_a_loop_in_its_narrowed_band() {
    // 275k triangles: more than five times `split::BAND_POLYGONS` polygons, so the band around
    // each level holds about that many instead of a fifth of the tube.
    let (length, n) = (60.0, 112);
    let step = TAU / n as f64 * 0.87;
    let m = revolve(&capsule_rings(length, step, |_| 1.0), n);
    assert!(m.face_sizes.len() > 5 * split::BAND_POLYGONS, "{} triangles", m.face_sizes.len());
    let o = halve(&m);
    check_loop("long tube", &o, TAU);
    let rise: f64 = o.seam.iter().map(|[a, b]| (a[2] - b[2]).abs()).sum();
    assert!(rise < 0.1 * o.length, "the seam climbs {rise:.3} over a length {:.3}", o.length);
}

#[test]
fn a_split_on_the_proxy_fiedler_vector_is_a_loop_around_the_tube() {
    let (length, n) = (8.0, 32);
    let step = TAU / n as f64 * 0.87;
    let m = revolve(&capsule_rings(length, step, |z| 1.0 + 0.1 * (z * 0.7).sin()), n);
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = build_charts(&mesh, &[], None).remove(0);
    let avoid = vec![false; m.positions.len()];
    let options = AutoSeamOptions::default();
    let proxy = cuts::coarse::Proxy::with_target(&chart, chart.positions.len() / 4).unwrap();
    let cutter = cuts::ChartCutter::new(&mesh, &chart, &options, &avoid).with_proxy(proxy);
    let seams = cutter.split_candidates(&avoid, false).remove(0);
    // One loop: every seam vertex has two seam edges, and the seam is connected.
    let mut degree = std::collections::BTreeMap::<u32, usize>::new();
    let mut length = 0.0;
    for &[a, b] in &seams {
        *degree.entry(a).or_default() += 1;
        *degree.entry(b).or_default() += 1;
        let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
        length += ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2) + (pa[2] - pb[2]).powi(2)).sqrt();
    }
    assert!(degree.values().all(|&d| d == 2), "the seam is not a loop: {degree:?}");
    assert!(length <= 1.3 * TAU * 1.1, "seam length {length:.3}");
    let halves = build_charts(&mesh, &seams, None);
    assert_eq!(halves.len(), 2);
    let area = |c: &uvflat_core::charts::Chart| -> f64 {
        c.triangles
            .iter()
            .map(|t| {
                let [a, b, d] = t.map(|v| c.positions[v as usize]);
                let (e, f) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [d[0] - a[0], d[1] - a[1], d[2] - a[2]]);
                let x = [e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]];
                0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
            })
            .sum()
    };
    let (a0, a1) = (area(&halves[0]), area(&halves[1]));
    let share = a0 / (a0 + a1);
    assert!((share - 0.5).abs() <= 0.1 + 1e-9, "area share {share:.3}");
}

/// Parts ([`uvflat_core::pipeline::parts`]) are halved by triangles, not area, prefer a
/// level that leaves no side of `max_triangles` or more, and then a balanced one
/// ([`split::BALANCED_SHARE`]): on a tube with a narrow waist at a fifth of its triangles, the
/// cheapest loop is the waist (the pipeline's split takes it); with no limit, that loop leaves
/// an unbalanced side, and with a limit of 0.65 of the triangles a side too large: either way
/// the tube is halved near its middle, along one loop. The tube's rings are twice as dense on
/// one half, so its middle by triangles is not its middle by area.
#[test]
fn parts_are_halved_by_triangles_and_leave_no_side_over_the_limit() {
    let (length, n) = (12.0, 32);
    let waist = |z: f64| 1.0 - 0.6 * (-((z - 0.3 * length) / 0.6).powi(2)).exp();
    let mut rings = capsule_rings(length, TAU / n as f64 * 0.87, waist);
    // Twice the rings on the far half (by z): a ring between each pair there.
    let mut dense = Vec::new();
    for w in rings.windows(2) {
        dense.push(w[0]);
        if w[0].0 > 0.5 * length && w[1].0 <= length {
            dense.push((0.5 * (w[0].0 + w[1].0), waist(0.5 * (w[0].0 + w[1].0))));
        }
    }
    dense.push(*rings.last().unwrap());
    rings = dense;
    let m = revolve(&rings, n);
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = build_charts(&mesh, &[], None).remove(0);
    let graph = ChartGraph::new(&mesh, &chart);
    let avoid = vec![false; m.positions.len()];
    let cost = cuts::edge_costs(&mesh, &graph, &chart, &AutoSeamOptions::default(), &avoid);
    let f = cuts::fiedler::fiedler_vector(&chart).expect("a tube has a Fiedler vector");
    let total = chart.triangles.len();
    // Triangles of each piece the seams leave.
    let sides = |seams: &[[u32; 2]]| -> Vec<usize> {
        build_charts(&mesh, seams, None).iter().map(|c| c.triangles.len()).collect()
    };
    // The pipeline's split: the waist, the cheapest loop.
    let area_split = split::spectral_halve(&graph, &cost, &chart).expect("the area split works on a tube");
    let area_tris = sides(&area_split.seams);
    assert_eq!(area_tris.len(), 2, "{area_tris:?}");
    let small = *area_tris.iter().min().unwrap() as f64 / total as f64;
    assert!(small < 0.3, "the split is not at the waist: sides {area_tris:?}");
    // No limit: the waist leaves an unbalanced side; the parts are balanced.
    let free = split::halve_into_parts(&graph, &cost, &chart, &avoid, &f, usize::MAX);
    let tris = sides(&free);
    assert_eq!(tris.len(), 2, "{tris:?}");
    let large = *tris.iter().max().unwrap() as f64 / total as f64;
    assert!(large <= split::BALANCED_SHARE, "parts without a limit are not balanced: sides {tris:?}");
    // A limit of 0.65 of the triangles: no side at or over it, one loop around the tube.
    let limit = (0.65 * total as f64) as usize;
    let parts = split::halve_into_parts(&graph, &cost, &chart, &avoid, &f, limit);
    let tris = sides(&parts);
    assert_eq!(tris.len(), 2, "{tris:?}");
    assert!(tris.iter().all(|&t| t < limit), "a side of {tris:?} holds {limit} triangles or more");
    let mut degree = std::collections::BTreeMap::<u32, usize>::new();
    for &[a, b] in &parts {
        *degree.entry(a).or_default() += 1;
        *degree.entry(b).or_default() += 1;
    }
    assert!(degree.values().all(|&d| d == 2), "the seam is not a loop: {degree:?}");
    // Halved by triangles: near the middle of the triangles, far from the middle of the area
    // (the dense half holds two thirds of the triangles on half the length).
    let share = tris[0] as f64 / total as f64;
    assert!((share - 0.5).abs() <= 0.1 + 1e-9, "triangle share {share:.3}: {tris:?}");
    let area_share = area_tris[0] as f64 / total as f64;
    assert!((area_share - 0.5).abs() > (share - 0.5).abs(), "by area {area_tris:?}, by triangles {tris:?}");
}
