//! The command line as clap reads it: the subcommands and their arguments.

use crate::scenario;
use clap::{Parser, Subcommand, ValueEnum};

/// A count: a non-negative integer, written as one (`1000000`) or as a real with no
/// fractional part (`1e6`); a negative or fractional value is refused with a message
/// (not clap's tip about `--`).
pub(crate) fn count_arg(v: &str) -> Result<u64, String> {
    if let Ok(n) = v.parse::<u64>() {
        return Ok(n);
    }
    match v.trim().parse::<f64>() {
        Ok(x) if x >= 0.0 && x.fract() == 0.0 && x < 18_446_744_073_709_551_616.0 => Ok(x as u64),
        Ok(x) => Err(format!(
            "{x} is not a count (a non-negative integer; 1e6 is one)"
        )),
        Err(_) => Err(format!(
            "{v} is not a count (a non-negative integer; 1e6 is one)"
        )),
    }
}

/// A count ([`count_arg`]) in `[LO, HI]`.
pub(crate) fn count_in<const LO: u64, const HI: u64>(v: &str) -> Result<u64, String> {
    let n = count_arg(v)?;
    if (LO..=HI).contains(&n) {
        Ok(n)
    } else if HI == u64::MAX {
        Err(format!("{n} is below the least allowed, {LO}"))
    } else {
        Err(format!("{n} is outside [{LO}, {HI}]"))
    }
}

