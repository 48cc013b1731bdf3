//! Tests of [`dsmc`](super).

use super::*;
use crate::checkpoint::{Reader, Writer};
use crate::random::normal;
use rand_core::SeedableRng;

/// A velocity of speed about `10^e` in a random direction.
fn velocity(rng: &mut rand_pcg::Pcg64Mcg, e: f64) -> [f64; 3] {
    let s = libm::pow(10.0, e);
    [s * normal(rng), s * normal(rng), s * normal(rng)]
}

/// Checks a species' counts, range, top and sum against its classes.
fn check(sp: &Species) {
    let n: usize = sp.classes.iter().map(|c| c.v.len()).sum();
    assert_eq!(sp.n, n);
    // the sum kept up to date is the one recomputed from the contents, bit for bit
    let mut again = sp.clone();
    again.resum();
    assert_eq!(sp.s.to_bits(), again.s.to_bits());
    assert_eq!(
        (sp.lo, sp.end, sp.exact, sp.x, sp.top.to_bits()),
        (
            again.lo,
            again.end,
            again.exact,
            again.x,
            again.top.to_bits()
        )
    );
    if n == 0 {
        assert_eq!((sp.s, sp.top), (0.0, 0.0));
        return;
    }
    assert!(sp.classes.len() <= MAX_CLASSES + 6, "{}", sp.classes.len());
    let moving = &sp.classes[1..];
    let (lo, end) = (sp.lo - 1, sp.end - 1);
    assert!(
        moving[..lo]
            .iter()
            .chain(&moving[end..])
            .all(|c| c.v.is_empty())
    );
    if lo < end {
        assert!(!moving[lo].v.is_empty() && !moving[end - 1].v.is_empty());
        assert_eq!(sp.top, moving[end - 1].w);
    } else {
        assert_eq!(sp.top, sp.classes[0].w);
    }
    let naive: f64 = sp.classes.iter().map(|c| c.v.len() as f64 * c.w).sum();
    assert!((sp.s - naive).abs() <= 1e-12 * naive, "{} vs {naive}", sp.s);
    for (d, c) in sp.classes.iter().enumerate() {
        let q = sp.q(d);
        assert_eq!(sp.index(q), Some(d));
        assert_eq!(c.w, class_bound(q));
        for v in &c.v {
            assert_eq!(class_of(v), q);
            assert!(norm(v) < c.w);
        }
    }
}

/// Random inserts and removals, speeds about `10^{center ± spread/2}`, checked after
/// each.
fn moves(
    sp: &mut Species,
    (center, spread): (f64, f64),
    steps: usize,
    rng: &mut rand_pcg::Pcg64Mcg,
) {
    for step in 0..steps {
        let remove = sp.n > 0 && (step % 3 == 2 || unit_f64(rng.next_u64()) < 0.3);
        if remove {
            let (d, idx) = sp.locate(below(rng, sp.n as u64) as usize);
            sp.remove(d, idx);
        } else {
            let v = match step % 50 {
                7 => [0.0; 3],
                // (|v|² = 2e-320, subnormal)
                8 => [1e-160, 0.0, -1e-160],
                _ => {
                    let e = center + spread * (unit_f64(rng.next_u64()) - 0.5);
                    velocity(rng, e)
                }
            };
            sp.reserve(&[class_of(&v)]).unwrap();
            sp.insert(v);
        }
        check(sp);
    }
}

#[test]
fn class_sums_follow_every_move() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    // speeds over a few octaves and over 2^110 (sums past 128 bits at times), with
    // particles at rest (zero and subnormal |v|²) among them
    for spread in [2.0, 33.0] {
        let mut sp = Species::default();
        moves(&mut sp, (0.0, spread), 4000, &mut rng);
        // (the exact sums are the common case: at rest or not)
        if spread == 2.0 {
            assert!(sp.exact);
        }
    }
}

#[test]
fn sums_fall_back_and_come_back() {
    let mut sp = Species::default();
    for _ in 0..4 {
        let v = [1.0, 0.0, 0.0];
        sp.reserve(&[class_of(&v)]).unwrap();
        sp.insert(v);
    }
    // at rest: still exact
    sp.reserve(&[Q_MIN]).unwrap();
    sp.insert([0.0; 3]);
    check(&sp);
    assert!(sp.exact);
    // 2^{-126} next to four at 1: X_0 would be 4 · 2^126
    let slow = [libm::scalbn(1.0, -126), 0.0, 0.0];
    sp.reserve(&[class_of(&slow)]).unwrap();
    sp.insert(slow);
    check(&sp);
    assert!(!sp.exact);
    let d = sp.index(class_of(&slow)).unwrap();
    sp.remove(d, 0);
    check(&sp);
    assert!(sp.exact);
    // speeds 2^128 apart are refused, and the species is as it was
    let before = sp.clone();
    let far = [libm::scalbn(1.0, -129), 0.0, 0.0];
    assert!(matches!(
        sp.reserve(&[class_of(&far)]),
        Err(Error::Capacity { .. })
    ));
    check(&sp);
    assert_eq!((sp.n, sp.s.to_bits()), (before.n, before.s.to_bits()));
}

