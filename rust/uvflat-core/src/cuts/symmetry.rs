//! Mirror symmetry of a chart: the map that sends every vertex to its mirror image.
//!
//! Precedent: extrinsic reflective symmetry detection by matching points to their reflections
//! (Mitra, Guibas & Pauly 2006 use it to verify candidate planes; Podolak et al. 2006's planar
//! reflective symmetry transform). Here the candidate planes are few and given: a plane through
//! the centroid of the chart's vertices, with normal a world axis ([`Symmetry::X`], `Y`, `Z`)
//! or each of the vertices' principal axes in turn ([`Symmetry::Auto`]; the normal of a mirror
//! plane of a symmetric point set is an eigenvector of its covariance). A plane is accepted
//! when:
//! 1. every vertex's reflection lies within [`TOLERANCE`] × the bounding-box diagonal of a
//!    vertex (the nearest, ties to the lower id; a uniform grid finds it);
//! 2. the map is an involution (`σ(σ(v)) = v`);
//! 3. it preserves edges (`σ(a)σ(b)` is an edge for every edge `ab`).
//!
//! Preconditions: none. Failures: `None` when no candidate plane is accepted (an asymmetric
//! chart, a scan whose two sides were not sampled alike, near-duplicate vertices that make
//! the match ambiguous). Deterministic: fixed candidate order, ties by ids.

use std::collections::HashMap;

use super::graph::ChartGraph;
use crate::geometry::{dot, norm, sub};

/// Mirror symmetry to keep in automatic seams ([`super::AutoSeamOptions::symmetry`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Symmetry {
    /// No symmetry (default).
    #[default]
    None,
    /// The plane through the centroid with normal +x.
    X,
    /// The plane through the centroid with normal +y.
    Y,
    /// The plane through the centroid with normal +z.
    Z,
    /// The first of the principal axes (largest variance first) whose plane through the
    /// centroid is a mirror of the chart.
    Auto,
}

impl Symmetry {
    /// The names [`Symmetry::parse`] accepts, in declaration order (the choices of the
    /// `symmetry` option in [`super::options::auto_seam_options`]).
    pub const NAMES: &'static [&'static str] = &["none", "x", "y", "z", "auto"];

    /// The name of this symmetry (one of [`Symmetry::NAMES`]).
    pub fn name(self) -> &'static str {
        match self {
            Symmetry::None => "none",
            Symmetry::X => "x",
            Symmetry::Y => "y",
            Symmetry::Z => "z",
            Symmetry::Auto => "auto",
        }
    }

    /// The symmetry named `name` (`"none"`, `"x"`, `"y"`, `"z"` or `"auto"`, lower case).
    ///
    /// Errors: [`UnknownSymmetry`] holding the name.
    pub fn parse(name: &str) -> Result<Symmetry, UnknownSymmetry> {
        match name {
            "none" => Ok(Symmetry::None),
            "x" => Ok(Symmetry::X),
            "y" => Ok(Symmetry::Y),
            "z" => Ok(Symmetry::Z),
            "auto" => Ok(Symmetry::Auto),
            other => Err(UnknownSymmetry(other.to_string())),
        }
    }
}

impl std::str::FromStr for Symmetry {
    type Err = UnknownSymmetry;

    fn from_str(s: &str) -> Result<Symmetry, UnknownSymmetry> {
        Symmetry::parse(s)
    }
}

impl std::fmt::Display for Symmetry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A symmetry name [`Symmetry::parse`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown symmetry {0:?}; expected one of \"none\", \"x\", \"y\", \"z\", \"auto\"")]
pub struct UnknownSymmetry(pub String);

/// Largest distance between a reflected vertex and its match, relative to the bounding-box
/// diagonal.
pub const TOLERANCE: f64 = 1e-4;

/// A mirror of a chart.
#[derive(Debug, Clone)]
pub struct Mirror {
    /// Mirror image of every chart vertex (an involution).
    pub vertex: Vec<u32>,
    /// Mirror image of every edge of the chart graph (an involution).
    pub edge: Vec<u32>,
    /// A point of the plane (the centroid of the vertices).
    pub centre: [f64; 3],
    /// Unit normal of the plane.
    pub normal: [f64; 3],
}

impl Mirror {
    /// Signed distance of `p` to the plane.
    pub fn side(&self, p: [f64; 3]) -> f64 {
        dot(sub(p, self.centre), self.normal)
    }
}

