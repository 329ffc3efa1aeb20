//! Seam costs prefer where an artist hides seams: concave creases over convex ones, hidden
//! surface (ambient occlusion) over exposed surface.
//!
//! The test surface is a closed box whose top (a 40 × 40 quad grid over [−2, 2]²) holds a
//! flat-bottomed trench along y = +0.6 and a flat-topped mesa along y = −0.6, each 2 long with
//! ramps at its ends. The mesa is the trench turned over (the map (x, y, z) ↦ (x, −y, −z) is an
//! isometry), so a path along the trench's floor and its image along the mesa's top have the
//! same length; the trench is made a little deeper (0.65) than the mesa is high (0.6), so by
//! length alone the mesa route is the shorter one.

mod common;

use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{self, cut_graph, visibility, AutoSeamOptions, ChartGraph};
use uvflat_core::mesh::PolyMesh;

const N: usize = 40;
const STEP: f64 = 0.1;
const TRENCH_DEPTH: f64 = 0.65;
const MESA_HEIGHT: f64 = 0.6;

struct Mesh {
    positions: Vec<[f64; 3]>,
    corner_verts: Vec<u32>,
    face_sizes: Vec<u32>,
}

/// 1 on |t| ≤ 0.25, 0 from |t| ≥ 0.35, linear between (steep walls two grid steps high).
fn plateau(t: f64) -> f64 {
    ((0.35 - t.abs()) / 0.1).clamp(0.0, 1.0)
}

/// 1 on |x| ≤ 1, 0 from |x| ≥ 1.4, linear between (the ramps at the ends).
fn along(x: f64) -> f64 {
    ((1.4 - x.abs()) / 0.4).clamp(0.0, 1.0)
}

fn height(x: f64, y: f64) -> f64 {
    along(x) * (MESA_HEIGHT * plateau(y + 0.6) - TRENCH_DEPTH * plateau(y - 0.6))
}

fn coord(i: usize) -> f64 {
    -2.0 + i as f64 * STEP
}

/// The closed box: top grid (vertex `i + j (N + 1)`), flat bottom grid at z = −1.5, walls.
fn box_with_trench_and_mesa() -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=N {
        for i in 0..=N {
            positions.push([coord(i), coord(j), height(coord(i), coord(j))]);
        }
    }
    for j in 0..=N {
        for i in 0..=N {
            positions.push([coord(i), coord(j), -1.5]);
        }
    }
    let top = |i: usize, j: usize| (j * (N + 1) + i) as u32;
    let bottom = |i: usize, j: usize| ((N + 1) * (N + 1) + j * (N + 1) + i) as u32;
    let mut faces: Vec<[u32; 4]> = Vec::new();
    for j in 0..N {
        for i in 0..N {
            faces.push([top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1)]);
            faces.push([bottom(i, j), bottom(i, j + 1), bottom(i + 1, j + 1), bottom(i + 1, j)]);
        }
    }
    // Walls: for every boundary edge u → v of the top (as its face runs it), the quad
    // (u, u below, v below, v) runs it the other way.
    let below = |v: u32| v + ((N + 1) * (N + 1)) as u32;
    let ring: Vec<(usize, usize)> = (0..N)
        .map(|i| (i, 0))
        .chain((0..N).map(|j| (N, j)))
        .chain((0..N).map(|i| (N - i, N)))
        .chain((0..N).map(|j| (0, N - j)))
        .collect();
    for k in 0..ring.len() {
        let (u, v) = (ring[k], ring[(k + 1) % ring.len()]);
        let (u, v) = (top(u.0, u.1), top(v.0, v.1));
        faces.push([u, below(u), below(v), v]);
    }
    let corner_verts = faces.iter().flatten().copied().collect();
    let face_sizes = vec![4; faces.len()];
    Mesh { positions, corner_verts, face_sizes }
}

