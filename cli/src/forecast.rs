//! `zakai forecast`: every method of the scenario through recorded observations, then the
//! predictive distributions of the state and of the observation ahead, with intervals.

use std::fmt::Write as _;

use serde_json::{json, Value};
use zakai::lab::recording::Recording;
use zakai::predictive::{Band, Forecast};

use crate::args::ForecastArgs;
use crate::Format;

/// One method's rows: per step its time, and per component of the state then of the
/// observation its mean, standard deviation and interval.
struct Rows {
    name: String,
    steps: Result<Vec<Step>, String>,
}

struct Step {
    t: f64,
    state: Vec<Band>,
    observation: Vec<Band>,
}

/// Runs the command.
pub(crate) fn command(a: &ForecastArgs) -> Result<(), String> {
    if !(a.level > 0.0 && a.level < 1.0) {
        return Err(format!(
            "--level must be strictly between 0 and 1, got {}",
            a.level
        ));
    }
    if !(1..=100_000).contains(&a.steps) {
        return Err(format!("--steps must be in [1, 100000], got {}", a.steps));
    }
    let (experiment, seed) = a.selection.experiment()?;
    let dt = a.dt.unwrap_or(experiment.config().time.dt_obs);
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(format!("--dt must be positive and finite, got {dt}"));
    }
    let bytes = std::fs::read(&a.observations)
        .map_err(|e| format!("cannot read {}: {e}", a.observations.display()))?;
    let recording =
        Recording::from_csv(experiment.model().n, &bytes, None).map_err(|e| e.to_string())?;
    let continuous = recording.continuous;
    let result = experiment
        .forecast_recorded(recording, seed, dt, a.steps)
        .map_err(|e| e.to_string())?;
    let methods: Vec<Rows> = result
        .methods
        .into_iter()
        .map(|(name, forecast)| Rows {
            name,
            steps: forecast.map(|(_, ahead)| {
                ahead
                    .iter()
                    .map(|f| step(f, result.last, a.level))
                    .collect()
            }),
        })
        .collect();
    let observed = if continuous { "dy" } else { "z" };
    let text = match a.output.format() {
        Format::Table => table(&methods, observed, a.level, dt),
        Format::Json => json_text(&methods, result.last, dt, a.level, continuous),
        Format::Csv => csv(&methods, observed),
    };
    crate::emit(&text, a.output.out.as_deref())
}

fn step(f: &Forecast, last: f64, level: f64) -> Step {
    let (state, observation) = f.bands(level);
    Step {
        t: last + f.ahead,
        state,
        observation,
    }
}

fn table(methods: &[Rows], observed: &str, level: f64, dt: f64) -> String {
    let mut s = String::new();
    for m in methods {
        let _ = writeln!(
            s,
            "{} — steps of {dt} ahead, {:.0}% intervals",
            m.name,
            level * 100.0
        );
        match &m.steps {
            Err(why) => {
                let _ = writeln!(s, "  no forecast: {why}\n");
            }
            Ok(steps) => {
                let Some(first) = steps.first() else { continue };
                let mut head = format!("{:>12}", "t");
                let names = (1..=first.state.len())
                    .map(|j| format!("x{j} mean"))
                    .chain((1..=first.observation.len()).map(|j| format!("{observed}{j} mean")));
                for name in names {
                    let _ = write!(head, " {name:>12} {:>27}", "interval");
                }
                let _ = writeln!(s, "{head}");
                for step in steps {
                    let _ = write!(s, "{:>12.6}", step.t);
                    for c in step.state.iter().chain(&step.observation) {
                        let _ = write!(
                            s,
                            " {:>12.6} [{:>12.6}, {:>12.6}]",
                            c.mean, c.lower, c.upper
                        );
                    }
                    s.push('\n');
                }
                s.push('\n');
            }
        }
    }
    s
}

fn json_text(methods: &[Rows], last: f64, dt: f64, level: f64, continuous: bool) -> String {
    let component =
        |c: &Band| json!({"mean": c.mean, "sd": c.sd, "lower": c.lower, "upper": c.upper});
    let methods: Vec<Value> = methods
        .iter()
        .map(|m| match &m.steps {
            Err(why) => json!({"name": m.name, "failure": why}),
            Ok(steps) => json!({
                "name": m.name,
                "failure": Value::Null,
                "steps": steps.iter().map(|s| json!({
                    "t": s.t,
                    "state": s.state.iter().map(component).collect::<Vec<_>>(),
                    "observation": s.observation.iter().map(component).collect::<Vec<_>>(),
                })).collect::<Vec<_>>(),
            }),
        })
        .collect();
    let value = json!({
        "last": last,
        "dt": dt,
        "level": level,
        "observing": if continuous { "increment" } else { "measurement" },
        "methods": methods,
    });
    serde_json::to_string_pretty(&value).unwrap_or_default() + "\n"
}

/// One row per method, step and component: `method,t,component,mean,sd,lower,upper`
/// (components `x1…` of the state, `z1…` or `dy1…` of the observation).
fn csv(methods: &[Rows], observed: &str) -> String {
    let mut s = String::from("method,t,component,mean,sd,lower,upper\n");
    for m in methods {
        let Ok(steps) = &m.steps else { continue };
        let name = m.name.replace('"', "\"\"");
        for step in steps {
            let named = step
                .state
                .iter()
                .enumerate()
                .map(|(j, c)| (format!("x{}", j + 1), c))
                .chain(
                    step.observation
                        .iter()
                        .enumerate()
                        .map(|(j, c)| (format!("{observed}{}", j + 1), c)),
                );
            for (label, c) in named {
                let _ = writeln!(
                    s,
                    "\"{name}\",{},{label},{},{},{},{}",
                    step.t, c.mean, c.sd, c.lower, c.upper
                );
            }
        }
    }
    s
}
