//! The command line: every subcommand and its arguments (clap).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use zakai::lab::experiment::Experiment;

use crate::{load, select_methods};

#[derive(Parser)]
#[command(
    name = "zakai",
    version,
    about = "Continuous-time nonlinear filtering, side by side"
)]
pub(crate) struct Cli {
    /// Largest memory a scenario's methods may need together, checked before anything is
    /// allocated (e.g. 512MiB, 8GiB; default 1GiB, the playground's cap). Also read from the
    /// environment variable ZAKAI_MEMORY_CAP.
    #[arg(long, global = true, env = "ZAKAI_MEMORY_CAP", value_parser = zakai::lab::scenario::parse_bytes)]
    pub(crate) memory_cap: Option<usize>,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// List the presets and the methods.
    List,
    /// Print a scenario (a preset or a scenario file) as JSON (edit it and pass the file to
    /// `run`).
    Show {
        /// A preset name or a path to a scenario JSON file.
        scenario: String,
        /// With the sizes the methods leave unset chosen from the problem (domain, prior),
        /// as every run chooses them; one note per choice on stderr.
        #[arg(long)]
        chosen: bool,
    },
    /// Simulate a scenario's truth and observations (no filters): as JSON
    /// `{"times": [...], "states": [...], "observations": [...]}` (rows flattened), or as the
    /// CSV files `zakai filter` reads (observations `t,dy1,…` or `t,z1,…`; truth `t,x1,…`).
    Simulate(SimulateArgs),
    /// Reproduce a paper's table: run every row's preset as a Monte Carlo job and print our
    /// numbers beside the paper's (`zakai reproduce` lists the tables).
    Reproduce {
        /// Table identifier (e.g. 000-table-1), or `all`.
        table: Option<String>,
        /// Runs per row (default: the table's own count).
        #[arg(long)]
        runs: Option<usize>,
    },
    /// Check the convex-filter conditions of 003 §3 (Theorem 3.8; Theorem 3.2 when a
    /// potential Φ is given) for a scenario's model on its domain.
    Convexity {
        /// A preset name or a path to a scenario JSON file.
        scenario: String,
        /// Φ for Theorem 3.2, an expression in the state variables (e.g. `-ln(cosh(x))`).
        #[arg(long, allow_hyphen_values = true)]
        phi: Option<String>,
        /// J for Theorem 3.2: rows separated by `;`, entries by `,` (a single number means
        /// that multiple of the identity).
        #[arg(long, default_value = "0", allow_hyphen_values = true)]
        j: String,
    },
    /// Check whether a scenario's model is a Yau filtering system, 002 (C1)–(C3) (the direct
    /// method's condition), on its domain: each condition with where it fails, l (given by the
    /// scenario's direct method or inferred) and the quadratics Σh² and η.
    YauSystem {
        /// A preset name or a path to a scenario JSON file.
        scenario: String,
    },
    /// J(t) = ∫ (p̂ − p)² dx of the scenario's continuous–discrete grid filters (`separation`,
    /// `implicit_fdm`) against the exact Gaussian-sum density (001 §4, Fig. 4).
    Jcurve {
        /// A preset name or a path to a scenario JSON file.
        scenario: String,
        /// Seeds of the runs: the first (default: the scenario's seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Number of runs (seeds seed, seed+1, …).
        #[arg(long, default_value_t = 1)]
        runs: usize,
        /// Samples of J per observation interval.
        #[arg(long, default_value_t = 10)]
        per_interval: usize,
        /// Write every sample of the first run as CSV to FILE.
        #[arg(long)]
        csv: Option<PathBuf>,
    },
    /// The accuracy–cost frontier: sweep every applicable method's cost knob over seeded runs
    /// and write MSE against time per step to CSV and an SVG plot, with the reference
    /// posterior's MSE (the optimal filter's) as the floor.
    Frontier(FrontierArgs),
    /// The convergence check: rerun each approximate method of the scenario at doubled
    /// resolution (grid points and time step, basis size, particles, substeps) on the same
    /// observations and report how far its estimate moved against its own posterior standard
    /// deviation — converged when by at most a twentieth of it.
    Check(Selection),
    Filter(FilterArgs),
    /// Smooth recorded observations: every method of the scenario as its fixed-interval
    /// smoother — the best estimate at each observation time from all the observations
    /// (RTS for the Gaussian filters, forward–backward on the grid, FFBSi for the particle
    /// filter); methods without one say why. Arguments as for `filter`.
    Smooth(FilterArgs),
    /// Forecast after recorded observations: every method of the scenario through the data
    /// (as `filter`), then the predictive distributions of the state and of the observation
    /// --steps steps of --dt ahead, with central intervals of probability --level (quantiles
    /// of each method's own law: a Gaussian's, a cloud's, a grid's; integers for counts).
    Forecast(ForecastArgs),
    /// Run a scenario once or as a Monte Carlo job and print per-method results.
    Run(RunArgs),
    /// Fit the scenario's parameters to recorded observations by maximum likelihood under
    /// one method (within the bounds: L-BFGS on the method's score where it gives one, else
    /// Nelder–Mead; standard errors from the observed information), or with --profile draw the log-likelihood along one parameter for every
    /// selected method.
    Fit(FitArgs),
    /// Draw from the posterior of the scenario's parameters given recorded observations under
    /// one method (their priors from the scenario, uniform on finite bounds when absent):
    /// adaptive random-walk Metropolis on a deterministic likelihood, particle marginal
    /// Metropolis–Hastings on the particle filter's; chains started around the
    /// maximum-likelihood estimate; R̂ and effective sample sizes with each summary.
    Sample(SampleArgs),
}

