//! Peel: uncross the outline of a large piece by making the few faces where it crosses itself
//! an island of their own, instead of solving the piece again or splitting it.
//!
//! Precedent: xatlas and PartUV split a chart until its map is valid. On a large piece whose
//! map keeps the rule everywhere but at a few places where its outline crosses itself, the
//! split throws the solve away and solves two halves again: on fertility subdivided three
//! times (576k triangles) with `slim`, the one chart's map had a single pair of crossing
//! segments among 4,864, and its 34 s solve was followed by a split and 21 s of solves of
//! the halves. Removing faces from a flip-free map leaves the rest flip-free with the same
//! density, so the rest keeps its UVs and only the peeled faces are solved again.
//!
//! For a piece of at least [`PEEL_FROM`] triangles whose only problem is an outline that
//! crosses itself:
//! 1. the patch: where the outline crosses itself, triangles of its two sides overlap (on
//!    fertility, along a strip whose patch took 7,866 faces: one crossing pair of segments
//!    says little of how much overlaps). Overlapping triangles joined by shared vertices
//!    make sides; for each overlapping pair, the side of smaller 3D area is peeled (then, as
//!    a second try, the other). The patch is the faces within `r` rings (by shared vertices) of the
//!    peeled triangles' vertices, for `r` in [`RINGS`], never more than [`MAX_PATCH_SHARE`]
//!    of the piece's faces. An outline that only touches itself overlaps no triangle: the
//!    touching segments ([`crate::metrics::closed_seams::outline_crossings`]) stand in for them.
//!    Where it does both (two sides of a cut lying on each other nearly, as across rough
//!    surface, besides overlapping triangles elsewhere), a third try peels one side of the
//!    overlaps and both segments of every crossing;
//! 2. the piece rebuilt with the patch's border as seams (and without the piece's own cuts
//!    that run inside the patch, so a patch that straddles a cut is one piece, not a scatter
//!    of small islands; the user's seams and earlier splits' stay): the rest keeps its UVs and
//!    is measured again, the patch's pieces are solved with the method. A patch piece that
//!    breaks the rule as it is (a ring of faces around a hole of the surface is an annulus;
//!    on rough surface the cuts joining holes cross their own sides) takes the pipeline's
//!    road without a split (its holes joined to its outline, cones), then the last resort
//!    ([`super::last_resort`]): a small island by another method rather than the whole
//!    piece split and solved again;
//! 3. the first attempt whose pieces all keep the rule replaces the piece, its border added
//!    to the seams. Otherwise the piece is left as it was (the repair's rounds and split
//!    follow as before).
//!
//! Smaller pieces are peeled too, once the repair has done all it can (every split level and
//! the last resort) and the outline still crosses itself: on the beetle with a vertex
//! collapsed onto a neighbour in 1% of its triangles (the surface folds over there), `abf`
//! left one island of 38,656 faces whose outline crossed itself, and `scaffold` stalled on
//! it; peeled, it is three islands that keep the rule.
//!
//! A piece that folds at a few faces (flipped or zero-area UV triangles in at most
//! [`MAX_FLIPPED_FACES`] faces) is peeled the same way: from [`FLIPS_PEEL_FROM`] triangles
//! after every solve of the repair (its outline may cross itself too: the patch then holds
//! the crossings' side as well), and at any size once the repair has done all it can, when
//! the last resort does not bring it within the rule ([`apply_flips`], from `super::repair`).
//! The patch is the faces within `r` rings of the folded faces' corners, with the fewest
//! faces that join it to the piece's outline (so the rest stays a disk, not a ring around a
//! hole). `arap`, which stops at its iteration cap with a few faces folded, is the case met:
//! on the shared meshes subdivided twice (88k–618k triangles) every cone round and split
//! left such folds (each round a whole solve), and the camel's head took 92 s, the lion
//! 63 s, the cow 25 s and the bunny 22 s; peeled after their solve, 7.8, 6.1, 3.8 and 2.9 s.
//! On a surface with collapsed triangles, `arap` left a small piece folded at one face after
//! every split, which the last resort's `scaffold` mapped beyond the density bound.
//!
//! Bounded: at most `3 × RINGS.len()` rebuilds of a piece. Deterministic: overlapping pairs
//! and sides in index order, rings and borders in face order.

use super::outcome::{ChartStatus, Problem};
use super::solve::{measure, solve_chart};
use super::{Context, Piece};
use crate::charts::{build_charts_with, Chart};

/// Pieces with fewer triangles are not peeled: the repair's one-cone round and split cost
/// little there, and they keep the piece whole or in halves instead of adding small islands.
pub const PEEL_FROM: usize = 100_000;

/// Pieces with fewer triangles that fold at a few faces are peeled only once the repair has
/// done all it can ([`apply_flips`] from `super::repair`); from this size a cone round or a
/// split is a costly solve that leaves such folds where they were (see the module docs).
pub const FLIPS_PEEL_FROM: usize = 50_000;

/// Most pairs of touching or crossing outline segments whose faces a peel takes (when no
/// triangles overlap, or in its last try).
pub const MAX_TOUCHES: usize = 64;

/// Rings of faces around the crossings tried, in order.
pub const RINGS: [usize; 3] = [1, 2, 4];

