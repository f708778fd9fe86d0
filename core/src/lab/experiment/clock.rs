//! Wall-clock time of the methods' steps: a [`Clock`] (the standard one where `Instant` works),
//! and the sampling of steps too short to time one by one.

use alloc::vec::Vec;

/// A source of wall-clock time in seconds (std: `Instant`; wasm: `performance.now()`).
pub trait Clock {
    /// Seconds since an arbitrary fixed origin.
    fn now(&self) -> f64;
}

/// The standard clock where `std::time::Instant` works: with `std`, except on
/// wasm32-unknown-unknown, where `Instant` panics — there the driver times nothing unless it
/// is given a clock (the wasm crate's reads `performance.now()`).
#[cfg(all(
    feature = "std",
    not(all(target_arch = "wasm32", target_os = "unknown"))
))]
mod standard_clock {
    use super::Clock;

    /// [`Clock`] on `std::time::Instant`.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct StdClock(std::time::Instant);

    impl Default for StdClock {
        fn default() -> Self {
            StdClock(std::time::Instant::now())
        }
    }

    impl Clock for StdClock {
        fn now(&self) -> f64 {
            self.0.elapsed().as_secs_f64()
        }
    }

    /// Calls `f` with the standard clock (`std::time::Instant`).
    pub fn with_standard_clock<T>(f: impl FnOnce(Option<&dyn Clock>) -> T) -> T {
        f(Some(&StdClock::default()))
    }
}

/// Without `std`, or on wasm32-unknown-unknown: no standard clock.
#[cfg(not(all(
    feature = "std",
    not(all(target_arch = "wasm32", target_os = "unknown"))
)))]
mod standard_clock {
    use super::Clock;

    /// Calls `f` without a clock (the driver then times nothing).
    pub fn with_standard_clock<T>(f: impl FnOnce(Option<&dyn Clock>) -> T) -> T {
        f(None)
    }
}

pub use standard_clock::*;

/// Timed steps that averaged less than this (seconds) are sampled: only one step in
/// [`SAMPLE_EVERY`] is timed. The two clock reads that time a step are a sizeable share of the
/// cheapest steps (sub-microsecond filters) and a small one at this threshold; timing one step
/// in [`SAMPLE_EVERY`] makes their share negligible, and the mean over the first steps and the
/// sampled ones of a run estimates the mean step as well as all of them would (BENCHMARKS.md,
/// "The driver's own cost per step", has the measurements).
pub const SAMPLED_BELOW: f64 = 5e-6;

/// See [`SAMPLED_BELOW`].
pub const SAMPLE_EVERY: usize = 32;

/// `records.extend_from_slice(values)` as a loop of pushes: the driver appends an estimate's
/// few values after every step, and the copy's call to `memcpy` cost more than the values.
pub(super) fn append(records: &mut Vec<f64>, values: &[f64]) {
    records.reserve(values.len());
    for &v in values {
        records.push(v);
    }
}

/// Steps of each method always timed, before their mean decides whether to sample.
pub(super) const TIMED_FIRST: usize = 16;
