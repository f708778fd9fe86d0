//! The Gaussian-sum filter: the exact filtering density of a linear model with a
//! Gaussian-mixture prior and Gaussian-mixture measurement noise — the reference density of
//! 001 §4 (Šimandl & Švácha, 2002) against which J(t) is measured.
//!
//! Model: `dx = (A x + b) dt + G dw`, `z_k = C x_k + c + v_k`,
//! `p(v_k) = Σ_j β_j N(μ_j, R_j)`, `p(x_0) = Σ_i α_i N(m_i, P_i)`.
//!
//! * **Prediction**: every component exactly, `m ← Φ m + Γ b`, `P ← Φ P Φᵀ + Q_d` (Van Loan's
//!   discretisation, shared with the Kalman–Bucy filter).
//! * **Update**: every component i meets every noise component j:
//!   `S = C P_i Cᵀ + R_j`, `K = P_i Cᵀ S⁻¹`, `m_ij = m_i + K ν_ij` with
//!   `ν_ij = z − C m_i − c − μ_j`, `P_ij = P_i − K S Kᵀ`, `w_ij ∝ α_i β_j N(ν_ij; 0, S)`.
//! * **Mixture reduction**: the count grows by the factor J at every measurement, so
//!   components with relative weight below `prune` are dropped and pairs are merged
//!   (moment-preserving) in order of Runnalls' bound on the Kullback–Leibler discrepancy
//!   `B_ij = ½ [(w_i + w_j) log det P_ij − w_i log det P_i − w_j log det P_j]`, while
//!   `B ≤ merge_cost` or the count exceeds `max_components`. The largest cost accepted and the
//!   pruned weight are reported ([`GaussianSumFilter::reduction`]), so how exact the reference
//!   is stays visible; with no pruning or cap-forced merging the density is exact.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use serde::{Deserialize, Serialize};

use super::kalman::linear::{affine_parts, Discretization};
use super::method::{
    builder_fn, problems_from, BuildContext, Method, MethodInfo, ParamInfo, ParamKind,
    ProblemContext, Takes,
};
use super::{marginal, Estimate, Filter, Observation};
use crate::error::{FilterError, ZakaiError};
use crate::grid::TensorGrid;
use crate::linalg::{cholesky, gaussian_log_density, log_sum_exp, symmetrize};
use crate::model::{GaussianMixture, Model, ObservationModel, Prior};
use crate::validate::ConfigProblem;

/// Parameters of [`GaussianSumFilter`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaussianSumParams {
    /// Most components kept after a measurement.
    pub max_components: usize,
    /// Components whose weight is below `prune` times the largest weight are dropped.
    pub prune: f64,
    /// Pairs whose merging costs at most this (Runnalls' bound, nats) are always merged.
    pub merge_cost: f64,
}

impl Default for GaussianSumParams {
    fn default() -> Self {
        GaussianSumParams {
            max_components: 64,
            prune: 1e-12,
            merge_cost: 1e-10,
        }
    }
}

impl GaussianSumParams {
    /// Every problem with the parameters.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if !(1..=4096).contains(&self.max_components) {
            p.push((
                "max_components",
                format!("must be between 1 and 4096, got {}", self.max_components),
            ));
        }
        if !(0.0..1.0).contains(&self.prune) {
            p.push(("prune", "must be in [0, 1)".into()));
        }
        if !(self.merge_cost >= 0.0 && self.merge_cost.is_finite()) {
            p.push(("merge_cost", "must be nonnegative and finite".into()));
        }
        p
    }
}

/// The Gaussian-sum filter registered as a [`Method`].
pub struct GaussianSum;
builder_fn!(GaussianSum);

