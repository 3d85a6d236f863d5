//! The house rules of ARCHITECTURE.md, read from the source: each layer of the library
//! imports only the layers below it, `model` and `theory` stand side by side, only `model`
//! names the engine; no function in `src/` is over 100 lines and no file over 600.
//!
//! `cargo test --test integration house -- --nocapture` prints the longest functions and
//! files.

use std::collections::{BTreeMap, BTreeSet};
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

/// The module path of a file under `src/` (`src/run/guard.rs` is `run::guard`, `src/run.rs`
/// is `run`); `None` for the crate roots.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?.with_extension("");
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main") {
        return None;
    }
    Some(parts.join("::"))
}

/// The module paths `text` (the file of module `own`) names: `crate::a::b::...` and
/// `super::x::...`, each cut to the longest prefix that is one of `modules`.
fn named_modules(text: &str, own: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let parent = own.rsplit_once("::").map_or("", |(p, _)| p);
    let mut found = BTreeSet::new();
    for (prefix, base) in [("crate::", ""), ("super::", parent)] {
        for (i, _) in text.match_indices(prefix) {
            let before = text[..i].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let rest: String = text[i + prefix.len()..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            let mut path: Vec<&str> = if base.is_empty() {
                vec![]
            } else {
                base.split("::").collect()
            };
            path.extend(rest.split("::").filter(|p| !p.is_empty()));
            while !path.is_empty() {
                let candidate = path.join("::");
                if modules.contains(&candidate) {
                    found.insert(candidate);
                    break;
                }
                path.pop();
            }
        }
    }
    found
}

#[test]
fn no_two_files_use_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let modules: BTreeMap<String, PathBuf> = files
        .iter()
        .filter_map(|f| Some((module_of(&src, f)?, f.clone())))
        .collect();
    let names: BTreeSet<String> = modules.keys().cloned().collect();
    let uses: BTreeMap<&String, BTreeSet<String>> = modules
        .iter()
        .map(|(m, f)| {
            let text = fs::read_to_string(f).unwrap();
            // The code that uses: not the unit tests (which may use anything) and not the
            // comments (a "see also" link each way is no knot).
            let code: String = text
                .split("\n#[cfg(test)]\nmod tests")
                .next()
                .unwrap_or(&text)
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            (m, named_modules(&code, m, &names))
        })
        .collect();
    // A parent names its children to declare them: only a pair of files neither of which is
    // the other's module counts.
    let related =
        |a: &str, b: &str| a.starts_with(&format!("{b}::")) || b.starts_with(&format!("{a}::"));
    let mut circles = Vec::new();
    for (a, used) in &uses {
        for b in used {
            if a.as_str() < b.as_str()
                && !related(a, b)
                && uses.get(b).is_some_and(|back| back.contains(a.as_str()))
            {
                circles.push(format!("{a} <-> {b}"));
            }
        }
    }
    assert!(
        circles.is_empty(),
        "files that use each other (move what both need to one of them, or a third):\n{}",
        circles.join("\n")
    );
}

#[test]
fn the_module_reader_resolves_crate_and_super_paths() {
    let modules: BTreeSet<String> = ["run", "run::stop", "run::guard", "scene"]
        .map(String::from)
        .into();
    let text = "use crate::run::stop::{A, B};\nuse super::guard::X;\n/// [`S`](crate::scene::S)";
    let found: Vec<String> = named_modules(text, "run::limits", &modules)
        .into_iter()
        .collect();
    assert_eq!(found, ["run::guard", "run::stop", "scene"]);
}
