//! The atlas rule on every chart of every mesh (automatic seams on): every island is a disk,
//! has no flipped triangle, an outline that does not cross itself, and at most 5% of its area
//! outside [1/s, s] of its own texel density — measured on the returned UVs by `metrics`,
//! independently of the pipeline's own reports. Open meshes, meshes with holes, closed meshes
//! and several parts, triangles and quads, with abf, slim, lscm, mips and scaffold.

mod common;

use common::{cube, load, shared_meshes, soup_of, sphere, with_holes, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{abf, mips, scaffold, slim};
use uvflat_core::{metrics, unwrap, ChartKind, ChartStatus, MeshInput, Method, UnwrapOptions, Unwrapped};

fn methods() -> Vec<Method> {
    vec![
        Method::Abf(abf::AbfOptions::default()),
        Method::Slim(slim::SlimOptions::default()),
        Method::Lscm,
        Method::Mips(mips::MipsOptions::default()),
        Method::Scaffold(scaffold::ScaffoldOptions::default()),
    ]
}

/// An open tube (two boundary loops) of quads.
fn tube(nu: usize, nv: usize, h: f64) -> Soup {
    let (s, _) = common::cut_cylinder(nu, nv, h);
    s
}

/// Two parts: a hemisphere and a moved copy of a tube.
fn two_parts() -> Soup {
    let mut a = sphere(24, 12, |c| c[2] > 0.0);
    let b = tube(16, 6, 2.0);
    let off = a.positions.len() as u32;
    a.positions.extend(b.positions.iter().map(|p| [p[0] + 4.0, p[1], p[2]]));
    a.corner_verts.extend(b.corner_verts.iter().map(|v| v + off));
    a.face_sizes.extend(&b.face_sizes);
    a
}

/// The generated meshes: (name, soup).
fn meshes() -> Vec<(&'static str, Soup)> {
    vec![
        ("open hemisphere", sphere(32, 16, |c| c[2] > 0.0)),
        ("open tube", tube(24, 12, 3.0)),
        ("sphere with 3 holes", sphere(32, 16, |c| c[2] < 0.8 && c[0] < 0.85 && c[1] < 0.85)),
        ("two parts", two_parts()),
        ("cube", cube(4)),
        ("flat quad grid", {
            let faces: Vec<Vec<u32>> = (0..8)
                .flat_map(|j| (0..8).map(move |i| vec![j * 9 + i, j * 9 + i + 1, (j + 1) * 9 + i + 1, (j + 1) * 9 + i]))
                .collect();
            let positions = (0..9).flat_map(|j| (0..9).map(move |i| [i as f64, j as f64, 0.0])).collect();
            soup_of(positions, faces, |_| true)
        }),
    ]
}

/// The rule on the returned UVs, measured by `metrics` (not by the reports), and the
/// islands' topology from the user's and the new seams.
fn check_rule(name: &str, method: &str, s: &Soup, user_seams: &[[u32; 2]], r: &Unwrapped) {
    let ctx = format!("{name} / {method}");
    assert!(r.charts.iter().all(|c| c.status != ChartStatus::Failed), "{ctx}: a chart failed: {:?}", r.charts);
    for c in &r.charts {
        assert!(
            matches!(c.status, ChartStatus::Solved | ChartStatus::Fallback),
            "{ctx}: chart {} is {:?} ({}): {:?}",
            c.id,
            c.status,
            c.reason_code(),
            c.reason
        );
    }
    let m = metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
    assert_eq!(m.flips, 0, "{ctx}: flips");
    assert_eq!(m.overlapping_charts, 0, "{ctx}: an outline crosses itself");
    for (i, c) in m.per_chart.iter().enumerate() {
        assert!(c.density.outside <= 0.05 + 1e-12, "{ctx}: island {i}: {:.3} of its area outside [1/2, 2]", c.density.outside);
    }
    // Every island is a disk: the charts of the user's seams plus the new ones.
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let mut all: Vec<[u32; 2]> = user_seams.to_vec();
    all.extend_from_slice(&r.new_seams);
    for ch in build_charts(&mesh, &all, None) {
        assert_eq!(ch.kind, ChartKind::Disk, "{ctx}: an island of {} faces is {:?}", ch.faces.len(), ch.kind);
    }
    assert_eq!(m.charts, r.charts.len(), "{ctx}: islands measured against charts reported");
}

#[test]
fn every_island_keeps_the_rule_on_generated_meshes() {
    for (name, s) in meshes() {
        for method in methods() {
            let r = unwrap(&s.input(), &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
            check_rule(name, method.name(), &s, &[], &r);
        }
    }
}

/// A flat grid is already a perfect disk: no cut, one island.
#[test]
fn a_valid_disk_is_not_cut() {
    let (_, s) = meshes().into_iter().find(|m| m.0 == "flat quad grid").unwrap();
    let r = unwrap(&s.input(), &UnwrapOptions::default()).unwrap();
    assert!(r.new_seams.is_empty());
    assert_eq!(r.charts.len(), 1);
    assert_eq!(r.charts[0].status, ChartStatus::Solved);
}

/// The user's seams are kept: every user seam edge separates UVs (its two faces' corners
/// differ at an end) in the output.
#[test]
fn user_seams_are_kept() {
    let s = sphere(24, 12, |c| c[2] > -0.5);
    // A meridian seam from the pole down to the rim.
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let mut seams = Vec::new();
    for f in 0..mesh.n_faces() {
        for c in mesh.face_corners(f) {
            let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f, c)));
            let (pa, pb) = (s.positions[a as usize], s.positions[b as usize]);
            if pa[1].abs() < 1e-9 && pb[1].abs() < 1e-9 && pa[0] >= -1e-9 && pb[0] >= -1e-9 && a != b {
                seams.push([a.min(b), a.max(b)]);
            }
        }
    }
    seams.sort_unstable();
    seams.dedup();
    assert!(seams.len() >= 4);
    for method in [Method::Abf(Default::default()), Method::Slim(Default::default())] {
        let input = MeshInput { seams: &seams, ..s.input() };
        let r = unwrap(&input, &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
        check_rule("hemisphere with a seam", method.name(), &s, &seams, &r);
        // UV of (face, vertex) pairs: the two sides of each seam edge differ.
        let mut uv_at = std::collections::HashMap::new();
        for f in 0..mesh.n_faces() {
            for c in mesh.face_corners(f) {
                uv_at.insert((f, mesh.corner_vert(c)), r.uv[c]);
            }
        }
        for e in &seams {
            let faces: Vec<usize> = (0..mesh.n_faces())
                .filter(|&f| uv_at.contains_key(&(f, e[0])) && uv_at.contains_key(&(f, e[1])))
                .filter(|&f| {
                    mesh.face_corners(f).any(|c| {
                        let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f, c)));
                        [a.min(b), a.max(b)] == *e
                    })
                })
                .collect();
            assert_eq!(faces.len(), 2, "seam {e:?}");
            let same = (0..2).all(|k| uv_at[&(faces[0], e[k])] == uv_at[&(faces[1], e[k])]);
            assert!(!same, "{}: the user's seam {e:?} was closed", method.name());
        }
    }
}

