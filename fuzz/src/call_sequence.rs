//! Random call sequences over live handles of every scheme, with random arguments
//! (NaN, infinities, huge and tiny values included). After each successful call the
//! invariants hold: a sim's time is finite and where the call put it, moments are
//! finite (or `COAG_CAPACITY`), and under pure coagulation an advance keeps the mass
//! concentration M1 and does not raise the number concentration M0. A failed call
//! leaves the sim as it was. No call returns `COAG_PANIC`.

use super::{check_observables, checkpoint, is_status, kinds, last_error, scheme_of, sim_of};
use arbitrary::Arbitrary;
use coagula::*;
use std::ptr::{null, null_mut};

/// A double from a byte code: the interesting values, or a scaled one.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Zero,
    Neg(u8),
    Small(u16),
    Big(u16),
    Tiny,
    Huge,
    Nan,
    Inf,
    Raw(u64),
}

impl Num {
    fn value(self) -> f64 {
        match self {
            Num::Zero => 0.0,
            Num::Neg(v) => -f64::from(v) - 0.5,
            Num::Small(v) => f64::from(v) / 256.0,
            Num::Big(v) => f64::from(v) * 1e3,
            Num::Tiny => 5e-324,
            Num::Huge => 1e300,
            Num::Nan => f64::NAN,
            Num::Inf => f64::INFINITY,
            Num::Raw(b) => f64::from_bits(b),
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Op {
    New(u8),
    Free(u8),
    Advance(u8, Num),
    AdvanceBy(u8, u8),
    SetCounts(u8, Vec<u8>, Num),
    SetSizes(u8, Vec<u16>),
    SetKernel(u8, u8, Num),
    SetDt(u8, Num),
    SetTime(u8, Num),
    SetMass(u8, Num),
    WorkLimit(u8, u16),
    Reseed(u8, u64),
    Moment(u8, Num),
    Concentration(u8, Num, Num),
    Counts(u8, u16),
    Sizes(u8, u16),
    RoundTrip(u8),
    RestoreInto(u8, u8),
    Clone(u8),
    Config(u8),
}

const SLOTS: usize = 4;

fn slot(i: u8) -> usize {
    usize::from(i) % SLOTS
}

/// M0 and M1 of a sim when both are finite.
unsafe fn m01(s: *const coag_sim) -> Option<(f64, f64)> {
    let (mut a, mut b) = (0.0, 0.0);
    unsafe {
        (coag_sim_moment(s, 0.0, &mut a) == COAG_OK && coag_sim_moment(s, 1.0, &mut b) == COAG_OK)
            .then_some((a, b))
    }
}

/// A built-in kernel of core's table (every family; a temperature model or a gas is
/// refused by a coagulation sim) with its first parameter `p`.
unsafe fn kernel(code: u8, p: Num) -> Option<*mut coag_kernel> {
    let all = coagula_core::kernel::builtin::BUILTINS;
    let b = &all[usize::from(code) % all.len()];
    let name = std::ffi::CString::new(b.name).unwrap();
    let v = [p.value()];
    let n = usize::from(code / 64 % 2).min(b.params.len());
    let mut k = null_mut();
    let st = unsafe { coag_kernel_new(name.as_ptr(), v.as_ptr(), n, &mut k) };
    assert!(is_status(st));
    (st == COAG_OK).then_some(k)
}

/// Runs the operations decoded from `data` (as libFuzzer's typed target decodes
/// them: `Vec<Op>` from the whole input).
pub fn run(data: &[u8]) {
    let u = arbitrary::Unstructured::new(data);
    let Ok(ops) = <Vec<Op> as Arbitrary>::arbitrary_take_rest(u) else {
        return;
    };
    let mut sims: [(*mut coag_sim, usize); SLOTS] = [(null_mut(), 0); SLOTS];
    unsafe {
        for op in ops.into_iter().take(32) {
            macro_rules! live {
                ($i:expr) => {
                    sims[slot($i)].0
                };
            }
            match op {
                Op::New(kind) => {
                    let i = slot(kind);
                    coag_sim_free(sims[i].0);
                    // (% 2·kinds: the slot engine's kind too)
                    let kind = usize::from(kind >> 2) % (2 * kinds());
                    // 60 monomers and 128 KiB of tables: most of an execution's time
                    // went into growing, checkpointing and cloning size tables
                    // (set_counts made sizes up to millions), which the budget caps
                    let s = sim_of(kind, 60, 128 << 10);
                    // short calls: many operations per execution
                    assert_eq!(coag_sim_set_work_limit(s, 500), COAG_OK);
                    sims[i] = (s, kind);
                }
                Op::Free(i) => {
                    coag_sim_free(sims[slot(i)].0);
                    sims[slot(i)].0 = null_mut();
                }
                Op::Advance(i, t) | Op::SetCounts(i, _, t) if live!(i).is_null() => {
                    let _ = t;
                    let st = coag_sim_advance_to(null_mut(), 1.0, null_mut());
                    assert_eq!(st, COAG_NULL_PARAMETER);
                }
                Op::Advance(i, t) => {
                    let s = live!(i);
                    let before = m01(s);
                    let mut t0 = 0.0;
                    coag_sim_time(s, &mut t0);
                    let target = t.value().min(t0 + 50.0);
                    // the state is compared only where the call must refuse
                    let ck = (target.is_nan() || target < t0).then(|| checkpoint(s));
                    let st = coag_sim_advance_to(s, target, null_mut());
                    assert!(is_status(st), "advance: {st}: {}", last_error());
                    let mut t1 = -1.0;
                    assert_eq!(coag_sim_time(s, &mut t1), COAG_OK);
                    if st == COAG_OK {
                        assert_eq!(t1, target, "time after advance");
                        // pure coagulation keeps the mass and never raises the number
                        let pure = {
                            let id = scheme_of(sims[slot(i)].1);
                            id.law != coagula_core::scheme::facade::Law::TimeStepped
                                && id.law != coagula_core::scheme::facade::Law::Gas
                        };
                        if let (Some((n0, m0)), Some((n1, m1)), true) = (before, m01(s), pure) {
                            assert!(n1 <= n0 * (1.0 + 1e-12), "N/V rose: {n0} -> {n1}");
                            assert!((m1 - m0).abs() <= 1e-9 * m0, "M1 changed: {m0} -> {m1}");
                        }
                    } else if st == COAG_TIME_BACKWARDS
                        || st == COAG_INVALID_ARGUMENT && !target.is_finite()
                    {
                        assert_eq!(Some(checkpoint(s)), ck, "refused advance changed the sim");
                    } else if st == COAG_INTERRUPTED {
                        assert!(t1 >= t0 && t1 <= target);
                    }
                    check_observables(s);
                }
                Op::AdvanceBy(i, h) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let mut t0 = 0.0;
                    coag_sim_time(s, &mut t0);
                    let st = coag_sim_advance_to(s, t0 + f64::from(h) / 64.0, null_mut());
                    assert!(is_status(st), "advance: {st}: {}", last_error());
                    check_observables(s);
                }
                Op::SetCounts(i, counts, v) => {
                    let s = live!(i);
                    let c: Vec<u64> = counts.iter().take(24).map(|&c| u64::from(c)).collect();
                    let ck = checkpoint(s);
                    let st = coag_sim_set_counts(s, c.as_ptr(), c.len(), v.value());
                    assert!(is_status(st));
                    if st != COAG_OK {
                        assert_eq!(checkpoint(s), ck, "refused set_counts changed the sim");
                    }
                    check_observables(s);
                }
                Op::SetSizes(i, sizes) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let x: Vec<f64> = sizes.iter().take(64).map(|&v| f64::from(v) / 8.0).collect();
                    let ck = checkpoint(s);
                    let st = coag_sim_set_sizes(s, x.as_ptr(), x.len());
                    assert!(is_status(st));
                    if st != COAG_OK {
                        assert_eq!(checkpoint(s), ck, "refused set_sizes changed the sim");
                    }
                    check_observables(s);
                }
                Op::SetKernel(i, code, p) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    if let Some(k) = kernel(code, p) {
                        let ck = checkpoint(s);
                        let st = coag_sim_set_kernel(s, k);
                        assert!(is_status(st));
                        if st != COAG_OK {
                            assert_eq!(checkpoint(s), ck);
                        }
                        coag_kernel_free(k);
                    }
                }
                Op::SetDt(i, v) | Op::SetTime(i, v) | Op::SetMass(i, v) if live!(i).is_null() => {
                    let _ = v;
                }
                Op::SetDt(i, v) => {
                    let st = coag_sim_set_dt(live!(i), v.value());
                    assert!(is_status(st));
                }
                Op::SetTime(i, v) => {
                    let st = coag_sim_set_time(live!(i), v.value());
                    assert!(is_status(st));
                    if st == COAG_OK {
                        let mut t = 0.0;
                        coag_sim_time(live!(i), &mut t);
                        assert_eq!(t, v.value());
                    }
                }
                Op::SetMass(i, v) => {
                    let st = coag_sim_set_mass(live!(i), v.value());
                    assert!(is_status(st));
                    check_observables(live!(i));
                }
                Op::WorkLimit(i, units) => {
                    if !live!(i).is_null() {
                        assert_eq!(
                            // never 0 (unlimited): a tiny Δt would then run for hours
                            coag_sim_set_work_limit(live!(i), 1 + u64::from(units % 1024) * 2),
                            COAG_OK
                        );
                    }
                }
                Op::Reseed(i, seed) => {
                    let st = coag_sim_reseed(live!(i), seed, 0);
                    assert!(st == COAG_OK || live!(i).is_null() && st == COAG_NULL_PARAMETER);
                }
                Op::Moment(i, m) => {
                    let mut v = 0.0;
                    let st = coag_sim_moment(live!(i), m.value(), &mut v);
                    assert!(is_status(st));
                    if st == COAG_OK {
                        assert!(v.is_finite());
                    }
                }
                Op::Concentration(i, a, b) => {
                    let mut v = 0.0;
                    let st = coag_sim_concentration(live!(i), a.value(), b.value(), &mut v);
                    assert!(is_status(st));
                    if st == COAG_OK {
                        assert!(
                            v.is_finite() && v >= 0.0 && v.is_sign_positive(),
                            "C({}, {}) = {v}",
                            a.value(),
                            b.value()
                        );
                    }
                }
                Op::Counts(i, len) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let mut need = 0usize;
                    if coag_sim_state_len(s, &mut need) == COAG_OK && need <= 1 << 20 {
                        let mut buf = vec![0u64; usize::from(len).min(need + 2)];
                        let mut v = 0.0;
                        let st = coag_sim_get_counts(s, buf.as_mut_ptr(), buf.len(), &mut v);
                        assert!(is_status(st));
                    }
                }
                Op::Sizes(i, len) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let mut buf = vec![0.0f64; usize::from(len) % 64];
                    let st = coag_sim_get_sizes(s, buf.as_mut_ptr(), buf.len());
                    assert!(is_status(st));
                }
                Op::RoundTrip(i) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let ck = checkpoint(s);
                    assert_eq!(coag_sim_restore(s, ck.as_ptr(), ck.len()), COAG_OK);
                    assert_eq!(checkpoint(s), ck, "round trip changed the sim");
                }
                Op::RestoreInto(i, j) => {
                    let (a, b) = (live!(i), live!(j));
                    if a.is_null() || b.is_null() {
                        continue;
                    }
                    let (ca, cb) = (checkpoint(a), checkpoint(b));
                    let st = coag_sim_restore(b, ca.as_ptr(), ca.len());
                    assert!(
                        st == COAG_OK || st == COAG_BAD_CHECKPOINT || st == COAG_CAPACITY,
                        "{st}"
                    );
                    if st != COAG_OK {
                        assert_eq!(checkpoint(b), cb);
                    }
                }
                Op::Config(i) => {
                    // the scheme's name and its named observables read back
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let mut name = std::ptr::null();
                    assert_eq!(coag_sim_scheme(s, &mut name), COAG_OK);
                    let name = std::ffi::CStr::from_ptr(name).to_str().unwrap();
                    let id = coagula_core::scheme::registry::find(name).unwrap();
                    for o in id.observables {
                        let o = std::ffi::CString::new(*o).unwrap();
                        let mut v = 0.0;
                        let st = coag_sim_observable(s, o.as_ptr(), &mut v);
                        assert!(st == COAG_OK || st == COAG_CAPACITY, "{st}");
                    }
                    let mut v = 0.0;
                    assert_eq!(
                        coag_sim_observable(s, c"no-such".as_ptr(), &mut v),
                        COAG_UNSUPPORTED
                    );
                }
                Op::Clone(i) => {
                    let s = live!(i);
                    if s.is_null() {
                        continue;
                    }
                    let mut c = null_mut();
                    let st = coag_sim_clone(s, &mut c);
                    assert_eq!(st, COAG_OK, "clone: {}", last_error());
                    assert_eq!(checkpoint(c), checkpoint(s), "clone differs");
                    let j = (slot(i) + 1) % SLOTS;
                    coag_sim_free(sims[j].0);
                    sims[j] = (c, sims[slot(i)].1);
                }
            }
        }
        for (s, _) in sims {
            coag_sim_free(s);
        }
        let _ = null::<u8>();
    }
}