/// A finite, positive number (end times, sizes).
pub(crate) fn positive_f64(v: &str) -> Result<f64, String> {
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

#[derive(Parser)]
#[command(
    name = "coagula",
    version,
    about = "Stochastic particle simulation of coagulation and fragmentation"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Run a scenario (a TOML file, or the name of a built-in example: see `coagula
    /// examples`). With none: Lécot et al.'s coagulation-fragmentation test (mass flow,
    /// QMC, N = 2^14, P = 800 steps to T = 1) against the exact moments. Options
    /// override the scenario's values.
    Run {
        /// The scenario file or example name.
        scenario: Option<String>,
        /// Override a scenario value: `--set kernel.coefficient=2`, `--set
        /// output.observables='["M0","M2"]'` (TOML values; repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = scenario::parse_override)]
        set: Vec<(String, toml::Value)>,
        /// The scheme (`coagula schemes NAME` describes one).
        #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(
            coagula_core::scheme::registry::NAMES))]
        scheme: Option<String>,
        /// Number of simulation particles N0 (an integer; 1e6 is one).
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true)]
        particles: Option<u64>,
        /// log2 of the number of particles (mass flow: N = 2^m).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=30))]
        m: Option<u32>,
        /// Mass flow: number of steps P to the last output time (Δt = t_end/P).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
        steps: Option<u32>,
        /// Mass flow: the time step.
        #[arg(long, value_parser = positive_f64)]
        dt: Option<f64>,
        /// Mass flow: point set (niederreiter, sobol, mc; the scheme's `points` option).
        #[arg(long)]
        points: Option<String>,
        /// Independent replicas (run in parallel).
        #[arg(long, value_parser = count_in::<1, 1_000_000>, allow_negative_numbers = true)]
        replicas: Option<u64>,
        /// Seed, 0..=2^63-1 (replica r runs on its substream of the seed policy; replica
        /// 0 on the stream a C-ABI run with this seed uses).
        #[arg(long, value_parser = count_in::<0, {i64::MAX as u64}>, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Worker threads (0 = one per core; results do not depend on it).
        #[arg(long, value_parser = count_in::<0, 1024>, allow_negative_numbers = true)]
        threads: Option<u64>,
        /// Write every output time as CSV to this file (`-`: standard output).
        #[arg(long)]
        csv: Option<String>,
        /// Write the results as JSON to this file (`-`: standard output).
        #[arg(long)]
        json: Option<String>,
        /// Plot the observables against time, with confidence bands and the error
        /// against the exact solution (.svg or .png).
        #[arg(long)]
        plot: Option<String>,
        /// Rows of the terminal table (the CSV and JSON have every time).
        #[arg(long, default_value_t = 12, value_parser = count_in::<1, 100_000>, allow_negative_numbers = true)]
        rows: u64,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Check the scenario and the outputs, print the set-up, and stop without
        /// running.
        #[arg(long)]
        check: bool,
        /// Save every finished block of replicas in this directory, and take the
        /// blocks already saved there instead of running them again: a killed run
        /// resumes where it stopped, with the same results.
        #[arg(long, value_name = "DIR")]
        checkpoint: Option<String>,
    },
    /// List the schemes of the registry, or describe one with its options.
    Schemes {
        /// A scheme's name: its capabilities and options.
        name: Option<String>,
    },
    /// List the built-in example scenarios, or print one.
    Examples {
        /// An example's name: print its text.
        name: Option<String>,
    },
    /// Rerun the reproduction cases and compare with exact or published values.
    Validate {
        /// A subset that runs in under 2 minutes.
        #[arg(long)]
        quick: bool,
        /// Print a JSON array instead of the table.
        #[arg(long)]
        json: bool,
        /// Only the cases whose name starts with this (e.g. `eibeck2000/`).
        #[arg(long)]
        only: Option<String>,
    },
    /// Reproduce a paper's experiment: `lecot2019` (Figures 1-2), `eibeck2000`
    /// (Figures 1, 3, 5, 7 and the efficiency gain) or `maftei2016` (the Langevin
    /// test problem's step ladder, its open choices, kernels from first hits).
    Reproduce {
        /// Which experiment.
        #[arg(value_enum)]
        which: Experiment,
        /// eibeck2000: the figures to run (fig1, fig3, fig5, fig7, kappa, or all);
        /// maftei2016: the parts (ladder, choices, kernel, or all); lecot2019: grid
        /// (Figures 1-2), dt-ladder (deterministic QMC as Δt shrinks), or all.
        #[arg(long, value_delimiter = ',', default_value = "all")]
        figures: Vec<String>,
        /// eibeck2000: a tenth of the particles or replicas; maftei2016: 1/128 of the
        /// trajectories.
        #[arg(long)]
        quick: bool,
        /// Largest log2 N, 7..=24 (the paper's N = 2^7 .. 2^20).
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(7..=24))]
        m_max: u32,
        /// MC seeds averaged per cell (at least 1).
        #[arg(long, default_value_t = 4, value_parser = count_in::<1, {u64::MAX}>, allow_negative_numbers = true)]
        mc_seeds: u64,
        /// RQMC randomisations per N (0 = none; otherwise at least 2, for an interval).
        #[arg(long, default_value_t = 20, value_parser = rqmc_count)]
        rqmc: u32,
        /// lecot2019: draw Figure 2 (an .svg file); eibeck2000: a directory for
        /// `eibeck2000-<figure>.svg`; maftei2016: the bias plot (an .svg file).
        #[arg(long)]
        plot: Option<String>,
    },
    /// Print an exact solution: moments, gel mass, n_k (integer sizes) or c(x, t)
    /// (the exponential starts) at given times.
    Exact {
        /// Which solution.
        #[arg(long, value_enum, default_value = "constant")]
        solution: Solution,
        /// Kernel coefficient b (K = b K0): time runs b times faster.
        #[arg(long, default_value_t = 1.0, value_parser = positive_f64)]
        coefficient: f64,
        /// Sizes x at which to print c(x, t) (continuous solutions).
        #[arg(long, value_delimiter = ',', value_parser = positive_f64)]
        x: Vec<f64>,
        /// Comma-separated times, at most 100000 (a negative one is an error, not a flag).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "0,0.5,1,2,5",
            allow_negative_numbers = true
        )]
        times: Vec<f64>,
        /// Print n_1 .. n_kmax as well (at most 100000).
        #[arg(long, default_value_t = 0, value_parser = count_in::<0, 100_000>, allow_negative_numbers = true)]
        kmax: u64,
    },
    /// Print the t-values of the digital sequences (rank test on generating matrices).
    Qmc {
        /// Number of coordinates to analyse (1..=64).
        #[arg(long, default_value_t = 20, value_parser = count_in::<1, 64>, allow_negative_numbers = true)]
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
        #[arg(long, default_value_t = 400, value_parser = count_in::<2, 10_000_000>, allow_negative_numbers = true)]
        points: u64,
    },
}

