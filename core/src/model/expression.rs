//! Functions from text: `f` and `h` typed as expressions in `x1..xn` (and `x` when n = 1),
//! read by the one front end ([`super::syntax`]) and compiled once (`model::compile`), with
//! exact partial derivatives computed symbolically on that tree at construction. Functions
//! without a derivative rule there (`abs`, `erf`, rounding, …) make the whole function fall
//! back to central differences, reported as [`Derivatives::Numerical`].

use alloc::string::{String, ToString};
use alloc::vec::Vec;

use super::compile::Expression;
use super::function::{
    numerical_hessian, numerical_jacobian, per_point, BatchScratch, Derivatives, FixedPrograms,
    VectorFunction,
};
use super::program::{Program, BLOCK, MAX_INPUTS};
use super::syntax::{ExprError, Syntax, Variables};

/// One scalar expression: its tree (for exact derivatives) and the compiled [`Program`]
/// every evaluation runs.
#[derive(Clone, Debug)]
struct Scalar {
    expr: Expression,
    program: Program,
}

impl Scalar {
    fn new(expr: Expression) -> Scalar {
        let program = expr.program(expr.root());
        Scalar { expr, program }
    }

    #[inline]
    fn eval(&self, x: &[f64]) -> f64 {
        self.program.eval(x)
    }

    /// ∂/∂x_j (`x` and `x1` are the same variable in one dimension): `Err` when some function
    /// has no exact derivative, `Ok(None)` when the expression does not depend on x_j.
    fn partial(&self, j: usize) -> Result<Option<Scalar>, ()> {
        self.expr.partial(j).ok_or(()).map(|d| d.map(Scalar::new))
    }
}

/// Exact derivative tables, or `None` when some operator has no symbolic derivative.
#[derive(Clone, Debug)]
struct ExactDerivatives {
    /// `jacobian[i * n + j]` = ∂g_i/∂x_j (None = identically zero).
    jacobian: Vec<Option<Scalar>>,
    /// `hessian[(i * n + j) * n + l]` = ∂²g_i/∂x_j∂x_l.
    hessian: Vec<Option<Scalar>>,
    /// The values and `jacobian` in one program ([`Expression::with_jacobian`]).
    with_jacobian: Program,
}

/// A [`VectorFunction`] given by text expressions.
#[derive(Clone, Debug)]
pub struct ExpressionFunction {
    n: usize,
    texts: Vec<String>,
    components: Vec<Scalar>,
    exact: Option<ExactDerivatives>,
}

/// The value of `text`, an expression in `names` (a scenario's parameters) and constants
/// alone, e.g. `sqrt(2*q)`; errors carry the position, like any expression's.
pub(crate) fn constant_value(text: &str, names: &[(String, f64)]) -> Result<f64, ExprError> {
    super::compile::Expression::constant_value(text, names)
}

/// Reads `text` as [`ExpressionFunction::parse`] reads one component, in `variables` (the state
/// and, for a log-density, the measurement), with `names` (a scenario's parameters) standing
/// for their values: every mistake, an unknown name among them, is reported at its position in
/// `text` as written.
pub(crate) fn check_in(
    text: &str,
    variables: &Variables,
    names: &[(String, f64)],
) -> Result<(), ExprError> {
    super::syntax::Syntax::parse_in(text, variables, names).map(|_| ())
}

impl ExpressionFunction {
    /// Parses one expression per output component, in the state variables of an
    /// `n`-dimensional model. `what` names the function in error messages ("drift f").
    pub fn parse(what: &str, texts: &[String], n: usize, m: usize) -> Result<Self, ExprError> {
        Self::parse_in(what, texts, &Variables::state(n), m)
    }

    /// As [`ExpressionFunction::parse`], in `variables`: the function's inputs are the state
    /// and then the other variables, in their order (a log-density `log p(z | x)` reads
    /// `[x, z]`).
    pub(crate) fn parse_in(
        what: &str,
        texts: &[String],
        variables: &Variables,
        m: usize,
    ) -> Result<Self, ExprError> {
        let n = variables.count();
        if texts.len() != m {
            return Err(ExprError::WrongComponentCount {
                what: what.to_string(),
                expected: m,
                found: texts.len(),
            });
        }
        let mut operations = 0;
        let components = texts
            .iter()
            .map(|t| {
                let (scalar, ops) = compile(t, variables)?;
                operations = operations.max(ops);
                Ok(scalar)
            })
            .collect::<Result<Vec<_>, ExprError>>()?;
        // Nested functions or quotients grow the derivative trees fast, and differentiation
        // recurses through them: beyond the budget the derivatives are numerical instead, so
        // that parsing never overflows a 2 MiB thread stack (found by fuzzing; the budget is
        // measured by the test
        // `deep_or_long_expressions_are_refused_or_handled_on_a_small_stack`).
        let exact = if operations <= MAX_SYMBOLIC_OPERATIONS {
            exact_derivatives(&components, n)
        } else {
            None
        };
        Ok(ExpressionFunction {
            n,
            texts: texts.to_vec(),
            components,
            exact,
        })
    }

