//! The spectral Yau–Yau filter itself: the on-line step (004 Algorithm 2) on the off-line
//! operator (Algorithm 1).

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::filters::{Estimate, Filter, LengthCache, Observation, ObservationKind, Observed};
use crate::linalg;
use crate::model::dmz::{DmzCoefficients, LikelihoodPlacement, ObservedTerms, PartialIncrements};
use crate::model::Model;

use super::params::{SpectralBasis, SpectralParams};
use super::total_degree::{self, Table, TotalDegree};
use super::{legendre, offline, tensor};

/// The resolved sizes for an n-dimensional model.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Layout {
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
    /// Which products of the one-dimensional functions span the basis (resolved: never
    /// `Auto`).
    pub basis: SpectralBasis,
}

impl Layout {
    /// Dimension n.
    pub(crate) fn dims(&self) -> usize {
        self.offline.len()
    }
    /// `x = centre + half_width · ξ`.
    pub(crate) fn to_domain(&self, d: usize, xi: f64) -> f64 {
        self.centre[d] + self.half_width[d] * xi
    }
}

impl SpectralParams {
    /// The sizes for an n-dimensional model on `bounds`.
    pub(crate) fn layout(&self, n: usize, bounds: &[(f64, f64)]) -> Layout {
        let (off, on) = self.counts(n);
        Layout {
            offline: vec![off; n],
            online: vec![on; n],
            quadrature: self.quadrature(n),
            online_nodes: self.online_nodes(n),
            centre: bounds.iter().map(|b| 0.5 * (b.0 + b.1)).collect(),
            half_width: bounds.iter().map(|b| 0.5 * (b.1 - b.0)).collect(),
            basis: self.basis_for(n),
        }
    }
}

impl Layout {
    /// The off-line and on-line sets of the total-degree basis (degree = count − 1).
    pub(crate) fn total_degree(&self) -> (TotalDegree, TotalDegree) {
        let dims = self.dims();
        (
            TotalDegree {
                dims,
                degree: self.offline[0] - 1,
            },
            TotalDegree {
                dims,
                degree: self.online[0] - 1,
            },
        )
    }

    /// Off-line and on-line coefficients.
    fn lengths(&self) -> (usize, usize) {
        match self.basis {
            SpectralBasis::Auto | SpectralBasis::Tensor => {
                (self.offline.iter().product(), self.online.iter().product())
            }
            SpectralBasis::TotalDegree => {
                let (off, on) = self.total_degree();
                (off.len(), on.len())
            }
        }
    }
}

/// Algorithm 1 for the layout's basis: over `t0` in `partitions` implicit Euler steps (the
/// tensor basis), or in one (the total-degree basis takes N′ = 1, which its parameters check,
/// and a shorter remainder or gap gets one as well).
fn propagation_matrix(
    model: &Model,
    layout: &Layout,
    (t0, partitions): (f64, usize),
    potential_in_operator: bool,
) -> Result<DMatrix<f64>, FilterError> {
    match layout.basis {
        SpectralBasis::TotalDegree => {
            total_degree::propagation_matrix(model, layout, t0, potential_in_operator)
        }
        SpectralBasis::Auto | SpectralBasis::Tensor => {
            offline::propagation_matrix(model, layout, (t0, partitions), potential_in_operator)
        }
    }
}

/// The per-dimension matrices of the on-line step: the off-line basis at the on-line nodes
/// (nodes × N₁) and the projection `B⁻¹ Φᵀ diag(w)` (39) from nodal values to on-line
/// coefficients (N₂ × nodes).
fn axis_matrices(
    offline: usize,
    online: usize,
    nodes: &[f64],
    weights: &[f64],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let evaluate = basis_at(nodes, offline);
    let phi = DMatrix::from_fn(online, nodes.len(), |k, q| {
        legendre::basis(nodes[q], online)[0][k] * weights[q]
    });
    // B is symmetric positive definite (a Gram matrix of independent functions).
    let b = legendre::mass_matrix(online);
    let project = b
        .cholesky()
        .map(|c| c.solve(&phi))
        .unwrap_or_else(|| DMatrix::zeros(online, nodes.len()));
    (evaluate, project)
}

/// The first `count` basis functions at the points ξ ∈ [−1, 1] (points × count); rows of
/// points outside [−1, 1] are zero (the density is zero outside the domain).
fn basis_at(points: &[f64], count: usize) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(points.len(), count);
    for (q, &xi) in points.iter().enumerate() {
        if (-1.0..=1.0).contains(&xi) {
            for (k, v) in legendre::basis(xi, count)[0].iter().enumerate() {
                m[(q, k)] = *v;
            }
        }
    }
    m
}

impl Propagation {
    /// W as the on-line step applies it: for the tensor basis in 1-D already followed by the
    /// evaluation at the on-line nodes.
    fn new(w: DMatrix<f64>, online: &Online) -> Self {
        match online {
            Online::Tensor { evaluate, .. } if evaluate.len() == 1 => {
                Propagation::Nodal(&evaluate[0] * &w)
            }
            _ => Propagation::Coefficients(w),
        }
    }
}