/// `zakai fit`.
#[derive(Args)]
pub(crate) struct FitArgs {
    #[command(flatten)]
    pub(crate) selection: Selection,
    /// The observations (CSV, as for `zakai filter`).
    #[arg(long)]
    pub(crate) observations: PathBuf,
    /// The method whose likelihood is maximised (a catalogue key; default: the scenario's
    /// first method, or the first of --methods).
    #[arg(long)]
    pub(crate) method: Option<String>,
    /// Comma-separated parameters to fit (default: all the scenario declares); the others
    /// keep their values. With --profile: the parameters refitted at each value (the profile
    /// log-likelihood); without, a slice with the others held.
    #[arg(long, value_delimiter = ',')]
    pub(crate) params: Option<Vec<String>>,
    /// Instead of fitting: the log-likelihood along this parameter for every selected method
    /// — the profile, maximised over the --params at each value, or a slice with the others
    /// at their values — CSV to --out (or stdout), the plot to --svg.
    #[arg(long)]
    pub(crate) profile: Option<String>,
    /// Values of the profile.
    #[arg(long, default_value_t = 41)]
    pub(crate) points: usize,
    /// The profile's interval `LO,HI` (default: from the parameter's bounds and value).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub(crate) range: Option<Vec<f64>>,
    /// Where to draw the profile (SVG).
    #[arg(long)]
    pub(crate) svg: Option<PathBuf>,
    /// The optimiser: `auto` (L-BFGS on the method's score where it gives one — the
    /// Kalman, point-mass, SA and FDM filters —, else Nelder–Mead), `nelder-mead` or `lbfgs`.
    #[arg(long, value_enum, default_value_t = OptimiserArg::Auto)]
    pub(crate) optimiser: OptimiserArg,
    #[command(flatten)]
    pub(crate) output: Output,
}

