//! The core's modules form layers without cycles: a module uses only modules of lower layers
//! (or its own). Read from the source: every `crate::<module>` path outside comments, test
//! modules included (a test may use its own module's layer and those below, nothing above).
//! The harness floor `lab` counts each of its modules as one (`crate::lab::scenario` is
//! `lab::scenario`). Order, bottom to top (as the crate doc lists it; `testing`, the unit
//! tests' attribute, sits below them all): validate → error → linalg, random → grid, model →
//! simulate → diagnostics → filters → lab: bibliography → scenario → recording, metrics,
//! papers → experiment → study, fit → reproduction.
// Reads the core's sources from the file system: native only.
#![cfg(not(target_arch = "wasm32"))]

use std::collections::BTreeSet;
use std::path::Path;
use zakai_tests::test;

const LAYERS: &[&[&str]] = &[
    &["testing"],
    &["validate"],
    &["error"],
    &["linalg", "random"],
    &["grid", "model"],
    &["simulate"],
    &["diagnostics"],
    &["filters"],
    &["lab::bibliography"],
    &["lab::scenario"],
    &["lab::recording", "lab::metrics", "lab::papers"],
    &["lab::experiment"],
    &["lab::study", "lab::fit"],
    &["lab::reproduction"],
];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// A module name from the path after `crate::` (`lab::scenario` for the harness's modules).
fn module_name(rest: &str) -> String {
    let word = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
            .collect()
    };
    let first = word(rest);
    match rest[first.len()..].strip_prefix("::") {
        Some(after) if first == "lab" => format!("lab::{}", word(after)),
        _ => first,
    }
}

/// The crate modules `file` uses outside comments.
fn uses(file: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(file).unwrap();
    let mut found = BTreeSet::new();
    for line in text.lines() {
        let code = line.trim_start();
        if code.starts_with("//") {
            continue;
        }
        let code = code.split("//").next().unwrap_or("");
        for (i, _) in code.match_indices("crate::") {
            let name = module_name(&code[i + "crate::".len()..]);
            if !name.is_empty() {
                found.insert(name);
            }
        }
    }
    found
}

#[test]
fn core_modules_use_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let mut violations = Vec::new();
    let mut seen = BTreeSet::new();
    let mut modules = Vec::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        if stem == "lab" {
            for inner in std::fs::read_dir(&path).unwrap() {
                let inner = inner.unwrap().path();
                let stem = inner.file_stem().unwrap().to_string_lossy().into_owned();
                if stem != "mod" {
                    modules.push((format!("lab::{stem}"), inner));
                }
            }
        } else if stem != "lib" && stem != "internals" {
            modules.push((stem, path));
        }
    }
    for (module, path) in modules {
        let own = layer(&module).unwrap_or_else(|| {
            panic!("core module `{module}` is not placed in a layer of this test")
        });
        seen.insert(module.clone());
        for file in zakai_tests::rust_files(&path) {
            for used in uses(&file) {
                let Some(l) = layer(&used) else {
                    continue; // an item of lib.rs (a re-export), not a module
                };
                if used != module && l >= own {
                    violations.push(format!(
                        "{} uses crate::{used} (layer {l}, its own {own})",
                        file.strip_prefix(&src).unwrap().display()
                    ));
                }
            }
        }
    }
    assert!(violations.is_empty(), "{}", violations.join("\n"));
    let listed: BTreeSet<String> = LAYERS
        .iter()
        .flat_map(|l| l.iter().map(|m| m.to_string()))
        .collect();
    assert_eq!(seen, listed, "every layer module exists");
}

/// The code lines of `file` (comments dropped).
fn code_lines(file: &Path) -> Vec<String> {
    std::fs::read_to_string(file)
        .unwrap()
        .lines()
        .map(|l| l.trim_start())
        .filter(|l| !l.starts_with("//"))
        .map(|l| l.split("//").next().unwrap_or("").to_string())
        .collect()
}

/// Names after `prefix` in `line` (`super::` → the sibling named right after it).
fn names_after(line: &str, prefix: &str) -> Vec<String> {
    line.match_indices(prefix)
        .filter(|(i, _)| {
            // Not the tail of a longer path (`super::super::x` is the parent's sibling).
            !line[..*i].ends_with("::")
        })
        .map(|(i, _)| {
            line[i + prefix.len()..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect()
        })
        .collect()
}

/// Within every folder of the core, the files and subfolders side by side use each other
/// without a circle (`a.rs` uses `b.rs` and `b.rs` uses `a.rs`, directly or round a longer
/// loop); the folder's own `mod.rs`, which declares them, is left out.
#[test]
fn no_import_circle_between_siblings() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let mut circles = Vec::new();
    let mut folders = vec![src.clone()];
    while let Some(dir) = folders.pop() {
        let module_path = dir
            .strip_prefix(&src)
            .unwrap()
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("::");
        let mut siblings = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path.clone());
            }
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            if stem != "mod" && stem != "lib" && stem != "internals" {
                siblings.push((stem, path));
            }
        }
        let names: BTreeSet<&str> = siblings.iter().map(|(s, _)| s.as_str()).collect();
        let crate_prefix = if module_path.is_empty() {
            "crate::".to_string()
        } else {
            format!("crate::{module_path}::")
        };
        // Edges: sibling → the siblings its code names.
        let mut edges: Vec<(String, BTreeSet<String>)> = Vec::new();
        for (stem, path) in &siblings {
            let mut used = BTreeSet::new();
            for file in zakai_tests::rust_files(path) {
                let direct_child = file.parent() == Some(dir.as_path());
                for line in code_lines(&file) {
                    let mut found = names_after(&line, &crate_prefix);
                    if direct_child {
                        found.extend(names_after(&line, "super::"));
                    }
                    for name in found {
                        if name != *stem && names.contains(name.as_str()) {
                            used.insert(name);
                        }
                    }
                }
            }
            edges.push((stem.clone(), used));
        }
        // A circle is a sibling reachable from itself.
        for (start, _) in &edges {
            let mut seen = BTreeSet::new();
            let mut stack: Vec<String> = edges
                .iter()
                .find(|(s, _)| s == start)
                .map(|(_, u)| u.iter().cloned().collect())
                .unwrap_or_default();
            while let Some(next) = stack.pop() {
                if next == *start {
                    circles.push(format!(
                        "{}/{start}",
                        dir.strip_prefix(&src).unwrap().display()
                    ));
                    break;
                }
                if seen.insert(next.clone()) {
                    if let Some((_, u)) = edges.iter().find(|(s, _)| *s == next) {
                        stack.extend(u.iter().cloned());
                    }
                }
            }
        }
    }
    assert!(
        circles.is_empty(),
        "in a circle of imports: {}",
        circles.join(", ")
    );
}
