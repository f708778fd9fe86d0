//! The coefficients of the robust DMZ (Kolmogorov) equation at a set of points: the drift f,
//! its divergence ∇·f, `S⁻¹h` for the observation factor and `½ hᵀS⁻¹h` for the potential
//! (000 (2)–(4), 004 (17)). The grid filters of 000 tabulate them on their grid nodes, the
//! spectral filter of 004 on its quadrature nodes.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use serde::{Deserialize, Serialize};

use super::{Model, ObservationModel};
use crate::error::FilterError;

/// Where the `−½ hᵀS⁻¹h` term of the potential (4) is applied.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LikelihoodPlacement {
    /// In the update, with 000 (15) / 004 (42): `exp(Δyᵀ S⁻¹ h − ½ hᵀ S⁻¹ h Δτ)`, the Gaussian
    /// likelihood of the increment (bounded, so round-off far out in the domain cannot be
    /// amplified by `exp(Δyᵀ S⁻¹ h)` for steep h) — the same Lie splitting of the same
    /// equation, first order in Δτ either way.
    #[default]
    InUpdate,
    /// In the operator's potential, as 000 (2)–(4) and 004 (17) write it.
    InOperator,
}

/// f, ∇·f, S⁻¹h and ½hᵀS⁻¹h at `len` points.
#[derive(Clone, Debug)]
pub(crate) struct DmzCoefficients {
    /// `f[d][i] = f_d(x_i)`.
    pub f: Vec<Vec<f64>>,
    /// `∇·f(x_i)`.
    pub div_f: Vec<f64>,
    /// `s_inv_h[j][i] = (S⁻¹ h(x_i))_j`.
    pub s_inv_h: Vec<Vec<f64>>,
    /// `½ hᵀS⁻¹h(x_i)`.
    pub half_hsh: Vec<f64>,
}

/// S⁻¹ of a continuous observation model; refuses discrete observations (`who` names the
/// method, plural: "the Yau–Yau filters need …").
pub(crate) fn continuous_noise_inverse(
    model: &Model,
    who: &str,
) -> Result<DMatrix<f64>, FilterError> {
    let ObservationModel::Continuous { noise_cov } = &model.observations else {
        return Err(FilterError::Unsuitable(alloc::format!(
            "{who} need continuous observations dy = h dt + dw"
        )));
    };
    noise_cov
        .clone()
        .try_inverse()
        .ok_or(FilterError::NotPositiveDefinite {
            what: "observation noise covariance",
        })
}

impl DmzCoefficients {
    /// Evaluates the model at `len` points; `point(i, x)` writes point i into x. Non-finite
    /// values are refused with a message naming `who`.
    pub(crate) fn tabulate(
        model: &Model,
        who: &str,
        len: usize,
        mut point: impl FnMut(usize, &mut [f64]),
    ) -> Result<Self, FilterError> {
        let (n, m) = (model.n, model.m);
        let s_inv = continuous_noise_inverse(model, who)?;
        let mut out = DmzCoefficients {
            f: vec![vec![0.0; len]; n],
            div_f: vec![0.0; len],
            s_inv_h: vec![vec![0.0; len]; m],
            half_hsh: vec![0.0; len],
        };
        // Chunks of nodes as structure of arrays, f, ∂f and h over each chunk at once.
        const CHUNK: usize = 4096;
        let c = CHUNK.min(len);
        let mut x = vec![0.0; n];
        let (mut points, mut f) = (vec![0.0; n * c], vec![0.0; n * c]);
        let (mut jac, mut h) = (vec![0.0; n * n * c], vec![0.0; m * c]);
        let mut scratch = crate::model::BatchScratch::default();
        for start in (0..len).step_by(CHUNK) {
            let k = CHUNK.min(len - start);
            for p in 0..k {
                point(start + p, &mut x);
                for (j, v) in x.iter().enumerate() {
                    points[j * k + p] = *v;
                }
            }
            let (points, f) = (&points[..n * k], &mut f[..n * k]);
            let (jac, h) = (&mut jac[..n * n * k], &mut h[..m * k]);
            model.drift.eval_batch(points, f, &mut scratch);
            model.drift.jacobian_batch(points, jac, &mut scratch);
            model.observation.eval_batch(points, h, &mut scratch);
            for (j, column) in out.f.iter_mut().enumerate() {
                column[start..start + k].copy_from_slice(&f[j * k..(j + 1) * k]);
            }
            for p in 0..k {
                let i = start + p;
                out.div_f[i] = (0..n).map(|d| jac[(d * n + d) * k + p]).sum();
                let mut hsh = 0.0;
                for a in 0..m {
                    let sh: f64 = (0..m).map(|b| s_inv[(a, b)] * h[b * k + p]).sum();
                    out.s_inv_h[a][i] = sh;
                    hsh += h[a * k + p] * sh;
                }
                out.half_hsh[i] = 0.5 * hsh;
            }
        }
        let values = out
            .f
            .iter()
            .chain(&out.s_inv_h)
            .flatten()
            .chain(&out.div_f)
            .chain(&out.half_hsh);
        if values.into_iter().any(|v| !v.is_finite()) {
            return Err(FilterError::Unsuitable(alloc::format!(
                "{who}: f, ∇·f or h is not finite somewhere on the domain; shrink the domain"
            )));
        }
        Ok(out)
    }
}

