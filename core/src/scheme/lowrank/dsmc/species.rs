//! The particles of one size by speed class: the class structure that bounds a
//! pair's relative speed for the DSMC majorant (Osinsky 2023 §5; see the module docs
//! of [`dsmc`](super)).

use super::*;

/// The particles of one speed class.
#[derive(Clone, Debug)]
pub(super) struct Class {
    /// `2^{(q+1)/4}`, a little above (so that rounding never lets a speed pass it).
    pub(super) w: f64,
    pub(super) v: Vec<[f64; 3]>,
}

impl Class {
    pub(super) fn new(q: i32) -> Self {
        Class {
            w: class_bound(q),
            v: Vec::new(),
        }
    }
}

/// The particles of one size, by speed class.
///
/// `classes[0]` is the class of the particles (almost) at rest, [`Q_MIN`]; after it the
/// classes are dense: `classes[d]` is class `base + d − 1` (empty ones included), so a
/// class is found by a subtraction. The counts and the sum `S = Σ_q n_q W_q` are kept
/// up to date at every move: `W_q = R_r 2^h` with `q + 1 = 4h + r` and `R_r = 2^{r/4}`
/// (rounded up), so the moving classes' part of `S` is `2^a Σ_r R_r X_r` with integers
/// `X_r = Σ_{q ≡ r} n_q 2^{h − a}` (`a` the lowest occupied `h`), updated exactly; the
/// class at rest adds `n_0 W_{Q_MIN}`. `S` is the rounding of these: the same for the
/// same particles however they came there (a restored checkpoint goes on bit for bit).
/// A size whose speeds span so many octaves that an `X_r` does not fit in 128 bits
/// (about 2^87 with 2^40 particles) falls back to summing its classes in order at every
/// move; one whose moving classes would span more than [`MAX_CLASSES`] is refused.
#[derive(Clone, Debug)]
pub(super) struct Species {
    /// The class of `classes[1]`.
    pub(super) base: i32,
    /// The class at rest, then the moving classes (empty until the first `reserve`).
    pub(super) classes: Vec<Class>,
    /// Particles.
    pub(super) n: usize,
    /// `Σ_q n_q W_q` (0 when empty).
    pub(super) s: f64,
    /// The largest bound of an occupied class (0 when empty).
    pub(super) top: f64,
    /// The occupied moving classes are within `lo..end` (indices into `classes`, the
    /// first and one past the last occupied; `lo == end` when none is).
    pub(super) lo: usize,
    pub(super) end: usize,
    /// Whether `x` holds the sums (else `s` is summed class by class).
    pub(super) exact: bool,
    /// The `h` of the lowest occupied moving class, and `X_r`.
    pub(super) anchor: i32,
    pub(super) x: [u128; 4],
}

impl Default for Species {
    /// No particles (the fields as `resum` leaves them).
    fn default() -> Self {
        Species {
            base: 0,
            classes: Vec::new(),
            n: 0,
            s: 0.0,
            top: 0.0,
            lo: 1,
            end: 1,
            exact: true,
            anchor: 0,
            x: [0; 4],
        }
    }
}

/// A little above 1: class bounds are rounded up by it.
pub(super) const MARGIN: f64 = 1.0 + 1e-12;

/// `2^{r/4}` for r = 0..3 (each within half an ulp; [`MARGIN`] covers it).
pub(super) const ROOTS: [f64; 4] = [
    1.0,
    1.189_207_115_002_721,
    core::f64::consts::SQRT_2,
    1.681_792_830_507_429,
];

/// The mantissa bits of √2.
pub(super) const SQRT2_MANTISSA: u64 = core::f64::consts::SQRT_2.to_bits() & ((1 << 52) - 1);

/// The class at rest: `|v|² < 2^{−1022}` (zero or subnormal), bound `2^{−511}`.
pub(super) const Q_MIN: i32 = -2045;

/// The most moving classes one size may span: speeds within a factor `2^{128}`.
pub(super) const MAX_CLASSES: usize = 512;

