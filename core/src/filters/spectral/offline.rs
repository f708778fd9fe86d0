//! 004 Algorithm 1, the off-line part: the propagation over one observation interval T₀ as a
//! matrix from on-line coefficients to off-line coefficients.
//!
//! With `𝓛 = −(𝓛₀ − ½hᵀS⁻¹h)` (20), `𝓛₀ρ = ½ Σ_ij ∂_i∂_j (a_ij ρ) − Σ_i ∂_i(f_i ρ)` the
//! Fokker–Planck operator (`a = G Gᵀ`; 004 writes `½ Σ_ij Q_ij ∂_i∂_j ρ` for a constant Q, and
//! a state-dependent `a(x)` enters the same way, tabulated at the nodes), and Δs = T₀/N′, the functions `Z_l = (1 + Δs𝓛)^{N′} φ_l` (28) are
//! computed on a tensor Gauss–Legendre grid: φ_l exactly, each application of 𝓛 by the nodal
//! differentiation matrices (the derivative of the polynomial interpolant). For polynomial f and
//! h this is exact as long as the degree of `Z_l` stays below the number of nodes per dimension
//! (the default leaves 24 degrees of room: enough for the cubic sensor with N′ ≤ 3); for other
//! models it is the interpolation (collocation) approximation of 𝓛 applied to the basis. The
//! inner products of the normal matrix A (38) and of the right-hand sides D — one for every
//! on-line basis function φ_k — are Gauss–Legendre sums on the same nodes, and `A W = D` is
//! solved by Cholesky. Column k of W is the off-line solution ρ̃_k(·, T₀) of Algorithm 1, step 6.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::legendre;
use super::tensor;
use super::Layout;
use crate::error::FilterError;
use crate::model::dmz::DmzCoefficients;
use crate::model::Model;

/// The tensor quadrature grid of the off-line computation.
struct Nodes {
    /// Per dimension: nodes on [−1, 1] and weights.
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// Nodal differentiation matrix on [−1, 1].
    diff: DMatrix<f64>,
    /// Points per dimension and dimension count.
    q: usize,
    dims: usize,
}

impl Nodes {
    fn len(&self) -> usize {
        self.q.pow(self.dims as u32)
    }

    fn index(&self, flat: usize, d: usize) -> usize {
        (flat / self.q.pow(d as u32)) % self.q
    }

    /// `out = ∂v/∂ξ_d` (nodal), for values stored with the first dimension fastest: the
    /// differentiation matrix along dimension d.
    fn derivative(&self, v: &[f64], d: usize, out: &mut [f64]) {
        let shape = [self.q; tensor::MAX_DIMS];
        tensor::mode_product(&self.diff, v, &shape[..self.dims], d, out);
    }
}

/// Applies `1 + Δs𝓛` to nodal values `v` in place (with the potential `c.half_hsh`, zero when
/// the likelihood is applied in the update).
fn apply_step(
    nodes: &Nodes,
    layout: &Layout,
    c: &DmzCoefficients,
    diffusion: &[Diffusion],
    ds: f64,
    v: &mut [f64],
) {
    let len = v.len();
    let dims = nodes.dims;
    let mut fp = vec![0.0; len];
    let mut first = vec![0.0; len];
    let mut lo = vec![0.0; len];
    let mut tmp = vec![0.0; len];
    // 𝓛₀v: the drift part −Σ ∂_i(f_i v), then ½ Σ ∂_i ∂_j (a_ij v).
    for d in 0..dims {
        let r = layout.half_width[d];
        for ((p, f), x) in fp.iter_mut().zip(&c.f[d]).zip(v.iter()) {
            *p = f * x;
        }
        nodes.derivative(&fp, d, &mut tmp);
        for (l, t) in lo.iter_mut().zip(&tmp) {
            *l -= t / r;
        }
    }
    for Diffusion { i, j, a } in diffusion {
        for ((p, a), x) in fp.iter_mut().zip(a).zip(v.iter()) {
            *p = a * x;
        }
        nodes.derivative(&fp, *j, &mut first);
        nodes.derivative(&first, *i, &mut tmp);
        let r = layout.half_width[*i] * layout.half_width[*j];
        for (l, t) in lo.iter_mut().zip(&tmp) {
            *l += 0.5 * t / r;
        }
    }
    // (1 + Δs𝓛) v = v − Δs (𝓛₀ v − ½hᵀS⁻¹h v).
    for ((x, l), h) in v.iter_mut().zip(&lo).zip(&c.half_hsh) {
        *x -= ds * (l - h * *x);
    }
}

/// One entry `a_ij` of `a = G Gᵀ` at every quadrature node.
struct Diffusion {
    i: usize,
    j: usize,
    a: Vec<f64>,
}