/// How many patterns of missing components [`PartialIncrements`] keeps (the most recently used).
pub(crate) const PARTIAL_PATTERNS: usize = 8;

/// The likelihood terms of an increment of which only some components are observed (the
/// others NaN): with O the observed components, `dy_O ~ N(h_O Δτ, S_OO Δτ)` given the state,
/// so the factor of 000 (15) / 004 (42) becomes
/// `exp(Δy_Oᵀ S_OO⁻¹ h_O − ½ h_Oᵀ S_OO⁻¹ h_O Δτ)` — only the observed rows of h and S, with the
/// correlation of the missing components with the observed ones accounted for by taking the
/// marginal S_OO (not by dropping rows of S⁻¹).
#[derive(Clone, Debug)]
pub(crate) struct PartialIncrements {
    noise_cov: DMatrix<f64>,
    /// The patterns met so far, the most recently used first.
    parts: Vec<Pattern>,
    /// The observed components of the last increment, in order.
    values: Vec<f64>,
}

/// One pattern of observed components and its terms.
#[derive(Clone, Debug)]
struct Pattern {
    /// Which components are observed.
    observed: Vec<bool>,
    /// `gain[j][i] = (S_OO⁻¹ h_O(x_i))_j`.
    gain: Vec<Vec<f64>>,
    /// `half[i] = ½ h_Oᵀ S_OO⁻¹ h_O(x_i)`.
    half: Vec<f64>,
}

/// The terms of the observation factor of one increment: its observed components, with
/// `S_OO⁻¹ h_O` and `½ h_Oᵀ S_OO⁻¹ h_O` at every point (see [`PartialIncrements::terms`]; for a
/// whole increment, `S⁻¹h` and `½ hᵀS⁻¹h`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ObservedTerms<'a> {
    /// `Δy_O`, the observed components in order.
    pub dy: &'a [f64],
    /// `(S_OO⁻¹ h_O)_j` at every point, one row per observed component.
    pub gain: &'a [Vec<f64>],
    /// `½ h_Oᵀ S_OO⁻¹ h_O` at every point.
    pub half: &'a [f64],
}

impl ObservedTerms<'_> {
    /// The factor's exponent at every point, `out_i = Σ_j Δy_j gain_j(x_i) − scale · half(x_i)`
    /// (`scale` is Δτ, or the number of intervals when `half` already holds `½hᵀS⁻¹h T₀`).
    pub(crate) fn exponents(&self, scale: f64, out: &mut [f64]) {
        for (a, h) in out.iter_mut().zip(self.half) {
            *a = -scale * h;
        }
        for (y, g) in self.dy.iter().zip(self.gain) {
            for (a, h) in out.iter_mut().zip(g) {
                *a += y * h;
            }
        }
    }
}

