//! A deterministic reference for combinations without a closed form: the fixed-pivot
//! sectional method of Kumar & Ramkrishna (1996, Chem. Eng. Sci. 51:1311, eqs. 19–21)
//! for coagulation, with a particle source at one size, size-dependent removal
//! `λ(x)` and growth `dx/dt = G(x)`, integrated by classical fourth-order Runge–Kutta.
//!
//! The population is numbers per unit volume `N_i` at pivots `x_1 < … < x_M`. A
//! coagulation of pivots j and k makes a particle of size `v = x_j + x_k`, assigned to
//! the two pivots around it so that number and mass are kept (`η = (x_{i+1} − v) /
//! (x_{i+1} − x_i)` to `x_i`, the rest to `x_{i+1}`); a particle past the last pivot is
//! counted as lost. A source of rate S at size `x_s` is split the same way. Growth is
//! a first-order upwind flux `G(x_i) N_i / (x_{i+1} − x_i)` from pivot i to i + 1, which
//! keeps the number and moves mass at exactly `Σ G(x_i) N_i`: linear growth `G = g x`
//! then gives `M1' = g M1` without grid error. So M0 and M1 follow their exact moment
//! equations for a constant kernel; higher moments and the distribution converge as
//! the grid is refined (`docs/design/processes.md` shows the convergence).
//!
//! # Example
//! ```
//! use coagula_core::exact::{Exact, Sectional};
//! use coagula_core::kernel::Coagulation;
//! // K = 1 from unit monomers: integer pivots to 32, then a ratio of 1.05
//! let grid = Sectional::<Coagulation>::grid(32, 1e5, 1.05).unwrap();
//! let mut s = Sectional::new(Coagulation::constant(1.0).unwrap(), grid).unwrap();
//! s.set_number(0, 1.0).unwrap();
//! s.advance_to(2.0, 1e-3).unwrap();
//! let e = Exact::constant(1.0).unwrap();
//! assert!((s.moment(0.0) - e.moment(0, 2.0).unwrap()).abs() < 1e-10);
//! assert!((s.moment(2.0) / e.moment(2, 2.0).unwrap() - 1.0).abs() < 0.01);
//! ```

use crate::error::{Error, Result, finite};
use crate::kernel::CoagulationKernel;
use crate::memory::try_reserve;
use alloc::vec::Vec;

/// Where the product of a pair of pivots goes: pivot `to` gets `eta` of it, pivot
/// `to + 1` the rest; `to == usize::MAX`: past the grid (lost).
#[derive(Clone, Copy, Debug)]
struct Split {
    to: usize,
    eta: f64,
}

/// Largest number of pivots (the pair table is M²/2 entries).
pub const MAX_PIVOTS: usize = 4096;

/// The sectional reference solution (see the module docs).
#[derive(Clone, Debug)]
pub struct Sectional<K> {
    kernel: K,
    x: Vec<f64>,
    n: Vec<f64>,
    /// `K(x_j, x_k)`, `j ≥ k`, row-major lower triangle.
    rate: Vec<f64>,
    /// The split of `x_j + x_k`, same layout.
    split: Vec<Split>,
    removal: Vec<f64>,
    growth: Vec<f64>,
    /// Source: its rate per unit volume and the split of its size.
    source: Option<(f64, Split)>,
    t: f64,
    /// Number and mass per unit volume that left the grid (coagulation or growth past
    /// the last pivot), injected, removed.
    books: Books,
}

/// What a sectional solution's processes did, per unit volume, since the start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Books {
    /// Number injected by the source.
    pub injected_number: f64,
    /// Mass injected by the source.
    pub injected_mass: f64,
    /// Number removed by `λ(x)`.
    pub removed_number: f64,
    /// Mass removed by `λ(x)`.
    pub removed_mass: f64,
    /// Mass added by growth.
    pub grown_mass: f64,
    /// Number past the last pivot (lost to the grid).
    pub lost_number: f64,
    /// Mass past the last pivot.
    pub lost_mass: f64,
}

/// The split of size `v` over the pivots `x` ([`crate::classes::place`]; below the
/// first pivot: all to it).
fn split_of(x: &[f64], v: f64) -> Split {
    use crate::classes::Place;
    match crate::classes::place(x, v) {
        Place::Below => Split { to: 0, eta: 1.0 },
        Place::Above => Split {
            to: usize::MAX,
            eta: 0.0,
        },
        Place::Between { to, eta } => Split { to, eta },
    }
}

