//! A complex FFT of odd length whose prime factors are at most 31 and include one that rustfft
//! runs as a scalar butterfly, by Stockham's self-sorting stages vectorised across the
//! stage's independent sequences.
//!
//! rustfft's AVX planner has vector butterflies for the factors 2, 3, 5, 7 and 11 only; a
//! length with a prime factor from 13 to 31 — QIEM's 1-D grid of 2001 nodes, whose DST needs
//! an FFT of length 1001 = 7·11·13 — spends half its time in that factor's scalar butterflies.
//!
//! A stage of radix r on sequences of length n = r m interleaved with stride s (the first stage:
//! one sequence, s = 1) is the decimation in frequency
//!
//! `X_{r k' + k} = Σ_{p < m} W_m^{p k'} · [W_n^{p k} Σ_{j < r} x_{p + j m} W_r^{j k}]`,
//!
//! `W_n = e^{−2πi/n}`: each bracket `y_k(p)` is written to `q + s (r p + k)` (q the sequence), and
//! the next stage transforms the r s sequences of length m so formed. After the last stage the
//! values stand in natural order (Stockham's autosort: no digit reversal). Within a stage, the
//! flat index `f = q + s p` runs over `s m = L / r` consecutive inputs for every j, so the
//! butterflies of consecutive f are one vector operation; each output lane goes to its own
//! `q + s (r p + k)`. The length-r DFT uses the input's pairs: with `a_j = x_j + x_{r−j}` and
//! `b_j = x_j − x_{r−j}`, `A_k = x₀ + Σ_j a_j cos(2πjk/r)` and `B_k = Σ_j b_j sin(2πjk/r)` give
//! `X_k = A_k − i B_k` and `X_{r−k} = A_k + i B_k`, j, k = 1..(r − 1)/2.

use alloc::vec;
use alloc::vec::Vec;

use rustfft::num_complex::Complex;

/// The radices a plan may use: the odd primes up to 31 (the DFT's `((r − 1)/2)²` products per
/// pair stop paying beyond).
const RADICES: [usize; 10] = [31, 29, 23, 19, 17, 13, 11, 7, 5, 3];

/// The least prime factor rustfft's AVX planner runs as a scalar butterfly: a length without
/// one is left to rustfft.
const SCALAR_IN_RUSTFFT: usize = 13;

/// One radix-r stage: `r m` = the sequences' length, `stride` = s.
#[derive(Clone, Debug)]
// Read by the vector stages only (no plan is made without them).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
struct Stage {
    radix: usize,
    stride: usize,
    m: usize,
    /// `W_n^{p k}` at flat index f (p = f / s), k = 1..r, as `[re, re]` pairs: row k − 1 holds
    /// `2 s m` f64.
    twiddle_re: Vec<f64>,
    /// The same as `[−im, im]`: `x W = x ⊙ twiddle_re + swap(x) ⊙ twiddle_im`.
    twiddle_im: Vec<f64>,
    /// `cos(2πjk/r)` and `sin(2πjk/r)`, j, k = 1..=(r − 1)/2, row j.
    cos: Vec<f64>,
    sin: Vec<f64>,
}

/// A planned forward FFT of one odd length by [`Stage`]s.
#[derive(Clone, Debug)]
pub(crate) struct OddFft {
    stages: Vec<Stage>,
    /// The other half of each stage's ping-pong.
    buffer: Vec<Complex<f64>>,
}

impl OddFft {
    /// The plan for `len`, when its prime factors are all in [`RADICES`], one is at least
    /// [`SCALAR_IN_RUSTFFT`], and the stages run as vector operations here (AVX2) — else
    /// rustfft's own plan is as fast or faster.
    pub(crate) fn plan(len: usize) -> Option<OddFft> {
        if !vector_stages_available() {
            return None;
        }
        let mut rest = len;
        let mut radices = Vec::new();
        for &r in &RADICES {
            while rest.is_multiple_of(r) {
                radices.push(r);
                rest /= r;
            }
        }
        // Every stage's flat length L / r at least one vector of four complex numbers.
        let largest = radices.first().copied().unwrap_or(1);
        if rest != 1 || largest < SCALAR_IN_RUSTFFT || len < 4 * largest {
            return None;
        }
        let (mut n, mut stride) = (len, 1);
        let stages = radices
            .into_iter()
            .map(|radix| {
                let stage = Stage::new(radix, n, stride);
                n /= radix;
                stride *= radix;
                stage
            })
            .collect();
        Some(OddFft {
            stages,
            buffer: vec![Complex::new(0.0, 0.0); len],
        })
    }

