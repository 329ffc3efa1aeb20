//! Automatic seams on a subdivided mesh: time per phase, islands, the atlas rule.
//! `cargo run --release -p uvflat-core --example scan_phases -- MESH LEVELS [METHOD]`
use uvflat_core::{unwrap, Method, UnwrapOptions};

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let s = common::mesh_from_args(&args);
    let method = Method::parse(args.get(3).map(|s| s.as_str()).unwrap_or("abf"), &[]).unwrap();
    let t = std::time::Instant::now();
    let mut o = UnwrapOptions { method, ..Default::default() };
    if let Ok(k) = std::env::var("MAX_CONES") {
        o.auto_seams.max_cones = k.parse().unwrap();
    }
    if let Ok(v) = std::env::var("SAME_SEAMS") {
        o.auto_seams.same_seams = v == "1";
    }
    let r = unwrap(&s.input(), &o).unwrap();
    let secs = t.elapsed().as_secs_f64();
    let mut codes = std::collections::BTreeMap::new();
    for c in &r.charts {
        *codes.entry(c.status.name()).or_insert(0) += 1;
    }
    let worst = r.charts.iter().map(|c| c.density.outside).fold(0.0, f64::max);
    let flips: usize = r.charts.iter().map(|c| c.flips).sum();
    println!(
        "{} faces: {:.2} s, {} islands {:?}, flips {}, worst outside {:.3}, {} new seams",
        s.face_sizes.len(), secs, r.charts.len(), codes, flips, worst, r.new_seams.len()
    );
    let len: f64 = r.new_seams.iter().map(|e| { let (a, b) = (s.positions[e[0] as usize], s.positions[e[1] as usize]); ((a[0]-b[0]).powi(2)+(a[1]-b[1]).powi(2)+(a[2]-b[2]).powi(2)).sqrt() }).sum();
    println!("seam length {len:.4}");
    let mut sizes: Vec<usize> = r.charts.iter().map(|c| c.faces).collect();
    sizes.sort_unstable();
    let small = sizes.iter().filter(|&&n| n < 10).count();
    println!("islands under 10 faces: {small}, smallest {:?}", &sizes[..sizes.len().min(12)]);
    let mut large: Vec<_> = r.charts.iter().filter(|c| c.faces >= 10_000).collect();
    large.sort_by_key(|c| std::cmp::Reverse(c.faces));
    for c in large {
        println!("  island {} faces: {} iterations, {:.2} s solve", c.faces, c.iterations, c.seconds);
    }
    println!("{:?}", r.phases);
}
