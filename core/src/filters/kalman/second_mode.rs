//! The MAP filters' watch for a second posterior mode.
//!
//! The IEKF and IOKF of 003 §4 carry one Gaussian and move it, at every observation, to the
//! MAP point of the approximate posterior (4.5). When the observations cannot tell two states
//! apart — h = x² cannot tell x from −x — the exact posterior keeps two modes, the filters
//! follow one, and neither their innovations nor their updates show it: the other mode
//! explains every observation just as well. This watch looks for such a mode and follows it:
//!
//! 1. **Search** (at the first update, then every [`SEARCH_EVERY`] while no second mode is
//!    followed): starting from the reflection `2m_f − x̂` of the estimate x̂ through the mean
//!    `m_f` of the *free* distribution (the filter's initial Gaussian carried by the model
//!    alone, without observations), Levenberg–Marquardt steps on `(z − h(x))ᵀR⁻¹(z − h(x))`
//!    with `z = h(x̂)`, over the points `x̂ + P Hᵀ α` (the directions the observation
//!    informs), look for a second root of `h(x) = h(x̂)`. A root is a candidate when it
//!    matches to [`MATCH`] and lies at least [`SECOND_MODE_THRESHOLD`] posterior standard
//!    deviations from x̂ (closer, it could not move the mean that far).
//! 2. **Weight at discovery**: the ratio Λ of the free density at the candidate and at the
//!    estimate — how plausible the model alone makes the two states, the past observations
//!    being (by the search) explained alike. Below [`DROP_BELOW`] the candidate is not taken.
//! 3. **Follow**: the candidate becomes a second Gaussian (the estimate's covariance at the
//!    candidate's point) run through the same prediction and MAP update; Λ is multiplied at
//!    every observation by the ratio of their innovation densities `N(z − h(m); 0, HPHᵀ + R)`
//!    at the predicted means — the weights of a two-component Gaussian-sum filter (Alspach &
//!    Sorenson 1972). It is dropped when Λ falls below [`DROP_BELOW`] (the observations tell
//!    the states apart) or the two come within [`SECOND_MODE_THRESHOLD`] standard deviations.
//!
//! Once a second mode has been followed for [`CONFIRM`] updates, the self-check value is the
//! distance `w·d` of the two modes' weighted mean from the estimate, in the estimate's
//! standard deviations (`w = Λ/(1 + Λ)` the second mode's share, d their distance); above
//! [`SECOND_MODE_THRESHOLD`] it is a concern: the posterior has two modes (or one wide one
//! between them), the filter's estimate is one of them, and the conditional mean lies that far
//! away. On the bimodal case of the tests (h = x², dx = −½x dt + dv, prior N(0.3, 1)) the
//! concern is raised on 84 % of the steps where the IEKF is more than 0.1 from the exact mean;
//! on the presets (seeds 1–5) never.
//!
//! Cost: the search is a few Levenberg–Marquardt steps on the measurement equation and one
//! RK4 step of the free distribution's moment equations, once per [`SEARCH_EVERY`] updates
//! (bearings-only IEKF run: +4 %); while a second mode is followed every update costs twice.
//! The estimate itself is never changed. What the search cannot find — a second mode away
//! from the reflection, or one the observation tells apart only over time — this watch does
//! not see; if the free distribution cannot be propagated (non-finite moments) the watch
//! stops.

use nalgebra::{DMatrix, DVector};

use super::map_point::{
    in_standard_deviations, map_update, quadratic_form, spd_inverse_into, MapSolver, MapWork,
};
use super::measurement::Measurement;
use super::GaussianState;
use crate::filters::Concern;
use crate::linalg::{lower_cholesky_into, lower_cholesky_solve};
use crate::model::Model;

/// Updates between two searches, and how long a second mode is followed before it counts.
pub(crate) const SEARCH_EVERY: usize = 10;

/// The self-check threshold on the distance of the two modes' weighted mean from the
/// estimate, in the estimate's standard deviations; a second mode closer than this to the
/// estimate (which could not move the mean that far) is neither taken nor followed.
pub(crate) const SECOND_MODE_THRESHOLD: f64 = 0.25;

/// A second mode whose weight ratio falls below this is dropped.
pub(crate) const DROP_BELOW: f64 = 1e-3;

/// Updates a second mode is followed before it counts.
pub(crate) const CONFIRM: usize = 20;

/// Largest `(z − h(x))ᵀR⁻¹(z − h(x))` of a candidate: h(x) equals h(x̂) to 10⁻³ of one
/// observation's noise — a state the observation function cannot tell from the estimate, not
/// one it tells apart only slowly.
pub(crate) const MATCH: f64 = 1e-6;

