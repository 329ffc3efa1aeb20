//! Planar halving: the fallback of [`super::split`] when the spectral split finds no cut.
//!
//! Precedent: xatlas's piecewise parameterization and split-until-valid segmenters. The
//! chart's polygons are split at the median of their centroids' projection on the principal
//! axis of the chart (covariance of the polygon centroids), so both halves hold about half
//! the polygons and the new seam crosses the chart's long direction. The seam follows polygon
//! edges around the faces on one side of a plane, so on triangles it is a staircase; the
//! spectral split is preferred for that reason.
//!
//! Preconditions: none (any chart graph). Failures: an empty seam list when the chart has
//! fewer than two polygons or every candidate touches an avoided vertex. Deterministic: the
//! principal axis by power iteration from a fixed start, ties by polygon id.

use super::graph::ChartGraph;
use crate::charts::Chart;

/// Seams (mesh vertex pairs) that split `chart` into two parts; empty if it has fewer than two
/// polygons or every candidate split would touch a vertex in `avoid` (per mesh vertex).
///
/// Candidates, in order: the principal axis, then x, y and z, each split at the median of the
/// polygons, then at the 40/60, 30/70 and 20/80 quantiles.
pub fn halve_planar(graph: &ChartGraph, chart: &Chart, avoid: &[bool]) -> Vec<[u32; 2]> {
    let np = graph.polygons.len();
    if np < 2 {
        return Vec::new();
    }
    let centroid: Vec<[f64; 3]> = graph
        .polygons
        .iter()
        .map(|poly| {
            let mut c = [0.0; 3];
            for &v in poly {
                for k in 0..3 {
                    c[k] += chart.positions[v as usize][k];
                }
            }
            let n = poly.len() as f64;
            [c[0] / n, c[1] / n, c[2] / n]
        })
        .collect();
    let mut mean = [0.0; 3];
    for c in &centroid {
        for k in 0..3 {
            mean[k] += c[k] / np as f64;
        }
    }
    let mut cov = [[0.0f64; 3]; 3];
    for c in &centroid {
        let d = [c[0] - mean[0], c[1] - mean[1], c[2] - mean[2]];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j];
            }
        }
    }
    // Principal axis by power iteration from a fixed start (deterministic).
    let mut axis = [1.0, 0.7, 0.3];
    for _ in 0..64 {
        let next = [
            cov[0][0] * axis[0] + cov[0][1] * axis[1] + cov[0][2] * axis[2],
            cov[1][0] * axis[0] + cov[1][1] * axis[1] + cov[1][2] * axis[2],
            cov[2][0] * axis[0] + cov[2][1] * axis[1] + cov[2][2] * axis[2],
        ];
        let l = (next[0] * next[0] + next[1] * next[1] + next[2] * next[2]).sqrt();
        if !(l > 0.0) {
            break;
        }
        axis = [next[0] / l, next[1] / l, next[2] / l];
    }
    for axis in [axis, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        let proj: Vec<f64> = centroid
            .iter()
            .map(|c| (c[0] - mean[0]) * axis[0] + (c[1] - mean[1]) * axis[1] + (c[2] - mean[2]) * axis[2])
            .collect();
        let mut order: Vec<usize> = (0..np).collect();
        order.sort_by(|&a, &b| proj[a].total_cmp(&proj[b]).then(a.cmp(&b)));
        for q in [0.5, 0.4, 0.6, 0.3, 0.7, 0.2, 0.8] {
            let k = ((np as f64 * q) as usize).clamp(1, np - 1);
            let mut side = vec![false; np];
            for &p in &order[k..] {
                side[p] = true;
            }
            keep_sides_connected(graph, &mut side);
            let mut seams = Vec::new();
            let mut touches = false;
            for (e, p) in graph.edge_polygons.iter().enumerate() {
                if p[1] != u32::MAX && side[p[0] as usize] != side[p[1] as usize] {
                    let [a, b] = graph.edges[e];
                    let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
                    touches |= avoid[ma as usize] || avoid[mb as usize];
                    seams.push([ma.min(mb), ma.max(mb)]);
                }
            }
            if !touches && !seams.is_empty() {
                return seams;
            }
        }
    }
    Vec::new()
}

/// Move every connected piece of a side but its largest to the other side, so a split makes
/// two connected parts instead of a few slivers (a plane through a curved chart can cut off
/// small fragments).
fn keep_sides_connected(graph: &ChartGraph, side: &mut [bool]) {
    let np = side.len();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); np];
    for p in &graph.edge_polygons {
        if p[1] != u32::MAX {
            neighbours[p[0] as usize].push(p[1]);
            neighbours[p[1] as usize].push(p[0]);
        }
    }
    for pass in 0..2 {
        let mut comp = vec![u32::MAX; np];
        let mut sizes: Vec<(usize, bool)> = Vec::new();
        for s in 0..np {
            if comp[s] != u32::MAX {
                continue;
            }
            let id = sizes.len() as u32;
            let mut stack = vec![s];
            comp[s] = id;
            let mut n = 0;
            while let Some(p) = stack.pop() {
                n += 1;
                for &q in &neighbours[p] {
                    let q = q as usize;
                    if comp[q] == u32::MAX && side[q] == side[s] {
                        comp[q] = id;
                        stack.push(q);
                    }
                }
            }
            sizes.push((n, side[s]));
        }
        // Largest component of each side (first one on ties: deterministic).
        let mut best = [None::<usize>; 2];
        for (c, &(n, sd)) in sizes.iter().enumerate() {
            let slot = &mut best[sd as usize];
            if slot.is_none_or(|b| n > sizes[b].0) {
                *slot = Some(c);
            }
        }
        let mut changed = false;
        for p in 0..np {
            let c = comp[p] as usize;
            if Some(c) != best[sizes[c].1 as usize] && best[!sizes[c].1 as usize].is_some() {
                side[p] = !side[p];
                changed = true;
            }
        }
        if !changed || pass == 1 {
            break;
        }
    }
}
