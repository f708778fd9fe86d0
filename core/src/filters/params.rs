//! A method's parameters, each declared once.
//!
//! A family declares its parameter struct with `parameters!`: every field once, with its
//! type, default, the kind of form field it is, its label, its help and its range. From that
//! one declaration come the struct (serde, with defaults, unknown fields refused), its rustdoc
//! (the help), `Default`, the form schema the CLI, the wasm crate and the page read
//! ([`ParamInfo`], through `form()`), the fields left to JSON (`json_only()`) and the range
//! checks (`range_problems()`). What a family checks beyond ranges — one field against
//! another, a grid against the memory cap — it adds in its own `problems`.
//!
//! ```text
//! parameters! {
//!     /// Parameters of [`Pf`].
//!     pub struct PfParams {
//!         /// Number of particles; the error falls like 1/√N.
//!         particles: usize = 200 => int "particles N", range(1, 1e7);
//!         …
//!     }
//! }
//! ```
//!
//! Kinds: `int`, `optional_int`, `number`, `int_list`, `number_list`, `choice` (an enum with
//! [`Choices`]) and `json` (not a form field: left to JSON and the Rust API). Bounds:
//! `range(min, max)`, `at_least(min)`, `above(min)` (strictly), `at_most(max)`, `below(max)`
//! (strictly); a number is
//! always checked to be finite. The generated functions are the [`Declared`] trait's, which
//! every method's parameters implement.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

/// The kind of a parameter's value, for forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamKind {
    /// An integer.
    Int,
    /// An integer, or absent for "chosen by the method".
    OptionalInt,
    /// A real number.
    Number,
    /// One integer per dimension (or one for all).
    IntList,
    /// A list of reals.
    NumberList,
    /// One of [`ParamInfo::choices`].
    Choice,
}

/// One parameter of a method, described for forms and documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamInfo {
    /// Field name in the method's JSON (`"particles"`).
    pub name: String,
    /// Short label (`"particles N"`).
    pub label: String,
    /// One-line explanation.
    pub help: String,
    /// Kind of value.
    pub kind: ParamKind,
    /// Smallest allowed value, where there is one.
    pub min: Option<f64>,
    /// Whether [`ParamInfo::min`] itself is excluded (a step must be above 0).
    #[serde(default)]
    pub min_exclusive: bool,
    /// Largest allowed value, where there is one.
    pub max: Option<f64>,
    /// Whether [`ParamInfo::max`] itself is excluded.
    #[serde(default)]
    pub max_exclusive: bool,
    /// The allowed values of a [`ParamKind::Choice`].
    pub choices: Vec<String>,
}

impl ParamInfo {
    /// A parameter of `kind` with a label and a one-line explanation.
    pub fn new(name: &str, kind: ParamKind, label: &str, help: &str) -> Self {
        ParamInfo {
            name: name.into(),
            label: label.into(),
            help: help.into(),
            kind,
            min: None,
            min_exclusive: false,
            max: None,
            max_exclusive: false,
            choices: Vec::new(),
        }
    }
    /// With the allowed range `[min, max]`.
    pub fn range(mut self, min: f64, max: f64) -> Self {
        self.min = Some(min);
        self.max = Some(max);
        self
    }
    /// With a lower bound only.
    pub fn at_least(mut self, min: f64) -> Self {
        self.min = Some(min);
        self
    }
    /// With an upper bound.
    pub fn at_most(mut self, max: f64) -> Self {
        self.max = Some(max);
        self
    }
    /// With a strict upper bound.
    pub fn below(mut self, max: f64) -> Self {
        self.max = Some(max);
        self.max_exclusive = true;
        self
    }
    /// With a strict lower bound.
    pub fn above(mut self, min: f64) -> Self {
        self.min = Some(min);
        self.min_exclusive = true;
        self
    }
    /// With the allowed values of a choice.
    pub fn choices(mut self, choices: &[&str]) -> Self {
        self.choices = choices.iter().map(|c| (*c).into()).collect();
        self
    }

