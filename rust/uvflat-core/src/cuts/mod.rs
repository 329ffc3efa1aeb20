//! Automatic seams: plan the cuts that open a chart into a disk through a few cone
//! singularities (the chart pipeline, [`crate::pipeline`], decides which charts are cut and
//! checks the result).
//!
//! Steps (each in its own file):
//! 1. [`cones`]: greedy cone placement on the linearised conformal scale factor (held at 0 on
//!    the chart's boundary, if any) until `max |u| ≤ ln(max_stretch)` or `max_cones` (a
//!    closed genus-0 chart always gets 2).
//!    On a chart of [`coarse::PROXY_FROM`] triangles or more, the cones the prediction plans
//!    ([`ChartCutter::plan_cut`]) are placed on the chart's coarse proxy ([`coarse`]).
//! 2. [`cut_graph`]: 2g handle loops by tree–cotree with short loops; an approximate Steiner
//!    tree joining loops, cones and every boundary loop (so holes are joined to the outline)
//!    by shortest edge paths; dangling branches pruned.
//! 3. The caller adds the cut edges to the seams and rebuilds the chart, which is then a disk
//!    (χ = 1, one boundary loop); [`split`] halves a chart that repair rounds could not make
//!    valid, along the cheapest loop near the half-area level set of its Fiedler vector
//!    ([`fiedler`], [`min_cut`]; [`planar_split`] when that fails).
//!
//! Edge cost of a cut ([`edge_costs`]), where an artist would put a seam:
//! * 3D length;
//! * × a crease factor: creases from [`CREASE_START`] to [`CREASE_FULL`] of dihedral angle
//!   grow cheaper, down to [`CONCAVE_FACTOR`] where the surface folds inward (inside the legs,
//!   behind the ears: seams hide there) and [`CONVEX_FACTOR`] on sharp convex edges (natural
//!   boundaries, but in view);
//! * × [`SHARP_FACTOR`] on edges whose dihedral angle is at least `sharp_angle`, if set;
//! * × `1 + visibility_weight · visibility`, the mean visibility of its ends
//!   ([`visibility`]: `1 −` ambient occlusion), so exposed smooth surface is dearer than
//!   hidden surface;
//! * [`AVOID_COST`] (infinite: never cut) on edges touching a vertex the user asked to keep
//!   free of seams (such vertices never become cones).
//!
//! The options ([`AutoSeamOptions`]) are declared in [`options`] (`uvflat.AUTO_SEAM_OPTIONS`).
//!
//! Everything is deterministic: ties break by ids.

pub mod coarse;
pub mod cones;
pub mod cut_graph;
pub mod fiedler;
pub mod graph;
pub mod min_cut;
pub mod options;
pub mod planar_split;
pub mod split;
pub mod symmetric_cut;
pub mod symmetry;
pub mod visibility;

use crate::charts::{Chart, ChartKind};
use crate::error::{Result, UvError};
use crate::mesh::PolyMesh;

pub use graph::ChartGraph;
pub use options::auto_seam_options;
pub use symmetry::{Symmetry, UnknownSymmetry};

/// Cost factor of a cut along a sharp edge (cheaper: seams hide along creases).
pub const SHARP_FACTOR: f64 = 0.2;
/// Dihedral angle (radians, 30°) from which a crease starts to be cheaper to cut along. Below
/// it an edge is smooth surface: on coarse meshes many edges turn by 15–25°, and a preference
/// there makes the cost a noise that paths chase.
pub const CREASE_START: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// Dihedral angle (radians, 90°) from which a crease takes its full cost factor.
pub const CREASE_FULL: f64 = 90.0 * std::f64::consts::PI / 180.0;
/// Cost factor of a concave crease of at least [`CREASE_FULL`] (the cheapest place for a seam).
pub const CONCAVE_FACTOR: f64 = 0.2;
/// Cost factor of a convex crease of at least [`CREASE_FULL`] (a natural boundary, in view).
pub const CONVEX_FACTOR: f64 = 0.7;
/// Default [`AutoSeamOptions::visibility_weight`].
pub const VISIBILITY_WEIGHT: f64 = 1.0;
/// Cost of a cut along an edge touching an avoided vertex: none is ever cut (*Avoid Seams*
/// is a constraint, not a preference). A chart that cannot be opened without one stays
/// uncut there and is reported as breaking the rule.
pub const AVOID_COST: f64 = f64::INFINITY;
/// Most repair rounds per chart and split level (each may add cones on top of `max_cones`).
pub const REPAIR_ROUNDS: usize = 3;
/// Most halvings of one chart when cones cannot make it valid.
pub const MAX_SPLIT_DEPTH: usize = 4;

