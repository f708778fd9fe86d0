//! Every method's log-likelihood of the data ([`Filter::log_likelihood`], summed over the
//! steps) against an exact Kalman log-likelihood written here, independently of Zakai's
//! filters, on linear-Gaussian models: an Ornstein–Uhlenbeck state dx = −x dt + dv,
//! measured as z_k = x_k + v_k (R = 0.5, every 0.2) or observed continuously as dy = x dt + dw
//! (S = 1, increments over 0.05), with a gap and a missing value in the data.
//!
//! The approximate methods' tolerances are set from their measured errors, and each is shown
//! to be tight enough to matter: the same method started from a wrong prior — the mean moved
//! by 0.5, or the variance doubled — must fall outside it.
//!
//! The reference predicts exactly (x_{k+1} = e^{−Δτ} x_k + noise of variance
//! (1 − e^{−2Δτ})/2) and takes, per step,
//!
//! * a measurement: ℓ_k = ln N(z_k; m, P + R), m and P predicted;
//! * an increment over Δτ (the sampled-model update every filter makes:
//!   Δy = x Δτ + w, w ~ N(0, Δτ)): ℓ_k = ln N(Δy; mΔτ, PΔτ² + Δτ) − ln N(Δy; 0, Δτ), the
//!   likelihood ratio against Wiener measure;
//!
//! and nothing for a gap.

use zakai::{Filter, Model, Noise, Observation};
use zakai_tests::test;

/// The interval between measurements, and between increments (shorter: the continuous-time
/// methods' time discretisation errors must sit well below what a wrong prior changes).
const DT: f64 = 0.2;
const DT_INCREMENTS: f64 = 0.05;
const STEPS: usize = 60;
/// The prior every reference starts from, N(0, 1), and the two wrong ones a likelihood check
/// must tell from it: the mean moved by 0.5 and the variance doubled.
const PRIOR: (f64, f64) = (0.0, 1.0);
const WRONG_PRIORS: [(f64, f64); 2] = [(0.5, 1.0), (0.0, 2.0)];

/// The observation interval of the data.
fn step_of(continuous: bool) -> f64 {
    if continuous {
        DT_INCREMENTS
    } else {
        DT
    }
}
/// The step whose observation is missing, and the one that is a gap of two intervals.
const MISSING: usize = 17;
const GAP: usize = 31;

fn ln_normal(x: f64, mean: f64, var: f64) -> f64 {
    -0.5 * ((x - mean) * (x - mean) / var + (std::f64::consts::TAU * var).ln())
}

/// A fixed pseudo-random sequence of standard normals (Box–Muller on a small LCG).
fn normals(count: usize, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            let (u, v) = (uniform(), uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        })
        .collect()
}

/// The observations: (interval length, value; NaN = missing) per step, simulated exactly.
fn data(continuous: bool) -> Vec<(f64, f64)> {
    let e = normals(3 * STEPS, 11);
    let mut x = 0.3;
    let mut out = Vec::new();
    for k in 0..STEPS {
        let dt = step_of(continuous) * if k == GAP { 2.0 } else { 1.0 };
        let a = (-dt).exp();
        x = a * x + ((1.0 - a * a) / 2.0).sqrt() * e[3 * k];
        let value = if continuous {
            x * dt + dt.sqrt() * e[3 * k + 1]
        } else {
            x + 0.5f64.sqrt() * e[3 * k + 1]
        };
        out.push((dt, if k == MISSING { f64::NAN } else { value }));
    }
    out
}

/// The exact log-likelihood of `data` from the prior `N(m₀, P₀)`, its per-step terms summed.
fn kalman_log_likelihood(data: &[(f64, f64)], continuous: bool, (m0, p0): (f64, f64)) -> f64 {
    let (mut m, mut p) = (m0, p0);
    let mut total = 0.0;
    for &(dt, value) in data {
        let a = (-dt).exp();
        m *= a;
        p = a * a * p + (1.0 - a * a) / 2.0;
        if value.is_nan() {
            continue;
        }
        let (scale, r) = if continuous { (dt, dt) } else { (1.0, 0.5) };
        let s = scale * scale * p + r;
        total += ln_normal(value, scale * m, s);
        if continuous {
            total -= ln_normal(value, 0.0, r);
        }
        let k = p * scale / s;
        m += k * (value - scale * m);
        p -= k * scale * p;
    }
    total
}

