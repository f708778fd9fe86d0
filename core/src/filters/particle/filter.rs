//! The bootstrap particle filter itself.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::draws::{hilbert_order, Draws};
use super::PfParams;
use crate::error::FilterError;
use crate::filters::{kind_of, Estimate, Filter, Observation, Observed};
use crate::linalg::cholesky;
use crate::model::{BatchScratch, Diffusion, Model, ObservationModel};
use crate::random::NormalZiggurat;

/// The particle filter's self-check: the effective sample size after weighting (before any
/// resampling) as a share of N. Below 1 % the posterior rests on a handful of particles.
pub(crate) const ESS_SHARE_THRESHOLD: f64 = 0.01;

/// The particle filter's second self-check: distinct particles kept by the last resampling as
/// a share of N (N when the last step did not resample). Below 1 % the cloud is a few points
/// repeated: its spread, and the density drawn from it, say little about the posterior.
pub(crate) const UNIQUE_SHARE_THRESHOLD: f64 = 0.01;

/// How a particle filter weighs its particles.
#[derive(Clone, Debug)]
enum Weighing {
    /// Increments Δy of continuous observations: the density of their observed rows,
    /// `N(0, S)` (the residuals scaled by 1/√Δτ).
    Increments(crate::filters::ObservedNoise),
    /// Measurements: `p(z | x)` of any family.
    Measurements(crate::filters::MeasurementLikelihood),
}

/// G as the particles' Euler–Maruyama steps use it.
#[derive(Clone, Debug)]
enum ParticleDiffusion {
    /// A constant G, row-major.
    Constant(Vec<f64>),
    /// `G(x)`, and its n² entries at every particle as structure of arrays (entry (j, l) of
    /// particle i at `values[(j * n + l) * N + i]`).
    StateDependent {
        g: alloc::sync::Arc<dyn crate::model::VectorFunction>,
        values: Vec<f64>,
    },
}

/// The bootstrap particle filter.
///
/// Particles are stored as structure of arrays and moved, weighed and resampled one pass per
/// operation over all of them: f and h are evaluated on the whole population at once
/// ([`VectorFunction::eval_batch`](crate::model::VectorFunction::eval_batch)), the noise comes
/// from the ziggurat, weights take one `exp` per particle, and every buffer is allocated in the
/// constructor (the measurement density's batch buffers on the first step), so a step after the
/// first allocates nothing.
///
/// The bootstrap particle filter (Gordon, Salmond & Smith): particles follow the signal SDE by
/// Euler–Maruyama — or, for a linear SDE `dx = (A x + b) dt + G dv` with constant G, by its
/// exact Gaussian transition `N(e^{AΔτ} x + Γb, Q_Δτ)` in one draw per interval, whatever its
/// length —, weights are multiplied by the observation likelihood and kept in the log
/// domain, and systematic resampling runs whenever the effective sample size
/// `ESS = 1 / Σ wᵢ²` falls below `ess_threshold · N`.
///
/// Likelihoods: for an increment, `Δy ~ N(h(x) Δτ, S Δτ)`; for a measurement, the model's
/// noise density (Gaussian or mixture) at `z − h(x)`.
///
/// Cost: O(N (n² + m)) per step for N particles in n dimensions with m observed components
/// (the Euler–Maruyama moves, one likelihood per particle, O(N) systematic resampling); the
/// error of its estimates falls like 1/√N whatever n is.
///
/// ```
/// use zakai::{Filter, Model, Noise, Pf};
///
/// let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut pf = Pf::builder(&model)
///     .prior_gaussian(&[0.0], &[[1.0]])
///     .with(|p| p.particles = 1000)
///     .seed(7)
///     .build()
///     .unwrap();
/// pf.step_measurement(0.1, &[0.4]).unwrap();
/// assert!(pf.estimate().mean[0] > 0.0);
/// ```
///
/// # When it fails
///
/// With too few particles for the posterior — a sharp likelihood (small observation noise), a
/// long gap, a prior far from the data — the weights collapse onto a handful of particles and
/// the estimate's spread no longer measures its error. The self-check says so: the effective
/// sample size after weighting below 1 % of N, or the distinct particles a resampling kept below
/// 1 % ([`crate::Filter::self_check`]). Its log-likelihood is the logarithm of an unbiased
/// estimate, so it is biased low by about half its variance, and a random function of the
/// parameters.
#[derive(Clone, Debug)]
pub struct Pf {
    name: String,
    /// The model of the current step (for a driven model, frozen for it).
    pub(super) model: Model,
    /// A driven model ([`crate::Inputs`]), frozen into `model` at each step.
    pub(super) driven: Option<Model>,
    pub(super) params: PfParams,
    /// Its random numbers: its own generator, or supplied normals ([`super::draws`]).
    pub(super) draws: Draws,
    normal: NormalZiggurat,
    /// Component j of particle i at `particles[j * N + i]`.
    pub(super) particles: Vec<f64>,
    /// Normalised log-weights and the same weights in the linear domain.
    pub(super) log_weights: Vec<f64>,
    /// The last step's log-likelihood estimate ([`Filter::log_likelihood`]).
    log_likelihood: f64,
    weights: Vec<f64>,
    /// f (n·N), then the noise draws (n·N); h or the residual (m·N); resampling target (n·N).
    drift: Vec<f64>,
    noise: Vec<f64>,
    predicted: Vec<f64>,
    /// The moved particles until a step succeeds (then swapped with `particles`), and the
    /// resampling target.
    resampled: Vec<f64>,
    /// The log-weights and weights a step computes, swapped in when it succeeds: a failed
    /// step leaves the filter as it was.
    next_log_weights: Vec<f64>,
    next_weights: Vec<f64>,
    /// How the observed rows weigh a particle.
    weighing: Weighing,
    /// Resampling: the last particle whose copies start at each slot (N + 1), and the
    /// particle each slot copies (N).
    starts: Vec<usize>,
    ancestors: Vec<usize>,
    /// G and, for continuous observations, S⁻¹ (row-major).
    diffusion: ParticleDiffusion,
    noise_inverse: Vec<f64>,
    /// One residual (or h at one particle) while a density is evaluated, one particle, and
    /// work space.
    residual: Vec<f64>,
    point: Vec<f64>,
    work: Vec<f64>,
    /// The rows of the observed components of the current measurement.
    observed_rows: Vec<usize>,
    scratch: BatchScratch,
    resamples: usize,
    /// The particles' order along the Hilbert curve and its keys, and the weights in that
    /// order, when resampling sorts ([`Draws::is_supplied`]).
    order: Vec<usize>,
    keys: Vec<u128>,
    sorted_weights: Vec<f64>,
    /// The effective sample size after the last weighting.
    last_ess: f64,
    /// Distinct particles kept by the last resampling (N when the last step did not resample).
    last_unique: usize,
    /// Euler–Maruyama steps per prediction (per Δτ when built for it).
    pub(super) substeps: crate::filters::Substeps,
    /// The clouds between the Euler–Maruyama steps of the last prediction (after 1, …, S − 1
    /// of its S steps, n·N values each), kept when a smoother asks for them.
    pub(super) trail: Option<Vec<f64>>,
    /// The exact Gaussian transition of a linear SDE, drawn from in one move per interval
    /// instead of Euler–Maruyama substeps ([`super::exact`]).
    pub(super) exact: Option<super::exact::LinearTransition>,
}

