//! The box a grid should live on when the prior is too vague to say, read from the data.
//!
//! A grid or spectral method lives on a box. Without one, the Python API puts it around the
//! prior (mean ± 8 sd); for a diffuse prior — the Nile with N(1120, 10⁷) — that is
//! [−24 178, 26 418], and the posterior, some 50 wide, falls between cells. The measurements
//! say where the state can be: a 1-D state observed as `z = h(x) + v`, `v ~ N(0, R)`, lies
//! where `h(x)` is within a few noise sds of the measured values. This module finds that set
//! within the prior's box, by sampling h on a fine grid, and widens it by the state's own
//! motion over the longest interval between measurements.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::Recording;
use crate::model::measurement::GaussianMatch;
use crate::model::{Model, ObservationModel};

/// Noise sds either side of the measured range that `h(x)` may lie in.
pub const NOISE_SDS: f64 = 5.0;
/// Sds of the state's motion over the longest interval added at each end.
pub const MOTION_SDS: f64 = 5.0;
/// Points at which h is sampled across the prior's box.
const SAMPLES: usize = 20_001;
/// Samples that must fall in the set for it to be read as a box (fewer: the prior's box).
const MIN_HITS: usize = 10;

/// A box from the data and what it came from.
#[derive(Clone, Debug)]
pub struct DataDomain {
    /// `(lower, upper)` per dimension.
    pub bounds: Vec<(f64, f64)>,
    /// What it was read from, for the notes.
    pub note: String,
}

