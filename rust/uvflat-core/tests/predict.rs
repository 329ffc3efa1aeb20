//! The predicted flattening (conformal, outline lengths kept) that plans cones before any
//! solve: exact on a flat disk, growing with the curvature of a spherical cap, close to what
//! ABF measures on the same chart; disks predicted to break Max Stretch are cut before any
//! solve (for methods that do not balance area), and the plan does not depend on the method.

mod common;

use common::{sphere, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{cones::ScaleSolver, predicted_outside};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{abf, slim};
use uvflat_core::{unwrap, Method, UnwrapOptions};

/// The spherical cap `z > 1 − depth` of the unit sphere (`depth` 1: a hemisphere).
fn cap(depth: f64) -> Soup {
    sphere(48, 48, |c| c[2] > 1.0 - depth)
}

/// The predicted share outside `[1/s, s]` of the one chart of `s`.
fn predicted(s: &Soup, stretch: f64) -> f64 {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let solver = ScaleSolver::new(&charts[0]).unwrap();
    predicted_outside(&charts[0], &solver, stretch).unwrap()
}

/// The share outside `[1/s, s]` measured on the chart of `s` unwrapped by `method`, uncut.
fn measured(s: &Soup, method: Method, stretch: f64) -> f64 {
    let mut o = UnwrapOptions { method, ..Default::default() };
    o.auto_seams.enabled = false;
    o.auto_seams.max_stretch = stretch;
    let r = unwrap(&s.input(), &o).unwrap();
    assert_eq!(r.charts.len(), 1);
    r.charts[0].density.outside
}

#[test]
fn a_flat_disk_is_predicted_without_distortion() {
    let s = common::planar_disk(8, 24);
    assert_eq!(predicted(&s, 1.05), 0.0);
}

#[test]
fn the_prediction_grows_with_the_cap_and_follows_abf() {
    let mut last = -1.0;
    let mut seen_nonzero = false;
    for depth in [0.3, 0.6, 1.0, 1.4] {
        let s = cap(depth);
        let p = predicted(&s, 1.5);
        let m = measured(&s, Method::Abf(abf::AbfOptions::default()), 1.5);
        assert!(p >= last - 1e-12, "depth {depth}: predicted {p:.3} below the shallower cap's {last:.3}");
        assert!((p - m).abs() <= 0.08, "depth {depth}: predicted {p:.3}, ABF measures {m:.3}");
        seen_nonzero |= p > 0.05;
        last = p;
    }
    assert!(seen_nonzero, "no cap was predicted to break the bound: the comparison proves little");
}

#[test]
fn a_disk_predicted_to_break_the_rule_is_cut_before_any_solve() {
    // A deep cap: far beyond Max Stretch 2 when flattened as it is.
    let s = cap(1.6);
    assert!(predicted(&s, 2.0) > uvflat_core::pipeline::triage::PREDICTED_BREAK);
    let abf = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() }).unwrap();
    assert_eq!(abf.phases.solve, 0.0, "ABF solved the cap as it is first");
    assert!(!abf.new_seams.is_empty());
    // SLIM balances area: it is solved as it is first.
    let slim = unwrap(&s.input(), &UnwrapOptions { method: Method::Slim(slim::SlimOptions::default()), ..Default::default() }).unwrap();
    assert!(slim.phases.solve > 0.0, "SLIM was not tried on the cap as it is");
    // A shallow cap keeps the rule as it is and is solved without a cut.
    let shallow = unwrap(&cap(0.3).input(), &UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() }).unwrap();
    assert!(shallow.new_seams.is_empty() && shallow.phases.solve > 0.0);
}

#[test]
fn a_disk_predicted_to_break_the_rule_by_a_little_more_than_allowed_is_cut_before_any_solve() {
    use uvflat_core::pipeline::triage::{PREDICTED_BREAK, PREDICTED_BREAK_PLANNED};
    // The shallowest cap predicted between the two bounds.
    let (depth, s) = (0..=20)
        .map(|k| 0.9 + 0.03 * k as f64)
        .map(|d| (d, cap(d)))
        .find(|(_, s)| (PREDICTED_BREAK_PLANNED..PREDICTED_BREAK).contains(&predicted(s, 2.0)))
        .expect("a cap predicted between the bounds");
    // ABF's map of it as it is breaks the rule: its solve would be thrown away.
    assert!(measured(&s, Method::Abf(abf::AbfOptions::default()), 2.0) > 0.05, "depth {depth}");
    for method in [Method::Abf(abf::AbfOptions::default()), Method::Lscm] {
        let name = method.name();
        let r = unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }).unwrap();
        assert_eq!(r.phases.solve, 0.0, "{name}, depth {depth}: the cap was solved as it is first");
        assert!(!r.new_seams.is_empty());
        common::assert_islands_keep_the_rule(&s, name, &r);
    }
    // SLIM balances area: it is solved as it is first.
    let options = UnwrapOptions { method: Method::Slim(slim::SlimOptions::default()), ..Default::default() };
    assert!(unwrap(&s.input(), &options).unwrap().phases.solve > 0.0, "SLIM was not tried on the cap as it is");
}

