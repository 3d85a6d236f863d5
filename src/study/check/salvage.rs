//! `uncoil check DIR --salvage`: turns what a killed run left (`kill -9`, a crash, a
//! scheduler's SIGKILL after its grace time) into sound files under their final names.
//!
//! - `samples.csv.partial` is cut after its last complete row (read with the `csv` crate, as
//!   every reader of the file reads it) and renamed `samples.csv`: every row it keeps is a
//!   row the run wrote, byte for byte.
//! - `run.mcap.partial` is read as far as its data goes (every chunk the run finished; the
//!   writer flushes each), and its header, metadata and messages are written into a new,
//!   finished `run.mcap` with a summary, plus a `run` record naming the salvage. A log that
//!   does not read at all is left in place and named as lost.
//! - `report.json` is a [`SalvageReport`] (`kind = "salvaged"`): the run id, the scene, how
//!   far the samples go, what was lost, and the stamp of `samples.csv`, so that
//!   `uncoil check DIR` verifies the folder as any other run's.
//!
//! Nothing is simulated again and no number is made up: the ledger, the bang and the
//! references, which a run books at its end, are absent, and the report says so.

use std::collections::BTreeMap;
use std::fs::{self, File};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use mcap::records::Record;

use crate::output::folder::{self, FileStamp};
use crate::output::{CSV_COLUMNS, partial_path, write_atomic};
use crate::scene::folded;

use super::crashed::{Cut, Unfinished};

/// The `kind` of a salvaged run's `report.json`.
pub const KIND: &str = "salvaged";

/// The stop reason a salvaged log's `run` record and report carry.
pub const STOP_REASON: &str = "killed: salvaged by uncoil check --salvage";

/// A salvaged run's `report.json`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SalvageReport {
    /// Always [`KIND`].
    pub kind: String,
    /// The killed run's id, from its lock file or its log's scene record.
    pub run_id: String,
    /// The scene's name.
    pub scene_name: String,
    /// The scene's text with its overrides, from the log (`None` when the run wrote no
    /// log, as a folded chain's does not, or when the log did not read).
    pub scene_text: Option<String>,
    /// Whose columns `samples.csv` has: `coil` or `folded-chain`.
    pub samples_of: String,
    /// Why the run ended: [`STOP_REASON`].
    pub stop_reason: String,
    /// The complete rows kept in `samples.csv`.
    pub rows: u64,
    /// The simulated time of the last of them (s).
    pub t_s: f64,
    /// The messages kept in `run.mcap` (`None`: no log was kept).
    pub log_messages: Option<u64>,
    /// What could not be kept, a fact a line; every run's ledger, bang and references
    /// among them, which a run books only at its end.
    pub lost: Vec<String>,
    /// The files, as a finished run's `report.json` names them.
    pub files: BTreeMap<String, FileStamp>,
}

/// Why a folder could not be salvaged.
#[derive(Debug, thiserror::Error)]
pub enum SalvageError {
    /// Not a killed run's folder: a finished run's, a folder with no run, or a run still
    /// going. Nothing was changed.
    #[error("{0}")]
    NotKilled(String),
    /// A killed run's folder with nothing to keep. Nothing was changed.
    #[error("{0}")]
    Nothing(String),
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] anyhow::Error),
}

/// What a salvage kept.
#[derive(Debug, Clone)]
pub struct Salvaged {
    /// The report written.
    pub report: SalvageReport,
    /// The files under their final names.
    pub written: Vec<PathBuf>,
}

