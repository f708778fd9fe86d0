//! The continuous–discrete grid filter itself: Fokker–Planck steps between measurements
//! (the separation approach or the unsplit implicit FDM), Bayes' rule at each one.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::implicit::{ImplicitPart, ImplicitStep};
use super::numerical_diffusion;
use super::upwind::UpwindAdvection;
use super::{FpeParams, FpeScheme, MAX_SUBSTEPS};
use crate::error::{FilterError, ZakaiError};
use crate::filters::{
    normalise_on_grid, Estimate, Filter, LengthCache, Observation, ObservationKind, Observed,
    REMAINDER_PLANS,
};
use crate::grid::cross::CrossDiffusion;
use crate::grid::TensorGrid;
use crate::model::{MeasurementDensity, Model, ObservationModel};

/// The model fits the filter: discrete measurements (their density `p(z | x)` is returned;
/// any family, the update (6) multiplies it in node by node). Mixed terms of `Q = G Gᵀ`
/// (which 001 (24) does not have) are checked for diagonal dominance on the grid when the
/// filter is built (`grid::cross`).
pub(crate) fn check_model(name: &str, model: &Model) -> Result<MeasurementDensity, FilterError> {
    let noise = match &model.observations {
        ObservationModel::Discrete { density } => density.clone(),
        ObservationModel::Continuous { .. } => {
            return Err(FilterError::Unsuitable(format!(
                "{name} is the continuous–discrete filter of 001: it needs discrete measurements z_k = h(x_k) + v_k, and this model observes dy = h dt + dw"
            )))
        }
    };
    Ok(noise)
}

/// The grid of cells that tile `bounds` (the ends of the box are cell faces).
pub(super) fn cell_grid(
    params: &FpeParams,
    bounds: &[(f64, f64)],
) -> Result<TensorGrid, ZakaiError> {
    cells_over(bounds, &params.shape(bounds.len()))
}

/// The grid of `shape` cells that tile `bounds` (the ends of the box are cell faces; the
/// centres at `a + (i + ½)Δ`): the finite volumes of 001 (11), and the point-mass filter's
/// points.
pub(crate) fn cells_over(bounds: &[(f64, f64)], shape: &[usize]) -> Result<TensorGrid, ZakaiError> {
    let cell_bounds: Vec<(f64, f64)> = bounds
        .iter()
        .zip(shape)
        .map(|(&(a, b), &c)| {
            let half = 0.5 * (b - a) / c as f64;
            (a - half, b + half)
        })
        .collect();
    TensorGrid::new(&cell_bounds, shape)
}

/// `a = G Gᵀ` on the cells of `grid`: the diagonal the implicit step takes and the mixed
/// terms' explicit step; refused where `a` is not finite or its mixed terms cannot be made
/// positive on these cells (see `CrossDiffusion::diagonal_left`). Checked before a run as well (the method's
/// suitability), so that such a model is "not applicable" rather than a failed build.
pub(super) fn diffusion_on(
    name: &str,
    model: &Model,
    grid: &TensorGrid,
) -> Result<(Vec<Vec<f64>>, CrossDiffusion), FilterError> {
    let table = model
        .process_noise()
        .tabulate(model.n, grid.len(), |i, x| grid.node(i, x));
    table.require_finite(name)?;
    let cross = CrossDiffusion::new(grid, &table.off);
    let diffusion = cross.diagonal_left(name, grid, table.diagonal)?;
    Ok((diffusion, cross))
}

/// What the filter tabulates from the model on its cells: once for an autonomous model, at
/// every step for a driven one ([`crate::Inputs`]: the dynamics at the interval's
/// midpoint, the measurement at its end).
#[derive(Clone, Debug)]
pub(super) struct Tabulated {
    pub(super) advection: UpwindAdvection,
    pub(super) divergence: Vec<f64>,
    /// `a_ll = (G Gᵀ)_ll` at every cell, per dimension.
    pub(super) diffusion: Vec<Vec<f64>>,
    /// The mixed terms of `a`, a positive explicit step (`grid::cross`).
    pub(super) cross: CrossDiffusion,
    /// p(z | x) and h at the cell centres.
    pub(super) measurement: crate::filters::grid_state::GridMeasurement,
}