/// How the on-line step goes between coefficients and the on-line nodes.
#[derive(Clone, Debug)]
enum Online {
    /// The tensor basis: per dimension, the off-line basis at the on-line nodes (nodes × N₁)
    /// and `B⁻¹ Φᵀ diag(w)` (39), nodal values to on-line coefficients (N₂ × nodes).
    Tensor {
        evaluate: Vec<DMatrix<f64>>,
        project: Vec<DMatrix<f64>>,
    },
    /// The total-degree basis, by sum factorisation (`total_degree`).
    TotalDegree(TotalDegreeOnline),
}

/// The total-degree basis' on-line part.
#[derive(Clone, Debug)]
struct TotalDegreeOnline {
    offline: TotalDegree,
    online: TotalDegree,
    /// The off-line and on-line one-dimensional functions at the on-line nodes (nodes ×
    /// count, column-major).
    offline_table: DMatrix<f64>,
    online_table: DMatrix<f64>,
    /// The mass matrix of the on-line set, factored: the projection (39) solves with it.
    mass: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    /// The on-line set's multi-indices (the self-check's degrees).
    indices: Vec<Vec<usize>>,
    /// `1/Π r_d`: the projection integrates on U = [−1, 1]ⁿ, as the tensor basis' does.
    inverse_jacobian: f64,
    /// The nodal values times the weights, and the sum factorisation's intermediates.
    weighted: Vec<f64>,
    scratch: Vec<Vec<f64>>,
}

impl TotalDegreeOnline {
    fn new(layout: &Layout, nodes: &[f64]) -> Result<Self, FilterError> {
        let (offline, online) = layout.total_degree();
        let mass = total_degree::mass_matrix(online)
            .cholesky()
            .ok_or_else(|| {
                FilterError::Unsuitable("the on-line mass matrix is not positive definite".into())
            })?;
        Ok(TotalDegreeOnline {
            offline,
            online,
            offline_table: basis_at(nodes, offline.degree + 1),
            online_table: basis_at(nodes, online.degree + 1),
            mass,
            indices: online.indices(),
            inverse_jacobian: 1.0 / layout.half_width.iter().product::<f64>(),
            weighted: Vec::new(),
            scratch: total_degree::scratch(layout.dims()),
        })
    }

    /// Off-line coefficients to values at the on-line nodes.
    fn evaluate(&mut self, offline: &[f64], values: &mut [f64]) {
        // The same table in every dimension.
        let tables = [Table::of(&self.offline_table); total_degree::MAX_DIMS];
        let dims = self.offline.dims;
        total_degree::evaluate(
            self.offline,
            offline,
            &tables[..dims],
            values,
            &mut self.scratch,
        );
    }

    /// The projection (39): `c = B⁻¹ ⟨ρ, φ_k⟩` on U, the inner products by the nodes' weights.
    fn project(&mut self, values: &[f64], weight: &[f64], coeffs: &mut [f64]) {
        self.weighted.clear();
        let s = self.inverse_jacobian;
        self.weighted
            .extend(values.iter().zip(weight).map(|(v, w)| v * w * s));
        let tables = [Table::of(&self.online_table); total_degree::MAX_DIMS];
        let tables = &tables[..self.online.dims];
        total_degree::project(
            self.online,
            &self.weighted,
            tables,
            coeffs,
            &mut self.scratch,
        );
        let len = coeffs.len();
        let mut c = nalgebra::DVectorViewMut::from_slice(coeffs, len);
        self.mass.solve_mut(&mut c);
    }
}

/// W of Algorithm 1 as the on-line step applies it.
#[derive(Clone, Debug)]
enum Propagation {
    /// The tensor basis in 1-D: the evaluation at the on-line nodes times W (nodes × N₂), one
    /// product per step.
    Nodal(DMatrix<f64>),
    /// Otherwise W itself (off-line coefficients × on-line coefficients); the evaluation
    /// follows as a tensor product or, for the total-degree basis, by sum factorisation (W's
    /// rows are not a tensor product, so fusing would cost more).
    Coefficients(DMatrix<f64>),
}

