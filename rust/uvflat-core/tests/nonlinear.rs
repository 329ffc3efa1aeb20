//! The nonlinear methods: ARAP (Liu et al. 2008) and SLIM (Rabinovich et al. 2017).
//!
//! Properties checked: SLIM never flips a triangle; the energies of both never increase from
//! one iteration to the next; developable surfaces flatten to an isometry; pins stay exactly
//! where they were pinned; every iterative method gives the same map on one thread as on two.

mod common;

use common::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::arap::{self, ArapOptions};
use uvflat_core::methods::slim::{self, SlimOptions, SlimStart, SlimStep};
use uvflat_core::{unwrap, ChartKind, ChartStatus, Method, OptionValue, UnwrapOptions};

const MESHES: &[&str] = &["camelhead.off", "lion.off", "alligator.obj", "beetle.off", "halftunnel.off"];

fn opts(method: Method) -> UnwrapOptions {
    UnwrapOptions { method, ..Default::default() }
}

/// The method alone on the chart as given: automatic seams off (nothing is cut).
fn uncut(method: Method) -> UnwrapOptions {
    let mut o = opts(method);
    o.auto_seams.enabled = false;
    o
}

/// A disk with a bump: planar disk lifted onto a smooth non-developable height field.
fn bumpy_disk() -> Soup {
    let mut s = planar_disk(10, 7);
    for p in s.positions.iter_mut() {
        p[2] = 3.0 * (-(p[0] * p[0] + p[1] * p[1]) / 20.0).exp() + 0.4 * (0.7 * p[0]).sin();
    }
    s
}

fn charts_of(s: &Soup, seams: &[[u32; 2]]) -> Vec<Chart> {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, seams, None)
}

fn synthetic() -> Vec<(&'static str, Soup, Vec<[u32; 2]>)> {
    let (cyl, seams) = cut_cylinder(48, 12, 2.0);
    vec![("planar_disk", planar_disk(8, 7), vec![]), ("cut_cylinder", cyl, seams), ("bumpy_disk", bumpy_disk(), vec![])]
}

#[test]
fn slim_never_flips_on_shared_meshes_and_synthetic_disks() {
    let mut cases: Vec<(String, Soup, Vec<[u32; 2]>)> =
        synthetic().into_iter().map(|(n, s, seams)| (n.to_string(), s, seams)).collect();
    if let Some(dir) = shared_meshes() {
        for f in MESHES {
            cases.push((f.to_string(), load(&dir.join(f)), vec![]));
        }
    }
    for (name, s, seams) in &cases {
        let mut input = s.input();
        input.seams = seams;
        let r = unwrap(&input, &uncut(Method::Slim(SlimOptions::default()))).unwrap();
        let mut disks = 0;
        for c in &r.charts {
            if matches!(c.kind, ChartKind::Disk | ChartKind::DiskWithHoles) {
                disks += 1;
                // SLIM never flips; an outline that crosses itself (no promise of SLIM's) is
                // reported invalid, never solved.
                let expected = if c.overlap { ChartStatus::Invalid } else { ChartStatus::Solved };
                assert_eq!(c.status, expected, "{name}: chart {}: {:?}", c.id, c.reason);
                assert_eq!(c.flips, 0, "{name}: chart {} ({} faces) flips", c.id, c.faces);
                // No iteration only when the start is already an isometry (the minimum).
                assert!(c.iterations >= 1 || c.distortion.symmetric_dirichlet <= 1.0 + 1e-9, "{name}: chart {}", c.id);
                assert!(c.distortion.symmetric_dirichlet.is_finite() && c.distortion.symmetric_dirichlet >= 1.0 - 1e-9);
            }
        }
        assert!(disks > 0, "{name}");
        // Stronger than the majority-based flip count: every triangle is positively oriented.
        for chart in charts_of(s, seams) {
            if matches!(chart.kind, ChartKind::Disk | ChartKind::DiskWithHoles) && chart.defect.is_none() {
                let sol = slim::solve(&chart, &[], &SlimOptions::default()).unwrap();
                assert!(sol.fallback.is_none());
                let neg = common::doubled_signed_areas(&chart.triangles, &sol.uv).iter().filter(|a| a.is_nan() || **a <= 0.0).count();
                assert_eq!(neg, 0, "{name}: {neg} non-positive triangles");
            }
        }
    }
}

