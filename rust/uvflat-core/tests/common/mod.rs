//! Test helpers: tiny OFF/OBJ readers, the shared mesh folder, analytic meshes.
#![allow(dead_code)]

use std::path::PathBuf;

pub struct Soup {
    pub positions: Vec<[f64; 3]>,
    pub corner_verts: Vec<u32>,
    pub face_sizes: Vec<u32>,
}

impl Soup {
    pub fn input(&self) -> uvflat_core::MeshInput<'_> {
        uvflat_core::MeshInput {
            positions: &self.positions,
            corner_verts: &self.corner_verts,
            face_sizes: &self.face_sizes,
            ..Default::default()
        }
    }
}

/// `<repo>/../shared/meshes`, or None (tests print why they skip).
pub fn shared_meshes() -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes");
    if p.is_dir() {
        Some(p)
    } else {
        eprintln!("SKIP: ../shared/meshes not found beside the repository; shared-mesh checks skipped");
        None
    }
}

pub fn load(path: &std::path::Path) -> Soup {
    let text = std::fs::read_to_string(path).unwrap();
    let ext = path.extension().unwrap().to_str().unwrap();
    let mut s = Soup { positions: vec![], corner_verts: vec![], face_sizes: vec![] };
    if ext == "off" {
        let mut toks = text
            .lines()
            .map(|l| l.split('#').next().unwrap())
            .flat_map(|l| l.split_whitespace())
            .map(str::to_string);
        let head = toks.next().unwrap();
        assert!(head.ends_with("OFF"));
        let nv: usize = toks.next().unwrap().parse().unwrap();
        let nf: usize = toks.next().unwrap().parse().unwrap();
        let _ne: usize = toks.next().unwrap().parse().unwrap();
        for _ in 0..nv {
            let p: Vec<f64> = (0..3).map(|_| toks.next().unwrap().parse().unwrap()).collect();
            s.positions.push([p[0], p[1], p[2]]);
        }
        for _ in 0..nf {
            let k: usize = toks.next().unwrap().parse().unwrap();
            for _ in 0..k {
                s.corner_verts.push(toks.next().unwrap().parse().unwrap());
            }
            s.face_sizes.push(k as u32);
        }
    } else {
        for line in text.lines() {
            let mut it = line.split_whitespace();
            match it.next() {
                Some("v") => {
                    let p: Vec<f64> = it.take(3).map(|x| x.parse().unwrap()).collect();
                    s.positions.push([p[0], p[1], p[2]]);
                }
                Some("f") => {
                    let mut k = 0;
                    for tok in it {
                        let i: i64 = tok.split('/').next().unwrap().parse().unwrap();
                        let i = if i < 0 { s.positions.len() as i64 + i } else { i - 1 };
                        s.corner_verts.push(i as u32);
                        k += 1;
                    }
                    s.face_sizes.push(k);
                }
                _ => {}
            }
        }
    }
    s
}

/// A planar disk: concentric rings of vertices (irregular triangles), z = 0.
pub fn planar_disk(rings: usize, per_ring: usize) -> Soup {
    let mut positions = vec![[0.0, 0.0, 0.0]];
    for r in 1..=rings {
        let n = per_ring * r;
        for k in 0..n {
            let a = std::f64::consts::TAU * (k as f64 + 0.3 * (r % 2) as f64) / n as f64;
            let rad = r as f64 * (1.0 + 0.1 * (3.0 * a).sin());
            positions.push([rad * a.cos(), 0.7 * rad * a.sin(), 0.0]);
        }
    }
    // Triangulate ring r-1 to ring r by walking both rings.
    let mut corner_verts = Vec::new();
    let start = |r: usize| if r == 0 { 0 } else { 1 + per_ring * r * (r - 1) / 2 };
    let count = |r: usize| if r == 0 { 1 } else { per_ring * r };
    for r in 1..=rings {
        let (s0, n0, s1, n1) = (start(r - 1), count(r - 1), start(r), count(r));
        let (mut i, mut j) = (0usize, 0usize);
        let ang = |s: usize, n: usize, k: usize, pos: &Vec<[f64; 3]>| {
            let p = pos[s + k % n];
            let a = p[1].atan2(p[0]);
            let base = std::f64::consts::TAU * (k / n) as f64;
            (if a < 0.0 { a + std::f64::consts::TAU } else { a }) + base
        };
        while i < n0 || j < n1 {
            let advance_outer = if n0 == 1 {
                true
            } else if i >= n0 {
                true
            } else if j >= n1 {
                false
            } else {
                ang(s1, n1, j + 1, &positions) < ang(s0, n0, i + 1, &positions)
            };
            if advance_outer {
                corner_verts.extend([(s0 + i % n0) as u32, (s1 + j % n1) as u32, (s1 + (j + 1) % n1) as u32]);
                j += 1;
                if n0 == 1 && j >= n1 {
                    break;
                }
            } else {
                corner_verts.extend([(s0 + i % n0) as u32, (s1 + j % n1) as u32, (s0 + (i + 1) % n0) as u32]);
                i += 1;
            }
        }
    }
    let face_sizes = vec![3u32; corner_verts.len() / 3];
    Soup { positions, corner_verts, face_sizes }
}

