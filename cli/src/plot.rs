//! Plots (plotters): drawn as SVG, which needs no font files; a `.png` is that SVG
//! rasterised by resvg with the system's fonts (text is left out where none is found).

use crate::output::rows;
use crate::runner::Outcome;
use crate::scenario::{Observable, Plan};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(crate) fn err<E: std::fmt::Display>(e: E) -> String {
    format!("plot: {e}")
}

/// The output format of a plot path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.svg`.
    Svg,
    /// `.png`.
    Png,
}

/// Checks a plot path's extension and creates the file, so a bad name or directory
/// fails before any work.
pub fn check(path: &str) -> Result<Format, String> {
    let format = if path.ends_with(".svg") {
        Format::Svg
    } else if path.ends_with(".png") {
        Format::Png
    } else {
        return Err(format!(
            "plot: {path}: the file name must end in .svg or .png"
        ));
    };
    std::fs::File::create(path).map_err(|e| format!("--plot {path}: {e}"))?;
    Ok(format)
}

/// Draws into an SVG document, then writes it, or its rasterisation for `.png`.
pub fn render(
    path: &str,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<(), String> {
    let format = check(path)?;
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, size).into_drawing_area())?;
    match format {
        Format::Svg => std::fs::write(path, svg).map_err(|e| format!("plot: {path}: {e}")),
        Format::Png => rasterise(&svg, path),
    }
}

/// SVG text to a PNG file with resvg.
fn rasterise(svg: &str, path: &str) -> Result<(), String> {
    use resvg::{tiny_skia, usvg};
    let mut opt = usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    if db.is_empty() {
        eprintln!(
            "warning: no system fonts found, so {path} has no text (install fonts-dejavu-core, or plot to .svg)"
        );
    }
    let family = db
        .faces()
        .flat_map(|f| f.families.iter().map(|(n, _)| n.clone()))
        .find(|n| n == "DejaVu Sans" || n == "Liberation Sans" || n.contains("Sans"));
    if let Some(f) = family {
        db.set_sans_serif_family(f);
    }
    let tree = usvg::Tree::from_str(svg, &opt).map_err(err)?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| "plot: empty image".to_string())?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap
        .save_png(path)
        .map_err(|e| format!("plot: {path}: {e}"))
}

/// The plot of a run: per observable a panel of the mean against time with its 95%
/// confidence band (replicas) and the exact solution, and under it, where the exact
/// solution is known, the relative error `(ours − exact)/exact` with the band, so that
/// an error of 1e-4 is as visible as one of 1.
pub fn run(path: &str, plan: &Plan, out: &Outcome) -> Result<(), String> {
    let with_exact = plan.exact.is_some()
        && plan
            .observables
            .iter()
            .any(|o| plan.exact.and_then(|e| e.value(o, plan.times[0])).is_some());
    let n = plan.observables.len() as u32;
    let cols = n.clamp(1, 4);
    let blocks = n.div_ceil(4).max(1);
    let sizes = u32::from(plan.classes.len() > 1);
    let size = (
        (520 * cols + 40).max(760),
        blocks * if with_exact { 780 } else { 440 } + sizes * 460 + 40,
    );
    render(path, size, |root| {
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(&plan.title, ("sans-serif", 22)).map_err(err)?;
        let (top, bottom) = if sizes == 1 {
            let h = root.dim_in_pixel().1;
            let (a, b) = root.split_vertically(h.saturating_sub(460));
            (a, Some(b))
        } else {
            (root, None)
        };
        draw_run(&top, plan, out, with_exact)?;
        if let Some(b) = &bottom {
            draw_sizes(b, plan, out)?;
        }
        // (the SVG document is closed once, after every panel)
        top.present().map_err(err)
    })
}

/// The time axis' label: its units.
fn time_label(plan: &Plan) -> String {
    if plan.units.is_empty() {
        "t (units of 1/(K c0))".into()
    } else {
        "t [s]".into()
    }
}

