//! 002 Algorithm 2, the direct method as a [`Filter`] (1-D; the ODE part is n-dimensional).
//!
//! For a Yau filtering system (C1)–(C3) with Q = I and S = I, `f = l + F′` with l affine
//! (the `linear` parameter, 0 by default, which makes `F = ∫ f`), and
//! `q = ½(l² − l′ − η)`, `η = f² + f′ + h²` (7), (33) is then the quadratic `Qx² + px + r`
//! whose coefficients come from the check of (C1)–(C3) in [`crate::diagnostics::yau_system`]
//! (numerical on the domain; a model that fails is refused with that report). Per observation
//! interval:
//!
//! 1. decompose û (the density times `e^{−F}`, (30)–(31)) with the Gaussian approximation of
//!    Algorithm 1;
//! 2. carry every Gaussian through (32) by the Riccati ODEs (35)–(37), and — a deviation
//!    from the paper, whose Algorithm 1 drops it — the residual that Algorithm 1 leaves below
//!    α·max with the zeroth-order factor `e^{q(x)Δt}` of (32) only (an O(Δt) error; dropping
//!    it at every step made the MSE grow as Δt shrank, docs/reproduction.md, "002 Tables 3 and 4");
//! 3. recombine and apply the observation factor `exp(Δyᵀh)` (30), in the log domain with one
//!    common shift so that nothing overflows; negative values of the recombined sum (from the
//!    negative terms) are set to zero;
//! 4. the density is `e^{F} û` (31), normalised on the grid, whose moments give the estimate.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::gaussian_approximation::Decomposition;
use super::riccati::{propagate_scalar_term, KolmogorovCoefficients};
use super::DirectParams;
use crate::diagnostics::yau_system::{self, Affine};
use crate::error::FilterError;
use crate::filters::{Estimate, Filter, Observation, ObservationKind, Observed};
use crate::grid::TensorGrid;
use crate::model::dmz::PartialIncrements;
use crate::model::{Model, ObservationModel};

/// The direct method's self-check threshold: the share `Σ|r| / Σ|û|` of û that Algorithm 1
/// leaves to the residual r, which is carried over the interval with the zeroth-order factor
/// `e^{q(x)Δt}` only (an O(Δt) error from the neglected diffusion and drift, see the module
/// doc). Measured on `direct-4.3` (10 runs, Δt = 0.1), largest share over the run → the
/// direct method's MSE against QIEM's 0.181: α = 0.01 (the default) 0.022 → 0.174, α = 0.1
/// 0.21 → 0.174, α = 0.2 0.36 → 0.178, α = 0.4 0.47 → 0.187; `direct-4.4` (Δt = 10⁻³) 0.020.
/// Above a quarter the first-order carry starts to cost accuracy.
pub(crate) const RESIDUAL_SHARE_THRESHOLD: f64 = 0.25;

/// The direct method of 002.
///
/// The direct method of 002 for Yau filtering systems. Built: the Gaussian
/// approximation of Algorithm 1 (`gaussian_approximation`) and the Riccati ODEs (35)–(37)
/// that carry one Gaussian through the Kolmogorov equation (32) (`riccati`), and the filter
/// of Algorithm 2 with its (C2)/(C3) check and the transformations (29)–(31) (`filter.rs`).
///
/// # When it fails
///
/// Only Yau filtering systems are taken: a model outside the conditions (C1)–(C3) of 002 is
/// refused at construction with the condition that fails ([`crate::diagnostics`] decides them).
/// Within them, when Algorithm 1 leaves a large share of the density in its residual (the
/// Gaussians no longer hold it), the self-check says so ([`crate::Filter::self_check`]).
#[derive(Clone, Debug)]
pub struct Direct {
    name: String,
    grid: TensorGrid,
    params: DirectParams,
    /// The coefficients of (32) over an interval with its increment, and without the
    /// observation's −½Σh² (a gap, or the missing components' share of it).
    coefficients: [KolmogorovCoefficients; 2],
    /// The observation factor's terms for increments with some components missing.
    partial: PartialIncrements,
    /// F at the grid nodes.
    potential: Vec<f64>,
    /// h at the grid nodes, per component.
    h: Vec<Vec<f64>>,
    /// û at the grid nodes (largest value 1).
    u_hat: Vec<f64>,
    /// The normalised density e^{F} û.
    density: Vec<f64>,
    estimate: Estimate,
    /// Storage of the estimate's moments.
    moments: crate::grid::Moments,
    terms: usize,
    /// Σ|residual| / Σ|û| of the last decomposition (the self-check).
    residual_share: f64,
    /// The grid's node coordinates.
    nodes: Vec<f64>,
    work: StepWork,
    /// What a step starts from: û and the estimate, the density, the terms and the share.
    saved: (crate::filters::SavedDensity, Vec<f64>, usize, f64, f64),
    /// `ln ∫ e^{F} û`, the mass of the density û stands for (û is kept scaled to a largest
    /// value of 1; the scale is this).
    log_mass: f64,
    /// The last step's log-likelihood ([`Filter::log_likelihood`]).
    log_likelihood: f64,
}

