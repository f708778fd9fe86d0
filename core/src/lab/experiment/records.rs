//! What a run records: each method's track (estimates, covariances, times, failures and the
//! self-checks' concerns), its smoother's track, and the finished [`RunResult`]; and the
//! [`Observer`] that hears of progress.

use alloc::borrow::Cow;
use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::Concern;
use crate::lab::metrics;
use crate::lab::recording::Recording;

use super::clock::{SAMPLED_BELOW, SAMPLE_EVERY, TIMED_FIRST};

/// Receives progress from the driver.
pub trait Observer {
    /// After observation `k` of `total` was given to every live filter.
    fn on_step(&mut self, _k: usize, _total: usize) {}
    /// When method `index` fails at observation `k`.
    fn on_failure(&mut self, _index: usize, _k: usize, _message: &str) {}
}

/// An observer that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;
impl Observer for Silent {}

/// Where and why a method failed in a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Failure {
    /// Observation index where it failed.
    pub k: usize,
    /// The error message.
    pub message: String,
}

/// A self-check that warned during a run ([`crate::Filter::self_check`]): when it first crossed its
/// threshold, on how many steps, and its worst value — one record per side of a two-sided
/// check (a band) that was crossed.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ConcernRecord {
    /// What is watched.
    pub check: Cow<'static, str>,
    /// The documented threshold.
    #[serde(deserialize_with = "nan_from_null")]
    pub threshold: f64,
    /// Whether values above the threshold are the problem (else below).
    pub above: bool,
    /// What it means and what to change.
    pub advice: Cow<'static, str>,
    /// Observation index and time of the first crossing.
    pub first_k: usize,
    /// τ at the first crossing.
    pub first_t: f64,
    /// Steps on which the threshold was crossed.
    pub steps: usize,
    /// The value furthest beyond the threshold.
    #[serde(deserialize_with = "nan_from_null")]
    pub worst: f64,
}

/// A number serialised as JSON writes it, NaN as `null`, read back.
pub(super) fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    <Option<f64> as serde::Deserialize>::deserialize(d).map(|v| v.unwrap_or(f64::NAN))
}

impl ConcernRecord {
    /// One line: check, worst value against the threshold, since when, how often, advice.
    pub fn describe(&self) -> String {
        alloc::format!(
            "{} {:.3e} {} {:.1e} from t = {:.4} on {} step(s): {}",
            self.check,
            self.worst,
            if self.above { ">" } else { "<" },
            self.threshold,
            self.first_t,
            self.steps,
            self.advice
        )
    }

    pub(crate) fn record(records: &mut Vec<ConcernRecord>, c: &Concern, k: usize, t: f64) {
        // A two-sided check (a band) keeps one record per side crossed, each with its own
        // threshold and worst value.
        match records
            .iter_mut()
            .find(|r| r.check == c.check && r.above == c.above)
        {
            Some(r) => {
                r.steps += 1;
                let worse = if c.above {
                    c.value > r.worst
                } else {
                    c.value < r.worst
                };
                if worse {
                    r.worst = c.value;
                }
            }
            None => records.push(ConcernRecord {
                check: Cow::Borrowed(c.check),
                threshold: c.threshold,
                above: c.above,
                advice: Cow::Borrowed(c.advice),
                first_k: k,
                first_t: t,
                steps: 1,
                worst: c.value,
            }),
        }
    }
}

