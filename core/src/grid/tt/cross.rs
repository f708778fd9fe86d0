//! TT-cross: a tensor in TT format from its values at entries the algorithm chooses — the
//! two-site (DMRG) cross interpolation of Savostyanov & Oseledets 2011 ("Fast adaptive
//! interpolation of multi-dimensional arrays in tensor train format", Proc. 7th Int. Workshop
//! on Multidimensional Systems), built on Oseledets & Tyrtyshnikov 2010 ("TT-cross
//! approximation for multidimensional arrays", Linear Algebra Appl. 432).
//!
//! Each dimension k keeps nested sets of left indices `I_k` (multi-indices of the dimensions
//! before k) and right indices `J_k` (of the dimensions from k on). A sweep visits the pairs
//! (k, k + 1) and evaluates the function on the *supercore* `I_k × n_k × n_{k+1} × J_{k+2}`,
//! an `(r_k n_k) × (n_{k+1} r_{k+2})` matrix; its truncated SVD `U Σ Vᵀ` (within ε‖M‖_F, at
//! most the rank cap) gives the new rank, and the rows of U of nearly largest volume
//! ([`super::maxvol`]) the next left set — going back, V's give the right sets. The cores
//! are the interpolation `U Û⁻¹` of the truncated `U Σ Vᵀ`: the tensor equals the function on
//! the entries the last sweep evaluated up to that truncation (exactly where nothing was
//! truncated). Sweeps alternate in direction until two consecutive
//! approximations agree within ε (relative, Frobenius).
//!
//! Cost: `Σ_k r_k n_k n_{k+1} r_{k+2}` evaluations per sweep, and an SVD of each supercore.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::maxvol::maxvol;
use super::svd::{sorted_svd, truncated_svd};
use super::TensorTrain;

/// Points evaluated per call of the function.
const BATCH: usize = 8192;

/// What the cross approximation aims at.
#[derive(Clone, Debug)]
pub(crate) struct CrossOptions {
    /// Relative accuracy of each supercore's truncation and of the stopping test.
    pub eps: f64,
    /// The largest rank.
    pub max_rank: usize,
    /// The most sweeps (each one direction).
    pub max_sweeps: usize,
    /// Multi-indices where the function is not small (where its mass is): the first right
    /// index sets are read from them. At least one; more make the start richer.
    pub start: Vec<Vec<usize>>,
}

/// How the cross approximation went.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct CrossReport {
    /// Entries evaluated.
    pub evaluations: usize,
    /// Sweeps made.
    pub sweeps: usize,
    /// Whether the last two sweeps agreed within ε (else `max_sweeps` stopped it).
    pub converged: bool,
    /// The largest |value| met.
    pub largest: f64,
    /// Whether a rank reached the cap.
    pub capped: bool,
}

/// The sets of multi-indices a sweep reads and writes.
struct IndexSets {
    /// `left[k]`: multi-indices of dimensions `0..k`.
    left: Vec<Vec<Vec<usize>>>,
    /// `right[k]`: multi-indices of dimensions `k..d`.
    right: Vec<Vec<Vec<usize>>>,
}

/// The function on the supercore of the pair (k, k + 1): rows `α + r_k i`, columns
/// `j + n_{k+1} β`.
fn supercore<E>(
    shape: &[usize],
    sets: &IndexSets,
    k: usize,
    eval: &mut impl FnMut(&[usize], &mut [f64]) -> Result<(), E>,
    report: &mut CrossReport,
) -> Result<DMatrix<f64>, E> {
    let d = shape.len();
    let (left, right) = (&sets.left[k], &sets.right[k + 2]);
    let (n1, n2) = (shape[k], shape[k + 1]);
    let (rows, cols) = (left.len() * n1, n2 * right.len());
    let total = rows * cols;
    let mut values = vec![0.0; total];
    let mut points = Vec::with_capacity(BATCH.min(total) * d);
    let mut start = 0;
    while start < total {
        let end = (start + BATCH).min(total);
        points.clear();
        for flat in start..end {
            let (row, col) = (flat % rows, flat / rows);
            let (alpha, i) = (row % left.len(), row / left.len());
            let (j, beta) = (col % n2, col / n2);
            points.extend_from_slice(&left[alpha]);
            points.push(i);
            points.push(j);
            points.extend_from_slice(&right[beta]);
        }
        eval(&points, &mut values[start..end])?;
        start = end;
    }
    report.evaluations += total;
    report.largest = values
        .iter()
        .fold(report.largest, |m, v| m.max(libm::fabs(*v)));
    Ok(DMatrix::from_vec(rows, cols, values))
}

/// The truncated SVD of a supercore: `(U_r, s_r, V_rᵀ)` within `eps ‖M‖_F`, rank at most
/// `cap`.
fn truncated(m: DMatrix<f64>, eps: f64, cap: usize) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let (u, s, vt, _) = truncated_svd(&m, eps * m.norm(), cap);
    (u, s, vt)
}

