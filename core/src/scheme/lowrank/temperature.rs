//! Temperature-dependent low-rank Monte Carlo (Osinsky 2023, §4): every size i carries a
//! partial temperature `T_i`, collisions happen at rate `C_ij(T_i, T_j)/V` per pair, and
//! each one either aggregates or bounces, changing the temperatures (the kernels are a
//! [`TemperatureKernel`]; see [`crate::kernel::temperature`]).
//!
//! It is the low-rank event loop with the per-size tree engine and the rule [`Collide`]:
//!
//! * **Kernel and state.** [`Temperatures`] is the kernel at the current temperatures (a
//!   [`CoagulationKernel`] of rank 3 whose factors are `a_k(i, T_i)`, `b_k(i)`): the
//!   engine builds and grows from it, and the rule moves its temperatures.
//! * **Proposals** at rate `(A + Aᵀ)/V` from the rank-3 bound (the engine's), accepted
//!   with `C/(A + Aᵀ)` (same-size pairs also with `(N_i − 1)/N_i`, the engine's thinning
//!   of the particle paired with itself). The accepting uniform `u ∈ (0, C]` also
//!   decides the outcome: a bounce when `u ≤ C^res = f C`, else an aggregation.
//! * **Updates**, from the counts and temperatures before the event (`N_s`):
//!   aggregation `i + j → k` sets `T_k ← (N_k T_k + B/C^agg)/(N_k + 1)` and
//!   `T_i ← (N_i T_i − D^agg_ij/C^agg)/(N_i − 1)` (0 when the size empties), `T_j`
//!   likewise; a bounce sets `T_i ← T_i − D^res_ij/(C^res N_i)`, `T_j` likewise. A
//!   same-size pair (i = j) removes two particles' share: `T_i ← (N_i T_i −
//!   2 D^agg_ii/C^agg)/(N_i − 2)` and `T_i ← T_i − 2 D^res_ii/(C^res N_i)`. Every
//!   temperature is clipped at 0. The changed sizes' factor rows are then rewritten in
//!   the tree (O(log M) each).
//! * Particle doubling and the growth of M are the engine's, as in plain low-rank MC.
//!
//! The per-event energy shares are those of the population equations (e.g. an `i = i`
//! aggregation, of rate `C^agg n_i²/2`, takes `2 D^agg_ii/C^agg` from the species'
//! energy); the author's implementation updates a same-size aggregation by
//! `2T' − T_i`, `T' = (N_i T_i − D/C)/(N_i − 1)`, which differs at O(1/N_i).
//!
//! # Example
//! ```
//! use coagula_core::kernel::temperature::ClosedForm;
//! use coagula_core::scheme::Scheme;
//! use coagula_core::scheme::lowrank::{TemperatureMc, Temperatures};
//! let mut rng = rand_pcg::Pcg64Mcg::new(11);
//! // the model family with a closed form: c = 1, γ = 1/2, n_1(0) = 1, T_1(0) = 1
//! let model = ClosedForm::new(1.0, 0.5).unwrap();
//! let kernel = Temperatures::new(model, &[1.0]).unwrap();
//! let mut sim = TemperatureMc::<_>::monodisperse(kernel, 20_000).unwrap();
//! sim.advance_to(2.0, &mut rng).unwrap();
//! let exact = model.exact(1.0, 1.0, 2.0);
//! assert!((sim.moment(0.0) / exact.number() - 1.0).abs() < 0.05);
//! assert!((sim.mean_temperature() / exact.mean_temperature() - 1.0).abs() < 0.05);
//! ```

use super::proposal::{Candidate, Low, Outcome, ProposalEngine};
use super::rule::{EventRule, Reweighed};
use super::trees::WideTree;
use super::{LowRankMc, TreeEngine, UniformEngine};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::kernel::temperature::{PairRates, TemperatureKernel};
use crate::random::open_unit;
use crate::scheme::population::try_reserve;
use alloc::vec::Vec;
use rand_core::Rng;

