//! What `coagula run` writes: a table with a legend on the terminal, CSV and JSON with
//! every output time.

use crate::runner::Outcome;
use crate::scenario::Plan;
use coagula_core::scheme::facade::Law;
use serde::Serialize;
use std::io::Write;

/// An output destination: a file, or standard output for `-`.
pub enum Sink {
    /// Standard output.
    Stdout,
    /// A file, created before the run.
    File(String, std::fs::File),
}

impl Sink {
    /// Opens (creates) the destination now, so a bad path fails before any work.
    pub fn open(flag: &str, path: &str) -> Result<Self, String> {
        if path == "-" {
            Ok(Sink::Stdout)
        } else {
            std::fs::File::create(path)
                .map(|f| Sink::File(path.to_string(), f))
                .map_err(|e| format!("{flag} {path}: {e}"))
        }
    }

    /// The writer.
    pub fn writer(&mut self) -> Box<dyn Write + '_> {
        match self {
            Sink::Stdout => Box::new(std::io::stdout()),
            Sink::File(_, f) => Box::new(f),
        }
    }

    /// Whether it is standard output.
    pub fn is_stdout(&self) -> bool {
        matches!(self, Sink::Stdout)
    }
}

/// One output row: per observable the mean, its 95% half-width, the exact value.
pub struct Row {
    /// Time.
    pub t: f64,
    /// `(mean, half-width of the 95% CI (NaN for one replica), exact or NaN)`.
    pub cells: Vec<(f64, f64, f64)>,
}

/// The rows of an outcome.
pub fn rows(plan: &Plan, out: &Outcome) -> Vec<Row> {
    plan.times
        .iter()
        .enumerate()
        .map(|(i, &t)| Row {
            t,
            cells: plan
                .observables
                .iter()
                .enumerate()
                .map(|(j, o)| {
                    let r = &out.stats[i][j];
                    let half = if r.count() >= 2 {
                        let (lo, hi) = r.ci95();
                        0.5 * (hi - lo)
                    } else {
                        f64::NAN
                    };
                    let exact = plan.exact.and_then(|e| e.value(o, t)).unwrap_or(f64::NAN);
                    (r.mean(), half, exact)
                })
                .collect(),
        })
        .collect()
}

/// Describes the set-up in a few lines.
pub fn describe(plan: &Plan) -> String {
    let s = &plan.scenario;
    let mut d = String::new();
    d.push_str(&plan.title);
    if let Some(src) = &s.reference {
        d.push_str(&format!("\nreference: {src}"));
    }
    d.push_str(&format!(
        "\nscheme: {} ({}), {} particles",
        plan.scheme.name, plan.scheme.summary, plan.particles
    ));
    if plan.scheme.takes_option("dt") {
        let r = plan.options.randomization();
        d.push_str(&format!(
            ", dt = {}, {:?} points{}",
            plan.options.dt(),
            plan.options.points(),
            if r == coagula_core::qmc::Randomization::None {
                String::new()
            } else {
                format!(" ({r:?})")
            }
        ));
    }
    let coefficient = if plan.units.is_empty() {
        format!("{}", plan.coefficient)
    } else {
        // the physical coefficient, in the units of the table
        format!(
            "{:.4e} {}",
            plan.coefficient,
            plan.units.split(';').next().unwrap_or("")
        )
    };
    d.push_str(&format!(
        "\nkernel: {} (coefficient {coefficient}){}, initial: {:?}",
        plan.kernel_name,
        if plan.size_unit != 1.0 {
            format!(", sizes on a grid of {}", plan.size_unit)
        } else {
            String::new()
        },
        s.initial.kind
    ));
    if plan.model.fragments() {
        d.push_str(", binary uniform fragmentation");
    }
    d.push_str(&format!(
        "\nreplicas: {}, seed {} (replica r on its substream of the seed policy); the sims will hold about {} ({})",
        plan.replicas,
        plan.seed,
        bytes(plan.memory),
        plan.memory_basis
    ));
    match &plan.exact {
        Some(e) => d.push_str(&format!("\nexact solution: {}", e.name)),
        None => d.push_str("\nexact solution: none known for this set-up"),
    }
    d
}