/// The spectral Yau–Yau filter of 004.
///
/// The off-line/on-line spectral Yau–Yau filter of 004 ("DMZ method"), on the generalized
/// Legendre basis of its appendix: the tensor basis (appendix (48)) for n = 1, 2 and 3, the
/// complete basis of total degree ≤ N ([`crate::SpectralBasis::TotalDegree`]) for n = 1 to 6.
///
/// The domain box is mapped affinely onto U = [−1, 1]ⁿ. Off-line (`offline`, Algorithm 1):
/// the Kolmogorov equation (17) over one observation interval T₀ becomes a matrix W from the
/// coefficients of the density on the on-line basis (N₂ functions per dimension, or those of
/// total degree below N₂) to those of the propagated density on the off-line basis (N₁). On-line (Algorithm 2),
/// per observation interval and without keeping any past observation:
///
/// 1. propagation (40): `g = W c`;
/// 2. the density at the on-line Gauss–Legendre nodes, the robust-form factor
///    `exp(hᵀS⁻¹Δy)` of (42) there (shifted by its largest exponent, so it cannot overflow;
///    the constant cancels in the normalisation);
/// 3. estimate (41): mean, covariance and the largest node from the nodal values;
/// 4. projection (39) of the updated density onto the on-line basis: `c = B⁻¹⟨ρ, φ_k⟩`, the
///    mass matrix B of (49) being the tensor product of the closed form (restricted to the
///    total-degree set, factored once, for that basis).
///
/// Steps 2 and 4 use the tensor structure: one matrix product per dimension (`tensor`), or
/// sum factorisation over the last dimension for the total-degree basis (`total_degree`); for
/// the tensor basis in 1-D the evaluation of step 2 is folded into W off-line, so steps 1–2
/// are one product, and the whole step is about a thousand multiply–adds and 35 exponentials. The density is a
/// polynomial and can dip below zero where it is small; the factor (42) sets those nodal
/// values to zero before the update, and the plotted marginals are clipped at zero.
///
/// # When it fails
///
/// The Legendre basis must hold the posterior on its box: when the energy in the highest degrees
/// passes its threshold the self-check says the basis is too small for the posterior (raise the
/// on-line or off-line basis, or narrow the box; the playground's lesson 7 shows it) —
/// [`crate::Filter::self_check`]. Its off-line operator is made once, so a driven model is
/// refused.
#[derive(Clone, Debug)]
pub struct Spectral {
    name: String,
    layout: Layout,
    t0: f64,
    /// W of Algorithm 1, in 1-D already followed by the evaluation at the on-line nodes.
    propagation: Propagation,
    /// Between coefficients and the on-line nodes.
    online: Online,
    /// Per on-line node (first dimension fastest): quadrature weight times the Jacobian,
    /// coordinates per dimension, and S⁻¹h per observation component.
    weight: Vec<f64>,
    coords: Vec<Vec<f64>>,
    s_inv_h: Vec<Vec<f64>>,
    /// `½hᵀS⁻¹h T₀` per node when the likelihood is applied in the update, else zero.
    potential: Vec<f64>,
    /// The factor's terms for increments with some components missing.
    partial: PartialIncrements,
    /// On-line coefficients c (N₂ per dimension, first dimension fastest; for the
    /// total-degree basis in its set's order).
    coeffs: Vec<f64>,
    offline: Vec<f64>,
    values: Vec<f64>,
    /// The factor's exponents per node.
    exponents: Vec<f64>,
    /// Intermediates of the tensor products.
    scratch: [Vec<f64>; 2],
    estimate: Estimate,
    /// Σc² and its top-degree part, measured as the coefficients are normalised (the
    /// self-check's numbers).
    energy: Energy,
    /// The coefficients, estimate and energy a step started from.
    saved: (crate::filters::SavedDensity, Energy),
    /// The last step's log-likelihood ([`Filter::log_likelihood`]).
    log_likelihood: f64,
    /// Whether `−½hᵀS⁻¹h` is in the off-line operator (then an interval without its
    /// increment has an operator of its own, without that term: `gaps`).
    likelihood_in_operator: bool,
    /// What the off-line part needs to make the operator of another interval length: the
    /// model and N′ partitions of T₀.
    model: Model,
    partitions: usize,
    /// Operators for interval lengths other than T₀ (the remainders of irregular intervals
    /// after whole T₀), at most [`crate::filters::REMAINDER_PLANS`]: each is one off-line
    /// computation of Algorithm 1 and one matrix of W's size.
    remainders: LengthCache<Propagation>,
    /// With the likelihood in the operator, the operators of intervals without a (whole)
    /// increment — the Fokker–Planck part alone, one off-line computation per length: T₀'s
    /// (made on the first such interval) and the remainders' (at most
    /// [`crate::filters::REMAINDER_PLANS`]).
    whole_gap: Option<Propagation>,
    gaps: LengthCache<Propagation>,
}

/// Which off-line operator a propagation uses.
#[derive(Clone, Copy, Debug)]
enum Leg {
    /// The operator of T₀.
    Whole,
    /// The remainder operator at the front of its cache.
    Remainder,
    /// T₀'s operator without the observation term (likelihood in the operator, no whole
    /// increment).
    WholeGap,
    /// The remainder's operator without the observation term, at the front of its cache.
    RemainderGap,
}

