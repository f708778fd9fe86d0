//! Fixed-interval smoothing ([`Smoother`] documents it).

use alloc::boxed::Box;
use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use super::{normalise_on_grid, DensityView, Estimate, Filter, Observation};
use crate::error::FilterError;
use crate::grid::{Moments, TensorGrid};

/// How a method smooths, for the catalogue: the smoother and what it computes, or why the
/// method has none.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Smoothing {
    /// The method's smoother: a short name and what it computes (what is exact, what is
    /// approximate, its cost).
    By(&'static str, &'static str),
    /// The method has no smoother, and why.
    NotAvailable(&'static str),
}

/// [`Smoothing`] as the catalogue shows it (serde).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SmootherInfo {
    /// The smoother's name (`"RTS"`, `"forward–backward"`, `"FFBSi"`), or `None` when the
    /// method has none.
    pub name: Option<String>,
    /// What it computes, or why there is none.
    pub summary: String,
}

impl From<Smoothing> for SmootherInfo {
    fn from(s: Smoothing) -> Self {
        match s {
            Smoothing::By(name, summary) => SmootherInfo {
                name: Some(name.into()),
                summary: summary.into(),
            },
            Smoothing::NotAvailable(why) => SmootherInfo {
                name: None,
                summary: why.into(),
            },
        }
    }
}

/// What a smoother is told before its forward pass, so that it can check its memory before
/// it allocates anything.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SmoothingPlan {
    /// The steps the forward pass will take (an estimate; more are accepted while the memory
    /// lasts).
    pub steps: usize,
    /// The most bytes the smoother's records may take ([`crate::validate::memory_cap`] by
    /// default).
    pub memory_cap: usize,
}

impl SmoothingPlan {
    /// A plan for `steps` steps under the process's memory cap.
    pub fn for_steps(steps: usize) -> Self {
        SmoothingPlan {
            steps,
            memory_cap: crate::validate::memory_cap(),
        }
    }

    /// An error when `per_step` bytes for every planned step (and one more) exceed the cap.
    pub fn check(&self, name: &str, per_step: usize, what: &str) -> Result<(), FilterError> {
        let need = per_step.checked_mul(self.steps + 1);
        match need {
            Some(b) if b <= self.memory_cap => Ok(()),
            _ => Err(FilterError::Unsuitable(format!(
                "{name}'s smoother would keep {} for {} steps ({what}), more than the memory cap of {} MiB",
                need.map_or_else(|| "more than usize::MAX bytes".into(), |b| format!("{} MiB", b >> 20)),
                self.steps,
                self.memory_cap >> 20
            ))),
        }
    }
}

/// One smoothed time: `index` 0 is the time the forward pass started at, `i` the time after its
/// i-th step.
#[derive(Clone, Copy, Debug)]
pub struct SmoothedStep<'a> {
    /// Which time (see above).
    pub index: usize,
    /// The smoothed mean and covariance.
    pub estimate: &'a Estimate,
    /// The smoothed density, for grid smoothers.
    pub density: Option<DensityView<'a>>,
}

impl SmoothedStep<'_> {
    /// The smoothed marginal density of component `dim` at the points `at`, into `out`: the
    /// grid smoother's own density integrated over the other components, else the Gaussian
    /// of the smoothed mean and variance.
    pub fn marginal_density(&self, dim: usize, at: &[f64], out: &mut [f64]) {
        if let Some(grid) = self.density.and_then(|v| {
            TensorGrid::new(v.bounds, v.shape)
                .ok()
                .map(|g| (g, v.values))
        }) {
            grid.0.marginal(grid.1, dim, at, out);
            return;
        }
        let var = self
            .estimate
            .covariance
            .as_ref()
            .map_or(0.0, |p| p[(dim, dim)]);
        super::marginal::gaussian(self.estimate.mean[dim], var, at, out);
    }
}

