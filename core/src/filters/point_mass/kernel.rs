//! The transition kernel on the grid: `T[i, j] = P(x_k ∈ cell i | x_(k−1) = ξ_j)` for
//! `x_k = F(ξ_j) + w_k`, `w_k ~ N(0, Q(ξ_j))`, cut at `radius` standard deviations.
//!
//! * **Diagonal Q** (constant or a function of the state): `T` is a product over the
//!   dimensions of the Gaussian's mass in each cell's interval,
//!   `Φ((x_i + Δ/2 − F_l)/σ_l) − Φ((x_i − Δ/2 − F_l)/σ_l)` — the cell-integrated kernel, which
//!   keeps the mass of a kernel narrower than a cell (σ = 0 puts it all in the cell holding
//!   F_l); renormalised over the cut window.
//! * **Correlated constant Q**: `T ∝ exp(−½ dᵀQ⁻¹d)`, `d = x_i − F(ξ_j)`, at the cell
//!   centres of the window, renormalised over the window.
//!
//! * **Gaussian-mixture w_k** `Σ_c π_c N(μ_c, Q_c)` ([`crate::TransitionMixture`]): the
//!   kernel is the mixture of the components' kernels, `T = Σ_c π_c T_c`, each `T_c` that of
//!   `F + μ_c` with `Q_c` as above ([`Kernel`]).
//!
//! In all, a window is that of the unbounded lattice of cells: what it puts beyond the box is
//! lost (counted, for the self-check), never folded back. Cost: per source cell, the product
//! of the window widths `2·radius·σ_l/Δx_l + 1` (summed over a mixture's components).

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use crate::error::FilterError;
use crate::grid::TensorGrid;
use crate::model::{MixtureComponent, Model, ProcessNoise};

/// The shape of w_k's covariance on the grid.
#[derive(Clone, Debug)]
enum Spread {
    /// σ_l at every cell, n per cell (constant Q: one row).
    Diagonal { sd: Vec<f64>, constant: bool },
    /// Q⁻¹ (row-major) and the window's half-widths σ_l = √Q_ll.
    Correlated { inverse: Vec<f64>, sd: Vec<f64> },
}

/// The kernel tabulated for one transition: F at every cell and the spread of w_k.
#[derive(Clone, Debug)]
pub(super) struct TransitionKernel {
    /// F(ξ_j), n per cell (shared by a mixture's components).
    centres: alloc::sync::Arc<Vec<f64>>,
    /// The component's mean μ_c added to F (zeros for `N(0, Q)` noise), and the centre
    /// `F(ξ_j) + μ_c` of the cell being visited.
    shift: Vec<f64>,
    centre: Vec<f64>,
    spread: Spread,
    radius: f64,
    /// Per dimension: the first cell of the window and its weights (reused).
    first: Vec<isize>,
    weights: Vec<Vec<f64>>,
    /// An odometer over the window and one displacement (correlated Q).
    counter: Vec<usize>,
    d: Vec<f64>,
    /// Every source cell's windows, computed once for a kernel that does not change (an
    /// autonomous model with a diagonal Q) when they fit in [`CACHED_VALUES`].
    cache: Option<alloc::sync::Arc<WindowCache>>,
}

/// Most cells a correlated Q's window may have (its weights are summed over the whole window
/// for every cell at every transition).
pub(super) const MAX_CORRELATED_WINDOW: usize = 1 << 20;

/// Most window weights a kernel keeps (64 MiB): the memory estimate counts up to this many.
pub(super) const CACHED_VALUES: usize = 8 << 20;

/// The windows of every source cell: per (cell, dimension) the first cell and the weights
/// `values[start[i]..start[i + 1]]`, and per cell the window's mass inside the box (0 where it
/// misses the box).
#[derive(Clone, Debug)]
struct WindowCache {
    first: Vec<isize>,
    start: Vec<usize>,
    values: Vec<f64>,
    inside: Vec<f64>,
}

/// A walk over a correlated Q's window (on the unbounded lattice of cells; its extent per
/// dimension is `weights[l].len()`).
struct Odometer<'a> {
    grid: &'a TensorGrid,
    first: &'a [isize],
    weights: &'a [Vec<f64>],
    counter: &'a mut [usize],
    d: &'a mut [f64],
    centre: &'a [f64],
}