impl Tabulated {
    /// f, ∇·f and a = G Gᵀ of `dynamics`, h and p(z | x) of `measurement`, on `grid`.
    pub(super) fn of(
        name: &str,
        grid: &TensorGrid,
        dynamics: &Model,
        measurement: &Model,
    ) -> Result<Self, FilterError> {
        let noise = check_model(name, measurement)?;
        let n = dynamics.n;
        let advection = UpwindAdvection::new(grid, &*dynamics.drift);
        let mut jac = vec![0.0; n * n];
        let mut divergence = Vec::with_capacity(grid.len());
        grid.for_each_node(|_, x| {
            dynamics.drift.jacobian(x, &mut jac);
            divergence.push((0..n).map(|l| jac[l * n + l]).sum());
        });
        let (diffusion, cross) = diffusion_on(name, dynamics, grid)?;
        Ok(Tabulated {
            advection,
            divergence,
            diffusion,
            cross,
            measurement: crate::filters::grid_state::GridMeasurement::new(
                grid,
                measurement,
                &noise,
            ),
        })
    }
}

/// How an observation interval is cut into FPE steps.
#[derive(Clone, Debug)]
pub(super) struct StepPlan {
    pub(super) substeps: usize,
    pub(super) dt: f64,
    pub(super) implicit: ImplicitStep,
}

