//! The scaffold's couplings between chart vertices: *chords*, scaffold edges joining two
//! boundary vertices that are not chart edges. The global step's pattern
//! ([`crate::methods::nonlinear::pattern::BlockPattern`]) holds a set of chords and serves
//! every scaffold whose chords are among them.
//!
//! Preconditions: sorted, unique pair lists `(a, b)`, `a > b`. Failures: none.

/// Whether the sorted list `a` is a subset of the sorted list `b`.
pub(super) fn is_subset(a: &[(u32, u32)], b: &[(u32, u32)]) -> bool {
    let mut i = 0;
    for x in a {
        while i < b.len() && b[i] < *x {
            i += 1;
        }
        if i == b.len() || b[i] != *x {
            return false;
        }
    }
    true
}

/// Chords of a scaffold: its edges between two chart vertices (`< n`) that are not chart
/// edges, as `(a, b)`, `a > b`, sorted and unique.
pub(super) fn scaffold_chords(n: usize, scaffold: &[[u32; 3]], edges: &[(u32, u32)]) -> Vec<(u32, u32)> {
    let mut c: Vec<(u32, u32)> = scaffold
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| (a as usize) < n && (b as usize) < n)
        .map(|(a, b)| (a.max(b), a.min(b)))
        .filter(|e| edges.binary_search(e).is_err())
        .collect();
    c.sort_unstable();
    c.dedup();
    c
}
