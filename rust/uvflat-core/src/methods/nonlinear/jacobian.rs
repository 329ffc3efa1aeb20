//! Per-triangle rest shapes and Jacobian operators, one type for every nonlinear method.
//!
//! A chart triangle f with corners t = (t0, t1, t2) is laid out in a 2D rest frame; the
//! piecewise linear UV map restricted to it has the constant Jacobian
//!
//! ```text
//! J[k][j] = Σ_i grad[f][j][i] · x_k(t_i)      (k = u or v, j = x or y of the rest frame)
//! ```
//!
//! where `grad[f][j][i]` is the derivative along rest axis j of corner i's hat function. The
//! rest shape comes from one of three layouts:
//!
//! * [`TriangleOperators::new`]: from the clamped corner angles and the longest 3D edge (law
//!   of sines; ARAP, SLIM) — exact for ordinary triangles, thin but valid for degenerate ones;
//! * [`TriangleOperators::local_frames`]: the 3D triangle in its own orthonormal frame
//!   ([`crate::geometry::local_frame`]; MIPS, scaffold) — exact for ordinary triangles; a
//!   degenerate one gets the thin shape of [`TriangleOperators::new`], so a barrier holds it;
//! * [`TriangleOperators::planar`]: 2D points as they are (the scaffold's triangles, whose rest
//!   shape is their current shape).
//!
//! Preconditions: triangle indices in range. Never fails; see each constructor for degenerate
//! input.

use rayon::prelude::*;

use crate::geometry::{clamped_angles, local_frame, norm, sub, triangle_area};

/// A 2×2 Jacobian `[[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]]`.
pub type Jacobian = [[f64; 2]; 2];

/// Row-major entries `(J00, J01, J10, J11)` of a Jacobian.
#[inline]
pub fn flat(j: Jacobian) -> [f64; 4] {
    [j[0][0], j[0][1], j[1][0], j[1][1]]
}

/// Per-triangle gradient operators and rest areas of a set of triangles (see the module docs).
#[derive(Debug, Clone)]
pub struct TriangleOperators {
    /// `grad[f][j][i]`: derivative along rest axis j of the hat function of corner i.
    pub grad: Vec<[[f64; 3]; 2]>,
    /// Rest area (energy weight) of every triangle: > 0 from [`TriangleOperators::new`]; 0 for
    /// a degenerate triangle from the other constructors.
    pub area: Vec<f64>,
    /// Sum of `area`.
    pub total_area: f64,
}

/// Gradients and area of the 2D triangle `q` (counter-clockwise for a positive area); zero
/// gradients and area for a degenerate or non-finite one.
#[inline]
fn planar_rest(q: [[f64; 2]; 3]) -> ([[f64; 3]; 2], f64) {
    let (e1, e2) = ([q[1][0] - q[0][0], q[1][1] - q[0][1]], [q[2][0] - q[0][0], q[2][1] - q[0][1]]);
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    if !(det.abs() > 0.0) || !det.is_finite() {
        return ([[0.0; 3]; 2], 0.0);
    }
    // R = [e1 e2] (columns); J = U R⁻¹ with U = [x1 − x0, x2 − x0].
    let inv = [[e2[1] / det, -e2[0] / det], [-e1[1] / det, e1[0] / det]];
    let mut g = [[0.0; 3]; 2];
    for c in 0..2 {
        g[c] = [-(inv[0][c] + inv[1][c]), inv[0][c], inv[1][c]];
    }
    (g, 0.5 * det.abs())
}

/// Length of edge k (corner k to corner k + 1) of triangle `t`.
#[inline]
fn edge(positions: &[[f64; 3]], t: &[u32; 3], k: usize) -> f64 {
    norm(sub(positions[t[(k + 1) % 3] as usize], positions[t[k] as usize]))
}

/// Longest 3D edge of triangle `t`.
#[inline]
fn longest_edge(positions: &[[f64; 3]], t: &[u32; 3]) -> f64 {
    edge(positions, t, 0).max(edge(positions, t, 1)).max(edge(positions, t, 2))
}

/// Mean 3D edge length of `triangles` (each edge once per triangle), 1 when there is none.
fn mean_edge(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    let (sum, count) = triangles.iter().fold((0.0, 0usize), |(s, c), t| (s + edge(positions, t, 0) + edge(positions, t, 1) + edge(positions, t, 2), c + 3));
    if count > 0 && sum > 0.0 {
        sum / count as f64
    } else {
        1.0
    }
}

