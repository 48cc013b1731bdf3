//! `coagula reproduce maftei2016`: Maftei, Bossy & Jabir (2016), Langevin collision
//! schemes — the test problem of §4.2 (SPEC §7) on a halving ladder of steps, with
//! Richardson–Romberg, the paper's open choices measured, and collision kernels from
//! first hits in the Brownian limit:
//!
//! - `ladder`: `E f(X_T, U_T)` for the specular and the absorbing wall at
//!   Δt = T/4 .. T/256, its bias against the extrapolated limit (a weighted fit of
//!   `a + C Δt + C₂ Δt²`), the fitted weak order, Richardson–Romberg and its order, the
//!   hits per trajectory and the absorbed fraction, against the paper's numbers;
//! - `choices`: how much the periodic border and the velocity bound move the result;
//! - `kernel`: the first-hit kernel of the Langevin relative motion with friction
//!   against Smoluchowski's `4π(D1 + D2)(r1 + r2)` (with its transient) for relaxation
//!   times τ → 0 and steps Δt.
//!
//! Trajectory `i` of a run has its own generator (key, i): the results do not depend on
//! the number of threads. `--quick` runs 1/128 of the trajectories.

use coagula_core::langevin::kernel::{FirstHits, first_hit_kernel, smoluchowski};
use coagula_core::langevin::{
    Drift, Estimate, Friction, VelocityBound, Wall, paper, richardson_romberg,
};
use coagula_core::observe::Replicas;
use plotters::prelude::*;
use rayon::prelude::*;
use std::time::Instant;

mod cases;
mod fits;
pub use cases::{cases, first_hits_scenario};

/// The experiments, in the order `all` runs them.
pub const PARTS: [&str; 3] = ["ladder", "choices", "kernel"];

/// Largest step of the fits (limit, orders).
const FIT_DT: f64 = 0.2;

/// Trajectories per batch (a rayon task).
const CHUNK: u64 = 1 << 16;

fn err(e: coagula_core::Error) -> String {
    e.to_string()
}

/// Statistics of one ensemble of the test problem.
#[derive(Clone, Copy, Default)]
pub struct Run {
    pub f: Replicas,
    pub hits: Replicas,
    pub absorbed: u64,
    pub steps: u64,
}

/// `n` trajectories of the test problem with ids `first_id..`, under `key`.
pub fn run(
    wall: Wall,
    dt: f64,
    choices: paper::Choices,
    n: u64,
    key: u64,
    first_id: u64,
) -> Result<Run, String> {
    run_on(true, wall, dt, choices, n, key, first_id)
}

/// [`run`] on all threads or on this one (the same chunks, merged in the same order: the
/// same bits).
fn run_on(
    parallel: bool,
    wall: Wall,
    dt: f64,
    choices: paper::Choices,
    n: u64,
    key: u64,
    first_id: u64,
) -> Result<Run, String> {
    let one = |c: u64| -> Result<Run, String> {
        let m = CHUNK.min(n - c * CHUNK) as usize;
        let mut b = paper::batch(wall, dt, choices, m, key, first_id + c * CHUNK).map_err(err)?;
        let rep = b.advance_to(paper::T).map_err(err)?;
        Ok(Run {
            f: b.statistics(|x, u| paper::observable(x[0], u[0])),
            hits: b.hit_statistics(),
            absorbed: b.absorbed() as u64,
            steps: rep.proposals,
        })
    };
    let parts = over_chunks(parallel, n.div_ceil(CHUNK), one)?;
    // merged in chunk order: the same bits for any number of threads
    Ok(parts.iter().fold(Run::default(), |mut a, p| {
        a.f.merge(&p.f);
        a.hits.merge(&p.hits);
        a.absorbed += p.absorbed;
        a.steps += p.steps;
        a
    }))
}

/// `one(c)` for the chunks `c = 0..chunks`, on all threads or on this one, the results
/// in chunk order.
fn over_chunks<T: Send>(
    parallel: bool,
    chunks: u64,
    one: impl Fn(u64) -> Result<T, String> + Sync + Send,
) -> Result<Vec<T>, String> {
    if parallel {
        (0..chunks).into_par_iter().map(one).collect()
    } else {
        (0..chunks).map(one).collect()
    }
}

