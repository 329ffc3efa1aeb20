//! Parameterization methods, one file each, and the [`Method`] enum that dispatches.
//!
//! Every method maps one [`Chart`] to per-chart-vertex UVs. Charts that no method can map
//! (closed, higher genus, defects found while building the chart) fail here with a reason.

pub mod abf;
pub mod arap;
pub mod bff;
pub mod boundary_eigen;
pub mod fixed_boundary;
pub mod harmonic;
pub mod lscm;
pub mod mean_value;
pub mod mips;
pub mod nonlinear;
pub mod options;
pub mod planar;
pub mod quad_repair;
pub mod scaffold;
pub mod slim;
pub mod spectral;
pub mod tutte;

use crate::charts::Chart;
use crate::error::{Result, UvError};
use crate::charts::ChartKind;

/// Where a fixed-boundary method puts the outer boundary loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BoundaryShape {
    /// Unit circle, vertices spaced by 3D arc length. Default. Strictly convex, so the
    /// barycentric methods with positive weights never flip.
    #[default]
    Circle,
    /// Unit square, the four boundary vertices nearest the quarter arc lengths at its corners.
    Square,
    /// Virtual boundary (Lee, Kim, Lee 2002): a band of virtual triangles around the outer
    /// loop goes to the unit circle and the real boundary settles freely inside it (see
    /// [`fixed_boundary::add_virtual_band`]). Less distortion than `Circle`; with mean value
    /// (or uniform) weights still no flips.
    Virtual,
}

/// Options of the spectral conformal method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralOptions {
    /// Most solves of the eigenvector search (Lanczos, `methods/boundary_eigen.rs`). Default 200.
    pub max_iterations: usize,
    /// Stop when the eigenvector's residual `‖M w − θ w‖_B / θ` (`M = (Q + εB)⁻¹ B`) is at
    /// most this. Default 1e-10.
    pub tolerance: f64,
}

impl Default for SpectralOptions {
    fn default() -> Self {
        SpectralOptions { max_iterations: 200, tolerance: 1e-10 }
    }
}

/// The parameterization method and its options.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// Tutte 1963: uniform weights, fixed boundary.
    Tutte { boundary: BoundaryShape },
    /// Eck et al. 1995: cotangent weights, fixed boundary.
    Harmonic { boundary: BoundaryShape },
    /// Floater 2003: mean value weights, fixed boundary.
    MeanValue { boundary: BoundaryShape },
    /// Lévy et al. 2002 / Desbrun et al. 2002: least squares conformal, free boundary.
    Lscm,
    /// Mullen et al. 2008: spectral conformal, free boundary, no pins.
    Spectral(SpectralOptions),
    /// Sawhney & Crane 2017: boundary first flattening with the outline's lengths kept, the
    /// conformal map of least area distortion (the one automatic seams plan on); no pins.
    Bff,
    /// Sheffer & de Sturler 2001 / Sheffer et al. 2005: angle based flattening (ABF++ by
    /// default), UVs by LSCM from the solved angles; falls back to LSCM when it fails.
    /// Default: the best atlas on closed, open and seamed meshes.
    Abf(abf::AbfOptions),
    /// Liu et al. 2008: as-rigid-as-possible, local/global iterations from LSCM, free
    /// boundary; no injectivity guarantee.
    Arap(arap::ArapOptions),
    /// Rabinovich et al. 2017: symmetric Dirichlet by reweighted proxies with a flip-free line
    /// search, free boundary; never flips a triangle of a chart that starts valid.
    Slim(slim::SlimOptions),
    /// Hormann & Greiner 2000: MIPS energy σ1/σ2 + σ2/σ1 by projected Newton from a flip-free
    /// start with a flip-free line search, free boundary; never flips.
    Mips(mips::MipsOptions),
    /// Jiang, Schaefer & Panozzo 2017 (SCAF): symmetric Dirichlet on the chart plus a
    /// scaffold triangulation of the free space, re-meshed as the chart moves; no flips and
    /// no boundary self-overlap.
    Scaffold(scaffold::ScaffoldOptions),
}

