//! J(t) of 001 §4: the integrated squared error `J(t) = ∫ (p̂(x, t | z^k) − p(x, t | z^k))² dx`
//! of a grid filter's density against the exact Gaussian-sum density, at the measurement
//! times (before the update, J'_k, and after it, J_k) and in between (Fig. 4 of 001).
//!
//! The driver runs the continuous–discrete grid filters of the scenario (`separation`,
//! `implicit_fdm`) and the Gaussian-sum reference (the scenario's `gaussian_sum` method, or
//! one with default parameters) on the same simulated measurements, predicting each
//! observation interval in `per_interval` equal parts and sampling J after each. The integral
//! is the midpoint rule over the filter's cells, the reference evaluated at the centres.

use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::filters::fpe_split::{ContinuousDiscreteGrid, FpeScheme};
use crate::filters::gaussian_sum::{GaussianSum, GaussianSumParams, Reduction};
use crate::filters::Filter;
use crate::lab::experiment::Experiment;
use crate::lab::scenario::MethodConfig;

/// Where in the observation cycle a sample of J was taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JKind {
    /// After the Bayes update at t_k: J_k (circles in 001 Fig. 4).
    Filtering,
    /// Just before the update at t_k: J'_k (crosses in 001 Fig. 4).
    Predictive,
    /// Strictly between two measurement times.
    Between,
}

/// One sample of J(t) for every grid filter.
#[derive(Clone, Debug, PartialEq)]
pub struct JSample {
    /// Time t.
    pub t: f64,
    /// Where in the cycle.
    pub kind: JKind,
    /// J(t) per grid filter, in [`JCurve::names`] order.
    pub values: Vec<f64>,
}

/// J(t) of one run.
#[derive(Clone, Debug)]
pub struct JCurve {
    /// The grid filters' display names.
    pub names: Vec<String>,
    /// The samples, in time order.
    pub samples: Vec<JSample>,
    /// Per grid filter: mean over the measurement times of |x̂ − x̂_GSF| (the distance of its
    /// conditional mean from the exact one).
    pub mean_gap: Vec<f64>,
    /// How far the reference's mixture reduction moved it from the exact density.
    pub reduction: Reduction,
    /// Components of the reference at the end of the run.
    pub components: usize,
}

impl JCurve {
    /// Fraction of samples (of `kinds`) where filter `a`'s J is below filter `b`'s.
    pub fn fraction_below(&self, a: usize, b: usize, kinds: &[JKind]) -> f64 {
        let chosen: Vec<&JSample> = self
            .samples
            .iter()
            .filter(|s| kinds.contains(&s.kind))
            .collect();
        let below = chosen.iter().filter(|s| s.values[a] < s.values[b]).count();
        below as f64 / chosen.len().max(1) as f64
    }

    /// Mean J of filter `i` over the samples of `kinds`.
    pub fn mean(&self, i: usize, kinds: &[JKind]) -> f64 {
        let v: Vec<f64> = self
            .samples
            .iter()
            .filter(|s| kinds.contains(&s.kind))
            .map(|s| s.values[i])
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    }
}

/// `∫ (p̂ − p)² dx` on the filter's cells, with `reference` scratch for p at the centres.
fn integrated_squared_error(
    filter: &ContinuousDiscreteGrid,
    gsf: &GaussianSum,
    reference: &mut [f64],
) -> f64 {
    let grid = filter.grid();
    gsf.tabulate(grid, reference);
    let values = filter.density().map_or(&[][..], |d| d.values);
    values
        .iter()
        .zip(reference.iter())
        .map(|(p, q)| (p - q) * (p - q))
        .sum::<f64>()
        * grid.cell_volume()
}

/// Runs J(t) for `experiment` with `seed` (see the module doc).
pub fn j_curve(
    experiment: &Experiment,
    seed: u64,
    per_interval: usize,
) -> Result<JCurve, ZakaiError> {
    let config = experiment.config();
    let (model, prior) = (experiment.model(), experiment.prior());
    if let Some(why) = crate::filters::method::refusal::<crate::filters::gaussian_sum::GaussianSum>(
        model,
    )
    .or_else(|| crate::filters::method::refusal::<crate::filters::fpe_split::Separation>(model))
    {
        return Err(crate::error::FilterError::Unsuitable(why).into());
    }
    let bounds = config.bounds();
    let dt_obs = config.time.dt_obs;
    let probes = config.probe_points();
    let ctx = crate::filters::method::BuildContext {
        model,
        prior,
        seed,
        probes: &probes,
        bounds: &bounds,
        dt_obs: Some(dt_obs),
        supplied: None,
    };
    let mut grids = Vec::new();
    let mut gsf_params = GaussianSumParams::default();
    for (method, name) in config.methods.iter().zip(experiment.method_names()) {
        let (scheme, params) = match method {
            MethodConfig::Separation(p) => (FpeScheme::Separation, p),
            MethodConfig::ImplicitFdm(p) => (FpeScheme::ImplicitFdm, p),
            MethodConfig::GaussianSum(p) => {
                gsf_params = p.clone();
                continue;
            }
            _ => continue,
        };
        grids.push(ContinuousDiscreteGrid::new(
            name.clone(),
            scheme,
            &ctx,
            params,
        )?);
    }
    if grids.is_empty() {
        return Err(ZakaiError::Other(
            "J(t) needs at least one `separation` or `implicit_fdm` method in the scenario".into(),
        ));
    }
    let mut gsf = GaussianSum::new("GSF".into(), &ctx, &gsf_params)?;
    let per_interval = per_interval.max(1);
    let trajectory = experiment.simulate(seed)?;
    let mut scratch: Vec<Vec<f64>> = grids.iter().map(|g| vec![0.0; g.grid().len()]).collect();
    let mut samples = Vec::new();
    let mut gap = vec![0.0; grids.len()];
    let mut sample = |t: f64,
                      kind: JKind,
                      grids: &[ContinuousDiscreteGrid],
                      gsf: &GaussianSum,
                      samples: &mut Vec<JSample>| {
        let values = grids
            .iter()
            .zip(scratch.iter_mut())
            .map(|(g, r)| integrated_squared_error(g, gsf, r))
            .collect();
        samples.push(JSample { t, kind, values });
    };
    for k in 0..=trajectory.steps() {
        let t = trajectory.times[k];
        if k > 0 {
            let h = dt_obs / per_interval as f64;
            for part in 1..=per_interval {
                for g in &mut grids {
                    g.predict(h)?;
                }
                gsf.predict(h)?;
                let kind = if part == per_interval {
                    JKind::Predictive
                } else {
                    JKind::Between
                };
                sample(
                    t - dt_obs + part as f64 * h,
                    kind,
                    &grids,
                    &gsf,
                    &mut samples,
                );
            }
        }
        let z = trajectory.observation(k);
        for g in &mut grids {
            g.update(z)?;
        }
        gsf.update(z)?;
        sample(t, JKind::Filtering, &grids, &gsf, &mut samples);
        let exact = gsf.estimate().mean;
        for (g, gap) in grids.iter().zip(gap.iter_mut()) {
            *gap += (g.estimate().mean - &exact).norm();
        }
    }
    let count = (trajectory.steps() + 1) as f64;
    Ok(JCurve {
        names: grids.iter().map(|g| String::from(g.name())).collect(),
        samples,
        mean_gap: gap.iter().map(|g| g / count).collect(),
        reduction: gsf.reduction(),
        components: gsf.len(),
    })
}