    /// The expressions as given.
    pub fn texts(&self) -> &[String] {
        &self.texts
    }

    /// True when every component is affine in x (all second derivatives vanish
    /// symbolically or, with numerical derivatives, at the probe points given).
    pub fn is_affine(&self, probes: &[Vec<f64>]) -> bool {
        match &self.exact {
            Some(d) => d.hessian.iter().all(|h| match h {
                None => true,
                Some(s) => probes.iter().all(|p| s.eval(p) == 0.0),
            }),
            None => {
                let mut hess = alloc::vec![0.0; self.n * self.n];
                probes.iter().all(|p| {
                    (0..self.components.len()).all(|i| {
                        self.hessian(i, p, &mut hess);
                        hess.iter().all(|v| v.abs() < 1e-6)
                    })
                })
            }
        }
    }
}

/// Most operations (operators, functions and parentheses) in one component for which exact
/// symbolic derivatives are computed; larger expressions get numerical derivatives.
pub(crate) const MAX_SYMBOLIC_OPERATIONS: usize = 16;
/// Deepest parenthesis nesting for which exact symbolic derivatives are computed.
pub(crate) const MAX_SYMBOLIC_DEPTH: usize = 6;

/// The compiled expression and its symbolic cost: the number of operations (operators,
/// functions, parentheses), or `usize::MAX` when it nests deeper than [`MAX_SYMBOLIC_DEPTH`].
fn compile(text: &str, variables: &Variables) -> Result<(Scalar, usize), ExprError> {
    let syntax = Syntax::parse_in(text, variables, &[])?;
    let operations = if syntax.depth > MAX_SYMBOLIC_DEPTH {
        usize::MAX
    } else {
        syntax.operations
    };
    Ok((Scalar::new(Expression::from_syntax(&syntax)), operations))
}

fn exact_derivatives(components: &[Scalar], n: usize) -> Option<ExactDerivatives> {
    let mut jacobian = Vec::with_capacity(components.len() * n);
    let mut hessian = Vec::with_capacity(components.len() * n * n);
    for c in components {
        for j in 0..n {
            let d = c.partial(j).ok()?;
            for l in 0..n {
                hessian.push(match &d {
                    Some(dj) => dj.partial(l).ok()?,
                    None => None,
                });
            }
            jacobian.push(d);
        }
    }
    let expressions: Vec<&Expression> = components.iter().map(|c| &c.expr).collect();
    let with_jacobian = Expression::with_jacobian(&expressions, n)?;
    Some(ExactDerivatives {
        jacobian,
        hessian,
        with_jacobian,
    })
}

fn eval_table(table: &[Option<Scalar>], x: &[f64], out: &mut [f64]) {
    for (o, d) in out.iter_mut().zip(table) {
        *o = d.as_ref().map_or(0.0, |s| s.eval(x));
    }
}

/// Runs each program of `table` (None = identically zero) over the points (structure of
/// arrays, see [`VectorFunction::eval_batch`]) in blocks of [`BLOCK`] points; output r goes
/// to `out[r * k..(r + 1) * k]`.
fn eval_table_batch<'s>(
    table: impl Iterator<Item = Option<&'s Scalar>> + Clone,
    n: usize,
    points: &[f64],
    out: &mut [f64],
    scratch: &mut BatchScratch,
) {
    eval_programs_batch(
        table.map(|s| s.map(|s| &s.program)),
        n,
        points,
        out,
        scratch,
    )
}

/// Fewer points than this are evaluated one by one by [`eval_programs_batch`].
const FEW_POINTS: usize = 8;

