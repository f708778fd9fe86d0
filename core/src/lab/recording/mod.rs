//! Recorded observations: what the driver ([`crate::lab::experiment::Experiment`]) feeds every filter, whether
//! Zakai simulated them ([`Trajectory`] converts) or a user recorded them. The truth is
//! optional: without it a run reports estimates, covariances, failures and timings, with it
//! also errors against it.
//!
//! Layout (the same as [`Trajectory`]'s): times `τ_0 < τ_1 < … < τ_N`, where τ₀ is the time
//! the prior describes; observation row k is
//!
//! * for continuous observations `dy = h dt + dw`: the increment `y(τ_k) − y(τ_{k−1})` (row 0
//!   is the start and holds zeros);
//! * for discrete measurements `z_k = h(x_k) + v_k`: the measurement at τ_k (row 0 is a
//!   measurement at the prior's time, assimilated without a prediction).
//!
//! Missing data: a NaN component was not observed (an empty cell in a CSV file); a row whose
//! components are all NaN is a prediction to τ_k only. Times may be irregular: every method
//! predicts over τ_k − τ_{k−1} whatever its length (the grid and spectral filters as whole Δτ
//! with the operator made for Δτ, plus one remainder with an operator of its own).

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::simulate::Trajectory;
use crate::validate::ConfigProblem;

pub mod bits;
#[cfg(feature = "std")]
mod csv;
pub mod data_domain;

/// Which part of a recording a row problem is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    /// Times and observations.
    Observations,
    /// The true states.
    Truth,
}

/// Observations at known times, with the true states when they are known.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Recording {
    /// State dimension n.
    pub n: usize,
    /// Observation dimension m.
    pub m: usize,
    /// τ_0, …, τ_N.
    #[serde(with = "bits")]
    pub times: Vec<f64>,
    /// Row k at `observations[k*m..(k+1)*m]` (see the module doc; N + 1 rows).
    #[serde(with = "bits")]
    pub observations: Vec<f64>,
    /// Whether rows are increments of a continuous observation (else measurements).
    pub continuous: bool,
    /// The true states x(τ_k), row-major (N + 1 rows), when known.
    #[serde(with = "bits")]
    pub truth: Option<Vec<f64>>,
    /// k, the number of known inputs u1..uk on each row (0: none) of a driven model
    /// ([`crate::Inputs`]).
    #[serde(default)]
    pub input_count: usize,
    /// The known inputs, row k at `inputs[k*input_count..]`: those over `(τ_{k−1}, τ_k]`
    /// (N + 1 rows; row 0's are read by a measurement at τ₀).
    #[serde(default, with = "bits")]
    pub inputs: Vec<f64>,
}

pub use crate::filters::INTERVAL_TOLERANCE;

/// Whether a step of length `step` is the interval `dt_obs` up to [`INTERVAL_TOLERANCE`].
pub fn is_interval(step: f64, dt_obs: f64) -> bool {
    (step - dt_obs).abs() <= INTERVAL_TOLERANCE * dt_obs
}

impl Recording {
    /// Increments of a continuous observation: `times` = τ₀, …, τ_N (τ₀ the prior's time) and
    /// `dy` the N increments over `(τ_{k−1}, τ_k]`, row-major (N·m values) — observations
    /// only, the truth unknown. Checks everything at once ([`Recording::problems`]).
    pub fn increments(
        n: usize,
        m: usize,
        times: Vec<f64>,
        dy: &[f64],
    ) -> Result<Self, crate::ZakaiError> {
        let mut observations = alloc::vec![0.0; m];
        observations.extend_from_slice(dy);
        Recording {
            n,
            m,
            times,
            observations,
            continuous: true,
            truth: None,
            input_count: 0,
            inputs: Vec::new(),
        }
        .checked()
    }

    /// Measurements `z_k` at `times` (the first at the prior's time), row-major — the truth
    /// unknown. Checks everything at once ([`Recording::problems`]).
    pub fn measurements(
        n: usize,
        m: usize,
        times: Vec<f64>,
        z: &[f64],
    ) -> Result<Self, crate::ZakaiError> {
        Recording {
            n,
            m,
            times,
            observations: z.to_vec(),
            continuous: false,
            truth: None,
            input_count: 0,
            inputs: Vec::new(),
        }
        .checked()
    }