impl Spectral {
    /// Runs the off-line part for `model` on `bounds` and projects the prior.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &SpectralParams,
    ) -> Result<Self, crate::error::ZakaiError> {
        let dt_obs = ctx.interval(&name)?;
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        let n = model.n;
        if let Some((field, msg)) = params.problems(n).into_iter().next() {
            return Err(FilterError::Unsuitable(format!("{name} {field}: {msg}")).into());
        }
        let t0 = params.t0.unwrap_or(dt_obs);
        if (t0 - dt_obs).abs() > 1e-9 * dt_obs {
            return Err(FilterError::Unsuitable(format!(
                "{name}: T₀ = {t0} must equal the observation interval Δτ = {dt_obs} (004 propagates one interval per observation)"
            )).into());
        }
        let layout = params.layout(n, bounds);
        let in_operator = params.likelihood == LikelihoodPlacement::InOperator;
        let propagation = propagation_matrix(model, &layout, (t0, params.partitions), in_operator)?;
        let (xi, w) = legendre::gauss_legendre(layout.online_nodes);
        let online = match layout.basis {
            SpectralBasis::Auto | SpectralBasis::Tensor => {
                let (evaluate, project) = (0..n)
                    .map(|d| axis_matrices(layout.offline[d], layout.online[d], &xi, &w))
                    .unzip();
                Online::Tensor { evaluate, project }
            }
            SpectralBasis::TotalDegree => {
                Online::TotalDegree(TotalDegreeOnline::new(&layout, &xi)?)
            }
        };
        let propagation = Propagation::new(propagation, &online);
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
        let (offline_len, online_len) = layout.lengths();
        let mut filter = Spectral {
            name,
            t0,
            propagation,
            weight,
            coords,
            s_inv_h: c.s_inv_h,
            partial: PartialIncrements::of(model, "the spectral filters of 004")?,
            potential: if in_operator {
                vec![0.0; len]
            } else {
                c.half_hsh.iter().map(|h| h * t0).collect()
            },
            coeffs: vec![0.0; online_len],
            offline: vec![0.0; offline_len],
            exponents: vec![0.0; values.len()],
            values,
            scratch: [Vec::new(), Vec::new()],
            energy: Energy::default(),
            estimate: Estimate {
                mean: DVector::zeros(n),
                covariance: None,
                map: None,
            },
            saved: (
                crate::filters::SavedDensity::new(online_len, &Estimate::zeros(n)),
                Energy::default(),
            ),
            log_likelihood: 0.0,
            likelihood_in_operator: in_operator,
            model: model.clone(),
            partitions: params.partitions,
            remainders: LengthCache::new(crate::filters::REMAINDER_PLANS),
            whole_gap: None,
            gaps: LengthCache::new(crate::filters::REMAINDER_PLANS),
            online,
            layout,
        };
        filter.normalise_and_project()?;
        Ok(filter)
    }

    /// Takes the estimate (41) from the nodal values, projects them onto the on-line basis
    /// (39) and normalises the coefficients; returns the mass they had.
    fn normalise_and_project(&mut self) -> Result<f64, FilterError> {
        let (values, weight, coords) = (&self.values, &self.weight, &self.coords);
        let out = &mut self.estimate;
        let mass = match self.layout.dims() {
            1 => estimate_at_nodes::<1>(values, weight, coords, out),
            2 => estimate_at_nodes::<2>(values, weight, coords, out),
            3 => estimate_at_nodes::<3>(values, weight, coords, out),
            4 => estimate_at_nodes::<4>(values, weight, coords, out),
            5 => estimate_at_nodes::<5>(values, weight, coords, out),
            _ => estimate_at_nodes::<6>(values, weight, coords, out),
        }?;
        match &mut self.online {
            Online::Tensor { project, .. } => {
                let shape = [self.layout.online_nodes; tensor::MAX_DIMS];
                tensor::multilinear(
                    project,
                    &self.values,
                    &shape[..project.len()],
                    &mut self.scratch,
                    &mut self.coeffs,
                );
                self.energy = scale_and_measure(&mut self.coeffs, 1.0 / mass, &self.layout.online);
            }
            Online::TotalDegree(o) => {
                o.project(&self.values, &self.weight, &mut self.coeffs);
                let (total, worst_tail) = total_degree::scale_and_measure(
                    &mut self.coeffs,
                    1.0 / mass,
                    &o.indices,
                    o.online.degree,
                );
                self.energy = Energy { total, worst_tail };
            }
        }
        Ok(mass)
    }

    /// The remainder operator for intervals of length `rest` (< T₀): made off-line the first
    /// time that length occurs (N′ partitions scaled down with it), kept among the last
    /// [`crate::filters::REMAINDER_PLANS`]; moved to the front of the list.
    fn remainder(&mut self, rest: f64) -> Result<(), FilterError> {
        let with_likelihood = self.likelihood_in_operator;
        self.recent_first(|f| &mut f.remainders, rest, with_likelihood)
    }

    /// The operators of an interval without a whole increment when the likelihood is in the
    /// operator: Algorithm 1 for the Fokker–Planck part alone (N′ partitions scaled with the
    /// length), T₀'s when `whole` (made once) and the remainder's `rest` when positive (made the
    /// first time that length occurs, kept among the last [`crate::filters::REMAINDER_PLANS`]).
    /// A gap is whole T₀ legs and a remainder, as an interval with an increment is: the
    /// off-line method is made for short intervals, and one operator over a long gap is not
    /// accurate.
    fn gap(&mut self, whole: bool, rest: f64) -> Result<(), FilterError> {
        if whole && self.whole_gap.is_none() {
            let w =
                propagation_matrix(&self.model, &self.layout, (self.t0, self.partitions), false)?;
            self.whole_gap = Some(Propagation::new(w, &self.online));
        }
        if rest > 0.0 {
            self.recent_first(|f| &mut f.gaps, rest, false)?;
        }
        Ok(())
    }

    /// Moves the off-line operator over `length` to the front of the cache `pick` selects,
    /// making it the first time that length occurs — Algorithm 1 with N′ partitions scaled
    /// with the length, −½hᵀS⁻¹h in it when `with_likelihood`.
    fn recent_first(
        &mut self,
        pick: fn(&mut Self) -> &mut LengthCache<Propagation>,
        length: f64,
        with_likelihood: bool,
    ) -> Result<(), FilterError> {
        if pick(self).bring_to_front(length) {
            return Ok(());
        }
        let partitions = libm::ceil(self.partitions as f64 * length / self.t0).max(1.0) as usize;
        let w = propagation_matrix(
            &self.model,
            &self.layout,
            (length, partitions),
            with_likelihood,
        )?;
        let made = Propagation::new(w, &self.online);
        pick(self).insert(length, made);
        Ok(())
    }

    /// Propagation (40) over T₀ (`Leg::Whole`), with the remainder operator at the front or
    /// the gap operator of a length, and the density at the on-line nodes.
    fn propagate(&mut self, leg: Leg) {
        let propagation = match leg {
            Leg::Remainder => self.remainders.front(),
            Leg::WholeGap => self.whole_gap.as_ref().expect("made before the step"),
            Leg::RemainderGap => self.gaps.front(),
            Leg::Whole => &self.propagation,
        };
        let w = match propagation {
            Propagation::Nodal(e) => {
                return linalg::combine_columns(&mut self.values, e.as_slice(), &self.coeffs);
            }
            Propagation::Coefficients(w) => w,
        };
        linalg::combine_columns(&mut self.offline, w.as_slice(), &self.coeffs);
        match &mut self.online {
            Online::Tensor { evaluate, .. } => tensor::multilinear(
                evaluate,
                &self.offline,
                &self.layout.offline,
                &mut self.scratch,
                &mut self.values,
            ),
            Online::TotalDegree(o) => o.evaluate(&self.offline, &mut self.values),
        }
    }

    /// The marginal of the expansion on the on-line basis over the components `kept` (each
    /// with its points, the first fastest in `out`), clipped at zero: one tensor product with
    /// the basis at the points for a kept component and the basis' integrals (only φ_0's is
    /// not zero) for every other one.
    fn marginal(&self, kept: &[(usize, &[f64])], out: &mut [f64]) {
        let values = self.projected(kept);
        // `values` runs over the kept components in increasing order; `out` in `kept`'s order.
        let swapped = kept.len() == 2 && kept[0].0 > kept[1].0;
        let (first, second) = (kept[0].1.len(), kept.get(1).map_or(1, |k| k.1.len()));
        for j in 0..second {
            for i in 0..first {
                let v = if swapped {
                    values[j + second * i]
                } else {
                    values[i + first * j]
                };
                out[i + first * j] = v.max(0.0);
            }
        }
    }

    /// The projected density's marginal over the components `kept` at their points, the
    /// kept components in increasing order with the first fastest (not clipped).
    fn projected(&self, kept: &[(usize, &[f64])]) -> Vec<f64> {
        let n = self.layout.dims();
        let on = &self.layout.online;
        // Per dimension: the functions at the kept points, or their integrals (one "point")
        // for a dimension integrated out.
        let factors: Vec<DMatrix<f64>> = (0..n)
            .map(|d| match kept.iter().find(|(k, _)| *k == d) {
                Some((_, points)) => {
                    let (c, r) = (self.layout.centre[d], self.layout.half_width[d]);
                    let xi: Vec<f64> = points.iter().map(|x| (x - c) / r).collect();
                    basis_at(&xi, on[d])
                }
                None => DMatrix::from_fn(1, on[d], |_, k| {
                    self.layout.half_width[d] * legendre::basis_integral(k)
                }),
            })
            .collect();
        if let Online::TotalDegree(o) = &self.online {
            let view: Vec<Table> = factors.iter().map(Table::of).collect();
            let len: usize = view.iter().map(|t| t.points).product();
            let mut values = vec![0.0; len];
            let mut scratch = total_degree::scratch(n);
            total_degree::evaluate(o.online, &self.coeffs, &view, &mut values, &mut scratch);
            return values;
        }
        let len: usize = kept.iter().map(|(_, p)| p.len()).product();
        let mut values = vec![0.0; len];
        let mut scratch = [Vec::new(), Vec::new()];
        tensor::multilinear(&factors, &self.coeffs, on, &mut scratch, &mut values);
        values
    }

    /// The robust-form factor `exp(hᵀS⁻¹Δy)` (42) — times `exp(−½hᵀS⁻¹h T₀)` per interval T₀
    /// when the likelihood is in the update — at the nodes, shifted by its largest exponent;
    /// an increment with some components missing gets the factor of the observed ones,
    /// `exp(Δy_Oᵀ S_OO⁻¹ h_O − ½ h_Oᵀ S_OO⁻¹ h_O Δτ)` ([`PartialIncrements`]). Products below
    /// zero (from negative nodal values, the polynomial's ripples where the density is small)
    /// are flushed to zero, so the factor cannot turn them into negative mass.
    /// Returns the logarithm the factor was divided by.
    fn update(&mut self, dy: &[f64], dt: f64) -> Result<f64, FilterError> {
        let (values, a) = (&mut self.values, &mut self.exponents);
        Ok(if dy.iter().any(|v| v.is_nan()) {
            let t = self.partial.terms(&self.s_inv_h, dy)?;
            observation_factor(values, a, &t, dt)
        } else {
            let (gain, half) = (&self.s_inv_h, &self.potential);
            observation_factor(values, a, &ObservedTerms { dy, gain, half }, dt / self.t0)
        })
    }
}

