//! A line of `coagula validate`'s table: what every reproduction case reports (the
//! experiments of `reproduce` build them, `validate` prints them).

use serde::Serialize;

/// One line of the validation table.
#[derive(Clone, Debug, Serialize)]
pub struct Case {
    /// The case's name (its prefix is the experiment).
    pub case: String,
    /// The quantity checked.
    pub quantity: String,
    /// The reference value.
    pub reference: f64,
    /// Ours.
    pub value: f64,
    /// Ours − reference.
    pub error: f64,
    /// The tolerance of |error|.
    pub tolerance: f64,
    /// Within it.
    pub pass: bool,
}
