//! How the nonlinear methods honour pins and fix their gauge.
//!
//! Pins are a promise: a pinned vertex ends exactly at its pinned UV, whatever the method.
//!
//! * A global step of a translation-invariant energy (ARAP, SLIM, scaffold) or a Newton step
//!   (MIPS) holds fixed values: [`anchors`] gives all pins when they span more than a point
//!   (the pins are Dirichlet values of every step, so they never move), else one vertex at
//!   its current UV (the energy is translation invariant, so this loses nothing).
//! * Energies measured against the 3D shape (ARAP, SLIM, scaffold's symmetric Dirichlet) want
//!   the 3D scale; pins spanning more than a point fix another scale. Such charts are solved
//!   against their 3D shape scaled by [`pins_scale`] (the scale of the least-squares
//!   similarity from the chart's free LSCM map onto the pins, times that map's area scale), so
//!   the unpinned part lies at the pins' scale, as Blender's Minimum Stretch does, instead
//!   of at 3D scale around them.
//! * Methods whose energy is similarity invariant (MIPS) need no scale; without spanning pins
//!   they fix their similarity gauge by two far-apart boundary vertices ([`gauge_vertices`])
//!   and are translated onto a single pin afterwards ([`translate_onto_first_pin`], exact).
//! * A method that finds no flip-free start honouring the pins falls back to a pinned map
//!   ([`pinned_fallback`]: pinned LSCM or the pinned mean value map, whichever flips less),
//!   never to a map that ignores them.
//!
//! Preconditions: pin and vertex ids in range of `uv` (or of the chart), one pin per vertex;
//! a chart with a boundary loop for [`gauge_vertices`]. Failures: [`pinned_fallback`] fails
//! like [`crate::methods::lscm::solve`] when neither pinned map can be computed; the others
//! none.

use crate::charts::Chart;
use crate::methods::lscm::pins_span;
use crate::methods::{ChartFailure, ChartSolution, Fallback};

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

/// Translate `uv` so that the first pin's vertex lands on its UV (no-op without pins). The
/// pinned vertex gets its UV bit for bit (`x + (t − x)` may differ from `t` in the last bit).
pub fn translate_onto_first_pin(uv: &mut [[f64; 2]], pins: &[(u32, [f64; 2])]) {
    if let Some(&(v, target)) = pins.first() {
        let d = [target[0] - uv[v as usize][0], target[1] - uv[v as usize][1]];
        for p in uv.iter_mut() {
            *p = [p[0] + d[0], p[1] + d[1]];
        }
        uv[v as usize] = target;
    }
}

/// The scale pins spanning more than a point give a chart: the least-squares similarity
/// `w ≈ a z + b` (complex) from the chart's free LSCM map `z` onto the pinned UVs `w`,
/// `|a|`, times the free map's area scale `sqrt(UV area / 3D area)`. For pins taken from a
/// similar copy of the LSCM map this is exactly that copy's area scale. `None` without
/// spanning pins, or when the free map cannot be computed or has no positive area (the
/// caller then keeps the 3D scale).
pub fn pins_scale(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Option<f64> {
    if !pins_span(pins) {
        return None;
    }
    let angles = crate::methods::chart_angles(&chart.positions, &chart.triangles);
    let (z, _) = crate::methods::lscm::solve_free(chart, &angles, &[]).ok()?;
    let a = similarity_scale(&z, pins)?;
    let (mut uv_area, mut area) = (0.0, 0.0);
    for t in &chart.triangles {
        let [p, q, r] = t.map(|v| chart.positions[v as usize]);
        area += crate::geometry::triangle_area([p, q, r]);
        uv_area += crate::geometry::signed_area_2d(t.map(|v| z[v as usize]));
    }
    let s = a * (uv_area / area).sqrt();
    (s.is_finite() && s > 0.0).then_some(s)
}

/// `|a|` of the least-squares similarity `w ≈ a z + b` from the points `z[v]` onto the pinned
/// UVs `w` of `pins`; `None` when the pinned vertices coincide in `z`.
pub fn similarity_scale(z: &[[f64; 2]], pins: &[(u32, [f64; 2])]) -> Option<f64> {
    let k = pins.len() as f64;
    let (mut mz, mut mw) = ([0.0; 2], [0.0; 2]);
    for &(v, w) in pins {
        let p = z[v as usize];
        mz = [mz[0] + p[0] / k, mz[1] + p[1] / k];
        mw = [mw[0] + w[0] / k, mw[1] + w[1] / k];
    }
    let (mut re, mut im, mut den) = (0.0, 0.0, 0.0);
    for &(v, w) in pins {
        let a = [z[v as usize][0] - mz[0], z[v as usize][1] - mz[1]];
        let b = [w[0] - mw[0], w[1] - mw[1]];
        re += a[0] * b[0] + a[1] * b[1];
        im += a[0] * b[1] - a[1] * b[0];
        den += a[0] * a[0] + a[1] * a[1];
    }
    let s = re.hypot(im) / den;
    (den > 0.0 && s.is_finite()).then_some(s)
}

/// The rest positions of an energy measured against the 3D shape: the chart's positions
/// scaled by [`pins_scale`] when pins span more than a point, else the chart's own. Returns
/// the positions and the scale applied (`None`: none).
pub fn rest_positions<'a>(chart: &'a Chart, pins: &[(u32, [f64; 2])]) -> (std::borrow::Cow<'a, [[f64; 3]]>, Option<f64>) {
    match pins_scale(chart, pins) {
        Some(s) => (chart.positions.iter().map(|p| [s * p[0], s * p[1], s * p[2]]).collect::<Vec<_>>().into(), Some(s)),
        None => (std::borrow::Cow::Borrowed(&chart.positions[..]), None),
    }
}

