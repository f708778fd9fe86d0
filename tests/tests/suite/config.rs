//! ScenarioConfig: JSON round trip of every preset, and validation reporting every problem.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::{presets, MethodConfig, ScenarioConfig};
use zakai_tests::test;

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
        // Papers cited by authors and year as well as number, in the title and the reference.
        for text in [&p.title, &p.reference] {
            assert!(
                zakai::lab::bibliography::AUTHORS
                    .iter()
                    .any(|(n, who)| text.contains(&format!("{who} [{n}]"))),
                "{}: {text}",
                p.name
            );
        }
        // The page's explanation panel: every preset says what to look for when played.
        assert!(p.description.contains("Look for:"), "{}", p.name);
        let json = serde_json::to_string(&p).unwrap();
        let back: ScenarioConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, p);
        // Every preset builds and its first two steps run.
        let experiment = Experiment::new(p.clone()).unwrap();
        let mut run = experiment.start(1).unwrap();
        run.advance(2, None, &mut zakai::lab::experiment::Silent);
    }
}

#[test]
fn validation_reports_every_bad_field() {
    let mut c = presets::preset("yau-2d").unwrap();
    c.model.drift[1] = "cos(x1) + sin(x3)".into();
    c.model.observation[0] = "x1 - ".into();
    c.prior = zakai::lab::scenario::PriorConfig::Gaussian {
        mean: vec![0.0].into(),
        cov: vec![vec![1.0, 2.0], vec![2.0, 1.0]].into(),
    };
    c.domain[1] = [3.0, -3.0];
    c.time.dt_obs = -0.1;
    let bad_method = format!("methods[{}].particles", c.methods.len());
    c.methods.push(MethodConfig::Pf(zakai::PfParams {
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

/// The one registration list: every catalogue entry builds from its key and its aliases, its
/// serde tag is its key, its schema names real fields of its parameters (and every parameter
/// that is not a form field is one of the few left to JSON), its defaults are valid, and every
/// preset uses only registered methods.
#[test]
fn every_registered_method_is_consistent_and_presets_use_only_registered_ones() {
    use zakai::lab::scenario::catalogue;
    let entries = catalogue();
    assert!(entries.len() >= 15, "all families are registered");
    let mut keys = std::collections::HashSet::new();
    for e in &entries {
        let key = e.info.key.as_str();
        assert!(keys.insert(key.to_string()), "{key} registered twice");
        let m = MethodConfig::from_key(key).expect("registered key builds");
        assert_eq!(m.key(), key);
        assert_eq!(
            m, e.defaults,
            "{key}: the catalogue's defaults are the key's"
        );
        for alias in &e.aliases {
            assert_eq!(MethodConfig::from_key(alias).expect("alias").key(), key);
        }
        assert!(!e.info.summary.is_empty() && !e.info.paper.is_empty() && !e.info.name.is_empty());
        let json = serde_json::to_value(&e.defaults).expect("serializes");
        assert_eq!(json["method"], key, "the serde tag is the key");
        let fields: Vec<&String> = json
            .as_object()
            .unwrap()
            .keys()
            .filter(|k| *k != "method")
            .collect();
        for p in &e.info.params {
            assert!(
                fields.contains(&&p.name),
                "{key}: schema names `{}`, not a parameter",
                p.name
            );
            assert!(
                !p.label.is_empty() && !p.help.is_empty(),
                "{key}.{}",
                p.name
            );
        }
        for f in fields {
            assert!(
                e.info.params.iter().any(|p| &p.name == f) != e.info.json_only.contains(f),
                "{key}: parameter `{f}` must be either a form field or listed as JSON-only"
            );
        }
        let dims: usize = if e.info.dims == "2" { 2 } else { 1 };
        assert!(
            e.defaults.problems(dims).is_empty(),
            "{key}: defaults are valid: {:?}",
            e.defaults.problems(dims)
        );
    }
    for p in zakai::lab::scenario::presets::all() {
        for m in &p.methods {
            assert!(
                keys.contains(m.key()),
                "{}: method {} is not registered",
                p.name,
                m.key()
            );
        }
    }
}

/// Every preset's methods apply to its model; the reasons for the ones that do not are the
/// conditions the constructors would fail on.
#[test]
fn suitability_names_the_reason_a_method_does_not_apply() {
    use zakai::lab::scenario::MethodConfig;
    for preset in zakai::lab::scenario::presets::all() {
        let e = zakai::lab::experiment::Experiment::new(preset.clone()).expect("valid preset");
        let probes = preset.probe_points();
        for m in &preset.methods {
            assert_eq!(
                m.suitability(e.model(), e.prior(), &probes, &preset.bounds()),
                None,
                "{} in {}",
                m.display_name(),
                preset.name
            );
        }
    }
    let reason = |preset: &str, key: &str| {
        let c = zakai::lab::scenario::presets::preset(preset).expect("preset");
        let e = zakai::lab::experiment::Experiment::new(c.clone()).expect("valid");
        MethodConfig::from_key(key).expect("key").suitability(
            e.model(),
            e.prior(),
            &c.probe_points(),
            &c.bounds(),
        )
    };
    assert!(reason("cubic-sensor-1d", "kalman")
        .expect("refused")
        .contains("linear model"));
    assert!(reason("cubic-sensor-1d", "separation")
        .expect("refused")
        .contains("discrete measurements"));
    assert!(reason("cubic-sensor-1d", "qiem4")
        .expect("refused")
        .contains("n = 1"));
    assert!(reason("sa-example-1", "qiem")
        .expect("refused")
        .contains("continuous observations"));
    assert!(reason("sa-example-1", "direct").is_some());
    assert_eq!(reason("sa-example-1", "gaussian_sum"), None);
    assert_eq!(reason("sa-example-2", "kalman"), None);
    assert_eq!(reason("cubic-sensor-1d", "pf"), None);
    // Every method that applies builds: the reasons are not too strict.
    for preset in ["cubic-sensor-1d", "sa-example-1"] {
        let c = zakai::lab::scenario::presets::preset(preset).expect("preset");
        let e = zakai::lab::experiment::Experiment::new(c.clone()).expect("valid");
        for entry in zakai::lab::scenario::catalogue() {
            let (key, m) = (entry.info.key, entry.defaults);
            if m.suitability(e.model(), e.prior(), &c.probe_points(), &c.bounds())
                .is_none()
            {
                e.build_method(&m, m.display_name(), 1)
                    .unwrap_or_else(|err| panic!("{key} on {preset} applies but fails: {err}"));
            }
        }
    }
}

/// The memory estimate grows with the grid and a configuration above the cap is refused by
/// validation, before anything is built.
#[test]
fn memory_cap_refuses_too_large_grids_before_allocation() {
    let mut c = zakai::lab::scenario::presets::preset("yau-2d").expect("preset");
    let qiem = c
        .methods
        .iter()
        .position(|m| m.key() == "qiem")
        .expect("qiem");
    let bytes = |points: usize| {
        let mut m = c.methods[qiem].clone();
        if let zakai::lab::scenario::MethodConfig::Qiem(p) = &mut m {
            p.points = vec![points];
        }
        m.memory_bytes(2).expect("finite")
    };
    assert!(bytes(256) > 3 * bytes(128) && bytes(128) > 3 * bytes(64));
    if let zakai::lab::scenario::MethodConfig::Qiem(p) = &mut c.methods[qiem] {
        p.points = vec![4000];
    }
    let problems = c.validate();
    let message = problems
        .iter()
        .find(|p| p.field == format!("methods[{qiem}]"))
        .map(|p| p.message.clone())
        .expect("refused");
    assert!(message.contains("above the cap of 1.00 GiB"), "{message}");
    assert!(zakai::lab::experiment::Experiment::new(c).is_err());
}

/// Legends and rows carry the resolution a reader compares methods by: grid points per
/// dimension, particles, spectral basis sizes — read from the methods' own parameters.
#[test]
fn method_labels_carry_the_resolution() {
    let mut config = presets::preset("yau-2d").unwrap();
    let mut qiem = MethodConfig::from_key("qiem").unwrap();
    if let MethodConfig::Qiem(p) = &mut qiem {
        p.points = vec![63, 127];
    }
    config.methods = vec![
        MethodConfig::from_key("qiem").unwrap(),
        qiem,
        MethodConfig::from_key("pf").unwrap(),
        MethodConfig::from_key("ekf").unwrap(),
        MethodConfig::from_key("ekf").unwrap(),
    ];
    let labels = config.method_labels();
    let MethodConfig::Qiem(default) = &config.methods[0] else {
        unreachable!()
    };
    let points = default.shape(2)[0];
    let MethodConfig::Pf(pf) = &config.methods[2] else {
        unreachable!()
    };
    assert_eq!(
        labels,
        [
            format!("QIEM({points}²)"),
            "QIEM(63×127)".to_string(),
            format!("PF({})", pf.particles),
            "EKF".to_string(),
            "EKF #2".to_string(),
        ]
    );
    // The plain names are unchanged (tables and files key on them).
    assert_eq!(config.method_names()[0], "QIEM");
    let spectral = presets::preset("cubic-sensor-1d").unwrap();
    let labels = spectral.method_labels();
    let i = spectral
        .methods
        .iter()
        .position(|m| m.key() == "spectral")
        .unwrap();
    let MethodConfig::Spectral(s) = &spectral.methods[i] else {
        unreachable!()
    };
    assert_eq!(
        labels[i],
        format!(
            "Spectral({}/{})",
            s.offline_basis.unwrap(),
            s.online_basis.unwrap()
        )
    );
}

/// A scenario for recorded data needs neither a domain (when no method lives on a grid) nor
/// a final time: it validates and runs over a recording, a simulation asks for T, and a grid
/// method asks for the domain with the reason. Without a divergence bound the failure rule
/// takes one from the problem (here 200 prior sds from the prior mean 1000).
#[test]
fn recorded_data_needs_no_domain_and_no_final_time() {
    let mut config: zakai::lab::scenario::ScenarioConfig =
        serde_json::from_value(serde_json::json!({
            "name": "flow",
            "model": {
                "drift": ["0"], "observation": ["x"], "diffusion": [[30.0]],
                "noise": { "kind": "discrete", "mixture": [
                    { "weight": 1.0, "mean": [0.0], "cov": [[400.0]] } ] }
            },
            "prior": { "kind": "gaussian", "mean": [1000.0], "cov": [[100.0]] },
            "time": { "dt_obs": 1.0 },
            "seed": 1,
            "methods": [{ "method": "kalman" }, { "method": "ukf" }, { "method": "pf" }]
        }))
        .unwrap();
    assert!(config.validate().is_empty(), "{:?}", config.validate());
    let prior = config.build_prior().unwrap();
    assert_eq!(config.divergence_bound(&prior), 1000.0 + 200.0 * 10.0);
    let e = zakai::lab::experiment::Experiment::new(config.clone()).unwrap();
    let z = [1010.0, f64::NAN, 990.0, 1005.0];
    let recording =
        zakai::lab::recording::Recording::measurements(1, 1, vec![0.0, 1.0, 2.0, 4.0], &z).unwrap();
    let run = e.filter_recorded(recording, 1).unwrap();
    assert!(run.methods.iter().all(|m| m.failure.is_none()));
    let simulated = e.start(1).expect_err("a simulation needs T");
    assert!(
        simulated.to_string().contains("time.t_final"),
        "{simulated}"
    );
    config
        .methods
        .push(zakai::lab::scenario::MethodConfig::from_key("qiem").unwrap());
    let problems = config.validate();
    assert!(
        problems
            .iter()
            .any(|p| p.field == "domain" && p.message.contains("grid")),
        "{problems:?}"
    );
}

/// The catalogue's `density` flag (what the page's density panel picks by default) says
/// which methods have a density, and its `score` flag which give their score: every registered method, built on the presets that apply
/// them all, has a grid density exactly when its entry says so — but for the spectral filter,
/// whose density is a Legendre expansion (drawn through its marginals, which then are not the
/// Gaussian of its estimate).
#[test]
fn the_catalogue_says_which_methods_have_a_density() {
    let mut seen = std::collections::BTreeSet::new();
    for preset in zakai_tests::PRESETS_FOR_EVERY_METHOD {
        let config = zakai::lab::scenario::presets::preset(preset).unwrap();
        let e = zakai::lab::experiment::Experiment::new(config.clone()).unwrap();
        for entry in zakai_tests::applicable_methods(&config, &e) {
            let f = e
                .build_method(&entry.defaults, entry.info.key.clone(), 1)
                .unwrap();
            let key = entry.info.key.as_str();
            if key == "spectral" || key == "tensor_train" {
                // Densities without a full grid: the spectral filter's Legendre expansion,
                // the TT filter's tensor train, shown by their marginals.
                assert!(entry.density);
                let grid: Vec<f64> = (0..41).map(|i| -2.0 + 0.1 * i as f64).collect();
                let (mut own, mut gaussian) = (vec![0.0; 41], vec![0.0; 41]);
                f.marginal_density(0, &grid, &mut own);
                let e = f.estimate();
                let var = e.covariance.unwrap()[(0, 0)];
                for (g, x) in gaussian.iter_mut().zip(&grid) {
                    let d = x - e.mean[0];
                    *g = (-0.5 * d * d / var).exp() / (2.0 * std::f64::consts::PI * var).sqrt();
                }
                let gap: f64 = own.iter().zip(&gaussian).map(|(a, b)| (a - b).abs()).sum();
                assert!(gap > 1e-6, "{preset} {key}: its marginal is the Gaussian");
            } else {
                assert_eq!(f.density().is_some(), entry.density, "{preset} {key}");
            }
            assert_eq!(entry.defaults.has_density(), entry.density);
            // The `score` flag likewise: a filter gives its score (here of no observations:
            // ln L = 0, an empty gradient), or says why it cannot on this model (the Kalman
            // filter's moment match of sv-ar1's variance), exactly when its entry says so.
            let score = f.score(&[], &[]);
            assert_eq!(score.is_some(), entry.score, "{preset} {key}");
            assert_eq!(entry.defaults.has_score(), entry.score);
            match score {
                Some(Ok(score)) => {
                    assert_eq!((score.log_likelihood, score.gradient.len()), (0.0, 0))
                }
                Some(Err(e)) => assert!(e.to_string().contains(key), "{preset}: {e}"),
                None => {}
            }
            seen.insert(entry.info.key.clone());
        }
    }
    assert_eq!(
        seen.len(),
        zakai::lab::scenario::catalogue().len(),
        "every method: {seen:?}"
    );
}
