//! The extended Kalman filter ([`Ekf`] documents it).

use alloc::string::String;

use super::measurement::MeasurementForm;
use super::{EkfParams, GaussianState};
use crate::error::FilterError;
use crate::filters::{Filter, Observation};
use crate::model::Model;

/// The extended Kalman filter.
///
/// The continuous–discrete extended Kalman filter (Jazwinski): between observations the mean
/// and covariance follow the linearised moment equations (`rk4_moments`);
/// at each observation the update linearises h at the predicted mean. This is the EKF that
/// 000 §4.2, 002 §4.2 and 004 §4 compare against.
///
/// # Example
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::{Ekf, Filter, Model, Noise};
///
/// // dx = −x³ dt + dv, z_k = x_k + v_k (Var v = 0.1) every 0.1.
/// let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut ekf = Ekf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
/// for z in [0.3, 0.5, 0.4] {
///     ekf.step_measurement(0.1, &[z]).unwrap();
/// }
/// let estimate = ekf.estimate();
/// assert!(estimate.mean[0] > 0.0 && estimate.variance(0) < 1.0);
/// # }
/// ```
///
/// # Cost
///
/// Per step, the RK4 substeps of the moment equations (each stage evaluates f, its Jacobian and
/// a few n × n products) and one update with an m × m solve: O(substeps · n³ + m³); no
/// allocation after construction.
///
/// # When it fails
///
/// Where f or h bends across the spread of the prior or posterior the linearisation is wrong,
/// and nothing in the Gaussian says so: with h = x³ started at x̂ = 0 the gain `H = h′(0) = 0`
/// and the filter never moves (docs/guide.md, "Fitting a model's parameters"); on the cubic
/// sensor it loses the state (the playground's lesson 3); a posterior with two modes (h = x²
/// with a prior straddling 0) is carried as one Gaussian. Its self-check watches the innovations
/// ([`crate::Filter::self_check`]).
#[derive(Clone, Debug)]
pub struct Ekf {
    name: String,
    model: Model,
    q: crate::model::ProcessNoise,
    form: MeasurementForm,
    substeps: crate::filters::Substeps,
    state: GaussianState,
}

impl Ekf {
    /// Builds the filter from the model and the prior's moments, for observation interval
    /// Δτ when the context has one (a step of another length then takes as many RK4 steps of
    /// at most Δτ/substeps as it needs); fails for measurements without the two moments its
    /// update needs (`MeasurementForm::new`).
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &EkfParams,
    ) -> Result<Self, crate::error::FilterError> {
        let (model, prior) = (ctx.model, ctx.prior);
        Ok(Ekf {
            form: MeasurementForm::new(&name, model)?,
            name,
            model: model.clone(),
            q: model.process_noise(),
            substeps: crate::filters::Substeps::new(params.substeps, ctx.dt_obs),
            state: GaussianState::initial(prior.mean(), prior.covariance(), &params.init, model.m)
                .with_affine_map(model, ctx.probes),
        })
    }
}

super::smoother::gaussian_filter!(Ekf);

impl Filter for Ekf {
    super::smoother::gaussian_filter_opening!(estimate);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let Ekf {
            name,
            model,
            q,
            form,
            substeps,
            state,
        } = self;
        let mut driven = super::DrivenStep::of(name, model, obs)?;
        let (step, form) = super::DrivenStep::parts(&mut driven, (model, obs.inputs), q, form);
        state.transaction(|state| {
            let steps = substeps.over(obs.dt);
            match state.predict_then_measure(name, &step, steps, form, obs)? {
                Some(meas) => state.linearized_update(step.measurement, meas),
                None => Ok(()),
            }
        })
    }

    fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
        super::approximations(&self.form, &self.q, &self.model, &self.name)
    }

    fn self_check(&self, out: &mut alloc::vec::Vec<crate::filters::Concern>) {
        self.state.innovations.check(out);
    }
}
