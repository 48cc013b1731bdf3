//! A checked scenario: the plan the runner executes, its observables and the exact
//! solution it is compared with.

use super::{InitKind, Scenario};
use coagula_core::exact::Exact;
use coagula_core::initial::Distribution;
use coagula_core::kernel::{Coagulation, Fragmentation};
use coagula_core::random::Generator;
use coagula_core::scheme::facade::Simulation;
use coagula_core::scheme::facade::Start;
use coagula_core::scheme::facade::{Model, Options, SchemeId};
use coagula_core::scheme::registry;

/// An observable of the output.
#[derive(Clone, Debug, PartialEq)]
pub enum Observable {
    /// `M_m`, any real order.
    Moment(f64),
    /// `n_k`, integer size k.
    Density(u64),
    /// `C(a, b)`, sizes in the closed `[a, b]`.
    Concentration(f64, f64),
    /// `C[a, b)`, sizes in the half-open class `[a, b)` (adjacent classes add up).
    Class(f64, f64),
    /// The gel-mass estimate.
    Gel,
    /// Number of simulation particles.
    Particles,
    /// A named observable of the scheme (`mean-temperature`, `energy`, …).
    Named(String),
}

impl Observable {
    /// Parses `M2`, `M1.5`, `n1`, `C(100,200)`, `C[100,200)`, `gel`, `N`.
    pub fn parse(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let num = |v: &str| -> Result<f64, String> {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("observable {s:?}: {v:?} is not a finite number"))
        };
        if t == "gel" {
            Ok(Observable::Gel)
        } else if t == "N" {
            Ok(Observable::Particles)
        } else if let Some(m) = t.strip_prefix('M') {
            let m = num(m)?;
            if m.abs() > 64.0 {
                return Err(format!(
                    "observable {s:?}: moment order must be in [-64, 64]"
                ));
            }
            Ok(Observable::Moment(m))
        } else if let Some(k) = t.strip_prefix('n') {
            match k.parse::<u64>() {
                Ok(k) if k >= 1 => Ok(Observable::Density(k)),
                _ => Err(format!(
                    "observable {s:?}: n<k> needs an integer size k ≥ 1"
                )),
            }
        } else if let Some(r) = t.strip_prefix("C(").and_then(|r| r.strip_suffix(')')) {
            let (a, b) = r
                .split_once(',')
                .ok_or_else(|| format!("observable {s:?}: write C(a,b)"))?;
            let (a, b) = (num(a)?, num(b)?);
            if !(a > 0.0 && b >= a) {
                return Err(format!("observable {s:?}: needs 0 < a ≤ b"));
            }
            Ok(Observable::Concentration(a, b))
        } else if let Some(r) = t.strip_prefix("C[").and_then(|r| r.strip_suffix(')')) {
            let (a, b) = r
                .split_once(',')
                .ok_or_else(|| format!("observable {s:?}: write C[a,b)"))?;
            let (a, b) = (num(a)?, num(b)?);
            if !(a > 0.0 && b > a) {
                return Err(format!("observable {s:?}: needs 0 < a < b"));
            }
            Ok(Observable::Class(a, b))
        } else if !t.is_empty()
            && t.chars()
                .all(|c| c.is_ascii_lowercase() || c == '-' || c.is_ascii_digit())
        {
            Ok(Observable::Named(t.to_string()))
        } else {
            Err(format!(
                "observable {s:?}: expected M<order>, n<size>, C(a,b), C[a,b), gel, N or a name the scheme has (mean-temperature, …)"
            ))
        }
    }

    /// A column name (`M2`, `n1`, `C(100,200)`, `gel`, `N`).
    pub fn name(&self) -> String {
        match self {
            Observable::Moment(m) => format!("M{m}"),
            Observable::Density(k) => format!("n{k}"),
            Observable::Concentration(a, b) => format!("C({a},{b})"),
            Observable::Class(a, b) => format!("C[{a},{b})"),
            Observable::Gel => "gel".into(),
            Observable::Particles => "N".into(),
            Observable::Named(n) => n.clone(),
        }
    }

    /// What it means, for the table's legend.
    pub fn meaning(&self) -> String {
        match self {
            Observable::Moment(m) => {
                format!("moment of order {m}: ∫ x^{m} c(x,t) dx per unit volume")
            }
            Observable::Density(k) => format!("number concentration of size {k}"),
            Observable::Concentration(a, b) => {
                format!("number concentration of sizes in [{a}, {b}] (Eibeck & Wagner eq. 5.2)")
            }
            Observable::Class(a, b) => {
                format!("number concentration of the size class [{a}, {b}) (half-open: adjacent classes add up)")
            }
            Observable::Gel => {
                "largest cluster's mass per unit volume (Eibeck & Wagner eq. 6.15): the gel mass past gelation; before it a finite-N value that tends to 0 as N grows (no exact value or error shown)".into()
            }
            Observable::Particles => "number of simulation particles".into(),
            Observable::Named(n) => format!("the scheme's observable {n}"),
        }
    }
}

