//! Compiling a text expression into a [`Program`], and its exact derivatives.
//!
//! The texts compiled here are the ones exmex accepts: a user's expression after
//! `normalize_expression`, or the unparsed text of an exmex derivative. They are read with
//! exmex's own conventions, so that a program computes exactly what exmex's interpretation
//! of the same text computes:
//!
//! * prefix operators (signs and functions such as `sin`) bind to the operand right after
//!   them, tighter than any binary operator (`-x^2` is `(-x)^2`; the user's text has been
//!   rewritten by `normalize_expression` so that this reading is the usual one);
//! * binary operators are applied by descending exmex priority (`^` 4, `/` 3, `*` 2, `-` 1,
//!   `+` 0), left to right among equals, and a commutative operator between two literal
//!   numbers first among its equals, as exmex orders them;
//! * `atan2(a, b)`, `min(a, b)`, `max(a, b)` are binary operators in call syntax;
//! * every operator applies the function of [`ZakaiOps`]' table (libm), so values agree
//!   bit for bit natively and in wasm.
//!
//! Operations on constants only are folded with the same functions. The one deliberate change
//! is `x^k` for an integer 0 ≤ k ≤ 4, recorded as multiplications ([`Operation::PowI`],
//! within 2 ulp of `libm::pow`).
//!
//! The text is read into an [`Expression`], a tree of operations (shared subtrees are one
//! node), which [`Expression::derivative`] differentiates symbolically by the rules in its doc
//! and [`Expression::program`] writes out in single assignment form (every node once).
//!
//! exmex itself is not used to evaluate or to differentiate: its evaluation of a flat
//! expression longer than the bits of a `usize` miscounts on 32-bit targets (wasm), which made
//! heavy derivatives panic in the playground, and its symbolic derivative of some sums inside
//! a function drops the outer factor (∂/∂x₁ √(x₁² + x₂² + 1) came out as 2x₁).

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use exmex::{MakeOperators, Operator};

use super::expression::ZakaiOps;
use super::expression_error::variable_index;
use super::program::{BinaryFn, Operand, Operation, Program, UnaryFn, MAX_POWI};

/// Deepest nesting of parentheses and prefix operators read (exmex's derivatives of the
/// longest accepted expressions stay far below it).
const MAX_DEPTH: usize = 1000;

/// A binary operator: its symbol or name, function, exmex priority and commutativity.
#[derive(Clone, Copy, Debug)]
struct Binary {
    symbol: &'static str,
    apply: BinaryFn,
    prio: i64,
    commutative: bool,
}

/// A node of an [`Expression`]; children are indices of earlier nodes.
#[derive(Clone, Copy, Debug)]
enum Node {
    Const(f64),
    Var(usize),
    Neg(usize),
    Unary(&'static str, UnaryFn, usize),
    Binary(Binary, usize, usize),
}

/// A scalar expression as a tree of operations over the state variables (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Expression {
    nodes: Vec<Node>,
    root: usize,
    table: Vec<Operator<'static, f64>>,
}

/// Compiles a text exmex accepts (a normalised user expression) in the state variables of an
/// `n`-dimensional model.
#[cfg(test)]
pub(crate) fn compile(text: &str, n: usize) -> Result<Program, String> {
    let e = Expression::parse(text, n)?;
    Ok(e.program(e.root()))
}

impl Expression {
    /// Reads `text` in the state variables of an `n`-dimensional model.
    pub(crate) fn parse(text: &str, n: usize) -> Result<Expression, String> {
        let mut e = Expression {
            nodes: Vec::new(),
            root: 0,
            table: ZakaiOps::make(),
        };
        let mut reader = Reader {
            text,
            pos: 0,
            n,
            depth: 0,
            e: &mut e,
        };
        let root = reader.expression()?;
        reader.skip_spaces();
        if reader.pos < text.len() {
            return Err(reader.unexpected());
        }
        e.root = root.node;
        Ok(e)
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

    fn operator(&self, repr: &str) -> Option<&Operator<'static, f64>> {
        self.table.iter().find(|op| op.repr() == repr)
    }

    fn binary(&self, repr: &str) -> Option<Binary> {
        let op = self.operator(repr)?;
        let b = op.bin().ok()?;
        Some(Binary {
            symbol: op.repr(),
            apply: b.apply,
            prio: b.prio,
            commutative: b.is_commutative,
        })
    }