/// The speed class of `v`: `q` with `|v|² ∈ [2^{q/2}, 2^{(q+1)/2})`, or [`Q_MIN`] for
/// `|v|² < 2^{−1022}`. `|v|²` must be finite.
#[inline]
pub(super) fn class_of(v: &[f64; 3]) -> i32 {
    let s = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    debug_assert!(s.is_finite(), "a speed without a class");
    let bits = s.to_bits();
    let field = ((bits >> 52) & 0x7ff) as i32;
    if field == 0 || !s.is_finite() {
        Q_MIN
    } else {
        2 * (field - 1023) + i32::from(bits & ((1 << 52) - 1) >= SQRT2_MANTISSA)
    }
}

/// A velocity whose components and `|v|²` are finite (`|v|² = inf` has no class).
pub(super) fn finite_speed(v: &[f64; 3]) -> bool {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).is_finite()
}

/// `(h, r)` with `q + 1 = 4h + r`, `0 ≤ r < 4`.
#[inline]
pub(super) fn class_parts(q: i32) -> (i32, usize) {
    ((q + 1).div_euclid(4), (q + 1).rem_euclid(4) as usize)
}

/// The bound of class q: `2^{(q+1)/4}`, a little above.
pub(super) fn class_bound(q: i32) -> f64 {
    let (h, r) = class_parts(q);
    libm::scalbn(ROOTS[r] * MARGIN, h)
}

impl Species {
    /// The index of class `q` in `classes`, if within the range.
    #[inline]
    pub(super) fn index(&self, q: i32) -> Option<usize> {
        if self.classes.is_empty() {
            return None;
        }
        if q == Q_MIN {
            return Some(0);
        }
        usize::try_from(i64::from(q) - i64::from(self.base) + 1)
            .ok()
            .filter(|&d| d >= 1 && d < self.classes.len())
    }

    /// The class at index `d`.
    #[inline]
    pub(super) fn q(&self, d: usize) -> i32 {
        if d == 0 {
            Q_MIN
        } else {
            self.base + (d - 1) as i32
        }
    }

    /// `2^a Σ_r R_r X_r`, rounded, plus the class at rest.
    pub(super) fn exact_sum(&self) -> f64 {
        let mut t = 0.0;
        for (r, &x) in self.x.iter().enumerate() {
            // (the same rounding as `x as f64`, in hardware when it fits 64 bits)
            let x = u64::try_from(x).map_or(x as f64, |x| x as f64);
            t += ROOTS[r] * MARGIN * x;
        }
        libm::scalbn(t, self.anchor) + self.rest()
    }

    /// `S` after a move that kept `x`, `lo`, `end` and `top` right.
    #[inline]
    pub(super) fn settle(&mut self) {
        if self.exact {
            self.s = self.exact_sum();
        } else {
            self.resum();
        }
    }

    /// The last occupied class (the class at rest when no moving one is).
    #[inline]
    pub(super) fn last_class(&self) -> usize {
        if self.lo < self.end { self.end - 1 } else { 0 }
    }

    /// `n_0 W_{Q_MIN}`.
    #[inline]
    pub(super) fn rest(&self) -> f64 {
        self.classes.first().map_or(0.0, |c| c.v.len() as f64 * c.w)
    }

    /// Recomputes everything from the classes (a function of their contents only).
    pub(super) fn resum(&mut self) {
        let moving = || {
            self.classes
                .iter()
                .enumerate()
                .skip(1)
                .filter(|(_, c)| !c.v.is_empty())
        };
        let still = self.classes.first().map_or(0, |c| c.v.len());
        let (lo, end) = match (moving().next(), moving().next_back()) {
            (Some((lo, _)), Some((hi, _))) => (lo, hi + 1),
            _ => (1, 1),
        };
        let anchor = if lo < end {
            class_parts(self.q(lo)).0
        } else {
            0
        };
        let (mut n, mut x, mut exact) = (still, [0u128; 4], true);
        for (d, c) in moving() {
            n += c.v.len();
            let (h, r) = class_parts(self.q(d));
            let add = 1u128
                .checked_shl((h - anchor) as u32)
                .and_then(|p| p.checked_mul(c.v.len() as u128))
                .and_then(|p| p.checked_add(x[r]));
            match add {
                Some(v) => x[r] = v,
                None => exact = false,
            }
        }
        (self.n, self.lo, self.end) = (n, lo, end);
        (self.exact, self.anchor, self.x) = (exact, anchor, x);
        self.top = if n > 0 {
            self.classes[self.last_class()].w
        } else {
            0.0
        };
        self.s = if n == 0 {
            0.0
        } else if exact {
            self.exact_sum()
        } else {
            let moving: f64 = self.classes[lo..end]
                .iter()
                .map(|c| c.v.len() as f64 * c.w)
                .sum();
            moving + self.rest()
        };
    }