/// Levenberg–Marquardt steps of one search.
const SEARCH_STEPS: usize = 30;

/// What the filter's step used, for the second mode to go through the same interval.
pub(super) struct Interval<'a> {
    pub solver: MapSolver,
    pub model: &'a Model,
    /// The process noise covariance.
    pub q: &'a crate::model::ProcessNoise,
    /// RK4 steps of the moment equations per interval.
    pub substeps: usize,
    pub dt: f64,
    pub meas: &'a Measurement,
}

/// The second-mode watch of one MAP filter (module doc). Allocates only when built.
#[derive(Clone, Debug)]
pub(crate) struct ModeWatch {
    /// The filter's initial Gaussian carried by the model alone, propagated at each search.
    free: GaussianState,
    /// Time and observation intervals since `free` was propagated.
    free_elapsed: f64,
    free_intervals: usize,
    /// The second mode followed, when `following`.
    shadow: GaussianState,
    shadow_work: MapWork,
    following: bool,
    /// ln of the second mode's weight over the estimate's.
    log_ratio: f64,
    /// Updates since the second mode was found.
    followed: usize,
    /// Its distance from the estimate at the last update, in the estimate's standard deviations.
    apart: f64,
    /// Updates since the last search.
    since_search: usize,
    /// Set when the free distribution could not be propagated: the watch stops.
    stopped: bool,
    /// The storage of a search.
    search: Search,
    /// A state difference (n) and a Cholesky factor (n × n).
    diff: DVector<f64>,
    factor: DMatrix<f64>,
}

impl ModeWatch {
    /// A watch for a filter starting from `initial`, with m observation components.
    pub(crate) fn new(initial: &GaussianState, m: usize) -> Self {
        let n = initial.mean.len();
        ModeWatch {
            free: initial.clone(),
            free_elapsed: 0.0,
            free_intervals: 0,
            shadow: initial.clone(),
            shadow_work: MapWork::new(n, m),
            following: false,
            log_ratio: 0.0,
            followed: 0,
            apart: 0.0,
            // The first search at the first update.
            since_search: SEARCH_EVERY - 1,
            stopped: false,
            search: Search::new(n, m),
            diff: DVector::zeros(n),
            factor: DMatrix::zeros(n, n),
        }
    }

    /// Time passing without an observation (`substeps` RK4 steps over `dt`): the free
    /// distribution's clock runs on, and a followed second mode is predicted as the filter is.
    pub(super) fn elapse(
        &mut self,
        model: &Model,
        q: &crate::model::ProcessNoise,
        substeps: usize,
        dt: f64,
    ) {
        self.free_elapsed += dt;
        self.free_intervals += 1;
        if self.following
            && !self.stopped
            && dt > 0.0
            && self
                .shadow
                .predict_linearized(model, q, dt, substeps)
                .is_err()
        {
            self.following = false;
        }
    }

    /// After the filter's update of `state` (its MAP point and Laplace covariance) over
    /// `interval`, with `log_density` its innovation's: follows the second mode through the
    /// same interval and update, or searches for one when it is time.
    pub(super) fn after_update(
        &mut self,
        interval: &Interval,
        state: &GaussianState,
        log_density: f64,
    ) {
        self.free_elapsed += interval.dt;
        self.free_intervals += 1;
        if self.stopped {
            return;
        }
        if self.following {
            self.follow(interval, state, log_density);
            return;
        }
        self.since_search += 1;
        if self.since_search >= SEARCH_EVERY {
            self.since_search = 0;
            self.search(interval.model, interval.q, interval.meas, state);
        }
    }

    /// One interval of the second mode; dropped when it fails, fades or merges.
    fn follow(&mut self, interval: &Interval, state: &GaussianState, log_density: f64) {
        let Interval {
            solver,
            model,
            q,
            substeps,
            dt,
            meas,
        } = *interval;
        let shadow = &mut self.shadow;
        let stepped = if dt > 0.0 {
            shadow.predict_linearized(model, q, dt, substeps)
        } else {
            Ok(())
        }
        .and_then(|()| map_update(solver, model, meas, shadow, &mut self.shadow_work));
        let Ok(report) = stepped else {
            self.following = false;
            return;
        };
        self.log_ratio += report.log_density - log_density;
        self.followed += 1;
        self.diff.copy_from(&shadow.mean);
        self.diff -= &state.mean;
        let apart = in_standard_deviations(&state.cov, &mut self.factor, &mut self.diff);
        self.apart = apart;
        let ratio = libm::exp(self.log_ratio);
        if !(ratio >= DROP_BELOW && apart >= SECOND_MODE_THRESHOLD) {
            self.following = false;
        }
    }

