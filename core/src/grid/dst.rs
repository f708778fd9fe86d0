//! The type-I discrete sine transform through rustfft, planned once.
//!
//! `X_k = Σ_{n=1}^{N} x_n sin(π n k / (N + 1))`, k = 1..N. It diagonalises the 3-point
//! Dirichlet Laplacian: the eigenvalues of `T = (1/Δs²) tridiag(1, −2, 1)` are
//! `−(4/Δs²) sin²(jπ / (2(N + 1)))` (000 Algorithm 3, line 13). DST-I is its own inverse up to
//! the factor `2/(N + 1)`.
//!
//! Computation (one real FFT of length N + 1 per line, which realfft performs as a complex FFT
//! of half that length): with M = N + 1 and x_0 = x_M = 0, the sequence
//! `y_j = sin(jπ/M)(x_j + x_{M−j}) + ½(x_j − x_{M−j})`, j = 0..M−1, has the real DFT
//! `Σ_j y_j e^{−2πijk/M} = R_k − i I_k` with `I_k = X_{2k}` (the antisymmetric half of y picks out
//! the even sine frequencies) and `R_k = X_{2k+1} − X_{2k−1}` (the symmetric half, through
//! `2 sin a cos b = sin(a + b) + sin(a − b)`), so the odd coefficients follow by the running sum
//! from `X_1 = R_0 / 2`.

use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use realfft::{RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;

/// A planned DST-I of one length with its scratch buffers.
pub struct DstPlan {
    n: usize,
    fft: Arc<dyn RealToComplex<f64>>,
    /// `sin(jπ/(N + 1))`, j = 0..N.
    sines: Vec<f64>,
    input: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    line: Vec<f64>,
}

impl DstPlan {
    /// Plans the transform of length `n` (allocates here, never in `transform`).
    pub fn new(n: usize) -> Self {
        let m = n + 1;
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(m);
        let sines = (0..m)
            .map(|j| libm::sin(j as f64 * core::f64::consts::PI / m as f64))
            .collect();
        DstPlan {
            n,
            sines,
            input: fft.make_input_vec(),
            spectrum: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            line: vec![0.0; n],
            fft,
        }
    }

    /// The length N.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Transforms one line of length N in place.
    pub fn transform(&mut self, x: &mut [f64]) {
        let n = self.n;
        let m = n + 1;
        self.input[0] = 0.0;
        for j in 1..m {
            let (a, b) = (x[j - 1], x[m - j - 1]);
            self.input[j] = self.sines[j] * (a + b) + 0.5 * (a - b);
        }
        let done =
            self.fft
                .process_with_scratch(&mut self.input, &mut self.spectrum, &mut self.scratch);
        // The buffers were made by the plan, so their lengths are right.
        debug_assert!(done.is_ok());
        let mut odd = 0.5 * self.spectrum[0].re;
        x[0] = odd;
        for (k, c) in self.spectrum.iter().enumerate().skip(1) {
            if 2 * k > n {
                break;
            }
            x[2 * k - 1] = -c.im;
            if 2 * k + 1 > n {
                break;
            }
            odd += c.re;
            x[2 * k] = odd;
        }
    }

    /// Transforms every line of a tensor array along the dimension with `stride`, whose lines
    /// have this plan's length.
    pub fn transform_axis(&mut self, data: &mut [f64], stride: usize) {
        let n = self.n;
        if stride == 1 {
            for line in data.chunks_exact_mut(n) {
                self.transform(line);
            }
            return;
        }
        let block = stride * n;
        let mut line = core::mem::take(&mut self.line);
        for l in 0..data.len() / n {
            // Line number l starts at (l / stride) * block + l % stride.
            let s = (l / stride) * block + l % stride;
            for (i, v) in line.iter_mut().enumerate() {
                *v = data[s + i * stride];
            }
            self.transform(&mut line);
            for (i, v) in line.iter().enumerate() {
                data[s + i * stride] = *v;
            }
        }
        self.line = line;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        for n in [1usize, 2, 5, 16, 31, 100] {
            let a: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 4.5).collect();
            let b: Vec<f64> = (0..n).map(|i| ((i * 5 + 1) % 13) as f64 * 0.3).collect();
            let mut plan = DstPlan::new(n);
            let (mut ta, mut tb) = (a.clone(), b.clone());
            plan.transform(&mut ta);
            plan.transform(&mut tb);
            for (x, y) in ta.iter().zip(naive(&a)) {
                assert!((x - y).abs() < 1e-10);
            }
            for (x, y) in tb.iter().zip(naive(&b)) {
                assert!((x - y).abs() < 1e-10);
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
