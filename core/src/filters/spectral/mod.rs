//! The off-line/on-line spectral Yau–Yau filter of 004 ("DMZ method"), on the generalized
//! Legendre basis of its appendix, for n = 1 and 2.
//!
//! The domain box is mapped affinely onto U = [−1, 1]ⁿ. Off-line ([`offline`], Algorithm 1):
//! the Kolmogorov equation (17) over one observation interval T₀ becomes a matrix W from the
//! coefficients of the density on the on-line basis (N₂ functions per dimension) to those of
//! the propagated density on the off-line basis (N₁ per dimension). On-line (Algorithm 2),
//! per observation interval and without keeping any past observation:
//!
//! 1. propagation (40): `g = W c`;
//! 2. the density at the on-line Gauss–Legendre nodes, the robust-form factor
//!    `exp(hᵀS⁻¹Δy)` of (42) there (shifted by its largest exponent, so it cannot overflow;
//!    the constant cancels in the normalisation);
//! 3. estimate (41): mean, covariance and the largest node from the nodal values;
//! 4. projection (39) of the updated density onto the on-line basis: `c = B⁻¹⟨ρ, φ_k⟩`, the
//!    mass matrix B of (49) being the tensor product of the closed form.
//!
//! Steps 2 and 4 use the tensor structure (two small matrix products per dimension pair); in
//! 1-D the evaluation of step 2 is folded into W off-line, so steps 1–2 are one product. The
//! whole step is about a thousand multiply–adds and 35 exponentials in 1-D. The density is a polynomial and can dip below
//! zero where it is small; those values are kept (as in 004) in the moments and clipped to zero
//! only in the plotted marginals.

pub mod legendre;
pub mod offline;

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::FilterError;
use crate::filters::{Estimate, Filter, Observation};
use crate::linalg;
use crate::model::dmz::{DmzCoefficients, Likelihood};
use crate::model::{Model, Prior};

/// Largest number of basis functions per dimension.
pub const MAX_BASIS: usize = 128;
/// Largest number of quadrature nodes per dimension.
pub const MAX_NODES: usize = 512;

/// Parameters of the spectral filter (004 Algorithm 1–2). Counts are per dimension.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpectralParams {
    /// N₁ + 1, off-line basis functions per dimension (default: 11 in 1-D, 15 in 2-D, 004's
    /// examples).
    pub offline_basis: Option<usize>,
    /// N₂ + 1, on-line basis functions per dimension (default: 16 in 1-D, 15 in 2-D).
    pub online_basis: Option<usize>,
    /// N′, Euler steps of the off-line operator `(1 + Δs𝓛)^{N′}` over T₀ (default 1, as 004).
    pub partitions: usize,
    /// T₀, the interval the off-line operator covers; it must be the observation interval Δτ
    /// (default: Δτ).
    pub t0: Option<f64>,
    /// Gauss–Legendre nodes per dimension of the off-line computation (default
    /// 2·max(N₁, N₂) + 24).
    pub quadrature: Option<usize>,
    /// Gauss–Legendre nodes per dimension on-line (default N₁ + N₂ + 8).
    pub online_nodes: Option<usize>,
    /// Where `−½hᵀS⁻¹h` goes: 004 (17) has it in the operator, which the implicit off-line
    /// step damps only by `1/(1 + ½hᵀS⁻¹h Δs)` — for steep h far out in the domain that loses
    /// against `exp(hᵀS⁻¹Δy)` and the filter blows up; the default applies it with the factor
    /// (42) as the bounded likelihood instead.
    pub likelihood: Likelihood,
}

impl Default for SpectralParams {
    fn default() -> Self {
        SpectralParams {
            offline_basis: None,
            online_basis: None,
            partitions: 1,
            t0: None,
            quadrature: None,
            online_nodes: None,
            likelihood: Likelihood::InUpdate,
        }
    }
}