/// Storage of a step, made once (a step allocates nothing).
#[derive(Clone, Debug)]
struct StepWork {
    decomposition: Decomposition,
    /// The observation factor's exponent at every node: Δyᵀh (30), or with components
    /// missing `Δy_Oᵀh_O − ½|h_O|²Δτ` (0 for a gap).
    factor: Vec<f64>,
    /// Every propagated term: (sign, a, b, c) of `± exp(a x² + b x + c)`.
    quadratics: Vec<(f64, f64, f64, f64)>,
    /// The nodes where each term can matter.
    windows: Vec<(usize, usize)>,
    /// The log of the carried residual, then of the density.
    log: Vec<f64>,
}

/// The model fits the direct method as 002 writes it: continuous observations, G = I, S = I.
pub(crate) fn check_model(model: &Model) -> Result<(), FilterError> {
    let ObservationModel::Continuous { noise_cov } = &model.observations else {
        return Err(FilterError::Unsuitable(
            "the direct method needs continuous observations dy = h dt + dw".into(),
        ));
    };
    let q = model.process_noise();
    let q = q.require_constant(
        "the direct method of 002",
        "its Gaussian approximation and Riccati ODEs (002 (7)–(12)) are derived for dx = f dt + dv",
    )?;
    let identity = |m: &DMatrix<f64>| (m - DMatrix::identity(m.nrows(), m.ncols())).amax() < 1e-12;
    if !identity(noise_cov) || !identity(q) {
        return Err(FilterError::Unsuitable(
            "the direct method of 002 is written for G = I and S = I".into(),
        ));
    }
    Ok(())
}

/// The (C1)–(C3) check of [`crate::diagnostics::yau_system`] with the given 1-D
/// `l = slope · x + offset`: the Kolmogorov quadratic `q(x) = Q x² + p x + r` of (32),
/// `q = ½(l² − l′ − η)`, and that of an interval without an observation, `q + ½Σh²` (η of
/// (7) without its Σh², quadratic since (C2) makes Σh² so) — or the report of the failing
/// conditions.
fn kolmogorov_quadratic(
    model: &Model,
    bounds: &[(f64, f64)],
    linear: [f64; 2],
) -> Result<[[f64; 3]; 2], FilterError> {
    let [slope, offset] = linear;
    let l = Affine {
        d_mat: DMatrix::from_element(1, 1, slope),
        d_vec: DVector::from_element(1, offset),
    };
    let system = yau_system::check(model, bounds, Some(&l));
    if let Some(message) = system.failure() {
        return Err(FilterError::Unsuitable(message));
    }
    let (eta, h2) = (
        system.eta.expect("(C3) holds"),
        system.sum_h2.expect("(C2) holds"),
    );
    let q = [
        0.5 * (slope * slope - eta.a[(0, 0)]),
        0.5 * (2.0 * slope * offset - eta.b[0]),
        0.5 * (offset * offset - slope - eta.c),
    ];
    let without_h2 = [
        q[0] + 0.5 * h2.a[(0, 0)],
        q[1] + 0.5 * h2.b[0],
        q[2] + 0.5 * h2.c,
    ];
    Ok([q, without_h2])
}

/// Whether the direct method applies to `model` on `bounds` with `params` — the model checks
/// and (C1)–(C3) — without building anything else.
pub(crate) fn check_system(
    model: &Model,
    params: &DirectParams,
    bounds: &[(f64, f64)],
) -> Result<(), FilterError> {
    check_model(model)?;
    kolmogorov_quadratic(model, bounds, params.linear).map(|_| ())
}

