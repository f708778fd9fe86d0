//! The core's modules form layers without cycles: a module uses only modules of lower layers
//! (or its own). Read from the source: every `crate::<module>` path outside comments and test
//! modules. Order, bottom to top (as the crate doc lists it; `testing`, the unit tests'
//! attribute, sits below them all): validate → error → linalg, random → grid, model →
//! simulate → recording, diagnostics → filters → scenario → metrics, papers → experiment →
//! study → reproduction.
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
    &["recording", "diagnostics"],
    &["filters"],
    &["scenario"],
    &["metrics", "papers"],
    &["experiment"],
    &["study"],
    &["reproduction"],
];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// The crate modules `file` uses outside comments and `#[cfg(test)]` modules.
fn uses(file: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(file).unwrap();
    let mut found = BTreeSet::new();
    for line in text.lines() {
        let code = line.trim_start();
        if code.starts_with("#[cfg(test)]") || code.starts_with("#[cfg(all(test") {
            break; // test modules sit at the end of a file and may use anything
        }
        if code.starts_with("//") {
            continue;
        }
        let code = code.split("//").next().unwrap_or("");
        for (i, _) in code.match_indices("crate::") {
            let rest = &code[i + "crate::".len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                .collect();
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
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let module = path.file_stem().unwrap().to_string_lossy().into_owned();
        if module == "lib" {
            continue;
        }
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
