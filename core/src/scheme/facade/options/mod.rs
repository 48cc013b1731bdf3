//! The settings of a scheme, by name, validated here once for every front end.
//!
//! Every setting is a key of [`KEYS`]: its name (the CLI's `[scheme]` key, the C ABI's
//! `coag_options_set_*` name, Python's keyword with `_` for `-`), what kind of value it
//! takes, its default and what it does. A registry entry lists the keys that apply to
//! it ([`SchemeInfo::options`](super::SchemeInfo::options)); a key set explicitly on a
//! scheme it does not apply to is refused at build ([`Error::OptionNotApplicable`]), so
//! the same mistake gets the same message from Rust, C, the CLI and Python.
//!
//! # Example
//! ```
//! use coagula_core::scheme::facade::{Options, Value};
//! let mut opts = Options::default();
//! opts.set("dt", Value::Real(0.005)).unwrap();
//! opts.set("points", Value::Name("sobol")).unwrap();
//! // 1e6-style counts are integers too
//! opts.set("size-limit", Value::Real(1e6)).unwrap();
//! assert_eq!(opts.size_limit(), 1_000_000);
//! assert!(opts.set("dt", Value::Real(-1.0)).is_err());
//! assert!(opts.set("no-such-key", Value::Flag(true)).is_err());
//! ```

use crate::error::{Error, Result};
use crate::qmc::Randomization;
use crate::qmc::points::PointSource;
use crate::random::{Purpose, substream};

/// The point set of the time-driven mass-flow scheme (Lécot et al. 2019, §3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Points {
    /// Niederreiter's (1,3)-sequence in base 2 (the paper's QMC).
    #[default]
    Niederreiter,
    /// Sobol' (Joe–Kuo direction numbers).
    Sobol,
    /// Pseudo-random points (plain Monte Carlo, the paper's MC twin).
    MonteCarlo,
}

/// How the time-driven mass-flow scheme keeps its particles sorted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sorting {
    /// Merge the few changed particles into the unchanged, still sorted, rest.
    #[default]
    Adaptive,
    /// A full unstable sort every step (for comparison).
    Full,
}

/// How the event-driven particle schemes draw particles by weight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    /// Flat sum trees in the workspace: `O(log n)` per draw and per update.
    SumTree,
    /// The paper's group acceptance–rejection (Eibeck & Wagner 2000 §5.1), with binades
    /// as the groups: about two tries per draw, `O(1)` updates for a weight that stays
    /// in its binade. Its index tables (four words per particle and weight) are
    /// allocated at construction, outside the workspace.
    Groups,
}

/// The engine of the bucketed low-rank scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BucketMode {
    /// Slots and alias tables: O(1) per proposal, fastest for large systems.
    Slots,
    /// Exact bucket counts in a sum tree: fastest for small systems.
    Counted,
    /// Block majorants over the size-pair matrix (`docs/design/block-majorants.md`):
    /// for kernels whose low-rank bound is loose or missing. Chosen when the kernel
    /// says its low-rank bound is loose, or has none or one of rank above 4, and it
    /// bounds blocks (`lowrank::prefers_blocks`).
    Blocks,
}

impl BucketMode {
    /// The engine's name, as the `engine` option takes it (NUL-terminated for C).
    pub const fn c_name(self) -> &'static core::ffi::CStr {
        match self {
            BucketMode::Slots => c"slots",
            BucketMode::Counted => c"counted",
            BucketMode::Blocks => c"blocks",
        }
    }

    /// The engine's name, as the `engine` option takes it.
    pub fn name(self) -> &'static str {
        // (the names are ASCII)
        self.c_name().to_str().unwrap_or("")
    }
}

/// How low-rank DSMC draws collision directions (Osinsky 2023 §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Directions {
    /// Integrated out: a pair is proposed against the bound of its rate averaged over
    /// the direction e, accepted with `|V_k − V_l|` over it, and e then drawn from its
    /// conditional law. Half the proposals of [`Uniform`](Self::Uniform).
    #[default]
    Conditional,
    /// Uniform on the sphere, and the pair accepted on `|(V_k − V_l)·e|` against twice
    /// that bound: the seed's eqs. 42 (per-size trees) and 43 (acceptance–rejection),
    /// kept as the paper's baseline.
    Uniform,
}

