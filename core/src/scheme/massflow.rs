//! Time-driven mass-flow scheme for coagulation–fragmentation, with quasi-random (QMC),
//! pseudo-random (MC) and randomised quasi-random (RQMC) points (Lécot, L'Ecuyer,
//! El Haddad & Tarhini 2019, §2; Lécot & Wagner 2004 for pure coagulation).
//!
//! The mass density `f = x c / M1` is approximated by N = 2^m particles of equal mass
//! `M1/N`, with the mass-flow kernels `K̃(x, y) = M1 K(x, y) / y` and `Ḟ(x)` (see
//! [`crate::kernel::FragmentationKernel`]). Each step of length Δt:
//! 1. the particles are sorted by size (this ordering is what makes QMC converge);
//! 2. the N points `u_p`, `nN ≤ p < (n+1)N`, of a 3-D (t,3)-sequence in base 2 whose
//!    first two coordinates form a (0,m,2)-net in every block select, for every particle
//!    `k = ⌊N u_1⌋` exactly once, a partner `l = ⌊N u_2⌋`; with `p_c = Δt K̃(x_k, x_l)`
//!    and `p_f = Δt Ḟ(x_k)`: `x_k ← x_k + x_l` if `u_3 < p_c`,
//!    `x_k ← F̂⁻¹_{x_k}((1 − u_3)/p_f)` if `u_3 ≥ 1 − p_f`, unchanged otherwise. The
//!    right-hand sides use the old sizes (double buffer).
//!
//! Moments are estimated by `M_m ≈ (M1/N) Σ_k x_k^{m−1}`.
//!
//! **Stability.** The scheme needs `Δt (sup K̃ + sup Ḟ) < 1`. Lécot's own test violates
//! it (`K̃ = 1/y` is unbounded); a step where `p_c + p_f > 1` gives coagulation priority
//! (fragmentation keeps probability `1 − p_c`), and every such case is counted in
//! [`StepReport::clipped`] — never silently.
//!
//! **Points.** [`PointSource`]: Niederreiter's (1,3)-sequence (default) or Sobol', as
//! is or randomised (digital shift, Matoušek or Owen scrambling, all of which keep the
//! net property, so every particle is still visited once per step); or pseudo-random
//! points (MC: every particle once, partner uniform, `u_3` uniform).
//!
//! **RQMC needs a new randomisation every step.** For a fixed randomisation the point
//! of block n that selects particle k (`k = ⌊N u_1⌋`) is point `nN + i_k` with `i_k` the
//! same in every block, so the `u_3` that particle rank k sees over the steps is itself a
//! low-discrepancy sequence (the (1,3) projection of a (t,3)-sequence). The smallest
//! particle keeps rank 0 until it coagulates, so it coagulates within a few 1/p_c steps with
//! certainty instead of surviving with probability `e^{−∫M0}`: the smallest particles,
//! which carry the largest weight `1/x` in M0, die too early and M0 is biased low by
//! O(N^{−1/2}) (constant kernel, Gamma(2) start, t = 10: smallest-rank survival 0 vs
//! 1/36), the same for every one of the three randomisations and independent of Δt.
//! [`PointSource::randomized_niederreiter`] and [`PointSource::randomized_sobol`]
//! therefore draw an independent randomisation for every block (array-RQMC; the
//! random parameters of block n come from a key and n, so runs are reproducible and
//! checkpoints resume). The variants with one randomisation for the whole run
//! ([`PointSource::ScrambledNiederreiter`], [`PointSource::ScrambledSobol`]) are kept
//! for comparison; their replicas are not unbiased.
//!
//! **Sorting.** After a step only the particles that coagulated or broke up have new
//! sizes; the others are still in order. The adaptive re-sort moves the unchanged ones
//! to the front (in order), sorts the few changed ones and merges from the back:
//! O(N + c log c) for c changes, instead of O(N log N) (selectable, see [`Sorting`]).
//!
//! # Example
//! ```
//! use coagula_core::kernel::{BinaryUniform, Coagulation};
//! use coagula_core::scheme::Scheme;
//! use coagula_core::scheme::massflow::{MassFlow, PointSource};
//! let k = Coagulation::constant(1.0).unwrap();
//! let f = BinaryUniform::new(1.0).unwrap();
//! let n = 1 << 12;
//! let mut sim = MassFlow::new(k, f, &vec![1.0; n], 1.0, 0.01, PointSource::niederreiter()).unwrap();
//! let mut rng = rand_pcg::Pcg64Mcg::new(1); // unused by QMC, required by the interface
//! sim.advance_to(1.0, &mut rng).unwrap();
//! let exact = 3.0 - 2.0 * (-1.0f64 / 3.0).exp(); // M2(1)
//! assert!((sim.moment(2.0) - exact).abs() < 0.01);
//! ```

