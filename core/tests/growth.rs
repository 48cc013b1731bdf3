//! Growth on real sizes by Strang splitting (issue 42): the closed form per particle
//! at every step, the fourth order of the host-rate integrator, and the exact
//! finite-N mean of the additive kernel with linear growth, on every real-size scheme
//! that takes processes.

use crate::common;
use crate::processes::{checkpoint, monomers, process_schemes, rng, sim};

use coagula_core::Error;
use coagula_core::kernel::Coagulation;
use coagula_core::observe::Replicas;
use coagula_core::process::{Power, Processes, UserRate};
use coagula_core::scheme::facade::State;

/// The schemes over real sizes that take processes.
fn real_size_schemes() -> Vec<crate::processes::V> {
    let v: Vec<_> = process_schemes()
        .into_iter()
        .filter(|&id| {
            let s = sim(id, Coagulation::constant(1.0).unwrap(), &[2], 1.0);
            matches!(s.state(), State::Sizes(_))
        })
        .collect();
    assert!(v.len() >= 2, "dsa and lowrank-sizes at least");
    v
}

fn sorted_sizes(s: &common::Sim) -> Vec<f64> {
    let State::Sizes(x) = s.state() else {
        panic!("not a sizes scheme")
    };
    let mut x = x.to_vec();
    x.sort_by(f64::total_cmp);
    x
}

/// Without coagulation, the splitting is the growth law's flow composed: at the times
/// k h every particle has its closed form `x(kh)`, between them it lags by the half
/// step not yet taken; the books count the mass grown.
#[test]
fn growth_alone_is_the_closed_form_at_every_step() {
    let h = 0.25;
    let start = [1u64, 2, 0, 3];
    for id in real_size_schemes() {
        // the closed forms written out (not the library's)
        let exact = |q: f64, g: f64, x: f64, t: f64| -> f64 {
            if q == 0.0 {
                x + g * t
            } else if q == 1.0 {
                x * (g * t).exp()
            } else if q == 1.0 / 3.0 {
                (x.powf(2.0 / 3.0) + 2.0 / 3.0 * g * t).powf(1.5)
            } else {
                (x.cbrt() + g * t / 3.0).powi(3)
            }
        };
        for (g, q) in [(0.4, 0.0), (0.3, 1.0 / 3.0), (0.3, 2.0 / 3.0), (0.5, 1.0)] {
            let mut s = sim(id, Coagulation::constant(1e-12).unwrap(), &start, 100.0);
            let x0 = sorted_sizes(&*s);
            let p = Processes::default()
                .with_growth(g, q)
                .unwrap()
                .with_growth_step(h)
                .unwrap();
            s.set_processes(Some(p)).unwrap();
            let mut r = rng(1);
            for (t, grown_for) in [(1.0, 1.0), (1.1, 1.0), (1.2, 1.25), (2.5, 2.5)] {
                s.advance_to(t, &mut r).unwrap();
                let x = sorted_sizes(&*s);
                for (a, b) in x.iter().zip(&x0) {
                    let want = exact(q, g, *b, grown_for);
                    assert!(
                        (a - want).abs() <= 1e-12 * want,
                        "{} G = {g} x^{q:.3}, t = {t}: {a} vs {want}",
                        id.label()
                    );
                }
                let books = s.books().unwrap();
                let m: f64 = x.iter().sum();
                assert!((books.current_mass() - m).abs() <= 1e-12 * m);
                let grown: f64 = m - x0.iter().sum::<f64>();
                assert!((books.grown_mass - grown).abs() <= 1e-12 * m);
            }
        }
    }
}

/// `x + ln x = x0 + ln x0 + c t`: the exact size under `dx/dt = c x / (1 + x)`.
fn saturating_growth(x0: f64, c: f64, t: f64) -> f64 {
    let target = x0 + x0.ln() + c * t;
    let mut x = x0 + c * t;
    for _ in 0..60 {
        x -= (x + x.ln() - target) / (1.0 + 1.0 / x);
    }
    x
}

