//! `coagula bench peers`: our runs beside the recorded figures of the authors' codes
//! and of PySDM and PyPartMC (docs/results/).

use super::*;

/// `initial.particles` of a scenario file as written (no overrides).
pub(super) fn original_particles(file: Option<&str>) -> Option<u64> {
    let (_, text) = crate::plans::resolve(file).ok()?;
    let t: toml::Table = toml::from_str(&text).ok()?;
    t.get("initial")?
        .get("particles")?
        .as_integer()
        .map(|n| n as u64)
}

/// The figures measured for the peers and the authors' code, side by side with ours on
/// this machine (see `docs/results/peers-golovin.md` and
/// `docs/results/osinsky2023-authors.md` for how).
const PEER_FIGURES: &str = include_str!("../../../../docs/results/peer-figures.csv");

/// One recorded figure.
struct Figure {
    problem: String,
    code: String,
    version: String,
    date: String,
    n: f64,
    t: f64,
    seconds: f64,
    rss_mb: Option<f64>,
    errors: Option<(f64, f64)>,
    collisions: Option<f64>,
    n_ratio: Option<f64>,
}

/// The built-in figures (`#` lines are comments).
fn figures() -> Vec<Figure> {
    let mut r = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_reader(PEER_FIGURES.as_bytes());
    let opt = |x: &str| x.trim().parse::<f64>().ok();
    r.records()
        .map(|rec| {
            let rec = rec.expect("built-in CSV");
            let f = |i: usize| rec.get(i).unwrap_or("").trim().to_string();
            let num = |i: usize| opt(&f(i)).expect("built-in number");
            Figure {
                problem: f(0),
                code: f(1),
                version: f(2),
                date: f(3),
                n: num(4),
                t: num(5),
                seconds: num(6),
                rss_mb: opt(&f(7)),
                errors: opt(&f(8)).zip(opt(&f(9))),
                collisions: opt(&f(10)),
                n_ratio: opt(&f(11)),
            }
        })
        .collect()
}

/// Our row of a peers problem: particles, seconds per run, RMS relative errors of
/// M0 and M2.
struct Ours {
    layout: &'static str,
    n: u64,
    seconds: f64,
    m0: f64,
    m2: f64,
}

