//! Recordings as CSV files (`std` feature; the `csv` crate): what `zakai simulate --format csv`
//! writes and `zakai filter --observations` reads, bit for bit (values are written in Rust's
//! shortest round-trip form).
//!
//! * Observations: header `t,dy1,…,dym` (increments of a continuous observation) or
//!   `t,z1,…,zm` (measurements); the first row is the prior's time τ₀ — for increments it
//!   holds zeros (the increment over `(τ_{k−1}, τ_k]` is on row k), for measurements it is a
//!   measurement at τ₀.
//! * Known inputs of a driven model ([`crate::Inputs`]): further columns `u1,…,uk`
//!   after the observations, every field a number — row k's are those over `(τ_{k−1}, τ_k]`.
//! * Truth (optional): header `t,x1,…,xn`, one row per observation row, at the same times.
//!
//! Blank lines and lines starting with `#` are skipped; fields may be padded with spaces. In
//! the observations, an empty field or `NaN`/`NA` (any case) is a missing component (written
//! back as `NaN`); a row with every component missing is a prediction only. Times must be
//! numbers. Every problem names its file, line and column.

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use super::{Part, Recording, INTERVAL_TOLERANCE};
use crate::error::ZakaiError;
use crate::validate::ConfigProblem;

/// Most problems reported from one file (the rest are counted).
const MAX_REPORTED: usize = 12;

/// A CSV table of numbers: column names and rows.
struct Table {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
    /// The file line of each row (1 = the header).
    lines: Vec<u64>,
}

/// Whether a field marks a missing value: empty, `NaN` or `NA` in any case.
fn is_missing_field(field: &str) -> bool {
    field.is_empty() || field.eq_ignore_ascii_case("nan") || field.eq_ignore_ascii_case("na")
}

/// Reads a table of numbers; with `missing` the data columns (all but the first, the time)
/// may hold missing values, read as NaN.
fn read_table(
    file: &str,
    text: &[u8],
    missing: bool,
    problems: &mut Vec<ConfigProblem>,
) -> Option<Table> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text);
    let columns: Vec<String> = match reader.headers() {
        Ok(h) => h.iter().map(str::to_string).collect(),
        Err(e) => {
            problems.push(ConfigProblem::new(
                file,
                format!("cannot read the header: {e}"),
            ));
            return None;
        }
    };
    let (mut rows, mut lines) = (Vec::new(), Vec::new());
    let before = problems.len();
    let mut skipped = 0usize;
    for record in reader.records() {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map_or(0, |p| p.line());
                let message = match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        expected_len, len, ..
                    } => format!(
                        "has {len} fields, the header {expected_len} ({})",
                        columns.join(",")
                    ),
                    _ => format!("{e}"),
                };
                problems.push(ConfigProblem::new(format!("{file} line {line}"), message));
                if problems.len() - before >= MAX_REPORTED {
                    break;
                }
                continue;
            }
        };
        let line = record.position().map_or(0, |p| p.line());
        let mut row = Vec::with_capacity(record.len());
        for (j, (field, column)) in record.iter().zip(&columns).enumerate() {
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => row.push(v),
                _ if missing && j > 0 && is_missing_field(field) => row.push(f64::NAN),
                _ => {
                    if problems.len() - before < MAX_REPORTED {
                        problems.push(ConfigProblem::new(
                            format!("{file} line {line}, column {column}"),
                            if missing && j > 0 {
                                format!("`{field}` is not a finite number (a missing value is an empty field or NaN)")
                            } else {
                                format!("`{field}` is not a finite number")
                            },
                        ));
                    } else {
                        skipped += 1;
                    }
                    row.push(f64::NAN);
                }
            }
        }
        rows.push(row);
        lines.push(line);
    }
    if skipped > 0 {
        problems.push(ConfigProblem::new(
            file,
            format!("and {skipped} more values that are not numbers"),
        ));
    }
    if rows.is_empty() && problems.len() == before {
        problems.push(ConfigProblem::new(file, "has a header but no rows"));
    }
    Some(Table {
        columns,
        rows,
        lines,
    })
}

/// Whether `name` is `prefix` or `prefix<j>` with j = `index` + 1.
fn names(name: &str, prefix: &str, index: usize, count: usize) -> bool {
    name == format!("{prefix}{}", index + 1) || (count == 1 && name == prefix)
}

