//! Legendre polynomials, the generalized Legendre basis of 004's appendix, Gauss–Legendre
//! quadrature and the nodal differentiation matrix, all on U = [−1, 1].
//!
//! * Legendre `L_k` by the three-term recurrence `L_{k+1} = ((2k+1) x L_k − k L_{k−1})/(k+1)`
//!   and their derivatives by `(1 − x²) L_k′ = k (L_{k−1} − x L_k)` — in the form
//!   `L_{k+1}′ = L_{k−1}′ + (2k+1) L_k`, which also holds at x = ±1;
//! * the generalized basis (appendix, Lemma 1) `φ_k = c_k (L_k − L_{k+2})`,
//!   `c_k = 1/√(4k+6)`, which vanishes at ±1, and its mass matrix (49):
//!   `b_kk = c_k²(2/(2k+1) + 2/(2k+5))`, `b_{k,k+2} = −c_k c_{k+2} 2/(2k+5)`;
//! * Gauss–Legendre nodes as the roots of `L_N` by Newton's method from the Chebyshev-like
//!   guesses `cos(π(i − ¼)/(N + ½))`, weights `2/((1 − x²) L_N′(x)²)`;
//! * the differentiation matrix of the polynomial interpolant on the nodes, from the
//!   barycentric weights `λ_j = 1/Π_{k≠j}(x_j − x_k)`: `D_ij = (λ_j/λ_i)/(x_i − x_j)`,
//!   `D_ii = −Σ_{j≠i} D_ij` (exact for polynomials of degree < N).

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

/// `L_0(x) … L_{count−1}(x)` and their first and second derivatives.
pub(crate) fn legendre(x: f64, count: usize) -> [Vec<f64>; 3] {
    let mut l = vec![0.0; count];
    let mut d1 = vec![0.0; count];
    let mut d2 = vec![0.0; count];
    if count > 0 {
        l[0] = 1.0;
    }
    if count > 1 {
        l[1] = x;
        d1[1] = 1.0;
    }
    for k in 1..count.saturating_sub(1) {
        let kf = k as f64;
        l[k + 1] = ((2.0 * kf + 1.0) * x * l[k] - kf * l[k - 1]) / (kf + 1.0);
        d1[k + 1] = d1[k - 1] + (2.0 * kf + 1.0) * l[k];
        d2[k + 1] = d2[k - 1] + (2.0 * kf + 1.0) * d1[k];
    }
    [l, d1, d2]
}

/// `c_k = 1/√(4k + 6)`.
fn scale(k: usize) -> f64 {
    1.0 / libm::sqrt(4.0 * k as f64 + 6.0)
}

/// `φ_0(x) … φ_{count−1}(x)` with first and second derivatives.
pub(crate) fn basis(x: f64, count: usize) -> [Vec<f64>; 3] {
    let all = legendre(x, count + 2);
    let mut out = [vec![0.0; count], vec![0.0; count], vec![0.0; count]];
    for (o, l) in out.iter_mut().zip(&all) {
        for (k, v) in o.iter_mut().enumerate() {
            *v = scale(k) * (l[k] - l[k + 2]);
        }
    }
    out
}

/// The mass matrix `b_kj = ⟨φ_k, φ_j⟩` on [−1, 1], (49).
pub(crate) fn mass_matrix(count: usize) -> DMatrix<f64> {
    DMatrix::from_fn(count, count, |k, j| {
        let (lo, hi) = (k.min(j), k.max(j));
        if k == j {
            let kf = k as f64;
            scale(k) * scale(k) * (2.0 / (2.0 * kf + 1.0) + 2.0 / (2.0 * kf + 5.0))
        } else if hi == lo + 2 {
            -scale(lo) * scale(hi) * 2.0 / (2.0 * hi as f64 + 1.0)
        } else {
            0.0
        }
    })
}

/// `∫_{−1}^{1} φ_k dx` (only φ_0 has a nonzero integral: 2 c_0).
pub(crate) fn basis_integral(k: usize) -> f64 {
    if k == 0 {
        2.0 * scale(0)
    } else {
        0.0
    }
}

