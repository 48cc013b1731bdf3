//! `coagula bench lowrank`: Osinsky's tables 1–3 rerun side by side with the paper.

use crate::options;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::registry::{self, Init, SchemeId, Simulation};
use std::time::{Duration, Instant};

/// One row of the paper's tables: time, max size M, seconds (inverse, AR, low-rank;
/// None = over 24 h) and collisions.
pub struct PaperRow {
    pub t: f64,
    pub m: u64,
    pub inverse: Option<f64>,
    pub rejection: Option<f64>,
    pub lowrank: f64,
    pub collisions: f64,
}

const fn row(
    t: f64,
    m: u64,
    inverse: Option<f64>,
    rejection: Option<f64>,
    lowrank: f64,
    collisions: f64,
) -> PaperRow {
    PaperRow {
        t,
        m,
        inverse,
        rejection,
        lowrank,
        collisions,
    }
}

/// Osinsky (2023) tables 1–3.
pub const BROWNIAN: [PaperRow; 5] = [
    row(10.0, 512, Some(67.0), Some(8.3), 3.5, 2.3e7),
    row(100.0, 4096, Some(3366.0), Some(18.5), 7.1, 3.9e7),
    row(1e3, 65536, None, Some(37.0), 11.0, 5.5e7),
    row(1e4, 524288, None, Some(74.0), 17.0, 7.2e7),
    row(1e5, 4194304, None, Some(147.0), 27.0, 8.9e7),
];
pub const BALLISTIC: [PaperRow; 5] = [
    row(1.0, 128, Some(6.5), Some(5.4), 4.4, 1.1e7),
    row(5.0, 512, Some(84.0), Some(17.0), 11.0, 2.3e7),
    row(50.0, 8192, Some(7967.0), Some(62.0), 23.0, 4.3e7),
    row(500.0, 131072, None, Some(221.0), 38.0, 6.3e7),
    row(5000.0, 2097152, None, Some(840.0), 58.0, 8.3e7),
];
pub const LINEAR: [PaperRow; 3] = [
    row(1.0, 128, Some(8.4), Some(14.0), 0.89, 7.6e6),
    row(3.0, 8192, Some(4887.0), Some(172.0), 3.5, 2.2e7),
    row(6.0, 2097152, None, Some(2370.0), 6.7, 4.4e7),
];

/// What one method reached at one checkpoint.
#[derive(Clone, Copy, Debug)]
pub struct Cell {
    pub seconds: f64,
    pub collisions: u64,
    pub max_size: u64,
}

/// The kernel of one of Osinsky's tables: "brownian", "ballistic" (free-molecular on
/// integer sizes), anything else the linear (additive) kernel.
pub(crate) fn paper_kernel(name: &str) -> Coagulation {
    match name {
        "brownian" => Coagulation::brownian(),
        "ballistic" => Coagulation::free_molecular()
            .with_min_size(1.0)
            .expect("valid"),
        _ => Coagulation::additive(),
    }
}

/// The facade as the CLI instantiates it.
type Sim = dyn Simulation<Coagulation, NoFragmentation, Generator>;

/// Scheme `id` from `n0` monomers in volume n0, through the registry.
fn monodisperse(id: SchemeId, k: Coagulation, n0: u64) -> Result<Box<Sim>, coagula_core::Error> {
    let init = Init::Counts {
        counts: &[n0],
        volume: n0 as f64,
    };
    registry::build(id, k, NoFragmentation, &init, &options())
}

