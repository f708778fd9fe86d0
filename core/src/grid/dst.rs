//! The type-I discrete sine transform through rustfft, planned once.
//!
//! `X_k = Σ_{n=1}^{N} x_n sin(π n k / (N + 1))`, k = 1..N. It diagonalises the 3-point
//! Dirichlet Laplacian: the eigenvalues of `T = (1/Δs²) tridiag(1, −2, 1)` are
//! `−(4/Δs²) sin²(jπ / (2(N + 1)))` (000 Algorithm 3, line 13). DST-I is its own inverse up to
//! the factor `2/(N + 1)`.
//!
//! Computation: two real lines at once, as the real and imaginary parts of one complex odd
//! extension of length 2(N + 1), whose FFT gives both transforms (−Im and +Re parts / 2).

use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// A planned DST-I of one length with its scratch buffers.
pub struct DstPlan {
    n: usize,
    fft: Arc<dyn Fft<f64>>,
    buffer: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl DstPlan {
    /// Plans the transform of length `n` (allocates here, never in `transform`).
    pub fn new(n: usize) -> Self {
        let m = 2 * (n + 1);
        let fft = FftPlanner::new().plan_fft_forward(m);
        let scratch = vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()];
        DstPlan {
            n,
            fft,
            buffer: vec![Complex::new(0.0, 0.0); m],
            scratch,
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

    /// Transforms two lines in place (`b` may be `None` for a single line).
    pub fn transform_pair(&mut self, a: &mut [f64], b: Option<&mut [f64]>) {
        let n = self.n;
        let m = 2 * (n + 1);
        let buf = &mut self.buffer;
        buf[0] = Complex::new(0.0, 0.0);
        buf[n + 1] = Complex::new(0.0, 0.0);
        match &b {
            Some(b) => {
                for i in 0..n {
                    buf[i + 1] = Complex::new(a[i], b[i]);
                    buf[m - 1 - i] = Complex::new(-a[i], -b[i]);
                }
            }
            None => {
                for i in 0..n {
                    buf[i + 1] = Complex::new(a[i], 0.0);
                    buf[m - 1 - i] = Complex::new(-a[i], 0.0);
                }
            }
        }
        self.fft.process_with_scratch(buf, &mut self.scratch);
        // FFT of the odd extension of x is −2i·DST(x); with x = a + i b it is
        // −2i·DST(a) + 2·DST(b), so DST(a) = −Im/2 and DST(b) = Re/2.
        for k in 0..n {
            a[k] = -0.5 * buf[k + 1].im;
        }
        if let Some(b) = b {
            for k in 0..n {
                b[k] = 0.5 * buf[k + 1].re;
            }
        }
    }

    /// Transforms every line of a tensor array along the dimension with `stride`, whose lines
    /// have this plan's length; `line` is scratch of twice that length.
    pub fn transform_axis(&mut self, data: &mut [f64], stride: usize, line: &mut Vec<f64>) {
        let n = self.n;
        line.resize(2 * n, 0.0);
        let block = stride * n;
        let lines = data.len() / n;
        // Line number l starts at (l / stride) * block + l % stride; take them two at a time.
        let start = |l: usize| (l / stride) * block + l % stride;
        let mut l = 0;
        while l < lines {
            let (la, lb) = line.split_at_mut(n);
            let s0 = start(l);
            for i in 0..n {
                la[i] = data[s0 + i * stride];
            }
            if l + 1 < lines {
                let s1 = start(l + 1);
                for i in 0..n {
                    lb[i] = data[s1 + i * stride];
                }
                self.transform_pair(la, Some(lb));
                for i in 0..n {
                    data[s1 + i * stride] = lb[i];
                }
            } else {
                self.transform_pair(la, None);
            }
            for i in 0..n {
                data[s0 + i * stride] = la[i];
            }
            l += 2;
        }
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
        for n in [1usize, 5, 16, 31] {
            let a: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 4.5).collect();
            let b: Vec<f64> = (0..n).map(|i| ((i * 5 + 1) % 13) as f64 * 0.3).collect();
            let mut plan = DstPlan::new(n);
            let (mut ta, mut tb) = (a.clone(), b.clone());
            plan.transform_pair(&mut ta, Some(&mut tb));
            for (x, y) in ta.iter().zip(naive(&a)) {
                assert!((x - y).abs() < 1e-10);
            }
            for (x, y) in tb.iter().zip(naive(&b)) {
                assert!((x - y).abs() < 1e-10);
            }
            plan.transform_pair(&mut ta, None);
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
        let mut line = Vec::new();
        DstPlan::new(n1).transform_axis(&mut d, n0, &mut line);
        for i in 0..n0 {
            let col: Vec<f64> = (0..n1).map(|j| data[i + j * n0]).collect();
            for (j, v) in naive(&col).iter().enumerate() {
                assert!((d[i + j * n0] - v).abs() < 1e-12);
            }
        }
    }
}
