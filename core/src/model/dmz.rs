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
pub enum Likelihood {
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
pub struct DmzCoefficients {
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
pub fn continuous_noise_inverse(model: &Model, who: &str) -> Result<DMatrix<f64>, FilterError> {
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
    pub fn tabulate(
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
