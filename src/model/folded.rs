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
use super::exact_chain::{
    self, Body, ExactChain, Floor, Joint, Layers, Outline, Pin, SolveStats, StepError, Surface,
};
use super::work::{BodyState, FloorImpulse, Moved, floor_impulses, step_work};
use super::{BangLedger, Model};
use crate::scene::folded::{ChainJoints, FoldedChain, Start};

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
    /// The floor's upward impulse on the chain since the start (N s).
    pub floor_impulse_ns: f64,
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Potential energy released since the start (J).
    pub released_j: f64,
    /// Work done on the chain since the start, by mechanism, as dissipated (J; positive =
    /// taken from the chain); `freeze_j` is unused.
    pub ledger: BangLedger,
}

/// What steps the chain: rapier's world (impulse or multibody joints), or the exact chain.
enum Engine {
    Rapier {
        world: Box<PhysicsWorld>,
        links: Vec<RigidBodyHandle>,
        floor: Option<ColliderHandle>,
    },
    Exact(Box<ExactChain>),
}

/// The folded chain in the engine.
pub struct FoldedModel {
    engine: Engine,
    /// One link's length, mass and moment of inertia about its centre (m, kg, kg m^2).
    link: (f64, f64, f64),
    dt: f64,
    pin_height_m: f64,
    g: f64,
    state: ChainState,
    potential0_j: f64,
    solve: SolveStats,
}

impl FoldedModel {
    /// The chain of `scene` at rest in its fold.
    pub fn new(scene: &FoldedChain) -> Self {
        let c = &scene.chain;
        let (l, m, b) = (c.link_m(), c.mass_kg / f64::from(c.links), c.thickness_m);
        // A link with a thickness turns as a rod of it (a rectangle l by b; the round ends'
        // share is left out, as the tape's pieces leave it).
        let inertia = m * (l * l + b * b) / 12.0;
        let nodes = match scene.start {
            Start::Fold => fold_nodes(scene),
            Start::Hanging { tilt_rad } => hanging_nodes(scene, tilt_rad),
        };
        let engine = match scene.solver.joints {
            ChainJoints::Exact => Engine::Exact(Box::new(exact_fold(scene, &nodes, m, inertia))),
            _ => rapier_fold(scene, &nodes, m, inertia),
        };
        let mut model = Self {
            engine,
            link: (l, m, inertia),
            dt: scene.solver.dt_s,
            pin_height_m: scene.pin_height_m,
            g: scene.gravity.g_m_s2,
            state: ChainState::default(),
            potential0_j: 0.0,
            solve: SolveStats::default(),
        };
        let links = model.links();
        model.potential0_j = model.potential_j(&links);
        model.state = model.observe(&links, 0.0, (0.0, 0.0));
        model
    }

    /// The state after the last step (at the start: at rest in the fold).
    pub fn state(&self) -> ChainState {
        self.state
    }

    /// How the exact chain's steps were solved so far (all zero on rapier's joints).
    pub fn solve_stats(&self) -> SolveStats {
        self.solve
    }

    /// Advances the chain by one step and books it. On the exact chain's failure the chain
    /// is left as it was.
    pub fn step(&mut self) -> Result<ChainState, StepError> {
        let dt = self.dt;
        let before = self.links();
        let energy_before = self.state.kinetic_j - self.state.released_j;
        let g = self.g;
        // Each of the floor's contacts beside the index of its link along the chain; the
        // work the links' contacts on each other did (normal, friction).
        let mut gravity_work = None;
        let mut layers = [0.0; 2];
        let contacts: Vec<(usize, FloorImpulse)> = match &mut self.engine {
            Engine::Rapier { world, floor, .. } => {
                world.step();
                match *floor {
                    None => Vec::new(),
                    Some(floor) => floor_impulses(&world.narrow_phase, &world.colliders, floor)
                        .filter_map(|(body, c)| {
                            Some((world.bodies.get(body)?.user_data as usize, c))
                        })
                        .collect(),
                }
            }
            Engine::Exact(chain) => {
                let report = chain.step(dt, [0.0, -g])?;
                self.solve.add(&report);
                gravity_work = Some(report.gravity_work_j);
                layers = chain.layers_work_j();
                chain
                    .contacts()
                    .iter()
                    .filter(|c| c.on == Surface::Floor)
                    .map(exact_chain_impulse)
                    .collect()
            }
        };
        let after = self.links();
        let (_, m, _) = self.link;
        let moved: Vec<Moved> = before
            .iter()
            .zip(&after)
            .map(|(a, b)| Moved {
                mass: m,
                before: body_state(a),
                after: body_state(b),
            })
            .collect();
        let work = step_work(
            &moved,
            &contacts,
            Vector::new(0.0, -g),
            dt,
            (gravity_work, layers[0] + layers[1]),
        );
        // The chain's momentum balance: the pin's impulse is what gravity and the floor
        // leave of the momentum's change.
        let dp: f64 = moved
            .iter()
            .map(|b| m * (b.after.linvel.y - b.before.linvel.y))
            .sum();
        let floor_up: f64 = contacts
            .iter()
            .map(|(_, c)| (c.normal + c.friction).y)
            .sum();
        let pin = dp - floor_up + m * after.len() as f64 * g * dt;
        let impulses = (
            self.state.pin_impulse_ns + pin,
            self.state.floor_impulse_ns + floor_up,
        );
        let mut next = self.observe(&after, self.state.t + dt, impulses);
        let mut ledger = self.state.ledger;
        ledger.floor_normal_j -= work.normal_j;
        ledger.floor_friction_j -= work.friction_j;
        ledger.layers_normal_j -= layers[0];
        ledger.layers_friction_j -= layers[1];
        ledger.joints_j -= work.joints_j;
        let energy_after = next.kinetic_j - next.released_j;
        ledger.residual_j += energy_before - energy_after
            + work.normal_j
            + work.friction_j
            + layers[0]
            + layers[1]
            + work.joints_j;
        next.ledger = ledger;
        self.state = next;
        Ok(next)
    }

