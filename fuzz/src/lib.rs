//! Shared by the fuzz targets: small sims of every scheme through the C ABI, and the
//! checks every call must pass.

use coagula::*;
use std::ptr::null_mut;

/// The scheme kinds the targets build: mass flow, then the `COAG_METHOD_*` (0–4 as
/// 1–5), then the event-driven schemes over particles (MFA, DSA). The bucketed low-rank
/// kind (1) has two engines: kind numbers `1 + KINDS·(2j + 1)` pin the slot engine,
/// which a small system would not otherwise reach ([`SLOTS_KIND`]).
pub const KINDS: usize = 8;

/// The bucketed low-rank kind on the slot engine (see [`KINDS`]).
pub const SLOTS_KIND: usize = 1 + KINDS;

/// Statuses a call may return (anything else, in particular `COAG_PANIC`, is a bug).
pub fn is_status(st: i32) -> bool {
    (COAG_OK..=COAG_RNG_FAILURE).contains(&st) && st != COAG_PANIC
}

/// A small sim of kind `kind % KINDS` (see [`KINDS`]) under the additive kernel (mass flow and the
/// event-driven schemes over particles: 16 particles; counts: 300 monomers and a few
/// larger), its growing tables capped at
/// 16 MiB and every call at 20 000 proposals, so that an execution stays short.
///
/// # Safety
/// Returns a live handle, freed by the caller with `coag_sim_free`.
pub unsafe fn small_sim(kind: usize) -> *mut coag_sim {
    unsafe { sim_of(kind, 300, 16 << 20) }
}

/// As [`small_sim`] with `monomers` monomers (and 20 dimers, 3 of size 4) in a count
/// scheme and its tables capped at `budget` bytes.
///
/// # Safety
/// Returns a live handle, freed by the caller with `coag_sim_free`.
pub unsafe fn sim_of(kind: usize, monomers: u64, budget: u64) -> *mut coag_sim {
    unsafe {
        let mut k = null_mut();
        assert_eq!(coag_kernel_new_additive(0.0, &mut k), COAG_OK);
        let mut s = null_mut();
        if kind % KINDS >= 6 {
            let mut c: coag_eventflow_config = std::mem::zeroed();
            assert_eq!(
                coag_eventflow_default_config(&mut c, size_of_val(&c)),
                COAG_OK
            );
            c.method = [COAG_EVENTFLOW_MFA, COAG_EVENTFLOW_DSA][kind % KINDS - 6];
            let x: Vec<f64> = (0..16).map(|i| 1.0 + (i % 3) as f64).collect();
            assert_eq!(
                coag_eventflow_new(&c, k, std::ptr::null(), x.as_ptr(), 16, &mut s),
                COAG_OK
            );
        } else if kind.is_multiple_of(KINDS) {
            let mut c: coag_massflow_config = std::mem::zeroed();
            assert_eq!(
                coag_massflow_default_config(&mut c, size_of_val(&c)),
                COAG_OK
            );
            c.dt = 0.05;
            let x: Vec<f64> = (0..16).map(|i| 1.0 + (i % 3) as f64).collect();
            assert_eq!(
                coag_massflow_new(&c, k, std::ptr::null(), x.as_ptr(), 16, &mut s),
                COAG_OK
            );
        } else {
            let mut c: coag_counts_config = std::mem::zeroed();
            assert_eq!(coag_counts_default_config(&mut c, size_of_val(&c)), COAG_OK);
            c.method = [
                COAG_METHOD_LOWRANK,
                COAG_METHOD_LOWRANK_TREE,
                COAG_METHOD_INVERSE,
                COAG_METHOD_REJECTION,
                COAG_METHOD_DSA_COUNTS,
            ][kind % KINDS - 1];
            c.memory_budget = budget;
            if kind % KINDS == 1 && (kind / KINDS) % 2 == 1 {
                c.bucket_mode = COAG_BUCKET_SLOTS;
            }
            let n = [monomers, 20, 0, 3];
            assert_eq!(coag_counts_new(&c, k, n.as_ptr(), n.len(), &mut s), COAG_OK);
        }
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
    for kind in (0..KINDS).chain([SLOTS_KIND]) {
        unsafe {
            let s = small_sim(kind);
            if kind % KINDS == 1 {
                let mut m = -1;
                assert_eq!(coag_sim_bucket_mode(s, &mut m), COAG_OK);
                let want = if kind == SLOTS_KIND {
                    COAG_BUCKET_SLOTS
                } else {
                    COAG_BUCKET_COUNTED
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
        let s = sim_of(SLOTS_KIND, 1 << 21, 16 << 20);
        seed_at(s, SLOTS_KIND, 3, 1e-3, &mut out);
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
                // dt is word 5 (after the header's three words, D and n)
                let dt = f64::from_le_bytes(buf[40..48].try_into().unwrap());
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
