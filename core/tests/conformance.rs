//! The shared conformance suite: every scheme of the registry, reached only through the
//! facade (`Simulation` + `Observe`), on the checks every scheme must pass — its law
//! against an exact solution within the replicas' standard errors, the same seed giving
//! the same bits, a checkpoint split (through the one envelope) equal to the unbroken
//! run, a clone that continues identically, observables that agree with each other,
//! settings and input the scheme does not take refused with the state as it was. A
//! scheme added to the registry joins every test here without a line changed: its
//! standard start comes from its entry's capabilities (`common::standard`). The
//! finite-N reference and the regime sweep cover the integer-size schemes the same way.

use crate::common;

use crate::common::{Sim, Start, model_for, options_for, standard, state_bits, z_max};
use coagula_core::Error;
use coagula_core::checkpoint::Writer;
use coagula_core::exact::Exact;
use coagula_core::kernel::temperature::ClosedForm;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::Replicas;
use coagula_core::scheme::Budget;
use coagula_core::scheme::facade::{
    Directions, Init, InitKind, KEYS, Law, Model, ModelKind, Options, State, Value,
};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

const N0: u64 = 4096;

/// The envelope of a sim (with a front end's stream of four words).
fn envelope(s: &Sim, stream: Option<[u64; 4]>) -> Vec<u8> {
    let mut w = Writer::new(&mut []);
    s.save_checkpoint(stream, &mut w);
    let mut buf = vec![0u8; w.needed()];
    let mut w = Writer::new(&mut buf);
    s.save_checkpoint(stream, &mut w);
    assert_eq!(w.finish().unwrap(), buf.len());
    buf
}

#[test]
fn the_registry_names_every_scheme_once() {
    let names: Vec<&str> = registry::SCHEMES.iter().map(|s| s.name).collect();
    assert_eq!(names, registry::NAMES);
    for (i, &info) in registry::SCHEMES.iter().enumerate() {
        assert_eq!(registry::find(info.name).unwrap().name, info.name);
        assert!(!names[..i].contains(&info.name), "{} twice", info.name);
        assert!(
            !registry::SCHEMES[..i].iter().any(|o| o.tag == info.tag),
            "{}: its checkpoint tag is another scheme's",
            info.name
        );
        assert!(!info.inits.is_empty(), "{}", info.name);
        for k in info.options {
            assert!(
                KEYS.iter().any(|key| key.name == *k),
                "{}: option {k}",
                info.name
            );
        }
    }
    let e = registry::find("no-such-scheme").unwrap_err();
    assert!(matches!(e, Error::UnknownName { what: "scheme", .. }));
    // the message lists the schemes
    assert!(e.to_string().contains("lowrank-sizes"), "{e}");
    assert!(registry::SCHEMES.len() >= 14);
}

