//! Quality of a UV map, computed independently of any solver (docs/design.md definitions).
//!
//! For each triangle, J is the Jacobian of the map from the triangle (in a local 2D frame of
//! its plane) to its UV triangle, with singular values σ1 ≥ σ2. Before measuring, each chart's
//! UVs are scaled so its UV area equals its 3D area. Weights are 3D areas over the total.
//! * flips: triangles whose signed UV area has the opposite sign to the chart's majority,
//!   plus zero-area UV triangles ([`is_flipped`]). The triangles are the render triangulation
//!   when one is given (else the core's own), and a quad counts as folded when either of its
//!   two diagonal splits has such a triangle: exporters and engines choose their own diagonal,
//!   so a flip-free quad is a strictly convex UV quad;
//! * overlap: the chart's UV boundary crosses or touches itself;
//! * conformal Σ w σ1/σ2; area Σ w max(σ1σ2, 1/(σ1σ2)); symmetric Dirichlet
//!   Σ w (σ1² + σ2² + σ1⁻² + σ2⁻²)/4. All are 1 for an isometry; a zero-area UV triangle with
//!   positive 3D area makes them infinite. Triangles with zero 3D area have weight 0 (they are
//!   still counted as flips when their UV triangle has zero area); a chart with no 3D area at
//!   all has every triangle counted as a flip and infinite distortion, never NaN.

pub mod closed_seams;
pub mod density;

pub use density::{density_spread, DensitySpread, DEFAULT_DENSITY_BOUND};

use crate::charts::{build_charts_with, FaceTriangulation, Quad};
use crate::error::{Result, UvError};
use crate::geometry::{cross2, local_frame, signed_area_2d, triangle_area};

/// Area-weighted distortion measures (1 is perfect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// Σ w σ1/σ2.
    pub conformal: f64,
    /// Σ w max(σ1σ2, 1/(σ1σ2)).
    pub area: f64,
    /// Σ w (σ1² + σ2² + σ1⁻² + σ2⁻²)/4.
    pub symmetric_dirichlet: f64,
}

impl Distortion {
    /// All NaN: the value reported for a chart without UVs.
    pub fn nan() -> Self {
        Distortion { conformal: f64::NAN, area: f64::NAN, symmetric_dirichlet: f64::NAN }
    }
}

/// Quality of one chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartMetrics {
    /// Number of input faces (for [`measure`]) or triangles (for [`chart_metrics`]).
    pub faces: usize,
    /// Flipped plus zero-area UV triangles.
    pub flips: usize,
    /// Whether the UV boundary crosses or touches itself, other than where the two sides of
    /// one cut lie on each other ([`closed_seams`]: the same surface points share those texels).
    pub overlap: bool,
    /// Distortion of the chart, area-normalised.
    pub distortion: Distortion,
    /// 3D area of the chart (weight of the chart in a whole-mesh average).
    pub area_3d: f64,
    /// Texel-density spread against `[1/2, 2]` ([`density`]).
    pub density: DensitySpread,
}

/// Quality of a whole UV map.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshMetrics {
    /// Number of UV islands (charts).
    pub charts: usize,
    /// Flipped plus zero-area triangles, summed over charts.
    pub flips: usize,
    /// Charts whose boundary crosses itself.
    pub overlapping_charts: usize,
    /// Distortion over all measured triangles (each chart area-normalised first).
    pub distortion: Distortion,
    /// Texel-density spread over all charts, each triangle's ratio taken against its own
    /// chart ([`density`]): the share outside `[1/2, 2]` is exact from [`aggregate`]; the
    /// percentiles are exact from [`measure`] and NaN from [`aggregate`] alone.
    pub density: DensitySpread,
    /// One entry per chart.
    pub per_chart: Vec<ChartMetrics>,
    /// `[conformal, area]` distortion of every input face ([`measure`] only; empty from
    /// [`aggregate`]): the 3D-area-weighted mean over the face's triangles, chart
    /// area-normalised. NaN for faces not measured (unselected) or without 3D area, ∞ where a
    /// triangle's UV has zero area.
    pub per_face: Vec<[f64; 2]>,
    /// Flipped or zero-area UV triangles of every input face ([`measure`] only; empty from
    /// [`aggregate`]), counted by [`face_flips`]: `flips` is their sum. 0 for faces not
    /// measured.
    pub face_flips: Vec<u32>,
}

/// Singular values (σ1 ≥ σ2 ≥ 0) and sign of the determinant of a 2×2 matrix [[a, b], [c, d]].
pub fn singular_values_2x2(a: f64, b: f64, c: f64, d: f64) -> (f64, f64, f64) {
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = (e * e + h * h).sqrt();
    let r = (f * f + g * g).sqrt();
    let det = a * d - b * c;
    (q + r, (q - r).abs(), det.signum())
}

/// Relative tolerance of [`flipped_triangles`]: a UV triangle whose area is at most this
/// times the square of its chart's UV bounding-box diagonal counts as zero-area.
///
/// The round-off of a signed area computed from coordinates of size diag is a few 1e-16 ·
/// diag², so below 1e-15 · diag² a sign means nothing. Larger values would call valid
/// triangles degenerate: real meshes have well-shaped UV triangles of 6e-12 · diag²
/// (camelhead) and 5e-15 · diag² (alligator with ABF's convex boundary).
pub const ZERO_AREA_RELATIVE: f64 = 1e-15;

/// The one flip definition (docs/design.md): triangle `t` is flipped when its signed UV area is at
/// most [`ZERO_AREA_RELATIVE`] · diag² in absolute value (diag: the diagonal of the bounding box
/// of the chart's UVs, so the test does not depend on the chart's scale), or when its sign is
/// opposite to the majority of the chart's triangles (positive wins a tie). Non-finite UVs
/// count as flipped. Used by the reports, [`measure`] and the methods' own "no flips" checks.
pub fn flipped_triangles(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<bool> {
    let used = || triangles.iter().flat_map(|t| t.iter().map(|&v| uv[v as usize]));
    // The bounding box of the used UVs without a copy of them: its two corners have the same
    // bounding frame as all the points (unless a coordinate is NaN at every point, or there
    // are no points: then the points themselves).
    let (lo, hi) = used().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
    });
    let (centre, size) = if lo[0] <= hi[0] && lo[1] <= hi[1] {
        crate::geometry::bounding_frame(&[lo, hi])
    } else {
        crate::geometry::bounding_frame(&used().collect::<Vec<_>>())
    };
    // In the unit frame the bounding box's diagonal is at most 2√2, at least 2.
    let (lo, hi) = used().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        let q = [(p[0] - centre[0]) / size, (p[1] - centre[1]) / size];
        ([lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])])
    });
    let diag2 = if lo[0] <= hi[0] { (hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) } else { 0.0 };
    let eps = ZERO_AREA_RELATIVE * diag2;
    let areas: Vec<f64> = triangles
        .iter()
        .map(|t| {
            let q = t.map(|v| {
                let p = uv[v as usize];
                [(p[0] - centre[0]) / size, (p[1] - centre[1]) / size]
            });
            signed_area_2d(q)
        })
        .collect();
    let pos = areas.iter().filter(|&&a| a > eps).count();
    let neg = areas.iter().filter(|&&a| a < -eps).count();
    let majority = if neg > pos { -1.0 } else { 1.0 };
    areas.iter().map(|&a| !(a * majority > eps)).collect()
}

