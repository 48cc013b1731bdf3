//! Temperature-dependent coagulation (Osinsky 2023, §4 and appendix A): every size i
//! carries a partial temperature `T_i` (an energy), and a collision of an i- and a
//! j-cluster either aggregates or bounces (restitution), both changing temperatures.
//!
//! The population obeys
//!
//! ```text
//! dn_k/dt       = 1/2 Σ_{i+j=k} C^agg_ij n_i n_j − n_k Σ_j C^agg_kj n_j
//! d(n_k T_k)/dt = 1/2 Σ_{i+j=k} B_ij n_i n_j − n_k Σ_j D^agg_kj n_j − n_k Σ_j D^res_kj n_j
//! ```
//!
//! A [`TemperatureKernel`] gives, for one pair `(i, T_i), (j, T_j)`, the rates of that
//! system ([`PairRates`]) and the factors of a rank-3 proposal bound
//! `A(i, j) = Σ_k a_k(i, T_i) b_k(j)` with `A + Aᵀ ≥ C` (the collision rate), whose
//! `a` factors change when a temperature does.
//!
//! Two kernels are built in:
//!
//! * [`Ballistic`] — Maxwellian velocities, hard spheres of diameter `i^{1/3}`, an
//!   aggregation barrier `W_ij` and restitution coefficient ε: the paper's model. The
//!   seed's appendix is damaged; the formulas are those recovered in the project's
//!   `TEMPERATURE.md` (from the author's implementation and a kinetic derivation).
//! * [`ClosedForm`] — a family with constants c and γ whose solution is known in closed form
//!   ([`ClosedForm::exact`]), to test a scheme against.
//!
//! [`rhs`] evaluates the right-hand side of the equations above for sizes truncated at a
//! maximum, so that they can be integrated deterministically.
//!
//! # Example
//! ```
//! use coagula_core::kernel::temperature::{Ballistic, TemperatureKernel};
//! let k = Ballistic::paper(); // ε = 0.99, a = 0.1, λ = 0.4
//! let r = k.rates(1, 1.0, 2, 1.0);
//! // a collision aggregates or bounces
//! assert!((r.aggregation + r.restitution - r.collision).abs() < 1e-12 * r.collision);
//! // the proposal bound covers the collision rate
//! let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
//! let (mut a2, mut b2) = ([0.0; 3], [0.0; 3]);
//! k.factors(1, 1.0, &mut a, &mut b);
//! k.factors(2, 1.0, &mut a2, &mut b2);
//! let bound: f64 = (0..3).map(|q| a[q] * b2[q] + a2[q] * b[q]).sum();
//! assert!(r.collision <= bound);
//! ```

pub(crate) use super::coagulation::size_cbrt;
use crate::error::{Error, Result};
use libm::{exp, log, pow, sqrt};

/// `sqrt(π/2)`.
const SQRT_HALF_PI: f64 = 1.253_314_137_315_500_3;

/// The rates of one pair `(i, T_i), (j, T_j)`: per unit of `n_i n_j` (each unordered
/// pair of an i- and a j-cluster in volume V collides at rate `collision / V`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairRates {
    /// `C_ij`: all collisions.
    pub collision: f64,
    /// `C^agg_ij`: collisions that aggregate.
    pub aggregation: f64,
    /// `C^res_ij = C_ij − C^agg_ij`: collisions that bounce.
    pub restitution: f64,
    /// `B_ij`: the rate at which aggregations bring energy to size `i + j`.
    pub energy_gain: f64,
    /// `[D^agg_ij, D^agg_ji]`: the rates at which aggregations take energy from sizes i
    /// and j.
    pub aggregation_loss: [f64; 2],
    /// `[D^res_ij, D^res_ji]`: the rates at which bounces take energy from sizes i and j.
    pub restitution_loss: [f64; 2],
}

/// A temperature-dependent kernel (see the module docs).
pub trait TemperatureKernel {
    /// The rates of the pair `(i, T_i), (j, T_j)` (sizes ≥ 1, temperatures ≥ 0).
    fn rates(&self, i: u64, ti: f64, j: u64, tj: f64) -> PairRates;

