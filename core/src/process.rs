//! Processes beside coagulation: a particle source, size-dependent removal and growth
//! by monomer attachment, with the books a host needs to close its budgets.
//!
//! What a process is lives here; how it joins a scheme is the facade's (one way in for
//! every scheme of the registry: [`Simulation::set_processes`](crate::scheme::facade::Simulation::set_processes)).
//! The processes and coagulation are independent competing Poisson clocks, so the
//! combined finite-N chain is simulated exactly by thinning over the scheme's own exact
//! clock (Gillespie 1976; the design is `docs/design/processes.md`):
//!
//! * **source** — particles arrive at rate `S V` (S per unit volume and time), each
//!   with a size drawn from a [`Distribution`] (nucleation: monodisperse; emission: any
//!   of them). S may follow a piecewise-constant schedule `S(t)`
//!   ([`Source::with_schedule`]): the thinning bound then holds until the next change,
//!   where the candidate is drawn afresh (an exponential's residual is exponential). On integer sizes a continuous distribution's draw is rounded to the
//!   nearest integer, at least 1 (as [`counts_on_grid`](crate::initial::counts_on_grid)
//!   puts a continuous start on the grid: say so where it matters);
//! * **removal** — each particle leaves at rate `λ(x) = c x^p` (dilution and outflow:
//!   `p = 0`; deposition and sedimentation: a power of size). Dilution with a
//!   background population is a removal at λ and a source of rate `λ n_b` with the
//!   background's distribution ([`Processes::dilution`]);
//! * **growth** — on integer sizes, a particle of size i gains a monomer at rate
//!   `G(i) = g i^q`: the attachment chain, exact there (its mean follows
//!   `dx/dt = G(x)` to first order in `1/x`). On real sizes, `dx/dt = G(x)` by Strang
//!   splitting of a step the caller sets ([`Processes::with_growth_step`]): every
//!   particle grows by a step at the times `(k + ½) h` (in closed form for a power,
//!   by a fourth-order Runge–Kutta step otherwise), and the exact clock runs in between;
//!   second order in `h` at the times `k h`. This is an approximation of the
//!   continuous equation, and says so.
//!
//! The exponents are at most 1: then `Σ λ(x_i)` and `Σ G(x_i)` never grow when two
//! particles merge (`(x + y)^p ≤ x^p + y^p` for `0 ≤ p ≤ 1`, `≤ x^p` for `p ≤ 0`), so
//! the total process rate at the last process event bounds it until the next one — the
//! thinning bound that makes the scheme exact.
//!
//! # Example
//! ```
//! use coagula_core::kernel::{Coagulation, NoFragmentation};
//! use coagula_core::process::{Processes, Source};
//! use coagula_core::initial::Distribution;
//! use coagula_core::random::{Generator, generator};
//! use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
//! use coagula_core::scheme::registry;
//! let model = Model::Coagulation {
//!     kernel: Coagulation::constant(1.0).unwrap(),
//!     fragmentation: NoFragmentation,
//! };
//! // an empty box of volume 1000 and monomers nucleated at S = 0.5 per unit volume
//! let init = Init::Counts { counts: &[], volume: 1000.0 };
//! let info = registry::find("lowrank").unwrap();
//! let mut sim: Box<dyn Simulation<_, _, Generator>> =
//!     registry::build(info, model, &init, &Options::default()).unwrap();
//! let source = Source::new(0.5, Distribution::Monodisperse { size: 1.0 }).unwrap();
//! sim.set_processes(Some(Processes::default().with_source(source))).unwrap();
//! sim.advance_to(4.0, &mut generator(7, 0)).unwrap();
//! let books = sim.books().unwrap();
//! // every particle injected is a monomer: the mass is what was injected
//! assert_eq!(books.injected_mass, books.injected_number as f64);
//! assert_eq!(books.current_mass(), books.injected_mass);
//! // M1 = S t = 2 per unit volume, within the noise of ~2000 injections
//! assert!((sim.moment(1.0) - 2.0).abs() < 0.2);
//! ```

use crate::error::{Error, Result};
use crate::initial::Distribution;
use crate::random::open_unit;
use alloc::sync::Arc;
use alloc::vec::Vec;
use rand_core::Rng;

