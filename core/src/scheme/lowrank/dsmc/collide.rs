//! The DSMC collision rule: the accepted pair's direction, the collision or merge it
//! makes, and the rule's checkpoint (Osinsky 2023 §5; see the module docs of
//! [`dsmc`](super)).

use super::*;

/// A particle: size, class, index in the class.
type At = (u64, i32, usize);

/// What an accepted collision changes, from `plan` to `commit`.
#[derive(Clone, Copy, Debug, Default)]
enum Pending {
    #[default]
    None,
    /// The two particles leave with these velocities.
    Bounce {
        k: At,
        vk: [f64; 3],
        l: At,
        vl: [f64; 3],
    },
    /// The two particles become one of size `size` with velocity `v`.
    Merge {
        k: At,
        l: At,
        size: u64,
        v: [f64; 3],
    },
}

/// The DSMC collision rule (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Collisions {
    /// The accepted pair (class index, index in the class), its direction and
    /// `(V_k − V_l)·e`.
    k: (usize, usize),
    l: (usize, usize),
    e: [f64; 3],
    gn: f64,
    pending: Pending,
}

/// A direction uniform on the unit sphere (Marsaglia 1972). Each try is accepted with
/// probability π/4, so 64 rejections in a row (probability 2^-142 for a working
/// generator) mean a stuck one: the pole is returned instead of looping forever.
#[inline]
fn direction<G: Rng + ?Sized>(rng: &mut G) -> [f64; 3] {
    for _ in 0..64 {
        let u1 = 2.0 * unit_f64(rng.next_u64()) - 1.0;
        let u2 = 2.0 * unit_f64(rng.next_u64()) - 1.0;
        let s = u1 * u1 + u2 * u2;
        if s < 1.0 {
            let r = 2.0 * libm::sqrt(1.0 - s);
            return [u1 * r, u2 * r, 1.0 - 2.0 * s];
        }
    }
    [0.0, 0.0, 1.0]
}

/// A collision direction for relative velocity `g` (`|g| = gabs`): `e` with density
/// ∝ `|g·e|` on the unit sphere, and `g·e`. For `g = 0` any direction (`g·e = 0`).
#[inline]
fn oriented<G: Rng + ?Sized>(g: &[f64; 3], gabs: f64, rng: &mut G) -> ([f64; 3], f64) {
    let r = direction(rng);
    if gabs.is_nan() || gabs <= 0.0 {
        return (r, 0.0);
    }
    let gh = [g[0] / gabs, g[1] / gabs, g[2] / gabs];
    let c = libm::sqrt(unit_f64(rng.next_u64()));
    // a uniform direction perpendicular to ĝ from r (r ∥ ĝ has probability 0; its
    // rounding remnant is caught by the length test)
    let rg = r[0] * gh[0] + r[1] * gh[1] + r[2] * gh[2];
    let mut p = [r[0] - rg * gh[0], r[1] - rg * gh[1], r[2] - rg * gh[2]];
    let pl = norm(&p);
    if pl.is_nan() || pl <= 1e-8 {
        return (gh, gabs);
    }
    let sn = libm::sqrt((1.0 - c * c).max(0.0)) / pl;
    for (pk, gk) in p.iter_mut().zip(gh) {
        *pk = c * gk + sn * *pk;
    }
    (p, gabs * c)
}

fn bad_velocity(v: f64) -> Error {
    Error::InvalidRate {
        name: "particle velocity after a collision",
        value: v,
    }
}

impl<S> Gas<S> {
    /// Removes the particle at `at`.
    fn remove(&mut self, (size, q, idx): At) {
        let sp = &mut self.species[size as usize - 1];
        let d = sp.index(q).expect("a particle's class");
        sp.remove(d, idx);
    }

    /// Removes particles `ats` (the later index first where two share a class).
    fn remove_both(&mut self, mut ats: [At; 2]) {
        if ats[0] < ats[1] {
            ats.swap(0, 1);
        }
        for at in ats {
            self.remove(at);
        }
    }
}

impl<S: Sticking + Clone> EventRule<Gas<S>> for Collisions {
    const REWEIGHS: bool = true;
    const DOUBLES: bool = false;
    const TAG: Option<u64> = Some(crate::scheme::tag::DSMC);

    fn for_kernel(_kernel: &Gas<S>) -> Self {
        Collisions::default()
    }

