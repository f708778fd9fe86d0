//! What a filter consumes: one [`Observation`] per step — how far to predict, then an
//! increment of a continuous observation (000 (1)) or a discrete measurement (001 (1)), with
//! missing components as NaN and, for a driven model, its time and known inputs.

use crate::error::FilterError;

/// What an observation row means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObservationKind {
    /// Δy = y(τ_k) − y(τ_{k−1}) of a continuous observation dy = h dt + dw.
    Increment,
    /// z_k = h(x_k) + v_k of a discrete measurement.
    Measurement,
}

/// One observation, handed to every filter in turn: how far to predict, then what to
/// assimilate.
#[derive(Clone, Copy, Debug)]
pub struct Observation<'a> {
    /// τ_k − τ_{k−1}: how far to predict before using `value`. 0 assimilates without
    /// predicting (a measurement at the prior's time τ₀).
    pub dt: f64,
    /// The increment or measurement (length m).
    pub value: &'a [f64],
    /// Increment or measurement.
    pub kind: ObservationKind,
    /// The time τ_k and the known inputs over the interval ending at it, for a driven model
    /// ([`crate::Inputs`]); `None` for an autonomous one.
    pub inputs: Option<crate::model::Inputs<'a>>,
}

impl<'a> Observation<'a> {
    /// An increment Δy = y(τ_k) − y(τ_{k−1}) of a continuous observation, after `dt`.
    pub fn increment(dt: f64, dy: &'a [f64]) -> Self {
        Observation {
            dt,
            value: dy,
            kind: ObservationKind::Increment,
            inputs: None,
        }
    }
    /// A measurement z_k = h(x_k) + v_k, `dt` after the previous one (0 at the prior's time).
    pub fn measurement(dt: f64, z: &'a [f64]) -> Self {
        Observation {
            dt,
            value: z,
            kind: ObservationKind::Measurement,
            inputs: None,
        }
    }

    /// The same observation at time `t` = τ_k with the known inputs `u` over the interval
    /// ending at it, for a driven model ([`crate::Inputs`]).
    pub fn with_inputs(self, t: f64, u: &'a [f64]) -> Self {
        Observation {
            inputs: Some(crate::model::Inputs { t, u }),
            ..self
        }
    }
}
/// Which components of an [`Observation`] were observed (see [`Observation::check`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observed {
    /// None: the step is a prediction only (an empty value, or every component missing).
    Nothing,
    /// Every component.
    All,
    /// Some components are missing (NaN) and the others observed.
    Some,
}

impl Observation<'_> {
    /// A prediction over `dt` with nothing to assimilate (a gap in the recording, or a
    /// forecast): what [`Filter::predict`](super::Filter::predict) steps with.
    pub fn nothing(dt: f64) -> Observation<'static> {
        Observation {
            dt,
            value: &[],
            kind: ObservationKind::Measurement,
            inputs: None,
        }
    }

    /// The two models a step over this observation uses, for a driven `model`
    /// ([`crate::Inputs`]): the dynamics' at the interval's midpoint (a discrete-time map's
    /// at its end, the time its transition reaches) and the
    /// measurement's at its end (an increment's, over the interval, is the dynamics'), both
    /// with the observation's inputs. `None` for an autonomous model; an error when a driven
    /// model's observation carries no inputs, or inputs that do not fit it.
    pub fn frozen(
        &self,
        model: &crate::model::Model,
    ) -> Result<Option<(crate::model::Model, crate::model::Model)>, FilterError> {
        if !model.is_driven() {
            return Ok(None);
        }
        let Some(crate::model::Inputs { t, u }) = self.inputs else {
            return Err(FilterError::BadObservation(
                "the model reads the time t and known inputs: give each step the observation's time and inputs (Observation::with_inputs)".into(),
            ));
        };
        // A discrete-time map's transition reaches τ_k and reads its time.
        let at = match model.is_discrete_time() {
            true => t,
            false => t - 0.5 * self.dt,
        };
        let dynamics = model.at(at, u)?;
        let measurement = match self.kind {
            ObservationKind::Increment => dynamics.clone(),
            ObservationKind::Measurement => model.at(t, u)?,
        };
        Ok(Some((dynamics, measurement)))
    }

    /// The same interval (with its time and inputs) with nothing observed: the prediction
    /// half of this step.
    pub fn predicting(&self) -> Observation<'_> {
        Observation {
            value: &[],
            kind: ObservationKind::Measurement,
            ..*self
        }
    }

    /// Whether a component's value marks it missing: NaN is the missing marker (as in
    /// pandas and statsmodels); ±∞ is an error, never a marker.
    pub fn is_missing(value: f64) -> bool {
        value.is_nan()
    }

    /// Checks this observation for a filter `name` that takes observations of `kind` with `m`
    /// components, before anything moves: `dt` must be finite and nonnegative; the value must
    /// be empty (nothing observed) or of the filter's kind and length m, each component finite
    /// or NaN (missing). Returns which components were observed.
    pub fn check(
        &self,
        name: &str,
        kind: ObservationKind,
        m: usize,
    ) -> Result<Observed, FilterError> {
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(FilterError::BadObservation(alloc::format!(
                "{name}: the step Δτ must be finite and nonnegative, got {}",
                self.dt
            )));
        }
        if self.value.is_empty() {
            return Ok(Observed::Nothing);
        }
        if self.kind != kind || self.value.len() != m {
            let what = match kind {
                ObservationKind::Increment => "increments",
                ObservationKind::Measurement => "measurements z_k",
            };
            return Err(FilterError::BadObservation(alloc::format!(
                "{name} needs {what} of length {m}"
            )));
        }
        if let Some(i) = self.value.iter().position(|v| v.is_infinite()) {
            return Err(FilterError::BadObservation(alloc::format!(
                "{name}: component {} of the observation is {} (NaN marks a missing component; infinities are not values)",
                i + 1,
                self.value[i]
            )));
        }
        let missing = self.value.iter().filter(|v| Self::is_missing(**v)).count();
        Ok(if missing == 0 {
            Observed::All
        } else if missing == m {
            Observed::Nothing
        } else {
            Observed::Some
        })
    }
}

/// The observation kind `model` makes (increments or measurements).
pub(crate) fn kind_of(model: &crate::model::Model) -> ObservationKind {
    match model.observations {
        crate::model::ObservationModel::Continuous { .. } => ObservationKind::Increment,
        crate::model::ObservationModel::Discrete { .. } => ObservationKind::Measurement,
    }
}
