//! The exact Kalman filter and Rauch–Tung–Striebel smoother of a linear-Gaussian model,
//! written here with nalgebra alone — nothing of Zakai's filters — so that the tests that
//! promise an independent reference have one in any dimension.
//!
//! The signal is `dx = (A x + b) dt + G dv` (`Q = G Gᵀ`), carried exactly over a step `Δ`:
//! `x' = Φ x + c + noise`, with `Φ = e^{AΔ}`, `c = ∫₀^Δ e^{As} b ds` and the noise covariance
//! `Q_Δ = ∫₀^Δ e^{As} Q e^{Aᵀs} ds`, all three read off one block exponential (Van Loan 1978,
//! "Computing integrals involving the matrix exponential", IEEE TAC 23). It is observed by
//!
//! * measurements `z = H x + d + v`, `v ~ N(0, R)`, or
//! * increments over the step (the sampled model every continuous-observation filter in Zakai
//!   updates with): `Δy = (H x + d) Δ + w`, `w ~ N(0, S Δ)`, with the log-likelihood taken
//!   against Wiener measure (minus `ln N(Δy; 0, SΔ)`).
//!
//! Missing components (NaN) are left out of the update; a row with nothing observed only
//! predicts.

use nalgebra::{DMatrix, DVector};

/// How the state is observed.
#[derive(Clone, Debug)]
pub enum Sensor {
    /// `z = H x + d + v`, `v ~ N(0, R)`.
    Measurement {
        h: DMatrix<f64>,
        d: DVector<f64>,
        r: DMatrix<f64>,
    },
    /// `Δy = (H x + d) Δ + w`, `w ~ N(0, S Δ)`.
    Increment {
        h: DMatrix<f64>,
        d: DVector<f64>,
        s: DMatrix<f64>,
    },
}

/// A linear-Gaussian model: the SDE `dx = (A x + b) dt + G dv` with `Q = G Gᵀ`, and its sensor.
#[derive(Clone, Debug)]
pub struct LinearGaussian {
    pub a: DMatrix<f64>,
    pub b: DVector<f64>,
    pub q: DMatrix<f64>,
    pub sensor: Sensor,
}

/// A mean and covariance.
pub type Moments = (DVector<f64>, DMatrix<f64>);

/// The filter's moments after a row (and what the smoother needs to go back over it).
#[derive(Clone, Debug)]
pub struct Row {
    /// Mean and covariance after the row's update.
    pub mean: DVector<f64>,
    pub cov: DMatrix<f64>,
    /// The row's log-likelihood term (0 for a row with nothing observed).
    pub log_likelihood: f64,
    /// The prediction into the row (`Φ`, predicted mean and covariance).
    phi: DMatrix<f64>,
    predicted_mean: DVector<f64>,
    predicted_cov: DMatrix<f64>,
}

impl Row {
    /// The standard deviation of component `i`.
    pub fn sd(&self, i: usize) -> f64 {
        self.cov[(i, i)].sqrt()
    }
}

fn ln_normal(x: &DVector<f64>, mean: &DVector<f64>, cov: &DMatrix<f64>) -> f64 {
    let chol = cov
        .clone()
        .cholesky()
        .expect("a positive definite covariance");
    let r = x - mean;
    let solved = chol.solve(&r);
    let log_det: f64 = chol.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum();
    -0.5 * (r.dot(&solved) + log_det + x.len() as f64 * std::f64::consts::TAU.ln())
}

impl LinearGaussian {
    /// A scalar model `dx = (a x + b) dt + g dv` with `sensor` (1×1 matrices).
    pub fn scalar(a: f64, b: f64, g: f64, sensor: Sensor) -> Self {
        LinearGaussian {
            a: DMatrix::from_element(1, 1, a),
            b: DVector::from_element(1, b),
            q: DMatrix::from_element(1, 1, g * g),
            sensor,
        }
    }