    /// `C_ij` alone (what a proposal's acceptance needs; the other rates are needed
    /// only for accepted pairs). Must equal `rates(i, ti, j, tj).collision`.
    fn collision(&self, i: u64, ti: f64, j: u64, tj: f64) -> f64 {
        self.rates(i, ti, j, tj).collision
    }

    /// The factors of size `i` at temperature `t` of the proposal bound
    /// `A(i, j) = Σ_k a_k(i, T_i) b_k(j)`, with `A(i, j) + A(j, i) ≥ C_ij` for all
    /// temperatures; unused entries are 0.
    fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]);
}

/// The ballistic kernels of the paper (see the module docs), with restitution
/// coefficient ε ∈ (0, 1], barrier height `a ≥ 0` and barrier exponent λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ballistic {
    eps: f64,
    a: f64,
    lambda: f64,
}

impl Ballistic {
    /// The kernels for restitution coefficient `eps ∈ (0, 1]`, aggregation barrier
    /// `a ≥ 0` and exponent `lambda` (finite). `W_ij` is the normal kinetic energy
    /// below which a collision sticks: a collision bounces with probability
    /// `f = e^{−q}(1 + q)`, `q = W / (ε² μ s²)`, so with `a = 0` every collision
    /// bounces.
    pub fn new(eps: f64, a: f64, lambda: f64) -> Result<Self> {
        if !(eps > 0.0 && eps <= 1.0) {
            return Err(Error::OutOfRange {
                name: "restitution coefficient",
                value: eps,
                range: "(0, 1]",
            });
        }
        if !(a >= 0.0 && a.is_finite()) {
            return Err(Error::OutOfRange {
                name: "aggregation barrier a",
                value: a,
                range: "[0, inf)",
            });
        }
        crate::error::finite("barrier exponent lambda", lambda)?;
        Ok(Ballistic { eps, a, lambda })
    }

    /// The paper's parameters: ε = 0.99, a = 0.1, λ = 0.4.
    pub fn paper() -> Self {
        Ballistic {
            eps: 0.99,
            a: 0.1,
            lambda: 0.4,
        }
    }

    /// The aggregation barrier `W_ij = a (i^{1/3} j^{1/3})^λ / (i^{1/3} + j^{1/3})^λ`.
    pub fn barrier(&self, i: u64, j: u64) -> f64 {
        self.barrier_of(size_cbrt(i), size_cbrt(j))
    }

    /// The barrier from the cube roots of the sizes (`z^λ` as `e^{λ ln z}`: within a
    /// few ulp of `pow`, at half its cost).
    #[inline]
    fn barrier_of(&self, ci: f64, cj: f64) -> f64 {
        self.a * exp(self.lambda * log(ci * cj / (ci + cj)))
    }
}

impl TemperatureKernel for Ballistic {
    #[inline]
    fn collision(&self, i: u64, ti: f64, j: u64, tj: f64) -> f64 {
        let (x, y) = (i as f64, j as f64);
        let s2 = ti / x + tj / y;
        if s2.is_nan() || s2 <= 0.0 {
            return 0.0;
        }
        let d = size_cbrt(i) + size_cbrt(j);
        SQRT_HALF_PI * d * d * sqrt(s2)
    }

