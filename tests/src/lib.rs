//! Helpers shared by the integration tests (most live in the test files themselves).
//!
//! The same tests run natively (`cargo test`) and in WebAssembly (`wasm-pack test --node` in
//! `tests/`): each file imports [`test`], the standard attribute natively and
//! `wasm_bindgen_test` on wasm32. Files that need the file system or threads are native only.

#[cfg(not(target_arch = "wasm32"))]
pub use core::prelude::v1::test;
#[cfg(target_arch = "wasm32")]
pub use wasm_bindgen_test::wasm_bindgen_test as test;

pub mod kalman_reference;

/// `l.score(θ)` (the method's ln L and its gradient) against `l.log_likelihood`: the same ln L
/// to 1e-10 relative, and a gradient equal to central differences of ln L (steps `step` and
/// 2·`step` times max(|θ_p|, 1), Richardson-extrapolated) to `tolerance` of the gradient's
/// size.
pub fn assert_score_is_the_derivative(
    l: &zakai::lab::fit::Likelihood,
    theta: &[f64],
    step: f64,
    tolerance: f64,
) {
    let score = l.score(theta).expect("a score").unwrap();
    let value = l.log_likelihood(theta).unwrap();
    println!(
        "θ = {theta:?}: ln L {} (run {value}), gradient {:?}",
        score.log_likelihood, score.gradient
    );
    assert!(
        (score.log_likelihood - value).abs() < 1e-10 * value.abs(),
        "{} vs {value}",
        score.log_likelihood
    );
    let size = score.gradient.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    for p in 0..theta.len() {
        let difference = |h: f64| {
            let (mut up, mut down) = (theta.to_vec(), theta.to_vec());
            up[p] += h;
            down[p] -= h;
            (l.log_likelihood(&up).unwrap() - l.log_likelihood(&down).unwrap()) / (2.0 * h)
        };
        let h = step * theta[p].abs().max(1.0);
        let (coarse, fine) = (difference(2.0 * h), difference(h));
        let extrapolated = fine + (fine - coarse) / 3.0;
        println!(
            "  ∂/∂θ{p}: score {:.10e}, differences {extrapolated:.10e}",
            score.gradient[p]
        );
        assert!(
            (score.gradient[p] - extrapolated).abs() < tolerance * size,
            "θ{p}: {} vs {extrapolated}",
            score.gradient[p]
        );
    }
}

/// The `.rs` files under `path` (or `path` itself), for the tests that read sources.
pub fn rust_files(path: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    if path.is_dir() {
        for entry in std::fs::read_dir(path).unwrap() {
            out.extend(rust_files(&entry.unwrap().path()));
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_path_buf());
    }
    out
}

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::ScenarioConfig;
use zakai::lab::scenario::{catalogue, CatalogueEntry};

/// Presets that between them apply every method of the catalogue.
pub const PRESETS_FOR_EVERY_METHOD: [&str; 6] = [
    "cubic-sensor-1d",
    "sa-example-1",
    "direct-4.3",
    "yau-2d",
    "bearings-only",
    "sv-ar1",
];

/// Observation row k of a simulated run, as the increment or measurement its model takes.
pub fn observation_of(data: &zakai::simulate::Trajectory, k: usize) -> zakai::Observation<'_> {
    let z = data.observation(k);
    if data.continuous {
        zakai::Observation::increment(data.dt_obs, z)
    } else {
        zakai::Observation::measurement(data.dt_obs, z)
    }
}

/// A model whose posterior keeps two modes: `dx = −½x dt + dv`, `dy = x² dt + dw` (h = x²
/// cannot tell x from −x) with the prior N(0.3, 1) straddling 0 and the state starting at 1.2,
/// on [−6, 6], Δτ = 0.01, running the EKF (tests choose their methods).
pub fn bimodal_scenario(t_final: f64) -> ScenarioConfig {
    let json = serde_json::json!({
        "name": "bimodal",
        "title": "h = x²: dx = −½x dt + dv, dy = x² dt + dw",
        "reference": "",
        "description": "",
        "model": {
            "drift": ["-0.5*x"],
            "observation": ["x^2"],
            "diffusion": null,
            "noise": { "kind": "continuous", "cov": null }
        },
        "prior": { "kind": "gaussian", "mean": [0.3], "cov": [[1.0]] },
        "initial_state": [1.2],
        "domain": [[-6.0, 6.0]],
        "time": { "t_final": t_final, "dt_obs": 0.01, "inner_steps": 10 },
        "seed": 5,
        "methods": [{ "method": "ekf" }]
    });
    serde_json::from_value(json).expect("a valid scenario")
}