/// Checks the header `t,<prefix>1,…`; returns the data column count.
fn check_header(
    file: &str,
    t: &Table,
    prefixes: &[&str],
    problems: &mut Vec<ConfigProblem>,
) -> Option<(usize, usize)> {
    let cols = &t.columns;
    if cols.first().map(String::as_str) != Some("t") {
        problems.push(ConfigProblem::new(
            format!("{file} line 1"),
            format!(
                "the first column must be `t` (the time), got `{}`",
                cols.first().map_or("", String::as_str)
            ),
        ));
        return None;
    }
    let count = cols.len() - 1;
    if count == 0 {
        problems.push(ConfigProblem::new(
            format!("{file} line 1"),
            "needs data columns after `t`",
        ));
        return None;
    }
    for (which, prefix) in prefixes.iter().enumerate() {
        if cols[1..]
            .iter()
            .enumerate()
            .all(|(j, c)| names(c, prefix, j, count))
        {
            return Some((which, count));
        }
    }
    let expected: Vec<String> = prefixes.iter().map(|p| format!("t,{p}1,{p}2,…")).collect();
    problems.push(ConfigProblem::new(
        format!("{file} line 1"),
        format!(
            "the header `{}` is not one of {}",
            cols.join(","),
            expected.join(" or ")
        ),
    ));
    None
}

/// Takes the known inputs `u1,…,uk` (the columns from the first named `u…` on) out of the
/// observations table: their count and values, row-major. Every input must be a number.
fn split_inputs(t: &mut Table, problems: &mut Vec<ConfigProblem>) -> (usize, Vec<f64>) {
    let Some(first) = t
        .columns
        .iter()
        .skip(1)
        .position(|c| c.starts_with('u'))
        .map(|j| j + 1)
    else {
        return (0, Vec::new());
    };
    let count = t.columns.len() - first;
    if let Some(j) =
        (first..t.columns.len()).find(|&j| t.columns[j] != format!("u{}", j - first + 1))
    {
        problems.push(ConfigProblem::new(
            "observations line 1",
            format!(
                "the known inputs must be the last columns, named u1,…,u{count} in order; column {} is `{}`",
                j + 1,
                t.columns[j]
            ),
        ));
        return (0, Vec::new());
    }
    let mut values = Vec::with_capacity(count * t.rows.len());
    for (row, line) in t.rows.iter_mut().zip(&t.lines) {
        if let Some(j) = row[first..].iter().position(|v| v.is_nan()) {
            if problems.len() < MAX_REPORTED {
                problems.push(ConfigProblem::new(
                    format!("observations line {line}, column u{}", j + 1),
                    "a known input must be given on every row (a driven model reads it over the interval)",
                ));
            }
        }
        values.extend_from_slice(&row[first..]);
        row.truncate(first);
    }
    t.columns.truncate(first);
    (count, values)
}

