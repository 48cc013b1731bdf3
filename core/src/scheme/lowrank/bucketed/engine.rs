//! The bucketed engine as a [`ProposalEngine`], with its checkpoint (see the module
//! docs of [`bucketed`](super)).

use super::*;

impl<const R: usize, const W: usize> ProposalEngine<R> for BucketedEngine<R, W> {
    type Loc = Loc;
    const TAG: u64 = crate::scheme::tag::BUCKETED;
    const LOW: Low = Low::Factors;

    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self> {
        Self::with_counts(kernel, counts, pop)
    }

    #[inline]
    fn refresh<G: Rng + ?Sized>(&mut self, pop: &Population, rng: &mut G) -> Result<f64> {
        self.refresh_rates(pop, rng)
    }

    /// The rate is constant until the tables change: proposals in batches, with no
    /// clock per proposal (see `clock`) — except in a small system, where almost every
    /// event changes the rates and a batch's gamma and beta draws would cost more than
    /// an exponential per proposal.
    #[inline]
    fn batches(&self, pop: &Population) -> bool {
        pop.n >= SMALL_N
    }

    #[inline(always)]
    fn needs_refresh(&self) -> bool {
        self.stale()
    }

    #[inline(always)]
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<Loc>> {
        self.draw(rng)
    }

    #[inline(always)]
    fn bounds(&self, &((bu, _), (bv, _)): &Loc) -> (f64, f64) {
        self.pair_bounds(bu, bv)
    }