/// The largest exponent of a removal or growth rate (see the module docs).
pub const MAX_EXPONENT: f64 = 1.0;
/// The smallest one (a rate `x^p` below it underflows on any size of interest).
pub const MIN_EXPONENT: f64 = -10.0;

fn exponent(name: &'static str, p: f64) -> Result<f64> {
    if p.is_finite() && (MIN_EXPONENT..=MAX_EXPONENT).contains(&p) {
        Ok(p)
    } else {
        Err(Error::OutOfRange {
            name,
            value: p,
            range: "[-10, 1] (at most 1: the thinning bound needs a rate that merging cannot raise)",
        })
    }
}

fn rate(name: &'static str, c: f64) -> Result<f64> {
    if (0.0..=1e300).contains(&c) {
        Ok(c)
    } else {
        Err(Error::OutOfRange {
            name,
            value: c,
            range: "[0, 1e300]",
        })
    }
}

/// Particles injected at `rate` per unit volume and time with sizes from `sizes`, at a
/// piecewise-constant rate `S(t)` ([`with_schedule`](Source::with_schedule)), or at a
/// host's rate function of time with a bound
/// ([`with_rate_function`](Source::with_rate_function)).
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    rate: f64,
    sizes: Distribution,
    /// `(t_k, S_k)`: `S(t) = S_k` on `[t_k, t_{k+1})`, the last one after; `rate`
    /// before `t_0`. Empty: the constant `rate`.
    schedule: Vec<(f64, f64)>,
    /// `S(t)` as a host's function of time, at most its bound (then `rate` and
    /// `schedule` are not used).
    function: Option<UserRate>,
    /// A listed or counted distribution's cumulative mass weights (size × count), for
    /// draws from its mass distribution by bisection ([`mass_size`](Source::mass_size));
    /// empty for the others.
    mass_cdf: Vec<f64>,
}

/// Largest number of pieces of a source's schedule.
pub const MAX_SCHEDULE: usize = 1 << 20;

impl Source {
    /// A source of `rate` particles per unit volume and time (finite, ≥ 0) with sizes
    /// drawn from `sizes` (checked as an initial distribution; an explicit list or
    /// counts is drawn from with replacement).
    pub fn new(rate: f64, sizes: Distribution) -> Result<Self> {
        let rate = self::rate("source rate", rate)?;
        match &sizes {
            Distribution::Monodisperse { size } => {
                crate::error::positive("source size", *size)?;
            }
            d => d.check()?,
        }
        let mut mass_cdf = Vec::new();
        let weights: Option<Vec<f64>> = match &sizes {
            Distribution::Sizes(x) => Some(x.clone()),
            Distribution::Counts(c) => Some(
                c.iter()
                    .enumerate()
                    .map(|(i, &n)| (i + 1) as f64 * n as f64)
                    .collect(),
            ),
            _ => None,
        };
        if let Some(w) = weights {
            crate::memory::try_reserve(&mut mass_cdf, w.len())?;
            let mut acc = 0.0;
            for v in w {
                acc += v;
                mass_cdf.push(acc);
            }
        }
        Ok(Source {
            rate,
            sizes,
            schedule: Vec::new(),
            function: None,
            mass_cdf,
        })
    }

    /// The rate as a host's function of time, `S(t) = f(t)` particles per unit volume
    /// and time, at most the function's bound at every time: candidates come at the
    /// bound and a source event is kept with `S(t)/bound` (thinning, exact for any `S`
    /// within the bound; a value above it is [`Error::BoundExceeded`], negative or NaN
    /// [`Error::InvalidRate`], raised before anything changes). Replaces the constant
    /// rate; not with a schedule.
    pub fn with_rate_function(mut self, f: UserRate) -> Result<Self> {
        if !self.schedule.is_empty() {
            return Err(Error::Unsupported {
                what: "a source rate given both as a schedule and as a function (one of them)",
            });
        }
        self.function = Some(f);
        Ok(self)
    }

    /// The source back at the rate it was built with (and its schedule, if any).
    pub fn without_rate_function(mut self) -> Self {
        self.function = None;
        self
    }