impl Recording {
    /// Reads a recording from CSV text: `observations` (header `t,dy1,…` or `t,z1,…`, then the
    /// known inputs `u1,…` of a driven model, if any), and
    /// optionally the `truth` (`t,x1,…`) for an `n`-dimensional state. Every problem — header,
    /// a field that is not a number (with its line and column), a row of the wrong length,
    /// times not increasing, truth rows at other times — is reported at once.
    pub fn from_csv(
        n: usize,
        observations: &[u8],
        truth: Option<&[u8]>,
    ) -> Result<Self, ZakaiError> {
        let mut problems = Vec::new();
        let mut obs = read_table("observations", observations, true, &mut problems);
        let (input_count, inputs) = obs
            .as_mut()
            .map_or((0, Vec::new()), |t| split_inputs(t, &mut problems));
        let truth = truth.and_then(|t| read_table("truth", t, false, &mut problems));
        let kind = obs
            .as_ref()
            .and_then(|t| check_header("observations", t, &["dy", "z"], &mut problems));
        if let Some(t) = &truth {
            if let Some((_, count)) = check_header("truth", t, &["x"], &mut problems) {
                if count != n {
                    problems.push(ConfigProblem::new(
                        "truth line 1",
                        format!("has {count} state columns, the model's state has n = {n}"),
                    ));
                }
            }
        }
        let (Some(obs), Some((kind, m))) = (obs, kind) else {
            return Err(ZakaiError::Config(problems));
        };
        let continuous = kind == 0;
        if continuous {
            if let Some(first) = obs.rows.first() {
                if first[1..].iter().any(|&v| v != 0.0 && !v.is_nan()) {
                    problems.push(ConfigProblem::new(
                        format!("observations line {}", obs.lines[0]),
                        "the first row is the start τ₀ (the prior's time): its increments must be 0 (the increment over (τ₀, τ₁] goes on the next row)",
                    ));
                }
            }
        }
        let times: Vec<f64> = obs.rows.iter().map(|r| r[0]).collect();
        let values: Vec<f64> = obs
            .rows
            .iter()
            .flat_map(|r| r[1..].iter().copied())
            .collect();
        let mut recording = Recording {
            n,
            m,
            times,
            observations: values,
            continuous,
            truth: None,
            input_count,
            inputs,
        };
        let mut truth_lines = Vec::new();
        if let Some(t) = truth {
            truth_lines.clone_from(&t.lines);
            if t.rows.len() != obs.rows.len() {
                problems.push(ConfigProblem::new(
                    "truth",
                    format!(
                        "has {} rows, the observations {}",
                        t.rows.len(),
                        obs.rows.len()
                    ),
                ));
            } else if let Some(k) = (0..t.rows.len()).find(|&k| {
                let (a, b) = (t.rows[k][0], recording.times[k]);
                (a - b).abs() > INTERVAL_TOLERANCE * a.abs().max(b.abs())
            }) {
                problems.push(ConfigProblem::new(
                    format!("truth line {}", t.lines[k]),
                    format!(
                        "time {} differs from the observation time {} on line {}",
                        t.rows[k][0], recording.times[k], obs.lines[k]
                    ),
                ));
            }
            recording.truth = Some(t.rows.iter().flat_map(|r| r[1..].iter().copied()).collect());
        }
        if problems.is_empty() {
            // Lengths and increasing times, each row problem at its file and line.
            problems = recording.placed_problems(&|part, row, _, text| {
                let (file, lines) = match part {
                    Part::Observations => ("observations", &obs.lines),
                    Part::Truth => ("truth", &truth_lines),
                };
                ConfigProblem::new(format!("{file} line {}", lines[row]), text)
            });
        }
        if problems.is_empty() {
            Ok(recording)
        } else {
            Err(ZakaiError::Config(problems))
        }
    }

    /// The observations as CSV (see the module doc), then the known inputs when there are
    /// any, values in shortest round-trip form.
    pub fn observations_csv(&self) -> String {
        let prefix = if self.continuous { "dy" } else { "z" };
        write_table(
            &self.times,
            &[
                (prefix, self.m, &self.observations),
                ("u", self.input_count, &self.inputs),
            ],
        )
    }

    /// The truth as CSV (`t,x1,…`), when it is known.
    pub fn truth_csv(&self) -> Option<String> {
        self.truth
            .as_ref()
            .map(|t| write_table(&self.times, &[("x", self.n, t)]))
    }
}

