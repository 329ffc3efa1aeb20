//! The coarse proxy a large chart's cones are planned on (`cuts::coarse`): it keeps the
//! chart's topology and outline exactly, its vertices are the chart's, it is the same from run
//! to run, and its prediction of a cut chart's flattening is close to the chart's own: at most
//! `pipeline::predict::PROXY_MARGIN` more optimistic (the margin the plan relies on), and at
//! most 0.02 more pessimistic.

mod common;

use common::{load, octahedron_sphere, shared_meshes, sphere, with_holes, Soup};
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::cuts::coarse::{wants_proxy, Proxy, CLOSED_PROXY_FROM, PROXY_FROM, PROXY_VERTICES};
use uvflat_core::cuts::{AutoSeamOptions, ChartCutter};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::pipeline::predict::PROXY_MARGIN;

/// An octahedron subdivided `levels` times, on an ellipsoid with a bump (smooth, closed,
/// curvature uneven).
fn bumpy_ellipsoid(levels: usize) -> Soup {
    let mut s = octahedron_sphere(levels);
    for p in &mut s.positions {
        let bump = 1.0 + 0.6 * (-8.0 * ((p[0] - 0.6).powi(2) + p[1].powi(2))).exp();
        *p = [2.0 * bump * p[0], p[1], 0.6 * p[2]];
    }
    s
}

fn charts_of(s: &Soup) -> Vec<Chart> {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    build_charts(&mesh, &[], None)
}

/// Euler characteristic `V − E + F` of an oriented manifold triangle list: an edge is two
/// directed edges, or one on the boundary.
fn euler(n: usize, triangles: &[[u32; 3]]) -> i64 {
    let directed: std::collections::HashSet<(u32, u32)> =
        triangles.iter().flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]).collect();
    let twins = directed.iter().filter(|&&(a, b)| directed.contains(&(b, a))).count();
    let edges = twins / 2 + (directed.len() - twins);
    n as i64 - edges as i64 + triangles.len() as i64
}

/// Every invariant of a proxy of `chart` made down to `target` vertices.
fn check_proxy(chart: &Chart, target: usize, name: &str) -> Proxy {
    let proxy = Proxy::with_target(chart, target).unwrap_or_else(|| panic!("{name}: no proxy"));
    let (pc, n, m) = (&proxy.chart, chart.positions.len(), proxy.fine_of.len());
    pc.sanity_check();
    assert_eq!(pc.positions.len(), m, "{name}");
    assert!(m < n / 2, "{name}: {n} vertices coarsened to {m} only (target {target})");
    // Same topology: Euler characteristic, genus, kind, boundary loops vertex for vertex.
    assert_eq!(euler(m, &pc.triangles), euler(n, &chart.triangles), "{name}: Euler characteristic");
    assert_eq!((pc.genus, pc.kind), (chart.genus, chart.kind), "{name}");
    assert_eq!(pc.boundary_loops.len(), chart.boundary_loops.len(), "{name}");
    for (a, b) in pc.boundary_loops.iter().zip(&chart.boundary_loops) {
        let back: Vec<u32> = a.iter().map(|&c| proxy.fine_of[c as usize]).collect();
        assert_eq!(&back, b, "{name}: the outline is kept exactly");
    }
    // Its vertices are the chart's, in order; every chart vertex has a representative.
    assert!(proxy.fine_of.windows(2).all(|w| w[0] < w[1]), "{name}");
    for (c, &v) in proxy.fine_of.iter().enumerate() {
        assert_eq!(pc.positions[c], chart.positions[v as usize], "{name}");
        assert_eq!(proxy.rep[v as usize], c as u32, "{name}: a survivor represents itself");
    }
    assert_eq!(proxy.rep.len(), n);
    assert!(proxy.rep.iter().all(|&c| (c as usize) < m), "{name}");
    // No proxy triangle lost its area.
    let p = &pc.positions;
    for t in &pc.triangles {
        let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        let (e, f) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
        let x = [e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]];
        assert!(x.iter().map(|v| v * v).sum::<f64>() > 0.0, "{name}: a proxy triangle without area");
    }
    proxy
}

#[test]
fn the_proxy_keeps_topology_outline_and_vertices() {
    let closed = bumpy_ellipsoid(5);
    let holes = with_holes(&sphere(96, 64, |_| true), 5, 60, 7);
    let cap = sphere(96, 64, |c| c[2] > -0.3);
    for (name, s) in [("bumpy ellipsoid", closed), ("sphere with holes", holes), ("cap", cap)] {
        for chart in charts_of(&s) {
            if chart.triangles.len() < 1000 {
                continue;
            }
            check_proxy(&chart, chart.positions.len() / 8, name);
        }
    }
}

#[test]
fn the_proxy_of_shared_meshes_keeps_their_topology() {
    let Some(dir) = shared_meshes() else {
        eprintln!("skipped: ../shared/meshes is absent");
        return;
    };
    for name in ["bunny.off", "3holes.off", "fertility.off", "camelhead.off"] {
        let s = load(&dir.join(name));
        for chart in charts_of(&s) {
            if chart.triangles.len() < 1000 || chart.defect.is_some() {
                continue;
            }
            check_proxy(&chart, chart.positions.len() / 6, name);
        }
    }
}