/// A fixed-interval smoother: a filter (its forward pass, which steps exactly as the method's
/// filter does) that keeps what its backward pass needs.
///
/// Fixed-interval smoothing: the best estimate of the state at every observation time from
/// **all** the data, `p(x_k | z_1:N)`, where a filter gives `p(x_k | z_1:k)`.
///
/// Every smoother is a forward pass and a backward pass. The forward pass is the method's own
/// filter, which a [`Smoother`] wraps: it steps exactly as the filter does and keeps what the
/// backward pass needs. [`Smoother::smooth`] then runs backward over the steps taken. A filter
/// becomes its smoother with [`Filter::smoother`](super::Filter::smoother); a method without
/// one returns an error saying why (and says so in the catalogue, [`Smoothing`]).
///
/// * **Gaussian filters** (Kalman–Bucy, EKF, UKF, IEKF, IOKF): the Rauch–Tung–Striebel
///   recursion in its general Gaussian form (Särkkä 2013, *Bayesian Filtering and Smoothing*,
///   ch. 8–10):
///   `G_k = C_{k,k+1} P⁻_{k+1}⁻¹`, `m^s_k = m_k + G_k (m^s_{k+1} − m⁻_{k+1})`,
///   `P^s_k = P_k + G_k (P^s_{k+1} − P⁻_{k+1}) G_kᵀ` (S1)
///   with `C_{k,k+1} = Cov(x_k, x_{k+1} | z_1:k) = P_k Φ_kᵀ`, where Φ_k solves `dΦ/dt = A(t) Φ`,
///   `Φ(0) = I`, along the filter's own moment equations: A = ∂f/∂x at the mean for the EKF
///   (the extended RTS smoother), A = E[f(x)(x − m)ᵀ] P⁻¹ by the sigma points for the UKF
///   (the statistically linearised drift of Särkkä's continuous–discrete unscented RTS
///   smoother), A the drift matrix for the Kalman–Bucy filter (Φ = e^{AΔτ}: the exact RTS
///   smoother of the sampled model, the one the filter updates with).
/// * **Grid filters**: the forward–backward recursion on the filter's own grid. If one step of
///   the scheme carries the density as `p⁻_{k+1} = T_k p_k` (the discrete Fokker–Planck or
///   Kolmogorov operator, exactly as the filter applies it) and then multiplies by the
///   likelihood, the smoothed densities of that discrete model are
///   `p^s_k = p_k ⊙ T_kᵀ (p^s_{k+1} ⊘ p⁻_{k+1})` (S2)
///   (the discrete form of `p(x_k | z_1:N) = p(x_k | z_1:k)
///   ∫ p(x_{k+1} | x_k) p(x_{k+1} | z_1:N) / p(x_{k+1} | z_1:k) dx_{k+1}`, whose Gaussian case
///   is the RTS recursion), so the smoothed
///   density is consistent with the filter's, and converges with it as the grid is refined.
///   `T_kᵀ` — one step of the backward equation's solution operator in the scheme's
///   discretisation — is each
///   scheme's transposed step (`GridTransition::carry_back`: the θ-scheme's and 001's
///   tridiagonal solves transposed with the same factors, QIEM's symmetric DST solve and
///   antisymmetric drift differences, the superposition map transposed, 001's upwind part).
/// * **Particle filter**: forward filtering, backward simulation (FFBSi; Godsill, Doucet &
///   West 2004): trajectories drawn backward through the stored particle clouds with
///   probabilities `∝ w_k^i p(x_{k+1} | x_k^i)`, the transition density of the filter's own
///   Euler–Maruyama steps. Its cost is O(M N) per Euler step for M trajectories and N
///   particles.
pub trait Smoother: Filter {
    /// The backward pass over the steps taken so far: `visit` sees every smoothed time, from
    /// the last to the first (index 0). The forward pass is not changed and may go on.
    fn smooth(&mut self, visit: &mut dyn FnMut(SmoothedStep<'_>)) -> Result<(), FilterError>;
    /// What the smoother approximates or costs on this run, beyond the catalogue's summary.
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }
}

/// The smoothed estimates of `smoother`, in time order: n + 1 of them after n steps, entry 0
/// at the time the forward pass started (the prior, smoothed by every observation) and entry
/// `i` at the time after the i-th step — so entry `i` pairs with the filter's estimate after
/// step `i`, and with observation `i − 1` of the steps' sequence (0-based).
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::{smoothed_estimates, Filter, Model, Noise, SmoothingPlan, Ukf};
///
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
/// let ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
/// let mut smoother = ukf.smoother(&SmoothingPlan::for_steps(3)).unwrap();
/// for z in [0.3, 0.5, 0.4] {
///     smoother.step_measurement(0.1, &[z]).unwrap();
/// }
/// let smoothed = smoothed_estimates(smoother.as_mut()).unwrap();
/// assert_eq!(smoothed.len(), 4); // the start and the three steps
/// // At the last step the smoothed estimate is the filter's.
/// assert!((smoothed[3].mean[0] - smoother.estimate().mean[0]).abs() < 1e-12);
/// println!("sd at the start, smoothed: {}", smoothed[0].sd(0));
/// # }
/// ```
pub fn smoothed_estimates(smoother: &mut dyn Smoother) -> Result<Vec<Estimate>, FilterError> {
    let mut out: Vec<Estimate> = Vec::new();
    smoother.smooth(&mut |step| out.push(step.estimate.clone()))?;
    out.reverse();
    Ok(out)
}

/// The [`Filter`] methods of a smoother that are its forward pass's (the filter in field
/// `$filter`), and [`Filter::as_smoother`]; `step` is the smoother's own.
macro_rules! forward_pass {
    ($filter:ident) => {
        fn name(&self) -> &str {
            self.$filter.name()
        }
        fn log_likelihood(&self) -> Option<f64> {
            self.$filter.log_likelihood()
        }
        fn estimate(&self) -> $crate::filters::Estimate {
            self.$filter.estimate()
        }
        fn estimate_into(&self, out: &mut $crate::filters::Estimate) {
            self.$filter.estimate_into(out)
        }
        fn density(&self) -> Option<$crate::filters::DensityView<'_>> {
            self.$filter.density()
        }
        fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
            self.$filter.warnings()
        }
        fn self_check(&self, out: &mut alloc::vec::Vec<$crate::filters::Concern>) {
            self.$filter.self_check(out)
        }
        fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
            self.$filter.marginal_density(dim, grid, out)
        }
        fn as_smoother(&mut self) -> Option<&mut dyn $crate::filters::smoothing::Smoother> {
            Some(self)
        }
    };
}
pub(crate) use forward_pass;

