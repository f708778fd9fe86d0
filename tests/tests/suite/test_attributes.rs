//! Every test also runs in WebAssembly: `wasm-pack test --node` runs only functions marked
//! `#[wasm_bindgen_test]`, and a plain `#[test]` compiles there without running. So every
//! module (or file) that holds a `#[test]` must import the attribute that is
//! `wasm_bindgen_test` on wasm32 — `crate::testing::test` in the core, `zakai_tests::test`
//! here — or the test would silently be native only. Read from the sources.
// Reads sources from the file system: native only.
#![cfg(not(target_arch = "wasm32"))]

use std::path::Path;
use zakai_tests::test;

/// The imports that make `#[test]` mean `wasm_bindgen_test` on wasm32 (the core's, the
/// integration tests', and the test helpers' own unit tests').
const IMPORTS: [&str; 3] = [
    "use crate::testing::test",
    "use zakai_tests::test",
    "use crate::test",
];

/// A `{ … }` block: a module's (or the file's) or any other.
struct Scope {
    module: bool,
    imports: bool,
    tests: Vec<usize>,
}

/// Lines of the `#[test]`s in `text` whose module does not import the attribute.
fn unimported_tests(text: &str) -> Vec<usize> {
    let chars: Vec<char> = text.chars().collect();
    let mut scopes = vec![Scope {
        module: true,
        imports: false,
        tests: Vec::new(),
    }];
    let mut missing = Vec::new();
    // Code since the last `;`, `{` or `}`, comments and literals left out.
    let mut recent = String::new();
    let (mut i, mut line) = (0, 1);
    let skip_to = |i: &mut usize, line: &mut usize, end: &dyn Fn(usize) -> bool| {
        while *i < chars.len() && !end(*i) {
            if chars[*i] == '\n' {
                *line += 1;
            }
            *i += 1;
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        match c {
            '/' if next == Some('/') => {
                skip_to(&mut i, &mut line, &|j| chars[j] == '\n');
                continue;
            }
            '/' if next == Some('*') => {
                i += 2;
                skip_to(&mut i, &mut line, &|j| {
                    chars[j] == '*' && chars.get(j + 1) == Some(&'/')
                });
                i += 2;
                continue;
            }
            'r' if matches!(next, Some('"' | '#'))
                && !recent.ends_with(|p: char| p.is_alphanumeric() || p == '_') =>
            {
                let hashes = chars[i + 1..].iter().take_while(|&&h| h == '#').count();
                if chars.get(i + 1 + hashes) == Some(&'"') {
                    i += 2 + hashes;
                    skip_to(&mut i, &mut line, &|j| {
                        chars[j] == '"' && (1..=hashes).all(|h| chars.get(j + h) == Some(&'#'))
                    });
                    i += 1 + hashes;
                    continue;
                }
            }
            '"' => {
                i += 1;
                skip_to(&mut i, &mut line, &|j| {
                    chars[j] == '"'
                        && chars[..j].iter().rev().take_while(|&&b| b == '\\').count() % 2 == 0
                });
                i += 1;
                continue;
            }
            // A character literal ('{', '\n', '\''), not a lifetime ('a).
            '\'' if next == Some('\\') => {
                i += 3;
                skip_to(&mut i, &mut line, &|j| chars[j] == '\'');
                i += 1;
                continue;
            }
            '\'' if chars.get(i + 2) == Some(&'\'') => {
                i += 3;
                continue;
            }
            '{' => {
                let words: Vec<&str> = recent.split_whitespace().collect();
                let module = words.len() >= 2 && words[words.len() - 2] == "mod";
                scopes.push(Scope {
                    module,
                    imports: false,
                    tests: Vec::new(),
                });
                recent.clear();
            }
            '}' => {
                let scope = scopes.pop().expect("balanced braces");
                if scope.module && !scope.imports {
                    missing.extend(scope.tests);
                }
                recent.clear();
            }
            ';' => {
                let statement = recent.split_whitespace().collect::<Vec<_>>().join(" ");
                let scope = scopes.last_mut().unwrap();
                if scope.module && IMPORTS.contains(&statement.as_str()) {
                    scope.imports = true;
                }
                recent.clear();
            }
            ']' => {
                recent.push(c);
                let compact: String = recent.chars().filter(|c| !c.is_whitespace()).collect();
                if compact.ends_with("#[test]") {
                    scopes.last_mut().unwrap().tests.push(line);
                }
            }
            _ => {
                if c == '\n' {
                    line += 1;
                }
                recent.push(c);
            }
        }
        i += 1;
    }
    let file = scopes.pop().expect("balanced braces");
    assert!(scopes.is_empty(), "unbalanced braces");
    if !file.imports {
        missing.extend(file.tests);
    }
    missing
}

#[test]
fn the_reader_finds_tests_without_the_import() {
    let without = "mod a {\n    #[test]\n    fn t() { let s = \"}\"; let c = '{'; }\n}\n";
    assert_eq!(unimported_tests(without), vec![2]);
    let with = "mod a {\n    use zakai_tests::test;\n    #[test]\n    fn t() {}\n}\n";
    assert!(unimported_tests(with).is_empty());
    // The file's import does not reach a nested module.
    let nested = "use zakai_tests::test;\n#[test]\nfn t() {}\nmod b {\n    // }\n    #[test]\n    fn u() {}\n}\n";
    assert_eq!(unimported_tests(nested), vec![6]);
    let raw = "use crate::testing::test;\nfn f<'a>(x: &'a str) { let r = r#\"{ \"#; }\n#[test]\nfn t() {}\n";
    assert!(unimported_tests(raw).is_empty());
}

#[test]
fn every_test_runs_in_webassembly_too() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut missing = Vec::new();
    let mut tests = 0;
    for dir in ["../core/src", "tests", "src"] {
        for file in zakai_tests::rust_files(&root.join(dir)) {
            let text = std::fs::read_to_string(&file).unwrap();
            tests += text.matches("#[test]").count();
            for line in unimported_tests(&text) {
                missing.push(format!("{}:{line}", file.display()));
            }
        }
    }
    assert!(tests > 150, "only {tests} tests found");
    assert!(
        missing.is_empty(),
        "#[test] without `use crate::testing::test;` / `use zakai_tests::test;` in its module \
         (it would not run in WebAssembly):\n{}",
        missing.join("\n")
    );
}