/// Options of automatic seams ([`crate::UnwrapOptions::auto_seams`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AutoSeamOptions {
    /// Hold every chart to the atlas rule ([`crate::pipeline::rule`]) and cut where it breaks
    /// it (default `true`). When `false` nothing is cut: closed and higher-genus charts fail
    /// with a "mark seams" reason.
    pub enabled: bool,
    /// Max Stretch `s` (default 2.0; must be > 1): at most 5% of an island's 3D area may have
    /// a texel density outside `[1/s, s]` of the island's own. Cones are planned while the
    /// predicted `max |u| > ln(s)` (up to `max_cones`); a piece that still breaks the rule
    /// gets another cone or is split.
    pub max_stretch: f64,
    /// Most cones per chart (default 8; a closed sphere gets at least 2 whatever this says).
    pub max_cones: usize,
    /// Mesh vertices where seams must not go (default none).
    pub avoid_vertices: Vec<u32>,
    /// Dihedral angle (radians) from which an edge counts as sharp and is preferred for
    /// seams; `None` (default) prefers nothing beyond the built-in crease preference.
    pub sharp_angle: Option<f64>,
    /// How much dearer a seam is on exposed surface than on hidden surface (default
    /// [`VISIBILITY_WEIGHT`] = 1: a fully exposed edge costs twice a fully occluded one; 0
    /// turns the term off and skips the occlusion rays). Visibility is `1 −` ambient occlusion
    /// per vertex ([`visibility`]); must be finite and in `[0, 100]`.
    pub visibility_weight: f64,
    /// Mirror symmetry the seams keep (default [`Symmetry::None`]). When a chart is its own
    /// mirror image ([`symmetry`]), cut costs and cones are made symmetric (a cone's mirror is
    /// a cone too, so a chart may get up to twice `max_cones`), and a closed genus-0 chart is
    /// cut on one half and the cut mirrored ([`symmetric_cut`]): its seams map onto themselves.
    /// Other charts get symmetric costs and cones only; splits are not mirrored.
    pub symmetry: Symmetry,
    /// Plan every method's cuts on the same method-independent prediction (default `false`).
    /// The methods that do not even out area (ABF, LSCM, spectral, MIPS) always do: cones and
    /// cuts come from the conformal flattening that keeps the pieces' outline lengths
    /// ([`crate::pipeline::predict`]), and the method's own solve, check and repair add to
    /// them where it breaks the rule (a repair re-cuts through the plan's cones and its own).
    /// When `true`, SLIM, ARAP and scaffold start from that plan too, so switching methods
    /// keeps the seams wherever the new method keeps the rule on them. When `false` they start
    /// from the cutter's cones alone, which usually gives them fewer, shorter seams and fewer
    /// islands: `slim` on the bunny made 146 seam edges and 1 island against the plan's 226 and
    /// 3, and on fertility subdivided three times (576k triangles) took 22.6 s for 2 islands
    /// against 31.9 s for 10 on the plan (its outline crossed itself at more places).
    pub same_seams: bool,
}

impl Default for AutoSeamOptions {
    fn default() -> Self {
        AutoSeamOptions {
            enabled: true,
            max_stretch: 2.0,
            max_cones: 8,
            avoid_vertices: Vec::new(),
            sharp_angle: None,
            visibility_weight: VISIBILITY_WEIGHT,
            symmetry: Symmetry::None,
            same_seams: false,
        }
    }
}

impl AutoSeamOptions {
    /// Check the options against a mesh of `n_vertices` vertices.
    ///
    /// Errors: [`UvError::Option`] naming `max_stretch`, `max_cones`, `sharp_angle`,
    /// `visibility_weight` or `avoid_vertices` (with the entry and vertex).
    pub fn validate(&self, n_vertices: usize) -> Result<()> {
        if !(self.max_stretch.is_finite() && self.max_stretch > 1.0) {
            return Err(UvError::Option {
                name: "max_stretch".into(),
                reason: format!("must be a finite number greater than 1, got {}", self.max_stretch),
            });
        }
        if self.max_cones > 1000 {
            return Err(UvError::Option { name: "max_cones".into(), reason: format!("must be at most 1000, got {}", self.max_cones) });
        }
        if let Some(a) = self.sharp_angle {
            if !(a.is_finite() && a > 0.0 && a < std::f64::consts::PI) {
                return Err(UvError::Option {
                    name: "sharp_angle".into(),
                    reason: format!("must be an angle in radians strictly between 0 and π, got {a}"),
                });
            }
        }
        if !(self.visibility_weight.is_finite() && (0.0..=100.0).contains(&self.visibility_weight)) {
            return Err(UvError::Option {
                name: "visibility_weight".into(),
                reason: format!("must be a number from 0 to 100, got {}", self.visibility_weight),
            });
        }
        if let Some((i, &v)) = self.avoid_vertices.iter().enumerate().find(|(_, &v)| v as usize >= n_vertices) {
            return Err(UvError::Option {
                name: "avoid_vertices".into(),
                reason: format!("entry {i}: vertex index {v} out of range (mesh has {n_vertices} vertices)"),
            });
        }
        Ok(())
    }
}