#[derive(Subcommand)]
pub(crate) enum BenchKind {
    /// Schemes side by side on one scenario (default: the built-in one): wall time,
    /// events per second and the error against the exact solution, e.g.
    /// `coagula bench scenario quickstart-constant --schemes lowrank,inverse,rejection`
    /// or `coagula bench scenario --vary scheme.points=qmc,mc`.
    Scenario {
        /// Scenario file or example name.
        scenario: Option<String>,
        /// Schemes to compare (comma-separated registry names; default: the scenario's).
        #[arg(long, value_delimiter = ',')]
        schemes: Vec<String>,
        /// A setting to vary: `KEY=v1,v2,...` (TOML values).
        #[arg(long, value_parser = parse_vary)]
        vary: Option<(String, Vec<toml::Value>)>,
        /// Override a scenario value (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = scenario::parse_override)]
        set: Vec<(String, toml::Value)>,
        /// Alternating rounds; the fastest of each row is kept.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
        repeat: u32,
    },
    /// Langevin trajectory batches (Maftei et al. 2016): trajectory-steps per second on
    /// one thread and on all threads (the same bits), for the paper's 1-D specular and
    /// absorbing problems and a 3-D ball with friction.
    Langevin {
        /// Trajectories per run (at least 1).
        #[arg(long, default_value_t = 1 << 20, value_parser = count_in::<1, {u64::MAX}>, allow_negative_numbers = true)]
        trajectories: u64,
        /// Time step of the 1-D runs (> 0; the run goes to T = 3.2).
        #[arg(long, default_value_t = 0.05, value_parser = positive_f64)]
        dt: f64,
        /// Runs of each (the minimum time is reported).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        repeat: u32,
    },
    /// The temperature-dependent low-rank MC against acceptance-rejection on the
    /// paper's ballistic model (Osinsky 2023, table 4): seconds to reach each t, side
    /// by side with the paper's, and collisions per second against the paper's.
    Temperature {
        /// Initial monomers of the full-scale rows (the paper's 1e7).
        #[arg(long, default_value_t = 10_000_000, value_parser = count_in::<2, {1u64 << 32}>, allow_negative_numbers = true)]
        n0: u64,
        /// Times of the full-scale rows (comma-separated, increasing; the flag without a
        /// value skips them).
        #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "1e3,1e4", value_parser = positive_f64)]
        times: Vec<f64>,
        /// Initial monomers of the scaled rows.
        #[arg(long, default_value_t = 1 << 18, value_parser = count_in::<2, {1u64 << 32}>, allow_negative_numbers = true)]
        scaled_n0: u64,
        /// Times of the scaled rows (comma-separated, increasing; the flag without a
        /// value skips them).
        #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "1e5,1e6", value_parser = positive_f64)]
        scaled_times: Vec<f64>,
        /// Wall-clock budget of one run in seconds (cells beyond it print "-").
        #[arg(long, default_value_t = 1800.0, value_parser = positive_f64)]
        budget: f64,
        /// Alternating rounds of both methods (the fastest of each cell is kept).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
        repeat: u32,
        /// Seed of the random streams.
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true, default_value_t = 1)]
        seed: u64,
        /// Time only the low-rank method (the AR columns print "-").
        #[arg(long)]
        skip_baseline: bool,
    },
    /// Low-rank DSMC against acceptance-rejection on the paper's workload (Osinsky
    /// 2023, tables 5-6: N_k ~ exp(-a (k-1)), a = 0.1 and 0.01, eps = 0.99).
    Dsmc {
        /// Particles (about; the paper's tables are read as 1e5, the default is 1e6).
        #[arg(long, default_value_t = 1_000_000, value_parser = count_in::<100, {1u64 << 32}>, allow_negative_numbers = true)]
        particles: u64,
        /// Times (comma-separated, increasing).
        #[arg(long, value_delimiter = ',', default_value = "1,10,100", value_parser = positive_f64)]
        times: Vec<f64>,
        /// Wall-clock budget of one run in seconds (cells beyond it print "-").
        #[arg(long, default_value_t = 900.0, value_parser = positive_f64)]
        budget: f64,
        /// Alternating rounds of both methods (the fastest of each cell is kept).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
        repeat: u32,
        /// Seed of the random streams.
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true, default_value_t = 1)]
        seed: u64,
    },
    /// Low-rank MC vs acceptance-rejection vs inverse, with the paper's figures.
    Lowrank {
        /// Initial number of monomers (the paper uses 1e7).
        #[arg(long, default_value_t = 10_000_000, value_parser = count_in::<2, {u32::MAX as u64}>, allow_negative_numbers = true)]
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
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true, default_value_t = 1)]
        seed: u64,
    },
    /// Low-rank only, one kernel to one time (for profiling).
    LowrankSingle {
        /// The table's kernel.
        #[arg(long, value_enum, default_value = "brownian")]
        kernel: PaperTable,
        /// Initial number of monomers.
        #[arg(long, default_value_t = 10_000_000, value_parser = count_in::<2, {u32::MAX as u64}>, allow_negative_numbers = true)]
        n0: u64,
        /// End time (finite, > 0).
        #[arg(long, default_value_t = 10.0, value_parser = positive_f64)]
        t: f64,
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true, default_value_t = 1)]
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
        #[arg(long, value_parser = count_in::<2, {u64::MAX}>, value_delimiter = ',', default_values_t = [32u64, 128, 256, 1000])]
        n0: Vec<u64>,
        /// Length of the initial count vector (monomers only; longer = larger M).
        #[arg(long, default_value_t = 1)]
        len: usize,
        /// End time.
        #[arg(long, default_value_t = 64.0)]
        t: f64,
        /// Replicas per layout.
        #[arg(long, value_parser = count_in::<1, {u64::MAX}>, allow_negative_numbers = true, default_value_t = 1000)]
        replicas: u64,
        /// Instead: a host's stepping. The replicas are built once (cells), then all
        /// advanced through this many steps of about one event per cell each (times
        /// growing geometrically from 1, as the event rate falls like 1/t), the three
        /// layouts (per-size tree, bucketed, continuous sizes) side by side. Prints
        /// build cost per cell and stepping cost per event; shows the cost's growth
        /// with the largest size M. `--len` and `--t` do not apply.
        #[arg(long, value_parser = count_arg, allow_negative_numbers = true)]
        host_steps: Option<u64>,
    },
    /// Ours next to the figures measured for the peers (PySDM, PyPartMC) and for the
    /// authors' own code (Osinsky's Fortran), read from docs/results/peer-figures.csv
    /// (built in): Golovin's or the constant kernel from the exponential start with
    /// low-rank over sizes, at equal or better M0 and M2 error; with --authors, the paper's 13 rows
    /// from 1e7 monomers with the bucketed layout.
    Peers {
        /// Seeds per particle number (RMS errors over them).
        #[arg(long, default_value_t = 8, value_parser = count_in::<2, 10_000>, allow_negative_numbers = true)]
        seeds: u64,
        /// Largest particle number, as log2 (12..=24).
        #[arg(long, default_value_t = 18, value_parser = clap::value_parser!(u32).range(12..=24))]
        max_log2n: u32,
        /// Also run the paper's 13 rows against the authors' Fortran figures (about a
        /// minute).
        #[arg(long)]
        authors: bool,
        /// The peers' problem: Golovin's kernel to t = 5.4, or the constant kernel to
        /// t = 10, from the exponential start.
        #[arg(long, value_enum, default_value_t = PeerProblem::Golovin)]
        problem: PeerProblem,
    },
    /// Block majorants against the low-rank engine on a kernel no low-rank bound fits
    /// (the atmospheric kernel from monomers): acceptance and cost per interval of t.
    Blocks {
        /// Built-in coagulation kernel (at its default parameters).
        #[arg(long, default_value = "atmospheric")]
        kernel: String,
        /// Registry schemes, comma-separated; `NAME:ENGINE` pins the `engine` option
        /// (`lowrank:slots`: the low-rank bound, as before block majorants).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "lowrank-blocks,lowrank:slots"
        )]
        schemes: Vec<String>,
        /// The kernel's parameters, `NAME=VALUE` (repeatable; e.g. `unit-radius=1e-5` for
        /// the gravitational kernel).
        #[arg(long = "param", value_parser = name_value)]
        params: Vec<(String, f64)>,
        /// Initial particles.
        #[arg(long, default_value_t = 1_000_000, value_parser = count_in::<2, {1u64 << 32}>, allow_negative_numbers = true)]
        n0: u64,
        /// Mean size of a geometric start (1: monomers).
        #[arg(long, default_value_t = 1.0, value_parser = positive_f64)]
        mean: f64,
        /// Number concentration of the start (particles per unit volume).
        #[arg(long, default_value_t = 1.0, value_parser = positive_f64)]
        concentration: f64,
        /// The ends of the intervals of t, comma-separated, increasing.
        #[arg(long, value_delimiter = ',', default_value = "5,100,1000,3000")]
        times: Vec<f64>,
        /// Wall-clock seconds a run may take (the intervals after are skipped).
        #[arg(long, default_value_t = 120.0, value_parser = positive_f64)]
        budget: f64,
        /// Alternating rounds (the fastest of each interval kept).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
        repeat: u32,
    },
    /// What a monomer source and dilution cost per event against pure coagulation
    /// (K = 1 from monomers), the same start, alternating runs.
    Processes {
        /// Registry scheme (one that takes processes).
        #[arg(long, default_value = "lowrank")]
        scheme: String,
        /// Initial monomers (c0 = 1).
        #[arg(long, default_value_t = 1_000_000, value_parser = count_in::<2, {1u64 << 32}>, allow_negative_numbers = true)]
        n0: u64,
        /// End time (> 0).
        #[arg(long, default_value_t = 2.0, value_parser = positive_f64)]
        t: f64,
        /// Monomers injected per unit volume and time.
        #[arg(long, default_value_t = 0.5, value_parser = positive_f64)]
        source: f64,
        /// Dilution rate per particle.
        #[arg(long, default_value_t = 0.25, value_parser = positive_f64)]
        sink: f64,
        /// Alternating rounds (the fastest of each kept).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
        repeat: u32,
    },
}

