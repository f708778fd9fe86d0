//! Tensor grids on a box with zero Dirichlet boundary (000 §2.1, (6)–(10)), densities on them,
//! their moments, and the DST-I plans that diagonalise the discrete Laplacian.
//!
//! A grid has N_d *interior* nodes in dimension d, `s_i = lower_d + i Δs_d`, i = 1..N_d, with
//! `Δs_d = (upper_d − lower_d)/(N_d + 1)`; the boundary nodes carry the zero Dirichlet value and
//! are not stored. Values are stored with the first dimension fastest.

/// The mixed second derivatives of the Fokker–Planck operator as a positive step.
pub(crate) mod cross;
#[cfg(feature = "std")]
#[doc(hidden)]
pub(crate) mod dst;
/// Tridiagonal systems along grid lines (the dimension-split implicit steps).
pub(crate) mod lines;
/// Odd-length FFTs by vectorised Stockham stages (the DST's half length).
#[cfg(feature = "std")]
mod odd_fft;
/// Tensors in tensor-train format (groundwork for the filters beyond three dimensions).
pub(crate) mod tt;

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::error::ZakaiError;

/// Largest number of grid nodes any method may allocate (2²⁴ ≈ 16.8 million, 128 MiB per
/// array of f64).
pub(crate) const MAX_NODES: usize = 1 << 24;

/// Calls `f(start)` for the first node of every grid line along the dimension with `stride`
/// and `n` nodes per line.
pub(crate) fn for_each_line(len: usize, stride: usize, n: usize, mut f: impl FnMut(usize)) {
    let block = stride * n;
    for outer in (0..len).step_by(block) {
        for inner in 0..stride {
            f(outer + inner);
        }
    }
}

/// A read-only view of a grid density (first dimension fastest).
#[derive(Clone, Copy, Debug)]
pub struct DensityView<'a> {
    /// Per-dimension `(lower, upper)` bounds of the grid.
    pub bounds: &'a [(f64, f64)],
    /// Points per dimension.
    pub shape: &'a [usize],
    /// Normalised density values at the grid points.
    pub values: &'a [f64],
}

/// A tensor grid of interior nodes on a box.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorGrid {
    bounds: Vec<(f64, f64)>,
    shape: Vec<usize>,
    spacing: Vec<f64>,
    strides: Vec<usize>,
    len: usize,
    /// The node coordinates of the first dimension.
    first_axis: Vec<f64>,
}

/// What [`TensorGrid::moments`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Moments {
    /// Σ u Δs^D.
    pub mass: f64,
    /// Mean.
    pub mean: DVector<f64>,
    /// Covariance.
    pub covariance: DMatrix<f64>,
    /// The node of largest value (the MAP cell).
    pub map: DVector<f64>,
}

impl Moments {
    /// Zero moments of dimension `d`: storage for [`TensorGrid::moments_into`].
    pub fn zeros(d: usize) -> Moments {
        Moments {
            mass: 0.0,
            mean: DVector::zeros(d),
            covariance: DMatrix::zeros(d, d),
            map: DVector::zeros(d),
        }
    }
}