/// `values ← values · exp(Δyᵀg − scale · half − shift)` at the nodes ([`ObservedTerms`]), with
/// `shift` the largest exponent (see [`Spectral::update`]), returned; `a` is scratch.
fn observation_factor(values: &mut [f64], a: &mut [f64], terms: &ObservedTerms, scale: f64) -> f64 {
    terms.exponents(scale, a);
    let shift = a.iter().copied().fold(f64::NEG_INFINITY, linalg::larger);
    // Flushing products below 0 to 0 clips the negative values.
    linalg::scale_by_exp(values, a, shift, 0.0);
    shift
}

/// The quadrature mass of the nodal values' positive part (what the factor (42) multiplies:
/// it flushes negative products to zero).
fn positive_mass(values: &[f64], weight: &[f64]) -> f64 {
    values.iter().zip(weight).map(|(v, w)| v.max(0.0) * w).sum()
}

/// The estimate (41) from nodal values on the on-line grid of an N-dimensional model: mean
/// and covariance by the quadrature, the MAP as the largest node, all in one pass; also the
/// mass. Writes into `out` (allocating only a covariance or MAP it does not have yet); fails
/// when the mass is not finite or not positive, leaving `out` as it was.
fn estimate_at_nodes<const N: usize>(
    values: &[f64],
    weight: &[f64],
    coords: &[Vec<f64>],
    out: &mut Estimate,
) -> Result<f64, FilterError> {
    let x: [&[f64]; N] = core::array::from_fn(|d| coords[d].as_slice());
    let (mut mass, mut first, mut second) = (0.0, [0.0; N], [[0.0; N]; N]);
    let mut best = (f64::NEG_INFINITY, 0);
    for (i, (&v, &w)) in values.iter().zip(weight).enumerate() {
        if v > best.0 {
            best = (v, i);
        }
        let vw = v * w;
        mass += vw;
        let xi: [f64; N] = core::array::from_fn(|d| x[d][i]);
        for ((f, s), &xa) in first.iter_mut().zip(second.iter_mut()).zip(&xi) {
            *f += vw * xa;
            for (s, &xb) in s.iter_mut().zip(&xi) {
                *s += vw * xa * xb;
            }
        }
    }
    if !mass.is_finite() {
        return Err(FilterError::NonFinite { what: "density" });
    }
    if mass <= 0.0 {
        return Err(FilterError::MassLost);
    }
    let inv = 1.0 / mass;
    let mean = &mut out.mean;
    mean.iter_mut().zip(&first).for_each(|(m, f)| *m = f * inv);
    // From one triangle, so that the covariance is exactly symmetric.
    let covariance = out.covariance.get_or_insert_with(|| DMatrix::zeros(N, N));
    for a in 0..N {
        for b in 0..N {
            let (hi, lo) = (a.max(b), a.min(b));
            covariance[(a, b)] = second[hi][lo] * inv - mean[hi] * mean[lo];
        }
    }
    let map = out.map.get_or_insert_with(|| DVector::zeros(N));
    map.iter_mut()
        .enumerate()
        .for_each(|(d, m)| *m = x[d][best.1]);
    Ok(mass)
}