impl Odometer<'_> {
    /// Calls `f(index in the box or None, dᵀQ⁻¹d)` for every cell of the window, d the
    /// cell's centre less the kernel's (`inverse` is Q⁻¹, row-major).
    fn each(&mut self, inverse: &[f64], mut f: impl FnMut(Option<usize>, f64)) {
        let n = self.grid.dim();
        self.counter.iter_mut().for_each(|c| *c = 0);
        loop {
            let mut idx = Some(0usize);
            for l in 0..n {
                let i = self.first[l] + self.counter[l] as isize;
                idx = idx
                    .filter(|_| i >= 0 && i < self.grid.shape()[l] as isize)
                    .map(|idx| idx + i as usize * self.grid.stride(l));
                self.d[l] =
                    self.grid.coordinate(l, 0) + i as f64 * self.grid.spacing()[l] - self.centre[l];
            }
            let mut w = 0.0;
            for a in 0..n {
                for b in 0..n {
                    w += self.d[a] * inverse[a * n + b] * self.d[b];
                }
            }
            f(idx, w);
            let mut l = 0;
            loop {
                if l == n {
                    return;
                }
                self.counter[l] += 1;
                if self.counter[l] < self.weights[l].len() {
                    break;
                }
                self.counter[l] = 0;
                l += 1;
            }
        }
    }
}

/// Φ, the standard normal distribution function.
fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x * core::f64::consts::FRAC_1_SQRT_2)
}

impl TransitionKernel {
    /// The kernel of `centres` (F at every cell) with the model's Q, or Q(ξ) at every cell;
    /// with `component`, that of one component `N(μ_c, Q_c)` of a mixture noise. A
    /// state-dependent Q with mixed terms is refused (not implemented), as is a correlated Q
    /// that is singular (its density does not exist). With a `keep` budget, the windows are
    /// computed once and kept when they fit in it (for a kernel used at every step: an
    /// autonomous model's).
    fn new(
        name: &str,
        model: &Model,
        grid: &TensorGrid,
        (centres, radius, keep): (&alloc::sync::Arc<Vec<f64>>, f64, usize),
        component: Option<&MixtureComponent>,
    ) -> Result<Self, FilterError> {
        let n = model.n;
        let spread = spread_on(name, model, grid, radius, component)?;
        let mut kernel = TransitionKernel {
            centres: centres.clone(),
            shift: component.map_or_else(|| vec![0.0; n], |c| c.mean.as_slice().to_vec()),
            centre: vec![0.0; n],
            spread,
            radius,
            first: vec![0; n],
            weights: vec![Vec::new(); n],
            counter: vec![0; n],
            d: vec![0.0; n],
            cache: None,
        };
        if keep > 0 && matches!(kernel.spread, Spread::Diagonal { .. }) {
            // Shared, not copied, by the filter's clones (a smoother's, a fork).
            kernel.cache = kernel
                .windows_of_every_cell(grid, keep)
                .map(alloc::sync::Arc::new);
        }
        Ok(kernel)
    }

    /// Sets `self.centre` to cell j's `F(ξ_j) + μ_c`.
    fn centre_of(&mut self, j: usize) {
        let n = self.shift.len();
        for ((c, f), s) in self
            .centre
            .iter_mut()
            .zip(&self.centres[j * n..(j + 1) * n])
            .zip(&self.shift)
        {
            *c = f + s;
        }
    }

    /// Every source cell's windows ([`WindowCache`]), or `None` past `budget` values.
    fn windows_of_every_cell(&mut self, grid: &TensorGrid, budget: usize) -> Option<WindowCache> {
        let n = grid.dim();
        let mut cache = WindowCache {
            first: Vec::with_capacity(grid.len() * n),
            start: vec![0],
            values: Vec::new(),
            inside: Vec::with_capacity(grid.len()),
        };
        for j in 0..grid.len() {
            let meets = self.window(grid, j);
            cache.inside.push(match meets {
                true => window_mass(&self.weights),
                false => 0.0,
            });
            for l in 0..n {
                if cache.values.len() + self.weights[l].len() > budget {
                    return None;
                }
                cache.first.push(self.first[l]);
                cache.values.extend_from_slice(&self.weights[l]);
                cache.start.push(cache.values.len());
            }
        }
        Some(cache)
    }