    /// With the known inputs of a driven model ([`crate::Inputs`]): `count` per row,
    /// row-major, one row per time (those over the interval ending at it), every one finite.
    pub fn with_inputs(
        mut self,
        count: usize,
        inputs: Vec<f64>,
    ) -> Result<Self, crate::ZakaiError> {
        self.input_count = count;
        self.inputs = inputs;
        self.checked()
    }

    /// The known inputs of row k (empty when the recording has none).
    pub fn inputs_at(&self, k: usize) -> &[f64] {
        let c = self.input_count;
        &self.inputs[k * c..(k + 1) * c]
    }

    /// With the true states (row-major, one row per time).
    pub fn with_truth(mut self, truth: Vec<f64>) -> Result<Self, crate::ZakaiError> {
        self.truth = Some(truth);
        self.checked()
    }

    fn checked(self) -> Result<Self, crate::ZakaiError> {
        let problems = self.problems();
        if problems.is_empty() {
            Ok(self)
        } else {
            Err(crate::ZakaiError::Config(problems))
        }
    }

    /// Appends the observation `value` at time `t` (a recording that grows as a sensor reports):
    /// refused, the recording left as it was, when t is not finite or does not follow the last
    /// time, the row does not have m components or has an infinite one (NaN marks a missing
    /// component), or the recording holds the truth (the new row would have none).
    pub fn push(&mut self, t: f64, value: &[f64]) -> Result<(), crate::ZakaiError> {
        self.push_with_inputs(t, value, &[])
    }

    /// [`Recording::push`] with the known inputs `u` over the interval ending at `t` (as many
    /// as the recording's [`Recording::input_count`], every one finite).
    pub fn push_with_inputs(
        &mut self,
        t: f64,
        value: &[f64],
        u: &[f64],
    ) -> Result<(), crate::ZakaiError> {
        let mut p = Vec::new();
        if u.len() != self.input_count || u.iter().any(|v| !v.is_finite()) {
            p.push(ConfigProblem::new(
                "inputs",
                format!("needs k = {} finite inputs, got {:?}", self.input_count, u),
            ));
        }
        let last = self.times.last().copied().unwrap_or(f64::NEG_INFINITY);
        if !(t.is_finite() && t > last) {
            p.push(ConfigProblem::new(
                "t",
                format!("must be finite and after the last time {last}, got {t}"),
            ));
        }
        if value.len() != self.m {
            p.push(ConfigProblem::new(
                "observation",
                format!("needs m = {} values, got {}", self.m, value.len()),
            ));
        } else if let Some(j) = value.iter().position(|v| v.is_infinite()) {
            p.push(ConfigProblem::new(
                "observation",
                format!("component {}: infinite (a missing value is NaN)", j + 1),
            ));
        }
        if self.truth.is_some() {
            p.push(ConfigProblem::new(
                "truth",
                "the recording holds the true states, which a new row would not have",
            ));
        }
        if !p.is_empty() {
            return Err(crate::ZakaiError::Config(p));
        }
        self.times.push(t);
        self.observations.extend_from_slice(value);
        self.inputs.extend_from_slice(u);
        Ok(())
    }

    /// The first `rows` rows (all of them when there are fewer): the recording up to τ_(rows−1).
    pub fn first_rows(&self, rows: usize) -> Recording {
        let rows = rows.min(self.times.len());
        Recording {
            n: self.n,
            m: self.m,
            times: self.times[..rows].to_vec(),
            observations: self.observations[..rows * self.m].to_vec(),
            continuous: self.continuous,
            truth: self.truth.as_ref().map(|t| t[..rows * self.n].to_vec()),
            input_count: self.input_count,
            inputs: self.inputs[..rows * self.input_count].to_vec(),
        }
    }

    /// N, the number of observation intervals.
    pub fn steps(&self) -> usize {
        self.times.len().saturating_sub(1)
    }
    /// Observation row k.
    pub fn observation(&self, k: usize) -> &[f64] {
        &self.observations[k * self.m..(k + 1) * self.m]
    }
    /// The true state at τ_k, when known.
    pub fn state(&self, k: usize) -> Option<&[f64]> {
        self.truth
            .as_deref()
            .map(|t| &t[k * self.n..(k + 1) * self.n])
    }
    /// τ_k − τ_{k−1} (0 for k = 0).
    pub fn step_length(&self, k: usize) -> f64 {
        if k == 0 {
            0.0
        } else {
            self.times[k] - self.times[k - 1]
        }
    }