/// Runs a scheme through the checkpoints, stopping (None for the rest) once the wall
/// clock passes `budget`. Time is advanced in slices so the budget is checked often.
fn run_checkpoints(sim: &mut Sim, times: &[f64], budget: Duration, seed: u64) -> Vec<Option<Cell>> {
    let mut rng = generator(seed, 0);
    let start = Instant::now();
    let mut collisions = 0u64;
    let mut out = Vec::new();
    let mut over = false;
    for &t in times {
        if over {
            out.push(None);
            continue;
        }
        // slices: 200 per checkpoint interval, so a slow method is stopped promptly
        let t0 = sim.time();
        for s in 1..=200 {
            let target = t0 + (t - t0) * f64::from(s) / 200.0;
            match sim.advance_to(target, &mut rng) {
                Ok(rep) => collisions += rep.events,
                Err(e) => {
                    eprintln!("error: {e}");
                    over = true;
                    break;
                }
            }
            if start.elapsed() > budget {
                over = true;
                break;
            }
        }
        if over {
            out.push(None);
        } else {
            out.push(Some(Cell {
                seconds: start.elapsed().as_secs_f64(),
                collisions,
                max_size: sim.max_size().unwrap_or(0),
            }));
        }
    }
    out
}

/// Wall-clock budgets of the baseline runs, in seconds.
#[derive(Clone, Copy, Debug)]
pub struct Budgets {
    pub ar: f64,
    pub inverse: f64,
}

pub fn lowrank(
    n0: u64,
    budgets: Budgets,
    only: Option<String>,
    skip_baselines: bool,
    repeat: u32,
    seed: u64,
) {
    let tables: [(&str, &[PaperRow]); 3] = [
        ("brownian", &BROWNIAN),
        ("ballistic", &BALLISTIC),
        ("linear", &LINEAR),
    ];
    println!(
        "Osinsky (2023) tables 1-3 from {n0:.0e} monomers; acceptance-rejection stopped after {} s, inverse after {} s (\"-\").",
        budgets.ar, budgets.inverse
    );
    println!("coll/s and ratios are ours; \"paper\" columns are the paper's low-rank figures.");
    if n0 != 10_000_000 {
        println!(
            "note: N0 = {n0} here, the paper's tables use 1e7: compare collisions per second, not seconds or collisions."
        );
    }
    println!(
        "LR = bucketed low-rank (the default layout), fastest of {repeat} run(s); tree = low-rank with per-size 8-ary trees."
    );
    for (name, rows) in tables {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let times: Vec<f64> = rows.iter().map(|r| r.t).collect();
        let kernel = paper_kernel(name);
        let (lr, tree, ar, inv) =
            bench_kernel(kernel, n0, &times, budgets, skip_baselines, repeat, seed);
        println!();
        println!("{name}");
        println!(
            "{:>8} {:>9} {:>9} | {:>8} {:>8} {:>8} {:>8} | {:>10} {:>10} {:>7} | {:>7} {:>7} | {:>9} {:>9}",
            "t",
            "M",
            "coll",
            "inv s",
            "AR s",
            "tree s",
            "LR s",
            "LR coll/s",
            "paper c/s",
            "x paper",
            "LR/AR",
            "paper",
            "inv coll",
            "AR coll"
        );
        for (i, r) in rows.iter().enumerate() {
            let fmt = |c: Option<Cell>| c.map_or("-".to_string(), |c| format!("{:.2}", c.seconds));
            let l = lr[i];
            let paper_cps = r.collisions / r.lowrank;
            let (lrs, lrc, m, cps) = match l {
                Some(c) => (
                    format!("{:.2}", c.seconds),
                    format!("{:.2e}", c.collisions as f64),
                    c.max_size,
                    c.collisions as f64 / c.seconds,
                ),
                None => ("-".into(), "-".into(), 0, f64::NAN),
            };
            let ratio_ar = match (ar[i], l) {
                (Some(a), Some(l)) => format!("{:.1}", a.seconds / l.seconds),
                _ => "-".into(),
            };
            let paper_ar = r
                .rejection
                .map_or("-".into(), |a| format!("{:.1}", a / r.lowrank));
            let _ = r.inverse;
            println!(
                "{:>8} {:>9} {:>9} | {:>8} {:>8} {:>8} {:>8} | {:>10.3e} {:>10.3e} {:>7.2} | {:>7} {:>7} | {:>9} {:>9}",
                r.t,
                m,
                lrc,
                fmt(inv[i]),
                fmt(ar[i]),
                fmt(tree[i]),
                lrs,
                cps,
                paper_cps,
                cps / paper_cps,
                ratio_ar,
                paper_ar,
                inv[i].map_or("-".into(), |c| format!("{:.2e}", c.collisions as f64)),
                ar[i].map_or("-".into(), |c| format!("{:.2e}", c.collisions as f64)),
            );
            let _ = r.m;
        }
    }
}

