//! Time `unwrap` on a mesh with many charts (e.g. ../shared/meshes/cube_40k.obj, whose
//! non-manifold edges split it into tens of thousands of tiny charts, or the same mesh with
//! the seams of Blender's Smart UV Project):
//! `cargo run --release --example many_charts -- MESH [METHOD] [REPEATS] [SEAMS]`, where the
//! optional SEAMS file holds one seam per line as two 0-based vertex indices. Prints the
//! median, minimum and maximum wall-clock seconds and the median CPU seconds of a call.
//! Allocator: mimalloc, as in the Python extension (glibc's heaps grow and trim around the
//! millions of small blocks that tens of thousands of charts allocate).
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use uvflat_core::{unwrap, Method, UnwrapOptions};

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("mesh path");
    let method = args.next().unwrap_or_else(|| "lscm".into());
    let repeats: usize = args.next().map(|r| r.parse().unwrap()).unwrap_or(5);
    let seams: Vec<[u32; 2]> = args
        .next()
        .map(|f| {
            std::fs::read_to_string(&f)
                .expect("seams file")
                .lines()
                .filter(|l| !l.trim().is_empty())
                .map(|l| {
                    let v: Vec<u32> = l.split_whitespace().map(|x| x.parse().expect("vertex index")).collect();
                    [v[0], v[1]]
                })
                .collect()
        })
        .unwrap_or_default();
    let s = common::load(std::path::Path::new(&path));
    let options = UnwrapOptions { method: Method::parse(&method, &[]).expect("method name"), ..Default::default() };
    let mut times = Vec::new();
    let mut cpu = Vec::new();
    let mut n_charts = 0;
    for _ in 0..repeats {
        let (t, c) = (Instant::now(), common::cpu_seconds());
        let r = unwrap(&uvflat_core::MeshInput { seams: &seams, ..s.input() }, &options).unwrap();
        times.push(t.elapsed().as_secs_f64());
        cpu.push(common::cpu_seconds() - c);
        n_charts = r.charts.len();
    }
    times.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    println!(
        "{path}: {n_charts} charts, {method}, threads {}: median {:.4} s (min {:.4}, max {:.4}), CPU {:.4} s",
        rayon::current_num_threads(),
        times[times.len() / 2],
        times[0],
        times[times.len() - 1],
        cpu[cpu.len() / 2]
    );
}