/// The table `t,<prefix>1,…` of `times` and, for each block `(prefix, width, values)`, its
/// columns (row-major values, `width` per row).
fn write_table(times: &[f64], blocks: &[(&str, usize, &[f64])]) -> String {
    let mut out = String::from("t");
    for (prefix, width, _) in blocks {
        for j in 1..=*width {
            out.push_str(&format!(",{prefix}{j}"));
        }
    }
    out.push('\n');
    for (k, t) in times.iter().enumerate() {
        out.push_str(&format!("{t:?}"));
        for (_, width, values) in blocks {
            for v in &values[k * width..(k + 1) * width] {
                out.push_str(&format!(",{v:?}"));
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    fn problems(r: Result<Recording, ZakaiError>) -> Vec<ConfigProblem> {
        match r {
            Err(ZakaiError::Config(p)) => p,
            other => panic!("expected problems, got {other:?}"),
        }
    }

    #[test]
    fn csv_round_trip_is_bit_exact() {
        let r = Recording {
            n: 2,
            m: 1,
            times: alloc::vec![0.0, 0.1, 0.2 + 1e-17, 0.30000000000000004],
            observations: alloc::vec![0.0, 1e-300, -0.123_456_789_012_345_68, 5e300],
            continuous: true,
            truth: Some(alloc::vec![
                1.0,
                -2.0,
                f64::MIN_POSITIVE,
                3.0,
                1.0 / 3.0,
                0.1,
                7e-9,
                -0.0
            ]),
            input_count: 0,
            inputs: Vec::new(),
        };
        let back = Recording::from_csv(
            2,
            r.observations_csv().as_bytes(),
            r.truth_csv().as_deref().map(str::as_bytes),
        )
        .unwrap();
        assert_eq!(
            back.times.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            r.times.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(
            back.observations
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>(),
            r.observations
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        );
        let (a, b) = (back.truth.unwrap(), r.truth.unwrap());
        assert_eq!(
            a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert!(back.continuous);
    }

    /// Empty fields, `NaN` and `NA` in the observations are missing components (NaN), a row
    /// may miss them all, and they are written back as `NaN`; a missing time is an error, and
    /// so is an infinity.
    #[test]
    fn missing_values_are_nan() {
        let r = Recording::from_csv(
            1,
            b"t,z1,z2\n0,1,2\n0.1,,3\n0.3, NA ,nan\n0.4,5,NaN\n",
            None,
        )
        .unwrap();
        assert_eq!(r.times, alloc::vec![0.0, 0.1, 0.3, 0.4]);
        let o = &r.observations;
        assert_eq!((o[0], o[1], o[3], o[6]), (1.0, 2.0, 3.0, 5.0));
        assert!(o[2].is_nan() && o[4].is_nan() && o[5].is_nan() && o[7].is_nan());
        let back = Recording::from_csv(1, r.observations_csv().as_bytes(), None).unwrap();
        assert_eq!(
            back.observations
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>(),
            o.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        let p = problems(Recording::from_csv(1, b"t,z1\n0,1\n,2\n", None));
        assert_eq!(p[0].field, "observations line 3, column t", "{p:?}");
        let p = problems(Recording::from_csv(1, b"t,z1\n0,1\n0.1,inf\n", None));
        assert!(
            p[0].message.contains("missing value is an empty field"),
            "{p:?}"
        );
        let p = problems(Recording::from_csv(
            1,
            b"t,z1\n0,1\n0.1,2\n",
            Some(b"t,x1\n0,\n0.1,2\n"),
        ));
        assert_eq!(p[0].field, "truth line 2, column x1", "{p:?}");
    }

    #[test]
    fn bad_files_name_line_and_column() {
        let p = problems(Recording::from_csv(
            1,
            b"t,z1\n0,1\n0.1,abc\n0.2\n0.1,4\n",
            None,
        ));
        let text = format!("{p:?}");
        assert!(p.iter().any(|p| p.field == "observations line 3, column z1" && p.message.contains("`abc`")), "{text}");
        assert!(
            p.iter()
                .any(|p| p.field == "observations line 4" && p.message.contains("1 fields")),
            "{text}"
        );
        let p = problems(Recording::from_csv(1, b"t,z1\n0,1\n0.2,2\n0.1,3\n", None));
        assert_eq!(p[0].field, "observations line 4", "{p:?}");
        assert!(p[0].message.contains("increase"), "{p:?}");
        let p = problems(Recording::from_csv(1, b"time,q\n0,1\n", None));
        assert_eq!(p[0].field, "observations line 1");
        let p = problems(Recording::from_csv(1, b"t,dy1\n0,0.5\n0.1,1\n", None));
        assert!(p[0].message.contains("must be 0"), "{p:?}");
        let p = problems(Recording::from_csv(
            1,
            b"t,z1\n0,1\n0.1,2\n",
            Some(b"t,x1\n0,1\n0.2,2\n"),
        ));
        assert_eq!(p[0].field, "truth line 3", "{p:?}");
        let p = problems(Recording::from_csv(
            2,
            b"t,z1\n0,1\n0.1,2\n",
            Some(b"t,x1\n0,1\n0.1,2\n"),
        ));
        assert!(p[0].message.contains("n = 2"), "{p:?}");
    }
}
