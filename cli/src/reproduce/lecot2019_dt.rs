//! The Δt ladder of `coagula reproduce lecot2019`: the time-driven mass-flow scheme
//! (Lécot et al. 2019, §3) at fixed N as the time step shrinks, with the paper's
//! deterministic QMC points (Niederreiter, and Sobol' as a second sequence), RQMC
//! (Owen's scrambling, re-randomised every block) and MC on the same step code. Only the
//! point source differs between the columns; `docs/results/lecot2019-dt-ladder.md`
//! says what the ladder shows and when deterministic QMC should not be used.

use coagula_core::exact::{ClosedMoments, Exact};
use coagula_core::initial::{Distribution, lattice_shift};
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::Replicas;
use coagula_core::qmc::Randomization;
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{Init, Model, Options, Points, Simulation};
use coagula_core::scheme::registry;
use rayon::prelude::*;

/// The point sets of a ladder row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Set {
    Niederreiter,
    Sobol,
    Rqmc,
    Mc,
}

/// The case: K = 1 from the exponential start c(x, 0) = e^{−x}, where
/// `M0(t) = 1/(1 + t/2)`.
pub struct Case {
    /// log2 N.
    pub m: u32,
    /// The end time.
    pub t_end: f64,
    /// The time steps, largest first.
    pub dts: Vec<f64>,
    /// Replicas of each randomised point set.
    pub reps: u64,
}

/// One time step's results: M0(t_end) of each point set.
pub struct Row {
    pub dt: f64,
    pub niederreiter: f64,
    pub sobol: f64,
    /// (mean, half-width of the 95 % interval, standard deviation of one run)
    pub rqmc: (f64, f64, f64),
    pub mc: (f64, f64, f64),
    /// Coagulations per step (the deterministic run's): the points of a block that
    /// fall below `Δt K̃`, which the net structure stratifies.
    pub events_per_step: f64,
    /// Euler's recurrence of the moment equation (the scheme's mean-field expectation).
    pub euler: f64,
    /// Clipped steps over all runs of the row (probabilities Δt K̃ cut at 1).
    pub clipped: u64,
}

/// M0 at `t_end` of one run, its clipped steps and its events.
fn run(case: &Case, dt: f64, set: Set, seed: u64) -> Result<(f64, u64, u64), String> {
    let n = 1usize << case.m;
    let randomised = set != Set::Niederreiter && set != Set::Sobol;
    let shift = lattice_shift(randomised, seed, 0);
    let start = Distribution::Exponential { mean: 1.0 };
    // the mass-flow scheme's particles sample the mass distribution x c(x) / M1
    let sizes: Vec<f64> = (0..n)
        .map(|i| start.inverse((i as f64 + shift) / n as f64, true))
        .collect();
    let mut o = Options::default().with_dt(dt).with_stream(seed, 0);
    o = match set {
        Set::Niederreiter => o,
        Set::Sobol => o.with_points(Points::Sobol),
        Set::Rqmc => o.with_randomization(Randomization::Owen),
        Set::Mc => o.with_points(Points::MonteCarlo),
    };
    let mut sim: Box<dyn Simulation<Coagulation, NoFragmentation, Generator>> = registry::build(
        registry::find("massflow").map_err(|e| e.to_string())?,
        Model::coagulation(
            Coagulation::constant(1.0).map_err(|e| e.to_string())?,
            NoFragmentation,
        ),
        &Init::Sizes {
            sizes: &sizes,
            mass: 1.0,
        },
        &o,
    )
    .map_err(|e| e.to_string())?;
    let rep = sim
        .advance_to(case.t_end, &mut generator(seed, 0))
        .map_err(|e| e.to_string())?;
    Ok((sim.moment(0.0), rep.clipped, rep.events))
}

/// The ladder, rows in the order of `case.dts` (runs in parallel).
pub fn ladder(case: &Case) -> Result<Vec<Row>, String> {
    let mut jobs = Vec::new();
    for (i, &dt) in case.dts.iter().enumerate() {
        jobs.push((i, dt, Set::Niederreiter, 0));
        jobs.push((i, dt, Set::Sobol, 0));
        for r in 0..case.reps {
            jobs.push((i, dt, Set::Rqmc, r + 1));
            jobs.push((i, dt, Set::Mc, r + 1));
        }
    }
    let values = jobs
        .par_iter()
        .map(|&(i, dt, set, seed)| run(case, dt, set, seed).map(|(v, c, e)| (i, set, v, c, e)))
        .collect::<Result<Vec<_>, String>>()?;
    let euler_of = |dt: f64| {
        // c(x, 0) = e^{−x}: M_m(0) = m!
        let k = ClosedMoments::Constant {
            b: 1.0,
            lambda: 0.0,
        };
        k.euler([1.0, 1.0, 2.0, 6.0], dt, (case.t_end / dt).round() as u64)[0]
    };
    Ok(case
        .dts
        .iter()
        .enumerate()
        .map(|(i, &dt)| {
            let of = |set| values.iter().filter(move |v| v.0 == i && v.1 == set);
            let stats = |set| {
                let mut r = Replicas::new();
                for v in of(set) {
                    r.push(v.2);
                }
                (r.mean(), r.ci95().1 - r.mean(), r.variance().sqrt())
            };
            Row {
                dt,
                niederreiter: of(Set::Niederreiter).map(|v| v.2).sum(),
                sobol: of(Set::Sobol).map(|v| v.2).sum(),
                rqmc: stats(Set::Rqmc),
                mc: stats(Set::Mc),
                euler: euler_of(dt),
                events_per_step: of(Set::Niederreiter).map(|v| v.4).sum::<u64>() as f64
                    / (case.t_end / dt).round(),
                clipped: values.iter().filter(|v| v.0 == i).map(|v| v.3).sum(),
            }
        })
        .collect())
}

/// Prints the ladder as relative errors of M0(t_end) against the exact solution.
pub fn print(case: &Case, rows: &[Row]) {
    let exact = Exact::constant_exponential(1.0)
        .and_then(|e| e.moment(0, case.t_end))
        .unwrap_or(f64::NAN);
    println!(
        "\nΔt ladder at fixed N = 2^{}: K = 1, exponential start, relative error of M0(t = {}) \
         (exact {exact:.6}); RQMC and MC over {} replicas each, ±95 %; Euler: the moment \
         equation's explicit Euler steps, the scheme's mean-field expectation",
        case.m, case.t_end, case.reps
    );
    println!(
        "{:>8} | {:>10} {:>10} | {:>21} {:>8} | {:>21} {:>8} | {:>10} | {:>7} | {:>8}",
        "dt",
        "QMC Nied.",
        "QMC Sobol",
        "RQMC (Owen)",
        "sd",
        "MC",
        "sd",
        "Euler",
        "ev/step",
        "clipped"
    );
    let rel = |v: f64| (v - exact) / exact;
    for r in rows {
        println!(
            "{:>8} | {:>+10.2e} {:>+10.2e} | {:>+10.2e} ± {:>8.1e} {:>8.1e} | {:>+10.2e} ± {:>8.1e} {:>8.1e} | {:>+10.2e} | {:>7.1} | {:>8}",
            r.dt,
            rel(r.niederreiter),
            rel(r.sobol),
            rel(r.rqmc.0),
            r.rqmc.1 / exact,
            r.rqmc.2 / exact,
            rel(r.mc.0),
            r.mc.1 / exact,
            r.mc.2 / exact,
            rel(r.euler),
            r.events_per_step,
            r.clipped
        );
    }
}