/// Salvages the killed run in `dir` (see the module's documentation).
pub fn salvage(dir: &Path) -> Result<Salvaged, SalvageError> {
    let holder = killed_run(dir)?;
    let samples = partial_path(&dir.join(folder::SAMPLES));
    let (cut, samples_of) = complete_samples(&samples)?;
    let log = partial_path(&dir.join(folder::LOG));
    let read_log = log.exists().then(|| read_log(&log));
    let (run_id, scene_name, scene_text) = identify(dir, &holder, read_log.as_ref())?;
    let mut lost = vec![
        "the ledger, the final bang and the references: a run books them at its end".to_owned(),
    ];
    // The log first: the samples' rename is what marks the folder salvaged.
    let mut written = Vec::new();
    let log_messages = match read_log {
        Some(Ok(l)) => {
            let path = dir.join(folder::LOG);
            let (messages, end_s) = write_log(&l, &path, &run_id, cut.t_s)?;
            fs::remove_file(&log).with_context(|| format!("cannot remove {}", log.display()))?;
            written.push(path);
            lost.push(match end_s {
                Some(end) => format!(
                    "the log's messages after t = {end} s: the chunk being written when the \
                     run was killed (the log writes its messages in chunks of 8 MiB)"
                ),
                None => "the log's messages: the run was killed before the log finished its \
                         first chunk (it writes its messages in chunks of 8 MiB)"
                    .to_owned(),
            });
            Some(messages)
        }
        Some(Err(e)) => {
            let shown = log.display();
            lost.push(format!("{shown}: left as it is, it does not read: {e:#}"));
            None
        }
        // A salvage cut short after its log was written: that log is the one kept.
        None => crate::output::inspect::read_inventory(&dir.join(folder::LOG))
            .ok()
            .filter(|inv| {
                inv.metadata.get("run").and_then(|m| m.get("stop_reason"))
                    == Some(&STOP_REASON.to_owned())
            })
            .map(|inv| inv.channels.values().map(|c| c.messages).sum()),
    };
    let final_samples = keep_samples(&samples, &cut, dir)?;
    let report = SalvageReport {
        kind: KIND.to_owned(),
        run_id,
        scene_name,
        scene_text,
        samples_of: samples_of.to_owned(),
        stop_reason: STOP_REASON.to_owned(),
        rows: cut.rows,
        t_s: cut.t_s,
        log_messages,
        lost,
        files: [(folder::SAMPLES.to_owned(), FileStamp::of(&final_samples)?)].into(),
    };
    let text = serde_json::to_string_pretty(&report).context("cannot write the report")?;
    let path = dir.join(folder::REPORT);
    write_atomic(&path, text.as_bytes())?;
    written.insert(0, final_samples);
    written.push(path);
    Ok(Salvaged { report, written })
}

/// Whether `dir` is a killed run's folder: no report, no process holding its lock, a
/// `samples.csv.partial`. Returns what its lock file says (empty if it has none).
fn killed_run(dir: &Path) -> Result<String, SalvageError> {
    let shown = dir.display();
    if describe(dir).is_some() {
        return Err(SalvageError::NotKilled(format!(
            "{shown} was salvaged already: `uncoil check {}` says what it holds",
            crate::output::shell_word(dir)
        )));
    }
    if dir.join(folder::REPORT).exists() {
        return Err(SalvageError::NotKilled(format!(
            "{shown} has a {}: its run ended, and there is nothing to salvage",
            folder::REPORT
        )));
    }
    let unfinished = Unfinished::of(dir);
    if let Some(u) = &unfinished
        && u.running()
    {
        let holder = u.lock.as_ref().map_or("", |(h, _)| h.as_str());
        return Err(SalvageError::NotKilled(format!(
            "{shown}: a run still writes it ({holder}); salvage it once that process is gone"
        )));
    }
    match unfinished {
        Some(u) if u.has_samples() => Ok(u.lock.map(|(h, _)| h).unwrap_or_default()),
        _ => Err(SalvageError::NotKilled(format!(
            "{shown} holds no {}.partial: not a killed run's folder",
            folder::SAMPLES
        ))),
    }
}

/// The complete rows of a killed run's `samples` and whose columns they have (`coil` or
/// `folded-chain`); none, or foreign columns, is nothing to keep.
fn complete_samples(samples: &Path) -> Result<(Cut, &'static str), SalvageError> {
    let cut = super::crashed::complete_rows(samples)?;
    if cut.rows == 0 {
        return Err(SalvageError::Nothing(format!(
            "{}: no complete row: the run was killed before its first sample, and there is \
             nothing to salvage",
            samples.display()
        )));
    }
    let samples_of = if cut.header.iter().eq(CSV_COLUMNS.iter()) {
        "coil"
    } else if cut.header == super::chain_columns() {
        folded::KIND
    } else {
        return Err(SalvageError::Nothing(format!(
            "{}: its header is neither a coil's nor a folded chain's columns",
            samples.display()
        )));
    };
    Ok((cut, samples_of))
}

/// The run's id, its scene's name and text: the id from the lock file (the scene's text
/// and its name from the log, else the name from the lock), else made from the log's scene.
fn identify(
    dir: &Path,
    holder: &str,
    log: Option<&anyhow::Result<ReadLog>>,
) -> Result<(String, String, Option<String>), SalvageError> {
    let (scene_name, scene_text) = match log {
        Some(Ok(l)) => (l.scene.get("name").cloned(), l.scene.get("text").cloned()),
        _ => (None, None),
    };
    let (lock_id, lock_scene) = parse_holder(holder);
    let scene_name = scene_name.or(lock_scene).unwrap_or_default();
    let run_id = match (lock_id, &scene_text) {
        (Some(id), _) => id,
        (None, Some(text)) => folder::run_id(&scene_name, text),
        (None, None) => {
            return Err(SalvageError::Nothing(format!(
                "{}: neither its lock file nor its log names the run",
                dir.display()
            )));
        }
    };
    Ok((run_id, scene_name, scene_text))
}