    /// Brings the free distribution to the present, one RK4 step per [`SEARCH_EVERY`]
    /// observation intervals; false (and the watch stops) when it cannot be propagated.
    fn bring_free_up_to_date(&mut self, model: &Model, q: &crate::model::ProcessNoise) -> bool {
        if self.free_elapsed > 0.0 {
            let steps = self.free_intervals.div_ceil(SEARCH_EVERY).max(1);
            if self
                .free
                .predict_linearized(model, q, self.free_elapsed, steps)
                .is_err()
            {
                self.stopped = true;
                return false;
            }
        }
        self.free_elapsed = 0.0;
        self.free_intervals = 0;
        true
    }

    /// Looks for a second mode (module doc, steps 1 and 2) and starts following it.
    fn search(
        &mut self,
        model: &Model,
        q: &crate::model::ProcessNoise,
        meas: &Measurement,
        state: &GaussianState,
    ) {
        if !self.bring_free_up_to_date(model, q) || !self.candidate(model, meas, state) {
            return;
        }
        let (free, factor, diff) = (&self.free, &mut self.factor, &mut self.diff);
        let log_ratio = log_gaussian_kernel(free, factor, diff, &self.search.x)
            - log_gaussian_kernel(free, factor, diff, &state.mean);
        if log_ratio.is_nan() || log_ratio < libm::log(DROP_BELOW) {
            return;
        }
        self.shadow.mean.copy_from(&self.search.x);
        self.shadow.cov.copy_from(&state.cov);
        self.log_ratio = log_ratio;
        self.followed = 0;
        self.following = true;
    }

    /// The search's point (module doc, step 1), left in `search.x`; whether it is a candidate.
    fn candidate(&mut self, model: &Model, meas: &Measurement, state: &GaussianState) -> bool {
        let search = &mut self.search;
        if !search.prepare(model, meas, state) {
            return false;
        }
        // From the reflection of the estimate through the free mean, projected on x̂ + Bα.
        self.diff.copy_from(&self.free.mean);
        self.diff -= &state.mean;
        self.diff *= 2.0;
        if !search.project(&self.diff) {
            return false;
        }
        let mismatch = search.solve(model, meas, &state.mean);
        // An exact match (to MATCH, in units of one observation's noise) …
        if mismatch.is_nan() || mismatch > MATCH {
            return false;
        }
        // … and apart from the estimate.
        self.diff.copy_from(&search.x);
        self.diff -= &state.mean;
        let apart = in_standard_deviations(&state.cov, &mut self.factor, &mut self.diff);
        apart >= SECOND_MODE_THRESHOLD
    }

    /// The distance of the two modes' mean from the estimate, in the estimate's standard
    /// deviations, `w·d` with `w = Λ/(1 + Λ)` the second mode's share of their weight and d
    /// their distance — once a second mode has been followed for [`CONFIRM`] updates.
    pub(crate) fn shift(&self) -> Option<f64> {
        if !self.following || self.followed < CONFIRM {
            return None;
        }
        let ratio = libm::exp(self.log_ratio);
        Some(ratio / (1.0 + ratio) * self.apart)
    }

    /// The self-check (module doc).
    pub(crate) fn check(&self, out: &mut alloc::vec::Vec<Concern>) {
        let Some(shift) = self.shift() else {
            return;
        };
        if shift > SECOND_MODE_THRESHOLD {
            out.push(Concern::above(
                "mean of the estimate's mode and a second mode, from the estimate, in standard deviations",
                shift,
                SECOND_MODE_THRESHOLD,
                "another state explains the observations about as well as the estimate: the posterior has two modes, the MAP filter follows one, and its estimate is that mode, not the conditional mean; use a grid, spectral or particle filter here",
            ));
        }
    }
}

/// `−½ (x − m)ᵀ P⁻¹ (x − m)` of `gaussian`, through the storage `factor` and `diff`.
fn log_gaussian_kernel(
    gaussian: &GaussianState,
    factor: &mut DMatrix<f64>,
    diff: &mut DVector<f64>,
    x: &DVector<f64>,
) -> f64 {
    diff.copy_from(x);
    *diff -= &gaussian.mean;
    let d = in_standard_deviations(&gaussian.cov, factor, diff);
    -0.5 * d * d
}

