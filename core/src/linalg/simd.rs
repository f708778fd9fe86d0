//! Per-node loops compiled twice: for the target as configured, and with AVX2 for x86-64 CPUs
//! that have it, chosen at run time.
//!
//! The grid filters spend most of their time in short loops over every node (the factor (15)
//! of 000, the moments, the DST's pre- and post-passes). Written lane by lane, they vectorise
//! to the widest registers the compiler may use; a portable x86-64 build may only use SSE2's
//! two lanes, while the machines this runs on usually have AVX2's four. A kernel defined with
//! [`per_node_kernel!`] checks the CPU once per call (`is_x86_feature_detected!` caches its
//! answer) and runs its AVX2 copy when it can.
//!
//! The two copies do the same arithmetic in the same order — FMA is not enabled and Rust never
//! fuses a multiply and an add by itself — so their results are bit-identical; only the
//! vector width differs. Without `std` or on other architectures (wasm32 builds with
//! `+simd128` instead) there is one copy. (The two loops that also use FMA, and so may differ
//! in the last bit, dispatch by hand: [`super::scale_by_exp`] and the spectral filter's tensor
//! products, `filters::spectral::tensor`.)

/// Defines a function whose body is compiled for the target and, on x86-64 with `std`, once
/// more with AVX2 enabled, and runs the AVX2 copy when the CPU has it (see the module doc).
/// Plain functions only: no generics, no `self`.
///
/// Written `per_node_kernel! { wide: … }`, the function is compiled a third time with
/// AVX-512F, run where the CPU has it: eight lanes and 32 registers, which the loops of many
/// exponentials and logarithms (the particle filter's weights, the expression programs' passes)
/// use well — 20 % off the stochastic-volatility PF step on the machine of `BENCHMARKS.md`. Not
/// the default: some loops the compiler vectorises for AVX2 it leaves scalar for AVX-512 (the
/// factor (15)'s exponent split made QIEM's step 27 % slower), so a kernel opts in where its
/// benchmark says so. Bits are the same in every copy (no FMA either way).
macro_rules! per_node_kernel {
    (wide: $(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[inline(always)]
            fn body($($arg: $ty),*) $(-> $ret)? $body
            #[cfg(all(feature = "std", target_arch = "x86_64"))]
            {
                #[target_feature(enable = "avx512f")]
                unsafe fn avx512($($arg: $ty),*) $(-> $ret)? {
                    body($($arg),*)
                }
                if std::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU supports AVX-512F, checked just above.
                    return unsafe { avx512($($arg),*) };
                }
            }
            $crate::linalg::simd::per_node_kernel!(@narrow body ($($arg: $ty),*) $(-> $ret)?)
        }
    };
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[inline(always)]
            fn body($($arg: $ty),*) $(-> $ret)? $body
            $crate::linalg::simd::per_node_kernel!(@narrow body ($($arg: $ty),*) $(-> $ret)?)
        }
    };
    // The AVX2 copy and the plain one, calling `$body_fn`.
    (@narrow $body_fn:ident ($($arg:ident: $ty:ty),*) $(-> $ret:ty)?) => {{
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        {
            #[target_feature(enable = "avx2")]
            unsafe fn avx2($($arg: $ty),*) $(-> $ret)? {
                $body_fn($($arg),*)
            }
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                return unsafe { avx2($($arg),*) };
            }
        }
        $body_fn($($arg),*)
    }};
}

pub(crate) use per_node_kernel;
