//! Boundary first flattening with the outline's lengths kept (`methods/bff.rs`): the analytic
//! map of a hemisphere, a flat chart laid as it is, pins, holes, the outline that cannot close,
//! unfolding, and automatic seams planned on its own scale factor.

mod common;

use common::{assert_islands_keep_the_rule, doubled_signed_areas, planar_disk, sphere, with_holes, Soup};
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::bff;
use uvflat_core::{unwrap, ChartStatus, Method, UnwrapOptions};

fn only_chart(s: &Soup) -> Chart {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let mut charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    charts.pop().unwrap()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

#[test]
fn a_hemisphere_is_mapped_as_by_the_stereographic_projection() {
    // The conformal map of the unit hemisphere onto the plane that keeps the equator's length
    // is the stereographic projection from the other pole: the unit disk, the point at polar
    // angle ψ at distance tan(ψ/2) from the pole's image.
    let s = sphere(128, 128, |c| c[2] > 0.0);
    let chart = only_chart(&s);
    let sol = bff::solve(&chart, &[]).unwrap();
    assert!(doubled_signed_areas(&chart.triangles, &sol.uv).iter().all(|&a| a > 0.0), "a flipped triangle");
    let pole = chart.positions.iter().position(|p| p[2] > 0.999_999).unwrap();
    let mut worst: f64 = 0.0;
    for (p, uv) in chart.positions.iter().zip(&sol.uv) {
        let psi = p[2].clamp(-1.0, 1.0).acos();
        worst = worst.max((dist(*uv, sol.uv[pole]) - (psi / 2.0).tan()).abs());
    }
    assert!(worst < 0.01, "farthest from the stereographic projection: {worst:.4}");
    // The outline keeps its 3D edge lengths.
    let outline = &chart.boundary_loops[0];
    for k in 0..outline.len() {
        let (a, b) = (outline[k] as usize, outline[(k + 1) % outline.len()] as usize);
        let l3 = ((0..3).map(|d| (chart.positions[a][d] - chart.positions[b][d]).powi(2)).sum::<f64>()).sqrt();
        let l2 = dist(sol.uv[a], sol.uv[b]);
        assert!((l2 / l3 - 1.0).abs() < 0.01, "outline edge {k}: {l2} in UV, {l3} in 3D");
    }
}

#[test]
fn a_curved_chart_without_the_planar_shortcut_is_laid_flat_when_it_is_flat() {
    // Called directly (the pipeline lays flat charts as they are before any method): the
    // scale factor is zero, the outline turns as it does in 3D, and cotangent weights
    // reproduce the chart's own coordinates.
    let s = planar_disk(8, 7);
    let chart = only_chart(&s);
    let sol = bff::solve(&chart, &[]).unwrap();
    for t in &chart.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let l3 = ((0..3).map(|d| (chart.positions[a][d] - chart.positions[b][d]).powi(2)).sum::<f64>()).sqrt();
            assert!((dist(sol.uv[a], sol.uv[b]) - l3).abs() < 1e-9 * (1.0 + l3), "edge {a}-{b}");
        }
    }
}

#[test]
fn pins_are_kept_through_lscm_and_one_pin_translates_the_map() {
    let s = sphere(32, 32, |c| c[2] > 0.2);
    let chart = only_chart(&s);
    let outline = &chart.boundary_loops[0];
    let (a, b) = (outline[0], outline[outline.len() / 2]);
    let two = [(a, [0.25, -1.0]), (b, [3.0, 2.0])];
    let sol = bff::solve(&chart, &two).unwrap();
    assert_eq!(sol.uv[a as usize], [0.25, -1.0]);
    assert_eq!(sol.uv[b as usize], [3.0, 2.0]);
    assert!(sol.note.as_deref().unwrap_or("").contains("LSCM"), "{:?}", sol.note);
    let free = bff::solve(&chart, &[]).unwrap();
    let one = bff::solve(&chart, &[(b, [5.0, 7.0])]).unwrap();
    assert_eq!(one.uv[b as usize], [5.0, 7.0]);
    let shift = [5.0 - free.uv[b as usize][0], 7.0 - free.uv[b as usize][1]];
    for (p, q) in free.uv.iter().zip(&one.uv) {
        assert!((p[0] + shift[0] - q[0]).abs() < 1e-12 && (p[1] + shift[1] - q[1]).abs() < 1e-12);
    }
}

#[test]
fn a_chart_with_holes_is_flattened_through_a_virtual_fill_and_no_seam_is_cut_without_auto_seams() {
    let s = with_holes(&sphere(64, 64, |c| c[2] > 0.3), 3, 10, 5);
    let chart = only_chart(&s);
    assert!(chart.boundary_loops.len() > 1, "the test needs holes");
    let sol = bff::solve(&chart, &[]).unwrap();
    assert_eq!(sol.uv.len(), chart.positions.len());
    assert!(doubled_signed_areas(&chart.triangles, &sol.uv).iter().all(|&a| a > 0.0), "a flipped triangle");
    let mut options = UnwrapOptions { method: Method::Bff, ..Default::default() };
    options.auto_seams.enabled = false;
    let r = unwrap(&s.input(), &options).unwrap();
    assert!(r.new_seams.is_empty());
    assert_eq!(r.charts[0].status, ChartStatus::Solved, "{:?}", r.charts[0].reason);
}

