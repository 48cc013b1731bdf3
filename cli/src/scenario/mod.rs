//! Scenario files: what `coagula run SCENARIO.toml` simulates, parsed with serde + toml
//! and checked in full before any work starts.
//!
//! A scenario names a built-in kernel of core's table with its parameters, an optional
//! fragmentation kernel, an initial condition, a scheme of core's registry with its
//! options, output times and observables, and the replicas and seed. The kernel's
//! parameters and the scheme's options are core's (`kernel::builtin`,
//! `scheme::facade::KEYS`): they are checked there, and a mistake gets the message C
//! and Python get. `examples/` holds one scenario per paper experiment and short ones
//! for new users; `examples/README.md` documents every key. Unknown keys and wrong
//! types are errors naming the key and its line; values out of range are errors naming
//! the key, its line and the range.
//!
//! The parts: the format here; the command line's overrides ([`overrides`]); the
//! checks that turn a scenario into a [`Plan`] ([`check`]); the plan ([`plan`]).

mod check;
mod memory;
pub mod overrides;
pub mod plan;
pub mod processes;

pub use overrides::{line_of, parse_override};
pub use plan::{Observable, Plan, Sim};

use serde::{Deserialize, Serialize};
use std::fmt;

/// The built-in default: Lécot et al.'s coagulation–fragmentation test.
pub const DEFAULT_SCENARIO: &str =
    include_str!("../../../examples/lecot2019-coagulation-fragmentation.toml");
/// Its name in messages.
pub const DEFAULT_NAME: &str =
    "built-in default (examples/lecot2019-coagulation-fragmentation.toml)";

/// A scenario file as written.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// One line saying what the case is.
    pub title: Option<String>,
    /// The reference (paper, figure, equation), shown with the results.
    pub reference: Option<String>,
    /// The kernel: `kind` (a name of core's table of built-in kernels) and its
    /// parameters by name.
    pub kernel: toml::Table,
    /// Fragmentation (the schemes that break particles).
    pub fragmentation: Option<FragSpec>,
    /// The initial condition.
    pub initial: InitialSpec,
    /// The scheme: `name` (a registry name) and its options by key.
    pub scheme: toml::Table,
    /// Output times and observables.
    pub output: OutputSpec,
    /// A particle source beside coagulation (finite-N schemes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<processes::SourceSpec>,
    /// Removal of particles at a power of size (finite-N schemes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sink: Option<processes::SinkSpec>,
    /// Growth by monomer attachment (finite-N schemes over integer sizes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth: Option<processes::GrowthSpec>,
    /// Replicas, seed, threads.
    #[serde(default)]
    pub run: RunSpec,
    /// A parameter sweep (`coagula run` only): every leaf is an array of values for
    /// the key of its path (`[sweep]` then `initial.particles = [1000, 10000]`), and
    /// the run covers every combination.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<toml::Table>,
}

/// `[fragmentation]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FragSpec {
    /// Which kernel: `binary-uniform` (`F(x, y) = 2λ/(x+y)`, Lécot et al. §4).
    pub kind: FragKind,
    /// λ, the break-up rate per particle (default 1).
    pub rate: Option<f64>,
}

/// Fragmentation kernels.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum FragKind {
    /// Binary break-up into two uniform pieces.
    BinaryUniform,
}

/// Initial conditions.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum InitKind {
    /// Every particle of size `size` (default 1).
    Monodisperse,
    /// `c(x, 0) = (c0/μ) e^{−x/μ}`, μ = `mean`.
    Exponential,
    /// Log-normal number distribution of median `median` and geometric standard
    /// deviation `gsd`.
    Lognormal,
    /// A list of particle sizes (`sizes`).
    Sizes,
    /// Counts of integer sizes (`counts[i − 1]` particles of size i).
    Counts,
}

/// `[initial]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct InitialSpec {
    /// Which distribution.
    pub kind: InitKind,
    /// Number of simulation particles N0 (distributions; mass flow: a power of 2);
    /// `1e6` is an integer too.
    pub particles: Option<f64>,
    /// Monodisperse size (default 1).
    pub size: Option<f64>,
    /// Exponential mean size (default 1).
    pub mean: Option<f64>,
    /// Log-normal median size.
    pub median: Option<f64>,
    /// Log-normal geometric standard deviation (> 1).
    pub gsd: Option<f64>,
    /// Size grid of the integer-size schemes for a continuous distribution: size i
    /// stands for `i · resolution` (default 1/64).
    pub resolution: Option<f64>,
    /// Explicit sizes (`kind = "sizes"`).
    pub sizes: Option<Vec<f64>>,
    /// Explicit counts (`kind = "counts"`).
    pub counts: Option<Vec<u64>>,
    /// Number concentration c0 of the start (default 1; m⁻³ in physical units).
    pub concentration: Option<f64>,
    /// The temperature of every size (temperature-dependent schemes and gases, from a
    /// monodisperse start or counts; default 1).
    pub temperature: Option<f64>,
    /// The temperature of each size of `counts` (instead of `temperature`).
    pub temperatures: Option<Vec<f64>>,
}

/// Spacing of generated output times.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Spacing {
    /// `t-end · i / count`, i = 1..count.
    #[default]
    Linear,
    /// `count` times from `t-start` to `t-end`, equal ratios.
    Log,
}

