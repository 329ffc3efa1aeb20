//! Broad phase: the pairs of 2D boxes that share a point, through a uniform grid that is
//! refined where it is crowded.
//!
//! Precedent: uniform-grid broad phases (Ericson, *Real-Time Collision Detection*, 2005,
//! ch. 7) and their hierarchical variant, a grid per level of a quadtree (ibid. 7.2–7.3).
//!
//! A grid of cells about the boxes' mean size finds the pairs of a map of even density in
//! about linear time. A map that crushes part of a surface packs thousands of boxes into one
//! such cell (fertility subdivided three times under `lscm`: 51,846 triangles in one cell,
//! 37 s of pair tests). So a cell holding more than [`LEAF`] boxes is binned again, on a grid
//! over that cell sized by the mean extent of its own boxes (clipped to the cell), down to
//! [`MAX_DEPTH`] levels; a cell whose boxes all reach every sub-cell (no refinement helps) is
//! tested pair by pair.
//!
//! Complete: cells are found by a monotone map of a coordinate to its cell (clamped to the
//! grid), so a point shared by two boxes lies in a cell that both are binned to, at every
//! level. A pair can be visited more than once (once per leaf cell its boxes share): callers
//! that collect pairs deduplicate them.
//!
//! Bounded: a level's cell size is raised until its boxes fill at most
//! [`MAX_ENTRIES_PER_BOX`] cells each on average, so a few large boxes among many small ones do
//! not fill every sub-cell. Deterministic: cells in index order, boxes in input order within
//! a cell. Preconditions: finite boxes with `lo <= hi` (others are skipped).

use std::ops::ControlFlow;

/// An axis-aligned box `(lo, hi)`.
pub type Box2 = ([f64; 2], [f64; 2]);

/// Cells with at most this many boxes are tested pair by pair.
pub const LEAF: usize = 32;
/// Levels of refinement below the first grid.
pub const MAX_DEPTH: usize = 6;
/// Most cells per axis on the first level and on each refined one.
const MAX_CELLS_TOP: f64 = 4096.0;
const MAX_CELLS_SUB: f64 = 64.0;
/// Average cells a box is binned to, at most, on one level.
const MAX_ENTRIES_PER_BOX: usize = 8;

/// Call `visit(i, j)` (`i < j`) for the pairs of `boxes` that share a point, each at least
/// once; pairs of boxes that do not share a point may be visited too (they share a cell).
/// Stops when `visit` breaks.
pub fn visit_pairs(boxes: &[Box2], mut visit: impl FnMut(u32, u32) -> ControlFlow<()>) -> ControlFlow<()> {
    let ids: Vec<u32> = (0..boxes.len() as u32)
        .filter(|&i| {
            let (lo, hi) = boxes[i as usize];
            (0..2).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k])
        })
        .collect();
    let Some(region) = union(boxes, &ids) else { return ControlFlow::Continue(()) };
    cell_pairs(boxes, &ids, region, 0, &mut visit)
}

/// The pairs of `boxes` that share a point and pass `test`, sorted, each once.
pub fn overlapping_pairs(boxes: &[Box2], mut test: impl FnMut(u32, u32) -> bool) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let _ = visit_pairs(boxes, |i, j| {
        if share_point(boxes[i as usize], boxes[j as usize]) && test(i, j) {
            out.push((i, j));
        }
        ControlFlow::Continue(())
    });
    out.sort_unstable();
    out.dedup();
    out
}

/// Whether two closed boxes share a point.
pub fn share_point(a: Box2, b: Box2) -> bool {
    (0..2).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
}

fn union(boxes: &[Box2], ids: &[u32]) -> Option<Box2> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for &i in ids {
        let (l, h) = boxes[i as usize];
        for k in 0..2 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
        }
    }
    (lo[0] <= hi[0] && lo[1] <= hi[1]).then_some((lo, hi))
}