impl TensorGrid {
    /// A grid with `shape[d]` interior nodes on `[bounds[d].0, bounds[d].1]`; refuses grids
    /// beyond 2²⁴ nodes before allocating anything.
    pub fn new(bounds: &[(f64, f64)], shape: &[usize]) -> Result<Self, ZakaiError> {
        if bounds.len() != shape.len() || shape.is_empty() {
            return Err(ZakaiError::Dimension(format!(
                "grid has {} bounds and {} point counts",
                bounds.len(),
                shape.len()
            )));
        }
        let mut len: usize = 1;
        for (d, &n) in shape.iter().enumerate() {
            if n < 3 {
                return Err(ZakaiError::Other(format!(
                    "grid needs at least 3 points in dimension {}, got {n}",
                    d + 1
                )));
            }
            len = len
                .checked_mul(n)
                .filter(|&l| l <= MAX_NODES)
                .ok_or_else(|| ZakaiError::TooLarge {
                    what: format!("grid of {shape:?} points"),
                    limit: MAX_NODES,
                    unit: "nodes",
                })?;
        }
        let spacing = bounds
            .iter()
            .zip(shape)
            .map(|(b, &n)| (b.1 - b.0) / (n + 1) as f64)
            .collect();
        let mut strides = vec![1; shape.len()];
        for d in 1..shape.len() {
            strides[d] = strides[d - 1] * shape[d - 1];
        }
        let mut grid = TensorGrid {
            bounds: bounds.to_vec(),
            shape: shape.to_vec(),
            spacing,
            strides,
            len,
            first_axis: Vec::new(),
        };
        grid.first_axis = (0..shape[0]).map(|i| grid.coordinate(0, i)).collect();
        Ok(grid)
    }

    /// Dimension D.
    pub fn dim(&self) -> usize {
        self.shape.len()
    }
    /// Interior nodes per dimension.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }
    /// Box bounds.
    pub fn bounds(&self) -> &[(f64, f64)] {
        &self.bounds
    }
    /// Δs per dimension.
    pub fn spacing(&self) -> &[f64] {
        &self.spacing
    }
    /// Distance in the flat array between neighbours in dimension d.
    pub fn stride(&self, d: usize) -> usize {
        self.strides[d]
    }
    /// Total number of nodes.
    pub fn len(&self) -> usize {
        self.len
    }
    /// Always false (a grid has at least 3 nodes per dimension).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// Volume of one cell, Π Δs_d.
    pub fn cell_volume(&self) -> f64 {
        self.spacing.iter().product()
    }
    /// Coordinate of node `i` (0-based interior index) in dimension d.
    pub fn coordinate(&self, d: usize, i: usize) -> f64 {
        self.bounds[d].0 + (i + 1) as f64 * self.spacing[d]
    }
    /// The node coordinates of flat index `idx`, written into `x`.
    pub fn node(&self, idx: usize, x: &mut [f64]) {
        let mut rest = idx;
        for (d, xd) in x.iter_mut().enumerate().take(self.dim()) {
            let i = rest % self.shape[d];
            rest /= self.shape[d];
            *xd = self.coordinate(d, i);
        }
    }
    /// Per-dimension index of flat index `idx` in dimension d.
    pub fn index_in(&self, idx: usize, d: usize) -> usize {
        (idx / self.strides[d]) % self.shape[d]
    }

    /// The flat indices of the nodes before and after `idx` along dimension d, `None` past
    /// the ends of its grid line.
    pub fn neighbours(&self, idx: usize, d: usize) -> [Option<usize>; 2] {
        let (j, stride) = (self.index_in(idx, d), self.strides[d]);
        [
            (j > 0).then(|| idx - stride),
            (j + 1 < self.shape[d]).then(|| idx + stride),
        ]
    }

    /// Advances the odometer `counter` (per-dimension indices from dimension `first` on) and
    /// the coordinates `x` to the next node in storage order.
    fn next_node(&self, counter: &mut [usize], x: &mut [f64], first: usize) {
        for k in first..self.dim() {
            counter[k] += 1;
            if counter[k] < self.shape[k] {
                x[k] += self.spacing[k];
                return;
            }
            counter[k] = 0;
            x[k] = self.coordinate(k, 0);
        }
    }

    /// Calls `f(idx, x)` for every node in storage order, updating the coordinates `x`
    /// incrementally (an odometer) instead of dividing the flat index.
    pub fn for_each_node(&self, mut f: impl FnMut(usize, &[f64])) {
        let d = self.dim();
        let mut counter = vec![0usize; d];
        let mut x: Vec<f64> = (0..d).map(|k| self.coordinate(k, 0)).collect();
        for idx in 0..self.len {
            f(idx, &x);
            self.next_node(&mut counter, &mut x, 0);
        }
    }