use super::{Budget, Scheme, StepReport, check_target};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::process::{Books, Processes};
use crate::qmc::Word;
use crate::tree::{Weight, unit_f64};
use alloc::vec::Vec;
use rand_core::Rng;

pub use crate::qmc::points::PointSource;

pub use super::facade::Sorting;

/// `f64`s of workspace a mass-flow scheme of `n` particles steps in (`6n`: the sizes,
/// the next sizes, one block of 3-D points and the re-sort's scratch); `None` if it
/// overflows. See [`MassFlow::new_in`].
pub const fn workspace_len(n: usize) -> Option<usize> {
    n.checked_mul(6)
}

/// Validates a mass-flow set-up (what [`MassFlow::new`] and [`MassFlow::new_in`] refuse:
/// N not a power of two ≥ 2, a size, the mass or Δt not finite and positive) without
/// touching any workspace, so a caller can check before handing memory over.
pub fn check_setup(initial: &[f64], mass: f64, dt: f64) -> Result<()> {
    let n = initial.len();
    if n < 2 || !n.is_power_of_two() {
        return Err(Error::NotPowerOfTwo {
            name: "number of particles",
            value: n as u64,
        });
    }
    crate::error::positive("mass", mass)?;
    crate::error::positive("dt", dt)?;
    for &v in initial {
        crate::error::positive("initial size", v)?;
    }
    Ok(())
}

/// The workspace split into (sizes, next sizes, points, scratch); `cur` says which half
/// of the first `2n` holds the sizes.
#[inline]
fn split(ws: &mut [f64], n: usize, cur: usize) -> (&mut [f64], &mut [f64], &mut [f64], &mut [f64]) {
    let (ab, rest) = ws.split_at_mut(2 * n);
    let (pts, rest) = rest.split_at_mut(3 * n);
    let scratch = &mut rest[..n];
    let (a, b) = ab.split_at_mut(n);
    if cur == 0 {
        (a, b, pts, scratch)
    } else {
        (b, a, pts, scratch)
    }
}

/// The time-driven mass-flow scheme. See the module docs.
///
/// `B` is the workspace: an owned `Vec<f64>` ([`MassFlow::new`]) or storage the caller
/// owns, e.g. `&mut [f64]` ([`MassFlow::new_in`]); it is sized at construction and no
/// step allocates.
pub struct MassFlow<K, F, B = Vec<f64>> {
    kernel: K,
    frag: F,
    points: PointSource,
    sorting: Sorting,
    m: u32,
    mass: f64,
    dt: f64,
    time: f64,
    steps: u64,
    /// Particles N.
    n: usize,
    /// Which half of the double buffer holds the sizes (0 or 1).
    cur: usize,
    /// `[sizes A | sizes B | points (3N) | scratch (N)]`: the sizes, sorted ascending
    /// between steps, in half `cur`; the next sizes in the other.
    ws: B,
    totals: StepReport,
}

