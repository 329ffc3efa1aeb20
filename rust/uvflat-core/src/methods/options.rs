//! The declared options of every method: name, type, default, range or choices, and doc.
//!
//! One table, read by the Python module (`uvflat.METHOD_OPTIONS`) and through it by the
//! add-on, the batch script and the type stub's tests, so that every front end offers the
//! options [`Method::parse`](super::Method::parse) accepts with the defaults it uses. A test
//! checks that parsing the declared defaults gives each method's `Default` options. The
//! options of automatic seams are declared the same way in
//! [`crate::cuts::options::auto_seam_options`].

/// The type and domain of an option.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// An integer in `min..=max`.
    Int { min: i64, max: i64 },
    /// A float in `[min, max]`; `min_exclusive` / `max_exclusive` tell whether `min` / `max`
    /// itself is refused (`max` is infinite for no upper bound).
    Float { min: f64, min_exclusive: bool, max: f64, max_exclusive: bool },
    /// One of the strings.
    Choice(&'static [&'static str]),
    /// `(vertex indices, values)`: a value at chosen mesh vertices.
    VertexValues,
    /// A boolean.
    Bool,
    /// Mesh vertex indices.
    Vertices,
}

/// The default value of an option.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionDefault {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(&'static str),
    /// No value (an empty list of vertex values or indices; an option that is off).
    Empty,
}

/// One declared option.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionSpec {
    /// Keyword accepted by [`Method::parse`](super::Method::parse) (or by
    /// [`AutoSeamOptions::parse`](crate::AutoSeamOptions::parse)).
    pub name: &'static str,
    pub kind: OptionKind,
    pub default: OptionDefault,
    /// One line for users.
    pub doc: &'static str,
}

const ITERATIONS: OptionKind = OptionKind::Int { min: 1, max: i64::MAX };
const POSITIVE: OptionKind = OptionKind::Float { min: 0.0, min_exclusive: true, max: f64::INFINITY, max_exclusive: false };
const NON_NEGATIVE: OptionKind = OptionKind::Float { min: 0.0, min_exclusive: false, max: f64::INFINITY, max_exclusive: false };
const ENERGY_CHANGE: &str = "stop when the energy changes by less than this (relative)";

const FIXED: &[OptionSpec] = &[OptionSpec {
    name: "boundary",
    kind: OptionKind::Choice(&["circle", "square", "virtual"]),
    default: OptionDefault::Str("circle"),
    doc: "shape the boundary is fixed to (virtual: a band of virtual triangles on the circle)",
}];

const SPECTRAL: &[OptionSpec] = &[
    OptionSpec {
        name: "max_iterations",
        kind: ITERATIONS,
        default: OptionDefault::Int(200),
        doc: "most solves of the eigenvector search",
    },
    OptionSpec {
        name: "tolerance",
        kind: POSITIVE,
        default: OptionDefault::Float(1e-10),
        doc: "stop when the eigenvector's residual, relative to its eigenvalue, is below this",
    },
];

const ABF: &[OptionSpec] = &[
    OptionSpec {
        name: "solver",
        kind: OptionKind::Choice(&["abf++", "abf"]),
        default: OptionDefault::Str("abf++"),
        doc: "abf++: block elimination (fast); abf: the full system by sparse LU",
    },
    OptionSpec {
        name: "boundary",
        kind: OptionKind::Choice(&["free", "convex"]),
        default: OptionDefault::Str("free"),
        doc: "constraint on the outer boundary angles (convex: at most 180 degrees)",
    },
    OptionSpec { name: "max_iterations", kind: ITERATIONS, default: OptionDefault::Int(30), doc: "most Newton iterations" },
    OptionSpec {
        name: "tolerance",
        kind: POSITIVE,
        default: OptionDefault::Float(1e-5),
        doc: "largest violation of the angle constraints accepted",
    },
    OptionSpec {
        name: "angle_sums",
        kind: OptionKind::VertexValues,
        default: OptionDefault::Empty,
        doc: "(vertex indices, angle sums in radians) prescribed at mesh vertices",
    },
];

const fn iterative(iterations: i64, tolerance: f64) -> [OptionSpec; 2] {
    [
        OptionSpec { name: "max_iterations", kind: ITERATIONS, default: OptionDefault::Int(iterations), doc: "most iterations" },
        OptionSpec { name: "tolerance", kind: NON_NEGATIVE, default: OptionDefault::Float(tolerance), doc: ENERGY_CHANGE },
    ]
}

const ARAP: &[OptionSpec] = &iterative(100, 1e-6);
const MIPS: &[OptionSpec] = &iterative(50, 1e-6);
const SCAFFOLD: &[OptionSpec] = &iterative(100, 1e-4);
const SLIM_ITER: [OptionSpec; 2] = iterative(15, 1e-4);
const SLIM: &[OptionSpec] = &[
    SLIM_ITER[0],
    OptionSpec { doc: "stop when the energy changes by less than this (relative), or is predicted to at the next iteration", ..SLIM_ITER[1] },
    OptionSpec {
        name: "start",
        kind: OptionKind::Choice(&["auto", "mean_value"]),
        default: OptionDefault::Str("auto"),
        doc: "flip-free start (auto: the better of LSCM, when flip-free, and mean value)",
    },
    OptionSpec {
        name: "step",
        kind: OptionKind::Choice(&["newton", "proxy"]),
        default: OptionDefault::Str("newton"),
        doc: "steps after the first (newton: projected Newton, fewer iterations; proxy: SLIM's own)",
    },
];

/// The options `method` accepts (empty for a method without options or an unknown name).
pub fn method_options(method: &str) -> &'static [OptionSpec] {
    match method {
        "tutte" | "harmonic" | "mean_value" => FIXED,
        "spectral" => SPECTRAL,
        "abf" => ABF,
        "arap" => ARAP,
        "slim" => SLIM,
        "mips" => MIPS,
        "scaffold" => SCAFFOLD,
        _ => &[],
    }
}
