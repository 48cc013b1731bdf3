//! SVG plots (text in SVG needs no font files, so the CLI stays self-contained).

use plotters::prelude::*;

fn err<E: std::fmt::Display>(e: E) -> String {
    format!("plot: {e}")
}

pub(crate) fn check_svg(path: &str) -> Result<(), String> {
    if path.ends_with(".svg") {
        Ok(())
    } else {
        Err(format!(
            "plot: {path}: only SVG output is supported (use a .svg file name)"
        ))
    }
}

/// M2 and M3 against time, simulation (points) and exact (lines).
pub fn moments(
    path: &str,
    traj: &[(f64, f64, f64)],
    exact: impl Fn(f64) -> (f64, f64),
) -> Result<(), String> {
    check_svg(path)?;
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    draw_moments(root, traj, exact)
}

fn draw_moments<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    traj: &[(f64, f64, f64)],
    exact: impl Fn(f64) -> (f64, f64),
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let t_max = traj.last().map_or(1.0, |p| p.0);
    let y_max = traj.iter().map(|p| p.2).fold(1.0, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Lécot et al. (2019): K = 1, F = 2/(x+y)",
            ("sans-serif", 22),
        )
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..t_max, 0.0..y_max)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("t")
        .y_desc("moment")
        .draw()
        .map_err(err)?;
    let n = 200;
    let grid: Vec<f64> = (0..=n)
        .map(|i| t_max * f64::from(i) / f64::from(n))
        .collect();
    chart
        .draw_series(LineSeries::new(
            grid.iter().map(|&t| (t, exact(t).0)),
            &BLUE,
        ))
        .map_err(err)?
        .label("M2 exact")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    chart
        .draw_series(LineSeries::new(grid.iter().map(|&t| (t, exact(t).1)), &RED))
        .map_err(err)?
        .label("M3 exact")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    chart
        .draw_series(
            traj.iter()
                .map(|p| Circle::new((p.0, p.1), 2, BLUE.filled())),
        )
        .map_err(err)?
        .label("M2 simulation")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
    chart
        .draw_series(
            traj.iter()
                .map(|p| Circle::new((p.0, p.2), 2, RED.filled())),
        )
        .map_err(err)?
        .label("M3 simulation")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Figure 2 of Lécot et al.: log2 of the mean error against log2 N, one curve per P,
/// QMC solid and MC dashed; M2 on the left, M3 on the right.
pub fn figure2(path: &str, cells: &[crate::lecot::Cell]) -> Result<(), String> {
    check_svg(path)?;
    let root = SVGBackend::new(path, (1400, 600)).into_drawing_area();
    draw_figure2(root, cells)
}

fn draw_figure2<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    cells: &[crate::lecot::Cell],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
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
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("log2 N")
            .y_desc("log2 error")
            .draw()
            .map_err(err)?;
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
                .map_err(err)?
                .label(format!("P = {p}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(DashedLineSeries::new(mc, 6, 4, c.stroke_width(1)))
                .map_err(err)?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