#[test]
fn the_planned_seams_do_not_depend_on_the_method() {
    // A closed sphere: every conformal method gets the predicted plan; where each keeps the
    // rule on it, the seams are the same.
    let s = common::cube_sphere(10);
    let seams = |method: Method| {
        let r = unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }).unwrap();
        assert!(r.charts.iter().all(|c| c.status.name() == "solved"), "{:?}", r.charts.iter().map(|c| c.status.name()).collect::<Vec<_>>());
        let mut e = r.new_seams.clone();
        e.sort_unstable();
        e
    };
    let abf = seams(Method::Abf(abf::AbfOptions::default()));
    assert!(!abf.is_empty());
    assert_eq!(abf, seams(Method::Lscm));
    assert_eq!(abf, seams(Method::Spectral(Default::default())));
    // MIPS sees angles only: it is planned like the conformal methods.
    assert_eq!(abf, seams(Method::Mips(Default::default())));
}

#[test]
fn a_plan_predicted_above_the_mean_limit_is_split_before_any_solve() {
    // The bunny, closed: its best plan keeps the rule with a predicted mean area distortion
    // above the limit (ABF's map of it too), so the split comes first and the halves, which
    // keep the rule with a lower mean, are the result.
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::load(&dir.join("bunny.off"));
    let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() }).unwrap();
    assert!(r.phases.predicted_splits >= 1, "{:?}", r.phases);
    assert!(r.phases.splits >= r.phases.predicted_splits);
    // The split's planning is counted in its own part of `plan_cuts`, and the parts add up.
    let p = &r.phases;
    assert!(p.split_plans > 0.0 && p.cone_placement > 0.0 && p.cut_state > 0.0, "{p:?}");
    let parts = p.cut_state + p.cone_placement + p.split_plans + p.cut_graphs;
    assert!((parts - p.plan_cuts).abs() <= 1e-9 * p.plan_cuts, "{p:?}");
    assert!(r.charts.len() >= 2);
    let options = UnwrapOptions::default();
    let rule = uvflat_core::pipeline::rule::AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
    for c in &r.charts {
        assert_eq!(c.status.name(), "solved");
        assert!(rule.broken(c).is_none(), "chart {} breaks the rule: {:?}", c.id, rule.broken(c));
    }
    // The islands' mean area distortion, weighted by their 3D area: within the limit the
    // split is for.
    let mut area = vec![0.0; r.charts.len()];
    for (f, &c) in r.face_chart.iter().enumerate() {
        let corner = |k: usize| s.positions[s.corner_verts[3 * f + k] as usize];
        assert_eq!(s.face_sizes[f], 3);
        area[c as usize] += uvflat_core::geometry::triangle_area([corner(0), corner(1), corner(2)]);
    }
    let total: f64 = area.iter().sum();
    let mean: f64 = r.charts.iter().zip(&area).map(|(c, a)| a * c.distortion.area).sum::<f64>() / total;
    assert!(mean <= uvflat_core::pipeline::repair::MEAN_AREA_LIMIT, "mean area {mean:.3}");
    // SLIM balances area and plans no prediction: nothing is split before its solve.
    let slim = unwrap(&s.input(), &UnwrapOptions { method: Method::Slim(slim::SlimOptions::default()), ..Default::default() }).unwrap();
    assert_eq!(slim.phases.predicted_splits, 0);
}