/// The spectral self-check's threshold: the share of the on-line coefficients' energy (Σc²)
/// in the top quarter of the degrees of any dimension. A resolved density's coefficients decay
/// fast and leave little there. Measured on dx = −x dt + dv, dy = x dt + dw (400 intervals of
/// 0.01, prior N(0, 0.5)) against the Kalman–Bucy mean, largest tail share over the run →
/// largest |Δ mean|: on [−4, 4] with 16 on-line functions (the 1-D default) 2.1e-3 → 0.52,
/// with 20 5.9e-3 → 1.3e-2, with 24 5.9e-4 → 8.3e-4, with 30 1.6e-5 → 7.3e-4; on [−6, 6] with
/// 16 3.1e-2 → 2.4, with 40 1.0e-4 → 6.5e-4. A box too small for the state's path is a
/// different failure this check does not see (on [−2, 2]: 1.7e-7, yet 0.048 off).
pub(crate) const TAIL_ENERGY_THRESHOLD: f64 = 1e-3;

impl Spectral {
    /// The largest share, over the dimensions, of Σc² in the top quarter of the degrees.
    pub fn tail_energy(&self) -> f64 {
        self.energy.share()
    }
}

/// Of a tensor basis' coefficients: Σc² over all of them and, the largest over the
/// dimensions, Σc² over those whose degree in that dimension is in its top quarter.
#[derive(Clone, Copy, Debug, Default)]
struct Energy {
    total: f64,
    worst_tail: f64,
}