/// `coagula bench langevin`: trajectory-steps per second, one thread against all.
pub fn bench(n: u64, dt: f64, repeat: u32) -> Result<(), String> {
    use coagula_core::langevin::{Batch, Config};
    let threads = rayon::current_num_threads();
    println!(
        "# coagula bench langevin: {n} trajectories, minimum of {repeat} runs, {threads} threads, coagula {}",
        env!("CARGO_PKG_VERSION")
    );
    println!(
        "{:<40} {:>14} {:>14} {:>8} {:>10}",
        "problem", "1 thread M/s", "all M/s", "speedup", "same bits"
    );
    for (name, wall) in [
        ("1-D specular, the paper's drift", Wall::Specular),
        ("1-D absorbing, the paper's drift", Wall::Absorbing),
    ] {
        let mut best = [f64::INFINITY; 2];
        let mut out = [Run::default(); 2];
        for _ in 0..repeat {
            // alternating: one thread, then all
            for (i, par) in [false, true].into_iter().enumerate() {
                let start = Instant::now();
                out[i] = run_on(par, wall, dt, paper::Choices::default(), n, 1, 0)?;
                best[i] = best[i].min(start.elapsed().as_secs_f64());
            }
        }
        let (a, b) = (out[0], out[1]);
        let same = a.f == b.f && a.hits == b.hits && a.absorbed == b.absorbed;
        println!(
            "{name:<40} {:>14.1} {:>14.1} {:>8.2} {:>10}",
            a.steps as f64 / best[0] / 1e6,
            b.steps as f64 / best[1] / 1e6,
            best[0] / best[1],
            same
        );
    }
    // 3-D: outside the unit ball with friction (the kernel estimation's motion)
    let cfg = Config::<3>::ball(1.0, 0.01, 2.0, Wall::Specular).map_err(err)?;
    let one = |c: u64| -> Result<(Replicas, u64), String> {
        let m = CHUNK.min(n - c * CHUNK) as usize;
        let mut b = Batch::with_starts(cfg, Friction { rate: 1.0 }, m, 2, c * CHUNK, |_| {
            ([1.5, 0.0, 0.0], [-1.0, 0.0, 0.0])
        })
        .map_err(err)?;
        let rep = b.advance_to(1.0).map_err(err)?;
        Ok((b.statistics(|x, _| x[0]), rep.proposals))
    };
    let mut best = [f64::INFINITY; 2];
    let mut res = [(Replicas::new(), 0u64); 2];
    for _ in 0..repeat {
        for (i, par) in [false, true].into_iter().enumerate() {
            let start = Instant::now();
            let parts = over_chunks(par, n.div_ceil(CHUNK), one)?;
            best[i] = best[i].min(start.elapsed().as_secs_f64());
            res[i] = parts.iter().fold((Replicas::new(), 0), |(mut r, s), p| {
                r.merge(&p.0);
                (r, s + p.1)
            });
        }
    }
    println!(
        "{:<40} {:>14.1} {:>14.1} {:>8.2} {:>10}",
        "3-D ball, friction (dt = 0.01)",
        res[0].1 as f64 / best[0] / 1e6,
        res[1].1 as f64 / best[1] / 1e6,
        best[0] / best[1],
        res[0] == res[1]
    );
    Ok(())
}

/// The first-hit kernel of `p` on all threads: chunks of 2^14 trajectories with ids
/// `c · 2^14..` under `seed`, merged in chunk order (the same bits for any number of
/// threads). The per-trajectory statistics and the hits in the window.
fn kernel_on_threads<const D: usize, Dr: Drift<D> + Sync>(
    p: &FirstHits,
    drift: &Dr,
    seed: u64,
) -> Result<(Replicas, u64), String> {
    let (n, chunk) = (p.trajectories, 1u64 << 14);
    let parts: Vec<(Replicas, u64)> = (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let share = FirstHits {
                trajectories: chunk.min(n - c * chunk),
                ..*p
            };
            first_hit_kernel::<D, _>(&share, drift, seed, c * chunk)
                .map(|k| (k.replicas, k.hits))
                .map_err(err)
        })
        .collect::<Result<_, String>>()?;
    Ok(parts
        .iter()
        .fold((Replicas::new(), 0), |(mut a, h), (r, k)| {
            a.merge(r);
            (a, h + k)
        }))
}

