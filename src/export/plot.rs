//! Convergence plots (SVG, plotters): best reachability and best cost against time.

use crate::optimize::output::HistoryRow;
use plotters::prelude::*;

/// An SVG with two panels sharing the time axis: best `R` (top) and best cost (bottom).
pub fn convergence_svg(title: &str, history: &[HistoryRow]) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 640)).into_drawing_area();
        root.fill(&WHITE).expect("drawing on a string cannot fail");
        let root = root
            .titled(title, ("sans-serif", 22))
            .expect("drawing on a string cannot fail");
        let (top, bottom) = root.split_vertically(300);
        let t_max = history.last().map_or(1.0, |r| r.elapsed_s).max(1e-3);
        let series = |f: fn(&HistoryRow) -> f64| -> Vec<(f64, f64)> {
            history.iter().map(|r| (r.elapsed_s, f(r))).collect()
        };
        let mut r_chart = ChartBuilder::on(&top)
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..t_max, 0.0..1.05)
            .expect("chart");
        r_chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("best R")
            .draw()
            .expect("mesh");
        r_chart
            .draw_series(LineSeries::new(series(|r| r.best_reachability), &BLUE))
            .expect("series");
        let costs = series(|r| r.best_cost);
        let finite: Vec<f64> = costs
            .iter()
            .map(|c| c.1)
            .filter(|c| c.is_finite())
            .collect();
        let (lo, hi) = finite
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &c| {
                (a.min(c), b.max(c))
            });
        let (lo, hi) = if lo.is_finite() && hi > lo {
            (lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
        } else if lo.is_finite() {
            (lo - 1.0, lo + 1.0)
        } else {
            (0.0, 1.0)
        };
        let mut c_chart = ChartBuilder::on(&bottom)
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..t_max, lo..hi)
            .expect("chart");
        c_chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("best cost (Eq. 23)")
            .draw()
            .expect("mesh");
        c_chart
            .draw_series(LineSeries::new(costs, &RED))
            .expect("series");
        root.present().expect("present");
    }
    svg
}