/// Cuts `samples` after its last complete row and renames it `dir/samples.csv`.
fn keep_samples(samples: &Path, cut: &Cut, dir: &Path) -> anyhow::Result<PathBuf> {
    let file = fs::OpenOptions::new()
        .write(true)
        .open(samples)
        .with_context(|| format!("cannot open {}", samples.display()))?;
    file.set_len(cut.end_byte)
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot cut {}", samples.display()))?;
    drop(file);
    let kept = dir.join(folder::SAMPLES);
    fs::rename(samples, &kept).with_context(|| format!("cannot rename {}", samples.display()))?;
    Ok(kept)
}

/// One line on a salvaged run's folder (`None` for any other): how far its files go.
pub fn describe(dir: &Path) -> Option<String> {
    let text = fs::read_to_string(dir.join(folder::REPORT)).ok()?;
    let r: SalvageReport = serde_json::from_str(&text).ok()?;
    (r.kind == KIND).then(|| {
        format!(
            "a killed run, salvaged: {} rows of samples up to t = {} s simulated, {}; no \
             ledger, bang or references (a run books them at its end)",
            r.rows,
            super::seconds(r.t_s),
            r.log_messages.map_or_else(
                || "no log".to_owned(),
                |m| format!("{m} messages in {}", folder::LOG)
            )
        )
    })
}

/// The run id and scene name a lock file's text names (`run ID of scene NAME, process N`).
fn parse_holder(text: &str) -> (Option<String>, Option<String>) {
    let Some(rest) = text.strip_prefix("run ") else {
        return (None, None);
    };
    let Some((id, rest)) = rest.split_once(" of scene ") else {
        return (None, None);
    };
    let scene = rest.rsplit_once(", process ").map_or(rest, |(s, _)| s);
    (Some(id.to_owned()), Some(scene.to_owned()))
}

/// A cut log, read as far as its data goes.
struct ReadLog {
    bytes: Vec<u8>,
    profile: String,
    library: String,
    /// Its metadata records, in the order written.
    metadata: Vec<mcap::records::Metadata>,
    scene: BTreeMap<String, String>,
}

fn read_log(path: &Path) -> anyhow::Result<ReadLog> {
    let bytes = fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    anyhow::ensure!(
        bytes.starts_with(mcap::MAGIC),
        "not an MCAP file (it does not start with the MCAP magic bytes)"
    );
    let (mut profile, mut library, mut metadata) = (String::new(), String::new(), Vec::new());
    for record in mcap::read::LinearReader::new(&bytes).context("not an MCAP file")? {
        match record {
            Ok(Record::Header(h)) => (profile, library) = (h.profile, h.library),
            Ok(Record::Metadata(m)) => metadata.push(m),
            Ok(_) => {}
            Err(_) => break,
        }
    }
    let scene = metadata
        .iter()
        .find(|m| m.name == "scene")
        .map(|m| m.metadata.clone())
        .unwrap_or_default();
    Ok(ReadLog {
        bytes,
        profile,
        library,
        metadata,
        scene,
    })
}