impl Direct {
    /// Checks (C1)–(C3) on the domain, tabulates F and the prior.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &DirectParams,
    ) -> Result<Self, FilterError> {
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        if let Some((field, msg)) = params.problems(model.n).into_iter().next() {
            return Err(FilterError::Unsuitable(format!("{name} {field}: {msg}")));
        }
        check_model(model)?;
        let grid = TensorGrid::new(bounds, &[params.points])
            .map_err(|e| FilterError::Unsuitable(format!("{e}")))?;
        let x: Vec<f64> = (0..params.points).map(|i| grid.coordinate(0, i)).collect();
        let dx = grid.spacing()[0];
        let [slope, offset] = params.linear;
        let [full, without_h2] = kolmogorov_quadratic(model, bounds, params.linear)?;
        let (mut fv, mut hv) = ([0.0], vec![0.0; model.m]);
        let mut h = vec![Vec::with_capacity(x.len()); model.m];
        let mut rest = Vec::with_capacity(x.len());
        for &xi in &x {
            model.drift.eval(&[xi], &mut fv);
            model.observation.eval(&[xi], &mut hv);
            for (c, v) in h.iter_mut().zip(&hv) {
                c.push(*v);
            }
            rest.push(fv[0] - slope * xi - offset);
        }
        if rest
            .iter()
            .chain(h.iter().flatten())
            .any(|v| !v.is_finite())
        {
            return Err(FilterError::Unsuitable(
                "f or h is not finite on the domain; shrink it".into(),
            ));
        }
        // F = ∫ (f − l) from the first node, by the trapezoidal rule.
        let mut potential = vec![0.0; x.len()];
        for i in 1..x.len() {
            potential[i] = potential[i - 1] + 0.5 * dx * (rest[i - 1] + rest[i]);
        }
        let coefficients = |[qq, p, r]: [f64; 3]| KolmogorovCoefficients {
            d_mat: DMatrix::from_element(1, 1, slope),
            d_vec: DVector::from_element(1, offset),
            q: DMatrix::from_element(1, 1, qq),
            p: DVector::from_element(1, p),
            r,
        };
        let log_u: Vec<f64> = x
            .iter()
            .zip(&potential)
            .map(|(&xi, &big_f)| libm::log(prior.density(&[xi])) - big_f)
            .collect();
        let mut filter = Direct {
            name,
            params: params.clone(),
            coefficients: [coefficients(full), coefficients(without_h2)],
            partial: PartialIncrements::new(DMatrix::identity(model.m, model.m)),
            potential,
            h,
            u_hat: vec![0.0; x.len()],
            density: vec![0.0; x.len()],
            work: StepWork {
                decomposition: Decomposition::with_capacity(x.len(), params.max_terms),
                factor: vec![0.0; x.len()],
                quadratics: Vec::with_capacity(params.max_terms),
                windows: Vec::with_capacity(params.max_terms),
                log: vec![0.0; x.len()],
            },
            estimate: Estimate {
                mean: DVector::zeros(1),
                covariance: None,
                map: None,
            },
            moments: crate::grid::Moments::zeros(1),
            terms: 0,
            residual_share: 0.0,
            saved: (
                crate::filters::SavedDensity::new(x.len(), &Estimate::zeros(1)),
                vec![0.0; x.len()],
                0,
                0.0,
                0.0,
            ),
            log_mass: 0.0,
            log_likelihood: 0.0,
            nodes: x,
            grid,
        };
        exp_shifted(&log_u, &mut filter.u_hat);
        filter.refresh()?;
        Ok(filter)
    }

    /// Gaussians in the last decomposition.
    pub fn terms(&self) -> usize {
        self.terms
    }

    /// The density `e^{F} û` normalised on the grid, and the estimate; records the mass
    /// `e^{F} û` had.
    fn refresh(&mut self) -> Result<(), FilterError> {
        for ((l, &u), &big_f) in self
            .work
            .log
            .iter_mut()
            .zip(&self.u_hat)
            .zip(&self.potential)
        {
            *l = if u > 0.0 {
                libm::log(u) + big_f
            } else {
                f64::NEG_INFINITY
            };
        }
        let shift = exp_shifted(&self.work.log, &mut self.density);
        crate::filters::normalise_on_grid(
            &self.grid,
            &mut self.density,
            &mut self.moments,
            &mut self.estimate,
        )?;
        self.log_mass = libm::log(self.moments.mass) + shift;
        Ok(())
    }
}

