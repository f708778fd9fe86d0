//! The one front end of text expressions: a lexer and a parser that read `f` and `h` as typed
//! into a syntax tree, which compilation (`model::compile`), exact differentiation and
//! the polynomial normal form (`model::symbolic`) all read.
//!
//! Every mistake is reported with the character position a user can fix: a stray character,
//! unbalanced parentheses, a missing operand or operator, an unknown name, a constant that
//! overflows, chained powers, nesting that is too deep.
//!
//! The language, with the usual mathematical conventions:
//!
//! * numbers (`2`, `.5`, `2.5e-3`), the constants `pi`/`PI`, `e`/`E`, `TAU`, the state
//!   variables `x1..xn` (and `x` when n = 1), the functions of `FUNCTIONS` applied to a
//!   parenthesised argument;
//! * `+ − * / ^`, with `^` binding tightest and a leading minus looser than `^`: `-x^2` is
//!   −(x²) and `exp(-(x-1)^2)` is exp(−((x−1)²)); right after `^` a sign belongs to the
//!   exponent's first operand (`2^-x` = 2^(−x));
//! * chained powers `a^b^c` are refused, asking for parentheses.
//!
//! The tree also fixes the order in which a chain of operators at one level is evaluated —
//! the order of the flat evaluator Zakai used before this front end (exmex 0.21): by
//! descending priority (`^` 4, `/` 3, `*` 2, `-` 1, `+` 0), left to right among equals, a
//! commutative operator between two literal numbers first among its equals; a leading sign
//! is `0 − …`, a sign after another operator `(0 − …)`. So every expression computes the same
//! bits as before, and the compiled programs are tested against exmex to the last bit.

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec;
use alloc::vec::Vec;

/// Functions an expression may call. All have exact derivatives except `abs`, `signum`,
/// `floor`, `ceil`, `round`, `trunc`, `fract`, `cbrt`, `erf`, `erfc` (numerical derivatives).
#[cfg(test)]
pub(crate) const FUNCTIONS: &[&str] = &[
    "abs", "signum", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh",
    "acosh", "atanh", "floor", "round", "ceil", "trunc", "fract", "exp", "sqrt", "cbrt", "ln",
    "log", "log2", "log10", "erf", "erfc",
];

/// A real function of one real variable.
pub(crate) type RealFn = fn(f64) -> f64;

/// The sign of `v` as ±1 (by its sign bit), NaN for NaN.
fn signum(v: f64) -> f64 {
    if v.is_nan() {
        v
    } else if v.is_sign_negative() {
        -1.0
    } else {
        1.0
    }
}

/// `v − trunc v`.
fn fract(v: f64) -> f64 {
    v - libm::trunc(v)
}

/// The functions of `FUNCTIONS`, by name, every transcendental one computed by the pure-Rust
/// `libm` crate or the crate's own branch-free `exp`, `ln` and `atan` and correctly rounded `sqrt`
/// ([`crate::linalg::elementary`]) rather than the platform's maths library, so that an expression gives
/// bit-identical values natively and in wasm (same seed → same trajectory everywhere).
const FUNCTION_TABLE: &[(&str, RealFn)] = &[
    ("abs", libm::fabs),
    ("signum", signum),
    ("sin", libm::sin),
    ("cos", libm::cos),
    ("tan", libm::tan),
    ("asin", libm::asin),
    ("acos", libm::acos),
    ("atan", crate::linalg::elementary::atan),
    ("sinh", libm::sinh),
    ("cosh", libm::cosh),
    ("tanh", libm::tanh),
    ("asinh", libm::asinh),
    ("acosh", libm::acosh),
    ("atanh", libm::atanh),
    ("floor", libm::floor),
    ("round", libm::round),
    ("ceil", libm::ceil),
    ("trunc", libm::trunc),
    ("fract", fract),
    ("exp", crate::linalg::elementary::exp),
    ("sqrt", crate::linalg::elementary::sqrt),
    ("cbrt", libm::cbrt),
    ("ln", crate::linalg::elementary::ln),
    ("log", crate::linalg::elementary::ln),
    ("log2", libm::log2),
    ("log10", libm::log10),
    ("erf", libm::erf),
    ("erfc", libm::erfc),
];

/// A function of the expression language: its name and what it computes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Function {
    pub(crate) name: &'static str,
    pub(crate) apply: RealFn,
}

impl Function {
    /// The function called `name`, if the language has one.
    pub(crate) fn named(name: &str) -> Option<Function> {
        FUNCTION_TABLE
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(name, apply)| Function { name, apply })
    }
}

