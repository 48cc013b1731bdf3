//! The processes of [`crate::process`] driven over a scheme's own exact clock, for every
//! scheme of the registry that takes them (the facade names no scheme: it reads and
//! replaces the state through [`Controls`]).
//!
//! Thinning (`docs/design/processes.md`): at the last process event (or call start) the
//! total process rate `R = S V + Σ λ(x_i) + Σ G(x_i)` bounds it until the next process
//! event, since merging cannot raise it and V changes only at a particle doubling, where
//! the scheme halts ([`Budget::doubled`]) and the bound is drawn afresh (an exponential's
//! residual is exponential). A candidate comes at `Exp(R̄)`; the scheme coagulates to it
//! with its own clock; then a source, removal or growth event happens with probability
//! its rate over `R̄` (which particle: in proportion to its rate), or nothing.
//!
//! Growth on real sizes is split off (Strang splitting, [`Processes::with_growth_step`]):
//! the instants `(k + ½) h` end a candidate's bound like a schedule's change, and there
//! every particle grows by a step.
//!
//! The candidate is kept across calls and in checkpoints, so that a run split at any
//! times gives the bits of an unbroken one.
//!
//! Cost: on a scheme that edits single particles ([`Controls::edits`]: lowrank's
//! engines, direct simulation) a process event is a draw and an edit; elsewhere it
//! reads and replaces the state (`O(occupied sizes)` on counts, `O(N)` on sizes).

use super::{Controls, State};
use crate::error::{Error, Result};
use crate::memory::try_reserve;
use crate::observe::Observe;
use crate::process::{Books, Power, Processes, UserRate};
use crate::random::{Ziggurat, open_unit};
use crate::scheme::{Budget, Scheme, StepReport};
use alloc::vec::Vec;
use rand_core::Rng;

mod record;

/// The bound of a void candidate: the next change of a scheduled source's rate, where
/// the candidate is drawn afresh and nothing happens.
const VOID: f64 = -1.0;

/// The bound of a growth instant on real sizes (`(k + ½) h` of the splitting step h):
/// every particle grows by a step, and the candidate is drawn afresh.
const GROW: f64 = -2.0;

/// The most growth steps one advance takes (each one rebuilds the state, O(N)).
const MAX_GROWTH_STEPS: f64 = (1u64 << 24) as f64;

/// The first growth instant `origin + (k + ½) h` after `now`.
fn next_growth(h: f64, origin: f64, now: f64) -> Result<f64> {
    let steps = (now - origin) / h;
    if steps.abs() < (1u64 << 50) as f64 {
        let k0 = libm::floor(steps - 0.5);
        for k in [k0 - 1.0, k0, k0 + 1.0, k0 + 2.0] {
            let at = origin + (k + 0.5) * h;
            if at > now {
                return Ok(at);
            }
        }
    }
    Err(Error::OutOfRange {
        name: "growth step",
        value: h,
        range: "large enough that time / step < 2^50 (the growth instants must be distinct)",
    })
}

/// The processes of one sim, their books and the pending candidate.
#[derive(Clone, Debug)]
pub(crate) struct Driver {
    procs: Processes,
    books: Books,
    /// The next candidate time and the bound it was drawn with.
    pending: Option<(f64, f64)>,
    integer: bool,
    /// Where the grid of growth instants starts (the time growth was set or the clock
    /// was, see [`start`](Driver::start)).
    origin: f64,
}

/// A population as the driver edits it.
enum Held {
    Counts(Vec<(u64, u64)>),
    Sizes(Vec<f64>),
}

fn held<K, F, S: Controls<K, F>>(s: &S) -> Result<Held> {
    match s.state() {
        State::Sizes(x) => {
            let mut v = Vec::new();
            try_reserve(&mut v, x.len() + 1)?;
            v.extend_from_slice(x);
            Ok(Held::Sizes(v))
        }
        State::Counts(..) => {
            let mut v = Vec::new();
            let mut err = None;
            s.for_each_count(&mut |i, n| {
                if err.is_none()
                    && let Err(e) = try_reserve(&mut v, 1)
                {
                    err = Some(e);
                }
                if err.is_none() {
                    v.push((i, n));
                }
            })?;
            match err {
                Some(e) => Err(e),
                None => Ok(Held::Counts(v)),
            }
        }
    }
}

