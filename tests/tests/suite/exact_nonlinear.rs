//! Every approximate method against an exact finite-dimensional filter of a *nonlinear*
//! model: Beneš's (V. E. Beneš, "Exact finite-dimensional filters for certain diffusions with
//! nonlinear drift", Stochastics 5, 1981). For `dx = tanh(x) dt + dw`, `dy = x dt + dv`,
//! f′ + f² = 1 is constant, so with `F = log cosh` the unnormalised density is
//! `u(t, x) = cosh(x) v(t, x)`, where v is the Kalman–Bucy density of the *linear* model
//! `dx = dw`, `dy = x dt + dv` (the constant ½(f′ + f²) drops on normalisation). A prior
//! `p₀ ∝ cosh(x) N(x; μ₀, P₀)` — the Gaussian mixture `w± N(μ₀ ± P₀, P₀)`, `w± ∝ e^{±μ₀}` —
//! therefore stays of that form, and the exact conditional mean is `μ_t + P_t tanh(μ_t)` with
//! `(μ_t, P_t)` from the Kalman–Bucy filter. With the filters' own discrete observation model
//! (a Gaussian likelihood of each increment, an exact prediction) this is exact step by step,
//! not only as Δτ → 0.
//!
//! This is the case: on a wide domain ([−12, 12]: the state drifts away from 0) each
//! method with its default sizes must either stay within a stated tolerance of the exact mean
//! or raise a self-check warning during the run — never be silently off.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::ScenarioConfig;
use zakai::Concern;
use zakai::{Filter, Kalman, Model, Noise, Observation};
use zakai_tests::test;

const MU0: f64 = 0.5;
const P0: f64 = 1.0;

fn benes_scenario() -> ScenarioConfig {
    let (wp, wm) = (MU0.exp(), (-MU0).exp());
    let json = serde_json::json!({
        "name": "benes",
        "title": "Beneš filter: dx = tanh(x) dt + dw, dy = x dt + dv",
        "reference": "Beneš (1981)",
        "description": "",
        "model": {
            "drift": ["tanh(x)"],
            "observation": ["x"],
            "diffusion": null,
            "noise": { "kind": "continuous", "cov": null }
        },
        "prior": {
            "kind": "mixture",
            "components": [
                { "weight": wp / (wp + wm), "mean": [MU0 + P0], "cov": [[P0]] },
                { "weight": wm / (wp + wm), "mean": [MU0 - P0], "cov": [[P0]] }
            ]
        },
        "initial_state": null,
        "domain": [[-12.0, 12.0]],
        "time": { "t_final": 4.0, "dt_obs": 0.01, "inner_steps": 10 },
        "seed": 5,
        "methods": [{ "method": "ekf" }]
    });
    serde_json::from_value(json).expect("a valid scenario")
}

/// Time-averaged RMS distance of each applicable method's mean from the exact Beneš mean over
/// `seeds`, and on how many steps it raised a self-check warning.
fn against_benes(seeds: &[u64]) -> Vec<(String, f64, f64, usize)> {
    let config = benes_scenario();
    let e = Experiment::new(config.clone()).expect("valid");
    let linear = Model::from_text(&["0"], &["x"], Noise::continuous(1.0)).unwrap();
    let dt = config.time.dt_obs;
    let mut out = Vec::new();
    for entry in zakai_tests::applicable_methods(&config, &e) {
        let m = entry.defaults;
        let (mut sum, mut worst, mut steps, mut warned) = (0.0, 0.0f64, 0, 0);
        for &seed in seeds {
            let data = e.simulate(seed).unwrap();
            let mut filter = e.build_method(&m, m.display_name(), seed).unwrap();
            let mut exact = Kalman::builder(&linear)
                .prior_gaussian(&[MU0], &[[P0]])
                .build()
                .unwrap();
            let mut concerns: Vec<Concern> = Vec::new();
            for k in 1..=data.steps() {
                let dy = data.observation(k);
                exact.step_increment(dt, dy).unwrap();
                if filter.step(&Observation::increment(dt, dy)).is_err() {
                    // A failure is a warning of its own (reported as the run's failure).
                    warned += 1;
                    break;
                }
                let kb = exact.estimate();
                let (mu, p) = (kb.mean[0], kb.covariance.unwrap()[(0, 0)]);
                let d = filter.estimate().mean[0] - (mu + p * mu.tanh());
                sum += d * d;
                worst = worst.max(d.abs());
                steps += 1;
                concerns.clear();
                filter.self_check(&mut concerns);
                warned += usize::from(!concerns.is_empty());
            }
        }
        out.push((
            entry.info.key.to_string(),
            (sum / steps.max(1) as f64).sqrt(),
            worst,
            warned,
        ));
    }
    out
}