/// Gradients and area of [`TriangleOperators::new`]'s rest frame of triangle `t`: the
/// clamped angles and the longest edge (`mean_edge` when the corners coincide).
#[inline]
fn sines_rest(positions: &[[f64; 3]], t: &[u32; 3], mean_edge: f64) -> ([[f64; 3]; 2], f64) {
    let p = [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
    let a = clamped_angles(p);
    let longest = longest_edge(positions, t);
    let longest = if longest > 0.0 { longest } else { mean_edge };
    // Side opposite corner k is proportional to sin a_k.
    let s = longest / a[0].sin().max(a[1].sin()).max(a[2].sin());
    let (l01, l02) = (s * a[2].sin(), s * a[1].sin());
    let (x1, x2, y2) = (l01, l02 * a[0].cos(), l02 * a[0].sin());
    let det = x1 * y2;
    let g = [[-1.0 / x1, 1.0 / x1, 0.0], [(x2 - x1) / det, -x2 / det, x1 / det]];
    (g, 0.5 * det)
}

impl TriangleOperators {
    fn from_parts(parts: Vec<([[f64; 3]; 2], f64)>) -> Self {
        let (grad, area): (Vec<[[f64; 3]; 2]>, Vec<f64>) = parts.into_iter().unzip();
        let total_area = area.iter().sum();
        TriangleOperators { grad, area, total_area }
    }

    /// Rest frames from the clamped corner angles ([`clamped_angles`]) and the longest 3D
    /// edge (law of sines); `area` is the area of that frame triangle. Never fails: a triangle
    /// whose corners coincide gets an equilateral shape with the chart's mean edge length.
    pub fn new(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Self {
        let mean_edge = mean_edge(positions, triangles);
        let rest = |t: &[u32; 3]| sines_rest(positions, t, mean_edge);
        // Small charts sequentially: the same values without rayon's overhead.
        let (grad, area): (Vec<[[f64; 3]; 2]>, Vec<f64>) =
            if triangles.len() < 1024 { triangles.iter().map(rest).unzip() } else { triangles.par_iter().map(rest).unzip() };
        let total_area = area.iter().sum();
        TriangleOperators { grad, area, total_area }
    }

    /// [`TriangleOperators::new`] of `triangles`, whose first `self.len()` are the triangles
    /// `self` was made from by [`TriangleOperators::new`]: their frames are taken over (unless
    /// their corners coincide, whose frame depends on the mean edge of all the triangles), only
    /// the others are computed. The same values as `new(positions, triangles)`, for the few
    /// triangles a method adds to a chart's (SLIM's other quad diagonals).
    pub fn extended(&self, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Self {
        let mean_edge = mean_edge(positions, triangles);
        let mut grad = Vec::with_capacity(triangles.len());
        let mut area = Vec::with_capacity(triangles.len());
        for (f, t) in triangles.iter().enumerate() {
            let (g, a) = if f < self.len() && longest_edge(positions, t) > 0.0 {
                (self.grad[f], self.area[f])
            } else {
                sines_rest(positions, t, mean_edge)
            };
            grad.push(g);
            area.push(a);
        }
        let total_area = area.iter().sum();
        TriangleOperators { grad, area, total_area }
    }

    /// Rest frames from each 3D triangle in its own orthonormal frame; `area` is the 3D area.
    /// A triangle that is degenerate in that frame (collinear or coincident corners) gets
    /// [`Self::new`]'s thin but valid shape from its clamped angles instead, so its energy
    /// still keeps it from collapsing or flipping in the map: with zero area it would carry no
    /// energy, and a barrier method's line search would let it flip (scaffold on a scan with
    /// collapsed vertices folded three such triangles).
    pub fn local_frames(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Self {
        let mut mean: Option<f64> = None;
        let mut parts: Vec<([[f64; 3]; 2], f64)> = Vec::with_capacity(triangles.len());
        for t in triangles {
            let p = [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
            let (g, a) = planar_rest(local_frame(p));
            parts.push(if a > 0.0 {
                (g, triangle_area(p))
            } else {
                sines_rest(positions, t, *mean.get_or_insert_with(|| mean_edge(positions, triangles)))
            });
        }
        Self::from_parts(parts)
    }

    /// Rest frames of 2D triangles as they are (counter-clockwise for a positive area); a
    /// degenerate or non-finite one gets area 0 and zero gradients.
    pub fn planar(points: &[[f64; 2]], triangles: &[[u32; 3]]) -> Self {
        Self::from_parts(
            triangles
                .iter()
                .map(|t| planar_rest([points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]]))
                .collect(),
        )
    }

    /// Whether the 2D triangle `q` has a non-degenerate rest shape (what [`Self::planar`]
    /// gives a positive area).
    pub fn planar_is_valid(q: [[f64; 2]; 3]) -> bool {
        planar_rest(q).1 > 0.0
    }

    /// Multiply every area by its weight (e.g. ½ for the four triangles of a quad's two
    /// splits) and recompute the total.
    pub fn weighted(mut self, weights: &[f64]) -> Self {
        for (a, w) in self.area.iter_mut().zip(weights) {
            *a *= w;
        }
        self.total_area = self.area.iter().sum();
        self
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.area.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.area.is_empty()
    }

    /// Jacobian of triangle `f` whose corners have the UVs `x`.
    #[inline]
    pub fn jacobian_of(&self, f: usize, x: [[f64; 2]; 3]) -> Jacobian {
        let g = &self.grad[f];
        let mut j = [[0.0; 2]; 2];
        for i in 0..3 {
            for k in 0..2 {
                j[k][0] += g[0][i] * x[i][k];
                j[k][1] += g[1][i] * x[i][k];
            }
        }
        j
    }

    /// Jacobian of triangle `f` (vertices `t`) under `uv`.
    #[inline]
    pub fn jacobian(&self, f: usize, t: &[u32; 3], uv: &[[f64; 2]]) -> Jacobian {
        self.jacobian_of(f, [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]])
    }

    /// Per-triangle stiffness `Σ_j grad[j][a]·grad[j][b]` (the cotangent Laplacian of the
    /// triangle divided by its area), row-major 3 × 3.
    #[inline]
    pub fn stiffness(&self, f: usize) -> [[f64; 3]; 3] {
        let g = &self.grad[f];
        let mut l = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                l[a][b] = g[0][a] * g[0][b] + g[1][a] * g[1][b];
            }
        }
        l
    }

    /// Pull a gradient with respect to the row-major Jacobian entries (see [`flat`]) back to
    /// triangle `f`'s six UV coordinates, ordered `(u0, u1, u2, v0, v1, v2)`.
    #[inline]
    pub fn pull_gradient(&self, f: usize, gj: [f64; 4]) -> [f64; 6] {
        let g = &self.grad[f];
        let mut out = [0.0; 6];
        for r in 0..2 {
            for c in 0..2 {
                for k in 0..3 {
                    out[3 * r + k] += gj[2 * r + c] * g[c][k];
                }
            }
        }
        out
    }

    /// `Bᵀ H B` for a symmetric 4×4 matrix `H` over the row-major Jacobian entries, `B` the
    /// 4×6 map from `(u0, u1, u2, v0, v1, v2)` of triangle `f` to them.
    pub fn pull_hessian(&self, f: usize, h: &[[f64; 4]; 4]) -> [[f64; 6]; 6] {
        let g = &self.grad[f];
        let b_row = |m: usize| {
            let (r, c) = (m / 2, m % 2);
            let mut row = [0.0; 6];
            for k in 0..3 {
                row[3 * r + k] = g[c][k];
            }
            row
        };
        let b: [[f64; 6]; 4] = [b_row(0), b_row(1), b_row(2), b_row(3)];
        let mut hb = [[0.0; 6]; 4];
        for m in 0..4 {
            for k in 0..6 {
                hb[m][k] = (0..4).map(|l| h[m][l] * b[l][k]).sum();
            }
        }
        let mut out = [[0.0; 6]; 6];
        for i in 0..6 {
            for k in 0..6 {
                out[i][k] = (0..4).map(|m| b[m][i] * hb[m][k]).sum();
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Extending the operators of some triangles by more gives exactly the operators of all
    /// of them, a triangle with coincident corners (whose frame uses the mean edge) included.
    #[test]
    fn extended_operators_equal_the_operators_of_all_triangles() {
        let mut seed = 99u64;
        let mut rand = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut positions: Vec<[f64; 3]> = (0..9).map(|_| [rand(), rand(), rand()]).collect();
        positions.push(positions[0]);
        positions.push(positions[0]);
        let mut tris: Vec<[u32; 3]> = (0..7u32).map(|i| [i, i + 1, i + 2]).collect();
        tris.insert(2, [0, 9, 10]);
        for n in [0, 1, 3, tris.len()] {
            let all = TriangleOperators::new(&positions, &tris);
            let ext = TriangleOperators::new(&positions, &tris[..n]).extended(&positions, &tris);
            assert_eq!(all.grad, ext.grad, "{n}");
            assert_eq!(all.area, ext.area, "{n}");
            assert_eq!(all.total_area, ext.total_area, "{n}");
        }
    }

    /// A known affine map A applied to a triangle has Jacobian A in every layout.
    #[test]
    fn the_jacobian_of_an_affine_map_is_its_linear_part() {
        let a = [[1.7, -0.4], [0.3, 0.8]];
        let q = [[0.2, -0.1], [1.5, 0.3], [0.4, 1.1]];
        let map = |p: [f64; 2]| [a[0][0] * p[0] + a[0][1] * p[1] + 3.0, a[1][0] * p[0] + a[1][1] * p[1] - 2.0];
        let uv: Vec<[f64; 2]> = q.iter().map(|&p| map(p)).collect();
        let ops = TriangleOperators::planar(&q, &[[0, 1, 2]]);
        let j = ops.jacobian(0, &[0, 1, 2], &uv);
        for r in 0..2 {
            for c in 0..2 {
                assert!((j[r][c] - a[r][c]).abs() < 1e-12, "{j:?}");
            }
        }
        assert!((ops.area[0] - 0.5 * ((1.3 * 1.2) - (0.4 * 0.2))).abs() < 1e-12);
        // The same triangle in 3D (z = 0) in either 3D layout: the rest frame differs from the
        // plane's by a rotation, so J Jᵀ (the metric of the map, frame-independent) agrees.
        let p: Vec<[f64; 3]> = q.iter().map(|z| [z[0], z[1], 0.0]).collect();
        let mm = |j: Jacobian| [j[0][0] * j[0][0] + j[0][1] * j[0][1], j[0][0] * j[1][0] + j[0][1] * j[1][1], j[1][0] * j[1][0] + j[1][1] * j[1][1]];
        let want = mm(a);
        for ops in [TriangleOperators::new(&p, &[[0, 1, 2]]), TriangleOperators::local_frames(&p, &[[0, 1, 2]])] {
            let got = mm(ops.jacobian(0, &[0, 1, 2], &uv));
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-12, "{got:?} vs {want:?}");
            }
            assert!((ops.area[0] - triangle_area([p[0], p[1], p[2]])).abs() < 1e-12);
            // Stiffness rows sum to zero (constants are in the kernel).
            for row in ops.stiffness(0) {
                assert!(row.iter().sum::<f64>().abs() < 1e-12);
            }
        }
    }

    #[test]
    fn pulled_back_derivatives_match_the_chain_rule() {
        // f(J) = Σ c_m J_m (linear): the pulled gradient is ∂f/∂x, exactly.
        let q = [[0.0, 0.0], [1.0, 0.2], [0.3, 0.9]];
        let ops = TriangleOperators::planar(&q, &[[0, 1, 2]]);
        let c = [0.7, -1.1, 0.4, 2.0];
        let x = [[0.1, 0.2], [1.3, -0.4], [0.5, 0.8]];
        let f = |x: [[f64; 2]; 3]| flat(ops.jacobian_of(0, x)).iter().zip(c).map(|(a, b)| a * b).sum::<f64>();
        let g = ops.pull_gradient(0, c);
        for k in 0..6 {
            let mut xp = x;
            xp[k % 3][k / 3] += 1.0;
            assert!((f(xp) - f(x) - g[k]).abs() < 1e-12);
        }
        // Bᵀ I B is the stiffness on each component.
        let id = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        let h = ops.pull_hessian(0, &id);
        let l = ops.stiffness(0);
        for a in 0..3 {
            for b in 0..3 {
                assert!((h[a][b] - l[a][b]).abs() < 1e-12 && (h[3 + a][3 + b] - l[a][b]).abs() < 1e-12);
                assert!(h[a][3 + b].abs() < 1e-12);
            }
        }
    }

    #[test]
    fn degenerate_triangles_get_a_thin_but_valid_rest_shape() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let ops = TriangleOperators::new(&p, &[[0, 1, 2]]);
        assert!(ops.area[0] > 0.0 && ops.grad[0].iter().flatten().all(|x| x.is_finite()));
        // In their own frames too: the same thin shape, so a barrier still holds it.
        let local = TriangleOperators::local_frames(&p, &[[0, 1, 2]]);
        assert_eq!((local.area[0], local.grad[0]), (ops.area[0], ops.grad[0]));
        // Two coincident corners beside an ordinary triangle: ordinary stays exact.
        let q = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
        let local = TriangleOperators::local_frames(&q, &[[0, 1, 2], [0, 3, 1]]);
        assert!((local.area[0] - 0.5).abs() < 1e-15);
        assert!(local.area[1] > 0.0 && local.grad[1].iter().flatten().all(|x| x.is_finite()));
        assert!(!TriangleOperators::planar_is_valid([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]));
        let w = TriangleOperators::planar(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], &[[0, 1, 2]]).weighted(&[0.5]);
        assert!((w.total_area - 0.25).abs() < 1e-15);
    }
}
