//! Texel-density spread of a chart: what *Max Stretch* promises (docs/design.md).
//!
//! Per triangle, the density ratio is `r = (UV area / 3D area) / (chart UV area / chart 3D
//! area)`: 1 where the triangle gets the chart's own texel density, 4 where it gets four times
//! as many texels per square metre. A flipped or zero-area UV triangle has `r = 0` (it shows
//! no texture the right way round). The spread is the share of the chart's 3D area whose `r`
//! lies outside `[1/s, s]` and the area-weighted 5th and 95th percentiles of `r`.
//!
//! Preconditions: none; a chart without 3D area has every triangle outside (share 1) and
//! percentiles 0, never NaN.

use crate::geometry::{signed_area_2d, triangle_area};

/// The bound of [`DensitySpread::outside`] in [`super::chart_metrics`] and [`super::measure`]:
/// `[1/2, 2]`.
pub const DEFAULT_DENSITY_BOUND: f64 = 2.0;

/// Density spread of one chart or a whole map (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensitySpread {
    /// Area-weighted 5th percentile of the density ratio.
    pub p5: f64,
    /// Area-weighted 95th percentile of the density ratio.
    pub p95: f64,
    /// Share of 3D area (0 to 1) whose density ratio is outside `[1/bound, bound]`.
    pub outside: f64,
    /// The bound `s` the share was measured against.
    pub bound: f64,
}

impl DensitySpread {
    /// NaN everywhere: the value of a chart without UVs.
    pub fn nan() -> Self {
        DensitySpread { p5: f64::NAN, p95: f64::NAN, outside: f64::NAN, bound: f64::NAN }
    }
}

/// `(ratio, 3D area)` of every triangle of a chart (see the module docs). The chart's
/// orientation is the sign of its total signed UV area; triangles of the other sign count 0.
pub fn density_ratios(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<(f64, f64)> {
    let a3: Vec<f64> = triangles
        .iter()
        .map(|t| triangle_area([positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]]))
        .collect();
    let a2: Vec<f64> =
        triangles.iter().map(|t| signed_area_2d([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]])).collect();
    let total3: f64 = a3.iter().sum();
    let signed: f64 = a2.iter().sum();
    let sign = if signed < 0.0 { -1.0 } else { 1.0 };
    let total2: f64 = a2.iter().map(|&a| (sign * a).max(0.0)).sum();
    if !(total3 > 0.0) || !(total2 > 0.0) || !total2.is_finite() {
        return a3.iter().map(|&w| (0.0, w)).collect();
    }
    let mean = total2 / total3;
    a3.iter()
        .zip(&a2)
        .map(|(&w, &a)| {
            let r = if w > 0.0 { (sign * a).max(0.0) / w / mean } else { 1.0 };
            (if r.is_finite() { r } else { 0.0 }, w)
        })
        .collect()
}

/// Spread of `(ratio, weight)` samples against `[1/bound, bound]`.
pub fn spread_of(mut samples: Vec<(f64, f64)>, bound: f64) -> DensitySpread {
    let total: f64 = samples.iter().map(|s| s.1).sum();
    if samples.is_empty() {
        return DensitySpread { p5: f64::NAN, p95: f64::NAN, outside: 0.0, bound };
    }
    if !(total > 0.0) {
        return DensitySpread { p5: 0.0, p95: 0.0, outside: 1.0, bound };
    }
    let lo = 1.0 / bound;
    let outside: f64 = samples.iter().filter(|s| !(s.0 >= lo && s.0 <= bound)).map(|s| s.1).sum::<f64>() / total;
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let quantile = |q: f64| {
        let target = q * total;
        let mut acc = 0.0;
        for s in &samples {
            acc += s.1;
            if acc >= target {
                return s.0;
            }
        }
        samples.last().map_or(f64::NAN, |s| s.0)
    };
    DensitySpread { p5: quantile(0.05), p95: quantile(0.95), outside: outside.clamp(0.0, 1.0), bound }
}

/// Density spread of one chart against `[1/bound, bound]` (see the module docs).
pub fn density_spread(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &[[f64; 2]], bound: f64) -> DensitySpread {
    spread_of(density_ratios(positions, triangles, uv), bound)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of equal 3D area, one mapped at 4× the area of the other: ratios 1.6 and
    /// 0.4 (the chart's mean density is 2.5 / 2), so with bound 2 half the area is outside.
    #[test]
    fn analytic_two_triangles() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let tris = [[0, 1, 2], [1, 3, 2]];
        // Second triangle's far corner pushed out so its UV area is 4x the first's.
        let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.5, 2.5]];
        let a2 = signed_area_2d([uv[1], uv[3], uv[2]]);
        assert!((a2 - 4.0 * 0.5).abs() < 1e-12, "{a2}");
        let s = density_spread(&p, &tris, &uv, 2.0);
        assert!((s.outside - 0.5).abs() < 1e-12, "{s:?}");
        assert!((s.p5 - 0.4).abs() < 1e-12 && (s.p95 - 1.6).abs() < 1e-12, "{s:?}");
        let s = density_spread(&p, &tris, &uv, 3.0);
        assert_eq!(s.outside, 0.0);
    }

    /// An isometry at any scale has every ratio 1; a flipped triangle counts as outside.
    #[test]
    fn isometry_and_flip() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let uv: Vec<[f64; 2]> = p.iter().map(|q| [3.0 * q[0] + 1.0, 3.0 * q[1] - 2.0]).collect();
        let s = density_spread(&p, &tris, &uv, 1.01);
        assert_eq!(s.outside, 0.0);
        assert!((s.p5 - 1.0).abs() < 1e-12 && (s.p95 - 1.0).abs() < 1e-12);
        let mut folded = uv.clone();
        folded[3] = [-2.0, -2.0];
        let s = density_spread(&p, &tris, &folded, 2.0);
        assert!(s.outside >= 0.5, "{s:?}");
        // No 3D area: everything outside, never NaN.
        let flat = [[0.0, 0.0, 0.0]; 4];
        let s = density_spread(&flat, &tris, &uv, 2.0);
        assert_eq!(s.outside, 1.0);
        assert!(!s.p5.is_nan());
    }
}