    /// The host's rate function, if the rate is one.
    pub fn rate_function(&self) -> Option<&UserRate> {
        self.function.as_ref()
    }

    /// A bound of the rate from `t` until [`next_change`](Source::next_change): the
    /// rate itself, or a rate function's bound.
    pub fn bound_at(&self, t: f64) -> f64 {
        match &self.function {
            Some(f) => f.bound(),
            None => self.rate_at(t),
        }
    }

    /// The rate at `t`, a rate function's value checked against its bound.
    pub fn rate_now(&self, t: f64) -> Result<f64> {
        match &self.function {
            Some(f) => f.at(t),
            None => Ok(self.rate_at(t)),
        }
    }

    /// The rate as a piecewise-constant function of time: `rates[k]` from `times[k]` to
    /// `times[k + 1]`, the last rate after the last time, the source's own rate before
    /// the first. Times finite, ≥ 0 and strictly ascending; rates as `new`'s; 1 to
    /// [`MAX_SCHEDULE`] pieces, as many times as rates.
    pub fn with_schedule(mut self, times: &[f64], rates: &[f64]) -> Result<Self> {
        if self.function.is_some() {
            return Err(Error::Unsupported {
                what: "a source rate given both as a schedule and as a function (one of them)",
            });
        }
        if times.len() != rates.len() || times.is_empty() || times.len() > MAX_SCHEDULE {
            return Err(Error::BufferLength {
                name: "source schedule (as many times as rates, 1 to 2^20)",
                expected: times.len().clamp(1, MAX_SCHEDULE),
                got: rates.len(),
            });
        }
        let mut last = -1.0;
        for &t in times {
            if !(t.is_finite() && t >= 0.0 && t > last) {
                return Err(Error::OutOfRange {
                    name: "source schedule time (finite, ≥ 0, strictly ascending)",
                    value: t,
                    range: "(previous time, inf)",
                });
            }
            last = t;
        }
        let mut schedule = Vec::new();
        crate::memory::try_reserve(&mut schedule, times.len())?;
        for (&t, &r) in times.iter().zip(rates) {
            schedule.push((t, self::rate("source rate", r)?));
        }
        self.schedule = schedule;
        Ok(self)
    }

    /// Particles per unit volume and time: the constant rate, or with a schedule the
    /// rate before its first time.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The schedule's `(time, rate)` pieces (empty: a constant rate).
    pub fn schedule(&self) -> &[(f64, f64)] {
        &self.schedule
    }

    /// The rate at time `t` (of the constant rate or the schedule: see
    /// [`rate_now`](Source::rate_now) for a rate function).
    pub fn rate_at(&self, t: f64) -> f64 {
        // the last piece that starts at or before t
        match self.schedule.partition_point(|p| p.0 <= t) {
            0 => self.rate,
            k => self.schedule[k - 1].1,
        }
    }

    /// The first time after `t` at which the rate changes (`inf`: never).
    pub fn next_change(&self, t: f64) -> f64 {
        let k = self.schedule.partition_point(|p| p.0 <= t);
        self.schedule.get(k).map_or(f64::INFINITY, |p| p.0)
    }

    /// Particles injected per unit volume from `t0` to `t1 ≥ t0`: exact for a constant
    /// rate and a schedule (summed over its pieces), the midpoint rule for a host's rate
    /// function (second order in `t1 − t0`; its value checked against its bound).
    pub fn injected_between(&self, t0: f64, t1: f64) -> Result<f64> {
        if self.function.is_some() {
            return Ok(self.rate_now(0.5 * (t0 + t1))? * (t1 - t0));
        }
        let (mut t, mut sum) = (t0, 0.0);
        while t < t1 {
            let end = self.next_change(t).min(t1);
            sum += self.rate_at(t) * (end - t);
            t = end;
        }
        Ok(sum)
    }

