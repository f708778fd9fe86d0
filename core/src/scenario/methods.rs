//! The methods a scenario can run, each with its own parameters (serde, with defaults), and
//! the one place that turns a [`MethodConfig`] into a boxed [`Filter`].

use alloc::boxed::Box;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use super::ConfigProblem;
use crate::error::ZakaiError;
use crate::filters::direct::filter::DirectFilter;
use crate::filters::fpe_split::{ContinuousDiscreteGrid, FpeScheme};
use crate::filters::gaussian_sum::GaussianSumFilter;
use crate::filters::kalman::{
    validate_init, EkfParams, ExtendedKalman, IekfParams, IokfParams, KalmanBucy, KalmanParams,
    MapKalman, MapSolver, UkfParams, UnscentedKalman,
};
use crate::filters::particle::{ParticleFilter, PfParams};
use crate::filters::spectral::SpectralFilter;
use crate::filters::Filter;
use crate::model::{Model, Prior};

pub use crate::filters::direct::filter::DirectParams;
pub use crate::filters::fpe_split::FpeParams;
pub use crate::filters::gaussian_sum::GaussianSumParams;
pub use crate::filters::spectral::SpectralParams;
pub use crate::filters::yau_fd::{Scheme, YauYauParams};

#[cfg(feature = "std")]
fn yau_yau(
    name: String,
    scheme: Scheme,
    p: &YauYauParams,
    ctx: &BuildContext,
) -> Result<Box<dyn Filter>, ZakaiError> {
    Ok(Box::new(crate::filters::yau_fd::YauYauFilter::new(
        name, scheme, ctx.model, ctx.prior, p, ctx.bounds, ctx.dt_obs,
    )?))
}

#[cfg(not(feature = "std"))]
fn yau_yau(
    name: String,
    _: Scheme,
    _: &YauYauParams,
    _: &BuildContext,
) -> Result<Box<dyn Filter>, ZakaiError> {
    Err(ZakaiError::Other(format!(
        "{name} needs the `std` feature of zakai (FFT plans)"
    )))
}

/// One method with its parameters. In JSON: `{"method": "pf", "particles": 200}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum MethodConfig {
    /// Kalman–Bucy filter (linear Gaussian models only).
    Kalman(KalmanParams),
    /// Extended Kalman filter.
    Ekf(EkfParams),
    /// Unscented Kalman filter.
    Ukf(UkfParams),
    /// Bootstrap particle filter.
    Pf(PfParams),
    /// Iterated EKF: Gauss–Newton MAP update (003 (4.5)).
    Iekf(IekfParams),
    /// Iterated optimisation Kalman filter: λ-homotopy MAP update (003 Algorithm 4.1).
    Iokf(IokfParams),
    /// Yau–Yau implicit Euler (000 (12)–(14)).
    Iem(YauYauParams),
    /// Yau–Yau quasi-implicit Euler with DST (000 (17)–(18)).
    Qiem(YauYauParams),
    /// The superposition technique of 000 §2.5 over QIEM.
    Spt(YauYauParams),
    /// Fourth-order 2-D QIEM (000 (20)–(21), Algorithm 4).
    Qiem4(YauYauParams),
    /// The off-line/on-line spectral Yau–Yau filter of 004 (generalized Legendre basis).
    Spectral(SpectralParams),
    /// The direct method of 002: Gaussian approximation and Riccati ODEs.
    Direct(DirectParams),
    /// The continuous–discrete grid filter of 001 with the separation approach (SA).
    Separation(FpeParams),
    /// The continuous–discrete grid filter of 001 with the classic implicit FDM.
    ImplicitFdm(FpeParams),
    /// The exact Gaussian-sum filter (linear models, mixture prior and noise; 001 §4).
    GaussianSum(GaussianSumParams),
}

