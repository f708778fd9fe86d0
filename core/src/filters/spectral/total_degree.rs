//! The complete polynomial basis of total degree at most N, for 004's "moderate-high
//! dimensional cases" (its abstract): the generalized Legendre products
//! `φ_k(x) = Π_d φ_{k_d}(x_d)` with `|k|₁ = k_1 + ⋯ + k_n ≤ N`, `binomial(N + n, n)` functions
//! instead of the tensor basis' `(N + 1)ⁿ` (004's appendix (48) writes its `S_N^n` with
//! `‖k‖_∞ ≤ N`, the tensor basis of [`super::tensor`]; this module is the total-degree set).
//!
//! * **Order.** The multi-indices of `n` dimensions and degree `N` are ordered by their last
//!   component, outermost: the block of `k_n = j` holds the set of `n − 1` dimensions and
//!   degree `N − j`, recursively, so that every such block is contiguous.
//! * **Evaluation by sum factorisation.** On a tensor grid with `q_d` points along dimension
//!   d, `Σ_k c_k Π_d φ_{k_d}(x_d) = Σ_{j=0}^{N} φ_j(x_n) · (the (n−1)-dimensional expansion of
//!   degree N − j)`: `(N + 1) Π q_d` multiply–adds at the top level (and fewer below) instead
//!   of `binomial(N + n, n) Π q_d`. The projection onto the basis, `⟨v, φ_k⟩` for every k, is
//!   its transpose.
//! * **Off-line (004 Algorithm 1, N′ = 1).** `Z_l = (1 + Δs𝓛) φ_l` for every off-line
//!   function, with `𝓛₀φ = ½ Σ_ij a_ij ∂_i∂_j φ − (∇·f) φ − Σ_i f_i ∂_i φ` (a constant `a =
//!   G Gᵀ`) written out from the one-dimensional derivatives — exact, no differentiation
//!   matrix — and the normal matrix A (38) and right-hand sides D accumulated over chunks of a
//!   tensor Gauss–Legendre grid, so that the functions' values at every node are never held at
//!   once.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::legendre;
use super::Layout;
use crate::error::FilterError;
use crate::model::dmz::DmzCoefficients;
use crate::model::Model;

/// Largest state dimension of the total-degree basis.
pub(crate) const MAX_DIMS: usize = 6;

/// `binomial(n, k)`, or `usize::MAX` when it does not fit (each partial product
/// `binomial(n, i + 1)` is an integer, computed in 128 bits before the division).
pub(crate) fn binomial(n: usize, k: usize) -> usize {
    let k = k.min(n.saturating_sub(k));
    let mut acc: u128 = 1;
    for i in 0..k {
        acc = acc * (n - i) as u128 / (i + 1) as u128;
        if acc > usize::MAX as u128 {
            return usize::MAX;
        }
    }
    acc as usize
}

/// The functions of the total-degree sets of the off-line and on-line counts (N + 1 each) in
/// n dimensions, `(M₁, M₂)`.
pub(crate) fn set_sizes(offline: usize, online: usize, n: usize) -> (usize, usize) {
    (
        binomial(offline.max(1) - 1 + n, n),
        binomial(online.max(1) - 1 + n, n),
    )
}

/// The multi-indices `k ∈ ℕⁿ` with `|k|₁ ≤ degree`, in the module's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TotalDegree {
    /// n.
    pub dims: usize,
    /// N.
    pub degree: usize,
}

impl TotalDegree {
    /// `binomial(N + n, n)`.
    pub(crate) fn len(self) -> usize {
        binomial(self.degree + self.dims, self.dims)
    }

    /// The set of one dimension fewer and degree `N − j`: the block of last component j.
    fn block(self, j: usize) -> TotalDegree {
        TotalDegree {
            dims: self.dims - 1,
            degree: self.degree - j,
        }
    }

    /// Every multi-index, in order (first component first in each).
    pub(crate) fn indices(self) -> Vec<Vec<usize>> {
        if self.dims == 0 {
            return vec![Vec::new()];
        }
        let mut all = Vec::with_capacity(self.len());
        for j in 0..=self.degree {
            for mut k in self.block(j).indices() {
                k.push(j);
                all.push(k);
            }
        }
        all
    }
}

/// One dimension's basis functions at its points: `values[i + points·k] = φ_k(ξ_i)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Table<'a> {
    pub values: &'a [f64],
    pub points: usize,
}

impl<'a> Table<'a> {
    /// A (points × functions) matrix's columns.
    pub(crate) fn of(m: &'a DMatrix<f64>) -> Self {
        Table {
            values: m.as_slice(),
            points: m.nrows(),
        }
    }
}

