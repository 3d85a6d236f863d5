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

mod work;
pub use work::BangLedger;

/// What ended the final bang.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BangEnd {
    /// The moving tape's energy above lying at rest on the floor (kinetic, plus its weight
    /// times its height above lying flat) fell below `stop.rest_fraction` of the kinetic
    /// energy the bang received.
    Rest,
    /// `stop.bang_cap_s` of simulated time passed first.
    Cap,
}

/// The final bang as measured so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BangRecord {
    /// Simulated time of the release (s).
    pub started_s: f64,
    /// Kinetic energy of the tape at the release (J).
    pub kinetic_in_j: f64,
    /// Fastest speed of any point of the tape since the release (m/s).
    pub top_speed_m_s: f64,
    /// Largest floor normal force on the moving tape in one step, its normal impulse over
    /// the step (N).
    pub peak_floor_force_n: f64,
    /// Normal impulse of the floor on the moving tape since the release (N s).
    pub floor_impulse_n_s: f64,
    /// Where the dissipated energy went, by mechanism.
    pub ledger: BangLedger,
    /// What ended the bang, once it has ended.
    pub end: Option<BangEnd>,
}
use work::{BodyState, Moved};

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
    /// The final bang so far (all zero before the release).
    pub bang: BangRecord,
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
    /// Angular momentum of the moving part (the coil and the link hanging from it) about
    /// the origin `(0, b/2)` over the last step, from how far it moved, counter-clockwise
    /// (kg m^2/s); 0 once the coil is released.
    pub angular_momentum_o: f64,
    /// What acted on the tape during the last step, as impulses (N s).
    pub impulses: StepImpulses,
}

/// The impulses on the tape during one step (N s, up and +x positive), read from the
/// engine: summed over the steps of a sample interval and divided by it, they are the
/// interval's mean forces.
///
/// The moving part is the coil with the link hanging from it (the link that left the coil
/// last, not yet laid). Its external forces are gravity, the floor's contact on the coil,
/// and the laid tape pulling through the hanging link's near node:
/// ```text
/// total = P(t + dt) - P(t) - m g dt        over the moving part's own bodies (N_tot, F_tot)
/// floor = the floor's contact impulses on the coil                             (N, F)
/// laid  = total - floor: the laid tape's pull through its end                  (N_int, F_int)
/// ```
/// The set is fixed within the step; a link shed after it carries its momentum out with it.
/// All zero once the coil is released.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StepImpulses {
    /// Impulse of every force but gravity on the moving part (N s).
    pub total: [f64; 2],
    /// Impulse of the floor's contacts on the coil (N s).
    pub floor_on_coil: [f64; 2],
    /// Impulse of the floor's contacts on everything that moves: the coil and the laid
    /// links not yet frozen (N s).
    pub floor_on_moving: [f64; 2],
    /// Angular impulses on the moving part about the paper's origin, the laid tape's outer
    /// end on the floor (here on the contact plane, `(0, b/2)`).
    pub about_origin: AngularImpulses,
}

/// Angular impulses about the origin over a step, counter-clockwise positive (N m s).
/// `change - gravity - floor - laid` is the torque identity's gap, a measurement error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct AngularImpulses {
    /// Change of the moving part's angular momentum `L_O` over the step.
    pub change: f64,
    /// Gravity, at each body's centre of mass (mid-step).
    pub gravity: f64,
    /// The floor's contacts on the coil, at their points.
    pub floor: f64,
    /// The laid tape's pull, at the node it pulls through.
    pub laid: f64,
    /// Gravity as eq. (16) places it: across the floor at the contact line, not at the
    /// spiral's off-centre centre of mass.
    pub gravity_at_contact_line: f64,
    /// Everything but gravity as eq. (16) places it: the momentum balance's vertical
    /// impulse at the contact line, its horizontal one in the floor's plane.
    pub others_at_contact_line: f64,
}

impl StepImpulses {
    /// Impulse of the laid tape on the moving part, `total - floor_on_coil` (N s).
    pub fn laid(&self) -> [f64; 2] {
        [
            self.total[0] - self.floor_on_coil[0],
            self.total[1] - self.floor_on_coil[1],
        ]
    }

    /// Adds another step's impulses.
    pub fn add(&mut self, other: &Self) {
        *self = self.combine(other, 1.0, 1.0);
    }

    /// `a self + b other`, field by field.
    pub fn combine(&self, other: &Self, a: f64, b: f64) -> Self {
        let v = |x: [f64; 2], y: [f64; 2]| [a * x[0] + b * y[0], a * x[1] + b * y[1]];
        let (p, q) = (&self.about_origin, &other.about_origin);
        let s = |x: f64, y: f64| a * x + b * y;
        Self {
            total: v(self.total, other.total),
            floor_on_coil: v(self.floor_on_coil, other.floor_on_coil),
            floor_on_moving: v(self.floor_on_moving, other.floor_on_moving),
            about_origin: AngularImpulses {
                change: s(p.change, q.change),
                gravity: s(p.gravity, q.gravity),
                floor: s(p.floor, q.floor),
                laid: s(p.laid, q.laid),
                gravity_at_contact_line: s(p.gravity_at_contact_line, q.gravity_at_contact_line),
                others_at_contact_line: s(p.others_at_contact_line, q.others_at_contact_line),
            },
        }
    }
}