/// What kind of value a key takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A finite real number.
    Real,
    /// A non-negative integer (a real with no fractional part is accepted: `1e6`).
    Count,
    /// On or off.
    Flag,
    /// One of the names listed.
    Name(&'static [&'static str]),
}

/// A value given for a key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value<'a> {
    /// A real number.
    Real(f64),
    /// An integer.
    Count(u64),
    /// On or off.
    Flag(bool),
    /// A name.
    Name(&'a str),
}

/// One setting.
#[derive(Clone, Copy, Debug)]
pub struct Key {
    /// Its name.
    pub name: &'static str,
    /// What it takes.
    pub kind: Kind,
    /// Its default, as text.
    pub default: &'static str,
    /// What it does.
    pub doc: &'static str,
    /// Whether a checkpoint written under another value of it is refused (`false` for
    /// the settings a restored state may move between: the random stream, the memory
    /// budget, the capacity).
    pub must_match: bool,
}

/// Every key, in the order of their bits in [`Options`] and of a checkpoint's record.
pub const KEYS: &[Key] = &[
    Key {
        name: "dt",
        kind: Kind::Real,
        default: "0.01",
        doc: "time step of the time-driven schemes (> 0)",
        must_match: true,
    },
    Key {
        name: "points",
        kind: Kind::Name(&["niederreiter", "sobol", "mc"]),
        default: "niederreiter",
        doc: "point set of the mass-flow scheme: Niederreiter's (1,3)-sequence, Sobol', or pseudo-random (MC)",
        must_match: true,
    },
    Key {
        name: "randomization",
        kind: Kind::Name(&["none", "shift", "matousek", "owen"]),
        default: "none",
        doc: "randomisation of the point set (RQMC): none, a digital shift, Matousek's linear scrambling, Owen's nested scrambling; drawn from the seed's scrambling stream",
        must_match: true,
    },
    Key {
        name: "sorting",
        kind: Kind::Name(&["adaptive", "full"]),
        default: "adaptive",
        doc: "how the mass-flow scheme keeps its particles sorted: merge the changed ones (adaptive) or sort all (full)",
        must_match: true,
    },
    Key {
        name: "size-limit",
        kind: Kind::Count,
        default: "4294967296",
        doc: "largest particle size of the integer-size schemes (>= 2); a merge past it is a capacity error",
        must_match: true,
    },
    Key {
        name: "memory-budget",
        kind: Kind::Count,
        default: "half the machine's memory",
        doc: "bytes the growing schemes may hold; growth past it is a capacity error with the state unchanged",
        must_match: false,
    },
    Key {
        name: "batched-clock",
        kind: Kind::Flag,
        default: "true",
        doc: "low-rank schemes: draw proposal times in batches (faster; a run then depends on where a host stops it)",
        must_match: true,
    },
    Key {
        name: "capacity",
        kind: Kind::Count,
        default: "0",
        doc: "particle capacity of direct simulation (0: the initial number, four times it with fragmentation)",
        must_match: false,
    },
    Key {
        name: "truncation",
        kind: Kind::Real,
        default: "inf",
        doc: "truncation b_N of the mass flow algorithm: a coagulation past it removes the particle (inf: none)",
        must_match: true,
    },
    Key {
        name: "strict-bound",
        kind: Kind::Flag,
        default: "false",
        doc: "event-driven schemes: a kernel above its product majorant is an error instead of a counted violation",
        must_match: true,
    },
    Key {
        name: "sampler",
        kind: Kind::Name(&["default", "tree", "groups"]),
        default: "default",
        doc: "how mfa and dsa draw particles by weight: sum trees or the paper's groups (default: groups for mfa, the tree for dsa)",
        must_match: true,
    },
    Key {
        name: "engine",
        kind: Kind::Name(&["auto", "slots", "counted", "blocks"]),
        default: "auto",
        doc: "the low-rank scheme's engine: slots and alias tables (large systems), exact bucket counts (small ones), block majorants (kernels with a loose or no low-rank bound), or chosen by the kernel and the particle number",
        must_match: true,
    },
    Key {
        name: "directions",
        kind: Kind::Name(&["conditional", "uniform"]),
        default: "conditional",
        doc: "DSMC collision directions: from their conditional law, or uniform on the sphere (the paper's eqs. 42-43 baseline)",
        must_match: true,
    },
    Key {
        name: "seed",
        kind: Kind::Count,
        default: "0",
        doc: "seed of the sim's random stream (seed policy: seed, stream -> generator) and of its point scrambling",
        must_match: false,
    },
    Key {
        name: "stream",
        kind: Kind::Count,
        default: "0",
        doc: "stream of the seed policy",
        must_match: false,
    },
];

