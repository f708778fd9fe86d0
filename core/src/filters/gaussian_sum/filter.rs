//! The Gaussian-sum filter itself.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::GaussianSumParams;
use crate::error::{FilterError, ZakaiError};
use crate::filters::kalman::linear::{affine_parts, Discretization};
use crate::filters::{marginal, Estimate, Filter, Observation, ObservationKind, Observed};
use crate::grid::TensorGrid;
use crate::linalg::{
    cholesky_in, gaussian_log_density_factored, log_det_from_factor, log_sum_exp, symmetrize,
};
use crate::model::{GaussianMixture, Model, ObservationModel, Prior};

/// One weighted Gaussian `w N(m, P)` with the Cholesky factor and `log det` of P (for its
/// density), in storage that is rewritten in place.
#[derive(Clone, Debug)]
struct Component {
    w: f64,
    m: DVector<f64>,
    p: DMatrix<f64>,
    /// `L` with `P = L Lᵀ` in the lower triangle (the upper is not read).
    l: DMatrix<f64>,
    log_det: f64,
}

impl Component {
    fn zeros(n: usize) -> Self {
        Component {
            w: 0.0,
            m: DVector::zeros(n),
            p: DMatrix::zeros(n, n),
            l: DMatrix::zeros(n, n),
            log_det: 0.0,
        }
    }

    fn new(w: f64, m: &DVector<f64>, p: &DMatrix<f64>) -> Result<Self, FilterError> {
        let mut c = Component::zeros(m.len());
        c.w = w;
        c.m.copy_from(m);
        c.p.copy_from(p);
        c.refactor()?;
        Ok(c)
    }

    /// Makes this a copy of `from` in place (same dimension).
    fn copy_from(&mut self, from: &Component) {
        self.w = from.w;
        self.m.copy_from(&from.m);
        self.p.copy_from(&from.p);
        self.l.copy_from(&from.l);
        self.log_det = from.log_det;
    }

    /// Symmetrises P and factors it again in place.
    fn refactor(&mut self) -> Result<(), FilterError> {
        symmetrize(&mut self.p);
        let chol = cholesky_in(&mut self.l, &self.p, "Gaussian-sum component covariance")?;
        self.l = chol.unpack_dirty();
        self.log_det = log_det_from_factor(&self.l);
        Ok(())
    }

    /// `log N(x; m, P)`, with `r` (n) as storage.
    fn log_density(&self, x: &[f64], r: &mut DVector<f64>) -> f64 {
        for ((r, x), m) in r.iter_mut().zip(x).zip(&self.m) {
            *r = x - m;
        }
        gaussian_log_density_factored(&self.l, self.log_det, r)
    }
}

/// A model the Gaussian-sum filter fits: `dx = (A x + b) dt + G dw`, `z = C x + c + v`.
#[derive(Clone, Debug)]
pub(crate) struct LinearMixtureModel<'p> {
    a: DMatrix<f64>,
    b: DVector<f64>,
    c: DMatrix<f64>,
    c0: DVector<f64>,
    noise: GaussianMixture,
    prior: &'p GaussianMixture,
}

/// The model's affine parts, noise and prior mixture when the filter fits it (linear,
/// discrete measurements, Gaussian-mixture prior), or why it does not fit.
pub(crate) fn check_model<'p>(
    model: &Model,
    prior: &'p Prior,
    probes: &[Vec<f64>],
) -> Result<LinearMixtureModel<'p>, FilterError> {
    let method = "the Gaussian-sum filter";
    let noise = match &model.observations {
        ObservationModel::Discrete { density } => match density.additive() {
            Some(noise) => noise.clone(),
            None => {
                return Err(FilterError::Unsuitable(format!(
                    "{method} of 001 needs additive Gaussian or Gaussian-mixture noise z_k = C x_k + v_k; this model's measurements are {}",
                    density.describe()
                )))
            }
        },
        ObservationModel::Continuous { .. } => {
            return Err(FilterError::Unsuitable(format!(
                "{method} of 001 needs discrete measurements z_k = C x_k + v_k; this model observes dy = h dt + dw"
            )))
        }
    };
    model.process_noise().require_constant(
        method,
        "its components are exact Kalman filters of a linear-Gaussian model",
    )?;
    let (a, b) = affine_parts(&*model.drift, method, "drift f", probes)?;
    let (c, c0) = affine_parts(&*model.observation, method, "observation h", probes)?;
    let Prior::Mixture(mixture) = prior else {
        return Err(FilterError::Unsuitable(format!(
            "{method} needs a Gaussian or Gaussian-mixture prior, not a density expression"
        )));
    };
    Ok(LinearMixtureModel {
        a,
        b,
        c,
        c0,
        noise,
        prior: mixture,
    })
}

