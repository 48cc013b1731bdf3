//! Shared by the fuzz targets: small sims of every scheme through the C ABI, and the
//! checks every call must pass.

use coagula::*;
use std::ptr::null_mut;

/// The scheme kinds the targets build: every scheme of core's registry in its order,
/// and, at `kinds() + i`, scheme i with the options that pin what a small system would
/// not reach by itself (the bucketed low-rank scheme's slot engine).
pub fn kinds() -> usize {
    coagula_core::scheme::registry::SCHEMES.len()
}

/// The registry's bucketed low-rank scheme on the slot engine (see [`kinds`]).
pub fn slots_kind() -> usize {
    kinds()
        + coagula_core::scheme::registry::SCHEMES
            .iter()
            .position(|s| s.name == "lowrank")
            .unwrap_or(0)
}

/// Statuses a call may return (anything else, in particular `COAG_PANIC`, is a bug).
pub fn is_status(st: i32) -> bool {
    (COAG_OK..=COAG_REENTRANT).contains(&st) && st != COAG_PANIC
}

/// A small sim of kind `kind` (see [`kinds`]) from its registry entry's capabilities:
/// the additive kernel, a temperature model or hard spheres as its model takes;
/// 16 particle sizes, counts of 300 monomers and a few larger, the same counts at
/// temperature 1, or 45 Maxwellian particles; its growing tables capped at 16 MiB and
/// every call at 20 000 proposals, so that an execution stays short.
///
/// # Safety
/// Returns a live handle, freed by the caller with `coag_sim_free`.
pub unsafe fn small_sim(kind: usize) -> *mut coag_sim {
    unsafe { sim_of(kind, 300, 16 << 20) }
}

/// The scheme of kind `kind` (see [`kinds`]).
pub fn scheme_of(kind: usize) -> coagula_core::scheme::facade::SchemeId {
    let all = coagula_core::scheme::registry::SCHEMES;
    all[kind % all.len()]
}

/// As [`small_sim`] with `monomers` monomers (and 20 dimers, 3 of size 4) in a count
/// scheme and its tables capped at `budget` bytes.
///
/// # Safety
/// Returns a live handle, freed by the caller with `coag_sim_free`.
pub unsafe fn sim_of(kind: usize, monomers: u64, budget: u64) -> *mut coag_sim {
    use coagula_core::scheme::facade::{InitKind, ModelKind};
    let id = scheme_of(kind);
    unsafe {
        let (kname, params): (&std::ffi::CStr, &[f64]) = match id.model {
            ModelKind::Coagulation => (c"additive", &[1.0]),
            ModelKind::Temperature => (c"temperature-ballistic", &[]),
            ModelKind::Gas => (c"hard-spheres", &[0.9]),
        };
        let mut k = null_mut();
        assert_eq!(
            coag_kernel_new(kname.as_ptr(), params.as_ptr(), params.len(), &mut k),
            COAG_OK
        );
        let mut o = null_mut();
        assert_eq!(coag_options_new(&mut o), COAG_OK);
        if id.takes_option("memory-budget") {
            assert_eq!(
                coag_options_set_count(o, c"memory-budget".as_ptr(), budget),
                COAG_OK
            );
        }
        if id.takes_option("dt") {
            assert_eq!(coag_options_set_real(o, c"dt".as_ptr(), 0.05), COAG_OK);
        }
        if id.takes_option("engine") && (kind / kinds()) % 2 == 1 {
            assert_eq!(
                coag_options_set_name(o, c"engine".as_ptr(), c"slots".as_ptr()),
                COAG_OK
            );
        }
        let name = std::ffi::CString::new(id.name).unwrap();
        let n = [monomers, 20, 0, 3];
        let x: Vec<f64> = (0..16).map(|i| 1.0 + (i % 3) as f64).collect();
        let mut s = null_mut();
        let st = match id.inits[0] {
            InitKind::Counts => coag_sim_new_counts(
                name.as_ptr(),
                k,
                std::ptr::null(),
                o,
                n.as_ptr(),
                n.len(),
                monomers as f64,
                &mut s,
            ),
            InitKind::Sizes => coag_sim_new_sizes(
                name.as_ptr(),
                k,
                std::ptr::null(),
                o,
                x.as_ptr(),
                x.len(),
                1.0,
                &mut s,
            ),
            InitKind::Temperatures => coag_sim_new_temperatures(
                name.as_ptr(),
                k,
                o,
                n.as_ptr(),
                [1.0; 4].as_ptr(),
                n.len(),
                monomers as f64,
                &mut s,
            ),
            InitKind::Velocities => coag_sim_new_maxwellian(
                name.as_ptr(),
                k,
                o,
                [40, 5].as_ptr(),
                [1.0, 1.0].as_ptr(),
                2,
                450.0,
                &mut s,
            ),
        };
        assert_eq!(st, COAG_OK, "{}: {}", id.name, last_error());
        coag_options_free(o);
        coag_kernel_free(k);
        assert_eq!(coag_sim_set_work_limit(s, 20_000), COAG_OK);
        s
    }
}

