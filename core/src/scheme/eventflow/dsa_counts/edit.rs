//! Single-particle edits of direct simulation over size counts, for processes beside
//! coagulation (`docs/design/processes.md`): a size drawn by count (or by count times
//! size) in one pass over the counts, O(M); the edit one count and one leaf of the
//! majorant tree, O(log M) — where replacing the state rebuilt every table.

use super::DsaCounts;
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below;
use rand_core::Rng;

impl<K: CoagulationKernel> DsaCounts<K> {
    /// Whether single-particle edits are supported (always).
    pub fn edits(&self) -> bool {
        true
    }

    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size, and
    /// the size again as the handle for [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        let weight = |k: usize, c: u64| {
            if by_mass {
                c.checked_mul(k as u64 + 1)
            } else {
                Some(c)
            }
        };
        let mut total = 0u64;
        for (k, &c) in self.counts.iter().enumerate() {
            total = total.checked_add(weight(k, c)?)?;
        }
        if total == 0 {
            return None;
        }
        let mut u = below(rng, total);
        for (k, &c) in self.counts.iter().enumerate() {
            let w = weight(k, c)?;
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
            return Err(Error::OutOfRange {
                name: "particle handle",
                value: handle as f64,
                range: "an occupied size, from the last draw",
            });
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
        if x == 0 {
            return Err(Error::OutOfRange {
                name: "size",
                value: 0.0,
                range: "1 or more",
            });
        }
        self.pop.check_size(x)?;
        if x as usize > self.counts.len() {
            self.grow(x)?;
        }
        let k = x as usize - 1;
        self.set_count(k, self.counts[k] + 1)?;
        self.pop.n += 1;
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
