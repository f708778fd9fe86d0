//! The log-likelihood profiles as an SVG plot (plotters, the frontier's palette): ln L against
//! the parameter, one line per method, each maximum marked with a dot and a dashed drop line.

use std::path::Path;

use plotters::prelude::*;
use zakai::lab::fit::Profile;

use crate::frontier_plot::PALETTE;

/// Draws `profiles` (of one parameter, at the same values) into the SVG file `path`; ln L is
/// shown down to 20 below the highest maximum (lower values on the bottom edge). `refitted`
/// names the parameters maximised over at each value (empty: a slice, the others held).
pub fn draw(
    profiles: &[Profile],
    refitted: &[String],
    title: &str,
    path: &Path,
) -> Result<(), String> {
    let y_label = if refitted.is_empty() {
        String::from("ln L (the others at their values); below max − 20: on the bottom edge")
    } else {
        format!(
            "max over {} of ln L; below max − 20: on the bottom edge",
            refitted.join(", ")
        )
    };
    let err = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    let Some(first) = profiles.first() else {
        return Err(format!("nothing to plot in {}", path.display()));
    };
    let (x0, x1) = (
        first.values[0],
        *first.values.last().unwrap_or(&first.values[0]),
    );
    let top = profiles
        .iter()
        .filter_map(|p| p.maximum.map(|m| m.1))
        .fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() || x1 <= x0 {
        return Err(format!(
            "nothing to plot in {}: every method failed",
            path.display()
        ));
    }
    let bottom = top - 20.0;
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{title}: log-likelihood along {}", first.parameter),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, bottom..(top + 2.0))
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(first.parameter.as_str())
        .y_desc(y_label)
        .draw()
        .map_err(|e| err(&e))?;
    for (i, p) in profiles.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let line: Vec<(f64, f64)> = p
            .values
            .iter()
            .zip(&p.log_likelihoods)
            .filter(|(_, l)| l.is_finite())
            .map(|(&x, &l)| (x, l.max(bottom)))
            .collect();
        chart
            .draw_series(LineSeries::new(line, colour.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(match p.maximum {
                Some((x, _)) => format!("{}: maximum at {x:.4}", p.method),
                None => format!("{}: failed", p.method),
            })
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        if let Some((x, l)) = p.maximum {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(x, bottom), (x, l)],
                    5,
                    4,
                    colour.stroke_width(1),
                ))
                .map_err(|e| err(&e))?;
            chart
                .draw_series(std::iter::once(Circle::new((x, l), 5, colour.filled())))
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
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