/// Every scheme against an exact solution of its law (32 replicas, Student t on their
/// own standard error at the suite's false-alarm rate, 7.2 SE):
/// * coagulation, K = 1 from monomers: `M2(t) = 1 + t` for every scheme (the mass-flow
///   step is an explicit Euler step in expectation, `E[M2'] = M2 + Δt`, which is exact
///   here) and `M0(t) = 1/(1 + t/2)` for every event-driven scheme (the time-driven
///   scheme's M0 carries an O(Δt) bias, checked in its own tests). A factor 2 in a
///   rate moves M0(1) to 1/2 and M2(1) to 3: ~150 SE each (measured SEs: 1.0e-3 and
///   4e-3..7e-3);
/// * the temperature family with a closed form (c = 1, γ = 1/2): N and the mean
///   temperature (docs/design/temperature.md) at t = 1 from 20 000 monomers. A factor 2
///   in the collision rate moves N(1) by ~20 % (hundreds of SE); a bounce that does not
///   cool leaves the mean temperature 15 % high;
/// * a gas (hard spheres): see [`the_first_collision_of_a_gas_comes_at_the_exact_rate`].
#[test]
fn every_scheme_matches_the_exact_solution_of_its_law() {
    let k = Coagulation::constant(1.0).unwrap();
    let e = Exact::constant(1.0).unwrap();
    let (t, reps) = (1.0, 32u64);
    let z = z_max(reps);
    let mut failures = String::new();
    for (i, &info) in registry::SCHEMES.iter().enumerate() {
        let n0 = match info.model {
            ModelKind::Coagulation => N0,
            ModelKind::Temperature => 20_000,
            ModelKind::Gas => continue,
        };
        let (mut m0, mut m2, mut temp) = (Replicas::new(), Replicas::new(), Replicas::new());
        for r in 0..reps {
            let mut s = standard(info, n0, k).unwrap();
            let mut rng = Pcg64Mcg::seed_from_u64(1000 * i as u64 + r);
            s.advance_to(t, &mut rng).unwrap();
            m0.push(s.moment(0.0));
            m2.push(s.moment(2.0));
            if let Some(x) = s.observable("mean-temperature") {
                temp.push(x);
            }
        }
        let mut checks = Vec::new();
        if info.model == ModelKind::Temperature {
            let exact = ClosedForm::new(1.0, 0.5).unwrap().exact(1.0, 1.0, t);
            checks.push(("N", &m0, exact.number()));
            checks.push(("mean temperature", &temp, exact.mean_temperature()));
        } else {
            checks.push(("M2", &m2, e.moment(2, t).unwrap()));
            if info.law != Law::TimeStepped {
                checks.push(("M0", &m0, e.moment(0, t).unwrap()));
            }
        }
        for (q, st, want) in checks {
            let zz = (st.mean() - want) / st.std_error();
            println!(
                "{} {q}: {} ± {} vs {want} ({zz:+.2} SE)",
                info.name,
                st.mean(),
                st.std_error()
            );
            if zz.is_nan() || zz.abs() > z {
                failures.push_str(&format!(
                    "{} {q}(t={t}): {} vs exact {want} ({zz:.1} SE > {z:.2})\n",
                    info.name,
                    st.mean()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

/// A gas (every scheme whose law is a gas, both collision-direction laws): from a fixed
/// state of 24 particles of sizes 1–3, the time to the first collision is exponential
/// with rate `R = Σ_{k<l} π (R_k + R_l)² |V_k − V_l| / V` (`R_k` half the diameter
/// `size^{1/3}`): its mean over 40 000 replicas matches `1/R` within the suite's
/// threshold (SE 0.5 %). A factor N/(N − 1) in the pair count is 4 % (8 SE), a factor
/// 2 in the direction's law or the cross-section 100 %.
#[test]
fn the_first_collision_of_a_gas_comes_at_the_exact_rate() {
    let mut r0 = Pcg64Mcg::seed_from_u64(3u64.wrapping_mul(0x9e37_79b9));
    let (sizes, vel) =
        coagula_core::initial::maxwellian(&[12, 8, 4], &[1.0, 2.0, 0.5], &mut r0).unwrap();
    let volume = 500.0;
    let mut rate = 0.0;
    for a in 0..sizes.len() {
        for b in a + 1..sizes.len() {
            let rr = ((sizes[a] as f64).cbrt() + (sizes[b] as f64).cbrt()) / 2.0;
            let g = (0..3)
                .map(|k| (vel[3 * a + k] - vel[3 * b + k]).powi(2))
                .sum::<f64>()
                .sqrt();
            rate += std::f64::consts::PI * rr * rr * g / volume;
        }
    }
    let init = Init::Velocities {
        sizes: &sizes,
        velocities: &vel,
        volume,
    };
    let reps = 40_000u64;
    let mut ran = 0;
    for &info in registry::SCHEMES.iter().filter(|s| s.law == Law::Gas) {
        for d in [Directions::Conditional, Directions::Uniform] {
            ran += 1;
            let opts = Options::default().with_directions(d);
            let model = model_for(info, Coagulation::constant(1.0).unwrap());
            let mut st = Replicas::new();
            let mut rng = Pcg64Mcg::seed_from_u64(4u64.wrapping_mul(0x9e37_79b9));
            for _ in 0..reps {
                let mut s: Box<Sim> = registry::build(info, model, &init, &opts).unwrap();
                loop {
                    let rep = s
                        .advance_within(1e12, &mut Budget::work(1), &mut rng)
                        .unwrap();
                    if rep.events > 0 {
                        break;
                    }
                }
                st.push(s.time());
            }
            let zz = (st.mean() - 1.0 / rate) / st.std_error();
            println!(
                "{} first collision ({d:?}): {} ± {} vs 1/R = {} ({zz:+.2} SE)",
                info.name,
                st.mean(),
                st.std_error(),
                1.0 / rate
            );
            assert!(zz.abs() < z_max(reps), "{} {d:?}: {zz:.1} SE", info.name);
        }
    }
    assert!(ran >= 4);
}

/// The same seed gives the same bits, through the facade, for every scheme; another
/// seed gives another run.
#[test]
fn same_seed_same_bits() {
    let k = Coagulation::additive();
    for &info in registry::SCHEMES {
        let run = |seed: u64| {
            let mut s = standard(info, N0, k).unwrap();
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            let mut reps = Vec::new();
            for h in 1..=4 {
                reps.push(s.advance_to(0.25 * f64::from(h), &mut rng).unwrap());
            }
            (state_bits(&*s), reps, s.totals())
        };
        let (a, b, c) = (run(5), run(5), run(6));
        assert_eq!(a, b, "{}", info.name);
        assert_ne!(a.0, c.0, "{}: another seed, another run", info.name);
        assert!(a.2.events > 0, "{}", info.name);
    }
}

/// Save at t1 (the one envelope, with a front end's stream), run on to t2; restore into
/// a fresh sim and run it to t2 with the generator as it was at the save: the same bits
/// and every field of the books, for every scheme. A truncated or corrupted envelope,
/// or one of another scheme, is refused and changes nothing.
#[test]
fn checkpoint_split_equals_unbroken_run() {
    let k = Coagulation::additive();
    let schemes = registry::SCHEMES;
    for (i, &info) in schemes.iter().enumerate() {
        let mut a = standard(info, N0, k).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        a.advance_to(0.7, &mut rng).unwrap();
        let buf = envelope(&*a, Some([1, 2, 3, u64::MAX]));
        let at_save = rng.clone();
        a.advance_to(2.0, &mut rng).unwrap();

        let mut b = standard(info, N0, k).unwrap();
        let before = state_bits(&*b);
        assert!(b.restore_checkpoint(&buf[..buf.len() / 2]).is_err());
        // a flipped bit anywhere in the header (issue 40: the first 40 bytes of the old
        // temperature and DSMC envelopes were not covered) or in the body
        let stride = (buf.len() / 64).max(1);
        for j in (0..buf.len().min(96)).chain((96..buf.len()).step_by(stride)) {
            let mut flipped = buf.clone();
            flipped[j] ^= 4;
            assert!(
                b.restore_checkpoint(&flipped).is_err(),
                "{}: byte {j} of {} flipped",
                info.name,
                buf.len()
            );
        }
        let other = schemes[(i + 1) % schemes.len()];
        let o = standard(other, N0, k).unwrap();
        assert!(
            b.restore_checkpoint(&envelope(&*o, None)).is_err(),
            "{}: a checkpoint of {}",
            info.name,
            other.name
        );
        assert_eq!(
            state_bits(&*b),
            before,
            "{}: a refused restore changes nothing",
            info.name
        );
        assert_eq!(
            b.restore_checkpoint(&buf).unwrap(),
            Some([1, 2, 3, u64::MAX])
        );
        let mut rng_b = at_save;
        b.advance_to(2.0, &mut rng_b).unwrap();
        assert_eq!(state_bits(&*a), state_bits(&*b), "{}", info.name);
        assert_eq!(a.totals(), b.totals(), "{}", info.name);
        if info.model == ModelKind::Gas {
            // (the books a restore once lost: issue 40)
            assert!(a.totals().bounces > 0, "{}: no bounce to carry", info.name);
        }
    }
}

/// A clone continues exactly as the original (same generator), and independently of it.
#[test]
fn a_clone_continues_identically() {
    let k = Coagulation::additive();
    for &info in registry::SCHEMES {
        let mut a = standard(info, N0, k).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(8);
        a.advance_to(0.5, &mut rng).unwrap();
        let mut b = a.duplicate().unwrap();
        assert_eq!(b.info().name, info.name);
        assert_eq!(state_bits(&*a), state_bits(&*b), "{}", info.name);
        // and its checkpoint is the original's, settings records included
        let save = |s: &Sim| {
            let mut w = Writer::new(&mut []);
            s.save_checkpoint(None, &mut w);
            let mut buf = vec![0u8; w.needed()];
            let mut w = Writer::new(&mut buf);
            s.save_checkpoint(None, &mut w);
            w.finish().unwrap();
            buf
        };
        assert!(
            save(&*a) == save(&*b),
            "{}: clone's checkpoint differs",
            info.name
        );
        let mut rng_b = rng.clone();
        a.advance_to(1.5, &mut rng).unwrap();
        assert_ne!(
            state_bits(&*a),
            state_bits(&*b),
            "{}: independent",
            info.name
        );
        b.advance_to(1.5, &mut rng_b).unwrap();
        assert_eq!(state_bits(&*a), state_bits(&*b), "{}", info.name);
    }
}

/// The observables agree with each other and with the state: the zeroth moment is the
/// total concentration, the first is conserved, sizes outside the state have none; the
/// named observables of the entry answer, others do not.
#[test]
fn observables_agree_with_the_state() {
    let k = Coagulation::additive();
    for &info in registry::SCHEMES {
        let mut s = standard(info, N0, k).unwrap();
        let mass0 = s.moment(1.0);
        s.advance_to(1.0, &mut Pcg64Mcg::seed_from_u64(9)).unwrap();
        let m0 = s.moment(0.0);
        approx::assert_relative_eq!(
            s.concentration(0.0, f64::INFINITY),
            m0,
            max_relative = 1e-12
        );
        approx::assert_relative_eq!(s.moment(1.0), mass0, max_relative = 1e-12);
        assert_eq!(s.concentration(-2.0, -1.0), 0.0);
        for name in info.observables {
            let v = s.observable(name);
            assert!(
                v.is_some_and(f64::is_finite),
                "{}: {name} = {v:?}",
                info.name
            );
        }
        assert_eq!(s.observable("no-such-observable"), None);
        match s.state() {
            State::Counts(c, v) => {
                assert_eq!(c.iter().sum::<u64>(), s.particles(), "{}", info.name);
                approx::assert_relative_eq!(m0, s.particles() as f64 / v, max_relative = 1e-12);
                approx::assert_relative_eq!(s.number_density(1.0), c[0] as f64 / v);
                let largest = c.iter().rposition(|&n| n > 0).unwrap() + 1;
                assert_eq!(s.gel_mass(), Some(largest as f64 / v));
                assert_eq!(s.concentration(largest as f64 + 0.5, 1e300), 0.0);
                assert!(s.max_size().unwrap() >= largest as u64);
            }
            State::Sizes(x) => {
                assert_eq!(x.len() as u64, s.particles());
                let largest = x.iter().copied().fold(0.0, f64::max);
                match info.law {
                    Law::TimeStepped => assert_eq!(s.gel_mass(), None),
                    // no truncation: nothing left the system
                    Law::MassFlow => assert_eq!(s.gel_mass(), Some(0.0)),
                    _ => assert_eq!(s.gel_mass(), Some(largest / s.volume()), "{}", info.name),
                }
                assert_eq!(s.concentration(largest * 1.5, 1e300), 0.0);
            }
        }
    }
}

/// Refused input leaves the state (every bit of it, the books included) unchanged, and
/// the sim still runs: a target in the past or NaN, a setter of a state or a setting
/// the scheme does not have, a garbage checkpoint.
#[test]
fn refused_input_leaves_the_state_unchanged() {
    let k = Coagulation::additive();
    for &info in registry::SCHEMES {
        let mut s = standard(info, N0, k).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(4);
        s.advance_to(0.5, &mut rng).unwrap();
        let before = state_bits(&*s);
        let same = |s: &Sim| state_bits(s) == before;
        assert!(matches!(
            s.advance_to(0.25, &mut rng),
            Err(Error::TimeBackwards { .. })
        ));
        assert!(s.advance_to(f64::NAN, &mut rng).is_err());
        assert!(s.set_time(-1.0).is_err() && s.set_time(f64::INFINITY).is_err());
        assert!(s.restore_checkpoint(&[0u8; 64]).is_err());
        let counts = info.inits.contains(&InitKind::Counts);
        let sizes = info.inits.contains(&InitKind::Sizes);
        // (no particle at all is a valid, empty system since issue 14)
        assert!(s.set_counts(&[0, 0], 0.0).is_err());
        assert!(s.set_counts(&[3], f64::NAN).is_err());
        assert!(s.set_sizes(&[1.0, f64::NAN]).is_err());
        if !counts {
            assert!(matches!(
                s.set_counts(&[3], 1.0),
                Err(Error::Unsupported { .. })
            ));
        }
        if !sizes {
            assert!(matches!(
                s.set_sizes(&[1.0]),
                Err(Error::Unsupported { .. })
            ));
        }
        if !info.takes_option("dt") {
            assert!(matches!(s.set_dt(0.1), Err(Error::Unsupported { .. })));
        } else {
            assert!(s.set_dt(-1.0).is_err());
        }
        if !info.fragmentation {
            assert!(s.set_fragmentation(NoFragmentation).is_err());
        }
        if info.model != ModelKind::Coagulation {
            assert!(matches!(s.set_kernel(k), Err(Error::Unsupported { .. })));
            assert!(s.set_mass(2.0).is_err());
        }
        if matches!(
            info.name,
            "lowrank" | "lowrank-tree" | "lowrank-binary-tree"
        ) {
            // the additive kernel has rank 1; the Brownian one rank 2
            assert!(s.set_kernel(Coagulation::brownian()).is_err());
        }
        assert!(same(&*s), "{}: state changed by refused input", info.name);
        // and the sim still runs
        s.advance_to(1.0, &mut rng).unwrap();
    }
}

/// A valid value of every key (for the applicability check).
fn sample(key: &str) -> Value<'static> {
    match key {
        "dt" => Value::Real(0.005),
        "points" => Value::Name("sobol"),
        "randomization" => Value::Name("owen"),
        "sorting" => Value::Name("full"),
        "size-limit" => Value::Count(1 << 20),
        "memory-budget" => Value::Count(1 << 30),
        "batched-clock" => Value::Flag(false),
        "capacity" => Value::Count(4 * N0),
        "truncation" => Value::Real(1e6),
        "strict-bound" => Value::Flag(true),
        "sampler" => Value::Name("tree"),
        "engine" => Value::Name("slots"),
        "directions" => Value::Name("uniform"),
        "seed" | "stream" => Value::Count(7),
        other => panic!("no sample value for option {other}"),
    }
}

/// Every option a scheme does not take is refused by name at build, with the scheme's
/// name; every option it takes builds. A model or an initial state of another kind is
/// refused.
#[test]
fn settings_and_inputs_a_scheme_does_not_take_are_refused() {
    let k = Coagulation::constant(1.0).unwrap();
    let start = Start::monomers(64);
    for &info in registry::SCHEMES {
        let model = model_for(info, k);
        let init = start.init(info);
        for key in KEYS {
            let mut o = Options::default();
            o.set(key.name, sample(key.name)).unwrap();
            let r = registry::build::<_, _, Pcg64Mcg>(info, model, &init, &o);
            if info.takes_option(key.name) {
                assert!(r.is_ok(), "{} with {}: {:?}", info.name, key.name, r.err());
            } else {
                assert_eq!(
                    r.err(),
                    Some(Error::OptionNotApplicable {
                        key: key.name,
                        scheme: info.name
                    }),
                    "{} with {}",
                    info.name,
                    key.name
                );
            }
        }
        for &other in registry::SCHEMES {
            let theirs = model_for(other, k);
            if other.model != info.model {
                assert!(matches!(
                    registry::build::<_, _, Pcg64Mcg>(info, theirs, &init, &options_for(info)),
                    Err(Error::Unsupported { .. })
                ));
            }
            let init2 = start.init(other);
            if !info.accepts(&init2) {
                assert!(matches!(
                    registry::build::<_, _, Pcg64Mcg>(info, model, &init2, &options_for(info)),
                    Err(Error::Unsupported { .. })
                ));
            }
        }
    }
}

/// Review of issue 13: the registry's options reach every scheme at construction — a
/// memory budget the initial tables do not fit is refused by every size-count scheme
/// (it used to be checked against the default first), a state longer than the size
/// limit is refused, and a fragmentation kernel is refused by the schemes that cannot
/// break particles (it used to be dropped silently).
#[test]
fn options_and_kernels_reach_every_scheme_at_construction() {
    let k = Coagulation::constant(1.0).unwrap();
    let mut counts = vec![0u64; 1 << 16];
    counts[0] = 1000;
    let init = Init::Counts {
        counts: &counts,
        volume: 1000.0,
    };
    let tight = Options::default().with_memory_budget(1 << 10);
    let short = Options::default().with_size_limit(1000);
    let frag = coagula_core::kernel::BinaryUniform::new(1.0).unwrap();
    for info in common::count_schemes() {
        let built = |o: &Options| {
            registry::build::<_, _, Pcg64Mcg>(
                info,
                Model::coagulation(k, NoFragmentation),
                &init,
                o,
            )
        };
        assert!(built(&Options::default()).is_ok(), "{}", info.name);
        assert!(
            matches!(built(&tight), Err(Error::Capacity { .. })),
            "{}: a 1 KiB budget for 65536 sizes",
            info.name
        );
        assert!(
            matches!(built(&short), Err(Error::Capacity { .. })),
            "{}",
            info.name
        );
        assert!(
            matches!(
                registry::build::<_, _, Pcg64Mcg>(
                    info,
                    Model::coagulation(k, frag),
                    &init,
                    &Options::default()
                ),
                Err(Error::Unsupported { .. })
            ),
            "{}: fragmentation",
            info.name
        );
    }
}
