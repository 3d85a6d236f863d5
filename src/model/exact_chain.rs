//! The exact chain: rigid bodies in a row joined end to end by revolute joints, the first
//! optionally pinned to the world, on an optional frictional floor. Each step holds the
//! joints exactly, by a direct solve in time linear in the number of bodies, and the
//! floor's contacts to a stated tolerance. Pure `f64`: it uses no engine, and knows nothing
//! of coils or ledgers.
//!
//! Each body has maximal coordinates `q = (x, y, theta)` about its centre of mass and a
//! constant diagonal mass matrix `M = diag(m, m, I)`: in the plane the configuration space is
//! flat, and the chain is a holonomically constrained system whose standard integrator is
//! RATTLE (Andersen 1983; Hairer, Lubich and Wanner, Geometric Numerical Integration, VII.1):
//! symplectic, second order, its energy error bounded rather than drifting. A step of length
//! `h`, the velocity `v` held at whole steps (where `G(q) v = 0`: every joint's two anchors
//! move together):
//!
//! ```text
//! 1. floor's impulses at q:  v' = v + M^-1 (G^T mu + C^T p),     G(q) v' = 0
//! 2. half kick and drift:    v~ = v' + h g / 2 + M^-1 G(q)^T lambda,
//!                            q+ = q + h v~,                       g(q+) = 0  (SHAKE)
//! 3. half kick, impulses:    v+ = v~ + h g / 2 + M^-1 (G(q+)^T nu + C(q+)^T p+),
//!                            G(q+) v+ = 0
//! ```
//!
//! `g` is every joint's gap (the two anchors' world points, 2 rows each; the pin's anchor
//! and its world point, 2 rows) and `G` its Jacobian. The drift closes every joint at the
//! step's end by Newton's method; stages 1 and 3 hold the joints at a whole step, so an
//! impact there does no work on them however it changes the bodies' spins (an impulse in the
//! drift would: its joints close over the step with the spins of after the impact). The
//! floor's contacts act in stages 1 and 3: inelastic, with Coulomb friction, each point's
//! normal velocity at least its target (stage 1: closing its gap over the step and meeting
//! gravity's half kick; stage 3: not approaching). A contact's rows touch only its own body,
//! so they join the banded system: each point off, sticking or sliding, the modes changed
//! where a solve breaks a condition (an active set, `solve/active.rs`; Júdice and Pires'
//! block pivoting, then Murty's single pivots), each pass one direct solve linear in the
//! bodies and contacts. Where the modes do not settle, the stage's contacts are solved by
//! projected Gauss-Seidel against the chain's exact response (`solve/delassus.rs`, Baraff
//! 1996, section 8; `O(k N)` for `k` contacts). Either way the contacts' impulses act from
//! the velocity with the joints held, so their work is booked apart from the joints'
//! ([`ContactImpulse::work_j`]). A contact point
//! the drift takes below the floor (it moves on an arc, not on its velocity's line) is moved
//! out by position, with the joints kept closed. Each impulse's work is measured over its
//! own stage ([`ContactImpulse::work_j`], [`StepReport::gravity_work_j`]).
//!
//! Each solve is the direct solve of a block-tridiagonal system (`blocks.rs`) whose block `i`
//! holds the pin's rows (body 0) and the joint to body `i + 1`: a joint touches two
//! neighbours, so the system is banded. A step whose drift would turn a body by more than
//! [`Tolerance::max_turn_rad`] (an impact at its start can spin a piece far faster than the
//! step was chosen for), or whose solve fails, is taken again as two halves
//! (`halving.rs`); so, bounded ([`ExactChain::step_bounded`]), is one whose joints do more
//! work than its bound allows: joints held exactly do none, so that work is its error.
//!
//! References: D. Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996
//! (the block-tridiagonal solve of a loop-free chain, contacts as auxiliary constraints); H.
//! C. Andersen, "Rattle: a velocity version of the Shake algorithm", J. Comput. Phys. 52, 24
//! (1983); J.-P. Ryckaert, G. Ciccotti and H. J. C. Berendsen, J. Comput. Phys. 23, 327
//! (1977) (SHAKE); J. J. Júdice and F. M. Pires, "A block principal pivoting algorithm for
//! large-scale strictly monotone linear complementarity problems", Comput. Oper. Res. 21, 587
//! (1994); K. G. Murty, "Note on a Bard-type scheme for solving the complementarity
//! problem", Opsearch 11, 123 (1974).

