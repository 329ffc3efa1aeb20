//! Least squares conformal maps.
//!
//! Paper: B. Lévy, S. Petitjean, N. Ray, J. Maillot, "Least Squares Conformal Maps for
//! Automatic Texture Atlas Generation", SIGGRAPH 2002. The energy equals that of Discrete
//! Conformal Parameterization (Desbrun, Meyer, Alliez 2002): ½ Σ cot|∇|² − signed UV area.
//!
//! The energy of a triangle depends only on its angles: with the largest angle at corner 2,
//! the map is conformal iff `w2 − w0 = q (w1 − w0)` with `q = (sin α1 / sin α2) e^{iα0}`, and
//! the triangle's LSCM energy is `|w2 − w0 − q (w1 − w0)|² · sin α2 / (2 sin α0 sin α1)`.
//! Assembling it from angles lets ABF drive the same solver with its solved angles, and makes
//! degenerate 3D triangles harmless (their clamped angles describe a thin valid triangle).
//!
//! Preconditions: a chart that is a disk (possibly with holes). Pins: with two or more pinned
//! vertices at distinct UVs, they are fixed exactly; with one, the automatic solution is
//! translated onto it. With none, the paper pins the two boundary vertices farthest apart
//! along the chart's longest bounding-box axis ([`auto_pins`]). That is what the
//! reconstruction of ABF's angles does ([`solve_with_angles`]), whose angles a planar map
//! nearly satisfies, and so do the starts of ARAP, SLIM and scaffold. The method itself
//! ([`solve`], and the start of MIPS, [`solve_free`]) does not: a pinned vertex is a point, and
//! a point has no capacity in the plane, so on a fine mesh the energy is lowest with the
//! chart crushed towards a point and stretched in a spike at each pin (a bunny subdivided
//! twice, one 81k-triangle chart: 52% of its area outside [½, 2] of its density, the 5th
//! percentile at 0.03). Its free map is fixed on the whole boundary instead: the smallest
//! eigenvector of the energy against the boundary mass (Mullen et al. 2008, as `spectral`'s,
//! [`super::boundary_eigen`]; 2% outside on that chart), moved by the similarity that puts the
//! two automatic pins where they would have been pinned.
//!
//! Failures: a singular system (chart of disconnected pieces or all-degenerate triangles).

use super::{chart_angles, ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::solvers::ordering::{Ordering, OrderingKind};
use crate::solvers::{FixedValueSolver, Symmetry};
use faer::c64;

/// Triplets of the LSCM quadratic form (twice the conformal energy E_D − A) over interleaved unknowns `[u0, v0, u1, v1, …]`
/// (size `2n`), assembled per triangle from corner angles. Symmetric positive semidefinite by
/// construction (a sum of squares); only the lower triangle (row ≥ column) is emitted, which
/// is all the symmetric solver reads.
pub fn conformal_triplets(triangles: &[[u32; 3]], angles: &[[f64; 3]]) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::with_capacity(triangles.len() * 36);
    for (t, a) in triangles.iter().zip(angles) {
        // Rotate labels so the largest angle is at position 2.
        let k = (0..3).max_by(|&i, &j| a[i].total_cmp(&a[j])).unwrap();
        let r = (k + 1) % 3; // new label 0
        let v = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        let al = [a[r], a[(r + 1) % 3], a[(r + 2) % 3]];
        let (s0, s1, s2) = (al[0].sin(), al[1].sin(), al[2].sin());
        let ratio = s1 / s2;
        let (qr, qi) = (ratio * al[0].cos(), ratio * al[0].sin());
        let w = s2 / (2.0 * s0 * s1);
        // Residual Σ c_k w_k with c0 = q − 1, c1 = −q, c2 = 1.
        let c = [(qr - 1.0, qi), (-qr, -qi), (1.0, 0.0)];
        for i in 0..3 {
            for j in 0..3 {
                let (ai, bi) = c[i];
                let (aj, bj) = c[j];
                let (ui, vi) = (2 * v[i], 2 * v[i] + 1);
                let (uj, vj) = (2 * v[j], 2 * v[j] + 1);
                // Rows: Re = Σ a u − b v, Im = Σ b u + a v.
                for (r, c, val) in [
                    (ui, uj, ai * aj + bi * bj),
                    (ui, vj, -ai * bj + bi * aj),
                    (vi, uj, -bi * aj + ai * bj),
                    (vi, vj, bi * bj + ai * aj),
                ] {
                    if r >= c {
                        out.push((r, c, w * val));
                    }
                }
            }
        }
    }
    out
}

