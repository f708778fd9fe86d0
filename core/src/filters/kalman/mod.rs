//! Gaussian filters on nalgebra, n-dimensional: [`Kalman`] (exact for linear Gaussian
//! models), [`Ekf`], [`Ukf`] and the MAP-update filters of 003
//! ([`MapKalman`]: IEKF and IOKF). They share the Gaussian state
//! `N(m, P)`, the observation-as-measurement form of [`measurement`], and the
//! continuous-time propagation of [`propagate`].

pub(crate) mod ekf;
pub(crate) mod linear;
pub(crate) mod map;
pub(crate) mod map_point;
pub(crate) mod measurement;
mod method;
mod params;
pub(crate) mod propagate;
mod score;
pub(crate) mod second_mode;
pub(crate) mod smoother;
pub(crate) mod ukf;

pub use ekf::Ekf;
pub use linear::Kalman;
pub use map::MapKalman;
pub use map_point::MapSolver;
pub use method::{Iekf, Iokf};
pub use params::EkfParams;
pub use params::IekfParams;
pub use params::IokfParams;
pub use params::KalmanParams;
pub use params::UkfParams;
pub(crate) use params::MAX_SUBSTEPS;
pub use ukf::Ukf;

use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::FilterError;
use crate::linalg::{check_finite_matrix, check_finite_vector, lower_cholesky_solve, symmetrize};

/// An optional initial Gaussian that overrides the prior's moments (002 starts its EKF at
/// x̂₀ = 1 with P₀ ∈ {1, 5, 10} whatever σ₀ is).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianInit {
    /// x̂₀ (length n).
    pub mean: Option<Vec<f64>>,
    /// P₀ as a full n × n matrix (rows), or
    pub cov: Option<Vec<Vec<f64>>>,
    /// P₀ = variance · I.
    pub variance: Option<f64>,
}

/// The approximations a Gaussian filter makes of this model, for its warnings: the
/// measurements' moment match ([`measurement::MeasurementForm::warnings`]) and, when G depends
/// on the state, the process noise taken at the mean; a mixture transition noise taken by its
/// moments ([`crate::TransitionMixture`]).
pub(crate) fn approximations(
    form: &measurement::MeasurementForm,
    q: &crate::model::ProcessNoise,
    model: &crate::model::Model,
    name: &str,
) -> Vec<alloc::string::String> {
    let mut out = form.warnings();
    out.extend(model.moments_only(name));
    if q.constant().is_none() {
        out.push(
            "replaces the state-dependent process noise Q(x) = G(x)G(x)ᵀ by Q at the current mean in dP/dt = FP + PFᵀ + Q (E[Q(x)] ≠ Q(E[x]) where Q is not affine): an approximation that grows with the spread of the posterior"
                .into(),
        );
    }
    out
}

/// Updates over which the innovation self-check averages the normalised innovation squared.
pub(crate) const NIS_WINDOW: usize = 50;

/// The innovation self-check's band: the mean per observed component of the last
/// [`NIS_WINDOW`] NIS values `νᵀ P_zz⁻¹ ν` of a consistent filter is χ²(k)/k-distributed, with
/// k the components observed over the window (W·m when none is missing); the band is its
/// two-sided 1 − 10⁻⁵ interval (Wilson–Hilferty, z = 4.4), so a well-specified Kalman filter
/// warns on a window about once in 10⁵. Outside it, the filter's covariance does not describe
/// its errors (too small above the band — the usual way an EKF loses track —, too large below).
pub(crate) fn nis_band(k: usize) -> (f64, f64) {
    let k = k as f64;
    let (a, b) = (1.0 - 2.0 / (9.0 * k), 4.4 * libm::sqrt(2.0 / (9.0 * k)));
    let cube = |x: f64| x * x * x;
    (cube(a - b), cube(a + b))
}

/// The last [`NIS_WINDOW`] normalised innovations squared with the number of components
/// each had observed, in a ring (no allocation).
#[derive(Clone, Debug)]
pub(crate) struct InnovationWindow {
    values: [f64; NIS_WINDOW],
    components: [usize; NIS_WINDOW],
    count: usize,
    /// Σ values, kept as each value enters and leaves (the check runs every step) and summed
    /// afresh each time the ring wraps, so rounding cannot build up.
    sum: f64,
    /// Σ components.
    observed: usize,
}

impl Default for InnovationWindow {
    fn default() -> Self {
        Self::new()
    }
}