type Cells = Vec<Option<Cell>>;

fn bench_kernel(
    kernel: Coagulation,
    n0: u64,
    times: &[f64],
    budgets: Budgets,
    skip_baselines: bool,
    repeat: u32,
    seed: u64,
) -> (Cells, Cells, Cells, Cells) {
    let day = Duration::from_secs(24 * 3600);
    let run = |id: SchemeId, budget: Duration, seed: u64| {
        let mut s = monodisperse(id, kernel, n0).expect("valid set-up");
        run_checkpoints(&mut *s, times, budget, seed)
    };
    let mut lr_cells: Cells = vec![None; times.len()];
    for k in 0..u64::from(repeat) {
        let cells = run(SchemeId::LowRank, day, seed + 10 * k);
        for (best, c) in lr_cells.iter_mut().zip(cells) {
            *best = match (*best, c) {
                (Some(b), Some(c)) if b.seconds <= c.seconds => Some(b),
                (_, c) => c.or(*best),
            };
        }
    }
    let tree_cells = run(SchemeId::LowRankTree, day, seed + 3);
    let none = vec![None; times.len()];
    if skip_baselines {
        return (lr_cells, tree_cells, none.clone(), none);
    }
    let ar_cells = run(
        SchemeId::Rejection,
        Duration::from_secs_f64(budgets.ar),
        seed + 1,
    );
    if budgets.inverse <= 0.0 {
        return (lr_cells, tree_cells, ar_cells, none);
    }
    let inv_cells = run(
        SchemeId::Inverse,
        Duration::from_secs_f64(budgets.inverse),
        seed + 2,
    );
    (lr_cells, tree_cells, ar_cells, inv_cells)
}

/// Low-rank only, one kernel, to one time: for profiling.
pub fn lowrank_single(name: &str, n0: u64, t: f64, seed: u64, binary: bool, bucketed: bool) {
    let kernel = paper_kernel(name);
    let id = match (bucketed, binary) {
        (true, _) => SchemeId::LowRank,
        (false, true) => SchemeId::LowRankBinaryTree,
        (false, false) => SchemeId::LowRankTree,
    };
    let start = Instant::now();
    let mut sim = monodisperse(id, kernel, n0).expect("valid");
    let mut rng = generator(seed, 0);
    let rep = sim.advance_to(t, &mut rng).expect("runs");
    let s = start.elapsed().as_secs_f64();
    eprintln!(
        "proposals {} rejections {} violations {}",
        rep.proposals, rep.rejections, rep.bound_violations
    );
    println!(
        "{name} t={t} ({}): {} collisions, M={}, {s:.3} s, {:.3e} coll/s, N/V={:.6e}",
        id.name(),
        rep.events,
        sim.max_size().unwrap_or(0),
        rep.events as f64 / s,
        sim.moment(0.0)
    );
}