/// `[output]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct OutputSpec {
    /// Explicit output times (ascending, > 0).
    pub times: Option<Vec<f64>>,
    /// Last output time (with `count`).
    pub t_end: Option<f64>,
    /// First output time of a log spacing.
    pub t_start: Option<f64>,
    /// Number of generated times.
    pub count: Option<u32>,
    /// Linear (default) or log spacing of generated times.
    pub spacing: Option<Spacing>,
    /// Observables: `M<m>` (moment of real order m), `n<k>` (number density of integer
    /// size k), `C(a,b)` (number concentration of sizes in [a, b]), `C[a,b)` (of the
    /// half-open class [a, b)), `gel` (gel-mass estimate), `N` (simulation particles),
    /// or a named observable of the scheme
    /// (`mean-temperature`, `energy`, …).
    pub observables: Vec<String>,
    /// Edges of the size classes `[e_i, e_{i+1})` of the size-distribution panel of
    /// `--plot` (ascending, > 0, 2 to 201 of them); by default log-spaced, 5 a decade,
    /// from the smallest size to past the exact solution's large sizes at the end.
    pub classes: Option<Vec<f64>>,
    /// Log axes in `--plot` (time, and values that span decades); by default on for
    /// log-spaced output times.
    pub log_axes: Option<bool>,
}

/// A count written as an integer or as a real with no fractional part (`1e6`).
fn count<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Count {
        Int(u64),
        Real(f64),
    }
    match Count::deserialize(d)? {
        Count::Int(n) => Ok(n),
        Count::Real(x) if x >= 0.0 && x.fract() == 0.0 && x < 18_446_744_073_709_551_616.0 => {
            Ok(x as u64)
        }
        Count::Real(x) => Err(serde::de::Error::custom(format!(
            "{x} is not a count (a non-negative integer; 1e6 is one)"
        ))),
    }
}

/// `[run]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct RunSpec {
    /// Independent replicas (default 1).
    #[serde(default = "one", deserialize_with = "count")]
    pub replicas: u64,
    /// Seed of the seed policy (0..=2^63 − 1): replica r runs on its substream
    /// `Purpose::Replica(r)` of this seed (replica 0 on `generator(seed, 0)`).
    #[serde(default = "one", deserialize_with = "count")]
    pub seed: u64,
    /// Worker threads (0 = one per core). Results do not depend on it.
    #[serde(default)]
    pub threads: usize,
}

fn one() -> u64 {
    1
}

impl Default for RunSpec {
    fn default() -> Self {
        RunSpec {
            replicas: 1,
            seed: 1,
            threads: 0,
        }
    }
}

/// An error in a scenario: its message, and where it is.
#[derive(Debug)]
pub struct ScenarioError {
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// Where a scenario's text came from and how it was overridden, so that errors can
/// name the file, the key and its line.
pub struct Source<'a> {
    /// File name (or the built-in default's name).
    pub name: &'a str,
    /// The text.
    pub text: &'a str,
    /// Overrides `key = value` from the command line, in order.
    pub overrides: &'a [(String, toml::Value)],
    /// Keys removed before the overrides are applied.
    pub drops: &'a [String],
}

impl Source<'_> {
    /// `file:line: key = …: message` for a key path such as `kernel.a`.
    pub fn at(&self, key: &str, message: impl fmt::Display) -> ScenarioError {
        if self.overrides.iter().any(|(k, _)| k == key) {
            return ScenarioError {
                message: format!("{key} (set on the command line): {message}"),
            };
        }
        let place = match line_of(self.text, key) {
            Some(line) => format!("{}:{line}: ", self.name),
            None => format!("{}: ", self.name),
        };
        ScenarioError {
            message: format!("{place}{key}: {message}"),
        }
    }
}

/// Parses and checks a scenario: syntax, unknown keys and types (with the line), then
/// the overrides, then every value (ranges, combinations, memory).
pub fn load(src: &Source<'_>) -> Result<Plan, ScenarioError> {
    let as_written = |e: toml::de::Error| ScenarioError {
        message: format!("{}: {}", src.name, e.to_string().trim_end()),
    };
    // `source` was the citation's key before it named a particle source
    if let Ok(t) = toml::from_str::<toml::Table>(src.text)
        && let Some(toml::Value::String(_)) = t.get("source")
    {
        return Err(src.at(
            "source",
            "a string: the citation's key is `reference`; `[source]` is a particle source (rate, kind, ...)",
        ));
    }
    if src.overrides.is_empty() && src.drops.is_empty() {
        // syntax, unknown keys and wrong types, with the line
        let scenario: Scenario = toml::from_str(src.text).map_err(as_written)?;
        return check::check(scenario, src);
    }
    let mut table: toml::Table = toml::from_str(src.text).map_err(|e| ScenarioError {
        message: format!("{}: {e}", src.name),
    })?;
    for key in src.drops {
        overrides::remove_key(&mut table, key);
    }
    for (key, value) in src.overrides {
        overrides::set_key(&mut table, key, value.clone())
            .map_err(|m| ScenarioError { message: m })?;
    }
    let scenario = match Scenario::deserialize(table) {
        Ok(s) => s,
        Err(e) => {
            // an error of the file as written keeps its line; else the overrides caused it
            if let Err(raw) = toml::from_str::<Scenario>(src.text) {
                let missing = raw.to_string().contains("missing field");
                if !missing {
                    return Err(as_written(raw));
                }
            }
            return Err(ScenarioError {
                message: format!(
                    "{} with the command line's overrides: {}",
                    src.name,
                    e.to_string().trim_end()
                ),
            });
        }
    };
    check::check(scenario, src)
}

/// Whether a scenario text is a first-hit kernel scenario.
pub fn is_first_hits(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("first-hits"))
}

#[cfg(test)]
mod tests;
