//! The Kalman–Bucy filter ([`Kalman`] documents it).

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::measurement::MeasurementForm;
use super::{GaussianState, KalmanParams};
use crate::error::FilterError;
use crate::filters::{Filter, Observation};
use crate::model::{Model, VectorFunction};

/// Jacobian of `g` at `x` as a matrix.
fn jacobian_at(g: &dyn VectorFunction, x: &[f64]) -> DMatrix<f64> {
    let (n, m) = (g.input_dim(), g.output_dim());
    let mut j = vec![0.0; n * m];
    g.jacobian(x, &mut j);
    DMatrix::from_row_slice(m, n, &j)
}

/// `(J, g(0))` of an affine `g`, or an error (for `method`) naming the first probe where `J`
/// differs.
pub(crate) fn affine_parts(
    g: &dyn VectorFunction,
    method: &str,
    what: &str,
    probes: &[Vec<f64>],
) -> Result<(DMatrix<f64>, DVector<f64>), FilterError> {
    let n = g.input_dim();
    let origin = vec![0.0; n];
    let j0 = jacobian_at(g, &origin);
    for p in probes {
        let jp = jacobian_at(g, p);
        let scale = 1.0 + j0.amax();
        if (&jp - &j0).amax() > 1e-6 * scale {
            return Err(FilterError::Unsuitable(format!(
                "{method} needs a linear model, but the Jacobian of the {what} at {p:?} differs from the one at 0"
            )));
        }
    }
    Ok((j0, DVector::from_vec(g.value(&origin))))
}

/// `(A, b)` when `f` is affine over `probes` — its Jacobian the same at every probe as at 0
/// and its values `A p + b` there —, else `None`: what lets a filter treat a model that is
/// linear, whatever its text, as the linear model it is (the particle filter's exact
/// transition, the EKF's and UKF's moments of an affine map).
pub(crate) fn affine_over(
    f: &dyn VectorFunction,
    probes: &[Vec<f64>],
) -> Option<(DMatrix<f64>, DVector<f64>)> {
    if probes.is_empty() {
        return None;
    }
    let (a, b) = affine_parts(f, "", "", probes).ok()?;
    // The values too, not only the slopes: f(p) = A p + b at every probe.
    let affine = probes.iter().all(|p| {
        let value = DVector::from_vec(f.value(p));
        let affine = &a * DVector::from_column_slice(p) + &b;
        (value - &affine).amax() <= 1e-9 * (1.0 + affine.amax())
    });
    affine.then_some((a, b))
}

/// k transitions of the map `x_k = A x_(k−1) + b + w_k`, `w_k ~ N(0, Q)`, as one:
/// `(Φ, Γ b, Q_d) = (A^k, Σ_(i<k) A^i b, Σ_(i<k) A^i Q A^iᵀ)` (the discrete Kalman filter's
/// prediction, k times).
pub(crate) fn transitions(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    q: &DMatrix<f64>,
    k: usize,
) -> (DMatrix<f64>, DVector<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let (mut phi, mut gamma_b, mut qd) = (
        DMatrix::identity(n, n),
        DVector::zeros(n),
        DMatrix::zeros(n, n),
    );
    for _ in 0..k {
        gamma_b = a * gamma_b + b;
        qd = a * qd * a.transpose() + q;
        phi = a * phi;
    }
    crate::linalg::symmetrize(&mut qd);
    (phi, gamma_b, qd)
}

/// Exact discretisation of `dx = (A x + b) dt + G dv` over `dt`: `(Φ, Γ b, Q_d)`.
pub(crate) fn discretize(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    q: &DMatrix<f64>,
    dt: f64,
) -> (DMatrix<f64>, DVector<f64>, DMatrix<f64>) {
    let n = a.nrows();
    // [[A, b], [0, 0]] Δτ  →  [[Φ, Γ b], [0, 1]].
    let mut aug = DMatrix::zeros(n + 1, n + 1);
    aug.view_mut((0, 0), (n, n)).copy_from(&(a * dt));
    aug.view_mut((0, n), (n, 1)).copy_from(&(b * dt));
    let e = crate::linalg::expm(&aug);
    let phi = e.view((0, 0), (n, n)).into_owned();
    let gamma_b = e.view((0, n), (n, 1)).column(0).into_owned();
    // Van Loan: exp([[−A, Q], [0, Aᵀ]] Δτ) = [[·, Φ⁻¹ Q_d], [0, Φᵀ]].
    let mut vl = DMatrix::zeros(2 * n, 2 * n);
    vl.view_mut((0, 0), (n, n)).copy_from(&(-a * dt));
    vl.view_mut((0, n), (n, n)).copy_from(&(q * dt));
    vl.view_mut((n, n), (n, n)).copy_from(&(a.transpose() * dt));
    let ev = crate::linalg::expm(&vl);
    let mut qd = &phi * ev.view((0, n), (n, n));
    crate::linalg::symmetrize(&mut qd);
    (phi, gamma_b, qd)
}

