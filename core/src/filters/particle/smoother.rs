//! Forward filtering, backward simulation (FFBSi; Godsill, Doucet & West 2004) for the
//! particle filter ([`crate::Smoother`]).
//!
//! The forward pass is the particle filter, keeping after every step its particles and
//! weights, and the clouds between the Euler–Maruyama steps of each prediction. Between two
//! observations the particles move S Euler–Maruyama steps of length h, each with the Gaussian
//! transition density `p(x' | x) = N(x'; x + f(x) h, Q h)`, `Q = G Gᵀ`; along those steps the
//! filtering distribution is the moved cloud with the weights of the last observation. The
//! backward pass draws M trajectories: the last point from the final weights, then each
//! earlier point among the cloud before it with probability
//! `∝ w^i N(x' ; x^i + f(x^i) h, Q h)` (the backward kernel of the discretised chain), down to
//! the start. For a discrete-time model the steps are its transitions and the kernel is the
//! transition density itself, `∝ w^i N(x'; F(x^i), Q)` (or the mixture's density when w_k is
//! a Gaussian mixture); for a linear SDE, whose particles move by its exact transition, one
//! move per interval with the kernel `∝ w^i N(x'; Φ x^i + Γb, Q_Δ)` (`super::exact`). A driven model's moves are weighed with the model the forward pass froze
//! for them, from each step's recorded time and inputs. The smoothed mean and covariance at an observation time are those of the M
//! trajectories' points there: consistent for the discretised model's smoother, with an error of
//! order N^−½ from the particle clouds plus M^−½ from the trajectories. A step of length 0 (the update at τ₀) does not move
//! a trajectory.
//!
//! Cost: O(M N n²) per Euler–Maruyama step backward (every trajectory weighs every particle),
//! and n·N·S values kept per step. The density exists only for a nonsingular Q, so a model
//! whose noise drives fewer components than it has is refused — unless it is a linear SDE
//! whose drift carries the noise into every component (then `Q_Δ` is nonsingular).

use alloc::boxed::Box;
use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use rand::RngExt;

use super::Pf;
use crate::error::FilterError;
use crate::filters::smoothing::{no_smoother, SmoothedStep, Smoother, SmoothingPlan};
use crate::filters::{Estimate, Filter, Observation};
use crate::model::BatchScratch;
use crate::random::{rng_from_seed, SimRng};

/// One step of the forward pass.
#[derive(Clone, Debug)]
struct Record {
    /// Euler–Maruyama steps of the prediction (0: the step did not move) and their length.
    substeps: usize,
    h: f64,
    /// The clouds after 1, …, S − 1 Euler steps (n·N each).
    trail: Vec<f64>,
    /// Particles and log-weights after the step.
    particles: Vec<f64>,
    log_weights: Vec<f64>,
    /// A driven model's step: its length, time and inputs (the backward pass freezes the
    /// model for each of its moves as the forward pass did).
    inputs: Option<(f64, f64, Vec<f64>)>,
}

/// The FFBSi smoother of the particle filter (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Ffbsi {
    filter: Pf,
    start: (Vec<f64>, Vec<f64>),
    records: Vec<Record>,
    /// L⁻¹ with `Q = L Lᵀ`.
    whiten: DMatrix<f64>,
    rng: SimRng,
}

impl Pf {
    /// The FFBSi smoother from the filter's current state (see the module doc).
    pub(super) fn ffbsi(&self, plan: &SmoothingPlan) -> Result<Box<dyn Smoother>, FilterError> {
        let whiten = match &self.exact {
            // A linear SDE's exact transition: its covariance Q_Δ is nonsingular for every
            // Δ > 0 or for none (the pair (A, G) controllable), so one length tells.
            Some(exact) => {
                let mut exact = exact.clone();
                exact.over(1.0).whiten.clone().ok_or_else(|| {
                    no_smoother(
                        self.name(),
                        "FFBSi weighs backward draws with the exact transition density N(Φx + Γb, Q_Δ), and this model's Q_Δ is singular: the noise G never reaches some direction of the state",
                    )
                })?
            }
            None => self.euler_whitening()?,
        };
        let (n, count) = (self.model.n, self.params.particles);
        let substeps = match self.exact {
            Some(_) => 1,
            None => self.substeps.per_interval(),
        };
        let per_step = (n * substeps + 1) * count * core::mem::size_of::<f64>();
        plan.check(
            self.name(),
            per_step,
            "the particle clouds of every Euler step",
        )?;
        let mut filter = self.clone();
        filter.trail = Some(Vec::new());
        // The backward draws use a stream of their own, seeded from the filter's.
        let rng = rng_from_seed(filter.draws.derived_seed() ^ 0x9e37_79b9_7f4a_7c15);
        Ok(Box::new(Ffbsi {
            start: (filter.particles.clone(), filter.log_weights.clone()),
            filter,
            records: Vec::with_capacity(plan.steps),
            whiten,
            rng,
        }))
    }

