//! n-gon triangulation by ear clipping in the polygon's own plane (concave polygons too),
//! O(n log n) for n corners in practice (a heap of ears, a linked ring, a grid of corners).

use crate::geometry::{cross, dot, norm};

/// Triangulate a simple polygon given by its 3D corner positions, in order.
///
/// Returns triangles as triples of corner positions `0..n`, oriented like the polygon.
/// The polygon is projected onto the plane of its Newell normal and ears are clipped,
/// among the valid ears the one with the best
/// (largest) minimum angle is cut, which keeps quads split along the better diagonal.
/// Degenerate or self-intersecting input never fails: when no valid ear exists the rest is
/// fanned, so the result always has exactly `n - 2` triangles covering every corner.
///
/// Paper: ear clipping rests on the two-ears theorem (G. H. Meisters, "Polygons have ears",
/// Amer. Math. Monthly 82, 1975). Cost: about O(n log n) for n corners spread over the
/// polygon's bounding box (a heap of ears, a linked ring and a grid of corners; see
/// `ear_clip`), so a face of thousands of corners triangulates in milliseconds; adversarial
/// shapes (many corners crowded into a few ears' boxes) can still cost up to O(n²).
/// Preconditions: finite positions. Failures: none (see above).
pub fn triangulate_polygon(pts: &[[f64; 3]]) -> Vec<[usize; 3]> {
    triangulate_polygon_avoiding(pts, |_, _| false)
}

/// [`triangulate_polygon`], preferring ears whose new diagonal `(i, j)` (corner positions) is
/// not `taken`: a diagonal that already exists as an edge elsewhere would make two triangles
/// share a directed edge (two quads around a valence-2 vertex split along the same diagonal).
/// A taken diagonal is used only when no other valid ear exists.
pub fn triangulate_polygon_avoiding(pts: &[[f64; 3]], taken: impl FnMut(usize, usize) -> bool) -> Vec<[usize; 3]> {
    triangulate_polygon_with(pts, taken, None)
}

/// [`triangulate_polygon_avoiding`] where a quad is split through one corner (`through`),
/// always: used for a vertex shared by only two faces (a cone point with a small angle sum,
/// as around a valence-2 vertex), which flattening opens up to a full turn — the other
/// diagonal would leave a sliver with an angle near π there, and where both faces split away
/// from the vertex they hold the same triangle twice (a fold).
pub fn triangulate_polygon_with(
    pts: &[[f64; 3]],
    mut taken: impl FnMut(usize, usize) -> bool,
    through: Option<usize>,
) -> Vec<[usize; 3]> {
    let n = pts.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return vec![[0, 1, 2]];
    }
    // Newell normal and a 2D basis of its plane.
    let nrm = crate::geometry::newell_normal(n, |i| pts[i]);
    let ln = norm(nrm);
    let p2: Vec<[f64; 2]> = if ln > 0.0 {
        let z = [nrm[0] / ln, nrm[1] / ln, nrm[2] / ln];
        let helper = if z[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
        let x = cross(helper, z);
        let lx = norm(x);
        let x = [x[0] / lx, x[1] / lx, x[2] / lx];
        let y = cross(z, x);
        pts.iter().map(|p| [dot(*p, x), dot(*p, y)]).collect()
    } else {
        return (1..n - 1).map(|i| [0, i, i + 1]).collect();
    };

    if let (4, Some(k)) = (n, through) {
        // A vertex shared by only two faces: when both split away from it they hold the same
        // triangle (a fold) whatever the geometry says, and a non-planar quad there can make
        // the mean-plane test below reject the split through it. The split through it is the
        // surface's own fan around it.
        return if k % 2 == 0 { vec![[0, 1, 2], [0, 2, 3]] } else { vec![[0, 1, 3], [1, 2, 3]] };
    }
    if n == 4 {
        // Quads: pick the diagonal whose two triangles have the larger minimum angle (both
        // must be positively oriented), so a corner of ~180° never ends up in a sliver.
        let area2 = |a: usize, b: usize, c: usize| {
            let (pa, pb, pc) = (p2[a], p2[b], p2[c]);
            (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0])
        };
        let mut best: Option<(f64, [[usize; 3]; 2])> = None;
        for (d0, d1) in [(0usize, 2usize), (1, 3)] {
            let tris = if d0 == 0 { [[0, 1, 2], [0, 2, 3]] } else { [[0, 1, 3], [1, 2, 3]] };
            if tris.iter().any(|t| area2(t[0], t[1], t[2]) <= 0.0) {
                continue;
            }
            let q = tris
                .iter()
                .map(|t| min_angle_2d(p2[t[0]], p2[t[1]], p2[t[2]]))
                .fold(f64::INFINITY, f64::min)
                - if taken(d0, d1) { 10.0 } else { 0.0 };
            if best.is_none_or(|(bq, _)| q > bq + 1e-9 * bq.abs() + 1e-300) {
                best = Some((q, tris));
            }
        }
        if let Some((_, tris)) = best {
            return tris.to_vec();
        }
    }
    let clipped = ear_clip(&p2, &mut taken);
    // Ear clipping's triangles, unless they hold an angle flattening would clamp (three
    // corners on one line, as a greedy clip can leave them) and a better triangulation exists.
    let smallest = |t: &[[usize; 3]]| {
        let angles = t.iter().map(|t| min_angle_2d(p2[t[0]], p2[t[1]], p2[t[2]]));
        angles.fold(f64::INFINITY, |a, b| if b.is_nan() { f64::NEG_INFINITY } else { a.min(b) })
    };
    let worst = smallest(&clipped);
    if n <= BEST_UP_TO && !(worst >= crate::geometry::MIN_ANGLE) {
        if let Some(best) = best_min_angle(&p2, &mut taken) {
            if smallest(&best) > worst {
                return best;
            }
        }
    }
    clipped
}