use super::blocks::BlockTridiag;

/// The compliance of a point moved out of the floor, relative to its own inverse effective
/// mass: it keeps the position projection's system regular when such points are redundant
/// (two ends of a link flat on the floor and a joint between them).
pub const REGULARISATION: f64 = 1e-9;

/// A rigid body of the chain, about its centre of mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Mass (kg, > 0).
    pub mass_kg: f64,
    /// Moment of inertia about the centre of mass (kg m^2, > 0).
    pub inertia_kg_m2: f64,
    /// Centre of mass (world, m).
    pub position_m: [f64; 2],
    /// Rotation of the body's axes (rad, counter-clockwise).
    pub angle_rad: f64,
    /// Velocity of the centre of mass (m/s).
    pub velocity_m_s: [f64; 2],
    /// Spin (rad/s, counter-clockwise).
    pub spin_rad_s: f64,
}

impl Body {
    /// Kinetic energy (J).
    pub fn kinetic_j(&self) -> f64 {
        let [u, w] = self.velocity_m_s;
        0.5 * self.mass_kg * (u * u + w * w) + 0.5 * self.inertia_kg_m2 * self.spin_rad_s.powi(2)
    }

    /// The world offset of a point `local` of the body's axes (from its centre, m).
    pub fn arm(&self, local: [f64; 2]) -> [f64; 2] {
        rotate(local, self.angle_rad)
    }

    /// The world position of a point `local` of the body's axes (m).
    pub fn point(&self, local: [f64; 2]) -> [f64; 2] {
        let a = self.arm(local);
        [self.position_m[0] + a[0], self.position_m[1] + a[1]]
    }

    /// The velocity of the material point at the world offset `arm` (m/s).
    pub fn velocity_at(&self, arm: [f64; 2]) -> [f64; 2] {
        let [u, w] = self.velocity_m_s;
        [u - self.spin_rad_s * arm[1], w + self.spin_rad_s * arm[0]]
    }
}

/// The revolute joint between body `i` and body `i + 1`: its anchor in each body's axes,
/// from its centre of mass (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// On body `i`.
    pub prev: [f64; 2],
    /// On body `i + 1`.
    pub next: [f64; 2],
}

/// The first body pinned to the world: its anchor (body axes, from its centre, m) held at
/// `at_m` (world, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pin {
    /// The anchor in body 0's axes (m).
    pub anchor: [f64; 2],
    /// Where the world holds it (m).
    pub at_m: [f64; 2],
}

/// The floor: the half-plane behind the line through `point_m` with unit `normal`
/// pointing out of it, with Coulomb friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// A point on the floor's surface (m).
    pub point_m: [f64; 2],
    /// The surface's unit normal, out of the floor.
    pub normal: [f64; 2],
    /// Coulomb's coefficient (>= 0).
    pub friction: f64,
}

impl Floor {
    /// The tangent along which friction is counted: the normal turned a quarter clockwise
    /// (`+x` for a floor facing `+y`).
    pub fn tangent(&self) -> [f64; 2] {
        [self.normal[1], -self.normal[0]]
    }

    /// How far `p` lies above the surface (m; negative: below).
    fn gap(&self, p: [f64; 2]) -> f64 {
        dot(
            self.normal,
            [p[0] - self.point_m[0], p[1] - self.point_m[1]],
        )
    }
}

/// A tape's midline in one body (its nodes in the body's axes, from its centre of mass) or
/// in the world (the laid tape's), each node with its place along the tape.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Outline {
    /// The nodes, in order along the tape (m); consecutive nodes bound a link.
    pub nodes: Vec<[f64; 2]>,
    /// Each node's arc length along the tape from its outer end (m), increasing.
    pub arc_m: Vec<f64>,
}

