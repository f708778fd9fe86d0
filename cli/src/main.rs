//! `zakai` — run Zakai scenarios from the command line.
//!
//! ```text
//! zakai list
//! zakai show <preset>
//! zakai run <preset|file.json> [--methods ekf,ukf,pf] [--runs N] [--seed S]
//!           [--format table|json|csv] [--out FILE]
//! zakai filter <preset|file.json> --observations obs.csv [--truth truth.csv]
//!              [--methods …] [--format table|json|csv] [--out FILE]
//! zakai fit <preset|file.json> --observations obs.csv [--method KEY] [--params a,b]
//!           [--format table|json|csv] [--out FILE]
//! zakai fit <preset|file.json> --observations obs.csv --profile a [--methods …]
//!           [--points N] [--range LO,HI] [--svg FILE] [--out FILE]
//! zakai simulate <preset|file.json> [--seed S] [--format json|csv] [--out FILE]
//!                [--truth-out FILE]
//! zakai reproduce [table|figure|all] [--runs N]
//! zakai jcurve <preset|file.json> [--seed S] [--runs N] [--per-interval K] [--csv FILE]
//! ```
//!
//! Errors are one-line messages on stderr with a non-zero exit status; nothing panics.

mod fit;
mod frontier_plot;
mod output;
mod profile_plot;
mod recorded;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use zakai::lab::experiment::Experiment;
use zakai::lab::reproduction;
use zakai::lab::scenario::catalogue;
use zakai::lab::scenario::{presets, MethodConfig, ScenarioConfig};
use zakai::lab::study::monte_carlo::MonteCarlo;

/// `print!` to stdout that ends the program quietly when the reader has gone (`zakai show
/// cubic-sensor-1d | head`) instead of panicking, and with a message on any other write error.
macro_rules! out {
    ($($arg:tt)*) => { write_out(format_args!($($arg)*)) };
}

/// `println!` counterpart of [`out!`].
macro_rules! outln {
    ($($arg:tt)*) => { write_out(format_args!("{}\n", format_args!($($arg)*))) };
}

fn write_out(text: std::fmt::Arguments) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(text).and_then(|()| stdout.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: cannot write the output: {e}");
        std::process::exit(1);
    }
}

#[derive(Parser)]
#[command(
    name = "zakai",
    version,
    about = "Continuous-time nonlinear filtering, side by side"
)]
struct Cli {
    /// Largest memory a scenario's methods may need together, checked before anything is
    /// allocated (e.g. 512MiB, 8GiB; default 1GiB, the playground's cap). Also read from the
    /// environment variable ZAKAI_MEMORY_CAP.
    #[arg(long, global = true, env = "ZAKAI_MEMORY_CAP", value_parser = zakai::lab::scenario::parse_bytes)]
    memory_cap: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
    /// Run a scenario once or as a Monte Carlo job and print per-method results.
    Run(RunArgs),
    /// Fit the scenario's parameters to recorded observations by maximum likelihood under
    /// one method (Nelder–Mead within the bounds, standard errors from the observed
    /// information), or with --profile draw the log-likelihood along one parameter for every
    /// selected method.
    Fit(FitArgs),
}

/// `zakai fit`.
#[derive(Args)]
struct FitArgs {
    #[command(flatten)]
    selection: Selection,
    /// The observations (CSV, as for `zakai filter`).
    #[arg(long)]
    observations: PathBuf,
    /// The method whose likelihood is maximised (a catalogue key; default: the scenario's
    /// first method, or the first of --methods).
    #[arg(long)]
    method: Option<String>,
    /// Comma-separated parameters to fit (default: all the scenario declares); the others
    /// keep their values. With --profile: the parameters refitted at each value (the profile
    /// log-likelihood); without, a slice with the others held.
    #[arg(long, value_delimiter = ',')]
    params: Option<Vec<String>>,
    /// Instead of fitting: the log-likelihood along this parameter for every selected method
    /// — the profile, maximised over the --params at each value, or a slice with the others
    /// at their values — CSV to --out (or stdout), the plot to --svg.
    #[arg(long)]
    profile: Option<String>,
    /// Values of the profile.
    #[arg(long, default_value_t = 41)]
    points: usize,
    /// The profile's interval `LO,HI` (default: from the parameter's bounds and value).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    range: Option<Vec<f64>>,
    /// Where to draw the profile (SVG).
    #[arg(long)]
    svg: Option<PathBuf>,
    #[command(flatten)]
    output: Output,
}