    /// What is wrong with `value` against this parameter's bounds, if anything.
    fn outside(&self, value: f64) -> Option<String> {
        let within = value.is_finite()
            && self.min.is_none_or(|m| {
                if self.min_exclusive {
                    value > m
                } else {
                    value >= m
                }
            })
            && self.max.is_none_or(|m| {
                if self.max_exclusive {
                    value < m
                } else {
                    value <= m
                }
            });
        if within {
            return None;
        }
        let (open, close) = (
            if self.min_exclusive { '(' } else { '[' },
            if self.max_exclusive { ')' } else { ']' },
        );
        let requirement = match (self.min, self.max) {
            (Some(lo), Some(hi)) => format!("in {open}{lo}, {hi}{close}"),
            (Some(lo), None) if self.min_exclusive => format!("above {lo} and finite"),
            (Some(lo), None) => format!("at least {lo} and finite"),
            (None, Some(hi)) if self.max_exclusive => format!("below {hi}"),
            (None, Some(hi)) => format!("at most {hi}"),
            (None, None) => "finite".into(),
        };
        Some(format!("must be {requirement}, got {value}"))
    }
}

/// A parameter struct declared with `parameters!`: what the declaration generates.
pub trait Declared {
    /// The form fields, in declaration order.
    fn form() -> Vec<ParamInfo>;
    /// The fields not in the form (left to JSON and the Rust API).
    fn json_only() -> Vec<String>;
    /// Every field outside its declared range, as `(field, message)`.
    fn range_problems(&self) -> Vec<(&'static str, String)>;
}

/// An enum a choice parameter takes: its values as JSON writes them.
pub(crate) trait Choices {
    /// The values, as serde names them.
    const NAMES: &'static [&'static str];
}

/// Shared by the Yau–Yau and spectral filters.
impl Choices for crate::model::dmz::LikelihoodPlacement {
    const NAMES: &'static [&'static str] = &["in_update", "in_operator"];
}

/// A parameter value whose numbers a range check reads.
pub(crate) trait ParamValue {
    /// The problem with the first number outside `info`'s bounds, if any.
    fn range_problem(&self, info: &ParamInfo) -> Option<String>;
}

impl ParamValue for usize {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        info.outside(*self as f64)
    }
}

impl ParamValue for f64 {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        info.outside(*self)
    }
}

impl<T: ParamValue> ParamValue for Option<T> {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        self.as_ref().and_then(|v| v.range_problem(info))
    }
}

impl<T: ParamValue> ParamValue for [T] {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        self.iter().find_map(|v| v.range_problem(info))
    }
}

impl<T: ParamValue> ParamValue for Vec<T> {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        self.as_slice().range_problem(info)
    }
}

impl<T: ParamValue, const N: usize> ParamValue for [T; N] {
    fn range_problem(&self, info: &ParamInfo) -> Option<String> {
        self.as_slice().range_problem(info)
    }
}

