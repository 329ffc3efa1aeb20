//! Automatic seams: closed and higher-genus charts are cut into disks and every face unwraps.

mod common;

use common::{cube_sphere as sphere, load, shared_meshes, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{self, AutoSeamOptions};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{abf, mips, scaffold, slim};
use uvflat_core::{unwrap, BoundaryShape, ChartKind, ChartStatus, Method, UnwrapOptions, Unwrapped};

fn opts(method: Method) -> UnwrapOptions {
    UnwrapOptions { method, ..Default::default() }
}

/// Methods that promise no flipped triangle.
fn promises_no_flips(m: &Method) -> bool {
    matches!(m, Method::Tutte { .. } | Method::MeanValue { .. } | Method::Slim(_) | Method::Mips(_) | Method::Scaffold(_) | Method::Abf(_))
}

fn all_methods() -> Vec<Method> {
    vec![
        Method::Tutte { boundary: BoundaryShape::Circle },
        Method::Harmonic { boundary: BoundaryShape::Circle },
        Method::MeanValue { boundary: BoundaryShape::Circle },
        Method::Lscm,
        Method::Spectral(Default::default()),
        Method::Abf(abf::AbfOptions::default()),
        Method::Arap(Default::default()),
        Method::Slim(slim::SlimOptions::default()),
        Method::Mips(mips::MipsOptions::default()),
        Method::Scaffold(scaffold::ScaffoldOptions::default()),
    ]
}

/// Torus (genus 1) of `nu × nv` quads; with `holes > 1`, several tori glued side by side along
/// a shared edge would be needed for genus 2 — see [`double_torus`].
fn torus(nu: usize, nv: usize, r_major: f64, r_minor: f64) -> Soup {
    let mut positions = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (i as f64 / nu as f64 * std::f64::consts::TAU, j as f64 / nv as f64 * std::f64::consts::TAU);
            let r = r_major + r_minor * b.cos();
            positions.push([r * a.cos(), r * a.sin(), r_minor * b.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((j % nv) * nu + (i % nu)) as u32;
    let mut corner_verts = Vec::new();
    let mut face_sizes = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            face_sizes.push(4);
        }
    }
    Soup { positions, corner_verts, face_sizes }
}

/// A closed genus-2 surface: the boundary of a thickened plate with two square holes
/// (a 7 × 3 grid of cells, the cells (1,1) and (5,1) removed), built from quads.
fn double_torus() -> Soup {
    // Top and bottom grids of (nx+1) × (ny+1) points at z = ±0.5, cells of size 1.
    let (nx, ny) = (7usize, 3usize);
    let hole = |i: usize, j: usize| j == 1 && (i == 1 || i == 5);
    let mut positions = Vec::new();
    for z in [0.5f64, -0.5] {
        for j in 0..=ny {
            for i in 0..=nx {
                positions.push([i as f64, j as f64, z]);
            }
        }
    }
    let top = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let bot = |i: usize, j: usize| ((ny + 1) * (nx + 1) + j * (nx + 1) + i) as u32;
    let mut cv = Vec::new();
    let mut fs = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if hole(i, j) {
                continue;
            }
            cv.extend([top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1)]);
            cv.extend([bot(i, j), bot(i, j + 1), bot(i + 1, j + 1), bot(i + 1, j)]);
            fs.extend([4, 4]);
        }
    }
    // Side walls along every boundary edge of the plate (outer rim and the holes' rims),
    // oriented outwards: for a top boundary edge a→b (plate on its left), the wall is
    // a, bot(a), bot(b), b reversed appropriately.
    let solid = |i: isize, j: isize| i >= 0 && j >= 0 && (i as usize) < nx && (j as usize) < ny && !hole(i as usize, j as usize);
    for j in 0..ny as isize {
        for i in 0..nx as isize {
            if !solid(i, j) {
                continue;
            }
            let (iu, ju) = (i as usize, j as usize);
            // Neighbour below (j-1): edge (i,j)→(i+1,j) on the top face runs left to right.
            if !solid(i, j - 1) {
                cv.extend([top(iu, ju), bot(iu, ju), bot(iu + 1, ju), top(iu + 1, ju)]);
                fs.push(4);
            }
            if !solid(i, j + 1) {
                cv.extend([top(iu + 1, ju + 1), bot(iu + 1, ju + 1), bot(iu, ju + 1), top(iu, ju + 1)]);
                fs.push(4);
            }
            if !solid(i - 1, j) {
                cv.extend([top(iu, ju + 1), bot(iu, ju + 1), bot(iu, ju), top(iu, ju)]);
                fs.push(4);
            }
            if !solid(i + 1, j) {
                cv.extend([top(iu + 1, ju), bot(iu + 1, ju), bot(iu + 1, ju + 1), top(iu + 1, ju + 1)]);
                fs.push(4);
            }
        }
    }
    Soup { positions, corner_verts: cv, face_sizes: fs }
}