#[test]
fn energies_never_increase_for_arap_and_slim() {
    let mut charts: Vec<(String, Chart)> = Vec::new();
    for (name, s, seams) in synthetic() {
        for c in charts_of(&s, &seams) {
            charts.push((name.to_string(), c));
        }
    }
    if let Some(dir) = shared_meshes() {
        for f in MESHES {
            let s = load(&dir.join(f));
            let c = charts_of(&s, &[])
                .into_iter()
                .filter(|c| matches!(c.kind, ChartKind::Disk | ChartKind::DiskWithHoles) && c.defect.is_none())
                .max_by_key(|c| c.triangles.len())
                .unwrap();
            charts.push((f.to_string(), c));
        }
    }
    for (name, chart) in &charts {
        let mut last = Vec::new();
        for (start, step) in [(SlimStart::Auto, SlimStep::Newton), (SlimStart::MeanValue, SlimStep::Newton), (SlimStart::MeanValue, SlimStep::Proxy)] {
            let o = SlimOptions { max_iterations: 15, tolerance: 0.0, start, step };
            let (sol, h) = slim::solve_with_history(chart, &[], &o).unwrap();
            last.push(*h.energy.last().unwrap());
            let optimal_start = h.energy[0] - 1.0 < 1e-9;
            assert!(h.energy.len() >= 2 || optimal_start, "{name}: SLIM made no progress from {}", h.energy[0]);
            assert_eq!(h.energy.len(), h.step.len() + 1);
            for w in h.energy.windows(2) {
                assert!(w[1] < w[0], "{name} {start:?}: SLIM energy rose {} -> {}", w[0], w[1]);
            }
            assert!(h.step.iter().all(|&t| t > 0.0 && t <= 1.0));
            // The reported energy is the energy of the returned map (on quad charts, over both
            // diagonal splits, each quad's four triangles at half weight).
            let (tris, w) = chart.triangles_both_splits();
            let mut ops = arap::TriangleOperators::new(&chart.positions, &tris);
            for (a, w) in ops.area.iter_mut().zip(&w) {
                *a *= w;
            }
            ops.total_area = ops.area.iter().sum();
            let e = slim::symmetric_dirichlet(&ops, &tris, &sol.uv);
            assert!((e - h.energy.last().unwrap()).abs() <= 1e-12 * e, "{name}");
        }
        // The projected Newton steps reach at least SLIM's own energy from the same start.
        assert!(last[1] <= last[2] * (1.0 + 1e-9), "{name}: Newton steps reached {} > SLIM's {}", last[1], last[2]);
        let o = ArapOptions { max_iterations: 15, tolerance: 0.0 };
        let (sol, h) = arap::solve_with_history(chart, &[], &o).unwrap();
        assert_eq!(h.len(), sol.iterations + 1);
        for w in h.windows(2) {
            assert!(w[1] <= w[0] * (1.0 + 1e-12) + 1e-15, "{name}: ARAP energy rose {} -> {}", w[0], w[1]);
        }
    }
}

#[test]
fn developable_surfaces_flatten_to_an_isometry() {
    let (cyl, seams) = cut_cylinder(48, 12, 2.0);
    let disk = planar_disk(8, 7);
    for (name, s, seams) in [("cut_cylinder", &cyl, &seams[..]), ("planar_disk", &disk, &[][..])] {
        let mut input = s.input();
        input.seams = seams;
        let slim_from_circle = SlimOptions { max_iterations: 500, tolerance: 1e-14, start: SlimStart::MeanValue, ..Default::default() };
        for m in [
            Method::Arap(ArapOptions::default()),
            Method::Slim(SlimOptions::default()),
            Method::Slim(slim_from_circle),
        ] {
            let r = unwrap(&input, &opts(m.clone())).unwrap();
            assert_eq!(r.charts.len(), 1);
            let c = &r.charts[0];
            assert_eq!(c.status, ChartStatus::Solved, "{name} {m:?}: {:?}", c.reason);
            assert_eq!(c.flips, 0, "{name} {m:?}");
            let d = c.distortion.symmetric_dirichlet;
            assert!((d - 1.0).abs() < 1e-6, "{name} {m:?}: symmetric Dirichlet {d}");
            assert!((c.distortion.area - 1.0).abs() < 1e-6, "{name} {m:?}: {:?}", c.distortion);
        }
        // Without area normalisation too: the methods find the isometric scale themselves.
        let chart = &charts_of(s, seams)[0];
        let (_, h) = arap::solve_with_history(chart, &[], &ArapOptions::default()).unwrap();
        assert!(*h.last().unwrap() < 1e-12, "{name}: ARAP energy {:?}", h.last());
        let (_, h) = slim::solve_with_history(chart, &[], &slim_from_circle).unwrap();
        assert!(h.energy[0] > 1.0 + 1e-3, "{name}: the circle start is not already isometric");
        assert!((h.energy.last().unwrap() - 1.0).abs() < 1e-8, "{name}: SLIM energy {:?}", h.energy.last());
    }
}

