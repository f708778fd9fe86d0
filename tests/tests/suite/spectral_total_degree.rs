//! 004's spectral filter on the total-degree basis (issue 63, item 3): in one dimension the
//! same set as the tensor basis, so the two must agree to rounding; beyond three dimensions,
//! where the tensor basis stops, against the Kalman–Bucy filter on coupled linear models.

use nalgebra::DMatrix;
use zakai::{
    Filter, Kalman, LikelihoodPlacement, Model, Noise, Spectral, SpectralBasis, SpectralParams,
};
use zakai_tests::test;

/// In 1-D the total-degree set is the tensor set: with the same functions and on-line nodes
/// the two filters differ only in how the off-line step is computed (the tensor basis
/// differentiates the interpolant on its nodes, the total-degree basis writes the derivatives
/// out; both exact for the cubic sensor's zero drift) and in the off-line quadrature: the
/// means agree within 10⁻⁹ over 200 increments.
#[test]
fn in_one_dimension_the_total_degree_basis_is_the_tensor_basis() {
    let model = Model::from_text(&["0"], &["x^3"], Noise::continuous(1.0)).unwrap();
    let build = |basis| {
        Spectral::builder(&model)
            .prior_gaussian(&[1.0], &[[0.1]])
            .domain(&[(-4.0, 4.0)])
            .dt(0.01)
            .params(SpectralParams {
                offline_basis: Some(40),
                online_basis: Some(40),
                online_nodes: Some(90),
                basis,
                ..SpectralParams::default()
            })
            .build()
            .unwrap()
    };
    let (mut tensor, mut total) = (
        build(SpectralBasis::Tensor),
        build(SpectralBasis::TotalDegree),
    );
    let mut worst: f64 = 0.0;
    for k in 0..200 {
        let dy = [0.01 * (0.3 * k as f64).sin() + 0.005];
        tensor.step_increment(0.01, &dy).unwrap();
        total.step_increment(0.01, &dy).unwrap();
        worst = worst.max((tensor.estimate().mean[0] - total.estimate().mean[0]).abs());
    }
    eprintln!("1-D tensor against total degree: {worst:e}");
    assert!(worst < 1e-9, "{worst}");
}

/// A coupled linear model in `d` dimensions, `dx_i = (−x_i + 0.3 x_{i+1}) dt + dv_i`,
/// `dy_i = x_i dt + dw_i`, from its prior N(0, 0.5 I) on [−3, 3]^d: the largest distance of the
/// total-degree filter's means from the Kalman–Bucy filter's, in exact posterior sds, and the
/// largest relative error of its variances, over `steps` increments of a simulated path.
fn coupled_linear(d: usize, count: usize, half: f64, steps: usize) -> (f64, f64, f64) {
    coupled_linear_with(d, count, half, steps, None, LikelihoodPlacement::InUpdate)
}

/// [`coupled_linear`] with a diffusion matrix G (`dv` replaced by `G dv`) and the placement of
/// `−½hᵀS⁻¹h`.
fn coupled_linear_with(
    d: usize,
    count: usize,
    half: f64,
    steps: usize,
    g: Option<DMatrix<f64>>,
    likelihood: LikelihoodPlacement,
) -> (f64, f64, f64) {
    let drift: Vec<String> = (1..=d)
        .map(|i| {
            if i < d {
                format!("-x{i} + 0.3*x{}", i + 1)
            } else {
                format!("-x{i}")
            }
        })
        .collect();
    let sensor: Vec<String> = (1..=d).map(|i| format!("x{i}")).collect();
    let drift: Vec<&str> = drift.iter().map(String::as_str).collect();
    let sensor: Vec<&str> = sensor.iter().map(String::as_str).collect();
    let mut model = Model::from_text(&drift, &sensor, Noise::continuous(1.0)).unwrap();
    if let Some(g) = g {
        model = model.with_diffusion(g).unwrap();
    }
    let mean = vec![0.0; d];
    let cov: Vec<Vec<f64>> = (0..d)
        .map(|i| (0..d).map(|j| if i == j { 0.5 } else { 0.0 }).collect())
        .collect();
    let dt = 0.01;
    let mut rng = zakai::simulate::rng_from_seed(11);
    let time = zakai::simulate::TimeGrid {
        dt_obs: dt,
        steps,
        inner_steps: 10,
    };
    let start: Vec<f64> = (0..d).map(|i| 0.4 * (i as f64 + 1.0).sin()).collect();
    let path = zakai::simulate::simulate(&model, &start, time, &mut rng).unwrap();
    let mut kalman = Kalman::builder(&model)
        .prior_gaussian(&mean, &cov)
        .build()
        .unwrap();
    let mut spectral = Spectral::builder(&model)
        .prior_gaussian(&mean, &cov)
        .domain(&vec![(-half, half); d])
        .dt(dt)
        .params(SpectralParams {
            offline_basis: Some(count),
            online_basis: Some(count),
            basis: SpectralBasis::TotalDegree,
            likelihood,
            ..SpectralParams::default()
        })
        .build()
        .unwrap();
    let (mut mean_error, mut variance_error) = (0.0f64, 0.0f64);
    for k in 1..=steps {
        let dy = path.observation(k);
        kalman.step_increment(dt, dy).unwrap();
        spectral.step_increment(dt, dy).unwrap();
        let (exact, estimate) = (kalman.estimate(), spectral.estimate());
        let (p, q) = (exact.covariance.unwrap(), estimate.covariance.unwrap());
        for i in 0..d {
            let sd = p[(i, i)].sqrt();
            mean_error = mean_error.max((estimate.mean[i] - exact.mean[i]).abs() / sd);
            variance_error = variance_error.max((q[(i, i)] / p[(i, i)] - 1.0).abs());
        }
    }
    eprintln!(
        "total degree {} in {d}-D on ±{half}: {mean_error:.4} sd, variances {variance_error:.4}, tail share {:.2e}",
        count - 1,
        spectral.tail_energy()
    );
    // The self-check reports the share exactly when it is above its threshold, 10⁻³.
    let mut concerns = Vec::new();
    spectral.self_check(&mut concerns);
    let warned = concerns
        .iter()
        .any(|c| c.check.contains("highest Legendre degrees"));
    assert_eq!(warned, spectral.tail_energy() > 1e-3, "{concerns:?}");
    (mean_error, variance_error, spectral.tail_energy())
}