    /// The forward FFT of `z` (this plan's length); `z` is overwritten, and the result is
    /// where the returned slice points (`z` itself or the plan's buffer).
    pub(crate) fn process<'a>(&'a mut self, z: &'a mut [Complex<f64>]) -> &'a [Complex<f64>] {
        let mut from: &mut [Complex<f64>] = z;
        let mut to: &mut [Complex<f64>] = &mut self.buffer;
        for stage in &self.stages {
            stage.run(bytemuck::cast_slice(from), bytemuck::cast_slice_mut(to));
            core::mem::swap(&mut from, &mut to);
        }
        from
    }
}

impl Stage {
    fn new(radix: usize, n: usize, stride: usize) -> Stage {
        let m = n / radix;
        let flat = stride * m;
        let turn = -2.0 * core::f64::consts::PI / n as f64;
        let mut twiddle_re = Vec::with_capacity(2 * (radix - 1) * flat);
        let mut twiddle_im = Vec::with_capacity(2 * (radix - 1) * flat);
        for k in 1..radix {
            for f in 0..flat {
                // p k < n: the angle is reduced exactly.
                let angle = turn * ((f / stride) * k) as f64;
                let (s, c) = (libm::sin(angle), libm::cos(angle));
                twiddle_re.extend([c, c]);
                twiddle_im.extend([-s, s]);
            }
        }
        let half = (radix - 1) / 2;
        let unit = 2.0 * core::f64::consts::PI / radix as f64;
        let table = |f: fn(f64) -> f64| -> Vec<f64> {
            (1..=half)
                .flat_map(|j| (1..=half).map(move |k| f(unit * ((j * k) % radix) as f64)))
                .collect()
        };
        Stage {
            radix,
            stride,
            m,
            twiddle_re,
            twiddle_im,
            cos: table(libm::cos),
            sin: table(libm::sin),
        }
    }

    /// This stage from `x` into `y` (interleaved complex numbers, the plan's length).
    fn run(&self, x: &[f64], y: &mut [f64]) {
        match self.radix {
            3 => self.run_radix::<1>(x, y),
            5 => self.run_radix::<2>(x, y),
            7 => self.run_radix::<3>(x, y),
            11 => self.run_radix::<5>(x, y),
            13 => self.run_radix::<6>(x, y),
            17 => self.run_radix::<8>(x, y),
            19 => self.run_radix::<9>(x, y),
            23 => self.run_radix::<11>(x, y),
            29 => self.run_radix::<14>(x, y),
            31 => self.run_radix::<15>(x, y),
            _ => unreachable!("the radix is one of RADICES"),
        }
    }

    /// [`Stage::run`] for `r = 2H + 1`, with the widest vectors the CPU has.
    fn run_radix<const H: usize>(&self, x: &[f64], y: &mut [f64]) {
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        {
            assert!(x.len() == 2 * self.len() && y.len() == x.len());
            if std::is_x86_feature_detected!("avx512f") {
                // SAFETY: AVX-512F is checked just above, and the lengths of x and y; the
                // tables have the lengths `Stage::new` gave them.
                return unsafe { vectors::stage_avx512::<H>(self, x, y) };
            }
            // SAFETY: a plan exists only where AVX2 and FMA do (`vector_stages_available`).
            unsafe { vectors::stage_avx2::<H>(self, x, y) }
        }
        #[cfg(not(all(feature = "std", target_arch = "x86_64")))]
        unreachable!("no plan is made without AVX2 ({x:p}, {y:p})")
    }

    /// The plan's length.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    fn len(&self) -> usize {
        self.radix * self.stride * self.m
    }
}

