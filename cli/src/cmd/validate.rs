//! `coagula validate`: the reproduction cases, as data (`cli/cases/validate.toml`:
//! scenario + overrides + reference + tolerance), run through the same scenario runner
//! as `coagula run`.

pub use crate::cases::Case;
use crate::examples;
use crate::runner::{self, Outcome};
use crate::scenario::{self, Observable, Plan, Source};
use coagula_core::exact::ClosedMoments;
use coagula_core::kernel::Fragmentation;
use coagula_core::observe::{Replicas, TEST_ALPHA, student_t_threshold};
use coagula_core::scheme::facade::{InitKind, Model, ModelKind};
use coagula_core::scheme::registry::SCHEMES;
use rayon::prelude::*;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The cases file, built in.
pub const CASES: &str = include_str!("../../cases/validate.toml");

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CasesFile {
    case: Vec<CaseSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseSpec {
    name: String,
    scenario: String,
    #[serde(default)]
    schemes: Vec<String>,
    #[serde(default = "both_modes")]
    modes: Vec<String>,
    #[serde(default)]
    set: BTreeMap<String, toml::Value>,
    #[serde(default)]
    quick: BTreeMap<String, toml::Value>,
    #[serde(default)]
    full: BTreeMap<String, toml::Value>,
    #[serde(default)]
    drop: Vec<String>,
    check: Vec<Check>,
}

fn both_modes() -> Vec<String> {
    vec!["quick".into(), "full".into()]
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Check {
    observable: String,
    t: Option<f64>,
    #[serde(default)]
    metric: Metric,
    reference: Reference,
    tolerance: Tolerance,
}

#[derive(Clone, Copy, Default, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum Metric {
    #[default]
    Mean,
    MeanAbsError,
    Events,
}

#[derive(Clone, Deserialize)]
#[serde(untagged)]
enum Reference {
    Named(String),
    Value(f64),
    Run { run: BTreeMap<String, toml::Value> },
}

#[derive(Clone, Deserialize)]
#[serde(untagged)]
enum Tolerance {
    Named(String),
    Absolute { absolute: f64 },
    Relative { relative: f64 },
}

/// Runs every case (a subset with `quick`; those whose name starts with `only`), prints
/// a table or JSON, and returns whether all passed; an error for a malformed cases
/// file or an `only` that selects nothing.
pub fn run(quick: bool, json: bool, only: Option<&str>) -> Result<bool, String> {
    let start = std::time::Instant::now();
    let cases = evaluate(CASES, quick, only)?;
    let all = cases.iter().all(|c| c.pass);
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&cases).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "{:<52} {:<70} {:>13} {:>13} {:>10} {:>10} {:>5}",
            "case", "quantity", "reference", "ours", "error", "tolerance", "pass"
        );
        for c in &cases {
            println!(
                "{:<52} {:<70} {:>13.6e} {:>13.6e} {:>10.2e} {:>10.2e} {:>5}",
                c.case,
                c.quantity,
                c.reference,
                c.value,
                c.error,
                c.tolerance,
                if c.pass { "pass" } else { "FAIL" }
            );
        }
        let failed = cases.iter().filter(|c| !c.pass).count();
        println!(
            "\nvalidate: {} passed, {failed} failed ({:.0} s)",
            cases.len() - failed,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(all)
}