/// Top vertex nearest (x, y).
fn top_vertex(x: f64, y: f64) -> u32 {
    let i = ((x + 2.0) / STEP).round() as usize;
    let j = ((y + 2.0) / STEP).round() as usize;
    (j * (N + 1) + i) as u32
}

/// The cut joining two cones at (∓1.7, 0) with seams kept off the top between |x| ≤ 1.5 except
/// along the middle of the trench's floor and of the mesa's top, and off the bottom: the two
/// ways round are along the trench or along the mesa. Returns the cut's top vertices.
fn cut_between_cones(options: &AutoSeamOptions) -> Vec<[f64; 3]> {
    let m = box_with_trench_and_mesa();
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let chart = &charts[0];
    assert!(chart.boundary_loops.is_empty(), "the box is closed");
    let avoid: Vec<bool> = m
        .positions
        .iter()
        .enumerate()
        .map(|(v, p)| {
            let on_top = v < (N + 1) * (N + 1);
            let corridor = (p[1] - 0.6).abs() <= 0.1 + 1e-9 || (p[1] + 0.6).abs() <= 0.1 + 1e-9;
            !on_top || (p[0].abs() <= 1.5 + 1e-9 && !corridor)
        })
        .collect();
    let graph = ChartGraph::new(&mesh, chart);
    let cost = cuts::edge_costs(&mesh, &graph, chart, options, &avoid);
    let chart_vertex = |mesh_v: u32| chart.mesh_vertex.iter().position(|&m| m == mesh_v).unwrap() as u32;
    let cones = [chart_vertex(top_vertex(-1.7, 0.0)), chart_vertex(top_vertex(1.7, 0.0))];
    let cut = cut_graph::join_and_prune(&graph, &cost, vec![false; graph.edges.len()], &cones, &[]);
    let mut out = Vec::new();
    for (e, &c) in cut.iter().enumerate() {
        if c {
            for v in graph.edges[e] {
                out.push(chart.positions[v as usize]);
            }
        }
    }
    assert!(!out.is_empty(), "no cut");
    out
}

/// Which side the cut passes the middle by: +1 the trench, −1 the mesa.
fn side(cut: &[[f64; 3]]) -> i32 {
    let middle: Vec<&[f64; 3]> = cut.iter().filter(|p| p[0].abs() <= 1.0).collect();
    assert!(!middle.is_empty());
    let trench = middle.iter().all(|p| p[1] > 0.0);
    let mesa = middle.iter().all(|p| p[1] < 0.0);
    assert!(trench || mesa, "the cut runs both ways");
    if trench {
        1
    } else {
        -1
    }
}

#[test]
fn by_length_alone_the_cut_runs_over_the_mesa() {
    // The control: the trench route is the longer one, so the next test's result comes from
    // the visibility term, not from the geometry.
    let o = AutoSeamOptions { visibility_weight: 0.0, ..Default::default() };
    assert_eq!(side(&cut_between_cones(&o)), -1);
}

#[test]
fn with_visibility_the_cut_hides_in_the_trench() {
    assert_eq!(side(&cut_between_cones(&AutoSeamOptions::default())), 1);
}

