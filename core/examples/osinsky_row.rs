//! One of Osinsky's low-rank rows, from 10^7 monomers, through the registry's `lowrank`
//! scheme and nothing else: the smallest program that embeds the library, used to
//! compare peak memory with the authors' own small driver (docs/results/).
//!
//! ```text
//! cargo run --release -p coagula-core --example osinsky_row -- brownian 10
//! ```
//! Kernels: `brownian`, `ballistic` (free-molecular, sizes ≥ 1), `linear` (K = i + j).
//! Prints the collisions, M (the largest size the state can hold), N(t)/V and the wall
//! time.

use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
use coagula_core::scheme::registry;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: osinsky_row brownian|ballistic|linear T (T > 0)";
    let t = args
        .get(1)
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|t| t.is_finite() && *t > 0.0);
    let (Some(name), Some(t)) = (args.first(), t) else {
        eprintln!("{usage}");
        return ExitCode::FAILURE;
    };
    let kernel = match name.as_str() {
        "brownian" => Ok(Coagulation::brownian()),
        "ballistic" => Coagulation::free_molecular().with_min_size(1.0),
        "linear" => Ok(Coagulation::additive()),
        _ => {
            eprintln!("{usage}");
            return ExitCode::FAILURE;
        }
    };
    let n0 = 10_000_000u64;
    let init = Init::Counts {
        counts: &[n0],
        volume: n0 as f64,
    };
    let start = Instant::now();
    let run = kernel.and_then(|k| {
        let mut sim: Box<dyn Simulation<Coagulation, NoFragmentation, Generator>> =
            registry::build(
                registry::find("lowrank").unwrap(),
                Model::coagulation(k, NoFragmentation),
                &init,
                &Options::default(),
            )?;
        let mut rng = generator(1, 0);
        let rep = sim.advance_to(t, &mut rng)?;
        Ok((rep.events, sim.max_size().unwrap_or(0), sim.moment(0.0)))
    });
    match run {
        Ok((events, m, nv)) => {
            let s = start.elapsed().as_secs_f64();
            println!("{name} t={t}: {events} collisions, M={m}, N/V={nv:.6e}, {s:.3} s");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("osinsky_row: {e}");
            ExitCode::FAILURE
        }
    }
}
