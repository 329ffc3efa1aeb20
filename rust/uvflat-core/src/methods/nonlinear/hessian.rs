//! Derivatives of the distortion densities with respect to the Jacobian's entries
//! `(J00, J01, J10, J11)` (row-major, [`super::jacobian::flat`]) and their projections onto the
//! positive semidefinite cone, for projected Newton steps (Teran, Sifakis, Irving & Fedkiw
//! 2005: project each element's Hessian, then assemble; MIPS and SLIM's Newton steps).
//!
//! * [`symmetric_dirichlet_derivatives`] with the analytic projection [`project_twist`]
//!   (Smith, Goes & Kim 2019: only the twist eigenvalue can be negative);
//! * [`mips_derivatives`] with the numerical projections [`project_psd4`] and [`project_abs4`]
//!   (cyclic Jacobi).
//!
//! Preconditions: `det J > 0` (a valid map of a barrier method). Failures: none; a
//! non-finite matrix projects to zero in [`project_psd4`].

use super::jacobian::Jacobian;
use super::proxy::closest_rotation;

/// Gradient and Hessian of the symmetric Dirichlet density with respect to the Jacobian's
/// entries `j = (J00, J01, J10, J11)`. With `I2 = ‖J‖²`, `I3 = det J` and `g3 = ∂I3/∂j`,
/// the density is `I2 (1 + I3⁻²)`, so
/// `∇ = 2j (1 + I3⁻²) − 2 I2 I3⁻³ g3` and
/// `∇² = 2 (1 + I3⁻²) Id − 2 I3⁻³ (2j g3ᵀ + g3 2jᵀ) + 6 I2 I3⁻⁴ g3 g3ᵀ − 2 I2 I3⁻³ ∇²I3`.
/// Preconditions: det J > 0.
pub fn symmetric_dirichlet_derivatives(j: Jacobian) -> ([f64; 4], [[f64; 4]; 4]) {
    let v = [j[0][0], j[0][1], j[1][0], j[1][1]];
    let i2: f64 = v.iter().map(|x| x * x).sum();
    let i3 = v[0] * v[3] - v[1] * v[2];
    let g3 = [v[3], -v[2], -v[1], v[0]];
    let (r2, r3, r4) = (1.0 / (i3 * i3), 1.0 / (i3 * i3 * i3), 1.0 / (i3 * i3 * i3 * i3));
    let mut g = [0.0; 4];
    let mut h = [[0.0; 4]; 4];
    for a in 0..4 {
        g[a] = 2.0 * v[a] * (1.0 + r2) - 2.0 * i2 * r3 * g3[a];
        for b in 0..4 {
            h[a][b] = -2.0 * r3 * (2.0 * v[a] * g3[b] + g3[a] * 2.0 * v[b]) + 6.0 * i2 * r4 * g3[a] * g3[b];
        }
        h[a][a] += 2.0 * (1.0 + r2);
    }
    // ∇²I3: ∂²(ad − bc) is 1 at (a, d), (d, a) and −1 at (b, c), (c, b).
    h[0][3] -= 2.0 * i2 * r3;
    h[3][0] -= 2.0 * i2 * r3;
    h[1][2] += 2.0 * i2 * r3;
    h[2][1] += 2.0 * i2 * r3;
    (g, h)
}

/// Project the symmetric Dirichlet Hessian of [`symmetric_dirichlet_derivatives`] onto the positive
/// semidefinite cone, analytically (Smith, Goes & Kim, "Analytic eigensystems for isotropic
/// distortion energies", 2019). For `J = U Σ Vᵀ` its eigenvectors are the two scalings
/// `U diag(·) Vᵀ` (eigenvalues `2 + 6σᵢ⁻⁴ > 0`), the flip `U [[0,1],[1,0]] Vᵀ / √2`
/// (eigenvalue `2 + 2(σ₂⁻³ − σ₁⁻³)/(σ₁ − σ₂) > 2`) and the twist `U [[0,−1],[1,0]] Vᵀ / √2
/// = R₉₀ R / √2` (`R = U Vᵀ` the closest rotation) with eigenvalue
/// `λ = 2 − 2(σ₁⁻³ + σ₂⁻³)/(σ₁ + σ₂)`, the only one that can be negative: then `−λ t tᵀ` is
/// added. Preconditions: det J > 0.
pub fn project_twist(j: Jacobian, h: &mut [[f64; 4]; 4]) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let q = (0.5 * (a + d)).hypot(0.5 * (c - b));
    let r = (0.5 * (a - d)).hypot(0.5 * (c + b));
    let (s1, s2) = (q + r, q - r);
    let lambda = 2.0 - 2.0 * (s1.powi(-3) + s2.powi(-3)) / (s1 + s2);
    if lambda < 0.0 {
        let (rc, rs) = closest_rotation(j);
        let t = [-rs, -rc, rc, -rs].map(|x| x * std::f64::consts::FRAC_1_SQRT_2);
        for x in 0..4 {
            for y in 0..4 {
                h[x][y] -= lambda * t[x] * t[y];
            }
        }
    }
}