/// Whether the stages run as vector operations here (AVX2 with FMA); without them rustfft's
/// scalar butterflies are as fast, and no plan is made.
fn vector_stages_available() -> bool {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    return std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma");
    #[allow(unreachable_code)]
    false
}

#[cfg(all(feature = "std", target_arch = "x86_64"))]
mod vectors {
    use core::arch::x86_64::*;

    use super::Stage;

    /// Complex numbers as `[re, im]` lane pairs, `COMPLEX` per vector, and the arithmetic a
    /// stage does on them.
    trait Lanes: Copy {
        const COMPLEX: usize;
        /// # Safety: `COMPLEX` complex numbers readable at `at`.
        unsafe fn load(at: *const f64) -> Self;
        /// # Safety: `COMPLEX` complex numbers writable at `at`.
        unsafe fn store(self, at: *mut f64);
        /// Lane `lane`'s complex number to `at`. # Safety: two f64 writable at `at`.
        unsafe fn store_one(self, lane: usize, at: *mut f64);
        fn add(self, other: Self) -> Self;
        fn sub(self, other: Self) -> Self;
        fn mul(self, other: Self) -> Self;
        /// `self · b + c`, rounded once.
        fn mul_add(self, b: Self, c: Self) -> Self;
        fn splat(c: f64) -> Self;
        /// `(re, im) → (im, re)` in every pair.
        fn swap(self) -> Self;
        /// `(re, im) → (im, −re)`: the product by −i.
        fn times_minus_i(self) -> Self;
    }

    /// Defines [`Lanes`] for one vector type from its intrinsics. Its methods are only
    /// reached from the `stage_*` function compiled with that type's features.
    macro_rules! lanes {
        ($t:ty, $complex:expr, $load:ident, $store:ident, $add:ident, $sub:ident, $mul:ident,
         $fma:ident, $set1:ident, $permute:ident, $swap:expr, $sign:expr, $one:expr) => {
            impl Lanes for $t {
                const COMPLEX: usize = $complex;
                #[inline(always)]
                unsafe fn load(at: *const f64) -> Self {
                    // SAFETY: the caller's.
                    unsafe { $load(at) }
                }
                #[inline(always)]
                unsafe fn store(self, at: *mut f64) {
                    // SAFETY: the caller's.
                    unsafe { $store(at, self) }
                }
                #[inline(always)]
                unsafe fn store_one(self, lane: usize, at: *mut f64) {
                    // SAFETY: the caller's.
                    unsafe { _mm_storeu_pd(at, $one(self, lane)) }
                }
                #[inline(always)]
                fn add(self, o: Self) -> Self {
                    // SAFETY (here and below): the type's features are enabled (macro doc).
                    unsafe { $add(self, o) }
                }
                #[inline(always)]
                fn sub(self, o: Self) -> Self {
                    unsafe { $sub(self, o) }
                }
                #[inline(always)]
                fn mul(self, o: Self) -> Self {
                    unsafe { $mul(self, o) }
                }
                #[inline(always)]
                fn mul_add(self, b: Self, c: Self) -> Self {
                    unsafe { $fma(self, b, c) }
                }
                #[inline(always)]
                fn splat(c: f64) -> Self {
                    unsafe { $set1(c) }
                }
                #[inline(always)]
                fn swap(self) -> Self {
                    unsafe { $permute(self, $swap) }
                }
                #[inline(always)]
                fn times_minus_i(self) -> Self {
                    unsafe { $mul(self.swap(), $sign) }
                }
            }
        };
    }

    /// Lane `lane` of two complex numbers.
    #[inline(always)]
    unsafe fn one_of_two(v: __m256d, lane: usize) -> __m128d {
        // SAFETY: AVX (macro doc of `lanes`).
        unsafe {
            if lane == 0 {
                _mm256_castpd256_pd128(v)
            } else {
                _mm256_extractf128_pd(v, 1)
            }
        }
    }