/// The search of step 1 (module doc) in the directions the observation informs: points
/// `x(α) = x̂ + Bα`, `B = P Hᵀ` at x̂ (α ∈ ℝᵐ), and Levenberg–Marquardt steps on
/// `c(α) = rᵀR⁻¹r`, `r = scale·h(x(α)) − scale·h(x̂)`. Along directions the observation does not
/// inform (a bearing's range) every point matches h(x̂) and says nothing about a second mode;
/// along B a second root of `h(x) = h(x̂)` is a state the observations cannot tell from the
/// estimate (−x̂ for h = x²).
#[derive(Clone, Debug)]
struct Search {
    /// `scale·h(x̂)` (m).
    target: DVector<f64>,
    /// R⁻¹ (m × m) and the storage of R's Cholesky factor.
    r_inv: DMatrix<f64>,
    r_factor: DMatrix<f64>,
    /// B = P Hᵀ at x̂ (n × m).
    b: DMatrix<f64>,
    /// scale·∂h/∂x at a point (m × n) and its row-major evaluation.
    h: DMatrix<f64>,
    rows: alloc::vec::Vec<f64>,
    /// J = scale·H(x(α)) B, the normal matrix JᵀR⁻¹J, its damped copy and factor (m × m).
    j: DMatrix<f64>,
    normal: DMatrix<f64>,
    damped: DMatrix<f64>,
    factor: DMatrix<f64>,
    /// α, a trial α, the step, the gradient JᵀR⁻¹r, the residual and R⁻¹r (m).
    alpha: DVector<f64>,
    trial: DVector<f64>,
    step: DVector<f64>,
    gradient: DVector<f64>,
    residual: DVector<f64>,
    weighted: DVector<f64>,
    /// x(α) (n).
    x: DVector<f64>,
}

impl Search {
    fn new(n: usize, m: usize) -> Self {
        Search {
            target: DVector::zeros(m),
            r_inv: DMatrix::zeros(m, m),
            r_factor: DMatrix::zeros(m, m),
            b: DMatrix::zeros(n, m),
            h: DMatrix::zeros(m, n),
            rows: alloc::vec![0.0; m * n],
            j: DMatrix::zeros(m, m),
            normal: DMatrix::zeros(m, m),
            damped: DMatrix::zeros(m, m),
            factor: DMatrix::zeros(m, m),
            alpha: DVector::zeros(m),
            trial: DVector::zeros(m),
            step: DVector::zeros(m),
            gradient: DVector::zeros(m),
            residual: DVector::zeros(m),
            weighted: DVector::zeros(m),
            x: DVector::zeros(n),
        }
    }

    /// z, R⁻¹, B and `HPHᵀ = HB` (in `normal`) at the estimate; false when R is singular.
    fn prepare(&mut self, model: &Model, meas: &Measurement, state: &GaussianState) -> bool {
        meas.predict_into(model, state.mean.as_slice(), self.target.as_mut_slice());
        if spd_inverse_into(&meas.noise_cov, &mut self.r_factor, &mut self.r_inv, "R").is_err() {
            return false;
        }
        meas.jacobian_into(model, state.mean.as_slice(), &mut self.rows, &mut self.h);
        let (m, n) = self.h.shape();
        for i in 0..n {
            for k in 0..m {
                self.b[(i, k)] = (0..n).map(|j| state.cov[(i, j)] * self.h[(k, j)]).sum();
            }
        }
        times_b(&self.h, &self.b, &mut self.normal);
        true
    }

    /// `α = (HPHᵀ)⁻¹ H d`: the point x̂ + Bα nearest x̂ + d in the metric of P⁻¹ (`BᵀP⁻¹ = H`);
    /// false when HPHᵀ is singular (the observation informs no direction at x̂).
    fn project(&mut self, d: &DVector<f64>) -> bool {
        if !lower_cholesky_into(&self.normal, &mut self.factor) {
            return false;
        }
        self.alpha.gemv(1.0, &self.h, d, 0.0);
        lower_cholesky_solve(&self.factor, &mut self.alpha);
        self.alpha.iter().all(|v| v.is_finite())
    }

    /// `c(α)` at `alpha`, with x(α) in `x` and the residual in `residual`.
    fn cost(&mut self, model: &Model, meas: &Measurement, xhat: &DVector<f64>, trial: bool) -> f64 {
        let alpha = if trial { &self.trial } else { &self.alpha };
        self.x.copy_from(xhat);
        self.x.gemv(1.0, &self.b, alpha, 1.0);
        meas.predict_into(model, self.x.as_slice(), self.residual.as_mut_slice());
        self.residual -= &self.target;
        let c = quadratic_form(&self.r_inv, &self.residual);
        if c.is_finite() {
            c
        } else {
            f64::INFINITY
        }
    }

