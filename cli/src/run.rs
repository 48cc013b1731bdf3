//! `coagula run`: load and check a scenario, open every output, run the replicas, and
//! write the table, CSV, JSON and plot.

use crate::output::{self, Sink};
use crate::scenario::{self, DEFAULT_NAME, DEFAULT_SCENARIO, Source};
use crate::{ensemble, examples, plot, runner};
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
    /// `--checkpoint DIR`: save every finished block of replicas there, and take the
    /// blocks found there instead of running them again.
    pub checkpoint: Option<String>,
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

/// Loads a scenario with its overrides; `--steps P` sets Δt = t_end / P. A scenario
/// with a sweep is refused: only `coagula run` expands one ([`points`]).
pub fn plan(
    scenario: Option<&str>,
    overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
) -> Result<scenario::Plan, String> {
    let plan = load_plan(scenario, overrides, steps)?;
    if plan.scenario.sweep.is_some() {
        return Err("a [sweep] table runs only with coagula run".into());
    }
    Ok(plan)
}

fn load_plan(
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

/// Most points a sweep may have.
pub const MAX_POINTS: usize = 10_000;

/// A sweep point: the values it sets, and its plan.
pub type Point = (Vec<(String, toml::Value)>, scenario::Plan);

/// The sweep's axes: every leaf of the `[sweep]` table (an array of values) under its
/// dotted path, in the table's order.
fn axes(
    table: &toml::Table,
    prefix: &str,
    out: &mut Vec<(String, Vec<toml::Value>)>,
) -> Result<(), String> {
    for (k, v) in table {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(t) => axes(t, &key, out)?,
            toml::Value::Array(a) if !a.is_empty() => out.push((key, a.clone())),
            toml::Value::Array(_) => return Err(format!("sweep.{key}: an empty list")),
            _ => {
                return Err(format!(
                    "sweep.{key}: a list of values is needed (e.g. {key} = [1, 2])"
                ));
            }
        }
    }
    Ok(())
}

/// The plans to run: one, or one per combination of a sweep's values (the first
/// axis slowest). Every point keeps the scenario's seed. An empty `[sweep]` (`--set
/// sweep={}`) is no sweep.
pub fn points(
    scenario: Option<&str>,
    overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
) -> Result<Vec<Point>, String> {
    let base = load_plan(scenario, overrides.clone(), steps)?;
    let Some(sweep) = base.scenario.sweep.clone() else {
        return Ok(vec![(Vec::new(), base)]);
    };
    let mut ax = Vec::new();
    axes(&sweep, "", &mut ax)?;
    if ax.is_empty() {
        // an empty table (`--set sweep={}`) switches the sweep off
        return Ok(vec![(Vec::new(), base)]);
    }
    // a key and the table it lies in are the same setting
    let clash = |a: &str, b: &str| {
        a == b
            || a.strip_prefix(b).is_some_and(|r| r.starts_with('.'))
            || b.strip_prefix(a).is_some_and(|r| r.starts_with('.'))
    };
    for (key, _) in &ax {
        if let Some((k, _)) = overrides.iter().find(|(k, _)| clash(k, key)) {
            return Err(format!(
                "{key} is swept and {k} is set on the command line: drop one"
            ));
        }
        if steps.is_some() && clash(key, "scheme.dt") {
            return Err(format!(
                "{key} is swept and --steps sets scheme.dt: drop one"
            ));
        }
        if clash(key, "sweep") {
            return Err(format!("sweep.{key}: a sweep cannot set the sweep"));
        }
        if clash(key, "run.threads") {
            return Err(format!(
                "sweep.{key}: threads do not change the results (set run.threads once)"
            ));
        }
    }
    let count = ax
        .iter()
        .try_fold(1usize, |n, (_, v)| n.checked_mul(v.len()))
        .filter(|&n| n <= MAX_POINTS)
        .ok_or_else(|| format!("the sweep has more than {MAX_POINTS} points"))?;
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        // mixed radix, the last axis fastest
        let mut rest = i;
        let mut set = vec![(String::new(), toml::Value::Boolean(false)); ax.len()];
        for (slot, (key, values)) in set.iter_mut().zip(&ax).rev() {
            *slot = (key.clone(), values[rest % values.len()].clone());
            rest /= values.len();
        }
        let mut ov = overrides.clone();
        ov.extend(set.iter().cloned());
        let label = label(&set);
        let plan =
            load_plan(scenario, ov, steps).map_err(|e| format!("sweep point {label}: {e}"))?;
        out.push((set, plan));
    }
    Ok(out)
}

