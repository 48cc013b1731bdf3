//! Sources, removal and growth beside coagulation (issue 42), on every scheme of the
//! registry that takes them: the books balance exactly; removal and growth alone follow
//! their exact finite-N laws; a source and a sink with the constant kernel follow the
//! exact finite-N master equation; checkpoints split = unbroken; schemes that take no
//! processes refuse them and stay as they were.

use crate::common;

use coagula_core::Error;
use coagula_core::initial::Distribution;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::Replicas;
use coagula_core::process::{Books, Processes, Source, UserRate};
use coagula_core::scheme::facade::{
    BucketMode, Init, InitKind, Law, Model, Options, SchemeId, State,
};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// The finite-N schemes that take processes (the time-driven mass flow takes them
/// too: `processes_massflow.rs`).
pub(crate) fn process_schemes() -> Vec<V> {
    let p = Processes::default().with_removal(1.0, 0.0).unwrap();
    let mut v: Vec<V> = registry::SCHEMES
        .iter()
        .copied()
        .filter(|s| s.takes_processes(&p).is_ok() && s.law == Law::FiniteN)
        .map(|info| V { info, slots: false })
        .collect();
    // the default scheme's slot engine too (small systems run its counted engine)
    v.push(V {
        info: registry::find("lowrank").unwrap(),
        slots: true,
    });
    v
}

/// A scheme of the registry, and for `lowrank` which engine it is pinned to.
#[derive(Clone, Copy)]
pub(crate) struct V {
    info: SchemeId,
    slots: bool,
}

impl std::ops::Deref for V {
    type Target = coagula_core::scheme::facade::SchemeInfo;
    fn deref(&self) -> &Self::Target {
        self.info
    }
}

impl V {
    pub(crate) fn label(&self) -> String {
        if self.slots {
            format!("{} (slots)", self.info.name)
        } else {
            self.info.name.to_string()
        }
    }
}

/// A sim of `id` from `counts` in `volume` (as particle sizes for a sizes scheme).
pub(crate) fn sim(id: V, k: Coagulation, counts: &[u64], volume: f64) -> Box<common::Sim> {
    let model = Model::coagulation(k, NoFragmentation);
    if id.inits.contains(&InitKind::Counts) {
        let init = Init::Counts { counts, volume };
        let opts = if id.slots {
            Options::default().with_engine(Some(BucketMode::Slots))
        } else {
            Options::default()
        };
        let s = registry::build(id.info, model, &init, &opts).unwrap();
        assert_eq!(
            id.slots,
            s.engine() == Some(BucketMode::Slots),
            "{}",
            id.label()
        );
        return s;
    }
    let mut sizes = Vec::new();
    for (i, &c) in counts.iter().enumerate() {
        sizes.extend(std::iter::repeat_n((i + 1) as f64, c as usize));
    }
    let n = sizes.len() as f64;
    // mass per unit volume: the sizes' sum over `volume`
    let init = Init::Sizes {
        sizes: &sizes,
        mass: sizes.iter().sum::<f64>() / volume,
    };
    // a fixed-capacity scheme gets room for what the sources bring
    let opts = if id.takes_option("capacity") {
        Options::default().with_capacity(sizes.len() * 8 + 64)
    } else {
        Options::default()
    };
    let s = registry::build(id.info, model, &init, &opts).unwrap();
    assert!((s.volume() - volume).abs() < 1e-9 * volume, "{n} particles");
    s
}

/// Particle number and mass of the state.
fn tally(s: &common::Sim) -> (u64, f64) {
    match s.state() {
        State::Sizes(x) => (x.len() as u64, x.iter().sum()),
        State::Counts(..) => {
            let (mut n, mut m) = (0u64, 0u64);
            s.for_each_count(&mut |i, c| {
                n += c;
                m += i * c;
            })
            .unwrap();
            (n, m as f64)
        }
    }
}

pub(crate) use common::checkpoint;

pub(crate) fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

pub(crate) fn monomers(rate: f64) -> Source {
    Source::new(rate, Distribution::Monodisperse { size: 1.0 }).unwrap()
}

