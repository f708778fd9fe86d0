//! Exact normal forms of text expressions, so that structural conditions such as 002's
//! (C1)–(C3) can be decided symbolically rather than at test points.
//!
//! An expression is read from the syntax tree the evaluator compiles ([`super::syntax`]) — so `-x^2` is
//! `−(x²)` here too — into a [`Poly`]: a
//! polynomial with real coefficients in *atoms*, which are the state variables `x_i` and the
//! elementary functions sin, cos, tan, sinh, cosh, tanh, exp of such polynomials. Sums,
//! products, integer powers up to [`MAX_POWER`], division by constants and derivatives stay
//! in this ring:
//!
//! ```text
//! (sin u)′ = u′ cos u      (cos u)′ = −u′ sin u     (tan u)′ = u′ (1 + tan² u)
//! (sinh u)′ = u′ cosh u    (cosh u)′ = u′ sinh u    (tanh u)′ = u′ (1 − tanh² u)
//! (exp u)′ = u′ exp u
//! ```
//!
//! The normal form applies, until none is left: sin² u → 1 − cos² u; cosh² u → 1 + sinh² u;
//! exp u · exp v → exp(u + v) and exp(u + c) → e^c exp u for a constant c; an odd function of
//! an argument whose first term is negative becomes minus the function of the negated argument
//! (an even one, the function of the negated argument); a function of a constant is
//! evaluated (by `libm`, as the evaluator does). A coefficient that cancels to below 10⁻¹²
//! of the largest term summed into it is dropped as rounding.
//!
//! Soundness: equal normal forms mean equal functions on all of Rⁿ. The converse fails —
//! sin 2x and 2 sin x cos x have different normal forms — so a normal form that keeps a
//! function atom proves nothing about the function's shape. A normal form without one is the
//! polynomial itself, and then its degree is exact. Other functions of a non-constant (sqrt,
//! ln, atan, abs, erf, …), non-integer or negative powers of a non-constant and division by a
//! non-constant have no normal form here: [`parse`] returns [`Unsupported`] saying which.

use alloc::boxed::Box;
use alloc::collections::BTreeMap;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec;
use alloc::vec::Vec;
use core::cmp::Ordering;
use core::fmt;

use super::syntax::{Function, Node, Op, Syntax};

/// Most terms a normal form may have; larger expressions are [`Unsupported`].
pub(crate) const MAX_TERMS: usize = 4096;
/// Largest integer power of a non-constant expanded.
pub(crate) const MAX_POWER: u32 = 64;

/// Most term-by-term products one multiplication may form.
const MAX_PRODUCTS: usize = 1 << 18;

/// A sum below this fraction of its largest term is rounding (cancellation to zero).
const ROUNDING: f64 = 1e-12;

/// Why an expression has no normal form.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Unsupported(pub String);

impl fmt::Display for Unsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

type Sym = Result<Poly, Unsupported>;

/// The elementary functions kept as atoms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Elementary {
    /// sin
    Sin,
    /// cos
    Cos,
    /// tan
    Tan,
    /// sinh
    Sinh,
    /// cosh
    Cosh,
    /// tanh
    Tanh,
    /// exp
    Exp,
}

/// Symmetry of a function under `u ↦ −u`.
enum Parity {
    Odd,
    Even,
    Neither,
}

impl Elementary {
    const ALL: [Elementary; 7] = [
        Elementary::Sin,
        Elementary::Cos,
        Elementary::Tan,
        Elementary::Sinh,
        Elementary::Cosh,
        Elementary::Tanh,
        Elementary::Exp,
    ];

    /// The name in expressions.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Elementary::Sin => "sin",
            Elementary::Cos => "cos",
            Elementary::Tan => "tan",
            Elementary::Sinh => "sinh",
            Elementary::Cosh => "cosh",
            Elementary::Tanh => "tanh",
            Elementary::Exp => "exp",
        }
    }

    /// Its value at `v`, as the evaluator computes it.
    pub(crate) fn value(self, v: f64) -> f64 {
        (Function::named(self.name())
            .expect("a function of the language")
            .apply)(v)
    }

    fn parity(self) -> Parity {
        match self {
            Elementary::Cos | Elementary::Cosh => Parity::Even,
            Elementary::Exp => Parity::Neither,
            _ => Parity::Odd,
        }
    }
}

