//! What dynamic dispatch costs: the bucketed low-rank scheme on Osinsky's Brownian
//! row (10^7 monomers to t = 10), called three ways — the Rust generic path
//! (`Bucketed<_, 2, 4>`), the facade of the registry (`Box<dyn Simulation>`), and the C
//! ABI (`coag_sim_new_counts` + `coag_sim_advance_to`, which adds the kernel handle's and
//! the random source's enum dispatch). Each path advances in 200 slices, as the CLI's
//! bench does. The paths alternate, `ROUNDS` rounds; the minimum of each is reported
//! with its ratio to the generic path.
//!
//! `cargo bench -p coagula-ffi --bench dispatch` (`DISPATCH_ROUNDS`, `DISPATCH_N0` to
//! change the defaults of 5 rounds and 10^7 monomers).

use coagula::*;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
use coagula_core::scheme::lowrank::Bucketed;
use coagula_core::scheme::registry;
use std::time::Instant;

const T: f64 = 10.0;

/// One way of running the row: `(seconds, collisions)` from `(n0, seed)`.
type Path = fn(u64, u64) -> (f64, u64);
const SLICES: u32 = 200;

fn env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn generic(n0: u64, seed: u64) -> (f64, u64) {
    let start = Instant::now();
    let mut s = Bucketed::<_, 2, 4>::monodisperse(Coagulation::brownian(), n0).unwrap();
    let mut rng = generator(seed, 0);
    let mut ev = 0;
    for i in 1..=SLICES {
        ev += s
            .advance_to(T * f64::from(i) / f64::from(SLICES), &mut rng)
            .unwrap()
            .events;
    }
    (start.elapsed().as_secs_f64(), ev)
}

fn facade(n0: u64, seed: u64) -> (f64, u64) {
    let start = Instant::now();
    let init = Init::Counts {
        counts: &[n0],
        volume: n0 as f64,
    };
    let mut s: Box<dyn Simulation<Coagulation, NoFragmentation, Generator>> = registry::build(
        registry::find("lowrank").unwrap(),
        Model::coagulation(Coagulation::brownian(), NoFragmentation),
        &init,
        &Options::default(),
    )
    .unwrap();
    let mut rng = generator(seed, 0);
    let mut ev = 0;
    for i in 1..=SLICES {
        ev += s
            .advance_to(T * f64::from(i) / f64::from(SLICES), &mut rng)
            .unwrap()
            .events;
    }
    (start.elapsed().as_secs_f64(), ev)
}

fn c_abi(n0: u64, seed: u64) -> (f64, u64) {
    let start = Instant::now();
    let mut ev = 0;
    unsafe {
        let mut k = std::ptr::null_mut();
        assert_eq!(
            coag_kernel_new(c"brownian".as_ptr(), std::ptr::null(), 0, &mut k),
            COAG_OK
        );
        let mut o = std::ptr::null_mut();
        assert_eq!(coag_options_new(&mut o), COAG_OK);
        assert_eq!(coag_options_set_count(o, c"seed".as_ptr(), seed), COAG_OK);
        let mut s = std::ptr::null_mut();
        assert_eq!(
            coag_sim_new_counts(
                c"lowrank".as_ptr(),
                k,
                std::ptr::null(),
                o,
                [n0].as_ptr(),
                1,
                n0 as f64,
                &mut s
            ),
            COAG_OK
        );
        coag_options_free(o);
        let mut rep = std::mem::MaybeUninit::<coag_step_report>::uninit();
        assert_eq!(
            coag_step_report_init(rep.as_mut_ptr(), std::mem::size_of::<coag_step_report>()),
            COAG_OK
        );
        let mut rep = rep.assume_init();
        for i in 1..=SLICES {
            let t = T * f64::from(i) / f64::from(SLICES);
            assert_eq!(coag_sim_advance_to(s, t, &mut rep), COAG_OK);
            ev += rep.events;
        }
        coag_sim_free(s);
        coag_kernel_free(k);
    }
    (start.elapsed().as_secs_f64(), ev)
}

fn main() {
    let rounds = env("DISPATCH_ROUNDS", 5);
    let n0 = env("DISPATCH_N0", 10_000_000);
    let paths: [(&str, Path); 3] = [
        ("rust generic", generic),
        ("facade (dyn)", facade),
        ("C ABI", c_abi),
    ];
    let mut best = [f64::INFINITY; 3];
    let mut events = [0u64; 3];
    for r in 0..rounds {
        for (i, (_, f)) in paths.iter().enumerate() {
            let (s, ev) = f(n0, 1 + r);
            best[i] = best[i].min(s);
            events[i] = ev;
        }
    }
    println!(
        "bucketed low-rank, Brownian kernel, {n0} monomers to t = {T}, {SLICES} slices; min of {rounds} alternating rounds"
    );
    for (i, (name, _)) in paths.iter().enumerate() {
        println!(
            "{name:>14}: {:.3} s  ratio {:.3}  ({} collisions in the last round)",
            best[i],
            best[i] / best[0],
            events[i]
        );
    }
}