/// The bunny subdivided twice (111,456 triangles, closed: planned on its proxy) under `abf`:
/// its plan is split before any solve, the split following the Fiedler vector made beside
/// the plan (`pipeline/repair.rs`). Every island keeps the rule, and the outcome is the same on
/// one thread, to the bit.
#[test]
fn a_scan_planned_on_its_proxy_splits_the_same_on_any_number_of_threads() {
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::subdivide(&common::subdivide(&common::load(&dir.join("bunny.off"))));
    assert!(s.face_sizes.len() >= uvflat_core::cuts::coarse::CLOSED_PROXY_FROM);
    let options = UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.phases.predicted_splits >= 1, "{:?}", r.phases);
    common::assert_islands_keep_the_rule(&s, "abf", &r);
    common::assert_same_on_one_thread(&s, &options, &r);
}

#[test]
fn a_plan_predicted_to_break_the_rule_is_split_before_its_solve() {
    // The lion subdivided once (66,696 triangles, open): no plan of cones is predicted to
    // keep the rule, and the one solve of the best plan broke it; the split comes first, its
    // halves keep the rule, and the chart itself is never solved.
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::subdivide(&common::load(&dir.join("lion.off")));
    let options = UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.phases.predicted_splits >= 1, "{:?}", r.phases);
    // Every solve is of an island kept: one round per island, none thrown away.
    assert_eq!(r.phases.repair_rounds, r.charts.len(), "{:?}", r.phases);
    common::assert_islands_keep_the_rule(&s, "abf", &r);
}

/// A method whose map is far from a plan that keeps the rule (LSCM's free boundary crushes
/// regions the prediction does not) is split after its first solve: cones placed on the
/// prediction do not bring such a map back. ABF's map follows the prediction and is never
/// sent that way; SLIM plans no prediction.
#[test]
fn a_map_far_from_its_plan_is_split_after_one_solve() {
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::load(&dir.join("camelhead.off"));
    let run = |method: Method| unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }).unwrap();
    let lscm = run(Method::Lscm);
    assert!(lscm.phases.far_splits >= 1, "{:?}", lscm.phases);
    assert!(lscm.phases.splits >= lscm.phases.far_splits, "{:?}", lscm.phases);
    let options = UnwrapOptions::default();
    let rule = uvflat_core::pipeline::rule::AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
    for c in &lscm.charts {
        assert!(matches!(c.status.name(), "solved" | "fallback"), "chart {}: {:?}", c.id, c.reason);
        assert!(rule.broken(c).is_none(), "chart {} breaks the rule: {:?}", c.id, rule.broken(c));
    }
    assert_eq!(run(Method::Abf(abf::AbfOptions::default())).phases.far_splits, 0);
    assert_eq!(run(Method::Slim(slim::SlimOptions::default())).phases.far_splits, 0);
}

/// A large chart whose first map breaks the density bound under a conformal method is split
/// without cone rounds (`pipeline/repair.rs::CONE_ROUNDS_BELOW`): the beetle subdivided twice
/// under `lscm` (618,496 triangles), far from its plan as a whole, goes to the split after one
/// solve, and every island keeps the rule. (With LSCM's two automatic pins, a half of 323,892
/// triangles also stayed at 8.2% outside the bound after three cone rounds and was split
/// again; its free map fixed on the boundary, `methods/lscm.rs::solve_free`, does not.)
#[test]
fn a_large_chart_beyond_the_density_bound_is_split_after_one_solve() {
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::subdivide(&common::subdivide(&common::load(&dir.join("beetle.off"))));
    assert!(s.face_sizes.len() >= 2 * uvflat_core::pipeline::repair::CONE_ROUNDS_BELOW);
    let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Lscm, ..Default::default() }).unwrap();
    assert!(r.phases.far_splits >= 1, "{:?}", r.phases);
    assert!(r.phases.repair_rounds <= 4, "{:?}", r.phases);
    common::assert_islands_keep_the_rule(&s, "lscm", &r);
}

/// A large piece that folds at a few faces after its solve is peeled there, before more cones
/// or a split (`pipeline/peel.rs::FLIPS_PEEL_FROM`): `arap` on the bunny subdivided twice
/// (111,456 triangles) stops at its iteration cap with a few faces folded and its outline
/// crossing itself, and every cone round and split left such folds (19 solves, 6 islands).
/// Now one solve and one peel, no split, and every island keeps the rule.
#[test]
fn a_large_piece_that_folds_at_a_few_faces_is_peeled_after_its_solve() {
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::subdivide(&common::subdivide(&common::load(&dir.join("bunny.off"))));
    assert!(s.face_sizes.len() >= uvflat_core::pipeline::peel::FLIPS_PEEL_FROM);
    let options = UnwrapOptions { method: Method::Arap(Default::default()), ..Default::default() };
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.phases.peels >= 1, "{:?}", r.phases);
    assert_eq!(r.phases.splits, 0, "{:?}", r.phases);
    assert!(r.phases.repair_rounds <= 2, "{:?}", r.phases);
    common::assert_islands_keep_the_rule(&s, "arap", &r);
}