impl<K: CoagulationKernel> Sectional<K> {
    /// Pivots 1, 2, …, `dense` (integer sizes) then a geometric grid of ratio `ratio`
    /// up to `largest`. Errors: `dense` < 1, `ratio` not in (1, 2], `largest` below
    /// `dense`, more than [`MAX_PIVOTS`] pivots.
    pub fn grid(dense: u64, largest: f64, ratio: f64) -> Result<Vec<f64>> {
        if dense < 1 {
            return Err(Error::OutOfRange {
                name: "dense pivots",
                value: dense as f64,
                range: "[1, inf)",
            });
        }
        if !(ratio > 1.0 && ratio <= 2.0) {
            return Err(Error::OutOfRange {
                name: "grid ratio",
                value: ratio,
                range: "(1, 2]",
            });
        }
        if finite("largest pivot", largest)? < dense as f64 {
            return Err(Error::OutOfRange {
                name: "largest pivot",
                value: largest,
                range: "[dense, inf)",
            });
        }
        let mut x = Vec::new();
        let mut v = 1.0;
        while v <= dense as f64 {
            if x.len() >= MAX_PIVOTS {
                return Err(too_many());
            }
            x.push(v);
            v += 1.0;
        }
        let mut v = dense as f64 * ratio;
        while v <= largest * (1.0 + 1e-12) {
            if x.len() >= MAX_PIVOTS {
                return Err(too_many());
            }
            // a pivot at least one unit past the last
            let last = x[x.len() - 1];
            x.push(v.max(last + 1.0));
            v = x[x.len() - 1] * ratio;
        }
        Ok(x)
    }

    /// A solution on pivots `x` (ascending, finite, > 0; at most [`MAX_PIVOTS`]) with
    /// no particles, under `kernel`.
    pub fn new(kernel: K, x: Vec<f64>) -> Result<Self> {
        if x.len() > MAX_PIVOTS {
            return Err(too_many());
        }
        crate::classes::check_pivots(&x)?;
        let m = x.len();
        let pairs = m * (m + 1) / 2;
        let (mut rate, mut split) = (Vec::new(), Vec::new());
        try_reserve(&mut rate, pairs)?;
        try_reserve(&mut split, pairs)?;
        for j in 0..m {
            for k in 0..=j {
                let r = kernel.rate(x[j], x[k]);
                if !(r >= 0.0 && r.is_finite()) {
                    return Err(Error::InvalidRate {
                        name: "coagulation kernel",
                        value: r,
                    });
                }
                rate.push(r);
                split.push(split_of(&x, x[j] + x[k]));
            }
        }
        let mut n = Vec::new();
        try_reserve(&mut n, m)?;
        n.resize(m, 0.0);
        Ok(Sectional {
            kernel,
            removal: alloc::vec![0.0; m],
            growth: alloc::vec![0.0; m],
            x,
            n,
            rate,
            split,
            source: None,
            t: 0.0,
            books: Books::default(),
        })
    }

    /// The discrete Smoluchowski equations on the integer sizes `1..=largest` (at most
    /// [`MAX_PIVOTS`]): `dN_k/dt = ½ Σ_{i+j=k} K(i, j) N_i N_j − N_k Σ_j K(k, j) N_j`
    /// (Smoluchowski 1916; SPEC's discrete form), a sectional solution whose pivots are
    /// every integer, so that each pair's product lands on a pivot and the fixed-pivot
    /// split is exact; what passes `largest` is booked as lost
    /// ([`Books::lost_mass`]): a solution is the infinite system's as long as that
    /// stays negligible. The error is then RK4's alone (fourth order in the step).
    ///
    /// # Example
    /// ```
    /// use coagula_core::exact::{Exact, Sectional};
    /// use coagula_core::kernel::Coagulation;
    /// let mut s = Sectional::discrete(Coagulation::constant(1.0).unwrap(), 256).unwrap();
    /// s.set_number(0, 1.0).unwrap();
    /// s.advance_to(2.0, 1e-2).unwrap();
    /// let e = Exact::constant(1.0).unwrap();
    /// // n_3(2) = (t/2)² / (1 + t/2)⁴
    /// let n3 = s.numbers()[2];
    /// assert!((n3 - e.number_density(3, 2.0).unwrap()).abs() < 1e-9);
    /// assert!(s.books().lost_mass < 1e-30);
    /// ```
    pub fn discrete(kernel: K, largest: usize) -> Result<Self> {
        if largest == 0 || largest > MAX_PIVOTS {
            return Err(too_many());
        }
        Self::new(kernel, (1..=largest).map(|i| i as f64).collect())
    }

    /// The pivots.
    pub fn pivots(&self) -> &[f64] {
        &self.x
    }

    /// The numbers per unit volume at the pivots.
    pub fn numbers(&self) -> &[f64] {
        &self.n
    }

    /// The kernel.
    pub fn kernel(&self) -> &K {
        &self.kernel
    }

