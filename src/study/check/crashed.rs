//! What a run's folder holds after the run was killed (`kill -9`, a crash, a scheduler's
//! SIGKILL), or while it still runs: its `.partial` files and its lock, and no
//! `report.json`. Read, never changed.

use std::fmt::Write as _;
use std::path::Path;

use crate::output::inspect::read_inventory;
use crate::output::{folder, partial_path};

/// A folder whose run did not finish: no `report.json`, and its `.partial` files or its
/// lock. The one test of a killed (or still running) run's folder, for `check` and
/// `check --salvage`.
pub(super) struct Unfinished {
    /// The `.partial` files' names.
    pub(super) partial: Vec<String>,
    /// Who the lock names, and whether a process still holds it.
    pub(super) lock: Option<(String, bool)>,
}

impl Unfinished {
    /// What `dir` holds if its run did not finish; `None` if it has a report, or neither
    /// a partial file nor a lock.
    pub(super) fn of(dir: &Path) -> Option<Self> {
        if dir.join(folder::REPORT).exists() {
            return None;
        }
        let partial: Vec<String> = [folder::SAMPLES, folder::REPORT, folder::LOG]
            .into_iter()
            .map(|name| partial_path(&dir.join(name)))
            .filter(|p| p.exists())
            .map(|p| {
                p.file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        let lock = folder::lock_holder(dir);
        (!partial.is_empty() || lock.is_some()).then_some(Self { partial, lock })
    }

    /// Whether a process still holds the lock: the run is going.
    pub(super) fn running(&self) -> bool {
        self.lock.as_ref().is_some_and(|(_, held)| *held)
    }

    /// Whether its samples were left partial: what a salvage keeps.
    pub(super) fn has_samples(&self) -> bool {
        let name = format!("{}.partial", folder::SAMPLES);
        self.partial.contains(&name)
    }
}

/// What the folder `dir` holds if a run was killed in it (a `.partial` file or a lock, and
/// no `report.json`), a fact a line; `None` if it is not such a folder.
pub fn crashed_run(dir: &Path) -> Option<Vec<String>> {
    let unfinished = Unfinished::of(dir)?;
    let running = unfinished.running();
    let Unfinished { partial, lock } = unfinished;
    let mut lines = vec![format!(
        "{}: no {}; partial files: {}",
        if running {
            "a run still going"
        } else {
            "an interrupted run"
        },
        folder::REPORT,
        if partial.is_empty() {
            "none".to_owned()
        } else {
            partial.join(", ")
        }
    )];
    let samples = partial_path(&dir.join(folder::SAMPLES));
    if samples.exists() {
        lines.push(match complete_rows(&samples) {
            Ok(cut) if cut.rows == 0 => format!("{}.partial: no complete row", folder::SAMPLES),
            Ok(cut) => format!(
                "{}.partial: {} complete rows, up to t = {} s simulated",
                folder::SAMPLES,
                cut.rows,
                super::seconds(cut.t_s)
            ),
            Err(e) => format!("{}.partial: not readable: {e:#}", folder::SAMPLES),
        });
    }
    let log = partial_path(&dir.join(folder::LOG));
    if log.exists() {
        lines.push(match read_inventory(&log) {
            Ok(inv) => {
                let messages: u64 = inv.channels.values().map(|c| c.messages).sum();
                let mut line = format!("{}.partial: readable, {messages} messages", folder::LOG);
                if let Some((_, end)) = inv.time_range_ns {
                    let _ = write!(line, ", up to t = {:.4} s", end as f64 * 1e-9);
                }
                line
            }
            Err(e) => format!("{}.partial: not readable: {e:#}", folder::LOG),
        });
    }
    if let Some((holder, held)) = lock {
        let holder = if holder.is_empty() {
            "it did not say whose".to_owned()
        } else {
            holder
        };
        lines.push(format!(
            ".uncoil.lock: {holder}; {}",
            if held {
                "still held: that process is running"
            } else {
                "stale: its process is gone, and it blocks no new run"
            }
        ));
    }
    if !running && samples.exists() {
        lines.push(format!(
            "to keep what it wrote: uncoil check {} --salvage",
            crate::output::shell_word(dir)
        ));
    }
    Some(lines)
}

/// The complete rows of a cut `samples.csv`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Cut {
    /// The header's columns.
    pub header: Vec<String>,
    /// Complete rows: ended by a newline, with every column, the first a number.
    pub rows: u64,
    /// The simulated time of the last (its first column, `t_s`; 0 with no row).
    pub t_s: f64,
    /// Where the last complete row ends (bytes from the start of the file).
    pub end_byte: u64,
}

/// The complete rows of a cut `samples.csv` (a coil's or a folded chain's: those ended by a
/// newline, with every column), read with the `csv` crate.
pub(super) fn complete_rows(path: &Path) -> anyhow::Result<Cut> {
    let bytes = std::fs::read(path)?;
    let ended = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let mut reader = csv::Reader::from_reader(&bytes[..ended]);
    let header = reader.headers()?.clone();
    anyhow::ensure!(
        header.get(0) == Some("t_s"),
        "its header does not start with t_s"
    );
    let mut cut = Cut {
        header: header.iter().map(str::to_owned).collect(),
        rows: 0,
        t_s: 0.0,
        end_byte: reader.position().byte(),
    };
    let mut record = csv::StringRecord::new();
    while let Ok(true) = reader.read_record(&mut record) {
        match record.get(0).map(str::parse::<f64>) {
            Some(Ok(t_s)) if record.len() == header.len() => {
                cut.rows += 1;
                cut.t_s = t_s;
                cut.end_byte = reader.position().byte();
            }
            _ => break,
        }
    }
    Ok(cut)
}