/// `(A, b, Q)`: a linear model's dynamics, or `(Φ, Γb, Q_d)` of one interval.
pub(crate) type LinearParts = (DMatrix<f64>, DVector<f64>, DMatrix<f64>);

/// `(A, b, Q)` of the linear dynamics `dx = (A x + b) dt + G dv` (or the map `A x + b + w_k`),
/// a mixture transition noise taken by its mean and covariance; an error when the drift is
/// not affine over `probes` or G depends on the state.
pub(crate) fn linear_dynamics(
    model: &Model,
    probes: &[Vec<f64>],
) -> Result<LinearParts, FilterError> {
    let (a, mut b) = affine_parts(&*model.drift, "the Kalman–Bucy filter", "drift f", probes)?;
    // A mixture transition noise by its mean: x_k = A x + (b + μ̄) + (w_k − μ̄).
    if let Some(w) = &model.transition_mixture {
        b += w.mean();
    }
    let q = model
        .process_noise()
        .require_constant(
            "the Kalman–Bucy filter",
            "it is the exact filter of a linear-Gaussian model",
        )?
        .clone();
    Ok((a, b, q))
}

/// The Kalman–Bucy filter.
///
/// The Kalman–Bucy filter for linear Gaussian models — the exact reference.
///
/// For a discrete-time map `x_k = A x_(k−1) + b + w_k` ([`crate::Dynamics::Discrete`]) it is
/// the Kalman filter itself: `m ← A m + b`, `P ← A P Aᵀ + Q` per transition.
///
/// For `dx = (A x + b) dt + G dv` the prediction over Δτ is exact:
/// `m ← Φ m + Γ b`, `P ← Φ P Φᵀ + Q_d` with `Φ = e^{AΔτ}`, `Γ = ∫₀^Δτ e^{As} ds` and
/// `Q_d = ∫₀^Δτ e^{As} Q e^{Aᵀs} ds` (Van Loan's block exponential). The update uses the
/// observation as a measurement (`measurement`): exact for discrete linear
/// measurements; for increments, the discrete Kalman filter of the sampled model
/// `Δy = C x Δτ + w`, `w ~ N(0, S Δτ)` (the observation integral `∫ C x dt` by its value at the
/// interval's end), which converges to the Kalman–Bucy filter as Δτ → 0 — its variance after
/// an update sits O(Δτ) below the Riccati equation's (lesson 2 of the playground: 0.0865
/// against P∞ = 0.0905 with S = 0.01, Δτ = 0.01).
///
/// The model must be affine: A, b, C, c are read off at the origin and the Jacobians are
/// checked at probe points spread over the domain; a nonlinear model is refused with an error.
///
/// # Example
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::{Filter, Kalman, Model, Noise};
///
/// // dx = −x dt + dv, z = x + v (Var v = 0.1), from N(0, 1), one measurement after 0.1.
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut kf = Kalman::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
/// kf.step_measurement(0.1, &[0.5]).unwrap();
/// // The exact prediction: P⁻ = e^{−0.2} + (1 − e^{−0.2})/2; then the gain P⁻/(P⁻ + 0.1).
/// let p = (-0.2f64).exp() + (1.0 - (-0.2f64).exp()) / 2.0;
/// assert!((kf.estimate().mean[0] - 0.5 * p / (p + 0.1)).abs() < 1e-12);
/// // A nonlinear model is refused.
/// let cubic = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
/// assert!(Kalman::builder(&cubic).prior_gaussian(&[0.0], &[[1.0]]).build().is_err());
/// # }
/// ```
///
/// # Cost
///
/// Per step, matrix exponentials and products of n × n matrices and an m × m solve:
/// O(n³ + m³).
///
/// # When it fails
///
/// It does not: on a linear Gaussian model it is exact (for increments, up to the O(Δτ) of the
/// sampled model above), and a model that is not affine is refused at construction. A noise or
/// prior that is a mixture is used through its first two moments, which is no longer exact (the
/// Gaussian-sum filter is).
#[derive(Clone, Debug)]
pub struct Kalman {
    pub(super) name: String,
    pub(super) model: Model,
    pub(super) a: DMatrix<f64>,
    pub(super) b: DVector<f64>,
    pub(super) q: DMatrix<f64>,
    pub(super) form: MeasurementForm,
    pub(super) state: GaussianState,
    /// The method's overrides of the prior's moments (for its score's perturbed priors).
    pub(super) init: super::GaussianInit,
    /// The exact discretisation of the last interval, reused while Δτ does not change.
    cached: Option<Discretization>,
    /// Storage of the prediction: Φ m and Φ P.
    moved: (DVector<f64>, DMatrix<f64>),
}

