//! Gaussian and Gaussian-mixture densities: observation noise (001 uses mixtures,
//! p(v_k) = Σ_i α_i N(v_k : μ_i, Σ_i)), priors and the Gaussian-sum reference.

use alloc::vec::Vec;

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use rand::Rng;

use crate::error::ZakaiError;
use crate::linalg::{gaussian_log_density, log_sum_exp};

/// One weighted Gaussian component `α N(μ, Σ)`.
#[derive(Clone, Debug)]
pub struct MixtureComponent {
    /// Weight α (the weights of a mixture sum to one).
    pub weight: f64,
    /// Mean μ.
    pub mean: DVector<f64>,
    /// Covariance Σ.
    pub cov: DMatrix<f64>,
    chol: Cholesky<f64, Dyn>,
    /// `log α − ½ log det(2π Σ)`.
    log_scale: f64,
}

/// A Gaussian mixture `Σ_i α_i N(μ_i, Σ_i)`; a single Gaussian is a mixture of one.
#[derive(Clone, Debug)]
pub struct GaussianMixture {
    components: Vec<MixtureComponent>,
}

impl GaussianMixture {
    /// Builds a mixture, normalising the weights. Fails on negative or zero total weight,
    /// inconsistent dimensions, non-finite entries or a covariance that is not positive
    /// definite.
    pub fn new(parts: Vec<(f64, DVector<f64>, DMatrix<f64>)>) -> Result<Self, ZakaiError> {
        let Some(first) = parts.first() else {
            return Err(ZakaiError::Other(
                "a mixture needs at least one component".into(),
            ));
        };
        let d = first.1.len();
        let total: f64 = parts.iter().map(|p| p.0).sum();
        if !(total > 0.0 && total.is_finite()) || parts.iter().any(|p| p.0 < 0.0) {
            return Err(ZakaiError::Other(
                "mixture weights must be nonnegative with a positive finite sum".into(),
            ));
        }
        let mut components = Vec::with_capacity(parts.len());
        for (i, (w, mean, cov)) in parts.into_iter().enumerate() {
            if mean.len() != d || cov.nrows() != d || cov.ncols() != d {
                return Err(ZakaiError::Dimension(alloc::format!(
                    "mixture component {i} has mean of length {} and covariance {}×{}, expected {d}",
                    mean.len(),
                    cov.nrows(),
                    cov.ncols()
                )));
            }
            let chol = crate::linalg::cholesky(&cov, "mixture covariance").map_err(|_| {
                ZakaiError::Other(alloc::format!(
                    "covariance of mixture component {i} is not symmetric positive definite"
                ))
            })?;
            let log_det: f64 = (0..d).map(|k| libm::log(chol.l_dirty()[(k, k)])).sum();
            let log_scale = libm::log(w / total)
                - log_det
                - 0.5 * d as f64 * libm::log(2.0 * core::f64::consts::PI);
            components.push(MixtureComponent {
                log_scale,
                weight: w / total,
                mean,
                cov,
                chol,
            });
        }
        Ok(GaussianMixture { components })
    }

    /// A single Gaussian `N(mean, cov)`.
    pub fn gaussian(mean: DVector<f64>, cov: DMatrix<f64>) -> Result<Self, ZakaiError> {
        Self::new(alloc::vec![(1.0, mean, cov)])
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.components[0].mean.len()
    }

    /// The components.
    pub fn components(&self) -> &[MixtureComponent] {
        &self.components
    }

    /// `log p(x)`.
    pub fn log_pdf(&self, x: &DVector<f64>) -> f64 {
        log_sum_exp(
            self.components
                .iter()
                .map(|c| libm::log(c.weight) + gaussian_log_density(&(x - &c.mean), &c.chol)),
        )
    }

    /// `log p(x)` without allocating: `work` (length ≥ dim) holds the whitened residual.
    /// Used where a density is evaluated at every grid node (001 (6)).
    pub fn log_pdf_slice(&self, x: &[f64], work: &mut [f64]) -> f64 {
        let d = self.dim();
        let mut max = f64::NEG_INFINITY;
        let mut sum = 0.0;
        // log-sum-exp in one pass with a running maximum.
        for c in &self.components {
            let l = c.chol.l_dirty();
            let mut quad = 0.0;
            for i in 0..d {
                let mut r = x[i] - c.mean[i];
                for k in 0..i {
                    r -= l[(i, k)] * work[k];
                }
                r /= l[(i, i)];
                work[i] = r;
                quad += r * r;
            }
            let v = c.log_scale - 0.5 * quad;
            if v == f64::NEG_INFINITY || v.is_nan() {
                continue;
            }
            if v > max {
                sum = sum * libm::exp(max - v) + 1.0;
                max = v;
            } else {
                sum += libm::exp(v - max);
            }
        }
        if max == f64::NEG_INFINITY {
            return max;
        }
        max + libm::log(sum)
    }