/// The resolved sizes for an n-dimensional model.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Off-line basis functions per dimension.
    pub offline: Vec<usize>,
    /// On-line basis functions per dimension.
    pub online: Vec<usize>,
    /// Off-line quadrature nodes per dimension.
    pub quadrature: usize,
    /// On-line nodes per dimension.
    pub online_nodes: usize,
    /// Centre of the domain per dimension.
    pub centre: Vec<f64>,
    /// Half-width of the domain per dimension.
    pub half_width: Vec<f64>,
}

impl Layout {
    /// Dimension n.
    pub fn dims(&self) -> usize {
        self.offline.len()
    }
    /// `x = centre + half_width · ξ`.
    pub fn to_domain(&self, d: usize, xi: f64) -> f64 {
        self.centre[d] + self.half_width[d] * xi
    }
}

impl SpectralParams {
    /// Off-line and on-line basis counts per dimension (N₁ + 1, N₂ + 1) for an `n`-dimensional
    /// model, the defaults filled in.
    pub fn counts(&self, n: usize) -> (usize, usize) {
        let (off, on) = if n == 1 { (11, 16) } else { (15, 15) };
        (
            self.offline_basis.unwrap_or(off),
            self.online_basis.unwrap_or(on),
        )
    }

    /// Every problem with these parameters for an n-dimensional model, `(field, message)`.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if !(1..=2).contains(&n) {
            p.push((
                "method",
                format!("the spectral filter is built for n = 1 and 2; the model has n = {n}"),
            ));
            return p;
        }
        let (off, on) = self.counts(n);
        for (field, v) in [("offline_basis", off), ("online_basis", on)] {
            if !(1..=MAX_BASIS).contains(&v) {
                p.push((field, format!("must be between 1 and {MAX_BASIS}, got {v}")));
            }
        }
        if !(1..=50).contains(&self.partitions) {
            p.push((
                "partitions",
                format!("N′ must be between 1 and 50, got {}", self.partitions),
            ));
        }
        if let Some(t0) = self.t0 {
            if !(t0.is_finite() && t0 > 0.0) {
                p.push(("t0", format!("T₀ must be positive and finite, got {t0}")));
            }
        }
        let largest = off.max(on);
        let quadrature = self.quadrature.unwrap_or(2 * largest + 24);
        if quadrature < largest + 2 || quadrature > MAX_NODES {
            p.push((
                "quadrature",
                format!(
                    "needs between {} (two more than the basis) and {MAX_NODES} nodes, got {quadrature}",
                    largest + 2
                ),
            ));
        }
        let online_nodes = self.online_nodes.unwrap_or(off + on + 8);
        if online_nodes < largest + 1 || online_nodes > MAX_NODES {
            p.push((
                "online_nodes",
                format!(
                    "needs between {} and {MAX_NODES} nodes, got {online_nodes}",
                    largest + 1
                ),
            ));
        }
        // The off-line matrices: nodes × off-line functions, twice.
        let columns = off.pow(n as u32) + on.pow(n as u32);
        let bytes = quadrature.pow(n as u32) * columns * 8;
        if bytes > 256 << 20 {
            p.push((
                "quadrature",
                format!(
                    "the off-line matrices would take {} MiB (cap 256 MiB); use fewer nodes or basis functions",
                    bytes >> 20
                ),
            ));
        }
        p
    }

    /// The sizes for an n-dimensional model on `bounds`.
    pub fn layout(&self, n: usize, bounds: &[(f64, f64)]) -> Layout {
        let (off, on) = self.counts(n);
        Layout {
            offline: vec![off; n],
            online: vec![on; n],
            quadrature: self.quadrature.unwrap_or(2 * off.max(on) + 24),
            online_nodes: self.online_nodes.unwrap_or(off + on + 8),
            centre: bounds.iter().map(|b| 0.5 * (b.0 + b.1)).collect(),
            half_width: bounds.iter().map(|b| 0.5 * (b.1 - b.0)).collect(),
        }
    }
}

