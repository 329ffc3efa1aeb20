//! The declared option tables agree with the parsers: `methods::options` with
//! `Method::parse`, `cuts::options` with `AutoSeamOptions::parse`, `Default` and `validate`.

use uvflat_core::methods::options::{method_options, OptionDefault, OptionKind};
use uvflat_core::{auto_seam_options, method_names, AutoSeamOptions, Method, OptionValue, Symmetry, UnknownSymmetry, UvError};

fn value_of(d: OptionDefault) -> Option<OptionValue> {
    match d {
        OptionDefault::Bool(b) => Some(OptionValue::Bool(b)),
        OptionDefault::Int(i) => Some(OptionValue::Int(i)),
        OptionDefault::Float(x) => Some(OptionValue::Float(x)),
        OptionDefault::Str(s) => Some(OptionValue::Str(s.to_string())),
        OptionDefault::Empty => None,
    }
}

#[test]
fn declared_defaults_are_the_methods_defaults() {
    for &name in method_names() {
        let declared: Vec<(String, OptionValue)> = method_options(name)
            .iter()
            .filter_map(|o| value_of(o.default).map(|v| (o.name.to_string(), v)))
            .collect();
        let with = Method::parse(name, &declared).unwrap_or_else(|e| panic!("{name}: {e}"));
        let without = Method::parse(name, &[]).unwrap();
        assert_eq!(format!("{with:?}"), format!("{without:?}"), "{name}: declared defaults differ");
    }
}

