//! The accuracy–cost frontier: every method's MSE against its time per step as its cost knob
//! (grid size, basis size, particle count, iterations, substeps) is swept, over the same seeded
//! runs, with the optimal filter's MSE as the floor no method can beat on average.
//!
//! The floor is a *reference posterior*: the exact Gaussian-sum filter where it applies
//! (linear models with discrete, mixture noise), else QIEM on a fine grid whose convergence is
//! shown by [`reference_check`] — halving Δs and Δt must move the posterior mean by less than
//! a tolerance (the issue asks for 1e-3) over a few runs. Beyond QIEM's three dimensions the
//! grid is the tensor-train filter's (its twin halves Δs; its steps are exact one-dimensional
//! flows and splitting, with no Δt of its own).
//!
//! All methods of a sweep run in one [`Experiment`], so they see the same truth and
//! observations in every run: their MSEs are paired, and differences are not sampling noise.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::monte_carlo::MonteCarlo;
use crate::error::ZakaiError;
use crate::filters::fpe_split::FpeParams;
use crate::filters::gaussian_sum::GaussianSumParams;
use crate::filters::kalman::{EkfParams, IekfParams, UkfParams};
use crate::filters::particle::PfParams;
use crate::filters::spectral::SpectralParams;
use crate::filters::tensor_train::TensorTrainParams;
use crate::filters::yau_fd::YauYauParams;
use crate::lab::experiment::Experiment;
use crate::lab::scenario::{MethodConfig, ScenarioConfig};

/// One method at one setting of its cost knob.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// The method family (`"PF"`, `"QIEM"`, …).
    pub family: &'static str,
    /// The knob (`"particles"`, `"points"`, …).
    pub knob: &'static str,
    /// Its value.
    pub value: usize,
    /// The method's own time step, where it is swept as a second knob (the grid methods: a
    /// coarse grid gains nothing from a fine Δt, so each grid is run at several).
    pub dt: Option<f64>,
    /// The method with that setting.
    pub method: MethodConfig,
}

impl SweepPoint {
    /// The setting in words: `"191"` or `"191, Δt = 0.0025"`.
    pub fn setting(&self) -> String {
        match self.dt {
            Some(dt) => format!("{}, Δt = {dt}", self.value),
            None => format!("{}", self.value),
        }
    }
}

/// The reference posterior of a scenario and its fine twin (half the steps) for the check.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// The reference filter.
    pub method: MethodConfig,
    /// The same with Δs and Δt halved (`None` for an exact reference).
    pub finer: Option<MethodConfig>,
    /// How it is described in reports.
    pub label: String,
}

/// The reference for `config`: the exact Gaussian-sum filter where it applies, else QIEM with
/// `points` per dimension and step `dt` (the finer twin has `2·points + 1` points — half the
/// spacing — and `dt/2`), else — beyond three dimensions — the tensor-train filter with
/// `points` per dimension (its twin `2·points + 1`; `dt` does not apply).
pub fn reference(config: &ScenarioConfig, points: usize, dt: f64) -> Result<Reference, ZakaiError> {
    let e = Experiment::new(ScenarioConfig {
        methods: vec![MethodConfig::Ekf(EkfParams::default())],
        ..config.clone()
    })?;
    let probes = config.probe_points();
    let bounds = config.bounds();
    let gsf = MethodConfig::GaussianSum(GaussianSumParams {
        max_components: 256,
        ..GaussianSumParams::default()
    });
    if gsf
        .suitability(e.model(), e.prior(), &probes, &bounds)
        .is_none()
    {
        return Ok(Reference {
            method: gsf,
            finer: None,
            label: "Gaussian-sum filter (exact, 256 components)".into(),
        });
    }
    let qiem = |p: usize, dt: f64| {
        MethodConfig::Qiem(YauYauParams {
            points: vec![p],
            dt,
            ..YauYauParams::default()
        })
    };
    let method = qiem(points, dt);
    let Some(reason) = method.suitability(e.model(), e.prior(), &probes, &bounds) else {
        return Ok(Reference {
            finer: Some(qiem(2 * points + 1, dt / 2.0)),
            label: format!("QIEM, {points} points per dimension, Δt = {dt:e}"),
            method,
        });
    };
    let tt = |p: usize| {
        MethodConfig::TensorTrain(TensorTrainParams {
            points: vec![p],
            ..TensorTrainParams::default()
        })
    };
    let method = tt(points);
    if config.state_dim() <= 3
        || method
            .suitability(e.model(), e.prior(), &probes, &bounds)
            .is_some()
    {
        return Err(ZakaiError::Filter(crate::FilterError::Unsuitable(format!(
            "no reference posterior for this scenario: {reason}"
        ))));
    }
    Ok(Reference {
        finer: Some(tt(2 * points + 1)),
        label: format!("tensor-train filter, {points} points per dimension (ε 10⁻⁷, ranks ≤ 30)"),
        method,
    })
}