    fn rates(&self, i: u64, ti: f64, j: u64, tj: f64) -> PairRates {
        let (x, y) = (i as f64, j as f64);
        let s2 = ti / x + tj / y;
        if s2.is_nan() || s2 <= 0.0 {
            // both species at rest: nothing collides
            return PairRates::default();
        }
        let (ci, cj) = (size_cbrt(i), size_cbrt(j));
        let d = ci + cj;
        let c = SQRT_HALF_PI * d * d * sqrt(s2);
        let mu = x * y / (x + y);
        let q = self.barrier_of(ci, cj) / (self.eps * self.eps * mu * s2);
        // f = e^{−q}(1 + q), g = e^{−q}(1 + q + q²/2); q = inf gives 0, not 0·inf
        let (f, g) = if q.is_finite() {
            let e = exp(-q);
            (e * (1.0 + q), e * (1.0 + q + 0.5 * q * q))
        } else {
            (0.0, 0.0)
        };
        let four_thirds = 4.0 / 3.0;
        let energy_gain = c
            * ((1.0 - f) * ti * tj * (1.0 / x + 1.0 / y)
                + four_thirds * (1.0 - g) * (ti - tj) * (ti - tj) / (x + y))
            / s2;
        let agg = |ta: f64, a: f64, tb: f64, b: f64| {
            c * ta * ((1.0 - f) * tb / b + four_thirds * (1.0 - g) * ta / a) / s2
        };
        let e1 = 1.0 + self.eps;
        let res = |ta: f64, a: f64, tb: f64, b: f64| {
            four_thirds
                * e1
                * c
                * g
                * (b / (a + b))
                * (ta - e1 * (b * ta + a * tb) / (2.0 * (a + b)))
        };
        PairRates {
            collision: c,
            aggregation: c * (1.0 - f),
            restitution: c * f,
            energy_gain,
            aggregation_loss: [agg(ti, x, tj, y), agg(tj, y, ti, x)],
            restitution_loss: [res(ti, x, tj, y), res(tj, y, ti, x)],
        }
    }

    /// `A(i, j) = sqrt(π/2) (i^{1/3} + j^{1/3})² sqrt(T_i/i)`: `a = sqrt(π/2 · T_i/i)
    /// (i^{2/3}, 2 i^{1/3}, 1)`, `b = (1, j^{1/3}, j^{2/3})`; `A + Aᵀ ≥ C` since
    /// `sqrt(θ_i + θ_j) ≤ sqrt(θ_i) + sqrt(θ_j)`.
    fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]) {
        let x = i as f64;
        let ci = size_cbrt(i);
        let w = SQRT_HALF_PI * sqrt(t / x);
        *a = [w * ci * ci, 2.0 * w * ci, w];
        *b = [1.0, ci, ci * ci];
    }
}

/// The built-in temperature kernels as one type: the temperature model a registry
/// build takes (`Model::Temperature`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TemperatureModel {
    /// The paper's ballistic kernels.
    Ballistic(Ballistic),
    /// The family with a closed-form solution.
    ClosedForm(ClosedForm),
}

impl TemperatureModel {
    /// A fingerprint of the model and its parameters (for checkpoints).
    pub fn fingerprint(&self) -> u64 {
        match *self {
            TemperatureModel::Ballistic(b) => crate::checkpoint::fingerprint([
                0x5445_4d50_4241_4c4c, // "TEMPBALL"
                b.eps.to_bits(),
                b.a.to_bits(),
                b.lambda.to_bits(),
            ]),
            TemperatureModel::ClosedForm(m) => crate::checkpoint::fingerprint([
                0x5445_4d50_434c_4f53, // "TEMPCLOS"
                m.c.to_bits(),
                m.gamma.to_bits(),
            ]),
        }
    }
}

impl TemperatureKernel for TemperatureModel {
    #[inline]
    fn rates(&self, i: u64, ti: f64, j: u64, tj: f64) -> PairRates {
        match self {
            TemperatureModel::Ballistic(k) => k.rates(i, ti, j, tj),
            TemperatureModel::ClosedForm(k) => k.rates(i, ti, j, tj),
        }
    }
    #[inline]
    fn collision(&self, i: u64, ti: f64, j: u64, tj: f64) -> f64 {
        match self {
            TemperatureModel::Ballistic(k) => k.collision(i, ti, j, tj),
            TemperatureModel::ClosedForm(k) => k.collision(i, ti, j, tj),
        }
    }
    #[inline]
    fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]) {
        match self {
            TemperatureModel::Ballistic(k) => k.factors(i, t, a, b),
            TemperatureModel::ClosedForm(k) => k.factors(i, t, a, b),
        }
    }
}

