//! Distortion densities of one Jacobian and the area-weighted chart energies built on them.
//!
//! * Symmetric Dirichlet (Smith & Schaefer 2015; SLIM, Rabinovich et al. 2017; SCAF, Jiang et
//!   al. 2017): `D(J) = ‖J‖²_F (1 + 1/det² J) = σ1² + σ2² + σ1⁻² + σ2⁻²`, 4 for a rotation, its
//!   minimum; `+∞` unless `det J > 0` (a barrier against flips). The chart energy
//!   [`symmetric_dirichlet`] is `Σ A D / (4 Σ A)`, 1 for an isometry.
//! * MIPS (Hormann & Greiner 2000): `‖J‖²/det J = σ1/σ2 + σ2/σ1`, 2 for a similarity, its
//!   minimum; `+∞` unless `det J > 0`. The chart energy [`mips_energy`] is `Σ A M / (2 Σ A)`.
//! * ARAP (Liu et al. 2008): `min_R ‖J − R‖²_F = ‖J‖² − 2 |(J00 + J11, J10 − J01)| + 2`, 0 for
//!   a rotation. The chart energy [`arap_energy`] is `Σ A · ARAP / Σ A`.
//!
//! Optimal scale: `D(sJ)` summed is `s² P + s⁻² Q` with `P = Σ A ‖J‖²`, `Q = Σ A ‖J⁻¹‖²`,
//! minimised by `s = (Q/P)^{1/4}` ([`optimal_scale`]).
//!
//! Preconditions: `uv` holds every vertex the triangles name. Failures: none; an invalid map
//! has energy `+∞` (symmetric Dirichlet, MIPS) and no finite optimal scale.

use rayon::prelude::*;

use super::jacobian::{Jacobian, TriangleOperators};

#[inline]
fn det(j: Jacobian) -> f64 {
    j[0][0] * j[1][1] - j[0][1] * j[1][0]
}

#[inline]
fn frobenius2(j: Jacobian) -> f64 {
    j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1]
}

/// Symmetric Dirichlet density `‖J‖² (1 + 1/det²)` of one Jacobian; 4 for a rotation, `+∞`
/// unless `det J > 0`.
#[inline]
pub fn symmetric_dirichlet_density(j: Jacobian) -> f64 {
    let det = det(j);
    if !(det > 0.0) {
        return f64::INFINITY;
    }
    frobenius2(j) * (1.0 + 1.0 / (det * det))
}

/// MIPS density `‖J‖² / det J` of one Jacobian; 2 for a similarity, `+∞` unless `det J > 0`.
#[inline]
pub fn mips_density(j: Jacobian) -> f64 {
    let det = det(j);
    if det > 0.0 {
        frobenius2(j) / det
    } else {
        f64::INFINITY
    }
}

/// ARAP density `min_{R ∈ SO(2)} ‖J − R‖²_F` of one Jacobian; 0 for a rotation.
#[inline]
pub fn arap_density(j: Jacobian) -> f64 {
    let trace_rt_j = (j[0][0] + j[1][1]).hypot(j[1][0] - j[0][1]);
    (frobenius2(j) - 2.0 * trace_rt_j + 2.0).max(0.0)
}

/// `Σ_f weight[f] · density(J_f)` over `triangles` (the operators' triangles, in order);
/// triangles of zero weight contribute nothing (not even a `+∞`).
pub fn weighted_sum(
    ops: &TriangleOperators,
    weight: &[f64],
    triangles: &[[u32; 3]],
    uv: &[[f64; 2]],
    density: impl Fn(Jacobian) -> f64 + Sync,
) -> f64 {
    ordered_sum(triangles.len(), |f| {
        let w = weight[f];
        if w == 0.0 {
            return 0.0;
        }
        w * density(ops.jacobian(f, &triangles[f], uv))
    })
}

/// Triangles per partial sum of [`ordered_sum`].
const SUM_CHUNK: usize = 2048;

