//! Single-particle edits of the bucketed layouts, for processes beside coagulation
//! (`docs/design/processes.md`): a particle drawn uniformly or in proportion to its size
//! (a bucket by its particle number, or by particle number times its largest size, then
//! a particle of the bucket, accepted with its size over that largest size), removed or
//! added in O(1) after an O(buckets) draw. The per-size tree layouts draw a size in one
//! pass over their counts and edit in O(log M) (`tree.rs`).

use super::bound::MAX_PARTICLES as MAX_REFERENCE;
use super::bound::bucket_range;
use super::{Clock, Coagulate, LowRankMc, ProposalEngine};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::{open_unit, unit_f64};
use rand_core::Rng;

/// A bucket drawn in proportion to `n_b` (or `n_b · hi_b` when `by_mass`) from
/// `(b, n_b)` for b = 1.., with `hi_b` the bucket's largest size (at most `m`); `n` is
/// `Σ n_b` (a uniform draw then needs one pass, stopping at its bucket).
pub(super) fn pick_bucket<G: Rng + ?Sized>(
    counts: impl Iterator<Item = (usize, u64)> + Clone,
    n: u64,
    by_mass: bool,
    m: u64,
    rng: &mut G,
) -> Option<usize> {
    pick(counts, n, by_mass, |b| bucket_range(b).1.min(m), rng)
}

/// An entry drawn in proportion to `n_b` (or `n_b · hi(b)` when `by_mass`) from
/// `(b, n_b)`; `n` is `Σ n_b`. A bucket's `hi` is its largest size (the draw is then
/// thinned by [`keep_by_mass`]); a single size's is the size itself.
pub(super) fn pick<G: Rng + ?Sized>(
    counts: impl Iterator<Item = (usize, u64)> + Clone,
    n: u64,
    by_mass: bool,
    hi: impl Fn(usize) -> u64,
    rng: &mut G,
) -> Option<usize> {
    if !by_mass {
        if n == 0 {
            return None;
        }
        let mut k = crate::random::below(rng, n);
        let mut last = None;
        for (b, c) in counts {
            if c > 0 {
                last = Some(b);
                if k < c {
                    return Some(b);
                }
                k -= c;
            }
        }
        return last;
    }
    let weight = |(b, n): (usize, u64)| n as f64 * hi(b) as f64;
    let total: f64 = counts.clone().map(weight).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut u = unit_f64(rng.next_u64()) * total;
    let mut last = None;
    for c in counts {
        let w = weight(c);
        if w > 0.0 {
            last = Some(c.0);
            if u < w {
                return Some(c.0);
            }
            u -= w;
        }
    }
    last
}

/// Whether a particle of size `x` in bucket `b` is kept by a draw by mass (accepted
/// with `x / hi_b`).
pub(super) fn keep_by_mass<G: Rng + ?Sized>(b: usize, x: u64, m: u64, rng: &mut G) -> bool {
    let hi = bucket_range(b).1.min(m);
    x >= hi || open_unit(rng) * (hi as f64) < x as f64
}

/// The edits of the coagulation scheme over an engine that has them.
impl<K: CoagulationKernel, const R: usize, E: ProposalEngine<R>> LowRankMc<K, R, E, Coagulate> {
    /// Whether single-particle edits are supported.
    pub fn edits(&self) -> bool {
        E::EDITS
    }

    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size and
    /// a handle for [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        let (x, (b, s)) = self.engine.draw_particle(by_mass, self.pop.n, rng)?;
        Some((x, ((b as u64) << 44) | s))
    }

    /// Removes the particle of size `x` a draw returned `handle` for (nothing changed
    /// since); the next proposal is drawn afresh.
    pub fn remove_drawn(&mut self, x: u64, handle: u64) -> Result<()> {
        if !E::EDITS || self.pop.n == 0 {
            return Err(unsupported());
        }
        let at = ((handle >> 44) as usize, handle & ((1 << 44) - 1));
        self.engine.remove_particle(at, x);
        self.pop.n -= 1;
        self.settle_edit();
        Ok(())
    }

    /// Adds a particle of size `x` (within the size limit and the memory budget; on
    /// error nothing changed); the next proposal is drawn afresh.
    pub fn add_particle(&mut self, x: u64) -> Result<()> {
        if !E::EDITS {
            return Err(unsupported());
        }
        self.pop.check_added(x)?;
        if self.pop.n >= MAX_REFERENCE {
            return Err(Error::Capacity {
                name: "particles",
                capacity: MAX_REFERENCE as usize,
            });
        }
        self.engine.add_particle(&self.kernel, x, &self.pop)?;
        self.pop.n += 1;
        if self.pop.n > self.pop.n0 {
            // the reference the quantisation and the checkpoint check hold n to
            self.pop.n0 = self.pop.n.saturating_mul(2).min(MAX_REFERENCE);
            self.engine.rereference(&self.pop);
        }
        self.settle_edit();
        Ok(())
    }

    /// After an edit, as after an event: the engine's housekeeping, and a new clock only
    /// when the proposal rate changed (a slot layout keeps its weights when a particle
    /// leaves or takes a free slot: the pending proposal stays a draw of the same
    /// process).
    fn settle_edit(&mut self) {
        self.engine.settle(&self.pop);
        if self.engine.needs_refresh() || self.pop.n < 2 {
            self.clock = Clock::Stale;
        }
    }
}

fn unsupported() -> Error {
    Error::Unsupported {
        what: "single-particle edits on this layout",
    }
}