/// One method's record in one run (serialised bit for bit, [`crate::lab::recording::bits`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MethodTrack {
    /// Display name.
    pub name: String,
    /// State dimension.
    pub n: usize,
    /// Estimates x̂(τ_k), row-major, for k = 0..(rows − 1); rows stop at a failure.
    #[serde(with = "crate::lab::recording::bits")]
    pub estimates: Vec<f64>,
    /// Covariances P(τ_k) (n × n each, row-major) for the rows of `estimates`, when the
    /// method has them (Kalman family, particle and grid filters); empty otherwise.
    #[serde(with = "crate::lab::recording::bits")]
    pub covariances: Vec<f64>,
    /// The failure, if the method failed.
    pub failure: Option<Failure>,
    /// Its self-checks that warned (empty when every check stayed within its threshold).
    pub concerns: Vec<ConcernRecord>,
    /// Wall time spent in the timed steps' `step` (seconds; 0 without a clock). Every step is
    /// timed, except that a method whose timed steps average under [`SAMPLED_BELOW`] is timed
    /// on one step in [`SAMPLE_EVERY`] (see there).
    #[serde(with = "crate::lab::recording::bits")]
    pub seconds: f64,
    /// Number of steps taken.
    pub steps: usize,
    /// Number of steps whose wall time is in [`MethodTrack::seconds`].
    pub timed_steps: usize,
    /// Wall time spent building the filter — its off-line part (seconds; 0 without a clock).
    #[serde(with = "crate::lab::recording::bits")]
    pub build_seconds: f64,
    /// The innovations `z_k − h(x̂_{k|k−1})` of discrete measurements (m per row of
    /// `estimates`, NaN where a component is missing or the prediction failed), with
    /// `x̂_{k|k−1}` the mean the method predicts for τ_k before it sees `z_k` (on a fork): the
    /// part of each measurement its prediction did not expect. Empty unless the run records
    /// them ([`ExperimentRun::record_innovations`](super::ExperimentRun::record_innovations)).
    #[serde(with = "crate::lab::recording::bits")]
    pub innovations: Vec<f64>,
    /// The probability integral transform of each observation under the law the method
    /// predicted for it (m per row of `estimates`; NaN where a component is missing or the
    /// law is not defined): uniform and independent when model and method are right. Empty
    /// unless the run records its checks
    /// ([`ExperimentRun::record_checks`](super::ExperimentRun::record_checks)).
    #[serde(default, with = "crate::lab::recording::bits")]
    pub pit: Vec<f64>,
    /// The standardised one-step errors `(z − E z) / sd z` under the same law (as `pit`).
    #[serde(default, with = "crate::lab::recording::bits")]
    pub standardized: Vec<f64>,
    /// Each row's marginal density of one state component at the run's points (as many per
    /// row as points), when the run records them
    /// ([`ExperimentRun::record_marginals`](super::ExperimentRun::record_marginals)).
    #[serde(default, with = "crate::lab::recording::bits")]
    pub marginals: Vec<f64>,
    /// The log-likelihood of each row's observation given the ones before it
    /// ([`crate::Filter::log_likelihood`]; one per row of `estimates`, 0 where nothing was
    /// observed, NaN where the method gives none).
    #[serde(with = "crate::lab::recording::bits")]
    pub log_likelihoods: Vec<f64>,
    /// Estimates the method went on giving after a failure that left its state intact (the
    /// track-loss rule or the divergence bound, not a failed step or non-finite numbers),
    /// rows `failure.k ..`, row-major — for display only (a failed run's numbers never reach a
    /// table). Empty unless the run follows failed methods
    /// ([`ExperimentRun::follow_failed_methods`](super::ExperimentRun::follow_failed_methods)).
    #[serde(with = "crate::lab::recording::bits")]
    pub after_failure: Vec<f64>,
    /// Since when the error has been above the track-loss threshold.
    #[serde(with = "crate::lab::recording::bits")]
    pub(super) off_track_since: Option<f64>,
    /// Whether the method is still stepped after its failure (a followed run, the state
    /// intact; see `after_failure`).
    pub(super) following: bool,
    /// The smoothed estimates of a smoothing run ([`Experiment::smooth_recorded`](super::Experiment::smooth_recorded)); `None`
    /// in a filtering run.
    #[serde(default)]
    pub smoothed: Option<SmoothedTrack>,
}

/// One method's fixed-interval smoother over a run ([`crate::Smoother`]): the
/// best estimates of the states at the observation times given all the observations.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SmoothedTrack {
    /// The smoother (`"RTS"`, `"forward–backward"`, `"FFBSi"`), `None` when the method has
    /// none.
    pub smoother: Option<String>,
    /// Smoothed means E[x(τ_k) | all observations], row-major, one row per row of the
    /// filter's estimates; empty when there is no smoothed track.
    #[serde(with = "crate::lab::recording::bits")]
    pub estimates: Vec<f64>,
    /// Smoothed covariances (n × n per row, row-major).
    #[serde(with = "crate::lab::recording::bits")]
    pub covariances: Vec<f64>,
    /// Why there is no smoothed track: the method has no smoother, the filter failed, or the
    /// backward pass failed.
    pub failure: Option<String>,
    /// What the smoother approximated or cost on this run.
    pub notes: Vec<String>,
    /// Wall time of the backward pass (seconds; 0 without a clock).
    #[serde(with = "crate::lab::recording::bits")]
    pub seconds: f64,
}

