//! Bounds removed by a change of variables: the optimiser moves freely in u ∈ ℝᵖ and every
//! point it tries maps inside the bounds — θ = lo + (hi − lo)/(1 + e^{−u}) on a finite
//! interval, lo + e^u or hi − e^{−u} on a half-line, θ = u on the whole line (the transforms
//! statsmodels uses for variances and the like).

/// The change of variables of one parameter, from its bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transform {
    /// Unbounded: θ = u.
    Identity,
    /// `[lo, ∞)`: θ = lo + eᵘ.
    Lower(f64),
    /// `(−∞, hi]`: θ = hi − e^{−u}.
    Upper(f64),
    /// `[lo, hi]`: θ = lo + (hi − lo) σ(u), σ the logistic function.
    Interval(f64, f64),
}

impl Transform {
    /// The transform for bounds `(lo, hi)` (infinite where open).
    pub fn of(bounds: (f64, f64)) -> Transform {
        match (bounds.0.is_finite(), bounds.1.is_finite()) {
            (false, false) => Transform::Identity,
            (true, false) => Transform::Lower(bounds.0),
            (false, true) => Transform::Upper(bounds.1),
            (true, true) => Transform::Interval(bounds.0, bounds.1),
        }
    }

    /// θ(u).
    pub fn to_bounded(self, u: f64) -> f64 {
        match self {
            Transform::Identity => u,
            Transform::Lower(lo) => lo + libm::exp(u),
            Transform::Upper(hi) => hi - libm::exp(-u),
            Transform::Interval(lo, hi) => {
                let t = lo + (hi - lo) / (1.0 + libm::exp(-u));
                t.clamp(lo, hi)
            }
        }
    }

    /// u(θ), with θ first moved inside the bounds by a millionth of its scale when it sits on
    /// one (a start on a bound has no finite u).
    pub fn to_free(self, theta: f64) -> f64 {
        let nudge = |b: f64| 1e-6 * b.abs().max(1.0);
        match self {
            Transform::Identity => theta,
            Transform::Lower(lo) => libm::log((theta - lo).max(nudge(lo))),
            Transform::Upper(hi) => -libm::log((hi - theta).max(nudge(hi))),
            Transform::Interval(lo, hi) => {
                let width = hi - lo;
                let s = ((theta - lo) / width).clamp(1e-6, 1.0 - 1e-6);
                libm::log(s / (1.0 - s))
            }
        }
    }
}

impl Transform {
    /// dθ/du at θ.
    pub(crate) fn slope(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => 1.0,
            Transform::Lower(lo) => theta - lo,
            Transform::Upper(hi) => hi - theta,
            Transform::Interval(lo, hi) => (theta - lo) * (hi - theta) / (hi - lo),
        }
    }

    /// `d ln(dθ/du) / du` at θ: 0 on the whole line, 1 for `lo + eᵘ`, −1 for `hi − e^{−u}`,
    /// `1 − 2σ(u) = 1 − 2(θ − lo)/(hi − lo)` on an interval.
    pub(crate) fn log_slope_derivative(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => 0.0,
            Transform::Lower(_) => 1.0,
            Transform::Upper(_) => -1.0,
            Transform::Interval(lo, hi) => 1.0 - 2.0 * (theta - lo) / (hi - lo),
        }
    }

    /// The Wald interval `θ̂ ± z·se` computed where the fit moved, on the unbounded scale
    /// u, and mapped back: `θ(û ± z·se_u)` with `se_u = se/|dθ/du|` (the delta method), so
    /// that it stays inside the bounds (a variance's interval is `lo + (θ̂ − lo)·e^(±z se/(θ̂ −
    /// lo))`, never below its bound); on an unbounded parameter the usual `θ̂ ± z·se`. NaN
    /// without a standard error or with θ̂ on a bound (where u is infinite).
    pub fn wald_interval(self, theta: f64, se: f64, z: f64) -> (f64, f64) {
        let slope = self.slope(theta);
        if !(se.is_finite() && slope > 0.0 && slope.is_finite()) {
            return (f64::NAN, f64::NAN);
        }
        let (u, half) = (self.to_free(theta), z * se / slope);
        (self.to_bounded(u - half), self.to_bounded(u + half))
    }
}

/// θ(u) componentwise.
#[cfg(feature = "fit")]
pub(crate) fn bounded(transforms: &[Transform], u: &[f64]) -> alloc::vec::Vec<f64> {
    transforms
        .iter()
        .zip(u)
        .map(|(t, &u)| t.to_bounded(u))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// Issue 56, item 5: a variance q ≥ 0 with θ̂ = 400 ± 717 had the interval
    /// (−1005, 1805) on the θ scale; on u = ln q it is 400·e^(±1.96·717/400), inside the
    /// bound, and to first order in se it is the symmetric one.
    #[test]
    fn wald_intervals_stay_inside_the_bounds() {
        let lower = Transform::of((0.0, f64::INFINITY));
        let (a, b) = lower.wald_interval(400.0, 717.0, 1.96);
        let spread = (1.96f64 * 717.0 / 400.0).exp();
        assert!(
            (a - 400.0 / spread).abs() < 1e-9 && (b - 400.0 * spread).abs() < 1e-6,
            "{a} {b}"
        );
        assert!(a > 0.0);
        let (a, b) = lower.wald_interval(400.0, 1e-3, 1.96);
        assert!((a - (400.0 - 1.96e-3)).abs() < 1e-8 && (b - (400.0 + 1.96e-3)).abs() < 1e-8);
        let (a, b) = Transform::of((0.0, 1.0)).wald_interval(0.9, 0.2, 1.96);
        assert!(0.0 < a && a < 0.9 && 0.9 < b && b < 1.0, "{a} {b}");
        let (a, b) = Transform::of((f64::NEG_INFINITY, 2.0)).wald_interval(1.0, 3.0, 1.96);
        assert!(b < 2.0 && a < 1.0 - 1.96 * 3.0, "{a} {b}");
        let (a, b) = Transform::Identity.wald_interval(-3.0, 0.5, 2.0);
        assert_eq!((a, b), (-4.0, -2.0));
        assert!(lower.wald_interval(0.0, 1.0, 1.96).0.is_nan());
        assert!(lower.wald_interval(3.0, f64::NAN, 1.96).1.is_nan());
    }

    #[test]
    fn transforms_round_trip_and_stay_inside() {
        for (bounds, theta) in [
            ((f64::NEG_INFINITY, f64::INFINITY), -3.5),
            ((0.0, f64::INFINITY), 2.0),
            ((f64::NEG_INFINITY, 1.0), -4.0),
            ((-1.0, 5.0), 0.25),
        ] {
            let t = Transform::of(bounds);
            let back = t.to_bounded(t.to_free(theta));
            assert!((back - theta).abs() < 1e-12 * theta.abs().max(1.0), "{t:?}");
            for u in [-700.0, -30.0, 0.0, 30.0, 700.0] {
                let v = t.to_bounded(u);
                assert!(bounds.0 <= v && v <= bounds.1, "{t:?} {u} {v}");
            }
        }
        // A start on a bound is moved just inside.
        let t = Transform::of((0.0, f64::INFINITY));
        assert!(t.to_free(0.0).is_finite());
    }
}