/// Runs the cases of a cases text.
pub fn evaluate(text: &str, quick: bool, only: Option<&str>) -> Result<Vec<Case>, String> {
    let file: CasesFile = toml::from_str(text).map_err(|e| format!("validate cases: {e}"))?;
    let mode = if quick { "quick" } else { "full" };
    let mut out = Vec::new();
    let selected = |name: &str| only.is_none_or(|p| name.starts_with(p));
    // cases computed in code (a trajectory batch, a scheme with per-size temperatures
    // are not population scenarios): `maftei2016/...`, `osinsky2023/temperature/...`
    let coded = |prefix: &str| only.is_none_or(|p| prefix.starts_with(p) || p.starts_with(prefix));
    const LANGEVIN: &str = "maftei2016/";
    const TEMPERATURE: &str = "osinsky2023/temperature/";
    let langevin = coded(LANGEVIN);
    let temperature = coded(TEMPERATURE);
    const DSMC: &str = "osinsky2023/dsmc/";
    let dsmc = coded(DSMC);
    if !langevin
        && !temperature
        && !dsmc
        && !file
            .case
            .iter()
            .any(|c| selected(&c.name) && c.modes.iter().any(|m| m == mode))
    {
        return Err(format!(
            "no {mode} case starts with {:?}",
            only.unwrap_or_default()
        ));
    }
    // the scenario cases, run side by side (many run one replica on one thread; the
    // results do not depend on the threads, and come back in the file's order)
    let mut jobs = Vec::new();
    for spec in &file.case {
        if !spec.modes.iter().any(|m| m == mode) || !selected(&spec.name) {
            continue;
        }
        let schemes: Vec<Option<String>> = if spec.schemes.is_empty() {
            vec![None]
        } else {
            spec.schemes
                .iter()
                .flat_map(|s| {
                    if s == "all-counts" {
                        SCHEMES
                            .iter()
                            .filter(|i| {
                                i.inits.contains(&InitKind::Counts)
                                    && i.model == ModelKind::Coagulation
                            })
                            .map(|i| Some(i.name.to_string()))
                            .collect::<Vec<_>>()
                    } else {
                        vec![Some(s.clone())]
                    }
                })
                .collect()
        };
        for scheme in schemes {
            let name = match &scheme {
                Some(s) => format!("{}/{s}", spec.name),
                None => spec.name.clone(),
            };
            let mut overrides: Vec<(String, toml::Value)> = spec
                .set
                .iter()
                .chain(if quick { &spec.quick } else { &spec.full })
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            if let Some(s) = &scheme {
                overrides.push(("scheme.name".into(), toml::Value::String(s.clone())));
            }
            jobs.push((name, spec, overrides));
        }
    }
    // (and beside them the cases computed in code)
    let (results, coded) = rayon::join(
        || {
            jobs.par_iter()
                .map(|(name, spec, overrides)| {
                    let mut cases = Vec::new();
                    run_case(name, spec, overrides, &mut cases).map(|()| cases)
                })
                .collect::<Vec<Result<Vec<Case>, String>>>()
        },
        || -> Result<Vec<Case>, String> {
            let mut cases = Vec::new();
            if langevin {
                cases.extend(crate::reproduce::maftei2016::cases(quick)?);
            }
            if temperature {
                cases.extend(crate::reproduce::osinsky2023::cases(quick)?);
            }
            if dsmc {
                cases.extend(crate::reproduce::osinsky2023::dsmc_cases(quick)?);
            }
            Ok(cases)
        },
    );
    for r in results {
        out.extend(r?);
    }
    let mut cases = coded?;
    if langevin || temperature || dsmc {
        cases.retain(|c| selected(&c.case));
        if cases.is_empty() && out.is_empty() {
            return Err(format!(
                "no {mode} case starts with {:?}",
                only.unwrap_or_default()
            ));
        }
        out.extend(cases);
    }
    Ok(out)
}

fn plan_of(spec: &CaseSpec, overrides: &[(String, toml::Value)]) -> Result<Plan, String> {
    let (file, text) = examples::get(&spec.scenario)
        .ok_or_else(|| format!("validate: no example scenario {}", spec.scenario))?;
    let src = Source {
        name: file,
        text,
        overrides,
        drops: &spec.drop,
    };
    scenario::load(&src).map_err(|e| e.to_string())
}

fn run_case(
    name: &str,
    spec: &CaseSpec,
    overrides: &[(String, toml::Value)],
    out: &mut Vec<Case>,
) -> Result<(), String> {
    let plan = plan_of(spec, overrides).map_err(|e| format!("case {name}: {e}"))?;
    let outcome = runner::run(&plan, true).map_err(|e| format!("case {name}: {e}"))?;
    for check in &spec.check {
        out.push(evaluate_check(
            name, spec, overrides, &plan, &outcome, check,
        )?);
    }
    Ok(())
}

