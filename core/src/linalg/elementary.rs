//! `e^x` and `ln x` over the whole real line, written so that a loop of them vectorises.
//!
//! `libm`'s scalar `exp` and `log` branch on their argument, so a loop over particles or nodes
//! calls them one value at a time: on the stochastic-volatility model they were half a particle
//! filter's step (the variance e^x of every particle and its logarithm). These two use only
//! additions, multiplications, one division (`ln`), integer bit operations and selects, so the
//! compiler turns a loop of them into vector code (four lanes with AVX2, see
//! [`super::simd`]); without FMA their bits are the same on every IEEE-754 target, wasm included.
//! Both are within 2 ulp of the correctly rounded value (tested against `libm` here), and
//! their special values are IEEE's: `exp(−∞) = 0`, `exp(+∞) = +∞`, results below the normal
//! range as subnormals, `ln 0 = −∞`, `ln x = NaN` for `x < 0`, NaN in, NaN out.

/// 1.5·2⁵²: adding and subtracting it rounds a double of magnitude below 2⁵¹ to the nearest
/// integer, which is then held in the sum's low mantissa bits.
const ROUND: f64 = 6_755_399_441_055_744.0;
/// `ln 2 = LN2_HI + LN2_LO`, the high part with 32 trailing zero bits so that `k·LN2_HI` is
/// exact for |k| < 2²⁰ (fdlibm's split).
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
/// Above this, `e^x` exceeds the largest double.
const EXP_OVERFLOW: f64 = 709.782_712_893_384;
/// Below this, `e^x` is less than half the smallest subnormal.
const EXP_UNDERFLOW: f64 = -745.133_219_101_941_1;

/// `2^k` for an integer-valued `k` in [−1022, 1023], from `k + ROUND`.
#[inline(always)]
fn power_of_two(k_plus_round: f64) -> f64 {
    // The low bits of k + ROUND hold k (two's complement in the mantissa); adding the bias and
    // shifting by 52 leaves k + 1023 in the exponent field.
    f64::from_bits(k_plus_round.to_bits().wrapping_add(1023) << 52)
}

/// `Σ_{i ≤ 13} rⁱ/i!` in Estrin's scheme (five multiply–adds deep instead of Horner's
/// fourteen), truncation below 10⁻¹⁸ for |r| ≤ ½ ln 2.
#[inline(always)]
pub(super) fn exp_taylor(r: f64, madd: &impl Fn(f64, f64, f64) -> f64) -> f64 {
    const C: [f64; 14] = [
        1.0,
        1.0,
        0.5,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5_040.0,
        1.0 / 40_320.0,
        1.0 / 362_880.0,
        1.0 / 3_628_800.0,
        1.0 / 39_916_800.0,
        1.0 / 479_001_600.0,
        1.0 / 6_227_020_800.0,
    ];
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let pair = |j: usize| madd(C[2 * j + 1], r, C[2 * j]);
    let low = madd(madd(pair(3), r2, pair(2)), r4, madd(pair(1), r2, pair(0)));
    let high = madd(pair(6), r4, madd(pair(5), r2, pair(4)));
    madd(high, r8, low)
}

/// `e^x` for every real x.
///
/// `x = k ln 2 + r` with `k = round(x / ln 2)` and `|r| ≤ ½ ln 2` (Cody–Waite with the
/// two-part ln 2), `e^r` by its Taylor polynomial of degree 13 ([`exp_taylor`]), and
/// `2^k = 2^{k₁} 2^{k₂}` with `k₁ = round(k/2)`, two normal powers of two, so that results near
/// overflow and in the subnormal range are formed with one rounding.
#[inline(always)]
pub(crate) fn exp(x: f64) -> f64 {
    // Clamped so that k stays within [−1075, 1024] (each half within the normal exponents);
    // the ends are set after.
    let y = x.clamp(EXP_UNDERFLOW - 1.0, EXP_OVERFLOW + 1.0);
    let t = y * core::f64::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    let r = (y - k * LN2_HI) - k * LN2_LO;
    let p = exp_taylor(r, &|p, r, c| p * r + c);
    let half = (k * 0.5 + ROUND) - ROUND;
    let value = p * power_of_two(half + ROUND) * power_of_two((k - half) + ROUND);
    if x > EXP_OVERFLOW {
        f64::INFINITY
    } else if x < EXP_UNDERFLOW {
        0.0
    } else {
        // NaN falls through: the clamp keeps it, and so does every operation after.
        value
    }
}

