//! Lécot et al. (2019): the coagulation–fragmentation test (K = 1, F = 2/(x+y),
//! monodisperse start, T = 1) — the CLI's default run, its validation cases and the
//! reproduction of the paper's Figure 2.

use coagula_core::exact::Exact;
use coagula_core::kernel::{
    BinaryUniform, Coagulation, CoagulationKernel, FragmentationKernel, NoFragmentation,
};
use coagula_core::observe::Replicas;
use coagula_core::observe::{TEST_ALPHA, student_t_threshold};
use coagula_core::qmc::Randomization;
use coagula_core::random::{Purpose, generator, substream};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::massflow::{MassFlow, PointSource};
use rayon::prelude::*;
use std::io::Write;

/// Which points drive the scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Points {
    /// Niederreiter's (1,3)-sequence.
    Qmc,
    /// Sobol' (Joe–Kuo).
    Sobol,
    /// Pseudo-random points.
    Mc,
    /// Owen-scrambled Niederreiter.
    Rqmc,
}

impl Points {
    pub fn source(self, seed: u64) -> PointSource {
        let mut rng = substream(seed, 0, Purpose::Scrambling);
        match self {
            Points::Qmc => PointSource::niederreiter(),
            Points::Sobol => PointSource::sobol(),
            Points::Mc => PointSource::monte_carlo(),
            Points::Rqmc => PointSource::randomized_niederreiter(Randomization::Owen, &mut rng),
        }
    }
}

/// Discretisation and observation of a mass-flow run.
#[derive(Clone, Copy, Debug)]
pub struct Spec {
    /// log2 of the number of particles.
    pub m: u32,
    /// Steps to `t_end`.
    pub steps: u32,
    pub t_end: f64,
    /// Equally spaced observation times.
    pub checkpoints: u32,
    pub points: Points,
    pub seed: u64,
}

/// One run of a mass-flow case; returns `(t, M2, M3)` at each checkpoint.
pub fn trajectory<K: CoagulationKernel, F: FragmentationKernel>(
    kernel: K,
    frag: F,
    spec: Spec,
) -> Result<Vec<(f64, f64, f64)>, coagula_core::Error> {
    let Spec {
        m,
        steps,
        t_end,
        checkpoints,
        points,
        seed,
    } = spec;
    let mut sim = MassFlow::new(
        kernel,
        frag,
        &vec![1.0; 1 << m],
        1.0,
        t_end / f64::from(steps),
        points.source(seed),
    )?;
    let mut rng = generator(seed, 0);
    let mut out = Vec::with_capacity(checkpoints as usize);
    for h in 1..=checkpoints {
        let t = t_end * f64::from(h) / f64::from(checkpoints);
        sim.advance_to(t, &mut rng)?;
        out.push((t, sim.moment(2.0), sim.moment(3.0)));
    }
    Ok(out)
}

/// Lécot's case (K = 1, F = 2/(x+y), T = 1): trajectory at the 100 checkpoints hT/100.
pub fn try_lecot_case(
    m: u32,
    steps: u32,
    points: Points,
    seed: u64,
) -> Result<Vec<(f64, f64, f64)>, coagula_core::Error> {
    let k = Coagulation::constant(1.0)?;
    let f = BinaryUniform::new(1.0)?;
    let spec = Spec {
        m,
        steps,
        t_end: 1.0,
        checkpoints: 100,
        points,
        seed,
    };
    trajectory(k, f, spec)
}

/// [`try_lecot_case`] for parameters known to be valid (the reproduction grids).
pub fn lecot_case(m: u32, steps: u32, points: Points, seed: u64) -> Vec<(f64, f64, f64)> {
    try_lecot_case(m, steps, points, seed).expect("Lécot's case runs")
}

/// Errors of one trajectory: at T/100, T/10, T, and the mean over the 100 checkpoints,
/// for M2 and M3: `[[e_001, e_01, e_1, mean]; 2]`.
pub fn errors(traj: &[(f64, f64, f64)]) -> [[f64; 4]; 2] {
    let exact = Exact::coagulation_fragmentation();
    let mut out = [[0.0; 4]; 2];
    for (h, &(t, m2, m3)) in traj.iter().enumerate() {
        let e = [
            (m2 - exact.moment(2, t).unwrap()).abs(),
            (m3 - exact.moment(3, t).unwrap()).abs(),
        ];
        for i in 0..2 {
            out[i][3] += e[i] / traj.len() as f64;
            match h + 1 {
                1 => out[i][0] = e[i],
                10 => out[i][1] = e[i],
                100 => out[i][2] = e[i],
                _ => {}
            }
        }
    }
    out
}