    /// Cells in the window of the widest kernel (for the cost and memory estimates).
    pub(super) fn widest_window(&self, grid: &TensorGrid) -> f64 {
        let n = grid.dim();
        let sd: &[f64] = match &self.spread {
            Spread::Diagonal { sd, .. } | Spread::Correlated { sd, .. } => sd,
        };
        (0..n)
            .map(|l| {
                let widest = sd.iter().skip(l).step_by(n).fold(0.0f64, |a, &b| a.max(b));
                2.0 * self.radius * widest / grid.spacing()[l] + 1.0
            })
            .product()
    }

    /// The window of source cell `j` (computed, not read from the cache): per dimension its
    /// first cell (on the unbounded lattice) and its weights, normalised over the window; false
    /// when F(ξ_j) is so far outside the box that the window misses it.
    fn window(&mut self, grid: &TensorGrid, j: usize) -> bool {
        let n = grid.dim();
        self.centre_of(j);
        let centre = &self.centre;
        let mut inside = true;
        for l in 0..n {
            let (dx, x0, cells) = (grid.spacing()[l], grid.coordinate(l, 0), grid.shape()[l]);
            let sd = match &self.spread {
                Spread::Diagonal { sd, constant } => sd[if *constant { l } else { j * n + l }],
                Spread::Correlated { sd, .. } => sd[l],
            };
            let w = &mut self.weights[l];
            w.clear();
            let Some((lo, hi)) = extent(grid, l, centre[l], self.radius * sd) else {
                inside = false;
                continue;
            };
            if let Spread::Correlated { .. } = self.spread {
                // Only the range (checked against MAX_WINDOW when the kernel is made): the
                // weights are of the whole displacement, normalised over the whole window.
                self.first[l] = lo as isize;
                w.resize((hi - lo) as usize + 1, 1.0);
                continue;
            }
            // Only the cells in the box are kept; the normaliser is the whole window's mass,
            // Φ at its outer edges, so what falls beyond the box is lost (and counted).
            let (lo_in, hi_in) = (lo.max(0.0) as isize, hi.min((cells - 1) as f64) as isize);
            self.first[l] = lo_in;
            if sd == 0.0 {
                // All of it in the cell that holds F (lo = hi).
                w.push(1.0);
                continue;
            }
            // Φ at the cells' edges, each edge once: a cell's mass is the difference.
            let edge = |i: f64| normal_cdf((x0 + (i - 0.5) * dx - centre[l]) / sd);
            let total = edge(hi + 1.0) - edge(lo);
            let mut below = edge(lo_in as f64);
            for i in lo_in..=hi_in {
                let above = edge((i + 1) as f64);
                w.push(above - below);
                below = above;
            }
            if total > 0.0 {
                w.iter_mut().for_each(|v| *v /= total);
            }
        }
        inside
    }