/// `coagula bench lowrank-small`: the per-size tree and the bucketed layout on many
/// small constant-kernel systems (a host running many small cells), side by side.
pub fn lowrank_small(
    n0s: &[u64],
    len: usize,
    t: f64,
    replicas: u64,
) -> Result<(), coagula_core::Error> {
    if !(t.is_finite() && t > 0.0) {
        return Err(coagula_core::Error::OutOfRange {
            name: "--t",
            value: t,
            range: "(0, inf)",
        });
    }
    if len == 0 || replicas < 2 {
        return Err(coagula_core::Error::OutOfRange {
            name: "--len / --replicas",
            value: len.min(replicas as usize) as f64,
            range: "len >= 1, replicas >= 2",
        });
    }
    let k = Coagulation::constant(1.0)?;
    println!(
        "constant kernel, monomers in a count vector of length {len}, to t = {t}, {replicas} replicas"
    );
    println!(
        "{:>8} {:>9} | {:>9} {:>9} {:>10} {:>12} {:>10}",
        "N0", "layout", "accept", "s", "ns/event", "mean N/V", "SE"
    );
    for &n0 in n0s {
        let mut init = vec![0u64; len];
        init[0] = n0;
        let v = n0 as f64;
        for (layout, id) in [
            ("tree", SchemeId::LowRankTree),
            ("bucketed", SchemeId::LowRank),
        ] {
            let start = Instant::now();
            let (mut prop, mut ev) = (0u64, 0u64);
            let mut st = coagula_core::observe::Replicas::new();
            for r in 0..replicas {
                let mut rng = generator(r ^ (n0 << 32), 0);
                let init = Init::Counts {
                    counts: &init,
                    volume: v,
                };
                let mut s: Box<Sim> = registry::build(id, k, NoFragmentation, &init, &options())?;
                let rep = s.advance_to(t, &mut rng)?;
                let nv = s.particles() as f64 / s.volume();
                prop += rep.proposals;
                ev += rep.events;
                st.push(nv);
            }
            // everything a host pays per accepted event: building, stepping, reading
            let secs = start.elapsed().as_secs_f64();
            println!(
                "{n0:>8} {layout:>9} | {:>9.4} {:>9.3} {:>10.1} {:>12.6} {:>10.2e}",
                ev as f64 / prop.max(1) as f64,
                secs,
                secs * 1e9 / ev.max(1) as f64,
                st.mean(),
                st.std_error()
            );
        }
    }
    Ok(())
}

/// `coagula bench lowrank-small --host-steps S`: `cells` constant-kernel cells of `n0`
/// monomers each (volume n0), built once, then advanced together through `S` steps of
/// about one event per cell (`t ← t (1 + 4/(3 n0))` from t = 1: the rate of a cell
/// between doublings is about 3 n0 / (4 t)), on the per-size tree, the bucketed layout
/// and continuous sizes. The counts layouts' largest size M grows like t while the
/// particle number stays near n0, so their cost per event shows any O(M) work.
pub fn lowrank_host_steps(n0s: &[u64], cells: u64, steps: u64) -> Result<(), coagula_core::Error> {
    if cells == 0 || steps == 0 {
        return Err(coagula_core::Error::OutOfRange {
            name: "--replicas / --host-steps",
            value: 0.0,
            range: "[1, inf)",
        });
    }
    // (small cells are the point; the continuous-sizes layout holds N0 sizes per cell)
    if let Some(&n0) = n0s.iter().find(|&&n| n == 0 || n > 1 << 24) {
        return Err(coagula_core::Error::OutOfRange {
            name: "--n0 (with --host-steps)",
            value: n0 as f64,
            range: "[1, 2^24]",
        });
    }
    let k = Coagulation::constant(1.0)?;
    println!(
        "constant kernel, {cells} cells of N0 monomers (volume N0) built once, then {steps} host steps of about one event per cell"
    );
    println!(
        "{:>8} {:>9} | {:>12} {:>12} {:>12} {:>10} {:>10}",
        "N0", "layout", "build ns", "ns/event", "events/call", "t end", "M end"
    );
    for &n0 in n0s {
        let counts = [n0];
        let ones = vec![1.0; n0 as usize];
        for (layout, id) in [
            ("tree", SchemeId::LowRankTree),
            ("bucketed", SchemeId::LowRank),
            ("sizes", SchemeId::LowRankSizes),
        ] {
            let init = if id == SchemeId::LowRankSizes {
                // (M1 = 1: volume Σ sizes / M1 = N0, as the counts layouts')
                Init::Sizes {
                    sizes: &ones,
                    mass: 1.0,
                }
            } else {
                Init::Counts {
                    counts: &counts,
                    volume: n0 as f64,
                }
            };
            let start = Instant::now();
            let mut sims: Vec<Box<Sim>> = (0..cells)
                .map(|_| registry::build(id, k, NoFragmentation, &init, &options()))
                .collect::<Result<_, _>>()?;
            let build = start.elapsed().as_secs_f64();
            let mut rngs: Vec<Generator> =
                (0..cells).map(|c| generator(c ^ (n0 << 32), 0)).collect();
            let (mut t, mut events, mut calls) = (1.0f64, 0u64, 0u64);
            let start = Instant::now();
            for _ in 0..steps {
                t *= 1.0 + 4.0 / (3.0 * n0 as f64);
                for (sim, rng) in sims.iter_mut().zip(&mut rngs) {
                    events += sim.advance_to(t, rng)?.events;
                    calls += 1;
                }
            }
            let secs = start.elapsed().as_secs_f64();
            let m = sims
                .iter()
                .map(|s| s.max_size().unwrap_or(0))
                .max()
                .unwrap_or(0);
            println!(
                "{n0:>8} {layout:>9} | {:>12.0} {:>12.1} {:>12.2} {t:>10.3e} {:>10}",
                build * 1e9 / cells as f64,
                secs * 1e9 / events.max(1) as f64,
                events as f64 / calls as f64,
                if id == SchemeId::LowRankSizes {
                    "-".to_string()
                } else {
                    m.to_string()
                }
            );
        }
    }
    Ok(())
}

