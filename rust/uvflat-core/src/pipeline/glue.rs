//! Glue: lay the faces of small islands on the islands around them, where they fit, so an
//! atlas is not left with confetti.
//!
//! Repair leaves specks: the peel's patch pieces between cuts that cross ([`super::peel`]), a
//! few faces between a hole's cut and the outline, a split's sliver. On `3holes` with three
//! large holes `abf` made 34 islands, 28 of them under 10 faces, most of a single face. An
//! island of one face costs the artist a packing margin and a seam for nothing: laid flat
//! beside its neighbour it has no distortion to speak of.
//!
//! Precedent: xatlas and PartUV merge a small chart into a neighbour when the merged chart
//! still keeps its bound, solving the merged chart again. Here nothing is solved: the island
//! keeps its map and the face is laid rigidly beside it, so the cost is local.
//!
//! For every piece of at most [`SPECK_FACES`] faces (a speck), in piece order, each of its
//! faces is laid on a neighbouring island (a piece that is no speck, is a disk and keeps the
//! rule) across the edges it shares with it, when
//! - those edges are one run along the island's outline (not every side of the face), none
//!   of them an edge the input chart cut (a user's seam, a non-manifold edge or one between
//!   opposite normals): the island stays a disk, and the user's seams stay;
//! - the face's corners on the run take the island's UVs; its other corners are placed by the
//!   similarity that best maps the face's flattening (its projection on its Newell plane) onto
//!   them, so a face laid across one edge keeps its shape exactly;
//! - every triangle of the face (both splits of a quad) keeps its turn and has a texel density
//!   within `[1/s, s]` of the island's own (`s`: Max Stretch);
//! - the outline stays simple: the face's new sides touch no side of the island's outline
//!   (found on a grid; the segment test of the rule's own measure), and at both ends of
//!   the run the face fits in the island's open angle.
//!
//! A face with every side on one island is laid across all but one of them (the one left
//! stays a seam), each side in turn, when it has at most [`MAX_CLOSING_CORNERS`] corners.
//!
//! A face that fits nowhere is tried again once more of its speck is laid. A speck is glued
//! when every face of it is laid (on one island or several); otherwise what was laid for it is
//! undone. Each island that took faces is then rebuilt and measured on its render triangles;
//! if it breaks the rule, its specks are left as they were and the pass runs again without
//! them (at most [`MAX_PASSES`] passes; after that nothing is glued).
//!
//! Seams: the edges a face was laid across are seams no more; the edges between faces of one
//! speck that were not laid across each other become seams, so the seams reported stay
//! exactly the islands' borders.
//!
//! Preconditions: automatic seams on (the full rule), a method that finds the outline itself
//! (Tutte, mean value and harmonic keep a convex outline), no pinned corner in the chart.
//! Deterministic: specks, faces and islands in index order; hash maps are only looked up.

use std::collections::{HashMap, HashSet};

use super::solve::remeasure;
use super::{outline_pairs, Context, Piece};
use crate::charts::{build_charts_with, Chart, ChartKind};
use crate::geometry::{cross, cross2, dot, newell_normal, norm, sub};
use crate::metrics::segments_intersect;

/// Pieces of at most this many faces are specks, laid on their neighbours when they fit.
pub const SPECK_FACES: usize = 32;

/// Faces of at most this many corners are tried across all but one of their sides when every
/// side is on the island (closing a gap where the outline meets itself), each side in turn
/// the one left: a triangle or quad closes such a gap; a cap of thousands of corners on a
/// cylinder's end does not, and trying each of its sides costs its corners squared (1.8 s for
/// two 5,000-gon caps).
pub const MAX_CLOSING_CORNERS: usize = 16;

/// Passes over the specks at most: each pass after the first leaves out the specks of the
/// islands that broke the rule once rebuilt.
pub const MAX_PASSES: usize = 3;

/// Lay the specks of `pieces` (the outcome of one input chart, `original`) on their
/// neighbours where they fit (see the module docs).
pub fn apply(ctx: &Context<'_, '_>, original: &Chart, pieces: &mut Vec<Piece>) {
    if !ctx.rule.full || !ctx.options.method.free_boundary() || pieces.len() < 2 || super::pinned(ctx, original) {
        return;
    }
    let t = std::time::Instant::now();
    let is_target = |p: &Piece| {
        p.report.faces > SPECK_FACES
            && p.uv.is_some()
            && p.report.status.mapped()
            && ctx.rule.broken(&p.report).is_none()
            && piece_chart(p, original).kind == ChartKind::Disk
    };
    let specks: Vec<usize> = (0..pieces.len()).filter(|&k| pieces[k].report.faces <= SPECK_FACES).collect();
    let targets: Vec<bool> = pieces.iter().map(is_target).collect();
    if specks.is_empty() || !targets.iter().any(|&x| x) {
        return;
    }
    let frame = Frame::new(ctx, original, pieces, &specks, &targets);
    let mut excluded: Vec<usize> = Vec::new();
    for _ in 0..MAX_PASSES {
        let mut pass = Pass::new(ctx, &frame, original, pieces);
        for &s in &specks {
            if !excluded.contains(&s) {
                pass.glue_speck(s, &piece_chart(&pieces[s], original).faces);
            }
        }
        if pass.glued.is_empty() {
            break;
        }
        match pass.rebuild() {
            Ok(rebuilt) => {
                let glued = pass.glued.len();
                let done = Done { glued: pass.glued, merged: pass.merged };
                done.replace(ctx, original, pieces, rebuilt);
                ctx.clock.add(|p| {
                    p.glued += glued;
                    p.glue += t.elapsed().as_secs_f64();
                });
                return;
            }
            Err(broke) => excluded.extend(broke),
        }
    }
    ctx.clock.add(|p| p.glue += t.elapsed().as_secs_f64());
}

