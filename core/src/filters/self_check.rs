//! A method's self-check ([`super::Filter::self_check`]): a [`Concern`] when a watched
//! quantity crosses its documented threshold, and the grid filters' checks (mass near the
//! boundary of the box, posterior width in grid cells).

use alloc::vec::Vec;

use super::Estimate;

/// A self-check's finding: the watched quantity crossed its documented threshold, so the
/// method's result may not be trustworthy (see [`Filter::self_check`](super::Filter::self_check)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Concern {
    /// What is watched, e.g. `"mass near the boundary"`.
    pub check: &'static str,
    /// Its value now.
    pub value: f64,
    /// The threshold it crossed.
    pub threshold: f64,
    /// Whether values above the threshold are the problem (else values below it).
    pub above: bool,
    /// What it means and what to change.
    pub advice: &'static str,
}

impl Concern {
    /// `value` is a problem when above `threshold`.
    pub fn above(check: &'static str, value: f64, threshold: f64, advice: &'static str) -> Self {
        Concern {
            check,
            value,
            threshold,
            above: true,
            advice,
        }
    }
    /// `value` is a problem when below `threshold`.
    pub fn below(check: &'static str, value: f64, threshold: f64, advice: &'static str) -> Self {
        Concern {
            check,
            value,
            threshold,
            above: false,
            advice,
        }
    }
}
/// The grid self-check's first threshold: mass on the two outermost nodes of any face, as a
/// share of the density's mass. The grid filters' boundary (zero Dirichlet for the Yau–Yau
/// schemes, outflow for the separation approach) loses mass that reaches the edge of the box,
/// and the renormalisation after each update hides the loss; a density still this close to
/// the boundary is being cut off.
pub(crate) const BOUNDARY_MASS_THRESHOLD: f64 = 1e-4;

/// The grid self-check's second threshold: the posterior's smallest standard deviation in
/// grid spacings, below which the grid cannot resolve it (the observation factor then weighs
/// nodes, not mass).
pub(crate) const WIDTH_IN_CELLS_THRESHOLD: f64 = 2.0;
/// The name of the grid filters' boundary-mass self-check.
pub(crate) const BOUNDARY_MASS_CHECK: &str = "mass near the boundary";

/// The self-check of a density `u` on `grid` with its `estimate` (Yau–Yau and
/// continuous–discrete grid filters): mass near the boundary and width in cells.
pub(crate) fn grid_self_check(
    grid: &crate::grid::TensorGrid,
    u: &[f64],
    estimate: &Estimate,
    out: &mut Vec<Concern>,
) {
    let mass = grid.mass(u);
    let widths: Vec<(f64, f64)> = match &estimate.covariance {
        Some(p) => (0..grid.dim())
            .map(|d| (p[(d, d)], grid.spacing()[d]))
            .collect(),
        None => Vec::new(),
    };
    density_concerns(grid.mass_near_boundary(u, 2) / mass, &widths, out);
}

/// The concerns every grid density shares: `near`, the share of its mass within two nodes
/// of a face, above [`BOUNDARY_MASS_THRESHOLD`], and the posterior's narrowest width in
/// cells — from `(variance, spacing)` per dimension — below
/// [`WIDTH_IN_CELLS_THRESHOLD`].
pub(crate) fn density_concerns(near: f64, widths: &[(f64, f64)], out: &mut Vec<Concern>) {
    if near > BOUNDARY_MASS_THRESHOLD {
        out.push(Concern::above(
            BOUNDARY_MASS_CHECK,
            near,
            BOUNDARY_MASS_THRESHOLD,
            "the density reaches the edge of the box and is cut off there: widen the domain",
        ));
    }
    let cells = widths
        .iter()
        .map(|&(variance, spacing)| libm::sqrt(variance.max(0.0)) / spacing)
        .fold(f64::INFINITY, f64::min);
    if cells < WIDTH_IN_CELLS_THRESHOLD {
        out.push(Concern::below(
            "posterior width in grid cells",
            cells,
            WIDTH_IN_CELLS_THRESHOLD,
            "the posterior is narrower than the grid resolves: use more points or cells, or a smaller box",
        ));
    }
}