/// `Σ_{f < n} term(f)`, in parallel but with the same rounding on any number of threads:
/// fixed chunks of `SUM_CHUNK` terms summed in order, then their sums in order. (A plain
/// parallel sum splits by the threads' work stealing, so a tolerance test on the energy could
/// stop after a different iteration on one thread than on two.) One chunk or less is summed
/// right here, without rayon.
pub fn ordered_sum(n: usize, term: impl Fn(usize) -> f64 + Sync) -> f64 {
    ordered_fold(n, 0.0, term, |a, b| a + b)
}

/// [`ordered_sum`] of values of any type with `add` and its neutral `zero`.
fn ordered_fold<T: Copy + Send + Sync>(n: usize, zero: T, term: impl Fn(usize) -> T + Sync, add: impl Fn(T, T) -> T + Sync) -> T {
    let chunk = |k: usize| (k * SUM_CHUNK..((k + 1) * SUM_CHUNK).min(n)).fold(zero, |s, f| add(s, term(f)));
    if n <= SUM_CHUNK {
        return chunk(0);
    }
    let partial: Vec<T> = (0..n.div_ceil(SUM_CHUNK)).into_par_iter().map(chunk).collect();
    partial.into_iter().fold(zero, &add)
}

/// `Σ A_f · density(J_f)` with the operators' rest areas as weights.
pub fn area_weighted(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]], density: impl Fn(Jacobian) -> f64 + Sync) -> f64 {
    weighted_sum(ops, &ops.area, triangles, uv, density)
}

/// Symmetric Dirichlet energy `Σ A (‖J‖² + ‖J⁻¹‖²) / (4 Σ A)` of `uv`: 1 for an isometry,
/// `+∞` if any triangle of positive area has a non-positive Jacobian determinant.
pub fn symmetric_dirichlet(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    area_weighted(ops, triangles, uv, symmetric_dirichlet_density) / (4.0 * ops.total_area)
}

/// MIPS energy `Σ A ‖J‖²/det J / (2 Σ A)`: 1 for a conformal map, `+∞` if a triangle of
/// positive area is not positively oriented or the total area is 0.
pub fn mips_energy(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    let sum = area_weighted(ops, triangles, uv, mips_density);
    if ops.total_area > 0.0 {
        sum / (2.0 * ops.total_area)
    } else {
        f64::INFINITY
    }
}

/// ARAP energy `Σ A ‖J − R‖² / Σ A` with the closest rotations: 0 for an isometry.
pub fn arap_energy(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    area_weighted(ops, triangles, uv, arap_density) / ops.total_area
}

/// The factor `s = (Q/P)^{1/4}` minimising `E(s) = s² P + s⁻² Q`, `P = Σ A ‖J‖²`,
/// `Q = Σ A ‖J‖²/det² = Σ A ‖J⁻¹‖²`, over `n` triangles given as `(area, J)` by
/// `area_and_jacobian`: the best uniform scale of a map for the symmetric Dirichlet energy.
/// Not finite for a map with a degenerate triangle.
pub fn optimal_scale(n: usize, area_and_jacobian: impl Fn(usize) -> (f64, Jacobian) + Sync) -> f64 {
    let (p, q) = ordered_fold(
        n,
        (0.0, 0.0),
        |f| {
            let (a, j) = area_and_jacobian(f);
            let det = det(j);
            let fro = frobenius2(j);
            (a * fro, a * fro / (det * det))
        },
        |a, b| (a.0 + b.0, a.1 + b.1),
    );
    (q / p).sqrt().sqrt()
}

/// Multiply every UV by `s` (no-op unless `s` is finite and positive).
pub fn scale_uv(uv: &mut [[f64; 2]], s: f64) {
    if s.is_finite() && s > 0.0 {
        for x in uv.iter_mut() {
            *x = [s * x[0], s * x[1]];
        }
    }
}