impl Method for GaussianSum {
    const KEY: &'static str = "gaussian_sum";
    const ALIASES: &'static [&'static str] = &["gsf"];
    type Params = GaussianSumParams;
    type Filter = GaussianSumFilter;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "GSF".into(),
            summary: "Gaussian-sum filter, exact for linear models with mixture prior and noise"
                .into(),
            paper: "Sorenson & Alspach (1971); the reference of 001 Šimandl & Švácha (2002), §4"
                .into(),
            takes: Takes::Measurements,
            dims: "any".into(),
            params: vec![
                ParamInfo::new(
                    "max_components",
                    ParamKind::Int,
                    "max components",
                    "most Gaussians kept after a measurement (pairs are merged beyond it)",
                )
                .range(1.0, 4096.0),
                ParamInfo::new(
                    "prune",
                    ParamKind::Number,
                    "prune below",
                    "drop components lighter than this fraction of the heaviest",
                )
                .range(0.0, 1.0),
                ParamInfo::new(
                    "merge_cost",
                    ParamKind::Number,
                    "merge cost (nats)",
                    "always merge pairs whose Runnalls bound on the KL discrepancy is below this",
                )
                .at_least(0.0),
            ],
            json_only: Vec::new(),
        }
    }
    fn display_name(_: &GaussianSumParams) -> String {
        "GSF".into()
    }
    fn problems(p: &GaussianSumParams, _: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems())
    }
    fn suitability(problem: &ProblemContext, _: &GaussianSumParams) -> Result<(), String> {
        check_model(problem.model, problem.prior, problem.probes)
            .map(|_| ())
            .map_err(|e| format!("{e}"))
    }
    fn memory(p: &GaussianSumParams, n: usize) -> Option<usize> {
        // Candidates after an update (noise mixtures of up to 4 components assumed) and their
        // pairwise merge costs.
        let k = p.max_components.checked_mul(4)?;
        let values = k
            .checked_mul(k)?
            .checked_add(k.checked_mul(n * n + n + 2)?)?;
        values.checked_mul(8)
    }
    fn build(
        ctx: &BuildContext,
        p: &GaussianSumParams,
        name: String,
    ) -> Result<GaussianSumFilter, ZakaiError> {
        GaussianSumFilter::new(name, ctx.model, ctx.prior, p, ctx.probes)
    }
}

/// One weighted Gaussian `w N(m, P)` with `log det P`.
#[derive(Clone, Debug)]
struct Component {
    w: f64,
    m: DVector<f64>,
    p: DMatrix<f64>,
    /// Cholesky factor of `p`, kept for evaluating the density.
    chol: Cholesky<f64, Dyn>,
    log_det: f64,
}

impl Component {
    fn new(w: f64, m: DVector<f64>, mut p: DMatrix<f64>) -> Result<Self, FilterError> {
        symmetrize(&mut p);
        let chol = cholesky(&p, "Gaussian-sum component covariance")?;
        let log_det = 2.0
            * chol
                .l_dirty()
                .diagonal()
                .iter()
                .map(|d| libm::log(*d))
                .sum::<f64>();
        Ok(Component {
            w,
            m,
            p,
            chol,
            log_det,
        })
    }
}

/// A model the Gaussian-sum filter fits: `dx = (A x + b) dt + G dw`, `z = C x + c + v`.
pub struct LinearMixtureModel<'p> {
    a: DMatrix<f64>,
    b: DVector<f64>,
    c: DMatrix<f64>,
    c0: DVector<f64>,
    noise: GaussianMixture,
    prior: &'p GaussianMixture,
}

/// The model's affine parts, noise and prior mixture when the filter fits it (linear,
/// discrete measurements, Gaussian-mixture prior), or why it does not fit.
pub fn check_model<'p>(
    model: &Model,
    prior: &'p Prior,
    probes: &[Vec<f64>],
) -> Result<LinearMixtureModel<'p>, FilterError> {
    let method = "the Gaussian-sum filter";
    let noise = match &model.observations {
        ObservationModel::Discrete { noise } => noise.clone(),
        ObservationModel::Continuous { .. } => {
            return Err(FilterError::Unsuitable(format!(
                "{method} of 001 needs discrete measurements z_k = C x_k + v_k; this model observes dy = h dt + dw"
            )))
        }
    };
    let (a, b) = affine_parts(&*model.drift, method, "drift f", probes)?;
    let (c, c0) = affine_parts(&*model.observation, method, "observation h", probes)?;
    let Prior::Mixture(mixture) = prior else {
        return Err(FilterError::Unsuitable(format!(
            "{method} needs a Gaussian or Gaussian-mixture prior, not a density expression"
        )));
    };
    Ok(LinearMixtureModel {
        a,
        b,
        c,
        c0,
        noise,
        prior: mixture,
    })
}

/// How far the reduction moved the mixture from the exact one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reduction {
    /// Largest Runnalls cost of a merge forced by the component cap (0: none forced).
    pub forced_cost: f64,
    /// Total weight dropped by pruning, summed over measurements.
    pub pruned_weight: f64,
}

