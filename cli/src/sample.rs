//! `zakai sample`: draws from the posterior of a scenario's parameters given recorded
//! observations under one method, with their summary (table or JSON) or every draw (CSV),
//! and the chains' traces and marginals drawn (SVG).

use std::fmt::Write as _;
use std::time::Instant;

use zakai::lab::fit::Likelihood;
use zakai::lab::posterior::{
    sample_from_estimate, Posterior, RandomNumbers, SampleOptions, Sampler,
};

use crate::args::{SampleArgs, SamplerArg};
use crate::Format;

/// Runs the command.
pub(crate) fn command(a: &SampleArgs) -> Result<(), String> {
    let mut config = crate::load(&a.selection.scenario)?;
    if let Some(keys) = &a.selection.methods {
        crate::select_methods(&mut config, keys)?;
    }
    if let Some(key) = &a.method {
        crate::select_methods(&mut config, std::slice::from_ref(key))?;
    }
    if a.common_random_numbers && a.correlation.is_some() {
        return Err("--correlation with --common-random-numbers: one or the other (common numbers are ρ = 1 without the exactness)".into());
    }
    let seed = a.selection.seed.unwrap_or(config.seed);
    let recording = crate::fit::recording(config.state_dim(), &a.observations)?;
    let names = a.params.clone().unwrap_or_default();
    let likelihood =
        Likelihood::new(&config, recording, 0, &names, seed).map_err(|e| e.to_string())?;
    for note in likelihood.chosen_defaults() {
        eprintln!("default from the problem (held at every point) — {note}");
    }
    let surrogate = match &a.surrogate {
        None => None,
        Some(spec) => {
            let mut screen = config.clone();
            if spec.trim_start().starts_with('{') {
                let method = serde_json::from_str(spec)
                    .map_err(|e| format!("--surrogate: invalid method JSON: {e}"))?;
                screen.methods = vec![method];
            } else {
                crate::select_methods(&mut screen, std::slice::from_ref(spec))?;
            }
            let recording = likelihood.recording().clone();
            Some(
                Likelihood::new(&screen, recording, 0, &names, seed)
                    .map_err(|e| format!("--surrogate: {e}"))?,
            )
        }
    };
    let options = SampleOptions {
        draws: a.draws,
        warmup: a.warmup,
        chains: a.chains,
        seed,
        sampler: match a.sampler {
            SamplerArg::Auto => Sampler::Automatic,
            SamplerArg::Metropolis => Sampler::Metropolis,
            SamplerArg::Pmmh => Sampler::PseudoMarginal,
            SamplerArg::Langevin => Sampler::Langevin,
        },
        random_numbers: match (a.common_random_numbers, a.correlation) {
            (_, Some(rho)) => RandomNumbers::Correlated(rho),
            (true, None) => RandomNumbers::Common,
            (false, None) => RandomNumbers::Fresh,
        },
        // A start of the scenario's values skips the fit.
        start: a.no_fit.then(|| likelihood.start().to_vec()),
        covariance: None,
    };
    let bar = crate::progress_bar(
        a.warmup + a.draws,
        &format!("iterations of {} chains", a.chains),
    )?;
    let clock = Instant::now();
    let progress = |t: usize, _total: usize| {
        bar.set_position(t as u64);
        true
    };
    let screen = surrogate
        .as_ref()
        .map(|s| s as &dyn zakai::lab::fit::Evaluate);
    let result = sample_from_estimate(&likelihood, &likelihood, screen, &options, &progress);
    bar.finish_and_clear();
    let (posterior, _) = result.map_err(|e| e.to_string())?;
    let seconds = clock.elapsed().as_secs_f64();
    if let Some(svg) = &a.svg {
        crate::sample_plot::draw(&posterior, &config.name, svg)?;
    }
    crate::emit(
        &render(&posterior, seconds, a.output.format()),
        a.output.out.as_deref(),
    )
}