/// The continuous–discrete grid filter.
///
/// The continuous–discrete grid filter of 001 (Šimandl & Švácha, 2005), with the separation
/// approach to the Fokker–Planck equation and the classic implicit FDM it is compared with.
///
/// Model (001 (1)–(2)): `dx = f(x) dt + G dw`, measurements `z_k = h(x_k) + v_k` at the
/// observation times, `v_k` Gaussian or a Gaussian mixture. The density lives on a tensor grid
/// of `N_1 × ⋯ × N_n` cells covering the scenario's domain; `P[i]` is the cell average and the
/// value at the cell centre (001 (11), (18)).
///
/// * **Bayes update** at `t_k` (001 (6)–(7)): `P ← P · p_v(z_k − h(x[i])) / c'_k`, evaluated in
///   the log domain so that a sharp likelihood cannot underflow the whole grid.
/// * **Prediction** between measurements: the FPE (4)
///   `∂p/∂t = −∇p · f − p ∇·f + ½ Σ_l Q_ll ∂²p/∂x_l²` over `M` steps of `Δt` by one of two
///   schemes ([`FpeScheme`]) — with `½ Σ_l ∂²(a_ll p)/∂x_l²` in its place when `a = G Gᵀ`
///   depends on the state (`implicit`), and the mixed terms `Σ_{l<k} ∂_l∂_k (a_lk p)`, which
///   001 does not have, as an explicit positive step of their own before the implicit one
///   (`crate::grid::cross`: a diffusion along the grid's diagonals that lends part of the
///   diagonal of `a`):
///   - the **separation approach** (SA, 001 §3): per step, the hyperbolic part (9) by the
///     explicit upwind finite-volume scheme (12)–(14) / (19)–(22) (`upwind`), then the
///     parabolic part (10) by the implicit scheme (17) / (24) (`implicit`) — tridiagonal
///     solves along the grid lines of each axis in turn (exactly (17) in 1-D, a
///     locally one-dimensional splitting of (24) in more), factored once per step length;
///   - the **classic implicit FDM** on the unsplit FPE (the comparator of 001 §4).
///
/// **Step choice.** `Δt` is the parameter `dt` rounded down to divide the observation interval
/// Δτ, then reduced further — the filter sub-steps automatically — until the CFL condition
/// (16) / (23) `Σ_l |f_l| Δt / Δx_l ≤ 1` holds at every cell (SA) and `1 + Δt min ∇·f ≥ ½`
/// (both: the implicit matrix then keeps a dominant positive diagonal). When that happens the
/// filter says so in its [`Filter::warnings`](crate::Filter::warnings). The FDM's central differences lose positivity
/// when a cell Péclet number `|f_l| Δx_l / Q_ll` exceeds 1; that is a grid condition no step
/// choice can fix, so it is a warning.
///
/// 001 (24) discretises the diagonal of `Q = G Gᵀ` only. Mixed terms are taken when the cells
/// allow a nonnegative scheme, `a_ll ≥ Σ_k |a_lk| Δx_l/Δx_k` at every cell (a correlated Q with
/// cells shaped like it); otherwise the model is refused with where, and the explicit step's
/// condition `Δt Σ_{l<k} |a_lk|/(Δx_lΔx_k) ≤ 1` sub-steps like the CFL condition.
///
/// Cost: per observation interval, Δτ/Δt steps of O(cells) each (a tridiagonal solve per
/// grid line and dimension, the upwind fluxes), and one likelihood per cell at a
/// measurement.
///
/// ```
/// use zakai::{Filter, Model, Noise, Separation};
///
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut filter = Separation::builder(&model)
///     .prior_gaussian(&[0.0], &[[1.0]])
///     .domain(&[(-6.0, 6.0)])
///     .dt(0.5)
///     .build()
///     .unwrap();
/// filter.step_measurement(0.5, &[0.3]).unwrap();
/// assert!(filter.estimate().mean[0] > 0.0);
/// ```
///
/// # When it fails
///
/// On a box too small for the posterior (mass at its edge) or cells too coarse for it, the
/// self-checks say so ([`crate::Filter::self_check`]); the step choice above keeps the CFL and
/// positivity conditions, and says when it had to sub-step, and the FDM's Péclet condition, which
/// no step can fix, is a warning ([`crate::Filter::warnings`]).
#[derive(Clone, Debug)]
pub struct ContinuousDiscreteGrid {
    pub(super) name: String,
    pub(super) scheme: FpeScheme,
    pub(super) grid: TensorGrid,
    /// The model on the cells.
    pub(super) table: Tabulated,
    pub(super) m: usize,
    /// A driven model ([`crate::Inputs`]), tabulated anew at every step.
    pub(super) driven: Option<Model>,
    target_dt: f64,
    /// Δτ, the observation interval the filter is built for.
    pub(super) dt_obs: f64,
    /// The plan for Δτ, and for up to [`REMAINDER_PLANS`] other lengths (the remainders of
    /// irregular intervals after whole Δτ), the most recently used first.
    plan: Option<StepPlan>,
    remainders: LengthCache<StepPlan>,
    pub(super) u: Vec<f64>,
    /// The density and estimate a step started from.
    saved: crate::filters::SavedDensity,
    /// The last step's log-likelihood ([`Filter::log_likelihood`]).
    log_likelihood: f64,
    tmp: Vec<f64>,
    /// One cell centre while the likelihood is evaluated.
    node: Vec<f64>,
    estimate: Estimate,
    /// Storage of the estimate's moments (see [`normalise_on_grid`]).
    moments: crate::grid::Moments,
    warnings: Vec<String>,
    /// The FDM's steps per unit time that keep implicit Euler's numerical diffusion, weighted
    /// by the prior, at [`numerical_diffusion::FDM_PRIOR_RATIO_TARGET`] of the model's (0 for SA,
    /// whose numerical diffusion is the cells'; 0 where the model has no diffusion of its
    /// own, which no step fixes).
    accuracy_rate: f64,
    /// The last step's predicted density (before its update), kept for a smoother.
    predicted: Option<Vec<f64>>,
}

