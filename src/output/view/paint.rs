//! The painter of `/scene` and `/tf`: the floor, the tape on and off the coil as line strips,
//! the ghosts of eq. (7) and of the exact-geometry model, each frame one whole scene, as the
//! SDK's `foxglove.SceneUpdate`. Lines are rounded to 1 µm and thinned where the tape is
//! straight. It writes nothing itself.

use foxglove::messages::{
    Color, CubePrimitive, Duration, FrameTransform, FrameTransforms, KeyValuePair, LinePrimitive,
    Point3, Pose, Quaternion, SceneEntity, SceneEntityDeletion, SceneUpdate, Timestamp, Vector3,
    line_primitive, scene_entity_deletion,
};

use super::stamp_ns;
use crate::run::frame::Frame;
use crate::scene::Scene;

/// Rounds a coordinate to 1 µm: far below what a drawing shows.
pub(super) fn um(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// The time stamp of an entity at simulated time `t_s`.
fn time(t_s: f64) -> Timestamp {
    let ns = stamp_ns(t_s);
    // A run of more than 136 years is not simulated.
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

/// A pose at `(x, y)` in the plane, unrotated.
fn pose_at(x: f64, y: f64) -> Pose {
    Pose {
        position: Some(Vector3 { x, y, z: 0.0 }),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    }
}

const fn rgb(r: f64, g: f64, b: f64) -> Color {
    Color { r, g, b, a: 1.0 }
}

/// Floor: light grey. Tape: dark blue off the coil, lighter on it. Eq. (7): orange.
/// Exact geometry: green.
const FLOOR: Color = rgb(0.75, 0.75, 0.75);
const TAPE_OFF: Color = rgb(0.10, 0.25, 0.60);
const TAPE_ON: Color = rgb(0.25, 0.55, 0.95);
const EQ7: Color = rgb(0.95, 0.50, 0.05);
const EXACT: Color = rgb(0.10, 0.70, 0.25);

/// The frame `contact`: the simulation's contact line on the floor, unrotated.
pub(super) fn contact_transform(frame: &Frame) -> FrameTransforms {
    let pose = pose_at(um(frame.contact_x_m), 0.0);
    FrameTransforms {
        transforms: vec![FrameTransform {
            timestamp: Some(time(frame.t_s)),
            parent_frame_id: "world".into(),
            child_frame_id: "contact".into(),
            translation: pose.position,
            rotation: pose.orientation,
        }],
    }
}

/// Most points drawn for one line: a longer line (the wound part of a thin tape, thousands
/// of links) is drawn through every k-th node, its ends kept. A drawing only.
pub(super) const MAX_LINE_POINTS: usize = 2048;

/// How a line is thinned for drawing.
#[derive(Clone, Copy, Debug)]
pub(super) enum Thin {
    /// Douglas-Peucker simplification within this tolerance (m): for a line of long straight
    /// runs, the laid tape. It splits a spiral unevenly and costs O(n^2) on it.
    Straight(f64),
    /// A walk along the line that drops a node while the chord over the dropped ones stays
    /// within this tolerance (m), at most [`MAX_SKIP`] in a row: for a curve, the wound coil.
    Curve(f64),
}

/// Most nodes a curve's walk drops in a row: it bounds the walk's cost.
const MAX_SKIP: usize = 32;

/// The points of a line strip as drawn: the nodes that `thin` keeps, then at most
/// [`MAX_LINE_POINTS`] of them, the ends always kept.
pub(super) fn drawn(nodes: &[[f64; 2]], thin: Thin) -> Vec<Point3> {
    let keep = match thin {
        Thin::Straight(tol_m) => douglas_peucker(nodes, tol_m),
        Thin::Curve(tol_m) => curve_walk(nodes, tol_m),
    };
    let kept: Vec<[f64; 2]> = nodes
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(p, _)| *p)
        .collect();
    let step = kept.len().div_ceil(MAX_LINE_POINTS).max(1);
    let last = kept.len().saturating_sub(1);
    kept.iter()
        .enumerate()
        .filter(|(i, _)| i % step == 0 || *i == last)
        .map(|(_, &p)| point(p))
        .collect()
}

/// `n` nodes of which only the two ends are kept so far.
fn ends_kept(n: usize) -> Vec<bool> {
    let mut keep = vec![false; n];
    if n > 0 {
        keep[0] = true;
        keep[n - 1] = true;
    }
    keep
}

/// Which nodes Douglas-Peucker keeps within `tol_m`.
fn douglas_peucker(nodes: &[[f64; 2]], tol_m: f64) -> Vec<bool> {
    let n = nodes.len();
    let mut keep = ends_kept(n);
    if n == 0 {
        return keep;
    }
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        let far = (i + 1..j)
            .map(|k| (k, distance_to_segment(nodes[k], nodes[i], nodes[j])))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, d)) = far
            && d > tol_m
        {
            keep[k] = true;
            stack.push((i, k));
            stack.push((k, j));
        }
    }
    keep
}

/// Which nodes a walk along a curve keeps: from the last kept node, the next is the
/// farthest one whose chord passes within `tol_m` of every node between.
fn curve_walk(nodes: &[[f64; 2]], tol_m: f64) -> Vec<bool> {
    let n = nodes.len();
    let mut keep = ends_kept(n);
    let mut anchor = 0;
    while anchor + 1 < n {
        let mut next = anchor + 1;
        while next + 1 < n
            && next - anchor <= MAX_SKIP
            && (anchor + 1..=next)
                .all(|k| distance_to_segment(nodes[k], nodes[anchor], nodes[next + 1]) <= tol_m)
        {
            next += 1;
        }
        keep[next] = true;
        anchor = next;
    }
    keep
}

