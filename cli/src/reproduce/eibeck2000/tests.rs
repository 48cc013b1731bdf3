//! Tests of [`eibeck2000`](super).

use super::*;

#[test]
fn unknown_figures_and_plot_paths_are_refused_before_any_run() {
    let e = reproduce(&["fig9".into()], true, None).unwrap_err();
    assert!(e.contains("unknown figure"), "{e}");
    let e = reproduce(&["fig5".into()], true, Some("/no/such/dir")).unwrap_err();
    assert!(e.contains("not a directory"), "{e}");
}

/// The ensemble's statistics are per output time and functional, over the
/// replicas, and the effort is cumulative: a small DSA run from monomers under
/// K = 1 has M0 = 1/(1 + t/2) within the replicas' error and one event per lost
/// particle.
#[test]
fn ensemble_statistics_follow_the_trajectories() {
    let k = Coagulation::constant(1.0).unwrap();
    let times = [0.5, 1.0, 2.0];
    let n = 512;
    let trajs = ensemble(64, &|| dsa(k, n), &times, 7, &|s| {
        vec![s.moment(0.0), s.particles() as f64]
    })
    .unwrap();
    assert_eq!(trajs.len(), 64);
    let m0 = stats(&trajs, 0);
    let exact = Exact::constant(1.0).unwrap();
    for (i, &t) in times.iter().enumerate() {
        assert_eq!(m0[i].count(), 64);
        let x = exact.moment(0, t).unwrap();
        let tol = coagula_core::observe::student_t_threshold(1e-6, 63) * m0[i].std_error();
        // (plus 2/N for the finite-N bias of the Marcus–Lushnikov process)
        assert!((m0[i].mean() - x).abs() < tol + 2.0 / n as f64, "t = {t}");
    }
    for t in &trajs {
        assert!(t.proposals.windows(2).all(|w| w[0] <= w[1]));
        assert!(t.secs.windows(2).all(|w| w[0] <= w[1]));
        // each DSA coagulation removes one particle; proposals include rejections
        let lost = n as u64 - *t.values.last().unwrap().get(1).unwrap() as u64;
        assert!(*t.proposals.last().unwrap() >= lost);
    }
    let e = effort(&trajs);
    assert_eq!(e.len(), times.len());
    assert!(e[2].1 >= e[0].1 && e[0].1 > 0.0);
}
