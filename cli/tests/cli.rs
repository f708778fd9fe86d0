//! The `zakai` binary: clean failures, and the same numbers in every output format.

use std::process::{Command, Output};

fn zakai(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_zakai"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn temp_file(name: &str, contents: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("zakai-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// Measurements `z` at times 0, 1, 2, … as the CSV `zakai filter` reads (NaN: an empty field).
fn measurements_csv(z: &[f64]) -> String {
    let mut csv = String::from("t,z1\n");
    for (k, v) in z.iter().enumerate() {
        let cell = if v.is_nan() {
            String::new()
        } else {
            v.to_string()
        };
        csv.push_str(&format!("{k},{cell}\n"));
    }
    csv
}

fn assert_clean_failure(o: &Output, needle: &str) {
    assert!(!o.status.success(), "should fail");
    let err = stderr(o);
    assert!(err.contains(needle), "stderr lacks `{needle}`: {err}");
    assert!(!err.contains("panicked"), "panicked: {err}");
    assert_eq!(
        err.trim().lines().count(),
        1,
        "one-line message expected: {err}"
    );
}

#[test]
fn malformed_files_fail_cleanly() {
    let path = temp_file("broken.json", "{ \"name\": \"x\", ");
    let o = zakai(&["run", path.to_str().unwrap()]);
    assert_clean_failure(&o, "invalid scenario JSON");

    let o = zakai(&["run", "/no/such/file.json"]);
    assert_clean_failure(&o, "neither a preset");

    // A well-formed file with a bad expression: the message names the field and position.
    let show = zakai(&["show", "cubic-sensor-1d"]);
    assert!(show.status.success());
    let mut v: serde_json::Value = serde_json::from_slice(&show.stdout).unwrap();
    v["model"]["observation"][0] = "x^^3".into();
    v["time"]["dt_obs"] = serde_json::json!(0.0);
    let path = temp_file("bad-expr.json", &v.to_string());
    let o = zakai(&["run", path.to_str().unwrap()]);
    assert_clean_failure(&o, "model.observation[0]: syntax error at position 2");
    assert!(
        stderr(&o).contains("time.dt_obs: must be positive"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_arguments_fail_cleanly() {
    assert_clean_failure(&zakai(&["show", "nope"]), "`nope` is neither a preset");
    assert_clean_failure(
        &zakai(&["run", "cubic-sensor-1d", "--methods", "ekf,magic"]),
        "unknown method `magic`",
    );
    assert_clean_failure(
        &zakai(&["run", "cubic-sensor-1d", "--runs", "0"]),
        "at least 1",
    );
    let o = zakai(&["run", "cubic-sensor-1d", "--format", "xml"]);
    assert!(!o.status.success());
    assert!(!stderr(&o).contains("panicked"));
}

#[test]
fn reproduce_lists_tables_and_prints_ours_beside_the_paper() {
    let o = zakai(&["reproduce"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("000-table-1"));
    assert_clean_failure(&zakai(&["reproduce", "999-table-9"]), "unknown table");
    assert_clean_failure(
        &zakai(&["reproduce", "000-table-1", "--runs", "0"]),
        "at least 1",
    );
    let o = zakai(&["reproduce", "000-table-1", "--runs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    // Every row with the paper's numbers for both methods.
    for needle in [
        "h = x^2", "h = x^6", "0.6364", "0.4630", "1.3314", "0.5597", "QIEM",
    ] {
        assert!(out.contains(needle), "{needle} missing from\n{out}");
    }
    assert!(!out.contains("NaN"));
}

/// `zakai yau-system`: example 4.4 with its l = x + 1 holds (η printed); the 2-D example (33)
/// fails (C1) — its drift has a varying curl — and names the derivatives.
#[test]
fn yau_system_reports_each_condition() {
    let o = zakai(&["yau-system", "direct-4.4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("): holds") && out.contains("η = "), "{out}");
    assert!(out.contains("(given)"), "{out}");
    let o = zakai(&["yau-system", "yau-2d"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("does not hold") && out.contains("[FAILS] (C1)"),
        "{out}"
    );
    assert!(out.contains("∂f2/∂x1 − ∂f1/∂x2"), "{out}");
    assert_clean_failure(&zakai(&["yau-system", "no-such-preset"]), "no-such-preset");
}

#[test]
fn convexity_reports_each_condition() {
    let o = zakai(&["convexity", "cos-x3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("Theorem 3.8") && out.contains("does not hold"),
        "{out}"
    );
    assert!(out.contains("[FAILS] f is linear"), "{out}");
    let o = zakai(&[
        "convexity",
        "cubic-sensor-1d",
        "--phi",
        "-x^2/2",
        "--j",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("Theorem 3.2"));
    assert_clean_failure(
        &zakai(&["convexity", "cubic-sensor-1d", "--phi", "sin(x"]),
        "position",
    );
    assert_clean_failure(
        &zakai(&["convexity", "cubic-sensor-1d", "--phi", "x", "--j", "1,2;3"]),
        "--j",
    );
}

#[test]
fn list_names_every_preset() {
    let o = zakai(&["list"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    for p in [
        "cubic-sensor-1d",
        "yau-2d",
        "sa-example-1",
        "direct-4.3",
        "bearings-only",
        "cos-x6",
    ] {
        assert!(out.contains(p), "{p} missing");
    }
}

#[test]
fn table_json_and_csv_carry_the_same_numbers_and_never_nan() {
    let args = [
        "run",
        "cubic-sensor-1d",
        "--methods",
        "ekf,ukf,pf",
        "--runs",
        "12",
        "--seed",
        "5",
    ];
    let json = zakai(&[&args[..], &["--format", "json"]].concat());
    assert!(json.status.success(), "{}", stderr(&json));
    let text = String::from_utf8_lossy(&json.stdout);
    assert!(!text.to_lowercase().contains("nan"));
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    let methods = summary["methods"].as_array().unwrap();
    // ekf, ukf and the preset's four particle filters.
    assert_eq!(methods.len(), 6);
    let table = zakai(&[&args[..], &["--format", "table"]].concat());
    let table = String::from_utf8_lossy(&table.stdout).into_owned();
    let csv = zakai(&[&args[..], &["--format", "csv"]].concat());
    let csv = String::from_utf8_lossy(&csv.stdout).into_owned();
    for m in methods {
        let name = m["name"].as_str().unwrap();
        let failed = m["failed"].as_u64().unwrap();
        let runs = m["runs"].as_u64().unwrap();
        assert_eq!(runs, 12);
        let row = table.lines().find(|l| l.starts_with(name)).unwrap();
        // Failed runs sit beside the MSE, marked †; a complete row has no mark.
        if failed > 0 {
            assert!(row.contains(&format!("{failed}/{runs}")), "{row}");
        } else {
            assert!(!row.contains('†'), "{row}");
        }
        let csv_row = csv
            .lines()
            .find(|l| l.starts_with(&format!("{name},")))
            .unwrap();
        // The mean log-likelihood of the runs the method finished, in all three.
        if failed < runs {
            let ll = m["log_likelihood"].as_f64().expect("a mean log-likelihood");
            assert!(row.contains(&format!("{ll:.3}")), "{row} vs {ll}");
            let csv_ll: f64 = csv_row.split(',').nth(13).unwrap().parse().unwrap();
            assert_eq!(csv_ll, ll);
        }
        match m["mse"].as_f64() {
            Some(mse) => {
                assert!(row.contains(&format!("{mse:.4}")), "{row} vs {mse}");
                let csv_mse: f64 = csv_row.split(',').nth(3).unwrap().parse().unwrap();
                assert_eq!(csv_mse, mse);
            }
            None => {
                assert_eq!(failed, runs);
                assert!(row.contains("failed"));
            }
        }
    }
    // A second run with the same seed gives the same numbers.
    let again = zakai(&[&args[..], &["--format", "json"]].concat());
    let again: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    for (a, b) in methods.iter().zip(again["methods"].as_array().unwrap()) {
        assert_eq!(a["mse"], b["mse"]);
    }
}

#[test]
fn out_writes_a_file() {
    let dir = std::env::temp_dir().join(format!("zakai-cli-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("r.csv");
    let o = zakai(&[
        "run",
        "sa-example-1",
        "--format",
        "csv",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(&path).unwrap();
    assert!(csv.starts_with("method,runs,failed,mse"));
    let methods = zakai::lab::scenario::presets::preset("sa-example-1")
        .unwrap()
        .methods
        .len();
    assert_eq!(csv.lines().count(), 1 + methods);
}

#[test]
fn frontier_writes_csv_and_svg_with_the_floor() {
    let dir = std::env::temp_dir().join(format!("zakai-cli-frontier-{}", std::process::id()));
    let o = zakai(&[
        "frontier",
        "cubic-sensor-1d",
        "--runs",
        "2",
        "--check-runs",
        "1",
        "--methods",
        "pf,qiem",
        "--reference-points",
        "201",
        "--reference-dt",
        "1e-3",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("optimal MSE (floor)"), "{out}");
    assert!(out.contains("convergence: halving Δs and Δt"), "{out}");
    let csv = std::fs::read_to_string(dir.join("cubic-sensor-1d-frontier.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "family,knob,value,dt,mse,mse_stderr,failed,runs,seconds_per_step"
    );
    // The reference, 7 particle counts and 5 grids at Δt = Δτ, Δτ/4 and 10⁻³ (Δτ = 0.01).
    assert_eq!(lines.len(), 1 + 1 + 7 + 5 * 3);
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("QIEM,points,47,0.0025,")),
        "{csv}"
    );
    let svg = std::fs::read_to_string(dir.join("cubic-sensor-1d-frontier.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("optimal MSE"));
    let bad = zakai(&["frontier", "cubic-sensor-1d", "--runs", "0"]);
    assert!(!bad.status.success());
}

/// The memory cap: 1 GiB by default, raised or lowered natively with
/// `--memory-cap` / `ZAKAI_MEMORY_CAP`; checked before anything is allocated.
#[test]
fn the_memory_cap_can_be_changed_natively() {
    // cubic-sensor-1d with QIEM on 2 000 001 points: ≈ 0.15 GiB for the grid method.
    let show = zakai(&["show", "cubic-sensor-1d"]);
    let mut config: serde_json::Value = serde_json::from_slice(&show.stdout).unwrap();
    config["methods"] = serde_json::json!([{ "method": "qiem", "points": [2000001], "dt": 0.001 }]);
    config["time"]["t_final"] = serde_json::json!(0.01);
    let path = temp_file("cap.json", &config.to_string());
    let path = path.to_str().unwrap();
    let lowered = zakai(&["--memory-cap", "64MiB", "run", path]);
    assert_clean_failure(&lowered, "above the cap of 64.0 MiB");
    let by_env = Command::new(env!("CARGO_BIN_EXE_zakai"))
        .args(["run", path])
        .env("ZAKAI_MEMORY_CAP", "100MiB")
        .output()
        .unwrap();
    assert_clean_failure(&by_env, "above the cap of 100.0 MiB");
    let default = zakai(&["run", path]);
    assert!(default.status.success(), "{}", stderr(&default));
    let bad = zakai(&["--memory-cap", "lots", "run", path]);
    assert_eq!(bad.status.code(), Some(2), "a usage error");
    assert!(
        stderr(&bad).contains("`lots` is not a size"),
        "{}",
        stderr(&bad)
    );
}

#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::process::Stdio;
    // The reader goes away at once (as `zakai list | head -1` does after one line): the writes
    // fail with a broken pipe, which must end the program without a panic.
    let mut child = Command::new(env!("CARGO_BIN_EXE_zakai"))
        .arg("list")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
}

/// `simulate --format csv` → `filter` gives every method exactly the estimates the simulated
/// run gives (`simulate --estimates`), bit for bit, for continuous and discrete observations;
/// without the truth there is no MSE, with it the MSE is the run's.
#[test]
fn filtering_a_simulated_csv_reproduces_the_simulated_run_bit_for_bit() {
    for (preset, methods) in [
        ("cubic-sensor-1d", "ekf,ukf,pf,qiem,spectral"),
        ("sa-example-1", "ekf,ukf,pf,separation"),
    ] {
        let obs = temp_file(&format!("{preset}-obs.csv"), "");
        let truth = temp_file(&format!("{preset}-truth.csv"), "");
        let o = zakai(&[
            "simulate",
            preset,
            "--seed",
            "4",
            "--format",
            "csv",
            "--out",
            obs.to_str().unwrap(),
            "--truth-out",
            truth.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // The simulated run, through a scenario file with the same methods.
        let show = zakai(&["show", preset]);
        let mut v: serde_json::Value = serde_json::from_slice(&show.stdout).unwrap();
        v["methods"] = methods
            .split(',')
            .map(|k| serde_json::json!({ "method": k }))
            .collect();
        let scenario = temp_file(&format!("{preset}.json"), &v.to_string());
        let scenario = scenario.to_str().unwrap();
        let sim = zakai(&["simulate", scenario, "--seed", "4", "--estimates"]);
        assert!(sim.status.success(), "{}", stderr(&sim));
        let sim: serde_json::Value = serde_json::from_slice(&sim.stdout).unwrap();
        let filtered = |with_truth: bool| {
            let mut args = vec![
                "filter",
                scenario,
                "--observations",
                obs.to_str().unwrap(),
                "--seed",
                "4",
                "--format",
                "json",
            ];
            if with_truth {
                args.extend(["--truth", truth.to_str().unwrap()]);
            }
            let o = zakai(&args);
            assert!(o.status.success(), "{}", stderr(&o));
            serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
        };
        let (blind, known) = (filtered(false), filtered(true));
        let sim_methods = sim["estimates"].as_array().unwrap();
        assert_eq!(sim_methods.len(), methods.split(',').count());
        for (i, s) in sim_methods.iter().enumerate() {
            let f = &blind["methods"][i];
            assert_eq!(f["name"], s["name"]);
            let bits = |v: &serde_json::Value| -> Vec<u64> {
                v.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap().to_bits())
                    .collect()
            };
            assert_eq!(
                bits(&f["estimates"]),
                bits(&s["values"]),
                "{preset} {}",
                s["name"]
            );
            assert!(f["mse"].is_null(), "no truth, no MSE");
            // Every method gives the data's log-likelihood, one term per row, and their sum.
            if f["failure"].is_null() {
                let terms: Vec<f64> = f["log_likelihoods"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().expect("a finite term"))
                    .collect();
                let total = f["log_likelihood"].as_f64().expect("a total");
                let n = blind["n"].as_u64().unwrap() as usize;
                assert_eq!(terms.len(), bits(&f["estimates"]).len() / n);
                assert!(
                    (total - terms.iter().sum::<f64>()).abs() <= 1e-9 * total.abs().max(1.0),
                    "{preset} {}: {total}",
                    s["name"]
                );
            }
            assert!(
                f["failure"].is_null() || !s["failure"].is_null(),
                "{preset} {}: {}",
                s["name"],
                f["failure"]
            );
        }
        assert!(blind["truth"].is_null());
        assert_eq!(
            known["truth"], sim["states"],
            "the truth file reads back exactly"
        );
        // The Kalman-family and particle rows carry covariances (n × n per row).
        let ukf = &known["methods"][1];
        assert_eq!(
            ukf["covariances"].as_array().unwrap().len(),
            ukf["estimates"].as_array().unwrap().len()
        );
        assert!(known["methods"][1]["mse"].as_f64().is_some());
    }
}

/// Bad observation files fail with one line naming the file's line and column; a recording
/// whose steps differ from the Δτ a grid method is built for is refused with the row.
#[test]
fn bad_observation_files_name_the_line() {
    let filter = |csv: &str, extra: &[&str]| {
        let mut args = vec!["filter", "cubic-sensor-1d", "--observations", csv];
        args.extend_from_slice(extra);
        zakai(&args)
    };
    let file = |name: &str, text: &str| temp_file(name, text).to_str().unwrap().to_string();
    assert_clean_failure(&filter("/no/such.csv", &[]), "cannot read /no/such.csv");
    let bad = file("bad.csv", "t,dy1\n0,0\n0.01,0.1\n0.02,oops\n");
    assert_clean_failure(
        &filter(&bad, &[]),
        "observations line 4, column dy1: `oops` is not a finite number",
    );
    let kind = file("kind.csv", "t,z1\n0,0\n0.01,0.1\n");
    assert_clean_failure(&filter(&kind, &[]), "the recording holds measurements");
    // An uneven step is taken by every method, the grid and spectral filters included (two
    // Δτ and a remainder).
    let uneven = file("uneven.csv", "t,dy1\n0,0\n0.01,0.1\n0.035,0.1\n");
    let o = filter(&uneven, &["--methods", "ukf,pf,qiem,spectral"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Gaps: an empty field and NaN are missing increments (predictions only).
    let gaps = file("gaps.csv", "t,dy1\n0,0\n0.01,\n0.02,NaN\n0.03,0.1\n");
    let o = filter(&gaps, &["--methods", "ukf,pf,qiem"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `zakai check`: each method against itself at doubled resolution, with a verdict per row;
/// on the cubic sensor QIEM (399 points, Δt = 10⁻³) is converged and PF(50) is not (its
/// estimate moves by 0.22 against a posterior sd of 0.72 when the particles double).
#[test]
fn check_reports_which_methods_are_converged() {
    let o = zakai(&["check", "cubic-sensor-1d", "--methods", "qiem,pf"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let row = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_else(|| panic!("no row {name} in\n{text}"))
            .to_string()
    };
    assert!(
        row("QIEM").contains(" converged") && row("QIEM").contains("[399] → [799]"),
        "{text}"
    );
    assert!(row("PF(50)").contains("NOT converged"), "{text}");
    assert!(
        text.contains("not converged for this scenario: PF(50)"),
        "{text}"
    );
}

/// `zakai show --chosen` prints the scenario as a run builds it: sizes the methods left unset
/// chosen from the problem (the 1-D spectral basis from the domain against the prior's sd),
/// with a note per choice on stderr; without the flag the file's own (unset) values.
#[test]
fn show_chosen_prints_the_sizes_chosen_from_the_problem() {
    let show = zakai(&["show", "cubic-sensor-1d"]);
    let mut v: serde_json::Value = serde_json::from_slice(&show.stdout).unwrap();
    v["methods"] = serde_json::json!([{ "method": "spectral" }]);
    let path = temp_file("spectral-unset.json", &v.to_string());
    let plain = zakai(&["show", path.to_str().unwrap()]);
    assert!(plain.status.success(), "{}", stderr(&plain));
    let plain: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert!(plain["methods"][0]["online_basis"].is_null());
    let chosen = zakai(&["show", path.to_str().unwrap(), "--chosen"]);
    assert!(chosen.status.success(), "{}", stderr(&chosen));
    let json: serde_json::Value = serde_json::from_slice(&chosen.stdout).unwrap();
    let basis = json["methods"][0]["online_basis"]
        .as_u64()
        .expect("a basis size chosen");
    let note = stderr(&chosen);
    assert!(
        note.contains("default from the problem — Spectral: basis")
            && note.contains(&basis.to_string()),
        "{note}"
    );
}

/// The cubic-sensor-fit preset's data from `zakai simulate` (seed 3), as a CSV file.
fn fit_observations() -> std::path::PathBuf {
    let o = zakai(&[
        "simulate",
        "cubic-sensor-fit",
        "--seed",
        "3",
        "--format",
        "csv",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    temp_file("fit-obs.csv", &String::from_utf8_lossy(&o.stdout))
}

#[test]
fn fit_reports_the_estimate_in_every_format_and_refuses_bad_requests() {
    let obs = fit_observations();
    let obs = obs.to_str().unwrap();
    let args = [
        "fit",
        "cubic-sensor-fit",
        "--observations",
        obs,
        "--method",
        "ekf",
    ];
    let json = zakai(&[&args[..], &["--format", "json", "--params", "r"]].concat());
    assert!(json.status.success(), "{}", stderr(&json));
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let r = v["parameters"]["r"]["estimate"].as_f64().unwrap();
    let se = v["parameters"]["r"]["stderr"].as_f64().unwrap();
    assert_eq!(v["method"], "EKF");
    assert!(v["converged"].as_bool().unwrap() && se > 0.0, "{v}");
    // The same estimate in the CSV and the table.
    let csv = zakai(&[&args[..], &["--format", "csv", "--params", "r"]].concat());
    let text = String::from_utf8_lossy(&csv.stdout).into_owned();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(row[0], "r");
    assert_eq!(row[1].parse::<f64>().unwrap(), r);
    let table = zakai(&[&args[..], &["--params", "r"]].concat());
    assert!(String::from_utf8_lossy(&table.stdout).contains(&format!("{r:.6}")));
    // Requests that cannot be met: one line each, non-zero.
    assert_clean_failure(
        &zakai(&[&args[..], &["--params", "sigma"]].concat()),
        "no parameter `sigma`",
    );
    assert_clean_failure(
        &zakai(&[
            "fit",
            "cubic-sensor-fit",
            "--observations",
            obs,
            "--profile",
            "r",
            "--range",
            "1",
        ]),
        "--range needs LO,HI",
    );
    assert_clean_failure(
        &zakai(&[
            "fit",
            "cubic-sensor-fit",
            "--observations",
            obs,
            "--profile",
            "r",
            "--range",
            "3,9",
        ]),
        "within the bounds",
    );
    assert_clean_failure(
        &zakai(&["fit", "cubic-sensor-1d", "--observations", obs]),
        "declares no parameter",
    );
}

#[test]
fn fit_profile_writes_csv_and_svg_with_each_maximum() {
    let obs = fit_observations();
    let dir = obs.parent().unwrap();
    let (csv, svg) = (dir.join("r.csv"), dir.join("r.svg"));
    let o = zakai(&[
        "fit",
        "cubic-sensor-fit",
        "--observations",
        obs.to_str().unwrap(),
        "--profile",
        "r",
        "--points",
        "21",
        "--methods",
        "ekf,ukf",
        "--out",
        csv.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "r,EKF loglik,UKF loglik");
    assert_eq!(lines.len(), 22);
    // The EKF's printed maximum lies at the best of its column's values or between its
    // neighbours.
    let err = stderr(&o);
    let peak: f64 = err
        .lines()
        .find(|l| l.starts_with("EKF: ln L peaks at r = "))
        .and_then(|l| l["EKF: ln L peaks at r = ".len()..].split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    let rows: Vec<(f64, f64)> = lines[1..]
        .iter()
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (c[0], c[1])
        })
        .collect();
    let best = (0..rows.len())
        .max_by(|&i, &j| rows[i].1.total_cmp(&rows[j].1))
        .unwrap();
    let (lo, hi) = (
        rows[best.saturating_sub(1)].0,
        rows[(best + 1).min(rows.len() - 1)].0,
    );
    assert!(lo <= peak && peak <= hi, "{peak} not in [{lo}, {hi}]");
    let drawing = std::fs::read_to_string(&svg).unwrap();
    assert!(drawing.contains("<svg") && drawing.contains("EKF: maximum at"));
}

/// `zakai smooth` on a short local-level series with a gap (rows 4–7 missing): the Kalman
/// smoother's CSV columns are an RTS smoother written here (to 10⁻⁹ relative), the smoothed
/// sd inside the gap is below the filter's, the JSON carries the same numbers, and a method
/// without a smoother has empty smoothed cells and says why in the table.
#[test]
fn smooth_writes_the_smoothed_estimates_beside_the_filtered() {
    let z = [
        1.2,
        0.7,
        1.9,
        f64::NAN,
        f64::NAN,
        f64::NAN,
        f64::NAN,
        2.4,
        2.0,
        2.8,
    ];
    let csv = measurements_csv(&z);
    let obs = temp_file("smooth-obs.csv", &csv);
    let scenario = temp_file(
        "smooth-scenario.json",
        r#"{ "name": "level", "model": { "drift": ["0"], "observation": ["x"], "diffusion": [[0.5]],
             "noise": { "kind": "discrete", "mixture": [{ "mean": [0], "cov": [[0.3]] }] } },
             "prior": { "kind": "gaussian", "mean": [0], "cov": [[4]] },
             "domain": [[-10, 14]], "time": { "dt_obs": 1 },
             "methods": [{ "method": "kalman" }, { "method": "gaussian_sum" }] }"#,
    );
    let args = |format: &str| {
        zakai(&[
            "smooth",
            scenario.to_str().unwrap(),
            "--observations",
            obs.to_str().unwrap(),
            "--format",
            format,
        ])
    };
    // The reference: scalar Kalman filter and RTS smoother, q = 0.25 per step, r = 0.3.
    let (q, r) = (0.25, 0.3);
    let (mut m, mut p) = (0.0, 4.0);
    let (mut filtered, mut predicted) = (Vec::new(), Vec::new());
    for (k, v) in z.iter().enumerate() {
        if k > 0 {
            p += q;
        }
        predicted.push((m, p));
        if !v.is_nan() {
            let g = p / (p + r);
            m += g * (v - m);
            p -= g * p;
        }
        filtered.push((m, p));
    }
    let mut smoothed = filtered.clone();
    for k in (0..z.len() - 1).rev() {
        let ((m, p), (mp, pp)) = (filtered[k], predicted[k + 1]);
        let g = p / pp;
        smoothed[k] = (
            m + g * (smoothed[k + 1].0 - mp),
            p + g * g * (smoothed[k + 1].1 - pp),
        );
    }
    let o = args("csv");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (x, sd, fsd, gsf) = (
        col("KF smoothed x1"),
        col("KF smoothed sd1"),
        col("KF sd1"),
        col("GSF smoothed x1"),
    );
    for (k, line) in lines[1..].iter().enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let value = |i: usize| cells[i].parse::<f64>().unwrap();
        let (want_m, want_p) = smoothed[k];
        assert!(
            (value(x) - want_m).abs() < 1e-9 * (1.0 + want_m.abs()),
            "row {k}"
        );
        assert!((value(sd) - want_p.sqrt()).abs() < 1e-9, "row {k}");
        if (3..7).contains(&k) {
            assert!(value(sd) < value(fsd), "row {k}: the gap is bridged");
        }
        assert_eq!(cells[gsf], "", "row {k}: no smoother, no value");
    }
    let o = args("json");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let s = &v["methods"][0]["smoothed"];
    assert_eq!(s["smoother"], "RTS");
    assert!((s["estimates"][5].as_f64().unwrap() - smoothed[5].0).abs() < 1e-9);
    let table = String::from_utf8(args("table").stdout).unwrap();
    assert!(table.contains("no smoother:"), "{table}");
}

include!("../../core/examples/data/nile.rs");

/// The Nile's flow as the recorded series of a test: years 1901–1910 unknown and 1950 dropped
/// (a gap and an irregular step), filtered by `zakai filter` with `scenario` (JSON) into CSV
/// rows; returns the times, the measurements (NaN where unknown), the header and the rows.
fn filter_the_nile(tag: &str, scenario: &str) -> NileRun {
    let mut csv = String::from("t,z1\n");
    let (mut times, mut z) = (Vec::new(), Vec::new());
    for (k, &v) in NILE.iter().enumerate() {
        if k == 79 {
            continue;
        }
        let value = if (30..40).contains(&k) { f64::NAN } else { v };
        times.push(1871.0 + k as f64);
        z.push(value);
        let cell = if value.is_nan() {
            String::new()
        } else {
            v.to_string()
        };
        csv.push_str(&format!("{},{cell}\n", 1871 + k));
    }
    let obs = temp_file(&format!("{tag}-obs.csv"), &csv);
    let scenario = temp_file(&format!("{tag}-scenario.json"), scenario);
    let out = zakai(&[
        "filter",
        scenario.to_str().unwrap(),
        "--observations",
        obs.to_str().unwrap(),
        "--format",
        "csv",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    NileRun {
        times,
        z,
        head,
        rows,
        stderr: err,
    }
}

/// A point-mass density `p` on `grid` normalised to weights summing to 1, and its mean and
/// standard deviation.
fn normalised_moments(grid: &[f64], p: &mut [f64]) -> (f64, f64) {
    let mass: f64 = p.iter().sum();
    p.iter_mut().for_each(|v| *v /= mass);
    let mean: f64 = grid.iter().zip(p.iter()).map(|(x, w)| x * w).sum();
    let var: f64 = grid
        .iter()
        .zip(p.iter())
        .map(|(x, w)| (x - mean).powi(2) * w)
        .sum();
    (mean, var.sqrt())
}

/// The SA's estimates within 0.05 and the PF(5000)'s within 0.2 of the point-mass
/// reference's standard deviations at every row (`reference`: mean and sd per row).
fn sa_and_pf_follow(head: &[String], rows: &[Vec<f64>], reference: &[(f64, f64)], what: &str) {
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let worst = |method: &str| {
        rows.iter()
            .zip(reference)
            .map(|(row, (mean, sd))| (row[col(method)] - mean).abs() / sd)
            .fold(0.0f64, f64::max)
    };
    let (sa, pf) = (worst("SA x1"), worst("PF(5000) x1"));
    println!("{what}: SA within {sa:.4} sd, PF(5000) within {pf:.4} sd of the point-mass filter");
    assert!(sa < 0.05, "SA {sa} sd from the point-mass filter");
    assert!(pf < 0.2, "PF {pf} sd from the point-mass filter");
}

/// What [`filter_the_nile`] returns.
struct NileRun {
    times: Vec<f64>,
    z: Vec<f64>,
    head: Vec<String>,
    rows: Vec<Vec<f64>>,
    stderr: String,
}

/// A recorded series through the CLI with a measurement density beyond Gaussian noise: the
/// Nile's flow as a local level observed with Student-t noise (ν = 4, σ = 100: the 1913 low
/// of 456 is an outlier to it), with ten years missing and 1950 dropped (a two-year step).
/// `zakai filter` runs the separation approach, the particle filter and the UKF; the SA is
/// held against a point-mass filter written here (the local level's Gaussian transition on a
/// fine grid, the t density in a few lines), the UKF's moment match is named in its warnings.
#[test]
fn filter_takes_student_t_noise_on_a_recorded_series() {
    let (q, nu, sigma) = (1500.0f64, 4.0f64, 100.0f64);
    let NileRun {
        times,
        z,
        head,
        rows,
        stderr: err,
    } = filter_the_nile(
        "nile-t",
        &format!(
            r#"{{ "name": "nile-t", "model": {{ "drift": ["0"], "observation": ["x"], "diffusion": [[{}]],
                 "noise": {{ "kind": "student_t", "dof": {nu}, "scale": {sigma} }} }},
                 "prior": {{ "kind": "gaussian", "mean": [1120], "cov": [[40000]] }},
                 "domain": [[300, 1700]], "time": {{ "dt_obs": 1 }},
                 "methods": [{{ "method": "separation", "cells": [700], "dt": 0.05 }},
                             {{ "method": "pf", "particles": 5000 }}, {{ "method": "ukf" }}] }}"#,
            q.sqrt()
        ),
    );
    assert!(err.contains("UKF") && err.contains("moment match"), "{err}");
    // The point-mass reference on [−500, 2500], 2 units apart; the transition kernel depends
    // on the distance in cells only.
    let (cells, dx) = (1500usize, 2.0);
    let grid: Vec<f64> = (0..=cells).map(|i| -500.0 + i as f64 * dx).collect();
    let normal =
        |v: f64, var: f64| (-v * v / (2.0 * var)).exp() / (2.0 * std::f64::consts::PI * var).sqrt();
    let mut p: Vec<f64> = grid.iter().map(|x| normal(x - 1120.0, 40000.0)).collect();
    let mut reference = Vec::new();
    for (k, &zk) in z.iter().enumerate() {
        if k > 0 {
            let var = q * (times[k] - times[k - 1]);
            let kernel: Vec<f64> = (0..=cells)
                .map(|d| normal(d as f64 * dx, var) * dx)
                .collect();
            p = (0..=cells)
                .map(|i| (0..=cells).map(|j| kernel[i.abs_diff(j)] * p[j]).sum())
                .collect();
        }
        if !zk.is_nan() {
            for (pi, &x) in p.iter_mut().zip(&grid) {
                let r = (zk - x) / sigma;
                *pi *= (1.0 + r * r / nu).powf(-(nu + 1.0) / 2.0);
            }
        }
        reference.push(normalised_moments(&grid, &mut p));
    }
    sa_and_pf_follow(&head, &rows, &reference, "Nile with t noise");
}

/// `zakai filter` on the Nile's flow (a recorded series, years 1901–1910 unknown and 1950
/// dropped) with a noise that grows with the level, `dx = 1.2 √|x| dv` (`model.diffusion`
/// an expression in x), measured with Gaussian noise: the SA and the PF against a point-mass
/// filter of Euler–Maruyama kernels written here; the UKF says that it takes Q at its mean.
#[test]
fn filter_takes_a_state_dependent_diffusion_on_a_recorded_series() {
    let (s, r) = (1.2f64, 15000.0f64);
    let NileRun {
        times,
        z,
        head,
        rows,
        stderr: err,
    } = filter_the_nile(
        "nile-sqrt",
        &format!(
            r#"{{ "name": "nile-sqrt", "model": {{ "drift": ["0"], "observation": ["x"],
                 "diffusion": [["{s}*sqrt(abs(x))"]],
                 "noise": {{ "kind": "discrete", "mixture": [{{ "weight": 1, "mean": [0], "cov": [[{r}]] }}] }} }},
                 "prior": {{ "kind": "gaussian", "mean": [1120], "cov": [[40000]] }},
                 "domain": [[300, 1700]], "time": {{ "dt_obs": 1 }},
                 "methods": [{{ "method": "separation", "cells": [700], "dt": 0.05 }},
                             {{ "method": "pf", "particles": 5000, "substeps": 4 }}, {{ "method": "ukf" }}] }}"#
        ),
    );
    assert!(
        err.contains("UKF") && err.contains("state-dependent process noise"),
        "{err}"
    );
    // The point-mass reference on [0, 2500], 2 units apart: per year 4 Euler–Maruyama kernels
    // N(x, s²|x| h), h = 1/4, each column normalised.
    let (cells, dx, h) = (1250usize, 2.0, 0.25);
    let grid: Vec<f64> = (0..=cells).map(|i| i as f64 * dx).collect();
    let kernel: Vec<Vec<f64>> = grid
        .iter()
        .map(|&from| {
            let var = (s * s * from.abs() * h).max(dx * dx / 4.0);
            let column: Vec<f64> = grid
                .iter()
                .map(|&to| (-(to - from) * (to - from) / (2.0 * var)).exp())
                .collect();
            let total: f64 = column.iter().sum();
            column.into_iter().map(|v| v / total).collect()
        })
        .collect();
    let mut p: Vec<f64> = grid
        .iter()
        .map(|x| (-(x - 1120.0) * (x - 1120.0) / 80000.0).exp())
        .collect();
    let mut reference = Vec::new();
    for (k, &zk) in z.iter().enumerate() {
        if k > 0 {
            let substeps = ((times[k] - times[k - 1]) / h).round() as usize;
            for _ in 0..substeps {
                let mut next = vec![0.0; p.len()];
                for (j, pj) in p.iter().enumerate() {
                    if *pj > 1e-300 {
                        for (n, kij) in next.iter_mut().zip(&kernel[j]) {
                            *n += kij * pj;
                        }
                    }
                }
                p = next;
            }
        }
        if !zk.is_nan() {
            for (pi, &x) in p.iter_mut().zip(&grid) {
                *pi *= (-(zk - x) * (zk - x) / (2.0 * r)).exp();
            }
        }
        reference.push(normalised_moments(&grid, &mut p));
    }
    sa_and_pf_follow(
        &head,
        &rows,
        &reference,
        &format!("Nile with G(x) = {s}√|x|"),
    );
}

/// `zakai forecast` on a local level with a gap at the end: the Kalman filter's forecast
/// computed here by hand (m, P + s q; the measurement's P + s q + r), in the CSV, the table
/// and the JSON; counts of a Poisson series as integers; bad requests refused.
#[test]
fn forecast_prints_the_predictive_intervals_in_every_format() {
    let z = [1.2, 0.7, 1.9, 2.4, f64::NAN, 2.0];
    let csv = measurements_csv(&z);
    let obs = temp_file("forecast-obs.csv", &csv);
    let scenario = temp_file(
        "forecast-scenario.json",
        r#"{ "name": "level", "model": { "drift": ["0"], "observation": ["x"], "diffusion": [[0.5]],
             "noise": { "kind": "discrete", "mixture": [{ "mean": [0], "cov": [[0.3]] }] } },
             "prior": { "kind": "gaussian", "mean": [0], "cov": [[4]] },
             "domain": [[-10, 14]], "time": { "dt_obs": 1 },
             "methods": [{ "method": "kalman" }] }"#,
    );
    let with_steps = |steps: &str, format: &str, extra: &[&str]| {
        let mut all = vec![
            "forecast",
            scenario.to_str().unwrap(),
            "--observations",
            obs.to_str().unwrap(),
            "--steps",
            steps,
            "--format",
            format,
        ];
        all.extend_from_slice(extra);
        zakai(&all)
    };
    let args = |format: &str, extra: &[&str]| with_steps("3", format, extra);
    let (q, r) = (0.25, 0.3);
    let (mut m, mut p) = (0.0, 4.0);
    for (k, v) in z.iter().enumerate() {
        if k > 0 {
            p += q;
        }
        if !v.is_nan() {
            let g = p / (p + r);
            m += g * (v - m);
            p -= g * p;
        }
    }
    let z975 = 1.959963984540054;
    let o = args("csv", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("method,t,component,mean,sd,lower,upper"));
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 6, "{text}");
    for (i, row) in rows.iter().enumerate() {
        let s = (i / 2 + 1) as f64;
        let value = |c: usize| row[c].parse::<f64>().unwrap();
        assert_eq!(value(1), 5.0 + s);
        let var = p + s * q + if row[2] == "z1" { r } else { 0.0 };
        assert!((value(3) - m).abs() < 1e-12, "{row:?}");
        assert!((value(4) - var.sqrt()).abs() < 1e-12, "{row:?}");
        assert!((value(5) - (m - z975 * var.sqrt())).abs() < 1e-8, "{row:?}");
        assert!((value(6) - (m + z975 * var.sqrt())).abs() < 1e-8, "{row:?}");
    }
    let o = args("json", &["--level", "0.5"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["level"], 0.5);
    let last = &v["methods"][0]["steps"][2]["observation"][0];
    let sd = (p + 3.0 * q + r).sqrt();
    assert!((last["upper"].as_f64().unwrap() - (m + 0.6744897501960817 * sd)).abs() < 1e-8);
    let table = String::from_utf8(args("table", &[]).stdout).unwrap();
    assert!(
        table.contains("KF — steps of 1 ahead, 95% intervals"),
        "{table}"
    );
    assert_clean_failure(&args("csv", &["--level", "1"]), "--level");
    assert_clean_failure(&with_steps("0", "csv", &[]), "--steps");
    assert_clean_failure(&args("csv", &["--dt", "-1"]), "--dt");
}

/// The Nile's local level with q under a log-normal prior (on [0, ∞)) and r uniform on
/// [0, 40 000], the Kalman filter's likelihood.
const NILE_POSTERIOR: &str = r#"{ "name": "nile",
 "parameters": { "q": { "value": 1000, "bounds": [0, null], "prior": {"kind": "lognormal", "mu": 7, "sigma": 2} },
                 "r": { "value": 10000, "bounds": [0, 40000] } },
 "model": { "drift": ["0"], "observation": ["x"], "diffusion": [["sqrt(q)"]],
            "noise": { "kind": "discrete", "mixture": [{ "mean": [0], "cov": [["r"]] }] } },
 "prior": { "kind": "gaussian", "mean": [1120], "cov": [[1e7]] },
 "domain": [[-2000, 4000]], "time": { "dt_obs": 1 }, "methods": [{"method": "kalman"}] }"#;

/// `zakai sample` on the Nile (a gap of ten years): the CSV has one row per draw (`chain`,
/// `draw`, `q`, `r`, `lp`) and its draws' means are the JSON summary's (the same seed, the
/// same chains); the table names the sampler and the start; the SVG is written; bad requests
/// fail with one line.
#[test]
fn sample_writes_every_draw_the_summary_and_the_plot_and_refuses_bad_requests() {
    // Writes the observations (with the gap) and the scenario, and filters them once.
    filter_the_nile("sample", NILE_POSTERIOR);
    let dir = std::env::temp_dir().join(format!("zakai-cli-test-{}", std::process::id()));
    let (obs, scenario) = (dir.join("sample-obs.csv"), dir.join("sample-scenario.json"));
    let (csv, svg) = (dir.join("draws.csv"), dir.join("posterior.svg"));
    let base = [
        "sample",
        scenario.to_str().unwrap(),
        "--observations",
        obs.to_str().unwrap(),
        "--draws",
        "300",
        "--warmup",
        "300",
        "--seed",
        "4",
    ];
    let o = zakai(
        &[
            &base[..],
            &[
                "--out",
                csv.to_str().unwrap(),
                "--svg",
                svg.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "chain,draw,q,r,lp");
    assert_eq!(lines.len(), 1 + 4 * 300);
    let rows: Vec<Vec<f64>> = lines[1..]
        .iter()
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert!(rows
        .iter()
        .all(|r| r[2] > 0.0 && (0.0..=40_000.0).contains(&r[3]) && r[4].is_finite()));
    let json = zakai(&[&base[..], &["--format", "json"]].concat());
    assert!(json.status.success(), "{}", stderr(&json));
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["sampler"], "adaptive random-walk Metropolis");
    for (i, name) in ["q", "r"].iter().enumerate() {
        let s = &v["summary"][i];
        assert_eq!(s["name"], *name);
        let mean = rows.iter().map(|r| r[2 + i]).sum::<f64>() / rows.len() as f64;
        let want = s["mean"].as_f64().unwrap();
        assert!(
            (mean - want).abs() < 1e-9 * want.abs(),
            "{name}: {mean} vs {want}"
        );
        assert!(s["diagnostics"]["rhat"].as_f64().unwrap() > 0.9, "{s}");
    }
    let table = String::from_utf8_lossy(&zakai(&base).stdout).into_owned();
    assert!(
        table.contains("adaptive random-walk Metropolis")
            && table.contains("maximum-likelihood estimate")
            && table.contains("lognormal(mu = 7.0, sigma = 2.0) on [0, inf]"),
        "{table}"
    );
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(drawn.contains("<svg") && drawn.contains("prior"));
    assert_clean_failure(&zakai(&[&base[..], &["--chains", "0"]].concat()), "chains");
    // Delayed acceptance screened by the UKF (here the Kalman filter's equal): said in a note.
    let screened = zakai(&[&base[..], &["--surrogate", "ukf"]].concat());
    assert!(screened.status.success(), "{}", stderr(&screened));
    assert!(String::from_utf8_lossy(&screened.stdout).contains("note: delayed acceptance"));
    assert_clean_failure(
        &zakai(&[&base[..], &["--surrogate", "nosuch"]].concat()),
        "unknown method",
    );
    // Correlated pseudo-marginal steps: ρ in [0, 1), and not with common random numbers.
    assert_clean_failure(
        &zakai(&[&base[..], &["--correlation", "1.5"]].concat()),
        "ρ must be in [0, 1)",
    );
    assert_clean_failure(
        &zakai(
            &[
                &base[..],
                &["--correlation", "0.9", "--common-random-numbers"],
            ]
            .concat(),
        ),
        "one or the other",
    );
    let open = dir.join("open.json");
    std::fs::write(&open, NILE_POSTERIOR.replace("[0, 40000]", "[0, null]")).unwrap();
    let mut args = base.to_vec();
    args[1] = open.to_str().unwrap();
    assert_clean_failure(&zakai(&args), "parameters.r.prior");
}