#[test]
fn pins_stay_exactly_where_pinned() {
    let s = planar_disk(8, 7);
    // Corners of three vertices far apart, pinned at their own (x, y): a consistent set.
    let nv = s.positions.len() as u32;
    let targets = [1u32, nv - 1, nv - 9];
    let corner_of = |v: u32| s.corner_verts.iter().position(|&x| x == v).unwrap() as u32;
    let consistent: Vec<(u32, [f64; 2])> =
        targets.iter().map(|&v| (corner_of(v), [s.positions[v as usize][0], s.positions[v as usize][1]])).collect();
    // The same vertices pinned 1.3 times farther apart and rotated: no isometry fits them.
    let stretched: Vec<(u32, [f64; 2])> = consistent.iter().map(|&(c, p)| (c, [1.3 * p[1], -1.3 * p[0]])).collect();
    // One pin: a translation only.
    let single = vec![(corner_of(5), [10.0, -4.0])];
    for pins in [&consistent, &stretched, &single] {
        for m in [Method::Arap(ArapOptions::default()), Method::Slim(SlimOptions::default())] {
            let mut input = s.input();
            input.pins = pins;
            let r = unwrap(&input, &opts(m.clone())).unwrap();
            let c = &r.charts[0];
            assert_ne!(c.status, ChartStatus::Failed, "{m:?}: {:?}", c.reason);
            for &(corner, p) in pins.iter() {
                assert_eq!(r.uv[corner as usize], p, "{m:?}: pinned corner {corner} moved");
                // Every corner of the pinned vertex carries the pin.
                let v = s.corner_verts[corner as usize];
                for (k, &x) in s.corner_verts.iter().enumerate() {
                    if x == v {
                        assert_eq!(r.uv[k], p);
                    }
                }
            }
            if matches!(m, Method::Slim(_)) && c.status == ChartStatus::Solved {
                assert_eq!(c.flips, 0, "{m:?} with pins {pins:?}");
            }
            if pins == &consistent {
                // Pins that an isometry satisfies: the isometry itself is found.
                assert_eq!(c.status, ChartStatus::Solved);
                assert!((c.distortion.symmetric_dirichlet - 1.0).abs() < 1e-6, "{m:?}: {:?}", c.distortion);
                for (i, p) in s.positions.iter().enumerate() {
                    let k = s.corner_verts.iter().position(|&x| x == i as u32).unwrap();
                    let d = (r.uv[k][0] - p[0]).hypot(r.uv[k][1] - p[1]);
                    assert!(d < 1e-3, "{m:?}: vertex {i} is {d} from its planar position");
                }
            }
        }
    }
}

#[test]
fn slim_reports_when_pins_rule_out_a_flip_free_start() {
    // Pin the three corners of one triangle mirrored (two UVs swapped): every map honouring
    // the pins inverts that triangle, so no flip-free start exists and the chart falls back to
    // pinned LSCM, saying why.
    let s = planar_disk(3, 6);
    let f = 7usize;
    let (ca, cb, cc) = (3 * f as u32, 3 * f as u32 + 1, 3 * f as u32 + 2);
    let p = |c: u32| {
        let q = s.positions[s.corner_verts[c as usize] as usize];
        [q[0], q[1]]
    };
    let pins = [(ca, p(ca)), (cb, p(cc)), (cc, p(cb))];
    let mut input = s.input();
    input.pins = &pins;
    let r = unwrap(&input, &uncut(Method::Slim(SlimOptions::default()))).unwrap();
    let c = &r.charts[0];
    // The fallback folds under these pins: mapped, but reported invalid (never solved).
    assert_eq!(c.status, ChartStatus::Invalid, "{:?}", c.reason);
    assert_eq!(c.reason_code(), "invalid_flips");
    assert_eq!(c.method, "lscm");
    assert!(c.reason.as_deref().unwrap_or("").contains("no flip-free starting map"), "{:?}", c.reason);
    for &(corner, p) in &pins {
        assert_eq!(r.uv[corner as usize], p);
    }
    // The same triangle pinned in its own orientation is fine.
    let pins = [(ca, p(ca)), (cb, p(cb)), (cc, p(cc))];
    input.pins = &pins;
    let r = unwrap(&input, &uncut(Method::Slim(SlimOptions::default()))).unwrap();
    assert_eq!(r.charts[0].status, ChartStatus::Solved, "{:?}", r.charts[0].reason);
    assert_eq!(r.charts[0].flips, 0);
}