impl InnovationWindow {
    /// An empty window.
    pub(crate) fn new() -> Self {
        InnovationWindow {
            values: [0.0; NIS_WINDOW],
            components: [0; NIS_WINDOW],
            count: 0,
            sum: 0.0,
            observed: 0,
        }
    }

    /// Records one normalised innovation squared of an update that observed `components`.
    pub(crate) fn push(&mut self, nis: f64, components: usize) {
        let slot = self.count % NIS_WINDOW;
        let old = core::mem::replace(&mut self.values[slot], nis);
        let old_components = core::mem::replace(&mut self.components[slot], components);
        self.observed = self.observed + components - old_components;
        self.count += 1;
        self.sum = if slot + 1 == NIS_WINDOW || !(old.is_finite() && self.sum.is_finite()) {
            self.values.iter().sum()
        } else {
            self.sum - old + nis
        };
    }

    /// What [`InnovationWindow::rollback`] needs to undo the next push (a step pushes at
    /// most once): the running totals and the slot it will overwrite — a few numbers, not
    /// the window.
    pub(crate) fn mark(&self) -> WindowMark {
        let slot = self.count % NIS_WINDOW;
        WindowMark {
            count: self.count,
            sum: self.sum,
            observed: self.observed,
            slot: (self.values[slot], self.components[slot]),
        }
    }

    /// Back to the window of `mark`, undoing the push made since, if any.
    pub(crate) fn rollback(&mut self, mark: &WindowMark) {
        debug_assert!(self.count <= mark.count + 1, "one push per step");
        let slot = mark.count % NIS_WINDOW;
        (self.values[slot], self.components[slot]) = mark.slot;
        self.count = mark.count;
        self.sum = mark.sum;
        self.observed = mark.observed;
    }

    /// The mean NIS per observed component over the last window, once it is full, with the
    /// number of components observed over it.
    pub(crate) fn mean(&self) -> Option<(f64, usize)> {
        (self.count >= NIS_WINDOW && self.observed > 0)
            .then(|| (self.sum / self.observed as f64, self.observed))
    }

    /// The innovation self-check: a [`crate::filters::Concern`] when the window's mean is
    /// outside [`nis_band`].
    pub(crate) fn check(&self, out: &mut alloc::vec::Vec<crate::filters::Concern>) {
        let Some((mean, observed)) = self.mean() else {
            return;
        };
        let (lo, hi) = nis_band(observed);
        const CHECK: &str = "normalised innovation squared (mean over 50 updates, per component)";
        if mean > hi {
            out.push(crate::filters::Concern::above(
                CHECK,
                mean,
                hi,
                "the innovations are larger than the filter's covariance says: its estimate is overconfident and may have lost track",
            ));
        } else if mean < lo {
            out.push(crate::filters::Concern::below(
                CHECK,
                mean,
                lo,
                "the innovations are smaller than the filter's covariance says: its covariance is too large",
            ));
        }
    }
}

/// An [`InnovationWindow`] before a push ([`InnovationWindow::mark`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct WindowMark {
    count: usize,
    sum: f64,
    observed: usize,
    slot: (f64, usize),
}

/// The Gaussian state `N(m, P)` of the Kalman family, with the storage its steps work in
/// (made once: a step allocates nothing).
#[derive(Clone, Debug)]
pub(crate) struct GaussianState {
    /// Mean m.
    pub mean: DVector<f64>,
    /// Covariance P.
    pub cov: DMatrix<f64>,
    /// The last normalised innovations squared (the innovation self-check).
    pub innovations: InnovationWindow,
    /// What an update is made of: a filter writes the residual `z − ẑ`, `P_xz` and `P_zz`
    /// here before [`GaussianState::update`].
    pub parts: UpdateParts,
    work: UpdateWork,
    moments: propagate::MomentWork,
    /// The log-likelihood of the last step's observation ([`crate::Filter::log_likelihood`]):
    /// from the Gaussian predictive density of the update, 0 after a step without one.
    pub log_likelihood: f64,
    /// The state a step started from ([`GaussianState::save`]).
    saved: (DVector<f64>, DMatrix<f64>, WindowMark, f64),
    /// The model's map when it is affine ([`GaussianState::with_affine_map`]): its transitions'
    /// moments taken exactly instead of by the filter's own approximation.
    affine: Option<propagate::AffineMap>,
}

/// The residual `r = z − ẑ` (m), the cross covariance `P_xz` (n × m) and the innovation
/// covariance `P_zz` (m × m) of one update.
#[derive(Clone, Debug)]
pub(crate) struct UpdateParts {
    /// r.
    pub residual: DVector<f64>,
    /// P_xz.
    pub pxz: DMatrix<f64>,
    /// P_zz.
    pub pzz: DMatrix<f64>,
    /// The components observed (the others' rows are neutral: see [`measurement`]).
    pub observed: usize,
}

