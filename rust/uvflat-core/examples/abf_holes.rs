//! ABF on a mesh cut into many charts, some of them with holes: per chart the holes, the
//! triangles, the cost of the angle solve with holes open and with holes filled, and whether
//! each layout folds; then `unwrap` with `abf` end to end (wall and CPU medians) and the
//! quality of the whole result.
//!
//! `cargo run --release --example abf_holes -- MESH.off SEAMS.txt [REPEATS] [all|profile]`
//!
//! SEAMS.txt holds one seam edge per line, two vertex indices (e.g. the seams Blender's Smart
//! UV Project makes on camelhead, marked from its islands and saved with `numpy.savetxt`).
//! With the `bpy` module and `blender_scripts/` on `sys.path` (as `benchmark.py` cuts
//! `camelhead_smart`):
//!
//! ```text
//! import common, benchmark, numpy as np
//! common.reset_scene(); common.load_addon()
//! obj = benchmark.smart_cut(common.load_mesh_object(common.SHARED_MESHES / "camelhead.off"))
//! me = obj.data; ev = np.zeros(2 * len(me.edges), int); me.edges.foreach_get("vertices", ev)
//! seam = np.zeros(len(me.edges), bool); me.edges.foreach_get("use_seam", seam)
//! np.savetxt("/tmp/camelhead_smart_seams.txt", ev.reshape(-1, 2)[seam], fmt="%d")
//! ```
//!
//! (an OFF file keeps its vertex order in Blender, so the indices are the file's).
//! Per-chart lines are printed for charts with holes (`all`: every chart): Newton iterations,
//! factorizations, seconds (fastest of five), flipped triangles, boundary crossing and outer
//! loop crossing itself of each map, the ABF energy Σ ((α − β)/β)² of each, and what
//! `abf::solve` chose; then the angle solves, Newton steps and factorizations of all charts
//! with the filled solve run on any fold and only where it may help. Set `RAYON_NUM_THREADS=1`
//! for CPU-time comparisons on a shared machine. `profile`: only `abf::solve` on every chart,
//! REPEATS times (for `perf record`).
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::abf::{self, AbfOptions};
use uvflat_core::methods::{fixed_boundary, lscm};
use uvflat_core::metrics::{boundary_self_overlap, count_flips, measure};
use uvflat_core::{unwrap, Method, UnwrapOptions};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("mesh path");
    let seams_path = args.next().expect("seams file");
    let repeats: usize = args.next().map(|r| r.parse().expect("repeats")).unwrap_or(5);
    let mode = args.next().unwrap_or_default();
    let all = mode == "all";
    let s = common::load(std::path::Path::new(&path));
    let seams: Vec<[u32; 2]> = std::fs::read_to_string(&seams_path)
        .expect("seams file")
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f64>().expect("vertex index") as u32);
            Some([it.next()?, it.next()?])
        })
        .collect();
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &seams, None);
    let opts = AbfOptions::default();
    if mode == "profile" {
        // Only `abf::solve` on every chart, `repeats` times (for perf).
        let mut cpu = Vec::new();
        for _ in 0..repeats {
            let c0 = common::cpu_seconds();
            for c in charts.iter().filter(|c| c.defect.is_none() && !c.boundary_loops.is_empty()) {
                std::hint::black_box(abf::solve(c, &[], &opts).expect("solve"));
            }
            cpu.push(common::cpu_seconds() - c0);
        }
        cpu.sort_by(f64::total_cmp);
        println!("abf::solve on every chart: cpu median {:.4} s per pass (min {:.4})", cpu[cpu.len() / 2], cpu[0]);
        return;
    }
    println!("{} faces, {} seams, {} charts", s.face_sizes.len(), seams.len(), charts.len());
    println!(
        "chart  tris holes | open: it fact  s      flips ovl outer | filled: it fact  s      flips ovl outer | energy open filled | layout s folds s | solve(): s     note"
    );
    let (mut t_open, mut t_filled, mut t_solve) = (0.0, 0.0, 0.0);
    let (mut n_folded, mut n_holed) = (0, 0);
    // Deterministic work: [angle solves, Newton steps, factorizations] of every chart's open
    // solve, plus the filled solve where any fold triggers it and where `filling_may_help` does.
    let (mut work_any_fold, mut work_may_help) = ([0usize; 3], [0usize; 3]);
    for (i, c) in charts.iter().enumerate() {
        if c.defect.is_some() || c.boundary_loops.is_empty() {
            continue;
        }
        let holes = c.boundary_loops.len() - 1;
        let outer = c.outer_loop().expect("a boundary");
        // Flipped triangles, any boundary crossing, the outer loop crossing itself.
        let folds = |uv: &[[f64; 2]]| {
            let outer_crosses = boundary_self_overlap(uv, &c.boundary_loops[outer..=outer]);
            (count_flips(&c.triangles, uv), boundary_self_overlap(uv, &c.boundary_loops), outer_crosses)
        };
        let beta = abf::target_angles(c);
        let energy = |a: &[[f64; 3]]| a.iter().flatten().zip(beta.iter().flatten()).map(|(x, y)| ((x - y) / y).powi(2)).sum::<f64>();
        let (d_open, open) = fastest(|| abf::solve_angles(c, &opts).expect("open solve"));
        let (d_lay, (uv, _)) = fastest(|| lscm::solve_with_angles(c, &open.alpha, &[]).expect("layout"));
        let (d_folds, f_open) = fastest(|| folds(&uv));
        // The filled solve (it may fail: a reduced system that is not positive definite).
        let filled = fixed_boundary::filled_chart(c);
        let (d_filled, fa) = fastest(|| abf::solve_angles(&filled, &opts).ok());
        let filled_row = match &fa {
            Some(fa) => {
                let alpha = &fa.alpha[..c.triangles.len()];
                let (uv, _) = lscm::solve_with_angles(c, alpha, &[]).expect("layout");
                let f = folds(&uv);
                let e = energy(alpha);
                (format!("{:3} {:3} {d_filled:.4} {:5} {:5} {:5}", fa.iterations, fa.factorizations, f.0, f.1, f.2), e)
            }
            None => ("failed".to_string(), f64::NAN),
        };
        let (d_solve, sol) = fastest(|| abf::solve(c, &[], &opts).expect("solve"));
        t_solve += d_solve;
        let open_work = [1, open.iterations, open.factorizations];
        let filled_work = fa.as_ref().map_or([1, 0, 0], |fa| [1, fa.iterations, fa.factorizations]);
        let any_fold = holes > 0 && (f_open.0, f_open.1) != (0, false);
        let may_help = holes > 0 && lscm::filling_may_help(c, &uv, (f_open.0, f_open.1));
        for k in 0..3 {
            work_any_fold[k] += open_work[k] + if any_fold { filled_work[k] } else { 0 };
            work_may_help[k] += open_work[k] + if may_help { filled_work[k] } else { 0 };
        }
        if holes > 0 {
            n_holed += 1;
            t_open += d_open;
            t_filled += d_filled;
            n_folded += usize::from((f_open.0, f_open.1) != (0, false));
        }
        if holes > 0 || all {
            println!(
                "{i:5} {:5} {holes:5} | {:3} {:3} {d_open:.4} {:5} {:5} {:5} | {} | {:.3e} {:.3e} | {d_lay:.4} {d_folds:.4} | {d_solve:.4} {:?}",
                c.triangles.len(),
                open.iterations,
                open.factorizations,
                f_open.0,
                f_open.1,
                f_open.2,
                filled_row.0,
                energy(&open.alpha),
                filled_row.1,
                sol.note.as_deref().map(|n| &n[..n.len().min(60)])
            );
        }
    }
    println!(
        "holed charts {n_holed} (open layout folds on {n_folded}): open {t_open:.4} s, filled {t_filled:.4} s; abf::solve on all charts {t_solve:.4} s"
    );
    println!(
        "[angle solves, Newton steps, factorizations]: filled solve on any fold {work_any_fold:?}, filled solve where it may help {work_may_help:?}"
    );
    let options = UnwrapOptions { method: Method::Abf(opts), ..Default::default() };
    let input = uvflat_core::MeshInput { seams: &seams, ..s.input() };
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut result = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let c0 = common::cpu_seconds();
        result = Some(unwrap(&input, &options).unwrap());
        wall.push(t.elapsed().as_secs_f64());
        cpu.push(common::cpu_seconds() - c0);
    }
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    let r = result.expect("one run");
    let m = measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
    let notes = r.charts.iter().filter(|c| c.reason.as_deref().is_some_and(|n| n.contains("holes filled"))).count();
    let fallbacks = r.charts.iter().filter(|c| c.method != "abf" && c.method != "abf++").count();
    println!(
        "unwrap abf, threads {}: wall median {:.4} s (min {:.4}), cpu median {:.4} s (min {:.4}); {} charts, flips {}, overlapping {}, \
         conformal {:.6}, area {:.6}, mean |angle error| {:.6} rad, holes-filled notes {notes}, other methods {fallbacks}",
        rayon::current_num_threads(),
        wall[wall.len() / 2],
        wall[0],
        cpu[cpu.len() / 2],
        cpu[0],
        m.charts,
        m.flips,
        m.overlapping_charts,
        m.distortion.conformal,
        m.distortion.area,
        mean_angle_error(&s, &r.uv)
    );
    let per_chart: Vec<String> = r.charts.iter().map(|c| format!("{}:{}", c.id, c.flips)).filter(|x| !x.ends_with(":0")).collect();
    println!("charts with flips: {per_chart:?}");
}