/// One row of `coagula bench scenario`: a scheme (and a varied setting) on the scenario.
struct BenchRow {
    label: String,
    plan: crate::scenario::Plan,
    best: f64,
    outcome: Option<crate::runner::Outcome>,
}

/// `coagula bench scenario`: schemes (and values of one setting) side by side on the
/// same scenario, `repeat` alternating rounds, the minimum wall time of each kept:
/// wall seconds, events per second, and the error of each observable at the last
/// output time against the exact solution where known.
pub fn scenario(
    file: Option<&str>,
    schemes: &[String],
    vary: Option<(String, Vec<toml::Value>)>,
    overrides: Vec<(String, toml::Value)>,
    repeat: u32,
) -> Result<(), String> {
    if let Some((key, _)) = &vary
        && (key.starts_with("output.") || key == "output")
    {
        return Err(format!(
            "--vary {key}: the rows must share output times and observables (vary a kernel, initial, scheme or run setting)"
        ));
    }
    let base = crate::run::plan(file, overrides.clone(), None)?;
    let schemes: Vec<String> = if schemes.is_empty() {
        vec![base.scheme.name().to_string()]
    } else {
        schemes.to_vec()
    };
    let values: Vec<Option<toml::Value>> = match &vary {
        Some((_, vs)) => vs.iter().cloned().map(Some).collect(),
        None => vec![None],
    };
    let mut rows = Vec::new();
    for s in &schemes {
        for v in &values {
            let mut ov = overrides.clone();
            ov.push(("scheme.name".into(), toml::Value::String(s.clone())));
            let mut label = s.clone();
            if let (Some((key, _)), Some(v)) = (&vary, v) {
                ov.push((key.clone(), v.clone()));
                label = format!("{s} {key}={v}");
            }
            let plan = crate::run::plan(file, ov, None).map_err(|e| format!("{label}: {e}"))?;
            rows.push(BenchRow {
                label,
                plan,
                best: f64::INFINITY,
                outcome: None,
            });
        }
    }
    println!("{}\n", crate::output::describe(&base));
    if let Some(n) = original_particles(file)
        && Some(n) != base.scenario.initial.particles
    {
        println!(
            "note: N0 = {:?} here, the scenario file (and the source's figures) use {n}: compare rates and errors, not seconds\n",
            base.scenario.initial.particles
        );
    }
    for round in 0..repeat {
        for row in rows.iter_mut() {
            let out =
                crate::runner::run(&row.plan, true).map_err(|e| format!("{}: {e}", row.label))?;
            eprintln!(
                "round {}/{repeat}: {} {:.3} s",
                round + 1,
                row.label,
                out.seconds
            );
            if out.seconds < row.best {
                row.best = out.seconds;
            }
            row.outcome = Some(out);
        }
    }
    let obs = &base.observables;
    let t_end = *base.times.last().expect("times");
    let mut head = format!(
        "{:<40} {:>10} {:>12} {:>12} {:>10}",
        "scheme", "seconds", "events", "events/s", "ns/event"
    );
    for o in obs {
        head.push_str(&format!(" {:>24}", format!("{} − exact (±95%)", o.name())));
    }
    println!("{head}");
    for row in &rows {
        let out = row.outcome.as_ref().expect("ran");
        let ev = out.totals.events as f64;
        let mut line = format!(
            "{:<40} {:>10.3} {:>12.4e} {:>12.4e} {:>10.1}",
            row.label,
            row.best,
            ev,
            ev / row.best,
            1e9 * row.best / ev.max(1.0)
        );
        let last = row.plan.times.len() - 1;
        let t_row = row.plan.times[last];
        for (j, o) in row.plan.observables.iter().enumerate() {
            let r = &out.stats[last][j];
            let cell = match row.plan.exact.and_then(|e| e.value(o, t_row)) {
                Some(x) if r.count() >= 2 => {
                    let (lo, hi) = r.ci95();
                    format!("{:+.2e} (±{:.1e})", r.mean() - x, 0.5 * (hi - lo))
                }
                Some(x) => format!("{:+.2e}", r.mean() - x),
                None => "-".into(),
            };
            line.push_str(&format!(" {cell:>24}"));
        }
        println!("{line}");
    }
    println!(
        "\nseconds: the fastest of {repeat} alternating rounds (all replicas, {} threads); errors at t = {t_end}, the mean of the replicas",
        if base.threads == 0 {
            "all".to_string()
        } else {
            base.threads.to_string()
        }
    );
    Ok(())
}