    /// Visits source cell `j`'s window by lines along dimension 0 (contiguous in the grid):
    /// `row(offset, factor, w)` says that cells `offset..offset + w.len()` of the box have
    /// `T[i, j] = factor · w[i − offset]`. Returns the weight the window puts outside the box.
    ///
    /// A diagonal Q's window is a product over the dimensions of weights already clipped to
    /// the box, so each line is one contiguous run (a loop the compiler vectorises) and the
    /// mass inside is the product of the per-dimension sums; a correlated Q's is visited cell
    /// by cell (lines of one).
    fn visit(
        &mut self,
        grid: &TensorGrid,
        j: usize,
        mut row: impl FnMut(usize, f64, &[f64]),
    ) -> f64 {
        if matches!(self.spread, Spread::Correlated { .. }) {
            if !self.window(grid, j) {
                return 1.0;
            }
            let Spread::Correlated { inverse, .. } = &self.spread else {
                unreachable!("matched above")
            };
            let mut odometer = Odometer {
                grid,
                first: &self.first,
                weights: &self.weights,
                counter: &mut self.counter,
                d: &mut self.d,
                centre: &self.centre,
            };
            // exp(−½(q − q_min)): a kernel narrower than a cell keeps its mass in the
            // nearest cells instead of underflowing everywhere.
            let mut least = f64::INFINITY;
            odometer.each(inverse, |_, q| least = least.min(q));
            let mut total = 0.0;
            odometer.each(inverse, |_, q| total += libm::exp(-0.5 * (q - least)));
            if !(total > 0.0 && total.is_finite()) {
                return 1.0;
            }
            let mut inside = 0.0;
            odometer.each(inverse, |idx, q| {
                if let Some(idx) = idx {
                    let w = libm::exp(-0.5 * (q - least)) / total;
                    inside += w;
                    row(idx, w, &[1.0]);
                }
            });
            return (1.0 - inside).max(0.0);
        }
        let n = grid.dim();
        let inside = match &self.cache {
            Some(cache) if cache.inside[j] == 0.0 => 0.0,
            Some(cache) => {
                let at =
                    |l: usize| &cache.values[cache.start[j * n + l]..cache.start[j * n + l + 1]];
                window_lines(
                    grid,
                    &cache.first[j * n..(j + 1) * n],
                    at,
                    &mut self.counter,
                    row,
                );
                cache.inside[j]
            }
            None => match self.window(grid, j) {
                false => 0.0,
                true => {
                    let weights = &self.weights;
                    let at = |l: usize| weights[l].as_slice();
                    window_lines(grid, &self.first, at, &mut self.counter, row);
                    window_mass(weights)
                }
            },
        };
        (1.0 - inside).max(0.0)
    }

    /// Adds `scale · T p` to `out`; returns the mass (of `scale · p`) carried outside the box.
    fn add_predicted(&mut self, grid: &TensorGrid, p: &[f64], scale: f64, out: &mut [f64]) -> f64 {
        let mut lost = 0.0;
        for (j, &pj) in p.iter().enumerate() {
            if pj > 0.0 {
                let pj = scale * pj;
                lost += pj
                    * self.visit(grid, j, |offset, factor, w| {
                        crate::linalg::add_scaled(
                            &mut out[offset..offset + w.len()],
                            pj * factor,
                            w,
                        )
                    });
            }
        }
        lost
    }

    /// Adds `scale · Tᵀ β` to `out`: the smoother's backward pass.
    fn add_transposed(&mut self, grid: &TensorGrid, beta: &[f64], scale: f64, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            let mut sum = 0.0;
            self.visit(grid, j, |offset, factor, w| {
                let line = &beta[offset..offset + w.len()];
                sum += factor * crate::linalg::dot(line, w);
            });
            *o += scale * sum;
        }
    }
}

/// The cells (on the unbounded lattice of dimension `l`, as reals) whose centres lie within
/// `reach` of `centre`, rounded to the nearest: `(lo, hi)`, or `None` when they miss the box.
fn extent(grid: &TensorGrid, l: usize, centre: f64, reach: f64) -> Option<(f64, f64)> {
    let (dx, x0, cells) = (grid.spacing()[l], grid.coordinate(l, 0), grid.shape()[l]);
    let lo = libm::floor((centre - reach - x0) / dx + 0.5);
    let hi = libm::floor((centre + reach - x0) / dx + 0.5);
    match hi < 0.0 || lo > (cells - 1) as f64 || (hi - lo).is_nan() {
        true => None,
        false => Some((lo, hi)),
    }
}

/// φ, the standard normal density.
fn normal_pdf(x: f64) -> f64 {
    libm::exp(-0.5 * x * x) / libm::sqrt(core::f64::consts::TAU)
}

