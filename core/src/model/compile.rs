//! Compiling an expression's [`Syntax`] tree into a [`Program`], and its exact derivatives.
//!
//! The tree is read into an [`Expression`], a tree of operations (shared subtrees are one
//! node) in which operations on constants only are folded with the same functions, which
//! [`Expression::derivative`] differentiates symbolically by the rules in its doc and
//! [`Expression::program`] writes out in single assignment form (every node once). Every
//! operation applies the function of the syntax's tables (libm), so values agree bit for bit
//! natively and in wasm. The deliberate changes: `x^k` for an integer 0 ≤ k ≤ 4, recorded as
//! multiplications ([`Operation::PowI`], within 2 ulp of `libm::pow`), and three identities
//! that save a function or a division — `ln(e^u) = u`, `ln(c e^u) = ln c + u` (c > 0) and
//! `a / e^u = a e^{−u}` — exact in the reals, and within rounding of the written form (closer
//! where e^u would overflow: `ln(exp(800))` is 800, not ∞).

use alloc::vec::Vec;

use super::program::{Operand, Operation, Program, UnaryFn, MAX_POWI};
#[cfg(test)]
use super::syntax::ExprError;
use super::syntax::{Function, Node as Syntactic, Op, Syntax};

/// A node of an [`Expression`]; children are indices of earlier nodes.
#[derive(Clone, Copy, Debug)]
enum Node {
    Const(f64),
    Var(usize),
    Neg(usize),
    Unary(&'static str, UnaryFn, usize),
    Binary(Op, usize, usize),
}

/// A scalar expression as a tree of operations over the state variables (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Expression {
    nodes: Vec<Node>,
    root: usize,
}

/// Compiles a text in the state variables of an `n`-dimensional model.
#[cfg(test)]
pub(crate) fn compile(text: &str, n: usize) -> Result<Program, ExprError> {
    let e = Expression::parse(text, n)?;
    Ok(e.program(e.root()))
}

impl Expression {
    /// The operations of a syntax tree, constants folded.
    pub(crate) fn from_syntax(syntax: &Syntax) -> Expression {
        let mut e = Expression {
            nodes: Vec::new(),
            root: 0,
        };
        // Children come before their parents in both trees.
        let mut ids = Vec::with_capacity(syntax.nodes.len());
        for node in &syntax.nodes {
            let id = match *node {
                Syntactic::Number(v) => e.number(v),
                Syntactic::Variable(j) => e.push(Node::Var(j)),
                Syntactic::Negate(a) => e.negate(ids[a]),
                Syntactic::Call(f, a) => e.call(f.name, f.apply, ids[a]),
                Syntactic::Binary(op, a, b) => e.apply(op, ids[a], ids[b]),
            };
            ids.push(id);
        }
        e.root = ids[syntax.root];
        e
    }

    /// The value of `text`, an expression in `names` (a scenario's parameters) and constants
    /// alone — no state variable — folded as compilation folds constants.
    pub(crate) fn constant_value(
        text: &str,
        names: &[(alloc::string::String, f64)],
    ) -> Result<f64, crate::error::ExprError> {
        let e = Expression::from_syntax(&Syntax::parse_with(text, 0, names)?);
        // With no variable every node folds to a constant.
        Ok(e.constant(e.root()).unwrap_or(f64::NAN))
    }

    /// Reads `text` in the state variables of an `n`-dimensional model.
    #[cfg(test)]
    pub(crate) fn parse(text: &str, n: usize) -> Result<Expression, ExprError> {
        Ok(Expression::from_syntax(&Syntax::parse(text, n)?))
    }

    /// The node of the whole expression.
    pub(crate) fn root(&self) -> usize {
        self.root
    }

    /// The constant value of node `id`, if it is one.
    pub(crate) fn constant(&self, id: usize) -> Option<f64> {
        match self.nodes[id] {
            Node::Const(c) => Some(c),
            _ => None,
        }
    }