impl Energy {
    /// The tail's share of the total (0 when the total is not positive).
    fn share(self) -> f64 {
        if self.total > 0.0 {
            self.worst_tail / self.total
        } else {
            0.0
        }
    }

    /// Whether the share is above `threshold`, without dividing.
    fn share_above(self, threshold: f64) -> bool {
        self.total > 0.0 && self.worst_tail > threshold * self.total
    }
}

/// `c ← c·scale` for the coefficients of a tensor basis with `counts` functions per dimension
/// (first dimension fastest), and their [`Energy`]. The total is summed in the scaling pass
/// itself, in four interleaved partial sums (one chain of additions would wait on each one's
/// latency); the self-check reads it after every step, and 004's 1-D step is itself short.
fn scale_and_measure(coeffs: &mut [f64], scale: f64, counts: &[usize]) -> Energy {
    let mut lanes = [0.0; 4];
    let mut chunks = coeffs.chunks_exact_mut(4);
    for chunk in &mut chunks {
        for (l, c) in lanes.iter_mut().zip(chunk) {
            *c *= scale;
            *l += *c * *c;
        }
    }
    for (l, c) in lanes.iter_mut().zip(chunks.into_remainder()) {
        *c *= scale;
        *l += *c * *c;
    }
    let mut worst_tail: f64 = 0.0;
    let mut stride = 1;
    for &count in counts {
        // Dimension d's degree is (i / stride) % count: in each block of stride · count
        // coefficients, degrees from `from` on are the block's end, from `from · stride`.
        let (block, from) = (stride * count, (count - count.div_ceil(4)) * stride);
        let mut tail = 0.0;
        let mut start = 0;
        while start + block <= coeffs.len() {
            tail += coeffs[start + from..start + block]
                .iter()
                .map(|c| c * c)
                .sum::<f64>();
            start += block;
        }
        worst_tail = worst_tail.max(tail);
        stride = block;
    }
    Energy {
        total: (lanes[0] + lanes[2]) + (lanes[1] + lanes[3]),
        worst_tail,
    }
}

