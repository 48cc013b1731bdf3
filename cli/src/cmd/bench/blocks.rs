//! `coagula bench blocks`: block majorants (`lowrank-blocks`) against the low-rank
//! engine (`lowrank:slots`, the `lowrank` scheme pinned to its bucketed engine;
//! unpinned it would choose block majorants) on a kernel no low-rank bound fits
//! (issue 45), from monomers, interval by interval of t: proposals, coagulations, acceptance and the cost per
//! proposal and per coagulation. Runs alternate between the schemes; the fastest of
//! each interval is kept (the event counts are those of one seed).

use coagula_core::kernel::NoFragmentation;
use coagula_core::kernel::builtin::{self, Builtin};
use coagula_core::random::generator;
use coagula_core::scheme::facade::{Init, Model, Options, Value};
use coagula_core::scheme::registry;
use std::time::{Duration, Instant};

/// One interval of one run.
#[derive(Clone, Copy, Default)]
struct Cell {
    seconds: f64,
    proposals: u64,
    events: u64,
}

/// The kernel and the start of a run.
pub struct BlocksStart {
    /// A built-in coagulation kernel.
    pub kernel: String,
    /// Its parameters by name (the rest at their defaults).
    pub params: Vec<(String, f64)>,
    /// Initial particles.
    pub n0: u64,
    /// Mean size of a geometric start (1: monomers).
    pub mean: f64,
    /// Particles per unit volume at the start.
    pub concentration: f64,
}

impl BlocksStart {
    /// Counts `N_i` of the start: `n0` monomers, or a geometric law of mean `mean`
    /// (`N_i = round(n0 (1 − q) q^{i−1})`, q = 1 − 1/mean, to 50 means).
    fn counts(&self) -> Vec<u64> {
        if self.mean <= 1.0 {
            return vec![self.n0];
        }
        let q = 1.0 - 1.0 / self.mean;
        let mut p = 1.0 - q;
        (0..(50.0 * self.mean) as usize)
            .map(|_| {
                let c = (self.n0 as f64 * p).round() as u64;
                p *= q;
                c
            })
            .collect()
    }
}

/// One run of `scheme` through `times`; `None` past the wall-clock `budget`.
fn once(
    scheme: &str,
    start: &BlocksStart,
    times: &[f64],
    budget: Duration,
    seed: u64,
) -> Result<Vec<Option<Cell>>, String> {
    let (name, engine) = match scheme.split_once(':') {
        Some((name, engine)) => (name, Some(engine)),
        None => (scheme, None),
    };
    let info = registry::find(name).map_err(|e| e.to_string())?;
    let mut opts = Options::default();
    if let Some(engine) = engine {
        opts.set("engine", Value::Name(engine))
            .map_err(|e| format!("{scheme}: {e}"))?;
    }
    let params: Vec<(&str, f64)> = start.params.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    let kernel = &start.kernel;
    let Builtin::Coagulation(k) = builtin::make(kernel, &params).map_err(|e| e.to_string())? else {
        return Err(format!("{kernel}: not a coagulation kernel"));
    };
    let counts = start.counts();
    let n: u64 = counts.iter().sum();
    let init = Init::Counts {
        counts: &counts,
        volume: n as f64 / start.concentration,
    };
    let mut sim = registry::build::<_, _, coagula_core::random::Generator>(
        info,
        Model::coagulation(k, NoFragmentation),
        &init,
        &opts,
    )
    .map_err(|e| e.to_string())?;
    let mut rng = generator(seed, 0);
    let start = Instant::now();
    let mut out = Vec::new();
    for &t in times {
        if start.elapsed() > budget {
            out.push(None);
            continue;
        }
        let t0 = Instant::now();
        let rep = sim.advance_to(t, &mut rng).map_err(|e| e.to_string())?;
        out.push(Some(Cell {
            seconds: t0.elapsed().as_secs_f64(),
            proposals: rep.proposals,
            events: rep.events,
        }));
    }
    Ok(out)
}

/// The table (see the module docs); `budget` seconds per run.
pub fn blocks(
    start: &BlocksStart,
    schemes: &[String],
    times: &[f64],
    budget: f64,
    repeat: u32,
) -> Result<(), String> {
    let what = if start.mean <= 1.0 {
        "monomers".to_string()
    } else {
        format!("particles of geometric sizes, mean {}", start.mean)
    };
    println!(
        "{} kernel {:?} from {} {what} ({} per unit volume), seed 1; alternating runs, the fastest of {repeat} kept per interval; {budget} s a run",
        start.kernel, start.params, start.n0, start.concentration
    );
    let budget = Duration::from_secs_f64(budget);
    let mut best: Vec<Vec<Option<Cell>>> = vec![vec![None; times.len()]; schemes.len()];
    for _ in 0..repeat {
        for (s, scheme) in schemes.iter().enumerate() {
            let run = once(scheme, start, times, budget, 1)?;
            for (b, c) in best[s].iter_mut().zip(run) {
                if let Some(c) = c
                    && b.is_none_or(|b| c.seconds < b.seconds)
                {
                    *b = Some(c);
                }
            }
        }
    }
    println!(
        "{:>20} {:>22} {:>12} {:>11} {:>10} {:>9} {:>12} {:>10}",
        "scheme",
        "interval",
        "proposals",
        "events",
        "accepted",
        "seconds",
        "ns/proposal",
        "ns/event"
    );
    for (s, scheme) in schemes.iter().enumerate() {
        let mut from = 0.0;
        for (&t, c) in times.iter().zip(&best[s]) {
            let interval = format!("({from}, {t}]");
            from = t;
            let Some(c) = c else {
                println!("{scheme:>20} {interval:>22} {:>12}", "(past the budget)");
                continue;
            };
            println!(
                "{:>20} {:>22} {:>12} {:>11} {:>9.2}% {:>9.3} {:>12.1} {:>10.1}",
                scheme,
                interval,
                c.proposals,
                c.events,
                100.0 * c.events as f64 / c.proposals.max(1) as f64,
                c.seconds,
                c.seconds * 1e9 / c.proposals.max(1) as f64,
                c.seconds * 1e9 / c.events.max(1) as f64
            );
        }
    }
    Ok(())
}
