//! The example scenarios of `examples/`, built into the binary so that `coagula run NAME`
//! and `coagula validate` work from any directory.

/// `(file name, text)` of every example scenario.
pub const EXAMPLES: &[(&str, &str)] = &[
    (
        "aerosol-brownian-physical.toml",
        include_str!("../../examples/aerosol-brownian-physical.toml"),
    ),
    (
        "blocks-atmospheric.toml",
        include_str!("../../examples/blocks-atmospheric.toml"),
    ),
    (
        "constant-exponential-massflow.toml",
        include_str!("../../examples/constant-exponential-massflow.toml"),
    ),
    (
        "lecot2019-coagulation-fragmentation.toml",
        include_str!("../../examples/lecot2019-coagulation-fragmentation.toml"),
    ),
    (
        "multiplicative-gelation.toml",
        include_str!("../../examples/multiplicative-gelation.toml"),
    ),
    (
        "osinsky2023-table1-brownian.toml",
        include_str!("../../examples/osinsky2023-table1-brownian.toml"),
    ),
    (
        "osinsky2023-table2-ballistic.toml",
        include_str!("../../examples/osinsky2023-table2-ballistic.toml"),
    ),
    (
        "osinsky2023-table3-linear.toml",
        include_str!("../../examples/osinsky2023-table3-linear.toml"),
    ),
    (
        "partmc-emission-dilution.toml",
        include_str!("../../examples/partmc-emission-dilution.toml"),
    ),
    (
        "processes-source-dilution.toml",
        include_str!("../../examples/processes-source-dilution.toml"),
    ),
    (
        "quickstart-constant.toml",
        include_str!("../../examples/quickstart-constant.toml"),
    ),
    (
        "quickstart-golovin.toml",
        include_str!("../../examples/quickstart-golovin.toml"),
    ),
    (
        "soot-free-molecular-physical.toml",
        include_str!("../../examples/soot-free-molecular-physical.toml"),
    ),
];

/// The text of an example by file name, with or without `.toml`.
pub fn get(name: &str) -> Option<(&'static str, &'static str)> {
    let name = name.strip_prefix("examples/").unwrap_or(name);
    EXAMPLES
        .iter()
        .find(|(f, _)| *f == name || f.strip_suffix(".toml") == Some(name))
        .copied()
}

/// The examples' names (file names without `.toml`), as `coagula run NAME` takes them.
pub fn names() -> Vec<&'static str> {
    EXAMPLES
        .iter()
        .map(|(f, _)| f.strip_suffix(".toml").unwrap_or(f))
        .collect()
}
