//! `coagula run`: load and check a scenario, open every output, run the replicas, and
//! write the table, CSV, JSON and plot.

use crate::output::{self, Sink};
use crate::plans::{label, points, resolve};
use crate::scenario;
use crate::{ensemble, plot, runner};
use std::io::Write;

/// The flags of `coagula run` that override scenario values.
pub struct Flags {
    /// `--scheme`.
    pub scheme: Option<String>,
    /// `--particles`.
    pub particles: Option<u64>,
    /// `--m` (2^m particles).
    pub m: Option<u32>,
    /// `--dt`.
    pub dt: Option<f64>,
    /// `--points`.
    pub points: Option<String>,
    /// `--replicas`.
    pub replicas: Option<u64>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--threads`.
    pub threads: Option<u64>,
}

/// `coagula run` with its flags as overrides after the `--set` ones.
pub fn command(
    scenario: Option<&str>,
    mut ov: Vec<(String, toml::Value)>,
    f: Flags,
    steps: Option<u32>,
    outputs: Outputs,
) -> Result<(), String> {
    let int = |n: u64, flag: &str| {
        i64::try_from(n)
            .map(toml::Value::Integer)
            .map_err(|_| format!("{flag} {n} is too large"))
    };
    let mut put = |k: &str, v: toml::Value| ov.push((k.to_string(), v));
    if let Some(s) = f.scheme {
        put("scheme.name", toml::Value::String(s));
    }
    if let Some(m) = f.m {
        put("initial.particles", toml::Value::Integer(1i64 << m));
    }
    if let Some(n) = f.particles {
        put("initial.particles", int(n, "--particles")?);
    }
    if let Some(dt) = f.dt {
        put("scheme.dt", toml::Value::Float(dt));
    }
    if let Some(p) = f.points {
        put("scheme.points", toml::Value::String(p));
    }
    if let Some(r) = f.replicas {
        put("run.replicas", int(r, "--replicas")?);
    }
    if let Some(sd) = f.seed {
        // TOML integers are i64: clap keeps the seed below 2^63
        put("run.seed", int(sd, "--seed")?);
    }
    if let Some(t) = f.threads {
        put("run.threads", int(t, "--threads")?);
    }
    run(scenario, ov, steps, outputs)
}

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

/// `coagula run`.
pub fn run(
    scenario: Option<&str>,
    overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
    out: Outputs,
) -> Result<(), String> {
    // a Langevin first-hit kernel scenario (no population: its own runner)
    let (name, text) = resolve(scenario)?;
    if crate::scenario::is_first_hits(&text) {
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
    let mut points = points(scenario, overrides, steps)?;
    // the size classes are recorded for the size-distribution panel of a plot only
    if out.plot.is_none() {
        for (_, p) in points.iter_mut() {
            p.classes.clear();
        }
    }
    // (the scenario check bounds replicas x times x observables; the classes add columns)
    for (_, p) in &points {
        let kept = p
            .replicas
            .saturating_mul(p.times.len() as u64)
            .saturating_mul(p.columns() as u64);
        if kept > 1 << 25 {
            return Err(format!(
                "--plot: {} replicas x {} times x {} values (observables and size classes): more than 2^25 values to keep; give fewer output.classes, times or replicas",
                p.replicas,
                p.times.len(),
                p.columns()
            ));
        }
    }
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
                for w in &plan.warnings {
                    println!("warning: {w}");
                }
            }
        }
        return Ok(());
    }
    if root {
        for w in points.iter().flat_map(|(_, p)| &p.warnings) {
            eprintln!("warning: {w}");
        }
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
    // a failed write names its destination (`--csv /dev/full: No space left on device`)
    let named = |flag: &str, sink: &Sink, e: String| match sink {
        Sink::File(p, _) => format!("{flag} {p}: {e}"),
        Sink::Stdout => format!("{flag} -: {e}"),
    };
    if let Some(sink) = csv.as_mut() {
        let r = if sweep {
            output::csv_sweep(&runs, &mut *sink.writer())
        } else {
            output::csv(&plans[0], &done.outcomes[0], &mut *sink.writer())
        };
        r.map_err(|e| named("--csv", sink, e))?;
        if let Sink::File(p, _) = sink {
            writeln!(table, "wrote {p}").map_err(io)?;
        }
    }
    if let Some(sink) = json.as_mut() {
        let r = if sweep {
            output::json_sweep(&runs, &mut *sink.writer())
        } else {
            output::json(&plans[0], &done.outcomes[0], &mut *sink.writer())
        };
        r.map_err(|e| named("--json", sink, e))?;
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