/// What every pass reads: the chart's corners around the specks.
struct Frame {
    /// Sorted mesh vertex pairs of the edges the input chart cut (its outline, slits too).
    cut: HashSet<[u32; 2]>,
    /// Directed edge `(a, b)` (mesh vertices) → the corner starting it and its face, for the
    /// edges of faces at a speck's vertex.
    twin: HashMap<(u32, u32), (u32, u32)>,
    /// Corner of a target piece at a speck's vertex → (piece, chart vertex).
    near: HashMap<u32, (u32, u32)>,
}

impl Frame {
    fn new(ctx: &Context<'_, '_>, original: &Chart, pieces: &[Piece], specks: &[usize], targets: &[bool]) -> Frame {
        let mesh = ctx.mesh;
        let cut: HashSet<[u32; 2]> = outline_pairs(original).into_iter().collect();
        let mut at_speck: HashSet<u32> = HashSet::new();
        for &s in specks {
            let chart = pieces[s].chart.as_ref().unwrap_or(original);
            for &f in &chart.faces {
                at_speck.extend(mesh.face_corners(f as usize).map(|c| mesh.corner_vert(c)));
            }
        }
        let mut twin = HashMap::new();
        for &f in &original.faces {
            for c in mesh.face_corners(f as usize) {
                let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f as usize, c)));
                if at_speck.contains(&a) && at_speck.contains(&b) {
                    twin.insert((a, b), (c as u32, f));
                }
            }
        }
        let mut near = HashMap::new();
        for (k, p) in pieces.iter().enumerate() {
            if !targets[k] {
                continue;
            }
            for &(c, v) in &p.chart.as_ref().unwrap_or(original).corner_vertex {
                if at_speck.contains(&mesh.corner_vert(c as usize)) {
                    near.insert(c, (k as u32, v));
                }
            }
        }
        Frame { cut, twin, near }
    }
}

/// One island that takes faces: its UVs (new corners appended), its outline as `next`/`prev`
/// chart vertices (counter-clockwise, the island on the left) and a grid of outline sides.
struct Island {
    uv: Vec<[f64; 2]>,
    next: HashMap<u32, u32>,
    prev: HashMap<u32, u32>,
    /// Cell → outline sides `(from, to)` binned there; a side is alive while `next[from]`
    /// is `to` (sides replaced by laid faces are left behind and skipped).
    grid: HashMap<(i64, i64), Vec<(u32, u32)>>,
    cell: f64,
    /// Mean texel density: UV area over 3D area.
    density: f64,
    /// 3D area of laid faces that may still fall outside the density bound (half the slack
    /// the rule leaves the island).
    budget: f64,
}

impl Island {
    fn new(chart: &Chart, uv: &[[f64; 2]], outside: f64) -> Island {
        let (mut a2, mut a3) = (0.0, 0.0);
        for t in &chart.triangles {
            let p = t.map(|v| chart.positions[v as usize]);
            a3 += crate::geometry::triangle_area(p);
            a2 += crate::geometry::signed_area_2d(t.map(|v| uv[v as usize]));
        }
        let mut next = HashMap::new();
        let mut prev = HashMap::new();
        let (mut total, mut longest, mut sides) = (0.0f64, 0.0f64, 0usize);
        for l in &chart.boundary_loops {
            for i in 0..l.len() {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                next.insert(a, b);
                prev.insert(b, a);
                let d = dist(uv[a as usize], uv[b as usize]);
                total += d;
                longest = longest.max(d);
                sides += 1;
            }
        }
        let cell = (total / sides.max(1) as f64).max(longest / 32.0).max(f64::MIN_POSITIVE);
        let budget = 0.5 * (super::rule::MAX_OUTSIDE_SHARE - outside).max(0.0) * a3;
        let mut island = Island { uv: uv.to_vec(), next, prev, grid: HashMap::new(), cell, density: a2 / a3, budget };
        for l in &chart.boundary_loops {
            for i in 0..l.len() {
                island.bin(l[i], l[(i + 1) % l.len()], &mut Vec::new(), 0);
            }
        }
        island
    }

    /// The cells the box of `a`–`b` covers.
    fn cells(&self, a: [f64; 2], b: [f64; 2]) -> impl Iterator<Item = (i64, i64)> {
        let at = |x: f64| (x / self.cell).floor() as i64;
        let (x0, x1) = (at(a[0].min(b[0])), at(a[0].max(b[0])));
        let (y0, y1) = (at(a[1].min(b[1])), at(a[1].max(b[1])));
        (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| (x, y)))
    }

    /// Bin the side `from → to`, journalled as island `k`'s.
    fn bin(&mut self, from: u32, to: u32, journal: &mut Vec<Undo>, k: usize) {
        let cells: Vec<(i64, i64)> = self.cells(self.uv[from as usize], self.uv[to as usize]).collect();
        for c in cells {
            self.grid.entry(c).or_default().push((from, to));
            journal.push(Undo::Grid(k, c));
        }
    }

    /// Whether the segment `a`–`b` (whose ends are outline vertices `ends`, if any) touches
    /// a live outline side other than the sides of `run` (a path along the outline) and those
    /// with an end in `ends`.
    fn touches(&self, a: [f64; 2], b: [f64; 2], ends: [Option<u32>; 2], run: &[u32]) -> bool {
        let mut seen: HashSet<(u32, u32)> = HashSet::new();
        let shared = |v: u32| ends.contains(&Some(v));
        let on_run = |from: u32, to: u32| run.windows(2).any(|w| w[0] == from && w[1] == to);
        for c in self.cells(a, b) {
            for &(from, to) in self.grid.get(&c).map_or(&[][..], |v| &v[..]) {
                if self.next.get(&from) != Some(&to) || shared(from) || shared(to) || on_run(from, to) {
                    continue;
                }
                if seen.insert((from, to)) && segments_intersect(a, b, self.uv[from as usize], self.uv[to as usize]) {
                    return true;
                }
            }
        }
        false
    }

    /// The island's angle at outline vertex `v` (from the side leaving it, counter-clockwise
    /// to the side arriving).
    fn angle(&self, v: u32) -> f64 {
        let p = self.uv[v as usize];
        let (n, q) = (self.uv[self.next[&v] as usize], self.uv[self.prev[&v] as usize]);
        ccw_angle([n[0] - p[0], n[1] - p[1]], [q[0] - p[0], q[1] - p[1]])
    }
}