    /// Every link's state, from the pin on: the exact chain's bodies, or the engine's read
    /// as such (each link's centre of mass is its centre).
    fn links(&self) -> Vec<Body> {
        let (_, m, inertia) = self.link;
        match &self.engine {
            Engine::Exact(chain) => chain.bodies().to_vec(),
            Engine::Rapier { world, links, .. } => links
                .iter()
                .map(|&h| {
                    let b = &world.bodies[h];
                    let (p, v) = (b.translation(), b.linvel());
                    Body {
                        mass_kg: m,
                        inertia_kg_m2: inertia,
                        position_m: [p.x, p.y],
                        angle_rad: b.rotation().angle(),
                        velocity_m_s: [v.x, v.y],
                        spin_rad_s: b.angvel(),
                    }
                })
                .collect(),
        }
    }

    /// The chain's potential energy relative to the plane y = 0 (J).
    fn potential_j(&self, links: &[Body]) -> f64 {
        let (_, m, _) = self.link;
        links.iter().map(|b| m * self.g * b.position_m[1]).sum()
    }

    /// The state at time `t` of `links`, with the pin's and the floor's impulses so far and
    /// no ledger. The free end is the last link's far node: the fold's free end, or a
    /// hanging chain's top.
    fn observe(&self, links: &[Body], t: f64, (pin, floor): (f64, f64)) -> ChainState {
        let (l, _, _) = self.link;
        let kinetic_j = links.iter().map(Body::kinetic_j).sum();
        let last = links.last().expect("at least four links");
        let arm = last.arm([0.5 * l, 0.0]);
        let tip = last.point([0.5 * l, 0.0]);
        ChainState {
            t,
            x_m: self.pin_height_m - tip[1],
            speed_m_s: -last.velocity_at(arm)[1],
            pin_impulse_ns: pin,
            floor_impulse_ns: floor,
            kinetic_j,
            released_j: self.potential0_j - self.potential_j(links),
            ledger: BangLedger::default(),
        }
    }

    /// The lowest point of the chain now (m above the plane y = 0).
    pub fn lowest_m(&self) -> f64 {
        let l = self.link.0;
        self.links()
            .iter()
            .map(|b| b.point([0.5 * l, 0.0])[1].min(b.point([-0.5 * l, 0.0])[1]))
            .fold(f64::INFINITY, f64::min)
    }

    /// The engine's own kinetic energy of the chain (J), to check the masses it uses.
    #[cfg(test)]
    fn engine_kinetic_j(&self) -> f64 {
        match &self.engine {
            Engine::Rapier { world, links, .. } => links
                .iter()
                .map(|&h| world.bodies[h].kinetic_energy())
                .sum(),
            Engine::Exact(chain) => chain.kinetic_j(),
        }
    }
}

/// The work split's view of a link's motion.
fn body_state(b: &Body) -> BodyState {
    BodyState {
        linvel: Vector::new(b.velocity_m_s[0], b.velocity_m_s[1]),
        angvel: b.spin_rad_s,
        kinetic_j: b.kinetic_j(),
    }
}

/// An exact chain's contact as the work split books it, beside its body's index.
pub(super) fn exact_chain_impulse(c: &exact_chain::ContactImpulse) -> (usize, FloorImpulse) {
    (
        c.body,
        FloorImpulse::of_chain(c.normal_n_s, c.friction_n_s, c.arm_m, c.work_j),
    )
}

