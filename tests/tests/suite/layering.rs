//! The core's modules form layers without cycles: a module uses only modules of lower layers
//! (or its own). Read from the source: every `crate::<module>` path outside comments, test
//! modules included (a test may use its own module's layer and those below, nothing above).
//! The harness floor `lab` counts each of its modules as one (`crate::lab::scenario` is
//! `lab::scenario`). Order, bottom to top (as the crate doc lists it; `testing`, the unit
//! tests' attribute, sits below them all): validate → error → linalg → random → grid, model →
//! simulate → diagnostics → filters → lab: bibliography → scenario → recording, metrics,
//! checks, mcmc, papers → experiment → study, fit → posterior, reproduction.
// Reads the core's sources from the file system: native only.
#![cfg(not(target_arch = "wasm32"))]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use zakai_tests::test;

const LAYERS: &[&[&str]] = &[
    &["testing"],
    &["validate"],
    &["error"],
    &["linalg"],
    &["random"],
    &["grid", "model"],
    &["simulate"],
    &["diagnostics"],
    &["filters"],
    &["lab::bibliography"],
    &["lab::scenario"],
    &[
        "lab::recording",
        "lab::metrics",
        "lab::checks",
        "lab::mcmc",
        "lab::papers",
    ],
    &["lab::experiment"],
    &["lab::study", "lab::fit"],
    &["lab::posterior", "lab::reproduction"],
];

fn layer(module: &str) -> Option<usize> {
    // `crate::lab` itself (or a glob of it): the harness floor, from its lowest layer up.
    let module = if module == "lab" {
        "lab::bibliography"
    } else {
        module
    };
    LAYERS.iter().position(|l| l.contains(&module))
}

/// `source` with its comments (`//…`, nested `/*…*/`) and the contents of its string and
/// character literals (raw strings included) replaced by spaces: what is left is code, and a
/// `crate::` inside a message or a doc comment is not a use.
fn code_only(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && !chars[..i]
                .last()
                .is_some_and(|p| p.is_alphanumeric() || *p == '_')
        {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= chars.len() {
                    break;
                }
                if chars[j] == '"' && (0..hashes).all(|h| chars.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                out.push(blank(chars[j]));
                j += 1;
            }
            i = j;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                out.push(blank(chars[i.min(chars.len() - 1)]));
                i += 1;
            }
            i += 1;
        } else if c == '\'' && (next == Some('\\') || chars.get(i + 2) == Some(&'\'')) {
            // A character literal ('"', '\'', 'x'); a lifetime 'a has no closing quote.
            i += if next == Some('\\') { 3 } else { 2 };
            while i < chars.len() && chars[i] != '\'' {
                i += 1;
            }
            i += 1;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The module path of `file` under `src` (`filters/kalman/ekf.rs` → filters, kalman, ekf; a
/// `mod.rs` is its folder's module; `lib.rs` the crate's).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let mut path: Vec<String> = file
        .strip_prefix(src)
        .unwrap()
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(path.last().map(String::as_str), Some("mod" | "lib")) {
        path.pop();
    }
    path
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A tiny reader of paths in code.
struct Paths<'a> {
    code: &'a [char],
    at: usize,
}

impl Paths<'_> {
    fn skip_space(&mut self) {
        while self.code.get(self.at).is_some_and(|c| c.is_whitespace()) {
            self.at += 1;
        }
    }

    fn word(&mut self) -> String {
        self.skip_space();
        let start = self.at;
        while self.code.get(self.at).is_some_and(|&c| is_ident(c)) {
            self.at += 1;
        }
        self.code[start..self.at].iter().collect()
    }

    fn eat(&mut self, token: &str) -> bool {
        self.skip_space();
        let t: Vec<char> = token.chars().collect();
        if self.code[self.at..].starts_with(&t) {
            self.at += t.len();
            true
        } else {
            false
        }
    }

    /// The paths of a tree `a::b::{c, d::{e, self}}` from here, each as its segments.
    fn tree(&mut self) -> Vec<Vec<String>> {
        let mut prefix = Vec::new();
        loop {
            if self.eat("{") {
                let mut out = Vec::new();
                loop {
                    if self.eat("}") {
                        break;
                    }
                    for tail in self.tree() {
                        let mut path = prefix.clone();
                        path.extend(tail.into_iter().filter(|s| s != "self"));
                        out.push(path);
                    }
                    self.eat(",");
                    if self.at >= self.code.len() {
                        break;
                    }
                }
                return out;
            }
            let word = self.word();
            if word.is_empty() {
                return vec![prefix];
            }
            prefix.push(word);
            if !self.eat("::") {
                // `a as b`: the alias is not a path (a whole word, not the start of `assert`).
                let save = self.at;
                if self.word() == "as" {
                    self.word();
                } else {
                    self.at = save;
                }
                return vec![prefix];
            }
        }
    }
}

