//! Pins are a promise: a pinned vertex ends exactly at its pinned UV, whatever the method, the
//! number of pins and whether the pins agree with the mesh; and the nonlinear methods lay the
//! unpinned part out at the pins' scale, not at 3D scale around them.
//!
//! Charts: a bumpy grid disk, a spherical cap (far from developable) and a cut cylinder of
//! quads. Pins: 1, 3, 4 and 10 vertices spread over the chart, at a scaled, rotated and moved
//! copy of the chart's free LSCM map (scales 0.05 and 3), or at positions that no map of the
//! mesh fits (stretched and jittered), or mirrored (every map honouring them folds, so the
//! barrier methods fall back).

mod common;

use common::*;
use uvflat_core::charts::{build_charts, Chart};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::nonlinear::pins::pinned_fallback;
use uvflat_core::methods::{self, arap, mips, scaffold, slim};
use uvflat_core::Method;

fn chart_of(s: &Soup, seams: &[[u32; 2]]) -> Chart {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let mut charts = build_charts(&mesh, seams, None);
    assert_eq!(charts.len(), 1);
    charts.remove(0)
}

/// A planar ring disk lifted onto a smooth bump (not developable).
fn bumpy_disk() -> Chart {
    let mut s = planar_disk(6, 7);
    for p in s.positions.iter_mut() {
        p[2] = 1.5 * (-(p[0] * p[0] + p[1] * p[1]) / 10.0).exp() + 0.3 * (0.8 * p[0]).sin() * (0.6 * p[1]).cos();
    }
    chart_of(&s, &[])
}

/// A spherical cap reaching almost to the equator: the ring disk projected onto the unit sphere.
fn cap() -> Chart {
    let mut s = planar_disk(6, 7);
    let r_max = s.positions.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
    for p in s.positions.iter_mut() {
        let (x, y) = (0.97 * p[0] / r_max, 0.97 * p[1] / r_max);
        *p = [x, y, (1.0 - x * x - y * y).sqrt()];
    }
    chart_of(&s, &[])
}

/// A cylinder of quads cut along one generator.
fn cylinder() -> Chart {
    let (s, seams) = cut_cylinder(16, 5, 1.5);
    chart_of(&s, &seams)
}

fn charts() -> Vec<(&'static str, Chart)> {
    vec![("bumpy disk", bumpy_disk()), ("cap", cap()), ("cylinder", cylinder())]
}

/// `k` distinct chart vertices spread over the chart (a fixed stride through the vertex list,
/// so boundary and interior vertices both occur).
fn pinned_vertices(chart: &Chart, k: usize) -> Vec<u32> {
    let n = chart.positions.len();
    assert!(n >= 2 * k);
    (0..k).map(|i| ((2 * i + 1) * n / (2 * k)) as u32).collect()
}

fn free_lscm(chart: &Chart) -> Vec<[f64; 2]> {
    methods::solve(&Method::Lscm, chart, &[]).unwrap().uv
}

/// `sqrt(UV area / 3D area)` over the triangles for which `keep` holds.
fn density(chart: &Chart, uv: &[[f64; 2]], keep: impl Fn(&[u32; 3]) -> bool) -> f64 {
    let (mut a2, mut a3) = (0.0, 0.0);
    for t in chart.triangles.iter().filter(|t| keep(t)) {
        let [p, q, r] = t.map(|v| chart.positions[v as usize]);
        let (e1, e2) = ([q[0] - p[0], q[1] - p[1], q[2] - p[2]], [r[0] - p[0], r[1] - p[1], r[2] - p[2]]);
        let c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        a3 += 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        a2 += 0.5 * doubled_signed_areas(&[*t], uv)[0];
    }
    (a2 / a3).sqrt()
}

/// The pins of `vertices` at the similarity `scale · rot(angle) · z + shift` of the map `z`.
fn similar_pins(z: &[[f64; 2]], vertices: &[u32], scale: f64, angle: f64, shift: [f64; 2]) -> Vec<(u32, [f64; 2])> {
    let (c, s) = (scale * angle.cos(), scale * angle.sin());
    vertices.iter().map(|&v| {
        let p = z[v as usize];
        (v, [c * p[0] - s * p[1] + shift[0], s * p[0] + c * p[1] + shift[1]])
    }).collect()
}

/// Largest distance of a pinned vertex from its pin.
fn pin_displacement(uv: &[[f64; 2]], pins: &[(u32, [f64; 2])]) -> f64 {
    pins.iter().map(|&(v, p)| (uv[v as usize][0] - p[0]).hypot(uv[v as usize][1] - p[1])).fold(0.0, f64::max)
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum PinSet {
    /// A similar copy of the free LSCM map at this scale.
    Similar(f64),
    /// The LSCM map stretched 2.5× along u and jittered by up to a fifth of its size.
    Inconsistent,
}

fn pin_sets(chart: &Chart, k: usize, set: PinSet) -> Vec<(u32, [f64; 2])> {
    let z = free_lscm(chart);
    let vertices = pinned_vertices(chart, k);
    match set {
        PinSet::Similar(scale) => similar_pins(&z, &vertices, scale, 0.7, [0.5, 0.25]),
        PinSet::Inconsistent => {
            let size = z.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max);
            let mut state = 0x2545_f491_4f6c_dd1du64;
            let mut jitter = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            similar_pins(&z, &vertices, 0.4, -0.3, [0.1, 0.9])
                .into_iter()
                .map(|(v, p)| (v, [2.5 * p[0] + 0.4 * size * jitter(), p[1] + 0.4 * size * jitter()]))
                .collect()
        }
    }
}

