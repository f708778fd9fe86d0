//! The fourth-order QIEM of 000 (Yueh, Lin, Yau), (20)–(21) and Algorithm 4 (2-D): the
//! 9-point Laplacian diagonalised by the DSTs of QIEM, with a compact right-hand side.

use super::operator::KolmogorovOperator;
use super::qiem::SpectralSolve;
use crate::grid::TensorGrid;

impl SpectralSolve {
    /// The spectral solve of 000 Algorithm 4 (2-D, equal Δs and Q in both dimensions) with the
    /// compact right-hand side: in the DST basis, with `σ_j = −4 sin²(jπ/(2(N+1)))`, the 9-point
    /// Laplacian (20)–(21) has eigenvalues `λ̃ = ((σ_i + 6)(σ_j + 6) − 36)/(6Δs²)` and the 5-point
    /// one `λ₅ = (σ_i + σ_j)/Δs²`. Algorithm 4 divides by `1 − (Δt/2) Q λ̃`; the 9-point stencil
    /// alone is only second order (its error is `(Δs²/12)Δ²u`), so we also apply the compact
    /// (Mehrstellen) operator `I + (Δs²/12)Δ₅` to the right-hand side, which makes the Laplacian
    /// part fourth order: divisor `(1 + cλ₅)/(1 + cλ₅ − (Δt/2) Q λ̃)`, `c = Δs²/12`.
    pub(super) fn new_fourth_order(op: &KolmogorovOperator, grid: &TensorGrid, dt: f64) -> Self {
        let ds = grid.spacing()[0];
        let q = op.diffusion[0];
        let c = ds * ds / 12.0;
        Self::from_symbol(grid, |sin2| {
            let (s1, s2) = (-4.0 * sin2[0], -4.0 * sin2[1]);
            let nine = ((s1 + 6.0) * (s2 + 6.0) - 36.0) / (6.0 * ds * ds);
            let five = (s1 + s2) / (ds * ds);
            (1.0 + c * five) / (1.0 + c * five - 0.5 * dt * q * nine)
        })
    }
}