/// `(Δτ, Φ, Γ b, Q_d)` of [`discretize`].
#[derive(Clone, Debug)]
pub(crate) struct Discretization {
    pub(crate) dt: f64,
    pub(crate) phi: DMatrix<f64>,
    pub(crate) gamma_b: DVector<f64>,
    pub(crate) qd: DMatrix<f64>,
    /// Φᵀ.
    phi_t: DMatrix<f64>,
}

impl Discretization {
    /// The exact discretisation over `dt`, reusing `cache` while Δτ does not change: of the
    /// SDE, or of the k transitions of a discrete-time map ([`transitions`]).
    pub(crate) fn for_step<'c>(
        cache: &'c mut Option<Discretization>,
        (a, b, q): (&DMatrix<f64>, &DVector<f64>, &DMatrix<f64>),
        dynamics: &crate::model::Dynamics,
        dt: f64,
    ) -> Result<&'c Discretization, FilterError> {
        if cache.as_ref().map(|d| d.dt) != Some(dt) {
            let (phi, gamma_b, qd) = match dynamics {
                crate::model::Dynamics::Continuous => discretize(a, b, q, dt),
                crate::model::Dynamics::Discrete { .. } => {
                    transitions(a, b, q, dynamics.transitions(dt)?)
                }
            };
            *cache = Some(Discretization {
                dt,
                phi_t: phi.transpose(),
                phi,
                gamma_b,
                qd,
            });
        }
        Ok(cache.as_ref().expect("just filled"))
    }

    /// Moves `N(m, P)` over the interval in place: `m ← Φ m + Γ b`, `P ← Φ P Φᵀ + Q_d`, with
    /// `moved` (n, n × n) as storage.
    pub(crate) fn propagate(
        &self,
        m: &mut DVector<f64>,
        p: &mut DMatrix<f64>,
        moved: &mut (DVector<f64>, DMatrix<f64>),
    ) {
        moved.0.copy_from(&self.gamma_b);
        moved.0.gemv(1.0, &self.phi, m, 1.0);
        m.copy_from(&moved.0);
        moved.1.gemm(1.0, &self.phi, p, 0.0);
        p.copy_from(&self.qd);
        p.gemm(1.0, &moved.1, &self.phi_t, 1.0);
    }
}

impl Kalman {
    /// Builds the filter; linearity is checked at the context's probe points.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &KalmanParams,
    ) -> Result<Self, FilterError> {
        let (model, prior, probes) = (ctx.model, ctx.prior, ctx.probes);
        let (a, b, q) = linear_dynamics(model, probes)?;
        affine_parts(
            &*model.observation,
            "the Kalman–Bucy filter",
            "observation h",
            probes,
        )?;
        Ok(Kalman {
            form: MeasurementForm::new(&name, model)?,
            name,
            model: model.clone(),
            a,
            b,
            q,
            state: GaussianState::initial(prior.mean(), prior.covariance(), &params.init, model.m),
            init: params.init.clone(),
            cached: None,
            moved: (DVector::zeros(model.n), DMatrix::zeros(model.n, model.n)),
        })
    }
}

super::smoother::gaussian_filter!(Kalman);

impl Filter for Kalman {
    super::smoother::gaussian_filter_opening!(estimate);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        // Checked before anything moves: a refused observation leaves the state.
        let Kalman {
            name,
            model,
            a,
            b,
            q,
            form,
            state,
            cached,
            moved,
            ..
        } = self;
        let meas = form.at(name, obs)?;
        state.transaction(|state| {
            if obs.dt > 0.0 {
                let d = Discretization::for_step(cached, (a, b, q), &model.dynamics, obs.dt)?;
                d.propagate(&mut state.mean, &mut state.cov, moved);
                state.record_prediction(&d.phi);
            }
            match meas {
                Some(meas) => {
                    meas.noise_at(model, state.mean.as_slice())?;
                    state.linearized_update(model, meas)
                }
                None => state.check(),
            }
        })
    }

    fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
        let mut out = self.form.warnings();
        out.extend(self.model.moments_only(&self.name));
        out
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        self.state.innovations.check(out);
    }

    crate::filters::score::score_of_filter!();
}