/// [`GridTransition`]'s storage methods for a grid filter whose density is its field `u`,
/// normalised by its `normalise()`, and whose field `predicted: Option<Vec<f64>>` keeps the
/// last step's predicted density when asked (invoked in the filter's own module); with
/// `carried by forward, backward`, also `carry` and `carry_back` by the filter's methods
/// `forward(dt)` and `backward(dt)` (its prediction over `dt` on `u` and its transpose) run
/// on the values in `u`'s place.
macro_rules! density_storage {
    (carried by $forward:ident, $backward:ident) => {
        #[cfg(test)]
        fn carry(&mut self, obs: &Observation, values: &mut Vec<f64>) -> Result<(), FilterError> {
            if obs.dt > 0.0 {
                core::mem::swap(&mut self.u, values);
                let carried = self.$forward(obs.dt);
                core::mem::swap(&mut self.u, values);
                carried?;
            }
            Ok(())
        }

        fn carry_back(
            &mut self,
            obs: &Observation,
            values: &mut Vec<f64>,
        ) -> Result<(), FilterError> {
            if obs.dt > 0.0 {
                core::mem::swap(&mut self.u, values);
                let carried = self.$backward(obs.dt, obs.inputs);
                core::mem::swap(&mut self.u, values);
                carried?;
            }
            Ok(())
        }

        crate::filters::smoothing::density_storage!();
    };
    () => {
        fn restore(&mut self, values: &[f64]) -> Result<(), FilterError> {
            self.u.copy_from_slice(values);
            self.normalise()
        }

        fn keep_predicted(&mut self) {
            self.predicted = Some(self.u.clone());
        }

        fn last_predicted(&self) -> &[f64] {
            self.predicted.as_deref().unwrap_or(&[])
        }
    };
}
pub(crate) use density_storage;

/// The refusal of a method without a smoother.
pub(crate) fn no_smoother(name: &str, why: &str) -> FilterError {
    FilterError::Unsuitable(format!("{name} has no smoother: {why}"))
}

