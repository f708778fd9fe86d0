//! The bootstrap particle filter (Gordon, Salmond & Smith): particles follow the signal SDE by
//! Euler–Maruyama, weights are multiplied by the observation likelihood and kept in the log
//! domain, and systematic resampling runs whenever the effective sample size
//! `ESS = 1 / Σ wᵢ²` falls below `ess_threshold · N`.
//!
//! Likelihoods: for an increment, `Δy ~ N(h(x) Δτ, S Δτ)`; for a measurement, the model's
//! noise density (Gaussian or mixture) at `z − h(x)`.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::error::{FilterError, ZakaiError};
use crate::filters::method::{
    builder_fn, problems_from, BuildContext, Method, MethodInfo, ParamInfo, ParamKind, Takes,
};
use crate::filters::{Estimate, Filter, Observation, ObservationKind};
use crate::linalg::{cholesky, gaussian_log_density, log_sum_exp};
use crate::model::{Model, ObservationModel, Prior};
use crate::random::{rng_from_seed, standard_normal, SimRng};
use crate::validate::ConfigProblem;

/// Parameters of [`ParticleFilter`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PfParams {
    /// Number of particles N.
    pub particles: usize,
    /// Resample when ESS < ess_threshold · N (0 = never, 1 = always).
    pub ess_threshold: f64,
    /// Euler–Maruyama steps per observation interval.
    pub substeps: usize,
}

impl Default for PfParams {
    fn default() -> Self {
        PfParams {
            particles: 200,
            ess_threshold: 0.5,
            substeps: 1,
        }
    }
}

impl PfParams {
    /// Problems with these parameters.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if self.particles == 0 || self.particles > 10_000_000 {
            p.push((
                "particles",
                format!("must be in 1..=10000000, got {}", self.particles),
            ));
        }
        if !(0.0..=1.0).contains(&self.ess_threshold) {
            p.push((
                "ess_threshold",
                format!("must be in [0, 1], got {}", self.ess_threshold),
            ));
        }
        if self.substeps == 0 {
            p.push(("substeps", "must be at least 1".into()));
        }
        p
    }
}

/// The bootstrap particle filter registered as a [`Method`].
pub struct Pf;
builder_fn!(Pf);

impl Method for Pf {
    const KEY: &'static str = "pf";
    type Params = PfParams;
    type Filter = ParticleFilter;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "PF".into(),
            summary: "bootstrap particle filter (systematic resampling on an ESS threshold)".into(),
            paper: "Gordon, Salmond & Smith (1993); the baseline of 000–004".into(),
            takes: Takes::Both,
            dims: "any".into(),
            params: vec![
                ParamInfo::new(
                    "particles",
                    ParamKind::Int,
                    "particles N",
                    "number of particles; the error falls like 1/√N",
                )
                .range(1.0, 1e7),
                ParamInfo::new(
                    "ess_threshold",
                    ParamKind::Number,
                    "resample below ESS/N",
                    "resample when the effective sample size 1/Σwᵢ² falls below this fraction of N (0 never, 1 every step)",
                )
                .range(0.0, 1.0),
                ParamInfo::new(
                    "substeps",
                    ParamKind::Int,
                    "substeps",
                    "Euler–Maruyama steps of each particle per observation interval",
                )
                .at_least(1.0),
            ],
            json_only: Vec::new(),
        }
    }
    fn display_name(p: &PfParams) -> String {
        format!("PF({})", p.particles)
    }
    fn problems(p: &PfParams, _: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems())
    }
    fn memory(p: &PfParams, n: usize) -> Option<usize> {
        // Particles, their copies while resampling, weights and scratch.
        p.particles.checked_mul(3 * n + 3)?.checked_mul(8)
    }
    fn build(ctx: &BuildContext, p: &PfParams, name: String) -> Result<ParticleFilter, ZakaiError> {
        Ok(ParticleFilter::new(
            name, ctx.model, ctx.prior, p, ctx.seed,
        )?)
    }
}

/// The particle filter's self-check: the effective sample size after weighting (before any
/// resampling) as a share of N. Below 1 % the posterior rests on a handful of particles.
pub const ESS_SHARE_THRESHOLD: f64 = 0.01;

/// The bootstrap particle filter (see the module doc).
pub struct ParticleFilter {
    name: String,
    model: Model,
    params: PfParams,
    rng: SimRng,
    /// Particle i at `particles[i*n..(i+1)*n]`.
    particles: Vec<f64>,
    log_weights: Vec<f64>,
    scratch: Vec<f64>,
    resamples: usize,
    /// The effective sample size after the last weighting.
    last_ess: f64,
}

impl ParticleFilter {
    /// Draws N particles from the prior with a generator seeded by `seed`.
    pub fn new(
        name: String,
        model: &Model,
        prior: &Prior,
        params: &PfParams,
        seed: u64,
    ) -> Result<Self, FilterError> {
        if let Some((field, msg)) = params.problems().into_iter().next() {
            return Err(FilterError::Unsuitable(format!("PF {field}: {msg}")));
        }
        let mut rng = rng_from_seed(seed);
        let n = model.n;
        let mut particles = Vec::with_capacity(params.particles * n);
        for _ in 0..params.particles {
            particles.extend_from_slice(prior.sample(&mut rng).as_slice());
        }
        Ok(ParticleFilter {
            name,
            model: model.clone(),
            params: params.clone(),
            rng,
            particles,
            log_weights: vec![-libm::log(params.particles as f64); params.particles],
            scratch: Vec::new(),
            resamples: 0,
            last_ess: params.particles as f64,
        })
    }

