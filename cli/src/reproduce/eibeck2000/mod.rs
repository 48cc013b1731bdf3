//! `coagula reproduce eibeck2000`: Eibeck & Wagner (2000), *An efficient stochastic
//! algorithm for studying coagulation dynamics and gelation phenomena*, §6 — the event-
//! driven mass flow algorithm (MFA) against direct simulation (DSA) from monomers:
//!
//! - `fig1`: kernel 6.2 (free molecular), `m2(t)` and `C(t, 100, 200)` from MFA with
//!   N = 16, b_N = 1000 and DSA with N = 2^9..2^13, against a long DSA reference;
//! - `fig3`: the quotient (6.13) of the normalised systematic errors of `m2` (DSA
//!   Ñ = 2^11, 2^13; MFA N = 16, 64), "a factor of about six" in favour of MFA;
//! - `fig5`: the multiplicative kernel, MFA (N = b_N = 10^5) against Flory's gel mass
//!   `1 − 1/t` and `n_k` (6.8), DSA (N = 10^6) against the Marcus–Lushnikov mass
//!   `1 − t*/t` (6.11);
//! - `fig7`: the product kernel `(xy)^0.8`, MFA's gel mass for N = 10^2..10^5 with
//!   b_N = 100 N converging, DSA's largest cluster for growing N not;
//! - `kappa`: the efficiency gain (5.6) for `m2` with the constant kernel on [0, 200]
//!   (paper: about 20), with its effort and variance factors.
//!
//! Each prints a table (ours ± standard error against the reference, and the error in
//! standard errors) and, with `--plot DIR`, draws `DIR/eibeck2000-<figure>.svg`.
//! `--quick` runs the same with a tenth of the particles or replicas.

use crate::scenario::Sim;
use coagula_core::exact::Exact;
use coagula_core::kernel::{Coagulation, Fragmentation};
use coagula_core::observe::Replicas;
use coagula_core::random::generator;
use coagula_core::scheme::facade::{Init, Model, Options};
use coagula_core::scheme::registry;
use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;
use std::time::Instant;

/// The experiments, in the order `all` runs them.
pub const FIGURES: [&str; 5] = ["fig5", "fig7", "fig1", "fig3", "kappa"];

/// One trajectory observed at the output times: the functionals, and the effort spent
/// up to each time (seconds of this thread, proposals).
struct Traj {
    values: Vec<Vec<f64>>,
    secs: Vec<f64>,
    proposals: Vec<u64>,
}

fn err(e: coagula_core::Error) -> String {
    e.to_string()
}

/// Runs `sim` through `times` with the replica's own generator.
fn trajectory(
    mut sim: Box<Sim>,
    times: &[f64],
    seed: u64,
    replica: u64,
    observe: &(dyn Fn(&Sim) -> Vec<f64> + Sync),
) -> Result<Traj, String> {
    let mut rng = generator(seed, replica);
    let start = Instant::now();
    let mut proposals = 0;
    let mut out = Traj {
        values: Vec::with_capacity(times.len()),
        secs: Vec::with_capacity(times.len()),
        proposals: Vec::with_capacity(times.len()),
    };
    for &t in times {
        proposals += sim.advance_to(t, &mut rng).map_err(err)?.proposals;
        out.secs.push(start.elapsed().as_secs_f64());
        out.proposals.push(proposals);
        out.values.push(observe(&*sim));
    }
    Ok(out)
}

/// `replicas` trajectories in parallel.
fn ensemble(
    replicas: u64,
    build: &(dyn Fn() -> Result<Box<Sim>, String> + Sync),
    times: &[f64],
    seed: u64,
    observe: &(dyn Fn(&Sim) -> Vec<f64> + Sync),
) -> Result<Vec<Traj>, String> {
    (0..replicas)
        .into_par_iter()
        .map(|r| trajectory(build()?, times, seed, r, observe))
        .collect()
}

/// The replicas' statistics of functional `f` at each output time.
fn stats(trajs: &[Traj], f: usize) -> Vec<Replicas> {
    let n = trajs.first().map_or(0, |t| t.values.len());
    (0..n)
        .map(|i| {
            let mut r = Replicas::new();
            for t in trajs {
                r.push(t.values[i][f]);
            }
            r
        })
        .collect()
}