/// `out = A0 · X · A1ᵀ` for X of shape `rows × cols` stored column-major (first dimension
/// fastest), A0 `s0 × rows`, A1 `s1 × cols`; `t` is scratch of `s0 · cols`. For a 1-D model
/// (A1 the 1 × 1 identity) it is the one product `A0 · x`.
fn tensor_product(a0: &DMatrix<f64>, a1: &DMatrix<f64>, x: &[f64], t: &mut [f64], out: &mut [f64]) {
    let (s0, rows) = a0.shape();
    let (s1, cols) = a1.shape();
    if (s1, cols) == (1, 1) && a1[(0, 0)] == 1.0 {
        return linalg::combine_columns(&mut out[..s0], a0.as_slice(), &x[..rows]);
    }
    for (tj, xj) in t.chunks_exact_mut(s0).zip(x.chunks_exact(rows)) {
        linalg::combine_columns(tj, a0.as_slice(), xj);
    }
    for i in 0..s1 {
        let oi = &mut out[i * s0..(i + 1) * s0];
        oi.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..cols {
            let w = a1[(i, j)];
            for (ov, tv) in oi.iter_mut().zip(&t[j * s0..(j + 1) * s0]) {
                *ov += w * tv;
            }
        }
    }
}

/// Per-dimension matrices of the on-line step, and the 1 × 1 identity for the second
/// dimension of a 1-D model.
struct Axis {
    /// Off-line basis at the on-line nodes (nodes × N₁).
    evaluate: DMatrix<f64>,
    /// `B⁻¹ Φᵀ diag(w)`: nodal values to on-line coefficients (N₂ × nodes).
    project: DMatrix<f64>,
}

impl Axis {
    fn identity() -> Self {
        Axis {
            evaluate: DMatrix::identity(1, 1),
            project: DMatrix::identity(1, 1),
        }
    }

    fn new(offline: usize, online: usize, nodes: &[f64], weights: &[f64]) -> Self {
        let evaluate = DMatrix::from_fn(nodes.len(), offline, |q, l| {
            legendre::basis(nodes[q], offline)[0][l]
        });
        let phi = DMatrix::from_fn(online, nodes.len(), |k, q| {
            legendre::basis(nodes[q], online)[0][k] * weights[q]
        });
        // B is symmetric positive definite (a Gram matrix of independent functions).
        let b = legendre::mass_matrix(online);
        let project = b
            .cholesky()
            .map(|c| c.solve(&phi))
            .unwrap_or_else(|| DMatrix::zeros(online, nodes.len()));
        Axis { evaluate, project }
    }
}

/// W of Algorithm 1 as the on-line step applies it.
enum Propagation {
    /// 1-D: the evaluation at the on-line nodes times W (nodes × N₂), one product per step.
    Nodal(DMatrix<f64>),
    /// 2-D: W itself (off-line coefficients × on-line coefficients); the evaluation follows
    /// as a tensor product (W's rows are not a tensor product, so fusing would cost more).
    Coefficients(DMatrix<f64>),
}

/// The spectral Yau–Yau filter of 004.
pub struct SpectralFilter {
    name: String,
    layout: Layout,
    t0: f64,
    /// W of Algorithm 1, in 1-D already followed by the evaluation at the on-line nodes.
    propagation: Propagation,
    axes: [Axis; 2],
    /// Per on-line node (first dimension fastest): quadrature weight times the Jacobian,
    /// coordinates per dimension, and S⁻¹h per observation component.
    weight: Vec<f64>,
    coords: Vec<Vec<f64>>,
    s_inv_h: Vec<Vec<f64>>,
    /// `½hᵀS⁻¹h T₀` per node when the likelihood is applied in the update, else zero.
    potential: Vec<f64>,
    /// On-line coefficients c (N₂ per dimension, first dimension fastest).
    coeffs: Vec<f64>,
    offline: Vec<f64>,
    values: Vec<f64>,
    scratch: Vec<f64>,
    estimate: Estimate,
}