/// Whether a chart cannot be flattened without cuts: closed or with handles, and no defect.
/// (The pipeline also cuts charts with holes and charts that break the atlas rule.)
pub fn needs_cut(chart: &Chart) -> bool {
    chart.defect.is_none() && matches!(chart.kind, ChartKind::Closed | ChartKind::HigherGenus) && !chart.triangles.is_empty()
}

/// The cuts chosen for one chart.
#[derive(Debug, Clone, Default)]
pub struct ChartCuts {
    /// Cut edges as chart vertex pairs `[a, b]`, `a < b`.
    pub edges: Vec<[u32; 2]>,
    /// The same edges as mesh vertex pairs (seams to add).
    pub seams: Vec<[u32; 2]>,
    /// Cone vertices (chart vertex ids).
    pub cones: Vec<u32>,
    /// Curvature concentrated at each cone (radians).
    pub cone_curvature: Vec<f64>,
    /// Total 3D length of the cut edges.
    pub length: f64,
    /// Largest |log scale factor| predicted with these cones.
    pub max_log_scale: f64,
    /// Whether the cut was planned on one half of a mirror-symmetric chart and mirrored (it is
    /// then its own mirror image).
    pub mirrored: bool,
}

/// Per-edge cut costs of `graph` (see the module docs). Casts the occlusion rays when
/// `options.visibility_weight > 0`.
pub fn edge_costs(mesh: &PolyMesh<'_>, graph: &ChartGraph, chart: &Chart, options: &AutoSeamOptions, avoid: &[bool]) -> Vec<f64> {
    edge_costs_cached(mesh, graph, chart, options, avoid, None)
}

/// [`edge_costs`], taking the visibility from `cache` when it knows the chart's corners.
pub fn edge_costs_cached(
    mesh: &PolyMesh<'_>,
    graph: &ChartGraph,
    chart: &Chart,
    options: &AutoSeamOptions,
    avoid: &[bool],
    cache: Option<&visibility::VisibilityCache>,
) -> Vec<f64> {
    // A mesh wound inwards has its valleys where the winding sees ridges.
    let inward = cache.map_or_else(|| visibility::wound_inward(mesh), |c| c.inward(mesh));
    let visibility = (options.visibility_weight > 0.0).then(|| match cache {
        Some(c) => c.chart(mesh, chart, inward),
        None => visibility::chart_visibility(mesh, chart, inward),
    });
    (0..graph.edges.len())
        .map(|e| {
            let [a, b] = graph.edges[e];
            // A zero-length edge still costs a little, so paths stay short in edge count.
            let mut c = graph.length[e].max(1e-12);
            if !graph.is_boundary(e) {
                let ramp = ((graph.dihedral[e] - CREASE_START) / (CREASE_FULL - CREASE_START)).clamp(0.0, 1.0);
                let full = if graph.concave[e] != inward { CONCAVE_FACTOR } else { CONVEX_FACTOR };
                c *= 1.0 - ramp * (1.0 - full);
            }
            if let Some(s) = options.sharp_angle {
                if graph.dihedral[e] >= s {
                    c *= SHARP_FACTOR;
                }
            }
            if let Some(vis) = &visibility {
                c *= 1.0 + options.visibility_weight * 0.5 * (vis[a as usize] + vis[b as usize]);
            }
            if avoid[chart.mesh_vertex[a as usize] as usize] || avoid[chart.mesh_vertex[b as usize] as usize] {
                c = AVOID_COST;
            }
            c
        })
        .collect()
}