/// A host's growth rate is integrated by classical Runge–Kutta: its error at a fixed
/// time falls 16-fold when the step halves (a wrong stage weight would make it fall
/// 4- or 2-fold).
#[test]
fn a_host_growth_rate_is_integrated_to_fourth_order() {
    let c = 2.0;
    let t = 4.0;
    let id = real_size_schemes()[0];
    let error = |h: f64| {
        let mut s = sim(id, Coagulation::constant(1e-12).unwrap(), &[1], 1.0);
        // sizes 0.05: the rate's curvature is largest below 1
        s.set_sizes(&[0.05]).unwrap();
        let rate = UserRate::new(move |x: f64| c * x / (1.0 + x), c, 4).unwrap();
        let p = Processes::default()
            .with_user_growth(rate)
            .with_growth_step(h)
            .unwrap();
        s.set_processes(Some(p)).unwrap();
        s.advance_to(t, &mut rng(2)).unwrap();
        (sorted_sizes(&*s)[0] - saturating_growth(0.05, c, t)).abs()
    };
    let (e1, e2, e3) = (error(0.4), error(0.2), error(0.1));
    for (a, b) in [(e1, e2), (e2, e3)] {
        let ratio = a / b;
        assert!(
            (12.0..22.0).contains(&ratio),
            "error ratio {ratio:.2} ({a:.3e} → {b:.3e}): not fourth order"
        );
    }
    assert!(e3 < 1e-4, "{e3}");
}

/// `∫₀ᵗ M(s) ds` of the split chain with linear growth `g` from mass `m0`: the mass
/// is `m0 e^{g h k}` after the k-th growth instant `(k − ½) h` (`lie`: the instants
/// at `k h` instead, Lie splitting's first-order placement).
fn mass_integral(m0: f64, g: f64, h: f64, t: f64, lie: bool) -> f64 {
    let offset = if lie { 1.0 } else { 0.5 };
    let (mut sum, mut now, mut k) = (0.0, 0.0, 0.0);
    while now < t {
        let next = ((k + offset) * h).min(t);
        sum += m0 * (g * h * k).exp() * (next - now);
        now = next;
        k += 1.0;
    }
    sum
}

/// The additive kernel `K = x + y` with linear growth: merges come at the total rate
/// `Σ_{i<j} (x_i + x_j) / V = (N − 1) M / V` and the mass M(t) is deterministic (merges
/// keep it, growth multiplies it), so `E[N(t)] − 1 = (N0 − 1) e^{−∫M/V}` exactly at any
/// N. Replicas of every real-size scheme against it at the split chain's `∫M`; the
/// continuous equation's `∫M = m0 (e^{gt} − 1)/g` is within O(h²) of it; growth at
/// the wrong instants (`k h`, Lie) is many standard errors off.
#[test]
fn linear_growth_with_the_additive_kernel_has_its_exact_finite_n_mean() {
    let (n0, v, g, h) = (40u64, 40.0, 0.5, 0.5);
    let times = [0.75, 1.5, 2.0];
    let reps = 2000u64;
    let z_max = common::z_max(reps);
    let m0 = n0 as f64; // unit sizes
    let mut failures = String::new();
    for (k, id) in real_size_schemes().into_iter().enumerate() {
        let mut number = vec![Replicas::new(); times.len()];
        for r in 0..reps {
            let mut s = sim(id, Coagulation::additive(), &[n0], v);
            let p = Processes::default()
                .with_growth(g, 1.0)
                .unwrap()
                .with_growth_step(h)
                .unwrap();
            s.set_processes(Some(p)).unwrap();
            let mut gr = rng(0x9e37 << 40 | (k as u64) << 32 | r);
            for (i, &t) in times.iter().enumerate() {
                s.advance_to(t, &mut gr).unwrap();
                number[i].push(s.particles() as f64);
            }
        }
        for (i, &t) in times.iter().enumerate() {
            let expect = |lie| 1.0 + (n0 - 1) as f64 * (-mass_integral(m0, g, h, t, lie) / v).exp();
            let (mean, se) = (number[i].mean(), number[i].std_error());
            let z = (mean - expect(false)) / se;
            if z.abs() > z_max {
                failures += &format!(
                    "{} t = {t}: E[N] {mean:.4} vs {:.4} (z = {z:.2})\n",
                    id.label(),
                    expect(false)
                );
            }
            // the test's power: the first-order placement is far off (by t = 1.5)
            let z_lie = (mean - expect(true)) / se;
            eprintln!("{} t = {t}: z = {z:.2}, z_lie = {z_lie:.2}", id.label());
            if t >= 1.5 {
                assert!(
                    z_lie.abs() > 3.0 * z_max,
                    "{} t = {t}: z_lie = {z_lie:.2}",
                    id.label()
                );
            }
        }
    }
    // the splitting's own error against the continuous equation: second order
    let exact = |t: f64| m0 * ((g * t).exp() - 1.0) / g;
    for t in [1.0, 2.0] {
        let e1 = (mass_integral(m0, g, 0.2, t, false) - exact(t)).abs();
        let e2 = (mass_integral(m0, g, 0.1, t, false) - exact(t)).abs();
        assert!((3.5..4.5).contains(&(e1 / e2)), "{t}: {e1} {e2}");
    }
    assert!(failures.is_empty(), "{failures}");
}

