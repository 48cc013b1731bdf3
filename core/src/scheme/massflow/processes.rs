//! Sources, removal and growth in the time-driven mass flow: the particles keep their
//! number and their equal share `M1/N` of the mass; a process moves mass, so it moves
//! particles between sizes and changes M1 (the design and its derivation:
//! `docs/design/processes.md`, "Mass-flow schemes").
//!
//! With the unnormalised mass density `g = x c`, a source of `S p(x)` particles, removal
//! at `λ(x)` and growth `dx/dt = G(x)` add to the coagulation terms
//! `S x p(x) − λ g − ∂(G g)/∂x + (G/x) g`. Over a step of length h, from sizes `x_k`:
//!
//! * growth carries mass along its characteristics: every particle is moved to its
//!   grown size `Φ_h(x)` (after the coagulation jumps; `Φ_h` is monotone, so the order
//!   holds) and the mass on a particle would grow by `Φ_h(x_k)/x_k`; removal takes
//!   `1 − e^{−h λ(x_k)}` of it. Their log-factor `γ_k = ln(Φ_h(x_k)/x_k) − h λ(x_k)`
//!   differs between particles; equal shares are kept by letting particle k take its
//!   partner l's size with probability `(γ_l − γ_k)^+` — the same partner and the same
//!   uniform `u_3` that select coagulation, so QMC points drive it too. The expected
//!   share at `x_k` is then `(1 + γ_k − γ̄)/N`, the normalised `e^{γ_k}` to first
//!   order in h (a γ the same for every particle — dilution, linear growth — moves
//!   none);
//! * a source adds the mass `μ ∫S dt` (μ the mean size it injects): a particle takes a
//!   size from the source's mass distribution `x p(x)/μ` with probability the injected
//!   share of the new mass, at the rescaled `u_3` (a conditional uniform);
//! * M1 becomes `M1/N Σ_k (Φ_h(x_k)/x_k) e^{−h λ(x_k)} + μ ∫S dt`, and the books count
//!   the three parts, so that they balance to rounding.
//!
//! The step is first order in h, as the coagulation step is (Lécot & Tarhini 2007 split
//! condensation and deposition off the QMC coagulation of the mass flow the same way;
//! the update here is ours, derived above and checked against the exact solutions in
//! `core/tests/processes_massflow.rs`).

use crate::error::{Error, Result};
use crate::process::{Books, Processes, Source};

/// What one step of length h does beside coagulation, from the sizes before it.
pub(super) struct Plan<'a> {
    /// The source, when it injects in this step.
    pub source: Option<&'a Source>,
    /// The probability that a particle takes a source size: the injected share of the
    /// mass after the step.
    pub source_share: f64,
    /// Whether particles jump to their partner's size (`γ` in the scratch differs).
    pub jumps: bool,
    /// Whether the particles grow (their grown sizes are in the next-sizes buffer).
    pub grows: bool,
    /// M1 after the step.
    pub mass: f64,
    injected: f64,
    removed: f64,
    grown: f64,
}

impl Plan<'_> {
    /// Enters the step in the books.
    pub fn book(&self, books: &mut Books) {
        books.injected_mass += self.injected;
        books.removed_mass += self.removed;
        books.grown_mass += self.grown;
    }
}

/// The removal rate at `x`: the power's and the host's, summed.
fn removal(p: &Processes, x: f64) -> Result<f64> {
    let mut r = p.removal.map_or(0.0, |q| q.at(x));
    if let Some(u) = &p.user_removal {
        r += u.at(x)?;
    }
    Ok(r)
}

/// The largest share of the mass one step may remove: beyond it M1 would be the
/// rounding residue of nearly equal sums (and the step is far outside the first-order
/// regime of the scheme).
const MAX_REMOVED_SHARE: f64 = 1.0 - 1e-6;

/// The largest spread of the log-factors γ over one step: the jump probabilities
/// `(γ_l − γ_k)^+` are a linearisation and must stay below 1.
const MAX_SPREAD: f64 = 1.0;

/// What a step of `h` does to a particle of size `x`: its grown size `Φ_h(x)` (one
/// formula for every particle, so that equal sizes stay equal), the mass it gains per
/// unit of its mass `Φ/x − 1`, what of the grown mass it keeps `(Φ/x) e^{−hλ}` and
/// loses `(Φ/x)(1 − e^{−hλ})`, and its log-factor `γ = ln(Φ/x) − hλ`.
pub(super) struct Factors {
    pub size: f64,
    gain: f64,
    kept: f64,
    lost: f64,
    gamma: f64,
}

