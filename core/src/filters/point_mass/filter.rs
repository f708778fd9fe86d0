//! The point-mass filter itself: the transition kernel's prediction between measurements,
//! Bayes' rule at each one.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::kernel::Kernel;
use super::PointMassParams;
use crate::error::{FilterError, ZakaiError};
use crate::filters::grid_state::GridMeasurement;
use crate::filters::{normalise_on_grid, Estimate, Filter, Observation, ObservationKind, Observed};
use crate::grid::TensorGrid;
use crate::model::{MeasurementDensity, Model, ObservationModel};

/// The largest share of the mass a prediction may carry out of the box before the
/// self-check says so.
const LOST_MASS_THRESHOLD: f64 = 1e-4;

/// The model fits the filter: a discrete-time map with discrete measurements (their
/// density is returned).
pub(super) fn check_model(name: &str, model: &Model) -> Result<MeasurementDensity, FilterError> {
    if !model.is_discrete_time() {
        return Err(FilterError::Unsuitable(format!(
            "{name} predicts through a discrete-time map x_k = F(x_(k−1)) + w_k, and this model is an SDE dx = f dt + G dv (the separation filter solves its Fokker–Planck equation)"
        )));
    }
    match &model.observations {
        ObservationModel::Discrete { density } => Ok(density.clone()),
        ObservationModel::Continuous { .. } => Err(FilterError::Unsuitable(format!(
            "{name} needs discrete measurements z_k ~ p(z | x_k)"
        ))),
    }
}

/// The point-mass filter for discrete-time models.
///
/// The point-mass method (Šimandl, Královec & Söderström 2006, "Advanced point-mass method for
/// nonlinear state estimation", Automatica 42 — the discrete-time counterpart of 001's grid
/// filter, from the same group) for `x_k = F(x_(k−1), t_k, u_k) + w_k`,
/// `w_k ~ N(0, Q(x_(k−1)))`, `z_k ~ p(z | x_k)`. The density lives on `N_1 × ⋯ × N_n` cells
/// tiling the domain; `P[i]` is its value at cell i's centre.
///
/// * **Prediction**, per transition (the Chapman–Kolmogorov equation on the grid):
///   `P⁻[i] = Σ_j T[i, j] P[j]` with `T[i, j]` the mass of `N(F(ξ_j), Q(ξ_j))` in cell i — per
///   dimension the difference of two normal distribution functions for a diagonal Q, the
///   density at the cell centre for a correlated one —, the kernel cut at `radius` standard
///   deviations and renormalised there, so that the cost is cells × window and no mass is
///   made or lost inside the box; what lands beyond it is lost and reported by the
///   self-check. A step over k periods applies k transitions ([`Model::transitions`]).
/// * **Update** at each measurement (001 (6)–(7)): `P ← P · p(z_k | x[i]) / c_k`, in the log
///   domain; its normaliser is the step's likelihood.
///
/// ```
/// use zakai::{Filter, Model, Noise, PointMass};
///
/// // An AR(1) observed in noise, one transition per unit of time.
/// let model = Model::from_text(&["0.9*x"], &["x"], Noise::discrete(1.0))
///     .unwrap()
///     .discrete_time(1.0)
///     .unwrap()
///     .with_transition_noise(&[[0.5]])
///     .unwrap();
/// let mut filter = PointMass::builder(&model)
///     .prior_gaussian(&[0.0], &[[1.0]])
///     .domain(&[(-8.0, 8.0)])
///     .build()
///     .unwrap();
/// filter.step_measurement(1.0, &[0.7]).unwrap();
/// // The Kalman filter's answer: P⁻ = 0.81 + 0.5, mean 0.7 P⁻/(P⁻ + 1).
/// let p = 0.81 + 0.5;
/// assert!((filter.estimate().mean[0] - 0.7 * p / (p + 1.0)).abs() < 1e-3);
/// ```
///
/// # Cost
///
/// Per transition, for every cell the window of `Π_l (2·radius·σ_l/Δx_l + 1)` cells its kernel
/// reaches (σ_l the sd of w_k): linear in the cells for a fixed kernel; per measurement, one
/// likelihood per cell. A driven model's F is tabulated anew for every transition.
///
/// # When it fails
///
/// A box too small for the posterior or for where F carries the mass (the self-check reports
/// the mass lost at the edge and near it), cells too coarse for the posterior (the width
/// self-check) or for the kernel (a kernel narrower than a cell moves mass by whole cells:
/// its error is of the order of the cell). A continuous-time model is refused: its
/// prediction is the Fokker–Planck equation ([`crate::Separation`]).
#[derive(Clone, Debug)]
pub struct PointMass {
    pub(super) name: String,
    pub(super) grid: TensorGrid,
    /// The transition on the cells (an autonomous model's, made once; a driven model's, made
    /// for every transition: `None` until the first).
    pub(super) kernel: Option<Kernel>,
    /// p(z | x) and h on the cells (a driven model's frozen for each step).
    pub(super) measurement: GridMeasurement,
    pub(super) model: Model,
    pub(super) radius: f64,
    pub(super) u: Vec<f64>,
    tmp: Vec<f64>,
    node: Vec<f64>,
    saved: crate::filters::SavedDensity,
    log_likelihood: f64,
    estimate: Estimate,
    moments: crate::grid::Moments,
    /// The share of the mass the last prediction carried out of the box.
    lost: f64,
    predicted: Option<Vec<f64>>,
}