/// The LSCM energy as a Hermitian form `w* H w` in `w = u + iv` (n × n, lower triangle only):
/// the same energy as [`conformal_triplets`] in half the dimension, which is what
/// [`LscmSolver`] factors.
pub fn conformal_hermitian(triangles: &[[u32; 3]], angles: &[[f64; 3]]) -> Vec<(u32, u32, c64)> {
    let mut out = Vec::with_capacity(triangles.len() * 6);
    for (t, a) in triangles.iter().zip(angles) {
        let k = (0..3).max_by(|&i, &j| a[i].total_cmp(&a[j])).unwrap();
        let r = (k + 1) % 3;
        let v = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        let al = [a[r], a[(r + 1) % 3], a[(r + 2) % 3]];
        let (s0, s1, s2) = (al[0].sin(), al[1].sin(), al[2].sin());
        let ratio = s1 / s2;
        let q = c64::new(ratio * al[0].cos(), ratio * al[0].sin());
        let w = s2 / (2.0 * s0 * s1);
        let c = [q - c64::new(1.0, 0.0), -q, c64::new(1.0, 0.0)];
        for i in 0..3 {
            for j in 0..3 {
                if v[i] >= v[j] {
                    // Row i, column j of Σ κ c̄ cᵀ.
                    out.push((v[i], v[j], c[i].conj() * c[j] * w));
                }
            }
        }
    }
    out
}

/// Two vertices to pin when the user pinned none: the boundary vertices (all vertices for a
/// chart without boundary) extremal along the longest axis of the chart's bounding box, with
/// UVs `(0, 0)` and `(d, 0)`, `d` their 3D distance. Ties go to the smaller mesh vertex.
pub fn auto_pins(chart: &Chart) -> [(u32, [f64; 2]); 2] {
    let mut cand: Vec<u32> = chart.boundary_loops.iter().flatten().copied().collect();
    if cand.len() < 2 {
        cand = (0..chart.positions.len() as u32).collect();
    }
    let p = &chart.positions;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in &cand {
        for d in 0..3 {
            lo[d] = lo[d].min(p[v as usize][d]);
            hi[d] = hi[d].max(p[v as usize][d]);
        }
    }
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap();
    let key = |v: &u32| (p[*v as usize][axis], chart.mesh_vertex[*v as usize], *v);
    let a = *cand.iter().min_by(|x, y| key(x).partial_cmp(&key(y)).unwrap()).unwrap();
    let mut b = *cand.iter().max_by(|x, y| {
        let (kx, ky) = (key(x), key(y));
        kx.0.total_cmp(&ky.0).then(ky.1.cmp(&kx.1)).then(ky.2.cmp(&kx.2))
    }).unwrap();
    if b == a {
        b = if a == cand[0] { cand[1] } else { cand[0] };
    }
    let d = crate::geometry::norm(crate::geometry::sub(p[b as usize], p[a as usize]));
    let d = if d > 0.0 { d } else { 1.0 };
    [(a, [0.0, 0.0]), (b, [d, 0.0])]
}

/// A factored LSCM system for one chart and one set of pinned vertices: solve again for new
/// pin positions without refactoring (live unwrap while dragging pins). Works on the complex
/// Hermitian form ([`conformal_hermitian`]).
pub struct LscmSolver {
    solver: FixedValueSolver<c64>,
    pinned: Vec<u32>,
    n: usize,
}

