//! Every correction the repository cites (`ERRATA A2`, `A18's`, `(C1)`) is defined in
//! docs/errata.md, so a reader of the repository alone can look each one up.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The ids in `text`: a capital A, B or C and one or two digits, standing alone as a word.
fn ids(text: &str) -> BTreeSet<String> {
    let bytes = text.as_bytes();
    let word = |i: usize| {
        bytes
            .get(i)
            .is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_')
    };
    let mut out = BTreeSet::new();
    for (i, &b) in bytes.iter().enumerate() {
        if !matches!(b, b'A' | b'B' | b'C') || (i > 0 && word(i - 1)) {
            continue;
        }
        let digits = bytes[i + 1..]
            .iter()
            .take_while(|c| c.is_ascii_digit())
            .count();
        if (1..=2).contains(&digits) && !word(i + 1 + digits) {
            out.insert(text[i..=i + digits].to_owned());
        }
    }
    out
}

fn files(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, exts, out);
        } else if path
            .extension()
            .is_some_and(|e| exts.iter().any(|x| e == *x))
        {
            out.push(path);
        }
    }
}

#[test]
fn the_id_reader_finds_ids_and_nothing_else() {
    let found = ids("ERRATA A1-A3, (C1), A18's; not A100, UA4, A4b, B or 4A1");
    let want: BTreeSet<String> = ["A1", "A3", "C1", "A18"].map(String::from).into();
    assert_eq!(found, want);
}

#[test]
fn every_cited_correction_is_defined_in_docs_errata() {
    let root = Path::new(ROOT);
    let errata = fs::read_to_string(root.join("docs/errata.md")).unwrap();
    let defined: BTreeSet<String> = errata
        .lines()
        .filter_map(|l| l.strip_prefix("- **"))
        .filter_map(|l| l.split([',', '.']).next())
        .map(str::to_owned)
        .collect();
    assert!(
        defined.contains("A1") && defined.contains("C3"),
        "{defined:?}"
    );
    let mut cited = Vec::new();
    files(&root.join("src"), &["rs", "py", "pyi"], &mut cited);
    files(&root.join("docs"), &["md", "ipynb"], &mut cited);
    files(&root.join("scenes"), &["toml"], &mut cited);
    files(&root.join("tests"), &["rs", "py"], &mut cited);
    cited.extend(["README.md", "ARCHITECTURE.md"].map(|f| root.join(f)));
    let mut missing = Vec::new();
    for path in cited.iter().filter(|p| !p.ends_with("docs/errata.md")) {
        let text = fs::read_to_string(path).unwrap();
        for id in ids(&text).difference(&defined) {
            missing.push(format!("{}: {id}", path.display()));
        }
    }
    // This file's own examples are not citations.
    missing.retain(|m| !m.contains("tests/errata.rs"));
    assert!(
        missing.is_empty(),
        "cited but not in docs/errata.md: {missing:#?}"
    );
}