fn fmt_num(v: f64) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.6e}")
    }
}

/// The terminal table: at most `max_rows` rows (evenly picked, the last included), a
/// legend that explains every column, and the totals.
pub fn table(
    plan: &Plan,
    out: &Outcome,
    max_rows: usize,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    writeln!(w, "{}\n", describe(plan))?;
    let rows = rows(plan, out);
    let with_ci = plan.replicas >= 2;
    let with_exact = rows.iter().any(|r| r.cells.iter().any(|c| !c.2.is_nan()));
    let mut head = format!("{:>12}", "t");
    for o in &plan.observables {
        let name = o.name();
        head.push_str(&format!(" {name:>13}"));
        if with_ci {
            head.push_str(&format!(" {:>10}", "±95%"));
        }
        if with_exact {
            head.push_str(&format!(" {:>13} {:>10}", format!("{name} exact"), "error"));
        }
    }
    writeln!(w, "{head}")?;
    let n = rows.len();
    let pick: Vec<usize> = if n <= max_rows {
        (0..n).collect()
    } else {
        let mut v: Vec<usize> = (1..=max_rows).map(|k| k * n / max_rows - 1).collect();
        v.dedup();
        v
    };
    for &i in &pick {
        let r = &rows[i];
        let mut line = format!("{:>12.6}", r.t);
        for &(mean, half, exact) in &r.cells {
            line.push_str(&format!(" {:>13}", fmt_num(mean)));
            if with_ci {
                line.push_str(&format!(
                    " {:>10}",
                    if half.is_nan() {
                        "-".into()
                    } else {
                        format!("{half:.2e}")
                    }
                ));
            }
            if with_exact {
                let err = mean - exact;
                line.push_str(&format!(
                    " {:>13} {:>10}",
                    fmt_num(exact),
                    if err.is_nan() {
                        "-".into()
                    } else {
                        format!("{err:.2e}")
                    }
                ));
            }
        }
        writeln!(w, "{line}")?;
    }
    if pick.len() < n {
        writeln!(
            w,
            "({} of {n} output times shown; --csv or --json has them all)",
            pick.len()
        )?;
    }
    writeln!(w, "\ncolumns:")?;
    writeln!(w, "  t: time{}", physical_note(plan))?;
    for o in &plan.observables {
        writeln!(w, "  {}: {}", o.name(), o.meaning())?;
    }
    if with_ci {
        writeln!(
            w,
            "  ±95%: half-width of the 95% confidence interval of the mean over {} replicas (Student t)",
            plan.replicas
        )?;
    }
    if with_exact {
        writeln!(w, "  exact: the analytical solution; error: ours − exact")?;
    }
    if plan.scheme.law == Law::TimeStepped {
        writeln!(
            w,
            "  time step: the error includes the scheme's O(dt) time-step bias (an Euler step, Lécot et al. 2019 §2), which {}: halve scheme.dt to see its size (`coagula validate` measures it against the Euler reference)",
            if with_ci {
                "±95% does not cover (it is the spread over replicas only)"
            } else {
                "one replica cannot tell from chance"
            }
        )?;
    }
    let t = &out.totals;
    writeln!(
        w,
        "\ntotals over {} replicas: {} events, {} proposals ({} rejected), {} clipped, {} particle doublings; {:.2} s{}",
        plan.replicas,
        t.events,
        t.proposals,
        t.rejections,
        t.clipped,
        t.doublings,
        out.seconds,
        match out.resident {
            Some((before, peak)) => format!(
                ", {} held at the peak (resident memory)",
                bytes(peak.saturating_sub(before))
            ),
            None => String::new(),
        }
    )?;
    writeln!(
        w,
        "  events: coagulations (and break-ups) carried out; proposals/rejected: candidate pairs of the event-driven schemes and those refused by the acceptance test;"
    )?;
    writeln!(
        w,
        "  clipped: mass-flow steps whose probability dt·K̃ exceeded 1 and was cut to 1 (a time-step bias: lower dt if not 0); doublings: particle-number doublings (Osinsky §2)"
    )?;
    Ok(())
}

