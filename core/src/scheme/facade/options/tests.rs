//! Tests of [`options`](super).

use super::*;

#[test]
fn the_table_names_every_key_once_and_in_word_order() {
    assert_eq!(KEYS.len(), Options::default().words().len());
    assert!(KEYS.len() <= 32);
    for (i, k) in KEYS.iter().enumerate() {
        assert_eq!(key_index(k.name), Some(i));
    }
}

#[test]
fn set_checks_the_kind_and_the_range_and_changes_nothing_on_error() {
    let mut o = Options::default();
    let before = o.clone();
    assert!(matches!(
        o.set("dt", Value::Real(0.0)),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(
        o.set("dt", Value::Name("x")),
        Err(Error::OptionValue { .. })
    ));
    assert!(matches!(
        o.set("size-limit", Value::Real(1.5)),
        Err(Error::OptionValue { .. })
    ));
    assert!(matches!(
        o.set("size-limit", Value::Real(-1.0)),
        Err(Error::OptionValue { .. })
    ));
    assert!(matches!(
        o.set("points", Value::Name("halton")),
        Err(Error::OptionValue { .. })
    ));
    assert!(matches!(
        o.set("nope", Value::Flag(true)),
        Err(Error::UnknownName { .. })
    ));
    assert_eq!(o, before);
    o.set("size-limit", Value::Real(1e6)).unwrap();
    assert_eq!(o.size_limit(), 1_000_000);
    assert!(o.is_given("size-limit") && !o.is_given("dt"));
}

#[test]
fn a_given_key_must_apply() {
    let o = Options::default().with_truncation(10.0);
    assert!(o.check_for("mfa", &["truncation"]).is_ok());
    let e = o.check_for("dsa", &["capacity"]).unwrap_err();
    assert_eq!(
        e,
        Error::OptionNotApplicable {
            key: "truncation",
            scheme: "dsa"
        }
    );
    // seed and stream apply everywhere
    assert!(
        Options::default()
            .with_stream(1, 2)
            .check_for("dsa", &[])
            .is_ok()
    );
}
