//! Proposal times of an event-driven scheme, drawn in batches instead of one exponential
//! per proposal.
//!
//! Between two changes of its rate, the stream of proposals of a low-rank scheme is a
//! Poisson process of constant rate `1/mean_dt`, and its arrival times are independent
//! of what the proposals do. A [`Batch`] therefore draws only the time of the `c`-th
//! arrival, `T_c = now + Γ(c)·mean_dt`, and lets the scheme make up to `c` proposals
//! without looking at a clock. When the rate changes after the `k`-th of them, the time
//! of that arrival follows from the order statistics of a Poisson process: given `T_c`,
//! the first `c − 1` arrivals are uniform on `(now, T_c)`, so the `k`-th is
//! `now + (T_c − now)·B(k, c − k)` with `B` a beta variate. The arrivals after it are
//! discarded and a new batch starts at the new rate (the strong Markov property of the
//! Poisson process makes this exact).
//!
//! Near the target time `t` a batch that overshoots (`T_c > t`, made rare by choosing
//! `c` six standard deviations below the expected number of arrivals) is cut back
//! exactly: the number of arrivals before `t` is binomial `(c − 1, (t − now)/(T_c −
//! now))` and, given it is `m`, those arrivals are uniform on `(now, t)`. With fewer than
//! [`MIN_EXPECTED`] arrivals left, [`Batch::plan`] declines and the caller draws one
//! exponential per proposal.
//!
//! Cost: one gamma variate per batch and a beta variate (two gammas) per rate change,
//! against one exponential per proposal — about 10 % of a linear-kernel proposal.

use rand_core::Rng;

use crate::random::{beta, binomial_by_count, gamma};

/// Below this many expected arrivals before the target, [`Batch::plan`] declines.
pub(crate) const MIN_EXPECTED: f64 = 256.0;
/// Batches are planned this many standard deviations short of the expected arrivals,
/// so that one overshoots the target (and is cut back) with probability ~1e-9.
const SIGMAS: f64 = 6.0;
/// Largest batch (arrivals past a rate change are drawn for nothing, but cost nothing).
const MAX_BATCH: f64 = 1048576.0;

/// A batch of arrivals of a Poisson process (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Batch {
    /// Time the batch starts from.
    pub start: f64,
    /// `T_c`, or the target time for the last batch.
    pub end: f64,
    /// Arrivals in the batch.
    pub len: u64,
    /// Arrivals uniform on `(start, end)`: `len − 1` (the last one is at `end`), or
    /// `len` for the last batch (no arrival at `end`).
    uniform: u64,
    /// The batch reaches the target time: after `len` arrivals the clock stands at `t`.
    pub last: bool,
}

impl Batch {
    /// Plans a batch from time `now` towards `t`, proposals `mean_dt` apart on average;
    /// `None` when fewer than [`MIN_EXPECTED`] arrivals are expected before `t`.
    #[inline]
    pub(crate) fn plan<R: Rng + ?Sized>(
        now: f64,
        mean_dt: f64,
        t: f64,
        rng: &mut R,
    ) -> Option<Batch> {
        Self::plan_with_margin(now, mean_dt, t, SIGMAS, rng)
    }

    /// [`Batch::plan`] with `c = μ − margin·√μ` for `μ` expected arrivals (exact for
    /// any margin; the margin only sets how often a batch is cut back).
    fn plan_with_margin<R: Rng + ?Sized>(
        now: f64,
        mean_dt: f64,
        t: f64,
        margin: f64,
        rng: &mut R,
    ) -> Option<Batch> {
        let mu = (t - now) / mean_dt;
        if mu.is_nan() || mu < MIN_EXPECTED {
            return None;
        }
        let c = libm::floor((mu - margin * libm::sqrt(mu)).min(MAX_BATCH)).max(1.0);
        let end = now + gamma(c, rng) * mean_dt;
        let c = c as u64;
        Some(if end <= t {
            Batch {
                start: now,
                end,
                len: c,
                uniform: c - 1,
                last: false,
            }
        } else {
            let m = binomial_by_count(c - 1, (t - now) / (end - now), rng);
            Batch {
                start: now,
                end: t,
                len: m,
                uniform: m,
                last: true,
            }
        })
    }