/// Particle number and mass of the state (a mass-flow state's mass is the one it
/// carries).
fn tally<K, F, S: Controls<K, F>>(s: &S) -> Result<(u64, f64)> {
    if let (Some(m), State::Sizes(x)) = (s.carried_mass(), s.state()) {
        return Ok((x.len() as u64, m));
    }
    match s.state() {
        State::Sizes(x) => Ok((x.len() as u64, x.iter().sum())),
        State::Counts(..) => {
            let (mut n, mut m) = (0u64, 0u128);
            s.for_each_count(&mut |i, c| {
                n = n.saturating_add(c);
                m = m.saturating_add(u128::from(i) * u128::from(c));
            })?;
            Ok((n, m as f64))
        }
    }
}

/// A removal or growth law: a power of size, or a host's function with its bound.
#[derive(Clone, Copy)]
enum Rate<'a> {
    Power(&'a Power),
    User(&'a UserRate),
}

impl Rate<'_> {
    fn at(&self, x: f64) -> Result<f64> {
        match self {
            Rate::Power(p) => Ok(p.at(x)),
            Rate::User(u) => u.at(x),
        }
    }
}

/// The removal and growth laws of `p`, each with whether it grows.
fn laws(p: &Processes) -> impl Iterator<Item = (Rate<'_>, bool)> {
    let power = [(&p.removal, false), (&p.growth, true)]
        .into_iter()
        .filter_map(|(q, g)| q.as_ref().map(|q| (Rate::Power(q), g)));
    let user = [(&p.user_removal, false), (&p.user_growth, true)]
        .into_iter()
        .filter_map(|(q, g)| q.as_ref().map(|q| (Rate::User(q), g)));
    power.chain(user)
}

/// The laws drawn as events by thinning: every law on integer sizes; on real sizes
/// growth is split off ([`GROW`]) and only removal is.
fn thinned(p: &Processes, integer: bool) -> impl Iterator<Item = (Rate<'_>, bool)> {
    laws(p).filter(move |&(_, grow)| integer || !grow)
}

/// The thinning weight of occupied entry `k` of `h` (counts times the rate per
/// particle; a host's rate by its bound, which merges cannot raise in total — its value
/// is the acceptance, [`keep`]).
fn weight(h: &Held, rate: Rate<'_>, k: usize) -> Result<f64> {
    let per = |x: f64| match rate {
        Rate::User(u) => Ok(u.bound()),
        _ => rate.at(x),
    };
    match h {
        Held::Counts(v) => Ok(per(v[k].0 as f64)? * v[k].1 as f64),
        Held::Sizes(x) => per(x[k]),
    }
}

/// Whether the particle of size `x` drawn for `rate` acts: always for a power (drawn by
/// its rate); for a host's rate (drawn by its bound) with probability `f(x)/bound`,
/// which evaluates and checks `f` there.
fn keep<G: Rng + ?Sized>(rate: Rate<'_>, x: f64, rng: &mut G) -> Result<bool> {
    match rate {
        Rate::User(u) => {
            let f = u.at(x)?;
            Ok(open_unit(rng) * u.bound() < f)
        }
        _ => Ok(true),
    }
}

/// The size of entry `k` of `h`.
fn size_of(h: &Held, k: usize) -> f64 {
    match h {
        Held::Counts(v) => v[k].0 as f64,
        Held::Sizes(x) => x[k],
    }
}

fn entries(h: &Held) -> usize {
    match h {
        Held::Counts(v) => v.len(),
        Held::Sizes(x) => x.len(),
    }
}

/// `Σ rate(x)` over the particles of `h`.
fn total(h: &Held, rate: Rate<'_>) -> Result<f64> {
    let mut sum = 0.0;
    for k in 0..entries(h) {
        sum += weight(h, rate, k)?;
    }
    Ok(sum)
}