impl LscmSolver {
    /// Assemble and factor the LSCM system of `triangles` (over `n` vertices) with the given
    /// corner `angles` and `pinned` vertices (at least two, distinct).
    pub fn new(n: usize, triangles: &[[u32; 3]], angles: &[[f64; 3]], pinned: &[u32]) -> Result<Self, ChartFailure> {
        Self::with_ordering(n, triangles, angles, pinned, OrderingKind::Amd.into())
    }

    /// [`LscmSolver::new`] with the given ordering (a chart's shared one, see
    /// [`Chart::ordering`]).
    pub fn with_ordering(n: usize, triangles: &[[u32; 3]], angles: &[[f64; 3]], pinned: &[u32], ordering: Ordering<'_>) -> Result<Self, ChartFailure> {
        let trip = conformal_hermitian(triangles, angles);
        let solver = FixedValueSolver::with_ordering(n, &trip, pinned, Symmetry::Symmetric, ordering)?;
        Ok(LscmSolver { solver, pinned: pinned.to_vec(), n })
    }

    /// UVs for the pinned vertices at `pin_uvs` (same order as `pinned`).
    pub fn solve(&self, pin_uvs: &[[f64; 2]]) -> Result<Vec<[f64; 2]>, ChartFailure> {
        assert_eq!(pin_uvs.len(), self.pinned.len());
        let vals: Vec<c64> = pin_uvs.iter().map(|p| c64::new(p[0], p[1])).collect();
        let x = self.solver.solve(&[vals], &[])?;
        Ok((0..self.n).map(|i| [x[0][i].re, x[0][i].im]).collect())
    }
}

/// Whether pins span more than a point (two or more at distinct UVs).
pub(crate) fn pins_span(pins: &[(u32, [f64; 2])]) -> bool {
    pins.len() >= 2 && pins.iter().any(|p| p.1 != pins[0].1)
}

/// The chart of a method that takes no pins (`method`: spectral, bff) when its pins span more
/// than a point: LSCM with those pins held, the note saying so; `None` otherwise (the method
/// solves it and translates onto a single pin,
/// [`super::nonlinear::pins::translate_onto_single_pin`]).
pub(crate) fn instead_for_pins(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    method: &str,
) -> Option<Result<ChartSolution, ChartFailure>> {
    if !pins_span(pins) {
        return None;
    }
    let angles = chart_angles(&chart.positions, &chart.triangles);
    Some(solve_with_angles(chart, &angles, pins).map(|(uv, _)| {
        let mut s = ChartSolution::direct(uv);
        s.note = Some(format!("pinned chart: solved as LSCM with the pins ({method} takes no pins)"));
        s
    }))
}

/// LSCM of a chart driven by given corner angles (solved angles for ABF). Pins as described in
/// the module docs, two automatic ones when none span; the returned note says how they were
/// used. For angles nearly consistent with a planar map (ABF's) the two pins cost nothing;
/// for a surface's own angles see [`solve_free`].
pub fn solve_with_angles(
    chart: &Chart,
    angles: &[[f64; 3]],
    pins: &[(u32, [f64; 2])],
) -> Result<(Vec<[f64; 2]>, Option<String>), ChartFailure> {
    solve_pinned_or_free(chart, angles, pins, false)
}

/// [`solve_with_angles`] for a surface's own (3D) angles: without pins spanning more than a
/// point, the similarity of the free map is fixed on the boundary ([`free_map`]) instead of by
/// two pinned vertices, which on a fine mesh crush the chart (module docs); the result is then
/// moved so that the automatic pins land where they would have been pinned. Falls back to the
/// two pins when the free map cannot be computed.
pub fn solve_free(
    chart: &Chart,
    angles: &[[f64; 3]],
    pins: &[(u32, [f64; 2])],
) -> Result<(Vec<[f64; 2]>, Option<String>), ChartFailure> {
    solve_pinned_or_free(chart, angles, pins, true)
}

