//! The stepping verbs of a [`Batch`](super::Batch).

use super::*;

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> Batch<D, Dr, B> {
    /// [`with_starts`](Batch::with_starts) in storage the caller owns: `ws` holds at
    /// least [`workspace_len`]`(D, n)` words (overwritten; any excess is left alone).
    ///
    /// ```
    /// use coagula_core::langevin::{workspace_len, Batch, Config, Friction, Wall};
    /// let cfg = Config::<3>::ball(1.0, 0.01, 1.0, Wall::Absorbing).unwrap();
    /// let mut ws = vec![0u64; workspace_len(3, 100).unwrap()]; // the caller's memory
    /// let b = Batch::with_starts_in(cfg, Friction { rate: 1.0 }, 100, 42, 0,
    ///     |i| ([2.0 + i as f64, 0.0, 0.0], [-1.0, 0.0, 0.0]), &mut ws[..]).unwrap();
    /// assert_eq!(b.len(), 100);
    /// ```
    pub fn with_starts_in(
        cfg: Config<D>,
        drift: Dr,
        n: usize,
        key: u64,
        first_id: u64,
        mut start: impl FnMut(usize) -> ([f64; D], [f64; D]),
        mut ws: B,
    ) -> Result<Self> {
        if n == 0 {
            return Err(Error::Empty);
        }
        if D == 0 || D > 3 {
            return Err(Error::Dimension {
                requested: D,
                max: 3,
            });
        }
        if D == 1 && cfg.radius != 0.0 {
            return Err(Error::Unsupported {
                what: "a ball in one dimension",
            });
        }
        first_id.checked_add(n as u64 - 1).ok_or(Error::Overflow {
            name: "trajectory id",
        })?;
        let need = workspace_len(D, n).ok_or(Error::Overflow {
            name: "Langevin workspace",
        })?;
        let got = ws.as_ref().len();
        if got < need {
            return Err(Error::BufferLength {
                name: "Langevin workspace (u64 words)",
                expected: need,
                got,
            });
        }
        let w = Layout::<D>::W;
        // every start is checked before the workspace is written
        for i in 0..n {
            let (x, u) = start(i);
            cfg.check_start(&x, &u)?;
        }
        let recs = &mut ws.as_mut()[..need];
        for i in 0..n {
            let (x, u) = start(i);
            let t = Traj {
                x,
                u,
                rng: crate::random::generator(key, first_id + i as u64),
                hits: 0,
                first: f64::INFINITY,
            };
            t.store(&mut recs[i * w..(i + 1) * w]);
        }
        Ok(Batch {
            cfg,
            drift,
            ws,
            n,
            key,
            first_id,
            time: 0.0,
            totals: StepReport::default(),
        })
    }

    /// Number of trajectories.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false (a batch has at least one trajectory).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The configuration.
    pub fn config(&self) -> &Config<D> {
        &self.cfg
    }

    /// The drift.
    pub fn drift(&self) -> &Dr {
        &self.drift
    }

    /// The generators' key and the first trajectory's id.
    pub fn key(&self) -> (u64, u64) {
        (self.key, self.first_id)
    }

    /// Counts over the batch's life (events = wall hits, bounces = specular ones,
    /// removed = absorbed trajectories, proposals = trajectory-steps).
    pub fn totals(&self) -> StepReport {
        self.totals
    }

    pub(super) fn records(&self) -> &[u64] {
        &self.ws.as_ref()[..self.n * Layout::<D>::W]
    }

    pub(super) fn trajs(&self) -> impl Iterator<Item = Traj<D>> + '_ {
        self.records().chunks_exact(Layout::<D>::W).map(Traj::load)
    }

    /// Positions now (an absorbed trajectory's is where it hit the wall).
    pub fn positions(&self) -> impl Iterator<Item = [f64; D]> + '_ {
        self.trajs().map(|t| t.x)
    }

    /// Velocities now (an absorbed trajectory's is `U_θ−`, its velocity at the hit).
    pub fn velocities(&self) -> impl Iterator<Item = [f64; D]> + '_ {
        self.trajs().map(|t| t.u)
    }

    /// Wall hits of each trajectory so far (0 or 1 for an absorbing wall).
    pub fn hits(&self) -> impl Iterator<Item = u64> + '_ {
        self.trajs().map(|t| t.hits)
    }

    /// Time of each trajectory's first hit (`+inf` if none yet).
    pub fn first_hits(&self) -> impl Iterator<Item = f64> + '_ {
        self.trajs().map(|t| t.first)
    }

    /// Mean, variance and standard error of `f(X, U)` over the trajectories (absorbed
    /// ones at their hit, as the paper's absorption scheme returns them).
    pub fn statistics(&self, mut f: impl FnMut(&[f64; D], &[f64; D]) -> f64) -> Replicas {
        let mut r = Replicas::new();
        for t in self.trajs() {
            r.push(f(&t.x, &t.u));
        }
        r
    }

    /// Wall hits per trajectory: their mean and standard error.
    pub fn hit_statistics(&self) -> Replicas {
        let mut r = Replicas::new();
        for h in self.hits() {
            r.push(h as f64);
        }
        r
    }

    /// Trajectories absorbed so far (0 for a specular wall).
    pub fn absorbed(&self) -> usize {
        if self.cfg.wall == Wall::Absorbing {
            self.trajs().filter(|t| t.hits > 0).count()
        } else {
            0
        }
    }

    /// One step of length `h` from time `t`.
    #[inline(always)]
    pub(super) fn step(
        cfg: &Config<D>,
        drift: &Dr,
        t: f64,
        h: f64,
        tr: &mut Traj<D>,
    ) -> Result<Hit> {
        let b = drift.drift(t, &tr.x, &tr.u);
        let mut xf = [0.0; D];
        for k in 0..D {
            xf[k] = tr.x[k] + h * tr.u[k];
        }
        // time s into the step at which the straight path meets the wall, and the
        // outward normal there
        let mut contact: Option<(f64, [f64; D], [f64; D])> = None;
        if D == 1 {
            let (x, u) = (tr.x[0], tr.u[0]);
            if xf[0] < 0.0 || (x == 0.0 && u < 0.0) {
                let mut xt = [0.0; D];
                xt[0] = 0.0;
                let mut n = [0.0; D];
                n[0] = 1.0;
                contact = Some(((-x / u).clamp(0.0, h), xt, n));
            }
        } else {
            let c = dot(&tr.x, &tr.x) - cfg.radius * cfg.radius;
            let bq = dot(&tr.x, &tr.u);
            let a = dot(&tr.u, &tr.u);
            if !(a.is_finite() && (bq * bq).is_finite()) {
                return Err(Error::InvalidRate {
                    name: "velocity (too large to find the wall: |u|² overflows)",
                    value: a,
                });
            }
            if bq < 0.0 && a > 0.0 {
                let disc = bq * bq - a * c;
                let s = if c <= 0.0 {
                    Some(0.0)
                } else if disc >= 0.0 {
                    // the smaller root, in the form without cancellation
                    let s = c / (libm::sqrt(disc) - bq);
                    (s < h).then_some(s)
                } else {
                    None
                };
                if let Some(s) = s {
                    let mut xt = [0.0; D];
                    for k in 0..D {
                        xt[k] = tr.x[k] + s * tr.u[k];
                    }
                    let r = libm::sqrt(dot(&xt, &xt));
                    let n = core::array::from_fn(|k| xt[k] / r);
                    contact = Some((s, xt, n));
                }
            }
        }
        let sig = cfg.sigma;
        let Some((s, xt, n)) = contact else {
            let sh = sig * libm::sqrt(h);
            let mut u = [0.0; D];
            for k in 0..D {
                u[k] = tr.u[k] + b[k] * h + sh * NormalZiggurat::sample(&mut tr.rng);
            }
            Self::finish(cfg, tr, xf, u)?;
            return Ok(Hit::None);
        };
        let ss = sig * libm::sqrt(s);
        let mut um = [0.0; D];
        for k in 0..D {
            um[k] = Self::bounded(
                cfg,
                tr.u[k] + b[k] * s + ss * NormalZiggurat::sample(&mut tr.rng),
            );
        }
        if !um.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "velocity at a wall hit (the drift returned NaN or infinity)",
                value: um
                    .iter()
                    .copied()
                    .find(|v| !v.is_finite())
                    .unwrap_or(f64::NAN),
            });
        }
        tr.hits = tr.hits.saturating_add(1); // (restored counts may stand anywhere)
        if tr.first == f64::INFINITY {
            tr.first = (t + s).min(t + h);
        }
        if cfg.wall == Wall::Absorbing {
            tr.x = xt;
            tr.u = um;
            return Ok(Hit::Absorbed);
        }
        // reflect the velocity, mirror the free position in the tangent plane
        let un = dot(&um, &n);
        let ut: [f64; D] = core::array::from_fn(|k| um[k] - 2.0 * un * n[k]);
        let mut d = 0.0;
        for k in 0..D {
            d += (xf[k] - xt[k]) * n[k];
        }
        for k in 0..D {
            xf[k] -= 2.0 * d * n[k];
        }
        if D == 1 {
            xf[0] = xf[0].abs();
        }
        let b2 = drift.drift(t + s, &xt, &ut);
        let sr = sig * libm::sqrt(h - s);
        let mut u = [0.0; D];
        for k in 0..D {
            u[k] = ut[k] + b2[k] * (h - s) + sr * NormalZiggurat::sample(&mut tr.rng);
        }
        Self::finish(cfg, tr, xf, u)?;
        Ok(Hit::Bounce)
    }

    /// A velocity component with the bound applied.
    #[inline(always)]
    pub(super) fn bounded(cfg: &Config<D>, mut u: f64) -> f64 {
        match cfg.bound {
            VelocityBound::None => {}
            VelocityBound::Clamp(v) => u = u.clamp(-v, v),
            VelocityBound::Reflect(v) => {
                if u > v {
                    u = 2.0 * v - u;
                } else if u < -v {
                    u = -2.0 * v - u;
                }
                u = u.clamp(-v, v);
            }
        }
        u
    }

    /// Applies the options to the new state and stores it, or fails on a non-finite
    /// velocity (a drift returning NaN or infinity).
    #[inline(always)]
    pub(super) fn finish(
        cfg: &Config<D>,
        tr: &mut Traj<D>,
        mut x: [f64; D],
        mut u: [f64; D],
    ) -> Result<()> {
        for k in 0..D {
            if !u[k].is_finite() {
                return Err(Error::InvalidRate {
                    name: "velocity after a step (the drift returned NaN or infinity)",
                    value: u[k],
                });
            }
            u[k] = Self::bounded(cfg, u[k]);
        }
        if D == 1
            && let Some(l) = cfg.period
        {
            // one period back without a branch (a trajectory crosses the border at
            // random steps); more periods are rare and reduced exactly by fmod
            x[0] -= l * f64::from(u8::from(x[0] >= l));
            if x[0] >= l {
                x[0] = libm::fmod(x[0], l);
            }
        }
        if let Some(&bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "position after a step (the velocity overflowed)",
                value: bad,
            });
        }
        tr.x = x;
        tr.u = u;
        Ok(())
    }

    /// `t` moved onto the grid point `k dt` within 1e-9 dt of it (targets such as 0.7
    /// with dt = 0.1, which is 7 dt only up to rounding, step as the grid point).
    #[inline]
    pub(super) fn snap(dt: f64, t: f64) -> f64 {
        let g = libm::round(t / dt) * dt;
        if (g - t).abs() <= 1e-9 * dt { g } else { t }
    }

    /// The index k of the first grid point `k dt` after `s` (snapped).
    #[inline]
    pub(super) fn first_grid(dt: f64, s: f64) -> f64 {
        let k = libm::round(s / dt);
        if k * dt <= s { k + 1.0 } else { k }
    }
}