/// `key = value, ...` of a sweep point.
pub fn label(set: &[(String, toml::Value)]) -> String {
    set.iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
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
        if !overrides.is_empty()
            || steps.is_some()
            || out.csv.is_some()
            || out.plot.is_some()
            || out.checkpoint.is_some()
        {
            return Err(format!(
                "{name}: a first-hit kernel scenario takes no --set, --steps, --csv, --plot or --checkpoint (edit the file; --json - prints JSON)"
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
    let points = points(scenario, overrides, steps)?;
    let sweep = points.len() > 1 || !points[0].0.is_empty();
    // what every rank finds alike is checked before MPI starts
    if out.csv.as_deref() == Some("-") && out.json.as_deref() == Some("-") {
        return Err("--csv - and --json -: only one of them can go to standard output".into());
    }
    if sweep && out.plot.is_some() {
        return Err("--plot draws one run: a sweep writes --csv or --json".into());
    }
    if sweep && out.csv.is_some() {
        output::check_sweep_columns(&points)?;
    }
    let world = ensemble::world()?;
    let root = world.rank() == 0;
    // every output is opened (by rank 0) before the work starts; a failure there ends
    // the whole job (the other ranks would wait for rank 0)
    let opened = || -> Result<(Option<Sink>, Option<Sink>), String> {
        if !root {
            return Ok((None, None));
        }
        let csv = out
            .csv
            .as_deref()
            .map(|p| Sink::open("--csv", p))
            .transpose()?;
        let json = out
            .json
            .as_deref()
            .map(|p| Sink::open("--json", p))
            .transpose()?;
        if let Some(p) = &out.plot {
            plot::check(p)?;
        }
        Ok((csv, json))
    };
    let (mut csv, mut json) = opened().map_err(|e| world.fatal(e))?;
    if out.check {
        if root {
            for (set, plan) in &points {
                if sweep {
                    println!("sweep point {}:", label(set));
                }
                println!(
                    "{}\n\nscenario checked: {} output times, {} observables; not run (--check)",
                    output::describe(plan),
                    plan.times.len(),
                    plan.observables.len()
                );
            }
        }
        return Ok(());
    }
    let to_stdout =
        csv.as_ref().is_some_and(Sink::is_stdout) || json.as_ref().is_some_and(Sink::is_stdout);
    let plans: Vec<scenario::Plan> = points.iter().map(|(_, p)| p.clone()).collect();
    let dir = out.checkpoint.as_deref().map(std::path::Path::new);
    let Some(done) = ensemble::run(&plans, &*world, dir, out.quiet)? else {
        return Ok(());
    };
    let mut table: Box<dyn Write> = if to_stdout {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    };
    let io = |e: std::io::Error| e.to_string();
    for ((set, plan), outcome) in points.iter().zip(&done.outcomes) {
        if sweep {
            writeln!(table, "=== sweep point {} ===", label(set)).map_err(io)?;
        }
        output::table(plan, outcome, out.rows, &mut *table).map_err(io)?;
        if sweep {
            writeln!(table).map_err(io)?;
        }
    }
    if world.size() > 1 || done.resumed > 0 {
        writeln!(
            table,
            "{} blocks of up to {} replicas over {} processes; {} resumed from checkpoints",
            done.blocks,
            runner::BLOCK,
            world.size(),
            done.resumed
        )
        .map_err(io)?;
    }
    let runs: Vec<output::SweepRun<'_>> = points
        .iter()
        .zip(&done.outcomes)
        .map(|((set, plan), o)| (&set[..], plan, o))
        .collect();
    if let Some(sink) = csv.as_mut() {
        if sweep {
            output::csv_sweep(&runs, &mut *sink.writer())?;
        } else {
            output::csv(&plans[0], &done.outcomes[0], &mut *sink.writer())?;
        }
        if let Sink::File(p, _) = sink {
            writeln!(table, "wrote {p}").map_err(io)?;
        }
    }
    if let Some(sink) = json.as_mut() {
        if sweep {
            output::json_sweep(&runs, &mut *sink.writer())?;
        } else {
            output::json(&plans[0], &done.outcomes[0], &mut *sink.writer())?;
        }
        if let Sink::File(p, _) = sink {
            writeln!(table, "wrote {p}").map_err(io)?;
        }
    }
    if let Some(p) = &out.plot {
        plot::run(p, &plans[0], &done.outcomes[0])?;
        writeln!(table, "wrote {p}").map_err(io)?;
    }
    Ok(())
}
