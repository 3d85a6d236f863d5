//! `run.mcap`: the view's file sink, the Foxglove SDK's MCAP writer.
//!
//! Metadata records: `scene` (name, file text), `tool` (name, version), `resolution`,
//! `solver`, and at the end `run` (run id, stop reason, steps, times) and `ledger`. No wall time goes
//! in, so a repeated run writes the same bytes.
//!
//! The file is written as `run.mcap.partial` and renamed when finished, so a file named
//! `run.mcap` is always complete. Messages go into zstd-compressed chunks of about 8 MiB
//! (compression starts afresh in each chunk, and a wound coil's drawing, repeated from one
//! drawing to the next, costs its full size once per chunk: the thin tape's log is 12.2 MB
//! in 1 MiB chunks, 10.7 MB in 8 MiB ones, by `ls -l` on two builds that differ in this
//! constant);
//! the writer finishes a chunk by seeking back to its header, which flushes it to the file,
//! so a crash (even a `kill -9`) leaves every completed chunk readable in the `.partial`
//! file (`mcap recover`, or [`crate::output::inspect`], which reads as far as the data goes).

use std::collections::BTreeMap;
use std::fs::{self, File};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context as _;
use foxglove::{Context, McapCompression, McapWriteOptions, McapWriterHandle};

use crate::output::partial_path as partial;
use crate::run::RunReport;
use crate::scene::Scene;

/// Target uncompressed size of a chunk (bytes): the unit that survives a crash.
pub(super) const CHUNK_SIZE: u64 = 8 * 1024 * 1024;

/// An open `run.mcap.partial`, a sink of the run's context.
pub struct McapFile {
    path: PathBuf,
    handle: McapWriterHandle<BufWriter<File>>,
    /// The run's id (`output::folder::run_id`), written into the `run` record.
    run_id: String,
}

fn pairs(pairs: &[(&str, String)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_owned(), v.clone()))
        .collect()
}

/// Flattens a JSON object into `a.b = value` strings, for MCAP metadata.
fn flatten(prefix: &str, value: &serde_json::Value, out: &mut BTreeMap<String, String>) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        serde_json::Value::String(s) => {
            out.insert(prefix.to_owned(), s.clone());
        }
        other => {
            out.insert(prefix.to_owned(), other.to_string());
        }
    }
}

impl McapFile {
    /// Opens `path`'s partial file as a sink of `context` and writes the scene's metadata.
    pub fn create(context: &Arc<Context>, path: &Path, scene: &Scene) -> anyhow::Result<Self> {
        // An earlier run's finished log must not survive beside this run's partial one.
        crate::output::remove_stale(path)?;
        let tmp = partial(path);
        let file =
            File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let options = McapWriteOptions::new()
            .compression(Some(McapCompression::Zstd))
            .chunk_size(Some(CHUNK_SIZE))
            // zstd's fastest level (tools/mcap_cost.sh measures the cost).
            .compression_level(1)
            // Compress on the run's thread: zstd's worker threads made no measurable
            // difference on 2 cores, and spawn none this way.
            .compression_threads(0);
        let handle = context
            .mcap_writer_with_options(options)
            .create(BufWriter::new(file))
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        let version = env!("CARGO_PKG_VERSION");
        let s = &scene.solver;
        for (name, meta) in [
            (
                "scene",
                pairs(&[
                    ("name", scene.name.clone()),
                    ("text", scene.source_text.clone()),
                ]),
            ),
            (
                "tool",
                pairs(&[("name", "uncoil".into()), ("version", version.into())]),
            ),
            (
                "resolution",
                pairs(&[
                    (
                        "links_per_turn",
                        scene.discretisation.links_per_turn.to_string(),
                    ),
                    (
                        "sample_interval_s",
                        scene.output.sample_interval_s.to_string(),
                    ),
                    ("scene_rate_hz", scene.output.scene_rate_hz.to_string()),
                ]),
            ),
            (
                "solver",
                pairs(&[
                    ("engine", "rapier2d-f64 0.36".into()),
                    ("max_dt_s", s.max_dt_s.to_string()),
                    ("steps_per_link", s.steps_per_link.to_string()),
                    ("iterations", s.iterations.to_string()),
                    ("freeze_speed_m_s", s.freeze_speed_m_s.to_string()),
                ]),
            ),
        ] {
            handle
                .write_metadata(name, meta)
                .with_context(|| format!("cannot write {}", tmp.display()))?;
        }
        Ok(Self {
            path: path.to_owned(),
            handle,
            run_id: crate::output::folder::run_id(&scene.name, &scene.source_text),
        })
    }

    /// Writes the run's end (stop reason, counts, the ledger), finishes the file and renames
    /// it to its final name.
    pub fn finish(self, report: &RunReport) -> anyhow::Result<()> {
        let tmp = partial(&self.path);
        // The log's own errors (a full disk while its last chunks are written) name it.
        let write = |e: foxglove::FoxgloveError| {
            anyhow::Error::new(e).context(format!("cannot write {}", tmp.display()))
        };
        self.handle
            .write_metadata(
                "run",
                pairs(&[
                    ("run_id", self.run_id.clone()),
                    ("stop_reason", report.stop.to_string()),
                    ("links", report.links.to_string()),
                    ("steps", report.steps.to_string()),
                    ("sim_time_s", report.sim_time_s.to_string()),
                    // No wall time: it differs from run to run, and a repeated run must write the
                    // same bytes (report.json has it).
                ]),
            )
            .map_err(write)?;
        let mut ledger = BTreeMap::new();
        flatten("", &serde_json::to_value(report.ledger)?, &mut ledger);
        self.handle
            .write_metadata("ledger", ledger)
            .map_err(write)?;
        let out = self.handle.close().map_err(write)?;
        out.into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        fs::rename(&tmp, &self.path)
            .with_context(|| format!("cannot rename to {}", self.path.display()))?;
        Ok(())
    }
}