/// Named constants an expression may use.
#[cfg(test)]
pub(crate) const CONSTANTS: &[&str] = &["PI", "pi", "E", "e", "TAU"];

fn constant(name: &str) -> Option<f64> {
    match name {
        "PI" | "pi" => Some(core::f64::consts::PI),
        "E" | "e" => Some(core::f64::consts::E),
        "TAU" => Some(core::f64::consts::TAU),
        _ => None,
    }
}

/// A binary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Op {
    Add,
    Sub,
    Mul,
    Div,
    /// `^`, computed by `libm::pow`.
    Pow,
}

impl Op {
    fn from_char(c: char) -> Option<Op> {
        Some(match c {
            '+' => Op::Add,
            '-' => Op::Sub,
            '*' => Op::Mul,
            '/' => Op::Div,
            '^' => Op::Pow,
            _ => return None,
        })
    }

    /// What the operator computes.
    pub(crate) fn apply(self) -> fn(f64, f64) -> f64 {
        match self {
            Op::Add => |a, b| a + b,
            Op::Sub => |a, b| a - b,
            Op::Mul => |a, b| a * b,
            Op::Div => |a, b| a / b,
            Op::Pow => libm::pow,
        }
    }

    /// Its priority in a chain (see the module doc).
    fn priority(self) -> i64 {
        match self {
            Op::Pow => 4,
            Op::Div => 3,
            Op::Mul => 2,
            Op::Sub => 1,
            Op::Add => 0,
        }
    }

    fn commutative(self) -> bool {
        matches!(self, Op::Add | Op::Mul)
    }
}

pub(crate) use crate::error::ExprError;

/// The state variable names of an `n`-dimensional model: `x1..xn`, and `x` when `n = 1`.
pub(crate) fn variable_names(n: usize) -> Vec<String> {
    let mut names: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    if n == 1 {
        names.push("x".to_string());
    }
    names
}

/// Index of the state variable `name` (`x` ↦ 0 when n = 1), if it is one.
pub(crate) fn variable_index(name: &str, n: usize) -> Option<usize> {
    if n == 1 && name == "x" {
        return Some(0);
    }
    let i: usize = name.strip_prefix('x')?.parse().ok()?;
    (i >= 1 && i <= n && !name[1..].starts_with('0')).then(|| i - 1)
}

/// The variables an expression may read, in the order of its inputs: the state `x1..xn` (`x`
/// when n = 1), then the measurement `z1..zm` of a log-density `log p(z | x)` (`z` when
/// m = 1), then, in a driven model ([`crate::Inputs`]), the time `t` and the known
/// inputs `u1..uk`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Variables {
    n: usize,
    m: usize,
    inputs: Option<usize>,
}

impl Variables {
    /// The state variables of an `n`-dimensional model alone.
    pub(crate) fn state(n: usize) -> Self {
        Variables {
            n,
            m: 0,
            inputs: None,
        }
    }

    /// The state variables, then the measurement `z1..zm` (and `z` when m = 1, as `x` for
    /// the state).
    pub(crate) fn state_and_measurement(n: usize, m: usize) -> Self {
        Variables { n, m, inputs: None }
    }

    /// The time `t` alone: what a known input's expression reads.
    pub(crate) const fn time() -> Self {
        Variables {
            n: 0,
            m: 0,
            inputs: Some(0),
        }
    }

    /// These variables followed by the time `t` and the `k` known inputs `u1..uk` of a driven
    /// model (`None`: an autonomous model, whose expressions may not read `t`).
    pub(crate) fn driven(self, inputs: Option<usize>) -> Self {
        Variables { inputs, ..self }
    }

    /// How many inputs an expression in these variables takes.
    pub(crate) fn count(&self) -> usize {
        self.n + self.m + self.inputs.map_or(0, |k| 1 + k)
    }

    /// The input `name` stands for, if it is one of these variables (`z` is `z1` when it is
    /// the only measurement component).
    pub(crate) fn index(&self, name: &str) -> Option<usize> {
        let numbered = |prefix: char, count: usize| {
            let i: usize = name.strip_prefix(prefix)?.parse().ok()?;
            (i >= 1 && i <= count && !name[1..].starts_with('0')).then(|| i - 1)
        };
        if let Some(i) = variable_index(name, self.n) {
            return Some(i);
        }
        if name == "z" && self.m == 1 {
            return Some(self.n);
        }
        if let Some(i) = numbered('z', self.m) {
            return Some(self.n + i);
        }
        let k = self.inputs?;
        if name == "t" {
            return Some(self.n + self.m);
        }
        numbered('u', k).map(|i| self.n + self.m + 1 + i)
    }

