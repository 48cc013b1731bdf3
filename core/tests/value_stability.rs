//! Value stability (the rand habit): seeded outputs of every scheme, pinned. These are
//! not correctness checks — the conformance tests are — but a tripwire: any change to a
//! random stream, a draw order or a rounding shows up here, and a change that means to
//! alter them updates the pins in the same commit and says so in its message.
//!
//! Each pin is a report (events, proposals, rejections, doublings) and an FNV-1a hash
//! of the state (counts, or sizes' bits), printed on a mismatch so that a deliberate
//! update is a copy.

use coagula_core::kernel::{BinaryUniform, Coagulation, CoagulationKernel};
use coagula_core::qmc::Randomization;
use coagula_core::scheme::baseline::{AcceptanceRejection, Inverse};
use coagula_core::scheme::lowrank::{Bucketed, BucketedCounted, LowRank};
use coagula_core::scheme::massflow::{MassFlow, PointSource};
use coagula_core::scheme::{Scheme, StepReport};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// FNV-1a over 64-bit words.
fn fnv(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

type Pin = (u64, u64, u64, u64, u64);

fn pin(rep: StepReport, state: u64) -> Pin {
    (
        rep.events,
        rep.proposals,
        rep.rejections,
        rep.doublings,
        state,
    )
}

fn check(name: &str, got: Pin, want: Pin, failures: &mut String) {
    if got != want {
        failures.push_str(&format!("{name}: got {got:?}, pinned {want:?}\n"));
    }
}

/// A size-count scheme from 2000 monomers to t = 1.5 on seed 42.
fn counts_pin<S: Scheme>(mut s: S, counts: impl Fn(&S) -> Vec<u64>) -> Pin {
    let mut rng = Pcg64Mcg::seed_from_u64(42);
    let rep = s.advance_to(1.5, &mut rng).unwrap();
    pin(rep, fnv(counts(&s)))
}

#[test]
fn size_count_schemes_are_value_stable() {
    fn all<K: CoagulationKernel + Copy, const R: usize, const W: usize>(
        name: &str,
        k: K,
        want: [Pin; 5],
        failures: &mut String,
    ) {
        let n0 = 2000;
        let got = [
            counts_pin(LowRank::<K, R>::monodisperse(k, n0).unwrap(), |s| {
                s.counts().to_vec()
            }),
            counts_pin(Bucketed::<K, R, W>::monodisperse(k, n0).unwrap(), |s| {
                s.counts().into_owned()
            }),
            counts_pin(Inverse::monodisperse(k, n0).unwrap(), |s| s.counts()),
            if k.sup_rate(1.0, 2.0).is_some() {
                counts_pin(AcceptanceRejection::monodisperse(k, n0).unwrap(), |s| {
                    s.counts()
                })
            } else {
                (0, 0, 0, 0, 0)
            },
            counts_pin(
                BucketedCounted::<K, R, W>::monodisperse(k, n0).unwrap(),
                |s| s.counts().into_owned(),
            ),
        ];
        let names = [
            "LowRank",
            "Bucketed",
            "Inverse",
            "AcceptanceRejection",
            "BucketedCounted",
        ];
        for (i, scheme) in names.iter().enumerate() {
            check(&format!("{name} {scheme}"), got[i], want[i], failures);
        }
    }
    let mut failures = String::new();
    all::<_, 1, 2>(
        "constant",
        Coagulation::constant(1.0).unwrap(),
        [
            (857, 857, 0, 0, 6611134844062161652),
            (832, 986, 154, 0, 13158605767358922332),
            (885, 885, 0, 0, 14576362283316678503),
            (860, 860, 0, 0, 2032075766861111642),
            (850, 850, 0, 0, 6531131345283194385),
        ],
        &mut failures,
    );
    all::<_, 1, 2>(
        "additive",
        Coagulation::additive(),
        [
            (2200, 2201, 1, 2, 9058174104570674959),
            (2204, 2631, 427, 2, 2167236001803353035),
            (2250, 2250, 0, 2, 8515852320400115809),
            (2220, 36318, 34098, 2, 14969627286106257695),
            (2124, 2127, 3, 2, 17367301671838741731),
        ],
        &mut failures,
    );
    all::<_, 2, 4>(
        "brownian",
        Coagulation::brownian(),
        [
            (2017, 2017, 0, 2, 12553428287362706833),
            (2051, 2418, 367, 2, 7405196712709603969),
            (2057, 2057, 0, 2, 7889359025669339345),
            (2070, 2377, 307, 2, 806088874076014372),
            (2002, 2004, 2, 2, 11052555270129327972),
        ],
        &mut failures,
    );
    all::<_, 3, 6>(
        "ballistic",
        Coagulation::free_molecular().with_min_size(1.0).unwrap(),
        [
            (2769, 3833, 1064, 2, 14282439342857389910),
            (2796, 4495, 1699, 2, 12836370239848841393),
            (2775, 2775, 0, 2, 14471779863178766222),
            (2738, 5263, 2525, 2, 1015803066374961111),
            (2796, 3812, 1016, 2, 17820453303645770141),
        ],
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures}");
}

#[test]
fn mass_flow_is_value_stable() {
    let mut failures = String::new();
    let mut key = Pcg64Mcg::seed_from_u64(7);
    let sources = [
        (
            "niederreiter",
            PointSource::niederreiter(),
            (1084, 51200, 0, 0, 3912149161184120340),
        ),
        (
            "sobol",
            PointSource::sobol(),
            (1067, 51200, 0, 0, 624291934428782012),
        ),
        (
            "mc",
            PointSource::monte_carlo(),
            (1041, 51200, 0, 0, 11721847907050127431),
        ),
        (
            "rqmc-owen",
            PointSource::randomized_niederreiter(Randomization::Owen, &mut key),
            (1075, 51200, 0, 0, 13149859491019460695),
        ),
        (
            "rqmc-matousek",
            PointSource::randomized_sobol(Randomization::Matousek, &mut key),
            (1088, 51200, 0, 0, 7305217675960912766),
        ),
    ];
    for (name, src, want) in sources {
        let mut s = MassFlow::new(
            Coagulation::constant(1.0).unwrap(),
            BinaryUniform::new(1.0).unwrap(),
            &vec![1.0; 1 << 10],
            1.0,
            0.01,
            src,
        )
        .unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(42);
        let rep = s.advance_to(0.5, &mut rng).unwrap();
        let got = pin(rep, fnv(s.sizes().iter().map(|x| x.to_bits())));
        check(name, got, want, &mut failures);
    }
    assert!(failures.is_empty(), "{failures}");
}

#[test]
fn event_driven_schemes_are_value_stable() {
    use coagula_core::scheme::eventflow::{Dsa, DsaCounts, Mfa, Sampler};
    let mut failures = String::new();
    // (continuous sizes: the fragments go below 1)
    let k = Coagulation::free_molecular();
    let f = BinaryUniform::new(0.2).unwrap();
    let pins = [
        ("mfa tree", (9752, 15176, 5424, 0, 13692449450339832355)),
        ("mfa groups", (9707, 15199, 5492, 0, 1873077775543394603)),
        ("dsa tree", (2123, 2567, 444, 0, 3325791614150317223)),
        ("dsa groups", (2085, 2536, 451, 0, 16189620071892263025)),
    ];
    for (i, (name, want)) in pins.into_iter().enumerate() {
        let sampler = if i % 2 == 0 {
            Sampler::SumTree
        } else {
            Sampler::Groups
        };
        let mut rng = Pcg64Mcg::seed_from_u64(42);
        // 2000 monomers with fragmentation events to t = 1.5
        let (rep, sizes) = if i < 2 {
            let mut s = Mfa::new(k, f, &[1.0; 2000], 1.0)
                .unwrap()
                .with_sampler(sampler)
                .unwrap();
            (s.advance_to(1.5, &mut rng).unwrap(), s.sizes().to_vec())
        } else {
            let mut s = Dsa::new(k, f, &[1.0; 2000], 2000.0, 8000)
                .unwrap()
                .with_sampler(sampler)
                .unwrap();
            (s.advance_to(1.5, &mut rng).unwrap(), s.sizes().to_vec())
        };
        let got = pin(rep, fnv(sizes.iter().map(|x| x.to_bits())));
        check(name, got, want, &mut failures);
    }
    // direct simulation over size counts, 2000 monomers to t = 1.5: a kernel whose
    // low-rank form is exact (its factors cached) and one whose is not
    let got = counts_pin(
        DsaCounts::monodisperse(Coagulation::brownian(), 2000).unwrap(),
        |s| s.counts().into_owned(),
    );
    check(
        "dsa-counts brownian",
        got,
        (1510, 1580, 70, 0, 7519374349937584895),
        &mut failures,
    );
    let got = counts_pin(
        DsaCounts::monodisperse(k.with_min_size(1.0).unwrap(), 2000).unwrap(),
        |s| s.counts().into_owned(),
    );
    check(
        "dsa-counts ballistic",
        got,
        (1732, 3692, 1960, 0, 6884049382458626855),
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures}");
}

/// Low-rank over particle sizes: 2000 sizes of an exponential start (the quantile
/// midpoints of Exp(1)) to t = 2 on seed 42, with a rank-1 exact bound (Golovin's
/// kernel) and the rank-3 ballistic bound (squeezed, K evaluated).
#[test]
fn lowrank_sizes_is_value_stable() {
    use coagula_core::scheme::lowrank::LowRankSizes;
    let n = 2000;
    let sizes: Vec<f64> = (0..n)
        .map(|i| -(1.0 - (i as f64 + 0.5) / n as f64).ln())
        .collect();
    let mut failures = String::new();
    let mut rng = Pcg64Mcg::seed_from_u64(42);
    let mut s = LowRankSizes::<_, 1, 2>::new(Coagulation::additive(), &sizes, n as f64).unwrap();
    let rep = s.advance_to(2.0, &mut rng).unwrap();
    let got = pin(rep, fnv(s.sizes().iter().map(|x| x.to_bits())));
    check(
        "lowrank-sizes additive",
        got,
        (2919, 2953, 34, 2, 13561644901882726402),
        &mut failures,
    );
    let mut rng = Pcg64Mcg::seed_from_u64(42);
    let k = Coagulation::free_molecular();
    let mut s = LowRankSizes::<_, 3, 6>::new(k, &sizes, n as f64).unwrap();
    let rep = s.advance_to(2.0, &mut rng).unwrap();
    let got = pin(rep, fnv(s.sizes().iter().map(|x| x.to_bits())));
    check(
        "lowrank-sizes ballistic",
        got,
        (3296, 4364, 1068, 3, 15502914626313247711),
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures}");
}

/// Langevin batches: the paper's problem (specular and absorbing, 1-D) and a 3-D ball
/// with friction, 500 trajectories under key 42; the pin hashes every position,
/// velocity and hit count.
#[test]
fn langevin_batches_are_value_stable() {
    use coagula_core::langevin::{Batch, Config, Friction, Wall, paper};
    let mut failures = String::new();
    let state = |xs: Vec<u64>| fnv(xs);
    for (name, wall, want) in [
        (
            "langevin specular",
            Wall::Specular,
            (563, 32000, 0, 0, 1364375592708310675),
        ),
        (
            "langevin absorbing",
            Wall::Absorbing,
            (146, 28312, 0, 0, 4005323854573415476),
        ),
    ] {
        let mut b = paper::batch(wall, 0.05, paper::Choices::default(), 500, 42, 0).unwrap();
        let rep = b.advance_to(paper::T).unwrap();
        let mut words: Vec<u64> = b
            .positions()
            .chain(b.velocities())
            .map(|x| x[0].to_bits())
            .collect();
        words.extend(b.hits());
        check(name, pin(rep, state(words)), want, &mut failures);
    }
    let cfg = Config::<3>::ball(1.0, 0.02, 1.0, Wall::Specular).unwrap();
    let mut b = Batch::with_starts(cfg, Friction { rate: 1.0 }, 500, 42, 0, |_| {
        ([1.5, 0.0, 0.0], [-1.0, 0.0, 0.0])
    })
    .unwrap();
    let rep = b.advance_to(1.0).unwrap();
    let mut words: Vec<u64> = b
        .positions()
        .chain(b.velocities())
        .flatten()
        .map(f64::to_bits)
        .collect();
    words.extend(b.hits());
    check(
        "langevin 3-D ball",
        pin(rep, state(words)),
        (252, 25000, 0, 0, 11814231682642413468),
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures}");
}

#[test]
fn temperature_schemes_are_value_stable() {
    use coagula_core::kernel::temperature::{Ballistic, ClosedForm};
    use coagula_core::scheme::lowrank::{TemperatureMc, TemperatureRejection, Temperatures};
    let mut failures = String::new();
    // counts and temperature bits
    macro_rules! run {
        ($s:expr) => {{
            let mut s = $s;
            let mut rng = Pcg64Mcg::seed_from_u64(42);
            let rep = s.advance_to(30.0, &mut rng).unwrap();
            let mut words: Vec<u64> = s.counts().to_vec();
            words.extend(s.kernel().temperatures().iter().map(|t| t.to_bits()));
            (pin(rep, fnv(words)), rep.bounces)
        }};
    }
    let ballistic = Temperatures::new(Ballistic::new(0.9, 0.5, 0.4).unwrap(), &[1.0, 0.5]).unwrap();
    let model = Temperatures::new(ClosedForm::new(1.0, 0.5).unwrap(), &[1.0]).unwrap();
    for (name, got, want) in [
        (
            "temperature low-rank, ballistic",
            run!(TemperatureMc::<_>::new(ballistic.clone(), &[1500, 500], 2000.0).unwrap()),
            ((29987, 40117, 10130, 5, 11799343273566508897), 24865),
        ),
        (
            "temperature rejection, ballistic",
            run!(TemperatureRejection::new(ballistic, &[1500, 500], 2000.0).unwrap()),
            ((29928, 182457, 152529, 5, 4335032559574439556), 24761),
        ),
        (
            "temperature low-rank, model",
            run!(TemperatureMc::<_>::new(model, &[2000], 2000.0).unwrap()),
            ((6148, 8722, 2574, 3, 13565433818158184155), 3073),
        ),
    ] {
        if got != want {
            failures.push_str(&format!("{name}: got {got:?}, pinned {want:?}\n"));
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

#[test]
fn dsmc_is_value_stable() {
    use coagula_core::kernel::gas::StickBelow;
    use coagula_core::scheme::lowrank::dsmc::{Gas, LowRankDsmc, RejectionDsmc};
    let mut failures = String::new();
    let mut rng = Pcg64Mcg::seed_from_u64(42);
    let gas = Gas::maxwellian(0.9, &[600, 200, 60], &[1.0, 1.0, 2.0], &mut rng)
        .unwrap()
        .with_sticking(StickBelow { speed: 0.2 });
    macro_rules! run {
        ($s:expr) => {{
            let mut s = $s;
            let mut rng = Pcg64Mcg::seed_from_u64(42);
            let rep = s.advance_to(5.0, &mut rng).unwrap();
            let mut words = Vec::new();
            for size in 1..=s.max_size() as u64 {
                for v in s.kernel().velocities(size) {
                    words.push(size);
                    words.extend(v.iter().map(|c| c.to_bits()));
                }
            }
            (pin(rep, fnv(words)), rep.bounces)
        }};
    }
    for (name, got, want) in [
        (
            "dsmc low-rank",
            run!(LowRankDsmc::new_gas(gas.clone(), 8600.0).unwrap()),
            ((1580, 2425, 845, 0, 192067642762159394), 1559),
        ),
        (
            "dsmc rejection",
            run!(RejectionDsmc::new_gas(gas, 8600.0).unwrap()),
            ((1535, 10910, 9375, 0, 13390194858158570277), 1516),
        ),
    ] {
        if got != want {
            failures.push_str(&format!("{name}: got {got:?}, pinned {want:?}\n"));
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

/// Every scheme of the registry, built through it from the suite's standard start (the
/// conformance tests' `common::standard`: 2048 monomers, the additive kernel, or the
/// scheme's temperature model or gas), run to t = 1.5 on seed 42: the report and a hash
/// of the whole state (`common::state_bits`). A scheme added to the registry fails here
/// until it is pinned.
#[test]
fn every_registry_scheme_is_value_stable() {
    use crate::common::{Sim, standard, state_bits};
    use coagula_core::scheme::registry;
    // lowrank-tree and lowrank-binary-tree agree: a sum tree's search maps one uniform
    // to the same particle whatever its arity
    const PINS: &[(&str, Pin)] = &[
        ("massflow", (9673, 307200, 0, 0, 5290409906748756131)),
        ("lowrank", (2166, 2168, 2, 2, 1325362049796669126)),
        ("lowrank-tree", (2269, 2270, 1, 2, 6494809902827688707)),
        (
            "lowrank-binary-tree",
            (2269, 2270, 1, 2, 6494809902827688707),
        ),
        (
            "lowrank-blocks",
            (2447, 5835, 3388, 2, 12935128342079144210),
        ),
        ("inverse", (2282, 2282, 0, 2, 5247040761069309302)),
        ("rejection", (2155, 25337, 23182, 2, 5272263596675280727)),
        ("mfa", (10241, 32280, 22039, 0, 12727288476529336162)),
        ("dsa", (1627, 3670, 2043, 0, 3078326075113058261)),
        ("dsa-counts", (1621, 3603, 1982, 0, 221548900314250824)),
        ("lowrank-sizes", (2279, 2279, 0, 2, 2364236902791145940)),
        ("temperature", (1605, 2284, 679, 0, 3419479300055532468)),
        (
            "temperature-rejection",
            (1624, 2450, 826, 0, 5229304295555439157),
        ),
        ("dsmc", (1075, 1711, 636, 0, 1657399837960174287)),
        (
            "dsmc-rejection",
            (1089, 4421, 3332, 0, 10542260871445829706),
        ),
    ];
    let mut failures = String::new();
    for &info in registry::SCHEMES {
        let mut s: Box<Sim> = standard(info, 2048, Coagulation::additive())
            .unwrap_or_else(|| panic!("{}: not built", info.name));
        let rep = s.advance_to(1.5, &mut Pcg64Mcg::seed_from_u64(42)).unwrap();
        let got = pin(rep, fnv(state_bits(&*s)));
        match PINS.iter().find(|(n, _)| *n == info.name) {
            Some(&(_, want)) => check(info.name, got, want, &mut failures),
            None => failures.push_str(&format!("(\"{}\", {got:?}),\n", info.name)),
        }
    }
    assert!(failures.is_empty(), "{failures}");
}