/// Polygons of up to this many corners whose ear clipping holds an angle below
/// [`crate::geometry::MIN_ANGLE`] are triangulated for the largest smallest angle instead
/// ([`best_min_angle`], O(n³)) where that does better.
pub const BEST_UP_TO: usize = 32;

/// The triangulation of a simple polygon (counter-clockwise in its plane, `p2`) whose smallest
/// angle is largest, by dynamic programming over its diagonals (Klincsek 1980: the best
/// triangulation of the sub-polygon `i..=j` is a triangle `(i, k, j)` with the best ones on
/// either side of it). Greedy ear clipping can be left with three corners on one line where a
/// side holds an extra corner (a pentagon that is a square with a corner on one side: clipping
/// the two best ears first leaves the straight corner's triangle, without area, whose angles
/// are then clamped and bend a flat face). Diagonals that are `taken` cost as in
/// [`ear_clip`]. A diagonal must lie inside the polygon, crossing no side and passing
/// through no corner. `None` when the polygon has no such triangulation (self-intersecting, or
/// degenerate to round-off); the caller keeps ear clipping's triangles then.
fn best_min_angle(p2: &[[f64; 2]], taken: &mut impl FnMut(usize, usize) -> bool) -> Option<Vec<[usize; 3]>> {
    let n = p2.len();
    let area2 = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let scale = p2.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
    // Whether segments ab and cd meet (touching counts), to round-off of the polygon's scale.
    let eps = 1e-12 * scale * scale;
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (0..2).all(|k| r[k] >= p[k].min(q[k]) - 1e-12 * scale && r[k] <= p[k].max(q[k]) + 1e-12 * scale)
    };
    let meet = |a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
        let (d1, d2) = (area2(a, b, c), area2(a, b, d));
        let (d3, d4) = (area2(c, d, a), area2(c, d, b));
        let apart = |x: f64, y: f64| (x > eps && y < -eps) || (x < -eps && y > eps);
        if apart(d1, d2) && apart(d3, d4) {
            return true;
        }
        (d1.abs() <= eps && within(a, b, c))
            || (d2.abs() <= eps && within(a, b, d))
            || (d3.abs() <= eps && within(c, d, a))
            || (d4.abs() <= eps && within(c, d, b))
    };
    // Diagonal (i, j) strictly inside the corner at i, between its sides.
    let inside_corner = |i: usize, j: usize| {
        let (a, b, c) = (p2[(i + n - 1) % n], p2[i], p2[(i + 1) % n]);
        let d = p2[j];
        if area2(a, b, c) > 0.0 {
            area2(b, c, d) > 0.0 && area2(b, d, a) > 0.0
        } else {
            !(area2(b, d, c) >= 0.0 && area2(b, a, d) >= 0.0)
        }
    };
    let side = |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1);
    // valid[i * n + j], i < j: a side, or a diagonal inside both corners that crosses or
    // touches no side not ending at i or j, and passes through no other corner.
    let mut valid = vec![false; n * n];
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (p2[i], p2[j]);
            let crosses = (0..n).any(|k| {
                let l = (k + 1) % n;
                ![k, l].contains(&i) && ![k, l].contains(&j) && meet(a, b, p2[k], p2[l])
            });
            let through = (0..n).any(|k| k != i && k != j && area2(a, b, p2[k]).abs() <= eps && within(a, b, p2[k]));
            valid[i * n + j] = side(i, j) || (inside_corner(i, j) && inside_corner(j, i) && !crosses && !through);
        }
    }
    let mut cost = |i: usize, j: usize| if !side(i, j) && taken(i, j) { 10.0 } else { 0.0 };
    // best[i * n + j]: the largest smallest angle over triangulations of corners i..=j, and the
    // apex k of the triangle on (i, j).
    let mut best = vec![(f64::NEG_INFINITY, usize::MAX); n * n];
    for i in 0..n - 1 {
        best[i * n + i + 1] = (f64::INFINITY, usize::MAX);
    }
    for gap in 2..n {
        for i in 0..n - gap {
            let j = i + gap;
            if !valid[i * n + j] {
                continue;
            }
            let mut here = (f64::NEG_INFINITY, usize::MAX);
            for k in i + 1..j {
                let (left, right) = (best[i * n + k].0, best[k * n + j].0);
                if left == f64::NEG_INFINITY || right == f64::NEG_INFINITY || !(area2(p2[i], p2[k], p2[j]) > 0.0) {
                    continue;
                }
                let q = (min_angle_2d(p2[i], p2[k], p2[j]) - cost(i, k) - cost(k, j)).min(left).min(right);
                if q > here.0 {
                    here = (q, k);
                }
            }
            best[i * n + j] = here;
        }
    }
    if best[n - 1].1 == usize::MAX {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        let k = best[i * n + j].1;
        if k == usize::MAX {
            continue;
        }
        out.push([i, k, j]);
        stack.push((i, k));
        stack.push((k, j));
    }
    out.sort_unstable();
    (out.len() == n - 2).then_some(out)
}

