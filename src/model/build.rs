//! Building the model: the links as chords of the spiral, the wound coil's summed mass
//! properties, the collision groups and the coil's contact ball. It steps nothing.

use super::*;

/// One link of the discretised tape: a chord of the spiral between two nodes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Link {
    /// Node towards the laid end (body frame of the coil).
    pub(super) near: [f64; 2],
    /// Node towards the centre.
    pub(super) far: [f64; 2],
    pub(super) mass_kg: f64,
    pub(super) length_m: f64,
    /// Chord over arc length of the spiral between the nodes.
    pub(super) chord_ratio: f64,
    /// How far the node line sits below the contact surface (m), see [`Model`].
    pub(super) inset_m: f64,
}

impl Link {
    pub(super) fn centre(&self) -> [f64; 2] {
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
pub(super) struct Piece {
    /// The links `first..=last`, from the laid end inward.
    pub(super) first: usize,
    pub(super) last: usize,
    pub(super) body: RigidBodyHandle,
    /// Height of its centre of mass when it lies flat on the floor (m).
    pub(super) rest_y_m: f64,
}

/// Running sums of the coil's mass moments in its body frame.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct CoilSums {
    pub(super) mass: f64,
    pub(super) first: [f64; 2],
    /// Second moment about the body origin, own inertia of each link included.
    pub(super) second: f64,
}

impl CoilSums {
    pub(super) fn add(&mut self, link: &Link, sign: f64) {
        let c = link.centre();
        let m = sign * link.mass_kg;
        self.mass += m;
        self.first[0] += m * c[0];
        self.first[1] += m * c[1];
        self.second += m * (c[0] * c[0] + c[1] * c[1] + link.length_m * link.length_m / 12.0);
    }

    pub(super) fn mass_properties(&self) -> MassProperties {
        let com = [self.first[0] / self.mass, self.first[1] / self.mass];
        let inertia = self.second - self.mass * (com[0] * com[0] + com[1] * com[1]);
        MassProperties::new(Vector::new(com[0], com[1]), self.mass, inertia.max(0.0))
    }
}

impl Model {
    pub(super) fn tape_groups() -> InteractionGroups {
        InteractionGroups::new(TAPE_GROUP, FLOOR_GROUP, InteractionTestMode::And)
    }

    /// The coil's contact: the osculating circle of the midline at its lowest point, shrunk
    /// by `chord_ratio` (see `refit_ball`).
    pub(super) fn ball_builder(
        spiral: &Spiral,
        psi: f64,
        chord_ratio: f64,
        friction: f64,
    ) -> ColliderBuilder {
        let c = spiral.curvature_centre(psi);
        ColliderBuilder::ball(spiral.curvature_radius(psi) * chord_ratio)
            .density(0.0)
            .friction(friction)
            .position(Pose::from_translation(Vector::new(c[0], c[1])))
            .collision_groups(Self::tape_groups())
    }
}

/// The links of the spiral: chords between its nodes, `links_per_turn` to a turn, the
/// tape's mass spread over them by length.
pub(super) fn chain_links(spiral: &Spiral, links_per_turn: u32, mass_kg: f64) -> Vec<Link> {
    let nodes = spiral.link_nodes(links_per_turn);
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
        link.mass_kg = mass_kg * link.length_m / total_len;
    }
    links
}