/// A model family with a closed-form solution ([`ClosedForm::exact`]): with constants
/// `c > 0`, `γ ≥ 0`,
/// `C^agg_ij = c sqrt((T_i/i + T_j/j)/2)`, `C^res_ij = C^agg_ij`, `B_ij = C^agg_ij (T_i + T_j)`,
/// `D^agg_ij = C^agg_ij T_i`, `D^res_ij = γ C^agg_ij T_i`: a new cluster gets `T_i + T_j`,
/// survivors keep their temperatures, and each bounce lowers the species' total by
/// `γ T_i`. γ = 0 is a constant kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosedForm {
    c: f64,
    gamma: f64,
}

impl ClosedForm {
    /// The family's kernels for `c > 0` and `γ ≥ 0` (both finite).
    pub fn new(c: f64, gamma: f64) -> Result<Self> {
        crate::error::positive("model constant c", c)?;
        if !(gamma >= 0.0 && gamma.is_finite()) {
            return Err(Error::OutOfRange {
                name: "model exponent gamma",
                value: gamma,
                range: "[0, inf)",
            });
        }
        Ok(ClosedForm { c, gamma })
    }

    /// The solution from `n_1(0) = n0`, `T_1(0) = t0` at time t.
    pub fn exact(&self, n0: f64, t0: f64, t: f64) -> ClosedFormSolution {
        let g1 = 1.0 + self.gamma;
        let u = pow(1.0 + g1 * self.c * n0 * sqrt(t0) * t / 2.0, 1.0 / g1);
        ClosedFormSolution {
            n0,
            t0,
            u,
            gamma: self.gamma,
        }
    }
}

impl TemperatureKernel for ClosedForm {
    fn rates(&self, i: u64, ti: f64, j: u64, tj: f64) -> PairRates {
        let cagg = self.c * sqrt(0.5 * (ti / i as f64 + tj / j as f64));
        PairRates {
            collision: 2.0 * cagg,
            aggregation: cagg,
            restitution: cagg,
            energy_gain: cagg * (ti + tj),
            aggregation_loss: [cagg * ti, cagg * tj],
            restitution_loss: [self.gamma * cagg * ti, self.gamma * cagg * tj],
        }
    }

    /// `C = 2c sqrt((θ_i + θ_j)/2) ≤ √2 c (sqrt(θ_i) + sqrt(θ_j))`: rank 1,
    /// `a = √2 c sqrt(T_i/i)`, `b = 1`.
    fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]) {
        *a = [
            core::f64::consts::SQRT_2 * self.c * sqrt(t / i as f64),
            0.0,
            0.0,
        ];
        *b = [1.0, 0.0, 0.0];
    }
}

/// The closed-form solution of a [`ClosedForm`] (TEMPERATURE.md):
/// `u(t) = [1 + (1+γ) c n0 sqrt(T0) t / 2]^{1/(1+γ)}`, `n_k = n0 (u − 1)^{k−1} / u^{k+1}`,
/// `N = n0 / u`, `T_k = k T0 u^{−2γ}`, mean temperature `T0 u^{1−2γ}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosedFormSolution {
    n0: f64,
    t0: f64,
    u: f64,
    gamma: f64,
}

impl ClosedFormSolution {
    /// `u(t)`.
    pub fn u(&self) -> f64 {
        self.u
    }
    /// The number concentration `N(t) = Σ_k n_k`.
    pub fn number(&self) -> f64 {
        self.n0 / self.u
    }
    /// `n_k(t)` (0 for k = 0).
    pub fn density(&self, k: u64) -> f64 {
        if k == 0 {
            return 0.0;
        }
        let u = self.u;
        self.n0 * pow((u - 1.0) / u, (k - 1) as f64) / (u * u)
    }
    /// `T_k(t)`.
    pub fn temperature(&self, k: u64) -> f64 {
        k as f64 * self.t0 * pow(self.u, -2.0 * self.gamma)
    }
    /// The mean temperature `Σ n_k T_k / N`.
    pub fn mean_temperature(&self) -> f64 {
        self.t0 * pow(self.u, 1.0 - 2.0 * self.gamma)
    }
}

