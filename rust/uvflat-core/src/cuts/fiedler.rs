//! The Fiedler vector of a chart: the smoothest non-constant function on its surface.
//!
//! Precedent: spectral partitioning (Fiedler 1973; Pothen, Simon & Liou 1990) and its use for
//! mesh segmentation (Liu & Zhang 2004; Lévy 2006, "Laplace–Beltrami eigenfunctions"): the
//! second eigenfunction `f` of `L f = λ M f` — `L` the cotangent Laplacian (Neumann on the
//! chart's boundary), `M` the lumped mass matrix (a third of each triangle's area at each of
//! its corners) — varies along the chart's longest intrinsic direction (along a tube, around
//! a U bend), so its level sets are smooth loops or paths across the chart, and the level that
//! halves the area is a natural place to split it.
//!
//! Computation: inverse iteration on the shifted pencil, `(L + σM) y = M x`, with `x` kept
//! `M`-orthogonal to the constants (the eigenvector of `λ = 0`) and of unit `M`-norm;
//! `σ = 10⁻⁸ · tr L / tr M` is far below `λ₂` for any mesh resolution and makes the matrix
//! definite. One symbolic (in the chart's shared vertex order, [`Chart::vertex_order`]) and
//! one numeric sparse Cholesky factorization (faer), then
//! [`MIN_ITERATIONS`] to [`MAX_ITERATIONS`] solves. The start mixes the vertices' coordinates
//! on the chart's principal axes with a fixed hash of the vertex ids (see `start_vector`),
//! already close to `f` on elongated charts and never blind to it. Where `λ₂` is repeated (a
//! round sphere) the iteration converges to some function of that eigenspace: still smooth,
//! which is all a split needs.
//!
//! Preconditions: a connected chart (charts are). Degenerate triangles are safe (clamped
//! angles keep `L` positive semi-definite; a small diagonal term is added).
//!
//! Failures: `None` when the chart has fewer than 3 vertices or no area, the factorization
//! fails, or a value is not finite; the caller falls back to a planar split. Deterministic:
//! no randomness, sums in a fixed order.

use faer::sparse::SparseColMat;

use crate::charts::Chart;
use crate::geometry::triangle_area;

/// Most inverse-iteration solves.
pub const MAX_ITERATIONS: usize = 40;
/// Fewest solves (a component of the start along `f` that is small grows by `λ₃/λ₂` a solve).
pub const MIN_ITERATIONS: usize = 10;
/// Stop when the `M`-norm change of the normalised iterate is below this.
const TOLERANCE: f64 = 1e-7;

/// The Fiedler vector of `chart` (one value per chart vertex), or `None` (see the module docs).
pub fn fiedler_vector(chart: &Chart) -> Option<Vec<f64>> {
    let n = chart.positions.len();
    if n < 3 || chart.triangles.is_empty() {
        return None;
    }
    // Lower triangle of L (row ≥ col) and the lumped mass.
    let (entries, _) = super::cones::cotan_laplacian(chart);
    let mut mass = vec![0.0f64; n];
    for t in &chart.triangles {
        let area = triangle_area([chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]]);
        for &v in t {
            mass[v as usize] += area / 3.0;
        }
    }
    let total_mass: f64 = mass.iter().sum();
    if !(total_mass > 0.0 && total_mass.is_finite()) {
        return None;
    }
    // A vertex whose triangles all have zero area still gets a little mass.
    let floor = 1e-12 * total_mass / n as f64;
    for m in &mut mass {
        *m = m.max(floor);
    }
    let total_mass: f64 = mass.iter().sum();
    let trace_l: f64 = entries.iter().filter(|e| e.0 == e.1).map(|e| e.2).sum();
    let sigma = 1e-8 * trace_l.max(1e-300) / total_mass;
    let eps = 1e-12 * trace_l.max(1e-300) / n as f64;
    // Analysed in the chart's shared vertex order (the cone system's, when the chart was cut).
    let (symbolic, argsort, llt) = super::cones::analyse_in_vertex_order(chart, &entries)?;
    let values: Vec<f64> =
        entries.iter().map(|e| if e.0 == e.1 { e.2 + sigma * mass[e.0 as usize] + eps } else { e.2 }).collect();
    let mat = SparseColMat::new_from_argsort(symbolic, &argsort, &values).ok()?;
    let factor = super::cones::Factor::new(&llt, &mat)?;
    drop((mat, values, entries));

    let mut x = start_vector(chart, &mass);
    if !normalise(&mut x, &mass) {
        return None;
    }
    for it in 0..MAX_ITERATIONS {
        let mut y: Vec<f64> = (0..n).map(|i| mass[i] * x[i]).collect();
        factor.solve_columns_in_place(&llt, &mut y, 1);
        if !normalise(&mut y, &mass) {
            return None;
        }
        let change: f64 = (0..n).map(|i| mass[i] * (y[i] - x[i]) * (y[i] - x[i])).sum::<f64>().sqrt();
        x = y;
        if it + 1 >= MIN_ITERATIONS && change < TOLERANCE {
            break;
        }
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Remove the `M`-weighted mean and scale to unit `M`-norm; `false` if nothing is left.
fn normalise(x: &mut [f64], mass: &[f64]) -> bool {
    let total: f64 = mass.iter().sum();
    let mean = x.iter().zip(mass).map(|(a, m)| a * m).sum::<f64>() / total;
    for a in x.iter_mut() {
        *a -= mean;
    }
    let norm = x.iter().zip(mass).map(|(a, m)| a * a * m).sum::<f64>().sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return false;
    }
    // Relative to the chart: a vector of pure round-off is no direction.
    let scale = x.iter().fold(0.0f64, |s, a| s.max(a.abs()));
    if !(norm > 1e-13 * scale * total.sqrt()) {
        return false;
    }
    for a in x.iter_mut() {
        *a /= norm;
    }
    true
}

