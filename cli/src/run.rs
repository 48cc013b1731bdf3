//! `coagula run`: load and check a scenario, open every output, run the replicas, and
//! write the table, CSV, JSON and plot.

use crate::output::{self, Sink};
use crate::scenario::{self, DEFAULT_NAME, DEFAULT_SCENARIO, Source};
use crate::{examples, plot, runner};
use coagula_core::scheme::registry::SchemeId;
use std::io::Write;

/// Where the results go.
pub struct Outputs {
    /// `--csv`.
    pub csv: Option<String>,
    /// `--json`.
    pub json: Option<String>,
    /// `--plot`.
    pub plot: Option<String>,
    /// Rows of the terminal table.
    pub rows: usize,
    /// No progress bar.
    pub quiet: bool,
    /// Check only: print the set-up and stop.
    pub check: bool,
}

/// The scenario's name and text: a file, else a built-in example, else the default.
pub fn resolve(scenario: Option<&str>) -> Result<(String, String), String> {
    match scenario {
        None => Ok((DEFAULT_NAME.into(), DEFAULT_SCENARIO.into())),
        Some(p) => {
            let path = std::path::Path::new(p);
            if path.exists() {
                let text = std::fs::read_to_string(path).map_err(|e| format!("{p}: {e}"))?;
                Ok((p.to_string(), text))
            } else if let Some((file, text)) = examples::get(p) {
                Ok((format!("example {file}"), text.to_string()))
            } else {
                Err(format!(
                    "{p}: no such file, and no built-in example of that name (coagula examples lists them)"
                ))
            }
        }
    }
}

/// Loads a scenario with its overrides; `--steps P` sets Δt = t_end / P.
pub fn plan(
    scenario: Option<&str>,
    mut overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
) -> Result<scenario::Plan, String> {
    let (name, text) = resolve(scenario)?;
    let load = |ov: &[(String, toml::Value)]| {
        scenario::load(&Source {
            name: &name,
            text: &text,
            overrides: ov,
            drops: &[],
        })
        .map_err(|e| e.to_string())
    };
    let plan = load(&overrides)?;
    match steps {
        None => Ok(plan),
        Some(p) => {
            if plan.scheme != SchemeId::MassFlow {
                return Err(format!(
                    "--steps {p}: scheme {} is event-driven and has no time step",
                    plan.scheme.name()
                ));
            }
            let t_end = *plan.times.last().expect("times");
            overrides.push(("scheme.dt".into(), toml::Value::Float(t_end / f64::from(p))));
            load(&overrides).map_err(|e| format!("--steps {p}: {e}"))
        }
    }
}

/// `coagula run`.
pub fn run(
    scenario: Option<&str>,
    overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
    out: Outputs,
) -> Result<(), String> {
    // a Langevin first-hit kernel scenario (no population: its own runner)
    let (name, text) = resolve(scenario)?;
    if crate::reproduce::maftei2016::is_first_hits(&text) {
        if !overrides.is_empty() || steps.is_some() || out.csv.is_some() || out.plot.is_some() {
            return Err(format!(
                "{name}: a first-hit kernel scenario takes no --set, --steps, --csv or --plot (edit the file; --json - prints JSON)"
            ));
        }
        if out.json.as_deref().is_some_and(|p| p != "-") {
            return Err(format!(
                "{name}: --json goes to standard output (-) for a first-hit kernel scenario"
            ));
        }
        if out.check {
            return Ok(());
        }
        return crate::reproduce::maftei2016::first_hits_scenario(&name, &text, out.json.is_some());
    }
    let plan = plan(scenario, overrides, steps)?;
    // every output is opened before the work starts
    if out.csv.as_deref() == Some("-") && out.json.as_deref() == Some("-") {
        return Err("--csv - and --json -: only one of them can go to standard output".into());
    }
    let mut csv = match &out.csv {
        Some(p) => Some(Sink::open("--csv", p)?),
        None => None,
    };
    let mut json = match &out.json {
        Some(p) => Some(Sink::open("--json", p)?),
        None => None,
    };
    if let Some(p) = &out.plot {
        plot::check(p)?;
    }
    if out.check {
        println!(
            "{}\n\nscenario checked: {} output times, {} observables; not run (--check)",
            output::describe(&plan),
            plan.times.len(),
            plan.observables.len()
        );
        return Ok(());
    }
    let to_stdout =
        csv.as_ref().is_some_and(Sink::is_stdout) || json.as_ref().is_some_and(Sink::is_stdout);
    let outcome = runner::run(&plan, out.quiet)?;
    let mut table: Box<dyn Write> = if to_stdout {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    };
    let io = |e: std::io::Error| e.to_string();
    output::table(&plan, &outcome, out.rows, &mut *table).map_err(io)?;
    if let Some(sink) = csv.as_mut() {
        output::csv(&plan, &outcome, &mut *sink.writer())?;
        if let Sink::File(p, _) = sink {
            writeln!(table, "wrote {p}").map_err(io)?;
        }
    }
    if let Some(sink) = json.as_mut() {
        output::json(&plan, &outcome, &mut *sink.writer())?;
        if let Sink::File(p, _) = sink {
            writeln!(table, "wrote {p}").map_err(io)?;
        }
    }
    if let Some(p) = &out.plot {
        plot::run(p, &plan, &outcome)?;
        writeln!(table, "wrote {p}").map_err(io)?;
    }
    Ok(())
}