impl SpectralFilter {
    /// Runs the off-line part for `model` on `bounds` and projects the prior.
    pub fn new(
        name: String,
        model: &Model,
        prior: &Prior,
        params: &SpectralParams,
        bounds: &[(f64, f64)],
        dt_obs: f64,
    ) -> Result<Self, FilterError> {
        let n = model.n;
        if let Some((field, msg)) = params.problems(n).into_iter().next() {
            return Err(FilterError::Unsuitable(format!("{name} {field}: {msg}")));
        }
        let t0 = params.t0.unwrap_or(dt_obs);
        if (t0 - dt_obs).abs() > 1e-9 * dt_obs {
            return Err(FilterError::Unsuitable(format!(
                "{name}: T₀ = {t0} must equal the observation interval Δτ = {dt_obs} (004 propagates one interval per observation)"
            )));
        }
        let layout = params.layout(n, bounds);
        let in_operator = params.likelihood == Likelihood::InOperator;
        let propagation =
            offline::propagation_matrix(model, &layout, (t0, params.partitions), in_operator)?;
        let (xi, w) = legendre::gauss_legendre(layout.online_nodes);
        let axis = |d: usize| Axis::new(layout.offline[d], layout.online[d], &xi, &w);
        let (axes, propagation) = if n == 1 {
            let a0 = axis(0);
            let nodal = &a0.evaluate * &propagation;
            ([a0, Axis::identity()], Propagation::Nodal(nodal))
        } else {
            ([axis(0), axis(1)], Propagation::Coefficients(propagation))
        };
        let q = layout.online_nodes;
        let len = q.pow(n as u32);
        let index = |i: usize, d: usize| (i / q.pow(d as u32)) % q;
        let jacobian: f64 = layout.half_width.iter().product();
        let weight = (0..len)
            .map(|i| jacobian * (0..n).map(|d| w[index(i, d)]).product::<f64>())
            .collect();
        let coords: Vec<Vec<f64>> = (0..n)
            .map(|d| {
                (0..len)
                    .map(|i| layout.to_domain(d, xi[index(i, d)]))
                    .collect()
            })
            .collect();
        let c = DmzCoefficients::tabulate(model, "the spectral filters of 004", len, |i, x| {
            for (d, v) in x.iter_mut().enumerate() {
                *v = coords[d][i];
            }
        })?;
        let mut x = vec![0.0; n];
        let values: Vec<f64> = (0..len)
            .map(|i| {
                for (d, v) in x.iter_mut().enumerate() {
                    *v = coords[d][i];
                }
                prior.density(&x)
            })
            .collect();
        let offline_len: usize = layout.offline.iter().product();
        let online_len: usize = layout.online.iter().product();
        let mut filter = SpectralFilter {
            name,
            t0,
            propagation,
            weight,
            coords,
            s_inv_h: c.s_inv_h,
            potential: if in_operator {
                vec![0.0; len]
            } else {
                c.half_hsh.iter().map(|h| h * t0).collect()
            },
            coeffs: vec![0.0; online_len],
            offline: vec![0.0; offline_len],
            values,
            scratch: vec![0.0; q * q.max(layout.offline.iter().copied().max().unwrap_or(1))],
            estimate: Estimate {
                mean: DVector::zeros(n),
                covariance: None,
                map: None,
            },
            axes,
            layout,
        };
        filter.normalise_and_project()?;
        Ok(filter)
    }

    /// The resolved sizes.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Takes the estimate (41) from the nodal values, projects them onto the on-line basis
    /// (39) and normalises the coefficients (the mass, the moments and the largest node in one
    /// pass over the nodes; n ≤ 2).
    fn normalise_and_project(&mut self) -> Result<(), FilterError> {
        let n = self.layout.dims();
        let (mut mass, mut first, mut second) = (0.0, [0.0; 2], [0.0; 3]);
        let mut best = (f64::NEG_INFINITY, 0);
        let x0 = &self.coords[0];
        let x1 = self.coords.get(1).unwrap_or(x0);
        for (i, (&v, &w)) in self.values.iter().zip(&self.weight).enumerate() {
            if v > best.0 {
                best = (v, i);
            }
            let vw = v * w;
            let (a, b) = (x0[i], x1[i]);
            mass += vw;
            first[0] += vw * a;
            first[1] += vw * b;
            second[0] += vw * a * a;
            second[1] += vw * a * b;
            second[2] += vw * b * b;
        }
        if !mass.is_finite() {
            return Err(FilterError::NonFinite { what: "density" });
        }
        if mass <= 0.0 {
            return Err(FilterError::MassLost);
        }
        let inv = 1.0 / mass;
        let mean = DVector::from_fn(n, |a, _| first[a] * inv);
        // second[a + b] is E[x_a x_b] for a, b ∈ {0, 1}.
        let covariance = DMatrix::from_fn(n, n, |a, b| second[a + b] * inv - mean[a] * mean[b]);
        let map = DVector::from_iterator(n, (0..n).map(|d| self.coords[d][best.1]));
        self.estimate = Estimate {
            mean,
            covariance: Some(covariance),
            map: Some(map),
        };
        let [a0, a1] = &self.axes;
        tensor_product(
            &a0.project,
            &a1.project,
            &self.values,
            &mut self.scratch,
            &mut self.coeffs,
        );
        self.coeffs.iter_mut().for_each(|c| *c *= inv);
        Ok(())
    }