/// With automatic seams off nothing is cut, and a chart that breaks the promise (flips or a
/// crossing outline) is never reported solved.
#[test]
fn without_auto_seams_nothing_is_cut_and_broken_charts_say_so() {
    let s = sphere(32, 16, |c| c[2] < 0.8 && c[0] < 0.85 && c[1] < 0.85);
    for method in methods() {
        let mut o = UnwrapOptions { method: method.clone(), ..Default::default() };
        o.auto_seams.enabled = false;
        let r = unwrap(&s.input(), &o).unwrap();
        assert!(r.new_seams.is_empty(), "{}", method.name());
        let m = metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
        for (c, mc) in r.charts.iter().zip(&m.per_chart) {
            if mc.flips > 0 || mc.overlap {
                assert_eq!(c.status, ChartStatus::Invalid, "{}: {:?}", method.name(), c);
                assert!(c.reason_code().starts_with("invalid_"));
            }
        }
    }
}

/// Same output whatever the run and the thread count.
#[test]
fn output_is_identical_across_runs_and_thread_counts() {
    let s = two_parts();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| unwrap(&s.input(), &UnwrapOptions::default()).unwrap())
    };
    let a = run(1);
    let b = run(2);
    let c = run(2);
    assert_eq!(a.uv, b.uv);
    assert_eq!(b.uv, c.uv);
    assert_eq!(a.new_seams, b.new_seams);
}