#[test]
fn declared_domains_are_the_parsers() {
    for &name in method_names() {
        for o in method_options(name) {
            let parse = |v: OptionValue| Method::parse(name, &[(o.name.to_string(), v)]);
            match o.kind {
                OptionKind::Int { min, .. } => {
                    assert!(parse(OptionValue::Int(min)).is_ok(), "{name}.{}", o.name);
                    assert!(parse(OptionValue::Int(min - 1)).is_err(), "{name}.{}", o.name);
                }
                OptionKind::Float { min, min_exclusive, max, .. } => {
                    assert_eq!(max, f64::INFINITY, "{name}.{}: methods declare no upper bound", o.name);
                    assert!(parse(OptionValue::Float(min + 1e-3)).is_ok(), "{name}.{}", o.name);
                    assert_eq!(parse(OptionValue::Float(min)).is_err(), min_exclusive, "{name}.{}", o.name);
                    assert!(parse(OptionValue::Float(min - 1.0)).is_err(), "{name}.{}", o.name);
                }
                OptionKind::Choice(choices) => {
                    for c in choices {
                        assert!(parse(OptionValue::Str(c.to_string())).is_ok(), "{name}.{}={c}", o.name);
                    }
                    assert!(parse(OptionValue::Str("no such choice".into())).is_err(), "{name}.{}", o.name);
                }
                OptionKind::VertexValues => {
                    assert!(parse(OptionValue::VertexValues(vec![])).is_ok(), "{name}.{}", o.name);
                }
                OptionKind::Bool | OptionKind::Vertices => panic!("{name}.{}: no method option is of this kind", o.name),
            }
        }
        // and nothing else
        match Method::parse(name, &[("surely_not_an_option".into(), OptionValue::Int(1))]) {
            Err(UvError::Option { name: opt, .. }) => assert_eq!(opt, "surely_not_an_option"),
            other => panic!("{name}: {other:?}"),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Automatic seams

const N_VERTICES: usize = 10;

fn auto(name: &str, v: OptionValue) -> uvflat_core::Result<AutoSeamOptions> {
    let o = AutoSeamOptions::parse(&[(name.to_string(), v)])?;
    o.validate(N_VERTICES)?;
    Ok(o)
}

fn option_name(e: UvError) -> String {
    match e {
        UvError::Option { name, .. } => name,
        other => panic!("not an option error: {other:?}"),
    }
}

#[test]
fn auto_seam_declared_defaults_are_the_default_options() {
    let declared: Vec<(String, OptionValue)> =
        auto_seam_options().iter().filter_map(|o| value_of(o.default).map(|v| (o.name.to_string(), v))).collect();
    // every option but the two that are off by default has a value
    assert_eq!(declared.len(), auto_seam_options().len() - 2);
    let parsed = AutoSeamOptions::parse(&declared).unwrap();
    assert_eq!(parsed, AutoSeamOptions::default());
    // and each declared default differs from a non-default value, so the comparison bites
    let d = AutoSeamOptions::default();
    assert!(d.enabled && d.max_stretch == 2.0 && d.max_cones == 8);
    assert!(d.avoid_vertices.is_empty() && d.sharp_angle.is_none());
    assert_eq!(d.visibility_weight, uvflat_core::cuts::VISIBILITY_WEIGHT);
    assert_eq!(d.symmetry, Symmetry::None);
    // an option declared without a default is off in the default options
    for o in auto_seam_options().iter().filter(|o| o.default == OptionDefault::Empty) {
        match o.name {
            "avoid_vertices" | "sharp_angle" => {}
            other => panic!("{other}: declared without a default"),
        }
    }
}

#[test]
fn auto_seam_declared_names_are_the_fields() {
    let names: Vec<&str> = auto_seam_options().iter().map(|o| o.name).collect();
    assert_eq!(
        names,
        [
            "auto_seams",
            "max_stretch",
            "max_cones",
            "avoid_vertices",
            "sharp_angle",
            "visibility_weight",
            "symmetry",
            "same_seams"
        ]
    );
    assert!(auto_seam_options().iter().all(|o| !o.doc.is_empty()));
    assert_eq!(option_name(AutoSeamOptions::parse(&[("no_such".into(), OptionValue::Int(1))]).unwrap_err()), "no_such");
}

#[test]
fn auto_seam_declared_ranges_are_what_validate_keeps() {
    for o in auto_seam_options() {
        let ok = |v: OptionValue| auto(o.name, v.clone()).unwrap_or_else(|e| panic!("{}={v:?} refused: {e}", o.name));
        let refused = |v: OptionValue| {
            let e = auto(o.name, v.clone()).expect_err(&format!("{}={v:?} accepted", o.name));
            assert_eq!(option_name(e), o.name);
        };
        match o.kind {
            OptionKind::Int { min, max } => {
                ok(OptionValue::Int(min));
                ok(OptionValue::Int(max));
                refused(OptionValue::Int(min - 1));
                refused(OptionValue::Int(max + 1));
                refused(OptionValue::Float(min as f64));
            }
            OptionKind::Float { min, min_exclusive, max, max_exclusive } => {
                let step = 1e-6 * (1.0 + min.abs());
                ok(OptionValue::Float(min + step));
                if min_exclusive {
                    refused(OptionValue::Float(min));
                } else {
                    ok(OptionValue::Float(min));
                }
                refused(OptionValue::Float(min - step));
                if max.is_finite() {
                    ok(OptionValue::Float(max - 1e-6 * (1.0 + max.abs())));
                    if max_exclusive {
                        refused(OptionValue::Float(max));
                    } else {
                        ok(OptionValue::Float(max));
                    }
                    refused(OptionValue::Float(max + 1e-6 * (1.0 + max.abs())));
                } else {
                    ok(OptionValue::Float(1e12));
                    refused(OptionValue::Float(f64::INFINITY));
                }
                refused(OptionValue::Float(f64::NAN));
                refused(OptionValue::Str("a".into()));
                refused(OptionValue::Bool(true));
            }
            OptionKind::Choice(choices) => {
                for c in choices {
                    ok(OptionValue::Str(c.to_string()));
                }
                refused(OptionValue::Str("w".into()));
                refused(OptionValue::Int(0));
            }
            OptionKind::Bool => {
                let field = |a: &AutoSeamOptions| match o.name {
                    "auto_seams" => a.enabled,
                    "same_seams" => a.same_seams,
                    other => panic!("{other}: a boolean option this test does not know"),
                };
                for v in [false, true] {
                    assert_eq!(field(&ok(OptionValue::Bool(v))), v, "{}", o.name);
                }
                refused(OptionValue::Int(1));
            }
            OptionKind::Vertices => {
                ok(OptionValue::Vertices(vec![]));
                ok(OptionValue::Vertices(vec![N_VERTICES as u32 - 1]));
                refused(OptionValue::Vertices(vec![N_VERTICES as u32]));
                refused(OptionValue::Float(1.0));
            }
            OptionKind::VertexValues => panic!("{}: automatic seams take no per-vertex values", o.name),
        }
    }
}

#[test]
fn symmetry_names_round_trip() {
    let all = [Symmetry::None, Symmetry::X, Symmetry::Y, Symmetry::Z, Symmetry::Auto];
    assert_eq!(Symmetry::NAMES.len(), all.len());
    for s in all {
        assert_eq!(Symmetry::parse(s.name()), Ok(s));
        assert_eq!(s.name().parse::<Symmetry>(), Ok(s));
        assert_eq!(s.to_string(), s.name());
    }
    assert_eq!(Symmetry::parse("w"), Err(UnknownSymmetry("w".into())));
    assert_eq!(Symmetry::parse("X"), Err(UnknownSymmetry("X".into())));
    assert!(Symmetry::parse("w").unwrap_err().to_string().contains("\"w\""));
    match auto_seam_options().iter().find(|o| o.name == "symmetry").unwrap().kind {
        OptionKind::Choice(c) => assert_eq!(c, Symmetry::NAMES),
        other => panic!("{other:?}"),
    }
}
