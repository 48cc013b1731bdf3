//! Single-particle edits of direct simulation over size counts, for processes beside
//! coagulation (`docs/design/processes.md`): a size drawn by count (or by count times
//! size) in one pass over the counts, O(M); the edit one count and one leaf of the
//! majorant tree, O(log M) — where replacing the state rebuilt every table.

use super::DsaCounts;
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below_wide;
use crate::scheme::population::bad_handle;
use rand_core::Rng;

impl<K: CoagulationKernel> DsaCounts<K> {
    /// Whether single-particle edits are supported (always).
    pub fn edits(&self) -> bool {
        true
    }

    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size, and
    /// the size again as the handle for [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        // (u128: a mass of up to 2^64 sizes of up to 2^64 each)
        let weight = |k: usize, c: u64| u128::from(c) * if by_mass { k as u128 + 1 } else { 1 };
        let total: u128 = self
            .counts
            .iter()
            .enumerate()
            .map(|(k, &c)| weight(k, c))
            .sum();
        let mut u = below_wide(rng, total)?;
        for (k, &c) in self.counts.iter().enumerate() {
            let w = weight(k, c);
            if u < w {
                return Some((k as u64 + 1, k as u64 + 1));
            }
            u -= w;
        }
        None
    }

    /// Removes a particle of size `x` (`handle`, from the draw, is `x` too; a size
    /// without particles is an error, nothing changed). The next event is drawn afresh.
    pub fn remove_drawn(&mut self, x: u64, handle: u64) -> Result<()> {
        let k = usize::try_from(x.wrapping_sub(1))
            .ok()
            .filter(|&k| handle == x && self.counts.get(k).is_some_and(|&c| c > 0));
        let Some(k) = k else {
            return Err(bad_handle(handle, "an occupied size, from the last draw"));
        };
        self.set_count(k, self.counts[k] - 1)?;
        self.pop.n -= 1;
        self.pending = None;
        Ok(())
    }

    /// Adds a particle of size `x` (at least 1, within the size limit and the memory
    /// budget, with a valid majorant there). Errors leave the particles unchanged (the
    /// size table may have grown). The next event is drawn afresh.
    pub fn add_particle(&mut self, x: u64) -> Result<()> {
        // N and the mass Σ k N_k stay within u64, as every state set from counts (the
        // table's length bounds the sizes; the exact sum only when that bound fails)
        let n = self.pop.check_added(x)?;
        let quick = n.checked_mul(x.max(self.counts.len() as u64)).is_some();
        if !quick {
            let mass = self.counts.iter().enumerate().try_fold(x, |m, (k, &c)| {
                c.checked_mul(k as u64 + 1).and_then(|v| m.checked_add(v))
            });
            mass.ok_or(Error::Overflow {
                name: "total mass (sum of i N_i)",
            })?;
        }
        if x as usize > self.counts.len() {
            self.grow(x)?;
        }
        let k = x as usize - 1;
        self.set_count(k, self.counts[k] + 1)?;
        self.pop.n = n;
        self.pop.n0 = self.pop.n0.max(self.pop.n);
        self.pending = None;
        Ok(())
    }

    /// Sets `N_{k+1} = c` and its leaf `h N` (an invalid majorant is an error, nothing
    /// changed).
    fn set_count(&mut self, k: usize, c: u64) -> Result<()> {
        let w = if c == 0 { 0.0 } else { self.h[k] * c as f64 };
        if !(w >= 0.0 && w.is_finite()) {
            return Err(Error::InvalidRate {
                name: "product majorant h(x) of an added size",
                value: self.h[k],
            });
        }
        self.tree.update_many([(k, w)])?;
        self.counts[k] = c;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;
    use rand_pcg::Pcg64Mcg;

    /// An addition that would take N or the mass past u64 is refused, the state as it
    /// was; a draw by mass over a mass past u64 still draws (128-bit weights).
    #[test]
    fn additions_keep_n_and_the_mass_within_u64() {
        let k = Coagulation::constant(1.0).unwrap();
        let mut s = DsaCounts::new(k, &[u64::MAX - 2], 1.0).unwrap();
        let e = s.add_particle(8).unwrap_err();
        assert!(matches!(e, Error::Overflow { .. }), "{e}");
        assert_eq!(
            (s.pop.n, s.counts[0], s.counts[7]),
            (u64::MAX - 2, u64::MAX - 2, 0)
        );
        s.add_particle(1).unwrap();
        s.add_particle(1).unwrap();
        assert!(matches!(s.add_particle(1), Err(Error::Overflow { .. })));
        assert_eq!(s.pop.n, u64::MAX);
        let mut rng = Pcg64Mcg::new(7);
        let mut t = DsaCounts::new(k, &[0, 0, 0, 1 << 62, 1 << 62], 1.0);
        // (N 2^63, mass 9 · 2^62: refused when set from counts, as before)
        assert!(t.is_err());
        t = DsaCounts::new(k, &[0, 0, 1 << 62], 1.0);
        let t = t.unwrap();
        assert_eq!(t.draw_particle(true, &mut rng), Some((3, 3)));
        assert_eq!(t.draw_particle(false, &mut rng), Some((3, 3)));
    }
}
