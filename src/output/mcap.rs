//! `run.mcap`: every run as an MCAP log that Foxglove (or Lichtblick) opens as it is. It
//! turns samples, frames and events into JSON messages stamped with simulation time; it does
//! no physics and reads nothing back (see [`crate::output::inspect`]).
//!
//! Channels, all JSON-encoded with a `jsonschema` schema:
//! - `/scene`: `foxglove.SceneUpdate`, schema text vendored unchanged from the npm package
//!   `@foxglove/schemas` 2.1.0 (`schemas/foxglove/`). Entities in frame `world`, metres,
//!   x along the floor and y up: `floor` (a cube under `y = 0`), `tape/off_coil` and
//!   `tape/on_coil` (one line strip each, through the link nodes, as thick as the tape),
//!   `ghost/eq7` (the coil of eq. 7: a circle with a spoke showing its rotation) and
//!   `ghost/exact` (the exact-geometry model's wound spiral), each in its own colour. Every
//!   message carries every entity, so a seek redraws the whole scene from one message; a
//!   ghost past its reference's end is deleted. Coordinates are rounded to 1 µm; the tape
//!   off the coil keeps only the nodes that stand out by more than b/20 from a straight run
//!   (the flat laid tape becomes a few segments), and a line has at most 2048 points (a
//!   thin tape's thousands of wound links are then drawn through every k-th node).
//! - `/state`: one message per sample with the fields of `samples.csv` (schema
//!   `uncoil.State`, `schemas/uncoil.State.json`); a reference past its end is left out.
//! - `/events`: detaches (one message per step that shed links, normally one link), the
//!   start and the end of the final bang with its energies, warnings (schema `uncoil.Event`).
//! - `/tf`: `foxglove.FrameTransforms` (official schema, vendored likewise), one with each
//!   drawing: the frame `contact` at the simulation's contact line on the floor, so that a
//!   3D view following it keeps the coil in sight along the 2 m of a yoga mat.
//!
//! Metadata records: `scene` (name, file text), `tool` (name, version), `resolution`,
//! `solver`, and at the end `run` (stop reason, steps, times) and `ledger`.
//!
//! The file is written as `run.mcap.partial` and renamed when finished, so a file named
//! `run.mcap` is always complete. Messages go into zstd-compressed chunks of about 1 MiB;
//! the writer finishes a chunk by seeking back to its header, which flushes it to the file,
//! so a crash (even a `kill -9`) leaves every completed chunk readable in the `.partial`
//! file (`mcap recover`, or [`crate::output::inspect`], which reads as far as the data goes).

use std::collections::BTreeMap;
use std::fs::{self, File};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions, Writer};
use serde::Serialize;

use crate::run::frame::{Event, Frame};
use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;
use foxglove::*;
use paint::*;

mod foxglove;
mod paint;

/// The official `foxglove.SceneUpdate` JSON schema (npm `@foxglove/schemas` 2.1.0).
pub const SCENE_UPDATE_SCHEMA: &str = include_str!("../../schemas/foxglove/SceneUpdate.json");
/// The official `foxglove.FrameTransforms` JSON schema (npm `@foxglove/schemas` 2.1.0).
pub const FRAME_TRANSFORMS_SCHEMA: &str =
    include_str!("../../schemas/foxglove/FrameTransforms.json");
/// The JSON schema of `/state` messages.
pub const STATE_SCHEMA: &str = include_str!("../../schemas/uncoil.State.json");
/// The JSON schema of `/events` messages.
pub const EVENT_SCHEMA: &str = include_str!("../../schemas/uncoil.Event.json");

/// Topic of the scene drawings.
pub const SCENE_TOPIC: &str = "/scene";
/// Topic of the samples.
pub const STATE_TOPIC: &str = "/state";
/// Topic of the events.
pub const EVENTS_TOPIC: &str = "/events";
/// Topic of the frame transforms.
pub const TF_TOPIC: &str = "/tf";

/// Target uncompressed size of a chunk (bytes): the unit that survives a crash.
const CHUNK_SIZE: u64 = 1024 * 1024;

/// Simulation time in nanoseconds, the MCAP log and publish time.
fn stamp_ns(t_s: f64) -> u64 {
    // Times are >= 0 and far below 2^64 ns (584 years).
    (t_s.max(0.0) * 1e9).round() as u64
}

/// Writes `dir/run.mcap`.
pub struct McapObserver {
    path: PathBuf,
    state: Option<Open>,
}

/// The channels, in the order of `Open::channels`.
#[derive(Clone, Copy)]
enum Channel {
    Scene,
    State,
    Events,
    Tf,
}