/// The particle (index into `h`) at `u ∈ [0, Σ rate)` of the cumulative rates.
fn pick(h: &Held, rate: Rate<'_>, mut u: f64) -> Result<usize> {
    let last = entries(h);
    for k in 0..last {
        let w = weight(h, rate, k)?;
        if u < w {
            return Ok(k);
        }
        u -= w;
    }
    // rounding past the last: the last particle of positive rate
    for k in (0..last).rev() {
        if weight(h, rate, k)? > 0.0 {
            return Ok(k);
        }
    }
    Ok(0)
}

/// What a process event did.
enum Event {
    Inject(f64),
    Remove(usize),
    Grow(usize),
}

impl Driver {
    /// The driver of `procs` on a scheme whose sizes are integers (`integer`) or not,
    /// with books starting from `number` particles of mass `mass`.
    pub(crate) fn new(procs: Processes, integer: bool, number: u64, mass: f64) -> Self {
        Driver {
            procs,
            books: Books::starting(number, mass),
            pending: None,
            integer,
            origin: 0.0,
        }
    }

    /// Starts the grid of growth instants at `origin`, or keeps `previous`'s when it had
    /// the same growth and step (a host that changes another process mid-step keeps
    /// the step's count).
    pub(crate) fn start(&mut self, origin: f64, previous: Option<&Driver>) {
        let same = |p: &Processes| {
            p.growth == self.procs.growth
                && p.user_growth == self.procs.user_growth
                && p.growth_step == self.procs.growth_step
        };
        self.origin = match previous {
            Some(d) if same(&d.procs) => d.origin,
            _ => origin,
        };
    }

    pub(crate) fn processes(&self) -> &Processes {
        &self.procs
    }

    pub(crate) fn books(&self) -> Books {
        self.books
    }

    /// The host replaced the state: new books from it, the candidate drawn afresh.
    pub(crate) fn rebase<K, F, S: Controls<K, F>>(&mut self, s: &S) -> Result<()> {
        let (n, m) = tally(s)?;
        self.books = Books::starting(n, m);
        self.pending = None;
        Ok(())
    }

    /// The clock was set to `t`: the candidate is drawn afresh, the growth instants
    /// counted from `t`.
    pub(crate) fn forget(&mut self, t: f64) {
        self.pending = None;
        self.origin = t;
    }

    /// A bound of the source's rate in the sim's volume from time `t` until the next
    /// change of a schedule (the rate itself, or a rate function's bound).
    fn source_rate(&self, volume: f64, t: f64) -> f64 {
        self.procs
            .source
            .as_ref()
            .map_or(0.0, |s| s.bound_at(t) * volume)
    }

    /// Whether a candidate at `u` (below the source's bound `src`) injects: always
    /// with a constant or scheduled rate; with a rate function when `u` is below its
    /// value now (thinning within the source's share).
    fn source_keeps(&self, u: f64, volume: f64, t: f64) -> Result<bool> {
        match &self.procs.source {
            Some(q) if q.rate_function().is_some() => Ok(u < q.rate_now(t)? * volume),
            _ => Ok(true),
        }
    }

    /// The total process rate of the state.
    fn rate<K, F, S: Scheme + Controls<K, F> + Observe>(
        &self,
        s: &S,
    ) -> Result<(f64, Option<Held>)> {
        let mut r = self.source_rate(s.volume(), s.time());
        if thinned(&self.procs, self.integer).next().is_none() {
            return Ok((r, None));
        }
        let h = held(s)?;
        for (law, _) in thinned(&self.procs, self.integer) {
            r += total(&h, law)?;
        }
        Ok((r, Some(h)))
    }