impl PointMass {
    /// Builds the filter on the context's box, with the prior tabulated on the cells.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &PointMassParams,
    ) -> Result<Self, ZakaiError> {
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        let n = model.n;
        crate::filters::method::refuse_problems(&name, params.problems(n))?;
        check_model(&name, model)?;
        let grid = crate::filters::fpe_split::cells_over(bounds, &params.shape(n))?;
        // A driven model's kernel and measurement are made for each step, from the model at
        // the step's time and inputs; here, at its start (t = 0, inputs 0), only the
        // measurement's tabulation is set up.
        let start = model.at(0.0, &vec![0.0; model.inputs.unwrap_or(0)])?;
        let kernel = match model.is_driven() {
            false => Some(Kernel::new(&name, model, &grid, params.radius, true)?),
            true => None,
        };
        let measurement = GridMeasurement::new(&grid, &start, &check_model(&name, &start)?);
        let (u, moments, estimate) = crate::filters::grid_state::prior_on_grid(&grid, prior)?;
        let len = grid.len();
        Ok(PointMass {
            name,
            kernel,
            measurement,
            model: model.clone(),
            radius: params.radius,
            saved: crate::filters::SavedDensity::new(len, &estimate),
            log_likelihood: 0.0,
            u,
            tmp: vec![0.0; len],
            node: vec![0.0; n],
            estimate,
            moments,
            lost: 0.0,
            predicted: None,
            grid,
        })
    }

    /// The grid of cell centres.
    pub fn grid(&self) -> &TensorGrid {
        &self.grid
    }

    /// Cells in the window of the widest kernel (summed over a mixture noise's components): the
    /// prediction's cost per cell.
    pub fn kernel_window(&self) -> f64 {
        self.kernel
            .as_ref()
            .map_or(0.0, |k| k.widest_window(&self.grid))
    }

    /// The transitions over `dt` (each of a driven model at the time it reaches), on
    /// `self.u` (forward) or transposed; returns the share of the mass carried out of the box
    /// (forward).
    fn transitions(
        &mut self,
        dt: f64,
        inputs: Option<crate::model::Inputs<'_>>,
        transposed: bool,
    ) -> Result<f64, FilterError> {
        let k = self.model.transitions(dt)?;
        let mut lost = 0.0;
        for j in 0..k {
            let j = if transposed { k - 1 - j } else { j };
            if self.model.is_driven() {
                let model = self.model.transition_at(inputs, j, k)?;
                self.kernel = Some(Kernel::new(
                    &self.name,
                    &model,
                    &self.grid,
                    self.radius,
                    false,
                )?);
            }
            let kernel = self.kernel.as_mut().expect("made in new, or just above");
            if transposed {
                kernel.predict_transposed(&self.grid, &self.u, &mut self.tmp);
            } else {
                let mass = self.grid.mass(&self.u) / self.grid.cell_volume();
                let out = kernel.predict(&self.grid, &self.u, &mut self.tmp);
                if mass > 0.0 {
                    lost = 1.0 - (1.0 - lost) * (1.0 - out / mass);
                }
            }
            core::mem::swap(&mut self.u, &mut self.tmp);
        }
        if self.u.iter().any(|v| !v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "predictive density",
            });
        }
        Ok(lost)
    }

    /// The transitions over `dt` on `u` (an autonomous model's: the smoother's forward pass).
    #[cfg(test)]
    fn propagate(&mut self, dt: f64) -> Result<f64, FilterError> {
        self.transitions(dt, None, false)
    }

    /// Their transpose over `dt` on `u` (the smoother's backward pass), each of a driven
    /// model at the time it reaches with the step's `inputs`.
    fn propagate_back(
        &mut self,
        dt: f64,
        inputs: Option<crate::model::Inputs<'_>>,
    ) -> Result<f64, FilterError> {
        self.transitions(dt, inputs, true)
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

    /// The step once `obs` is checked (it may fail half-way); returns its log-likelihood and
    /// the share of the mass its prediction lost.
    fn advance(
        &mut self,
        obs: &Observation,
        observed: Observed,
    ) -> Result<(f64, f64), FilterError> {
        let lost = if obs.dt > 0.0 {
            self.transitions(obs.dt, obs.inputs, false)?
        } else {
            0.0
        };
        if let Some(kept) = &mut self.predicted {
            kept.copy_from_slice(&self.u);
        }
        let log_likelihood = match observed {
            Observed::Nothing => self.normalise().map(|_| 0.0)?,
            Observed::All | Observed::Some => {
                let shift = self.measurement.multiply(
                    &self.grid,
                    (&mut self.u, &mut self.tmp),
                    &mut self.node,
                    obs.value,
                )?;
                self.normalise()?;
                libm::log(self.moments.mass) + shift
            }
        };
        Ok((log_likelihood, lost))
    }
}

