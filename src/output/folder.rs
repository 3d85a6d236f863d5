//! A run's output folder, owned by one run at a time: the one place that names a run's
//! files, takes the folder, and says whether the files in it belong together.
//!
//! - **One writer.** A run takes an advisory lock on `DIR/.uncoil.lock` (the standard
//!   library's `File::try_lock`, `flock` on Linux: released by the system when the process
//!   ends, however it ends) and writes into it who holds it. A second run into the same folder
//!   is refused at once, naming the folder and the holder.
//! - **One run's files.** The lock taken, every file an earlier run may have left
//!   (`samples.csv`, `report.json`, `run.mcap`, the pictures of `uncoil plot`, their
//!   `.partial`s) is removed before the run writes anything: the folder is the run's, and an
//!   older file beside a newer one would be read as part of it. Removing rather than refusing
//!   without `--force` keeps a re-run into the same folder, the common case, one command.
//! - **One run id.** The id is derived from what makes the run: the version of `uncoil`, the
//!   scene's name and its text with the overrides. Two runs with the same id write the same
//!   bytes (a run is deterministic), so a repeated run still writes identical files. It goes
//!   into `report.json` (`run_id`) and `run.mcap`'s `run` metadata; `samples.csv` is tied
//!   to it by its size and hash in `report.json` (`files`), which also catch a stopped run's
//!   samples beside a finished run's report.

use std::fs::{self, File, OpenOptions};
use std::io::{Read as _, Write as _};
use std::path::{Path, PathBuf};

use anyhow::Context as _;

/// The samples, streamed.
pub const SAMPLES: &str = "samples.csv";
/// The report, written at the end.
pub const REPORT: &str = "report.json";
/// The Foxglove log.
pub const LOG: &str = "run.mcap";
/// The Foxglove layout, written beside the log (or for a live view) so that the hint a run
/// prints names a file that exists wherever it runs.
pub const LAYOUT: &str = "foxglove-layout.json";
/// The tape's shape through the final bang, which `uncoil plot` draws from a run's log.
pub const BANG_SVG: &str = "bang.svg";
/// The pictures `uncoil plot` draws from a run's files.
pub const PLOTS: [&str; 5] = [
    "motion.svg",
    "energy.svg",
    "approach.svg",
    "forces.svg",
    BANG_SVG,
];
/// The lock file.
const LOCK: &str = ".uncoil.lock";

/// Why a folder could not be taken for a run.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// Another run holds the folder.
    #[error(
        "{} is being written by another run ({holder}); wait for it to end or choose another \
         folder with --out",
        dir.display()
    )]
    Busy {
        /// The folder.
        dir: PathBuf,
        /// Who holds it, as it wrote itself into the lock file.
        holder: String,
    },
    /// The folder or its lock file could not be made or written.
    #[error(transparent)]
    Io(#[from] anyhow::Error),
}

/// A folder taken for one run: locked until this is dropped, emptied of earlier runs' files.
#[derive(Debug)]
pub struct RunFolder {
    dir: PathBuf,
    run_id: String,
    _lock: File,
}

