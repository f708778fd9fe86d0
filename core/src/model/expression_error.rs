//! Errors of text expressions, and the position-aware lexical check that produces them.
//!
//! The expression parser itself is the `exmex` crate (feature `std`); exmex reports errors
//! without a position, so before handing a text to it we scan it once here and report the
//! common mistakes — a stray character, unbalanced parentheses, a missing operand or operator,
//! an unknown name, a constant that overflows — with the character position a user can fix.

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec;
use alloc::vec::Vec;

/// Functions an expression may call. All have exact derivatives except `abs`, `signum`,
/// `floor`, `ceil`, `round`, `trunc`, `fract`, `erf`, `erfc` (numerical derivatives).
pub const FUNCTIONS: &[&str] = &[
    "abs", "signum", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh",
    "acosh", "atanh", "floor", "round", "ceil", "trunc", "fract", "exp", "sqrt", "cbrt", "ln",
    "log", "log2", "log10", "erf", "erfc",
];

/// A real function of one real variable.
pub(crate) type RealFn = fn(f64) -> f64;

/// The unary functions, by name, as computed by `libm` (the expression evaluator's, and the
/// symbolic normal form's for constant arguments; `signum` and `fract` are exmex's own).
pub(crate) const LIBM_UNARY: &[(&str, RealFn)] = &[
    ("abs", libm::fabs),
    ("sin", libm::sin),
    ("cos", libm::cos),
    ("tan", libm::tan),
    ("asin", libm::asin),
    ("acos", libm::acos),
    ("atan", libm::atan),
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
    ("exp", libm::exp),
    ("sqrt", libm::sqrt),
    ("cbrt", libm::cbrt),
    ("ln", libm::log),
    ("log", libm::log),
    ("log2", libm::log2),
    ("log10", libm::log10),
    ("erf", libm::erf),
    ("erfc", libm::erfc),
];

/// Named constants an expression may use.
pub const CONSTANTS: &[&str] = &["PI", "pi", "E", "e", "TAU"];

pub use crate::error::ExprError;

/// The state variable names of an `n`-dimensional model: `x1..xn`, and `x` when `n = 1`.
pub fn variable_names(n: usize) -> Vec<String> {
    let mut names: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    if n == 1 {
        names.push("x".to_string());
    }
    names
}

/// Index of the state variable `name` (`x` ↦ 0 when n = 1), if it is one.
pub fn variable_index(name: &str, n: usize) -> Option<usize> {
    if n == 1 && name == "x" {
        return Some(0);
    }
    let i: usize = name.strip_prefix('x')?.parse().ok()?;
    (i >= 1 && i <= n && !name[1..].starts_with('0')).then(|| i - 1)
}

/// The kind of a token.
#[derive(Clone, Copy, PartialEq, Debug)]
pub(crate) enum Token {
    Operand,
    Function,
    Open,
    Close,
    Operator,
    Comma,
}

/// Checks `text` for the mistakes listed in the module doc, for a model with `n` state
/// variables, and returns it rewritten for exmex with the usual mathematical conventions:
///
/// * numeric literals in plain decimal form (exmex does not read exponents such as `2.5e-3`);
/// * a leading minus binds looser than `^`: `-x^2` is `-(x^2)` and `exp(-(x-1)^2)` is
///   `exp(-((x-1)^2))` (exmex alone would square the negated operand);
/// * chained powers `a^b^c` are refused with a message asking for parentheses (exmex would
///   read them left to right, the opposite of the usual right-to-left convention).
pub fn normalize_expression(text: &str, n: usize) -> Result<String, ExprError> {
    let syntax = |position: usize, message: &str| ExprError::Syntax {
        expr: text.to_string(),
        position: Some(position),
        message: message.to_string(),
    };
    if let Some((position, _)) = text.char_indices().nth(MAX_EXPRESSION_CHARS) {
        return Err(syntax(
            position,
            &format!("longer than {MAX_EXPRESSION_CHARS} characters"),
        ));
    }
    let tokens = tokenize(text, n)?;
    // Nesting (parentheses and stacked signs, each of which becomes a level below): exmex
    // differentiates recursively, and a few hundred levels overflow the 1 MiB stack of wasm
    // (found by fuzzing: `x1^-----…`).
    let (mut depth, mut signs) = (0usize, 0usize);
    for (i, t) in tokens.iter().enumerate() {
        match t.kind {
            Token::Open => depth += 1,
            Token::Close => depth = depth.saturating_sub(1),
            _ => {}
        }
        signs = if is_unary_sign(&tokens, i) {
            signs + 1
        } else {
            0
        };
        if depth + signs > MAX_NESTING {
            return Err(syntax(
                t.position,
                &format!("nests deeper than {MAX_NESTING} levels of parentheses and signs"),
            ));
        }
    }
    // Chained powers: `^` whose left operand already ends a power `a^b`.
    let mut depth_of_last_power: Vec<Option<usize>> = vec![None];
    for (i, t) in tokens.iter().enumerate() {
        match t.kind {
            Token::Open => depth_of_last_power.push(None),
            Token::Close => {
                depth_of_last_power.pop();
            }
            Token::Operator if t.text == "^" => {
                let last = depth_of_last_power.last_mut().expect("balanced");
                if let Some(prev) = *last {
                    if operand_end(&tokens, prev + 1) == i {
                        return Err(syntax(
                            t.position,
                            "chained powers are ambiguous: write a^(b^c) or (a^b)^c",
                        ));
                    }
                }
                *last = Some(i);
            }
            _ => {}
        }
    }
    let mut out = String::with_capacity(text.len() + 8);
    let mut close_after: Vec<usize> = Vec::new();
    for (i, t) in tokens.iter().enumerate() {
        let prev = if i == 0 { None } else { Some(&tokens[i - 1]) };
        if is_unary_sign(&tokens, i) {
            match prev {
                // At the start of an expression or argument: `-a^b…` → `0-a^b…`.
                None
                | Some(Token_ {
                    kind: Token::Open | Token::Comma,
                    ..
                }) => {
                    out.push('0');
                    out.push_str(&t.text);
                }
                // After `^` exmex's tight unary minus is the convention: `2^-x` = 2^(−x).
                Some(p) if p.text == "^" => out.push_str(&t.text),
                // After another operator: wrap the signed power `(0-a^b)`.
                Some(_) => {
                    out.push_str("(0");
                    out.push_str(&t.text);
                    close_after.push(power_end(&tokens, i + 1));
                }
            }
        } else {
            out.push_str(&t.text);
        }
        while close_after.last() == Some(&(i + 1)) {
            close_after.pop();
            out.push(')');
        }
    }
    Ok(out)
}