impl crate::filters::smoothing::GridTransition for PointMass {
    fn grid_density(&self) -> (&TensorGrid, &[f64]) {
        (&self.grid, &self.u)
    }

    crate::filters::smoothing::density_storage!(carried by propagate, propagate_back);
}

impl Filter for PointMass {
    crate::filters::kept_estimate_accessors!(density in u);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, ObservationKind::Measurement, self.model.m)?;
        if self.model.is_driven() {
            let Some(crate::model::Inputs { t, u }) = obs.inputs else {
                return Err(FilterError::BadObservation(
                    "the model reads the time t and known inputs: give each step the observation's time and inputs (Observation::with_inputs)".into(),
                ));
            };
            let measurement = self.model.at(t, u)?;
            let noise = check_model(&self.name, &measurement)?;
            self.measurement.refresh(&self.grid, &measurement, &noise);
        }
        self.measurement.likelihood.check(&self.name, obs.value)?;
        self.saved.save(&self.u, &self.estimate);
        let mut lost = 0.0;
        let result = self.advance(obs, observed).map(|(ll, l)| {
            lost = l;
            ll
        });
        let (u, estimate) = (&mut self.u, &mut self.estimate);
        self.saved
            .settle(result, u, estimate, &mut self.log_likelihood)?;
        self.lost = lost;
        Ok(())
    }

    crate::filters::score::score_of_filter!();

    fn smoother(
        &self,
        plan: &crate::filters::smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn crate::filters::smoothing::Smoother>, FilterError> {
        crate::filters::smoothing::grid_smoother(self, plan)
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        crate::filters::grid_self_check(&self.grid, &self.u, &self.estimate, out);
        if self.lost > LOST_MASS_THRESHOLD {
            out.push(crate::filters::Concern::above(
                "mass carried out of the box by the last prediction",
                self.lost,
                LOST_MASS_THRESHOLD,
                "the transition F(x) + w moves mass beyond the domain, where it is lost: widen the domain",
            ));
        }
    }
}
