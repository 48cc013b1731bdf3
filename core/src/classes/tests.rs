use super::*;
use crate::random::generator;

fn mass(c: &Classes, n: &[f64]) -> f64 {
    n.iter().zip(c.pivots()).map(|(a, x)| a * x).sum()
}

#[test]
fn bad_grids_are_refused() {
    assert!(Classes::new(&[]).is_err());
    assert!(Classes::new(&[0.0, 1.0]).is_err());
    assert!(Classes::new(&[-1.0]).is_err());
    assert!(Classes::new(&[1.0, 1.0]).is_err());
    assert!(Classes::new(&[2.0, 1.0]).is_err());
    assert!(Classes::new(&[1.0, f64::NAN]).is_err());
    assert!(Classes::new(&[1.0, f64::INFINITY]).is_err());
    assert!(Classes::new(&[f64::MIN_POSITIVE]).is_ok());
}

#[test]
fn the_split_keeps_number_and_mass() {
    let c = Classes::new(&[1.0, 2.0, 5.0, 11.0, 30.0]).unwrap();
    assert_eq!(c.place(0.5), Place::Below);
    assert_eq!(c.place(30.5), Place::Above);
    assert_eq!(c.place(f64::NAN), Place::Above);
    assert_eq!(c.place(30.0), Place::Between { to: 4, eta: 1.0 });
    assert_eq!(c.place(1.0), Place::Between { to: 0, eta: 1.0 });
    assert_eq!(c.place(2.0), Place::Between { to: 1, eta: 1.0 });
    // a factor-2 error in η would move mass: check number and mass for many sizes
    let mut x = 1.0;
    while x <= 30.0 {
        let mut n = [0.0; 5];
        let out = c.project(|f| f(x, 0.25), &mut n).unwrap();
        assert_eq!(out, Outside::default());
        assert!((n.iter().sum::<f64>() - 0.25).abs() < 1e-15);
        assert!((mass(&c, &n) - 0.25 * x).abs() < 1e-13 * x, "{x}");
        assert!(n.iter().all(|&v| v >= 0.0));
        // only the two neighbours get any
        assert!(n.iter().filter(|&&v| v > 0.0).count() <= 2);
        x += 0.37;
    }
}

#[test]
fn outside_the_grid_is_booked_not_classed() {
    let c = Classes::new(&[2.0, 4.0]).unwrap();
    let mut n = [9.0; 2];
    let out = c
        .project(
            |f| {
                f(1.0, 2.0);
                f(3.0, 1.0);
                f(8.0, 0.5);
            },
            &mut n,
        )
        .unwrap();
    assert_eq!(n, [0.5, 0.5]);
    assert_eq!(
        out,
        Outside {
            below_number: 2.0,
            below_mass: 2.0,
            above_number: 0.5,
            above_mass: 4.0
        }
    );
}

#[test]
fn bad_points_and_buffers_leave_the_output_alone() {
    let c = Classes::new(&[1.0, 2.0]).unwrap();
    let mut n = [7.0; 2];
    assert!(c.project(|f| f(1.5, 1.0), &mut [0.0; 3]).is_err());
    for (x, w) in [
        (f64::NAN, 1.0),
        (0.0, 1.0),
        (1.0, -1.0),
        (1.0, f64::INFINITY),
    ] {
        assert!(c.project(|f| f(x, w), &mut n).is_err());
        assert_eq!(n, [7.0; 2]);
    }
}

#[test]
fn integer_pivots_give_the_counts_back() {
    // counts on sizes 1..=6 in volume 4, projected on pivots 1..=6: the same numbers
    let counts = [5u64, 0, 3, 1, 0, 2];
    let c = Classes::new(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
    let mut n = [0.0; 6];
    c.project(
        |f| {
            for (i, &k) in counts.iter().enumerate() {
                f((i + 1) as f64, k as f64 / 4.0);
            }
        },
        &mut n,
    )
    .unwrap();
    let back = c.counts(&n, 4.0, &mut generator(1, 2)).unwrap();
    assert_eq!(back, counts);
}

#[test]
fn counts_round_without_bias() {
    // 0.3 per unit volume in volume 10: 3 exactly; 0.37 → 3 or 4, mean 3.7
    let c = Classes::new(&[1.0, 2.0]).unwrap();
    let mut rng = generator(7, 0);
    let reps = 40_000;
    let mut sum = 0u64;
    for _ in 0..reps {
        let k = c.counts(&[0.3, 0.37], 10.0, &mut rng).unwrap();
        assert_eq!(k[0], 3);
        assert!(k[1] == 3 || k[1] == 4);
        sum += k[1];
    }
    // Bernoulli(0.7): SE of the mean sqrt(0.21 / reps) = 2.3e-3; 6 SE
    let mean = sum as f64 / reps as f64;
    assert!(
        (mean - 3.7).abs() < 6.0 * (0.21f64 / reps as f64).sqrt(),
        "{mean}"
    );
    assert!(c.counts(&[1.0], 1.0, &mut rng).is_err());
    assert!(c.counts(&[1.0, -1.0], 1.0, &mut rng).is_err());
    assert!(c.counts(&[1.0, f64::NAN], 1.0, &mut rng).is_err());
    assert!(c.counts(&[1.0, 1.0], 0.0, &mut rng).is_err());
    assert!(c.counts(&[1e300, 1.0], 1.0, &mut rng).is_err());
}

#[test]
fn rates_are_the_change_over_the_step() {
    let mut out = [0.0; 2];
    rates(&[1.0, 2.0], &[2.0, 1.0], 0.5, &mut out).unwrap();
    assert_eq!(out, [2.0, -2.0]);
    assert!(rates(&[1.0], &[1.0, 2.0], 1.0, &mut out).is_err());
    assert!(rates(&[1.0, 2.0], &[1.0, 2.0], 0.0, &mut out).is_err());
    assert!(rates(&[1.0, 2.0], &[1.0, 2.0], f64::NAN, &mut out).is_err());
}
