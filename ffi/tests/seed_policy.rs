//! One seed policy: a sim made through the C ABI with `(seed, stream)` and the same
//! scheme built in Rust through the registry with `random::generator(seed, stream)`
//! (and, for RQMC, the scrambling key from `random::substream(.., Scrambling)`) run bit
//! for bit alike.

use coagula::*;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::qmc::Randomization;
use coagula_core::random::{Generator, Purpose, generator, substream};
use coagula_core::scheme::massflow::PointSource;
use coagula_core::scheme::registry::{self, Init, Options, SchemeId, Simulation, State};

const SEED: u64 = 1234;
const STREAM: u64 = 7;

fn c_counts(method: i32, n0: u64, t: f64) -> Vec<u64> {
    unsafe {
        let mut k = std::ptr::null_mut();
        assert_eq!(coag_kernel_new_brownian(&mut k), COAG_OK);
        let mut cfg = std::mem::MaybeUninit::<coag_counts_config>::uninit();
        assert_eq!(
            coag_counts_default_config(cfg.as_mut_ptr(), std::mem::size_of::<coag_counts_config>()),
            COAG_OK
        );
        let mut cfg = cfg.assume_init();
        (cfg.method, cfg.seed, cfg.stream) = (method, SEED, STREAM);
        let mut s = std::ptr::null_mut();
        assert_eq!(coag_counts_new(&cfg, k, [n0].as_ptr(), 1, &mut s), COAG_OK);
        for h in 1..=4 {
            assert_eq!(
                coag_sim_advance_to(s, t * f64::from(h) / 4.0, std::ptr::null_mut()),
                COAG_OK
            );
        }
        let mut len = 0;
        assert_eq!(coag_sim_state_len(s, &mut len), COAG_OK);
        let mut out = vec![0u64; len];
        assert_eq!(
            coag_sim_get_counts(s, out.as_mut_ptr(), len, std::ptr::null_mut()),
            COAG_OK
        );
        coag_sim_free(s);
        coag_kernel_free(k);
        out
    }
}

fn rust_counts(id: SchemeId, n0: u64, t: f64) -> Vec<u64> {
    let init = Init::Counts {
        counts: &[n0],
        volume: n0 as f64,
    };
    let mut s: Box<dyn Simulation<_, _, Generator>> = registry::build(
        id,
        Coagulation::brownian(),
        NoFragmentation,
        &init,
        // the C ABI's default clock (kept between calls)
        &Options::default().with_batched_clock(false),
    )
    .unwrap();
    let mut rng = generator(SEED, STREAM);
    for h in 1..=4 {
        s.advance_to(t * f64::from(h) / 4.0, &mut rng).unwrap();
    }
    match s.state() {
        // up to the largest occupied size, as coag_sim_get_counts writes them
        State::Counts(c, _) => {
            let end = c.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
            c[..end].to_vec()
        }
        State::Sizes(_) => unreachable!(),
    }
}

#[test]
fn size_count_schemes_match_across_front_ends() {
    for (method, id) in [
        (COAG_METHOD_LOWRANK, SchemeId::LowRank),
        (COAG_METHOD_LOWRANK_TREE, SchemeId::LowRankTree),
        (COAG_METHOD_INVERSE, SchemeId::Inverse),
    ] {
        let (c, r) = (c_counts(method, 20_000, 2.0), rust_counts(id, 20_000, 2.0));
        assert_eq!(c, r, "{}", id.name());
        assert!(c[0] < 20_000, "{}: something happened", id.name());
    }
}

#[test]
fn rqmc_mass_flow_matches_across_front_ends() {
    let n = 1024usize;
    let sizes = vec![1.0; n];
    let c_sizes = unsafe {
        let mut k = std::ptr::null_mut();
        assert_eq!(coag_kernel_new_additive(0.0, &mut k), COAG_OK);
        let mut cfg = std::mem::MaybeUninit::<coag_massflow_config>::uninit();
        assert_eq!(
            coag_massflow_default_config(
                cfg.as_mut_ptr(),
                std::mem::size_of::<coag_massflow_config>()
            ),
            COAG_OK
        );
        let mut cfg = cfg.assume_init();
        (cfg.randomization, cfg.seed, cfg.stream) = (COAG_RANDOMIZATION_OWEN, SEED, STREAM);
        let mut s = std::ptr::null_mut();
        assert_eq!(
            coag_massflow_new(&cfg, k, std::ptr::null(), sizes.as_ptr(), n, &mut s),
            COAG_OK
        );
        assert_eq!(coag_sim_advance_to(s, 0.5, std::ptr::null_mut()), COAG_OK);
        let mut out = vec![0.0; n];
        assert_eq!(coag_sim_get_sizes(s, out.as_mut_ptr(), n), COAG_OK);
        coag_sim_free(s);
        coag_kernel_free(k);
        out
    };
    let points = PointSource::randomized_niederreiter(
        Randomization::Owen,
        &mut substream(SEED, STREAM, Purpose::Scrambling),
    );
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    let mut s: Box<dyn Simulation<_, _, Generator>> = registry::build(
        SchemeId::MassFlow,
        Coagulation::additive(),
        NoFragmentation,
        &init,
        &Options::default().with_points(points),
    )
    .unwrap();
    s.advance_to(0.5, &mut generator(SEED, STREAM)).unwrap();
    let State::Sizes(r) = s.state() else {
        unreachable!()
    };
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&c_sizes), bits(r));
}