    /// Every name, for messages.
    pub(crate) fn names(&self) -> Vec<String> {
        let mut names = variable_names(self.n);
        names.extend((1..=self.m).map(|i| format!("z{i}")));
        if self.m == 1 {
            names.push("z".to_string());
        }
        if let Some(k) = self.inputs {
            names.push("t".to_string());
            names.extend((1..=k).map(|i| format!("u{i}")));
        }
        names
    }
}

/// Longest expression accepted, in characters.
pub(crate) const MAX_EXPRESSION_CHARS: usize = 1000;
/// Deepest nesting of parentheses and stacked unary signs accepted.
pub(crate) const MAX_NESTING: usize = 32;
/// Most distinct state variables one expression may use.
pub(crate) const MAX_VARIABLES: usize = 16;

/// What a token is.
#[derive(Clone, Copy, Debug)]
enum Lexeme {
    /// A number literal or a named constant.
    Number(f64),
    Variable(usize),
    Function(Function),
    Open,
    Close,
    Operator(char),
    Comma,
}

/// The kind of a token, for the check of neighbours.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    Operand,
    Function,
    Open,
    Close,
    Operator,
    Comma,
}

impl Lexeme {
    fn kind(self) -> Kind {
        match self {
            Lexeme::Number(_) | Lexeme::Variable(_) => Kind::Operand,
            Lexeme::Function(_) => Kind::Function,
            Lexeme::Open => Kind::Open,
            Lexeme::Close => Kind::Close,
            Lexeme::Operator(_) => Kind::Operator,
            Lexeme::Comma => Kind::Comma,
        }
    }
}

/// One token and its character position.
#[derive(Clone, Copy, Debug)]
struct Token {
    lexeme: Lexeme,
    position: usize,
}

/// A node of a [`Syntax`] tree; children are indices of earlier nodes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Node {
    /// A number literal or a named constant.
    Number(f64),
    /// The state variable x_{j+1}.
    Variable(usize),
    /// A sign right after `^` (`2^-x`).
    Negate(usize),
    /// A function applied to its argument.
    Call(Function, usize),
    /// `a op b`.
    Binary(Op, usize, usize),
}

/// An expression read: its tree, in which every node comes after its children (so one pass in
/// index order visits children first), and the measures of its size the derivative budget of
/// [`super::expression`] uses.
#[derive(Clone, Debug)]
pub(crate) struct Syntax {
    pub(crate) nodes: Vec<Node>,
    pub(crate) root: usize,
    /// Operators and parentheses, counted as the written-out evaluation order has them (a
    /// sign after another operator opens parentheses of its own).
    pub(crate) operations: usize,
    /// Deepest nesting of those parentheses.
    pub(crate) depth: usize,
}

impl Syntax {
    /// Reads `text` in the state variables of an `n`-dimensional model, or says at which
    /// character it goes wrong.
    pub(crate) fn parse(text: &str, n: usize) -> Result<Syntax, ExprError> {
        Syntax::parse_with(text, n, &[])
    }

    /// As [`Syntax::parse_in`], in the state variables of an `n`-dimensional model.
    pub(crate) fn parse_with(
        text: &str,
        n: usize,
        names: &[(String, f64)],
    ) -> Result<Syntax, ExprError> {
        Syntax::parse_in(text, &Variables::state(n), names)
    }

    /// Reads `text` in `variables`, with `names` — a scenario's parameters — read as the
    /// numbers they stand for (exactly as if the value had been typed).
    pub(crate) fn parse_in(
        text: &str,
        variables: &Variables,
        names: &[(String, f64)],
    ) -> Result<Syntax, ExprError> {
        if let Some((position, _)) = text.char_indices().nth(MAX_EXPRESSION_CHARS) {
            return Err(syntax_error(
                text,
                position,
                &format!("longer than {MAX_EXPRESSION_CHARS} characters"),
            ));
        }
        let tokens = tokenize(text, variables, names)?;
        let mut parser = Parser {
            text,
            tokens: &tokens,
            at: 0,
            nodes: Vec::new(),
            parentheses: 0,
            signs: 0,
            operations: 0,
            depth: 0,
            deepest: 0,
            variables: Vec::new(),
        };
        let root = parser.level()?;
        if let Some(t) = tokens.get(parser.at) {
            // Only a `)` or `,` stops a level; the lexer balanced the parentheses.
            return Err(parser.error(
                t.position,
                "`,` separates nothing here: no function takes two arguments",
            ));
        }
        if parser.variables.len() > MAX_VARIABLES {
            return Err(ExprError::Syntax {
                expr: text.to_string(),
                position: None,
                message: format!("at most {MAX_VARIABLES} distinct variables per expression"),
            });
        }
        Ok(Syntax {
            nodes: parser.nodes,
            root: root.node,
            operations: parser.operations,
            depth: parser.deepest,
        })
    }
}