/// The method's log-likelihood of `data`, summed.
fn log_likelihood(filter: &mut dyn Filter, data: &[(f64, f64)], continuous: bool) -> f64 {
    data.iter()
        .map(|&(dt, value)| {
            let z = [value];
            let obs = if continuous {
                Observation::increment(dt, &z)
            } else {
                Observation::measurement(dt, &z)
            };
            filter.step(&obs).unwrap();
            filter.log_likelihood().expect("every method gives one")
        })
        .sum()
}

/// The Gaussian filters against `exact`: the Kalman and Gaussian-sum filters (exact
/// discretisation and update) to 10⁻⁹ relative, the extended, unscented and iterated ones to
/// their RK4 moment equations' error (4 substeps per interval), 10⁻⁷ (1.2·10⁻⁸ measured on
/// the measurements, 1.9·10⁻¹⁰ on the increments); the Gaussian-sum and MAP filters on
/// measurements only.
fn gaussian_filters_match(model: &Model, data: &[(f64, f64)], continuous: bool, exact: f64) {
    let mut methods: Vec<(&str, Box<dyn Filter>, f64)> = vec![
        (
            "KF",
            Box::new(prior(zakai::Kalman::builder(model)).build().unwrap()),
            1e-9,
        ),
        (
            "EKF",
            Box::new(prior(zakai::Ekf::builder(model)).build().unwrap()),
            1e-7,
        ),
        (
            "UKF",
            Box::new(prior(zakai::Ukf::builder(model)).build().unwrap()),
            1e-7,
        ),
    ];
    if !continuous {
        methods.push((
            "GSF",
            Box::new(prior(zakai::GaussianSum::builder(model)).build().unwrap()),
            1e-9,
        ));
        methods.push((
            "IEKF",
            Box::new(prior(zakai::Iekf::builder(model)).build().unwrap()),
            1e-7,
        ));
        methods.push((
            "IOKF",
            Box::new(prior(zakai::Iokf::builder(model)).build().unwrap()),
            1e-7,
        ));
    }
    for (name, f, tolerance) in &mut methods {
        let ll = log_likelihood(f.as_mut(), data, continuous);
        let error = (ll - exact).abs() / exact.abs().max(1.0);
        println!("{name}: relative error {error:.1e}");
        assert!(error < *tolerance, "{name}: {ll} against {exact}");
    }
}

/// The particle filter's (2000 particles) log-likelihood of `data`, its mean over 20 seeds,
/// within four standard errors (plus `slack`) of `exact`; from each prior of `wrong` it must
/// fall outside that band. (On the increments both wrong priors are checked; on the
/// measurements four standard errors, about 0.15, are wider than the shifted mean's 0.021, and
/// only the doubled variance, 0.223, is.)
fn particle_filter_matches(
    model: &Model,
    data: &[(f64, f64)],
    continuous: bool,
    exact: f64,
    slack: f64,
    wrong: &[(f64, f64)],
) {
    let mean_and_se = |p: (f64, f64)| {
        let runs: Vec<f64> = (0..20)
            .map(|seed| {
                let mut pf = prior_at(zakai::Pf::builder(model), p)
                    .with(|p| {
                        p.particles = 2000;
                        // Euler–Maruyama steps of 0.005: the transition's own bias (the
                        // stationary variance 1/(2 − h) instead of ½) stays below the check.
                        p.substeps = Some((step_of(continuous) / 0.005).round() as usize);
                    })
                    .seed(seed)
                    .dt(step_of(continuous))
                    .build()
                    .unwrap();
                log_likelihood(&mut pf, data, continuous)
            })
            .collect();
        let mean = runs.iter().sum::<f64>() / runs.len() as f64;
        let se = (runs.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
            / (runs.len() * (runs.len() - 1)) as f64)
            .sqrt();
        (mean, se)
    };
    let (mean, se) = mean_and_se(PRIOR);
    println!("PF(2000): mean ℓ {mean:.4} ± {se:.4} against {exact:.4}");
    let band = 4.0 * se + slack;
    assert!((mean - exact).abs() < band, "{mean} ± {se} against {exact}");
    for &p in wrong {
        let (off, _) = mean_and_se(p);
        println!("PF(2000) from N{p:?}: mean ℓ {off:.4} (band ±{band:.4})");
        assert!(
            (off - exact).abs() > band,
            "PF from the wrong prior N{p:?}: {off} is within {band} of {exact}"
        );
    }
}

