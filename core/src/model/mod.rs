//! The filtering model
//!
//! ```text
//!     dx = f(x) dt + G(x) dv,                   v standard Brownian motion in Rⁿ
//!     dy = h(x) dt + dw,   E[dw dwᵀ] = S dt      (continuous, 000 (1), 002 (1), 004 (1))
//!     z_k = h(x_k) + v_k,  v_k ~ Gaussian or mixture  (continuous–discrete, 001 (1)–(2), 003 (5.2))
//!     z_k ~ p(z | x_k)                            (counts, outliers, volatility: [`measurement`])
//! ```
//!
//! with Q = G Gᵀ (the identity by default, as in 000, 002 and 004; constant in all five papers,
//! a function of the state here when a model needs one: [`diffusion`]).
//!
//! A **discrete-time** model ([`Dynamics::Discrete`], [`Model::discrete_time`]) replaces the SDE
//! by a map from one observation time to the next, the form of FilterPy, statsmodels and
//! `particles`:
//!
//! ```text
//!     x_k = F(x_{k−1}, t_k, u_k) + w_k,   w_k ~ N(0, G Gᵀ)      (one transition per Δτ)
//!                                          or w_k ~ Σ_j π_j N(μ_j, Q_j)   (a mixture)
//! ```
//!
//! F is held where the drift is (`drift`) and G where the diffusion is, so that expressions,
//! closures, state-dependent noise, known inputs and fits carry over unchanged.

mod compile;
pub(crate) mod diffusion;
pub(crate) mod dmz;
pub(crate) mod expression;
pub(crate) mod function;
pub(crate) mod inputs;
pub(crate) mod measurement;
pub(crate) mod noise;
pub(crate) mod prior;
pub(crate) mod program;
pub(crate) mod symbolic;
pub(crate) mod syntax;

use alloc::format;
use alloc::sync::Arc;

use nalgebra::{DMatrix, DVector};

pub use diffusion::{Diffusion, ProcessNoise};
pub use function::{BatchScratch, ClosureFunction, Derivatives, FixedPrograms, VectorFunction};
pub use inputs::Inputs;
pub use measurement::MeasurementDensity;
pub use noise::{GaussianMixture, MixtureComponent};
pub use prior::{Prior, TabulatedDensity};

use crate::error::ZakaiError;

/// The observation noise of a model built by [`Model::from_text`] or
/// [`Model::from_closures`].
#[derive(Clone, Debug)]
pub enum Noise {
    /// Continuous observations `dy = h dt + dw` with `E[dw dwᵀ] = S dt`, S given.
    Continuous(DMatrix<f64>),
    /// Continuous observations with `S = s·I`.
    ContinuousScalar(f64),
    /// Discrete measurements `z_k = h(x_k) + v_k`, `v_k ~ N(0, R)`, R given.
    Discrete(DMatrix<f64>),
    /// Discrete measurements with `R = r·I` (r is a variance, as FilterPy's `R`).
    DiscreteScalar(f64),
    /// Discrete measurements with `v_k` from a Gaussian mixture.
    DiscreteMixture(GaussianMixture),
    /// Discrete measurements from any [`MeasurementDensity`] (Poisson counts, Student-t,
    /// state-dependent variance, a log-density).
    Measurement(MeasurementDensity),
}

impl Noise {
    /// Continuous observations `dy = h dt + dw` with intensity `E[dw dwᵀ] = s·I dt`.
    pub fn continuous(s: f64) -> Self {
        Noise::ContinuousScalar(s)
    }
    /// Discrete measurements `z_k = h(x_k) + v_k` with `v_k ~ N(0, variance·I)`.
    pub fn discrete(variance: f64) -> Self {
        Noise::DiscreteScalar(variance)
    }