    /// Sets the number per unit volume at pivot `i` (finite, ≥ 0).
    pub fn set_number(&mut self, i: usize, number: f64) -> Result<()> {
        if i >= self.n.len() {
            return Err(Error::IndexOutOfRange {
                name: "pivot",
                index: i as u64,
                limit: self.n.len() as u64,
            });
        }
        if !(number >= 0.0 && number.is_finite()) {
            return Err(Error::OutOfRange {
                name: "number at a pivot",
                value: number,
                range: "[0, inf)",
            });
        }
        self.n[i] = number;
        Ok(())
    }

    /// Adds `number` particles per unit volume of size `v`, split between the pivots
    /// around it keeping number and mass (past the last pivot: refused).
    pub fn add_at(&mut self, v: f64, number: f64) -> Result<()> {
        crate::error::positive("size", v)?;
        let s = split_of(&self.x, v);
        if s.to == usize::MAX {
            return Err(Error::OutOfRange {
                name: "size (past the last pivot)",
                value: v,
                range: "[first pivot, last pivot]",
            });
        }
        if !(number >= 0.0 && number.is_finite()) {
            return Err(Error::OutOfRange {
                name: "number",
                value: number,
                range: "[0, inf)",
            });
        }
        self.n[s.to] += s.eta * number;
        if s.eta < 1.0 {
            self.n[s.to + 1] += (1.0 - s.eta) * number;
        }
        Ok(())
    }

    /// A source of `rate` particles per unit volume and time of size `size`.
    pub fn with_source(mut self, rate: f64, size: f64) -> Result<Self> {
        crate::error::positive("size", size)?;
        if !(rate >= 0.0 && rate.is_finite()) {
            return Err(Error::OutOfRange {
                name: "source rate",
                value: rate,
                range: "[0, inf)",
            });
        }
        let s = split_of(&self.x, size);
        if s.to == usize::MAX {
            return Err(Error::OutOfRange {
                name: "source size (past the last pivot)",
                value: size,
                range: "[first pivot, last pivot]",
            });
        }
        self.source = Some((rate, s));
        Ok(self)
    }