/// A value of a method option as it arrives from Python, the add-on or a command line.
#[derive(Debug, Clone, PartialEq)]
pub enum OptionValue {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    /// Values at chosen mesh vertices, `(vertex, value)` (e.g. ABF's `angle_sums`; from Python
    /// a pair `(vertex indices, values)` of arrays).
    VertexValues(Vec<(u32, f64)>),
    /// Mesh vertex indices (automatic seams' `avoid_vertices`).
    Vertices(Vec<u32>),
}

/// Names accepted by [`Method::parse`].
pub fn method_names() -> &'static [&'static str] {
    &["tutte", "harmonic", "mean_value", "lscm", "spectral", "bff", "abf", "arap", "slim", "mips", "scaffold"]
}

fn opt_err(name: impl Into<String>, reason: impl Into<String>) -> UvError {
    UvError::Option { name: name.into(), reason: reason.into() }
}

fn as_float(name: &'static str, v: &OptionValue) -> Result<f64> {
    match v {
        OptionValue::Float(x) => Ok(*x),
        OptionValue::Int(i) => Ok(*i as f64),
        OptionValue::Bool(b) => Err(opt_err(name, format!("expected a number, got the boolean {b}"))),
        OptionValue::Str(s) => Err(opt_err(name, format!("expected a number, got the string {s:?}"))),
        OptionValue::VertexValues(_) => Err(opt_err(name, "expected a number, got per-vertex values")),
        OptionValue::Vertices(_) => Err(opt_err(name, "expected a number, got vertex indices")),
    }
}

fn as_count(name: &'static str, v: &OptionValue) -> Result<usize> {
    match v {
        OptionValue::Int(i) if *i >= 1 => Ok(*i as usize),
        OptionValue::Int(i) => Err(opt_err(name, format!("expected a positive integer, got {i}"))),
        OptionValue::Float(x) => Err(opt_err(name, format!("expected a positive integer, got {x}"))),
        OptionValue::Bool(b) => Err(opt_err(name, format!("expected a positive integer, got the boolean {b}"))),
        OptionValue::Str(s) => Err(opt_err(name, format!("expected a positive integer, got the string {s:?}"))),
        OptionValue::VertexValues(_) => Err(opt_err(name, "expected a positive integer, got per-vertex values")),
        OptionValue::Vertices(_) => Err(opt_err(name, "expected a positive integer, got vertex indices")),
    }
}

impl Default for Method {
    /// [`Method::Abf`] with its default options.
    fn default() -> Self {
        Method::Abf(abf::AbfOptions::default())
    }
}