/// The builder with the prior N(0, 1) every reference starts from.
fn prior<M: zakai::method::Method>(b: zakai::Builder<'_, M>) -> zakai::Builder<'_, M> {
    prior_at(b, PRIOR)
}

/// The builder with the prior `N(m₀, P₀)`.
fn prior_at<M: zakai::method::Method>(
    b: zakai::Builder<'_, M>,
    (m0, p0): (f64, f64),
) -> zakai::Builder<'_, M> {
    b.prior_gaussian(&[m0], &[[p0]])
}

/// `ll(prior)`, a method's log-likelihood of the data from that prior, within `tolerance` of
/// the exact value from [`PRIOR`] — and, from each of [`WRONG_PRIORS`], outside it: the check
/// would catch a misplaced prior. Returns the error.
fn holds_and_tells_the_prior(
    name: &str,
    tolerance: f64,
    exact: f64,
    ll: impl Fn((f64, f64)) -> f64,
) -> f64 {
    let error = (ll(PRIOR) - exact).abs();
    let wrong = WRONG_PRIORS.map(|p| (ll(p) - exact).abs());
    println!(
        "{name}: |Δℓ| {error:.2e} (allowed {tolerance:.0e}); from a wrong prior {:.2e}, {:.2e}",
        wrong[0], wrong[1]
    );
    assert!(
        error < tolerance,
        "{name}: |Δℓ| = {error:e} (allowed {tolerance:e})"
    );
    for (p, off) in WRONG_PRIORS.iter().zip(wrong) {
        assert!(
            off > tolerance,
            "{name}: from the wrong prior N{p:?} ℓ is off by only {off:e}, within the tolerance"
        );
    }
    error
}

fn model(continuous: bool) -> Model {
    let noise = if continuous {
        Noise::continuous(1.0)
    } else {
        Noise::discrete(0.5)
    };
    Model::from_text(&["-x"], &["x"], noise).unwrap()
}

/// Discrete measurements: the Kalman and Gaussian-sum filters give the exact value to 10⁻⁹;
/// the extended, unscented and iterated filters to their RK4 moment equations' error (10⁻⁷
/// allowed; 1.2·10⁻⁸ measured); the grid filter of 001 converges to it (1.7·10⁻² on 800 cells,
/// 4.6·10⁻³ on 3200 measured) and on 3200 cells holds it within TOL_SA, which a wrong prior
/// breaks; the particle filter's mean over 20 seeds is within four standard errors of it.
#[test]
fn measurements_every_method_against_the_exact_likelihood() {
    let (data, model) = (data(false), model(false));
    let exact = kalman_log_likelihood(&data, false, PRIOR);
    assert!(exact.is_finite() && exact < 0.0, "{exact}");
    let moved = WRONG_PRIORS.map(|p| kalman_log_likelihood(&data, false, p) - exact);
    println!("a wrong prior moves the exact ℓ by {moved:.3?}");
    gaussian_filters_match(&model, &data, false, exact);
    let grid = |cells: usize, p: (f64, f64)| {
        let mut f = prior_at(zakai::Separation::builder(&model), p)
            .domain(&[(-6.0, 6.0)])
            .dt(DT)
            .with(|p| p.cells = vec![cells])
            .build()
            .unwrap();
        log_likelihood(&mut f, &data, false)
    };
    let coarse = (grid(800, PRIOR) - exact).abs();
    let fine = holds_and_tells_the_prior("SA (3200 cells)", TOL_SA, exact, |p| grid(3200, p));
    println!("SA: |Δℓ| {coarse:.2e} on 800 cells, {fine:.2e} on 3200 (ℓ = {exact:.4})");
    assert!(fine < 0.5 * coarse, "{coarse} → {fine}");
    particle_filter_matches(&model, &data, false, exact, 1e-3, &WRONG_PRIORS[1..]);
}

/// The log-likelihood of the increments `data` by the Yau–Yau method `M` (QIEM, IEM, SPT) on
/// [−6, 6] with `(points, dt)` nodes and inner step, `edit` applied to its parameters, from
/// the prior `p`.
fn yau_yau_log_likelihood<M: zakai::method::Method<Params = zakai::YauYauParams>>(
    model: &Model,
    data: &[(f64, f64)],
    (points, dt): (usize, f64),
    edit: fn(&mut zakai::YauYauParams),
    p: (f64, f64),
) -> f64 {
    let mut f = prior_at(zakai::Builder::<M>::new(model), p)
        .domain(&[(-6.0, 6.0)])
        .dt(DT_INCREMENTS)
        .with(|q| {
            q.points = vec![points];
            q.dt = dt;
            edit(q);
        })
        .build()
        .unwrap();
    log_likelihood(&mut f, data, true)
}

