//! ScenarioConfig: JSON round trip of every preset, and validation reporting every problem.

use zakai::experiment::Experiment;
use zakai::scenario::{presets, MethodConfig, ScenarioConfig};

#[test]
fn every_preset_is_valid_and_round_trips_through_json() {
    let all = presets::all();
    assert!(all.len() >= 14);
    for p in all {
        assert!(p.validate().is_empty(), "{}: {:?}", p.name, p.validate());
        assert!(
            !p.reference.is_empty() && !p.description.is_empty(),
            "{}",
            p.name
        );
        let json = serde_json::to_string(&p).unwrap();
        let back: ScenarioConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, p);
        // Every preset builds and its first two steps run.
        let experiment = Experiment::new(p.clone()).unwrap();
        let mut run = experiment.start(1).unwrap();
        run.advance(2, None, &mut zakai::experiment::Silent);
    }
}

#[test]
fn validation_reports_every_bad_field() {
    let mut c = presets::preset("yau-2d").unwrap();
    c.model.drift[1] = "cos(x1) + sin(x3)".into();
    c.model.observation[0] = "x1 - ".into();
    c.prior = zakai::scenario::PriorConfig::Gaussian {
        mean: vec![0.0],
        cov: vec![vec![1.0, 2.0], vec![2.0, 1.0]],
    };
    c.domain[1] = [3.0, -3.0];
    c.time.dt_obs = -0.1;
    let bad_method = format!("methods[{}].particles", c.methods.len());
    c.methods
        .push(MethodConfig::Pf(zakai::filters::particle::PfParams {
            particles: 0,
            ..Default::default()
        }));
    let problems = c.validate();
    let fields: Vec<&str> = problems.iter().map(|p| p.field.as_str()).collect();
    for expected in [
        "model.drift[1]",
        "model.observation[0]",
        "prior.mean",
        "prior.cov",
        "domain[1]",
        "time.dt_obs",
        bad_method.as_str(),
    ] {
        assert!(
            fields.contains(&expected),
            "{expected} missing from {fields:?}"
        );
    }
    let msg = Experiment::new(c).err().unwrap().to_string();
    assert!(
        msg.contains("unknown variable `x3` at position 14"),
        "{msg}"
    );
}

#[test]
fn unknown_fields_and_methods_are_rejected() {
    let mut v = serde_json::to_value(presets::preset("cubic-sensor-1d").unwrap()).unwrap();
    v["methods"][0]["substepz"] = 3.into();
    let e = serde_json::from_value::<ScenarioConfig>(v.clone()).unwrap_err();
    assert!(e.to_string().contains("substepz"), "{e}");
    v["methods"][0] = serde_json::json!({"method": "kalmn"});
    assert!(serde_json::from_value::<ScenarioConfig>(v).is_err());
}

/// Every method key is listed (the CLI's `list`, the page's "add method" menu), builds from its
/// key, and every preset uses only listed methods.
#[test]
fn every_method_is_listed_and_every_listed_method_exists() {
    for (key, about) in zakai::scenario::METHODS {
        let m = zakai::scenario::MethodConfig::from_key(key).expect("listed key builds");
        assert_eq!(m.key(), *key);
        assert!(!about.is_empty());
    }
    for p in zakai::scenario::presets::all() {
        for m in &p.methods {
            assert!(
                zakai::scenario::METHODS.iter().any(|(k, _)| *k == m.key()),
                "{}: method {} is not listed",
                p.name,
                m.key()
            );
        }
    }
}
