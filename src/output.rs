//! Outputs of a run: `samples.csv` (written as the run goes), `report.json`, and the
//! readable summary. Files are written under a temporary name (`.partial`), flushed to disk
//! and renamed when complete, and a finished file of an earlier run into the same folder is
//! removed when a run starts, so a killed run never leaves a file that looks finished. This
//! module does no physics.

pub mod background;
pub mod compare;
pub mod crossing;
pub mod fields;
pub mod files;
pub mod folded;
pub mod folder;
pub mod inspect;
pub mod sci;
pub mod summary;
pub mod table;
pub mod view;

pub use summary::summary;

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use anyhow::Context as _;

use crate::output::fields::fields;
use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;

/// Column names of `samples.csv`, in order: the fields of [`Sample`] as serde names them
/// (see [`fields`](crate::output::fields::fields)).
pub static CSV_COLUMNS: LazyLock<Vec<&'static str>> = LazyLock::new(|| {
    fields(&Sample::default())
        .expect("a sample is a flat record of numbers")
        .into_iter()
        .map(|(name, _)| name)
        .collect()
});

/// `path` as one word of a shell command that a hint prints: as it is when it is made of
/// safe characters, else in single quotes (a `'` in it closed, escaped and reopened), so
/// that the hint works when pasted.
pub fn shell_word(path: &Path) -> String {
    let text = path.display().to_string();
    let safe = |c: char| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c);
    if !text.is_empty() && text.chars().all(safe) {
        text
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

/// Writes `path` atomically: into `path.partial`, flushed to disk, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = partial_path(path);
    let mut file =
        File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    file.write_all(bytes)
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    drop(file);
    fs::rename(&tmp, path).with_context(|| format!("cannot rename to {}", path.display()))?;
    Ok(())
}

/// Removes a finished output left by an earlier run into the same folder, so that a run
/// killed before it finishes leaves only `.partial` files, never an older complete-looking
/// file beside them.
pub fn remove_stale(path: &Path) -> anyhow::Result<()> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot remove the earlier {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// `path` with `.partial` appended to its name: where a file is written until it is complete.
pub(crate) fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// Streams samples into `samples.csv`. A reference past its tabulated end (or a
/// quantity that does not exist in a phase) is an empty cell, never `NaN`.
pub struct CsvObserver {
    path: PathBuf,
    out: Option<csv::Writer<File>>,
    /// One cell's text, reused.
    cell: String,
}

impl CsvObserver {
    /// An observer writing `dir/samples.csv`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join(folder::SAMPLES),
            out: None,
            cell: String::new(),
        }
    }
}

impl Observer for CsvObserver {
    fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
        remove_stale(&self.path)?;
        let tmp = partial_path(&self.path);
        let file =
            File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut out = csv::Writer::from_writer(file);
        out.write_record(CSV_COLUMNS.iter())
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        self.out = Some(out);
        Ok(())
    }

    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        let Some(out) = self.out.as_mut() else {
            return Ok(());
        };
        // Every number as `{:.9e}`; an empty cell where it is not finite (a reference past
        // its end, a quantity its phase does not have).
        let written = fields(sample)?.into_iter().try_for_each(|(_, v)| {
            self.cell.clear();
            if v.is_finite() {
                sci::push_sci9(&mut self.cell, v);
            }
            out.write_field(&self.cell)
        });
        written
            .and_then(|()| out.write_record(None::<&[u8]>))
            .with_context(|| format!("cannot write {}", partial_path(&self.path).display()))?;
        Ok(())
    }

    fn observe_final(&mut self, _report: &RunReport) -> anyhow::Result<()> {
        if let Some(out) = self.out.take() {
            let file = out
                .into_inner()
                .map_err(|e| e.into_error())
                .with_context(|| format!("cannot write {}", self.path.display()))?;
            file.sync_all()
                .with_context(|| format!("cannot write {}", self.path.display()))?;
            drop(file);
            fs::rename(partial_path(&self.path), &self.path)
                .with_context(|| format!("cannot rename to {}", self.path.display()))?;
        }
        Ok(())
    }
}

/// Writes `report.json` at the end of the run: the [`RunReport`], the run's id and the
/// stamp (size and hash) of the `samples.csv` beside it, if any (see [`folder`]). Put it
/// after the CSV observer, which finishes `samples.csv` first.
pub struct ReportObserver {
    path: PathBuf,
    run_id: String,
}

impl ReportObserver {
    /// An observer writing `dir/report.json`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join(folder::REPORT),
            run_id: String::new(),
        }
    }
}

impl Observer for ReportObserver {
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()> {
        self.run_id = folder::run_id(&scene.name, &scene.source_text);
        remove_stale(&self.path)
    }
    fn observe_sample(&mut self, _sample: &Sample) -> anyhow::Result<()> {
        Ok(())
    }
    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()> {
        /// `report.json`: the report, then the run's id and the files it was written with.
        #[derive(serde::Serialize)]
        struct Written<'a> {
            #[serde(flatten)]
            report: &'a RunReport,
            run_id: &'a str,
            files: std::collections::BTreeMap<&'static str, folder::FileStamp>,
        }
        let samples = self.path.with_file_name(folder::SAMPLES);
        let mut files = std::collections::BTreeMap::new();
        if samples.exists() {
            files.insert(folder::SAMPLES, folder::FileStamp::of(&samples)?);
        }
        let written = Written {
            report,
            run_id: &self.run_id,
            files,
        };
        let mut text = serde_json::to_string_pretty(&written)?;
        text.push('\n');
        write_atomic(&self.path, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hint's path, pasted into a shell, is the path: spaces, quotes and all.
    #[test]
    fn a_shell_word_reads_back_as_its_path() {
        for path in [
            "runs/yoga-mat",
            "my dir/run.mcap",
            "it's here",
            "a\"b$c`d",
            "",
        ] {
            let word = shell_word(Path::new(path));
            let echoed = std::process::Command::new("sh")
                .arg("-c")
                .arg(format!("printf '%s' {word}"))
                .output()
                .unwrap();
            assert_eq!(String::from_utf8_lossy(&echoed.stdout), path, "{word}");
        }
        assert_eq!(shell_word(Path::new("runs/yoga-mat")), "runs/yoga-mat");
    }
}
