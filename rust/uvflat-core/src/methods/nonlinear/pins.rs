//! How the nonlinear methods honour pins and fix their gauge.
//!
//! * A global step of a translation-invariant energy (ARAP, SLIM) needs fixed values:
//!   [`anchors`] gives all pins when they span more than a point, else one vertex at its
//!   current UV (the energy is translation invariant, so this loses nothing).
//! * Methods whose energy is similarity invariant and does not see pins (MIPS, scaffold) move
//!   the finished map onto the pins by the least-squares similarity
//!   ([`honour_pins_by_similarity`], exact for one or two pins), and fix the similarity gauge of
//!   their Newton system by two far-apart boundary vertices ([`gauge_vertices`]).
//!
//! Preconditions: pin and vertex ids in range of `uv`; a chart with a boundary loop for
//! [`gauge_vertices`]. Failures: none.

use crate::charts::Chart;
use crate::methods::lscm::pins_span;

/// The vertices held fixed by a global step and their UVs: all pins when they span more than
/// a point, else the first pin (or vertex 0 without pins) at its current UV.
pub fn anchors(pins: &[(u32, [f64; 2])], uv: &[[f64; 2]]) -> Vec<(u32, [f64; 2])> {
    if pins_span(pins) {
        pins.to_vec()
    } else {
        anchor_vertices(pins).into_iter().map(|v| (v, uv[v as usize])).collect()
    }
}

/// The vertices of [`anchors`], known before any map: all pins when they span more than a
/// point, else the first pin (or vertex 0 without pins).
pub fn anchor_vertices(pins: &[(u32, [f64; 2])]) -> Vec<u32> {
    if pins_span(pins) {
        pins.iter().map(|p| p.0).collect()
    } else {
        vec![pins.first().map_or(0, |p| p.0)]
    }
}

/// Translate `uv` so that the first pin's vertex lands on its UV (no-op without pins).
pub fn translate_onto_first_pin(uv: &mut [[f64; 2]], pins: &[(u32, [f64; 2])]) {
    if let Some(&(v, target)) = pins.first() {
        let d = [target[0] - uv[v as usize][0], target[1] - uv[v as usize][1]];
        for p in uv.iter_mut() {
            *p = [p[0] + d[0], p[1] + d[1]];
        }
    }
}

/// Move a finished map onto the pins by the least-squares similarity (a translation onto the
/// first pin when the pins do not span more than a point); returns the report's note, `None`
/// without pins.
pub fn honour_pins_by_similarity(uv: &mut [[f64; 2]], pins: &[(u32, [f64; 2])], method: &str) -> Option<String> {
    if pins.is_empty() {
        return None;
    }
    let mut target = vec![[f64::NAN; 2]; uv.len()];
    for &(v, p) in pins {
        target[v as usize] = p;
    }
    let moved = pins_span(pins) && crate::metrics::fit_similarity_points(uv, &target);
    if !moved {
        translate_onto_first_pin(uv, pins);
    }
    Some(format!(
        "{} pinned vertex(es): the {method} map was moved onto them by a least-squares similarity (exact for one or two pins)",
        pins.len()
    ))
}

/// Two far-apart vertices of the outer loop (the first one, and the one farthest from it in
/// UV), the similarity gauge of a Newton system.
pub fn gauge_vertices(chart: &Chart, uv: &[[f64; 2]]) -> [u32; 2] {
    let outer = &chart.boundary_loops[chart.outer_loop().unwrap_or(0)];
    let a = outer[0];
    let pa = uv[a as usize];
    let b = outer
        .iter()
        .copied()
        .max_by(|&x, &y| {
            let d = |v: u32| (uv[v as usize][0] - pa[0]).hypot(uv[v as usize][1] - pa[1]);
            d(x).total_cmp(&d(y))
        })
        .unwrap_or(a);
    [a, b]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_are_the_pins_when_they_span_else_one_vertex_where_it_is() {
        let uv = vec![[0.5, 0.5], [1.0, 2.0], [3.0, 4.0]];
        assert_eq!(anchors(&[], &uv), vec![(0, [0.5, 0.5])]);
        assert_eq!(anchors(&[(2, [9.0, 9.0])], &uv), vec![(2, [3.0, 4.0])]);
        let pins = [(1, [0.0, 0.0]), (2, [1.0, 0.0])];
        assert_eq!(anchors(&pins, &uv), pins.to_vec());
    }

    #[test]
    fn a_similar_map_lands_exactly_on_two_pins() {
        let mut uv = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        // The pins are the map rotated by 90°, scaled by 2 and moved.
        let pins = [(0, [5.0, 5.0]), (1, [5.0, 7.0])];
        assert!(honour_pins_by_similarity(&mut uv, &pins, "test").is_some());
        let want = [[5.0, 5.0], [5.0, 7.0], [3.0, 5.0]];
        for (p, q) in uv.iter().zip(want) {
            assert!((p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12, "{uv:?}");
        }
        let mut one = vec![[0.0, 0.0], [1.0, 0.0]];
        honour_pins_by_similarity(&mut one, &[(1, [3.0, 3.0])], "test");
        assert_eq!(one, vec![[2.0, 3.0], [3.0, 3.0]]);
        assert!(honour_pins_by_similarity(&mut one, &[], "test").is_none());
    }
}