/// Closed low-poly cylinder: `n` side quads and two n-gon caps.
fn capped_cylinder(n: usize) -> Soup {
    let mut positions = Vec::new();
    for z in [0.0f64, 1.0] {
        for i in 0..n {
            let a = i as f64 / n as f64 * std::f64::consts::TAU;
            positions.push([a.cos(), a.sin(), z]);
        }
    }
    let mut cv = Vec::new();
    let mut fs = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        cv.extend([i as u32, j as u32, (n + j) as u32, (n + i) as u32]);
        fs.push(4);
    }
    cv.extend((0..n as u32).rev());
    fs.push(n as u32);
    cv.extend(n as u32..2 * n as u32);
    fs.push(n as u32);
    Soup { positions, corner_verts: cv, face_sizes: fs }
}

/// Euler characteristic V − E of the graph of new seams.
fn seam_graph_chi(seams: &[[u32; 2]]) -> i64 {
    let mut v: Vec<u32> = seams.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    v.len() as i64 - seams.len() as i64
}

/// Every face unwrapped, promises kept, every chart a disk, UVs finite.
fn check(name: &str, method: &Method, r: &Unwrapped) {
    for c in &r.charts {
        assert_ne!(c.status, ChartStatus::Failed, "{name} {}: chart {} failed: {:?}", method.name(), c.id, c.reason);
        assert!(matches!(c.kind, ChartKind::Disk | ChartKind::DiskWithHoles), "{name}: chart {} is {:?}", c.id, c.kind);
        if promises_no_flips(method) && c.status == ChartStatus::Solved {
            assert_eq!(c.flips, 0, "{name} {}: chart {} has {} flips", method.name(), c.id, c.flips);
        }
        if matches!(method, Method::Scaffold(_)) && c.status == ChartStatus::Solved {
            assert!(!c.overlap, "{name}: scaffold chart {} overlaps", c.id);
        }
    }
    assert!(r.face_chart.iter().all(|&c| c >= 0), "{name}: a face has no chart");
    assert!(r.uv.iter().flatten().all(|x| x.is_finite()), "{name}: non-finite UV");
}

fn generated() -> Vec<(&'static str, Soup, usize)> {
    vec![
        ("sphere", sphere(8), 0),
        ("torus", torus(24, 12, 2.0, 0.6), 1),
        ("double torus", double_torus(), 2),
        ("capped cylinder", capped_cylinder(8), 0),
    ]
}

#[test]
fn generated_closed_surfaces_unwrap_with_every_method() {
    for (name, soup, genus) in generated() {
        let mesh = PolyMesh::new(&soup.positions, &soup.corner_verts, &soup.face_sizes).unwrap();
        let charts = build_charts(&mesh, &[], None);
        assert_eq!(charts.len(), 1, "{name}");
        assert_eq!(charts[0].genus, genus, "{name}");
        for m in all_methods() {
            let r = unwrap(&soup.input(), &opts(m.clone())).unwrap();
            check(name, &m, &r);
        }
    }
}

#[test]
fn cut_graph_of_a_closed_genus_g_chart_has_euler_characteristic_one_minus_two_g() {
    for (name, soup, genus) in generated() {
        let mesh = PolyMesh::new(&soup.positions, &soup.corner_verts, &soup.face_sizes).unwrap();
        let chart = &build_charts(&mesh, &[], None)[0];
        let avoid = vec![false; soup.positions.len()];
        let cut = cuts::cut_chart(&mesh, chart, &AutoSeamOptions::default(), &avoid, &[], 0);
        assert_eq!(seam_graph_chi(&cut.seams), 1 - 2 * genus as i64, "{name}");
        let rebuilt = build_charts(&mesh, &cut.seams, None);
        assert_eq!(rebuilt.len(), 1, "{name}: the cut disconnects the chart");
        rebuilt[0].sanity_check();
        assert_eq!(rebuilt[0].kind, ChartKind::Disk, "{name}");
        assert_eq!(rebuilt[0].boundary_loops.len(), 1, "{name}");
        // Gauss–Bonnet on a closed surface: the cones hold 2πχ (χ = 2 − 2g) when nothing else
        // carries curvature.
        let total: f64 = cut.cone_curvature.iter().sum();
        let chi = 2.0 - 2.0 * genus as f64;
        assert!((total - std::f64::consts::TAU * chi).abs() < 1e-3 * (1.0 + total.abs()), "{name}: {total} vs 2π·{chi}");
    }
}

