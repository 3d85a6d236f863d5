//! The falling folded chain in the engine: `links` rigid links joined end to end by the
//! final bang's revolute impulse joints, the first pinned to the world, released from rest
//! in the scene's fold (see [`FoldedChain`]). With the floor enabled every link has a
//! segment collider that meets the floor (never another link), as the bang's pieces do.
//!
//! Each step is booked as the bang books it (`work::step_work`): the floor's normal and
//! friction work, the joints' work (each link's kinetic-energy change less gravity's and the
//! floor's work, the pin included), and the residual the split leaves of the change of
//! energy. Energies are computed from the masses and inertias as built and the bodies' poses
//! and velocities. The pin's force is the chain's momentum balance over the step.

use rapier2d_f64::prelude::*;

use super::build::floor_builder;
use super::work::{BodyState, FloorImpulse, floor_impulses, moved, step_work};
use super::{BangLedger, Model};
use crate::scene::folded::{ChainJoints, FoldedChain};

/// The chain's state after a step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChainState {
    /// Simulated time (s).
    pub t: f64,
    /// How far the free end has fallen below the pin's height (m).
    pub x_m: f64,
    /// The free end's downward speed (m/s).
    pub speed_m_s: f64,
    /// The pin's upward impulse on the chain since the start (N s).
    pub pin_impulse_ns: f64,
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Potential energy released since the start (J).
    pub released_j: f64,
    /// Work done on the chain since the start, by mechanism, as dissipated (J; positive =
    /// taken from the chain); `freeze_j` is unused.
    pub ledger: BangLedger,
}

/// The folded chain in the engine.
pub struct FoldedModel {
    world: PhysicsWorld,
    links: Vec<RigidBodyHandle>,
    floor: Option<ColliderHandle>,
    /// One link's length, mass and moment of inertia about its centre (m, kg, kg m^2).
    link: (f64, f64, f64),
    pin_height_m: f64,
    g: f64,
    state: ChainState,
    potential0_j: f64,
}