/// [`VectorFunction::eval_batch`] of a table of programs (`None`: identically zero) over
/// points of `n` inputs.
pub(crate) fn eval_programs_batch<'s>(
    table: impl Iterator<Item = Option<&'s Program>> + Clone,
    n: usize,
    points: &[f64],
    out: &mut [f64],
    scratch: &mut BatchScratch,
) {
    let k = points.len() / n;
    if k < FEW_POINTS && n <= MAX_INPUTS {
        // A handful of points (a UKF's sigma points): point by point on scalars, the same
        // operations and bits ([`Program::eval`]) without a pass's setup per instruction.
        let mut x = [0.0; MAX_INPUTS];
        for p in 0..k {
            for (j, x) in x.iter_mut().take(n).enumerate() {
                *x = points[j * k + p];
            }
            for (r, s) in table.clone().enumerate() {
                out[r * k + p] = s.map_or(0.0, |s| s.eval(&x[..n]));
            }
        }
        return;
    }
    let registers = table
        .clone()
        .flatten()
        .map(|s| s.registers())
        .max()
        .unwrap_or(0);
    let registers = scratch.take(registers * BLOCK);
    let mut start = 0;
    while start < k {
        let lanes = BLOCK.min(k - start);
        let block = |j: usize| &points[j * k + start..j * k + start + lanes];
        let run = |inputs: &[&[f64]], registers: &mut [f64], out: &mut [f64]| {
            for (r, s) in table.clone().enumerate() {
                let o = &mut out[r * k + start..r * k + start + lanes];
                match s {
                    Some(s) => s.run(inputs, lanes, registers, o),
                    None => o.fill(0.0),
                }
            }
        };
        if n <= MAX_INPUTS {
            let mut inputs = [&[][..]; MAX_INPUTS];
            for (j, input) in inputs.iter_mut().take(n).enumerate() {
                *input = block(j);
            }
            run(&inputs[..n], registers, out);
        } else {
            let inputs: Vec<&[f64]> = (0..n).map(block).collect();
            run(&inputs, registers, out);
        }
        start += lanes;
    }
}