/// The scheme's own expectation for Lécot's case: explicit Euler steps of the (linear)
/// moment equations M2' = 1 − M2/3, M3' = 3 M2 − M3/2.
pub fn euler_expectation(steps: u32, t: f64) -> (f64, f64) {
    let h = 1.0 / f64::from(steps);
    let n = (t / h).round() as u32;
    let (mut m2, mut m3) = (1.0, 1.0);
    for _ in 0..n {
        (m2, m3) = (m2 + h * (1.0 - m2 / 3.0), m3 + h * (3.0 * m2 - 0.5 * m3));
    }
    (m2, m3)
}

/// `coagula run` with no scenario: Lécot's case, printed as a table.
pub fn run_default(
    m: u32,
    steps: u32,
    points: Points,
    seed: u64,
    csv: Option<&str>,
    plot: Option<&str>,
) -> Result<(), String> {
    if m == 0 || m > 30 {
        return Err(format!(
            "--m {m}: log2 of the particle number must be in 1..=30"
        ));
    }
    if steps == 0 || !steps.is_multiple_of(100) {
        // the errors are read at t = h/100: with P not a multiple of 100 those times
        // would cut the steps short, and the run would not be the P-step scheme asked for
        return Err(format!(
            "--steps {steps}: must be a positive multiple of 100 (the moments are compared at t = h/100, which must fall on steps)"
        ));
    }
    // every output is opened before the work starts ("-": standard output, and the
    // table then goes to standard error)
    let mut csv_out: Option<csv::Writer<Box<dyn std::io::Write>>> = match csv {
        Some("-") => Some(csv::Writer::from_writer(Box::new(std::io::stdout()))),
        Some(path) => Some(csv::Writer::from_writer(Box::new(
            std::fs::File::create(path).map_err(|e| format!("--csv {path}: {e}"))?,
        ))),
        None => None,
    };
    if let Some(path) = plot {
        crate::plot::check_svg(path)?;
        std::fs::File::create(path).map_err(|e| format!("--plot {path}: {e}"))?;
    }
    let mut table: Box<dyn std::io::Write> = if csv == Some("-") {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    };
    let io = |e: std::io::Error| e.to_string();
    let start = std::time::Instant::now();
    let traj = try_lecot_case(m, steps, points, seed).map_err(|e| e.to_string())?;
    let secs = start.elapsed().as_secs_f64();
    let exact = Exact::coagulation_fragmentation();
    writeln!(
        table,
        "Lécot et al. (2019) coagulation-fragmentation test: K = 1, F = 2/(x+y), c(x,0) = δ(x-1)\n\
         scheme: mass flow, {points:?} points, N = 2^{m} = {}, P = {steps} steps to T = 1 ({secs:.2} s)\n",
        1u64 << m
    )
    .map_err(io)?;
    writeln!(
        table,
        "{:>6} {:>12} {:>12} {:>10} {:>12} {:>12} {:>10}",
        "t", "M2", "M2 exact", "|err|", "M3", "M3 exact", "|err|"
    )
    .map_err(io)?;
    for &(t, m2, m3) in &traj {
        let h = (t * 100.0).round() as u32;
        if h == 1 || h.is_multiple_of(10) {
            let (e2, e3) = (exact.moment(2, t).unwrap(), exact.moment(3, t).unwrap());
            writeln!(
                table,
                "{t:>6.2} {m2:>12.6} {e2:>12.6} {:>10.2e} {m3:>12.6} {e3:>12.6} {:>10.2e}",
                (m2 - e2).abs(),
                (m3 - e3).abs()
            )
            .map_err(io)?;
        }
    }
    let err = errors(&traj);
    writeln!(
        table,
        "\nmean |error| over t = h/100, h = 1..100: M2 {:.3e}, M3 {:.3e}",
        err[0][3], err[1][3]
    )
    .map_err(io)?;
    if let (Some(path), Some(w)) = (csv, csv_out.as_mut()) {
        w.write_record(["t", "M2", "M2_exact", "M3", "M3_exact"])
            .map_err(|e| e.to_string())?;
        for &(t, m2, m3) in &traj {
            let row = [
                t,
                m2,
                exact.moment(2, t).unwrap(),
                m3,
                exact.moment(3, t).unwrap(),
            ];
            w.write_record(row.iter().map(|v| v.to_string()))
                .map_err(|e| e.to_string())?;
        }
        w.flush().map_err(|e| e.to_string())?;
        if path != "-" {
            writeln!(table, "wrote {path}").map_err(io)?;
        }
    }
    if let Some(path) = plot {
        crate::plot::moments(path, &traj, |t| {
            (exact.moment(2, t).unwrap(), exact.moment(3, t).unwrap())
        })?;
        writeln!(table, "wrote {path}").map_err(io)?;
    }
    Ok(())
}