fn physical_note(plan: &Plan) -> &'static str {
    if !plan.units.is_empty() {
        " in s; concentrations per m³, sizes in monomers"
    } else {
        " in the kernel's units (1/(K·c0))"
    }
}

/// CSV: `t`, then per observable its mean, `_ci95` (half-width, with replicas) and
/// `_exact` (where known).
pub fn csv(plan: &Plan, out: &Outcome, w: &mut dyn Write) -> Result<(), String> {
    let (head, recs) = csv_records(plan, out);
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(&head).map_err(|e| e.to_string())?;
    for rec in recs {
        wr.write_record(&rec).map_err(|e| e.to_string())?;
    }
    wr.flush().map_err(|e| e.to_string())
}

/// Whether a plan's output has an exact value anywhere.
fn has_exact(plan: &Plan) -> bool {
    plan.exact.is_some_and(|e| {
        plan.times.iter().any(|&t| {
            plan.observables
                .iter()
                .any(|o| e.value(o, t).is_some_and(|v| !v.is_nan()))
        })
    })
}

/// The CSV columns of a plan's run.
fn csv_head(plan: &Plan) -> Vec<String> {
    let with_ci = plan.replicas >= 2;
    let with_exact = has_exact(plan);
    let mut head = vec!["t".to_string()];
    for o in &plan.observables {
        head.push(o.name());
        if with_ci {
            head.push(format!("{}_ci95", o.name()));
        }
        if with_exact {
            head.push(format!("{}_exact", o.name()));
        }
    }
    head
}

/// Refuses a sweep whose points would write different CSV columns (before the run).
pub fn check_sweep_columns(points: &[crate::plans::Point]) -> Result<(), String> {
    let Some((_, first)) = points.first() else {
        return Ok(());
    };
    let head = csv_head(first);
    for (set, plan) in &points[1..] {
        let other = csv_head(plan);
        if other != head {
            return Err(format!(
                "--csv: sweep point {} has other columns than the first ({} vs {}): write --json instead",
                crate::plans::label(set),
                other.join(","),
                head.join(",")
            ));
        }
    }
    Ok(())
}

/// The CSV header and records of one run.
fn csv_records(plan: &Plan, out: &Outcome) -> (Vec<String>, Vec<Vec<String>>) {
    let rows = rows(plan, out);
    let with_ci = plan.replicas >= 2;
    let with_exact = has_exact(plan);
    let head = csv_head(plan);
    let recs = rows
        .iter()
        .map(|r| {
            let mut rec = vec![r.t.to_string()];
            for &(m, h, e) in &r.cells {
                rec.push(m.to_string());
                if with_ci {
                    rec.push(h.to_string());
                }
                if with_exact {
                    rec.push(e.to_string());
                }
            }
            rec
        })
        .collect();
    (head, recs)
}

/// A sweep point's run: the values it sets, its plan, its outcome.
pub type SweepRun<'a> = (&'a [(String, toml::Value)], &'a Plan, &'a Outcome);

/// CSV of a sweep: the swept keys' values, then the columns of [`csv()`], for every
/// point. The points must have the same columns (the same observables, and replicas
/// and exact values on all or none).
pub fn csv_sweep(runs: &[SweepRun<'_>], w: &mut dyn Write) -> Result<(), String> {
    let mut wr = csv::Writer::from_writer(w);
    let mut first: Option<Vec<String>> = None;
    for (set, plan, out) in runs {
        let (head, recs) = csv_records(plan, out);
        let keys: Vec<String> = set.iter().map(|(k, _)| k.clone()).collect();
        let head: Vec<String> = keys.into_iter().chain(head).collect();
        match &first {
            None => {
                wr.write_record(&head).map_err(|e| e.to_string())?;
                first = Some(head);
            }
            Some(h) if *h != head => {
                return Err(format!(
                    "--csv: sweep point {} has other columns than the first ({} vs {}): write --json instead",
                    crate::plans::label(set),
                    head.join(","),
                    h.join(",")
                ));
            }
            Some(_) => {}
        }
        let vals: Vec<String> = set.iter().map(|(_, v)| csv_value(v)).collect();
        for rec in recs {
            let rec: Vec<String> = vals.iter().cloned().chain(rec).collect();
            wr.write_record(&rec).map_err(|e| e.to_string())?;
        }
    }
    wr.flush().map_err(|e| e.to_string())
}

/// A TOML value in a CSV cell: strings bare, the rest as TOML writes them.
fn csv_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        v => v.to_string(),
    }
}

