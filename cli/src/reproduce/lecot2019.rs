//! `coagula reproduce lecot2019`: Lécot et al. (2019), *QMC simulation of
//! coagulation–fragmentation*, Figures 1–2 — the errors of M2 and M3 of the
//! coagulation–fragmentation test (K = 1, F = 2/(x+y), monodisperse start, T = 1) for
//! N = 2^7..2^20 and P = 100..1600 steps, QMC against MC, RQMC intervals, fitted slopes.
//! (The single case is the scenario `examples/lecot2019-coagulation-fragmentation.toml`,
//! the CLI's default run; its validation cases are data in `cli/cases/`.)

use coagula_core::exact::{ClosedMoments, Exact};
use coagula_core::kernel::{BinaryUniform, Coagulation, Fragmentation};
use coagula_core::observe::Replicas;
use coagula_core::qmc::Randomization;
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{Init, Model, Options, Points as PointSet, Simulation};
use coagula_core::scheme::registry;
use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;

/// The point sets of the experiment: the paper's QMC (Niederreiter), its MC twin, and
/// QMC randomised by Owen's scrambling (RQMC, one scrambling per seed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Points {
    /// Niederreiter's (1,3)-sequence.
    Qmc,
    /// Pseudo-random points.
    Mc,
    /// Owen-scrambled Niederreiter points.
    Rqmc,
}

impl Points {
    /// The registry's options of the point set, with time step `dt` and the seed's
    /// stream (the RQMC scrambling draws from it).
    fn options(self, dt: f64, seed: u64) -> Options {
        let o = Options::default().with_dt(dt).with_stream(seed, 0);
        match self {
            Points::Qmc => o,
            Points::Mc => o.with_points(PointSet::MonteCarlo),
            Points::Rqmc => o.with_randomization(Randomization::Owen),
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

/// One run of a mass-flow case (the registry's `massflow`); returns `(t, M2, M3)` at
/// each checkpoint.
pub fn trajectory(
    kernel: Coagulation,
    frag: Fragmentation,
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
    let sizes = vec![1.0; 1 << m];
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    let mut sim: Box<dyn Simulation<Coagulation, Fragmentation, Generator>> = registry::build(
        registry::find("massflow")?,
        Model::coagulation(kernel, frag),
        &init,
        &points.options(t_end / f64::from(steps), seed),
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
    let f = Fragmentation::BinaryUniform(BinaryUniform::new(1.0)?);
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
    let k = ClosedMoments::Constant {
        b: 1.0,
        lambda: 1.0,
    };
    let m = k.euler([1.0; 4], h, (t / h).round() as u64);
    (m[2], m[3])
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
    if let Some(path) = plot {
        // a bad name or directory fails now, not after the grid
        crate::plot::check(path)?;
    }
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
        figure2(path, &cells)?;
        println!("\nwrote {path}");
    }
    Ok(())
}

/// Figure 2 of Lécot et al.: log2 of the mean error against log2 N, one curve per P,
/// QMC solid and MC dashed; M2 on the left, M3 on the right.
pub fn figure2(path: &str, cells: &[Cell]) -> Result<(), String> {
    crate::plot::render(path, (1400, 600), |root| draw_figure2(root, cells))
}

fn draw_figure2<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    cells: &[Cell],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(crate::plot::err)?;
    let panels = root.split_evenly((1, 2));
    let colors = [RED, BLUE, GREEN, MAGENTA, BLACK];
    let mut ps: Vec<u32> = cells.iter().map(|c| c.steps).collect();
    ps.sort_unstable();
    ps.dedup();
    for (i, panel) in panels.iter().enumerate() {
        let ys: Vec<f64> = cells
            .iter()
            .flat_map(|c| [c.qmc[i][3].log2(), c.mc[i][3].log2()])
            .collect();
        let (ylo, yhi) = ys
            .iter()
            .fold((f64::MAX, f64::MIN), |a, &y| (a.0.min(y), a.1.max(y)));
        let (mlo, mhi) = cells
            .iter()
            .fold((u32::MAX, 0), |a, c| (a.0.min(c.m), a.1.max(c.m)));
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!("mean error of M{} (log2), QMC solid, MC dashed", i + 2),
                ("sans-serif", 20),
            )
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(f64::from(mlo)..f64::from(mhi), (ylo - 0.5)..(yhi + 0.5))
            .map_err(crate::plot::err)?;
        chart
            .configure_mesh()
            .x_desc("log2 N")
            .y_desc("log2 error")
            .draw()
            .map_err(crate::plot::err)?;
        for (pi, &p) in ps.iter().enumerate() {
            let c = colors[pi % colors.len()];
            let q: Vec<(f64, f64)> = cells
                .iter()
                .filter(|x| x.steps == p)
                .map(|x| (f64::from(x.m), x.qmc[i][3].log2()))
                .collect();
            let mc: Vec<(f64, f64)> = cells
                .iter()
                .filter(|x| x.steps == p)
                .map(|x| (f64::from(x.m), x.mc[i][3].log2()))
                .collect();
            chart
                .draw_series(LineSeries::new(q, c.stroke_width(2)))
                .map_err(crate::plot::err)?
                .label(format!("P = {p}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(DashedLineSeries::new(mc, 6, 4, c.stroke_width(1)))
                .map_err(crate::plot::err)?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(crate::plot::err)?;
    }
    root.present().map_err(crate::plot::err)?;
    Ok(())
}