/// Choose cones and cut edges that open `chart` into a disk (one shot; see [`ChartCutter`]).
///
/// * `avoid`: per mesh vertex, whether seams must stay away from it.
/// * `seed_cones`: chart vertices that must be cones (added by repair rounds).
/// * `extra_cones`: how many cones beyond `options.max_cones` may be placed.
///
/// Preconditions: [`needs_cut`] holds. Never fails: the worst case is a cut without the
/// distortion bound (reported through [`ChartCuts::max_log_scale`]).
pub fn cut_chart(
    mesh: &PolyMesh<'_>,
    chart: &Chart,
    options: &AutoSeamOptions,
    avoid: &[bool],
    seed_cones: &[u32],
    extra_cones: usize,
) -> ChartCuts {
    ChartCutter::new(mesh, chart, options, avoid).cut(seed_cones, extra_cones)
}

/// The cutting state of one chart, built once and reused by every repair round: its edge
/// graph and cut costs, and its scale-factor system with the symbolic analysis done (each
/// round is then numeric refactors only).
pub struct ChartCutter<'a> {
    chart: &'a Chart,
    options: &'a AutoSeamOptions,
    graph: ChartGraph,
    cost: Vec<f64>,
    allowed: Vec<bool>,
    boundary: Vec<bool>,
    min_cones: usize,
    solver: Option<cones::ScaleSolver>,
    mirror: Option<symmetry::Mirror>,
    /// The handle loops of the last cut and their root (they depend on the root only).
    loops: std::sync::Mutex<Option<(u32, Vec<bool>)>>,
    /// The coarse proxy of a large chart ([`coarse`]), made on first use.
    proxy: std::sync::OnceLock<Option<coarse::Proxy>>,
    /// The chart's Fiedler vector ([`Self::fiedler`]), made on first use.
    fiedler: std::sync::OnceLock<Option<Vec<f64>>>,
}

impl<'a> ChartCutter<'a> {
    /// Analyse `chart` (preconditions of [`cut_chart`]).
    pub fn new(mesh: &PolyMesh<'_>, chart: &'a Chart, options: &'a AutoSeamOptions, avoid: &[bool]) -> Self {
        Self::with_cache(mesh, chart, options, avoid, None)
    }

    /// [`Self::new`], with the visibility of the chart's corners from `cache` when known
    /// (the pipeline keeps one per unwrap, so a chart's pieces do not cast rays again).
    pub fn with_cache(
        mesh: &PolyMesh<'_>,
        chart: &'a Chart,
        options: &'a AutoSeamOptions,
        avoid: &[bool],
        cache: Option<&visibility::VisibilityCache>,
    ) -> Self {
        // The scale system's analysis and the graph's costs (occlusion rays) are independent.
        let (solver, (graph, cost)) = rayon::join(|| cones::ScaleSolver::new(chart), || Self::graph_and_costs(mesh, chart, options, avoid, cache));
        Self::assemble(chart, options, avoid, graph, cost, solver)
    }

    /// The edge graph of `chart` and its cut costs ([`edge_costs_cached`]).
    fn graph_and_costs(
        mesh: &PolyMesh<'_>,
        chart: &Chart,
        options: &AutoSeamOptions,
        avoid: &[bool],
        cache: Option<&visibility::VisibilityCache>,
    ) -> (ChartGraph, Vec<f64>) {
        let graph = ChartGraph::new(mesh, chart);
        let cost = edge_costs_cached(mesh, &graph, chart, options, avoid, cache);
        (graph, cost)
    }

    /// [`Self::with_cache`] with the chart's scale system built already (`None`: it failed).
    pub fn with_solver(
        mesh: &PolyMesh<'_>,
        chart: &'a Chart,
        options: &'a AutoSeamOptions,
        avoid: &[bool],
        cache: Option<&visibility::VisibilityCache>,
        solver: Option<cones::ScaleSolver>,
    ) -> Self {
        let (graph, cost) = Self::graph_and_costs(mesh, chart, options, avoid, cache);
        Self::assemble(chart, options, avoid, graph, cost, solver)
    }