/// `zakai sample`.
#[derive(Args)]
pub(crate) struct SampleArgs {
    #[command(flatten)]
    pub(crate) selection: Selection,
    /// The observations (CSV, as for `zakai filter`).
    #[arg(long)]
    pub(crate) observations: PathBuf,
    /// The method whose likelihood is used (a catalogue key; default: the scenario's first
    /// method, or the first of --methods).
    #[arg(long)]
    pub(crate) method: Option<String>,
    /// Comma-separated parameters to sample (default: all the scenario declares); the others
    /// keep their values.
    #[arg(long, value_delimiter = ',')]
    pub(crate) params: Option<Vec<String>>,
    /// Draws kept per chain.
    #[arg(long, default_value_t = 1000)]
    pub(crate) draws: usize,
    /// Warm-up iterations per chain (the proposal adapts; discarded).
    #[arg(long, default_value_t = 1000)]
    pub(crate) warmup: usize,
    /// Chains.
    #[arg(long, default_value_t = 4)]
    pub(crate) chains: usize,
    /// The sampler: `auto` (PMMH for the particle filter, else random-walk Metropolis),
    /// `metropolis`, `pmmh` or `langevin` (on the method's score, where it gives one).
    #[arg(long, value_enum, default_value_t = SamplerArg::Auto)]
    pub(crate) sampler: SamplerArg,
    /// PMMH with the same random numbers at every proposal (a smooth but biased likelihood)
    /// instead of fresh ones.
    #[arg(long)]
    pub(crate) common_random_numbers: bool,
    /// Correlated pseudo-marginal steps (Deligiannidis, Doucet & Pitt 2018): the particle
    /// filter's random numbers move with each proposal by U' = ρU + √(1 − ρ²)ε with this ρ in
    /// [0, 1) (e.g. 0.99), so that far fewer particles keep the chain moving; still the
    /// exact posterior.
    #[arg(long, value_name = "RHO")]
    pub(crate) correlation: Option<f64>,
    /// Delayed acceptance: screen each proposal with this cheaper method's likelihood first
    /// (a catalogue key, or a method as JSON, e.g. `{"method":"point_mass","cells":[100]}`),
    /// and run --method only on the proposals it passes; the draws stay exact for --method.
    #[arg(long)]
    pub(crate) surrogate: Option<String>,
    /// Start the chains around the scenario's values rather than the maximum-likelihood
    /// estimate (no fit first).
    #[arg(long)]
    pub(crate) no_fit: bool,
    /// Where to draw the chains' traces and marginal histograms, the prior drawn in (SVG).
    #[arg(long)]
    pub(crate) svg: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: Output,
}

/// `zakai sample --sampler`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SamplerArg {
    /// PMMH for a method that draws random numbers, else random-walk Metropolis.
    Auto,
    /// Adaptive random-walk Metropolis.
    Metropolis,
    /// Particle marginal Metropolis–Hastings.
    Pmmh,
    /// Metropolis-adjusted Langevin steps on the method's score (the Kalman, point-mass, SA
    /// and FDM filters).
    Langevin,
}

/// `zakai fit --optimiser`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OptimiserArg {
    /// L-BFGS where the method gives its score, else Nelder–Mead.
    Auto,
    /// Nelder–Mead (no gradient).
    NelderMead,
    /// L-BFGS on the method's score (an error for a method without one).
    Lbfgs,
}

/// Which methods of the scenario run, and with which seed (`run`, `filter`).
#[derive(Args)]
pub(crate) struct Selection {
    /// A preset name or a path to a scenario JSON file.
    pub(crate) scenario: String,
    /// Comma-separated method keys to keep (e.g. ekf,ukf,pf); keys the scenario lacks are
    /// added with default parameters.
    #[arg(long, value_delimiter = ',')]
    pub(crate) methods: Option<Vec<String>>,
    /// Seed (default: the scenario's): of the first run (`run`), of the methods' random
    /// numbers (`filter`).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
}

impl Selection {
    /// The scenario with the chosen methods, built, and the seed.
    pub(crate) fn experiment(&self) -> Result<(Experiment, u64), String> {
        let mut config = load(&self.scenario)?;
        if let Some(keys) = &self.methods {
            select_methods(&mut config, keys)?;
        }
        let seed = self.seed.unwrap_or(config.seed);
        let experiment = Experiment::new(config).map_err(|e| e.to_string())?;
        for note in experiment.chosen_defaults() {
            eprintln!("default from the problem — {note}");
        }
        Ok((experiment, seed))
    }
}

/// Where and how results are written (`run`, `filter`).
#[derive(Args)]
pub(crate) struct Output {
    /// Output format: `table`; `json`; `csv` (`run`: one row per method; `filter`: estimates
    /// and standard deviations per time). Default: from the extension of --out (`.json`,
    /// `.csv`), else `table`.
    #[arg(long, value_enum)]
    pub(crate) format: Option<Format>,
    /// Write the output to FILE instead of stdout.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
}

impl Output {
    /// The format asked for, else the one the --out file's extension names, else a table.
    pub(crate) fn format(&self) -> Format {
        self.format
            .unwrap_or_else(|| match extension(self.out.as_deref()).as_deref() {
                Some("json") => Format::Json,
                Some("csv") => Format::Csv,
                _ => Format::Table,
            })
    }
}

/// The lower-case extension of `path`, if any.
pub(crate) fn extension(path: Option<&std::path::Path>) -> Option<String> {
    path?.extension()?.to_str().map(str::to_ascii_lowercase)
}

