//! The declared options of automatic seams: name, type, default, range or choices, and doc.
//!
//! One table, as [`crate::methods::options`] is for the methods: read by the Python module
//! (`uvflat.AUTO_SEAM_OPTIONS`) and through it by the add-on, the batch script and the type
//! stub's tests, so that every front end offers the options [`AutoSeamOptions::parse`]
//! accepts with the defaults [`AutoSeamOptions::default`] has. Tests check that the declared
//! defaults parse to the default options and that every declared range is the one
//! [`AutoSeamOptions::validate`] keeps.

use super::{AutoSeamOptions, Symmetry, VISIBILITY_WEIGHT};
use crate::error::{Result, UvError};
use crate::methods::options::{OptionDefault, OptionKind, OptionSpec};
use crate::methods::OptionValue;

const AUTO_SEAMS: &[OptionSpec] = &[
    OptionSpec {
        name: "auto_seams",
        kind: OptionKind::Bool,
        default: OptionDefault::Bool(true),
        doc: "hold every island to the atlas rule (a disk, no flips, a clean outline, texel density within max_stretch), cutting where needed",
    },
    OptionSpec {
        name: "max_stretch",
        kind: OptionKind::Float { min: 1.0, min_exclusive: true, max: f64::INFINITY, max_exclusive: false },
        default: OptionDefault::Float(2.0),
        doc: "at most 5% of an island's area may have a texel density outside [1/s, s] of the island's own",
    },
    OptionSpec {
        name: "max_cones",
        kind: OptionKind::Int { min: 0, max: 1000 },
        default: OptionDefault::Int(8),
        doc: "most cone points per island (a closed sphere gets at least 2)",
    },
    OptionSpec {
        name: "avoid_vertices",
        kind: OptionKind::Vertices,
        default: OptionDefault::Empty,
        doc: "mesh vertex indices where seams must not go (no cut edge touches them, none becomes a cone)",
    },
    OptionSpec {
        name: "sharp_angle",
        kind: OptionKind::Float { min: 0.0, min_exclusive: true, max: std::f64::consts::PI, max_exclusive: true },
        default: OptionDefault::Empty,
        doc: "dihedral angle in radians from which an edge counts as sharp and is preferred for seams (none: no preference)",
    },
    OptionSpec {
        name: "visibility_weight",
        kind: OptionKind::Float { min: 0.0, min_exclusive: false, max: 100.0, max_exclusive: false },
        default: OptionDefault::Float(VISIBILITY_WEIGHT),
        doc: "how much dearer a seam is on exposed surface than in hidden places (per-vertex ambient occlusion; 0: off)",
    },
    OptionSpec {
        name: "symmetry",
        kind: OptionKind::Choice(Symmetry::NAMES),
        default: OptionDefault::Str("none"),
        doc: "mirror plane the seams keep on a mirror-symmetric island (x, y, z: across that axis through its centre; auto: a principal axis)",
    },
    OptionSpec {
        name: "same_seams",
        kind: OptionKind::Bool,
        default: OptionDefault::Bool(false),
        doc: "plan the cuts of slim, arap and scaffold on the prediction the other methods use, so switching methods keeps the seams (off: they start from the cones alone and usually get fewer seams and islands)",
    },
];

/// The options of automatic seams, in the order front ends show them.
pub fn auto_seam_options() -> &'static [OptionSpec] {
    AUTO_SEAMS
}

fn opt_err(name: &str, reason: impl Into<String>) -> UvError {
    UvError::Option { name: name.to_string(), reason: reason.into() }
}

fn describe(v: &OptionValue) -> String {
    match v {
        OptionValue::Bool(b) => format!("the boolean {b}"),
        OptionValue::Int(i) => format!("the integer {i}"),
        OptionValue::Float(x) => format!("the number {x}"),
        OptionValue::Str(s) => format!("the string {s:?}"),
        OptionValue::VertexValues(_) => "per-vertex values".into(),
        OptionValue::Vertices(_) => "vertex indices".into(),
    }
}

fn number(name: &str, v: &OptionValue) -> Result<f64> {
    match v {
        OptionValue::Float(x) => Ok(*x),
        OptionValue::Int(i) => Ok(*i as f64),
        other => Err(opt_err(name, format!("expected a number, got {}", describe(other)))),
    }
}

impl AutoSeamOptions {
    /// Options from `(name, value)` pairs named as in [`auto_seam_options`]; an option not
    /// given keeps its default. Ranges are checked by [`AutoSeamOptions::validate`].
    ///
    /// Errors: [`UvError::Option`] naming an unknown option, a value of the wrong type, a
    /// negative `max_cones` or an unknown `symmetry`.
    pub fn parse(values: &[(String, OptionValue)]) -> Result<AutoSeamOptions> {
        let mut o = AutoSeamOptions::default();
        for (name, value) in values {
            o.set(name, value)?;
        }
        Ok(o)
    }

    /// Set the option `name` (see [`AutoSeamOptions::parse`]).
    pub fn set(&mut self, name: &str, value: &OptionValue) -> Result<()> {
        match name {
            "auto_seams" => match value {
                OptionValue::Bool(b) => self.enabled = *b,
                other => return Err(opt_err(name, format!("expected a boolean, got {}", describe(other)))),
            },
            "max_stretch" => self.max_stretch = number(name, value)?,
            "max_cones" => match value {
                OptionValue::Int(i) if *i >= 0 => self.max_cones = (*i).min(u32::MAX as i64) as usize,
                OptionValue::Int(i) => return Err(opt_err(name, format!("must be a non-negative integer, got {i}"))),
                other => return Err(opt_err(name, format!("expected a non-negative integer, got {}", describe(other)))),
            },
            "avoid_vertices" => match value {
                OptionValue::Vertices(v) => self.avoid_vertices = v.clone(),
                other => return Err(opt_err(name, format!("expected vertex indices, got {}", describe(other)))),
            },
            "sharp_angle" => self.sharp_angle = Some(number(name, value)?),
            "visibility_weight" => self.visibility_weight = number(name, value)?,
            "same_seams" => match value {
                OptionValue::Bool(b) => self.same_seams = *b,
                other => return Err(opt_err(name, format!("expected a boolean, got {}", describe(other)))),
            },
            "symmetry" => match value {
                OptionValue::Str(s) => self.symmetry = Symmetry::parse(s).map_err(|e| opt_err(name, e.to_string()))?,
                other => {
                    return Err(opt_err(name, format!("expected one of {:?}, got {}", Symmetry::NAMES, describe(other))))
                }
            },
            other => return Err(opt_err(other, format!("automatic seams have no option {other:?}"))),
        }
        Ok(())
    }
}