/// Closed charts plan on a proxy from `CLOSED_PROXY_FROM` triangles, of about a third of their
/// vertices; a chart of that size with several holes does not until `PROXY_FROM`, nor does a
/// smaller closed one.
#[test]
fn closed_charts_plan_on_a_proxy_from_a_lower_size() {
    let closed = charts_of(&bumpy_ellipsoid(7)).remove(0);
    let n = closed.triangles.len();
    assert!((CLOSED_PROXY_FROM..PROXY_FROM).contains(&n), "{n} triangles");
    assert!(wants_proxy(&closed));
    let proxy = Proxy::new(&closed).expect("a closed chart of 131k triangles has a proxy");
    let (v, m) = (closed.positions.len(), proxy.chart.positions.len());
    assert!(m <= PROXY_VERTICES && m * 10 <= v * 4 && m * 10 >= v * 2, "{v} vertices coarsened to {m}");
    let holes = with_holes(&bumpy_ellipsoid(7), 5, 30, 3);
    let with_holes: Vec<Chart> = charts_of(&holes).into_iter().filter(|c| c.triangles.len() > 1000).collect();
    assert_eq!(with_holes.len(), 1);
    assert_eq!(with_holes[0].boundary_loops.len(), 5);
    assert!(!wants_proxy(&with_holes[0]) && Proxy::new(&with_holes[0]).is_none());
    let small = charts_of(&bumpy_ellipsoid(6)).remove(0);
    assert!(!wants_proxy(&small) && Proxy::new(&small).is_none());
}

#[test]
fn the_proxy_is_the_same_from_run_to_run() {
    let chart = charts_of(&bumpy_ellipsoid(4)).remove(0);
    let (a, b) = (Proxy::with_target(&chart, 400).unwrap(), Proxy::with_target(&chart, 400).unwrap());
    assert_eq!(a.fine_of, b.fine_of);
    assert_eq!(a.chart.triangles, b.chart.triangles);
    assert_eq!(a.rep, b.rep);
}

/// `(share outside [1/s, s], area-weighted mean of max(r, 1/r))` of predicted ratios.
fn stats(ratios: &[(f64, f64)], s: f64) -> (f64, f64) {
    let total: f64 = ratios.iter().map(|x| x.1).sum();
    let outside: f64 = ratios.iter().filter(|x| x.0 > s || x.0 < 1.0 / s).map(|x| x.1).sum::<f64>() / total;
    let mean = ratios.iter().map(|&(x, a)| a * x.max(1.0 / x)).sum::<f64>() / total;
    (outside, mean)
}

#[test]
fn a_cut_planned_on_the_proxy_opens_the_chart_and_is_predicted_close_to_the_chart() {
    let s = bumpy_ellipsoid(6);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let chart = build_charts(&mesh, &[], None).remove(0);
    let avoid = vec![false; s.positions.len()];
    let options = AutoSeamOptions { max_stretch: 1.5, max_cones: 2, ..Default::default() };
    let proxy = Proxy::with_target(&chart, chart.positions.len() / 4).unwrap();
    let cutter = ChartCutter::new(&mesh, &chart, &options, &avoid).with_proxy(proxy);
    assert!(cutter.proxy().is_some());
    let mut seeds: Vec<u32> = Vec::new();
    for round in 0..3 {
        let cut = cutter.plan_cut(&seeds, round);
        // Cones are vertices of the chart where cones are allowed, seeds kept (by their
        // representatives).
        assert!(cut.cones.len() >= 2, "a closed chart gets at least 2 cones");
        for &c in &cut.cones {
            assert!(cutter.allowed()[c as usize], "cone {c} is not allowed");
        }
        for &v in &seeds {
            let rep = cutter.proxy().unwrap().fine_of[cutter.proxy().unwrap().rep[v as usize] as usize];
            assert!(cut.cones.contains(&rep), "round {round}: seed {v} (representative {rep}) lost");
        }
        // The cut opens the chart into one disk.
        let pieces = build_charts(&mesh, &cut.seams, None);
        assert_eq!(pieces.len(), 1, "round {round}");
        assert_eq!((pieces[0].boundary_loops.len(), pieces[0].genus), (1, 0), "round {round}: not a disk");
        // The proxy's prediction is close to the chart's own, and not pessimistic beyond a
        // hair (the plan's margin covers the optimism only).
        let on_proxy = stats(&cutter.predicted_ratios_after(&cut).unwrap(), 1.5);
        let on_chart = stats(&cutter.predicted_ratios_on_chart(&cut).unwrap(), 1.5);
        eprintln!("round {round}: proxy {on_proxy:?}, chart {on_chart:?}, {} cones", cut.cones.len());
        assert!(on_chart.1 > 1.05, "round {round}: the case must have distortion to predict");
        assert!(
            on_chart.0 - on_proxy.0 <= PROXY_MARGIN.0 && on_proxy.0 - on_chart.0 <= 0.02,
            "round {round}: share outside {on_proxy:?} on the proxy, {on_chart:?} on the chart"
        );
        assert!(
            on_chart.1 - on_proxy.1 <= PROXY_MARGIN.1 && on_proxy.1 - on_chart.1 <= 0.02,
            "round {round}: mean {on_proxy:?} on the proxy, {on_chart:?} on the chart"
        );
        // Next round: one more cone where the surface is most crushed on the chart's own
        // prediction (any chart vertex: it goes to its representative).
        seeds = cut.cones.clone();
        let ratios = cutter.predicted_ratios_on_chart(&cut).unwrap();
        let worst = (0..chart.triangles.len()).min_by(|&a, &b| ratios[a].0.total_cmp(&ratios[b].0)).unwrap();
        let v = chart.triangles[worst][0];
        if cutter.allowed()[v as usize] {
            seeds.push(v);
        }
    }
}