/// Same output with one thread and two when a large chart's split halves go through the
/// pipeline side by side (from `SEQUENTIAL_HALVES_FROM` triangles, under `abf`): the bunny
/// subdivided twice (111,456 triangles), split before any solve.
#[test]
fn large_halves_side_by_side_give_the_same_output_as_in_turn() {
    use uvflat_core::pipeline::repair::SEQUENTIAL_HALVES_FROM;
    let Some(dir) = shared_meshes() else { return };
    let s = common::subdivide(&common::subdivide(&load(&dir.join("bunny.off"))));
    assert!(s.face_sizes.len() >= SEQUENTIAL_HALVES_FROM, "{} triangles", s.face_sizes.len());
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| unwrap(&s.input(), &UnwrapOptions::default()).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert!(a.phases.splits >= 1, "the whole chart was not split: {:?}", a.phases);
    assert_eq!(a.new_seams, b.new_seams);
    assert_eq!(a.uv, b.uv);
    check_rule("bunny subdivided twice", "abf", &s, &[], &b);
}

/// With `same_seams` on, every method's cuts are planned on the method-independent
/// prediction, so the methods that keep the rule on the plan get exactly the same seams
/// (`abf`, which balances angles, and `slim`, `arap` and `scaffold`, which even out area). Off
/// (the default), `slim` starts from the cutter's cones alone and gets fewer seams of its own.
#[test]
fn the_methods_get_the_same_seams_with_same_seams_on() {
    let Some(dir) = shared_meshes() else { return };
    let cases: [(&str, Vec<Method>); 2] = [
        ("bunny.off", vec![Method::Slim(Default::default()), Method::Scaffold(Default::default())]),
        (
            "decimated-max.obj",
            vec![
                Method::Slim(Default::default()),
                Method::Arap(Default::default()),
                Method::Scaffold(Default::default()),
            ],
        ),
    ];
    for (name, others) in cases {
        let s = load(&dir.join(name));
        let run = |method: &Method, same_seams: bool| {
            let mut o = UnwrapOptions { method: method.clone(), ..Default::default() };
            o.auto_seams.same_seams = same_seams;
            let r = unwrap(&s.input(), &o).unwrap();
            check_rule(name, method.name(), &s, &[], &r);
            r.new_seams
        };
        let abf = run(&Method::Abf(Default::default()), true);
        assert!(!abf.is_empty(), "{name}: nothing was cut");
        for m in &others {
            assert_eq!(run(m, true), abf, "{name} / {}: not the seams of abf", m.name());
        }
        let own = run(&others[0], false);
        let default = unwrap(&s.input(), &UnwrapOptions { method: others[0].clone(), ..Default::default() }).unwrap();
        assert_eq!(default.new_seams, own, "{name}: same_seams is not off by default");
        assert!(own.len() < abf.len(), "{name}: slim's own seams {} against the plan's {}", own.len(), abf.len());
    }
}

/// The shared meshes (closed and open): the rule on every island with abf and slim.
#[test]
fn every_island_keeps_the_rule_on_shared_meshes() {
    let Some(dir) = shared_meshes() else { return };
    for name in ["bunny.off", "3holes.off", "halftunnel.off", "camelhead.off", "cow.off"] {
        let s = load(&dir.join(name));
        for method in methods() {
            let r = unwrap(&s.input(), &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
            check_rule(name, method.name(), &s, &[], &r);
        }
    }
}

/// The atlas's mean area distortion (3D-area-weighted over its islands, each measured against
/// its own density by `metrics`) stays within the pipeline's limit on the closed shared meshes
/// with `abf`: on 3holes, whose single island keeps the rule at 1.39 (the excess sits on the
/// saddles between its handles, where cones do not help), the chart is split. A chart already
/// within the limit is not split for it: fertility stays one island.
#[test]
fn the_mean_area_distortion_stays_within_its_limit_on_closed_shared_meshes() {
    use uvflat_core::pipeline::repair::MEAN_AREA_LIMIT;
    let Some(dir) = shared_meshes() else { return };
    for name in ["3holes.off", "bunny.off", "cow.off", "fertility.off", "decimated-max.obj"] {
        let s = load(&dir.join(name));
        let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(Default::default()), ..Default::default() }).unwrap();
        check_rule(name, "abf", &s, &[], &r);
        let m = metrics::measure(&s.positions, &s.corner_verts, &s.face_sizes, &r.uv, None).unwrap();
        let total: f64 = m.per_chart.iter().map(|c| c.area_3d).sum();
        let mean: f64 = m.per_chart.iter().map(|c| c.area_3d * c.distortion.area).sum::<f64>() / total;
        assert!(mean <= MEAN_AREA_LIMIT, "{name}: mean area distortion {mean:.4} over {} islands", m.charts);
        if name == "fertility.off" {
            assert_eq!(r.charts.len(), 1, "{name}: a chart within the limit was split");
        }
    }
}