fn syntax_error(text: &str, position: usize, message: &str) -> ExprError {
    ExprError::Syntax {
        expr: text.to_string(),
        position: Some(position),
        message: message.to_string(),
    }
}

/// An operand of one level and whether its first and last leaves are literal numbers (which
/// the evaluation order of a chain looks at, see the module doc).
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
}

/// Recursive descent over the tokens.
struct Parser<'t> {
    text: &'t str,
    tokens: &'t [Token],
    at: usize,
    nodes: Vec<Node>,
    /// Parentheses open at the current token.
    parentheses: usize,
    /// Unary signs in a row ending at the current token.
    signs: usize,
    operations: usize,
    /// Parentheses of the written-out order open now, and the most ever open.
    depth: usize,
    deepest: usize,
    /// The distinct variables used.
    variables: Vec<usize>,
}

impl Parser<'_> {
    fn error(&self, position: usize, message: &str) -> ExprError {
        syntax_error(self.text, position, message)
    }

    fn push(&mut self, node: Node) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    fn peek(&self) -> Option<Token> {
        self.tokens.get(self.at).copied()
    }

    fn position(&self) -> usize {
        self.peek()
            .map_or_else(|| self.text.chars().count(), |t| t.position)
    }

    /// Consumes the next token, keeping count of nesting (parentheses and stacked signs) and
    /// of operations.
    fn take(&mut self, sign: bool) -> Result<Token, ExprError> {
        let t = self.tokens[self.at];
        self.at += 1;
        match t.lexeme {
            Lexeme::Open => {
                self.parentheses += 1;
                self.operations += 1;
                self.enter();
            }
            Lexeme::Close => {
                self.parentheses -= 1;
                self.depth -= 1;
            }
            Lexeme::Operator(_) => self.operations += 1,
            _ => {}
        }
        self.signs = if sign { self.signs + 1 } else { 0 };
        if self.parentheses + self.signs > MAX_NESTING {
            return Err(self.error(
                t.position,
                &format!("nests deeper than {MAX_NESTING} levels of parentheses and signs"),
            ));
        }
        Ok(t)
    }

    fn enter(&mut self) {
        self.depth += 1;
        self.deepest = self.deepest.max(self.depth);
    }

    /// Consumes a `+` or `−` that comes next, as a unary sign.
    fn sign(&mut self) -> Result<Option<Op>, ExprError> {
        match self.peek() {
            Some(Token {
                lexeme: Lexeme::Operator(c @ ('+' | '-')),
                ..
            }) => {
                self.take(true)?;
                Ok(Op::from_char(c))
            }
            _ => Ok(None),
        }
    }

    /// Consumes `^` when it comes next.
    fn power_sign(&mut self) -> Result<bool, ExprError> {
        match self.peek() {
            Some(Token {
                lexeme: Lexeme::Operator('^'),
                ..
            }) => {
                self.take(false)?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    fn chained(&self) -> Result<(), ExprError> {
        match self.peek() {
            Some(Token {
                lexeme: Lexeme::Operator('^'),
                position,
            }) => Err(self.error(
                position,
                "chained powers are ambiguous: write a^(b^c) or (a^b)^c",
            )),
            _ => Ok(()),
        }
    }

    fn zero(&mut self) -> Value {
        let node = self.push(Node::Number(0.0));
        Value::leaf(node, true)
    }

    /// One level: operands joined by binary operators, up to a `)`, a `,` or the end.
    fn level(&mut self) -> Result<Value, ExprError> {
        let mut values = Vec::new();
        let mut ops = Vec::new();
        if let Some(s) = self.sign()? {
            // `−a…` is `0 − a…`.
            values.push(self.zero());
            ops.push(s);
            values.push(self.after_operator()?);
        } else {
            values.push(self.operand()?);
        }
        while let Some(t) = self.peek() {
            let Lexeme::Operator(c) = t.lexeme else {
                break;
            };
            self.take(false)?;
            let op = Op::from_char(c).expect("the lexer's operators");
            if op == Op::Pow {
                if ops.last() == Some(&Op::Pow) {
                    return Err(self.error(
                        t.position,
                        "chained powers are ambiguous: write a^(b^c) or (a^b)^c",
                    ));
                }
                values.push(self.exponent()?);
            } else {
                values.push(self.after_operator()?);
            }
            ops.push(op);
        }
        Ok(self.chain(values, ops))
    }

    /// The operand after `+ − * /`: a sign there opens a group `(0 ± a[^b])` of its own.
    fn after_operator(&mut self) -> Result<Value, ExprError> {
        let Some(s) = self.sign()? else {
            return self.operand();
        };
        self.operations += 1;
        self.enter();
        let mut values = vec![self.zero(), self.after_operator()?];
        let mut ops = vec![s];
        if self.power_sign()? {
            ops.push(Op::Pow);
            values.push(self.exponent()?);
            self.chained()?;
        }
        self.depth -= 1;
        Ok(self.chain(values, ops))
    }

    /// The exponent after `^`: a sign there belongs to its first operand.
    fn exponent(&mut self) -> Result<Value, ExprError> {
        match self.sign()? {
            Some(Op::Sub) => {
                let value = self.after_operator()?;
                let node = self.push(Node::Negate(value.node));
                Ok(Value { node, ..value })
            }
            Some(_) => self.after_operator(),
            None => self.operand(),
        }
    }

    /// A number, constant, variable, parenthesised level or function call.
    fn operand(&mut self) -> Result<Value, ExprError> {
        let Some(t) = self.peek() else {
            return Err(self.error(self.position(), "an operand is missing"));
        };
        match t.lexeme {
            Lexeme::Number(v) => {
                self.take(false)?;
                let node = self.push(Node::Number(v));
                Ok(Value::leaf(node, true))
            }
            Lexeme::Variable(j) => {
                self.take(false)?;
                if !self.variables.contains(&j) {
                    self.variables.push(j);
                }
                let node = self.push(Node::Variable(j));
                Ok(Value::leaf(node, false))
            }
            Lexeme::Function(f) => {
                self.take(false)?;
                let inner = self.parenthesised()?;
                let node = self.push(Node::Call(f, inner.node));
                Ok(Value { node, ..inner })
            }
            Lexeme::Open => self.parenthesised(),
            _ => Err(self.error(t.position, "an operand is missing")),
        }
    }

    /// `( level )`.
    fn parenthesised(&mut self) -> Result<Value, ExprError> {
        match self.peek() {
            Some(Token {
                lexeme: Lexeme::Open,
                ..
            }) => {
                self.take(false)?;
            }
            _ => return Err(self.error(self.position(), "`(` expected")),
        }
        let inner = self.level()?;
        match self.peek() {
            Some(Token {
                lexeme: Lexeme::Close,
                ..
            }) => {
                self.take(false)?;
                Ok(inner)
            }
            Some(t) => Err(self.error(
                t.position,
                "`,` separates nothing here: no function takes two arguments",
            )),
            None => Err(self.error(self.position(), "`)` expected")),
        }
    }

    /// Joins the operands of one level in the evaluation order of the module doc: by
    /// priority × 10, + 5 for a commutative operator between two literal numbers; the first
    /// of the highest goes first, and its result takes its place.
    fn chain(&mut self, mut values: Vec<Value>, mut ops: Vec<Op>) -> Value {
        let mut keys: Vec<i64> = (0..ops.len())
            .map(|i| {
                let raise =
                    ops[i].commutative() && values[i].last_literal && values[i + 1].first_literal;
                ops[i].priority() * 10 + if raise { 5 } else { 0 }
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
            values[best] = Value {
                node: self.push(Node::Binary(op, a.node, b.node)),
                first_literal: a.first_literal,
                last_literal: b.last_literal,
            };
        }
        values[0]
    }
}

/// Splits `text` into tokens, reporting lexical mistakes with their positions.
fn tokenize(
    text: &str,
    variables: &Variables,
    names: &[(String, f64)],
) -> Result<Vec<Token>, ExprError> {
    let chars: Vec<char> = text.chars().collect();
    let syntax = |position: usize, message: &str| ExprError::Syntax {
        expr: text.to_string(),
        position: Some(position),
        message: message.to_string(),
    };
    if chars.iter().all(|c| c.is_whitespace()) {
        return Err(ExprError::Syntax {
            expr: text.to_string(),
            position: None,
            message: "the expression is empty".to_string(),
        });
    }
    let mut tokens: Vec<Token> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        let lexeme = if c.is_whitespace() {
            i += 1;
            continue;
        } else if c.is_ascii_digit() || c == '.' {
            i = number_end(&chars, i);
            let literal: String = chars[start..i].iter().collect();
            match literal.parse::<f64>() {
                Ok(v) if v.is_finite() => Lexeme::Number(v),
                Ok(_) => {
                    return Err(ExprError::NonFiniteConstant {
                        expr: text.to_string(),
                        literal,
                        position: start,
                    })
                }
                Err(_) => return Err(syntax(start, &format!("malformed number `{literal}`"))),
            }
        } else if is_name_start(c) {
            i = name_end(&chars, i);
            let name: String = chars[start..i].iter().collect();
            if let Some(f) = Function::named(&name) {
                Lexeme::Function(f)
            } else if let Some(v) = constant(&name) {
                Lexeme::Number(v)
            } else if let Some(j) = variables.index(&name) {
                Lexeme::Variable(j)
            } else if let Some((_, v)) = names.iter().find(|(p, _)| *p == name) {
                Lexeme::Number(*v)
            } else {
                let mut allowed = variables.names();
                allowed.extend(names.iter().map(|(p, _)| p.clone()));
                return Err(ExprError::UnknownVariable {
                    expr: text.to_string(),
                    name,
                    position: start,
                    allowed: if allowed.is_empty() {
                        // A coefficient of a scenario that declares no parameters.
                        "numbers only: the scenario declares no parameters".to_string()
                    } else {
                        allowed.join(", ")
                    },
                });
            }
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            return Err(syntax(
                start,
                "`**` is not an operator here: write powers with `^`, e.g. x^3",
            ));
        } else {
            i += 1;
            match c {
                '(' => {
                    open.push(start);
                    Lexeme::Open
                }
                ')' => {
                    if open.pop().is_none() {
                        return Err(syntax(start, "`)` without a matching `(`"));
                    }
                    Lexeme::Close
                }
                '+' | '-' | '*' | '/' | '^' => Lexeme::Operator(c),
                ',' => Lexeme::Comma,
                _ => return Err(syntax(start, &format!("unexpected character `{c}`"))),
            }
        };
        let prev = tokens.last().map(|t| t.lexeme.kind());
        check_adjacent(prev, lexeme.kind(), c).map_err(|m| syntax(start, m))?;
        tokens.push(Token {
            lexeme,
            position: start,
        });
    }
    if let Some(p) = open.pop() {
        return Err(syntax(p, "`(` is never closed"));
    }
    match tokens.last() {
        Some(t) if t.lexeme.kind() == Kind::Operator => {
            Err(syntax(t.position, "an operator needs an operand after it"))
        }
        Some(t) if t.lexeme.kind() == Kind::Function => Err(syntax(
            t.position,
            "a function name must be followed by `(`",
        )),
        _ => Ok(tokens),
    }
}

/// Whether `c` starts a name (a function, constant, variable or parameter).
fn is_name_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

/// The end of the name starting at `chars[i]`.
fn name_end(chars: &[char], mut i: usize) -> usize {
    while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
        i += 1;
    }
    i
}

/// The end of the number literal starting at `chars[i]` (digits and points, then an
/// optional exponent `e±d…`).
fn number_end(chars: &[char], mut i: usize) -> usize {
    while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
        i += 1;
    }
    if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
        let mut j = i + 1;
        if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
            j += 1;
        }
        if j < chars.len() && chars[j].is_ascii_digit() {
            i = j;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
        }
    }
    i
}

