//! Stiff and wide problems at the methods' defaults: nothing silently wrong.
//!
//! Drifts the presets never draw — `−a x³`, `−a x⁵`, `a (x − 2x³)` with scales a up to 10 —
//! on boxes up to ±10, with the diffusion G and the observation noise S each over two
//! decades, observed through h = x (increments for the Yau–Yau and spectral filters, discrete
//! measurements for the continuous–discrete grid filters of 001). Every grid and spectral
//! method is built with nothing but the prior, the box and Δτ, and its conditional mean is
//! held against a reference density the test computes itself: within 0.05 reference
//! posterior sd at every step, or loud — a build or step that fails, a guarantee the method
//! reports as violated, or a self-check whose cause the reference confirms (mass near the
//! boundary only counts where the reference has mass there). SA and FDM, first order, choose
//! their cells and steps so that their numerical diffusion under the prior is small, and are
//! loud through their numerical-diffusion self-check where it is not
//! (`core/src/filters/fpe_split/numerical_diffusion.rs`): of their eleven runs here, ten are
//! within 0.033 sd, and SA's on −2.5x³ over ±9.5 (its cells capped at 4000) is 0.18 sd off
//! with that check.
//!
//! The reference: the Fokker–Planck equation `∂p/∂t = −∂(f p)/∂x + ½G² ∂²p/∂x²` on the line
//! where the density lives (±(min(L, 5) + 1), doubled while mass reaches its ends, where the
//! flux is zero), by finite volumes with Scharfetter–Gummel fluxes (exact for a drift constant
//! across a cell face) on cells fine enough that the cell Péclet number |f| h/D stays below
//! 1/4 on |x| ≤ 3, and implicit Euler in time (positive and stable at any step); then Bayes'
//! rule with the increment's likelihood `exp(h Δy/S − h² Δτ/(2S))` or the measurement's
//! `N(z; h, S)` cell by cell. It is checked against itself at half the resolution in space and
//! time (within 0.02 sd). The issue asked for a point-mass reference; resolving a Gaussian
//! transition kernel of width G√δ on these drifts needed far more nodes than this scheme.

use zakai::nalgebra::DMatrix;
use zakai::{Concern, Filter, Iem, ImplicitFdm, Model, Noise, Qiem, Separation, Spectral, Spt};
use zakai_tests::test;
use zakai_tests::Lcg;

/// The drifts drawn, with their formulas for the model and for the reference.
#[derive(Clone, Copy, Debug)]
enum Drift {
    Cubic,
    Quintic,
    DoubleWell,
}

