//! The frontier as an SVG plot (plotters): MSE against time per step on a log axis, every
//! setting as a dot, one line per method family through its best settings (each one more
//! accurate than every cheaper setting of the family: the family's own frontier), and the
//! optimal MSE as a dashed floor.

use std::path::Path;

use plotters::prelude::*;
use zakai::lab::study::frontier::Frontier;

pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(36, 80, 179),
    RGBColor(217, 72, 15),
    RGBColor(43, 138, 62),
    RGBColor(174, 62, 201),
    RGBColor(232, 89, 12),
    RGBColor(11, 114, 133),
    RGBColor(194, 37, 92),
    RGBColor(92, 148, 13),
    RGBColor(54, 79, 199),
    RGBColor(134, 46, 156),
];

/// Draws `f` into the SVG file `path`.
pub fn draw(f: &Frontier, title: &str, path: &Path) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    let usable: Vec<_> = f
        .points
        .iter()
        // Methods that failed in some runs are left out: their MSE covers the good runs only.
        .filter(|p| p.failed == 0)
        .filter_map(|p| Some((p, p.mse?)))
        .filter(|(p, m)| m.is_finite() && p.seconds_per_step > 0.0)
        .collect();
    let floor = f.floor.1;
    let (mut tmin, mut tmax) = (f64::INFINITY, 0.0f64);
    let (mut ymin, mut ymax) = (floor, floor);
    for (p, m) in &usable {
        tmin = tmin.min(p.seconds_per_step);
        tmax = tmax.max(p.seconds_per_step);
        ymin = ymin.min(*m);
        ymax = ymax.max(*m);
    }
    if f.floor_seconds_per_step > 0.0 {
        tmin = tmin.min(f.floor_seconds_per_step);
        tmax = tmax.max(f.floor_seconds_per_step);
    }
    if !(tmin.is_finite() && tmax > 0.0) {
        return Err(format!("nothing to plot in {}", path.display()));
    }
    // Up to 1.5× the floor, where the frontier is decided: settings further off are drawn at
    // the top edge.
    let ytop = ymax.min(1.5 * floor).max(floor * 1.1);
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{title}: MSE vs time per step ({} runs)", f.runs),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(
            ((tmin * 1e6 / 1.5)..(tmax * 1e6 * 1.5)).log_scale(),
            (ymin.min(floor) * 0.95)..ytop,
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("µs per observation interval (log scale)")
        .y_desc(format!(
            "MSE ({}, (43)); above 1.5× the optimum: on the top edge",
            zakai::lab::bibliography::cite("004")
        ))
        .draw()
        .map_err(|e| err(&e))?;
    let (x0, x1) = (tmin * 1e6 / 1.5, tmax * 1e6 * 1.5);
    chart
        .draw_series(DashedLineSeries::new(
            vec![(x0, floor), (x1, floor)],
            6,
            4,
            BLACK.stroke_width(2),
        ))
        .map_err(|e| err(&e))?
        .label(format!("optimal MSE {floor:.3} ({})", f.floor.0))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    let mut families: Vec<&str> = usable.iter().map(|(p, _)| p.sweep.family).collect();
    families.dedup();
    for (i, family) in families.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let mut pts: Vec<(f64, f64)> = usable
            .iter()
            .filter(|(p, _)| p.sweep.family == *family)
            .map(|(p, m)| (p.seconds_per_step * 1e6, *m))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best = f64::INFINITY;
        let envelope: Vec<(f64, f64)> = pts
            .iter()
            .filter(|&&(_, m)| {
                let better = m < best;
                best = best.min(m);
                better
            })
            .map(|&(t, m)| (t, m.min(ytop)))
            .collect();
        for p in &mut pts {
            p.1 = p.1.min(ytop);
        }
        chart
            .draw_series(LineSeries::new(envelope, colour.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(*family)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y)| Circle::new((x, y), 3, colour.filled())),
            )
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