    /// Lane `lane` of four complex numbers.
    #[inline(always)]
    unsafe fn one_of_four(v: __m512d, lane: usize) -> __m128d {
        // SAFETY: AVX-512F (macro doc of `lanes`).
        unsafe {
            let half = if lane < 2 {
                _mm512_castpd512_pd256(v)
            } else {
                _mm512_extractf64x4_pd(v, 1)
            };
            one_of_two(half, lane % 2)
        }
    }

    lanes!(
        __m256d,
        2,
        _mm256_loadu_pd,
        _mm256_storeu_pd,
        _mm256_add_pd,
        _mm256_sub_pd,
        _mm256_mul_pd,
        _mm256_fmadd_pd,
        _mm256_set1_pd,
        _mm256_permute_pd,
        0b0101,
        _mm256_set_pd(-1.0, 1.0, -1.0, 1.0),
        one_of_two
    );
    lanes!(
        __m512d,
        4,
        _mm512_loadu_pd,
        _mm512_storeu_pd,
        _mm512_add_pd,
        _mm512_sub_pd,
        _mm512_mul_pd,
        _mm512_fmadd_pd,
        _mm512_set1_pd,
        _mm512_permute_pd,
        0b0101_0101,
        _mm512_set_pd(-1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0),
        one_of_four
    );