/// The exact solution of a scenario, in its units: `M_m(t) = c0 μ^m E.moment(m, t)`.
#[derive(Clone, Copy, Debug)]
pub struct ExactRef {
    /// The solution (with the scenario's time scale as its coefficient).
    pub solution: Exact,
    /// c0, the start's number concentration.
    pub c0: f64,
    /// μ, the start's size scale.
    pub mu: f64,
    /// What it is, for the legend.
    pub name: &'static str,
}

impl ExactRef {
    /// The exact value of an observable at t, where known.
    pub fn value(&self, o: &Observable, t: f64) -> Option<f64> {
        let e = &self.solution;
        match *o {
            Observable::Moment(m) if (0.0..=3.0).contains(&m) && m.fract() == 0.0 => e
                .moment(m as u32, t)
                .ok()
                .map(|v| self.c0 * self.mu.powf(m) * v),
            Observable::Density(k) if self.mu == 1.0 && !e.is_continuous() => {
                e.number_density(k, t).ok().map(|v| self.c0 * v)
            }
            Observable::Concentration(a, b)
                if self.mu == 1.0 && !e.is_continuous() && b - a <= 1e5 =>
            {
                let (lo, hi) = (a.ceil().max(1.0) as u64, b.floor() as u64);
                self.sum_density(lo, hi, t)
            }
            Observable::Class(a, b) if self.mu == 1.0 && !e.is_continuous() && b - a <= 1e5 => {
                // the integers in [a, b): ⌈a⌉ ..= ⌈b⌉ − 1
                let (lo, hi) = (a.ceil().max(1.0) as u64, b.ceil() as u64);
                if hi <= lo {
                    return Some(0.0);
                }
                self.sum_density(lo, hi - 1, t)
            }
            // the estimator (the largest cluster) is the gel mass only past gelation: where
            // the exact gel mass is 0 the table shows no exact value and no error
            Observable::Gel => e
                .gel_mass(t)
                .ok()
                .filter(|&g| g > 0.0)
                .map(|g| self.c0 * self.mu * g),
            _ => None,
        }
    }

    /// `c0 Σ_{k=lo}^{hi} n_k(t)` of the solution (0 for an empty range).
    fn sum_density(&self, lo: u64, hi: u64, t: f64) -> Option<f64> {
        let mut s = 0.0;
        for k in lo..=hi {
            s += self.solution.number_density(k, t).ok()?;
        }
        Some(self.c0 * s)
    }
}

/// A scenario checked and turned into what the runner needs.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The scenario as given (after overrides).
    pub scenario: Scenario,
    /// Title for output.
    pub title: String,
    /// The scheme.
    pub scheme: SchemeId,
    /// The built-in kernel's name (core's table).
    pub kernel_name: String,
    /// Its coefficient b (1 where it has none).
    pub coefficient: f64,
    /// Its units (`""`: dimensionless; else the physical units of the table).
    pub units: &'static str,
    /// The physics, in the simulation's size units.
    pub model: Model<Coagulation, Fragmentation>,
    /// The initial distribution.
    pub dist: Distribution,
    /// Simulation particles of a distribution (explicit lists give theirs).
    pub particles: usize,
    /// Number concentration of the start.
    pub c0: f64,
    /// Temperatures of the start (temperature models and gases): one per size.
    pub temperatures: Vec<f64>,
    /// The size one unit of the simulation stands for (`resolution` for integer-size
    /// schemes from a continuous start, else 1).
    pub size_unit: f64,
    /// The scheme's options (their seed and stream set per replica).
    pub options: Options,
    /// Output times.
    pub times: Vec<f64>,
    /// Observables.
    pub observables: Vec<Observable>,
    /// Replicas.
    pub replicas: u64,
    /// Seed.
    pub seed: u64,
    /// Threads (0 = all).
    pub threads: usize,
    /// The exact solution, where one is known.
    pub exact: Option<ExactRef>,
    /// What the sims will hold at most, summed over those running at once, in bytes.
    pub memory: u64,
    /// What `memory` assumes (the start, or the largest size at the end and its source).
    pub memory_basis: String,
    /// Warnings about the run, printed before it starts (a run past a gel point).
    pub warnings: Vec<String>,
    /// Edges of the size classes recorded for the size-distribution plot (scenario
    /// units; empty: none). Their concentrations follow the observables in each row.
    pub classes: Vec<f64>,
    /// Log axes in plots.
    pub log_axes: bool,
    /// The processes beside coagulation, in simulation units (`[source]`, `[sink]`,
    /// `[growth]`).
    pub processes: Option<coagula_core::process::Processes>,
}