/// Every process alone and all together, on integer and on real sizes.
fn cases(integer: bool) -> Vec<(&'static str, Processes)> {
    let mut v = vec![
        (
            "monomer source",
            Processes::default().with_source(monomers(0.5)),
        ),
        (
            "exponential source",
            Processes::default()
                .with_source(Source::new(0.5, Distribution::Exponential { mean: 3.0 }).unwrap()),
        ),
        (
            "listed source",
            Processes::default()
                .with_source(Source::new(0.5, Distribution::Counts(vec![0, 2, 0, 1])).unwrap()),
        ),
        (
            "dilution",
            Processes::default().with_removal(0.3, 0.0).unwrap(),
        ),
        (
            "deposition x^1",
            Processes::default().with_removal(0.1, 1.0).unwrap(),
        ),
        (
            "deposition x^-1",
            Processes::default().with_removal(0.5, -1.0).unwrap(),
        ),
        (
            "background dilution",
            Processes::dilution(0.2, 0.5, Distribution::Exponential { mean: 2.0 }).unwrap(),
        ),
        (
            "user removal",
            Processes::default()
                .with_user_removal(UserRate::new(|x: f64| 0.8 / (1.0 + x), 0.8, 1).unwrap()),
        ),
        (
            "scheduled source",
            Processes::default().with_source(
                monomers(0.2)
                    .with_schedule(&[0.5, 1.3, 2.0], &[1.0, 0.0, 0.6])
                    .unwrap(),
            ),
        ),
    ];
    if !integer {
        // growth by splitting (growth.rs checks its accuracy)
        v.push((
            "split growth",
            Processes::default()
                .with_growth(0.1, 1.0)
                .unwrap()
                .with_growth_step(0.3)
                .unwrap(),
        ));
        v.push((
            "split user growth and removal",
            Processes::default()
                .with_user_growth(UserRate::new(|x: f64| 0.3 * x / (1.0 + x), 0.3, 2).unwrap())
                .with_user_removal(UserRate::new(|x: f64| 0.2 / x, 0.2, 3).unwrap())
                .with_growth_step(0.3)
                .unwrap(),
        ));
    }
    if integer {
        v.push((
            "growth",
            Processes::default().with_growth(0.3, 0.0).unwrap(),
        ));
        v.push((
            "linear growth",
            Processes::default().with_growth(0.1, 1.0).unwrap(),
        ));
        v.push((
            "user growth and removal",
            Processes::default()
                .with_user_growth(UserRate::new(|x: f64| 0.3 * x / (1.0 + x), 0.3, 2).unwrap())
                .with_user_removal(UserRate::new(|x: f64| 0.2 / x, 0.2, 3).unwrap()),
        ));
        v.push((
            "all",
            Processes::dilution(0.2, 0.5, Distribution::Monodisperse { size: 1.0 })
                .unwrap()
                .with_growth(0.2, 1.0 / 3.0)
                .unwrap(),
        ));
    }
    v
}

fn balance(b: &Books, s: &common::Sim, what: &str) {
    let (n, m) = tally(s);
    assert_eq!(b.current_number(), n, "{what}: number");
    if matches!(s.state(), State::Counts(..)) {
        assert_eq!(b.current_mass(), m, "{what}: mass (exact on integer sizes)");
    } else {
        assert!(
            (b.current_mass() - m).abs() <= 1e-12 * m.max(1.0),
            "{what}: mass {} vs {m}",
            b.current_mass()
        );
    }
}

#[test]
fn the_books_balance_on_every_scheme_and_process() {
    let schemes = process_schemes();
    let names: Vec<String> = schemes.iter().map(|s| s.label()).collect();
    assert_eq!(names.len(), 10, "{names:?}");
    for id in schemes {
        let integer = id.inits.contains(&InitKind::Counts);
        for (what, p) in cases(integer) {
            let what = format!("{} / {what}", id.label());
            let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[60, 20, 5], 40.0);
            s.set_processes(Some(p.clone())).unwrap();
            let mut g = rng(3);
            let mut events = 0;
            for k in 1..=20 {
                s.advance_to(0.5 * f64::from(k), &mut g).unwrap();
                let b = s.books().unwrap();
                balance(&b, &*s, &what);
                events = b.injected_number + b.removed_number + b.grown_mass as u64;
            }
            assert!(events > 10, "{what}: only {events} process events");
            // doubling is off while processes run (dilution takes N far below N0/2)
            assert_eq!(s.totals().doublings, 0, "{what}");
            assert_eq!(s.books().unwrap().doublings, 0, "{what}");
        }
    }
}

