//! A slice of the log-likelihood along one parameter, the others held at their values — with
//! one unknown the log-likelihood itself; not the profile likelihood max_ψ ln L(θ, ψ), which
//! would refit the others at each value — drawn for several methods on the same data to show
//! where each one's maximum lies.

use alloc::string::String;
use alloc::vec::Vec;

#[cfg(feature = "fit")]
use super::Likelihood;
use super::{Evaluate, LogLikelihood};

/// One method's log-likelihood along one parameter.
#[derive(Clone, Debug)]
pub struct Profile {
    /// The method's display name.
    pub method: String,
    /// The parameter.
    pub parameter: String,
    /// The parameter's values.
    pub values: Vec<f64>,
    /// ln L at each value (`f64::NEG_INFINITY` where the method failed).
    pub log_likelihoods: Vec<f64>,
    /// The maximum, `(θ*, ln L(θ*))`: the best value refined by the parabola through it and
    /// its two neighbours (the best value itself at an end of the grid); `None` when the
    /// method failed everywhere.
    pub maximum: Option<(f64, f64)>,
    /// What the method says about its likelihood at the maximum (its violated guarantees
    /// and self-checks that warned, [`LogLikelihood::concerns`]; one more run), each with its
    /// advice — empty when it says nothing, or before [`Profile::check_maximum`]. A refitted
    /// profile's are at its best grid value, where the refitted parameters are known.
    pub notes: Vec<String>,
}

/// `points` evenly spaced values of a parameter with bounds `(lo, hi)` and value `value`:
/// the bounds less 1 % of the width at each end when both are finite (a variance at 0 is no
/// model), from a quarter to four times the distance to the one finite bound, or
/// `value ± 3·max(|value|, 1)` when unbounded.
pub fn profile_grid(bounds: (f64, f64), value: f64, points: usize) -> Vec<f64> {
    let (lo, hi) = bounds;
    let (a, b) = match (lo.is_finite(), hi.is_finite()) {
        (true, true) => (lo + 0.01 * (hi - lo), hi - 0.01 * (hi - lo)),
        (true, false) => {
            let d = (value - lo).max(1e-2);
            (lo + 0.25 * d, lo + 4.0 * d)
        }
        (false, true) => {
            let d = (hi - value).max(1e-2);
            (hi - 4.0 * d, hi - 0.25 * d)
        }
        (false, false) => {
            let d = 3.0 * value.abs().max(1.0);
            (value - d, value + d)
        }
    };
    let points = points.max(2);
    (0..points)
        .map(|i| a + (b - a) * i as f64 / (points - 1) as f64)
        .collect()
}

/// The log-likelihood of `likelihood` (of one parameter: a [`super::Likelihood`], a
/// [`super::FilterLikelihood`]) at `values`, one
/// batch through `evaluate` (`likelihood` itself runs them on every core).
pub fn profile(likelihood: &dyn LogLikelihood, evaluate: &dyn Evaluate, values: &[f64]) -> Profile {
    let points: Vec<Vec<f64>> = values.iter().map(|&v| alloc::vec![v]).collect();
    let log_likelihoods = evaluate.log_likelihoods(&points);
    let mut profile = Profile::new(likelihood, values.to_vec(), log_likelihoods);
    profile.check_maximum(likelihood);
    profile
}

impl Profile {
    /// The profile of `likelihood` (of one parameter) from its values at `values`, computed
    /// elsewhere (one at a time, as the playground does between frames); the maximum is
    /// found here.
    pub fn new(
        likelihood: &dyn LogLikelihood,
        values: Vec<f64>,
        log_likelihoods: Vec<f64>,
    ) -> Profile {
        Profile {
            method: likelihood.method().into(),
            parameter: likelihood.names()[0].clone(),
            maximum: maximum(&values, &log_likelihoods),
            values,
            log_likelihoods,
            notes: Vec::new(),
        }
    }

    /// Fills [`Profile::notes`] with the concerns of `likelihood` (the one this profile was
    /// drawn from, of its one parameter) at the maximum.
    pub fn check_maximum(&mut self, likelihood: &dyn LogLikelihood) {
        self.notes = self
            .maximum
            .map(|(at, _)| self.notes_at(likelihood.concerns(&[at]), "the maximum", at))
            .unwrap_or_default();
    }

    /// `concerns` at `where_` (the parameter's value `at`), each prefixed with where.
    fn notes_at(&self, concerns: Vec<String>, where_: &str, at: f64) -> Vec<String> {
        // Six decimals, or six significant digits where decimals would hide the value.
        let at = if at != 0.0 && !(1e-3..1e6).contains(&at.abs()) {
            alloc::format!("{at:.5e}")
        } else {
            alloc::format!("{at:.6}")
        };
        concerns
            .into_iter()
            .map(|c| alloc::format!("at {where_} {} = {at}: {c}", self.parameter))
            .collect()
    }
}

