//! 002 Algorithm 1: a density tabulated on a uniform 1-D grid as a sum of Gaussians
//! `Σ c_i exp(−(x − μ_i)²/(2σ_i²))`.
//!
//! With the threshold `E = α max φ`: every peak (local maximum on the grid) of the residual
//! that reaches E becomes a Gaussian with the peak as mean and height; its width σ_i is the
//! least-squares fit to the residual on the peak's neighbourhood free of other peaks — the
//! monotone descent on both sides, while the residual stays positive — by Brent's minimisation
//! over ln σ (to 10⁻⁷ relative). The fitted Gaussians are subtracted and the step repeated; when no peak
//! of the residual reaches E, the same is done for the peaks of its negative (negative
//! weights); the method stops when neither has a peak above E, or at `max_terms`.

use alloc::vec::Vec;

/// One term `c exp(−(x − μ)²/(2σ²))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GaussianTerm {
    /// Weight c (the height at the mean; negative for the negative-residual pass).
    pub weight: f64,
    /// Mean μ.
    pub mean: f64,
    /// Width σ.
    pub sigma: f64,
}

impl GaussianTerm {
    /// The term's value at x.
    pub(crate) fn value(&self, x: f64) -> f64 {
        let d = (x - self.mean) / self.sigma;
        self.weight * libm::exp(-0.5 * d * d)
    }
}

/// The sum of the terms at every grid point.
/// (The tests' form of the algorithm; the filter runs [`Decomposition`].)
#[cfg(test)]
pub(crate) fn evaluate(terms: &[GaussianTerm], grid: &[f64]) -> Vec<f64> {
    grid.iter()
        .map(|&x| terms.iter().map(|t| t.value(x)).sum())
        .collect()
}

/// Indices of the grid's local maxima of `f` that reach `threshold`, into `found`.
fn peaks(f: &[f64], threshold: f64, found: &mut Vec<usize>) {
    let n = f.len();
    found.clear();
    found.extend((0..n).filter(|&i| {
        let left = if i > 0 { f[i - 1] } else { f64::NEG_INFINITY };
        let right = if i + 1 < n {
            f[i + 1]
        } else {
            f64::NEG_INFINITY
        };
        f[i] >= threshold && f[i] > left && f[i] >= right
    }));
}

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

/// The step of the uniform grid.
fn spacing(grid: &[f64]) -> f64 {
    (grid[grid.len() - 1] - grid[0]) / (grid.len() - 1).max(1) as f64
}

/// The least-squares width of a Gaussian of height `f[i]` at `grid[i]` on `lo..=hi`.
fn fit_sigma(
    grid: &[f64],
    f: &[f64],
    i: usize,
    (lo, hi): (usize, usize),
    tail: &mut Vec<f64>,
) -> f64 {
    let (x0, y0) = (grid[i], f[i]);
    let h = spacing(grid);
    // Beyond 9σ from the peak the Gaussian is below e^{−40.5} of its height: there the
    // residual is y itself, summed once by prefix sums of y² instead of evaluating exp.
    tail.clear();
    tail.push(0.0);
    for &y in &f[lo..=hi] {
        tail.push(tail[tail.len() - 1] + y * y);
    }
    let squares = |from: usize, to: usize| tail[to + 1 - lo] - tail[from - lo];
    let cost = |ln_sigma: f64| {
        let sigma = libm::exp(ln_sigma);
        let reach = libm::ceil(9.0 * sigma / h).min((hi - lo + 1) as f64) as usize;
        let (l, r) = (i.saturating_sub(reach).max(lo), (i + reach).min(hi));
        let inv = 1.0 / sigma;
        let near: f64 = grid[l..=r]
            .iter()
            .zip(&f[l..=r])
            .map(|(&x, &y)| {
                let d = (x - x0) * inv;
                let r = y - y0 * crate::linalg::exp_nonpositive(-0.5 * d * d);
                r * r
            })
            .sum();
        let before = if l > lo { squares(lo, l - 1) } else { 0.0 };
        let after = if r < hi { squares(r + 1, hi) } else { 0.0 };
        near + before + after
    };
    let width = (grid[hi] - grid[lo]).max(h);
    let ln_sigma = minimise(cost, libm::log(0.25 * h), libm::log(2.0 * width), 1e-7);
    libm::exp(ln_sigma)
}