impl VectorFunction for ExpressionFunction {
    fn input_dim(&self) -> usize {
        self.n
    }
    fn output_dim(&self) -> usize {
        self.components.len()
    }
    #[inline]
    fn eval(&self, x: &[f64], out: &mut [f64]) {
        for (o, c) in out.iter_mut().zip(&self.components) {
            *o = c.eval(x);
        }
    }
    fn jacobian(&self, x: &[f64], out: &mut [f64]) {
        match &self.exact {
            Some(d) => eval_table(&d.jacobian, x, out),
            None => {
                let f = |y: &[f64], o: &mut [f64]| self.eval(y, o);
                numerical_jacobian(&f, self.n, self.components.len(), x, out)
            }
        }
    }
    fn eval_with_jacobian(&self, x: &[f64], value: &mut [f64], jacobian: &mut [f64]) {
        match &self.exact {
            Some(d) => {
                let m = value.len();
                d.with_jacobian.eval_all(x, |r, v| match r.checked_sub(m) {
                    None => value[r] = v,
                    Some(e) => jacobian[e] = v,
                })
            }
            None => {
                self.eval(x, value);
                self.jacobian(x, jacobian)
            }
        }
    }
    fn hessian(&self, i: usize, x: &[f64], out: &mut [f64]) {
        let nn = self.n * self.n;
        match &self.exact {
            Some(d) => eval_table(&d.hessian[i * nn..(i + 1) * nn], x, out),
            None => {
                let j = |y: &[f64], o: &mut [f64]| self.jacobian(y, o);
                numerical_hessian(&j, self.n, self.components.len(), i, x, out)
            }
        }
    }
    fn eval_batch(&self, points: &[f64], out: &mut [f64], scratch: &mut BatchScratch) {
        let table = self.components.iter().map(Some);
        eval_table_batch(table, self.n, points, out, scratch)
    }
    fn jacobian_batch(&self, points: &[f64], out: &mut [f64], scratch: &mut BatchScratch) {
        match &self.exact {
            Some(d) => eval_table_batch(
                d.jacobian.iter().map(Option::as_ref),
                self.n,
                points,
                out,
                scratch,
            ),
            None => {
                let outputs = self.n * self.components.len();
                per_point(self.n, outputs, points, out, scratch, |x, o| {
                    self.jacobian(x, o)
                })
            }
        }
    }
    fn expressions(&self) -> Option<&[String]> {
        Some(&self.texts)
    }
    fn with_inputs_fixed(&self, first: usize, values: &[f64]) -> Option<FixedPrograms> {
        Some(FixedPrograms(
            self.components
                .iter()
                .map(|c| c.program.with_inputs_fixed(first, values))
                .collect(),
        ))
    }
    fn derivatives(&self) -> Derivatives {
        if self.exact.is_some() {
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
    use alloc::vec;

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// A driven function with its time and input fixed: what reads only them is computed
    /// once (`8*cos(1.2*t)` leaves one addition per point besides the state's own
    /// operations), and every value, at points and in batches, is the driven function's at
    /// the point extended by the fixed values, bit for bit.
    #[test]
    fn fixed_inputs_are_folded_into_the_programs() {
        let variables = Variables::state(1).driven(Some(1));
        let texts = strings(&["x/2 + 25*x/(1 + x^2) + 8*cos(1.2*t) + u1*x"]);
        let driven = ExpressionFunction::parse_in("F", &texts, &variables, 1).unwrap();
        let (t, u) = (7.0, 0.3);
        let fixed = driven.with_inputs_fixed(1, &[t, u]).unwrap();
        let whole = driven.components[0].program.len();
        assert!(
            fixed.0[0].len() <= whole - 3,
            "{} of {whole} instructions",
            fixed.0[0].len()
        );
        let points: Vec<f64> = (0..600).map(|i| -12.0 + 0.04 * i as f64).collect();
        let mut batch = alloc::vec![0.0; points.len()];
        super::eval_programs_batch(
            fixed.0.iter().map(Some),
            1,
            &points,
            &mut batch,
            &mut BatchScratch::default(),
        );
        for (x, b) in points.iter().zip(&batch) {
            let want = driven.components[0].eval(&[*x, t, u]);
            assert_eq!(fixed.0[0].eval(&[*x]).to_bits(), want.to_bits(), "at {x}");
            assert_eq!(b.to_bits(), want.to_bits(), "batch at {x}");
        }
    }

    /// A batch of every size from 1 to 40 points — a few evaluated one by one, more in
    /// blocks — gives each point the bits of its own evaluation, for a 2-D range–bearing
    /// measurement function.
    #[test]
    fn batches_of_any_size_equal_points_to_the_last_bit() {
        let f = ExpressionFunction::parse(
            "h",
            &strings(&["sqrt(x1^2 + x2^2)", "atan(x2/x1) + exp(-x1)"]),
            2,
            2,
        )
        .unwrap();
        let mut scratch = BatchScratch::default();
        for k in 1..=40 {
            let xs: Vec<[f64; 2]> = (0..k)
                .map(|i| [1.0 + 0.37 * i as f64, -2.0 + 0.11 * (i * i) as f64])
                .collect();
            let points: Vec<f64> = (0..2).flat_map(|j| xs.iter().map(move |x| x[j])).collect();
            let mut out = vec![0.0; 2 * k];
            f.eval_batch(&points, &mut out, &mut scratch);
            for (p, x) in xs.iter().enumerate() {
                let want = f.value(x);
                for r in 0..2 {
                    assert_eq!(out[r * k + p].to_bits(), want[r].to_bits(), "{k} points");
                }
            }
        }
    }

    #[test]
    fn values_with_the_jacobian_equal_each_alone_to_the_last_bit() {
        // Shared subexpressions (x1^3, exp(-x1), the quotient), a constant and a zero
        // derivative, and a function without an exact derivative (erf: both numerical).
        for texts in [
            &["x1 - x1^3*x2", "exp(-x1)/(1 + x2^2) + sin(x1*x2)", "2.5"][..],
            &["x2 + erf(x1)", "x1*x2", "x1"][..],
        ] {
            let f = ExpressionFunction::parse("f", &strings(texts), 2, 3).unwrap();
            for x in [[0.3, -1.2], [-2.0, 0.7], [1e-3, 40.0]] {
                let (mut value, mut jacobian) = (vec![f64::NAN; 3], vec![f64::NAN; 6]);
                f.eval_with_jacobian(&x, &mut value, &mut jacobian);
                let mut alone = vec![0.0; 6];
                f.jacobian(&x, &mut alone);
                let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&value), bits(&f.value(&x)), "{texts:?} at {x:?}");
                assert_eq!(bits(&jacobian), bits(&alone), "{texts:?} at {x:?}");
            }
        }
    }

    #[test]
    fn values_and_exact_derivatives() {
        let f =
            ExpressionFunction::parse("drift f", &strings(&["-cos(x1)-sin(x2)", "x1^3*x2"]), 2, 2)
                .unwrap();
        assert_eq!(f.derivatives(), Derivatives::Exact);
        let x = [0.3, -1.2];
        let v = f.value(&x);
        assert!((v[0] - (-(0.3f64).cos() - (-1.2f64).sin())).abs() < 1e-14);
        let mut jac = vec![0.0; 4];
        f.jacobian(&x, &mut jac);
        assert!((jac[0] - (0.3f64).sin()).abs() < 1e-14);
        assert!((jac[1] + (-1.2f64).cos()).abs() < 1e-14);
        assert!((jac[2] - 3.0 * 0.09 * -1.2).abs() < 1e-13);
        assert!((jac[3] - 0.027).abs() < 1e-14);
        let mut hess = vec![0.0; 4];
        f.hessian(1, &x, &mut hess);
        assert!((hess[0] - 6.0 * 0.3 * -1.2).abs() < 1e-13);
        assert!((hess[1] - 3.0 * 0.09).abs() < 1e-13);
    }