/// Storage of the update: the Cholesky factor of P_zz, Kᵀ, P_zz⁻¹ r, and the linearised
/// observation `H` (with its row-major evaluation) at the mean; the factor of R and R⁻¹z of
/// the likelihood's reference density.
#[derive(Clone, Debug)]
struct UpdateWork {
    factor: DMatrix<f64>,
    noise_factor: DMatrix<f64>,
    noise_whitened: DVector<f64>,
    gain_t: DMatrix<f64>,
    whitened: DVector<f64>,
    h: DMatrix<f64>,
    rows: Vec<f64>,
}

impl GaussianState {
    /// From the prior moments, overridden by `init` where it says so, for `m` observation
    /// components.
    pub(crate) fn initial(
        prior_mean: DVector<f64>,
        prior_cov: DMatrix<f64>,
        init: &GaussianInit,
        m: usize,
    ) -> Self {
        let n = prior_mean.len();
        let mean = init
            .mean
            .as_ref()
            .map(|m| DVector::from_column_slice(m))
            .unwrap_or(prior_mean);
        let cov = if let Some(rows) = &init.cov {
            DMatrix::from_fn(n, n, |i, j| rows[i][j])
        } else if let Some(v) = init.variance {
            DMatrix::identity(n, n) * v
        } else {
            prior_cov
        };
        GaussianState {
            mean,
            cov,
            innovations: InnovationWindow::new(),
            parts: UpdateParts {
                residual: DVector::zeros(m),
                pxz: DMatrix::zeros(n, m),
                pzz: DMatrix::zeros(m, m),
                observed: m,
            },
            log_likelihood: 0.0,
            work: UpdateWork {
                factor: DMatrix::zeros(m, m),
                noise_factor: DMatrix::zeros(m, m),
                noise_whitened: DVector::zeros(m),
                gain_t: DMatrix::zeros(m, n),
                whitened: DVector::zeros(m),
                h: DMatrix::zeros(m, n),
                rows: alloc::vec![0.0; m * n],
            },
            moments: propagate::MomentWork::new(n),
            saved: (
                DVector::zeros(n),
                DMatrix::zeros(n, n),
                WindowMark::default(),
                0.0,
            ),
            affine: None,
        }
    }

    /// Predicts the transitions of `model`'s map by their exact moments when it is affine over
    /// `probes` ([`propagate::AffineMap`]), whatever the filter's own moments of a map: the
    /// same moments (the EKF's linearisation and the UKF's unscented transform are exact for
    /// an affine map) without evaluating the map.
    pub(crate) fn with_affine_map(
        mut self,
        model: &crate::model::Model,
        probes: &[Vec<f64>],
    ) -> Self {
        self.affine = propagate::AffineMap::of(model, probes);
        self
    }

    /// Keeps the mean, covariance, innovation window and log-likelihood (no allocation), so
    /// that [`GaussianState::restore`] can undo a step that fails; the step to come starts
    /// with a log-likelihood of 0 (nothing observed yet).
    pub(crate) fn save(&mut self) {
        let copy = crate::linalg::small::copy;
        copy(self.saved.0.as_mut_slice(), self.mean.as_slice());
        copy(self.saved.1.as_mut_slice(), self.cov.as_slice());
        self.saved.2 = self.innovations.mark();
        self.saved.3 = self.log_likelihood;
        self.log_likelihood = 0.0;
    }

    /// Back to the state of the last [`GaussianState::save`].
    pub(crate) fn restore(&mut self) {
        self.mean.copy_from(&self.saved.0);
        self.cov.copy_from(&self.saved.1);
        self.innovations.rollback(&self.saved.2);
        self.log_likelihood = self.saved.3;
    }

    /// Runs `step` on the state; when it fails, the state is restored to what it was before
    /// (the [`crate::filters::Filter`] contract).
    pub(crate) fn transaction<T>(
        &mut self,
        step: impl FnOnce(&mut Self) -> Result<T, FilterError>,
    ) -> Result<T, FilterError> {
        self.save();
        let result = step(self);
        if result.is_err() {
            self.restore();
        }
        result
    }

