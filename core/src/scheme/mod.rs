//! Stepping schemes, all behind one interface: [`Scheme::advance_to`].
//!
//! A host time integrator calls `advance_to(t, rng)` once per outer step: time-driven
//! schemes take their steps up to `t`, event-driven ones process every event before `t`
//! and stop exactly at `t` (the exponential waiting times are memoryless, so the residual
//! wait is simply redrawn). The returned [`StepReport`] says what happened; observables
//! are read between calls.
//!
//! Schemes:
//! * [`massflow`] — the time-driven mass-flow scheme of Lécot et al. (2019): QMC, MC,
//!   RQMC;
//! * [`lowrank`] — Osinsky's low-rank Monte Carlo with segment trees, and the inverse and
//!   acceptance–rejection baselines it is measured against (Osinsky 2023).

pub(crate) mod clock;
pub mod lowrank;
pub mod massflow;

use crate::error::Result;
use rand_core::Rng;

/// What one call of [`Scheme::advance_to`] did. `#[non_exhaustive]`: schemes to come
/// add what they report; build one with `StepReport::default()`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct StepReport {
    /// Time reached (the requested time on success).
    pub time: f64,
    /// Accepted events (coagulations, fragmentations).
    pub events: u64,
    /// Proposals, accepted or not.
    pub proposals: u64,
    /// Proposals rejected by thinning (including same-particle rejections).
    pub rejections: u64,
    /// Proposals where the kernel exceeded its declared bound. Always 0 since a
    /// violated bound became an error (`Error::BoundExceeded`, the state as before the
    /// event); kept for the C ABI's step report.
    pub bound_violations: u64,
    /// Time steps whose probabilities exceeded 1 and were clipped (time-driven schemes).
    pub clipped: u64,
    /// Times the particle number was doubled (size-count schemes).
    pub doublings: u64,
    /// Particles that left the system (beyond a truncation size, into a gel, absorbed
    /// by a wall); 0 for the schemes that keep every particle.
    pub removed: u64,
    /// Collisions that bounced instead of merging (schemes with restitution, specular
    /// walls); 0 for pure coagulation.
    pub bounces: u64,
}

impl StepReport {
    /// Adds the counts of `other` (time is taken from `other`).
    pub fn accumulate(&mut self, other: &StepReport) {
        self.time = other.time;
        self.events += other.events;
        self.proposals += other.proposals;
        self.rejections += other.rejections;
        self.bound_violations += other.bound_violations;
        self.clipped += other.clipped;
        self.doublings += other.doublings;
        self.removed += other.removed;
        self.bounces += other.bounces;
    }
}

/// The stepping interface shared by every scheme.
pub trait Scheme {
    /// Current simulation time.
    fn time(&self) -> f64;

    /// Runs until time `t ≥ self.time()`. Errors (a time in the past, a capacity
    /// exceeded, a kernel returning NaN) leave the state as it was before the failing
    /// event.
    fn advance_to<R: Rng + ?Sized>(&mut self, t: f64, rng: &mut R) -> Result<StepReport>;
}

/// A uniform double in `(0, 1]` (never 0, so `ln` is finite).
#[inline]
pub(crate) fn open_unit<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    ((rng.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// An exponential variate with mean 1.
#[inline]
pub(crate) fn exp1<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    -libm::log(open_unit(rng))
}

/// Validates a target time against the current time.
pub(crate) fn check_target(now: f64, t: f64) -> Result<()> {
    crate::error::finite("t", t)?;
    if t < now {
        return Err(crate::error::Error::TimeBackwards { now, requested: t });
    }
    Ok(())
}

/// Exponential variates by the ziggurat method (Marsaglia & Tsang 2000), 256 layers:
/// one 64-bit draw, one multiply and one comparison in ~99% of calls, exact in
/// distribution (the rare wedge and tail cases fall back to `exp`/`ln`). The tables are
/// constants ([`ziggurat_table`]), computed with `libm` and checked bit for bit against
/// that computation by a test, so they are identical on every platform and building a
/// scheme costs no 500 `exp`/`ln` calls (which dominated small systems).
#[derive(Clone, Copy)]
pub(crate) struct Ziggurat;

impl core::fmt::Debug for Ziggurat {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Ziggurat")
    }
}

