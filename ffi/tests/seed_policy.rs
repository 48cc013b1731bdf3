//! One seed policy: every scheme of the registry made through the C ABI with the
//! options' `(seed, stream)` and the same scheme built in Rust through the registry
//! with `random::generator(seed, stream)` run bit for bit alike (the RQMC scrambling
//! and a gas's Maxwellian velocities drawn from the same seed policy's streams).

use coagula::*;
use coagula_core::kernel::Coagulation;
use coagula_core::kernel::Fragmentation;
use coagula_core::kernel::builtin;
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{Init, InitKind, Model, Options, SchemeId, Simulation, State};
use coagula_core::scheme::registry;
use std::ffi::CString;

const SEED: u64 = 1234;
const STREAM: u64 = 7;
const N0: u64 = 4096;

/// The kernel of a scheme's model kind, by name and parameters of core's table.
fn kernel_of(id: SchemeId) -> (&'static str, Vec<f64>) {
    use coagula_core::scheme::facade::ModelKind;
    match id.model {
        ModelKind::Coagulation => ("additive", vec![1.0]),
        ModelKind::Temperature => ("temperature-closed-form", vec![1.0, 0.5]),
        ModelKind::Gas => ("hard-spheres", vec![0.9, 0.0]),
    }
}

/// The state's bits, with per-size temperatures and velocities where the scheme has
/// them.
fn rust_bits(id: SchemeId, t: f64) -> Vec<u64> {
    let (name, params) = kernel_of(id);
    let pairs: Vec<(&str, f64)> = builtin::find(name)
        .unwrap()
        .params
        .iter()
        .zip(&params)
        .map(|(p, &v)| (p.name, v))
        .collect();
    let model: Model<Coagulation, Fragmentation> = Model::of_builtin(
        builtin::make(name, &pairs).unwrap(),
        |c| c,
        Fragmentation::None,
    )
    .unwrap();
    let mut opts = Options::default().with_stream(SEED, STREAM);
    if id.takes_option("randomization") {
        opts = opts.with_randomization(coagula_core::qmc::Randomization::Owen);
    }
    let ones = vec![1.0; N0 as usize];
    let (psizes, vel) =
        coagula_core::initial::maxwellian_of_seed(&[N0], &[1.0], SEED, STREAM).unwrap();
    let init = match id.inits[0] {
        InitKind::Counts => Init::Counts {
            counts: &[N0],
            volume: N0 as f64,
        },
        InitKind::Sizes => Init::Sizes {
            sizes: &ones,
            mass: 1.0,
        },
        InitKind::Temperatures => Init::Temperatures {
            counts: &[N0],
            temperatures: &[1.0],
            volume: N0 as f64,
        },
        InitKind::Velocities => Init::Velocities {
            sizes: &psizes,
            velocities: &vel,
            volume: N0 as f64 * 10.0,
        },
    };
    let mut s: Box<dyn Simulation<Coagulation, Fragmentation, Generator>> =
        registry::build(id, model, &init, &opts).unwrap();
    let mut rng = generator(SEED, STREAM);
    for h in 1..=4 {
        s.advance_to(t * f64::from(h) / 4.0, &mut rng).unwrap();
    }
    let mut v: Vec<u64> = match s.state() {
        State::Counts(c, _) => {
            let end = c.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
            c[..end].to_vec()
        }
        State::Sizes(x) => x.iter().map(|x| x.to_bits()).collect(),
    };
    let _ = s.size_values("temperature", &mut |k, x| v.extend([k, x.to_bits()]));
    let _ = s.velocities(&mut |k, u| v.extend([k, u[0].to_bits(), u[1].to_bits(), u[2].to_bits()]));
    v
}