/// A variable `x_i` or an elementary function of a normal form.
#[derive(Clone, Debug)]
pub(crate) enum Atom {
    /// The state variable `x_{i+1}`.
    Var(usize),
    /// `f(u)`, u in normal form and not constant.
    Apply(Elementary, Box<Poly>),
}

impl Ord for Atom {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self, other) {
            (Atom::Var(a), Atom::Var(b)) => a.cmp(b),
            (Atom::Var(_), Atom::Apply(..)) => Ordering::Less,
            (Atom::Apply(..), Atom::Var(_)) => Ordering::Greater,
            (Atom::Apply(f, u), Atom::Apply(g, v)) => f.cmp(g).then_with(|| u.cmp(v)),
        }
    }
}
impl PartialOrd for Atom {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl PartialEq for Atom {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Atom {}

/// A product of atoms with positive exponents, sorted by atom, each atom once.
pub(crate) type Monomial = Vec<(Atom, u32)>;

/// The product of two monomials.
fn times(a: &[(Atom, u32)], b: &[(Atom, u32)]) -> Monomial {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            Ordering::Less => {
                out.push(a[i].clone());
                i += 1;
            }
            Ordering::Greater => {
                out.push(b[j].clone());
                j += 1;
            }
            Ordering::Equal => {
                out.push((a[i].0.clone(), a[i].1 + b[j].1));
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// `m` with the exponent of its `idx`-th atom lowered by `by` (the atom dropped at zero).
fn lowered(m: &[(Atom, u32)], idx: usize, by: u32) -> Monomial {
    let mut out = m.to_vec();
    if out[idx].1 == by {
        out.remove(idx);
    } else {
        out[idx].1 -= by;
    }
    out
}

/// A normal form: terms sorted by monomial, no zero coefficient.
#[derive(Clone, Debug, Default)]
pub(crate) struct Poly {
    terms: Vec<(Monomial, f64)>,
}

impl Ord for Poly {
    fn cmp(&self, other: &Self) -> Ordering {
        for ((ma, ca), (mb, cb)) in self.terms.iter().zip(&other.terms) {
            let o = ma.cmp(mb).then_with(|| ca.total_cmp(cb));
            if o != Ordering::Equal {
                return o;
            }
        }
        self.terms.len().cmp(&other.terms.len())
    }
}
impl PartialOrd for Poly {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl PartialEq for Poly {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Poly {}

impl Poly {
    /// The constant `c`.
    pub(crate) fn constant(c: f64) -> Poly {
        Poly::monomial(Vec::new(), c)
    }

    /// The state variable `x_{i+1}`.
    pub(crate) fn variable(i: usize) -> Poly {
        Poly::monomial(vec![(Atom::Var(i), 1)], 1.0)
    }

    /// `c · m` for a monomial already in normal form.
    fn monomial(m: Monomial, c: f64) -> Poly {
        Poly {
            terms: if c == 0.0 { Vec::new() } else { vec![(m, c)] },
        }
    }

    /// The terms: each monomial with its coefficient.
    pub(crate) fn terms(&self) -> impl Iterator<Item = (&[(Atom, u32)], f64)> {
        self.terms.iter().map(|(m, c)| (m.as_slice(), *c))
    }

    /// The value when the normal form is a constant.
    pub(crate) fn as_constant(&self) -> Option<f64> {
        match self.terms.as_slice() {
            [] => Some(0.0),
            [(m, c)] if m.is_empty() => Some(*c),
            _ => None,
        }
    }

    /// True when no function atom is left: the normal form is a polynomial in x.
    pub(crate) fn is_polynomial(&self) -> bool {
        self.terms
            .iter()
            .all(|(m, _)| m.iter().all(|(a, _)| matches!(a, Atom::Var(_))))
    }

    /// The largest total exponent of a term (0 for constants).
    pub(crate) fn degree(&self) -> u32 {
        self.terms
            .iter()
            .map(|(m, _)| m.iter().map(|(_, k)| k).sum())
            .max()
            .unwrap_or(0)
    }

    /// `self + other` (sums of normal monomials need no rewriting; the sum can still exceed
    /// [`MAX_TERMS`] or overflow).
    pub(crate) fn add(&self, other: &Poly) -> Sym {
        collect(self.terms.iter().chain(&other.terms).cloned(), false)
    }

    /// `c · self`.
    pub(crate) fn scale(&self, c: f64) -> Poly {
        if c == 0.0 {
            return Poly::default();
        }
        Poly {
            terms: self.terms.iter().map(|(m, v)| (m.clone(), v * c)).collect(),
        }
    }

    /// `self · other`.
    pub(crate) fn mul(&self, other: &Poly) -> Sym {
        if self.terms.len().saturating_mul(other.terms.len()) > MAX_PRODUCTS {
            return Err(too_large());
        }
        let products = self.terms.iter().flat_map(|(ma, ca)| {
            other
                .terms
                .iter()
                .map(move |(mb, cb)| (times(ma, mb), ca * cb))
        });
        collect(products, true)
    }

    /// `selfᵏ`.
    pub(crate) fn pow(&self, k: u32) -> Sym {
        let mut result = Poly::constant(1.0);
        let mut square = self.clone();
        let mut k = k;
        while k > 0 {
            if k & 1 == 1 {
                result = result.mul(&square)?;
            }
            k >>= 1;
            if k > 0 {
                square = square.mul(&square)?;
            }
        }
        Ok(result)
    }

    /// `f(arg)` in normal form.
    pub(crate) fn apply(f: Elementary, arg: Poly) -> Sym {
        if let Some(c) = arg.as_constant() {
            return finite_constant(f.value(c), f.name());
        }
        let negative_lead = arg.terms[0].1 < 0.0;
        match f.parity() {
            Parity::Odd if negative_lead => Ok(Poly::apply(f, arg.scale(-1.0))?.scale(-1.0)),
            Parity::Even if negative_lead => Poly::apply(f, arg.scale(-1.0)),
            Parity::Neither => {
                // exp(u + c) = e^c exp(u).
                let c = arg.terms.iter().find(|(m, _)| m.is_empty()).map(|t| t.1);
                let c = c.unwrap_or(0.0);
                let factor = libm::exp(c);
                if !factor.is_finite() {
                    return Err(Unsupported(format!("exp({c}) is not finite")));
                }
                let atom = Atom::Apply(f, Box::new(arg.add(&Poly::constant(-c))?));
                Ok(Poly::monomial(vec![(atom, 1)], factor))
            }
            _ => Ok(Poly::monomial(
                vec![(Atom::Apply(f, Box::new(arg)), 1)],
                1.0,
            )),
        }
    }

    /// `∂/∂x_{i+1}`.
    pub(crate) fn derivative(&self, i: usize) -> Sym {
        let mut total = Poly::default();
        for (m, c) in &self.terms {
            for (idx, (atom, k)) in m.iter().enumerate() {
                let inner = atom_derivative(atom, i)?;
                if inner.terms.is_empty() {
                    continue;
                }
                let rest = Poly::monomial(lowered(m, idx, 1), c * f64::from(*k));
                total = total.add(&rest.mul(&inner)?)?;
            }
        }
        Ok(total)
    }

    /// The normal form written as an expression in the state variables of an `n`-dimensional
    /// model (`x` when n = 1), which [`parse`] reads back to the same normal form.
    pub(crate) fn display(&self, n: usize) -> impl fmt::Display + '_ {
        Shown { poly: self, n }
    }
}

/// The derivative of one atom.
fn atom_derivative(atom: &Atom, i: usize) -> Sym {
    let (f, u) = match atom {
        Atom::Var(j) => return Ok(Poly::constant(if *j == i { 1.0 } else { 0.0 })),
        Atom::Apply(f, u) => (*f, u.as_ref()),
    };
    let du = u.derivative(i)?;
    if du.terms.is_empty() {
        return Ok(du);
    }
    let same = || Poly::apply(f, u.clone());
    let one = Poly::constant(1.0);
    let outer = match f {
        Elementary::Sin => Poly::apply(Elementary::Cos, u.clone())?,
        Elementary::Cos => Poly::apply(Elementary::Sin, u.clone())?.scale(-1.0),
        Elementary::Tan => one.add(&same()?.pow(2)?)?,
        Elementary::Sinh => Poly::apply(Elementary::Cosh, u.clone())?,
        Elementary::Cosh => Poly::apply(Elementary::Sinh, u.clone())?,
        Elementary::Tanh => one.add(&same()?.pow(2)?.scale(-1.0))?,
        Elementary::Exp => same()?,
    };
    outer.mul(&du)
}

fn too_large() -> Unsupported {
    Unsupported(format!("its normal form exceeds {MAX_TERMS} terms"))
}

fn overflowed() -> Unsupported {
    Unsupported("a coefficient of its normal form is not finite".into())
}

fn finite_constant(v: f64, what: &str) -> Sym {
    if v.is_finite() {
        Ok(Poly::constant(v))
    } else {
        Err(Unsupported(format!("`{what}` of a constant is not finite")))
    }
}

/// Sums like terms, applying the module doc's rewriting when `rewrite`.
fn collect(terms: impl Iterator<Item = (Monomial, f64)>, rewrite: bool) -> Sym {
    // Per monomial: the sum and the largest contribution to it.
    let mut sum: BTreeMap<Monomial, (f64, f64)> = BTreeMap::new();
    let mut pending: Vec<(Monomial, f64)> = Vec::new();
    for term in terms {
        pending.push(term);
        while let Some((m, c)) = pending.pop() {
            if c == 0.0 {
                continue;
            }
            match if rewrite { rewritten(&m)? } else { None } {
                Some(parts) => pending.extend(parts.into_iter().map(|(p, v)| (p, v * c))),
                None => {
                    let (total, largest) = sum.entry(m).or_insert((0.0, 0.0));
                    *total += c;
                    *largest = largest.max(c.abs());
                }
            }
            if sum.len() + pending.len() > 4 * MAX_TERMS {
                return Err(too_large());
            }
        }
    }
    if sum.values().any(|(c, _)| !c.is_finite()) {
        return Err(overflowed());
    }
    let terms: Vec<(Monomial, f64)> = sum
        .into_iter()
        .filter(|(_, (c, largest))| c.abs() > ROUNDING * largest)
        .map(|(m, (c, _))| (m, c))
        .collect();
    if terms.len() > MAX_TERMS {
        return Err(too_large());
    }
    Ok(Poly { terms })
}

/// One rewriting step of the normal form for monomial `m`, or None when it is normal.
fn rewritten(m: &[(Atom, u32)]) -> Result<Option<Vec<(Monomial, f64)>>, Unsupported> {
    let is_exp = |a: &Atom| matches!(a, Atom::Apply(Elementary::Exp, _));
    let exps: Vec<u32> = m.iter().filter(|(a, _)| is_exp(a)).map(|t| t.1).collect();
    if exps.len() > 1 || exps.iter().any(|&k| k > 1) {
        let mut argument = Poly::default();
        let mut rest = Vec::new();
        for (a, k) in m {
            match a {
                Atom::Apply(Elementary::Exp, u) => {
                    argument = argument.add(&u.scale(f64::from(*k)))?
                }
                _ => rest.push((a.clone(), *k)),
            }
        }
        let merged = Poly::apply(Elementary::Exp, argument)?;
        return Ok(Some(
            merged
                .terms
                .iter()
                .map(|(e, c)| (times(&rest, e), *c))
                .collect(),
        ));
    }
    for (idx, (a, k)) in m.iter().enumerate() {
        let (partner, sign) = match a {
            Atom::Apply(Elementary::Sin, _) if *k >= 2 => (Elementary::Cos, -1.0),
            Atom::Apply(Elementary::Cosh, _) if *k >= 2 => (Elementary::Sinh, 1.0),
            _ => continue,
        };
        let Atom::Apply(_, u) = a else { continue };
        let lower = lowered(m, idx, 2);
        let square = [(Atom::Apply(partner, u.clone()), 2)];
        return Ok(Some(vec![(times(&lower, &square), sign), (lower, 1.0)]));
    }
    Ok(None)
}

/// The normal form of the text expression `text` in the state variables of an
/// `n`-dimensional model.
pub(crate) fn parse(text: &str, n: usize) -> Sym {
    let syntax = Syntax::parse(text, n).map_err(|e| Unsupported(e.to_string()))?;
    // Children come before their parents: one pass, each child taken by its one parent.
    let mut forms: Vec<Option<Poly>> = Vec::with_capacity(syntax.nodes.len());
    let take = |forms: &mut Vec<Option<Poly>>, id: usize| forms[id].take().expect("a tree");
    for node in &syntax.nodes {
        let form = match *node {
            Node::Number(v) => Poly::constant(v),
            Node::Variable(j) => Poly::variable(j),
            Node::Negate(a) => take(&mut forms, a).scale(-1.0),
            Node::Call(f, a) => function(f, take(&mut forms, a))?,
            Node::Binary(op, a, b) => {
                let (a, b) = (take(&mut forms, a), take(&mut forms, b));
                match op {
                    Op::Add => a.add(&b)?,
                    Op::Sub => a.add(&b.scale(-1.0))?,
                    Op::Mul => a.mul(&b)?,
                    Op::Div => divide(a, b)?,
                    Op::Pow => raise(a, b)?,
                }
            }
        };
        forms.push(Some(form));
    }
    Ok(take(&mut forms, syntax.root))
}

/// `a / b`, for a non-zero constant b.
fn divide(a: Poly, b: Poly) -> Sym {
    match b.as_constant() {
        Some(c) if c != 0.0 => {
            let quotient = a.scale(1.0 / c);
            if quotient.terms.iter().any(|(_, v)| !v.is_finite()) {
                return Err(overflowed());
            }
            Ok(quotient)
        }
        _ => Err(Unsupported("division by a non-constant".into())),
    }
}

/// `f(argument)`.
fn function(f: Function, argument: Poly) -> Sym {
    let name = f.name;
    if let Some(g) = Elementary::ALL.iter().find(|g| g.name() == name) {
        return Poly::apply(*g, argument);
    }
    match argument.as_constant() {
        Some(c) => finite_constant((f.apply)(c), name),
        None => Err(Unsupported(format!(
            "`{name}` of a non-constant has no normal form"
        ))),
    }
}

/// `base ^ exponent`.
fn raise(base: Poly, exponent: Poly) -> Sym {
    match (base.as_constant(), exponent.as_constant()) {
        (Some(b), Some(k)) => finite_constant(libm::pow(b, k), "^"),
        (_, Some(k)) if k >= 0.0 && libm::trunc(k) == k && k <= f64::from(MAX_POWER) => {
            base.pow(k as u32)
        }
        (_, Some(k)) => Err(Unsupported(format!(
            "the power {k} of a non-constant has no normal form (integers 0 to {MAX_POWER} have)"
        ))),
        (Some(b), None) if b > 0.0 => Poly::apply(Elementary::Exp, exponent.scale(libm::log(b))),
        _ => Err(Unsupported(
            "a non-constant power of a non-constant or non-positive base".into(),
        )),
    }
}

/// [`Poly::display`]'s value.
struct Shown<'a> {
    poly: &'a Poly,
    n: usize,
}

impl fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.poly.terms.is_empty() {
            return f.write_str("0");
        }
        for (t, (m, c)) in self.poly.terms.iter().enumerate() {
            let sign = if *c < 0.0 { "-" } else { "+" };
            match (t, sign) {
                (0, "-") => f.write_str("-")?,
                (0, _) => {}
                _ => write!(f, " {sign} ")?,
            }
            let magnitude = c.abs();
            if m.is_empty() || magnitude != 1.0 {
                write!(f, "{magnitude}")?;
                if !m.is_empty() {
                    f.write_str("*")?;
                }
            }
            for (j, (atom, k)) in m.iter().enumerate() {
                if j > 0 {
                    f.write_str("*")?;
                }
                match atom {
                    Atom::Var(i) if self.n == 1 && *i == 0 => f.write_str("x")?,
                    Atom::Var(i) => write!(f, "x{}", i + 1)?,
                    Atom::Apply(g, u) => write!(f, "{}({})", g.name(), u.display(self.n))?,
                }
                if *k > 1 {
                    write!(f, "^{k}")?;
                }
            }
        }
        Ok(())
    }
}

/// The fuzz target's property of the normal form (fuzz/fuzz_targets/expression.rs, through
/// `zakai::fuzzing`): `text` in `n` variables either is refused with a reason, or has a normal
/// form whose display reads back to the same form and whose derivative in every variable
/// exists or is refused. Panics, naming the text, when it does not hold.
#[cfg(any(test, fuzzing))]
pub(crate) fn check_normal_form(text: &str, n: usize) {
    use alloc::string::ToString;
    match parse(text, n) {
        Ok(p) => {
            let shown = p.display(n).to_string();
            let again = parse(&shown, n)
                .unwrap_or_else(|e| panic!("{text}: its display {shown} does not read back: {e}"));
            assert!(again == p, "{text}: {shown} reads back differently");
            for j in 0..n {
                let _ = p.derivative(j);
            }
        }
        Err(e) => assert!(!e.0.is_empty(), "{text}: refused without a reason"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The fuzz target's property on texts of each kind: polynomials, elementary functions
    /// of them, quotients, powers, refused and malformed text.
    #[test]
    fn normal_forms_read_back_from_their_display() {
        for (text, n) in [
            ("(x + 1)^2", 1),
            ("x1*x2 - 3*x2^3", 2),
            ("sin(x) + cos(2*x)", 1),
            ("exp(-x1^2)*x3", 3),
            ("1/(1 + x^2)", 1),
            ("sqrt(abs(x))", 1),
            ("x^^3", 1),
            ("y + 1", 1),
            ("", 2),
        ] {
            check_normal_form(text, n);
        }
    }

    fn form(text: &str, n: usize) -> Poly {
        parse(text, n).unwrap_or_else(|e| panic!("{text}: {e}"))
    }

    fn shown(text: &str, n: usize) -> String {
        form(text, n).display(n).to_string()
    }

    #[test]
    fn polynomials_expand_to_their_coefficients() {
        assert_eq!(shown("(x + 1)^2", 1), "1 + 2*x + x^2");
        assert_eq!(shown("(x1 - x2)*(x1 + x2)", 2), "x1^2 - x2^2");
        assert_eq!(shown("-x^2 + 3/2", 1), "1.5 - x^2");
        assert_eq!(shown("2^3*x - 8*x", 1), "0");
        assert_eq!(form("(x + 1)^6", 1).degree(), 6);
        assert_eq!(form("(x + 1)^6", 1).terms().count(), 7);
    }

    #[test]
    fn pythagorean_identities_reduce() {
        assert_eq!(shown("x*sin(x)*x*sin(x) + (x*cos(x))^2", 1), "x^2");
        assert_eq!(shown("cosh(2*x)^2 - sinh(2*x)^2", 1), "1");
        assert_eq!(shown("sin(-x)^2 + cos(-x)^2", 1), "1");
        assert_eq!(shown("sin(-x) + sin(x)", 1), "0");
        assert_eq!(shown("exp(x)*exp(-x)", 1), "1");
        let e = form("exp(x + 1)*exp(-x)", 1)
            .as_constant()
            .expect("constant");
        assert!((e - core::f64::consts::E).abs() < 1e-15);
        assert_eq!(
            shown("2^x", 1),
            form("exp(0.6931471805599453*x)", 1).display(1).to_string()
        );
    }

    #[test]
    fn derivatives_follow_the_chain_rule() {
        // (tanh x)′ + tanh² x = 1: 002's example 4.3 has η = 1 + x².
        let f = form("tanh(x)", 1);
        let eta = f.derivative(0).unwrap().add(&f.pow(2).unwrap()).unwrap();
        assert_eq!(eta.display(1).to_string(), "1");
        let g = form("x1^2*sin(x2) + exp(x1*x2)", 2);
        assert_eq!(
            g.derivative(1).unwrap().display(2).to_string(),
            "x1*exp(x1*x2) + x1^2*cos(x2)"
        );
        assert_eq!(shown("tan(x)", 1), "tan(x)");
        assert_eq!(
            form("tan(x)", 1)
                .derivative(0)
                .unwrap()
                .display(1)
                .to_string(),
            "1 + tan(x)^2"
        );
    }

    /// A normal form's value at x, atom by atom.
    fn value(p: &Poly, x: &[f64]) -> f64 {
        p.terms()
            .map(|(m, c)| {
                c * m
                    .iter()
                    .map(|(a, k)| {
                        let v = match a {
                            Atom::Var(i) => x[*i],
                            Atom::Apply(f, u) => f.value(value(u, x)),
                        };
                        libm::pow(v, f64::from(*k))
                    })
                    .product::<f64>()
            })
            .sum()
    }

    /// The normal form and the compiled program read the same tree: they agree in value.
    #[test]
    fn normal_forms_have_the_evaluators_values() {
        use crate::model::expression::ExpressionFunction;
        use crate::model::VectorFunction;
        let texts = [
            "-x1^2 + 2^-x2*3 - x1/2*x2",
            "exp(-(x1 - 1)^2/2) * sin(x2)^3 - cosh(x1)^2",
            "tanh(2*x1 - x2)^2 + tan(x2/4) - sinh(-x1)*E + 3^(2^1)",
            "x1^2^3",
            "(x1 - x2)^3/(2*PI) - -x2 + +x1",
        ];
        for text in texts {
            let Ok(f) = ExpressionFunction::parse("g", &[text.to_string()], 2, 1) else {
                // Chained powers are refused by both.
                assert!(parse(text, 2).is_err(), "{text}");
                continue;
            };
            let p = form(text, 2);
            for x in [[0.3, -1.2], [-0.7, 0.9], [1.4, 0.2]] {
                let want = f.value(&x)[0];
                let got = value(&p, &x);
                assert!(
                    (got - want).abs() < 1e-12 * (1.0 + want.abs()),
                    "{text} at {x:?}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn derivatives_agree_with_central_differences() {
        // Normal forms evaluated atom by atom, their derivatives against central differences.
        let eval = |p: &Poly, x: f64| value(p, &[x]);
        for text in [
            "sin(x)^3*cosh(x/2)",
            "tanh(x^2 - 1)*exp(-x)",
            "tan(x/3)^2 + sinh(x)^3",
        ] {
            let p = form(text, 1);
            let d = p.derivative(0).unwrap();
            for x in [-1.3, -0.2, 0.4, 1.1] {
                let h = 1e-5;
                let numeric = (eval(&p, x + h) - eval(&p, x - h)) / (2.0 * h);
                assert!(
                    (eval(&d, x) - numeric).abs() < 1e-7 * (1.0 + numeric.abs()),
                    "{text} at {x}: {} against {numeric}",
                    eval(&d, x)
                );
            }
        }
    }

    #[test]
    fn displayed_forms_read_back_unchanged() {
        for (text, n) in [
            ("x1^2*tanh(x2 - 0.3*x1) - exp(-x1)*cos(x2)^3 + 1e-3", 2),
            ("sin(x)^5 - cosh(3*x)^3 + tan(-x)", 1),
        ] {
            let p = form(text, n);
            assert_eq!(form(&p.display(n).to_string(), n), p, "{text}");
        }
    }

    #[test]
    fn what_has_no_normal_form_says_why() {
        for (text, why) in [
            ("sqrt(x)", "`sqrt` of a non-constant"),
            ("1/x", "division by a non-constant"),
            ("x^0.5", "the power 0.5"),
            ("x^x", "non-constant power"),
            ("erfc(0.5 - x)", "`erfc` of a non-constant"),
        ] {
            let e = parse(text, 1).expect_err(text);
            assert!(e.0.contains(why), "{text}: {e}");
        }
        // Every monomial of degree ≤ 40 in two variables: C(42, 2) = 861, the smallest
        // coefficient 1 beside the largest 40!/(13!·13!·14!) ≈ 10¹⁷, none lost as rounding.
        assert_eq!(form("(x1 + x2 + 1)^40", 2).terms().count(), 861);
        assert!(parse("(x1 + x2 + x3 + x4 + 1)^40", 4)
            .expect_err("too many terms")
            .0
            .contains("exceeds"));
        // Coefficients that overflow are refused, not dropped.
        // Sums are checked like products: too many terms or an overflowing coefficient is
        // refused, never a silently wrong sum.
        assert!(parse("(x1 + x2 + x3 + 1)^24 + (x2 + x3 + x4 + 1)^24", 4)
            .expect_err("2925 + 2925 − 325 terms")
            .0
            .contains("exceeds"));
        for text in ["(1e200*x + 1)^2", "x/1e-320", "1e308*x + 1e308*x"] {
            let e = parse(text, 1).expect_err(text);
            assert!(e.0.contains("not finite"), "{text}: {e}");
        }
        // Constants of any function are evaluated.
        assert_eq!(shown("sqrt(4)*x + abs(-1)", 1), "1 + 2*x");
    }
}