/// What a grid filter gives its forward–backward smoother (S2): its density, the predicted
/// density of its last step, and the scheme's transposed step.
pub(crate) trait GridTransition: Filter + Clone + 'static {
    /// The grid and the current (normalised) density on it.
    fn grid_density(&self) -> (&TensorGrid, &[f64]);
    /// Carries `values` over `obs.dt` as the step with `obs` does before it assimilates:
    /// `values ← T_k values`, not renormalised (the forward pass keeps the step's own
    /// [`GridTransition::last_predicted`] instead; this is for the adjoint tests).
    #[cfg(test)]
    fn carry(&mut self, obs: &Observation, values: &mut Vec<f64>) -> Result<(), FilterError>;
    /// The transposed step: `values ← T_kᵀ values` for the step with `obs`.
    fn carry_back(&mut self, obs: &Observation, values: &mut Vec<f64>) -> Result<(), FilterError>;
    /// Sets the filter's density to `values` (already normalised), to refilter a segment
    /// from a checkpoint.
    fn restore(&mut self, values: &[f64]) -> Result<(), FilterError>;
    /// Keeps every step's predicted density `p⁻ = T_k p_k` (before the update) from now on.
    fn keep_predicted(&mut self);
    /// The last step's predicted density (after [`GridTransition::keep_predicted`]).
    fn last_predicted(&self) -> &[f64];
}

/// A recorded step: its length, observation and, for a driven model, its time and inputs
/// (kept so that the backward pass can redo the step's operator, and a segment between
/// checkpoints can be refiltered).
#[derive(Clone, Debug)]
struct StepRecord {
    dt: f64,
    value: Vec<f64>,
    kind: super::ObservationKind,
    inputs: Option<(f64, Vec<f64>)>,
}

impl StepRecord {
    fn observation(&self) -> Observation<'_> {
        Observation {
            dt: self.dt,
            value: &self.value,
            kind: self.kind,
            inputs: self
                .inputs
                .as_ref()
                .map(|(t, u)| crate::model::Inputs { t: *t, u }),
        }
    }
}

/// The forward–backward smoother (S2) of a grid filter `F`. Every step's filtered and
/// predicted densities are kept when they fit under the memory cap; otherwise the filtered
/// density every `stride` steps (checkpoints), and the backward pass refilters each segment
/// between two checkpoints from the first (memory: the checkpoints and one segment, for one
/// more forward pass).
#[derive(Clone, Debug)]
pub(crate) struct GridSmoother<F: GridTransition> {
    filter: F,
    /// A copy of the filter the backward pass steps and carries with.
    worker: F,
    steps: Vec<StepRecord>,
    /// The filtered density after step `i · stride` (index 0: the start).
    checkpoints: Vec<Vec<f64>>,
    /// With `stride` 1, every step's predicted density.
    predicted: Vec<Vec<f64>>,
    stride: usize,
    cells: usize,
}

impl<F: GridTransition> GridSmoother<F> {
    /// The smoother of `filter` from its current state, for `plan`: every density is kept
    /// when they fit under the cap, else checkpoints every ⌈√steps⌉-th (refused when even
    /// those do not fit).
    pub(crate) fn new(filter: &F, plan: &SmoothingPlan) -> Result<Self, FilterError> {
        let cells = filter.grid_density().1.len();
        let bytes = cells.saturating_mul(core::mem::size_of::<f64>());
        let stride = match plan.check(
            filter.name(),
            bytes.saturating_mul(2),
            "the filtered and predicted densities of every step",
        ) {
            Ok(()) => 1,
            Err(_) => {
                let stride = libm::ceil(libm::sqrt(plan.steps.max(1) as f64)) as usize;
                // The checkpoints, and one segment's filtered and predicted densities.
                let kept = plan.steps / stride + 2 * stride + 2;
                let per = bytes.saturating_mul(kept) / (plan.steps + 1).max(1) + 1;
                plan.check(
                    filter.name(),
                    per,
                    "densities at checkpoints every ⌈√N⌉ steps and one segment",
                )?;
                stride
            }
        };
        let mut filter = filter.clone();
        filter.keep_predicted();
        Ok(GridSmoother {
            worker: filter.clone(),
            checkpoints: vec![filter.grid_density().1.to_vec()],
            filter,
            steps: Vec::new(),
            predicted: Vec::new(),
            stride,
            cells,
        })
    }
}