    /// The cutter of `chart` from its graph, costs and scale system.
    fn assemble(
        chart: &'a Chart,
        options: &'a AutoSeamOptions,
        avoid: &[bool],
        graph: ChartGraph,
        mut cost: Vec<f64>,
        solver: Option<cones::ScaleSolver>,
    ) -> Self {
        let boundary = chart.boundary_mask();
        // A cone is the tip of a slit, and its angle in the flattening is about its angle sum
        // on the surface (ABF's were 2–25° smaller on the bunny's cones): at a saddle vertex
        // (angle sum of 2π or more) the slit's two sides overlap at the tip. Cones go where
        // the surface is convex: a positive angle defect (a threshold would depend on the
        // mesh's resolution, as defects shrink with the vertex's area).
        let convex = |v: usize| solver.as_ref().is_none_or(|s| s.defect[v] > 0.0);
        let mut allowed: Vec<bool> =
            (0..chart.positions.len()).map(|v| !boundary[v] && !avoid[chart.mesh_vertex[v] as usize] && convex(v)).collect();
        let mirror = symmetry::detect(&graph, &chart.positions, options.symmetry);
        if let Some(m) = &mirror {
            // The mean of an edge's cost and its mirror's; forbidden if either is.
            cost = (0..cost.len())
                .map(|e| {
                    let (a, b) = (cost[e], cost[m.edge[e] as usize]);
                    if a.is_finite() && b.is_finite() {
                        0.5 * (a + b)
                    } else {
                        AVOID_COST
                    }
                })
                .collect();
            allowed = (0..allowed.len()).map(|v| allowed[v] && allowed[m.vertex[v] as usize]).collect();
        }
        let min_cones = match (chart.boundary_loops.is_empty(), chart.genus) {
            (true, 0) => 2,
            (true, _) => 1,
            (false, _) => 0,
        };
        ChartCutter {
            chart,
            options,
            graph,
            cost,
            allowed,
            boundary,
            min_cones,
            solver,
            mirror,
            loops: Default::default(),
            proxy: Default::default(),
            fiedler: Default::default(),
        }
    }

    /// The chart's mirror, when [`AutoSeamOptions::symmetry`] asked for one and found it.
    pub fn mirror(&self) -> Option<&symmetry::Mirror> {
        self.mirror.as_ref()
    }

    /// The edge graph of the chart.
    pub fn graph(&self) -> &ChartGraph {
        &self.graph
    }

    /// Cut cost of every edge of [`Self::graph`] ([`edge_costs`]).
    pub fn costs(&self) -> &[f64] {
        &self.cost
    }

    /// Free the scale system's numeric factors and remembered solves (the next cut that
    /// needs them factors again; the analysis is kept): on a large chart they would otherwise
    /// stay in memory beside the method's own factor while it solves the pieces.
    pub fn release_factors(&mut self) {
        if let Some(solver) = self.solver.as_mut() {
            solver.release_factors();
        }
    }

    /// Per chart vertex: whether it may become a cone (inside the chart, not avoided, a
    /// positive angle defect: not a saddle).
    pub fn allowed(&self) -> &[bool] {
        &self.allowed
    }

    /// `(predicted density ratio, 3D area)` per triangle of the chart (in `chart.triangles`
    /// order) once cut along `cut`, when the cut leaves it in one piece: the flattening of
    /// [`predicted_outside`] for that piece. The piece's interior equations are the
    /// chart's (cutting changes no angle), and `u = 0` on both sides of a cut edge is `u = 0`
    /// at its vertices, so the chart's own system with the cut's vertices held gives it: one
    /// numeric factorization on the chart's analysis, no new chart, ordering or assembly.
    /// `None` when the system failed.
    ///
    /// On a large chart the flattening is the proxy's ([`coarse`]: the cut's vertices held by
    /// the proxy vertices that represent them), read back on the chart.
    pub fn predicted_ratios_after(&self, cut: &ChartCuts) -> Option<Vec<(f64, f64)>> {
        let Some(proxy) = self.proxy() else { return self.predicted_ratios_on_chart(cut) };
        let fixed = cut_vertices(cut);
        if fixed.is_empty() && self.chart.boundary_loops.is_empty() {
            return None;
        }
        let mut held: Vec<u32> = fixed.iter().map(|&v| proxy.rep[v as usize]).collect();
        held.sort_unstable();
        held.dedup();
        let u = proxy.solver.solve_refactored(&held)?;
        ratios_of(self.chart, &proxy.to_chart(&u, &fixed))
    }

    /// [`Self::predicted_ratios_after`] on the chart's own system, proxy or not.
    pub fn predicted_ratios_on_chart(&self, cut: &ChartCuts) -> Option<Vec<(f64, f64)>> {
        let fixed = cut_vertices(cut);
        if fixed.is_empty() && self.chart.boundary_loops.is_empty() {
            return None;
        }
        ratios_of(self.chart, &self.solver.as_ref()?.solve_refactored(&fixed)?)
    }