/// One cell of the reproduction grid.
#[derive(Clone, Copy, Debug)]
pub struct Cell {
    pub m: u32,
    pub steps: u32,
    pub qmc: [[f64; 4]; 2],
    pub mc: [[f64; 4]; 2],
}

/// The paper's grid: N = 2^m for m in `ms`, P in `ps`; QMC (one run) and MC (mean of
/// `mc_seeds` runs). Cells run in parallel.
pub fn grid(ms: &[u32], ps: &[u32], mc_seeds: u64) -> Vec<Cell> {
    let jobs: Vec<(u32, u32)> = ms
        .iter()
        .flat_map(|&m| ps.iter().map(move |&p| (m, p)))
        .collect();
    jobs.par_iter()
        .map(|&(m, p)| {
            let qmc = errors(&lecot_case(m, p, Points::Qmc, 0));
            let mut mc = [[0.0; 4]; 2];
            for seed in 0..mc_seeds {
                let e = errors(&lecot_case(m, p, Points::Mc, seed + 1));
                for i in 0..2 {
                    for j in 0..4 {
                        mc[i][j] += e[i][j] / mc_seeds as f64;
                    }
                }
            }
            Cell {
                m,
                steps: p,
                qmc,
                mc,
            }
        })
        .collect()
}

/// Least-squares slope of log2(error) against log2(N).
pub fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |a, &(x, y)| (a.0 + x, a.1 + y));
    let (mx, my) = (sx / n, sy / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for &(x, y) in points {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
    }
    sxy / sxx
}