/// The right-hand side of the population equations (module docs) for sizes
/// `1..=n.len()` (clusters past the last size are dropped: a truncation): from the
/// concentrations `n[k − 1] = n_k` and the energy densities `e[k − 1] = n_k T_k`, writes
/// `dn[k − 1] = dn_k/dt` and `de[k − 1] = d(n_k T_k)/dt`. O(L²) kernel evaluations
/// for L sizes. Errors: `e`, `dn` or `de` not as long as `n`.
pub fn rhs<K: TemperatureKernel + ?Sized>(
    kernel: &K,
    n: &[f64],
    e: &[f64],
    dn: &mut [f64],
    de: &mut [f64],
) -> Result<()> {
    let l = n.len();
    for (name, got) in [("e", e.len()), ("dn", dn.len()), ("de", de.len())] {
        if got != l {
            return Err(Error::BufferLength {
                name,
                expected: l,
                got,
            });
        }
    }
    dn.fill(0.0);
    de.fill(0.0);
    let temp = |k: usize| if n[k] > 0.0 { e[k] / n[k] } else { 0.0 };
    for a in 0..l {
        if n[a] <= 0.0 {
            continue;
        }
        for b in a..l {
            if n[b] <= 0.0 {
                continue;
            }
            let (i, j) = (a as u64 + 1, b as u64 + 1);
            let r = kernel.rates(i, temp(a), j, temp(b));
            // ordered pairs (a, b) and (b, a) for a ≠ b: the 1/2 of the gain cancels
            let w = if a == b { 0.5 } else { 1.0 } * n[a] * n[b];
            let m = a + b + 1; // index of size i + j
            if m < l {
                dn[m] += w * r.aggregation;
                de[m] += w * r.energy_gain;
            }
            // each of the two species loses one cluster per aggregation
            let lose = |x: &mut [f64], y: &mut [f64], k: usize, d_agg: f64, d_res: f64| {
                x[k] -= w * r.aggregation;
                y[k] -= w * (d_agg + d_res);
            };
            lose(dn, de, a, r.aggregation_loss[0], r.restitution_loss[0]);
            lose(dn, de, b, r.aggregation_loss[1], r.restitution_loss[1]);
        }
    }
    Ok(())
}

