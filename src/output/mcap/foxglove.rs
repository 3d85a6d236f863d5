//! The Foxglove message types `run.mcap` writes on `/scene` and `/tf`
//! (`foxglove.SceneUpdate`, `foxglove.FrameTransforms` and their parts), serialised to the
//! JSON their vendored schemas describe. Plain data; it draws nothing.

use super::*;

#[derive(Serialize)]
pub(super) struct Time {
    pub(super) sec: u32,
    pub(super) nsec: u32,
}

impl Time {
    pub(super) fn at(t_s: f64) -> Self {
        let ns = stamp_ns(t_s);
        // A run of more than 136 years is not simulated.
        Self {
            sec: (ns / 1_000_000_000) as u32,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

#[derive(Serialize, Clone, Copy)]
pub(super) struct Vector3 {
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) z: f64,
}

#[derive(Serialize, Clone, Copy)]
pub(super) struct Quaternion {
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) z: f64,
    pub(super) w: f64,
}

#[derive(Serialize, Clone, Copy)]
pub(super) struct Pose {
    pub(super) position: Vector3,
    pub(super) orientation: Quaternion,
}

impl Pose {
    pub(super) fn at(x: f64, y: f64) -> Self {
        Self {
            position: Vector3 { x, y, z: 0.0 },
            orientation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            },
        }
    }
}

#[derive(Serialize, Clone, Copy)]
pub(super) struct Color {
    pub(super) r: f64,
    pub(super) g: f64,
    pub(super) b: f64,
    pub(super) a: f64,
}

pub(super) const fn rgb(r: f64, g: f64, b: f64) -> Color {
    Color { r, g, b, a: 1.0 }
}

/// Floor: light grey. Tape: dark blue off the coil, lighter on it. Eq. (7): orange.
/// Exact geometry: green.
pub(super) const FLOOR: Color = rgb(0.75, 0.75, 0.75);
pub(super) const TAPE_OFF: Color = rgb(0.10, 0.25, 0.60);
pub(super) const TAPE_ON: Color = rgb(0.25, 0.55, 0.95);
pub(super) const EQ7: Color = rgb(0.95, 0.50, 0.05);
pub(super) const EXACT: Color = rgb(0.10, 0.70, 0.25);

#[derive(Serialize)]
pub(super) struct CubePrimitive {
    pub(super) pose: Pose,
    pub(super) size: Vector3,
    pub(super) color: Color,
}

#[derive(Serialize)]
pub(super) struct LinePrimitive {
    /// 0 line strip, 1 line loop, 2 line list.
    #[serde(rename = "type")]
    pub(super) kind: u8,
    pub(super) pose: Pose,
    pub(super) thickness: f64,
    pub(super) scale_invariant: bool,
    pub(super) points: Vec<Vector3>,
    pub(super) color: Color,
    pub(super) colors: [Color; 0],
    pub(super) indices: [u32; 0],
}

pub(super) const LINE_STRIP: u8 = 0;
pub(super) const LINE_LOOP: u8 = 1;
pub(super) const LINE_LIST: u8 = 2;

#[derive(Serialize)]
pub(super) struct KeyValuePair {
    pub(super) key: &'static str,
    pub(super) value: &'static str,
}

#[derive(Serialize)]
pub(super) struct SceneEntity {
    pub(super) timestamp: Time,
    pub(super) frame_id: &'static str,
    pub(super) id: &'static str,
    pub(super) lifetime: Time,
    pub(super) frame_locked: bool,
    pub(super) metadata: Vec<KeyValuePair>,
    pub(super) arrows: [(); 0],
    pub(super) cubes: Vec<CubePrimitive>,
    pub(super) spheres: [(); 0],
    pub(super) cylinders: [(); 0],
    pub(super) lines: Vec<LinePrimitive>,
    pub(super) triangles: [(); 0],
    pub(super) texts: [(); 0],
    pub(super) models: [(); 0],
}

#[derive(Serialize)]
pub(super) struct SceneEntityDeletion {
    pub(super) timestamp: Time,
    /// 0: the entity with this id.
    #[serde(rename = "type")]
    pub(super) kind: u8,
    pub(super) id: &'static str,
}

#[derive(Serialize)]
pub(super) struct FrameTransform {
    pub(super) timestamp: Time,
    pub(super) parent_frame_id: &'static str,
    pub(super) child_frame_id: &'static str,
    pub(super) translation: Vector3,
    pub(super) rotation: Quaternion,
}

#[derive(Serialize)]
pub(super) struct FrameTransforms {
    pub(super) transforms: [FrameTransform; 1],
}

/// The frame `contact`: the simulation's contact line on the floor, unrotated.
pub(super) fn contact_transform(frame: &Frame) -> FrameTransforms {
    let pose = Pose::at(um(frame.contact_x_m), 0.0);
    FrameTransforms {
        transforms: [FrameTransform {
            timestamp: Time::at(frame.t_s),
            parent_frame_id: "world",
            child_frame_id: "contact",
            translation: pose.position,
            rotation: pose.orientation,
        }],
    }
}

#[derive(Serialize)]
pub(super) struct SceneUpdate {
    pub(super) deletions: Vec<SceneEntityDeletion>,
    pub(super) entities: Vec<SceneEntity>,
}