#[test]
fn an_outline_whose_edges_all_turn_one_way_is_refused_with_a_reason() {
    let s = sphere(16, 16, |c| c[2] > 0.5);
    let chart = only_chart(&s);
    let outline = &chart.boundary_loops[0];
    let err = bff::outline_curve(&chart, outline, &vec![0.0; outline.len()]).unwrap_err();
    assert!(err.0.contains("cannot be closed"), "{}", err.0);
    // Half the edges along x and half along y: closing it shrinks every edge to nothing.
    let mut corner = vec![0.0; outline.len()];
    corner[outline.len() / 2] = std::f64::consts::FRAC_PI_2;
    let err = bff::outline_curve(&chart, outline, &corner).unwrap_err();
    assert!(err.0.contains("mesh vertex") && err.0.contains("too curved"), "{}", err.0);
}

#[test]
fn automatic_seams_keep_the_rule_with_no_fallback_and_no_more_islands_than_lscm_on_shared_meshes() {
    // The plan's prediction is bff's own scale factor, so bff rarely needs the repair's cuts
    // that LSCM's free outline does.
    let Some(dir) = common::shared_meshes() else { return };
    for name in ["bunny.off", "cow.off", "3holes.off", "fertility.off", "camelhead.off"] {
        let s = common::load(&dir.join(name));
        let options = UnwrapOptions { method: Method::Bff, ..Default::default() };
        let r = unwrap(&s.input(), &options).unwrap();
        assert_islands_keep_the_rule(&s, name, &r);
        assert!(r.charts.iter().all(|c| c.status == ChartStatus::Solved), "{name}: {:?}", r.charts);
        let lscm = unwrap(&s.input(), &UnwrapOptions { method: Method::Lscm, ..Default::default() }).unwrap();
        assert!(r.charts.len() <= lscm.charts.len(), "{name}: {} islands, lscm {}", r.charts.len(), lscm.charts.len());
        common::assert_same_on_one_thread(&s, &options, &r);
    }
}

#[test]
fn a_vertex_dragged_across_its_neighbours_is_unfolded_and_a_fixed_one_is_left() {
    use uvflat_core::methods::quad_repair::unfold;
    use uvflat_core::metrics::count_flips;
    let s = planar_disk(5, 6);
    let chart = only_chart(&s);
    let flat: Vec<[f64; 2]> = chart.positions.iter().map(|p| [p[0], p[1]]).collect();
    // The vertex of the first ring nearest +x, dragged past the centre: its star folds.
    let v = (0..chart.positions.len())
        .filter(|&i| (chart.positions[i][0].hypot(chart.positions[i][1]) - 1.0).abs() < 0.2)
        .max_by(|&a, &b| chart.positions[a][0].total_cmp(&chart.positions[b][0]))
        .unwrap();
    let mut uv = flat.clone();
    uv[v] = [-0.5 * flat[v][0], 0.3];
    let folded = count_flips(&chart.triangles, &uv);
    assert!(folded > 0);
    let before: Vec<bool> = doubled_signed_areas(&chart.triangles, &uv).iter().map(|&a| a > 0.0).collect();
    let mut fixed = vec![false; uv.len()];
    fixed[v] = true;
    let mut pinned = uv.clone();
    let (left_fixed, _) = unfold(&chart.positions, &chart.triangles, &mut pinned, &fixed);
    assert_eq!(pinned[v], uv[v], "a fixed vertex moved");
    let (left, moved) = unfold(&chart.positions, &chart.triangles, &mut uv, &[]);
    assert_eq!(left, 0, "{folded} folded, {left} left");
    assert!(moved >= 1 && moved < uv.len() / 4, "moved {moved} of {}", uv.len());
    // Nothing positive was turned over on the way, with or without the fixed vertex.
    let areas_of = |uv: &[[f64; 2]]| doubled_signed_areas(&chart.triangles, uv);
    for (areas, what) in [(areas_of(&uv), "free"), (areas_of(&pinned), "fixed")] {
        assert!(areas.iter().zip(&before).all(|(&a, &b)| !b || a > 0.0), "{what}: a positive triangle turned over");
    }
    assert!(left_fixed <= folded);
}

#[test]
fn triangles_collapsed_in_3d_are_given_area_when_unfolded() {
    // An inside vertex of a flat disk moved onto its neighbour, in 3D and in the map: the two
    // triangles on their edge have no area in either. Unfolding gives them room (their target
    // comes from their two longest 3D edges, not from the edge that has no length), and turns
    // nothing else over.
    use uvflat_core::methods::quad_repair::unfold;
    let s = planar_disk(5, 6);
    let chart = only_chart(&s);
    let (v, w) = (0u32, chart.triangles[0][1]);
    let mut positions = chart.positions.clone();
    positions[v as usize] = positions[w as usize];
    let mut uv: Vec<[f64; 2]> = positions.iter().map(|p| [p[0], p[1]]).collect();
    // Each triangle on the collapsed edge starts at v (its orientation kept): one of the two
    // edges at its first corner has no length.
    let mut triangles = chart.triangles.clone();
    let mut on_edge = 0;
    for t in &mut triangles {
        if t.contains(&v) && t.contains(&w) {
            while t[0] != v {
                t.rotate_left(1);
            }
            on_edge += 1;
        }
    }
    assert_eq!(on_edge, 2);
    let before = uvflat_core::metrics::count_flips(&triangles, &uv);
    assert_eq!(before, 2, "the two triangles on the collapsed edge have no area");
    let (left, _) = unfold(&positions, &triangles, &mut uv, &[]);
    assert_eq!(left, 0, "{left} of {before} still without area");
}