/// The entries of `a` that are not zero at every node, tabulated there.
fn tabulate_diffusion(model: &Model, nodes: &Nodes, layout: &Layout) -> Vec<Diffusion> {
    let n = nodes.dims;
    let q = model.process_noise();
    let mut entries: Vec<Diffusion> = (0..n * n)
        .map(|k| Diffusion {
            i: k / n,
            j: k % n,
            a: Vec::with_capacity(nodes.len()),
        })
        .collect();
    let mut x = vec![0.0; n];
    let mut a = DMatrix::zeros(n, n);
    for node in 0..nodes.len() {
        for (d, v) in x.iter_mut().enumerate() {
            *v = layout.to_domain(d, nodes.nodes[nodes.index(node, d)]);
        }
        a.fill(0.0);
        q.add_at(&x, 1.0, &mut a);
        for e in entries.iter_mut() {
            e.a.push(a[(e.i, e.j)]);
        }
    }
    entries.retain(|e| e.a.iter().any(|&v| v != 0.0));
    entries
}

/// Tabulates a tensor basis (`counts` functions per dimension) on the nodes, one column per
/// multi-index (first dimension fastest).
fn tabulate_basis(nodes: &Nodes, counts: &[usize]) -> DMatrix<f64> {
    let per_dim: Vec<Vec<Vec<f64>>> = counts
        .iter()
        .map(|&count| {
            nodes
                .nodes
                .iter()
                .map(|&x| legendre::basis(x, count)[0].clone())
                .collect()
        })
        .collect();
    let total: usize = counts.iter().product();
    DMatrix::from_fn(nodes.len(), total, |i, col| {
        let mut rest = col;
        let mut value = 1.0;
        for (d, &count) in counts.iter().enumerate() {
            let k = rest % count;
            rest /= count;
            value *= per_dim[d][nodes.index(i, d)][k];
        }
        value
    })
}

/// Algorithm 1: the matrix W (off-line basis × on-line basis) whose column k holds the
/// coefficients of ρ̃_k(·, T₀).
/// `(t0, partitions)` are T₀ and N′; `potential_in_operator` keeps `½hᵀS⁻¹h` in 𝓛 (20).
pub(crate) fn propagation_matrix(
    model: &Model,
    layout: &Layout,
    (t0, partitions): (f64, usize),
    potential_in_operator: bool,
) -> Result<DMatrix<f64>, FilterError> {
    let quadrature = layout.quadrature;
    let (x, w) = legendre::gauss_legendre(quadrature);
    let nodes = Nodes {
        diff: legendre::differentiation_matrix(&x),
        nodes: x,
        weights: w,
        q: quadrature,
        dims: layout.dims(),
    };
    let mut c =
        DmzCoefficients::tabulate(model, "the spectral filters of 004", nodes.len(), |i, p| {
            for (d, v) in p.iter_mut().enumerate() {
                *v = layout.to_domain(d, nodes.nodes[nodes.index(i, d)]);
            }
        })?;
    if !potential_in_operator {
        c.half_hsh.iter_mut().for_each(|v| *v = 0.0);
    }
    let diffusion = tabulate_diffusion(model, &nodes, layout);
    let ds = t0 / partitions as f64;
    let mut z = tabulate_basis(&nodes, &layout.offline);
    for mut column in z.column_iter_mut() {
        let v = column.as_mut_slice();
        for _ in 0..partitions {
            apply_step(&nodes, layout, &c, &diffusion, ds, v);
        }
    }
    let online = tabulate_basis(&nodes, &layout.online);
    // Quadrature weights of the tensor grid (the Jacobian is a common factor and cancels).
    let weight: Vec<f64> = (0..nodes.len())
        .map(|i| {
            (0..nodes.dims)
                .map(|d| nodes.weights[nodes.index(i, d)])
                .product()
        })
        .collect();
    let mut wz = z.clone();
    for (i, mut row) in wz.row_iter_mut().enumerate() {
        row *= weight[i];
    }
    let a = z.transpose() * &wz;
    let d = wz.transpose() * online;
    solve_normal_equations(a, &d)
}

/// W = A⁻¹ D, the normal equations (37)–(38) of Algorithm 1 solved by Cholesky; refused when
/// A or D is not finite or A is not positive definite.
pub(crate) fn solve_normal_equations(
    a: DMatrix<f64>,
    d: &DMatrix<f64>,
) -> Result<DMatrix<f64>, FilterError> {
    if a.iter().chain(d.iter()).any(|v| !v.is_finite()) {
        return Err(FilterError::Unsuitable(
            "the spectral filter's off-line matrices are not finite: shrink the domain or T₀"
                .into(),
        ));
    }
    let functions = a.nrows();
    let chol = a.cholesky().ok_or_else(|| {
        FilterError::Unsuitable(format!(
            "the normal matrix A (004 (38)) of {functions} off-line basis functions is not positive definite; use fewer off-line basis functions"
        ))
    })?;
    Ok(chol.solve(d))
}
