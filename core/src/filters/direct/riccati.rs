//! 002 Theorem 3.3: the Kolmogorov equation (32) with `l(x) = Dx + d` and
//! `q(x) = ½(Σ l_i² − Σ ∂l_i/∂x_i − η) = xᵀQx + pᵀx + r` (33) keeps a Gaussian-type initial
//! value `exp(xᵀAx + Bᵀx + C)` in that form (34), with
//!
//! * `dA/dt = 2A² − (AD + DᵀA) + Q`  (35)
//! * `dBᵀ/dt = 2BᵀA − BᵀD − 2dᵀA + pᵀ`  (36)
//! * `dC/dt = tr A + ½BᵀB − dᵀB + r`  (37)
//!
//! integrated here by classical RK4 (A re-symmetrised after every step), for any n.

use nalgebra::{DMatrix, DVector};

use super::gaussian_approximation::GaussianTerm;
#[cfg(test)]
use crate::linalg::symmetrize;

/// `exp(xᵀAx + Bᵀx + C)` with A symmetric: the Riccati ODEs (35)–(37) in n dimensions, which
/// the tests hold to the Kolmogorov equation (32); the filter, 1-D, runs their scalar form
/// ([`propagate_scalar_term`]).
#[cfg(test)]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct QuadraticExponent {
    /// A (n × n, symmetric).
    pub a: DMatrix<f64>,
    /// B.
    pub b: DVector<f64>,
    /// C.
    pub c: f64,
}

/// The coefficients of (32)–(33): `l(x) = Dx + d`, `q(x) = xᵀQx + pᵀx + r`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct KolmogorovCoefficients {
    /// D.
    pub d_mat: DMatrix<f64>,
    /// d.
    pub d_vec: DVector<f64>,
    /// Q (symmetric).
    pub q: DMatrix<f64>,
    /// p.
    pub p: DVector<f64>,
    /// r.
    pub r: f64,
}

#[cfg(test)]
impl QuadraticExponent {
    /// A 1-D Gaussian term `|c| exp(−(x − μ)²/(2σ²))` (the sign of c is kept by the caller):
    /// `A = −1/(2σ²)`, `B = μ/σ²`, `C = ln|c| − μ²/(2σ²)`.
    pub(crate) fn from_term(term: &GaussianTerm) -> Self {
        let [a, b, c] = scalar_exponent(term);
        QuadraticExponent {
            a: DMatrix::from_element(1, 1, a),
            b: DVector::from_element(1, b),
            c,
        }
    }

    /// The value `exp(xᵀAx + Bᵀx + C)` at x.
    pub(crate) fn value(&self, x: &[f64]) -> f64 {
        let v = DVector::from_column_slice(x);
        libm::exp((v.transpose() * &self.a * &v)[(0, 0)] + self.b.dot(&v) + self.c)
    }

    fn rates(&self, k: &KolmogorovCoefficients) -> QuadraticExponent {
        let (a, b) = (&self.a, &self.b);
        let da = a * a * 2.0 - (a * &k.d_mat + k.d_mat.transpose() * a) + &k.q;
        // Column-vector form of (36): dB/dt = 2AB − DᵀB − 2Ad + p (A symmetric).
        let db = a * b * 2.0 - k.d_mat.transpose() * b - a * &k.d_vec * 2.0 + &k.p;
        let dc = a.trace() + 0.5 * b.dot(b) - k.d_vec.dot(b) + k.r;
        QuadraticExponent {
            a: da,
            b: db,
            c: dc,
        }
    }

    fn plus(&self, rate: &QuadraticExponent, h: f64) -> QuadraticExponent {
        QuadraticExponent {
            a: &self.a + &rate.a * h,
            b: &self.b + &rate.b * h,
            c: self.c + rate.c * h,
        }
    }