impl Method {
    /// Build a method from its name and options.
    ///
    /// Errors: [`UvError::Option`] for an unknown method, an option the method does not take,
    /// or a value of the wrong type or out of range.
    pub fn parse(name: &str, options: &[(String, OptionValue)]) -> Result<Method> {
        let mut boundary = BoundaryShape::Circle;
        let mut spectral = SpectralOptions::default();
        let mut abf_opts = abf::AbfOptions::default();
        let mut arap_opts = arap::ArapOptions::default();
        let mut slim_opts = slim::SlimOptions::default();
        let mut mips_opts = mips::MipsOptions::default();
        let mut scaffold_opts = scaffold::ScaffoldOptions::default();
        let fixed = matches!(name, "tutte" | "harmonic" | "mean_value");
        for (key, value) in options {
            match (key.as_str(), name) {
                ("boundary", _) if fixed => {
                    boundary = match value {
                        OptionValue::Str(s) if s == "circle" => BoundaryShape::Circle,
                        OptionValue::Str(s) if s == "square" => BoundaryShape::Square,
                        OptionValue::Str(s) if s == "virtual" => BoundaryShape::Virtual,
                        other => return Err(opt_err("boundary", format!("expected \"circle\", \"square\" or \"virtual\", got {other:?}"))),
                    }
                }
                ("max_iterations", "spectral") => spectral.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "spectral") => spectral.tolerance = as_float("tolerance", value)?,
                ("solver", "abf") => {
                    abf_opts.solver = match value {
                        OptionValue::Str(s) if s == "abf++" => abf::AbfSolver::AbfPlusPlus,
                        OptionValue::Str(s) if s == "abf" => abf::AbfSolver::Plain,
                        other => return Err(opt_err("solver", format!("expected \"abf++\" or \"abf\", got {other:?}"))),
                    }
                }
                ("max_iterations", "abf") => abf_opts.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "abf") => abf_opts.tolerance = as_float("tolerance", value)?,
                ("boundary", "abf") => {
                    abf_opts.boundary = match value {
                        OptionValue::Str(s) if s == "free" => abf::AbfBoundary::Free,
                        OptionValue::Str(s) if s == "convex" => abf::AbfBoundary::Convex,
                        other => return Err(opt_err("boundary", format!("expected \"free\" or \"convex\", got {other:?}"))),
                    }
                }
                ("angle_sums", "abf") => {
                    abf_opts.angle_sums = match value {
                        OptionValue::VertexValues(v) => v.clone(),
                        other => {
                            return Err(opt_err("angle_sums", format!("expected (vertex indices, sums in radians), got {other:?}")))
                        }
                    }
                }
                ("max_iterations", "arap") => arap_opts.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "arap") => arap_opts.tolerance = as_float("tolerance", value)?,
                ("max_iterations", "slim") => slim_opts.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "slim") => slim_opts.tolerance = as_float("tolerance", value)?,
                ("max_iterations", "mips") => mips_opts.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "mips") => mips_opts.tolerance = as_float("tolerance", value)?,
                ("max_iterations", "scaffold") => scaffold_opts.max_iterations = as_count("max_iterations", value)?,
                ("tolerance", "scaffold") => scaffold_opts.tolerance = as_float("tolerance", value)?,
                ("start", "slim") => {
                    slim_opts.start = match value {
                        OptionValue::Str(s) if s == "auto" => slim::SlimStart::Auto,
                        OptionValue::Str(s) if s == "mean_value" => slim::SlimStart::MeanValue,
                        other => return Err(opt_err("start", format!("expected \"auto\" or \"mean_value\", got {other:?}"))),
                    }
                }
                ("step", "slim") => {
                    slim_opts.step = match value {
                        OptionValue::Str(s) if s == "newton" => slim::SlimStep::Newton,
                        OptionValue::Str(s) if s == "proxy" => slim::SlimStep::Proxy,
                        other => return Err(opt_err("step", format!("expected \"newton\" or \"proxy\", got {other:?}"))),
                    }
                }
                _ => {
                    if !method_names().contains(&name) {
                        break;
                    }
                    // Name the offending keyword, not the catch-all `**options`.
                    return Err(opt_err(key.as_str(), format!("method {name:?} has no option {key:?}")));
                }
            }
        }
        let m = match name {
            "tutte" => Method::Tutte { boundary },
            "harmonic" => Method::Harmonic { boundary },
            "mean_value" => Method::MeanValue { boundary },
            "lscm" => Method::Lscm,
            "spectral" => Method::Spectral(spectral),
            "bff" => Method::Bff,
            "abf" => Method::Abf(abf_opts),
            "arap" => Method::Arap(arap_opts),
            "slim" => Method::Slim(slim_opts),
            "mips" => Method::Mips(mips_opts),
            "scaffold" => Method::Scaffold(scaffold_opts),
            other => {
                return Err(opt_err("method", format!("unknown method {other:?}; expected one of {:?}", method_names())))
            }
        };
        m.validate()?;
        Ok(m)
    }

    /// Stable name of the method.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Tutte { .. } => "tutte",
            Method::Harmonic { .. } => "harmonic",
            Method::MeanValue { .. } => "mean_value",
            Method::Lscm => "lscm",
            Method::Spectral(_) => "spectral",
            Method::Bff => "bff",
            Method::Abf(_) => "abf",
            Method::Arap(_) => "arap",
            Method::Slim(_) => "slim",
            Method::Mips(_) => "mips",
            Method::Scaffold(_) => "scaffold",
        }
    }

    /// Check option values (also done by [`Method::parse`]).
    pub fn validate(&self) -> Result<()> {
        if let Method::Spectral(o) = self {
            if !(o.tolerance > 0.0 && o.tolerance.is_finite()) {
                return Err(opt_err("tolerance", format!("must be a positive number, got {}", o.tolerance)));
            }
            if o.max_iterations == 0 {
                return Err(opt_err("max_iterations", "must be at least 1"));
            }
        }
        if let Method::Abf(o) = self {
            if !(o.tolerance > 0.0 && o.tolerance.is_finite()) {
                return Err(opt_err("tolerance", format!("must be a positive number, got {}", o.tolerance)));
            }
            if o.max_iterations == 0 {
                return Err(opt_err("max_iterations", "must be at least 1"));
            }
            abf::validate_angle_sums(&o.angle_sums, &[])?;
        }
        let iterative = match self {
            Method::Arap(o) => Some((o.max_iterations, o.tolerance)),
            Method::Slim(o) => Some((o.max_iterations, o.tolerance)),
            Method::Mips(o) => Some((o.max_iterations, o.tolerance)),
            Method::Scaffold(o) => Some((o.max_iterations, o.tolerance)),
            _ => None,
        };
        if let Some((max_iterations, tolerance)) = iterative {
            if !(tolerance >= 0.0 && tolerance.is_finite()) {
                return Err(opt_err("tolerance", format!("must be a non-negative number, got {tolerance}")));
            }
            if max_iterations == 0 {
                return Err(opt_err("max_iterations", "must be at least 1"));
            }
        }
        Ok(())
    }
}