/// What building a filter needs besides its own parameters.
pub struct BuildContext<'a> {
    /// The model.
    pub model: &'a Model,
    /// The prior.
    pub prior: &'a Prior,
    /// Seed for methods that draw random numbers.
    pub seed: u64,
    /// Points of the domain where structural assumptions (linearity) are checked.
    pub probes: &'a [Vec<f64>],
    /// The scenario's domain (grid methods live here).
    pub bounds: &'a [(f64, f64)],
    /// Δτ.
    pub dt_obs: f64,
}

/// Every method key with a one-line description (for `zakai list` and the page).
pub const METHODS: &[(&str, &str)] = &[
    (
        "kalman",
        "Kalman–Bucy filter, exact for linear Gaussian models",
    ),
    (
        "ekf",
        "extended Kalman filter (continuous–discrete, RK4 moment equations)",
    ),
    (
        "ukf",
        "unscented Kalman filter (van der Merwe scaled sigma points)",
    ),
    (
        "pf",
        "bootstrap particle filter (systematic resampling on an ESS threshold)",
    ),
    (
        "iekf",
        "iterated EKF: Gauss–Newton on the MAP problem (003 (4.5))",
    ),
    (
        "iokf",
        "iterated optimisation Kalman filter: λ-homotopy with guarded Newton steps (003 Algorithm 4.1)",
    ),
    (
        "qiem",
        "Yau–Yau quasi-implicit Euler, Laplacian by DST-I (000 (17)–(18), Algorithm 3)",
    ),
    (
        "iem",
        "Yau–Yau implicit Euler θ-scheme, tridiagonal / split (000 (12)–(14), Algorithm 2)",
    ),
    (
        "spt",
        "Yau–Yau superposition technique over QIEM (000 §2.5)",
    ),
    (
        "qiem4",
        "fourth-order 2-D QIEM (000 (20)–(21), Algorithm 4)",
    ),
    (
        "direct",
        "direct method for Yau filtering systems: Gaussian approximation + Riccati ODEs (002)",
    ),
    (
        "spectral",
        "off-line/on-line spectral Yau–Yau filter, generalized Legendre basis (004)",
    ),
    (
        "separation",
        "continuous–discrete FPE filter, separation approach: upwind FV + implicit FD (001 §3)",
    ),
    (
        "implicit_fdm",
        "continuous–discrete FPE filter, classic implicit FDM on the unsplit FPE (001 §4)",
    ),
    (
        "gaussian_sum",
        "Gaussian-sum filter, exact for linear models with mixture prior and noise (001 §4)",
    ),
];