fn solve_pinned_or_free(
    chart: &Chart,
    angles: &[[f64; 3]],
    pins: &[(u32, [f64; 2])],
    free: bool,
) -> Result<(Vec<[f64; 2]>, Option<String>), ChartFailure> {
    let n = chart.positions.len();
    if pins_span(pins) {
        let pinned: Vec<u32> = pins.iter().map(|p| p.0).collect();
        let uvs: Vec<[f64; 2]> = pins.iter().map(|p| p.1).collect();
        let s = LscmSolver::with_ordering(n, &chart.triangles, angles, &pinned, chart.ordering_if_known(OrderingKind::Amd))?;
        return Ok((s.solve(&uvs)?, None));
    }
    let auto = auto_pins(chart);
    let mut uv = match free.then(|| free_map(chart, angles, auto)).flatten() {
        Some(uv) => uv,
        None => {
            let ordering = chart.ordering_if_known(OrderingKind::Amd);
            let s = LscmSolver::with_ordering(n, &chart.triangles, angles, &[auto[0].0, auto[1].0], ordering)?;
            s.solve(&[auto[0].1, auto[1].1])?
        }
    };
    let mut note = None;
    if !pins.is_empty() {
        super::nonlinear::pins::translate_onto_first_pin(&mut uv, pins);
        note = Some(if pins.len() == 1 {
            "one pinned vertex: the chart was translated onto it".to_string()
        } else {
            "all pins share one UV: the chart was translated onto it".to_string()
        });
    }
    Ok((uv, note))
}

/// Most solves of [`free_map`]'s Lanczos run, and the relative residual at which it stops.
/// Tight, because a developable chart's map must come out exact (`tests/methods.rs`, the
/// planar disk and the cut cylinder): its eigenvalue is the shift alone, far below the
/// others (stopped at 10⁻³, the cylinder's map was off by 10⁻⁶), so two or three solves reach
/// it. On curved charts the pieces of the bunny subdivided twice converge in 5–10 solves and
/// those of the camel's head subdivided twice in 5–17. A chart of 292k vertices (the whole fertility statue subdivided
/// three times) stops at the cap, 6·10⁻³ from the eigenvector: still a map fixed on the
/// boundary, so nothing is crushed by pins.
pub const FREE_MAP_SOLVES: usize = 40;
/// See [`FREE_MAP_SOLVES`].
pub const FREE_MAP_TOLERANCE: f64 = 1e-9;

/// The free map of `chart` without pins: the conformal energy's smallest eigenvector against
/// the boundary mass (spectral conformal parameterization, [`super::boundary_eigen::BoundaryIteration`],
/// a few Lanczos steps), moved by a similarity so that the automatic pins `auto` land on their
/// UVs. `None` when the chart has no boundary, the iteration fails, or the two pins land on
/// one point (the caller pins them instead).
fn free_map(chart: &Chart, angles: &[[f64; 3]], auto: [(u32, [f64; 2]); 2]) -> Option<Vec<[f64; 2]>> {
    let energy = conformal_hermitian(&chart.triangles, angles);
    let mut it = super::boundary_eigen::BoundaryIteration::new(chart, energy).ok()?;
    it.lanczos(FREE_MAP_SOLVES, FREE_MAP_TOLERANCE).ok()?;
    let w = it.uv();
    let at = |v: u32| c64::new(w[v as usize][0], w[v as usize][1]);
    let (za, zb) = (at(auto[0].0), at(auto[1].0));
    let (ta, tb) = (c64::new(auto[0].1[0], auto[0].1[1]), c64::new(auto[1].1[0], auto[1].1[1]));
    let dz = zb - za;
    if dz.norm().is_nan() || dz.norm() == 0.0 {
        return None;
    }
    let a = (tb - ta) / dz;
    let uv: Vec<[f64; 2]> = w.iter().map(|p| {
        let z = a * (c64::new(p[0], p[1]) - za) + ta;
        [z.re, z.im]
    }).collect();
    uv.iter().all(|p| p[0].is_finite() && p[1].is_finite()).then_some(uv)
}

