//! Random numbers: the one seeded generator of a run and the platform-independent normal
//! draws every simulator and random filter uses (same seed, same stream natively and in wasm).

use nalgebra::DVector;
use rand::{RngExt, SeedableRng};

/// The generator of every random number in a run (platform-independent stream).
pub type SimRng = rand::rngs::Xoshiro256PlusPlus;

/// A generator from a seed.
pub fn rng_from_seed(seed: u64) -> SimRng {
    SimRng::seed_from_u64(seed)
}

/// One N(0, 1) draw by the Box–Muller transform, computed with `libm` so that the stream of
/// normals is bit-identical on every platform (a ziggurat sampler's `exp` would come from the
/// platform's maths library natively and from Rust's port in wasm).
pub fn standard_normal<R: rand::Rng + ?Sized>(rng: &mut R) -> f64 {
    // u1 in (0, 1] so that ln u1 is finite.
    let u1 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(core::f64::consts::TAU * u2)
}

/// A vector of independent N(0, 1) draws.
pub fn standard_normal_vector<R: rand::Rng + ?Sized>(rng: &mut R, d: usize) -> DVector<f64> {
    DVector::from_fn(d, |_, _| standard_normal(rng))
}

/// Layers of the normal ziggurat (Marsaglia & Tsang 2000, "The ziggurat method for generating
/// random variables", J. Stat. Softw. 5(8)): 256 strips of equal area [`ZIGGURAT_AREA`] under
/// `f(x) = exp(−x²/2)`, the base strip ending at [`ZIGGURAT_R`].
const ZIGGURAT_LAYERS: usize = 256;
/// Start of the tail, r, for 256 layers (Marsaglia & Tsang 2000, §3).
const ZIGGURAT_R: f64 = 3.654_152_885_361_009;
/// Area of each strip, v, for 256 layers (Marsaglia & Tsang 2000, §3).
const ZIGGURAT_AREA: f64 = 4.928_673_233_99e-3;

/// N(0, 1) draws by the ziggurat method (Marsaglia & Tsang 2000): one 64-bit draw and a
/// comparison for 99 % of the samples (the ziggurat's geometry), so several times faster
/// than [`standard_normal`]'s Box–Muller. Its tables are computed with `libm` in the constructor,
/// so the stream is the same on every platform. The particle filter draws its noise here; the
/// simulators keep [`standard_normal`] so that the simulated truth does not depend on it.
#[derive(Clone, Debug)]
pub(crate) struct NormalZiggurat {
    /// `x[i]`: right edge of strip i (x[0] = v/f(r) for the base strip, x[1] = r, x[256] = 0).
    x: [f64; ZIGGURAT_LAYERS + 1],
    /// `f[i] = exp(−x[i]²/2)`.
    f: [f64; ZIGGURAT_LAYERS + 1],
}

impl Default for NormalZiggurat {
    fn default() -> Self {
        Self::new()
    }
}

impl NormalZiggurat {
    /// Builds the tables: x₁ = r, x_{i+1} = √(−2 ln(v/x_i + f(x_i))).
    pub(crate) fn new() -> Self {
        let density = |x: f64| libm::exp(-0.5 * x * x);
        let mut x = [0.0; ZIGGURAT_LAYERS + 1];
        x[0] = ZIGGURAT_AREA / density(ZIGGURAT_R);
        x[1] = ZIGGURAT_R;
        for i in 1..ZIGGURAT_LAYERS - 1 {
            x[i + 1] = libm::sqrt(-2.0 * libm::log(ZIGGURAT_AREA / x[i] + density(x[i])));
        }
        x[ZIGGURAT_LAYERS] = 0.0;
        let mut f = [0.0; ZIGGURAT_LAYERS + 1];
        for (fi, xi) in f.iter_mut().zip(&x) {
            *fi = density(*xi);
        }
        NormalZiggurat { x, f }
    }

