//! One module per subcommand, and the one place a command's result becomes an exit
//! code: `Ok(true)` succeeds, `Ok(false)` fails quietly (a validation that found a
//! failing case has printed it), `Err(message)` prints `error: message` and fails.

pub mod bench;
mod exact;
mod examples;
mod kernels;
mod qmc;
mod reproduce;
pub mod run;
mod schemes;
pub mod validate;
mod validate_discrete;
mod validate_sectional;

use crate::args::{BenchKind, Command};
use std::process::ExitCode;

/// A command's result (see the module docs).
pub type Done = Result<bool, String>;

/// `Ok(true)` of a step that either succeeded or failed with a message.
fn ok<E: std::fmt::Display>(r: Result<(), E>) -> Done {
    r.map(|()| true).map_err(|e| e.to_string())
}

/// The exit code of a command's result (printing its error).
pub fn exit(done: Done) -> ExitCode {
    match done {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs a command.
pub(crate) fn dispatch(command: Command) -> Done {
    match command {
        Command::Run {
            scenario,
            set,
            scheme,
            particles,
            m,
            steps,
            dt,
            points,
            replicas,
            seed,
            threads,
            csv,
            json,
            plot,
            rows,
            quiet,
            check,
            checkpoint,
        } => {
            let flags = run::Flags {
                scheme,
                particles,
                m,
                dt,
                points,
                replicas,
                seed,
                threads,
            };
            let outputs = run::Outputs {
                csv,
                json,
                plot,
                rows: rows as usize,
                quiet,
                check,
                checkpoint,
            };
            ok(run::command(
                scenario.as_deref(),
                set,
                flags,
                steps,
                outputs,
            ))
        }
        Command::Examples { name } => ok(examples::command(name.as_deref())),
        Command::Schemes { name } => ok(schemes::command(name.as_deref())),
        Command::Validate { quick, json, only } => validate::run(quick, json, only.as_deref()),
        Command::Reproduce {
            which,
            m_max,
            mc_seeds,
            rqmc,
            plot,
            figures,
            quick,
        } => ok(reproduce::command(
            which,
            m_max,
            mc_seeds,
            rqmc,
            plot.as_deref(),
            &figures,
            quick,
        )),
        Command::Exact {
            solution,
            coefficient,
            x,
            times,
            kmax,
        } => ok(exact::command(solution, coefficient, &x, &times, kmax)),
        Command::Kernels { min, max, points } => ok(kernels::command(min, max, points as usize)),
        Command::Qmc { dims, m } => ok(qmc::command(dims as usize, m)),
        Command::Bench { which } => bench_command(which),
    }
}

fn bench_command(which: BenchKind) -> Done {
    match which {
        BenchKind::Langevin {
            trajectories,
            dt,
            repeat,
        } => ok(crate::reproduce::maftei2016::bench(
            trajectories,
            dt,
            repeat,
        )),
        BenchKind::Dsmc {
            particles,
            times,
            budget,
            repeat,
            seed,
        } => {
            if !times.windows(2).all(|w| w[0] < w[1]) {
                return Err("--times must increase".into());
            }
            ok(crate::reproduce::osinsky2023::bench_dsmc(
                particles, &times, budget, repeat, seed,
            ))
        }
        BenchKind::Temperature {
            n0,
            times,
            scaled_n0,
            scaled_times,
            budget,
            repeat,
            seed,
            skip_baseline,
        } => {
            let increasing = |v: &[f64]| v.windows(2).all(|w| w[0] < w[1]);
            if !increasing(&times) || !increasing(&scaled_times) {
                return Err("--times and --scaled-times must increase".into());
            }
            let settings = crate::reproduce::osinsky2023::Table4 {
                n0,
                times,
                scaled_n0,
                scaled_times,
                budget,
                repeat,
                seed,
                skip_baseline,
            };
            ok(crate::reproduce::osinsky2023::bench(&settings))
        }
        BenchKind::Lowrank {
            n0,
            budget,
            ar_budget,
            inverse_budget,
            only,
            skip_baselines,
            repeat,
            seed,
        } => {
            let budgets = bench::Budgets {
                ar: ar_budget.unwrap_or(budget),
                inverse: inverse_budget.unwrap_or(budget),
            };
            if let Some((name, value)) = [
                ("--budget", budget),
                ("--ar-budget", budgets.ar),
                ("--inverse-budget", budgets.inverse),
            ]
            .into_iter()
            .find(|&(_, b)| !(b.is_finite() && b >= 0.0))
            {
                return Err(format!("{name} = {value} must be finite and >= 0 seconds"));
            }
            bench::lowrank(
                n0,
                budgets,
                only.map(|o| o.name().to_string()),
                skip_baselines,
                repeat,
                seed,
            );
            Ok(true)
        }
        BenchKind::Scenario {
            scenario,
            schemes,
            vary,
            set,
            repeat,
        } => ok(bench::scenario(
            scenario.as_deref(),
            &schemes,
            vary,
            set,
            repeat,
        )),
        BenchKind::LowrankSingle {
            kernel,
            n0,
            t,
            seed,
            binary,
            bucketed,
        } => {
            bench::lowrank_single(kernel.name(), n0, t, seed, binary, bucketed);
            Ok(true)
        }
        BenchKind::LowrankSmall {
            n0,
            len,
            t,
            replicas,
            host_steps,
        } => ok(match host_steps {
            Some(steps) => bench::lowrank_host_steps(&n0, replicas, steps),
            None => bench::lowrank_small(&n0, len, t, replicas),
        }),
        BenchKind::Blocks {
            kernel,
            params,
            schemes,
            n0,
            mean,
            concentration,
            times,
            budget,
            repeat,
        } => ok(bench::blocks(
            &bench::BlocksStart {
                kernel,
                params,
                n0,
                mean,
                concentration,
            },
            &schemes,
            &times,
            budget,
            repeat,
        )),
        BenchKind::Processes {
            scheme,
            n0,
            t,
            source,
            sink,
            repeat,
        } => ok(bench::processes(&scheme, n0, t, source, sink, repeat)),
        BenchKind::Peers {
            seeds,
            max_log2n,
            authors,
            problem,
        } => ok(bench::peers(
            seeds,
            max_log2n,
            authors,
            matches!(problem, crate::args::PeerProblem::Constant),
        )),
    }
}
