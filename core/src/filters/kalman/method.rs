//! The Gaussian filters registered as [`Method`]s: [`Kalman`] (Kalman–Bucy), [`Ekf`],
//! [`Ukf`], [`Iekf`] and [`Iokf`]. Their state is a mean and a covariance, so their memory is
//! a constant; they apply to every dimension.

use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::{
    validate_init, Ekf, EkfParams, IekfParams, IokfParams, Kalman, KalmanParams, MapKalman,
    MapSolver, Ukf, UkfParams, MAX_SUBSTEPS,
};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::double;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes, SMALL_MEMORY,
};
use crate::filters::params::Declared;
use crate::validate::ConfigProblem;

/// A Gaussian filter's own problems and those of its optional starting Gaussian `init`.
fn with_init(
    own: Vec<(&'static str, String)>,
    init: &super::GaussianInit,
    n: usize,
) -> Vec<ConfigProblem> {
    let mut problems = problems_from(own);
    problems.extend(validate_init(init, n));
    problems
}

/// The MAP-update filter of 003 with `solver`.
fn map_kalman(
    ctx: &BuildContext,
    init: &super::GaussianInit,
    substeps: usize,
    solver: MapSolver,
    name: String,
) -> Result<MapKalman, ZakaiError> {
    Ok(MapKalman::new(name, solver, ctx, init, substeps)?)
}

/// How the Gaussian filters treat a state-dependent G(x).
const GAUSSIAN_Q: &str =
    "Q(x̂) = G(x̂)G(x̂)ᵀ at the current mean in the covariance equation dP/dt = FP + PFᵀ + Q";

/// How the EKF-type filters predict through a discrete-time map.
const EKF_MAP: &str = "m ← F(m), P ← J P Jᵀ + Q(m) with J = ∂F/∂x at the mean, per transition";

/// How the Gaussian filters treat time and known inputs.
const GAUSSIAN_INPUTS: &str = "each step's inputs held over its interval, t at the interval's midpoint in the moment equations (a discrete-time map's transition at the time it reaches) and at τ_k in the update";

/// Why the MAP filters refuse time and known inputs.
const MAP_INPUTS: &str = "the second-mode watch of 003 carries the model's free distribution over several intervals at once, which a time-varying model does not allow; not implemented";

/// A Gaussian filter's description, with the parameters its params type `P` declares.
fn info<P: Declared>(key: &str, name: &str, summary: &str, paper: &str) -> MethodInfo {
    MethodInfo {
        key: key.into(),
        name: name.into(),
        summary: summary.into(),
        paper: paper.into(),
        takes: Takes::Both,
        dims: "any".into(),
        params: P::form(),
        json_only: P::json_only(),
    }
}

builder_fn!(Kalman);

impl Method for Kalman {
    const SCORE: bool = true;
    const SMOOTHING: Smoothing = Smoothing::By(
        "RTS",
        "the Rauch–Tung–Striebel smoother of the sampled model the filter updates with (Φ = e^{AΔτ}): exact on linear-Gaussian models",
    );
    const KEY: &'static str = "kalman";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Refused(
            "the exact filter of a linear-Gaussian model needs a constant G",
        );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "its matrices F, H and the transition over Δτ are computed once, for a time-invariant model",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "x_k = A x_(k−1) + b + w_k: m ← A m + b, P ← A P Aᵀ + Q (the Kalman filter itself)",
    );
    const EXACT: bool = true;
    const ALIASES: &'static [&'static str] = &["kf"];
    type Params = KalmanParams;
    type Filter = Kalman;

    /// Exact where the model is linear-Gaussian: a mixture (the measurement noise, the
    /// transition noise or the prior) is taken by its first two moments — the best linear
    /// filter, not the exact one (the Gaussian-sum filter is).
    fn exact_on(model: &crate::model::Model, prior: &crate::model::Prior) -> bool {
        let single = |m: &crate::model::GaussianMixture| m.components().len() == 1;
        let noise = match &model.observations {
            crate::model::ObservationModel::Continuous { .. } => true,
            crate::model::ObservationModel::Discrete { density } => {
                density.additive().is_some_and(single)
            }
        };
        let start = matches!(prior, crate::model::Prior::Mixture(m) if single(m));
        noise && start && model.transition_mixture.is_none()
    }

    fn info() -> MethodInfo {
        info::<Self::Params>(
            Self::KEY,
            "KF",
            "Kalman–Bucy filter, exact for linear Gaussian models",
            "Kalman & Bucy (1961); the exact reference of every paper",
        )
    }
    fn display_name(_: &KalmanParams) -> String {
        "KF".into()
    }
    fn problems(p: &KalmanParams, n: usize) -> Vec<ConfigProblem> {
        validate_init(&p.init, n)
    }
    fn suitability(problem: &ProblemContext, _: &KalmanParams) -> Result<(), String> {
        let affine = |f: &dyn crate::model::VectorFunction, what| {
            super::linear::affine_parts(f, "the Kalman–Bucy filter", what, problem.probes)
                .map(|_| ())
                .map_err(|e| format!("{e}"))
        };
        affine(&*problem.model.drift, "drift f")?;
        affine(&*problem.model.observation, "observation h")
    }
    fn memory(_: &KalmanParams, _: usize) -> Option<usize> {
        Some(SMALL_MEMORY)
    }
    fn build(ctx: &BuildContext, p: &KalmanParams, name: String) -> Result<Kalman, ZakaiError> {
        Ok(Kalman::new(name, ctx, p)?)
    }
}