    /// The coarse proxy of the chart ([`coarse::Proxy::new`]: charts of at least
    /// [`coarse::PROXY_FROM`] triangles, closed ones from [`coarse::CLOSED_PROXY_FROM`]), made
    /// on first use; `None` on a smaller chart and on a mirror-symmetric one (its cones are
    /// placed in pairs on the chart itself).
    pub fn proxy(&self) -> Option<&coarse::Proxy> {
        if self.mirror.is_some() || self.solver.is_none() {
            return None;
        }
        self.proxy.get_or_init(|| coarse::Proxy::new(self.chart)).as_ref()
    }

    /// Candidate seams for halving the chart ([`split::candidates`]); on a chart with a proxy
    /// ([`Self::proxy`]) the Fiedler vector whose levels the split follows is the proxy's,
    /// read back on the chart (an inverse iteration on the proxy instead of the chart: the
    /// minimum cut that places the seam is made on the chart). `all`: every candidate; else
    /// only the first (the planar split is made only when the spectral one fails: 0.36–0.44 s
    /// on fertility subdivided three times, 576k triangles).
    pub fn split_candidates(&self, avoid: &[bool], all: bool) -> Vec<Vec<[u32; 2]>> {
        let fiedler = if self.proxy().is_some() { self.fiedler().map(<[f64]>::to_vec) } else { None };
        split::candidates_with(&self.graph, &self.cost, self.chart, avoid, fiedler, all)
    }

    /// The chart's Fiedler vector (per chart vertex), read from its proxy when it has one
    /// ([`Self::proxy`]), as [`Self::split_candidates`] reads it; made once.
    pub fn fiedler(&self) -> Option<&[f64]> {
        self.fiedler
            .get_or_init(|| match self.proxy() {
                Some(p) => Some(p.to_chart(&fiedler::fiedler_vector(&p.chart)?, &[])),
                None => fiedler::fiedler_vector(self.chart),
            })
            .as_deref()
    }

    /// This cutter with `proxy` as the chart's proxy, whatever the chart's size (made by the
    /// caller with [`coarse::Proxy::with_target`]; it is not used on a mirror-symmetric chart).
    pub fn with_proxy(self, proxy: coarse::Proxy) -> Self {
        let _ = self.proxy.set(Some(proxy));
        self
    }

    /// [`Self::cut`] with the cones placed on the chart's proxy when it has one (a large chart;
    /// the prediction's rounds, [`crate::pipeline::predict`]): a cone placed on the proxy is a
    /// vertex of the chart, and `seed_cones` go to the proxy vertices that represent them. The
    /// cut is made on the chart.
    pub fn plan_cut(&self, seed_cones: &[u32], extra_cones: usize) -> ChartCuts {
        let Some(proxy) = self.proxy() else { return self.cut(seed_cones, extra_cones) };
        let mut seeds: Vec<u32> = Vec::with_capacity(seed_cones.len());
        for &v in seed_cones {
            let c = proxy.rep[v as usize];
            if !seeds.contains(&c) {
                seeds.push(c);
            }
        }
        let allowed: Vec<bool> = proxy
            .fine_of
            .iter()
            .enumerate()
            .map(|(c, &v)| self.allowed[v as usize] && proxy.solver.defect[c] > 0.0)
            .collect();
        let options = self.options;
        let mut cones = cones::place_cones(
            &proxy.solver,
            &allowed,
            self.min_cones,
            options.max_cones + extra_cones,
            options.max_stretch.ln(),
            &seeds,
        );
        cones.vertices = cones.vertices.iter().map(|&c| proxy.fine_of[c as usize]).collect();
        cones.u = proxy.to_chart(&cones.u, &cones.vertices);
        self.cut_with(cones)
    }

    /// How many pieces the chart falls into when cut along `cut` (its polygons joined across
    /// the edges `cut` leaves whole): what [`crate::charts::build_charts_with`] would make of
    /// it, without building them.
    pub fn pieces_after(&self, cut: &ChartCuts) -> usize {
        self.joined_after(cut).1
    }

    /// The polygons joined across the edges `cut` leaves whole, and how many pieces they make.
    fn joined_after(&self, cut: &ChartCuts) -> (crate::charts::UnionFind, usize) {
        let graph = &self.graph;
        let mut is_cut = vec![false; graph.edges.len()];
        for e in &cut.edges {
            if let Ok(id) = graph.edges.binary_search(e) {
                is_cut[id] = true;
            }
        }
        let mut uf = crate::charts::UnionFind::new(graph.polygons.len());
        let mut pieces = graph.polygons.len();
        for (e, p) in graph.edge_polygons.iter().enumerate() {
            if !is_cut[e] && p[1] != u32::MAX && uf.union(p[0], p[1]) {
                pieces -= 1;
            }
        }
        (uf, pieces)
    }

