//! Repair: cones and cuts, then splits, until every piece of a chart keeps the atlas rule.
//!
//! Precedents: xatlas's piecewise parameterization and PartUV's split-until-valid. Round 0
//! cuts the chart as planned by [`crate::cuts::ChartCutter`] (cones on the scale factor, handle
//! loops, holes joined to the outline); each further round adds one cone at the vertex of
//! the worst density (or a flip) of the first piece that breaks the rule, and re-cuts. The
//! best attempt is kept (fewest failures, flips, overlaps, non-disks, then the least area
//! beyond the density bound, then the fewest pieces). When no round keeps the rule, the chart
//! is halved ([`crate::cuts::split`], along the cheapest loop by the cutter's edge costs) and
//! each half goes through the pipeline again, to a bounded depth; the halves replace the chart
//! only when they are better. At the last split level the planar split is tried too when the
//! spectral one leaves a piece that breaks the rule.
//!
//! Bounded: at most `1 + REPAIR_ROUNDS` solves per chart and level, `MAX_SPLIT_DEPTH` levels.
//! Deterministic: every choice breaks ties by ids.

use super::solve::solve_chart;
use super::{Context, Piece};
use crate::charts::{build_charts_with, Chart};
use crate::cuts::{self, ChartCutter};
use crate::mesh::PolyMesh;

/// Repair `chart` (already cut along `base_seams`). `first`: the chart solved as it is, if it
/// was (it is one of the attempts). Returns the best pieces found.
pub fn repair(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]], depth: usize, first: Option<Piece>) -> Vec<Piece> {
    let t = std::time::Instant::now();
    let mask = face_mask(ctx.mesh.n_faces(), chart);
    // Graph, costs and the scale system's analysis once; each round refactors numerically.
    let cutter = ChartCutter::new(ctx.mesh, chart, &ctx.options.auto_seams, ctx.avoid);
    ctx.clock.add(|p| p.plan_cuts += t.elapsed().as_secs_f64());
    let mut seed: Vec<u32> = Vec::new();
    let mut best: Vec<Piece> = Vec::new();
    if let Some(p) = first {
        if let Some(v) = worst_vertex(chart, &p, cutter.allowed(), &[]) {
            seed.push(v);
        }
        best.push(p);
    }
    for round in 0..=cuts::REPAIR_ROUNDS {
        let t = std::time::Instant::now();
        let cut = cutter.cut(&seed, round);
        if cut.seams.is_empty() && !best.is_empty() {
            break;
        }
        let mut all: Vec<[u32; 2]> = base_seams.to_vec();
        all.extend_from_slice(&cut.seams);
        let sub = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
        ctx.clock.add(|p| p.plan_cuts += t.elapsed().as_secs_f64());
        let t = std::time::Instant::now();
        let n_pieces = sub.len();
        let mut pieces: Vec<Piece> = Vec::with_capacity(sub.len());
        for (k, c) in sub.into_iter().enumerate() {
            // A piece the cut did not open (it should not happen) breaks the rule and is
            // repaired or split like any other.
            let (mut report, uv, face_flips) = solve_chart(&c, ctx.pins, ctx.options, &ctx.rule);
            let seams = if k == 0 {
                report.cones = cut.cones.len();
                report.cut_length = cut.length;
                cut.seams.clone()
            } else {
                Vec::new()
            };
            pieces.push(Piece::new(Some(c), report, uv, face_flips, seams));
        }
        ctx.clock.add(|p| {
            p.repair_solve += t.elapsed().as_secs_f64();
            p.repair_pieces += n_pieces;
            p.repair_rounds += 1;
        });
        let valid = all_valid(ctx, &pieces);
        let next = pieces
            .iter()
            .find(|p| ctx.rule.broken(&p.report).is_some() || !p.report.status.mapped())
            .and_then(|p| worst_vertex(chart, p, cutter.allowed(), &cut.cones));
        if best.is_empty() || better(ctx, &pieces, &best) {
            best = pieces;
        }
        if valid {
            break;
        }
        match next {
            Some(v) => {
                seed = cut.cones.clone();
                seed.push(v);
            }
            None => break,
        }
    }
    if !all_valid(ctx, &best) && depth < cuts::MAX_SPLIT_DEPTH && chart.faces.len() >= 2 {
        // The spectral split; at the last split level, where the halves cannot be split again,
        // also the planar one when the first leaves a piece that breaks the rule (one more
        // attempt per chart of that level, so the work stays bounded).
        let t = std::time::Instant::now();
        let candidates = cuts::split::candidates(cutter.graph(), cutter.costs(), chart, ctx.avoid);
        ctx.clock.add(|p| p.plan_cuts += t.elapsed().as_secs_f64());
        let tries = if depth + 1 == cuts::MAX_SPLIT_DEPTH { candidates.len() } else { 1 };
        for split in candidates.into_iter().take(tries).filter(|s| !s.is_empty()) {
            ctx.clock.add(|p| p.splits += 1);
            let mut all: Vec<[u32; 2]> = base_seams.to_vec();
            all.extend_from_slice(&split);
            let halves = build_charts_with(ctx.mesh, &all, Some(&mask), ctx.render);
            let mut out = Vec::new();
            for (k, h) in halves.into_iter().enumerate() {
                // Each half takes the pipeline's road again (cut, or solve then repair).
                let mut list = super::run(ctx, h, &all, depth + 1);
                if k == 0 {
                    if let Some(p) = list.first_mut() {
                        p.seams.extend_from_slice(&split);
                        p.report.cut_length += split_length(ctx.mesh, &split);
                    }
                }
                out.extend(list);
            }
            if better(ctx, &out, &best) {
                best = out;
            }
            if all_valid(ctx, &best) {
                break;
            }
        }
    }
    best
}

