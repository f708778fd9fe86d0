//! Errors of text expressions, and the position-aware lexical check that produces them.
//!
//! The expression parser itself is the `exmex` crate (feature `std`); exmex reports errors
//! without a position, so before handing a text to it we scan it once here and report the
//! common mistakes — a stray character, unbalanced parentheses, a missing operand or operator,
//! an unknown name, a constant that overflows — with the character position a user can fix.

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;
use core::fmt;

/// Functions an expression may call. All have exact derivatives except `abs`, `signum`,
/// `floor`, `ceil`, `round`, `trunc`, `fract`, `erf`, `erfc` (numerical derivatives).
pub const FUNCTIONS: &[&str] = &[
    "abs", "signum", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh",
    "acosh", "atanh", "floor", "round", "ceil", "trunc", "fract", "exp", "sqrt", "cbrt", "ln",
    "log", "log2", "log10", "erf", "erfc",
];

/// Named constants an expression may use.
pub const CONSTANTS: &[&str] = &["PI", "pi", "E", "e", "TAU"];

/// An invalid text expression. `position` counts characters from 0.
#[derive(Clone, Debug, PartialEq)]
pub enum ExprError {
    /// The text does not parse.
    Syntax {
        /// The expression text.
        expr: String,
        /// Character position of the problem, when known.
        position: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A name that is neither a state variable, a function nor a constant.
    UnknownVariable {
        /// The expression text.
        expr: String,
        /// The unknown name.
        name: String,
        /// Character position where it starts.
        position: usize,
        /// The allowed variable names.
        allowed: String,
    },
    /// A vector function has the wrong number of components.
    WrongComponentCount {
        /// Which function (e.g. "drift f").
        what: String,
        /// Expected count.
        expected: usize,
        /// Given count.
        found: usize,
    },
    /// A numeric constant that is not finite (e.g. `1e400`).
    NonFiniteConstant {
        /// The expression text.
        expr: String,
        /// The literal as written.
        literal: String,
        /// Character position where it starts.
        position: usize,
    },
    /// The expression layer is not available (built without the `std` feature).
    Unavailable,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExprError::Syntax {
                expr,
                position: Some(p),
                message,
            } => write!(f, "syntax error at position {p} in `{expr}`: {message}"),
            ExprError::Syntax {
                expr,
                position: None,
                message,
            } => write!(f, "syntax error in `{expr}`: {message}"),
            ExprError::UnknownVariable {
                expr,
                name,
                position,
                allowed,
            } => write!(
                f,
                "unknown variable `{name}` at position {position} in `{expr}` (allowed: {allowed})"
            ),
            ExprError::WrongComponentCount {
                what,
                expected,
                found,
            } => write!(f, "{what} needs {expected} component(s), {found} given"),
            ExprError::NonFiniteConstant {
                expr,
                literal,
                position,
            } => write!(
                f,
                "constant `{literal}` at position {position} in `{expr}` is not a finite number"
            ),
            ExprError::Unavailable => write!(f, "text expressions need the `std` feature of zakai"),
        }
    }
}

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

#[derive(Clone, Copy, PartialEq, Debug)]
enum Token {
    Operand,
    Function,
    Open,
    Close,
    Operator,
    Comma,
}

/// Checks `text` for the mistakes listed in the module doc, for a model with `n` state
/// variables, and returns it normalised for exmex (numeric literals in plain decimal form,
/// since exmex does not read exponents such as `2.5e-3`).
pub fn normalize_expression(text: &str, n: usize) -> Result<String, ExprError> {
    let mut normalized = String::with_capacity(text.len());
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
    let mut open: Vec<usize> = Vec::new();
    let mut prev: Option<(Token, usize)> = None;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        let token = if c.is_whitespace() {
            normalized.push(c);
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
                Ok(v) if v.is_finite() => normalized.push_str(&format!("{v}")),
                Ok(_) => {
                    return Err(ExprError::NonFiniteConstant {
                        expr: text.to_string(),
                        literal,
                        position: start,
                    })
                }
                Err(_) => return Err(syntax(start, &format!("malformed number `{literal}`"))),
            }
            Token::Operand
        } else if c.is_ascii_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let name: String = chars[start..i].iter().collect();
            normalized.push_str(&name);
            if FUNCTIONS.contains(&name.as_str()) {
                Token::Function
            } else if CONSTANTS.contains(&name.as_str()) || variable_index(&name, n).is_some() {
                Token::Operand
            } else {
                return Err(ExprError::UnknownVariable {
                    expr: text.to_string(),
                    name,
                    position: start,
                    allowed: variable_names(n).join(", "),
                });
            }
        } else {
            i += 1;
            normalized.push(c);
            match c {
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
            }
        };
        check_adjacent(prev, token, start, c).map_err(|m| syntax(start, m))?;
        prev = Some((token, start));
    }
    if let Some(p) = open.pop() {
        return Err(syntax(p, "`(` is never closed"));
    }
    match prev {
        Some((Token::Operator, p)) => Err(syntax(p, "an operator needs an operand after it")),
        Some((Token::Function, p)) => Err(syntax(p, "a function name must be followed by `(`")),
        _ => Ok(normalized),
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

    fn position(e: ExprError) -> Option<usize> {
        match e {
            ExprError::Syntax { position, .. } => position,
            ExprError::UnknownVariable { position, .. } => Some(position),
            ExprError::NonFiniteConstant { position, .. } => Some(position),
            _ => None,
        }
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
        assert_eq!(normalize_expression("1E2 + x", 1).unwrap(), "100 + x");
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
