//! The accuracy–cost frontier: the reference posterior, its convergence check, the sweep and
//! the "cheapest within 5 %" rule.

use zakai::lab::scenario::{presets, MethodConfig};
use zakai::lab::study::frontier::{
    default_sweep, frontier, reference, reference_check, Frontier, FrontierPoint, SweepPoint,
};
use zakai_tests::test;

fn cubic() -> zakai::lab::scenario::ScenarioConfig {
    let mut c = presets::preset("cubic-sensor-1d").expect("preset");
    c.time.t_final = 1.0;
    c
}

#[test]
fn the_reference_is_exact_where_it_can_be_and_qiem_otherwise() {
    let exact = reference(&presets::preset("sa-example-1").unwrap(), 801, 1e-4).unwrap();
    assert!(matches!(exact.method, MethodConfig::GaussianSum(_)));
    assert!(exact.finer.is_none());
    let grid = reference(&cubic(), 401, 1e-3).unwrap();
    match (&grid.method, grid.finer.as_ref()) {
        (MethodConfig::Qiem(a), Some(MethodConfig::Qiem(b))) => {
            // Half the spacing: (N + 1) interior intervals become 2(N + 1).
            assert_eq!(b.points[0] + 1, 2 * (a.points[0] + 1));
            assert_eq!(b.dt, a.dt / 2.0);
        }
        other => panic!("{other:?}"),
    }
    // Beyond three dimensions, where QIEM stops, the tensor-train filter, its twin at half the
    // spacing; a model it refuses as well (a discrete-time map) has no reference.
    let four = presets::preset("cubic-sensor-4d").unwrap();
    let tt = reference(&four, 47, 1e-3).unwrap();
    match (&tt.method, tt.finer.as_ref()) {
        (MethodConfig::TensorTrain(a), Some(MethodConfig::TensorTrain(b))) => {
            assert_eq!(
                (a.points.as_slice(), b.points.as_slice()),
                (&[47][..], &[95][..])
            );
        }
        other => panic!("{other:?}"),
    }
    let mut map = four.clone();
    map.model.dynamics = zakai::lab::scenario::DynamicsKind::Discrete;
    assert!(reference(&map, 47, 1e-3).is_err());
}

/// Refining the reference moves the posterior mean less and less: the check measures the
/// convergence it reports (coarse pair above fine pair, and the fine pair well below 1e-2).
#[test]
fn reference_check_shrinks_with_refinement() {
    let c = cubic();
    let coarse = reference_check(&c, &reference(&c, 51, 2e-3).unwrap(), 2, 1)
        .unwrap()
        .unwrap();
    let fine = reference_check(&c, &reference(&c, 401, 2.5e-4).unwrap(), 2, 1)
        .unwrap()
        .unwrap();
    assert!(
        fine.max_mean_change < coarse.max_mean_change,
        "{fine:?} vs {coarse:?}"
    );
    assert!(fine.max_mean_change < 1e-2, "{fine:?}");
}

#[test]
fn the_sweep_keeps_only_methods_that_apply() {
    let families = |c| {
        let mut f: Vec<&str> = default_sweep(&c)
            .unwrap()
            .iter()
            .map(|p| p.family)
            .collect();
        f.dedup();
        f
    };
    let cubic = families(cubic());
    for f in ["PF", "QIEM", "IEM", "Spectral", "EKF", "TT"] {
        assert!(cubic.contains(&f), "{f} missing from {cubic:?}");
    }
    assert!(!cubic.contains(&"SA") && !cubic.contains(&"FDM"));
    let sa = families(presets::preset("sa-example-1").unwrap());
    // The TT filter takes discrete measurements (001 (6)) as well as increments.
    assert!(sa.contains(&"SA") && sa.contains(&"FDM") && sa.contains(&"PF") && sa.contains(&"TT"));
    assert!(!sa.contains(&"QIEM") && !sa.contains(&"Spectral"));
}

/// Each grid is swept at Δt = Δτ, Δτ/4 and min(Δτ, 10⁻³), never finer than that and each once.
#[test]
fn grids_are_swept_at_several_steps() {
    let steps = |c: &zakai::lab::scenario::ScenarioConfig| -> Vec<f64> {
        default_sweep(c)
            .unwrap()
            .iter()
            .filter(|p| p.family == "QIEM" && p.value == 95)
            .map(|p| p.dt.expect("grid methods carry their step"))
            .collect()
    };
    let mut c = cubic();
    assert_eq!(steps(&c), vec![0.01, 0.0025, 1e-3]);
    c.time.dt_obs = 1e-3;
    assert_eq!(steps(&c), vec![1e-3]);
    c.time.dt_obs = 2e-3;
    assert_eq!(steps(&c), vec![2e-3, 1e-3]);
}

/// A small frontier end to end: the floor is the reference's MSE and every swept point has
/// its MSE over the same paired runs; a converged grid filter lands within 5 % of the floor.
#[test]
fn a_small_frontier_runs_and_the_grid_filter_reaches_the_floor() {
    let c = cubic();
    let r = reference(&c, 401, 2.5e-4).unwrap();
    let sweep: Vec<SweepPoint> = default_sweep(&c)
        .unwrap()
        .into_iter()
        .filter(|p| {
            (p.family == "QIEM" && p.value == 191 && p.dt == Some(1e-3))
                || (p.family == "PF" && p.value == 50)
        })
        .collect();
    assert_eq!(sweep.len(), 2);
    let f = frontier(&c, &r, &sweep, 4, 1, &|| {}).unwrap();
    assert_eq!(f.points.len(), 2);
    assert!(f.floor.1.is_finite() && f.floor.1 > 0.0);
    let qiem = f.cheapest_within("QIEM", 0.05).expect("QIEM within 5 %");
    assert_eq!(qiem.sweep.value, 191);
}

#[test]
fn cheapest_within_ignores_failed_and_too_inaccurate_settings() {
    let point = |value, mse, failed, secs| FrontierPoint {
        sweep: SweepPoint {
            family: "PF",
            knob: "particles",
            value,
            dt: None,
            method: MethodConfig::from_key("pf").unwrap(),
        },
        mse: Some(mse),
        mse_stderr: Some(0.01),
        failed,
        seconds_per_step: secs,
    };
    let f = Frontier {
        runs: 10,
        floor: ("reference".into(), 1.0, 0.01),
        floor_seconds_per_step: 1e-3,
        points: vec![
            point(50, 1.2, 0, 1e-5),
            point(100, 1.04, 1, 2e-5),
            point(200, 1.03, 0, 4e-5),
            point(500, 1.01, 0, 9e-5),
        ],
    };
    assert_eq!(f.cheapest_within("PF", 0.05).unwrap().sweep.value, 200);
    assert!(f.cheapest_within("PF", 0.001).is_none());
    assert!(f.cheapest_within("QIEM", 0.05).is_none());
}