impl FoldedModel {
    /// The chain of `scene` at rest in its fold.
    pub fn new(scene: &FoldedChain) -> Self {
        let c = &scene.chain;
        let n = c.links as usize;
        let (l, m) = (c.link_m(), c.mass_kg / f64::from(c.links));
        let inertia = m * l * l / 12.0;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, -scene.gravity.g_m_s2);
        let ip = &mut world.integration_parameters;
        ip.dt = scene.solver.dt_s;
        ip.num_solver_iterations = scene.solver.substeps as usize;
        ip.num_internal_stabilization_iterations = scene.solver.relax_iterations as usize;
        ip.length_unit = l;
        ip.normalized_max_linear_velocity = Real::MAX;
        let soft = SpringCoefficients::new(
            scene.solver.contact_hz,
            ip.static_contact_softness.damping_ratio,
        );
        ip.static_contact_softness = soft;
        ip.contact_softness = soft;
        let ground = world.insert_body(
            RigidBodyBuilder::fixed().translation(Vector::new(0.0, scene.pin_height_m)),
        );
        let floor = scene.floor.enabled.then(|| {
            world.insert_collider(
                floor_builder(-scene.pin_height_m, scene.floor.friction),
                Some(ground),
            )
        });
        let nodes = fold_nodes(scene);
        let joint_soft = SpringCoefficients::new(
            scene.solver.joint_hz,
            SpringCoefficients::<Real>::joint_defaults().damping_ratio,
        );
        let (near, far) = (Vector::new(-0.5 * l, 0.0), Vector::new(0.5 * l, 0.0));
        let mut links = Vec::with_capacity(n);
        for k in 0..n {
            let (a, b) = (nodes[k], nodes[k + 1]);
            let body = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(Pose::new(0.5 * (a + b), (b - a).to_angle()))
                    .additional_mass_properties(MassProperties::new(Vector::ZERO, m, inertia))
                    .user_data(k as u128)
                    .can_sleep(false),
            );
            if floor.is_some() {
                world.insert_collider(
                    ColliderBuilder::polyline(vec![near, far], None)
                        .density(0.0)
                        .friction(scene.floor.friction)
                        .collision_groups(Model::tape_groups()),
                    Some(body),
                );
            }
            world.bodies[body].recompute_mass_properties_from_colliders(&world.colliders);
            let (parent, anchor) = match links.last() {
                None => (ground, Vector::ZERO),
                Some(&prev) => (prev, far),
            };
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(anchor)
                .local_anchor2(near)
                .contacts_enabled(false)
                .softness(joint_soft);
            match scene.solver.joints {
                ChainJoints::Impulse => {
                    world.insert_impulse_joint(parent, body, joint);
                }
                ChainJoints::Multibody => {
                    world
                        .insert_multibody_joint(parent, body, joint)
                        .expect("a chain has no loop");
                }
            }
            links.push(body);
        }
        if scene.solver.joints == ChainJoints::Multibody {
            fold_multibody(&mut world, &links, &nodes);
        }
        let mut model = Self {
            world,
            links,
            floor,
            link: (l, m, inertia),
            pin_height_m: scene.pin_height_m,
            g: scene.gravity.g_m_s2,
            state: ChainState::default(),
            potential0_j: 0.0,
        };
        model.potential0_j = model.potential_j();
        model.state = model.observe(0.0, 0.0);
        model
    }

    /// The state after the last step (at the start: at rest in the fold).
    pub fn state(&self) -> ChainState {
        self.state
    }

    /// Advances the chain by one engine step and books it.
    pub fn step(&mut self) -> ChainState {
        let dt = self.world.integration_parameters.dt;
        let before: Vec<BodyState> = self
            .links
            .iter()
            .map(|&h| BodyState::of(&self.world.bodies[h]))
            .collect();
        let energy_before = self.state.kinetic_j - self.state.released_j;
        self.world.step();
        // Each link's body holds its index along the chain.
        let contacts: Vec<(usize, FloorImpulse)> = match self.floor {
            None => Vec::new(),
            Some(floor) => floor_impulses(&self.world.narrow_phase, &self.world.colliders, floor)
                .filter_map(|(body, c)| Some((self.world.bodies.get(body)?.user_data as usize, c)))
                .collect(),
        };
        let moved = moved(&self.world.bodies, self.links.iter().copied(), &before);
        let work = step_work(&moved, &contacts, self.world.gravity, dt);
        // The chain's momentum balance: the pin's impulse is what gravity and the floor
        // leave of the momentum's change.
        let (_, m, _) = self.link;
        let dp: f64 = moved
            .iter()
            .map(|b| m * (b.after.linvel.y - b.before.linvel.y))
            .sum();
        let floor_up: f64 = contacts
            .iter()
            .map(|(_, c)| (c.normal + c.friction).y)
            .sum();
        let pin = dp - floor_up + m * self.links.len() as f64 * self.g * dt;
        let mut next = self.observe(self.state.t + dt, self.state.pin_impulse_ns + pin);
        let mut ledger = self.state.ledger;
        ledger.floor_normal_j -= work.normal_j;
        ledger.floor_friction_j -= work.friction_j;
        ledger.joints_j -= work.joints_j;
        let energy_after = next.kinetic_j - next.released_j;
        ledger.residual_j +=
            energy_before - energy_after + work.normal_j + work.friction_j + work.joints_j;
        next.ledger = ledger;
        self.state = next;
        next
    }

    /// The chain's potential energy relative to the plane y = 0 (J).
    fn potential_j(&self) -> f64 {
        let (_, m, _) = self.link;
        self.links
            .iter()
            .map(|&h| m * self.g * self.world.bodies[h].translation().y)
            .sum()
    }

    /// The state at time `t`, with the pin's impulse `pin` so far and no ledger.
    fn observe(&self, t: f64, pin: f64) -> ChainState {
        let (l, m, inertia) = self.link;
        let kinetic_j = self
            .links
            .iter()
            .map(|&h| {
                let b = &self.world.bodies[h];
                0.5 * m * b.linvel().length_squared() + 0.5 * inertia * b.angvel() * b.angvel()
            })
            .sum();
        let last = &self.world.bodies[*self.links.last().expect("at least four links")];
        let end = Vector::new(0.5 * l, 0.0);
        let tip = last.position().transform_point(end);
        let arm = tip - last.translation();
        let tip_vy = last.linvel().y + last.angvel() * arm.x;
        ChainState {
            t,
            x_m: self.pin_height_m - tip.y,
            speed_m_s: -tip_vy,
            pin_impulse_ns: pin,
            kinetic_j,
            released_j: self.potential0_j - self.potential_j(),
            ledger: BangLedger::default(),
        }
    }

    /// The lowest point of the chain now (m above the plane y = 0).
    pub fn lowest_m(&self) -> f64 {
        let end = Vector::new(0.5 * self.link.0, 0.0);
        self.links
            .iter()
            .map(|&h| {
                let p = self.world.bodies[h].position();
                p.transform_point(end).y.min(p.transform_point(-end).y)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The engine's own kinetic energy of the chain (J), to check the masses it uses.
    #[cfg(test)]
    fn engine_kinetic_j(&self) -> f64 {
        self.links
            .iter()
            .map(|&h| self.world.bodies[h].kinetic_energy())
            .sum()
    }
}

/// Puts a multibody chain into its fold: the engine sets a multibody's joint angles to
/// zero at insertion (a straight chain), so each link's angle relative to its parent is
/// applied as a displacement of its coordinate, and the default damping of every angle
/// (0.1 per unit angular velocity) is removed.
fn fold_multibody(world: &mut PhysicsWorld, links: &[RigidBodyHandle], nodes: &[Vector]) {
    let mut parent_angle = 0.0;
    for (k, &h) in links.iter().enumerate() {
        let angle = (nodes[k + 1] - nodes[k]).to_angle();
        let (mb, id) = world
            .multibody_joints
            .get_mut(MultibodyJointHandle(h.0))
            .expect("every link is in the multibody");
        let link = mb.link_mut(id).expect("the link's id is its multibody's");
        link.joint.apply_displacement(&[angle - parent_angle]);
        parent_angle = angle;
    }
    let (mb, _) = world
        .multibody_joints
        .get_mut(MultibodyJointHandle(links[0].0))
        .expect("the first link is in the multibody");
    mb.damping_mut().fill(0.0);
    mb.forward_kinematics(&world.bodies, true);
    mb.update_rigid_bodies(&mut world.bodies, true);
}

/// The nodes of the chain in its fold: the left arm straight down from the pin, the two
/// lowest links meeting at the fold across the separation, the right arm its mirror image.
fn fold_nodes(scene: &FoldedChain) -> Vec<Vector> {
    let c = &scene.chain;
    let (n, l, d, h) = (
        c.links as usize,
        c.link_m(),
        c.separation_m,
        scene.pin_height_m,
    );
    let half = n / 2;
    let mut nodes: Vec<Vector> = (0..half)
        .map(|k| Vector::new(0.0, h - k as f64 * l))
        .collect();
    nodes.push(Vector::new(0.5 * d, h - c.fold_depth_m()));
    for j in (0..half).rev() {
        let p = nodes[j];
        nodes.push(Vector::new(d - p.x, p.y));
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(extra: &str) -> FoldedModel {
        let text = format!("kind = \"folded-chain\"\n{extra}");
        FoldedModel::new(&FoldedChain::from_toml_str(&text, "test").expect("valid"))
    }

    #[test]
    fn starts_in_its_fold_at_rest() {
        let model = chain("[chain]\nlinks = 10\nseparation_m = 0.15");
        let s = model.state();
        assert!(s.x_m.abs() < 1e-12 && s.kinetic_j == 0.0 && s.released_j.abs() < 1e-12);
        let depth = 4.0 * 0.1 + (0.01f64 - 0.075 * 0.075).sqrt();
        assert!((model.lowest_m() - (1.0 - depth)).abs() < 1e-12);
        // A multibody is put into the same fold.
        let multi =
            chain("[chain]\nlinks = 10\nseparation_m = 0.15\n[solver]\njoints = \"multibody\"");
        let m = multi.state();
        assert!(
            m.x_m.abs() < 1e-12 && (multi.lowest_m() - model.lowest_m()).abs() < 1e-12,
            "{m:?}"
        );
    }

    #[test]
    fn the_engine_moves_the_masses_as_built() {
        let mut model = chain("[chain]\nlinks = 20\n[solver]\ndt_s = 1e-4");
        for _ in 0..200 {
            model.step();
        }
        let s = model.state();
        assert!(s.kinetic_j > 0.0);
        assert!((model.engine_kinetic_j() / s.kinetic_j - 1.0).abs() < 1e-9);
        // With no floor, nothing but the joints does work, and the ledger closes on them.
        let numerical = s.ledger.joints_j + s.ledger.residual_j;
        assert!((s.released_j - s.kinetic_j - numerical).abs() < 1e-12 * s.released_j);
    }
}