/// The names of the keys, in table order.
pub const KEY_NAMES: [&str; KEYS.len()] = {
    let mut out = [""; KEYS.len()];
    let mut i = 0;
    while i < KEYS.len() {
        out[i] = KEYS[i].name;
        i += 1;
    }
    out
};

fn unknown_key() -> Error {
    Error::UnknownName {
        what: "option",
        known: &KEY_NAMES,
    }
}

/// The keys every scheme takes.
pub const GENERAL: &[&str] = &["seed", "stream"];

/// The index of a key by name.
pub fn key_index(name: &str) -> Option<usize> {
    KEYS.iter().position(|k| k.name == name)
}

/// The settings of a scheme (see the module docs). `Default` gives every key its
/// default; [`set`](Self::set) and the `with_*` methods set one, remembering that it
/// was given (a given key that does not apply to the scheme is an error at build).
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    dt: f64,
    points: Points,
    randomization: Randomization,
    sorting: Sorting,
    size_limit: u64,
    memory_budget: usize,
    batched_clock: bool,
    capacity: usize,
    truncation: f64,
    strict_bound: bool,
    sampler: Option<Sampler>,
    engine: Option<BucketMode>,
    directions: Directions,
    seed: u64,
    stream: u64,
    /// Bit i: `KEYS[i]` was given.
    given: u32,
}

impl Default for Options {
    /// Every key at its default (the memory budget: half the machine's memory with the
    /// `std` feature, [`DEFAULT_MEMORY_BUDGET`](crate::memory::DEFAULT_MEMORY_BUDGET)
    /// without).
    fn default() -> Self {
        Options {
            dt: 0.01,
            points: Points::Niederreiter,
            randomization: Randomization::None,
            sorting: Sorting::Adaptive,
            size_limit: crate::memory::DEFAULT_SIZE_LIMIT,
            memory_budget: crate::memory::default_memory_budget(),
            batched_clock: true,
            capacity: 0,
            truncation: f64::INFINITY,
            strict_bound: false,
            sampler: None,
            engine: None,
            directions: Directions::Conditional,
            seed: 0,
            stream: 0,
            given: 0,
        }
    }
}

/// The error of a value of the wrong kind for `key`.
fn wrong_kind(key: &'static Key) -> Error {
    Error::OptionValue {
        key: key.name,
        expected: match key.kind {
            Kind::Real => "a finite real number",
            Kind::Count => "a non-negative integer",
            Kind::Flag => "true or false",
            Kind::Name(_) => "one of the names the key lists",
        },
    }
}

fn real(key: &'static Key, v: Value<'_>) -> Result<f64> {
    match v {
        Value::Real(x) if !x.is_nan() => Ok(x),
        Value::Count(n) => Ok(n as f64),
        _ => Err(wrong_kind(key)),
    }
}

fn count(key: &'static Key, v: Value<'_>) -> Result<u64> {
    match v {
        Value::Count(n) => Ok(n),
        // 1e6 is an integer; 2^64 and above, negative or fractional values are not
        Value::Real(x)
            if (0.0..18_446_744_073_709_551_616.0).contains(&x) && libm::trunc(x) == x =>
        {
            Ok(x as u64)
        }
        _ => Err(wrong_kind(key)),
    }
}

fn flag(key: &'static Key, v: Value<'_>) -> Result<bool> {
    match v {
        Value::Flag(b) => Ok(b),
        Value::Count(0) => Ok(false),
        Value::Count(1) => Ok(true),
        _ => Err(wrong_kind(key)),
    }
}

fn name(key: &'static Key, v: Value<'_>) -> Result<usize> {
    let Kind::Name(names) = key.kind else {
        return Err(wrong_kind(key));
    };
    match v {
        Value::Name(s) => names
            .iter()
            .position(|&n| n == s)
            .ok_or(Error::OptionValue {
                key: key.name,
                expected: key_names_message(key),
            }),
        _ => Err(wrong_kind(key)),
    }
}