    /// The linear(ised) update from [`GaussianState::parts`] (residual `r = z − ẑ`, `P_xz`,
    /// `P_zz`) of the measurement `meas`: gain `K = P_xz P_zz⁻¹`, `m += K r`,
    /// `P −= K P_zz Kᵀ = P_xz Kᵀ`; the log-likelihood from the innovation's density.
    pub(crate) fn update(&mut self, meas: &measurement::Measurement) -> Result<(), FilterError> {
        let nis = self.gain()?;
        self.innovations.push(nis, self.parts.observed);
        let log_density = self.innovation_log_density(nis);
        self.record_log_likelihood(log_density, meas)?;
        // m += K r: Kᵀ's column i (contiguous) against r.
        let (gain_t, r) = (&self.work.gain_t, self.parts.residual.as_slice());
        for (m, column) in self
            .mean
            .iter_mut()
            .zip(gain_t.as_slice().chunks_exact(r.len()))
        {
            *m += column.iter().zip(r).map(|(k, r)| k * r).sum::<f64>();
        }
        self.downdate_covariance()
    }

    /// After [`GaussianState::gain`] returned `nis`: the log-density of the innovation
    /// `r ~ N(0, P_zz)`, `−½ rᵀP_zz⁻¹r − ½ ln det P_zz` (without the constant `−(m/2) ln 2π`),
    /// from the Cholesky factor of `P_zz` that the gain left — the weight of one observation in
    /// a comparison of Gaussian hypotheses, as in the Gaussian-sum filter.
    pub(crate) fn innovation_log_density(&self, nis: f64) -> f64 {
        let factor = &self.work.factor;
        -0.5 * nis
            - (0..factor.nrows())
                .map(|i| crate::linalg::elementary::ln(factor[(i, i)]))
                .sum::<f64>()
    }

    /// Records the step's log-likelihood from the innovation's log-density `log_density`
    /// ([`GaussianState::innovation_log_density`], at the predicted mean): for a measurement
    /// `log N(z; ẑ, P_zz)`, the Gaussian predictive density of z; for an increment
    /// `log N(Δy; ĥΔτ, P_zz) − log N(Δy; 0, SΔτ)`, the same against the Wiener reference, so
    /// that it estimates the Kallianpur–Striebel normaliser of the interval
    /// `E[exp(ΔyᵀS⁻¹h − ½hᵀS⁻¹h Δτ)]`. Missing components add nothing (their rows of P_zz and
    /// R are identity rows, their values 0).
    pub(crate) fn record_log_likelihood(
        &mut self,
        log_density: f64,
        meas: &measurement::Measurement,
    ) -> Result<(), FilterError> {
        let observed = meas.count as f64;
        let mut ll = log_density - 0.5 * observed * crate::model::measurement::LN_TAU;
        if meas.continuous {
            let work = &mut self.work;
            let chol = crate::linalg::cholesky_in(
                &mut work.noise_factor,
                &meas.noise_cov,
                "observation noise covariance",
            )?;
            work.noise_whitened.copy_from(&meas.value);
            chol.solve_mut(&mut work.noise_whitened);
            let quadratic = meas.value.dot(&work.noise_whitened);
            work.noise_factor = chol.unpack_dirty();
            let half_log_det: f64 = (0..work.noise_factor.nrows())
                .map(|i| crate::linalg::elementary::ln(work.noise_factor[(i, i)]))
                .sum();
            ll -= -0.5 * quadratic
                - half_log_det
                - 0.5 * observed * crate::model::measurement::LN_TAU;
        }
        self.log_likelihood = ll;
        Ok(())
    }

    /// The gain of the update in [`GaussianState::parts`]: `Kᵀ = P_zz⁻¹ P_xzᵀ` into the
    /// state's storage; returns the normalised
    /// innovation squared `rᵀ P_zz⁻¹ r`.
    pub(crate) fn gain(&mut self) -> Result<f64, FilterError> {
        let UpdateParts {
            residual, pxz, pzz, ..
        } = &self.parts;
        let work = &mut self.work;
        crate::linalg::lower_cholesky_checked(pzz, &mut work.factor, "innovation covariance")?;
        crate::linalg::small::copy(work.whitened.as_mut_slice(), residual.as_slice());
        lower_cholesky_solve(&work.factor, &mut work.whitened);
        // K = P_xz P_zz⁻¹  ⇔  P_zz Kᵀ = P_xzᵀ, column by column.
        work.gain_t.tr_copy_from(pxz);
        crate::linalg::lower_cholesky_solve_columns(&work.factor, work.gain_t.as_mut_slice());
        Ok(residual.dot(&work.whitened))
    }