/// Smallest share of a quad's area (in its Newell plane) that each of the four triangles of
/// its two diagonal splits must hold for [`convex_quad`]: about a corner of 177° on a square.
pub const CONVEX_QUAD_MARGIN: f64 = 0.02;

/// Whether a quad is clearly convex in 3D: every triangle of both of its diagonal splits,
/// projected onto the quad's Newell plane, is positive and holds at least
/// [`CONVEX_QUAD_MARGIN`] of the quad's projected area. Only such quads are asked to stay
/// strictly convex in UV ([`crate::charts::Chart::quads`]): a quad that is concave (or nearly
/// so, or folded) in 3D has one split with a triangle turned over on the surface itself; its
/// faithful map keeps that shape, and keeping both splits positive in UV would distort it
/// (Blender splits such a quad along its inner diagonal, the one positive on the surface).
pub fn convex_quad(pts: &[[f64; 3]; 4]) -> bool {
    let nrm = crate::geometry::newell_normal(4, |i| pts[i]);
    let twice_area = norm(nrm);
    if !(twice_area > 0.0) {
        return false;
    }
    let signed = |a: usize, b: usize, c: usize| {
        let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
        let e1 = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
        let e2 = [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]];
        dot(cross(e1, e2), nrm) / twice_area
    };
    [(0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)]
        .iter()
        .all(|&(a, b, c)| signed(a, b, c) >= CONVEX_QUAD_MARGIN * twice_area)
}