/// The pairs among `ids`, all of whose boxes meet `region`, at refinement `depth`.
fn cell_pairs(
    boxes: &[Box2],
    ids: &[u32],
    region: Box2,
    depth: usize,
    visit: &mut impl FnMut(u32, u32) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let every_pair = |visit: &mut dyn FnMut(u32, u32) -> ControlFlow<()>| {
        for (x, &i) in ids.iter().enumerate() {
            for &j in &ids[x + 1..] {
                visit(i.min(j), i.max(j))?;
            }
        }
        ControlFlow::Continue(())
    };
    if ids.len() <= LEAF || depth > MAX_DEPTH {
        return every_pair(visit);
    }
    let (lo, hi) = region;
    let extent = [hi[0] - lo[0], hi[1] - lo[1]];
    // A box clamped into the region (monotone, so a box binned here by a rounding hair
    // outside it still spans at least one cell, and a shared point stays shared).
    let clip = |i: u32| {
        let (l, h) = boxes[i as usize];
        let clamp = |x: f64, k: usize| x.max(lo[k]).min(hi[k]);
        ([clamp(l[0], 0), clamp(l[1], 1)], [clamp(h[0], 0), clamp(h[1], 1)])
    };
    let mean = ids
        .iter()
        .map(|&i| {
            let (l, h) = clip(i);
            (h[0] - l[0]).max(h[1] - l[1])
        })
        .sum::<f64>()
        / ids.len() as f64;
    let widest = extent[0].max(extent[1]);
    let most = if depth == 0 { MAX_CELLS_TOP } else { MAX_CELLS_SUB };
    let mut cell = mean.max(widest / most);
    if !(cell > 0.0 && cell.is_finite()) {
        return every_pair(visit); // every box on one point or one line along an axis
    }
    // Cells per axis, the cell of a coordinate (monotone, clamped), and a box's cell range.
    let cells = |cell: f64| [0, 1].map(|k| ((extent[k] / cell) as usize + 1).min(most as usize));
    let index = |x: f64, k: usize, cell: f64, n: usize| ((((x - lo[k]) / cell).max(0.0)) as usize).min(n - 1);
    let span = |i: u32, cell: f64, n: [usize; 2]| {
        let (l, h) = clip(i);
        [0, 1].map(|k| [index(l[k], k, cell, n[k]), index(h[k], k, cell, n[k])])
    };
    let entries = |cell: f64| {
        let n = cells(cell);
        ids.iter().map(|&i| {
            let s = span(i, cell, n);
            (s[0][1] - s[0][0] + 1) * (s[1][1] - s[1][0] + 1)
        })
        .sum::<usize>()
    };
    while entries(cell) > MAX_ENTRIES_PER_BOX * ids.len() {
        cell *= 2.0;
    }
    let n = cells(cell);
    if n[0] * n[1] < 2 {
        return every_pair(visit);
    }
    let mut binned: Vec<(u32, u32)> = Vec::new();
    for &i in ids {
        let s = span(i, cell, n);
        for gy in s[1][0]..=s[1][1] {
            for gx in s[0][0]..=s[0][1] {
                binned.push(((gy * n[0] + gx) as u32, i));
            }
        }
    }
    binned.sort_unstable();
    let mut a = 0;
    while a < binned.len() {
        let mut b = a;
        while b < binned.len() && binned[b].0 == binned[a].0 {
            b += 1;
        }
        if b - a >= 2 {
            let members: Vec<u32> = binned[a..b].iter().map(|e| e.1).collect();
            let c = binned[a].0 as usize;
            let (gx, gy) = (c % n[0], c / n[0]);
            // The cell's own region (the last cells reach the region's far side).
            let from = [lo[0] + gx as f64 * cell, lo[1] + gy as f64 * cell];
            let to = [
                if gx + 1 == n[0] { hi[0] } else { lo[0] + (gx + 1) as f64 * cell },
                if gy + 1 == n[1] { hi[1] } else { lo[1] + (gy + 1) as f64 * cell },
            ];
            // A cell no box left out would not thin by refining again: pair by pair.
            let next = if members.len() == ids.len() { MAX_DEPTH + 1 } else { depth + 1 };
            cell_pairs(boxes, &members, (from, to), next, visit)?;
        }
        a = b;
    }
    ControlFlow::Continue(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair of boxes that share a point, by testing all pairs.
    fn all_pairs(boxes: &[Box2]) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if share_point(boxes[i], boxes[j]) {
                    out.push((i as u32, j as u32));
                }
            }
        }
        out
    }

    /// A deterministic stream of numbers in [0, 1).
    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn finds_every_pair_of_a_crowded_and_uneven_field() {
        // Many tiny boxes crowded into a corner (as a crushed region of a map), a few large
        // ones across everything, boxes touching at an edge or a corner, and degenerate boxes
        // (a point, a segment along an axis).
        let mut seed = 7u64;
        let mut boxes: Vec<Box2> = Vec::new();
        for _ in 0..3000 {
            let (x, y) = (1e-3 * lcg(&mut seed), 1e-3 * lcg(&mut seed));
            let s = 1e-5 * lcg(&mut seed);
            boxes.push(([x, y], [x + s, y + 0.5 * s]));
        }
        for _ in 0..400 {
            let (x, y) = (lcg(&mut seed), lcg(&mut seed));
            let s = 0.05 * lcg(&mut seed);
            boxes.push(([x, y], [x + s, y + s]));
        }
        for _ in 0..5 {
            let (x, y) = (0.5 * lcg(&mut seed), 0.5 * lcg(&mut seed));
            boxes.push(([x, y], [x + 0.5, y + 0.5]));
        }
        boxes.push(([0.25, 0.25], [0.5, 0.5]));
        boxes.push(([0.5, 0.5], [0.75, 0.6])); // touches the one before at a corner
        boxes.push(([0.3, 0.3], [0.3, 0.3])); // a point
        boxes.push(([0.2, 0.4], [0.9, 0.4])); // a segment
        let found = overlapping_pairs(&boxes, |_, _| true);
        assert_eq!(found, all_pairs(&boxes));
    }

    #[test]
    fn refining_keeps_the_tests_near_linear_on_a_crushed_field() {
        // 20,000 disjoint tiny boxes in a few cells of the first grid (sized by 200 large
        // ones): a grid of one level tests millions of pairs there.
        let mut boxes: Vec<Box2> = Vec::new();
        for k in 0..200 {
            let x = (k % 20) as f64 * 1.0;
            let y = (k / 20) as f64 * 1.0;
            boxes.push(([x, y], [x + 0.9, y + 0.9]));
        }
        for k in 0..20_000 {
            let x = 0.95 + (k % 200) as f64 * 2.4e-4;
            let y = 0.95 + (k / 200) as f64 * 2.4e-4;
            boxes.push(([x, y], [x + 1e-4, y + 1e-4]));
        }
        let mut visits = 0usize;
        let mut found = 0;
        let _ = visit_pairs(&boxes, |i, j| {
            visits += 1;
            found += share_point(boxes[i as usize], boxes[j as usize]) as usize;
            ControlFlow::Continue(())
        });
        assert_eq!(found, 0);
        assert!(visits < 50 * boxes.len(), "{visits} pairs visited for {} boxes", boxes.len());
    }

    #[test]
    fn a_visit_that_breaks_stops_the_search() {
        let boxes: Vec<Box2> = (0..100).map(|_| ([0.0, 0.0], [1.0, 1.0])).collect();
        let mut visits = 0;
        let r = visit_pairs(&boxes, |_, _| {
            visits += 1;
            if visits == 3 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        assert!(r.is_break());
        assert_eq!(visits, 3);
    }

    #[test]
    fn non_finite_and_reversed_boxes_are_skipped() {
        let boxes: Vec<Box2> = vec![
            ([0.0, 0.0], [1.0, 1.0]),
            ([f64::NAN, 0.0], [1.0, 1.0]),
            ([0.5, 0.5], [0.4, 0.6]),
            ([0.5, 0.5], [2.0, 2.0]),
        ];
        assert_eq!(overlapping_pairs(&boxes, |_, _| true), vec![(0, 3)]);
    }
}
