//! The bucketed engine's stream rates and its alias tables over the buckets (see the
//! module docs of [`bucketed`](super)).

use super::*;

impl<const R: usize, const W: usize> BucketedEngine<R, W> {
    /// Rebuilds the proposal tables if they are stale (or the overflow has grown past
    /// [`OVER_MAX`] buckets or 1/16 of the rate); returns the proposal rates and redraws
    /// the overflow countdown.
    pub(super) fn refresh_rates<Rn: Rng + ?Sized>(
        &mut self,
        pop: &Population,
        rng: &mut Rn,
    ) -> Result<f64> {
        if let Some(e) = self.poisoned {
            return Err(e);
        }
        let mut rates = self.rates();
        if !rates.total.is_finite() {
            return Err(crate::scheme::population::rate_overflow(rates.total));
        }
        // a small system grows a bucket at most events (every new size is a new slot),
        // and a rebuild costs O(buckets) against a scan of ≤ OVER_MAX grown buckets for
        // an overflow proposal: there the overflow may carry half the rate
        let share = if pop.n < SMALL_N { 2.0 } else { 16.0 };
        if pop.n >= 2 && rates.total > 0.0 && (self.rates_stale || rates.over > rates.total / share)
        {
            self.rebuild_tables();
            if let Some(e) = self.poisoned {
                return Err(e);
            }
            rates = self.rates();
        }
        self.rates_changed = false;
        self.over_rate = rates.over;
        // (an empty system has no rate at all: no overflow proposal either)
        self.over_p = if rates.total > 0.0 {
            (rates.over / rates.total).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.countdown = geometric(self.over_p, rng);
        Ok(rates.total)
    }

    /// The streams' rates: main `Σ_k M_k M_{R+k} s_k s_{R+k}` and overflow (the sum
    /// of [`Self::over_terms`]), each summed from its own terms so that a small
    /// overflow keeps its relative precision.
    pub(super) fn rates(&self) -> StreamRates {
        let (mut main, mut over) = (0.0, 0.0);
        for k in 0..R {
            let ck = self.scale[k] * self.scale[R + k];
            main += self.main[k] as f64 * self.main[R + k] as f64 * ck;
            let [a, b] = self.over_terms(k);
            over += a + b;
        }
        StreamRates {
            over,
            total: main + over,
        }
    }

    /// Component k's overflow terms: `O_k T_{R+k} s_k s_{R+k}` (side u grown) and
    /// `M_k O_{R+k} s_k s_{R+k}` (side u in the tables, side v grown), `O = T − M`
    /// (saturating: the terms are meaningless only while the tables are stale).
    pub(super) fn over_terms(&self, k: usize) -> [f64; 2] {
        let ck = self.scale[k] * self.scale[R + k];
        let ou = self.row_total[k].saturating_sub(self.main[k]) as f64;
        let ov = self.row_total[R + k].saturating_sub(self.main[R + k]) as f64;
        [
            ou * self.row_total[R + k] as f64 * ck,
            self.main[k] as f64 * ov * ck,
        ]
    }

    /// Rebuilds the tables from the current slots (which become `tab`); the overflow
    /// empties.
    #[cold]
    pub(super) fn rebuild_tables(&mut self) {
        for bk in &mut self.buckets {
            bk.tab = bk.slots;
        }
        self.main = self.row_total;
        self.over.clear();
        self.build_tables();
        // proposals drawn against the old tables are void
        self.ahead.clear();
        self.pipeline = self.counts.len() >= PIPELINE_COUNTS || self.slots_total >= PIPELINE_SLOTS;
    }

    /// Builds the alias tables from the buckets' `tab` slots and `main` (a function of
    /// them alone, so a restored checkpoint rebuilds the very same tables).
    pub(super) fn build_tables(&mut self) {
        // component weights: c_k = T_{v,k} s_k s_{R+k}, S_A = Σ_k T_{u,k} c_k
        let mut c = [0.0; R];
        let mut sa = 0.0;
        for k in 0..R {
            c[k] = self.main[R + k] as f64 * self.scale[k] * self.scale[R + k];
            sa += self.main[k] as f64 * c[k];
        }
        let sc = &mut self.scratch;
        // side u, jointly over (k, b): integer weights summing to at most 2^61
        sc.weights.clear();
        for (k, &ck) in c.iter().enumerate() {
            if ck <= 0.0 {
                // no pairs of component k (its v row is empty)
                continue;
            }
            // (ck / sa first: ck · 2^61 overflows for kernels near the largest double,
            // fuzzing finding 10; ck ≤ sa / T_{u,k}, so f · q · slots stays ≤ 2^61)
            let f = ck / sa * (1u64 << 61) as f64;
            for (b, bk) in self.buckets.iter().enumerate() {
                // q · slots is exact in u64; rounded up once, so a bucket with
                // slots is never left out (and one without never chosen)
                // (≤ row_total < 2^63: the checked sums of `resync` and `grow` bound it)
                let qs = bk.q[k] * bk.tab;
                if qs > 0 {
                    sc.weights.push((
                        ((qs as f64 * f) as u64).saturating_add(1),
                        (k << 16 | b) as u32,
                    ));
                }
            }
        }
        let mut ok = self.joint.rebuild(sc);
        // one row over the buckets, weight q_r(b) tab_b
        let mut row = |table: &mut Alias, r: usize| {
            sc.weights.clear();
            sc.weights.extend(
                self.buckets
                    .iter()
                    .enumerate()
                    .map(|(b, bk)| (bk.q[r] * bk.tab, b as u32)),
            );
            table.rebuild(sc)
        };
        for (k, table) in self.side_v.iter_mut().enumerate() {
            ok &= row(table, R + k);
        }
        for (k, table) in self.side_u.iter_mut().enumerate() {
            ok &= row(table, k);
        }
        if !ok {
            self.poison();
        }
        self.rates_stale = false;
    }
}
