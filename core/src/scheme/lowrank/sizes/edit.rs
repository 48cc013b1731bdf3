//! Single-particle edits of [`LowRankSizes`], for the processes beside coagulation
//! (`crate::scheme::facade` drives them): a uniform draw, a removal and an insertion,
//! each O(log buckets), instead of rebuilding the layout per process event.

use super::{Layout, LowRankSizes, bytes_for, key, row_factors};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below;
use crate::scheme::population::{try_reserve, within_budget};
use alloc::vec::Vec;
use rand_core::Rng;

impl<K: CoagulationKernel, const R: usize, const W: usize> LowRankSizes<K, R, W> {
    /// A particle drawn uniformly: its size and index, for
    /// [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, rng: &mut G) -> Option<(f64, u64)> {
        let n = self.p.sizes.len();
        if n == 0 {
            return None;
        }
        let i = below(rng, n as u64) as usize;
        Some((self.p.sizes[i], i as u64))
    }

    /// Removes the particle of size `x` a draw returned `index` for (nothing changed
    /// since: else an error, nothing removed). The next proposal is drawn afresh.
    pub fn remove_drawn(&mut self, x: f64, index: u64) -> Result<()> {
        let i = usize::try_from(index)
            .ok()
            .filter(|&i| i < self.p.sizes.len() && self.p.sizes[i] == x)
            .ok_or(Error::IndexOutOfRange {
                name: "drawn particle (of that size)",
                index,
                limit: self.p.sizes.len() as u64,
            })?;
        self.leave(i);
        self.take_last_into(i);
        self.pending = None;
        Ok(())
    }

    /// Adds a particle of size `x` (finite, > 0; within the memory budget; on error
    /// nothing changed). A size below the smallest bucket rebuilds the layout (O(N));
    /// otherwise O(log buckets). The next proposal is drawn afresh.
    pub fn add_particle(&mut self, x: f64) -> Result<()> {
        crate::error::positive("size", x)?;
        let f = row_factors::<K, R, W>(&self.kernel, x)?;
        let n = self.p.sizes.len();
        within_budget(
            bytes_for::<R, W>(n + 1, self.p.buckets.len() + 1),
            self.memory_budget,
        )?;
        if key(x) < self.p.base {
            let mut v = Vec::new();
            try_reserve(&mut v, n + 1)?;
            v.extend_from_slice(&self.p.sizes);
            v.push(x);
            let l = Layout::build(&self.kernel, &v, self.memory_budget)?;
            let n0 = self.n0;
            self.install(l);
            self.n0 = n0;
            return Ok(());
        }
        let b = self.bucket_for(key(x))?;
        try_reserve(&mut self.p.buckets[b].list, 1)?;
        try_reserve(&mut self.p.sizes, 1)?;
        try_reserve(&mut self.p.at, 1)?;
        self.p.sizes.push(x);
        self.p.at.push(0);
        self.enter(n, b, &f);
        self.pending = None;
        Ok(())
    }

    /// After particle j left its bucket: the last particle takes index j, and the
    /// arrays shrink by one.
    pub(super) fn take_last_into(&mut self, j: usize) {
        let last = self.p.sizes.len() - 1;
        if j != last {
            let (y, pos) = (self.p.sizes[last], self.p.at[last]);
            self.p.sizes[j] = y;
            self.p.at[j] = pos;
            let b = self.bucket_of(y);
            self.p.buckets[b].list[pos as usize] = j as u32;
        }
        self.p.sizes.pop();
        self.p.at.pop();
    }
}
