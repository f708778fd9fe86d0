//! The methods a scenario can run: the one registration list (`registry!`) from which the
//! serde-tagged [`MethodConfig`], key lookup, display names, checks, memory estimates,
//! construction and the method catalogue ([`catalogue`]) are generated. Everything about a
//! method lives in its family's folder (its [`Method`] implementation); this file only lists
//! the families.

use alloc::boxed::Box;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use super::ConfigProblem;
use crate::error::ZakaiError;
use crate::filters::direct::Direct;
use crate::filters::fpe_split::{ImplicitFdm, Separation};
use crate::filters::gaussian_sum::GaussianSum;
use crate::filters::kalman::{Ekf, Iekf, Iokf, Kalman, Ukf};
use crate::filters::method::memory_estimate;
use crate::filters::method::{BuildContext, Method, MethodInfo, ProblemContext};
use crate::filters::particle::Pf;
use crate::filters::point_mass::PointMass;
use crate::filters::spectral::Spectral;
use crate::filters::tensor_train::TensorTrainFilter;
use crate::filters::yau_fd::{Iem, Qiem, Qiem4, Spt};
use crate::filters::Filter;
use crate::model::{Model, Prior};

/// One method of the catalogue: its description and its default parameters (as a
/// [`MethodConfig`], so it serializes to the JSON a scenario holds).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CatalogueEntry {
    /// Key, names, paper and parameter schema.
    #[serde(flatten)]
    pub info: MethodInfo,
    /// Other keys accepted on the command line.
    pub aliases: Vec<&'static str>,
    /// Whether the method is built for one observation interval Δτ.
    pub needs_interval: bool,
    /// Whether the method lives on the scenario's domain.
    pub needs_domain: bool,
    /// Whether the method is an exact reference (never marked failed by the track-loss test).
    pub exact: bool,
    /// Whether the method's posterior is a density on a grid or basis (the page's density
    /// panel shows one of these by default).
    pub density: bool,
    /// Whether the method draws random numbers (its likelihood is random in the parameters).
    pub random: bool,
    /// Whether the method gives its score, ln L with its gradient in the parameters (a fit then
    /// uses L-BFGS).
    pub score: bool,
    /// Its fixed-interval smoother, or why it has none.
    pub smoother: crate::filters::smoothing::SmootherInfo,
    /// What it does with a state-dependent diffusion G(x).
    pub state_diffusion: crate::filters::method::Support,
    /// What it does with a driven model (time and known inputs).
    pub inputs: crate::filters::method::Support,
    /// What it does with a discrete-time model `x_k = F(x_(k−1), t_k, u_k) + w_k`.
    pub discrete_time: crate::filters::method::Support,
    /// The default parameters.
    pub defaults: MethodConfig,
}