    fn push(&mut self, node: Node) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// `a op b`, folded with the operator's own function when both are constants (so that
    /// a folded constant has the bits evaluation would give).
    fn apply(&mut self, op: Op, a: usize, b: usize) -> usize {
        match (self.constant(a), self.constant(b)) {
            (Some(x), Some(y)) => self.push(Node::Const((op.apply())(x, y))),
            _ => match (op, self.nodes[b]) {
                // a / e^u = a e^{−u}: a product where a quotient was (the precision 1/s(x) of
                // a variance s = e^g).
                (Op::Div, Node::Unary("exp", f, u)) => {
                    let minus_u = self.negate(u);
                    let e = self.call("exp", f, minus_u);
                    match self.constant(a) {
                        Some(1.0) => e,
                        _ => self.push(Node::Binary(Op::Mul, a, e)),
                    }
                }
                _ => self.push(Node::Binary(op, a, b)),
            },
        }
    }

    fn negate(&mut self, a: usize) -> usize {
        match self.nodes[a] {
            Node::Const(c) => self.push(Node::Const(-c)),
            Node::Neg(u) => u,
            _ => self.push(Node::Neg(a)),
        }
    }

    fn call(&mut self, name: &'static str, f: UnaryFn, a: usize) -> usize {
        if let Some(c) = self.constant(a) {
            return self.push(Node::Const(f(c)));
        }
        // ln(e^u) = u and ln(c e^u) = ln c + u for a constant c > 0: the logarithm of an
        // exponential is its exponent, with no exp or ln to compute (the variance e^x of a
        // stochastic-volatility model, whose log-density reads ln s(x)).
        if matches!(name, "ln" | "log") {
            if let Some(u) = self.exponent_of(a) {
                return u;
            }
            if let Node::Binary(Op::Mul, x, y) = self.nodes[a] {
                for (c, e) in [(x, y), (y, x)] {
                    if let (Some(c), Some(u)) = (self.constant(c), self.exponent_of(e)) {
                        if c > 0.0 {
                            let ln_c = self.number(f(c));
                            return self.apply(Op::Add, ln_c, u);
                        }
                    }
                }
            }
        }
        self.push(Node::Unary(name, f, a))
    }

    /// u when node `id` is `exp(u)`.
    fn exponent_of(&self, id: usize) -> Option<usize> {
        match self.nodes[id] {
            Node::Unary("exp", _, u) => Some(u),
            _ => None,
        }
    }

    // Constructors of derivatives, which also drop zeros and unit factors.

    fn number(&mut self, c: f64) -> usize {
        self.push(Node::Const(c))
    }

    fn is(&self, id: usize, c: f64) -> bool {
        self.constant(id) == Some(c)
    }

    fn add(&mut self, a: usize, b: usize) -> usize {
        if self.is(a, 0.0) {
            return b;
        }
        if self.is(b, 0.0) {
            return a;
        }
        self.apply(Op::Add, a, b)
    }

    fn sub(&mut self, a: usize, b: usize) -> usize {
        if self.is(b, 0.0) {
            return a;
        }
        if self.is(a, 0.0) {
            return self.negate(b);
        }
        self.apply(Op::Sub, a, b)
    }

    fn mul(&mut self, a: usize, b: usize) -> usize {
        if self.is(a, 0.0) || self.is(b, 0.0) {
            return self.number(0.0);
        }
        if self.is(a, 1.0) {
            return b;
        }
        if self.is(b, 1.0) {
            return a;
        }
        self.apply(Op::Mul, a, b)
    }

    fn div(&mut self, a: usize, b: usize) -> usize {
        if self.is(a, 0.0) {
            return self.number(0.0);
        }
        if self.is(b, 1.0) {
            return a;
        }
        self.apply(Op::Div, a, b)
    }

    fn pow(&mut self, a: usize, k: f64) -> usize {
        if k == 1.0 {
            return a;
        }
        let k = self.number(k);
        self.apply(Op::Pow, a, k)
    }

    fn func(&mut self, name: &'static str, a: usize) -> usize {
        let f = Function::named(name).expect("a function of the language");
        self.call(f.name, f.apply, a)
    }