pub(super) fn factors(p: &Processes, x: f64, h: f64) -> Result<Factors> {
    let (size, lr) = if p.user_growth.is_some() {
        let y = p.grow(x, h)?;
        (y, libm::log(y / x))
    } else {
        let lr = p.log_growth(x, h)?;
        (x + x * libm::expm1(lr), lr)
    };
    if !(size.is_finite() && size > 0.0 && lr.is_finite()) {
        return Err(Error::InvalidRate {
            name: "grown size (finite and positive)",
            value: size,
        });
    }
    let hl = h * crate::error::finite("removal rate", removal(p, x)?)?;
    let ratio = size / x;
    let (kept, lost) = if hl == 0.0 {
        (ratio, 0.0)
    } else {
        (ratio * libm::exp(-hl), ratio * -libm::expm1(-hl))
    };
    Ok(Factors {
        size,
        gain: ratio - 1.0,
        kept,
        lost,
        gamma: lr - hl,
    })
}

/// The plan of a step from `t` to `t + h` over the sorted sizes `x` of mass `mass`,
/// writing `γ_k` into `gamma` (when a removal or growth acts) and, when the particles
/// grow, their grown sizes `Φ_h(x_k)` into `phi` (the step keeps them for the
/// particles it does not move, and grows the others itself). Nothing else changes,
/// so an error leaves the scheme as it was.
pub(super) fn plan<'a>(
    p: &'a Processes,
    x: &[f64],
    gamma: &mut [f64],
    phi: &mut [f64],
    mass: f64,
    t: f64,
    h: f64,
) -> Result<Plan<'a>> {
    let grows = p.grows();
    let w = mass / x.len() as f64;
    let (mut grown_sum, mut removed_sum, mut kept_sum) = (0.0, 0.0, x.len() as f64);
    let local = p.removal.is_some() || p.user_removal.is_some() || p.grows();
    // the same γ for every particle (a constant removal rate, linear growth): no
    // jumps, and the sums are N times one particle's (the grown sizes still each)
    let uniform = p.user_removal.is_none()
        && p.user_growth.is_none()
        && p.removal.is_none_or(|q| q.exponent == 0.0)
        && p.growth.is_none_or(|q| q.exponent == 1.0);
    let mut jumps = false;
    if local && uniform {
        let f = factors(p, x.first().copied().unwrap_or(1.0), h)?;
        let n = x.len() as f64;
        (grown_sum, removed_sum, kept_sum) = (n * f.gain, n * f.lost, n * f.kept);
        if grows {
            // (the formula of `factors`: lr is the same at every size here)
            let e = libm::expm1(p.log_growth(x.first().copied().unwrap_or(1.0), h)?);
            for (g, &xk) in phi.iter_mut().zip(x) {
                *g = xk + xk * e;
            }
            if let Some(&y) = phi.last()
                && !(y.is_finite() && y > 0.0)
            {
                return Err(Error::InvalidRate {
                    name: "grown size (finite and positive)",
                    value: y,
                });
            }
        }
    } else if local {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        kept_sum = 0.0;
        // (the sizes are sorted, and repeat often — a start from monomers, integer
        // sizes from coagulation: a run of equal sizes is evaluated once)
        let mut last: Option<(f64, Factors)> = None;
        for ((g, f), &xk) in gamma.iter_mut().zip(phi.iter_mut()).zip(x) {
            if last.as_ref().is_none_or(|l| l.0 != xk) {
                let fk = factors(p, xk, h)?;
                lo = lo.min(fk.gamma);
                hi = hi.max(fk.gamma);
                last = Some((xk, fk));
            }
            if let Some((_, fk)) = &last {
                grown_sum += fk.gain;
                removed_sum += fk.lost;
                kept_sum += fk.kept;
                *g = fk.gamma;
                *f = fk.size;
            }
        }
        if hi - lo > MAX_SPREAD {
            return Err(Error::OutOfRange {
                name: "spread of the processes' log-factors over one mass-flow step (dt times the difference of the removal and relative growth rates between sizes)",
                value: hi - lo,
                range: "at most 1: take a smaller dt",
            });
        }
        jumps = hi > lo;
    }
    if local && kept_sum < (1.0 - MAX_REMOVED_SHARE) * (x.len() as f64 + grown_sum) {
        return Err(Error::OutOfRange {
            name: "share of the mass one mass-flow step removes",
            value: removed_sum / (x.len() as f64 + grown_sum),
            range: "below 1 - 1e-6: take a smaller dt",
        });
    }
    let (grown, removed) = (w * grown_sum, w * removed_sum);
    let (source, injected) = match &p.source {
        Some(s) => {
            let n = s.injected_between(t, t + h)?;
            let m = crate::error::finite("injected mass", n * s.sizes().mean())?;
            (if m > 0.0 { Some(s) } else { None }, m)
        }
        None => (None, 0.0),
    };
    let after = w * kept_sum + injected;
    if !(after.is_finite() && after > 0.0) {
        return Err(Error::OutOfRange {
            name: "mass after a step of the processes",
            value: after,
            range: "finite and > 0 (a removal that empties the population in one step: take a smaller dt)",
        });
    }
    Ok(Plan {
        source,
        source_share: injected / after,
        jumps,
        grows,
        mass: after,
        injected,
        removed,
        grown,
    })
}