    /// `P −= P_xz Kᵀ` with the gain of the last [`GaussianState::gain`], kept symmetric.
    pub(crate) fn downdate_covariance(&mut self) -> Result<(), FilterError> {
        crate::linalg::small::subtract_product(
            self.cov.nrows(),
            self.cov.as_mut_slice(),
            self.parts.pxz.as_slice(),
            self.work.gain_t.as_slice(),
        );
        symmetrize(&mut self.cov);
        self.check()
    }

    /// Writes into [`GaussianState::parts`] the update with h linearised at `at` (the mean
    /// when `None`): `H = scale · ∂h/∂x`, `r = z − scale · h`, `P_xz = P Hᵀ`,
    /// `P_zz = H P Hᵀ + R`.
    pub(crate) fn linearize(
        &mut self,
        model: &crate::model::Model,
        meas: &measurement::Measurement,
        at: Option<&DVector<f64>>,
    ) {
        let (work, parts) = (&mut self.work, &mut self.parts);
        let x = at.unwrap_or(&self.mean).as_slice();
        meas.linearize_into(
            model,
            x,
            parts.residual.as_mut_slice(),
            &mut work.rows,
            &mut work.h,
        );
        parts.observed = meas.count;
        parts.residual.zip_apply(&meas.value, |r, z| *r = z - *r);
        // P_xz = P Hᵀ, P_zz = R + H P_xz.
        let n = work.h.ncols();
        let (h, pxz) = (work.h.as_slice(), parts.pxz.as_mut_slice());
        crate::linalg::small::times_transpose(n, self.cov.as_slice(), h, pxz);
        crate::linalg::small::copy(parts.pzz.as_mut_slice(), meas.noise_cov.as_slice());
        crate::linalg::small::add_product(n, parts.pzz.as_mut_slice(), h, pxz);
    }

    /// The Kalman update with h linearised at the current mean (KF, EKF):
    /// [`GaussianState::linearize`] then [`GaussianState::update`].
    pub(crate) fn linearized_update(
        &mut self,
        model: &crate::model::Model,
        meas: &measurement::Measurement,
    ) -> Result<(), FilterError> {
        self.linearize(model, meas, None);
        self.update(meas)
    }

    /// The EKF prediction over `dt`: the linearised moment equations (Jazwinski) in
    /// `substeps` RK4 steps.
    /// A discrete-time map is predicted by its transitions instead, each through its
    /// Jacobian ([`GaussianState::predict_transitions`]).
    pub(crate) fn predict_linearized(
        &mut self,
        model: &crate::model::Model,
        q: &crate::model::ProcessNoise,
        dt: f64,
        substeps: usize,
    ) -> Result<(), FilterError> {
        if model.is_discrete_time() {
            let step = StepModels {
                dynamics: model,
                q,
                measurement: model,
                unfrozen: None,
            };
            return self.predict_transitions(&step, dt, &mut propagate::linearized_map);
        }
        if let (1, None, Some(q)) = (model.n, &self.moments.sensitivity, q.constant()) {
            return self.predict_scalar(model, q[(0, 0)], dt, substeps);
        }
        self.predict_with(dt, substeps, |at, rates, jacobian| {
            propagate::linearized_rates(model, q, jacobian, at, rates);
            Ok(())
        })
    }

