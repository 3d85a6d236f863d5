//! The import rules of ARCHITECTURE.md, read from the source: each layer of the library
//! imports only the layers below it, `model` and `theory` stand side by side, and only
//! `model` names the engine.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The library's layers, lowest first; a layer may import the layers of a lower rank.
const LAYERS: [(&str, u32); 7] = [
    ("scene", 1),
    ("spiral", 2),
    ("theory", 3),
    ("model", 3),
    ("run", 4),
    ("output", 5),
    ("study", 6),
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
