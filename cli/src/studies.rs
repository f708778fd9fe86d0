//! The commands that run the lab's studies: `reproduce` (the papers' tables and figures),
//! `check` (convergence), `frontier`, `jcurve`, `convexity` and `yau-system`.

use std::path::PathBuf;

use zakai::lab::experiment::Experiment;
use zakai::lab::reproduction;

use crate::args::*;
use crate::{frontier_plot, load, output, progress_bar};

pub(crate) fn reproduce(id: Option<&str>, runs: Option<usize>) -> Result<(), String> {
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
pub(crate) fn check(selection: &Selection) -> Result<(), String> {
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

pub(crate) fn frontier(a: &FrontierArgs) -> Result<(), String> {
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

pub(crate) fn jcurve(
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
pub(crate) fn parse_matrix(text: &str, n: usize) -> Result<nalgebra::DMatrix<f64>, String> {
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

pub(crate) fn convexity(scenario: &str, phi: Option<&str>, j: &str) -> Result<(), String> {
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
pub(crate) fn print_report(r: &zakai::diagnostics::ConditionReport) {
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

pub(crate) fn yau_system(scenario: &str) -> Result<(), String> {
    let config = load(scenario)?;
    config.check().map_err(|e| e.to_string())?;
    let system = config.yau_system().map_err(|e| e.to_string())?;
    print_report(&system.report);
    Ok(())
}