/// The catalogue's methods that apply, with their default parameters, to the scenario
/// `config` (built as `experiment`) and need at most 64 MiB.
pub fn applicable_methods(config: &ScenarioConfig, experiment: &Experiment) -> Vec<CatalogueEntry> {
    catalogue()
        .into_iter()
        .filter(|entry| {
            let m = &entry.defaults;
            m.suitability(
                experiment.model(),
                experiment.prior(),
                &config.probe_points(),
                &config.bounds(),
            )
            .is_none()
                && m.memory_bytes(experiment.model().n)
                    .is_some_and(|b| b <= 64 << 20)
        })
        .collect()
}

/// A cell of a paper's table that Zakai does not reproduce, stated with the reason: the
/// per-row check asserts that it still deviates (so the list stays true) instead of that it
/// agrees.
pub struct Deviation {
    /// Row label.
    pub row: &'static str,
    /// Method (display name, as in the table).
    pub method: &'static str,
    /// Why it does not reproduce (also in docs/reproduction.md).
    pub why: &'static str,
}

/// How many standard errors of the difference a reproduced cell may be off: k = 3.
pub const K: f64 = 3.0;

/// Runs every row of the paper's table `id` with `runs` runs from the preset's seed and
/// compares every cell that has a paper value with it, component by component. The standard
/// error of the difference combines ours (`s`, from the runs) with the paper's, which the
/// papers do not report and which is taken as ours scaled to the paper's run count,
/// `s·√(runs / paper runs)`; a cell reproduces when `|ours − paper| ≤ K·√(s² + s_paper²)`.
/// Cells listed in `deviations` must instead lie outside that band. Prints every comparison;
/// returns the rows for further checks.
pub fn compare_with_paper(
    id: &str,
    runs: usize,
    deviations: &[Deviation],
) -> Vec<zakai::lab::reproduction::RowResult> {
    let table = zakai::lab::papers::table(id).expect("a reproduced table");
    let mut seen = vec![false; deviations.len()];
    let mut rows = Vec::new();
    for row in &table.rows {
        let r = zakai::lab::reproduction::reproduce_row(&table, row, runs, &|| {}).expect("runs");
        for cell in &r.cells {
            let Some(paper) = cell.paper.values() else {
                continue;
            };
            let ours = cell
                .ours
                .as_ref()
                .unwrap_or_else(|| panic!("{id} {}: {} failed in every run", row.label, cell.name));
            let stderr = cell.stderr.as_ref().expect("standard errors");
            let listed = deviations
                .iter()
                .position(|d| d.row == row.label && d.method == cell.name);
            for (i, ((&o, &p), &s)) in ours.iter().zip(paper).zip(stderr).enumerate() {
                let s_paper = s * (runs as f64 / table.runs as f64).sqrt();
                let band = K * (s * s + s_paper * s_paper).sqrt();
                let off = (o - p).abs() / (band / K);
                println!(
                    "{id} {:<10} {:<10} [{i}] ours {o:.4} ± {s:.4}, paper {p:.4}: {off:.1} s.e. of the difference{}",
                    row.label,
                    cell.name,
                    if listed.is_some() { " (listed as not reproduced)" } else { "" }
                );
                match listed {
                    None => assert!(
                        (o - p).abs() <= band,
                        "{id} {} {} [{i}]: ours {o:.4} ± {s:.4} against the paper's {p:.4}, {off:.1} standard errors of the difference apart (k = {K})",
                        row.label,
                        cell.name
                    ),
                    Some(d) => {
                        seen[d] = true;
                        assert!(
                            (o - p).abs() > band,
                            "{id} {} {} [{i}]: listed as not reproduced ({}) but ours {o:.4} ± {s:.4} is within {K} standard errors of the paper's {p:.4}: take it off the list",
                            row.label,
                            cell.name,
                            deviations[d].why
                        );
                    }
                }
            }
        }
        rows.push(r);
    }
    for (d, seen) in deviations.iter().zip(seen) {
        assert!(
            seen,
            "{id}: listed deviation {} {} is not a cell of the table",
            d.row, d.method
        );
    }
    rows
}