/// Temperature-dependent low-rank MC over the per-size trees (see the module docs);
/// `T` is the tree layout ([`WideTree`] or [`BinaryTree`](super::BinaryTree)).
pub type TemperatureMc<TK, T = WideTree<3>> =
    LowRankMc<Temperatures<TK>, 3, TreeEngine<3, T>, Collide>;

/// The temperature-dependent scheme on the acceptance–rejection engine (uniform pairs,
/// one bound `2 max A` for all): the baseline that [`TemperatureMc`] is timed against.
pub type TemperatureRejection<TK> = LowRankMc<Temperatures<TK>, 3, UniformEngine<3>, Collide>;

/// A temperature kernel with the partial temperatures of every size: the collision
/// kernel at the current temperatures (see the module docs).
#[derive(Clone, Debug)]
pub struct Temperatures<TK> {
    model: TK,
    /// `temps[i − 1] = T_i`; sizes past the end are at temperature 0.
    temps: Vec<f64>,
    /// The factors the rule validated for the sizes an event changes, keyed by size
    /// and temperature bits, so that the engine's reweighing that follows does not
    /// evaluate them again (a pure cache: a miss evaluates the model).
    recent: heapless::Vec<Recent, 3>,
}

/// A cached factor row: size, temperature bits, `a`, `b`.
type Recent = (u64, u64, [f64; 3], [f64; 3]);

impl<TK: TemperatureKernel> Temperatures<TK> {
    /// The kernels `model` with `temperatures[i − 1] = T_i` (finite, ≥ 0; sizes past
    /// the slice start at 0).
    pub fn new(model: TK, temperatures: &[f64]) -> Result<Self> {
        check_temperatures(temperatures)?;
        let mut temps = Vec::new();
        try_reserve(&mut temps, temperatures.len())?;
        temps.extend_from_slice(temperatures);
        Ok(Temperatures {
            model,
            temps,
            recent: heapless::Vec::new(),
        })
    }

    /// The kernels.
    pub fn model(&self) -> &TK {
        &self.model
    }

    /// The partial temperature `T_size` (0 for a size never held).
    #[inline]
    pub fn temperature(&self, size: u64) -> f64 {
        usize::try_from(size.wrapping_sub(1))
            .ok()
            .and_then(|i| self.temps.get(i))
            .copied()
            .unwrap_or(0.0)
    }

    /// The temperatures, `T_i` at index `i − 1` (sizes past the end are at 0).
    pub fn temperatures(&self) -> &[f64] {
        &self.temps
    }

    /// The rates of a pair of sizes at the current temperatures.
    #[inline]
    pub fn rates(&self, x: u64, y: u64) -> PairRates {
        self.model
            .rates(x, self.temperature(x), y, self.temperature(y))
    }
}

fn check_temperatures(t: &[f64]) -> Result<()> {
    for &v in t {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(Error::OutOfRange {
                name: "partial temperature",
                value: v,
                range: "[0, inf)",
            });
        }
    }
    Ok(())
}

impl<TK: TemperatureKernel> CoagulationKernel for Temperatures<TK> {
    /// The collision rate `C(x, T_x, y, T_y)` (sizes rounded to integers).
    fn rate(&self, x: f64, y: f64) -> f64 {
        self.rates(x as u64, y as u64).collision
    }

    fn rank(&self) -> usize {
        3
    }

    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        let (mut fa, mut fb) = ([0.0; 3], [0.0; 3]);
        let i = x as u64;
        let t = self.temperature(i);
        match self.recent.iter().find(|r| r.0 == i && r.1 == t.to_bits()) {
            Some(r) => (fa, fb) = (r.2, r.3),
            None => self.model.factors(i, t, &mut fa, &mut fb),
        }
        a[..3].copy_from_slice(&fa);
        b[..3].copy_from_slice(&fb);
    }

    fn min_size(&self) -> f64 {
        1.0
    }
}