    /// The prediction through a discrete-time map over `dt`: its k transitions
    /// ([`crate::Model::transitions`]), each by [`propagate::transition`] with the map's
    /// `moments` — or with the exact moments of the filter's own map when it is affine
    /// ([`GaussianState::with_affine_map`]); the earlier transitions of a driven model at the
    /// times they reach.
    pub(crate) fn predict_transitions(
        &mut self,
        step: &StepModels<'_>,
        dt: f64,
        moments: &mut propagate::MapMoments<'_>,
    ) -> Result<(), FilterError> {
        let k = step.dynamics.transitions(dt)?;
        // The filter's own map (not a driven model's) by its exact moments when it is affine.
        let mut exact;
        let moments: &mut propagate::MapMoments<'_> = match (&mut self.affine, &step.unfrozen) {
            (Some(map), None) => {
                exact = |_: &crate::model::Model,
                         at: (&DVector<f64>, &DMatrix<f64>),
                         out: (&mut DVector<f64>, &mut DMatrix<f64>),
                         jacobian: &mut [f64]| {
                    map.moments(at, out, jacobian);
                    Ok(())
                };
                &mut exact
            }
            _ => moments,
        };
        for j in 0..k {
            let earlier = match step.unfrozen {
                Some((model, inputs)) if j + 1 < k => Some(model.transition_at(inputs, j, k)?),
                _ => None,
            };
            let q = earlier.as_ref().map(|model| model.process_noise());
            let (model, q) = match (&earlier, &q) {
                (Some(model), Some(q)) => (&**model, q),
                _ => (step.dynamics, step.q),
            };
            propagate::transition(
                model,
                q,
                &mut self.mean,
                &mut self.cov,
                &mut self.moments,
                moments,
            )?;
            check_moments(&self.mean, &self.cov)?;
        }
        Ok(())
    }

    /// Integrates moment equations given by `rates` over `dt` in `substeps` RK4 steps (see
    /// [`propagate::rk4_moments`]), in the state's own storage.
    pub(crate) fn predict_with(
        &mut self,
        dt: f64,
        substeps: usize,
        rates: impl FnMut(
            (&DVector<f64>, &DMatrix<f64>),
            (&mut DVector<f64>, &mut DMatrix<f64>),
            &mut [f64],
        ) -> Result<(), FilterError>,
    ) -> Result<(), FilterError> {
        propagate::rk4_moments(
            &mut self.mean,
            &mut self.cov,
            dt,
            substeps,
            &mut self.moments,
            rates,
        )?;
        self.check()
    }

    /// [`GaussianState::predict_linearized`] of a scalar state with a constant Q, when no
    /// sensitivity is tracked: [`propagate::rk4_moments`] of [`propagate::linearized_rates`] on
    /// two numbers (`dm/dt = f(m)`, `dP/dt = 2 f′(m) P + Q`), the same operations in the same
    /// order — so the same bits — without the n-dimensional storage.
    fn predict_scalar(
        &mut self,
        model: &crate::model::Model,
        q: f64,
        dt: f64,
        substeps: usize,
    ) -> Result<(), FilterError> {
        let h = dt / substeps as f64;
        let rates = |m: f64, p: f64| {
            let (mut f, mut a) = ([0.0], [0.0]);
            model.drift.eval_with_jacobian(&[m], &mut f, &mut a);
            (f[0], 2.0 * (a[0] * p) + q)
        };
        let (mut m, mut p) = (self.mean[0], self.cov[(0, 0)]);
        for _ in 0..substeps {
            let k0 = rates(m, p);
            let half = 0.5 * h;
            let k1 = rates(m + half * k0.0, p + half * k0.1);
            let k2 = rates(m + half * k1.0, p + half * k1.1);
            let k3 = rates(m + h * k2.0, p + h * k2.1);
            let sixth = h / 6.0;
            m += sixth * (k0.0 + 2.0 * (k1.0 + k2.0) + k3.0);
            p += sixth * (k0.1 + 2.0 * (k1.1 + k2.1) + k3.1);
        }
        self.mean[0] = m;
        self.cov[(0, 0)] = p;
        self.check()
    }

    /// The common first half of an EKF-type step (with the `step`'s models): the measurement equation of `obs` (checked
    /// before anything moves, so a refused one leaves the state; `name` is the filter's, for
    /// errors), then the linearised prediction over `obs.dt` and R at the predicted mean;
    /// `None` when there is nothing to assimilate (a prediction only, or the zero increment at
    /// τ₀).
    pub(crate) fn predict_then_measure<'f>(
        &mut self,
        name: &str,
        step: &StepModels<'_>,
        substeps: usize,
        form: &'f mut measurement::MeasurementForm,
        obs: &crate::filters::Observation,
    ) -> Result<Option<&'f measurement::Measurement>, FilterError> {
        let meas = form.at(name, obs)?;
        if obs.dt > 0.0 && step.dynamics.is_discrete_time() {
            self.predict_transitions(step, obs.dt, &mut propagate::linearized_map)?;
        } else if obs.dt > 0.0 {
            self.predict_linearized(step.dynamics, step.q, obs.dt, substeps)?;
        }
        match meas {
            Some(meas) => {
                meas.noise_at(step.measurement, self.mean.as_slice())?;
                Ok(Some(meas))
            }
            None => Ok(None),
        }
    }

    /// Mean and covariance as an [`Estimate`](crate::filters::Estimate).
    pub(crate) fn estimate(&self) -> crate::filters::Estimate {
        crate::filters::Estimate {
            mean: self.mean.clone(),
            covariance: Some(self.cov.clone()),
            map: None,
        }
    }

    /// [`GaussianState::estimate`] into `out`, reusing its storage, with `map` as its MAP
    /// point.
    pub(crate) fn estimate_into(
        &self,
        out: &mut crate::filters::Estimate,
        map: Option<&DVector<f64>>,
    ) {
        crate::filters::copy_vector(&mut out.mean, &self.mean);
        crate::filters::copy_matrix(&mut out.covariance, &self.cov);
        crate::filters::copy_optional_vector(&mut out.map, map);
    }

    /// Tracks the transition of every prediction from now on ([`propagate::Sensitivity`]),
    /// for an RTS smoother.
    pub(crate) fn track_transitions(&mut self) {
        self.moments.sensitivity = Some(propagate::Sensitivity::new(self.mean.len()));
    }

    /// The tracked transition, when [`GaussianState::track_transitions`] was called.
    pub(crate) fn transition(&self) -> Option<&propagate::Sensitivity> {
        self.moments.sensitivity.as_ref()
    }

    /// After a prediction made without the moment equations (the Kalman–Bucy filter's exact
    /// one, with transition matrix `phi`): Φ ← phi Φ and the predicted moments, when the
    /// transitions are tracked (nothing is done, nor allocated, otherwise).
    pub(crate) fn record_prediction(&mut self, phi: &DMatrix<f64>) {
        if let Some(s) = self.moments.sensitivity.as_mut() {
            s.phi = phi * &s.phi;
            s.predicted.0.copy_from(&self.mean);
            s.predicted.1.copy_from(&self.cov);
        }
    }

    /// A step begins, when the transitions are tracked: Φ = I, and the prediction is the
    /// current (m, P) until one is made ([`propagate::Sensitivity::begin`]).
    pub(crate) fn begin_tracked_step(&mut self) {
        if let Some(s) = self.moments.sensitivity.as_mut() {
            s.begin(&self.mean, &self.cov);
        }
    }

    /// Fails when m or P is non-finite.
    pub(crate) fn check(&self) -> Result<(), FilterError> {
        check_moments(&self.mean, &self.cov)
    }
}

