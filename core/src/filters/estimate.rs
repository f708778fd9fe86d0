//! What a filter reports: its [`Estimate`] (mean, covariance where the method has one, MAP
//! point where it computes one), and the in-place copies that keep a step allocation-free.

use nalgebra::{DMatrix, DVector};

/// A filter's current estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Conditional mean (or the method's point estimate).
    pub mean: DVector<f64>,
    /// Conditional covariance, where the method has one.
    pub covariance: Option<DMatrix<f64>>,
    /// Maximum a posteriori point, where the method computes one.
    pub map: Option<DVector<f64>>,
}

impl Estimate {
    /// Zero mean (n) and covariance (n × n), no MAP point: the storage a filter that computes
    /// its estimate in place ([`Filter::estimate_into`](super::Filter::estimate_into)) fills for [`Filter::estimate`](super::Filter::estimate).
    pub(crate) fn zeros(n: usize) -> Self {
        Estimate {
            mean: DVector::zeros(n),
            covariance: Some(DMatrix::zeros(n, n)),
            map: None,
        }
    }

    /// The mean (n) and covariance (n × n) to be written in place, reallocated only when
    /// their shapes differ; no MAP point.
    pub(crate) fn mean_and_covariance(
        &mut self,
        n: usize,
    ) -> (&mut DVector<f64>, &mut DMatrix<f64>) {
        if self.mean.len() != n {
            self.mean = DVector::zeros(n);
        }
        if !matches!(&self.covariance, Some(c) if c.shape() == (n, n)) {
            self.covariance = Some(DMatrix::zeros(n, n));
        }
        self.map = None;
        let cov = self.covariance.as_mut().expect("set just above");
        (&mut self.mean, cov)
    }

    /// The variance of component `i`, `covariance[(i, i)]`; NaN for a method without a
    /// covariance.
    ///
    /// # Panics
    ///
    /// If `i` is not below the state's dimension.
    pub fn variance(&self, i: usize) -> f64 {
        assert!(
            i < self.mean.len(),
            "component {i} of a {}-dimensional estimate",
            self.mean.len()
        );
        self.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)])
    }

    /// The standard deviation of component `i`, the square root of [`Estimate::variance`].
    ///
    /// # Panics
    ///
    /// If `i` is not below the state's dimension.
    pub fn sd(&self, i: usize) -> f64 {
        libm::sqrt(self.variance(i))
    }

    /// Makes this a copy of `src`, reusing this estimate's storage where the shapes agree (no
    /// allocation when they do).
    pub fn copy_from(&mut self, src: &Estimate) {
        copy_vector(&mut self.mean, &src.mean);
        match &src.covariance {
            Some(from) => copy_matrix(&mut self.covariance, from),
            None => self.covariance = None,
        }
        copy_optional_vector(&mut self.map, src.map.as_ref());
    }
}

/// `to ← from.cloned()`, in place when both hold vectors of the same length.
pub(crate) fn copy_optional_vector(to: &mut Option<DVector<f64>>, from: Option<&DVector<f64>>) {
    match (to, from) {
        (Some(to), Some(from)) => copy_vector(to, from),
        (to, from) => *to = from.cloned(),
    }
}

/// `to ← Some(from)`, in place when `to` holds a matrix of the same shape.
pub(crate) fn copy_matrix(to: &mut Option<DMatrix<f64>>, from: &DMatrix<f64>) {
    match to {
        Some(m) if m.shape() == from.shape() => m.copy_from(from),
        other => *other = Some(from.clone()),
    }
}

/// `to ← from`, in place when the lengths agree.
pub(crate) fn copy_vector(to: &mut DVector<f64>, from: &DVector<f64>) {
    if to.len() == from.len() {
        to.copy_from(from);
    } else {
        *to = from.clone();
    }
}