    /// `(Φ, c, Q_Δ)` over a step `dt`, from one block exponential: with
    /// `M = [[A, Q, b], [0, −Aᵀ, 0], [0, 0, 0]]`, `e^{MΔ}` holds `Φ` top left,
    /// `∫₀^Δ e^{A(Δ−s)} Q e^{−Aᵀs} ds = Q_Δ Φ^{−ᵀ}` top middle and `c` top right.
    pub fn transition(&self, dt: f64) -> (DMatrix<f64>, DVector<f64>, DMatrix<f64>) {
        let n = self.a.nrows();
        let mut m = DMatrix::zeros(2 * n + 1, 2 * n + 1);
        m.view_mut((0, 0), (n, n)).copy_from(&(&self.a * dt));
        m.view_mut((0, n), (n, n)).copy_from(&(&self.q * dt));
        m.view_mut((n, n), (n, n))
            .copy_from(&(-self.a.transpose() * dt));
        m.view_mut((0, 2 * n), (n, 1)).copy_from(&(&self.b * dt));
        let e = m.exp();
        let phi = e.view((0, 0), (n, n)).into_owned();
        let c = e.view((0, 2 * n), (n, 1)).column(0).into_owned();
        let q = e.view((0, n), (n, n)) * phi.transpose();
        // Symmetric to round-off.
        let q = (&q + q.transpose()) * 0.5;
        (phi, c, q)
    }

    /// The filter from the prior `N(mean, cov)` over `rows` of (step length, observation with
    /// NaN for a missing component); a step of 0 only updates.
    pub fn filter(&self, mean: &[f64], cov: &DMatrix<f64>, rows: &[(f64, Vec<f64>)]) -> Vec<Row> {
        let n = mean.len();
        let (mut m, mut p) = (DVector::from_column_slice(mean), cov.clone());
        let mut out = Vec::with_capacity(rows.len());
        for (dt, z) in rows {
            let phi = if *dt > 0.0 {
                let (phi, c, q) = self.transition(*dt);
                m = &phi * &m + c;
                p = &phi * &p * phi.transpose() + q;
                phi
            } else {
                DMatrix::identity(n, n)
            };
            let (predicted_mean, predicted_cov) = (m.clone(), p.clone());
            let seen: Vec<usize> = (0..z.len()).filter(|&i| !z[i].is_nan()).collect();
            let mut log_likelihood = 0.0;
            if !seen.is_empty() {
                let (h, d, noise, scale) = match &self.sensor {
                    Sensor::Measurement { h, d, r } => (h, d, r.clone(), 1.0),
                    Sensor::Increment { h, d, s } => (h, d, s * *dt, *dt),
                };
                let hs = DMatrix::from_fn(seen.len(), n, |i, j| scale * h[(seen[i], j)]);
                let ds = DVector::from_fn(seen.len(), |i, _| scale * d[seen[i]]);
                let rs = DMatrix::from_fn(seen.len(), seen.len(), |i, j| noise[(seen[i], seen[j])]);
                let zs = DVector::from_fn(seen.len(), |i, _| z[seen[i]]);
                let predicted = &hs * &m + ds;
                let s = &hs * &p * hs.transpose() + &rs;
                log_likelihood = ln_normal(&zs, &predicted, &s);
                if matches!(self.sensor, Sensor::Increment { .. }) {
                    log_likelihood -= ln_normal(&zs, &DVector::zeros(seen.len()), &rs);
                }
                let gain = &p * hs.transpose() * s.clone().try_inverse().expect("S invertible");
                m += &gain * (zs - predicted);
                // Joseph form, symmetric to round-off.
                let i_kh = DMatrix::identity(n, n) - &gain * &hs;
                p = &i_kh * &p * i_kh.transpose() + &gain * rs * gain.transpose();
            }
            out.push(Row {
                mean: m.clone(),
                cov: p.clone(),
                log_likelihood,
                phi,
                predicted_mean,
                predicted_cov,
            });
        }
        out
    }

    /// The Rauch–Tung–Striebel smoother over the filter's rows: the mean and covariance of the
    /// state at each row given every row.
    pub fn smooth(rows: &[Row]) -> Vec<Moments> {
        let mut out: Vec<Moments> = vec![(DVector::zeros(0), DMatrix::zeros(0, 0)); rows.len()];
        let last = rows.len() - 1;
        out[last] = (rows[last].mean.clone(), rows[last].cov.clone());
        for k in (0..last).rev() {
            let next = &rows[k + 1];
            let c = &rows[k].cov
                * next.phi.transpose()
                * next
                    .predicted_cov
                    .clone()
                    .try_inverse()
                    .expect("an invertible prediction");
            let mean = &rows[k].mean + &c * (&out[k + 1].0 - &next.predicted_mean);
            let cov = &rows[k].cov + &c * (&out[k + 1].1 - &next.predicted_cov) * c.transpose();
            out[k] = (mean, cov);
        }
        out
    }
}