/// Largest share of a piece's faces a patch may take. On a scan with many holes (the bunny
/// subdivided twice with 100 holes of 30 faces, `tests/scan_holes.rs`) the cuts joining the
/// holes cross their own sides at 50 places, and the patch around them takes 10.6% of the
/// faces: with 5% the peel gave up, and the chart was split four levels deep (52 solves, 30 s)
/// to be mapped by another method in the end. With `slim` on another draw of the holes the
/// overlapping sides took 21%: with 15% the chart was split eight times (10.5 s, 6 of 12
/// islands by `scaffold`, the largest 19,519 faces); with 25% it is peeled (3.3 s, 1 of 27
/// islands by `scaffold`, the largest 58,690 faces).
pub const MAX_PATCH_SHARE: f64 = 0.25;

/// The note a peeled piece's report carries.
const NOTE: &str = "its outline crossed itself: the faces there were made an island of their own";

/// The note a piece peeled for its flips carries ([`apply_flips`]).
const FLIPS_NOTE: &str = "some of its triangles folded: the faces there were made an island of their own";

/// Peel every piece of `pieces` that qualifies (see the module docs): whose outline crosses
/// itself, from [`PEEL_FROM`] triangles, or that folds at a few faces, from
/// [`FLIPS_PEEL_FROM`]; `original`: the chart a piece without a chart of its own stands for.
pub fn apply(ctx: &Context<'_, '_>, original: &Chart, base_seams: &[[u32; 2]], pieces: &mut Vec<Piece>) {
    apply_from(ctx, original, base_seams, pieces, PEEL_FROM);
    apply_flips(ctx, original, base_seams, pieces, FLIPS_PEEL_FROM);
}

/// [`apply`] to pieces of at least `min_triangles` triangles (0: the repair's last step, see
/// the module docs).
pub(super) fn apply_from(
    ctx: &Context<'_, '_>,
    original: &Chart,
    base_seams: &[[u32; 2]],
    pieces: &mut Vec<Piece>,
    min_triangles: usize,
) {
    apply_to(ctx, original, base_seams, pieces, min_triangles, Problem::Overlap);
}

/// Peel the faces with flipped or zero-area UV triangles out of every piece of at least
/// `min_triangles` triangles that [`folds_at_few`] faces (see the module docs).
pub(super) fn apply_flips(
    ctx: &Context<'_, '_>,
    original: &Chart,
    base_seams: &[[u32; 2]],
    pieces: &mut Vec<Piece>,
    min_triangles: usize,
) {
    apply_to(ctx, original, base_seams, pieces, min_triangles, Problem::Flips);
}

/// Whether the first problem of `piece` is flipped or zero-area UV triangles, in at most
/// [`MAX_FLIPPED_FACES`] faces.
pub(super) fn folds_at_few(ctx: &Context<'_, '_>, piece: &Piece) -> bool {
    ctx.rule.full
        && ctx.rule.broken(&piece.report) == Some(Problem::Flips)
        && piece.face_flips.iter().filter(|&&n| n > 0).count() <= MAX_FLIPPED_FACES
}

/// Most faces with flipped or zero-area UV triangles a piece may have to be peeled
/// ([`apply_flips`]): more is a map that folds, not a few faces that do.
pub const MAX_FLIPPED_FACES: usize = 64;

/// [`apply_from`] for pieces whose first problem is `problem` (an outline that crosses itself,
/// or flips).
fn apply_to(
    ctx: &Context<'_, '_>,
    original: &Chart,
    base_seams: &[[u32; 2]],
    pieces: &mut Vec<Piece>,
    min_triangles: usize,
    problem: Problem,
) {
    let mut k = 0;
    while k < pieces.len() {
        let replaced = {
            let p = &pieces[k];
            let chart = p.chart.as_ref().unwrap_or(original);
            let due = chart.triangles.len() >= min_triangles
                && p.report.status.mapped()
                && ctx.rule.broken(&p.report) == Some(problem)
                && (problem != Problem::Flips || folds_at_few(ctx, p))
                && !super::pinned(ctx, chart);
            if due {
                peel(ctx, chart, base_seams, p)
            } else {
                None
            }
        };
        match replaced {
            Some(new) => {
                let n = new.len();
                pieces.splice(k..k + 1, new);
                ctx.clock.add(|p| p.peels += 1);
                k += n;
            }
            None => k += 1,
        }
    }
}