/// Tolerances on the time-averaged RMS distance from the exact mean (seeds 1–3, 400 steps
/// each), per method, with what was measured on 2026-11-25: the grid filters 0.005 (0.0009–
/// 0.0011), the direct method 0.03 (0.015: its residual is carried with the zeroth-order
/// factor only, an O(Δτ) error), the particle filter 0.15 (0.09: Monte Carlo error of its
/// default particle count), the Gaussian filters 0.1 (EKF, IEKF, IOKF 0.037 — h is linear,
/// so the MAP update is the Kalman update and the three coincide —, UKF 0.057: the posterior
/// `cosh(x) N(μ, P)` is not Gaussian), the spectral filter 0.01.
fn tolerance(key: &str) -> f64 {
    match key {
        "qiem" | "iem" | "spt" | "qiem4" => 0.005,
        "direct" => 0.03,
        "pf" => 0.15,
        "ekf" | "ukf" | "iekf" | "iokf" => 0.1,
        _ => 0.01,
    }
}

/// Each method lands within its tolerance of the exact Beneš mean or warns during the run;
/// the grid filters and the direct method, which resolve the posterior here, must land within
/// it (a warning is no excuse for them). The spectral filter's default basis follows the
/// domain against the prior's width (36 functions here; with 004's fixed 16 it was off by
/// RMS 1.3): RMS 0.074, above its tolerance, and it warns on every step that its top
/// Legendre degrees hold too much of the coefficients' energy.
#[test]
fn every_method_is_near_the_exact_benes_mean_or_warns() {
    let results = against_benes(&[1, 2, 3]);
    let mut keys = Vec::new();
    for (key, rms, worst, warned) in &results {
        let tol = tolerance(key);
        println!(
            "{key:<10} RMS {rms:.5} (tolerance {tol})  worst {worst:.4}  warned on {warned} steps"
        );
        if ["qiem", "iem", "spt", "direct"].contains(&key.as_str()) {
            assert!(*rms <= tol, "{key}: RMS {rms} from the exact mean");
        } else {
            assert!(
                *rms <= tol || *warned > 0,
                "{key}: RMS {rms} from the exact mean (tolerance {tol}) and no warning"
            );
        }
        keys.push(key.as_str());
    }
    for key in [
        "ekf", "ukf", "pf", "iekf", "iokf", "qiem", "iem", "spt", "spectral", "direct",
    ] {
        assert!(keys.contains(&key), "{key} applies to the Beneš model");
    }
}

/// The convergence check (`zakai check`, [`zakai::lab::study::convergence`]) agrees with the exact
/// filter on the Beneš model (seed 1): QIEM, within 0.005 of the exact mean, is judged
/// converged (it moves by 0.0006 against a posterior sd of 1.07 when refined), and the
/// spectral filter with its default basis (36 functions), off by RMS 0.074, is judged not
/// converged (it moves by 0.064, more than 0.05 sd) — the check a user without an exact
/// filter can make.
#[test]
fn the_convergence_check_agrees_with_the_exact_filter() {
    use zakai::lab::study::convergence::convergence_check;
    let config = benes_scenario();
    let e = Experiment::new(config.clone()).expect("valid");
    let methods: Vec<_> = ["qiem", "spectral"]
        .iter()
        .map(|k| zakai::lab::scenario::MethodConfig::from_key(k).unwrap())
        .collect();
    let rows = convergence_check(&e, &methods, 1, 1 << 30).unwrap();
    for r in &rows {
        println!("{r:?}");
    }
    assert_eq!(rows[0].converged, Some(true), "QIEM: {:?}", rows[0]);
    assert_eq!(rows[1].converged, Some(false), "spectral: {:?}", rows[1]);
}

/// An independent reference for a bimodal posterior: the DMZ equation of `dx = −½x dt + dv`,
/// `dy = x² dt + dw` solved on a fine uniform grid by explicit finite differences (central
/// in space, forward Euler in time, steps within the stability bound Δt ≤ Δs²/2) and the
/// likelihood `exp(h Δy − ½h² Δτ)` of each increment — written here, sharing no code with
/// the filters. h = x² cannot tell x from −x, so the posterior of a prior straddling 0 keeps
/// two modes. (Native only, as the test that uses it.)
#[cfg(not(target_arch = "wasm32"))]
struct FineGrid {
    x: Vec<f64>,
    p: Vec<f64>,
    ds: f64,
}

#[cfg(not(target_arch = "wasm32"))]
impl FineGrid {
    fn new(lo: f64, hi: f64, points: usize, mean: f64, var: f64) -> Self {
        let ds = (hi - lo) / (points - 1) as f64;
        let x: Vec<f64> = (0..points).map(|i| lo + i as f64 * ds).collect();
        let mut p: Vec<f64> = x
            .iter()
            .map(|&x| (-(x - mean) * (x - mean) / (2.0 * var)).exp())
            .collect();
        let total: f64 = p.iter().sum::<f64>() * ds;
        p.iter_mut().for_each(|v| *v /= total);
        FineGrid { x, p, ds }
    }

