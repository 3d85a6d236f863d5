//! What Foxglove shows of a run: the same channels written to `run.mcap` and, with the
//! `live` feature, served over the Foxglove WebSocket protocol while the run goes. Both go
//! through the Foxglove SDK (crate `foxglove`): each run logs into its own SDK context, and
//! the file and the server are sinks of it. It does no physics; [`drawings`] reads the
//! tape back from `/scene` (for [`crate::output::inspect`] and `uncoil plot`'s `bang.svg`).
//!
//! Channels, all protobuf-encoded:
//! - `/scene`: `foxglove.SceneUpdate`, the SDK's own type and schema. Entities in frame
//!   `world`, metres, x along the floor and y up: `floor` (a cube under `y = 0`),
//!   `tape/off_coil` and `tape/on_coil` (one line strip each, through the link nodes, as thick
//!   as the tape), `ghost/eq7` (the coil of eq. 7: a translucent disc with a spoke showing
//!   its rotation) and `ghost/exact` (the exact-geometry model's wound spiral), each in its
//!   own colour. Every message carries every entity, so a seek (or a viewer that connects
//!   late) draws the whole scene from one message; a ghost past its reference's end is
//!   deleted. The wound coil and the exact ghost are drawn in their own body frames, placed
//!   by the line's pose: a rigid coil keeps its points from drawing to drawing, so the log's
//!   compression stores them about once. Lines keep only the nodes a chord cannot pass
//!   within tolerance (b/20 off the coil, b/4 on it); a coil of more than 1024 such nodes (a
//!   thin tape) is drawn through its outermost 1024, with a disc for the turns inside.
//! - `/state`: one message per sample, its fields as `float`s: schema `uncoil.State`, made
//!   from the [`Sample`]'s fields (see [`channels::State`]).
//! - `/events`: detaches (one message per step that shed links, normally one link), the
//!   start and the end of the final bang with its energies, warnings: schema `uncoil.Event`,
//!   derived from [`channels::EventMessage`].
//! - `/tf`: `foxglove.FrameTransforms`, one with each drawing: the frame `contact` at the
//!   simulation's contact line on the floor, so that a 3D view following it keeps the coil in
//!   sight along the 2 m of a yoga mat.
//!
//! Messages are stamped with simulation time (ns from 0). `run.mcap` also has metadata
//! records (see [`mod@file`]). With a pace ([`ViewObserver::pace`]) the observer holds the run
//! back so that simulated time goes at that multiple of real time, the bang included.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::run::frame::{Event, Frame};
use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;
use channels::Channels;
use file::McapFile;
use paint::Painter;

pub mod channels;
pub mod drawings;
pub mod file;
#[cfg(feature = "live")]
pub mod live;
mod paint;

/// The Foxglove layout of the channels below (`tools/foxglove-layout.json`, built in): a run
/// with a view writes it beside its log, as `foxglove-layout.json`.
pub const FOXGLOVE_LAYOUT: &str = include_str!("../../tools/foxglove-layout.json");

/// Topic of the scene drawings.
pub const SCENE_TOPIC: &str = "/scene";
/// Topic of the samples.
pub const STATE_TOPIC: &str = "/state";
/// Topic of the events.
pub const EVENTS_TOPIC: &str = "/events";
/// Topic of the frame transforms.
pub const TF_TOPIC: &str = "/tf";

/// Simulation time in nanoseconds, the log and publish time of every message.
pub(crate) fn stamp_ns(t_s: f64) -> u64 {
    // Times are >= 0 and far below 2^64 ns (584 years).
    (t_s.max(0.0) * 1e9).round() as u64
}

/// Logs a run's channels into its own Foxglove SDK context, whose sinks are `run.mcap`
/// (unless [`ViewObserver::without_file`]) and a live server ([`ViewObserver::serve`]).
pub struct ViewObserver {
    context: Arc<foxglove::Context>,
    channels: Channels,
    path: Option<PathBuf>,
    file: Option<McapFile>,
    painter: Option<Painter>,
    pace: Option<Pace>,
    #[cfg(feature = "live")]
    live: Option<live::Live>,
}