/// The names in `text` that are not functions or built-in constants — state variables and
/// parameters — with their character positions, in order.
pub(crate) fn free_names(text: &str) -> Vec<(String, usize)> {
    let chars: Vec<char> = text.chars().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_ascii_digit() || c == '.' {
            i = number_end(&chars, i);
        } else if is_name_start(c) {
            let end = name_end(&chars, i);
            let name: String = chars[i..end].iter().collect();
            if Function::named(&name).is_none() && constant(&name).is_none() {
                found.push((name, i));
            }
            i = end;
        } else {
            i += 1;
        }
    }
    found
}

/// Whether `text` reads a state variable of an `n`-dimensional model (a coefficient that is a
/// function of the state, such as a diffusion entry `0.3*sqrt(abs(x))`).
pub(crate) fn reads_state(text: &str, n: usize) -> bool {
    free_names(text)
        .iter()
        .any(|(name, _)| variable_index(name, n).is_some())
}

/// The state variables `text` reads in an `n`-dimensional model, as ascending indices (the
/// dimensions a function of the state depends on, for the tensor-train filter's blocks).
pub(crate) fn variables_read(text: &str, n: usize) -> Vec<usize> {
    let mut read: Vec<usize> = free_names(text)
        .iter()
        .filter_map(|(name, _)| variable_index(name, n))
        .collect();
    read.sort_unstable();
    read.dedup();
    read
}

