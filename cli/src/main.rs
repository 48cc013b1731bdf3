//! `coagula` — command-line interface of the coagula library.

use clap::{Parser, Subcommand, ValueEnum};
use coagula_core::exact::Exact;
use coagula_core::kernel::{Coagulation, check_low_rank, check_majorant, log_grid};
use std::process::ExitCode;

mod bench;
mod lecot;
mod plot;
mod validate;

/// A finite, positive number (end times, sizes).
fn positive_f64(v: &str) -> Result<f64, String> {
    let x: f64 = v.parse().map_err(|e| format!("{e}"))?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{v} is not a finite positive number"))
    }
}

/// One of Osinsky's tables (a kernel of the paper's benchmarks).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum PaperTable {
    /// The Brownian (continuum) kernel, table 1.
    Brownian,
    /// The free-molecular (ballistic) kernel on integer sizes, table 2.
    Ballistic,
    /// The linear (additive) kernel, table 3.
    Linear,
}

impl PaperTable {
    pub(crate) fn name(self) -> &'static str {
        match self {
            PaperTable::Brownian => "brownian",
            PaperTable::Ballistic => "ballistic",
            PaperTable::Linear => "linear",
        }
    }
}

/// The registry's options as the CLI uses them: the defaults, with the memory budget
/// of this machine (half its physical memory).
pub(crate) fn options() -> coagula_core::scheme::registry::Options {
    coagula_core::scheme::registry::Options::default()
        .with_memory_budget(coagula_core::scheme::population::machine_memory_budget())
}

#[derive(Parser)]
#[command(
    name = "coagula",
    version,
    about = "Stochastic particle simulation of coagulation and fragmentation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case. With no options: Lécot et al.'s coagulation-fragmentation test (QMC,
    /// N = 2^14, P = 400 steps to T = 1), printed against the exact moments.
    Run {
        /// log2 of the number of particles N.
        #[arg(long, default_value_t = 14)]
        m: u32,
        /// Number of time steps P to T = 1.
        #[arg(long, default_value_t = 400)]
        steps: u32,
        /// Point source.
        #[arg(long, value_enum, default_value = "qmc")]
        points: lecot::Points,
        /// Seed (MC and RQMC).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write t,M2,M2_exact,M3,M3_exact at the 100 checkpoints to this CSV file.
        #[arg(long)]
        csv: Option<String>,
        /// Draw the moments against the exact solution (an .svg file).
        #[arg(long)]
        plot: Option<String>,
    },
    /// Rerun the reproduction cases and compare with exact or published values.
    Validate {
        /// A subset that runs in under 2 minutes.
        #[arg(long)]
        quick: bool,
        /// Print a JSON array instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Reproduce a paper's experiment: `lecot2019` (Figures 1-2).
    Reproduce {
        /// Which experiment.
        #[arg(value_enum)]
        which: Experiment,
        /// Largest log2 N, 7..=24 (the paper's N = 2^7 .. 2^20).
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(7..=24))]
        m_max: u32,
        /// MC seeds averaged per cell (at least 1).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..))]
        mc_seeds: u64,
        /// RQMC randomisations per N (0 = none; otherwise at least 2, for an interval).
        #[arg(long, default_value_t = 20, value_parser = rqmc_count)]
        rqmc: u32,
        /// Draw Figure 2 (an .svg file).
        #[arg(long)]
        plot: Option<String>,
    },
    /// Print an exact solution (SPEC §3): moments, gel mass and n_k at given times.
    Exact {
        /// Which solution.
        #[arg(long, value_enum, default_value = "constant")]
        solution: Solution,
        /// Comma-separated times (a negative one is an error, not a flag).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "0,0.5,1,2,5",
            allow_negative_numbers = true
        )]
        times: Vec<f64>,
        /// Print n_1 .. n_kmax as well.
        #[arg(long, default_value_t = 0)]
        kmax: u64,
    },
    /// Print the t-values of the digital sequences (rank test on generating matrices).
    Qmc {
        /// Number of coordinates to analyse (1..=64).
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=64))]
        dims: u64,
        /// Largest m (block size 2^m) for the sequence t-values (1..=62).
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=62))]
        m: u32,
    },
    /// Benchmarks: `coagula bench lowrank` reruns Osinsky's tables 1-3.
    Bench {
        #[command(subcommand)]
        which: BenchKind,
    },
    /// Check every built-in kernel's bounds on a log grid and print the worst acceptance.
    Kernels {
        /// Smallest size of the grid, > 0 (1 = integer sizes, bounds narrowed to x ≥ 1).
        #[arg(long, default_value_t = 1.0, value_parser = positive_f64)]
        min: f64,
        /// Largest size of the grid (> min).
        #[arg(long, default_value_t = 1e9, value_parser = positive_f64)]
        max: f64,
        /// Grid points (at least 2).
        #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u64).range(2..=10_000_000))]
        points: u64,
    },
}

