//! Vector-valued functions of the state with their derivatives.
//!
//! Drift `f: Rⁿ → Rⁿ` and observation `h: Rⁿ → Rᵐ` are both [`VectorFunction`]s. Methods need
//! values on whole grids (Yau–Yau solvers), Jacobians (EKF, IEKF, IOKF, div f in the
//! Kolmogorov operator (2) of 000) and second derivatives (Laplacians, ∇(div f), Hessians of
//! h for the MAP Newton steps of 003 (4.7)). Two sources implement the trait: Rust closures
//! ([`ClosureFunction`]) and text expressions (`expression::ExpressionFunction`, feature `std`).

use alloc::boxed::Box;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

/// How a function's derivatives are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Derivatives {
    /// Exact (symbolic derivatives of expressions, or closures supplied by the user).
    Exact,
    /// Central finite differences (used only where no exact derivative exists).
    Numerical,
}

/// A function `Rⁿ → Rᵐ` with first and second derivatives.
pub trait VectorFunction: Send + Sync {
    /// n, the number of inputs.
    fn input_dim(&self) -> usize;
    /// m, the number of outputs.
    fn output_dim(&self) -> usize;
    /// Writes `g(x)` into `out` (length m).
    fn eval(&self, x: &[f64], out: &mut [f64]);
    /// Writes the Jacobian, row-major: `out[i * n + j] = ∂g_i/∂x_j` (length m·n).
    fn jacobian(&self, x: &[f64], out: &mut [f64]);
    /// Writes `g(x)` into `value` and the Jacobian into `jacobian` (as
    /// [`VectorFunction::eval`] and [`VectorFunction::jacobian`], the same values): text
    /// expressions compute the two in one compiled program, what they share once.
    fn eval_with_jacobian(&self, x: &[f64], value: &mut [f64], jacobian: &mut [f64]) {
        self.eval(x, value);
        self.jacobian(x, jacobian);
    }
    /// Writes the Hessian of component `i`, row-major: `out[j * n + l] = ∂²g_i/∂x_j∂x_l`.
    fn hessian(&self, i: usize, x: &[f64], out: &mut [f64]);
    /// Whether derivatives are exact or numerical.
    fn derivatives(&self) -> Derivatives;

    /// The text expressions of the components, when the function was given as text (for
    /// symbolic checks, `model::symbolic`).
    fn expressions(&self) -> Option<&[String]> {
        None
    }

    /// The value as a new vector (convenience for non-hot paths).
    fn value(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.output_dim()];
        self.eval(x, &mut out);
        out
    }

    /// `g` at k points at once, structure of arrays: component j of point p is
    /// `points[j * k + p]` (k = `points.len() / n`), and component i of `g` at point p is
    /// written to `out[i * k + p]`. `scratch` is grown on first use and then reused, so
    /// repeated calls allocate nothing.
    ///
    /// Text expressions run their compiled programs one pass per operation over the batch;
    /// this default loops over the points with [`VectorFunction::eval`].
    fn eval_batch(&self, points: &[f64], out: &mut [f64], scratch: &mut BatchScratch) {
        let (n, m) = (self.input_dim(), self.output_dim());
        per_point(n, m, points, out, scratch, |x, o| self.eval(x, o));
    }

    /// The function with its inputs `first..` fixed to `values`, compiled for that (a driven
    /// model frozen for one step): text expressions fold what depends on the fixed inputs
    /// alone; `None` (the default) when the function has no such form, and then a frozen
    /// function appends the fixed values to every point instead.
    #[doc(hidden)]
    fn with_inputs_fixed(&self, _first: usize, _values: &[f64]) -> Option<FixedPrograms> {
        None
    }

    /// The Jacobian at k points at once (layout as [`VectorFunction::eval_batch`]): entry
    /// ∂g_i/∂x_j at point p is written to `out[(i * n + j) * k + p]`.
    fn jacobian_batch(&self, points: &[f64], out: &mut [f64], scratch: &mut BatchScratch) {
        let (n, m) = (self.input_dim(), self.output_dim());
        per_point(n, m * n, points, out, scratch, |x, o| self.jacobian(x, o));
    }
}

