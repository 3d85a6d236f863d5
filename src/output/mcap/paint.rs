//! The painter of `/scene`: the floor, the tape on and off the coil as line strips, the
//! ghosts of eq. (7) and of the exact-geometry model, each frame one whole scene. Lines are
//! rounded to 1 µm and thinned where the tape is straight. It writes nothing itself.

use super::foxglove::*;
use super::*;

/// Rounds a coordinate to 1 µm: far below what a drawing shows, and it halves the text.
pub(super) fn um(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// Most points drawn for one line: a longer line (the wound part of a thin tape, thousands
/// of links) is drawn through every k-th node, its ends kept. A drawing only.
pub(super) const MAX_LINE_POINTS: usize = 2048;

/// The points of a line strip as drawn: with a tolerance, the nodes that Douglas-Peucker
/// simplification keeps (the flat laid tape becomes a few segments); then at most
/// [`MAX_LINE_POINTS`] of them. A curve of many turns (the wound coil) is not simplified:
/// Douglas-Peucker splits a spiral unevenly and costs O(n^2) on it.
pub(super) fn drawn(nodes: &[[f64; 2]], tol_m: Option<f64>) -> Vec<Vector3> {
    let n = nodes.len();
    let mut keep = vec![tol_m.is_none(); n];
    if n > 0 {
        keep[0] = true;
        keep[n - 1] = true;
    }
    let tol_m = tol_m.unwrap_or(f64::INFINITY);
    let mut stack = if tol_m.is_finite() {
        vec![(0, n.saturating_sub(1))]
    } else {
        vec![]
    };
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

pub(super) fn point(p: [f64; 2]) -> Vector3 {
    Vector3 {
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

/// Segments of the eq. (7) circle.
pub(super) const CIRCLE_SEGMENTS: u32 = 48;

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

    pub(super) fn entity(t_s: f64, id: &'static str, label: &'static str) -> SceneEntity {
        SceneEntity {
            timestamp: Time::at(t_s),
            frame_id: "world",
            id,
            lifetime: Time { sec: 0, nsec: 0 },
            frame_locked: false,
            metadata: vec![KeyValuePair {
                key: "label",
                value: label,
            }],
            arrows: [],
            cubes: vec![],
            spheres: [],
            cylinders: [],
            lines: vec![],
            triangles: [],
            texts: [],
            models: [],
        }
    }

    pub(super) fn line(
        kind: u8,
        thickness: f64,
        color: Color,
        points: Vec<Vector3>,
    ) -> LinePrimitive {
        LinePrimitive {
            kind,
            pose: Pose::at(0.0, 0.0),
            thickness,
            scale_invariant: false,
            points,
            color,
            colors: [],
            indices: [],
        }
    }

    pub(super) fn paint(&self, frame: &Frame) -> SceneUpdate {
        let t = frame.t_s;
        let b = self.thickness_m;
        let ghost = 0.25 * b;
        // Drawing tolerance: a twentieth of the tape's thickness, the width of its line.
        let tol = 0.05 * b;
        let mut entities = Vec::with_capacity(5);
        let mut deletions = Vec::new();

        let mut floor = Self::entity(t, "floor", "floor, top at y = 0");
        let depth = 10.0 * b;
        floor.cubes.push(CubePrimitive {
            pose: Pose::at(
                um(0.5 * (self.floor_from_m + self.floor_to_m)),
                um(-0.5 * depth),
            ),
            size: Vector3 {
                x: um(self.floor_to_m - self.floor_from_m),
                y: um(depth),
                z: um(depth),
            },
            color: FLOOR,
        });
        entities.push(floor);

        for (id, label, nodes, color, tol) in [
            (
                "tape/off_coil",
                "simulated tape off the coil",
                &frame.off_coil_m,
                TAPE_OFF,
                Some(tol),
            ),
            (
                "tape/on_coil",
                "simulated tape on the coil",
                &frame.on_coil_m,
                TAPE_ON,
                None,
            ),
        ] {
            let mut e = Self::entity(t, id, label);
            e.lines
                .push(Self::line(LINE_STRIP, b, color, drawn(nodes, tol)));
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
            e.lines.push(Self::line(LINE_LOOP, ghost, EQ7, circle));
            // The spoke points at the outer end's start position, straight down at t = 0.
            let a = d.rotation_rad - 0.5 * std::f64::consts::PI;
            let tip = [c[0] + d.radius_m * a.cos(), c[1] + d.radius_m * a.sin()];
            e.lines.push(Self::line(
                LINE_LIST,
                ghost,
                EQ7,
                vec![point(c), point(tip)],
            ));
            entities.push(e);
        } else {
            deletions.push(SceneEntityDeletion {
                timestamp: Time::at(t),
                kind: 0,
                id: "ghost/eq7",
            });
        }

        if let Some(g) = &frame.exact {
            let mut e = Self::entity(t, "ghost/exact", "exact-geometry coil");
            e.lines.push(Self::line(
                LINE_STRIP,
                ghost,
                EXACT,
                drawn(&g.points_m, None),
            ));
            entities.push(e);
        } else {
            deletions.push(SceneEntityDeletion {
                timestamp: Time::at(t),
                kind: 0,
                id: "ghost/exact",
            });
        }
        SceneUpdate {
            deletions,
            entities,
        }
    }
}