/// The moving part at the start of a step, for its balances over the step.
struct MovingSnapshot {
    bodies: Vec<RigidBodyHandle>,
    momentum: [f64; 2],
    angular_momentum: f64,
    /// Each body's centre of mass (world, m).
    centres: Vec<Vector>,
    /// Each body's rotation angle (rad).
    angles: Vec<f64>,
    /// Where the laid tape pulls on it (world, m).
    pull_at: Option<Vector>,
    /// The contact line's x (m).
    contact_x: f64,
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
}

/// Consecutive links that left the coil together and move as one rigid body: a single
/// link while the coil rolls; in the final bang, the remaining wound links grouped into
/// pieces at least `solver.bang_piece_m` long. The body's frame is the coil's frame at the
/// moment the piece left it, so its nodes are the spiral's own coordinates.
#[derive(Debug, Clone, Copy)]
struct Piece {
    /// The links `first..=last`, from the laid end inward.
    first: usize,
    last: usize,
    body: RigidBodyHandle,
    /// Height of its centre of mass when it lies flat on the floor (m).
    rest_y_m: f64,
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

/// In the bang a piece is pinned this fraction of R above the floor's contact plane (the
/// engine's tolerances scale with R): see [`Model::pin_to_world`].
const PIN_LIFT_PER_RADIUS: f64 = 1e-4;

const TAPE_GROUP: Group = Group::GROUP_1;
const FLOOR_GROUP: Group = Group::GROUP_2;

/// The contact-resolved tape.
pub struct Model {
    world: PhysicsWorld,
    spiral: Spiral,
    moments: SpiralMoments,
    links: Vec<Link>,
    /// Each link's near and far node in the frame of the body that holds it (m): the
    /// spiral's coordinates while it is wound or in a piece spawned from the coil, the
    /// world's in a piece joined from moving links.
    local: Vec<[Vector; 2]>,
    link_angle: f64,
    steps_per_link: f64,
    max_dt: f64,
    freeze_speed: f64,
    bang_step_rad: f64,
    /// Shortest piece the remaining wound links are grouped into at the release (m).
    bang_piece_m: f64,
    /// How far above the floor's contact plane a piece is pinned in the bang (m).
    pin_lift_m: f64,
    /// Softness of every joint (see `Solver::joint_hz`).
    joint_softness: SpringCoefficients<Real>,
    /// Softness of every joint from the release on (see `Solver::bang_joint_hz`).
    bang_joint_softness: SpringCoefficients<Real>,
    friction: f64,
    /// Gravity across the floor, `g cos(alpha)`, pulling towards it (m/s^2).
    g: f64,
    /// Gravity along the floor, `g sin(alpha)`, towards +x (m/s^2); 0 on a level floor.
    g_along: f64,
    /// First moment `sum m_k x_k` of the tape lying flat from `x = 0` (kg m).
    flat_first_moment: f64,
    half_b: f64,
    bang_fraction: f64,
    bang_iterations: usize,
    bang_cap_s: f64,
    rest_fraction: f64,
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

    free: VecDeque<Piece>,
    frozen_potential_j: f64,
    /// Near node of each frozen link, from the outer end, and the far node of the last one
    /// (world frame, m): frozen links have no body left to ask.
    frozen_nodes: Vec<[f64; 2]>,