/// The engine's world for a scene, still empty: gravity tilted by the slope, the solver's
/// settings and the floor's stiffness. Returns it with gravity along the floor and across
/// it (m/s^2).
pub(super) fn new_world(scene: &Scene) -> (PhysicsWorld, f64, f64) {
    let mut world = PhysicsWorld::new();
    // A slope tilts gravity in the simulation frame; the floor stays the plane y = b/2.
    let (sin_a, cos_a) = scene.floor.slope_deg.to_radians().sin_cos();
    let (g_along, g_perp) = (scene.gravity.g_m_s2 * sin_a, scene.gravity.g_m_s2 * cos_a);
    world.gravity = Vector::new(g_along, -g_perp);
    let ip = &mut world.integration_parameters;
    ip.num_solver_iterations = scene.solver.iterations as usize;
    // The engine's tolerances (contact prediction, corrective speed) are fractions of
    // `length_unit`: the coil's size sets the scale of what moves.
    ip.length_unit = 0.1 * scene.tape.outer_radius_m;
    // The engine clamps speeds at `normalized_max_linear_velocity * length_unit` (2.4 m/s
    // for the yoga mat): the end of an unroll is far faster than that, so lift the cap.
    ip.normalized_max_linear_velocity = Real::MAX;
    ip.dt = scene.solver.max_dt_s;
    // No continuous collision detection: the adaptive step turns no body by more than a
    // fraction of a link angle (a bang piece by `bang_step_rad`), so nothing moves through
    // the floor within a step, and the guards' penetration bound checks that every step.
    // Left on, the engine sweeps every fast body against the floor each step (an eighth of
    // the thin tape's engine time).
    ip.max_ccd_substeps = 0;
    // The floor is a damped spring in rapier (60 Hz by default): the coil would sink
    // g / (2 pi f)^2 into it, losing that potential energy in the spring's damper, and the
    // load changes of every link would be damped too. See `Solver::contact_hz`.
    let floor_soft = SpringCoefficients::new(
        scene.solver.contact_hz,
        ip.static_contact_softness.damping_ratio,
    );
    ip.static_contact_softness = floor_soft;
    ip.contact_softness = floor_soft;
    (world, g_along, g_perp)
}

/// The floor: a half-space whose surface is the laid tape's midline plane, `y = b/2`, or
/// out of the tape's reach on a fixed axis.
pub(super) fn insert_floor(
    world: &mut PhysicsWorld,
    scene: &Scene,
    spiral: &Spiral,
    ground: RigidBodyHandle,
) -> ColliderHandle {
    // On a fixed axis the tape hangs freely: the floor is put out of its reach.
    let floor_y = if scene.axis.fixed {
        -(spiral.length() + scene.tape.outer_radius_m + 1.0)
    } else {
        0.5 * scene.tape.thickness_m
    };
    world.insert_collider(floor_builder(floor_y, scene.floor.friction), Some(ground))
}

/// A floor: the half-space below `y` in its parent's frame, with `friction`, meeting the
/// tape and nothing else.
pub(super) fn floor_builder(y: f64, friction: f64) -> ColliderBuilder {
    ColliderBuilder::new(SharedShape::halfspace(Vector::Y))
        .translation(Vector::new(0.0, y))
        .friction(friction)
        .collision_groups(InteractionGroups::new(
            FLOOR_GROUP,
            TAPE_GROUP,
            InteractionTestMode::And,
        ))
}

/// How the coil starts: where it stands, how it is turned and how it moves.
pub(super) struct CoilStart {
    /// The spiral's parameter at its lowest point.
    pub(super) psi_low: f64,
    /// The spiral centre's position (m).
    origin: [f64; 2],
    /// The coil's rotation (rad).
    pub(super) angle: f64,
    /// See `Model::angle_offset` (rad).
    pub(super) angle_offset: f64,
    linvel: Vector,
    /// Clockwise spin, negative (rad/s).
    omega: f64,
    /// The first link's chord ratio, which shrinks the contact ball.
    chord_ratio: f64,
}

