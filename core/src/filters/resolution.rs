//! The narrowest posterior standard deviation a 1-D problem leads one to expect, from which
//! the grid methods choose their resolution when it is left unset (ten points or cells per
//! that width, [`POINTS_PER_SD`]): a constant count would be too coarse for a sharp sensor
//! on a wide box and wasteful for a vague one.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use crate::filters::method::ProblemContext;
use crate::model::ObservationModel;

/// Points (or cells) per expected posterior standard deviation of a grid chosen from the
/// problem: the self-check warns below [`crate::filters::WIDTH_IN_CELLS_THRESHOLD`] per sd,
/// and 000's second-order schemes are within about 10⁻³ of the exact filter at this
/// resolution (the Kalman–Bucy comparison in the tests).
pub(crate) const POINTS_PER_SD: f64 = 10.0;

/// The expected posterior width and what it came from.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ExpectedWidth {
    /// The smaller of the two below.
    pub width: f64,
    /// The prior's standard deviation.
    pub prior_sd: f64,
    /// The steady-state sd of the filter linearised at the prior's most informative point
    /// (∞ where h is flat).
    pub steady: f64,
}

impl ExpectedWidth {
    /// `count` points or cells per [`POINTS_PER_SD`] of the width over `[lo, hi]`, within
    /// `range`.
    pub(crate) fn count(&self, (lo, hi): (f64, f64), range: (usize, usize)) -> usize {
        let wanted = libm::ceil((hi - lo) * POINTS_PER_SD / self.width);
        (wanted.min(range.1 as f64) as usize).max(range.0)
    }

    /// What the count was chosen from, for the note beside it.
    pub(crate) fn describe(&self, range: (usize, usize)) -> String {
        let steady = if self.steady.is_finite() {
            format!("{:.3}", self.steady)
        } else {
            "none (h is flat there)".into()
        };
        format!(
            "{POINTS_PER_SD} per the narrowest posterior sd to expect on the prior's ±3 sd: the smaller of the prior's {:.3} and the linearised filter's steady state {steady} (within {}–{})",
            self.prior_sd, range.0, range.1
        )
    }
}

/// The narrowest posterior sd to expect for a 1-D model over the prior's ±3 sd within the box:
/// the prior's, or the steady state of the filter linearised at the most informative point,
/// whichever is smaller; `None` for n > 1 or a degenerate prior. With c = ∂h/∂x and Q = G Gᵀ
/// (at the prior's mean):
///
/// * increments dy = h dt + dw, E\[dw²\] = S dt: the Riccati equation P' = Q − c²P²/S settles at
///   P = √(Q S)/|c|, with c²/S summed over the components as Σ_j c_j²/S_jj;
/// * measurements z = h(x) + v every Δτ with Var v_j = R_j (the noise's variance, or its
///   value at x for a state-dependent one): the discrete Riccati recursion
///   P = (P + V)/(1 + (P + V) I), V = Q Δτ (Q for a discrete-time map), I = Σ_j c_j²/R_j, settles at the positive root
///   of P² + V P − V/I = 0. A measurement density without a variance (a log-density, Student-t
///   with ν ≤ 2) or an unknown Δτ contributes no steady state.
pub(crate) fn expected_width(problem: &ProblemContext) -> Option<ExpectedWidth> {
    let model = problem.model;
    if model.n != 1 {
        return None;
    }
    let (lo, hi) = problem.bounds[0];
    let prior_sd = libm::sqrt(problem.prior.covariance()[(0, 0)]);
    let centre = problem.prior.mean()[0];
    let (a, b) = (
        (centre - 3.0 * prior_sd).max(lo),
        (centre + 3.0 * prior_sd).min(hi),
    );
    let q = model.process_noise().at(&[centre])[(0, 0)];
    let (mut jacobian, mut hx, mut variance) =
        (vec![0.0; model.m], vec![0.0; model.m], vec![0.0; model.m]);
    let all = vec![true; model.m];
    let mut steady = f64::INFINITY;
    const SAMPLES: usize = 64;
    for k in 0..=SAMPLES {
        let x = a + (b - a) * k as f64 / SAMPLES as f64;
        model.observation.jacobian(&[x], &mut jacobian);
        let sd = match &model.observations {
            ObservationModel::Continuous { noise_cov } => {
                let information: f64 = jacobian
                    .iter()
                    .enumerate()
                    .map(|(i, c)| c * c / noise_cov[(i, i)])
                    .sum();
                libm::sqrt(libm::sqrt(q / information))
            }
            ObservationModel::Discrete { density } => {
                let Some(dt_obs) = problem.dt_obs else {
                    continue;
                };
                use crate::model::measurement::GaussianMatch;
                match density.gaussian_match(model.m) {
                    Ok(GaussianMatch::Constant { cov, .. }) => {
                        for (j, v) in variance.iter_mut().enumerate() {
                            *v = cov[(j, j)];
                        }
                    }
                    Ok(GaussianMatch::StateDependent) => {
                        model.observation.eval(&[x], &mut hx);
                        if density
                            .conditional_variance(&[x], &hx, &all, &mut variance)
                            .is_err()
                        {
                            continue;
                        }
                    }
                    Err(_) => continue,
                }
                let information: f64 = jacobian.iter().zip(&variance).map(|(c, r)| c * c / r).sum();
                // A discrete-time map's noise is per transition (one per Δτ).
                let v = if model.is_discrete_time() {
                    q
                } else {
                    q * dt_obs
                };
                libm::sqrt(0.5 * (-v + libm::sqrt(v * v + 4.0 * v / information)))
            }
        };
        if sd > 0.0 && sd.is_finite() {
            steady = steady.min(sd);
        }
    }
    let width = prior_sd.min(steady);
    (width > 0.0 && width.is_finite()).then_some(ExpectedWidth {
        width,
        prior_sd,
        steady,
    })
}