include!("../../core/examples/data/nile.rs");

/// The point-mass transition of the double well `dx = (x − x³) dt + g dv` over one
/// Euler–Maruyama step `h`, between the equally spaced nodes `xs`: for each source node, the
/// nodes the Gaussian N(x + (x − x³)h, g²h) reaches (8 sds) with their weights, normalised to
/// 1 — the references' kernel, written here, independent of Zakai.
pub fn double_well_kernel(xs: &[f64], h: f64, g2: f64) -> Vec<Vec<(usize, f64)>> {
    let (lo, dx, nodes) = (xs[0], xs[1] - xs[0], xs.len());
    xs.iter()
        .map(|&x| {
            let (mu, var) = (x + (x - x * x * x) * h, g2 * h);
            let reach = (8.0 * var.sqrt() / dx).ceil() as isize + 1;
            let centre = ((mu - lo) / dx).round() as isize;
            let mut row: Vec<(usize, f64)> = (centre - reach..=centre + reach)
                .filter(|&j| j >= 0 && (j as usize) < nodes)
                .map(|j| {
                    let d = xs[j as usize] - mu;
                    (j as usize, (-d * d / (2.0 * var)).exp())
                })
                .collect();
            let total: f64 = row.iter().map(|e| e.1).sum();
            row.iter_mut().for_each(|e| e.1 /= total);
            row
        })
        .collect()
}

/// `K p` for a kernel of [`double_well_kernel`] (rows are source nodes).
pub fn carry(kernel: &[Vec<(usize, f64)>], p: &[f64]) -> Vec<f64> {
    let mut next = vec![0.0; p.len()];
    for (i, row) in kernel.iter().enumerate() {
        for &(j, w) in row {
            next[j] += p[i] * w;
        }
    }
    next
}

/// `Kᵀ r` for a kernel of [`double_well_kernel`].
pub fn carry_back(kernel: &[Vec<(usize, f64)>], r: &[f64]) -> Vec<f64> {
    kernel
        .iter()
        .map(|row| row.iter().map(|&(j, w)| w * r[j]).sum())
        .collect()
}

/// A small generator of the tests' own (64-bit LCG, Box–Muller), so that data the tests
/// simulate owe nothing to Zakai.
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform on (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// The larger of `a` and `b`, NaN when either is: `f64::max` drops a NaN, so a fold with it
/// would report a NaN estimate as no gap at all.
pub fn max_or_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The largest |x̂ − reference mean| over the rows, in reference sds, of method `index` of
/// `run` (which must not have failed, and must have a row for every reference row).
pub fn worst_gap(
    run: &zakai::lab::experiment::RunResult,
    index: usize,
    means: &[f64],
    sds: &[f64],
) -> f64 {
    let track = &run.methods[index];
    assert!(
        track.failure.is_none(),
        "{}: {:?}",
        track.name,
        track.failure
    );
    assert_eq!(track.estimates.len(), means.len(), "{}", track.name);
    track
        .estimates
        .iter()
        .zip(means.iter().zip(sds))
        .map(|(e, (m, s))| (e - m).abs() / s)
        .fold(0.0, max_or_nan)
}

/// Simulated measurements as a recorded series with a gap and an irregular step: the rows in
/// `gap` missing (NaN in every component) and row `dropped` left out (an interval twice as
/// long), with the truth and the known inputs (the row after the dropped one keeps its own:
/// they are held over the whole longer interval).
pub fn with_gap_and_irregular_step(
    data: &zakai::simulate::Trajectory,
    gap: core::ops::Range<usize>,
    dropped: usize,
) -> zakai::lab::recording::Recording {
    let (n, m) = (data.n, data.m);
    let (mut times, mut z, mut truth, mut inputs) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for k in (0..data.times.len()).filter(|&k| k != dropped) {
        times.push(data.times[k]);
        inputs.extend_from_slice(data.inputs_at(k));
        let row = data.observation(k);
        z.extend(
            row.iter()
                .map(|&v| if gap.contains(&k) { f64::NAN } else { v }),
        );
        truth.extend_from_slice(&data.states[k * n..(k + 1) * n]);
    }
    zakai::lab::recording::Recording::measurements(n, m, times, &z)
        .unwrap()
        .with_truth(truth)
        .unwrap()
        .with_inputs(data.input_count, inputs)
        .unwrap()
}