struct Open {
    writer: Writer<BufWriter<File>>,
    /// MCAP channel ids, indexed by [`Channel`].
    channels: [u16; 4],
    /// Next sequence number of each channel.
    sequence: [u32; 4],
    painter: Painter,
}

impl McapObserver {
    /// An observer writing `dir/run.mcap`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join("run.mcap"),
            state: None,
        }
    }

    /// Where the finished file goes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn partial(&self) -> PathBuf {
        let mut name = self.path.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        self.path.with_file_name(name)
    }

    fn write(&mut self, channel: Channel, t_s: f64, data: &[u8]) -> anyhow::Result<()> {
        let Some(open) = self.state.as_mut() else {
            return Ok(());
        };
        let which = channel as usize;
        let channel_id = open.channels[which];
        let sequence = open.sequence[which];
        open.sequence[which] += 1;
        let ns = stamp_ns(t_s);
        open.writer.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence,
                log_time: ns,
                publish_time: ns,
            },
            data,
        )?;
        Ok(())
    }
}

/// A sample as a `/state` message: a quantity that does not exist (a reference past its
/// end, `NaN` in the sample, an empty CSV cell) is left out rather than written as `null`,
/// which Foxglove Studio's JSON-schema reader does not accept as a number type.
fn state_message(sample: &Sample) -> anyhow::Result<Vec<u8>> {
    let data = serde_json::to_vec(sample)?;
    // The common case, every quantity present, is written directly.
    if !data.windows(4).any(|w| w == b"null") {
        return Ok(data);
    }
    let mut value = serde_json::to_value(sample)?;
    if let Some(map) = value.as_object_mut() {
        map.retain(|_, v| !v.is_null());
    }
    Ok(serde_json::to_vec(&value)?)
}