/// The replicas' values of a check's metric.
fn metric(plan: &Plan, out: &Outcome, check: &Check, name: &str) -> Result<Replicas, String> {
    let o = Observable::parse(&check.observable).map_err(|e| format!("case {name}: {e}"))?;
    let j = plan
        .observables
        .iter()
        .position(|x| *x == o)
        .ok_or_else(|| format!("case {name}: observable {} is not an output", o.name()))?;
    let mut r = Replicas::new();
    match check.metric {
        Metric::Mean => {
            let i = time_index(plan, check, name)?;
            for v in &out.values {
                r.push(v[i][j]);
            }
        }
        Metric::MeanAbsError => {
            let e = plan
                .exact
                .ok_or_else(|| format!("case {name}: mean-abs-error needs an exact solution"))?;
            for v in &out.values {
                let mut s = 0.0;
                for (i, &t) in plan.times.iter().enumerate() {
                    let x = e
                        .value(&o, t)
                        .ok_or_else(|| format!("case {name}: no exact {} at t = {t}", o.name()))?;
                    s += (v[i][j] - x).abs();
                }
                r.push(s / plan.times.len() as f64);
            }
        }
        Metric::Events => {
            for &e in &out.events {
                r.push(e as f64);
            }
        }
    }
    Ok(r)
}

fn time_index(plan: &Plan, check: &Check, name: &str) -> Result<usize, String> {
    let t = check
        .t
        .ok_or_else(|| format!("case {name}: the check of {} needs t", check.observable))?;
    plan.times
        .iter()
        .position(|&x| (x - t).abs() <= 1e-12 * t.abs().max(1.0))
        .ok_or_else(|| format!("case {name}: t = {t} is not an output time"))
}

/// The moment equations stepped by explicit Euler at the plan's Δt to time t, for the
/// kernels whose moments close (constant and additive, with binary uniform
/// fragmentation for the constant kernel): the expectation of a time-driven scheme.
fn euler(plan: &Plan, order: f64, t: f64) -> Option<f64> {
    let e = plan.exact?;
    if order.fract() != 0.0 || !(0.0..=3.0).contains(&order) {
        return None;
    }
    let mut m = [0.0; 4];
    for (k, v) in m.iter_mut().enumerate() {
        *v = e.value(&Observable::Moment(k as f64), 0.0)?;
    }
    let b = plan.coefficient;
    let Model::Coagulation { fragmentation, .. } = plan.model else {
        return None;
    };
    let closed = match (plan.kernel_name.as_str(), fragmentation) {
        ("constant", Fragmentation::None) => ClosedMoments::Constant { b, lambda: 0.0 },
        ("constant", Fragmentation::BinaryUniform(f)) => ClosedMoments::Constant {
            b,
            lambda: f.lambda(),
        },
        ("additive", Fragmentation::None) => ClosedMoments::Additive { b },
        _ => return None,
    };
    let h = plan.options.dt();
    let m = closed.euler(m, h, (t / h).round() as u64);
    Some(m[order as usize])
}