/// `coagula reproduce lecot2019`: the table of errors and the Figure-2 plot.
pub fn reproduce(m_max: u32, mc_seeds: u64, rqmc: u32, plot: Option<&str>) -> Result<(), String> {
    let ms: Vec<u32> = (7..=m_max).collect();
    let ps = [100, 200, 400, 800, 1600];
    let start = std::time::Instant::now();
    let cells = grid(&ms, &ps, mc_seeds);
    println!(
        "Lécot et al. (2019) Figures 1-2: absolute errors of M2 and M3; QMC = Niederreiter (1,3)-sequence, \
         MC = mean over {mc_seeds} seeds ({:.0} s)",
        start.elapsed().as_secs_f64()
    );
    for (i, name) in ["M2", "M3"].iter().enumerate() {
        println!("\n{name}: error at t = 0.01 / 0.1 / 1 and mean over 100 times");
        println!(
            "{:>4} {:>5} | {:>9} {:>9} {:>9} {:>9} | {:>9} {:>9} {:>9} {:>9} | {:>7}",
            "m",
            "P",
            "QMC .01",
            "QMC .1",
            "QMC 1",
            "QMC mean",
            "MC .01",
            "MC .1",
            "MC 1",
            "MC mean",
            "MC/QMC"
        );
        for c in &cells {
            let q = c.qmc[i];
            let mc = c.mc[i];
            println!(
                "{:>4} {:>5} | {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} | {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} | {:>7.1}",
                c.m,
                c.steps,
                q[0],
                q[1],
                q[2],
                q[3],
                mc[0],
                mc[1],
                mc[2],
                mc[3],
                mc[3] / q[3]
            );
        }
        println!("fitted slopes of log2(mean error) vs log2(N) (m = 7..{m_max}):");
        for &p in &ps {
            let q: Vec<(f64, f64)> = cells
                .iter()
                .filter(|c| c.steps == p)
                .map(|c| (f64::from(c.m), c.qmc[i][3].log2()))
                .collect();
            let mc: Vec<(f64, f64)> = cells
                .iter()
                .filter(|c| c.steps == p)
                .map(|c| (f64::from(c.m), c.mc[i][3].log2()))
                .collect();
            println!("  P = {p:>4}: QMC {:+.3}, MC {:+.3}", slope(&q), slope(&mc));
        }
        let below = cells.iter().filter(|c| c.qmc[i][3] < c.mc[i][3]).count();
        println!(
            "QMC mean error below MC mean error in {below} of {} cells",
            cells.len()
        );
    }
    if rqmc > 0 {
        println!(
            "\nRQMC (Owen-scrambled Niederreiter), {rqmc} randomisations, P = 100, values at t = 1:"
        );
        println!(
            "{:>4} | {:>22} {:>22} {:>10} | {:>22} {:>22} {:>10}",
            "m",
            "M2 mean ± 95%",
            "M2 exact / Euler",
            "covers",
            "M3 mean ± 95%",
            "M3 exact / Euler",
            "covers"
        );
        let (e2, e3) = euler_expectation(100, 1.0);
        let exact = Exact::coagulation_fragmentation();
        for &m in ms.iter().filter(|&&m| m <= 16) {
            let vals: Vec<(f64, f64)> = (0..rqmc)
                .into_par_iter()
                .map(|s| {
                    let tr = lecot_case(m, 100, Points::Rqmc, u64::from(s) + 1000);
                    let &(_, m2, m3) = tr.last().expect("100 checkpoints");
                    (m2, m3)
                })
                .collect();
            let (mut r2, mut r3) = (Replicas::new(), Replicas::new());
            for &(a, b) in &vals {
                r2.push(a);
                r3.push(b);
            }
            let cover = |r: &Replicas, x: f64| {
                let (lo, hi) = r.ci95();
                lo <= x && x <= hi
            };
            let (x2, x3) = (exact.moment(2, 1.0).unwrap(), exact.moment(3, 1.0).unwrap());
            println!(
                "{m:>4} | {:>11.6} ± {:>8.1e} {:>10.6}/{:>10.6} {:>5}/{:<4} | {:>11.6} ± {:>8.1e} {:>10.6}/{:>10.6} {:>5}/{:<4}",
                r2.mean(),
                r2.ci95().1 - r2.mean(),
                x2,
                e2,
                cover(&r2, x2),
                cover(&r2, e2),
                r3.mean(),
                r3.ci95().1 - r3.mean(),
                x3,
                e3,
                cover(&r3, x3),
                cover(&r3, e3)
            );
        }
    }
    if let Some(path) = plot {
        crate::plot::figure2(path, &cells)?;
        println!("\nwrote {path}");
    }
    Ok(())
}