/// A diagonal Q's kernel with its derivatives in the centre `c_l = F_l(ξ_j)` and the spread
/// `σ_l` of each source cell's window: per (cell j, dimension l) the window's first cell in
/// the box, its weights `w = (Φ(b) − Φ(a))/Z` (a, b the cells' edges less c over σ; Z the whole
/// window's mass, which renormalises it) and
///
/// ```text
/// ∂w/∂c = (−(φ(b) − φ(a))/σ − w ∂Z/∂c)/Z,    ∂w/∂σ = (−(bφ(b) − aφ(a))/σ − w ∂Z/∂σ)/Z,
/// ```
///
/// with `∂Z` the same differences at the window's outer edges (the window's extent held: a
/// cell entering it as c moves carries a mass below `Φ(−radius)`). What the gradient of the
/// point-mass likelihood needs ([`super::score`]).
#[derive(Clone, Debug)]
pub(super) struct KernelDerivatives {
    first: Vec<isize>,
    start: Vec<usize>,
    weights: Vec<f64>,
    by_centre: Vec<f64>,
    by_spread: Vec<f64>,
    /// c and σ per (cell, dimension).
    centre: Vec<f64>,
    spread: Vec<f64>,
    counter: Vec<usize>,
}

impl KernelDerivatives {
    /// c per (source cell, dimension), row-major.
    pub(super) fn centres(&self) -> &[f64] {
        &self.centre
    }

    /// σ per (source cell, dimension), row-major.
    pub(super) fn spreads(&self) -> &[f64] {
        &self.spread
    }

    /// For source cell `j`: `(Tᵀv)_j = Σ_i v_i T[i, j]`, returned, and for every dimension l
    /// `by_centre[l] = Σ_i v_i ∂T[i, j]/∂c_l`, `by_spread[l] = Σ_i v_i ∂T[i, j]/∂σ_l` (T the
    /// product of the dimensions' weights) — one walk over the window's lines along dimension
    /// 0, three sums per line ([`dot3`]).
    pub(super) fn adjoint(
        &mut self,
        grid: &TensorGrid,
        j: usize,
        v: &[f64],
        by_centre: &mut [f64],
        by_spread: &mut [f64],
    ) -> f64 {
        let n = self.counter.len();
        by_centre.iter_mut().for_each(|b| *b = 0.0);
        by_spread.iter_mut().for_each(|b| *b = 0.0);
        let range = |l: usize| self.start[j * n + l]..self.start[j * n + l + 1];
        if (0..n).any(|l| range(l).is_empty()) {
            return 0.0;
        }
        let (w, dc, ds) = (&self.weights, &self.by_centre, &self.by_spread);
        let first = &self.first[j * n..(j + 1) * n];
        let line = range(0);
        let counter = &mut self.counter;
        counter.iter_mut().for_each(|c| *c = 0);
        let mut total = 0.0;
        loop {
            let mut offset = first[0] as usize;
            let mut factor = 1.0;
            for l in 1..n {
                offset += (first[l] as usize + counter[l]) * grid.stride(l);
                factor *= w[range(l)][counter[l]];
            }
            let [plain, centre, spread] = dot3(
                &v[offset..offset + line.len()],
                &w[line.clone()],
                &dc[line.clone()],
                &ds[line.clone()],
            );
            total += factor * plain;
            by_centre[0] += factor * centre;
            by_spread[0] += factor * spread;
            for l in 1..n {
                let others: f64 = (1..n)
                    .filter(|&m| m != l)
                    .map(|m| w[range(m)][counter[m]])
                    .product();
                let at = range(l).start + counter[l];
                by_centre[l] += dc[at] * others * plain;
                by_spread[l] += ds[at] * others * plain;
            }
            let mut l = 1;
            loop {
                if l >= n {
                    return total;
                }
                counter[l] += 1;
                if counter[l] < range(l).len() {
                    break;
                }
                counter[l] = 0;
                l += 1;
            }
        }
    }
}

crate::linalg::simd::per_node_kernel! {
    wide:
    /// `[Σ v_i a_i, Σ v_i b_i, Σ v_i c_i]` in one pass over v, each in eight lanes added in a
    /// fixed order ([`crate::linalg::lanes_total`]).
    fn dot3(v: &[f64], a: &[f64], b: &[f64], c: &[f64]) -> [f64; 3] {
        const LANES: usize = 8;
        let len = v.len().min(a.len()).min(b.len()).min(c.len());
        let whole = len - len % LANES;
        let mut s = [[0.0; LANES]; 3];
        for start in (0..whole).step_by(LANES) {
            for l in 0..LANES {
                let x = v[start + l];
                s[0][l] += x * a[start + l];
                s[1][l] += x * b[start + l];
                s[2][l] += x * c[start + l];
            }
        }
        for (l, i) in (whole..len).enumerate() {
            s[0][l] += v[i] * a[i];
            s[1][l] += v[i] * b[i];
            s[2][l] += v[i] * c[i];
        }
        s.map(crate::linalg::lanes_total)
    }
}

