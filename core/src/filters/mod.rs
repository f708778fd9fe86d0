//! Filters: one [`Filter`] trait, one folder per method family.
//!
//! * [`kalman`] — Kalman–Bucy (exact for linear Gaussian models), EKF, UKF, and the MAP
//!   updates of 003 (IEKF, IOKF);
//! * [`particle`] — the bootstrap particle filter;
//! * [`yau_fd`] — the finite-difference Yau–Yau filters of 000 (IEM, QIEM, SPT, QIEM-4; the
//!   filters need the `std` feature for their FFT plans);
//! * [`spectral`] — the off-line/on-line spectral Yau–Yau filter of 004 (Legendre basis);
//! * [`direct`] — the direct method of 002 (Gaussian approximation and Riccati ODEs);
//! * [`fpe_split`] — the continuous–discrete Fokker–Planck grid filters of 001;
//! * [`gaussian_sum`] — the exact Gaussian-sum filter of linear models with mixtures;
//! * [`tensor_train`] — the Yau–Yau grid filter in tensor-train format, beyond three
//!   dimensions.
//!
//! Every family folder has the same shape: `mod.rs` (the module doc — idea, equations,
//! example, cost — and the family's public names), `params.rs` (its parameters, each
//! declared once with `parameters!`, see [`params`]), `filter.rs` (its filter; the Gaussian
//! family has one file per filter type instead: `linear.rs`, `ekf.rs`, `ukf.rs`, `map.rs`) and
//! `method.rs` (its registration: the [`method::Method`] implementation), beside the building
//! blocks named in its paper's words (`operator.rs`, `riccati.rs`, `legendre.rs`, …). The
//! catalogue (`lab::scenario`) lists each family once; [`builder::Builder`] builds any of them.
//!
//! Every filter is built from a [`crate::model::Model`], a prior and its own parameters,
//! consumes the same [`Observation`]s, and exposes its [`Estimate`]; grid methods also expose
//! their density through [`DensityView`].
//!
//! This module holds the trait; what it consumes and reports lives beside it, in files named
//! for what they hold: `observation.rs`, `estimate.rs`, `self_check.rs` (concerns and the grid
//! checks), `likelihood.rs` (the observation's likelihood), `grid_state.rs` (a grid density
//! between steps), `intervals.rs` (steps of any length) and `resolution.rs` (grid sizes).

pub(crate) mod builder;
pub(crate) mod direct;
mod estimate;
pub(crate) mod fpe_split;
pub(crate) mod gaussian_sum;
pub(crate) mod grid_score;
mod grid_state;
mod intervals;
pub(crate) mod kalman;
mod likelihood;
pub(crate) mod marginal;
pub(crate) mod method;
mod observation;
pub(crate) mod params;
pub(crate) mod particle;
pub(crate) use particle::SuppliedNormals;
pub(crate) mod point_mass;
pub(crate) mod predictive;
pub(crate) mod resolution;
pub(crate) mod score;
mod self_check;
pub(crate) mod smoothing;
pub(crate) mod spectral;
pub(crate) mod tensor_train;
pub(crate) mod yau_fd;

use alloc::string::String;
use alloc::vec::Vec;

use crate::error::FilterError;
pub use crate::grid::DensityView;

pub use estimate::Estimate;
pub(crate) use estimate::{copy_matrix, copy_optional_vector, copy_vector};
pub(crate) use grid_state::{kept_estimate_accessors, normalise_on_grid, SavedDensity};
pub use intervals::INTERVAL_TOLERANCE;
pub(crate) use intervals::{whole_intervals, LengthCache, Substeps, REMAINDER_PLANS};
pub use likelihood::observation_log_likelihoods;
pub(crate) use likelihood::{observed_residual, MeasurementLikelihood, ObservedNoise};
pub(crate) use observation::kind_of;
pub use observation::{Observation, ObservationKind, Observed};
pub(crate) use resolution::{count_problem, per_dimension, product};
pub use score::{Perturbation, Score};
pub use self_check::Concern;
pub(crate) use self_check::{grid_self_check, WIDTH_IN_CELLS_THRESHOLD};

