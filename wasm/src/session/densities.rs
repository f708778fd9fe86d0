//! A session's densities for the plots: marginals on a grid, the two halves of the next step,
//! 2-D marginals and log-concavity maps.

use crate::to_js;
use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::Session;

/// The two halves of the next step ([`Session::preview`]).
#[derive(Serialize)]
struct Preview {
    t: f64,
    dt: f64,
    predicted: Vec<Vec<f64>>,
    likelihood: Option<Vec<f64>>,
}

#[wasm_bindgen]
impl Session {
    /// `points` equally spaced points over the domain of component `dim`.
    #[wasm_bindgen(js_name = densityGrid)]
    pub fn density_grid(&self, dim: usize, points: usize) -> Vec<f64> {
        let domain = &self.experiment.config().domain;
        let Some([lo, hi]) = domain.get(dim).copied() else {
            return Vec::new();
        };
        let points = points.clamp(2, 4096);
        (0..points)
            .map(|i| lo + (hi - lo) * i as f64 / (points - 1) as f64)
            .collect()
    }

    /// Method `index`'s current marginal density of component `dim` on
    /// [`Session::density_grid`] (empty once the method has failed, unless the failure left
    /// its state intact and the session follows it: then its density is drawn on).
    pub fn density(&self, index: usize, dim: usize, points: usize) -> Vec<f64> {
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Vec::new();
        };
        if !track.has_state() || dim >= track.n {
            return Vec::new();
        }
        let grid = self.density_grid(dim, points);
        let mut out = vec![0.0; grid.len()];
        filter.marginal_density(dim, &grid, &mut out);
        out
    }

    /// The next step in two halves, without moving the run: every method's density of
    /// component `dim` on [`Session::density_grid`] after the predict half (a fork of each
    /// filter predicted to the next observation time; empty for a failed method or a failed
    /// prediction), and, for a 1-D model, the likelihood of the next observation on the same
    /// grid scaled to a maximum of 1 (what multiplies the prediction into the posterior; null
    /// in more dimensions or with a component missing). `{t, dt, predicted, likelihood}`, or
    /// null when there is no next step.
    pub fn preview(&self, dim: usize, points: usize) -> Result<JsValue, JsError> {
        let Some(obs) = self.run.next_observation() else {
            return Ok(JsValue::NULL);
        };
        let grid = self.density_grid(dim, points);
        let predicted: Vec<Vec<f64>> = self
            .run
            .filters()
            .iter()
            .zip(self.run.tracks())
            .map(|(filter, track)| {
                if !track.has_state() || dim >= track.n {
                    return Vec::new();
                }
                let mut ahead = filter.fork();
                if ahead.step(&obs.predicting()).is_err() {
                    return Vec::new();
                }
                let mut out = vec![0.0; grid.len()];
                ahead.marginal_density(dim, &grid, &mut out);
                out
            })
            .collect();
        let model = self.experiment.model();
        let likelihood = (model.n == 1)
            .then(|| {
                let states: Vec<Vec<f64>> = grid.iter().map(|&x| vec![x]).collect();
                zakai::observation_log_likelihoods(model, &states, &obs)
            })
            .flatten()
            .and_then(|log| {
                let top = log.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                top.is_finite()
                    .then(|| log.iter().map(|l| (l - top).exp()).collect::<Vec<f64>>())
            });
        let r = self.run.recording();
        let k = self.run.position();
        to_js(&Preview {
            t: r.times[k],
            dt: obs.dt,
            predicted,
            likelihood,
        })
    }

    /// Method `index`'s current joint (marginal) density of components `x` and `y` (from 0)
    /// on the raster `densityGrid(x, points) × densityGrid(y, points)` (component `x`
    /// fastest; empty for 1-D models, failed methods and a pair that is not two different
    /// components of the state).
    pub fn density2d(&self, index: usize, points: usize, x: usize, y: usize) -> Vec<f64> {
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Vec::new();
        };
        if !track.has_state() || x == y || x.max(y) >= track.n {
            return Vec::new();
        }
        let (xs, ys) = (self.density_grid(x, points), self.density_grid(y, points));
        let mut out = vec![0.0; xs.len() * ys.len()];
        filter.marginal_density_2d((x, y), &xs, &ys, &mut out);
        out
    }

    /// The smallest eigenvalue of ∇²(−log p) (003 §3) of [`Session::density2d`] at every
    /// raster point (NaN where the density is below `relative_floor` of its maximum or at the
    /// raster's edge): the log-concavity layer of the 2-D heatmap.
    #[wasm_bindgen(js_name = logConcavity2d)]
    pub fn log_concavity_2d(
        &self,
        index: usize,
        points: usize,
        x: usize,
        y: usize,
        relative_floor: f64,
    ) -> Vec<f64> {
        let values = self.density2d(index, points, x, y);
        if values.is_empty() {
            return Vec::new();
        }
        let (xs, ys) = (self.density_grid(x, points), self.density_grid(y, points));
        // The raster's points are the interior nodes of a grid one spacing wider.
        let bounds: Vec<(f64, f64)> = [&xs, &ys]
            .iter()
            .map(|g| {
                let h = g[1] - g[0];
                (g[0] - h, g[g.len() - 1] + h)
            })
            .collect();
        let shape = [xs.len(), ys.len()];
        let view = zakai::DensityView {
            bounds: &bounds,
            shape: &shape,
            values: &values,
        };
        let floor = if relative_floor.is_finite() && relative_floor >= 0.0 {
            relative_floor
        } else {
            1e-8
        };
        zakai::diagnostics::log_concavity::log_concavity(&view, floor, 1e-6)
            .map(|d| d.min_curvature)
            .unwrap_or_default()
    }

    /// Log-concavity of method `index`'s current grid density (003 §3): `{log_concave, worst:
    /// [point, value] | null, shape, min_curvature}` with `min_curvature` per grid node (null
    /// where the density is below `relative_floor` of its maximum), or `null` for methods
    /// without a grid density (or beyond 2-D).
    #[wasm_bindgen(js_name = logConcavity)]
    pub fn log_concavity(&self, index: usize, relative_floor: f64) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Map {
            log_concave: bool,
            worst: Option<(Vec<f64>, f64)>,
            shape: Vec<usize>,
            min_curvature: Vec<Option<f64>>,
        }
        let view = self
            .run
            .filters()
            .get(index)
            .filter(|_| !self.run.tracks()[index].failed())
            .and_then(|f| f.density());
        let floor = if relative_floor.is_finite() && relative_floor >= 0.0 {
            relative_floor
        } else {
            1e-8
        };
        let Some(view) = view else {
            return Ok(JsValue::NULL);
        };
        match zakai::diagnostics::log_concavity::log_concavity(&view, floor, 1e-6) {
            None => Ok(JsValue::NULL),
            Some(d) => to_js(&Map {
                log_concave: d.log_concave,
                worst: d.worst,
                shape: view.shape.to_vec(),
                min_curvature: d
                    .min_curvature
                    .iter()
                    .map(|v| v.is_finite().then_some(*v))
                    .collect(),
            }),
        }
    }
}