    /// `out_i += ln p(r_i)` at `count = out.len()` points at once, component j of point i at
    /// `data[rows[j]·count + i]` (d rows, the mixture's dimension, from structure-of-arrays
    /// data with rows to skip — a measurement's missing components): each component's residuals whitened by
    /// forward substitution one row at a time over all the points, their squared norms, and for
    /// a mixture the log-sum-exp across components per point — passes that vectorise, where
    /// [`GaussianMixture::log_pdf_slice`] walks point by point (equal to it up to rounding; a
    /// component whose value is NaN counts for nothing, as there). `work` grows to
    /// `(d + K + 3)·count` values on first use.
    pub(crate) fn add_log_pdf_batch(
        &self,
        (data, rows): (&[f64], &[usize]),
        out: &mut [f64],
        work: &mut Vec<f64>,
    ) {
        let (d, count, k) = (self.dim(), out.len(), self.components.len());
        work.resize((d + k + 3) * count, 0.0);
        let (white, rest) = work.split_at_mut(d * count);
        let (quad, rest) = rest.split_at_mut(count);
        let (logs, rest) = rest.split_at_mut(k * count);
        let (top, sums) = rest.split_at_mut(count);
        for (c, comp) in self.components.iter().enumerate() {
            let l = comp.chol.l_dirty();
            for i in 0..d {
                let (done, row) = white.split_at_mut(i * count);
                let w = &mut row[..count];
                let r = &data[rows[i] * count..(rows[i] + 1) * count];
                centred(w, r, comp.mean[i]);
                for j in 0..i {
                    subtract_scaled(w, &done[j * count..(j + 1) * count], l[(i, j)]);
                }
                divide(w, l[(i, i)]);
                match i {
                    0 => squares(quad, w),
                    _ => add_squares(quad, w),
                }
            }
            match k {
                1 => add_log_gaussian(out, quad, comp.log_scale),
                _ => set_log_gaussian(&mut logs[c * count..(c + 1) * count], quad, comp.log_scale),
            }
        }
        if k > 1 {
            top.fill(f64::NEG_INFINITY);
            for c in 0..k {
                keep_larger(top, &logs[c * count..(c + 1) * count]);
            }
            sums.fill(0.0);
            for c in 0..k {
                add_exp_below(sums, &logs[c * count..(c + 1) * count], top);
            }
            add_log_sum(out, top, sums);
        }
    }

    /// The marginal density of the components where `kept` is true: the mixture of the
    /// components' marginals with the same weights (a Gaussian's marginal keeps the rows and
    /// columns of the kept components). Used for observations with missing components.
    pub fn marginal(&self, kept: &[bool]) -> Result<Self, ZakaiError> {
        let rows: Vec<usize> = (0..self.dim()).filter(|&i| kept[i]).collect();
        let k = rows.len();
        self.new_like(|c| {
            (
                c.weight,
                DVector::from_fn(k, |i, _| c.mean[rows[i]]),
                DMatrix::from_fn(k, k, |i, j| c.cov[(rows[i], rows[j])]),
            )
        })
    }

    /// A mixture with a component made by `f` from each of these.
    fn new_like(
        &self,
        f: impl Fn(&MixtureComponent) -> (f64, DVector<f64>, DMatrix<f64>),
    ) -> Result<Self, ZakaiError> {
        Self::new(self.components.iter().map(f).collect())
    }

    /// The mixture mean Σ α_i μ_i.
    pub fn mean(&self) -> DVector<f64> {
        let mut m = DVector::zeros(self.dim());
        for c in &self.components {
            m += &c.mean * c.weight;
        }
        m
    }

    /// The mixture covariance Σ α_i (Σ_i + (μ_i − μ)(μ_i − μ)ᵀ).
    pub fn covariance(&self) -> DMatrix<f64> {
        let m = self.mean();
        let d = self.dim();
        let mut p = DMatrix::zeros(d, d);
        for c in &self.components {
            let dm = &c.mean - &m;
            p += (&c.cov + &dm * dm.transpose()) * c.weight;
        }
        p
    }

    /// One draw: a component by its weight, then μ + L ξ with ξ ~ N(0, I).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        let mut out = DVector::zeros(self.dim());
        self.sample_into(rng, out.as_mut_slice());
        out
    }

    /// One draw into `out` (its dimension), without allocating: a component by its weight,
    /// then μ + L ξ with ξ ~ N(0, I) drawn into `out` and multiplied in place (L is lower
    /// triangular, so row i reads only ξ_0..ξ_i: from the last row up).
    pub fn sample_into<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        let chosen = self.pick(rand::RngExt::random(rng));
        for v in out.iter_mut() {
            *v = crate::random::standard_normal(rng);
        }
        chosen.transform(out);
    }

    /// The component a uniform `u` in [0, 1) picks by the cumulative weights.
    pub(crate) fn pick(&self, u: f64) -> &MixtureComponent {
        let mut acc = 0.0;
        for c in &self.components {
            acc += c.weight;
            if u < acc {
                return c;
            }
        }
        &self.components[self.components.len() - 1]
    }
}

