//! The observation's likelihood as the grid and particle filters multiply it in: the noise
//! density of the observed components (marginals for missing ones), `p(z | x)` of a
//! measurement (001 (3), (6)–(7)), and the observation factor of an increment (000 (2)).

use alloc::vec::Vec;

use super::Observation;
use crate::error::FilterError;
use crate::model::expression::ExpressionFunction;
use crate::model::measurement::{
    ln_gamma, poisson_log_of_valid, rate_error, rate_is_valid, variance_error, variance_is_valid,
    variance_log_of_valid,
};
use crate::model::VectorFunction;

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
    /// A batch's inputs (a log-density's states and measurement) and outputs (s(x) or
    /// ln p(z | x) at every point), grown on first use.
    batch_in: Vec<f64>,
    batch_out: Vec<f64>,
    /// For a variance s(x) given as expressions: `ln s(x)` and `1/s(x)` compiled from them
    /// (for s = e^g, g and e^{−g}: no logarithm and no division per point, see
    /// `model::compile`), and their batch values.
    log_form: Option<alloc::boxed::Box<(ExpressionFunction, ExpressionFunction)>>,
    precisions: Vec<f64>,
}

impl MeasurementLikelihood {
    /// For `density` and `m` measurement components.
    pub(crate) fn new(density: &crate::model::MeasurementDensity, m: usize) -> Self {
        let mut likelihood = MeasurementLikelihood {
            density: density.clone(),
            noise: None,
            pattern: None,
            constant: 0.0,
            residual: alloc::vec![0.0; m],
            work: alloc::vec![0.0; m],
            batch_in: Vec::new(),
            batch_out: Vec::new(),
            log_form: None,
            precisions: Vec::new(),
        };
        likelihood.set_density(density);
        likelihood
    }

    /// The same storage for another `density` of as many components (a driven model's, frozen
    /// for the next step): what it computes once per density is computed again.
    pub(crate) fn set_density(&mut self, density: &crate::model::MeasurementDensity) {
        self.density = density.clone();
        self.noise = density.additive().cloned().map(ObservedNoise::new);
        self.pattern = None;
        self.constant = match density {
            crate::model::MeasurementDensity::StudentT { dof, scale } => {
                crate::model::measurement::student_t_log_constant(*dof, *scale)
            }
            _ => 0.0,
        };
        self.log_form = match density {
            crate::model::MeasurementDensity::Heteroscedastic(s) => {
                log_form(&**s).map(alloc::boxed::Box::new)
            }
            _ => None,
        };
    }

    /// Whether [`MeasurementLikelihood::add_batch`] takes this family.
    pub(crate) fn batches(&self) -> bool {
        matches!(
            self.density,
            crate::model::MeasurementDensity::Heteroscedastic(_)
                | crate::model::MeasurementDensity::LogDensity(_)
                | crate::model::MeasurementDensity::Poisson
                | crate::model::MeasurementDensity::StudentT { .. }
        )
    }