/// Distance of `p` from the segment from `a` to `b` (m).
pub(super) fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - s * dx).hypot(p[1] - a[1] - s * dy)
}

pub(super) fn point(p: [f64; 2]) -> Point3 {
    Point3 {
        x: um(p[0]),
        y: um(p[1]),
        z: 0.0,
    }
}

/// Turns frames into scene updates.
pub(super) struct Painter {
    pub(super) thickness_m: f64,
    pub(super) floor_from_m: f64,
    pub(super) floor_to_m: f64,
}

/// The drawing tolerance of a wound turn, in tape thicknesses.
pub(super) const CURVE_TOLERANCE: f64 = 0.25;

/// Segments of the eq. (7) circle: at the yoga mat's 6 cm a chord strays 0.5 mm, a tenth of
/// the tape's thickness.
pub(super) const CIRCLE_SEGMENTS: u32 = 24;

impl Painter {
    pub(super) fn new(scene: &Scene) -> Self {
        let spiral = crate::spiral::Spiral::wound(
            scene.tape.outer_radius_m,
            scene.tape.thickness_m,
            scene.tape.core_radius_m,
        );
        let r = scene.tape.outer_radius_m;
        Self {
            thickness_m: scene.tape.thickness_m,
            floor_from_m: -2.0 * r,
            floor_to_m: spiral.length() + 2.0 * r,
        }
    }

    pub(super) fn entity(t_s: f64, id: &str, label: &str) -> SceneEntity {
        SceneEntity {
            timestamp: Some(time(t_s)),
            frame_id: "world".into(),
            id: id.into(),
            lifetime: Some(Duration::new(0, 0)),
            metadata: vec![KeyValuePair {
                key: "label".into(),
                value: label.into(),
            }],
            ..SceneEntity::default()
        }
    }

    pub(super) fn line(
        kind: line_primitive::Type,
        thickness: f64,
        color: Color,
        points: Vec<Point3>,
    ) -> LinePrimitive {
        LinePrimitive {
            r#type: kind as i32,
            pose: Some(pose_at(0.0, 0.0)),
            thickness,
            points,
            color: Some(color),
            ..LinePrimitive::default()
        }
    }

    pub(super) fn paint(&self, frame: &Frame) -> SceneUpdate {
        let t = frame.t_s;
        let b = self.thickness_m;
        let ghost = 0.25 * b;
        // Drawing tolerances: a straight run keeps every node off it by more than a twentieth
        // of the tape's thickness, the width of its line; a wound turn is drawn through chords
        // that stray at most a quarter of that width from its nodes.
        let straight = 0.05 * b;
        let curve = CURVE_TOLERANCE * b;
        let mut entities = Vec::with_capacity(5);
        let mut deletions = Vec::new();

        let mut floor = Self::entity(t, "floor", "floor, top at y = 0");
        let depth = 10.0 * b;
        floor.cubes.push(CubePrimitive {
            pose: Some(pose_at(
                um(0.5 * (self.floor_from_m + self.floor_to_m)),
                um(-0.5 * depth),
            )),
            size: Some(Vector3 {
                x: um(self.floor_to_m - self.floor_from_m),
                y: um(depth),
                z: um(depth),
            }),
            color: Some(FLOOR),
        });
        entities.push(floor);

        for (id, label, nodes, color, thin) in [
            (
                "tape/off_coil",
                "simulated tape off the coil",
                &frame.off_coil_m,
                TAPE_OFF,
                Thin::Straight(straight),
            ),
            (
                "tape/on_coil",
                "simulated tape on the coil",
                &frame.on_coil_m,
                TAPE_ON,
                Thin::Curve(curve),
            ),
        ] {
            let mut e = Self::entity(t, id, label);
            e.lines.push(Self::line(
                line_primitive::Type::LineStrip,
                b,
                color,
                drawn(nodes, thin),
            ));
            entities.push(e);
        }

        if let Some(d) = &frame.eq7 {
            let mut e = Self::entity(t, "ghost/eq7", "eq. (7) continuum coil");
            let c = d.centre_m;
            let circle = (0..CIRCLE_SEGMENTS)
                .map(|k| {
                    let a = 2.0 * std::f64::consts::PI * f64::from(k) / f64::from(CIRCLE_SEGMENTS);
                    point([c[0] + d.radius_m * a.cos(), c[1] + d.radius_m * a.sin()])
                })
                .collect();
            e.lines.push(Self::line(
                line_primitive::Type::LineLoop,
                ghost,
                EQ7,
                circle,
            ));
            // The spoke points at the outer end's start position, straight down at t = 0.
            let a = d.rotation_rad - 0.5 * std::f64::consts::PI;
            let tip = [c[0] + d.radius_m * a.cos(), c[1] + d.radius_m * a.sin()];
            e.lines.push(Self::line(
                line_primitive::Type::LineList,
                ghost,
                EQ7,
                vec![point(c), point(tip)],
            ));
            entities.push(e);
        } else {
            deletions.push(deletion(t, "ghost/eq7"));
        }

        if let Some(g) = &frame.exact {
            let mut e = Self::entity(t, "ghost/exact", "exact-geometry coil");
            e.lines.push(Self::line(
                line_primitive::Type::LineStrip,
                ghost,
                EXACT,
                drawn(&g.points_m, Thin::Curve(curve)),
            ));
            entities.push(e);
        } else {
            deletions.push(deletion(t, "ghost/exact"));
        }
        SceneUpdate {
            deletions,
            entities,
        }
    }
}

/// Deletes the entity `id` at `t_s`.
fn deletion(t_s: f64, id: &str) -> SceneEntityDeletion {
    SceneEntityDeletion {
        timestamp: Some(time(t_s)),
        r#type: scene_entity_deletion::Type::MatchingId as i32,
        id: id.into(),
    }
}