/// `out[i_1 + q_1 i_2 + …] = Σ_{k ∈ set} c_k Π_d tables[d](i_d, k_d)` (first dimension
/// fastest), by sum factorisation over the last dimension; `scratch[d]` holds at least the
/// points of the first `d + 1` dimensions' grid (grown when shorter).
pub(crate) fn evaluate(
    set: TotalDegree,
    c: &[f64],
    tables: &[Table],
    out: &mut [f64],
    scratch: &mut [Vec<f64>],
) {
    let n = set.dims;
    debug_assert!(n >= 1 && tables.len() == n && c.len() == set.len());
    let last = tables[n - 1];
    if n == 1 {
        for (i, o) in out[..last.points].iter_mut().enumerate() {
            *o = (0..=set.degree)
                .map(|k| c[k] * last.values[i + last.points * k])
                .sum();
        }
        return;
    }
    let inner: usize = tables[..n - 1].iter().map(|t| t.points).product();
    let (lower, upper) = scratch.split_at_mut(n - 2);
    let block_values = &mut upper[0];
    if block_values.len() < inner {
        block_values.resize(inner, 0.0);
    }
    let out = &mut out[..inner * last.points];
    out.iter_mut().for_each(|v| *v = 0.0);
    let mut offset = 0;
    for j in 0..=set.degree {
        let block = set.block(j);
        let len = block.len();
        evaluate(
            block,
            &c[offset..offset + len],
            &tables[..n - 1],
            &mut block_values[..inner],
            lower,
        );
        offset += len;
        for (i, slab) in out.chunks_exact_mut(inner).enumerate() {
            let f = last.values[i + last.points * j];
            for (o, v) in slab.iter_mut().zip(&block_values[..inner]) {
                *o += f * v;
            }
        }
    }
}

/// The transpose of [`evaluate`]: `out[k] = Σ_i v_i Π_d tables[d](i_d, k_d)` for every k of
/// `set`, `v` on the tables' grid (first dimension fastest).
pub(crate) fn project(
    set: TotalDegree,
    v: &[f64],
    tables: &[Table],
    out: &mut [f64],
    scratch: &mut [Vec<f64>],
) {
    let n = set.dims;
    let last = tables[n - 1];
    if n == 1 {
        for (k, o) in out[..=set.degree].iter_mut().enumerate() {
            let column = &last.values[last.points * k..last.points * (k + 1)];
            *o = column.iter().zip(v).map(|(a, b)| a * b).sum();
        }
        return;
    }
    let inner: usize = tables[..n - 1].iter().map(|t| t.points).product();
    let (lower, upper) = scratch.split_at_mut(n - 2);
    let summed = &mut upper[0];
    if summed.len() < inner {
        summed.resize(inner, 0.0);
    }
    let mut offset = 0;
    for j in 0..=set.degree {
        let summed = &mut summed[..inner];
        summed.iter_mut().for_each(|s| *s = 0.0);
        for (i, slab) in v[..inner * last.points].chunks_exact(inner).enumerate() {
            let f = last.values[i + last.points * j];
            for (s, x) in summed.iter_mut().zip(slab) {
                *s += f * x;
            }
        }
        let block = set.block(j);
        let len = block.len();
        project(
            block,
            summed,
            &tables[..n - 1],
            &mut out[offset..offset + len],
            lower,
        );
        offset += len;
    }
}

/// Scratch for [`evaluate`] and [`project`] in `dims` dimensions.
pub(crate) fn scratch(dims: usize) -> Vec<Vec<f64>> {
    vec![Vec::new(); dims.saturating_sub(1).max(1)]
}

/// The basis' mass matrix restricted to `set`, `B_kl = Π_d b_{k_d l_d}` ((49) per dimension).
pub(crate) fn mass_matrix(set: TotalDegree) -> DMatrix<f64> {
    let b = legendre::mass_matrix(set.degree + 1);
    let indices = set.indices();
    DMatrix::from_fn(indices.len(), indices.len(), |r, c| {
        indices[r]
            .iter()
            .zip(&indices[c])
            .map(|(&k, &l)| b[(k, l)])
            .product()
    })
}