    fn step(&mut self, dt: f64, dy: f64) {
        let substeps = (dt / (0.4 * self.ds * self.ds)).ceil() as usize;
        let h = dt / substeps as f64;
        let n = self.x.len();
        let mut next = vec![0.0; n];
        for _ in 0..substeps {
            for (i, out) in next.iter_mut().enumerate().take(n - 1).skip(1) {
                // ∂p/∂t = ½ p″ − ∂(f p)/∂x with f = −½x.
                let diffusion =
                    0.5 * (self.p[i + 1] - 2.0 * self.p[i] + self.p[i - 1]) / (self.ds * self.ds);
                let flux = |j: usize| -0.5 * self.x[j] * self.p[j];
                let drift = (flux(i + 1) - flux(i - 1)) / (2.0 * self.ds);
                *out = self.p[i] + h * (diffusion - drift);
            }
            next[0] = 0.0;
            next[n - 1] = 0.0;
            std::mem::swap(&mut self.p, &mut next);
        }
        for (p, &x) in self.p.iter_mut().zip(&self.x) {
            let hx = x * x;
            *p *= (hx * dy - 0.5 * hx * hx * dt).exp();
        }
        let total: f64 = self.p.iter().sum::<f64>() * self.ds;
        self.p.iter_mut().for_each(|v| *v /= total);
    }

    fn mean(&self) -> f64 {
        self.x.iter().zip(&self.p).map(|(x, p)| x * p).sum::<f64>() * self.ds
    }
}

/// Against the independent fine grid on the bimodal posterior (seeds 1–2, 300 intervals):
/// every method lands within its tolerance (as for Beneš's filter) of the conditional mean or
/// warns. The grid filters agree with the independent grid to 10⁻⁴ (measured 7·10⁻⁵), which
/// also checks the reference; EKF 0.083, UKF 0.038, PF 0.070 (the posterior mean drifts to 0
/// between the modes, and so do they). The MAP filters estimate a *mode* (003 §4) and follow
/// one of the two (RMS 0.56 from the mean): they must say so, by their second-mode watch,
/// on at least half of the steps where they are off by more than the tolerance (measured 493
/// of 586 for the IEKF, 492 of 585 for the IOKF; the steps left are the first 20, before the
/// watch has found and followed the second mode, and those where the two modes have nearly
/// merged, less than a quarter of a standard deviation from the mean).
// A Monte Carlo reproduction: run once, natively (its numbers are the core's, which the
// determinism test holds the wasm build to).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn every_method_is_near_the_fine_grid_mean_on_a_bimodal_posterior_or_warns() {
    let config = zakai_tests::bimodal_scenario(3.0);
    let e = Experiment::new(config.clone()).expect("valid");
    let dt = config.time.dt_obs;
    for entry in zakai_tests::applicable_methods(&config, &e) {
        let m = entry.defaults;
        let (mut sum, mut steps, mut warned) = (0.0, 0, 0);
        let (mut off, mut off_warned) = (0, 0);
        for seed in [1u64, 2] {
            let data = e.simulate(seed).unwrap();
            let mut filter = e.build_method(&m, m.display_name(), seed).unwrap();
            let mut reference = FineGrid::new(-6.0, 6.0, 1201, 0.3, 1.0);
            let mut concerns: Vec<Concern> = Vec::new();
            for k in 1..=data.steps() {
                let dy = data.observation(k);
                reference.step(dt, dy[0]);
                if filter.step(&Observation::increment(dt, dy)).is_err() {
                    warned += 1;
                    break;
                }
                let d = filter.estimate().mean[0] - reference.mean();
                sum += d * d;
                steps += 1;
                concerns.clear();
                filter.self_check(&mut concerns);
                warned += usize::from(!concerns.is_empty());
                if d.abs() > tolerance(&entry.info.key) {
                    off += 1;
                    off_warned += usize::from(!concerns.is_empty());
                }
            }
        }
        let key = entry.info.key.to_string();
        let rms = (sum / steps.max(1) as f64).sqrt();
        let tol = tolerance(&key);
        println!("{key:<10} RMS {rms:.5} (tolerance {tol})  warned on {warned} steps, on {off_warned} of the {off} steps off by more");
        match key.as_str() {
            "iekf" | "iokf" => assert!(
                2 * off_warned >= off,
                "{key}: warned on {off_warned} of the {off} steps it is off by more than {tol}"
            ),
            "qiem" | "iem" | "spt" => assert!(rms <= 1e-4, "{key}: RMS {rms} from the fine grid"),
            _ => assert!(
                rms <= tol || warned > 0,
                "{key}: RMS {rms} from the fine-grid mean (tolerance {tol}) and no warning"
            ),
        }
    }
}
