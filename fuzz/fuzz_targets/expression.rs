//! Expression parsing + symbolic differentiation: any text, in 1 to 3 state variables, either
//! parses or returns an `ExprError` whose position lies inside the text; parsed functions
//! evaluate, differentiate (Jacobian and Hessian) and report affinity without panicking. The
//! exact normal form (`model::symbolic`, through `zakai::fuzzing`) of each component either exists — and then its
//! display reads back to the same normal form, and its derivatives exist or are refused — or
//! is refused with a reason.
#![no_main]

use libfuzzer_sys::fuzz_target;
use zakai::ExpressionFunction;
use zakai::ExprError;
use zakai::VectorFunction;

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let n = 1 + usize::from(head % 3);
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    // Up to three components separated by ';' (a vector function).
    let texts: Vec<String> = text.split(';').take(3).map(str::to_string).collect();
    let m = texts.len();
    for t in &texts {
        zakai::fuzzing::normal_form_reads_back(t, n);
    }
    match ExpressionFunction::parse("fuzzed", &texts, n, m) {
        Ok(f) => {
            let points = [vec![0.0; n], vec![0.5; n], vec![-1.25; n], vec![3.0; n]];
            let mut out = vec![0.0; m];
            let mut jac = vec![0.0; m * n];
            let mut hess = vec![0.0; n * n];
            for x in &points {
                f.eval(x, &mut out);
                f.jacobian(x, &mut jac);
                for i in 0..m {
                    f.hessian(i, x, &mut hess);
                }
            }
            let _ = f.is_affine(&points);
        }
        Err(e) => {
            let message = e.to_string();
            assert!(!message.is_empty());
            let position = match &e {
                ExprError::Syntax { position, .. } => *position,
                ExprError::UnknownVariable { position, .. } => Some(*position),
                _ => None,
            };
            if let Some(p) = position {
                assert!(
                    p <= text.len(),
                    "position {p} beyond the text ({} bytes)",
                    text.len()
                );
            }
        }
    }
});