/// `ln x` for every real x.
///
/// `x = 2^e m` with `m ∈ [√½, √2)` (read from the bits; subnormals scaled by 2⁵⁴ first), then
/// fdlibm's form of `ln m = ln(1 + f)`: with `s = f/(2 + f)`, `ln(1 + f) = 2 atanh s = f −
/// ½f² + s(½f² + R(s²))`, R the series `Σ_{j=1}^{10} 2 s^{2j}/(2j + 1)` (truncation below
/// 10⁻¹⁸ for `|s| ≤ 0.172`), and `e ln 2` added in two parts.
#[inline(always)]
pub(crate) fn ln(x: f64) -> f64 {
    const TWO_54: f64 = 18_014_398_509_481_984.0;
    const MANTISSA: u64 = 0x000f_ffff_ffff_ffff;
    const ONE: u64 = 0x3ff0_0000_0000_0000;
    let subnormal = x < f64::MIN_POSITIVE;
    let y = if subnormal { x * TWO_54 } else { x };
    let bits = y.to_bits();
    // The biased exponent as a double, by writing it into the mantissa of 2⁵².
    let biased = f64::from_bits(0x4330_0000_0000_0000 | (bits >> 52)) - 4_503_599_627_370_496.0;
    let m = f64::from_bits((bits & MANTISSA) | ONE);
    let high = m > core::f64::consts::SQRT_2;
    let m = if high { 0.5 * m } else { m };
    let e = biased - 1023.0 + if high { 1.0 } else { 0.0 } - if subnormal { 54.0 } else { 0.0 };
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let z = s * s;
    let half_f2 = 0.5 * f * f;
    let r = atanh_tail(z);
    let value = e * LN2_HI - ((half_f2 - (s * (half_f2 + r) + e * LN2_LO)) - f);
    if x == f64::INFINITY {
        f64::INFINITY
    } else if x == 0.0 {
        f64::NEG_INFINITY
    } else if x > 0.0 {
        value
    } else {
        // Negative or NaN.
        f64::NAN
    }
}

/// `√x`, correctly rounded (IEEE 754), so the same bits as `libm::sqrt`: the processor's
/// instruction where the standard library is there to name it (inlined, and vectorised in a
/// loop), `libm`'s otherwise.
#[inline(always)]
pub(crate) fn sqrt(x: f64) -> f64 {
    #[cfg(feature = "std")]
    return x.sqrt();
    #[cfg(not(feature = "std"))]
    libm::sqrt(x)
}

/// `atan x` for every real x, without branches (so that a pass of it vectorises).
///
/// Cephes' reduction and rational approximation (Moshier 1989, `atan.c`): for `|x| > tan 3π/8`,
/// `atan|x| = π/2 + atan(−1/|x|)`; for `|x| > 0.66`, `π/4 + atan((|x| − 1)/(|x| + 1))`; then on
/// the reduced z, `atan z = z + z · z² P(z²)/Q(z²)` (degrees 4 and 5), with the low part of π/2
/// (`6.123…e−17`, or half of it for π/4) added before the high part; the sign of x restored.
/// Within 2 ulp of `libm::atan` (tested over 20 decades and the reductions' ends).
#[inline(always)]
pub(crate) fn atan(x: f64) -> f64 {
    const TAN_3PI_8: f64 = 2.414_213_562_373_095;
    const MOREBITS: f64 = 6.123_233_995_736_766e-17;
    const P: [f64; 5] = [
        -8.750_608_600_031_904e-1,
        -1.615_753_718_733_365e1,
        -7.500_855_792_314_705e1,
        -1.228_866_684_490_136e2,
        -6.485_021_904_942_025e1,
    ];
    const Q: [f64; 5] = [
        2.485_846_490_142_306e1,
        1.650_270_098_316_988_5e2,
        4.328_810_604_912_903e2,
        4.853_903_996_359_137e2,
        1.945_506_571_482_614e2,
    ];
    const SIGN: u64 = 1 << 63;
    let t = f64::from_bits(x.to_bits() & !SIGN);
    let big = t > TAN_3PI_8;
    let middle = t > 0.66;
    let z = if big {
        -1.0 / t
    } else if middle {
        (t - 1.0) / (t + 1.0)
    } else {
        t
    };
    let (base, low) = if big {
        (core::f64::consts::FRAC_PI_2, MOREBITS)
    } else if middle {
        (core::f64::consts::FRAC_PI_4, 0.5 * MOREBITS)
    } else {
        (0.0, 0.0)
    };
    let z2 = z * z;
    let p = (((P[0] * z2 + P[1]) * z2 + P[2]) * z2 + P[3]) * z2 + P[4];
    let q = ((((z2 + Q[0]) * z2 + Q[1]) * z2 + Q[2]) * z2 + Q[3]) * z2 + Q[4];
    // Not negative (atan of |x|): x's sign bit is the result's.
    let value = base + ((z * (z2 * p / q) + z) + low);
    f64::from_bits(value.to_bits() | (x.to_bits() & SIGN))
}