impl RunFolder {
    /// Takes `dir` (created if missing) for the run `run_id` of the scene `scene`.
    pub fn take(dir: &Path, run_id: &str, scene: &str) -> Result<Self, FolderError> {
        fs::create_dir_all(dir)
            .with_context(|| format!("cannot create output folder {}", dir.display()))?;
        let path = dir.join(LOCK);
        let mut lock = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .with_context(|| format!("cannot open the lock file {}", path.display()))?;
        if lock.try_lock().is_err() {
            let holder = fs::read_to_string(&path).unwrap_or_default();
            let holder = holder.trim();
            return Err(FolderError::Busy {
                dir: dir.to_owned(),
                holder: if holder.is_empty() {
                    "it has not said which".to_owned()
                } else {
                    holder.to_owned()
                },
            });
        }
        lock.set_len(0)
            .and_then(|()| {
                writeln!(
                    lock,
                    "run {run_id} of scene {scene}, process {}",
                    std::process::id()
                )
            })
            .with_context(|| format!("cannot write the lock file {}", path.display()))?;
        for name in [SAMPLES, REPORT, LOG, LAYOUT].into_iter().chain(PLOTS) {
            for file in [dir.join(name), crate::output::partial_path(&dir.join(name))] {
                crate::output::remove_stale(&file)?;
            }
        }
        Ok(Self {
            dir: dir.to_owned(),
            run_id: run_id.to_owned(),
            _lock: lock,
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The run's id.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// Gives the folder up before the run wrote anything: `written` (files made for it
    /// already) and the lock file are removed, so no one reads the folder as a run's that
    /// was killed. Best effort: what cannot be removed is left.
    pub fn abandon(self, written: &[&str]) {
        for name in written {
            let _ = fs::remove_file(self.dir.join(name));
        }
        let _ = fs::remove_file(self.dir.join(LOCK));
    }
}

/// Who took `dir`'s lock, as it wrote itself into the lock file, and whether a process
/// still holds it (`false`: stale, its process gone, so it blocks no new run); `None` if
/// the folder has no lock file.
pub fn lock_holder(dir: &Path) -> Option<(String, bool)> {
    let path = dir.join(LOCK);
    let file = OpenOptions::new().read(true).write(true).open(&path).ok()?;
    let held = file.try_lock().is_err();
    drop(file);
    let text = fs::read_to_string(&path).unwrap_or_default();
    Some((text.trim().to_owned(), held))
}

/// The id of a run: FNV-1a (64 bits, the same on every platform) of `uncoil`'s version,
/// the scene's name and its text with the overrides, in hex.
pub fn run_id(scene_name: &str, scene_text: &str) -> String {
    let text = format!("{}\n{scene_name}\n{scene_text}", env!("CARGO_PKG_VERSION"));
    format!("{:016x}", fnv1a(text.as_bytes()))
}

/// FNV-1a's starting value (64 bits).
const FNV1A_START: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a, 64 bits.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_more(FNV1A_START, bytes)
}

/// FNV-1a of what `hash` was taken over, then `bytes`.
fn fnv1a_more(hash: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(hash, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A file as `report.json` names it: its size and FNV-1a hash.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FileStamp {
    /// Size (bytes).
    pub bytes: u64,
    /// FNV-1a of its bytes, in hex.
    pub fnv1a: String,
}

impl FileStamp {
    /// The stamp of the file at `path`, read in blocks (a thin tape's `samples.csv` is
    /// tens of megabytes).
    pub fn of(path: &Path) -> anyhow::Result<Self> {
        let read = || -> std::io::Result<Self> {
            let mut file = File::open(path)?;
            let mut block = vec![0; 1 << 16];
            let (mut bytes, mut hash) = (0u64, FNV1A_START);
            loop {
                let n = file.read(&mut block)?;
                if n == 0 {
                    break;
                }
                bytes += n as u64;
                hash = fnv1a_more(hash, &block[..n]);
            }
            Ok(Self {
                bytes,
                fnv1a: format!("{hash:016x}"),
            })
        };
        read().with_context(|| format!("cannot read {}", path.display()))
    }
}

/// What is wrong with how the files in `dir` belong together: `report.json`'s run id and
/// its stamp of `samples.csv` against the file, and `run.mcap`'s run id, steps and stop
/// reason (when there is one) against the report. Empty for a folder whose files are one
/// run's.
pub fn mismatches(dir: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    let Ok(text) = fs::read_to_string(dir.join(REPORT)) else {
        return problems; // a missing report is reported by the outputs' own check
    };
    let Ok(report) = serde_json::from_str::<serde_json::Value>(&text) else {
        return problems;
    };
    let Some(id) = report.get("run_id").and_then(|v| v.as_str()) else {
        problems.push(format!("{REPORT}: no run_id"));
        return problems;
    };
    match report.pointer("/files/samples.csv") {
        Some(stamp) => {
            let stamp: Option<FileStamp> = serde_json::from_value(stamp.clone()).ok();
            match (stamp, FileStamp::of(&dir.join(SAMPLES))) {
                (Some(want), Ok(got)) if want != got => problems.push(format!(
                    "{SAMPLES} is not the one {REPORT} was written with ({} bytes, FNV-1a \
                     {}; the report says {} bytes, {})",
                    got.bytes, got.fnv1a, want.bytes, want.fnv1a
                )),
                (None, _) => problems.push(format!("{REPORT}: files.samples.csv unreadable")),
                _ => {}
            }
        }
        None => problems.push(format!("{REPORT}: no files.samples.csv")),
    }
    let log = dir.join(LOG);
    if log.exists() {
        match crate::output::inspect::read_inventory(&log) {
            Ok(inv) => {
                let run = inv.metadata.get("run");
                let field = |k: &str| run.and_then(|m| m.get(k)).map(String::as_str);
                if field("run_id") != Some(id) {
                    problems.push(format!(
                        "{LOG} belongs to run {}, {REPORT} to run {id}",
                        field("run_id").unwrap_or("(none)")
                    ));
                }
                let steps = report.get("steps").map(ToString::to_string);
                if field("steps").map(str::to_owned) != steps {
                    problems.push(format!(
                        "{LOG} ends after {} steps, {REPORT} after {}",
                        field("steps").unwrap_or("(none)"),
                        steps.as_deref().unwrap_or("(none)")
                    ));
                }
            }
            Err(e) => problems.push(format!("{LOG}: {e:#}")),
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stamp_read_in_blocks_is_the_hash_of_the_whole_file() {
        // Several blocks and a part of one, so that the blocks' joins are crossed.
        let bytes: Vec<u8> = (0..200_003_u32).map(|i| (i * 7 % 251) as u8).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("samples.csv");
        fs::write(&path, &bytes).unwrap();
        let stamp = FileStamp::of(&path).unwrap();
        assert_eq!(stamp.bytes, bytes.len() as u64);
        assert_eq!(stamp.fnv1a, format!("{:016x}", fnv1a(&bytes)));
    }
}