impl Pf {
    /// Draws N particles from the prior with a generator seeded by `seed`, or from the
    /// supplied normals ([`crate::filters::method::BuildContext::supplied`]).
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &PfParams,
    ) -> Result<Self, FilterError> {
        let (model, prior, seed) = (ctx.model, ctx.prior, ctx.seed);
        if let Some((field, msg)) = params.problems().into_iter().next() {
            return Err(FilterError::Unsuitable(format!("PF {field}: {msg}")));
        }
        let mut draws = Draws::new(seed, ctx.supplied);
        let (n, m, count) = (model.n, model.m, params.particles);
        let mut particles = vec![0.0; count * n];
        let mut z = Vec::new();
        for i in 0..count {
            let x = draws.prior_draw(prior, &mut z);
            for j in 0..n {
                particles[j * count + i] = x[j];
            }
        }
        let noise_inverse = match &model.observations {
            ObservationModel::Continuous { noise_cov } => cholesky(noise_cov, "observation noise")?
                .inverse()
                .transpose()
                .as_slice()
                .to_vec(),
            ObservationModel::Discrete { .. } => Vec::new(),
        };
        let weighing = match &model.observations {
            ObservationModel::Continuous { noise_cov } => {
                Weighing::Increments(crate::filters::ObservedNoise::new(
                    crate::model::GaussianMixture::gaussian(
                        nalgebra::DVector::zeros(m),
                        noise_cov.clone(),
                    )
                    .map_err(|_| FilterError::NotPositiveDefinite {
                        what: "observation noise",
                    })?,
                ))
            }
            ObservationModel::Discrete { density } => {
                Weighing::Measurements(crate::filters::MeasurementLikelihood::new(density, m))
            }
        };
        let uniform = 1.0 / count as f64;
        Ok(Pf {
            name,
            model: model.clone(),
            driven: model.is_driven().then(|| model.clone()),
            params: params.clone(),
            draws,
            normal: NormalZiggurat::new(),
            particles,
            log_weights: vec![-libm::log(count as f64); count],
            log_likelihood: 0.0,
            weights: vec![uniform; count],
            drift: vec![0.0; count * n],
            noise: vec![0.0; count * n],
            predicted: vec![0.0; count * m],
            resampled: vec![0.0; count * n],
            next_log_weights: vec![0.0; count],
            next_weights: vec![0.0; count],
            weighing,
            starts: vec![0; count + 1],
            ancestors: vec![0; count],
            diffusion: match &model.diffusion {
                Diffusion::Constant(g) => {
                    ParticleDiffusion::Constant(g.transpose().as_slice().to_vec())
                }
                Diffusion::StateDependent(g) => ParticleDiffusion::StateDependent {
                    g: g.clone(),
                    values: vec![0.0; n * n * count],
                },
            },
            noise_inverse,
            residual: vec![0.0; m],
            point: vec![0.0; n],
            work: vec![0.0; m],
            observed_rows: Vec::with_capacity(m),
            scratch: BatchScratch::default(),
            resamples: 0,
            order: Vec::new(),
            keys: Vec::new(),
            sorted_weights: Vec::new(),
            last_ess: count as f64,
            last_unique: count,
            substeps: crate::filters::Substeps::new(params.substeps.unwrap_or(1), ctx.dt_obs),
            trail: None,
            exact: super::exact::LinearTransition::of(model, ctx.probes),
        })
    }

    /// The model the next prediction uses: `dynamics`, a driven model frozen for the step
    /// (its drift and, when state-dependent, its G).
    fn freeze_dynamics(&mut self, dynamics: &Model) {
        if let (ParticleDiffusion::StateDependent { g, .. }, Diffusion::StateDependent(frozen)) =
            (&mut self.diffusion, &dynamics.diffusion)
        {
            *g = frozen.clone();
        }
        self.model = dynamics.clone();
    }

    /// The moves of a prediction over `dt` and the length each stands for: the
    /// Euler–Maruyama substeps ([`crate::filters::Substeps`]), one move of length `dt` for a
    /// linear SDE's exact transition, or for a discrete-time model its transitions, each
    /// counted as length 1 (the transition's noise is `G Gᵀ` itself).
    pub(super) fn moves(&self, dt: f64) -> Result<(usize, f64), FilterError> {
        if self.model.is_discrete_time() {
            return Ok((self.model.transitions(dt)?, 1.0));
        }
        if self.exact.is_some() {
            return Ok((1, dt));
        }
        let substeps = self.substeps.over(dt);
        Ok((substeps, dt / substeps as f64))
    }

    /// How many times the filter has resampled.
    pub fn resample_count(&self) -> usize {
        self.resamples
    }

    /// Euler–Maruyama for every particle: x += f(x) h + G(x) ξ √h, in the steps
    /// [`crate::filters::Substeps`] gives for `dt`, from `particles` into `resampled` (the
    /// particles move only when the step succeeds). A state-dependent G is evaluated at every
    /// particle at the start of each substep; where it is not finite the step fails.
    ///
    /// For a discrete-time model the moves are its transitions instead, `x ← F(x) + G(x) ξ`,
    /// or `F(x) + w` with w drawn from a mixture transition noise (one per period in `dt`, each of a driven model at the time it reaches, with the
    /// step's `inputs`): the particles are drawn from the transition itself.
    fn predict_into_spare(
        &mut self,
        dt: f64,
        inputs: Option<crate::model::Inputs<'_>>,
    ) -> Result<(), FilterError> {
        let (n, count) = (self.model.n, self.params.particles);
        let (substeps, h) = self.moves(dt)?;
        let discrete = self.model.is_discrete_time();
        if substeps == 0 {
            // No transition (a step shorter than rounding of the period): the particles stay.
            self.resampled.copy_from_slice(&self.particles);
        }
        if let Some(exact) = &mut self.exact {
            // x' ~ N(Φ x + Γb, Q_Δ): one draw over the whole interval.
            self.draws.normals(&self.normal, &mut self.noise);
            super::exact::draw(
                exact.over(dt),
                &self.particles,
                &self.noise,
                &mut self.resampled,
            );
            return Ok(());
        }
        let sqrt_h = libm::sqrt(h);
        for substep in 0..substeps {
            if let (true, Some(driven)) = (discrete && substeps > 1, &self.driven) {
                let model = driven
                    .transition_at(inputs, substep, substeps)?
                    .into_owned();
                self.freeze_dynamics(&model);
            }
            let from = if substep == 0 {
                &self.particles
            } else {
                &self.resampled
            };
            self.model
                .drift
                .eval_batch(from, &mut self.drift, &mut self.scratch);
            if let ParticleDiffusion::StateDependent { g, values } = &mut self.diffusion {
                g.eval_batch(from, values, &mut self.scratch);
                if let Some(bad) = values.iter().position(|v| !v.is_finite()) {
                    let i = bad % count;
                    let x: Vec<f64> = (0..n).map(|j| from[j * count + i]).collect();
                    return Err(FilterError::Unsuitable(format!(
                        "{}: the diffusion G(x) is not finite at the particle x = {x:.4?}; write G so that it is defined wherever the state can go (e.g. sqrt(abs(x)) rather than sqrt(x))",
                        self.name
                    )));
                }
            }
            if substep == 0 {
                self.resampled.copy_from_slice(&self.particles);
            } else if let Some(trail) = &mut self.trail {
                trail.extend_from_slice(&self.resampled);
            }
            self.draws.normals(&self.normal, &mut self.noise);
            if let (true, Some(w)) = (discrete, &self.model.transition_mixture) {
                // x ← F(x) + w, w drawn from the mixture: a component per particle, then
                // its mean and factor applied to the particle's normals.
                for i in 0..count {
                    let c = w.mixture().pick(self.draws.uniform());
                    for (l, xi) in self.point.iter_mut().enumerate() {
                        *xi = self.noise[l * count + i];
                    }
                    c.transform(&mut self.point);
                    for (j, w) in self.point.iter().enumerate() {
                        self.resampled[j * count + i] = self.drift[j * count + i] + w;
                    }
                }
                continue;
            }
            for j in 0..n {
                let x = &mut self.resampled[j * count..(j + 1) * count];
                let f = &self.drift[j * count..(j + 1) * count];
                match discrete {
                    true => x.copy_from_slice(f),
                    false => x.iter_mut().zip(f).for_each(|(x, f)| *x += f * h),
                }
                for l in 0..n {
                    let xi = &self.noise[l * count..(l + 1) * count];
                    match &self.diffusion {
                        ParticleDiffusion::Constant(g) => {
                            let g = g[j * n + l] * sqrt_h;
                            if g != 0.0 {
                                x.iter_mut().zip(xi).for_each(|(x, xi)| *x += g * xi);
                            }
                        }
                        ParticleDiffusion::StateDependent { values, .. } => {
                            let g = &values[(j * n + l) * count..(j * n + l + 1) * count];
                            x.iter_mut()
                                .zip(xi)
                                .zip(g)
                                .for_each(|((x, xi), g)| *x += g * sqrt_h * xi);
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Into `next_log_weights`: the log-weights times the likelihood of the observed
    /// components of `obs` at the particles (the moved ones in `resampled` when `moved`);
    /// then normalised, with the linear weights in `next_weights`. Returns the step's
    /// log-likelihood estimate, the log of the weights' total `ln Σ wᵢ p(obs | xᵢ)` — for an
    /// increment against the Wiener reference `N(Δy; 0, SΔτ)`, whose factors the weights
    /// leave out.
    fn weigh(
        &mut self,
        obs: &Observation,
        observed: Observed,
        moved: bool,
    ) -> Result<f64, FilterError> {
        let (m, count) = (self.model.m, self.params.particles);
        let particles = if moved {
            &self.resampled
        } else {
            &self.particles
        };
        self.model
            .observation
            .eval_batch(particles, &mut self.predicted, &mut self.scratch);
        let lw = &mut self.next_log_weights;
        lw.copy_from_slice(&self.log_weights);
        // The log-density of the observation under the reference the weights are taken
        // against (0 for measurements: their weights are whole densities).
        let mut reference = 0.0;
        let noise = match &mut self.weighing {
            Weighing::Measurements(likelihood) => {
                if let Some(noise) = likelihood.additive_density() {
                    // Additive noise: the residuals z − h(x) as a batch, then the noise
                    // density of the observed components at every particle's, as a batch.
                    self.observed_rows.clear();
                    for (a, z) in obs.value.iter().enumerate() {
                        self.predicted[a * count..(a + 1) * count]
                            .iter_mut()
                            .for_each(|r| *r = z - *r);
                        if observed == Observed::All || !Observation::is_missing(*z) {
                            self.observed_rows.push(a);
                        }
                    }
                    noise.add_log_pdf_batch(
                        (&self.predicted, &self.observed_rows),
                        lw,
                        &mut self.work,
                    );
                } else if !likelihood.add_batch(
                    obs.value,
                    (particles, &self.predicted, count),
                    lw,
                    &mut self.scratch,
                )? {
                    // ln p(z | xᵢ) of the observed components, particle by particle for the
                    // families with no expression of the state to batch.
                    let reads_state = likelihood.reads_state();
                    for (i, w) in lw.iter_mut().enumerate() {
                        if reads_state {
                            for (j, x) in self.point.iter_mut().enumerate() {
                                *x = particles[j * count + i];
                            }
                        }
                        for (a, h) in self.residual.iter_mut().enumerate() {
                            *h = self.predicted[a * count + i];
                        }
                        *w += likelihood.log_at(obs.value, &self.point, &self.residual)?;
                    }
                }
                return normalise(&mut self.next_log_weights, &mut self.next_weights);
            }
            Weighing::Increments(noise) => noise,
        };
        // Increments: residuals Δy − h(x)Δτ, in place (NaN in missing rows, which are not
        // read).
        for (a, z) in obs.value.iter().enumerate() {
            self.predicted[a * count..(a + 1) * count]
                .iter_mut()
                .for_each(|r| *r = z - *r * obs.dt);
        }
        match observed {
            Observed::Some => {
                let noise = noise.of(obs.value)?;
                let unscale = 1.0 / libm::sqrt(obs.dt);
                let k = crate::filters::observed_residual(
                    obs.value,
                    |a| obs.value[a] * unscale,
                    &mut self.residual,
                );
                reference = noise.log_pdf_slice(&self.residual[..k], &mut self.work);
                let predicted = &self.predicted;
                for (i, w) in lw.iter_mut().enumerate() {
                    let k = crate::filters::observed_residual(
                        obs.value,
                        |a| predicted[a * count + i] * unscale,
                        &mut self.residual,
                    );
                    *w += noise.log_pdf_slice(&self.residual[..k], &mut self.work);
                }
            }
            // −½ rᵀ (S Δτ)⁻¹ r, against −½ Δyᵀ (S Δτ)⁻¹ Δy.
            _ => {
                let c = -0.5 / obs.dt;
                for a in 0..m {
                    for b in 0..m {
                        let s = c * self.noise_inverse[a * m + b];
                        reference += s * obs.value[a] * obs.value[b];
                        let (ra, rb) = (
                            &self.predicted[a * count..(a + 1) * count],
                            &self.predicted[b * count..(b + 1) * count],
                        );
                        lw.iter_mut()
                            .zip(ra.iter().zip(rb))
                            .for_each(|(w, (x, y))| *w += s * x * y);
                    }
                }
            }
        }
        let total = normalise(&mut self.next_log_weights, &mut self.next_weights)?;
        Ok(total - reference)
    }

    /// Systematic resampling with the uniform `u` ([`systematic_ancestors`]), the particles
    /// gathered from their ancestors one component at a time. With supplied normals the
    /// particles are taken in their Hilbert order ([`hilbert_order`]; Deligiannidis, Doucet &
    /// Pitt 2018, §4.1).
    fn resample(&mut self, u: f64) {
        let (n, count) = (self.model.n, self.params.particles);
        let unique = if self.draws.is_supplied() {
            hilbert_order(&self.particles, n, &mut self.order, &mut self.keys);
            self.sorted_weights.clear();
            self.sorted_weights
                .extend(self.order.iter().map(|&i| self.weights[i]));
            let unique = systematic_ancestors(
                &self.sorted_weights,
                u,
                &mut self.starts,
                &mut self.ancestors,
                &mut self.resampled,
            );
            for a in &mut self.ancestors {
                *a = self.order[*a];
            }
            unique
        } else {
            systematic_ancestors(
                &self.weights,
                u,
                &mut self.starts,
                &mut self.ancestors,
                &mut self.resampled,
            )
        };
        for d in 0..n {
            let from = &self.particles[d * count..(d + 1) * count];
            let to = &mut self.resampled[d * count..(d + 1) * count];
            for (x, &a) in to.iter_mut().zip(&self.ancestors) {
                *x = from[a];
            }
        }
        core::mem::swap(&mut self.particles, &mut self.resampled);
        self.last_unique = unique.max(1);
        let lw = -libm::log(count as f64);
        self.log_weights.iter_mut().for_each(|w| *w = lw);
        self.weights
            .iter_mut()
            .for_each(|w| *w = 1.0 / count as f64);
        self.resamples += 1;
    }

    fn effective_sample_size(&self) -> f64 {
        1.0 / sum_of_squares(&self.weights)
    }

    /// Component `dim` of every particle.
    fn component(&self, dim: usize) -> &[f64] {
        let count = self.params.particles;
        &self.particles[dim * count..(dim + 1) * count]
    }
}

/// Normalises `log_weights` and fills the linear `weights`: one exponential per particle;
/// returns the log of their total before, or [`FilterError::MassLost`] when no weight is left
/// (nothing finite, or NaN).
fn normalise(log_weights: &mut [f64], weights: &mut [f64]) -> Result<f64, FilterError> {
    let max = largest(log_weights);
    if !max.is_finite() {
        return Err(FilterError::MassLost);
    }
    let total = exponentiate_shifted(weights, log_weights, max);
    if !(total.is_finite() && total > 0.0) {
        return Err(FilterError::MassLost);
    }
    let shift = max + libm::log(total);
    rescale(weights, log_weights, 1.0 / total, shift);
    Ok(shift)
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// The largest log-weight ([`crate::linalg::largest_in_lanes`]).
    fn largest(lw: &[f64]) -> f64 {
        crate::linalg::largest_in_lanes(lw)
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `w_i ← w_i · inv` and `lw_i ← lw_i − shift`: the weights normalised in both domains.
    fn rescale(w: &mut [f64], lw: &mut [f64], inv: f64, shift: f64) {
        w.iter_mut().for_each(|w| *w *= inv);
        lw.iter_mut().for_each(|w| *w -= shift);
    }
}

/// Systematic resampling's ancestors: points `t_j = (u + j)/N` on the CDF `c_i` of the
/// normalised weights; slot j copies the particle i with `c_{i−1} < t_j ≤ c_i`, written to
/// `ancestors` (N); returns how many particles have copies. `starts` (N + 1, all zero, and
/// left so) and `running` (at least N) are scratch.
///
/// Without a branch per copy (a walk that copies while the next point lies below the CDF
/// mispredicts on most particles: a third of the particle filter's step at 10⁴ particles):
/// particle i's copies end at slot `e_i = #{j : t_j ≤ c_i} = ⌊N c_i − u⌋ + 1` (clamped to
/// 0..=N) and start at `e_{i−1}`; each particle writes its index at its start — the last
/// writer there is the one that has copies — and a running maximum over the slots fills in
/// the later copies. Slots that round-off leaves uncovered (`e_{N−1} < N`) get the last
/// particle.
fn systematic_ancestors(
    weights: &[f64],
    u: f64,
    starts: &mut [usize],
    ancestors: &mut [usize],
    running: &mut [f64],
) -> usize {
    let count = weights.len();
    let running = &mut running[..count];
    // The CDF in four independent chains of additions instead of one: each quarter's running
    // sums from 0 side by side, then each quarter's CDF the last value of the one before plus
    // them — non-decreasing across the quarters, as the slots need.
    const CHAINS: usize = 4;
    let quarter = count / CHAINS;
    // Block b is `b q..block_end(b)`, the last one taking the remainder.
    let block_end = |b: usize| {
        if b + 1 == CHAINS {
            count
        } else {
            (b + 1) * quarter
        }
    };
    let mut sums = [0.0; CHAINS];
    for k in 0..quarter {
        for (b, sum) in sums.iter_mut().enumerate() {
            *sum += weights[b * quarter + k];
            running[b * quarter + k] = *sum;
        }
    }
    for at in CHAINS * quarter..count {
        sums[CHAINS - 1] += weights[at];
        running[at] = sums[CHAINS - 1];
    }
    let mut base = 0.0;
    for b in 0..CHAINS {
        let block = &mut running[b * quarter..block_end(b)];
        if b > 0 {
            block.iter_mut().for_each(|c| *c += base);
        }
        if let Some(&last) = block.last() {
            base = last;
        }
    }
    // Each particle's end slot `N c_i − u + 1` in [0, N] (a vector pass), truncated below.
    slot_ends(running, count as f64, u);
    // Particle i writes its index at its start e_{i−1}.
    let (mut start, mut unique) = (0, 0);
    for (i, e) in running.iter().enumerate() {
        // SAFETY: `slot_ends` left e finite and within [0, N], N = count < 2⁶³ (through
        // i64: one instruction, where the conversion to an unsigned integer takes two).
        let end = unsafe { e.to_int_unchecked::<i64>() as usize };
        starts[start] = i;
        unique += usize::from(end > start);
        start = end;
    }
    starts[start] = count - 1;
    // The owners: a running maximum over the slots, in CHAINS blocks side by side (each
    // block's own maximum, then the blocks before it carried in), the slots zeroed again for
    // the next call as they are read.
    let mut owners = [0usize; CHAINS];
    let take = |at: usize, owner: &mut usize, starts: &mut [usize], ancestors: &mut [usize]| {
        *owner = (*owner).max(starts[at]);
        starts[at] = 0;
        ancestors[at] = *owner;
    };
    for k in 0..quarter {
        for (b, owner) in owners.iter_mut().enumerate() {
            take(b * quarter + k, owner, starts, ancestors);
        }
    }
    for at in CHAINS * quarter..count {
        take(at, &mut owners[CHAINS - 1], starts, ancestors);
    }
    starts[count] = 0;
    let mut carry = owners[0];
    for b in 1..CHAINS {
        ancestors[b * quarter..block_end(b)]
            .iter_mut()
            .for_each(|a| *a = (*a).max(carry));
        carry = carry.max(owners[b]);
    }
    unique
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `c ← clamp(N c − u + 1, 0, N)`: the end slots of systematic resampling from the CDF
    /// (`max` takes 0 for a NaN, so every value ends within [0, N]).
    fn slot_ends(cdf: &mut [f64], slots: f64, u: f64) {
        for c in cdf.iter_mut() {
            *c = (slots * *c - u + 1.0).max(0.0).min(slots);
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `w_i = e^{lw_i − max}` for every particle (all exponents ≤ 0, so
    /// [`linalg::exp_nonpositive`](crate::linalg::exp_nonpositive), which vectorises, where
    /// `libm::exp` does not) and their sum, in lanes. No FMA, so the weights, and the
    /// resampling decisions that follow from them, are the same bits on every target.
    fn exponentiate_shifted(w: &mut [f64], lw: &[f64], max: f64) -> f64 {
        for (w, lw) in w.iter_mut().zip(lw) {
            *w = crate::linalg::exp_nonpositive(lw - max);
        }
        crate::linalg::sum_in_lanes(w, |w| w)
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `Σ w_i²`.
    fn sum_of_squares(w: &[f64]) -> f64 {
        crate::linalg::sum_in_lanes(w, |w| w * w)
    }
}

impl Filter for Pf {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        // Checked before anything moves: a refused observation leaves the particles.
        let frozen = match &self.driven {
            Some(model) => obs.frozen(model)?,
            None => None,
        };
        if let Some((_, measurement)) = &frozen {
            if let ObservationModel::Discrete { density } = &measurement.observations {
                // The likelihood's storage kept from step to step, its density the step's.
                match &mut self.weighing {
                    Weighing::Measurements(likelihood) => likelihood.set_density(density),
                    weighing => {
                        *weighing = Weighing::Measurements(
                            crate::filters::MeasurementLikelihood::new(density, measurement.m),
                        )
                    }
                }
            }
        }
        let mut observed = obs.check(&self.name, kind_of(&self.model), self.model.m)?;
        if let Weighing::Measurements(likelihood) = &mut self.weighing {
            likelihood.check(&self.name, obs.value)?;
        }
        let continuous = matches!(self.model.observations, ObservationModel::Continuous { .. });
        if continuous && obs.dt == 0.0 {
            // An increment over no time: nothing to assimilate.
            observed = Observed::Nothing;
        }
        let moved = obs.dt > 0.0;
        // The particles move into the spare buffer and the weights into the next ones; only
        // a step that succeeds swaps them in (and keeps the generator's advance).
        let draws = self.draws.clone();
        if let Some((dynamics, _)) = &frozen {
            self.freeze_dynamics(dynamics);
        }
        if moved {
            let trail_len = self.trail.as_ref().map(Vec::len);
            if let Err(e) = self.predict_into_spare(obs.dt, obs.inputs) {
                self.draws = draws;
                if let (Some(trail), Some(len)) = (&mut self.trail, trail_len) {
                    trail.truncate(len);
                }
                return Err(e);
            }
        }
        if let Some((_, measurement)) = frozen {
            self.model = measurement;
        }
        let mut log_likelihood = 0.0;
        if observed != Observed::Nothing {
            match self.weigh(obs, observed, moved) {
                Ok(ll) => log_likelihood = ll,
                Err(e) => {
                    self.draws = draws;
                    return Err(e);
                }
            }
            core::mem::swap(&mut self.log_weights, &mut self.next_log_weights);
            core::mem::swap(&mut self.weights, &mut self.next_weights);
        }
        if moved {
            core::mem::swap(&mut self.particles, &mut self.resampled);
        }
        self.log_likelihood = log_likelihood;
        if observed == Observed::Nothing {
            return Ok(());
        }
        self.last_ess = self.effective_sample_size();
        self.last_unique = self.params.particles;
        // With supplied normals the uniform is read at every step, resampled or not, so that
        // each random number keeps its place in U whatever θ does to the weights.
        let supplied = self.draws.is_supplied();
        let u = supplied.then(|| self.draws.uniform());
        if self.last_ess < self.params.ess_threshold * self.params.particles as f64 {
            let u = u.unwrap_or_else(|| self.draws.uniform());
            self.resample(u);
        }
        Ok(())
    }

    fn log_likelihood(&self) -> Option<f64> {
        Some(self.log_likelihood)
    }

    fn smoother(
        &self,
        plan: &crate::filters::smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn crate::filters::smoothing::Smoother>, FilterError> {
        self.ffbsi(plan)
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
        let unique = self.last_unique as f64 / self.params.particles as f64;
        if unique < UNIQUE_SHARE_THRESHOLD {
            out.push(crate::filters::Concern::below(
                "distinct particles after resampling, share of N",
                unique,
                UNIQUE_SHARE_THRESHOLD,
                "resampling kept copies of a few particles: the cloud has collapsed; use more particles",
            ));
        }
    }

    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        crate::filters::marginal::kernel_density(self.component(dim), &self.weights, grid, out);
    }

    /// The cloud: the particles with their weights.
    fn state_law(&self) -> Result<crate::filters::predictive::StateLaw, FilterError> {
        Ok(crate::filters::predictive::StateLaw::Points {
            n: self.model.n,
            points: self.particles.clone(),
            weights: self.weights.clone(),
            cells: None,
        })
    }

    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        let points = self
            .component(dims.0)
            .iter()
            .zip(self.component(dims.1))
            .zip(&self.weights)
            .map(|((a, b), w)| (*a, *b, *w));
        crate::filters::marginal::histogram_2d(points, xs, ys, out);
    }

    fn estimate(&self) -> Estimate {
        let mut out = Estimate::zeros(self.model.n);
        self.estimate_into(&mut out);
        out
    }

    /// The weighted mean and covariance of the particles, written into `out`.
    fn estimate_into(&self, out: &mut Estimate) {
        let n = self.model.n;
        let (mean, cov) = out.mean_and_covariance(n);
        for j in 0..n {
            mean[j] = weighted_sum(self.component(j), &self.weights);
        }
        for a in 0..n {
            for b in 0..=a {
                let c = weighted_product_about(
                    (self.component(a), mean[a]),
                    (self.component(b), mean[b]),
                    &self.weights,
                );
                cov[(a, b)] = c;
                cov[(b, a)] = c;
            }
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `Σ w_i x_i`, in lanes.
    fn weighted_sum(x: &[f64], w: &[f64]) -> f64 {
        crate::linalg::sum_zipped_in_lanes([x, w], |[x, w]| w * x)
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `Σ w_i (x_i − m_x)(y_i − m_y)`, in lanes.
    fn weighted_product_about(x: (&[f64], f64), y: (&[f64], f64), w: &[f64]) -> f64 {
        let ((x, mx), (y, my)) = (x, y);
        crate::linalg::sum_zipped_in_lanes([x, y, w], |[x, y, w]| w * (x - mx) * (y - my))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The textbook walk: slot j takes the first particle whose CDF reaches `(u + j)/N`, the
    /// last particle if round-off leaves none.
    fn walk(weights: &[f64], u: f64) -> Vec<usize> {
        let n = weights.len();
        let mut cdf = Vec::with_capacity(n);
        let mut c = 0.0;
        for w in weights {
            c += w;
            cdf.push(c);
        }
        (0..n)
            .map(|j| {
                let t = (u + j as f64) / n as f64;
                cdf.iter().position(|&c| t <= c).unwrap_or(n - 1)
            })
            .collect()
    }

    #[test]
    fn systematic_ancestors_are_the_walks() {
        for (n, u) in [
            (1usize, 0.3),
            (2, 0.999),
            (7, 0.5),
            (100, 0.01),
            (1000, 0.73),
        ] {
            // Uneven weights with zeros (never copied) and a few heavy ones (copied often).
            let raw: Vec<f64> = (0..n)
                .map(|i| {
                    let v = libm::sin(i as f64 * 1.7 + 0.3).abs();
                    if i % 5 == 3 {
                        0.0
                    } else {
                        v * v * v * if i % 11 == 0 { 40.0 } else { 1.0 }
                    }
                })
                .collect();
            let total: f64 = raw.iter().sum();
            let weights: Vec<f64> = raw.iter().map(|w| w / total).collect();
            let (mut starts, mut ancestors) = (vec![0; n + 1], vec![0; n]);
            let mut running = vec![0.0; n];
            let unique =
                systematic_ancestors(&weights, u, &mut starts, &mut ancestors, &mut running);
            let expected = walk(&weights, u);
            assert_eq!(ancestors, expected, "N = {n}, u = {u}");
            let mut distinct = expected.clone();
            distinct.dedup();
            assert_eq!(unique, distinct.len(), "N = {n}");
            assert!(ancestors.iter().all(|&a| weights[a] > 0.0), "N = {n}");
        }
        // All the weight on one particle: every slot copies it.
        let mut weights = vec![0.0; 50];
        weights[17] = 1.0;
        let (mut starts, mut ancestors) = (vec![0; 51], vec![0; 50]);
        assert_eq!(
            systematic_ancestors(&weights, 0.4, &mut starts, &mut ancestors, &mut [0.0; 50]),
            1
        );
        assert!(ancestors.iter().all(|&a| a == 17));
    }
}