/// The mean effort per trajectory up to each output time: (seconds, proposals).
fn effort(trajs: &[Traj]) -> Vec<(f64, f64)> {
    let n = trajs.first().map_or(0, |t| t.secs.len());
    let r = trajs.len() as f64;
    (0..n)
        .map(|i| {
            (
                trajs.iter().map(|t| t.secs[i]).sum::<f64>() / r,
                trajs.iter().map(|t| t.proposals[i] as f64).sum::<f64>() / r,
            )
        })
        .collect()
}

/// `ours − reference` in standard errors (`–` when the standard error is 0).
fn z(r: &Replicas, reference: f64) -> String {
    let se = r.std_error();
    if se > 0.0 {
        format!("{:+.2}", (r.mean() - reference) / se)
    } else if r.mean() == reference {
        "0".into()
    } else {
        "exact≠".into()
    }
}

fn index_of(times: &[f64], t: f64) -> usize {
    times
        .iter()
        .position(|&s| (s - t).abs() < 1e-9)
        .expect("table time on the output grid")
}

fn grid(dt: f64, t_end: f64) -> Vec<f64> {
    let n = (t_end / dt).round() as usize;
    (1..=n).map(|i| i as f64 * dt).collect()
}

/// The registry's scheme `scheme` on `kernel` (no fragmentation) from `init`.
fn build(
    scheme: &str,
    kernel: Coagulation,
    init: &Init<'_>,
    opts: &Options,
) -> Result<Box<Sim>, String> {
    registry::build(
        registry::find(scheme).map_err(err)?,
        Model::coagulation(kernel, Fragmentation::None),
        init,
        opts,
    )
    .map_err(err)
}

/// The mass flow algorithm from `n` monomers of total mass 1, truncated at `truncation`.
fn mfa(kernel: Coagulation, n: usize, truncation: f64) -> Result<Box<Sim>, String> {
    let sizes = vec![1.0; n];
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    build(
        "mfa",
        kernel,
        &init,
        &Options::default().with_truncation(truncation),
    )
}

/// Direct simulation from `n` monomers in volume `n`.
fn dsa(kernel: Coagulation, n: usize) -> Result<Box<Sim>, String> {
    let sizes = vec![1.0; n];
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    build("dsa", kernel, &init, &Options::default())
}

/// Direct simulation over size counts from `n` monomers in volume `n`.
fn dsa_counts(kernel: Coagulation, n: u64) -> Result<Box<Sim>, String> {
    let init = Init::Counts {
        counts: &[n],
        volume: n as f64,
    };
    build("dsa-counts", kernel, &init, &Options::default())
}

/// Runs the named experiments (`all` for every one); `plot` is a directory.
pub fn reproduce(which: &[String], quick: bool, plot: Option<&str>) -> Result<(), String> {
    let mut list: Vec<&str> = Vec::new();
    for w in which {
        if w == "all" {
            list.extend(FIGURES);
        } else if let Some(f) = FIGURES.iter().find(|f| **f == w.as_str()) {
            list.push(f);
        } else {
            return Err(format!(
                "unknown figure {w:?}: one of all, {}",
                FIGURES.join(", ")
            ));
        }
    }
    if list.is_empty() {
        list.extend(FIGURES);
    }
    if let Some(dir) = plot
        && !std::path::Path::new(dir).is_dir()
    {
        return Err(format!("--plot {dir}: not a directory"));
    }
    let path = |name: &str| plot.map(|d| format!("{d}/eibeck2000-{name}.svg"));
    println!(
        "Eibeck & Wagner (2000) §6, {} mode, {} threads",
        if quick { "quick" } else { "full" },
        rayon::current_num_threads()
    );
    // Figures 1 and 3 come from the same runs: one pass makes both
    let mut did_1_3 = false;
    for f in list {
        let start = Instant::now();
        match f {
            "fig5" => fig5(quick, path("fig5"))?,
            "fig7" => fig7(quick, path("fig7"))?,
            "fig1" | "fig3" if did_1_3 => continue,
            "fig1" | "fig3" => {
                did_1_3 = true;
                fig1_3(quick, path("fig1"), path("fig3"))?
            }
            _ => kappa(quick, path("kappa"))?,
        }
        println!("({f}: {:.0} s)", start.elapsed().as_secs_f64());
    }
    Ok(())
}

/// A curve of a plot: label, points, colour, dashed.
type Curve = (String, Vec<(f64, f64)>, RGBColor, bool);