/// Quantum of the ear quality (radians): ears whose qualities round to the same multiple are
/// tied, and a tie goes to the smaller corner index, so the choice does not depend on
/// round-off (rectangles, regular polygons) or on where the polygon lies.
const QUALITY_QUANTUM: f64 = 1e-9;

/// A corner turning by less than this (the sine of its turning angle) is straight, not an ear:
/// corners collinear in 3D are so only to round-off once projected, and an ear there would
/// be a triangle of zero area.
const COLLINEAR: f64 = 1e-10;

/// A corner within this fraction of the polygon's extent from an ear's sides counts as in the
/// ear, for the same reason: a corner on the diagonal of an ear (a collinear run) would
/// otherwise leave a zero-area triangle behind.
const NEAR: f64 = 1e-10;

/// Ear clipping of the projected polygon `p2` (module docs of [`triangulate_polygon_with`]).
///
/// Cost about O(k log k) for k corners on polygons whose corners are spread over their
/// bounding box (O(k²) at worst on adversarial ones), instead of the O(k³) of rescanning
/// every ear against every corner after each cut:
/// * the remaining corners form a doubly linked ring, so a cut is O(1);
/// * the ears sit in a max-heap by quality (the minimum angle, a taken diagonal ranking below
///   every free one), with a version per corner that invalidates the entries of a corner whose
///   neighbours changed: the best ear of the current ring is popped, exactly as a full rescan
///   would pick it;
/// * whether another corner lies in an ear is asked of a uniform grid over the remaining
///   corners that are not strictly convex (only they can lie in an ear of a simple polygon:
///   if any corner does, the one of the intruding chain farthest from the ear's diagonal is
///   reflex), or of their list when the ear's bounding box covers more cells than they are;
///   a convex polygon's ears are then tested in O(1);
/// * an ear that holds a corner waits on that corner ("blocked by it"): vertices never move,
///   so the ear stays invalid until that corner turns convex or is cut, and is evaluated
///   again only then.
///
/// On a simple polygon the same ears are valid as in the exhaustive test (a convex corner
/// whose triangle holds no other remaining corner, boundary included, within round-off), so
/// the result is the same triangulation up to ties of quality within [`QUALITY_QUANTUM`]. When
/// no valid ear is left (degenerate or self-intersecting input) every corner is evaluated once
/// more, and then the rest is fanned.
fn ear_clip(p2: &[[f64; 2]], taken: &mut impl FnMut(usize, usize) -> bool) -> Vec<[usize; 3]> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = p2.len();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let mut version = vec![0u32; n];
    let mut remaining = n;
    // Corners that are not strictly convex: only they can lie in an ear of a simple polygon
    // (if any corner does, the corner of the intruding chain farthest from the ear's diagonal
    // is one of them).
    let not_convex = |b: usize, prev: &[usize], next: &[usize]| {
        let (pa, pb, pc) = (p2[prev[b]], p2[b], p2[next[b]]);
        let area2 = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
        let (ab, bc) = ((pb[0] - pa[0]).hypot(pb[1] - pa[1]), (pc[0] - pb[0]).hypot(pc[1] - pb[1]));
        !(area2 > COLLINEAR * ab * bc)
    };
    let mut reflex: Vec<bool> = (0..n).map(|b| not_convex(b, &prev, &next)).collect();
    let mut grid = Grid::new(p2, &reflex);
    // Corners closer than this to an ear's sides count as in it (round-off of the projection).
    let near = NEAR * grid.extent;
    // Ears waiting on the corner that lies in them: (ear corner, its version then).
    let mut blocked: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    let mut heap: BinaryHeap<(i64, Reverse<u32>, u32)> = BinaryHeap::new();
    let mut out = Vec::with_capacity(n - 2);

    // Evaluate corner `b` as an ear with its current neighbours: into the heap when valid, onto
    // the blocking corner's list when another corner lies in it, nowhere when not convex.
    let mut evaluate = |b: usize,
                        prev: &[usize],
                        next: &[usize],
                        remaining: usize,
                        version: &[u32],
                        grid: &Grid,
                        blocked: &mut [Vec<(u32, u32)>],
                        heap: &mut BinaryHeap<(i64, Reverse<u32>, u32)>| {
        if not_convex(b, prev, next) {
            return; // reflex, or straight to round-off (collinear corners of a 3D face)
        }
        let (a, c) = (prev[b], next[b]);
        let (pa, pb, pc) = (p2[a], p2[b], p2[c]);
        let inside = |o: usize| o != a && o != b && o != c && point_near_triangle(p2[o], pa, pb, pc, near);
        if let Some(o) = grid.find(pa, pb, pc, near, &inside) {
            blocked[o].push((b as u32, version[b]));
            return;
        }
        // A taken diagonal ranks below every free one.
        let q = min_angle_2d(pa, pb, pc) - if remaining > 3 && taken(a, c) { 10.0 } else { 0.0 };
        heap.push(((q / QUALITY_QUANTUM).round() as i64, Reverse(b as u32), version[b]));
    };

    for b in 0..n {
        evaluate(b, &prev, &next, remaining, &version, &grid, &mut blocked, &mut heap);
    }
    let mut rescanned = false;
    while remaining > 3 {
        let Some((_, Reverse(b), v)) = heap.pop() else {
            // No ear known. Cannot happen for a simple polygon (every one of more than three
            // corners has two ears, and every ear is in the heap or waits on a corner still
            // there); for degenerate input, evaluate every corner once more, then give up.
            if rescanned {
                break;
            }
            rescanned = true;
            let mut b = (0..n).find(|&i| alive[i]).expect("corners remain");
            for _ in 0..remaining {
                version[b] += 1;
                evaluate(b, &prev, &next, remaining, &version, &grid, &mut blocked, &mut heap);
                b = next[b];
            }
            continue;
        };
        let b = b as usize;
        if !alive[b] || version[b] != v {
            continue; // stale: cut already, or its neighbours changed
        }
        rescanned = false;
        let (a, c) = (prev[b], next[b]);
        out.push([a, b, c]);
        alive[b] = false;
        if reflex[b] {
            grid.remove(b, p2[b]);
        }
        remaining -= 1;
        next[a] = c;
        prev[c] = a;
        // The neighbours' corners changed: one that turned convex no longer blocks ears.
        let mut woken = vec![b];
        for w in [a, c] {
            let now = not_convex(w, &prev, &next);
            if reflex[w] && !now {
                grid.remove(w, p2[w]);
                woken.push(w);
            } else if !reflex[w] && now {
                grid.insert(w, p2[w]); // only on degenerate input
            }
            reflex[w] = now;
        }
        // The two neighbours have new ears; the ears that waited on a corner gone from the
        // grid may be free now.
        for w in [a, c] {
            version[w] += 1;
            evaluate(w, &prev, &next, remaining, &version, &grid, &mut blocked, &mut heap);
        }
        for g in woken {
            for (e, ev) in std::mem::take(&mut blocked[g]) {
                let e = e as usize;
                if alive[e] && version[e] == ev {
                    version[e] += 1;
                    evaluate(e, &prev, &next, remaining, &version, &grid, &mut blocked, &mut heap);
                }
            }
        }
    }
    // The last triangle, or the fan of what no ear could cut, from the smallest corner left.
    let first = (0..n).find(|&i| alive[i]).expect("corners remain");
    let mut ring = Vec::with_capacity(remaining);
    let mut b = first;
    for _ in 0..remaining {
        ring.push(b);
        b = next[b];
    }
    for i in 1..ring.len() - 1 {
        out.push([ring[0], ring[i], ring[i + 1]]);
    }
    out
}