/// A nonlinear filter: predict over an interval, assimilate what was observed, report.
///
/// A step either succeeds or returns an error and leaves the filter exactly as it was:
/// bad input — a step Δτ that is negative or not finite, an observation of the wrong kind
/// or length, an infinite component ([`FilterError::BadObservation`]) — is refused before
/// anything moves; a numeric failure
/// found while computing (non-finite numbers, lost mass, a failed factorisation) restores
/// the state the step started from. The driver marks the method failed for the run.
///
/// Missing data: a component whose value is NaN ([`Observation::is_missing`]) was not
/// observed; an observation with every component missing, or an empty one
/// ([`Observation::nothing`]), is a prediction only ([`Filter::predict`]). Where only some
/// components are missing, the Gaussian and particle filters and the grid filters of discrete
/// measurements use the observed rows of h and of the noise; a method that cannot says so
/// with an error.
///
/// Every filter is [`Clone`] and [`Debug`]; [`Fork::fork`] clones one behind a
/// `Box<dyn Filter>`, e.g. to forecast from the current state while the original goes on:
///
/// ```
/// use zakai::{Filter, Fork, Model, Noise, Ukf};
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1))?;
/// let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build()?;
/// ukf.step_measurement(0.1, &[0.4])?;
/// let mut ahead = ukf.fork();
/// for _ in 0..10 {
///     ahead.predict(0.1)?; // no measurement: the predictive distribution one Δτ further
/// }
/// assert!(ahead.estimate().mean[0].abs() < ukf.estimate().mean[0].abs());
/// ukf.update(&[f64::NAN])?; // a missing value: nothing to assimilate
/// # Ok::<(), zakai::ZakaiError>(())
/// ```
pub trait Filter: core::fmt::Debug + Fork {
    /// Display name, e.g. `"EKF"` or `"PF(200)"`.
    fn name(&self) -> &str;
    /// Predicts over `obs.dt`, then assimilates the components of `obs.value` that were
    /// observed (see the trait doc for missing components and errors).
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError>;
    /// Predicts over `dt` without an observation: a gap, or a forecast (on a
    /// [`fork`](Fork::fork) of the filter). For continuous observations this is an interval
    /// whose increment was not recorded.
    fn predict(&mut self, dt: f64) -> Result<(), FilterError> {
        self.step(&Observation::nothing(dt))
    }
    /// [`Filter::predict`] for a driven model ([`crate::Inputs`]): predicts over `dt`
    /// to the time `t` with the known inputs `u` over the interval, as a step of
    /// `Observation::nothing(dt).with_inputs(t, u)`. An autonomous model ignores `t` and `u`.
    fn predict_with(&mut self, dt: f64, t: f64, u: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::nothing(dt).with_inputs(t, u))
    }
    /// Assimilates the measurement `z` at the current time, without predicting (discrete
    /// measurements; NaN components are missing). Continuous observations come as increments
    /// over an interval: step with them ([`Filter::step_increment`]).
    fn update(&mut self, z: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::measurement(0.0, z))
    }
    /// The predictive estimates `dt`, `2 dt`, … `steps · dt` ahead, from a fork of the filter
    /// (the filter itself does not move): the forecast with its spread. For the density ahead
    /// (grid methods), step a [`fork`](Fork::fork) with [`Filter::predict`] and read
    /// [`Filter::density`].
    fn forecast(&self, dt: f64, steps: usize) -> Result<Vec<Estimate>, FilterError> {
        let mut ahead = self.fork();
        (0..steps)
            .map(|_| {
                ahead.predict(dt)?;
                Ok(ahead.estimate())
            })
            .collect()
    }
    /// [`Filter::forecast`] for a driven model: the predictive estimates at the ends of the
    /// intervals `ahead`, each `(dt, t, u)` — its length, the time it ends at and the known
    /// inputs over it ([`Filter::predict_with`]) — from a fork of the filter.
    fn forecast_with(&self, ahead: &[(f64, f64, &[f64])]) -> Result<Vec<Estimate>, FilterError> {
        let mut fork = self.fork();
        ahead
            .iter()
            .map(|&(dt, t, u)| {
                fork.predict_with(dt, t, u)?;
                Ok(fork.estimate())
            })
            .collect()
    }
    /// Predicts over `dt` and assimilates the measurement `z` (discrete observations;
    /// `dt = 0` assimilates at the prior's time).
    fn step_measurement(&mut self, dt: f64, z: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::measurement(dt, z))
    }
    /// Predicts over `dt` and assimilates the increment `dy` = y(t + dt) − y(t) (continuous
    /// observations).
    fn step_increment(&mut self, dt: f64, dy: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::increment(dt, dy))
    }
    /// The log-likelihood of the observation the last step assimilated, given the ones
    /// before it; 0 after a step that observed nothing (a gap, a prediction, every component
    /// missing); `None` when the method does not give one. Summed over the steps it is the
    /// log-likelihood of the data, which a maximum-likelihood fit maximises.
    ///
    /// * A measurement z_k: `ℓ_k = ln p(z_k | z_1:k−1) = ln ∫ p_v(z_k − h(x)) p(x | z_1:k−1) dx`
    ///   over the observed components (their marginal noise density).
    /// * An increment Δy over Δτ: `ℓ_k = ln ∫ exp(ΔyᵀS⁻¹h − ½hᵀS⁻¹hΔτ) p(x | past) dx`, the
    ///   likelihood ratio of the interval's observation against Wiener measure (the
    ///   Kallianpur–Striebel normaliser of the robust DMZ factor, 000 (15), 004 (42)); with
    ///   components missing, the same with the observed rows of h and the marginal S_OO.
    ///
    /// Exact for the Kalman–Bucy filter on linear-Gaussian models (for the sampled-model
    /// update it makes; with mixture noise it uses the noise's first two moments) and for the
    /// Gaussian-sum filter up to its reported mixture reduction; from the normalising constant
    /// of the density for the grid and spectral filters (converging as the grid is refined)
    /// and from the mass ratio of `e^{F} û` for the direct method; the particle filter's is
    /// the log of its weights' mean (whose exponential is unbiased for the likelihood); the
    /// EKF, UKF, IEKF and IOKF give their Gaussian predictive density's, an approximation.
    fn log_likelihood(&self) -> Option<f64> {
        None
    }
    /// The log-likelihood of `observations` (the first at the filter's time: a step of
    /// length 0) from the filter as built, and its gradient in the parameters the model was
    /// built from — the model and prior at two points around the filter's for each parameter
    /// in `perturbed` ([`Perturbation`]). `None` for the methods that do not give it (a fit then
    /// needs no gradient: Nelder–Mead); an error when this filter's model or data are outside
    /// what its score covers (which the error names). The filter itself is not stepped; it
    /// must not have been either (the recursion starts from its state, the prior's derivative
    /// is taken there: a stepped filter's score is wrong).
    fn score(
        &self,
        _observations: &[Observation<'_>],
        _perturbed: &[Perturbation],
    ) -> Option<Result<Score, FilterError>> {
        None
    }
    /// This filter, from its current state, as the forward pass of its fixed-interval smoother
    /// ([`smoothing::Smoother`]): a filter that steps exactly as this one does and keeps what the
    /// backward pass needs, with its memory checked against `plan` before anything is kept.
    /// An error for methods without a smoother (the catalogue says why,
    /// [`method::Method::SMOOTHING`]).
    fn smoother(
        &self,
        _plan: &smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn smoothing::Smoother>, FilterError> {
        Err(smoothing::no_smoother(
            self.name(),
            "the method does not implement one",
        ))
    }
    /// This filter as a smoother, when it is one (what [`Filter::smoother`] returned).
    fn as_smoother(&mut self) -> Option<&mut dyn smoothing::Smoother> {
        None
    }
    /// The law of the state the filter holds, for predictive distributions
    /// ([`predictive::ObservationLaw`], [`predictive::forecast`]): the particle filter's
    /// cloud, a grid or spectral filter's density at its nodes, the Gaussian-sum filter's
    /// mixture; this default, the Gaussian of the estimate (the Kalman family, the direct
    /// method), or an error when the estimate has no covariance.
    fn state_law(&self) -> Result<predictive::StateLaw, FilterError> {
        predictive::StateLaw::of_estimate(self.name(), self.estimate())
    }
    /// The current estimate.
    fn estimate(&self) -> Estimate;
    /// [`Filter::estimate`] into `out`, reusing its storage: a loop that reads the estimate
    /// after every step passes the same `out` each time, and allocates nothing for it (every
    /// filter of the catalogue writes it in place; this default builds it afresh).
    fn estimate_into(&self, out: &mut Estimate) {
        *out = self.estimate();
    }
    /// The current density, for grid methods; `None` otherwise.
    fn density(&self) -> Option<DensityView<'_>> {
        None
    }
    /// How many numbers hold the density, against the full grid they stand for, for a method
    /// whose density is compressed (the tensor-train filter); `None` otherwise.
    fn footprint(&self) -> Option<Footprint> {
        None
    }
    /// Warnings about the chosen parameters (violated stability or positivity conditions),
    /// known before the first step.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The method's self-checks of its current state, cheap enough to run after every step:
    /// each check whose documented threshold is crossed pushes a [`Concern`] into `out`
    /// (nothing is allocated when all is well). A concern is a warning, not a failure.
    fn self_check(&self, _out: &mut Vec<Concern>) {}
    /// The filter's marginal density of state component `dim` at the points `grid`, written
    /// into `out` (for plots). The default is the Gaussian N(m_d, P_dd) of the estimate.
    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        let est = self.estimate();
        let var = est.covariance.map_or(0.0, |p| p[(dim, dim)]);
        marginal::gaussian(est.mean[dim], var, grid, out);
    }
    /// The filter's joint marginal density of components `dims` on the raster `xs × ys`
    /// (`xs` fastest), written into `out` (for 2-D heatmaps). The default uses the grid
    /// density when there is one ([`Filter::density`]), else the Gaussian of the estimate.
    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        if let Some(view) = self.density() {
            if let Ok(grid) = crate::grid::TensorGrid::new(view.bounds, view.shape) {
                grid.marginal_2d(view.values, dims, xs, ys, out);
                return;
            }
        }
        let est = self.estimate();
        let (a, b) = dims;
        let cov = est.covariance.map_or([[0.0; 2]; 2], |p| {
            [[p[(a, a)], p[(a, b)]], [p[(b, a)], p[(b, b)]]]
        });
        marginal::gaussian_2d([est.mean[a], est.mean[b]], cov, xs, ys, out);
    }
}

/// What a compressed density costs to hold ([`Filter::footprint`]): the numbers kept and the
/// points of the full tensor grid they stand for, with the tensor-train ranks `r₀ … r_d`
/// now and the largest each has reached since the filter was built.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    /// Numbers the density is held in.
    pub numbers: usize,
    /// Points of the full tensor grid (a float: `160¹⁰` does not fit a `usize`).
    pub grid_points: f64,
    /// The ranks now, `r₀ = r_d = 1`.
    pub ranks: Vec<usize>,
    /// The largest value each rank has taken so far.
    pub peak_ranks: Vec<usize>,
}

/// Cloning a filter behind `Box<dyn Filter>`: implemented for every [`Filter`] that is
/// [`Clone`] (all of the catalogue's are).
pub trait Fork {
    /// An independent copy of the filter in its current state: stepping one does not move the
    /// other.
    fn fork(&self) -> alloc::boxed::Box<dyn Filter>;
}

impl<F: Filter + Clone + 'static> Fork for F {
    fn fork(&self) -> alloc::boxed::Box<dyn Filter> {
        alloc::boxed::Box::new(self.clone())
    }
}

impl Clone for alloc::boxed::Box<dyn Filter> {
    fn clone(&self) -> Self {
        self.fork()
    }
}