/// A problem of `coagula bench peers`.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum PeerProblem {
    /// K = x + y to t = 5.4
    Golovin,
    /// K = 1 to t = 10
    Constant,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Experiment {
    Lecot2019,
    Eibeck2000,
    Maftei2016,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Solution {
    /// K = 1 from monomers.
    Constant,
    /// K = x + y from monomers.
    Additive,
    /// K = x y from monomers, Flory's post-gel solution (Eibeck & Wagner eqs. 6.8-6.9).
    Multiplicative,
    /// K = x y, Marcus-Lushnikov limit (Eibeck & Wagner eqs. 6.10-6.11).
    MarcusLushnikov,
    /// K = 1, F = 2/(x+y) (Lécot et al. 2019, §4): moments only.
    CoagFrag,
    /// K = 1 from c(x,0) = e^-x.
    ConstantExponential,
    /// Golovin: K = x + y from c(x,0) = e^-x.
    Golovin,
}

/// `KEY=v1,v2,...` for `bench scenario --vary`.
pub(crate) fn parse_vary(s: &str) -> Result<(String, Vec<toml::Value>), String> {
    let (k, vs) = s
        .split_once('=')
        .ok_or_else(|| format!("--vary {s}: write KEY=v1,v2,..."))?;
    let mut values = Vec::new();
    for v in vs.split(',') {
        values.push(scenario::parse_override(&format!("{k}={v}"))?.1);
    }
    if values.is_empty() {
        return Err(format!("--vary {s}: no values"));
    }
    Ok((k.trim().to_string(), values))
}

/// An RQMC randomisation count: 0 (none) or at least 2 (an interval needs two).
pub(crate) fn rqmc_count(v: &str) -> Result<u32, String> {
    let r: u32 = v.parse().map_err(|e| format!("{e}"))?;
    if r == 1 {
        Err("1 randomisation gives no interval: use 0 or at least 2".into())
    } else {
        Ok(r)
    }
}

/// `NAME=VALUE` with a finite number.
fn name_value(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("{s:?}: write NAME=VALUE"))?;
    let v: f64 = v
        .parse()
        .map_err(|_| format!("{s:?}: {v:?} is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{s:?}: not finite"));
    }
    Ok((k.to_string(), v))
}
