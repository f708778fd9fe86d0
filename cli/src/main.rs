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
//! zakai sample <preset|file.json> --observations obs.csv [--method KEY] [--params a,b]
//!              [--draws N] [--warmup N] [--chains C] [--seed S] [--svg FILE]
//!              [--format table|json|csv] [--out FILE]
//! zakai simulate <preset|file.json> [--seed S] [--format json|csv] [--out FILE]
//!                [--truth-out FILE]
//! zakai reproduce [table|figure|all] [--runs N]
//! zakai jcurve <preset|file.json> [--seed S] [--runs N] [--per-interval K] [--csv FILE]
//! ```
//!
//! Errors are one-line messages on stderr with a non-zero exit status; nothing panics.

mod fit;
mod forecast;
mod frontier_plot;
mod output;
mod profile_plot;
mod recorded;
mod sample;
mod sample_plot;

use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::catalogue;
use zakai::lab::scenario::{presets, MethodConfig, ScenarioConfig};
use zakai::lab::study::monte_carlo::MonteCarlo;

/// `print!` to stdout that ends the program quietly when the reader has gone (`zakai show
/// cubic-sensor-1d | head`) instead of panicking, and with a message on any other write error.
macro_rules! out {
    ($($arg:tt)*) => { $crate::write_out(format_args!($($arg)*)) };
}

/// `println!` counterpart of [`out!`].
macro_rules! outln {
    ($($arg:tt)*) => { $crate::write_out(format_args!("{}\n", format_args!($($arg)*))) };
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

mod args;
mod studies;

use args::*;
use studies::*;

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
    let optimiser = match a.optimiser {
        args::OptimiserArg::Auto => zakai::lab::fit::Optimiser::Automatic,
        args::OptimiserArg::NelderMead => zakai::lab::fit::Optimiser::NelderMead,
        args::OptimiserArg::Lbfgs => zakai::lab::fit::Optimiser::Lbfgs,
    };
    let result = fit::fit(&config, recording, 0, &names, seed, optimiser)?;
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
    s.push_str(&support(
        "A discrete-time model x_k = F(x_(k-1), t_k, u_k) + w_k (model.dynamics: \"discrete\")",
        |m| m.discrete_time,
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
        Command::Forecast(args) => forecast::command(&args),
        Command::Fit(args) => fit_command(&args),
        Command::Sample(args) => sample::command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("zakai: error: {message}");
            ExitCode::FAILURE
        }
    }
}