/// Whether `text` reads the time `t` or a known input `u1`, `u2`, … of a driven model
/// ([`crate::Inputs`]).
pub(crate) fn reads_drive(text: &str) -> bool {
    free_names(text)
        .iter()
        .any(|(name, _)| name == "t" || crate::error::is_input_name(name))
}

/// `text` with every parameter of `names` replaced by its value, written so that it reads
/// back to the same `f64` (in parentheses when negative): the expression a model is built
/// from once the parameters have values.
pub(crate) fn substitute(text: &str, names: &[(String, f64)]) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut last = 0;
    for (name, at) in free_names(text) {
        if let Some((_, v)) = names.iter().find(|(p, _)| *p == name) {
            out.extend(&chars[last..at]);
            out.push_str(&if *v < 0.0 {
                format!("({v:?})")
            } else {
                format!("{v:?}")
            });
            last = at + name.chars().count();
        }
    }
    out.extend(&chars[last..]);
    out
}

/// Whether a token of kind `token` (whose first character is `c`) may follow one of kind
/// `prev`; the message says what is wrong when it may not.
fn check_adjacent(prev: Option<Kind>, token: Kind, c: char) -> Result<(), &'static str> {
    use Kind::*;
    let Some(p) = prev else {
        return match token {
            Close => Err("`)` cannot start an expression"),
            Comma => Err("`,` cannot start an expression"),
            Operator if c != '-' && c != '+' => Err("an operator needs an operand before it"),
            _ => Ok(()),
        };
    };
    match (p, token) {
        (Operand | Close, Operand | Function | Open) => Err("missing operator"),
        (Function, t) if t != Open => Err("a function name must be followed by `(`"),
        (Operator | Open | Comma, Close) => Err("missing operand before `)`"),
        (Operator | Open | Comma, Operator) if c != '-' && c != '+' => {
            Err("an operator needs an operand before it")
        }
        (Open | Comma | Operator, Comma) => Err("missing operand before `,`"),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    fn position(e: ExprError) -> Option<usize> {
        match e {
            ExprError::Syntax { position, .. } => position,
            ExprError::UnknownVariable { position, .. } => Some(position),
            ExprError::NonFiniteConstant { position, .. } => Some(position),
            _ => None,
        }
    }

    fn error(text: &str, n: usize) -> ExprError {
        Syntax::parse(text, n).unwrap_err()
    }

    /// The tree written out with every operation in parentheses.
    fn shown(s: &Syntax, id: usize) -> String {
        match s.nodes[id] {
            Node::Number(v) => format!("{v}"),
            Node::Variable(j) => format!("x{}", j + 1),
            Node::Negate(a) => format!("(-{})", shown(s, a)),
            Node::Call(f, a) => format!("{}({})", f.name, shown(s, a)),
            Node::Binary(op, a, b) => {
                let symbol = ['+', '-', '*', '/', '^'][op as usize];
                format!("({}{symbol}{})", shown(s, a), shown(s, b))
            }
        }
    }

    fn tree(text: &str, n: usize) -> String {
        let s = Syntax::parse(text, n).unwrap();
        shown(&s, s.root)
    }

    /// Python's power operator gets a hint at its position.
    #[test]
    fn double_star_suggests_the_caret() {
        let e = error("2*x**3", 1);
        assert!(e.to_string().contains("write powers with `^`"), "{e}");
        assert_eq!(position(e), Some(3));
    }

    #[test]
    fn sound_expressions_pass() {
        for e in [
            "x^3",
            "-cos(x1)-sin(x2)",
            "x1 - x2",
            "2.5e-3*x1^2",
            "-(x)",
            "exp(-x^2/2)",
        ] {
            let n = if e.contains("x2") { 2 } else { 1 };
            assert!(Syntax::parse(e, n).is_ok(), "{e}");
        }
    }

    #[test]
    fn mistakes_report_their_position() {
        assert_eq!(position(error("x1 + $", 1)), Some(5));
        assert_eq!(position(error("sin(x1", 1)), Some(3));
        assert_eq!(position(error("x1 + y", 1)), Some(5));
        assert_eq!(position(error("x1 *", 1)), Some(3));
        assert_eq!(position(error("2 x1", 1)), Some(2));
        assert_eq!(position(error("x3", 2)), Some(0));
        assert_eq!(position(error("x + 1e999", 1)), Some(4));
        assert_eq!(position(error("x)", 1)), Some(1));
        assert_eq!(position(error("x, 1", 1)), Some(1));
        assert_eq!(position(error("sin(x, 1)", 1)), Some(5));
        assert!(matches!(error("x3", 2), ExprError::UnknownVariable { .. }));
        assert!(matches!(
            error("1e999", 1),
            ExprError::NonFiniteConstant { .. }
        ));
        let deep = format!("{}x{}", "(".repeat(40), ")".repeat(40));
        assert_eq!(position(error(&deep, 1)), Some(MAX_NESTING));
        let signs = format!("x^{}x", "-".repeat(40));
        assert_eq!(position(error(&signs, 1)), Some(2 + MAX_NESTING));
        assert!(error(&"x+".repeat(600), 1)
            .to_string()
            .contains("longer than"));
    }

    #[test]
    fn exponents_are_read() {
        assert_eq!(tree("2.5e-3*x", 1), "(0.0025*x1)");
        assert_eq!(tree("1E2 + x", 1), "(100+x1)");
        assert_eq!(tree(".5*pi", 1), format!("(0.5*{})", core::f64::consts::PI));
    }

    #[test]
    fn unary_minus_binds_looser_than_powers() {
        assert_eq!(tree("-x1^2", 2), "(0-(x1^2))");
        assert_eq!(tree("exp(-(x1-1)^2)", 2), "exp((0-((x1-1)^2)))");
        assert_eq!(tree("3*-x1^2", 2), "(3*(0-(x1^2)))");
        assert_eq!(tree("x1/-sin(x2)^2*4", 2), "((x1/(0-(sin(x2)^2)))*4)");
        assert_eq!(tree("2^-x1", 2), "(2^(-x1))");
        assert_eq!(tree("x1 - -x2", 2), "(x1-(0-x2))");
        assert_eq!(tree("x*--x^2", 1), "(x1*(0-(0-(x1^2))))");
    }

    /// The chain order of the module doc: priority, then literal pairs of `+` and `*` first.
    #[test]
    fn chains_follow_the_evaluation_order() {
        assert_eq!(tree("x + 1 + 2", 1), "(x1+(1+2))");
        assert_eq!(tree("x1 + x2 - x1", 2), "(x1+(x2-x1))");
        // `/` (30) first, then `* 4` (20 + 5: between two literals) before `x1 *` (20).
        assert_eq!(tree("x1 * x2 / 3 * 4", 2), "(x1*((x2/3)*4))");
        assert_eq!(
            tree("erf(x/2) + pi", 1),
            format!("(erf((x1/2))+{})", core::f64::consts::PI)
        );
    }

    #[test]
    fn chained_powers_are_refused() {
        assert_eq!(position(error("2^x1^2", 1)), Some(4));
        assert_eq!(position(error("2^-x^2", 1)), Some(4));
        assert_eq!(position(error("x*-x^2^3", 1)), Some(6));
        assert!(Syntax::parse("2^(x1^2)", 1).is_ok());
        assert!(Syntax::parse("(2^x1)^2", 1).is_ok());
        assert!(Syntax::parse("x1^2 + x1^3", 1).is_ok());
    }

    #[test]
    fn operations_count_the_written_out_order() {
        let s = Syntax::parse("-x^2 + 3*-x", 1).unwrap();
        // `0-x^2+3*(0-x)`: five operators and one parenthesis, one deep.
        assert_eq!((s.operations, s.depth), (6, 1));
        let s = Syntax::parse("sin(cos(x))", 1).unwrap();
        assert_eq!((s.operations, s.depth), (2, 2));
    }

    /// The published list of functions is the table the evaluator computes with.
    #[test]
    fn the_function_list_is_the_table() {
        let names: Vec<&str> = FUNCTION_TABLE.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, FUNCTIONS);
        for c in CONSTANTS {
            assert!(constant(c).is_some(), "{c}");
        }
    }

    #[test]
    fn variable_names_follow_the_dimension() {
        assert_eq!(variable_index("x", 1), Some(0));
        assert_eq!(variable_index("x", 2), None);
        assert_eq!(variable_index("x2", 2), Some(1));
        assert_eq!(variable_index("x02", 2), None);
        assert_eq!(variable_index("x0", 2), None);
        let many: Vec<String> = (1..=17).map(|i| format!("x{i}")).collect();
        assert!(Syntax::parse(&many.join("+"), 17).is_err());
        assert!(Syntax::parse(&many[..16].join("+"), 17).is_ok());
    }
}