/// Gauss–Legendre nodes (ascending) and weights of `n` points on [−1, 1].
pub(crate) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut x = libm::cos(core::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        let mut derivative = 1.0;
        for _ in 0..100 {
            let [l, d1, _] = legendre(x, n + 1);
            derivative = d1[n];
            let dx = l[n] / derivative;
            x -= dx;
            if dx.abs() <= 1e-16 {
                break;
            }
        }
        let [_, d1, _] = legendre(x, n + 1);
        derivative = if d1[n].is_finite() { d1[n] } else { derivative };
        let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[n - 1 - i] = x;
        nodes[i] = -x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// The differentiation matrix of the interpolating polynomial on `nodes`.
pub(crate) fn differentiation_matrix(nodes: &[f64]) -> DMatrix<f64> {
    let n = nodes.len();
    // Barycentric weights, scaled by a common factor (only their ratios matter).
    let lambda: Vec<f64> = (0..n)
        .map(|j| {
            let p: f64 = (0..n)
                .filter(|&k| k != j)
                .map(|k| 2.0 * (nodes[j] - nodes[k]))
                .product();
            1.0 / p
        })
        .collect();
    let mut d = DMatrix::zeros(n, n);
    for i in 0..n {
        let mut diagonal = 0.0;
        for j in 0..n {
            if i != j {
                let v = lambda[j] / lambda[i] / (nodes[i] - nodes[j]);
                d[(i, j)] = v;
                diagonal -= v;
            }
        }
        d[(i, i)] = diagonal;
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn quadrature_is_exact_to_degree_2n_minus_1() {
        for n in [1usize, 2, 5, 16, 40, 80] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n = {n}");
            for p in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(p as i32)).sum();
                let exact = if p % 2 == 1 {
                    0.0
                } else {
                    2.0 / (p as f64 + 1.0)
                };
                assert!((q - exact).abs() < 1e-12, "n = {n}, degree {p}: {q}");
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]));
        }
    }

    #[test]
    fn basis_vanishes_at_the_ends_and_has_the_closed_form_mass_matrix() {
        let count = 12;
        for end in [-1.0, 1.0] {
            let [v, _, _] = basis(end, count);
            assert!(v.iter().all(|v| v.abs() < 1e-14));
        }
        let (x, w) = gauss_legendre(30);
        let b = mass_matrix(count);
        let tabulated: Vec<[Vec<f64>; 3]> = x.iter().map(|&x| basis(x, count)).collect();
        for k in 0..count {
            let integral: f64 = tabulated.iter().zip(&w).map(|(t, w)| w * t[0][k]).sum();
            assert!((integral - basis_integral(k)).abs() < 1e-14);
            for j in 0..count {
                let q: f64 = tabulated
                    .iter()
                    .zip(&w)
                    .map(|(t, w)| w * t[0][k] * t[0][j])
                    .sum();
                assert!(
                    (q - b[(k, j)]).abs() < 1e-14,
                    "b[{k}][{j}] {q} vs {}",
                    b[(k, j)]
                );
            }
        }
    }

    #[test]
    fn derivatives_match_differences_and_the_differentiation_matrix() {
        let count = 10;
        let h = 1e-5;
        for &x in &[-0.93, -0.2, 0.0, 0.41, 0.999] {
            let [v, d1, d2] = basis(x, count);
            let [vp, d1p, _] = basis(x + h, count);
            let [vm, d1m, _] = basis(x - h, count);
            for k in 0..count {
                assert!((d1[k] - (vp[k] - vm[k]) / (2.0 * h)).abs() < 1e-6 * (1.0 + d1[k].abs()));
                assert!((d2[k] - (d1p[k] - d1m[k]) / (2.0 * h)).abs() < 1e-5 * (1.0 + d2[k].abs()));
                let _ = v[k];
            }
        }
        let (nodes, _) = gauss_legendre(24);
        let d = differentiation_matrix(&nodes);
        for k in 0..count {
            let values: Vec<f64> = nodes.iter().map(|&x| basis(x, count)[0][k]).collect();
            for (i, &x) in nodes.iter().enumerate() {
                let numeric: f64 = (0..nodes.len()).map(|j| d[(i, j)] * values[j]).sum();
                let exact = basis(x, count)[1][k];
                assert!(
                    (numeric - exact).abs() < 1e-10,
                    "k = {k}: {numeric} vs {exact}"
                );
            }
        }
    }
}