/// Every method, iterative ones capped so the test stays quick.
fn methods_under_test() -> Vec<Method> {
    every_method(20, 60)
}

#[test]
fn every_method_holds_every_pin_exactly() {
    let mut worst = 0.0f64;
    for (name, chart) in charts() {
        for k in [1usize, 3, 4, 10] {
            for set in [PinSet::Similar(0.05), PinSet::Similar(3.0), PinSet::Inconsistent] {
                let pins = pin_sets(&chart, k, set);
                for m in methods_under_test() {
                    let sol = methods::solve(&m, &chart, &pins).unwrap_or_else(|e| panic!("{name}, {k} pins {set:?}, {m:?}: failed: {}", e.0));
                    let d = pin_displacement(&sol.uv, &pins);
                    worst = worst.max(d);
                    assert!(
                        d == 0.0,
                        "{name}, {k} pins {set:?}, {}: a pin moved by {d:e} (fallback {:?})",
                        m.name(),
                        sol.fallback
                    );
                    assert!(sol.uv.iter().all(|p| p[0].is_finite() && p[1].is_finite()), "{name} {}: non-finite UV", m.name());
                }
            }
        }
    }
    eprintln!("largest pin displacement over every chart, pin set and method: {worst:e}");
}

#[test]
fn nonlinear_methods_lay_the_free_part_out_at_the_pins_scale() {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for (name, chart) in charts() {
        let z = free_lscm(&chart);
        let lscm_density = density(&chart, &z, |_| true);
        for k in [3usize, 4, 10] {
            for scale in [0.05, 3.0] {
                let pins = pin_sets(&chart, k, PinSet::Similar(scale));
                let pinned: Vec<bool> = {
                    let mut p = vec![false; chart.positions.len()];
                    pins.iter().for_each(|&(v, _)| p[v as usize] = true);
                    p
                };
                let want = scale * lscm_density;
                let nonlinear = [
                    Method::Arap(arap::ArapOptions::default()),
                    Method::Slim(slim::SlimOptions::default()),
                    Method::Mips(mips::MipsOptions::default()),
                    Method::Scaffold(scaffold::ScaffoldOptions { max_iterations: 30, ..Default::default() }),
                ];
                for m in nonlinear {
                    let sol = methods::solve(&m, &chart, &pins).unwrap();
                    assert!(sol.fallback.is_none(), "{name}, {k} pins at scale {scale}, {}: {:?}", m.name(), sol.fallback);
                    assert_eq!(pin_displacement(&sol.uv, &pins), 0.0);
                    let got = density(&chart, &sol.uv, |t| t.iter().all(|&v| !pinned[v as usize]));
                    let ratio = got / want;
                    (lo, hi) = (lo.min(ratio), hi.max(ratio));
                    assert!(
                        (0.75..=1.25).contains(&ratio),
                        "{name}, {k} pins at scale {scale}, {}: the unpinned part has density {got:.4}, the pins {want:.4} (ratio {ratio:.3})",
                        m.name()
                    );
                }
            }
        }
    }
    eprintln!("density of the unpinned part over the pins' scale: {lo:.3} to {hi:.3}");
}

/// Pins mirrored (the LSCM map reflected): every map honouring them folds, so the barrier
/// methods have no flip-free start and fall back; the fallback holds the pins.
#[test]
fn fallbacks_hold_the_pins() {
    for (name, chart) in charts() {
        let z = free_lscm(&chart);
        let mirrored: Vec<[f64; 2]> = z.iter().map(|p| [-p[0], p[1]]).collect();
        let pins = similar_pins(&mirrored, &pinned_vertices(&chart, 10), 0.3, 0.2, [0.0, 0.0]);
        for m in [
            Method::Slim(slim::SlimOptions::default()),
            Method::Mips(mips::MipsOptions::default()),
            Method::Scaffold(scaffold::ScaffoldOptions::default()),
        ] {
            let sol = methods::solve(&m, &chart, &pins).unwrap();
            let fb = sol.fallback.as_ref().unwrap_or_else(|| panic!("{name}, {}: no fallback with mirrored pins", m.name()));
            assert!(matches!(fb.method, "lscm" | "mean_value"), "{name}, {}: fell back to {}", m.name(), fb.method);
            assert_eq!(pin_displacement(&sol.uv, &pins), 0.0, "{name}, {}: fallback {} moved a pin", m.name(), fb.method);
        }
        // The shared fallback itself, with spanning pins and with a single pin.
        for pins in [pins.clone(), vec![(3u32, [0.123456789, -7.654321])]] {
            let sol = pinned_fallback(&chart, &pins, "test").unwrap();
            assert!(sol.fallback.is_some());
            assert_eq!(pin_displacement(&sol.uv, &pins), 0.0, "{name}: pinned fallback moved a pin");
        }
    }
}