/// Of coefficients on `indices`: Σc² (after `c ← c·scale`) and, the largest over the
/// dimensions, Σc² over the functions whose degree in that dimension is in the top quarter of
/// `0..=degree` — the spectral self-check's numbers, as the tensor basis measures them. (The
/// share of the top quarter of the *total* degrees does not track the error: on the 2-D test
/// model it is 0.66, 0.15 and 0.09 at degrees 8, 14 and 20, whose means are 0.27, 0.026 and
/// 0.0027 sds off, where the per-dimension share falls 0.075, 0.0031, 0.00006.)
pub(crate) fn scale_and_measure(
    coeffs: &mut [f64],
    scale: f64,
    indices: &[Vec<usize>],
    degree: usize,
) -> (f64, f64) {
    let from = (degree + 1) - (degree + 1).div_ceil(4);
    let dims = indices.first().map_or(0, Vec::len);
    let mut tails = [0.0; MAX_DIMS];
    let mut total = 0.0;
    for (c, k) in coeffs.iter_mut().zip(indices) {
        *c *= scale;
        let e = *c * *c;
        total += e;
        for (t, &kd) in tails.iter_mut().zip(k) {
            if kd >= from {
                *t += e;
            }
        }
    }
    let worst = tails[..dims].iter().copied().fold(0.0, f64::max);
    (total, worst)
}

/// 004 Algorithm 1 on the total-degree basis: the matrix W (off-line functions × on-line
/// functions) whose column k holds the coefficients of ρ̃_k(·, T₀), from
/// `Z_l = (1 + T₀𝓛) φ_l` (one implicit Euler step, N′ = 1) on a tensor Gauss–Legendre grid of
/// `layout.quadrature` points per dimension. `potential_in_operator` keeps `½hᵀS⁻¹h` in 𝓛.
pub(crate) fn propagation_matrix(
    model: &Model,
    layout: &Layout,
    t0: f64,
    potential_in_operator: bool,
) -> Result<DMatrix<f64>, FilterError> {
    let n = layout.dims();
    let (offline, online) = layout.total_degree();
    let q = layout.quadrature;
    let (xi, w) = legendre::gauss_legendre(q);
    // Per node of the 1-D rule: φ_k, φ_k′, φ_k″ of the off-line count, φ_k of the on-line.
    let count = offline.degree.max(online.degree) + 1;
    let one_d: Vec<[Vec<f64>; 3]> = xi.iter().map(|&x| legendre::basis(x, count)).collect();
    let a = constant_diffusion(model)?;
    let off_indices = offline.indices();
    let on_indices = online.indices();
    let (m1, m2) = (off_indices.len(), on_indices.len());
    let total = q.pow(n as u32);
    const CHUNK: usize = 1024;
    let mut gram = DMatrix::<f64>::zeros(m1, m1);
    let mut rhs = DMatrix::<f64>::zeros(m1, m2);
    let mut node = vec![0usize; n];
    let (mut v, mut d1, mut d2) = ([0.0; MAX_DIMS], [0.0; MAX_DIMS], [0.0; MAX_DIMS]);
    for start in (0..total).step_by(CHUNK) {
        let len = CHUNK.min(total - start);
        let index = |flat: usize, d: usize| (flat / q.pow(d as u32)) % q;
        let c = DmzCoefficients::tabulate(model, "the spectral filters of 004", len, |i, x| {
            for (d, v) in x.iter_mut().enumerate() {
                *v = layout.to_domain(d, xi[index(start + i, d)]);
            }
        })?;
        let mut z = DMatrix::<f64>::zeros(len, m1);
        let mut phi = DMatrix::<f64>::zeros(len, m2);
        for p in 0..len {
            for (d, i) in node.iter_mut().enumerate() {
                *i = index(start + p, d);
            }
            let weight: f64 = node.iter().map(|&i| w[i]).product();
            let div = c.div_f[p];
            let potential = if potential_in_operator {
                c.half_hsh[p]
            } else {
                0.0
            };
            for (l, k) in off_indices.iter().enumerate() {
                for d in 0..n {
                    let [f0, f1, f2] = &one_d[node[d]];
                    let r = layout.half_width[d];
                    v[d] = f0[k[d]];
                    d1[d] = f1[k[d]] / r;
                    d2[d] = f2[k[d]] / (r * r);
                }
                // Products of the values before and after each dimension: Π over the others
                // without dividing (a factor φ_k(ξ) may be zero).
                let mut before = [1.0; MAX_DIMS + 1];
                let mut after = [1.0; MAX_DIMS + 1];
                for d in 0..n {
                    before[d + 1] = before[d] * v[d];
                    after[n - 1 - d] = after[n - d] * v[n - 1 - d];
                }
                let all = before[n];
                let mut l0 = -div * all;
                for d in 0..n {
                    let others = before[d] * after[d + 1];
                    l0 += 0.5 * a[(d, d)] * d2[d] * others - c.f[d][p] * d1[d] * others;
                    for e in d + 1..n {
                        if a[(d, e)] != 0.0 {
                            // ½ (a_de + a_ed) ∂_d ∂_e φ, a symmetric.
                            let between: f64 = v[d + 1..e].iter().product();
                            l0 += a[(d, e)] * d1[d] * d1[e] * before[d] * between * after[e + 1];
                        }
                    }
                }
                // (1 + Δs𝓛) φ = φ − Δs (𝓛₀ φ − ½hᵀS⁻¹h φ), as the tensor basis' off-line step.
                z[(p, l)] = (all - t0 * (l0 - potential * all)) * libm::sqrt(weight);
            }
            for (k, idx) in on_indices.iter().enumerate() {
                let value: f64 = idx
                    .iter()
                    .enumerate()
                    .map(|(d, &kd)| one_d[node[d]][0][kd])
                    .product();
                phi[(p, k)] = value * libm::sqrt(weight);
            }
        }
        // Both carry √w, so the products carry w: A += Zᵀ W Z, D += Zᵀ W Φ.
        gram.gemm_tr(1.0, &z, &z, 1.0);
        rhs.gemm_tr(1.0, &z, &phi, 1.0);
    }
    super::offline::solve_normal_equations(gram, &rhs)
}