    #[inline(always)]
    fn prepare<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        outcome: &Outcome,
        pop: &Population,
    ) -> Result<()> {
        let Outcome::Merge { size } = *outcome else {
            return Ok(());
        };
        if size > self.m {
            // the fallible part first (new buckets' factors), so an error changes nothing
            self.reserve_m(2 * self.m, pop.memory_budget)?;
            self.extend_buckets(kernel, 2 * self.m)?;
        }
        Ok(())
    }

    #[inline(always)]
    fn apply(&mut self, c: &Candidate<Loc>, outcome: &Outcome) {
        if let Outcome::Merge { size } = *outcome {
            self.merge(c, size);
        }
    }

    #[cold]
    fn double(&mut self, _pop: &Population) {
        self.double_particles();
    }

    #[inline(always)]
    fn settle(&mut self, pop: &Population) {
        self.after_event(pop.n);
    }

    fn counts(&self) -> Cow<'_, [u64]> {
        Cow::Owned(self.count_vec())
    }

    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        let mut scratch: Vec<u32> = Vec::new();
        for (b, bk) in self.buckets.iter().enumerate() {
            if bk.n == 0 {
                continue;
            }
            let (lo, hi) = bucket_range(b);
            let hi = hi.min(self.m);
            let list = b
                .checked_sub(SINGLE as usize)
                .and_then(|l| self.lists.get(l))
                .filter(|_| !bk.grid);
            match list {
                // a list bucket: its particles' offsets, sorted and counted
                Some(list) => each_in_list(lo, list, &mut scratch, f),
                None => {
                    for s in lo..=hi {
                        let c = self.counts[s as usize];
                        if c > 0 {
                            f(s, u64::from(c));
                        }
                    }
                }
            }
        }
    }

    const EDITS: bool = true;

    fn draw_particle<G: Rng + ?Sized>(
        &self,
        by_mass: bool,
        n: u64,
        rng: &mut G,
    ) -> Option<(u64, (usize, u64))> {
        let counts = self
            .buckets
            .iter()
            .enumerate()
            .skip(1)
            .map(|(b, bk)| (b, bk.n));
        // (bounded: a degenerate random stream cannot hang the call; a real one passes
        // MAX_TRIES rejections in a row with probability below 2^-400)
        for _ in 0..crate::random::MAX_TRIES {
            let b =
                crate::scheme::lowrank::edit::pick_bucket(counts.clone(), n, by_mass, self.m, rng)?;
            // a uniform slot of the bucket, an empty one drawn again: a uniform particle
            let bk = &self.buckets[b];
            let Some((s, x)) = (0..crate::random::MAX_TRIES).find_map(|_| {
                let s = below(rng, bk.slots);
                self.occupant(b, s).map(|x| (s, x))
            }) else {
                continue;
            };
            if !by_mass || crate::scheme::lowrank::edit::keep_by_mass(b, x, self.m, rng) {
                return Some((x, (b, s)));
            }
        }
        None
    }

    fn remove_particle(&mut self, (b, s): (usize, u64), x: u64) {
        self.remove(b, s, x);
    }

    fn add_particle<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        x: u64,
        pop: &Population,
    ) -> Result<()> {
        while x > self.m {
            self.reserve_m(2 * self.m, pop.memory_budget)?;
            self.extend_buckets(kernel, 2 * self.m)?;
            self.double_m();
        }
        self.insert(x);
        Ok(())
    }

    fn rereference(&mut self, pop: &Population) {
        self.qmax = ((1u64 << 60) / pop.n0.max(1)).min(1 << 53);
        self.requantise();
        self.rates_stale = true;
    }

    fn rate_now(&self) -> Option<f64> {
        if self.stale() {
            return None;
        }
        let r = self.rates();
        let consistent = r.over.to_bits() == self.over_rate.to_bits()
            && (if r.total > 0.0 {
                (r.over / r.total).clamp(0.0, 1.0)
            } else {
                0.0
            })
            .to_bits()
                == self.over_p.to_bits();
        consistent.then_some(r.total)
    }

    fn max_size(&self) -> u64 {
        self.m
    }

    /// Each bucket's slots and list order, the tables' slot counts and the
    /// bookkeeping between resyncs — everything the next proposal depends on, so a
    /// restored run continues bit for bit. The bounds and alias tables are rebuilt
    /// from the kernel and the saved slot counts.
    fn save(&self, w: &mut Writer) {
        for v in [
            self.since_resync,
            self.planned,
            u64::from(self.poisoned.is_some()),
            u64::from(self.rates_stale),
            u64::from(self.rates_changed),
            u64::from(self.pipeline),
        ] {
            w.u64(v);
        }
        // the proposals drawn ahead: 0 (none), or 2, their number and each one's five
        // words (1 was a format that drew one side u ahead: refused)
        if self.ahead.is_empty() {
            w.u64(0);
        } else {
            w.u64(2);
            w.u64(self.ahead.len() as u64);
            for a in self.ahead.iter() {
                for v in [a.k as u64, a.bu as u64, a.su, a.bv as u64, a.sv] {
                    w.u64(v);
                }
            }
        }
        for &v in &self.base_slack {
            w.u64(v);
        }
        w.u64(self.over.len() as u64);
        for &b in &self.over {
            w.u64(b as u64);
        }
        w.u64(self.counts.len() as u64);
        for &c in &self.counts {
            w.u64(u64::from(c));
        }
        w.u64(self.buckets.len() as u64);
        for bk in &self.buckets {
            for v in [
                bk.slots,
                bk.tab,
                bk.n,
                bk.cap,
                bk.judged,
                u64::from(bk.grid),
            ] {
                w.u64(v);
            }
        }
        for list in &self.lists {
            w.u64(list.len() as u64);
            for &off in list {
                w.u64(u64::from(off));
            }
        }
        // the overflow stream as the last refresh left it (a scheme between proposals
        // keeps it across calls)
        w.f64(self.over_rate);
        w.f64(self.over_p);
        w.u64(self.countdown);
    }

    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        let n = pop.n;
        // doubling keeps n below n0 (it doubles when n < n0/2); a fresh start has n = n0
        if pop.n0 > MAX_PARTICLES || n > pop.n0 {
            return Err(bad("invalid particle number or reference"));
        }
        within_budget(
            count_len(m).checked_mul(core::mem::size_of::<u32>()),
            pop.memory_budget,
        )?;
        let (since_resync, planned) = (r.u64()?, r.u64()?);
        let flag = |r: &mut Reader| -> Result<bool> {
            match r.u64()? {
                0 => Ok(false),
                1 => Ok(true),
                _ => Err(bad("invalid flag")),
            }
        };
        let (poisoned, stale, changed, pipeline) = (flag(r)?, flag(r)?, flag(r)?, flag(r)?);
        let mut ahead = heapless::Deque::<Ahead, { AHEAD + 1 }>::new();
        match r.u64()? {
            0 => {}
            1 => {
                return Err(bad(
                    "a run drawing side u ahead (before proposals were drawn whole): not supported",
                ));
            }
            2 => {
                // (a queue is filled to AHEAD + 1 and one taken before anything else runs)
                if r.u64()? != AHEAD as u64 {
                    return Err(bad("draw ahead inconsistent"));
                }
                for _ in 0..AHEAD {
                    let (k, bu, su) = (r.usize()?, r.usize()?, r.u64()?);
                    let (bv, sv) = (r.usize()?, r.u64()?);
                    let _ = ahead.push_back(Ahead { k, bu, su, bv, sv });
                }
            }
            _ => return Err(bad("invalid flag")),
        }
        let mut base_slack = [0u64; W];
        for v in &mut base_slack {
            *v = r.u64()?;
        }
        let nb = bucket_of(m) + 1;
        let over_len = r.usize()?;
        if over_len > OVER_MAX {
            return Err(bad("overflow list too long"));
        }
        let mut over = heapless::Vec::<usize, OVER_MAX>::new();
        for _ in 0..over_len {
            over.push(r.usize()?)
                .map_err(|_| bad("overflow list too long"))?;
        }
        if r.usize()? != count_len(m) {
            return Err(bad("count array of another length"));
        }
        let mut counts = Vec::new();
        try_reserve(&mut counts, count_len(m))?;
        for _ in 0..count_len(m) {
            counts.push(u32::try_from(r.u64()?).map_err(|_| bad("count above 2^32"))?);
        }
        if r.usize()? != nb {
            return Err(bad("bucket table of another length"));
        }
        // a fresh engine of the same kernel supplies the bounds up to M
        let mut s = Self::with_counts(kernel, &[1], pop)?;
        s.extend_buckets(kernel, m)?;
        s.quantise();
        for bk in s.buckets.iter_mut() {
            let (slots, tab, bn, cap, judged) = (r.u64()?, r.u64()?, r.u64()?, r.u64()?, r.u64()?);
            // (`judged` is only a heuristic's memory; doublings double it even in a
            // bucket that has since emptied, so any value is one a run can leave.
            // `tab` is that of the tables in use: a resync may shrink the slots below
            // it, and leaves the tables stale until the next proposal rebuilds them —
            // a state a budget can stop in, found by fuzzing)
            if bn > slots || (!stale && tab > slots) {
                return Err(bad("bucket slots inconsistent"));
            }
            (bk.slots, bk.tab, bk.n, bk.cap, bk.judged) = (slots, tab, bn, cap, judged);
            bk.grid = flag(r)?;
        }
        for list in s.lists.iter_mut() {
            let len = r.usize()?;
            let mut l = Vec::new();
            try_reserve(&mut l, len.min(n as usize))?;
            for _ in 0..len {
                l.push(u32::try_from(r.u64()?).map_err(|_| bad("list offset"))?);
            }
            *list = l;
        }
        let (over_rate, over_p, countdown) = (r.f64()?, r.f64()?, r.u64()?);
        if !(over_rate >= 0.0 && over_rate.is_finite() && (0.0..=1.0).contains(&over_p)) {
            return Err(bad("overflow stream inconsistent"));
        }
        // every redundant piece must agree, or a later proposal would index out of
        // range: particles, grid levels, list offsets, the overflow and the draw ahead
        let mut total = 0u64;
        for (b, bk) in s.buckets.iter().enumerate() {
            total = total.checked_add(bk.n).ok_or(bad("particle number"))?;
            if b == 0 {
                // (size 0 holds nobody: a count there, never observed, was doubled
                // past 2^32 — found by fuzzing)
                if bk.n != 0 || bk.slots != 0 || counts[0] != 0 {
                    return Err(bad("bucket 0 holds particles"));
                }
                continue;
            }
            let (lo, hi) = bucket_range(b);
            let width = 1u64 << width_bits(b);
            if bk.grid {
                let cs = &counts[lo as usize..=hi as usize];
                let sum: u64 = cs.iter().map(|&c| u64::from(c)).sum();
                let mx = u64::from(cs.iter().copied().max().unwrap_or(0));
                if sum != bk.n || mx > bk.cap || bk.cap.checked_mul(width) != Some(bk.slots) {
                    return Err(bad("grid bucket inconsistent"));
                }
            } else {
                let list = s
                    .lists
                    .get(b.wrapping_sub(SINGLE as usize))
                    .ok_or(bad("a singleton bucket in list mode"))?;
                // (the bucket of M runs past M: no particle is larger than M)
                if list.len() as u64 != bk.n
                    || list
                        .iter()
                        .any(|&o| u64::from(o) >= width || lo + u64::from(o) > m)
                {
                    return Err(bad("list bucket inconsistent"));
                }
            }
        }
        if total != n || counts[m as usize + 1..].iter().any(|&c| c != 0) {
            return Err(bad("counts do not add up"));
        }
        // the overflow holds distinct buckets; with current tables, exactly the grown
        // ones (stale tables are rebuilt, and the overflow emptied, before any use)
        let grown = s.buckets.iter().filter(|bk| bk.slots > bk.tab).count();
        if over.iter().enumerate().any(|(i, &b)| {
            b >= nb || over[..i].contains(&b) || (!stale && s.buckets[b].slots <= s.buckets[b].tab)
        }) || (!stale && over.len() != grown)
        {
            return Err(bad("overflow list inconsistent"));
        }
        let slot_ok = |b: usize, sl: u64| b < nb && sl < s.buckets[b].tab;
        if (!ahead.is_empty() && !pipeline)
            || ahead
                .iter()
                .any(|a| a.k >= R || !slot_ok(a.bu, a.su) || !slot_ok(a.bv, a.sv))
        {
            return Err(bad("draw ahead inconsistent"));
        }
        s.counts = counts;
        s.over = over;
        s.m = m;
        s.slots_total = s
            .buckets
            .iter()
            .try_fold(0u64, |a, bk| a.checked_add(bk.slots))
            .filter(|&t| t <= 1 << 60)
            .ok_or(bad("slot count overflows"))?;
        s.planned = planned;
        s.since_resync = since_resync;
        s.base_slack = base_slack;
        for rr in 0..W {
            match (s.weight(rr, |bk| bk.slots), s.weight(rr, |bk| bk.tab)) {
                (Some(t), Some(mn)) => {
                    s.row_total[rr] = t;
                    s.main[rr] = mn;
                }
                _ => return Err(bad("slot weights overflow")),
            }
        }
        let slack_ok = (0..W).all(|rr| base_slack[rr] <= s.row_total[rr]);
        if planned > s.slots_total || !slack_ok || since_resync > 1 << 62 {
            return Err(bad("resync bookkeeping inconsistent"));
        }
        s.set_resync_threshold();
        if !stale {
            s.build_tables();
            if s.poisoned.is_some() {
                return Err(bad("slot weights overflow"));
            }
        }
        // main-stream proposals need main-stream tables (a refresh draws the countdown
        // 0 when the overflow carries the whole rate)
        if !stale && s.joint.n == 0 && (countdown != 0 || !ahead.is_empty()) {
            return Err(bad("main-stream proposals without main-stream tables"));
        }
        s.rates_stale = stale;
        s.rates_changed = changed;
        s.pipeline = pipeline;
        s.ahead = ahead;
        (s.over_rate, s.over_p, s.countdown) = (over_rate, over_p, countdown);
        if poisoned {
            s.poison();
        }
        Ok(s)
    }
}