/// A plan whose predicted mean area distortion stays far above the split's limit (the cow,
/// closed, under `abf`: its rounds stall near 1.57) is split before any solve when the chart
/// may be split, so its one-cone rounds are skipped there; where it may not (the last split
/// level), they run as before. Either way the plan's mean stays far above the limit: the
/// rounds skipped would not have kept the chart whole.
#[test]
fn a_plan_far_above_the_split_limit_gets_no_one_cone_rounds_when_a_split_follows() {
    use uvflat_core::pipeline::{predict, repair, Context};
    let Some(dir) = common::shared_meshes() else { return };
    let s = common::load(&dir.join("cow.off"));
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let options = UnwrapOptions { method: Method::Abf(abf::AbfOptions::default()), ..Default::default() };
    let pins = std::collections::HashMap::new();
    let avoid = vec![false; s.positions.len()];
    let ctx = Context::new(&mesh, None, &pins, &options, &avoid);
    let cutter = repair::cutter(&ctx, &charts[0]);
    let far = repair::MEAN_AREA_LIMIT + repair::MEAN_AREA_GAIN;
    let whole = predict::plan(&ctx, &charts[0], &cutter, &[], false);
    let rounds_whole = ctx.clock.get().predicted_rounds;
    let split = predict::plan(&ctx, &charts[0], &cutter, &[], true);
    let rounds_split = ctx.clock.get().predicted_rounds - rounds_whole;
    assert!(whole.mean_area > far, "the premise: a plan far above the limit, {:.3}", whole.mean_area);
    assert!(split.mean_area > far, "skipped rounds would have kept it whole: {:.3}", split.mean_area);
    assert!(rounds_split < rounds_whole, "rounds: {rounds_split} with a split to follow, {rounds_whole} without");
    // The same rounds up to the first that did not help: the same best plan's mean or one
    // the one-cone rounds lowered.
    assert!(whole.mean_area <= split.mean_area + 1e-12);
}

#[test]
fn a_large_nearly_closed_disk_is_cut_before_any_solve_under_a_method_that_balances_area() {
    use uvflat_core::pipeline::triage::{PREDICTED_BREAK, PREDICTED_FAR, PREDICT_FROM};
    let slim = || UnwrapOptions { method: Method::Slim(slim::SlimOptions::default()), ..Default::default() };
    // A sphere with a small hole at its south pole: no flattening of it keeps the rule, and its
    // solve as it is would be thrown away.
    let nearly_closed = sphere(200, 200, |c| c[2] > -0.995);
    let triangles: usize = nearly_closed.face_sizes.iter().map(|&k| k as usize - 2).sum();
    assert!(triangles >= PREDICT_FROM, "{triangles} triangles: the disk is not large");
    assert!(predicted(&nearly_closed, 2.0) > PREDICTED_FAR);
    let r = unwrap(&nearly_closed.input(), &slim()).unwrap();
    assert_eq!(r.phases.solve, 0.0, "SLIM solved the nearly closed sphere as it is first: {:?}", r.phases);
    assert!(!r.new_seams.is_empty());
    common::assert_islands_keep_the_rule(&nearly_closed, "slim", &r);
    // Three quarters of the sphere: predicted beyond the bound for parts, not beyond the far
    // one. SLIM keeps the rule on it as it is, one island without a cut.
    let three_quarters = sphere(200, 200, |c| c[2] > -0.5);
    let p = predicted(&three_quarters, 2.0);
    assert!(p > PREDICTED_BREAK && p < PREDICTED_FAR, "predicted {p:.3}");
    let r = unwrap(&three_quarters.input(), &slim()).unwrap();
    assert!(r.phases.solve > 0.0, "SLIM did not solve three quarters of the sphere as they are first");
    let (islands, seams) = (r.charts.len(), r.new_seams.len());
    assert!(seams == 0 && islands == 1, "{islands} islands, {seams} new seams");
    common::assert_islands_keep_the_rule(&three_quarters, "slim", &r);
}