fn metadata(name: &str, pairs: &[(&str, String)]) -> Metadata {
    Metadata {
        name: name.into(),
        metadata: pairs
            .iter()
            .map(|(k, v)| ((*k).to_owned(), v.clone()))
            .collect(),
    }
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

impl Observer for McapObserver {
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()> {
        // An earlier run's finished log must not survive beside this run's partial one.
        crate::output::remove_stale(&self.path)?;
        let tmp = self.partial();
        let file =
            File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let version = env!("CARGO_PKG_VERSION");
        let mut writer = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .chunk_size(Some(CHUNK_SIZE))
            // zstd's fastest level: on the yoga mat it writes a smaller file than the
            // default level and costs a third less time (tools/mcap_cost.sh).
            .compression_level(1)
            // Compress on the run's thread: zstd's worker threads made no measurable
            // difference on 2 cores (tools/mcap_cost.sh), and spawn none this way.
            .compression_threads(0)
            .library(format!("uncoil {version}"))
            .create(BufWriter::new(file))?;
        writer.write_metadata(&metadata(
            "scene",
            &[
                ("name", scene.name.clone()),
                ("text", scene.source_text.clone()),
            ],
        ))?;
        writer.write_metadata(&metadata(
            "tool",
            &[("name", "uncoil".into()), ("version", version.into())],
        ))?;
        writer.write_metadata(&metadata(
            "resolution",
            &[
                (
                    "links_per_turn",
                    scene.discretisation.links_per_turn.to_string(),
                ),
                (
                    "sample_interval_s",
                    scene.output.sample_interval_s.to_string(),
                ),
                ("scene_rate_hz", scene.output.scene_rate_hz.to_string()),
            ],
        ))?;
        let s = &scene.solver;
        writer.write_metadata(&metadata(
            "solver",
            &[
                ("engine", "rapier2d-f64 0.36".into()),
                ("max_dt_s", s.max_dt_s.to_string()),
                ("steps_per_link", s.steps_per_link.to_string()),
                ("iterations", s.iterations.to_string()),
                ("freeze_speed_m_s", s.freeze_speed_m_s.to_string()),
            ],
        ))?;
        // Schemas and channels go into the first chunk, beside the first messages: written
        // before the metadata, they would fill a chunk of their own, without messages and
        // so without message indexes, which Foxglove Studio refuses to read.
        let no_meta = BTreeMap::new();
        let scene_schema = writer.add_schema(
            "foxglove.SceneUpdate",
            "jsonschema",
            SCENE_UPDATE_SCHEMA.as_bytes(),
        )?;
        let state_schema =
            writer.add_schema("uncoil.State", "jsonschema", STATE_SCHEMA.as_bytes())?;
        let event_schema =
            writer.add_schema("uncoil.Event", "jsonschema", EVENT_SCHEMA.as_bytes())?;
        let tf_schema = writer.add_schema(
            "foxglove.FrameTransforms",
            "jsonschema",
            FRAME_TRANSFORMS_SCHEMA.as_bytes(),
        )?;
        let scene_ch = writer.add_channel(scene_schema, SCENE_TOPIC, "json", &no_meta)?;
        let state_ch = writer.add_channel(state_schema, STATE_TOPIC, "json", &no_meta)?;
        let events_ch = writer.add_channel(event_schema, EVENTS_TOPIC, "json", &no_meta)?;
        let tf_ch = writer.add_channel(tf_schema, TF_TOPIC, "json", &no_meta)?;

        self.state = Some(Open {
            writer,
            channels: [scene_ch, state_ch, events_ch, tf_ch],
            sequence: [0; 4],
            painter: Painter::new(scene),
        });
        Ok(())
    }

    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        let data = state_message(sample)?;
        self.write(Channel::State, sample.t_s, &data)
    }

    fn wants_frames(&self) -> bool {
        true
    }

    fn observe_frame(&mut self, frame: &Frame) -> anyhow::Result<()> {
        let Some(open) = self.state.as_mut() else {
            return Ok(());
        };
        let data = serde_json::to_vec(&open.painter.paint(frame))?;
        let tf = serde_json::to_vec(&contact_transform(frame))?;
        self.write(Channel::Scene, frame.t_s, &data)?;
        self.write(Channel::Tf, frame.t_s, &tf)
    }

    fn observe_event(&mut self, event: &Event) -> anyhow::Result<()> {
        let data = serde_json::to_vec(event)?;
        self.write(Channel::Events, event.t_s(), &data)
    }

    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()> {
        let Some(mut open) = self.state.take() else {
            return Ok(());
        };
        open.writer.write_metadata(&metadata(
            "run",
            &[
                ("stop_reason", report.stop.to_string()),
                ("links", report.links.to_string()),
                ("steps", report.steps.to_string()),
                ("sim_time_s", report.sim_time_s.to_string()),
                // No wall time: it differs from run to run, and a repeated run must write the
                // same bytes (report.json has it).
            ],
        ))?;
        let mut ledger = BTreeMap::new();
        flatten("", &serde_json::to_value(report.ledger)?, &mut ledger);
        open.writer.write_metadata(&Metadata {
            name: "ledger".into(),
            metadata: ledger,
        })?;
        open.writer.finish()?;
        let mut out = open.writer.into_inner();
        std::io::Write::flush(&mut out)?;
        drop(out);
        fs::rename(self.partial(), &self.path)
            .with_context(|| format!("cannot rename to {}", self.path.display()))?;
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// foxglove.SceneUpdate, the parts used here. Field names and required fields follow the
// vendored schema; `tests` validates a painted frame's shape against it.

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        Scene::from_toml_str(
            "[tape]\nouter_radius_m = 0.02\nthickness_m = 0.004\nmass_kg = 0.2\n\
             [push]\ncontact_speed_m_s = 0.3\n[discretisation]\nlinks_per_turn = 8\n",
            "small",
        )
        .expect("valid scene")
    }

    #[test]
    fn schema_properties_are_the_csv_columns_in_order() {
        let schema: serde_json::Value = serde_json::from_str(STATE_SCHEMA).unwrap();
        let props: Vec<&str> = schema["properties"]
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut sorted = crate::output::CSV_COLUMNS.to_vec();
        sorted.sort_unstable();
        // serde_json's map is sorted (no preserve_order feature): compare as sets.
        assert_eq!(props, sorted);
        // Every simulated quantity is required; a reference may be absent past its end.
        let required: Vec<&str> = schema["required"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        let refs = crate::output::CSV_COLUMNS
            .iter()
            .filter(|c| !required.contains(c))
            .count();
        assert_eq!(
            refs, 33,
            "optional: r_ref..friction_ref, the exact model, r_ft, the valid reference, theta, \
             the forces and torques on the moving part (none after the release) and the exact model's"
        );
    }

    #[test]
    fn schema_properties_match_the_sample_field_by_field() {
        // The schema's properties, in the order its text lists them, are the sample's
        // fields in declaration order; each has the type its value serialises to and a
        // description.
        let schema: serde_json::Value = serde_json::from_str(STATE_SCHEMA).unwrap();
        let props = &schema["properties"];
        let as_json = serde_json::to_value(Sample::default()).unwrap();
        let mut last = 0;
        for name in crate::output::CSV_COLUMNS.iter() {
            let at = STATE_SCHEMA
                .find(&format!("\"{name}\": {{"))
                .unwrap_or_else(|| panic!("{name} is not a property of uncoil.State"));
            assert!(at > last, "{name} is out of order in uncoil.State");
            last = at;
            let want = if as_json[name].is_u64() {
                "integer"
            } else {
                "number"
            };
            assert_eq!(props[name]["type"], want, "{name}");
            assert!(
                props[name]["description"]
                    .as_str()
                    .is_some_and(|d| !d.is_empty()),
                "{name} has no description"
            );
        }
    }

    #[test]
    fn vendored_scene_schema_is_foxglove_scene_update() {
        let schema: serde_json::Value = serde_json::from_str(SCENE_UPDATE_SCHEMA).unwrap();
        assert_eq!(schema["title"], "foxglove.SceneUpdate");
    }

    #[test]
    fn painted_entities_carry_every_required_field() {
        // The required fields of an entity, from the vendored schema, are all present.
        let schema: serde_json::Value = serde_json::from_str(SCENE_UPDATE_SCHEMA).unwrap();
        let entity = &schema["properties"]["entities"]["items"];
        let painter = Painter::new(&scene());
        let frame = Frame {
            t_s: 1.5,
            contact_x_m: 0.01,
            off_coil_m: vec![[0.0, 0.002], [0.01, 0.002]],
            on_coil_m: vec![],
            eq7: None,
            exact: None,
        };
        let msg = serde_json::to_value(painter.paint(&frame)).unwrap();
        for e in msg["entities"].as_array().unwrap() {
            for key in entity["required"].as_array().unwrap() {
                assert!(
                    e.get(key.as_str().unwrap()).is_some(),
                    "entity {} lacks {key}",
                    e["id"]
                );
            }
            assert_eq!(e["timestamp"]["sec"], 1);
            assert_eq!(e["timestamp"]["nsec"], 500_000_000);
        }
        // Both ghosts are absent: both are deleted.
        assert_eq!(msg["deletions"].as_array().unwrap().len(), 2);
    }

    #[test]
    fn drawing_drops_straight_runs_keeps_bends_and_caps_the_points() {
        // A flat run, a step up, a flat run: 2 + 2 corners survive, nothing else.
        let mut nodes: Vec<[f64; 2]> = (0..100).map(|k| [f64::from(k) * 1e-3, 0.0]).collect();
        nodes.extend((100..200).map(|k| [f64::from(k) * 1e-3, 0.01]));
        let d = drawn(&nodes, Some(1e-4));
        let xy: Vec<(f64, f64)> = d.iter().map(|p| (p.x, p.y)).collect();
        assert_eq!(
            xy,
            [(0.0, 0.0), (0.099, 0.0), (0.1, 0.01), (0.199, 0.01)],
            "kept {xy:?}"
        );
        // A circle keeps every node it needs, up to the cap, and both ends.
        let circle: Vec<[f64; 2]> = (0..=10_000)
            .map(|k| {
                let a = f64::from(k) * 2.0 * std::f64::consts::PI / 10_000.0;
                [a.cos(), a.sin()]
            })
            .collect();
        let d = drawn(&circle, None);
        assert!(d.len() <= MAX_LINE_POINTS + 1, "{} points", d.len());
        assert!(d.len() > MAX_LINE_POINTS / 2, "{} points", d.len());
        assert!((d.last().unwrap().x - 1.0).abs() < 1e-9, "the end is kept");
    }

    #[test]
    fn a_crash_leaves_the_completed_chunks_readable() {
        let dir = tempfile::tempdir().unwrap();
        let mut mcap = McapObserver::new(dir.path());
        let s = scene();
        mcap.observe_init(&s).unwrap();
        // Enough messages for a few 1 MiB chunks (about 800 bytes each, uncompressed).
        let n = 5000;
        for k in 0..n {
            let t = f64::from(k) * 1e-3;
            let data = format!("{{\"t_s\":{t},\"pad\":\"{}\"}}", "x".repeat(800));
            mcap.write(Channel::State, t, data.as_bytes()).unwrap();
        }
        // A crash: nothing is flushed or finished, the buffered tail is lost.
        std::mem::forget(mcap);
        let bytes = fs::read(dir.path().join("run.mcap.partial")).unwrap();
        let mut read = 0u32;
        let mut last = None;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            match m {
                Ok(m) => {
                    assert!(last.is_none_or(|t| t <= m.log_time), "time order");
                    last = Some(m.log_time);
                    read += 1;
                }
                Err(_) => break,
            }
        }
        assert!(
            read >= 3000 && read < n,
            "{read} of {n} messages readable after a crash, expected the completed chunks"
        );
        assert!(!dir.path().join("run.mcap").exists(), "no finished file");
    }
}