impl ContinuousDiscreteGrid {
    /// Builds the filter on `bounds` (the cells tile the box) for observation interval
    /// `dt_obs` (used for the step-choice warnings).
    pub(crate) fn new(
        name: String,
        scheme: FpeScheme,
        ctx: &crate::filters::method::BuildContext,
        params: &FpeParams,
    ) -> Result<Self, ZakaiError> {
        let dt_obs = ctx.interval(&name)?;
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        let n = model.n;
        let problems = params.problems(n);
        if let Some((field, msg)) = problems.first() {
            return Err(ZakaiError::InvalidParameter {
                method: name,
                field,
                message: msg.clone(),
            });
        }
        let grid = cell_grid(params, bounds)?;
        // A driven model is tabulated at its start (t = 0, the first inputs unknown: zeros)
        // for the step-choice warnings; every step tabulates it anew.
        let start = model.at(0.0, &vec![0.0; model.inputs.unwrap_or(0)])?;
        let table = Tabulated::of(&name, &grid, &start, &start)?;
        let (u, moments, estimate) = crate::filters::grid_state::prior_on_grid(&grid, prior)?;
        let len = grid.len();
        // The FDM's ratio is proportional to Δt: its value at Δt = 1 over the target is the
        // rate of steps.
        let accuracy_rate = match scheme {
            FpeScheme::ImplicitFdm => {
                let per_unit_time = numerical_diffusion::numerical_diffusion_ratio(
                    scheme,
                    &grid,
                    &table.advection,
                    &table.diffusion,
                    1.0,
                    &u,
                );
                let rate = per_unit_time / numerical_diffusion::FDM_PRIOR_RATIO_TARGET;
                if rate.is_finite() {
                    rate
                } else {
                    0.0
                }
            }
            FpeScheme::Separation => 0.0,
        };
        let mut filter = ContinuousDiscreteGrid {
            name,
            scheme,
            grid,
            table,
            m: model.m,
            driven: model.is_driven().then(|| model.clone()),
            target_dt: params.dt,
            dt_obs,
            plan: None,
            remainders: LengthCache::new(REMAINDER_PLANS),
            saved: crate::filters::SavedDensity::new(len, &estimate),
            log_likelihood: 0.0,
            u,
            tmp: vec![0.0; len],
            node: vec![0.0; n],
            estimate,
            moments,
            warnings: Vec::new(),
            accuracy_rate,
            predicted: None,
        };
        let (_, notes) = filter.step_count(dt_obs)?;
        filter.warnings = notes;
        filter.plan_for(dt_obs)?;
        if scheme == FpeScheme::ImplicitFdm {
            filter.warnings.extend(filter.peclet_warning());
        }
        Ok(filter)
    }

    /// The operators of a driven model's step: `table` in place of the last one, and the
    /// implicit step for Δτ factorised for it (the remainders' plans are dropped).
    fn retabulate(&mut self, table: Tabulated) -> Result<(), FilterError> {
        self.table = table;
        self.remainders = LengthCache::new(REMAINDER_PLANS);
        self.plan_for(self.dt_obs)
    }

    /// The grid of cell centres.
    pub fn grid(&self) -> &TensorGrid {
        &self.grid
    }

    /// The scheme.
    pub fn scheme(&self) -> FpeScheme {
        self.scheme
    }

