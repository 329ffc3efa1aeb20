//! Chart scheduling: the output of `unwrap` does not depend on the number of threads nor on
//! the order charts are solved in (largest first, tiny charts batched).
mod common;

use uvflat_core::{unwrap, Method, MeshInput, UnwrapOptions, Unwrapped};

/// A wavy height-field grid of `n × n` quads cut by seams into vertical strips of different
/// widths (charts of different sizes), plus `tiny` separate triangles (one-face charts).
fn many_charts(n: usize, tiny: usize) -> (common::Soup, Vec<[u32; 2]>) {
    let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            positions.push([x, y, 0.2 * (3.0 * x).sin() * (2.0 * y).cos()]);
        }
    }
    let mut corner_verts = Vec::new();
    let mut face_sizes = Vec::new();
    for i in 0..n {
        for j in 0..n {
            corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            face_sizes.push(4);
        }
    }
    // Seams along columns 1, 3, 6, 10, ...: strips of widths 1, 2, 3, 4, ...
    let mut seams = Vec::new();
    let mut col = 1;
    let mut width = 2;
    while col < n {
        for j in 0..n {
            seams.push([id(col, j), id(col, j + 1)]);
        }
        col += width;
        width += 1;
    }
    for t in 0..tiny {
        let base = positions.len() as u32;
        let (x, z) = (2.0 + 0.1 * t as f64, 0.01 * (t % 7) as f64);
        positions.extend([[x, 0.0, z], [x + 0.05, 0.0, 0.0], [x, 0.07 + 0.001 * (t % 5) as f64, 0.0]]);
        corner_verts.extend([base, base + 1, base + 2]);
        face_sizes.push(3);
    }
    (common::Soup { positions, corner_verts, face_sizes }, seams)
}

fn run_in_pool(threads: usize, input: &MeshInput<'_>, options: &UnwrapOptions) -> Unwrapped {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| unwrap(input, options).unwrap())
}

fn assert_bitwise_equal(a: &Unwrapped, b: &Unwrapped) {
    assert_eq!(a.face_chart, b.face_chart);
    assert_eq!(a.uv.len(), b.uv.len());
    for (c, (p, q)) in a.uv.iter().zip(&b.uv).enumerate() {
        assert!(
            p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits(),
            "corner {c}: {p:?} vs {q:?}"
        );
    }
    assert_eq!(a.charts.len(), b.charts.len());
    for (r, s) in a.charts.iter().zip(&b.charts) {
        assert_eq!((r.id, r.status, r.iterations, r.flips), (s.id, s.status, s.iterations, s.flips));
        assert_eq!(r.residual.to_bits(), s.residual.to_bits(), "chart {}", r.id);
    }
}

#[test]
fn one_and_two_threads_give_bit_identical_unwraps() {
    let (soup, seams) = many_charts(24, 600);
    let input = MeshInput { seams: &seams, ..soup.input() };
    for name in ["lscm", "slim", "abf"] {
        let options = UnwrapOptions { method: Method::parse(name, &[]).unwrap(), ..Default::default() };
        let one = run_in_pool(1, &input, &options);
        let two = run_in_pool(2, &input, &options);
        // Reports are indexed by chart id, and charts of every size were solved.
        assert!(one.charts.iter().enumerate().all(|(i, r)| r.id == i));
        assert!(one.charts.len() > 600 + 4, "{} charts", one.charts.len());
        let big = one.charts.iter().map(|r| r.triangles).max().unwrap();
        assert!(big > 8 * 24, "largest chart has {big} triangles");
        assert!(one.charts.iter().all(|r| r.flips == 0 && r.status == uvflat_core::ChartStatus::Solved), "{name}");
        assert_bitwise_equal(&one, &two);
    }
}

#[test]
fn scheduled_unwrap_matches_each_chart_solved_alone() {
    // Solving a chart inside a large batch gives exactly the UVs of solving it on its own mesh
    // (here: the tiny triangles, each translated copy compared through its edge lengths).
    let (soup, seams) = many_charts(6, 40);
    let input = MeshInput { seams: &seams, ..soup.input() };
    let all = unwrap(&input, &UnwrapOptions::default()).unwrap();
    let first_tiny = 36; // after the grid's quads
    for t in 0..40 {
        let f = first_tiny + t;
        let c0 = 36 * 4 + 3 * t;
        let single = common::Soup {
            positions: (0..3).map(|k| soup.positions[soup.corner_verts[c0 + k] as usize]).collect(),
            corner_verts: vec![0, 1, 2],
            face_sizes: vec![3],
        };
        let alone = unwrap(&single.input(), &UnwrapOptions::default()).unwrap();
        assert!(all.face_solved(f));
        for k in 0..3 {
            let p = all.uv[c0 + k];
            let q = alone.uv[k];
            assert!(p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits(), "face {f} corner {k}");
        }
    }
}