fn c_bits(id: SchemeId, t: f64) -> Vec<u64> {
    unsafe {
        let (name, params) = kernel_of(id);
        let cname = CString::new(name).unwrap();
        let scheme = CString::new(id.name).unwrap();
        let mut k = std::ptr::null_mut();
        assert_eq!(
            coag_kernel_new(cname.as_ptr(), params.as_ptr(), params.len(), &mut k),
            COAG_OK
        );
        let mut o = std::ptr::null_mut();
        assert_eq!(coag_options_new(&mut o), COAG_OK);
        assert_eq!(coag_options_set_count(o, c"seed".as_ptr(), SEED), COAG_OK);
        assert_eq!(
            coag_options_set_count(o, c"stream".as_ptr(), STREAM),
            COAG_OK
        );
        if id.takes_option("randomization") {
            assert_eq!(
                coag_options_set_name(o, c"randomization".as_ptr(), c"owen".as_ptr()),
                COAG_OK
            );
        }
        let mut s = std::ptr::null_mut();
        let st = match id.inits[0] {
            InitKind::Counts => coag_sim_new_counts(
                scheme.as_ptr(),
                k,
                std::ptr::null(),
                o,
                [N0].as_ptr(),
                1,
                N0 as f64,
                &mut s,
            ),
            InitKind::Sizes => {
                let ones = vec![1.0; N0 as usize];
                coag_sim_new_sizes(
                    scheme.as_ptr(),
                    k,
                    std::ptr::null(),
                    o,
                    ones.as_ptr(),
                    ones.len(),
                    1.0,
                    &mut s,
                )
            }
            InitKind::Temperatures => coag_sim_new_temperatures(
                scheme.as_ptr(),
                k,
                o,
                [N0].as_ptr(),
                [1.0].as_ptr(),
                1,
                N0 as f64,
                &mut s,
            ),
            InitKind::Velocities => coag_sim_new_maxwellian(
                scheme.as_ptr(),
                k,
                o,
                [N0].as_ptr(),
                [1.0].as_ptr(),
                1,
                N0 as f64 * 10.0,
                &mut s,
            ),
        };
        assert_eq!(st, COAG_OK, "{}", id.name);
        for h in 1..=4 {
            assert_eq!(
                coag_sim_advance_to(s, t * f64::from(h) / 4.0, std::ptr::null_mut()),
                COAG_OK
            );
        }
        let mut v = Vec::new();
        let mut len = 0;
        assert_eq!(coag_sim_state_len(s, &mut len), COAG_OK);
        if id.inits.contains(&InitKind::Sizes) {
            let mut out = vec![0.0; len];
            assert_eq!(coag_sim_get_sizes(s, out.as_mut_ptr(), len), COAG_OK);
            v.extend(out.iter().map(|x| x.to_bits()));
        } else {
            let mut out = vec![0u64; len];
            assert_eq!(
                coag_sim_get_counts(s, out.as_mut_ptr(), len, std::ptr::null_mut()),
                COAG_OK
            );
            v.extend(out);
        }
        let mut occ = 0;
        assert_eq!(coag_sim_occupied(s, &mut occ), COAG_OK);
        let (mut ks, mut xs) = (vec![0u64; occ], vec![0.0; occ]);
        let mut w = 0;
        if coag_sim_size_values(
            s,
            c"temperature".as_ptr(),
            ks.as_mut_ptr(),
            xs.as_mut_ptr(),
            occ,
            &mut w,
        ) == COAG_OK
        {
            for i in 0..w {
                v.extend([ks[i], xs[i].to_bits()]);
            }
        }
        let mut n = 0;
        assert_eq!(coag_sim_particle_count(s, &mut n), COAG_OK);
        let (mut ps, mut vs) = (vec![0u64; n as usize], vec![0.0; 3 * n as usize]);
        if coag_sim_velocities(s, ps.as_mut_ptr(), vs.as_mut_ptr(), n as usize) == COAG_OK {
            for p in 0..n as usize {
                v.extend([
                    ps[p],
                    vs[3 * p].to_bits(),
                    vs[3 * p + 1].to_bits(),
                    vs[3 * p + 2].to_bits(),
                ]);
            }
        }
        coag_sim_free(s);
        coag_options_free(o);
        coag_kernel_free(k);
        v
    }
}

#[test]
fn every_scheme_matches_across_front_ends() {
    for &id in registry::SCHEMES {
        let (c, r) = (c_bits(id, 1.0), rust_bits(id, 1.0));
        assert_eq!(c, r, "{}", id.name);
        assert!(!c.is_empty(), "{}", id.name);
    }
}
