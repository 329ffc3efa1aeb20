//! Time `unwrap` on a mesh with many charts (e.g. ../shared/meshes/cube_40k.obj, whose
//! non-manifold edges split it into tens of thousands of tiny charts):
//! `cargo run --release --example many_charts -- MESH [METHOD] [REPEATS]`.
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use uvflat_core::{unwrap, Method, UnwrapOptions};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("mesh path");
    let method = args.next().unwrap_or_else(|| "lscm".into());
    let repeats: usize = args.next().map(|r| r.parse().unwrap()).unwrap_or(5);
    let s = common::load(std::path::Path::new(&path));
    let options = UnwrapOptions { method: Method::parse(&method, &[]).expect("method name"), ..Default::default() };
    let mut times = Vec::new();
    let mut n_charts = 0;
    for _ in 0..repeats {
        let t = Instant::now();
        let r = unwrap(&s.input(), &options).unwrap();
        times.push(t.elapsed().as_secs_f64());
        n_charts = r.charts.len();
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{path}: {n_charts} charts, {method}, threads {}: median {:.4} s (min {:.4}, max {:.4})",
        rayon::current_num_threads(),
        times[times.len() / 2],
        times[0],
        times[times.len() - 1]
    );
}