/// Longest expression accepted, in characters.
pub const MAX_EXPRESSION_CHARS: usize = 1000;
/// Deepest nesting of parentheses and stacked unary signs accepted.
pub const MAX_NESTING: usize = 32;

/// Whether token `i` is a unary `+`/`−` (at the start, after `(`, `,` or another operator).
fn is_unary_sign(tokens: &[Token_], i: usize) -> bool {
    let t = &tokens[i];
    t.kind == Token::Operator
        && (t.text == "-" || t.text == "+")
        && (i == 0
            || matches!(
                tokens[i - 1].kind,
                Token::Open | Token::Comma | Token::Operator
            ))
}

/// One token with its text (already normalised) and character position.
#[derive(Clone, Debug)]
pub(crate) struct Token_ {
    pub(crate) kind: Token,
    pub(crate) text: String,
    pub(crate) position: usize,
}

/// Index one past the atom starting at `i` (a number, name, `( … )` or `f( … )`), skipping
/// leading unary signs.
fn operand_end(tokens: &[Token_], mut i: usize) -> usize {
    while i < tokens.len() && tokens[i].kind == Token::Operator {
        i += 1;
    }
    if i >= tokens.len() {
        return i;
    }
    if tokens[i].kind == Token::Function {
        i += 1;
    }
    if i < tokens.len() && tokens[i].kind == Token::Open {
        let mut depth = 0;
        while i < tokens.len() {
            match tokens[i].kind {
                Token::Open => depth += 1,
                Token::Close => {
                    depth -= 1;
                    if depth == 0 {
                        return i + 1;
                    }
                }
                _ => {}
            }
            i += 1;
        }
        return i;
    }
    i + 1
}

/// Index one past the power `atom [^ atom]` starting at `i` (chains were refused earlier).
fn power_end(tokens: &[Token_], i: usize) -> usize {
    let end = operand_end(tokens, i);
    if end < tokens.len() && tokens[end].text == "^" {
        operand_end(tokens, end + 1)
    } else {
        end
    }
}