/// A change a pass made, to undo a speck that could not be glued whole.
enum Undo {
    Next(usize, u32, Option<u32>),
    Prev(usize, u32, Option<u32>),
    Uv(usize),
    Budget(usize, f64),
    Grid(usize, (i64, i64)),
    Corner(u32),
    Merged([u32; 2]),
    Face(u32),
}

/// One pass over the specks.
struct Pass<'p, 'c, 'a, 'm> {
    ctx: &'c Context<'a, 'm>,
    frame: &'p Frame,
    original: &'p Chart,
    pieces: &'p [Piece],
    islands: HashMap<usize, Island>,
    /// Corner of a laid face → (island, chart vertex of the island).
    laid: HashMap<u32, (u32, u32)>,
    /// Face laid → island.
    faces: HashMap<u32, usize>,
    /// Sorted mesh vertex pairs of the edges faces were laid across.
    merged: HashSet<[u32; 2]>,
    journal: Vec<Undo>,
    /// Specks glued whole, with the islands their faces went to (in order).
    glued: Vec<(usize, Vec<usize>)>,
}

/// An island rebuilt with the faces laid on it.
struct Rebuilt {
    island: usize,
    chart: Chart,
    uv: Vec<[f64; 2]>,
    report: super::outcome::ChartReport,
    face_flips: Vec<u32>,
}

impl<'p, 'c, 'a, 'm> Pass<'p, 'c, 'a, 'm> {
    fn new(ctx: &'c Context<'a, 'm>, frame: &'p Frame, original: &'p Chart, pieces: &'p [Piece]) -> Self {
        Pass {
            ctx,
            frame,
            original,
            pieces,
            islands: HashMap::new(),
            laid: HashMap::new(),
            faces: HashMap::new(),
            merged: HashSet::new(),
            journal: Vec::new(),
            glued: Vec::new(),
        }
    }