/// The total-degree basis converges to the exact filter as its degree grows: in 2-D on
/// [−3, 3]² (the posterior's sd about 0.64) degrees 8, 14 and 20 put the means 0.27, 0.026
/// and 0.0027 exact sds from the Kalman–Bucy filter's (measured; each step asserted at least
/// five times closer, the last below 0.005 sd, its variances within 2 %).
#[test]
fn total_degree_basis_converges_to_the_kalman_bucy_filter() {
    let errors: Vec<(f64, f64, f64)> = [9, 15, 21]
        .iter()
        .map(|&count| coupled_linear(2, count, 3.0, 50))
        .collect();
    assert!(
        errors[1].0 < errors[0].0 / 5.0 && errors[2].0 < errors[1].0 / 5.0,
        "{errors:?}"
    );
    assert!(errors[2].0 < 0.005 && errors[2].1 < 0.02, "{errors:?}");
    // The self-check's share of the energy in the top quarter of the degrees falls with them.
    assert!(errors[0].2 > 1e-3 && errors[2].2 < 1e-3, "{errors:?}");
}

/// The terms the diagonal case leaves out: a correlated process noise, `G Gᵀ` with the
/// off-diagonal entry 0.5 (the written-out `a₁₂ ∂₁∂₂φ`), and `−½hᵀS⁻¹h` in the off-line
/// operator as 004 (17) writes it; degree 20 in 2-D on [−3, 3]², each within 0.02 exact sd of
/// the Kalman–Bucy means and 3 % of its variances (measured: 0.0104 sd and 1.9 % with the
/// correlated noise, 0.0031 sd and 0.6 % with the potential in the operator).
#[test]
fn correlated_noise_and_the_potential_in_the_operator_match_the_kalman_bucy_filter() {
    let g = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.5, 0.866]);
    let correlated = coupled_linear_with(2, 21, 3.0, 50, Some(g), LikelihoodPlacement::InUpdate);
    let in_operator = coupled_linear_with(2, 21, 3.0, 50, None, LikelihoodPlacement::InOperator);
    for (what, (mean_error, variance_error, _)) in [
        ("G Gᵀ correlated", correlated),
        ("in_operator", in_operator),
    ] {
        assert!(
            mean_error < 0.02 && variance_error < 0.03,
            "{what}: {mean_error} sd, {variance_error}"
        );
    }
}

/// Beyond three dimensions, where the tensor basis stops: on [−2.25, 2.25]ⁿ (±3.5 posterior
/// sds; the box alone puts 2-D's means 0.067 sd off the exact ones, as degree 14 shows) the
/// default degrees — 8 in 4-D (495 functions), 5 in 5-D (252), 3 in 6-D (84), each built in
/// 2–3 s — run, their means 0.13, 0.31 and 0.18 exact sds from the Kalman–Bucy filter's
/// (measured; asserted below 0.15, 0.35 and 0.25) and their variances off by 39 %, 113 % and
/// 110 %: too few functions for this posterior, and the self-check says so (the energy share
/// in the top quarter of the degrees, 0.010–0.052, above its 10⁻³), as an approximation that
/// cannot vouch for its result must. (Degree 10 in 4-D: 0.078 sd in a 23 s build; degree 5 in
/// 6-D: 0.31 sd in 98 s — the off-line Gram matrix on a tensor Gauss grid is the cost.)
// Three off-line builds of 2–3 s natively: run once, natively (the wasm build runs the same
// core code on the other tests).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn total_degree_basis_in_four_five_and_six_dimensions_against_the_kalman_bucy_filter() {
    for (d, count, steps, bound) in [(4, 9, 50, 0.15), (5, 6, 20, 0.35), (6, 4, 20, 0.25)] {
        let (mean_error, _, tail) = coupled_linear(d, count, 2.25, steps);
        assert!(mean_error < bound, "{d}-D: {mean_error} sd");
        assert!(tail > 1e-3, "{d}-D: the tail share {tail}");
    }
}