impl PartialIncrements {
    /// For the observation noise covariance S (positive definite).
    pub(crate) fn new(noise_cov: DMatrix<f64>) -> Self {
        PartialIncrements {
            noise_cov,
            parts: Vec::new(),
            values: Vec::new(),
        }
    }

    /// For `model`'s continuous observations; refuses discrete ones (`who` names the method,
    /// plural, as in [`continuous_noise_inverse`]).
    pub(crate) fn of(model: &Model, who: &str) -> Result<Self, FilterError> {
        match &model.observations {
            ObservationModel::Continuous { noise_cov } => Ok(Self::new(noise_cov.clone())),
            ObservationModel::Discrete { .. } => Err(FilterError::Unsuitable(alloc::format!(
                "{who} need continuous observations dy = h dt + dw"
            ))),
        }
    }

    /// The terms for the pattern of missing components (NaN) of `dy`, from `S⁻¹h` at the points
    /// (`s_inv_h[j][i]`, as [`DmzCoefficients`] tabulates it): made the first time the pattern
    /// occurs (h is recovered as `S (S⁻¹h)`), kept among the last [`PARTIAL_PATTERNS`].
    pub(crate) fn terms(
        &mut self,
        s_inv_h: &[Vec<f64>],
        dy: &[f64],
    ) -> Result<ObservedTerms<'_>, FilterError> {
        let same = |p: &Pattern| p.observed.iter().zip(dy).all(|(&o, v)| o != v.is_nan());
        let i = match self.parts.iter().position(same) {
            Some(i) => i,
            None => {
                let pattern: Vec<bool> = dy.iter().map(|v| !v.is_nan()).collect();
                let part = self.make(s_inv_h, pattern)?;
                self.parts.truncate(PARTIAL_PATTERNS - 1);
                self.parts.insert(0, part);
                0
            }
        };
        self.parts[..=i].rotate_right(1);
        self.values.clear();
        self.values
            .extend(dy.iter().copied().filter(|v| !v.is_nan()));
        let part = &self.parts[0];
        Ok(ObservedTerms {
            dy: &self.values,
            gain: &part.gain,
            half: &part.half,
        })
    }

    fn make(&self, s_inv_h: &[Vec<f64>], pattern: Vec<bool>) -> Result<Pattern, FilterError> {
        let rows: Vec<usize> = (0..pattern.len()).filter(|&j| pattern[j]).collect();
        let s = &self.noise_cov;
        let s_oo = DMatrix::from_fn(rows.len(), rows.len(), |a, b| s[(rows[a], rows[b])]);
        let s_oo_inv = s_oo.try_inverse().ok_or(FilterError::NotPositiveDefinite {
            what: "observed block of the observation noise covariance",
        })?;
        let len = s_inv_h.first().map_or(0, Vec::len);
        let (m, k) = (pattern.len(), rows.len());
        let mut gain = vec![vec![0.0; len]; k];
        let mut half = vec![0.0; len];
        let (mut sh, mut h_o) = (vec![0.0; m], vec![0.0; k]);
        for i in 0..len {
            for (v, column) in sh.iter_mut().zip(s_inv_h) {
                *v = column[i];
            }
            for (h, &r) in h_o.iter_mut().zip(&rows) {
                *h = (0..m).map(|b| s[(r, b)] * sh[b]).sum();
            }
            let mut hgh = 0.0;
            for (a, g) in gain.iter_mut().enumerate() {
                g[i] = (0..k).map(|b| s_oo_inv[(a, b)] * h_o[b]).sum();
                hgh += h_o[a] * g[i];
            }
            half[i] = 0.5 * hgh;
        }
        Ok(Pattern {
            observed: pattern,
            gain,
            half,
        })
    }
}