    /// The observation model for `m` observation components.
    pub fn observation_model(self, m: usize) -> Result<ObservationModel, ZakaiError> {
        let scalar = |v: f64, what: &str| {
            if v > 0.0 && v.is_finite() {
                Ok(DMatrix::identity(m, m) * v)
            } else {
                Err(ZakaiError::OutOfRange {
                    what: what.into(),
                    value: v,
                    requirement: "positive and finite",
                })
            }
        };
        Ok(match self {
            Noise::Continuous(s) => ObservationModel::Continuous { noise_cov: s },
            Noise::ContinuousScalar(s) => ObservationModel::Continuous {
                noise_cov: scalar(s, "the observation noise intensity")?,
            },
            Noise::Discrete(r) => {
                ObservationModel::additive(GaussianMixture::gaussian(DVector::zeros(r.nrows()), r)?)
            }
            Noise::DiscreteScalar(r) => ObservationModel::additive(GaussianMixture::gaussian(
                DVector::zeros(m),
                scalar(r, "the measurement noise variance")?,
            )?),
            Noise::DiscreteMixture(noise) => ObservationModel::additive(noise),
            Noise::Measurement(density) => ObservationModel::Discrete { density },
        })
    }
}

/// How the state is observed.
#[derive(Clone, Debug)]
pub enum ObservationModel {
    /// `dy = h(x) dt + dw` with `E[dw dwᵀ] = S dt`; filters receive increments Δy.
    Continuous {
        /// S (m × m, symmetric positive definite).
        noise_cov: DMatrix<f64>,
    },
    /// Measurements `z_k ~ p(z | x_k)` at the observation times: `z_k = h(x_k) + v_k` with v_k
    /// from a Gaussian or mixture (001, 003), or another [`MeasurementDensity`].
    Discrete {
        /// `p(z | x)`.
        density: MeasurementDensity,
    },
}

impl ObservationModel {
    /// Measurements `z_k = h(x_k) + v_k`, v_k from `noise` (001 (1)–(2)).
    pub fn additive(noise: GaussianMixture) -> Self {
        ObservationModel::Discrete {
            density: MeasurementDensity::Additive(noise),
        }
    }
}

/// How the signal moves between observation times.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Dynamics {
    /// The SDE `dx = f(x) dt + G(x) dv` of the five papers: every method discretises it in
    /// time (its own scheme and step).
    #[default]
    Continuous,
    /// The map `x_k = F(x_{k−1}, t_k, u_k) + w_k`, `w_k ~ N(0, G Gᵀ)`, one transition per
    /// `period` (the observation interval Δτ the map is written for), with F held in
    /// [`Model::drift`] and G in [`Model::diffusion`]. A step over `k·period` applies k
    /// transitions; a step that is not a whole number of periods is refused
    /// ([`Model::transitions`]). The Kalman and Gaussian-sum filters are exact for a linear
    /// F; the point-mass and particle filters use the transition itself (no time
    /// discretisation); the EKF, UKF, IEKF and IOKF predict through F by their own
    /// linearisation; the methods of the continuous-time equations (Yau–Yau, spectral,
    /// direct, the Fokker–Planck grids) refuse it.
    Discrete {
        /// The time between two transitions (Δτ).
        period: f64,
    },
}

impl Dynamics {
    /// The number of transitions a discrete-time model makes over a step of length `dt` (k
    /// when `dt/period` is within 10⁻⁶ of the whole number k, at most [`MAX_TRANSITIONS`];
    /// an error otherwise, and for a continuous-time model, whose filters never ask).
    pub fn transitions(&self, dt: f64) -> Result<usize, crate::error::FilterError> {
        let Dynamics::Discrete { period } = *self else {
            return Err(crate::error::FilterError::Unsuitable(
                "a continuous-time model makes no transitions".into(),
            ));
        };
        let periods = dt / period;
        // The nearest integer by adding and taking away 1.5·2⁵² (exact below 2⁵¹; a count that
        // large, NaN or a half-way one is refused below either way).
        const ROUND: f64 = 6_755_399_441_055_744.0;
        let k = (periods + ROUND) - ROUND;
        if (0.0..=MAX_TRANSITIONS as f64).contains(&k) && libm::fabs(periods - k) <= 1e-6 {
            Ok(k as usize)
        } else {
            Err(crate::error::FilterError::BadObservation(format!(
                "the step's interval {dt} is not a whole number of the discrete-time model's period {period} (one transition x_k = F(x_(k−1)) + w_k per period)"
            )))
        }
    }
}