    /// A stage with two complex numbers per vector.
    ///
    /// # Safety
    ///
    /// The CPU must support AVX2 and FMA; x and y hold the plan's length.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn stage_avx2<const H: usize>(st: &Stage, x: &[f64], y: &mut [f64]) {
        // SAFETY: the caller's.
        unsafe { stage::<__m256d, H>(st, x, y) }
    }

    /// A stage with four complex numbers per vector.
    ///
    /// # Safety
    ///
    /// The CPU must support AVX-512F; x and y hold the plan's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn stage_avx512<const H: usize>(st: &Stage, x: &[f64], y: &mut [f64]) {
        // SAFETY: the caller's.
        unsafe { stage::<__m512d, H>(st, x, y) }
    }

    /// The radix-(2H + 1) butterflies of a stage (module doc) on `V::COMPLEX` consecutive flat
    /// indices at a time; the last block overlaps the one before when `V::COMPLEX` does not
    /// divide the flat length (out of place, its common values are written twice alike).
    ///
    /// # Safety
    ///
    /// V's features are enabled; x and y hold `2 r s m` f64; the flat length `s m` is at
    /// least `V::COMPLEX` (`OddFft::plan`).
    #[inline(always)]
    unsafe fn stage<V: Lanes, const H: usize>(st: &Stage, x: &[f64], y: &mut [f64]) {
        let r = 2 * H + 1;
        let flat = st.stride * st.m;
        let width = V::COMPLEX;
        assert!(flat >= width && x.len() == 2 * r * flat && y.len() == x.len());
        assert!(st.twiddle_re.len() == 2 * (r - 1) * flat);
        assert!(st.twiddle_im.len() == st.twiddle_re.len());
        assert!(st.cos.len() == H * H && st.sin.len() == H * H);
        let (xp, yp) = (x.as_ptr(), y.as_mut_ptr());
        let (re, im) = (st.twiddle_re.as_ptr(), st.twiddle_im.as_ptr());
        let starts = (0..flat - width + 1).step_by(width);
        let last = (!flat.is_multiple_of(width)).then_some(flat - width);
        for f in starts.chain(last) {
            // SAFETY: inputs `f + j flat + width ≤ r flat`, twiddles `(k − 1) flat + f + width
            // ≤ (r − 1) flat`, outputs `q + s (r p + k) < r flat` for every lane (lengths
            // asserted above).
            unsafe {
                let first = V::load(xp.add(2 * f));
                let mut a = [first; H];
                let mut b = [first; H];
                let mut sum = first;
                for j in 0..H {
                    let lo = V::load(xp.add(2 * (f + (j + 1) * flat)));
                    let hi = V::load(xp.add(2 * (f + (r - 1 - j) * flat)));
                    a[j] = lo.add(hi);
                    b[j] = lo.sub(hi);
                    sum = sum.add(a[j]);
                }
                put(st, yp, f, 0, sum);
                for k in 0..H {
                    let (mut big_a, mut big_b) = (first, V::splat(0.0));
                    for j in 0..H {
                        let at = j * H + k;
                        big_a = a[j].mul_add(V::splat(st.cos[at]), big_a);
                        big_b = b[j].mul_add(V::splat(st.sin[at]), big_b);
                    }
                    let turned = big_b.times_minus_i();
                    let (lo, hi) = (k + 1, r - 1 - k);
                    put(
                        st,
                        yp,
                        f,
                        lo,
                        twiddled(st, re, im, f, lo, big_a.add(turned)),
                    );
                    put(
                        st,
                        yp,
                        f,
                        hi,
                        twiddled(st, re, im, f, hi, big_a.sub(turned)),
                    );
                }
            }
        }
    }

    /// Output k of the block at flat index f: the last stage's lanes are consecutive (q = f,
    /// s k apart), the others' go one by one to `q + s (r p + k)` with `f = q + s p`.
    ///
    /// # Safety
    ///
    /// As [`stage`]'s; `f` a block of it.
    #[inline(always)]
    unsafe fn put<V: Lanes>(st: &Stage, y: *mut f64, f: usize, k: usize, v: V) {
        // SAFETY: the outputs lie in y (the caller's).
        unsafe {
            if st.m == 1 {
                v.store(y.add(2 * (f + st.stride * k)));
            } else {
                for lane in 0..V::COMPLEX {
                    let g = f + lane;
                    let (p, q) = (g / st.stride, g % st.stride);
                    v.store_one(lane, y.add(2 * (q + st.stride * (st.radix * p + k))));
                }
            }
        }
    }

    /// `v W_n^{p k}` for the block at flat index f (every twiddle is 1 in the last stage).
    ///
    /// # Safety
    ///
    /// As [`stage`]'s; `re` and `im` the stage's tables, `f` a block of it, `k ≥ 1`.
    #[inline(always)]
    unsafe fn twiddled<V: Lanes>(
        st: &Stage,
        re: *const f64,
        im: *const f64,
        f: usize,
        k: usize,
        v: V,
    ) -> V {
        if st.m == 1 {
            return v;
        }
        let at = 2 * ((k - 1) * st.stride * st.m + f);
        // SAFETY: the tables hold `(r − 1) s m` complex numbers (the caller's).
        unsafe {
            v.swap()
                .mul_add(V::load(im.add(at)), v.mul(V::load(re.add(at))))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use rustfft::FftPlanner;

    #[test]
    fn equals_rustfft() {
        let mut planner = FftPlanner::<f64>::new();
        // Flat lengths of one vector (13·5, 31·5) and odd ones, where the last block overlaps
        // (1001: 77, 91, 143), repeated radices (13²·5, 3²·17), every radix.
        for len in [1001usize, 65, 155, 845, 153, 437, 203, 2145] {
            let Some(mut plan) = OddFft::plan(len) else {
                assert!(!vector_stages_available(), "{len} has a plan");
                continue;
            };
            let x: Vec<Complex<f64>> = (0..len)
                .map(|i| Complex::new(((i * 7 + 3) % 11) as f64 - 4.5, ((i * 5) % 13) as f64))
                .collect();
            let mut z = x.clone();
            let ours = plan.process(&mut z).to_vec();
            let mut reference = x;
            planner.plan_fft_forward(len).process(&mut reference);
            let size = reference.iter().map(|c| c.norm()).fold(0.0, f64::max);
            for (k, (a, b)) in ours.iter().zip(&reference).enumerate() {
                assert!(
                    (a - b).norm() < 1e-13 * size,
                    "length {len}, k = {k}: {a} against {b}"
                );
            }
        }
    }

    #[test]
    fn lengths_rustfft_runs_well_are_left_to_it() {
        // Even, a prime above 31, no factor from 13 up, too short (a flat length below four).
        for len in [1002usize, 37 * 13, 7 * 11 * 5, 13, 13 * 3, 1] {
            assert!(OddFft::plan(len).is_none(), "{len}");
        }
    }
}
