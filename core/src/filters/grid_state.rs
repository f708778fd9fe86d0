//! A grid filter's density between steps: normalised to unit mass with its estimate read off
//! ([`normalise_on_grid`]), and kept before each step so that a failed step leaves the filter
//! as it was ([`SavedDensity`]).

use alloc::vec::Vec;

use super::Estimate;

/// The state a grid filter's step starts from — its density and estimate —, kept so that a
/// step that fails can be undone (the [`Filter`](super::Filter) contract): one copy of the density per step,
/// into storage made once.
#[derive(Clone, Debug)]
pub(crate) struct SavedDensity {
    u: Vec<f64>,
    estimate: Estimate,
}

impl SavedDensity {
    /// Storage for a density of `len` values and an estimate like `estimate`.
    pub(crate) fn new(len: usize, estimate: &Estimate) -> Self {
        SavedDensity {
            u: alloc::vec![0.0; len],
            estimate: estimate.clone(),
        }
    }

    /// Keeps `u` and `estimate`.
    pub(crate) fn save(&mut self, u: &[f64], estimate: &Estimate) {
        self.u.copy_from_slice(u);
        self.estimate.copy_from(estimate);
    }

    /// Puts back what [`SavedDensity::save`] kept.
    pub(crate) fn restore(&self, u: &mut [f64], estimate: &mut Estimate) {
        u.copy_from_slice(&self.u);
        estimate.copy_from(&self.estimate);
    }

    /// Ends a step that returned `result` (its log-likelihood, or why it failed): a success
    /// records the log-likelihood, a failure puts back what [`SavedDensity::save`] kept and
    /// leaves the last log-likelihood.
    pub(crate) fn settle(
        &self,
        result: Result<f64, crate::error::FilterError>,
        u: &mut [f64],
        estimate: &mut Estimate,
        log_likelihood: &mut f64,
    ) -> Result<(), crate::error::FilterError> {
        match result {
            Ok(ll) => {
                *log_likelihood = ll;
                Ok(())
            }
            Err(e) => {
                self.restore(u, estimate);
                Err(e)
            }
        }
    }
}
/// Normalises a grid density to unit mass in place and writes its estimate (mean,
/// covariance, MAP node) into `estimate`, through `moments` (storage of the grid's dimension,
/// so that nothing is allocated once the estimate has its covariance and MAP); a non-finite or
/// vanished mass is an error, never NaN, and leaves `estimate` as it was.
pub(crate) fn normalise_on_grid(
    grid: &crate::grid::TensorGrid,
    u: &mut [f64],
    moments: &mut crate::grid::Moments,
    estimate: &mut Estimate,
) -> Result<(), crate::error::FilterError> {
    grid.moments_into(u, moments);
    if !moments.mass.is_finite() {
        return Err(crate::error::FilterError::NonFinite { what: "density" });
    }
    if moments.mass <= 0.0 {
        return Err(crate::error::FilterError::MassLost);
    }
    let inv = 1.0 / moments.mass;
    u.iter_mut().for_each(|v| *v *= inv);
    estimate.mean.copy_from(&moments.mean);
    match &mut estimate.covariance {
        Some(c) => c.copy_from(&moments.covariance),
        none => *none = Some(moments.covariance.clone()),
    }
    match &mut estimate.map {
        Some(m) => m.copy_from(&moments.map),
        none => *none = Some(moments.map.clone()),
    }
    Ok(())
}

/// The prior σ₀ on `grid`'s nodes, normalised, with its moments and estimate (a density that
/// is not finite on the grid, or has no mass there, is an error): where a grid filter starts.
pub(crate) fn prior_on_grid(
    grid: &crate::grid::TensorGrid,
    prior: &crate::model::Prior,
) -> Result<(Vec<f64>, crate::grid::Moments, Estimate), crate::error::FilterError> {
    let n = grid.dim();
    let mut u = grid.tabulate(|x| prior.density(x));
    if u.iter().any(|v| !v.is_finite()) {
        return Err(crate::error::FilterError::NonFinite {
            what: "prior density",
        });
    }
    let mut moments = crate::grid::Moments::zeros(n);
    let mut estimate = Estimate {
        mean: nalgebra::DVector::zeros(n),
        covariance: None,
        map: None,
    };
    normalise_on_grid(grid, &mut u, &mut moments, &mut estimate)?;
    Ok((u, moments, estimate))
}