/// `initial.particles` of a scenario file as written (no overrides).
fn original_particles(file: Option<&str>) -> Option<u64> {
    let (_, text) = crate::run::resolve(file).ok()?;
    let t: toml::Table = toml::from_str(&text).ok()?;
    t.get("initial")?
        .get("particles")?
        .as_integer()
        .map(|n| n as u64)
}

/// The figures measured for the peers and the authors' code, side by side with ours on
/// this machine (see `docs/results/peers-golovin.md` and
/// `docs/results/osinsky2023-authors.md` for how).
const PEER_FIGURES: &str = include_str!("../../docs/results/peer-figures.csv");

/// One recorded figure.
struct Figure {
    problem: String,
    code: String,
    version: String,
    date: String,
    n: f64,
    t: f64,
    seconds: f64,
    rss_mb: Option<f64>,
    errors: Option<(f64, f64)>,
    collisions: Option<f64>,
    n_ratio: Option<f64>,
}

/// The built-in figures (`#` lines are comments).
fn figures() -> Vec<Figure> {
    let mut r = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_reader(PEER_FIGURES.as_bytes());
    let opt = |x: &str| x.trim().parse::<f64>().ok();
    r.records()
        .map(|rec| {
            let rec = rec.expect("built-in CSV");
            let f = |i: usize| rec.get(i).unwrap_or("").trim().to_string();
            let num = |i: usize| opt(&f(i)).expect("built-in number");
            Figure {
                problem: f(0),
                code: f(1),
                version: f(2),
                date: f(3),
                n: num(4),
                t: num(5),
                seconds: num(6),
                rss_mb: opt(&f(7)),
                errors: opt(&f(8)).zip(opt(&f(9))),
                collisions: opt(&f(10)),
                n_ratio: opt(&f(11)),
            }
        })
        .collect()
}