impl MethodConfig {
    /// The method key (`"ekf"`, `"pf"`, …).
    pub fn key(&self) -> &'static str {
        match self {
            MethodConfig::Kalman(_) => "kalman",
            MethodConfig::Ekf(_) => "ekf",
            MethodConfig::Ukf(_) => "ukf",
            MethodConfig::Pf(_) => "pf",
            MethodConfig::Iekf(_) => "iekf",
            MethodConfig::Iokf(_) => "iokf",
            MethodConfig::Iem(_) => "iem",
            MethodConfig::Qiem(_) => "qiem",
            MethodConfig::Spt(_) => "spt",
            MethodConfig::Qiem4(_) => "qiem4",
            MethodConfig::Spectral(_) => "spectral",
            MethodConfig::Direct(_) => "direct",
            MethodConfig::Separation(_) => "separation",
            MethodConfig::ImplicitFdm(_) => "implicit_fdm",
            MethodConfig::GaussianSum(_) => "gaussian_sum",
        }
    }

    /// The method with default parameters, from its key.
    pub fn from_key(key: &str) -> Option<Self> {
        Some(match key {
            "kalman" | "kf" => MethodConfig::Kalman(KalmanParams::default()),
            "ekf" => MethodConfig::Ekf(EkfParams::default()),
            "ukf" => MethodConfig::Ukf(UkfParams::default()),
            "pf" => MethodConfig::Pf(PfParams::default()),
            "iekf" => MethodConfig::Iekf(IekfParams::default()),
            "iokf" => MethodConfig::Iokf(IokfParams::default()),
            "iem" => MethodConfig::Iem(YauYauParams::default()),
            "qiem" => MethodConfig::Qiem(YauYauParams::default()),
            "spt" => MethodConfig::Spt(YauYauParams::default()),
            "qiem4" => MethodConfig::Qiem4(YauYauParams::default()),
            "spectral" => MethodConfig::Spectral(SpectralParams::default()),
            "direct" => MethodConfig::Direct(DirectParams::default()),
            "separation" | "sa" => MethodConfig::Separation(FpeParams::default()),
            "implicit_fdm" | "fdm" => MethodConfig::ImplicitFdm(FpeParams::default()),
            "gaussian_sum" | "gsf" => MethodConfig::GaussianSum(GaussianSumParams::default()),
            _ => return None,
        })
    }

    /// Display name: `"KF"`, `"EKF"`, `"UKF"`, `"PF(200)"`.
    pub fn display_name(&self) -> String {
        match self {
            MethodConfig::Kalman(_) => "KF".into(),
            MethodConfig::Ekf(_) => "EKF".into(),
            MethodConfig::Ukf(_) => "UKF".into(),
            MethodConfig::Pf(p) => format!("PF({})", p.particles),
            MethodConfig::Iekf(p) => format!("IEKF({})", p.iterations),
            MethodConfig::Iokf(p) => format!("IOKF({}×{})", p.newton_steps, p.splits),
            MethodConfig::Iem(_) => "IEM".into(),
            MethodConfig::Qiem(_) => "QIEM".into(),
            MethodConfig::Spt(_) => "SPT".into(),
            MethodConfig::Qiem4(_) => "QIEM-4".into(),
            MethodConfig::Spectral(_) => "Spectral".into(),
            MethodConfig::Direct(_) => "Direct".into(),
            MethodConfig::Separation(_) => "SA".into(),
            MethodConfig::ImplicitFdm(_) => "FDM".into(),
            MethodConfig::GaussianSum(_) => "GSF".into(),
        }
    }

    /// Appends every problem with the parameters for an `n`-dimensional model.
    pub fn validate(&self, n: usize, field: &str, problems: &mut Vec<ConfigProblem>) {
        let mut push = |name: &str, msg: String| {
            problems.push(ConfigProblem::new(format!("{field}.{name}"), msg));
        };
        match self {
            MethodConfig::Kalman(p) => validate_init(&p.init, n, field, problems),
            MethodConfig::Ekf(p) => {
                if p.substeps == 0 {
                    push("substeps", "must be at least 1".into());
                }
                validate_init(&p.init, n, field, problems);
            }
            MethodConfig::Ukf(p) => {
                for (name, msg) in p.problems(n) {
                    push(name, msg);
                }
                validate_init(&p.init, n, field, problems);
            }
            MethodConfig::Pf(p) => {
                for (name, msg) in p.problems() {
                    push(name, msg);
                }
            }
            MethodConfig::Iekf(p) => {
                for (name, msg) in p.problems() {
                    push(name, msg);
                }
                validate_init(&p.init, n, field, problems);
            }
            MethodConfig::Iokf(p) => {
                for (name, msg) in p.problems() {
                    push(name, msg);
                }
                validate_init(&p.init, n, field, problems);
            }
            MethodConfig::Iem(p) | MethodConfig::Qiem(p) => {
                for (name, msg) in p.problems(n) {
                    push(name, msg);
                }
            }
            MethodConfig::Spt(p) => {
                for (name, msg) in p.problems(n).into_iter().chain(p.superposition_problems(n)) {
                    push(name, msg);
                }
            }
            MethodConfig::Qiem4(p) => {
                for (name, msg) in p.problems(n).into_iter().chain(p.fourth_order_problems(n)) {
                    push(name, msg);
                }
            }
            MethodConfig::Spectral(p) => {
                for (name, msg) in p.problems(n) {
                    push(name, msg);
                }
            }
            MethodConfig::Direct(p) => {
                for (name, msg) in p.problems(n) {
                    push(name, msg);
                }
            }
            MethodConfig::Separation(p) | MethodConfig::ImplicitFdm(p) => {
                for (name, msg) in p.problems(n) {
                    push(name, msg);
                }
            }
            MethodConfig::GaussianSum(p) => {
                for (name, msg) in p.problems() {
                    push(name, msg);
                }
            }
        }
    }

    /// Why the method does not apply to `model` and `prior` on the domain `bounds` (wrong
    /// dimension, continuous vs discrete observations, a nonlinear model for the exact linear
    /// filters, not a Yau system for the direct method, …), or `None` when it does. Cheap:
    /// nothing is built. `probes` are where linearity is checked.
    pub fn suitability(
        &self,
        model: &Model,
        prior: &Prior,
        probes: &[Vec<f64>],
        bounds: &[(f64, f64)],
    ) -> Option<String> {
        let mut problems = Vec::new();
        self.validate(model.n, "", &mut problems);
        if let Some(p) = problems.iter().find(|p| p.field == ".method") {
            return Some(p.message.clone());
        }
        let name = self.display_name();
        let result = match self {
            MethodConfig::Kalman(_) => crate::filters::kalman::linear::affine_parts(
                &*model.drift,
                "the Kalman–Bucy filter",
                "drift f",
                probes,
            )
            .and_then(|_| {
                crate::filters::kalman::linear::affine_parts(
                    &*model.observation,
                    "the Kalman–Bucy filter",
                    "observation h",
                    probes,
                )
            })
            .map(|_| ()),
            MethodConfig::Iem(_)
            | MethodConfig::Qiem(_)
            | MethodConfig::Spt(_)
            | MethodConfig::Qiem4(_)
            | MethodConfig::Spectral(_) => crate::model::dmz::continuous_noise_inverse(
                model,
                "the Yau–Yau and spectral DMZ filters",
            )
            .map(|_| ()),
            MethodConfig::Direct(p) => {
                crate::filters::direct::filter::check_system(model, p, bounds)
            }
            MethodConfig::Separation(_) | MethodConfig::ImplicitFdm(_) => {
                crate::filters::fpe_split::check_model(&name, model).map(|_| ())
            }
            MethodConfig::GaussianSum(_) => {
                crate::filters::gaussian_sum::check_model(model, prior, probes).map(|_| ())
            }
            _ => Ok(()),
        };
        result.err().map(|e| format!("{e}"))
    }

    /// Memory the method allocates for an `n`-dimensional model, estimated from its
    /// parameters before anything is allocated (bytes; `None` when it overflows).
    pub fn memory_bytes(&self, n: usize) -> Option<usize> {
        const SMALL: usize = 64 << 10;
        let f64s = |count: Option<usize>| count.and_then(|c| c.checked_mul(8));
        let per_dim =
            |counts: &[usize]| crate::filters::product(&crate::filters::per_dimension(counts, n));
        let grid = |p: &YauYauParams| {
            let nodes = per_dim(&p.points)?;
            let samples = p.likelihood_samples.checked_pow(n as u32)?;
            // u, tmp, the operator's p (n), q, div f, S⁻¹h, ½hᵀS⁻¹h, and the cell samples.
            let arrays = 8 + 2 * n + samples;
            f64s(nodes.checked_mul(arrays))
        };
        let bytes = match self {
            MethodConfig::Kalman(_)
            | MethodConfig::Ekf(_)
            | MethodConfig::Ukf(_)
            | MethodConfig::Iekf(_)
            | MethodConfig::Iokf(_) => Some(SMALL),
            MethodConfig::Pf(p) => f64s(p.particles.checked_mul(3 * n + 3)),
            MethodConfig::Iem(p) | MethodConfig::Qiem(p) | MethodConfig::Qiem4(p) => grid(p),
            MethodConfig::Spt(p) => {
                let nodes = per_dim(&p.points)?;
                let bumps = per_dim(&p.centres)?;
                grid(p)?.checked_add(f64s(nodes.checked_mul(bumps))?)
            }
            MethodConfig::Spectral(p) => {
                let (off, on) = p.counts(n);
                let (off, on) = (off.checked_pow(n as u32)?, on.checked_pow(n as u32)?);
                f64s(
                    off.checked_mul(on)?
                        .checked_mul(3)?
                        .checked_add(off.checked_mul(off)?),
                )
            }
            MethodConfig::Direct(p) => f64s(p.points.checked_mul(4 * p.max_terms + 8)),
            MethodConfig::Separation(p) | MethodConfig::ImplicitFdm(p) => {
                let cells = per_dim(&p.cells)?;
                f64s(p.band_values(n)?.checked_add(cells.checked_mul(6 + 2 * n)?))
            }
            MethodConfig::GaussianSum(p) => {
                // Candidates after an update (noise mixtures of up to 4 components assumed)
                // and their pairwise merge costs.
                let k = p.max_components.checked_mul(4)?;
                f64s(k.checked_mul(k)?.checked_add(k.checked_mul(n * n + n + 2)?))
            }
        }?;
        Some(bytes.max(SMALL))
    }

    /// Builds the filter.
    pub fn build(&self, name: String, ctx: &BuildContext) -> Result<Box<dyn Filter>, ZakaiError> {
        let (model, prior) = (ctx.model, ctx.prior);
        Ok(match self {
            MethodConfig::Kalman(p) => {
                Box::new(KalmanBucy::new(name, model, prior, p, ctx.probes)?)
            }
            MethodConfig::Ekf(p) => Box::new(ExtendedKalman::new(name, model, prior, p)),
            MethodConfig::Ukf(p) => Box::new(UnscentedKalman::new(name, model, prior, p)?),
            MethodConfig::Pf(p) => Box::new(ParticleFilter::new(name, model, prior, p, ctx.seed)?),
            MethodConfig::Iekf(p) => Box::new(MapKalman::new(
                name,
                model,
                prior,
                &p.init,
                p.substeps,
                MapSolver::GaussNewton {
                    iterations: p.iterations,
                    tolerance: p.tolerance,
                },
            )),
            MethodConfig::Iokf(p) => Box::new(MapKalman::new(
                name,
                model,
                prior,
                &p.init,
                p.substeps,
                MapSolver::Homotopy {
                    splits: p.splits,
                    newton_steps: p.newton_steps,
                },
            )),
            MethodConfig::Iem(p) => yau_yau(name, Scheme::Iem, p, ctx)?,
            MethodConfig::Qiem(p) => yau_yau(name, Scheme::Qiem, p, ctx)?,
            MethodConfig::Spt(p) => yau_yau(name, Scheme::Superposition, p, ctx)?,
            MethodConfig::Qiem4(p) => yau_yau(name, Scheme::Qiem4, p, ctx)?,
            MethodConfig::Spectral(p) => Box::new(SpectralFilter::new(
                name, model, prior, p, ctx.bounds, ctx.dt_obs,
            )?),
            MethodConfig::Direct(p) => {
                Box::new(DirectFilter::new(name, model, prior, p, ctx.bounds)?)
            }
            MethodConfig::Separation(p) => Box::new(ContinuousDiscreteGrid::new(
                name,
                FpeScheme::Separation,
                model,
                prior,
                p,
                ctx.bounds,
                ctx.dt_obs,
            )?),
            MethodConfig::ImplicitFdm(p) => Box::new(ContinuousDiscreteGrid::new(
                name,
                FpeScheme::ImplicitFdm,
                model,
                prior,
                p,
                ctx.bounds,
                ctx.dt_obs,
            )?),
            MethodConfig::GaussianSum(p) => {
                Box::new(GaussianSumFilter::new(name, model, prior, p, ctx.probes)?)
            }
        })
    }
}