/// A function's compiled components with some inputs fixed
/// ([`VectorFunction::with_inputs_fixed`]); opaque.
#[doc(hidden)]
#[derive(Clone, Debug)]
pub struct FixedPrograms(pub(crate) Vec<super::program::Program>);

impl core::fmt::Debug for dyn VectorFunction {
    /// Its dimensions and, when it has them, its expressions (closures are opaque).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let mut d = f.debug_struct("VectorFunction");
        d.field("inputs", &self.input_dim())
            .field("outputs", &self.output_dim());
        match self.expressions() {
            Some(texts) => d.field("expressions", &texts).finish(),
            None => d.finish_non_exhaustive(),
        }
    }
}

/// Reusable working memory of batch evaluations ([`VectorFunction::eval_batch`]).
#[derive(Clone, Debug, Default)]
pub struct BatchScratch {
    values: Vec<f64>,
}

impl BatchScratch {
    /// At least `len` values (grown, never shrunk).
    pub fn take(&mut self, len: usize) -> &mut [f64] {
        if self.values.len() < len {
            self.values.resize(len, 0.0);
        }
        &mut self.values[..len]
    }
}

/// A batch evaluation by one call of `g(x, out)` per point: gathers each point from the
/// structure of arrays, scatters its `outputs` values.
pub(crate) fn per_point(
    n: usize,
    outputs: usize,
    points: &[f64],
    out: &mut [f64],
    scratch: &mut BatchScratch,
    g: impl Fn(&[f64], &mut [f64]),
) {
    let k = points.len() / n.max(1);
    let (x, value) = scratch.take(n + outputs).split_at_mut(n);
    for p in 0..k {
        for (j, v) in x.iter_mut().enumerate() {
            *v = points[j * k + p];
        }
        g(x, value);
        for (i, v) in value.iter().enumerate() {
            out[i * k + p] = *v;
        }
    }
}

/// Values a numerical derivative keeps on the stack (beyond, it allocates): the Jacobians
/// and Hessians of every model within the scenarios' dimension limits.
const STACK_VALUES: usize = 512;

/// `f` on `len` zeros: on the stack when `len` ≤ [`STACK_VALUES`] (so a filter's step through
/// a closure model's numerical derivatives allocates nothing), else on the heap.
fn with_scratch<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    if len <= STACK_VALUES {
        f(&mut [0.0; STACK_VALUES][..len])
    } else {
        f(&mut vec![0.0; len])
    }
}

/// Central differences of `g` (k outputs) at `x` along each of the n coordinates: calls
/// `take(j, g(x + h e_j), g(x − h e_j), h)` for every j, with the step h ∝ ε^(1/3) scaled to
/// |x_j| (error O(ε^(2/3))). The shifted points and values live on the stack.
fn central_differences(
    g: &dyn Fn(&[f64], &mut [f64]),
    n: usize,
    k: usize,
    x: &[f64],
    mut take: impl FnMut(usize, &[f64], &[f64], f64),
) {
    with_scratch(n + 2 * k, |buf| {
        let (xp, rest) = buf.split_at_mut(n);
        let (gp, gm) = rest.split_at_mut(k);
        xp.copy_from_slice(&x[..n]);
        for j in 0..n {
            let h = 6.0e-6 * libm::fmax(1.0, libm::fabs(x[j]));
            xp[j] = x[j] + h;
            g(xp, gp);
            xp[j] = x[j] - h;
            g(xp, gm);
            xp[j] = x[j];
            take(j, gp, gm, h);
        }
    })
}

/// Central-difference Jacobian of `eval` at `x` (step ∝ ε^(1/3), error O(ε^(2/3))).
pub(crate) fn numerical_jacobian(
    eval: &dyn Fn(&[f64], &mut [f64]),
    n: usize,
    m: usize,
    x: &[f64],
    out: &mut [f64],
) {
    central_differences(eval, n, m, x, |j, fp, fm, h| {
        for i in 0..m {
            out[i * n + j] = (fp[i] - fm[i]) / (2.0 * h);
        }
    })
}