impl Drift {
    fn text(self, a: f64) -> String {
        match self {
            Drift::Cubic => format!("-{a}*x^3"),
            Drift::Quintic => format!("-{a}*x^5"),
            Drift::DoubleWell => format!("{a}*(x - 2*x^3)"),
        }
    }
    fn eval(self, a: f64, x: f64) -> f64 {
        match self {
            Drift::Cubic => -a * x.powi(3),
            Drift::Quintic => -a * x.powi(5),
            Drift::DoubleWell => a * (x - 2.0 * x.powi(3)),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Problem {
    drift: Drift,
    scale: f64,
    half_width: f64,
    g: f64,
    s: f64,
}

const DT_OBS: f64 = 0.01;
const STEPS: usize = 20;
const PRIOR: (f64, f64) = (0.3, 1.0);

/// `exp(ln lo + u (ln hi − ln lo))`: log-uniform on [lo, hi].
fn log_uniform(rng: &mut Lcg, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.uniform() * (hi.ln() - lo.ln())).exp()
}

fn draw(rng: &mut Lcg, drift: Drift) -> Problem {
    Problem {
        drift,
        scale: log_uniform(rng, 1.0, 10.0),
        half_width: 3.0 + 7.0 * rng.uniform(),
        g: log_uniform(rng, 0.2, 20.0),
        s: log_uniform(rng, 0.01, 1.0),
    }
}

/// The truth from the prior by Euler–Maruyama with 200 substeps per interval, and its
/// observations: increments `∫h dt + √S ΔW` or measurements `h(x) + √S ε`.
fn observe(p: &Problem, discrete: bool, rng: &mut Lcg) -> Vec<f64> {
    const FINE: usize = 200;
    let dt = DT_OBS / FINE as f64;
    let mut x = PRIOR.0 + PRIOR.1.sqrt() * rng.normal();
    (0..STEPS)
        .map(|_| {
            let mut integral = 0.0;
            for _ in 0..FINE {
                integral += x * dt;
                // A stiff drift's explicit step is kept from overshooting by the substep.
                x += p.drift.eval(p.scale, x) * dt + p.g * dt.sqrt() * rng.normal();
            }
            if discrete {
                x + p.s.sqrt() * rng.normal()
            } else {
                integral + (p.s * DT_OBS).sqrt() * rng.normal()
            }
        })
        .collect()
}

/// The reference filter's means and sds after every observation, on `cells` cells with
/// `substeps` implicit steps per interval.
fn reference(p: &Problem, discrete: bool, obs: &[f64], refine: usize) -> Result<Reference, f64> {
    // The drifts confine beyond |x| ≈ 2: the line is cut at ±(min(L, 5) + 1), or further
    // when mass reaches its ends (where the flux is zero).
    let mut reach = p.half_width.min(5.0) + 1.0;
    loop {
        match reference_on(p, discrete, obs, reach, refine) {
            Err(at_ends) if reach < 40.0 => {
                eprintln!("reach {reach}: {at_ends:e} at the ends");
                reach *= 2.0;
            }
            done => return done,
        }
    }
}

/// [`reference`] on ±`reach`, with cells fine enough that the cell Péclet number |f| h / D
/// stays below 1/4 where the density lives (|x| ≤ 3), and 100 steps per interval, both times
/// `refine`; the mass that reached the ends as the error.
fn reference_on(
    p: &Problem,
    discrete: bool,
    obs: &[f64],
    reach: f64,
    refine: usize,
) -> Result<Reference, f64> {
    let diffusion = 0.5 * p.g * p.g;
    let steep = (0..=300)
        .map(|k| p.drift.eval(p.scale, -3.0 + 0.02 * k as f64).abs())
        .fold(0.0, f64::max);
    let cells = (2.0 * reach * steep / (0.25 * diffusion)).clamp(4000.0, 8000.0) as usize * refine;
    let substeps = 100 * refine;
    let h = 2.0 * reach / cells as f64;
    let xs: Vec<f64> = (0..cells).map(|i| -reach + (i as f64 + 0.5) * h).collect();
    let mut density: Vec<f64> = xs
        .iter()
        .map(|x| (-(x - PRIOR.0).powi(2) / (2.0 * PRIOR.1)).exp())
        .collect();
    // Face k between cells k and k + 1: flux F = (D/h)(B(−Pe) p_k − B(Pe) p_(k+1)),
    // Pe = f h / D, B(z) = z/(eᶻ − 1) (the Bernoulli function).
    let bernoulli = |z: f64| {
        if z.abs() < 1e-8 {
            1.0 - 0.5 * z
        } else {
            z / z.exp_m1()
        }
    };
    let delta = DT_OBS / substeps as f64;
    // (I − δ A) p_new = p_old, A p_k = (F_(k−1/2) − F_(k+1/2))/h with no flux through the ends.
    let mut matrix = Tridiagonal::identity(cells);
    for k in 0..cells - 1 {
        let pe = p.drift.eval(p.scale, -reach + (k as f64 + 1.0) * h) * h / diffusion;
        let (out, back) = (
            diffusion / h * bernoulli(-pe),
            diffusion / h * bernoulli(pe),
        );
        // F_(k+1/2) = out p_k − back p_(k+1) leaves cell k and enters cell k + 1.
        matrix.diag[k] += delta * out / h;
        matrix.upper[k] -= delta * back / h;
        matrix.diag[k + 1] += delta * back / h;
        matrix.lower[k + 1] -= delta * out / h;
    }
    let solve = matrix.factor();
    let mut out = Reference {
        means: Vec::new(),
        sds: Vec::new(),
        xs: xs.clone(),
        last: Vec::new(),
    };
    for &y in obs {
        for _ in 0..substeps {
            solve.solve(&mut density);
        }
        for (d, x) in density.iter_mut().zip(&xs) {
            let log_likelihood = if discrete {
                -(y - x).powi(2) / (2.0 * p.s)
            } else {
                x * y / p.s - x * x * DT_OBS / (2.0 * p.s)
            };
            *d *= log_likelihood.exp();
        }
        let mass: f64 = density.iter().sum();
        assert!(mass > 0.0 && mass.is_finite(), "reference mass {mass}");
        density.iter_mut().for_each(|d| *d /= mass);
        let at_ends: f64 = density[..cells / 50]
            .iter()
            .chain(&density[cells - cells / 50..])
            .sum();
        if at_ends > 1e-9 {
            return Err(at_ends);
        }
        let mean: f64 = density.iter().zip(&xs).map(|(d, x)| d * x).sum();
        let var: f64 = density
            .iter()
            .zip(&xs)
            .map(|(d, x)| d * (x - mean).powi(2))
            .sum();
        out.means.push(mean);
        out.sds.push(var.sqrt());
    }
    out.last = density;
    Ok(out)
}

struct Reference {
    means: Vec<f64>,
    sds: Vec<f64>,
    xs: Vec<f64>,
    /// The last step's cell masses.
    last: Vec<f64>,
}

impl Reference {
    /// The last step's mass within a twentieth of the box's width of its edges or beyond.
    fn mass_near_edge(&self, half_width: f64) -> f64 {
        self.xs
            .iter()
            .zip(&self.last)
            .filter(|(x, _)| x.abs() > 0.9 * half_width)
            .map(|(_, d)| d)
            .sum()
    }
}

/// A tridiagonal matrix (row i: `lower[i] x_(i−1) + diag[i] x_i + upper[i] x_(i+1)`).
struct Tridiagonal {
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
}

/// [`Tridiagonal`] eliminated once (Thomas' algorithm without pivoting: the implicit step's
/// matrix is an M-matrix, diagonally dominant by columns).
struct Factored {
    lower: Vec<f64>,
    /// `1 / pivot_i`.
    inverse_pivot: Vec<f64>,
    /// `upper_i / pivot_i`.
    ratio: Vec<f64>,
}

impl Tridiagonal {
    fn identity(n: usize) -> Self {
        Tridiagonal {
            lower: vec![0.0; n],
            diag: vec![1.0; n],
            upper: vec![0.0; n],
        }
    }

    fn factor(&self) -> Factored {
        let n = self.diag.len();
        let (mut inverse_pivot, mut ratio) = (vec![0.0; n], vec![0.0; n]);
        for i in 0..n {
            let pivot = self.diag[i]
                - if i > 0 {
                    self.lower[i] * ratio[i - 1]
                } else {
                    0.0
                };
            inverse_pivot[i] = 1.0 / pivot;
            ratio[i] = self.upper[i] / pivot;
        }
        Factored {
            lower: self.lower.clone(),
            inverse_pivot,
            ratio,
        }
    }
}

impl Factored {
    fn solve(&self, rhs: &mut [f64]) {
        let n = rhs.len();
        rhs[0] *= self.inverse_pivot[0];
        for i in 1..n {
            rhs[i] = (rhs[i] - self.lower[i] * rhs[i - 1]) * self.inverse_pivot[i];
        }
        for i in (0..n - 1).rev() {
            rhs[i] -= self.ratio[i] * rhs[i + 1];
        }
    }
}

/// What a method did on one problem.
enum Outcome {
    /// Within the tolerance at every step (the worst gap in reference sds).
    Right(f64),
    /// Off by this many sds, and it said so (how).
    Warned(f64, String),
    /// Off by this many sds with nothing said that explains it (what it said, if anything).
    Silent(f64, String),
}

/// The bound (issue 56): within 0.05 posterior sd, or loud.
const TOLERANCE: f64 = 0.05;

fn run(
    (name, tolerance): (&str, f64),
    built: Result<impl Filter, zakai::ZakaiError>,
    obs: &[f64],
    discrete: bool,
    exact: &Reference,
    half_width: f64,
) -> Outcome {
    let mut filter = match built {
        Ok(f) => f,
        Err(e) => return Outcome::Warned(f64::NAN, format!("refused: {e}")),
    };
    let violated: Vec<String> = filter
        .warnings()
        .into_iter()
        .filter(|w| w.contains("violated"))
        .collect();
    let mut gap = 0.0f64;
    let mut concerns: Vec<Concern> = Vec::new();
    for (k, &y) in obs.iter().enumerate() {
        let step = if discrete {
            filter.step_measurement(DT_OBS, &[y])
        } else {
            filter.step_increment(DT_OBS, &[y])
        };
        if let Err(e) = step {
            return Outcome::Warned(f64::NAN, format!("step {k} failed: {e}"));
        }
        let mean = filter.estimate().mean[0];
        gap = zakai_tests::max_or_nan(gap, (mean - exact.means[k]).abs() / exact.sds[k]);
        filter.self_check(&mut concerns);
    }
    let edge = exact.mass_near_edge(half_width);
    let explaining: Vec<String> = concerns
        .iter()
        .filter(|c| c.check != "mass near the boundary" || edge > 1e-4)
        .map(|c| format!("{}: {}", c.check, c.advice))
        .chain(violated)
        .collect();
    let said = concerns
        .iter()
        .map(|c| c.check)
        .collect::<Vec<_>>()
        .join(", ");
    if gap <= tolerance {
        Outcome::Right(gap)
    } else if let Some(first) = explaining.first() {
        Outcome::Warned(gap, first.clone())
    } else {
        Outcome::Silent(
            gap,
            format!("{name}: {said} (reference mass near the edge {edge:.1e})"),
        )
    }
}

/// 6 problems (each drift twice, seed 56), each with increments (QIEM, IEM, SPT, the
/// spectral filter) and with measurements (SA, FDM), 20 intervals of Δτ = 0.01: every
/// method within 0.05 sd of the reference or loud, and the reference within 0.02 sd of
/// itself at half the cells and twice the step. Two tests, one per kind of observation, so
/// that the two halves run side by side (the same draws: each draws both kinds' data).
#[test]
fn stiff_and_wide_problems_are_right_or_loud_at_the_defaults_with_increments() {
    right_or_loud(false);
}

/// See [`stiff_and_wide_problems_are_right_or_loud_at_the_defaults_with_increments`].
#[test]
fn stiff_and_wide_problems_are_right_or_loud_at_the_defaults_with_measurements() {
    right_or_loud(true);
}

/// The six problems with increments (`measurements == false`) or measurements.
fn right_or_loud(measurements: bool) {
    let mut rng = Lcg(56);
    let mut silent = Vec::new();
    let (mut right, mut warned) = (0, 0);
    for drift in [Drift::Cubic, Drift::Quintic, Drift::DoubleWell].repeat(2) {
        let p = draw(&mut rng, drift);
        let text = p.drift.text(p.scale);
        let g = DMatrix::from_element(1, 1, p.g);
        let bounds = [(-p.half_width, p.half_width)];
        for discrete in [false, true] {
            let obs = observe(&p, discrete, &mut rng);
            if discrete != measurements {
                continue;
            }
            let exact = reference(&p, discrete, &obs, 2).unwrap();
            let coarse = reference(&p, discrete, &obs, 1).unwrap();
            let own = exact
                .means
                .iter()
                .zip(&coarse.means)
                .zip(&exact.sds)
                .map(|((a, b), s)| (a - b).abs() / s)
                .fold(0.0, f64::max);
            eprintln!("reference: {own:.4} sd from itself at half resolution");
            assert!(
                own < 0.02,
                "{p:?}: the reference moved by {own} sd at half resolution"
            );
            let noise = if discrete {
                Noise::discrete(p.s)
            } else {
                Noise::continuous(p.s)
            };
            let model = Model::from_text(&[&text], &["x"], noise)
                .and_then(|m| m.with_diffusion(g.clone()))
                .unwrap();
            macro_rules! build {
                ($method:ty) => {
                    <$method>::builder(&model)
                        .prior_gaussian(&[PRIOR.0], &[[PRIOR.1]])
                        .domain(&bounds)
                        .dt(DT_OBS)
                        .build()
                };
            }
            let outcomes: Vec<(&str, Outcome)> = if discrete {
                // SA's upwind step obeys the CFL condition 001 (16), |f| Δt ≤ Δx, by
                // sub-stepping: with |f| above 10⁴ at the box's edge (the quintic on ±7) that
                // is some 10⁵ steps per interval, a minute of this test for one row; its
                // cost, not its accuracy, is the limit there, and FDM covers those problems.
                let steepest = p.drift.eval(p.scale, p.half_width).abs();
                let mut rows = vec![(
                    "FDM",
                    run(
                        ("FDM", TOLERANCE),
                        build!(ImplicitFdm),
                        &obs,
                        true,
                        &exact,
                        p.half_width,
                    ),
                )];
                if steepest <= 1e4 {
                    rows.push((
                        "SA",
                        run(
                            ("SA", TOLERANCE),
                            build!(Separation),
                            &obs,
                            true,
                            &exact,
                            p.half_width,
                        ),
                    ));
                }
                rows
            } else {
                vec![
                    (
                        "QIEM",
                        run(
                            ("QIEM", TOLERANCE),
                            build!(Qiem),
                            &obs,
                            false,
                            &exact,
                            p.half_width,
                        ),
                    ),
                    (
                        "IEM",
                        run(
                            ("IEM", TOLERANCE),
                            build!(Iem),
                            &obs,
                            false,
                            &exact,
                            p.half_width,
                        ),
                    ),
                    (
                        "SPT",
                        run(
                            ("SPT", TOLERANCE),
                            build!(Spt),
                            &obs,
                            false,
                            &exact,
                            p.half_width,
                        ),
                    ),
                    (
                        "Spectral",
                        run(
                            ("Spectral", TOLERANCE),
                            build!(Spectral),
                            &obs,
                            false,
                            &exact,
                            p.half_width,
                        ),
                    ),
                ]
            };
            for (name, outcome) in outcomes {
                match outcome {
                    Outcome::Right(gap) => {
                        right += 1;
                        eprintln!("{name} on {text} ±{:.1} G {:.2} S {:.3}: within {gap:.3} sd", p.half_width, p.g, p.s);
                    }
                    Outcome::Warned(gap, why) => {
                        warned += 1;
                        eprintln!("{name} on {text} ±{:.1} G {:.2} S {:.3}: off by {gap:.3} sd, and said {why}", p.half_width, p.g, p.s);
                    }
                    Outcome::Silent(gap, said) => silent.push(format!(
                        "{name} on {text} ±{:.1} G {:.2} S {:.3}: off by {gap:.3} sd; said only {said}",
                        p.half_width, p.g, p.s
                    )),
                }
            }
        }
    }
    eprintln!("{right} within {TOLERANCE} sd, {warned} off and loud");
    assert!(silent.is_empty(), "silently wrong:\n{}", silent.join("\n"));
}

/// The case (issue 56, item 1): dx = −x³ dt + 0.5 dv, dy = x dt + dw with S = 0.1,
/// prior N(0.3, 1), Δτ = 0.01, on [−5, 5] and on the wider [−6, 6]. QIEM at its defaults
/// (Δt = 10⁻³) broke its stability condition where |f| = 125 and said 2.75 ± 3.94 where the
/// posterior was 0.10 ± 0.84, and widening the box made it worse; now it shortens its step
/// until (31) and Δt p² ≤ Q hold, says so, and is within 0.05 sd of the reference on both
/// boxes.
#[test]
fn qiem_on_a_stiff_cubic_drift_shortens_its_step_and_is_right() {
    for half_width in [5.0, 6.0] {
        let p = Problem {
            drift: Drift::Cubic,
            scale: 1.0,
            half_width,
            g: 0.5,
            s: 0.1,
        };
        let obs = observe(&p, false, &mut Lcg(31));
        let exact = reference(&p, false, &obs, 2).unwrap();
        let model = Model::from_text(&["-1*x^3"], &["x"], Noise::continuous(p.s))
            .and_then(|m| m.with_diffusion(DMatrix::from_element(1, 1, p.g)))
            .unwrap();
        let qiem = Qiem::builder(&model)
            .prior_gaussian(&[PRIOR.0], &[[PRIOR.1]])
            .domain(&[(-half_width, half_width)])
            .dt(DT_OBS)
            .build()
            .unwrap();
        let warnings = qiem.warnings();
        assert!(
            warnings
                .iter()
                .any(|w| w.starts_with("(31) QIEM stability: Δt")),
            "{warnings:?}"
        );
        assert!(
            !warnings.iter().any(|w| w.contains("violated")),
            "{warnings:?}"
        );
        match run(
            ("QIEM", TOLERANCE),
            Ok(qiem),
            &obs,
            false,
            &exact,
            half_width,
        ) {
            Outcome::Right(gap) => eprintln!("±{half_width}: within {gap:.4} sd"),
            Outcome::Warned(gap, why) | Outcome::Silent(gap, why) => {
                panic!("±{half_width}: off by {gap} sd ({why})")
            }
        }
    }
}