/// A chart could not be mapped; the string says why, in words a user can act on.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartFailure(pub String);

/// The method that actually produced a chart's UVs when it is not the requested one.
#[derive(Debug, Clone, PartialEq)]
pub struct Fallback {
    /// Name of the method used.
    pub method: &'static str,
    /// Why the requested method was not used.
    pub reason: String,
}

/// UVs of one chart (per chart vertex) and how they were obtained.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartSolution {
    /// UV per chart vertex.
    pub uv: Vec<[f64; 2]>,
    /// Iterations of an iterative method (0 for direct solves).
    pub iterations: usize,
    /// Final residual of an iterative method (0 for direct solves).
    pub residual: f64,
    /// A remark for the report (for example how pins were honoured).
    pub note: Option<String>,
    /// Set when another method produced the UVs.
    pub fallback: Option<Fallback>,
}

impl ChartSolution {
    pub(crate) fn direct(uv: Vec<[f64; 2]>) -> Self {
        ChartSolution { uv, iterations: 0, residual: 0.0, note: None, fallback: None }
    }
}

impl From<crate::solvers::SolveError> for ChartFailure {
    fn from(e: crate::solvers::SolveError) -> Self {
        ChartFailure(e.to_string())
    }
}

/// Corner angles of every chart triangle, clamped to valid triangles (see
/// [`crate::geometry::clamped_angles`]).
pub fn chart_angles(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    triangles
        .iter()
        .map(|t| crate::geometry::clamped_angles([positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]]))
        .collect()
}

/// Number of quads of `chart` that are not strictly convex under `uv` (with the chart's
/// positive orientation; [`crate::metrics::quad_folds`]).
pub fn nonconvex_quads(chart: &Chart, uv: &[[f64; 2]]) -> usize {
    chart.quads.iter().filter(|q| crate::metrics::quad_folds(q, uv, 1.0) > 0).count()
}

