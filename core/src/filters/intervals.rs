//! Intervals of any length between observations: integrator substeps over a step
//! ([`Substeps`]), whole intervals Δτ and a remainder ([`whole_intervals`]), and the cache of
//! operators made for lengths other than Δτ ([`LengthCache`]).

use alloc::vec::Vec;

use super::Concern;

/// Steps of an integrator (the Kalman family's RK4 moment equations, the particle filter's
/// Euler–Maruyama) over one filter step: `per_interval` over Δτ, and over a step of another
/// length as many steps of at most Δτ/`per_interval` as it needs — so a gap of many intervals
/// is not one long, inaccurate or unstable step. Without Δτ, `per_interval` whatever the
/// step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Substeps {
    per_interval: usize,
    longest: Option<f64>,
}

impl Substeps {
    /// `per_interval` (at least 1) steps per Δτ = `dt_obs`, when known.
    pub(crate) fn new(per_interval: usize, dt_obs: Option<f64>) -> Self {
        let per_interval = per_interval.max(1);
        Substeps {
            per_interval,
            longest: dt_obs
                .filter(|dt| *dt > 0.0 && dt.is_finite())
                .map(|dt| dt / per_interval as f64),
        }
    }

    /// The steps over Δτ.
    pub(crate) fn per_interval(&self) -> usize {
        self.per_interval
    }

    /// The steps over `dt` (exactly `per_interval` over Δτ).
    pub(crate) fn over(&self, dt: f64) -> usize {
        match self.longest {
            Some(h) => libm::ceil(dt / h - 1e-9).max(1.0) as usize,
            None => self.per_interval,
        }
    }
}

/// How many plans for interval lengths other than Δτ a grid filter keeps (the remainders of
/// irregular intervals): each is one factorisation or spectral solve of the grid's size.
pub(crate) const REMAINDER_PLANS: usize = 4;

/// Operators (solvers, plans, off-line matrices) made for interval lengths other than Δτ, the
/// most recently used first and at most `keep` of them, with a count of how often a step
/// needed a length it did not have: when the lengths keep changing (jittered time stamps),
/// nearly every step makes one, which the self-check reports ([`LengthCache::check`]).
#[derive(Clone, Debug)]
pub(crate) struct LengthCache<T> {
    entries: Vec<(f64, T)>,
    keep: usize,
    /// Lengths asked for, and those that had to be made.
    asked: usize,
    made: usize,
}

/// The self-check of the grid and spectral filters' caches of operators for interval lengths
/// other than Δτ: the share of the irregular steps whose length had to get an operator of its own
/// (reported above one half once more were made than are kept).
pub(crate) const REBUILT_SHARE_CHECK: &str = "share of irregular steps that made a new operator";

impl<T> LengthCache<T> {
    /// Empty, keeping at most `keep` operators.
    pub(crate) fn new(keep: usize) -> Self {
        LengthCache {
            entries: Vec::new(),
            keep,
            asked: 0,
            made: 0,
        }
    }

    /// Moves the operator for `length` to the front; false when there is none (then
    /// [`LengthCache::insert`] one).
    pub(crate) fn bring_to_front(&mut self, length: f64) -> bool {
        self.asked += 1;
        match self.entries.iter().position(|e| e.0 == length) {
            Some(i) => {
                self.entries[..=i].rotate_right(1);
                true
            }
            None => false,
        }
    }

    /// Puts `value`, made for `length`, at the front, dropping the least recently used past
    /// `keep`.
    pub(crate) fn insert(&mut self, length: f64, value: T) {
        self.made += 1;
        self.entries.truncate(self.keep.saturating_sub(1));
        self.entries.insert(0, (length, value));
    }

    /// The operator at the front (the one just brought there or inserted).
    pub(crate) fn front(&mut self) -> &mut T {
        &mut self.entries[0].1
    }

    /// A concern when more operators were made than are kept and more than half of the
    /// lengths asked for had to be made: the steps' lengths keep changing, and each one costs
    /// an operator's construction (for the spectral filter, Algorithm 1 of 004 off-line).
    pub(crate) fn check(&self, out: &mut Vec<Concern>) {
        let share = self.made as f64 / self.asked.max(1) as f64;
        if self.made > self.keep && share > 0.5 {
            out.push(Concern::above(
                REBUILT_SHARE_CHECK,
                share,
                0.5,
                "the steps between observations keep changing length (e.g. jittered time stamps), so most steps make an operator of their own: round the times to a common step, or choose Δτ so that it divides them",
            ));
        }
    }
}

/// Relative tolerance within which a step τ_k − τ_{k−1} counts as the interval Δτ (the
/// driver then steps by Δτ exactly, so a recording written from a simulation filters bit for
/// bit as the simulation did).
pub const INTERVAL_TOLERANCE: f64 = 1e-9;

/// `interval` as whole intervals Δτ = `dt_obs` and a remainder in (0, Δτ) (0 when the
/// interval is a multiple of Δτ up to [`INTERVAL_TOLERANCE`]): how a grid
/// filter built for Δτ crosses an interval of any length with the operators it has.
pub(crate) fn whole_intervals(interval: f64, dt_obs: f64) -> (usize, f64) {
    let tolerance = INTERVAL_TOLERANCE;
    let ratio = interval / dt_obs;
    let nearest = libm::round(ratio);
    if nearest >= 1.0 && (ratio - nearest).abs() <= tolerance * ratio {
        return (nearest as usize, 0.0);
    }
    let whole = libm::floor(ratio);
    (whole as usize, interval - whole * dt_obs)
}
