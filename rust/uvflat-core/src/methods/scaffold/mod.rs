//! `scaffold`: globally bijective maps — no flipped triangle and no boundary self-overlap —
//! by minimising symmetric Dirichlet on the chart plus a scaffold mesh of the free space.
//!
//! Paper: Z. Jiang, S. Schaefer, D. Panozzo, "Simplicial complex augmentation framework for
//! bijective maps", ACM TOG 36(6) (SIGGRAPH Asia), 2017 (SCAF).
//!
//! Every iteration:
//! 1. *Scaffold.* A box around the chart's current UVs (its bounding box grown by
//!    [`BOX_MARGIN`], with points along its sides) and the chart's boundary vertices (all
//!    loops) are triangulated by a constrained Delaunay triangulation (`spade`, bulk loaded)
//!    with the boundary edges as constraints. Triangles inside the chart are dropped; the
//!    rest — between the chart and the box, and inside the holes — is the scaffold. Chart ∪
//!    scaffold is a triangulated square whose boundary (the box) is fixed.
//! 2. *Energy.* Symmetric Dirichlet D(J) = ‖J‖² + ‖J⁻¹‖² on the chart triangles (3D rest
//!    shapes, weighted by 3D area) plus, on every scaffold triangle, D relative to its shape at
//!    the start of the iteration, all scaffold triangles sharing the total weight
//!    [`SCAFFOLD_WEIGHT`] × chart area. D is a barrier: +∞ as any triangle degenerates.
//! 3. *Step.* One SLIM global step (Rabinovich et al. 2017: reweighted proxy
//!    Σ w ‖W (J − R)‖², W from the singular values, R the closest rotation; the local step is
//!    [`super::nonlinear::proxy::reweight`]) on the whole square with the box fixed, then the flip-free line search
//!    over chart *and* scaffold triangles.
//!
//! Files: `mesh.rs` (the scaffold triangulation), `chords.rs` (the scaffold's couplings between
//! chart vertices), `regularise.rs` (the factorisation of a global step, shifted when it fails);
//! energies, proxy, starts, pins, pattern and the iteration bookkeeping are the nonlinear
//! kernel's ([`super::nonlinear`]).
//!
//! Linear algebra: the unknowns are the chart's (u, v), interleaved; the box is fixed and goes
//! to the right-hand side. The matrix is the chart's SLIM matrix (same pattern every iteration)
//! plus the scaffold's entries, which between chart vertices are only *chords* (scaffold edges
//! joining two boundary vertices that are not chart edges). One sparse Cholesky symbolic
//! analysis (AMD ordering) is kept while its pattern covers the scaffold's chords — the entries
//! of chords the current scaffold lacks are zero, so the factorisation is exactly that of the
//! current matrix — and each iteration costs one numeric factorisation and one solve, like
//! SLIM's. When a scaffold brings a new chord the analysis is redone for the union of old and
//! new chords.
//!
//! Re-meshing: the paper re-meshes the scaffold every iteration. Here a fresh Delaunay
//! scaffold is taken when it needs no new symbolic analysis, when the previous scaffold
//! limited the last step (its first degenerating triangle bounded the line search below a full
//! step), when the previous one is `STALE_AFTER` (10) iterations old, or on the first
//! iteration; otherwise the previous iteration's scaffold is kept. The
//! kept scaffold is a valid triangulation of the free space (the line search kept its triangles
//! positive and the box is fixed) and its rest shapes are reset to the current ones, so every
//! iteration minimises the same energy — chart symmetric Dirichlet plus scaffold symmetric
//! Dirichlet at its minimum — over a valid scaffold, only not always a Delaunay one. Kept
//! scaffolds get skinnier as the boundary moves, which can only hold the boundary back; that
//! is what the re-mesh triggers undo (on a wavy cone whose isometric flattening overlaps
//! itself, 100 iterations re-meshing at most every 10 end at the energy of re-meshing every
//! iteration to 1e-5, without the age trigger 9 % further from the isometry). (On a 22k-triangle chart with a 56-vertex boundary every
//! Delaunay scaffold has the same chords anyway; on a chart with a 1136-vertex boundary nearly
//! every re-mesh flips a few chords, and keeping the scaffold saves an analysis per
//! iteration.)
//!
//! Start: the valid map with the lower energy among LSCM and the mean value map on a circle
//! (Floater 2003; an embedding by Tutte's theorem), each scaled by the energy-optimal factor,
//! the latter computed only when LSCM is above a symmetric Dirichlet energy of 2
//! ([`super::nonlinear::start::pick_staged`]). Valid: every triangle positive, no boundary
//! self-overlap, and a scaffold can be built.
//!
//! Quads: the chart energy and the line search also cover the other diagonal's two triangles
//! of every quad ([`crate::methods::barrier_triangles`]), so quads stay strictly convex.
//!
//! Guarantee: all chart and scaffold triangles stay positively oriented and the box boundary is
//! fixed, so chart ∪ scaffold stays an embedded triangulation of the box (a locally injective
//! map of a disk onto a convex polygon's interior with the boundary fixed is injective):
//! no chart triangle flips and the chart boundary cannot cross itself or a hole.
//!
//! Monotonicity: the scaffold energy is at its minimum (J = I) at the start of every
//! iteration, and the line search lowers chart + scaffold energy, so the chart's own symmetric
//! Dirichlet energy strictly decreases every iteration ([`solve_with_history`] returns it).
//!
//! Pins: with two or more pinned vertices at distinct UVs, the start honours them (pinned LSCM
//! or pinned mean value, not rescaled), they are fixed values of every global step
//! (eliminated on the step's pattern, `held.rs`), so they hold exactly, and the chart's rest
//! shapes are the 3D triangles scaled by the pins' scale
//! ([`super::nonlinear::pins::pins_scale`]), so the unpinned part lies at the pins' scale. When
//! no valid start honours them the chart falls back to a pinned map
//! ([`super::nonlinear::pins::pinned_fallback`]). A single pin is reached by translating the
//! result (exact).
//!
//! Failures: a chart that is not a disk ([`crate::methods::require_disk`]). When neither start is valid
//! (degenerate charts in floating point), the mean value map is returned marked as a fallback.
//! When a fresh scaffold cannot be built (a boundary vertex collinear with a boundary edge to
//! round-off, so the triangulation would split the constraint) the previous scaffold is kept;
//! when there is none, the iterations stop and the last map — valid by the guarantee — is
//! returned with a note. A global step whose matrix does not factor (round-off on large charts
//! with many holes) is regularised by a proximal diagonal shift and retried
//! (`solve_regularised`); when even that fails the iterations stop likewise. A chart that
//! stops before its first iteration is never reported solved: it keeps its valid start,
//! marked as a fallback to that start's method with the reason and the energy reached.

