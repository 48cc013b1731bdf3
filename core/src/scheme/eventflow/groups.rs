//! The paper's weighted index sampling (Eibeck & Wagner 2000, §5.1): the weights are
//! split into groups by size bounds `B_1 < … < B_γ`; a group is drawn in proportion to
//! its total weight, then a member uniformly, accepted with probability `q_i / B_j`
//! (else another member of the same group).
//!
//! Here the bounds are powers of two: group g holds the weights of one binade
//! `[2^(e−1), 2^e)` and accepts with probability at least 1/2. A window of 64 binades
//! follows the largest weight (it sits 16 binades below the window's top after a
//! rebuild; the window moves up when a weight passes its top and down when the largest
//! falls 31 binades); the weights below the window share one catch-all group, at least
//! 2^16 times below the largest weight, drawn exactly by a scan of its members; the
//! zero weights share a group that is never drawn. Group totals are exact integer sums
//! of the weights' 53-bit mantissas (in the catch-all: of the weights in units of the
//! window's lowest last place, rounded down, an error below `n 2^−68` of the total), so
//! they never drift: they depend on the multiset of weights and the window only, never
//! on the order of the updates. The members of each group sit together in one
//! permutation of the particles, so moving a particle by k binades costs k swaps.
//!
//! The permutation does depend on the history: a checkpoint stores it (and the binade
//! window), so a restored run draws the same particles as the unbroken one.

use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::random::unit_f64;

/// Tries of the acceptance–rejection within a group before the exact scan (see
/// `Groups::sample`).
const GROUP_TRIES: u32 = 64;
use alloc::vec::Vec;
use rand_core::Rng;

/// Binades with their own group.
const BINADES: usize = 64;
/// Groups: 0 holds the zero weights, 1 the catch-all, 2.. the binades.
const NG: usize = BINADES + 2;
/// Where `fill` puts the largest weight's binade: room for weights to grow by 16 binades
/// before the window moves up.
const HEADROOM: i32 = 16;
/// The window moves down when the largest weight falls this far below its top.
const SINK: i32 = 48;

/// The binade of a finite positive double: its biased exponent field (0 for
/// subnormals).
#[inline(always)]
fn exponent(q: f64) -> i32 {
    ((q.to_bits() >> 52) & 0x7ff) as i32
}

/// A particle and its weight, in the order of the groups.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Slot {
    w: f64,
    i: u32,
}

/// One weight per particle, sampled by groups.
#[derive(Clone, Debug)]
pub(crate) struct Groups {
    /// The weight of each particle.
    w: Vec<f64>,
    /// The group of each particle.
    key: Vec<u8>,
    /// Each particle's place in `perm`.
    pos: Vec<u32>,
    /// The particles with their weights, group by group (a draw reads one slot).
    perm: Vec<Slot>,
    /// `perm[start[g]..start[g + 1]]` is group g.
    start: [u32; NG + 1],
    /// The exact integer total of each group (see the module docs).
    sum: [u128; NG],
    /// The total of each group as a double.
    gw: [f64; NG],
    /// The exponent field of the lowest binade with its own group.
    base: i32,
    /// Each group's acceptance bound and the power of two a unit of its total stands
    /// for (from `base`).
    bnd: [f64; NG],
    units: [f64; NG],
    /// The total weight: the groups' totals summed from the lowest.
    total: f64,
    /// The highest group with a member (0 when none has a positive weight).
    hi: usize,
    /// The lowest positive group with a member (`NG` when none).
    lo: usize,
}

