//! The type-I discrete sine transform through rustfft, planned once.
//!
//! `X_k = Σ_{n=1}^{N} x_n sin(π n k / (N + 1))`, k = 1..N. It diagonalises the 3-point
//! Dirichlet Laplacian: the eigenvalues of `T = (1/Δs²) tridiag(1, −2, 1)` are
//! `−(4/Δs²) sin²(jπ / (2(N + 1)))` (000 Algorithm 3, line 13). DST-I is its own inverse up to
//! the factor `2/(N + 1)`.
//!
//! Computation (one real DFT of length M = N + 1 per line; along an axis of a tensor array, two
//! lines per complex FFT of length M, batched): with x_0 = x_M = 0, the sequence
//! `y_j = sin(jπ/M)(x_j + x_{M−j}) + ½(x_j − x_{M−j})`, j = 0..M−1, has the real DFT
//! `Σ_j y_j e^{−2πijk/M} = R_k − i I_k` with `I_k = X_{2k}` (the antisymmetric half of y picks out
//! the even sine frequencies) and `R_k = X_{2k+1} − X_{2k−1}` (the symmetric half, through
//! `2 sin a cos b = sin(a + b) + sin(a − b)`), so the odd coefficients follow by the running sum
//! from `X_1 = R_0 / 2`.
//!
//! A single line's real DFT, for even M = 2L: the complex FFT of length L of
//! `z_j = y_{2j} + i y_{2j+1}` gives `E_k = (Z_k + conj Z_{L−k})/2` and
//! `O_k = (Z_k − conj Z_{L−k})/(2i)`, the DFTs of the even and odd samples, and
//! `Y_k = E_k + e^{−2πik/M} O_k` — computed inside the unpacking pass, so that the spectrum is
//! never stored. For odd M, the complex FFT of length M of y itself. Where L is odd with a
//! prime factor from 13 to 31 (N = 2001: L = 1001 = 7·11·13), the FFT of length L is
//! `odd_fft`'s vectorised Stockham stages instead of rustfft's plan, whose butterflies for
//! those primes are scalar.

use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use super::odd_fft::OddFft;

/// A planned DST-I of one length with its scratch buffers. (Public for the benchmark of a bare
/// transform pair, through `zakai::internals` with the feature `unstable-internals`; without
/// it, unreachable.)
#[derive(Clone)]
#[cfg_attr(not(feature = "unstable-internals"), allow(unreachable_pub))]
pub struct DstPlan {
    n: usize,
    /// One line's real DFT through a complex FFT of half the length (M even).
    half: Option<HalfLength>,
    /// Complex FFT of length N + 1 for two lines at once (their sequences y as real and
    /// imaginary part), run over a whole axis in one batch; also one line of odd M alone.
    pair_fft: Arc<dyn Fft<f64>>,
    /// `sin(jπ/(N + 1))`, j = 0..N.
    sines: Vec<f64>,
    /// The batch of paired lines of one axis, or one line of odd M (grown on first use, then
    /// reused).
    batch: Vec<Complex<f64>>,
    pair_scratch: Vec<Complex<f64>>,
    /// One block of a strided axis, transposed into consecutive lines.
    line: Vec<f64>,
}

impl core::fmt::Debug for DstPlan {
    /// The length (the FFT plans are opaque).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DstPlan")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}

/// The real DFT of one line of even length M = 2L by a complex FFT of length L (module doc).
#[derive(Clone)]
struct HalfLength {
    fft: Arc<dyn Fft<f64>>,
    /// The same FFT by vectorised Stockham stages, where the length is odd with a factor
    /// rustfft runs as a scalar butterfly.
    odd: Option<OddFft>,
    /// `z_j = y_{2j} + i y_{2j+1}`, transformed in place.
    z: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    /// `−(i/2) e^{−2πik/M}`, k = 0..L−1.
    twiddles: Vec<Complex<f64>>,
}

/// Writes X_1..X_N into `x` from the real DFT `Y_k = R_k − i I_k` of y, k = 0, 1, … (see the
/// module doc): `X_{2k} = I_k`, `X_{2k+1} = X_{2k−1} + R_k`, `X_1 = R_0/2`.
#[inline(always)]
fn unpack(mut spectrum: impl Iterator<Item = Complex<f64>>, x: &mut [f64]) {
    let mut odd = 0.5 * spectrum.next().unwrap_or_default().re;
    x[0] = odd;
    // (x[2k−1], x[2k]) = (X_{2k}, X_{2k+1}), the last pair possibly cut short.
    for (pair, c) in x[1..].chunks_mut(2).zip(spectrum) {
        pair[0] = -c.im;
        if let Some(v) = pair.get_mut(1) {
            odd += c.re;
            *v = odd;
        }
    }
}

/// `(Z_k, conj Z_{L−k})` for k = 0..L−1, with `Z_L = Z_0`.
fn with_mirror(z: &[Complex<f64>]) -> impl Iterator<Item = (Complex<f64>, Complex<f64>)> + '_ {
    let mirror = core::iter::once(&z[0]).chain(z[1..].iter().rev());
    z.iter().zip(mirror).map(|(a, b)| (*a, b.conj()))
}

