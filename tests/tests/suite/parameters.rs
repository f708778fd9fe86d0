//! A scenario's named parameters: used in expressions and coefficients, they build the same
//! model as the numbers typed in their place; unknown and unused names are reported with
//! their positions and fields.

use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;

/// An Ornstein–Uhlenbeck model with discrete measurements, its numbers written `theta`, `q`,
/// `r`, `m0` and `p0` or as numbers.
fn scenario(drift: &str, g: &str, r: &str, m0: &str, p0: &str, parameters: &str) -> ScenarioConfig {
    let json = format!(
        r#"{{
        "name": "ou", "parameters": {parameters},
        "model": {{ "drift": ["{drift}"], "observation": ["x"], "diffusion": [[{g}]],
                   "noise": {{ "kind": "discrete", "mixture": [{{ "mean": [0], "cov": [[{r}]] }}] }} }},
        "prior": {{ "kind": "gaussian", "mean": [{m0}], "cov": [[{p0}]] }},
        "time": {{ "dt_obs": 0.5 }},
        "methods": [{{ "method": "kalman" }}]
    }}"#
    );
    serde_json::from_str(&json).unwrap()
}

const PARAMETERS: &str = r#"{ "theta": { "value": 0.7, "bounds": [0, 5] },
    "q": { "value": 0.3, "bounds": [0, null] }, "r": { "value": 0.2 },
    "m0": { "value": -1.5 } }"#;

#[test]
fn parameters_build_the_model_their_values_typed_in_build() {
    let named = scenario(
        "-theta*x",
        "\"sqrt(q)\"",
        "\"r\"",
        "\"m0\"",
        "\"2*r\"",
        PARAMETERS,
    );
    assert!(named.validate().is_empty(), "{:?}", named.validate());
    let typed = scenario(
        "-0.7*x",
        &format!("{:?}", 0.3f64.sqrt()),
        "0.2",
        "-1.5",
        "0.4",
        "{}",
    );
    let (a, b) = (named.build_model().unwrap(), typed.build_model().unwrap());
    for x in [-2.0, 0.0, 0.3, 4.0] {
        assert_eq!(a.drift.value(&[x]), b.drift.value(&[x]));
    }
    assert_eq!(a.diffusion.constant(), b.diffusion.constant());
    assert!(a.diffusion.constant().is_some());
    let (pa, pb) = (named.build_prior().unwrap(), typed.build_prior().unwrap());
    assert_eq!(pa.mean(), pb.mean());
    assert_eq!(pa.covariance(), pb.covariance());
    assert_eq!(
        format!("{:?}", a.observations),
        format!("{:?}", b.observations)
    );
    // The JSON round trip keeps expressions as expressions.
    let back: ScenarioConfig =
        serde_json::from_str(&serde_json::to_string(&named).unwrap()).unwrap();
    assert_eq!(back, named);
    // New values give the model of those values.
    let moved = named
        .with_parameter_values(&[("theta".into(), 2.0), ("m0".into(), 3.0)])
        .unwrap();
    assert_eq!(moved.build_model().unwrap().drift.value(&[1.0]), vec![-2.0]);
    assert_eq!(moved.build_prior().unwrap().mean()[0], 3.0);
    assert!(named
        .with_parameter_values(&[("sigma".into(), 1.0)])
        .is_err());
}

#[test]
fn unknown_unused_and_ill_formed_parameters_are_reported_where_they_are() {
    // `thet` is unknown: reported at its position in the drift, the parameters listed.
    let c = scenario("-thet*x", "\"sqrt(q)\"", "\"r\"", "\"m0\"", "1", PARAMETERS);
    let problems = c.validate();
    let drift = problems
        .iter()
        .find(|p| p.field == "model.drift[0]")
        .expect("the drift's problem");
    assert!(
        drift.message.contains("`thet` at position 1") && drift.message.contains("theta"),
        "{}",
        drift.message
    );
    // theta is then used nowhere.
    assert!(problems
        .iter()
        .any(|p| p.field == "parameters.theta" && p.message.contains("no expression")));
    // An unknown name in a coefficient.
    let c = scenario(
        "-theta*x",
        "\"sqrt(qq)\"",
        "\"r\"",
        "\"m0\"",
        "1",
        PARAMETERS,
    );
    assert!(
        c.validate().iter().any(|p| p.field == "model.diffusion[0][0]"
            && p.message.contains("`qq` at position 5")),
        "{:?}",
        c.validate()
    );
    // A name taken by a variable or a function, a value outside its bounds, bounds
    // that are no interval.
    let c = scenario(
        "-theta*x",
        "1",
        "0.2",
        "0",
        "1",
        r#"{ "theta": { "value": 7, "bounds": [0, 5] }, "x": { "value": 1 },
             "sin": { "value": 1 }, "z2": { "value": 1 }, "b": { "value": 1, "bounds": [2, 1] } }"#,
    );
    let problems = c.validate();
    let has = |field: &str, text: &str| {
        problems
            .iter()
            .any(|p| p.field == field && p.message.contains(text))
    };
    assert!(
        has("parameters.theta.value", "outside the bounds"),
        "{problems:?}"
    );
    // z1…zm are a log-density's measurement (model.noise.kind = log_density).
    for name in ["x", "sin", "z2"] {
        assert!(
            has(&format!("parameters.{name}"), "already a variable"),
            "{problems:?}"
        );
    }
    assert!(has("parameters.b.bounds", "lower < upper"), "{problems:?}");
    // A covariance that a parameter's value makes invalid is reported as one.
    let c = scenario(
        "-theta*x",
        "1",
        "\"r\"",
        "0",
        "1",
        r#"{ "theta": { "value": 1 }, "r": { "value": -1 } }"#,
    );
    assert!(c
        .validate()
        .iter()
        .any(|p| p.field == "model.noise.mixture[0].cov"));
}

/// Issue 56, item 7: a parameter value that makes a coefficient invalid is named with the
/// coefficient — `sqrt(q)` at q = −1 is NaN — at the entry's own path, not as "model.diffusion:
/// entries must be finite".
#[test]
fn a_value_that_breaks_a_coefficient_is_named_with_it() {
    let parameters = r#"{ "theta": { "value": 0.7 }, "q": { "value": -1 }, "r": { "value": 0.2 },
        "m0": { "value": -1.5 } }"#;
    let c = scenario(
        "-theta*x",
        "\"sqrt(q)\"",
        "\"r\"",
        "\"m0\"",
        "1",
        parameters,
    );
    let problems = c.validate();
    let entry = problems
        .iter()
        .find(|p| p.field == "model.diffusion[0][0]")
        .unwrap_or_else(|| panic!("{problems:?}"));
    assert!(
        entry.message.contains("`sqrt(q)` is NaN") && entry.message.contains("q = -1"),
        "{}",
        entry.message
    );
}