    /// `L⁻¹` with `Q = G Gᵀ = L Lᵀ`, which whitens an Euler–Maruyama step's (or a map's)
    /// Gaussian transition; an error when Q depends on the state or is singular.
    fn euler_whitening(&self) -> Result<DMatrix<f64>, FilterError> {
        let q = self.model.process_noise();
        let q = q.constant().ok_or_else(|| {
            no_smoother(
                self.name(),
                "FFBSi here weighs backward draws with one Gaussian Euler–Maruyama transition density N(x + f h, Q h), and this model's Q = G(x) G(x)ᵀ depends on the state",
            )
        })?;
        let chol = q.clone().cholesky().ok_or_else(|| {
            no_smoother(
                self.name(),
                "FFBSi needs the transition density of the Euler–Maruyama step, and this model's diffusion G Gᵀ is singular",
            )
        })?;
        chol.l()
            .try_inverse()
            .ok_or(FilterError::NotPositiveDefinite {
                what: "diffusion G Gᵀ",
            })
    }
}

impl Filter for Ffbsi {
    crate::filters::smoothing::forward_pass!(filter);
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        if let Some(t) = &mut self.filter.trail {
            t.clear();
        }
        self.filter.step(obs)?;
        let (substeps, h) = match obs.dt > 0.0 {
            true => self.filter.moves(obs.dt)?,
            false => (0, 0.0),
        };
        self.records.push(Record {
            substeps,
            h,
            trail: self
                .filter
                .trail
                .as_ref()
                .map_or_else(Vec::new, |t| t.clone()),
            particles: self.filter.particles.clone(),
            log_weights: self.filter.log_weights.clone(),
            inputs: obs.inputs.map(|i| (obs.dt, i.t, i.u.to_vec())),
        });
        Ok(())
    }
}

/// Draws an index with probabilities `∝ exp(log_p)` (`log_p` is overwritten).
fn draw(log_p: &mut [f64], rng: &mut SimRng) -> usize {
    let max = log_p.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let mut total = 0.0;
    for v in log_p.iter_mut() {
        *v = libm::exp(*v - max);
        total += *v;
    }
    let mut u = rng.random::<f64>() * total;
    for (i, v) in log_p.iter().enumerate() {
        u -= v;
        if u <= 0.0 {
            return i;
        }
    }
    log_p.len() - 1
}