/// The tape's thickness: each body is every point within `radius_m` of its midline (a chain
/// of capsules, one a link), the laid tape a still chain of the same, and the floor meets a
/// body at its face. Bodies' layers meet each other, and the laid tape, as the floor meets
/// them: inelastic, with Coulomb friction (`solve/layers.rs`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Layers {
    /// Half the tape's thickness (m, >= 0).
    pub radius_m: f64,
    /// Coulomb's coefficient between layers (>= 0).
    pub friction: f64,
    /// Two points of the tape closer than this along it never meet (m): they are on the
    /// same layer, however tightly it is bent.
    pub exclusion_m: f64,
    /// Each body's midline, body by body.
    pub outlines: Vec<Outline>,
    /// The laid tape that no longer moves, in the world's axes; empty if none.
    pub laid: Outline,
}

/// How closely a step is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// The largest gap a joint, and the largest distance a contact point, may be left from
    /// where it belongs at the end of a step (m).
    pub position_m: f64,
    /// The most Newton iterations a step may take.
    pub max_iterations: u32,
    /// The largest angle a body may turn in a step's drift before the step is halved (rad).
    pub max_turn_rad: f64,
}

/// The largest turn of a body in one step's drift before the step is halved (rad): twice
/// the final bang's default step rule (`solver.bang_step_rad`, 0.15 rad), room for an
/// impact's spin-up.
pub const DEFAULT_MAX_TURN_RAD: f64 = 0.3;

/// The tolerance a chain of pieces `length_m` long is solved to: joints closed, and contact
/// points on the floor, within 1e-9 of that length (never finer than the coordinates'
/// rounding allows, see [`ExactChain::step`]), in at most 50 iterations, no body turning by
/// more than [`DEFAULT_MAX_TURN_RAD`] in a step.
pub fn tolerance_for(length_m: f64) -> Tolerance {
    Tolerance {
        position_m: 1e-9 * length_m,
        max_iterations: 50,
        max_turn_rad: DEFAULT_MAX_TURN_RAD,
    }
}

mod halving;
mod report;
mod solve;

pub use report::{ContactImpulse, ErrorBound, SolveStats, StepError, StepReport, Surface};

/// The chain, its joints, its pin and its floor.
#[derive(Debug)]
pub struct ExactChain {
    bodies: Vec<Body>,
    joints: Vec<Joint>,
    pin: Option<Pin>,
    /// Every body's contact points (body axes, from its centre), body by body.
    vertices: Vec<[f64; 2]>,
    /// Where body `i`'s points start in `vertices` (one more entry than bodies).
    vertex_at: Vec<usize>,
    floor: Option<Floor>,
    /// The tape's thickness and its layers' contacts, if set.
    layers: Option<Layers>,
    laid_index: solve::LaidIndex,
    tolerance: Tolerance,
    /// Each vertex's normal and friction impulse in the last stage: the next one's first
    /// guess.
    warm: Vec<[f64; 2]>,
    /// The same for the layers' contacts, by their keys, in order.
    layer_warm: Vec<(solve::Key, [f64; 2])>,
    contacts: Vec<ContactImpulse>,
    /// No step taken yet: the pin, if any, is new (see `solve/rows.rs`).
    fresh: bool,
    /// Whether the steps are bounded in their joints' error ([`Self::step_bounded`]): then
    /// a gap the joints start a step with is closed by position, not by the drift's
    /// velocity, and after a move by position the drift's velocity is held to the joints
    /// again, what that takes reported as [`StepReport::projection_j`] (part of the joints'
    /// work, which the bound counts whole).
    bounded: bool,
    /// Where the steps are bounded, the depth of halving a step starts at: one less than the
    /// deepest part of the last step, so a step grows back by one halving a step and the
    /// solves a depth it would refuse are not thrown away.
    start_depth: u32,
    /// The deepest part of the step being taken.
    deepest: u32,
    scratch: solve::Scratch,
    system: BlockTridiag,
}