/// Most transitions one step of a discrete-time model may make (a longer gap is an error
/// naming it, not a step that runs for hours).
pub const MAX_TRANSITIONS: usize = 10_000_000;

/// A filtering model: dimensions, drift, observation function, diffusion and noise.
#[derive(Clone)]
pub struct Model {
    /// State dimension n.
    pub n: usize,
    /// Observation dimension m.
    pub m: usize,
    /// Drift f: Rⁿ → Rⁿ; for a discrete-time model ([`Dynamics::Discrete`]), the
    /// transition map F.
    pub drift: Arc<dyn VectorFunction>,
    /// Observation function h: Rⁿ → Rᵐ.
    pub observation: Arc<dyn VectorFunction>,
    /// Diffusion G (n × n, constant or a function of the state), Q = G Gᵀ; for a
    /// discrete-time model, the factor of the transition noise, `w_k ~ N(0, G Gᵀ)`.
    pub diffusion: Diffusion,
    /// Continuous or discrete observations.
    pub observations: ObservationModel,
    /// `Some(k)` for a driven model: its functions read the state, then the time `t` and k
    /// known inputs `u1..uk` ([`Inputs`]); `None` for an autonomous model.
    pub inputs: Option<usize>,
    /// An SDE or a map from one observation time to the next.
    pub dynamics: Dynamics,
    /// A discrete-time model's transition noise when it is a Gaussian mixture
    /// ([`Model::with_transition_mixture`], which keeps it consistent with `dynamics`, `n` and
    /// G; read with [`Model::transition_mixture`]); `None` for `w_k ~ N(0, G Gᵀ)`.
    pub(crate) transition_mixture: Option<Arc<TransitionMixture>>,
}

/// Transition noise that is a Gaussian mixture, `w_k ~ Σ_j π_j N(μ_j, Q_j)` (outliers in the
/// signal, jumps, a noise with a heavy tail), with its first two moments.
///
/// The filters that carry a density take it exactly: the particle filter draws `w_k` from it,
/// the point-mass filter's kernel is the mixture of the components' kernels, the Gaussian-sum
/// filter (linear F) splits every component into one per noise component (Sorenson & Alspach
/// 1971), exactly, before its mixture reduction. The Gaussian filters (Kalman, EKF, UKF, IEKF,
/// IOKF) see it through its mean `μ̄ = Σ π_j μ_j` and covariance
/// `Σ π_j (Q_j + μ_j μ_jᵀ) − μ̄ μ̄ᵀ` (the model's G is a square root of it): the Kalman filter
/// is then the best *linear* filter, not the exact one, and each says so in its warnings.
#[derive(Clone, Debug)]
pub struct TransitionMixture {
    mixture: GaussianMixture,
    mean: DVector<f64>,
}

impl TransitionMixture {
    /// The mixture `Σ_j π_j N(μ_j, Q_j)`.
    pub fn mixture(&self) -> &GaussianMixture {
        &self.mixture
    }

    /// Its mean `μ̄ = Σ π_j μ_j`.
    pub fn mean(&self) -> &DVector<f64> {
        &self.mean
    }

    /// Draws one `w_k` into `out` (n): a component by its weight, then its Gaussian.
    pub fn sample_into<R: rand::Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        self.mixture.sample_into(rng, out);
    }
}