    /// The size at `u ∈ [0, 1)` of the source's *mass* distribution `x p(x) / μ` (the
    /// distribution of the size a unit of injected mass sits on, which a mass-flow
    /// particle takes: Lécot et al. 2019 represent the mass density): the inverse CDF
    /// of a continuous distribution, the listed sizes weighted by their sizes.
    pub fn mass_size(&self, u: f64) -> f64 {
        let u = u.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0);
        // the first entry whose cumulative weight passes u × total (O(log n))
        let pick = || {
            let total = self.mass_cdf.last().copied().unwrap_or(0.0);
            let k = self.mass_cdf.partition_point(|&c| c <= u * total);
            k.min(self.mass_cdf.len().saturating_sub(1))
        };
        match &self.sizes {
            Distribution::Monodisperse { size } => *size,
            Distribution::Sizes(x) => x.get(pick()).copied().unwrap_or(f64::NAN),
            Distribution::Counts(_) => (pick() + 1) as f64,
            d => d.inverse(u, true),
        }
    }

    /// The size distribution.
    pub fn sizes(&self) -> &Distribution {
        &self.sizes
    }

    /// One size (rounded to an integer ≥ 1 when `integer`).
    pub fn draw<G: Rng + ?Sized>(&self, integer: bool, rng: &mut G) -> f64 {
        let x = match &self.sizes {
            Distribution::Monodisperse { size } => *size,
            Distribution::Sizes(x) => x[crate::random::below(rng, x.len() as u64) as usize],
            Distribution::Counts(c) => {
                let total = c.iter().fold(0u64, |a, &b| a.saturating_add(b));
                let mut k = crate::random::below(rng, total);
                let mut size = c.len();
                for (i, &n) in c.iter().enumerate() {
                    if k < n {
                        size = i + 1;
                        break;
                    }
                    k -= n;
                }
                size as f64
            }
            d => d.inverse(open_unit(rng), false),
        };
        if integer { libm::round(x).max(1.0) } else { x }
    }
}

/// A rate `c x^p` per particle (removal) or monomers per unit time (growth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Power {
    /// The coefficient c ≥ 0.
    pub coefficient: f64,
    /// The exponent p ∈ [−10, 1].
    pub exponent: f64,
}

impl Power {
    /// `c x^p`, checked (`what` names it in an error).
    pub fn new(what: &'static str, coefficient: f64, exponent: f64) -> Result<Self> {
        Ok(Power {
            coefficient: rate(what, coefficient)?,
            exponent: self::exponent(what, exponent)?,
        })
    }

    /// The rate at size `x`.
    #[inline]
    pub fn at(&self, x: f64) -> f64 {
        if self.exponent == 0.0 {
            self.coefficient
        } else {
            self.coefficient * libm::pow(x, self.exponent)
        }
    }

    /// The size that `x > 0` grows to in time `t ≥ 0` at `dx/dt = c x^p`, in closed
    /// form: `x e^{ct}` for `p = 1`, else `(x^{1−p} + (1−p) c t)^{1/(1−p)}` (constant
    /// growth `p = 0`: `x + ct`; the continuum regime of condensation, `dv/dt ∝ v^{1/3}`:
    /// `p = 1/3`; the free-molecular one, `dv/dt ∝ v^{2/3}`: `p = 2/3`).
    pub fn grown(&self, x: f64, t: f64) -> f64 {
        let (c, p) = (self.coefficient, self.exponent);
        if p == 1.0 {
            x * libm::exp(c * t)
        } else if p == 0.0 {
            x + c * t
        } else {
            // x (1 + a c t x^{−a})^{1/a}: the same, keeping its digits for q near 1
            // and not overflowing x^a for a large a
            let a = 1.0 - p;
            x * libm::exp(libm::log1p(a * c * t * libm::pow(x, -a)) / a)
        }
    }
}

impl Power {
    /// `ln(x(t)/x)` for [`grown`](Power::grown): the log of the factor a size grows
    /// by, without forming the size (`c t`, `log1p(c t/x)`, or
    /// `log1p((1−p) c t x^{p−1})/(1−p)`).
    pub fn log_growth(&self, x: f64, t: f64) -> f64 {
        let (c, p) = (self.coefficient, self.exponent);
        if c == 0.0 {
            0.0
        } else if p == 1.0 {
            c * t
        } else if p == 0.0 {
            libm::log1p(c * t / x)
        } else {
            let a = 1.0 - p;
            libm::log1p(a * c * t * libm::pow(x, -a)) / a
        }
    }
}

