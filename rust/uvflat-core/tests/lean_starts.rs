//! The mean value start without a general LU ([`mean_value::solve_lean`]): iterative
//! refinement on the Cholesky factorization of the system's symmetric part.
//!
//! Properties checked: the refinement converges on every test chart (holes, quads, pins) and
//! gives the LU's map to 1e-9; the map is flip-free; the start's looser solve
//! ([`mean_value::solve_start`]) is flip-free and near the LU map; large charts' barrier
//! starts use it with the LU map's energy, and SLIM from it never flips and never increases
//! its energy. Also
//! the staged choice of start ([`start::pick_staged`], which skips the mean value map when
//! LSCM is near an isometry) against the choice among both candidates.

mod common;

use common::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::mean_value;
use uvflat_core::methods::nonlinear::energy::{scale_optimally, symmetric_dirichlet};
use uvflat_core::methods::nonlinear::start;
use uvflat_core::methods::nonlinear::TriangleOperators;
use uvflat_core::methods::slim::{self, SlimOptions};
use uvflat_core::methods::BoundaryShape;

const MESHES: &[&str] = &["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off", "3holes.off"];

fn charts_of(s: &Soup, seams: &[[u32; 2]]) -> Vec<Chart> {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, seams, None)
}

/// A disk lifted onto a smooth non-developable height field (curved: unequal mean value
/// weights in the two directions of an edge).
fn bumpy_disk(rings: usize, per_ring: usize) -> Soup {
    let mut s = planar_disk(rings, per_ring);
    let scale = rings as f64 / 10.0;
    for p in s.positions.iter_mut() {
        let (x, y) = (p[0] / scale, p[1] / scale);
        p[2] = scale * (3.0 * (-(x * x + y * y) / 20.0).exp() + 0.4 * (0.7 * x).sin());
    }
    s
}

/// A disk lifted onto a paraboloid four times as deep as the disk is wide: a cup, far from
/// developable (its conformal map shrinks the bottom against the rim).
fn cup(rings: usize, per_ring: usize) -> Soup {
    let mut s = planar_disk(rings, per_ring);
    let r_max = s.positions.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
    for p in s.positions.iter_mut() {
        p[2] = 8.0 * (p[0] * p[0] + p[1] * p[1]) / r_max;
    }
    s
}

/// Smallest doubled signed area of the chart's triangles under `uv`.
fn least_area(chart: &Chart, uv: &[[f64; 2]]) -> f64 {
    common::doubled_signed_areas(&chart.triangles, uv).into_iter().fold(f64::INFINITY, f64::min)
}

fn max_difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs())).fold(0.0, f64::max)
}

/// Every disk chart (with or without holes) of the synthetic cases and the shared meshes.
fn disk_charts() -> Vec<(String, Chart)> {
    let (cyl, seams) = cut_cylinder(48, 12, 2.0);
    let mut soups = vec![
        ("bumpy_disk".to_string(), bumpy_disk(10, 7), vec![]),
        ("cup".to_string(), cup(10, 7), vec![]),
        ("cut_cylinder (quads)".to_string(), cyl, seams),
    ];
    match shared_meshes() {
        Some(dir) => {
            for f in MESHES {
                soups.push((f.to_string(), load(&dir.join(f)), vec![]));
            }
        }
        None => eprintln!("shared meshes absent: checking the synthetic charts only"),
    }
    let mut out = Vec::new();
    for (name, s, seams) in soups {
        for (i, c) in charts_of(&s, &seams).into_iter().enumerate() {
            if c.defect.is_none() && !c.boundary_loops.is_empty() && c.triangles.len() >= 8 {
                out.push((format!("{name} chart {i}"), c));
            }
        }
    }
    out
}

#[test]
fn refinement_converges_to_the_lu_mean_value_map_without_flips() {
    let charts = disk_charts();
    assert!(!charts.is_empty());
    for (name, chart) in &charts {
        let lu = mean_value::solve(chart, &[], BoundaryShape::Circle).unwrap().uv;
        let refined = mean_value::solve_by_refinement(chart, &[]).unwrap().unwrap_or_else(|| panic!("{name}: refinement did not converge"));
        let d = max_difference(&lu, &refined.uv);
        assert!(d < 1e-9, "{name}: refined map differs from the LU map by {d:e}");
        assert!(least_area(chart, &refined.uv) > 0.0, "{name}: the refined mean value map flips a triangle");
    }
}

