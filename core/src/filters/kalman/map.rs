//! The MAP-update filters (IEKF, IOKF) ([`MapKalman`] documents it).

use alloc::string::String;
use alloc::vec::Vec;

use super::map_point::{map_update, MapSolver, MapWork, UpdateReport};
use super::measurement::MeasurementForm;
use super::second_mode::{Interval, ModeWatch};
use super::{GaussianInit, GaussianState};
use crate::error::FilterError;
use crate::filters::{Estimate, Filter, Observation};
use crate::model::Model;

/// The MAP filters' convergence self-check threshold: the Gauss–Newton step still left at the
/// point an update returns, in standard deviations of the Laplace covariance there. At a MAP
/// point the step is zero; the IEKF stops when its step falls below its tolerance, the IOKF
/// after l × m Newton steps whether or not it got there (003 Algorithm 4.1). Above the
/// threshold the reported mean and covariance are those of a point the iteration had not yet
/// left: e.g. a sharp measurement z = 1.44 of h = x² (R = 0.01) against a prior N(0.3, 1)
/// stops the IOKF with l = 3, m = 2 at 0.51, a step of 12 posterior standard deviations short
/// of the mode at 1.2. Largest per run, seeds 1–5, IEKF / IOKF: `bearings-only` 5e-11 / 2e-8,
/// `cubic-sensor-1d` 0.025 / 0.007, `cubic-sensor-2d` 0.028 / 9e-4, `cos-x2` 3e-5 / 1e-8,
/// `cos-x4` 0.056 / 0.12, `yau-2d` and `sa-example-2` at rounding; `direct-4.3` (Δτ = 0.1)
/// IOKF 0.006, IEKF 0.05–0.09 in three runs, 0.89 in one and 3.19 in the run where it loses
/// the state (MSE 38 against 0.13–0.22).
pub(crate) const MAP_UNCONVERGED_THRESHOLD: f64 = 1.0;

/// The MAP filters' self-check threshold on `√((x_MAP − m)ᵀ P⁻¹ (x_MAP − m))`, the distance
/// of one update's MAP point from the predicted mean in predicted standard deviations: an
/// update that lands far outside the predicted Gaussian means that Gaussian did not describe
/// the posterior. Largest per run, seeds 1–5, IEKF and IOKF alike: `yau-2d` 0.35–0.53,
/// `cos-x2` 0.44–0.71, `bearings-only` 1.09–1.39, `sa-example-1` 1.37–1.80, `cubic-sensor-1d`
/// 0.65–2.06, `direct-4.3` (Δτ = 0.1, where the EKF family loses the state) 2.54–3.26.
pub(crate) const MAP_JUMP_THRESHOLD: f64 = 3.0;

/// A Gaussian filter whose update is the MAP point of 003 §4 (IEKF or IOKF).
///
/// The MAP framework of 003 §4: between observations the Gaussian approximation (4.2) is
/// carried exactly as in the EKF (mean by (4.3), covariance by the linearised moment
/// equations); at an observation the update is the maximiser of the approximate posterior,
/// i.e. the minimiser of
///
/// `L_λ(x) = (x − m)ᵀ P⁻¹ (x − m) + λ (z − h(x))ᵀ R⁻¹ (z − h(x))`  (4.5), (4.8)
///
/// with λ = 1, computed by
///
/// * **IEKF** — Gauss–Newton on (4.5): `x ← m + K(x)(z − h(x) − H(x)(m − x))`,
///   `K = P Hᵀ(H P Hᵀ + R)⁻¹`, until the step is below the tolerance or the iteration count
///   is reached;
/// * **IOKF** (Algorithm 4.1) — the λ-homotopy (4.6)–(4.8): `λ_j = j/l`, j = 1..l, and m
///   Newton steps on `L_{λ_j}` from the previous minimiser, with the exact Hessian
///   `2P⁻¹ + 2λ HᵀR⁻¹H − 2λ Σ_i (R⁻¹ r)_i ∇²h_i`. A Hessian that is not positive definite is
///   damped (Levenberg: `+ μ I`, μ growing tenfold), and every step is cut back (Armijo) until
///   L decreases; a step that finds neither is a reported failure, never NaN.
///
/// Both leave the covariance of the Laplace approximation at the final point,
/// `P ← P − K H P` with H at that point. For continuous observations h and R are those of the
/// increment (`h Δτ`, `S Δτ`), as for the EKF.
///
/// # Example
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::{Filter, Iekf, Iokf, Model, Noise};
///
/// // dx = −x dt + dv, z = x² + v (Var v = 0.1): the MAP point moves with the measurement.
/// let model = Model::from_text(&["-x"], &["x^2"], Noise::discrete(0.1)).unwrap();
/// let mut iekf = Iekf::builder(&model).prior_gaussian(&[1.0], &[[0.5]]).build().unwrap();
/// let mut iokf = Iokf::builder(&model).prior_gaussian(&[1.0], &[[0.5]]).build().unwrap();
/// for filter in [&mut iekf, &mut iokf] {
///     filter.step_measurement(0.1, &[1.2]).unwrap();
///     assert!(filter.estimate().mean[0] > 0.5);
/// }
/// # }
/// ```
///
/// # Cost
///
/// The EKF's prediction, then per update up to the iteration count of Gauss–Newton (IEKF) or
/// l × m Newton steps (IOKF), each with h, its Jacobian (and for the IOKF its Hessians) and an
/// n × n or m × m solve: O(iterations · (n³ + m³)).
///
/// # When it fails
///
/// The MAP point of a posterior with two modes is one of them, and the Laplace covariance there
/// says nothing of the other; the filter watches for a second mode and reports it (its
/// self-check), as it reports an update that stopped before reaching the MAP point (the step
/// still left, in standard deviations) — [`crate::Filter::self_check`].
#[derive(Clone, Debug)]
pub struct MapKalman {
    name: String,
    model: Model,
    q: crate::model::ProcessNoise,
    form: MeasurementForm,
    substeps: crate::filters::Substeps,
    solver: MapSolver,
    state: GaussianState,
    work: MapWork,
    /// What the last update reported.
    last: UpdateReport,
    /// The watch for a second posterior mode.
    watch: ModeWatch,
}