impl core::fmt::Debug for Model {
    /// Dimensions, diffusion and observation noise (the functions f and h are opaque).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Model")
            .field("n", &self.n)
            .field("m", &self.m)
            .field("diffusion", &self.diffusion)
            .field("observations", &self.observations)
            .field("inputs", &self.inputs)
            .field("dynamics", &self.dynamics)
            .field("transition_mixture", &self.transition_mixture)
            .finish_non_exhaustive()
    }
}

impl Model {
    /// Builds a model, checking that all dimensions agree.
    pub fn new(
        drift: Arc<dyn VectorFunction>,
        observation: Arc<dyn VectorFunction>,
        diffusion: DMatrix<f64>,
        observations: ObservationModel,
    ) -> Result<Self, ZakaiError> {
        Self::assemble(
            drift,
            observation,
            Diffusion::Constant(diffusion),
            observations,
            None,
        )
    }

    /// A driven model ([`Inputs`]): `drift`, `observation` and the functions of `diffusion`
    /// and of the measurement density read the state, then the time `t` and the `inputs`
    /// known inputs `u1..uk` (the drift's n outputs give the state dimension). Each filter
    /// step fixes `(t, u)` from its observation ([`Model::at`]).
    pub fn driven(
        drift: Arc<dyn VectorFunction>,
        observation: Arc<dyn VectorFunction>,
        diffusion: Diffusion,
        observations: ObservationModel,
        inputs: usize,
    ) -> Result<Self, ZakaiError> {
        Self::assemble(drift, observation, diffusion, observations, Some(inputs))
    }

    /// Checks every dimension: the functions read n (+ 1 + k for a driven model) inputs.
    fn assemble(
        drift: Arc<dyn VectorFunction>,
        observation: Arc<dyn VectorFunction>,
        diffusion: Diffusion,
        observations: ObservationModel,
        inputs: Option<usize>,
    ) -> Result<Self, ZakaiError> {
        let extra = inputs.map_or(0, |k| 1 + k);
        let n = drift.output_dim();
        let m = observation.output_dim();
        let dim = |what: &str, got: usize, want: usize| {
            if got == want {
                Ok(())
            } else {
                Err(ZakaiError::Dimension(format!(
                    "{what} is {got}, expected {want}"
                )))
            }
        };
        dim("drift input dimension", drift.input_dim(), n + extra)?;
        dim(
            "observation input dimension",
            observation.input_dim(),
            n + extra,
        )?;
        match &observations {
            ObservationModel::Continuous { noise_cov } => {
                dim("observation noise S rows", noise_cov.nrows(), m)?;
                dim("observation noise S columns", noise_cov.ncols(), m)?;
                crate::linalg::cholesky(noise_cov, "observation noise covariance S")?;
            }
            ObservationModel::Discrete { density } => density.check(n, m, extra)?,
        }
        diffusion.check(n, extra)?;
        Ok(Model {
            n,
            m,
            drift,
            observation,
            diffusion,
            observations,
            inputs,
            dynamics: Dynamics::Continuous,
            transition_mixture: None,
        })
    }

    /// The same model in discrete time ([`Dynamics::Discrete`]): its drift read as the
    /// transition map F and G Gᵀ as the covariance of `w_k` in
    /// `x_k = F(x_{k−1}, t_k, u_k) + w_k`, one transition per observation interval. Refused
    /// for continuous observations `dy = h dt + dw`, which need a signal in continuous time.
    ///
    /// ```
    /// use zakai::{Dynamics, Model, Noise};
    ///
    /// // An AR(1) observed in noise, one transition per unit of time:
    /// // x_k = 0.9 x_{k−1} + w_k, w_k ~ N(0, 0.5), z_k = x_k + v_k, v_k ~ N(0, 1).
    /// let model = Model::from_text(&["0.9*x"], &["x"], Noise::discrete(1.0))
    ///     .unwrap()
    ///     .discrete_time(1.0)
    ///     .unwrap()
    ///     .with_transition_noise(&[[0.5]])
    ///     .unwrap();
    /// assert_eq!(model.dynamics, Dynamics::Discrete { period: 1.0 });
    /// assert_eq!(model.transitions(3.0).unwrap(), 3);
    /// assert!(model.transitions(2.5).is_err());
    /// ```
    pub fn discrete_time(self, period: f64) -> Result<Self, ZakaiError> {
        if !(period > 0.0 && period.is_finite()) {
            return Err(ZakaiError::OutOfRange {
                what: "the period of a discrete-time model's transition".into(),
                value: period,
                requirement: "positive and finite",
            });
        }
        if self.is_continuous() {
            return Err(ZakaiError::Config(alloc::vec![
                crate::validate::ConfigProblem::new(
                    "model.dynamics",
                    "a discrete-time model needs discrete measurements z_k ~ p(z | x_k): continuous observations dy = h dt + dw need a signal in continuous time",
                )
            ]));
        }
        Ok(Model {
            dynamics: Dynamics::Discrete { period },
            ..self
        })
    }