impl ExactChain {
    /// A chain of `bodies` joined by `joints` (one fewer), pinned by `pin` if given, solved
    /// to `tolerance`. No body touches anything until [`Self::set_floor`].
    ///
    /// # Panics
    /// If the joints are not one fewer than the bodies.
    pub fn new(
        bodies: Vec<Body>,
        joints: Vec<Joint>,
        pin: Option<Pin>,
        tolerance: Tolerance,
    ) -> Self {
        assert_eq!(
            joints.len() + 1,
            bodies.len().max(1),
            "one joint between neighbours"
        );
        let vertex_at = vec![0; bodies.len() + 1];
        Self {
            bodies,
            joints,
            pin,
            vertices: Vec::new(),
            vertex_at,
            floor: None,
            layers: None,
            laid_index: solve::LaidIndex::default(),
            tolerance,
            warm: Vec::new(),
            layer_warm: Vec::new(),
            contacts: Vec::new(),
            fresh: true,
            bounded: false,
            start_depth: 0,
            deepest: 0,
            scratch: solve::Scratch::default(),
            system: BlockTridiag::default(),
        }
    }

    /// Puts the chain on `floor`, body `i` touching it at the points `points[i]` (body
    /// axes, from its centre, m). A point two bodies share (a joint's) belongs to one.
    ///
    /// # Panics
    /// If `points` does not have one entry per body.
    pub fn set_floor(&mut self, floor: Floor, points: &[Vec<[f64; 2]>]) {
        assert_eq!(points.len(), self.bodies.len(), "contact points per body");
        self.floor = Some(floor);
        self.vertices.clear();
        self.vertex_at.clear();
        for p in points {
            self.vertex_at.push(self.vertices.len());
            self.vertices.extend_from_slice(p);
        }
        self.vertex_at.push(self.vertices.len());
        self.warm = vec![[0.0; 2]; self.vertices.len()];
    }

    /// Gives the tape its thickness ([`Layers`]): from the next step on, the floor meets each
    /// body at its face, `layers.radius_m` below its midline, and the bodies' layers meet
    /// each other and the laid tape.
    ///
    /// # Panics
    /// If `layers` does not have one outline per body, or an outline's arcs are not one per
    /// node.
    pub fn set_layers(&mut self, layers: Layers) {
        assert_eq!(
            layers.outlines.len(),
            self.bodies.len(),
            "outlines per body"
        );
        for o in layers.outlines.iter().chain([&layers.laid]) {
            assert_eq!(o.nodes.len(), o.arc_m.len(), "one arc per node");
        }
        self.laid_index = solve::LaidIndex::new(&layers);
        self.layers = Some(layers);
        self.layer_warm.clear();
    }

    /// The tape's thickness and its layers, if set.
    pub fn layers(&self) -> Option<&Layers> {
        self.layers.as_ref()
    }

    /// Half the tape's thickness: how far below a body's midline the floor meets it (m; 0
    /// without [`Layers`]).
    fn radius_m(&self) -> f64 {
        self.layers.as_ref().map_or(0.0, |l| l.radius_m)
    }

    /// The bodies.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The bodies, to set their state (the structure stays).
    pub fn bodies_mut(&mut self) -> &mut [Body] {
        &mut self.bodies
    }

    /// The joints.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// The pin, if any.
    pub fn pin(&self) -> Option<Pin> {
        self.pin
    }

    /// Body `i`'s contact points (body axes, m).
    pub fn vertices(&self, i: usize) -> &[[f64; 2]] {
        &self.vertices[self.vertex_at[i]..self.vertex_at[i + 1]]
    }

    /// The contacts' impulses of the last step, contact point by contact point: the floor's,
    /// and the layers' on each other and on the laid tape.
    pub fn contacts(&self) -> &[ContactImpulse] {
        &self.contacts
    }

    /// The work the layers' contacts did in the last step (J; normal, friction; negative:
    /// taken from the chain): every contact not on the floor.
    pub fn layers_work_j(&self) -> [f64; 2] {
        self.contacts
            .iter()
            .filter(|c| c.on != Surface::Floor)
            .fold([0.0; 2], |w, c| [w[0] + c.work_j[0], w[1] + c.work_j[1]])
    }

    /// The position tolerance a step is solved to now: the chain's, or 4096 roundings of its
    /// largest coordinate if that is wider (m).
    pub fn position_tolerance_m(&self) -> f64 {
        solve::position_tolerance(self)
    }

    /// Kinetic energy (J).
    pub fn kinetic_j(&self) -> f64 {
        self.bodies.iter().map(Body::kinetic_j).sum()
    }