/// An open cylinder of radius 1 and height h, cut open along one generator (seam) — as a
/// grid of quads whose first and last columns share vertices, plus the seam edges.
pub fn cut_cylinder(nu: usize, nv: usize, h: f64) -> (Soup, Vec<[u32; 2]>) {
    let mut positions = Vec::new();
    for j in 0..=nv {
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            positions.push([a.cos(), a.sin(), h * j as f64 / nv as f64]);
        }
    }
    let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
    let mut corner_verts = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let face_sizes = vec![4u32; nu * nv];
    let seams = (0..nv).map(|j| [id(0, j), id(0, j + 1)]).collect();
    (Soup { positions, corner_verts, face_sizes }, seams)
}

/// Split every triangle into four at its edge midpoints (triangle meshes only).
/// The mesh at `args[1]` subdivided `args[2]` times (0 when absent): the examples' input.
pub fn mesh_from_args(args: &[String]) -> Soup {
    let mut s = load(std::path::Path::new(&args[1]));
    let levels: usize = args.get(2).map(|x| x.parse().expect("LEVELS is a number")).unwrap_or(0);
    for _ in 0..levels {
        s = subdivide(&s);
    }
    s
}

/// A regular octahedron (vertices on the unit axes) subdivided `levels` times, its vertices
/// pushed onto the unit sphere: a closed genus-0 triangle mesh of `8 · 4^levels` triangles.
pub fn octahedron_sphere(levels: usize) -> Soup {
    let positions =
        vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    let faces: [[u32; 3]; 8] = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    let mut s = Soup { positions, corner_verts: faces.iter().flatten().copied().collect(), face_sizes: vec![3; 8] };
    for _ in 0..levels {
        s = subdivide(&s);
    }
    for p in &mut s.positions {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        *p = [p[0] / n, p[1] / n, p[2] / n];
    }
    s
}

pub fn subdivide(s: &Soup) -> Soup {
    assert!(s.face_sizes.iter().all(|&k| k == 3), "subdivision needs a triangle mesh");
    let mut positions = s.positions.clone();
    let mut mid = std::collections::HashMap::new();
    let mut corner_verts = Vec::with_capacity(4 * s.corner_verts.len());
    for t in s.corner_verts.chunks_exact(3) {
        let mut m = [0u32; 3];
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            m[k] = *mid.entry((a, b)).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
                (positions.len() - 1) as u32
            });
        }
        corner_verts.extend_from_slice(&[t[0], m[0], m[2], m[0], t[1], m[1], m[2], m[1], t[2], m[0], m[1], m[2]]);
    }
    let face_sizes = vec![3; corner_verts.len() / 3];
    Soup { positions, corner_verts, face_sizes }
}

/// Every method with every boundary / solver variant, the iterative ones capped at
/// `iterations` (scaffold at half of it) and spectral at `spectral_iterations`.
pub fn every_method(iterations: usize, spectral_iterations: usize) -> Vec<uvflat_core::Method> {
    use uvflat_core::methods::{abf, arap, mips, scaffold, slim};
    use uvflat_core::{BoundaryShape, Method, SpectralOptions};
    let mut v = Vec::new();
    for b in [BoundaryShape::Circle, BoundaryShape::Square, BoundaryShape::Virtual] {
        v.push(Method::Tutte { boundary: b });
        v.push(Method::Harmonic { boundary: b });
        v.push(Method::MeanValue { boundary: b });
    }
    v.extend([
        Method::Lscm,
        Method::Spectral(SpectralOptions { max_iterations: spectral_iterations, ..Default::default() }),
        Method::Bff,
        Method::Abf(abf::AbfOptions::default()),
        Method::Abf(abf::AbfOptions { solver: abf::AbfSolver::Plain, ..Default::default() }),
        Method::Abf(abf::AbfOptions { boundary: abf::AbfBoundary::Convex, ..Default::default() }),
        Method::Arap(arap::ArapOptions { max_iterations: iterations, ..Default::default() }),
        Method::Slim(slim::SlimOptions { max_iterations: iterations, ..Default::default() }),
        Method::Mips(mips::MipsOptions { max_iterations: iterations, ..Default::default() }),
        Method::Scaffold(scaffold::ScaffoldOptions { max_iterations: (iterations / 2).max(1), ..Default::default() }),
    ]);
    v
}

