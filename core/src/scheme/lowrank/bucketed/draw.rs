//! The bucketed engine's draws: a bucket pair, a slot in each, the overflow lists
//! and the pair's bounds (see the module docs of [`bucketed`](super)).

use super::*;

impl<const R: usize, const W: usize> BucketedEngine<R, W> {
    /// A slot of the overflow of row r: bucket b with probability
    /// `q_r(b) (slots_b − tab_b) / (T_r − main_r)`, then a uniform grown slot.
    pub(super) fn pick_over<Rn: Rng + ?Sized>(&self, r: usize, rng: &mut Rn) -> (usize, u64) {
        let mut x = below(rng, self.row_total[r] - self.main[r]);
        let mut last = (0, 0);
        for &b in &self.over {
            let bk = &self.buckets[b];
            let w = bk.q[r] * (bk.slots - bk.tab);
            if w > 0 {
                last = (b, bk.tab + below(rng, bk.slots - bk.tab));
                if x < w {
                    return last;
                }
                x -= w;
            }
        }
        // not reached: the weights add up to the row's overflow
        last
    }

    /// A proposal of the overflow stream: pairs with at least one slot grown since
    /// the tables were built, `Σ_k (O_k T_{R+k} + main_k O_{R+k}) s_k s_{R+k}` with
    /// `O = T − main`. Returns the two slots and their occupants, `None` when a slot
    /// is empty.
    #[cold]
    #[inline(never)]
    #[allow(clippy::type_complexity)]
    pub(super) fn draw_overflow<Rn: Rng + ?Sized>(
        &self,
        rng: &mut Rn,
    ) -> Option<((usize, u64, u64), (usize, u64, u64))> {
        let ((bu, su), (bv, sv)) = self.overflow_slots(rng)?;
        let xu = self.occupant(bu, su)?;
        let xv = self.occupant(bv, sv)?;
        Some(((bu, su, xu), (bv, sv, xv)))
    }