/// Why a 1-D grid of `shape` points on the problem's box cannot resolve the posterior to
/// expect ([`expected_width`]): fewer than [`crate::filters::WIDTH_IN_CELLS_THRESHOLD`] points
/// per its sd, the width self-check's bound, which a run would then report at every step.
/// `None` when it can, or when nothing is expected (n > 1, a degenerate prior). For a box
/// chosen around a diffuse prior (the Nile's N(1120, 10⁷): a box 38 000 wide for a posterior
/// some 60 wide) this is the refusal "give a domain".
pub(crate) fn too_coarse(problem: &ProblemContext, shape: &[usize]) -> Option<String> {
    let width = expected_width(problem)?;
    let (&points, &(lo, hi)) = (shape.first()?, problem.bounds.first()?);
    let per_sd = points as f64 * width.width / (hi - lo);
    (per_sd < crate::filters::WIDTH_IN_CELLS_THRESHOLD).then(|| {
        format!(
            "{points} points on [{lo:.4e}, {hi:.4e}] put {per_sd:.3} in the narrowest posterior sd to expect ({:.3e}; {}), fewer than the {} the grid needs to resolve it",
            width.width,
            if width.steady < width.prior_sd {
                "the linearised filter's steady state"
            } else {
                "the prior's"
            },
            crate::filters::WIDTH_IN_CELLS_THRESHOLD
        )
    })
}
/// One count for every dimension, or the per-dimension list as given.
pub(crate) fn per_dimension(counts: &[usize], n: usize) -> Vec<usize> {
    match counts.len() {
        1 => alloc::vec![counts[0]; n],
        _ => counts.to_vec(),
    }
}

/// The product of `counts`, or `None` on overflow.
pub(crate) fn product(counts: &[usize]) -> Option<usize> {
    counts.iter().try_fold(1usize, |a, &k| a.checked_mul(k))
}

/// A per-dimension count list must have one entry or `n`.
pub(crate) fn count_problem(
    field: &'static str,
    counts: &[usize],
    n: usize,
    problems: &mut Vec<(&'static str, String)>,
) {
    if counts.len() != 1 && counts.len() != n {
        problems.push((
            field,
            alloc::format!("give one count or {n}, got {}", counts.len()),
        ));
    }
}
