//! Rows of a tall matrix that span a submatrix of nearly largest volume (`maxvol`: Goreinov,
//! Oseledets, Savostyanov, Tyrtyshnikov & Zamarashkin 2010, "How to find a good submatrix", in
//! *Matrix Methods: Theory, Algorithms and Applications*): the interpolation points of the
//! cross approximation.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

/// A row swap must grow the volume by this factor to be made.
const GROWTH: f64 = 1.05;

/// Most swaps tried.
const SWAPS: usize = 100;

/// `r` row indices of the `m × r` matrix `u` (`m ≥ r`) whose submatrix `Û` has a volume
/// `|det Û|` that no single row swap grows by more than [`GROWTH`]: every entry of `u Û⁻¹` is
/// then at most 1.05 in modulus, so the rows interpolate the others with bounded
/// coefficients — when the swaps stop for that reason; after [`SWAPS`] swaps, or at a
/// singular `Û`, the rows found so far are returned without that bound. Started from the pivots of Gaussian elimination with row pivoting; a
/// rank-deficient `u` gets its pivots where they can be found and unused rows after.
pub(super) fn maxvol(u: &DMatrix<f64>) -> Vec<usize> {
    let (m, r) = u.shape();
    debug_assert!(m >= r, "a tall matrix");
    let mut work = u.clone();
    let mut used = vec![false; m];
    let mut rows = Vec::with_capacity(r);
    for j in 0..r {
        let pick = (0..m)
            .filter(|&i| !used[i])
            .max_by(|&a, &b| libm::fabs(work[(a, j)]).total_cmp(&libm::fabs(work[(b, j)])))
            .expect("m ≥ r rows");
        used[pick] = true;
        rows.push(pick);
        let pivot = work[(pick, j)];
        if pivot == 0.0 {
            continue;
        }
        for i in (0..m).filter(|&i| !used[i]) {
            let factor = work[(i, j)] / pivot;
            if factor != 0.0 {
                for c in j..r {
                    work[(i, c)] -= factor * work[(pick, c)];
                }
            }
        }
    }
    for _ in 0..SWAPS {
        let Some(inverse) = u.select_rows(rows.iter()).try_inverse() else {
            break;
        };
        let b = u * inverse;
        let (mut best, mut at) = (0.0, (0, 0));
        for j in 0..r {
            for i in 0..m {
                let v = libm::fabs(b[(i, j)]);
                if v > best {
                    (best, at) = (v, (i, j));
                }
            }
        }
        if best <= GROWTH {
            break;
        }
        rows[at.1] = at.0;
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The chosen rows are distinct and interpolate every row with coefficients at most 1.05.
    #[test]
    fn chosen_rows_interpolate_with_bounded_coefficients() {
        let u = DMatrix::from_fn(40, 5, |i, j| {
            libm::cos((i * (j + 1)) as f64 * 0.37 + j as f64)
        });
        let rows = maxvol(&u);
        let mut sorted = rows.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 5);
        let b = &u * u.select_rows(rows.iter()).try_inverse().unwrap();
        assert!(b.amax() <= GROWTH + 1e-12, "{}", b.amax());
        for (j, &i) in rows.iter().enumerate() {
            assert!((b[(i, j)] - 1.0).abs() < 1e-12);
        }
    }
}