/// The box the measurements of `recording` put a 1-D state of `model` in, within `prior_box`:
/// the x where every observed component's `h_j(x)` is within [`NOISE_SDS`] noise sds of the
/// range of its measurements, widened by [`MOTION_SDS`] sds of the state's motion `√(Q Δτ)`
/// over the longest interval and by a tenth of its width (its ends, found on 20 001 samples
/// of the box, moved out by one sample). `None` — keep the prior's box — for more than one
/// dimension, continuous observations, a driven model, a noise without a constant variance,
/// measurements fewer than ten samples of the box explain, or a box from the data not
/// narrower than half the prior's.
pub fn domain_from_data(
    model: &Model,
    recording: &Recording,
    prior_box: &[(f64, f64)],
) -> Option<DataDomain> {
    // A driven model's h and G read the time and inputs, which a box for the whole run
    // cannot: it keeps the prior's box.
    if model.n != 1 || recording.continuous || prior_box.len() != 1 || model.is_driven() {
        return None;
    }
    let ObservationModel::Discrete { density } = &model.observations else {
        return None;
    };
    let Ok(GaussianMatch::Constant { cov, .. }) = density.gaussian_match(model.m) else {
        return None;
    };
    let m = model.m;
    // The measured range of each component, widened by its noise.
    let mut ranges = vec![(f64::INFINITY, f64::NEG_INFINITY); m];
    for k in 0..=recording.steps() {
        for (range, &z) in ranges.iter_mut().zip(recording.observation(k)) {
            if z.is_finite() {
                *range = (range.0.min(z), range.1.max(z));
            }
        }
    }
    let windows: Vec<Option<(f64, f64)>> = ranges
        .iter()
        .enumerate()
        .map(|(j, &(lo, hi))| {
            let sd = libm::sqrt(cov[(j, j)]);
            (lo <= hi).then_some((lo - NOISE_SDS * sd, hi + NOISE_SDS * sd))
        })
        .collect();
    if windows.iter().all(Option::is_none) {
        return None;
    }
    let (a, b) = prior_box[0];
    let mut hx = vec![0.0; m];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut hits = 0usize;
    for i in 0..SAMPLES {
        let x = a + (b - a) * i as f64 / (SAMPLES - 1) as f64;
        model.observation.eval(&[x], &mut hx);
        let explains = hx
            .iter()
            .zip(&windows)
            .all(|(h, w)| w.is_none_or(|(l, u)| (l..=u).contains(h)));
        if explains {
            lo = lo.min(x);
            hi = hi.max(x);
            hits += 1;
        }
    }
    // A set the samples barely resolve keeps the prior's box; else its ends, which the
    // samples place to within one step, move out by that step.
    if hits < MIN_HITS {
        return None;
    }
    let step = (b - a) / (SAMPLES - 1) as f64;
    let (lo, hi) = (lo - step, hi + step);
    let longest = (1..=recording.steps())
        .map(|k| recording.step_length(k))
        .fold(0.0, f64::max);
    let q = model.process_noise().at(&[0.5 * (lo + hi)])[(0, 0)];
    // Q is per unit time for an SDE, per transition for a discrete-time map.
    let elapsed = match model.dynamics {
        crate::model::Dynamics::Discrete { period } => longest / period,
        crate::model::Dynamics::Continuous => longest,
    };
    let motion = MOTION_SDS * libm::sqrt((q * elapsed).max(0.0));
    let margin = motion + 0.1 * (hi - lo);
    let bounds = ((lo - margin).max(a), (hi + margin).min(b));
    // (NaN-safe: a width that is not positive, or not narrower, keeps the prior's box.)
    let width = bounds.1 - bounds.0;
    if width.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) || width > 0.5 * (b - a) {
        return None;
    }
    let note = format!(
        "domain [{:.6}, {:.6}] from the data: where h is within {NOISE_SDS} noise sds of the measurements' range, widened by {MOTION_SDS} sds of the state's motion over the longest interval ({motion:.4}) and a tenth — the prior's box [{a:.6}, {b:.6}] is {:.0} times as wide",
        bounds.0,
        bounds.1,
        (b - a) / (bounds.1 - bounds.0)
    );
    Some(DataDomain {
        bounds: vec![bounds],
        note,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Noise;
    use crate::testing::test;

    fn recording(zs: &[f64]) -> Recording {
        let times = (0..zs.len()).map(|k| k as f64).collect();
        Recording::measurements(1, 1, times, zs).expect("recording")
    }

    /// A random walk with Q = 4 measured as z = x + v, R = 1, between 10 and 30 inside a
    /// prior box of ±10⁴: the box is [10 − 5 − 10 − 3, 30 + 5 + 10 + 3] (noise, motion 5·√4,
    /// a tenth of the 30 wide set).
    #[test]
    fn a_level_measured_directly_gets_its_range_with_noise_and_motion() {
        let model = Model::from_text(&["0"], &["x"], Noise::discrete(1.0))
            .and_then(|m| m.with_diffusion(nalgebra::DMatrix::from_element(1, 1, 2.0)))
            .expect("model");
        let d = domain_from_data(&model, &recording(&[10.0, 30.0, 20.0]), &[(-1e4, 1e4)])
            .expect("a box");
        let (lo, hi) = d.bounds[0];
        // Sampling h on 20 001 points of the box (1.0 apart), the ends moved out by one:
        // within two samples of the exact ends.
        assert!(
            (lo - -8.0).abs() < 2.0 && (hi - 48.0).abs() < 2.0,
            "{lo} {hi}"
        );
        assert!(d.note.contains("from the data"), "{}", d.note);
        // A box the prior already fits keeps the prior's.
        assert!(domain_from_data(&model, &recording(&[10.0, 30.0]), &[(0.0, 50.0)]).is_none());
        // Measurements nothing in the box explains: the prior's box.
        assert!(domain_from_data(&model, &recording(&[5e4, 6e4]), &[(-1e4, 1e4)]).is_none());
        // A set narrower than the samples resolve (20 wide, samples 800 apart): the prior's.
        assert!(domain_from_data(&model, &recording(&[0.0, 10.0]), &[(-8e6, 8e6)]).is_none());
    }

    /// Through h = x³ the set is the cube roots' range: z in [−8, 27] with R = 0.01 (sd 0.1)
    /// puts x in [−∛8.5, ∛27.5] before the margins (motion 5·√(0.01·1), a tenth of the width).
    #[test]
    fn a_cubic_sensor_gets_the_cube_roots() {
        let model = Model::from_text(&["-x"], &["x^3"], Noise::discrete(0.01))
            .and_then(|m| m.with_diffusion(nalgebra::DMatrix::from_element(1, 1, 0.1)))
            .expect("model");
        let d =
            domain_from_data(&model, &recording(&[-8.0, 27.0]), &[(-100.0, 100.0)]).expect("a box");
        let (lo, hi) = d.bounds[0];
        let (a, b) = (-(8.5f64.cbrt()), 27.5f64.cbrt());
        let margin = 5.0 * (0.01f64 * 1.0).sqrt() + 0.1 * (b - a);
        // Within three samples (0.01 apart) of the exact ends.
        assert!((lo - (a - margin)).abs() < 0.03, "{lo} vs {}", a - margin);
        assert!((hi - (b + margin)).abs() < 0.03, "{hi} vs {}", b + margin);
    }
}
