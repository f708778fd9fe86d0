//! Text expressions: exact derivatives agree with finite differences; errors are typed.

use zakai::ExprError;
use zakai::ExpressionFunction;
use zakai::{Derivatives, VectorFunction};
use zakai_tests::test;

fn parse(texts: &[&str], n: usize) -> ExpressionFunction {
    let t: Vec<String> = texts.iter().map(|s| s.to_string()).collect();
    ExpressionFunction::parse("f", &t, n, t.len()).unwrap()
}

#[test]
fn exact_derivatives_agree_with_finite_differences() {
    // Central differences with step 1e-5 have error ~1e-10 × |f'''|; tolerance 1e-6.
    let cases: Vec<(Vec<&str>, usize)> = vec![
        (vec!["x^3", "x*sin(x)", "x*cos(x)", "tanh(x)"], 1),
        (
            vec!["-cos(x1)-sin(x2)", "cos(x1)+sin(x2)", "x1^3*exp(-x2^2/2)"],
            2,
        ),
        (
            vec![
                "atan((x1 + 40)/(x2 + 50))",
                "sqrt(x1^2 + x2^2 + 1)",
                "x1*x2/(1 + x2^2)",
            ],
            2,
        ),
    ];
    let points = [[0.3, -0.7], [1.9, 0.4], [-1.1, 2.2]];
    for (texts, n) in cases {
        let f = parse(&texts, n);
        assert_eq!(f.derivatives(), Derivatives::Exact, "{texts:?}");
        let m = texts.len();
        for p in points {
            let x = &p[..n];
            let mut jac = vec![0.0; m * n];
            f.jacobian(x, &mut jac);
            for j in 0..n {
                let h = 1e-5;
                let mut xp = x.to_vec();
                let mut xm = x.to_vec();
                xp[j] += h;
                xm[j] -= h;
                let (fp, fm) = (f.value(&xp), f.value(&xm));
                for i in 0..m {
                    let fd = (fp[i] - fm[i]) / (2.0 * h);
                    assert!(
                        (jac[i * n + j] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                        "{} d/dx{j} at {x:?}",
                        texts[i]
                    );
                }
                // Second derivatives against differences of the exact Jacobian.
                let (mut jp, mut jm) = (vec![0.0; m * n], vec![0.0; m * n]);
                f.jacobian(&xp, &mut jp);
                f.jacobian(&xm, &mut jm);
                for i in 0..m {
                    let mut hess = vec![0.0; n * n];
                    f.hessian(i, x, &mut hess);
                    for l in 0..n {
                        let fd = (jp[i * n + l] - jm[i * n + l]) / (2.0 * h);
                        assert!(
                            (hess[l * n + j] - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                            "{} d²/dx{l}dx{j} at {x:?}: {} vs {fd}",
                            texts[i],
                            hess[l * n + j]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn errors_are_typed_and_readable() {
    let one = |t: &str, n: usize| ExpressionFunction::parse("drift f", &[t.to_string()], n, 1);
    match one("x1 + * 2", 2).unwrap_err() {
        ExprError::Syntax { position, .. } => assert_eq!(position, Some(5)),
        e => panic!("unexpected {e:?}"),
    }
    let e = one("y^2", 1).unwrap_err();
    assert!(matches!(e, ExprError::UnknownVariable { ref name, position: 0, .. } if name == "y"));
    assert!(e.to_string().contains("allowed: x1, x"), "{e}");
    let e = one("2e400*x", 1).unwrap_err();
    assert!(
        matches!(e, ExprError::NonFiniteConstant { position: 0, .. }),
        "{e:?}"
    );
    let e = ExpressionFunction::parse("drift f", &["x1".into()], 2, 2).unwrap_err();
    assert_eq!(e.to_string(), "drift f needs 2 component(s), 1 given");
}

/// Regression for the fuzzer's first find: a power followed by a hundred stacked
/// minus signs overflowed the stack in exmex's recursive differentiation. Such input is now a
/// syntax error with its position; everything the limits accept — up to 32 levels of nesting
/// and 1000 characters, with exact derivatives only within the symbolic budget (16 operations,
/// 6 levels) and numerical ones beyond — parses and differentiates on a 2 MiB stack (a
/// test thread's; the wasm build links an 8 MiB stack).
#[test]
fn deep_or_long_expressions_are_refused_or_handled_on_a_small_stack() {
    let crash = format!("x1^{}x1*x1*-066661--2", "-".repeat(97));
    let err = ExpressionFunction::parse("h", &[crash], 2, 1).unwrap_err();
    let message = err.to_string();
    assert!(message.contains("nests deeper than 32"), "{message}");
    assert!(message.contains("position 35"), "{message}");
    let long = "x+".repeat(600);
    let err = ExpressionFunction::parse("h", &[long], 1, 1).unwrap_err();
    assert!(err.to_string().contains("longer than 1000 characters"));

    // `open` k times, then `inner`, then `close` k times.
    let nest = |open: &str, k: usize, inner: &str, close: &str| {
        format!("{}{inner}{}", open.repeat(k), close.repeat(k))
    };
    let mut accepted = Vec::new();
    for k in [2, 4, 6, 8, 12, 16, 31] {
        accepted.push(nest("(", k, "x", ")"));
        accepted.push(nest("-", k, "x", ""));
        accepted.push(nest("sin(", k, "x+1", ")"));
        accepted.push(nest("1/(1+", k, "x", ")"));
        accepted.push(nest("x-(1-(", k / 2, "x", "))"));
        accepted.push(nest("", k, "x", "+x*x"));
        accepted.push(nest("", k, "x", "*sin(x)"));
        accepted.push(nest("", k, "x", "/(1+x^2)"));
        accepted.push(nest("", k, "x", "*exp(-x)"));
    }
    let parse_all = move || {
        let mut exact = 0;
        for text in &accepted {
            let f = ExpressionFunction::parse("h", std::slice::from_ref(text), 1, 1)
                .unwrap_or_else(|e| panic!("{text}: {e}"));
            let (mut v, mut j, mut h) = ([0.0], [0.0], [0.0]);
            f.eval(&[0.3], &mut v);
            f.jacobian(&[0.3], &mut j);
            f.hessian(0, &[0.3], &mut h);
            assert!(
                v[0].is_finite() && j[0].is_finite() && h[0].is_finite(),
                "{text}"
            );
            exact += usize::from(f.derivatives() == Derivatives::Exact);
        }
        (exact, accepted.len())
    };
    // Natively on a thread with a 2 MiB stack; in WebAssembly on the stack the build links
    // (8 MiB, .cargo/config.toml) — the page's.
    #[cfg(not(target_arch = "wasm32"))]
    let (exact, total) = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(parse_all)
        .unwrap()
        .join()
        .expect("no stack overflow on 2 MiB");
    #[cfg(target_arch = "wasm32")]
    let (exact, total) = parse_all();
    assert!(
        exact >= 20,
        "only {exact} of {total} with exact derivatives"
    );
}
