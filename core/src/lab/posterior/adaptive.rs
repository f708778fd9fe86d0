//! The adaptive random-walk proposal of one chain: Haario, Saksman & Tamminen (2001), "An
//! adaptive Metropolis algorithm", Bernoulli 7, 223–242, with a global scale tuned by
//! stochastic approximation (Andrieu & Thoms 2008, "A tutorial on adaptive MCMC", Statistics
//! and Computing 18, 343–373, Algorithm 4).
//!
//! A proposal is `u' = u + λ L z`, z ~ N(0, I_d), `L Lᵀ = s_d (C + ε I)`, `s_d = 2.38²/d`
//! (Haario et al. (2001), after Gelman, Roberts & Gilks (1996): the optimal scaling for a
//! Gaussian target of covariance C). C is the initial covariance for the first `t₀`
//! iterations, then the chain's own empirical covariance of all its states so far (their
//! running mean and sums of products, Welford's updates); ε I (ε = 10⁻¹⁰ of C's mean
//! diagonal) keeps it positive definite. λ starts at 1 and follows
//! `ln λ ← ln λ + t^{−0.6} (α_t − α*)`, α_t the acceptance probability of the t-th
//! proposal and α* the target rate (0.44 in one dimension, 0.234 in more: Roberts, Gelman &
//! Gilks 1997; Roberts & Rosenthal 2001).
//!
//! The same learning serves the Langevin proposal ([`Kind::Langevin`]), preconditioned by C.
//!
//! Adaptation runs during the warm-up only: the draws kept come from a fixed random-walk
//! kernel, so they are an ordinary Metropolis–Hastings chain whatever the adaptation did.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use crate::random::{standard_normal, SimRng};

/// Iterations before the empirical covariance replaces the initial one: `max(100, 10 d)`.
fn initial_period(d: usize) -> usize {
    (10 * d).max(100)
}

/// A random walk or a Langevin step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// `u' = u + λ L z`, `L Lᵀ = s_d C`, `s_d = 2.38²/d`, α* = 0.234 (0.44 in one dimension).
    RandomWalk,
    /// The Metropolis-adjusted Langevin algorithm (Roberts & Tweedie 1996, "Exponential
    /// convergence of Langevin distributions and their discrete approximations", Bernoulli 2,
    /// 341–363), preconditioned by C: `u' = u + ½ λ² L Lᵀ ∇ ln π(u) + λ L z`, `L Lᵀ = s_d C`,
    /// `s_d = 1.65²/d^{1/3}` and α* = 0.574 (Roberts & Rosenthal 1998, "Optimal scaling of
    /// discrete approximations to Langevin diffusions", JRSS B 60, 255–268).
    Langevin,
}

impl Kind {
    /// `s_d`.
    fn scale(self, d: usize) -> f64 {
        match self {
            Kind::RandomWalk => 2.38 * 2.38 / d as f64,
            Kind::Langevin => 1.65 * 1.65 / libm::cbrt(d as f64),
        }
    }
}

/// One chain's proposal and what it has learned.
#[derive(Clone, Debug)]
pub(super) struct Proposal {
    kind: Kind,
    d: usize,
    /// The Cholesky factor of `s_d C₀`, row-major lower triangle.
    initial: Vec<f64>,
    /// The factor in use, row-major lower triangle.
    factor: Vec<f64>,
    /// ln λ.
    log_scale: f64,
    /// States seen, their running mean and sums of products about it (row-major d × d).
    count: usize,
    mean: Vec<f64>,
    products: Vec<f64>,
    /// The target acceptance rate α*.
    target_rate: f64,
}

impl Proposal {
    /// A proposal of `kind` and dimension d with initial covariance `c0` (d × d row-major,
    /// positive definite).
    pub(super) fn new(kind: Kind, c0: &[f64], d: usize) -> Option<Self> {
        let factor = cholesky(c0, d, kind.scale(d))?;
        Some(Proposal {
            kind,
            d,
            initial: factor.clone(),
            factor,
            log_scale: 0.0,
            count: 0,
            mean: vec![0.0; d],
            products: vec![0.0; d * d],
            target_rate: match kind {
                Kind::RandomWalk if d == 1 => 0.44,
                Kind::RandomWalk => 0.234,
                Kind::Langevin => 0.574,
            },
        })
    }

    /// `L v`.
    fn times_factor(&self, v: &[f64]) -> Vec<f64> {
        (0..self.d)
            .map(|i| (0..=i).map(|j| self.factor[i * self.d + j] * v[j]).sum())
            .collect()
    }

