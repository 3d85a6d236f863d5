//! The contact-resolved model: the tape as thin rigid links in rapier2d. This is the only
//! module that imports the engine; it knows nothing of references, files or reports.
//!
//! What is modelled, and why only that:
//! - The wound part is one rigid body (the coil) whose mass properties are the exact sum
//!   of its links (chords of the spiral, mass on the midline). Locked joint chains cannot
//!   hold a wound coil, so the wound links are not separate bodies.
//! - The coil touches the floor through a ball that is refitted every step to the
//!   osculating circle of the midline spiral at its current lowest point, so the contact is
//!   truly curved and the coil rolls on the spiral itself. The floor's contact plane is the
//!   laid tape's midline plane, `y = b/2`: the inextensible midline rolls without slip, and
//!   the zero-velocity point is the midline peel point.
//! - A link leaves the coil when the coil's lowest point passes the link's far node; it
//!   becomes a body with a segment collider, joined by revolute joints to its neighbours.
//! - A laid link whose nodes have stopped moving is frozen: removed from the engine, its
//!   potential energy kept, its neighbour pinned to the world at the shared node. No body
//!   exists for the wound links or the resting tape, so a step costs the same whatever the
//!   number of links.
//! - When the coil's equivalent radius reaches the bang radius, the remaining links are
//!   released as a free chain and the final bang is resolved by contact.
//!
//! - Variants (App. A-E): a slope tilts gravity in this frame (the floor stays `y = b/2`);
//!   a core makes a spool; with no friction the coil starts spinning in place; a sticky floor
//!   holds the coil bilaterally at its contact; a fixed axis pins the spiral's centre and
//!   turns the picture by a quarter turn, so the tape leaves at the side and hangs.
//!
//! Every change of energy is measured where it happens, into an [`EnergyLedger`].

use std::collections::VecDeque;
use std::f64::consts::PI;

use rapier2d_f64::prelude::*;
use serde::Serialize;

use crate::scene::Scene;
use crate::spiral::{Spiral, SpiralMoments, rotate};

/// Where the energy went, each part measured where it happens (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EnergyLedger {
    /// Lost inside engine steps while the coil rolls (contacts, joints, integration).
    pub step_j: f64,
    /// Lost (or gained, if negative) when a link leaves the coil.
    pub detach_j: f64,
    /// Kinetic energy discarded when laid links were frozen while the coil rolls.
    pub freeze_j: f64,
    /// Lost from the start of the final bang on (steps and freezes alike).
    pub bang_j: f64,
}

impl EnergyLedger {
    /// Sum of all losses (J).
    pub fn total_j(&self) -> f64 {
        self.step_j + self.detach_j + self.freeze_j + self.bang_j
    }
}

/// The phase of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// The coil rolls and sheds links.
    Rolling,
    /// The remaining links were released and the final bang is being resolved.
    Bang,
    /// Nothing more to simulate.
    Done,
}

/// What the model reports after each step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Observation {
    /// Simulated time (s).
    pub t_s: f64,
    /// Phase after this step.
    pub phase: Phase,
    /// Laid mass fraction, measured along the continuous spiral up to the lowest point.
    pub laid_fraction: f64,
    /// Spiral parameter of the coil's lowest midline point (rad).
    pub psi_low: f64,
    /// Contact-line position: x of the coil's lowest midline point (m).
    pub x_m: f64,
    /// Clockwise spin of the coil (rad/s).
    pub omega_rad_s: f64,
    /// Kinetic energy of everything that moves (J).
    pub kinetic_j: f64,
    /// Potential energy of the whole tape above the floor, y = 0 (J).
    pub potential_j: f64,
    /// Upward force of the floor on the tape's moving part (N), from contact impulses.
    pub normal_n: f64,
    /// Horizontal force of the floor on the tape's moving part, +x positive (N).
    pub friction_n: f64,
    /// The energy ledger so far.
    pub ledger: EnergyLedger,
    /// Links that have left the coil.
    pub detached: usize,
    /// Bodies in the engine (coil and moving links).
    pub active_bodies: usize,
    /// Largest joint separation among the active joints (m).
    pub max_joint_gap_m: f64,
    /// Deepest penetration of a collider into the floor (m).
    pub max_penetration_m: f64,
    /// The last step's length (s).
    pub dt_s: f64,
    /// Linear momentum of everything that moves, `sum m v` (kg m/s).
    pub momentum_kg_m_s: [f64; 2],
}

/// Diagnostics of the world after a step, read by the run's guards ([`Model::health`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Health {
    /// Horizontal speed of the coil's material point at its lowest midline point (m/s),
    /// zero when it rolls without slipping; `None` once the coil is released.
    pub slip_m_s: Option<f64>,
    /// Largest distance of a moving body's centre of mass from the start of the tape (m).
    pub farthest_m: f64,
    /// Lowest centre of mass of a moving body, negative below the floor (m).
    pub lowest_m: f64,
    /// Fastest spin of a moving body (rad/s).
    pub max_spin_rad_s: f64,
    /// Every moving body's position and velocity are finite.
    pub finite: bool,
}

/// One link of the discretised tape: a chord of the spiral between two nodes.
#[derive(Debug, Clone, Copy)]
struct Link {
    /// Node towards the laid end (body frame of the coil).
    near: [f64; 2],
    /// Node towards the centre.
    far: [f64; 2],
    mass_kg: f64,
    length_m: f64,
    /// Chord over arc length of the spiral between the nodes.
    chord_ratio: f64,
    /// How far the node line sits below the contact surface (m), see [`Model`].
    inset_m: f64,
}