/// Fails when m or P is non-finite.
fn check_moments(mean: &DVector<f64>, cov: &DMatrix<f64>) -> Result<(), FilterError> {
    check_finite_vector(mean, "mean")?;
    check_finite_matrix(cov, "covariance")
}

/// Validates a [`GaussianInit`] against the state dimension, appending problems.
pub(crate) fn validate_init(init: &GaussianInit, n: usize) -> Vec<crate::validate::ConfigProblem> {
    use crate::validate::{check_spd, check_vector, ConfigProblem};
    let mut problems = Vec::new();
    if let Some(m) = &init.mean {
        check_vector(m, n, "init.mean", &mut problems);
    }
    if let Some(c) = &init.cov {
        check_spd(c, n, "init.cov", &mut problems);
    }
    if let Some(v) = init.variance {
        if !(v > 0.0 && v.is_finite()) {
            problems.push(ConfigProblem::new(
                "init.variance",
                "must be positive and finite",
            ));
        }
    }
    problems
}

/// The models one step of a Gaussian filter uses: the dynamics' (with its process noise Q)
/// over the interval and the measurement's at its end — the filter's own model for both, or,
/// for a driven model, those frozen for the step ([`crate::Inputs`]).
#[derive(Debug)]
pub(crate) struct StepModels<'a> {
    /// The model over the interval.
    pub dynamics: &'a crate::model::Model,
    /// Its process noise Q.
    pub q: &'a crate::model::ProcessNoise,
    /// The model at the measurement.
    pub measurement: &'a crate::model::Model,
    /// A driven model before it was frozen, with the step's inputs: what the earlier
    /// transitions of a discrete-time map over several periods read
    /// ([`crate::Model::transition_at`]); `None` for an autonomous model.
    pub unfrozen: Option<(&'a crate::model::Model, Option<crate::model::Inputs<'a>>)>,
}

/// What a driven model's step uses in place of the filter's own model, process noise and
/// measurement form: the models frozen for the step's observation.
pub(crate) struct DrivenStep {
    dynamics: crate::model::Model,
    q: crate::model::ProcessNoise,
    measurement: crate::model::Model,
    form: measurement::MeasurementForm,
}

impl DrivenStep {
    /// `None` for an autonomous model; checked before anything moves (inputs missing or not
    /// finite are an error).
    pub(crate) fn of(
        name: &str,
        model: &crate::model::Model,
        obs: &crate::filters::Observation,
    ) -> Result<Option<Self>, FilterError> {
        let Some((dynamics, measurement)) = obs.frozen(model)? else {
            return Ok(None);
        };
        Ok(Some(DrivenStep {
            q: dynamics.process_noise(),
            form: measurement::MeasurementForm::new(name, &measurement)?,
            dynamics,
            measurement,
        }))
    }