    /// The two slots `((bu, su), (bv, sv))` of an overflow-stream proposal (`None`
    /// only when the overflow is empty).
    #[allow(clippy::type_complexity)]
    pub(super) fn overflow_slots<Rn: Rng + ?Sized>(
        &self,
        rng: &mut Rn,
    ) -> Option<((usize, u64), (usize, u64))> {
        let mut r = open_unit(rng) * self.over_rate;
        let mut pick = None;
        'terms: for k in 0..R {
            for (grown_u, w) in [true, false].into_iter().zip(self.over_terms(k)) {
                if w > 0.0 {
                    pick = Some((k, grown_u));
                    if r < w {
                        break 'terms;
                    }
                    r -= w;
                }
            }
        }
        let (k, grown_u) = pick?;
        let ((bu, su), (bv, sv)) = if grown_u {
            let u = self.pick_over(k, rng);
            // side v from the whole row: its main part or its overflow
            let v = if below(rng, self.row_total[R + k]) < self.main[R + k] {
                let bv = self.side_v[k].sample(rng.next_u64()) as usize;
                (bv, below(rng, self.buckets[bv].tab))
            } else {
                self.pick_over(R + k, rng)
            };
            (u, v)
        } else {
            let bu = if R > 1 {
                self.side_u[k].sample(rng.next_u64()) as usize
            } else {
                self.joint.sample(rng.next_u64()) as usize & 0xffff
            };
            let u = (bu, below(rng, self.buckets[bu].tab));
            (u, self.pick_over(R + k, rng))
        };
        Some(((bu, su), (bv, sv)))
    }

    /// Draws side u of a proposal — component k, bucket and slot — and prefetches the
    /// slot's count or list entry.
    #[inline(always)]
    pub(super) fn draw_u<Rn: Rng + ?Sized>(
        &self,
        rng: &mut Rn,
        fetch: bool,
    ) -> (usize, usize, u64) {
        let id = self.joint.sample(rng.next_u64()) as usize;
        let (k, bu) = (id >> 16, id & 0xffff);
        let su = below(rng, self.buckets[bu].tab);
        if fetch {
            self.prefetch_slot(bu, su);
        }
        (k, bu, su)
    }

    /// Prefetches the count or list entry of slot `s` of bucket `b`.
    #[inline(always)]
    pub(super) fn prefetch_slot(&self, b: usize, s: u64) {
        let bk = &self.buckets[b];
        if bk.grid {
            let x = bk.lo + (s & ((1 << bk.sh) - 1));
            if let Some(c) = self.counts.get(x as usize) {
                prefetch(c);
            }
        } else if let Some(e) = self
            .lists
            .get(b.wrapping_sub(SINGLE as usize))
            .and_then(|l| l.get(s as usize))
        {
            prefetch(e);
        }
    }

    /// Draws side v of a main-stream proposal of component k whose side u is in bucket
    /// `bu`. A full singleton bucket holds only its size, so its slot is drawn only if
    /// it is `bu` (for the same-particle test); deferring that draw keeps the two slots
    /// independent and uniform.
    #[inline(always)]
    pub(super) fn draw_v<Rn: Rng + ?Sized>(
        &self,
        k: usize,
        bu: usize,
        rng: &mut Rn,
    ) -> (usize, u64) {
        let bv = self.side_v[k].sample(rng.next_u64()) as usize;
        let bk = &self.buckets[bv];
        // (a width-1 bucket is a singleton: `sh == 0`)
        let sv = if bu != bv && bk.sh == 0 && bk.slots == bk.n {
            0
        } else {
            below(rng, bk.tab)
        };
        (bv, sv)
    }

    /// Draws a whole main-stream proposal ahead and prefetches its two slots (side v's
    /// slot is drawn whatever the bucket: it may fill or empty before the draw is used).
    #[inline(always)]
    pub(super) fn draw_ahead<Rn: Rng + ?Sized>(&self, rng: &mut Rn) -> Ahead {
        let (k, bu, su) = self.draw_u(rng, true);
        let bv = self.side_v[k].sample(rng.next_u64()) as usize;
        let sv = below(rng, self.buckets[bv].tab);
        self.prefetch_slot(bv, sv);
        Ahead { k, bu, su, bv, sv }
    }

    /// `Σ_b q_r(b) n_b`: the weight of the real particles in row r.
    pub(super) fn live(&self, r: usize) -> u64 {
        self.buckets.iter().map(|bk| bk.q[r] * bk.n).sum()
    }

    /// The size held by slot `s` of bucket `b`, if the slot is full.
    #[inline(always)]
    pub(super) fn occupant(&self, b: usize, s: u64) -> Option<u64> {
        let bk = &self.buckets[b];
        if bk.grid {
            let x = bk.lo + (s & ((1 << bk.sh) - 1));
            let level = s >> bk.sh;
            (level < u64::from(self.counts[x as usize])).then_some(x)
        } else {
            let list = &self.lists[b - SINGLE as usize];
            list.get(s as usize).map(|&off| bk.lo + u64::from(off))
        }
    }

    /// One proposal: the two slots and their occupants (see [`ProposalEngine::propose`]).
    #[inline(always)]
    pub(super) fn draw<Rn: Rng + ?Sized>(&mut self, rng: &mut Rn) -> Option<Candidate<Loc>> {
        // Main stream, unpipelined: side u first, so an empty slot rejects before side
        // v is drawn. With slots or counts beyond the caches, whole proposals are drawn
        // AHEAD proposals ahead and both their slots prefetched: a draw depends only on
        // the tables, which stay fixed until a refresh discards it (occupancy is read
        // when the proposal is used).
        let ((bu, su, xu), (bv, sv, xv)) = if self.countdown > 0 {
            self.countdown -= 1;
            if self.pipeline {
                while !self.ahead.is_full() {
                    let a = self.draw_ahead(rng);
                    // (room: not full)
                    let _ = self.ahead.push_back(a);
                }
                let a = self.ahead.pop_front()?;
                let xu = self.occupant(a.bu, a.su)?;
                let xv = self.occupant(a.bv, a.sv)?;
                ((a.bu, a.su, xu), (a.bv, a.sv, xv))
            } else {
                let (k, bu, su) = self.draw_u(rng, false);
                let xu = self.occupant(bu, su)?;
                let (bv, sv) = self.draw_v(k, bu, rng);
                let xv = self.occupant(bv, sv)?;
                ((bu, su, xu), (bv, sv, xv))
            }
        } else {
            // the overflow stream's turn; then the count to its next one
            self.countdown = geometric(self.over_p, rng);
            self.draw_overflow(rng)?
        };
        if bu == bv && su == sv {
            // the particle with itself
            return None;
        }
        Some(Candidate {
            x: xu,
            y: xv,
            at: ((bu, su), (bv, sv)),
        })
    }

    /// `(bound, low)` of the pair in buckets `bu`, `bv`: the quantised largest factors
    /// and the smallest ones.
    #[inline(always)]
    pub(super) fn pair_bounds(&self, bu: usize, bv: usize) -> (f64, f64) {
        let (gu, gv) = (&self.buckets[bu], &self.buckets[bv]);
        let mut bound = 0.0;
        let mut low = 0.0;
        for kk in 0..R {
            bound += gu.hi[kk] * gv.hi[R + kk] + gv.hi[kk] * gu.hi[R + kk];
            low += gu.min[kk] * gv.min[R + kk] + gv.min[kk] * gu.min[R + kk];
        }
        (bound, low)
    }
}