impl Groups {
    /// Room for `cap` particles (allocated here, once).
    pub(crate) fn new(cap: usize) -> Result<Self> {
        if u32::try_from(cap).is_err() {
            return Err(Error::Capacity {
                name: "particles (the group sampler indexes them with 32 bits)",
                capacity: cap,
            });
        }
        let mut g = Groups {
            w: Vec::new(),
            key: Vec::new(),
            pos: Vec::new(),
            perm: Vec::new(),
            start: [0; NG + 1],
            sum: [0; NG],
            gw: [0.0; NG],
            base: 1023 - 32,
            bnd: [0.0; NG],
            units: [0.0; NG],
            total: 0.0,
            hi: 0,
            lo: NG,
        };
        g.set_base(1023 - 32);
        let oom = |_| Error::Capacity {
            name: "group sampler tables",
            capacity: cap,
        };
        g.w.try_reserve_exact(cap).map_err(oom)?;
        g.key.try_reserve_exact(cap).map_err(oom)?;
        g.pos.try_reserve_exact(cap).map_err(oom)?;
        g.perm.try_reserve_exact(cap).map_err(oom)?;
        Ok(g)
    }

    fn len(&self) -> usize {
        self.w.len()
    }

    /// The group of weight `q` in the window from `base`; `None` above the window.
    #[inline(always)]
    fn key_in(base: i32, q: f64) -> Option<usize> {
        if q <= 0.0 {
            return Some(0);
        }
        let e = exponent(q);
        if e < base {
            Some(1)
        } else if e < base + BINADES as i32 {
            Some(2 + (e - base) as usize)
        } else {
            None
        }
    }

    /// The integer that `q` adds to the total of its group `g`.
    #[inline(always)]
    fn mantissa(&self, q: f64, g: usize) -> u64 {
        if q <= 0.0 {
            return 0;
        }
        match g {
            0 => 0,
            // the catch-all counts in units of the lowest binade's last place
            1 => libm::scalbn(q, 1075 - self.base) as u64,
            _ => (q.to_bits() & ((1 << 52) - 1)) | (1 << 52),
        }
    }

    /// Moves the window: the lowest binade with its own group has exponent field
    /// `base`. Each group's unit (the power of two one unit of its total stands for)
    /// and acceptance bound (the top of its binade; the window's lowest binade's
    /// bottom for the catch-all) follow.
    fn set_base(&mut self, base: i32) {
        self.base = base;
        for g in 0..NG {
            let e = if g <= 1 { base } else { base + (g - 2) as i32 };
            self.units[g] = libm::scalbn(1.0, e - 1075);
            self.bnd[g] = if g <= 1 {
                libm::scalbn(1.0, base - 1023)
            } else {
                libm::scalbn(1.0, e - 1022)
            };
        }
    }

    #[inline(always)]
    fn unit(&self, g: usize) -> f64 {
        self.units[g]
    }

    #[inline(always)]
    fn count(&self, g: usize) -> u32 {
        self.start[g + 1] - self.start[g]
    }

    /// Group g's total as a double from its exact one (then `add_up`).
    #[inline(always)]
    fn refresh(&mut self, g: usize) {
        self.gw[g] = if g == 0 {
            0.0
        } else {
            self.sum[g] as f64 * self.unit(g)
        };
    }

    /// The total weight from the groups', summed from the lowest.
    #[inline(always)]
    fn add_up(&mut self) {
        let mut t = 0.0;
        for g in self.lo..=self.hi {
            t += self.gw[g];
        }
        self.total = t;
    }

    /// Puts `s` at place p.
    #[inline(always)]
    fn put(&mut self, p: usize, s: Slot) {
        self.perm[p] = s;
        self.pos[s.i as usize] = p as u32;
    }

    /// Particle i's slot.
    #[inline(always)]
    fn slot(&self, i: usize) -> Slot {
        Slot {
            w: self.w[i],
            i: i as u32,
        }
    }

    /// Moves particle i from its group to group b, `|b − a|` swaps.
    fn relocate(&mut self, i: usize, b: usize) {
        let mut a = usize::from(self.key[i]);
        let mut p = self.pos[i] as usize;
        let me = self.slot(i);
        while a < b {
            // to the end of group a, then the boundary moves below it
            let last = self.start[a + 1] as usize - 1;
            self.put(p, self.perm[last]);
            self.put(last, me);
            self.start[a + 1] -= 1;
            p = last;
            a += 1;
        }
        while a > b {
            let first = self.start[a] as usize;
            self.put(p, self.perm[first]);
            self.put(first, me);
            self.start[a] += 1;
            p = first;
            a -= 1;
        }
        self.perm[p] = me;
        self.key[i] = b as u8;
    }