/// A uniform grid over the remaining corners that are not strictly convex, about one cell
/// per corner of the polygon, for the question "does a corner lie in this ear?".
struct Grid {
    /// Larger side of the polygon's bounding box.
    extent: f64,
    origin: [f64; 2],
    /// Reciprocal of the cell size.
    inv: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
    /// The corners in the grid, and the position of each in that list.
    members: Vec<u32>,
    position: Vec<u32>,
}

impl Grid {
    /// The grid of the corners `p2[i]` with `member[i]`.
    fn new(p2: &[[f64; 2]], member: &[bool]) -> Self {
        let n = p2.len();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in p2 {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        // Cell size for about n cells over the box (a thin box gets a single row).
        let size = ((w * h) / n as f64).sqrt().max(w.max(h) / n as f64);
        let (nx, ny, inv) = if size > 0.0 && size.is_finite() {
            let cells = |e: f64| ((e / size).floor() as usize + 1).min(n);
            (cells(w), cells(h), 1.0 / size)
        } else {
            (1, 1, 0.0)
        };
        let mut grid = Grid {
            extent: w.max(h),
            origin: lo,
            inv,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
            members: Vec::new(),
            position: vec![u32::MAX; n],
        };
        for (i, &p) in p2.iter().enumerate() {
            if member[i] {
                grid.insert(i, p);
            }
        }
        grid
    }

    /// Column and row of the cell of `p` (clamped to the grid).
    fn coords(&self, p: [f64; 2]) -> (usize, usize) {
        let f = |x: f64, o: f64, m: usize| {
            let c = (x - o) * self.inv;
            if c >= 0.0 {
                (c as usize).min(m - 1)
            } else {
                0
            }
        };
        (f(p[0], self.origin[0], self.nx), f(p[1], self.origin[1], self.ny))
    }

    fn cell(&self, p: [f64; 2]) -> usize {
        let (x, y) = self.coords(p);
        y * self.nx + x
    }

    fn insert(&mut self, i: usize, p: [f64; 2]) {
        if self.position[i] != u32::MAX {
            return;
        }
        let k = self.cell(p);
        self.cells[k].push(i as u32);
        self.position[i] = self.members.len() as u32;
        self.members.push(i as u32);
    }

    fn remove(&mut self, i: usize, p: [f64; 2]) {
        let at = self.position[i];
        if at == u32::MAX {
            return;
        }
        let k = self.cell(p);
        if let Some(pos) = self.cells[k].iter().position(|&j| j as usize == i) {
            self.cells[k].swap_remove(pos);
        }
        self.members.swap_remove(at as usize);
        if let Some(&moved) = self.members.get(at as usize) {
            self.position[moved as usize] = at;
        }
        self.position[i] = u32::MAX;
    }

    /// A corner of the grid for which `inside` holds among those that can lie within `near`
    /// of the triangle `a b c`: the corners of the cells its bounding box (grown by `near`)
    /// meets, or all of them when those cells outnumber them.
    fn find(&self, a: [f64; 2], b: [f64; 2], c: [f64; 2], near: f64, inside: &impl Fn(usize) -> bool) -> Option<usize> {
        let lo = [a[0].min(b[0]).min(c[0]) - near, a[1].min(b[1]).min(c[1]) - near];
        let hi = [a[0].max(b[0]).max(c[0]) + near, a[1].max(b[1]).max(c[1]) + near];
        let (x0, y0) = self.coords(lo);
        let (x1, y1) = self.coords(hi);
        if (x1 - x0 + 1) * (y1 - y0 + 1) > self.members.len() {
            return self.members.iter().map(|&o| o as usize).find(|&o| inside(o));
        }
        for y in y0..=y1 {
            for cell in &self.cells[y * self.nx + x0..=y * self.nx + x1] {
                if let Some(&o) = cell.iter().find(|&&o| inside(o as usize)) {
                    return Some(o as usize);
                }
            }
        }
        None
    }
}

/// Whether `p` lies in the counter-clockwise triangle `a b c` or within `near` of it (on the
/// inner side of every side's line shifted outward by `near`).
fn point_near_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2], near: f64) -> bool {
    let s = |u: [f64; 2], v: [f64; 2]| {
        let len = (v[0] - u[0]).hypot(v[1] - u[1]);
        (v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0]) >= -near * len
    };
    s(a, b) && s(b, c) && s(c, a)
}

