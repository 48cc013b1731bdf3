//! Runs a scenario's replicas in parallel (rayon) and gathers their statistics.
//!
//! Replica r runs on `substream(seed, 0, Purpose::Replica(r))` of the core's seed policy
//! (replica 0 on `generator(seed, 0)`), and, for RQMC, on its own scrambling from
//! `substream(seed, r, Scrambling)`, results are collected in
//! replica order and merged sequentially, so every figure is bit-identical whatever
//! the number of threads.

use crate::scenario::plan::Sim;
use crate::scenario::{Observable, Plan};
use coagula_core::observe::Replicas;
use coagula_core::random::{Generator, Purpose, substream};
use coagula_core::scheme::StepReport;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What the runs gave.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// `values[r][i][j]`: replica r, time i, observable j.
    pub values: Vec<Vec<Vec<f64>>>,
    /// Statistics over replicas, `[time][observable]`.
    pub stats: Vec<Vec<Replicas>>,
    /// Totals of every replica's reports.
    pub totals: StepReport,
    /// Events of each replica.
    pub events: Vec<u64>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// The process's resident memory before the run and at its peak, in bytes (Linux;
    /// `None` elsewhere): what the run held is the difference.
    pub resident: Option<(u64, u64)>,
}

/// The process's resident memory now and at its peak (`VmRSS`, `VmHWM` of
/// `/proc/self/status`), in bytes; `None` where the kernel does not say.
pub fn resident_memory() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line[name.len()..]
            .trim()
            .strip_suffix("kB")?
            .trim()
            .parse()
            .ok()?;
        Some(kb * 1024)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// The generator of replica r: the core's seed policy (`Purpose::Replica`; replica 0
/// is `generator(seed, 0)`, the stream a C-ABI run with that seed uses).
pub fn rng_of(plan: &Plan, replica: u64) -> Generator {
    substream(plan.seed, 0, Purpose::Replica(replica))
}

/// Builds replica r's simulation: its start (the quantile lattice shifted by the
/// core's `initial::lattice_shift` of the seed and the replica) and its options.
pub fn build(plan: &Plan, replica: u64) -> Result<Box<Sim>, String> {
    let shift = coagula_core::initial::lattice_shift(plan.randomised(), plan.seed, replica);
    let start = plan.start(shift, replica)?;
    plan.build(&start, replica)
}

/// An observable of a simulation, in the scenario's size units.
pub fn observe(plan: &Plan, sim: &Sim, o: &Observable) -> f64 {
    let d = plan.size_unit;
    match o {
        Observable::Moment(m) => sim.moment(*m) * if d == 1.0 { 1.0 } else { d.powf(*m) },
        Observable::Density(k) => sim.number_density(*k as f64 / d),
        Observable::Concentration(a, b) => sim.concentration(on_grid(a / d), on_grid(b / d)),
        Observable::Class(a, b) => sim.class_concentration(on_grid(a / d), on_grid(b / d)),
        Observable::Gel => sim.gel_mass().unwrap_or(f64::NAN) * d,
        Observable::Particles => sim.particles() as f64,
        Observable::Named(n) => sim.observable(n).unwrap_or(f64::NAN),
    }
}

/// A size in grid units, snapped to the nearest integer when within rounding of it
/// (`1.1 / 0.1` is `11.000000000000002`: the edge is size 11, not past it).
fn on_grid(x: f64) -> f64 {
    let r = x.round();
    if (x - r).abs() <= 1e-9 * r.abs().max(1.0) {
        r
    } else {
        x
    }
}

/// The concentrations of the plan's size classes (none when it has none).
fn classes<'a>(plan: &'a Plan, sim: &'a Sim) -> impl Iterator<Item = f64> + 'a {
    let d = plan.size_unit;
    plan.classes
        .windows(2)
        .map(move |w| sim.class_concentration(on_grid(w[0] / d), on_grid(w[1] / d)))
}

/// One replica's observables (`[time][observable]`) and its totals.
type ReplicaRows = (Vec<Vec<f64>>, StepReport);

/// One replica: the observables at every output time, and its totals.
fn replica(
    plan: &Plan,
    r: u64,
    tick: &(dyn Fn() + Sync),
) -> Result<(Vec<Vec<f64>>, StepReport), String> {
    let mut sim = build(plan, r)?;
    let mut rng = rng_of(plan, r);
    let mut rows = Vec::with_capacity(plan.times.len());
    for &t in &plan.times {
        sim.advance_to(t, &mut rng)
            .map_err(|e| format!("replica {r} at t = {:.6e}: {e}", sim.time()))?;
        rows.push(
            plan.observables
                .iter()
                .map(|o| observe(plan, &*sim, o))
                .chain(classes(plan, &*sim))
                .collect(),
        );
        tick();
    }
    Ok((rows, sim.totals()))
}

/// A progress bar on standard error that appears once a run has taken a second, and
/// never when standard error is not a terminal (or `quiet`).
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: AtomicBool,
    quiet: bool,
}