#[derive(Serialize)]
struct Series {
    observable: String,
    meaning: String,
    mean: Vec<Option<f64>>,
    std_error: Vec<Option<f64>>,
    ci95: Vec<Option<[f64; 2]>>,
    exact: Vec<Option<f64>>,
}

#[derive(Serialize)]
struct Report<'a> {
    title: &'a str,
    scheme: &'a str,
    replicas: u64,
    seed: u64,
    exact_solution: Option<&'a str>,
    times: &'a [f64],
    series: Vec<Series>,
    events: u64,
    proposals: u64,
    rejections: u64,
    clipped: u64,
    doublings: u64,
    seconds: f64,
    /// What the sims were estimated to hold at most, and on what basis.
    memory_estimate: u64,
    memory_basis: &'a str,
    /// The process's resident memory before the run and at its peak (null where the
    /// system does not say): what the run held is the difference.
    resident_before: Option<u64>,
    resident_peak: Option<u64>,
    scenario: &'a crate::scenario::Scenario,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// JSON: the scenario, the times, and per observable the mean, standard error, CI and
/// exact values (null where undefined).
pub fn json(plan: &Plan, out: &Outcome, w: &mut dyn Write) -> Result<(), String> {
    serde_json::to_writer_pretty(&mut *w, &report(plan, out)).map_err(|e| e.to_string())?;
    writeln!(w).map_err(|e| e.to_string())
}

/// The JSON report of one run.
fn report<'a>(plan: &'a Plan, out: &Outcome) -> Report<'a> {
    let series = plan
        .observables
        .iter()
        .enumerate()
        .map(|(j, o)| Series {
            observable: o.name(),
            meaning: o.meaning(),
            mean: out.stats.iter().map(|s| finite(s[j].mean())).collect(),
            std_error: out.stats.iter().map(|s| finite(s[j].std_error())).collect(),
            ci95: out
                .stats
                .iter()
                .map(|s| {
                    let (lo, hi) = s[j].ci95();
                    (lo.is_finite() && hi.is_finite()).then_some([lo, hi])
                })
                .collect(),
            exact: plan
                .times
                .iter()
                .map(|&t| plan.exact.and_then(|e| e.value(o, t)).and_then(finite))
                .collect(),
        })
        .collect();
    let t = &out.totals;
    Report {
        title: &plan.title,
        scheme: plan.scheme.name,
        replicas: plan.replicas,
        seed: plan.seed,
        exact_solution: plan.exact.map(|e| e.name),
        times: &plan.times,
        series,
        events: t.events,
        proposals: t.proposals,
        rejections: t.rejections,
        clipped: t.clipped,
        doublings: t.doublings,
        seconds: out.seconds,
        memory_estimate: plan.memory,
        memory_basis: &plan.memory_basis,
        resident_before: out.resident.map(|r| r.0),
        resident_peak: out.resident.map(|r| r.1),
        scenario: &plan.scenario,
    }
}

/// JSON of a sweep: `{"sweep": [{"set": {key: value}, "report": ...}]}`, each report
/// as [`json`] writes one run.
pub fn json_sweep(runs: &[SweepRun<'_>], w: &mut dyn Write) -> Result<(), String> {
    let points: Vec<serde_json::Value> = runs
        .iter()
        .map(|(set, plan, out)| {
            let set: serde_json::Map<String, serde_json::Value> = set
                .iter()
                .map(|(k, v)| (k.clone(), serde_json::to_value(v).unwrap_or_default()))
                .collect();
            serde_json::json!({ "set": set, "report": report(plan, out) })
        })
        .collect();
    serde_json::to_writer_pretty(&mut *w, &serde_json::json!({ "sweep": points }))
        .map_err(|e| e.to_string())?;
    writeln!(w).map_err(|e| e.to_string())
}

/// A byte count in B, KiB, MiB or GiB (three significant digits at most).
fn bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}