/// The result of [`reference_check`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceCheck {
    /// Runs compared.
    pub runs: usize,
    /// Largest |x̂_ref − x̂_finer| over the runs, the observation times and the components.
    pub max_mean_change: f64,
}

/// Runs the reference and its finer twin on seeds `seed..seed + runs` and reports the largest
/// change of the posterior mean.
pub fn reference_check(
    config: &ScenarioConfig,
    reference: &Reference,
    runs: usize,
    seed: u64,
) -> Result<Option<ReferenceCheck>, ZakaiError> {
    let Some(finer) = &reference.finer else {
        return Ok(None);
    };
    let e = Experiment::new(ScenarioConfig {
        methods: vec![reference.method.clone(), finer.clone()],
        ..config.clone()
    })?;
    let mut worst = 0.0f64;
    for r in 0..runs as u64 {
        let result = e.run(seed + r)?;
        let (a, b) = (&result.methods[0], &result.methods[1]);
        if a.failed() || b.failed() {
            return Err(ZakaiError::Other(format!(
                "the reference failed in run {}: {:?}",
                seed + r,
                a.failure
                    .as_ref()
                    .or(b.failure.as_ref())
                    .map(|f| &f.message)
            )));
        }
        for (x, y) in a.estimates.iter().zip(&b.estimates) {
            worst = worst.max(libm::fabs(x - y));
        }
    }
    Ok(Some(ReferenceCheck {
        runs,
        max_mean_change: worst,
    }))
}

/// The default sweep for `config`: every method family that applies to the model, each over
/// its cost knob.
pub fn default_sweep(config: &ScenarioConfig) -> Result<Vec<SweepPoint>, ZakaiError> {
    let n = config.state_dim();
    let dt_obs = config.time.dt_obs;
    // The grid methods' steps: one per observation interval, four, and the fine
    // min(Δτ, 10⁻³) (each at most once).
    let fine = dt_obs.min(1e-3);
    let mut grid_steps: Vec<f64> = [dt_obs, dt_obs / 4.0, fine]
        .into_iter()
        .filter(|&dt| dt >= fine)
        .collect();
    grid_steps.dedup();
    // N + 1 = 3·2^k or 2^k: the DST-I of QIEM runs on FFTs of length N + 1, fast for these.
    let grid_points: &[usize] = match n {
        1 => &[47, 95, 191, 383, 767],
        2 => &[15, 31, 63, 127],
        _ => &[7, 15, 31],
    };
    let mut all: Vec<SweepPoint> = Vec::new();
    let add = |all: &mut Vec<SweepPoint>,
               family,
               knob,
               values: &[usize],
               make: &dyn Fn(usize) -> MethodConfig| {
        for &value in values {
            all.push(SweepPoint {
                family,
                knob,
                value,
                dt: None,
                method: make(value),
            });
        }
    };
    add(&mut all, "EKF", "substeps", &[1, 4, 16], &|s| {
        MethodConfig::Ekf(EkfParams {
            substeps: s,
            ..EkfParams::default()
        })
    });
    add(&mut all, "UKF", "substeps", &[1, 4, 16], &|s| {
        MethodConfig::Ukf(UkfParams {
            substeps: s,
            ..UkfParams::default()
        })
    });
    add(&mut all, "IEKF", "iterations", &[1, 3, 10], &|i| {
        MethodConfig::Iekf(IekfParams {
            iterations: i,
            ..IekfParams::default()
        })
    });
    add(
        &mut all,
        "PF",
        "particles",
        &[50, 100, 200, 500, 1000, 2000, 5000],
        &|p| {
            MethodConfig::Pf(PfParams {
                particles: p,
                ..PfParams::default()
            })
        },
    );
    for (family, make) in [
        (
            "QIEM",
            MethodConfig::Qiem as fn(YauYauParams) -> MethodConfig,
        ),
        ("IEM", MethodConfig::Iem),
    ] {
        for &value in grid_points {
            for &dt in &grid_steps {
                let params = YauYauParams {
                    points: vec![value],
                    dt,
                    ..YauYauParams::default()
                };
                all.push(SweepPoint {
                    family,
                    knob: "points",
                    value,
                    dt: Some(dt),
                    method: make(params),
                });
            }
        }
    }
    add(
        &mut all,
        "Spectral",
        "online basis",
        &[6, 8, 12, 16, 24, 32, 48, 64, 80, 96, 128],
        &|k| {
            MethodConfig::Spectral(SpectralParams {
                online_basis: Some(k),
                offline_basis: Some(k.max(11)),
                ..SpectralParams::default()
            })
        },
    );
    // The tensor-train filter: in 1-D a grid filter like QIEM (its one-dimensional flow is the
    // exact exponential), beyond it the only grid-exact method past three dimensions.
    let tt_points: &[usize] = match n {
        1 => &[48, 96, 192, 384],
        _ => &[16, 32, 64, 128],
    };
    add(&mut all, "TT", "points", tt_points, &|p| {
        MethodConfig::TensorTrain(TensorTrainParams {
            points: vec![p],
            ..TensorTrainParams::default()
        })
    });
    add(&mut all, "SA", "cells", &[25, 50, 100, 200, 400], &|c| {
        MethodConfig::Separation(FpeParams {
            cells: vec![c],
            dt: 0.01,
        })
    });
    add(&mut all, "FDM", "cells", &[25, 50, 100, 200, 400], &|c| {
        MethodConfig::ImplicitFdm(FpeParams {
            cells: vec![c],
            dt: 0.01,
        })
    });
    let e = Experiment::new(ScenarioConfig {
        methods: vec![MethodConfig::Ekf(EkfParams::default())],
        ..config.clone()
    })?;
    let (probes, bounds) = (config.probe_points(), config.bounds());
    all.retain(|p| {
        let mut problems = Vec::new();
        p.method.validate(n, "", &mut problems);
        problems.is_empty()
            && p.method
                .suitability(e.model(), e.prior(), &probes, &bounds)
                .is_none()
    });
    Ok(all)
}