    fn unary_fn(&self, name: &str) -> UnaryFn {
        self.operator(name)
            .and_then(|op| op.unary().ok())
            .expect("a function of the operator table")
    }

    /// `a op b`, folded with the operator's own function when both are constants (so that
    /// a folded constant has exmex's bits).
    fn apply(&mut self, op: Binary, a: usize, b: usize) -> usize {
        match (self.constant(a), self.constant(b)) {
            (Some(x), Some(y)) => self.push(Node::Const((op.apply)(x, y))),
            _ => self.push(Node::Binary(op, a, b)),
        }
    }

    fn negate(&mut self, a: usize) -> usize {
        match self.nodes[a] {
            Node::Const(c) => self.push(Node::Const(-c)),
            _ => self.push(Node::Neg(a)),
        }
    }

    fn call(&mut self, name: &'static str, f: UnaryFn, a: usize) -> usize {
        match self.constant(a) {
            Some(c) => self.push(Node::Const(f(c))),
            None => self.push(Node::Unary(name, f, a)),
        }
    }

    // Constructors of derivatives, which also drop zeros and unit factors.

    fn number(&mut self, c: f64) -> usize {
        self.push(Node::Const(c))
    }

    fn is(&self, id: usize, c: f64) -> bool {
        self.constant(id) == Some(c)
    }

    fn op(&self, symbol: &str) -> Binary {
        self.binary(symbol).expect("an arithmetic operator")
    }

    fn add(&mut self, a: usize, b: usize) -> usize {
        if self.is(a, 0.0) {
            return b;
        }
        if self.is(b, 0.0) {
            return a;
        }
        let op = self.op("+");
        self.apply(op, a, b)
    }

    fn sub(&mut self, a: usize, b: usize) -> usize {
        if self.is(b, 0.0) {
            return a;
        }
        if self.is(a, 0.0) {
            return self.negate(b);
        }
        let op = self.op("-");
        self.apply(op, a, b)
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
        let op = self.op("*");
        self.apply(op, a, b)
    }

    fn div(&mut self, a: usize, b: usize) -> usize {
        if self.is(a, 0.0) {
            return self.number(0.0);
        }
        if self.is(b, 1.0) {
            return a;
        }
        let op = self.op("/");
        self.apply(op, a, b)
    }

    fn pow(&mut self, a: usize, k: f64) -> usize {
        if k == 1.0 {
            return a;
        }
        let (op, k) = (self.op("^"), self.number(k));
        self.apply(op, a, k)
    }