    /// FPE steps per observation interval of length `interval` (see the module doc), with the
    /// notes on why more steps than `interval / dt` were needed.
    pub fn step_count(&self, interval: f64) -> Result<(usize, Vec<String>), FilterError> {
        let mut notes = Vec::new();
        let requested = libm::ceil(interval / self.target_dt - 1e-9).max(1.0);
        let mut steps = requested;
        let mut x = vec![0.0; self.grid.dim()];
        // An explicit part with a rate bound: Δt ≤ 1/rate, sub-stepping (with a note) if not.
        let mut explicit = |what: &str, (rate, idx): (f64, usize), steps: &mut f64| {
            let needed = libm::ceil(rate * interval);
            if needed > *steps {
                self.grid.node(idx, &mut x);
                notes.push(format!(
                    "{what} reaches {:.3} at x = {:?} with Δt = {:.3e}; the filter sub-steps with Δt = {:.3e} ({} steps per observation interval)",
                    rate * interval / *steps,
                    rounded(&x),
                    interval / *steps,
                    interval / needed,
                    needed
                ));
                *steps = needed;
            }
        };
        if self.scheme == FpeScheme::Separation {
            explicit(
                "(16)/(23) CFL: Σ|f_l|Δt/Δx_l",
                self.table.advection.courant_rate(&self.grid),
                &mut steps,
            );
        }
        if !self.table.cross.is_empty() {
            explicit(
                "mixed terms of Q = G Gᵀ (an explicit step): Σ_(l<k) |a_lk| Δt/(Δx_l Δx_k)",
                self.table.cross.rate_bound(self.grid.len()),
                &mut steps,
            );
        }
        // Capped: beyond it the self-check reports the ratio (a run is not refused for it).
        let needed = libm::ceil(self.accuracy_rate * interval)
            .min(numerical_diffusion::FDM_ACCURACY_SUBSTEPS as f64);
        if needed > steps {
            notes.push(format!(
                "implicit Euler's numerical diffusion ½f²Δt, weighted by the prior, is {:.3} of the model's ½a with Δt = {:.3e}; the filter sub-steps with Δt = {:.3e} ({} steps per observation interval, at most {}) to bring it towards {}",
                self.accuracy_rate * numerical_diffusion::FDM_PRIOR_RATIO_TARGET * interval / steps,
                interval / steps,
                interval / needed,
                needed,
                numerical_diffusion::FDM_ACCURACY_SUBSTEPS,
                numerical_diffusion::FDM_PRIOR_RATIO_TARGET
            ));
            steps = needed;
        }
        let (min_div, idx) =
            self.table
                .divergence
                .iter()
                .enumerate()
                .fold(
                    (f64::INFINITY, 0),
                    |acc, (i, &d)| if d < acc.0 { (d, i) } else { acc },
                );
        if min_div < 0.0 {
            let needed = libm::ceil(2.0 * -min_div * interval);
            if needed > steps {
                self.grid.node(idx, &mut x);
                notes.push(format!(
                    "diagonal of the implicit step: 1 + Δt ∇·f = {:.3} < ½ at x = {:?}; the filter sub-steps with Δt = {:.3e} ({} steps per observation interval)",
                    1.0 + interval / steps * min_div,
                    rounded(&x),
                    interval / needed,
                    needed
                ));
                steps = needed;
            }
        }
        if !steps.is_finite() || steps > MAX_SUBSTEPS as f64 {
            // Say what asked for the steps, and the parameter that fixes it.
            let why = if notes.is_empty() {
                format!(
                    "the interval {interval:.4e} in steps of the method's Δt = {:.4e}; raise the method's `dt` (or check the times' unit: a recording in seconds makes a yearly Δτ 3.2e7)",
                    self.target_dt
                )
            } else {
                format!(
                    "{}; use fewer cells or a smaller domain (the conditions scale with Δx)",
                    notes.join("; ")
                )
            };
            return Err(FilterError::Unsuitable(format!(
                "{} would need {steps:.3e} FPE steps per observation interval (more than {MAX_SUBSTEPS}): {why}",
                self.name,
            )));
        }
        Ok((steps as usize, notes))
    }

    /// The FDM positivity warning: a cell Péclet number `|f_l| Δx_l / a_ll` above 1 (with a
    /// state-dependent `a`, the smaller of its values at the cell's two neighbours along `l`,
    /// whose coefficients in the cell's row the advection must not turn positive).
    fn peclet_warning(&self) -> Option<String> {
        let mut worst = (0.0, 0, 0);
        for l in 0..self.grid.dim() {
            let (dx, a) = (self.grid.spacing()[l], &self.table.diffusion[l]);
            for (idx, f) in self.table.advection.velocity(l).iter().enumerate() {
                // a at the neighbours (the cell's own where its line ends).
                let [below, above] = self.grid.neighbours(idx, l).map(|n| a[n.unwrap_or(idx)]);
                let pe = libm::fabs(*f) * dx / below.min(above);
                if pe > worst.0 || pe.is_nan() {
                    worst = (pe, l, idx);
                }
            }
        }
        (worst.0 > 1.0 || worst.0.is_nan()).then(|| {
            let mut x = vec![0.0; self.grid.dim()];
            self.grid.node(worst.2, &mut x);
            format!(
                "M-matrix condition of the implicit FDM: the cell Péclet number |f_{0}|Δx_{0}/a_{0}{0} is {1:.3} > 1 at x = {2:?}; central differences may turn the density negative there",
                worst.1 + 1,
                worst.0,
                rounded(&x)
            )
        })
    }

    /// The plan of the implicit step for intervals of length `interval`.
    pub(super) fn plan_of(&self, interval: f64) -> Result<StepPlan, FilterError> {
        let (substeps, _) = self.step_count(interval)?;
        let dt = interval / substeps as f64;
        let part = match self.scheme {
            FpeScheme::Separation => ImplicitPart::Parabolic,
            FpeScheme::ImplicitFdm => ImplicitPart::Unsplit,
        };
        let implicit = ImplicitStep::new(
            &self.grid,
            &self.table.advection,
            &self.table.divergence,
            &self.table.diffusion,
            dt,
            part,
        )?;
        Ok(StepPlan {
            substeps,
            dt,
            implicit,
        })
    }