    /// Integrates (35)–(37) over `dt` in at least `substeps` RK4 steps — more when A is large:
    /// (35) behaves like `dA/dt = 2A²`, whose explicit steps are stable only for
    /// `h · 4‖A‖ ≲ 2.7`, so a narrow Gaussian (‖A‖ = 1/(2σ²)) gets `h ≤ 1/(4‖A‖)`.
    pub(crate) fn propagate(&mut self, k: &KolmogorovCoefficients, dt: f64, substeps: usize) {
        let steps = steps_for(dt, self.a.amax().max(k.d_mat.amax()), substeps);
        let h = dt / steps as f64;
        if self.a.nrows() == 1 {
            let u = rk4_scalar([self.a[(0, 0)], self.b[0], self.c], k, h, steps);
            self.a[(0, 0)] = u[0];
            self.b[0] = u[1];
            self.c = u[2];
            return;
        }
        for _ in 0..steps {
            let k1 = self.rates(k);
            let k2 = self.plus(&k1, 0.5 * h).rates(k);
            let k3 = self.plus(&k2, 0.5 * h).rates(k);
            let k4 = self.plus(&k3, h).rates(k);
            self.a += (k1.a + k2.a * 2.0 + k3.a * 2.0 + k4.a) * (h / 6.0);
            self.b += (k1.b + k2.b * 2.0 + k3.b * 2.0 + k4.b) * (h / 6.0);
            self.c += (k1.c + 2.0 * k2.c + 2.0 * k3.c + k4.c) * (h / 6.0);
            symmetrize(&mut self.a);
        }
    }
}

/// `(a, b, c)` with `exp(a x² + b x + c)` the 1-D Gaussian term (the scalar
/// [`QuadraticExponent::from_term`]).
pub(crate) fn scalar_exponent(term: &GaussianTerm) -> [f64; 3] {
    let s2 = term.sigma * term.sigma;
    [
        -0.5 / s2,
        term.mean / s2,
        libm::log(term.weight.abs()) - 0.5 * term.mean * term.mean / s2,
    ]
}

/// The 1-D term carried over `dt` by (35)–(37): [`QuadraticExponent::propagate`] on
/// scalars, without allocating.
pub(crate) fn propagate_scalar_term(
    term: &GaussianTerm,
    k: &KolmogorovCoefficients,
    dt: f64,
    substeps: usize,
) -> [f64; 3] {
    let u = scalar_exponent(term);
    let steps = steps_for(dt, libm::fabs(u[0]).max(k.d_mat.amax()), substeps);
    rk4_scalar(u, k, dt / steps as f64, steps)
}

/// RK4 steps over `dt`: at least `substeps`, and enough that `h·max(|A|, |D|) ≤ ¼` (the
/// Riccati equation (35) is stiff for narrow terms).
fn steps_for(dt: f64, scale: f64, substeps: usize) -> usize {
    let stiff = libm::ceil(4.0 * dt * scale).min(1e6) as usize;
    substeps.max(stiff).max(1)
}

/// (35)–(37) for n = 1 in plain numbers (the direct filter's inner loop):
/// `a' = 2a² − 2Da + Q`, `b' = 2ab − Db − 2ad + p`, `c' = a + ½b² − db + r`; `steps` RK4
/// steps of length h from `u = (a, b, c)`.
fn rk4_scalar(mut u: [f64; 3], k: &KolmogorovCoefficients, h: f64, steps: usize) -> [f64; 3] {
    let (dm, dv, q, p, r) = (k.d_mat[(0, 0)], k.d_vec[0], k.q[(0, 0)], k.p[0], k.r);
    let rates = |[a, b, _]: [f64; 3]| {
        [
            2.0 * a * a - 2.0 * dm * a + q,
            2.0 * a * b - dm * b - 2.0 * a * dv + p,
            a + 0.5 * b * b - dv * b + r,
        ]
    };
    let step =
        |u: [f64; 3], k: [f64; 3], s: f64| [u[0] + s * k[0], u[1] + s * k[1], u[2] + s * k[2]];
    for _ in 0..steps {
        let k1 = rates(u);
        let k2 = rates(step(u, k1, 0.5 * h));
        let k3 = rates(step(u, k2, 0.5 * h));
        let k4 = rates(step(u, k3, h));
        for i in 0..3 {
            u[i] += (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) * (h / 6.0);
        }
    }
    u
}