    /// Adds `ln p(z | x)` at every one of `count` points to `out`, as a batch: a variance s(x)
    /// or a log-density runs its compiled program one pass per operation over all the points,
    /// like h, instead of point by point; Poisson counts take ln Γ(z + 1) once per component.
    /// `points` (n·count) and `hx` (m·count) are in structure-of-arrays layout
    /// ([`crate::VectorFunction::eval_batch`]); Student-t's arithmetic runs in lanes. Returns
    /// false, adding nothing, for additive noise (which has its own batch in the filters,
    /// [`crate::GaussianMixture`]'s). The values and the messages are those of
    /// [`MeasurementLikelihood::log_at`]; where several points are bad, the one named is the
    /// first in component order (the pointwise path names the first point).
    pub(crate) fn add_batch(
        &mut self,
        z: &[f64],
        (points, hx, count): (&[f64], &[f64], usize),
        out: &mut [f64],
        scratch: &mut crate::model::BatchScratch,
    ) -> Result<bool, FilterError> {
        let point = |i: usize| -> Vec<f64> {
            let n = points.len() / count;
            (0..n).map(|j| points[j * count + i]).collect()
        };
        match &self.density {
            crate::model::MeasurementDensity::Heteroscedastic(s) => {
                let m = z.len();
                self.batch_out.resize(m * count, 0.0);
                if let Some(form) = &self.log_form {
                    let (log_s, precision) = &**form;
                    self.precisions.resize(m * count, 0.0);
                    log_s.eval_batch(points, &mut self.batch_out, scratch);
                    precision.eval_batch(points, &mut self.precisions, scratch);
                    for (j, &zj) in z.iter().enumerate() {
                        if Observation::is_missing(zj) {
                            continue;
                        }
                        let block = j * count..(j + 1) * count;
                        let (l, p) = (&self.batch_out[block.clone()], &self.precisions[block]);
                        if !all_valid_log_forms(l, p) {
                            let i = (0..count)
                                .position(|i| !log_form_is_valid(l[i], p[i]))
                                .unwrap_or(0);
                            let x = point(i);
                            return Err(FilterError::Likelihood(variance_error(
                                j,
                                s.value(&x)[j],
                                &x,
                            )));
                        }
                        add_log_form_logs(out, zj, &hx[j * count..(j + 1) * count], l, p);
                    }
                    return Ok(true);
                }
                s.eval_batch(points, &mut self.batch_out, scratch);
                for (j, &zj) in z.iter().enumerate() {
                    if Observation::is_missing(zj) {
                        continue;
                    }
                    let v = &self.batch_out[j * count..(j + 1) * count];
                    let h = &hx[j * count..(j + 1) * count];
                    if !all_valid_variances(v) {
                        let i = v.iter().position(|&v| !variance_is_valid(v)).unwrap_or(0);
                        return Err(FilterError::Likelihood(variance_error(j, v[i], &point(i))));
                    }
                    add_variance_logs(out, zj, h, v);
                }
                Ok(true)
            }
            crate::model::MeasurementDensity::LogDensity(l) => {
                if z.iter().all(|v| v.is_nan()) {
                    return Ok(true);
                }
                self.batch_out.resize(count, 0.0);
                // The states, then the measurement as constant rows (grown on first use).
                self.batch_in.clear();
                self.batch_in.extend_from_slice(points);
                for &zj in z {
                    self.batch_in.extend(core::iter::repeat_n(zj, count));
                }
                l.eval_batch(&self.batch_in, &mut self.batch_out, scratch);
                if !all_valid_log_densities(&self.batch_out) {
                    let i = self
                        .batch_out
                        .iter()
                        .position(|&v| !log_density_is_valid(v))
                        .unwrap_or(0);
                    return Err(FilterError::Likelihood(alloc::format!(
                        "the log-density is {} at x = {:?}, z = {z:?}",
                        self.batch_out[i],
                        point(i)
                    )));
                }
                crate::linalg::add_in_place(out, &self.batch_out);
                Ok(true)
            }
            crate::model::MeasurementDensity::StudentT { dof, scale } => {
                for (j, &zj) in z.iter().enumerate() {
                    if !Observation::is_missing(zj) {
                        let h = &hx[j * count..(j + 1) * count];
                        add_student_t_logs(out, zj, h, (*dof, *scale), self.constant);
                    }
                }
                Ok(true)
            }
            crate::model::MeasurementDensity::Poisson => {
                // ln Γ(z + 1) once per component, not once per point.
                for (j, &zj) in z.iter().enumerate() {
                    if Observation::is_missing(zj) {
                        continue;
                    }
                    let log_factorial = ln_gamma(zj + 1.0);
                    let rates = &hx[j * count..(j + 1) * count];
                    if !all_valid_rates(rates) {
                        let i = rates.iter().position(|&r| !rate_is_valid(r)).unwrap_or(0);
                        return Err(FilterError::Likelihood(rate_error(j, rates[i], &point(i))));
                    }
                    add_poisson_logs(out, zj, rates, log_factorial);
                }
                Ok(true)
            }
            _ => Ok(false),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::expression::ExpressionFunction;
    use crate::model::syntax::Variables;
    use crate::model::MeasurementDensity;
    use crate::testing::test;
    use alloc::string::String;
    use alloc::sync::Arc;
    use alloc::{format, vec};

    /// The batch (one pass of the programs of ln s(x) and 1/s(x), or of the log-density's, over
    /// the points; Poisson's ln Γ once per component; Student-t's arithmetic
    /// in lanes) gives what the point-by-point path gives
    /// to 10⁻¹², at 7 points of a 2-D
    /// state with 2 measurement components, a missing one included; and the same error when
    /// a variance is not positive.
    #[test]
    fn the_batch_likelihood_is_the_pointwise_one() {
        let text = |t: &[&str]| t.iter().map(|s| String::from(*s)).collect::<Vec<_>>();
        let state = Variables::state(2);
        let variance =
            ExpressionFunction::parse_in("s", &text(&["exp(x1)", "1 + x2^2"]), &state, 2).unwrap();
        let log_density = ExpressionFunction::parse_in(
            "l",
            &text(&["-abs(z1 - x1) - 0.5*(z2 - x2)^2 - log(2)"]),
            &Variables::state_and_measurement(2, 2),
            1,
        )
        .unwrap();
        let families = [
            MeasurementDensity::Heteroscedastic(Arc::new(variance)),
            MeasurementDensity::LogDensity(Arc::new(log_density)),
            MeasurementDensity::Poisson,
            MeasurementDensity::student_t(3.5, 0.7).unwrap(),
        ];
        let count = 7;
        let points: Vec<f64> = (0..2 * count).map(|k| 0.3 * k as f64 - 1.1).collect();
        let hx: Vec<f64> = (0..2 * count).map(|k| 0.2 + 0.25 * k as f64).collect();
        for density in families {
            let poisson = matches!(density, MeasurementDensity::Poisson);
            let values: [&[f64]; 2] = match poisson {
                true => [&[2.0, 0.0], &[3.0, f64::NAN]],
                false => [&[0.4, -0.7], &[1.3, f64::NAN]],
            };
            for z in values {
                if matches!(density, MeasurementDensity::LogDensity(_)) && z[1].is_nan() {
                    continue; // a log-density takes whole measurements only
                }
                let mut likelihood = MeasurementLikelihood::new(&density, 2);
                // A variance given as expressions is evaluated through ln s and 1/s.
                assert_eq!(
                    likelihood.log_form.is_some(),
                    matches!(density, MeasurementDensity::Heteroscedastic(_))
                );
                likelihood.check("test", z).unwrap();
                let mut batch = vec![0.5; count];
                let mut scratch = crate::model::BatchScratch::default();
                assert!(likelihood
                    .add_batch(z, (&points, &hx, count), &mut batch, &mut scratch)
                    .unwrap());
                for (i, b) in batch.iter().enumerate() {
                    let x = [points[i], points[count + i]];
                    let h = [hx[i], hx[count + i]];
                    let one = likelihood.log_at(z, &x, &h).unwrap();
                    assert!(
                        (b - 0.5 - one).abs() < 1e-12,
                        "{density:?} {z:?} {i}: {b} vs {one}"
                    );
                }
            }
        }
        // A variance that is not positive: the same message either way.
        let bad = ExpressionFunction::parse_in("s", &text(&["x1", "1"]), &state, 2).unwrap();
        let density = MeasurementDensity::Heteroscedastic(Arc::new(bad));
        let mut likelihood = MeasurementLikelihood::new(&density, 2);
        let z = [0.4, 0.1];
        likelihood.check("test", &z).unwrap();
        let e = likelihood
            .add_batch(
                &z,
                (&points, &hx, count),
                &mut vec![0.0; count],
                &mut Default::default(),
            )
            .unwrap_err();
        let one = likelihood
            .log_at(&z, &[points[0], points[count]], &[hx[0], hx[count]])
            .unwrap_err();
        assert_eq!(format!("{e}"), format!("{one}"));
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += ln N(z; h_i, v_i)` for variances already checked.
    fn add_variance_logs(out: &mut [f64], z: f64, h: &[f64], v: &[f64]) {
        for ((o, &h), &v) in out.iter_mut().zip(h).zip(v) {
            *o += variance_log_of_valid(z, h, v);
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += ln Poisson(z; rate_i)` for rates already checked.
    fn add_poisson_logs(out: &mut [f64], z: f64, rates: &[f64], log_factorial: f64) {
        for (o, &rate) in out.iter_mut().zip(rates) {
            *o += poisson_log_of_valid(z, rate, log_factorial);
        }
    }
}

/// `ln s(x)` and `1/s(x)` of a variance given as expressions, compiled from its texts (in the
/// state alone; `None` for a function of other variables or given as code).
fn log_form(
    s: &dyn crate::model::VectorFunction,
) -> Option<(ExpressionFunction, ExpressionFunction)> {
    let texts = s.expressions()?;
    let (n, m) = (s.input_dim(), s.output_dim());
    let wrap = |f: &str| -> Vec<alloc::string::String> {
        texts.iter().map(|t| alloc::format!("{f}({t})")).collect()
    };
    let log_s = ExpressionFunction::parse("ln s(x)", &wrap("ln"), n, m).ok()?;
    let precision = ExpressionFunction::parse("1/s(x)", &wrap("1/"), n, m).ok()?;
    Some((log_s, precision))
}

/// Whether `ln s` and `1/s` at a point come from a positive, finite variance (`ln s` finite,
/// `1/s` finite and not negative).
#[inline(always)]
fn log_form_is_valid(log_s: f64, precision: f64) -> bool {
    (log_s.abs() < f64::INFINITY) & (0.0..f64::INFINITY).contains(&precision)
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// Whether every point's `ln s` and `1/s` are valid ([`log_form_is_valid`]), in one pass.
    fn all_valid_log_forms(log_s: &[f64], precision: &[f64]) -> bool {
        log_s
            .iter()
            .zip(precision)
            .fold(true, |ok, (&l, &p)| ok & log_form_is_valid(l, p))
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += ln N(z; h_i, s_i) = −½ (ln 2π + ln s_i + (z − h_i)² / s_i)` from `ln s_i` and
    /// `1/s_i`, checked.
    fn add_log_form_logs(out: &mut [f64], z: f64, h: &[f64], log_s: &[f64], precision: &[f64]) {
        for (((o, &h), &l), &p) in out.iter_mut().zip(h).zip(log_s).zip(precision) {
            let r = z - h;
            *o += -0.5 * (crate::model::measurement::LN_TAU + l + r * r * p);
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// Whether every variance is positive and finite (a pass without an early exit, which
    /// vectorises; the caller finds the first bad one only when there is one).
    fn all_valid_variances(v: &[f64]) -> bool {
        v.iter().fold(true, |ok, &v| ok & variance_is_valid(v))
    }
}

/// Whether a log-density value can be used: not NaN and not +∞ (−∞ is a point the
/// measurement rules out).
#[inline(always)]
fn log_density_is_valid(v: f64) -> bool {
    (v < f64::INFINITY) | (v == f64::NEG_INFINITY)
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// Whether every log-density value is valid ([`log_density_is_valid`]), in one pass.
    fn all_valid_log_densities(v: &[f64]) -> bool {
        v.iter().fold(true, |ok, &v| ok & log_density_is_valid(v))
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += ln t_ν((z − h_i)/σ)/σ` (Student-t's log-density with its log normalising
    /// constant `constant`), as [`crate::model::measurement::student_t_log_density`] at
    /// one point.
    fn add_student_t_logs(out: &mut [f64], z: f64, h: &[f64], t: (f64, f64), constant: f64) {
        let (dof, scale) = t;
        for (o, &h) in out.iter_mut().zip(h) {
            *o += crate::model::measurement::student_t_log_term(z - h, dof, scale, constant);
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// Whether every Poisson rate is nonnegative and finite (as [`all_valid_variances`]).
    fn all_valid_rates(rates: &[f64]) -> bool {
        rates.iter().fold(true, |ok, &r| ok & rate_is_valid(r))
    }
}