/// The pieces that replace `piece` (of `chart`), or `None` when no attempt keeps the rule.
fn peel(ctx: &Context<'_, '_>, chart: &Chart, base_seams: &[[u32; 2]], piece: &Piece) -> Option<Vec<Piece>> {
    let uv = piece.uv.as_ref()?;
    let polygons = crate::cuts::graph::face_polygons(ctx.mesh, chart);
    let vertex_faces = vertex_faces(&polygons, chart.positions.len());
    // The piece's own seams: every outline edge (slits included, whose two sides are both in
    // the piece).
    let outline = super::outline_pairs(chart);
    let mut mask = vec![false; ctx.mesh.n_faces()];
    // Chart face of every mesh face of the piece, and where its corners start.
    let mut face_at = vec![u32::MAX; ctx.mesh.n_faces()];
    let mut corner_start = Vec::with_capacity(polygons.len());
    let mut at = 0usize;
    for (i, &f) in chart.faces.iter().enumerate() {
        mask[f as usize] = true;
        face_at[f as usize] = i as u32;
        corner_start.push(at);
        at += polygons[i].len();
    }
    let limit = (MAX_PATCH_SHARE * polygons.len() as f64) as usize;
    // The seams given before this piece's cuts (the user's, earlier splits'), sorted pairs.
    let mut kept: Vec<[u32; 2]> = base_seams.iter().map(|&[a, b]| [a.min(b), a.max(b)]).collect();
    kept.sort_unstable();
    // Where the outline crosses itself, the triangles on its two sides overlap (often along
    // a strip, not at one point): the patch holds the overlapping triangles of one side. An
    // outline that only touches itself overlaps no triangle: the patch holds the touching
    // segments of one side. A piece that folds holds the corners of its folded faces too
    // (with the sides of its crossings, when its outline also crosses itself).
    let folds = piece.report.flips > 0;
    let (overlapping, touching) = if piece.report.overlap {
        let loops = &chart.boundary_loops;
        let touching =
            crate::metrics::closed_seams::outline_crossings(&chart.positions, &chart.triangles, uv, loops, MAX_TOUCHES);
        (overlap_sides(chart, uv), touching)
    } else {
        ([Vec::new(), Vec::new()], Vec::new())
    };
    let folded: Vec<u32> = {
        let mut corners: Vec<u32> = piece
            .face_flips
            .iter()
            .zip(&polygons)
            .filter(|(&n, _)| n > 0)
            .flat_map(|(_, poly)| poly.iter().copied())
            .collect();
        corners.sort_unstable();
        corners.dedup();
        corners
    };
    let mut sides: Vec<Vec<u32>> = if !piece.report.overlap {
        vec![folded.clone()]
    } else if overlapping.iter().all(|s| s.is_empty()) {
        [0, 1].map(|k| touching.iter().flat_map(|c| c[k]).collect()).to_vec()
    } else {
        overlapping.to_vec()
    };
    if !overlapping[0].is_empty() && !touching.is_empty() {
        // Last: where the outline crosses itself without triangles overlapping (two sides of
        // a cut lying on each other nearly, as across rough surface), the rest would still
        // cross itself: one side of the overlaps and both segments of every crossing.
        let mut both = overlapping[0].clone();
        both.extend(touching.iter().flat_map(|c| c[0].into_iter().chain(c[1])));
        sides.push(both);
    }
    for side in &mut sides {
        side.extend_from_slice(&folded);
        side.sort_unstable();
        side.dedup();
    }
    for seeds in sides.iter().filter(|s| !s.is_empty()) {
        for &r in &RINGS {
            let mut patch = rings(&polygons, &vertex_faces, seeds, r);
            if folds {
                // Faces that fold inside the piece: the patch reaches the outline, so the rest
                // stays a disk rather than a ring around it.
                reach_outline(chart, &polygons, &vertex_faces, &mut patch);
            }
            if patch.iter().filter(|&&x| x).count() > limit {
                break;
            }
            let border = border_edges(chart, &polygons, &vertex_faces, &patch);
            if border.is_empty() {
                continue;
            }
            // The cuts made for this piece with both sides in the patch are undone there (the
            // patch's pieces are cut again on their own road): a patch that straddles a cut is
            // one piece, not a scatter of small islands. The user's seams and those of earlier
            // splits stay.
            let inner = inner_edges(chart, &polygons, &patch);
            let mut seams: Vec<[u32; 2]> = outline
                .iter()
                .filter(|e| inner.binary_search(e).is_err() || kept.binary_search(e).is_ok())
                .copied()
                .collect();
            seams.extend_from_slice(&border);
            seams.sort_unstable();
            seams.dedup();
            let rebuilt = build_charts_with(ctx.mesh, &seams, Some(&mask), ctx.render);
            let mut out: Vec<Piece> = Vec::with_capacity(rebuilt.len());
            let mut valid = true;
            for c in rebuilt {
                c.inherit_vertex_order(chart);
                let in_patch = patch[face_at[c.faces[0] as usize] as usize];
                let (report, uv, flips) = if in_patch {
                    solve_chart(&c, ctx.pins, ctx.options, &ctx.rule)
                } else {
                    keep_uvs(ctx, chart, piece, uv, &c, &face_at, &corner_start)
                };
                let keeps = report.status.mapped() && ctx.rule.broken(&report).is_none();
                if keeps {
                    out.push(Piece::new(Some(c), report, uv, flips, Vec::new()));
                    continue;
                }
                if !in_patch {
                    valid = false;
                    break;
                }
                // A patch piece that breaks the rule as it is (a ring of faces around a hole
                // of the surface is an annulus) takes the pipeline's road without a split: its
                // holes joined to its outline, cones; then the last resort (a small island by
                // another method rather than the whole piece solved again or split).
                let mut list = super::run(ctx, c, &seams, crate::cuts::MAX_SPLIT_DEPTH);
                let keep = |p: &Piece| p.report.status.mapped() && ctx.rule.broken(&p.report).is_none();
                if !list.iter().all(keep) {
                    super::last_resort::apply(ctx, chart, &mut list, "its cones");
                }
                valid = list.iter().all(keep);
                out.extend(list);
                if !valid {
                    break;
                }
            }
            if valid && !out.is_empty() {
                // The piece's cuts undone inside the patch are seams no more.
                let undone = |e: &[u32; 2]| {
                    let e = [e[0].min(e[1]), e[0].max(e[1])];
                    inner.binary_search(&e).is_ok() && kept.binary_search(&e).is_err()
                };
                let (gone, mut seams): (Vec<[u32; 2]>, Vec<[u32; 2]>) = piece.seams.iter().partition(|e| undone(e));
                let length = super::repair::split_length(ctx.mesh, &border)
                    - super::repair::split_length(ctx.mesh, &gone);
                seams.extend_from_slice(&border);
                let first = &mut out[0];
                // (a patch piece that took the pipeline's road carries the cuts made there)
                seams.append(&mut first.seams);
                first.seams = seams;
                first.report.cones = piece.report.cones;
                first.report.cut_length = piece.report.cut_length + length;
                return Some(out);
            }
        }
    }
    None
}

