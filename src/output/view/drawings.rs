//! `/scene` read back: each drawing's tape as one midline in world coordinates, for the
//! readers of a finished run (`uncoil inspect`'s count of where the tape crosses itself,
//! `uncoil plot`'s `bang.svg`). The tape's lines (entities `tape/*`) are joined in order
//! along the tape, from its outer end: the tape off the coil as drawn, then the wound tape
//! from its outermost point in. Each line is placed by its pose. It reads what
//! the painter (`view/paint.rs`) wrote and nothing else.

use anyhow::Context as _;
use foxglove::messages::{LinePrimitive, SceneUpdate};
use prost::Message as _;

use super::SCENE_TOPIC;

/// The tape's lines in order along the tape from its outer end, each with whether its
/// points run the other way (the wound tape is drawn from its inner end out).
pub const TAPE_LINES: [(&str, bool); 2] = [("tape/off_coil", false), ("tape/on_coil", true)];

/// The tape as one drawing shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct TapeDrawing {
    /// Simulated time (s), from the message's log time.
    pub t_s: f64,
    /// The tape's thickness, the width its lines are drawn with (m).
    pub thickness_m: f64,
    /// The drawn midline in the world frame (m), from the tape's outer end: the points of
    /// the lines of [`TAPE_LINES`] in turn.
    pub midline_m: Vec<[f64; 2]>,
}

/// The drawings of `/scene` in an MCAP file's bytes whose log time is after `after_ns`
/// (every one for `None`), in file order; and why reading stopped early, for a file cut
/// short (the drawings before the cut are kept).
pub fn tape_drawings(
    bytes: &[u8],
    after_ns: Option<u64>,
) -> anyhow::Result<(Vec<TapeDrawing>, Option<String>)> {
    let mut out = Vec::new();
    for message in mcap::MessageStream::new(bytes).context("not an MCAP file")? {
        let m = match message {
            Ok(m) => m,
            Err(e) => return Ok((out, Some(e.to_string()))),
        };
        if m.channel.topic != SCENE_TOPIC || after_ns.is_some_and(|t| m.log_time <= t) {
            continue;
        }
        let update = SceneUpdate::decode(m.data.as_ref())
            .with_context(|| format!("a {SCENE_TOPIC} message at {} ns", m.log_time))?;
        out.push(tape_of(&update, m.log_time as f64 * 1e-9));
    }
    Ok((out, None))
}

/// The tape of one drawing.
fn tape_of(update: &SceneUpdate, t_s: f64) -> TapeDrawing {
    let mut midline = Vec::new();
    let mut thickness = 0.0_f64;
    for (id, reversed) in TAPE_LINES {
        let Some(entity) = update.entities.iter().find(|e| e.id == id) else {
            continue;
        };
        for line in &entity.lines {
            thickness = thickness.max(line.thickness);
            let mut points = placed(line);
            if reversed {
                points.reverse();
            }
            midline.extend(points);
        }
    }
    TapeDrawing {
        t_s,
        thickness_m: thickness,
        midline_m: midline,
    }
}

/// A line's points in the world frame: turned by its pose's rotation about z, then moved to
/// its position.
fn placed(line: &LinePrimitive) -> Vec<[f64; 2]> {
    let (origin, angle) = line.pose.as_ref().map_or(([0.0, 0.0], 0.0), |pose| {
        let o = pose.position.as_ref().map_or([0.0, 0.0], |p| [p.x, p.y]);
        let a = pose
            .orientation
            .as_ref()
            .map_or(0.0, |q| 2.0 * q.z.atan2(q.w));
        (o, a)
    });
    let (sin, cos) = angle.sin_cos();
    line.points
        .iter()
        .map(|p| {
            [
                origin[0] + cos * p.x - sin * p.y,
                origin[1] + sin * p.x + cos * p.y,
            ]
        })
        .collect()
}