impl Progress {
    /// A bar of `len` steps.
    pub fn new(len: u64, message: &str, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} ({elapsed}, about {eta} left)",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar.set_message(message.to_string());
        Progress {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
            quiet,
        }
    }

    /// One step done.
    pub fn tick(&self) {
        if !self.quiet
            && !self.shown.load(Ordering::Relaxed)
            && self.start.elapsed().as_secs_f64() > 1.0
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            // stderr() hides itself when standard error is not a terminal
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        self.bar.inc(1);
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Runs every replica of a plan on `plan.threads` threads (0 = all cores).
pub fn run(plan: &Plan, quiet: bool) -> Result<Outcome, String> {
    let start = Instant::now();
    let before = resident_memory();
    let progress = Progress::new(
        plan.replicas * plan.times.len() as u64,
        &format!("{} x {}", plan.replicas, plan.scheme.name),
        quiet,
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(plan.threads)
        .build()
        .map_err(|e| format!("thread pool: {e}"))?;
    let tick = || progress.tick();
    let results: Vec<Result<ReplicaRows, String>> = pool.install(|| {
        (0..plan.replicas)
            .into_par_iter()
            .map(|r| replica(plan, r, &tick))
            .collect()
    });
    progress.finish();
    let (values, totals, events) = collect(results)?;
    let stats = statistics(&values, plan.times.len(), plan.columns());
    Ok(Outcome {
        values,
        stats,
        totals,
        events,
        seconds: start.elapsed().as_secs_f64(),
        resident: before
            .zip(resident_memory())
            .map(|((now, _), (_, peak))| (now, peak)),
    })
}

/// The replicas' rows in order, the totals of their reports and their events; the
/// first replica's error if one failed.
type Collected = (Vec<Vec<Vec<f64>>>, StepReport, Vec<u64>);

fn collect(results: Vec<Result<ReplicaRows, String>>) -> Result<Collected, String> {
    let mut values = Vec::with_capacity(results.len());
    let mut totals = StepReport::default();
    let mut events = Vec::with_capacity(results.len());
    for res in results {
        let (rows, rep) = res?;
        totals.accumulate(&rep);
        events.push(rep.events);
        values.push(rows);
    }
    Ok((values, totals, events))
}

/// Replicas per block: the unit of work that an ensemble shares out over processes
/// and saves in checkpoints. Inside a block the replicas are pushed in order; blocks
/// are merged in block order (Chan et al.'s update, [`Replicas::merge`]), so every
/// figure has the same bits whatever the number of processes and threads.
pub const BLOCK: u64 = 8;

/// The number of blocks of `replicas` replicas.
pub fn blocks(replicas: u64) -> u64 {
    replicas.div_ceil(BLOCK)
}

/// The replicas of block `b` (of `replicas` in all).
pub fn block_replicas(replicas: u64, b: u64) -> core::ops::Range<u64> {
    b * BLOCK..replicas.min((b + 1) * BLOCK)
}

/// Statistics per (time, observable): replicas pushed in order within each block of
/// [`BLOCK`], blocks merged in order.
pub fn statistics(values: &[Vec<Vec<f64>>], times: usize, obs: usize) -> Vec<Vec<Replicas>> {
    let mut stats = vec![vec![Replicas::new(); obs]; times];
    for chunk in values.chunks(BLOCK as usize) {
        merge_stats(&mut stats, &pushed(chunk, times, obs));
    }
    stats
}

/// Welford statistics of one block, replicas pushed in order.
fn pushed(values: &[Vec<Vec<f64>>], times: usize, obs: usize) -> Vec<Vec<Replicas>> {
    let mut stats = vec![vec![Replicas::new(); obs]; times];
    for rows in values {
        for (i, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                stats[i][j].push(v);
            }
        }
    }
    stats
}

/// Merges a block's statistics into `acc` (same shape).
pub fn merge_stats(acc: &mut [Vec<Replicas>], block: &[Vec<Replicas>]) {
    for (a, b) in acc.iter_mut().zip(block) {
        for (x, y) in a.iter_mut().zip(b) {
            x.merge(y);
        }
    }
}

/// One block's results: its statistics, the totals of its replicas' reports and each
/// replica's events.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// `[time][observable]`.
    pub stats: Vec<Vec<Replicas>>,
    /// Totals of the block's reports.
    pub totals: StepReport,
    /// Events of each replica.
    pub events: Vec<u64>,
}

/// Runs block `b` of a plan (its replicas in parallel on the current rayon pool).
pub fn run_block(plan: &Plan, b: u64, tick: &(dyn Fn() + Sync)) -> Result<Block, String> {
    let results: Vec<Result<ReplicaRows, String>> = block_replicas(plan.replicas, b)
        .into_par_iter()
        .map(|r| replica(plan, r, tick))
        .collect();
    let (values, totals, events) = collect(results)?;
    Ok(Block {
        stats: pushed(&values, plan.times.len(), plan.columns()),
        totals,
        events,
    })
}