/// Doubled signed area of every triangle under `uv` (positive: counter-clockwise).
pub fn doubled_signed_areas(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<f64> {
    triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        })
        .collect()
}

/// CPU time of all threads of this process so far (scheduler statistics, nanoseconds): a
/// timing that other processes on a busy machine do not inflate.
pub fn cpu_seconds() -> f64 {
    let mut ns = 0u64;
    if let Ok(dir) = std::fs::read_dir("/proc/self/task") {
        for t in dir.flatten() {
            if let Ok(s) = std::fs::read_to_string(t.path().join("schedstat")) {
                ns += s.split_whitespace().next().and_then(|x| x.parse::<u64>().ok()).unwrap_or(0);
            }
        }
    }
    ns as f64 * 1e-9
}

/// Small deterministic generator (xorshift), uniform in [0, 1).
pub struct QuadRng(pub u64);
impl QuadRng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A noisy, curved quad grid (a saddle with bumps and some dart-shaped quads), `n × n` quads, and random seams
/// that cut it into charts (random walks along grid edges from the border).
pub fn curved_quad_grid(n: usize, seed: u64) -> (Soup, Vec<[u32; 2]>) {
    let mut rng = QuadRng(seed);
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64 * 2.0 - 1.0, j as f64 / n as f64 * 2.0 - 1.0);
            let h = 2.0 / n as f64;
            let (mut jx, mut jy) = (0.3 * h * (rng.next() - 0.5), 0.3 * h * (rng.next() - 0.5));
            // Every few interior vertices move 0.6 of the way along their quad's diagonal:
            // that quad becomes a dart (concave in 3D, convex only by moving it in UV), so
            // a faithful map folds it on one diagonal.
            if i > 0 && j > 0 && i < n - 1 && j < n - 1 && (7 * i + 3 * j) % 11 == 0 {
                jx = 0.6 * h;
                jy = 0.6 * h;
            }
            let z = 0.6 * (x * x - y * y) + 0.2 * (3.0 * x).sin() * (2.0 * y).cos();
            positions.push([x + jx, y + jy, z]);
        }
    }
    let mut corner_verts = Vec::new();
    let mut face_sizes = Vec::new();
    for j in 0..n {
        for i in 0..n {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            face_sizes.push(4);
        }
    }
    let mut seams = Vec::new();
    for w in 0..4 {
        let (mut i, mut j) = if w % 2 == 0 { (0, (rng.next() * n as f64) as usize) } else { ((rng.next() * n as f64) as usize, 0) };
        for _ in 0..n {
            let (ni, nj) = if rng.next() < 0.5 { ((i + 1).min(n), j) } else { (i, (j + 1).min(n)) };
            if (ni, nj) == (i, j) {
                break;
            }
            seams.push([id(i, j), id(ni, nj)]);
            (i, j) = (ni, nj);
        }
    }
    (Soup { positions, corner_verts, face_sizes }, seams)
}