/// LSCM with the chart's 3D angles.
///
/// A chart with holes is solved with its holes open (free boundaries, as in the paper). When
/// that map folds in a way closing the holes can mend ([`filling_may_help`]: a flipped
/// triangle, or a crossing that involves a hole), the chart is solved again with every hole filled by a virtual fan
/// ([`super::fixed_boundary::filled_chart`], as Blender's own unwrapper fills holes), and the
/// filled solution is kept when it folds less (fewer flipped triangles, then no overlap); the
/// report's note says so.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    let angles = chart_angles(&chart.positions, &chart.triangles);
    let (uv, note) = solve_free(chart, &angles, pins)?;
    if chart.boundary_loops.len() > 1 {
        let open = folds(chart, &uv);
        if filling_may_help(chart, &uv, open) {
            let filled = super::fixed_boundary::filled_chart(chart);
            let filled_angles = chart_angles(&filled.positions, &filled.triangles);
            if let Ok((mut closed_uv, closed_note)) = solve_free(&filled, &filled_angles, pins) {
                closed_uv.truncate(chart.positions.len());
                if folds(chart, &closed_uv) < open {
                    let mut s = ChartSolution::direct(closed_uv);
                    s.note = Some(holes_filled_note(open, closed_note));
                    return Ok(s);
                }
            }
        }
    }
    let mut s = ChartSolution::direct(uv);
    s.note = note;
    Ok(s)
}

/// How much a map of `chart` folds: its flipped or degenerate triangles (a quad folded on
/// either of its splits counts, as in the chart's report), and whether a boundary loop
/// crosses itself or another (a closed seam does not count, [`crate::metrics::closed_seams`],
/// as in the chart's report). Ordered: fewer flips first, then no overlap.
pub(crate) fn folds(chart: &Chart, uv: &[[f64; 2]]) -> (usize, bool) {
    let flipped = crate::metrics::count_flips_with_quads(&chart.triangles, &chart.quads, uv);
    let loops = &chart.boundary_loops;
    let overlap = crate::metrics::closed_seams::outline_overlap(&chart.positions, &chart.triangles, uv, loops);
    (flipped, overlap)
}

/// Whether solving `chart` again with its holes filled can give a map that folds less than
/// `uv`, which folds as `open` (see `folds`), so that the second solve is worth its cost.
///
/// The filled map is kept only when it folds strictly less. With flipped triangles it may
/// (closing the holes removes the folds they cause, e.g. on halftunnel), so the answer is
/// yes. With no flipped triangle it must have no boundary crossing at all; when the open
/// map's outer loop crosses itself (rather than a hole crossing something), the crossing
/// comes from the chart's overall shape, which closing the holes does not undo, so the
/// answer is no. Measured on the Smart UV Project cuts of seven shared meshes (camelhead,
/// beetle, bunny, cow, lion, fertility, 3holes): of the 22 holed charts whose open outer
/// loop crossed itself without flips, the 21 whose filled solve succeeded all still crossed
/// with their holes filled, while the two charts the filled map fixed had only hole loops
/// crossing. A heuristic, not a proof:
/// on random bumpy or wound grids with holes, about one in thirty such charts stops
/// crossing with its holes filled, and keeps its crossing here (it never affects flips: the
/// second solve always runs when the open map has a flipped triangle). A map that does not
/// fold needs no second solve.
///
/// Cost: one more crossing test of the outer loop alone, only when `open` has a crossing and
/// no flip. Preconditions: `uv` is a map of `chart`.
pub fn filling_may_help(chart: &Chart, uv: &[[f64; 2]], open: (usize, bool)) -> bool {
    match open {
        (0, false) => false,
        (0, true) => match chart.outer_loop() {
            Some(l) => {
                let outer = std::slice::from_ref(&chart.boundary_loops[l]);
                !crate::metrics::closed_seams::outline_overlap(&chart.positions, &chart.triangles, uv, outer)
            }
            None => true,
        },
        _ => true,
    }
}