impl MixtureComponent {
    /// `ξ ← μ + L ξ` in place (L lower triangular, so row i reads only ξ_0..ξ_i: from the
    /// last row up): a standard normal ξ becomes a draw of this component.
    pub(crate) fn transform(&self, xi: &mut [f64]) {
        let l = self.chol.l_dirty();
        for i in (0..xi.len()).rev() {
            let mut v = 0.0;
            for k in 0..=i {
                v += l[(i, k)] * xi[k];
            }
            xi[i] = self.mean[i] + v;
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `w_i = r_i − μ`.
    fn centred(w: &mut [f64], r: &[f64], mean: f64) {
        w.iter_mut().zip(r).for_each(|(w, r)| *w = r - mean);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `w_i −= a v_i`.
    fn subtract_scaled(w: &mut [f64], v: &[f64], a: f64) {
        w.iter_mut().zip(v).for_each(|(w, v)| *w -= a * v);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `w_i /= a`.
    fn divide(w: &mut [f64], a: f64) {
        w.iter_mut().for_each(|w| *w /= a);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `q_i = w_i²`.
    fn squares(q: &mut [f64], w: &[f64]) {
        q.iter_mut().zip(w).for_each(|(q, w)| *q = w * w);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `q_i += w_i²`.
    fn add_squares(q: &mut [f64], w: &[f64]) {
        q.iter_mut().zip(w).for_each(|(q, w)| *q += w * w);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += c − ½ q_i`.
    fn add_log_gaussian(out: &mut [f64], q: &[f64], c: f64) {
        out.iter_mut().zip(q).for_each(|(o, q)| *o += c - 0.5 * q);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i = c − ½ q_i`.
    fn set_log_gaussian(out: &mut [f64], q: &[f64], c: f64) {
        out.iter_mut().zip(q).for_each(|(o, q)| *o = c - 0.5 * q);
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `top_i = max(top_i, v_i)`, a NaN `v_i` ignored.
    fn keep_larger(top: &mut [f64], v: &[f64]) {
        top.iter_mut()
            .zip(v)
            .for_each(|(t, &v)| *t = crate::linalg::larger(*t, v));
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `s_i += e^{v_i − top_i}` (0 for a NaN `v_i`, or where every value is −∞).
    fn add_exp_below(s: &mut [f64], v: &[f64], top: &[f64]) {
        for ((s, &v), &t) in s.iter_mut().zip(v).zip(top) {
            let e = crate::linalg::elementary::exp(v - t);
            *s += if e.is_nan() { 0.0 } else { e };
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `out_i += top_i + ln s_i` (−∞ where every component is −∞ or NaN).
    fn add_log_sum(out: &mut [f64], top: &[f64], s: &[f64]) {
        for ((o, &t), &s) in out.iter_mut().zip(top).zip(s) {
            *o += if t == f64::NEG_INFINITY {
                f64::NEG_INFINITY
            } else {
                t + crate::linalg::elementary::ln(s)
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;

    /// The batch log-density is the point-by-point one to 10⁻¹² (relative, at least 1): a 1-D
    /// Gaussian, a correlated 2-D one, and a 2-D mixture of three read from rows 0 and 2 of
    /// three (a missing middle component); residuals so far out that every component
    /// underflows give −∞ both ways.
    #[test]
    fn batch_log_densities_are_the_pointwise_ones() {
        let one = GaussianMixture::gaussian(
            DVector::from_element(1, 0.3),
            DMatrix::from_element(1, 1, 0.5),
        )
        .unwrap();
        let cov = DMatrix::from_row_slice(2, 2, &[1.0, 0.6, 0.6, 2.0]);
        let two =
            GaussianMixture::gaussian(DVector::from_vec(vec![0.1, -0.2]), cov.clone()).unwrap();
        let mixture = GaussianMixture::new(vec![
            (0.5, DVector::from_vec(vec![0.0, 0.0]), cov.clone()),
            (
                0.3,
                DVector::from_vec(vec![3.0, -1.0]),
                DMatrix::identity(2, 2) * 0.2,
            ),
            (0.2, DVector::from_vec(vec![-2.0, 4.0]), cov * 3.0),
        ])
        .unwrap();
        let count = 203;
        let data: Vec<f64> = (0..3 * count)
            .map(|k| {
                let v = libm::sin(k as f64 * 0.77) * 6.0;
                if k % 97 == 5 {
                    1e200
                } else {
                    v
                }
            })
            .collect();
        for (density, rows) in [
            (&one, vec![1usize]),
            (&two, vec![0, 1]),
            (&mixture, vec![0, 2]),
        ] {
            let mut out = vec![0.25; count];
            let mut work = Vec::new();
            density.add_log_pdf_batch((&data, &rows), &mut out, &mut work);
            let mut scratch = vec![0.0; 2];
            for (i, o) in out.iter().enumerate() {
                let x: Vec<f64> = rows.iter().map(|&r| data[r * count + i]).collect();
                let want = density.log_pdf_slice(&x, &mut scratch);
                let got = o - 0.25;
                if want == f64::NEG_INFINITY || got == f64::NEG_INFINITY {
                    assert_eq!(got, want, "point {i}");
                    continue;
                }
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "point {i}: {got} against {want}"
                );
            }
            assert!(
                out.iter().any(|&o| o == f64::NEG_INFINITY),
                "an underflowing point"
            );
        }
    }
}