impl MapKalman {
    /// Builds the filter from the model and the prior's moments; fails for measurements
    /// without the two moments its update needs (`MeasurementForm::new`).
    pub(crate) fn new(
        name: String,
        solver: MapSolver,
        ctx: &crate::filters::method::BuildContext,
        init: &GaussianInit,
        substeps: usize,
    ) -> Result<Self, crate::error::FilterError> {
        let (model, prior) = (ctx.model, ctx.prior);
        let state = GaussianState::initial(prior.mean(), prior.covariance(), init, model.m)
            .with_affine_map(model, ctx.probes);
        Ok(MapKalman {
            form: MeasurementForm::new(&name, model)?,
            name,
            model: model.clone(),
            q: model.process_noise(),
            substeps: crate::filters::Substeps::new(substeps, ctx.dt_obs),
            solver,
            watch: ModeWatch::new(&state, model.m),
            state,
            work: MapWork::new(model.n, model.m),
            last: UpdateReport {
                iterations: 0,
                jump: 0.0,
                unconverged: 0.0,
                log_density: 0.0,
            },
        })
    }

    /// Iterations or Newton steps of the last update.
    pub fn last_iterations(&self) -> usize {
        self.last.iterations
    }
}

super::smoother::gaussian_filter!(MapKalman);

impl Filter for MapKalman {
    super::smoother::gaussian_filter_opening!();

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let MapKalman {
            name,
            model,
            q,
            form,
            substeps,
            solver,
            state,
            work,
            watch,
            last,
        } = self;
        let steps = substeps.over(obs.dt);
        let stepped = state.transaction(|state| {
            // An autonomous model (the MAP filters refuse a driven one: `Method::INPUTS`).
            let own = super::StepModels {
                dynamics: model,
                q,
                measurement: model,
                unfrozen: None,
            };
            let Some(meas) = state.predict_then_measure(name, &own, steps, form, obs)? else {
                return Ok(None);
            };
            let report = map_update(*solver, model, meas, state, work)?;
            // The Gaussian predictive density at the predicted mean, as the EKF's.
            state.record_log_likelihood(report.log_density, meas)?;
            Ok(Some((report, meas)))
        })?;
        let Some((report, meas)) = stepped else {
            watch.elapse(model, q, steps, obs.dt);
            return Ok(());
        };
        *last = report;
        let interval = Interval {
            solver: *solver,
            model,
            q,
            substeps: steps,
            dt: obs.dt,
            meas,
        };
        watch.after_update(&interval, state, last.log_density);
        Ok(())
    }

    fn estimate(&self) -> Estimate {
        let mut e = self.state.estimate();
        e.map = Some(self.state.mean.clone());
        e
    }

    fn estimate_into(&self, out: &mut Estimate) {
        self.state.estimate_into(out, Some(&self.state.mean));
    }

    fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
        super::approximations(&self.form, &self.q, &self.model, &self.name)
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        self.state.innovations.check(out);
        self.watch.check(out);
        if self.last.jump > MAP_JUMP_THRESHOLD {
            out.push(crate::filters::Concern::above(
                "MAP point from the predicted mean, in predicted standard deviations",
                self.last.jump,
                MAP_JUMP_THRESHOLD,
                "one update moved the estimate far outside the predicted Gaussian: the posterior is far from Gaussian (possibly two modes) and the Laplace approximation cannot describe it",
            ));
        }
        if self.last.unconverged > MAP_UNCONVERGED_THRESHOLD {
            out.push(crate::filters::Concern::above(
                "Gauss–Newton step left at the update's point, in posterior standard deviations",
                self.last.unconverged,
                MAP_UNCONVERGED_THRESHOLD,
                "the update's iterations ended before the MAP point: the estimate and covariance are not the MAP filter's; raise iterations (IEKF) or newton_steps and splits (IOKF)",
            ));
        }
    }
}