impl<K, F, B> core::fmt::Debug for MassFlow<K, F, B> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("MassFlow")
            .field("particles", &self.n)
            .field("dt", &self.dt)
            .field("time", &self.time)
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel> MassFlow<K, F> {
    /// A scheme over the particles `initial` (N sizes, N a power of two ≥ 2), carrying
    /// total mass `mass` (M1), with time step `dt`, in a workspace it allocates once
    /// (`6N` doubles; see [`new_in`](MassFlow::new_in) for caller-owned storage).
    ///
    /// Errors: N not a power of two, a size not finite and positive, mass or dt not
    /// finite and positive, the workspace cannot be allocated.
    pub fn new(
        kernel: K,
        frag: F,
        initial: &[f64],
        mass: f64,
        dt: f64,
        points: PointSource,
    ) -> Result<Self> {
        let len = workspace_len(initial.len()).ok_or(Error::Overflow {
            name: "mass-flow workspace",
        })?;
        let mut ws = Vec::new();
        crate::scheme::population::try_resize(&mut ws, len, 0.0)?;
        MassFlow::new_in(kernel, frag, initial, mass, dt, points, ws)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    MassFlow<K, F, B>
{
    /// [`new`](MassFlow::new) in storage the caller owns: `workspace` holds at least
    /// [`workspace_len`]`(N)` doubles (its contents are overwritten; any excess is
    /// unused). Construction copies the sizes in, and no step allocates.
    ///
    /// Errors: as for `new`, and a workspace that is too small
    /// ([`Error::BufferLength`]).
    ///
    /// ```
    /// use coagula_core::kernel::{Coagulation, NoFragmentation};
    /// use coagula_core::scheme::Scheme;
    /// use coagula_core::scheme::massflow::{MassFlow, PointSource, workspace_len};
    /// let mut buf = vec![0.0; workspace_len(1024).unwrap()]; // the caller's memory
    /// let k = Coagulation::constant(1.0).unwrap();
    /// let mut sim = MassFlow::new_in(k, NoFragmentation, &[1.0; 1024], 1.0, 0.01,
    ///                                PointSource::niederreiter(), &mut buf[..]).unwrap();
    /// sim.advance_to(1.0, &mut rand_pcg::Pcg64Mcg::new(1)).unwrap();
    /// assert!((sim.moment(1.0) - 1.0).abs() < 1e-12); // the mass is carried exactly
    /// assert!(sim.moment(2.0) > 1.5); // M2 = 1 + t for K = 1, here from 1024 particles
    /// ```
    pub fn new_in(
        kernel: K,
        frag: F,
        initial: &[f64],
        mass: f64,
        dt: f64,
        points: PointSource,
        mut workspace: B,
    ) -> Result<Self> {
        check_setup(initial, mass, dt)?;
        let n = initial.len();
        let need = workspace_len(n).ok_or(Error::Overflow {
            name: "mass-flow workspace",
        })?;
        let got = workspace.as_ref().len();
        if got < need {
            return Err(Error::BufferLength {
                name: "mass-flow workspace (f64s)",
                expected: need,
                got,
            });
        }
        let ws = &mut workspace.as_mut()[..need];
        ws.fill(0.0);
        let x = &mut ws[..n];
        x.copy_from_slice(initial);
        x.sort_unstable_by(f64::total_cmp);
        Ok(MassFlow {
            kernel,
            frag,
            points,
            sorting: Sorting::Adaptive,
            m: n.trailing_zeros(),
            mass,
            dt,
            time: 0.0,
            steps: 0,
            n,
            cur: 0,
            ws: workspace,
            totals: StepReport::default(),
        })
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel> MassFlow<K, F> {
    /// N particles sampled from the initial *mass* distribution by its inverse CDF at
    /// the centred 1-D low-discrepancy set `(k + 1/2)/N`.
    pub fn from_inverse_cdf(
        kernel: K,
        frag: F,
        n: usize,
        inverse_cdf: impl Fn(f64) -> f64,
        mass: f64,
        dt: f64,
        points: PointSource,
    ) -> Result<Self> {
        let init: Vec<f64> = (0..n)
            .map(|k| inverse_cdf((k as f64 + 0.5) / n as f64))
            .collect();
        Self::new(kernel, frag, &init, mass, dt, points)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    MassFlow<K, F, B>
{
    /// Selects the re-sorting strategy.
    pub fn with_sorting(mut self, sorting: Sorting) -> Self {
        self.sorting = sorting;
        self
    }

    /// The particle sizes, sorted ascending.
    pub fn sizes(&self) -> &[f64] {
        let o = self.cur * self.n;
        &self.ws.as_ref()[o..o + self.n]
    }

    /// Replaces the particle sizes (a host that applies growth or nucleation between
    /// steps). Same length, every size finite and positive; on error nothing changes.
    pub fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        if sizes.len() != self.n {
            return Err(Error::BufferLength {
                name: "sizes",
                expected: self.n,
                got: sizes.len(),
            });
        }
        for &v in sizes {
            crate::error::positive("size", v)?;
        }
        let (x, ..) = split(self.ws.as_mut(), self.n, self.cur);
        x.copy_from_slice(sizes);
        x.sort_unstable_by(f64::total_cmp);
        Ok(())
    }

    /// The time step Δt.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Steps taken so far (the index of the next point block).
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Total mass M1 carried by the particles.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// The moment estimate `M_m ≈ (M1/N) Σ_k x_k^{m−1}`.
    pub fn moment(&self, m: f64) -> f64 {
        crate::observe::mass_flow_moment(self.sizes(), self.mass, self.n, m)
    }

    /// Number concentration of sizes in `[a, b]`: `(M1/N) Σ_{a ≤ x_k ≤ b} 1/x_k`.
    pub fn concentration(&self, a: f64, b: f64) -> f64 {
        let w = self.mass / self.n as f64;
        crate::observe::sum_concentration(self.sizes().iter().map(|&x| (x, w / x)), a, b)
    }

    /// Number concentration per bin `[edges[i], edges[i+1])` into `out` (length
    /// `edges.len() − 1`).
    pub fn histogram(&self, edges: &[f64], out: &mut [f64]) -> Result<()> {
        if edges.len() < 2 || out.len() != edges.len() - 1 {
            return Err(Error::BufferLength {
                name: "histogram out",
                expected: edges.len().saturating_sub(1),
                got: out.len(),
            });
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        let w = self.mass / self.n as f64;
        for &x in self.sizes() {
            // edges are sorted; find the bin by binary search
            let i = edges.partition_point(|&e| e <= x);
            if i > 0 && i < edges.len() {
                out[i - 1] += w / x;
            }
        }
        Ok(())
    }

    /// Totals over the whole run.
    pub fn totals(&self) -> StepReport {
        self.totals
    }

    /// One step of length `h` into the next-sizes buffer; returns its report. The sizes
    /// are not touched, so an error leaves the state as it was.
    /// With `procs`, the processes' moves join the step (see `processes.rs`) and their
    /// plan is returned; the caller commits it after the step.
    #[inline(never)]
    fn step<'p, R: Rng + ?Sized>(
        &mut self,
        h: f64,
        rng: &mut R,
        procs: Option<&'p Processes>,
    ) -> Result<(StepReport, Option<processes::Plan<'p>>)> {
        // (two instances, so that a run without processes keeps the loop it had)
        match procs {
            Some(_) => self.step_in::<true, R>(h, rng, procs),
            None => self.step_in::<false, R>(h, rng, None),
        }
    }

    #[inline(always)]
    fn step_in<'p, const P: bool, R: Rng + ?Sized>(
        &mut self,
        h: f64,
        rng: &mut R,
        procs: Option<&'p Processes>,
    ) -> Result<(StepReport, Option<processes::Plan<'p>>)> {
        let n = self.n;
        let nf = n as f64;
        let mut rep = StepReport::default();
        let (x, next, pts, gamma) = split(self.ws.as_mut(), n, self.cur);
        let (kernel, frag, mass) = (&self.kernel, &self.frag, self.mass);
        let plan = match procs {
            Some(p) => Some(processes::plan(p, x, gamma, next, mass, self.time, h)?),
            None => None,
        };
        let (jumps, share, source, grows) = match &plan {
            Some(p) => (p.jumps, p.source_share, p.source, p.grows),
            None => (false, 0.0, None, false),
        };
        let bound = crate::kernel::break_rate_bound(frag);
        // particle k's move with partner l and uniform u3 (next[k] from the old sizes)
        let mut one = |k: usize, l: usize, u3: f64| -> Result<()> {
            let (xk, xl) = (x[k], x[l]);
            let kt = kernel.rate(xk, xl);
            let fd = crate::kernel::checked_break_rate_within(frag, xk, bound)?;
            if !(kt >= 0.0 && kt.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "coagulation kernel",
                    value: kt,
                });
            }
            let pc = h * mass * kt / xl;
            let pf = h * fd;
            // the processes' bands follow coagulation's: a jump to the partner's size,
            // then a source size (both 0 without processes)
            let pj = if P && jumps {
                (gamma[l] - gamma[k]).max(0.0)
            } else {
                0.0
            };
            let (aj, asrc) = if P {
                (pc + pj, pc + pj + share)
            } else {
                (pc, pc)
            };
            if asrc + pf > 1.0 {
                rep.clipped += 1;
            }
            let new = if u3 < pc {
                rep.events += 1;
                xk + xl
            } else if P && u3 < aj {
                rep.events += 1;
                xl
            } else if P
                && u3 < asrc
                && let Some(s) = source
            {
                rep.events += 1;
                let y = s.mass_size((u3 - aj) / share);
                if !(y > 0.0 && y.is_finite()) {
                    return Err(Error::InvalidRate {
                        name: "source size (finite and > 0; a distribution's mass quantile underflowed)",
                        value: y,
                    });
                }
                y
            } else if pf > 0.0 && u3 >= 1.0 - pf {
                rep.events += 1;
                let piece = frag.inverse_piece(xk, ((1.0 - u3) / pf).min(1.0));
                // (a followed piece larger than its particle would create mass, as MFA
                // and DSA refuse too)
                if !(piece > 0.0 && piece <= xk) {
                    return Err(Error::InvalidRate {
                        name: "fragment size (must lie in (0, x])",
                        value: piece,
                    });
                }
                piece
            } else {
                xk
            };
            if !new.is_finite() {
                // two sizes near f64::MAX merged: refuse the step, not return inf
                return Err(Error::Overflow {
                    name: "particle size (a coagulation passed the largest f64)",
                });
            }
            if P && grows {
                // the plan left `Φ_h(x_k)` there; a particle that moved grows from
                // its new size, marked negative for the re-sort
                if let Some(p) = procs
                    && new != xk
                {
                    next[k] = -processes::factors(p, new, h)?.size;
                }
            } else {
                next[k] = new;
            }
            Ok(())
        };
        // the partner of a point: ⌊N u⌋ (a u64 word's top m digits, as `to_unit` keeps
        // 53 bits and N = 2^m)
        let partner = |u: f64| ((nf * u) as usize).min(n - 1);
        // the block's points in the order of the particle they move: row k = ⌊N u_0⌋
        // holds (u_1, u_2), two values, not the block path's three (written nearly in
        // order), so that the loop below walks the sizes like MC's instead of scattered
        // (same points, same pairs, same bits)
        let by_particle = |k: usize, w1: u64, w2: u64| {
            if let Some(row) = pts.get_mut(2 * k..2 * k + 2) {
                row[0] = w1.to_unit();
                row[1] = w2.to_unit();
            }
            Ok(())
        };
        let sorted = match &self.points {
            PointSource::MonteCarlo => {
                for p in 0..n {
                    let l = u64::uniform_below(rng, n as u64) as usize;
                    one(p, l, unit_f64(rng.next_u64()))?;
                }
                rep.proposals = n as u64;
                return Ok((rep, plan));
            }
            PointSource::Niederreiter(seq) if n == 1 << self.m => {
                crate::qmc::walk_by_first(seq, self.steps, self.m, by_particle)?
            }
            PointSource::Sobol(seq) if n == 1 << self.m => {
                crate::qmc::walk_by_first(seq, self.steps, self.m, by_particle)?
            }
            _ => false,
        };
        if sorted {
            for (k, u) in pts.chunks_exact(2).take(n).enumerate() {
                one(k, partner(u[0]), u[1])?;
            }
        } else {
            self.points.block(self.steps, self.m, pts)?;
            for u in pts.chunks_exact(3).take(n) {
                one(partner(u[0]), partner(u[1]), u[2])?;
            }
        }
        rep.proposals = n as u64;
        Ok((rep, plan))
    }

    /// Sorts the next sizes (old order with some entries changed) ascending; a particle
    /// changed in the step iff its next size differs from its size — or, `marked`
    /// (growth moved every size, monotonely), iff it is negative (its size negated).
    fn resort(&mut self, marked: bool) {
        // (two instances: the loop without marks stays as it was)
        if marked {
            self.resort_in::<true>()
        } else {
            self.resort_in::<false>()
        }
    }

    #[inline(never)]
    fn resort_in<const MARKED: bool>(&mut self) {
        let marked = MARKED;
        let (x, next, _, scratch) = split(self.ws.as_mut(), self.n, self.cur);
        match self.sorting {
            Sorting::Full => {
                if marked {
                    next.iter_mut().for_each(|v| *v = v.abs());
                }
                next.sort_unstable_by(f64::total_cmp)
            }
            Sorting::Adaptive => {
                let (mut w, mut changed) = (0, 0);
                for i in 0..next.len() {
                    let v = next[i];
                    if if marked { v < 0.0 } else { v != x[i] } {
                        scratch[changed] = if marked { -v } else { v };
                        changed += 1;
                    } else {
                        next[w] = v;
                        w += 1;
                    }
                }
                let scratch = &mut scratch[..changed];
                scratch.sort_unstable_by(f64::total_cmp);
                // merge from the back: the unchanged prefix [0, w) and the scratch
                let (mut i, mut j, mut out) = (w, scratch.len(), next.len());
                while j > 0 {
                    out -= 1;
                    if i > 0 && next[i - 1] > scratch[j - 1] {
                        next[out] = next[i - 1];
                        i -= 1;
                    } else {
                        next[out] = scratch[j - 1];
                        j -= 1;
                    }
                }
                // (a Runge–Kutta step of a host's growth rate need not be monotone)
                if marked && next.windows(2).any(|w| w[0] > w[1]) {
                    next.sort_unstable_by(f64::total_cmp);
                }
            }
        }
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Scheme
    for MassFlow<K, F, B>
{
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        self.totals
    }

    /// Takes steps of Δt until `t`; a last, shorter step lands exactly on `t` when `t`
    /// is not a multiple of Δt.
    ///
    /// Each step costs N units of the budget (a step is taken whole while a unit is
    /// left). A step too small to move the clock at the current time (`time + Δt ==
    /// time`: a tiny Δt, or a time near the end of the doubles) is an error, not a hang.
    fn advance_within<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
    ) -> Result<StepReport> {
        self.run(t, budget, rng, None)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    MassFlow<K, F, B>
{
    /// [`advance_within`](Scheme::advance_within) with the processes `procs` in every
    /// step (`docs/design/processes.md`, "Mass-flow schemes"), entered in `books`: a source, removal and growth
    /// beside coagulation and fragmentation. Growth moves the sizes by the scheme's own
    /// step (a splitting step set in `procs` is not used here).
    pub fn advance_processes<R: Rng + ?Sized>(
        &mut self,
        procs: &Processes,
        books: &mut Books,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
    ) -> Result<StepReport> {
        self.run(t, budget, rng, Some((procs, books)))
    }

    fn run<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
        mut procs: Option<(&Processes, &mut Books)>,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        loop {
            let remaining = t - self.time;
            if remaining <= 1e-9 * self.dt {
                self.time = t;
                break;
            }
            let h = if remaining < self.dt * (1.0 - 1e-9) {
                remaining
            } else {
                self.dt
            };
            if self.time + h <= self.time {
                rep.time = self.time;
                self.totals.accumulate(&rep);
                return Err(Error::OutOfRange {
                    name: "dt",
                    value: h,
                    range: "above the resolution of the current time (time + dt > time)",
                });
            }
            if !budget.poll() || !budget.take(self.n as u64) {
                rep.interrupted = true;
                break;
            }
            let stepped = self
                .step(h, rng, procs.as_ref().map(|p| p.0))
                .map(|(r, plan)| {
                    self.resort(plan.as_ref().is_some_and(|p| p.grows));
                    (r, plan)
                });
            let r = match stepped {
                Ok((r, plan)) => {
                    if let (Some(plan), Some((_, books))) = (plan, procs.as_mut()) {
                        plan.book(books);
                        self.mass = plan.mass;
                    }
                    r
                }
                Err(e) => {
                    rep.time = self.time;
                    self.totals.accumulate(&rep);
                    return Err(e);
                }
            };
            self.cur ^= 1;
            self.steps += 1;
            self.time += h;
            rep.events += r.events;
            rep.proposals += r.proposals;
            rep.clipped += r.clipped;
        }
        rep.time = self.time;
        self.totals.accumulate(&rep);
        Ok(rep)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    crate::observe::Observe for MassFlow<K, F, B>
{
    /// 1: each particle carries the mass `M1 / N` instead of living in a volume.
    fn volume(&self) -> f64 {
        1.0
    }
    fn particles(&self) -> u64 {
        self.n as u64
    }
    fn moment(&self, order: f64) -> f64 {
        MassFlow::moment(self, order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        MassFlow::concentration(self, a, b)
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        let w = self.mass / self.n as f64;
        for &x in self.sizes() {
            f(x, w / x);
        }
    }
    /// None: the scheme keeps every particle (no gel leaves the system).
    fn gel_mass(&self) -> Option<f64> {
        None
    }
}

impl<K, F, B> MassFlow<K, F, B> {
    /// Replaces the coagulation kernel (e.g. new parameters between outer steps).
    pub fn set_kernel(&mut self, kernel: K) {
        self.kernel = kernel;
    }

    /// Replaces the fragmentation kernel.
    pub fn set_fragmentation(&mut self, frag: F) {
        self.frag = frag;
    }

    /// Changes the time step (finite and positive).
    pub fn set_dt(&mut self, dt: f64) -> Result<()> {
        self.dt = crate::error::positive("dt", dt)?;
        Ok(())
    }

    /// Sets the clock (finite, not negative): a host that keeps its own time origin.
    /// The point sequence continues where it stands.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = super::check_time(t)?;
        Ok(())
    }

    /// Changes the total mass M1 the particles carry (finite and positive): a host
    /// adding or removing mass between steps (each particle then carries `M1 / N`).
    pub fn set_mass(&mut self, mass: f64) -> Result<()> {
        self.mass = crate::error::positive("mass", mass)?;
        Ok(())
    }
}

mod checkpoint;
mod entry;
mod processes;
pub use entry::MassFlowEntry;

#[cfg(test)]
mod tests;