    fn chart(&self, k: usize) -> &'p Chart {
        self.pieces[k].chart.as_ref().unwrap_or(self.original)
    }

    /// Lay every face of speck `s` (faces `faces`) or none.
    fn glue_speck(&mut self, s: usize, faces: &[u32]) {
        let mark = self.journal.len();
        let mut pending: Vec<u32> = faces.to_vec();
        loop {
            let before = pending.len();
            pending.retain(|&f| !self.lay(f));
            if pending.is_empty() || pending.len() == before {
                break;
            }
        }
        if pending.is_empty() {
            let mut went: Vec<usize> = Vec::new();
            for f in faces {
                let k = self.faces[f];
                if !went.contains(&k) {
                    went.push(k);
                }
            }
            self.glued.push((s, went));
        } else {
            self.undo(mark);
        }
    }

    fn undo(&mut self, mark: usize) {
        while self.journal.len() > mark {
            match self.journal.pop().expect("above the mark") {
                Undo::Next(k, v, old) => restore(&mut self.islands.get_mut(&k).expect("island").next, v, old),
                Undo::Prev(k, v, old) => restore(&mut self.islands.get_mut(&k).expect("island").prev, v, old),
                Undo::Budget(k, old) => self.islands.get_mut(&k).expect("island").budget = old,
                Undo::Uv(k) => {
                    self.islands.get_mut(&k).expect("island").uv.pop();
                }
                Undo::Grid(k, c) => {
                    self.islands.get_mut(&k).expect("island").grid.get_mut(&c).expect("binned").pop();
                }
                Undo::Corner(c) => {
                    self.laid.remove(&c);
                }
                Undo::Merged(e) => {
                    self.merged.remove(&e);
                }
                Undo::Face(f) => {
                    self.faces.remove(&f);
                }
            }
        }
    }

    /// The island and chart vertex of corner `c` of an island (its own or a laid face's).
    fn owner(&self, c: u32) -> Option<(u32, u32)> {
        self.laid.get(&c).or_else(|| self.frame.near.get(&c)).copied()
    }

    /// Lay face `f` on the first island it fits, trying the islands it shares most edges with
    /// first. Returns whether it was laid.
    fn lay(&mut self, f: u32) -> bool {
        let mesh = self.ctx.mesh;
        let corners: Vec<u32> = mesh.face_corners(f as usize).map(|c| c as u32).collect();
        let n = corners.len();
        let verts: Vec<u32> = corners.iter().map(|&c| mesh.corner_vert(c as usize)).collect();
        // Per side i (verts[i] → verts[i+1]): the island across it and its chart vertices at
        // both ends.
        let mut across: Vec<Option<(usize, u32, u32)>> = vec![None; n];
        for i in 0..n {
            let (a, b) = (verts[i], verts[(i + 1) % n]);
            if self.frame.cut.contains(&[a.min(b), a.max(b)]) {
                continue;
            }
            let Some(&(c, g)) = self.frame.twin.get(&(b, a)) else { continue };
            let c_next = mesh.next_corner(g as usize, c as usize) as u32;
            if let (Some((k, vb)), Some((k2, va))) = (self.owner(c), self.owner(c_next)) {
                if k == k2 {
                    across[i] = Some((k as usize, va, vb));
                }
            }
        }
        let mut islands: Vec<(usize, usize)> = Vec::new();
        for &(k, _, _) in across.iter().flatten() {
            match islands.iter_mut().find(|e| e.1 == k) {
                Some(e) => e.0 += 1,
                None => islands.push((1, k)),
            }
        }
        islands.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
        for (shared, k) in islands {
            // A face whose every side is on the island closes a gap where the outline meets
            // itself: it is laid across all but one of its sides (the one left is a seam).
            let spare: Vec<Option<usize>> = match shared == n {
                true if n > MAX_CLOSING_CORNERS => continue,
                true => (0..n).rev().map(Some).collect(),
                false => vec![None],
            };
            for spare in spare {
                if self.lay_on(f, k, &corners, &verts, &across, spare) {
                    return true;
                }
            }
        }
        false
    }

    /// Lay face `f` on island `k` across its sides on `k` but `spare`, if it fits (module docs).
    fn lay_on(
        &mut self,
        f: u32,
        k: usize,
        corners: &[u32],
        verts: &[u32],
        across: &[Option<(usize, u32, u32)>],
        spare: Option<usize>,
    ) -> bool {
        let n = verts.len();
        let on = |i: usize| spare != Some(i % n) && across[i % n].is_some_and(|x| x.0 == k);
        let m = (0..n).filter(|&i| on(i)).count();
        if m == 0 || m == n {
            return false;
        }
        // The run starts at the side whose predecessor is not on the island.
        let Some(i0) = (0..n).find(|&i| on(i) && !on(i + n - 1)) else { return false };
        if !(0..m).all(|j| on(i0 + j)) {
            return false;
        }
        // Chart vertex of each face corner on the run; the ends of consecutive sides agree.
        let mut vid: Vec<Option<u32>> = vec![None; n];
        for j in 0..m {
            let i = (i0 + j) % n;
            let (_, va, vb) = across[i].expect("on the run");
            for (at, v) in [(i, va), ((i + 1) % n, vb)] {
                match vid[at] {
                    Some(w) if w != v => return false,
                    _ => vid[at] = Some(v),
                }
            }
        }
        if !self.islands.contains_key(&k) {
            let chart = self.chart(k);
            let uv = self.pieces[k].uv.as_ref().expect("a target has UVs");
            self.islands.insert(k, Island::new(chart, uv, self.pieces[k].report.density.outside));
        }
        let island = &self.islands[&k];
        // The run along the outline: p[0] → … → p[m] (the island's direction).
        let p: Vec<u32> = (0..=m).map(|t| vid[(i0 + m - t) % n].expect("on the run")).collect();
        if !(0..m).all(|t| island.next.get(&p[t]) == Some(&p[t + 1])) {
            return false;
        }
        // The face flattened, then placed by the similarity that maps its run onto the island.
        let pos: Vec<[f64; 3]> = verts.iter().map(|&v| self.ctx.mesh.positions()[v as usize]).collect();
        let Some(flat) = flatten(&pos) else { return false };
        let run: Vec<usize> = (0..=m).map(|j| (i0 + j) % n).collect();
        let pairs: Vec<([f64; 2], [f64; 2])> =
            run.iter().map(|&i| (flat[i], island.uv[vid[i].expect("on the run") as usize])).collect();
        let Some(place) = similarity(&pairs) else { return false };
        let uv_at: Vec<[f64; 2]> =
            (0..n).map(|i| vid[i].map_or_else(|| place.apply(flat[i]), |v| island.uv[v as usize])).collect();
        // Every triangle keeps its turn and the island's density within Max Stretch, or
        // within its square on the area the island may still have outside the bound.
        let s = self.ctx.rule.max_stretch;
        let mut outside = 0.0;
        for t in face_triangles(n) {
            let a3 = crate::geometry::triangle_area(t.map(|i| pos[i]));
            let a2 = crate::geometry::signed_area_2d(t.map(|i| uv_at[i]));
            let r = a2 / (a3 * island.density);
            if !(a3 > 0.0 && r > 1.0 / (s * s) && r < s * s) {
                return false;
            }
            if !(r > 1.0 / s && r < s) {
                outside += a3;
            }
        }
        if n == 4 {
            // (both splits of a quad were checked: each covers it once)
            outside *= 0.5;
        } else if n > 4 {
            outside /= n as f64;
        }
        if outside > island.budget {
            return false;
        }
        // The new sides: from p[0] through the face's other corners to p[m].
        let q: Vec<usize> = (1..n - m).map(|j| (i0 + m + j) % n).collect();
        let mut chain: Vec<[f64; 2]> = vec![island.uv[p[0] as usize]];
        chain.extend(q.iter().map(|&i| uv_at[i]));
        chain.push(island.uv[p[m] as usize]);
        let last = chain.len() - 2;
        for (j, w) in chain.windows(2).enumerate() {
            let ends = [(j == 0).then_some(p[0]), (j == last).then_some(p[m])];
            if island.touches(w[0], w[1], ends, &p) {
                return false;
            }
        }
        // At both ends of the run the face fits in the island's open angle.
        let (u0, um) = (island.uv[p[0] as usize], island.uv[p[m] as usize]);
        let (u1, um1) = (island.uv[p[1] as usize], island.uv[p[m - 1] as usize]);
        let face_at_p0 = ccw_angle(diff(chain[1], u0), diff(u1, u0));
        let face_at_pm = ccw_angle(diff(um1, um), diff(chain[chain.len() - 2], um));
        let full = 2.0 * std::f64::consts::PI - 1e-9;
        if island.angle(p[0]) + face_at_p0 >= full || island.angle(p[m]) + face_at_pm >= full {
            return false;
        }
        // Fits: commit, journalled.
        let island = self.islands.get_mut(&k).expect("built above");
        let journal = &mut self.journal;
        if outside > 0.0 {
            journal.push(Undo::Budget(k, island.budget));
            island.budget -= outside;
        }
        let mut new_vid = vid.clone();
        for &i in &q {
            new_vid[i] = Some(island.uv.len() as u32);
            island.uv.push(uv_at[i]);
            journal.push(Undo::Uv(k));
        }
        let mut outline: Vec<u32> = vec![p[0]];
        outline.extend(q.iter().map(|&i| new_vid[i].expect("placed")));
        outline.push(p[m]);
        for &v in &p[1..m] {
            journal.push(Undo::Next(k, v, island.next.remove(&v)));
            journal.push(Undo::Prev(k, v, island.prev.remove(&v)));
        }
        for w in outline.windows(2) {
            journal.push(Undo::Next(k, w[0], island.next.insert(w[0], w[1])));
            journal.push(Undo::Prev(k, w[1], island.prev.insert(w[1], w[0])));
            island.bin(w[0], w[1], journal, k);
        }
        for (i, &c) in corners.iter().enumerate() {
            self.laid.insert(c, (k as u32, new_vid[i].expect("every corner placed")));
            journal.push(Undo::Corner(c));
        }
        for &i in &run[..m] {
            let (a, b) = (verts[i], verts[(i + 1) % n]);
            self.merged.insert([a.min(b), a.max(b)]);
            journal.push(Undo::Merged([a.min(b), a.max(b)]));
        }
        self.faces.insert(f, k);
        journal.push(Undo::Face(f));
        true
    }

    /// Every island that took faces, rebuilt and measured; `Err` with the specks of the
    /// islands that broke the rule.
    fn rebuild(&self) -> Result<Vec<Rebuilt>, Vec<usize>> {
        let ctx = self.ctx;
        let mesh = ctx.mesh;
        let mut took: Vec<usize> = self.glued.iter().flat_map(|g| g.1.iter().copied()).collect();
        took.sort_unstable();
        took.dedup();
        let mut out = Vec::with_capacity(took.len());
        let mut broke: Vec<usize> = Vec::new();
        for &k in &took {
            let old = self.chart(k);
            let island = &self.islands[&k];
            let mut added: Vec<u32> = self.faces.iter().filter(|e| *e.1 == k).map(|e| *e.0).collect();
            added.sort_unstable();
            let mut mask = vec![false; mesh.n_faces()];
            for &f in old.faces.iter().chain(&added) {
                mask[f as usize] = true;
            }
            // Seams: the old outline and the laid faces' sides, less the sides laid across.
            let mut seams = outline_pairs(old);
            for &f in &added {
                for c in mesh.face_corners(f as usize) {
                    let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f as usize, c)));
                    seams.push([a.min(b), a.max(b)]);
                }
            }
            seams.retain(|e| !self.merged.contains(e));
            seams.sort_unstable();
            seams.dedup();
            let fits = self.rebuilt(k, old, island, &seams, &mask);
            match fits {
                Some(r) => out.push(r),
                None => broke.extend(self.glued.iter().filter(|g| g.1.contains(&k)).map(|g| g.0)),
            }
        }
        if broke.is_empty() {
            Ok(out)
        } else {
            Err(broke)
        }
    }

    /// Island `k` (chart `old`) rebuilt with its laid faces, if it keeps the rule.
    fn rebuilt(&self, k: usize, old: &Chart, island: &Island, seams: &[[u32; 2]], mask: &[bool]) -> Option<Rebuilt> {
        let ctx = self.ctx;
        let mesh = ctx.mesh;
        let mut charts = build_charts_with(mesh, seams, Some(mask), ctx.render);
        if charts.len() != 1 {
            return None;
        }
        let chart = charts.pop().expect("one chart");
        // Where each old face's corners start in the old chart.
        let mut start = Vec::with_capacity(old.faces.len());
        let mut at = 0usize;
        for &f in &old.faces {
            start.push(at);
            at += mesh.face_corners(f as usize).len();
        }
        let mut vid_of = vec![u32::MAX; chart.positions.len()];
        let mut at = 0usize;
        for &f in &chart.faces {
            let m = mesh.face_corners(f as usize).len();
            for j in 0..m {
                let (c, v) = chart.corner_vertex[at + j];
                let w = match old.faces.binary_search(&f) {
                    Ok(i) => old.corner_vertex[start[i] + j].1,
                    Err(_) => self.laid.get(&c)?.1,
                };
                if vid_of[v as usize] == u32::MAX {
                    vid_of[v as usize] = w;
                } else if vid_of[v as usize] != w {
                    return None;
                }
            }
            at += m;
        }
        let uv: Vec<[f64; 2]> = vid_of.iter().map(|&w| island.uv[w as usize]).collect();
        let (report, face_flips) = remeasure(&chart, &uv, &self.pieces[k].report, &ctx.rule)?;
        if ctx.rule.broken(&report).is_some() {
            return None;
        }
        Some(Rebuilt { island: k, chart, uv, report, face_flips })
    }

}