/// `ln(1 + y)` for y ≥ −1, accurate for small y too: `u = 1 + y` rounded, then
/// `ln u − ((u − 1) − y)/u`, which corrects for the rounding of u to first order (Goldberg
/// 1991, "What every computer scientist should know about floating-point arithmetic", Thm 4's
/// idea); within a few ulp of `libm::log1p`.
#[inline(always)]
pub(crate) fn ln_1p(y: f64) -> f64 {
    let u = 1.0 + y;
    let value = ln(u) - ((u - 1.0) - y) / u;
    if u == f64::INFINITY {
        f64::INFINITY
    } else if u == 0.0 {
        f64::NEG_INFINITY
    } else if u == 1.0 {
        // ln(1 + y) = y to rounding when 1 + y rounds to 1.
        y
    } else {
        value
    }
}

/// `R(z) = Σ_{j=1}^{10} 2 z^j/(2j + 1)`, in Estrin's scheme.
#[inline(always)]
fn atanh_tail(z: f64) -> f64 {
    const C: [f64; 10] = [
        2.0 / 3.0,
        2.0 / 5.0,
        2.0 / 7.0,
        2.0 / 9.0,
        2.0 / 11.0,
        2.0 / 13.0,
        2.0 / 15.0,
        2.0 / 17.0,
        2.0 / 19.0,
        2.0 / 21.0,
    ];
    let z2 = z * z;
    let z4 = z2 * z2;
    let z8 = z4 * z4;
    let pair = |j: usize| C[2 * j] + C[2 * j + 1] * z;
    // c₀ + c₁z + … + c₉z⁹, then times z.
    let low = (pair(0) + pair(1) * z2) + (pair(2) + pair(3) * z2) * z4;
    let p = low + pair(4) * z8;
    p * z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    fn ulps(a: f64, b: f64) -> u64 {
        if a == b || (a.is_nan() && b.is_nan()) {
            0
        } else {
            (a.to_bits() as i64).abs_diff(b.to_bits() as i64)
        }
    }

    /// Arguments spread over `[lo, hi]` by a fixed low-discrepancy rule, with the ends.
    fn spread(lo: f64, hi: f64, count: usize) -> impl Iterator<Item = f64> {
        (0..count)
            .map(move |i| lo + (hi - lo) * ((i as f64 * 0.618_033_988_749_894_9) % 1.0))
            .chain([lo, hi])
    }

    #[test]
    fn exp_is_within_two_ulp_of_libm() {
        let ranges = [
            (-1.0, 1.0),
            (-0.35, 0.35),
            (-40.0, 40.0),
            (-708.0, 709.7),
            // Results near the largest double and among the subnormals.
            (700.0, 709.78),
            (-745.1, -708.0),
        ];
        for (lo, hi) in ranges {
            for x in spread(lo, hi, 20_000) {
                let (got, want) = (exp(x), libm::exp(x));
                // Subnormal results have fewer bits: within 2 of their last place too.
                assert!(
                    ulps(got, want) <= 2,
                    "exp({x:e}): {got:e} against libm {want:e}"
                );
            }
        }
    }

    #[test]
    fn exp_special_values() {
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert_eq!(exp(-746.0), 0.0);
        assert!(exp(f64::NAN).is_nan());
        assert!(exp(-744.0) > 0.0 && exp(-744.0) < f64::MIN_POSITIVE);
        assert!(exp(709.78).is_finite());
    }

    #[test]
    fn ln_is_within_two_ulp_of_libm() {
        let ranges = [
            (0.5, 2.0),
            (0.9, 1.1),
            (1e-300, 1e-250),
            (1e-10, 1e10),
            (1e300, f64::MAX),
            // Subnormal arguments.
            (4.9e-324, 2.2e-308),
        ];
        for (lo, hi) in ranges {
            for x in spread(lo, hi, 20_000) {
                let (got, want) = (ln(x), libm::log(x));
                assert!(
                    ulps(got, want) <= 2,
                    "ln({x:e}): {got:e} against libm {want:e}"
                );
            }
        }
        // Near 1, where ln x is small and its relative error matters most.
        for i in 1..2000 {
            let x = 1.0 + (i as f64 - 1000.0) * 1e-9;
            let (got, want) = (ln(x), libm::log(x));
            assert!(
                ulps(got, want) <= 2,
                "ln({x:e}): {got:e} against libm {want:e}"
            );
        }
    }

    #[test]
    fn ln_special_values() {
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f64::NEG_INFINITY);
        assert_eq!(ln(-0.0), f64::NEG_INFINITY);
        assert_eq!(ln(f64::INFINITY), f64::INFINITY);
        assert!(ln(-1.0).is_nan());
        assert!(ln(f64::NEG_INFINITY).is_nan());
        assert!(ln(f64::NAN).is_nan());
        assert_eq!(ln(2.0), core::f64::consts::LN_2);
        assert!(ulps(ln(core::f64::consts::E), 1.0) <= 1);
    }

    #[test]
    fn ln_1p_is_within_four_ulp_of_libm() {
        for (lo, hi) in [(-0.9, 1.0), (-1e-6, 1e-6), (1e-300, 1e-10), (1.0, 1e300)] {
            for y in spread(lo, hi, 20_000) {
                let (got, want) = (ln_1p(y), libm::log1p(y));
                assert!(
                    ulps(got, want) <= 4,
                    "ln_1p({y:e}): {got:e} against libm {want:e}"
                );
            }
        }
        assert_eq!(ln_1p(0.0), 0.0);
        assert_eq!(ln_1p(f64::INFINITY), f64::INFINITY);
        assert_eq!(ln_1p(-1.0), f64::NEG_INFINITY);
        assert!(ln_1p(-2.0).is_nan());
    }

    #[test]
    fn atan_is_libm_s_within_two_ulp() {
        let ulp = |v: f64| f64::from_bits(v.abs().to_bits() + 1) - v.abs();
        let mut points = alloc::vec![0.0, -0.0, 0.66, 2.414_213_562_373_095, 1.0, 1e300, -1e-300];
        points.extend([f64::MIN_POSITIVE, 5e-324, f64::MAX, 0.659_999_999_999_999_9]);
        for i in 0..20_000 {
            // 20 decades either side of 1, and the reductions' neighbourhoods densely.
            let e = -10.0 + 20.0 * i as f64 / 20_000.0;
            points.push(libm::pow(10.0, e));
            points.push(-libm::pow(10.0, e) * 1.000_000_3);
            points.push(0.5 + i as f64 * 1e-4);
        }
        for x in points {
            let (ours, reference) = (atan(x), libm::atan(x));
            assert!(
                (ours - reference).abs() <= 2.0 * ulp(reference),
                "atan({x:e}) = {ours:e} against {reference:e}"
            );
            assert_eq!(
                ours.is_sign_negative(),
                reference.is_sign_negative(),
                "{x:e}"
            );
        }
        assert_eq!(atan(f64::INFINITY), core::f64::consts::FRAC_PI_2);
        assert_eq!(atan(f64::NEG_INFINITY), -core::f64::consts::FRAC_PI_2);
        assert!(atan(f64::NAN).is_nan());
    }

    #[test]
    fn sqrt_is_libm_s_to_the_bit() {
        for x in [
            0.0,
            -0.0,
            1e-310,
            2.0,
            0.5,
            1e300,
            f64::INFINITY,
            -1.0,
            f64::NAN,
            3.7e-5,
        ] {
            let (ours, reference) = (sqrt(x), libm::sqrt(x));
            assert!(ours.to_bits() == reference.to_bits() || (ours.is_nan() && reference.is_nan()));
        }
    }
}