#[test]
fn auto_seams_off_keeps_the_refusal() {
    let soup = sphere(4);
    let o = UnwrapOptions { auto_seams: AutoSeamOptions { enabled: false, ..Default::default() }, ..Default::default() };
    let r = unwrap(&soup.input(), &o).unwrap();
    assert_eq!(r.charts.len(), 1);
    assert_eq!(r.charts[0].status, ChartStatus::Failed);
    assert!(r.charts[0].reason.as_deref().unwrap().contains("mark at least one seam"));
    assert!(r.new_seams.is_empty());
}

#[test]
fn avoided_vertices_are_never_on_a_cut_and_never_cones() {
    // Avoid a cap of the sphere (z > 0.3): cuts run through the rest.
    let soup = sphere(8);
    let avoid: Vec<u32> = (0..soup.positions.len() as u32).filter(|&v| soup.positions[v as usize][2] > 0.3).collect();
    assert!(!avoid.is_empty());
    let o = UnwrapOptions { auto_seams: AutoSeamOptions { avoid_vertices: avoid.clone(), ..Default::default() }, ..Default::default() };
    let r = unwrap(&soup.input(), &o).unwrap();
    assert!(!r.new_seams.is_empty());
    for s in &r.new_seams {
        assert!(!avoid.contains(&s[0]) && !avoid.contains(&s[1]), "seam {s:?} touches the avoided region");
    }
    check("sphere avoid", &o.method, &r);
}

#[test]
fn sharp_edges_attract_the_cut() {
    // A cube of 8 × 8 quads per face: with sharp_angle the seams lie on the cube's edges.
    let n = 8usize;
    let mut soup = sphere(n);
    // Un-project back to the cube.
    for p in &mut soup.positions {
        let m = p[0].abs().max(p[1].abs()).max(p[2].abs());
        *p = [p[0] / m, p[1] / m, p[2] / m];
    }
    let on_cube_edge = |p: [f64; 3]| p.iter().filter(|x| (x.abs() - 1.0).abs() < 1e-9).count() >= 2;
    let o = UnwrapOptions { auto_seams: AutoSeamOptions { sharp_angle: Some(0.5), ..Default::default() }, ..Default::default() };
    let r = unwrap(&soup.input(), &o).unwrap();
    assert!(!r.new_seams.is_empty());
    let sharp = r.new_seams.iter().filter(|s| on_cube_edge(soup.positions[s[0] as usize]) && on_cube_edge(soup.positions[s[1] as usize])).count();
    assert!(sharp * 10 >= r.new_seams.len() * 9, "{sharp} of {} seams on sharp edges", r.new_seams.len());
    check("cube", &o.method, &r);
}

#[test]
fn output_is_identical_across_runs_and_thread_counts() {
    let soup = torus(30, 14, 2.0, 0.7);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| unwrap(&soup.input(), &opts(Method::Abf(abf::AbfOptions::default()))).unwrap())
    };
    let a = run(1);
    let b = run(2);
    let c = run(2);
    assert_eq!(a.new_seams, b.new_seams);
    assert_eq!(b.new_seams, c.new_seams);
    assert_eq!(a.uv, b.uv);
    assert_eq!(b.uv, c.uv);
}

const CLOSED: &[(&str, usize)] =
    &[("bunny.off", 0), ("cow.off", 0), ("decimated-max.obj", 0), ("3holes.off", 3), ("fertility.off", 4)];

#[test]
fn shared_closed_meshes_unwrap_completely() {
    shared_closed(&[
        Method::Abf(abf::AbfOptions::default()),
        Method::Lscm,
        Method::Slim(slim::SlimOptions::default()),
        Method::Scaffold(scaffold::ScaffoldOptions::default()),
        Method::MeanValue { boundary: BoundaryShape::Circle },
    ]);
}