    ledger: EnergyLedger,
    bang: BangRecord,
    phase: Phase,
    t: f64,
    last_dt: f64,
    x_low: f64,
    chord_ratio: f64,
    shedding: bool,
    /// Kinetic plus potential energy at the last observation, the next step's start (J).
    energy_j: f64,
    /// The last step's impulses on the moving part.
    impulses: StepImpulses,
    /// The moving part's angular momentum about the origin over the last step, from how
    /// far it moved (kg m^2/s): see [`Self::moved_angular_momentum`].
    moved_angular_momentum: f64,
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
        let local = links
            .iter()
            .map(|l| {
                [
                    Vector::new(l.near[0], l.near[1]),
                    Vector::new(l.far[0], l.far[1]),
                ]
            })
            .collect();
        let mut model = Self {
            world,
            spiral,
            moments,
            links,
            local,
            link_angle: 2.0 * PI / f64::from(scene.links_per_turn),
            steps_per_link: scene.solver.steps_per_link,
            max_dt: scene.solver.max_dt_s,
            freeze_speed: scene.solver.freeze_speed_m_s,
            bang_step_rad: scene.solver.bang_step_rad,
            bang_piece_m: scene.solver.bang_piece_m,
            pin_lift_m: PIN_LIFT_PER_RADIUS * tape.outer_radius_m,
            joint_softness: SpringCoefficients::new(
                scene.solver.joint_hz,
                SpringCoefficients::<Real>::joint_defaults().damping_ratio,
            ),
            bang_joint_softness: SpringCoefficients::new(
                scene.solver.bang_joint_hz,
                SpringCoefficients::<Real>::joint_defaults().damping_ratio,
            ),
            friction: scene.friction,
            g: g_perp,
            g_along,
            flat_first_moment,
            half_b: 0.5 * b,
            bang_fraction,
            bang_iterations: scene.solver.bang_iterations as usize,
            bang_cap_s: scene.stop.bang_cap_s,
            rest_fraction: scene.stop.rest_fraction,
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
            bang: BangRecord::default(),
            phase: Phase::Rolling,
            t: 0.0,
            last_dt: 0.0,
            x_low: 0.0,
            chord_ratio: first.chord_ratio,
            shedding: true,
            energy_j: 0.0,
            impulses: StepImpulses::default(),
            moved_angular_momentum: 0.0,
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
        let states: Vec<BodyState> = if self.phase == Phase::Bang {
            self.free
                .iter()
                .map(|l| BodyState::of(&self.world.bodies[l.body]))
                .collect()
        } else {
            Vec::new()
        };
        let moving = self.snapshot();
        self.world.step();
        self.t += dt;
        self.last_dt = dt;
        // The floor's contact impulses of the step, read once for the forces and the ledger.
        let contacts: Vec<work::FloorImpulse> =
            work::floor_impulses(&self.world.narrow_phase, &self.world.colliders, self.floor)
                .collect();
        self.impulses = self.step_impulses(&moving, &contacts, dt);
        self.moved_angular_momentum = self.moved_angular_momentum(&moving, dt);
        let (kinetic, potential) = self.energy();
        let after = kinetic + potential;
        match self.phase {
            Phase::Rolling => self.ledger.step_j += before - after,
            _ => self.book_bang_step(&states, &contacts, before - after, kinetic, dt),
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
        if self.phase == Phase::Bang && self.t - self.bang.started_s >= self.bang_cap_s {
            self.end_bang(BangEnd::Cap);
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

    /// Creates the body of the links `first..=last` with the coil's velocity field, in the
    /// coil's frame.
    fn spawn_piece(&mut self, first: usize, last: usize, coil: RigidBodyHandle) -> Piece {
        let mut sums = CoilSums::default();
        for link in &self.links[first..=last] {
            sums.add(link, 1.0);
        }
        let body = &self.world.bodies[coil];
        let pose = *body.position();
        let (linvel, angvel, com) = (body.linvel(), body.angvel(), body.center_of_mass());
        let mprops = sums.mass_properties();
        let r = pose.transform_point(mprops.local_com) - com;
        let handle = self.world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .additional_mass_properties(mprops)
                .linvel(linvel + Vector::new(-angvel * r.y, angvel * r.x))
                .angvel(angvel)
                .can_sleep(false)
                .user_data(first as u128),
        );
        self.world.bodies[handle].recompute_mass_properties_from_colliders(&self.world.colliders);
        Piece {
            first,
            last,
            body: handle,
            rest_y_m: self.rest_height_m(first, last),
        }
    }

    /// How far a link's segment collider lies below its node line (m): its inset while the
    /// coil rolls, none in the bang (see [`Self::lay_piece`]).
    fn inset_m(&self, k: usize) -> f64 {
        match self.phase {
            Phase::Rolling => self.links[k].inset_m,
            _ => 0.0,
        }
    }

    /// Height of the centre of mass of the links `first..=last` lying flat on the floor:
    /// each link's node line sits its collider's inset above the contact plane `y = b/2` (m).
    fn rest_height_m(&self, first: usize, last: usize) -> f64 {
        let mass: f64 = self.links[first..=last].iter().map(|l| l.mass_kg).sum();
        (first..=last)
            .map(|k| self.links[k].mass_kg * (self.half_b + self.inset_m(k)))
            .sum::<f64>()
            / mass
    }

    /// The piece's nodes in its body frame, from its near node inward.
    fn piece_nodes(&self, piece: Piece) -> impl Iterator<Item = Vector> + '_ {
        std::iter::once(self.local[piece.first][0])
            .chain(self.local[piece.first..=piece.last].iter().map(|l| l[1]))
    }

    /// Gives a laid piece its floor contact: one segment per link. While the coil rolls a
    /// segment lies its link's inset below the node line, so that the link lies on the
    /// floor as the coil laid it; in the bang it lies on the node line, which a piece turned
    /// over its pinned node would otherwise push into the floor at the pin, where neither
    /// can give. A link hanging from the coil needs none: its near node rests on the
    /// previous link and its far node is carried by the coil, which stands on its own curved
    /// contact; a collider there would touch the floor just before the node arrives, a
    /// corner impact on every link.
    fn lay_piece(&mut self, piece: Piece) {
        if !self.world.bodies[piece.body].colliders().is_empty() {
            return;
        }
        if self.phase != Phase::Rolling {
            // One polyline through the piece's nodes: one contact pair per piece, not per
            // link (cheaper, and no doubled contact where two links meet).
            let nodes: Vec<Vector> = self.piece_nodes(piece).collect();
            self.world.insert_collider(
                ColliderBuilder::polyline(nodes, None)
                    .density(0.0)
                    .friction(self.friction)
                    .collision_groups(Self::tape_groups()),
                Some(piece.body),
            );
            return;
        }
        for k in piece.first..=piece.last {
            let [near, far] = self.local[k];
            let half = 0.5 * (near - far).length();
            let inset = self.inset_m(k);
            self.world.insert_collider(
                ColliderBuilder::segment(Vector::new(-half, -inset), Vector::new(half, -inset))
                    .position(Pose::new(0.5 * (near + far), (near - far).to_angle()))
                    .density(0.0)
                    .friction(self.friction)
                    .collision_groups(Self::tape_groups()),
                Some(piece.body),
            );
        }
    }

    /// Joins the near node of `piece` to whatever holds it: the previous free piece, or the
    /// world if that one is frozen, or nothing for the tape's outer end.
    fn join_near_node(&mut self, piece: Piece) {
        let near = self.local[piece.first][0];
        if let Some(prev) = self.free.back().copied() {
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(self.local[prev.last][1])
                .local_anchor2(near)
                .contacts_enabled(false)
                .softness(self.joint_softness);
            self.world
                .insert_impulse_joint(prev.body, piece.body, joint);
        } else if piece.first > 0 {
            self.pin_to_world(piece);
        }
    }

    /// Pins the near node of `piece` to the world where it is now (in the bang, not below
    /// the floor's contact plane). The world's body also
    /// holds the floor, and the pin disables their contact while the coil rolls: the pinned
    /// link lies on the floor, held there by its neighbours (with the contact as well, the
    /// pin and the floor fight over it). In the final bang the pinned piece may swing, and
    /// without the contact it would pass through the floor.
    fn pin_to_world(&mut self, piece: Piece) {
        let near = self.local[piece.first][0];
        let mut node = self.world.bodies[piece.body]
            .position()
            .transform_point(near);
        if self.phase != Phase::Rolling {
            // Just above the contact plane: on or below it, the floor pushes the pinned node
            // out while the pin holds it, and the solver's two impulses grow against each
            // other without bound.
            node.y = node.y.max(self.half_b + self.pin_lift_m);
        }
        let joint = RevoluteJointBuilder::new()
            .local_anchor1(node)
            .local_anchor2(near)
            .contacts_enabled(self.phase != Phase::Rolling)
            .softness(self.joint_softness);
        self.world
            .insert_impulse_joint(self.ground, piece.body, joint);
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
            self.lay_piece(prev);
        }
        let piece = self.spawn_piece(k, k, coil);
        // The previous free link was pinned to the coil at this link's near node.
        if let Some(prev) = self.free.back().copied() {
            self.unpin_from_coil(prev.body, coil);
        }
        self.join_near_node(piece);
        if k == 0 {
            // The tape's free end has no previous link to rest on: without a floor contact
            // it would droop below the floor until laid, and be pushed out then.
            self.lay_piece(piece);
        }
        self.free.push_back(piece);
        // Both bodies are in the coil's frame: the far node has the same coordinates in each.
        let far = self.links[k].far;
        let far = Vector::new(far[0], far[1]);
        self.world.insert_impulse_joint(
            piece.body,
            coil,
            RevoluteJointBuilder::new()
                .local_anchor1(far)
                .local_anchor2(far)
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

    /// Joins the moving links, in order along the tape, into rigid pieces at least
    /// `bang_piece_m` long (a short remainder joins the last piece). Each piece moves with
    /// its parts' momentum and angular momentum; the kinetic energy of their relative
    /// motion is lost, and returned (J).
    fn join_pieces(&mut self) -> f64 {
        let before = self.energy().0;
        let parts: Vec<Piece> = self.free.drain(..).collect();
        let mut groups: Vec<std::ops::Range<usize>> = Vec::new();
        let (mut start, mut length) = (0, 0.0);
        for (i, p) in parts.iter().enumerate() {
            length += self.links[p.first..=p.last]
                .iter()
                .map(|l| l.length_m)
                .sum::<f64>();
            if length >= self.bang_piece_m {
                groups.push(start..i + 1);
                start = i + 1;
                length = 0.0;
            }
        }
        if start < parts.len() {
            match groups.last_mut() {
                Some(last) => last.end = parts.len(),
                None => groups.push(start..parts.len()),
            }
        }
        for group in groups {
            let group = &parts[group];
            // Mass, centre of mass and momentum, then inertia and angular momentum about
            // the centre of mass (world frame).
            let (mut mass, mut first_moment, mut momentum) = (0.0, Vector::ZERO, Vector::ZERO);
            for part in group {
                let body = &self.world.bodies[part.body];
                mass += body.mass();
                first_moment += body.center_of_mass() * body.mass();
                momentum += body.linvel() * body.mass();
            }
            let com = first_moment / mass;
            let (mut inertia, mut spin) = (0.0, 0.0);
            for part in group {
                let body = &self.world.bodies[part.body];
                let r = body.center_of_mass() - com;
                let own = body.mass_properties().effective_angular_inertia();
                inertia += own + body.mass() * r.length_squared();
                spin += own * body.angvel() + body.mass() * r.perp_dot(body.linvel());
            }
            // The new body's frame is the world's: its nodes are where they are now.
            for part in group {
                let pose = *self.world.bodies[part.body].position();
                for k in part.first..=part.last {
                    self.local[k] = self.local[k].map(|n| pose.transform_point(n));
                }
                self.world.remove_body(part.body);
            }
            let first = group[0].first;
            let body = self.world.insert_body(
                RigidBodyBuilder::dynamic()
                    .additional_mass_properties(MassProperties::new(com, mass, inertia))
                    .linvel(momentum / mass)
                    .angvel(spin / inertia)
                    .can_sleep(false)
                    .user_data(first as u128),
            );
            self.world.bodies[body].recompute_mass_properties_from_colliders(&self.world.colliders);
            let last = group[group.len() - 1].last;
            let piece = Piece {
                first,
                last,
                body,
                rest_y_m: self.rest_height_m(first, last),
            };
            self.join_near_node(piece);
            self.lay_piece(piece);
            self.free.push_back(piece);
        }
        before - self.energy().0
    }

    /// Releases the remaining wound links as a free chain: the final bang begins.
    fn release_coil(&mut self) {
        let Some(coil) = self.coil else { return };
        let (kinetic_in, potential_in) = self.energy();
        let before = kinetic_in + potential_in;
        self.phase = Phase::Bang;
        // From here on every joint, old and new, has the bang's softness.
        self.joint_softness = self.bang_joint_softness;
        for (_, j) in self.world.impulse_joints.iter_mut() {
            j.data.softness = self.bang_joint_softness;
        }
        if let Some(prev) = self.free.back().copied() {
            self.unpin_from_coil(prev.body, coil);
        }
        // The piece pinned to the world may swing in the bang: let it touch the floor.
        if let Some(first) = self.free.front().copied() {
            let pins: Vec<_> = self
                .world
                .impulse_joints
                .joints_between(self.ground, first.body)
                .map(|(h, _)| h)
                .collect();
            for h in pins {
                if let Some(j) = self.world.impulse_joints.get_mut(h, false) {
                    j.data.set_contacts_enabled(true);
                }
            }
        }
        for k in self.first_attached..self.links.len() {
            let piece = self.spawn_piece(k, k, coil);
            self.join_near_node(piece);
            self.free.push_back(piece);
        }
        self.world.remove_body(coil);
        self.coil = None;
        self.coil_ball = None;
        self.first_attached = self.links.len();
        // The engine leaves the joints a few microns apart under tension; closing those gaps
        // later, under the bang's far larger tension, would do work on the tape. Close them
        // now, by position alone, then join the links into the bang's pieces.
        self.close_gaps();
        let joined_j = self.join_pieces();
        self.bang.ledger.freeze_j += joined_j;
        self.world.integration_parameters.num_solver_iterations = self.bang_iterations;
        let (kinetic, potential) = self.energy();
        self.bang.started_s = self.t;
        self.bang.kinetic_in_j = kinetic_in;
        // Spawning copies the velocity field, so this is the joining's loss, but for closing
        // the gaps, which moves the links by microns.
        let release_j = before - kinetic - potential;
        self.ledger.bang_j += release_j;
        self.bang.ledger.residual_j += release_j - joined_j;
    }

    /// Freezes settled pieces from the laid end: a piece whose nodes all move slower than
    /// the freeze speed and that is not holding the coil is removed from the engine.
    fn freeze_settled(&mut self) {
        let min_free = usize::from(self.coil.is_some());
        while self.free.len() > min_free {
            let oldest = self.free[0];
            let body = &self.world.bodies[oldest.body];
            let pose = *body.position();
            let nodes: Vec<Vector> = self
                .piece_nodes(oldest)
                .map(|n| pose.transform_point(n))
                .collect();
            let fastest = nodes
                .iter()
                .map(|&p| body.velocity_at_point(p).length())
                .fold(0.0, f64::max);
            if fastest >= self.freeze_speed {
                break;
            }
            let kinetic = body.kinetic_energy();
            self.frozen_potential_j += self.potential_of(body);
            // The last entry was the previous frozen piece's far node: this one's near node.
            self.frozen_nodes.pop();
            self.frozen_nodes.extend(nodes.iter().map(|p| [p.x, p.y]));
            self.world.remove_body(oldest.body);
            self.free.pop_front();
            // Pin the next piece where its near node is now, not where the frozen piece's
            // far node was: a joint stretched by tension would otherwise hand its stretch to
            // the anchor at every freeze, and the laid tape would creep.
            if let Some(next) = self.free.front().copied() {
                self.pin_to_world(next);
            }
            match self.phase {
                Phase::Rolling => self.ledger.freeze_j += kinetic,
                _ => {
                    self.ledger.bang_j += kinetic;
                    self.bang.ledger.freeze_j += kinetic;
                }
            }
        }
    }

    /// Books one step of the final bang: the work of the floor (its `contacts`) and the joints
    /// on the moving pieces (from their states `before` it, in the order of `free`) into the
    /// bang's ledger, with `lost_j` what the step dissipated and `kinetic` the kinetic energy
    /// after it; the fastest point, the floor's impulse; and ends the bang once it has come to
    /// rest.
    fn book_bang_step(
        &mut self,
        before: &[BodyState],
        contacts: &[work::FloorImpulse],
        lost_j: f64,
        kinetic: f64,
        dt: f64,
    ) {
        self.ledger.bang_j += lost_j;
        if self.free.is_empty() {
            // Everything is frozen: at rest.
            self.bang.ledger.residual_j += lost_j;
            self.end_bang(BangEnd::Rest);
            return;
        }
        let bodies: Vec<Moved<'_>> = self
            .free
            .iter()
            .zip(before)
            .map(|(p, &before)| Moved {
                body: &self.world.bodies[p.body],
                before,
            })
            .collect();
        let floor: Vec<_> = contacts
            .iter()
            .filter_map(|&c| {
                #[allow(clippy::cast_possible_truncation)]
                let k = self.world.bodies.get(c.body)?.user_data as usize;
                let i = self.free.binary_search_by_key(&k, |p| p.first).ok()?;
                Some((i, c))
            })
            .collect();
        let work = work::step_work(&bodies, &floor, self.world.gravity, dt);
        let impulse: f64 = floor.iter().map(|(_, c)| c.normal.length()).sum();
        // Potential energy above lying flat on the floor: the weight across the floor times
        // the centre of mass's height above where it would lie (never negative: on a fixed
        // axis the tape hangs far above a floor it cannot reach).
        let raised_j: f64 = self
            .free
            .iter()
            .map(|p| {
                let body = &self.world.bodies[p.body];
                body.mass() * self.g * (body.center_of_mass().y - p.rest_y_m).max(0.0)
            })
            .sum();
        let top_speed = self
            .free
            .iter()
            .flat_map(|&p| {
                let body = &self.world.bodies[p.body];
                let pose = *body.position();
                self.piece_nodes(p)
                    .map(move |n| body.velocity_at_point(pose.transform_point(n)).length())
            })
            .fold(0.0, f64::max);

        let b = &mut self.bang;
        b.ledger.floor_normal_j -= work.normal_j;
        b.ledger.floor_friction_j -= work.friction_j;
        b.ledger.joints_j -= work.joints_j;
        b.ledger.residual_j += lost_j + work.normal_j + work.friction_j + work.joints_j;
        b.top_speed_m_s = b.top_speed_m_s.max(top_speed);
        b.floor_impulse_n_s += impulse;
        if dt > 0.0 {
            b.peak_floor_force_n = b.peak_floor_force_n.max(impulse / dt);
        }
        if kinetic + raised_j < self.rest_fraction * b.kinetic_in_j {
            self.end_bang(BangEnd::Rest);
        }
    }

    /// Ends the final bang: nothing more is simulated.
    fn end_bang(&mut self, why: BangEnd) {
        self.bang.end = Some(why);
        self.phase = Phase::Done;
    }

    /// Closes the joints' gaps along the chain by translating each piece, from the laid end
    /// on, so that its near node meets what holds it; velocities are untouched.
    fn close_gaps(&mut self) {
        // The first piece meets the world pin's anchor, if it has one.
        let mut target: Option<Vector> = self.free.front().and_then(|first| {
            self.world
                .impulse_joints
                .joints_between(self.ground, first.body)
                .map(|(_, j)| j.data.local_anchor1())
                .last()
        });
        for i in 0..self.free.len() {
            let piece = self.free[i];
            let [near, far] = [self.local[piece.first][0], self.local[piece.last][1]];
            let body = &mut self.world.bodies[piece.body];
            let pose = *body.position();
            if let Some(t) = target {
                let d = t - pose.transform_point(near);
                body.set_translation(pose.translation + d, false);
            }
            target = Some(body.position().transform_point(far));
        }
    }

    /// The bodies of the moving part while the coil rolls: the coil, and the link hanging
    /// from it if it has not been laid (it has no floor contact yet). Empty after the release.
    fn moving_part(&self) -> Vec<RigidBodyHandle> {
        let Some(coil) = self.coil else {
            return Vec::new();
        };
        let hanging = self
            .free
            .back()
            .filter(|p| self.world.bodies[p.body].colliders().is_empty())
            .map(|p| p.body);
        std::iter::once(coil).chain(hanging).collect()
    }

    /// Linear momentum of some bodies (kg m/s).
    fn momentum_of(&self, bodies: &[RigidBodyHandle]) -> [f64; 2] {
        bodies.iter().fold([0.0, 0.0], |p, &h| {
            let body = &self.world.bodies[h];
            let v = body.linvel() * body.mass();
            [p[0] + v.x, p[1] + v.y]
        })
    }

    /// The paper's origin: the laid tape's outer end, on the floor's contact plane.
    fn origin(&self) -> Vector {
        Vector::new(0.0, self.half_b)
    }

    /// Angular momentum of some bodies about the origin, counter-clockwise (kg m^2/s).
    fn angular_momentum_of(&self, bodies: &[RigidBodyHandle]) -> f64 {
        bodies
            .iter()
            .map(|&h| {
                let body = &self.world.bodies[h];
                let r = body.center_of_mass() - self.origin();
                let own = body.mass_properties().effective_angular_inertia();
                r.perp_dot(body.linvel() * body.mass()) + own * body.angvel()
            })
            .sum()
    }

    /// Where the laid tape pulls on the moving part: the hanging link's near node, or, if
    /// the last link to leave has been laid, the coil's node it is joined at (world, m).
    fn pull_point(&self) -> Option<Vector> {
        self.coil?;
        let p = self.free.back()?;
        let body = &self.world.bodies[p.body];
        let node = if body.colliders().is_empty() {
            self.local[p.first][0]
        } else {
            self.local[p.last][1]
        };
        Some(body.position().transform_point(node))
    }

    /// The moving part's angular momentum about the origin over the step just taken, from
    /// how far each body moved and turned in it, at its mid-step position (kg m^2/s). The
    /// engine's velocities after a step are not quite those: on a resting contact they keep
    /// gravity's pull of the last substep (`g dt / substeps`, 2.3 mm/s downward for the thin
    /// tape at 1 ms and 4 iterations, where the coil's centre of mass really descends at
    /// 0.46 mm/s), which is nothing for the momentum's rate of change (a steady offset) but
    /// everything for `x P_y` with the contact line metres from the origin.
    fn moved_angular_momentum(&self, before: &MovingSnapshot, dt: f64) -> f64 {
        if dt <= 0.0 {
            return 0.0;
        }
        let o = self.origin();
        before
            .bodies
            .iter()
            .zip(before.centres.iter().zip(&before.angles))
            .map(|(&h, (&c0, &a0))| {
                let body = &self.world.bodies[h];
                let c1 = body.center_of_mass();
                let mut turn = body.rotation().angle() - a0;
                turn -= (turn / (2.0 * PI)).round() * 2.0 * PI;
                let own = body.mass_properties().effective_angular_inertia();
                (0.5 * (c0 + c1) - o).perp_dot((c1 - c0) * (body.mass() / dt)) + own * turn / dt
            })
            .sum()
    }

    fn snapshot(&self) -> MovingSnapshot {
        let bodies = self.moving_part();
        MovingSnapshot {
            momentum: self.momentum_of(&bodies),
            angular_momentum: self.angular_momentum_of(&bodies),
            centres: bodies
                .iter()
                .map(|&h| self.world.bodies[h].center_of_mass())
                .collect(),
            angles: bodies
                .iter()
                .map(|&h| self.world.bodies[h].rotation().angle())
                .collect(),
            pull_at: self.pull_point(),
            contact_x: self.x_low,
            bodies,
        }
    }

    /// The impulses of the step just taken on the moving part, `before` at its start (see
    /// [`StepImpulses`]).
    fn step_impulses(
        &self,
        before: &MovingSnapshot,
        contacts: &[work::FloorImpulse],
        dt: f64,
    ) -> StepImpulses {
        let mut out = StepImpulses::default();
        let o = self.origin();
        let moving = &before.bodies;
        let mut floor_angular = 0.0;
        for c in contacts {
            let f = c.normal + c.friction;
            out.floor_on_moving[0] += f.x;
            out.floor_on_moving[1] += f.y;
            if Some(c.body) == self.coil
                && let Some(i) = moving.iter().position(|&h| h == c.body)
            {
                out.floor_on_coil[0] += f.x;
                out.floor_on_coil[1] += f.y;
                floor_angular += (before.centres[i] + c.arm - o).perp_dot(f);
            }
        }
        if moving.is_empty() {
            return out;
        }
        let after = self.momentum_of(moving);
        let mut gravity_angular = 0.0;
        let mut gravity_at_x = 0.0;
        let mut mass = 0.0;
        for (&h, &c0) in moving.iter().zip(&before.centres) {
            let body = &self.world.bodies[h];
            let w = self.world.gravity * (body.mass() * dt);
            let mid = 0.5 * (c0 + body.center_of_mass());
            gravity_angular += (mid - o).perp_dot(w);
            gravity_at_x += Vector::new(before.contact_x - o.x, mid.y - o.y).perp_dot(w);
            mass += body.mass();
        }
        let g = self.world.gravity * (mass * dt);
        out.total = [
            after[0] - before.momentum[0] - g.x,
            after[1] - before.momentum[1] - g.y,
        ];
        let laid = out.laid();
        let pull_at = match (before.pull_at, self.pull_point()) {
            (Some(a), Some(b)) => Some(0.5 * (a + b)),
            (a, b) => a.or(b),
        };
        let laid_angular = pull_at.map_or(0.0, |p| (p - o).perp_dot(Vector::new(laid[0], laid[1])));
        out.about_origin = AngularImpulses {
            change: self.angular_momentum_of(moving) - before.angular_momentum,
            gravity: gravity_angular,
            floor: floor_angular,
            laid: laid_angular,
            gravity_at_contact_line: gravity_at_x,
            others_at_contact_line: (before.contact_x - o.x) * out.total[1],
        };
        out
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
        // The floor's force on everything that moves over the last step.
        let (normal_n, friction_n) = if self.last_dt > 0.0 {
            let f = self.impulses.floor_on_moving;
            (f[1] / self.last_dt, f[0] / self.last_dt)
        } else {
            (0.0, 0.0)
        };
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
            bang: self.bang,
            detached: self.first_attached,
            active_bodies: self.world.bodies.len() - 1,
            max_joint_gap_m: self.max_joint_gap(),
            max_penetration_m: self.max_penetration(),
            dt_s: self.last_dt,
            angular_momentum_o: self.moved_angular_momentum,
            impulses: self.impulses,
        }
    }

    /// The link nodes in the world frame (m), for drawing: `(off, wound)`. `off` runs from
    /// the tape's outer end through the frozen and the moving links that left the coil;
    /// `wound` runs from the coil's outermost attached node inward. Consecutive nodes bound
    /// one link; either list is empty when it has no link.
    pub fn link_nodes(&self) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        let mut off = self.frozen_nodes.clone();
        for (i, &piece) in self.free.iter().enumerate() {
            if i == 0 {
                // The first moving piece's near node replaces the last frozen far node.
                off.pop();
            }
            let pose = self.world.bodies[piece.body].position();
            let nodes = self.piece_nodes(piece).map(|n| pose.transform_point(n));
            // Each piece's far node is the next one's near node.
            let skip_far = usize::from(i + 1 < self.free.len());
            let count = piece.last - piece.first + 2 - skip_far;
            off.extend(nodes.take(count).map(|p| [p.x, p.y]));
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

    /// Where the tape's free (inner) end is: x of its innermost node (m).
    pub fn tape_end_x_m(&self) -> f64 {
        if let Some(&piece) = self.free.back() {
            let pose = self.world.bodies[piece.body].position();
            return pose.transform_point(self.local[piece.last][1]).x;
        }
        if self.coil.is_none()
            && let Some(n) = self.frozen_nodes.last()
        {
            return n[0];
        }
        let (_, wound) = self.link_nodes();
        wound.last().map_or(0.0, |n| n[0])
    }

    /// The tape's midline length as the links lay it: the sum of their lengths (m).
    pub fn tape_length_m(&self) -> f64 {
        self.links.iter().map(|l| l.length_m).sum()
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

    /// The floor's force on everything touching it during the last step of length `dt`:
    /// `(normal, horizontal)` in N, the step's contact impulses (as the model reads them)
    /// over `dt`.
    fn floor_forces(world: &PhysicsWorld, floor: ColliderHandle, dt: f64) -> (f64, f64) {
        work::floor_impulses(&world.narrow_phase, &world.colliders, floor).fold(
            (0.0, 0.0),
            |(n, f), c| {
                let p = c.normal + c.friction;
                (n + p.y / dt, f + p.x / dt)
            },
        )
    }

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
        let (n, f) = floor_forces(&world, floor, 1e-3);
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
        let (n, f) = floor_forces(&world, floor, 1e-3);
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
    fn impulses_on_the_moving_part_have_the_papers_signs_and_close_the_momentum_balance() {
        // Early in the unroll: the floor holds the coil up (N > 0, about M g) and the total
        // horizontal force points along +x, where the coil goes (eq. 11 before its sign
        // change); the laid tape's share is what the momentum balance leaves of the floor's.
        let mut model = Model::new(&yoga());
        let (mut sum, mut time) = (StepImpulses::default(), 0.0);
        for _ in 0..300 {
            let o = model.step();
            sum.add(&o.impulses);
            time += o.dt_s;
        }
        let weight = 1.5 * 9.81;
        let n = sum.floor_on_coil[1] / time;
        assert!((n / weight - 1.0).abs() < 0.15, "N = {n} N");
        assert!(sum.total[0] > 0.0, "F_tot = {} N", sum.total[0] / time);
        let laid = sum.laid();
        assert!(
            (laid[0] + sum.floor_on_coil[0] - sum.total[0]).abs() < 1e-15,
            "F + F_int != F_tot"
        );
        // The floor's force on everything that moves includes the coil's.
        assert!(sum.floor_on_moving[1] >= sum.floor_on_coil[1]);
    }

    #[test]
    fn engine_reports_a_velocity_that_keeps_the_last_substeps_gravity() {
        // On a resting contact the velocity the engine reports after a step is not the one
        // it moved the body by: it keeps gravity's pull of the last substep, g dt / substeps.
        // This is why `L_O` is taken from how far the bodies moved. `cargo test --release
        // --lib engine_reports -- --nocapture` prints the figures.
        let mut model = Model::new(&yoga());
        model.set_shedding(false);
        for _ in 0..300 {
            model.step();
        }
        let coil = model.coil.unwrap();
        let (mut moved, mut reported, mut dt) = (0.0, 0.0, 0.0);
        for _ in 0..100 {
            let c0 = model.world.bodies[coil].center_of_mass();
            let o = model.step();
            let body = &model.world.bodies[coil];
            moved += body.center_of_mass().y - c0.y;
            reported += body.linvel().y * o.dt_s;
            dt += o.dt_s;
        }
        let substeps = model.world.integration_parameters.num_solver_iterations as f64;
        let lag = (reported - moved) / dt;
        let expected = -9.81 * model.last_dt / substeps;
        eprintln!(
            "coil moved {:.3e} m/s, reported {:.3e} m/s: lag {lag:.3e} m/s, g dt / {substeps} = {expected:.3e} m/s",
            moved / dt,
            reported / dt
        );
        assert!(
            (lag / expected - 1.0).abs() < 0.2,
            "lag {lag}, expected {expected}"
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