/// A brick wall of hexagons (pairs of grid quads merged, rows offset), noisy and curved, with
/// some middle vertices pushed across their hexagon: concave n-gons in 3D.
pub fn brick_hexagons(n: usize, seed: u64) -> Soup {
    let mut rng = QuadRng(seed);
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let h = 2.0 / n as f64;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (mut x, mut y) = (i as f64 * h - 1.0, j as f64 * h - 1.0);
            x += 0.3 * h * (rng.next() - 0.5);
            y += 0.3 * h * (rng.next() - 0.5);
            if i > 0 && j > 0 && i < n && j < n && (5 * i + 3 * j) % 7 == 0 {
                y += 0.7 * h;
            }
            positions.push([x, y, 0.5 * (x * x - y * y) + 0.2 * (3.0 * x).sin()]);
        }
    }
    let (mut corner_verts, mut face_sizes) = (Vec::new(), Vec::new());
    for j in 0..n {
        let mut i = 0;
        if j % 2 == 1 {
            corner_verts.extend([id(0, j), id(1, j), id(1, j + 1), id(0, j + 1)]);
            face_sizes.push(4);
            i = 1;
        }
        while i < n {
            if i + 2 <= n {
                corner_verts.extend([id(i, j), id(i + 1, j), id(i + 2, j), id(i + 2, j + 1), id(i + 1, j + 1), id(i, j + 1)]);
                face_sizes.push(6);
                i += 2;
            } else {
                corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                face_sizes.push(4);
                i += 1;
            }
        }
    }
    Soup { positions, corner_verts, face_sizes }
}

/// The unit cube `[0, 1]³` of `6 × n × n` quads, wound outwards.
pub fn cube(n: usize) -> Soup {
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut cv = Vec::new();
    let mut fs = Vec::new();
    let ni = n as i64;
    for axis in 0..3 {
        for side in [0, ni] {
            for i in 0..ni {
                for j in 0..ni {
                    let mk = |a: i64, b: i64| {
                        let mut p = [0i64; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = a;
                        p[(axis + 2) % 3] = b;
                        p
                    };
                    let mut q = [mk(i, j), mk(i + 1, j), mk(i + 1, j + 1), mk(i, j + 1)];
                    if side == 0 {
                        q.reverse();
                    }
                    for p in q {
                        let v = *index.entry(p).or_insert_with(|| {
                            positions.push([p[0] as f64 / ni as f64, p[1] as f64 / ni as f64, p[2] as f64 / ni as f64]);
                            (positions.len() - 1) as u32
                        });
                        cv.push(v);
                    }
                    fs.push(4);
                }
            }
        }
    }
    Soup { positions, corner_verts: cv, face_sizes: fs }
}

/// Unit sphere from a subdivided cube: `n × n` quads a side projected on the sphere (exactly
/// mirror-symmetric in the three coordinate planes when `n` is even).
pub fn cube_sphere(n: usize) -> Soup {
    let mut s = cube(n);
    for p in &mut s.positions {
        let x = [p[0] * 2.0 - 1.0, p[1] * 2.0 - 1.0, p[2] * 2.0 - 1.0];
        let l = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        *p = [x[0] / l, x[1] / l, x[2] / l];
    }
    s
}

/// A latitude–longitude sphere of radius 1: `nu` segments, `nv` rings (quads, triangle fans
/// at the poles). Faces for which `keep(centroid)` is false are left out.
pub fn sphere(nu: usize, nv: usize, keep: impl Fn([f64; 3]) -> bool) -> Soup {
    let mut positions = vec![[0.0, 0.0, 1.0]];
    for j in 1..nv {
        let t = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let a = std::f64::consts::TAU * i as f64 / nu as f64;
            positions.push([t.sin() * a.cos(), t.sin() * a.sin(), t.cos()]);
        }
    }
    positions.push([0.0, 0.0, -1.0]);
    let south = (positions.len() - 1) as u32;
    let ring = |j: usize, i: usize| (1 + (j - 1) * nu + i % nu) as u32;
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for i in 0..nu {
        faces.push(vec![0, ring(1, i), ring(1, i + 1)]);
    }
    for j in 1..nv - 1 {
        for i in 0..nu {
            faces.push(vec![ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)]);
        }
    }
    for i in 0..nu {
        faces.push(vec![ring(nv - 1, i), south, ring(nv - 1, i + 1)]);
    }
    soup_of(positions, faces, keep)
}

/// A soup of the faces whose centroid `keep` accepts, unused vertices dropped.
pub fn soup_of(positions: Vec<[f64; 3]>, faces: Vec<Vec<u32>>, keep: impl Fn([f64; 3]) -> bool) -> Soup {
    let mut used = vec![u32::MAX; positions.len()];
    let mut out = Soup { positions: Vec::new(), corner_verts: Vec::new(), face_sizes: Vec::new() };
    for f in faces {
        let mut c = [0.0; 3];
        for &v in &f {
            for k in 0..3 {
                c[k] += positions[v as usize][k] / f.len() as f64;
            }
        }
        if !keep(c) {
            continue;
        }
        for &v in &f {
            if used[v as usize] == u32::MAX {
                used[v as usize] = out.positions.len() as u32;
                out.positions.push(positions[v as usize]);
            }
            out.corner_verts.push(used[v as usize]);
        }
        out.face_sizes.push(f.len() as u32);
    }
    out
}