/// One point of the frontier: a swept method's MSE and cost.
#[derive(Clone, Debug, PartialEq)]
pub struct FrontierPoint {
    /// What was swept.
    pub sweep: SweepPoint,
    /// Mean MSE (004 (43)) over the runs where the method did not fail.
    pub mse: Option<f64>,
    /// Its standard error.
    pub mse_stderr: Option<f64>,
    /// Runs in which the method failed.
    pub failed: usize,
    /// Mean wall time per observation interval (seconds).
    pub seconds_per_step: f64,
}

/// The frontier of a scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct Frontier {
    /// Runs.
    pub runs: usize,
    /// The floor: the reference's label, MSE and its standard error.
    pub floor: (String, f64, f64),
    /// The reference's time per step.
    pub floor_seconds_per_step: f64,
    /// Every swept point.
    pub points: Vec<FrontierPoint>,
}

impl Frontier {
    /// The cheapest point (by time per step) of `family` whose MSE is within `fraction` of the
    /// floor (e.g. 0.05 for 5 %).
    pub fn cheapest_within(&self, family: &str, fraction: f64) -> Option<&FrontierPoint> {
        let bound = self.floor.1 * (1.0 + fraction);
        self.points
            .iter()
            .filter(|p| {
                p.sweep.family == family && p.failed == 0 && p.mse.is_some_and(|m| m <= bound)
            })
            .min_by(|a, b| a.seconds_per_step.total_cmp(&b.seconds_per_step))
    }
}

/// Runs the reference and every swept method on seeds `seed..seed + runs` (one experiment:
/// paired runs); `progress` is called after each run.
pub fn frontier(
    config: &ScenarioConfig,
    reference: &Reference,
    sweep: &[SweepPoint],
    runs: usize,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Result<Frontier, ZakaiError> {
    let mut methods = vec![reference.method.clone()];
    methods.extend(sweep.iter().map(|p| p.method.clone()));
    let e = Experiment::new(ScenarioConfig {
        methods,
        ..config.clone()
    })?;
    let summary = MonteCarlo::new(&e).run(runs, seed, progress)?;
    let floor = &summary.methods[0];
    let Some(floor_mse) = floor.mse else {
        return Err(ZakaiError::Other(format!(
            "the reference failed in every run: {}",
            floor.first_failure.clone().unwrap_or_default()
        )));
    };
    let points = sweep
        .iter()
        .zip(&summary.methods[1..])
        .map(|(p, s)| FrontierPoint {
            sweep: p.clone(),
            mse: s.mse,
            mse_stderr: s.mse_stderr,
            failed: s.failed,
            seconds_per_step: s.seconds_per_step,
        })
        .collect();
    Ok(Frontier {
        runs,
        floor: (
            reference.label.clone(),
            floor_mse,
            floor.mse_stderr.unwrap_or(0.0),
        ),
        floor_seconds_per_step: floor.seconds_per_step,
        points,
    })
}