/// Scans lose patches of surface: closed shared meshes with holes cut into them keep the rule
/// with every method. Cuts that join a hole to the outline across nearly flat surface are
/// not opened by most methods (their two sides cross), and linear conformal maps shrink
/// regions their planned cones do not cover: a piece still broken after its repair is mapped by
/// the method's flip-free kin or `scaffold`, reported as a fallback that names the method it
/// replaces and the one that replaced it.
#[test]
fn meshes_with_holes_keep_the_rule_with_every_method() {
    let Some(dir) = shared_meshes() else { return };
    for (name, k, size, seed) in [("cow.off", 6, 60, 1), ("bunny.off", 3, 300, 2), ("decimated-max.obj", 5, 100, 3)] {
        let s = with_holes(&load(&dir.join(name)), k, size, seed);
        for method in methods() {
            let r = unwrap(&s.input(), &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
            check_rule(name, method.name(), &s, &[], &r);
            for c in r.charts.iter().filter(|c| c.method != method.name()) {
                assert_eq!(c.status, ChartStatus::Fallback, "{name} / {}: chart {}", method.name(), c.id);
                let why = c.reason.as_deref().unwrap_or("");
                assert!(why.starts_with(method.name()) && why.contains(c.method), "{name} / {}: {why}", method.name());
            }
            eprintln!("{name} with holes / {}: {} islands, {} by scaffold", method.name(), r.charts.len(), r.charts.iter().filter(|c| c.method == "scaffold").count());
        }
    }
}

/// `s`'s triangles merged in pairs into quads, as a triangles-to-quads conversion does: each
/// triangle not merged yet, in order, takes the first neighbour across its edges that is an
/// unmerged triangle. Such meshes have vertices shared by only two faces (a quad and a
/// triangle, or two quads) whose quads are folded across both diagonals.
fn tris_to_quads(s: &Soup) -> Soup {
    let tri = |f: usize| [s.corner_verts[3 * f], s.corner_verts[3 * f + 1], s.corner_verts[3 * f + 2]];
    let n = s.face_sizes.len();
    assert!(s.face_sizes.iter().all(|&k| k == 3));
    let mut by_edge: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    for f in 0..n {
        let t = tri(f);
        for k in 0..3 {
            by_edge.insert((t[k], t[(k + 1) % 3]), f);
        }
    }
    let mut used = vec![false; n];
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for f in 0..n {
        if used[f] {
            continue;
        }
        let t = tri(f);
        let mut merged = false;
        for k in 0..3 {
            let (a, b, w) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if let Some(&g) = by_edge.get(&(b, a)).filter(|&&g| g != f && !used[g]) {
                let o = tri(g).into_iter().find(|&v| v != a && v != b).unwrap();
                faces.push(vec![w, a, o, b]);
                used[f] = true;
                used[g] = true;
                merged = true;
                break;
            }
        }
        if !merged {
            used[f] = true;
            faces.push(t.to_vec());
        }
    }
    soup_of(s.positions.clone(), faces, |_| true)
}

/// Triangles merged into quads: no chart fails or folds where a vertex is shared by only two
/// faces (each quad there is split through that vertex, whatever its shape), and the rule
/// holds.
#[test]
fn triangles_merged_into_quads_keep_the_rule() {
    let Some(dir) = shared_meshes() else { return };
    // The beetle's merged quads are often concave or folded in 3D (long thin triangles):
    // asked to stay convex in UV, SLIM could not start on a 3,700-face piece of it.
    for name in ["decimated-max.obj", "bunny.off", "cow.off", "beetle.off"] {
        let s = tris_to_quads(&load(&dir.join(name)));
        assert!(s.face_sizes.iter().filter(|&&k| k == 4).count() * 3 > s.face_sizes.len(), "{name}: mostly quads");
        for method in [Method::Abf(Default::default()), Method::Slim(Default::default()), Method::Lscm] {
            let r = unwrap(&s.input(), &UnwrapOptions { method: method.clone(), ..Default::default() }).unwrap();
            check_rule(name, method.name(), &s, &[], &r);
        }
    }
}

/// `s` with every interior vertex whose index is a multiple of `every` and whose fan is five
/// to eight triangles untouched so far dissolved: its fan becomes one n-gon (the ring of its
/// neighbours), as dissolving vertices in a modeller does. Deterministic.
fn dissolve_into_ngons(s: &Soup, every: usize) -> Soup {
    let n = s.face_sizes.len();
    assert!(s.face_sizes.iter().all(|&k| k == 3));
    let tri = |f: usize| [s.corner_verts[3 * f], s.corner_verts[3 * f + 1], s.corner_verts[3 * f + 2]];
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); s.positions.len()];
    for f in 0..n {
        for v in tri(f) {
            around[v as usize].push(f);
        }
    }
    let mut dead = vec![false; n];
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for v in (0..s.positions.len()).step_by(every.max(1)) {
        let fan = &around[v];
        if !(5..=8).contains(&fan.len()) || fan.iter().any(|&f| dead[f]) {
            continue;
        }
        // The ring: each fan triangle (v, a, b) links a -> b.
        let mut next = std::collections::HashMap::new();
        for &f in fan {
            let t = tri(f);
            let i = t.iter().position(|&x| x == v as u32).unwrap();
            next.insert(t[(i + 1) % 3], t[(i + 2) % 3]);
        }
        let t0 = tri(fan[0]);
        let start = t0[(t0.iter().position(|&x| x == v as u32).unwrap() + 1) % 3];
        let mut ring = vec![start];
        while ring.len() <= fan.len() {
            match next.get(ring.last().unwrap()) {
                Some(&w) if w == start => break,
                Some(&w) => ring.push(w),
                None => break,
            }
        }
        if ring.len() != fan.len() || next.get(ring.last().unwrap()) != Some(&start) {
            continue; // on the boundary, or not one disk around v
        }
        for &f in fan {
            dead[f] = true;
        }
        faces.push(ring);
    }
    faces.extend((0..n).filter(|&f| !dead[f]).map(|f| tri(f).to_vec()));
    soup_of(s.positions.clone(), faces, |_| true)
}