/// Run the scenario's methods on recorded observations (CSV with header `t,dy1,…` for
/// increments of dy = h dt + dw or `t,z1,…` for measurements; the first row is the prior's
/// time). The scenario gives the model, prior, domain, Δτ and methods; its simulation
/// settings are not used. Without --truth there are no errors, only estimates.
#[derive(Args)]
pub(crate) struct FilterArgs {
    #[command(flatten)]
    pub(crate) selection: Selection,
    /// The observations (CSV).
    #[arg(long)]
    pub(crate) observations: PathBuf,
    /// The true states (CSV `t,x1,…` at the observation times), for errors.
    #[arg(long)]
    pub(crate) truth: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: Output,
}

/// `zakai forecast`.
#[derive(Args)]
pub(crate) struct ForecastArgs {
    #[command(flatten)]
    pub(crate) selection: Selection,
    /// The observations (CSV, as for `zakai filter`).
    #[arg(long)]
    pub(crate) observations: PathBuf,
    /// Steps ahead.
    #[arg(long, default_value_t = 10)]
    pub(crate) steps: usize,
    /// The step (default: the scenario's Δτ).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) dt: Option<f64>,
    /// Probability of the central intervals.
    #[arg(long, default_value_t = 0.95)]
    pub(crate) level: f64,
    #[command(flatten)]
    pub(crate) output: Output,
}

#[derive(Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    pub(crate) selection: Selection,
    /// Number of Monte Carlo runs (seeds seed, seed+1, …).
    #[arg(long, default_value_t = 1)]
    pub(crate) runs: usize,
    #[command(flatten)]
    pub(crate) output: Output,
}

/// Output formats of `zakai simulate`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SimFormat {
    /// One JSON object.
    Json,
    /// CSV files of observations (and truth with --truth-out).
    Csv,
}

/// Output formats of `zakai run`.
#[derive(Clone, Copy, ValueEnum)]
pub enum Format {
    /// Aligned text table.
    Table,
    /// JSON summary.
    Json,
    /// CSV, one row per method.
    Csv,
}

/// The arguments of `zakai frontier`.
#[derive(Args)]
pub(crate) struct FrontierArgs {
    /// A preset name or a path to a scenario JSON file.
    pub(crate) scenario: String,
    /// Monte Carlo runs (seeds seed, seed+1, …).
    #[arg(long, default_value_t = 100)]
    pub(crate) runs: usize,
    /// Seed of the first run (default: the scenario's seed).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    /// Directory for `<scenario>-frontier.csv` and `.svg`.
    #[arg(long, default_value = ".")]
    pub(crate) out: PathBuf,
    /// Method families to sweep (e.g. pf,qiem,spectral; default: all that apply).
    #[arg(long, value_delimiter = ',')]
    pub(crate) methods: Option<Vec<String>>,
    /// Grid points per dimension of the QIEM reference posterior (N + 1 a power of two or
    /// 3·2^k keeps its DST fast); beyond three dimensions, of the tensor-train reference.
    #[arg(long, default_value_t = 767)]
    pub(crate) reference_points: usize,
    /// Time step of the QIEM reference posterior (the tensor-train reference has none).
    #[arg(long, default_value_t = 1e-4)]
    pub(crate) reference_dt: f64,
    /// Runs of the convergence check of the reference (halved Δs and Δt).
    #[arg(long, default_value_t = 5)]
    pub(crate) check_runs: usize,
    /// Widen the scenario's domain by this factor about its centre first (grid methods,
    /// the reference included, cannot follow a state that leaves their box).
    #[arg(long, default_value_t = 1.0)]
    pub(crate) widen: f64,
}

/// Arguments of `zakai simulate`.
#[derive(Args)]
pub(crate) struct SimulateArgs {
    /// A preset name or a path to a scenario JSON file.
    pub(crate) scenario: String,
    /// Seed (default: the scenario's seed).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    /// `json` or `csv` (the observations; the truth goes to --truth-out). Default: `csv`
    /// when --out ends in `.csv`, else `json`.
    #[arg(long, value_enum)]
    pub(crate) format: Option<SimFormat>,
    /// Write the output (CSV: the observations) to FILE instead of stdout.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// CSV only: write the true states to FILE.
    #[arg(long)]
    pub(crate) truth_out: Option<PathBuf>,
    /// Also run the scenario's methods on these observations and add
    /// `"estimates": [{"name", "values", "failure"}]` (rows flattened) — what the
    /// native-vs-wasm determinism test compares.
    #[arg(long)]
    pub(crate) estimates: bool,
}
