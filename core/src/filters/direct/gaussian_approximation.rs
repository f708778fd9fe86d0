//! 002 Algorithm 1: a density tabulated on a uniform 1-D grid as a sum of Gaussians
//! `Σ c_i exp(−(x − μ_i)²/(2σ_i²))`.
//!
//! With the threshold `E = α max φ`: every peak (local maximum on the grid) of the residual
//! that reaches E becomes a Gaussian with the peak as mean and height; its width σ_i is the
//! least-squares fit to the residual on the peak's neighbourhood free of other peaks — the
//! monotone descent on both sides, while the residual stays positive — by golden-section
//! search over ln σ (to 10⁻⁷ relative). The fitted Gaussians are subtracted and the step repeated; when no peak
//! of the residual reaches E, the same is done for the peaks of its negative (negative
//! weights); the method stops when neither has a peak above E, or at `max_terms`.

use alloc::vec;
use alloc::vec::Vec;

/// One term `c exp(−(x − μ)²/(2σ²))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianTerm {
    /// Weight c (the height at the mean; negative for the negative-residual pass).
    pub weight: f64,
    /// Mean μ.
    pub mean: f64,
    /// Width σ.
    pub sigma: f64,
}

impl GaussianTerm {
    /// The term's value at x.
    pub fn value(&self, x: f64) -> f64 {
        let d = (x - self.mean) / self.sigma;
        self.weight * libm::exp(-0.5 * d * d)
    }
}

/// The sum of the terms at every grid point.
pub fn evaluate(terms: &[GaussianTerm], grid: &[f64]) -> Vec<f64> {
    grid.iter()
        .map(|&x| terms.iter().map(|t| t.value(x)).sum())
        .collect()
}

/// Indices of the grid's local maxima of `f` that reach `threshold`.
fn peaks(f: &[f64], threshold: f64) -> Vec<usize> {
    let n = f.len();
    (0..n)
        .filter(|&i| {
            let left = if i > 0 { f[i - 1] } else { f64::NEG_INFINITY };
            let right = if i + 1 < n {
                f[i + 1]
            } else {
                f64::NEG_INFINITY
            };
            f[i] >= threshold && f[i] > left && f[i] >= right
        })
        .collect()
}

/// The neighbourhood of peak i free of other peaks: the monotone descent on both sides, while
/// `f` stays positive.
fn neighbourhood(f: &[f64], i: usize) -> (usize, usize) {
    let mut lo = i;
    while lo > 0 && f[lo - 1] < f[lo] && f[lo - 1] > 0.0 {
        lo -= 1;
    }
    let mut hi = i;
    while hi + 1 < f.len() && f[hi + 1] < f[hi] && f[hi + 1] > 0.0 {
        hi += 1;
    }
    (lo, hi)
}

/// The least-squares width of a Gaussian of height `f[i]` at `grid[i]` on `lo..=hi`.
fn fit_sigma(grid: &[f64], f: &[f64], i: usize, (lo, hi): (usize, usize)) -> f64 {
    let (x0, y0) = (grid[i], f[i]);
    let h = (grid[grid.len() - 1] - grid[0]) / (grid.len() - 1).max(1) as f64;
    let (xs, ys) = (&grid[lo..=hi], &f[lo..=hi]);
    let cost = |ln_sigma: f64| {
        let inv = libm::exp(-ln_sigma);
        xs.iter()
            .zip(ys)
            .map(|(&x, &y)| {
                let d = (x - x0) * inv;
                let r = y - y0 * crate::linalg::exp_nonpositive(-0.5 * d * d);
                r * r
            })
            .sum::<f64>()
    };
    let width = (grid[hi] - grid[lo]).max(h);
    let (mut a, mut b) = (libm::log(0.25 * h), libm::log(2.0 * width));
    let ratio = 0.5 * (libm::sqrt(5.0) - 1.0);
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut fc, mut fd) = (cost(c), cost(d));
    // Golden section down to a relative width of 10⁻⁷ in σ.
    while b - a > 1e-7 {
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - ratio * (b - a);
            fc = cost(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + ratio * (b - a);
            fd = cost(d);
        }
    }
    libm::exp(0.5 * (a + b))
}

/// 002 Algorithm 1 on the uniform grid `grid` (ascending) for the values `phi`.
pub fn gaussian_approximation(
    grid: &[f64],
    phi: &[f64],
    alpha: f64,
    max_terms: usize,
) -> Vec<GaussianTerm> {
    let threshold = alpha * phi.iter().copied().fold(0.0, f64::max);
    let mut terms: Vec<GaussianTerm> = Vec::new();
    let mut residual = phi.to_vec();
    let mut flipped = vec![0.0; phi.len()];
    while terms.len() < max_terms {
        // Step 2 on the residual, else step 4 on its negative.
        let mut sign = 1.0;
        let mut found = peaks(&residual, threshold);
        if found.is_empty() {
            for (f, r) in flipped.iter_mut().zip(&residual) {
                *f = -r;
            }
            found = peaks(&flipped, threshold);
            sign = -1.0;
        }
        if found.is_empty() {
            break;
        }
        let f = if sign > 0.0 { &residual } else { &flipped };
        let new: Vec<GaussianTerm> = found
            .iter()
            .take(max_terms - terms.len())
            .map(|&i| GaussianTerm {
                weight: sign * f[i],
                mean: grid[i],
                sigma: fit_sigma(grid, f, i, neighbourhood(f, i)),
            })
            .collect();
        for (r, &x) in residual.iter_mut().zip(grid) {
            *r -= new.iter().map(|t| t.value(x)).sum::<f64>();
        }
        terms.extend(new);
    }
    terms
}
