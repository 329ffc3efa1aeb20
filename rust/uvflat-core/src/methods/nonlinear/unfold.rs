//! Isometric unfolding of a chart without interior vertices.
//!
//! A triangulated disk whose vertices all lie on its one boundary loop (a triangulated
//! polygon: `F = V − 2` triangles) has a dual graph that is a tree, so it is developable: laying
//! the triangles out one after the other across their shared edges, each with its own 3D edge
//! lengths, gives a map that is an isometry on every triangle. Every vertex sits on an open fan
//! of triangles joined edge to edge through it, so it is placed once and keeps its place.
//!
//! Such charts are what a model cut into many small islands is made of (one or two quads per
//! island), and an isometry is the global minimiser of the distortion energies of the barrier
//! methods (symmetric Dirichlet, ARAP), so they need no solve at all. Each triangle is laid
//! out counter-clockwise, so the map has no flipped triangle; the outline of a long strip may
//! still overlap itself, which no per-triangle energy sees either.
//!
//! Preconditions: none (any chart). Returns `None` for a chart that is not a triangulated
//! polygon (interior vertices, holes, a disconnected or non-manifold triangle set), or whose
//! unfolding has a triangle of zero or non-finite area (degenerate 3D triangles).

use crate::charts::Chart;
use crate::geometry::{norm, sub};

/// The isometric unfolding of `chart` (module docs), or `None` where it does not apply.
pub fn unfold(chart: &Chart) -> Option<Vec<[f64; 2]>> {
    let (n, tris) = (chart.positions.len(), &chart.triangles);
    if tris.is_empty() || chart.boundary_loops.len() != 1 || chart.boundary_loops[0].len() != n || tris.len() + 2 != n {
        return None;
    }
    // Interior edges: the two triangles of every edge (sorted edge keys).
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * tris.len());
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), f as u32));
        }
    }
    edges.sort_unstable();
    let mut across: Vec<[u32; 3]> = vec![[u32::MAX; 3]; tris.len()];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && (edges[j].0, edges[j].1) == (edges[i].0, edges[i].1) {
            j += 1;
        }
        match j - i {
            1 => {}
            2 => {
                let (f, g) = (edges[i].2 as usize, edges[i + 1].2 as usize);
                let side = |f: usize| (0..3).find(|&k| {
                    let (a, b) = (tris[f][k], tris[f][(k + 1) % 3]);
                    (a.min(b), a.max(b)) == (edges[i].0, edges[i].1)
                });
                across[f][side(f)?] = g as u32;
                across[g][side(g)?] = f as u32;
            }
            _ => return None,
        }
        i = j;
    }
    let p = &chart.positions;
    let len = |a: u32, b: u32| norm(sub(p[b as usize], p[a as usize]));
    let mut uv = vec![[f64::NAN; 2]; n];
    let mut placed = vec![false; tris.len()];
    // The first triangle: its first edge along +u.
    let t0 = tris[0];
    let l01 = len(t0[0], t0[1]);
    uv[t0[0] as usize] = [0.0, 0.0];
    uv[t0[1] as usize] = [l01, 0.0];
    uv[t0[2] as usize] = apex([0.0, 0.0], [l01, 0.0], len(t0[0], t0[2]), len(t0[1], t0[2]))?;
    placed[0] = true;
    let mut stack = vec![0usize];
    let mut count = 1;
    while let Some(f) = stack.pop() {
        for k in 0..3 {
            let g = across[f][k];
            if g == u32::MAX || placed[g as usize] {
                continue;
            }
            let g = g as usize;
            // In g's own winding the shared edge runs b → a; its third corner c follows a.
            let (a, b) = (tris[f][k], tris[f][(k + 1) % 3]);
            let c = (0..3).map(|m| tris[g][m]).find(|&v| v != a && v != b)?;
            let pos = apex(uv[b as usize], uv[a as usize], len(b, c), len(a, c))?;
            let old = uv[c as usize];
            if !old[0].is_nan() {
                // Placed before through its fan: it must be the same point.
                let scale = len(a, c).max(len(b, c)).max(f64::MIN_POSITIVE);
                if ((old[0] - pos[0]).powi(2) + (old[1] - pos[1]).powi(2)).sqrt() > 1e-9 * scale {
                    return None;
                }
            }
            uv[c as usize] = pos;
            placed[g] = true;
            count += 1;
            stack.push(g);
        }
    }
    (count == tris.len() && uv.iter().all(|q| q[0].is_finite() && q[1].is_finite())).then_some(uv)
}