/// The minimum of `f` on `[a, b]` to an absolute tolerance `tol`, by Brent's method:
/// parabolic interpolation through the three best points when it falls inside the bracket and
/// shrinks the step, a golden-section step otherwise (R. P. Brent, *Algorithms for
/// Minimization without Derivatives*, 1973, ch. 5). About 10 evaluations where golden section
/// alone needs 35 for the same tolerance.
fn minimise(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let golden = 0.5 * (3.0 - libm::sqrt(5.0));
    let mut x = a + golden * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x);
    let (mut fw, mut fv) = (fx, fx);
    // The step before last (e) and the last step (d).
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (a + b);
        let tol1 = 1.5e-8 * x.abs() + tol / 3.0;
        let tol2 = 2.0 * tol1;
        if (x - mid).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut parabolic = false;
        if e.abs() > tol1 {
            let r = (x - w) * (fx - fv);
            let q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            let mut q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < mid { tol1 } else { -tol1 };
                }
                parabolic = true;
            }
        }
        if !parabolic {
            e = if x < mid { b - x } else { a - x };
            d = golden * e;
        }
        let u = x + if d.abs() >= tol1 { d } else { tol1.copysign(d) };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    x
}

/// 002 Algorithm 1 on the uniform grid `grid` (ascending) for the values `phi`.
/// (The tests' form of the algorithm; the filter runs [`Decomposition`].)
#[cfg(test)]
pub(crate) fn gaussian_approximation(
    grid: &[f64],
    phi: &[f64],
    alpha: f64,
    max_terms: usize,
) -> Vec<GaussianTerm> {
    decompose(grid, phi, alpha, max_terms).0
}

/// Algorithm 1 with what it leaves: the terms and the residual `phi − Σ terms` on the grid.
/// (The tests' form of the algorithm; the filter runs [`Decomposition`].)
#[cfg(test)]
pub(crate) fn decompose(
    grid: &[f64],
    phi: &[f64],
    alpha: f64,
    max_terms: usize,
) -> (Vec<GaussianTerm>, Vec<f64>) {
    let mut work = Decomposition::with_capacity(phi.len(), max_terms);
    work.run(grid, phi, alpha, max_terms);
    (work.terms, work.residual)
}

/// Algorithm 1 in storage made once: [`Decomposition::run`] leaves the terms and the
/// residual in `terms` and `residual` and allocates nothing once its buffers have reached
/// their working size.
#[derive(Clone, Debug, Default)]
pub(crate) struct Decomposition {
    /// The Gaussians found.
    pub terms: Vec<GaussianTerm>,
    /// `phi − Σ terms` on the grid.
    pub residual: Vec<f64>,
    flipped: Vec<f64>,
    found: Vec<usize>,
    tail: Vec<f64>,
}

impl Decomposition {
    /// Storage for `points` grid values and up to `max_terms` terms.
    pub(crate) fn with_capacity(points: usize, max_terms: usize) -> Self {
        Decomposition {
            terms: Vec::with_capacity(max_terms),
            residual: Vec::with_capacity(points),
            flipped: Vec::with_capacity(points),
            found: Vec::with_capacity(points),
            tail: Vec::with_capacity(points + 1),
        }
    }

    /// Algorithm 1 on the uniform grid `grid` (ascending) for the values `phi`.
    pub(crate) fn run(&mut self, grid: &[f64], phi: &[f64], alpha: f64, max_terms: usize) {
        let Decomposition {
            terms,
            residual,
            flipped,
            found,
            tail,
        } = self;
        let threshold = alpha * phi.iter().copied().fold(0.0, f64::max);
        terms.clear();
        residual.clear();
        residual.extend_from_slice(phi);
        flipped.clear();
        flipped.resize(phi.len(), 0.0);
        let h = spacing(grid);
        while terms.len() < max_terms {
            // Step 2 on the residual, else step 4 on its negative.
            let mut sign = 1.0;
            peaks(residual, threshold, found);
            if found.is_empty() {
                for (f, r) in flipped.iter_mut().zip(residual.iter()) {
                    *f = -r;
                }
                peaks(flipped, threshold, found);
                sign = -1.0;
            }
            if found.is_empty() {
                break;
            }
            let f = if sign > 0.0 { &*residual } else { &*flipped };
            let first = terms.len();
            for &i in found.iter().take(max_terms - first) {
                let sigma = fit_sigma(grid, f, i, neighbourhood(f, i), tail);
                terms.push(GaussianTerm {
                    weight: sign * f[i],
                    mean: grid[i],
                    sigma,
                });
            }
            // Each term only within 9σ of its mean (beyond, below e^{−40.5} of its height).
            for t in &terms[first..] {
                let index = |x: f64| {
                    libm::floor((x - grid[0]) / h).clamp(0.0, (grid.len() - 1) as f64) as usize
                };
                let (l, r) = (
                    index(t.mean - 9.0 * t.sigma),
                    index(t.mean + 9.0 * t.sigma) + 1,
                );
                for (res, &x) in residual[l..r.min(grid.len())].iter_mut().zip(&grid[l..]) {
                    *res -= t.value(x);
                }
            }
        }
    }
}