    /// The time of arrival `k` (`1 ≤ k ≤ len`); `start` for `k = 0`.
    pub(crate) fn time_of<R: Rng + ?Sized>(&self, k: u64, rng: &mut R) -> f64 {
        if k == 0 {
            self.start
        } else if k > self.uniform {
            self.end
        } else {
            let b = beta(k as f64, (self.uniform - k + 1) as f64, rng);
            self.start + (self.end - self.start) * b
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{mean_var, open_unit};
    use alloc::vec::Vec;
    use rand_core::SeedableRng;

    /// Arrivals of a unit-rate Poisson process before t = 2000, stepped by batches
    /// with the rate "changing" (a restart) after a geometric number of arrivals (mean
    /// 300) and one exponential at a time at the end, as the schemes do. `misplace`
    /// restarts at the batch's end instead of the arrival's time (a plausible bug).
    /// Returns the counts per replica and the numbers of restarts, cut-back batches
    /// and restarts inside cut-back batches.
    fn arrivals(margin: f64, seed: u64, reps: usize, misplace: bool) -> (Vec<f64>, [u64; 3]) {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let t = 2000.0;
        let mut counts = Vec::with_capacity(reps);
        let mut seen = [0u64; 3];
        for _ in 0..reps {
            let (mut now, mut n) = (0.0, 0u64);
            loop {
                let Some(b) = Batch::plan_with_margin(now, 1.0, t, margin, &mut rng) else {
                    loop {
                        now += super::super::exp1(&mut rng);
                        if now > t {
                            break;
                        }
                        n += 1;
                    }
                    break;
                };
                seen[1] += u64::from(b.last);
                let mut k = 0;
                let mut restarted = false;
                while k < b.len {
                    k += 1;
                    n += 1;
                    if open_unit(&mut rng) < 1.0 / 300.0 {
                        now = if misplace {
                            b.end
                        } else {
                            b.time_of(k, &mut rng)
                        };
                        assert!(now >= b.start && now <= b.end);
                        restarted = true;
                        seen[0] += 1;
                        seen[2] += u64::from(b.last);
                        break;
                    }
                }
                if !restarted {
                    now = b.end;
                    if b.last {
                        break;
                    }
                }
            }
            counts.push(n as f64);
        }
        (counts, seen)
    }

    /// The arrivals before t must be Poisson(t) — a law that depends on every restart
    /// time and every cut-back being right. Run with the schemes' margin (cut-backs
    /// rare) and with a negative one (most batches overshoot t and are cut back).
    fn poisson_through_restarts(margin: f64, seed: u64) {
        let (t, reps) = (2000.0, 4000);
        let (counts, [restarts, cuts, cut_restarts]) = arrivals(margin, seed, reps, false);
        assert!(restarts > 5 * reps as u64, "restarts exercised: {restarts}");
        if margin < 0.0 {
            assert!(
                cuts > reps as u64 && cut_restarts > reps as u64,
                "cut-backs exercised: {cuts}, {cut_restarts}"
            );
        }
        let (m, v) = mean_var(&counts);
        // Poisson(t): mean = variance = t; se of the sample variance ≈ t √(2/reps)
        let se_m = libm::sqrt(t / reps as f64);
        assert!(
            (m - t).abs() < 5.0 * se_m,
            "margin {margin}: mean count {m} vs {t}"
        );
        let se_v = t * libm::sqrt(2.0 / reps as f64);
        assert!(
            (v - t).abs() < 5.0 * se_v,
            "margin {margin}: count variance {v} vs {t}"
        );
    }

    #[test]
    fn batched_arrivals_are_poisson() {
        poisson_through_restarts(SIGMAS, 11);
    }

    #[test]
    fn cut_back_batches_are_exact() {
        poisson_through_restarts(-2.0, 12);
    }

    /// The restart times' law, directly: in a batch ending with arrival c at `end`,
    /// the gap `end − time_of(c − 1)` has mean `(end − start)/c`; in a cut-back batch
    /// of m arrivals, `t − time_of(m)` has mean `(t − start)/(m + 1)`. A beta shape off
    /// by one doubles the first (and halves or shifts the second) — tens of SE here.
    #[test]
    fn last_arrival_gaps_have_their_mean() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(14);
        let reps = 20_000;
        for margin in [SIGMAS, -2.0] {
            let (mut sum, mut n) = (0.0, 0);
            while n < reps {
                let b = Batch::plan_with_margin(0.0, 1.0, 500.0, margin, &mut rng).unwrap();
                if b.len < 2 {
                    continue;
                }
                // gap scaled by its expected value: mean 1, sd ~1
                let x = if b.last {
                    (b.end - b.time_of(b.len, &mut rng)) * (b.len + 1) as f64 / (b.end - b.start)
                } else {
                    (b.end - b.time_of(b.len - 1, &mut rng)) * b.len as f64 / (b.end - b.start)
                };
                sum += x;
                n += 1;
            }
            let mean = sum / n as f64;
            assert!(
                (mean - 1.0).abs() < 5.0 / libm::sqrt(n as f64),
                "margin {margin}: scaled last gap {mean}"
            );
        }
    }

    /// The Poisson check has power: restarting at the batch's end instead of the
    /// arrival's time moves the mean count by far more than 5 SE.
    #[test]
    fn the_poisson_check_catches_misplaced_restarts() {
        let (t, reps) = (2000.0, 2000);
        let (counts, _) = arrivals(SIGMAS, 13, reps, true);
        let (m, _) = mean_var(&counts);
        assert!(
            (m - t).abs() > 5.0 * libm::sqrt(t / reps as f64),
            "mean {m}"
        );
    }
}