/// `a b⁻¹` for a square `b` (the interpolation of the other rows by the chosen ones); a
/// singular `b` (a function that is zero on a whole supercore) by its pseudo-inverse.
fn times_inverse(a: &DMatrix<f64>, b: DMatrix<f64>) -> DMatrix<f64> {
    match b.clone().try_inverse() {
        Some(inv) => a * inv,
        None => {
            let (u, s, vt) = sorted_svd(b);
            let top = s.first().copied().unwrap_or(0.0);
            let inv_s = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                s.len(),
                s.iter()
                    .map(|&v| if v > 1e-14 * top { 1.0 / v } else { 0.0 }),
            ));
            a * vt.transpose() * inv_s * u.transpose()
        }
    }
}

/// The TT approximation of the function `eval` on the grid of `shape` by two-site cross
/// interpolation (module doc). `eval(points, out)` writes the values at `out.len()`
/// multi-indices, `points` holding them one after the other (d numbers each); its error
/// stops the approximation.
pub(crate) fn cross<E>(
    shape: &[usize],
    mut eval: impl FnMut(&[usize], &mut [f64]) -> Result<(), E>,
    options: &CrossOptions,
) -> Result<(TensorTrain, CrossReport), E> {
    let d = shape.len();
    let mut report = CrossReport::default();
    if d == 1 {
        let points: Vec<usize> = (0..shape[0]).collect();
        let mut values = vec![0.0; shape[0]];
        eval(&points, &mut values)?;
        report.evaluations = shape[0];
        report.largest = values.iter().fold(0.0, |m, v| m.max(libm::fabs(*v)));
        report.converged = true;
        return Ok((TensorTrain::rank_one(&[values]), report));
    }
    let cap = options.max_rank.max(1);
    let mut sets = IndexSets {
        left: vec![Vec::new(); d + 1],
        right: vec![Vec::new(); d + 1],
    };
    sets.left[0] = vec![Vec::new()];
    sets.right[d] = vec![Vec::new()];
    for k in 1..d {
        let mut suffixes: Vec<Vec<usize>> = options.start.iter().map(|p| p[k..].to_vec()).collect();
        suffixes.sort_unstable();
        suffixes.dedup();
        suffixes.truncate(cap);
        sets.right[k] = suffixes;
    }
    let mut previous: Option<TensorTrain> = None;
    let mut cores: Vec<Vec<f64>> = vec![Vec::new(); d];
    let mut ranks = vec![1; d + 1];
    for sweep in 0..options.max_sweeps.max(2) {
        let forward = sweep % 2 == 0;
        if forward {
            for k in 0..d - 1 {
                let m = supercore(shape, &sets, k, &mut eval, &mut report)?;
                let r_left = sets.left[k].len();
                let (u, s, vt) = truncated(m, options.eps, cap);
                let r = s.len();
                report.capped |= r == cap && r < u.nrows().min(vt.ncols());
                let chosen = maxvol(&u);
                let u_hat = u.select_rows(chosen.iter());
                cores[k] = times_inverse(&u, u_hat.clone()).as_slice().to_vec();
                ranks[k + 1] = r;
                sets.left[k + 1] = chosen
                    .iter()
                    .map(|&row| {
                        let mut idx = sets.left[k][row % r_left].clone();
                        idx.push(row / r_left);
                        idx
                    })
                    .collect();
                if k == d - 2 {
                    let mut last = u_hat;
                    for (j, mut column) in last.column_iter_mut().enumerate() {
                        column *= s[j];
                    }
                    cores[d - 1] = (last * vt).as_slice().to_vec();
                }
            }
        } else {
            for k in (0..d - 1).rev() {
                let m = supercore(shape, &sets, k, &mut eval, &mut report)?;
                let n2 = shape[k + 1];
                let (u, s, vt) = truncated(m, options.eps, cap);
                let r = s.len();
                report.capped |= r == cap && r < u.nrows().min(vt.ncols());
                let v = vt.transpose();
                let chosen = maxvol(&v);
                let v_hat = v.select_rows(chosen.iter());
                cores[k + 1] = times_inverse(&v, v_hat.clone())
                    .transpose()
                    .as_slice()
                    .to_vec();
                ranks[k + 1] = r;
                sets.right[k + 1] = chosen
                    .iter()
                    .map(|&col| {
                        let mut idx = vec![col % n2];
                        idx.extend_from_slice(&sets.right[k + 2][col / n2]);
                        idx
                    })
                    .collect();
                if k == 0 {
                    let mut first = u;
                    for (j, mut column) in first.column_iter_mut().enumerate() {
                        column *= s[j];
                    }
                    cores[0] = (first * v_hat.transpose()).as_slice().to_vec();
                }
            }
        }
        report.sweeps = sweep + 1;
        let tt = TensorTrain::of_cores(shape.to_vec(), ranks.clone(), cores.clone());
        if let Some(before) = &previous {
            let mut difference = tt.add(&before.scaled(-1.0));
            difference.round(1e-3, usize::MAX);
            if difference.norm() <= options.eps * tt.norm() {
                report.converged = true;
                return Ok((tt, report));
            }
        }
        previous = Some(tt);
    }
    Ok((previous.expect("at least two sweeps"), report))
}