impl CoilStart {
    /// The coil on the floor at its lowest point, rolling at the push speed; spinning in
    /// place on a frictionless floor; turned by a quarter turn about its centre on a fixed
    /// axis.
    pub(super) fn new(
        scene: &Scene,
        spiral: &Spiral,
        first: &Link,
        mprops: &MassProperties,
    ) -> Self {
        let b = scene.tape.thickness_m;
        let psi_low = spiral.psi_out;
        let coil_angle = spiral.rotation_with_bottom_at(psi_low);
        let p = rotate(spiral.point(psi_low), coil_angle);
        // The contact circle is shrunk by the first link's chord ratio (see `refit_ball`), so
        // the lowest node sits its inset below the floor plane, as every node does when it
        // reaches the floor: start the coil there rather than dropping it onto the floor.
        let origin = [-p[0], 0.5 * b - p[1] - first.inset_m];
        // Rolling about the contact point at the pushed contact-line speed: x' = omega rho.
        let contact_radius = spiral.curvature_radius(psi_low) * first.chord_ratio;
        let omega = -scene.push.contact_speed_m_s / contact_radius;
        let com_local = mprops.local_com;
        let com = rotate([com_local.x, com_local.y], coil_angle);
        let rel = [origin[0] + com[0], origin[1] + com[1] - 0.5 * b];
        // Without friction nothing can make it roll: it starts spinning in place (App. D),
        // its surface moving at the push speed.
        let linvel = if scene.floor.friction > 0.0 {
            Vector::new(-omega * rel[1], omega * rel[0])
        } else {
            Vector::ZERO
        };
        // On a fixed axis (App. E) the picture is turned by a quarter turn about the spiral's
        // centre, which stays at the origin: the tape leaves at the right and hangs down.
        let angle_offset = if scene.axis.fixed { 0.5 * PI } else { 0.0 };
        let (origin, angle, linvel) = if scene.axis.fixed {
            let angle = coil_angle + angle_offset;
            let c = rotate([com_local.x, com_local.y], angle);
            ([0.0, 0.0], angle, Vector::new(-omega * c[1], omega * c[0]))
        } else {
            (origin, coil_angle, linvel)
        };
        Self {
            psi_low,
            origin,
            angle,
            angle_offset,
            linvel,
            omega,
            chord_ratio: first.chord_ratio,
        }
    }
}

/// The coil as one rigid body at its start, on its axis if it has one, with its contact
/// ball and, on a sticky floor, the joints that hold it. Returns the body, the ball and
/// the sticky joints.
pub(super) fn insert_coil(
    world: &mut PhysicsWorld,
    scene: &Scene,
    spiral: &Spiral,
    start: &CoilStart,
    sums: &CoilSums,
    ground: RigidBodyHandle,
) -> (
    RigidBodyHandle,
    ColliderHandle,
    Option<[ImpulseJointHandle; 2]>,
) {
    let coil = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(Pose::new(
                Vector::new(start.origin[0], start.origin[1]),
                start.angle,
            ))
            .additional_mass_properties(sums.mass_properties())
            .linvel(start.linvel)
            .angvel(start.omega)
            .can_sleep(false),
    );
    if scene.axis.fixed {
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
        Model::ball_builder(
            spiral,
            start.psi_low,
            start.chord_ratio,
            scene.floor.friction,
        ),
        Some(coil),
    );
    // The engine computes mass properties lazily at the next step; energies are read
    // before that, so compute them now.
    world.bodies[coil].recompute_mass_properties_from_colliders(&world.colliders);
    // A sticky floor holds the coil bilaterally where a floor contact only pushes; the
    // anchors are set by `restick` before the first step.
    let stick = scene.floor.sticky.then(|| {
        [JointAxesMask::LIN_X, JointAxesMask::LIN_Y].map(|axis| {
            world.insert_impulse_joint(
                ground,
                coil,
                GenericJointBuilder::new(axis).contacts_enabled(false),
            )
        })
    });
    (coil, coil_ball, stick)
}

/// The laid fraction at which the coil is released: where its equivalent radius reaches
/// `stop.bang_radius_m`.
pub(super) fn bang_fraction(scene: &Scene, spiral: &Spiral, moments: &SpiralMoments) -> f64 {
    let bang_r = scene.stop.bang_radius_m;
    if scene.tape.core_radius_m > 0.0 {
        // On a core the mass is not spread over a disc: use the spiral's own laid
        // fraction at the midline radius bang_r.
        let psi = spiral
            .psi_at_radius(bang_r)
            .clamp(spiral.psi_in, spiral.psi_out);
        1.0 - moments.at(psi)[0] / spiral.length()
    } else {
        1.0 - (bang_r / scene.tape.outer_radius_m).powi(2)
    }
}

/// First moment `sum m_k x_k` of the tape lying flat from `x = 0` (kg m).
pub(super) fn flat_first_moment(links: &[Link]) -> f64 {
    let mut laid_x = 0.0;
    let mut moment = 0.0;
    for link in links {
        moment += link.mass_kg * (laid_x + 0.5 * link.length_m);
        laid_x += link.length_m;
    }
    moment
}