fn curve_of(label: impl Into<String>, t: &[f64], y: &[f64], c: RGBColor, dashed: bool) -> Curve {
    (
        label.into(),
        t.iter().copied().zip(y.iter().copied()).collect(),
        c,
        dashed,
    )
}

const COLORS: [RGBColor; 6] = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    ylabel: &str,
    curves: &[Curve],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let pts = curves.iter().flat_map(|c| c.1.iter());
    let (mut x1, mut y0, mut y1) = (f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        if x.is_finite() && y.is_finite() {
            (x1, y0, y1) = (x1.max(x), y0.min(y), y1.max(y));
        }
    }
    let pad = 0.05 * (y1 - y0).max(1e-12);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x1, (y0 - pad)..(y1 + pad))
        .map_err(crate::plot::err)?;
    chart
        .configure_mesh()
        .x_desc("t")
        .y_desc(ylabel)
        .draw()
        .map_err(crate::plot::err)?;
    for (label, p, c, dashed) in curves {
        let c = *c;
        if *dashed {
            chart
                .draw_series(DashedLineSeries::new(p.clone(), 6, 4, c.stroke_width(1)))
                .map_err(crate::plot::err)?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1))
                });
        } else {
            chart
                .draw_series(LineSeries::new(p.clone(), c.stroke_width(2)))
                .map_err(crate::plot::err)?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()
        .map_err(crate::plot::err)?;
    Ok(())
}

/// Panels side by side (`rows` × `cols`), each `(title, y label, curves)`.
fn figure(
    path: &str,
    rows: usize,
    cols: usize,
    panels: &[(String, String, Vec<Curve>)],
) -> Result<(), String> {
    let size = (700 * cols as u32, 480 * rows as u32);
    crate::plot::render(path, size, |root| {
        root.fill(&WHITE).map_err(crate::plot::err)?;
        for (area, (title, ylabel, curves)) in root.split_evenly((rows, cols)).iter().zip(panels) {
            draw_panel(area, title, ylabel, curves)?;
        }
        root.present().map_err(crate::plot::err)
    })?;
    println!("wrote {path}");
    Ok(())
}

/// Figures 4–5: the multiplicative kernel. MFA's gel mass `1 − n/N` and `n_1..n_5`
/// against Flory's solution, DSA's largest cluster against the Marcus–Lushnikov limit.
fn fig5(quick: bool, plot: Option<String>) -> Result<(), String> {
    let times = grid(0.05, 3.0);
    let (n_mfa, r_mfa) = if quick { (10_000, 8) } else { (100_000, 32) };
    let (n_dsa, r_dsa) = if quick { (100_000, 2) } else { (1_000_000, 8) };
    let k = Coagulation::multiplicative();
    let observe_mfa = |s: &Sim| {
        let mut v = vec![s.gel_mass().unwrap_or(f64::NAN)];
        v.extend((1..=5).map(|k| s.number_density(f64::from(k))));
        v
    };
    let m = ensemble(
        r_mfa,
        &|| mfa(k, n_mfa, n_mfa as f64),
        &times,
        50,
        &observe_mfa,
    )?;
    let d = ensemble(r_dsa, &|| dsa(k, n_dsa), &times, 51, &|s: &Sim| {
        vec![s.gel_mass().unwrap_or(f64::NAN)]
    })?;
    let flory = Exact::multiplicative();
    let ml = Exact::marcus_lushnikov();
    let (gm, gd) = (stats(&m, 0), stats(&d, 0));
    println!(
        "\n## Figure 5: gel mass, K = xy from monomers\n\nMFA N = b_N = {n_mfa} ({r_mfa} replicas) \
         against Flory 1 − 1/t (6.9); DSA N = {n_dsa} ({r_dsa} replicas, largest cluster / N, 6.15) \
         against the Marcus–Lushnikov 1 − t*/t (6.11).\n"
    );
    println!("| t | MFA | ± SE | 1 − 1/t | z | DSA | ± SE | 1 − t*/t | z |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for t in [0.5, 1.0, 1.5, 2.0, 2.5, 3.0] {
        let i = index_of(&times, t);
        let (ef, em) = (
            flory.gel_mass(t).map_err(err)?,
            ml.gel_mass(t).map_err(err)?,
        );
        println!(
            "| {t} | {:.5} | {:.1e} | {ef:.5} | {} | {:.5} | {:.1e} | {em:.5} | {} |",
            gm[i].mean(),
            gm[i].std_error(),
            z(&gm[i], ef),
            gd[i].mean(),
            gd[i].std_error(),
            z(&gd[i], em)
        );
    }
    println!("\nFigure 4: MFA's n_k against Flory's solution (6.8), ours (SE from reference)\n");
    println!("| t | n_1 | n_2 | n_3 | n_4 | n_5 |");
    println!("|---|---|---|---|---|---|");
    for t in [0.5, 1.0, 2.0, 3.0] {
        let i = index_of(&times, t);
        let mut row = format!("| {t} |");
        for kk in 1..=5u64 {
            let r = &stats(&m, kk as usize)[i];
            let e = flory.number_density(kk, t).map_err(err)?;
            row += &format!(" {:.4e} ({}) |", r.mean(), z(r, e));
        }
        println!("{row}");
    }
    if let Some(p) = plot {
        let mean = |g: &[Replicas]| g.iter().map(Replicas::mean).collect::<Vec<_>>();
        let ef: Vec<f64> = times
            .iter()
            .map(|&t| flory.gel_mass(t).unwrap_or(f64::NAN))
            .collect();
        let em: Vec<f64> = times
            .iter()
            .map(|&t| ml.gel_mass(t).unwrap_or(f64::NAN))
            .collect();
        let curves = vec![
            curve_of(
                format!("MFA N = b_N = {n_mfa}"),
                &times,
                &mean(&gm),
                RED,
                false,
            ),
            curve_of("1 − 1/t (6.9)", &times, &ef, RED, true),
            curve_of(format!("DSA N = {n_dsa}"), &times, &mean(&gd), BLUE, false),
            curve_of("1 − t*/t (6.11)", &times, &em, BLUE, true),
        ];
        figure(
            &p,
            1,
            1,
            &[(
                "Gel mass, K = xy (Eibeck & Wagner Fig. 5)".into(),
                "gel mass".into(),
                curves,
            )],
        )?;
    }
    Ok(())
}