/// A rate per particle that a host gives as a function of size, with a bound over
/// every size (a removal or growth law that is no power of size; as a user kernel
/// declares its majorant). The thinning draws against `bound` per particle and accepts
/// with `f(x) / bound`; a value above the bound, negative or NaN is an error
/// ([`Error::BoundExceeded`], [`Error::InvalidRate`]) that leaves the state as it was.
/// `tag` names the function in checkpoints (a checkpoint restores only into a sim with
/// the same tag and bound: the function itself cannot be compared).
#[derive(Clone)]
pub struct UserRate {
    f: Arc<dyn Fn(f64) -> f64 + Send + Sync>,
    bound: f64,
    tag: u64,
}

impl UserRate {
    /// The rate `f(x)` per particle, at most `bound` (finite, > 0) at every size.
    pub fn new(
        f: impl Fn(f64) -> f64 + Send + Sync + 'static,
        bound: f64,
        tag: u64,
    ) -> Result<Self> {
        if !(bound.is_finite() && bound > 0.0 && bound <= 1e300) {
            return Err(Error::OutOfRange {
                name: "bound of a user rate",
                value: bound,
                range: "(0, 1e300]",
            });
        }
        Ok(UserRate {
            f: Arc::new(f),
            bound,
            tag,
        })
    }

    /// The bound per particle.
    pub fn bound(&self) -> f64 {
        self.bound
    }

    /// The tag.
    pub fn tag(&self) -> u64 {
        self.tag
    }

    /// The rate at size `x`, checked against the bound.
    pub fn at(&self, x: f64) -> Result<f64> {
        let v = (self.f)(x);
        if !(v >= 0.0 && v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "user rate (removal, growth or source)",
                value: v,
            });
        }
        if v > self.bound {
            return Err(Error::BoundExceeded {
                name: "user rate above its declared bound",
                rate: v,
                bound: self.bound,
            });
        }
        Ok(v)
    }
}

impl PartialEq for UserRate {
    /// The same function (the same allocation), bound and tag.
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.f, &other.f) && self.bound == other.bound && self.tag == other.tag
    }
}

impl core::fmt::Debug for UserRate {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UserRate")
            .field("bound", &self.bound)
            .field("tag", &self.tag)
            .finish_non_exhaustive()
    }
}

/// The processes of a population beside coagulation (any of them may be absent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Processes {
    /// The source.
    pub source: Option<Source>,
    /// The removal rate per particle, `λ(x) = c x^p`.
    pub removal: Option<Power>,
    /// Growth by monomer attachment, `G(i) = g i^q` (integer sizes).
    pub growth: Option<Power>,
    /// A host's removal rate per particle (beside `removal`: the two add up).
    pub user_removal: Option<UserRate>,
    /// A host's growth rate, monomers per unit time (integer sizes; beside `growth`).
    pub user_growth: Option<UserRate>,
    /// The splitting step of growth on real sizes (see
    /// [`with_growth_step`](Processes::with_growth_step)); unused on integer sizes.
    pub growth_step: Option<f64>,
}

impl Processes {
    /// With a source.
    pub fn with_source(mut self, source: Source) -> Self {
        self.source = Some(source);
        self
    }

    /// With removal at `λ(x) = c x^p` per particle.
    pub fn with_removal(mut self, c: f64, p: f64) -> Result<Self> {
        self.removal = Some(Power::new("removal rate", c, p)?);
        Ok(self)
    }

    /// With growth by monomer attachment at `G(i) = g i^q` per particle.
    pub fn with_growth(mut self, g: f64, q: f64) -> Result<Self> {
        self.growth = Some(Power::new("growth rate", g, q)?);
        Ok(self)
    }

    /// Dilution at rate λ with a background of `number` particles per unit volume
    /// distributed as `sizes`: removal at λ and a source at `λ number`.
    pub fn dilution(lambda: f64, number: f64, sizes: Distribution) -> Result<Self> {
        let inflow = rate("background number concentration", number)? * lambda;
        Ok(Processes::default()
            .with_removal(lambda, 0.0)?
            .with_source(Source::new(inflow, sizes)?))
    }

