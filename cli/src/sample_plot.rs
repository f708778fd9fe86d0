//! A posterior's draws as an SVG plot (plotters, the frontier's palette): for each
//! parameter a row with the chains' traces (left) and the marginal histogram of all draws as
//! a density, the prior's density drawn over it (right).

use std::path::Path;

use plotters::prelude::*;
use zakai::lab::posterior::Posterior;

use crate::frontier_plot::PALETTE;

/// Bins of each histogram.
const BINS: usize = 40;

/// Draws `posterior` into the SVG file `path`.
pub fn draw(posterior: &Posterior, title: &str, path: &Path) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    let p = posterior.names.len();
    let root = SVGBackend::new(path, (1000, 60 + 240 * p as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root
        .titled(
            &format!(
                "{title}: posterior under {} ({}, {} chains × {} draws)",
                posterior.method,
                posterior.sampler,
                posterior.chains.len(),
                posterior.draws
            ),
            ("sans-serif", 18),
        )
        .map_err(|e| err(&e))?;
    let panels = root.split_evenly((p, 2));
    for (i, name) in posterior.names.iter().enumerate() {
        let chains = posterior.values(i);
        let all: Vec<f64> = chains.iter().flatten().copied().collect();
        let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
        };
        // Traces.
        let mut trace = ChartBuilder::on(&panels[2 * i])
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..posterior.draws as f64, lo..hi)
            .map_err(|e| err(&e))?;
        trace
            .configure_mesh()
            .x_desc("draw")
            .y_desc(name.as_str())
            .draw()
            .map_err(|e| err(&e))?;
        for (c, values) in chains.iter().enumerate() {
            let colour = PALETTE[c % PALETTE.len()].mix(0.7);
            trace
                .draw_series(LineSeries::new(
                    values.iter().enumerate().map(|(d, &v)| (d as f64, v)),
                    colour.stroke_width(1),
                ))
                .map_err(|e| err(&e))?;
        }
        // Histogram as a density, and the prior.
        let width = (hi - lo) / BINS as f64;
        let mut counts = [0usize; BINS];
        for v in &all {
            counts[(((v - lo) / width) as usize).min(BINS - 1)] += 1;
        }
        let density: Vec<f64> = counts
            .iter()
            .map(|&k| k as f64 / (all.len() as f64 * width))
            .collect();
        let (prior, bounds) = (&posterior.priors[i], posterior.bounds[i]);
        let curve: Vec<(f64, f64)> = (0..=200)
            .map(|k| lo + (hi - lo) * k as f64 / 200.0)
            .map(|x| (x, prior.density(x, bounds)))
            .filter(|(_, y)| y.is_finite())
            .collect();
        let top = density
            .iter()
            .copied()
            .chain(curve.iter().map(|c| c.1))
            .fold(0.0, f64::max)
            * 1.1;
        let mut marginal = ChartBuilder::on(&panels[2 * i + 1])
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(lo..hi, 0.0..top.max(f64::MIN_POSITIVE))
            .map_err(|e| err(&e))?;
        marginal
            .configure_mesh()
            .x_desc(name.as_str())
            .y_desc("density")
            .draw()
            .map_err(|e| err(&e))?;
        marginal
            .draw_series(density.iter().enumerate().map(|(b, &d)| {
                let x0 = lo + b as f64 * width;
                Rectangle::new([(x0, 0.0), (x0 + width, d)], PALETTE[0].mix(0.45).filled())
            }))
            .map_err(|e| err(&e))?
            .label("posterior draws")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], PALETTE[0].filled()));
        marginal
            .draw_series(DashedLineSeries::new(curve, 6, 4, BLACK.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label("prior")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        marginal
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