/// Growth on real sizes needs its step; a bad step is refused; a host's rate out of its
/// bound during a growth step is an error that leaves the state as it was.
#[test]
fn growth_on_real_sizes_is_refused_without_a_step_and_errors_change_nothing() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(Processes::default().with_growth_step(bad).is_err(), "{bad}");
    }
    for id in real_size_schemes() {
        let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[10, 3], 10.0);
        let p = Processes::default().with_growth(1.0, 0.0).unwrap();
        match s.set_processes(Some(p)) {
            Err(Error::Unsupported { what }) => {
                assert!(
                    what.contains("growth step") && what.contains("lowrank"),
                    "{what}"
                )
            }
            other => panic!("{}: {other:?}", id.label()),
        }
        assert!(s.processes().is_none());
        // more than 2^24 steps in one advance: refused up front, nothing changed
        let tiny = Processes::default()
            .with_growth(1.0, 0.0)
            .unwrap()
            .with_growth_step(1e-9)
            .unwrap();
        s.set_processes(Some(tiny)).unwrap();
        let before = common::state_bits(&*s);
        assert!(s.advance_to(1.0, &mut rng(4)).is_err());
        assert_eq!((common::state_bits(&*s), s.time()), (before, 0.0));
        // a rate that leaves its bound once the sizes pass 3
        let rate = UserRate::new(|x: f64| if x < 3.0 { 1.0 } else { 5.0 }, 1.0, 5).unwrap();
        let p = Processes::default()
            .with_user_growth(rate)
            .with_growth_step(0.5)
            .unwrap();
        s.set_processes(Some(p)).unwrap();
        let mut g = rng(4);
        let e = s.advance_to(50.0, &mut g).unwrap_err();
        assert!(matches!(e, Error::BoundExceeded { .. }), "{e}");
        let (before, t, books) = (common::state_bits(&*s), s.time(), s.books());
        assert!(s.advance_to(60.0, &mut g).is_err());
        assert_eq!(common::state_bits(&*s), before, "{}", id.label());
        assert_eq!((s.time(), s.books()), (t, books), "{}", id.label());
    }
}

/// A run split through checkpoints at and between growth instants gives the bits of
/// an unbroken one.
#[test]
fn split_growth_runs_keep_their_bits_through_checkpoints() {
    for id in real_size_schemes() {
        let p = Processes::dilution(
            0.3,
            0.5,
            coagula_core::initial::Distribution::Monodisperse { size: 1.0 },
        )
        .unwrap()
        .with_growth(0.2, 1.0 / 3.0)
        .unwrap()
        .with_growth_step(0.25)
        .unwrap();
        let make = || {
            let mut s = sim(id, Coagulation::additive(), &[60, 20], 50.0);
            s.set_processes(Some(p.clone())).unwrap();
            s
        };
        // 0.375 is a growth instant, 1.0 a step's end, 2.2 between
        let whole = same_bits_split(make, &[0.375, 1.0, 2.2], 3.0, 6, &id.label());
        assert!(whole.books().unwrap().grown_mass > 0.0);
        // another step is another fingerprint: refused
        let other = p.clone().with_growth_step(0.5).unwrap();
        let mut s = sim(id, Coagulation::additive(), &[60, 20], 50.0);
        s.set_processes(Some(other)).unwrap();
        assert!(s.restore_checkpoint(&checkpoint(&*whole)).is_err());
    }
}