    /// Evaluates `f` at every node.
    pub fn tabulate(&self, mut f: impl FnMut(&[f64]) -> f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.len);
        self.for_each_node(|_, x| out.push(f(x)));
        out
    }

    /// Mass Σ u Δs^D (rectangle rule; the boundary values are zero). The sum runs in eight
    /// lanes: the drivers' self-check takes it after every
    /// step, and as one chain of dependent additions it was a sizeable share of a QIEM run.
    pub fn mass(&self, u: &[f64]) -> f64 {
        crate::linalg::sum_in_lanes(u, |v| v) * self.cell_volume()
    }

    /// The mass of the positive part, Σ max(u, 0) Δs^D: what an observation factor that
    /// leaves only positive values multiplies.
    pub fn positive_mass(&self, u: &[f64]) -> f64 {
        crate::linalg::sum_in_lanes(u, |v| v.max(0.0)) * self.cell_volume()
    }

    /// Mass on the `layers` outermost nodes next to every face of the box (a node near two
    /// faces counts twice — an upper bound). Only those slabs are visited, so in 1-D it costs
    /// 2·`layers` additions.
    pub fn mass_near_boundary(&self, u: &[f64], layers: usize) -> f64 {
        let mut sum = 0.0;
        for d in 0..self.dim() {
            let (len, stride) = (self.shape[d], self.strides[d]);
            let block = len * stride;
            let (low, high) = (layers.min(len), len.saturating_sub(layers).max(layers));
            for outer in (0..u.len()).step_by(block) {
                for i in (0..low).chain(high..len) {
                    let start = outer + i * stride;
                    sum += u[start..start + stride].iter().sum::<f64>();
                }
            }
        }
        sum * self.cell_volume()
    }

    /// Mass (rectangle rule), mean, covariance and the node of largest value of a density that
    /// need not be normalised. One pass, line by line along the first dimension: each line
    /// contributes its sums `Σw`, `Σw x₀`, `Σw x₀²`, and the other coordinates are constant on it.
    pub fn moments(&self, u: &[f64]) -> Moments {
        let mut out = Moments::zeros(self.dim());
        self.moments_into(u, &mut out);
        out
    }

    /// [`TensorGrid::moments`] written into `out` (of this grid's dimension), allocating
    /// nothing: the filters' step calls it on storage made at construction.
    pub fn moments_into(&self, u: &[f64], out: &mut Moments) {
        let d = self.dim();
        let n0 = self.shape[0];
        let mut total = 0.0;
        // The largest value and the first line that holds it.
        let mut best = (f64::NEG_INFINITY, 0);
        let (mean, second) = (out.mean.as_mut_slice(), out.covariance.as_mut_slice());
        mean.fill(0.0);
        second.fill(0.0);
        // Coordinates of the current line in dimensions 1..D, kept in `map` until the end.
        let x = out.map.as_mut_slice();
        for (line, values) in u.chunks_exact(n0).enumerate() {
            let mut rest = line;
            for (k, xk) in x.iter_mut().enumerate().skip(1) {
                *xk = self.coordinate(k, rest % self.shape[k]);
                rest /= self.shape[k];
            }
            let [s0, s1, s2, top] = line_sums(values, &self.first_axis);
            if top > best.0 {
                best = (top, line);
            }
            total += s0;
            mean[0] += s1;
            second[0] += s2;
            for a in 1..d {
                mean[a] += s0 * x[a];
                second[a * d] += s1 * x[a];
                for b in 1..=a {
                    second[a * d + b] += s0 * x[a] * x[b];
                }
            }
        }
        mean.iter_mut().for_each(|m| *m /= total);
        for a in 0..d {
            for b in 0..=a {
                let c = second[a * d + b] / total - mean[a] * mean[b];
                second[a * d + b] = c;
                second[b * d + a] = c;
            }
        }
        // The first node of that line that holds the largest value (the first node of the
        // grid when no value is larger than −∞).
        let line = &u[best.1 * n0..(best.1 + 1) * n0];
        let i = first_index_of(line, best.0).unwrap_or(0);
        self.node(best.1 * n0 + i, x);
        out.mass = total * self.cell_volume();
    }

    /// Where `x` falls along dimension `dim`: `(i, f)` with x between node i and i + 1 (0-based,
    /// −1 and N standing for the zero boundary) at fraction f; `None` outside the box.
    fn locate(&self, dim: usize, x: f64) -> Option<(isize, f64)> {
        let n = self.shape[dim] as f64;
        // Node i (0-based) sits at lo + (i + 1) h; boundaries carry zero.
        let s = (x - self.bounds[dim].0) / self.spacing[dim] - 1.0;
        if !(s > -1.0 && s < n) {
            return None;
        }
        let i = libm::floor(s);
        Some((i as isize, s - i))
    }

    /// A read-only view of `values` on this grid (what grid filters return as their density).
    pub fn view<'a>(&'a self, values: &'a [f64]) -> DensityView<'a> {
        DensityView {
            bounds: &self.bounds,
            shape: &self.shape,
            values,
        }
    }

    /// Marginal density of dimension `dim` at the points `at` (linear interpolation of the
    /// marginal summed over the other dimensions, zero outside the box), for a density `u`
    /// normalised to unit mass.
    pub fn marginal(&self, u: &[f64], dim: usize, at: &[f64], out: &mut [f64]) {
        let n = self.shape[dim];
        let mut m = vec![0.0; n];
        for (idx, &w) in u.iter().enumerate() {
            m[self.index_in(idx, dim)] += w;
        }
        let other: f64 = self.cell_volume() / self.spacing[dim];
        let value = |i: isize| {
            if i < 0 || i >= n as isize {
                0.0
            } else {
                m[i as usize] * other
            }
        };
        for (o, &x) in out.iter_mut().zip(at) {
            *o = self
                .locate(dim, x)
                .map_or(0.0, |(i, f)| (1.0 - f) * value(i) + f * value(i + 1));
        }
    }

    /// Joint marginal density of dimensions `a` and `b` on the raster `xs × ys` (`xs`
    /// fastest; bilinear interpolation of the marginal summed over the other dimensions, zero
    /// outside the box), for a density `u` normalised to unit mass.
    pub fn marginal_2d(
        &self,
        u: &[f64],
        (a, b): (usize, usize),
        xs: &[f64],
        ys: &[f64],
        out: &mut [f64],
    ) {
        let (na, nb) = (self.shape[a], self.shape[b]);
        let mut m = vec![0.0; na * nb];
        for (idx, &w) in u.iter().enumerate() {
            m[self.index_in(idx, a) + na * self.index_in(idx, b)] += w;
        }
        let other = self.cell_volume() / (self.spacing[a] * self.spacing[b]);
        let value = |i: isize, j: isize| {
            if i < 0 || j < 0 || i >= na as isize || j >= nb as isize {
                0.0
            } else {
                m[i as usize + na * j as usize] * other
            }
        };
        for (row, &y) in out.chunks_mut(xs.len()).zip(ys) {
            let Some((j, g)) = self.locate(b, y) else {
                row.iter_mut().for_each(|o| *o = 0.0);
                continue;
            };
            for (o, &x) in row.iter_mut().zip(xs) {
                *o = self.locate(a, x).map_or(0.0, |(i, f)| {
                    (1.0 - g) * ((1.0 - f) * value(i, j) + f * value(i + 1, j))
                        + g * ((1.0 - f) * value(i, j + 1) + f * value(i + 1, j + 1))
                });
            }
        }
    }
}

