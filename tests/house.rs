//! The house rules of ARCHITECTURE.md, read from the source: each layer of the library
//! imports only the layers below it, `model` and `theory` stand side by side, only `model`
//! names the engine; no function in `src/` is over 100 lines and no file over 600.
//!
//! `cargo test --test integration house -- --nocapture` prints the longest functions and
//! files.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The library's layers, lowest first; a layer may import the layers of a lower rank.
const LAYERS: [(&str, u32); 8] = [
    ("scene", 1),
    ("spiral", 2),
    ("theory", 3),
    ("model", 3),
    ("run", 4),
    ("output", 5),
    ("study", 6),
    ("python", 7),
];

/// The crates only the model may name.
const ENGINE_CRATES: [&str; 3] = ["rapier2d", "parry2d", "nalgebra"];

fn rank(layer: &str) -> Option<u32> {
    LAYERS.iter().find(|(n, _)| *n == layer).map(|(_, r)| *r)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The layer a library file belongs to: `src/run.rs` and `src/run/*` are `run`; `None` for
/// the crate roots and the binary's own modules.
fn layer_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    rank(name).map(|_| name.to_string())
}

/// The top-level modules a file names as `crate::<module>`, in code or in doc links.
fn crate_paths(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for (i, _) in text.match_indices("crate::") {
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &text[i + "crate::".len()..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        found.insert(name);
    }
    found
}

#[test]
fn each_layer_imports_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut broken = Vec::new();
    let mut seen_layers = BTreeSet::new();
    for file in &files {
        let Some(layer) = layer_of(&src, file) else {
            continue;
        };
        seen_layers.insert(layer.clone());
        let own = rank(&layer).unwrap();
        let text = fs::read_to_string(file).unwrap();
        for used in crate_paths(&text) {
            let allowed = used == layer || rank(&used).is_some_and(|r| r < own);
            if !allowed {
                broken.push(format!(
                    "{} (layer {layer}, rank {own}) imports crate::{used} (rank {})",
                    file.display(),
                    rank(&used).map_or("none".into(), |r| r.to_string())
                ));
            }
        }
        for engine in ENGINE_CRATES {
            if layer != "model" && text.contains(&format!("{engine}::")) {
                broken.push(format!(
                    "{} names {engine}: only the model may",
                    file.display()
                ));
            }
        }
    }
    assert_eq!(
        seen_layers.len(),
        LAYERS.len(),
        "every layer has files: found {seen_layers:?}"
    );
    assert!(
        broken.is_empty(),
        "import rules of ARCHITECTURE.md broken:\n{}",
        broken.join("\n")
    );
}

#[test]
fn the_rule_reader_sees_imports_and_doc_links() {
    let text = "use crate::run::Sample;\n//! see [`x`](crate::theory::References)\nuncrate::no";
    let found: Vec<_> = crate_paths(text).into_iter().collect();
    assert_eq!(found, ["run", "theory"]);
}

/// The longest a function in `src/` may be, from its `fn` line to its closing brace.
const MAX_FUNCTION_LINES: usize = 100;
/// The longest a file in `src/` may be, its unit tests included.
const MAX_FILE_LINES: usize = 600;

/// The functions of a rustfmt-formatted file outside its `mod tests`: name, first line
/// (1-based) and length in lines. A function ends at the first later line that is its
/// indent followed by `}`; a declaration without a body (`;`) or on one line is skipped.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let code = lines
        .iter()
        .position(|l| l.trim_start().ends_with("mod tests {"))
        .unwrap_or(lines.len());
    let mut found = Vec::new();
    let mut i = 0;
    while i < code {
        let line = lines[i];
        let indent = &line[..line.len() - line.trim_start().len()];
        let head = line.trim_start();
        let head = head
            .strip_prefix("pub(crate) ")
            .or_else(|| head.strip_prefix("pub(super) "))
            .or_else(|| head.strip_prefix("pub "))
            .unwrap_or(head);
        let head = head.strip_prefix("const ").unwrap_or(head);
        if let Some(rest) = head.strip_prefix("fn ") {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let opens = (i..code).find(|&j| {
                let t = lines[j].trim_end();
                t.ends_with('{') || t.ends_with(';') || t.ends_with('}')
            });
            if let Some(j) = opens.filter(|&j| lines[j].trim_end().ends_with('{')) {
                let close = format!("{indent}}}");
                if let Some(k) = (j + 1..lines.len()).find(|&k| lines[k] == close) {
                    found.push((name, i + 1, k - i + 1));
                    i = k;
                }
            }
        }
        i += 1;
    }
    found
}

#[test]
fn no_function_is_over_100_lines_and_no_file_over_600() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut fns = Vec::new();
    let mut sizes = Vec::new();
    for file in &files {
        let text = fs::read_to_string(file).unwrap();
        let rel = file.strip_prefix(&src).unwrap().display().to_string();
        sizes.push((text.lines().count(), rel.clone()));
        for (name, line, len) in functions(&text) {
            fns.push((len, format!("src/{rel}:{line} {name}")));
        }
    }
    fns.sort_unstable_by(|a, b| b.cmp(a));
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    println!("longest functions:");
    for (len, at) in fns.iter().take(10) {
        println!("  {len:4} {at}");
    }
    println!("longest files:");
    for (len, at) in sizes.iter().take(10) {
        println!("  {len:4} src/{at}");
    }
    let long: Vec<_> = fns
        .iter()
        .filter(|(l, _)| *l > MAX_FUNCTION_LINES)
        .collect();
    let big: Vec<_> = sizes.iter().filter(|(l, _)| *l > MAX_FILE_LINES).collect();
    assert!(
        long.is_empty() && big.is_empty(),
        "over {MAX_FUNCTION_LINES} lines: {long:?}; files over {MAX_FILE_LINES}: {big:?}"
    );
}

#[test]
fn the_function_reader_measures_from_fn_to_its_brace() {
    let text = "fn a() {\n    x;\n}\nimpl A {\n    pub(crate) fn b(\n        y: u8,\n    ) -> u8 {\n        y\n    }\n    fn c(&self);\n}\n#[cfg(test)]\nmod tests {\n    fn t() {\n    }\n}\n";
    assert_eq!(
        functions(text),
        [("a".to_string(), 1, 3), ("b".to_string(), 5, 5)]
    );
}
