//! ABF on charts with holes: the holes are left open, and the angles are solved a second time
//! with the holes filled only when that can fold less (flipped triangles, or a crossing that
//! is not the outer loop crossing itself). Analytic and property checks, no snapshot numbers.

mod common;

use common::*;
use proptest::prelude::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::methods::abf::{self, AbfOptions};
use uvflat_core::methods::{fixed_boundary, lscm};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::metrics::{boundary_self_overlap, count_flips};
use uvflat_core::ChartKind;

const FILLED_NOTE: &str = "holes filled by virtual fans";

/// The holed charts of a mesh.
fn holed_charts(s: &Soup) -> Vec<Chart> {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, &[], None)
        .into_iter()
        .filter(|c| c.defect.is_none() && c.kind == ChartKind::DiskWithHoles)
        .collect()
}

/// A grid of `nu × nv` quads (each split into two triangles) over the parameter rectangle,
/// placed in 3D by `f(u, v)` with u, v in [0, 1], without the quads for which `hole(i, j)`.
fn grid(nu: usize, nv: usize, f: impl Fn(f64, f64) -> [f64; 3], hole: impl Fn(usize, usize) -> bool) -> Soup {
    let mut positions = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            positions.push(f(i as f64 / nu as f64, j as f64 / nv as f64));
        }
    }
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut corner_verts = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            if !hole(i, j) {
                corner_verts.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                corner_verts.extend([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    let face_sizes = vec![3u32; corner_verts.len() / 3];
    Soup { positions, corner_verts, face_sizes }
}

/// How a map of `chart` folds: flipped triangles, boundary crossing.
fn folds(chart: &Chart, uv: &[[f64; 2]]) -> (usize, bool) {
    (count_flips(&chart.triangles, uv), boundary_self_overlap(uv, &chart.boundary_loops))
}

/// The map with the holes open and the map with them filled, each with its angle solve's
/// Newton iterations, or `None` for a path whose angle solve did not converge.
type Path = Option<(Vec<[f64; 2]>, usize)>;
fn both_paths(chart: &Chart, opts: &AbfOptions) -> (Path, Path) {
    let valid = |a: &abf::AbfAngles| a.converged && a.alpha.iter().flatten().all(|&x| x > 0.0 && x < std::f64::consts::PI);
    let open = abf::solve_angles(chart, opts).ok().filter(valid).map(|a| {
        let (uv, _) = lscm::solve_with_angles(chart, &a.alpha, &[]).unwrap();
        (uv, a.iterations)
    });
    let filled_chart = fixed_boundary::filled_chart(chart);
    let filled = abf::solve_angles(&filled_chart, opts).ok().filter(valid).map(|a| {
        let (uv, _) = lscm::solve_with_angles(chart, &a.alpha[..chart.triangles.len()], &[]).unwrap();
        (uv, a.iterations)
    });
    (open, filled)
}

/// A strip winding one and a half turns around an axis with a small pitch (nearly a planar
/// annulus sector of 3π), with a hole in its middle: its flattening has no flipped triangle,
/// but the outline overlaps itself, and closing the hole cannot change that. The chart is
/// solved once, with the hole open, and carries no holes-filled note.
#[test]
fn outer_loop_crossing_itself_is_not_solved_again() {
    let turns = 3.0 * std::f64::consts::PI;
    let s = grid(
        60,
        6,
        |u, v| {
            let (a, r) = (turns * u, 1.0 + v);
            [r * a.cos(), r * a.sin(), 0.05 * a]
        },
        |i, j| (28..32).contains(&i) && (2..4).contains(&j),
    );
    let charts = holed_charts(&s);
    assert_eq!(charts.len(), 1);
    let chart = &charts[0];
    assert_eq!(chart.boundary_loops.len(), 2);
    let opts = AbfOptions::default();
    let (open, filled) = both_paths(chart, &opts);
    let (open_uv, open_iterations) = open.expect("open solve converges");
    // The case: no flip, the outer loop alone crosses itself ...
    assert_eq!(folds(chart, &open_uv), (0, true));
    let outer = chart.outer_loop().unwrap();
    assert!(boundary_self_overlap(&open_uv, &chart.boundary_loops[outer..=outer]));
    assert!(!lscm::filling_may_help(chart, &open_uv, (0, true)));
    // ... and with the hole filled it still does: a second solve would be wasted.
    let (filled_uv, _) = filled.expect("filled solve converges");
    assert!(folds(chart, &filled_uv) >= folds(chart, &open_uv));
    let sol = abf::solve(chart, &[], &opts).unwrap();
    assert!(sol.fallback.is_none());
    assert_eq!(sol.iterations, open_iterations, "only the open solve ran");
    assert!(!sol.note.as_deref().unwrap_or("").contains(FILLED_NOTE), "{:?}", sol.note);
    assert_eq!(sol.uv, open_uv);
}

/// halftunnel: with open holes the map has flipped triangles, so the angles are solved again
/// with the holes filled, that map is kept (it folds less), and the report says so: the note
/// names the open map's flips, the iterations are those of both solves, the residual that of
/// the filled solve.
#[test]
fn flipped_open_map_is_solved_with_holes_filled_and_reported() {
    let Some(dir) = shared_meshes() else { return };
    let s = load(&dir.join("halftunnel.off"));
    let charts = holed_charts(&s);
    assert_eq!(charts.len(), 1);
    let chart = &charts[0];
    let opts = AbfOptions::default();
    let (open, filled) = both_paths(chart, &opts);
    let (open_uv, open_iterations) = open.expect("open solve converges");
    let (filled_uv, filled_iterations) = filled.expect("filled solve converges");
    let open_folds = folds(chart, &open_uv);
    assert!(open_folds.0 > 0, "the open map folds: {open_folds:?}");
    assert!(folds(chart, &filled_uv) < open_folds);
    assert!(lscm::filling_may_help(chart, &open_uv, open_folds));
    let sol = abf::solve(chart, &[], &opts).unwrap();
    let note = sol.note.as_deref().unwrap_or("");
    assert!(note.starts_with(FILLED_NOTE), "{note}");
    assert!(note.contains(&format!("{} flipped triangle(s)", open_folds.0)), "{note}");
    assert_eq!(sol.iterations, open_iterations + filled_iterations);
    assert!(sol.residual < opts.tolerance);
    assert_eq!(sol.uv, filled_uv);
}

/// A random holed chart: a grid with one or two rectangular holes, either bumpy (Gaussians of
/// random height and width placed at random, some tall and narrow: holes on hills enclose
/// much curvature) or wound around an axis by `turns` half turns with a pitch (a strip whose
/// flattening may overlap itself).
fn random_holed_grid(wind: Option<(f64, f64)>, bumps: &[(f64, f64, f64, f64)], holes: &[(usize, usize, usize, usize)]) -> Soup {
    let (nu, nv) = if wind.is_some() { (40, 8) } else { (14, 14) };
    grid(
        nu,
        nv,
        |u, v| {
            let z: f64 = bumps.iter().map(|&(x, y, h, w)| h * (-((u - x).powi(2) + (v - y).powi(2)) / (w * w)).exp()).sum();
            match wind {
                None => [u, v, z],
                Some((turns, pitch)) => {
                    let (a, r) = (turns * std::f64::consts::PI * u, 1.0 + v + 0.3 * z);
                    [r * a.cos(), r * a.sin(), pitch * a]
                }
            }
        },
        |i, j| holes.iter().any(|&(i0, j0, di, dj)| (i0..i0 + di).contains(&i) && (j0..j0 + dj).contains(&j) && i < nu - 1 && j < nv - 1),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// On random holed charts the map `abf::solve` returns never has more flipped triangles
    /// than the other path (holes open or holes filled, whichever it did not return), never
    /// folds more than the open map, and is the same on a second run.
    #[test]
    fn chosen_path_never_flips_more_than_the_other(
        wind in prop::option::of((1.0f64..3.5, 0.0f64..0.3)),
        bumps in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, -6.0f64..6.0, 0.05f64..0.3), 1..5),
        holes in prop::collection::vec((1usize..10, 1usize..6, 1usize..4, 1usize..3), 1..3),
    ) {
        let s = random_holed_grid(wind, &bumps, &holes);
        let opts = AbfOptions::default();
        for chart in holed_charts(&s) {
            let sol = abf::solve(&chart, &[], &opts).unwrap();
            if sol.fallback.is_some() {
                continue;
            }
            let (open, filled) = both_paths(&chart, &opts);
            let chosen = folds(&chart, &sol.uv);
            if let Some((uv, _)) = &open {
                prop_assert!(chosen <= folds(&chart, uv), "chosen {:?}, open {:?}", chosen, folds(&chart, uv));
                prop_assert!(chosen.0 <= count_flips(&chart.triangles, uv));
            }
            if let Some((uv, _)) = &filled {
                prop_assert!(chosen.0 <= count_flips(&chart.triangles, uv), "chosen {:?}, filled {:?}", chosen, folds(&chart, uv));
            }
            let again = abf::solve(&chart, &[], &opts).unwrap();
            prop_assert_eq!(&again.uv, &sol.uv);
            prop_assert_eq!(again.iterations, sol.iterations);
        }
    }
}
