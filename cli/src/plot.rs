//! Plots (plotters): drawn as SVG, which needs no font files; a `.png` is that SVG
//! rasterised by resvg with the system's fonts (text is left out where none is found).

use crate::output::rows;
use crate::runner::Outcome;
use crate::scenario::Plan;
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
    let size = (
        520 * cols + 40,
        blocks * if with_exact { 780 } else { 440 } + 40,
    );
    render(path, size, |root| draw_run(root, plan, out, with_exact))
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
    root: DrawingArea<DB, Shift>,
    plan: &Plan,
    out: &Outcome,
    with_exact: bool,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(&plan.title, ("sans-serif", 22)).map_err(err)?;
    let data = rows(plan, out);
    let n = plan.observables.len();
    let cols = n.clamp(1, 4);
    let per = if with_exact { 2 } else { 1 };
    let grid = root.split_evenly((per * n.div_ceil(4).max(1), cols));
    let t_max = *plan.times.last().expect("times");
    let t_min = if plan.times.len() > 1 {
        0.0
    } else {
        t_max * 0.5
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
        // exact curve on a fine grid where known
        let exact_at = |t: f64| plan.exact.and_then(|e| e.value(o, t));
        let fine: Vec<(f64, f64)> = (0..=300)
            .map(|i| t_min + (t_max - t_min) * f64::from(i) / 300.0)
            .filter_map(|t| exact_at(t).filter(|v| v.is_finite()).map(|v| (t, v)))
            .collect();
        let (ylo, yhi) = span(
            pts.iter()
                .flat_map(|p| {
                    let h = if p.2.is_finite() { p.2 } else { 0.0 };
                    [p.1 - h, p.1 + h]
                })
                .chain(fine.iter().map(|p| p.1)),
        );
        let mut chart = ChartBuilder::on(&grid[value_panel])
            .caption(format!("{name}(t)"), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(35)
            .y_label_area_size(70)
            .build_cartesian_2d(t_min..t_max, ylo..yhi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("t")
            .y_label_formatter(&|v| tick(*v, yhi - ylo))
            .draw()
            .map_err(err)?;
        if has_band {
            let band: Vec<(f64, f64)> = pts
                .iter()
                .map(|p| (p.0, p.1 + p.2))
                .chain(pts.iter().rev().map(|p| (p.0, p.1 - p.2)))
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
            let errs: Vec<(f64, f64, f64)> = pts
                .iter()
                .filter(|p| p.3.is_finite() && p.3 != 0.0)
                .map(|p| (p.0, (p.1 - p.3) / p.3.abs(), p.2 / p.3.abs()))
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
                .x_label_area_size(35)
                .y_label_area_size(70)
                .build_cartesian_2d(t_min..t_max, elo..ehi)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("t")
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
                    [(t_min, 0.0), (t_max, 0.0)],
                    BLACK.stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