    /// Runs `s` to `t` within `budget` with the processes (see the module docs).
    pub(crate) fn advance<K, F, S, G>(
        &mut self,
        s: &mut S,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport>
    where
        S: Scheme + Controls<K, F> + Observe,
        G: Rng + ?Sized,
    {
        if s.runs_processes() {
            // the time-driven mass flow: its own steps carry the processes
            return s.advance_processes(&self.procs, &mut self.books, t, budget, rng);
        }
        crate::scheme::check_target(s.time(), t)?;
        if let Some(h) = self.split()
            && (t - s.time()) / h > MAX_GROWTH_STEPS
        {
            // each step rebuilds the state: refused rather than a call without end
            return Err(Error::OutOfRange {
                name: "growth step (steps in one advance)",
                value: h,
                range: "at least (t - now) / 2^24: split the advance or take a larger step",
            });
        }
        let mut out = StepReport {
            time: s.time(),
            ..StepReport::default()
        };
        loop {
            let (at, bound) = match self.pending {
                Some(p) => p,
                None => {
                    let r = if self.fast(s) {
                        self.bound_fast(s)
                    } else {
                        self.rate(s)?.0
                    };
                    let r = crate::error::finite("total process rate", r)?;
                    let now = s.time();
                    let at = if r > 0.0 {
                        now + Ziggurat::new().sample(rng) / r
                    } else {
                        f64::INFINITY
                    };
                    // the bound holds until a scheduled source changes its rate: a
                    // candidate past that is void there, and drawn afresh
                    let change = self
                        .procs
                        .source
                        .as_ref()
                        .map_or(f64::INFINITY, |q| q.next_change(now));
                    // and until the particles grow by a splitting step (real sizes)
                    let grow = match self.split() {
                        Some(h) => next_growth(h, self.origin, now)?,
                        None => f64::INFINITY,
                    };
                    // (a candidate exactly at an instant comes after it: the next
                    // instant is drawn from the candidate's time, strictly later)
                    let (at, r) = if at <= change && at < grow {
                        (at, r)
                    } else if grow <= change {
                        (grow, GROW)
                    } else {
                        (change, VOID)
                    };
                    self.pending = Some((at, r));
                    (at, r)
                }
            };
            let target = if at <= t { at } else { t };
            budget.set_halt_at_doubling(true);
            let rep = s.advance_within(target, budget, rng);
            budget.set_halt_at_doubling(false);
            let halted = budget.resume();
            let rep = rep?;
            out.accumulate(&rep);
            // every event of the coagulation schemes that take processes is a merge
            self.books.merged = self.books.merged.saturating_add(rep.events);
            if let Some(td) = halted {
                // V and N doubled at td: the bound no longer holds. No event followed
                // (the scheme halts before its next proposal), so the state has stood
                // since td: back to td, where the candidate's residual wait (exponential)
                // and the scheme's next proposal are drawn afresh — the same whether or
                // not the call's target came first, so a split run keeps its bits.
                for _ in 0..rep.doublings {
                    self.books.double();
                }
                s.set_time(td)?;
                self.pending = None;
                out.interrupted = false;
                out.time = td;
                continue;
            }
            if rep.interrupted {
                return Ok(out);
            }
            if at > t {
                out.time = s.time();
                return Ok(out);
            }
            if bound == VOID || bound == GROW {
                // a scheduled rate changes here, or the particles grow by a step: the
                // candidate is drawn afresh
                if bound == GROW {
                    if !budget.take(1) {
                        out.interrupted = true;
                        out.time = s.time();
                        return Ok(out);
                    }
                    self.grow_all(s)?;
                }
                self.pending = None;
                out.time = s.time();
                if at >= t {
                    return Ok(out);
                }
                continue;
            }
            // the candidate at `at`, where the scheme stands
            if !budget.take(1) {
                out.interrupted = true;
                out.time = s.time();
                return Ok(out);
            }
            self.candidate(s, bound, rng)?;
            self.pending = None;
            out.time = s.time();
            if at >= t {
                return Ok(out);
            }
        }
    }

    /// The splitting step when growth on real sizes is split off.
    fn split(&self) -> Option<f64> {
        if self.integer || !self.procs.grows() {
            None
        } else {
            self.procs.growth_step
        }
    }

    /// Every particle grows by one splitting step (real sizes; on error, the state and
    /// the books are unchanged).
    fn grow_all<K, F, S: Controls<K, F>>(&mut self, s: &mut S) -> Result<()> {
        let (Some(h), State::Sizes(x)) = (self.split(), s.state()) else {
            return Err(Error::Unsupported {
                what: "growth by splitting on integer sizes (growth is monomer attachment there)",
            });
        };
        if x.is_empty() {
            return Ok(()); // (an emptied population waits for its source)
        }
        let mut y = Vec::new();
        try_reserve(&mut y, x.len())?;
        let (mut before, mut after) = (0.0, 0.0);
        for &xi in x {
            let g = crate::error::finite("grown size", self.procs.grow(xi, h)?)?;
            before += xi;
            after += g;
            y.push(g);
        }
        s.set_sizes(&y)?;
        s.set_doubling(false);
        self.books.grown_mass += after - before;
        Ok(())
    }

    /// Whether the scheme edits single particles: then a process event costs a draw
    /// and an edit, not a state replacement. On integer sizes every process has its
    /// bound (`x^p ≤ 1` or `≤ x` on sizes ≥ 1); on real sizes only a size-independent
    /// removal does (sizes may be below 1), and only a scheme that draws by mass
    /// takes a removal or growth at a positive power.
    fn fast<K, F, S: Controls<K, F>>(&self, s: &S) -> bool {
        if !s.edits() {
            return false;
        }
        let by_mass = thinned(&self.procs, self.integer)
            .any(|(l, _)| matches!(l, Rate::Power(p) if p.exponent > 0.0));
        if self.integer {
            return !by_mass || s.draws_by_mass();
        }
        // (a user rate has its bound at every size: uniform draws; growth is split off)
        self.procs.removal.is_none_or(|p| p.exponent == 0.0)
    }

    /// The bound of the edited path: `S V`, and for removal and growth `c N` (exponent
    /// ≤ 0: `c x^p ≤ c` on sizes ≥ 1) or `c M1` (exponent in (0, 1]: `c x^p ≤ c x`),
    /// a user rate's bound times N; merging keeps M1 and lowers N, so it holds until
    /// the next process event.
    fn bound_fast<K, F, S: Scheme + Controls<K, F> + Observe>(&self, s: &S) -> f64 {
        let mut r = self.source_rate(s.volume(), s.time());
        for (law, _) in thinned(&self.procs, self.integer) {
            r += self.law_bound(s, law);
        }
        r
    }

    /// One law's share of the edited path's bound, and whether it draws by mass.
    fn law_bound<K, F, S: Controls<K, F> + Observe>(&self, s: &S, law: Rate<'_>) -> f64 {
        let (n, m) = (s.particles() as f64, self.books.current_mass());
        match law {
            Rate::Power(p) if p.exponent > 0.0 => p.coefficient * m,
            Rate::Power(p) => p.coefficient * n,
            Rate::User(u) => u.bound() * n,
        }
    }

    /// The candidate on the edited path: a particle drawn uniformly (exponent ≤ 0) or
    /// by mass, accepted with its rate over the component's bound per particle.
    fn candidate_fast<K, F, S, G>(&mut self, s: &mut S, bound: f64, rng: &mut G) -> Result<()>
    where
        S: Scheme + Controls<K, F> + Observe,
        G: Rng + ?Sized,
    {
        let mut u = open_unit(rng) * bound;
        let src = self.source_rate(s.volume(), s.time());
        if u < src {
            if !self.source_keeps(u, s.volume(), s.time())? {
                return Ok(()); // thinned
            }
            let source = self.procs.source.as_ref().ok_or(Error::Empty)?;
            let x = source.draw(self.integer, rng);
            s.add_particle(x)?;
            self.books.injected_number += 1;
            self.books.injected_mass += x;
            return Ok(());
        }
        u -= src;
        let procs = self.procs.clone();
        for (law, grow) in thinned(&procs, self.integer) {
            let w = self.law_bound(s, law);
            if u >= w {
                u -= w;
                continue;
            }
            let by_mass = matches!(law, Rate::Power(p) if p.exponent > 0.0);
            let Some((xf, h)) = s.draw_particle(by_mass, rng) else {
                return Ok(());
            };
            // the rate over its bound: x^p ≤ 1, x^p / x ≤ 1, or f(x) / bound ≤ 1
            let keep = match law {
                Rate::Power(p) if by_mass => p.at(xf) / (p.coefficient * xf),
                Rate::Power(p) => p.at(xf) / p.coefficient,
                Rate::User(q) => q.at(xf)? / q.bound(),
            };
            if open_unit(rng) >= keep {
                return Ok(());
            }
            s.remove_drawn(xf, h)?;
            if grow {
                if let Err(e) = s.add_particle(xf + 1.0) {
                    // (back as it was: a size that was there fits)
                    s.add_particle(xf)?;
                    return Err(e);
                }
                self.books.grown_mass += 1.0;
            } else {
                self.books.removed_number += 1;
                self.books.removed_mass += xf;
            }
            return Ok(());
        }
        Ok(())
    }

    /// Decides and applies the candidate (on error the state and books are unchanged;
    /// the candidate stays pending).
    fn candidate<K, F, S, G>(&mut self, s: &mut S, bound: f64, rng: &mut G) -> Result<()>
    where
        S: Scheme + Controls<K, F> + Observe,
        G: Rng + ?Sized,
    {
        if self.fast(s) {
            return self.candidate_fast(s, bound, rng);
        }
        let mut u = open_unit(rng) * bound;
        let src = self.source_rate(s.volume(), s.time());
        let event = if u < src {
            if !self.source_keeps(u, s.volume(), s.time())? {
                return Ok(()); // thinned
            }
            let source = self.procs.source.as_ref().ok_or(Error::Empty)?;
            Some((Event::Inject(source.draw(self.integer, rng)), None))
        } else {
            u -= src;
            let (_, h) = self.rate(s)?;
            let mut chosen = None;
            if let Some(h) = h {
                for (law, grow) in thinned(&self.procs, self.integer) {
                    let w = total(&h, law)?;
                    if u < w {
                        let k = pick(&h, law, u)?;
                        if !keep(law, size_of(&h, k), rng)? {
                            break; // thinned
                        }
                        chosen = Some(if grow {
                            Event::Grow(k)
                        } else {
                            Event::Remove(k)
                        });
                        break;
                    }
                    u -= w;
                }
                chosen.map(|e| (e, Some(h)))
            } else {
                None
            }
        };
        let Some((event, h)) = event else {
            return Ok(()); // thinned
        };
        let h = match h {
            Some(h) => h,
            None => held(s)?,
        };
        self.apply(s, h, event)
    }

    fn apply<K, F, S>(&mut self, s: &mut S, h: Held, event: Event) -> Result<()>
    where
        S: Controls<K, F> + Observe,
    {
        let volume = s.volume();
        let mut books = self.books;
        match h {
            Held::Counts(mut v) => {
                match event {
                    Event::Inject(x) => {
                        let i = x as u64;
                        match v.binary_search_by_key(&i, |p| p.0) {
                            Ok(k) => v[k].1 += 1,
                            Err(k) => {
                                try_reserve(&mut v, 1)?;
                                v.insert(k, (i, 1));
                            }
                        }
                        books.injected_number += 1;
                        books.injected_mass += x;
                    }
                    Event::Remove(k) => {
                        v[k].1 -= 1;
                        books.removed_number += 1;
                        books.removed_mass += v[k].0 as f64;
                    }
                    Event::Grow(k) => {
                        let i = v[k].0;
                        v[k].1 -= 1;
                        match v.binary_search_by_key(&(i + 1), |p| p.0) {
                            Ok(j) => v[j].1 += 1,
                            Err(j) => {
                                try_reserve(&mut v, 1)?;
                                v.insert(j, (i + 1, 1));
                            }
                        }
                        books.grown_mass += 1.0;
                    }
                }
                v.retain(|p| p.1 > 0);
                let (mut sizes, mut counts) = (Vec::new(), Vec::new());
                try_reserve(&mut sizes, v.len())?;
                try_reserve(&mut counts, v.len())?;
                sizes.extend(v.iter().map(|p| p.0));
                counts.extend(v.iter().map(|p| p.1));
                s.set_pairs(&sizes, &counts, volume)?;
                s.set_doubling(false);
            }
            Held::Sizes(mut x) => {
                match event {
                    Event::Inject(y) => {
                        x.push(y);
                        books.injected_number += 1;
                        books.injected_mass += y;
                    }
                    Event::Remove(k) => {
                        books.removed_number += 1;
                        books.removed_mass += x[k];
                        x.swap_remove(k);
                    }
                    Event::Grow(_) => {
                        return Err(Error::Unsupported {
                            what: "growth on a scheme over real sizes (growth by monomer attachment runs on integer sizes: lowrank)",
                        });
                    }
                }
                s.set_sizes(&x)?;
                s.set_doubling(false);
            }
        }
        self.books = books;
        Ok(())
    }
}
