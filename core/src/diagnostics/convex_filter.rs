//! The convex-filter conditions of 003 §3.1 checked for a model on its domain, each reported
//! with its name and, when it fails, the worst point.
//!
//! * Theorem 3.8 (continuous observations): f linear, `½hᵀS⁻¹h` convex and a log-concave
//!   initial density; the remaining condition, Definition 3.6 (admissible observations),
//!   depends on the observation path and is what the log-concavity map of a run's density
//!   shows.
//! * Theorem 3.2 (linear h = Hx, with a user-supplied potential Φ and symmetric J):
//!   1. `f = Lx + l − ∇Φ` (L, l read off f + ∇Φ, which must be affine),
//!   2. `Φ + xᵀJx` convex, 3. `u(0, x) − Φ − xᵀJx` convex with `u(0, ·) = −log σ₀`,
//!   4. `xᵀHᵀS⁻¹Hx − ΔΦ + |∇Φ|² + 4xᵀ(Jᵀ − Lᵀ)Jx` convex.
//!
//! "Convex" is decided numerically on a tensor grid of points inside the domain (11 per
//! dimension, at most 11⁴): the smallest eigenvalue of the Hessian must not fall below
//! `−10⁻⁶(1 + |largest eigenvalue|)`. Hessians of f, h and Φ are those of the expressions
//! (exact where the expressions allow it); the Hessians of `−log σ₀` and of condition 4's
//! function are central differences (tolerance `10⁻³` relative).

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::{fmt_point, interior_points, Condition, ConditionReport};
use crate::model::function::VectorFunction;
use crate::model::{Model, ObservationModel, Prior};

/// The evaluation points of the module doc: 11 per dimension up to 4 dimensions, else 3.
fn points(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    interior_points(bounds, if bounds.len() <= 4 { 11 } else { 3 })
}

fn min_max_eigen(m: &DMatrix<f64>) -> (f64, f64) {
    let e = m.clone().symmetric_eigenvalues();
    (e.min(), e.max())
}

/// Central-difference Hessian of a scalar function.
fn numeric_hessian(f: &dyn Fn(&[f64]) -> f64, x: &[f64], h: f64) -> DMatrix<f64> {
    let n = x.len();
    let mut p = x.to_vec();
    let mut at = |di: isize, i: usize, dj: isize, j: usize| {
        p.copy_from_slice(x);
        p[i] += di as f64 * h;
        p[j] += dj as f64 * h;
        f(&p)
    };
    DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            (at(1, i, 0, j) - 2.0 * at(0, i, 0, j) + at(-1, i, 0, j)) / (h * h)
        } else {
            (at(1, i, 1, j) - at(1, i, -1, j) - at(-1, i, 1, j) + at(-1, i, -1, j)) / (4.0 * h * h)
        }
    })
}

/// "Convex on the domain": the smallest Hessian eigenvalue over the points, with the worst
/// point; `relative` is the tolerance relative to the largest eigenvalue seen.
fn convex(
    name: &str,
    pts: &[Vec<f64>],
    relative: f64,
    hessian: &dyn Fn(&[f64]) -> Option<DMatrix<f64>>,
) -> Condition {
    let mut worst: Option<(f64, &Vec<f64>)> = None;
    let mut largest: f64 = 0.0;
    for x in pts {
        let Some(h) = hessian(x) else { continue };
        if h.iter().any(|v| !v.is_finite()) {
            continue;
        }
        let (lo, hi) = min_max_eigen(&h);
        largest = largest.max(hi.abs()).max(lo.abs());
        if worst.is_none_or(|w| lo < w.0) {
            worst = Some((lo, x));
        }
    }
    match worst {
        None => Condition {
            name: name.into(),
            holds: false,
            detail: "could not be evaluated anywhere on the domain".into(),
        },
        Some((lo, x)) => {
            let holds = lo >= -relative * (1.0 + largest);
            Condition {
                name: name.into(),
                holds,
                detail: format!(
                    "smallest Hessian eigenvalue {lo:.4e} at x = {}",
                    fmt_point(x)
                ),
            }
        }
    }
}