/// The refusal of speeds 2^128 apart does not depend on the order the particles come
/// in (classes 0 and −511 are 511 apart; −514, inside the padding a rebuild leaves
/// below −511, is 514 from 0), and a bounce's two classes are reserved together.
#[test]
fn refusals_do_not_depend_on_order() {
    let at = |q: i32| [libm::sqrt(libm::exp2(f64::from(q) / 2.0 + 0.1)), 0.0, 0.0];
    for order in [[0, -511, -514], [-514, -511, 0], [-511, -514, 0]] {
        let mut sp = Species::default();
        let mut got = Vec::new();
        for q in order {
            assert_eq!(class_of(&at(q)), q);
            let r = sp.reserve(&[q]);
            if r.is_ok() {
                sp.insert(at(q));
            }
            got.push(r.is_ok());
            check(&sp);
        }
        // whichever came first of 0 and −514, the other is refused; −511 fits
        let refused = got.iter().filter(|ok| !**ok).count();
        assert_eq!(refused, 1, "{order:?}: {got:?}");
    }
    // two classes at once, both outside the range: one rebuild holds both
    let mut sp = Species::default();
    sp.reserve(&[0]).unwrap();
    sp.insert(at(0));
    sp.reserve(&[-40, 60]).unwrap();
    sp.insert(at(-40));
    sp.insert(at(60));
    check(&sp);
    assert_eq!(sp.n, 3);
}

/// A size whose speeds drift down (a cooling gas) keeps a bounded range of classes:
/// the empty ones above are dropped when the range is rebuilt.
#[test]
fn the_range_follows_the_speeds() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let mut sp = Species::default();
    for k in 0..60 {
        // speeds around 10^{-k}: the range would span 800 classes if never trimmed
        moves(&mut sp, (-f64::from(k), 1.0), 60, &mut rng);
        // (a few stay: the range moves down with particles in it all along)
        while sp.n > 3 {
            let (d, idx) = sp.locate(below(&mut rng, sp.n as u64) as usize);
            sp.remove(d, idx);
            check(&sp);
        }
    }
}

#[test]
fn an_older_checkpoint_with_zero_speeds_loads() {
    // the format before the dense classes: v = 0 in class i32::MIN, classes in
    // the order they were made
    let mut buf = alloc::vec![0u8; 1024];
    let mut w = Writer::new(&mut buf);
    w.u64(1);
    w.u64(4);
    w.u64(class_of(&[2.0, 0.0, 0.0]) as i64 as u64);
    w.f64s(&[2.0, 0.0, 0.0]);
    w.u64(i32::MIN as i64 as u64);
    w.f64s(&[0.0; 6]);
    w.u64(class_of(&[0.5, 0.0, 0.0]) as i64 as u64);
    w.f64s(&[]);
    // |v|² = 2^{−1022.2} (subnormal): the old layout's class −2045, which is Q_MIN's
    // number
    let tiny = libm::sqrt(libm::exp2(-1022.2));
    w.u64(-2045i64 as u64);
    w.f64s(&[tiny, 0.0, 0.0]);
    let len = w.needed();
    let gas = Gas::from_particles(0.9, NeverStick, &[1], &[[1.0, 0.0, 0.0]]).unwrap();
    let mut r = Reader::new(&buf[..len]);
    let back = Collisions::default().load(&gas, &mut r).unwrap().unwrap();
    assert_eq!(back.counts(), alloc::vec![4]);
    let sp = &back.species[0];
    check(sp);
    assert_eq!(sp.classes[sp.index(Q_MIN).unwrap()].v.len(), 3);
    // a class listed twice is refused
    let mut buf = alloc::vec![0u8; 1024];
    let mut w = Writer::new(&mut buf);
    w.u64(1);
    w.u64(2);
    for _ in 0..2 {
        w.u64(class_of(&[2.0, 0.0, 0.0]) as i64 as u64);
        w.f64s(&[2.0, 0.0, 0.0]);
    }
    let len = w.needed();
    let mut r = Reader::new(&buf[..len]);
    assert!(matches!(
        Collisions::default().load(&gas, &mut r),
        Err(Error::Checkpoint { .. })
    ));
}