/// How far the reduction moved the mixture from the exact one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reduction {
    /// Largest Runnalls cost of a merge forced by the component cap (0: none forced).
    pub forced_cost: f64,
    /// Total weight dropped by pruning, summed over measurements.
    pub pruned_weight: f64,
}

/// The Gaussian-sum filter.
///
/// The Gaussian-sum filter: the exact filtering density of a linear model with a
/// Gaussian-mixture prior and Gaussian-mixture measurement noise — the reference density of
/// 001 §4 (Šimandl & Švácha, 2005) against which J(t) is measured.
///
/// Model: `dx = (A x + b) dt + G dw`, `z_k = C x_k + c + v_k`,
/// `p(v_k) = Σ_j β_j N(μ_j, R_j)`, `p(x_0) = Σ_i α_i N(m_i, P_i)`.
///
/// * **Prediction**: every component exactly, `m ← Φ m + Γ b`, `P ← Φ P Φᵀ + Q_d` (Van Loan's
///   discretisation, shared with the Kalman–Bucy filter).
/// * **Update**: every component i meets every noise component j:
///   `S = C P_i Cᵀ + R_j`, `K = P_i Cᵀ S⁻¹`, `m_ij = m_i + K ν_ij` with
///   `ν_ij = z − C m_i − c − μ_j`, `P_ij = P_i − K S Kᵀ`, `w_ij ∝ α_i β_j N(ν_ij; 0, S)`.
/// * **Mixture reduction**: the count grows by the factor J at every measurement, so
///   components with relative weight below `prune` are dropped and pairs are merged
///   (moment-preserving) in order of Runnalls' bound on the Kullback–Leibler discrepancy
///   `B_ij = ½ [(w_i + w_j) log det P_ij − w_i log det P_i − w_j log det P_j]`, while
///   `B ≤ merge_cost` or the count exceeds `max_components`. The largest cost accepted and the
///   pruned weight are reported ([`GaussianSum::reduction`]), so how exact the reference
///   is stays visible; with no pruning or cap-forced merging the density is exact.
///
/// Cost: per measurement, one Kalman update per pair of a prior and a noise component, then
/// the reduction over the candidates' pairwise merge costs: O(K² + K n³) for K candidates in
/// n dimensions, K at most `max_components` times the noise components.
///
/// ```
/// use zakai::{Filter, GaussianSum, Model, Noise};
///
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
/// let mut gsf = GaussianSum::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
/// gsf.step_measurement(0.5, &[0.3]).unwrap();
/// assert!(gsf.estimate().mean[0] > 0.0);
/// ```
///
/// # When it fails
///
/// Exact for linear, time-invariant models with Gaussian-mixture noise and prior, up to its
/// mixture reduction: the components multiply at every update and are pruned and merged back to
/// the cap, and what that moved is reported ([`Reduction`]). A nonlinear model, or one that reads
/// the time or known inputs, is refused.
#[derive(Clone, Debug)]
pub struct GaussianSum {
    name: String,
    /// An SDE or a discrete-time map (`A` its matrix then).
    dynamics: crate::model::Dynamics,
    a: DMatrix<f64>,
    b: DVector<f64>,
    q: DMatrix<f64>,
    c: DMatrix<f64>,
    c0: DVector<f64>,
    noise: GaussianMixture,
    /// A discrete-time map's transition noise when it is a mixture (`q` is then zero and each
    /// transition splits every component into one per noise component).
    transition_noise: Option<GaussianMixture>,
    params: GaussianSumParams,
    /// The mixture: the first `len` slots of `components`.
    components: Vec<Component>,
    len: usize,
    cached: Option<Discretization>,
    reduction: Reduction,
    /// The last step's log-likelihood ([`Filter::log_likelihood`]).
    log_likelihood: f64,
    work: UpdateWork,
    /// The mixture a step started from (its first `.1` slots), restored when the step fails.
    saved: (Vec<Component>, usize, Reduction, f64),
}