/// The sim's checkpoint.
///
/// # Safety
/// `s` live.
pub unsafe fn checkpoint(s: *const coag_sim) -> Vec<u8> {
    unsafe {
        let mut n = 0usize;
        assert_eq!(coag_sim_checkpoint_size(s, &mut n), COAG_OK);
        let mut b = vec![0u8; n];
        assert_eq!(
            coag_sim_checkpoint(s, b.as_mut_ptr(), n, null_mut()),
            COAG_OK
        );
        b
    }
}

/// Replaces the last 8 bytes by the checksum of the rest (so that the fuzzer reaches
/// the state's own validation).
pub fn reseal(b: &mut [u8]) {
    if b.len() >= 8 {
        let at = b.len() - 8;
        let sum = coagula_core::checkpoint::checksum(&b[..at]);
        b[at..].copy_from_slice(&sum.to_le_bytes());
    }
}

/// The checks every live sim passes: a finite time that is not negative; M0 and M1
/// finite and not negative, or `COAG_CAPACITY` when they overflow a double.
///
/// # Safety
/// `s` live.
pub unsafe fn check_observables(s: *const coag_sim) {
    unsafe {
        let mut t = -1.0;
        assert_eq!(coag_sim_time(s, &mut t), COAG_OK);
        assert!(t.is_finite() && t >= 0.0, "time {t}");
        for m in [0.0, 1.0] {
            let mut v = -1.0;
            let st = coag_sim_moment(s, m, &mut v);
            assert!(
                st == COAG_CAPACITY || (st == COAG_OK && v.is_finite() && v >= 0.0),
                "M{m} = {v} ({st})"
            );
        }
        let mut n = 0u64;
        assert_eq!(coag_sim_particle_count(s, &mut n), COAG_OK);
    }
}