/// Generates [`MethodConfig`] and its dispatch from `Variant => MethodType` lines; the serde
/// tag of a variant (its snake_case name) must be the method's [`Method::KEY`] (tested).
macro_rules! registry {
    ($($(#[$attr:meta])* $variant:ident => $method:ty,)*) => {
        /// One method with its parameters. In JSON: `{"method": "pf", "particles": 200}`.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "method", rename_all = "snake_case")]
        pub enum MethodConfig {
            $($(#[$attr])* #[doc = concat!("[`", stringify!($method), "`].")] $variant(<$method as Method>::Params),)*
        }

        impl MethodConfig {
            /// The method key (`"ekf"`, `"pf"`, …).
            pub fn key(&self) -> &'static str {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::KEY,)* }
            }

            /// The method with default parameters, from its key or an alias (`"kf"`, `"sa"`).
            pub fn from_key(key: &str) -> Option<Self> {
                $($(#[$attr])* {
                    if key == <$method>::KEY || <$method>::ALIASES.contains(&key) {
                        return Some(MethodConfig::$variant(Default::default()));
                    }
                })*
                None
            }

            /// Display name with the sizes that matter: `"KF"`, `"PF(200)"`, `"IEKF(6)"`.
            pub fn display_name(&self) -> String {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::display_name(p),)* }
            }

            /// The name with the resolution of an `n`-dimensional run (`"QIEM(399)"`), see
            /// [`Method::label`].
            pub fn label(&self, n: usize) -> String {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::label(p, n),)* }
            }

            /// The method's description.
            pub fn info(&self) -> MethodInfo {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::info(),)* }
            }

            /// Whether the method is built for one observation interval Δτ.
            pub fn needs_interval(&self) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::NEEDS_INTERVAL,)* }
            }

            /// Whether the method lives on the scenario's domain.
            pub fn needs_domain(&self) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::NEEDS_DOMAIN,)* }
            }

            /// Whether the method draws random numbers ([`Method::RANDOM`]).
            pub fn is_random(&self) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::RANDOM,)* }
            }
            /// Whether the method gives its score ([`Method::SCORE`]).
            pub fn has_score(&self) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::SCORE,)* }
            }
            /// The method's smoother, or why it has none ([`Method::SMOOTHING`]).
            pub fn smoothing(&self) -> crate::filters::smoothing::Smoothing {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::SMOOTHING,)* }
            }
            /// Whether the method is an exact reference on this model and prior
            /// ([`Method::exact_on`]).
            pub fn is_exact_on(&self, model: &crate::model::Model, prior: &crate::model::Prior) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::exact_on(model, prior),)* }
            }

            /// Whether the method's posterior is a density on a grid or basis ([`Method::DENSITY`]).
            pub fn has_density(&self) -> bool {
                match self { $($(#[$attr])* MethodConfig::$variant(_) => <$method>::DENSITY,)* }
            }

            /// Every problem with the parameters for an `n`-dimensional model, fields
            /// relative to the method (`"particles"`, `"init.mean"`, `"method"`).
            pub fn problems(&self, n: usize) -> Vec<ConfigProblem> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::problems(p, n),)* }
            }

            /// Points per dimension of the method's grid, `None` without one
            /// ([`Method::grid_shape`]).
            pub fn grid_shape(&self, n: usize) -> Option<Vec<usize>> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::grid_shape(p, n),)* }
            }

            /// Why the method does not apply to this problem, or `Ok` (cheap: nothing built).
            pub fn check_suitability(&self, problem: &ProblemContext) -> Result<(), String> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => crate::filters::method::suitability_of::<$method>(problem, p),)* }
            }

            /// Memory the method allocates for an `n`-dimensional model, estimated from its
            /// parameters before anything is allocated (bytes; `None` when it overflows).
            pub fn memory_bytes(&self, n: usize) -> Option<usize> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => memory_estimate::<$method>(p, n),)* }
            }

            /// The method at doubled resolution with what was doubled, or `None` (exact
            /// filters; sizes past the method's limits), see [`Method::refined`].
            pub fn refined(&self, n: usize) -> Option<(MethodConfig, String)> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::refined(p, n).map(|(p, what)| (MethodConfig::$variant(p), what)),)* }
            }

            /// The method with the sizes left unset chosen from the problem, and a note of
            /// what was chosen, or `None` (see [`Method::problem_defaults`]).
            pub fn problem_defaults(&self, problem: &ProblemContext) -> Option<(MethodConfig, String)> {
                match self { $($(#[$attr])* MethodConfig::$variant(p) => crate::filters::method::problem_defaults_of::<$method>(problem, p).map(|(p, note)| (MethodConfig::$variant(p), note)),)* }
            }

            /// Why this method and `other` compute the same estimates on `problem`, when
            /// the family knows ([`Method::coincidence`]).
            pub fn coincidence(&self, other: &MethodConfig, problem: &ProblemContext) -> Option<String> {
                let other_params: &dyn core::any::Any = match other { $($(#[$attr])* MethodConfig::$variant(q) => q,)* };
                match self { $($(#[$attr])* MethodConfig::$variant(p) => <$method>::coincidence(p, other.key(), other_params, problem),)* }
            }

            /// Builds the filter.
            pub fn build(&self, name: String, ctx: &BuildContext) -> Result<Box<dyn Filter>, ZakaiError> {
                Ok(match self {
                    $($(#[$attr])* MethodConfig::$variant(p) => Box::new(crate::filters::method::build_of::<$method>(ctx, p, name)?),)*
                })
            }
        }

        /// Every registered method: description, aliases and default parameters (for
        /// `zakai list`, the wasm crate's schema and the page's forms).
        pub fn catalogue() -> Vec<CatalogueEntry> {
            alloc::vec![$($(#[$attr])* CatalogueEntry {
                info: <$method>::info(),
                aliases: <$method>::ALIASES.to_vec(),
                needs_interval: <$method>::NEEDS_INTERVAL,
                needs_domain: <$method>::NEEDS_DOMAIN,
                exact: <$method>::EXACT,
                density: <$method>::DENSITY,
                random: <$method>::RANDOM,
                score: <$method>::SCORE,
                smoother: <$method>::SMOOTHING.into(),
                state_diffusion: <$method>::STATE_DIFFUSION,
                inputs: <$method>::INPUTS,
                discrete_time: <$method>::DISCRETE_TIME,
                defaults: MethodConfig::$variant(Default::default()),
            },)*]
        }
    };
}

registry! {
    Kalman => Kalman,
    Ekf => Ekf,
    Ukf => Ukf,
    Pf => Pf,
    Iekf => Iekf,
    Iokf => Iokf,
    Qiem => Qiem,
    Iem => Iem,
    Spt => Spt,
    Qiem4 => Qiem4,
    Spectral => Spectral,
    Direct => Direct,
    Separation => Separation,
    ImplicitFdm => ImplicitFdm,
    GaussianSum => GaussianSum,
    PointMass => PointMass,
    TensorTrain => TensorTrainFilter,
}

impl MethodConfig {
    /// Appends every problem with the parameters for an `n`-dimensional model, its fields
    /// under `field` (`"methods[2]"`).
    pub fn validate(&self, n: usize, field: &str, problems: &mut Vec<ConfigProblem>) {
        for p in self.problems(n) {
            problems.push(ConfigProblem::new(
                format!("{field}.{}", p.field),
                p.message,
            ));
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
        if let Some(p) = self
            .problems(model.n)
            .into_iter()
            .find(|p| p.field == "method")
        {
            return Some(p.message);
        }
        let problem = ProblemContext {
            model,
            prior,
            probes,
            bounds,
            dt_obs: None,
            frozen_at_start: false,
        };
        self.check_suitability(&problem).err()
    }
}
