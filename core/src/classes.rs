//! Host coupling on size classes: a population projected onto a host's size grid
//! keeping number and mass, a population built back from class numbers, and the change
//! per class over a step as source terms a transport equation can use.
//!
//! A host (a CFD cell, a sectional or moment solver beside the particles) describes a
//! population by numbers per unit volume `N_i` at pivots `x_1 < … < x_M`. A particle of
//! size `v` with `x_i ≤ v ≤ x_{i+1}` is split between the two pivots around it,
//! `η = (x_{i+1} − v) / (x_{i+1} − x_i)` to `x_i` and `1 − η` to `x_{i+1}`, so that both
//! its number (`η + (1 − η) = 1`) and its mass (`η x_i + (1 − η) x_{i+1} = v`) are kept:
//! the fixed-pivot rule of Kumar & Ramkrishna (1996, Chem. Eng. Sci. 51:1311, eqs.
//! 19–21), the same split [`crate::exact::Sectional`] gives a coagulation product. A
//! particle below the first pivot or above the last cannot keep both; it is not put into
//! a class but counted in [`Outside`], so that classes plus outside give the population's
//! number and mass to rounding.
//!
//! Back from classes, class i holds `N_i V` particles of size `x_i` in a volume V; the
//! fractional part is rounded up with its own probability, from the caller's generator,
//! so the expected number per class is `N_i V` exactly ([`Classes::counts`]).
//!
//! # Example
//! ```
//! use coagula_core::classes::Classes;
//! // pivots 1, 2, 4, 8; one particle of size 3 and one of size 8 per unit volume
//! let c = Classes::new(&[1.0, 2.0, 4.0, 8.0]).unwrap();
//! let mut n = [0.0; 4];
//! let out = c.project(|f| { f(3.0, 1.0); f(8.0, 1.0); }, &mut n).unwrap();
//! assert_eq!(n, [0.0, 0.5, 0.5, 1.0]);
//! // number 2 and mass 11 are kept
//! assert_eq!(n.iter().sum::<f64>(), 2.0);
//! assert_eq!(n.iter().zip(c.pivots()).map(|(a, x)| a * x).sum::<f64>(), 11.0);
//! assert_eq!(out.below_number + out.above_number, 0.0);
//! ```

use crate::error::{Error, Result};
use crate::memory::try_reserve;
use alloc::vec::Vec;
use rand_core::Rng;

/// Largest number of classes a grid may have.
pub const MAX_CLASSES: usize = 1 << 20;

/// Where a size falls on a grid of pivots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Place {
    /// Below the first pivot.
    Below,
    /// Above the last pivot.
    Above,
    /// `eta` to pivot `to`, `1 − eta` to pivot `to + 1` (`eta` = 1 on the last pivot).
    Between {
        /// The pivot at or below the size.
        to: usize,
        /// The fraction that goes to it.
        eta: f64,
    },
}

/// Where size `v` falls on the ascending pivots `x` (not empty).
pub(crate) fn place(x: &[f64], v: f64) -> Place {
    let m = x.len();
    // (NaN falls through both tests and is placed above: callers refuse it first)
    if v < x[0] {
        return Place::Below;
    }
    if v.is_nan() || v > x[m - 1] {
        return Place::Above;
    }
    // the last pivot not above v
    let i = x.partition_point(|&p| p <= v) - 1;
    if i + 1 == m {
        return Place::Between { to: i, eta: 1.0 };
    }
    Place::Between {
        to: i,
        eta: (x[i + 1] - v) / (x[i + 1] - x[i]),
    }
}

/// Checks pivots: 1 to [`MAX_CLASSES`] of them, finite, > 0, strictly ascending.
pub(crate) fn check_pivots(x: &[f64]) -> Result<()> {
    if x.is_empty() || x.len() > MAX_CLASSES {
        return Err(Error::BufferLength {
            name: "pivots (1 to 2^20 of them)",
            expected: if x.is_empty() { 1 } else { MAX_CLASSES },
            got: x.len(),
        });
    }
    crate::error::positive("first pivot", x[0])?;
    crate::error::finite("last pivot", x[x.len() - 1])?;
    for w in x.windows(2) {
        if w[1] <= w[0] || w[1].is_nan() {
            return Err(Error::OutOfRange {
                name: "pivot (strictly ascending)",
                value: w[1],
                range: "(previous pivot, inf)",
            });
        }
    }
    Ok(())
}

/// What a projection could not put into a class: the number and mass per unit volume
/// of the particles below the first pivot and above the last.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outside {
    /// Number below the first pivot.
    pub below_number: f64,
    /// Mass below the first pivot.
    pub below_mass: f64,
    /// Number above the last pivot.
    pub above_number: f64,
    /// Mass above the last pivot.
    pub above_mass: f64,
}

/// A host's size grid (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Classes {
    pivots: Vec<f64>,
}

impl Classes {
    /// A grid on `pivots`: 1 to [`MAX_CLASSES`] of them, finite, > 0 and strictly
    /// ascending.
    pub fn new(pivots: &[f64]) -> Result<Self> {
        check_pivots(pivots)?;
        let mut v = Vec::new();
        try_reserve(&mut v, pivots.len())?;
        v.extend_from_slice(pivots);
        Ok(Classes { pivots: v })
    }