/// The message of the last failed call on this thread.
pub fn last_error() -> String {
    let mut buf = vec![0 as std::ffi::c_char; 1024];
    unsafe { coag_last_error_message(buf.as_mut_ptr(), buf.len(), std::ptr::null_mut()) };
    unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

/// Restore from arbitrary bytes into a sim of every scheme: a checkpoint is either
/// refused (`COAG_BAD_CHECKPOINT`, or `COAG_CAPACITY` past the memory budget) with the
/// sim unchanged, or accepted as a valid state that a bounded advance takes to a
/// status. The first byte picks the scheme and whether the bytes are resealed with a
/// correct checksum (to reach the state's own validation).
pub fn checkpoint_restore(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let mut buf = rest.to_vec();
    if mode & 1 == 1 {
        reseal(&mut buf);
    }
    unsafe {
        let s = small_sim(usize::from(mode >> 1));
        let before = checkpoint(s);
        let st = coag_sim_restore(s, buf.as_ptr(), buf.len());
        match st {
            COAG_OK => {
                // a short advance shows the restored state runs (1000 proposals keep
                // an execution under a millisecond)
                assert_eq!(coag_sim_set_work_limit(s, 1000), COAG_OK);
                check_observables(s);
                let mut t = 0.0;
                assert_eq!(coag_sim_time(s, &mut t), COAG_OK);
                let a = coag_sim_advance_to(s, t + 0.5, std::ptr::null_mut());
                assert!(is_status(a), "advance after restore: {a}: {}", last_error());
                check_observables(s);
            }
            COAG_BAD_CHECKPOINT | COAG_CAPACITY => {
                assert_eq!(checkpoint(s), before, "a refused restore changed the sim");
            }
            other => panic!("restore returned {other}"),
        }
        coag_sim_free(s);
    }
}

/// The seed inputs of `checkpoint_restore`, by file name: a checkpoint of every
/// scheme (and of the slot engine), fresh and advanced to t = 0.3 and 1, under both modes (as written, and
/// resealed after the mode byte). `cargo test` checks that the committed seeds are
/// these (a format change must regenerate them with `seed_corpus`, or the campaign
/// starts from checkpoints that are all refused at the configuration record).
pub fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for kind in (0..kinds()).chain([slots_kind()]) {
        unsafe {
            let s = small_sim(kind);
            if scheme_of(kind).name == "lowrank" {
                let mut m = std::ptr::null();
                assert_eq!(coag_sim_engine(s, &mut m), COAG_OK);
                let m = std::ffi::CStr::from_ptr(m).to_str().unwrap();
                let want = if kind == slots_kind() {
                    "slots"
                } else {
                    "counted"
                };
                assert_eq!(m, want, "kind {kind}: the engine");
            }
            for (step, t) in [0.0, 0.3, 1.0].into_iter().enumerate() {
                seed_at(s, kind, step, t, &mut out);
            }
            coag_sim_free(s);
        }
    }
    // the slot engine drawing proposals ahead (2^21 monomers: past 2^20 slots), whose
    // queue of them is in the checkpoint; restorable into the small sim of its kind
    unsafe {
        let s = sim_of(slots_kind(), 1 << 21, 16 << 20);
        seed_at(s, slots_kind(), 3, 1e-3, &mut out);
        coag_sim_free(s);
    }
    out
}

/// Advances `s` to `t` and adds its checkpoint as seed `seed-{kind}-{step}-{reseal}`,
/// as written and resealed.
///
/// # Safety
/// `s` live.
unsafe fn seed_at(
    s: *mut coag_sim,
    kind: usize,
    step: usize,
    t: f64,
    out: &mut Vec<(String, Vec<u8>)>,
) {
    let st = unsafe { coag_sim_advance_to(s, t, std::ptr::null_mut()) };
    assert_eq!(st, COAG_OK, "seed advance: {}", last_error());
    let ck = unsafe { checkpoint(s) };
    for reseal in 0..2u8 {
        let mut data = vec![(kind as u8) << 1 | reseal];
        data.extend_from_slice(&ck);
        out.push((format!("seed-{kind}-{step}-{reseal}"), data));
    }
}

#[path = "call_sequence.rs"]
pub mod call_sequence;

/// Langevin batches of the `langevin_restore` target: dim 1 (the paper's problem with
/// its border and bound) or 3 (a ball with friction), specular or absorbing.
pub const LANGEVIN_KINDS: usize = 4;

/// A small Langevin batch of kind `k` (8 trajectories).
///
/// # Safety
/// Returns a live handle the caller frees.
pub unsafe fn small_langevin(k: usize) -> *mut coag_langevin {
    unsafe {
        let mut c = std::mem::zeroed::<coag_langevin_config>();
        assert_eq!(
            coag_langevin_default_config(&mut c, std::mem::size_of::<coag_langevin_config>()),
            COAG_OK
        );
        c.wall = if k.is_multiple_of(2) {
            COAG_WALL_SPECULAR
        } else {
            COAG_WALL_ABSORBING
        };
        c.dt = 0.05;
        let (x, u): (Vec<f64>, Vec<f64>) = if k < 2 {
            c.drift = COAG_DRIFT_MAFTEI2016;
            c.period = 1.0;
            c.bound_kind = COAG_BOUND_REFLECT;
            c.bound = 10.0;
            (vec![0.5], vec![-1.5])
        } else {
            c.dim = 3;
            c.radius = 1.0;
            c.drift = COAG_DRIFT_FRICTION;
            c.friction_rate = 1.0;
            (vec![1.5, 0.0, 0.0], vec![-1.0, 0.0, 0.0])
        };
        let mut h = null_mut();
        assert_eq!(
            coag_langevin_new(&c, 8, x.as_ptr(), u.as_ptr(), 3, 0, &mut h),
            COAG_OK
        );
        h
    }
}