/// Every path from `crate::` or `super::` in `source` (a file of module `module`), resolved
/// to the crate's root: grouped imports `crate::{a, b::{c}}` give each leaf, and `super::`
/// counts from the inline module it is written in (`mod tests { use super::… }` is the
/// file's module).
fn crate_paths(source: &str, module: &[String]) -> Vec<Vec<String>> {
    let code: Vec<char> = code_only(source).chars().collect();
    let mut found = Vec::new();
    // Inline modules open around the reading position: (name, brace depth inside it).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < code.len() {
        let c = code[i];
        if c == '{' {
            depth += 1;
            i += 1;
            continue;
        }
        if c == '}' {
            if inline.last().is_some_and(|(_, d)| *d == depth) {
                inline.pop();
            }
            depth = depth.saturating_sub(1);
            i += 1;
            continue;
        }
        let starts_word = is_ident(c) && (i == 0 || !is_ident(code[i - 1]));
        if !starts_word {
            i += 1;
            continue;
        }
        let mut reader = Paths { code: &code, at: i };
        let word = reader.word();
        if word == "mod" {
            let name = reader.word();
            if reader.eat("{") {
                inline.push((name, depth + 1));
                depth += 1;
                i = reader.at;
                continue;
            }
        }
        let after_path = i >= 2 && code[i - 2] == ':' && code[i - 1] == ':';
        if (word == "crate" || word == "super") && !after_path && reader.eat("::") {
            let mut base: Vec<String> = if word == "crate" {
                Vec::new()
            } else {
                let mut here: Vec<String> = module.to_vec();
                here.extend(inline.iter().map(|(n, _)| n.clone()));
                here.pop();
                here
            };
            // Further `super::`s climb on.
            loop {
                let save = reader.at;
                if reader.word() == "super" && reader.eat("::") {
                    base.pop();
                } else {
                    reader.at = save;
                    break;
                }
            }
            for tail in reader.tree() {
                let mut path = base.clone();
                path.extend(tail);
                found.push(path);
            }
            i = reader.at;
            continue;
        }
        i = reader.at.max(i + 1);
    }
    found
}

/// A layer module's name from a resolved path (`lab::scenario` for the harness's modules;
/// `lab` for anything else under `crate::lab`, a re-export of the floor or a glob).
fn module_name(path: &[String]) -> String {
    match path {
        [lab, inner, ..] if lab == "lab" && layer(&format!("lab::{inner}")).is_some() => {
            format!("lab::{inner}")
        }
        [lab, ..] if lab == "lab" => "lab".to_string(),
        [first, ..] => first.clone(),
        [] => String::new(),
    }
}

/// The crate root's re-exports (`pub use filters::kalman::Kalman;` in lib.rs): item name →
/// the layer module it comes from, so that `crate::Kalman` counts as a use of `filters`.
fn root_reexports(lib_rs: &str) -> BTreeMap<String, String> {
    let code: Vec<char> = code_only(lib_rs).chars().collect();
    let text: String = code.iter().collect();
    let mut out = BTreeMap::new();
    for (i, _) in text.match_indices("pub use ") {
        let at = text[..i].chars().count() + "pub use ".len();
        let mut reader = Paths { code: &code, at };
        for path in reader.tree() {
            if let (Some(item), Some(_)) = (path.last(), layer(&module_name(&path))) {
                out.insert(item.clone(), module_name(&path));
            }
        }
    }
    out
}

/// The layer violations of a file of module `own` (its layer name) with module path `module`;
/// `reexports` resolves items of the crate root ([`root_reexports`]).
fn violations_in(
    source: &str,
    own: &str,
    module: &[String],
    reexports: &BTreeMap<String, String>,
) -> Vec<String> {
    let own_layer = layer(own).expect("a placed module");
    crate_paths(source, module)
        .iter()
        .filter_map(|path| {
            let used = match path.first().and_then(|item| reexports.get(item)) {
                Some(source) => source.clone(),
                None => module_name(path),
            };
            // None: neither a layer module nor a re-export of one (`crate::nalgebra`).
            let l = layer(&used)?;
            // The floor's own modules may use what `lab` re-exports (not resolved here).
            if used == "lab" && own.starts_with("lab::") {
                return None;
            }
            (used != own && l >= own_layer).then(|| {
                format!(
                    "uses crate::{} (layer {l}, its own {own_layer})",
                    path.join("::")
                )
            })
        })
        .collect()
}