/// Gradient and Hessian of ‖J‖²/det J with respect to (J00, J01, J10, J11), for det J > 0.
pub fn mips_derivatives(j: [f64; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let n: f64 = j.iter().map(|x| x * x).sum();
    let d = j[0] * j[3] - j[1] * j[2];
    let g = [j[3], -j[2], -j[1], j[0]]; // ∇ det
    let mut grad = [0.0; 4];
    for k in 0..4 {
        grad[k] = 2.0 * j[k] / d - n * g[k] / (d * d);
    }
    let mut h = [[0.0; 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            let mut v = -2.0 * (j[a] * g[b] + g[a] * j[b]) / (d * d) + 2.0 * n * g[a] * g[b] / (d * d * d);
            if a == b {
                v += 2.0 / d;
            }
            h[a][b] = v;
        }
    }
    // ∂² det: entries (0,3), (3,0) = 1; (1,2), (2,1) = −1.
    let s = n / (d * d);
    h[0][3] -= s;
    h[3][0] -= s;
    h[1][2] += s;
    h[2][1] += s;
    (grad, h)
}

/// Project a symmetric 4×4 matrix onto the positive semidefinite cone (cyclic Jacobi
/// eigen-decomposition, negative eigenvalues set to zero).
pub fn project_psd4(a: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    filter_eigenvalues4(a, |x| x.max(0.0))
}

/// A symmetric 4×4 matrix with its negative eigenvalues mirrored (replaced by their absolute
/// values): positive semidefinite, and along a direction of negative curvature as steep as the
/// energy bends. Chen et al. 2024 ("Trust-region eigenvalue filtering for projected Newton")
/// find it converges in fewer iterations than clamping to zero.
pub fn project_abs4(a: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    filter_eigenvalues4(a, f64::abs)
}

/// `V f(Λ) Vᵀ` for the eigen-decomposition `V Λ Vᵀ` of a symmetric 4×4 matrix (cyclic Jacobi).
fn filter_eigenvalues4(a: &[[f64; 4]; 4], f: impl Fn(f64) -> f64) -> [[f64; 4]; 4] {
    let mut m = *a;
    let mut v = [[0.0; 4]; 4];
    for i in 0..4 {
        v[i][i] = 1.0;
    }
    let scale: f64 = m.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return [[0.0; 4]; 4];
    }
    for _sweep in 0..30 {
        let off: f64 = (0..4).flat_map(|p| (0..4).filter(move |&q| q != p).map(move |q| (p, q))).map(|(p, q)| m[p][q] * m[p][q]).sum();
        if off <= 1e-30 * scale * scale {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if m[p][q].abs() <= 1e-300 {
                    continue;
                }
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let (mkp, mkq) = (m[k][p], m[k][q]);
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for k in 0..4 {
                    let (mpk, mqk) = (m[p][k], m[q][k]);
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for k in 0..4 {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let lam: [f64; 4] = [f(m[0][0]), f(m[1][1]), f(m[2][2]), f(m[3][3])];
    let mut out = [[0.0; 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            out[a][b] = (0..4).map(|k| v[a][k] * lam[k] * v[b][k]).sum();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::nonlinear::energy::{mips_density, symmetric_dirichlet_density};

    fn jacobian_of(s1: f64, s2: f64, u: f64, v: f64) -> [[f64; 2]; 2] {
        let ru = [[u.cos(), -u.sin()], [u.sin(), u.cos()]];
        let rv = [[v.cos(), -v.sin()], [v.sin(), v.cos()]];
        let mut j = [[0.0; 2]; 2];
        for a in 0..2 {
            for b in 0..2 {
                j[a][b] = ru[a][0] * s1 * rv[b][0] + ru[a][1] * s2 * rv[b][1];
            }
        }
        j
    }

    #[test]
    fn density_derivatives_match_finite_differences() {
        for &(s1, s2, u, v) in &[(1.0, 1.0, 0.3, -0.2), (2.5, 0.4, 0.7, -1.1), (0.3, 0.2, 2.0, 0.5), (1.2, 0.9, -0.4, 0.0)] {
            let j = jacobian_of(s1, s2, u, v);
            let (g, h) = symmetric_dirichlet_derivatives(j);
            let f = |x: [f64; 4]| symmetric_dirichlet_density([[x[0], x[1]], [x[2], x[3]]]);
            let x0 = [j[0][0], j[0][1], j[1][0], j[1][1]];
            let eps = 1e-6;
            for a in 0..4 {
                let (mut xp, mut xm) = (x0, x0);
                xp[a] += eps;
                xm[a] -= eps;
                let fd = (f(xp) - f(xm)) / (2.0 * eps);
                assert!((fd - g[a]).abs() <= 1e-6 * (1.0 + g[a].abs()), "gradient {a}: {fd} vs {}", g[a]);
                let (gp, gm) = (symmetric_dirichlet_derivatives([[xp[0], xp[1]], [xp[2], xp[3]]]).0, symmetric_dirichlet_derivatives([[xm[0], xm[1]], [xm[2], xm[3]]]).0);
                for b in 0..4 {
                    let fd = (gp[b] - gm[b]) / (2.0 * eps);
                    assert!((fd - h[a][b]).abs() <= 1e-5 * (1.0 + h[a][b].abs()), "Hessian {a}{b}: {fd} vs {}", h[a][b]);
                }
            }
        }
    }

    #[test]
    fn analytic_projection_equals_the_eigen_decomposition() {
        let mut negative_seen = false;
        for k in 0..200 {
            let t = k as f64;
            let (s1, s2) = (0.15 + 3.0 * (0.37 * t).sin().abs(), 0.1 + 2.0 * (0.61 * t + 0.3).cos().abs());
            let j = jacobian_of(s1.max(s2), s1.min(s2), 0.13 * t, -0.29 * t);
            let (_, h) = symmetric_dirichlet_derivatives(j);
            let want = project_psd4(&h);
            let mut got = h;
            project_twist(j, &mut got);
            negative_seen |= got != h;
            let scale = h.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for a in 0..4 {
                for b in 0..4 {
                    assert!((got[a][b] - want[a][b]).abs() <= 1e-8 * scale, "{k}: ({a},{b}) {} vs {}", got[a][b], want[a][b]);
                }
            }
        }
        assert!(negative_seen, "no Jacobian with a negative twist eigenvalue was tested");
    }

    fn density4(j: [f64; 4]) -> f64 {
        mips_density([[j[0], j[1]], [j[2], j[3]]])
    }

    #[test]
    fn psd_projection_keeps_psd_matrices_and_clips_negative_eigenvalues() {
        let a = [[2.0, 1.0, 0.0, 0.0], [1.0, 2.0, 0.0, 0.0], [0.0, 0.0, 3.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        let p = project_psd4(&a);
        for i in 0..4 {
            for j in 0..4 {
                assert!((p[i][j] - a[i][j]).abs() < 1e-12);
            }
        }
        // diag(1, −2, 3, −4) rotated: projection is diag(1, 0, 3, 0) rotated the same way.
        let (c, s) = (0.6f64, 0.8f64);
        let q = [[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, c, s], [0.0, 0.0, -s, c]];
        let d = [1.0, -2.0, 3.0, -4.0];
        let mk = |d: [f64; 4]| {
            let mut m = [[0.0; 4]; 4];
            for i in 0..4 {
                for j in 0..4 {
                    m[i][j] = (0..4).map(|k| q[i][k] * d[k] * q[j][k]).sum();
                }
            }
            m
        };
        let p = project_psd4(&mk(d));
        let want = mk([1.0, 0.0, 3.0, 0.0]);
        for i in 0..4 {
            for j in 0..4 {
                assert!((p[i][j] - want[i][j]).abs() < 1e-12, "{p:?}");
            }
        }
        // Mirrored: diag(1, 2, 3, 4) rotated the same way; a PSD matrix is kept.
        let p = project_abs4(&mk(d));
        let want = mk([1.0, 2.0, 3.0, 4.0]);
        let kept = project_abs4(&a);
        for i in 0..4 {
            for j in 0..4 {
                assert!((p[i][j] - want[i][j]).abs() < 1e-12, "{p:?}");
                assert!((kept[i][j] - a[i][j]).abs() < 1e-12);
            }
        }
    }


    #[test]
    fn mips_derivatives_match_finite_differences() {
        let j = [1.3, 0.4, -0.2, 0.9];
        let (g, h) = mips_derivatives(j);
        let eps = 1e-6;
        for k in 0..4 {
            let (mut jp, mut jm) = (j, j);
            jp[k] += eps;
            jm[k] -= eps;
            let fd = (density4(jp) - density4(jm)) / (2.0 * eps);
            assert!((fd - g[k]).abs() < 1e-6, "gradient {k}: {fd} vs {}", g[k]);
            let (gp, _) = mips_derivatives(jp);
            let (gm, _) = mips_derivatives(jm);
            for l in 0..4 {
                let fd = (gp[l] - gm[l]) / (2.0 * eps);
                assert!((fd - h[l][k]).abs() < 1e-5, "hessian {l},{k}: {fd} vs {}", h[l][k]);
            }
        }
        // Conformal J (a scaled rotation): energy 2, gradient zero.
        let (c, s) = (0.8 * 1.7, 0.6 * 1.7);
        let jc = [c, -s, s, c];
        assert!((density4(jc) - 2.0).abs() < 1e-12);
        assert!(mips_derivatives(jc).0.iter().all(|x| x.abs() < 1e-12));
    }
}