/// The largest |x̂ − exact mean| and |P / exact P − 1| (diagonal) over every row and
/// component of a track's estimates and covariances (row-major: n, and n × n, per row) against
/// the exact filter's rows; a NaN anywhere is kept (see [`crate::max_or_nan`]).
pub fn worst_mean_and_variance(
    estimates: &[f64],
    covariances: &[f64],
    exact: &[Row],
) -> (f64, f64) {
    let n = exact[0].mean.len();
    assert_eq!(
        estimates.len(),
        exact.len() * n,
        "a mean per row and component"
    );
    assert_eq!(
        covariances.len(),
        exact.len() * n * n,
        "a covariance per row"
    );
    let (mut mean, mut variance) = (0.0f64, 0.0f64);
    for (k, row) in exact.iter().enumerate() {
        for d in 0..n {
            mean = crate::max_or_nan(mean, (estimates[k * n + d] - row.mean[d]).abs());
            let p = covariances[k * n * n + d * n + d];
            variance = crate::max_or_nan(variance, (p / row.cov[(d, d)] - 1.0).abs());
        }
    }
    (mean, variance)
}

/// The rows of a recording as [`LinearGaussian::filter`] takes them: (step length,
/// observation with NaN where missing); the start row of continuous observations (zeros: no
/// increment yet) observes nothing.
pub fn rows_of(r: &zakai::lab::recording::Recording) -> Vec<(f64, Vec<f64>)> {
    (0..r.times.len())
        .map(|k| {
            let z = if k == 0 && r.continuous {
                vec![f64::NAN; r.m]
            } else {
                r.observation(k).to_vec()
            };
            (r.step_length(k), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test;

    /// The block exponential against the scalar closed forms: Φ = e^{aΔ}, c = b(e^{aΔ} − 1)/a,
    /// Q_Δ = g²(e^{2aΔ} − 1)/(2a).
    #[test]
    fn the_transition_is_the_closed_form_in_one_dimension() {
        let model = LinearGaussian::scalar(
            -0.7,
            0.3,
            1.3,
            Sensor::Measurement {
                h: DMatrix::identity(1, 1),
                d: DVector::zeros(1),
                r: DMatrix::identity(1, 1),
            },
        );
        let dt = 0.37;
        let (phi, c, q) = model.transition(dt);
        let e = (-0.7f64 * dt).exp();
        assert!((phi[(0, 0)] - e).abs() < 1e-13);
        assert!((c[0] - 0.3 * (e - 1.0) / -0.7).abs() < 1e-13);
        assert!((q[(0, 0)] - 1.69 * (e * e - 1.0) / -1.4).abs() < 1e-13);
    }

    /// A 2-D transition's covariance against the integral by the trapezoid rule on 20 000
    /// panels (e^{As} by its Taylor series at each node).
    #[test]
    fn the_transition_covariance_is_the_integral() {
        let a = DMatrix::from_row_slice(2, 2, &[-0.5, 0.3, -0.2, -0.4]);
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.6, 0.6, 0.8]);
        let model = LinearGaussian {
            a: a.clone(),
            b: DVector::zeros(2),
            q: q.clone(),
            sensor: Sensor::Measurement {
                h: DMatrix::identity(2, 2),
                d: DVector::zeros(2),
                r: DMatrix::identity(2, 2),
            },
        };
        let dt = 0.8;
        let (_, _, exact) = model.transition(dt);
        let expm = |t: f64| {
            let (mut term, mut sum) = (DMatrix::identity(2, 2), DMatrix::identity(2, 2));
            for k in 1..30 {
                term = &term * &a * (t / k as f64);
                sum += &term;
            }
            sum
        };
        let panels = 20_000;
        let h = dt / panels as f64;
        let mut integral = DMatrix::zeros(2, 2);
        for i in 0..=panels {
            let e = expm(i as f64 * h);
            let w = if i == 0 || i == panels { 0.5 } else { 1.0 };
            integral += &e * &q * e.transpose() * (w * h);
        }
        assert!((integral - exact).abs().max() < 1e-8);
    }
}