/// The fastest of five runs of `f` (seconds) and its last result.
fn fastest<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..5 {
        let t = Instant::now();
        out = Some(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out.expect("five runs"))
}

/// Mean over the corners of the triangles of the mesh of |UV angle − 3D angle| (radians).
fn mean_angle_error(s: &common::Soup, uv: &[[f64; 2]]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    let mut start = 0usize;
    for &k in &s.face_sizes {
        let k = k as usize;
        if k == 3 {
            let p: Vec<[f64; 3]> = (0..3).map(|i| s.positions[s.corner_verts[start + i] as usize]).collect();
            let q: Vec<[f64; 3]> = (0..3).map(|i| [uv[start + i][0], uv[start + i][1], 0.0]).collect();
            for i in 0..3 {
                let a = angle(p[i], p[(i + 1) % 3], p[(i + 2) % 3]);
                let b = angle(q[i], q[(i + 1) % 3], q[(i + 2) % 3]);
                if a.is_finite() && b.is_finite() {
                    sum += (a - b).abs();
                    n += 1;
                }
            }
        }
        start += k;
    }
    sum / n.max(1) as f64
}

fn angle(o: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let u = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
    let v = [b[0] - o[0], b[1] - o[1], b[2] - o[2]];
    let dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let cr = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt().atan2(dot)
}