    /// With a host's removal rate per particle.
    pub fn with_user_removal(mut self, rate: UserRate) -> Self {
        self.user_removal = Some(rate);
        self
    }

    /// With a host's growth rate (monomers per unit time; integer sizes).
    pub fn with_user_growth(mut self, rate: UserRate) -> Self {
        self.user_growth = Some(rate);
        self
    }

    /// With growth on real sizes as Strang splitting of step `h` (finite, > 0): the
    /// particles grow by `h` at the times `(k + ½) h` and coagulate (and the other
    /// processes act, exactly) in between, so that at the times `k h` the state is
    /// second-order accurate in `h` (Strang 1968). Over a step a particle grows by the
    /// closed form of [`Power::grown`] when the growth is a power of size alone, else
    /// by one classical Runge–Kutta step (fourth order) of `dx/dt = G(x)`, the power's
    /// and the host's rates summed. On integer sizes growth is monomer attachment,
    /// exact, and the step is not used.
    pub fn with_growth_step(mut self, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0 && h <= 1e300) {
            return Err(Error::OutOfRange {
                name: "growth step",
                value: h,
                range: "(0, 1e300]",
            });
        }
        self.growth_step = Some(h);
        Ok(self)
    }

    /// The growth rate `G(x)` of real sizes: the power's and the host's, summed.
    pub fn growth_rate(&self, x: f64) -> Result<f64> {
        let mut g = self.growth.map_or(0.0, |p| p.at(x));
        if let Some(u) = &self.user_growth {
            g += u.at(x)?;
        }
        Ok(g)
    }

    /// The size that `x` grows to over one splitting step `h` (see
    /// [`with_growth_step`](Processes::with_growth_step)): exact for a power alone,
    /// one fourth-order Runge–Kutta step otherwise. A host's rate out of its bound is
    /// an error.
    pub fn grow(&self, x: f64, h: f64) -> Result<f64> {
        match (&self.growth, &self.user_growth) {
            (None, None) => Ok(x),
            (Some(p), None) => Ok(p.grown(x, h)),
            _ => {
                let k1 = self.growth_rate(x)?;
                let k2 = self.growth_rate(x + 0.5 * h * k1)?;
                let k3 = self.growth_rate(x + 0.5 * h * k2)?;
                let k4 = self.growth_rate(x + h * k3)?;
                Ok(x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
            }
        }
    }

    /// `ln(x'/x)` for the size `x'` that `x` grows to over `h` ([`grow`](Processes::grow)):
    /// in closed form for a power alone.
    pub fn log_growth(&self, x: f64, h: f64) -> Result<f64> {
        match (&self.growth, &self.user_growth) {
            (None, None) => Ok(0.0),
            (Some(p), None) => Ok(p.log_growth(x, h)),
            _ => Ok(libm::log(self.grow(x, h)? / x)),
        }
    }

    /// Whether there is no process at all (a growth step alone counts as one: a host
    /// may set it before the growth it splits).
    pub fn is_empty(&self) -> bool {
        self.source.is_none()
            && self.removal.is_none()
            && self.growth.is_none()
            && self.user_removal.is_none()
            && self.user_growth.is_none()
            && self.growth_step.is_none()
    }

    /// Whether any particle grows.
    pub fn grows(&self) -> bool {
        self.growth.is_some() || self.user_growth.is_some()
    }
}

/// The books of the processes: what came in, what left and what grew, in simulation
/// particles and their mass (sizes summed), since the processes were set (or the state
/// was replaced by a host), and the merges that took the number down. A particle
/// doubling doubles every entry, the initial state included, so that the mass
/// `initial + injected − removed + grown` and the number
/// `initial + injected − removed − merged` are the state's: exactly for integer sizes
/// (masses below 2^53), to rounding otherwise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Books {
    /// Particles at the start of the books.
    pub initial_number: u64,
    /// Their mass.
    pub initial_mass: f64,
    /// Particles the source injected.
    pub injected_number: u64,
    /// Their mass.
    pub injected_mass: f64,
    /// Particles removed.
    pub removed_number: u64,
    /// Their mass.
    pub removed_mass: f64,
    /// Monomers attached by growth (mass gained; the number is unchanged).
    pub grown_mass: f64,
    /// Merges by coagulation (each takes the number down by one).
    pub merged: u64,
    /// Particle doublings since the start of the books.
    pub doublings: u64,
}