/// `y_j = sin(jπ/M)(x_j + x_{M−j}) + ½(x_j − x_{M−j})` from `s = sin(jπ/M)`, `a = x_j`,
/// `b = x_{M−j}`.
#[inline(always)]
fn mix(s: f64, a: f64, b: f64) -> f64 {
    s * (a + b) + 0.5 * (a - b)
}

/// The pairs `(x_j, x_{M−j})`, j = 1..M−1, of x (length M − 1): a forward and a backward walk,
/// without index arithmetic, so that the loops over them vectorise.
fn ends(x: &[f64]) -> impl Iterator<Item = (&f64, &f64)> {
    x.iter().zip(x.iter().rev())
}

crate::linalg::simd::per_node_kernel! { wide:
    /// `y_0 = 0`, `y_j = mix(sin(jπ/M), x_j, x_{M−j})` for one line.
    fn mix_line(y: &mut [f64], sines: &[f64], x: &[f64]) {
        y[0] = 0.0;
        for ((y, s), (a, b)) in y[1..].iter_mut().zip(&sines[1..]).zip(ends(x)) {
            *y = mix(*s, *a, *b);
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    /// [`unpack`] of one line's real DFT `Y_k = (Z_k + conj Z_{L−k})/2 + t_k (Z_k − conj Z_{L−k})`
    /// from the half-length FFT Z and the twiddles t (module doc; `Z_L = Z_0`).
    /// k and L − k together: with `E = (Z_k + conj Z_{L−k})/2` and `D = Z_k − conj Z_{L−k}`,
    /// `Y_k = E + t_k D` and, since `t_{L−k} = conj t_k` (M = 2L), `Y_{L−k} = conj(E − t_k D)` —
    /// one complex product for two coefficients. Then the odd coefficients' running sum.
    fn unpack_half(z: &[Complex<f64>], twiddles: &[Complex<f64>], x: &mut [f64]) {
        let l = z.len();
        // Y_0 = E_0 + O_0, the sums of the even and of the odd samples: X_1 = Y_0 / 2.
        let mut odd = 0.5 * (z[0].re + z[0].im);
        x[0] = odd;
        // x[1..] has 2L − 2 slots: k = 1..=half forward, L − k backward from the end, and for
        // even L the middle k = L/2 alone. The odd coefficients `X_{2k+1} = X_1 + R_1 + … + R_k`
        // as a prefix sum in the front and, in the back, as `total − (R_{k+1} + … + R_{L−1})`:
        // two independent chains in the same loop, the total added once both are known.
        let half = (l - 1) / 2;
        let (front, rest) = x[1..].split_at_mut(2 * half);
        let (middle, back) = rest.split_at_mut(rest.len() - 2 * half);
        let upper = z[l - half..].iter().rev();
        let pairs = front.chunks_exact_mut(2).zip(back.rchunks_exact_mut(2));
        let mut later = 0.0;
        for (((p, q), (a, b)), t) in pairs.zip(z[1..=half].iter().zip(upper)).zip(&twiddles[1..]) {
            let (a, b) = (*a, b.conj());
            let e = (a + b) * 0.5;
            let td = t * (a - b);
            let (lo, hi) = (e + td, e - td);
            p[0] = -lo.im;
            odd += lo.re;
            p[1] = odd;
            q[0] = hi.im;
            q[1] = -later;
            later += hi.re;
        }
        if let [im, re] = middle {
            // k = L/2: Z_k and Z_{L−k} are the same.
            let a = z[l / 2];
            let c = (a + a.conj()) * 0.5 + twiddles[l / 2] * (a - a.conj());
            *im = -c.im;
            odd += c.re;
            *re = odd;
        }
        let total = odd + later;
        for q in back.chunks_exact_mut(2) {
            q[1] += total;
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    /// The sequences y of consecutive pairs of lines of length n, as the real and imaginary
    /// parts of one complex sequence of length n + 1 per pair: `z = y_a + i y_b`.
    fn mix_pairs(batch: &mut [Complex<f64>], sines: &[f64], data: &[f64], n: usize) {
        for (two, z) in data.chunks_exact(2 * n).zip(batch.chunks_exact_mut(n + 1)) {
            let (la, lb) = two.split_at(n);
            z[0] = Complex::new(0.0, 0.0);
            let both = ends(la).zip(ends(lb));
            for ((v, s), ((a1, b1), (a2, b2))) in z[1..].iter_mut().zip(&sines[1..]).zip(both) {
                *v = Complex::new(mix(*s, *a1, *b1), mix(*s, *a2, *b2));
            }
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    /// Both lines of every pair from the FFT Z of `z = y_a + i y_b`:
    /// `Y_a = (Z_k + conj Z_{M−k})/2`, `Y_b = (Z_k − conj Z_{M−k})/(2i)`, then [`unpack`].
    fn unpack_pairs(data: &mut [f64], batch: &[Complex<f64>], n: usize) {
        for (two, z) in data.chunks_exact_mut(2 * n).zip(batch.chunks_exact(n + 1)) {
            let (la, lb) = two.split_at_mut(n);
            unpack(with_mirror(z).map(|(a, b)| (a + b) * 0.5), la);
            unpack(
                with_mirror(z).map(|(a, b)| (a - b) * Complex::new(0.0, -0.5)),
                lb,
            );
        }
    }
}

#[cfg_attr(not(feature = "unstable-internals"), allow(unreachable_pub))]
impl DstPlan {
    /// Plans the transform of length `n` (allocates here; a whole-axis batch grows once on
    /// the first [`DstPlan::transform_axis`], never in later ones).
    pub fn new(n: usize) -> Self {
        let m = n + 1;
        let mut planner = FftPlanner::<f64>::new();
        let pair_fft = planner.plan_fft_forward(m);
        let sines = (0..m)
            .map(|j| libm::sin(j as f64 * core::f64::consts::PI / m as f64))
            .collect();
        let half = m.is_multiple_of(2).then(|| {
            let l = m / 2;
            let fft = planner.plan_fft_forward(l);
            let twiddles = (0..l)
                .map(|k| {
                    let theta = 2.0 * core::f64::consts::PI * k as f64 / m as f64;
                    Complex::new(0.0, -0.5) * Complex::new(libm::cos(theta), -libm::sin(theta))
                })
                .collect();
            HalfLength {
                odd: OddFft::plan(l),
                z: vec![Complex::new(0.0, 0.0); l],
                scratch: vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()],
                fft,
                twiddles,
            }
        });
        DstPlan {
            n,
            half,
            sines,
            pair_scratch: vec![Complex::new(0.0, 0.0); pair_fft.get_inplace_scratch_len()],
            batch: Vec::new(),
            line: Vec::new(),
            pair_fft,
        }
    }

    /// Transforms one line of length N in place.
    pub fn transform(&mut self, x: &mut [f64]) {
        match &mut self.half {
            Some(h) => {
                mix_line(bytemuck::cast_slice_mut(&mut h.z), &self.sines, x);
                let spectrum = match &mut h.odd {
                    Some(odd) => odd.process(&mut h.z),
                    None => {
                        h.fft.process_with_scratch(&mut h.z, &mut h.scratch);
                        &h.z
                    }
                };
                unpack_half(spectrum, &h.twiddles, x);
            }
            None => {
                let z = &mut self.batch;
                z.resize(self.n + 1, Complex::new(0.0, 0.0));
                z[0] = Complex::new(0.0, 0.0);
                for ((z, s), (a, b)) in z[1..].iter_mut().zip(&self.sines[1..]).zip(ends(x)) {
                    *z = Complex::new(mix(*s, *a, *b), 0.0);
                }
                self.pair_fft
                    .process_with_scratch(z, &mut self.pair_scratch);
                unpack(z.iter().copied(), x);
            }
        }
    }

    /// Transforms every line of a tensor array along the dimension with `stride`, whose lines
    /// have this plan's length. Lines along a strided dimension are first brought together
    /// by a tiled transpose of each block, so that every pass reads memory in order.
    pub fn transform_axis(&mut self, data: &mut [f64], stride: usize) {
        if stride == 1 {
            self.transform_lines(data);
            return;
        }
        let block = stride * self.n;
        let mut lines = core::mem::take(&mut self.line);
        lines.resize(block, 0.0);
        for chunk in data.chunks_exact_mut(block) {
            // chunk: n rows (position along the line) × stride columns (the lines).
            transpose(chunk, self.n, stride, &mut lines);
            self.transform_lines(&mut lines);
            transpose(&lines, stride, self.n, chunk);
        }
        self.line = lines;
    }

    /// Transforms consecutive lines of length N: two lines per complex FFT (`z = y_a + i y_b`,
    /// then `Y_a = (Z_k + conj Z_{M−k})/2`, `Y_b = (Z_k − conj Z_{M−k})/(2i)`), all pairs in one
    /// batched FFT call; an odd last line goes through [`DstPlan::transform`].
    fn transform_lines(&mut self, data: &mut [f64]) {
        let n = self.n;
        let m = n + 1;
        let lines = data.len() / n;
        let pairs = lines / 2;
        if pairs > 0 {
            self.batch.resize(pairs * m, Complex::new(0.0, 0.0));
            let whole = &mut data[..2 * n * pairs];
            mix_pairs(&mut self.batch, &self.sines, whole, n);
            self.pair_fft
                .process_with_scratch(&mut self.batch, &mut self.pair_scratch);
            unpack_pairs(whole, &self.batch, n);
        }
        if lines % 2 == 1 {
            let last = (lines - 1) * n;
            self.transform(&mut data[last..last + n]);
        }
    }
}

/// `dst = srcᵀ` for `src` of `rows × cols` (row-major), in 16 × 16 tiles.
fn transpose(src: &[f64], rows: usize, cols: usize, dst: &mut [f64]) {
    const TILE: usize = 16;
    for r0 in (0..rows).step_by(TILE) {
        for c0 in (0..cols).step_by(TILE) {
            for r in r0..(r0 + TILE).min(rows) {
                for c in c0..(c0 + TILE).min(cols) {
                    dst[c * rows + r] = src[r * cols + c];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    fn naive(x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (1..=n)
            .map(|k| {
                (1..=n)
                    .map(|j| {
                        x[j - 1] * (core::f64::consts::PI * (j * k) as f64 / (n + 1) as f64).sin()
                    })
                    .sum()
            })
            .collect()
    }

    #[test]
    fn matches_the_definition_and_inverts_itself() {
        // M = N + 1 odd (one full-length FFT: 2, 4, 16, 100, 2000) and even, its half L odd
        // (pairs k, L − k only: 1, 5, 25, 1001) or even (a middle k = L/2 too: 3, 31, 1999).
        for n in [1usize, 2, 3, 4, 5, 16, 25, 31, 100, 1001, 1999, 2000] {
            let a: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 4.5).collect();
            let b: Vec<f64> = (0..n).map(|i| ((i * 5 + 1) % 13) as f64 * 0.3).collect();
            let mut plan = DstPlan::new(n);
            let (mut ta, mut tb) = (a.clone(), b.clone());
            plan.transform(&mut ta);
            plan.transform(&mut tb);
            // Round-off (ours and the naive sum's) relative to the coefficients' size.
            let tolerance = |y: f64| 1e-12 * (1.0 + y.abs().max(n as f64));
            for (x, y) in ta.iter().zip(naive(&a)) {
                assert!((x - y).abs() < tolerance(y), "n = {n}: {x} {y}");
            }
            for (x, y) in tb.iter().zip(naive(&b)) {
                assert!((x - y).abs() < tolerance(y), "n = {n}: {x} {y}");
            }
            plan.transform(&mut ta);
            let scale = 2.0 / (n + 1) as f64;
            for (x, y) in ta.iter().zip(&a) {
                assert!((x * scale - y).abs() < 1e-10);
            }
        }
    }

    #[test]
    fn axis_transform_of_a_2d_array() {
        let (n0, n1) = (4usize, 3usize);
        let data: Vec<f64> = (0..n0 * n1).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut d = data.clone();
        DstPlan::new(n1).transform_axis(&mut d, n0);
        for i in 0..n0 {
            let col: Vec<f64> = (0..n1).map(|j| data[i + j * n0]).collect();
            for (j, v) in naive(&col).iter().enumerate() {
                assert!((d[i + j * n0] - v).abs() < 1e-12);
            }
        }
        let mut rows = data.clone();
        DstPlan::new(n0).transform_axis(&mut rows, 1);
        for j in 0..n1 {
            let row = &data[j * n0..(j + 1) * n0];
            for (i, v) in naive(row).iter().enumerate() {
                assert!((rows[i + j * n0] - v).abs() < 1e-12);
            }
        }
    }
}