    /// The piece of every chart triangle after cutting along `cut` (the pieces
    /// [`Self::pieces_after`] counts that hold a triangle, numbered from 0 in the order of
    /// their first triangle), and their number. A cut into several pieces is predicted on the
    /// chart with the cut held ([`Self::predicted_ratios_after`]: a piece's flattening with
    /// its outline's lengths kept is the chart's with the cut's vertices held), the pieces
    /// told apart by these labels.
    pub fn triangle_pieces(&self, cut: &ChartCuts) -> (Vec<u32>, usize) {
        let (mut uf, _) = self.joined_after(cut);
        let chart = self.chart;
        let mut label_of = vec![u32::MAX; self.graph.polygons.len()];
        let mut next = 0u32;
        let labels = chart
            .triangle_face
            .iter()
            .map(|f| {
                // Graph polygons are the chart's faces, in order ([`graph::face_polygons`]).
                let root = uf.find(chart.faces.binary_search(f).unwrap_or(0) as u32) as usize;
                if label_of[root] == u32::MAX {
                    label_of[root] = next;
                    next += 1;
                }
                label_of[root]
            })
            .collect();
        (labels, next as usize)
    }

    /// Cones and cut for this round (arguments as in [`cut_chart`]).
    pub fn cut(&self, seed_cones: &[u32], extra_cones: usize) -> ChartCuts {
        let (options, min_cones) = (self.options, self.min_cones);
        let seeds = match &self.mirror {
            Some(m) => mirrored(seed_cones, m),
            None => seed_cones.to_vec(),
        };
        let cones = match &self.solver {
            Some(solver) => cones::place_cones(
                solver,
                &self.allowed,
                min_cones,
                options.max_cones + extra_cones,
                options.max_stretch.ln(),
                &seeds,
            ),
            None => cones::Cones { vertices: seeds.clone(), curvature: vec![0.0; seeds.len()], u: vec![], max_u: f64::INFINITY },
        };
        self.cut_with(cones)
    }

    /// The cut of [`Self::cut`] through the cones placed (mirrored when the chart is).
    fn cut_with(&self, mut cones: cones::Cones) -> ChartCuts {
        let (chart, options, graph, cost, boundary, min_cones) =
            (self.chart, self.options, &self.graph, &self.cost, &self.boundary, self.min_cones);
        let mut cone_vertices = cones.vertices.clone();
        if cone_vertices.len() < min_cones {
            // Every vertex is avoided or the system failed: pick far-apart vertices anyway.
            for v in 0..chart.positions.len() as u32 {
                if cone_vertices.len() >= min_cones {
                    break;
                }
                if !boundary[v as usize] && !cone_vertices.contains(&v) {
                    cone_vertices.push(v);
                }
            }
        }
        if let Some(m) = &self.mirror {
            // Add the cones' mirrors; solve again with the symmetric set held (its curvature),
            // which may place a cone more when the set is still short of `min_cones`.
            for _ in 0..3 {
                let sym = mirrored(&cone_vertices, m);
                let Some(solver) = &self.solver else {
                    cone_vertices = sym;
                    break;
                };
                let again = cones::place_cones(solver, &self.allowed, min_cones, sym.len(), options.max_stretch.ln(), &sym);
                let done = again.vertices == sym;
                cone_vertices = again.vertices.clone();
                cones = again;
                if done {
                    break;
                }
            }
            cone_vertices = mirrored(&cone_vertices, m);
        }
        let planned = match &self.mirror {
            Some(m) if chart.boundary_loops.is_empty() && chart.genus == 0 => {
                symmetric_cut::symmetric_cut(graph, cost, &chart.positions, m, &cone_vertices)
            }
            _ => None,
        };
        let mirrored_cut = planned.is_some();
        let cut = planned.unwrap_or_else(|| self.plain_cut(&cone_vertices));
        let mut out = ChartCuts {
            cones: cone_vertices.clone(),
            // Cones added after the solve (none placed, or mirrors) carry no predicted curvature.
            cone_curvature: if self.mirror.is_none() || cones.vertices == cone_vertices { cones.curvature.clone() } else { Vec::new() },
            max_log_scale: cones.max_u,
            mirrored: mirrored_cut,
            ..Default::default()
        };
        out.cone_curvature.resize(cone_vertices.len(), 0.0);
        for (e, &c) in cut.iter().enumerate() {
            if c {
                let [a, b] = graph.edges[e];
                out.edges.push([a, b]);
                let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
                out.seams.push([ma.min(mb), ma.max(mb)]);
                out.length += graph.length[e];
            }
        }
        out
    }