builder_fn!(Ekf);

impl Method for Ekf {
    const SMOOTHING: Smoothing = Smoothing::By(
        "extended RTS",
        "the extended RTS smoother: the RTS recursion with the transition's sensitivity Φ integrated along the EKF's moment equations (dΦ/dt = ∂f/∂x(m) Φ); a Gaussian approximation",
    );
    const KEY: &'static str = "ekf";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(GAUSSIAN_Q);
    const INPUTS: crate::filters::method::Support =
        crate::filters::method::Support::Exact(GAUSSIAN_INPUTS);
    const DISCRETE_TIME: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(EKF_MAP);
    type Params = EkfParams;
    type Filter = Ekf;

    fn info() -> MethodInfo {
        info::<Self::Params>(
            Self::KEY,
            "EKF",
            "extended Kalman filter (continuous–discrete, RK4 moment equations)",
            "Jazwinski (1970); the baseline of 000 (Yueh, Lin & Yau 2014) and 002 (Shi, Yang & Yau 2018)",
        )
    }
    fn display_name(_: &EkfParams) -> String {
        "EKF".into()
    }
    fn problems(p: &EkfParams, n: usize) -> Vec<ConfigProblem> {
        with_init(p.range_problems(), &p.init, n)
    }
    fn memory(_: &EkfParams, _: usize) -> Option<usize> {
        Some(SMALL_MEMORY)
    }
    fn build(ctx: &BuildContext, p: &EkfParams, name: String) -> Result<Ekf, ZakaiError> {
        Ok(Ekf::new(name, ctx, p)?)
    }
    fn refined(p: &EkfParams, _: usize) -> Option<(EkfParams, String)> {
        let (substeps, what) = double("substeps", p.substeps, MAX_SUBSTEPS)?;
        Some((
            EkfParams {
                substeps,
                ..p.clone()
            },
            what,
        ))
    }
}

builder_fn!(Ukf);

impl Method for Ukf {
    const SMOOTHING: Smoothing = Smoothing::By(
        "unscented RTS",
        "the continuous–discrete unscented RTS smoother: the cross-covariance follows the sigma points' statistically linearised drift (dΦ/dt = E[f (x − m)ᵀ] P⁻¹ Φ); a Gaussian approximation",
    );
    const KEY: &'static str = "ukf";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(GAUSSIAN_Q);
    const INPUTS: crate::filters::method::Support =
        crate::filters::method::Support::Exact(GAUSSIAN_INPUTS);
    const DISCRETE_TIME: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(
            "the sigma points through F, m and P their weighted moments plus Q, per transition",
        );
    type Params = UkfParams;
    type Filter = Ukf;

    fn info() -> MethodInfo {
        info::<Self::Params>(
            Self::KEY,
            "UKF",
            "unscented Kalman filter (van der Merwe scaled sigma points)",
            "Julier & Uhlmann (1997); Wan & van der Merwe (2000)",
        )
    }
    fn display_name(_: &UkfParams) -> String {
        "UKF".into()
    }
    fn problems(p: &UkfParams, n: usize) -> Vec<ConfigProblem> {
        with_init(p.problems(n), &p.init, n)
    }
    fn memory(_: &UkfParams, _: usize) -> Option<usize> {
        Some(SMALL_MEMORY)
    }
    fn build(ctx: &BuildContext, p: &UkfParams, name: String) -> Result<Ukf, ZakaiError> {
        Ok(Ukf::new(name, ctx, p)?)
    }
    fn refined(p: &UkfParams, _: usize) -> Option<(UkfParams, String)> {
        let (substeps, what) = double("substeps", p.substeps, MAX_SUBSTEPS)?;
        Some((
            UkfParams {
                substeps,
                ..p.clone()
            },
            what,
        ))
    }
}