#[test]
fn shared_closed_meshes_unwrap_completely_with_the_other_methods() {
    shared_closed(&[
        Method::Tutte { boundary: BoundaryShape::Circle },
        Method::Harmonic { boundary: BoundaryShape::Circle },
        Method::Spectral(Default::default()),
        Method::Arap(Default::default()),
        Method::Mips(mips::MipsOptions::default()),
    ]);
}

fn shared_closed(methods: &[Method]) {
    let Some(dir) = shared_meshes() else { return };
    for &(f, genus) in CLOSED {
        let s = load(&dir.join(f));
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let charts = build_charts(&mesh, &[], None);
        let main = charts.iter().max_by_key(|c| c.faces.len()).unwrap();
        assert_eq!(main.genus, genus, "{f}");
        for m in methods {
            let t = std::time::Instant::now();
            let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
            let cones: usize = r.charts.iter().map(|c| c.cones).sum();
            let worst_area = r.charts.iter().map(|c| c.distortion.area).fold(0.0, f64::max);
            let worst_conf = r.charts.iter().map(|c| c.distortion.conformal).fold(0.0, f64::max);
            eprintln!(
                "{f:>20} {:>10}: {} charts, {} cones, {} seams, conformal ≤ {worst_conf:.3}, area ≤ {worst_area:.3}, {:.2} s",
                m.name(),
                r.charts.len(),
                cones,
                r.new_seams.len(),
                t.elapsed().as_secs_f64()
            );
            check(f, m, &r);
        }
    }
}

#[test]
fn meshes_with_holes_are_joined_to_their_outline() {
    let Some(dir) = shared_meshes() else { return };
    for f in ["beetle.off", "halftunnel.off"] {
        let s = load(&dir.join(f));
        let m = Method::Abf(abf::AbfOptions::default());
        let r = unwrap(&s.input(), &opts(m.clone())).unwrap();
        // Every island a disk: the holes are joined to the outline by new seams.
        assert!(!r.new_seams.is_empty(), "{f}");
        assert!(r.charts.iter().all(|c| c.kind == ChartKind::Disk && c.status == ChartStatus::Solved), "{f}: {:?}", r.charts);
        check(f, &m, &r);
        // Automatic seams off: nothing is cut, the holes stay.
        let mut o = opts(m.clone());
        o.auto_seams.enabled = false;
        let r = unwrap(&s.input(), &o).unwrap();
        assert!(r.new_seams.is_empty(), "{f}");
        assert!(r.charts.iter().any(|c| c.kind == ChartKind::DiskWithHoles), "{f}");
    }
}

/// Cones are the tips of slits, and a tip at a saddle vertex (angle sum of 2π or more) opens
/// to more than 2π in the flattening, so the slit's sides overlap there: no cone is ever
/// placed where the angle defect is not positive, however many the cutter is asked for (the torus's inner half is all saddles; 3holes' handles are ringed by them).
#[test]
fn cones_are_never_placed_at_saddle_vertices() {
    let mut soups = vec![("torus", torus(48, 24, 2.0, 0.7))];
    if let Some(dir) = shared_meshes() {
        soups.push(("3holes", load(&dir.join("3holes.off"))));
    } else {
        eprintln!("skipping 3holes: the shared meshes folder is absent");
    }
    for (name, s) in soups {
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let chart = &build_charts(&mesh, &[], None)[0];
        let solver = cuts::cones::ScaleSolver::new(chart).unwrap();
        let saddles = (0..chart.positions.len()).filter(|&v| solver.defect[v] <= 0.0).count();
        assert!(saddles > chart.positions.len() / 4, "{name}: {saddles} saddle vertices");
        let options = AutoSeamOptions::default();
        let avoid = vec![false; s.positions.len()];
        let cutter = cuts::ChartCutter::new(&mesh, chart, &options, &avoid);
        for v in 0..chart.positions.len() {
            if solver.defect[v] <= 0.0 {
                assert!(!cutter.allowed()[v], "{name}: saddle vertex {v} allowed as a cone");
            }
        }
        for extra in [0, 8, 24] {
            let cut = cutter.cut(&[], extra);
            assert!(!cut.cones.is_empty(), "{name}: a closed chart gets a cone");
            for &c in &cut.cones {
                assert!(solver.defect[c as usize] > 0.0, "{name}: cone {c} at defect {}", solver.defect[c as usize]);
            }
        }
    }
}
