//! The five papers Zakai implements, cited by authors and year as well as by number.

/// The five papers by number with their authors and year (`shared/papers/README.md`).
pub const AUTHORS: [(&str, &str); 5] = [
    ("000", "Yueh, Lin & Yau 2014"),
    ("001", "Šimandl & Švácha 2005"),
    ("002", "Shi, Yang & Yau 2018"),
    ("003", "Kang, Salmon & Yau 2023"),
    ("004", "Shi, Chen & Yau 2021"),
];

/// A paper cited by authors and year as well as number: `"Shi, Chen & Yau 2021 [004]"` for
/// `"004"`; an unknown number stays as it is.
pub fn cite(paper: &str) -> alloc::string::String {
    match AUTHORS.iter().find(|(n, _)| *n == paper) {
        Some((n, who)) => alloc::format!("{who} [{n}]"),
        None => paper.into(),
    }
}