    /// The widest gap between a joint's two anchors, or the pin's anchor and its point (m).
    pub fn joint_gap_m(&self) -> f64 {
        let mut widest: f64 = 0.0;
        for (i, j) in self.joints.iter().enumerate() {
            let (a, b) = (
                self.bodies[i].point(j.prev),
                self.bodies[i + 1].point(j.next),
            );
            widest = widest.max((a[0] - b[0]).hypot(a[1] - b[1]));
        }
        if let (Some(pin), Some(first)) = (self.pin, self.bodies.first()) {
            let a = first.point(pin.anchor);
            widest = widest.max((a[0] - pin.at_m[0]).hypot(a[1] - pin.at_m[1]));
        }
        widest
    }

    /// Advances the chain by `h` (s) under `gravity` (m/s^2). On an error the chain is left
    /// as it was. The tolerance is never taken finer than 4096 roundings of the largest
    /// coordinate (9e-13 of it), which Newton's method could not reach.
    ///
    /// A step whose drift turns a body by more than [`Tolerance::max_turn_rad`] (an impact
    /// at its start can spin a piece far faster than the step was chosen for), whose drift
    /// does not close the joints, that leaves a joint open wider than a thousand position
    /// tolerances, or that fails, is taken again as two halves, down to 1/1024 of it; the
    /// report sums the halves.
    pub fn step(&mut self, h: f64, gravity: [f64; 2]) -> Result<StepReport, StepError> {
        self.bounded = false;
        self.step_within(h, gravity, 0, None)
    }

    /// [`Self::step`], with the joints' error bounded: a step (or a part of one) whose
    /// joints do work outside `bound` ([`StepReport::joint_error_j`]) is taken again in
    /// halves as well, the second half bounded by what the first left. Joints held exactly
    /// do no work, and RATTLE's error in it falls steeply with the step (on the thin tape at
    /// b/R = 1/100 a step half as long took the bang's joint work from 15 % to 0.1 % of what
    /// it dissipated: docs/final-bang.md). A step still outside its bound at 1/1024 of its
    /// length fails ([`StepError::Inaccurate`]).
    pub fn step_bounded(
        &mut self,
        h: f64,
        gravity: [f64; 2],
        bound: ErrorBound,
    ) -> Result<StepReport, StepError> {
        self.bounded = true;
        self.deepest = 0;
        let report = self.step_within(h, gravity, 0, Some(bound));
        self.start_depth = self.deepest.saturating_sub(1);
        report
    }
}

/// Which of a rigid body's `points` can touch a floor: the corners of their convex hull
/// (Andrew's monotone chain), a point on the line between two others dropped. A half-plane
/// reaches a body first at a corner; a point inside the hull or on an edge between corners
/// touches only when both ends of that edge do, and the impulse it would take is the same
/// force and moment shared between them. So the floor holds a body exactly as well by its
/// corners alone, and a piece lying flat keeps two contacts instead of one per node. Points
/// are compared exactly: points collinear only within rounding stay, harmlessly.
pub fn hull_corners(points: &[[f64; 2]]) -> Vec<bool> {
    let mut corner = vec![false; points.len()];
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a][0]
            .total_cmp(&points[b][0])
            .then(points[a][1].total_cmp(&points[b][1]))
    });
    order.dedup_by(|a, b| points[*a] == points[*b]);
    if order.len() <= 2 {
        for &i in &order {
            corner[i] = true;
        }
        return corner;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    // The lower hull left to right, then the upper right to left.
    let mut hull: Vec<usize> = Vec::with_capacity(2 * order.len());
    for pass in [order.clone(), order.iter().rev().copied().collect()] {
        let base = hull.len();
        for i in pass {
            while hull.len() >= base + 2
                && cross(
                    points[hull[hull.len() - 2]],
                    points[hull[hull.len() - 1]],
                    points[i],
                ) <= 0.0
            {
                hull.pop();
            }
            hull.push(i);
        }
    }
    for i in hull {
        corner[i] = true;
    }
    corner
}

/// `p` turned by `angle` (rad).
fn rotate(p: [f64; 2], angle: f64) -> [f64; 2] {
    let (s, c) = angle.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[cfg(test)]
mod tests;