    /// Removal at rate `lambda(x)` per particle (finite, ≥ 0 at every pivot).
    pub fn with_removal(mut self, mut lambda: impl FnMut(f64) -> f64) -> Result<Self> {
        for (i, &x) in self.x.iter().enumerate() {
            let l = lambda(x);
            if !(l >= 0.0 && l.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "removal rate",
                    value: l,
                });
            }
            self.removal[i] = l;
        }
        Ok(self)
    }

    /// Growth `dx/dt = g(x)` (finite, ≥ 0 at every pivot).
    pub fn with_growth(mut self, mut g: impl FnMut(f64) -> f64) -> Result<Self> {
        for (i, &x) in self.x.iter().enumerate() {
            let v = g(x);
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "growth rate",
                    value: v,
                });
            }
            self.growth[i] = v;
        }
        Ok(self)
    }

    /// The time.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The books since the start.
    pub fn books(&self) -> Books {
        self.books
    }

    /// `M_k = Σ x_i^k N_i`.
    pub fn moment(&self, k: f64) -> f64 {
        self.x
            .iter()
            .zip(&self.n)
            .fold(0.0, |s, (&x, &n)| s + n * libm::pow(x, k))
    }

    /// The number per unit volume at pivots in `[a, b)`.
    pub fn concentration(&self, a: f64, b: f64) -> f64 {
        self.x
            .iter()
            .zip(&self.n)
            .filter(|&(&x, _)| x >= a && x < b)
            .fold(0.0, |s, (_, &n)| s + n)
    }

    /// `dN/dt` at `n` into `out`, and the rates of the books `[injected number,
    /// injected mass, removed number, removed mass, grown mass, lost number, lost mass]`.
    fn derivative(&self, n: &[f64], out: &mut [f64]) -> [f64; 7] {
        let m = self.x.len();
        out.fill(0.0);
        let mut books = [0.0; 7];
        let mut idx = 0;
        for j in 0..m {
            let nj = n[j];
            if nj == 0.0 {
                // (an empty pivot: no pair with it; its row of the table is skipped)
                idx += j + 1;
                continue;
            }
            for k in 0..=j {
                let r = self.rate[idx] * nj * n[k];
                let s = self.split[idx];
                idx += 1;
                if r == 0.0 {
                    continue;
                }
                // each unordered pair once: j = k pairs at half the rate
                let r = if j == k { 0.5 * r } else { r };
                out[j] -= r;
                out[k] -= r;
                if s.to == usize::MAX {
                    books[5] += r;
                    books[6] += r * (self.x[j] + self.x[k]);
                } else {
                    out[s.to] += s.eta * r;
                    if s.eta < 1.0 {
                        out[s.to + 1] += (1.0 - s.eta) * r;
                    }
                }
            }
        }
        for i in 0..m {
            let l = self.removal[i] * n[i];
            out[i] -= l;
            books[2] += l;
            books[3] += l * self.x[i];
            let g = self.growth[i] * n[i];
            if g != 0.0 {
                if i + 1 < m {
                    books[4] += g;
                    let f = g / (self.x[i + 1] - self.x[i]);
                    out[i] -= f;
                    out[i + 1] += f;
                } else if m > 1 {
                    // the last pivot grows out of the grid at the rate of its width
                    // below: lost, with the mass it had
                    let f = g / (self.x[i] - self.x[i - 1]);
                    out[i] -= f;
                    books[5] += f;
                    books[6] += f * self.x[i];
                }
            }
        }
        if let Some((rate, s)) = self.source {
            out[s.to] += s.eta * rate;
            if s.eta < 1.0 {
                out[s.to + 1] += (1.0 - s.eta) * rate;
            }
            books[0] += rate;
            let size = s.eta * self.x[s.to]
                + if s.eta < 1.0 {
                    (1.0 - s.eta) * self.x[s.to + 1]
                } else {
                    0.0
                };
            books[1] += rate * size;
        }
        books
    }

    /// Integrates to `t` with fourth-order Runge–Kutta steps of at most `dt`. Errors: a
    /// time before the current one, a step that is not finite and positive, a state
    /// that turns non-finite (a step too long for the rates), more than 10^8 steps.
    pub fn advance_to(&mut self, t: f64, dt: f64) -> Result<()> {
        finite("t", t)?;
        crate::error::positive("dt", dt)?;
        if t < self.t {
            return Err(Error::TimeBackwards {
                now: self.t,
                requested: t,
            });
        }
        let steps = libm::ceil((t - self.t) / dt);
        if steps > 1e8 {
            return Err(Error::OutOfRange {
                name: "steps (t - time) / dt",
                value: steps,
                range: "[0, 1e8]",
            });
        }
        // the work up front: 4 passes over the pair table a step, at most 1e12 pair
        // updates a call (minutes; a finer grid with as many steps would run for days)
        let work = steps * 4.0 * self.rate.len() as f64;
        if work > 1e12 {
            return Err(Error::OutOfRange {
                name: "pair updates of the call (4 x steps x pairs of pivots; fewer steps or pivots)",
                value: work,
                range: "[0, 1e12]",
            });
        }
        let steps = steps as u64;
        if steps == 0 {
            return Ok(());
        }
        let h = (t - self.t) / steps as f64;
        let m = self.n.len();
        let mut k = [
            alloc::vec![0.0; m],
            alloc::vec![0.0; m],
            alloc::vec![0.0; m],
            alloc::vec![0.0; m],
        ];
        let mut y = alloc::vec![0.0; m];
        let (n0, b0) = (self.n.clone(), self.books);
        let t0 = self.t;
        for step in 0..steps {
            let b1 = self.derivative(&self.n, &mut k[0]);
            for i in 0..m {
                y[i] = self.n[i] + 0.5 * h * k[0][i];
            }
            let b2 = self.derivative(&y, &mut k[1]);
            for i in 0..m {
                y[i] = self.n[i] + 0.5 * h * k[1][i];
            }
            let b3 = self.derivative(&y, &mut k[2]);
            for i in 0..m {
                y[i] = self.n[i] + h * k[2][i];
            }
            let b4 = self.derivative(&y, &mut k[3]);
            let mut ok = true;
            for i in 0..m {
                self.n[i] += h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
                ok &= self.n[i].is_finite();
            }
            let db: [f64; 7] =
                core::array::from_fn(|q| h / 6.0 * (b1[q] + 2.0 * b2[q] + 2.0 * b3[q] + b4[q]));
            let b = &mut self.books;
            b.injected_number += db[0];
            b.injected_mass += db[1];
            b.removed_number += db[2];
            b.removed_mass += db[3];
            b.grown_mass += db[4];
            b.lost_number += db[5];
            b.lost_mass += db[6];
            self.t = if step + 1 == steps {
                t
            } else {
                t0 + (step + 1) as f64 * h
            };
            if !ok {
                self.n = n0;
                self.books = b0;
                self.t = t0;
                return Err(Error::InvalidRate {
                    name: "sectional solution (a step too long for the rates)",
                    value: f64::NAN,
                });
            }
        }
        Ok(())
    }
}

fn too_many() -> Error {
    Error::OutOfRange {
        name: "pivots",
        value: f64::NAN,
        range: "[1, 4096]",
    }
}

#[cfg(test)]
#[path = "sectional_tests.rs"]
mod tests;