    fn func(&mut self, name: &'static str, a: usize) -> usize {
        let f = self.unary_fn(name);
        self.call(name, f, a)
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
                match op.symbol {
                    "+" => self.add(da, db),
                    "-" => self.sub(da, db),
                    "*" => {
                        let (x, y) = (self.mul(da, b), self.mul(a, db));
                        self.add(x, y)
                    }
                    "/" => {
                        let (x, y) = (self.mul(da, b), self.mul(a, db));
                        let (top, bottom) = (self.sub(x, y), self.mul(b, b));
                        self.div(top, bottom)
                    }
                    "^" => match self.constant(b) {
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
                    _ => return None,
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
        let mut ssa = Vec::new();
        let mut done: Vec<Option<Operand>> = alloc::vec![None; self.nodes.len()];
        let result = self.emit(id, &mut ssa, &mut done);
        Program::from_ssa(&ssa, result)
    }

    fn emit(&self, id: usize, ssa: &mut Vec<Operation>, done: &mut [Option<Operand>]) -> Operand {
        if let Some(o) = done[id] {
            return o;
        }
        let operation = match self.nodes[id] {
            Node::Const(c) => return Operand::Const(c),
            Node::Var(j) => return Operand::Var(j),
            Node::Neg(a) => Operation::Neg(self.emit(a, ssa, done)),
            Node::Unary(_, f, a) => Operation::Unary(f, self.emit(a, ssa, done)),
            Node::Binary(op, a, b) => {
                let (x, y) = (self.emit(a, ssa, done), self.emit(b, ssa, done));
                match op.symbol {
                    "+" => Operation::Add(x, y),
                    "-" => Operation::Sub(x, y),
                    "*" => Operation::Mul(x, y),
                    "/" => Operation::Div(x, y),
                    "^" => match y {
                        Operand::Const(k)
                            if k.fract() == 0.0 && (0.0..=MAX_POWI as f64).contains(&k) =>
                        {
                            Operation::PowI(x, k as i32)
                        }
                        _ => Operation::Binary(op.apply, x, y),
                    },
                    _ => Operation::Binary(op.apply, x, y),
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

/// An operand of one level of an expression, and whether the first and the last of exmex's
/// flat nodes in it are literal numbers: a commutative operator between two literal nodes
/// goes first among its equals in exmex's flat evaluation, even where one of them ends a
/// parenthesised group (`erf(x/2) + pi`).
#[derive(Clone, Copy)]
struct Value {
    node: usize,
    first_literal: bool,
    last_literal: bool,
}

impl Value {
    fn leaf(node: usize, literal: bool) -> Value {
        Value {
            node,
            first_literal: literal,
            last_literal: literal,
        }
    }

    /// `self op other`, computed as `node`.
    fn joined(self, other: Value, node: usize) -> Value {
        Value {
            node,
            first_literal: self.first_literal,
            last_literal: other.last_literal,
        }
    }
}

/// A recursive-descent reader of exmex's language that builds an [`Expression`].
struct Reader<'t, 'e> {
    text: &'t str,
    pos: usize,
    n: usize,
    depth: usize,
    e: &'e mut Expression,
}

impl Reader<'_, '_> {
    fn rest(&self) -> &str {
        &self.text[self.pos..]
    }

    fn skip_spaces(&mut self) {
        let rest = self.rest();
        self.pos += rest.len() - rest.trim_start().len();
    }

    fn unexpected(&self) -> String {
        match self.rest().chars().next() {
            Some(c) => format!("unexpected `{c}` at byte {}", self.pos),
            None => String::from("unexpected end of the expression"),
        }
    }

    /// Consumes `c` (after spaces) when it comes next.
    fn eat(&mut self, c: char) -> bool {
        self.skip_spaces();
        let found = self.rest().starts_with(c);
        if found {
            self.pos += c.len_utf8();
        }
        found
    }

    fn expect(&mut self, c: char) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(self.unexpected())
        }
    }

    /// A name (letters, digits, `_`, starting with a letter or `_`), without consuming it.
    fn peek_name(&self) -> Option<&str> {
        let rest = self.rest();
        let first = rest.chars().next()?;
        if !(first.is_alphabetic() || first == '_') {
            return None;
        }
        let end = rest
            .char_indices()
            .find(|(_, c)| !(c.is_alphanumeric() || *c == '_'))
            .map_or(rest.len(), |(i, _)| i);
        Some(&rest[..end])
    }

    fn variable(&self, name: &str) -> Result<usize, String> {
        variable_index(name, self.n).ok_or_else(|| format!("unknown variable {name}"))
    }

    /// One level: operands separated by binary operators, combined in exmex's order.
    fn expression(&mut self) -> Result<Value, String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(format!("nests deeper than {MAX_DEPTH} levels"));
        }
        let mut values = alloc::vec![self.prefixed()?];
        let mut ops: Vec<Binary> = Vec::new();
        loop {
            self.skip_spaces();
            let Some(symbol) = ["^", "*", "/", "+", "-"]
                .into_iter()
                .find(|s| self.rest().starts_with(s))
            else {
                break;
            };
            self.pos += 1;
            let op = self
                .e
                .binary(symbol)
                .ok_or_else(|| format!("no binary operator `{symbol}`"))?;
            ops.push(op);
            values.push(self.prefixed()?);
        }
        // exmex's order: priority × 10, + 5 for a commutative operator between two literal
        // numbers; the first of the highest goes first, and its result takes its place.
        let mut keys: Vec<i64> = (0..ops.len())
            .map(|i| {
                let raise =
                    ops[i].commutative && values[i].last_literal && values[i + 1].first_literal;
                ops[i].prio * 10 + if raise { 5 } else { 0 }
            })
            .collect();
        while !ops.is_empty() {
            let mut best = 0;
            for i in 1..ops.len() {
                if keys[i] > keys[best] {
                    best = i;
                }
            }
            let (op, b) = (ops.remove(best), values.remove(best + 1));
            keys.remove(best);
            let a = values[best];
            values[best] = a.joined(b, self.e.apply(op, a.node, b.node));
        }
        self.depth -= 1;
        Ok(values[0])
    }

    /// An operand with its prefix operators (signs and functions), innermost applied first.
    fn prefixed(&mut self) -> Result<Value, String> {
        let mut prefixes: Vec<Option<(&'static str, UnaryFn)>> = Vec::new(); // None: negation
        loop {
            self.skip_spaces();
            if self.rest().starts_with('-') {
                self.pos += 1;
                prefixes.push(None);
            } else if self.rest().starts_with('+') {
                self.pos += 1;
            } else if let Some(name) = self.peek_name() {
                let unary = self
                    .e
                    .operator(name)
                    .filter(|op| op.bin().is_err() && op.constant().is_none())
                    .and_then(|op| op.unary().ok().map(|f| (op.repr(), f)));
                match unary {
                    Some(f) => {
                        self.pos += name.len();
                        prefixes.push(Some(f));
                    }
                    None => break,
                }
            } else {
                break;
            }
            if prefixes.len() > MAX_DEPTH {
                return Err(format!("nests deeper than {MAX_DEPTH} levels"));
            }
        }
        let mut value = self.atom()?;
        for prefix in prefixes.into_iter().rev() {
            value.node = match prefix {
                None => self.e.negate(value.node),
                Some((name, f)) => self.e.call(name, f, value.node),
            };
        }
        Ok(value)
    }

    /// A number, a named constant, a variable (`x1` or `{x1}`), a parenthesised expression
    /// or a binary operator in call syntax (`atan2(a, b)`).
    fn atom(&mut self) -> Result<Value, String> {
        self.skip_spaces();
        let rest = self.rest();
        if rest.starts_with('(') {
            self.pos += 1;
            let inner = self.expression()?;
            self.expect(')')?;
            return Ok(inner);
        }
        if let Some(inner) = rest.strip_prefix('{') {
            let end = inner.find('}').ok_or_else(|| self.unexpected())?;
            let j = self.variable(&inner[..end])?;
            self.pos += end + 2;
            return Ok(Value::leaf(self.e.push(Node::Var(j)), false));
        }
        // A number as exmex reads it: digits and dots, not a lone dot.
        let digits = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        if digits > 0 {
            let number = &rest[..digits];
            let value: f64 = number
                .parse()
                .map_err(|_| format!("not a number: `{number}` at byte {}", self.pos))?;
            self.pos += digits;
            return Ok(Value::leaf(self.e.number(value), true));
        }
        let Some(name) = self.peek_name() else {
            return Err(self.unexpected());
        };
        let name_len = name.len();
        if let Some(op) = self.e.operator(name) {
            if let Some(c) = op.constant() {
                self.pos += name_len;
                return Ok(Value::leaf(self.e.number(c), true));
            }
            if let Some(b) = self.e.binary(name) {
                self.pos += name_len;
                self.expect('(')?;
                let a = self.expression()?;
                self.expect(',')?;
                let second = self.expression()?;
                self.expect(')')?;
                let node = self.e.apply(b, a.node, second.node);
                return Ok(a.joined(second, node));
            }
        }
        let j = self.variable(name)?;
        self.pos += name_len;
        Ok(Value::leaf(self.e.push(Node::Var(j)), false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::string::ToString;
    use alloc::vec;
    use exmex::prelude::*;

    type Ex = FlatEx<f64, ZakaiOps>;

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

    /// The program against exmex's interpretation of the same text: within `max_ulp` ulp, or
    /// (when `relative` > 0) within `relative · max(1, |value|)` — an integer power's 2 ulp
    /// carried through later sums.
    fn agrees_with_exmex(text: &str, n: usize, max_ulp: u64) {
        agrees_within(text, n, max_ulp, 0.0)
    }

    fn agrees_within(text: &str, n: usize, max_ulp: u64, relative: f64) {
        let ex = Ex::parse(text).unwrap();
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

    #[test]
    fn every_function_and_constant_of_the_table_reads() {
        for op in ZakaiOps::make() {
            let name = op.repr();
            let text = if op.constant().is_some() {
                format!("{name}*x")
            } else if op.bin().is_ok() && name.chars().all(char::is_alphanumeric) {
                format!("{name}(x, 0.3)")
            } else if op.bin().is_ok() {
                format!("x{name}0.3")
            } else {
                format!("{name}(x/4)")
            };
            agrees_with_exmex(&text, 1, 0);
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

    /// More operands in one level than a 32-bit `usize` has bits, and the heavy derivatives
    /// that first showed it: held against closed forms, not against exmex's own evaluation,
    /// which miscounts there on 32-bit targets (wasm32: its `[usize]` number tracker adds 64
    /// per full word) and panics under overflow checks.
    #[test]
    fn long_expressions_and_their_derivatives() {
        let sum = (0..70)
            .map(|i| format!("{i}.5*x"))
            .collect::<Vec<_>>()
            .join("+");
        // Σ_{i<70} (i + ½) = 70²/2.
        agrees_with_closed_form(&sum, |x| 2450.0 * x, 1e-14);
        // h = x (1 + x²)⁻⁴, h′ = (1 + x²)⁻⁴ − 8x²(1 + x²)⁻⁵, h″ = −24x(1 + x²)⁻⁵ + 80x³(1 + x²)⁻⁶.
        let h = format!("x{}", "/(1+x^2)".repeat(4));
        let ex = Ex::parse(&h).unwrap();
        let d = ex.clone().partial(0).unwrap();
        let dd = d.clone().partial(0).unwrap();
        let q = |x: f64| 1.0 / (1.0 + x * x);
        let closed_forms: [&dyn Fn(f64) -> f64; 2] =
            [&|x| q(x).powi(4) - 8.0 * x * x * q(x).powi(5), &|x| {
                -24.0 * x * q(x).powi(5) + 80.0 * x.powi(3) * q(x).powi(6)
            }];
        for (text, closed_form) in [d.unparse().to_string(), dd.unparse().to_string()]
            .iter()
            .zip(closed_forms)
        {
            assert!(text.len() > 300, "a long derivative: {text}");
            agrees_with_closed_form(text, closed_form, 1e-13);
        }
        assert!(compile(&format!("{}x{}", "(".repeat(2000), ")".repeat(2000)), 1).is_err());
        assert!(compile("x +", 1).is_err());
        assert!(compile("y", 1).is_err());
        assert!(compile("(x", 1).is_err());
    }

    #[test]
    fn programs_equal_exmex_to_the_last_bit() {
        for (text, n) in [
            ("-cos(x1)-sin(x2)", 2),
            ("exp(-(x-0.5)^2.5)", 1),
            ("2*-x/3 + atan2(x, 2) - min(x, 0.5)*max(x, -1)", 1),
            ("tanh(x1)*x2 - 0.1*x1 + sqrt(abs(x2)) + erf(x1/2) + pi", 2),
            ("-0.4*x1 + 0.1*x2", 2),
            ("x1*x2/(1+x1^1.5)", 2),
            ("signum(x)*fract(x) + log(1+x^0.5)", 1),
            ("3", 1),
            ("x", 1),
            ("sin(2*pi/4)*x", 1),
        ] {
            agrees_with_exmex(text, n, 0);
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
            agrees_with_exmex(text, n, 2);
        }
        // Inside longer expressions the 2 ulp are carried through the sums: 1e-14 relative.
        for (text, n) in [
            ("-x^2 + 2*x^3/4 - sin(pi/2)", 1),
            ("x1^4 - x2^2 + x1^0", 2),
            ("(x1 - x2)^3 * cos(x1)^2", 2),
        ] {
            agrees_within(text, n, 2, 1e-14);
        }
    }

    #[test]
    fn derivatives_from_exmex_compile_and_agree() {
        let ex = Ex::parse("sin(x1)*x2^2.5 - exp(-x1*x2) / (1 + x1^2)").unwrap();
        for v in 0..2 {
            let d = ex.clone().partial(v).unwrap();
            let text = d.unparse().to_string();
            agrees_within(&text, 2, 2, 1e-14);
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
        for text in ["abs(x)", "erf(x)", "min(x, 1)", "floor(x)*x", "cbrt(x)"] {
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