/// Figure 7: the product kernel (xy)^0.8. MFA's gel mass for N = 10^2..10^5 with
/// b_N = 100 N (right), DSA's largest cluster for growing N (left).
fn fig7(quick: bool, plot: Option<String>) -> Result<(), String> {
    let times = grid(0.1, 4.0);
    let k = Coagulation::product(0.8).map_err(err)?;
    let ns_mfa: &[usize] = if quick {
        &[100, 1_000, 10_000]
    } else {
        &[100, 1_000, 10_000, 100_000]
    };
    let ns_dsa: &[usize] = if quick {
        &[10_000, 100_000]
    } else {
        &[100_000, 1_000_000, 10_000_000]
    };
    let budget = if quick { 200_000 } else { 500_000 };
    let mut mfa_g = Vec::new();
    for &n in ns_mfa {
        let r = (budget / n).clamp(4, 2000) as u64;
        let start = Instant::now();
        let m = ensemble(
            r,
            &|| mfa(k, n, 100.0 * n as f64),
            &times,
            70 + n as u64,
            &|s| vec![s.gel_mass().unwrap_or(f64::NAN)],
        )?;
        eprintln!(
            "fig7: MFA N = {n}, {r} replicas: {:.1} s",
            start.elapsed().as_secs_f64()
        );
        mfa_g.push((n, r, stats(&m, 0)));
    }
    let mut dsa_g = Vec::new();
    for &n in ns_dsa {
        let r = 2;
        let start = Instant::now();
        let d = ensemble(r, &|| dsa(k, n), &times, 71 + n as u64, &|s| {
            vec![s.gel_mass().unwrap_or(f64::NAN)]
        })?;
        eprintln!(
            "fig7: DSA N = {n}, {r} replicas: {:.1} s",
            start.elapsed().as_secs_f64()
        );
        dsa_g.push((n, r, stats(&d, 0)));
    }
    println!(
        "\n## Figure 7: gel mass, K = (xy)^0.8 from monomers\n\nMFA (1 − n/N, b_N = 100 N) and DSA \
         (largest cluster / N), mean ± SE over the replicas.\n"
    );
    let mut head = "| t |".to_string();
    for (n, r, _) in &mfa_g {
        head += &format!(" MFA N = {n} (R = {r}) |");
    }
    for (n, r, _) in &dsa_g {
        head += &format!(" DSA N = {n} (R = {r}) |");
    }
    println!("{head}");
    println!("|---{}|", "|---".repeat(mfa_g.len() + dsa_g.len()));
    for t in [1.0, 1.5, 2.0, 3.0, 4.0] {
        let i = index_of(&times, t);
        let mut row = format!("| {t} |");
        for (_, _, g) in mfa_g.iter().chain(&dsa_g) {
            row += &format!(" {:.4} ± {:.1e} |", g[i].mean(), g[i].std_error());
        }
        println!("{row}");
    }
    if let Some(p) = plot {
        let mean = |g: &[Replicas]| g.iter().map(Replicas::mean).collect::<Vec<_>>();
        let right: Vec<Curve> = mfa_g
            .iter()
            .enumerate()
            .map(|(i, (n, _, g))| {
                curve_of(format!("MFA N = {n}"), &times, &mean(g), COLORS[i], false)
            })
            .collect();
        let mut left: Vec<Curve> = dsa_g
            .iter()
            .enumerate()
            .map(|(i, (n, _, g))| {
                curve_of(format!("DSA N = {n}"), &times, &mean(g), COLORS[i], false)
            })
            .collect();
        if let Some((n, _, g)) = mfa_g.last() {
            left.push(curve_of(
                format!("MFA N = {n}"),
                &times,
                &mean(g),
                BLACK,
                true,
            ));
        }
        figure(
            &p,
            1,
            2,
            &[
                (
                    "DSA, K = (xy)^0.8 (Fig. 7 left)".into(),
                    "gel mass".into(),
                    left,
                ),
                (
                    "MFA, b_N = 100 N (Fig. 7 right)".into(),
                    "gel mass".into(),
                    right,
                ),
            ],
        )?;
    }
    Ok(())
}