impl Ffbsi {
    /// The model of move `s` of a recorded step: the filter's own for an autonomous model; a
    /// driven one frozen as the forward pass froze it (a map's transition s at the time it
    /// reaches, an SDE's at the interval's midpoint).
    fn dynamics_of(
        &self,
        record: &Record,
        s: usize,
    ) -> Result<alloc::borrow::Cow<'_, crate::model::Model>, FilterError> {
        use alloc::borrow::Cow;
        let (Some(driven), Some((dt, t, u))) = (&self.filter.driven, &record.inputs) else {
            return Ok(Cow::Borrowed(&self.filter.model));
        };
        let inputs = Some(crate::model::Inputs { t: *t, u });
        if driven.is_discrete_time() {
            return Ok(Cow::Owned(
                driven
                    .transition_at(inputs, s, record.substeps)?
                    .into_owned(),
            ));
        }
        let obs = Observation::nothing(*dt).with_inputs(*t, u);
        let (dynamics, _) = obs.frozen(driven)?.expect("a driven model");
        Ok(Cow::Owned(dynamics))
    }

    /// Moves every trajectory in `points` (n·M, component-major) one Euler step back, onto
    /// the cloud `cloud` (n·N) with log-weights `log_w`: the backward kernel of the module doc.
    #[allow(clippy::too_many_arguments)]
    fn back_one(
        &mut self,
        dynamics: &crate::model::Model,
        cloud: &[f64],
        log_w: &[f64],
        h: f64,
        points: &mut [f64],
        drift: &mut Vec<f64>,
        scratch: &mut BatchScratch,
        log_p: &mut [f64],
    ) -> Result<(), FilterError> {
        let (n, count) = (dynamics.n, log_w.len());
        let m = points.len() / n;
        drift.resize(n * count, 0.0);
        let chosen = if let Some(exact) = &mut self.filter.exact {
            // The exact transition over the step: N(x'; Φ x_i + Γb, Q_Δ).
            let t = exact.over(h);
            super::exact::means(t, cloud, drift);
            let whiten = t.whiten.clone().ok_or_else(|| {
                no_smoother(
                    self.filter.name(),
                    "the exact transition's covariance Q_Δ is singular over this step",
                )
            })?;
            back_gaussian(
                &whiten,
                0.5,
                (points, m),
                drift,
                log_w,
                log_p,
                &mut self.rng,
            )
        } else {
            dynamics.drift.eval_batch(cloud, drift, scratch);
            match dynamics.transition_mixture.clone() {
                Some(noise) => self.back_mixture(noise.mixture(), (points, m), drift, log_w, log_p),
                None => {
                    // The Euler step's mean x_i + f(x_i) h, or a map's F(x_i) itself (h = 1).
                    if !dynamics.is_discrete_time() {
                        drift
                            .iter_mut()
                            .zip(cloud)
                            .for_each(|(d, x)| *d = x + *d * h);
                    }
                    back_gaussian(
                        &self.whiten,
                        0.5 / h,
                        (points, m),
                        drift,
                        log_w,
                        log_p,
                        &mut self.rng,
                    )
                }
            }
        };
        for (t, &i) in chosen.iter().enumerate() {
            for j in 0..n {
                points[j * m + t] = cloud[j * count + i];
            }
        }
        Ok(())
    }

    /// The backward draws of a discrete-time map whose noise is a Gaussian mixture: the
    /// transition density `Σ_c π_c N(x' − F(x_i); μ_c, Q_c)` at every pair.
    fn back_mixture(
        &mut self,
        noise: &crate::model::GaussianMixture,
        (points, m): (&[f64], usize),
        drift: &[f64],
        log_w: &[f64],
        log_p: &mut [f64],
    ) -> Vec<usize> {
        let (n, count) = (self.filter.model.n, log_w.len());
        let (mut r, mut work) = (vec![0.0; n], vec![0.0; n]);
        let mut chosen = vec![0usize; m];
        for (t, pick) in chosen.iter_mut().enumerate() {
            for (i, lp) in log_p.iter_mut().enumerate() {
                for (j, r) in r.iter_mut().enumerate() {
                    *r = points[j * m + t] - drift[j * count + i];
                }
                *lp = log_w[i] + noise.log_pdf_slice(&r, &mut work);
            }
            *pick = draw(log_p, &mut self.rng);
        }
        chosen
    }
}

/// The backward draws of a Gaussian transition kernel whose means at the particles are
/// `centres` (n·N, overwritten): `N(x'; centre_i, C)` with `whiten = L⁻¹` of a factor of
/// `C = L Lᵀ / (2 scale)` — `Q h` of an Euler step (scale ½h⁻¹), a map's Q or the exact
/// transition's `Q_Δ` (scale ½). One particle index per trajectory point.
fn back_gaussian(
    whiten: &DMatrix<f64>,
    scale: f64,
    (points, m): (&[f64], usize),
    centres: &mut [f64],
    log_w: &[f64],
    log_p: &mut [f64],
    rng: &mut SimRng,
) -> Vec<usize> {
    let (n, count) = (whiten.nrows(), log_w.len());
    // The whitened means, once per particle; each trajectory's point is whitened once too,
    // and the exponent of a pair is then a squared distance.
    let mut centre = DVector::zeros(n);
    let mut white = DVector::zeros(n);
    for i in 0..count {
        for j in 0..n {
            centre[j] = centres[j * count + i];
        }
        white.gemv(1.0, whiten, &centre, 0.0);
        for j in 0..n {
            centres[j * count + i] = white[j];
        }
    }
    let mut chosen = vec![0usize; m];
    for (t, pick) in chosen.iter_mut().enumerate() {
        for j in 0..n {
            centre[j] = points[j * m + t];
        }
        white.gemv(1.0, whiten, &centre, 0.0);
        log_p.copy_from_slice(log_w);
        for j in 0..n {
            let w = white[j];
            for (lp, &mean) in log_p.iter_mut().zip(&centres[j * count..(j + 1) * count]) {
                let d = w - mean;
                *lp -= scale * d * d;
            }
        }
        *pick = draw(log_p, rng);
    }
    chosen
}