    /// The lowest and highest positive groups with members, found again.
    fn rescan(&mut self) {
        self.hi = (1..NG).rev().find(|&g| self.count(g) > 0).unwrap_or(0);
        self.lo = (1..NG).find(|&g| self.count(g) > 0).unwrap_or(NG);
    }

    /// Sets the weight of particle `i < len` to `q` (finite, not negative).
    pub(crate) fn set(&mut self, i: usize, q: f64) {
        let Some(b) = Self::key_in(self.base, q) else {
            // above the window: build it again around the new largest weight
            self.w[i] = q;
            self.rebuild();
            return;
        };
        let a = usize::from(self.key[i]);
        let old = self.mantissa(self.w[i], a);
        self.sum[a] -= u128::from(old);
        self.sum[b] += u128::from(self.mantissa(q, b));
        self.w[i] = q;
        if a != b {
            self.relocate(i, b);
            self.refresh(a);
        } else {
            self.perm[self.pos[i] as usize].w = q;
        }
        self.refresh(b);
        if b > self.hi {
            self.hi = b;
        }
        if b >= 1 && b < self.lo {
            self.lo = b;
        }
        if a != b && self.count(a) == 0 && (a == self.hi || a == self.lo) {
            self.rescan();
        }
        self.follow_down();
        self.add_up();
    }

    /// Moves the window down when the largest weight has sunk far below its top while
    /// some weights sit in the catch-all: they stay at least `2^(BINADES − SINK)` times
    /// below the largest (the window can move: the base is not at the lowest binade,
    /// and then it moves down by at least `SINK − HEADROOM` binades).
    #[inline(always)]
    fn follow_down(&mut self) {
        if self.base > 1 && self.count(1) > 0 && self.hi < 2 + (BINADES as i32 - SINK) as usize {
            self.rebuild();
        }
    }

    /// Appends a particle of weight `q` (the caller has checked the capacity).
    pub(crate) fn push(&mut self, q: f64) {
        let i = self.len();
        self.w.push(0.0);
        self.key.push((NG - 1) as u8);
        self.pos.push(i as u32);
        self.perm.push(Slot {
            w: 0.0,
            i: i as u32,
        });
        self.start[NG] += 1;
        self.set(i, q);
    }

    /// Removes particle i: the last particle takes its index.
    pub(crate) fn swap_remove(&mut self, i: usize) {
        let a = usize::from(self.key[i]);
        self.sum[a] -= u128::from(self.mantissa(self.w[i], a));
        self.refresh(a);
        // into the highest group with members (the groups above it are empty: their
        // boundaries all sit at the end), to the end of the permutation, then off it
        let top = if self.hi >= 1 && self.count(self.hi) > 0 {
            self.hi.max(a)
        } else {
            a
        };
        self.relocate(i, top);
        let p = self.pos[i] as usize;
        let end = self.perm.len() - 1;
        self.put(p, self.perm[end]);
        self.perm.pop();
        for b in &mut self.start[top + 1..] {
            *b -= 1;
        }
        let last = self.len() - 1;
        if i != last {
            let p = self.pos[last] as usize;
            self.perm[p].i = i as u32;
            self.pos[i] = p as u32;
            self.key[i] = self.key[last];
            self.w[i] = self.w[last];
        }
        self.w.pop();
        self.key.pop();
        self.pos.pop();
        if a >= 1 && self.count(a) == 0 {
            self.rescan();
        }
        self.follow_down();
        self.add_up();
    }