/// The collision rule of the temperature-dependent scheme (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Collide {
    /// The rates of the last accepted pair.
    rates: PairRates,
    /// The temperatures the accepted event sets, from `plan` to `commit`.
    pending: heapless::Vec<(u64, f64), 3>,
}

/// A rate of a [`TemperatureKernel`] that is not a finite number (or a negative one
/// where only non-negative ones make sense).
fn invalid(name: &'static str, value: f64) -> Error {
    Error::InvalidRate { name, value }
}

impl Collide {
    /// Validates a collision rate against the bound.
    #[inline]
    fn check_collision(c: f64, bound: f64) -> Result<()> {
        if !(c >= 0.0 && c.is_finite()) {
            return Err(invalid("temperature kernel: collision rate", c));
        }
        if c > bound * (1.0 + 1e-12) {
            return Err(Error::BoundExceeded {
                name: "temperature-dependent low-rank bound",
                rate: c,
                bound,
            });
        }
        Ok(())
    }

    /// Validates the rates of an accepted pair against the bound.
    fn check(r: &PairRates, bound: f64) -> Result<()> {
        let c = r.collision;
        Self::check_collision(c, bound)?;
        for (name, v) in [
            ("temperature kernel: aggregation rate", r.aggregation),
            ("temperature kernel: restitution rate", r.restitution),
        ] {
            if !(v >= 0.0 && v <= c * (1.0 + 1e-12)) {
                return Err(invalid(name, v));
            }
        }
        for v in [r.energy_gain]
            .into_iter()
            .chain(r.aggregation_loss)
            .chain(r.restitution_loss)
        {
            if !v.is_finite() {
                return Err(invalid("temperature kernel: energy rate", v));
            }
        }
        Ok(())
    }
}

/// `a / b`, 0 when `b` is 0 (an event of rate 0 moves no energy).
#[inline]
fn per(a: f64, b: f64) -> f64 {
    if b > 0.0 { a / b } else { 0.0 }
}

impl<TK: TemperatureKernel + Clone> EventRule<Temperatures<TK>> for Collide {
    const REWEIGHS: bool = true;
    const TAG: Option<u64> = Some(crate::scheme::tag::TEMPERATURE);

    fn for_kernel(_kernel: &Temperatures<TK>) -> Self {
        Collide::default()
    }

    #[inline]
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        kernel: &Temperatures<TK>,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        _low: Low,
        _spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>> {
        let (bound, _) = bounds();
        let (tx, ty) = (kernel.temperature(c.x), kernel.temperature(c.y));
        let cxy = kernel.model.collision(c.x, tx, c.y, ty);
        Self::check_collision(cxy, bound)?;
        let u = bound * open_unit(rng);
        if u > cxy {
            return Ok(None);
        }
        // the other rates only for an accepted pair
        let r = kernel.model.rates(c.x, tx, c.y, ty);
        Self::check(&r, bound)?;
        self.rates = r;
        // given acceptance, u is uniform on (0, C]: a bounce with probability C^res / C
        Ok(Some(if u <= r.restitution {
            Outcome::Bounce
        } else {
            Outcome::Merge {
                size: c.x.saturating_add(c.y),
            }
        }))
    }