#[test]
fn concave_creases_are_cheaper_than_convex_ones() {
    let m = box_with_trench_and_mesa();
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    let graph = ChartGraph::new(&mesh, chart);
    let avoid = vec![false; m.positions.len()];
    let o = AutoSeamOptions { visibility_weight: 0.0, ..Default::default() };
    let cost = cuts::edge_costs(&mesh, &graph, chart, &o, &avoid);
    // Edges along x at |x| < 0.9 on the rows where a wall meets the floor (y = +0.4) or the
    // trench's rim (y = +0.2), and their images on the mesa (y = −0.4, y = −0.2).
    let row = |y: f64| -> Vec<usize> {
        (0..graph.edges.len())
            .filter(|&e| {
                let [a, b] = graph.edges[e];
                let (pa, pb) = (chart.positions[a as usize], chart.positions[b as usize]);
                let on_top = pa[2] > -1.0 && pb[2] > -1.0;
                on_top && (pa[1] - y).abs() < 1e-9 && (pb[1] - y).abs() < 1e-9 && pa[0].abs() < 0.9 && pb[0].abs() < 0.9
            })
            .collect()
    };
    let (floor, rim, mesa_foot, mesa_edge) = (row(0.4), row(0.2), row(-0.2), row(-0.4));
    assert!(floor.len() >= 16 && rim.len() >= 16 && mesa_foot.len() >= 16 && mesa_edge.len() >= 16);
    for &e in floor.iter().chain(&mesa_foot) {
        assert!(graph.concave[e], "edge {e} at the foot of a wall should be concave");
    }
    for &e in rim.iter().chain(&mesa_edge) {
        assert!(!graph.concave[e], "edge {e} at the top of a wall should be convex");
    }
    // Same length (0.1), about the same dihedral angle (73° and 72°) on each pair: the concave
    // one costs much less.
    for (&c, &v) in floor.iter().zip(&mesa_edge) {
        assert!((graph.length[c] - graph.length[v]).abs() < 1e-12);
        assert!(cost[c] < 0.75 * cost[v], "concave {} vs convex {}", cost[c], cost[v]);
        assert!(cost[v] < graph.length[v], "a sharp convex edge is cheaper than flat surface");
    }
}

/// Ambient occlusion of the box's vertices.
fn box_occlusion() -> (Mesh, Vec<f64>) {
    let m = box_with_trench_and_mesa();
    let triangles: Vec<[u32; 3]> = m.corner_verts.chunks(4).flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    let ao = visibility::ambient_occlusion(&m.positions, &triangles, visibility::RAYS, 1.8);
    (m, ao)
}

#[test]
fn the_floor_of_a_deep_trench_is_occluded_and_a_convex_top_is_not() {
    let (_, ao) = box_occlusion();
    let floor = ao[top_vertex(0.0, 0.6) as usize];
    let mesa = ao[top_vertex(0.0, -0.6) as usize];
    let plain = ao[top_vertex(0.0, -1.8) as usize];
    // Nothing rises above the mesa's top: no ray is blocked. (The plain beside the mesa sees
    // the mesa low on its horizon.)
    assert_eq!(mesa, 0.0);
    // A slot of depth d and half-width w lets through sin(atan(w/d)) of cosine-weighted light:
    // 0.47 with the trench's rim (w = 0.35, d = 0.65), less with its floor (w = 0.25). Its ends
    // are 1 to 1.4 away and let a little more through.
    let bound = 1.0 - (0.35f64 / 0.65).atan().sin();
    assert!(floor > bound - 0.15, "floor occlusion {floor:.3} (slot bound {bound:.3})");
    assert!(floor > mesa && floor > plain);
    // A vertex in the middle of a wall sees half the sky at most.
    let wall = ao[top_vertex(0.0, 0.3) as usize];
    assert!(wall > 0.0 && wall < floor + 1e-12, "wall {wall:.3}, floor {floor:.3}");
}

#[test]
fn occlusion_is_identical_across_thread_counts() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| box_occlusion().1)
    };
    let (a, b) = (run(1), run(2));
    assert!(a.iter().any(|&x| x > 0.0));
    assert_eq!(a, b);
}