impl Link {
    fn centre(&self) -> [f64; 2] {
        [
            0.5 * (self.near[0] + self.far[0]),
            0.5 * (self.near[1] + self.far[1]),
        ]
    }

    /// Angle of the chord from far to near node, in the coil frame.
    fn angle(&self) -> f64 {
        (self.near[1] - self.far[1]).atan2(self.near[0] - self.far[0])
    }
}

/// A link that left the coil and is simulated as its own body.
#[derive(Debug, Clone, Copy)]
struct FreeLink {
    index: usize,
    body: RigidBodyHandle,
}

/// Running sums of the coil's mass moments in its body frame.
#[derive(Debug, Clone, Copy, Default)]
struct CoilSums {
    mass: f64,
    first: [f64; 2],
    /// Second moment about the body origin, own inertia of each link included.
    second: f64,
}

impl CoilSums {
    fn add(&mut self, link: &Link, sign: f64) {
        let c = link.centre();
        let m = sign * link.mass_kg;
        self.mass += m;
        self.first[0] += m * c[0];
        self.first[1] += m * c[1];
        self.second += m * (c[0] * c[0] + c[1] * c[1] + link.length_m * link.length_m / 12.0);
    }

    fn mass_properties(&self) -> MassProperties {
        let com = [self.first[0] / self.mass, self.first[1] / self.mass];
        let inertia = self.second - self.mass * (com[0] * com[0] + com[1] * com[1]);
        MassProperties::new(Vector::new(com[0], com[1]), self.mass, inertia.max(0.0))
    }
}

const TAPE_GROUP: Group = Group::GROUP_1;
const FLOOR_GROUP: Group = Group::GROUP_2;

/// The force of a floor collider on everything touching it during the last step, from
/// the contact impulses divided by `dt`: `(normal, horizontal)` in N, upward and +x
/// positive. The sign convention is pinned by the resting- and sliding-box tests.
pub fn floor_forces(narrow_phase: &NarrowPhase, floor: ColliderHandle, dt: f64) -> (f64, f64) {
    if dt <= 0.0 {
        return (0.0, 0.0);
    }
    let (mut fx, mut fy) = (0.0, 0.0);
    for pair in narrow_phase.contact_pairs_with(floor) {
        let PairContacts::Rigid(contacts) = &pair.contacts else {
            continue;
        };
        // The solver pushes collider 2 along +normal and collider 1 along -normal.
        let sign = if pair.collider1 == floor { 1.0 } else { -1.0 };
        for manifold in contacts.solver_manifolds() {
            let n = manifold.data.normal;
            // Friction acts along perp(-n) on collider 1 and the opposite on collider 2.
            let t = Vector::new(n.y, -n.x);
            for point in &manifold.points {
                let f = n * point.data.impulse - t * point.data.tangent_impulse.x;
                fx += sign * f.x / dt;
                fy += sign * f.y / dt;
            }
        }
    }
    (fy, fx)
}

/// The contact-resolved tape.
pub struct Model {
    world: PhysicsWorld,
    spiral: Spiral,
    moments: SpiralMoments,
    links: Vec<Link>,
    link_angle: f64,
    steps_per_link: f64,
    max_dt: f64,
    freeze_speed: f64,
    bang_step_rad: f64,
    /// Softness of every joint (see `Solver::joint_hz`).
    joint_softness: SpringCoefficients<Real>,
    friction: f64,
    /// Gravity across the floor, `g cos(alpha)`, pulling towards it (m/s^2).
    g: f64,
    /// Gravity along the floor, `g sin(alpha)`, towards +x (m/s^2); 0 on a level floor.
    g_along: f64,
    /// First moment `sum m_k x_k` of the tape lying flat from `x = 0` (kg m).
    flat_first_moment: f64,
    half_b: f64,
    bang_fraction: f64,
    settle_time: f64,
    total_mass: f64,

    ground: RigidBodyHandle,
    floor: ColliderHandle,
    coil: Option<RigidBodyHandle>,
    coil_ball: Option<ColliderHandle>,
    /// A sticky floor's hold on the coil, moved every step: no slip at the contact line
    /// (x locked) and the contact ball's centre at its height (y locked).
    stick: Option<[ImpulseJointHandle; 2]>,
    coil_sums: CoilSums,
    /// Index of the outermost link still in the coil.
    first_attached: usize,
    /// Unwrapped rotation angle of the coil (rad).
    coil_angle: f64,
    /// The coil's rotation minus that of a rolling coil with the same point leaving it:
    /// 0 on the floor, pi/2 on a fixed axis, where the tape leaves at the side (rad).
    angle_offset: f64,
    psi_low: f64,

    free: VecDeque<FreeLink>,
    frozen_potential_j: f64,
    /// Near node of each frozen link, from the outer end, and the far node of the last one
    /// (world frame, m): frozen links have no body left to ask.
    frozen_nodes: Vec<[f64; 2]>,

    ledger: EnergyLedger,
    phase: Phase,
    t: f64,
    bang_started_s: f64,
    last_dt: f64,
    x_low: f64,
    chord_ratio: f64,
    shedding: bool,
    /// Kinetic plus potential energy at the last observation, the next step's start (J).
    energy_j: f64,
}

