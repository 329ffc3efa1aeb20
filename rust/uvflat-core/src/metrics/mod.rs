//! Quality of a UV map, computed independently of any solver (DESIGN.md definitions).
//!
//! For each triangle, J is the Jacobian of the map from the triangle (in a local 2D frame of
//! its plane) to its UV triangle, with singular values σ1 ≥ σ2. Before measuring, each chart's
//! UVs are scaled so its UV area equals its 3D area. Weights are 3D areas over the total.
//! * flips: triangles whose signed UV area has the opposite sign to the chart's majority,
//!   plus zero-area UV triangles ([`is_flipped`]). The triangles are the render triangulation
//!   when one is given (else the core's own), and a quad counts as folded when either of its
//!   two diagonal splits has such a triangle: exporters and engines choose their own diagonal,
//!   so a flip-free quad is a strictly convex UV quad;
//! * overlap: the chart's UV boundary crosses or touches itself;
//! * conformal Σ w σ1/σ2; area Σ w max(σ1σ2, 1/(σ1σ2)); symmetric Dirichlet
//!   Σ w (σ1² + σ2² + σ1⁻² + σ2⁻²)/4. All are 1 for an isometry; a zero-area UV triangle with
//!   positive 3D area makes them infinite.

use crate::charts::{build_charts_with, FaceTriangulation, Quad};
use crate::error::{Result, UvError};
use crate::geometry::{cross2, local_frame, signed_area_2d, triangle_area};
use crate::mesh::PolyMesh;

/// Area-weighted distortion measures (1 is perfect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// Σ w σ1/σ2.
    pub conformal: f64,
    /// Σ w max(σ1σ2, 1/(σ1σ2)).
    pub area: f64,
    /// Σ w (σ1² + σ2² + σ1⁻² + σ2⁻²)/4.
    pub symmetric_dirichlet: f64,
}

impl Distortion {
    /// All NaN: the value reported for a chart without UVs.
    pub fn nan() -> Self {
        Distortion { conformal: f64::NAN, area: f64::NAN, symmetric_dirichlet: f64::NAN }
    }
}

/// Quality of one chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartMetrics {
    /// Number of input faces (for [`measure`]) or triangles (for [`chart_metrics`]).
    pub faces: usize,
    /// Flipped plus zero-area UV triangles.
    pub flips: usize,
    /// Whether the UV boundary crosses or touches itself.
    pub overlap: bool,
    /// Distortion of the chart, area-normalised.
    pub distortion: Distortion,
    /// 3D area of the chart (weight of the chart in a whole-mesh average).
    pub area_3d: f64,
}

/// Quality of a whole UV map.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshMetrics {
    /// Number of UV islands (charts).
    pub charts: usize,
    /// Flipped plus zero-area triangles, summed over charts.
    pub flips: usize,
    /// Charts whose boundary crosses itself.
    pub overlapping_charts: usize,
    /// Distortion over all measured triangles (each chart area-normalised first).
    pub distortion: Distortion,
    /// One entry per chart.
    pub per_chart: Vec<ChartMetrics>,
}

/// Singular values (σ1 ≥ σ2 ≥ 0) and sign of the determinant of a 2×2 matrix [[a, b], [c, d]].
pub fn singular_values_2x2(a: f64, b: f64, c: f64, d: f64) -> (f64, f64, f64) {
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = (e * e + h * h).sqrt();
    let r = (f * f + g * g).sqrt();
    let det = a * d - b * c;
    (q + r, (q - r).abs(), det.signum())
}

/// The one flip predicate: a UV triangle is flipped (or degenerate) when its doubled signed
/// area, taken with the chart's orientation (positive for a well-oriented triangle), is not
/// above round-off level of `scale`, the product of two of its edge lengths (`|e1| |e2|`,
/// the largest the doubled area can be). Every flip count in the crate goes through here.
#[inline]
pub fn is_flipped(signed_area: f64, scale: f64) -> bool {
    !(signed_area > 1e-12 * scale) || scale == 0.0
}

/// Doubled signed area and scale (`|e1| |e2|`) of a UV triangle, for [`is_flipped`].
#[inline]
fn area_and_scale(q: [[f64; 2]; 3]) -> (f64, f64) {
    let e1 = [q[1][0] - q[0][0], q[1][1] - q[0][1]];
    let e2 = [q[2][0] - q[0][0], q[2][1] - q[0][1]];
    (cross2(e1, e2), (e1[0].hypot(e1[1])) * (e2[0].hypot(e2[1])))
}