/// A Langevin batch's checkpoint.
///
/// # Safety
/// `h` live.
pub unsafe fn langevin_checkpoint(h: *const coag_langevin) -> Vec<u8> {
    unsafe {
        let mut n = 0;
        assert_eq!(coag_langevin_checkpoint_size(h, &mut n), COAG_OK);
        let mut b = vec![0u8; n];
        let mut w = 0;
        assert_eq!(coag_langevin_save(h, b.as_mut_ptr(), n, &mut w), COAG_OK);
        b.truncate(w);
        b
    }
}

/// Restore from arbitrary bytes into a Langevin batch: refused (`COAG_BAD_CHECKPOINT`)
/// with the batch unchanged, or accepted as a state that steps on (at most 1000 steps
/// of the restored dt, read from the checkpoint) to a status, with finite positions and
/// velocities. The first byte picks the kind and whether to reseal.
pub fn langevin_restore(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let mut buf = rest.to_vec();
    if mode & 1 == 1 {
        reseal(&mut buf);
    }
    unsafe {
        let h = small_langevin(usize::from(mode >> 1) % LANGEVIN_KINDS);
        let before = langevin_checkpoint(h);
        match coag_langevin_restore(h, buf.as_ptr(), buf.len()) {
            COAG_OK => {
                // dt is word 11: after the envelope's six words (magic, version, tag,
                // no records, the drift's fingerprint, no stream) and the batch's
                // header (three words), D and n
                let dt = f64::from_le_bytes(buf[88..96].try_into().unwrap());
                assert!(dt > 0.0 && dt.is_finite(), "restored dt {dt}");
                let (mut t, mut dim, mut n) = (0.0, 0usize, 0u64);
                assert_eq!(coag_langevin_info(h, &mut t, &mut dim, &mut n), COAG_OK);
                assert!(t.is_finite() && t >= 0.0 && n == 8, "time {t}, n {n}");
                let st = coag_langevin_advance_to(h, t + (1000.0 * dt).min(0.5), null_mut());
                assert!(
                    is_status(st),
                    "advance after restore: {st}: {}",
                    last_error()
                );
                let mut x = vec![0.0; 8 * dim];
                let mut u = vec![0.0; 8 * dim];
                assert_eq!(
                    coag_langevin_state(
                        h,
                        x.as_mut_ptr(),
                        u.as_mut_ptr(),
                        null_mut(),
                        null_mut(),
                        8
                    ),
                    COAG_OK
                );
                assert!(
                    x.iter().chain(&u).all(|v| v.is_finite()),
                    "state {x:?} {u:?}"
                );
            }
            COAG_BAD_CHECKPOINT => {
                assert_eq!(
                    langevin_checkpoint(h),
                    before,
                    "a refused restore changed the batch"
                );
            }
            other => panic!("restore returned {other}: {}", last_error()),
        }
        coag_langevin_free(h);
    }
}

/// The seed inputs of `langevin_restore`: every kind fresh and at t = 0.3 and 1, as
/// written and resealed.
pub fn langevin_seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for kind in 0..LANGEVIN_KINDS {
        unsafe {
            let h = small_langevin(kind);
            for (step, t) in [0.0, 0.3, 1.0].into_iter().enumerate() {
                assert_eq!(coag_langevin_advance_to(h, t, null_mut()), COAG_OK);
                let ck = langevin_checkpoint(h);
                for reseal in 0..2u8 {
                    let mut data = vec![(kind as u8) << 1 | reseal];
                    data.extend_from_slice(&ck);
                    out.push((format!("seed-{kind}-{step}-{reseal}"), data));
                }
            }
            coag_langevin_free(h);
        }
    }
    out
}