/// The Hessian of `−log σ₀` by central differences (None where σ₀ underflows).
fn prior_curvature(prior: &Prior, x: &[f64], h: f64) -> Option<DMatrix<f64>> {
    if prior.density(x) <= 1e-280 {
        return None;
    }
    Some(numeric_hessian(&|p| -libm::log(prior.density(p)), x, h))
}

fn step_size(bounds: &[(f64, f64)]) -> f64 {
    let width = bounds
        .iter()
        .map(|b| b.1 - b.0)
        .fold(0.0f64, f64::max)
        .max(1e-9);
    1e-3 * width
}

fn continuous_s_inv(model: &Model) -> Option<DMatrix<f64>> {
    match &model.observations {
        ObservationModel::Continuous { noise_cov } => noise_cov.clone().try_inverse(),
        ObservationModel::Discrete { .. } => None,
    }
}

fn linear_condition(name: &str, f: &dyn VectorFunction, pts: &[Vec<f64>]) -> Condition {
    let n = f.input_dim();
    let mut hess = vec![0.0; n * n];
    let mut worst = (0.0f64, 0usize, 0usize);
    for (p, x) in pts.iter().enumerate() {
        for i in 0..f.output_dim() {
            f.hessian(i, x, &mut hess);
            let size = hess.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if size > worst.0 {
                worst = (size, p, i);
            }
        }
    }
    Condition {
        name: name.into(),
        holds: worst.0 <= 1e-9,
        detail: if worst.0 <= 1e-9 {
            "all second derivatives vanish on the domain".into()
        } else {
            format!(
                "component {} has second derivative {:.4e} at x = {}",
                worst.2 + 1,
                worst.0,
                fmt_point(&pts[worst.1])
            )
        },
    }
}

fn not_continuous(theorem: &str) -> ConditionReport {
    ConditionReport {
        theorem: theorem.into(),
        conditions: vec![Condition {
            name: "continuous observations dy = h dt + dw".into(),
            holds: false,
            detail:
                "the model has discrete measurements; 003's theorems for them are not checked here"
                    .into(),
        }],
        note: None,
    }
}

/// Theorem 3.8: linear f, convex `½hᵀS⁻¹h`, log-concave σ₀ (Definition 3.6 depends on the
/// observations and is left to the density's log-concavity map).
pub fn theorem_3_8(model: &Model, prior: &Prior, bounds: &[(f64, f64)]) -> ConditionReport {
    let theorem = "Theorem 3.8 (linear f, convex ½hᵀS⁻¹h)";
    let Some(s_inv) = continuous_s_inv(model) else {
        return not_continuous(theorem);
    };
    let pts = points(bounds);
    let (n, m) = (model.n, model.m);
    let h_fn = &model.observation;
    let potential_hessian = |x: &[f64]| {
        let mut h = vec![0.0; m];
        let mut jac = vec![0.0; m * n];
        h_fn.eval(x, &mut h);
        h_fn.jacobian(x, &mut jac);
        let j = DMatrix::from_row_slice(m, n, &jac);
        let mut out = j.transpose() * &s_inv * &j;
        let mut second = vec![0.0; n * n];
        for a in 0..m {
            let w: f64 = (0..m).map(|b| s_inv[(a, b)] * h[b]).sum();
            h_fn.hessian(a, x, &mut second);
            out += DMatrix::from_row_slice(n, n, &second) * w;
        }
        Some(out)
    };
    let step = step_size(bounds);
    ConditionReport {
        theorem: theorem.into(),
        conditions: vec![
            linear_condition("f is linear", model.drift.as_ref(), &pts),
            convex("½hᵀS⁻¹h is convex", &pts, 1e-6, &potential_hessian),
            convex("the initial density is log-concave", &pts, 1e-3, &|x| {
                prior_curvature(prior, x, step)
            }),
        ],
        note: Some(
            "Definition 3.6 (admissible observations) depends on the observation path: check the run's density with the log-concavity map"
                .into(),
        ),
    }
}