/// `a = G Gᵀ`, which the total-degree off-line step needs constant (its derivatives are not
/// written out).
fn constant_diffusion(model: &Model) -> Result<DMatrix<f64>, FilterError> {
    model.process_noise().constant().cloned().ok_or_else(|| {
        FilterError::Unsuitable(
            "the total-degree spectral basis needs a constant G Gᵀ (its off-line step writes out the derivatives of φ only): use basis = tensor in 1–3 dimensions".into(),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn the_set_has_binomial_many_indices_in_blocks_of_the_last_component() {
        for (dims, degree) in [(1, 4), (2, 3), (3, 5), (6, 4)] {
            let set = TotalDegree { dims, degree };
            let all = set.indices();
            assert_eq!(all.len(), binomial(degree + dims, dims));
            assert!(all
                .iter()
                .all(|k| k.len() == dims && k.iter().sum::<usize>() <= degree));
            let mut sorted = all.clone();
            sorted.sort();
            sorted.dedup();
            assert_eq!(sorted.len(), all.len(), "distinct");
            // Blocks of the last component, contiguous and in increasing order.
            assert!(all.windows(2).all(|w| w[0][dims - 1] <= w[1][dims - 1]));
        }
        assert_eq!(binomial(10, 6), 210);
        assert_eq!(binomial(12, 6), 924);
    }

    /// Sum factorisation and its transpose against the definition, entry by entry, on grids of
    /// different sizes per dimension.
    #[test]
    fn evaluation_and_projection_match_the_definition() {
        for (points, degree) in [
            (vec![5], 3),
            (vec![4, 3], 2),
            (vec![3, 4, 2], 3),
            (vec![2, 3, 2, 3], 2),
        ] {
            let dims = points.len();
            let set = TotalDegree { dims, degree };
            let tables: Vec<Vec<f64>> = points
                .iter()
                .enumerate()
                .map(|(d, &q)| {
                    (0..q * (degree + 1))
                        .map(|i| libm::sin(0.7 * i as f64 + d as f64))
                        .collect()
                })
                .collect();
            let view: Vec<Table> = tables
                .iter()
                .zip(&points)
                .map(|(t, &q)| Table {
                    values: t,
                    points: q,
                })
                .collect();
            let indices = set.indices();
            let c: Vec<f64> = (0..set.len()).map(|i| libm::cos(0.3 * i as f64)).collect();
            let total: usize = points.iter().product();
            let node = |mut flat: usize| -> Vec<usize> {
                points
                    .iter()
                    .map(|&q| {
                        let i = flat % q;
                        flat /= q;
                        i
                    })
                    .collect()
            };
            let basis = |i: usize, k: &[usize]| -> f64 {
                let at = node(i);
                (0..dims)
                    .map(|d| tables[d][at[d] + points[d] * k[d]])
                    .product()
            };
            let mut out = vec![f64::NAN; total];
            let mut scratch = scratch(dims);
            evaluate(set, &c, &view, &mut out, &mut scratch);
            for (i, o) in out.iter().enumerate() {
                let want: f64 = indices.iter().zip(&c).map(|(k, c)| c * basis(i, k)).sum();
                assert!(
                    (o - want).abs() < 1e-12 * (1.0 + want.abs()),
                    "{points:?} {i}: {o} {want}"
                );
            }
            let v: Vec<f64> = (0..total).map(|i| libm::sin(1.1 * i as f64)).collect();
            let mut p = vec![f64::NAN; set.len()];
            project(set, &v, &view, &mut p, &mut scratch);
            for (k, got) in indices.iter().zip(&p) {
                let want: f64 = (0..total).map(|i| v[i] * basis(i, k)).sum();
                assert!(
                    (got - want).abs() < 1e-12 * (1.0 + want.abs()),
                    "{points:?} {k:?}"
                );
            }
        }
    }
}