/// "one of a, b, c" for a key of names (static: the table is).
fn key_names_message(key: &Key) -> &'static str {
    match key.name {
        "points" => "one of niederreiter, sobol, mc",
        "randomization" => "one of none, shift, matousek, owen",
        "sorting" => "one of adaptive, full",
        "sampler" => "one of default, tree, groups",
        "engine" => "one of auto, slots, counted, blocks",
        "directions" => "one of conditional, uniform",
        _ => "one of the names the key lists",
    }
}

impl Options {
    /// Sets key `key` to `value`, checking both (an unknown key, a value of the wrong
    /// kind or outside the key's range is an error and changes nothing).
    pub fn set(&mut self, key: &str, value: Value<'_>) -> Result<()> {
        let i = key_index(key).ok_or(unknown_key())?;
        let k = &KEYS[i];
        let mut next = self.clone();
        match k.name {
            "dt" => next.dt = check_dt(real(k, value)?)?,
            "points" => {
                next.points =
                    [Points::Niederreiter, Points::Sobol, Points::MonteCarlo][name(k, value)?]
            }
            "randomization" => {
                next.randomization = [
                    Randomization::None,
                    Randomization::DigitalShift,
                    Randomization::Matousek,
                    Randomization::Owen,
                ][name(k, value)?]
            }
            "sorting" => next.sorting = [Sorting::Adaptive, Sorting::Full][name(k, value)?],
            "size-limit" => next.size_limit = check_size_limit(count(k, value)?)?,
            "memory-budget" => {
                next.memory_budget = usize::try_from(count(k, value)?).unwrap_or(usize::MAX)
            }
            "batched-clock" => next.batched_clock = flag(k, value)?,
            "capacity" => {
                next.capacity = usize::try_from(count(k, value)?).map_err(|_| Error::Capacity {
                    name: "capacity (address space)",
                    capacity: usize::MAX,
                })?
            }
            "truncation" => next.truncation = check_truncation(real(k, value)?)?,
            "strict-bound" => next.strict_bound = flag(k, value)?,
            "sampler" => {
                next.sampler =
                    [None, Some(Sampler::SumTree), Some(Sampler::Groups)][name(k, value)?]
            }
            "engine" => {
                next.engine = [
                    None,
                    Some(BucketMode::Slots),
                    Some(BucketMode::Counted),
                    Some(BucketMode::Blocks),
                ][name(k, value)?]
            }
            "directions" => {
                next.directions = [Directions::Conditional, Directions::Uniform][name(k, value)?]
            }
            "seed" => next.seed = count(k, value)?,
            "stream" => next.stream = count(k, value)?,
            _ => return Err(unknown_key()),
        }
        next.given |= 1 << i;
        *self = next;
        Ok(())
    }

    /// Whether key `key` was given (set explicitly).
    pub fn is_given(&self, key: &str) -> bool {
        key_index(key).is_some_and(|i| self.given & (1 << i) != 0)
    }

    /// The keys given, in [`KEYS`] order.
    pub fn given(&self) -> impl Iterator<Item = &'static Key> + '_ {
        KEYS.iter()
            .enumerate()
            .filter(|(i, _)| self.given & (1 << i) != 0)
            .map(|(_, k)| k)
    }

    /// Checks every value (what [`set`](Self::set) checks, for values set with the
    /// `with_*` methods) and that every given key applies to `scheme`, whose keys are
    /// `applies` (plus [`GENERAL`]).
    pub fn check_for(&self, scheme: &'static str, applies: &[&str]) -> Result<()> {
        check_dt(self.dt)?;
        check_size_limit(self.size_limit)?;
        check_truncation(self.truncation)?;
        for k in self.given() {
            if !applies.contains(&k.name) && !GENERAL.contains(&k.name) {
                return Err(Error::OptionNotApplicable {
                    key: k.name,
                    scheme,
                });
            }
        }
        Ok(())
    }

    /// The value of every key as a word (reals by their bits, names by their index), in
    /// [`KEYS`] order: a checkpoint's record of the settings.
    pub fn words(&self) -> [u64; 15] {
        let opt = |o: Option<u64>| o.map_or(0, |v| v + 1);
        [
            self.dt.to_bits(),
            self.points as u64,
            self.randomization as u64,
            self.sorting as u64,
            self.size_limit,
            self.memory_budget as u64,
            u64::from(self.batched_clock),
            self.capacity as u64,
            self.truncation.to_bits(),
            u64::from(self.strict_bound),
            opt(self.sampler.map(|s| s as u64)),
            opt(self.engine.map(|e| e as u64)),
            self.directions as u64,
            self.seed,
            self.stream,
        ]
    }