    /// Replaces every weight (at most the capacity) and builds the groups, the window
    /// from the largest weight.
    pub(crate) fn fill(&mut self, weights: impl Iterator<Item = f64>) {
        self.w.clear();
        self.w.extend(weights);
        self.rebuild();
    }

    fn rebuild(&mut self) {
        let top = self
            .w
            .iter()
            .copied()
            .filter(|&q| q > 0.0)
            .map(exponent)
            .max();
        self.set_base(match top {
            Some(e) => (e + HEADROOM - BINADES as i32 + 1).max(1),
            None => 1023 - 32,
        });
        let n = self.len();
        self.key.clear();
        let base = self.base;
        self.key.extend(
            self.w
                .iter()
                .map(|&q| Self::key_in(base, q).unwrap_or(NG - 1) as u8),
        );
        // a stable counting sort by group
        let mut count = [0u32; NG + 1];
        for &k in &self.key {
            count[usize::from(k) + 1] += 1;
        }
        for g in 0..NG {
            count[g + 1] += count[g];
        }
        self.start = count;
        self.perm.clear();
        self.perm.resize(n, Slot::default());
        self.pos.clear();
        self.pos.resize(n, 0);
        let mut next = count;
        for i in 0..n {
            let g = usize::from(self.key[i]);
            let p = next[g] as usize;
            next[g] += 1;
            self.put(p, self.slot(i));
        }
        self.totals();
    }

    /// Group totals from the weights.
    fn totals(&mut self) {
        self.sum = [0; NG];
        for i in 0..self.len() {
            let g = usize::from(self.key[i]);
            self.sum[g] += u128::from(self.mantissa(self.w[i], g));
        }
        for g in 0..NG {
            self.refresh(g);
        }
        self.rescan();
        self.add_up();
    }

    /// The weight of particle i.
    #[inline(always)]
    pub(crate) fn weight(&self, i: usize) -> f64 {
        self.w[i]
    }

    /// The total weight (the groups' totals summed from the lowest).
    #[inline(always)]
    pub(crate) fn total(&self) -> f64 {
        self.total
    }