impl Model {
    /// Builds the world for a scene: floor, the wound coil as one body, nothing else.
    pub fn new(scene: &Scene) -> Self {
        let tape = &scene.tape;
        let b = tape.thickness_m;
        let spiral = Spiral::wound(tape.outer_radius_m, b, tape.core_radius_m);
        let moments = SpiralMoments::new(spiral);
        let nodes = spiral.link_nodes(scene.links_per_turn);
        let mut links: Vec<Link> = nodes
            .windows(2)
            .map(|w| {
                let (near, far) = (spiral.point(w[0]), spiral.point(w[1]));
                let length_m = (near[0] - far[0]).hypot(near[1] - far[1]);
                let chord_ratio = length_m / spiral.arc(w[1], w[0]);
                Link {
                    near,
                    far,
                    mass_kg: 0.0,
                    length_m,
                    chord_ratio,
                    inset_m: spiral.curvature_radius(w[0]) * (1.0 - chord_ratio),
                }
            })
            .collect();
        let total_len: f64 = links.iter().map(|l| l.length_m).sum();
        for link in &mut links {
            link.mass_kg = tape.mass_kg * link.length_m / total_len;
        }

        let mut world = PhysicsWorld::new();
        // A slope tilts gravity in the simulation frame; the floor stays the plane y = b/2.
        let (sin_a, cos_a) = scene.slope_deg.to_radians().sin_cos();
        let (g_along, g_perp) = (scene.g_m_s2 * sin_a, scene.g_m_s2 * cos_a);
        world.gravity = Vector::new(g_along, -g_perp);
        let ip = &mut world.integration_parameters;
        ip.num_solver_iterations = scene.solver.iterations as usize;
        // The engine's tolerances (contact prediction, corrective speed) are fractions of
        // `length_unit`: the coil's size sets the scale of what moves.
        ip.length_unit = 0.1 * tape.outer_radius_m;
        // The engine clamps speeds at `normalized_max_linear_velocity * length_unit` (2.4 m/s
        // for the yoga mat): the end of an unroll is far faster than that, so lift the cap.
        ip.normalized_max_linear_velocity = Real::MAX;
        ip.dt = scene.solver.max_dt_s;
        // The floor is a damped spring in rapier (60 Hz by default): the coil would sink
        // g / (2 pi f)^2 into it, losing that potential energy in the spring's damper, and the
        // load changes of every link would be damped too. See `Solver::contact_hz`.
        let floor_soft = SpringCoefficients::new(
            scene.solver.contact_hz,
            ip.static_contact_softness.damping_ratio,
        );
        ip.static_contact_softness = floor_soft;
        ip.contact_softness = floor_soft;

        let ground = world.insert_body(RigidBodyBuilder::fixed());
        // On a fixed axis the tape hangs freely: the floor is put out of its reach.
        let floor_y = if scene.fixed_axis {
            -(spiral.length() + tape.outer_radius_m + 1.0)
        } else {
            0.5 * b
        };
        let floor = world.insert_collider(
            ColliderBuilder::new(SharedShape::halfspace(Vector::Y))
                .translation(Vector::new(0.0, floor_y))
                .friction(scene.friction)
                .collision_groups(InteractionGroups::new(
                    FLOOR_GROUP,
                    TAPE_GROUP,
                    InteractionTestMode::And,
                )),
            Some(ground),
        );

        let mut coil_sums = CoilSums::default();
        for link in &links {
            coil_sums.add(link, 1.0);
        }
        let psi_low = spiral.psi_out;
        let coil_angle = spiral.rotation_with_bottom_at(psi_low);
        let p = rotate(spiral.point(psi_low), coil_angle);
        // The contact circle is shrunk by the first link's chord ratio (see `refit_ball`), so
        // the lowest node sits its inset below the floor plane, as every node does when it
        // reaches the floor: start the coil there rather than dropping it onto the floor.
        let first = links[0];
        let origin = [-p[0], 0.5 * b - p[1] - first.inset_m];
        let mprops = coil_sums.mass_properties();
        // Rolling about the contact point at the pushed contact-line speed: x' = omega rho.
        let contact_radius = spiral.curvature_radius(psi_low) * first.chord_ratio;
        let omega = -scene.push_speed_m_s / contact_radius;
        let com_local = mprops.local_com;
        let com = rotate([com_local.x, com_local.y], coil_angle);
        let rel = [origin[0] + com[0], origin[1] + com[1] - 0.5 * b];
        // Without friction nothing can make it roll: it starts spinning in place (App. D),
        // its surface moving at the push speed.
        let linvel = if scene.friction > 0.0 {
            Vector::new(-omega * rel[1], omega * rel[0])
        } else {
            Vector::ZERO
        };
        // On a fixed axis (App. E) the picture is turned by a quarter turn about the spiral's
        // centre, which stays at the origin: the tape leaves at the right and hangs down.
        let angle_offset = if scene.fixed_axis { 0.5 * PI } else { 0.0 };
        let (origin, coil_angle, linvel) = if scene.fixed_axis {
            let angle = coil_angle + angle_offset;
            let c = rotate([com_local.x, com_local.y], angle);
            ([0.0, 0.0], angle, Vector::new(-omega * c[1], omega * c[0]))
        } else {
            (origin, coil_angle, linvel)
        };
        let coil = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(Pose::new(Vector::new(origin[0], origin[1]), coil_angle))
                .additional_mass_properties(mprops)
                .linvel(linvel)
                .angvel(omega)
                .can_sleep(false),
        );
        if scene.fixed_axis {
            world.insert_impulse_joint(
                ground,
                coil,
                RevoluteJointBuilder::new()
                    .local_anchor1(Vector::ZERO)
                    .local_anchor2(Vector::ZERO)
                    .contacts_enabled(false),
            );
        }
        let coil_ball = world.insert_collider(
            Self::ball_builder(&spiral, psi_low, first.chord_ratio, scene.friction),
            Some(coil),
        );
        // The engine computes mass properties lazily at the next step; energies are read
        // before that, so compute them now.
        world.bodies[coil].recompute_mass_properties_from_colliders(&world.colliders);
        // A sticky floor holds the coil bilaterally where a floor contact only pushes; the
        // anchors are set by `restick` before the first step.
        let stick = scene.sticky.then(|| {
            [JointAxesMask::LIN_X, JointAxesMask::LIN_Y].map(|axis| {
                world.insert_impulse_joint(
                    ground,
                    coil,
                    GenericJointBuilder::new(axis).contacts_enabled(false),
                )
            })
        });