    /// The number of transitions a discrete-time model makes over a step of length `dt`
    /// ([`Dynamics::transitions`]).
    pub fn transitions(&self, dt: f64) -> Result<usize, crate::error::FilterError> {
        self.dynamics.transitions(dt)
    }

    /// The model of transition `j` of the `k` a step over `k` periods ending at time `t`
    /// makes, for a driven discrete-time model (transition j reaches time
    /// `t − (k − 1 − j)·period`, with the step's inputs `u`); the model itself when it is
    /// autonomous.
    pub fn transition_at(
        &self,
        inputs: Option<Inputs<'_>>,
        j: usize,
        k: usize,
    ) -> Result<alloc::borrow::Cow<'_, Model>, crate::error::FilterError> {
        use alloc::borrow::Cow;
        if !self.is_driven() {
            return Ok(Cow::Borrowed(self));
        }
        let Some(Inputs { t, u }) = inputs else {
            return Err(crate::error::FilterError::BadObservation(
                "the model reads the time t and known inputs: give each step the observation's time and inputs (Observation::with_inputs)".into(),
            ));
        };
        let period = match self.dynamics {
            Dynamics::Discrete { period } => period,
            Dynamics::Continuous => 0.0,
        };
        Ok(Cow::Owned(self.at(t - (k - 1 - j) as f64 * period, u)?))
    }

    /// The same model with the transition noise `w_k ~ N(0, Q)` (a discrete-time model's
    /// covariance, rows of Q; positive semidefinite — a zero row is a component without
    /// noise): G becomes a square root of Q.
    pub fn with_transition_noise<const N: usize>(self, q: &[[f64; N]]) -> Result<Self, ZakaiError> {
        let q = DMatrix::from_fn(q.len(), N, |i, j| q[i][j]);
        let g = crate::linalg::psd_square_root(&q, "transition noise covariance Q")?;
        self.with_diffusion(g)
    }

    /// The same discrete-time model with transition noise that is a Gaussian mixture,
    /// `w_k ~ Σ_j π_j N(μ_j, Q_j)` ([`TransitionMixture`] says how each family takes it); G
    /// becomes a square root of its covariance. Refused for a continuous-time model (a
    /// Brownian increment is Gaussian) and for a mixture of another dimension.
    ///
    /// ```
    /// use nalgebra::{DMatrix, DVector};
    /// use zakai::{GaussianMixture, Model, Noise};
    ///
    /// // A random walk that mostly creeps and now and then jumps:
    /// // w_k ~ 0.9 N(0, 0.01) + 0.1 N(0, 4).
    /// let part = |w: f64, var: f64| (w, DVector::from_element(1, 0.0), DMatrix::from_element(1, 1, var));
    /// let jumps = GaussianMixture::new(vec![part(0.9, 0.01), part(0.1, 4.0)])
    /// .unwrap();
    /// let model = Model::from_text(&["x"], &["x"], Noise::discrete(0.1))
    ///     .unwrap()
    ///     .discrete_time(1.0)
    ///     .unwrap()
    ///     .with_transition_mixture(jumps)
    ///     .unwrap();
    /// // G Gᵀ is the mixture's variance, 0.9 · 0.01 + 0.1 · 4.
    /// let g = model.diffusion.constant().unwrap()[(0, 0)];
    /// assert!((g * g - 0.409).abs() < 1e-12);
    /// ```
    pub fn with_transition_mixture(self, noise: GaussianMixture) -> Result<Self, ZakaiError> {
        if !self.is_discrete_time() {
            return Err(ZakaiError::Config(alloc::vec![
                crate::validate::ConfigProblem::new(
                    "model.transition_noise",
                    "a mixture transition noise needs a discrete-time model (model.dynamics = discrete): the noise of an SDE is a Brownian increment, Gaussian",
                )
            ]));
        }
        if noise.dim() != self.n {
            return Err(ZakaiError::Dimension(format!(
                "the transition noise mixture is {}-dimensional, the state {}",
                noise.dim(),
                self.n
            )));
        }
        let g = crate::linalg::psd_square_root(
            &noise.covariance(),
            "transition noise mixture's covariance",
        )?;
        let mean = noise.mean();
        let model = self.with_diffusion(g)?;
        Ok(Model {
            transition_mixture: Some(Arc::new(TransitionMixture {
                mixture: noise,
                mean,
            })),
            ..model
        })
    }

    /// The transition noise when it is a Gaussian mixture ([`Model::with_transition_mixture`]);
    /// `None` for `w_k ~ N(0, G Gᵀ)`.
    pub fn transition_mixture(&self) -> Option<&TransitionMixture> {
        self.transition_mixture.as_deref()
    }

    /// A warning for the Gaussian filters, which take a mixture transition noise through its
    /// first two moments ([`TransitionMixture`]); `None` when the noise is Gaussian.
    pub(crate) fn moments_only(&self, method: &str) -> Option<alloc::string::String> {
        self.transition_mixture.as_ref().map(|_| {
            format!("the transition noise is a Gaussian mixture: {method} takes it through its mean and covariance only (the Gaussian-sum, point-mass and particle filters carry the mixture itself)")
        })
    }

    /// True for a discrete-time model ([`Dynamics::Discrete`]).
    pub fn is_discrete_time(&self) -> bool {
        matches!(self.dynamics, Dynamics::Discrete { .. })
    }

    /// A model from text expressions in `x` (1-D) or `x1..xn`, with G = I:
    /// `Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1))`. Every invalid expression is
    /// reported at once, each with its field and character position.
    pub fn from_text(
        drift: &[&str],
        observation: &[&str],
        noise: Noise,
    ) -> Result<Self, ZakaiError> {
        Self::text_model(drift, observation, noise, None)
    }

    /// A driven model from text ([`Inputs`]): expressions in the state, the time `t` and the
    /// `inputs` known inputs `u1..uk`, with G = I:
    /// `Model::driven_from_text(&["-x + 2*u1"], &["x"], Noise::discrete(0.1), 1)`.
    pub fn driven_from_text(
        drift: &[&str],
        observation: &[&str],
        noise: Noise,
        inputs: usize,
    ) -> Result<Self, ZakaiError> {
        Self::text_model(drift, observation, noise, Some(inputs))
    }

    /// [`Model::from_text`], driven by `inputs` when given.
    fn text_model(
        drift: &[&str],
        observation: &[&str],
        noise: Noise,
        inputs: Option<usize>,
    ) -> Result<Self, ZakaiError> {
        use crate::validate::ConfigProblem;
        use alloc::string::String;
        use alloc::vec::Vec;
        let (n, m) = (drift.len(), observation.len());
        let variables = syntax::Variables::state(n).driven(inputs);
        let mut problems = Vec::new();
        let mut parse = |field: &str, texts: &[&str], out_dim: usize| {
            let owned: Vec<String> = texts.iter().map(|t| String::from(*t)).collect();
            for (i, t) in owned.iter().enumerate() {
                if let Err(e) = expression::ExpressionFunction::parse_in(
                    field,
                    core::slice::from_ref(t),
                    &variables,
                    1,
                ) {
                    problems.push(ConfigProblem::new(format!("{field}[{i}]"), format!("{e}")));
                }
            }
            expression::ExpressionFunction::parse_in(field, &owned, &variables, out_dim).ok()
        };
        let f = parse("drift", drift, n);
        let h = parse("observation", observation, m);
        if n == 0 {
            problems.push(ConfigProblem::new("drift", "needs at least one component"));
        }
        if m == 0 {
            problems.push(ConfigProblem::new(
                "observation",
                "needs at least one component",
            ));
        }
        match (f, h) {
            (Some(f), Some(h)) if problems.is_empty() => Model::assemble(
                Arc::new(f),
                Arc::new(h),
                Diffusion::Constant(DMatrix::identity(n, n)),
                noise.observation_model(m)?,
                inputs,
            ),
            _ => Err(ZakaiError::Config(problems)),
        }
    }

    /// A model from Rust closures `f(x, out)` (n outputs) and `h(x, out)` (m outputs), with
    /// G = I; derivatives by central differences (use [`ClosureFunction::with_jacobian`] and
    /// [`Model::new`] to give exact ones).
    pub fn from_closures(
        n: usize,
        m: usize,
        drift: impl Fn(&[f64], &mut [f64]) + Send + Sync + 'static,
        observation: impl Fn(&[f64], &mut [f64]) + Send + Sync + 'static,
        noise: Noise,
    ) -> Result<Self, ZakaiError> {
        Model::new(
            Arc::new(ClosureFunction::new(n, n, drift)),
            Arc::new(ClosureFunction::new(n, m, observation)),
            DMatrix::identity(n, n),
            noise.observation_model(m)?,
        )
    }

    /// The same model with diffusion G (n × n; Q = G Gᵀ), which replaces a mixture transition
    /// noise if there was one.
    pub fn with_diffusion(self, diffusion: DMatrix<f64>) -> Result<Self, ZakaiError> {
        let dynamics = self.dynamics;
        Ok(Model {
            dynamics,
            ..Model::assemble(
                self.drift,
                self.observation,
                Diffusion::Constant(diffusion),
                self.observations,
                self.inputs,
            )?
        })
    }

    /// The same model with a state-dependent diffusion `G(x)`: `g` maps the n state
    /// components to the n² entries of G, row-major (see [`Diffusion`] for what each method
    /// does with it).
    pub fn with_state_diffusion(self, g: Arc<dyn VectorFunction>) -> Result<Self, ZakaiError> {
        let diffusion = Diffusion::StateDependent(g);
        diffusion.check(self.n, self.inputs.map_or(0, |k| 1 + k))?;
        Ok(Model {
            diffusion,
            transition_mixture: None,
            ..self
        })
    }

    /// Q = G Gᵀ: a matrix when G is constant, a function of the state otherwise.
    pub fn process_noise(&self) -> ProcessNoise {
        ProcessNoise::of(&self.diffusion)
    }

    /// True for a driven model, whose functions read the time and known inputs ([`Inputs`]).
    pub fn is_driven(&self) -> bool {
        self.inputs.is_some()
    }

    /// True for continuous observations dy = h dt + dw.
    pub fn is_continuous(&self) -> bool {
        matches!(self.observations, ObservationModel::Continuous { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// A non-positive noise intensity is the structured `OutOfRange`, with its value.
    #[test]
    fn a_negative_intensity_is_out_of_range() {
        let e = Noise::ContinuousScalar(-1.0)
            .observation_model(1)
            .unwrap_err();
        assert!(
            matches!(e, ZakaiError::OutOfRange { value, requirement: "positive and finite", .. } if value == -1.0),
            "{e:?}"
        );
    }
}