/// The posterior as a table (the summary), JSON (the summary, the chains' acceptance and
/// notes) or CSV (one row per draw: `chain`, `draw`, each parameter, `lp` = ln L + ln p(θ)).
pub(crate) fn render(p: &Posterior, seconds: f64, format: Format) -> String {
    let summary = p.summary();
    match format {
        Format::Table => {
            let mut s = format!(
                "Posterior — {}, {}, {} chains × {} draws after {} of warm-up, {} observations\n",
                p.method,
                p.sampler,
                p.chains.len(),
                p.draws,
                p.warmup,
                p.observations
            );
            let _ = writeln!(
                s,
                "{:<12} {:>13} {:>12} {:>13} {:>13} {:>13} {:>10} {:>7} {:>8} {:>8}  prior",
                "parameter",
                "mean",
                "sd",
                "5 %",
                "median",
                "95 %",
                "mcse",
                "R-hat",
                "ESS bulk",
                "ESS tail"
            );
            for (i, r) in summary.iter().enumerate() {
                let (rhat, bulk, tail) = r.diagnostics.map_or(
                    ("—".to_string(), "—".to_string(), "—".to_string()),
                    |d| {
                        (
                            format!("{:.3}", d.rhat),
                            format!("{:.0}", d.ess_bulk),
                            format!("{:.0}", d.ess_tail),
                        )
                    },
                );
                let _ = writeln!(
                    s,
                    "{:<12} {:>13.6} {:>12.6} {:>13.6} {:>13.6} {:>13.6} {:>10.4} {:>7} {:>8} {:>8}  {}",
                    r.name, r.mean, r.sd, r.q05, r.median, r.q95, r.mcse, rhat, bulk, tail,
                    describe_prior(p, i)
                );
            }
            let rates: Vec<String> = p
                .chains
                .iter()
                .map(|c| format!("{:.2}", c.acceptance))
                .collect();
            let runs = if p.sampler.contains("Langevin") {
                "scores"
            } else {
                "evaluations"
            };
            let _ = writeln!(
                s,
                "acceptance {} (chains {}); {} {runs} in {seconds:.2} s",
                format_args!("{:.2}", p.acceptance()),
                rates.join(", "),
                p.evaluations
            );
            for note in &p.notes {
                let _ = writeln!(s, "note: {note}");
            }
            s
        }
        Format::Json => {
            let json = serde_json::json!({
                "method": p.method,
                "sampler": p.sampler,
                "observations": p.observations,
                "chains": p.chains.len(),
                "draws": p.draws,
                "warmup": p.warmup,
                "summary": summary,
                "priors": p.priors,
                "acceptance": p.chains.iter().map(|c| c.acceptance).collect::<Vec<_>>(),
                "evaluations": p.evaluations,
                "seconds": seconds,
                "notes": p.notes,
            });
            serde_json::to_string_pretty(&json).unwrap_or_default() + "\n"
        }
        Format::Csv => {
            let mut s = format!("chain,draw,{},lp\n", p.names.join(","));
            let n = p.names.len();
            for (c, chain) in p.chains.iter().enumerate() {
                for d in 0..p.draws {
                    let values: Vec<String> = chain.theta[d * n..(d + 1) * n]
                        .iter()
                        .map(|v| format!("{v:?}"))
                        .collect();
                    let _ = writeln!(
                        s,
                        "{c},{d},{},{:?}",
                        values.join(","),
                        chain.log_likelihood[d] + chain.log_prior[d]
                    );
                }
            }
            s
        }
    }
}

/// Parameter `i`'s prior in words: `lognormal(mu = 7, sigma = 1) on [0, inf]`.
pub(crate) fn describe_prior(p: &Posterior, i: usize) -> String {
    let (lo, hi) = p.bounds[i];
    let json = serde_json::to_value(&p.priors[i]).unwrap_or_default();
    let kind = json["kind"].as_str().unwrap_or("?").to_string();
    let numbers: Vec<String> = json
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, _)| *k != "kind")
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    if numbers.is_empty() {
        format!("{kind} on [{lo}, {hi}]")
    } else {
        format!("{kind}({}) on [{lo}, {hi}]", numbers.join(", "))
    }
}
