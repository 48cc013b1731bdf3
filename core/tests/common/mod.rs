//! Shared by the conformance tests: replica runs of any size-count scheme and the
//! family-wise thresholds (see `docs/design/statistical-tests.md`).
#![allow(dead_code)]

use coagula_core::Error;
use coagula_core::kernel::gas::HardSpheres;
use coagula_core::kernel::temperature::{ClosedForm, TemperatureModel};
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::{Replicas, TEST_ALPHA, student_t_threshold};
use coagula_core::scheme::facade::{
    Init, InitKind, Model, ModelKind, Options, Points, SchemeId, SchemeInfo, Simulation, State,
};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// The facade as the tests instantiate it.
pub type Sim = dyn Simulation<Coagulation, NoFragmentation, Pcg64Mcg>;

/// The registry's size-count schemes (every one the tests must cover).
pub fn count_schemes() -> impl Iterator<Item = &'static SchemeInfo> {
    registry::SCHEMES
        .iter()
        .copied()
        .filter(|s| s.inits.contains(&InitKind::Counts) && s.model == ModelKind::Coagulation)
}

/// Scheme `id` from `counts` in volume `v`; `None` when the kernel lacks the bound the
/// scheme needs (acceptance–rejection without a supremum).
pub fn build(id: SchemeId, k: Coagulation, counts: &[u64], v: f64) -> Option<Box<Sim>> {
    let init = Init::Counts { counts, volume: v };
    match registry::build(
        id,
        Model::coagulation(k, NoFragmentation),
        &init,
        &Options::default(),
    ) {
        Ok(s) => Some(s),
        Err(Error::Unsupported { .. }) => None,
        Err(e) => panic!("{}: {e}", id.name),
    }
}

/// The physics of a scheme's standard start: `kernel` for a coagulation scheme, the
/// closed-form temperature family (c = 1, γ = 1/2) for a temperature scheme, hard
/// spheres of restitution 0.9 for a gas.
pub fn model_for(info: SchemeId, kernel: Coagulation) -> Model<Coagulation, NoFragmentation> {
    match info.model {
        ModelKind::Coagulation => Model::coagulation(kernel, NoFragmentation),
        ModelKind::Temperature => Model::Temperature(TemperatureModel::ClosedForm(
            ClosedForm::new(1.0, 0.5).unwrap(),
        )),
        ModelKind::Gas => Model::Gas(HardSpheres::new(0.9, 0.0).unwrap()),
    }
}

/// The options of a scheme's standard start: Δt = 1/100 and Monte Carlo points where
/// they apply (replicas then independent), defaults otherwise.
pub fn options_for(info: SchemeId) -> Options {
    let mut o = Options::default();
    if info.takes_option("dt") {
        o = o.with_dt(0.01).with_points(Points::MonteCarlo);
    }
    o
}

/// The data of a standard start (owned, for an `Init` to borrow).
pub struct Start {
    counts: Vec<u64>,
    sizes: Vec<f64>,
    temperatures: Vec<f64>,
    particle_sizes: Vec<u64>,
    velocities: Vec<f64>,
    n0: u64,
}

impl Start {
    /// `n0` monomers (mass-flow schemes: `n0` particles of size 1 carrying mass 1; a
    /// temperature model: at temperature 1; a gas: Maxwellian at temperature 1 from a
    /// fixed seed, at number density 0.1).
    pub fn monomers(n0: u64) -> Start {
        let mut vr = Pcg64Mcg::seed_from_u64(0x0056_454c);
        let (particle_sizes, velocities) =
            coagula_core::initial::maxwellian(&[n0], &[1.0], &mut vr).unwrap();
        Start {
            counts: vec![n0],
            sizes: vec![1.0; n0 as usize],
            temperatures: vec![1.0],
            particle_sizes,
            velocities,
            n0,
        }
    }

    /// The initial state of the kind `info` takes.
    pub fn init(&self, info: SchemeId) -> Init<'_> {
        let v = self.n0 as f64;
        match info.inits[0] {
            InitKind::Counts => Init::Counts {
                counts: &self.counts,
                volume: v,
            },
            InitKind::Sizes => Init::Sizes {
                sizes: &self.sizes,
                mass: 1.0,
            },
            InitKind::Temperatures => Init::Temperatures {
                counts: &self.counts,
                temperatures: &self.temperatures,
                volume: v,
            },
            InitKind::Velocities => Init::Velocities {
                sizes: &self.particle_sizes,
                velocities: &self.velocities,
                volume: v / 0.1,
            },
        }
    }
}

