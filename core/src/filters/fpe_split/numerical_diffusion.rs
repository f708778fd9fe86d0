//! The numerical diffusion of the two schemes where the density is: a self-check of their
//! first-order error.
//!
//! Both schemes of 001 are first order, and their leading error is a diffusion the model does
//! not have (the modified equation of each scheme):
//!
//! * the upwind step (12)–(14) / (19)–(22) of the separation approach solves, to second
//!   order, `∂p/∂t = −f ∂p/∂x + ν ∂²p/∂x²` with `ν_l = ½ |f_l| Δx_l (1 − |f_l| Δt/Δx_l)` per
//!   axis (the classic upwind result; zero only at the CFL number 1);
//! * the implicit Euler step of the unsplit FDM adds `ν_l = ½ f_l² Δt` (implicit Euler on
//!   `∂p/∂t = −f ∂p/∂x`; its central differences add none).
//!
//! Against the model's own diffusion `½ a_ll` (a = G Gᵀ) the ratio is a cell Péclet number
//! (upwind) or a Courant–Péclet product (FDM). Weighted by the density, it says how much wider
//! the scheme makes the predicted density than the model does: at a ratio r a stationary
//! variance comes out about (1 + r) times too large, and the check warns above
//! [`NUMERICAL_DIFFUSION_THRESHOLD`] = 0.1 (the sd then about 5 % off; the FDM's,
//! [`FDM_NUMERICAL_DIFFUSION_THRESHOLD`], is 0.05). The defaults keep it lower under the
//! prior: the separation approach's cells chosen from the problem at half
//! ([`PRIOR_RATIO_TARGET`]), and the FDM's steps, which it shortens until the prior-weighted
//! ratio is a quarter ([`FDM_PRIOR_RATIO_TARGET`]). Measured on the stiff problems of `tests/tests/suite/stiff_edges.rs`
//! before those defaults: ratios of 0.46 and 0.72 left the conditional mean 0.12 and 0.27
//! posterior sd from the reference, 0.053 and 0.071 left it 0.054 and 0.057 sd off, while
//! 0.23 on another problem cost only 0.03 sd — the ratio bounds the error of the predicted
//! spread, not the mean's. With these defaults every run there is within 0.05 sd but one,
//! SA's cells capped at 4000 (0.18 sd off), which this check reports. In a dimension without
//! diffusion of its own (a_ll = 0) the scheme spreads a density the model only transports;
//! there is no model diffusion to compare with, and the check leaves that axis out (the
//! variance it adds there is what the grid's resolution costs).

use crate::filters::Concern;
use crate::grid::TensorGrid;

use super::upwind::UpwindAdvection;
use super::FpeScheme;

/// The largest density-weighted ratio of numerical to model diffusion before the self-check
/// warns (see the module doc).
pub(crate) const NUMERICAL_DIFFUSION_THRESHOLD: f64 = 0.1;

/// The ratio the separation approach's cells chosen from the problem aim for under the
/// prior: half the threshold, room for a posterior that moves to steeper drift.
pub(crate) const PRIOR_RATIO_TARGET: f64 = 0.5 * NUMERICAL_DIFFUSION_THRESHOLD;

/// The FDM's threshold: half the separation approach's. On the double well of the stiff
/// tests a ratio of 0.071 left the FDM 0.057 sd off (a hundredth of the step: 0.005), while
/// on the same problems the separation approach was within 0.03 sd at 0.23.
pub(crate) const FDM_NUMERICAL_DIFFUSION_THRESHOLD: f64 = 0.5 * NUMERICAL_DIFFUSION_THRESHOLD;

/// The ratio the FDM's steps aim for under the prior: a quarter of its threshold (its steps
/// are cheap — a tridiagonal solve per grid line — and the density moves on to steeper
/// drift).
pub(crate) const FDM_PRIOR_RATIO_TARGET: f64 = 0.25 * FDM_NUMERICAL_DIFFUSION_THRESHOLD;

/// The most FPE steps per observation interval the FDM takes for that target; beyond, it
/// keeps this many and the self-check reports the ratio.
pub(crate) const FDM_ACCURACY_SUBSTEPS: usize = 10_000;

/// The self-check's name.
pub(crate) const NUMERICAL_DIFFUSION_CHECK: &str = "numerical diffusion / model diffusion";