/// What the total-degree basis refuses, before anything is built: a dimension beyond 6, N′ ≠ 1,
/// a basis of no functions, and an off-line step of more than 5·10¹¹ multiply–adds (degree 11
/// in 6-D: 16⁶ nodes × 12 376 × 24 752 functions); the tensor basis beyond 3-D names the
/// total-degree basis, which the default (auto) takes there.
#[test]
fn the_total_degree_basis_refuses_what_it_cannot_do() {
    let total = |f: fn(&mut SpectralParams)| {
        let mut p = SpectralParams {
            basis: SpectralBasis::TotalDegree,
            ..SpectralParams::default()
        };
        f(&mut p);
        p
    };
    let fields = |p: &SpectralParams, n| -> Vec<&str> {
        p.problems(n).into_iter().map(|(f, _)| f).collect()
    };
    assert!(total(|_| {}).problems(6).is_empty());
    let seven = total(|_| {}).problems(7);
    assert!(
        seven.len() == 1 && seven[0].1.contains("n = 1 to 6"),
        "{seven:?}"
    );
    assert_eq!(fields(&total(|p| p.partitions = 2), 4), ["partitions"]);
    assert!(fields(&total(|p| p.offline_basis = Some(0)), 4).contains(&"offline_basis"));
    let big = total(|p| {
        p.offline_basis = Some(12);
        p.online_basis = Some(12);
    })
    .problems(6);
    assert!(
        big.iter()
            .any(|(f, m)| *f == "offline_basis" && m.contains("multiply–adds")),
        "{big:?}"
    );
    let tensor = SpectralParams {
        basis: SpectralBasis::Tensor,
        ..SpectralParams::default()
    }
    .problems(4);
    assert!(
        tensor.len() == 1 && tensor[0].1.contains("basis = total_degree"),
        "{tensor:?}"
    );
    // The default, auto, is the tensor basis up to 3-D and the total-degree basis beyond.
    let auto = SpectralParams::default();
    assert_eq!(
        (1..=6).map(|n| auto.basis_for(n)).collect::<Vec<_>>(),
        [
            SpectralBasis::Tensor,
            SpectralBasis::Tensor,
            SpectralBasis::Tensor,
            SpectralBasis::TotalDegree,
            SpectralBasis::TotalDegree,
            SpectralBasis::TotalDegree
        ]
    );
    assert!(auto.problems(6).is_empty());
}

/// A recorded series' irregularities on the total-degree basis: an interval of 1.3 Δτ (a
/// remainder operator made for 0.3 Δτ), an increment with one component missing, one with
/// both (a prediction), and a step refused for its length, which leaves the filter as it was.
#[test]
fn gaps_irregular_steps_and_refusals_leave_the_filter_consistent() {
    let model = Model::from_text(&["-x1", "-x2"], &["x1", "x2"], Noise::continuous(1.0)).unwrap();
    let cov = [[0.5, 0.0], [0.0, 0.5]];
    let mut spectral = Spectral::builder(&model)
        .prior_gaussian(&[0.3, -0.2], &cov)
        .domain(&[(-3.0, 3.0), (-3.0, 3.0)])
        .dt(0.01)
        .params(SpectralParams {
            offline_basis: Some(21),
            online_basis: Some(21),
            basis: SpectralBasis::TotalDegree,
            ..SpectralParams::default()
        })
        .build()
        .unwrap();
    let mut kalman = Kalman::builder(&model)
        .prior_gaussian(&[0.3, -0.2], &cov)
        .build()
        .unwrap();
    let steps: [(f64, [f64; 2]); 4] = [
        (0.01, [0.004, -0.003]),
        (0.013, [0.006, f64::NAN]),
        (0.01, [f64::NAN, f64::NAN]),
        (0.01, [-0.002, 0.001]),
    ];
    for (dt, dy) in steps {
        spectral.step_increment(dt, &dy).unwrap();
        kalman.step_increment(dt, &dy).unwrap();
        let (a, b) = (spectral.estimate(), kalman.estimate());
        let p = b.covariance.unwrap();
        for i in 0..2 {
            let off = (a.mean[i] - b.mean[i]).abs() / p[(i, i)].sqrt();
            assert!(off < 0.01, "dt {dt}, dy {dy:?}: component {i} {off} sd off");
        }
    }
    let before = spectral.estimate();
    assert!(spectral.step_increment(0.01, &[0.1]).is_err());
    assert_eq!(spectral.estimate(), before);
}