impl ViewObserver {
    /// An observer writing `dir/run.mcap`.
    pub fn new(dir: &Path) -> Self {
        let mut view = Self::without_file();
        view.path = Some(dir.join(crate::output::folder::LOG));
        view
    }

    /// An observer without a file: its channels reach only a live server, if one is started.
    pub fn without_file() -> Self {
        let context = foxglove::Context::new();
        let channels = Channels::new(&context);
        Self {
            context,
            channels,
            path: None,
            file: None,
            painter: None,
            pace: None,
            #[cfg(feature = "live")]
            live: None,
        }
    }

    /// Whether a live server was started on it.
    pub fn is_live(&self) -> bool {
        #[cfg(feature = "live")]
        {
            self.live.is_some()
        }
        #[cfg(not(feature = "live"))]
        {
            false
        }
    }

    /// Where the finished file goes, if one is written.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Holds the run back so that simulated time passes at `factor` times real time
    /// (0.1: ten times slower than real). It waits before each message, from the first on.
    pub fn pace(&mut self, factor: f64) {
        self.pace = Some(Pace {
            factor,
            start: None,
        });
    }

    /// Serves the channels over the Foxglove WebSocket protocol at `addr` (port 0: any free
    /// port) until the run ends; returns the address it listens on.
    #[cfg(feature = "live")]
    pub fn serve(&mut self, addr: std::net::SocketAddr) -> anyhow::Result<std::net::SocketAddr> {
        let server = live::Live::start(&self.context, addr)?;
        let at = server.addr();
        self.live = Some(server);
        Ok(at)
    }

    /// Viewers connected now (0 without a live server).
    pub fn viewers(&self) -> usize {
        #[cfg(feature = "live")]
        if let Some(live) = &self.live {
            return live.viewers();
        }
        0
    }

    fn wait_for(&mut self, t_s: f64) {
        if let Some(pace) = self.pace.as_mut() {
            pace.wait_for(t_s);
        }
    }
}

/// A pace: simulated seconds per real second, from the first message on.
struct Pace {
    factor: f64,
    start: Option<(Instant, f64)>,
}

impl Pace {
    fn wait_for(&mut self, t_s: f64) {
        let (start, t0) = *self.start.get_or_insert_with(|| (Instant::now(), t_s));
        let due = start + Duration::from_secs_f64(((t_s - t0) / self.factor).max(0.0));
        if let Some(left) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(left);
        }
    }
}

impl Observer for ViewObserver {
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()> {
        if let Some(path) = &self.path {
            self.file = Some(McapFile::create(&self.context, path, scene)?);
        }
        self.painter = Some(Painter::new(scene));
        Ok(())
    }

    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        self.wait_for(sample.t_s);
        self.channels
            .state
            .log_with_time(&channels::State(*sample), stamp_ns(sample.t_s));
        Ok(())
    }

    fn wants_frames(&self) -> bool {
        true
    }

    fn observe_frame(&mut self, frame: &Frame) -> anyhow::Result<()> {
        self.wait_for(frame.t_s);
        let Some(painter) = &mut self.painter else {
            return Ok(());
        };
        let ns = stamp_ns(frame.t_s);
        self.channels
            .scene
            .log_with_time(&channels::Drawing(painter.paint(frame)), ns);
        self.channels
            .tf
            .log_with_time(&paint::contact_transform(frame), ns);
        Ok(())
    }

    fn observe_event(&mut self, event: &Event) -> anyhow::Result<()> {
        self.wait_for(event.t_s());
        let message = channels::EventMessage::from(event);
        self.channels
            .events
            .log_with_time(&message, stamp_ns(event.t_s()));
        Ok(())
    }

    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()> {
        #[cfg(feature = "live")]
        if let Some(live) = self.live.take() {
            live.stop();
        }
        match self.file.take() {
            Some(file) => file.finish(report),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests;
