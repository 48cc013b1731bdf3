//! A mass-flow step with the Niederreiter points against one with Monte Carlo points,
//! side by side: 2^20 particles on Lécot's case (K = 1, binary uniform fragmentation,
//! Δt = 1/400) from t = 0.25, the two stepped in alternation (which goes first
//! alternates per round), printing each one's fastest step and the ratio.
//!
//! ```text
//! cargo run --release -p coagula-core --example massflow_step_ratio -- 100
//! ```
//! The argument is the number of rounds (default 100).

use coagula_core::kernel::{BinaryUniform, Coagulation};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::massflow::{MassFlow, PointSource, Sorting};
use rand_pcg::Pcg64Mcg;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let rounds = match std::env::args().nth(1) {
        None => 100,
        Some(a) => match a.parse::<usize>() {
            Ok(r) if r > 0 => r,
            _ => {
                eprintln!("usage: massflow_step_ratio [ROUNDS] (a positive integer, got {a:?})");
                return ExitCode::FAILURE;
            }
        },
    };
    match run(rounds) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("massflow_step_ratio: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(rounds: usize) -> Result<(), coagula_core::Error> {
    let dt = 1.0 / 400.0;
    let start = |points| -> Result<_, coagula_core::Error> {
        let k = Coagulation::constant(1.0)?;
        let f = BinaryUniform::new(1.0)?;
        let mut sim = MassFlow::new(k, f, &vec![1.0; 1 << 20], 1.0, dt, points)?
            .with_sorting(Sorting::Adaptive);
        let mut rng = Pcg64Mcg::new(1);
        sim.advance_to(0.25, &mut rng)?;
        Ok((sim, rng))
    };
    let mut sims = [
        start(PointSource::niederreiter())?,
        start(PointSource::monte_carlo())?,
    ];
    let mut fastest = [f64::INFINITY; 2];
    for r in 0..rounds {
        for which in [r % 2, 1 - r % 2] {
            let (sim, rng) = &mut sims[which];
            let t = sim.time() + dt;
            let clock = Instant::now();
            sim.advance_to(t, rng)?;
            fastest[which] = fastest[which].min(clock.elapsed().as_secs_f64());
        }
    }
    println!(
        "fastest step of {rounds}: QMC {:.2} ms, MC {:.2} ms, QMC/MC {:.3}",
        fastest[0] * 1e3,
        fastest[1] * 1e3,
        fastest[0] / fastest[1]
    );
    Ok(())
}