use rayon::prelude::*;

use super::nonlinear::energy::{scale_optimally, symmetric_dirichlet, weighted_sum};
use super::nonlinear::iterate::{quads_left_out_note, Change, Iteration};
use super::nonlinear::pattern::{chart_edges, BlockPattern, BLOCK};
use super::lscm::pins_span;
use super::nonlinear::pins::{pinned_fallback, pins_scale_note, rest_positions, translate_onto_single_pin};
use super::nonlinear::proxy::reweight;
use super::nonlinear::start::{self, flip_free_start};
use super::nonlinear::TriangleOperators;
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, max_flip_free_step, LineSearchOptions};

mod chords;
mod held;
mod mesh;
mod regularise;

use chords::{is_subset, scaffold_chords};
use mesh::{build_scaffold, Scaffold};
use regularise::solve_regularised;

pub use super::nonlinear::energy::symmetric_dirichlet_density;

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaffoldOptions {
    /// Most iterations (one scaffold rebuild and one global step each). Default 100.
    pub max_iterations: usize,
    /// Stop when the chart energy changes by less than this, relative to the energy.
    /// Default 1e-4, SLIM's: on every disk mesh of the test set and on Suzanne with her seams
    /// the symmetric Dirichlet reached is below that of Blender's MINIMUM_STRETCH unwrap
    /// (further iterations lower it by under 0.5 %).
    pub tolerance: f64,
}

impl Default for ScaffoldOptions {
    fn default() -> Self {
        ScaffoldOptions { max_iterations: 100, tolerance: 1e-4 }
    }
}

/// The box around the chart is its UV bounding box grown by this fraction of its larger side
/// on every side.
pub const BOX_MARGIN: f64 = 0.5;
/// Total weight of the scaffold triangles relative to the chart's 3D area.
pub const SCAFFOLD_WEIGHT: f64 = 0.01;
/// A scaffold kept this many iterations is re-meshed (see the module docs).
const STALE_AFTER: usize = 10;