/// Scheme `info`'s standard start from `n0` monomers (see [`Start`], [`model_for`],
/// [`options_for`]); `None` when a coagulation kernel lacks the bound the scheme needs.
pub fn standard(info: SchemeId, n0: u64, kernel: Coagulation) -> Option<Box<Sim>> {
    let start = Start::monomers(n0);
    match registry::build(
        info,
        model_for(info, kernel),
        &start.init(info),
        &options_for(info),
    ) {
        Ok(s) => Some(s),
        Err(Error::Unsupported { .. }) if info.model == ModelKind::Coagulation => None,
        Err(e) => panic!("{}: {e}", info.name),
    }
}

/// Every bit of a sim's state: counts or sizes, the volume, per-size temperatures and
/// velocities where it has them, the time and the books.
pub fn state_bits(s: &Sim) -> Vec<u64> {
    let mut v: Vec<u64> = match s.state() {
        State::Sizes(x) => x.iter().map(|v| v.to_bits()).collect(),
        State::Counts(c, vol) => c.iter().copied().chain([vol.to_bits()]).collect(),
    };
    let _ = s.size_values("temperature", &mut |k, t| v.extend([k, t.to_bits()]));
    let _ = s.velocities(&mut |k, u| v.extend([k, u[0].to_bits(), u[1].to_bits(), u[2].to_bits()]));
    v.push(s.time().to_bits());
    let t = s.totals();
    v.extend([
        t.events,
        t.proposals,
        t.rejections,
        t.bound_violations,
        t.clipped,
        t.doublings,
        t.removed,
        t.bounces,
    ]);
    v
}

/// Replica statistics of N/V, n_1, n_2 read through the facade's `Observe`, at each of
/// `times`; replica r runs on `Pcg64Mcg::seed_from_u64(seed · 0x9e3779b9 ^ r)`.
pub fn facade_replicas(
    seed: u64,
    reps: u64,
    times: &[f64],
    make: impl Fn() -> Box<Sim>,
) -> Vec<[Replicas; 3]> {
    let mut stats = vec![[Replicas::new(), Replicas::new(), Replicas::new()]; times.len()];
    for r in 0..reps {
        let mut rng = Pcg64Mcg::seed_from_u64(seed.wrapping_mul(0x9e37_79b9) ^ r);
        let mut s = make();
        for (ti, &t) in times.iter().enumerate() {
            s.advance_to(t, &mut rng).unwrap();
            let obs = [
                s.particles() as f64 / s.volume(),
                s.number_density(1.0),
                s.number_density(2.0),
            ];
            for (st, x) in stats[ti].iter_mut().zip(obs) {
                st.push(x);
            }
        }
    }
    stats
}

/// The threshold in SE for a mean of `reps` replicas at the suite's false-alarm rate.
pub fn z_max(reps: u64) -> f64 {
    student_t_threshold(TEST_ALPHA, reps - 1)
}

/// The observables' names, in the order of [`replicas`].
pub const LABELS: [&str; 3] = ["N/V", "N1/V", "N2/V"];

/// Mass `Σ i N_i` of a count vector `counts[i − 1] = N_i`.
pub fn mass(counts: &[u64]) -> u64 {
    counts
        .iter()
        .enumerate()
        .map(|(i, &c)| (i as u64 + 1) * c)
        .sum()
}

/// The checkpoint envelope of `s`, in a buffer of the size it needs.
pub fn checkpoint(s: &Sim) -> Vec<u8> {
    let mut w = coagula_core::checkpoint::Writer::new(&mut []);
    s.save_checkpoint(None, &mut w);
    let mut buf = vec![0u8; w.needed()];
    let mut w = coagula_core::checkpoint::Writer::new(&mut buf);
    s.save_checkpoint(None, &mut w);
    w.finish().unwrap();
    buf
}

/// The sim's checkpoint with byte `flip` (mod its length) set to `value`: restored, and
/// a short advance after it, or refused with the state and the books as they were.
pub fn corrupted_checkpoint(
    s: &mut Sim,
    flip: usize,
    value: u8,
    g: &mut Pcg64Mcg,
) -> Result<(), proptest::test_runner::TestCaseError> {
    let mut buf = checkpoint(s);
    let n = buf.len();
    buf[flip % n] = value;
    let kept = state_bits(s);
    let books = s.books();
    if s.restore_checkpoint(&buf[..n]).is_err() {
        proptest::prop_assert_eq!(state_bits(s), kept);
        proptest::prop_assert_eq!(s.books(), books);
    } else {
        let t2 = s.time() + 0.05;
        let _ = s.advance_within(t2, &mut coagula_core::scheme::Budget::work(20_000), g);
    }
    Ok(())
}