/// The facade as the CLI instantiates it.
pub type Sim = dyn Simulation<Coagulation, Fragmentation, Generator>;

impl Plan {
    /// Values recorded per output time: the observables, then the size classes.
    pub fn columns(&self) -> usize {
        self.observables.len() + self.classes.len().saturating_sub(1)
    }

    /// Replica r's start: the quantile lattice shifted by `shift` (1/2: centred), or
    /// counts at temperatures (a gas's velocities drawn from the velocity stream of the
    /// seed and the replica).
    pub fn start(&self, shift: f64, replica: u64) -> Result<Start, String> {
        let r = if self.temperatures.is_empty() {
            self.dist
                .start(self.scheme, self.particles, self.c0, self.size_unit, shift)
        } else {
            self.dist.start_at_temperatures(
                self.scheme,
                self.particles,
                self.c0,
                &self.temperatures,
                self.seed,
                replica,
            )
        };
        r.map_err(|e| e.to_string())
    }

    /// Builds replica r's sim from `start` (its options' stream: the seed and the
    /// replica, which the RQMC scrambling draws from).
    pub fn build(&self, start: &Start, replica: u64) -> Result<Box<Sim>, String> {
        let opts = self.options.clone().with_stream(self.seed, replica);
        let mut sim = registry::build(self.scheme, self.model, &start.init(), &opts)
            .map_err(|e| e.to_string())?;
        if self.processes.is_some() {
            sim.set_processes(self.processes.clone())
                .map_err(|e| e.to_string())?;
        }
        Ok(sim)
    }

    /// Whether replicas draw random numbers beyond the start (every scheme but the
    /// time-stepped one on deterministic QMC points).
    pub fn randomised(&self) -> bool {
        self.scheme.randomised(&self.options)
    }
}

/// The exact solution of a scenario, where the library has one (`marcus_lushnikov`: the
/// scheme simulates that process, whose multiplicative-kernel limit differs from Flory's
/// after gelation).
pub(crate) fn exact_of(
    s: &Scenario,
    kernel: &str,
    b: f64,
    frag: Fragmentation,
    c0: f64,
    mu: f64,
    marcus_lushnikov: bool,
) -> Option<ExactRef> {
    let mono = s.initial.kind == InitKind::Monodisperse;
    let expo = s.initial.kind == InitKind::Exponential;
    let (e, lambda, name) = match (kernel, &frag) {
        ("constant", Fragmentation::BinaryUniform(_)) => {
            // only Lécot's test: K = 1, F = 2/(x+y), unit monomers
            let rate = s.fragmentation.as_ref().and_then(|f| f.rate).unwrap_or(1.0);
            if mono && b == 1.0 && rate == 1.0 && c0 == 1.0 && mu == 1.0 {
                return Some(ExactRef {
                    solution: Exact::coagulation_fragmentation(),
                    c0,
                    mu,
                    name: "coagulation-fragmentation moments (Lécot et al. 2019, §4)",
                });
            }
            return None;
        }
        (_, Fragmentation::BinaryUniform(_)) => return None,
        ("constant", _) if mono => (
            Exact::constant(1.0).ok()?,
            0.0,
            "constant kernel, monodisperse start",
        ),
        ("constant", _) if expo => (
            Exact::constant_exponential(1.0).ok()?,
            0.0,
            "constant kernel, exponential start",
        ),
        ("additive", _) if mono => (
            Exact::additive(),
            1.0,
            "additive kernel, monodisperse start",
        ),
        ("additive", _) if expo => (
            Exact::additive_exponential(),
            1.0,
            "Golovin's additive-kernel solution, exponential start",
        ),
        ("multiplicative", _) if mono && marcus_lushnikov => (
            Exact::marcus_lushnikov(),
            2.0,
            "multiplicative kernel, Marcus–Lushnikov limit (Eibeck & Wagner eq. 6.11)",
        ),
        ("multiplicative", _) if mono => (
            Exact::multiplicative(),
            2.0,
            "multiplicative kernel, Flory's solution (Eibeck & Wagner eqs. 6.8–6.9)",
        ),
        _ => return None,
    };
    // the solution from concentration c0 of size scale μ with coefficient b is the unit
    // one at time b c0 μ^λ t, with M_m scaled by c0 μ^m
    let e = e.with_coefficient(b * c0 * mu.powf(lambda)).ok()?;
    Some(ExactRef {
        solution: e,
        c0,
        mu,
        name,
    })
}