/// A measurement's density on a grid's nodes: `p(z | x)` and h tabulated once (m values
/// per node).
#[derive(Clone, Debug)]
pub(crate) struct GridMeasurement {
    pub(crate) likelihood: super::MeasurementLikelihood,
    /// h at the nodes, row per node.
    pub(crate) h_nodes: Vec<f64>,
    pub(crate) m: usize,
    /// A chunk of [`BATCH`] nodes with positive density, for the families the likelihood
    /// evaluates as a batch ([`super::MeasurementLikelihood::add_batch`]): their indices,
    /// coordinates and h (structure of arrays) and log-likelihoods; grown on first use.
    chunk: (Vec<usize>, Vec<f64>, Vec<f64>, Vec<f64>),
    scratch: crate::model::BatchScratch,
}

/// Nodes per batch of the likelihood on a grid (a few kB of coordinates per chunk, whatever
/// the grid's size).
const BATCH: usize = 256;

impl GridMeasurement {
    /// The density `noise` of the model `measurement` (whose h is tabulated) on `grid`.
    pub(crate) fn new(
        grid: &crate::grid::TensorGrid,
        measurement: &crate::model::Model,
        noise: &crate::model::MeasurementDensity,
    ) -> Self {
        let mut made = GridMeasurement {
            likelihood: super::MeasurementLikelihood::new(noise, measurement.m),
            h_nodes: Vec::with_capacity(grid.len() * measurement.m),
            m: measurement.m,
            chunk: Default::default(),
            scratch: Default::default(),
        };
        made.tabulate(grid, measurement);
        made
    }

    /// The same storage for another measurement of as many components (a driven model's,
    /// frozen for the next step): h tabulated again, the density replaced.
    pub(crate) fn refresh(
        &mut self,
        grid: &crate::grid::TensorGrid,
        measurement: &crate::model::Model,
        noise: &crate::model::MeasurementDensity,
    ) {
        self.likelihood.set_density(noise);
        self.tabulate(grid, measurement);
    }

    /// h at every node of `grid`, a row per node.
    fn tabulate(&mut self, grid: &crate::grid::TensorGrid, measurement: &crate::model::Model) {
        let h_nodes = &mut self.h_nodes;
        h_nodes.clear();
        let mut hx = alloc::vec![0.0; self.m];
        grid.for_each_node(|_, x| {
            measurement.observation.eval(x, &mut hx);
            h_nodes.extend_from_slice(&hx);
        });
    }

    /// `log[i] = ln p(z | x_i)` at the nodes `chunk.0` (their coordinates and h gathered
    /// into the chunk), as a batch (for a family that [`super::MeasurementLikelihood::batches`]).
    fn chunk_log_likelihoods(
        &mut self,
        grid: &crate::grid::TensorGrid,
        node: &mut [f64],
        z: &[f64],
    ) -> Result<(), crate::error::FilterError> {
        let (n, m) = (grid.dim(), self.m);
        let (indices, points, h, out) = &mut self.chunk;
        let count = indices.len();
        points.resize(n * count, 0.0);
        h.resize(m * count, 0.0);
        for (i, &idx) in indices.iter().enumerate() {
            grid.node(idx, node);
            for (j, x) in node.iter().enumerate() {
                points[j * count + i] = *x;
            }
            for j in 0..m {
                h[j * count + i] = self.h_nodes[idx * m + j];
            }
        }
        out.clear();
        out.resize(count, 0.0);
        let batched = self
            .likelihood
            .add_batch(z, (points, h, count), out, &mut self.scratch)?;
        debug_assert!(batched, "called for a family with a batch only");
        Ok(())
    }