/// The triangles a barrier method (SLIM, MIPS, scaffold) keeps positive, with their area
/// weights, given its starting map `uv`: the chart's triangles, then the other diagonal's
/// two triangles of every quad that are positive at `uv` ([`Chart::triangles_both_splits`];
/// the four triangles of a quad weigh ½ each). Keeping both splits positive keeps quads
/// strictly convex, whichever diagonal an exporter picks. Also returns the number of
/// other-diagonal triangles left out because they are not positive at the start (no
/// barrier can restore them; the metrics count their quads).
pub fn barrier_triangles(chart: &Chart, uv: &[[f64; 2]]) -> (Vec<[u32; 3]>, Vec<f64>, usize) {
    let (all, w) = chart.triangles_both_splits();
    let n = chart.triangles.len();
    let mut tris = Vec::with_capacity(all.len());
    let mut weights = Vec::with_capacity(all.len());
    let mut left_out = 0;
    for (k, (t, wt)) in all.into_iter().zip(w).enumerate() {
        if k >= n {
            let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            let a = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
            if !(a > 0.0) {
                left_out += 1;
                continue;
            }
        }
        tris.push(t);
        weights.push(wt);
    }
    (tris, weights, left_out)
}

/// Make the non-convex quads of `sol` (a map of `chart` by `method`) strictly convex in place
/// with [`quad_repair::repair_quads`], which moves the few vertices involved and never flips
/// anything; `fixed` vertices (may be empty) and pinned ones stay. The repair is kept when it
/// fixed some quad, and the note says how many. Returns the quads still not strictly convex.
fn make_quads_convex(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    sol: &mut ChartSolution,
    method: &str,
    mut fixed: Vec<bool>,
) -> usize {
    let bad = nonconvex_quads(chart, &sol.uv);
    if bad == 0 {
        return 0;
    }
    if !pins.is_empty() {
        fixed.resize(chart.positions.len(), false);
        for &(v, _) in pins {
            fixed[v as usize] = true;
        }
    }
    let mut uv = sol.uv.clone();
    let (left, moved) = quad_repair::repair_quads(chart, &mut uv, &fixed);
    if left < bad && moved > 0 {
        sol.uv = uv;
        let done = if left == 0 { format!("{bad}") } else { format!("{} of {bad}", bad - left) };
        let note = format!("{done} quad(s) non-convex after {method} made strictly convex by moving {moved} vertex(es)");
        sol.note = Some(match sol.note.take() {
            Some(n) => format!("{n}; {note}"),
            None => note,
        });
        return left;
    }
    bad
}

/// Post-check of a linear method with no barrier at all (LSCM, spectral, ARAP): its
/// non-convex quads are made convex in place where the repair can ([`make_quads_convex`]; it
/// needs every triangle positive). What is left is the pipeline's to repair or report.
pub fn convex_quads(chart: &Chart, pins: &[(u32, [f64; 2])], mut sol: ChartSolution, method: &str) -> ChartSolution {
    if sol.fallback.is_none() {
        make_quads_convex(chart, pins, &mut sol, method, Vec::new());
    }
    sol
}

/// Post-check of a method that promises no flips but has no barrier for quads (ABF: its
/// angles are per triangle, so a quad's corner may exceed π): if `sol` leaves a quad of the
/// chart non-convex, first [`make_quads_convex`] moves the few vertices involved (never
/// flipping anything; pinned vertices and `fixed` ones stay) and the note says so;
/// if quads are still not convex, the chart is re-solved by SLIM, whose barrier covers both
/// diagonal splits of every quad and whose start (the mean value map on the polygon graph)
/// has convex quads; the report marks it as a fallback and says why. A solution that already
/// fell back (to LSCM, which promises nothing) is left alone, and so is one SLIM cannot
/// improve on.
pub fn convex_quads_or_slim(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    mut sol: ChartSolution,
    method: &str,
    fixed: Vec<bool>,
) -> std::result::Result<ChartSolution, ChartFailure> {
    if sol.fallback.is_some() {
        return Ok(sol);
    }
    let bad = nonconvex_quads(chart, &sol.uv);
    let left = make_quads_convex(chart, pins, &mut sol, method, fixed);
    if left == 0 {
        return Ok(sol);
    }
    let repaired = match slim::solve(chart, pins, &slim::SlimOptions::default()) {
        Ok(r) if r.fallback.is_none() && nonconvex_quads(chart, &r.uv) < left => r,
        _ => return Ok(sol),
    };
    let mut out = repaired;
    out.fallback = Some(Fallback {
        method: "slim",
        reason: format!(
            "the {method} layout left {bad} quad(s) non-convex (folded on one of their diagonals); SLIM, which keeps quads convex, was used instead{}",
            out.note.take().map(|n| format!(" ({n})")).unwrap_or_default()
        ),
    });
    Ok(out)
}