/// `s` with `k` holes: each the first `size` faces met by a breadth-first walk over faces
/// sharing an edge, from a face drawn by [`QuadRng`] seeded with `seed` (deterministic), the
/// way scans lose patches of surface. Unused vertices are dropped.
pub fn with_holes(s: &Soup, k: usize, size: usize, seed: u64) -> Soup {
    let mut starts = Vec::with_capacity(s.face_sizes.len());
    let mut at = 0usize;
    for &n in &s.face_sizes {
        starts.push(at);
        at += n as usize;
    }
    let face = |f: usize| &s.corner_verts[starts[f]..starts[f] + s.face_sizes[f] as usize];
    let mut by_edge: std::collections::HashMap<(u32, u32), Vec<usize>> = std::collections::HashMap::new();
    for f in 0..s.face_sizes.len() {
        let c = face(f);
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(f);
        }
    }
    let mut rng = QuadRng(seed.max(1));
    let mut dead = vec![false; s.face_sizes.len()];
    for _ in 0..k {
        let f0 = ((rng.next() * s.face_sizes.len() as f64) as usize).min(s.face_sizes.len() - 1);
        let mut queue = std::collections::VecDeque::from([f0]);
        let mut taken = vec![f0];
        dead[f0] = true;
        while let Some(f) = queue.pop_front() {
            let c = face(f);
            for i in 0..c.len() {
                let (a, b) = (c[i], c[(i + 1) % c.len()]);
                for &g in &by_edge[&(a.min(b), a.max(b))] {
                    if taken.len() < size && !dead[g] {
                        dead[g] = true;
                        taken.push(g);
                        queue.push_back(g);
                    }
                }
            }
        }
    }
    let faces: Vec<Vec<u32>> = (0..s.face_sizes.len()).filter(|&f| !dead[f]).map(|f| face(f).to_vec()).collect();
    soup_of(s.positions.clone(), faces, |_| true)
}

/// Every island of `r` (an unwrap of `s` with automatic seams) keeps the atlas rule, measured
/// on the UVs (no flip, no crossing outline, at most 5% outside the density bound), and the
/// seams reported cut `s` into exactly these islands, each a disk. `what` names the run.
pub fn assert_islands_keep_the_rule(s: &Soup, what: &str, r: &uvflat_core::Unwrapped) {
    use uvflat_core::charts::{build_charts, ChartKind};
    use uvflat_core::ChartStatus;
    let m = uvflat_core::metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
    assert_eq!(m.flips, 0, "{what}");
    assert_eq!(m.overlapping_charts, 0, "{what}: an outline crosses itself");
    for (c, mc) in r.charts.iter().zip(&m.per_chart) {
        let ok = matches!(c.status, ChartStatus::Solved | ChartStatus::Fallback);
        assert!(ok, "{what}: chart {}: {:?}", c.id, c.reason);
        assert!(mc.density.outside <= 0.05 + 1e-12, "{what}: chart {}: {:.3} outside", c.id, mc.density.outside);
    }
    let mesh = uvflat_core::mesh::PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &r.new_seams, None);
    for ch in &charts {
        assert_eq!(ch.kind, ChartKind::Disk, "{what}: an island of {} faces is {:?}", ch.faces.len(), ch.kind);
    }
    assert_eq!(charts.len(), r.charts.len(), "{what}: charts between the seams reported");
    assert_eq!(m.charts, r.charts.len(), "{what}: islands measured in UV");
}

/// `r` is what `options` give on `s` on one thread too, to the bit (seams and UVs).
pub fn assert_same_on_one_thread(s: &Soup, options: &uvflat_core::UnwrapOptions, r: &uvflat_core::Unwrapped) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let one = pool.install(|| uvflat_core::unwrap(&s.input(), options).unwrap());
    assert_eq!(one.new_seams, r.new_seams);
    let bits = |uv: &[[f64; 2]]| uv.iter().flat_map(|p| [p[0].to_bits(), p[1].to_bits()]).collect::<Vec<u64>>();
    assert!(bits(&one.uv) == bits(&r.uv), "the UVs differ on one thread");
}