/// `zakai show`: the scenario as JSON, with the sizes chosen from the problem on request.
fn show(scenario: &str, chosen: bool) -> Result<(), String> {
    let config = load(scenario)?;
    let config = if chosen {
        let experiment = Experiment::new(config).map_err(|e| e.to_string())?;
        for note in experiment.chosen_defaults() {
            eprintln!("default from the problem — {note}");
        }
        experiment.config().clone()
    } else {
        config
    };
    let json = serde_json::to_string_pretty(&config).map_err(|e| e.to_string())?;
    outln!("{json}");
    Ok(())
}

/// Which methods of the scenario run, and with which seed (`run`, `filter`).
#[derive(Args)]
struct Selection {
    /// A preset name or a path to a scenario JSON file.
    scenario: String,
    /// Comma-separated method keys to keep (e.g. ekf,ukf,pf); keys the scenario lacks are
    /// added with default parameters.
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Seed (default: the scenario's): of the first run (`run`), of the methods' random
    /// numbers (`filter`).
    #[arg(long)]
    seed: Option<u64>,
}

impl Selection {
    /// The scenario with the chosen methods, built, and the seed.
    fn experiment(&self) -> Result<(Experiment, u64), String> {
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
struct Output {
    /// Output format: `table`; `json`; `csv` (`run`: one row per method; `filter`: estimates
    /// and standard deviations per time). Default: from the extension of --out (`.json`,
    /// `.csv`), else `table`.
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Write the output to FILE instead of stdout.
    #[arg(long)]
    out: Option<PathBuf>,
}

impl Output {
    /// The format asked for, else the one the --out file's extension names, else a table.
    fn format(&self) -> Format {
        self.format
            .unwrap_or_else(|| match extension(self.out.as_deref()).as_deref() {
                Some("json") => Format::Json,
                Some("csv") => Format::Csv,
                _ => Format::Table,
            })
    }
}

/// The lower-case extension of `path`, if any.
fn extension(path: Option<&std::path::Path>) -> Option<String> {
    path?.extension()?.to_str().map(str::to_ascii_lowercase)
}

/// Run the scenario's methods on recorded observations (CSV with header `t,dy1,…` for
/// increments of dy = h dt + dw or `t,z1,…` for measurements; the first row is the prior's
/// time). The scenario gives the model, prior, domain, Δτ and methods; its simulation
/// settings are not used. Without --truth there are no errors, only estimates.
#[derive(Args)]
struct FilterArgs {
    #[command(flatten)]
    selection: Selection,
    /// The observations (CSV).
    #[arg(long)]
    observations: PathBuf,
    /// The true states (CSV `t,x1,…` at the observation times), for errors.
    #[arg(long)]
    truth: Option<PathBuf>,
    #[command(flatten)]
    output: Output,
}

#[derive(Args)]
struct RunArgs {
    #[command(flatten)]
    selection: Selection,
    /// Number of Monte Carlo runs (seeds seed, seed+1, …).
    #[arg(long, default_value_t = 1)]
    runs: usize,
    #[command(flatten)]
    output: Output,
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

fn load(scenario: &str) -> Result<ScenarioConfig, String> {
    if let Some(p) = presets::preset(scenario) {
        return Ok(p);
    }
    let path = std::path::Path::new(scenario);
    if !path.exists() {
        return Err(format!(
            "`{scenario}` is neither a preset (see `zakai list`) nor an existing file"
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {scenario}: {e}"))?;
    serde_json::from_str(&text).map_err(|e| format!("{scenario}: invalid scenario JSON: {e}"))
}

/// Keeps the scenario's methods whose key is listed, adding listed keys it lacks.
fn select_methods(config: &mut ScenarioConfig, keys: &[String]) -> Result<(), String> {
    let mut kept: Vec<MethodConfig> = Vec::new();
    for key in keys {
        let key = key.trim().to_lowercase();
        let key = MethodConfig::from_key(&key).map_or(key, |m| m.key().to_string());
        let matching: Vec<MethodConfig> = config
            .methods
            .iter()
            .filter(|m| m.key() == key)
            .cloned()
            .collect();
        if matching.is_empty() {
            let method = MethodConfig::from_key(&key).ok_or_else(|| {
                let known: Vec<String> = catalogue().into_iter().map(|m| m.info.key).collect();
                format!("unknown method `{key}` (known: {})", known.join(", "))
            })?;
            kept.push(method);
        } else {
            kept.extend(matching);
        }
    }
    config.methods = kept;
    Ok(())
}

fn run(a: &RunArgs) -> Result<(), String> {
    let runs = a.runs;
    if runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    let (experiment, seed) = a.selection.experiment()?;
    let bar = if runs > 1 {
        Some(progress_bar(runs, "runs")?)
    } else {
        None
    };
    let done = AtomicUsize::new(0);
    let progress = || {
        done.fetch_add(1, Ordering::Relaxed);
        if let Some(b) = &bar {
            b.inc(1);
        }
    };
    let summary = MonteCarlo::new(&experiment)
        .run(runs, seed, &progress)
        .map_err(|e| e.to_string())?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let text =
        output::render(&experiment, &summary, a.output.format()).map_err(|e| e.to_string())?;
    emit(&text, a.output.out.as_deref())
}

/// Writes `text` to `path`, or to stdout.
fn emit(text: &str, path: Option<&std::path::Path>) -> Result<(), String> {
    match path {
        Some(path) => {
            std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
        }
        None => {
            out!("{text}");
            Ok(())
        }
    }
}

fn filter(a: &FilterArgs, smooth: bool) -> Result<(), String> {
    let (experiment, seed) = a.selection.experiment()?;
    let result = recorded::filter(
        &experiment,
        &a.observations,
        a.truth.as_deref(),
        seed,
        smooth,
    )?;
    emit(
        &recorded::render(&result, a.output.format()),
        a.output.out.as_deref(),
    )
}

fn fit_command(a: &FitArgs) -> Result<(), String> {
    let mut config = load(&a.selection.scenario)?;
    if let Some(keys) = &a.selection.methods {
        select_methods(&mut config, keys)?;
    }
    let seed = a.selection.seed.unwrap_or(config.seed);
    let recording = fit::recording(config.state_dim(), &a.observations)?;
    if let Some(parameter) = &a.profile {
        if !(2..=10_000).contains(&a.points) {
            return Err(format!("--points must be in [2, 10000], got {}", a.points));
        }
        let range = match a.range.as_deref() {
            None => None,
            Some(&[lo, hi]) => Some((lo, hi)),
            Some(other) => return Err(format!("--range needs LO,HI, got {} values", other.len())),
        };
        let refit: Vec<String> = (a.params.iter().flatten())
            .filter(|n| *n != parameter)
            .cloned()
            .collect();
        let profiles = fit::profiles(
            &config, &recording, parameter, &refit, a.points, range, seed,
        )?;
        eprint!("{}", fit::maxima(&profiles));
        if let Some(svg) = &a.svg {
            profile_plot::draw(&profiles, &refit, &config.name, svg)?;
        }
        return emit(&fit::profiles_csv(&profiles), a.output.out.as_deref());
    }
    if let Some(key) = &a.method {
        select_methods(&mut config, std::slice::from_ref(key))?;
    }
    let names = a.params.clone().unwrap_or_default();
    let result = fit::fit(&config, recording, 0, &names, seed)?;
    emit(
        &fit::render_fit(&result, &config, a.output.format()),
        a.output.out.as_deref(),
    )
}

fn progress_bar(len: usize, what: &str) -> Result<ProgressBar, String> {
    let bar = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {what}"
        ))
        .map_err(|e| e.to_string())?,
    );
    Ok(bar)
}

fn reproduce(id: Option<&str>, runs: Option<usize>) -> Result<(), String> {
    let all = zakai::lab::papers::tables();
    let figures = zakai::lab::papers::figures();
    if runs == Some(0) {
        return Err("--runs must be at least 1".into());
    }
    let chosen: Vec<_> = match id {
        None => {
            outln!("Tables and figures (zakai reproduce <id>, or `all`):");
            for t in &all {
                outln!("  {:<14} {} [{}]", t.id, t.title, t.source);
            }
            for f in &figures {
                outln!("  {:<14} {} [{}]", f.id, f.title, f.source);
            }
            return Ok(());
        }
        Some("all") => all,
        Some(id) => match figures.iter().find(|f| f.id == id) {
            Some(f) => {
                outln!("{} — {} [{}]", f.id, f.title, f.source);
                return jcurve(
                    f.preset,
                    Some(1),
                    runs.unwrap_or(f.runs),
                    f.per_interval,
                    None,
                );
            }
            None => vec![zakai::lab::papers::table(id).ok_or_else(|| {
                let ids: Vec<&str> = all
                    .iter()
                    .map(|t| t.id)
                    .chain(figures.iter().map(|f| f.id))
                    .collect();
                format!("unknown table `{id}` (known: {})", ids.join(", "))
            })?],
        },
    };
    for table in &chosen {
        let runs = runs.unwrap_or(table.runs);
        let bar = progress_bar(runs * table.rows.len(), "runs")?;
        let mut results = Vec::new();
        for row in &table.rows {
            let tick = || bar.inc(1);
            results.push(
                reproduction::reproduce_row(table, row, runs, &tick).map_err(|e| e.to_string())?,
            );
        }
        bar.finish_and_clear();
        out!("{}", output::reproduction(table, &results, runs));
    }
    if id == Some("all") {
        for f in &figures {
            outln!("\n{} — {} [{}]", f.id, f.title, f.source);
            jcurve(
                f.preset,
                Some(1),
                runs.unwrap_or(f.runs),
                f.per_interval,
                None,
            )?;
        }
    }
    Ok(())
}

/// `zakai check`: the convergence check of every method of the selection (see
/// [`zakai::lab::study::convergence`]).
fn check(selection: &Selection) -> Result<(), String> {
    use zakai::lab::study::convergence::{convergence_check, CONVERGED_SHARE};
    let (experiment, seed) = selection.experiment()?;
    let methods = experiment.config().methods.clone();
    eprintln!(
        "convergence check of {} on the observations of seed {seed}: each method against itself at doubled resolution",
        experiment.config().name
    );
    let rows = convergence_check(&experiment, &methods, seed, zakai::memory_cap())
        .map_err(|e| e.to_string())?;
    outln!(
        "{:<14} {:>11} {:>11} {:>11}  {:<13} doubled",
        "method",
        "RMS moved",
        "max moved",
        "posterior sd",
        "verdict"
    );
    let mut unconverged = Vec::new();
    for r in &rows {
        let verdict = match (&r.failure, r.converged, &r.refined) {
            (Some(_), _, _) => "not checked",
            (None, _, None) => "exact",
            (None, Some(true), _) => "converged",
            (None, Some(false), _) => {
                unconverged.push(r.method.as_str());
                "NOT converged"
            }
            (None, None, _) => "no covariance",
        };
        let number = |v: f64, shown: bool| {
            if shown {
                format!("{v:.3e}")
            } else {
                "—".into()
            }
        };
        let checked = r.refined.is_some() && r.failure.is_none();
        outln!(
            "{:<14} {:>11} {:>11} {:>11}  {:<13} {}",
            r.method,
            number(r.rms_change, checked),
            number(r.max_change, checked),
            r.spread.map_or("—".into(), |s| format!("{s:.3e}")),
            verdict,
            r.failure
                .as_deref()
                .or(r.refined.as_deref())
                .unwrap_or("(exact filter: nothing to refine)")
        );
    }
    outln!(
        "converged: the estimate moved by at most {CONVERGED_SHARE} of the posterior standard deviation (RMS over time) when the resolution was doubled"
    );
    if !unconverged.is_empty() {
        outln!(
            "not converged for this scenario: {} — raise its resolution (or narrow the domain) and check again",
            unconverged.join(", ")
        );
    }
    Ok(())
}

/// The arguments of `zakai frontier`.
#[derive(Args)]
struct FrontierArgs {
    /// A preset name or a path to a scenario JSON file.
    scenario: String,
    /// Monte Carlo runs (seeds seed, seed+1, …).
    #[arg(long, default_value_t = 100)]
    runs: usize,
    /// Seed of the first run (default: the scenario's seed).
    #[arg(long)]
    seed: Option<u64>,
    /// Directory for `<scenario>-frontier.csv` and `.svg`.
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Method families to sweep (e.g. pf,qiem,spectral; default: all that apply).
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Grid points per dimension of the QIEM reference posterior (N + 1 a power of two or
    /// 3·2^k keeps its DST fast).
    #[arg(long, default_value_t = 767)]
    reference_points: usize,
    /// Time step of the QIEM reference posterior.
    #[arg(long, default_value_t = 1e-4)]
    reference_dt: f64,
    /// Runs of the convergence check of the reference (halved Δs and Δt).
    #[arg(long, default_value_t = 5)]
    check_runs: usize,
    /// Widen the scenario's domain by this factor about its centre first (grid methods,
    /// the reference included, cannot follow a state that leaves their box).
    #[arg(long, default_value_t = 1.0)]
    widen: f64,
}

fn frontier(a: &FrontierArgs) -> Result<(), String> {
    use zakai::lab::study::frontier as fr;
    if a.runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    if !(a.reference_dt > 0.0 && a.reference_dt.is_finite()) || a.reference_points < 3 {
        return Err("--reference-dt must be positive and --reference-points at least 3".into());
    }
    if !(a.widen >= 1.0 && a.widen.is_finite()) {
        return Err("--widen must be a finite factor of at least 1".into());
    }
    let mut config = load(&a.scenario)?;
    for [lo, hi] in &mut config.domain {
        let (c, r) = (0.5 * (*lo + *hi), 0.5 * (*hi - *lo) * a.widen);
        (*lo, *hi) = (c - r, c + r);
    }
    let seed = a.seed.unwrap_or(config.seed);
    let reference =
        fr::reference(&config, a.reference_points, a.reference_dt).map_err(|e| e.to_string())?;
    let mut sweep = fr::default_sweep(&config).map_err(|e| e.to_string())?;
    if let Some(keep) = &a.methods {
        let keep: Vec<String> = keep.iter().map(|k| k.to_lowercase()).collect();
        sweep.retain(|p| keep.contains(&p.family.to_lowercase()));
    }
    if sweep.is_empty() {
        return Err("no method to sweep (see --methods)".into());
    }
    eprintln!("reference: {}", reference.label);
    let check =
        fr::reference_check(&config, &reference, a.check_runs, seed).map_err(|e| e.to_string())?;
    let bar = progress_bar(a.runs, "runs")?;
    let tick = || bar.inc(1);
    let result = fr::frontier(&config, &reference, &sweep, a.runs, seed, &tick)
        .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&a.out)
        .map_err(|e| format!("cannot create {}: {e}", a.out.display()))?;
    let csv = a.out.join(format!("{}-frontier.csv", config.name));
    std::fs::write(&csv, output::frontier_csv(&result))
        .map_err(|e| format!("cannot write {}: {e}", csv.display()))?;
    let svg = a.out.join(format!("{}-frontier.svg", config.name));
    frontier_plot::draw(&result, &config.title, &svg)?;
    out!("{}", output::frontier(&result, check.as_ref(), seed));
    outln!("wrote {} and {}", csv.display(), svg.display());
    Ok(())
}

fn jcurve(
    scenario: &str,
    seed: Option<u64>,
    runs: usize,
    per_interval: usize,
    csv: Option<PathBuf>,
) -> Result<(), String> {
    if runs == 0 || per_interval == 0 {
        return Err("--runs and --per-interval must be at least 1".into());
    }
    let config = load(scenario)?;
    let first = seed.unwrap_or(config.seed);
    let experiment = Experiment::new(config).map_err(|e| e.to_string())?;
    let mut curves = Vec::with_capacity(runs);
    for r in 0..runs as u64 {
        curves.push(
            zakai::lab::study::density_error::j_curve(&experiment, first + r, per_interval)
                .map_err(|e| e.to_string())?,
        );
    }
    if let Some(path) = csv {
        std::fs::write(&path, output::j_curve_csv(&curves[0]))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    out!("{}", output::j_curve(&curves, first));
    Ok(())
}

/// J from `a,b;c,d` or a single number (times the identity).
fn parse_matrix(text: &str, n: usize) -> Result<nalgebra::DMatrix<f64>, String> {
    let rows: Vec<Vec<f64>> = text
        .split(';')
        .map(|row| {
            row.split(',')
                .map(|v| {
                    v.trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| format!("--j: `{}` is not a finite number", v.trim()))
                })
                .collect()
        })
        .collect::<Result<_, _>>()?;
    if rows.len() == 1 && rows[0].len() == 1 {
        return Ok(nalgebra::DMatrix::identity(n, n) * rows[0][0]);
    }
    if rows.len() != n || rows.iter().any(|r| r.len() != n) {
        return Err(format!(
            "--j must be {n} rows of {n} numbers (or one number)"
        ));
    }
    Ok(nalgebra::DMatrix::from_fn(n, n, |i, k| rows[i][k]))
}

fn convexity(scenario: &str, phi: Option<&str>, j: &str) -> Result<(), String> {
    use zakai::diagnostics::convex_filter;
    let config = load(scenario)?;
    let experiment = Experiment::new(config).map_err(|e| e.to_string())?;
    let (model, prior) = (experiment.model(), experiment.prior());
    if model.is_driven() {
        return Err(
            "003's convex-filter conditions are for a time-invariant model, and this one reads the time or known inputs"
                .into(),
        );
    }
    let bounds = experiment.config().bounds();
    let mut reports = vec![convex_filter::theorem_3_8(model, prior, &bounds)];
    if let Some(text) = phi {
        let phi = zakai::ExpressionFunction::parse("phi", &[text.to_string()], model.n, 1)
            .map_err(|e| e.to_string())?;
        let j = parse_matrix(j, model.n)?;
        reports.push(convex_filter::theorem_3_2(model, prior, &bounds, &phi, &j));
    }
    for r in &reports {
        print_report(r);
    }
    Ok(())
}

/// A theorem's conditions, one line each, and its note.
fn print_report(r: &zakai::diagnostics::ConditionReport) {
    outln!(
        "{}: {}",
        r.theorem,
        if r.holds() { "holds" } else { "does not hold" }
    );
    for c in &r.conditions {
        outln!(
            "  [{}] {} — {}",
            if c.holds { "ok" } else { "FAILS" },
            c.name,
            c.detail
        );
    }
    if let Some(note) = &r.note {
        outln!("  note: {note}");
    }
}

fn yau_system(scenario: &str) -> Result<(), String> {
    let config = load(scenario)?;
    config.check().map_err(|e| e.to_string())?;
    let system = config.yau_system().map_err(|e| e.to_string())?;
    print_report(&system.report);
    Ok(())
}

/// Arguments of `zakai simulate`.
#[derive(Args)]
struct SimulateArgs {
    /// A preset name or a path to a scenario JSON file.
    scenario: String,
    /// Seed (default: the scenario's seed).
    #[arg(long)]
    seed: Option<u64>,
    /// `json` or `csv` (the observations; the truth goes to --truth-out). Default: `csv`
    /// when --out ends in `.csv`, else `json`.
    #[arg(long, value_enum)]
    format: Option<SimFormat>,
    /// Write the output (CSV: the observations) to FILE instead of stdout.
    #[arg(long)]
    out: Option<PathBuf>,
    /// CSV only: write the true states to FILE.
    #[arg(long)]
    truth_out: Option<PathBuf>,
    /// Also run the scenario's methods on these observations and add
    /// `"estimates": [{"name", "values", "failure"}]` (rows flattened) — what the
    /// native-vs-wasm determinism test compares.
    #[arg(long)]
    estimates: bool,
}

fn simulate(a: SimulateArgs) -> Result<(), String> {
    let (scenario, seed, estimates) = (a.scenario.as_str(), a.seed, a.estimates);
    let config = load(scenario)?;
    let format = a
        .format
        .unwrap_or(match extension(a.out.as_deref()).as_deref() {
            Some("csv") => SimFormat::Csv,
            _ => SimFormat::Json,
        });
    if format == SimFormat::Csv {
        if estimates {
            return Err(
                "--estimates belongs to the JSON output (run `zakai filter` on the CSV instead)"
                    .into(),
            );
        }
        let experiment = Experiment::new(config.clone()).map_err(|e| e.to_string())?;
        // What the run observes: missing in the scenario's outages (`time.unobserved`).
        let recording = experiment.observed(
            experiment
                .simulate(seed.unwrap_or(config.seed))
                .map_err(|e| e.to_string())?,
        );
        if let (Some(path), Some(truth)) = (&a.truth_out, recording.truth_csv()) {
            emit(&truth, Some(path))?;
        }
        return emit(&recording.observations_csv(), a.out.as_deref());
    }
    if a.truth_out.is_some() {
        return Err("--truth-out needs CSV output (--format csv, or --out FILE.csv; the JSON output holds the states)".into());
    }
    let seed = seed.unwrap_or(config.seed);
    let experiment = Experiment::new(config).map_err(|e| e.to_string())?;
    let run = experiment.start(seed).map_err(|e| e.to_string())?;
    let (t, tracks) = if estimates {
        let result = run.finish();
        (result.recording, result.methods)
    } else {
        (run.recording().clone(), Vec::new())
    };
    let mut json = serde_json::json!({
        "seed": seed,
        "n": t.n,
        "m": t.m,
        "times": t.times,
        "states": t.truth,
        "observations": t.observations,
    });
    if estimates {
        json["estimates"] = tracks
            .iter()
            .map(|m| {
                serde_json::json!({
                    "name": m.name,
                    "values": m.estimates,
                    "failure": m.failure.as_ref().map(|f| &f.message),
                })
            })
            .collect();
    }
    emit(&format!("{json}\n"), a.out.as_deref())
}

fn list() -> String {
    let mut s = String::from("Presets:\n");
    for p in presets::all() {
        s.push_str(&format!(
            "  {:<18} {}  [{}]\n",
            p.name, p.title, p.reference
        ));
    }
    s.push_str("\nObservation noise (model.noise.kind):\n");
    for k in zakai::lab::scenario::noise_kinds() {
        let fields: Vec<&str> = k.fields.iter().map(|f| f.key).collect();
        s.push_str(&format!(
            "  {:<18} {} [fields: {}] — {}\n",
            k.kind,
            k.label,
            if fields.is_empty() {
                "none".to_string()
            } else {
                fields.join(", ")
            },
            k.summary
        ));
    }
    s.push_str("\nMethods:\n");
    for m in catalogue() {
        s.push_str(&format!(
            "  {:<18} {} — {}\n",
            m.info.key, m.info.summary, m.info.paper
        ));
    }
    let support =
        |title: &str, of: fn(&zakai::lab::scenario::CatalogueEntry) -> zakai::method::Support| {
            let mut s = format!("\n{title}:\n");
            for m in catalogue() {
                use zakai::method::Support;
                let (kind, how) = match of(&m) {
                    Support::Exact(how) => ("uses it", how),
                    Support::Approximate(how) => ("approximates it", how),
                    Support::Refused(how) => ("refuses it", how),
                };
                s.push_str(&format!("  {:<18} {kind}: {how}\n", m.info.key));
            }
            s
        };
    s.push_str(&support(
        "A diffusion G(x) that depends on the state (model.diffusion entries in x)",
        |m| m.state_diffusion,
    ));
    s.push_str(&support(
        "A driven model: expressions in the time t and known inputs u1..uk (model.inputs; CSV columns u1..uk)",
        |m| m.inputs,
    ));
    s
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    if let Some(cap) = cli.memory_cap {
        zakai::set_memory_cap(cap);
    }
    let result = match cli.command {
        Command::List => {
            out!("{}", list());
            Ok(())
        }
        Command::Show { scenario, chosen } => show(&scenario, chosen),
        Command::Simulate(args) => simulate(args),
        Command::Filter(args) => filter(&args, false),
        Command::Smooth(args) => filter(&args, true),
        Command::Reproduce { table, runs } => reproduce(table.as_deref(), runs),
        Command::Convexity { scenario, phi, j } => convexity(&scenario, phi.as_deref(), &j),
        Command::YauSystem { scenario } => yau_system(&scenario),
        Command::Frontier(args) => frontier(&args),
        Command::Check(selection) => check(&selection),
        Command::Jcurve {
            scenario,
            seed,
            runs,
            per_interval,
            csv,
        } => jcurve(&scenario, seed, runs, per_interval, csv),
        Command::Run(args) => run(&args),
        Command::Fit(args) => fit_command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("zakai: error: {message}");
            ExitCode::FAILURE
        }
    }
}