    /// Reserves room for one more particle in each class of `qs` (room for two where a
    /// class is listed once: both particles of a bounce may go to one class), the range
    /// of moving classes rebuilt around them if needed. Errors: the memory, or moving
    /// classes spanning more than [`MAX_CLASSES`].
    pub(super) fn reserve(&mut self, qs: &[i32]) -> Result<()> {
        if self.classes.is_empty() {
            try_reserve(&mut self.classes, 1)?;
            self.classes.push(Class::new(Q_MIN));
            (self.lo, self.end) = (1, 1);
        }
        // (checked whatever the range: the refusal depends on the particles alone, so
        // a state that was reached also loads, in any order)
        let (first, last) = self.moving_span(qs);
        if first <= last && (last - first) as usize >= MAX_CLASSES {
            return Err(Error::Capacity {
                name: "speed classes of one size (speeds within a factor 2^128)",
                capacity: MAX_CLASSES,
            });
        }
        if qs.iter().any(|&q| self.index(q).is_none()) {
            self.make_room(qs)?;
        }
        for &q in qs {
            if let Some(d) = self.index(q) {
                try_reserve(&mut self.classes[d].v, 2)?;
            }
        }
        Ok(())
    }

    /// Rebuilds the moving classes' range to span the occupied ones and `qs` (a few
    /// more below: speeds of a cooling gas keep falling); the empty classes outside
    /// are dropped. Nothing a sum depends on changes.
    #[cold]
    pub(super) fn make_room(&mut self, qs: &[i32]) -> Result<()> {
        let (first, last) = self.moving_span(qs);
        if first > last {
            return Ok(());
        }
        let from = first.saturating_sub(4).max(Q_MIN + 1);
        let mut classes = Vec::new();
        try_reserve(&mut classes, (last - from) as usize + 2)?;
        classes.push(core::mem::replace(&mut self.classes[0], Class::new(Q_MIN)));
        for q in from..=last {
            let kept = self.index(q).filter(|&d| d > 0);
            classes.push(match kept {
                Some(d) => core::mem::replace(&mut self.classes[d], Class::new(q)),
                None => Class::new(q),
            });
        }
        (self.classes, self.base) = (classes, from);
        // (the same contents: lo and end shift, the sums come out the same)
        self.resum();
        Ok(())
    }

    /// The lowest and highest of the occupied moving classes and the moving classes of
    /// `qs` (`first > last` when there are none).
    pub(super) fn moving_span(&self, qs: &[i32]) -> (i32, i32) {
        let (mut first, mut last) = if self.lo < self.end {
            (self.q(self.lo), self.q(self.end - 1))
        } else {
            (i32::MAX, i32::MIN)
        };
        for &q in qs.iter().filter(|&&q| q != Q_MIN) {
            (first, last) = (first.min(q), last.max(q));
        }
        (first, last)
    }

    /// Adds a particle (room reserved by `reserve`).
    pub(super) fn insert(&mut self, v: [f64; 3]) {
        let q = class_of(&v);
        let d = self.index(q).expect("class reserved");
        self.classes[d].v.push(v);
        self.n += 1;
        if d == 0 {
            // (at rest: the moving classes' sums stand)
            if self.lo == self.end {
                self.top = self.classes[0].w;
            }
            self.settle();
            return;
        }
        let (h, r) = class_parts(q);
        if self.lo == self.end {
            // the first moving particle
            (self.lo, self.end, self.top) = (d, d + 1, self.classes[d].w);
            (self.exact, self.anchor, self.x) = (true, h, [0; 4]);
            self.x[r] = 1;
            self.s = self.exact_sum();
            return;
        }
        self.lo = self.lo.min(d);
        if d >= self.end {
            (self.end, self.top) = (d + 1, self.classes[d].w);
        }
        if self.exact && !self.add_exact(h, r) {
            // (past 128 bits: the fallback)
            self.exact = false;
        }
        self.settle();
    }

