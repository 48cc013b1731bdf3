//! A [`Batch`](super::Batch)'s checkpoint.

use super::*;

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> crate::checkpoint::Checkpoint
    for Batch<D, Dr, B>
{
    /// The configuration, key, time, counts and every record (the drift is code: the
    /// restoring batch brings its own).
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::LANGEVIN);
        w.u64(D as u64);
        w.u64(self.n as u64);
        let c = &self.cfg;
        w.f64(c.dt);
        w.f64(c.sigma);
        w.u64(u64::from(c.wall == Wall::Absorbing));
        w.f64(c.radius);
        w.f64(c.period.unwrap_or(0.0));
        let (kind, v) = match c.bound {
            VelocityBound::None => (0, 0.0),
            VelocityBound::Clamp(v) => (1, v),
            VelocityBound::Reflect(v) => (2, v),
        };
        w.u64(kind);
        w.f64(v);
        w.u64(self.key);
        w.u64(self.first_id);
        w.f64(self.time);
        self.totals.save(w);
        w.u64s(self.records());
    }

    /// Refuses a checkpoint of another dimension or size, an invalid configuration or
    /// an invalid record (non-finite state, a zero generator, a first hit after the
    /// time); on error the batch is unchanged.
    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::LANGEVIN)?;
        if r.u64()? != D as u64 || r.u64()? != self.n as u64 {
            return Err(bad("a batch of another dimension or size"));
        }
        let (dt, sigma, absorbing, radius, period) =
            (r.f64()?, r.f64()?, r.u64()?, r.f64()?, r.f64()?);
        let (kind, v) = (r.u64()?, r.f64()?);
        let wall = match absorbing {
            0 => Wall::Specular,
            1 => Wall::Absorbing,
            _ => return Err(bad("invalid wall")),
        };
        let invalid = |_| bad("invalid configuration");
        let mut cfg = if D == 1 {
            if radius != 0.0 {
                return Err(bad("invalid configuration"));
            }
            let c = Config::<D>::half_line(dt, sigma, wall).map_err(invalid)?;
            if period != 0.0 {
                c.with_period(period).map_err(invalid)?
            } else {
                c
            }
        } else {
            if period != 0.0 {
                return Err(bad("invalid configuration"));
            }
            Config::<D>::ball(radius, dt, sigma, wall).map_err(invalid)?
        };
        let bound = match kind {
            0 if v == 0.0 => VelocityBound::None,
            1 => VelocityBound::Clamp(v),
            2 => VelocityBound::Reflect(v),
            _ => return Err(bad("invalid velocity bound")),
        };
        cfg = cfg.with_velocity_bound(bound).map_err(invalid)?;
        let (key, first_id, time) = (r.u64()?, r.u64()?, r.f64()?);
        if first_id.checked_add(self.n as u64 - 1).is_none() {
            return Err(bad("invalid trajectory ids"));
        }
        crate::scheme::check_time(time).map_err(|_| bad("invalid time"))?;
        if Self::snap(cfg.dt, time) / cfg.dt > MAX_STEP_INDEX {
            return Err(bad("a time beyond 2^52 steps"));
        }
        let totals = StepReport::read(r)?;
        if totals.time.is_nan() || totals.time > time {
            return Err(bad("totals after the time"));
        }
        let w = Layout::<D>::W;
        if r.u64()? != (self.n * w) as u64 {
            return Err(bad("records of the wrong length"));
        }
        // read into the copy half of the workspace (no allocation), check, then swap in
        let (recs, snap) = self.ws.as_mut()[..2 * self.n * w].split_at_mut(self.n * w);
        for v in snap.iter_mut() {
            *v = r.u64()?;
        }
        r.finish()?;
        let horizon = Self::snap(cfg.dt, time) + cfg.dt;
        for rec in snap.chunks_exact(w) {
            let t = Traj::<D>::load(rec);
            let stopped = t.stopped(wall);
            // a mirrored position may sit within rounding of the wall
            let r2 = dot(&t.x, &t.x);
            let placed = if D == 1 {
                if stopped {
                    t.x[0] == 0.0
                } else {
                    cfg.check_start(&t.x, &t.u).is_ok()
                }
            } else {
                r2 >= cfg.radius * cfg.radius * (1.0 - 1e-9)
                    && t.u.iter().all(|v| v.is_finite())
                    && match cfg.bound {
                        VelocityBound::None => true,
                        VelocityBound::Clamp(v) | VelocityBound::Reflect(v) => {
                            t.u.iter().all(|c| c.abs() <= v)
                        }
                    }
            };
            let ok = t.x.iter().chain(&t.u).all(|v| v.is_finite())
                && placed
                && t.rng.parts() != [0; 4]
                && (t.first == f64::INFINITY || (t.first >= 0.0 && t.first <= horizon))
                && (t.hits == 0) == (t.first == f64::INFINITY)
                && (wall == Wall::Specular || t.hits <= 1);
            if !ok {
                return Err(bad("an invalid trajectory record"));
            }
        }
        recs.copy_from_slice(snap);
        self.cfg = cfg;
        self.key = key;
        self.first_id = first_id;
        self.time = time;
        self.totals = totals;
        Ok(())
    }
}
