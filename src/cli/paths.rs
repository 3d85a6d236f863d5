//! The paths a command is given, checked before any work: each must exist (or, for an output
//! folder, be makeable) and be the kind of thing the command expects. A path that is not is a
//! [`PathError`], which names the path, what it is and what was expected, and exits 2
//! ([`crate::cli::exit`]).

use std::io::Read;
use std::path::{Path, PathBuf};

use uncoil::output::folder::{REPORT, SAMPLES};
use uncoil::study::sweep::INDEX_COLUMN;

/// A path that is missing or of the wrong kind for its command.
#[derive(Debug, thiserror::Error)]
#[error("{}: {found}; expected {expected}", path.display())]
pub struct PathError {
    /// The path as given.
    pub path: PathBuf,
    /// What is there: "no such file or folder", "a folder", "a file", ...
    pub found: String,
    /// What the command expected there.
    pub expected: String,
}

impl PathError {
    pub fn new(path: &Path, found: impl Into<String>, expected: impl Into<String>) -> Self {
        Self {
            path: path.to_owned(),
            found: found.into(),
            expected: expected.into(),
        }
    }
}

/// What is at `path`, said as a [`PathError`]'s `found`: missing, a folder or a file.
fn what_is(path: &Path) -> &'static str {
    match std::fs::metadata(path) {
        Err(_) => "no such file or folder",
        Ok(m) if m.is_dir() => "a folder",
        Ok(_) => "a file",
    }
}

/// `path` is a file; `expected` says what it should be.
pub fn file(path: &Path, expected: &str) -> Result<(), PathError> {
    if path.is_file() {
        Ok(())
    } else {
        Err(PathError::new(path, what_is(path), expected))
    }
}

/// `path` is a folder; `expected` says what it should be.
pub fn folder(path: &Path, expected: &str) -> Result<(), PathError> {
    if path.is_dir() {
        Ok(())
    } else {
        Err(PathError::new(path, what_is(path), expected))
    }
}

/// `path` can be an output folder: it is one, or it is missing and the nearest part of it
/// that exists is a folder (so it can be made).
pub fn out_folder(path: &Path) -> Result<(), PathError> {
    let expected = "an output folder (made if missing)";
    if let Some(taken) = path.ancestors().find(|a| a.exists())
        && !taken.is_dir()
    {
        let found = if taken == path {
            "a file".to_owned()
        } else {
            format!("{} is a file", taken.display())
        };
        return Err(PathError::new(path, found, expected));
    }
    Ok(())
}

/// `path` is an MCAP file: a file that starts with MCAP's magic bytes.
pub fn mcap_file(path: &Path) -> Result<(), PathError> {
    let expected = "an MCAP log, e.g. runs/yoga-mat/run.mcap";
    file(path, expected)?;
    if starts_with(path, mcap::MAGIC) {
        Ok(())
    } else {
        Err(PathError::new(
            path,
            "a file that is not MCAP (no MCAP magic bytes)",
            expected,
        ))
    }
}

/// A coil's finished run's output folder: one with `report.json` and `samples.csv`, its
/// report neither a folded chain's nor a salvaged one's.
pub fn run_folder(path: &Path) -> Result<(), PathError> {
    let expected =
        format!("a coil's run's output folder (with {REPORT} and {SAMPLES}), e.g. runs/yoga-mat");
    folder(path, &expected)?;
    if let Some(missing) = [REPORT, SAMPLES]
        .into_iter()
        .find(|f| !path.join(f).is_file())
    {
        return Err(PathError::new(
            path,
            format!("a folder with no {missing}"),
            expected,
        ));
    }
    let kind = std::fs::read_to_string(path.join(REPORT))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("kind").and_then(|k| k.as_str()).map(str::to_owned));
    match kind.as_deref() {
        Some("salvaged") => Err(PathError::new(
            path,
            "a killed run's folder, salvaged: it has no ledger, bang or references",
            expected,
        )),
        Some(other) => Err(PathError::new(path, format!("a {other}'s run"), expected)),
        None => Ok(()),
    }
}

/// The sweep file that `path` names: `path` itself, a `sweep.csv` (or a shard's file), or a
/// sweep's folder holding `sweep.csv`.
pub fn sweep_file(path: &Path) -> Result<PathBuf, PathError> {
    let expected = "a sweep's folder or its sweep.csv, e.g. sweeps/yoga-mat";
    let file = if path.is_dir() {
        let inside = path.join("sweep.csv");
        if !inside.is_file() {
            let shards = std::fs::read_dir(path)
                .into_iter()
                .flatten()
                .flatten()
                .any(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    name.starts_with("sweep.") && name.ends_with(".csv")
                });
            let found = if shards {
                "a folder of shard files and no sweep.csv (join them first: uncoil sweep \
                 --merge FILES)"
            } else {
                "a folder with no sweep.csv"
            };
            return Err(PathError::new(path, found, expected));
        }
        inside
    } else {
        file(path, expected)?;
        path.to_owned()
    };
    sweep_csv(&file, expected)?;
    Ok(file)
}

/// `path` is a file that starts as a sweep's does, with its index column; `expected` says
/// what it should be.
pub fn sweep_csv(path: &Path, expected: &str) -> Result<(), PathError> {
    file(path, expected)?;
    let header = format!("{INDEX_COLUMN},");
    if starts_with(path, header.as_bytes()) {
        Ok(())
    } else {
        Err(PathError::new(
            path,
            format!("a file that is not a sweep's (its first column is not `{INDEX_COLUMN}`)"),
            expected,
        ))
    }
}

/// Whether the file at `path` starts with `prefix`.
fn starts_with(path: &Path, prefix: &[u8]) -> bool {
    let mut head = vec![0; prefix.len()];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| head == prefix)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_path_is_named_with_what_was_expected() {
        let dir = tempfile::tempdir().unwrap();
        let a_file = dir.path().join("f");
        std::fs::write(&a_file, "index,links\n").unwrap();
        let missing = dir.path().join("missing");
        let e = file(&missing, "a scene").unwrap_err().to_string();
        assert!(
            e.ends_with("missing: no such file or folder; expected a scene"),
            "{e}"
        );
        let e = folder(&a_file, "a folder of scenes")
            .unwrap_err()
            .to_string();
        assert!(e.ends_with("f: a file; expected a folder of scenes"), "{e}");
        let e = out_folder(&a_file.join("sub")).unwrap_err().to_string();
        assert!(e.contains("f is a file; expected an output folder"), "{e}");
        assert!(out_folder(&missing.join("sub")).is_ok());
        assert!(sweep_file(&a_file).is_ok());
        let e = mcap_file(&a_file).unwrap_err().to_string();
        assert!(e.contains("not MCAP"), "{e}");
        let e = run_folder(dir.path()).unwrap_err().to_string();
        assert!(e.contains("a folder with no report.json"), "{e}");
    }
}