    #[test]
    fn x_and_x1_are_the_same_variable_in_one_dimension() {
        let f = ExpressionFunction::parse("h", &strings(&["x*x1"]), 1, 1).unwrap();
        let mut jac = [0.0];
        f.jacobian(&[2.0], &mut jac);
        assert!((jac[0] - 4.0).abs() < 1e-14);
    }

    #[test]
    fn erf_falls_back_to_numerical_derivatives() {
        let f = ExpressionFunction::parse("f", &strings(&["erf(x)"]), 1, 1).unwrap();
        assert_eq!(f.derivatives(), Derivatives::Numerical);
        let mut jac = [0.0];
        f.jacobian(&[0.4], &mut jac);
        let exact = 2.0 / core::f64::consts::PI.sqrt() * (-0.16f64).exp();
        assert!((jac[0] - exact).abs() < 1e-8);
    }

    #[test]
    fn operator_precedence_follows_mathematical_convention() {
        let f = ExpressionFunction::parse("f", &strings(&["-x^2 + 2*x^3/4 - sin(pi/2)"]), 1, 1)
            .unwrap();
        let x = 1.5f64;
        let expected = -(x * x) + 2.0 * x.powi(3) / 4.0 - 1.0;
        assert!((f.value(&[x])[0] - expected).abs() < 1e-14);
        let g = ExpressionFunction::parse("g", &strings(&["exp(-(x-0.5)^2)"]), 1, 1).unwrap();
        assert!((g.value(&[1.5])[0] - (-1.0f64).exp()).abs() < 1e-15);
        let h = ExpressionFunction::parse("h", &strings(&["2*-x^2"]), 1, 1).unwrap();
        assert_eq!(h.value(&[3.0])[0], -18.0);
    }

    /// Batch values and Jacobians equal the point-wise ones to the last bit, over several
    /// blocks and a partial one, for exact and numerical derivatives.
    #[test]
    fn batches_equal_points_to_the_last_bit() {
        for (texts, n) in [
            (&["-cos(x1)-sin(x2)", "x1^3*x2"][..], 2),
            (&["x^3", "tanh(x)/(1+x^2)", "erf(x)"][..], 1),
        ] {
            let f = ExpressionFunction::parse("f", &strings(texts), n, texts.len()).unwrap();
            let m = texts.len();
            let k = 2 * BLOCK + 37;
            let points: Vec<f64> = (0..n * k)
                .map(|i| -2.5 + 5.0 * ((i as f64 * 0.7548) % 1.0))
                .collect();
            let mut values = vec![0.0; m * k];
            let mut jacobians = vec![0.0; m * n * k];
            let mut scratch = BatchScratch::default();
            f.eval_batch(&points, &mut values, &mut scratch);
            f.jacobian_batch(&points, &mut jacobians, &mut scratch);
            let (mut v, mut jac) = (vec![0.0; m], vec![0.0; m * n]);
            for p in 0..k {
                let x: Vec<f64> = (0..n).map(|j| points[j * k + p]).collect();
                f.eval(&x, &mut v);
                f.jacobian(&x, &mut jac);
                for i in 0..m {
                    assert_eq!(
                        values[i * k + p].to_bits(),
                        v[i].to_bits(),
                        "{texts:?} value {i} at {x:?}"
                    );
                }
                for e in 0..m * n {
                    assert_eq!(
                        jacobians[e * k + p].to_bits(),
                        jac[e].to_bits(),
                        "{texts:?} ∂ {e} at {x:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn wrong_component_count_is_reported() {
        let e = ExpressionFunction::parse("drift f", &strings(&["x1"]), 2, 2).unwrap_err();
        assert!(matches!(
            e,
            ExprError::WrongComponentCount {
                expected: 2,
                found: 1,
                ..
            }
        ));
    }

    #[test]
    fn affinity_is_detected() {
        let probes = vec![vec![0.5, -2.0], vec![3.0, 1.0]];
        let lin =
            ExpressionFunction::parse("f", &strings(&["-0.05*x1 + x2", "0.7*x1"]), 2, 2).unwrap();
        assert!(lin.is_affine(&probes));
        let nonlin = ExpressionFunction::parse("f", &strings(&["x1*x2", "0.7*x1"]), 2, 2).unwrap();
        assert!(!nonlin.is_affine(&probes));
    }
}