/// Map one chart; see the module docs.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &ScaffoldOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
}

/// What [`solve_with_history`] reports beside the map.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScaffoldHistory {
    /// Chart symmetric Dirichlet energy per unit area / 4 of the start and after every
    /// iteration (strictly decreasing).
    pub energy: Vec<f64>,
    /// Seconds per iteration: `[scaffold triangulation, assembly, symbolic analysis, numeric
    /// factorisation, solve, line search]` (symbolic is 0 when the analysis was reused).
    pub seconds: Vec<[f64; 6]>,
    /// Scaffold triangles per iteration.
    pub scaffold_triangles: Vec<usize>,
    /// Per iteration: whether its scaffold was a fresh Delaunay re-mesh (false: the previous
    /// iteration's scaffold, kept).
    pub remeshed: Vec<bool>,
    /// Number of symbolic analyses (at most one per iteration).
    pub analyses: usize,
    /// Name of the starting map ("lscm" or "mean_value").
    pub start: &'static str,
    /// Seconds spent computing and checking the starting maps.
    pub start_seconds: f64,
}

/// A valid starting map: UVs, its energy and its name.
type Start = (Vec<[f64; 2]>, f64, &'static str);

/// The valid start with the lowest energy, each candidate scaled optimally (honouring the pins
/// instead when they span more than a point): LSCM and the mean value map on a circle (Floater 2003, an embedding by Tutte's theorem up to round-off), the
/// latter only when LSCM is above a symmetric Dirichlet energy of 2 ([`start::pick_staged`]). Valid:
/// every chart triangle positive, finite energy, no boundary self-overlap, and a scaffold can
/// be built around it. `None` when no candidate is valid (the reasons are returned).
fn pick_start(chart: &Chart, ops: &TriangleOperators, pins: &[(u32, [f64; 2])]) -> (Option<Start>, Vec<String>) {
    let tris = &chart.triangles;
    let mut rejected = Vec::new();
    // Pins spanning more than a point are honoured by the starts and fix their scale.
    let spanning = pins_span(pins);
    let best = start::pick_staged(
        chart,
        if spanning { pins } else { &[] },
        true,
        &mut rejected,
        |uv| {
            if !spanning {
                scale_optimally(ops, tris, uv)
            }
        },
        |uv| {
            let e = symmetric_dirichlet(ops, tris, uv);
            if !all_positive(tris, uv) || !e.is_finite() {
                Err("flipped or degenerate triangles".to_string())
            } else if crate::metrics::boundary_self_overlap(uv, &chart.boundary_loops) {
                Err("the boundary overlaps itself".to_string())
            } else {
                build_scaffold(chart, uv).map(|_| e)
            }
        },
        None::<fn()>,
    );
    (best.0, rejected)
}

/// [`solve`], also returning the chart's normalised symmetric Dirichlet energy before the first
/// iteration and after each iteration (strictly decreasing, see the module docs) and the time
/// split of every iteration.
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ScaffoldOptions,
) -> Result<(ChartSolution, ScaffoldHistory), ChartFailure> {
    run(chart, pins, options, Policy::default())
}

/// How the iterations treat the scaffold and the symbolic analysis (the default is the fast
/// one; the others exist to check it against).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Policy {
    /// Re-mesh the scaffold every iteration, as in the paper (default: keep the previous
    /// scaffold when re-meshing would need a new analysis and the old one did not limit the
    /// step).
    remesh_every_iteration: bool,
    /// Analyse exactly the current pattern every iteration (default: reuse an analysis whose
    /// pattern covers the scaffold's chords).
    exact_pattern: bool,
}