#[test]
fn schemes_without_processes_refuse_them_and_stay_as_they_were() {
    let p = Processes::default().with_removal(0.3, 0.0).unwrap();
    for &id in registry::SCHEMES {
        if id.takes_processes(&p).is_ok() {
            continue;
        }
        let Some(mut s) = common::standard(id, 64, Coagulation::constant(1.0).unwrap()) else {
            continue;
        };
        let before = s.particles();
        match s.set_processes(Some(p.clone())) {
            Err(Error::Unsupported { what }) => {
                assert!(what.contains("lowrank"), "{}: {what}", id.name)
            }
            other => panic!("{}: {other:?}", id.name),
        }
        assert!(s.processes().is_none() && s.books().is_none());
        assert_eq!(s.particles(), before);
    }
}

#[test]
fn bad_processes_are_refused() {
    assert!(Source::new(-1.0, Distribution::Monodisperse { size: 1.0 }).is_err());
    assert!(Source::new(f64::NAN, Distribution::Monodisperse { size: 1.0 }).is_err());
    assert!(Source::new(1.0, Distribution::Monodisperse { size: 0.0 }).is_err());
    assert!(
        Source::new(
            1.0,
            Distribution::Lognormal {
                median: 1.0,
                gsd: 0.5
            }
        )
        .is_err()
    );
    for p in [1.5, f64::NAN, f64::INFINITY, -11.0] {
        assert!(Processes::default().with_removal(1.0, p).is_err(), "{p}");
        assert!(Processes::default().with_growth(1.0, p).is_err(), "{p}");
    }
    assert!(Processes::default().with_removal(-1.0, 0.0).is_err());
    assert!(
        Processes::default()
            .with_removal(f64::INFINITY, 0.0)
            .is_err()
    );
}

/// Removal alone (coagulation negligible): each particle of size i survives to t with
/// probability e^{−λ(i) t}, independently — binomial totals over the replicas.
#[test]
fn removal_alone_is_exponential_per_size() {
    let (reps, t) = (400u64, 1.5);
    let counts = [40u64, 30, 0, 20];
    let (c, p) = (0.3, 0.5);
    for id in process_schemes() {
        let mut kept = [0u64; 4];
        for r in 0..reps {
            let mut s = sim(id, Coagulation::constant(1e-12).unwrap(), &counts, 100.0);
            s.set_processes(Some(Processes::default().with_removal(c, p).unwrap()))
                .unwrap();
            s.advance_to(t, &mut rng(r + 11)).unwrap();
            let mut at = |i: u64, n: u64| kept[i as usize - 1] += n;
            match s.state() {
                State::Sizes(x) => x.iter().for_each(|&y| at(y as u64, 1)),
                State::Counts(..) => s.for_each_count(&mut at).unwrap(),
            }
        }
        for (i, &n0) in counts.iter().enumerate() {
            if n0 == 0 {
                continue;
            }
            let q = (-c * ((i + 1) as f64).powf(p) * t).exp();
            let trials = (reps * n0) as f64;
            let z = (kept[i] as f64 - trials * q) / (trials * q * (1.0 - q)).sqrt();
            assert!(z.abs() < 5.0, "{} size {}: z = {z:.2}", id.label(), i + 1);
        }
    }
}