/// Storage of a step, made once (the update writes the next mixture into `next`; the merge
/// cost table and liveness marks grow to their working size once).
#[derive(Clone, Debug)]
struct UpdateWork {
    next: Vec<Component>,
    merged: Component,
    moved: (DVector<f64>, DMatrix<f64>),
    z: DVector<f64>,
    predicted: DVector<f64>,
    nu: DVector<f64>,
    /// C P (m × n), P Cᵀ (n × m), S (m × m) with its factor's storage, Kᵀ (m × n).
    cp: DMatrix<f64>,
    pct: DMatrix<f64>,
    s: DMatrix<f64>,
    s_factor: DMatrix<f64>,
    gain_t: DMatrix<f64>,
    cost: Vec<f64>,
    alive: Vec<bool>,
}

impl GaussianSum {
    /// Builds the filter; the model must be linear with discrete measurements and the prior a
    /// Gaussian mixture. `probes` are the points where linearity is checked.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &GaussianSumParams,
    ) -> Result<Self, ZakaiError> {
        let (model, prior, probes) = (ctx.model, ctx.prior, ctx.probes);
        crate::filters::method::refuse_problems(&name, params.problems())?;
        let LinearMixtureModel {
            a,
            b,
            c,
            c0,
            noise,
            prior: mixture,
        } = check_model(model, prior, probes)?;
        let n = a.nrows();
        let m = c.nrows();
        let transition_noise = model
            .transition_mixture
            .as_ref()
            .map(|w| w.mixture().clone());
        // Candidates after an update (a component per noise component) or a transition.
        let j = noise.components().len().max(
            transition_noise
                .as_ref()
                .map_or(1, |w| w.components().len()),
        );
        let slots = mixture.components().len().max(params.max_components) * j;
        let mut components = (0..slots).map(|_| Component::zeros(n)).collect::<Vec<_>>();
        for (slot, c) in components.iter_mut().zip(mixture.components()) {
            *slot = Component::new(c.weight, &c.mean, &c.cov)?;
        }
        Ok(GaussianSum {
            name,
            dynamics: model.dynamics,
            q: match &transition_noise {
                Some(_) => DMatrix::zeros(n, n),
                None => model
                    .process_noise()
                    .require_constant("the Gaussian-sum filter", "checked above")?
                    .clone(),
            },
            transition_noise,
            len: mixture.components().len(),
            work: UpdateWork {
                next: (0..slots).map(|_| Component::zeros(n)).collect(),
                merged: Component::zeros(n),
                moved: (DVector::zeros(n), DMatrix::zeros(n, n)),
                z: DVector::zeros(m),
                predicted: DVector::zeros(m),
                nu: DVector::zeros(m),
                cp: DMatrix::zeros(m, n),
                pct: DMatrix::zeros(n, m),
                s: DMatrix::zeros(m, m),
                s_factor: DMatrix::zeros(m, m),
                gain_t: DMatrix::zeros(m, n),
                // Their working size, as the method's memory estimate counts it.
                cost: Vec::with_capacity(slots * slots),
                alive: Vec::with_capacity(slots),
            },
            a,
            b,
            c,
            c0,
            noise,
            params: params.clone(),
            components,
            cached: None,
            reduction: Reduction::default(),
            saved: (
                (0..slots).map(|_| Component::zeros(n)).collect(),
                0,
                Reduction::default(),
                0.0,
            ),
            log_likelihood: 0.0,
        })
    }

    /// Number of components.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no components (never, after a successful build).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The mixture's components.
    /// Keeps the mixture (storage grown once to its working size).
    fn save(&mut self) {
        let (saved, len, reduction, log_likelihood) = &mut self.saved;
        *log_likelihood = self.log_likelihood;
        self.log_likelihood = 0.0;
        let n = self.a.nrows();
        if saved.len() < self.len {
            saved.resize_with(self.len, || Component::zeros(n));
        }
        for (to, from) in saved.iter_mut().zip(&self.components[..self.len]) {
            to.copy_from(from);
        }
        *len = self.len;
        *reduction = self.reduction;
    }

    /// Back to the mixture [`GaussianSum::save`] kept.
    fn restore(&mut self) {
        let (saved, len, reduction, log_likelihood) = &self.saved;
        self.log_likelihood = *log_likelihood;
        let n = self.a.nrows();
        if self.components.len() < *len {
            self.components.resize_with(*len, || Component::zeros(n));
        }
        for (to, from) in self.components.iter_mut().zip(&saved[..*len]) {
            to.copy_from(from);
        }
        self.len = *len;
        self.reduction = *reduction;
    }

    fn mixture(&self) -> &[Component] {
        &self.components[..self.len]
    }

    /// How far the reduction moved the mixture from the exact one.
    pub fn reduction(&self) -> Reduction {
        self.reduction
    }

    /// The transitions of a map whose noise is a mixture, one at a time, each splitting every
    /// component i into one per noise component c — `w_i π_c N(A m_i + b + μ_c,
    /// A P_i Aᵀ + Q_c)`, exact — then the reduction.
    fn split_transitions(
        &mut self,
        noise: &GaussianMixture,
        period: f64,
        dt: f64,
    ) -> Result<(), FilterError> {
        let transitions = self.dynamics.transitions(dt)?;
        let mut cached = self.cached.take();
        let d = Discretization::for_step(
            &mut cached,
            (&self.a, &self.b, &self.q),
            &self.dynamics,
            period,
        )?;
        let n = self.a.nrows();
        for _ in 0..transitions {
            let count = self.len * noise.components().len();
            let work = &mut self.work;
            work.next
                .resize_with(work.next.len().max(count), || Component::zeros(n));
            let mut slots = work.next.iter_mut();
            for comp in &mut self.components[..self.len] {
                d.propagate(&mut comp.m, &mut comp.p, &mut work.moved);
                for c in noise.components() {
                    let slot = slots.next().expect("slots for every pair");
                    slot.w = comp.w * c.weight;
                    slot.m.copy_from(&comp.m);
                    slot.m += &c.mean;
                    slot.p.copy_from(&comp.p);
                    slot.p += &c.cov;
                    slot.refactor()?;
                }
            }
            core::mem::swap(&mut self.components, &mut work.next);
            self.len = count;
            self.reduce();
        }
        self.cached = cached;
        Ok(())
    }

    /// Predicts every component over `dt` (exact).
    fn propagate(&mut self, dt: f64) -> Result<(), FilterError> {
        if let crate::model::Dynamics::Discrete { period } = self.dynamics {
            if let Some(noise) = self.transition_noise.take() {
                // Taken out while the reduction borrows the filter, and put back.
                let split = self.split_transitions(&noise, period, dt);
                self.transition_noise = Some(noise);
                return split;
            }
        }
        let d = Discretization::for_step(
            &mut self.cached,
            (&self.a, &self.b, &self.q),
            &self.dynamics,
            dt,
        )?;
        for comp in &mut self.components[..self.len] {
            d.propagate(&mut comp.m, &mut comp.p, &mut self.work.moved);
            comp.refactor()?;
        }
        Ok(())
    }

    /// The Bayes update with the observed components of `z`, then the mixture reduction; the
    /// log-likelihood `ln Σ_ij w_i β_j N(z; C m_i + c + μ_j, C P_i Cᵀ + R_j)` (exact). A
    /// missing component (NaN) is taken out as in the Kalman filters: its row of C and its
    /// entries of c, z and every noise mean read 0, its rows and columns of every noise
    /// covariance those of the identity — the same update as with the observed rows alone
    /// (a constant factor in every pair's weight, which the normalisation removes). The
    /// masked model is made for each update with a missing component.
    fn assimilate(&mut self, z: &[f64]) -> Result<(), FilterError> {
        if z.iter().any(|v| Observation::is_missing(*v)) {
            let seen: Vec<bool> = z.iter().map(|v| !Observation::is_missing(*v)).collect();
            let mut c = self.c.clone();
            let mut c0 = self.c0.clone();
            for (i, seen) in seen.iter().enumerate() {
                if !seen {
                    c.row_mut(i).fill(0.0);
                    c0[i] = 0.0;
                }
            }
            let noise = GaussianMixture::new(
                self.noise
                    .components()
                    .iter()
                    .map(|v| {
                        let mut mean = v.mean.clone();
                        let mut cov = v.cov.clone();
                        for (i, seen) in seen.iter().enumerate() {
                            if !seen {
                                mean[i] = 0.0;
                                cov.row_mut(i).fill(0.0);
                                cov.column_mut(i).fill(0.0);
                                cov[(i, i)] = 1.0;
                            }
                        }
                        (v.weight, mean, cov)
                    })
                    .collect(),
            )
            .map_err(|_| FilterError::NotPositiveDefinite {
                what: "noise covariance of the observed components",
            })?;
            let z: Vec<f64> = z
                .iter()
                .map(|v| if Observation::is_missing(*v) { 0.0 } else { *v })
                .collect();
            let GaussianSum {
                components,
                len,
                work,
                ..
            } = self;
            let total = Self::update_with(components, len, work, (&c, &c0, &noise), &z)?;
            // A masked row's density is N(0; 0, 1): take its 1/√(2π) out again.
            let missing = seen.iter().filter(|s| !**s).count() as f64;
            self.log_likelihood = total + 0.5 * missing * crate::model::measurement::LN_TAU;
        } else {
            let GaussianSum {
                c,
                c0,
                noise,
                components,
                len,
                work,
                ..
            } = self;
            self.log_likelihood = Self::update_with(components, len, work, (c, c0, noise), z)?;
        }
        self.reduce();
        Ok(())
    }

    /// The Bayes update of every pair (component, noise component) with `z = C x + c + v`
    /// into the mixture's storage (`components`, `len`); returns the log of the weights'
    /// total before normalisation, `ln p(z | past)`.
    fn update_with(
        components: &mut Vec<Component>,
        len: &mut usize,
        work: &mut UpdateWork,
        (c, c0, noise): (&DMatrix<f64>, &DVector<f64>, &GaussianMixture),
        z: &[f64],
    ) -> Result<f64, FilterError> {
        let count = *len * noise.components().len();
        work.z.copy_from_slice(z);
        // The bank holds max(prior, cap) × J; more only when merges failed to keep the cap.
        let n = c.ncols();
        work.next
            .resize_with(work.next.len().max(count), || Component::zeros(n));
        let mut slots = work.next.iter_mut();
        for comp in &components[..*len] {
            // P Cᵀ = (C P)ᵀ, P being symmetric.
            work.cp.gemm(1.0, c, &comp.p, 0.0);
            work.pct.tr_copy_from(&work.cp);
            work.predicted.copy_from(c0);
            work.predicted.gemv(1.0, c, &comp.m, 1.0);
            for v in noise.components() {
                work.s.copy_from(&v.cov);
                work.s.gemm(1.0, c, &work.pct, 1.0);
                symmetrize(&mut work.s);
                let chol = cholesky_in(&mut work.s_factor, &work.s, "innovation covariance")?;
                work.nu.copy_from(&work.z);
                work.nu -= &work.predicted;
                work.nu -= &v.mean;
                // Kᵀ = S⁻¹ (P Cᵀ)ᵀ.
                work.gain_t.tr_copy_from(&work.pct);
                chol.solve_mut(&mut work.gain_t);
                let slot = slots.next().expect("slots for every pair");
                slot.m.copy_from(&comp.m);
                slot.m.gemv_tr(1.0, &work.gain_t, &work.nu, 1.0);
                // P − K S Kᵀ = P − (P Cᵀ) Kᵀ.
                slot.p.copy_from(&comp.p);
                slot.p.gemm(-1.0, &work.pct, &work.gain_t, 1.0);
                slot.refactor()?;
                // The log weight for now, normalised below.
                let l = chol.l_dirty();
                slot.w = libm::log(comp.w)
                    + libm::log(v.weight)
                    + gaussian_log_density_factored(l, log_det_from_factor(l), &mut work.nu);
                work.s_factor = chol.unpack_dirty();
            }
        }
        let next = &mut work.next[..count];
        let total = log_sum_exp(next.iter().map(|c| c.w));
        if !total.is_finite() {
            return Err(FilterError::MassLost);
        }
        for c in next.iter_mut() {
            c.w = libm::exp(c.w - total);
        }
        core::mem::swap(components, &mut work.next);
        *len = count;
        Ok(total)
    }

    /// Keeps the slots among the first `len` that `keep` says (in order) at the front;
    /// returns how many.
    fn compact(
        components: &mut [Component],
        mut keep: impl FnMut(usize, &Component) -> bool,
    ) -> usize {
        let mut kept = 0;
        for i in 0..components.len() {
            if keep(i, &components[i]) {
                components.swap(kept, i);
                kept += 1;
            }
        }
        kept
    }

    /// Pruning, then merging by Runnalls' cost (see the module doc).
    fn reduce(&mut self) {
        let GaussianSum {
            params,
            components,
            len,
            work,
            reduction,
            ..
        } = self;
        let comps = &mut components[..*len];
        let largest = comps.iter().map(|c| c.w).fold(0.0, f64::max);
        let before: f64 = comps.iter().map(|c| c.w).sum();
        *len = Self::compact(comps, |_, c| c.w >= params.prune * largest);
        let comps = &mut components[..*len];
        let kept: f64 = comps.iter().map(|c| c.w).sum();
        reduction.pruned_weight += before - kept;
        for c in comps.iter_mut() {
            c.w /= kept;
        }
        let k = comps.len();
        if k < 2 {
            return;
        }
        let (cost, alive, merged) = (&mut work.cost, &mut work.alive, &mut work.merged);
        cost.clear();
        cost.resize(k * k, f64::INFINITY);
        for i in 0..k {
            for j in i + 1..k {
                cost[i * k + j] = merge(&comps[i], &comps[j], merged);
            }
        }
        alive.clear();
        alive.resize(k, true);
        let mut count = k;
        while count > 1 {
            let (mut best, mut bi, mut bj) = (f64::INFINITY, 0, 0);
            for i in (0..k).filter(|&i| alive[i]) {
                for j in (i + 1..k).filter(|&j| alive[j]) {
                    if cost[i * k + j] < best {
                        (best, bi, bj) = (cost[i * k + j], i, j);
                    }
                }
            }
            let forced = count > params.max_components;
            if !(forced || best <= params.merge_cost) || !best.is_finite() {
                break;
            }
            if forced && best > params.merge_cost {
                reduction.forced_cost = reduction.forced_cost.max(best);
            }
            merge(&comps[bi], &comps[bj], merged);
            core::mem::swap(&mut comps[bi], merged);
            alive[bj] = false;
            count -= 1;
            for j in (0..k).filter(|&j| alive[j] && j != bi) {
                let (lo, hi) = (bi.min(j), bi.max(j));
                cost[lo * k + hi] = merge(&comps[lo], &comps[hi], merged);
            }
        }
        *len = Self::compact(comps, |i, _| alive[i]);
    }

    /// The filtering density at `x`.
    pub fn pdf(&self, x: &[f64]) -> f64 {
        let mut r = DVector::zeros(x.len());
        self.mixture()
            .iter()
            .map(|c| c.w * libm::exp(c.log_density(x, &mut r)))
            .sum()
    }

    /// The filtering density at every node of `grid`, into `out`.
    pub fn tabulate(&self, grid: &TensorGrid, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut r = DVector::zeros(grid.dim());
        for c in self.mixture() {
            grid.for_each_node(|idx, x| {
                out[idx] += c.w * libm::exp(c.log_density(x, &mut r));
            });
        }
    }

    /// The mixture's mean and covariance into `mean` (n) and `cov` (n × n), without
    /// allocating: `m = Σ w_i m_i`, `P = Σ w_i (P_i + (m_i − m)(m_i − m)ᵀ)`.
    fn mixture_moments_into(&self, mean: &mut DVector<f64>, cov: &mut DMatrix<f64>) {
        mean.fill(0.0);
        for c in self.mixture() {
            mean.axpy(c.w, &c.m, 1.0);
        }
        cov.fill(0.0);
        let n = mean.len();
        for c in self.mixture() {
            for b in 0..n {
                for a in 0..n {
                    let spread = (c.m[a] - mean[a]) * (c.m[b] - mean[b]);
                    cov[(a, b)] += c.w * (c.p[(a, b)] + spread);
                }
            }
        }
    }
}