/// The iterations under `policy`.
fn run(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ScaffoldOptions,
    policy: Policy,
) -> Result<(ChartSolution, ScaffoldHistory), ChartFailure> {
    use std::time::Instant;
    crate::methods::require_disk(chart)?;
    let tris = &chart.triangles;
    let n = chart.positions.len();
    // Pins spanning more than a point fix the map's scale: the energy is measured against the
    // 3D shape at that scale (see the module docs).
    let (rest, scale) = rest_positions(chart, pins);
    let ops = TriangleOperators::local_frames(&rest, tris);
    // (Degenerate triangles get a thin rest shape of positive area: the chart's own area
    // decides.)
    let area_3d: f64 = tris
        .iter()
        .map(|t| crate::geometry::triangle_area([rest[t[0] as usize], rest[t[1] as usize], rest[t[2] as usize]]))
        .sum();
    if !(area_3d > 0.0) {
        return Err(ChartFailure("the chart has zero 3D area".into()));
    }
    let t_start = Instant::now();
    let (start, rejected) = pick_start(chart, &ops, pins);
    let Some((mut uv, mut energy, start_name)) = start else {
        let why = format!("no valid (flip-free, overlap-free) start for the scaffold iterations ({})", rejected.join("; "));
        if !pins.is_empty() {
            return Ok((pinned_fallback(chart, pins, &why)?, ScaffoldHistory::default()));
        }
        let mut sol = ChartSolution::direct(flip_free_start(chart)?);
        sol.fallback = Some(crate::methods::Fallback { method: "mean_value", reason: why });
        return Ok((sol, ScaffoldHistory::default()));
    };
    // Unknowns held at their values in every global step: the pins, when they span.
    let mut held = vec![false; 2 * n];
    if pins_span(pins) {
        for &(v, _) in pins {
            held[2 * v as usize] = true;
            held[2 * v as usize + 1] = true;
        }
    }
    // The chart energy and the barrier cover both diagonal splits of every quad, so quads stay
    // strictly convex (see `barrier_triangles`).
    let barrier_tris;
    // The global step weighs every barrier triangle by its full 3D area (`step_area`), the
    // energy by its barrier weight (½ for the four triangles of a quad's two splits).
    let (tris, ops, step_area, left_out) = if chart.quads.is_empty() {
        let step_area = ops.area.clone();
        (tris, ops, step_area, 0)
    } else {
        let (b, w, left_out) = crate::methods::barrier_triangles(chart, &uv);
        barrier_tris = b;
        let full = TriangleOperators::local_frames(&rest, &barrier_tris);
        let step_area = full.area.clone();
        let ops = full.weighted(&w);
        energy = symmetric_dirichlet(&ops, &barrier_tris, &uv);
        (&barrier_tris, ops, step_area, left_out)
    };
    drop(rest);
    let total = ops.total_area;
    let mut history = ScaffoldHistory {
        start: start_name,
        start_seconds: t_start.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let edges = chart_edges(tris);
    let mut pattern: Option<BlockPattern> = None;
    // Chords the analysis covers (the pattern's chords, tracked apart from the analysis so
    // that `policy.exact_pattern` changes the linear algebra only).
    let mut covered: Vec<(u32, u32)> = Vec::new();
    // The scaffold of the previous iteration: still a valid triangulation of the free space
    // after the step (the line search kept all its triangles positive, the box is fixed).
    let mut kept: Option<Scaffold> = None;
    let mut remesh = true;
    let mut age = 0usize;
    let ls = LineSearchOptions::default();
    let mut it = Iteration::new(energy, options.max_iterations, options.tolerance, Change::OfNew, f64::INFINITY);
    let mut stop_note: Option<String> = None;
    // Global steps that needed a diagonal shift to factor, and the largest relative shift.
    let (mut shifts, mut largest_shift) = (0usize, 0.0f64);
    // A cancelled unwrap discards this chart.
    while it.go_on() {
        let t0 = Instant::now();
        // Scaffold: the Delaunay re-mesh of the free space around the current map (SCAF), unless
        // it would need a new symbolic analysis while the previous scaffold neither limited the
        // last step nor is stale (then the previous one is kept, see the module docs).
        let fresh = build_scaffold(chart, &uv).and_then(|s| {
            let ok = s.triangles.iter().all(|t| {
                let q = |v: u32| if (v as usize) < n { uv[v as usize] } else { s.box_points[v as usize - n] };
                TriangleOperators::planar_is_valid([q(t[0]), q(t[1]), q(t[2])])
            });
            if ok {
                Ok(s)
            } else {
                Err("a degenerate scaffold triangle".to_string())
            }
        });
        let (scaffold, remeshed) = match (fresh, kept.take()) {
            (Ok(f), None) => (f, true),
            (Ok(f), Some(k)) => {
                let chords = scaffold_chords(n, &f.triangles, &edges);
                if policy.remesh_every_iteration || remesh || is_subset(&chords, &covered) {
                    (f, true)
                } else {
                    (k, false)
                }
            }
            (Err(_), Some(k)) => (k, false),
            (Err(why), None) => {
                stop_note = Some(format!("scaffold iterations stopped early: {why}"));
                break;
            }
        };
        let t1 = Instant::now();
        let big_n = n + scaffold.box_points.len();
        let mut all: Vec<[f64; 2]> = uv.clone();
        all.extend_from_slice(&scaffold.box_points);
        let s_tris = &scaffold.triangles;
        let s_ops = TriangleOperators::planar(&all, s_tris);
        if s_ops.area.contains(&0.0) {
            // Cannot happen: fresh scaffolds are checked above, kept ones stayed positive.
            stop_note = Some("scaffold iterations stopped early: a degenerate scaffold triangle".into());
            break;
        }
        let ws = SCAFFOLD_WEIGHT * total / s_tris.len().max(1) as f64;
        let s_weight = vec![ws; s_tris.len()];
        // Symbolic analysis: kept while it covers the scaffold's chords; otherwise redone for
        // the union of the old and new chords (scaffolds of consecutive iterations share most
        // chords, so the union settles), or the new chords alone once the union would be more
        // than twice their number. Entries of chords absent from the scaffold are zero.
        let chords = scaffold_chords(n, s_tris, &edges);
        let mut t_symbolic = 0.0;
        let covers = pattern.is_some() && is_subset(&chords, &covered);
        if !covers || policy.exact_pattern {
            let ts = Instant::now();
            if !covers {
                let mut u = std::mem::take(&mut covered);
                u.extend_from_slice(&chords);
                u.sort_unstable();
                u.dedup();
                covered = if u.len() > 2 * chords.len() + 16 { chords.clone() } else { u };
            }
            let wanted = if policy.exact_pattern { &chords } else { &covered };
            drop(pattern.take());
            match BlockPattern::new(n, tris, &edges, wanted) {
                Ok(p) => pattern = Some(p),
                Err(why) => {
                    stop_note = Some(format!("scaffold iterations stopped early: {why}"));
                    break;
                }
            }
            history.analyses += 1;
            t_symbolic = ts.elapsed().as_secs_f64();
        }
        let pat = pattern.as_ref().expect("analysed above");
        let t2 = Instant::now();
        // Assembly: SLIM's proxy on the chart (parallel per triangle), then a scatter into
        // the pattern's value slots; scaffold triangles at rest (J = I: W² = 4 I, W² R = 4 I).
        let blocks: Vec<([f64; 21], [[f64; 2]; 3])> = tris
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .map(|(f, t)| {
                let mut vals = [0.0; 21];
                let mut rhs = [[0.0; 2]; 3];
                let (area, g) = (step_area[f], &ops.grad[f]);
                if area > 0.0 {
                    let (k, p) = reweight(ops.jacobian(f, t, &uv));
                    let kk = [[k[0], k[1]], [k[1], k[2]]];
                    let l = ops.stiffness(f);
                    for (e, &(pp, qq)) in BLOCK.iter().enumerate() {
                        vals[e] = area * kk[pp % 2][qq % 2] * l[pp / 2][qq / 2];
                    }
                    for (a, row) in rhs.iter_mut().enumerate() {
                        for (s, x) in row.iter_mut().enumerate() {
                            *x = area * (g[0][a] * p[s][0] + g[1][a] * p[s][1]);
                        }
                    }
                }
                (vals, rhs)
            })
            .collect();
        let mut values = vec![0.0; pat.row_idx.len()];
        let mut b = vec![0.0; 2 * n];
        for ((t, slots), (vals, rhs)) in tris.iter().zip(&pat.chart_slots).zip(&blocks) {
            for (&s, &v) in slots.iter().zip(vals) {
                values[s as usize] += v;
            }
            for a in 0..3 {
                b[2 * t[a] as usize] += rhs[a][0];
                b[2 * t[a] as usize + 1] += rhs[a][1];
            }
        }
        let mut missing = false;
        for (t, r) in s_tris.iter().zip(&s_ops.grad) {
            for a in 0..3 {
                let ta = t[a] as usize;
                if ta >= n {
                    continue; // a box point: fixed, no equation
                }
                for s in 0..2 {
                    b[2 * ta + s] += ws * 4.0 * r[s][a];
                }
                for c in 0..3 {
                    let tc = t[c] as usize;
                    let v = ws * 4.0 * (r[0][a] * r[0][c] + r[1][a] * r[1][c]);
                    if tc >= n {
                        let q = scaffold.box_points[tc - n];
                        b[2 * ta] -= v * q[0];
                        b[2 * ta + 1] -= v * q[1];
                    } else if ta >= tc {
                        for s in 0..2 {
                            match pat.slot(2 * ta + s, 2 * tc + s) {
                                Some(k) => values[k] += v,
                                None => missing = true,
                            }
                        }
                    }
                }
            }
        }
        if missing {
            // Cannot happen: the pattern covers every chord and chart edge.
            stop_note = Some("scaffold iterations stopped early: a scaffold entry is missing from the pattern".into());
            break;
        }
        // Pins: fixed values of the step, eliminated on the same pattern (see `held`).
        held::eliminate(pat, &mut values, &mut b, &held, &uv);
        let t3 = Instant::now();
        let step = match solve_regularised(pat, &mut values, &mut b, &uv) {
            Ok(step) => {
                if step.shift > 0.0 {
                    shifts += 1;
                    largest_shift = largest_shift.max(step.shift);
                }
                step
            }
            Err(e) => {
                stop_note = Some(format!("scaffold iterations stopped early: the global step could not be factored ({e})"));
                break;
            }
        };
        let t4 = Instant::now();
        let (mut x, solve_seconds) = (step.x, step.solve_seconds);
        held::restore(&mut x, &held, &uv);
        if x[..2 * n].iter().any(|v| !v.is_finite()) {
            stop_note = Some("scaffold iterations stopped early: the global step is not finite".into());
            break;
        }
        let dir: Vec<[f64; 2]> =
            (0..big_n).map(|i| if i < n { [x[2 * i] - all[i][0], x[2 * i + 1] - all[i][1]] } else { [0.0, 0.0] }).collect();
        let t5 = Instant::now();
        let mut both: Vec<[u32; 3]> = tris.clone();
        both.extend_from_slice(s_tris);
        let total_energy = |q: &[[f64; 2]]| {
            weighted_sum(&ops, &ops.area, tris, q, symmetric_dirichlet_density)
                + weighted_sum(&s_ops, &s_weight, s_tris, q, symmetric_dirichlet_density)
        };
        let e0 = total_energy(&all);
        let scaffold_flip = max_flip_free_step(s_tris, &all, &dir);
        let out = flip_free_line_search(&both, &mut all, &dir, e0, total_energy, &ls);
        // The scaffold limited the step when its first degenerating triangle set the bound and
        // the trial started below a full step: re-mesh it next iteration.
        remesh = scaffold_flip <= out.flip_step && ls.safety * scaffold_flip < ls.max_step;
        // A scaffold kept for `STALE_AFTER` iterations is re-meshed too: one that only grows
        // skinnier slows the boundary down without ever bounding the step.
        age = if remeshed { 1 } else { age + 1 };
        remesh |= age >= STALE_AFTER;
        let t6 = Instant::now();
        history.seconds.push([
            (t1 - t0).as_secs_f64(),
            (t3 - t2).as_secs_f64() + (t2 - t1).as_secs_f64() - t_symbolic,
            t_symbolic,
            (t4 - t3).as_secs_f64() - solve_seconds,
            solve_seconds + (t5 - t4).as_secs_f64(),
            (t6 - t5).as_secs_f64(),
        ]);
        history.scaffold_triangles.push(s_tris.len());
        history.remeshed.push(remeshed);
        if out.step == 0.0 {
            it.stalled();
            break;
        }
        uv.copy_from_slice(&all[..n]);
        kept = Some(scaffold);
        if it.record(symmetric_dirichlet(&ops, tris, &uv)) {
            break;
        }
    }
    let (energy, iterations) = (it.energy(), it.iterations);
    history.energy = it.history;
    let mut sol = ChartSolution::direct(uv);
    sol.iterations = iterations;
    sol.residual = it.change;
    let pin_note = match scale {
        Some(_) => pins_scale_note(pins.len(), scale),
        None if pins_span(pins) => Some(format!("{} pinned vertex(es) held fixed", pins.len())),
        None => translate_onto_single_pin(&mut sol.uv, pins, "scaffold"),
    };
    let remeshes = history.remeshed.iter().filter(|&&r| r).count();
    let summary = format!(
        "symmetric Dirichlet {energy:.6} after {iterations} iteration(s), started from {}; scaffold re-meshed {remeshes} time(s), {} symbolic analysis(es)",
        history.start, history.analyses
    );
    let shift_note = (shifts > 0).then(|| {
        format!("{shifts} global step(s) factored with the diagonal shifted by up to {largest_shift:.0e} of its mean")
    });
    let quad_note = quads_left_out_note(left_out);
    let note = [Some(summary), stop_note.clone(), shift_note, pin_note, quad_note].into_iter().flatten().collect::<Vec<_>>().join("; ");
    if iterations == 0 && stop_note.is_some() {
        // Never "solved" without a single iteration: the start is what the chart gets.
        sol.fallback = Some(crate::methods::Fallback { method: history.start, reason: note });
    } else {
        sol.note = Some(note);
    }
    Ok((sol, history))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wavy cone ring cut open along one ray (its isometric flattening overlaps itself, so
    /// the scaffold is active): the chart and the number of its triangles.
    fn wavy_cone_chart(nu: usize, nv: usize) -> Chart {
        let mut positions = Vec::new();
        for j in 0..=nv {
            let r = 1.0 + j as f64 / nv as f64;
            for i in 0..nu {
                let a = std::f64::consts::TAU * i as f64 / nu as f64;
                positions.push([r * a.cos(), r * a.sin(), r * 0.35 * (5.0 * a).sin()]);
            }
        }
        let id = |i: usize, j: usize| (j * nu + i % nu) as u32;
        let mut corners = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                corners.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let sizes = vec![3u32; 2 * nu * nv];
        let seams: Vec<[u32; 2]> = (0..nv).map(|j| [id(0, j), id(0, j + 1)]).collect();
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        crate::charts::build_charts(&mesh, &seams, None).pop().unwrap()
    }

    #[test]
    fn a_reused_analysis_with_extra_zero_chords_gives_the_same_steps_as_a_fresh_one() {
        let chart = wavy_cone_chart(60, 4);
        let o = ScaffoldOptions { max_iterations: 12, tolerance: 0.0 };
        let remesh = Policy { remesh_every_iteration: true, exact_pattern: false };
        let exact = Policy { remesh_every_iteration: true, exact_pattern: true };
        let (a, ha) = run(&chart, &[], &o, remesh).unwrap();
        let (b, hb) = run(&chart, &[], &o, exact).unwrap();
        assert_eq!(ha.seconds.len(), 12);
        assert_eq!(hb.analyses, 12, "the exact policy analyses every iteration");
        // The scaffold is re-meshed every iteration and its chords change, yet the union
        // pattern is analysed fewer times.
        assert!(ha.analyses < 12, "{} analyses", ha.analyses);
        let scale = a.uv.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        for (p, q) in a.uv.iter().zip(&b.uv) {
            assert!((p[0] - q[0]).abs() <= 1e-9 * scale && (p[1] - q[1]).abs() <= 1e-9 * scale, "{p:?} vs {q:?}");
        }
        for (x, y) in ha.energy.iter().zip(&hb.energy) {
            assert!((x - y).abs() <= 1e-9 * x, "{x} vs {y}");
        }
    }

    #[test]
    fn keeping_the_scaffold_stays_bijective_and_matches_remeshing_every_iteration() {
        let chart = wavy_cone_chart(60, 4);
        let o = ScaffoldOptions { max_iterations: 40, tolerance: 0.0 };
        let (kept, hk) = run(&chart, &[], &o, Policy::default()).unwrap();
        let (fresh, hf) = run(&chart, &[], &o, Policy { remesh_every_iteration: true, exact_pattern: false }).unwrap();
        for (sol, h) in [(&kept, &hk), (&fresh, &hf)] {
            assert!(all_positive(&chart.triangles, &sol.uv));
            assert!(!crate::metrics::boundary_self_overlap(&sol.uv, &chart.boundary_loops));
            assert!(h.energy.windows(2).all(|w| w[1] < w[0]), "{:?}", h.energy);
        }
        assert!(hk.remeshed.iter().any(|&r| !r), "the default policy never kept a scaffold");
        assert!(hf.remeshed.iter().all(|&r| r));
        // Both minimise the same energy from the same start: the same result to 2 % of the
        // remaining distortion (energy − 1), with fewer analyses.
        let (ek, ef, e0) = (*hk.energy.last().unwrap(), *hf.energy.last().unwrap(), hk.energy[0]);
        eprintln!("kept {ek} ({} analyses) vs re-meshed {ef} ({} analyses), start {e0}", hk.analyses, hf.analyses);
        assert!((ek - ef).abs() < 0.02 * (ef - 1.0), "kept {ek} vs re-meshed {ef} from {e0}");
        assert!(hk.analyses < hf.analyses);
    }
}