    /// Levenberg–Marquardt on c(α) from the projected start; returns the final c, with the
    /// point in `x`.
    fn solve(&mut self, model: &Model, meas: &Measurement, xhat: &DVector<f64>) -> f64 {
        let mut c = self.cost(model, meas, xhat, false);
        let mut mu = 1e-3;
        for _ in 0..SEARCH_STEPS {
            if c <= MATCH * 1e-6 {
                break;
            }
            // J = scale·H(x) B at the current point (x holds x(α) after `cost`).
            meas.jacobian_into(model, self.x.as_slice(), &mut self.rows, &mut self.h);
            times_b(&self.h, &self.b, &mut self.j);
            self.weighted.gemv(1.0, &self.r_inv, &self.residual, 0.0);
            self.gradient.gemv_tr(1.0, &self.j, &self.weighted, 0.0);
            let m = self.j.nrows();
            for a in 0..m {
                for b in 0..m {
                    self.normal[(a, b)] = (0..m)
                        .map(|k| {
                            self.j[(k, a)]
                                * (0..m)
                                    .map(|l| self.r_inv[(k, l)] * self.j[(l, b)])
                                    .sum::<f64>()
                        })
                        .sum();
                }
            }
            let mut improved = false;
            while mu < 1e12 {
                self.damped.copy_from(&self.normal);
                for a in 0..m {
                    self.damped[(a, a)] += mu * (self.normal[(a, a)] + 1e-300);
                }
                if lower_cholesky_into(&self.damped, &mut self.factor) {
                    self.step.copy_from(&self.gradient);
                    lower_cholesky_solve(&self.factor, &mut self.step);
                    self.trial.copy_from(&self.alpha);
                    self.trial -= &self.step;
                    let trial_cost = self.cost(model, meas, xhat, true);
                    if trial_cost < c {
                        core::mem::swap(&mut self.alpha, &mut self.trial);
                        c = trial_cost;
                        mu = (mu / 10.0).max(1e-12);
                        improved = true;
                        break;
                    }
                }
                mu *= 10.0;
            }
            if !improved {
                break;
            }
        }
        // x and residual at the accepted α.
        self.cost(model, meas, xhat, false)
    }
}

/// `out = h B` (m × m) for h (m × n) and B (n × m).
fn times_b(h: &DMatrix<f64>, b: &DMatrix<f64>, out: &mut DMatrix<f64>) {
    let (m, n) = h.shape();
    for a in 0..m {
        for c in 0..m {
            out[(a, c)] = (0..n).map(|k| h[(a, k)] * b[(k, c)]).sum();
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::filters::kalman::GaussianInit;
    use crate::model::Noise;
    use crate::testing::test;

    /// The search from an estimate x̂ = 1.2 (sd 0.2) with the free distribution N(0, 1):
    /// for h = x² it finds the mirror −1.2 (to 10⁻⁸), a candidate; for h = x³ (one root) and
    /// h = x (linear) it finds x̂ itself, no candidate.
    #[test]
    fn the_search_finds_the_mirror_of_an_even_observation_and_nothing_else() {
        for (h, mirror) in [("x^2", Some(-1.2)), ("x^3", None), ("x", None)] {
            let model = Model::from_text(&["0"], &[h], Noise::continuous(1.0)).unwrap();
            let free = GaussianState::initial(
                DVector::from_element(1, 0.0),
                DMatrix::from_element(1, 1, 1.0),
                &GaussianInit::default(),
                1,
            );
            let mut watch = ModeWatch::new(&free, 1);
            let mut state = free.clone();
            state.mean[0] = 1.2;
            state.cov[(0, 0)] = 0.04;
            // Δy = 0 over Δτ = 0.01 with S = 1: scale 0.01, R = 0.01.
            let mut form = super::super::measurement::MeasurementForm::new("test", &model).unwrap();
            let obs = crate::filters::Observation::increment(0.01, &[0.0]);
            let meas = form.at("test", &obs).unwrap().unwrap();
            assert_eq!((meas.scale, meas.noise_cov[(0, 0)]), (0.01, 0.01));
            let found = watch.candidate(&model, meas, &state);
            match mirror {
                Some(x) => {
                    assert!(found, "{h}: no candidate");
                    assert!(
                        (watch.search.x[0] - x).abs() < 1e-8,
                        "{h}: {}",
                        watch.search.x[0]
                    );
                }
                None => assert!(!found, "{h}: candidate at {}", watch.search.x[0]),
            }
        }
    }
}
