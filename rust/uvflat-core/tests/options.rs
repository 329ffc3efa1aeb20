//! The declared option table (`methods::options`) agrees with `Method::parse`.

use uvflat_core::methods::options::{method_options, OptionDefault, OptionKind};
use uvflat_core::{method_names, Method, OptionValue, UvError};

fn value_of(d: OptionDefault) -> Option<OptionValue> {
    match d {
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
                OptionKind::Float { min, min_exclusive } => {
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
            }
        }
        // and nothing else
        match Method::parse(name, &[("surely_not_an_option".into(), OptionValue::Int(1))]) {
            Err(UvError::Option { name: opt, .. }) => assert_eq!(opt, "surely_not_an_option"),
            other => panic!("{name}: {other:?}"),
        }
    }
}