/// Tolerances on |Δℓ|, each 1.5 to 2.5 times the measured error (in the comment), and below
/// what a wrong prior changes: the shifted mean moves the exact ℓ of the increments by −0.085
/// and the doubled variance by −0.119; of the measurements by +0.021 and −0.223.
const TOL_SA: f64 = 8e-3; // 4.6e-3 (3200 cells)
const TOL_QIEM: f64 = 5e-3; // 3.3e-3 (3.3e-3 with 3 samples per cell)
const TOL_QIEM_IN_OPERATOR: f64 = 5e-3; // 2.4e-3
const TOL_IEM: f64 = 1e-3; // 4.1e-4
const TOL_SPT: f64 = 5e-3; // 3.3e-3
const TOL_SPECTRAL: f64 = 8e-4; // 3.9e-4 (64 functions)
const TOL_DIRECT: f64 = 5e-3; // 3.0e-3
const TOL_DIRECT_PARTIAL: f64 = 3e-3; // 1.1e-3 (a sensor that never reports)

/// Continuous observations: the Kalman–Bucy filter gives the exact value of the sampled model
/// to 10⁻⁹, the EKF/UKF to their RK4 moment equations' error (10⁻⁷ allowed). The grid and
/// spectral methods converge to it as their resolution grows (QIEM, IEM and SPT from 101
/// points and Δt = 0.02 to 401 and 0.005; the spectral filter from 32 to 64 functions) and, at the finer
/// resolution, hold it within their tolerances (the TOL_ constants, from the measured errors),
/// which a wrong prior would break; so does the direct method (002). The particle filter's
/// mean over seeds is within four standard errors, and from a wrong prior outside them.
#[test]
fn increments_every_method_against_the_exact_likelihood() {
    let (data, model) = (data(true), model(true));
    let exact = kalman_log_likelihood(&data, true, PRIOR);
    assert!(exact.is_finite(), "{exact}");
    let moved = WRONG_PRIORS.map(|p| kalman_log_likelihood(&data, true, p) - exact);
    println!("a wrong prior moves the exact ℓ by {moved:.3?}");
    gaussian_filters_match(&model, &data, true, exact);
    let qiem = |points: usize, dt: f64, edit: fn(&mut zakai::YauYauParams), p: (f64, f64)| {
        yau_yau_log_likelihood::<zakai::Qiem>(&model, &data, (points, dt), edit, p)
    };
    let coarse = (qiem(101, 0.02, |_| {}, PRIOR) - exact).abs();
    let fine = holds_and_tells_the_prior("QIEM (401, 0.005)", TOL_QIEM, exact, |p| {
        qiem(401, 0.005, |_| {}, p)
    });
    println!("QIEM: |Δℓ| {coarse:.2e} (101 points, Δt 0.02), {fine:.2e} (401, 0.005)");
    assert!(fine < 0.5 * coarse, "{coarse} → {fine}");
    // The same with the likelihood in the operator (000 (4): its implicit damping of
    // −½hᵀS⁻¹h is the less accurate form), and with the factor averaged over 3 samples per
    // cell.
    holds_and_tells_the_prior(
        "QIEM (401, 0.005), likelihood in the operator",
        TOL_QIEM_IN_OPERATOR,
        exact,
        |p| {
            qiem(
                401,
                0.005,
                |q| q.likelihood = zakai::LikelihoodPlacement::InOperator,
                p,
            )
        },
    );
    holds_and_tells_the_prior(
        "QIEM (401, 0.005), 3 samples per cell",
        TOL_QIEM,
        exact,
        |p| qiem(401, 0.005, |q| q.likelihood_samples = 3, p),
    );
    // IEM (the drift implicit) and the superposition technique on the same grid and step.
    let iem = |points: usize, dt: f64, p: (f64, f64)| {
        yau_yau_log_likelihood::<zakai::Iem>(&model, &data, (points, dt), |_| {}, p)
    };
    let coarse = (iem(101, 0.02, PRIOR) - exact).abs();
    let fine =
        holds_and_tells_the_prior("IEM (401, 0.005)", TOL_IEM, exact, |p| iem(401, 0.005, p));
    println!("IEM: |Δℓ| {coarse:.2e} (101 points, Δt 0.02), {fine:.2e} (401, 0.005)");
    assert!(fine < 0.5 * coarse, "IEM: {coarse} → {fine}");
    let spt = |points: usize, dt: f64, p: (f64, f64)| {
        yau_yau_log_likelihood::<zakai::Spt>(&model, &data, (points, dt), |_| {}, p)
    };
    let coarse = (spt(101, 0.02, PRIOR) - exact).abs();
    let fine =
        holds_and_tells_the_prior("SPT (401, 0.005)", TOL_SPT, exact, |p| spt(401, 0.005, p));
    println!("SPT: |Δℓ| {coarse:.2e} (101 points, Δt 0.02), {fine:.2e} (401, 0.005)");
    assert!(fine < 0.5 * coarse, "SPT: {coarse} → {fine}");
    let spectral = |basis: usize, p: (f64, f64)| {
        let mut f = prior_at(zakai::Spectral::builder(&model), p)
            .domain(&[(-6.0, 6.0)])
            .dt(DT_INCREMENTS)
            .with(|p| {
                p.offline_basis = Some(basis);
                p.online_basis = Some(basis);
            })
            .build()
            .unwrap();
        log_likelihood(&mut f, &data, true)
    };
    // The spectral filter's propagation over Δτ is one step (1 + Δτ𝓛) of 004's Algorithm 1
    // (N′ = 1): at Δτ = 0.2 its time error outweighed the basis (3.0·10⁻² with 16 functions,
    // 8.1·10⁻² with 32); at Δτ = 0.05 the basis sets the error (8.8·10⁻³ with 32 functions,
    // 3.9·10⁻⁴ with 64 measured).
    let s32 = (spectral(32, PRIOR) - exact).abs();
    let s64 = holds_and_tells_the_prior("spectral (64 functions)", TOL_SPECTRAL, exact, |p| {
        spectral(64, p)
    });
    println!("spectral: |Δℓ| {s32:.2e} (32 functions), {s64:.2e} (64)");
    assert!(s64 < 0.7 * s32, "spectral: {s32} → {s64}");
    let direct = |p: (f64, f64)| {
        let mut f = prior_at(zakai::Direct::builder(&model), p)
            .domain(&[(-6.0, 6.0)])
            .with(|p| p.linear = [-1.0, 0.0])
            .build()
            .unwrap();
        log_likelihood(&mut f, &data, true)
    };
    holds_and_tells_the_prior("direct", TOL_DIRECT, exact, direct);
    particle_filter_matches(&model, &data, true, exact, 1e-2, &WRONG_PRIORS);
}