    /// Propagation (40) and the density at the on-line nodes.
    fn propagate(&mut self) {
        let w = match &self.propagation {
            Propagation::Nodal(e) => {
                return linalg::combine_columns(&mut self.values, e.as_slice(), &self.coeffs);
            }
            Propagation::Coefficients(w) => w,
        };
        linalg::combine_columns(&mut self.offline, w.as_slice(), &self.coeffs);
        let [a0, a1] = &self.axes;
        tensor_product(
            &a0.evaluate,
            &a1.evaluate,
            &self.offline,
            &mut self.scratch,
            &mut self.values,
        );
    }

    /// The robust-form factor `exp(hᵀS⁻¹Δy)` (42) — times `exp(−½hᵀS⁻¹h T₀)` when the
    /// likelihood is in the update — at the nodes, shifted by its largest exponent. Negative
    /// nodal values (the polynomial's ripples where the density is small) are set to zero
    /// first, so the factor cannot turn them into negative mass.
    fn update(&mut self, dy: &[f64]) {
        let a = &mut self.scratch[..self.values.len()];
        for (a, p) in a.iter_mut().zip(&self.potential) {
            *a = -p;
        }
        for (y, sh) in dy.iter().zip(&self.s_inv_h) {
            for (a, h) in a.iter_mut().zip(sh) {
                *a += y * h;
            }
        }
        let shift = a.iter().copied().fold(f64::NEG_INFINITY, linalg::larger);
        // Flushing products below 0 to 0 clips the negative values.
        linalg::scale_by_exp(&mut self.values, a, shift, 0.0);
    }
}

impl Filter for SpectralFilter {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        crate::filters::check_increment(&self.name, obs, self.s_inv_h.len())?;
        if obs.dt <= 0.0 {
            return Ok(());
        }
        if (obs.dt - self.t0).abs() > 1e-9 * self.t0 {
            return Err(FilterError::BadObservation(format!(
                "{} was built for intervals of T₀ = {}, got {}",
                self.name, self.t0, obs.dt
            )));
        }
        self.propagate();
        self.update(obs.value);
        self.normalise_and_project()
    }

    fn estimate(&self) -> Estimate {
        self.estimate.clone()
    }

    /// The marginal of the projected density (39) on the on-line basis, clipped at zero;
    /// zero outside the domain.
    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        let n = self.layout.dims();
        let on = &self.layout.online;
        let (c, r) = (self.layout.centre[dim], self.layout.half_width[dim]);
        // Integrating out the other dimension keeps only its φ_0 coefficient.
        let other = if n == 2 {
            let o = 1 - dim;
            self.layout.half_width[o] * legendre::basis_integral(0)
        } else {
            1.0
        };
        for (o, &x) in out.iter_mut().zip(grid) {
            let xi = (x - c) / r;
            if !(-1.0..=1.0).contains(&xi) {
                *o = 0.0;
                continue;
            }
            let phi = &legendre::basis(xi, on[dim])[0];
            let value: f64 = (0..on[dim])
                .map(|k| {
                    let coeff = if n == 2 && dim == 1 {
                        self.coeffs[on[0] * k]
                    } else {
                        self.coeffs[k]
                    };
                    coeff * phi[k]
                })
                .sum();
            *o = (value * other).max(0.0);
        }
    }
}