/// The start's loose solve ([`mean_value::solve_start`]) on every test chart: flip-free, its
/// outline clean and its quads convex (checked, else solved again to full accuracy), and the
/// LU's map to the accuracy a start needs.
#[test]
fn the_start_solve_is_flip_free_and_near_the_lu_map() {
    let charts = disk_charts();
    for (name, chart) in &charts {
        let lu = mean_value::solve(chart, &[], BoundaryShape::Circle).unwrap().uv;
        let start = mean_value::solve_start(chart, &[]).unwrap().uv;
        let d = max_difference(&lu, &start);
        assert!(d < 1e-4, "{name}: start differs from the LU map by {d:e}");
        assert!(least_area(chart, &start) > 0.0, "{name}: the start flips a triangle");
        assert_eq!(uvflat_core::methods::nonconvex_quads(chart, &start), 0, "{name}: a quad is not convex");
    }
}

#[test]
fn refinement_honours_pins_like_the_lu_solve() {
    for (name, chart) in disk_charts().iter().take(4) {
        let lu0 = mean_value::solve(chart, &[], BoundaryShape::Circle).unwrap().uv;
        // Two pins a little away from the free map: the map is moved onto them and solved
        // again with them fixed.
        let (a, b) = (0u32, (chart.positions.len() / 2) as u32);
        let pins = [(a, [lu0[a as usize][0] + 0.01, lu0[a as usize][1]]), (b, [lu0[b as usize][0], lu0[b as usize][1] - 0.02])];
        let lu = mean_value::solve(chart, &pins, BoundaryShape::Circle).unwrap();
        let refined = mean_value::solve_by_refinement(chart, &pins).unwrap().unwrap_or_else(|| panic!("{name}: no convergence with pins"));
        let d = max_difference(&lu.uv, &refined.uv);
        assert!(d < 1e-9, "{name}: pinned refined map differs from the LU map by {d:e}");
        for (v, p) in pins {
            assert_eq!(refined.uv[v as usize], p, "{name}: pin {v} moved");
        }
    }
}

#[test]
fn large_charts_start_from_the_lean_map_and_slim_keeps_it_flip_free() {
    // About 100k triangles: above the size from which the barrier methods' mean value start
    // is solved without LU.
    let s = bumpy_disk(120, 7);
    let chart = charts_of(&s, &[]).remove(0);
    assert!(chart.triangles.len() >= start::SEQUENTIAL_STARTS_FROM, "{} triangles", chart.triangles.len());
    let lean = start::mean_value_start(&chart, &[]).unwrap().uv;
    let lu = mean_value::solve(&chart, &[], BoundaryShape::Circle).unwrap().uv;
    // Solved to the start's accuracy ([`mean_value::START_TOLERANCE`]) on a unit circle: the
    // map, and the energy the barrier methods start from, are the LU's to a few digits.
    let d = max_difference(&lu, &lean);
    assert!(d < 1e-5, "large chart: start differs from the LU map by {d:e}");
    assert!(least_area(&chart, &lean) > 0.0);
    let ops = TriangleOperators::new(&chart.positions, &chart.triangles);
    let energy = |uv: &[[f64; 2]]| {
        let mut uv = uv.to_vec();
        scale_optimally(&ops, &chart.triangles, &mut uv);
        symmetric_dirichlet(&ops, &chart.triangles, &uv)
    };
    let (e_lean, e_lu) = (energy(&lean), energy(&lu));
    assert!((e_lean - e_lu).abs() <= 1e-6 * e_lu, "start energy {e_lean} against the LU map's {e_lu}");
    let (sol, history) = slim::solve_with_history(&chart, &[], &SlimOptions { max_iterations: 3, ..Default::default() }).unwrap();
    assert!(sol.fallback.is_none());
    assert!(least_area(&chart, &sol.uv) > 0.0, "SLIM flipped a triangle");
    assert!(history.energy.windows(2).all(|w| w[1] <= w[0]), "energy increased: {:?}", history.energy);
}