/// Splits `text` into tokens, reporting lexical mistakes with their positions.
pub(crate) fn tokenize(text: &str, n: usize) -> Result<Vec<Token_>, ExprError> {
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
    let mut tokens: Vec<Token_> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        let (kind, token_text) = if c.is_whitespace() {
            i += 1;
            continue;
        } else if c.is_ascii_digit() || c == '.' {
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
            let literal: String = chars[start..i].iter().collect();
            match literal.parse::<f64>() {
                Ok(v) if v.is_finite() => (Token::Operand, format!("{v}")),
                Ok(_) => {
                    return Err(ExprError::NonFiniteConstant {
                        expr: text.to_string(),
                        literal,
                        position: start,
                    })
                }
                Err(_) => return Err(syntax(start, &format!("malformed number `{literal}`"))),
            }
        } else if c.is_ascii_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let name: String = chars[start..i].iter().collect();
            if FUNCTIONS.contains(&name.as_str()) {
                (Token::Function, name)
            } else if CONSTANTS.contains(&name.as_str()) || variable_index(&name, n).is_some() {
                (Token::Operand, name)
            } else {
                return Err(ExprError::UnknownVariable {
                    expr: text.to_string(),
                    name,
                    position: start,
                    allowed: variable_names(n).join(", "),
                });
            }
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            return Err(syntax(
                start,
                "`**` is not an operator here: write powers with `^`, e.g. x^3",
            ));
        } else {
            i += 1;
            let kind = match c {
                '(' => {
                    open.push(start);
                    Token::Open
                }
                ')' => {
                    if open.pop().is_none() {
                        return Err(syntax(start, "`)` without a matching `(`"));
                    }
                    Token::Close
                }
                '+' | '-' | '*' | '/' | '^' => Token::Operator,
                ',' => Token::Comma,
                _ => return Err(syntax(start, &format!("unexpected character `{c}`"))),
            };
            (kind, c.to_string())
        };
        let prev = tokens.last().map(|t| (t.kind, t.position));
        check_adjacent(prev, kind, start, c).map_err(|m| syntax(start, m))?;
        tokens.push(Token_ {
            kind,
            text: token_text,
            position: start,
        });
    }
    if let Some(p) = open.pop() {
        return Err(syntax(p, "`(` is never closed"));
    }
    match tokens.last() {
        Some(t) if t.kind == Token::Operator => {
            Err(syntax(t.position, "an operator needs an operand after it"))
        }
        Some(t) if t.kind == Token::Function => Err(syntax(
            t.position,
            "a function name must be followed by `(`",
        )),
        _ => Ok(tokens),
    }
}

fn check_adjacent(
    prev: Option<(Token, usize)>,
    token: Token,
    _pos: usize,
    c: char,
) -> Result<(), &'static str> {
    use Token::*;
    let Some((p, _)) = prev else {
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

    /// Python's power operator gets a hint at its position.
    #[test]
    fn double_star_suggests_the_caret() {
        let e = normalize_expression("2*x**3", 1).unwrap_err();
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
            assert!(normalize_expression(e, n).is_ok(), "{e}");
        }
    }

    #[test]
    fn mistakes_report_their_position() {
        assert_eq!(
            position(normalize_expression("x1 + $", 1).unwrap_err()),
            Some(5)
        );
        assert_eq!(
            position(normalize_expression("sin(x1", 1).unwrap_err()),
            Some(3)
        );
        assert_eq!(
            position(normalize_expression("x1 + y", 1).unwrap_err()),
            Some(5)
        );
        assert_eq!(
            position(normalize_expression("x1 *", 1).unwrap_err()),
            Some(3)
        );
        assert_eq!(
            position(normalize_expression("2 x1", 1).unwrap_err()),
            Some(2)
        );
        assert_eq!(
            position(normalize_expression("x3", 2).unwrap_err()),
            Some(0)
        );
        assert_eq!(
            position(normalize_expression("x + 1e999", 1).unwrap_err()),
            Some(4)
        );
        assert_eq!(
            position(normalize_expression("x)", 1).unwrap_err()),
            Some(1)
        );
        assert!(matches!(
            normalize_expression("x3", 2).unwrap_err(),
            ExprError::UnknownVariable { .. }
        ));
        assert!(matches!(
            normalize_expression("1e999", 1).unwrap_err(),
            ExprError::NonFiniteConstant { .. }
        ));
    }

    #[test]
    fn exponents_become_plain_decimals() {
        assert_eq!(normalize_expression("2.5e-3*x", 1).unwrap(), "0.0025*x");
        assert_eq!(normalize_expression("1E2 + x", 1).unwrap(), "100+x");
    }

    #[test]
    fn unary_minus_binds_looser_than_powers() {
        let norm = |t: &str| normalize_expression(t, 2).unwrap();
        assert_eq!(norm("-x1^2"), "0-x1^2");
        assert_eq!(norm("exp(-(x1-1)^2)"), "exp(0-(x1-1)^2)");
        assert_eq!(norm("3*-x1^2"), "3*(0-x1^2)");
        assert_eq!(norm("x1/-sin(x2)^2*4"), "x1/(0-sin(x2)^2)*4");
        assert_eq!(norm("2^-x1"), "2^-x1");
        assert_eq!(norm("x1 - -x2"), "x1-(0-x2)");
    }

    #[test]
    fn chained_powers_are_refused() {
        let e = normalize_expression("2^x1^2", 1).unwrap_err();
        assert_eq!(position(e), Some(4));
        assert!(normalize_expression("2^(x1^2)", 1).is_ok());
        assert!(normalize_expression("(2^x1)^2", 1).is_ok());
        assert!(normalize_expression("x1^2 + x1^3", 1).is_ok());
    }

    #[test]
    fn variable_names_follow_the_dimension() {
        assert_eq!(variable_index("x", 1), Some(0));
        assert_eq!(variable_index("x", 2), None);
        assert_eq!(variable_index("x2", 2), Some(1));
        assert_eq!(variable_index("x02", 2), None);
        assert_eq!(variable_index("x0", 2), None);
    }
}
