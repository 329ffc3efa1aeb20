//! Small holes are filled for the unwrap and joined to the outline by closed seams after it
//! (`pipeline/fill.rs`): the islands are disks that keep the rule, every join's two sides
//! have the same UVs, the avoided vertices are never joined through, and a hole that cannot
//! be joined leaves the mesh unwrapped as it is.

mod common;

use std::collections::HashMap;

use common::{assert_islands_keep_the_rule, sphere, with_holes, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::pipeline::fill::join_holes;
use uvflat_core::{unwrap, Method, UnwrapOptions, Unwrapped};

/// New seam edges whose two faces lie in one island, and whether each has the same UVs on both
/// sides (a closed seam; an open cut inside an island has its sides apart).
fn joins(s: &Soup, r: &Unwrapped) -> Vec<bool> {
    // Every corner of every face, by (face, vertex).
    let mut corner_of: HashMap<(usize, u32), usize> = HashMap::new();
    let mut faces_of_edge: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    let mut at = 0usize;
    for (f, &n) in s.face_sizes.iter().enumerate() {
        let c = &s.corner_verts[at..at + n as usize];
        for i in 0..c.len() {
            corner_of.insert((f, c[i]), at + i);
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            faces_of_edge.entry([a.min(b), a.max(b)]).or_default().push(f);
        }
        at += n as usize;
    }
    r.new_seams
        .iter()
        .filter_map(|e| {
            let faces = faces_of_edge.get(e)?;
            if faces.len() != 2 || r.face_chart[faces[0]] != r.face_chart[faces[1]] {
                return None;
            }
            Some(e.iter().all(|&v| r.uv[corner_of[&(faces[0], v)]] == r.uv[corner_of[&(faces[1], v)]]))
        })
        .collect()
}

#[test]
fn a_cap_with_small_holes_is_one_island_whose_holes_are_joined_by_closed_seams() {
    // A hemisphere with 6 holes of 12 faces: SLIM keeps the rule on the hemisphere whole.
    let s = with_holes(&sphere(64, 64, |c| c[2] > 0.0), 6, 12, 7);
    for method in [Method::Slim(Default::default()), Method::Abf(Default::default())] {
        let name = method.name();
        let r = unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }).unwrap();
        assert_islands_keep_the_rule(&s, name, &r);
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        // Holes that touch another at a vertex are one loop through it, cut open as before.
        let chart = &build_charts(&mesh, &[], None)[0];
        let simple = |l: &Vec<u32>| {
            let mut v: Vec<u32> = l.iter().map(|&x| chart.mesh_vertex[x as usize]).collect();
            v.sort_unstable();
            v.dedup();
            v.len() == l.len()
        };
        let holes = chart.boundary_loops.iter().filter(|l| simple(l)).count() - 1;
        assert!(holes >= 4, "{holes} holes");
        assert_eq!(r.phases.holes_filled, holes, "{name}: {:?}", r.phases);
        assert_eq!(r.phases.fill_undone, 0.0, "{name}");
        assert_eq!(r.charts.len(), 1, "{name}: {} islands", r.charts.len());
        // Each hole is joined by a path of edges inside the island, both sides at the same UVs.
        let closed = joins(&s, &r).into_iter().filter(|&c| c).count();
        assert!(closed >= holes, "{name}: {closed} closed seam edges for {holes} holes");
        // The closed seams reported are those, and new seams.
        assert_eq!(r.closed_seams.len(), closed, "{name}");
        assert!(r.closed_seams.iter().all(|e| r.new_seams.binary_search(e).is_ok()), "{name}");
        // The seams are the islands' borders: none lies along a hole.
        assert!(r.charts[0].cut_length > 0.0);
    }
}