/// Growth alone on integer sizes: at constant G = g each particle gains Poisson(g t)
/// monomers; at G(i) = g i (a Yule process) a particle of size i has mean size
/// i e^{gt} and variance i e^{gt}(e^{gt} − 1).
#[test]
fn growth_alone_follows_the_attachment_chain() {
    let (reps, t) = (300u64, 1.2);
    let counts = [30u64, 10];
    let n0: u64 = counts.iter().sum();
    let m0 = 30.0 + 20.0;
    for id in process_schemes()
        .into_iter()
        .filter(|s| s.inits.contains(&InitKind::Counts))
    {
        for (g, q) in [(0.4, 0.0), (0.3, 1.0)] {
            let mut mass = 0.0;
            for r in 0..reps {
                let mut s = sim(id, Coagulation::constant(1e-12).unwrap(), &counts, 100.0);
                s.set_processes(Some(Processes::default().with_growth(g, q).unwrap()))
                    .unwrap();
                s.advance_to(t, &mut rng(r + 1000)).unwrap();
                mass += tally(&*s).1;
            }
            let (mean, var) = if q == 0.0 {
                let a = n0 as f64 * g * t;
                (m0 + a, a)
            } else {
                let e = (g * t).exp();
                (m0 * e, m0 * e * (e - 1.0))
            };
            let z = (mass - reps as f64 * mean) / (reps as f64 * var).sqrt();
            assert!(z.abs() < 5.0, "{} G = {g} i^{q}: z = {z:.2}", id.label());
        }
    }
}

/// The exact finite-N law of the constant kernel K = 1 with a monomer source S V and
/// removal λ N (no particle doubling: it is off while processes run), a birth–death
/// chain on N solved by uniformisation; returns E[N/V] at `times`.
fn source_sink_reference(s: f64, lambda: f64, n_start: u64, v: f64, times: &[f64]) -> Vec<f64> {
    scheduled_reference(&[(0.0, s)], lambda, n_start, v, times)
}

/// As [`source_sink_reference`] with a source rate `pieces[k].1` from time
/// `pieces[k].0` on (0 before the first).
pub(crate) fn scheduled_reference(
    pieces: &[(f64, f64)],
    lambda: f64,
    n_start: u64,
    v: f64,
    times: &[f64],
) -> Vec<f64> {
    const NMAX: usize = 160;
    let s_max = pieces.iter().map(|p| p.1).fold(0.0, f64::max);
    let rate_down = |n: usize| (n * n.saturating_sub(1)) as f64 / (2.0 * v) + lambda * n as f64;
    let big = (0..=NMAX)
        .map(|n| rate_down(n) + s_max * v)
        .fold(0.0, f64::max)
        * 1.01;
    let mut p = vec![0.0; NMAX + 1];
    p[n_start as usize] = 1.0;
    let mut out = Vec::new();
    let mut now = 0.0;
    for &t in times {
        // in pieces of a ≤ 20 expected jumps (no underflow of e^{-a})
        while now < t {
            // (within one piece of the schedule)
            let k = pieces.partition_point(|p| p.0 <= now);
            let s = if k == 0 { 0.0 } else { pieces[k - 1].1 };
            let until = pieces.get(k).map_or(f64::INFINITY, |p| p.0);
            let rate_up = |n: usize| if n < NMAX { s * v } else { 0.0 };
            let dt = (t - now).min(20.0 / big).min(until - now);
            let a = big * dt;
            let mut term = p.clone();
            let mut weight = (-a).exp();
            let mut acc: Vec<f64> = term.iter().map(|x| x * weight).collect();
            let mut k = 0u32;
            while f64::from(k) < a || weight > 1e-18 {
                k += 1;
                let mut next = vec![0.0; NMAX + 1];
                for (n, &pn) in term.iter().enumerate() {
                    let (down, up) = (rate_down(n), rate_up(n));
                    next[n] += pn * (1.0 - (down + up) / big);
                    if n > 0 {
                        next[n - 1] += pn * down / big;
                    }
                    if n < NMAX {
                        next[n + 1] += pn * up / big;
                    }
                }
                term = next;
                weight *= a / f64::from(k);
                for (x, y) in acc.iter_mut().zip(&term) {
                    *x += y * weight;
                }
            }
            p = acc;
            now += dt;
        }
        assert!(p[NMAX] < 1e-12, "the truncation holds {}", p[NMAX]);
        out.push(p.iter().enumerate().map(|(n, q)| q * n as f64 / v).sum());
    }
    out
}

