//! The observation's likelihood as the grid and particle filters multiply it in: the noise
//! density of the observed components (marginals for missing ones), `p(z | x)` of a
//! measurement (001 (3), (6)–(7)), and the observation factor of an increment (000 (2)).

use alloc::vec::Vec;

use super::Observation;
use crate::error::FilterError;

/// The observation noise density of the components an observation has (001's mixtures, or a
/// Gaussian), with the marginal of each pattern of missing components met so far: built the
/// first time a pattern occurs, so a recording with gaps allocates only then.
#[derive(Clone, Debug)]
pub(crate) struct ObservedNoise {
    full: crate::model::GaussianMixture,
    marginals: Vec<(Vec<bool>, crate::model::GaussianMixture)>,
}

impl ObservedNoise {
    /// Over the density of every component.
    pub(crate) fn new(full: crate::model::GaussianMixture) -> Self {
        ObservedNoise {
            full,
            marginals: Vec::new(),
        }
    }

    /// The density of the components of `value` that are not missing.
    pub(crate) fn of(
        &mut self,
        value: &[f64],
    ) -> Result<&crate::model::GaussianMixture, FilterError> {
        let pattern = self.pattern_of(value)?;
        Ok(self.density(pattern))
    }

    /// Which density [`ObservedNoise::of`] gives for `value`: `None` for the full one, else
    /// the index of the marginal of its pattern of missing components (made the first time).
    pub(crate) fn pattern_of(&mut self, value: &[f64]) -> Result<Option<usize>, FilterError> {
        let seen = |v: &f64| !Observation::is_missing(*v);
        if value.iter().all(seen) {
            return Ok(None);
        }
        let found = self
            .marginals
            .iter()
            .position(|(pattern, _)| pattern.iter().zip(value).all(|(p, v)| *p == seen(v)));
        Ok(Some(match found {
            Some(i) => i,
            None => {
                let pattern: Vec<bool> = value.iter().map(seen).collect();
                let marginal =
                    self.full
                        .marginal(&pattern)
                        .map_err(|_| FilterError::NotPositiveDefinite {
                            what: "noise covariance of the observed components",
                        })?;
                self.marginals.push((pattern, marginal));
                self.marginals.len() - 1
            }
        }))
    }

    /// The density of a pattern from [`ObservedNoise::pattern_of`].
    pub(crate) fn density(&self, pattern: Option<usize>) -> &crate::model::GaussianMixture {
        match pattern {
            None => &self.full,
            Some(i) => &self.marginals[i].1,
        }
    }
}

/// The likelihood `x ↦ p(z | x)` of a measurement's observed components, as the grid and
/// particle filters multiply it in (Bayes' rule, 001 (3); on the grid 001 (6)–(7)): additive noise through the
/// marginal density of each pattern of missing components ([`ObservedNoise`]), the other
/// [`MeasurementDensity`](crate::model::MeasurementDensity) families component by component.
#[derive(Clone, Debug)]
pub(crate) struct MeasurementLikelihood {
    density: crate::model::MeasurementDensity,
    noise: Option<ObservedNoise>,
    /// The marginal of the current observation's pattern ([`MeasurementLikelihood::check`]).
    pattern: Option<usize>,
    /// Student-t's log normalising constant, computed once.
    constant: f64,
    residual: Vec<f64>,
    work: Vec<f64>,
}

impl MeasurementLikelihood {
    /// For `density` and `m` measurement components.
    pub(crate) fn new(density: &crate::model::MeasurementDensity, m: usize) -> Self {
        MeasurementLikelihood {
            density: density.clone(),
            noise: density.additive().cloned().map(ObservedNoise::new),
            pattern: None,
            constant: match density {
                crate::model::MeasurementDensity::StudentT { dof, scale } => {
                    crate::model::measurement::student_t_log_constant(*dof, *scale)
                }
                _ => 0.0,
            },
            residual: alloc::vec![0.0; m],
            work: alloc::vec![0.0; m],
        }
    }

    /// Whether [`MeasurementLikelihood::log_at`] reads the state x itself (a variance s(x), a
    /// log-density, and the place a Poisson rate is negative, for its message), not only h(x).
    pub(crate) fn reads_state(&self) -> bool {
        !matches!(
            self.density,
            crate::model::MeasurementDensity::Additive(_)
                | crate::model::MeasurementDensity::StudentT { .. }
        )
    }