    /// One N(0, 1) draw.
    #[inline]
    pub(crate) fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        loop {
            let bits = rng.next_u64();
            let i = (bits & 0xff) as usize;
            // The top 53 bits as a uniform in [0, 1), mapped to [−1, 1).
            let u = 2.0 * ((bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)) - 1.0;
            let x = u * self.x[i];
            if libm::fabs(x) < self.x[i + 1] {
                return x;
            }
            if i == 0 {
                return self.tail(rng, u < 0.0);
            }
            let y = self.f[i + 1] + (self.f[i] - self.f[i + 1]) * rng.random::<f64>();
            if y < crate::linalg::elementary::exp(-0.5 * x * x) {
                return x;
            }
        }
    }

    /// Marsaglia's tail beyond r: x = −ln(u₁)/r, y = −ln(u₂) until 2y > x².
    #[cold]
    fn tail<R: rand::Rng + ?Sized>(&self, rng: &mut R, negative: bool) -> f64 {
        loop {
            let x = -libm::log(1.0 - rng.random::<f64>()) / ZIGGURAT_R;
            let y = -libm::log(1.0 - rng.random::<f64>());
            if 2.0 * y > x * x {
                let v = ZIGGURAT_R + x;
                return if negative { -v } else { v };
            }
        }
    }

    /// Fills `out` with independent N(0, 1) draws.
    pub(crate) fn fill<R: rand::Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        for v in out {
            *v = self.sample(rng);
        }
    }
}

/// A uniform draw in (0, 1].
fn open_uniform<R: rand::Rng + ?Sized>(rng: &mut R) -> f64 {
    1.0 - rng.random::<f64>()
}

/// One Gamma(`shape`, 1) draw, `shape` > 0 and finite (NaN otherwise), by Marsaglia & Tsang's squeeze method (2000, "A
/// simple method for generating gamma variables", ACM TOMS 26(3)): with d = a − ⅓ and
/// c = 1/√(9d), v = (1 + cξ)³ for a normal ξ is accepted when ln u < ξ²/2 + d − dv + d ln v;
/// for a < 1, Gamma(a) = Gamma(a + 1) · u^{1/a} (their §6). With `libm`, so the stream is the
/// same on every platform.
pub(crate) fn gamma<R: rand::Rng + ?Sized>(rng: &mut R, shape: f64) -> f64 {
    // Not a shape (NaN, infinite, ≤ 0): no draw, and no endless rejection loop.
    if !(shape > 0.0 && shape.is_finite()) {
        return f64::NAN;
    }
    if shape < 1.0 {
        let u = open_uniform(rng);
        return gamma(rng, shape + 1.0) * libm::pow(u, 1.0 / shape);
    }
    let d = shape - 1.0 / 3.0;
    let c = 1.0 / libm::sqrt(9.0 * d);
    loop {
        let xi = standard_normal(rng);
        let t = 1.0 + c * xi;
        if t <= 0.0 {
            continue;
        }
        let v = t * t * t;
        let u = open_uniform(rng);
        if libm::log(u) < 0.5 * xi * xi + d - d * v + d * libm::log(v) {
            return d * v;
        }
    }
}

/// One draw of Student's t with ν = `dof` > 0 degrees of freedom: ξ / √(χ²_ν / ν), with
/// χ²_ν = 2 Gamma(ν/2).
pub(crate) fn student_t<R: rand::Rng + ?Sized>(rng: &mut R, dof: f64) -> f64 {
    let xi = standard_normal(rng);
    let chi2 = 2.0 * gamma(rng, 0.5 * dof);
    xi / libm::sqrt(chi2 / dof)
}