impl TransitionKernel {
    /// [`KernelDerivatives`] of this kernel (only c and σ without `windows`): an error for a
    /// correlated Q, a component of a mixture noise and a zero spread (whose kernel has no
    /// derivative in c).
    fn derivatives(
        &mut self,
        grid: &TensorGrid,
        windows: bool,
    ) -> Result<KernelDerivatives, FilterError> {
        let n = grid.dim();
        let Spread::Diagonal { sd, constant } = &self.spread else {
            return Err(FilterError::Unsuitable(
                "the gradient of the point-mass likelihood is implemented for a diagonal transition noise Q, and this one is correlated".into(),
            ));
        };
        if self.shift.iter().any(|&s| s != 0.0) {
            return Err(FilterError::Unsuitable(
                "the gradient of the point-mass likelihood is not implemented for a Gaussian-mixture transition noise".into(),
            ));
        }
        let (sd, constant) = (sd.clone(), *constant);
        let mut d = KernelDerivatives {
            first: Vec::with_capacity(grid.len() * n),
            start: vec![0],
            weights: Vec::new(),
            by_centre: Vec::new(),
            by_spread: Vec::new(),
            centre: Vec::with_capacity(grid.len() * n),
            spread: Vec::with_capacity(grid.len() * n),
            counter: vec![0; n],
        };
        for j in 0..grid.len() {
            self.centre_of(j);
            for l in 0..n {
                let (c, s) = (self.centre[l], sd[if constant { l } else { j * n + l }]);
                if s.is_nan() || s <= 0.0 {
                    return Err(FilterError::Unsuitable(
                        "the gradient of the point-mass likelihood needs a transition noise in every component (a zero sd puts the mass in one cell, which does not move smoothly with F)".into(),
                    ));
                }
                d.centre.push(c);
                d.spread.push(s);
                if !windows {
                    continue;
                }
                let (dx, x0, cells) = (grid.spacing()[l], grid.coordinate(l, 0), grid.shape()[l]);
                let Some((lo, hi)) = extent(grid, l, c, self.radius * s) else {
                    d.first.push(0);
                    d.start.push(d.weights.len());
                    continue;
                };
                let (lo_in, hi_in) = (lo.max(0.0) as isize, hi.min((cells - 1) as f64) as isize);
                d.first.push(lo_in);
                // Φ, φ/σ and aφ/σ at an edge: the mass below it and its derivatives' negatives.
                let edge = |i: f64| {
                    let a = (x0 + (i - 0.5) * dx - c) / s;
                    let density = normal_pdf(a) / s;
                    (normal_cdf(a), density, a * density)
                };
                let (low, high) = (edge(lo), edge(hi + 1.0));
                let total = high.0 - low.0;
                let (total_c, total_s) = (-(high.1 - low.1), -(high.2 - low.2));
                let mut below = edge(lo_in as f64);
                for i in lo_in..=hi_in {
                    let above = edge((i + 1) as f64);
                    let w = (above.0 - below.0) / total;
                    d.weights.push(w);
                    d.by_centre
                        .push((-(above.1 - below.1) - w * total_c) / total);
                    d.by_spread
                        .push((-(above.2 - below.2) - w * total_s) / total);
                    below = above;
                }
                d.start.push(d.weights.len());
            }
        }
        Ok(d)
    }
}

/// The mass of a product window clipped to the box: the product of the per-dimension sums.
fn window_mass(weights: &[Vec<f64>]) -> f64 {
    weights
        .iter()
        .map(|w| crate::linalg::sum_in_lanes(w, |v| v))
        .product()
}

