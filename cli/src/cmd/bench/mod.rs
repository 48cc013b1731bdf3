//! `coagula bench lowrank`: Osinsky's tables 1–3 rerun side by side with the paper.

use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{Init, Model, Options, SchemeId, Simulation};
use coagula_core::scheme::registry;
use std::time::{Duration, Instant};

mod blocks;
mod peers;
mod processes;
pub use blocks::{BlocksStart, blocks};
use peers::original_particles;
pub use peers::peers;
pub use processes::processes;

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
    registry::build(
        id,
        Model::coagulation(k, NoFragmentation),
        &init,
        &Options::default(),
    )
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
        let cells = run(registry::find("lowrank").unwrap(), day, seed + 10 * k);
        for (best, c) in lr_cells.iter_mut().zip(cells) {
            *best = match (*best, c) {
                (Some(b), Some(c)) if b.seconds <= c.seconds => Some(b),
                (_, c) => c.or(*best),
            };
        }
    }
    let tree_cells = run(registry::find("lowrank-tree").unwrap(), day, seed + 3);
    let none = vec![None; times.len()];
    if skip_baselines {
        return (lr_cells, tree_cells, none.clone(), none);
    }
    let ar_cells = run(
        registry::find("rejection").unwrap(),
        Duration::from_secs_f64(budgets.ar),
        seed + 1,
    );
    if budgets.inverse <= 0.0 {
        return (lr_cells, tree_cells, ar_cells, none);
    }
    let inv_cells = run(
        registry::find("inverse").unwrap(),
        Duration::from_secs_f64(budgets.inverse),
        seed + 2,
    );
    (lr_cells, tree_cells, ar_cells, inv_cells)
}

/// Low-rank only, one kernel, to one time: for profiling.
pub fn lowrank_single(name: &str, n0: u64, t: f64, seed: u64, binary: bool, bucketed: bool) {
    let kernel = paper_kernel(name);
    let id = match (bucketed, binary) {
        (true, _) => registry::find("lowrank").unwrap(),
        (false, true) => registry::find("lowrank-binary-tree").unwrap(),
        (false, false) => registry::find("lowrank-tree").unwrap(),
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
        id.name,
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
            ("tree", registry::find("lowrank-tree").unwrap()),
            ("bucketed", registry::find("lowrank").unwrap()),
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
                let mut s: Box<Sim> = registry::build(
                    id,
                    Model::coagulation(k, NoFragmentation),
                    &init,
                    &Options::default(),
                )?;
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
            ("tree", registry::find("lowrank-tree").unwrap()),
            ("bucketed", registry::find("lowrank").unwrap()),
            ("sizes", registry::find("lowrank-sizes").unwrap()),
        ] {
            let init = if id == registry::find("lowrank-sizes").unwrap() {
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
                .map(|_| {
                    registry::build(
                        id,
                        Model::coagulation(k, NoFragmentation),
                        &init,
                        &Options::default(),
                    )
                })
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
                if id == registry::find("lowrank-sizes").unwrap() {
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
    let base = crate::plans::plan(file, overrides.clone(), None)?;
    let schemes: Vec<String> = if schemes.is_empty() {
        vec![base.scheme.name.to_string()]
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
            let plan = crate::plans::plan(file, ov, None).map_err(|e| format!("{label}: {e}"))?;
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
        && Some(n as f64) != base.scenario.initial.particles
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