impl Filter for Spectral {
    crate::filters::kept_estimate_accessors!();

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        self.remainders.check(out);
        self.gaps.check(out);
        if self.energy.share_above(TAIL_ENERGY_THRESHOLD) {
            out.push(crate::filters::Concern::above(
                "energy in the highest Legendre degrees",
                self.energy.share(),
                TAIL_ENERGY_THRESHOLD,
                "the basis is too small for the posterior on this box: raise online_basis/offline_basis or narrow the domain",
            ));
        }
    }

    /// An interval of length `k T₀ + r` (0 ≤ r < T₀) is k propagations with the off-line
    /// operator and one with the remainder's (made the first time its length occurs), the
    /// increment's factor after the last with `½hᵀS⁻¹h (k T₀ + r)`.
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, ObservationKind::Increment, self.s_inv_h.len())?;
        if obs.dt <= 0.0 {
            self.log_likelihood = 0.0;
            return Ok(());
        }
        let (whole, rest) = crate::filters::whole_intervals(obs.dt, self.t0);
        // Off-line, before anything moves (it fails only on a degenerate basis). A gap with
        // the likelihood in the operator has operators of its own; an increment with some
        // components missing is the same prediction, then the observed components' factor.
        let gap = observed != Observed::All && self.likelihood_in_operator;
        if gap {
            self.gap(whole > 0, rest)?;
        } else if rest > 0.0 {
            self.remainder(rest)?;
        }
        self.saved.0.save(&self.coeffs, &self.estimate);
        self.saved.1 = self.energy;
        let legs = whole + usize::from(rest > 0.0);
        // Whether the operators carry the increment's −½hᵀS⁻¹h (likelihood in the operator,
        // 004 (17)): then every leg's loss of mass is the likelihood's, counted from the unit
        // mass the interval starts with; otherwise the factor's normaliser counts against
        // the predicted density's mass.
        let carried = self.likelihood_in_operator && observed == Observed::All;
        let mut log_likelihood = 0.0;
        let mut stepped = Ok(());
        for leg in 1..=legs {
            self.propagate(match (gap, leg > whole) {
                (false, false) => Leg::Whole,
                (false, true) => Leg::Remainder,
                (true, false) => Leg::WholeGap,
                (true, true) => Leg::RemainderGap,
            });
            let mut factor = None;
            if leg == legs && observed != Observed::Nothing {
                let before = if carried {
                    1.0
                } else {
                    positive_mass(&self.values, &self.weight)
                };
                match self.update(obs.value, obs.dt) {
                    Ok(shift) => factor = Some((shift, before)),
                    Err(e) => {
                        stepped = Err(e);
                        break;
                    }
                }
            }
            match self.normalise_and_project() {
                Ok(mass) => {
                    if let Some((shift, before)) = factor {
                        log_likelihood += libm::log(mass) + shift - libm::log(before);
                    } else if carried {
                        log_likelihood += libm::log(mass);
                    }
                }
                Err(e) => {
                    stepped = Err(e);
                    break;
                }
            }
        }
        match stepped {
            Ok(()) => self.log_likelihood = log_likelihood,
            Err(_) => {
                self.saved.0.restore(&mut self.coeffs, &mut self.estimate);
                self.energy = self.saved.1;
            }
        }
        stepped
    }

    /// The projected density (39) at the midpoints of a raster of the domain (256 cells
    /// across in 1-D, 96 in 2-D, 32 in 3-D, 12 beyond), clipped at zero, as the nodes' masses.
    fn state_law(&self) -> Result<crate::filters::predictive::StateLaw, FilterError> {
        let n = self.layout.dims();
        // Beyond three dimensions (the total-degree basis) about 10⁵ points: 17⁴, 10⁵, 6⁶.
        let per = match n {
            1 => 256,
            2 => 96,
            3 => 32,
            _ => libm::floor(libm::pow(1e5 + 1.0, 1.0 / n as f64)) as usize,
        };
        let (axes, cells): (Vec<Vec<f64>>, Vec<f64>) = (0..n)
            .map(|d| {
                let (c, r) = (self.layout.centre[d], self.layout.half_width[d]);
                let h = 2.0 * r / per as f64;
                ((0..per).map(|i| c - r + (i as f64 + 0.5) * h).collect(), h)
            })
            .unzip();
        let kept: Vec<(usize, &[f64])> =
            axes.iter().enumerate().map(|(d, a)| (d, &a[..])).collect();
        let values = self.projected(&kept);
        let k = values.len();
        let total: f64 = values.iter().map(|v| v.max(0.0)).sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(FilterError::MassLost);
        }
        let mut points = vec![0.0; n * k];
        for i in 0..k {
            let mut index = i;
            for (d, axis) in axes.iter().enumerate() {
                points[d * k + i] = axis[index % per];
                index /= per;
            }
        }
        Ok(crate::filters::predictive::StateLaw::Points {
            n,
            points,
            weights: values.iter().map(|v| v.max(0.0) / total).collect(),
            cells: Some(cells),
        })
    }

    /// The marginal of the projected density (39) on the on-line basis, clipped at zero;
    /// zero outside the domain.
    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        self.marginal(&[(dim, grid)], out);
    }

    /// The joint marginal of the projected density on the raster `xs × ys` (`xs` fastest),
    /// clipped at zero; zero outside the domain.
    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        self.marginal(&[(dims.0, xs), (dims.1, ys)], out);
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::test;

    /// The block sums against the definition, degree by degree, on a 3-D basis of 3 × 5 × 4.
    #[test]
    fn tail_energy_sums_the_top_quarter_of_each_dimension() {
        let counts = [3usize, 5, 4];
        let coeffs: alloc::vec::Vec<f64> =
            (0..60).map(|i| libm::sin(i as f64 * 0.7) + 0.1).collect();
        let total: f64 = coeffs.iter().map(|c| c * c).sum();
        let mut expected: f64 = 0.0;
        let mut stride = 1;
        for &count in &counts {
            let from = count - count.div_ceil(4);
            let tail: f64 = (0..60)
                .filter(|i| (i / stride) % count >= from)
                .map(|i| coeffs[i] * coeffs[i])
                .sum();
            expected = expected.max(tail / total);
            stride *= count;
        }
        let mut scaled = coeffs.clone();
        let energy = super::scale_and_measure(&mut scaled, -2.0, &counts);
        let got = energy.share();
        for (s, c) in scaled.iter().zip(&coeffs) {
            assert_eq!(*s, -2.0 * c);
        }
        assert!((energy.total - 4.0 * total).abs() <= 1e-14 * total);
        assert!(
            (got - expected).abs() <= 1e-15 * expected,
            "{got} vs {expected}"
        );
        assert!(got > 0.0);
    }
}