/// A run of one scheme and size in Figures 1 and 3: `m2` and `C(t, 100, 200)` at each time.
struct Run {
    label: String,
    scheme: &'static str,
    n: usize,
    m2: Vec<Replicas>,
    c: Vec<Replicas>,
}

/// Figures 1 and 3: kernel 6.2 from monomers on [0, 30]. `m2` and `C(t, 100, 200)` from
/// DSA (N = 2^9..2^13) and MFA (N = 16, 64; b_N = 1000 as in the paper, and b_N = ∞)
/// against a DSA reference, and the quotient (6.13) of the normalised systematic errors
/// of `m2` (MFA with b_N = ∞, so that the truncation does not add to its error).
fn fig1_3(quick: bool, plot1: Option<String>, plot3: Option<String>) -> Result<(), String> {
    let times = grid(0.5, 30.0);
    let k = Coagulation::free_molecular();
    // particle-trajectories per run: R = budget / N
    let budget: u64 = if quick { 1 << 21 } else { 1 << 25 };
    let observe = |s: &Sim| vec![s.moment(2.0), s.concentration(100.0, 200.0), s.moment(0.0)];
    // the reference: direct simulation over size counts (the same Marcus–Lushnikov
    // process, no particle list) from many monomers
    let n_ref: u64 = if quick { 1_000_000 } else { 10_000_000 };
    let r_ref = if quick { 4 } else { 8 };
    let reference = ensemble(r_ref, &|| dsa_counts(k, n_ref), &times, 10, &|s| observe(s))?;
    let (ref_m2, ref_c, ref_m0) = (
        stats(&reference, 0),
        stats(&reference, 1),
        stats(&reference, 2),
    );
    let mut runs = Vec::new();
    for n in [1usize << 9, 1 << 10, 1 << 11, 1 << 12, 1 << 13] {
        let r = budget / n as u64;
        let d = ensemble(r, &|| dsa(k, n), &times, 11 + n as u64, &|s| observe(s))?;
        runs.push(Run {
            label: format!("DSA {n} (R {r})"),
            scheme: "DSA",
            n,
            m2: stats(&d, 0),
            c: stats(&d, 1),
        });
    }
    for (n, b) in [
        (16usize, 1000.0),
        (64, 1000.0),
        (16, f64::INFINITY),
        (64, f64::INFINITY),
    ] {
        let r = budget / 16 / n as u64;
        let m = ensemble(
            r,
            &|| mfa(k, n, b),
            &times,
            12 + n as u64 + b.is_finite() as u64,
            &|s| observe(s),
        )?;
        runs.push(Run {
            label: format!("MFA {n}, b_N {b} (R {r})"),
            scheme: if b.is_finite() { "MFA" } else { "MFA∞" },
            n,
            m2: stats(&m, 0),
            c: stats(&m, 1),
        });
    }
    let last = times.len() - 1;
    let table_times = [1.0, 3.0, 10.0, 20.0, 30.0];
    println!(
        "\n## Figure 1: kernel 6.2 (free molecular) from monomers\n\nReference: direct simulation \
         over size counts, N = {n_ref}, {r_ref} replicas (m0(30) = {:.5} = 1/{:.0}: the paper's \
         particle number \"reduced by a factor 200\"). Entries: mean (difference from the reference \
         in standard errors of the difference).\n",
        ref_m0[last].mean(),
        1.0 / ref_m0[last].mean()
    );
    let diff_z = |a: &Replicas, b: &Replicas| {
        let se = (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
        if se > 0.0 {
            (a.mean() - b.mean()) / se
        } else {
            0.0
        }
    };
    for (name, is_m2) in [("m2", true), ("C(t, 100, 200)", false)] {
        let refs = if is_m2 { &ref_m2 } else { &ref_c };
        println!(
            "| {name}: run | {} |",
            table_times.map(|t| format!("t = {t}")).join(" | ")
        );
        println!("|---{}|", "|---".repeat(table_times.len()));
        let mut row = "| reference |".to_string();
        for t in table_times {
            row += &format!(" {:.5e} |", refs[index_of(&times, t)].mean());
        }
        println!("{row}");
        for run in &runs {
            let g = if is_m2 { &run.m2 } else { &run.c };
            let mut row = format!("| {} |", run.label);
            for t in table_times {
                let i = index_of(&times, t);
                row += &format!(" {:.5e} ({:+.1}) |", g[i].mean(), diff_z(&g[i], &refs[i]));
            }
            println!("{row}");
        }
        println!();
    }
    // Figure 3: quotient (6.13) = ẽ Ñ m0(t) / (e N) of the systematic errors of m2
    let find = |scheme: &str, n: usize| {
        runs.iter()
            .find(|r| r.scheme == scheme && r.n == n)
            .expect("run")
    };
    let mut q_curves = Vec::new();
    println!(
        "## Figure 3: quotient (6.13) of normalised systematic errors of m2\n\n\
         ẽ Ñ m0(t) / (e N), e = mean − reference (in standard errors in brackets), MFA with \
         b_N = ∞; paper: about 6.\n"
    );
    println!("| t | pair | DSA error (z) | MFA error (z) | quotient | ± SE |");
    println!("|---|---|---|---|---|---|");
    for (nd, nm) in [(1usize << 11, 16usize), (1 << 13, 64), (1 << 13, 16)] {
        let (d, m) = (find("DSA", nd), find("MFA∞", nm));
        let mut qs = Vec::new();
        for i in 0..times.len() {
            let ed = d.m2[i].mean() - ref_m2[i].mean();
            let em = m.m2[i].mean() - ref_m2[i].mean();
            let sd = (d.m2[i].std_error().powi(2) + ref_m2[i].std_error().powi(2)).sqrt();
            let sm = (m.m2[i].std_error().powi(2) + ref_m2[i].std_error().powi(2)).sqrt();
            let q = ed.abs() * nd as f64 * ref_m0[i].mean() / (em.abs() * nm as f64);
            let qse = q * ((sd / ed).powi(2) + (sm / em).powi(2)).sqrt();
            qs.push(q);
            if table_times.iter().any(|&t| (t - times[i]).abs() < 1e-9) {
                println!(
                    "| {} | DSA {nd} / MFA {nm} | {ed:+.3e} ({:+.1}) | {em:+.3e} ({:+.1}) | {q:.2} | {qse:.2} |",
                    times[i],
                    ed / sd,
                    em / sm
                );
            }
        }
        let c = COLORS[q_curves.len()];
        q_curves.push(curve_of(
            format!("DSA {nd} / MFA {nm}"),
            &times,
            &qs,
            c,
            false,
        ));
    }
    if let Some(p) = plot3 {
        let title = "Quotient (6.13) for m2, kernel 6.2 (Fig. 3)";
        figure(&p, 1, 1, &[(title.into(), "quotient".into(), q_curves)])?;
    }
    if let Some(p) = plot1 {
        let mean = |g: &[Replicas]| g.iter().map(Replicas::mean).collect::<Vec<_>>();
        let mut panels = Vec::new();
        for (name, is_m2) in [("C(t, 100, 200)", false), ("m2", true)] {
            let refs = if is_m2 { &ref_m2 } else { &ref_c };
            for who in ["DSA", "MFA"] {
                let mut c: Vec<Curve> = runs
                    .iter()
                    .filter(|r| r.scheme.starts_with(who))
                    .enumerate()
                    .map(|(i, run)| {
                        let g = if is_m2 { &run.m2 } else { &run.c };
                        curve_of(run.label.clone(), &times, &mean(g), COLORS[i], false)
                    })
                    .collect();
                let label = format!("reference (N = {n_ref})");
                c.push(curve_of(label, &times, &mean(refs), BLACK, true));
                panels.push((format!("{name}, {who} (Fig. 1)"), name.to_string(), c));
            }
        }
        figure(&p, 2, 2, &panels)?;
    }
    Ok(())
}

/// The efficiency gain (5.6) κ(t) = (r̃ Var ξ̃)/(r Var ξ) for m2 with the constant kernel
/// on [0, 200]: DSA and MFA from N monomers, each replica running one trajectory of each
/// in the same thread (so machine noise falls on both), effort in seconds and proposals.
fn kappa(quick: bool, plot: Option<String>) -> Result<(), String> {
    let times = [1.0, 5.0, 10.0, 20.0, 50.0, 100.0, 150.0, 200.0];
    let (ns, r): (&[usize], u64) = if quick {
        (&[1 << 10], 256)
    } else {
        (&[1 << 12, 1 << 14], 1024)
    };
    let k = Coagulation::constant(1.0).map_err(err)?;
    let observe = |s: &Sim| vec![s.moment(2.0)];
    let exact = Exact::constant(1.0).map_err(err)?;
    let mut curves = Vec::new();
    for (ci, &n) in ns.iter().enumerate() {
        let both: Vec<(Traj, Traj)> = (0..r)
            .into_par_iter()
            .map(|i| {
                let d = trajectory(dsa(k, n)?, &times, 90 + n as u64, i, &|s| observe(s))?;
                let m = trajectory(mfa(k, n, f64::INFINITY)?, &times, 91 + n as u64, i, &|s| {
                    observe(s)
                })?;
                Ok((d, m))
            })
            .collect::<Result<_, String>>()?;
        let (d, m): (Vec<Traj>, Vec<Traj>) = both.into_iter().unzip();
        let (vd, vm) = (stats(&d, 0), stats(&m, 0));
        let (ed, em) = (effort(&d), effort(&m));
        println!(
            "\n## Efficiency gain κ for m2, constant kernel (5.6), N = {n}\n\nN = Ñ = {n} monomers, \
             {r} replicas of each (a DSA and an MFA trajectory in turn on one thread); κ = κ_eff κ_var, \
             the effort r as seconds per trajectory (and as proposals); paper: about 20 on [0, 200].\n"
        );
        println!(
            "| t | m2 exact | DSA m2 (z) | MFA m2 (z) | κ_var | κ_eff (s) | κ (s) | κ_eff (proposals) | κ (proposals) |"
        );
        println!("|---|---|---|---|---|---|---|---|---|");
        let mut kap = Vec::new();
        for (i, &t) in times.iter().enumerate() {
            let x = exact.moment(2, t).map_err(err)?;
            let kvar = vd[i].variance() / vm[i].variance();
            let (ks, kp) = (ed[i].0 / em[i].0, ed[i].1 / em[i].1);
            kap.push(ks * kvar);
            println!(
                "| {t} | {x} | {:.3} ({}) | {:.3} ({}) | {kvar:.1} | {ks:.3} | {:.1} | {kp:.3} | {:.1} |",
                vd[i].mean(),
                z(&vd[i], x),
                vm[i].mean(),
                z(&vm[i], x),
                ks * kvar,
                kp * kvar
            );
        }
        curves.push(curve_of(
            format!("κ, N = {n} (effort in seconds)"),
            &times,
            &kap,
            COLORS[ci],
            false,
        ));
    }
    if let Some(p) = plot {
        let title = "Gain κ(t) for m2, K = 1 (paper: about 20 on [0, 200])";
        figure(&p, 1, 1, &[(title.into(), "κ".into(), curves)])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