    /// Refuses a measurement its family cannot produce (a count that is not a nonnegative
    /// integer, a log-density's measurement with some components missing) before anything
    /// moves, and prepares for it (the marginal noise density of its observed components,
    /// made the first time its pattern occurs); `name` is the filter's.
    pub(crate) fn check(&mut self, name: &str, z: &[f64]) -> Result<(), FilterError> {
        self.density
            .check_value(z)
            .map_err(|e| FilterError::BadObservation(alloc::format!("{name}: {e}")))?;
        if let Some(noise) = &mut self.noise {
            self.pattern = noise.pattern_of(z)?;
        }
        Ok(())
    }

    /// For additive noise, the density of the observed components of the `z` last given to
    /// [`MeasurementLikelihood::check`] (its marginal when some are missing), for a filter
    /// that forms the residuals z − h(x) itself, in a batch; `None` for the other families.
    pub(crate) fn additive_density(&self) -> Option<&crate::model::GaussianMixture> {
        self.noise.as_ref().map(|n| n.density(self.pattern))
    }

    /// `ln p(z | x)` of the observed components of `z` (NaN = missing), with `hx = h(x)`,
    /// for the `z` last given to [`MeasurementLikelihood::check`]; `x` is read only when
    /// [`MeasurementLikelihood::reads_state`].
    pub(crate) fn log_at(&mut self, z: &[f64], x: &[f64], hx: &[f64]) -> Result<f64, FilterError> {
        match &self.noise {
            Some(noise) => {
                let k = observed_residual(z, |a| z[a] - hx[a], &mut self.residual);
                Ok(noise
                    .density(self.pattern)
                    .log_pdf_slice(&self.residual[..k], &mut self.work))
            }
            None => match &self.density {
                crate::model::MeasurementDensity::StudentT { dof, scale } => {
                    Ok(crate::model::measurement::student_t_log_density(
                        z,
                        hx,
                        *dof,
                        *scale,
                        self.constant,
                    ))
                }
                density => density
                    .log_likelihood(z, x, hx, &mut self.work)
                    .map_err(FilterError::Likelihood),
            },
        }
    }
}

/// Writes `residual(a)` of the observed components `a` of `value` (NaN = missing) one after
/// another into `out`; returns how many.
pub(crate) fn observed_residual(
    value: &[f64],
    mut residual: impl FnMut(usize) -> f64,
    out: &mut [f64],
) -> usize {
    let mut k = 0;
    for (a, v) in value.iter().enumerate() {
        if !Observation::is_missing(*v) {
            out[k] = residual(a);
            k += 1;
        }
    }
    k
}
/// The log-likelihood of `obs` at each state of `states`, up to a constant in the state: for
/// an increment Δy over Δt, `hᵀS⁻¹Δy − ½hᵀS⁻¹h Δt` (the observation factor of the Yau–Yau
/// method, 000 (2) with S); for a measurement z, `log p(z | x)` (001 (6): `log p_v(z − h(x))`
/// for additive noise). `None` when a component of `obs` is missing, S is singular or the
/// measurement density is undefined at one of the states. What multiplies the predicted density into
/// the posterior (the update half of a step, for display).
pub fn observation_log_likelihoods(
    model: &crate::model::Model,
    states: &[Vec<f64>],
    obs: &Observation,
) -> Option<Vec<f64>> {
    if obs.value.iter().any(|v| !v.is_finite()) || obs.value.len() != model.m {
        return None;
    }
    // A driven model's measurement at the observation's time and inputs.
    let frozen = obs.frozen(model).ok()?;
    let model = frozen
        .as_ref()
        .map_or(model, |(_, measurement)| measurement);
    let mut hx = alloc::vec![0.0; model.m];
    match &model.observations {
        crate::model::ObservationModel::Continuous { noise_cov } => {
            let s_inv = noise_cov.clone().try_inverse()?;
            let dy = nalgebra::DVector::from_column_slice(obs.value);
            let s_inv_dy = &s_inv * dy;
            Some(
                states
                    .iter()
                    .map(|x| {
                        model.observation.eval(x, &mut hx);
                        let h = nalgebra::DVector::from_column_slice(&hx);
                        h.dot(&s_inv_dy) - 0.5 * h.dot(&(&s_inv * &h)) * obs.dt
                    })
                    .collect(),
            )
        }
        crate::model::ObservationModel::Discrete { density } => {
            let mut scratch = Vec::new();
            states
                .iter()
                .map(|x| {
                    model.observation.eval(x, &mut hx);
                    density.log_likelihood(obs.value, x, &hx, &mut scratch).ok()
                })
                .collect()
        }
    }
}