/// The lines along dimension 0 of a product window (per dimension l its first cell `first[l]`
/// in the box and its weights `weights(l)`, clipped to the box): `row(offset, factor, w₀)`
/// for each, with `factor` the product of the other dimensions' weights.
fn window_lines<'a>(
    grid: &TensorGrid,
    first: &[isize],
    weights: impl Fn(usize) -> &'a [f64],
    counter: &mut [usize],
    mut row: impl FnMut(usize, f64, &[f64]),
) {
    let n = first.len();
    if (0..n).any(|l| weights(l).is_empty()) {
        return;
    }
    let w0 = weights(0);
    counter.iter_mut().for_each(|c| *c = 0);
    loop {
        let mut offset = first[0] as usize;
        let mut factor = 1.0;
        for l in 1..n {
            offset += (first[l] as usize + counter[l]) * grid.stride(l);
            factor *= weights(l)[counter[l]];
        }
        row(offset, factor, w0);
        let mut l = 1;
        loop {
            if l >= n {
                return;
            }
            counter[l] += 1;
            if counter[l] < weights(l).len() {
                break;
            }
            counter[l] = 0;
            l += 1;
        }
    }
}

/// The model's transition kernel on the grid: that of `N(0, Q)` noise, or for a mixture noise
/// the weighted kernels of its components, `T = Σ_c π_c T_c`.
#[derive(Clone, Debug)]
pub(super) struct Kernel {
    parts: Vec<(f64, TransitionKernel)>,
}

impl Kernel {
    /// Tabulates `model`'s transition on `grid` ([`TransitionKernel::new`], once per
    /// component of a mixture noise).
    pub(super) fn new(
        name: &str,
        model: &Model,
        grid: &TensorGrid,
        radius: f64,
        keep: bool,
    ) -> Result<Self, FilterError> {
        let n = model.n;
        let mut centres = Vec::with_capacity(grid.len() * n);
        let mut fx = vec![0.0; n];
        grid.for_each_node(|_, x| {
            model.drift.eval(x, &mut fx);
            centres.extend_from_slice(&fx);
        });
        if centres.iter().any(|v| !v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "transition map F on the grid",
            });
        }
        let centres = alloc::sync::Arc::new(centres);
        let parts = match &model.transition_mixture {
            None => {
                let keep = if keep { CACHED_VALUES } else { 0 };
                vec![(
                    1.0,
                    TransitionKernel::new(name, model, grid, (&centres, radius, keep), None)?,
                )]
            }
            Some(w) => {
                // The kept windows share one budget.
                let components = w.mixture().components();
                let keep = if keep {
                    CACHED_VALUES / components.len()
                } else {
                    0
                };
                components
                    .iter()
                    .map(|c| {
                        TransitionKernel::new(name, model, grid, (&centres, radius, keep), Some(c))
                            .map(|k| (c.weight, k))
                    })
                    .collect::<Result<_, _>>()?
            }
        };
        Ok(Kernel { parts })
    }

    /// Cells the kernel's windows reach from the cell where they are widest, summed over a
    /// mixture's components (for the cost and memory estimates).
    pub(super) fn widest_window(&self, grid: &TensorGrid) -> f64 {
        self.parts.iter().map(|(_, k)| k.widest_window(grid)).sum()
    }

    /// The kernel's [`KernelDerivatives`] (only its c and σ without `windows`): an error for
    /// a Gaussian-mixture noise, a correlated Q or a zero spread.
    pub(super) fn derivatives(
        &mut self,
        grid: &TensorGrid,
        windows: bool,
    ) -> Result<KernelDerivatives, FilterError> {
        match self.parts.as_mut_slice() {
            [(_, kernel)] => kernel.derivatives(grid, windows),
            _ => Err(FilterError::Unsuitable(
                "the gradient of the point-mass likelihood is not implemented for a Gaussian-mixture transition noise".into(),
            )),
        }
    }

    /// The prediction `out = T p` (`out` overwritten); returns the mass carried outside the
    /// box.
    pub(super) fn predict(&mut self, grid: &TensorGrid, p: &[f64], out: &mut [f64]) -> f64 {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.parts
            .iter_mut()
            .map(|(w, k)| k.add_predicted(grid, p, *w, out))
            .sum()
    }

    /// The transposed step `out = Tᵀ β` (`out` overwritten): the smoother's backward pass.
    pub(super) fn predict_transposed(&mut self, grid: &TensorGrid, beta: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (w, k) in &mut self.parts {
            k.add_transposed(grid, beta, *w, out);
        }
    }
}