    /// A particle drawn with probability proportional to its weight (the total must be
    /// positive).
    #[inline]
    pub(crate) fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> usize {
        let total = self.total();
        if total.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            // (the callers never ask then)
            return 0;
        }
        let mut u = unit_f64(rng.next_u64()) * total;
        let mut g = self.hi;
        for k in (self.lo..=self.hi).rev() {
            let w = self.gw[k];
            if w > 0.0 {
                g = k;
                if u < w {
                    break;
                }
                u -= w;
            }
        }
        let (first, count) = (self.start[g] as usize, u64::from(self.count(g)));
        let members = &self.perm[first..first + count as usize];
        if g != 1 {
            // acceptance–rejection within the binade: each try accepts with probability
            // at least 1/2, so GROUP_TRIES rejections in a row come with probability
            // 2^-64 from a sound stream, and always from a stuck one (a broken host
            // callback), which must not hang the call; the scan below draws from the
            // same law, so the fallback changes nothing in distribution
            let bound = self.bnd[g];
            for _ in 0..GROUP_TRIES {
                let r = ((u128::from(rng.next_u64()) * u128::from(count)) >> 64) as usize;
                let s = members[r];
                if unit_f64(rng.next_u64()) * bound < s.w {
                    return s.i as usize;
                }
            }
        }
        // exactly, by the members' integer weights: the catch-all always (its bound can
        // be far above them, and the group is drawn rarely: see the module docs)
        let v = (unit_f64(rng.next_u64()) * self.sum[g] as f64) as u128;
        let mut acc = 0u128;
        for s in members {
            acc += u128::from(self.mantissa(s.w, g));
            if v < acc {
                return s.i as usize;
            }
        }
        // (v rounded up to the total: the last member of positive weight)
        let last = members.iter().rev().find(|s| self.mantissa(s.w, g) > 0);
        last.map_or(members[0].i, |s| s.i) as usize
    }

    /// The window and the order of the particles, for a checkpoint.
    pub(crate) fn save(&self, w: &mut Writer) {
        w.u64(self.base as u64);
        for pair in self.perm.chunks(2) {
            w.u64(u64::from(pair[0].i) | pair.get(1).map_or(0, |b| u64::from(b.i) << 32));
        }
    }

    /// The sampler of room `cap` with the window and the order written by
    /// [`save`](Self::save) over `weights` (each finite, not negative; at most `cap`),
    /// the order checked to be a permutation that keeps every group together.
    pub(crate) fn read(
        r: &mut Reader,
        cap: usize,
        weights: impl Iterator<Item = f64>,
    ) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        let base = r.u64()?;
        if !(1..2047).contains(&base) {
            return Err(bad("group sampler: binade window out of range"));
        }
        let base = base as i32;
        let mut w = Vec::new();
        let mut key = Vec::new();
        for q in weights {
            let k = Self::key_in(base, q).ok_or(bad("group sampler: a weight above its window"))?;
            w.push(q);
            key.push(k as u8);
        }
        let n = w.len();
        let mut perm = Vec::new();
        perm.try_reserve_exact(n)
            .map_err(|_| bad("group sampler: cannot allocate the order"))?;
        for _ in 0..n.div_ceil(2) {
            let v = r.u64()?;
            perm.push(v as u32);
            perm.push((v >> 32) as u32);
        }
        if n % 2 == 1 && perm.pop() != Some(0) {
            return Err(bad("group sampler: padding of the order is not zero"));
        }
        let mut seen = Vec::new();
        seen.resize(n, false);
        let mut prev = 0u8;
        for &i in &perm {
            let i = i as usize;
            if i >= n || seen[i] {
                return Err(bad("group sampler: the order is not a permutation"));
            }
            seen[i] = true;
            if key[i] < prev {
                return Err(bad("group sampler: the order splits a group"));
            }
            prev = key[i];
        }
        let mut count = [0u32; NG + 1];
        for &k in &key {
            count[usize::from(k) + 1] += 1;
        }
        for g in 0..NG {
            count[g + 1] += count[g];
        }
        let mut g = Groups::new(cap)?;
        g.set_base(base);
        g.w.extend_from_slice(&w);
        g.key.extend_from_slice(&key);
        g.start = count;
        g.pos.resize(n, 0);
        g.perm.extend(perm.iter().map(|&i| Slot {
            w: w[i as usize],
            i,
        }));
        for p in 0..n {
            g.pos[perm[p] as usize] = p as u32;
        }
        g.totals();
        Ok(g)
    }

    /// Checks the internal invariants (tests).
    #[cfg(test)]
    pub(crate) fn check(&self) {
        let n = self.len();
        assert_eq!(self.perm.len(), n);
        assert_eq!(self.start[0], 0);
        assert_eq!(self.start[NG] as usize, n);
        let mut sum = [0u128; NG];
        for i in 0..n {
            let g = usize::from(self.key[i]);
            assert_eq!(Self::key_in(self.base, self.w[i]), Some(g));
            assert_eq!(self.perm[self.pos[i] as usize], self.slot(i));
            let p = self.pos[i];
            assert!(self.start[g] <= p && p < self.start[g + 1]);
            sum[g] += u128::from(self.mantissa(self.w[i], g));
        }
        assert_eq!(sum, self.sum);
        let mut t = 0.0;
        for g in self.lo..=self.hi {
            t += self.gw[g];
        }
        assert_eq!(t.to_bits(), self.total.to_bits());
        // hi and lo are exact: the removal relies on hi
        assert!(self.hi == 0 || self.count(self.hi) > 0);
        assert!(self.lo == NG || self.count(self.lo) > 0);
        for g in 1..NG {
            assert_eq!(self.gw[g], self.sum[g] as f64 * self.unit(g));
            if self.count(g) > 0 {
                assert!(self.lo <= g && g <= self.hi);
            }
        }
    }
}