/// The third corner `c` of the counter-clockwise triangle `(a, b, c)` with `|ac| = lac` and
/// `|bc| = lbc`; `None` if that triangle has no positive area (lengths violating the triangle
/// inequality, or a degenerate edge).
fn apex(a: [f64; 2], b: [f64; 2], lac: f64, lbc: f64) -> Option<[f64; 2]> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let d = (dx * dx + dy * dy).sqrt();
    if !(d > 0.0) {
        return None;
    }
    let x = (lac * lac - lbc * lbc + d * d) / (2.0 * d);
    let y2 = lac * lac - x * x;
    if !(y2 > 0.0) {
        return None;
    }
    let y = y2.sqrt();
    let (ex, ey) = (dx / d, dy / d);
    Some([a[0] + x * ex - y * ey, a[1] + x * ey + y * ex])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::build_charts;
    use crate::mesh::PolyMesh;

    fn chart_of(positions: &[[f64; 3]], tris: &[[u32; 3]]) -> Chart {
        let corner: Vec<u32> = tris.iter().flatten().copied().collect();
        let sizes = vec![3u32; tris.len()];
        let mesh = PolyMesh::new(positions, &corner, &sizes).unwrap();
        build_charts(&mesh, &[], None).remove(0)
    }

    fn area(q: [[f64; 2]; 3]) -> f64 {
        0.5 * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]))
    }

    #[test]
    fn a_folded_strip_unfolds_isometrically_and_counter_clockwise() {
        // A zig-zag strip of 12 triangles folded in 3D along every other interior edge.
        let m = 7;
        let mut positions = Vec::new();
        for i in 0..m {
            let z = if i % 2 == 0 { 0.0 } else { 0.4 + 0.1 * i as f64 };
            positions.push([i as f64, 0.0, z]);
            positions.push([i as f64 + 0.3, 1.0, -z]);
        }
        let mut tris = Vec::new();
        for i in 0..m - 1 {
            let (a, b, c, d) = (2 * i as u32, 2 * i as u32 + 1, 2 * i as u32 + 2, 2 * i as u32 + 3);
            tris.push([a, c, b]);
            tris.push([b, c, d]);
        }
        let chart = chart_of(&positions, &tris);
        let uv = unfold(&chart).expect("a triangulated polygon");
        for t in &chart.triangles {
            let q = [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
            assert!(area(q) > 0.0, "{t:?} not counter-clockwise");
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let l3 = norm(sub(chart.positions[b], chart.positions[a]));
                let l2 = ((uv[b][0] - uv[a][0]).powi(2) + (uv[b][1] - uv[a][1]).powi(2)).sqrt();
                assert!((l3 - l2).abs() < 1e-12 * l3.max(1.0), "edge {a}-{b}: {l3} vs {l2}");
            }
        }
    }

    #[test]
    fn charts_with_an_interior_vertex_a_hole_or_a_degenerate_triangle_are_not_unfolded() {
        // A fan around an interior vertex (non-developable: raised centre).
        let mut positions = vec![[0.0, 0.0, 0.5]];
        let k = 6;
        for i in 0..k {
            let a = i as f64 / k as f64 * std::f64::consts::TAU;
            positions.push([a.cos(), a.sin(), 0.0]);
        }
        let fan: Vec<[u32; 3]> = (0..k as u32).map(|i| [0, 1 + i, 1 + (i + 1) % k as u32]).collect();
        assert!(unfold(&chart_of(&positions, &fan)).is_none());
        // A ring (one hole): every vertex is on a boundary, but the dual graph has a cycle.
        let m = 8u32;
        let mut ring = Vec::new();
        for i in 0..m {
            let a = i as f64 / m as f64 * std::f64::consts::TAU;
            ring.push([a.cos(), a.sin(), 0.0]);
            ring.push([2.0 * a.cos(), 2.0 * a.sin(), 0.3]);
        }
        let band: Vec<[u32; 3]> = (0..m)
            .flat_map(|i| {
                let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * ((i + 1) % m), 2 * ((i + 1) % m) + 1);
                [[a, b, d], [a, d, c]]
            })
            .collect();
        assert!(unfold(&chart_of(&ring, &band)).is_none());
        // Two triangles, one of them with collinear corners.
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
        assert!(unfold(&chart_of(&flat, &[[0, 1, 3], [1, 2, 3]])).is_some());
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        assert!(unfold(&chart_of(&line, &[[0, 1, 2], [0, 2, 3]])).is_none());
    }

    #[test]
    fn slim_keeps_the_unfolding_of_a_chart_without_interior_vertices_and_does_not_iterate() {
        // A fan of 8 triangles around a boundary vertex, bent in 3D (developable: no interior
        // vertex), plus a zig-zag tail.
        let mut positions = vec![[0.0, 0.0, 0.0]];
        for i in 0..9 {
            let a = i as f64 * 0.35;
            positions.push([a.cos(), a.sin(), 0.3 * (i % 2) as f64]);
        }
        let tris: Vec<[u32; 3]> = (1..9u32).map(|i| [0, i, i + 1]).collect();
        let chart = chart_of(&positions, &tris);
        let auto = crate::methods::slim::SlimOptions::default();
        let (sol, history) = crate::methods::slim::solve_with_history(&chart, &[], &auto).unwrap();
        assert_eq!(history.start, "unfold");
        assert!(history.step.is_empty(), "no iteration expected: {:?}", history.step);
        let e = history.energy[0];
        assert!((e - 1.0).abs() < 1e-12, "an isometry has symmetric Dirichlet 1, got {e}");
        // The mean value start iterates towards the same minimum and cannot go below it.
        let mv = crate::methods::slim::SlimOptions { start: crate::methods::slim::SlimStart::MeanValue, ..auto };
        let (_, mv_history) = crate::methods::slim::solve_with_history(&chart, &[], &mv).unwrap();
        assert_eq!(mv_history.start, "mean_value");
        assert!(*mv_history.energy.last().unwrap() >= e - 1e-12);
        for t in &chart.triangles {
            let q = [sol.uv[t[0] as usize], sol.uv[t[1] as usize], sol.uv[t[2] as usize]];
            assert!(area(q) > 0.0);
        }
    }
}