fn evaluate_check(
    name: &str,
    spec: &CaseSpec,
    overrides: &[(String, toml::Value)],
    plan: &Plan,
    out: &Outcome,
    check: &Check,
) -> Result<Case, String> {
    let r = metric(plan, out, check, name)?;
    let value = r.mean();
    let o = Observable::parse(&check.observable).map_err(|e| format!("case {name}: {e}"))?;
    let order = match o {
        Observable::Moment(m) => Some(m),
        _ => None,
    };
    let exact_at = |t: f64| plan.exact.and_then(|e| e.value(&o, t));
    let (reference, ref_label) = match &check.reference {
        Reference::Value(v) => (*v, "paper".to_string()),
        Reference::Named(n) if n == "exact" => {
            let t = check
                .t
                .ok_or_else(|| format!("case {name}: exact needs t"))?;
            (
                exact_at(t).ok_or_else(|| format!("case {name}: no exact {} known", o.name()))?,
                "exact".into(),
            )
        }
        Reference::Named(n) if n == "euler" => {
            let t = check
                .t
                .ok_or_else(|| format!("case {name}: euler needs t"))?;
            (
                order
                    .and_then(|m| euler(plan, m, t))
                    .ok_or_else(|| format!("case {name}: no Euler expectation of {}", o.name()))?,
                format!("Euler expectation at Δt = {}", plan.options.dt()),
            )
        }
        Reference::Named(n) if n == "sectional" => {
            let t = check
                .t
                .ok_or_else(|| format!("case {name}: sectional needs t"))?;
            (
                super::validate_sectional::reference(plan, &o, t)
                    .map_err(|e| format!("case {name}: {e}"))?,
                "sectional (fixed pivot)".into(),
            )
        }
        Reference::Named(n) if n == "discrete" => {
            let t = check
                .t
                .ok_or_else(|| format!("case {name}: discrete needs t"))?;
            (
                super::validate_discrete::reference(plan, &o, t)
                    .map_err(|e| format!("case {name}: {e}"))?,
                "discrete Smoluchowski equations".into(),
            )
        }
        Reference::Named(n) => return Err(format!("case {name}: unknown reference {n:?}")),
        Reference::Run { run } => {
            let mut ov = overrides.to_vec();
            ov.extend(run.iter().map(|(k, v)| (k.clone(), v.clone())));
            let p2 = plan_of(spec, &ov).map_err(|e| format!("case {name} (reference run): {e}"))?;
            let o2 =
                runner::run(&p2, true).map_err(|e| format!("case {name} (reference run): {e}"))?;
            let r2 = metric(&p2, &o2, check, name)?;
            let label: Vec<String> = run.iter().map(|(k, v)| format!("{k}={v}")).collect();
            (r2.mean(), format!("rerun with {}", label.join(", ")))
        }
    };
    let z = if r.count() >= 2 {
        student_t_threshold(TEST_ALPHA, r.count() - 1)
    } else {
        f64::NAN
    };
    let need_replicas = |what: &str| -> Result<(), String> {
        if r.count() < 2 {
            Err(format!(
                "case {name}: tolerance {what} needs at least 2 replicas"
            ))
        } else {
            Ok(())
        }
    };
    let what = match check.metric {
        Metric::Mean => format!("{} at t = {}", o.name(), check.t.unwrap_or(f64::NAN)),
        Metric::MeanAbsError => {
            format!("mean |{} error| over {} times", o.name(), plan.times.len())
        }
        Metric::Events => "events to the last time".into(),
    };
    let (tolerance, pass, tol_label) = match &check.tolerance {
        Tolerance::Named(n) if n == "replicas" => {
            need_replicas(n)?;
            let tol = z * r.std_error();
            (tol, (value - reference).abs() <= tol, format!("{z:.2} SE"))
        }
        Tolerance::Named(n) if n == "replicas+euler" => {
            need_replicas(n)?;
            let t = check.t.ok_or_else(|| format!("case {name}: needs t"))?;
            let bias = order
                .and_then(|m| Some((euler(plan, m, t)? - exact_at(t)?).abs()))
                .ok_or_else(|| format!("case {name}: no Euler bias of {}", o.name()))?;
            let tol = bias + z * r.std_error() + 1e-12 * reference.abs();
            (
                tol,
                (value - reference).abs() <= tol,
                format!("Euler bias {bias:.1e} + {z:.2} SE"),
            )
        }
        Tolerance::Named(n) if n == "below" => (0.0, value < reference, "ours < reference".into()),
        Tolerance::Named(n) => return Err(format!("case {name}: unknown tolerance {n:?}")),
        Tolerance::Absolute { absolute } => (
            *absolute,
            (value - reference).abs() <= *absolute,
            format!("±{absolute:.1e}"),
        ),
        Tolerance::Relative { relative } => {
            let tol = relative * reference.abs();
            (
                tol,
                (value - reference).abs() <= tol,
                format!("±{relative} relative"),
            )
        }
    };
    Ok(Case {
        case: name.to_string(),
        quantity: format!(
            "{what}, {} replicas (ref: {ref_label}; tol {tol_label})",
            plan.replicas
        ),
        reference,
        value,
        error: (value - reference).abs(),
        tolerance,
        pass,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every case of the built-in file parses and names scenarios, observables and
    /// output times that exist (in both modes), without running anything.
    #[test]
    fn cases_are_well_formed() {
        let file: CasesFile = toml::from_str(CASES).unwrap();
        assert!(file.case.len() >= 10);
        for spec in &file.case {
            let prefix = spec.name.split('/').next().unwrap();
            assert!(
                [
                    "lecot2019",
                    "osinsky2023",
                    "eibeck2000",
                    "maftei2016",
                    "exact",
                    "processes",
                    "blocks"
                ]
                .contains(&prefix),
                "{}",
                spec.name
            );
            for quick in [true, false] {
                let mode = if quick { "quick" } else { "full" };
                if !spec.modes.iter().any(|m| m == mode) {
                    continue;
                }
                // each listed scheme as the run sets it ("all-counts": one of them)
                let schemes: Vec<Option<String>> = if spec.schemes.is_empty() {
                    vec![None]
                } else {
                    spec.schemes
                        .iter()
                        .map(|s| {
                            Some(if s == "all-counts" {
                                "lowrank".into()
                            } else {
                                s.clone()
                            })
                        })
                        .collect()
                };
                for scheme in schemes {
                    let mut ov: Vec<(String, toml::Value)> = spec
                        .set
                        .iter()
                        .chain(if quick { &spec.quick } else { &spec.full })
                        .map(|(k, v)| (k.clone(), v.clone()))
                        .collect();
                    if let Some(s) = scheme {
                        ov.push(("scheme.name".into(), toml::Value::String(s)));
                    }
                    let plan = plan_of(spec, &ov).unwrap_or_else(|e| panic!("{}: {e}", spec.name));
                    for c in &spec.check {
                        let o = Observable::parse(&c.observable).unwrap();
                        assert!(
                            plan.observables.contains(&o),
                            "{}: {}",
                            spec.name,
                            c.observable
                        );
                        if c.metric == Metric::Mean {
                            time_index(&plan, c, &spec.name).unwrap();
                        }
                    }
                }
            }
        }
    }

    /// Euler's recurrence for the constant kernel's M2 is linear: M2 = 1 + n h exactly.
    #[test]
    fn euler_of_the_constant_kernel() {
        let ov = vec![("scheme.dt".to_string(), toml::Value::Float(0.01))];
        let (file, text) = examples::get("lecot2019-coagulation-fragmentation").unwrap();
        let drops = vec!["fragmentation".to_string()];
        let plan = scenario::load(&Source {
            name: file,
            text,
            overrides: &ov,
            drops: &drops,
        })
        .unwrap();
        assert!((euler(&plan, 2.0, 1.0).unwrap() - 2.0).abs() < 1e-12);
        assert!((euler(&plan, 1.0, 1.0).unwrap() - 1.0).abs() < 1e-15);
        // and converges to the exact M0 = 1/(1 + t/2) as Δt → 0, at first order
        let e = |dt: f64| {
            let ov = vec![("scheme.dt".to_string(), toml::Value::Float(dt))];
            let p = scenario::load(&Source {
                name: file,
                text,
                overrides: &ov,
                drops: &drops,
            })
            .unwrap();
            euler(&p, 0.0, 1.0).unwrap() - 1.0 / 1.5
        };
        let ratio = e(0.01) / e(0.005);
        assert!((ratio - 2.0).abs() < 0.05, "{ratio}");
    }

    /// `--only` selects by name prefix, and one that selects nothing is an error
    /// (not an empty, passing run).
    #[test]
    fn only_selects_by_prefix_and_refuses_an_empty_selection() {
        let e = evaluate(CASES, true, Some("no-such-source/")).unwrap_err();
        assert!(e.contains("no quick case"), "{e}");
        // a full-only prefix selects nothing in quick mode
        let e = evaluate(CASES, true, Some("eibeck2000/multiplicative-gel")).unwrap_err();
        assert!(e.contains("no quick case"), "{e}");
    }
}
