//! Log-concavity of a grid density (003 §3): where the Hessian of `−log p` fails to be positive
//! semidefinite, as a map and a yes/no.
//!
//! `U = ∇²(−log p)` by central differences of `log p` on the grid (second differences along
//! each axis, the four-point mixed difference across two), its smallest eigenvalue per node
//! (closed form for 2 × 2). Only nodes whose whole stencil carries density above
//! `relative_floor · max p` are evaluated — far in the tails `log p` is round-off — and the
//! others are NaN in the map. The density is log-concave on the evaluated region when no
//! smallest eigenvalue is below `−tolerance`.

use alloc::vec;
use alloc::vec::Vec;

use crate::grid::DensityView;

/// The result of [`log_concavity`].
#[derive(Clone, Debug, PartialEq)]
pub struct LogConcavity {
    /// Smallest eigenvalue of `∇²(−log p)` per grid node (NaN where not evaluated), in the
    /// view's storage order.
    pub min_curvature: Vec<f64>,
    /// True when no evaluated node has a smallest eigenvalue below `−tolerance`.
    pub log_concave: bool,
    /// The node with the most negative smallest eigenvalue and that value, if any node was
    /// evaluated.
    pub worst: Option<(Vec<f64>, f64)>,
}

/// Log-concavity map of a 1-D or 2-D grid density (`None` for other dimensions). Grid nodes
/// are `lower + (i + 1) Δs` with `Δs = (upper − lower)/(N + 1)`, as on a
/// `TensorGrid`.
pub fn log_concavity(
    view: &DensityView,
    relative_floor: f64,
    tolerance: f64,
) -> Option<LogConcavity> {
    let dims = view.shape.len();
    if !(1..=2).contains(&dims) {
        return None;
    }
    let (n0, n1) = (view.shape[0], if dims == 2 { view.shape[1] } else { 1 });
    let spacing: Vec<f64> = view
        .bounds
        .iter()
        .zip(view.shape)
        .map(|(b, &n)| (b.1 - b.0) / (n + 1) as f64)
        .collect();
    let max = view.values.iter().copied().fold(0.0, f64::max);
    let floor = relative_floor * max;
    let log: Vec<f64> = view
        .values
        .iter()
        .map(|&v| {
            if v > floor && v > 0.0 {
                libm::log(v)
            } else {
                f64::NAN
            }
        })
        .collect();
    let at = |i: isize, j: isize| -> f64 {
        if i < 0 || j < 0 || i >= n0 as isize || j >= n1 as isize {
            f64::NAN
        } else {
            log[i as usize + n0 * j as usize]
        }
    };
    let mut map = vec![f64::NAN; view.values.len()];
    let mut worst: Option<(usize, f64)> = None;
    for j in 0..n1 as isize {
        for i in 0..n0 as isize {
            let c = at(i, j);
            let uxx = -(at(i + 1, j) - 2.0 * c + at(i - 1, j)) / (spacing[0] * spacing[0]);
            let value = if dims == 1 {
                uxx
            } else {
                let uyy = -(at(i, j + 1) - 2.0 * c + at(i, j - 1)) / (spacing[1] * spacing[1]);
                let uxy = -(at(i + 1, j + 1) - at(i + 1, j - 1) - at(i - 1, j + 1)
                    + at(i - 1, j - 1))
                    / (4.0 * spacing[0] * spacing[1]);
                let half = 0.5 * (uxx - uyy);
                0.5 * (uxx + uyy) - libm::sqrt(half * half + uxy * uxy)
            };
            if value.is_nan() {
                continue;
            }
            let idx = i as usize + n0 * j as usize;
            map[idx] = value;
            if worst.is_none_or(|(_, w)| value < w) {
                worst = Some((idx, value));
            }
        }
    }
    let worst = worst.map(|(idx, value)| {
        let point = (0..dims)
            .map(|d| {
                let k = if d == 0 { idx % n0 } else { idx / n0 };
                view.bounds[d].0 + (k + 1) as f64 * spacing[d]
            })
            .collect();
        (point, value)
    });
    Some(LogConcavity {
        log_concave: worst.as_ref().is_none_or(|w| w.1 >= -tolerance),
        min_curvature: map,
        worst,
    })
}