/// A population that dilution empties waits for its source through the growth
/// instants, and grows what comes.
#[test]
fn an_emptied_population_grows_what_its_source_brings() {
    let p = Processes::default()
        .with_source(monomers(0.2))
        .with_removal(5.0, 0.0)
        .unwrap()
        .with_growth(0.5, 1.0)
        .unwrap()
        .with_growth_step(0.1)
        .unwrap();
    for id in real_size_schemes() {
        let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[3], 1.0);
        s.set_processes(Some(p.clone())).unwrap();
        let mut r = rng(18);
        let mut empty = 0;
        for k in 1..=200 {
            s.advance_to(0.25 * f64::from(k), &mut r).unwrap();
            empty += u32::from(s.particles() == 0);
        }
        let b = s.books().unwrap();
        assert!(empty > 50, "{}: empty {empty}", id.label());
        assert!(
            b.injected_number > 3 && b.grown_mass > 0.0,
            "{}: {b:?}",
            id.label()
        );
    }
}

/// The closed form where it is delicate: an exponent within 1e-9 of 1 gives `x e^{ct}`
/// to 1e-8 (the naive `(x^{1−q} + (1−q) c t)^{1/(1−q)}` keeps no digit there), and
/// q = −10 at a size of 1e30 does not overflow. The grid of growth instants starts
/// when the growth is set; setting another process keeps it.
#[test]
fn the_closed_form_keeps_its_digits_and_the_grid_starts_with_the_growth() {
    let near = Power::new("growth", 0.5, 1.0 - 1e-9).unwrap();
    let (x, t) = (3.0, 2.0);
    let want = x * (0.5f64 * t).exp();
    assert!(
        (near.grown(x, t) - want).abs() < 1e-8 * want,
        "{}",
        near.grown(x, t)
    );
    let steep = Power::new("growth", 0.5, -10.0).unwrap();
    let big = steep.grown(1e30, 1.0);
    assert!(
        big.is_finite() && (big - 1e30).abs() <= 1e-12 * 1e30,
        "{big}"
    );
    // processes set at t = 0.3: at t = 0.3 + 4 h the particles grew by 4 h exactly
    let id = real_size_schemes()[0];
    let mut s = sim(id, Coagulation::constant(1e-12).unwrap(), &[4], 100.0);
    s.advance_to(0.3, &mut rng(3)).unwrap();
    let p = Processes::default()
        .with_growth(0.5, 0.0)
        .unwrap()
        .with_growth_step(0.25)
        .unwrap();
    s.set_processes(Some(p.clone())).unwrap();
    s.advance_to(0.3 + 4.0 * 0.25, &mut rng(3)).unwrap();
    assert!(
        (sorted_sizes(&*s)[0] - 1.5).abs() < 1e-12,
        "{:?}",
        sorted_sizes(&*s)
    );
    // another process set: the grid stays (the next instant at 1.425, one more step)
    let p2 = p.with_removal(1e-9, 0.0).unwrap();
    s.set_processes(Some(p2)).unwrap();
    s.advance_to(1.5, &mut rng(3)).unwrap();
    assert!(
        (sorted_sizes(&*s)[0] - 1.625).abs() < 1e-12,
        "{:?}",
        sorted_sizes(&*s)
    );
}

/// Runs `make()` to `end` on generator `seed` once unbroken and once split at `at`,
/// each piece restored from a checkpoint into a fresh `make()`; asserts the same state
/// bits and books, and returns the unbroken sim.
pub(crate) fn same_bits_split(
    make: impl Fn() -> Box<common::Sim>,
    at: &[f64],
    end: f64,
    seed: u64,
    what: &str,
) -> Box<common::Sim> {
    let mut whole = make();
    whole.advance_to(end, &mut rng(seed)).unwrap();
    let mut split = make();
    let mut g = rng(seed);
    for &t in at {
        split.advance_to(t, &mut g).unwrap();
        let mut fresh = make();
        fresh.restore_checkpoint(&checkpoint(&*split)).unwrap();
        split = fresh;
    }
    split.advance_to(end, &mut g).unwrap();
    assert_eq!(
        common::state_bits(&*whole),
        common::state_bits(&*split),
        "{what}"
    );
    assert_eq!(whole.books(), split.books(), "{what}");
    whole
}