/// An observable's axis label with its units (per unit volume, sizes in the
/// scenario's units; with physical units, per m³ and sizes in monomers).
fn value_label(plan: &Plan, o: &Observable) -> String {
    let phys = !plan.units.is_empty();
    match o {
        Observable::Moment(m) if phys && *m == 0.0 => "M0 [m^-3]".into(),
        Observable::Moment(m) if phys => format!("M{m} [monomers^{m} m^-3]"),
        Observable::Moment(m) if *m == 0.0 => "M0 [per volume]".into(),
        Observable::Moment(m) if *m == 1.0 => "M1 [size per volume]".into(),
        Observable::Moment(m) => format!("M{m} [size^{m} per volume]"),
        Observable::Density(_) | Observable::Concentration(..) | Observable::Class(..) => {
            if phys {
                format!("{} [m^-3]", o.name())
            } else {
                format!("{} [per volume]", o.name())
            }
        }
        Observable::Gel if phys => "gel [monomers m^-3]".into(),
        Observable::Gel => "gel [size per volume]".into(),
        Observable::Particles => "N [simulation particles]".into(),
        Observable::Named(n) => n.clone(),
    }
}

/// A coordinate on a linear or a log10 axis (`None`: not drawable on a log axis).
fn on_axis(log: bool, v: f64) -> Option<f64> {
    if !v.is_finite() {
        None
    } else if log {
        (v > 0.0).then(|| v.log10())
    } else {
        Some(v)
    }
}

/// A tick label of a log10 (`log`) or linear axis spanning `range`.
fn axis_tick(log: bool, v: f64, range: f64) -> String {
    if log { log_tick(v) } else { tick(v, range) }
}

/// Tick labels of a log10 axis: the value 10^v at whole decades, none between.
fn log_tick(v: f64) -> String {
    if (v - v.round()).abs() > 1e-9 {
        return String::new();
    }
    let x = 10f64.powf(v.round());
    if (1e-3..1e4).contains(&x) {
        format!("{}", (x * 1e3).round() / 1e3)
    } else {
        format!("{x:.0e}")
    }
}

/// The size distribution `dN/dlog10 x = C[a, b) / log10(b/a)` on the plan's classes at
/// up to four output times (the first, the last and two between), against the exact
/// solution where it gives the classes; log size axis.
fn draw_sizes<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plan: &Plan,
    out: &Outcome,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = &plan.classes;
    let nobs = plan.observables.len();
    let nt = plan.times.len();
    let mut picks: Vec<usize> = [0, nt / 3, 2 * nt / 3, nt - 1].to_vec();
    picks.dedup();
    let x_of = |k: usize| (e[k] * e[k + 1]).sqrt().log10();
    let width = |k: usize| (e[k + 1] / e[k]).log10();
    let curve = |i: usize| -> Vec<(f64, f64)> {
        (0..e.len() - 1)
            .filter_map(|k| {
                let v = out.stats[i][nobs + k].mean() / width(k);
                on_axis(plan.log_axes, v).map(|y| (x_of(k), y))
            })
            .collect()
    };
    let exact = |i: usize| -> Vec<(f64, f64)> {
        let t = plan.times[i];
        (0..e.len() - 1)
            .filter_map(|k| {
                let o = Observable::Class(e[k], e[k + 1]);
                let v = plan.exact.and_then(|x| x.value(&o, t))? / width(k);
                on_axis(plan.log_axes, v).map(|y| (x_of(k), y))
            })
            .collect()
    };
    let all: Vec<(f64, f64)> = picks.iter().flat_map(|&i| curve(i)).collect();
    let values: Vec<f64> = all
        .iter()
        .map(|p| p.1)
        .chain(picks.iter().flat_map(|&i| exact(i)).map(|p| p.1))
        .filter(|v| v.is_finite())
        .collect();
    let top = values.iter().fold(f64::MIN, |a, &v| a.max(v));
    let (ylo, yhi) = if plan.log_axes {
        // six decades below the largest value, not the exact solution's far tail
        span(values.iter().copied().filter(|&v| v >= top - 6.0))
    } else {
        span(values.iter().copied())
    };
    let exact =
        |i: usize| -> Vec<(f64, f64)> { exact(i).into_iter().filter(|p| p.1 >= ylo).collect() };
    let (xlo, xhi) = (e[0].log10(), e[e.len() - 1].log10());
    let unit = if plan.units.is_empty() {
        "per volume"
    } else {
        "m^-3"
    };
    let mut chart = ChartBuilder::on(root)
        .caption(
            "size distribution dN/dlog10 x on the classes [e_i, e_i+1) (mean of the replicas; exact dashed where known)",
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(xlo..xhi, ylo..yhi)
        .map_err(err)?;
    let log_y = plan.log_axes;
    chart
        .configure_mesh()
        .x_desc(if plan.units.is_empty() {
            "size x"
        } else {
            "size x [monomers]"
        })
        .y_desc(format!("dN/dlog10 x [{unit}]"))
        .x_label_formatter(&|v| log_tick(*v))
        .y_label_formatter(&|v| axis_tick(log_y, *v, yhi - ylo))
        .draw()
        .map_err(err)?;
    for (c, &i) in picks.iter().enumerate() {
        let color = COLORS[c % COLORS.len()];
        chart
            .draw_series(LineSeries::new(curve(i), color.stroke_width(2)))
            .map_err(err)?
            .label(format!("t = {}", tick(plan.times[i], plan.times[nt - 1])))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        let ex = exact(i);
        if !ex.is_empty() {
            chart
                .draw_series(DashedLineSeries::new(ex, 6, 4, color.stroke_width(1)))
                .map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    Ok(())
}

const COLORS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// A tick label: plain digits for moderate magnitudes, else scientific; values below
/// a millionth of the axis' range are 0 (no "6.9e-18" for a rounding residue).
fn tick(v: f64, range: f64) -> String {
    let a = v.abs();
    if a <= 1e-6 * range {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.2e}")
    }
}

fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(v), a.1.max(v)));
    if lo > hi {
        (0.0, 1.0)
    } else if hi - lo <= 1e-300 + 1e-12 * hi.abs().max(lo.abs()) {
        let pad = 0.05 * lo.abs().max(1e-300);
        (lo - pad, hi + pad)
    } else {
        let pad = 0.06 * (hi - lo);
        (lo - pad, hi + pad)
    }
}