    /// ∂(node `id`)/∂x_j as a node, or `None` when the expression uses a function without a
    /// derivative here (`abs`, `signum`, rounding, `cbrt`, `erf`, `erfc`, `atan2`, `min`,
    /// `max`: the caller differentiates numerically). The rules, with u′ = ∂u/∂x_j:
    ///
    /// ```text
    /// (u ± v)′ = u′ ± v′     (u v)′ = u′ v + u v′      (u / v)′ = (u′ v − u v′) / v²
    /// (u^c)′ = c u^(c−1) u′  (u^v)′ = u^v (v′ ln u + v u′ / u)
    /// sin′ = cos   cos′ = −sin   tan′ = 1 + tan²   asin′ = 1/√(1−u²)  acos′ = −1/√(1−u²)
    /// atan′ = 1/(1+u²)   sinh′ = cosh   cosh′ = sinh   tanh′ = 1 − tanh²
    /// asinh′ = 1/√(u²+1)   acosh′ = 1/√(u²−1)   atanh′ = 1/(1−u²)
    /// exp′ = exp   sqrt′ = 1/(2√u)   ln′ = 1/u   log2′ = 1/(u ln 2)   log10′ = 1/(u ln 10)
    /// ```
    pub(crate) fn derivative(&mut self, id: usize, j: usize) -> Option<usize> {
        let mut memo = alloc::vec![None; self.nodes.len()];
        self.derive(id, j, &mut memo)
    }

    fn derive(&mut self, id: usize, j: usize, memo: &mut Vec<Option<usize>>) -> Option<usize> {
        if let Some(d) = memo[id] {
            return Some(d);
        }
        let d = match self.nodes[id] {
            Node::Const(_) => self.number(0.0),
            Node::Var(i) => self.number(if i == j { 1.0 } else { 0.0 }),
            Node::Neg(a) => {
                let da = self.derive(a, j, memo)?;
                if self.is(da, 0.0) {
                    da
                } else {
                    self.negate(da)
                }
            }
            Node::Binary(op, a, b) => {
                let (da, db) = (self.derive(a, j, memo)?, self.derive(b, j, memo)?);
                match op {
                    Op::Add => self.add(da, db),
                    Op::Sub => self.sub(da, db),
                    Op::Mul => {
                        let (x, y) = (self.mul(da, b), self.mul(a, db));
                        self.add(x, y)
                    }
                    Op::Div => {
                        let (x, y) = (self.mul(da, b), self.mul(a, db));
                        let (top, bottom) = (self.sub(x, y), self.mul(b, b));
                        self.div(top, bottom)
                    }
                    Op::Pow => match self.constant(b) {
                        Some(c) => {
                            let (c_node, power) = (self.number(c), self.pow(a, c - 1.0));
                            let scaled = self.mul(c_node, power);
                            self.mul(scaled, da)
                        }
                        None => {
                            let (ln_a, ratio) = (self.func("ln", a), self.div(da, a));
                            let (x, y) = (self.mul(db, ln_a), self.mul(b, ratio));
                            let sum = self.add(x, y);
                            self.mul(id, sum)
                        }
                    },
                }
            }
            Node::Unary(name, _, a) => {
                let da = self.derive(a, j, memo)?;
                if self.is(da, 0.0) {
                    da
                } else {
                    let outer = self.outer_derivative(name, a)?;
                    self.mul(outer, da)
                }
            }
        };
        memo.resize(self.nodes.len(), None);
        memo[id] = Some(d);
        Some(d)
    }

    /// f′(u) for a function f of the table applied to node `u`.
    fn outer_derivative(&mut self, name: &str, u: usize) -> Option<usize> {
        let one = self.number(1.0);
        let square = |e: &mut Expression| e.mul(u, u);
        Some(match name {
            "sin" => self.func("cos", u),
            "cos" => {
                let s = self.func("sin", u);
                self.negate(s)
            }
            "tan" => {
                let t = self.func("tan", u);
                let t2 = self.mul(t, t);
                self.add(one, t2)
            }
            "asin" | "acos" => {
                let u2 = square(self);
                let rest = self.sub(one, u2);
                let root = self.func("sqrt", rest);
                let d = self.div(one, root);
                if name == "asin" {
                    d
                } else {
                    self.negate(d)
                }
            }
            "atan" => {
                let u2 = square(self);
                let rest = self.add(one, u2);
                self.div(one, rest)
            }
            "sinh" => self.func("cosh", u),
            "cosh" => self.func("sinh", u),
            "tanh" => {
                let t = self.func("tanh", u);
                let t2 = self.mul(t, t);
                self.sub(one, t2)
            }
            "asinh" | "acosh" => {
                let u2 = square(self);
                let rest = if name == "asinh" {
                    self.add(u2, one)
                } else {
                    self.sub(u2, one)
                };
                let root = self.func("sqrt", rest);
                self.div(one, root)
            }
            "atanh" => {
                let u2 = square(self);
                let rest = self.sub(one, u2);
                self.div(one, rest)
            }
            "exp" => self.func("exp", u),
            "sqrt" => {
                let (two, root) = (self.number(2.0), self.func("sqrt", u));
                let bottom = self.mul(two, root);
                self.div(one, bottom)
            }
            "ln" | "log" => self.div(one, u),
            "log2" | "log10" => {
                let base = if name == "log2" {
                    core::f64::consts::LN_2
                } else {
                    core::f64::consts::LN_10
                };
                let base = self.number(base);
                let bottom = self.mul(u, base);
                self.div(one, bottom)
            }
            _ => return None,
        })
    }