/// The chain at its start on the exact chain: each link a body about its centre; in its
/// fold pinned at its first node, hanging free. On the floor each link touches it at its far
/// node (its near node is the pin's or the link before's; a hanging chain's first link
/// touches at both). With a thickness, the links are the tape's layers ([`Layers`]): the
/// floor meets them at their faces, and they meet each other.
fn exact_fold(scene: &FoldedChain, nodes: &[Vector], m: f64, inertia: f64) -> ExactChain {
    let l = scene.chain.link_m();
    let bodies = nodes
        .windows(2)
        .map(|w| {
            let c = 0.5 * (w[0] + w[1]);
            Body {
                mass_kg: m,
                inertia_kg_m2: inertia,
                position_m: [c.x, c.y],
                angle_rad: (w[1] - w[0]).to_angle(),
                velocity_m_s: [0.0, 0.0],
                spin_rad_s: 0.0,
            }
        })
        .collect::<Vec<_>>();
    let joints = vec![
        Joint {
            prev: [0.5 * l, 0.0],
            next: [-0.5 * l, 0.0],
        };
        bodies.len() - 1
    ];
    let pin = (scene.start == Start::Fold).then_some(Pin {
        anchor: [-0.5 * l, 0.0],
        at_m: [nodes[0].x, nodes[0].y],
    });
    let n = bodies.len();
    let mut chain = ExactChain::new(bodies, joints, pin, exact_chain::tolerance_for(l));
    let (near, far) = ([-0.5 * l, 0.0], [0.5 * l, 0.0]);
    if scene.floor.enabled {
        let floor = Floor {
            point_m: [0.0, 0.0],
            normal: [0.0, 1.0],
            friction: scene.floor.friction,
        };
        let mut points = vec![vec![far]; n];
        if pin.is_none() {
            points[0] = vec![near, far];
        }
        chain.set_floor(floor, &points);
    }
    let b = scene.chain.thickness_m;
    if b > 0.0 {
        chain.set_layers(Layers {
            radius_m: 0.5 * b,
            friction: scene.floor.friction,
            // The tightest fold, a half turn about a link's end, is pi b / 2 long along
            // the chain's axis: closer points are on the same layer.
            exclusion_m: std::f64::consts::FRAC_PI_2 * b,
            outlines: (0..n)
                .map(|i| Outline {
                    nodes: vec![near, far],
                    arc_m: vec![i as f64 * l, (i + 1) as f64 * l],
                })
                .collect(),
            laid: Outline::default(),
        });
    }
    chain
}

/// The chain in its fold in rapier's world, with the scene's joints.
fn rapier_fold(scene: &FoldedChain, nodes: &[Vector], m: f64, inertia: f64) -> Engine {
    let l = scene.chain.link_m();
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
    let ground = world
        .insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, scene.pin_height_m)));
    let floor = scene.floor.enabled.then(|| {
        world.insert_collider(
            floor_builder(-scene.pin_height_m, scene.floor.friction),
            Some(ground),
        )
    });
    let joint_soft = SpringCoefficients::new(
        scene.solver.joint_hz,
        SpringCoefficients::<Real>::joint_defaults().damping_ratio,
    );
    let (near, far) = (Vector::new(-0.5 * l, 0.0), Vector::new(0.5 * l, 0.0));
    let mut links = Vec::with_capacity(nodes.len() - 1);
    for (k, w) in nodes.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
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
        if scene.solver.joints == ChainJoints::Multibody {
            world
                .insert_multibody_joint(parent, body, joint)
                .expect("a chain has no loop");
        } else {
            world.insert_impulse_joint(parent, body, joint);
        }
        links.push(body);
    }
    if scene.solver.joints == ChainJoints::Multibody {
        fold_multibody(&mut world, &links, nodes);
    }
    Engine::Rapier {
        world: Box::new(world),
        links,
        floor,
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

/// The nodes of a hanging chain, from the floor up: the lower end at half the thickness
/// above it (its face on the floor), each link `tilt_rad` from the vertical, alternately
/// either way.
fn hanging_nodes(scene: &FoldedChain, tilt_rad: f64) -> Vec<Vector> {
    let c = &scene.chain;
    let l = c.link_m();
    let (s, co) = tilt_rad.sin_cos();
    let mut nodes = vec![Vector::new(0.0, 0.5 * c.thickness_m)];
    for k in 0..c.links as usize {
        let side = if k % 2 == 0 { 1.0 } else { -1.0 };
        let p = nodes[k];
        nodes.push(p + Vector::new(side * l * s, l * co));
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
            model.step().expect("steps");
        }
        let s = model.state();
        assert!(s.kinetic_j > 0.0);
        assert!((model.engine_kinetic_j() / s.kinetic_j - 1.0).abs() < 1e-9);
        // With no floor, nothing but the joints does work, and the ledger closes on them.
        let numerical = s.ledger.joints_j + s.ledger.residual_j;
        assert!((s.released_j - s.kinetic_j - numerical).abs() < 1e-12 * s.released_j);
    }
}