/// Our row of a peers problem: particles, seconds per run, RMS relative errors of
/// M0 and M2.
struct Ours {
    layout: &'static str,
    n: u64,
    seconds: f64,
    m0: f64,
    m2: f64,
}

/// `coagula bench peers`: see the command's help (`constant`: the constant kernel to
/// t = 10 instead of Golovin's to t = 5.4).
pub fn peers(
    seeds: u64,
    max_log2n: u32,
    authors: bool,
    constant: bool,
) -> Result<(), coagula_core::Error> {
    use coagula_core::exact::Exact;
    let figs = figures();
    let (problem, t, exact, kernel, name) = if constant {
        (
            "constant-exp",
            10.0,
            Exact::constant_exponential(1.0)?,
            Coagulation::constant(1.0)?,
            "The constant kernel K = 1",
        )
    } else {
        (
            "golovin-exp",
            5.4,
            Exact::additive_exponential(),
            Coagulation::additive(),
            "Golovin's kernel K = x + y",
        )
    };
    let (e0, e2) = (exact.moment(0, t)?, exact.moment(2, t)?);
    println!(
        "{name} from c(x,0) = e^-x to t = {t}: {} here ({seeds} seeds,\n\
         midpoint quantiles of Exp(1), one thread, seconds per run) against the peers' recorded\n\
         figures (CPU seconds of stepping; RMS relative errors over their seeds)\n",
        if constant {
            "lowrank-sizes and the bucketed layout on a 1/64 grid"
        } else {
            "lowrank-sizes"
        }
    );
    println!(
        "{:>10} {:>12} {:>10} {:>10}",
        "N", "s/run", "M0 err", "M2 err"
    );
    // the constant kernel also on the bucketed layout over integer sizes (a grid of
    // 1/64 of the mean; K = 1 has degree 0, so its coefficient is unchanged)
    let layouts: &[(&str, SchemeId)] = if constant {
        &[
            ("lowrank-sizes", SchemeId::LowRankSizes),
            ("lowrank (sizes on a 1/64 grid)", SchemeId::LowRank),
        ]
    } else {
        &[("lowrank-sizes", SchemeId::LowRankSizes)]
    };
    const GRID: f64 = 64.0;
    let mut ours = Vec::new();
    for &(label, id) in layouts {
        println!("{label}:");
        for lg in (12..=max_log2n).step_by(2) {
            let n = 1u64 << lg;
            let sizes: Vec<f64> = (0..n)
                .map(|i| -(-((i as f64 + 0.5) / n as f64)).ln_1p())
                .collect();
            let mut counts: Vec<u64> = Vec::new();
            if id == SchemeId::LowRank {
                for &x in &sizes {
                    let k = ((x * GRID).round() as usize).max(1);
                    if counts.len() < k {
                        counts.resize(k, 0);
                    }
                    counts[k - 1] += 1;
                }
            }
            let (kernel, m2_unit) = if id == SchemeId::LowRank {
                (kernel.with_min_size(1.0)?, GRID * GRID)
            } else {
                (kernel, 1.0)
            };
            let (mut s0, mut s2, mut secs) = (0.0, 0.0, 0.0);
            for seed in 0..seeds {
                let start = Instant::now();
                let init = if id == SchemeId::LowRank {
                    Init::Counts {
                        counts: &counts,
                        volume: n as f64,
                    }
                } else {
                    Init::Sizes {
                        sizes: &sizes,
                        mass: 1.0,
                    }
                };
                let mut sim: Box<Sim> =
                    registry::build(id, kernel, NoFragmentation, &init, &options())?;
                sim.advance_to(t, &mut generator(seed, 0))?;
                secs += start.elapsed().as_secs_f64();
                s0 += (sim.moment(0.0) / e0 - 1.0).powi(2);
                s2 += (sim.moment(2.0) / m2_unit / e2 - 1.0).powi(2);
            }
            let k = seeds as f64;
            let o = Ours {
                layout: if id == SchemeId::LowRank {
                    "grid"
                } else {
                    "sizes"
                },
                n,
                seconds: secs / k,
                m0: (s0 / k).sqrt(),
                m2: (s2 / k).sqrt(),
            };
            println!(
                "{:>10} {:>12.4} {:>9.2}% {:>9.2}%",
                format!("2^{lg}"),
                o.seconds,
                100.0 * o.m0,
                100.0 * o.m2
            );
            ours.push(o);
        }
    }
    println!(
        "\n{:<10} {:>8} {:>10} {:>9} {:>9} | {:>10} {:>10} {:>9}",
        "peer", "N", "CPU s", "M0 err", "M2 err", "ours", "our s", "ratio"
    );
    for f in figs.iter().filter(|f| f.problem == problem && f.t == t) {
        let Some((m0, m2)) = f.errors else { continue };
        let best = ours
            .iter()
            .filter(|o| o.m0 <= m0 && o.m2 <= m2)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
        let lg = f.n.log2().round();
        let (on, os, ratio) = match best {
            Some(o) => (
                format!("{} 2^{}", o.layout, o.n.trailing_zeros()),
                format!("{:.4}", o.seconds),
                format!("{:.1}x", f.seconds / o.seconds),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        println!(
            "{:<10} {:>8} {:>10.3} {:>8.2}% {:>8.2}% | {on:>10} {os:>10} {ratio:>9}",
            f.code,
            format!("2^{lg}"),
            f.seconds,
            100.0 * m0,
            100.0 * m2
        );
    }
    // every peer's version and date, once each
    let mut seen: Vec<String> = Vec::new();
    for f in figs.iter().filter(|f| f.problem == problem) {
        let who = format!("{} {}, measured {}", f.code, f.version, f.date);
        if !seen.contains(&who) {
            seen.push(who);
        }
    }
    if !seen.is_empty() {
        println!(
            "(peer figures: {}; ratio = peer CPU / ours at the cheapest of our rows with both errors at most the peer's; '-': none of ours up to 2^{max_log2n})",
            seen.join("; ")
        );
    }
    if !authors {
        return Ok(());
    }
    println!(
        "\nOsinsky's tables from 1e7 monomers: the bucketed layout here against the authors' Fortran (recorded)\n"
    );
    println!(
        "{:<10} {:>8} | {:>9} {:>8} {:>10} {:>12} | {:>9} {:>10} {:>12} | {:>6}",
        "kernel", "t", "Fortran s", "RSS MB", "coll", "N/N0", "ours s", "coll", "N/N0", "ratio"
    );
    for f in figs.iter().filter(|f| f.problem.starts_with("osinsky-")) {
        let name = f.problem.trim_start_matches("osinsky-");
        let start = Instant::now();
        let mut sim = monodisperse(SchemeId::LowRank, paper_kernel(name), f.n as u64)?;
        let rep = sim.advance_to(f.t, &mut generator(1, 0))?;
        let s = start.elapsed().as_secs_f64();
        println!(
            "{name:<10} {:>8} | {:>9.2} {:>8} {:>10.3e} {:>12.6e} | {s:>9.2} {:>10.3e} {:>12.6e} | {:>5.2}x",
            f.t,
            f.seconds,
            f.rss_mb.map_or("-".into(), |m| format!("{m:.0}")),
            f.collisions.unwrap_or(f64::NAN),
            f.n_ratio.unwrap_or(f64::NAN),
            rep.events as f64,
            sim.moment(0.0),
            f.seconds / s
        );
    }
    if let Some(f) = figs.iter().find(|f| f.problem.starts_with("osinsky-")) {
        println!(
            "(Fortran: {} at {}, gfortran -O3 -march=native, measured {}; ours: this run, wall seconds including the build)",
            f.code, f.version, f.date
        );
    }
    Ok(())
}