/// The first position of `value` in `line`: [`LANES`] values compared at a time without a
/// branch (a loop that vectorises), then the one block that holds it searched value by value.
fn first_index_of(line: &[f64], value: f64) -> Option<usize> {
    let block = line
        .chunks(LANES)
        .position(|c| c.iter().fold(false, |found, &w| found | (w == value)))?;
    let start = block * LANES;
    line[start..]
        .iter()
        .position(|&w| w == value)
        .map(|i| start + i)
}

/// Partial sums per lane in [`line_sums`]: four vectors of four, so that no chain of dependent
/// additions waits on another's latency.
const LANES: usize = 16;

crate::linalg::simd::per_node_kernel! {
    /// `[Σ w_i, Σ w_i x_i, Σ w_i x_i², max w_i]` along one grid line, in [`LANES`] interleaved
    /// partial sums and maxima (combined in a fixed order, so the result does not depend on the
    /// vector width) that the compiler keeps in vector registers — one chain of dependent
    /// additions would wait on every addition's latency.
    fn line_sums(w: &[f64], x: &[f64]) -> [f64; 4] {
        let (mut s0, mut s1, mut s2) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        let mut top = [f64::NEG_INFINITY; LANES];
        let mut w_chunks = w.chunks_exact(LANES);
        let mut x_chunks = x.chunks_exact(LANES);
        let mut add = |l: usize, w: f64, x: f64| {
            let wx = w * x;
            s0[l] += w;
            s1[l] += wx;
            s2[l] += wx * x;
            top[l] = if w > top[l] { w } else { top[l] };
        };
        for (w, x) in (&mut w_chunks).zip(&mut x_chunks) {
            for l in 0..LANES {
                add(l, w[l], x[l]);
            }
        }
        for (l, (w, x)) in w_chunks.remainder().iter().zip(x_chunks.remainder()).enumerate() {
            add(l, *w, *x);
        }
        let sum = crate::linalg::lanes_total::<LANES>;
        let largest = top.iter().fold(f64::NEG_INFINITY, |m, &t| if t > m { t } else { m });
        [sum(s0), sum(s1), sum(s2), largest]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn the_map_node_is_the_first_of_equal_maxima() {
        // 2-D, 53 × 3 nodes: the maximum 5 at (7, 1) and (40, 1) and (2, 2): lane 7 and lane 0
        // (node 40 = 5·8) of the first line that has it, then a later line.
        let g = TensorGrid::new(&[(0.0, 54.0), (0.0, 4.0)], &[53, 3]).unwrap();
        let mut u = vec![1.0; g.len()];
        for i in [53 + 7, 53 + 40, 2 * 53 + 2] {
            u[i] = 5.0;
        }
        let map = g.moments(&u).map;
        assert_eq!((map[0], map[1]), (8.0, 2.0), "node (7, 1) sits at (8, 2)");
        // Sums against the plain loop.
        let (w, x): (Vec<f64>, Vec<f64>) =
            (0..37).map(|i| (i as f64 * 0.3, 1.0 - i as f64)).unzip();
        let [s0, s1, s2, top] = line_sums(&w, &x);
        let plain =
            |f: &dyn Fn(f64, f64) -> f64| w.iter().zip(&x).map(|(w, x)| f(*w, *x)).sum::<f64>();
        assert!((s0 - plain(&|w, _| w)).abs() < 1e-12);
        assert!((s1 - plain(&|w, x| w * x)).abs() < 1e-11);
        assert!((s2 - plain(&|w, x| w * x * x)).abs() < 1e-9);
        assert_eq!(top, 36.0 * 0.3);
    }

    #[test]
    fn nodes_moments_and_marginals() {
        let g = TensorGrid::new(&[(-5.0, 5.0), (-4.0, 6.0)], &[199, 99]).unwrap();
        assert_eq!(g.len(), 199 * 99);
        assert!((g.spacing()[0] - 0.05).abs() < 1e-15);
        let (m1, m2, v1, v2) = (0.5, 1.0, 0.8, 0.5);
        let u = g.tabulate(|x| {
            (-(x[0] - m1) * (x[0] - m1) / (2.0 * v1) - (x[1] - m2) * (x[1] - m2) / (2.0 * v2)).exp()
        });
        let Moments {
            mass,
            mean,
            covariance: cov,
            map,
        } = g.moments(&u);
        assert!((mass - g.mass(&u)).abs() < 1e-12 * mass);
        // The box cuts the first Gaussian 5σ above its mean: a bias of ~1e-6 in its mean.
        assert!(
            (mean[0] - m1).abs() < 1e-5 && (mean[1] - m2).abs() < 1e-9,
            "{mean}"
        );
        assert!(
            (cov[(0, 0)] - v1).abs() < 1e-4 && (cov[(1, 1)] - v2).abs() < 1e-8,
            "{cov}"
        );
        assert!(cov[(0, 1)].abs() < 1e-9);
        assert!((map[0] - m1).abs() <= 0.05 && (map[1] - m2).abs() <= 0.1);
        let p: Vec<f64> = u.iter().map(|v| v / mass).collect();
        let at = [0.5, 10.0];
        let mut out = [0.0; 2];
        g.marginal(&p, 0, &at, &mut out);
        let exact = 1.0 / (2.0 * core::f64::consts::PI * v1).sqrt();
        assert!(
            (out[0] - exact).abs() < 1e-3 * exact,
            "{} vs {exact}",
            out[0]
        );
        assert_eq!(out[1], 0.0);
    }

    #[test]
    fn oversized_grids_are_refused_before_allocation() {
        let e = TensorGrid::new(&[(0.0, 1.0); 3], &[1000, 1000, 1000]).unwrap_err();
        assert!(alloc::format!("{e}").contains("exceeds the cap"), "{e}");
        assert!(TensorGrid::new(&[(0.0, 1.0)], &[2]).is_err());
    }

    /// The 2-D marginal of a 3-D Gaussian on the grid, sampled on a raster, is the 2-D
    /// Gaussian marginal: correct normalisation, shape and orientation of the axes.
    #[test]
    fn marginal_2d_of_a_gaussian() {
        let g = TensorGrid::new(&[(-4.0, 4.0), (-5.0, 5.0), (-3.0, 3.0)], &[79, 99, 29]).unwrap();
        let mut u = g.tabulate(|x| {
            (-(x[0] - 0.5).powi(2) / (2.0 * 0.6)
                - (x[1] + 1.0).powi(2) / (2.0 * 1.2)
                - x[2].powi(2))
            .exp()
        });
        let mass = g.mass(&u);
        u.iter_mut().for_each(|v| *v /= mass);
        let xs: Vec<f64> = (0..41).map(|i| -4.0 + 0.2 * i as f64).collect();
        let ys: Vec<f64> = (0..51).map(|i| -5.0 + 0.2 * i as f64).collect();
        let mut out = vec![0.0; xs.len() * ys.len()];
        g.marginal_2d(&u, (0, 1), &xs, &ys, &mut out);
        let mut worst = 0.0f64;
        for (j, y) in ys.iter().enumerate() {
            for (i, x) in xs.iter().enumerate() {
                let exact = (-(x - 0.5).powi(2) / 1.2 - (y + 1.0).powi(2) / 2.4).exp()
                    / (core::f64::consts::TAU * (0.6f64 * 1.2).sqrt());
                worst = worst.max((out[i + xs.len() * j] - exact).abs());
            }
        }
        assert!(worst < 2e-3, "largest error {worst}");
        let total: f64 = out.iter().sum::<f64>() * 0.2 * 0.2;
        assert!((total - 1.0).abs() < 1e-3, "{total}");
    }

    /// A grid past the node cap is the structured `TooLarge`, with the cap.
    #[test]
    fn a_grid_past_the_cap_is_too_large() {
        let e = TensorGrid::new(&[(0.0, 1.0), (0.0, 1.0)], &[100_000, 100_000]).unwrap_err();
        assert!(
            matches!(e, crate::error::ZakaiError::TooLarge { limit, unit: "nodes", .. } if limit == MAX_NODES),
            "{e:?}"
        );
        assert!(alloc::format!("{e}").contains("exceeds the cap"), "{e}");
    }
}