/// The filtered densities before `steps` and the steps' predicted densities, refiltered by
/// `worker` from the checkpoint `start` (the density before the first of them).
#[allow(clippy::type_complexity)]
fn refilter<F: GridTransition>(
    worker: &mut F,
    start: &[f64],
    steps: &[StepRecord],
) -> Result<(Vec<Vec<f64>>, Vec<Vec<f64>>), FilterError> {
    let mut filtered = Vec::with_capacity(steps.len());
    let mut predicted = Vec::with_capacity(steps.len());
    worker.restore(start)?;
    filtered.push(start.to_vec());
    for (j, record) in steps.iter().enumerate() {
        worker.step(&record.observation())?;
        predicted.push(worker.last_predicted().to_vec());
        if j + 1 < steps.len() {
            filtered.push(worker.grid_density().1.to_vec());
        }
    }
    Ok((filtered, predicted))
}

impl<F: GridTransition> Filter for GridSmoother<F> {
    forward_pass!(filter);
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        self.filter.step(obs)?;
        self.steps.push(StepRecord {
            dt: obs.dt,
            value: obs.value.to_vec(),
            kind: obs.kind,
            inputs: obs.inputs.map(|i| (i.t, i.u.to_vec())),
        });
        if self.stride == 1 {
            self.predicted.push(self.filter.last_predicted().to_vec());
        }
        if self.steps.len().is_multiple_of(self.stride) {
            self.checkpoints.push(self.filter.grid_density().1.to_vec());
        }
        Ok(())
    }
}

impl<F: GridTransition> Smoother for GridSmoother<F> {
    fn smooth(&mut self, visit: &mut dyn FnMut(SmoothedStep<'_>)) -> Result<(), FilterError> {
        let last = self.steps.len();
        let grid = self.filter.grid_density().0.clone();
        let n = grid.dim();
        let mut moments = Moments::zeros(n);
        let mut estimate = Estimate::zeros(n);
        // p^s at the last step is the filtered density.
        let mut smoothed = self.filter.grid_density().1.to_vec();
        normalise_on_grid(&grid, &mut smoothed, &mut moments, &mut estimate)?;
        visit(SmoothedStep {
            index: last,
            estimate: &estimate,
            density: Some(grid.view(&smoothed)),
        });
        let mut ratio = vec![0.0; self.cells];
        let mut k = last;
        while k > 0 {
            // The segment [from, k) of steps whose densities the recursion needs.
            let from = ((k - 1) / self.stride) * self.stride;
            // Kept (every step's, with `stride` 1), or refiltered from the segment's checkpoint.
            let refiltered;
            let (filtered, predicted): (&[Vec<f64>], &[Vec<f64>]) = if self.stride == 1 {
                (&self.checkpoints[from..k], &self.predicted[from..k])
            } else {
                let start = &self.checkpoints[from / self.stride];
                refiltered = refilter(&mut self.worker, start, &self.steps[from..k])?;
                (&refiltered.0, &refiltered.1)
            };
            for j in (from..k).rev() {
                // r = p^s_(j+1) ⊘ p⁻_(j+1) (0 where nothing was predicted: there p^s is 0
                // too), then p^s_j = p_j ⊙ T_jᵀ r.
                let pred = &predicted[j - from];
                let top = pred.iter().fold(0.0f64, |a, &b| a.max(b));
                for ((r, s), p) in ratio.iter_mut().zip(&smoothed).zip(pred) {
                    *r = if *p > 1e-300 * top && *p > 0.0 {
                        s / p
                    } else {
                        0.0
                    };
                }
                self.worker
                    .carry_back(&self.steps[j].observation(), &mut ratio)?;
                for ((s, p), r) in smoothed.iter_mut().zip(&filtered[j - from]).zip(&ratio) {
                    *s = (p * r).max(0.0);
                }
                normalise_on_grid(&grid, &mut smoothed, &mut moments, &mut estimate)?;
                visit(SmoothedStep {
                    index: j,
                    estimate: &estimate,
                    density: Some(grid.view(&smoothed)),
                });
            }
            k = from;
        }
        Ok(())
    }

    fn notes(&self) -> Vec<String> {
        if self.stride > 1 {
            vec![format!(
                "densities kept every {} steps (memory cap); each segment was refiltered in the backward pass",
                self.stride
            )]
        } else {
            Vec::new()
        }
    }
}

/// `Box<dyn Smoother>` of a grid filter.
pub(crate) fn grid_smoother<F: GridTransition>(
    filter: &F,
    plan: &SmoothingPlan,
) -> Result<Box<dyn Smoother>, FilterError> {
    Ok(Box::new(GridSmoother::new(filter, plan)?))
}
