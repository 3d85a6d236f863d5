//! Where a step's energy went, by mechanism: the work of the floor's normal and friction
//! impulses and of the joint impulses on the links, measured on the bodies the engine moved.
//!
//! For one body over one step, with `P` the total impulse on it and `v-`, `v+` its velocity
//! before and after, the change of kinetic energy is exactly `P . (v- + v+) / 2` (kinetic
//! energy is quadratic in the velocity). Splitting `P` into the impulses of the floor
//! contacts (read from the engine, summed over its substeps), gravity and the joints, and
//! each impulse's torque by its lever arm, gives each constraint's work as its impulse
//! times the mean velocity of the point it acts on:
//!
//! ```text
//! W_c = P_c . (u_c- + u_c+) / 2
//! ```
//!
//! The engine does not keep the joints' impulses summed over a step, so they are recovered
//! from the links' momentum balance, walking the chain from its free end inward: the
//! innermost link has one joint, and each joint's impulse is what its link's momentum change
//! leaves after gravity, the floor and the next joint. An ideal rigid joint does no work
//! (its two anchors move together); what the joints do work on is their compliance, drift
//! and correction: the numerical part. What the split does not explain (a lever arm turning
//! within the step, the integration of gravity, position corrections) is the residual.
//!
//! This is bookkeeping over what the engine did, not a model of its own: it never changes
//! a body.

use rapier2d_f64::prelude::*;

/// Energy dissipated since the final bang began, by mechanism (J; positive = dissipated).
/// The parts sum to the energy the bang dissipated (`residual_j` closes the sum).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct BangLedger {
    /// Work done against the floor's normal impulses: inelastic impacts and the contact's
    /// own compliance.
    pub floor_normal_j: f64,
    /// Work done against the floor's friction impulses: sliding.
    pub floor_friction_j: f64,
    /// Work done against the joint impulses; zero for ideal rigid joints, so numerical.
    pub joints_j: f64,
    /// Kinetic energy the model discarded: the relative motion of the links joined into the
    /// bang's pieces at the release, and what pieces at rest still had when frozen.
    pub freeze_j: f64,
    /// What the split above does not explain: numerical.
    pub residual_j: f64,
}

impl BangLedger {
    /// Sum of the parts: what the bang dissipated (J).
    pub fn total_j(&self) -> f64 {
        self.floor_normal_j
            + self.floor_friction_j
            + self.joints_j
            + self.freeze_j
            + self.residual_j
    }

    /// The numerical part, `|joints_j| + |residual_j|` (J).
    pub fn numerical_j(&self) -> f64 {
        self.joints_j.abs() + self.residual_j.abs()
    }
}

/// One body's motion at the start of a step.
#[derive(Debug, Clone, Copy)]
pub(super) struct BodyState {
    pub linvel: Vector,
    pub angvel: f64,
    pub rotation: Rotation,
}

impl BodyState {
    pub fn of(body: &RigidBody) -> Self {
        Self {
            linvel: body.linvel(),
            angvel: body.angvel(),
            rotation: *body.rotation(),
        }
    }

    /// Velocity of the material point at `arm` (world frame, from the centre of mass).
    fn velocity_at(&self, arm: Vector) -> Vector {
        self.linvel + Vector::new(-self.angvel * arm.y, self.angvel * arm.x)
    }
}

/// One floor contact's impulse on the tape over the last step, split into its normal and
/// friction parts, with the lever arm the solver applied it at (world frame, from the
/// body's centre of mass). Up and +x positive.
#[derive(Debug, Clone, Copy)]
pub(super) struct FloorImpulse {
    pub body: RigidBodyHandle,
    pub normal: Vector,
    pub friction: Vector,
    pub arm: Vector,
}