/// The vertices of the overlapping triangles of `chart` under `uv` to peel, two ways: for
/// each pair of overlapping triangles, the one of the side (its overlapping triangles joined
/// by shared vertices) of smaller area, and the other one. Empty when no triangles overlap.
fn overlap_sides(chart: &Chart, uv: &[[f64; 2]]) -> [Vec<u32>; 2] {
    let pairs = overlapping_triangles(&chart.triangles, uv);
    if pairs.is_empty() {
        return [Vec::new(), Vec::new()];
    }
    // Sides: the overlapping triangles joined by shared vertices.
    let mut tris: Vec<u32> = pairs.iter().flat_map(|p| [p.0, p.1]).collect();
    tris.sort_unstable();
    tris.dedup();
    let mut uf = crate::charts::UnionFind::new(chart.positions.len());
    for &t in &tris {
        let [a, b, c] = chart.triangles[t as usize];
        uf.union(a, b);
        uf.union(b, c);
    }
    let mut area: std::collections::BTreeMap<u32, f64> = Default::default();
    for &t in &tris {
        let [a, b, c] = chart.triangles[t as usize];
        let p = [chart.positions[a as usize], chart.positions[b as usize], chart.positions[c as usize]];
        *area.entry(uf.find(a)).or_insert(0.0) += crate::geometry::triangle_area(p);
    }
    // Per pair, the side to remove: the smaller one (ties to the lower root), unless one of the
    // two is removed already; and the other way round.
    let mut removed: [std::collections::BTreeSet<u32>; 2] = Default::default();
    for &(s, t) in &pairs {
        let (rs, rt) = (uf.find(chart.triangles[s as usize][0]), uf.find(chart.triangles[t as usize][0]));
        let small = if (area[&rs], rs) <= (area[&rt], rt) { (rs, rt) } else { (rt, rs) };
        for (k, pick) in [(0, small.0), (1, small.1)] {
            if !removed[k].contains(&rs) && !removed[k].contains(&rt) {
                removed[k].insert(pick);
            }
        }
    }
    let mut vertices = |roots: &std::collections::BTreeSet<u32>| {
        let mut v: Vec<u32> = tris
            .iter()
            .flat_map(|&t| chart.triangles[t as usize])
            .filter(|&v| roots.contains(&uf.find(v)))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let first = vertices(&removed[0]);
    [first, vertices(&removed[1])]
}

/// Pairs `(s, t)`, `s < t`, of triangles that share no vertex and whose UV interiors
/// overlap, sorted. Candidates come from [`crate::geometry::box_grid`] (a map that crushes a
/// region packs thousands of triangles where a uniform grid has one cell); triangles of zero
/// UV area have no interior and are left out.
fn overlapping_triangles(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> Vec<(u32, u32)> {
    let corners = |t: usize| triangles[t].map(|v| uv[v as usize]);
    let boxes: Vec<crate::geometry::box_grid::Box2> = (0..triangles.len())
        .map(|t| {
            let [a, b, c] = corners(t);
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if area == 0.0 {
                return ([f64::NAN; 2], [f64::NAN; 2]); // skipped by the broad phase
            }
            ([a[0].min(b[0]).min(c[0]), a[1].min(b[1]).min(c[1])], [a[0].max(b[0]).max(c[0]), a[1].max(b[1]).max(c[1])])
        })
        .collect();
    crate::geometry::box_grid::overlapping_pairs(&boxes, |s, t| {
        let (s, t) = (s as usize, t as usize);
        !triangles[s].iter().any(|v| triangles[t].contains(v)) && interiors_overlap(corners(s), corners(t))
    })
}

/// Whether two UV triangles' interiors overlap: no edge direction of either separates them
/// (the rule's separating-axis test with no tolerance; touching counts as apart).
fn interiors_overlap(a: [[f64; 2]; 3], b: [[f64; 2]; 3]) -> bool {
    crate::metrics::closed_seams::interiors_overlap(a, b, 0.0)
}

/// The rest `c` of `piece` (of `chart`) with the piece's UVs, measured again.
fn keep_uvs(
    ctx: &Context<'_, '_>,
    chart: &Chart,
    piece: &Piece,
    uv: &[[f64; 2]],
    c: &Chart,
    face_at: &[u32],
    corner_start: &[usize],
) -> (super::outcome::ChartReport, Option<Vec<[f64; 2]>>, Vec<u32>) {
    // Corners come in face order in both charts: a face's corners in `c` are its corners in
    // `chart`, in the same order.
    let mut new_uv = vec![[0.0; 2]; c.positions.len()];
    let mut at = 0usize;
    for &f in &c.faces {
        let m = ctx.mesh.face_corners(f as usize).len();
        let from = corner_start[face_at[f as usize] as usize];
        for k in 0..m {
            new_uv[c.corner_vertex[at + k].1 as usize] = uv[chart.corner_vertex[from + k].1 as usize];
        }
        at += m;
    }
    let mut report = super::outcome::ChartReport::new(c, piece.report.method);
    // A fallback's report names the method that mapped it (the rule's check replaced its
    // status and problem).
    let fell_back = piece.report.method != ctx.options.method.name();
    report.status = if fell_back { ChartStatus::Fallback } else { ChartStatus::Solved };
    report.problem = fell_back.then_some(Problem::FellBack);
    // The piece's note without the overlap or flips the rule found (they are gone).
    let (found, note) = if piece.report.flips > 0 {
        (super::solve::flips_note(piece.report.flips), FLIPS_NOTE)
    } else {
        (super::solve::OVERLAP_NOTE.to_string(), NOTE)
    };
    report.reason = piece
        .report
        .reason
        .as_deref()
        .map(|r| r.trim_end_matches(found.as_str()).trim_end_matches("; ").to_string())
        .filter(|r| !r.is_empty());
    super::solve::append(&mut report.reason, note.to_string());
    report.iterations = piece.report.iterations;
    report.residual = piece.report.residual;
    report.seconds = piece.report.seconds;
    match measure(c, &new_uv, &mut report, &ctx.rule) {
        Some(flips) => (report, Some(new_uv), flips),
        None => (report, None, Vec::new()),
    }
}

/// Add to `patch` (faces of `chart`, `polygons` their corners) the fewest faces, joined by
/// edges, that join it to the chart's outline (nothing when a face of the patch touches the
/// outline already). Deterministic: breadth-first in face order.
fn reach_outline(chart: &Chart, polygons: &[Vec<u32>], vertex_faces: &[Vec<u32>], patch: &mut [bool]) {
    let mut on_outline = vec![false; chart.positions.len()];
    for &v in chart.boundary_loops.iter().flatten() {
        on_outline[v as usize] = true;
    }
    let touches = |f: usize| polygons[f].iter().any(|&v| on_outline[v as usize]);
    let mut from = vec![u32::MAX; polygons.len()];
    let mut queue = std::collections::VecDeque::new();
    for f in 0..polygons.len() {
        if patch[f] {
            if touches(f) {
                return;
            }
            from[f] = f as u32;
            queue.push_back(f);
        }
    }
    while let Some(f) = queue.pop_front() {
        let poly = &polygons[f];
        for i in 0..poly.len() {
            let (a, b) = (poly[i] as usize, poly[(i + 1) % poly.len()] as usize);
            for &g in &vertex_faces[a] {
                let g = g as usize;
                if from[g] != u32::MAX || !vertex_faces[b].contains(&(g as u32)) {
                    continue;
                }
                from[g] = f as u32;
                if touches(g) {
                    let mut k = g;
                    while !patch[k] {
                        patch[k] = true;
                        k = from[k] as usize;
                    }
                    return;
                }
                queue.push_back(g);
            }
        }
    }
}

/// The faces around every vertex, in face order.
fn vertex_faces(polygons: &[Vec<u32>], n: usize) -> Vec<Vec<u32>> {
    let mut out: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, poly) in polygons.iter().enumerate() {
        for &v in poly {
            if out[v as usize].last() != Some(&(f as u32)) {
                out[v as usize].push(f as u32);
            }
        }
    }
    out
}

/// Faces within `r` rings of `seeds`: ring 1 holds the faces at a seed vertex, each further
/// ring the faces that share a vertex with the one before.
fn rings(polygons: &[Vec<u32>], vertex_faces: &[Vec<u32>], seeds: &[u32], r: usize) -> Vec<bool> {
    let mut inside = vec![false; polygons.len()];
    let mut front: Vec<u32> = seeds.to_vec();
    for _ in 0..r {
        let mut next = Vec::new();
        for &v in &front {
            for &f in &vertex_faces[v as usize] {
                if !inside[f as usize] {
                    inside[f as usize] = true;
                    next.extend_from_slice(&polygons[f as usize]);
                }
            }
        }
        next.sort_unstable();
        next.dedup();
        front = next;
    }
    inside
}

/// Edges between a face of `patch` and a face outside it, as sorted mesh vertex pairs.
fn border_edges(chart: &Chart, polygons: &[Vec<u32>], vertex_faces: &[Vec<u32>], patch: &[bool]) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    for (f, poly) in polygons.iter().enumerate() {
        if !patch[f] {
            continue;
        }
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let across =
                vertex_faces[a as usize].iter().any(|&g| !patch[g as usize] && polygons[g as usize].contains(&b));
            if across {
                out.push(mesh_pair(chart, a, b));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Mesh edges (sorted pairs, sorted) of which two faces of `patch` are sides: the chart's
/// own cuts running inside the patch.
fn inner_edges(chart: &Chart, polygons: &[Vec<u32>], patch: &[bool]) -> Vec<[u32; 2]> {
    let mut sides: Vec<[u32; 2]> = Vec::new();
    for (f, poly) in polygons.iter().enumerate() {
        if patch[f] {
            for i in 0..poly.len() {
                sides.push(mesh_pair(chart, poly[i], poly[(i + 1) % poly.len()]));
            }
        }
    }
    sides.sort_unstable();
    let mut out: Vec<[u32; 2]> = sides.windows(2).filter(|w| w[0] == w[1]).map(|w| w[0]).collect();
    out.dedup();
    out
}

/// The mesh vertices of chart vertices `a` and `b`, sorted.
fn mesh_pair(chart: &Chart, a: u32, b: u32) -> [u32; 2] {
    let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
    [ma.min(mb), ma.max(mb)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::outcome::ChartReport;
    use crate::pipeline::rule::AtlasRule;
    use crate::unwrap::UnwrapOptions;

    #[test]
    fn triangle_interiors_overlap_only_when_no_axis_separates_them() {
        let t = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let moved = |dx: f64, dy: f64| t.map(|p| [p[0] + dx, p[1] + dy]);
        assert!(interiors_overlap(t, moved(0.2, 0.2)));
        assert!(interiors_overlap(t, [[0.1, 0.1], [0.2, 0.1], [0.1, 0.2]]), "one inside the other");
        assert!(!interiors_overlap(t, moved(2.0, 0.0)));
        assert!(!interiors_overlap(t, moved(1.0, 0.0)), "touching at a corner");
        // Sharing the hypotenuse from the other side: touching, not overlapping.
        assert!(!interiors_overlap(t, [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]));
        // Apart along the hypotenuse's normal only (both boxes overlap).
        assert!(!interiors_overlap(t, [[0.6, 0.6], [1.6, 0.6], [0.6, 1.6]]));
    }

    /// A flat strip `cols × rows` of unit-ish squares (two triangles each), and its UVs laid
    /// along a circle of radius `radius` over `turn` radians: past a full turn its two ends
    /// lie on each other, though no triangle flips.
    type Strip = (Vec<[f64; 3]>, Vec<u32>, Vec<u32>, Vec<[f64; 2]>);

    fn coiled_strip(cols: usize, rows: usize, turn: f64, radius: f64) -> Strip {
        let width = 0.05 * radius;
        let length = turn * radius;
        let (positions, corners, sizes) =
            crate::pipeline::test_mesh::grid(cols, rows, length / cols as f64, width / rows as f64);
        // x along the circle, y inwards (counter-clockwise, so triangles keep their turn).
        // The radius shrinks by half the width over the strip, so its ends lie half on each
        // other (no edge of one lies along an edge of the other).
        let uv = |p: [f64; 3]| {
            let (a, r) = (p[0] / radius, radius - p[1] - 0.5 * width * p[0] / length);
            [r * a.cos(), r * a.sin()]
        };
        let uvs = positions.iter().map(|&p| uv(p)).collect();
        (positions, corners, sizes, uvs)
    }

    /// `pieces` is `chart` peeled once: two pieces or more, every face in one of them, every one
    /// within `rule`. Returns the largest (the rest).
    fn assert_peeled<'p>(ctx: &Context<'_, '_>, chart: &Chart, rule: &AtlasRule, pieces: &'p [Piece]) -> &'p Piece {
        assert!(pieces.len() >= 2, "not peeled: {:?}", pieces[0].report.reason);
        assert_eq!(ctx.clock.get().peels, 1);
        let faces: usize = pieces.iter().map(|p| p.report.faces).sum();
        assert_eq!(faces, chart.faces.len(), "faces lost or doubled");
        for p in pieces {
            assert!(p.report.status.mapped() && rule.broken(&p.report).is_none(), "{:?}", p.report.reason);
        }
        pieces.iter().max_by_key(|p| p.report.faces).unwrap()
    }

    #[test]
    fn a_coiled_strip_is_peeled_where_its_ends_overlap_and_keeps_the_rest_of_its_map() {
        let turn = 2.0 * std::f64::consts::PI * 1.03;
        let (positions, corners, sizes, vertex_uv) = coiled_strip(400, 3, turn, 10.0);
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let (chart, report, flips, uv) = measured_piece(&mesh, &vertex_uv);
        let options = UnwrapOptions::default();
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
        // The premise: flip-free and within the density bound, but the outline crosses itself.
        assert_eq!(report.flips, 0);
        assert_eq!(rule.broken(&report), Some(Problem::Overlap), "{:?}", report.reason);
        let pins = std::collections::HashMap::new();
        let avoid = vec![false; positions.len()];
        let ctx = Context::new(&mesh, None, &pins, &options, &avoid);
        let run = || {
            let piece = Piece::new(Some(chart.clone()), report.clone(), Some(uv.clone()), flips.clone(), Vec::new());
            let mut pieces = vec![piece];
            apply_from(&ctx, &chart, &[], &mut pieces, 0);
            pieces
        };
        let pieces = run();
        // The largest piece is the rest of the strip with its UVs exactly as they were, and
        // the patch is small.
        let rest = assert_peeled(&ctx, &chart, &rule, &pieces);
        assert!(rest.report.faces as f64 >= (1.0 - MAX_PATCH_SHARE) * chart.faces.len() as f64);
        let rest_chart = rest.chart.as_ref().unwrap();
        let rest_uv = rest.uv.as_ref().unwrap();
        for (v, &m) in rest_chart.mesh_vertex.iter().enumerate() {
            assert_eq!(rest_uv[v], vertex_uv[m as usize], "vertex {m} moved");
        }
        assert!(rest.report.reason.as_deref().is_some_and(|r| r.contains(NOTE) && !r.contains("crosses itself")));
        // The patch's border became seams, carried by the first piece.
        assert!(!pieces[0].seams.is_empty() && pieces[0].report.cut_length > 0.0);
        // Deterministic.
        let again = run();
        assert_eq!(again.len(), pieces.len());
        for (a, b) in again.iter().zip(&pieces) {
            assert_eq!(a.uv, b.uv);
            assert_eq!(a.seams, b.seams);
        }
    }

    /// A flat 20 × 20 grid mapped by its own plane, with the UVs of inner `vertices` (column,
    /// row) moved past their neighbours (`push` grid steps along x): the faces around fold.
    fn folded_grid(push: f64, vertices: &[(usize, usize)]) -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>, Vec<[f64; 2]>) {
        let n = 20;
        let (positions, corners, sizes) = crate::pipeline::test_mesh::grid(n, n, 1.0, 1.0);
        let mut uv: Vec<[f64; 2]> = positions.iter().map(|p| [p[0], p[1]]).collect();
        for &(i, j) in vertices {
            let v = j * (n + 1) + i;
            uv[v][0] += push;
            uv[v][1] += 0.3;
        }
        (positions, corners, sizes, uv)
    }

    type Measured = (Chart, ChartReport, Vec<u32>, Vec<[f64; 2]>);

    /// The one chart of `mesh`, its UVs from `vertex_uv`, its report held to the full rule and
    /// its flips per face.
    fn measured_piece(mesh: &crate::mesh::PolyMesh<'_>, vertex_uv: &[[f64; 2]]) -> Measured {
        let charts = crate::charts::build_charts(mesh, &[], None);
        assert_eq!(charts.len(), 1);
        let chart = charts.into_iter().next().unwrap();
        let uv: Vec<[f64; 2]> = chart.mesh_vertex.iter().map(|&v| vertex_uv[v as usize]).collect();
        let options = UnwrapOptions::default();
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
        let mut report = ChartReport::new(&chart, options.method.name());
        report.status = ChartStatus::Solved;
        let flips = measure(&chart, &uv, &mut report, &rule).unwrap();
        (chart, report, flips, uv)
    }

    #[test]
    fn a_piece_that_folds_at_a_few_faces_is_peeled_there_and_keeps_the_rest_of_its_map() {
        let (positions, corners, sizes, vertex_uv) = folded_grid(2.5, &[(9, 7)]);
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let (chart, report, flips, uv) = measured_piece(&mesh, &vertex_uv);
        let options = UnwrapOptions::default();
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
        // The premise: a few faces fold, and that is the first problem.
        let folded = flips.iter().filter(|&&k| k > 0).count();
        assert!((1..=MAX_FLIPPED_FACES).contains(&folded), "{folded} faces fold");
        assert_eq!(rule.broken(&report), Some(Problem::Flips), "{:?}", report.reason);
        let pins = std::collections::HashMap::new();
        let avoid = vec![false; mesh.n_vertices()];
        let ctx = Context::new(&mesh, None, &pins, &options, &avoid);
        let piece = Piece::new(Some(chart.clone()), report.clone(), Some(uv.clone()), flips.clone(), Vec::new());
        assert!(folds_at_few(&ctx, &piece));
        let mut pieces = vec![piece];
        apply_flips(&ctx, &chart, &[], &mut pieces, 0);
        // The rest keeps its UVs exactly, says why it was peeled, and no longer reports flips.
        let rest = assert_peeled(&ctx, &chart, &rule, &pieces);
        // The patch: the faces around the fold and a strip to the outline (7 rows away).
        let patch = chart.faces.len() - rest.report.faces;
        assert!(patch <= chart.faces.len() / 20, "a patch of {patch} faces");
        let rest_chart = rest.chart.as_ref().unwrap();
        let rest_uv = rest.uv.as_ref().unwrap();
        for (v, &m) in rest_chart.mesh_vertex.iter().enumerate() {
            let k = chart.mesh_vertex.iter().position(|&x| x == m).unwrap();
            assert_eq!(rest_uv[v], uv[k], "vertex {m} moved");
        }
        let why = rest.report.reason.as_deref().unwrap_or_default();
        assert!(why.contains(FLIPS_NOTE) && !why.contains("flipped or zero-area"), "{why}");
    }

    #[test]
    fn a_piece_that_folds_at_a_few_faces_and_whose_outline_crosses_itself_is_peeled_at_both() {
        // The coiled strip, its ends on each other, with one inner vertex pushed past its
        // neighbours along the strip halfway between: flips come first, the outline crosses
        // itself too (as `arap` leaves a large chart it has not converged on).
        let turn = 2.0 * std::f64::consts::PI * 1.03;
        let (cols, rows) = (400, 12);
        let (positions, corners, sizes, mut vertex_uv) = coiled_strip(cols, rows, turn, 10.0);
        let v = 2 * (cols + 1) + cols / 2;
        vertex_uv[v] = vertex_uv[v + 3];
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let (chart, report, flips, uv) = measured_piece(&mesh, &vertex_uv);
        let options = UnwrapOptions::default();
        let rule = AtlasRule { max_stretch: options.auto_seams.max_stretch, full: true };
        assert!(report.flips > 0 && report.overlap, "{:?}", report.reason);
        let pins = std::collections::HashMap::new();
        let avoid = vec![false; positions.len()];
        let ctx = Context::new(&mesh, None, &pins, &options, &avoid);
        let piece = Piece::new(Some(chart.clone()), report, Some(uv), flips, Vec::new());
        assert!(folds_at_few(&ctx, &piece));
        // Only pieces of the size asked are peeled.
        let mut pieces = vec![piece.clone()];
        apply_flips(&ctx, &chart, &[], &mut pieces, chart.triangles.len() + 1);
        assert_eq!(pieces.len(), 1);
        assert_eq!(ctx.clock.get().peels, 0);
        let mut pieces = vec![piece];
        apply_flips(&ctx, &chart, &[], &mut pieces, chart.triangles.len());
        assert_peeled(&ctx, &chart, &rule, &pieces);
        // The patch is small; the rest keeps the UVs it had.
        let rest: Vec<&Piece> = pieces.iter().filter(|p| p.report.faces >= chart.faces.len() / 10).collect();
        let kept: usize = rest.iter().map(|p| p.report.faces).sum();
        assert!(kept as f64 >= (1.0 - MAX_PATCH_SHARE) * chart.faces.len() as f64, "{kept} faces kept");
        for p in rest {
            let c = p.chart.as_ref().unwrap();
            for (v, &m) in c.mesh_vertex.iter().enumerate() {
                assert_eq!(p.uv.as_ref().unwrap()[v], vertex_uv[m as usize], "vertex {m} moved");
            }
        }
    }

    #[test]
    fn a_piece_that_folds_at_many_faces_is_not_peeled() {
        // Every third vertex of every other inner row folds its faces: a map that folds, not a
        // few faces that do.
        let pushed: Vec<(usize, usize)> =
            (2..18).step_by(2).flat_map(|j| (1..19).step_by(3).map(move |i| (i, j))).collect();
        let (positions, corners, sizes, vertex_uv) = folded_grid(2.5, &pushed);
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let (chart, report, flips, uv) = measured_piece(&mesh, &vertex_uv);
        assert!(flips.iter().filter(|&&k| k > 0).count() > MAX_FLIPPED_FACES);
        let options = UnwrapOptions::default();
        let pins = std::collections::HashMap::new();
        let avoid = vec![false; mesh.n_vertices()];
        let ctx = Context::new(&mesh, None, &pins, &options, &avoid);
        let mut pieces = vec![Piece::new(Some(chart.clone()), report, Some(uv.clone()), flips, Vec::new())];
        assert!(!folds_at_few(&ctx, &pieces[0]));
        apply_flips(&ctx, &chart, &[], &mut pieces, 0);
        assert_eq!(pieces.len(), 1);
        assert_eq!(pieces[0].uv.as_ref(), Some(&uv));
        assert_eq!(ctx.clock.get().peels, 0);
    }

    #[test]
    fn a_strip_short_of_a_turn_is_left_alone() {
        // No crossing: nothing to peel, the piece stays as it is.
        let (positions, corners, sizes, vertex_uv) = coiled_strip(200, 2, 5.0, 10.0);
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let chart = crate::charts::build_charts(&mesh, &[], None).into_iter().next().unwrap();
        let uv: Vec<[f64; 2]> = chart.mesh_vertex.iter().map(|&v| vertex_uv[v as usize]).collect();
        assert!(overlapping_triangles(&chart.triangles, &uv).is_empty());
        assert!(crate::metrics::boundary_crossings(&uv, &chart.boundary_loops, 4).is_empty());
    }

    #[test]
    fn overlapping_triangles_are_every_overlapping_pair_of_a_map_that_crushes_a_region() {
        // A coiled strip whose ends overlap, with a stretch of it crushed a thousandfold
        // toward one point (as a conformal map crushes a region of a large chart): the pairs
        // found through the grid are the pairs found by testing every two triangles.
        let (positions, corners, sizes, mut vertex_uv) = coiled_strip(300, 3, 7.5, 10.0);
        let centre = vertex_uv[40];
        for (v, p) in vertex_uv.iter_mut().enumerate() {
            if (20..220).contains(&(v % 301)) {
                *p = [centre[0] + 1e-3 * (p[0] - centre[0]), centre[1] + 1e-3 * (p[1] - centre[1])];
            }
        }
        let mesh = crate::mesh::PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let chart = crate::charts::build_charts(&mesh, &[], None).into_iter().next().unwrap();
        let uv: Vec<[f64; 2]> = chart.mesh_vertex.iter().map(|&v| vertex_uv[v as usize]).collect();
        let t = &chart.triangles;
        let corners_of = |i: usize| t[i].map(|v| uv[v as usize]);
        let mut every = Vec::new();
        for i in 0..t.len() {
            for j in i + 1..t.len() {
                if !t[i].iter().any(|v| t[j].contains(v)) && interiors_overlap(corners_of(i), corners_of(j)) {
                    every.push((i as u32, j as u32));
                }
            }
        }
        assert!(!every.is_empty(), "the strip's ends should overlap");
        assert_eq!(overlapping_triangles(t, &uv), every);
    }
}