/// The Gaussian-sum filter (see the module doc).
pub struct GaussianSumFilter {
    name: String,
    a: DMatrix<f64>,
    b: DVector<f64>,
    q: DMatrix<f64>,
    c: DMatrix<f64>,
    c0: DVector<f64>,
    noise: GaussianMixture,
    params: GaussianSumParams,
    components: Vec<Component>,
    cached: Option<Discretization>,
    reduction: Reduction,
}

impl GaussianSumFilter {
    /// Builds the filter; the model must be linear with discrete measurements and the prior a
    /// Gaussian mixture. `probes` are the points where linearity is checked.
    pub fn new(
        name: String,
        model: &Model,
        prior: &Prior,
        params: &GaussianSumParams,
        probes: &[Vec<f64>],
    ) -> Result<Self, ZakaiError> {
        if let Some((field, msg)) = params.problems().first() {
            return Err(ZakaiError::Other(format!("{name}: {field}: {msg}")));
        }
        let LinearMixtureModel {
            a,
            b,
            c,
            c0,
            noise,
            prior: mixture,
        } = check_model(model, prior, probes)?;
        let components = mixture
            .components()
            .iter()
            .map(|c| Component::new(c.weight, c.mean.clone(), c.cov.clone()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(GaussianSumFilter {
            name,
            a,
            b,
            q: model.process_noise(),
            c,
            c0,
            noise,
            params: params.clone(),
            components,
            cached: None,
            reduction: Reduction::default(),
        })
    }

    /// Number of components.
    pub fn len(&self) -> usize {
        self.components.len()
    }

    /// True when there are no components (never, after a successful build).
    pub fn is_empty(&self) -> bool {
        self.components.is_empty()
    }

    /// How far the reduction moved the mixture from the exact one.
    pub fn reduction(&self) -> Reduction {
        self.reduction
    }

    /// Predicts every component over `dt` (exact).
    pub fn predict(&mut self, dt: f64) -> Result<(), FilterError> {
        let d = Discretization::for_step(&mut self.cached, &self.a, &self.b, &self.q, dt);
        for comp in &mut self.components {
            let m = &d.phi * &comp.m + &d.gamma_b;
            let p = &d.phi * &comp.p * d.phi.transpose() + &d.qd;
            *comp = Component::new(comp.w, m, p)?;
        }
        Ok(())
    }

    /// The Bayes update with measurement `z`, then the mixture reduction.
    pub fn update(&mut self, z: &[f64]) -> Result<(), FilterError> {
        let z = DVector::from_column_slice(z);
        let mut next = Vec::with_capacity(self.components.len() * self.noise.components().len());
        let mut log_w = Vec::with_capacity(next.capacity());
        for comp in &self.components {
            let pct = &comp.p * self.c.transpose();
            let predicted = &self.c * &comp.m + &self.c0;
            for v in self.noise.components() {
                let mut s = &self.c * &pct + &v.cov;
                symmetrize(&mut s);
                let chol = cholesky(&s, "innovation covariance")?;
                let nu = &z - &predicted - &v.mean;
                let gain = chol.solve(&pct.transpose()).transpose();
                let m = &comp.m + &gain * &nu;
                let p = &comp.p - &gain * &s * gain.transpose();
                log_w.push(
                    libm::log(comp.w) + libm::log(v.weight) + gaussian_log_density(&nu, &chol),
                );
                next.push(Component::new(0.0, m, p)?);
            }
        }
        let total = log_sum_exp(log_w.iter().copied());
        if !total.is_finite() {
            return Err(FilterError::MassLost);
        }
        for (c, lw) in next.iter_mut().zip(&log_w) {
            c.w = libm::exp(lw - total);
        }
        self.components = next;
        self.reduce();
        Ok(())
    }

    /// Pruning, then merging by Runnalls' cost (see the module doc).
    fn reduce(&mut self) {
        let largest = self.components.iter().map(|c| c.w).fold(0.0, f64::max);
        let before: f64 = self.components.iter().map(|c| c.w).sum();
        self.components
            .retain(|c| c.w >= self.params.prune * largest);
        let kept: f64 = self.components.iter().map(|c| c.w).sum();
        self.reduction.pruned_weight += before - kept;
        for c in &mut self.components {
            c.w /= kept;
        }
        let k = self.components.len();
        if k < 2 {
            return;
        }
        let mut cost = alloc::vec![f64::INFINITY; k * k];
        for i in 0..k {
            for j in i + 1..k {
                cost[i * k + j] = merge(&self.components[i], &self.components[j]).1;
            }
        }
        let mut alive = alloc::vec![true; k];
        let mut count = k;
        while count > 1 {
            let (mut best, mut bi, mut bj) = (f64::INFINITY, 0, 0);
            for i in (0..k).filter(|&i| alive[i]) {
                for j in (i + 1..k).filter(|&j| alive[j]) {
                    if cost[i * k + j] < best {
                        (best, bi, bj) = (cost[i * k + j], i, j);
                    }
                }
            }
            let forced = count > self.params.max_components;
            if !(forced || best <= self.params.merge_cost) || !best.is_finite() {
                break;
            }
            if forced && best > self.params.merge_cost {
                self.reduction.forced_cost = self.reduction.forced_cost.max(best);
            }
            self.components[bi] = merge(&self.components[bi], &self.components[bj]).0;
            alive[bj] = false;
            count -= 1;
            for j in (0..k).filter(|&j| alive[j] && j != bi) {
                let (lo, hi) = (bi.min(j), bi.max(j));
                cost[lo * k + hi] = merge(&self.components[lo], &self.components[hi]).1;
            }
        }
        let mut i = 0;
        self.components.retain(|_| {
            i += 1;
            alive[i - 1]
        });
    }

    /// The filtering density at `x`.
    pub fn pdf(&self, x: &[f64]) -> f64 {
        let x = DVector::from_column_slice(x);
        self.components
            .iter()
            .map(|c| c.w * libm::exp(gaussian_log_density(&(&x - &c.m), &c.chol)))
            .sum()
    }

    /// The filtering density at every node of `grid`, into `out`.
    pub fn tabulate(&self, grid: &TensorGrid, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let n = grid.dim();
        let mut r = DVector::zeros(n);
        for c in &self.components {
            grid.for_each_node(|idx, x| {
                for d in 0..n {
                    r[d] = x[d] - c.m[d];
                }
                out[idx] += c.w * libm::exp(gaussian_log_density(&r, &c.chol));
            });
        }
    }

    fn mixture_moments(&self) -> (DVector<f64>, DMatrix<f64>) {
        let n = self.a.nrows();
        let mut mean = DVector::zeros(n);
        for c in &self.components {
            mean += &c.m * c.w;
        }
        let mut cov = DMatrix::zeros(n, n);
        for c in &self.components {
            let dm = &c.m - &mean;
            cov += (&c.p + &dm * dm.transpose()) * c.w;
        }
        (mean, cov)
    }
}

/// The moment-preserving merge of two components and its Runnalls cost.
fn merge(a: &Component, b: &Component) -> (Component, f64) {
    let w = a.w + b.w;
    let dm = &a.m - &b.m;
    let m = (&a.m * a.w + &b.m * b.w) / w;
    let p = (&a.p * a.w + &b.p * b.w) / w + &dm * dm.transpose() * (a.w * b.w / (w * w));
    match Component::new(w, m, p) {
        Ok(c) => {
            let cost = 0.5 * (w * c.log_det - a.w * a.log_det - b.w * b.log_det);
            (c, cost.max(0.0))
        }
        Err(_) => (a.clone(), f64::INFINITY),
    }
}

impl Filter for GaussianSumFilter {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        crate::filters::check_measurement(&self.name, obs, self.c.nrows())?;
        if obs.dt > 0.0 {
            self.predict(obs.dt)?;
        }
        self.update(obs.value)
    }

    fn estimate(&self) -> Estimate {
        let (mean, cov) = self.mixture_moments();
        Estimate {
            mean,
            covariance: Some(cov),
            map: None,
        }
    }

    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut one = alloc::vec![0.0; out.len()];
        let (a, b) = dims;
        for c in &self.components {
            let cov = [[c.p[(a, a)], c.p[(a, b)]], [c.p[(b, a)], c.p[(b, b)]]];
            marginal::gaussian_2d([c.m[a], c.m[b]], cov, xs, ys, &mut one);
            for (o, v) in out.iter_mut().zip(&one) {
                *o += c.w * v;
            }
        }
    }

    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut one = alloc::vec![0.0; grid.len()];
        for c in &self.components {
            marginal::gaussian(c.m[dim], c.p[(dim, dim)], grid, &mut one);
            for (o, v) in out.iter_mut().zip(&one) {
                *o += c.w * v;
            }
        }
    }
}