    fn plan(
        &mut self,
        kernel: &mut Temperatures<TK>,
        (x, y): (u64, u64),
        outcome: &Outcome,
        count: &dyn Fn(u64) -> u64,
    ) -> Result<()> {
        self.pending.clear();
        let r = self.rates;
        let (tx, ty) = (kernel.temperature(x), kernel.temperature(y));
        let (nx, ny) = (count(x) as f64, count(y) as f64);
        let mut set = |s: u64, t: f64| {
            // (capacity 3: a pair and the merged size)
            // (clipped at 0; a NaN stays NaN, for the check below)
            let _ = self.pending.push((s, if t < 0.0 { 0.0 } else { t }));
        };
        match *outcome {
            Outcome::Merge { size: k } => {
                let ca = r.aggregation;
                let (nk, tk) = (count(k) as f64, kernel.temperature(k));
                if x == y {
                    let left = nx - 2.0;
                    set(
                        x,
                        if left > 0.0 {
                            (nx * tx - 2.0 * per(r.aggregation_loss[0], ca)) / left
                        } else {
                            0.0
                        },
                    );
                } else {
                    let after = |n: f64, t: f64, d: f64| {
                        if n > 1.0 {
                            (n * t - per(d, ca)) / (n - 1.0)
                        } else {
                            0.0
                        }
                    };
                    set(x, after(nx, tx, r.aggregation_loss[0]));
                    set(y, after(ny, ty, r.aggregation_loss[1]));
                }
                set(k, (nk * tk + per(r.energy_gain, ca)) / (nk + 1.0));
            }
            Outcome::Bounce => {
                let cr = r.restitution;
                if x == y {
                    set(x, tx - 2.0 * per(r.restitution_loss[0], cr * nx));
                } else {
                    set(x, tx - per(r.restitution_loss[0], cr * nx));
                    set(y, ty - per(r.restitution_loss[1], cr * ny));
                }
            }
        }
        // the temperature table covers every size the event sets before anything
        // changes (commit then resizes within that capacity)
        let top = self.pending.iter().map(|p| p.0).max().unwrap_or(0);
        let need = usize::try_from(top).unwrap_or(usize::MAX);
        if need > kernel.temps.len() {
            let target = need.checked_next_power_of_two().unwrap_or(need);
            let more = target - kernel.temps.len();
            try_reserve(&mut kernel.temps, more)?;
        }
        kernel.recent.clear();
        for &(s, t) in &self.pending {
            if !t.is_finite() {
                return Err(invalid("temperature update", t));
            }
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            kernel.model.factors(s, t, &mut a, &mut b);
            if let Some(&v) = a.iter().chain(&b).find(|v| !(**v >= 0.0 && v.is_finite())) {
                return Err(invalid("low-rank factor", v));
            }
            let _ = kernel.recent.push((s, t.to_bits(), a, b));
        }
        Ok(())
    }

    fn commit(&mut self, kernel: &mut Temperatures<TK>) -> Reweighed {
        let mut sizes = Reweighed::new();
        for &(s, t) in &self.pending {
            let i = (s - 1) as usize;
            if i >= kernel.temps.len() {
                // within the capacity `plan` reserved: no allocation here
                kernel.temps.resize(i + 1, 0.0);
            }
            kernel.temps[i] = t;
            let _ = sizes.push(s);
        }
        self.pending.clear();
        sizes
    }

    fn save(&self, kernel: &Temperatures<TK>, w: &mut Writer) {
        w.f64s(&kernel.temps);
    }

    fn load(&self, kernel: &Temperatures<TK>, r: &mut Reader) -> Result<Option<Temperatures<TK>>> {
        let temps = r.f64s()?;
        check_temperatures(&temps).map_err(|_| Error::Checkpoint {
            what: "invalid partial temperature",
        })?;
        Ok(Some(Temperatures {
            model: kernel.model.clone(),
            temps,
            recent: heapless::Vec::new(),
        }))
    }
}

impl<TK, E> LowRankMc<Temperatures<TK>, 3, E, Collide>
where
    TK: TemperatureKernel + Clone,
    E: ProposalEngine<3>,
{
    /// The partial temperature of size `size`.
    pub fn temperature(&self, size: u64) -> f64 {
        self.kernel().temperature(size)
    }

    /// The kinetic energy density `Σ_i N_i T_i / V`.
    pub fn energy(&self) -> f64 {
        let mut e = 0.0;
        self.for_each_count(&mut |s, n| e += n as f64 * self.kernel().temperature(s));
        e / self.volume()
    }

    /// The mean temperature `Σ_i N_i T_i / N` (0 without particles).
    pub fn mean_temperature(&self) -> f64 {
        let n = self.particles();
        if n == 0 {
            return 0.0;
        }
        self.energy() * self.volume() / n as f64
    }
}