/// The iterated EKF: Gauss–Newton on the MAP problem of each update (003 (4.5)).
///
/// Builds a [`MapKalman`] (003, Kang, Salmon & Yau 2023), whose page gives the idea, an example,
/// the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Iekf;
builder_fn!(Iekf);

impl Method for Iekf {
    const SMOOTHING: Smoothing = Smoothing::By(
        "extended RTS",
        "the extended RTS smoother over the IEKF's filtered and predicted moments (the prediction is the EKF's); a Gaussian approximation",
    );
    const KEY: &'static str = "iekf";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(GAUSSIAN_Q);
    const INPUTS: crate::filters::method::Support =
        crate::filters::method::Support::Refused(MAP_INPUTS);
    const DISCRETE_TIME: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(EKF_MAP);
    type Params = IekfParams;
    type Filter = MapKalman;

    fn info() -> MethodInfo {
        info::<Self::Params>(
            Self::KEY,
            "IEKF",
            "iterated EKF: Gauss–Newton on the MAP problem of each update",
            "003 Kang, Salmon & Yau (2023), (4.5)",
        )
    }
    fn display_name(p: &IekfParams) -> String {
        format!("IEKF({})", p.iterations)
    }
    fn problems(p: &IekfParams, n: usize) -> Vec<ConfigProblem> {
        with_init(p.range_problems(), &p.init, n)
    }
    fn memory(_: &IekfParams, _: usize) -> Option<usize> {
        Some(SMALL_MEMORY)
    }
    fn build(ctx: &BuildContext, p: &IekfParams, name: String) -> Result<MapKalman, ZakaiError> {
        let solver = MapSolver::GaussNewton {
            iterations: p.iterations,
            tolerance: p.tolerance,
        };
        map_kalman(ctx, &p.init, p.substeps, solver, name)
    }
    fn refined(p: &IekfParams, _: usize) -> Option<(IekfParams, String)> {
        let (substeps, s) = double("substeps", p.substeps, MAX_SUBSTEPS)?;
        let (iterations, i) = double("iterations", p.iterations, 1000)?;
        let params = IekfParams {
            substeps,
            iterations,
            ..p.clone()
        };
        Some((params, format!("{s}, {i}")))
    }
}

/// The iterated optimisation Kalman filter: a λ-homotopy from the prior to the MAP problem
/// with guarded Newton steps (003 Algorithm 4.1).
///
/// Builds a [`MapKalman`] (003, Kang, Salmon & Yau 2023), whose page gives the idea, an example,
/// the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Iokf;
builder_fn!(Iokf);

impl Method for Iokf {
    const SMOOTHING: Smoothing = Smoothing::By(
        "extended RTS",
        "the extended RTS smoother over the IOKF's filtered and predicted moments (the prediction is the EKF's); a Gaussian approximation",
    );
    const KEY: &'static str = "iokf";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(GAUSSIAN_Q);
    const INPUTS: crate::filters::method::Support =
        crate::filters::method::Support::Refused(MAP_INPUTS);
    const DISCRETE_TIME: crate::filters::method::Support =
        crate::filters::method::Support::Approximate(EKF_MAP);
    type Params = IokfParams;
    type Filter = MapKalman;

    fn info() -> MethodInfo {
        info::<Self::Params>(
            Self::KEY,
            "IOKF",
            "iterated optimisation Kalman filter: λ-homotopy with guarded Newton steps",
            "003 Kang, Salmon & Yau (2023), Algorithm 4.1",
        )
    }
    fn display_name(p: &IokfParams) -> String {
        format!("IOKF({}×{})", p.newton_steps, p.splits)
    }
    fn problems(p: &IokfParams, n: usize) -> Vec<ConfigProblem> {
        with_init(p.range_problems(), &p.init, n)
    }
    fn memory(_: &IokfParams, _: usize) -> Option<usize> {
        Some(SMALL_MEMORY)
    }
    fn build(ctx: &BuildContext, p: &IokfParams, name: String) -> Result<MapKalman, ZakaiError> {
        let solver = MapSolver::Homotopy {
            splits: p.splits,
            newton_steps: p.newton_steps,
        };
        map_kalman(ctx, &p.init, p.substeps, solver, name)
    }
    fn refined(p: &IokfParams, _: usize) -> Option<(IokfParams, String)> {
        let (substeps, s) = double("substeps", p.substeps, MAX_SUBSTEPS)?;
        let (newton_steps, m) = double("Newton steps", p.newton_steps, 100)?;
        let params = IokfParams {
            substeps,
            newton_steps,
            ..p.clone()
        };
        Some((params, format!("{s}, {m}")))
    }
}