/// MIPS sees angles only, so it plans its cuts on the conformal prediction like ABF and LSCM:
/// on the cow with vertices dissolved into n-gons every island keeps the rule with MIPS's own
/// map (planned as an area-balancing method, one piece there was left 82% outside the bound
/// and even `scaffold` could not bring it within).
#[test]
fn mips_keeps_the_rule_on_ngons_with_its_own_map() {
    let Some(dir) = shared_meshes() else { return };
    let s = dissolve_into_ngons(&load(&dir.join("cow.off")), 3);
    assert!(s.face_sizes.iter().filter(|&&k| k > 4).count() > 100, "n-gons made");
    assert!(!Method::Mips(Default::default()).balances_area());
    let method = Method::Mips(Default::default());
    let r = unwrap(&s.input(), &UnwrapOptions { method, ..Default::default() }).unwrap();
    check_rule("cow n-gons", "mips", &s, &[], &r);
    for c in &r.charts {
        assert_eq!(c.method, "mips", "island {} was mapped by {}: {:?}", c.id, c.method, c.reason);
    }
}

/// The last resort tries the method's flip-free kin before `scaffold`: LSCM's pieces that
/// break the rule on the cow merged into quads are mapped by MIPS where that keeps the rule,
/// and every replaced island says which method broke the rule and which one replaced it.
#[test]
fn the_last_resort_tries_the_methods_flip_free_kin_first() {
    use uvflat_core::pipeline::last_resort::kin;
    let Some(dir) = shared_meshes() else { return };
    let s = tris_to_quads(&load(&dir.join("cow.off")));
    let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Lscm, ..Default::default() }).unwrap();
    check_rule("cow quads", "lscm", &s, &[], &r);
    let mut by = std::collections::BTreeMap::new();
    for c in r.charts.iter().filter(|c| c.method != "lscm") {
        assert_eq!(c.status, ChartStatus::Fallback, "island {}: {:?}", c.id, c.reason);
        let reason = c.reason.as_deref().unwrap_or("");
        assert!(reason.starts_with("lscm broke the atlas rule"), "island {}: {reason}", c.id);
        assert!(reason.contains(&format!("; {}, which", c.method)), "island {}: {reason}", c.id);
        *by.entry(c.method).or_insert(0) += 1;
    }
    assert!(by.get("mips").copied().unwrap_or(0) > 0, "no island by MIPS: {by:?}");
    assert!(by.keys().all(|m| ["mips", "scaffold"].contains(m)), "{by:?}");
    assert_eq!(kin(&Method::Arap(Default::default())).map(|m| m.name()), Some("slim"));
    assert_eq!(kin(&Method::Lscm).map(|m| m.name()), Some("mips"));
    assert!(kin(&Method::Slim(Default::default())).is_none());
}