/// Rightmost layer boundary and layer area of the 256-layer exponential ziggurat.
const ZIG_EXP_R: f64 = 7.697_117_470_131_05;
#[cfg(test)]
const ZIG_EXP_V: f64 = 0.003_949_659_822_581_557;

mod ziggurat_table;

impl Ziggurat {
    pub(crate) fn new() -> Self {
        Ziggurat
    }

    /// The tables as `libm` computes them: layer boundaries `x` and `f = exp(−x)`.
    #[cfg(test)]
    fn compute() -> ([f64; 257], [f64; 257]) {
        let (mut x, mut f) = ([0.0; 257], [0.0; 257]);
        let fr = libm::exp(-ZIG_EXP_R);
        x[0] = ZIG_EXP_V / fr;
        x[1] = ZIG_EXP_R;
        for i in 2..256 {
            x[i] = -libm::log(ZIG_EXP_V / x[i - 1] + libm::exp(-x[i - 1]));
        }
        x[256] = 0.0;
        for i in 0..257 {
            f[i] = libm::exp(-x[i]);
        }
        (x, f)
    }

    /// An exponential variate with mean 1.
    #[inline(always)]
    pub(crate) fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let (xs, fs) = (&ziggurat_table::X, &ziggurat_table::F);
        loop {
            let bits = rng.next_u64();
            let i = (bits & 0xff) as usize;
            let u = (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            let x = u * xs[i];
            if x < xs[i + 1] {
                return x;
            }
            if i == 0 {
                // tail beyond R: memoryless, R + Exp(1)
                return ZIG_EXP_R + exp1(rng);
            }
            let y = fs[i + 1] + (fs[i] - fs[i + 1]) * crate::tree::unit_f64(rng.next_u64());
            if y < libm::exp(-x) {
                return x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constant tables are what `libm` computes, bit for bit (on a mismatch the
    /// message is the table to paste into `ziggurat_table.rs`).
    #[test]
    fn ziggurat_tables_are_the_libm_computation() {
        let (x, f) = Ziggurat::compute();
        let same = |a: &[f64; 257], b: &[f64; 257]| {
            a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits())
        };
        if !same(&x, &ziggurat_table::X) || !same(&f, &ziggurat_table::F) {
            let mut out = alloc::string::String::new();
            for (name, t) in [("X", &x), ("F", &f)] {
                out.push_str(&alloc::format!(
                    "pub(super) static {name}: [f64; 257] = [\n"
                ));
                for v in t.iter() {
                    out.push_str(&alloc::format!(
                        "    f64::from_bits(0x{:016x}),\n",
                        v.to_bits()
                    ));
                }
                out.push_str("];\n");
            }
            panic!("ziggurat tables differ from libm's:\n{out}");
        }
    }

    /// The ziggurat's moments and tail probabilities match Exp(1) within 5 standard
    /// errors over 4e6 draws.
    #[test]
    fn ziggurat_is_exponential() {
        let z = Ziggurat::new();
        let mut rng = rand_pcg::Pcg64Mcg::new(77);
        let n = 4_000_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        let thresholds = [0.01, 0.5, 1.0, 3.0, 7.0, 7.7, 9.0];
        let mut above = [0usize; 7];
        for _ in 0..n {
            let x = z.sample(&mut rng);
            assert!(x >= 0.0 && x.is_finite());
            s1 += x;
            s2 += x * x;
            for (c, &t) in above.iter_mut().zip(&thresholds) {
                if x > t {
                    *c += 1;
                }
            }
        }
        let nf = n as f64;
        let mean = s1 / nf;
        assert!((mean - 1.0).abs() < 5.0 / libm::sqrt(nf), "mean {mean}");
        let m2 = s2 / nf; // E x² = 2, Var x² = 20
        assert!(
            (m2 - 2.0).abs() < 5.0 * libm::sqrt(20.0 / nf),
            "second moment {m2}"
        );
        for (c, &t) in above.iter().zip(&thresholds) {
            let p = libm::exp(-t);
            let se = libm::sqrt(p * (1.0 - p) / nf);
            let got = *c as f64 / nf;
            assert!(
                (got - p).abs() < 5.0 * se + 1e-9,
                "P(X > {t}) = {got}, expected {p}"
            );
        }
    }
}
