//! Compiling a text expression into a [`Program`] by tracing exmex's own evaluation.
//!
//! The expression is parsed by exmex a second time with a value type, [`Trace`], whose
//! operators do not compute but record: evaluating the parsed expression once on traced
//! variables writes down every operation in exactly the order (and with exactly the operator
//! functions) in which exmex evaluates it for numbers. Operations on constants only are folded
//! with the same functions, so every value keeps the bits exmex's interpretation gives it; the
//! one deliberate change is `x^k` for an integer 0 ≤ k ≤ 4, recorded as multiplications
//! ([`Operation::PowI`], within 2 ulp of `libm::pow`).

use alloc::rc::Rc;
use alloc::string::{String, ToString};
use alloc::vec::Vec;
use core::cell::RefCell;
use core::str::FromStr;

use exmex::prelude::*;
use exmex::{BinOp, MakeOperators, Operator};

use super::expression::ZakaiOps;
use super::expression_error::variable_index;
use super::program::{Operand, Operation, Program, MAX_POWI};

/// The operations recorded so far, in single assignment form.
type Tape = Rc<RefCell<Vec<Operation>>>;

/// A value during tracing: a constant, or an operand (a state variable or a recorded value).
#[derive(Clone, Debug)]
pub(crate) enum Trace {
    Const(f64),
    Value(Tape, Operand),
}

impl Default for Trace {
    fn default() -> Self {
        Trace::Const(0.0)
    }
}

impl FromStr for Trace {
    type Err = core::num::ParseFloatError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        f64::from_str(s).map(Trace::Const)
    }
}

impl Trace {
    fn operand(&self) -> Operand {
        match self {
            Trace::Const(c) => Operand::Const(*c),
            Trace::Value(_, o) => *o,
        }
    }

    fn tape(&self) -> Option<&Tape> {
        match self {
            Trace::Const(_) => None,
            Trace::Value(t, _) => Some(t),
        }
    }

    fn constant(&self) -> f64 {
        match self {
            Trace::Const(c) => *c,
            Trace::Value(..) => f64::NAN,
        }
    }
}

/// Records `operation` on the tape of whichever argument has one; with constants only,
/// `fold` (exmex's own function for the operator) computes the value now.
fn record(operation: Operation, args: [&Trace; 2], fold: impl FnOnce(f64, f64) -> f64) -> Trace {
    match args.iter().find_map(|t| t.tape()) {
        None => Trace::Const(fold(args[0].constant(), args[1].constant())),
        Some(tape) => {
            let mut ops = tape.borrow_mut();
            ops.push(operation);
            Trace::Value(tape.clone(), Operand::Reg(ops.len() - 1))
        }
    }
}

/// Capacity of the tables of traced operator functions below; exmex's operator table with
/// ours has 44 entries (checked by a test).
const MAX_OPERATORS: usize = 64;

/// The operator at `index` in [`ZakaiOps`]' table.
fn zakai_operator(index: usize) -> Operator<'static, f64> {
    ZakaiOps::make().swap_remove(index)
}

/// The traced form of the binary operator at index K of [`ZakaiOps`]' table.
fn traced_binary<const K: usize>(a: Trace, b: Trace) -> Trace {
    let op = zakai_operator(K);
    let f = op.bin().expect("traced only for binary operators").apply;
    let (x, y) = (a.operand(), b.operand());
    let operation = match op.repr() {
        "+" => Operation::Add(x, y),
        "-" => Operation::Sub(x, y),
        "*" => Operation::Mul(x, y),
        "/" => Operation::Div(x, y),
        "^" => match y {
            Operand::Const(k) if k.fract() == 0.0 && (0.0..=MAX_POWI as f64).contains(&k) => {
                Operation::PowI(x, k as i32)
            }
            _ => Operation::Binary(f, x, y),
        },
        _ => Operation::Binary(f, x, y),
    };
    record(operation, [&a, &b], f)
}

/// The traced form of the unary operator at index K of [`ZakaiOps`]' table.
fn traced_unary<const K: usize>(a: Trace) -> Trace {
    let op = zakai_operator(K);
    let f = op.unary().expect("traced only for unary operators");
    let x = a.operand();
    let operation = match op.repr() {
        "+" => return a,
        "-" => Operation::Neg(x),
        _ => Operation::Unary(f, x),
    };
    record(operation, [&a, &a], |v, _| f(v))
}

macro_rules! indexed {
    ($f:ident; $($k:literal)*) => { [$($f::<$k> as _),*] };
}

const TRACED_BINARY: [fn(Trace, Trace) -> Trace; MAX_OPERATORS] = indexed!(traced_binary;
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31
    32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63);
const TRACED_UNARY: [fn(Trace) -> Trace; MAX_OPERATORS] = indexed!(traced_unary;
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31
    32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63);

/// [`ZakaiOps`] with every operator replaced by its traced form (same names, priorities and
/// commutativity, so exmex parses a text into the same structure).
#[derive(Clone, Debug)]
pub(crate) struct TraceOps;

impl MakeOperators<Trace> for TraceOps {
    fn make<'a>() -> Vec<Operator<'a, Trace>> {
        let ops = ZakaiOps::make();
        assert!(ops.len() <= MAX_OPERATORS, "raise MAX_OPERATORS");
        ops.iter()
            .enumerate()
            .map(|(k, op)| {
                if let Some(c) = op.constant() {
                    return Operator::make_constant(op.repr(), Trace::Const(c));
                }
                let bin = op.bin().ok().map(|b| BinOp {
                    apply: TRACED_BINARY[k],
                    prio: b.prio,
                    is_commutative: b.is_commutative,
                });
                match (bin, op.has_unary()) {
                    (Some(b), true) => Operator::make_bin_unary(op.repr(), b, TRACED_UNARY[k]),
                    (Some(b), false) => Operator::make_bin(op.repr(), b),
                    (None, _) => Operator::make_unary(op.repr(), TRACED_UNARY[k]),
                }
            })
            .collect()
    }
}

/// Compiles a text exmex accepts (a normalised user expression, or the unparsed text of an
/// exmex derivative) in the state variables of an `n`-dimensional model.
pub(crate) fn compile(text: &str, n: usize) -> Result<Program, String> {
    let ex = FlatEx::<Trace, TraceOps>::parse(text).map_err(|e| e.msg().to_string())?;
    let tape: Tape = Rc::new(RefCell::new(Vec::new()));
    let args = ex
        .var_names()
        .iter()
        .map(|name| {
            variable_index(name, n)
                .map(|j| Trace::Value(tape.clone(), Operand::Var(j)))
                .ok_or_else(|| alloc::format!("unknown variable {name}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let result = ex.eval(&args).map_err(|e| e.msg().to_string())?;
    let ssa = tape.borrow();
    Ok(Program::from_ssa(&ssa, result.operand()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

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
    fn the_operator_table_fits() {
        assert!(ZakaiOps::make().len() <= MAX_OPERATORS);
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