/// Check that a chart can be mapped by a method that needs a disk (with or without holes).
pub fn require_disk(chart: &Chart) -> std::result::Result<(), ChartFailure> {
    if let Some(d) = &chart.defect {
        return Err(ChartFailure(d.clone()));
    }
    match chart.kind {
        ChartKind::Disk | ChartKind::DiskWithHoles => Ok(()),
        ChartKind::Closed => Err(ChartFailure(
            "closed surface without boundary: mark at least one seam to open it, or turn on automatic seams".into(),
        )),
        ChartKind::HigherGenus => Err(ChartFailure(format!(
            "surface of genus {}: mark seams that cut through every handle, or turn on automatic seams",
            chart.genus
        ))),
    }
}

impl Method {
    /// Whether the method promises no flipped triangles on an unpinned chart (README's
    /// "promise" column): Tutte and mean value on the circle or the virtual boundary, ABF on
    /// disk charts, SLIM, MIPS and scaffold. Pins are the user's constraint and may force
    /// flips; they are counted in the report then.
    pub fn promises_no_flips(&self, kind: ChartKind) -> bool {
        match self {
            Method::Tutte { boundary } | Method::MeanValue { boundary } => *boundary != BoundaryShape::Square,
            Method::Abf(_) => kind == ChartKind::Disk,
            Method::Slim(_) | Method::Mips(_) | Method::Scaffold(_) => true,
            Method::Harmonic { .. } | Method::Lscm | Method::Spectral(_) | Method::Bff | Method::Arap(_) => false,
        }
    }

    /// Whether the method finds the island's outline itself (every method but Tutte, mean value
    /// and harmonic, which map it onto a shape the user chose).
    pub fn free_boundary(&self) -> bool {
        !matches!(self, Method::Tutte { .. } | Method::MeanValue { .. } | Method::Harmonic { .. })
    }

    /// Whether the method's optimum on a flat chart is a similarity of it, so the chart is laid
    /// as it is ([`planar`]; a direct solve, 0 iterations): every free-boundary method but ABF
    /// with a convex outline or prescribed angle sums, which bend the outline.
    pub fn lays_flat_as_is(&self) -> bool {
        match self {
            Method::Abf(o) => o.boundary != abf::AbfBoundary::Convex && o.angle_sums.is_empty(),
            _ => self.free_boundary(),
        }
    }

    /// Whether the method trades angle distortion for area distortion (ARAP, SLIM, scaffold).
    /// The others (conformal maps, MIPS among them: its energy σ1/σ2 + σ2/σ1 sees angles only,
    /// and fixed-boundary maps) spread area at least about as much as the conformal
    /// flattening that keeps the outline's lengths, so that flattening predicts when they
    /// break Max Stretch ([`crate::pipeline::triage`]).
    pub fn balances_area(&self) -> bool {
        matches!(self, Method::Arap(_) | Method::Slim(_) | Method::Scaffold(_))
    }
}