/// Integrates the population equations (module docs) for sizes `1..=n.len()` (clusters
/// past the last size are dropped) from `t0` to `t1` by the classical Runge–Kutta
/// method with steps of at most `h`, in place: `n[k − 1] = n_k`, `e[k − 1] = n_k T_k`.
/// For comparing a Monte Carlo run with its equations; the step and the truncation
/// are the caller's to check (halve h, double the sizes). Errors: lengths differ, `h`
/// or the interval not finite and positive (an empty interval does nothing).
///
/// ```
/// use coagula_core::kernel::temperature::{ClosedForm, integrate};
/// let m = ClosedForm::new(1.0, 0.5).unwrap();
/// let (mut n, mut e) = (vec![0.0; 200], vec![0.0; 200]);
/// (n[0], e[0]) = (1.0, 1.0);
/// integrate(&m, &mut n, &mut e, 0.0, 1.0, 0.01).unwrap();
/// let exact = m.exact(1.0, 1.0, 1.0);
/// let number: f64 = n.iter().sum();
/// assert!((number - exact.number()).abs() < 1e-9);
/// ```
pub fn integrate<K: TemperatureKernel + ?Sized>(
    kernel: &K,
    n: &mut [f64],
    e: &mut [f64],
    t0: f64,
    t1: f64,
    h: f64,
) -> Result<()> {
    let l = n.len();
    if e.len() != l {
        return Err(Error::BufferLength {
            name: "e",
            expected: l,
            got: e.len(),
        });
    }
    crate::error::positive("step h", h)?;
    crate::error::finite("start time", t0)?;
    crate::error::finite("end time", t1)?;
    if t1 <= t0 {
        return Ok(());
    }
    let steps = libm::ceil((t1 - t0) / h).max(1.0);
    if steps > 1e12 {
        return Err(Error::OutOfRange {
            name: "steps of the deterministic solve",
            value: steps,
            range: "(0, 1e12]",
        });
    }
    let h = (t1 - t0) / steps;
    let mut k = alloc::vec![[alloc::vec![0.0; l], alloc::vec![0.0; l]]; 4];
    let (mut sn, mut se) = (alloc::vec![0.0; l], alloc::vec![0.0; l]);
    for _ in 0..steps as u64 {
        for stage in 0..4 {
            let w = [0.0, 0.5, 0.5, 1.0][stage] * h;
            for q in 0..l {
                let (dn, de) = if stage == 0 {
                    (0.0, 0.0)
                } else {
                    (k[stage - 1][0][q], k[stage - 1][1][q])
                };
                sn[q] = n[q] + w * dn;
                se[q] = e[q] + w * de;
            }
            let [kn, ke] = &mut k[stage];
            rhs(kernel, &sn, &se, kn, ke)?;
        }
        for q in 0..l {
            n[q] += h / 6.0 * (k[0][0][q] + 2.0 * k[1][0][q] + 2.0 * k[2][0][q] + k[3][0][q]);
            e[q] += h / 6.0 * (k[0][1][q] + 2.0 * k[1][1][q] + 2.0 * k[2][1][q] + k[3][1][q]);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::coagulation::{CBRT_TABLE, cbrt};
    use alloc::vec;
    use alloc::vec::Vec;
    use approx::assert_relative_eq;

    #[test]
    fn kernel_identities_of_temperature_md() {
        // D^agg_ij + D^agg_ji − B_ij = 4/3 C (1 − g) μ s²: the kinetic energy an
        // aggregation loses; with ε = 1 and no barrier, bounces conserve energy
        let k = Ballistic::paper();
        let elastic = Ballistic::new(1.0, 0.0, 0.4).unwrap();
        for &(i, ti, j, tj) in &[
            (1, 1.0, 1, 1.0),
            (1, 1.0, 7, 0.3),
            (5, 2.5, 3, 0.01),
            (100, 40.0, 1, 1.0),
            (64, 1e-3, 64, 5.0),
        ] {
            let r = k.rates(i, ti, j, tj);
            let (x, y) = (i as f64, j as f64);
            let s2 = ti / x + tj / y;
            let mu = x * y / (x + y);
            let q = k.barrier(i, j) / (0.99 * 0.99 * mu * s2);
            let g = exp(-q) * (1.0 + q + q * q / 2.0);
            let lost = r.aggregation_loss[0] + r.aggregation_loss[1] - r.energy_gain;
            assert_relative_eq!(
                lost,
                4.0 / 3.0 * r.collision * (1.0 - g) * mu * s2,
                max_relative = 1e-12
            );
            assert_relative_eq!(
                r.aggregation + r.restitution,
                r.collision,
                max_relative = 1e-15
            );
            let e = elastic.rates(i, ti, j, tj);
            let scale = e.restitution_loss[0].abs() + e.restitution_loss[1].abs();
            assert!((e.restitution_loss[0] + e.restitution_loss[1]).abs() <= 1e-13 * scale);
            // W is the energy below which a collision sticks: without it (q = 0)
            // every collision bounces
            assert_eq!((e.aggregation, e.restitution), (0.0, e.collision));
        }
    }

    #[test]
    fn the_proposal_bounds_cover_the_collision_rate() {
        let kernels: [&dyn TemperatureKernel; 2] =
            [&Ballistic::paper(), &ClosedForm::new(1.3, 0.5).unwrap()];
        for k in kernels {
            for i in [1u64, 2, 3, 10, 1000] {
                for j in [1u64, 4, 9, 500] {
                    for (ti, tj) in [(1.0, 1.0), (1e-6, 3.0), (20.0, 0.0), (0.0, 0.0)] {
                        let (mut ai, mut bi, mut aj, mut bj) =
                            ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
                        k.factors(i, ti, &mut ai, &mut bi);
                        k.factors(j, tj, &mut aj, &mut bj);
                        let bound: f64 = (0..3).map(|q| ai[q] * bj[q] + aj[q] * bi[q]).sum();
                        let c = k.rates(i, ti, j, tj).collision;
                        assert!(
                            c <= bound * (1.0 + 1e-12),
                            "{i} {ti} {j} {tj}: {c} > {bound}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_model_solution_solves_the_equations() {
        // d/dt of the closed form (central differences) against the right-hand side,
        // sizes truncated where n_k is below 1e-30 of n_1: checks the recovered
        // solution, the model's kernels and `rhs` together (a factor 2 in any of them,
        // or a lost 1/2 on equal sizes, moves the residual to O(1))
        for gamma in [0.0, 0.5, 1.0] {
            let m = ClosedForm::new(0.8, gamma).unwrap();
            let (n0, t0) = (0.3, 1.7);
            for t in [0.2, 1.0, 4.0] {
                let l = 400;
                let at = |t: f64| {
                    let s = m.exact(n0, t0, t);
                    let n: Vec<f64> = (1..=l as u64).map(|k| s.density(k)).collect();
                    let e: Vec<f64> = (1..=l as u64)
                        .map(|k| s.density(k) * s.temperature(k))
                        .collect();
                    (n, e)
                };
                let h = 1e-5;
                let (np, ep) = at(t + h);
                let (nm, em) = at(t - h);
                let (n, e) = at(t);
                let (mut dn, mut de) = (vec![0.0; l], vec![0.0; l]);
                rhs(&m, &n, &e, &mut dn, &mut de).unwrap();
                for k in 0..40 {
                    let fd_n = (np[k] - nm[k]) / (2.0 * h);
                    let fd_e = (ep[k] - em[k]) / (2.0 * h);
                    let sn = n[0] * 1e-6;
                    let se = e[0] * 1e-6;
                    assert!(
                        (dn[k] - fd_n).abs() < sn,
                        "γ {gamma} t {t} k {k}: {} vs {fd_n}",
                        dn[k]
                    );
                    assert!(
                        (de[k] - fd_e).abs() < se,
                        "γ {gamma} t {t} k {k}: {} vs {fd_e}",
                        de[k]
                    );
                }
                // the closed form's sums
                let s = m.exact(n0, t0, t);
                let total: f64 = n.iter().sum();
                assert_relative_eq!(total, s.number(), max_relative = 1e-9);
                let mean_t: f64 = e.iter().sum::<f64>() / total;
                assert_relative_eq!(mean_t, s.mean_temperature(), max_relative = 1e-9);
            }
        }
    }

    #[test]
    fn tabulated_cube_roots_and_the_fast_paths_are_exact_enough() {
        for i in 1..(CBRT_TABLE as u64 + 10) {
            let (got, want) = (size_cbrt(i), libm::cbrt(i as f64));
            assert!(
                (got - want).abs() <= f64::EPSILON * want,
                "cbrt({i}): {got} vs {want}"
            );
        }
        let k = Ballistic::paper();
        for (i, j) in [(1, 1), (2, 7), (30, 1000), (5000, 3)] {
            for (ti, tj) in [(1.0, 0.5), (0.0, 2.0), (3.0, 0.0)] {
                let r = k.rates(i, ti, j, tj);
                assert_eq!(k.collision(i, ti, j, tj).to_bits(), r.collision.to_bits());
                let want = 0.1
                    * pow(
                        cbrt(i as f64) * cbrt(j as f64) / (cbrt(i as f64) + cbrt(j as f64)),
                        0.4,
                    );
                assert!(
                    (k.barrier(i, j) / want - 1.0).abs() < 1e-14,
                    "barrier({i}, {j})"
                );
            }
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(Ballistic::new(0.0, 0.1, 0.4).is_err());
        assert!(Ballistic::new(1.5, 0.1, 0.4).is_err());
        assert!(Ballistic::new(0.9, -1.0, 0.4).is_err());
        assert!(Ballistic::new(0.9, 0.1, f64::NAN).is_err());
        assert!(ClosedForm::new(0.0, 1.0).is_err());
        assert!(ClosedForm::new(1.0, -0.5).is_err());
        let mut out = [0.0; 2];
        assert!(
            rhs(
                &ClosedForm::new(1.0, 0.0).unwrap(),
                &[1.0; 3],
                &[1.0; 2],
                &mut out,
                &mut [0.0; 2]
            )
            .is_err()
        );
        // species at rest do not collide (no 0/0)
        let r = Ballistic::paper().rates(1, 0.0, 2, 0.0);
        assert_eq!(r, PairRates::default());
    }
}