/// `out = exp(log − max log)` (all zero when no value is finite); returns the shift.
fn exp_shifted(log: &[f64], out: &mut [f64]) -> f64 {
    let shift = log.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    for (o, &v) in out.iter_mut().zip(log) {
        *o = if shift.is_finite() {
            libm::exp(v - shift)
        } else {
            0.0
        };
    }
    shift
}

impl Direct {
    /// One interval of Algorithm 2 with a checked increment over Δτ > 0 (it may fail
    /// half-way). With every component observed, (32) carries η's Σh² and the factor is
    /// `exp(Δyᵀh)` (30); otherwise (32) carries no observation term and the factor is the
    /// observed components' likelihood `exp(Δy_Oᵀh_O − ½|h_O|²Δτ)` (S = I) — exact for a gap,
    /// and for a partial increment the splitting of the in-update form (first order in Δτ).
    /// Returns the step's log-likelihood: with every component observed, the logarithm of
    /// the mass of `e^{F} û` after the interval against before it — (32) carries the
    /// increment's −½|h|²Δτ with η and the factor is `exp(Δyᵀh)`, so the ratio is the
    /// normaliser of the interval; with some missing, the factor's normaliser against the
    /// predicted density's mass (the same sum without the factor); 0 for a gap.
    fn advance(&mut self, obs: &Observation, observed: Observed) -> Result<f64, FilterError> {
        let before = self.log_mass;
        let len = self.u_hat.len();
        let StepWork {
            decomposition,
            factor,
            quadratics,
            windows,
            log: carried,
        } = &mut self.work;
        let x = &self.nodes;
        decomposition.run(x, &self.u_hat, self.params.alpha, self.params.max_terms);
        let (terms, residual) = (&decomposition.terms, &decomposition.residual);
        self.terms = terms.len();
        let mass: f64 = self.u_hat.iter().map(|u| u.abs()).sum();
        self.residual_share =
            residual.iter().map(|r| r.abs()).sum::<f64>() / mass.max(f64::MIN_POSITIVE);
        if terms.is_empty() {
            return Err(FilterError::MassLost);
        }
        // Exponents of every propagated term plus the observation factor, one common shift.
        let k = &self.coefficients[usize::from(observed != Observed::All)];
        match observed {
            Observed::All => {
                for (j, g) in factor.iter_mut().enumerate() {
                    *g = obs.value.iter().zip(&self.h).map(|(y, h)| y * h[j]).sum();
                }
            }
            Observed::Some => {
                let t = self.partial.terms(&self.h, obs.value)?;
                for (j, g) in factor.iter_mut().enumerate() {
                    let fit: f64 = t.dy.iter().zip(t.gain).map(|(y, h)| y * h[j]).sum();
                    *g = fit - t.half[j] * obs.dt;
                }
            }
            Observed::Nothing => factor.iter_mut().for_each(|g| *g = 0.0),
        }
        quadratics.clear();
        for t in terms {
            let [a, b, c] = propagate_scalar_term(t, k, obs.dt, self.params.substeps);
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                return Err(FilterError::NonFinite {
                    what: "Riccati solution",
                });
            }
            quadratics.push((t.weight.signum(), a, b, c));
        }
        // Each term only where it can matter: with Q its peak, G = max g and L ≤ shift a value
        // actually reached, a node where q − Q < −(800 + Q + G − L) has exponent below
        // shift − 800, where exp underflows to 0 anyway — the same sums as over the whole grid.
        let (x0, h) = (x[0], self.grid.spacing()[0]);
        let node = |v: f64| ((v - x0) / h).clamp(0.0, (len - 1) as f64);
        let factor = &*factor;
        let value = |(_, a, b, c): (f64, f64, f64, f64), j: usize| {
            a * x[j] * x[j] + b * x[j] + c + factor[j]
        };
        let peak = |(_, a, b, c): (f64, f64, f64, f64)| {
            (a < 0.0).then(|| (-b / (2.0 * a), c - b * b / (4.0 * a)))
        };
        let g_max = factor.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lower = quadratics
            .iter()
            .map(|&q| {
                let j = peak(q).map_or(0, |(centre, _)| libm::round(node(centre)) as usize);
                value(q, j)
            })
            .fold(f64::NEG_INFINITY, f64::max);
        windows.clear();
        windows.extend(quadratics.iter().map(|&q| match peak(q) {
            Some((centre, top)) => {
                let reach = libm::sqrt((800.0 + top + g_max - lower) / -q.1);
                if reach.is_finite() {
                    let from = libm::floor(node(centre - reach)) as usize;
                    let to = libm::ceil(node(centre + reach)) as usize + 1;
                    (from, to.min(len))
                } else {
                    (0, len)
                }
            }
            None => (0, len),
        }));
        let (qq, qp, qr) = (k.q[(0, 0)], k.p[0], k.r);
        for (((e, &r), &g), &xj) in carried.iter_mut().zip(residual).zip(factor).zip(x) {
            *e = if r != 0.0 {
                libm::log(r.abs()) + g + (qq * xj * xj + qp * xj + qr) * obs.dt
            } else {
                f64::NEG_INFINITY
            };
        }
        let mut shift = carried.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        for (&q, &(from, to)) in quadratics.iter().zip(windows.iter()) {
            shift = (from..to).map(|j| value(q, j)).fold(shift, f64::max);
        }
        for ((u, &r), &e) in self.u_hat.iter_mut().zip(residual).zip(carried.iter()) {
            *u = if e > f64::NEG_INFINITY {
                r.signum() * crate::linalg::exp_nonpositive(e - shift)
            } else {
                0.0
            };
        }
        for (&q, &(from, to)) in quadratics.iter().zip(windows.iter()) {
            for j in from..to {
                self.u_hat[j] += q.0 * crate::linalg::exp_nonpositive(value(q, j) - shift);
            }
        }
        self.u_hat.iter_mut().for_each(|u| *u = u.max(0.0));
        let top = self.u_hat.iter().copied().fold(0.0, f64::max);
        if top <= 0.0 || !top.is_finite() {
            return Err(FilterError::MassLost);
        }
        self.u_hat.iter_mut().for_each(|u| *u /= top);
        // With some components missing, ln ∫ e^{F} û e^{−g}: the predicted density's mass in
        // the units of û (every node's exponent carried its factor g).
        let predicted = (observed == Observed::Some).then(|| {
            let exponent =
                |(u, (f, g)): (&f64, (&f64, &f64))| (*u > 0.0).then(|| libm::log(*u) + f - g);
            let nodes = || {
                self.u_hat
                    .iter()
                    .zip(self.potential.iter().zip(factor.iter()))
            };
            let top = nodes()
                .filter_map(exponent)
                .fold(f64::NEG_INFINITY, f64::max);
            let sum: f64 = nodes()
                .filter_map(exponent)
                .map(|e| libm::exp(e - top))
                .sum();
            libm::log(sum * self.grid.cell_volume()) + top
        });
        self.refresh()?;
        Ok(match (observed, predicted) {
            (Observed::Nothing, _) => 0.0,
            (_, Some(predicted)) => self.log_mass - predicted,
            (_, None) => self.log_mass + libm::log(top) + shift - before,
        })
    }
}