/// The floor's impulses on everything touching it during the last step (summed over the
/// engine's substeps). The sign convention is pinned by the resting- and sliding-box tests.
pub(super) fn floor_impulses(
    narrow_phase: &NarrowPhase,
    colliders: &ColliderSet,
    floor: ColliderHandle,
) -> impl Iterator<Item = FloorImpulse> {
    narrow_phase
        .contact_pairs_with(floor)
        .flat_map(move |pair| {
            let PairContacts::Rigid(contacts) = &pair.contacts else {
                return Vec::new();
            };
            // The solver pushes collider 2 along +normal and collider 1 along -normal.
            let floor_first = pair.collider1 == floor;
            let (sign, other) = if floor_first {
                (1.0, pair.collider2)
            } else {
                (-1.0, pair.collider1)
            };
            let Some(body) = colliders.get(other).and_then(Collider::parent) else {
                return Vec::new();
            };
            let mut out = Vec::new();
            for manifold in contacts.solver_manifolds() {
                let n = manifold.data.normal;
                // Friction acts along perp(-n) on collider 1 and the opposite on collider 2.
                let t = Vector::new(n.y, -n.x);
                for sc in &manifold.data.solver_contacts {
                    let id = sc.contact_indices()[0] as usize;
                    let Some(point) = manifold.points.get(id) else {
                        continue;
                    };
                    let data = &point.data;
                    out.push(FloorImpulse {
                        body,
                        normal: n * (sign * data.impulse),
                        friction: t * (-sign * data.tangent_impulse.x),
                        arm: if floor_first {
                            data.solver_dp2
                        } else {
                            data.solver_dp1
                        },
                    });
                }
            }
            out
        })
}

/// A link of the chain as the work split sees it: its mass, its state before and after the
/// step, and its joints' anchors in its own frame (near node, far node).
pub(super) struct ChainLink<'a> {
    pub body: &'a RigidBody,
    pub before: BodyState,
    /// Anchor of the joint towards the laid end, in the body frame.
    pub near: Vector,
    /// Anchor of the joint towards the free end, in the body frame.
    pub far: Vector,
}

/// Work done on the chain during one step, by mechanism (J; positive = energy given to the
/// tape).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StepWork {
    pub normal_j: f64,
    pub friction_j: f64,
    pub joints_j: f64,
}

/// The work of one step: `links` run from the laid end to the free end; `pinned` says
/// whether the first is held to the world at its near node; `floor` are the floor's
/// impulses of the step, by index into `links`.
pub(super) fn step_work(
    links: &[ChainLink<'_>],
    pinned: bool,
    floor: &[(usize, FloorImpulse)],
    gravity: Vector,
    dt: f64,
) -> StepWork {
    let (mut normal_w, mut friction_w) = (0.0, 0.0);
    let mut contact_p = vec![Vector::ZERO; links.len()];
    for &(i, c) in floor {
        let link = &links[i];
        let u =
            0.5 * (link.before.velocity_at(c.arm) + BodyState::of(link.body).velocity_at(c.arm));
        normal_w += c.normal.dot(u);
        friction_w += c.friction.dot(u);
        contact_p[i] += c.normal + c.friction;
    }
    // Joint impulses from the momentum balance, free end first: the impulse on link i at
    // its near node is what its momentum change leaves after gravity, the floor and the
    // impulse of the joint at its far node (minus the impulse on link i + 1 at its near node).
    let mut joint_w = 0.0;
    let mut far_impulse = Vector::ZERO;
    for (i, link) in links.iter().enumerate().rev() {
        let body = link.body;
        let dp = (body.linvel() - link.before.linvel) * body.mass();
        let near_impulse = dp - gravity * (body.mass() * dt) - contact_p[i] - far_impulse;
        let after = BodyState::of(body);
        let anchor_u = |anchor: Vector| {
            0.5 * (link.before.velocity_at(link.before.rotation * anchor)
                + after.velocity_at(after.rotation * anchor))
        };
        let u_near = anchor_u(link.near);
        let held_u = if i > 0 {
            let prev = &links[i - 1];
            let prev_after = BodyState::of(prev.body);
            0.5 * (prev.before.velocity_at(prev.before.rotation * prev.far)
                + prev_after.velocity_at(prev_after.rotation * prev.far))
        } else if pinned {
            Vector::ZERO
        } else {
            // The tape's outer end: no joint, whatever is left is the residual's.
            u_near
        };
        joint_w += near_impulse.dot(u_near - held_u);
        far_impulse = -near_impulse;
    }
    StepWork {
        normal_j: normal_w,
        friction_j: friction_w,
        joints_j: joint_w,
    }
}