impl SmoothedTrack {
    /// A track without smoothed estimates, and why.
    pub(super) fn unavailable(smoother: Option<String>, why: String) -> Self {
        SmoothedTrack {
            smoother,
            failure: Some(why),
            ..Default::default()
        }
    }

    /// MSE of 004 (43) of the smoothed means against `truth` (`None` without them).
    pub fn mse(&self, truth: &[f64], n: usize) -> Option<f64> {
        (self.failure.is_none() && self.estimates.len() == truth.len()).then(|| {
            metrics::mse_components(truth, &self.estimates, n)
                .iter()
                .sum()
        })
    }
}

impl MethodTrack {
    /// Number of estimate rows.
    pub fn rows(&self) -> usize {
        self.estimates.len() / self.n
    }
    /// The log-likelihood of the data the method saw, the sum of
    /// [`MethodTrack::log_likelihoods`]: `None` when it failed (its rows stop early) or gives
    /// none.
    pub fn log_likelihood(&self) -> Option<f64> {
        if self.failed() || self.log_likelihoods.iter().any(|v| v.is_nan()) {
            return None;
        }
        Some(self.log_likelihoods.iter().sum())
    }
    /// True when the method failed in this run.
    pub fn failed(&self) -> bool {
        self.failure.is_some()
    }
    /// True while the method's filter holds a state to show: it has not failed, or it failed
    /// with its state intact and the run still steps it (a followed run; display only).
    pub fn has_state(&self) -> bool {
        self.failure.is_none() || self.following
    }
    /// Mean wall time per step in seconds (over the timed steps).
    pub fn seconds_per_step(&self) -> f64 {
        if self.timed_steps == 0 {
            0.0
        } else {
            self.seconds / self.timed_steps as f64
        }
    }

    /// Whether the driver times this method's next step: the first [`TIMED_FIRST`], then all
    /// when they average [`SAMPLED_BELOW`] or more, else one in [`SAMPLE_EVERY`].
    pub(super) fn times_next_step(&self) -> bool {
        // The mean's test multiplies instead of dividing: it runs on every step.
        self.timed_steps < TIMED_FIRST
            || self.steps.is_multiple_of(SAMPLE_EVERY)
            || self.seconds >= SAMPLED_BELOW * self.timed_steps as f64
    }
    /// The estimates when the method finished the run against `truth`, else `None`.
    fn complete(&self, truth: &[f64]) -> Option<&[f64]> {
        (!self.failed() && self.estimates.len() == truth.len()).then_some(&self.estimates[..])
    }
    /// MSE of 004 (43) summed over components against the truth's states; `None` when the
    /// method failed or did not finish.
    pub fn mse(&self, truth: &[f64]) -> Option<f64> {
        self.mse_components(truth).map(|c| c.iter().sum())
    }
    /// MSE of 004 (43) per component; `None` when failed or unfinished.
    pub fn mse_components(&self, truth: &[f64]) -> Option<Vec<f64>> {
        let est = self.complete(truth)?;
        Some(metrics::mse_components(truth, est, self.n))
    }
    /// E_RMS of 000 §4.2 per component (k = 1..N); `None` when failed or unfinished.
    pub fn rms_components(&self, truth: &[f64]) -> Option<Vec<f64>> {
        let est = self.complete(truth)?;
        Some(metrics::rms_components(truth, est, self.n))
    }
}

/// A finished run (serde: the transport of a run between processes, numbers bit for bit).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    /// The seed of the run.
    pub seed: u64,
    /// The observations, with the truth when it is known.
    pub recording: Recording,
    /// One record per method, in the scenario's order.
    pub methods: Vec<MethodTrack>,
    /// The methods' warnings about their parameters, as `(method, message)`.
    pub warnings: Vec<(String, String)>,
}

impl RunResult {
    /// MSE of 004 (43) of method `index` (`None` when it failed or the truth is unknown).
    pub fn mse(&self, index: usize) -> Option<f64> {
        self.methods
            .get(index)?
            .mse(self.recording.truth.as_deref()?)
    }
}