    /// The program computing node `id` (each node reachable from it once), an integer power
    /// 0 ≤ k ≤ [`MAX_POWI`] as multiplications.
    pub(crate) fn program(&self, id: usize) -> Program {
        self.program_of(&[Some(id)])
    }

    /// One program whose results are nodes `ids` (`None`: zero), every node reachable from
    /// them computed once, with the operations [`Expression::program`] gives each alone (so
    /// the same bits).
    fn program_of(&self, ids: &[Option<usize>]) -> Program {
        let mut ssa = Vec::new();
        let mut done: Vec<Option<Operand>> = alloc::vec![None; self.nodes.len()];
        let results: Vec<Operand> = ids
            .iter()
            .map(|id| id.map_or(Operand::Const(0.0), |id| self.emit(id, &mut ssa, &mut done)))
            .collect();
        Program::from_ssa(&ssa, &results)
    }

    /// `components` (each a function of the n state variables) and their partial derivatives
    /// as one program ([`Program::eval_all`]): results `0..m` the values, then `m + i n + j` =
    /// ∂g_i/∂x_j — the table [`Expression::partial`] gives, without evaluating twice what a
    /// value and its derivatives share (`x³` and `3x²`, `e^u` and its derivative `e^u u′`).
    /// `None` when some function has no exact derivative.
    pub(crate) fn with_jacobian(components: &[&Expression], n: usize) -> Option<Program> {
        let mut all = Expression {
            nodes: Vec::new(),
            root: 0,
        };
        let roots: Vec<usize> = components.iter().map(|c| all.append(c)).collect();
        let mut ids: Vec<Option<usize>> = roots.iter().map(|&r| Some(r)).collect();
        for &root in &roots {
            for j in 0..n {
                let d = all.derivative(root, j)?;
                ids.push((!all.is(d, 0.0)).then_some(d));
            }
        }
        Some(all.program_of(&ids))
    }

    /// Appends the nodes of `other` (its node i becomes node `offset + i`); returns its root's
    /// new index.
    fn append(&mut self, other: &Expression) -> usize {
        let offset = self.nodes.len();
        self.nodes
            .extend(other.nodes.iter().map(|node| match *node {
                Node::Neg(a) => Node::Neg(a + offset),
                Node::Unary(name, f, a) => Node::Unary(name, f, a + offset),
                Node::Binary(op, a, b) => Node::Binary(op, a + offset, b + offset),
                leaf => leaf,
            }));
        offset + other.root
    }

    fn emit(&self, id: usize, ssa: &mut Vec<Operation>, done: &mut [Option<Operand>]) -> Operand {
        if let Some(o) = done[id] {
            return o;
        }
        let operation = match self.nodes[id] {
            Node::Const(c) => return Operand::Const(c),
            Node::Var(j) => return Operand::Var(j),
            Node::Neg(a) => Operation::Neg(self.emit(a, ssa, done)),
            Node::Unary(name, f, a) => {
                let a = self.emit(a, ssa, done);
                match name {
                    "exp" => Operation::Exp(a),
                    "ln" | "log" => Operation::Ln(a),
                    "abs" => Operation::Abs(a),
                    "atan" => Operation::Atan(a),
                    "sqrt" => Operation::Sqrt(a),
                    _ => Operation::Unary(f, a),
                }
            }
            Node::Binary(op, a, b) => {
                let (x, y) = (self.emit(a, ssa, done), self.emit(b, ssa, done));
                match op {
                    Op::Add => Operation::Add(x, y),
                    Op::Sub => Operation::Sub(x, y),
                    Op::Mul => Operation::Mul(x, y),
                    Op::Div => Operation::Div(x, y),
                    Op::Pow => match y {
                        Operand::Const(k)
                            if libm::trunc(k) == k && (0.0..=MAX_POWI as f64).contains(&k) =>
                        {
                            Operation::PowI(x, k as i32)
                        }
                        _ => Operation::Binary(op.apply(), x, y),
                    },
                }
            }
        };
        ssa.push(operation);
        let operand = Operand::Reg(ssa.len() - 1);
        done[id] = Some(operand);
        operand
    }