        let bang_r = scene.stop.bang_radius_m;
        let bang_fraction = if tape.core_radius_m > 0.0 {
            // On a core the mass is not spread over a disc: use the spiral's own laid
            // fraction at the midline radius bang_r.
            let psi = spiral
                .psi_at_radius(bang_r)
                .clamp(spiral.psi_in, spiral.psi_out);
            1.0 - moments.at(psi)[0] / spiral.length()
        } else {
            1.0 - (bang_r / tape.outer_radius_m).powi(2)
        };
        let mut laid_x = 0.0;
        let mut flat_first_moment = 0.0;
        for link in &links {
            flat_first_moment += link.mass_kg * (laid_x + 0.5 * link.length_m);
            laid_x += link.length_m;
        }
        let mut model = Self {
            world,
            spiral,
            moments,
            links,
            link_angle: 2.0 * PI / f64::from(scene.links_per_turn),
            steps_per_link: scene.solver.steps_per_link,
            max_dt: scene.solver.max_dt_s,
            freeze_speed: scene.solver.freeze_speed_m_s,
            bang_step_rad: scene.solver.bang_step_rad,
            joint_softness: SpringCoefficients::new(
                scene.solver.joint_hz,
                SpringCoefficients::<Real>::joint_defaults().damping_ratio,
            ),
            friction: scene.friction,
            g: g_perp,
            g_along,
            flat_first_moment,
            half_b: 0.5 * b,
            bang_fraction,
            settle_time: scene.stop.settle_time_s,
            total_mass: tape.mass_kg,
            ground,
            floor,
            coil: Some(coil),
            coil_ball: Some(coil_ball),
            stick,
            coil_sums,
            first_attached: 0,
            coil_angle,
            angle_offset,
            psi_low,
            free: VecDeque::new(),
            frozen_potential_j: 0.0,
            frozen_nodes: Vec::new(),
            ledger: EnergyLedger::default(),
            phase: Phase::Rolling,
            t: 0.0,
            bang_started_s: 0.0,
            last_dt: 0.0,
            x_low: 0.0,
            chord_ratio: first.chord_ratio,
            shedding: true,
            energy_j: 0.0,
        };
        model.restick();
        model.energy_j = model.total_energy();
        model
    }

    fn tape_groups() -> InteractionGroups {
        InteractionGroups::new(TAPE_GROUP, FLOOR_GROUP, InteractionTestMode::And)
    }

    /// The coil's contact: the osculating circle of the midline at its lowest point, shrunk
    /// by `chord_ratio` (see `refit_ball`).
    fn ball_builder(spiral: &Spiral, psi: f64, chord_ratio: f64, friction: f64) -> ColliderBuilder {
        let c = spiral.curvature_centre(psi);
        ColliderBuilder::ball(spiral.curvature_radius(psi) * chord_ratio)
            .density(0.0)
            .friction(friction)
            .position(Pose::from_translation(Vector::new(c[0], c[1])))
            .collision_groups(Self::tape_groups())
    }

    /// Stops (or resumes) shedding links: the coil then rolls as a rigid spiral. For tests
    /// and diagnostics of the rolling contact alone.
    pub fn set_shedding(&mut self, on: bool) {
        self.shedding = on;
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Number of links of the tape.
    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// Kinetic and potential energy of the whole tape (J).
    pub fn energy(&self) -> (f64, f64) {
        let mut kinetic = 0.0;
        let mut potential = self.frozen_potential_j;
        for (_, body) in self.world.bodies.iter() {
            if !body.is_dynamic() {
                continue;
            }
            kinetic += body.kinetic_energy();
            potential += self.potential_of(body);
        }
        (kinetic, potential)
    }

    /// Potential energy `-m g.p` of one body, gravity tilted on a slope (J).
    fn potential_of(&self, body: &RigidBody) -> f64 {
        let c = body.center_of_mass();
        body.mass() * self.g * c.y - body.mass() * self.g_along * c.x
    }

    fn total_energy(&self) -> f64 {
        let (k, p) = self.energy();
        k + p
    }

    /// The next step's length, at most `max_dt`: while rolling, at least `steps_per_link`
    /// steps per link angle turned by the fastest spinning body; in the bang, no body turns
    /// by more than `bang_step_rad` in a step.
    fn next_dt(&self) -> f64 {
        let spin = self
            .world
            .bodies
            .iter()
            .filter(|(_, b)| b.is_dynamic())
            .map(|(_, b)| b.angvel().abs())
            .fold(0.0, f64::max);
        // While the coil rolls, the step resolves the shedding; in the bang no link is shed
        // and the step only has to keep the free links' rotations small.
        let turn = match self.phase {
            Phase::Rolling => self.link_angle / self.steps_per_link,
            _ => self.bang_step_rad,
        };
        if spin > 0.0 {
            (turn / spin).min(self.max_dt)
        } else {
            self.max_dt
        }
    }

    /// Advances the model by one adaptive step and reports the state.
    pub fn step(&mut self) -> Observation {
        let dt = self.next_dt();
        self.world.integration_parameters.dt = dt;
        let before = self.energy_j;
        self.world.step();
        self.t += dt;
        self.last_dt = dt;
        let after = self.total_energy();
        match self.phase {
            Phase::Rolling => self.ledger.step_j += before - after,
            _ => self.ledger.bang_j += before - after,
        }

        if let Some(coil) = self.coil {
            let angle = self.world.bodies[coil].rotation().angle();
            let mut d = angle - self.coil_angle;
            d -= (d / (2.0 * PI)).round() * 2.0 * PI;
            self.coil_angle += d;
            self.psi_low = self
                .spiral
                .lowest_psi(self.coil_angle - self.angle_offset, self.psi_low)
                .clamp(self.spiral.psi_in, self.spiral.psi_out);
            while self.shedding
                && self.first_attached + 1 < self.links.len()
                && self.psi_low <= self.near_node_psi(self.first_attached)
            {
                self.detach_outermost();
            }
            self.refit_ball();
            if self.laid_fraction() >= self.bang_fraction
                || self.first_attached + 1 >= self.links.len()
            {
                self.release_coil();
            }
        }
        self.freeze_settled();
        if self.phase == Phase::Bang && self.t - self.bang_started_s >= self.settle_time {
            self.phase = Phase::Done;
        }
        self.observe()
    }

    fn near_node_psi(&self, k: usize) -> f64 {
        if k == 0 {
            self.spiral.psi_out
        } else {
            self.far_node_psi(k - 1)
        }
    }

    fn far_node_psi(&self, k: usize) -> f64 {
        // Nodes step inward by one link angle from the outer end.
        #[allow(clippy::cast_precision_loss)]
        let psi = self.spiral.psi_out - self.link_angle * (k + 1) as f64;
        psi.max(self.spiral.psi_in)
    }

    /// Laid mass fraction along the continuous spiral up to the lowest point.
    pub fn laid_fraction(&self) -> f64 {
        1.0 - self.moments.at(self.psi_low)[0] / self.spiral.length()
    }

    fn refit_ball(&mut self) {
        self.chord_ratio = self.links[self.first_attached.min(self.links.len() - 1)].chord_ratio;
        let (Some(handle), true) = (self.coil_ball, self.phase == Phase::Rolling) else {
            return;
        };
        let c = self.spiral.curvature_centre(self.psi_low);
        let collider = &mut self.world.colliders[handle];
        collider.set_shape(SharedShape::ball(
            self.spiral.curvature_radius(self.psi_low) * self.chord_ratio,
        ));
        collider.set_position_wrt_parent(Pose::from_translation(Vector::new(c[0], c[1])));
        self.restick();
    }

    /// Moves a sticky floor's hold to the coil's current contact: x is locked at the material
    /// point under the ball's centre (no slip: a rolling contact point has zero velocity and
    /// zero horizontal acceleration), y at the ball's centre (its height is fixed, while the
    /// contact point itself accelerates upward, so pinning it in y would brake the roll).
    fn restick(&mut self) {
        let (Some([hold_x, hold_y]), Some(coil)) = (self.stick, self.coil) else {
            return;
        };
        let c = self.spiral.curvature_centre(self.psi_low);
        let rho = self.spiral.curvature_radius(self.psi_low) * self.chord_ratio;
        let pose = *self.world.bodies[coil].position();
        let centre = pose.transform_point(Vector::new(c[0], c[1]));
        let contact = Vector::new(centre.x, self.half_b);
        let under = pose.inverse_transform_point(Vector::new(centre.x, centre.y - rho));
        if let Some(joint) = self.world.impulse_joints.get_mut(hold_x, false) {
            joint.data.set_local_anchor1(contact);
            joint.data.set_local_anchor2(under);
        }
        if let Some(joint) = self.world.impulse_joints.get_mut(hold_y, false) {
            joint
                .data
                .set_local_anchor1(Vector::new(centre.x, self.half_b + rho));
            joint.data.set_local_anchor2(Vector::new(c[0], c[1]));
        }
    }

    /// Creates the body of link `k` with the coil's velocity field.
    fn spawn_link(&mut self, k: usize, coil: RigidBodyHandle) -> RigidBodyHandle {
        let link = self.links[k];
        let body = &self.world.bodies[coil];
        let pose = *body.position();
        let (linvel, angvel, com) = (body.linvel(), body.angvel(), body.center_of_mass());
        let c = link.centre();
        let centre = pose.transform_point(Vector::new(c[0], c[1]));
        let r = centre - com;
        let v = linvel + Vector::new(-angvel * r.y, angvel * r.x);
        let handle = self.world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(Pose::new(centre, self.coil_angle + link.angle()))
                .additional_mass_properties(MassProperties::new(
                    Vector::ZERO,
                    link.mass_kg,
                    link.mass_kg * link.length_m * link.length_m / 12.0,
                ))
                .linvel(v)
                .angvel(angvel)
                .can_sleep(false),
        );
        self.world.bodies[handle].recompute_mass_properties_from_colliders(&self.world.colliders);
        handle
    }

    /// Gives a laid link its floor contact. A link hanging from the coil needs none: its
    /// near node rests on the previous link and its far node is carried by the coil, which
    /// stands on its own curved contact; a collider there would touch the floor just before
    /// the node arrives, a corner impact on every link.
    fn lay_link(&mut self, k: usize, handle: RigidBodyHandle) {
        if !self.world.bodies[handle].colliders().is_empty() {
            return;
        }
        let link = self.links[k];
        let half = 0.5 * link.length_m;
        self.world.insert_collider(
            ColliderBuilder::segment(
                Vector::new(-half, -link.inset_m),
                Vector::new(half, -link.inset_m),
            )
            .density(0.0)
            .friction(self.friction)
            .collision_groups(Self::tape_groups()),
            Some(handle),
        );
    }

    /// Joins the near node of link `k` (body `body`) to whatever holds it: the previous free
    /// link, or the world if that link is frozen, or nothing for the tape's outer end.
    fn join_near_node(&mut self, k: usize, body: RigidBodyHandle) {
        let half = 0.5 * self.links[k].length_m;
        if let Some(prev) = self.free.back().copied() {
            let prev_half = 0.5 * self.links[prev.index].length_m;
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(Vector::new(-prev_half, 0.0))
                .local_anchor2(Vector::new(half, 0.0))
                .contacts_enabled(false)
                .softness(self.joint_softness);
            self.world.insert_impulse_joint(prev.body, body, joint);
        } else if k > 0 {
            let node = self.world.bodies[body]
                .position()
                .transform_point(Vector::new(half, 0.0));
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(node)
                .local_anchor2(Vector::new(half, 0.0))
                .contacts_enabled(false)
                .softness(self.joint_softness);
            self.world.insert_impulse_joint(self.ground, body, joint);
        }
    }

    /// Removes the joints between a free link and the coil.
    fn unpin_from_coil(&mut self, link: RigidBodyHandle, coil: RigidBodyHandle) {
        let joints: Vec<_> = self
            .world
            .impulse_joints
            .joints_between(link, coil)
            .map(|(h, _)| h)
            .collect();
        for h in joints {
            self.world.remove_impulse_joint(h);
        }
    }

    fn detach_outermost(&mut self) {
        let Some(coil) = self.coil else { return };
        let before = self.total_energy();
        let k = self.first_attached;
        if let Some(prev) = self.free.back().copied() {
            self.lay_link(prev.index, prev.body);
        }
        let handle = self.spawn_link(k, coil);
        // The previous free link was pinned to the coil at this link's near node.
        if let Some(prev) = self.free.back().copied() {
            self.unpin_from_coil(prev.body, coil);
        }
        self.join_near_node(k, handle);
        if k == 0 {
            // The tape's free end has no previous link to rest on: without a floor contact
            // it would droop below the floor until laid, and be pushed out then.
            self.lay_link(k, handle);
        }
        self.free.push_back(FreeLink {
            index: k,
            body: handle,
        });
        let far = self.links[k].far;
        let half = 0.5 * self.links[k].length_m;
        self.world.insert_impulse_joint(
            handle,
            coil,
            RevoluteJointBuilder::new()
                .local_anchor1(Vector::new(-half, 0.0))
                .local_anchor2(Vector::new(far[0], far[1]))
                .contacts_enabled(false)
                .softness(self.joint_softness),
        );
        // Remove the link's mass from the coil, keeping the velocity field.
        let link = self.links[k];
        self.coil_sums.add(&link, -1.0);
        self.first_attached += 1;
        let body = &mut self.world.bodies[coil];
        let (v_old, w, com_old) = (body.linvel(), body.angvel(), body.center_of_mass());
        body.set_additional_mass_properties(self.coil_sums.mass_properties(), true);
        body.recompute_mass_properties_from_colliders(&self.world.colliders);
        let r = body.center_of_mass() - com_old;
        body.set_linvel(v_old + Vector::new(-w * r.y, w * r.x), true);
        self.ledger.detach_j += before - self.total_energy();
    }

    /// Releases the remaining wound links as a free chain: the final bang begins.
    fn release_coil(&mut self) {
        let Some(coil) = self.coil else { return };
        let before = self.total_energy();
        // Stiff joints hold the rolling chain to its geometry; in the bang, with links
        // turning by up to `bang_step_rad` a step, their full position correction pumps
        // energy in (the yoga mat's rose 74 % above E0 at 0.1 rad a step). The bang gets the
        // engine's default joints.
        self.joint_softness = SpringCoefficients::joint_defaults();
        for (_, joint) in self.world.impulse_joints.iter_mut() {
            let _ = joint.data.set_softness(self.joint_softness);
        }
        for k in self.first_attached..self.links.len() {
            let handle = self.spawn_link(k, coil);
            if k == self.first_attached
                && let Some(prev) = self.free.back().copied()
            {
                self.unpin_from_coil(prev.body, coil);
            }
            self.join_near_node(k, handle);
            self.free.push_back(FreeLink {
                index: k,
                body: handle,
            });
        }
        for link in self.free.clone() {
            self.lay_link(link.index, link.body);
        }
        self.world.remove_body(coil);
        self.coil = None;
        self.coil_ball = None;
        self.first_attached = self.links.len();
        self.phase = Phase::Bang;
        self.bang_started_s = self.t;
        // Spawning copies the velocity field, so this is zero up to rounding.
        self.ledger.bang_j += before - self.total_energy();
    }

    /// Freezes settled links from the laid end: a link whose two nodes move slower than the
    /// freeze speed and that is not holding the coil is removed from the engine.
    fn freeze_settled(&mut self) {
        let min_free = usize::from(self.coil.is_some());
        while self.free.len() > min_free {
            let oldest = self.free[0];
            let body = &self.world.bodies[oldest.body];
            let half = 0.5 * self.links[oldest.index].length_m;
            let pose = body.position();
            let fastest = [half, -half]
                .into_iter()
                .map(|s| {
                    body.velocity_at_point(pose.transform_point(Vector::new(s, 0.0)))
                        .length()
                })
                .fold(0.0, f64::max);
            if fastest >= self.freeze_speed {
                break;
            }
            let kinetic = body.kinetic_energy();
            self.frozen_potential_j += self.potential_of(body);
            let [near, far] = [half, -half].map(|s| {
                let p = pose.transform_point(Vector::new(s, 0.0));
                [p.x, p.y]
            });
            // The last entry was the previous frozen link's far node: this link's near node.
            self.frozen_nodes.pop();
            self.frozen_nodes.extend([near, far]);
            self.world.remove_body(oldest.body);
            self.free.pop_front();
            if let Some(next) = self.free.front().copied() {
                let next_half = 0.5 * self.links[next.index].length_m;
                // Pin the next link where its near node is now, not where the frozen link's
                // far node was: a joint stretched by tension would otherwise hand its
                // stretch to the anchor at every freeze, and the laid tape would creep.
                let node = self.world.bodies[next.body]
                    .position()
                    .transform_point(Vector::new(next_half, 0.0));
                let joint = RevoluteJointBuilder::new()
                    .local_anchor1(node)
                    .local_anchor2(Vector::new(next_half, 0.0))
                    .contacts_enabled(false)
                    .softness(self.joint_softness);
                self.world
                    .insert_impulse_joint(self.ground, next.body, joint);
            }
            match self.phase {
                Phase::Rolling => self.ledger.freeze_j += kinetic,
                _ => self.ledger.bang_j += kinetic,
            }
        }
    }

    /// Linear momentum of the dynamic bodies (kg m/s).
    fn momentum(&self) -> [f64; 2] {
        let mut p = [0.0, 0.0];
        for (_, body) in self.world.bodies.iter() {
            if body.is_dynamic() {
                let v = body.linvel();
                p[0] += body.mass() * v.x;
                p[1] += body.mass() * v.y;
            }
        }
        p
    }

    /// Floor forces on the moving tape from the last step's contact impulses (N).
    fn floor_forces(&self) -> (f64, f64) {
        floor_forces(&self.world.narrow_phase, self.floor, self.last_dt)
    }

    fn max_joint_gap(&self) -> f64 {
        self.world
            .impulse_joints
            .iter()
            .map(|(_, j)| {
                let (b1, b2) = (&self.world.bodies[j.body1()], &self.world.bodies[j.body2()]);
                let a1 = b1.position().transform_point(j.data.local_anchor1());
                let a2 = b2.position().transform_point(j.data.local_anchor2());
                (a1 - a2).length()
            })
            .fold(0.0, f64::max)
    }

    fn max_penetration(&self) -> f64 {
        let mut deepest: f64 = 0.0;
        for pair in self.world.narrow_phase.contact_pairs_with(self.floor) {
            if let PairContacts::Rigid(contacts) = &pair.contacts {
                for m in &contacts.manifolds {
                    for p in &m.points {
                        deepest = deepest.max(-p.dist);
                    }
                }
            }
        }
        deepest
    }

    /// The state after the last step.
    pub fn observe(&mut self) -> Observation {
        let (kinetic_j, potential_j) = self.energy();
        self.energy_j = kinetic_j + potential_j;
        let (normal_n, friction_n) = self.floor_forces();
        let (x_m, omega) = match self.coil {
            Some(coil) => {
                let body = &self.world.bodies[coil];
                let p = self.spiral.point(self.psi_low);
                (
                    body.position().transform_point(Vector::new(p[0], p[1])).x,
                    -body.angvel(),
                )
            }
            None => (self.x_low, 0.0),
        };
        self.x_low = x_m;
        Observation {
            t_s: self.t,
            phase: self.phase,
            laid_fraction: self.laid_fraction(),
            psi_low: self.psi_low,
            x_m,
            omega_rad_s: omega,
            kinetic_j,
            potential_j,
            normal_n,
            friction_n,
            ledger: self.ledger,
            detached: self.first_attached,
            active_bodies: self.world.bodies.len() - 1,
            max_joint_gap_m: self.max_joint_gap(),
            max_penetration_m: self.max_penetration(),
            dt_s: self.last_dt,
            momentum_kg_m_s: self.momentum(),
        }
    }

    /// The link nodes in the world frame (m), for drawing: `(off, wound)`. `off` runs from
    /// the tape's outer end through the frozen and the moving links that left the coil;
    /// `wound` runs from the coil's outermost attached node inward. Consecutive nodes bound
    /// one link; either list is empty when it has no link.
    pub fn link_nodes(&self) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        let mut off = self.frozen_nodes.clone();
        for (i, link) in self.free.iter().enumerate() {
            let half = 0.5 * self.links[link.index].length_m;
            let pose = self.world.bodies[link.body].position();
            let ends: &[f64] = if i + 1 == self.free.len() {
                &[half, -half]
            } else {
                &[half]
            };
            if i == 0 {
                // The first moving link's near node replaces the last frozen far node.
                off.pop();
            }
            off.extend(ends.iter().map(|&s| {
                let p = pose.transform_point(Vector::new(s, 0.0));
                [p.x, p.y]
            }));
        }
        let mut wound = Vec::new();
        if let Some(coil) = self.coil {
            let pose = self.world.bodies[coil].position();
            let attached = &self.links[self.first_attached..];
            let nodes = attached
                .first()
                .map(|l| l.near)
                .into_iter()
                .chain(attached.iter().map(|l| l.far));
            wound.extend(nodes.map(|n| {
                let p = pose.transform_point(Vector::new(n[0], n[1]));
                [p.x, p.y]
            }));
        }
        (off, wound)
    }

    /// Potential energy of the tape lying flat, midline at `b/2`, from `x = 0` on (J).
    pub fn flat_potential_j(&self) -> f64 {
        self.total_mass * self.g * self.half_b - self.g_along * self.flat_first_moment
    }

    /// What the run's guards read after a step: slip at the rolling contact, how far the
    /// bodies have gone, their fastest spin, and whether every body state is finite.
    pub fn health(&self) -> Health {
        let slip_m_s = self.coil.map(|coil| {
            let body = &self.world.bodies[coil];
            let p = self.spiral.point(self.psi_low);
            let contact = body.position().transform_point(Vector::new(p[0], p[1]));
            body.velocity_at_point(contact).x
        });
        let mut health = Health {
            slip_m_s,
            farthest_m: 0.0,
            lowest_m: 0.0,
            max_spin_rad_s: 0.0,
            finite: true,
        };
        for (_, body) in self.world.bodies.iter() {
            if !body.is_dynamic() {
                continue;
            }
            let c = body.center_of_mass();
            let v = body.linvel();
            let w = body.angvel();
            health.finite &= [c.x, c.y, v.x, v.y, w].iter().all(|x| x.is_finite());
            health.farthest_m = health.farthest_m.max(c.length());
            health.lowest_m = health.lowest_m.min(c.y);
            health.max_spin_rad_s = health.max_spin_rad_s.max(w.abs());
        }
        health
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box of mass `m` on a halfspace floor with friction 0.5, started with speed `vx`.
    fn box_on_floor(vx: f64) -> (PhysicsWorld, ColliderHandle, RigidBodyHandle) {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1e-3;
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let floor = world.insert_collider(
            ColliderBuilder::new(SharedShape::halfspace(Vector::Y)).friction(0.5),
            Some(ground),
        );
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, 0.05))
                .linvel(Vector::new(vx, 0.0)),
        );
        world.insert_collider(
            ColliderBuilder::cuboid(0.1, 0.05)
                .density(100.0)
                .friction(0.5),
            Some(body),
        );
        (world, floor, body)
    }

    #[test]
    fn resting_box_feels_its_weight_upward_and_no_friction() {
        let (mut world, floor, body) = box_on_floor(0.0);
        for _ in 0..200 {
            world.step();
        }
        let weight = world.bodies[body].mass() * 9.81;
        let (n, f) = floor_forces(&world.narrow_phase, floor, 1e-3);
        assert!(
            (n / weight - 1.0).abs() < 0.01,
            "N = {n:.4} N, weight {weight:.4} N"
        );
        assert!(f.abs() < 1e-6 * weight, "F = {f:.3e} N on a resting box");
    }

    #[test]
    fn sliding_box_feels_friction_against_its_motion() {
        // Sliding towards +x: kinetic friction mu m g acts along -x.
        let (mut world, floor, body) = box_on_floor(1.0);
        for _ in 0..20 {
            world.step();
        }
        let weight = world.bodies[body].mass() * 9.81;
        assert!(world.bodies[body].linvel().x > 0.5, "still sliding");
        let (n, f) = floor_forces(&world.narrow_phase, floor, 1e-3);
        assert!(
            (n / weight - 1.0).abs() < 0.01,
            "N = {n:.4} N, weight {weight:.4} N"
        );
        assert!(
            (f / (-0.5 * weight) - 1.0).abs() < 0.01,
            "F = {f:.4} N, expected -mu m g = {:.4} N",
            -0.5 * weight
        );
    }

    fn yoga() -> Scene {
        Scene::from_toml_str(
            "[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\nmass_kg = 1.5\n\
             [push]\ncontact_speed_m_s = 0.3\n",
            "yoga",
        )
        .expect("valid scene")
    }

    #[test]
    fn rigid_spiral_rolls_without_losing_energy() {
        // Without shedding, the coil is a rigid eccentric spiral rocking on its curved
        // contact: energy is conserved but for the settling into the soft contact.
        let mut model = Model::new(&yoga());
        model.set_shedding(false);
        let (k0, p0) = model.energy();
        let mut worst: f64 = 0.0;
        for _ in 0..1000 {
            let o = model.step();
            worst = worst.max(((o.kinetic_j + o.potential_j) / (k0 + p0) - 1.0).abs());
        }
        assert!(
            worst < 0.003,
            "energy drifted by {:.3} % over 1 s",
            100.0 * worst
        );
    }

    #[test]
    fn ledger_parts_add_up_to_the_energy_lost_at_every_step() {
        let mut model = Model::new(&yoga());
        let (k0, p0) = model.energy();
        let e0 = k0 + p0;
        for _ in 0..3000 {
            let o = model.step();
            let lost = e0 - o.kinetic_j - o.potential_j;
            assert!(
                (o.ledger.total_j() - lost).abs() < 1e-9,
                "t = {:.4} s: ledger {:.6e} J, E0 - K - P = {:.6e} J",
                o.t_s,
                o.ledger.total_j(),
                lost
            );
            if o.phase == Phase::Done {
                break;
            }
        }
    }
}