/// The spread of w_k on `grid` (Q, or Q(ξ) at every cell): refused for a state-dependent Q
/// with mixed terms (not implemented), a correlated Q that is singular or whose window of
/// `radius` sd holds more than [`MAX_CORRELATED_WINDOW`] cells. What the method's
/// suitability checks before a run, and the kernel uses.
fn spread_on(
    name: &str,
    model: &Model,
    grid: &TensorGrid,
    radius: f64,
    component: Option<&MixtureComponent>,
) -> Result<Spread, FilterError> {
    let n = model.n;
    let spread = match (component, model.process_noise()) {
        (Some(c), _) => spread_of_constant(name, &c.cov)?,
        (None, ProcessNoise::Constant(q)) => spread_of_constant(name, &q)?,
        (None, ProcessNoise::StateDependent(_)) => {
            let table = model
                .process_noise()
                .tabulate(n, grid.len(), |i, x| grid.node(i, x));
            table.require_finite(name)?;
            if table
                .off
                .iter()
                .any(|(_, _, o)| o.iter().any(|v| *v != 0.0))
            {
                return Err(FilterError::Unsuitable(format!(
                    "{name}: a transition noise Q(x) = G(x) G(x)ᵀ with mixed terms is not implemented (a diagonal Q(x), or a constant correlated Q, is)"
                )));
            }
            let mut sd = vec![0.0; grid.len() * n];
            for (l, column) in table.diagonal.iter().enumerate() {
                for (j, q) in column.iter().enumerate() {
                    sd[j * n + l] = libm::sqrt(q.max(0.0));
                }
            }
            Spread::Diagonal {
                sd,
                constant: false,
            }
        }
    };
    if let Spread::Correlated { sd, .. } = &spread {
        let window: f64 = (0..n)
            .map(|l| 2.0 * radius * sd[l] / grid.spacing()[l] + 2.0)
            .product();
        if window > MAX_CORRELATED_WINDOW as f64 {
            return Err(FilterError::Unsuitable(format!(
                "{name}: the correlated transition noise reaches {window:.3e} cells from each cell (its window of ±{radius} sd), more than {MAX_CORRELATED_WINDOW}: use fewer cells, a smaller `radius`, or a diagonal Q"
            )));
        }
    }
    Ok(spread)
}

/// Why the model's transition noise does not fit the point-mass filter on `grid`, or `Ok`
/// ([`spread_on`]).
pub(super) fn check_noise(
    name: &str,
    model: &Model,
    grid: &TensorGrid,
    radius: f64,
) -> Result<(), FilterError> {
    match &model.transition_mixture {
        Some(w) => w
            .mixture()
            .components()
            .iter()
            .try_for_each(|c| spread_on(name, model, grid, radius, Some(c)).map(|_| ())),
        None => spread_on(name, model, grid, radius, None).map(|_| ()),
    }
}

/// The spread of a constant Q: its diagonal's square roots, or Q⁻¹ when it has mixed terms.
fn spread_of_constant(name: &str, q: &DMatrix<f64>) -> Result<Spread, FilterError> {
    let n = q.nrows();
    let sd: Vec<f64> = (0..n).map(|l| libm::sqrt(q[(l, l)].max(0.0))).collect();
    let correlated = (0..n).any(|a| (0..n).any(|b| a != b && q[(a, b)] != 0.0));
    if !correlated {
        return Ok(Spread::Diagonal { sd, constant: true });
    }
    let inverse = q.clone().try_inverse().filter(|_| q.clone().cholesky().is_some()).ok_or_else(|| {
        FilterError::Unsuitable(format!(
            "{name}: the transition noise Q = G Gᵀ is correlated and singular, so w_k has no density on the grid (make Q diagonal or nonsingular)"
        ))
    })?;
    Ok(Spread::Correlated {
        inverse: inverse.transpose().as_slice().to_vec(),
        sd,
    })
}