impl Filter for Direct {
    crate::filters::kept_estimate_accessors!(density in density);

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, ObservationKind::Increment, self.h.len())?;
        if obs.dt <= 0.0 {
            self.log_likelihood = 0.0;
            return Ok(());
        }
        let (saved, density, terms, share, log_mass) = &mut self.saved;
        saved.save(&self.u_hat, &self.estimate);
        density.copy_from_slice(&self.density);
        (*terms, *share, *log_mass) = (self.terms, self.residual_share, self.log_mass);
        match self.advance(obs, observed) {
            Ok(log_likelihood) => {
                self.log_likelihood = log_likelihood;
                Ok(())
            }
            Err(e) => {
                let (saved, density, terms, share, log_mass) = &self.saved;
                saved.restore(&mut self.u_hat, &mut self.estimate);
                self.density.copy_from_slice(density);
                (self.terms, self.residual_share, self.log_mass) = (*terms, *share, *log_mass);
                Err(e)
            }
        }
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        if self.residual_share > RESIDUAL_SHARE_THRESHOLD {
            out.push(crate::filters::Concern::above(
                "share of û left to Algorithm 1's residual (carried with e^{qΔt} only)",
                self.residual_share,
                RESIDUAL_SHARE_THRESHOLD,
                "the Gaussian approximation leaves much of the density to the residual, whose propagation neglects diffusion and drift: lower alpha or raise max_terms",
            ));
        }
    }
}