    /// Every problem with the recording: lengths against the dimensions, times not finite
    /// or not increasing, non-finite values — each with its row (rows count from 1, as in a
    /// file without its header).
    pub fn problems(&self) -> Vec<ConfigProblem> {
        self.placed_problems(&|_, row, field, text| {
            ConfigProblem::new(field, format!("row {}: {text}", row + 1))
        })
    }

    /// Every problem, each one about a row placed by `place(part, row, field, text)` (rows
    /// from 0): [`Recording::problems`] names the row, the CSV reader the file and line.
    pub(crate) fn placed_problems(
        &self,
        place: &dyn Fn(Part, usize, String, String) -> ConfigProblem,
    ) -> Vec<ConfigProblem> {
        let mut p = Vec::new();
        let rows = self.times.len();
        if rows < 2 {
            p.push(ConfigProblem::new(
                "times",
                format!("needs the start τ₀ and at least one observation time, got {rows} time(s)"),
            ));
        }
        if self.m == 0 || self.observations.len() != rows * self.m {
            p.push(ConfigProblem::new(
                "observations",
                format!(
                    "needs {rows} rows of m = {} values ({} in all), got {}",
                    self.m,
                    rows * self.m,
                    self.observations.len()
                ),
            ));
        }
        if let Some(k) = self
            .times
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(core::cmp::Ordering::Greater))
        {
            p.push(place(
                Part::Observations,
                k + 1,
                format!("times[{}]", k + 1),
                format!(
                    "times must increase, got {} after {}",
                    self.times[k + 1],
                    self.times[k]
                ),
            ));
        }
        if let Some(k) = self.times.iter().position(|t| !t.is_finite()) {
            p.push(place(
                Part::Observations,
                k,
                format!("times[{k}]"),
                "the time is not finite".into(),
            ));
        }
        let non_finite = |part, values: &[f64], width: usize, name: &str| {
            values.iter().position(|v| !v.is_finite()).map(|i| {
                let (k, j) = (i / width.max(1), i % width.max(1));
                place(
                    part,
                    k,
                    format!("{name}[{k}][{j}]"),
                    format!("component {}: not finite", j + 1),
                )
            })
        };
        // NaN marks a missing component; infinities are errors.
        p.extend(
            self.observations
                .iter()
                .position(|v| v.is_infinite())
                .map(|i| {
                    let (k, j) = (i / self.m.max(1), i % self.m.max(1));
                    place(
                        Part::Observations,
                        k,
                        format!("observations[{k}][{j}]"),
                        format!(
                            "component {}: infinite (a missing value is NaN or an empty cell)",
                            j + 1
                        ),
                    )
                }),
        );
        if let Some(truth) = &self.truth {
            if self.n == 0 || truth.len() != rows * self.n {
                p.push(ConfigProblem::new(
                    "truth",
                    format!(
                        "needs {rows} rows of n = {} values ({} in all), got {}",
                        self.n,
                        rows * self.n,
                        truth.len()
                    ),
                ));
            } else {
                p.extend(non_finite(Part::Truth, truth, self.n, "truth"));
            }
        }
        if self.inputs.len() != rows * self.input_count {
            p.push(ConfigProblem::new(
                "inputs",
                format!(
                    "needs {rows} rows of k = {} values ({} in all), got {}",
                    self.input_count,
                    rows * self.input_count,
                    self.inputs.len()
                ),
            ));
        } else {
            let c = self.input_count.max(1);
            p.extend(self.inputs.iter().position(|v| !v.is_finite()).map(|i| {
                place(
                    Part::Observations,
                    i / c,
                    format!("inputs[{}][{}]", i / c, i % c),
                    format!(
                        "input u{} is not finite (a driven model reads every input on every row)",
                        i % c + 1
                    ),
                )
            }));
        }
        p
    }
}

impl From<Trajectory> for Recording {
    fn from(t: Trajectory) -> Self {
        Recording {
            n: t.n,
            m: t.m,
            times: t.times,
            observations: t.observations,
            continuous: t.continuous,
            truth: Some(t.states),
            input_count: t.input_count,
            inputs: t.inputs,
        }
    }
}