fn min_angle_2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let ang = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let u = [q[0] - p[0], q[1] - p[1], 0.0];
        let v = [r[0] - p[0], r[1] - p[1], 0.0];
        crate::geometry::angle_between(u, v)
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area2(p: &[[f64; 3]], t: [usize; 3]) -> f64 {
        let a = p[t[0]];
        let b = p[t[1]];
        let c = p[t[2]];
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn convex_quad_tells_clearly_convex_quads_from_concave_folded_and_flat_cornered_ones() {
        let square = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(convex_quad(&square));
        // Winding does not matter (the Newell normal turns with it).
        let mut reversed = square;
        reversed.reverse();
        assert!(convex_quad(&reversed));
        // A dart: corner 2 pushed inside, concave.
        let dart = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.3, 0.0], [0.0, 1.0, 0.0]];
        assert!(!convex_quad(&dart));
        // Corner 2 on the diagonal's far side but nearly on the line 1-3: a corner of ~179°.
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.505, 0.505, 0.0], [0.0, 1.0, 0.0]];
        assert!(!convex_quad(&flat));
        // Clearly convex but not planar (two corners lifted: bent along a diagonal): convex.
        let h = 0.5f64 * (30.0f64.to_radians()).tan() * std::f64::consts::FRAC_1_SQRT_2;
        let bent = [[0.0, 0.0, 0.0], [1.0, 0.0, h], [1.0, 1.0, 0.0], [0.0, 1.0, h]];
        assert!(convex_quad(&bent));
        // Folded onto itself along the diagonal 0-2 (corner 3 brought over to corner 1's
        // side, lifted): the split along 1-3 holds a triangle turned over.
        let folded = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.8, 0.2, 0.3]];
        assert!(!convex_quad(&folded));
        // Degenerate (all corners on a line).
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        assert!(!convex_quad(&line));
    }

    #[test]
    fn concave_l_shape_is_covered_without_flips() {
        let p = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 4);
        let total: f64 = t.iter().map(|&t| area2(&p, t)).sum();
        assert!((total - 6.0).abs() < 1e-12, "twice the L area is 6, got {total}");
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }

    /// Smallest angle of a triangulation of `p`.
    fn smallest_angle(p: &[[f64; 3]], t: &[[usize; 3]]) -> f64 {
        let q = |i: usize| [p[i][0], p[i][1]];
        t.iter().map(|t| min_angle_2d(q(t[0]), q(t[1]), q(t[2]))).fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_corner_on_a_straight_side_leaves_no_triangle_without_area() {
        // A square with a fifth corner 1e-7 up its right side (a boolean's leftover), turned
        // to start anywhere: two of its five triangulations hold that corner's triangle on one
        // line (`tests/flat_charts.rs` has greedy ear clipping take one in a plate).
        let square = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1e-7, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for start in 0..5 {
            let p: Vec<[f64; 3]> = (0..5).map(|k| square[(start + k) % 5]).collect();
            let t = triangulate_polygon(&p);
            assert_eq!(t.len(), 3);
            assert!(t.iter().all(|&t| area2(&p, t) > 1e-9), "{start}: {t:?}");
            let total: f64 = t.iter().map(|&t| area2(&p, t)).sum();
            assert!((total - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn a_corner_on_a_straight_side_of_a_tilted_face_leaves_no_triangle_without_area() {
        // The same square on a plane turned by 0.6 rad about x, and by 0.3 about z.
        let (c, s, c2, s2) = (0.6f64.cos(), 0.6f64.sin(), 0.3f64.cos(), 0.3f64.sin());
        let p: Vec<[f64; 3]> = [[0.0, 0.0], [1.0, 0.0], [1.0, 1e-7], [1.0, 1.0], [0.0, 1.0]]
            .iter()
            .map(|&[x, y]| {
                let (y, z) = (c * y, s * y);
                [c2 * x - s2 * y, s2 * x + c2 * y, z]
            })
            .collect();
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 3);
        let area = |t: [usize; 3]| {
            let (a, b, d) = (p[t[0]], p[t[1]], p[t[2]]);
            crate::geometry::norm(crate::geometry::cross(crate::geometry::sub(b, a), crate::geometry::sub(d, a)))
        };
        assert!(t.iter().all(|&t| area(t) > 1e-9), "{t:?}");
    }

    #[test]
    fn small_polygons_with_corners_on_straight_sides_are_covered_by_positive_triangles() {
        // Star-shaped polygons of 5 to 32 corners (radii varied by a fixed sequence), half of
        // them with a corner on a straight side: every triangulation covers the polygon with
        // positive triangles (none on one line), and its smallest angle is at least the greedy
        // ear clipping's.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in 5..=BEST_UP_TO {
            for _ in 0..4 {
                let mut p: Vec<[f64; 3]> = (0..n)
                    .map(|k| {
                        let a = std::f64::consts::TAU * (k as f64 + 0.4 * next()) / n as f64;
                        let r = 0.4 + next();
                        [r * a.cos(), r * a.sin(), 0.0]
                    })
                    .collect();
                // A corner moved onto the middle of its neighbours' segment.
                if next() < 0.5 {
                    let k = (next() * n as f64) as usize % n;
                    let (a, b) = (p[(k + n - 1) % n], p[(k + 1) % n]);
                    p[k] = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, 0.0];
                }
                let twice: f64 = (0..n).map(|k| p[k][0] * p[(k + 1) % n][1] - p[(k + 1) % n][0] * p[k][1]).sum();
                let t = triangulate_polygon(&p);
                assert_eq!(t.len(), n - 2);
                assert!(t.iter().all(|&t| area2(&p, t) > 0.0), "{n}: {t:?}");
                let total: f64 = t.iter().map(|&t| area2(&p, t)).sum();
                assert!((total - twice).abs() < 1e-9 * twice.abs(), "{n}: {total} against {twice}");
                let ear = ear_clip(&p.iter().map(|q| [q[0], q[1]]).collect::<Vec<_>>(), &mut |_, _| false);
                assert!(smallest_angle(&p, &t) >= smallest_angle(&p, &ear) - 1e-12, "{n}");
            }
        }
    }

    #[test]
    fn a_quad_splits_through_the_requested_corner() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for k in 0..4 {
            let t = triangulate_polygon_with(&p, |_, _| false, Some(k));
            assert!(t.iter().all(|tri| tri.contains(&k)), "{k}: {t:?}");
        }
    }

    #[test]
    fn a_taken_diagonal_is_avoided() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for (a, b) in [(0, 2), (1, 3)] {
            let t = triangulate_polygon_avoiding(&p, |i, j| (i.min(j), i.max(j)) == (a, b));
            assert!(t.iter().all(|tri| !(tri.contains(&a) && tri.contains(&b))), "{t:?}");
        }
    }

    #[test]
    fn kite_is_split_along_the_diagonal_with_the_larger_minimum_angle() {
        // Diagonal 0-2 would give two slivers of angle ~0.05 rad; 1-3 gives a minimum of ~0.1.
        let p = [[0.0, 0.0, 0.0], [1.0, -0.05, 0.0], [2.0, 0.0, 0.0], [1.0, 0.05, 0.0]];
        let t = triangulate_polygon(&p);
        assert_eq!(t.len(), 2);
        assert!(t.iter().all(|&t| t.contains(&1) && t.contains(&3)), "{t:?}");
        assert!(t.iter().all(|&t| area2(&p, t) > 0.0));
    }
}