/// A step that observes nothing — a gap, or every component missing — adds nothing, and a
/// step that fails leaves the last value.
#[test]
fn nothing_observed_adds_nothing_and_a_failed_step_keeps_the_value() {
    let model = model(false);
    let mut f = zakai::Ukf::builder(&model)
        .prior_gaussian(&[0.0], &[[1.0]])
        .build()
        .unwrap();
    f.step_measurement(0.2, &[0.4]).unwrap();
    let ll = f.log_likelihood().unwrap();
    assert!(ll != 0.0 && ll.is_finite());
    assert!(f.step_measurement(f64::NAN, &[0.1]).is_err());
    assert_eq!(f.log_likelihood(), Some(ll));
    f.predict(0.2).unwrap();
    assert_eq!(f.log_likelihood(), Some(0.0));
    f.step_measurement(0.2, &[f64::NAN]).unwrap();
    assert_eq!(f.log_likelihood(), Some(0.0));
}

/// The same method on the two-sensor and the one-sensor model.
type Pair = (Box<dyn Filter>, Box<dyn Filter>);

/// A sensor that never reports adds nothing: with h = (x, x) and the second component always
/// missing, every method's log-likelihood is the one-sensor model's on the same data (the
/// observed rows with their marginal noise), measurements and increments alike.
#[test]
fn a_missing_component_is_the_one_sensor_likelihood() {
    use zakai::nalgebra::DMatrix;
    for continuous in [false, true] {
        let data = data(continuous);
        let (two, one) = if continuous {
            let s = DMatrix::from_row_slice(2, 2, &[1.0, 0.3, 0.3, 0.8]);
            (Noise::Continuous(s), Noise::continuous(1.0))
        } else {
            let r = DMatrix::from_row_slice(2, 2, &[0.5, 0.2, 0.2, 0.4]);
            (Noise::Discrete(r), Noise::discrete(0.5))
        };
        let two = Model::from_text(&["-x"], &["x", "x"], two).unwrap();
        let one = Model::from_text(&["-x"], &["x"], one).unwrap();
        let run = |f: &mut dyn Filter, width: usize| -> f64 {
            data.iter()
                .map(|&(dt, value)| {
                    let z = [value, f64::NAN];
                    let z = &z[..width];
                    let obs = if continuous {
                        Observation::increment(dt, z)
                    } else {
                        Observation::measurement(dt, z)
                    };
                    f.step(&obs).unwrap();
                    f.log_likelihood().unwrap()
                })
                .sum()
        };
        let mut pairs: Vec<(&str, Pair)> = vec![
            (
                "KF",
                (
                    Box::new(prior(zakai::Kalman::builder(&two)).build().unwrap()),
                    Box::new(prior(zakai::Kalman::builder(&one)).build().unwrap()),
                ),
            ),
            (
                "UKF",
                (
                    Box::new(prior(zakai::Ukf::builder(&two)).build().unwrap()),
                    Box::new(prior(zakai::Ukf::builder(&one)).build().unwrap()),
                ),
            ),
            (
                "PF",
                (
                    Box::new(
                        prior(zakai::Pf::builder(&two))
                            .dt(step_of(continuous))
                            .seed(3)
                            .build()
                            .unwrap(),
                    ),
                    Box::new(
                        prior(zakai::Pf::builder(&one))
                            .dt(step_of(continuous))
                            .seed(3)
                            .build()
                            .unwrap(),
                    ),
                ),
            ),
        ];
        if continuous {
            let qiem = |m: &Model| -> Box<dyn Filter> {
                Box::new(
                    prior(zakai::Qiem::builder(m))
                        .domain(&[(-6.0, 6.0)])
                        .dt(DT_INCREMENTS)
                        .with(|p| p.points = vec![201])
                        .build()
                        .unwrap(),
                )
            };
            pairs.push(("QIEM", (qiem(&two), qiem(&one))));
        } else {
            let sa = |m: &Model| -> Box<dyn Filter> {
                Box::new(
                    prior(zakai::Separation::builder(m))
                        .domain(&[(-6.0, 6.0)])
                        .dt(DT)
                        // The same grid for both models (left unset, the cells would follow
                        // each model's information).
                        .with(|p| p.cells = vec![200])
                        .build()
                        .unwrap(),
                )
            };
            pairs.push(("SA", (sa(&two), sa(&one))));
            pairs.push((
                "GSF",
                (
                    Box::new(prior(zakai::GaussianSum::builder(&two)).build().unwrap()),
                    Box::new(prior(zakai::GaussianSum::builder(&one)).build().unwrap()),
                ),
            ));
        }
        for (name, (a, b)) in &mut pairs {
            let (with_two, with_one) = (run(a.as_mut(), 2), run(b.as_mut(), 1));
            assert!(
                (with_two - with_one).abs() <= 1e-9 * with_one.abs().max(1.0),
                "{name} (continuous {continuous}): {with_two} against {with_one}"
            );
        }
    }
}

