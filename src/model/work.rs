//! Where a step's energy went, by mechanism: the work of the floor's normal and friction
//! impulses and of the joint impulses on the links, measured on the bodies the engine moved.
//!
//! For one body over one step, with `P` the total impulse on it and `v-`, `v+` its velocity
//! before and after, the change of kinetic energy is exactly `P . (v- + v+) / 2` (kinetic
//! energy is quadratic in the velocity), and likewise for the angular impulse. Splitting
//! `P` into the impulses of the floor contacts (read from the engine, summed over its
//! substeps), gravity and the joints gives each one's work as its impulse times the mean
//! velocity of the point it acts on:
//!
//! ```text
//! W_c = P_c . (u_c- + u_c+) / 2
//! ```
//!
//! Nothing else acts on a link, so the joints' work on it is its kinetic-energy change less
//! the work of gravity and of the floor: exact, without the joints' impulses (which the
//! engine does not keep summed over a step) or their lever arms, which turn within the step.
//! An ideal rigid joint does no work (its two anchors move together); what the joints do
//! work on is their compliance, drift and correction: the numerical part. The residual is
//! what the potential energy's change leaves of gravity's work (the integrator moves a body
//! by its velocity after the step, not the mean) and what the floor's lever arms turning
//! within a step make of its split.
//!
//! This is bookkeeping over what the engine did, not a model of its own: it never changes
//! a body.

use rapier2d_f64::prelude::*;

/// Energy dissipated since the final bang began, by mechanism (J; positive = dissipated).
/// The parts sum to the energy the bang dissipated (`residual_j` closes the sum).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BangLedger {
    /// Work done against the floor's normal impulses: inelastic impacts and the contact's
    /// own compliance.
    pub floor_normal_j: f64,
    /// Work done against the floor's friction impulses: sliding.
    pub floor_friction_j: f64,
    /// Work done against the normal impulses between the tape's own layers (a piece on
    /// another, or on the laid tape): their inelastic impacts.
    #[serde(default)]
    pub layers_normal_j: f64,
    /// Work done against the friction between the tape's own layers: rubbing.
    #[serde(default)]
    pub layers_friction_j: f64,
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
            + self.layers_normal_j
            + self.layers_friction_j
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
    pub kinetic_j: f64,
}

impl BodyState {
    pub fn of(body: &RigidBody) -> Self {
        Self {
            linvel: body.linvel(),
            angvel: body.angvel(),
            kinetic_j: body.kinetic_energy(),
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
    pub normal: Vector,
    pub friction: Vector,
    pub arm: Vector,
    /// The normal's and friction's work as the solver that applied them measured it (the
    /// exact chain applies them at the step's start, not over the whole step), J; `None`:
    /// the impulse times the mean velocity over the step.
    pub work_j: Option<[f64; 2]>,
}

impl FloorImpulse {
    /// The exact chain's impulse at a contact point: normal and friction (N s), the
    /// arm from the piece's centre of mass (m), and their work as the chain realised it (J).
    pub(super) fn of_chain(
        normal: [f64; 2],
        friction: [f64; 2],
        arm: [f64; 2],
        work_j: [f64; 2],
    ) -> Self {
        let v = |p: [f64; 2]| Vector::new(p[0], p[1]);
        Self {
            normal: v(normal),
            friction: v(friction),
            arm: v(arm),
            work_j: Some(work_j),
        }
    }
}

/// The floor's impulses on everything touching it during the last step (summed over the
/// engine's substeps), each beside the body it acts on. The sign convention is pinned by the
/// resting- and sliding-box tests.
pub(super) fn floor_impulses(
    narrow_phase: &NarrowPhase,
    colliders: &ColliderSet,
    floor: ColliderHandle,
) -> impl Iterator<Item = (RigidBodyHandle, FloorImpulse)> {
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
                    out.push((
                        body,
                        FloorImpulse {
                            normal: n * (sign * data.impulse),
                            friction: t * (-sign * data.tangent_impulse.x),
                            arm: if floor_first {
                                data.solver_dp2
                            } else {
                                data.solver_dp1
                            },
                            work_j: None,
                        },
                    ));
                }
            }
            out
        })
}

/// A body of the tape as the work split sees it: its mass, and its motion before and
/// after the step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Moved {
    pub mass: f64,
    pub before: BodyState,
    pub after: BodyState,
}

/// The bodies `handles` of `set` as the work split sees them, each beside its state
/// `before` the step (in the same order).
pub(super) fn moved(
    set: &RigidBodySet,
    handles: impl Iterator<Item = RigidBodyHandle>,
    before: &[BodyState],
) -> Vec<Moved> {
    handles
        .zip(before)
        .map(|(h, &before)| Moved {
            mass: set[h].mass(),
            before,
            after: BodyState::of(&set[h]),
        })
        .collect()
}

/// Work done on the tape during one step, by mechanism (J; positive = energy given to the
/// tape).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StepWork {
    pub normal_j: f64,
    pub friction_j: f64,
    pub joints_j: f64,
}

/// The work of one step on `bodies`; `floor` are the floor's impulses of the step, by index
/// into `bodies`; `gravity_work_j` gravity's work if the solver measured it (the exact
/// chain's half kicks), else gravity's impulse times each body's mean velocity over the
/// step; `layers_j` the work of the contacts between the tape's layers, as the solver
/// measured it (J), which is not the joints'.
pub(super) fn step_work(
    bodies: &[Moved],
    floor: &[(usize, FloorImpulse)],
    gravity: Vector,
    dt: f64,
    (gravity_work_j, layers_j): (Option<f64>, f64),
) -> StepWork {
    let (mut normal_w, mut friction_w) = (0.0, 0.0);
    let mut floor_w = vec![0.0; bodies.len()];
    for &(i, c) in floor {
        let [n, f] = c.work_j.unwrap_or_else(|| {
            let m = &bodies[i];
            let u = 0.5 * (m.before.velocity_at(c.arm) + m.after.velocity_at(c.arm));
            [c.normal.dot(u), c.friction.dot(u)]
        });
        normal_w += n;
        friction_w += f;
        floor_w[i] += n + f;
    }
    // The joints' impulses are the rest of each body's momentum change, so their work is
    // the rest of the kinetic-energy change: exact, with no lever arm to guess.
    let joint_w: f64 = match gravity_work_j {
        Some(gravity_w) => {
            let kinetic: f64 = bodies
                .iter()
                .map(|m| m.after.kinetic_j - m.before.kinetic_j)
                .sum();
            kinetic - gravity_w - normal_w - friction_w - layers_j
        }
        None => bodies
            .iter()
            .zip(&floor_w)
            .map(|(m, &floor)| {
                let gravity_w =
                    (gravity * (m.mass * dt)).dot(0.5 * (m.before.linvel + m.after.linvel));
                m.after.kinetic_j - m.before.kinetic_j - gravity_w - floor
            })
            .sum(),
    };
    StepWork {
        normal_j: normal_w,
        friction_j: friction_w,
        joints_j: joint_w,
    }
}

#[cfg(test)]
mod tests;