    /// Factorises the implicit step for Δτ (at construction).
    fn plan_for(&mut self, interval: f64) -> Result<(), FilterError> {
        self.plan = Some(self.plan_of(interval)?);
        Ok(())
    }

    /// FPE steps the filter takes per interval of the length it last predicted over.
    pub fn substeps(&self) -> Option<(usize, f64)> {
        self.plan.as_ref().map(|p| (p.substeps, p.dt))
    }

    /// Predicts the density over `interval` (001 Step 3): the FPE without a measurement, as
    /// whole intervals Δτ with the plan made for Δτ and the rest with a plan for its length
    /// (made the first time that length occurs and kept among the last [`REMAINDER_PLANS`]).
    /// The density is not renormalised (mass that leaves the grid is lost, as in the scheme).
    fn propagate(&mut self, interval: f64) -> Result<(), FilterError> {
        let (whole, rest) = crate::filters::whole_intervals(interval, self.dt_obs);
        for _ in 0..whole {
            let plan = self.plan.as_ref().expect("planned in new");
            self.run_plan(plan.substeps, plan.dt, false);
        }
        if rest > 0.0 {
            if !self.remainders.bring_to_front(rest) {
                let plan = self.plan_of(rest)?;
                self.remainders.insert(rest, plan);
            }
            let (substeps, dt) = (self.remainders.front().substeps, self.remainders.front().dt);
            self.run_plan(substeps, dt, true);
        }
        if self.u.iter().any(|v| !v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "predictive density",
            });
        }
        Ok(())
    }

    /// The transposed prediction over `interval` on `self.u` (the adjoint of
    /// [`ContinuousDiscreteGrid::propagate`]: the remainder's plan first, then the whole
    /// intervals, each FPE step as its implicit part transposed, then its upwind part).
    /// (A driven model has no smoother here, so the step's inputs are not read.)
    fn propagate_back(
        &mut self,
        interval: f64,
        _: Option<crate::model::Inputs<'_>>,
    ) -> Result<(), FilterError> {
        let (whole, rest) = crate::filters::whole_intervals(interval, self.dt_obs);
        if rest > 0.0 {
            if !self.remainders.bring_to_front(rest) {
                let plan = self.plan_of(rest)?;
                self.remainders.insert(rest, plan);
            }
            let (substeps, dt) = (self.remainders.front().substeps, self.remainders.front().dt);
            self.run_plan_back(substeps, dt, true);
        }
        for _ in 0..whole {
            let plan = self.plan.as_ref().expect("planned in new");
            self.run_plan_back(plan.substeps, plan.dt, false);
        }
        if self.u.iter().any(|v| !v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "backward function of the smoother",
            });
        }
        Ok(())
    }

    /// The transposed steps of [`ContinuousDiscreteGrid::run_plan`].
    fn run_plan_back(&mut self, substeps: usize, dt: f64, remainder: bool) {
        for _ in 0..substeps {
            let plan = match remainder {
                true => self.remainders.front(),
                false => self.plan.as_mut().expect("planned in new"),
            };
            plan.implicit.solve_transposed(&mut self.u, &mut self.tmp);
            if !self.table.cross.is_empty() {
                self.table
                    .cross
                    .step_transposed(&self.grid, dt, &self.u, &mut self.tmp);
                core::mem::swap(&mut self.u, &mut self.tmp);
            }
            if self.scheme == FpeScheme::Separation {
                self.table
                    .advection
                    .step_transposed(&self.grid, dt, &self.u, &mut self.tmp);
                core::mem::swap(&mut self.u, &mut self.tmp);
            }
        }
    }

    /// `substeps` FPE steps of `dt` with the Δτ plan, or the remainder plan at the front.
    fn run_plan(&mut self, substeps: usize, dt: f64, remainder: bool) {
        for _ in 0..substeps {
            if self.scheme == FpeScheme::Separation {
                self.table
                    .advection
                    .step(&self.grid, dt, &self.u, &mut self.tmp);
                core::mem::swap(&mut self.u, &mut self.tmp);
            }
            if !self.table.cross.is_empty() {
                self.table
                    .cross
                    .step(&self.grid, dt, &self.u, &mut self.tmp);
                core::mem::swap(&mut self.u, &mut self.tmp);
            }
            let plan = match remainder {
                true => self.remainders.front(),
                false => self.plan.as_mut().expect("planned in new"),
            };
            plan.implicit.solve(&mut self.u, &mut self.tmp);
        }
    }

    /// The Bayes update (6)–(7) with the observed components of `z` (NaN = missing: the
    /// noise density of the observed ones, its marginal), then the normalisation by `c'_k`;
    /// returns the log-likelihood `ln p(z | past) = ln(c'_k / ∫ p̂)`, the normaliser against
    /// the predicted density's mass.
    fn assimilate(&mut self, z: &[f64]) -> Result<f64, FilterError> {
        let shift = self.table.measurement.multiply(
            &self.grid,
            (&mut self.u, &mut self.tmp),
            &mut self.node,
            z,
        )?;
        self.normalise()?;
        Ok(libm::log(self.moments.mass) + shift)
    }

    /// Normalises the density and refreshes the estimate.
    fn normalise(&mut self) -> Result<(), FilterError> {
        normalise_on_grid(
            &self.grid,
            &mut self.u,
            &mut self.moments,
            &mut self.estimate,
        )
    }

    /// The step of [`Filter::step`] once `obs` is checked (it may fail half-way); returns its
    /// log-likelihood (0 without a measurement).
    fn advance(&mut self, obs: &Observation, observed: Observed) -> Result<f64, FilterError> {
        if obs.dt > 0.0 {
            self.propagate(obs.dt)?;
        }
        if let Some(kept) = &mut self.predicted {
            kept.copy_from_slice(&self.u);
        }
        match observed {
            Observed::Nothing => self.normalise().map(|_| 0.0),
            Observed::All | Observed::Some => self.assimilate(obs.value),
        }
    }
}