#[test]
fn visibility_from_grid_samples_follows_the_rays_of_every_vertex() {
    let m = box_with_trench_and_mesa();
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    let chart = charts.iter().max_by_key(|c| c.faces.len()).unwrap();
    let inward = visibility::wound_inward(&mesh);
    let full = visibility::chart_visibility_sampled(&mesh, chart, inward, usize::MAX);
    let n = chart.positions.len();
    let sampled = visibility::chart_visibility_sampled(&mesh, chart, inward, n / 6);
    assert_ne!(full, sampled, "the chart has {n} vertices: it must have been sampled");
    let mean_diff = full.iter().zip(&sampled).map(|(a, b)| (a - b).abs()).sum::<f64>() / n as f64;
    assert!(mean_diff < 0.05, "mean |difference| {mean_diff:.3}");
    // The trench's floor stays hidden and the mesa's top exposed.
    let at = |x: f64, y: f64| {
        let v = top_vertex(x, y);
        chart.mesh_vertex.iter().position(|&w| w == v).unwrap()
    };
    assert!(sampled[at(0.0, 0.6)] < 0.75, "trench floor {:.3}", sampled[at(0.0, 0.6)]);
    assert!(sampled[at(0.0, -0.6)] > 0.95, "mesa top {:.3}", sampled[at(0.0, -0.6)]);
    // Below the cap every vertex casts its own rays.
    assert_eq!(visibility::chart_visibility_sampled(&mesh, chart, inward, n), full);
}

#[test]
fn visibility_weight_is_validated() {
    for bad in [-1.0, f64::NAN, f64::INFINITY, 1000.0] {
        let o = AutoSeamOptions { visibility_weight: bad, ..Default::default() };
        let err = o.validate(10).unwrap_err().to_string();
        assert!(err.contains("visibility_weight"), "{err}");
    }
    assert!(AutoSeamOptions { visibility_weight: 0.0, ..Default::default() }.validate(10).is_ok());
}


/// Not a check: prints the time of the occlusion rays and of the whole edge cost on
/// camelhead.off (if ../shared/meshes is there) and on a generated torus of 100,000 triangles
/// (`cargo test --release --test seam_cost -- --ignored --nocapture`).
#[test]
#[ignore]
fn print_visibility_time() {
    let mut meshes: Vec<(String, common::Soup)> = Vec::new();
    if let Some(dir) = common::shared_meshes() {
        meshes.push(("camelhead.off".into(), common::load(&dir.join("camelhead.off"))));
    }
    // A bumpy torus: 250 × 200 quads split in two.
    let (nu, nv) = (250usize, 200usize);
    let mut positions = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (i as f64 / nu as f64 * std::f64::consts::TAU, j as f64 / nv as f64 * std::f64::consts::TAU);
            let r = 0.6 * (1.0 + 0.15 * (7.0 * a).sin() * (3.0 * b).cos());
            let big = 2.0 + r * b.cos();
            positions.push([big * a.cos(), big * a.sin(), r * b.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((j % nv) * nu + (i % nu)) as u32;
    let mut corner_verts = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            corner_verts.extend([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let face_sizes = vec![3; corner_verts.len() / 3];
    meshes.push(("torus 100k".into(), common::Soup { positions, corner_verts, face_sizes }));
    for (name, s) in &meshes {
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let charts = build_charts(&mesh, &[], None);
        let chart = charts.iter().max_by_key(|c| c.faces.len()).unwrap();
        let graph = ChartGraph::new(&mesh, chart);
        let avoid = vec![false; s.positions.len()];
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let t = std::time::Instant::now();
                let vis = visibility::chart_visibility(&mesh, chart, visibility::wound_inward(&mesh));
                let rays = t.elapsed().as_secs_f64();
                let t = std::time::Instant::now();
                let off = AutoSeamOptions { visibility_weight: 0.0, ..Default::default() };
                let _ = cuts::edge_costs(&mesh, &graph, chart, &off, &avoid);
                let plain = t.elapsed().as_secs_f64();
                let t = std::time::Instant::now();
                let _ = cuts::edge_costs(&mesh, &graph, chart, &AutoSeamOptions::default(), &avoid);
                let full = t.elapsed().as_secs_f64();
                let mean = vis.iter().sum::<f64>() / vis.len() as f64;
                println!(
                    "{name}: {} vertices, {} triangles, {threads} thread(s): occlusion {rays:.3} s, costs without {plain:.3} s, with {full:.3} s (mean visibility {mean:.3})",
                    chart.positions.len(),
                    chart.triangles.len()
                );
            });
        }
    }
}