/// Least-squares slope of `ln |b|` on `ln h` over the points where `|b| > 3 se`.
fn order(h: &[f64], b: &[f64], se: &[f64]) -> Option<(f64, usize)> {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(b)
        .zip(se)
        .filter(|((_, b), s)| b.abs() > 3.0 * **s)
        .map(|((h, b), _)| (h.ln(), b.abs().ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    Some((sxy / sxx, pts.len()))
}

pub fn reproduce(parts: &[String], quick: bool, plot: Option<&str>) -> Result<(), String> {
    for p in parts {
        if p != "all" && !PARTS.contains(&p.as_str()) {
            return Err(format!("unknown part {p:?} (ladder, choices, kernel, all)"));
        }
    }
    let want = |p: &str| parts.iter().any(|q| q == "all" || q == p);
    println!(
        "# maftei2016: {} threads{}",
        rayon::current_num_threads(),
        if quick {
            ", quick (1/128 of the trajectories)"
        } else {
            ""
        }
    );
    let scale = if quick { 128 } else { 1 };
    if want("ladder") {
        ladder((1 << 24) / scale, plot)?;
    }
    if want("choices") {
        choices((1 << 22) / scale)?;
    }
    if want("kernel") {
        kernel((1 << 18) / scale)?;
    }
    Ok(())
}

fn ladder(n: u64, plot: Option<&str>) -> Result<(), String> {
    let levels: Vec<u32> = (2..=8).collect();
    let mut curves = Vec::new();
    for (wall, reference, key) in [
        (Wall::Specular, paper::SPECULAR_REFERENCE, 2016),
        (Wall::Absorbing, paper::ABSORBING_REFERENCE, 2017),
    ] {
        let start = Instant::now();
        let mut runs = Vec::new();
        let mut steps = 0;
        for (i, &k) in levels.iter().enumerate() {
            let dt = paper::T / f64::from(1u32 << k);
            // independent trajectories at every level (ids offset by level)
            let r = run(wall, dt, paper::Choices::default(), n, key, i as u64 * n)?;
            steps += r.steps;
            runs.push((dt, r));
        }
        let secs = start.elapsed().as_secs_f64();
        let h: Vec<f64> = runs.iter().map(|r| r.0).collect();
        let y: Vec<f64> = runs.iter().map(|r| r.1.f.mean()).collect();
        let se: Vec<f64> = runs.iter().map(|r| r.1.f.std_error()).collect();
        // the asymptotic regime: dt ≤ T/16 (the coarsest steps are not, as the paper
        // notes of its own curve's start)
        let fit = h.iter().position(|&d| d <= FIT_DT).unwrap_or(0);
        let all_fits = fits::fits(&h, &y, &se, FIT_DT);
        let Some(chosen) = fits::central(&all_fits) else {
            return Err("the ladder has too few steps for a fit".into());
        };
        let (limit, limit_se) = (chosen.limit, chosen.se);
        let (lo, hi) = fits::spread(&all_fits);
        println!(
            "\n## {wall:?} wall, {n} trajectories per step, {:.2e} trajectory-steps in {secs:.1} s ({:.1} M/s)",
            steps as f64,
            steps as f64 / secs / 1e6
        );
        println!(
            "extrapolated limit (weighted fit of degree {} over the {} steps dt <= {}, the widest whose chi2 holds): {limit:.4} ± {limit_se:.4} (statistical) ± {:.4} (fit model: half the range {lo:.4} .. {hi:.4} of the fits below); the paper's reference {reference} differs by {:.4}",
            chosen.degree,
            chosen.points,
            chosen.max_dt,
            (hi - lo) / 2.0,
            limit - reference
        );
        for f in &all_fits {
            println!(
                "  fit of degree {} over the {} steps dt <= {}: {:.4} ± {:.4}, chi2 = {:.1} on {} degrees of freedom",
                f.degree, f.points, f.max_dt, f.limit, f.se, f.chi2, f.dof
            );
        }
        println!(
            "{:>9} {:>18} {:>10} {:>18} {:>18} {:>9} {:>9}",
            "dt", "E f ± SE", "bias", "RR(dt,dt/2) ± SE", "RR bias", "hits", "absorbed"
        );
        let mut rr_b = Vec::new();
        for (i, (dt, r)) in runs.iter().enumerate() {
            let rr = runs
                .get(i + 1)
                .map(|(_, fine)| richardson_romberg(&r.f, &fine.f));
            let rr_txt = rr.map_or(String::from("-"), |e| {
                format!("{:.4} ± {:.4}", e.mean, e.std_error)
            });
            let rrb = rr.map_or(String::from("-"), |e| format!("{:+.4}", e.mean - limit));
            if let Some(e) = rr {
                rr_b.push((*dt, e));
            }
            println!(
                "{dt:>9.5} {:>18} {:>+10.4} {rr_txt:>18} {rrb:>18} {:>9.4} {:>9.4}",
                format!("{:.4} ± {:.4}", r.f.mean(), r.f.std_error()),
                r.f.mean() - limit,
                r.hits.mean(),
                r.absorbed as f64 / n as f64,
            );
        }
        let bias: Vec<f64> = y.iter().map(|v| v - limit).collect();
        let p = order(&h[fit..], &bias[fit..], &se[fit..]);
        let rh: Vec<f64> = rr_b.iter().map(|r| r.0).collect();
        let rb: Vec<f64> = rr_b.iter().map(|r| r.1.mean - limit).collect();
        let rs: Vec<f64> = rr_b.iter().map(|r| r.1.std_error).collect();
        let rfit = rh.iter().position(|&d| d <= FIT_DT).unwrap_or(0);
        let q = order(&rh[rfit..], &rb[rfit..], &rs[rfit..]);
        let fmt = |o: Option<(f64, usize)>| {
            o.map_or("n/a".into(), |(p, k)| {
                format!("{p:.2} ({k} levels above 3 SE)")
            })
        };
        println!(
            "over dt <= {FIT_DT}: weak order (slope of log|bias|) {}; Richardson–Romberg order {}",
            fmt(p),
            fmt(q)
        );
        let last = &runs.last().unwrap().1;
        match wall {
            Wall::Specular => println!(
                "hits per trajectory at dt = {:.5}: {:.4} ± {:.4} (paper: {})",
                h.last().unwrap(),
                last.hits.mean(),
                last.hits.std_error(),
                paper::HITS_PER_TRAJECTORY
            ),
            Wall::Absorbing => println!(
                "absorbed fraction at dt = {:.5}: {:.4} (paper: {})",
                h.last().unwrap(),
                last.absorbed as f64 / n as f64,
                paper::ABSORBED_FRACTION
            ),
        }
        curves.push((wall, h, bias, se, rr_b, limit));
    }
    if let Some(path) = plot {
        draw(path, &curves)?;
        println!("\nwrote {path}");
    }
    Ok(())
}

type Curve = (
    Wall,
    Vec<f64>,
    Vec<f64>,
    Vec<f64>,
    Vec<(f64, Estimate)>,
    f64,
);

fn draw(path: &str, curves: &[Curve]) -> Result<(), String> {
    let root = SVGBackend::new(path, (1000, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let panels = root.split_evenly((1, 2));
    for (area, (wall, h, bias, se, rr, _)) in panels.iter().zip(curves) {
        let mut ch = ChartBuilder::on(area)
            .caption(
                format!("{wall:?} wall: |bias| vs dt (95% CI bars)"),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d((0.008f64..1.0).log_scale(), (1e-4f64..30.0).log_scale())
            .map_err(|e| e.to_string())?;
        ch.configure_mesh()
            .x_desc("dt")
            .y_desc("|E f - limit|")
            .draw()
            .map_err(|e| e.to_string())?;
        let pts = |xs: &[f64], ys: &[f64], ss: &[f64]| -> Vec<(f64, f64, f64, f64)> {
            xs.iter()
                .zip(ys)
                .zip(ss)
                .map(|((x, y), s)| {
                    let (lo, hi) = ((y.abs() - 1.96 * s).max(1e-4), y.abs() + 1.96 * s);
                    (*x, y.abs().max(1e-4), lo, hi)
                })
                .collect()
        };
        let euler = pts(h, bias, se);
        let rrh: Vec<f64> = rr.iter().map(|r| r.0).collect();
        let rrb: Vec<f64> = rr
            .iter()
            .map(|r| r.1.mean - curves.iter().find(|c| c.0 == *wall).unwrap().5)
            .collect();
        let rrs: Vec<f64> = rr.iter().map(|r| r.1.std_error).collect();
        let rich = pts(&rrh, &rrb, &rrs);
        for (data, color, label) in [(&euler, BLUE, "scheme"), (&rich, RED, "Richardson-Romberg")] {
            ch.draw_series(LineSeries::new(
                data.iter().map(|p| (p.0, p.1)),
                color.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            ch.draw_series(
                data.iter()
                    .map(|p| PathElement::new(vec![(p.0, p.2), (p.0, p.3)], color.stroke_width(2))),
            )
            .map_err(|e| e.to_string())?;
        }
        // reference slopes 1 and 2 through the coarsest point
        if let (Some(e), Some(r)) = (euler.first(), rich.first()) {
            let line = |p: (f64, f64, f64, f64), k: i32| -> Vec<(f64, f64)> {
                h.iter().map(|x| (*x, p.1 * (x / p.0).powi(k))).collect()
            };
            ch.draw_series(LineSeries::new(line(*e, 1), BLUE.mix(0.3)))
                .map_err(|e| e.to_string())?;
            ch.draw_series(LineSeries::new(line(*r, 2), RED.mix(0.3)))
                .map_err(|e| e.to_string())?;
        }
        ch.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}

fn choices(n: u64) -> Result<(), String> {
    let dt = paper::T / 128.0;
    println!(
        "\n## The paper's open choices, dt = {dt}, {n} trajectories each (the same ids in every row)"
    );
    println!(
        "{:<44} {:>20} {:>20}",
        "choice", "specular E f", "absorbing E f"
    );
    let rows = [
        (
            "period 1 (wrap), velocities reflected at ±10",
            paper::Choices::default(),
        ),
        (
            "period 1 (wrap), velocities clamped at ±10",
            paper::Choices {
                period: Some(1.0),
                bound: VelocityBound::Clamp(10.0),
            },
        ),
        (
            "period 1 (wrap), no velocity bound",
            paper::Choices {
                period: Some(1.0),
                bound: VelocityBound::None,
            },
        ),
        (
            "no periodic border, no velocity bound",
            paper::Choices::free(),
        ),
    ];
    for (name, c) in rows {
        let s = run(Wall::Specular, dt, c, n, 77, 0)?;
        let a = run(Wall::Absorbing, dt, c, n, 78, 0)?;
        println!(
            "{name:<44} {:>20} {:>20}",
            format!("{:.4} ± {:.4}", s.f.mean(), s.f.std_error()),
            format!("{:.4} ± {:.4}", a.f.mean(), a.f.std_error())
        );
    }
    println!(
        "(rows 1-3 share their trajectories until one reaches |u| = 10, so their differences are the bound's effect alone)"
    );
    Ok(())
}

/// The first-hit kernel of the relative motion `dU = −U/τ dt + (√(2D)/τ) dW` on the
/// sphere R = 1 (D = 1), averaged over `[t_a, t_b]`, against Smoluchowski.
fn kernel(n: u64) -> Result<(), String> {
    let (d, r, from, to): (f64, f64, f64, f64) = (1.0, 1.0, 0.25, 1.0);
    let outer = r + 8.0 * (2.0 * d * to).sqrt();
    let exact = smoluchowski(d, r, from, to);
    println!(
        "\n## Collision kernel from first hits, D1 + D2 = {d}, r1 + r2 = {r}, window [{from}, {to}], {n} trajectories; Smoluchowski with its transient: {exact:.4} (steady 4 pi D R = {:.4})",
        4.0 * std::f64::consts::PI * d * r
    );
    println!(
        "{:>8} {:>10} {:>10} {:>18} {:>10} {:>8} {:>8}",
        "tau", "sqrt(D tau)/R", "dt", "K ± SE", "rel. err", "hits", "s"
    );
    let mut fit = Vec::new();
    for (tau, frac) in [
        (0.16, 10.0),
        (0.04, 10.0),
        (0.01, 10.0),
        (0.0025, 5.0),
        (0.000625, 5.0),
        (0.04, 5.0),
        (0.04, 20.0),
    ] {
        let start = Instant::now();
        let dt = tau / frac;
        let p = FirstHits {
            radius: r,
            outer,
            from,
            to,
            dt,
            sigma: (2.0 * d).sqrt() / tau,
            velocity_sd: (d / tau).sqrt(),
            trajectories: n,
        };
        let (rep, hits) = kernel_on_threads::<3, _>(&p, &Friction { rate: 1.0 / tau }, 31)?;
        // the fit: sqrt(D tau)/R <= 0.2, each tau once
        if tau <= 0.04 && (frac == 10.0 || tau < 0.01) {
            fit.push((
                (d * tau).sqrt() / r,
                rep.mean() / exact - 1.0,
                rep.std_error() / exact,
            ));
        }
        println!(
            "{tau:>8} {:>10.3} {dt:>10.6} {:>18} {:>+10.4} {hits:>8} {:>8.1}",
            (d * tau).sqrt() / r,
            format!("{:.4} ± {:.4}", rep.mean(), rep.std_error()),
            rep.mean() / exact - 1.0,
            start.elapsed().as_secs_f64()
        );
    }
    // weighted least squares of the relative error on sqrt(D tau)/R: the intercept is
    // the Brownian limit
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y, s) in &fit {
        let w = 1.0 / (s * s);
        (sw, sx, sy, sxx, sxy) = (
            sw + w,
            sx + w * x,
            sy + w * y,
            sxx + w * x * x,
            sxy + w * x * y,
        );
    }
    let det = sw * sxx - sx * sx;
    let (a, b) = ((sxx * sy - sx * sxy) / det, (sw * sxy - sx * sy) / det);
    println!(
        "relative error = {a:+.4} ± {:.4} {b:+.3} ± {:.3} sqrt(D tau)/R (weighted fit over the {} rows with sqrt(D tau)/R <= 0.2, one dt each): the intercept is the Brownian limit",
        (sxx / det).sqrt(),
        (sw / det).sqrt(),
        fit.len()
    );
    Ok(())
}