impl crate::filters::smoothing::GridTransition for ContinuousDiscreteGrid {
    fn grid_density(&self) -> (&TensorGrid, &[f64]) {
        (&self.grid, &self.u)
    }

    crate::filters::smoothing::density_storage!(carried by propagate, propagate_back);
}

/// Coordinates rounded to 4 significant decimals for messages.
fn rounded(x: &[f64]) -> Vec<f64> {
    x.iter().map(|v| libm::round(v * 1e4) / 1e4).collect()
}

impl Filter for ContinuousDiscreteGrid {
    crate::filters::kept_estimate_accessors!(density in u);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, ObservationKind::Measurement, self.m)?;
        if let Some(model) = &self.driven {
            let (dynamics, measurement) = obs.frozen(model)?.expect("a driven model");
            self.retabulate(Tabulated::of(
                &self.name,
                &self.grid,
                &dynamics,
                &measurement,
            )?)?;
        }
        self.table
            .measurement
            .likelihood
            .check(&self.name, obs.value)?;
        self.saved.save(&self.u, &self.estimate);
        let result = self.advance(obs, observed);
        let (u, estimate) = (&mut self.u, &mut self.estimate);
        self.saved
            .settle(result, u, estimate, &mut self.log_likelihood)
    }

    crate::filters::score::score_of_filter!();

    fn smoother(
        &self,
        plan: &crate::filters::smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn crate::filters::smoothing::Smoother>, FilterError> {
        if self.driven.is_some() {
            return Err(crate::filters::smoothing::no_smoother(
                &self.name,
                "its backward pass replays one operator for every interval, and a driven model's changes with the time and inputs (not implemented)",
            ));
        }
        crate::filters::smoothing::grid_smoother(self, plan)
    }

    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        crate::filters::grid_self_check(&self.grid, &self.u, &self.estimate, out);
        if let Some(plan) = &self.plan {
            let ratio = numerical_diffusion::numerical_diffusion_ratio(
                self.scheme,
                &self.grid,
                &self.table.advection,
                &self.table.diffusion,
                plan.dt,
                &self.u,
            );
            numerical_diffusion::check(self.scheme, ratio, out);
        }
        self.remainders.check(out);
    }
}
