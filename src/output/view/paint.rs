//! The painter of `/scene` and `/tf`: the floor, the tape on and off the coil as line strips,
//! the ghosts of eq. (7) and of the exact-geometry model, each frame one whole scene, as the
//! SDK's `foxglove.SceneUpdate`. Coordinates are rounded to 1 µm; the wound coils are drawn
//! in their body frames, so that their bytes repeat from drawing to drawing; lines are
//! thinned where a chord passes their nodes within a tolerance. It writes nothing itself.

use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, Duration, FrameTransform, FrameTransforms,
    KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity, SceneEntityDeletion,
    SceneUpdate, Timestamp, Vector3, line_primitive, scene_entity_deletion,
};

use super::stamp_ns;
use crate::run::frame::{Frame, GhostDisc};
use crate::scene::Scene;
use crate::spiral::Placed;

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

/// The pose of a placed curve's body frame: at its origin, turned about z by its rotation.
fn placed_pose(placed: &Placed) -> Pose {
    let (sin, cos) = (0.5 * placed.rotation_rad).sin_cos();
    Pose {
        position: Some(Vector3 {
            x: um(placed.origin_m[0]),
            y: um(placed.origin_m[1]),
            z: 0.0,
        }),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: sin,
            w: cos,
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
const EQ7_DISC: Color = Color { a: 0.3, ..EQ7 };
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

/// Most points drawn for the tape off the coil: a longer line is drawn through every k-th
/// kept node, its ends kept. A drawing only.
pub(super) const MAX_LINE_POINTS: usize = 2048;

/// The points of a line strip as drawn: the nodes that [`sleeve`] keeps within `tol_m`, then
/// at most [`MAX_LINE_POINTS`] of them, every k-th from the first, the ends always kept. Both
/// steps run from the first node, so a line that only grows or shrinks at its far end keeps
/// its drawn points, and a log repeats their bytes.
pub(super) fn drawn(nodes: &[[f64; 2]], tol_m: f64) -> Vec<Point3> {
    let kept = kept_nodes(nodes, &sleeve(nodes, tol_m));
    let step = kept.len().div_ceil(MAX_LINE_POINTS).max(1);
    let last = kept.len().saturating_sub(1);
    kept.iter()
        .enumerate()
        .filter(|(i, _)| i % step == 0 || *i == last)
        .map(|(_, &p)| point(p))
        .collect()
}

/// The nodes whose `keep` is set.
fn kept_nodes(nodes: &[[f64; 2]], keep: &[bool]) -> Vec<[f64; 2]> {
    nodes
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(p, _)| *p)
        .collect()
}

/// Most points drawn for a wound coil. A coil of more (a thin tape's 300 turns) is drawn
/// through its outermost kept nodes only, and a disc fills the turns inside them: 1024 points
/// are the thin tape's outer 25 turns, its outer 2.5 mm, and its turns 0.1 mm apart show as
/// one solid disc at any zoom that shows the whole coil.
pub(super) const MAX_WOUND_POINTS: usize = 1024;

/// The points of a wound coil's line as drawn, from the inner end out: the nodes that
/// [`sleeve`] keeps within `tol_m`, at most the outermost [`MAX_WOUND_POINTS`] of them. As the
/// coil sheds its outer end, the drawing is the same run of kept points, shifted.
pub(super) fn drawn_wound(nodes: &[[f64; 2]], tol_m: f64, kept: &mut Kept) -> Vec<Point3> {
    let kept = kept_nodes(nodes, kept.of(nodes, tol_m));
    let from = kept.len().saturating_sub(MAX_WOUND_POINTS);
    kept[from..].iter().map(|&p| point(p)).collect()
}

/// What [`sleeve`] keeps of a line that only loses nodes at its far end from one drawing to
/// the next, a wound coil in its own frame: the walk runs once, and a later line whose nodes
/// are a leading part of the ones it ran on takes its answer from there, its own last node
/// kept, as a node's fate depends only on the nodes up to the next one.
#[derive(Debug, Default)]
pub(super) struct Kept {
    nodes: Vec<[f64; 2]>,
    tol_m: f64,
    keep: Vec<bool>,
    last: Vec<bool>,
}

impl Kept {
    fn of(&mut self, nodes: &[[f64; 2]], tol_m: f64) -> &[bool] {
        let m = nodes.len();
        let reuse = tol_m == self.tol_m && m <= self.nodes.len() && nodes == &self.nodes[..m];
        if !reuse {
            self.nodes = nodes.to_vec();
            self.tol_m = tol_m;
            self.keep = sleeve(nodes, tol_m);
        }
        self.last.clear();
        self.last.extend_from_slice(&self.keep[..m]);
        if let Some(end) = self.last.last_mut() {
            *end = true;
        }
        &self.last
    }
}

/// Which nodes a walk along the line keeps: from the last kept node it passes on to the next
/// node while one chord from the kept node can pass within `tol_m` of every node passed, and
/// keeps the node before the first it cannot reach. The chords that pass within `tol_m` of a
/// node at distance `d` point into a cone of half-width `asin(tol_m / d)` about it; the walk
/// holds the cones' intersection (the "sleeve") as its two edge directions. One pass without
/// trigonometry, and a node's fate depends only on the nodes before it.
fn sleeve(nodes: &[[f64; 2]], tol_m: f64) -> Vec<bool> {
    let n = nodes.len();
    let mut keep = vec![false; n];
    if n == 0 {
        return keep;
    }
    keep[0] = true;
    keep[n - 1] = true;
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let mut anchor = 0;
    // The open cone's clockwise and counter-clockwise edges, once a node is outside the
    // tolerance of the anchor.
    let mut cone: Option<([f64; 2], [f64; 2])> = None;
    let mut k = 1;
    while k < n {
        let v = [
            nodes[k][0] - nodes[anchor][0],
            nodes[k][1] - nodes[anchor][1],
        ];
        let d2 = v[0] * v[0] + v[1] * v[1];
        if d2 <= tol_m * tol_m {
            // Any chord from the anchor passes within tolerance of this node.
            k += 1;
            continue;
        }
        if let Some((cw, ccw)) = cone
            && (cross(cw, v) < 0.0 || cross(v, ccw) < 0.0)
        {
            // No chord to node k passes every node before it: keep the one before.
            anchor = k - 1;
            keep[anchor] = true;
            cone = None;
            continue;
        }
        // This node's cone: its direction turned by +-asin(tol / d).
        let sin = tol_m / d2.sqrt();
        let cos = (1.0 - sin * sin).sqrt();
        let turn = |s: f64| [cos * v[0] - s * v[1], s * v[0] + cos * v[1]];
        let (lo, hi) = (turn(-sin), turn(sin));
        cone = Some(match cone {
            None => (lo, hi),
            Some((cw, ccw)) => (
                if cross(cw, lo) > 0.0 { lo } else { cw },
                if cross(hi, ccw) > 0.0 { hi } else { ccw },
            ),
        });
        k += 1;
    }
    keep
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
    /// The wound coil's and the exact ghost's kept nodes, from the drawings before.
    coil: Kept,
    ghost: Kept,
}

/// The drawing tolerance of a wound turn, in tape thicknesses.
pub(super) const CURVE_TOLERANCE: f64 = 0.25;

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
            coil: Kept::default(),
            ghost: Kept::default(),
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
        Self::placed_line(kind, thickness, color, pose_at(0.0, 0.0), points)
    }

    /// A line whose points are in the frame that `pose` places in the world.
    fn placed_line(
        kind: line_primitive::Type,
        thickness: f64,
        color: Color,
        pose: Pose,
        points: Vec<Point3>,
    ) -> LinePrimitive {
        LinePrimitive {
            r#type: kind as i32,
            pose: Some(pose),
            thickness,
            points,
            color: Some(color),
            ..LinePrimitive::default()
        }
    }

    pub(super) fn paint(&mut self, frame: &Frame) -> SceneUpdate {
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

        let mut off = Self::entity(t, "tape/off_coil", "simulated tape off the coil");
        off.lines.push(Self::line(
            line_primitive::Type::LineStrip,
            b,
            TAPE_OFF,
            drawn(&frame.off_coil_m, straight),
        ));
        entities.push(off);
        entities.push(self.wound(frame, curve));
        if let Some(d) = &frame.eq7 {
            entities.push(Self::eq7(t, d, b));
        } else {
            deletions.push(deletion(t, "ghost/eq7"));
        }

        if let Some(g) = &frame.exact {
            let mut e = Self::entity(t, "ghost/exact", "exact-geometry coil");
            e.lines.push(Self::placed_line(
                line_primitive::Type::LineStrip,
                ghost,
                EXACT,
                placed_pose(&g.spiral),
                ghost_line(&g.spiral.points_m, curve, &mut self.ghost),
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

impl Painter {
    /// The wound coil in its own frame: its points repeat from drawing to drawing while it
    /// rolls, and the log's compression stores them about once per chunk.
    fn wound(&mut self, frame: &Frame, tol_m: f64) -> SceneEntity {
        let b = self.thickness_m;
        let mut on = Self::entity(frame.t_s, "tape/on_coil", "simulated tape on the coil");
        let wound = drawn_wound(&frame.on_coil.points_m, tol_m, &mut self.coil);
        if let Some(inner) = wound.first()
            && wound.len() == MAX_WOUND_POINTS
        {
            // The turns inside the drawn ones, as a disc about the spiral centre (the body
            // origin) out to the innermost drawn node's tape surface, beneath the lines and
            // the translucent eq. (7) disc.
            let r = inner.x.hypot(inner.y) + 0.5 * b;
            on.cylinders
                .push(disc(placed_pose(&frame.on_coil), -2.0 * b, r, b, TAPE_ON));
        }
        on.lines.push(Self::placed_line(
            line_primitive::Type::LineStrip,
            b,
            TAPE_ON,
            placed_pose(&frame.on_coil),
            wound,
        ));
        on
    }

    /// The coil of eq. (7): a translucent disc behind the tape (eq. 7 knows only the radius),
    /// a few bytes a drawing where a circle of line points would change all of them each
    /// time, and a spoke that turns with it.
    fn eq7(t_s: f64, d: &GhostDisc, b: f64) -> SceneEntity {
        let mut e = Self::entity(t_s, "ghost/eq7", "eq. (7) continuum coil");
        let c = d.centre_m;
        e.cylinders.push(disc(
            pose_at(um(c[0]), um(c[1])),
            -b,
            d.radius_m,
            b,
            EQ7_DISC,
        ));
        // The spoke points at the outer end's start position, straight down at t = 0.
        let a = d.rotation_rad - 0.5 * std::f64::consts::PI;
        let tip = [c[0] + d.radius_m * a.cos(), c[1] + d.radius_m * a.sin()];
        e.lines.push(Self::line(
            line_primitive::Type::LineList,
            0.25 * b,
            EQ7,
            vec![point(c), point(tip)],
        ));
        e
    }
}

/// A flat disc of radius `r_m` and height `h_m` about `pose`, moved to depth `z_m` (behind the
/// lines at `z = 0` in the layout's view from above).
fn disc(mut pose: Pose, z_m: f64, r_m: f64, h_m: f64, color: Color) -> CylinderPrimitive {
    if let Some(p) = pose.position.as_mut() {
        p.z = um(z_m);
    }
    CylinderPrimitive {
        pose: Some(pose),
        size: Some(Vector3 {
            x: um(2.0 * r_m),
            y: um(2.0 * r_m),
            z: um(h_m),
        }),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(color),
    }
}

/// The exact ghost's line: its points on the fixed grid drawn as a wound coil is, then its
/// contact point, which lies off the grid and moves with every drawing.
fn ghost_line(points: &[[f64; 2]], tol_m: f64, kept: &mut Kept) -> Vec<Point3> {
    let Some((contact, grid)) = points.split_last() else {
        return Vec::new();
    };
    let mut line = drawn_wound(grid, tol_m, kept);
    line.push(point(*contact));
    line
}

/// Deletes the entity `id` at `t_s`.
fn deletion(t_s: f64, id: &str) -> SceneEntityDeletion {
    SceneEntityDeletion {
        timestamp: Some(time(t_s)),
        r#type: scene_entity_deletion::Type::MatchingId as i32,
        id: id.into(),
    }
}