/// The report note of a chart re-solved with its holes filled, after the open-hole map
/// folded as `open` (see [`folds`]); `then` is the note of the filled solve, if any.
pub(crate) fn holes_filled_note(open: (usize, bool), then: Option<String>) -> String {
    let why = format!(
        "holes filled by virtual fans: with open holes the map had {} flipped triangle(s){}",
        open.0,
        if open.1 { " and a self-overlapping boundary" } else { "" }
    );
    match then {
        Some(n) => format!("{why}; {n}"),
        None => why,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LSCM on a bumpy grid chart: solved alone it orders its own system; once the chart's
    /// shared vertex order exists (a method that shares it asked first) it uses that one.
    /// Both give the same map to rounding.
    #[test]
    fn the_shared_vertex_order_gives_the_same_map() {
        let chart = crate::charts::bumpy_grid_chart(24);
        assert!(matches!(chart.ordering_if_known(OrderingKind::Amd), Ordering::Kind(_)), "no shared order before it is asked for");
        let own = solve(&chart, &[]).unwrap().uv;
        assert!(matches!(chart.ordering(OrderingKind::Amd), Ordering::Vertices { .. }));
        assert!(matches!(chart.ordering_if_known(OrderingKind::Amd), Ordering::Vertices { .. }));
        let shared = solve(&chart, &[]).unwrap().uv;
        let diff = own.iter().zip(&shared).fold(0.0f64, |m, (a, b)| m.max((a[0] - b[0]).abs()).max((a[1] - b[1]).abs()));
        assert!(diff < 1e-10, "maps differ by {diff}");
        // A clone (whose triangles may be changed) computes its own again; a copy with moved
        // vertices only (a method's unit frame) keeps it.
        assert!(matches!(chart.clone().ordering_if_known(OrderingKind::Amd), Ordering::Kind(_)));
        let moved = chart.with_positions(chart.positions.iter().map(|p| [2.0 * p[0], 2.0 * p[1], 2.0 * p[2]]).collect());
        match (moved.ordering_if_known(OrderingKind::Amd), chart.ordering_if_known(OrderingKind::Amd)) {
            (Ordering::Vertices { order: a, .. }, Ordering::Vertices { order: b, .. }) => assert_eq!(a, b),
            _ => panic!("the moved copy lost the shared order"),
        }
        assert_eq!(moved.positions[1], [2.0 * chart.positions[1][0], 2.0 * chart.positions[1][1], 2.0 * chart.positions[1][2]]);
    }

    /// The angle form equals ½ Σ cot α |e_opp|² − A on an arbitrary triangle and map.
    #[test]
    fn angle_form_equals_cotangent_form() {
        let p = [[0.1, 0.2, 0.0], [1.3, -0.1, 0.4], [0.4, 0.9, -0.3]];
        let a = crate::geometry::raw_angles(p);
        let w = [[0.3, 0.1], [1.1, 0.4], [0.2, 0.8]];
        let trip = conformal_triplets(&[[0, 1, 2]], &[a]);
        let x = [w[0][0], w[0][1], w[1][0], w[1][1], w[2][0], w[2][1]];
        let e_form: f64 = trip
            .iter()
            .map(|&(i, j, v)| if i == j { 1.0 } else { 2.0 } * x[i as usize] * v * x[j as usize])
            .sum();
        // Dirichlet energy ½∫|∇u|² + |∇v|² = ¼ Σ cot α_k |e_k|²; the form is 2 (E_D − A).
        let mut e_dirichlet = 0.0;
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let d = [w[j][0] - w[i][0], w[j][1] - w[i][1]];
            e_dirichlet += 0.25 / a[k].tan() * (d[0] * d[0] + d[1] * d[1]);
        }
        let expected = 2.0 * (e_dirichlet - crate::geometry::signed_area_2d(w));
        assert!((e_form - expected).abs() < 1e-12, "{e_form} vs {expected}");
        // The Hermitian form gives the same energy: w* H w with H from the lower triangle.
        let z: Vec<c64> = w.iter().map(|p| c64::new(p[0], p[1])).collect();
        let h = conformal_hermitian(&[[0, 1, 2]], &[a]);
        let mut e_h = c64::new(0.0, 0.0);
        for &(i, j, v) in &h {
            e_h += z[i as usize].conj() * v * z[j as usize];
            if i != j {
                e_h += z[j as usize].conj() * v.conj() * z[i as usize];
            }
        }
        assert!((e_h.re - e_form).abs() < 1e-12 && e_h.im.abs() < 1e-12, "{e_h} vs {e_form}");
    }
}