    #[inline]
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        gas: &Gas<S>,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        low: Low,
        _spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>> {
        let (x, y) = (c.x, c.y);
        let (sx, sy) = (&gas.species[x as usize - 1], &gas.species[y as usize - 1]);
        if gas.weighted && low != Low::Bound {
            return Err(Error::Unsupported {
                what: "a gas weighted for the per-size trees on another engine (use new_gas)",
            });
        }
        // the first particle ∝ its bound (weighted) or uniformly; the second uniformly
        // among the others
        let k = if gas.weighted {
            sx.weighted(sx.s * unit_f64(rng.next_u64()))
        } else {
            sx.locate(below(rng, sx.n as u64) as usize)
        };
        let l = if x == y {
            let r = below(rng, sx.n as u64 - 1) as usize;
            sx.locate(r + usize::from(r >= sx.global(k.0, k.1)))
        } else {
            sy.locate(below(rng, sy.n as u64) as usize)
        };
        let (ck, cl) = (&sx.classes[k.0], &sy.classes[l.0]);
        let (vk, vl) = (ck.v[k.1], cl.v[l.1]);
        let g = [vk[0] - vl[0], vk[1] - vl[1], vk[2] - vl[2]];
        let gabs = norm(&g);
        let uniform = gas.directions == Directions::Uniform;
        // |g| (the rate integrated over e), or |g·e| for a uniform e
        let speed = if uniform {
            let e = direction(rng);
            (self.e, self.gn) = (e, g[0] * e[0] + g[1] * e[1] + g[2] * e[2]);
            self.gn.abs()
        } else {
            gabs
        };
        let (rate, bound) = if gas.weighted {
            (speed, ck.w + cl.w)
        } else {
            // the pair's rate against the engine's bound
            let d = size_cbrt(x) + size_cbrt(y);
            (gas.scale() * d * d * speed, bounds().0)
        };
        if rate.is_nan() || rate > bound * (1.0 + 1e-12) {
            // a speed past its class's bound: an invariant broke
            return Err(Error::BoundExceeded {
                name: "DSMC speed bounds",
                rate,
                bound,
            });
        }
        if rate < bound * open_unit(rng) {
            return Ok(None);
        }
        if !uniform {
            // the direction given the pair: density ∝ |g·e| on the sphere, i.e.
            // cos θ = sqrt(U) from ĝ (the sign of e does not matter), azimuth uniform
            (self.e, self.gn) = oriented(&g, gabs, rng);
        }
        (self.k, self.l) = (k, l);
        let gn = self.gn;
        let p = gas.sticking.probability(x, y, gn.abs());
        if !(0.0..=1.0).contains(&p) {
            return Err(Error::InvalidRate {
                name: "sticking probability",
                value: p,
            });
        }
        Ok(Some(if p > 0.0 && open_unit(rng) <= p {
            Outcome::Merge {
                size: x.saturating_add(y),
            }
        } else {
            Outcome::Bounce
        }))
    }

    fn plan(
        &mut self,
        gas: &mut Gas<S>,
        (x, y): (u64, u64),
        outcome: &Outcome,
        _count: &dyn Fn(u64) -> u64,
    ) -> Result<()> {
        let (e, gn) = (self.e, self.gn);
        let (sx, sy) = (&gas.species[x as usize - 1], &gas.species[y as usize - 1]);
        let vk = sx.classes[self.k.0].v[self.k.1];
        let vl = sy.classes[self.l.0].v[self.l.1];
        // (by class: reserving may move the classes' indices)
        let k = (x, sx.q(self.k.0), self.k.1);
        let l = (y, sy.q(self.l.0), self.l.1);
        let (mx, my) = (x as f64, y as f64);
        self.pending = match *outcome {
            Outcome::Bounce => {
                // momentum along e exchanged, the normal relative velocity times −ε
                let q = (1.0 + gas.restitution) * gn / (mx + my);
                let (mut nk, mut nl) = (vk, vl);
                for d in 0..3 {
                    nk[d] -= q * my * e[d];
                    nl[d] += q * mx * e[d];
                }
                if !(finite_speed(&nk) && finite_speed(&nl)) {
                    return Err(bad_velocity(nk[0] + nl[0]));
                }
                // room in the classes they move to
                let (qk, ql) = (class_of(&nk), class_of(&nl));
                if x == y {
                    gas.species[x as usize - 1].reserve(&[qk, ql])?;
                } else {
                    gas.species[x as usize - 1].reserve(&[qk])?;
                    gas.species[y as usize - 1].reserve(&[ql])?;
                }
                Pending::Bounce {
                    k,
                    vk: nk,
                    l,
                    vl: nl,
                }
            }
            Outcome::Merge { size } => {
                let mut v = [0.0; 3];
                for d in 0..3 {
                    v[d] = (mx * vk[d] + my * vl[d]) / (mx + my);
                }
                if !finite_speed(&v) {
                    return Err(bad_velocity(v[0]));
                }
                let idx = usize::try_from(size - 1).map_err(|_| Error::Capacity {
                    name: "particle size",
                    capacity: usize::MAX,
                })?;
                if idx >= gas.species.len() {
                    let more = idx + 1 - gas.species.len();
                    try_reserve(&mut gas.species, more)?;
                    gas.species.resize(idx + 1, Species::default());
                }
                gas.species[idx].reserve(&[class_of(&v)])?;
                Pending::Merge { k, l, size, v }
            }
        };
        Ok(())
    }