/// The start of the iteration: the vertices' coordinates on the chart's three principal axes
/// (mass-weighted covariance; power iteration with deflation from fixed starts) weighted 1,
/// ½, ¼, plus 1% of a fixed hash of the vertex id. The mix matters on symmetric charts: one
/// coordinate alone can be even under a mirror of the chart while the Fiedler vector is odd
/// (a hairpin tube), and inverse iteration never leaves the symmetry class it starts in.
fn start_vector(chart: &Chart, mass: &[f64]) -> Vec<f64> {
    let total: f64 = mass.iter().sum();
    let mut mean = [0.0; 3];
    for (p, m) in chart.positions.iter().zip(mass) {
        for k in 0..3 {
            mean[k] += p[k] * m / total;
        }
    }
    let mut cov = [[0.0f64; 3]; 3];
    for (p, m) in chart.positions.iter().zip(mass) {
        let d = [p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += m * d[i] * d[j];
            }
        }
    }
    let mut axes: Vec<[f64; 3]> = Vec::with_capacity(3);
    for start in [[1.0, 0.7, 0.3], [0.3, 1.0, 0.7], [0.7, 0.3, 1.0]] {
        let mut axis = start;
        for _ in 0..64 {
            let mut next = [
                cov[0][0] * axis[0] + cov[0][1] * axis[1] + cov[0][2] * axis[2],
                cov[1][0] * axis[0] + cov[1][1] * axis[1] + cov[1][2] * axis[2],
                cov[2][0] * axis[0] + cov[2][1] * axis[1] + cov[2][2] * axis[2],
            ];
            // Deflate the axes found so far.
            for a in &axes {
                let d = next[0] * a[0] + next[1] * a[1] + next[2] * a[2];
                for k in 0..3 {
                    next[k] -= d * a[k];
                }
            }
            let l = (next[0] * next[0] + next[1] * next[1] + next[2] * next[2]).sqrt();
            if !(l > 1e-300 && l.is_finite()) {
                break;
            }
            axis = [next[0] / l, next[1] / l, next[2] / l];
        }
        axes.push(axis);
    }
    let coord = |p: &[f64; 3], a: &[f64; 3]| (p[0] - mean[0]) * a[0] + (p[1] - mean[1]) * a[1] + (p[2] - mean[2]) * a[2];
    let mut x: Vec<f64> = chart
        .positions
        .iter()
        .map(|p| coord(p, &axes[0]) + 0.5 * coord(p, &axes[1]) + 0.25 * coord(p, &axes[2]))
        .collect();
    let range = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let range = if range > 0.0 && range.is_finite() { range } else { 1.0 };
    for (v, a) in x.iter_mut().enumerate() {
        *a += 0.01 * range * hash_unit(v as u64);
    }
    x
}

/// A fixed pseudo-random number in `[−1, 1)` for `v` (SplitMix64's finaliser).
fn hash_unit(v: u64) -> f64 {
    let mut z = v.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