/// `coagula bench peers`: see the command's help (`constant`: the constant kernel to
/// t = 10 instead of Golovin's to t = 5.4).
pub fn peers(
    seeds: u64,
    max_log2n: u32,
    authors: bool,
    constant: bool,
) -> Result<(), coagula_core::Error> {
    use coagula_core::exact::Exact;
    let figs = figures();
    let (problem, t, exact, kernel, name) = if constant {
        (
            "constant-exp",
            10.0,
            Exact::constant_exponential(1.0)?,
            Coagulation::constant(1.0)?,
            "The constant kernel K = 1",
        )
    } else {
        (
            "golovin-exp",
            5.4,
            Exact::additive_exponential(),
            Coagulation::additive(),
            "Golovin's kernel K = x + y",
        )
    };
    let (e0, e2) = (exact.moment(0, t)?, exact.moment(2, t)?);
    println!(
        "{name} from c(x,0) = e^-x to t = {t}: {} here ({seeds} seeds,\n\
         midpoint quantiles of Exp(1), one thread, seconds per run) against the peers' recorded\n\
         figures (CPU seconds of stepping; RMS relative errors over their seeds)\n",
        if constant {
            "lowrank-sizes and the bucketed layout on a 1/64 grid"
        } else {
            "lowrank-sizes"
        }
    );
    println!(
        "{:>10} {:>12} {:>10} {:>10}",
        "N", "s/run", "M0 err", "M2 err"
    );
    // the constant kernel also on the bucketed layout over integer sizes (a grid of
    // 1/64 of the mean; K = 1 has degree 0, so its coefficient is unchanged)
    let layouts: &[(&str, SchemeId)] = if constant {
        &[
            ("lowrank-sizes", registry::find("lowrank-sizes").unwrap()),
            (
                "lowrank (sizes on a 1/64 grid)",
                registry::find("lowrank").unwrap(),
            ),
        ]
    } else {
        &[("lowrank-sizes", registry::find("lowrank-sizes").unwrap())]
    };
    const GRID: f64 = 64.0;
    let mut ours = Vec::new();
    for &(label, id) in layouts {
        println!("{label}:");
        for lg in (12..=max_log2n).step_by(2) {
            let n = 1u64 << lg;
            let sizes: Vec<f64> = (0..n)
                .map(|i| -(-((i as f64 + 0.5) / n as f64)).ln_1p())
                .collect();
            let mut counts: Vec<u64> = Vec::new();
            if id == registry::find("lowrank").unwrap() {
                for &x in &sizes {
                    let k = ((x * GRID).round() as usize).max(1);
                    if counts.len() < k {
                        counts.resize(k, 0);
                    }
                    counts[k - 1] += 1;
                }
            }
            let (kernel, m2_unit) = if id == registry::find("lowrank").unwrap() {
                (kernel.with_min_size(1.0)?, GRID * GRID)
            } else {
                (kernel, 1.0)
            };
            let (mut s0, mut s2, mut secs) = (0.0, 0.0, 0.0);
            for seed in 0..seeds {
                let start = Instant::now();
                let init = if id == registry::find("lowrank").unwrap() {
                    Init::Counts {
                        counts: &counts,
                        volume: n as f64,
                    }
                } else {
                    Init::Sizes {
                        sizes: &sizes,
                        mass: 1.0,
                    }
                };
                let mut sim: Box<Sim> = registry::build(
                    id,
                    Model::coagulation(kernel, NoFragmentation),
                    &init,
                    &Options::default(),
                )?;
                sim.advance_to(t, &mut generator(seed, 0))?;
                secs += start.elapsed().as_secs_f64();
                s0 += (sim.moment(0.0) / e0 - 1.0).powi(2);
                s2 += (sim.moment(2.0) / m2_unit / e2 - 1.0).powi(2);
            }
            let k = seeds as f64;
            let o = Ours {
                layout: if id == registry::find("lowrank").unwrap() {
                    "grid"
                } else {
                    "sizes"
                },
                n,
                seconds: secs / k,
                m0: (s0 / k).sqrt(),
                m2: (s2 / k).sqrt(),
            };
            println!(
                "{:>10} {:>12.4} {:>9.2}% {:>9.2}%",
                format!("2^{lg}"),
                o.seconds,
                100.0 * o.m0,
                100.0 * o.m2
            );
            ours.push(o);
        }
    }
    println!(
        "\n{:<10} {:>8} {:>10} {:>9} {:>9} | {:>10} {:>10} {:>9}",
        "peer", "N", "CPU s", "M0 err", "M2 err", "ours", "our s", "ratio"
    );
    for f in figs.iter().filter(|f| f.problem == problem && f.t == t) {
        let Some((m0, m2)) = f.errors else { continue };
        let best = ours
            .iter()
            .filter(|o| o.m0 <= m0 && o.m2 <= m2)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
        let lg = f.n.log2().round();
        let (on, os, ratio) = match best {
            Some(o) => (
                format!("{} 2^{}", o.layout, o.n.trailing_zeros()),
                format!("{:.4}", o.seconds),
                format!("{:.1}x", f.seconds / o.seconds),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        println!(
            "{:<10} {:>8} {:>10.3} {:>8.2}% {:>8.2}% | {on:>10} {os:>10} {ratio:>9}",
            f.code,
            format!("2^{lg}"),
            f.seconds,
            100.0 * m0,
            100.0 * m2
        );
    }
    // every peer's version and date, once each
    let mut seen: Vec<String> = Vec::new();
    for f in figs.iter().filter(|f| f.problem == problem) {
        let who = format!("{} {}, measured {}", f.code, f.version, f.date);
        if !seen.contains(&who) {
            seen.push(who);
        }
    }
    if !seen.is_empty() {
        println!(
            "(peer figures: {}; ratio = peer CPU / ours at the cheapest of our rows with both errors at most the peer's; '-': none of ours up to 2^{max_log2n})",
            seen.join("; ")
        );
        println!(
            "what the errors are made of (RMS over seeds = sqrt(bias^2 + one run's spread^2)):\n\
             - ours: event-driven, no time step; the bias is the O(1/N) of the finite system, so the error is one run's spread\n\
             - PySDM at dt = 1/48 (the recorded runs): at large N its M2 error is almost all time-step bias\n  \
             (-43 % at 2^18 and 2^20, gone at dt = 1/480); at 2^12-2^16 spread and bias mix\n\
             - PyPartMC at dt = 0.0015: spread and its finite-N bias\n\
             - at equal N our M2 error is the larger (2^12: about 60 % against 24 % and 31 %): M2 at t = 5.4 rests on the\n  \
             few largest clusters; the ratio column compares cost at equal or better error instead (docs/results/peers-golovin.md)"
        );
    }
    if !authors {
        return Ok(());
    }
    println!(
        "\nOsinsky's tables from 1e7 monomers: the bucketed layout here against the authors' Fortran (recorded)\n"
    );
    println!(
        "{:<10} {:>8} | {:>9} {:>8} {:>10} {:>12} | {:>9} {:>10} {:>12} | {:>6}",
        "kernel", "t", "Fortran s", "RSS MB", "coll", "N/N0", "ours s", "coll", "N/N0", "ratio"
    );
    for f in figs.iter().filter(|f| f.problem.starts_with("osinsky-")) {
        let name = f.problem.trim_start_matches("osinsky-");
        let start = Instant::now();
        let mut sim = monodisperse(
            registry::find("lowrank").unwrap(),
            paper_kernel(name),
            f.n as u64,
        )?;
        let rep = sim.advance_to(f.t, &mut generator(1, 0))?;
        let s = start.elapsed().as_secs_f64();
        println!(
            "{name:<10} {:>8} | {:>9.2} {:>8} {:>10.3e} {:>12.6e} | {s:>9.2} {:>10.3e} {:>12.6e} | {:>5.2}x",
            f.t,
            f.seconds,
            f.rss_mb.map_or("-".into(), |m| format!("{m:.0}")),
            f.collisions.unwrap_or(f64::NAN),
            f.n_ratio.unwrap_or(f64::NAN),
            rep.events as f64,
            sim.moment(0.0),
            f.seconds / s
        );
    }
    if let Some(f) = figs.iter().find(|f| f.problem.starts_with("osinsky-")) {
        println!(
            "(Fortran: {} at {}, gfortran -O3 -march=native, measured {}; ours: this run, wall seconds including the build)",
            f.code, f.version, f.date
        );
    }
    Ok(())
}