/// The mean and covariance of `points` (n·M, component-major).
fn moments(points: &[f64], n: usize, out: &mut Estimate) {
    let m = points.len() / n;
    for j in 0..n {
        out.mean[j] = points[j * m..(j + 1) * m].iter().sum::<f64>() / m as f64;
    }
    let mut cov = DMatrix::zeros(n, n);
    for a in 0..n {
        for b in 0..=a {
            let (ma, mb) = (out.mean[a], out.mean[b]);
            let c = (0..m)
                .map(|t| (points[a * m + t] - ma) * (points[b * m + t] - mb))
                .sum::<f64>()
                / m as f64;
            cov[(a, b)] = c;
            cov[(b, a)] = c;
        }
    }
    out.covariance = Some(cov);
}

impl Smoother for Ffbsi {
    fn smooth(&mut self, visit: &mut dyn FnMut(SmoothedStep<'_>)) -> Result<(), FilterError> {
        let (n, count) = (self.filter.model.n, self.filter.params.particles);
        let m = self.filter.params.trajectories;
        let last = self.records.len();
        let mut estimate = Estimate::zeros(n);
        let mut points = vec![0.0; n * m];
        let mut log_p = vec![0.0; count];
        // The last points, from the final weights.
        let (particles, log_w) = match self.records.last() {
            Some(r) => (r.particles.clone(), r.log_weights.clone()),
            None => self.start.clone(),
        };
        for t in 0..m {
            log_p.copy_from_slice(&log_w);
            let i = draw(&mut log_p, &mut self.rng);
            for j in 0..n {
                points[j * m + t] = particles[j * count + i];
            }
        }
        moments(&points, n, &mut estimate);
        visit(SmoothedStep {
            index: last,
            estimate: &estimate,
            density: None,
        });
        let mut drift = Vec::new();
        let mut scratch = BatchScratch::default();
        // An autonomous model's moves all have the filter's own model (cloned once).
        let own = self.filter.model.clone();
        for k in (0..last).rev() {
            let record = self.records[k].clone();
            if record.substeps > 0 {
                let (before, before_w) = match k {
                    0 => self.start.clone(),
                    _ => (
                        self.records[k - 1].particles.clone(),
                        self.records[k - 1].log_weights.clone(),
                    ),
                };
                // Back through the clouds after S − 1, …, 1 Euler steps, then the cloud the
                // step started from; all carry the weights of the step's start.
                for s in (0..record.substeps).rev() {
                    let cloud = match s {
                        0 => &before[..],
                        _ => &record.trail[(s - 1) * n * count..s * n * count],
                    };
                    let frozen = match self.filter.driven.is_some() {
                        true => Some(self.dynamics_of(&record, s)?.into_owned()),
                        false => None,
                    };
                    self.back_one(
                        frozen.as_ref().unwrap_or(&own),
                        cloud,
                        &before_w,
                        record.h,
                        &mut points,
                        &mut drift,
                        &mut scratch,
                        &mut log_p,
                    )?;
                }
            }
            if points.iter().any(|v| !v.is_finite()) {
                return Err(FilterError::NonFinite {
                    what: "smoothed trajectories",
                });
            }
            moments(&points, n, &mut estimate);
            visit(SmoothedStep {
                index: k,
                estimate: &estimate,
                density: None,
            });
        }
        Ok(())
    }

    fn notes(&self) -> Vec<String> {
        let (count, m) = (
            self.filter.params.particles,
            self.filter.params.trajectories,
        );
        let moves: usize = self.records.iter().map(|r| r.substeps).sum();
        let kind = match self.filter.model.is_discrete_time() {
            true => "transitions",
            false => "Euler–Maruyama steps",
        };
        vec![format!(
            "FFBSi: {m} trajectories through {count} particles over {moves} {kind} ({:.2e} kernel evaluations); Monte Carlo error ~ 1/√{m}",
            (m * count * moves) as f64
        )]
    }
}