#[test]
fn options_parse_and_validate() {
    let m = Method::parse(
        "slim",
        &[
            ("max_iterations".into(), OptionValue::Int(7)),
            ("tolerance".into(), OptionValue::Float(1e-3)),
            ("start".into(), OptionValue::Str("mean_value".into())),
        ],
    )
    .unwrap();
    assert_eq!(m, Method::Slim(SlimOptions { max_iterations: 7, tolerance: 1e-3, start: SlimStart::MeanValue, ..Default::default() }));
    assert_eq!(m.name(), "slim");
    let m = Method::parse("arap", &[("max_iterations".into(), OptionValue::Int(3))]).unwrap();
    assert_eq!(m, Method::Arap(ArapOptions { max_iterations: 3, ..Default::default() }));
    assert_eq!(m.name(), "arap");
    assert!(uvflat_core::method_names().contains(&"arap") && uvflat_core::method_names().contains(&"slim"));
    assert!(Method::parse("slim", &[("start".into(), OptionValue::Str("tutte".into()))]).is_err());
    assert!(Method::parse("arap", &[("start".into(), OptionValue::Str("auto".into()))]).is_err());
    assert!(Method::parse("arap", &[("max_iterations".into(), OptionValue::Int(0))]).is_err());
    assert!(Method::parse("slim", &[("tolerance".into(), OptionValue::Float(f64::NAN))]).is_err());
    assert!(Method::Slim(SlimOptions { tolerance: -1.0, ..Default::default() }).validate().is_err());
}

#[test]
fn slim_reaches_a_lower_symmetric_dirichlet_than_arap_on_a_curved_disk() {
    let s = bumpy_disk();
    let chart = &charts_of(&s, &[])[0];
    // Run to convergence (the default tolerance stops once Blender's quality is passed).
    let converged = SlimOptions { max_iterations: 200, tolerance: 1e-9, ..Default::default() };
    let (sol, h) = slim::solve_with_history(chart, &[], &converged).unwrap();
    let arap_sol = arap::solve(chart, &[], &ArapOptions::default()).unwrap();
    // SLIM minimises the symmetric Dirichlet energy: not worse than ARAP's map of the same chart
    // (ARAP's map measured at its own scale is a feasible point of SLIM's energy).
    let ops = arap::TriangleOperators::new(&chart.positions, &chart.triangles);
    let e_arap = slim::symmetric_dirichlet(&ops, &chart.triangles, &arap_sol.uv);
    assert!(*h.energy.last().unwrap() <= e_arap + 1e-9, "SLIM {:?} vs ARAP {e_arap}", h.energy.last());
    assert_eq!(uvflat_core::metrics::chart_metrics(&chart.positions, &chart.triangles, &sol.uv, &chart.boundary_loops).flips, 0);
    assert!(h.energy.last().unwrap() < &h.energy[0]);
}

/// The same UVs on one thread as on two: the energies are summed in fixed chunks, so every
/// tolerance test stops after the same iteration whatever the thread count.
#[test]
fn iterative_methods_give_the_same_map_on_any_number_of_threads() {
    // a curved disk of some 11k triangles: several partial sums, and the line search's energy
    // evaluations run on both threads
    let mut s = planar_disk(43, 6);
    let r = s.positions.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
    for p in s.positions.iter_mut() {
        let (x, y) = (p[0] / r, p[1] / r);
        p[2] = 0.6 * (x * x + y * y) + 0.1 * (5.0 * x).sin() * (3.0 * y).cos();
    }
    assert!(s.face_sizes.len() > 3 * 2048, "{} triangles", s.face_sizes.len());
    for name in ["slim", "mips", "scaffold", "arap", "abf"] {
        let method = Method::parse(name, &[("tolerance".to_string(), OptionValue::Float(1e-9))]).unwrap();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| unwrap(&s.input(), &opts(method.clone())).unwrap())
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one.charts[0].iterations, two.charts[0].iterations, "{name}");
        assert!(one.uv == two.uv, "{name}: the maps differ");
    }
}