#[derive(Subcommand)]
enum BenchKind {
    /// Low-rank MC vs acceptance-rejection vs inverse, with the paper's figures.
    Lowrank {
        /// Initial number of monomers (the paper uses 1e7).
        #[arg(long, default_value_t = 10_000_000, value_parser = clap::value_parser!(u64).range(2..=u64::from(u32::MAX)))]
        n0: u64,
        /// Wall-clock budget per baseline run, in seconds (cells beyond it print "-").
        #[arg(long, default_value_t = 600.0)]
        budget: f64,
        /// Budget of the acceptance-rejection runs alone (default: --budget), e.g. to
        /// let it finish a row the paper timed beyond ten minutes.
        #[arg(long)]
        ar_budget: Option<f64>,
        /// Budget of the inverse runs alone (default: --budget); 0 skips them.
        #[arg(long)]
        inverse_budget: Option<f64>,
        /// Only this table.
        #[arg(long, value_enum)]
        only: Option<PaperTable>,
        /// Time only the low-rank method.
        #[arg(long)]
        skip_baselines: bool,
        /// Run the bucketed low-rank column this many times (fresh seeds) and keep each
        /// cell's fastest time: on a shared machine the minimum is the least disturbed.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
        repeat: u32,
        /// Seed of the random streams.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Low-rank only, one kernel to one time (for profiling).
    LowrankSingle {
        /// The table's kernel.
        #[arg(long, value_enum, default_value = "brownian")]
        kernel: PaperTable,
        /// Initial number of monomers.
        #[arg(long, default_value_t = 10_000_000, value_parser = clap::value_parser!(u64).range(2..=u64::from(u32::MAX)))]
        n0: u64,
        /// End time (finite, > 0).
        #[arg(long, default_value_t = 10.0, value_parser = positive_f64)]
        t: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Use the binary tree layout instead of the 8-ary one.
        #[arg(long)]
        binary: bool,
        /// Use the bucketed layout.
        #[arg(long)]
        bucketed: bool,
    },
    /// Small systems side by side: per-size tree vs bucketed low-rank, many replicas of
    /// a constant-kernel run from N0 monomers, reporting acceptance (events/proposals),
    /// seconds and the mean N/V with its standard error.
    LowrankSmall {
        /// Initial particle numbers, comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [32u64, 128, 256, 1000])]
        n0: Vec<u64>,
        /// Length of the initial count vector (monomers only; longer = larger M).
        #[arg(long, default_value_t = 1)]
        len: usize,
        /// End time.
        #[arg(long, default_value_t = 64.0)]
        t: f64,
        /// Replicas per layout.
        #[arg(long, default_value_t = 1000)]
        replicas: u64,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum Experiment {
    Lecot2019,
}

#[derive(Clone, Copy, ValueEnum)]
enum Solution {
    Constant,
    Additive,
    Multiplicative,
    MarcusLushnikov,
    CoagFrag,
}

/// An RQMC randomisation count: 0 (none) or at least 2 (an interval needs two).
fn rqmc_count(v: &str) -> Result<u32, String> {
    let r: u32 = v.parse().map_err(|e| format!("{e}"))?;
    if r == 1 {
        Err("1 randomisation gives no interval: use 0 or at least 2".into())
    } else {
        Ok(r)
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            m,
            steps,
            points,
            seed,
            csv,
            plot,
        } => {
            return match lecot::run_default(m, steps, points, seed, csv.as_deref(), plot.as_deref())
            {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Validate { quick, json } => {
            return if validate::run(quick, json) {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            };
        }
        Command::Reproduce {
            which: Experiment::Lecot2019,
            m_max,
            mc_seeds,
            rqmc,
            plot,
        } => {
            return match lecot::reproduce(m_max, mc_seeds, rqmc, plot.as_deref()) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Exact {
            solution,
            times,
            kmax,
        } => exact(solution, &times, kmax),
        Command::Kernels { min, max, points } => {
            if max > min {
                kernels(min, max, points as usize)
            } else {
                Err(coagula_core::Error::OutOfRange {
                    name: "--max",
                    value: max,
                    range: "(--min, inf)",
                })
            }
        }
        Command::Qmc { dims, m } => qmc_tvalues(dims as usize, m),
        Command::Bench {
            which:
                BenchKind::Lowrank {
                    n0,
                    budget,
                    ar_budget,
                    inverse_budget,
                    only,
                    skip_baselines,
                    repeat,
                    seed,
                },
        } => {
            let budgets = bench::Budgets {
                ar: ar_budget.unwrap_or(budget),
                inverse: inverse_budget.unwrap_or(budget),
            };
            let bad = [
                ("--budget", budget),
                ("--ar-budget", budgets.ar),
                ("--inverse-budget", budgets.inverse),
            ]
            .into_iter()
            .find(|&(_, b)| !(b.is_finite() && b >= 0.0));
            match bad {
                Some((name, value)) => Err(coagula_core::Error::OutOfRange {
                    name,
                    value,
                    range: "[0, inf) seconds",
                }),
                None => {
                    bench::lowrank(
                        n0,
                        budgets,
                        only.map(|o| o.name().to_string()),
                        skip_baselines,
                        repeat,
                        seed,
                    );
                    Ok(())
                }
            }
        }
        Command::Bench {
            which:
                BenchKind::LowrankSingle {
                    kernel,
                    n0,
                    t,
                    seed,
                    binary,
                    bucketed,
                },
        } => {
            bench::lowrank_single(kernel.name(), n0, t, seed, binary, bucketed);
            Ok(())
        }
        Command::Bench {
            which:
                BenchKind::LowrankSmall {
                    n0,
                    len,
                    t,
                    replicas,
                },
        } => bench::lowrank_small(&n0, len, t, replicas),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn exact(solution: Solution, times: &[f64], kmax: u64) -> Result<(), coagula_core::Error> {
    let e = match solution {
        Solution::Constant => Exact::constant(1.0)?,
        Solution::Additive => Exact::additive(),
        Solution::Multiplicative => Exact::multiplicative(),
        Solution::MarcusLushnikov => Exact::marcus_lushnikov(),
        Solution::CoagFrag => Exact::coagulation_fragmentation(),
    };
    let mut header = String::from("t,M0,M1,M2,M3,gel_mass");
    for k in 1..=kmax {
        header.push_str(&format!(",n{k}"));
    }
    println!("{header}");
    for &t in times {
        let mut line = format!("{t}");
        for m in 0..=3 {
            line.push_str(&format!(",{}", e.moment(m, t)?));
        }
        line.push_str(&format!(",{}", e.gel_mass(t)?));
        for k in 1..=kmax {
            line.push_str(&format!(",{}", e.number_density(k, t)?));
        }
        println!("{line}");
    }
    Ok(())
}

fn kernels(min: f64, max: f64, points: usize) -> Result<(), coagula_core::Error> {
    let grid = log_grid(min, max, points);
    let narrow = if min >= 1.0 { 1.0 } else { 0.0 };
    let all = [
        ("constant", Coagulation::constant(1.0)?),
        ("additive", Coagulation::additive()),
        ("multiplicative", Coagulation::multiplicative()),
        ("product a=0.8", Coagulation::product(0.8)?),
        ("homogeneous g=1.5", Coagulation::homogeneous(1.5)?),
        ("free-molecular", Coagulation::free_molecular()),
        ("brownian", Coagulation::brownian()),
    ];
    println!("grid {min:e}..{max:e}, {points} points; bounds for sizes >= {narrow}");
    println!(
        "{:<18} {:>9} {:>11} {:>11} {:>9} {:>11} {:>11}",
        "kernel", "maj.viol", "maj.max", "maj.worst", "lr.viol", "lr.max", "lr.worst"
    );
    println!(
        "(max = largest K/bound, 1 when tight; worst = smallest K/bound, the worst acceptance)"
    );
    for (name, k) in all {
        let k = k.with_min_size(narrow)?;
        let m = check_majorant(&k, &grid)?;
        let l = check_low_rank(&k, &grid)?;
        println!(
            "{name:<18} {:>9} {:>11.6} {:>11.3e} {:>9} {:>11.6} {:>11.3e}",
            m.violations + m.monotonicity_violations,
            m.max_ratio,
            m.worst_acceptance,
            l.violations,
            l.max_ratio,
            l.worst_acceptance
        );
    }
    Ok(())
}

fn qmc_tvalues(dims: usize, m: u32) -> Result<(), coagula_core::Error> {
    use coagula_core::qmc::{Niederreiter2, Sobol, net};
    let nied = Niederreiter2::<u64>::new(dims)?;
    let sobol = Sobol::<u64>::new(dims)?;
    println!("t-values by the rank test, blocks of 2^m for m <= {m}");
    println!("{:>6} {:>12} {:>8}", "coord", "Nied. poly", "Nied. t");
    for j in 0..dims {
        println!(
            "{:>6} {:>#12b} {:>8}",
            j + 1,
            nied.polynomial(j),
            net::t_value_sequence(&nied, &[j], m)
        );
    }
    for s in 1..=dims.min(6) {
        let c: Vec<usize> = (0..s).collect();
        println!(
            "first {s} dims: Niederreiter t = {} (theory {}), Sobol' t = {}",
            net::t_value_sequence(&nied, &c, m),
            Niederreiter2::<u64>::new(s)?.t_theory(),
            net::t_value_sequence(&sobol, &c, m)
        );
    }
    Ok(())
}