/// Central-difference Hessian of component `i` built from a Jacobian (step ∝ ε^(1/3)).
pub(crate) fn numerical_hessian(
    jacobian: &dyn Fn(&[f64], &mut [f64]),
    n: usize,
    m: usize,
    i: usize,
    x: &[f64],
    out: &mut [f64],
) {
    central_differences(jacobian, n, m * n, x, |l, jp, jm, h| {
        for j in 0..n {
            out[j * n + l] = (jp[i * n + j] - jm[i * n + j]) / (2.0 * h);
        }
    });
    // Symmetrise: the exact Hessian is symmetric.
    for j in 0..n {
        for l in (j + 1)..n {
            let s = 0.5 * (out[j * n + l] + out[l * n + j]);
            out[j * n + l] = s;
            out[l * n + j] = s;
        }
    }
}

type Eval = Box<dyn Fn(&[f64], &mut [f64]) + Send + Sync>;

/// A [`VectorFunction`] from Rust closures: the value, optionally the Jacobian (otherwise
/// central differences are used and [`Derivatives::Numerical`] is reported).
pub struct ClosureFunction {
    n: usize,
    m: usize,
    value: Eval,
    jacobian: Option<Eval>,
}

impl core::fmt::Debug for ClosureFunction {
    /// Its dimensions and whether the Jacobian is given (the closures are opaque).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ClosureFunction")
            .field("n", &self.n)
            .field("m", &self.m)
            .field("jacobian_given", &self.jacobian.is_some())
            .finish_non_exhaustive()
    }
}

impl ClosureFunction {
    /// A function with `n` inputs and `m` outputs from its value closure.
    pub fn new(
        n: usize,
        m: usize,
        value: impl Fn(&[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        ClosureFunction {
            n,
            m,
            value: Box::new(value),
            jacobian: None,
        }
    }

    /// Supplies the exact Jacobian (row-major `m × n`).
    pub fn with_jacobian(
        mut self,
        jacobian: impl Fn(&[f64], &mut [f64]) + Send + Sync + 'static,
    ) -> Self {
        self.jacobian = Some(Box::new(jacobian));
        self
    }

    /// A linear map `x ↦ A x + b` with `A` row-major `m × n` (exact derivatives).
    pub fn affine(n: usize, m: usize, a: Vec<f64>, b: Vec<f64>) -> Self {
        let a2 = a.clone();
        ClosureFunction::new(n, m, move |x, out| {
            for i in 0..m {
                out[i] = b[i] + (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>();
            }
        })
        .with_jacobian(move |_, out| out.copy_from_slice(&a2))
    }
}

impl VectorFunction for ClosureFunction {
    fn input_dim(&self) -> usize {
        self.n
    }
    fn output_dim(&self) -> usize {
        self.m
    }
    fn eval(&self, x: &[f64], out: &mut [f64]) {
        (self.value)(x, out)
    }
    fn jacobian(&self, x: &[f64], out: &mut [f64]) {
        match &self.jacobian {
            Some(j) => j(x, out),
            None => numerical_jacobian(&*self.value, self.n, self.m, x, out),
        }
    }
    fn hessian(&self, i: usize, x: &[f64], out: &mut [f64]) {
        let jac = |y: &[f64], o: &mut [f64]| self.jacobian(y, o);
        numerical_hessian(&jac, self.n, self.m, i, x, out)
    }
    fn derivatives(&self) -> Derivatives {
        if self.jacobian.is_some() {
            Derivatives::Exact
        } else {
            Derivatives::Numerical
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn closures_get_a_batch_path_by_their_point_values() {
        let f = ClosureFunction::new(2, 2, |x, o| {
            o[0] = x[0] * x[1];
            o[1] = libm::sin(x[0]) - x[1];
        });
        let k = 5;
        let points: Vec<f64> = (0..2 * k).map(|i| 0.3 * i as f64 - 1.0).collect();
        let mut values = vec![0.0; 2 * k];
        let mut jac = vec![0.0; 4 * k];
        let mut scratch = BatchScratch::default();
        f.eval_batch(&points, &mut values, &mut scratch);
        f.jacobian_batch(&points, &mut jac, &mut scratch);
        for p in 0..k {
            let x = [points[p], points[k + p]];
            assert_eq!(values[p], x[0] * x[1]);
            assert_eq!(values[k + p], libm::sin(x[0]) - x[1]);
            let mut point_jac = [0.0; 4];
            f.jacobian(&x, &mut point_jac);
            for e in 0..4 {
                assert_eq!(jac[e * k + p], point_jac[e]);
            }
        }
    }
}