/// `max_l Σ_i u_i ν_l(i) / Σ_i u_i ½ a_ll(i)` for the density `u` on `grid` with steps of `dt`:
/// the scheme's numerical diffusion against the model's along the worst axis, where the
/// density is — over the axes the model diffuses along (0 for a density at rest; NaN where
/// the drift or diffusion is not finite there). `diffusion` is the diagonal the implicit step
/// takes (a_ll less what a correlated Q lends its mixed terms, `grid::cross`).
pub(crate) fn numerical_diffusion_ratio(
    scheme: FpeScheme,
    grid: &TensorGrid,
    advection: &UpwindAdvection,
    diffusion: &[alloc::vec::Vec<f64>],
    dt: f64,
    u: &[f64],
) -> f64 {
    let mut worst = 0.0f64;
    for (l, a) in diffusion.iter().enumerate() {
        let dx = grid.spacing()[l];
        let (mut numerical, mut model) = (0.0, 0.0);
        for ((&p, &f), &a) in u.iter().zip(advection.velocity(l)).zip(a) {
            let f = libm::fabs(f);
            let nu = match scheme {
                FpeScheme::Separation => 0.5 * f * dx * (1.0 - f * dt / dx).max(0.0),
                FpeScheme::ImplicitFdm => 0.5 * f * f * dt,
            };
            numerical += p.max(0.0) * nu;
            model += p.max(0.0) * 0.5 * a;
        }
        if numerical.is_nan() || model.is_nan() {
            return f64::NAN;
        }
        // An axis the model does not diffuse along has no diffusion to compare with: skipped
        // (see the module doc).
        if numerical > 0.0 && model > 0.0 {
            worst = worst.max(numerical / model);
        }
    }
    worst
}

/// Pushes the concern when the ratio exceeds the threshold, with the parameter that lowers it.
pub(crate) fn check(scheme: FpeScheme, ratio: f64, out: &mut alloc::vec::Vec<Concern>) {
    let threshold = match scheme {
        FpeScheme::Separation => NUMERICAL_DIFFUSION_THRESHOLD,
        FpeScheme::ImplicitFdm => FDM_NUMERICAL_DIFFUSION_THRESHOLD,
    };
    if ratio > threshold || ratio.is_nan() {
        out.push(Concern::above(
            NUMERICAL_DIFFUSION_CHECK,
            ratio,
            threshold,
            match scheme {
                FpeScheme::Separation => "the upwind step's numerical diffusion ½|f|Δx widens the predicted density beyond the model's: use more cells (a smaller Δx) or a smaller box",
                FpeScheme::ImplicitFdm => "implicit Euler's numerical diffusion ½f²Δt widens the predicted density beyond the model's: use a smaller dt",
            },
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;

    /// A constant drift 2 on 100 nodes of [0, 1] with a = 0.1: upwind's
    /// ν = ½·2·Δx·(1 − 2Δt/Δx) against ½·0.1, and the FDM's ½·4·Δt; no drift, no ratio; no
    /// model diffusion, no axis to compare (0); a NaN diffusion, NaN, which warns.
    #[test]
    fn the_ratios_are_the_modified_equations() {
        let grid = TensorGrid::new(&[(0.0, 1.0)], &[100]).expect("grid");
        let model = crate::model::Model::from_text(
            &["2 + 0*x"],
            &["x"],
            crate::model::Noise::discrete(0.1),
        )
        .expect("model");
        let adv = UpwindAdvection::new(&grid, &*model.drift);
        let u = vec![1.0; 100];
        let a = vec![vec![0.1; 100]];
        let sa = numerical_diffusion_ratio(FpeScheme::Separation, &grid, &adv, &a, 1e-3, &u);
        let dx = grid.spacing()[0];
        let expected = 0.5 * 2.0 * dx * (1.0 - 2.0 * 1e-3 / dx) / 0.05;
        assert!((sa - expected).abs() < 1e-12, "{sa} vs {expected}");
        let fdm = numerical_diffusion_ratio(FpeScheme::ImplicitFdm, &grid, &adv, &a, 1e-3, &u);
        assert!((fdm - 0.5 * 4.0 * 1e-3 / 0.05).abs() < 1e-12, "{fdm}");
        let mut out = vec::Vec::new();
        check(FpeScheme::Separation, sa, &mut out);
        assert_eq!(out.len(), 1, "0.16 > 0.1 warns");
        check(FpeScheme::ImplicitFdm, fdm, &mut out);
        assert_eq!(out.len(), 1, "0.04 < 0.05 does not");
        check(FpeScheme::ImplicitFdm, 1.5 * fdm, &mut out);
        assert_eq!(out.len(), 2, "0.06 does");
        check(FpeScheme::Separation, 1.5 * fdm, &mut out);
        assert_eq!(
            out.len(),
            2,
            "0.06 < 0.1 does not for the separation approach"
        );
        let none = vec![vec![0.0; 100]];
        assert_eq!(
            numerical_diffusion_ratio(FpeScheme::ImplicitFdm, &grid, &adv, &none, 1e-3, &u),
            0.0
        );
        let nan = vec![vec![f64::NAN; 100]];
        let r = numerical_diffusion_ratio(FpeScheme::ImplicitFdm, &grid, &adv, &nan, 1e-3, &u);
        assert!(r.is_nan());
        check(FpeScheme::ImplicitFdm, r, &mut out);
        assert_eq!(out.len(), 3, "NaN warns");
        let still =
            crate::model::Model::from_text(&["0*x"], &["x"], crate::model::Noise::discrete(0.1))
                .expect("model");
        let rest = UpwindAdvection::new(&grid, &*still.drift);
        assert_eq!(
            numerical_diffusion_ratio(FpeScheme::Separation, &grid, &rest, &none, 1e-3, &u),
            0.0
        );
    }
}