/// Whether every piece is mapped and keeps the rule.
pub fn all_valid(ctx: &Context<'_, '_>, pieces: &[Piece]) -> bool {
    pieces.iter().all(|p| p.report.status.mapped() && ctx.rule.broken(&p.report).is_none())
}

/// `a` is a strictly better set of pieces than `b` (see the module docs).
fn better(ctx: &Context<'_, '_>, a: &[Piece], b: &[Piece]) -> bool {
    let total = |ps: &[Piece]| {
        let mut t = (0usize, 0usize, 0usize, 0usize, 0.0f64);
        for p in ps {
            let x = ctx.rule.badness(&p.report, p.area);
            t = (t.0 + x.0, t.1 + x.1, t.2 + x.2, t.3 + x.3, t.4 + x.4);
        }
        t
    };
    let (x, y) = (total(a), total(b));
    (x.0, x.1, x.2, x.3)
        .cmp(&(y.0, y.1, y.2, y.3))
        .then(x.4.total_cmp(&y.4))
        .then(a.len().cmp(&b.len()))
        == std::cmp::Ordering::Less
}

/// Faces of `chart` as a selection mask over the mesh.
fn face_mask(n_faces: usize, chart: &Chart) -> Vec<bool> {
    let mut mask = vec![false; n_faces];
    for &f in &chart.faces {
        mask[f as usize] = true;
    }
    mask
}

/// The vertex of `original` (allowed as a cone, not in `exclude`) nearest the most crushed
/// texel density of `piece`: triangles by increasing density ratio (a flipped or zero-area
/// triangle first), the first of their corners that maps to an allowed vertex of `original`.
fn worst_vertex(original: &Chart, piece: &Piece, allowed: &[bool], exclude: &[u32]) -> Option<u32> {
    let uv = piece.uv.as_ref()?;
    let chart = piece.chart.as_ref().unwrap_or(original);
    if chart.triangles.is_empty() {
        return None;
    }
    // Piece vertex → original vertex through the shared corners.
    let mut corner_to_original = std::collections::HashMap::with_capacity(original.corner_vertex.len());
    for &(c, v) in &original.corner_vertex {
        corner_to_original.insert(c, v);
    }
    let mut to_original = vec![u32::MAX; chart.positions.len()];
    for &(c, v) in &chart.corner_vertex {
        if let Some(&o) = corner_to_original.get(&c) {
            to_original[v as usize] = o;
        }
    }
    let ratios = crate::metrics::density::density_ratios(&chart.positions, &chart.triangles, uv);
    // Crushed triangles first (a flip or zero area, then the smallest ratio): a cone there
    // opens the surface with an angle below 2π. A cone where the density is too high would
    // take more than 2π, and its slit's sides would overlap in UV.
    let mut order: Vec<(f64, usize)> = ratios
        .iter()
        .enumerate()
        .map(|(t, &(r, _))| (if r > 0.0 { -r.ln() } else { f64::INFINITY }, t))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for (_, t) in order {
        for &v in &chart.triangles[t] {
            let o = to_original[v as usize];
            if o != u32::MAX && allowed[o as usize] && !exclude.contains(&o) {
                return Some(o);
            }
        }
    }
    None
}

/// 3D length of mesh edges given as vertex pairs.
fn split_length(mesh: &PolyMesh<'_>, seams: &[[u32; 2]]) -> f64 {
    let p = mesh.positions();
    seams.iter().map(|s| crate::geometry::norm(crate::geometry::sub(p[s[1] as usize], p[s[0] as usize]))).sum()
}
