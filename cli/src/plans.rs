//! The plans a command runs: a scenario resolved (a file, a built-in example, the
//! default), loaded with the command line's overrides, its sweep expanded.

use crate::examples;
use crate::scenario::{self, DEFAULT_NAME, DEFAULT_SCENARIO, Source};
use coagula_core::scheme::facade::Law;

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
    let (name, text) = resolve(scenario)?;
    let plan = load_plan(&name, &text, overrides, steps)?;
    if plan.scenario.sweep.is_some() {
        return Err("a [sweep] table runs only with coagula run".into());
    }
    Ok(plan)
}

fn load_plan(
    name: &str,
    text: &str,
    mut overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
) -> Result<scenario::Plan, String> {
    let load = |ov: &[(String, toml::Value)]| {
        scenario::load(&Source {
            name,
            text,
            overrides: ov,
            drops: &[],
        })
        .map_err(|e| e.to_string())
    };
    let plan = load(&overrides)?;
    match steps {
        None => Ok(plan),
        Some(p) => {
            if plan.scheme.law != Law::TimeStepped {
                return Err(format!(
                    "--steps {p}: scheme {} is event-driven and has no time step",
                    plan.scheme.name
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
    let (name, text) = resolve(scenario)?;
    points_of(&name, &text, overrides, steps)
}

/// [`points`] of a scenario given as text (`name` says where it came from in errors):
/// what Python's `coagula.run` calls with a scenario built from a dict.
pub fn points_of(
    name: &str,
    text: &str,
    overrides: Vec<(String, toml::Value)>,
    steps: Option<u32>,
) -> Result<Vec<Point>, String> {
    let base = load_plan(name, text, overrides.clone(), steps)?;
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
            load_plan(name, text, ov, steps).map_err(|e| format!("sweep point {label}: {e}"))?;
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
