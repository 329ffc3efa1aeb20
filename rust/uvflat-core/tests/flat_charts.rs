//! Flat charts laid as they are (`methods/planar.rs`): a perforated plate, its holes joined to
//! the outline by automatic seams, comes out as one island that keeps every angle and length,
//! the two sides of every cut on each other, under every free-boundary method, even where a
//! face holds a sliver no triangulation avoids (a corner 1e-7 from the next, as a boolean
//! leaves where its cutter touches a grid line). Charts that are not flat, or whose flat map
//! would hold a triangle without area, are solved by the method as before. A flat chart laid
//! so is reported solved by the method, with 0 iterations and no note: the map is the method's
//! own optimum. A flat chart with a crack (a T-junction on its outline, as where a glyph's
//! contours touch) is laid closed and kept as one island: its sides touch at one surface point.

use uvflat_core::methods::planar;
use uvflat_core::{unwrap, ChartStatus, Method, UnwrapOptions};

mod common;

use common::Soup;

/// An `n`×`n` grid of unit quads, `holes` of 2×2 quads removed (by their lower-left quad),
/// turned onto a tilted plane. With `slivers`, the quad left of every hole gets a fifth corner
/// on its side along the hole, `1e-7` above its lower corner; `lift` moves one inner vertex
/// off the plane by that much.
fn plate(n: usize, holes: &[(usize, usize)], slivers: bool, lift: f64) -> Soup {
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let (c2, s2) = (0.3f64.cos(), 0.3f64.sin());
    let place = |x: f64, y: f64, z: f64| {
        // A turn about x, then about z.
        let (y, z) = (c * y - s * z, s * y + c * z);
        [c2 * x - s2 * y, s2 * x + c2 * y, z]
    };
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut positions: Vec<[f64; 3]> =
        (0..=n).flat_map(|j| (0..=n).map(move |i| (i, j))).map(|(i, j)| place(i as f64, j as f64, 0.0)).collect();
    let inner = at(n / 2, 1) as usize;
    positions[inner] = place((n / 2) as f64, 1.0, lift);
    let in_hole = |i: usize, j: usize| holes.iter().any(|&(hi, hj)| (hi..hi + 2).contains(&i) && (hj..hj + 2).contains(&j));
    let (mut corner_verts, mut face_sizes) = (Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..n {
            if in_hole(i, j) {
                continue;
            }
            let mut face = vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            if slivers && holes.contains(&(i + 1, j)) {
                positions.push(place((i + 1) as f64, j as f64 + 1e-7, 0.0));
                face.insert(2, positions.len() as u32 - 1);
            }
            face_sizes.push(face.len() as u32);
            corner_verts.extend(face);
        }
    }
    Soup { positions, corner_verts, face_sizes }
}

const HOLES: [(usize, usize); 4] = [(2, 2), (7, 3), (3, 7), (8, 8)];

fn run(s: &Soup, name: &str, auto_seams: bool) -> uvflat_core::Unwrapped {
    let mut o = UnwrapOptions { method: Method::parse(name, &[]).unwrap(), ..Default::default() };
    o.auto_seams.enabled = auto_seams;
    unwrap(&s.input(), &o).expect("unwrap")
}

#[test]
fn a_perforated_plate_with_slivers_is_one_island_laid_as_it_is() {
    let s = plate(12, &HOLES, true, 0.0);
    for name in ["abf", "lscm", "slim", "mips", "arap", "spectral", "scaffold"] {
        let r = run(&s, name, true);
        assert_eq!(r.charts.len(), 1, "{name}: {:?}", r.charts.iter().map(|c| (c.faces, &c.reason)).collect::<Vec<_>>());
        let c = &r.charts[0];
        assert_eq!((c.status, c.method), (ChartStatus::Solved, name), "{name}: {:?}", c.reason);
        assert_eq!((c.iterations, c.reason.as_deref()), (0, None), "{name}: laid as it is, no solve");
        assert!(!r.new_seams.is_empty(), "{name}: the holes are joined to the outline");
        let d = c.distortion;
        assert!(d.conformal < 1.0 + 1e-9 && d.area < 1.0 + 1e-9, "{name}: {d:?}");
        // Every corner of a vertex at one UV: each cut's two sides lie on each other.
        let mut uv_of: Vec<Option<[f64; 2]>> = vec![None; s.positions.len()];
        for (k, &v) in s.corner_verts.iter().enumerate() {
            let p = r.uv[k];
            match uv_of[v as usize] {
                None => uv_of[v as usize] = Some(p),
                Some(q) => assert!((p[0] - q[0]).abs().max((p[1] - q[1]).abs()) < 1e-12, "{name}: vertex {v}: {p:?} {q:?}"),
            }
        }
    }
}