#[test]
fn core_modules_use_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let reexports = root_reexports(&std::fs::read_to_string(src.join("lib.rs")).unwrap());
    // The map is read, not empty: the filter types come from `filters`.
    assert_eq!(reexports.get("Kalman").map(String::as_str), Some("filters"));
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
        } else if stem != "lib" {
            modules.push((stem, path));
        }
    }
    for (module, path) in modules {
        layer(&module).unwrap_or_else(|| {
            panic!("core module `{module}` is not placed in a layer of this test")
        });
        seen.insert(module.clone());
        for file in zakai_tests::rust_files(&path) {
            let source = std::fs::read_to_string(&file).unwrap();
            for v in violations_in(&source, &module, &module_of(&src, &file), &reexports) {
                violations.push(format!(
                    "{} {v}",
                    file.strip_prefix(&src).unwrap().display()
                ));
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

/// Within every folder of the core, the files and subfolders side by side use each other
/// without a circle (`a.rs` uses `b.rs` and `b.rs` uses `a.rs`, directly or round a longer
/// loop); the folder's own `mod.rs`, which declares them, is left out.
#[test]
fn no_import_circle_between_siblings() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let mut circles = Vec::new();
    let mut folders = vec![src.clone()];
    while let Some(dir) = folders.pop() {
        let folder: Vec<String> = dir
            .strip_prefix(&src)
            .unwrap()
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let mut siblings = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path.clone());
            }
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            if stem != "mod" && stem != "lib" {
                siblings.push((stem, path));
            }
        }
        let names: BTreeSet<&str> = siblings.iter().map(|(s, _)| s.as_str()).collect();
        // Edges: sibling → the siblings its code names (any path that resolves into this
        // folder's module and on to a sibling).
        let mut edges: Vec<(String, BTreeSet<String>)> = Vec::new();
        for (stem, path) in &siblings {
            let mut used = BTreeSet::new();
            for file in zakai_tests::rust_files(path) {
                let source = std::fs::read_to_string(&file).unwrap();
                for resolved in crate_paths(&source, &module_of(&src, &file)) {
                    let Some(rest) = resolved.strip_prefix(folder.as_slice()) else {
                        continue;
                    };
                    if let Some(name) = rest.first() {
                        if name != stem && names.contains(name.as_str()) {
                            used.insert(name.clone());
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

/// The scanner finds what a line-by-line search for `crate::<module>` missed: a grouped
/// import over several lines, a `super::super::` path (from an inline test module too) — and
/// not a path inside a string or a comment.
#[test]
fn the_scan_finds_planted_violations_in_every_form() {
    let module = |path: &str| -> Vec<String> { path.split("::").map(String::from).collect() };
    let planted = [
        // A grouped import spread over lines, from the grid (layer 4) up to the experiment.
        (
            "grid",
            "grid::planted",
            "use crate::{\n    linalg::Cholesky,\n    lab::{experiment::Experiment, scenario},\n};",
            vec!["lab::experiment", "lab::scenario"],
        ),
        // super::super from filters::kalman::planted is crate::filters::…; one more reaches
        // the crate's root.
        (
            "filters",
            "filters::kalman::planted",
            "use super::super::super::lab::fit::maximise;",
            vec!["lab::fit"],
        ),
        // In an inline module, `super` is the file's own module.
        (
            "model",
            "model::planted",
            "fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::super::super::simulate::Trajectory;\n}",
            vec!["simulate"],
        ),
        // Text is not code.
        (
            "grid",
            "grid::planted",
            "// use crate::lab::fit;\nconst A: &str = \"crate::lab::fit\";\nlet c = '\"'; /* crate::filters */",
            vec![],
        ),
        // The harness floor itself, and a glob of it.
        (
            "model",
            "model::planted",
            "use crate::lab;\nuse crate::lab::*;",
            vec!["lab", "lab"],
        ),
        // An item of the crate root, re-exported from a layer above; an alias in a group
        // (`as`), and a name that only starts with it (`assemble`).
        (
            "grid",
            "grid::planted",
            "use crate::Experiment;\nuse crate::{lab::fit as f, lab::assemble};",
            vec!["Experiment", "lab::fit", "lab::assemble"],
        ),
    ];
    let reexports = root_reexports(
        "pub use lab::experiment::Experiment;\npub use filters::{kalman::Kalman, Filter};",
    );
    assert_eq!(
        reexports.get("Experiment").map(String::as_str),
        Some("lab::experiment")
    );
    for (own, path, source, expected) in planted {
        let found = violations_in(source, own, &module(path), &reexports);
        assert_eq!(found.len(), expected.len(), "{source}: {found:?}");
        for (v, name) in found.iter().zip(&expected) {
            assert!(v.contains(&format!("crate::{name}")), "{source}: {v}");
        }
    }
}