    /// How many times the filter has resampled.
    pub fn resample_count(&self) -> usize {
        self.resamples
    }

    fn predict(&mut self, dt: f64) {
        let n = self.model.n;
        let h = dt / self.params.substeps as f64;
        let sqrt_h = libm::sqrt(h);
        let mut fx = vec![0.0; n];
        let mut xi = DVector::zeros(n);
        for p in self.particles.chunks_exact_mut(n) {
            for _ in 0..self.params.substeps {
                self.model.drift.eval(p, &mut fx);
                for v in xi.iter_mut() {
                    *v = standard_normal(&mut self.rng);
                }
                let noise = &self.model.diffusion * &xi;
                for i in 0..n {
                    p[i] += fx[i] * h + noise[i] * sqrt_h;
                }
            }
        }
    }

    fn weigh(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let (n, m) = (self.model.n, self.model.m);
        if obs.value.len() != m {
            return Err(FilterError::BadObservation(format!(
                "expected length {m}, got {}",
                obs.value.len()
            )));
        }
        let z = DVector::from_column_slice(obs.value);
        let mut hx = DVector::zeros(m);
        match (&self.model.observations, obs.kind) {
            (ObservationModel::Continuous { noise_cov }, ObservationKind::Increment) => {
                if obs.dt == 0.0 {
                    return Ok(());
                }
                let chol = cholesky(&(noise_cov * obs.dt), "observation noise")?;
                for (i, p) in self.particles.chunks_exact(n).enumerate() {
                    self.model.observation.eval(p, hx.as_mut_slice());
                    let r = &z - &hx * obs.dt;
                    self.log_weights[i] += gaussian_log_density(&r, &chol);
                }
            }
            (ObservationModel::Discrete { noise }, ObservationKind::Measurement) => {
                for (i, p) in self.particles.chunks_exact(n).enumerate() {
                    self.model.observation.eval(p, hx.as_mut_slice());
                    self.log_weights[i] += noise.log_pdf(&(&z - &hx));
                }
            }
            _ => {
                return Err(FilterError::BadObservation(
                    "observation kind does not match the model".into(),
                ))
            }
        }
        let total = log_sum_exp(self.log_weights.iter().copied());
        if !total.is_finite() {
            return Err(FilterError::MassLost);
        }
        for w in &mut self.log_weights {
            *w -= total;
        }
        Ok(())
    }

    /// Systematic resampling: one uniform u, points (u + i)/N on the weights' CDF.
    fn resample(&mut self) {
        let n = self.model.n;
        let count = self.params.particles;
        let u: f64 = self.rng.random();
        self.scratch.clear();
        let mut cumulative = 0.0;
        let mut j = 0;
        for (i, lw) in self.log_weights.iter().enumerate() {
            cumulative += libm::exp(*lw);
            while j < count && (u + j as f64) / count as f64 <= cumulative {
                self.scratch
                    .extend_from_slice(&self.particles[i * n..(i + 1) * n]);
                j += 1;
            }
        }
        // Round-off may leave the last few slots: fill them with the last particle.
        while j < count {
            self.scratch
                .extend_from_slice(&self.particles[(count - 1) * n..count * n]);
            j += 1;
        }
        core::mem::swap(&mut self.particles, &mut self.scratch);
        let lw = -libm::log(count as f64);
        self.log_weights.iter_mut().for_each(|w| *w = lw);
        self.resamples += 1;
    }

    fn effective_sample_size(&self) -> f64 {
        1.0 / self
            .log_weights
            .iter()
            .map(|w| libm::exp(2.0 * w))
            .sum::<f64>()
    }
}

impl Filter for ParticleFilter {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        // Checked before anything moves: a refused observation leaves the particles.
        crate::filters::check_for_model(&self.name, &self.model, obs)?;
        if obs.dt > 0.0 {
            self.predict(obs.dt);
        }
        self.weigh(obs)?;
        self.last_ess = self.effective_sample_size();
        if self.last_ess < self.params.ess_threshold * self.params.particles as f64 {
            self.resample();
        }
        Ok(())
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        let share = self.last_ess / self.params.particles as f64;
        if share < ESS_SHARE_THRESHOLD {
            out.push(crate::filters::Concern::below(
                "effective sample size after weighting, share of N",
                share,
                ESS_SHARE_THRESHOLD,
                "the weights collapsed onto a few particles: use more particles (or substeps)",
            ));
        }
    }

    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        let n = self.model.n;
        let samples: Vec<f64> = self
            .particles
            .iter()
            .skip(dim)
            .step_by(n)
            .copied()
            .collect();
        let weights: Vec<f64> = self.log_weights.iter().map(|w| libm::exp(*w)).collect();
        crate::filters::marginal::kernel_density(&samples, &weights, grid, out);
    }

    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        let n = self.model.n;
        let points = self
            .particles
            .chunks_exact(n)
            .zip(&self.log_weights)
            .map(|(p, lw)| (p[dims.0], p[dims.1], libm::exp(*lw)));
        crate::filters::marginal::histogram_2d(points, xs, ys, out);
    }

    fn estimate(&self) -> Estimate {
        let n = self.model.n;
        let mut mean = DVector::zeros(n);
        let mut second = DMatrix::zeros(n, n);
        for (p, lw) in self.particles.chunks_exact(n).zip(&self.log_weights) {
            let w = libm::exp(*lw);
            let x = DVector::from_column_slice(p);
            mean += &x * w;
            second += &x * x.transpose() * w;
        }
        let cov = second - &mean * mean.transpose();
        Estimate {
            mean,
            covariance: Some(cov),
            map: None,
        }
    }
}