    /// The Langevin step's mean from u with gradient g: `u + ½ λ² L Lᵀ g`.
    fn langevin_mean(&self, u: &[f64], g: &[f64]) -> Vec<f64> {
        let d = self.d;
        let lt_g: Vec<f64> = (0..d)
            .map(|j| (j..d).map(|i| self.factor[i * d + j] * g[i]).sum())
            .collect();
        let drift = self.times_factor(&lt_g);
        let h = libm::exp(2.0 * self.log_scale);
        u.iter().zip(drift).map(|(a, b)| a + 0.5 * h * b).collect()
    }

    /// A Langevin proposal from u with gradient g.
    pub(super) fn propose_langevin(&self, u: &[f64], g: &[f64], rng: &mut SimRng) -> Vec<f64> {
        let z: Vec<f64> = (0..self.d).map(|_| standard_normal(rng)).collect();
        let scale = libm::exp(self.log_scale);
        self.langevin_mean(u, g)
            .iter()
            .zip(self.times_factor(&z))
            .map(|(m, s)| m + scale * s)
            .collect()
    }

    /// `ln q(to | from)` of the Langevin proposal up to its constant (the same both ways):
    /// `−|L⁻¹(to − mean(from))|² / (2 λ²)`.
    pub(super) fn langevin_log_density(&self, from: &[f64], g: &[f64], to: &[f64]) -> f64 {
        let d = self.d;
        let r: Vec<f64> = to
            .iter()
            .zip(self.langevin_mean(from, g))
            .map(|(t, m)| t - m)
            .collect();
        // Forward substitution L y = r.
        let mut y = vec![0.0; d];
        for i in 0..d {
            let known: f64 = (0..i).map(|j| self.factor[i * d + j] * y[j]).sum();
            y[i] = (r[i] - known) / self.factor[i * d + i];
        }
        let h = libm::exp(2.0 * self.log_scale);
        -y.iter().map(|v| v * v).sum::<f64>() / (2.0 * h)
    }

    /// A proposal from `u`.
    pub(super) fn propose(&self, u: &[f64], rng: &mut SimRng) -> Vec<f64> {
        let z: Vec<f64> = (0..self.d).map(|_| standard_normal(rng)).collect();
        let scale = libm::exp(self.log_scale);
        (0..self.d)
            .map(|i| {
                let step: f64 = (0..=i).map(|j| self.factor[i * self.d + j] * z[j]).sum();
                u[i] + scale * step
            })
            .collect()
    }

    /// Learns from the t-th iteration (t ≥ 1): the state the chain is in after it and the
    /// acceptance probability of its proposal.
    pub(super) fn adapt(&mut self, t: usize, state: &[f64], acceptance: f64) {
        let d = self.d;
        self.log_scale += libm::pow(t as f64, -0.6) * (acceptance - self.target_rate);
        self.log_scale = self.log_scale.clamp(-20.0, 20.0);
        // Welford: mean and sums of products about it.
        self.count += 1;
        let n = self.count as f64;
        let delta: Vec<f64> = state.iter().zip(&self.mean).map(|(x, m)| x - m).collect();
        for (m, dx) in self.mean.iter_mut().zip(&delta) {
            *m += dx / n;
        }
        for (row, di) in self.products.chunks_mut(d).zip(&delta) {
            for ((p, x), m) in row.iter_mut().zip(state).zip(&self.mean) {
                *p += di * (x - m);
            }
        }
        if self.count >= initial_period(d) {
            let covariance: Vec<f64> = self.products.iter().map(|p| p / (n - 1.0)).collect();
            let trace: f64 = (0..d).map(|i| covariance[i * d + i]).sum::<f64>() / d as f64;
            let mut regular = covariance;
            for i in 0..d {
                regular[i * d + i] += 1e-10 * trace.max(f64::MIN_POSITIVE);
            }
            // A chain that has not moved yet keeps its initial factor.
            self.factor = cholesky(&regular, d, self.kind.scale(d)).unwrap_or(self.initial.clone());
        }
    }

    /// The scale λ reached.
    pub(super) fn scale(&self) -> f64 {
        libm::exp(self.log_scale)
    }
}

/// The lower Cholesky factor of `s c` (d × d row-major), `None` unless positive definite with
/// finite entries.
fn cholesky(c: &[f64], d: usize, s: f64) -> Option<Vec<f64>> {
    if c.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let m = DMatrix::from_row_slice(d, d, c) * s;
    let l = m.cholesky()?.l();
    Some((0..d * d).map(|k| l[(k / d, k % d)]).collect())
}
