//! The ABF problem of one chart: the constraint rows (angle sums and wheel conditions per
//! vertex, the triangle sums implied per face), the energy weights, and the evaluation of the
//! Lagrangian's gradient and (diagonal) Hessian at a state of angles and multipliers
//! (Sheffer & de Sturler 2001, with the log form of the wheel condition of ABF++,
//! Sheffer et al. 2005).
//!
//! Preconditions: a chart with triangles and at least one boundary vertex. Failures: none
//! here; a state with non-finite values evaluates to non-finite residuals, which the Newton
//! iteration reports.

use super::*;

/// One vertex constraint row: (vertex, wheel?) — the sum row when `wheel` is false.
#[derive(Clone, Copy)]
pub(super) struct Row {
    pub(super) vertex: u32,
    pub(super) wheel: bool,
    /// A sum row that is the inequality "sum ≤ target" (convex boundary), by a slack.
    pub(super) ineq: bool,
}

/// Most constraint rows touching one triangle (sum and wheel rows of its three vertices).
pub(super) const MAX_FACE_ROWS: usize = 6;

/// Constraint rows touching one triangle: (row, kind wheel?, local corner of the vertex).
#[derive(Clone, Copy, Default)]
pub(super) struct FaceRows {
    pub(super) len: u8,
    pub(super) rows: [(u32, bool, u8); MAX_FACE_ROWS],
}

/// The rows' gradient on the triangle's three corners: the sum row of corner k is `e_k`; the
/// wheel row of corner k, `log sin α_{k+2} − log sin α_{k+1}`, has `−cot α_{k+1}` at k+1
/// and `cot α_{k+2}` at k+2.
///
/// Written out per case so that the whole array is built at once: storing single entries at
/// computed positions and then reading the array as a vector stalls the processor's store
/// forwarding in the hot loops of the Newton step.
#[inline]
pub(super) fn row_grad(wheel: bool, k: usize, cot: &[f64; 3]) -> [f64; 3] {
    match (wheel, k) {
        (false, 0) => [1.0, 0.0, 0.0],
        (false, 1) => [0.0, 1.0, 0.0],
        (false, _) => [0.0, 0.0, 1.0],
        (true, 0) => [0.0, -cot[1], cot[2]],
        (true, 1) => [cot[0], 0.0, -cot[2]],
        (true, _) => [-cot[0], cot[1], 0.0],
    }
}

/// Below this many triangles a chart's per-triangle loops run sequentially (charts themselves
/// run in parallel).
pub(super) const PAR_MIN_FACES: usize = 4096;
/// Triangles per parallel work item.
pub(super) const PAR_CHUNK: usize = 1024;

/// Run `f(face, item)` over per-face items, in parallel for large charts, and return the
/// largest value it returns (at least 0; order-independent, so the same in parallel).
pub(super) fn for_faces_max<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) -> f64 + Sync + Send) -> f64 {
    use rayon::prelude::*;
    if items.len() < PAR_MIN_FACES {
        items.iter_mut().enumerate().fold(0.0f64, |m, (i, x)| m.max(f(i, x)))
    } else {
        items.par_iter_mut().with_min_len(PAR_CHUNK).enumerate().map(|(i, x)| f(i, x)).reduce(|| 0.0f64, f64::max)
    }
}

/// Run `f(face, item)` over per-face items, in parallel for large charts.
pub(super) fn for_faces<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) + Sync + Send) {
    use rayon::prelude::*;
    if items.len() < PAR_MIN_FACES {
        items.iter_mut().enumerate().for_each(|(i, x)| f(i, x));
    } else {
        items.par_iter_mut().with_min_len(PAR_CHUNK).enumerate().for_each(|(i, x)| f(i, x));
    }
}