    /// ∂/∂x_j of the whole expression as an expression of its own: `None` when some function
    /// has no derivative here, `Some(None)` when it is identically zero.
    pub(crate) fn partial(&self, j: usize) -> Option<Option<Expression>> {
        let mut d = self.clone();
        let root = d.derivative(self.root, j)?;
        if d.is(root, 0.0) {
            return Some(None);
        }
        d.root = root;
        Some(Some(d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::syntax::{variable_index, CONSTANTS, FUNCTIONS};
    use crate::testing::test;
    use alloc::format;
    use alloc::vec;
    use exmex::prelude::*;
    use exmex::{FloatOpsFactory, MakeOperators, Operator};

    /// exmex 0.21's float operators with every function of the language (and `^`) computed
    /// by `libm`, as the syntax's tables compute them: the independent interpreter the
    /// programs are held against.
    #[derive(Clone, Debug)]
    struct LibmOps;

    impl MakeOperators<f64> for LibmOps {
        fn make<'a>() -> Vec<Operator<'a, f64>> {
            let libm_names = FUNCTIONS
                .iter()
                .filter(|f| !matches!(**f, "signum" | "fract"));
            let mut ops: Vec<Operator<'a, f64>> = FloatOpsFactory::<f64>::make()
                .into_iter()
                .filter(|op| op.repr() != "^" && !libm_names.clone().any(|f| *f == op.repr()))
                .collect();
            ops.push(Operator::make_bin(
                "^",
                exmex::BinOp {
                    apply: libm::pow,
                    prio: 4,
                    is_commutative: false,
                },
            ));
            for name in libm_names {
                let f = Function::named(name).unwrap();
                ops.push(Operator::make_unary(f.name, f.apply));
            }
            ops.push(Operator::make_constant("pi", core::f64::consts::PI));
            ops
        }
    }

    type Ex = FlatEx<f64, LibmOps>;

    fn ulps(a: f64, b: f64) -> u64 {
        if a == b || (a.is_nan() && b.is_nan()) {
            0
        } else {
            (a.to_bits() as i64).abs_diff(b.to_bits() as i64)
        }
    }

    /// Points spread over [−3, 3]ⁿ by a fixed low-discrepancy rule.
    fn points(n: usize, count: usize) -> Vec<Vec<f64>> {
        (0..count)
            .map(|i| {
                (0..n)
                    .map(|j| -3.0 + 6.0 * ((i as f64 * (0.618_034 + 0.414_214 * j as f64)) % 1.0))
                    .collect()
            })
            .collect()
    }

    /// The program of `text` against exmex's interpretation of `exmex_text`, the same
    /// expression written in exmex's conventions (a tight unary minus: `-x^2` is written
    /// `0-x^2`): within `max_ulp` ulp, or (when `relative` > 0) within
    /// `relative · max(1, |value|)` — an integer power's 2 ulp carried through later sums.
    fn agrees_with_exmex(text: &str, exmex_text: &str, n: usize, max_ulp: u64) {
        agrees_within(text, exmex_text, n, max_ulp, 0.0)
    }

    fn agrees_within(text: &str, exmex_text: &str, n: usize, max_ulp: u64, relative: f64) {
        let ex = Ex::parse(exmex_text).unwrap();
        let program = compile(text, n).unwrap();
        for x in points(n, 500) {
            let args: Vec<f64> = ex
                .var_names()
                .iter()
                .map(|v| x[variable_index(v, n).unwrap()])
                .collect();
            let expected = ex.eval(&args).unwrap();
            let got = program.eval(&x);
            assert!(
                ulps(expected, got) <= max_ulp
                    || (got - expected).abs() <= relative * expected.abs().max(1.0),
                "{text} at {x:?}: exmex {expected:e}, program {got:e}"
            );
        }
    }

    /// `ln(e^u) = u`, `ln(c e^u) = ln c + u` and `a / e^u = a e^{−u}` compile without the
    /// logarithm, the exponential or the division they save, and give the written form's
    /// values to a few ulp — and past e^u's overflow, where the written form gives ∞.
    #[test]
    fn logarithms_of_exponentials_and_quotients_by_them_are_rewritten() {
        let ln_exp = compile("ln(exp(x1 + 2*x2))", 2).unwrap();
        assert_eq!(ln_exp.len(), compile("x1 + 2*x2", 2).unwrap().len());
        let scaled = compile("log(3*exp(x1))", 1).unwrap();
        assert_eq!(scaled.len(), 1, "one addition");
        let reciprocal = compile("1/exp(x1)", 1).unwrap();
        assert_eq!(reciprocal.len(), 2, "a negation and an exponential");
        let quotient = compile("x2/exp(x1)", 2).unwrap();
        assert_eq!(
            quotient.len(),
            3,
            "a negation, an exponential and a product"
        );
        let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0);
        for x in points(2, 200) {
            assert_eq!(ln_exp.eval(&x), x[0] + 2.0 * x[1]);
            assert!(close(scaled.eval(&x), libm::log(3.0 * libm::exp(x[0]))));
            assert!(close(reciprocal.eval(&x), 1.0 / libm::exp(x[0])));
            assert!(close(quotient.eval(&x), x[1] / libm::exp(x[0])));
        }
        assert_eq!(compile("ln(exp(x1))", 1).unwrap().eval(&[800.0]), 800.0);
    }
    #[test]
    fn every_function_constant_and_operator_reads() {
        let texts = FUNCTIONS
            .iter()
            .map(|f| format!("{f}(x/4)"))
            .chain(CONSTANTS.iter().map(|c| format!("{c}*x")))
            .chain(["+", "-", "*", "/", "^"].map(|o| format!("x{o}0.3")));
        for text in texts {
            agrees_with_exmex(&text, &text, 1, 0);
        }
    }

    /// The program of a 1-D `text` against a closed form, within `relative · max(1, |value|)`.
    fn agrees_with_closed_form(text: &str, closed_form: impl Fn(f64) -> f64, relative: f64) {
        let program = compile(text, 1).unwrap();
        for x in points(1, 500) {
            let (expected, got) = (closed_form(x[0]), program.eval(&x));
            assert!(
                (got - expected).abs() <= relative * expected.abs().max(1.0),
                "{text} at {x:?}: closed form {expected:e}, program {got:e}"
            );
        }
    }

    /// More operands in one level than a 32-bit `usize` has bits, and heavy derivatives: held
    /// against closed forms (exmex's own evaluation miscounts there on 32-bit targets, wasm32,
    /// and panics under overflow checks).
    #[test]
    fn long_expressions_and_their_derivatives() {
        let sum = (0..70)
            .map(|i| format!("{i}.5*x"))
            .collect::<Vec<_>>()
            .join("+");
        // Σ_{i<70} (i + ½) = 70²/2.
        agrees_with_closed_form(&sum, |x| 2450.0 * x, 1e-14);
        // h = x (1 + x²)⁻⁴, h′ = (1 + x²)⁻⁴ − 8x²(1 + x²)⁻⁵, h″ = −24x(1 + x²)⁻⁵ + 80x³(1 + x²)⁻⁶.
        let h = Expression::parse(&format!("x{}", "/(1+x^2)".repeat(4)), 1).unwrap();
        let d = h.partial(0).unwrap().unwrap();
        let dd = d.partial(0).unwrap().unwrap();
        let q = |x: f64| 1.0 / (1.0 + x * x);
        let closed_forms: [&dyn Fn(f64) -> f64; 2] =
            [&|x| q(x).powi(4) - 8.0 * x * x * q(x).powi(5), &|x| {
                -24.0 * x * q(x).powi(5) + 80.0 * x.powi(3) * q(x).powi(6)
            }];
        for (e, closed_form) in [d, dd].iter().zip(closed_forms) {
            let program = e.program(e.root());
            assert!(program.len() > 20, "a long derivative: {}", program.len());
            for x in points(1, 500) {
                let (expected, got) = (closed_form(x[0]), program.eval(&x));
                assert!(
                    (got - expected).abs() <= 1e-13 * expected.abs().max(1.0),
                    "at {x:?}: closed form {expected:e}, program {got:e}"
                );
            }
        }
        assert!(compile(&format!("{}x{}", "(".repeat(2000), ")".repeat(2000)), 1).is_err());
        assert!(compile("x +", 1).is_err());
        assert!(compile("y", 1).is_err());
        assert!(compile("(x", 1).is_err());
    }

    /// Each pair: the expression as typed, and as exmex reads it with the same meaning.
    /// A program's value at one point (scalars, instruction by instruction) is its batch
    /// value at that point to the last bit, for every kind of operation: negation, functions
    /// (the vectorising exp, ln and abs among them), the four operations with constants on
    /// either side, integer powers and a binary function; 600 points in one batch (past the
    /// AVX-512 and AVX2 widths and a block) against one at a time.
    #[test]
    fn points_equal_batches_to_the_last_bit() {
        for (text, n) in [
            ("-x1 + exp(x2/3) - ln(1 + x1^2) * abs(x2) / 7", 2),
            ("x1^3 - 2/x2 + x2^4 + x1^0 + abs(x1)^1.5", 2),
            ("sin(x1)*cos(x2) + tanh(3 - x1) - sqrt(abs(x1*x2))", 2),
            ("exp(-(x-0.5)^2.5) + log(2 + x)", 1),
        ] {
            let program = compile(text, n).unwrap();
            let xs = points(n, 600);
            let columns: Vec<Vec<f64>> =
                (0..n).map(|j| xs.iter().map(|x| x[j]).collect()).collect();
            let inputs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
            let mut out = vec![0.0; xs.len()];
            let mut registers = vec![0.0; program.registers() * xs.len()];
            program.run(&inputs, xs.len(), &mut registers, &mut out);
            for (x, batch) in xs.iter().zip(&out) {
                let point = program.eval(x);
                assert!(
                    point.to_bits() == batch.to_bits() || (point.is_nan() && batch.is_nan()),
                    "{text} at {x:?}: point {point:e}, batch {batch:e}"
                );
            }
        }
    }

    #[test]
    fn programs_equal_exmex_to_the_last_bit() {
        for (text, exmex_text, n) in [
            ("-cos(x1)-sin(x2)", "0-cos(x1)-sin(x2)", 2),
            ("exp(-(x-0.5)^2.5)", "exp(0-(x-0.5)^2.5)", 1),
            (
                "2*-x/3 + atan(x/2) - 0.5*x",
                "2*(0-x)/3 + atan(x/2) - 0.5*x",
                1,
            ),
            (
                "tanh(x1)*x2 - 0.1*x1 + sqrt(abs(x2)) + erf(x1/2) + pi",
                "tanh(x1)*x2 - 0.1*x1 + sqrt(abs(x2)) + erf(x1/2) + pi",
                2,
            ),
            ("-0.4*x1 + 0.1*x2", "0-0.4*x1 + 0.1*x2", 2),
            ("x1*x2/(1+x1^1.5)", "x1*x2/(1+x1^1.5)", 2),
            (
                "signum(x)*fract(x) + log(1+x^0.5)",
                "signum(x)*fract(x) + log(1+x^0.5)",
                1,
            ),
            ("3", "3", 1),
            ("x", "x", 1),
            ("sin(2*pi/4)*x", "sin(2*pi/4)*x", 1),
            ("-x1^2", "0-x1^2", 2),
            ("exp(-(x1-1)^2)", "exp(0-(x1-1)^2)", 2),
            ("3*-x1^2.5", "3*(0-x1^2.5)", 2),
            ("x1/-sin(x2)^2.5*4", "x1/(0-sin(x2)^2.5)*4", 2),
            ("2^-x1", "2^-x1", 2),
            ("x1 - -x2", "x1-(0-x2)", 2),
            ("x + 1 + 2e-3", "x + 1 + 0.002", 1),
            ("x1 * x2 / 3 * 4 - 2 * 3", "x1 * x2 / 3 * 4 - 2 * 3", 2),
        ] {
            agrees_with_exmex(text, exmex_text, n, 0);
        }
    }

    #[test]
    fn integer_powers_within_two_ulp() {
        for (text, n) in [
            ("x^3", 1),
            ("x^2", 1),
            ("x1^4", 2),
            ("(x1 - x2)^3", 2),
            ("x^0", 1),
        ] {
            agrees_with_exmex(text, text, n, 2);
        }
        // Inside longer expressions the 2 ulp are carried through the sums: 1e-14 relative.
        for (text, exmex_text, n) in [
            (
                "-x^2 + 2*x^3/4 - sin(pi/2)",
                "0-x^2 + 2*x^3/4 - sin(pi/2)",
                1,
            ),
            ("x1^4 - x2^2 + x1^0", "x1^4 - x2^2 + x1^0", 2),
            ("(x1 - x2)^3 * cos(x1)^2", "(x1 - x2)^3 * cos(x1)^2", 2),
        ] {
            agrees_within(text, exmex_text, n, 2, 1e-14);
        }
    }

    /// Our derivatives against central differences of the program (step 1e-5: error ~1e-10
    /// × |f‴|; tolerance 1e-6 relative), including the sum under a square root whose exmex
    /// derivative drops the outer factor, and every function with a rule.
    #[test]
    fn exact_derivatives_agree_with_central_differences() {
        for (text, n) in [
            ("sqrt(x1^2+x2^2+1)", 2),
            ("sin(x1)*x2^2.5 - exp(-x1*x2) / (1 + x1^2)", 2),
            (
                "x1^x2 + tan(x1/3) - cos(x2)*sinh(x1/2) + cosh(x2/3)*tanh(x1)",
                2,
            ),
            (
                "asin(x/4) + acos(x/5) + atan(x) + asinh(x) + acosh(x^2+2) + atanh(x/4)",
                1,
            ),
            (
                "ln(x^2+1) + log(x^2+2) + log2(x^2+3) + log10(x^2+4) + sqrt(x^2+1)",
                1,
            ),
            ("-x^3 + 2/(x^2+1) - -x", 1),
        ] {
            let e = Expression::parse(text, n).unwrap();
            let f = e.program(e.root());
            for x in points(n, 40)
                .into_iter()
                .map(|p| p.iter().map(|v| v * 0.25 + 1.0).collect::<Vec<f64>>())
            {
                for j in 0..n {
                    let d = e.partial(j).unwrap();
                    let exact = d.as_ref().map_or(0.0, |d| d.program(d.root()).eval(&x));
                    let h = 1e-5;
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[j] += h;
                    xm[j] -= h;
                    let fd = (f.eval(&xp) - f.eval(&xm)) / (2.0 * h);
                    assert!(
                        (exact - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                        "{text} d/dx{j} at {x:?}: {exact} against {fd}"
                    );
                }
            }
        }
        // No rule: the caller falls back to numerical derivatives.
        for text in ["abs(x)", "erf(x)", "signum(x)*x", "floor(x)*x", "cbrt(x)"] {
            let e = Expression::parse(text, 1).unwrap();
            assert!(e.partial(0).is_none(), "{text}");
        }
        assert!(Expression::parse("3*x2", 2)
            .unwrap()
            .partial(0)
            .unwrap()
            .is_none());
    }

    #[test]
    fn constants_fold_and_results_can_be_variables() {
        let p = compile("2*3 + x - x", 1).unwrap();
        assert!(p.len() <= 2);
        assert_eq!(compile("4^0.5 * 2", 1).unwrap().constant(), Some(4.0));
        let bare = compile("x1", 2).unwrap();
        assert!(bare.is_empty());
        assert_eq!(bare.eval(&[7.0, 1.0]), 7.0);
        let second = compile("x2", 2).unwrap();
        assert_eq!(second.eval(&[7.0, 1.0]), 1.0);
        let mut out = vec![0.0; 3];
        let mut regs = vec![0.0; 0];
        second.run(
            &[&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0]],
            3,
            &mut regs,
            &mut out,
        );
        assert_eq!(out, [4.0, 5.0, 6.0]);
    }
}