/// The profile log-likelihood of `parameter`: at each of `values`, ln L maximised over the
/// parameters `refit` (warm-started from the previous value's optimum), the scenario's other
/// parameters held — max_ψ ln L(θ, ψ), the curve whose drop of 1.92 from its maximum bounds
/// the 95 % likelihood-ratio interval. `full` evaluates the likelihood of
/// `[parameter, refit…]` (a [`Likelihood`] of those names, or a cluster's evaluator); the
/// sizes chosen from the problem are those of `full_likelihood`, held at every value.
/// `progress` hears `(values done, values)`. A value where the fit fails gets
/// `f64::NEG_INFINITY`.
#[cfg(feature = "fit")]
pub fn profile_refitted(
    full_likelihood: &Likelihood,
    full: &dyn Evaluate,
    values: &[f64],
    progress: &dyn Fn(usize, usize),
) -> Profile {
    use super::maximise::{maximise, FitOptions};
    use alloc::string::ToString;
    let names = full_likelihood.names();
    let (parameter, refit) = (names[0].clone(), &names[1..]);
    let options = FitOptions {
        standard_errors: false,
        ..FitOptions::default()
    };
    let mut start: Vec<f64> = full_likelihood.start()[1..].to_vec();
    let mut log_likelihoods = Vec::with_capacity(values.len());
    // Each value's full θ (the value, then the others refitted), for the concerns at the best.
    let mut thetas: Vec<Vec<f64>> = Vec::with_capacity(values.len());
    for (k, &v) in values.iter().enumerate() {
        let fixed = Fixed { full, value: v };
        let warm: Vec<(alloc::string::String, f64)> = core::iter::once((parameter.clone(), v))
            .chain(refit.iter().cloned().zip(start.iter().copied()))
            .collect();
        let inner = full_likelihood
            .config()
            .with_parameter_values(&warm)
            .and_then(|c| {
                Likelihood::new(
                    &c,
                    full_likelihood.recording().clone(),
                    0,
                    refit,
                    full_likelihood.seed(),
                )
            })
            .and_then(|l| maximise(&l, &fixed, &options, &|_, _| {}));
        match inner {
            Ok(fit) => {
                start = fit.estimate;
                log_likelihoods.push(fit.log_likelihood);
            }
            Err(_) => log_likelihoods.push(f64::NEG_INFINITY),
        }
        thetas.push(core::iter::once(v).chain(start.iter().copied()).collect());
        progress(k + 1, values.len());
    }
    let mut profile = Profile {
        method: full_likelihood.method().to_string(),
        parameter,
        maximum: maximum(values, &log_likelihoods),
        values: values.to_vec(),
        log_likelihoods,
        notes: Vec::new(),
    };
    // The best value on the grid, with the others as refitted there.
    let best = (0..values.len())
        .filter(|&i| profile.log_likelihoods[i].is_finite())
        .max_by(|&i, &j| profile.log_likelihoods[i].total_cmp(&profile.log_likelihoods[j]));
    if let Some(i) = best {
        // The grid value itself: the refitted others are known there, not at the vertex.
        profile.notes = profile.notes_at(
            full_likelihood.concerns(&thetas[i]),
            "the best value",
            values[i],
        );
    }
    profile
}

/// The likelihood of the refitted parameters with the profiled one fixed: each point gets the
/// fixed value put in front.
#[cfg(feature = "fit")]
struct Fixed<'a> {
    full: &'a dyn Evaluate,
    value: f64,
}

#[cfg(feature = "fit")]
impl Evaluate for Fixed<'_> {
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
        let full: Vec<Vec<f64>> = points
            .iter()
            .map(|p| {
                core::iter::once(self.value)
                    .chain(p.iter().copied())
                    .collect()
            })
            .collect();
        self.full.log_likelihoods(&full)
    }
}

/// The grid's best point refined by the parabola through it and its neighbours.
fn maximum(values: &[f64], ls: &[f64]) -> Option<(f64, f64)> {
    let best = (0..ls.len())
        .filter(|&i| ls[i].is_finite())
        .max_by(|&i, &j| ls[i].total_cmp(&ls[j]))?;
    if best == 0 || best + 1 == ls.len() || !ls[best - 1].is_finite() || !ls[best + 1].is_finite() {
        return Some((values[best], ls[best]));
    }
    let (x0, x1, x2) = (values[best - 1], values[best], values[best + 1]);
    let (y0, y1, y2) = (ls[best - 1], ls[best], ls[best + 1]);
    // Vertex of the parabola through the three points.
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let curvature = (d12 - d01) / (x2 - x0);
    if curvature.is_nan() || curvature >= 0.0 {
        return Some((x1, y1));
    }
    let vertex = 0.5 * (x0 + x1) - 0.5 * d01 / curvature;
    let vertex = vertex.clamp(x0, x2);
    let height = y1 + d01 * (vertex - x1) + curvature * (vertex - x0) * (vertex - x1);
    Some((vertex, height.max(y1)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn the_maximum_of_a_sampled_parabola_is_its_vertex() {
        let values: Vec<f64> = (0..11).map(|i| i as f64 * 0.5).collect();
        let ls: Vec<f64> = values
            .iter()
            .map(|x| 3.0 - 2.0 * (x - 1.8) * (x - 1.8))
            .collect();
        let (x, y) = maximum(&values, &ls).unwrap();
        assert!(
            (x - 1.8).abs() < 1e-12 && (y - 3.0).abs() < 1e-12,
            "{x} {y}"
        );
        // At the end of the grid, the end; nothing finite, nothing.
        let rising: Vec<f64> = values.clone();
        assert_eq!(maximum(&values, &rising), Some((5.0, 5.0)));
        assert_eq!(maximum(&values, &[f64::NEG_INFINITY; 11]), None);
    }

    #[test]
    fn profile_grids_follow_the_bounds() {
        let g = profile_grid((0.0, 10.0), 3.0, 5);
        assert_eq!((g[0], g[4]), (0.1, 9.9));
        let g = profile_grid((0.0, f64::INFINITY), 2.0, 3);
        assert_eq!((g[0], g[2]), (0.5, 8.0));
        let g = profile_grid((f64::NEG_INFINITY, f64::INFINITY), -1.0, 3);
        assert_eq!((g[0], g[2]), (-4.0, 2.0));
    }
}