/// The report's words for a rest shape scaled by [`rest_positions`].
pub fn pins_scale_note(pins: usize, scale: Option<f64>) -> Option<String> {
    scale.map(|s| format!("{pins} pinned vertex(es) held fixed; the rest of the chart solved at the pins' scale ({s:.4} × 3D)"))
}

/// The map a method falls back to when it has no flip-free start honouring `pins`: pinned
/// LSCM ([`crate::methods::lscm::solve`]) or the pinned mean value map on a circle
/// ([`crate::methods::nonlinear::start::mean_value_start`]), whichever has fewer flipped
/// triangles and folded quads (LSCM on a tie); both hold every pin exactly (a single pin by
/// translation). Marked as a fallback with `why`. Failures: when neither can be computed,
/// LSCM's reason.
pub fn pinned_fallback(chart: &Chart, pins: &[(u32, [f64; 2])], why: &str) -> Result<ChartSolution, ChartFailure> {
    let flips = |uv: &[[f64; 2]]| crate::metrics::count_flips_with_quads(&chart.triangles, &chart.quads, uv);
    let lscm = crate::methods::lscm::solve(chart, pins);
    let mean_value = super::start::mean_value_start(chart, pins);
    let (name, mut sol) = match (lscm, mean_value) {
        (Ok(l), Ok(m)) => {
            if flips(&m.uv) < flips(&l.uv) {
                ("mean_value", m)
            } else {
                ("lscm", l)
            }
        }
        (Ok(l), Err(_)) => ("lscm", l),
        (Err(_), Ok(m)) => ("mean_value", m),
        (Err(e), Err(_)) => return Err(e),
    };
    if !pins_span(pins) {
        translate_onto_first_pin(&mut sol.uv, pins);
    }
    let reason = match sol.note.take() {
        Some(n) => format!("{why}; {name} used instead ({n})"),
        None => format!("{why}; {name} used instead"),
    };
    sol.fallback = Some(Fallback { method: name, reason });
    Ok(sol)
}

/// Translate a finished map onto a pin that does not span (one pin, or pins sharing one UV:
/// the first is held exactly); returns the report's note, `None` without pins or with pins
/// spanning more than a point (those are held by the solve itself).
pub fn translate_onto_single_pin(uv: &mut [[f64; 2]], pins: &[(u32, [f64; 2])], method: &str) -> Option<String> {
    if pins.is_empty() || pins_span(pins) {
        return None;
    }
    translate_onto_first_pin(uv, pins);
    Some(if pins.len() == 1 {
        format!("one pinned vertex: the {method} map was translated onto it")
    } else {
        format!("all pins share one UV: the {method} map was translated onto it")
    })
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
    fn a_single_pin_is_reached_bit_for_bit() {
        // 0.1 + (0.3 − 0.1) is not 0.3 in floating point: the pin must still hold exactly.
        let mut one = vec![[0.1, 0.7], [1.1, 0.2]];
        let note = translate_onto_single_pin(&mut one, &[(0, [0.3, 1e-17])], "test");
        assert!(note.is_some());
        assert_eq!(one[0], [0.3, 1e-17]);
        assert!((one[1][0] - 1.3).abs() < 1e-15 && (one[1][1] + 0.5).abs() < 1e-15, "{one:?}");
        // Spanning pins are held by the solve, not moved onto here.
        let mut two = one.clone();
        assert!(translate_onto_single_pin(&mut two, &[(0, [0.0, 0.0]), (1, [1.0, 0.0])], "test").is_none());
        assert_eq!(two, one);
    }

    #[test]
    fn the_similarity_scale_is_exact_for_a_similar_copy() {
        let z = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.3, 0.4]];
        let (c, s) = (2.5 * 0.7f64.cos(), 2.5 * 0.7f64.sin());
        let pins: Vec<(u32, [f64; 2])> = (0..4u32).map(|v| {
            let p = z[v as usize];
            (v, [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 1.0])
        }).collect();
        assert!((similarity_scale(&z, &pins).unwrap() - 2.5).abs() < 1e-12);
        assert!(similarity_scale(&z, &[(0, [1.0, 1.0]), (0, [2.0, 2.0])]).is_none());
    }
}