/// Writes `log`'s metadata and every message that reads into a finished file at `path`
/// (through `path.salvage`: `path.partial` is the log read), with a `run` record for the
/// salvage; returns the messages kept and the last one's time (s).
fn write_log(
    log: &ReadLog,
    path: &Path,
    run_id: &str,
    t_s: f64,
) -> anyhow::Result<(u64, Option<f64>)> {
    let tmp = path.with_extension("mcap.salvage");
    let name = tmp.display();
    let out = File::create(&tmp).with_context(|| format!("cannot create {name}"))?;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile(log.profile.clone())
        .library(log.library.clone())
        .create(BufWriter::new(out))
        .with_context(|| format!("cannot write {name}"))?;
    for m in log.metadata.iter().filter(|m| m.name != "run") {
        w.write_metadata(m)
            .with_context(|| format!("cannot write {name}"))?;
    }
    let (mut messages, mut end_ns) = (0, None);
    for message in mcap::MessageStream::new(&log.bytes)? {
        let Ok(message) = message else { break };
        w.write(&message)
            .with_context(|| format!("cannot write {name}"))?;
        messages += 1;
        end_ns = end_ns.max(Some(message.log_time));
    }
    let run = [
        ("run_id", run_id.to_owned()),
        ("stop_reason", STOP_REASON.to_owned()),
        ("sim_time_s", t_s.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v))
    .collect();
    w.write_metadata(&mcap::records::Metadata {
        name: "run".to_owned(),
        metadata: run,
    })
    .and_then(|()| w.finish().map(|_| ()))
    .with_context(|| format!("cannot write {name}"))?;
    w.into_inner()
        .into_inner()
        .map_err(|e| e.into_error())
        .and_then(|f| f.sync_all())
        .with_context(|| format!("cannot write {name}"))?;
    fs::rename(&tmp, path).with_context(|| format!("cannot rename to {}", path.display()))?;
    Ok((messages, end_ns.map(|ns| ns as f64 * 1e-9)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lock_names_its_run_and_scene() {
        assert_eq!(
            parse_holder("run 00ab of scene yoga mat, process 12"),
            (Some("00ab".to_owned()), Some("yoga mat".to_owned()))
        );
        assert_eq!(parse_holder(""), (None, None));
        assert_eq!(parse_holder("someone"), (None, None));
    }

    /// A killed coil's folder, made by hand: a cut samples file and a lock, no log.
    fn killed(dir: &Path, samples: &str) {
        let held = folder::RunFolder::take(dir, "00cafe", "hand").unwrap();
        drop(held);
        fs::write(partial_path(&dir.join(folder::SAMPLES)), samples).unwrap();
    }

    fn row(t: &str) -> String {
        let mut v = vec![t.to_owned()];
        v.resize(CSV_COLUMNS.len(), "1.5".to_owned());
        v.join(",")
    }

    #[test]
    fn a_cut_row_is_dropped_and_the_folder_then_checks_sound() {
        let dir = tempfile::tempdir().unwrap();
        let header = CSV_COLUMNS.join(",");
        let (a, b) = (row("0.1"), row("0.2"));
        killed(dir.path(), &format!("{header}\n{a}\n{b}\n0.3,1.5,1."));
        // An earlier log that is not a salvage's is not counted as this one's.
        fs::write(dir.path().join(folder::LOG), "not a log").unwrap();
        let s = salvage(dir.path()).unwrap();
        assert_eq!(s.report.log_messages, None);
        fs::remove_file(dir.path().join(folder::LOG)).unwrap();
        assert_eq!((s.report.rows, s.report.t_s), (2, 0.2));
        assert_eq!(s.report.run_id, "00cafe");
        assert_eq!(s.report.samples_of, "coil");
        let kept = fs::read_to_string(dir.path().join(folder::SAMPLES)).unwrap();
        assert_eq!(kept, format!("{header}\n{a}\n{b}\n"));
        assert_eq!(
            super::super::verify_outputs(dir.path()),
            Vec::<String>::new()
        );
        // Salvaged once, it is a run that ended.
        assert!(matches!(
            salvage(dir.path()),
            Err(SalvageError::NotKilled(_))
        ));
    }

    #[test]
    fn a_folded_chains_samples_are_kept_as_a_chains() {
        let dir = tempfile::tempdir().unwrap();
        let columns = super::super::chain_columns();
        let row = vec!["0.25"; columns.len()].join(",");
        killed(
            dir.path(),
            &format!("{}\n{row}\n{row}\n0.5", columns.join(",")),
        );
        let s = salvage(dir.path()).unwrap();
        assert_eq!(s.report.samples_of, folded::KIND);
        assert_eq!(
            (s.report.rows, s.report.t_s, s.report.log_messages),
            (2, 0.25, None)
        );
        assert_eq!(
            super::super::verify_outputs(dir.path()),
            Vec::<String>::new()
        );
    }

    #[test]
    fn nothing_to_keep_and_no_run_are_refused_and_change_nothing() {
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(
            salvage(dir.path()),
            Err(SalvageError::NotKilled(_))
        ));
        let header = CSV_COLUMNS.join(",");
        killed(dir.path(), &format!("{header}\n0.1,2"));
        assert!(matches!(salvage(dir.path()), Err(SalvageError::Nothing(_))));
        let left = fs::read_to_string(partial_path(&dir.path().join(folder::SAMPLES))).unwrap();
        assert_eq!(left, format!("{header}\n0.1,2"));
        assert!(!dir.path().join(folder::REPORT).exists());
    }
}
