//! Walker alias tables (Walker 1977; Vose 1991): O(1) weighted sampling from one
//! random word, over integer weights, built exactly.

use alloc::vec::Vec;

/// A Walker alias table: O(1) sampling of an item with probability `w_i / Σ w` from
/// one random word. Rebuilt in O(items) (the bucketed low-rank layout rebuilds
/// rarely). Items of weight zero
/// are left out of the table, and each column names its items by their `u32` ids.
///
/// The table is built exactly in integers (Vose's method on `w_i · n` against the
/// column capacity `T = Σ w`); only the keep-thresholds are rounded, to 63-bit
/// fractions, so each item's probability is within `2^-52` (relative) of `w_i / T`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Alias {
    /// Columns.
    pub(crate) n: usize,
    /// Column c: `(keep threshold as a 63-bit fraction, own id, alias id)`; a column
    /// whose own weight fills it has threshold `2^63`.
    pub(crate) entries: Vec<(u64, u32, u32)>,
}

/// Build scratch shared by the tables (kept to avoid allocating per rebuild).
#[derive(Clone, Debug, Default)]
pub(crate) struct AliasScratch {
    /// Items: `(weight, id)`; zero weights are skipped by the build.
    pub(crate) weights: Vec<(u64, u32)>,
    scaled: Vec<u128>,
    /// Small columns from the front, large ones from the back.
    work: Vec<usize>,
}

impl Alias {
    /// Rebuilds the table from `scratch.weights` (an all-zero row gives an empty table,
    /// which must not be sampled). Returns false, leaving the table empty, when the
    /// total reaches 2^63 (checked in release builds: the thresholds would be wrong).
    #[must_use]
    pub(crate) fn rebuild(&mut self, scratch: &mut AliasScratch) -> bool {
        scratch.weights.retain(|&(w, _)| w > 0);
        self.entries.clear();
        self.n = 0;
        let total = scratch
            .weights
            .iter()
            .try_fold(0u64, |acc, &(w, _)| acc.checked_add(w));
        let Some(total) = total.filter(|&t| t < 1 << 63) else {
            return false;
        };
        let n = scratch.weights.len();
        self.n = n;
        if n == 0 {
            // an empty row: the table is never sampled (its component has no pairs)
            return true;
        }
        self.entries
            .extend(scratch.weights.iter().map(|&(_, id)| (1 << 63, id, id)));
        scratch.scaled.resize(n, 0);
        scratch.work.resize(n, 0);
        for (s, &(w, _)) in scratch.scaled.iter_mut().zip(&scratch.weights) {
            *s = u128::from(w) * n as u128;
        }
        let cap = u128::from(total);
        let to_frac = 9_223_372_036_854_775_808.0 / total as f64;
        let (scaled, work, row) = (&mut scratch.scaled, &mut scratch.work, &mut self.entries);
        let (mut ns, mut nl) = (0, n);
        for (i, &s) in scaled.iter().enumerate() {
            if s < cap {
                work[ns] = i;
                ns += 1;
            } else {
                nl -= 1;
                work[nl] = i;
            }
        }
        while ns > 0 && nl < n {
            ns -= 1;
            let l = work[ns];
            let g = work[nl];
            let sl = scaled[l];
            // sl < cap < 2^63: exact as i64, and the fraction stays below 2^63
            row[l].0 = (sl as i64 as f64 * to_frac) as i64 as u64;
            row[l].2 = row[g].1;
            scaled[g] -= cap - sl;
            if scaled[g] < cap {
                // g turns small: it leaves the large stack for the small one
                nl += 1;
                work[ns] = g;
                ns += 1;
            }
        }
        // what is left is full (exactly so in exact arithmetic: the capacities add up
        // to the weights): its threshold stays 2^63
        true
    }

    /// An item's id with probability `weight / total`, from one random word.
    #[inline(always)]
    pub(crate) fn sample(&self, word: u64) -> u32 {
        let m = u128::from(word) * self.n as u128;
        let c = (m >> 64) as usize;
        let (keep, own, alias) = self.entries[c];
        // the keep/alias choice is a coin flip to the branch predictor
        core::hint::select_unpredictable((m as u64 >> 1) < keep, own, alias)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;

    /// The probabilities an alias table implies (column c uniform, kept with
    /// `keep / 2^63`) equal `w_i / Σ w` to rounding, zero weights included; and
    /// `sample` follows the table.
    #[test]
    fn alias_tables_reproduce_their_weights() {
        let mut rng = rand_pcg::Pcg64Mcg::new(9);
        let cases: [alloc::vec::Vec<u64>; 4] = [
            alloc::vec![5],
            alloc::vec![0, 3, 0, 1, 0],
            alloc::vec![1 << 62, 1, 0, 1, 2],
            // totals must stay below 2^63: 700 weights below 2^51
            (0..700).map(|i| rng.next_u64() >> (13 + i % 40)).collect(),
        ];
        let mut sc = AliasScratch::default();
        for w in cases {
            let total: u64 = w.iter().sum();
            // ids: the item's index, spread out (as the joint table's are)
            let id = |i: usize| (i * 37 + 5) as u32;
            sc.weights = w.iter().enumerate().map(|(i, &x)| (x, id(i))).collect();
            let mut t = Alias::default();
            assert!(t.rebuild(&mut sc));
            let n = t.n;
            assert_eq!(
                n,
                w.iter().filter(|&&x| x > 0).count(),
                "zero items dropped"
            );
            let mut p = alloc::vec![0.0f64; w.len()];
            let index = |id: u32| (id as usize - 5) / 37;
            for &(keep, own, alias) in &t.entries {
                let k = keep as f64 / 9_223_372_036_854_775_808.0;
                p[index(own)] += k / n as f64;
                p[index(alias)] += (1.0 - k) / n as f64;
            }
            for i in 0..w.len() {
                let want = w[i] as f64 / total as f64;
                assert!(
                    (p[i] - want).abs() <= 1e-12 * want + 1e-18,
                    "item {i}: {} vs {want}",
                    p[i]
                );
                if w[i] == 0 {
                    assert_eq!(p[i], 0.0, "zero-weight item {i}");
                }
            }
            // sample: the column is the word's top part; low bits decide keep/alias
            for _ in 0..1000 {
                let word = rng.next_u64();
                let c = ((u128::from(word) * n as u128) >> 64) as usize;
                let (keep, own, alias) = t.entries[c];
                let low = (u128::from(word) * n as u128) as u64 >> 1;
                let want = if low < keep { own } else { alias };
                assert_eq!(t.sample(word), want);
                assert!(w[index(want)] > 0);
            }
        }
    }
}