/// The direct method (002) with a sensor that never reports: its partial step (the Kolmogorov
/// part alone, then the observed component's factor against the predicted mass) gives the
/// one-sensor likelihood up to the first-order splitting of the two forms, and both are within
/// the direct method's error of the exact value.
#[test]
fn the_direct_methods_partial_step_is_the_one_sensor_likelihood() {
    let data = data(true);
    let exact = kalman_log_likelihood(&data, true, PRIOR);
    let build = |m: &Model| {
        prior(zakai::Direct::builder(m))
            .domain(&[(-6.0, 6.0)])
            .with(|p| p.linear = [-1.0, 0.0])
            .build()
            .unwrap()
    };
    let two = Model::from_text(&["-x"], &["x", "x"], Noise::continuous(1.0)).unwrap();
    let mut f = build(&two);
    let partial: f64 = data
        .iter()
        .map(|&(dt, value)| {
            f.step(&Observation::increment(dt, &[value, f64::NAN]))
                .unwrap();
            f.log_likelihood().unwrap()
        })
        .sum();
    let whole = log_likelihood(&mut build(&model(true)), &data, true);
    println!("direct: partial {partial:.4}, whole {whole:.4}, exact {exact:.4}");
    // 002's form and the in-update splitting differ at first order in Δτ = 0.05 (4.1·10⁻³
    // measured; 10⁻² allowed); the partial step is within TOL_DIRECT_PARTIAL of the exact
    // value.
    assert!((partial - whole).abs() < 1e-2, "{partial} against {whole}");
    assert!(
        (partial - exact).abs() < TOL_DIRECT_PARTIAL,
        "{partial} against {exact}"
    );
}