    fn commit(&mut self, gas: &mut Gas<S>) -> Reweighed {
        let mut touched = Reweighed::new();
        let mut touch = |s: u64| {
            if !touched.contains(&s) {
                let _ = touched.push(s);
            }
        };
        match core::mem::take(&mut self.pending) {
            Pending::None => {}
            Pending::Bounce { k, vk, l, vl } => {
                // a particle that stays in its class is written in place (its size's
                // sums are unchanged); the others leave their classes (the later index
                // first) and join their new ones
                let (stay_k, stay_l) = (k.1 == class_of(&vk), l.1 == class_of(&vl));
                for (at, v, stay) in [(k, vk, stay_k), (l, vl, stay_l)] {
                    if stay {
                        let sp = &mut gas.species[at.0 as usize - 1];
                        let d = sp.index(at.1).expect("a particle's class");
                        sp.classes[d].v[at.2] = v;
                    }
                }
                match (stay_k, stay_l) {
                    (true, true) => {}
                    (false, true) => {
                        gas.remove(k);
                        gas.species[k.0 as usize - 1].insert(vk);
                        touch(k.0);
                    }
                    (true, false) => {
                        gas.remove(l);
                        gas.species[l.0 as usize - 1].insert(vl);
                        touch(l.0);
                    }
                    (false, false) => {
                        gas.remove_both([k, l]);
                        gas.species[k.0 as usize - 1].insert(vk);
                        gas.species[l.0 as usize - 1].insert(vl);
                        touch(k.0);
                        touch(l.0);
                    }
                }
            }
            Pending::Merge { k, l, size, v } => {
                gas.remove_both([k, l]);
                gas.species[size as usize - 1].insert(v);
                touch(k.0);
                touch(l.0);
                touch(size);
            }
        }
        touched
    }

    fn check_counts(gas: &Gas<S>, counts: &[u64]) -> Result<()> {
        let have = gas.species.iter().map(|s| s.n as u64);
        let agree = counts
            .iter()
            .copied()
            .chain(core::iter::repeat(0))
            .zip(have.chain(core::iter::repeat(0)))
            .take(counts.len().max(gas.species.len()))
            .all(|(a, b)| a == b);
        if agree {
            Ok(())
        } else {
            Err(Error::Unsupported {
                what: "DSMC counts must be those of the gas's particles (build from the Gas)",
            })
        }
    }

    fn save(&self, gas: &Gas<S>, w: &mut Writer) {
        w.u64(gas.species.len() as u64);
        for sp in &gas.species {
            let occupied = || {
                sp.classes
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| !c.v.is_empty())
            };
            w.u64(occupied().count() as u64);
            for (d, c) in occupied() {
                w.u64(sp.q(d) as i64 as u64);
                w.f64s(&c.v.iter().flatten().copied().collect::<Vec<_>>());
            }
        }
    }

    fn load(&self, gas: &Gas<S>, r: &mut Reader) -> Result<Option<Gas<S>>> {
        let bad = |what| Error::Checkpoint { what };
        let m = r.u64()?;
        let mut species = Vec::new();
        for _ in 0..m {
            let nc = r.u64()?;
            let mut sp = Species::default();
            for _ in 0..nc {
                let q = i32::try_from(r.u64()? as i64).map_err(|_| bad("invalid speed class"))?;
                let flat = r.f64s()?;
                // (older checkpoints: `v = 0` in class i32::MIN and subnormal `|v|²` in
                // classes below Q_MIN, all now in Q_MIN)
                // (Q_MIN, and in older checkpoints i32::MIN and the classes below Q_MIN,
                // may be listed more than once: all are Q_MIN now)
                let low = q == i32::MIN || (-2200..=Q_MIN).contains(&q);
                if flat.len() % 3 != 0 || !(low || (Q_MIN..=2047).contains(&q)) {
                    return Err(bad("invalid speed class"));
                }
                let fits = |x: &[f64; 3]| {
                    finite_speed(x) && (class_of(x) == q || (low && class_of(x) == Q_MIN))
                };
                let v: Vec<[f64; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                // (a class listed twice: its particles would be in the order of neither)
                let twice = !low
                    && !v.is_empty()
                    && sp.index(q).is_some_and(|d| !sp.classes[d].v.is_empty());
                if !v.iter().all(fits) || twice {
                    return Err(bad("particle velocities do not match their speed classes"));
                }
                for x in v {
                    sp.reserve(&[class_of(&x)])?;
                    sp.insert(x);
                }
            }
            try_reserve(&mut species, 1)?;
            species.push(sp);
        }
        Ok(Some(Gas {
            restitution: gas.restitution,
            sticking: gas.sticking.clone(),
            species,
            weighted: gas.weighted,
            directions: gas.directions,
        }))
    }
}
