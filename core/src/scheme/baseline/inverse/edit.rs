//! Single-particle edits of the inverse method, for processes beside coagulation
//! (`docs/design/processes.md`): a size drawn by count (or by count times size) in one
//! pass over the occupied sizes, then the row sums `r_a = Σ_b K(x_a, x_b) N_b` moved by
//! the one particle's column `K(·, x)`, as an event moves them — O(occupied), the cost
//! of one event, where replacing the state rebuilt every row (O(occupied²)).

use super::{Inverse, NONE};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below_wide;
use crate::scheme::population::bad_handle;
use rand_core::Rng;

impl<K: CoagulationKernel> Inverse<K> {
    /// Whether single-particle edits are supported (always).
    pub fn edits(&self) -> bool {
        true
    }

    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size and
    /// its occupied slot, the handle for [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        // (u128: a mass of up to 2^64 sizes of up to 2^64 each)
        let weight = |a: usize| {
            u128::from(self.count[a]) * if by_mass { u128::from(self.size[a]) } else { 1 }
        };
        let total: u128 = (0..self.size.len()).map(weight).sum();
        let mut k = below_wide(rng, total)?;
        for a in 0..self.size.len() {
            let w = weight(a);
            if k < w {
                return Some((self.size[a], a as u64));
            }
            k -= w;
        }
        None
    }

    /// Removes a particle of size `x` from the slot a draw returned as `handle`
    /// (nothing changed since). A handle that does not name an occupied slot of size
    /// `x`, or an invalid kernel value, is an error with nothing changed. The next
    /// event is drawn afresh.
    pub fn remove_drawn(&mut self, x: u64, handle: u64) -> Result<()> {
        let a = usize::try_from(handle)
            .ok()
            .filter(|&a| self.size.get(a) == Some(&x) && self.count[a] > 0);
        let Some(a) = a else {
            return Err(bad_handle(
                handle,
                "an occupied slot of the given size, from the last draw",
            ));
        };
        self.column(x)?;
        for b in 0..self.size.len() {
            self.row[b] -= self.scratch_j[b];
        }
        self.count[a] -= 1;
        if self.count[a] == 0 {
            self.remove_slot(a);
        }
        self.pop.n -= 1;
        self.pending = None;
        Ok(())
    }

    /// Adds a particle of size `x` (at least 1, within the size limit and the memory
    /// budget). Errors, an invalid kernel value among them, leave the scheme
    /// unchanged. The next event is drawn afresh.
    pub fn add_particle(&mut self, x: u64) -> Result<()> {
        // N and the mass Σ i N_i stay within u64, as every state set from counts
        let n = self.pop.check_added(x)?;
        let mass = (0..self.size.len()).try_fold(x, |m, a| {
            self.count[a]
                .checked_mul(self.size[a])
                .and_then(|v| m.checked_add(v))
        });
        mass.ok_or(Error::Overflow {
            name: "total mass (sum of i N_i)",
        })?;
        self.reserve_size(x)?;
        self.column(x)?;
        let kxx = self.rate(x, x)?;
        let occ = self.size.len();
        for b in 0..occ {
            self.row[b] += self.scratch_j[b];
        }
        let slot = self.slot[x as usize - 1];
        if slot == NONE {
            // a new occupied size: its row from scratch (it includes itself)
            let mut r = kxx;
            for b in 0..occ {
                r += self.scratch_j[b] * self.count[b] as f64;
            }
            self.slot[x as usize - 1] = occ as u32;
            self.size.push(x);
            self.count.push(1);
            self.row.push(r);
            self.diag.push(kxx);
        } else {
            self.count[slot as usize] += 1;
        }
        self.pop.n = n;
        // (the reference of doubling, which a checkpoint holds N to)
        self.pop.n0 = self.pop.n0.max(self.pop.n);
        self.pending = None;
        Ok(())
    }

    /// `scratch_j = K(·, x)` over the occupied slots; an invalid kernel value is an
    /// error (the rows untouched).
    fn column(&mut self, x: u64) -> Result<()> {
        let mut kx = core::mem::take(&mut self.scratch_j);
        kx.clear();
        let mut fill = || -> Result<()> {
            for a in 0..self.size.len() {
                let y = self.size[a];
                kx.push(self.rate(y, x)?);
            }
            Ok(())
        };
        let r = fill();
        self.scratch_j = kx;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;

    /// An addition that would take N or the mass past u64 is refused, the state as it
    /// was.
    #[test]
    fn additions_keep_n_and_the_mass_within_u64() {
        let k = Coagulation::constant(1.0).unwrap();
        let mut s = Inverse::new(k, &[u64::MAX - 2], 1.0).unwrap();
        let e = s.add_particle(8).unwrap_err();
        assert!(matches!(e, Error::Overflow { .. }), "{e}");
        assert_eq!((s.pop.n, s.size.len()), (u64::MAX - 2, 1));
        s.add_particle(1).unwrap();
        s.add_particle(1).unwrap();
        assert!(matches!(s.add_particle(1), Err(Error::Overflow { .. })));
        assert_eq!(s.pop.n, u64::MAX);
    }
}