/// On a large chart, work given to the staged start (SLIM's analysis of its global step) runs
/// on the calling thread, beside the mean value map or after LSCM alone, and does not change
/// the start; SLIM's map is the same with one thread and two.
#[test]
fn work_beside_a_large_start_changes_nothing() {
    let s = bumpy_disk(120, 7);
    let chart = charts_of(&s, &[]).remove(0);
    assert!(chart.triangles.len() >= start::SEQUENTIAL_STARTS_FROM, "{} triangles", chart.triangles.len());
    let ops = TriangleOperators::new(&chart.positions, &chart.triangles);
    let tris = &chart.triangles;
    let prepare = |uv: &mut Vec<[f64; 2]>| scale_optimally(&ops, tris, uv);
    let assess = |uv: &[[f64; 2]]| {
        let e = symmetric_dirichlet(&ops, tris, uv);
        if least_area(&chart, uv) > 0.0 && e.is_finite() { Ok(e) } else { Err("flips".to_string()) }
    };
    // With LSCM (the work after it, or beside the mean value map when LSCM is not good
    // enough) and without (beside the mean value map).
    for with_lscm in [true, false] {
        let alone = start::pick_staged(&chart, &[], with_lscm, &mut Vec::new(), prepare, assess, None::<fn()>);
        assert!(alone.1.is_none());
        let caller = std::thread::current().id();
        let work = || std::thread::current().id();
        let beside = start::pick_staged(&chart, &[], with_lscm, &mut Vec::new(), prepare, assess, Some(work));
        assert_eq!(beside.1, Some(caller), "with_lscm {with_lscm}: the work ran elsewhere or not at all");
        let (a, b) = (alone.0.expect("a start"), beside.0.expect("a start"));
        assert_eq!((a.1, a.2), (b.1, b.2), "with_lscm {with_lscm}");
        assert!(max_difference(&a.0, &b.0) == 0.0, "with_lscm {with_lscm}");
    }
    // Factorizations sequential, as `unwrap` has them (faer's parallel kernels sum in an order
    // that depends on the threads).
    // The setting is global: restored for the other tests of this file.
    let before = faer::get_global_parallelism();
    faer::set_global_parallelism(faer::Par::Seq);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| slim::solve(&chart, &[], &SlimOptions { max_iterations: 3, ..Default::default() }).unwrap())
    };
    let (one, two) = (run(1), run(2));
    faer::set_global_parallelism(before);
    assert!(one.fallback.is_none() && least_area(&chart, &two.uv) > 0.0);
    let d = max_difference(&one.uv, &two.uv);
    assert!(d == 0.0, "SLIM's map depends on the threads: {d:e}, {:?} / {:?}", one.note, two.note);
}

/// The staged start equals the choice among both candidates, except where it keeps a good
/// enough LSCM without computing the mean value map: then it is within `LSCM_GOOD_ENOUGH` of
/// that choice's energy (every energy is at least 1), and on these charts it is that choice.
/// A developable chart (the cut cylinder) takes the staged shortcut, a deep cup does not.
#[test]
fn staged_start_is_the_better_candidate_or_near_isometric_lscm() {
    let charts = disk_charts();
    let mut shortcuts = Vec::new();
    for (name, chart) in &charts {
        let ops = TriangleOperators::new(&chart.positions, &chart.triangles);
        let tris = &chart.triangles;
        let prepare = |uv: &mut Vec<[f64; 2]>| scale_optimally(&ops, tris, uv);
        let assess = |uv: &[[f64; 2]]| {
            let e = symmetric_dirichlet(&ops, tris, uv);
            if least_area(chart, uv) > 0.0 && e.is_finite() { Ok(e) } else { Err("flips".to_string()) }
        };
        let (candidates, mut rejected) = start::candidate_starts(chart, &[], true);
        let both = start::pick(chart, candidates, &mut rejected, prepare, assess).expect("a valid start");
        let staged = start::pick_staged(chart, &[], true, &mut Vec::new(), prepare, assess, None::<fn()>).0;
        let staged = staged.expect("a valid start");
        assert!(both.1 >= 1.0 - 1e-9 && staged.1 >= 1.0 - 1e-9, "{name}: energies {} {}", both.1, staged.1);
        let n = chart.triangles.len();
        let side_by_side = (start::SIDE_BY_SIDE_FROM..start::SEQUENTIAL_STARTS_FROM).contains(&n);
        if staged.2 == "lscm" && staged.1 <= start::LSCM_GOOD_ENOUGH && !side_by_side {
            assert!(staged.1 <= start::LSCM_GOOD_ENOUGH * both.1, "{name}: {} against {}", staged.1, both.1);
            assert_eq!(both.2, "lscm", "{name}: the mean value map was better ({} against {})", both.1, staged.1);
            shortcuts.push(name.clone());
        } else {
            assert_eq!(staged.2, both.2, "{name}");
            assert_eq!(staged.1, both.1, "{name}");
            assert!(max_difference(&staged.0, &both.0) == 0.0, "{name}");
        }
    }
    assert!(shortcuts.iter().any(|n| n.starts_with("cut_cylinder")), "the developable chart takes the shortcut: {shortcuts:?}");
    assert!(!shortcuts.iter().any(|n| n.starts_with("cup")), "the curved chart computes both: {shortcuts:?}");
}