/// What a pass that keeps the rule leaves: the specks glued and the sides laid across.
struct Done {
    glued: Vec<(usize, Vec<usize>)>,
    merged: HashSet<[u32; 2]>,
}

impl Done {
    /// Put the rebuilt islands in place of theirs, drop the glued specks and mend the seams.
    fn replace(&self, ctx: &Context<'_, '_>, original: &Chart, pieces: &mut Vec<Piece>, rebuilt: Vec<Rebuilt>) {
        let mesh = ctx.mesh;
        let length = |e: &[u32; 2]| {
            let p = mesh.positions();
            norm(sub(p[e[0] as usize], p[e[1] as usize]))
        };
        let sorted = |e: &[u32; 2]| [e[0].min(e[1]), e[0].max(e[1])];
        // The sides laid across are seams no more.
        for p in pieces.iter_mut() {
            let before = p.seams.len();
            let mut gone = 0.0;
            p.seams.retain(|e| {
                let merged = self.merged.contains(&sorted(e));
                if merged {
                    gone += length(e);
                }
                !merged
            });
            if p.seams.len() != before {
                p.report.cut_length = (p.report.cut_length - gone).max(0.0);
            }
        }
        for r in rebuilt {
            let p = &mut pieces[r.island];
            let seams = std::mem::take(&mut p.seams);
            *p = Piece::new(Some(r.chart), r.report, Some(r.uv), r.face_flips, seams);
        }
        // Each glued speck's seams, cones and cut length go to the first island it went to,
        // with the sides between its faces that were not laid across each other.
        for (s, went) in &self.glued {
            let chart = piece_chart(&pieces[*s], original);
            // The speck's own cuts (slits) are seams already.
            let mut own = outline_pairs(chart);
            own.sort_unstable();
            let mut inner: Vec<[u32; 2]> = Vec::new();
            for &f in &chart.faces {
                for c in mesh.face_corners(f as usize) {
                    let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(mesh.next_corner(f as usize, c)));
                    inner.push([a.min(b), a.max(b)]);
                }
            }
            inner.sort_unstable();
            let mut added: Vec<[u32; 2]> = inner
                .windows(2)
                .filter(|w| w[0] == w[1] && !self.merged.contains(&w[0]) && own.binary_search(&w[0]).is_err())
                .map(|w| w[0])
                .collect();
            added.dedup();
            let extra: f64 = added.iter().map(length).sum();
            let mut seams = std::mem::take(&mut pieces[*s].seams);
            seams.extend(added);
            let (cones, cut) = (pieces[*s].report.cones, pieces[*s].report.cut_length);
            let to = &mut pieces[went[0]];
            to.seams.extend(seams);
            to.report.cones += cones;
            to.report.cut_length += cut + extra;
        }
        let mut gone: Vec<usize> = self.glued.iter().map(|g| g.0).collect();
        gone.sort_unstable();
        let mut k = 0;
        pieces.retain(|_| {
            k += 1;
            gone.binary_search(&(k - 1)).is_err()
        });
    }
}