    /// Adds `2^h` to `X_r` (moving the anchor down if needed); false on overflow.
    pub(super) fn add_exact(&mut self, h: i32, r: usize) -> bool {
        if h < self.anchor {
            let shift = (self.anchor - h) as u32;
            if self
                .x
                .iter()
                .any(|&x| x != 0 && (shift >= 128 || x.leading_zeros() < shift))
            {
                return false;
            }
            for x in &mut self.x {
                *x = x.checked_shl(shift).unwrap_or(0);
            }
            self.anchor = h;
        }
        match 1u128
            .checked_shl((h - self.anchor) as u32)
            .and_then(|p| p.checked_add(self.x[r]))
        {
            Some(v) => {
                self.x[r] = v;
                true
            }
            None => false,
        }
    }

    /// Removes the particle at `idx` of class index `d` (swapping the last in).
    pub(super) fn remove(&mut self, d: usize, idx: usize) {
        self.classes[d].v.swap_remove(idx);
        self.n -= 1;
        if d == 0 {
            if self.n == 0 {
                self.resum();
            } else {
                self.settle();
            }
            return;
        }
        if self.exact {
            let (h, r) = class_parts(self.q(d));
            self.x[r] -= 1u128 << (h - self.anchor);
        }
        if self.classes[d].v.is_empty() {
            if d + 1 == self.end {
                self.end = (self.lo..d)
                    .rev()
                    .find(|&e| !self.classes[e].v.is_empty())
                    .map_or(self.lo, |e| e + 1);
            }
            if d == self.lo {
                self.lo = (d + 1..self.end)
                    .find(|&e| !self.classes[e].v.is_empty())
                    .unwrap_or(self.end);
            }
            if self.lo == self.end {
                // no moving particle left
                self.resum();
                return;
            }
            self.top = self.classes[self.end - 1].w;
            let h = class_parts(self.q(self.lo)).0;
            if self.exact && h > self.anchor {
                // (exact: nothing is left below the new lowest class)
                let shift = (h - self.anchor) as u32;
                for x in &mut self.x {
                    *x = x.checked_shr(shift).unwrap_or(0);
                }
                self.anchor = h;
            }
        }
        self.settle();
    }

    /// The particle at `global` in the order of the classes (those at rest first).
    #[inline]
    pub(super) fn locate(&self, mut global: usize) -> (usize, usize) {
        let still = self.classes[0].v.len();
        if global < still {
            return (0, global);
        }
        global -= still;
        for d in self.lo..self.end {
            let len = self.classes[d].v.len();
            if global < len {
                return (d, global);
            }
            global -= len;
        }
        // (past the end: the last particle)
        let last = self.last_class();
        (last, self.classes[last].v.len().saturating_sub(1))
    }

    /// The global index of particle `(d, idx)`.
    pub(super) fn global(&self, d: usize, idx: usize) -> usize {
        if d == 0 {
            return idx;
        }
        self.classes[0].v.len()
            + self.classes[self.lo..d]
                .iter()
                .map(|c| c.v.len())
                .sum::<usize>()
            + idx
    }

    /// A particle drawn ∝ its class bound, from `t ∈ [0, S)`.
    #[inline]
    pub(super) fn weighted(&self, mut t: f64) -> (usize, usize) {
        let still = &self.classes[0];
        let weight = still.v.len() as f64 * still.w;
        if t < weight {
            let idx = (t / still.w) as usize;
            return (0, idx.min(still.v.len() - 1));
        }
        t -= weight;
        for d in self.lo..self.end {
            let c = &self.classes[d];
            let weight = c.v.len() as f64 * c.w;
            if t < weight {
                let idx = (t / c.w) as usize;
                return (d, idx.min(c.v.len() - 1));
            }
            t -= weight;
        }
        // (rounding past the last class)
        let last = self.last_class();
        (last, self.classes[last].v.len().saturating_sub(1))
    }
}