/// The moment-preserving merge of two components into `out`, returning its Runnalls cost
/// (infinite when the merged covariance cannot be factored).
fn merge(a: &Component, b: &Component, out: &mut Component) -> f64 {
    let w = a.w + b.w;
    out.w = w;
    // The spread of the means first (in out.m), then the mean.
    out.m.copy_from(&a.m);
    out.m -= &b.m;
    out.p.copy_from(&a.p);
    out.p *= a.w;
    out.p.zip_apply(&b.p, |o, p| *o += p * b.w);
    out.p /= w;
    out.p.ger(a.w * b.w / (w * w), &out.m, &out.m, 1.0);
    out.m.copy_from(&a.m);
    out.m *= a.w;
    out.m.axpy(b.w, &b.m, 1.0);
    out.m /= w;
    match out.refactor() {
        Ok(()) => (0.5 * (w * out.log_det - a.w * a.log_det - b.w * b.log_det)).max(0.0),
        Err(_) => f64::INFINITY,
    }
}

impl Filter for GaussianSum {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, ObservationKind::Measurement, self.c.nrows())?;
        self.save();
        let stepped = (|| {
            if obs.dt > 0.0 {
                self.propagate(obs.dt)?;
            }
            match observed {
                Observed::Nothing => Ok(()),
                Observed::All | Observed::Some => self.assimilate(obs.value),
            }
        })();
        if stepped.is_err() {
            self.restore();
        }
        stepped
    }

    fn log_likelihood(&self) -> Option<f64> {
        Some(self.log_likelihood)
    }

    fn estimate(&self) -> Estimate {
        let mut out = Estimate::zeros(self.a.nrows());
        self.estimate_into(&mut out);
        out
    }

    fn estimate_into(&self, out: &mut Estimate) {
        let (mean, cov) = out.mean_and_covariance(self.a.nrows());
        self.mixture_moments_into(mean, cov);
    }

    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut one = alloc::vec![0.0; out.len()];
        let (a, b) = dims;
        for c in self.mixture() {
            let cov = [[c.p[(a, a)], c.p[(a, b)]], [c.p[(b, a)], c.p[(b, b)]]];
            marginal::gaussian_2d([c.m[a], c.m[b]], cov, xs, ys, &mut one);
            for (o, v) in out.iter_mut().zip(&one) {
                *o += c.w * v;
            }
        }
    }

    /// The mixture.
    fn state_law(&self) -> Result<crate::filters::predictive::StateLaw, FilterError> {
        Ok(crate::filters::predictive::StateLaw::GaussianSum(
            self.mixture()
                .iter()
                .map(|c| (c.w, c.m.clone(), c.p.clone()))
                .collect(),
        ))
    }

    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut one = alloc::vec![0.0; grid.len()];
        for c in self.mixture() {
            marginal::gaussian(c.m[dim], c.p[(dim, dim)], grid, &mut one);
            for (o, v) in out.iter_mut().zip(&one) {
                *o += c.w * v;
            }
        }
    }
}
