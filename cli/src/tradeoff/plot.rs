//! Accuracy against time as an SVG: one curve per model and weight precision, a point per
//! step count; x is the time of a direction and its PDF over the material's own sample,
//! y the mean relative variance. The material's own sampler sits at x = 1 (open circle).

use super::markdown::curves;
use super::sweep::Point;
use plotters::prelude::*;
use std::path::Path;

fn bounds(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    if lo.is_finite() {
        (lo / 1.5, hi * 1.5)
    } else {
        (0.1, 10.0)
    }
}

/// Writes the plot of `points` to `path`.
pub fn write_svg(points: &[Point], path: &Path, title: &str) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let (x0, x1) = bounds(
        points
            .iter()
            .map(|p| p.cost.ratio_sample)
            .chain(std::iter::once(1.0)),
    );
    let (y0, y1) = bounds(points.iter().flat_map(|p| [p.rv_mean, p.material_rv_mean]));
    let root = SVGBackend::new(path, (1100, 720)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("time of a direction + PDF / time of the material's own sample")
        .y_desc("mean relative variance RV over the wi grid")
        .draw()
        .map_err(|e| err(&e))?;
    let cs = curves(points);
    let mut models: Vec<&str> = cs.iter().map(|c| c[0].model.as_str()).collect();
    models.dedup();
    for c in &cs {
        let k = models.iter().position(|m| *m == c[0].model).unwrap_or(0);
        let color = Palette99::pick(k).to_rgba();
        let half = c[0].precision == "f16";
        let xy: Vec<(f64, f64)> = c
            .iter()
            .filter(|p| p.rv_mean.is_finite() && p.rv_mean > 0.0)
            .map(|p| (p.cost.ratio_sample, p.rv_mean))
            .collect();
        let style = color.stroke_width(if half { 1 } else { 2 });
        let label = format!("{} ({})", c[0].model, c[0].precision);
        chart
            .draw_series(LineSeries::new(xy.clone(), style))
            .map_err(|e| err(&e))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        if half {
            chart
                .draw_series(
                    xy.iter()
                        .map(|&p| TriangleMarker::new(p, 4, color.filled())),
                )
                .map_err(|e| err(&e))?;
        } else {
            chart
                .draw_series(xy.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| err(&e))?;
            // Step counts beside the f32 points, and the material's sampler at x = 1.
            chart
                .draw_series(c.iter().filter(|p| p.rv_mean.is_finite()).map(|p| {
                    Text::new(
                        format!("{}", p.steps),
                        (p.cost.ratio_sample, p.rv_mean),
                        ("sans-serif", 11).into_font().color(&color),
                    )
                }))
                .map_err(|e| err(&e))?;
            chart
                .draw_series(std::iter::once(Circle::new(
                    (1.0, c[0].material_rv_mean),
                    5,
                    color.stroke_width(2),
                )))
                .map_err(|e| err(&e))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}