/// Every scheme that takes processes against the exact finite-N law of a source and a
/// sink (above), with N0 = V = 16: at N ~ 16 an error of O(1/N) (a rate off by
/// N/(N − 1), a process applied to the wrong volume) moves E[N/V] by several percent,
/// many standard errors of 3000 replicas. E[M1/V] = S/λ + (m0 − S/λ) e^{−λt} holds
/// exactly at any N (it is linear), and is checked too.
#[test]
fn a_source_and_a_sink_follow_the_finite_n_master_equation() {
    let (s_rate, lambda, n0, v0) = (1.0, 0.5, 16u64, 16.0);
    let times = [0.5, 2.0];
    let exact = source_sink_reference(s_rate, lambda, n0, v0, &times);
    let reps = 3000u64;
    let z_max = common::z_max(reps);
    let mut failures = String::new();
    for (k, id) in process_schemes().into_iter().enumerate() {
        let mut number = vec![Replicas::new(); times.len()];
        let mut mass = vec![Replicas::new(); times.len()];
        for r in 0..reps {
            let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[n0], v0);
            let p = Processes::default()
                .with_source(monomers(s_rate))
                .with_removal(lambda, 0.0)
                .unwrap();
            s.set_processes(Some(p)).unwrap();
            let mut g = rng((k as u64) << 32 | r);
            for (i, &t) in times.iter().enumerate() {
                s.advance_to(t, &mut g).unwrap();
                number[i].push(s.particles() as f64 / s.volume());
                mass[i].push(s.moment(1.0));
            }
        }
        for (i, &t) in times.iter().enumerate() {
            let m_exact = s_rate / lambda + (1.0 - s_rate / lambda) * (-lambda * t).exp();
            for (what, st, want) in [
                ("E[N/V]", &number[i], exact[i]),
                ("E[M1/V]", &mass[i], m_exact),
            ] {
                let z = (st.mean() - want) / st.std_error();
                if z.abs() > z_max {
                    failures += &format!(
                        "{} t = {t} {what}: {:.5} vs exact {want:.5} (z = {z:.2})\n",
                        id.label(),
                        st.mean()
                    );
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

/// Failures of E[N/V] against `exact` at `times` over `reps` replicas of every scheme
/// that takes processes, from N0 = V = 16 under the constant kernel with the processes
/// `procs()` (replica r of variant k on the generator `seed | k << 32 | r`).
pub(crate) fn chain_failures(
    procs: impl Fn() -> Processes,
    times: &[f64],
    exact: &[f64],
    reps: u64,
    seed: u64,
) -> String {
    let z_max = common::z_max(reps);
    let mut failures = String::new();
    for (k, id) in process_schemes().into_iter().enumerate() {
        let mut number = vec![Replicas::new(); times.len()];
        for r in 0..reps {
            let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[16], 16.0);
            s.set_processes(Some(procs())).unwrap();
            let mut g = rng(seed | (k as u64) << 32 | r);
            for (i, &t) in times.iter().enumerate() {
                s.advance_to(t, &mut g).unwrap();
                number[i].push(s.particles() as f64 / s.volume());
            }
        }
        for (i, &t) in times.iter().enumerate() {
            let z = (number[i].mean() - exact[i]) / number[i].std_error();
            if z.abs() > z_max {
                failures += &format!(
                    "{} t = {t}: E[N/V] {:.5} vs exact {:.5} (z = {z:.2})\n",
                    id.label(),
                    number[i].mean(),
                    exact[i]
                );
            }
        }
    }
    failures
}

/// A host's rates against the exact laws of their powers: a constant user removal
/// drawn against a bound four times its value follows the same finite-N chain as
/// `with_removal` (a source and a sink, N0 = V = 16); a user rate above its bound is an
/// error that leaves the state as before the event.
#[test]
fn user_rates_follow_the_finite_n_master_equation() {
    let (s_rate, lambda) = (1.0, 0.5);
    let times = [0.5, 2.0];
    let exact = source_sink_reference(s_rate, lambda, 16, 16.0, &times);
    let procs = || {
        Processes::default()
            .with_source(monomers(s_rate))
            .with_user_removal(UserRate::new(move |_| lambda, 4.0 * lambda, 9).unwrap())
    };
    let failures = chain_failures(procs, &times, &exact, 3000, 0x05e4 << 40);
    for id in process_schemes() {
        // a rate above its bound: an error, the state as it was
        let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[16], 16.0);
        let p = Processes::default().with_user_removal(UserRate::new(|_| 2.0, 1.0, 9).unwrap());
        s.set_processes(Some(p)).unwrap();
        let mut g = rng(1);
        let e = s.advance_to(50.0, &mut g).unwrap_err();
        assert!(
            matches!(e, coagula_core::Error::BoundExceeded { .. }),
            "{}: {e}",
            id.label()
        );
        let (before, t) = (common::state_bits(&*s), s.time());
        assert!(s.advance_to(60.0, &mut g).is_err(), "{}", id.label());
        assert_eq!(s.time(), t, "{}", id.label());
        assert_eq!(common::state_bits(&*s), before, "{}", id.label());
    }
    assert!(failures.is_empty(), "{failures}");
}

/// A source that follows a schedule (on, off, on at another rate) with a sink, against
/// the same finite-N chain run piece by piece, on every scheme that takes processes: a
/// candidate that ran past a change with the old rate's bound (or a change missed)
/// moves E[N/V] by many standard errors.
#[test]
fn a_scheduled_source_follows_the_finite_n_master_equation() {
    let lambda = 0.5;
    let (times_s, rates_s) = ([0.2, 0.7, 1.5], [2.0, 0.0, 0.8]);
    let pieces: Vec<(f64, f64)> = [(0.0, 0.3)]
        .into_iter()
        .chain(times_s.iter().copied().zip(rates_s))
        .collect();
    let times = [0.7, 1.5, 2.5];
    let exact = scheduled_reference(&pieces, lambda, 16, 16.0, &times);
    let procs = || {
        let src = monomers(0.3).with_schedule(&times_s, &rates_s).unwrap();
        Processes::default()
            .with_source(src)
            .with_removal(lambda, 0.0)
            .unwrap()
    };
    let failures = chain_failures(procs, &times, &exact, 3000, 0x5ced << 40);
    assert!(failures.is_empty(), "{failures}");
}

/// A run split at any times, through a checkpoint into a fresh sim, gives the bits of an
/// unbroken one (the pending candidate and the books travel in the envelope); a
/// checkpoint with processes is refused by a sim without them, and the other way round.
#[test]
fn split_runs_through_checkpoints_keep_their_bits() {
    for id in process_schemes() {
        let integer = id.inits.contains(&InitKind::Counts);
        let p = Processes::dilution(0.3, 0.5, Distribution::Monodisperse { size: 1.0 }).unwrap();
        // (the inflow follows a schedule: splits at one of its changes and between)
        let inflow = p.source.clone().unwrap();
        let p = p.with_source(
            inflow
                .with_schedule(&[0.3, 1.0, 2.6], &[0.0, 0.4, 0.1])
                .unwrap(),
        );
        let p = if integer {
            p.with_growth(0.1, 1.0).unwrap()
        } else {
            p
        };
        let make = || {
            let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[100, 30], 50.0);
            s.set_processes(Some(p.clone())).unwrap();
            s
        };
        let mut whole = make();
        let mut g = rng(5);
        whole.advance_to(4.0, &mut g).unwrap();
        let mut split = make();
        let mut h = rng(5);
        for t in [0.3, 1.1, 2.5] {
            split.advance_to(t, &mut h).unwrap();
            let buf = checkpoint(&*split);
            let len = buf.len();
            let mut fresh = make();
            fresh.restore_checkpoint(&buf[..len]).unwrap();
            // a sim without processes refuses it, and is unchanged
            let mut bare = sim(id, Coagulation::constant(1.0).unwrap(), &[100, 30], 50.0);
            let before = common::state_bits(&*bare);
            assert!(
                bare.restore_checkpoint(&buf[..len]).is_err(),
                "{}",
                id.label()
            );
            assert_eq!(common::state_bits(&*bare), before);
            split = fresh;
        }
        split.advance_to(4.0, &mut h).unwrap();
        assert_eq!(
            common::state_bits(&*whole),
            common::state_bits(&*split),
            "{}",
            id.label()
        );
        assert_eq!(whole.books(), split.books(), "{}", id.label());
        let b = whole.books().unwrap();
        assert!(
            b.injected_number > 0 && b.removed_number > 0,
            "{}: {b:?}",
            id.label()
        );
        // a duplicate continues identically
        let mut copy = whole.duplicate().unwrap();
        let (mut g1, mut g2) = (rng(9), rng(9));
        whole.advance_to(6.0, &mut g1).unwrap();
        copy.advance_to(6.0, &mut g2).unwrap();
        assert_eq!(common::state_bits(&*whole), common::state_bits(&*copy));
        assert_eq!(whole.books(), copy.books());
    }
}

/// Any real number, the hostile ones often.
pub(crate) fn hostile() -> impl proptest::strategy::Strategy<Value = f64> {
    use proptest::prelude::*;
    prop_oneof![
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(-1.0),
        1 => Just(0.0),
        1 => Just(1e300),
        1 => Just(f64::MIN_POSITIVE),
        1 => any::<f64>(),
        6 => 0.0f64..3.0,
    ]
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Arbitrary process parameters on every scheme that takes them: a constructor or
    /// `set_processes` refuses, or the sim runs a short step under a work limit; a
    /// checkpoint with one byte changed restores or is refused with the sim unchanged.
    #[test]
    fn processes_never_panic(
        which in 0usize..9,
        rate in hostile(),
        kind in 0usize..3,
        p1 in hostile(),
        p2 in hostile(),
        c in hostile(),
        p in hostile(),
        g in hostile(),
        q in hostile(),
        t in hostile(),
        h in hostile(),
        flip in proptest::prelude::any::<usize>(),
        value in proptest::prelude::any::<u8>(),
    ) {
        let id = process_schemes()[which % process_schemes().len()];
        let sizes = match kind {
            0 => Distribution::Monodisperse { size: p1 },
            1 => Distribution::Exponential { mean: p1 },
            _ => Distribution::Lognormal { median: p1, gsd: p2 },
        };
        let mut procs = Processes::default();
        if let Ok(s) = Source::new(rate, sizes) {
            procs = procs.with_source(s);
        }
        if let Ok(r) = procs.clone().with_removal(c, p) {
            procs = r;
        }
        if let Ok(r) = procs.clone().with_growth(g, q) {
            procs = r;
        }
        if let Ok(r) = procs.clone().with_growth_step(h) {
            procs = r;
        }
        let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[30, 5], 30.0);
        let before = common::state_bits(&*s);
        if s.set_processes(Some(procs)).is_err() {
            proptest::prop_assert_eq!(common::state_bits(&*s), before);
            return Ok(());
        }
        let mut g = rng(1);
        let t = if t.is_finite() { t.clamp(-1.0, 3.0) } else { t };
        let _ = s.advance_within(t, &mut coagula_core::scheme::Budget::work(20_000), &mut g);
        // whatever was refused on the way, the books still count the particles
        if let Some(b) = s.books() {
            proptest::prop_assert_eq!(b.current_number(), s.particles());
        }
        common::corrupted_checkpoint(&mut *s, flip, value, &mut g)?;
    }
}