/// The chart in a unit frame: positions moved to the centre of their bounding box and divided
/// by its largest half extent rounded to a power of two, and the pins divided by the same size
/// (UV space has no origin to move). A power of two scales exactly, so pinned UVs come back
/// bit for bit. Returns the moved chart, the pins and the size to multiply the UVs by.
fn unit_chart(chart: &Chart, pins: &[(u32, [f64; 2])]) -> (Chart, Vec<(u32, [f64; 2])>, f64) {
    let (centre, size) = crate::geometry::bounding_frame(&chart.positions);
    let size = 2f64.powi(size.log2().round() as i32);
    let unit = chart.with_positions(crate::geometry::to_unit_frame(&chart.positions, centre, size));
    let pins = pins.iter().map(|&(v, p)| (v, [p[0] / size, p[1] / size])).collect();
    (unit, pins, size)
}

fn dispatch(method: &Method, chart: &Chart, pins: &[(u32, [f64; 2])]) -> std::result::Result<ChartSolution, ChartFailure> {
    match method {
        Method::Tutte { boundary } => tutte::solve(chart, pins, *boundary),
        Method::Harmonic { boundary } => harmonic::solve(chart, pins, *boundary),
        Method::MeanValue { boundary } => mean_value::solve(chart, pins, *boundary),
        Method::Lscm => lscm::solve(chart, pins).map(|sol| convex_quads(chart, pins, sol, "LSCM")),
        Method::Spectral(o) => {
            spectral::solve(chart, pins, o).map(|sol| convex_quads(chart, pins, sol, "the spectral map"))
        }
        Method::Bff => bff::solve(chart, pins).map(|sol| convex_quads(chart, pins, sol, "the bff map")),
        Method::Abf(o) => abf::solve(chart, pins, o).and_then(|sol| {
            // A convex outline stays put: its vertices do not move (holes' may).
            let mut fixed = Vec::new();
            if o.boundary == abf::AbfBoundary::Convex {
                fixed = vec![false; chart.positions.len()];
                for &v in chart.outer_loop().map(|l| &chart.boundary_loops[l][..]).unwrap_or(&[]) {
                    fixed[v as usize] = true;
                }
            }
            convex_quads_or_slim(chart, pins, sol, "ABF", fixed)
        }),
        Method::Arap(o) => arap::solve(chart, pins, o).map(|sol| convex_quads(chart, pins, sol, "ARAP")),
        Method::Slim(o) => slim::solve(chart, pins, o),
        Method::Mips(o) => mips::solve(chart, pins, o),
        Method::Scaffold(o) => scaffold::solve(chart, pins, o),
    }
}

/// What is wrong with a method's UVs, if anything: a non-finite UV, a flipped triangle
/// ([`crate::metrics::flipped_triangles`]) from a method that promises none, or a boundary
/// crossing itself from a method that promises no overlap (scaffold).
fn defect(chart: &Chart, uv: &[[f64; 2]], promise: bool, no_overlap: bool) -> Option<String> {
    if let Some(i) = uv.iter().position(|p| !p[0].is_finite() || !p[1].is_finite()) {
        return Some(format!("the solve produced a non-finite UV at mesh vertex {}", chart.mesh_vertex[i]));
    }
    if promise {
        let flips = crate::metrics::count_flips_with_quads(&chart.triangles, &chart.quads, uv);
        if flips > 0 {
            return Some(format!("the map has {flips} flipped or zero-area triangle(s) or folded quad(s) (degenerate 3D triangles?)"));
        }
        // Closed seams (the two sides of a cut on each other, as a flat chart laid as it is
        // has them) are no overlap.
        let (p, t, loops) = (&chart.positions, &chart.triangles, &chart.boundary_loops);
        let overlap = || crate::metrics::closed_seams::outline_overlap(p, t, uv, loops);
        if no_overlap && overlap() {
            return Some("the map's boundary crosses itself".into());
        }
    }
    None
}