pub(super) struct Problem<'a> {
    pub(super) tris: &'a [[u32; 3]],
    /// Target angle per corner; the energy weight is `1/β²`, computed where used.
    pub(super) beta: Vec<f64>,
    pub(super) rows: Vec<Row>,
    /// Sum target per row (2π interior, π active boundary; unused for wheel rows).
    pub(super) target: Vec<f64>,
    /// Sum row and wheel row of every vertex (`u32::MAX` for none): each triangle's
    /// [`FaceRows`] follow ([`Problem::face_rows`]), so they are not stored per triangle.
    pub(super) sum_row: Vec<u32>,
    pub(super) wheel_row: Vec<u32>,
    /// Reduced ABF++ matrix pattern, upper triangle by columns (the lower triangle by rows):
    /// column `j` holds rows `row_idx[col_ptr[j]..col_ptr[j + 1]]`, ascending, all ≤ j.
    /// 32-bit indices (half the memory of `usize`, in the symbolic factorization too): charts
    /// beyond about 400 million triangles are refused ([`Reduced::new`]).
    pub(super) col_ptr: Vec<u32>,
    pub(super) row_idx: Vec<u32>,
    /// Per triangle, for each pair (i, j ≤ i) of its rows in order, the offset of its entry in
    /// its column of `row_idx` ([`SLOT_SEARCH`]: look it up, see [`Problem::slot`]); triangle
    /// `f`'s pairs start at `slot_start[f]`.
    pub(super) slots: Vec<u8>,
    pub(super) slot_start: Vec<u32>,
    /// Whether any row is an inequality (interior-point iteration).
    pub(super) has_ineq: bool,
    /// Lower bound of every angle (interior-point iteration), or 0 for none.
    pub(super) lower: f64,
    /// The chart's shared vertex elimination order ([`crate::charts::Chart::vertex_order`]),
    /// from which the reduced system's ordering is taken when it would be AMD.
    pub(super) vertex_order: Option<&'a [u32]>,
}

impl<'a> Problem<'a> {
    /// `sum_target[v]`: the angle sum vertex `v` must reach (2π at interior vertices unless
    /// prescribed, any prescribed value, the convex cap at outer-loop vertices), or `None`;
    /// `ineq[v]`: the sum of `v` need only stay at or below its target.
    pub(super) fn new(tris: &'a [[u32; 3]], beta: Vec<f64>, interior: &[bool], sum_target: &[Option<f64>], ineq: &[bool]) -> Self {
        let n = interior.len();
        let mut sum_row = vec![u32::MAX; n];
        let mut wheel_row = vec![u32::MAX; n];
        let mut rows = Vec::new();
        let mut target = Vec::new();
        for v in 0..n {
            if let Some(t) = sum_target[v] {
                sum_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: false, ineq: ineq[v] });
                target.push(t);
            }
            if interior[v] {
                wheel_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: true, ineq: false });
                target.push(0.0);
            }
        }
        let m = rows.len();
        let (col_ptr, row_idx, slots, slot_start) = reduced_pattern(m, tris.len(), |f| face_rows_of(&tris[f], &sum_row, &wheel_row));
        let has_ineq = rows.iter().any(|r| r.ineq);
        Problem { tris, beta, rows, target, sum_row, wheel_row, col_ptr, row_idx, slots, slot_start, has_ineq, lower: 0.0, vertex_order: None }
    }

    /// The constraint rows touching triangle `f`.
    #[inline]
    pub(super) fn face_rows(&self, f: usize) -> FaceRows {
        face_rows_of(&self.tris[f], &self.sum_row, &self.wheel_row)
    }

    pub(super) fn m(&self) -> usize {
        self.rows.len()
    }

    /// Index in `row_idx` of the entry (`a`, `b`) (rows of one triangle, either order) whose
    /// stored slot offset is `offset` ([`Problem::slots`]).
    #[inline]
    pub(super) fn slot(&self, a: u32, b: u32, offset: u8) -> usize {
        let (r, c) = (a.max(b) as usize, a.min(b));
        let start = self.col_ptr[r] as usize;
        if offset != SLOT_SEARCH {
            return start + offset as usize;
        }
        let seg = &self.row_idx[start..self.col_ptr[r + 1] as usize];
        start + seg.binary_search(&c).expect("entry in pattern")
    }

    /// Index in `row_idx` of the diagonal entry of row `r` (the last of its column).
    pub(super) fn diagonal_slot(&self, r: usize) -> usize {
        self.col_ptr[r + 1] as usize - 1
    }
}