fn piece_chart<'x>(p: &'x Piece, original: &'x Chart) -> &'x Chart {
    p.chart.as_ref().unwrap_or(original)
}

fn restore(map: &mut HashMap<u32, u32>, v: u32, old: Option<u32>) {
    match old {
        Some(w) => map.insert(v, w),
        None => map.remove(&v),
    };
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn diff(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// The counter-clockwise angle from direction `a` to direction `b`, in `[0, 2π)`.
fn ccw_angle(a: [f64; 2], b: [f64; 2]) -> f64 {
    let t = cross2(a, b).atan2(a[0] * b[0] + a[1] * b[1]);
    if t < 0.0 {
        t + 2.0 * std::f64::consts::PI
    } else {
        t
    }
}

/// A polygon's corners projected on its Newell plane, counter-clockwise as the face turns;
/// `None` for a face without area.
fn flatten(pos: &[[f64; 3]]) -> Option<Vec<[f64; 2]>> {
    let n = newell_normal(pos.len(), |i| pos[i]);
    let l = norm(n);
    if !(l > 0.0) {
        return None;
    }
    let n = n.map(|x| x / l);
    let e = sub(pos[1], pos[0]);
    let e = sub(e, n.map(|x| x * dot(e, n)));
    let le = norm(e);
    if !(le > 0.0) {
        return None;
    }
    let e1 = e.map(|x| x / le);
    let e2 = cross(n, e1);
    Some(pos.iter().map(|&p| [dot(sub(p, pos[0]), e1), dot(sub(p, pos[0]), e2)]).collect())
}

/// The orientation-keeping similarity `z ↦ a z + b` (complex) nearest to mapping every
/// pair's `z` onto its `w`, least squares; `None` when the `z` coincide.
fn similarity(pairs: &[([f64; 2], [f64; 2])]) -> Option<Similarity> {
    let k = pairs.len() as f64;
    let (mut zc, mut wc) = ([0.0; 2], [0.0; 2]);
    for (z, w) in pairs {
        zc = [zc[0] + z[0] / k, zc[1] + z[1] / k];
        wc = [wc[0] + w[0] / k, wc[1] + w[1] / k];
    }
    let (mut re, mut im, mut den) = (0.0, 0.0, 0.0);
    for (z, w) in pairs {
        let (z, w) = (diff(*z, zc), diff(*w, wc));
        // w · conj(z)
        re += w[0] * z[0] + w[1] * z[1];
        im += w[1] * z[0] - w[0] * z[1];
        den += z[0] * z[0] + z[1] * z[1];
    }
    (den > 0.0).then(|| Similarity { a: [re / den, im / den], zc, wc })
}

/// `z ↦ a (z − zc) + wc`, complex.
struct Similarity {
    a: [f64; 2],
    zc: [f64; 2],
    wc: [f64; 2],
}

impl Similarity {
    fn apply(&self, z: [f64; 2]) -> [f64; 2] {
        let d = diff(z, self.zc);
        [self.a[0] * d[0] - self.a[1] * d[1] + self.wc[0], self.a[1] * d[0] + self.a[0] * d[1] + self.wc[1]]
    }
}

/// The triangles checked on a face of `n` corners: a triangle; both splits of a quad; a fan
/// from every corner of a larger polygon (each fan covers the polygon once; a convex one is
/// positive on all of them).
fn face_triangles(n: usize) -> Vec<[usize; 3]> {
    match n {
        3 => vec![[0, 1, 2]],
        4 => vec![[0, 1, 2], [0, 2, 3], [0, 1, 3], [1, 2, 3]],
        _ => (0..n).flat_map(|a| (1..n - 1).map(move |j| [a, (a + j) % n, (a + j + 1) % n])).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::build_charts;
    use crate::mesh::PolyMesh;
    use crate::pipeline::outcome::{ChartReport, ChartStatus};
    use crate::pipeline::solve::measure;
    use crate::pipeline::rule::AtlasRule;
    use crate::pipeline::test_mesh::grid;
    use crate::unwrap::UnwrapOptions;

    /// The edges between faces in `speck` and faces outside it, as sorted vertex pairs.
    fn border(corners: &[u32], speck: &[u32]) -> Vec<[u32; 2]> {
        let sides = |f: u32| {
            let t = &corners[3 * f as usize..3 * f as usize + 3];
            (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])])
        };
        let inside: HashSet<[u32; 2]> = speck.iter().flat_map(|&f| sides(f)).collect();
        let mut out: Vec<[u32; 2]> = (0..corners.len() as u32 / 3)
            .filter(|f| !speck.contains(f))
            .flat_map(sides)
            .filter(|e| inside.contains(e))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The two pieces of the grid split by `seams`, mapped by `uv_of` (the rest) and `speck_uv`
    /// (the speck), measured; the rest carries the seams.
    fn pieces(
        mesh: &PolyMesh<'_>,
        seams: &[[u32; 2]],
        rule: &AtlasRule,
        uv_of: impl Fn([f64; 3]) -> [f64; 2],
        speck_uv: impl Fn([f64; 3]) -> [f64; 2],
    ) -> Vec<Piece> {
        let mut charts = build_charts(mesh, seams, None);
        charts.sort_by_key(|c| std::cmp::Reverse(c.faces.len()));
        charts
            .into_iter()
            .enumerate()
            .map(|(k, c)| {
                let uv: Vec<[f64; 2]> =
                    c.positions.iter().map(|&p| if k == 0 { uv_of(p) } else { speck_uv(p) }).collect();
                let mut report = ChartReport::new(&c, "abf");
                report.status = ChartStatus::Solved;
                let flips = measure(&c, &uv, &mut report, rule).unwrap();
                let s = if k == 0 { seams.to_vec() } else { Vec::new() };
                Piece::new(Some(c), report, Some(uv), flips, s)
            })
            .collect()
    }

    fn context<'a, 'm>(
        mesh: &'a PolyMesh<'m>,
        options: &'a UnwrapOptions,
        pins: &'a HashMap<u32, [f64; 2]>,
        avoid: &'a [bool],
    ) -> Context<'a, 'm> {
        Context::new(mesh, None, pins, options, avoid)
    }

    #[test]
    fn a_speck_on_a_flat_grid_is_laid_back_where_it_was() {
        let (positions, corners, sizes) = grid(8, 8, 1.0, 0.7);
        let mesh = PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let original = build_charts(&mesh, &[], None).pop().unwrap();
        // Three faces at the grid's lower edge, mapped far away in a frame of their own.
        let speck = [2u32, 3, 5];
        let seams = border(&corners, &speck);
        let options = UnwrapOptions::default();
        let (pins, avoid) = (HashMap::new(), vec![false; positions.len()]);
        let ctx = context(&mesh, &options, &pins, &avoid);
        let run = || {
            let away = |p: [f64; 3]| [40.0 - 2.0 * p[1], 9.0 + 2.0 * p[0]];
            let mut list = pieces(&mesh, &seams, &ctx.rule, |p| [p[0], p[1]], away);
            assert_eq!(list.len(), 2);
            apply(&ctx, &original, &mut list);
            list
        };
        let list = run();
        assert_eq!(list.len(), 1, "the speck stays an island");
        assert_eq!(ctx.clock.get().glued, 1);
        let p = &list[0];
        let chart = p.chart.as_ref().unwrap();
        assert_eq!(chart.faces.len(), 128);
        assert_eq!(chart.kind, ChartKind::Disk);
        assert!(p.report.status == ChartStatus::Solved && ctx.rule.broken(&p.report).is_none(), "{:?}", p.report);
        // Laid rigidly beside the rest, the speck's faces are where the grid's map puts them.
        let uv = p.uv.as_ref().unwrap();
        for (v, q) in chart.positions.iter().enumerate() {
            assert!(dist(uv[v], [q[0], q[1]]) < 1e-12, "vertex at {q:?} laid at {:?}", uv[v]);
        }
        // No seam is left, nor any cut length.
        assert!(p.seams.is_empty(), "{:?}", p.seams);
        assert!(p.report.cut_length.abs() < 1e-12);
        // Deterministic.
        let again = run();
        assert_eq!(again[0].uv, list[0].uv);
    }

    #[test]
    fn a_speck_that_would_lie_on_its_island_is_left_alone() {
        // A strip laid along a circle, its last three cells apart: the rest takes 98% of the
        // turn, and those cells, laid straight on, would cross the gap and lie on its start.
        let (cols, radius) = (100usize, 10.0);
        let turn = 1.01 * 2.0 * std::f64::consts::PI;
        let (positions, corners, sizes) = grid(cols, 2, turn * radius / cols as f64, 0.25);
        let mesh = PolyMesh::new(&positions, &corners, &sizes).unwrap();
        let original = build_charts(&mesh, &[], None).pop().unwrap();
        let cell = |i: usize, j: usize| (2 * (j * cols + i)) as u32;
        let speck: Vec<u32> =
            (0..2).flat_map(|j| (cols - 3..cols).flat_map(move |i| [cell(i, j), cell(i, j) + 1])).collect();
        let seams = border(&corners, &speck);
        let coil = |p: [f64; 3]| {
            let (a, r) = (p[0] / radius, radius - p[1]);
            [r * a.cos(), r * a.sin()]
        };
        let options = UnwrapOptions::default();
        let (pins, avoid) = (HashMap::new(), vec![false; positions.len()]);
        let ctx = context(&mesh, &options, &pins, &avoid);
        let mut list = pieces(&mesh, &seams, &ctx.rule, coil, |p| [p[0], p[1]]);
        let before: Vec<Option<Vec<[f64; 2]>>> = list.iter().map(|p| p.uv.clone()).collect();
        // The premise: both pieces keep the rule.
        assert!(list.iter().all(|p| ctx.rule.broken(&p.report).is_none()));
        apply(&ctx, &original, &mut list);
        assert_eq!(list.len(), 2, "a speck laid across the gap");
        assert_eq!(ctx.clock.get().glued, 0);
        let after: Vec<Option<Vec<[f64; 2]>>> = list.iter().map(|p| p.uv.clone()).collect();
        assert_eq!(after, before, "a map changed");
        assert_eq!(list[0].seams, seams);
    }

    /// `k` faces of the grid grown from `start` across shared edges, in breadth-first order.
    fn grown(corners: &[u32], start: u32, k: usize) -> Vec<u32> {
        let n = corners.len() as u32 / 3;
        let sides = |f: u32| {
            let t = &corners[3 * f as usize..3 * f as usize + 3];
            (0..3).map(move |j| [t[j].min(t[(j + 1) % 3]), t[j].max(t[(j + 1) % 3])]).collect::<Vec<_>>()
        };
        let mut out = vec![start];
        let mut at = 0;
        while out.len() < k && at < out.len() {
            let f = out[at];
            at += 1;
            for g in 0..n {
                if out.len() < k && !out.contains(&g) && sides(g).iter().any(|e| sides(f).contains(e)) {
                    out.push(g);
                }
            }
        }
        out.sort_unstable();
        out
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]

        /// A speck grown from the lower edge of a grid (flat or bumpy), the rest mapped by a
        /// similarity of its plan view: whatever is glued, the faces stay partitioned, every
        /// piece keeps the rule, the seams are exactly the pieces' borders and the count of
        /// glued specks is what vanished; on a flat grid a glued speck lands where the rest's
        /// map puts it.
        #[test]
        fn glue_keeps_the_rule_and_the_seams_of_the_pieces(
            cols in 6usize..12,
            rows in 4usize..8,
            start in 0usize..6,
            k in 1usize..12,
            bump in proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..0.15],
            turn in 0.0f64..6.2,
            scale in 0.2f64..5.0,
        ) {
            let (mut positions, corners, sizes) = grid(cols, rows, 1.0, 0.8);
            for (v, p) in positions.iter_mut().enumerate() {
                p[2] = bump * ((v * 7919 % 13) as f64 / 13.0);
            }
            let mesh = PolyMesh::new(&positions, &corners, &sizes).unwrap();
            let original = build_charts(&mesh, &[], None).pop().unwrap();
            let speck = grown(&corners, 2 * (start % cols) as u32, k);
            let seams = border(&corners, &speck);
            let split = build_charts(&mesh, &seams, None);
            proptest::prop_assume!(split.len() == 2 && split.iter().all(|c| c.kind == ChartKind::Disk));
            let (c, s) = (turn.cos() * scale, turn.sin() * scale);
            let map = move |p: [f64; 3]| [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 1.0];
            let options = UnwrapOptions::default();
            let (pins, avoid) = (HashMap::new(), vec![false; positions.len()]);
            let ctx = context(&mesh, &options, &pins, &avoid);
            let mut list = pieces(&mesh, &seams, &ctx.rule, map, |p| [p[0] + 50.0, p[1]]);
            proptest::prop_assume!(list.iter().all(|p| ctx.rule.broken(&p.report).is_none()));
            apply(&ctx, &original, &mut list);
            // Faces partitioned, every piece keeps the rule.
            let mut faces: Vec<u32> = list.iter().flat_map(|p| p.chart.as_ref().unwrap().faces.clone()).collect();
            faces.sort_unstable();
            proptest::prop_assert_eq!(faces, (0..sizes.len() as u32).collect::<Vec<u32>>());
            for p in &list {
                let keeps = p.report.status.mapped() && ctx.rule.broken(&p.report).is_none();
                proptest::prop_assert!(keeps, "{:?}", p.report);
            }
            proptest::prop_assert_eq!(ctx.clock.get().glued, 2 - list.len());
            // The seams cut the grid into exactly the pieces.
            let all: Vec<[u32; 2]> = list.iter().flat_map(|p| p.seams.clone()).collect();
            let mut cut: Vec<Vec<u32>> = build_charts(&mesh, &all, None).into_iter().map(|c| c.faces).collect();
            let mut own: Vec<Vec<u32>> = list.iter().map(|p| p.chart.as_ref().unwrap().faces.clone()).collect();
            cut.sort();
            own.sort();
            proptest::prop_assert_eq!(cut, own);
            if list.len() == 1 && bump == 0.0 {
                let p = &list[0];
                let (chart, uv) = (p.chart.as_ref().unwrap(), p.uv.as_ref().unwrap());
                for (v, q) in chart.positions.iter().enumerate() {
                    let off = dist(uv[v], map(*q));
                    proptest::prop_assert!(off < 1e-9 * scale.max(1.0), "{:?} vs {:?}", uv[v], map(*q));
                }
            }
        }
    }

    #[test]
    fn outline_sides_meet_when_they_cross_or_touch() {
        // (the rule's own test, `metrics::segments_intersect`: touching counts)
        let (a, b) = ([0.0, 0.0], [1.0, 0.0]);
        assert!(segments_intersect(a, b, [0.5, -1.0], [0.5, 1.0]));
        assert!(segments_intersect(a, b, [0.5, 0.0], [0.5, 1.0]), "touching at a point");
        assert!(segments_intersect(a, b, [0.5, 0.0], [2.0, 0.0]), "overlapping along a line");
        assert!(!segments_intersect(a, b, [0.5, 1e-6], [0.5, 1.0]));
        assert!(!segments_intersect(a, b, [1.5, -1.0], [1.5, 1.0]));
    }

    #[test]
    fn the_similarity_maps_two_points_exactly_and_keeps_turn() {
        let s = similarity(&[([0.0, 0.0], [1.0, 1.0]), ([1.0, 0.0], [1.0, 3.0])]).unwrap();
        let p = s.apply([0.0, 1.0]);
        assert!(dist(p, [-1.0, 1.0]) < 1e-12, "{p:?}");
        assert!(similarity(&[([1.0, 1.0], [0.0, 0.0]), ([1.0, 1.0], [1.0, 0.0])]).is_none());
    }
}