fn draw_run<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plan: &Plan,
    out: &Outcome,
    with_exact: bool,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let data = rows(plan, out);
    // log time axis where asked for (and every time is > 0)
    let log_t = plan.log_axes && plan.times.first().is_some_and(|&t| t > 0.0);
    let tx = |t: f64| if log_t { t.log10() } else { t };
    let n = plan.observables.len();
    let cols = n.clamp(1, 4);
    let per = if with_exact { 2 } else { 1 };
    let grid = root.split_evenly((per * n.div_ceil(4).max(1), cols));
    let t_max = *plan.times.last().expect("times");
    let t_min = if log_t {
        plan.times[0]
    } else if plan.times.len() > 1 {
        0.0
    } else {
        t_max * 0.5
    };
    let (x_min, x_max) = if t_min < t_max {
        (tx(t_min), tx(t_max))
    } else {
        (tx(t_max) - 0.5, tx(t_max) + 0.5)
    };
    let x_label = time_label(plan);
    let x_tick = |v: &f64| {
        if log_t {
            log_tick(*v)
        } else {
            tick(*v, x_max - x_min)
        }
    };
    for (j, o) in plan.observables.iter().enumerate() {
        // observable j: block j / 4 of `per` panel rows, column j % 4
        let (block, col) = (j / 4, j % 4);
        let value_panel = block * per * cols + col;
        let color = COLORS[j % COLORS.len()];
        let name = o.name();
        let pts: Vec<(f64, f64, f64, f64)> = data
            .iter()
            .map(|r| (r.t, r.cells[j].0, r.cells[j].1, r.cells[j].2))
            .collect();
        let has_band = pts.iter().any(|p| p.2.is_finite());
        let raw = pts.clone();
        // exact curve on a fine grid where known
        let exact_at = |t: f64| plan.exact.and_then(|e| e.value(o, t));
        let fine: Vec<(f64, f64)> = (0..=300)
            .map(|i| {
                let f = f64::from(i) / 300.0;
                if log_t {
                    t_min * (t_max / t_min).powf(f)
                } else {
                    t_min + (t_max - t_min) * f
                }
            })
            .filter_map(|t| exact_at(t).filter(|v| v.is_finite()).map(|v| (t, v)))
            .collect();
        // a log value axis where asked for and the values are > 0 and span decades
        let positive = pts.iter().all(|p| p.1 > 0.0) && fine.iter().all(|p| p.1 > 0.0);
        let (vlo, vhi) = pts
            .iter()
            .map(|p| p.1)
            .chain(fine.iter().map(|p| p.1))
            .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(v), a.1.max(v)));
        let log_y = plan.log_axes && positive && vhi > 100.0 * vlo;
        let ty = |v: f64| if log_y { v.log10() } else { v };
        let pts: Vec<(f64, f64, f64, f64)> = pts
            .iter()
            .map(|p| {
                if log_y {
                    // the band as log10 of the interval's ends (its lower end kept > 0)
                    let lo = (p.1 - p.2).max(p.1 * 1e-3);
                    (
                        tx(p.0),
                        p.1.log10(),
                        (p.1 + p.2).log10() - p.1.log10(),
                        lo.log10() - p.1.log10(),
                    )
                } else {
                    (tx(p.0), p.1, p.2, -p.2)
                }
            })
            .collect();
        let fine: Vec<(f64, f64)> = fine.iter().map(|p| (tx(p.0), ty(p.1))).collect();
        let (ylo, yhi) = span(
            pts.iter()
                .flat_map(|p| {
                    let (up, down) = if p.2.is_finite() {
                        (p.2, p.3)
                    } else {
                        (0.0, 0.0)
                    };
                    [p.1 + down, p.1 + up]
                })
                .chain(fine.iter().map(|p| p.1)),
        );
        let mut chart = ChartBuilder::on(&grid[value_panel])
            .caption(format!("{name}(t)"), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(x_min..x_max, ylo..yhi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label.as_str())
            .y_desc(value_label(plan, o))
            .x_label_formatter(&x_tick)
            .y_label_formatter(&|v| axis_tick(log_y, *v, yhi - ylo))
            .draw()
            .map_err(err)?;
        if has_band {
            let band: Vec<(f64, f64)> = pts
                .iter()
                .map(|p| (p.0, p.1 + p.2))
                .chain(pts.iter().rev().map(|p| (p.0, p.1 + p.3)))
                .collect();
            chart
                .draw_series(std::iter::once(Polygon::new(
                    band,
                    color.mix(0.25).filled(),
                )))
                .map_err(err)?
                .label("95% CI of the mean")
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 4), (x + 18, y + 4)], color.mix(0.25).filled())
                });
        }
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.1)),
                color.stroke_width(2),
            ))
            .map_err(err)?
            .label(if plan.replicas > 1 {
                format!("mean of {} replicas", plan.replicas)
            } else {
                "simulation".to_string()
            })
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        if !fine.is_empty() {
            chart
                .draw_series(DashedLineSeries::new(
                    fine.clone(),
                    6,
                    4,
                    BLACK.stroke_width(1),
                ))
                .map_err(err)?
                .label("exact")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(err)?;

        if with_exact {
            // relative errors, so that growing and decaying observables read alike
            let errs: Vec<(f64, f64, f64)> = raw
                .iter()
                .filter(|p| p.3.is_finite() && p.3 != 0.0)
                .map(|p| (tx(p.0), (p.1 - p.3) / p.3.abs(), p.2 / p.3.abs()))
                .collect();
            let (elo, ehi) = span(
                errs.iter()
                    .flat_map(|e| {
                        let h = if e.2.is_finite() { e.2 } else { 0.0 };
                        [e.1 - h, e.1 + h]
                    })
                    .chain([0.0]),
            );
            let mut chart = ChartBuilder::on(&grid[value_panel + cols])
                .caption(
                    format!("{name}: (ours − exact) / exact"),
                    ("sans-serif", 18),
                )
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(80)
                .build_cartesian_2d(x_min..x_max, elo..ehi)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(x_label.as_str())
                .y_desc("relative error")
                .x_label_formatter(&x_tick)
                .y_label_formatter(&|v| tick(*v, ehi - elo))
                .draw()
                .map_err(err)?;
            if errs.iter().any(|e| e.2.is_finite()) {
                let band: Vec<(f64, f64)> = errs
                    .iter()
                    .map(|e| (e.0, e.1 + e.2))
                    .chain(errs.iter().rev().map(|e| (e.0, e.1 - e.2)))
                    .collect();
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        band,
                        color.mix(0.25).filled(),
                    )))
                    .map_err(err)?;
            }
            chart
                .draw_series(LineSeries::new(
                    errs.iter().map(|e| (e.0, e.1)),
                    color.stroke_width(2),
                ))
                .map_err(err)?;
            chart
                .draw_series(LineSeries::new(
                    [(x_min, 0.0), (x_max, 0.0)],
                    BLACK.stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    Ok(())
}