    /// The pivots.
    pub fn pivots(&self) -> &[f64] {
        &self.pivots
    }

    /// The number of classes.
    pub fn len(&self) -> usize {
        self.pivots.len()
    }

    /// Never: a grid has at least one pivot.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Where size `v` falls.
    pub fn place(&self, v: f64) -> Place {
        place(&self.pivots, v)
    }

    /// Projects the weighted points `points` gives (each `(size, number per unit
    /// volume)`, as [`crate::observe::Observe::points`] calls them) onto the classes:
    /// `numbers` (one per pivot) is overwritten with the class numbers per unit volume;
    /// what falls outside the grid is returned. Errors (nothing written): `numbers` of
    /// another length; a size or weight that is negative or not finite.
    pub fn project(
        &self,
        points: impl FnOnce(&mut dyn FnMut(f64, f64)),
        numbers: &mut [f64],
    ) -> Result<Outside> {
        if numbers.len() != self.pivots.len() {
            return Err(Error::BufferLength {
                name: "class numbers",
                expected: self.pivots.len(),
                got: numbers.len(),
            });
        }
        let mut acc = Vec::new();
        try_reserve(&mut acc, numbers.len())?;
        acc.resize(numbers.len(), 0.0);
        let mut out = Outside::default();
        let mut bad: Option<Error> = None;
        let x = &self.pivots;
        points(&mut |v: f64, w: f64| {
            if bad.is_some() {
                return;
            }
            if !(v > 0.0 && v.is_finite() && w >= 0.0 && w.is_finite()) {
                bad = Some(Error::OutOfRange {
                    name: "particle size or weight (finite, size > 0, weight ≥ 0)",
                    value: if v > 0.0 && v.is_finite() { w } else { v },
                    range: "(0, inf)",
                });
                return;
            }
            match place(x, v) {
                Place::Below => {
                    out.below_number += w;
                    out.below_mass += w * v;
                }
                Place::Above => {
                    out.above_number += w;
                    out.above_mass += w * v;
                }
                Place::Between { to, eta } => {
                    acc[to] += eta * w;
                    if eta < 1.0 {
                        acc[to + 1] += (1.0 - eta) * w;
                    }
                }
            }
        });
        if let Some(e) = bad {
            return Err(e);
        }
        numbers.copy_from_slice(&acc);
        Ok(out)
    }

    /// Checks class numbers per unit volume: one per pivot, each finite and ≥ 0.
    pub fn check_numbers(&self, numbers: &[f64]) -> Result<()> {
        if numbers.len() != self.pivots.len() {
            return Err(Error::BufferLength {
                name: "class numbers",
                expected: self.pivots.len(),
                got: numbers.len(),
            });
        }
        for &n in numbers {
            if !(n >= 0.0 && n.is_finite()) {
                return Err(Error::OutOfRange {
                    name: "class number per unit volume",
                    value: n,
                    range: "[0, inf)",
                });
            }
        }
        Ok(())
    }

    /// Particle counts per class in a volume `volume` for the class numbers per unit
    /// volume `numbers`: `N_i V` rounded down, and up with probability its fractional
    /// part (one draw from `rng` per class with one), so each count's expectation is
    /// `N_i V`. Errors (no draw made): `numbers` of another length; a number negative
    /// or not finite; a volume not finite and > 0; a count past 2^53.
    pub fn counts<G: Rng + ?Sized>(
        &self,
        numbers: &[f64],
        volume: f64,
        rng: &mut G,
    ) -> Result<Vec<u64>> {
        self.check_numbers(numbers)?;
        crate::error::positive("volume", volume)?;
        const LIMIT: f64 = 9_007_199_254_740_992.0; // 2^53
        for &n in numbers {
            if n * volume >= LIMIT {
                return Err(Error::OutOfRange {
                    name: "class number per unit volume (times the volume: a count below 2^53)",
                    value: n,
                    range: "[0, 2^53 / volume)",
                });
            }
        }
        let mut c = Vec::new();
        try_reserve(&mut c, numbers.len())?;
        for &n in numbers {
            let e = n * volume;
            let whole = libm::floor(e);
            let frac = e - whole;
            let up = frac > 0.0 && crate::random::unit_f64(rng.next_u64()) < frac;
            c.push(whole as u64 + u64::from(up));
        }
        Ok(c)
    }
}

/// The change per class over a step as rates: `out_i = (after_i − before_i) / dt`, the
/// source term a host's transport equation for class i adds. Errors: slices of unequal
/// lengths; `dt` not finite and > 0.
pub fn rates(before: &[f64], after: &[f64], dt: f64, out: &mut [f64]) -> Result<()> {
    if after.len() != before.len() || out.len() != before.len() {
        return Err(Error::BufferLength {
            name: "class numbers after the step and the rates (as many as before it)",
            expected: before.len(),
            got: if after.len() != before.len() {
                after.len()
            } else {
                out.len()
            },
        });
    }
    crate::error::positive("dt", dt)?;
    for ((o, a), b) in out.iter_mut().zip(after).zip(before) {
        *o = (a - b) / dt;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
