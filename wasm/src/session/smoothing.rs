//! A session's smoother: each method's fixed-interval smoothed track once the run is done.

use crate::{js_error, to_js};
use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::Session;

/// What [`Session::smooth`] returns.
#[derive(Serialize)]
struct SmoothedRun {
    rows: usize,
    grid: Vec<f64>,
    methods: Vec<SmoothedMethod>,
    densities: Option<Vec<Option<f64>>>,
}

/// One method's smoothed track for the page.
#[derive(Serialize)]
struct SmoothedMethod {
    smoother: Option<String>,
    failure: Option<String>,
    estimates: Vec<Option<f64>>,
    sds: Vec<Option<f64>>,
    mse: Option<f64>,
    notes: Vec<String>,
}

#[wasm_bindgen]
impl Session {
    /// Every method's fixed-interval smoother over the rows processed so far (the filters run
    /// again as their smoothers' forward passes, then backward): `{rows, grid, methods:
    /// [{smoother, failure, estimates, sds, mse, notes}], densities}` with the smoothed means
    /// and standard deviations row-major (n per row, null where there are none), and for
    /// method `density_method` its smoothed marginal density of component `dim` on
    /// [`Session::density_grid`] at every row (`rows × points`; the grid smoother's own density,
    /// else the Gaussian of its smoothed moments).
    pub fn smooth(
        &self,
        density_method: usize,
        dim: usize,
        points: usize,
    ) -> Result<JsValue, JsError> {
        let rows = self.run.position();
        let recording = self.run.recording().first_rows(rows);
        let grid = self.density_grid(dim, points);
        let mut densities = vec![f64::NAN; rows * grid.len()];
        let mut out = vec![0.0; grid.len()];
        let result = self
            .experiment
            .smooth_recorded_with(recording, self.seed, &mut |method, row, step| {
                if method != density_method || row >= rows || dim >= step.estimate.mean.len() {
                    return;
                }
                step.marginal_density(dim, &grid, &mut out);
                densities[row * grid.len()..(row + 1) * grid.len()].copy_from_slice(&out);
            })
            .map_err(js_error)?;
        let finite = |v: &f64| v.is_finite().then_some(*v);
        let truth = result.recording.truth.as_deref();
        let methods: Vec<SmoothedMethod> = result
            .methods
            .iter()
            .map(|track| {
                let s = track.smoothed.clone().unwrap_or_default();
                let n = track.n;
                let sds = s
                    .covariances
                    .chunks_exact(n * n)
                    .flat_map(|p| (0..n).map(move |i| p[i * n + i].max(0.0).sqrt()))
                    .map(|v| finite(&v))
                    .collect();
                SmoothedMethod {
                    mse: truth.and_then(|t| s.mse(t, n)),
                    estimates: s.estimates.iter().map(finite).collect(),
                    sds,
                    smoother: s.smoother,
                    failure: s.failure,
                    notes: s.notes,
                }
            })
            .collect();
        let has = densities.iter().any(|v| v.is_finite());
        to_js(&SmoothedRun {
            rows,
            grid,
            methods,
            densities: has.then(|| densities.iter().map(finite).collect()),
        })
    }
}