#[test]
fn charts_that_are_not_flat_or_would_keep_a_triangle_without_area_are_solved_by_the_method() {
    // Off the plane by 1e-3: the method solves it (no flat note), as it did.
    let bent = plate(12, &HOLES, false, 1e-3);
    // A triangle whose three corners lie on one line, on the plate's first side: laid flat, it
    // would have no area.
    let mut collinear = plate(6, &[], false, 0.0);
    let (a, b) = (collinear.positions[0], collinear.positions[1]);
    collinear.positions.push([(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0]);
    let mid = collinear.positions.len() as u32 - 1;
    collinear.corner_verts.extend([1, 0, mid]);
    collinear.face_sizes.push(3);
    for (what, s) in [("bent", &bent), ("collinear", &collinear)] {
        for name in ["abf", "lscm", "slim"] {
            let r = run(s, name, what == "bent");
            for c in &r.charts {
                assert_eq!(c.flips, 0, "{what} {name}: {:?}", c.reason);
                if name == "slim" {
                    let solved = c.reason.as_deref().unwrap_or("").contains("symmetric Dirichlet");
                    assert!(solved, "{what}: SLIM's own solve: {:?}", c.reason);
                }
            }
        }
    }
    let chart = |s: &Soup| {
        let mesh = uvflat_core::mesh::PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        uvflat_core::charts::build_charts(&mesh, &[], None).remove(0)
    };
    assert!(planar::project(&chart(&bent)).is_none());
    assert!(planar::project(&chart(&collinear)).is_none());
    assert!(planar::project(&chart(&plate(12, &HOLES, false, 0.0))).is_some());
}

#[test]
fn a_flat_chart_with_a_crack_is_one_island_laid_closed() {
    // The square [0, 4]² (tilted) with a crack of zero width down its middle from the top edge
    // to (2, 2): the crack's right side is one edge, its left side turns away at (2, 3), a
    // vertex on that edge; the same with the vertex off the edge by single-precision rounding.
    let (c, s) = (0.5f64.cos(), 0.5f64.sin());
    let place = |x: f64, y: f64| [x, c * y, s * y];
    for off in [0.0, 2e-7] {
        let pts =
            [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (2.0, 4.0), (2.0, 2.0), (2.0 + off, 3.0), (0.0, 4.0), (2.0, 1.0)];
        let positions: Vec<[f64; 3]> = pts.iter().map(|&(x, y)| place(x, y)).collect();
        let tris: [[u32; 3]; 7] = [[1, 2, 3], [1, 3, 4], [7, 1, 4], [0, 1, 7], [0, 7, 4], [0, 4, 5], [0, 5, 6]];
        let soup = Soup {
            positions,
            corner_verts: tris.iter().flatten().copied().collect(),
            face_sizes: vec![3; tris.len()],
        };
        for name in ["abf", "lscm", "slim", "scaffold"] {
            let r = run(&soup, name, true);
            let what = r.charts.iter().map(|c| (c.faces, c.status, &c.reason)).collect::<Vec<_>>();
            assert_eq!(r.charts.len(), 1, "{off} {name}: {what:?}");
            let c = &r.charts[0];
            let got = (c.status, c.iterations, c.flips, c.overlap);
            assert_eq!(got, (ChartStatus::Solved, 0, 0, false), "{off} {name}: {what:?}");
            assert!(r.new_seams.is_empty(), "{off} {name}: no cut");
            let d = c.distortion;
            assert!(d.conformal < 1.0 + 1e-9 && d.area < 1.0 + 1e-9, "{off} {name}: {d:?}");
        }
    }
}