/// Declares a method's parameter struct; see the module doc.
macro_rules! parameters {
    (
        $(#[doc = $sdoc:literal])+
        pub struct $name:ident {
            $(
                $(#[doc = $doc:literal])+
                $field:ident : $ty:ty = $default:expr => $kind:ident $($label:literal)?
                    $(, $bound:ident ( $($b:expr),* ))* ;
            )*
        }
    ) => {
        $(#[doc = $sdoc])+
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[doc = $doc])+
                pub $field: $ty,
            )*
        }

        impl Default for $name {
            fn default() -> Self {
                $name { $($field: $default,)* }
            }
        }

        impl $crate::filters::params::Declared for $name {
            // One push per declared field, expanded from the declaration.
            #[allow(clippy::vec_init_then_push)]
            fn form() -> alloc::vec::Vec<$crate::filters::params::ParamInfo> {
                #[allow(unused_mut)]
                let mut form = alloc::vec::Vec::new();
                $(
                    $crate::filters::params::parameters!(@field form, $field, $ty, $kind
                        $(, $label)?, concat!($($doc),+) $(, $bound($($b),*))*);
                )*
                form
            }

            #[allow(clippy::vec_init_then_push)]
            fn json_only() -> alloc::vec::Vec<alloc::string::String> {
                #[allow(unused_mut)]
                let mut names = alloc::vec::Vec::new();
                $(
                    $crate::filters::params::parameters!(@json names, $field, $kind);
                )*
                names
            }

            fn range_problems(&self) -> alloc::vec::Vec<(&'static str, alloc::string::String)> {
                #[allow(unused_imports)]
                use $crate::filters::params::ParamValue;
                let form = Self::form();
                let mut problems = alloc::vec::Vec::new();
                for info in &form {
                    let problem = match info.name.as_str() {
                        $(
                            stringify!($field) => {
                                $crate::filters::params::parameters!(@check self.$field, info, $kind)
                            }
                        )*
                        _ => None,
                    };
                    if let Some(message) = problem {
                        let field = [$(stringify!($field)),*]
                            .into_iter()
                            .find(|f| *f == info.name)
                            .unwrap_or("params");
                        problems.push((field, message));
                    }
                }
                problems
            }
        }
    };
    (@field $form:ident, $field:ident, $ty:ty, json, $doc:expr $(, $bound:ident ( $($b:expr),* ))*) => {};
    (@field $form:ident, $field:ident, $ty:ty, choice, $label:literal, $doc:expr) => {
        $form.push(
            $crate::filters::params::ParamInfo::new(
                stringify!($field),
                $crate::filters::params::ParamKind::Choice,
                $label,
                $doc.trim(),
            )
            .choices(<$ty as $crate::filters::params::Choices>::NAMES),
        );
    };
    (@field $form:ident, $field:ident, $ty:ty, $kind:ident, $label:literal, $doc:expr
        $(, $bound:ident ( $($b:expr),* ))*) => {
        $form.push(
            $crate::filters::params::ParamInfo::new(
                stringify!($field),
                $crate::filters::params::parameters!(@kind $kind),
                $label,
                $doc.trim(),
            )
            $(.$bound($($b as f64),*))*,
        );
    };
    (@kind int) => { $crate::filters::params::ParamKind::Int };
    (@kind optional_int) => { $crate::filters::params::ParamKind::OptionalInt };
    (@kind number) => { $crate::filters::params::ParamKind::Number };
    (@kind int_list) => { $crate::filters::params::ParamKind::IntList };
    (@kind number_list) => { $crate::filters::params::ParamKind::NumberList };
    (@json $names:ident, $field:ident, json) => {
        $names.push(alloc::string::String::from(stringify!($field)));
    };
    (@json $names:ident, $field:ident, $kind:ident) => {};
    (@check $value:expr, $info:ident, json) => { None };
    (@check $value:expr, $info:ident, choice) => { None };
    (@check $value:expr, $info:ident, $kind:ident) => { $value.range_problem($info) };
}
pub(crate) use parameters;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::dmz::LikelihoodPlacement;
    use crate::testing::test;
    use alloc::vec;

    /// A choice's names are the ones serde writes.
    #[test]
    fn choice_names_are_the_json_names() {
        let names: Vec<String> = [
            LikelihoodPlacement::InUpdate,
            LikelihoodPlacement::InOperator,
        ]
        .iter()
        .map(|l| serde_json::to_value(l).unwrap().as_str().unwrap().into())
        .collect();
        assert_eq!(names, LikelihoodPlacement::NAMES);
    }

    /// Bounds read every number of a value, NaN and infinities included.
    #[test]
    fn bounds_read_every_number() {
        let info = ParamInfo::new("x", ParamKind::NumberList, "x", "x").range(0.0, 1.0);
        assert!(vec![0.0, 0.5, 1.0].range_problem(&info).is_none());
        let message = vec![0.5, 1.5].range_problem(&info).unwrap();
        assert!(message.contains("in [0, 1], got 1.5"), "{message}");
        assert!(f64::NAN.range_problem(&info).is_some());
        let step = ParamInfo::new("dt", ParamKind::Number, "dt", "dt").above(0.0);
        assert!(0.0.range_problem(&step).is_some());
        assert!(f64::INFINITY.range_problem(&step).is_some());
        assert!(1e-9.range_problem(&step).is_none());
        assert!(None::<usize>.range_problem(&info).is_none());
    }
}