/// The rows of a triangle's vertices, in corner order (sum row before wheel row).
#[inline]
fn face_rows_of(t: &[u32; 3], sum_row: &[u32], wheel_row: &[u32]) -> FaceRows {
    let mut fr = FaceRows::default();
    for k in 0..3 {
        let v = t[k] as usize;
        for (r, wheel) in [(sum_row[v], false), (wheel_row[v], true)] {
            if r != u32::MAX {
                fr.rows[fr.len as usize] = (r, wheel, k as u8);
                fr.len += 1;
            }
        }
    }
    fr
}

/// Newton state: angles and multipliers (vertex multipliers per vertex so that they survive a
/// change of the constraint set).
#[derive(Clone)]
pub(super) struct State {
    pub(super) alpha: Vec<f64>,
    pub(super) lam_tri: Vec<f64>,
    pub(super) lam_sum: Vec<f64>,
    pub(super) lam_wheel: Vec<f64>,
    /// Slack of every inequality sum row, per vertex (sum + slack = target, slack > 0); the
    /// row's multiplier `lam_sum` is then its dual variable, > 0.
    pub(super) slack: Vec<f64>,
    /// Barrier parameter: the target of every product slack × multiplier.
    pub(super) mu: f64,
    /// Multiplier of every corner's lower bound `α ≥ lower` (empty without bounds).
    pub(super) z_lo: Vec<f64>,
}

/// Residual and Newton ingredients of one triangle at the current state.
#[derive(Clone, Copy, Default)]
pub(super) struct FaceEval {
    pub(super) cot: [f64; 3],
    /// ∂L/∂α per corner.
    pub(super) grad: [f64; 3],
    /// Diagonal Hessian of L in α per corner (see [`evaluate`]).
    pub(super) hess: [f64; 3],
    /// Triangle residual: angle sum − π.
    pub(super) c_tri: f64,
    /// log sin α per corner (the wheel rows' residual terms).
    pub(super) log_sin: [f64; 3],
}

/// Residuals and Newton ingredients at the current state.
pub(super) struct Eval {
    pub(super) faces: Vec<FaceEval>,
    /// Right-hand side residual of the Newton system per row: `c_row`, except on inequality
    /// rows `sum − target + μ/λ` (the slack eliminated through its complementarity equation).
    pub(super) c_newton: Vec<f64>,
    /// Per row, `slack/λ` on inequality rows (the eliminated slack's diagonal), else 0; empty
    /// without inequality rows.
    pub(super) diag: Vec<f64>,
    pub(super) residual: f64,
    pub(super) stationarity: f64,
    /// Largest product slack × multiplier of the inequality rows (0 without).
    pub(super) complementarity: f64,
}

/// Residuals, Lagrangian gradient and Hessian at the state.
///
/// The Hessian of the Lagrangian in α is diagonal: `2/β² ∓ λ_wheel / sin²α` (log-sine wheel
/// rows). It is used exactly where the triangle's projected Hessian (on angle changes that
/// keep its sum) is positive definite — all three entries positive, or exactly one negative
/// with `Σ 1/h < 0` (with a margin) — which keeps the reduced ABF++ matrix positive definite
/// and gives Newton's quadratic convergence; other triangles use the energy's `2/β²`.
pub(super) fn evaluate(p: &Problem<'_>, s: &State) -> Eval {
    let mut e = Eval { faces: Vec::new(), c_newton: Vec::new(), diag: Vec::new(), residual: 0.0, stationarity: 0.0, complementarity: 0.0 };
    evaluate_into(p, s, &mut e);
    e
}