    /// Handle loops (genus > 0) joined to the cones and boundary loops (see [`cut_graph`]).
    fn plain_cut(&self, cone_vertices: &[u32]) -> Vec<bool> {
        let (chart, graph, cost) = (self.chart, &self.graph, &self.cost);
        let loops = if chart.genus > 0 {
            let root = cone_vertices.first().copied().or_else(|| chart.boundary_loops.first().map(|l| l[0])).unwrap_or(0);
            // Repair rounds keep their first cone: the loops of one root are found once.
            let mut cached = self.loops.lock().unwrap_or_else(|e| e.into_inner());
            match cached.as_ref() {
                Some((r, l)) if *r == root => l.clone(),
                _ => {
                    let l = cut_graph::handle_loops(graph, cost, root, &chart.boundary_loops);
                    *cached = Some((root, l.clone()));
                    l
                }
            }
        } else {
            vec![false; graph.edges.len()]
        };
        cut_graph::join_and_prune(graph, cost, loops, cone_vertices, &chart.boundary_loops)
    }
}

/// The vertices of `cut`'s edges, ascending.
fn cut_vertices(cut: &ChartCuts) -> Vec<u32> {
    let mut fixed: Vec<u32> = cut.edges.iter().flat_map(|e| [e[0], e[1]]).collect();
    fixed.sort_unstable();
    fixed.dedup();
    fixed
}

/// `cones` and their mirror images, in order (each new mirror after its cone), without repeats.
fn mirrored(cones: &[u32], mirror: &symmetry::Mirror) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::with_capacity(2 * cones.len());
    for &c in cones {
        for v in [c, mirror.vertex[c as usize]] {
            if !out.contains(&v) {
                out.push(v);
            }
        }
    }
    out
}

/// The predicted share of `chart`'s 3D area outside `[1/s, s]` of its own density when it is
/// flattened conformally as it is, without cuts, with its outline's lengths kept (`s` = Max
/// Stretch; `solver`: the chart's scale system): triangle `t` gets the area ratio `exp(2 ū_t)`
/// (`ū_t` the mean over its corners of [`cones::ScaleSolver::base_u`]), relative to the
/// chart's area-weighted mean. A lower bound, roughly, for a free-boundary conformal map (LSCM,
/// ABF), whose outline is not held to its 3D lengths. `None` on a chart without a boundary or
/// when the system failed.
pub fn predicted_outside(chart: &Chart, solver: &cones::ScaleSolver, s: f64) -> Option<f64> {
    Some(crate::metrics::density::spread_of(predicted_ratios(chart, solver)?, s).outside)
}

/// `(predicted density ratio, 3D area)` per triangle of `chart` flattened conformally with its
/// outline's lengths kept ([`predicted_outside`]), the ratios relative to the
/// chart's area-weighted mean. `None` on a chart without a boundary or when the system failed.
pub fn predicted_ratios(chart: &Chart, solver: &cones::ScaleSolver) -> Option<Vec<(f64, f64)>> {
    if chart.boundary_loops.is_empty() {
        return None;
    }
    ratios_of(chart, solver.base_u()?)
}

/// `(e^{2ū} / mean, 3D area)` per triangle of `chart` for the log scale factor `u` (`ū` the
/// mean over the triangle's corners; the mean area-weighted). `None` without area.
fn ratios_of(chart: &Chart, u: &[f64]) -> Option<Vec<(f64, f64)>> {
    let samples: Vec<(f64, f64)> = chart
        .triangles
        .iter()
        .map(|t| {
            let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
            let ubar = (u[t[0] as usize] + u[t[1] as usize] + u[t[2] as usize]) / 3.0;
            ((2.0 * ubar).exp(), crate::geometry::triangle_area(p))
        })
        .collect();
    let total: f64 = samples.iter().map(|s| s.1).sum();
    let mean = samples.iter().map(|s| s.0 * s.1).sum::<f64>() / total;
    if !(mean > 0.0 && mean.is_finite()) {
        return None;
    }
    Some(samples.into_iter().map(|(r, a)| (r / mean, a)).collect())
}