/// The mirror of the chart whose graph is `graph` and vertex positions `positions`, as asked
/// by `symmetry` (see the module docs).
pub fn detect(graph: &ChartGraph, positions: &[[f64; 3]], symmetry: Symmetry) -> Option<Mirror> {
    let n = positions.len();
    if n == 0 || graph.n_vertices != n {
        return None;
    }
    let mut centre = [0.0; 3];
    for p in positions {
        for k in 0..3 {
            centre[k] += p[k] / n as f64;
        }
    }
    let candidates: Vec<[f64; 3]> = match symmetry {
        Symmetry::None => return None,
        Symmetry::X => vec![[1.0, 0.0, 0.0]],
        Symmetry::Y => vec![[0.0, 1.0, 0.0]],
        Symmetry::Z => vec![[0.0, 0.0, 1.0]],
        Symmetry::Auto => principal_axes(positions, centre),
    };
    candidates.into_iter().find_map(|normal| mirror_for_plane(graph, positions, centre, normal))
}

/// The mirror in the plane through `centre` with unit `normal`, if it is one (conditions 1–3).
pub fn mirror_for_plane(graph: &ChartGraph, positions: &[[f64; 3]], centre: [f64; 3], normal: [f64; 3]) -> Option<Mirror> {
    let n = positions.len();
    let (lo, hi) = crate::geometry::bounds(positions.iter());
    let diagonal = norm(sub(hi, lo));
    let l = norm(normal);
    if !(diagonal > 0.0 && diagonal.is_finite() && l > 0.0) {
        return None;
    }
    let normal = [normal[0] / l, normal[1] / l, normal[2] / l];
    let tol = TOLERANCE * diagonal;
    // Grid of cells of side `tol`: a match lies in one of the 27 cells around a reflection.
    let cell = |p: [f64; 3]| [(p[0] / tol).floor() as i64, (p[1] / tol).floor() as i64, (p[2] / tol).floor() as i64];
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
    for (v, &p) in positions.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(v as u32);
    }
    let mut vertex = vec![u32::MAX; n];
    for (v, &p) in positions.iter().enumerate() {
        let d = dot(sub(p, centre), normal);
        let r = [p[0] - 2.0 * d * normal[0], p[1] - 2.0 * d * normal[1], p[2] - 2.0 * d * normal[2]];
        let c = cell(r);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                    for &w in list {
                        let dist = norm(sub(positions[w as usize], r));
                        if dist <= tol && best.is_none_or(|b| (dist, w) < b) {
                            best = Some((dist, w));
                        }
                    }
                }
            }
        }
        vertex[v] = best?.1;
    }
    if (0..n).any(|v| vertex[vertex[v] as usize] != v as u32) {
        return None;
    }
    let mut edge = vec![0u32; graph.edges.len()];
    for (e, &[a, b]) in graph.edges.iter().enumerate() {
        let (ma, mb) = (vertex[a as usize], vertex[b as usize]);
        let key = [ma.min(mb), ma.max(mb)];
        edge[e] = graph.edges.binary_search(&key).ok()? as u32;
    }
    Some(Mirror { vertex, edge, centre, normal })
}

/// Principal axes of the points about `centre` (covariance eigenvectors by Jacobi rotations),
/// largest variance first.
fn principal_axes(positions: &[[f64; 3]], centre: [f64; 3]) -> Vec<[f64; 3]> {
    let mut a = [[0.0f64; 3]; 3];
    for p in positions {
        let d = sub(*p, centre);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += d[i] * d[j];
            }
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if !(off > 1e-15 * scale) {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J, V ← V J.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]).then(i.cmp(&j)));
    order.iter().map(|&k| [v[0][k], v[1][k], v[2][k]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_axes_of_a_stretched_rotated_box_are_its_edges() {
        // Points of a box 4 × 2 × 1 rotated about z by 30°.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let mut pts = Vec::new();
        for x in [-2.0, 2.0] {
            for y in [-1.0, 1.0] {
                for z in [-0.5, 0.5] {
                    pts.push([c * x - s * y, s * x + c * y, z]);
                }
            }
        }
        let axes = principal_axes(&pts, [0.0; 3]);
        let expect = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
        for (a, e) in axes.iter().zip(&expect) {
            assert!((dot(*a, *e).abs() - 1.0).abs() < 1e-12, "{a:?} vs {e:?}");
        }
    }
}