#[test]
fn joins_never_pass_through_an_avoided_vertex_and_a_hole_walled_in_by_them_is_not_joined() {
    let s = with_holes(&sphere(32, 32, |c| c[2] > 0.0), 2, 6, 5);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    assert!(chart.boundary_loops.len() >= 3, "{} loops", chart.boundary_loops.len());
    // The UVs of a flat projection: the rim is the loop of largest area.
    let uv: Vec<[f64; 2]> = chart.positions.iter().map(|p| [p[0], p[1]]).collect();
    let free = vec![false; s.positions.len()];
    let paths = join_holes(&mesh, chart, &uv, &free).expect("two holes joined");
    assert!(!paths.is_empty());
    // Every vertex of the smallest hole avoided but one: the join ends there.
    let hole = &chart.boundary_loops.iter().min_by_key(|l| l.len()).unwrap().clone();
    let on_hole: Vec<u32> = hole.iter().map(|&v| chart.mesh_vertex[v as usize]).collect();
    let mut avoid = vec![false; s.positions.len()];
    for &v in &on_hole[1..] {
        avoid[v as usize] = true;
    }
    let paths = join_holes(&mesh, chart, &uv, &avoid).expect("a way to the one vertex left");
    assert!(paths.iter().flatten().all(|&v| !avoid[v as usize]), "a join touches an avoided vertex");
    assert!(paths.iter().flatten().any(|&v| v == on_hole[0]), "the hole is not joined at its one vertex left");
    // Walled in on every side (its own vertices avoided): no join.
    let mut walled = vec![false; s.positions.len()];
    for &v in &on_hole {
        walled[v as usize] = true;
    }
    assert!(join_holes(&mesh, chart, &uv, &walled).is_none());
    // Through `unwrap`: the fill is undone, the hole cut open as without it, the rule kept.
    let mut options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    options.auto_seams.avoid_vertices = on_hole.clone();
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.phases.fill_undone > 0.0 && r.phases.holes_filled == 0, "{:?}", r.phases);
    assert!(r.charts.iter().all(|c| c.status.mapped()));
}

#[test]
fn no_hole_is_filled_with_automatic_seams_off_or_pins_or_a_fixed_outline() {
    let s = with_holes(&sphere(32, 32, |c| c[2] > 0.0), 2, 6, 5);
    let mut off = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    off.auto_seams.enabled = false;
    let r = unwrap(&s.input(), &off).unwrap();
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let loops = build_charts(&mesh, &[], None)[0].boundary_loops.len();
    assert!(loops >= 2);
    assert_eq!((r.phases.holes_filled, r.charts.len(), r.charts[0].boundary_loops), (0, 1, loops));
    let pins = [(0u32, [0.0, 0.0]), (5u32, [1.0, 0.0])];
    let pinned = uvflat_core::MeshInput { pins: &pins, ..s.input() };
    let r = unwrap(&pinned, &UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() }).unwrap();
    assert_eq!(r.phases.holes_filled, 0);
    let tutte = UnwrapOptions { method: Method::parse("tutte", &[]).unwrap(), ..Default::default() };
    let r = unwrap(&s.input(), &tutte).unwrap();
    assert_eq!(r.phases.holes_filled, 0);
}

#[test]
fn holes_are_filled_with_render_triangles_given_as_the_add_on_gives_them() {
    let s = with_holes(&sphere(48, 48, |c| c[2] > 0.0), 4, 10, 11);
    // Blender's split of every face: a fan from its first corner.
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut at = 0u32;
    for &n in &s.face_sizes {
        for k in 1..n - 1 {
            triangles.push([at, at + k, at + k + 1]);
        }
        at += n;
    }
    let input = uvflat_core::MeshInput { triangles: &triangles, ..s.input() };
    let options = UnwrapOptions { method: Method::Slim(Default::default()), ..Default::default() };
    let r = unwrap(&input, &options).unwrap();
    assert!(r.phases.holes_filled >= 3, "{:?}", r.phases);
    assert_eq!(r.phases.fill_undone, 0.0);
    assert_eq!(r.uv.len(), s.corner_verts.len());
    assert_eq!(r.face_chart.len(), s.face_sizes.len());
    assert_islands_keep_the_rule(&s, "slim", &r);
}