/// The real-size schemes edit single particles: a system that the sink empties waits
/// for the source and fills again, a source below every size present enters (lowrank
/// over sizes rebuilds its buckets then), and the books balance throughout.
#[test]
fn real_size_schemes_empty_and_refill_through_edits() {
    let p = Processes::default()
        .with_source(Source::new(0.2, Distribution::Sizes(vec![0.5, 2.0])).unwrap())
        .with_removal(5.0, 0.0)
        .unwrap();
    for v in process_schemes() {
        if v.inits.contains(&InitKind::Counts) {
            continue;
        }
        let mut s = sim(v, Coagulation::constant(1.0).unwrap(), &[3], 1.0);
        s.set_processes(Some(p.clone())).unwrap();
        let mut r = rng(17);
        let (mut empty, mut small) = (0, 0);
        for k in 1..=400 {
            s.advance_to(0.25 * f64::from(k), &mut r).unwrap();
            empty += u32::from(s.particles() == 0);
            if let State::Sizes(x) = s.state() {
                small += u32::from(x.contains(&0.5));
            }
            balance(&s.books().unwrap(), &*s, &v.label());
        }
        assert!(
            empty > 100 && small > 0,
            "{}: empty {empty}, small {small}",
            v.label()
        );
        let b = s.books().unwrap();
        // (20 injections expected over t = 100)
        assert!(
            b.injected_number > 5 && b.removed_number > 5,
            "{}: {b:?}",
            v.label()
        );
    }
}