/// Theorem 3.2 for linear h with the potential Φ (a scalar function of x) and symmetric J.
pub fn theorem_3_2(
    model: &Model,
    prior: &Prior,
    bounds: &[(f64, f64)],
    phi: &dyn VectorFunction,
    j: &DMatrix<f64>,
) -> ConditionReport {
    let theorem = "Theorem 3.2 (linear h, f = Lx + l − ∇Φ)";
    let Some(s_inv) = continuous_s_inv(model) else {
        return not_continuous(theorem);
    };
    let n = model.n;
    let pts = points(bounds);
    let step = step_size(bounds);
    let mut conditions = vec![linear_condition(
        "h is linear",
        model.observation.as_ref(),
        &pts,
    )];
    if phi.input_dim() != n || phi.output_dim() != 1 || j.shape() != (n, n) {
        conditions.push(Condition {
            name: "Φ: Rⁿ → R and J n × n".into(),
            holds: false,
            detail: format!(
                "Φ maps R^{} → R^{}, J is {} × {}; the model has n = {n}",
                phi.input_dim(),
                phi.output_dim(),
                j.nrows(),
                j.ncols()
            ),
        });
        return ConditionReport {
            theorem: theorem.into(),
            conditions,
            note: None,
        };
    }
    if (j - j.transpose()).amax() > 1e-12 {
        conditions.push(Condition {
            name: "J is symmetric".into(),
            holds: false,
            detail: "J ≠ Jᵀ".into(),
        });
    }
    let grad_phi = |x: &[f64]| {
        let mut g = vec![0.0; n];
        phi.jacobian(x, &mut g);
        g
    };
    let hess_phi = |x: &[f64]| {
        let mut h = vec![0.0; n * n];
        phi.hessian(0, x, &mut h);
        DMatrix::from_row_slice(n, n, &h)
    };
    // 1. f + ∇Φ affine: its Jacobian J_f + ∇²Φ is the same everywhere; L is that matrix.
    let affine_jacobian = |x: &[f64]| {
        let mut jac = vec![0.0; n * n];
        model.drift.jacobian(x, &mut jac);
        DMatrix::from_row_slice(n, n, &jac) + hess_phi(x)
    };
    let l = affine_jacobian(&pts[0]);
    let (deviation, at) = pts
        .iter()
        .map(|x| ((affine_jacobian(x) - &l).amax(), x))
        .fold((0.0, &pts[0]), |a, b| if b.0 > a.0 { b } else { a });
    let scale = 1.0 + l.amax();
    conditions.push(Condition {
        name: "1. f = Lx + l − ∇Φ".into(),
        holds: deviation <= 1e-6 * scale,
        detail: if deviation <= 1e-6 * scale {
            format!("L = {:?} (row-major)", l.transpose().as_slice())
        } else {
            format!(
                "f + ∇Φ is not affine: its Jacobian varies by {deviation:.4e} at x = {}",
                fmt_point(at)
            )
        },
    });
    conditions.push(convex("2. Φ + xᵀJx is convex", &pts, 1e-6, &|x| {
        Some(hess_phi(x) + j * 2.0)
    }));
    conditions.push(convex(
        "3. u(0, x) − Φ − xᵀJx is convex (u(0, ·) = −log σ₀)",
        &pts,
        1e-3,
        &|x| prior_curvature(prior, x, step).map(|u| u - hess_phi(x) - j * 2.0),
    ));
    // 4. with H from h's (constant) Jacobian.
    let mut hjac = vec![0.0; model.m * n];
    model.observation.jacobian(&pts[0], &mut hjac);
    let h = DMatrix::from_row_slice(model.m, n, &hjac);
    let hsh = h.transpose() * &s_inv * &h;
    let jl = (j.transpose() - l.transpose()) * j * 4.0;
    let g = |x: &[f64]| {
        let v = nalgebra::DVector::from_column_slice(x);
        let grad = grad_phi(x);
        let laplacian = hess_phi(x).trace();
        (v.transpose() * &hsh * &v)[(0, 0)] - laplacian
            + grad.iter().map(|a| a * a).sum::<f64>()
            + (v.transpose() * &jl * &v)[(0, 0)]
    };
    conditions.push(convex(
        "4. xᵀHᵀS⁻¹Hx − ΔΦ + |∇Φ|² + 4xᵀ(Jᵀ − Lᵀ)Jx is convex",
        &pts,
        1e-3,
        &|x| Some(numeric_hessian(&g, x, step)),
    ));
    ConditionReport {
        theorem: theorem.into(),
        conditions,
        note: None,
    }
}
