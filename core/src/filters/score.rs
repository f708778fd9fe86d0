//! The gradient of a filter's log-likelihood in the parameters a model was built from (the
//! score), for the methods that can give it from one forward and one backward pass
//! ([`super::Filter::score`]).
//!
//! A filter is built at a point θ; the model's dependence on each parameter θ_p comes as the
//! model and prior built at two points `θ − h e_p`, `θ + h e_p` around it
//! ([`Perturbation`]). A method differentiates its own recursion exactly (reverse mode,
//! Fisher's identity on a grid) and takes from the two models only the derivatives of the
//! model's functions — F, Q, ln p(z | x), ln p₀ at its nodes — as central differences of
//! those functions, which are smooth in θ where the likelihood's discretisation is not (a
//! grid window's extent, a step count): the score is then the derivative of the method's own
//! ln L up to the rounding of those differences (about 10⁻⁹ relative for h ≈ 10⁻⁵ of θ's
//! scale), where differencing ln L itself is not.

use crate::model::{Model, Prior};

/// The model and prior at `θ − h e_p` and `θ + h e_p`, for one parameter p: `width` is the
/// distance between the two points (2h, or less where a bound cut one side).
#[derive(Clone, Debug)]
pub struct Perturbation {
    /// The model and prior at the lower point.
    pub below: (Model, Prior),
    /// The model and prior at the upper point.
    pub above: (Model, Prior),
    /// The distance between the two points in θ_p.
    pub width: f64,
    /// Whether the measurement's density p(z | x) depends on the parameter (its derivative,
    /// a tabulation at both points for every measurement, is skipped when it does not).
    pub measurement: bool,
}

/// ln p(z_0, …, z_N | θ) and its gradient in θ, one entry per [`Perturbation`].
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    /// The log-likelihood.
    pub log_likelihood: f64,
    /// Its gradient.
    pub gradient: alloc::vec::Vec<f64>,
}

/// The [`super::Filter::score`] of a filter whose own `score_of(observations, perturbed)` gives
/// it, expanded inside its `impl Filter`.
macro_rules! score_of_filter {
    () => {
        fn score(
            &self,
            observations: &[crate::filters::Observation<'_>],
            perturbed: &[crate::filters::Perturbation],
        ) -> Option<Result<crate::filters::Score, crate::error::FilterError>> {
            Some(self.score_of(observations, perturbed))
        }
    };
}
pub(crate) use score_of_filter;

/// The error of a score asked of a driven model's filter (`driven`), which no method gives
/// yet: its pieces change with the time and inputs at every step.
pub(crate) fn refuse_driven(name: &str, driven: bool) -> Result<(), crate::error::FilterError> {
    match driven {
        false => Ok(()),
        true => Err(crate::error::FilterError::Unsuitable(alloc::format!(
            "{name}: the gradient of its likelihood is not implemented for a model that reads the time or inputs"
        ))),
    }
}
