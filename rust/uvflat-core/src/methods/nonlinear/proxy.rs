//! Local steps of the local/global methods: the closest rotation of a Jacobian (ARAP, Liu et
//! al. 2008) and SLIM's reweighted proxy of the symmetric Dirichlet energy (Rabinovich et al.
//! 2017, eq. 9), which the scaffold method reuses.
//!
//! SLIM: with the SVD `J = U Σ Vᵀ`, the proxy of a triangle is `‖W (J − R)‖²_F` with the
//! closest rotation `R = U Vᵀ` and `W² = U diag(w1², w2²) Uᵀ`,
//! `w² = h'(σ) / (2(σ − 1)) = (σ + 1)(σ² + 1) / σ³` for `h(σ) = σ² + σ⁻²`. For an isometry
//! `W² = 4 I`.
//!
//! Preconditions: [`reweight`] wants `det J > 0` (a valid map of a barrier method); a
//! degenerate Jacobian gets huge but finite weights. Failures: none.

use super::jacobian::Jacobian;

/// The rotation closest to `j` in the Frobenius norm (det +1), as `(cos θ, sin θ)`; the
/// identity for `j = 0`.
#[inline]
pub fn closest_rotation(j: Jacobian) -> (f64, f64) {
    let (c, s) = (j[0][0] + j[1][1], j[1][0] - j[0][1]);
    let r = c.hypot(s);
    if r > 0.0 {
        (c / r, s / r)
    } else {
        (1.0, 0.0)
    }
}

/// SLIM's local step of one triangle: `W²` (symmetric, as `[m00, m01, m11]`) and `W² R`
/// (row-major).
#[inline]
pub fn reweight(j: Jacobian) -> ([f64; 3], [[f64; 2]; 2]) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    // Singular values (det > 0 on a valid map, so q > r).
    let q = (0.5 * (a + d)).hypot(0.5 * (c - b));
    let r = (0.5 * (a - d)).hypot(0.5 * (c + b));
    let s1 = q + r;
    let s2 = (q - r).max(1e-300);
    let w = |s: f64| (s + 1.0) * (s * s + 1.0) / (s * s * s);
    let (w1, w2) = (w(s1), w(s2));
    // Left singular vector of σ1: principal eigenvector of J Jᵀ.
    let phi = 0.5 * (2.0 * (a * c + b * d)).atan2(a * a + b * b - c * c - d * d);
    let (cp, sp) = (phi.cos(), phi.sin());
    let m = [w1 * cp * cp + w2 * sp * sp, (w1 - w2) * cp * sp, w1 * sp * sp + w2 * cp * cp];
    let (rc, rs) = closest_rotation(j);
    let rot = [[rc, -rs], [rs, rc]];
    let mr = [
        [m[0] * rot[0][0] + m[1] * rot[1][0], m[0] * rot[0][1] + m[1] * rot[1][1]],
        [m[1] * rot[0][0] + m[2] * rot[1][0], m[1] * rot[0][1] + m[2] * rot[1][1]],
    ];
    (m, mr)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(a: f64) -> Jacobian {
        [[a.cos(), -a.sin()], [a.sin(), a.cos()]]
    }

    #[test]
    fn the_proxy_of_an_isometry_is_four_times_the_identity() {
        for a in [0.0, 0.9, -2.5] {
            let r = rot(a);
            let (m, mr) = reweight(r);
            assert!((m[0] - 4.0).abs() < 1e-12 && m[1].abs() < 1e-12 && (m[2] - 4.0).abs() < 1e-12, "{m:?}");
            for x in 0..2 {
                for y in 0..2 {
                    assert!((mr[x][y] - 4.0 * r[x][y]).abs() < 1e-12);
                }
            }
            let (c, s) = closest_rotation(r);
            assert!((c - a.cos()).abs() < 1e-12 && (s - a.sin()).abs() < 1e-12);
        }
    }

    #[test]
    fn reweighting_matches_the_svd() {
        let (s1, s2) = (2.5, 0.4);
        let (ru, rv) = (rot(0.7), rot(-1.1));
        let mut j = [[0.0; 2]; 2];
        for a in 0..2 {
            for b in 0..2 {
                j[a][b] = ru[a][0] * s1 * rv[b][0] + ru[a][1] * s2 * rv[b][1];
            }
        }
        let (m, mr) = reweight(j);
        let w = |s: f64| (s + 1.0) * (s * s + 1.0) / (s * s * s);
        // W² has eigenvalues w(s1), w(s2), with eigenvector U e1 for w(s1).
        let e1 = [ru[0][0], ru[1][0]];
        let me1 = [m[0] * e1[0] + m[1] * e1[1], m[1] * e1[0] + m[2] * e1[1]];
        assert!((me1[0] - w(s1) * e1[0]).abs() < 1e-12 && (me1[1] - w(s1) * e1[1]).abs() < 1e-12);
        assert!((m[0] + m[2] - w(s1) - w(s2)).abs() < 1e-12);
        // R = U Vᵀ is the closest rotation, and W² R is returned.
        let (c, s) = closest_rotation(j);
        let r = [[c, -s], [s, c]];
        let uvt = [
            [ru[0][0] * rv[0][0] + ru[0][1] * rv[0][1], ru[0][0] * rv[1][0] + ru[0][1] * rv[1][1]],
            [ru[1][0] * rv[0][0] + ru[1][1] * rv[0][1], ru[1][0] * rv[1][0] + ru[1][1] * rv[1][1]],
        ];
        let mm = [[m[0], m[1]], [m[1], m[2]]];
        for a in 0..2 {
            for b in 0..2 {
                assert!((r[a][b] - uvt[a][b]).abs() < 1e-12);
                assert!((mr[a][b] - (mm[a][0] * r[0][b] + mm[a][1] * r[1][b])).abs() < 1e-12);
            }
        }
        // A diagonal stretch: R = I and W² = diag(w(2), w(½)).
        let (m, mr) = reweight([[2.0, 0.0], [0.0, 0.5]]);
        assert!((m[0] - w(2.0)).abs() < 1e-9 && m[1].abs() < 1e-12 && (m[2] - w(0.5)).abs() < 1e-9, "{m:?}");
        assert!((mr[0][0] - w(2.0)).abs() < 1e-9 && (mr[1][1] - w(0.5)).abs() < 1e-9);
    }
}
