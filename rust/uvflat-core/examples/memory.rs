//! Peak memory and time of one unwrap of a large disk chart:
//! `cargo run --release --example memory -- METHOD TRIANGLES|MESH.off [SLIM_ITERATIONS]`.
//!
//! METHOD is `lscm`, `abf` or `slim`. The mesh is a mesh file (OFF/OBJ), or the hexagonal disk of
//! `blender_scripts/scaling.py` (`6 R²` triangles, lifted onto `z = 0.3 r²`). Prints wall and
//! CPU seconds of the unwrap, the chart's status and note, and the peak resident memory
//! (VmHWM) in MB and KB per triangle. Built with the system allocator, so a heap profiler
//! (e.g. `heaptrack`) can attribute the peak to its allocations.

#[path = "../tests/common/mod.rs"]
mod common;

use std::f64::consts::PI;
use std::time::Instant;

use uvflat_core::methods::slim::SlimOptions;
use uvflat_core::{unwrap, MeshInput, Method, UnwrapOptions};

/// The hexagonal disk of `6 R²` triangles nearest to `triangles` (as `scaling.py`).
fn disk(triangles: usize) -> (Vec<[f64; 3]>, Vec<u32>) {
    let rings = ((triangles as f64 / 6.0).sqrt().round() as usize).max(1);
    let mut pos = vec![[0.0, 0.0, 0.0]];
    for k in 1..=rings {
        let r = k as f64 / rings as f64;
        for j in 0..6 * k {
            let a = 2.0 * PI * j as f64 / (6 * k) as f64;
            pos.push([r * a.cos(), r * a.sin(), 0.3 * r * r]);
        }
    }
    let mut tris = Vec::with_capacity(6 * rings * rings * 3);
    for k in 1..=rings {
        let outer0 = 1 + 3 * k * (k - 1);
        let inner0 = if k > 1 { 1 + 3 * (k - 1) * (k - 2) } else { 0 };
        for s in 0..6 {
            for i in 0..k {
                let o = outer0 + s * k + i;
                let o_next = outer0 + (s * k + i + 1) % (6 * k);
                let inner = if k == 1 { 0 } else { inner0 + (s * (k - 1) + i) % (6 * (k - 1)) };
                tris.extend([o as u32, o_next as u32, inner as u32]);
            }
        }
        if k > 1 {
            for s in 0..6 {
                for i in 0..k - 1 {
                    let a_in = inner0 + (s * (k - 1) + i) % (6 * (k - 1));
                    let b_in = inner0 + (s * (k - 1) + i + 1) % (6 * (k - 1));
                    let o_mid = outer0 + (s * k + i + 1) % (6 * k);
                    tris.extend([a_in as u32, o_mid as u32, b_in as u32]);
                }
            }
        }
    }
    (pos, tris)
}

fn main() {
    let method = std::env::args().nth(1).unwrap_or_else(|| "abf".into());
    let mesh = std::env::args().nth(2).unwrap_or_else(|| "200000".into());
    let slim_iterations: usize = std::env::args().nth(3).map(|a| a.parse().expect("iterations")).unwrap_or(20);
    let (positions, corner_verts, face_sizes) = match mesh.parse::<usize>() {
        Ok(n) => {
            let (p, c) = disk(n);
            let f = vec![3u32; c.len() / 3];
            (p, c, f)
        }
        Err(_) => {
            let s = common::load(std::path::Path::new(&mesh));
            (s.positions, s.corner_verts, s.face_sizes)
        }
    };
    let method = match method.as_str() {
        "lscm" => Method::Lscm,
        "abf" => Method::Abf(Default::default()),
        "slim" => Method::Slim(SlimOptions { max_iterations: slim_iterations, tolerance: 0.0, ..Default::default() }),
        other => panic!("unknown method {other}"),
    };
    let input = MeshInput { positions: &positions, corner_verts: &corner_verts, face_sizes: &face_sizes, ..Default::default() };
    let t = Instant::now();
    let cpu0 = common::cpu_seconds();
    let r = unwrap(&input, &UnwrapOptions { method, ..Default::default() }).expect("unwrap");
    let (dt, dcpu) = (t.elapsed().as_secs_f64(), common::cpu_seconds() - cpu0);
    let c = &r.charts[0];
    println!("{} charts, iterations {:?}", r.charts.len(), r.charts.iter().map(|c| c.iterations).collect::<Vec<_>>());
    println!(
        "{} triangles: {dt:.3} s (cpu {dcpu:.3} s), {:?}, {} iterations, residual {:.3e}, flips {}, reason {:?}",
        face_sizes.len(),
        c.status,
        c.iterations,
        c.residual,
        c.flips,
        c.reason
    );
    // A digest of the UVs, to compare runs bit for bit.
    let digest = r.uv.iter().flatten().fold(0u64, |h, x| (h ^ x.to_bits()).wrapping_mul(0x100000001b3));
    println!("uv digest {digest:016x}");
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    if let Some(kb) = status.lines().find(|l| l.starts_with("VmHWM")).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok()) {
        println!("peak memory {:.1} MB, {:.3} KB/triangle", kb / 1024.0, kb / face_sizes.len() as f64);
    }
}