    /// The step's models and measurement form: `driven`'s when there is one, else the
    /// filter's own.
    pub(crate) fn parts<'a>(
        driven: &'a mut Option<DrivenStep>,
        (model, inputs): (&'a crate::model::Model, Option<crate::model::Inputs<'a>>),
        q: &'a crate::model::ProcessNoise,
        form: &'a mut measurement::MeasurementForm,
    ) -> (StepModels<'a>, &'a mut measurement::MeasurementForm) {
        match driven {
            Some(d) => (
                StepModels {
                    dynamics: &d.dynamics,
                    q: &d.q,
                    measurement: &d.measurement,
                    unfrozen: Some((model, inputs)),
                },
                &mut d.form,
            ),
            None => (
                StepModels {
                    dynamics: model,
                    q,
                    measurement: model,
                    unfrozen: None,
                },
                form,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{InnovationWindow, NIS_WINDOW};
    use crate::testing::test;

    /// The scalar prediction gives the general RK4's bits: one state predicted both ways (the
    /// general path taken by tracking the transition's sensitivity, which changes nothing in
    /// m and P).
    #[test]
    fn the_scalar_prediction_is_the_general_one_to_the_bit() {
        use crate::model::{Model, Noise};
        let model = Model::from_text(&["x - x^3 + 0.3*sin(x)"], &["x"], Noise::discrete(0.1))
            .unwrap()
            .with_diffusion(nalgebra::DMatrix::from_element(1, 1, 0.7))
            .unwrap();
        let q = model.process_noise();
        let start = |track: bool| {
            let mut state = super::GaussianState::initial(
                nalgebra::DVector::from_element(1, 0.8),
                nalgebra::DMatrix::from_element(1, 1, 0.3),
                &super::GaussianInit::default(),
                1,
            );
            if track {
                state.track_transitions();
            }
            state
        };
        let (mut scalar, mut general) = (start(false), start(true));
        for dt in [0.1, 0.25, 0.03] {
            scalar.predict_linearized(&model, &q, dt, 4).unwrap();
            general.predict_linearized(&model, &q, dt, 4).unwrap();
            assert_eq!(
                scalar.mean[0].to_bits(),
                general.mean[0].to_bits(),
                "dt = {dt}"
            );
            assert_eq!(
                scalar.cov[(0, 0)].to_bits(),
                general.cov[(0, 0)].to_bits(),
                "dt = {dt}"
            );
        }
        assert!(scalar.mean[0] != 0.8, "the state moved");
    }

    /// A push undone by a rollback leaves the window as it was — its mean, and the means
    /// after the same later pushes — at every position of the ring, the wrap included.
    #[test]
    fn a_rolled_back_push_leaves_the_window_as_it_was() {
        let mut window = InnovationWindow::new();
        for k in 0..3 * NIS_WINDOW {
            let before = window.clone();
            let mark = window.mark();
            window.push(1e3 + k as f64, 1 + k % 2);
            window.rollback(&mark);
            assert_eq!(window.mean(), before.mean(), "push {k}");
            let mut twin = before;
            let nis = libm::exp(libm::cos(k as f64));
            window.push(nis, 2);
            twin.push(nis, 2);
            assert_eq!(window.mean(), twin.mean(), "push {k}");
        }
    }

    /// The running sum against the window's values summed afresh, over 10 windows with an
    /// infinite value among them (which leaves the window after 50 pushes).
    #[test]
    fn the_window_mean_is_the_mean_of_its_last_values() {
        let mut window = InnovationWindow::new();
        let mut pushed = alloc::vec::Vec::new();
        for k in 0..10 * NIS_WINDOW + 7 {
            let nis = if k == 123 {
                f64::INFINITY
            } else {
                libm::exp(libm::sin(k as f64 * 1.3))
            };
            window.push(nis, 2);
            pushed.push(nis);
            let got = window.mean().map(|(mean, observed)| {
                assert_eq!(observed, 2 * NIS_WINDOW);
                mean
            });
            if pushed.len() < NIS_WINDOW {
                assert_eq!(got, None);
                continue;
            }
            let last = &pushed[pushed.len() - NIS_WINDOW..];
            let expected = last.iter().sum::<f64>() / (2 * NIS_WINDOW) as f64;
            let got = got.unwrap();
            if expected.is_finite() {
                assert!(
                    (got - expected).abs() <= 1e-12 * expected,
                    "step {k}: {got} vs {expected}"
                );
            } else {
                assert_eq!(got, expected, "step {k}");
            }
        }
    }
}