/// Validation cases of this paper (see `validate`).
pub fn cases(quick: bool, out: &mut Vec<crate::validate::Case>) {
    use crate::validate::Case;
    let m = if quick { 12 } else { 16 };
    let steps = 100;
    // QMC vs MC mean error
    let qmc = errors(&lecot_case(m, steps, Points::Qmc, 0));
    let seeds = 20;
    let mut mc = [Replicas::new(), Replicas::new()];
    let runs: Vec<[[f64; 4]; 2]> = (0..seeds)
        .into_par_iter()
        .map(|s| errors(&lecot_case(m, steps, Points::Mc, s + 1)))
        .collect();
    for e in &runs {
        mc[0].push(e[0][3]);
        mc[1].push(e[1][3]);
    }
    for (i, q) in ["M2", "M3"].iter().enumerate() {
        out.push(Case {
            case: format!("lecot2019/qmc-below-mc-N2^{m}-P{steps}"),
            quantity: format!(
                "mean |{q} error| over t=h/100 (reference: MC mean of {seeds} seeds)"
            ),
            reference: mc[i].mean(),
            value: qmc[i][3],
            error: qmc[i][3] - mc[i].mean(),
            tolerance: 0.0,
            pass: qmc[i][3] < mc[i].mean(),
        });
    }
    // RQMC against the exact value, and against the scheme's Euler expectation
    let r = 20;
    let vals: Vec<(f64, f64)> = (0..r)
        .into_par_iter()
        .map(|s| {
            let tr = lecot_case(m, steps, Points::Rqmc, s + 1000);
            let &(_, m2, m3) = tr.last().expect("checkpoints");
            (m2, m3)
        })
        .collect();
    let (e2, e3) = euler_expectation(steps, 1.0);
    let exact = Exact::coagulation_fragmentation();
    for (i, (name, euler, ex)) in [
        ("M2(1)", e2, exact.moment(2, 1.0).unwrap()),
        ("M3(1)", e3, exact.moment(3, 1.0).unwrap()),
    ]
    .into_iter()
    .enumerate()
    {
        let mut rep = Replicas::new();
        for v in &vals {
            rep.push(if i == 0 { v.0 } else { v.1 });
        }
        let se = rep.std_error();
        let z = student_t_threshold(TEST_ALPHA, rep.count() - 1);
        out.push(Case {
            case: format!("lecot2019/rqmc-euler-N2^{m}-P{steps}"),
            quantity: format!(
                "{name}, {r} Owen scramblings (reference: Euler-step expectation; tol {z:.2} SE)"
            ),
            reference: euler,
            value: rep.mean(),
            error: (rep.mean() - euler).abs(),
            tolerance: z * se,
            pass: (rep.mean() - euler).abs() <= z * se,
        });
        let bias = (euler - ex).abs();
        out.push(Case {
            case: format!("lecot2019/rqmc-exact-N2^{m}-P{steps}"),
            quantity: format!(
                "{name} (reference: exact; tol = O(Δt) Euler bias {bias:.1e} + {z:.2} SE)"
            ),
            reference: ex,
            value: rep.mean(),
            error: (rep.mean() - ex).abs(),
            tolerance: bias + z * se,
            pass: (rep.mean() - ex).abs() <= bias + z * se,
        });
    }
    // exact/: pure coagulation with the mass-flow scheme (RQMC replicas)
    exact_cases(quick, out);
}

fn exact_cases(quick: bool, out: &mut Vec<crate::validate::Case>) {
    use crate::validate::Case;
    let m = if quick { 12 } else { 15 };
    let steps = 200;
    let h = 1.0 / f64::from(steps);
    type Rec = fn(f64, f64, f64) -> (f64, f64);
    let cases: [(&str, Coagulation, Exact, Rec); 2] = [
        (
            "constant",
            Coagulation::constant(1.0).expect("valid"),
            Exact::constant(1.0).expect("valid"),
            |m0, m2, h| (m0 - 0.5 * h * m0 * m0, m2 + h),
        ),
        (
            "additive",
            Coagulation::additive(),
            Exact::additive(),
            |m0, m2, h| (m0 * (1.0 - h), m2 * (1.0 + 2.0 * h)),
        ),
    ];
    for (name, k, e, rec) in cases {
        let (mut m0e, mut m2e) = (1.0, 1.0);
        for _ in 0..steps {
            (m0e, m2e) = rec(m0e, m2e, h);
        }
        let vals: Vec<(f64, f64)> = (0..10u64)
            .into_par_iter()
            .map(|s| {
                let mut sim = MassFlow::new(
                    k,
                    NoFragmentation,
                    &vec![1.0; 1 << m],
                    1.0,
                    h,
                    Points::Rqmc.source(s + 7),
                )
                .expect("valid");
                sim.advance_to(1.0, &mut generator(1, 0)).expect("runs");
                (sim.moment(0.0), sim.moment(2.0))
            })
            .collect();
        for (q, idx, euler) in [("M0(1)", 0u32, m0e), ("M2(1)", 2, m2e)] {
            let mut r = Replicas::new();
            for v in &vals {
                r.push(if idx == 0 { v.0 } else { v.1 });
            }
            let ex = e.moment(idx, 1.0).expect("valid");
            let bias = (euler - ex).abs();
            let z = student_t_threshold(TEST_ALPHA, r.count() - 1);
            let tol = bias + z * r.std_error() + 1e-12;
            out.push(Case {
                case: format!("exact/{name}-massflow-N2^{m}-P{steps}"),
                quantity: format!(
                    "{q}, 10 RQMC replicas (tol = Euler bias {bias:.1e} + {z:.2} SE)"
                ),
                reference: ex,
                value: r.mean(),
                error: (r.mean() - ex).abs(),
                tolerance: tol,
                pass: (r.mean() - ex).abs() <= tol,
            });
        }
    }
}