/// Whether a UV triangle is degenerate (its area is at round-off level of its edges), in
/// either orientation.
#[inline]
pub fn uv_degenerate(q: [[f64; 2]; 3]) -> bool {
    let (c, l) = area_and_scale(q);
    is_flipped(c.abs(), l)
}

/// Number of folded triangles of one quad with `orientation` (+1 or −1): the larger count
/// of flipped triangles ([`is_flipped`]) over its two diagonal splits; 0 exactly when the UV
/// quad is strictly convex with that orientation.
pub fn quad_folds(q: &Quad, uv: &[[f64; 2]], orientation: f64) -> usize {
    let t = q.all_splits();
    let f = |k: usize| {
        let (a, l) = area_and_scale([uv[t[k][0] as usize], uv[t[k][1] as usize], uv[t[k][2] as usize]]);
        is_flipped(orientation * a, l) as usize
    };
    (f(0) + f(1)).max(f(2) + f(3))
}

/// Measure one chart given per-vertex positions and UVs over its triangles (no quads: every
/// triangle counts on its own; see [`chart_metrics_with_quads`]).
pub fn chart_metrics(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uv: &[[f64; 2]],
    boundary_loops: &[Vec<u32>],
) -> ChartMetrics {
    chart_metrics_with_quads(positions, triangles, &[], uv, boundary_loops)
}