/// [`evaluate`] into `e`, reusing its per-triangle buffer (one evaluation alive at a time).
pub(super) fn evaluate_into(p: &Problem<'_>, s: &State, e: &mut Eval) {
    let nf = p.tris.len();
    let mut faces = std::mem::take(&mut e.faces);
    faces.clear();
    faces.resize(nf, FaceEval::default());
    // The largest scaled gradient is reduced in the loop, not stored per triangle.
    let stationarity = for_faces_max(&mut faces, |f, fe| {
        let a = [s.alpha[3 * f], s.alpha[3 * f + 1], s.alpha[3 * f + 2]];
        let mut sn = [0.0; 3];
        let mut ct = [0.0; 3];
        let mut ls = [0.0; 3];
        for k in 0..3 {
            let (si, co) = a[k].sin_cos();
            sn[k] = si;
            ct[k] = co / si;
            ls[k] = si.ln();
        }
        let mut grad = [0.0; 3];
        let mut hess = [0.0; 3];
        let mut energy_hess = [0.0; 3];
        for k in 0..3 {
            let c = 3 * f + k;
            let w = 1.0 / (p.beta[c] * p.beta[c]);
            grad[k] = 2.0 * w * (a[k] - p.beta[c]) + s.lam_tri[f];
            energy_hess[k] = 2.0 * w;
            hess[k] = energy_hess[k];
        }
        let fr = p.face_rows(f);
        for &(_, wheel, k) in &fr.rows[..fr.len as usize] {
            let k = k as usize;
            let v = p.tris[f][k] as usize;
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            if wheel {
                let l = s.lam_wheel[v];
                grad[k1] -= l * ct[k1];
                grad[k2] += l * ct[k2];
                hess[k1] += l / (sn[k1] * sn[k1]);
                hess[k2] -= l / (sn[k2] * sn[k2]);
            } else {
                grad[k] += s.lam_sum[v];
            }
        }
        let mut stat: f64 = 0.0;
        let mut fallback_hess = energy_hess;
        if p.lower > 0.0 {
            // Lower bounds α ≥ lower, primal-dual: the bound's multiplier z enters the
            // gradient as −z; the Newton system, with dz eliminated through z (α − lower) = μ,
            // sees the Hessian + z/(α − lower) and the gradient with −μ/(α − lower) for −z.
            for k in 0..3 {
                let c = 3 * f + k;
                let gap = a[k] - p.lower;
                let z = s.z_lo[c];
                stat = stat.max((grad[k] - z).abs() / energy_hess[k]);
                hess[k] += z / gap;
                fallback_hess[k] += z / gap;
                grad[k] -= s.mu / gap;
            }
        } else {
            for k in 0..3 {
                stat = stat.max(grad[k].abs() / energy_hess[k]);
            }
        }
        // Exact Hessian where the triangle's projected Hessian is safely positive definite.
        let neg = hess.iter().filter(|&&h| h <= 0.0).count();
        let exact_ok = neg == 0 || {
            let inv = [1.0 / hess[0], 1.0 / hess[1], 1.0 / hess[2]];
            let largest = inv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            neg == 1 && inv.iter().all(|x| x.is_finite()) && inv[0] + inv[1] + inv[2] < -PROJECTED_HESSIAN_MARGIN * largest
        };
        if !exact_ok {
            hess = fallback_hess;
        }
        fe.cot = ct;
        fe.log_sin = ls;
        fe.grad = grad;
        fe.hess = hess;
        fe.c_tri = a[0] + a[1] + a[2] - PI;
        stat
    });
    let mut c_row: Vec<f64> = p.rows.iter().zip(&p.target).map(|(row, t)| if row.wheel { 0.0 } else { -t }).collect();
    for (f, fe) in faces.iter().enumerate() {
        let fr = p.face_rows(f);
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let k = k as usize;
            // The row's term of this triangle: log sin α_{k+2} − log sin α_{k+1}, or α_k.
            let term = if wheel { fe.log_sin[(k + 2) % 3] - fe.log_sin[(k + 1) % 3] } else { s.alpha[3 * f + k] };
            c_row[r as usize] += term;
        }
    }
    let mut complementarity: f64 = 0.0;
    if p.lower > 0.0 {
        for (a, z) in s.alpha.iter().zip(&s.z_lo) {
            complementarity = complementarity.max(z * (a - p.lower));
        }
    }
    let (mut c_newton, mut diag) = (Vec::new(), Vec::new());
    if p.has_ineq {
        c_newton = c_row.clone();
        diag = vec![0.0; c_row.len()];
        for (r, row) in p.rows.iter().enumerate() {
            if row.ineq {
                let v = row.vertex as usize;
                let (sl, z) = (s.slack[v], s.lam_sum[v]);
                c_newton[r] = c_row[r] + s.mu / z;
                c_row[r] += sl;
                diag[r] = sl / z;
                complementarity = complementarity.max(sl * z);
            }
        }
    }
    let residual = faces.iter().map(|fe| fe.c_tri).chain(c_row.iter().copied()).fold(0.0f64, |m, x| m.max(x.abs()));
    if !p.has_ineq {
        c_newton = c_row;
    }
    *e = Eval { faces, c_newton, diag, residual, stationarity, complementarity };
}