/// Map one chart with `method`, honouring `pins` (chart vertex, UV) as the method allows.
///
/// The chart is solved in a unit frame (its positions centred and scaled to unit size, pins
/// scaled alike) and its UVs scaled back, so the result does not depend on the chart's size or
/// place: any finite coordinates (1e-150 to 1e150 and beyond) give finite UVs.
///
/// Near-degenerate 3D triangles (collinear or coincident vertices) get clamped angles (at
/// least [`crate::geometry::MIN_ANGLE`], see [`crate::geometry::clamped_angles`]) wherever a
/// method uses angles or cotangents, and floored edge lengths in mean value weights, so every
/// system stays finite; the result is then checked rather than trusted.
///
/// Validity: a result with a non-finite UV, or with a flipped triangle from a method that
/// promises none on an unpinned chart ([`Method::promises_no_flips`]), or with a boundary
/// crossing itself from scaffold (on an unpinned chart), is never returned as solved: the
/// chart falls back to LSCM (methods without a promise; only for a non-finite result) and then
/// to Tutte's uniform-weight map onto the circle, which depends on the connectivity alone and
/// does not flip a triangle of a disk (Tutte's theorem; boundary points kept apart, see
/// [`fixed_boundary::boundary_positions`]); the fallback's reason says why, and says so when
/// the fallback still has flips. When no candidate gives finite UVs the chart fails with the
/// reason.
pub fn solve(method: &Method, chart: &Chart, pins: &[(u32, [f64; 2])]) -> std::result::Result<ChartSolution, ChartFailure> {
    require_disk(chart)?;
    let (unit, unit_pins, size) = unit_chart(chart, pins);
    let promise = pins.is_empty() && method.promises_no_flips(chart.kind);
    // A flat chart is laid as it is by every method whose optimum it is ([`planar`]).
    let flat = if unit_pins.is_empty() && method.lays_flat_as_is() { planar::project(&unit) } else { None };
    let mut sol = match flat {
        Some(uv) => ChartSolution::direct(uv),
        None => dispatch(method, &unit, &unit_pins)?,
    };
    // A method that already fell back has said why; only its finiteness is checked.
    let no_overlap = matches!(method, Method::Scaffold(_));
    if let Some(why) = defect(&unit, &sol.uv, promise && sol.fallback.is_none(), no_overlap) {
        let tutte = Method::Tutte { boundary: BoundaryShape::Circle };
        let mut candidates: Vec<Method> = Vec::new();
        if !promise && !matches!(method, Method::Lscm) {
            candidates.push(Method::Lscm);
        }
        if *method != tutte {
            candidates.push(tutte);
        }
        let mut last = why.clone();
        let mut found = None;
        for m in candidates {
            match dispatch(&m, &unit, &unit_pins) {
                Ok(s) => match defect(&unit, &s.uv, false, false) {
                    None => {
                        found = Some((m.name(), s));
                        break;
                    }
                    Some(d) => last = format!("{}: {d}", m.name()),
                },
                Err(ChartFailure(e)) => last = format!("{}: {e}", m.name()),
            }
        }
        let Some((name, mut s)) = found else {
            return Err(ChartFailure(if last == why { why } else { format!("{why}; fallback {last}") }));
        };
        let flips = crate::metrics::count_flips_with_quads(&unit.triangles, &unit.quads, &s.uv);
        let mut reason = format!("{} rejected: {why}", method.name());
        if flips > 0 {
            reason.push_str(&format!("; the fallback still has {flips} flipped triangle(s)"));
        }
        if let Some(note) = s.note.take() {
            reason.push_str(&format!("; {note}"));
        }
        s.fallback = Some(Fallback { method: name, reason });
        sol = s;
    }
    for p in sol.uv.iter_mut() {
        *p = [p[0] * size, p[1] * size];
    }
    if let Some(i) = sol.uv.iter().position(|p| !p[0].is_finite() || !p[1].is_finite()) {
        return Err(ChartFailure(format!("the UVs overflow at mesh vertex {} when scaled back to the chart's size", chart.mesh_vertex[i])));
    }
    Ok(sol)
}