/// Measure one chart given per-vertex positions and UVs over its triangles, with its quad
/// faces (whose two triangles are among `triangles`): the flips of a quad are counted by
/// [`quad_folds`] (both diagonal splits) instead of from its own two triangles. Distortion is
/// measured on `triangles`.
pub fn chart_metrics_with_quads(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    quads: &[Quad],
    uv: &[[f64; 2]],
    boundary_loops: &[Vec<u32>],
) -> ChartMetrics {
    let mut in_quad = vec![false; if quads.is_empty() { 0 } else { triangles.len() }];
    for q in quads {
        for &t in &q.triangles {
            in_quad[t as usize] = true;
        }
    }
    let get3 = |t: &[u32; 3]| [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
    let get2 = |t: &[u32; 3]| [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
    let mut area3 = 0.0;
    let mut area2 = 0.0;
    let mut pos = 0usize;
    let mut neg = 0usize;
    for t in triangles {
        area3 += triangle_area(get3(t));
        let a = signed_area_2d(get2(t));
        area2 += a.abs();
        if a > 0.0 {
            pos += 1;
        } else if a < 0.0 {
            neg += 1;
        }
    }
    let majority = if neg > pos { -1.0 } else { 1.0 };
    let scale = if area2 > 0.0 { (area3 / area2).sqrt() } else { 1.0 };
    let mut flips = 0usize;
    let mut sum = [0.0f64; 3];
    for (ti, t) in triangles.iter().enumerate() {
        let q2 = get2(t);
        let (a, l) = area_and_scale(q2);
        let degenerate = is_flipped(a.abs(), l);
        if is_flipped(majority * a, l) && !in_quad.get(ti).copied().unwrap_or(false) {
            flips += 1;
        }
        let p = get3(t);
        let w = triangle_area(p);
        if w <= 0.0 || area3 <= 0.0 {
            continue;
        }
        let (s1, s2) = if degenerate || area2 == 0.0 {
            (f64::INFINITY, 0.0)
        } else {
            let q = local_frame(p);
            // J = [du1 du2] · inv([dq1 dq2])
            let (x1, y1) = (q[1][0] - q[0][0], q[1][1] - q[0][1]);
            let (x2, y2) = (q[2][0] - q[0][0], q[2][1] - q[0][1]);
            let det = x1 * y2 - x2 * y1;
            let (u1, v1) = (scale * (q2[1][0] - q2[0][0]), scale * (q2[1][1] - q2[0][1]));
            let (u2, v2) = (scale * (q2[2][0] - q2[0][0]), scale * (q2[2][1] - q2[0][1]));
            // inv = 1/det [[y2, -x2], [-y1, x1]]
            let a11 = (u1 * y2 - u2 * y1) / det;
            let a12 = (-u1 * x2 + u2 * x1) / det;
            let a21 = (v1 * y2 - v2 * y1) / det;
            let a22 = (-v1 * x2 + v2 * x1) / det;
            let (s1, s2, _) = singular_values_2x2(a11, a12, a21, a22);
            (s1, s2)
        };
        let wn = w / area3;
        if s2 > 0.0 && s1.is_finite() {
            sum[0] += wn * s1 / s2;
            sum[1] += wn * (s1 * s2).max(1.0 / (s1 * s2));
            sum[2] += wn * 0.25 * (s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2));
        } else {
            sum = [f64::INFINITY; 3];
        }
    }
    flips += quads.iter().map(|q| quad_folds(q, uv, majority)).sum::<usize>();
    if !(area3 > 0.0) {
        // No 3D area: distortion is undefined, not perfect.
        sum = [f64::NAN; 3];
    }
    let overlap = boundary_self_overlap(uv, boundary_loops);
    ChartMetrics {
        faces: triangles.len(),
        flips,
        overlap,
        distortion: Distortion { conformal: sum[0], area: sum[1], symmetric_dirichlet: sum[2] },
        area_3d: area3,
    }
}

/// Whether the UV boundary (all loops of one chart) crosses or touches itself anywhere other
/// than at the shared endpoint of consecutive edges.
pub fn boundary_self_overlap(uv: &[[f64; 2]], loops: &[Vec<u32>]) -> bool {
    let mut segs: Vec<(u32, u32)> = Vec::new();
    for lp in loops {
        for i in 0..lp.len() {
            segs.push((lp[i], lp[(i + 1) % lp.len()]));
        }
    }
    let n = segs.len();
    if n < 2 {
        return false;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut total_len = 0.0;
    for &(a, b) in &segs {
        for p in [uv[a as usize], uv[b as usize]] {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let (pa, pb) = (uv[a as usize], uv[b as usize]);
        total_len += (pb[0] - pa[0]).hypot(pb[1] - pa[1]);
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(extent > 0.0) {
        return true; // everything collapsed onto one point
    }
    let cell = (total_len / n as f64).max(extent / 1024.0);
    let nx = (((hi[0] - lo[0]) / cell) as usize + 1).min(1024);
    let ny = (((hi[1] - lo[1]) / cell) as usize + 1).min(1024);
    let cx = |x: f64| (((x - lo[0]) / cell) as usize).min(nx - 1);
    let cy = |y: f64| (((y - lo[1]) / cell) as usize).min(ny - 1);
    let mut grid: std::collections::HashMap<usize, Vec<u32>> = std::collections::HashMap::new();
    for (i, &(a, b)) in segs.iter().enumerate() {
        let (pa, pb) = (uv[a as usize], uv[b as usize]);
        for gx in cx(pa[0].min(pb[0]))..=cx(pa[0].max(pb[0])) {
            for gy in cy(pa[1].min(pb[1]))..=cy(pa[1].max(pb[1])) {
                grid.entry(gy * nx + gx).or_default().push(i as u32);
            }
        }
    }
    for bucket in grid.values() {
        for x in 0..bucket.len() {
            for y in x + 1..bucket.len() {
                let (s, t) = (segs[bucket[x] as usize], segs[bucket[y] as usize]);
                let shared = s.0 == t.0 || s.0 == t.1 || s.1 == t.0 || s.1 == t.1;
                let (p1, p2, p3, p4) = (uv[s.0 as usize], uv[s.1 as usize], uv[t.0 as usize], uv[t.1 as usize]);
                if shared {
                    // Consecutive edges: overlap only if they fold back onto each other.
                    if s.0 == t.1 && s.1 == t.0 {
                        continue; // a two-edge loop
                    }
                    let (o, a, b) = if s.1 == t.0 {
                        (p2, p1, p4)
                    } else if s.0 == t.1 {
                        (p1, p2, p3)
                    } else if s.0 == t.0 {
                        (p1, p2, p4)
                    } else {
                        (p2, p1, p3)
                    };
                    let u = [a[0] - o[0], a[1] - o[1]];
                    let v = [b[0] - o[0], b[1] - o[1]];
                    if cross2(u, v) == 0.0 && u[0] * v[0] + u[1] * v[1] > 0.0 {
                        return true;
                    }
                    continue;
                }
                if segments_intersect(p1, p2, p3, p4) {
                    return true;
                }
            }
        }
    }
    false
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0]) && p[0] <= a[0].max(b[0]) && p[1] >= a[1].min(b[1]) && p[1] <= a[1].max(b[1])
}

/// Closed segments [p1,p2] and [p3,p4] share a point.
pub fn segments_intersect(p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], p4: [f64; 2]) -> bool {
    let d1 = orient(p3, p4, p1);
    let d2 = orient(p3, p4, p2);
    let d3 = orient(p1, p2, p3);
    let d4 = orient(p1, p2, p4);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    (d1 == 0.0 && on_segment(p3, p4, p1))
        || (d2 == 0.0 && on_segment(p3, p4, p2))
        || (d3 == 0.0 && on_segment(p1, p2, p3))
        || (d4 == 0.0 && on_segment(p1, p2, p4))
}

/// Scale a chart's UVs so its UV area equals its 3D area and centre its bounding box on
/// `center`. A chart with zero UV area is only translated.
pub fn area_normalize(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &mut [[f64; 2]], center: [f64; 2]) {
    let mut a3 = 0.0;
    let mut a2 = 0.0;
    for t in triangles {
        a3 += triangle_area([positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]]);
        a2 += signed_area_2d([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]).abs();
    }
    let s = if a2 > 0.0 && a3 > 0.0 { (a3 / a2).sqrt() } else { 1.0 };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in uv.iter() {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    for p in uv.iter_mut() {
        *p = [center[0] + s * (p[0] - mid[0]), center[1] + s * (p[1] - mid[1])];
    }
}

/// Least-squares similarity (uniform scale, rotation, translation; no reflection) taking `uv`
/// onto `target` (per vertex; NaN targets are ignored), applied in place.
///
/// Returns `false` and leaves `uv` unchanged when the target is degenerate (its triangles have
/// no area, so there is no place to fit to).
pub fn fit_similarity(uv: &mut [[f64; 2]], target: &[[f64; 2]], triangles: &[[u32; 3]]) -> bool {
    let target_area: f64 = triangles
        .iter()
        .map(|t| {
            let q = [target[t[0] as usize], target[t[1] as usize], target[t[2] as usize]];
            if q.iter().any(|p| p[0].is_nan()) {
                0.0
            } else {
                signed_area_2d(q).abs()
            }
        })
        .sum();
    if !(target_area > 1e-30) {
        return false;
    }
    fit_similarity_points(uv, target)
}

/// Least-squares similarity (no reflection) taking `uv` onto `target` at the vertices whose
/// target is not NaN, applied in place. Returns `false` (and changes nothing) when fewer than
/// two distinct points take part.
pub fn fit_similarity_points(uv: &mut [[f64; 2]], target: &[[f64; 2]]) -> bool {
    let (mut n, mut ms, mut mt) = (0.0, [0.0; 2], [0.0; 2]);
    for (s, t) in uv.iter().zip(target) {
        if t[0].is_nan() {
            continue;
        }
        n += 1.0;
        ms = [ms[0] + s[0], ms[1] + s[1]];
        mt = [mt[0] + t[0], mt[1] + t[1]];
    }
    if n == 0.0 {
        return false;
    }
    ms = [ms[0] / n, ms[1] / n];
    mt = [mt[0] / n, mt[1] / n];
    // Complex least squares: t - mt ≈ z (s - ms), z = Σ conj(s')t' / Σ |s'|².
    let (mut re, mut im, mut den) = (0.0, 0.0, 0.0);
    for (s, t) in uv.iter().zip(target) {
        if t[0].is_nan() {
            continue;
        }
        let a = [s[0] - ms[0], s[1] - ms[1]];
        let b = [t[0] - mt[0], t[1] - mt[1]];
        re += a[0] * b[0] + a[1] * b[1];
        im += a[0] * b[1] - a[1] * b[0];
        den += a[0] * a[0] + a[1] * a[1];
    }
    if !(den > 0.0) {
        return false;
    }
    let (zr, zi) = (re / den, im / den);
    for p in uv.iter_mut() {
        let a = [p[0] - ms[0], p[1] - ms[1]];
        *p = [mt[0] + zr * a[0] - zi * a[1], mt[1] + zi * a[0] + zr * a[1]];
    }
    true
}

/// Measure an existing per-corner UV map of a polygon mesh (for example Blender's own unwrap).
///
/// Islands are the faces connected through edges whose two faces have equal UVs at both ends;
/// non-manifold edges separate islands. `selected` restricts the measurement to some faces.
///
/// Errors: the mesh validation errors of [`PolyMesh::new`], [`UvError::Shape`] for a wrong
/// number of UVs or selection flags, [`UvError::NonFiniteUv`] for NaN or infinite UVs.
pub fn measure(
    positions: &[[f64; 3]],
    corner_verts: &[u32],
    face_sizes: &[u32],
    uv: &[[f64; 2]],
    selected: Option<&[bool]>,
) -> Result<MeshMetrics> {
    measure_with_triangles(positions, corner_verts, face_sizes, uv, selected, &[])
}

/// [`measure`] with the render triangulation (`triangles`: corner index triples, Blender's
/// `mesh.loop_triangles`; empty for the core's own): n-gons are measured on those triangles,
/// and quads on both diagonal splits either way.
///
/// Errors: those of [`measure`], and [`UvError::RenderTriangle`] for a bad triple (see
/// [`FaceTriangulation::new`]).
pub fn measure_with_triangles(
    positions: &[[f64; 3]],
    corner_verts: &[u32],
    face_sizes: &[u32],
    uv: &[[f64; 2]],
    selected: Option<&[bool]>,
    triangles: &[[u32; 3]],
) -> Result<MeshMetrics> {
    let mesh = PolyMesh::new(positions, corner_verts, face_sizes)?;
    let render = if triangles.is_empty() { None } else { Some(FaceTriangulation::new(&mesh, triangles)?) };
    if uv.len() != mesh.n_corners() {
        return Err(UvError::Shape {
            what: "uv",
            detail: format!("has {} rows, mesh has {} corners", uv.len(), mesh.n_corners()),
        });
    }
    if let Some(s) = selected {
        if s.len() != mesh.n_faces() {
            return Err(UvError::Shape {
                what: "selected",
                detail: format!("has {} entries, mesh has {} faces", s.len(), mesh.n_faces()),
            });
        }
    }
    if let Some(c) = uv.iter().position(|p| !p[0].is_finite() || !p[1].is_finite()) {
        return Err(UvError::NonFiniteUv { corner: c });
    }
    // UV seams: edges whose two corners' UVs differ at either end.
    let mut face_of = vec![0u32; mesh.n_corners()];
    for f in 0..mesh.n_faces() {
        for c in mesh.face_corners(f) {
            face_of[c] = f as u32;
        }
    }
    let mut recs: Vec<(u64, u32)> = Vec::with_capacity(mesh.n_corners());
    for f in 0..mesh.n_faces() {
        if selected.is_some_and(|s| !s[f]) {
            continue;
        }
        for c in mesh.face_corners(f) {
            let cn = mesh.next_corner(f, c);
            let (a, b) = (mesh.corner_vert(c), mesh.corner_vert(cn));
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            recs.push((key, c as u32));
        }
    }
    recs.sort_unstable();
    let mut seams = Vec::new();
    let mut i = 0;
    while i < recs.len() {
        let mut j = i + 1;
        while j < recs.len() && recs[j].0 == recs[i].0 {
            j += 1;
        }
        if j - i == 2 {
            let (c1, c2) = (recs[i].1 as usize, recs[i + 1].1 as usize);
            let (f1, f2) = (face_of[c1] as usize, face_of[c2] as usize);
            let (c1n, c2n) = (mesh.next_corner(f1, c1), mesh.next_corner(f2, c2));
            let v1 = mesh.corner_vert(c1);
            // Match ends by vertex.
            let (m1, m2) = if mesh.corner_vert(c2) == v1 { (c2, c2n) } else { (c2n, c2) };
            if uv[c1] != uv[m1] || uv[c1n] != uv[m2] {
                seams.push([v1, mesh.corner_vert(c1n)]);
            }
        }
        i = j;
    }
    let charts = build_charts_with(&mesh, &seams, selected, render.as_ref());
    let per_chart: Vec<ChartMetrics> = {
        use rayon::prelude::*;
        charts
            .par_iter()
            .map(|ch| {
                let mut vuv = vec![[0.0; 2]; ch.positions.len()];
                for &(c, v) in &ch.corner_vertex {
                    vuv[v as usize] = uv[c as usize];
                }
                let mut m = chart_metrics_with_quads(&ch.positions, &ch.triangles, &ch.quads, &vuv, &ch.boundary_loops);
                m.faces = ch.faces.len();
                m
            })
            .collect()
    };
    Ok(aggregate(per_chart))
}

/// Combine per-chart metrics into whole-mesh metrics (distortion weighted by 3D area).
pub fn aggregate(per_chart: Vec<ChartMetrics>) -> MeshMetrics {
    let total: f64 = per_chart.iter().map(|c| c.area_3d).sum();
    let mut d = if total > 0.0 { [0.0f64; 3] } else { [f64::NAN; 3] };
    for c in &per_chart {
        if c.area_3d > 0.0 && total > 0.0 {
            let w = c.area_3d / total;
            d[0] += w * c.distortion.conformal;
            d[1] += w * c.distortion.area;
            d[2] += w * c.distortion.symmetric_dirichlet;
        }
    }
    MeshMetrics {
        charts: per_chart.len(),
        flips: per_chart.iter().map(|c| c.flips).sum(),
        overlapping_charts: per_chart.iter().filter(|c| c.overlap).count(),
        distortion: Distortion { conformal: d[0], area: d[1], symmetric_dirichlet: d[2] },
        per_chart,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn singular_values_of_known_matrices() {
        let (s1, s2, sg) = singular_values_2x2(2.0, 0.0, 0.0, 0.5);
        assert!((s1 - 2.0).abs() < 1e-15 && (s2 - 0.5).abs() < 1e-15 && sg > 0.0);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let (s1, s2, sg) = singular_values_2x2(3.0 * c, -3.0 * s, 3.0 * s, 3.0 * c);
        assert!((s1 - 3.0).abs() < 1e-14 && (s2 - 3.0).abs() < 1e-14 && sg > 0.0);
        let (_, _, sg) = singular_values_2x2(1.0, 0.0, 0.0, -1.0);
        assert!(sg < 0.0);
    }

    #[test]
    fn stretch_and_flip_are_measured_analytically() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = vec![[0, 1, 2], [0, 2, 3]];
        let loops = vec![vec![0, 1, 2, 3]];
        let ident: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let m = chart_metrics(&p, &tris, &ident, &loops);
        assert_eq!(m.flips, 0);
        assert!(!m.overlap);
        for d in [m.distortion.conformal, m.distortion.area, m.distortion.symmetric_dirichlet] {
            assert!((d - 1.0).abs() < 1e-14);
        }
        // u stretched by 2: after area normalisation σ = (√2, 1/√2): conformal 2.
        let st: Vec<[f64; 2]> = p.iter().map(|q| [2.0 * q[0], q[1]]).collect();
        let m = chart_metrics(&p, &tris, &st, &loops);
        assert!((m.distortion.conformal - 2.0).abs() < 1e-13);
        assert!((m.distortion.area - 1.0).abs() < 1e-13);
        assert!((m.distortion.symmetric_dirichlet - 0.25 * (2.0 + 0.5 + 0.5 + 2.0)).abs() < 1e-13);
        // Move vertex 3 across the diagonal: triangle (0,2,3) flips and the boundary crosses.
        let mut fl = ident.clone();
        fl[3] = [1.0, 0.2];
        let m = chart_metrics(&p, &tris, &fl, &loops);
        assert_eq!(m.flips, 1);
        assert!(m.overlap);
    }

    #[test]
    fn fit_similarity_recovers_a_similarity() {
        let tris = vec![[0u32, 1, 2]];
        let src = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let (c, s, k) = (0.7f64.cos(), 0.7f64.sin(), 2.5);
        let tgt: Vec<[f64; 2]> = src.iter().map(|p| [3.0 + k * (c * p[0] - s * p[1]), -1.0 + k * (s * p[0] + c * p[1])]).collect();
        let mut uv = src.clone();
        assert!(fit_similarity(&mut uv, &tgt, &tris));
        for (a, b) in uv.iter().zip(&tgt) {
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
        let mut uv = src.clone();
        assert!(!fit_similarity(&mut uv, &[[0.0; 2]; 3], &tris));
        assert_eq!(uv, src);
    }
}