    /// The point source the settings describe: the point set, randomised (when asked)
    /// from the scrambling stream of `(seed, stream)` of the seed policy, so the sim's own
    /// stream is the same with and without it. Errors: randomised Monte Carlo points.
    pub fn point_source(&self) -> Result<PointSource> {
        let mut scramble = substream(self.seed, self.stream, Purpose::Scrambling);
        Ok(match (self.points, self.randomization) {
            (Points::Niederreiter, Randomization::None) => PointSource::niederreiter(),
            (Points::Sobol, Randomization::None) => PointSource::sobol(),
            (Points::MonteCarlo, Randomization::None) => PointSource::monte_carlo(),
            (Points::Niederreiter, r) => PointSource::randomized_niederreiter(r, &mut scramble),
            (Points::Sobol, r) => PointSource::randomized_sobol(r, &mut scramble),
            (Points::MonteCarlo, _) => {
                return Err(Error::Unsupported {
                    what: "randomization of Monte Carlo points (they are random already)",
                });
            }
        })
    }

    fn mark(mut self, key: &str) -> Self {
        if let Some(i) = key_index(key) {
            self.given |= 1 << i;
        }
        self
    }

    /// The time step (`dt`).
    pub fn dt(&self) -> f64 {
        self.dt
    }
    /// The point set (`points`).
    pub fn points(&self) -> Points {
        self.points
    }
    /// The randomisation (`randomization`).
    pub fn randomization(&self) -> Randomization {
        self.randomization
    }
    /// The sorting (`sorting`).
    pub fn sorting(&self) -> Sorting {
        self.sorting
    }
    /// The size limit (`size-limit`).
    pub fn size_limit(&self) -> u64 {
        self.size_limit
    }
    /// The memory budget in bytes (`memory-budget`).
    pub fn memory_budget(&self) -> usize {
        self.memory_budget
    }
    /// Batched proposal times (`batched-clock`).
    pub fn batched_clock(&self) -> bool {
        self.batched_clock
    }
    /// Direct simulation's capacity (`capacity`; 0: automatic).
    pub fn capacity(&self) -> usize {
        self.capacity
    }
    /// The truncation (`truncation`).
    pub fn truncation(&self) -> f64 {
        self.truncation
    }
    /// Bound violations are errors (`strict-bound`).
    pub fn strict_bound(&self) -> bool {
        self.strict_bound
    }
    /// The sampler (`sampler`; `None`: the scheme's default).
    pub fn sampler(&self) -> Option<Sampler> {
        self.sampler
    }
    /// The bucketed engine (`engine`; `None`: chosen by size).
    pub fn engine(&self) -> Option<BucketMode> {
        self.engine
    }
    /// The DSMC directions (`directions`).
    pub fn directions(&self) -> Directions {
        self.directions
    }
    /// The seed (`seed`).
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The stream (`stream`).
    pub fn stream(&self) -> u64 {
        self.stream
    }