/// Scale `uv` about the origin by the factor minimising the symmetric Dirichlet energy over
/// the operators' triangles ([`optimal_scale`]). No-op for an invalid map.
pub fn scale_optimally(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &mut [[f64; 2]]) {
    let s = optimal_scale(triangles.len(), |f| (ops.area[f], ops.jacobian(f, &triangles[f], uv)));
    scale_uv(uv, s);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotation(a: f64) -> Jacobian {
        [[a.cos(), -a.sin()], [a.sin(), a.cos()]]
    }

    #[test]
    fn rotations_are_the_minimum_of_every_density() {
        for a in [0.0, 0.4, -2.1, 3.0] {
            let r = rotation(a);
            assert!((symmetric_dirichlet_density(r) - 4.0).abs() < 1e-12);
            assert!((mips_density(r) - 2.0).abs() < 1e-12);
            assert!(arap_density(r) < 1e-24);
            // Any other map costs more.
            for j in [[[1.1, 0.0], [0.0, 1.0]], [[1.0, 0.2], [0.0, 1.0]], [[0.9, 0.0], [0.1, 1.2]]] {
                assert!(symmetric_dirichlet_density(j) > 4.0);
                assert!(arap_density(j) > 0.0);
            }
        }
        // MIPS is minimal on every similarity, not only rotations.
        assert!((mips_density([[3.0, 0.0], [0.0, 3.0]]) - 2.0).abs() < 1e-12);
        // Reflections and degenerate maps are infinitely bad for the barrier densities.
        let mirror = [[1.0, 0.0], [0.0, -1.0]];
        assert_eq!(symmetric_dirichlet_density(mirror), f64::INFINITY);
        assert_eq!(mips_density(mirror), f64::INFINITY);
        assert_eq!(symmetric_dirichlet_density([[1.0, 1.0], [1.0, 1.0]]), f64::INFINITY);
    }

    #[test]
    fn densities_match_their_singular_value_forms() {
        let (s1, s2) = (2.5, 0.4);
        let (u, v) = (rotation(0.7), rotation(-1.1));
        let mut j = [[0.0; 2]; 2];
        for a in 0..2 {
            for b in 0..2 {
                j[a][b] = u[a][0] * s1 * v[b][0] + u[a][1] * s2 * v[b][1];
            }
        }
        assert!((symmetric_dirichlet_density(j) - (s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2))).abs() < 1e-12);
        assert!((mips_density(j) - (s1 / s2 + s2 / s1)).abs() < 1e-12);
        assert!((arap_density(j) - ((s1 - 1.0f64).powi(2) + (s2 - 1.0f64).powi(2))).abs() < 1e-12);
    }

    #[test]
    fn a_scaled_chart_starts_at_the_known_energy_and_scales_back_to_the_isometry() {
        let q = [[0.0, 0.0], [1.0, 0.0], [0.2, 0.9], [1.3, 1.1]];
        let tris = [[0u32, 1, 2], [1, 3, 2]];
        let ops = TriangleOperators::planar(&q, &tris);
        for s in [0.5, 3.0] {
            let mut uv: Vec<[f64; 2]> = q.iter().map(|p| [s * p[0], s * p[1]]).collect();
            let want = 0.25 * (2.0 * s * s + 2.0 / (s * s));
            assert!((symmetric_dirichlet(&ops, &tris, &uv) - want).abs() < 1e-12);
            assert!((mips_energy(&ops, &tris, &uv) - 1.0).abs() < 1e-12);
            assert!((arap_energy(&ops, &tris, &uv) - 2.0 * (s - 1.0) * (s - 1.0)).abs() < 1e-12);
            scale_optimally(&ops, &tris, &mut uv);
            assert!((symmetric_dirichlet(&ops, &tris, &uv) - 1.0).abs() < 1e-12);
            assert!(arap_energy(&ops, &tris, &uv) < 1e-20);
        }
        let mut flat: Vec<[f64; 2]> = q.iter().map(|p| [p[0], 0.0 * p[1]]).collect();
        let before = flat.clone();
        scale_optimally(&ops, &tris, &mut flat);
        assert_eq!(flat, before, "an invalid map is not scaled");
    }
}