/// One Poisson(`rate`) draw, `rate` ≥ 0 and finite (NaN otherwise), as an `f64`. Below a rate of 10 by
/// multiplying uniforms until the product falls below e^{−λ} (Knuth, TAOCP vol. 2, §3.4.1);
/// from 10 on by Hörmann's transformed rejection with squeeze, PTRS (1993, "The transformed
/// rejection method for generating Poisson random variables", Insurance: Mathematics and
/// Economics 12), whose cost does not grow with λ.
pub(crate) fn poisson<R: rand::Rng + ?Sized>(rng: &mut R, rate: f64) -> f64 {
    // Not a rate (NaN, infinite, < 0): no draw, and no endless loop.
    if !(rate >= 0.0 && rate.is_finite()) {
        return f64::NAN;
    }
    if rate < 10.0 {
        let limit = libm::exp(-rate);
        let mut k = 0.0;
        let mut product = open_uniform(rng);
        while product > limit {
            k += 1.0;
            product *= open_uniform(rng);
        }
        return k;
    }
    let root = libm::sqrt(rate);
    let b = 0.931 + 2.53 * root;
    let a = -0.059 + 0.02483 * b;
    let inverse_alpha = 1.1239 + 1.1328 / (b - 3.4);
    let v_r = 0.9277 - 3.6224 / (b - 2.0);
    let ln_rate = libm::log(rate);
    loop {
        let u = rng.random::<f64>() - 0.5;
        let v = open_uniform(rng);
        let us = 0.5 - libm::fabs(u);
        let k = libm::floor((2.0 * a / us + b) * u + rate + 0.43);
        if us >= 0.07 && v <= v_r {
            return k;
        }
        if k < 0.0 || (us < 0.013 && v > us) {
            continue;
        }
        if libm::log(v) + libm::log(inverse_alpha) - libm::log(a / (us * us) + b)
            <= -rate + k * ln_rate - libm::lgamma(k + 1.0)
        {
            return k;
        }
    }
}

#[cfg(test)]
mod tests {
    /// A shape or rate that is not one gives NaN at once, not an endless rejection loop.
    #[test]
    fn draws_refuse_a_parameter_that_is_not_one() {
        let mut rng = rng_from_seed(1);
        for bad in [f64::NAN, f64::INFINITY, -1.0, 0.0] {
            assert!(gamma(&mut rng, bad).is_nan(), "gamma({bad})");
        }
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            assert!(poisson(&mut rng, bad).is_nan(), "poisson({bad})");
        }
        assert_eq!(poisson(&mut rng, 0.0), 0.0);
    }

    use super::*;
    use crate::testing::test;

    /// The ziggurat's strips: the recurrence closes at 0 (the 255th edge is small and positive),
    /// and every strip has area v.
    #[test]
    fn ziggurat_tables_close() {
        let z = NormalZiggurat::new();
        assert!(z.x[255] > 0.0 && z.x[255] < 0.3, "x[255] = {}", z.x[255]);
        for i in 1..ZIGGURAT_LAYERS - 1 {
            let area = z.x[i] * (z.f[i + 1] - z.f[i]);
            assert!((area - ZIGGURAT_AREA).abs() < 1e-12, "strip {i}: {area}");
        }
    }

    /// 10⁶ draws (seed 7) against N(0, 1): mean and variance within 4 standard errors,
    /// the share beyond the tail start r within 4 standard errors of 2(1 − Φ(r)), and the
    /// Kolmogorov–Smirnov distance on a 2001-point grid below 1.95/√N (0.1 % level).
    #[test]
    fn ziggurat_draws_are_standard_normal() {
        let z = NormalZiggurat::new();
        let mut rng = rng_from_seed(7);
        let count = 1_000_000;
        let mut draws: alloc::vec::Vec<f64> = (0..count).map(|_| z.sample(&mut rng)).collect();
        let n = count as f64;
        let mean = draws.iter().sum::<f64>() / n;
        let var = draws.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
        assert!(mean.abs() < 4.0 / n.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 4.0 * (2.0 / n).sqrt(), "variance {var}");
        let tail_p = libm::erfc(ZIGGURAT_R / core::f64::consts::SQRT_2);
        let tail = draws.iter().filter(|x| x.abs() > ZIGGURAT_R).count() as f64 / n;
        assert!(
            (tail - tail_p).abs() < 4.0 * (tail_p / n).sqrt(),
            "tail {tail} vs {tail_p}"
        );
        draws.sort_by(f64::total_cmp);
        let mut worst: f64 = 0.0;
        for k in 0..=2000 {
            let t = -5.0 + k as f64 * 0.005;
            let below = draws.partition_point(|&x| x <= t) as f64 / n;
            let cdf = 0.5 * libm::erfc(-t / core::f64::consts::SQRT_2);
            worst = worst.max((below - cdf).abs());
        }
        assert!(worst < 1.95 / n.sqrt(), "KS distance {worst}");
    }
}