    /// Sets `dt`.
    pub fn with_dt(mut self, dt: f64) -> Self {
        self.dt = dt;
        self.mark("dt")
    }
    /// Sets `points`.
    pub fn with_points(mut self, points: Points) -> Self {
        self.points = points;
        self.mark("points")
    }
    /// Sets `randomization`.
    pub fn with_randomization(mut self, r: Randomization) -> Self {
        self.randomization = r;
        self.mark("randomization")
    }
    /// Sets `sorting`.
    pub fn with_sorting(mut self, sorting: Sorting) -> Self {
        self.sorting = sorting;
        self.mark("sorting")
    }
    /// Sets `size-limit`.
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.size_limit = limit;
        self.mark("size-limit")
    }
    /// Sets `memory-budget` (bytes).
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.memory_budget = bytes;
        self.mark("memory-budget")
    }
    /// Sets `batched-clock`.
    pub fn with_batched_clock(mut self, on: bool) -> Self {
        self.batched_clock = on;
        self.mark("batched-clock")
    }
    /// Sets `capacity` (0: automatic).
    pub fn with_capacity(mut self, particles: usize) -> Self {
        self.capacity = particles;
        self.mark("capacity")
    }
    /// Sets `truncation`.
    pub fn with_truncation(mut self, b: f64) -> Self {
        self.truncation = b;
        self.mark("truncation")
    }
    /// Sets `strict-bound`.
    pub fn with_strict_bound(mut self, strict: bool) -> Self {
        self.strict_bound = strict;
        self.mark("strict-bound")
    }
    /// Sets `sampler`.
    pub fn with_sampler(mut self, sampler: Option<Sampler>) -> Self {
        self.sampler = sampler;
        self.mark("sampler")
    }
    /// Sets `engine` (`None`: chosen by size).
    pub fn with_engine(mut self, mode: Option<BucketMode>) -> Self {
        self.engine = mode;
        self.mark("engine")
    }
    /// Sets `directions`.
    pub fn with_directions(mut self, d: Directions) -> Self {
        self.directions = d;
        self.mark("directions")
    }
    /// Sets `seed` and `stream`.
    pub fn with_stream(mut self, seed: u64, stream: u64) -> Self {
        self.seed = seed;
        self.stream = stream;
        self.mark("seed").mark("stream")
    }

    /// Replaces the value of `dt` without marking it (a setter of a running sim).
    pub(crate) fn update_dt(&mut self, dt: f64) {
        self.dt = dt;
    }

    /// The settings a checkpoint's record of [`words`](Self::words) describes (the
    /// given keys stay `self`'s). Errors: a word that is no value of its key.
    pub(crate) fn with_words(&self, w: &[u64; 15]) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        let pick = |v: u64, n: u64| {
            if v < n {
                Ok(v as usize)
            } else {
                Err(bad("a setting's value is out of range"))
            }
        };
        let opt = |v: u64, n: u64| -> Result<Option<usize>> {
            if v == 0 {
                Ok(None)
            } else {
                pick(v - 1, n).map(Some)
            }
        };
        let o = Options {
            dt: f64::from_bits(w[0]),
            points: [Points::Niederreiter, Points::Sobol, Points::MonteCarlo][pick(w[1], 3)?],
            randomization: [
                Randomization::None,
                Randomization::DigitalShift,
                Randomization::Matousek,
                Randomization::Owen,
            ][pick(w[2], 4)?],
            sorting: [Sorting::Adaptive, Sorting::Full][pick(w[3], 2)?],
            size_limit: w[4],
            memory_budget: usize::try_from(w[5]).unwrap_or(usize::MAX),
            batched_clock: [false, true][pick(w[6], 2)?],
            capacity: usize::try_from(w[7]).unwrap_or(usize::MAX),
            truncation: f64::from_bits(w[8]),
            strict_bound: [false, true][pick(w[9], 2)?],
            sampler: opt(w[10], 2)?.map(|i| [Sampler::SumTree, Sampler::Groups][i]),
            engine: opt(w[11], 3)?
                .map(|i| [BucketMode::Slots, BucketMode::Counted, BucketMode::Blocks][i]),
            directions: [Directions::Conditional, Directions::Uniform][pick(w[12], 2)?],
            seed: w[13],
            stream: w[14],
            given: self.given,
        };
        if check_dt(o.dt).is_err()
            || check_size_limit(o.size_limit).is_err()
            || check_truncation(o.truncation).is_err()
        {
            return Err(bad("a setting's value is out of range"));
        }
        Ok(o)
    }

    /// The same settings with `mine`'s memory budget and capacity (what a restored
    /// state was checked against).
    pub(crate) fn with_budget_of(mut self, mine: &Options) -> Self {
        self.memory_budget = mine.memory_budget;
        self.capacity = mine.capacity;
        self
    }
}

fn check_dt(dt: f64) -> Result<f64> {
    crate::error::positive("dt", dt)
}

fn check_size_limit(limit: u64) -> Result<u64> {
    if limit < 2 {
        return Err(Error::OutOfRange {
            name: "size-limit",
            value: limit as f64,
            range: "[2, 2^64)",
        });
    }
    Ok(limit)
}

fn check_truncation(b: f64) -> Result<f64> {
    if b.is_nan() || b <= 0.0 {
        return Err(Error::OutOfRange {
            name: "truncation",
            value: b,
            range: "(0, inf]",
        });
    }
    Ok(b)
}

#[cfg(test)]
mod tests;
