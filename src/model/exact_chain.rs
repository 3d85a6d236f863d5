//! The exact chain: rigid bodies in a row joined end to end by revolute joints, the first
//! optionally pinned to the world, on an optional frictional floor. Each step solves the
//! joints exactly and the floor's contacts to a stated tolerance, in time linear in the
//! number of bodies. Pure `f64`: it uses no engine, and knows nothing of coils or ledgers.
//!
//! Each body has maximal coordinates `q = (x, y, theta)` about its centre of mass and a
//! constant diagonal mass matrix `M = diag(m, m, I)`: in the plane the configuration space is
//! flat, so the chain's equations are those of particles with holonomic constraints, and
//! the step is SHAKE's (Ryckaert, Ciccotti & Berendsen 1977), symplectic and second order:
//!
//! ```text
//! v+ = v + h g + M^-1 (G(q)^T lambda + C(q)^T p)      impulses along the start's normals
//! q+ = q + h v+                                         (theta+ = theta + h omega+)
//! g(q+) = 0                                             every joint closed at the step's end
//! ```
//!
//! `g` is every joint's gap (the two anchors' world points, 2 rows each; the pin's anchor
//! and its world point, 2 rows). The joints' impulses act along the start's Jacobian `G(q)`
//! and close the gaps at the end's, so their work over a smooth motion is of second order in
//! the step and does not accumulate; an exact step of a free chain keeps its momentum and
//! angular momentum to the solve's tolerance. The floor's contacts are inelastic, with
//! Coulomb friction: a contact point (a body's vertex within reach of the floor) either
//! leaves (`p = 0`), or ends the step on the floor (its predicted gap zero, `p_n >= 0`) and
//! sticks (`u_t+ = 0`, `|p_t| <= mu p_n`) or slides (`p_t = -mu p_n sign(u_t+)`), the
//! tangential velocity `u_t+` taken at the start's pose, the one its impulse acts at.
//!
//! The nonlinear system is solved by Newton's method on the joints' and contacts' gaps,
//! with the contacts' modes (off, stick, slide) chosen anew at each iteration: a direct
//! solve of a block-tridiagonal system each time ([`blocks`]), whose block `i` holds body
//! `i`'s contact rows and the joint to body `i + 1`. A contact touches one body and a joint
//! two neighbours, so the system stays banded whatever the contacts. Redundant contacts (a
//! straight chain sticking on the floor at every node) make it singular; each contact row
//! carries a compliance of [`REGULARISATION`] times its own inverse effective mass, far
//! below the tolerance. The step ends when the modes no longer change and every gap is
//! within the tolerance; a step that reaches the iteration cap first is reported as missed.
//!
//! References: D. Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996
//! (the block-tridiagonal solve of a loop-free chain); J.-P. Ryckaert, G. Ciccotti and H. J.
//! C. Berendsen, J. Comput. Phys. 23, 327 (1977) (SHAKE).

mod blocks;

use blocks::BlockTridiag;

/// A contact row's compliance, relative to its own inverse effective mass: it keeps the
/// system regular when contacts are redundant, and moves a contact's velocity by this
/// fraction of its impulse's effect.
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

/// How closely a step is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// The largest gap a joint, and the largest distance a contact point, may be left from
    /// where it belongs at the end of a step (m).
    pub position_m: f64,
    /// The most Newton iterations a step may take.
    pub max_iterations: u32,
}

/// The floor's impulse on one body during a step, where it acted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactImpulse {
    /// The body's index along the chain.
    pub body: usize,
    /// The vertex's index among the body's contact points.
    pub vertex: usize,
    /// Along the floor's normal (N s).
    pub normal_n_s: [f64; 2],
    /// Along its surface: friction (N s).
    pub friction_n_s: [f64; 2],
    /// From the body's centre of mass to the contact point, at the step's start (m).
    pub arm_m: [f64; 2],
}

/// How a step was solved.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations taken (each one direct solve).
    pub iterations: u32,
    /// Whether every gap came within the tolerance and every contact's mode settled.
    pub converged: bool,
    /// The widest joint gap left at the step's end (m).
    pub joint_gap_m: f64,
    /// The deepest a contact point ended below the floor (m; 0 if none).
    pub penetration_m: f64,
}

/// Why a step could not be taken. The chain is left as it was before the step.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The constraints' system was singular at block `block` (the body of that index).
    #[error("the exact chain's system is singular at body {block}")]
    Singular {
        /// The block whose pivot vanished.
        block: usize,
    },
    /// The solve gave a non-finite impulse or velocity.
    #[error("the exact chain's solve gave a non-finite value")]
    NonFinite,
}

/// A contact point's state in the solve.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    Off,
    /// On the floor, frictionless.
    Normal,
    Stick,
    /// Sliding in direction `+1` or `-1` along the floor's tangent.
    Slide(f64),
}

mod solve;

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
    tolerance: Tolerance,
    /// Each vertex's mode at the end of the last step: the next step's first guess.
    modes: Vec<Mode>,
    contacts: Vec<ContactImpulse>,
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
            tolerance,
            modes: Vec::new(),
            contacts: Vec::new(),
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
        self.modes = vec![Mode::Off; self.vertices.len()];
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

    /// The floor's impulses of the last step, contact point by contact point.
    pub fn contacts(&self) -> &[ContactImpulse] {
        &self.contacts
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
    /// as it was.
    pub fn step(&mut self, h: f64, gravity: [f64; 2]) -> Result<StepReport, StepError> {
        solve::step(self, h, gravity)
    }
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