/// A single triangle's shape test: its doubled signed area, taken with the chart's
/// orientation, is not above round-off level of `scale`, the product of two of its edge
/// lengths (`|e1| |e2|`, the largest the doubled area can be). Used where one triangle or one
/// quad is looked at alone (the methods' convex-quad checks, [`quad_folds`]); the flips a
/// report or [`measure`] counts come from [`flipped_triangles`], which also sees the chart's
/// scale and majority orientation.
#[inline]
pub fn is_flipped(signed_area: f64, scale: f64) -> bool {
    !(signed_area > 1e-12 * scale) || scale == 0.0
}

/// Number of [`flipped_triangles`].
pub fn count_flips(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> usize {
    flipped_triangles(triangles, uv).iter().filter(|&&f| f).count()
}

/// Singular values (σ1, σ2) of the Jacobian from 3D triangle `p` (in its own plane) to UV
/// triangle `q2` scaled by `scale`; `(∞, 0)` for a degenerate UV triangle. Precondition: `p`
/// has positive area.
fn triangle_singular_values(p: [[f64; 3]; 3], q2: [[f64; 2]; 3], scale: f64, degenerate: bool) -> (f64, f64) {
    if degenerate {
        return (f64::INFINITY, 0.0);
    }
    let q = local_frame(p);
    // J = [du1 du2] · inv([dq1 dq2])
    let (x1, y1) = (q[1][0] - q[0][0], q[1][1] - q[0][1]);
    let (x2, y2) = (q[2][0] - q[0][0], q[2][1] - q[0][1]);
    let det = x1 * y2 - x2 * y1;
    let (u1, v1) = (scale * (q2[1][0] - q2[0][0]), scale * (q2[1][1] - q2[0][1]));
    let (u2, v2) = (scale * (q2[2][0] - q2[0][0]), scale * (q2[2][1] - q2[0][1]));
    // inv = 1/det [[y2, -x2], [-y1, x1]]
    let a11 = (u1 * y2 - u2 * y1) / det;
    let a12 = (-u1 * x2 + u2 * x1) / det;
    let a21 = (v1 * y2 - v2 * y1) / det;
    let a22 = (-v1 * x2 + v2 * x1) / det;
    let (s1, s2, _) = singular_values_2x2(a11, a12, a21, a22);
    (s1, s2)
}

/// Per-triangle conformal (σ1/σ2) and area (max(σ1σ2, 1/(σ1σ2))) distortion of one chart,
/// after the same area normalisation as [`chart_metrics`]. A triangle without 3D area gets
/// NaN (it has no weight); a zero-area UV triangle gets ∞; in a chart without 3D area every
/// triangle gets ∞.
pub fn triangle_distortion(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let get3 = |t: &[u32; 3]| [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
    let get2 = |t: &[u32; 3]| [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
    let area3: f64 = triangles.iter().map(|t| triangle_area(get3(t))).sum();
    let area2: f64 = triangles.iter().map(|t| signed_area_2d(get2(t)).abs()).sum();
    if !(area3 > 0.0) || !(area2 > 0.0) {
        return vec![[f64::INFINITY; 2]; triangles.len()];
    }
    let scale = (area3 / area2).sqrt();
    triangles
        .iter()
        .map(|t| {
            let p = get3(t);
            if triangle_area(p) <= 0.0 {
                return [f64::NAN; 2];
            }
            let q2 = get2(t);
            let e1 = [q2[1][0] - q2[0][0], q2[1][1] - q2[0][1]];
            let e2 = [q2[2][0] - q2[0][0], q2[2][1] - q2[0][1]];
            let edges = e1[0].hypot(e1[1]) * e2[0].hypot(e2[1]);
            let degenerate = edges == 0.0 || signed_area_2d(q2).abs() <= 1e-12 * edges;
            let (s1, s2) = triangle_singular_values(p, q2, scale, degenerate);
            if s2 > 0.0 && s1.is_finite() {
                [s1 / s2, (s1 * s2).max(1.0 / (s1 * s2))]
            } else {
                [f64::INFINITY; 2]
            }
        })
        .collect()
}

/// Measure one chart given per-vertex positions and UVs over its triangles.
/// Doubled signed area and scale (`|e1| |e2|`) of a UV triangle, for [`is_flipped`].
#[inline]
fn area_and_scale(q: [[f64; 2]; 3]) -> (f64, f64) {
    let e1 = [q[1][0] - q[0][0], q[1][1] - q[0][1]];
    let e2 = [q[2][0] - q[0][0], q[2][1] - q[0][1]];
    (cross2(e1, e2), (e1[0].hypot(e1[1])) * (e2[0].hypot(e2[1])))
}

/// Whether a UV triangle is degenerate (its area is at round-off level of its edges), in
/// either orientation.
#[inline]
pub fn uv_degenerate(q: [[f64; 2]; 3]) -> bool {
    let (c, l) = area_and_scale(q);
    is_flipped(c.abs(), l)
}

/// Number of folded triangles of one quad with `orientation` (+1 or −1): the larger count
/// of flipped triangles ([`is_flipped`]) over its two diagonal splits; 0 exactly when the UV
/// quad is strictly convex with that orientation.
pub fn quad_folds(q: &Quad, uv: &[[f64; 2]], orientation: f64) -> usize {
    let t = q.all_splits();
    let f = |k: usize| {
        let (a, l) = area_and_scale([uv[t[k][0] as usize], uv[t[k][1] as usize], uv[t[k][2] as usize]]);
        is_flipped(orientation * a, l) as usize
    };
    (f(0) + f(1)).max(f(2) + f(3))
}

/// Which of `shown` are flipped or zero-area ([`is_flipped`]), oriented like the majority of
/// `triangles` (the chart's own): the render triangles a chart measures beside its own
/// ([`crate::charts::Chart::shown`]).
pub fn shown_flips(triangles: &[[u32; 3]], shown: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<bool> {
    if shown.is_empty() {
        return Vec::new();
    }
    let get = |t: &[u32; 3]| [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
    let total: f64 = triangles.iter().map(|t| signed_area_2d(get(t))).sum();
    let orientation = if total < 0.0 { -1.0 } else { 1.0 };
    shown
        .iter()
        .map(|t| {
            let (a, l) = area_and_scale(get(t));
            is_flipped(orientation * a, l)
        })
        .collect()
}

/// Flipped or zero-area UV triangles of every face of `chart` (aligned with `chart.faces`),
/// exactly as a chart's report and [`measure`] count them: the flips [`flip_charges`] puts on
/// the face's own triangles (a quad: the flips of its worse diagonal split) plus its flipped
/// render triangles among [`crate::charts::Chart::shown`] ([`shown_flips`]). The chart's flip
/// count is their sum.
pub fn face_flips(chart: &crate::charts::Chart, uv: &[[f64; 2]]) -> Vec<u32> {
    face_flips_with(chart, uv, false)
}

/// [`face_flips`]; with `every_own`, every own triangle counts as flipped (a chart without 3D
/// area, see [`chart_metrics`]).
fn face_flips_with(chart: &crate::charts::Chart, uv: &[[f64; 2]], every_own: bool) -> Vec<u32> {
    let mut out = vec![0u32; chart.faces.len()];
    let slot = |f: u32| chart.faces.binary_search(&f).expect("a chart triangle's face is a face of the chart");
    let charges = if every_own { vec![1u8; chart.triangles.len()] } else { flip_charges(&chart.triangles, &chart.quads, uv) };
    for (&f, &c) in chart.triangle_face.iter().zip(&charges) {
        if c > 0 {
            out[slot(f)] += c as u32;
        }
    }
    for (&f, bad) in chart.shown_face.iter().zip(shown_flips(&chart.triangles, &chart.shown, uv)) {
        if bad {
            out[slot(f)] += 1;
        }
    }
    out
}

/// Measure one chart given per-vertex positions and UVs over its triangles (no quads: every
/// triangle counts on its own; see [`chart_metrics_with_quads`]).
pub fn chart_metrics(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uv: &[[f64; 2]],
    boundary_loops: &[Vec<u32>],
) -> ChartMetrics {
    // Measure in unit frames (distortion is scale-invariant), so charts of any size give the
    // same numbers and no product of coordinates overflows or underflows.
    let (c3, s3) = crate::geometry::bounding_frame(positions);
    let positions = &crate::geometry::to_unit_frame(positions, c3, s3);
    let (c2, s2) = crate::geometry::bounding_frame(uv);
    let uv = &crate::geometry::to_unit_frame(uv, c2, s2);
    let get3 = |t: &[u32; 3]| [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
    let get2 = |t: &[u32; 3]| [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
    let flipped = flipped_triangles(triangles, uv);
    let mut area3 = 0.0;
    let mut area2 = 0.0;
    for t in triangles {
        area3 += triangle_area(get3(t));
        area2 += signed_area_2d(get2(t)).abs();
    }
    if !(area3 > 0.0) {
        // No 3D area: the area-normalised UV map is a single point, so every triangle is a
        // zero-area UV triangle (a flip) and the distortion is infinite, never NaN.
        return ChartMetrics {
            faces: triangles.len(),
            flips: triangles.len(),
            overlap: closed_seams::outline_overlap(positions, triangles, uv, boundary_loops),
            distortion: Distortion { conformal: f64::INFINITY, area: f64::INFINITY, symmetric_dirichlet: f64::INFINITY },
            area_3d: 0.0,
            density: density::spread_of(vec![(0.0, 0.0); triangles.len()], DEFAULT_DENSITY_BOUND),
        };
    }
    let scale = if area2 > 0.0 { (area3 / area2).sqrt() } else { 1.0 };
    let flips = flipped.iter().filter(|&&f| f).count();
    let mut sum = [0.0f64; 3];
    for (t, &bad) in triangles.iter().zip(&flipped) {
        let q2 = get2(t);
        let degenerate = bad && uv_zero_area(q2);
        let p = get3(t);
        let w = triangle_area(p);
        if w <= 0.0 {
            // Zero 3D area: weight 0 in the area-weighted distortion.
            continue;
        }
        let (s1, s2) = triangle_singular_values(p, q2, scale, degenerate);
        let wn = w / area3;
        if s2 > 0.0 && s1.is_finite() {
            sum[0] += wn * s1 / s2;
            sum[1] += wn * (s1 * s2).max(1.0 / (s1 * s2));
            sum[2] += wn * 0.25 * (s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2));
        } else {
            sum = [f64::INFINITY; 3];
        }
    }
    let overlap = closed_seams::outline_overlap(positions, triangles, uv, boundary_loops);
    ChartMetrics {
        faces: triangles.len(),
        flips,
        overlap,
        distortion: Distortion { conformal: sum[0], area: sum[1], symmetric_dirichlet: sum[2] },
        // Back to the input's units; overflows to +∞ only beyond ~1e154 per coordinate.
        area_3d: area3 * s3 * s3,
        density: density_spread(positions, triangles, uv, DEFAULT_DENSITY_BOUND),
    }
}

/// Whether a UV triangle (in a unit frame) has zero area by [`flipped_triangles`]' tolerance
/// (the bounding-box diagonal of a unit frame is at least 2, so the tolerance is at least
/// 4 · [`ZERO_AREA_RELATIVE`]): such a triangle makes the distortion measures infinite.
fn uv_zero_area(q: [[f64; 2]; 3]) -> bool {
    signed_area_2d(q).abs() <= 4.0 * ZERO_AREA_RELATIVE
}

/// Flipped triangles of a chart by the one definition ([`flipped_triangles`]) over its
/// triangles that are not in a quad and both diagonal splits of every quad, a quad counting
/// the flips of its worse split: 0 means every quad is strictly convex in UV. The sum of
/// [`flip_charges`].
pub fn count_flips_with_quads(triangles: &[[u32; 3]], quads: &[Quad], uv: &[[f64; 2]]) -> usize {
    if quads.is_empty() {
        return count_flips(triangles, uv);
    }
    flip_charges(triangles, quads, uv).iter().map(|&c| c as usize).sum()
}

/// The flips [`count_flips_with_quads`] counts, charged to the triangles of `triangles`: 1 for
/// a flipped triangle outside the quads ([`flipped_triangles`] over those triangles and both
/// splits of every quad), and a quad's count (the flips of its worse split, 0 to 2) on its
/// first own triangle, 0 on its second.
pub fn flip_charges(triangles: &[[u32; 3]], quads: &[Quad], uv: &[[f64; 2]]) -> Vec<u8> {
    if quads.is_empty() {
        return flipped_triangles(triangles, uv).into_iter().map(u8::from).collect();
    }
    let mut in_quad = vec![false; triangles.len()];
    for q in quads {
        for &t in &q.triangles {
            in_quad[t as usize] = true;
        }
    }
    let single: Vec<usize> = (0..triangles.len()).filter(|&t| !in_quad[t]).collect();
    let mut all: Vec<[u32; 3]> = single.iter().map(|&t| triangles[t]).collect();
    for q in quads {
        all.extend(q.all_splits());
    }
    let flipped = flipped_triangles(&all, uv);
    let mut charges = vec![0u8; triangles.len()];
    for (k, &t) in single.iter().enumerate() {
        charges[t] = flipped[k] as u8;
    }
    for (k, q) in quads.iter().enumerate() {
        let f = &flipped[single.len() + 4 * k..single.len() + 4 * k + 4];
        charges[q.triangles[0] as usize] = (f[0] as u8 + f[1] as u8).max(f[2] as u8 + f[3] as u8);
    }
    charges
}

/// [`chart_metrics`] with the chart's quad faces (whose own two triangles are among
/// `triangles`): a quad counts as folded on the split with more flipped triangles, so a
/// "no flips" quad is strictly convex in UV whichever diagonal a renderer or exporter picks.
/// Flips follow the one definition ([`flipped_triangles`]) over the chart's other triangles
/// and both splits of every quad; distortion is measured on `triangles`.
pub fn chart_metrics_with_quads(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    quads: &[Quad],
    uv: &[[f64; 2]],
    boundary_loops: &[Vec<u32>],
) -> ChartMetrics {
    let mut m = chart_metrics(positions, triangles, uv, boundary_loops);
    if quads.is_empty() || !(m.area_3d > 0.0) {
        return m;
    }
    let flips = count_flips_with_quads(triangles, quads, uv);
    m.flips = flips;
    m
}

/// Whether the UV boundary (all loops of one chart) crosses or touches itself anywhere other
/// than at the shared endpoint of consecutive edges.
pub fn boundary_self_overlap(uv: &[[f64; 2]], loops: &[Vec<u32>]) -> bool {
    self_overlap_with(uv, loops, BRUTE_FORCE_SEGMENTS)
}

/// [`boundary_self_overlap`], testing every pair of segments when there are at most
/// `brute_force` of them and through a grid ([`crate::geometry::box_grid`]) otherwise.
fn self_overlap_with(uv: &[[f64; 2]], loops: &[Vec<u32>], brute_force: usize) -> bool {
    !boundary_crossings_with(uv, loops, brute_force, 1).is_empty()
}

/// The pairs of outline segments (each as its two chart vertices, in loop order) that cross
/// or touch, as [`boundary_self_overlap`] finds them, up to `limit` pairs (sorted, so the
/// same whatever the grid's order). An outline collapsed onto one point gives one pair of its
/// first segments.
pub fn boundary_crossings(uv: &[[f64; 2]], loops: &[Vec<u32>], limit: usize) -> Vec<[[u32; 2]; 2]> {
    boundary_crossings_with(uv, loops, BRUTE_FORCE_SEGMENTS, limit)
}

/// [`boundary_crossings`] with the brute-force threshold of [`self_overlap_with`].
fn boundary_crossings_with(uv: &[[f64; 2]], loops: &[Vec<u32>], brute_force: usize, limit: usize) -> Vec<[[u32; 2]; 2]> {
    boundary_crossings_except(uv, loops, brute_force, limit, &|_, _| false)
}

/// [`boundary_crossings_with`], leaving out the pairs of segments that `benign` accepts (it is
/// asked only about pairs that cross or touch, and about consecutive segments that fold back
/// onto each other).
pub(crate) fn boundary_crossings_except(
    uv: &[[f64; 2]],
    loops: &[Vec<u32>],
    brute_force: usize,
    limit: usize,
    benign: &dyn Fn([u32; 2], [u32; 2]) -> bool,
) -> Vec<[[u32; 2]; 2]> {
    let mut segs: Vec<(u32, u32)> = Vec::new();
    for lp in loops {
        for i in 0..lp.len() {
            segs.push((lp[i], lp[(i + 1) % lp.len()]));
        }
    }
    let n = segs.len();
    if n < 2 || limit == 0 {
        return Vec::new();
    }
    let pair = |i: usize, j: usize| [[segs[i].0, segs[i].1], [segs[j].0, segs[j].1]];
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &(a, b) in &segs {
        for p in [uv[a as usize], uv[b as usize]] {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(extent > 0.0) {
        return vec![pair(0, 1)]; // everything collapsed onto one point
    }
    // Whether segments i and j overlap (consecutive ones only if they fold back).
    let crossing = |i: usize, j: usize| -> bool {
        let (s, t) = (segs[i], segs[j]);
        let shared = s.0 == t.0 || s.0 == t.1 || s.1 == t.0 || s.1 == t.1;
        let (p1, p2, p3, p4) = (uv[s.0 as usize], uv[s.1 as usize], uv[t.0 as usize], uv[t.1 as usize]);
        if shared {
            if s.0 == t.1 && s.1 == t.0 {
                return false; // a two-edge loop
            }
            let (o, a, b) = if s.1 == t.0 {
                (p2, p1, p4)
            } else if s.0 == t.1 {
                (p1, p2, p3)
            } else if s.0 == t.0 {
                (p1, p2, p4)
            } else {
                (p2, p1, p3)
            };
            let u = [a[0] - o[0], a[1] - o[1]];
            let v = [b[0] - o[0], b[1] - o[1]];
            let folds = cross2(u, v) == 0.0 && u[0] * v[0] + u[1] * v[1] > 0.0;
            return folds && !benign([s.0, s.1], [t.0, t.1]);
        }
        segments_intersect(p1, p2, p3, p4) && !benign([s.0, s.1], [t.0, t.1])
    };
    // Small outlines (the many tiny charts of a Smart UV Project cut): every pair, no grid.
    let mut found: Vec<(usize, usize)> = Vec::new();
    if n <= brute_force {
        'all: for i in 0..n {
            for j in i + 1..n {
                if crossing(i, j) {
                    found.push((i, j));
                    if found.len() >= limit {
                        break 'all;
                    }
                }
            }
        }
        return found.into_iter().map(|(i, j)| pair(i, j)).collect();
    }
    // Candidates from the refined grid of [`crate::geometry::box_grid`] (a crushed stretch of
    // outline packs many segments where a uniform grid has one cell); a pair can come twice.
    let boxes: Vec<crate::geometry::box_grid::Box2> = segs
        .iter()
        .map(|&(a, b)| {
            let (pa, pb) = (uv[a as usize], uv[b as usize]);
            ([pa[0].min(pb[0]), pa[1].min(pb[1])], [pa[0].max(pb[0]), pa[1].max(pb[1])])
        })
        .collect();
    let _ = crate::geometry::box_grid::visit_pairs(&boxes, |i, j| {
        let (i, j) = (i as usize, j as usize);
        if crate::geometry::box_grid::share_point(boxes[i], boxes[j]) && crossing(i, j) && !found.contains(&(i, j)) {
            found.push((i, j));
            if found.len() >= limit {
                return std::ops::ControlFlow::Break(());
            }
        }
        std::ops::ControlFlow::Continue(())
    });
    found.sort_unstable();
    found.into_iter().map(|(i, j)| pair(i, j)).collect()
}

/// Outlines of at most this many segments are tested pair by pair in
/// [`boundary_self_overlap`] (cheaper than building its grid).
const BRUTE_FORCE_SEGMENTS: usize = 24;

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0]) && p[0] <= a[0].max(b[0]) && p[1] >= a[1].min(b[1]) && p[1] <= a[1].max(b[1])
}

/// Closed segments `[p1, p2]` and `[p3, p4]` share a point.
pub fn segments_intersect(p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], p4: [f64; 2]) -> bool {
    let d1 = orient(p3, p4, p1);
    let d2 = orient(p3, p4, p2);
    let d3 = orient(p1, p2, p3);
    let d4 = orient(p1, p2, p4);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    (d1 == 0.0 && on_segment(p3, p4, p1))
        || (d2 == 0.0 && on_segment(p3, p4, p2))
        || (d3 == 0.0 && on_segment(p1, p2, p3))
        || (d4 == 0.0 && on_segment(p1, p2, p4))
}

/// Scale a chart's UVs so its UV area equals its 3D area and centre its bounding box on
/// `center`. A chart with zero UV area is only translated. Computed in unit frames, so charts
/// of any size (coordinates up to ~1e300) give finite UVs.
pub fn area_normalize(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &mut [[f64; 2]], center: [f64; 2]) {
    let (c3, s3) = crate::geometry::bounding_frame(positions);
    let (mid, s2) = crate::geometry::bounding_frame(uv);
    let p3 = crate::geometry::to_unit_frame(positions, c3, s3);
    let mut a3 = 0.0;
    let mut a2 = 0.0;
    for t in triangles {
        a3 += triangle_area([p3[t[0] as usize], p3[t[1] as usize], p3[t[2] as usize]]);
        let q = t.map(|v| [(uv[v as usize][0] - mid[0]) / s2, (uv[v as usize][1] - mid[1]) / s2]);
        a2 += signed_area_2d(q).abs();
    }
    // UV = centre + k (uv − mid) / s2: k = s3 √(a3 / a2) in unit frames, s2 when not scaling.
    let k = if a2 > 0.0 && a3 > 0.0 { s3 * (a3 / a2).sqrt() } else { s2 };
    for p in uv.iter_mut() {
        *p = [center[0] + k * ((p[0] - mid[0]) / s2), center[1] + k * ((p[1] - mid[1]) / s2)];
    }
}

/// Smallest agreement (0..1, see [`fit_similarity`]) between a chart's UVs and its fit target
/// for the fit to count: a mirrored target has about 0 (the best rotation collapses the chart).
pub const MIN_FIT_AGREEMENT: f64 = 0.5;

/// The best proper similarity (uniform scale, rotation, translation; no reflection) from the
/// points `uv` onto `target` (NaN targets ignored), in least squares: `p ↦ mt + z (p − ms)`
/// with complex `z`, and the agreement |Σ conj(a) b| / √(Σ|a|² Σ|b|²) ∈ [0, 1] of the centred
/// point sets a, b (1 for an exact similarity, about 0 for a mirror image). Computed in unit
/// frames, so any finite coordinates work. `None` when fewer than two distinct points take part.
struct Similarity {
    ms: [f64; 2],
    ss: f64,
    mt: [f64; 2],
    z: [f64; 2],
    agreement: f64,
}

fn best_similarity(uv: &[[f64; 2]], target: &[[f64; 2]]) -> Option<Similarity> {
    let pairs: Vec<([f64; 2], [f64; 2])> = uv.iter().zip(target).filter(|(_, t)| !t[0].is_nan()).map(|(s, t)| (*s, *t)).collect();
    if pairs.is_empty() {
        return None;
    }
    let src: Vec<[f64; 2]> = pairs.iter().map(|p| p.0).collect();
    let dst: Vec<[f64; 2]> = pairs.iter().map(|p| p.1).collect();
    let (cs, ss) = crate::geometry::bounding_frame(&src);
    let (ct, st) = crate::geometry::bounding_frame(&dst);
    let src = crate::geometry::to_unit_frame(&src, cs, ss);
    let dst = crate::geometry::to_unit_frame(&dst, ct, st);
    let n = src.len() as f64;
    let mean = |v: &[[f64; 2]]| v.iter().fold([0.0; 2], |m, p| [m[0] + p[0] / n, m[1] + p[1] / n]);
    let (ms, mt) = (mean(&src), mean(&dst));
    // Complex least squares: t − mt ≈ z (s − ms), z = Σ conj(s')t' / Σ |s'|².
    let (mut re, mut im, mut den, mut tt) = (0.0, 0.0, 0.0, 0.0);
    for (s, t) in src.iter().zip(&dst) {
        let a = [s[0] - ms[0], s[1] - ms[1]];
        let b = [t[0] - mt[0], t[1] - mt[1]];
        re += a[0] * b[0] + a[1] * b[1];
        im += a[0] * b[1] - a[1] * b[0];
        den += a[0] * a[0] + a[1] * a[1];
        tt += b[0] * b[0] + b[1] * b[1];
    }
    if !(den > 0.0) {
        return None;
    }
    let agreement = if tt > 0.0 { re.hypot(im) / (den * tt).sqrt() } else { 0.0 };
    // Back to input units: p ↦ ct + st (mt + z ((p − cs)/ss − ms)).
    Some(Similarity {
        ms: [cs[0] + ss * ms[0], cs[1] + ss * ms[1]],
        ss,
        mt: [ct[0] + st * mt[0], ct[1] + st * mt[1]],
        z: [st * re / den, st * im / den],
        agreement,
    })
}

impl Similarity {
    fn apply(&self, uv: &mut [[f64; 2]]) {
        let [zr, zi] = self.z;
        for p in uv.iter_mut() {
            let a = [(p[0] - self.ms[0]) / self.ss, (p[1] - self.ms[1]) / self.ss];
            *p = [self.mt[0] + zr * a[0] - zi * a[1], self.mt[1] + zi * a[0] + zr * a[1]];
        }
    }
}

/// Least-squares proper similarity (uniform scale, rotation, translation; no reflection)
/// taking `uv` onto `target` (per vertex; NaN targets are ignored), applied in place.
///
/// Returns `false` and leaves `uv` unchanged when the fit is degenerate: the target's triangles
/// have no area, or the best proper similarity agrees poorly with the target (agreement below
/// [`MIN_FIT_AGREEMENT`], as for a mirrored target, where it would shrink the chart to a
/// point). The caller then places the chart some other way.
pub fn fit_similarity(uv: &mut [[f64; 2]], target: &[[f64; 2]], triangles: &[[u32; 3]]) -> bool {
    let used: Vec<[f64; 2]> = triangles.iter().flat_map(|t| t.map(|v| target[v as usize])).filter(|p| !p[0].is_nan()).collect();
    let (ct, st) = crate::geometry::bounding_frame(&used);
    let target_area: f64 = triangles
        .iter()
        .map(|t| {
            let q = t.map(|v| target[v as usize]);
            if q.iter().any(|p| p[0].is_nan()) {
                0.0
            } else {
                signed_area_2d(q.map(|p| [(p[0] - ct[0]) / st, (p[1] - ct[1]) / st])).abs()
            }
        })
        .sum();
    if !(target_area > 1e-24) {
        return false;
    }
    match best_similarity(uv, target) {
        Some(sim) if sim.agreement >= MIN_FIT_AGREEMENT => {
            sim.apply(uv);
            true
        }
        _ => false,
    }
}

/// Least-squares similarity (no reflection) taking `uv` onto `target` at the vertices whose
/// target is not NaN, applied in place. Returns `false` (and changes nothing) when fewer than
/// two distinct points take part.
pub fn fit_similarity_points(uv: &mut [[f64; 2]], target: &[[f64; 2]]) -> bool {
    match best_similarity(uv, target) {
        Some(sim) => {
            sim.apply(uv);
            true
        }
        None => false,
    }
}

/// Measure an existing per-corner UV map of a polygon mesh (for example Blender's own unwrap).
///
/// Islands are the faces connected through edges whose two faces have equal UVs at both ends;
/// non-manifold edges separate islands. `selected` restricts the measurement to some faces.
///
/// Errors: the mesh validation errors of [`crate::validate::validate_input`], [`UvError::Shape`] for a wrong
/// number of UVs or selection flags, [`UvError::NonFiniteUv`] for NaN or infinite UVs on a measured face.
pub fn measure(
    positions: &[[f64; 3]],
    corner_verts: &[u32],
    face_sizes: &[u32],
    uv: &[[f64; 2]],
    selected: Option<&[bool]>,
) -> Result<MeshMetrics> {
    measure_with_triangles(positions, corner_verts, face_sizes, uv, selected, &[])
}

/// [`measure`] with the render triangulation (`triangles`: corner index triples, Blender's
/// `mesh.loop_triangles`; empty for the core's own): n-gons are measured on those triangles,
/// and quads on both diagonal splits either way.
///
/// Errors: those of [`measure`], and [`UvError::RenderTriangle`] for a bad triple (see
/// [`FaceTriangulation::new`]).
pub fn measure_with_triangles(
    positions: &[[f64; 3]],
    corner_verts: &[u32],
    face_sizes: &[u32],
    uv: &[[f64; 2]],
    selected: Option<&[bool]>,
    triangles: &[[u32; 3]],
) -> Result<MeshMetrics> {
    let input = crate::unwrap::MeshInput { positions, corner_verts, face_sizes, selected, ..Default::default() };
    let mesh = crate::validate::validate_input(&input, None, None)?;
    let render = if triangles.is_empty() { None } else { Some(FaceTriangulation::new(&mesh, triangles)?) };
    if uv.len() != mesh.n_corners() {
        return Err(UvError::Shape {
            what: "uv",
            detail: format!("has {} rows, mesh has {} corners", uv.len(), mesh.n_corners()),
        });
    }
    // Only the corners of measured faces are read: the others may hold anything.
    for f in 0..mesh.n_faces() {
        if selected.is_some_and(|s| !s[f]) {
            continue;
        }
        if let Some(c) = mesh.face_corners(f).find(|&c| !uv[c][0].is_finite() || !uv[c][1].is_finite()) {
            return Err(UvError::NonFiniteUv { corner: c });
        }
    }
    // UV seams: edges whose two corners' UVs differ at either end.
    let mut face_of = vec![0u32; mesh.n_corners()];
    for f in 0..mesh.n_faces() {
        for c in mesh.face_corners(f) {
            face_of[c] = f as u32;
        }
    }
    let mut recs: Vec<(u64, u32)> = Vec::with_capacity(mesh.n_corners());
    for f in 0..mesh.n_faces() {
        if selected.is_some_and(|s| !s[f]) {
            continue;
        }
        for c in mesh.face_corners(f) {
            let cn = mesh.next_corner(f, c);
            let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(cn));
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            recs.push((key, c as u32));
        }
    }
    recs.sort_unstable();
    let mut seams = Vec::new();
    let mut i = 0;
    while i < recs.len() {
        let mut j = i + 1;
        while j < recs.len() && recs[j].0 == recs[i].0 {
            j += 1;
        }
        if j - i == 2 {
            let (c1, c2) = (recs[i].1 as usize, recs[i + 1].1 as usize);
            let (f1, f2) = (face_of[c1] as usize, face_of[c2] as usize);
            let (c1n, c2n) = (mesh.next_corner(f1, c1), mesh.next_corner(f2, c2));
            let v1 = mesh.corner_vert(c1);
            // Match ends by vertex.
            let (m1, m2) = if mesh.corner_vert(c2) == v1 { (c2, c2n) } else { (c2n, c2) };
            if uv[c1] != uv[m1] || uv[c1n] != uv[m2] {
                seams.push([v1, mesh.corner_vert(c1n)]);
            }
        }
        i = j;
    }
    let charts = build_charts_with(&mesh, &seams, selected, render.as_ref());
    type Measured = (ChartMetrics, Vec<(u32, [f64; 2])>, Vec<(f64, f64)>, Vec<(u32, u32)>);
    let measured: Vec<Measured> = {
        use rayon::prelude::*;
        charts
            .par_iter()
            .map(|ch| {
                let mut vuv = vec![[0.0; 2]; ch.positions.len()];
                for &(c, v) in &ch.corner_vertex {
                    vuv[v as usize] = uv[c as usize];
                }
                let mut m = chart_metrics_with_quads(&ch.positions, &ch.triangles, &ch.quads, &vuv, &ch.boundary_loops);
                m.faces = ch.faces.len();
                // Per face, as a report counts them (a chart without 3D area: every own
                // triangle, as `chart_metrics`); the chart's count is their sum.
                let flips = face_flips_with(ch, &vuv, !(m.area_3d > 0.0));
                m.flips = flips.iter().map(|&n| n as usize).sum();
                let flips: Vec<(u32, u32)> = ch.faces.iter().copied().zip(flips).collect();
                (m, face_distortion(ch, &vuv), density::density_ratios(&ch.positions, &ch.triangles, &vuv), flips)
            })
            .collect()
    };
    let mut per_face = vec![[f64::NAN; 2]; mesh.n_faces()];
    let mut face_flips = vec![0u32; mesh.n_faces()];
    let mut per_chart = Vec::with_capacity(measured.len());
    let mut samples = Vec::new();
    for (m, faces, ratios, flips) in measured {
        for (f, d) in faces {
            per_face[f as usize] = d;
        }
        for (f, n) in flips {
            face_flips[f as usize] = n;
        }
        per_chart.push(m);
        samples.extend(ratios);
    }
    let mut out = aggregate(per_chart);
    out.per_face = per_face;
    out.face_flips = face_flips;
    out.density = density::spread_of(samples, DEFAULT_DENSITY_BOUND);
    Ok(out)
}

/// `(face, [conformal, area])` of every face of `chart`: 3D-area-weighted mean of its
/// triangles' [`triangle_distortion`]; NaN for a face without 3D area.
pub(crate) fn face_distortion(chart: &crate::charts::Chart, uv: &[[f64; 2]]) -> Vec<(u32, [f64; 2])> {
    let per_tri = triangle_distortion(&chart.positions, &chart.triangles, uv);
    let mut acc: std::collections::HashMap<u32, ([f64; 2], f64)> = std::collections::HashMap::new();
    for ((t, &f), d) in chart.triangles.iter().zip(&chart.triangle_face).zip(&per_tri) {
        let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
        let w = triangle_area(p);
        let e = acc.entry(f).or_insert(([0.0; 2], 0.0));
        if w > 0.0 {
            e.0[0] += w * d[0];
            e.0[1] += w * d[1];
            e.1 += w;
        }
    }
    chart
        .faces
        .iter()
        .map(|&f| {
            let d = match acc.get(&f) {
                Some(&(s, w)) if w > 0.0 => [s[0] / w, s[1] / w],
                _ => [f64::NAN; 2],
            };
            (f, d)
        })
        .collect()
}

/// Combine per-chart metrics into whole-mesh metrics (distortion weighted by 3D area).
pub fn aggregate(per_chart: Vec<ChartMetrics>) -> MeshMetrics {
    let total: f64 = per_chart.iter().map(|c| c.area_3d).sum();
    // No charts: NaN (nothing measured); charts but no 3D area: infinite (see chart_metrics).
    let mut d = if total > 0.0 {
        [0.0f64; 3]
    } else if per_chart.is_empty() {
        [f64::NAN; 3]
    } else {
        [f64::INFINITY; 3]
    };
    for c in &per_chart {
        if c.area_3d > 0.0 && total > 0.0 {
            let w = c.area_3d / total;
            d[0] += w * c.distortion.conformal;
            d[1] += w * c.distortion.area;
            d[2] += w * c.distortion.symmetric_dirichlet;
        }
    }
    let outside = if total > 0.0 {
        per_chart.iter().filter(|c| c.area_3d > 0.0).map(|c| c.area_3d / total * c.density.outside).sum()
    } else if per_chart.is_empty() {
        0.0
    } else {
        1.0
    };
    MeshMetrics {
        density: DensitySpread { p5: f64::NAN, p95: f64::NAN, outside, bound: DEFAULT_DENSITY_BOUND },
        charts: per_chart.len(),
        flips: per_chart.iter().map(|c| c.flips).sum(),
        overlapping_charts: per_chart.iter().filter(|c| c.overlap).count(),
        distortion: Distortion { conformal: d[0], area: d[1], symmetric_dirichlet: d[2] },
        per_chart,
        per_face: Vec::new(),
        face_flips: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pairwise test of small outlines and the grid agree, on random polygons (most
    /// crossing themselves), on regular ones (never) and on outlines folding back on an edge.
    #[test]
    fn pairwise_and_grid_overlap_tests_agree() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut crossing, mut clean) = (0, 0);
        for case in 0..400 {
            let k = 3 + case % 20;
            let uv: Vec<[f64; 2]> = if case % 3 == 0 {
                (0..k).map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / k as f64;
                    [a.cos(), a.sin()]
                })
                .collect()
            } else {
                (0..k).map(|_| [rnd(), rnd()]).collect()
            };
            let mut loops = vec![(0..k as u32).collect::<Vec<u32>>()];
            if case % 7 == 1 {
                loops[0].insert(2, 1); // the outline goes back along edge 1–2
            }
            let pairwise = self_overlap_with(&uv, &loops, usize::MAX);
            let grid = self_overlap_with(&uv, &loops, 0);
            assert_eq!(pairwise, grid, "case {case}: {uv:?}");
            // Every crossing pair, by both paths: the same pairs, in the same order.
            let all_pairwise = boundary_crossings_with(&uv, &loops, usize::MAX, usize::MAX);
            let all_grid = boundary_crossings_with(&uv, &loops, 0, usize::MAX);
            assert_eq!(all_pairwise, all_grid, "case {case}");
            assert_eq!(all_pairwise.is_empty(), !pairwise);
            // A limit stops at the first pairs.
            assert_eq!(boundary_crossings_with(&uv, &loops, usize::MAX, 1).len(), usize::from(pairwise));
            if pairwise { crossing += 1 } else { clean += 1 }
        }
        assert!(crossing > 50 && clean > 50, "{crossing} crossing, {clean} clean");
    }

    /// The flip test as first written: the bounding frame of a copy of every used UV.
    fn flipped_by_copy(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<bool> {
        let used: Vec<[f64; 2]> = triangles.iter().flat_map(|t| t.iter().map(|&v| uv[v as usize])).collect();
        let (centre, size) = crate::geometry::bounding_frame(&used);
        let (lo, hi) = used.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
            let q = [(p[0] - centre[0]) / size, (p[1] - centre[1]) / size];
            ([lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])])
        });
        let diag2 = if lo[0] <= hi[0] { (hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) } else { 0.0 };
        let eps = ZERO_AREA_RELATIVE * diag2;
        let areas: Vec<f64> = triangles
            .iter()
            .map(|t| signed_area_2d(t.map(|v| [(uv[v as usize][0] - centre[0]) / size, (uv[v as usize][1] - centre[1]) / size])))
            .collect();
        let pos = areas.iter().filter(|&&a| a > eps).count();
        let neg = areas.iter().filter(|&&a| a < -eps).count();
        let majority = if neg > pos { -1.0 } else { 1.0 };
        areas.iter().map(|&a| !(a * majority > eps)).collect()
    }

    #[test]
    fn flip_test_without_a_copy_of_the_uvs_agrees_with_the_copying_one() {
        // Random triangles over random UVs (some far from the origin, some vertices unused),
        // then the same with NaN in one coordinate of some or of every vertex, and empty.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..40 {
            let n = 3 + (next() * 30.0) as usize;
            let offset = if case % 3 == 0 { 1e6 } else { 0.0 };
            let mut uv: Vec<[f64; 2]> = (0..n).map(|_| [offset + next() * 4.0 - 2.0, next() - 0.5]).collect();
            let tris: Vec<[u32; 3]> = (0..1 + (next() * 40.0) as usize)
                .map(|_| {
                    let a = (next() * n as f64) as u32 % n as u32;
                    [a, (a + 1) % n as u32, (a + 2) % n as u32]
                })
                .collect();
            assert_eq!(flipped_triangles(&tris, &uv), flipped_by_copy(&tris, &uv), "case {case}");
            uv[tris[0][0] as usize][1] = f64::NAN;
            assert_eq!(flipped_triangles(&tris, &uv), flipped_by_copy(&tris, &uv), "case {case} with a NaN");
            for p in uv.iter_mut() {
                p[0] = f64::NAN;
            }
            assert_eq!(flipped_triangles(&tris, &uv), flipped_by_copy(&tris, &uv), "case {case}, NaN everywhere");
            assert!(flipped_triangles(&[], &uv).is_empty());
        }
    }

    #[test]
    fn singular_values_of_known_matrices() {
        let (s1, s2, sg) = singular_values_2x2(2.0, 0.0, 0.0, 0.5);
        assert!((s1 - 2.0).abs() < 1e-15 && (s2 - 0.5).abs() < 1e-15 && sg > 0.0);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let (s1, s2, sg) = singular_values_2x2(3.0 * c, -3.0 * s, 3.0 * s, 3.0 * c);
        assert!((s1 - 3.0).abs() < 1e-14 && (s2 - 3.0).abs() < 1e-14 && sg > 0.0);
        let (_, _, sg) = singular_values_2x2(1.0, 0.0, 0.0, -1.0);
        assert!(sg < 0.0);
    }

    #[test]
    fn stretch_and_flip_are_measured_analytically() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = vec![[0, 1, 2], [0, 2, 3]];
        let loops = vec![vec![0, 1, 2, 3]];
        let ident: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let m = chart_metrics(&p, &tris, &ident, &loops);
        assert_eq!(m.flips, 0);
        assert!(!m.overlap);
        for d in [m.distortion.conformal, m.distortion.area, m.distortion.symmetric_dirichlet] {
            assert!((d - 1.0).abs() < 1e-14);
        }
        // u stretched by 2: after area normalisation σ = (√2, 1/√2): conformal 2.
        let st: Vec<[f64; 2]> = p.iter().map(|q| [2.0 * q[0], q[1]]).collect();
        let m = chart_metrics(&p, &tris, &st, &loops);
        assert!((m.distortion.conformal - 2.0).abs() < 1e-13);
        assert!((m.distortion.area - 1.0).abs() < 1e-13);
        assert!((m.distortion.symmetric_dirichlet - 0.25 * (2.0 + 0.5 + 0.5 + 2.0)).abs() < 1e-13);
        // Move vertex 3 across the diagonal: triangle (0,2,3) flips and the boundary crosses.
        let mut fl = ident.clone();
        fl[3] = [1.0, 0.2];
        let m = chart_metrics(&p, &tris, &fl, &loops);
        assert_eq!(m.flips, 1);
        assert!(m.overlap);
    }

    #[test]
    fn fit_similarity_recovers_a_similarity() {
        let tris = vec![[0u32, 1, 2]];
        let src = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let (c, s, k) = (0.7f64.cos(), 0.7f64.sin(), 2.5);
        let tgt: Vec<[f64; 2]> = src.iter().map(|p| [3.0 + k * (c * p[0] - s * p[1]), -1.0 + k * (s * p[0] + c * p[1])]).collect();
        let mut uv = src.clone();
        assert!(fit_similarity(&mut uv, &tgt, &tris));
        for (a, b) in uv.iter().zip(&tgt) {
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
        let mut uv = src.clone();
        assert!(!fit_similarity(&mut uv, &[[0.0; 2]; 3], &tris));
        assert_eq!(uv, src);
    }
}