/// The triangles of an `n × n` grid of vertices, two per cell (for the module tests).
#[cfg(test)]
pub(super) fn grid_triangles(n: u32) -> Vec<[u32; 3]> {
    let id = |i: u32, j: u32| i * n + j;
    let mut tris = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            tris.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5 × 5 grid of vertices, two triangles per cell: 9 interior vertices.
    fn grid() -> (Vec<[u32; 3]>, Vec<bool>) {
        let n = 5u32;
        let tris = grid_triangles(n);
        let interior = (0..n * n).map(|v| (1..n - 1).contains(&(v / n)) && (1..n - 1).contains(&(v % n))).collect();
        (tris, interior)
    }

    /// A deterministic pseudo-random number in [−1, 1).
    fn noise(k: usize) -> f64 {
        let x = (k as u64 + 1).wrapping_mul(0x9e3779b97f4a7c15) >> 11;
        2.0 * (x as f64 / (1u64 << 53) as f64) - 1.0
    }

    fn state(tris: &[[u32; 3]], n: usize, seed: usize, beta: &[f64]) -> State {
        State {
            alpha: beta.iter().enumerate().map(|(c, b)| b + 0.05 * noise(seed + c)).collect(),
            lam_tri: (0..tris.len()).map(|f| 0.3 * noise(seed + 1000 + f)).collect(),
            lam_sum: (0..n).map(|v| 0.3 * noise(seed + 2000 + v)).collect(),
            lam_wheel: (0..n).map(|v| 0.3 * noise(seed + 3000 + v)).collect(),
            slack: vec![0.0; n],
            mu: 0.0,
            z_lo: Vec::new(),
        }
    }

    /// Every triangle's stored slot offsets locate the entries of its pairs of rows, also
    /// where a column is too long for a one-byte offset (an interior vertex of valence 200,
    /// numbered last so that its columns hold the rows of all its neighbours).
    #[test]
    fn slots_locate_every_pair_also_in_long_columns() {
        let k = 200u32;
        // Ring 1 (interior): 0..k, ring 2 (boundary): k..2k, centre: 2k.
        let centre = 2 * k;
        let mut tris = Vec::new();
        for i in 0..k {
            let j = (i + 1) % k;
            tris.push([centre, i, j]);
            tris.push([i, k + i, k + j]);
            tris.push([i, k + j, j]);
        }
        let n = (2 * k + 1) as usize;
        let interior: Vec<bool> = (0..n as u32).map(|v| v < k || v == centre).collect();
        let sum_target: Vec<Option<f64>> = interior.iter().map(|&i| i.then_some(2.0 * PI)).collect();
        let p = Problem::new(&tris, vec![PI / 3.0; 3 * tris.len()], &interior, &sum_target, &vec![false; n]);
        let mut searched = 0;
        for f in 0..tris.len() {
            let fr = p.face_rows(f);
            let slots = &p.slots[p.slot_start[f] as usize..p.slot_start[f + 1] as usize];
            let mut q = 0;
            for i in 0..fr.len as usize {
                for j in 0..=i {
                    let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                    let slot = p.slot(a, b, slots[q]);
                    let col = a.max(b) as usize;
                    assert!((p.col_ptr[col] as usize..p.col_ptr[col + 1] as usize).contains(&slot), "triangle {f} pair ({a}, {b}): slot outside column {col}");
                    assert_eq!(p.row_idx[slot], a.min(b), "triangle {f} pair ({a}, {b})");
                    searched += (slots[q] == SLOT_SEARCH) as usize;
                    q += 1;
                }
            }
            assert_eq!(q, slots.len());
        }
        assert!(searched > 0, "no column long enough to need the search");
    }

    #[test]
    fn face_rows_residuals_and_buffer_reuse() {
        let (tris, interior) = grid();
        let n = interior.len();
        // Targets: the right isosceles grid angles, perturbed; a prescribed sum at one
        // boundary vertex (π, a straight boundary there).
        let beta: Vec<f64> = tris.iter().flat_map(|_| [PI / 4.0, PI / 2.0, PI / 4.0]).enumerate().map(|(c, b)| b * (1.0 + 0.1 * noise(c))).collect();
        let sum_target: Vec<Option<f64>> = (0..n).map(|v| if interior[v] { Some(2.0 * PI) } else if v == 2 { Some(PI) } else { None }).collect();
        let p = Problem::new(&tris, beta.clone(), &interior, &sum_target, &vec![false; n]);
        // Every triangle's rows are those of its vertices, sum row before wheel row.
        for (f, t) in tris.iter().enumerate() {
            let fr = p.face_rows(f);
            let mut expected = Vec::new();
            for k in 0..3 {
                let v = t[k] as usize;
                for (r, row) in p.rows.iter().enumerate() {
                    if row.vertex as usize == v {
                        expected.push((r as u32, row.wheel, k as u8));
                    }
                }
            }
            assert_eq!(&fr.rows[..fr.len as usize], &expected[..], "triangle {f}");
        }
        // The row residuals follow the constraint definitions.
        let s = state(&tris, n, 7, &beta);
        let e = evaluate(&p, &s);
        for (r, row) in p.rows.iter().enumerate() {
            let v = row.vertex;
            let mut c = if row.wheel { 0.0 } else { -p.target[r] };
            for (f, t) in tris.iter().enumerate() {
                for k in 0..3 {
                    if t[k] == v {
                        let a = |q: usize| s.alpha[3 * f + q];
                        c += if row.wheel { a((k + 2) % 3).sin().ln() - a((k + 1) % 3).sin().ln() } else { a(k) };
                    }
                }
            }
            assert!((e.c_newton[r] - c).abs() < 1e-12, "row {r}: {} vs {c}", e.c_newton[r]);
        }
        for (f, fe) in e.faces.iter().enumerate() {
            let sum: f64 = s.alpha[3 * f..3 * f + 3].iter().sum();
            assert!((fe.c_tri - (sum - PI)).abs() < 1e-12);
        }
        // Evaluating into a buffer filled at another state gives the fresh evaluation, bit for bit.
        let mut reused = evaluate(&p, &state(&tris, n, 99, &beta));
        evaluate_into(&p, &s, &mut reused);
        assert_eq!(reused.residual.to_bits(), e.residual.to_bits());
        assert_eq!(reused.stationarity.to_bits(), e.stationarity.to_bits());
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&reused.c_newton), bits(&e.c_newton));
        for (a, b) in reused.faces.iter().zip(&e.faces) {
            for (x, y) in [(&a.cot, &b.cot), (&a.grad, &b.grad), (&a.hess, &b.hess), (&a.log_sin, &b.log_sin)] {
                assert_eq!(bits(x), bits(y));
            }
            assert_eq!(a.c_tri.to_bits(), b.c_tri.to_bits());
        }
    }
}