    /// Bayes' rule on the nodes (001 (6)): `u ← u · p(z | x)` for the observed components of
    /// `z` (NaN = missing), in the log domain so that a sharp likelihood cannot underflow the
    /// whole grid, and rescaled by its largest value; `log` and `node` are storage (a value per
    /// node, a point). Returns the log of what the rescaling and the predicted mass took away:
    /// after the caller normalises to `mass`, the step's log-likelihood
    /// `ln p(z | past)` is `ln mass + ` this.
    pub(crate) fn multiply(
        &mut self,
        grid: &crate::grid::TensorGrid,
        (u, log): (&mut [f64], &mut [f64]),
        node: &mut [f64],
        z: &[f64],
    ) -> Result<f64, crate::error::FilterError> {
        // The update keeps only the positive values (a negative one becomes 0).
        let before = grid.positive_mass(u);
        let m = self.m;
        let reads_state = self.likelihood.reads_state();
        // ln u in one pass (−∞ where u ≤ 0), each node's log-likelihood added to it.
        logs_of_positive(u, log);
        if self.likelihood.batches() {
            // As a batch, in chunks of the nodes with positive density.
            let mut start = 0;
            while start < u.len() {
                self.chunk.0.clear();
                let mut end = start;
                while end < u.len() && self.chunk.0.len() < BATCH {
                    if u[end] > 0.0 {
                        self.chunk.0.push(end);
                    }
                    end += 1;
                }
                self.chunk_log_likelihoods(grid, node, z)?;
                for (&idx, l) in self.chunk.0.iter().zip(&self.chunk.3) {
                    log[idx] += l;
                }
                start = end;
            }
        } else {
            for (idx, (u, log)) in u.iter().zip(log.iter_mut()).enumerate() {
                if *u > 0.0 {
                    let h = &self.h_nodes[idx * m..(idx + 1) * m];
                    if reads_state {
                        grid.node(idx, node);
                    }
                    *log += self.likelihood.log_at(z, node, h)?;
                }
            }
        }
        let max = crate::linalg::largest_in_lanes(log);
        if max == f64::NEG_INFINITY || max.is_nan() {
            return Err(crate::error::FilterError::MassLost);
        }
        exps_shifted(log, max, u);
        Ok(max - libm::log(before))
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `log_i ← ln u_i`, −∞ where `u_i ≤ 0` (the update keeps only the positive values).
    fn logs_of_positive(u: &[f64], log: &mut [f64]) {
        for (l, &u) in log.iter_mut().zip(u) {
            let value = crate::linalg::elementary::ln(u);
            *l = if u > 0.0 { value } else { f64::NEG_INFINITY };
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `u_i ← e^(log_i − shift)`.
    fn exps_shifted(log: &[f64], shift: f64, u: &mut [f64]) {
        for (u, l) in u.iter_mut().zip(log) {
            *u = crate::linalg::elementary::exp(l - shift);
        }
    }
}

/// The [`Filter`](super::Filter) accessors of a filter that keeps its `name`, its last step's
/// `log_likelihood` and its `estimate` in fields of those names (the grid and spectral
/// filters), expanded inside its `impl Filter`; with `density in u`, also its density on
/// `self.grid` held in `self.u`, and its marginals.
macro_rules! kept_estimate_accessors {
    () => {
        fn name(&self) -> &str {
            &self.name
        }

        fn log_likelihood(&self) -> Option<f64> {
            Some(self.log_likelihood)
        }

        fn estimate(&self) -> crate::filters::Estimate {
            self.estimate.clone()
        }

        fn estimate_into(&self, out: &mut crate::filters::Estimate) {
            out.copy_from(&self.estimate);
        }
    };
    (density in $u:ident) => {
        crate::filters::kept_estimate_accessors!();

        fn density(&self) -> Option<crate::filters::DensityView<'_>> {
            Some(self.grid.view(&self.$u))
        }

        fn state_law(
            &self,
        ) -> Result<crate::filters::predictive::StateLaw, crate::error::FilterError> {
            crate::filters::predictive::StateLaw::of_grid(&self.grid.view(&self.$u))
        }

        fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
            self.grid.marginal(&self.$u, dim, grid, out);
        }
    };
}
pub(crate) use kept_estimate_accessors;