impl Books {
    /// Books starting from `number` particles of total mass `mass`.
    pub fn starting(number: u64, mass: f64) -> Self {
        Books {
            initial_number: number,
            initial_mass: mass,
            ..Books::default()
        }
    }

    /// The particle number the books give.
    pub fn current_number(&self) -> u64 {
        (self.initial_number.saturating_add(self.injected_number))
            .saturating_sub(self.removed_number)
            .saturating_sub(self.merged)
    }

    /// The mass the books give.
    pub fn current_mass(&self) -> f64 {
        self.initial_mass + self.injected_mass - self.removed_mass + self.grown_mass
    }

    /// After a particle doubling.
    pub(crate) fn double(&mut self) {
        self.initial_number = self.initial_number.saturating_mul(2);
        self.injected_number = self.injected_number.saturating_mul(2);
        self.removed_number = self.removed_number.saturating_mul(2);
        self.merged = self.merged.saturating_mul(2);
        self.initial_mass *= 2.0;
        self.injected_mass *= 2.0;
        self.removed_mass *= 2.0;
        self.grown_mass *= 2.0;
        self.doublings += 1;
    }

    pub(crate) fn save(&self, w: &mut crate::checkpoint::Writer) {
        w.u64(self.initial_number);
        w.f64(self.initial_mass);
        w.u64(self.injected_number);
        w.f64(self.injected_mass);
        w.u64(self.removed_number);
        w.f64(self.removed_mass);
        w.f64(self.grown_mass);
        w.u64(self.merged);
        w.u64(self.doublings);
    }

    pub(crate) fn load(r: &mut crate::checkpoint::Reader) -> Result<Self> {
        let b = Books {
            initial_number: r.u64()?,
            initial_mass: r.f64()?,
            injected_number: r.u64()?,
            injected_mass: r.f64()?,
            removed_number: r.u64()?,
            removed_mass: r.f64()?,
            grown_mass: r.f64()?,
            merged: r.u64()?,
            doublings: r.u64()?,
        };
        let masses = [
            b.initial_mass,
            b.injected_mass,
            b.removed_mass,
            b.grown_mass,
        ];
        if masses.iter().any(|m| !(m.is_finite() && *m >= 0.0)) {
            return Err(Error::Checkpoint {
                what: "process books with a negative or non-finite mass",
            });
        }
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_schedule_is_piecewise_constant_and_checked() {
        let s = Source::new(0.3, Distribution::Monodisperse { size: 1.0 })
            .unwrap()
            .with_schedule(&[0.5, 2.0], &[1.0, 0.0])
            .unwrap();
        for (t, r, next) in [
            (0.0, 0.3, 0.5),
            (0.49, 0.3, 0.5),
            (0.5, 1.0, 2.0),
            (1.9, 1.0, 2.0),
            (2.0, 0.0, f64::INFINITY),
            (9.0, 0.0, f64::INFINITY),
        ] {
            assert_eq!(s.rate_at(t), r, "{t}");
            assert_eq!(s.next_change(t), next, "{t}");
        }
        let base = Source::new(0.3, Distribution::Monodisperse { size: 1.0 }).unwrap();
        assert_eq!(base.rate_at(5.0), 0.3);
        assert_eq!(base.next_change(5.0), f64::INFINITY);
        for (times, rates) in [
            (&[][..], &[][..]),
            (&[1.0][..], &[1.0, 2.0][..]),
            (&[1.0, 1.0][..], &[1.0, 2.0][..]),
            (&[2.0, 1.0][..], &[1.0, 2.0][..]),
            (&[-1.0][..], &[1.0][..]),
            (&[f64::NAN][..], &[1.0][..]),
            (&[1.0][..], &[-1.0][..]),
            (&[1.0][..], &[f64::INFINITY][..]),
        ] {
            assert!(
                base.clone().with_schedule(times, rates).is_err(),
                "{times:?} {rates:?}"
            );
        }
    }
}
