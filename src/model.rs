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

use std::f64::consts::PI;

use rapier2d_f64::prelude::*;
use serde::{Deserialize, Serialize};

use crate::scene::{BangEngine, Scene};
use crate::spiral::{Placed, Spiral, SpiralMoments, rotate};

mod bang;
mod blocks;
mod build;
pub mod exact_chain;
pub mod folded;
mod impulses;
mod observe;
mod parts;
mod shed;
mod work;

use build::{CoilSums, Piece};
pub use impulses::{AngularImpulses, StepImpulses};
use parts::{Accounts, Chain, Coil, Settings};
pub use work::BangLedger;

/// What ended the final bang.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BangEnd {
    /// The moving tape's energy above lying at rest on the floor (kinetic, plus its weight
    /// times its height above lying flat) fell below `stop.rest_fraction` of the kinetic
    /// energy the bang received.
    Rest,
    /// `stop.bang_cap_s` of simulated time passed first.
    Cap,
}

/// The largest stand-off of the released coil's chords from their arcs, in thicknesses, at
/// which the bang's layers meet: beyond it the polygon's own turns overlap by more than the
/// overlap guard's bound (half the thickness) before anything moves, so the thickness is
/// not resolved, and the layers are left out, the summary saying so.
pub const LAYERS_RESOLVED_PER_THICKNESS: f64 = 0.5;

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
    /// How the exact chain solved the bang's steps (all zero on the engine's).
    pub solve: exact_chain::SolveStats,
    /// How far the released coil's links stand off the arcs they stand for (m): a chord of
    /// length `l` turning by the link angle `phi` is `l phi / 8` inside its arc at its middle,
    /// where the next turn's polygon can reach it. The tape's layers are resolved, and meet,
    /// only where this is below half the thickness ([`LAYERS_RESOLVED_PER_THICKNESS`]).
    pub chord_sag_m: f64,
    /// Whether the bang's layers meet each other (see `chord_sag_m`).
    pub layers: bool,
    /// The ratio the handover scaled every speed by for the pieces' thickness, keeping the
    /// energy the unroll brought (see `Model::join_pieces`); 0 before the release.
    pub thickness_speed_ratio: f64,
}

use work::BodyState;

/// Where the energy went, each part measured where it happens (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
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
    /// Deepest two layers of the tape overlap (pieces not joined to each other, or a piece
    /// and the laid tape) at the end of the last step (m); 0 but in the bang.
    pub max_overlap_m: f64,
    /// The last step's length (s).
    pub dt_s: f64,
    /// Angular momentum of the moving part (the coil and the link hanging from it) about
    /// the origin `(0, b/2)` over the last step, from how far it moved, counter-clockwise
    /// (kg m^2/s); 0 once the coil is released.
    pub angular_momentum_o: f64,
    /// What acted on the tape during the last step, as impulses (N s).
    pub impulses: StepImpulses,
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
    /// The exact chain's solve failed, and why (the step was not taken).
    pub unsolved: Option<exact_chain::StepError>,
}

/// In the bang a piece is pinned this fraction of R above the floor's contact plane (the
/// engine's tolerances scale with R): see [`Model::pin_to_world`].
const PIN_LIFT_PER_RADIUS: f64 = 1e-4;

const TAPE_GROUP: Group = Group::GROUP_1;

const FLOOR_GROUP: Group = Group::GROUP_2;

/// The contact-resolved tape.
pub struct Model {
    world: PhysicsWorld,
    /// What the scene fixed.
    settings: Settings,
    /// The wound coil.
    coil: Coil,
    /// The links off the coil: moving, frozen.
    chain: Chain,
    /// The energy's books.
    accounts: Accounts,
    /// The final bang's record.
    bang: BangRecord,
    /// The bang's exact chain, once it steps the bang.
    exact: Option<bang::exact::ExactBang>,
    ground: RigidBodyHandle,
    floor: ColliderHandle,
    phase: Phase,
    t: f64,
    last_dt: f64,
    x_low: f64,
    shedding: bool,
}

impl Model {
    /// Builds the world for a scene: floor, the wound coil as one body, nothing else.
    pub fn new(scene: &Scene) -> Self {
        let tape = &scene.tape;
        let b = tape.thickness_m;
        let spiral = Spiral::wound(tape.outer_radius_m, b, tape.core_radius_m);
        let moments = SpiralMoments::new(spiral);
        let links = build::chain_links(&spiral, scene.discretisation.links_per_turn, tape.mass_kg);
        let (mut world, g_along, g_perp) = build::new_world(scene);
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let floor = build::insert_floor(&mut world, scene, &spiral, ground);
        let mut coil_sums = CoilSums::default();
        for link in &links {
            coil_sums.add(link, 1.0);
        }
        let first = links[0];
        let start = build::CoilStart::new(scene, &spiral, &first, &coil_sums.mass_properties());
        let (coil, coil_ball, stick) =
            build::insert_coil(&mut world, scene, &spiral, &start, &coil_sums, ground);
        let (psi_low, coil_angle, angle_offset) = (start.psi_low, start.angle, start.angle_offset);
        let bang_fraction = build::bang_fraction(scene, &spiral, &moments);
        let flat_first_moment = build::flat_first_moment(&links);
        let mut model = Self {
            world,
            settings: Settings {
                link_angle: 2.0 * PI / f64::from(scene.discretisation.links_per_turn),
                steps_per_link: scene.solver.steps_per_link,
                max_dt: scene.solver.max_dt_s,
                freeze_speed: scene.solver.freeze_speed_m_s,
                bang_step_rad: scene.solver.bang_step_rad,
                bang_tolerance: scene.solver.bang_tolerance,
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
                friction: scene.floor.friction,
                g: g_perp,
                g_along,
                flat_first_moment,
                half_b: 0.5 * b,
                bang_fraction,
                bang_iterations: scene.solver.bang_iterations as usize,
                bang_relax_iterations: scene.solver.bang_relax_iterations as usize,
                bang_engine: scene.solver.bang_engine,
                self_friction: tape.self_friction,
                bang_cap_s: scene.stop.bang_cap_s,
                rest_fraction: scene.stop.rest_fraction,
                total_mass: tape.mass_kg,
            },
            coil: Coil {
                spiral,
                moments,
                body: Some(coil),
                ball: Some(coil_ball),
                stick,
                sums: coil_sums,
                first_attached: 0,
                angle: coil_angle,
                angle_offset,
                psi_low,
                chord_ratio: first.chord_ratio,
            },
            chain: Chain::wound(links),
            accounts: Accounts::default(),
            bang: BangRecord::default(),
            exact: None,
            ground,
            floor,
            phase: Phase::Rolling,
            t: 0.0,
            last_dt: 0.0,
            x_low: 0.0,
            shedding: true,
        };
        model.restick();
        model.accounts.energy_j = model.total_energy();
        model
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
        self.chain.len()
    }

    /// Kinetic and potential energy of the whole tape (J).
    pub fn energy(&self) -> (f64, f64) {
        let mut kinetic = 0.0;
        let mut potential = self.chain.frozen_potential_j;
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
        body.mass() * self.settings.g * c.y - body.mass() * self.settings.g_along * c.x
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
            Phase::Rolling => self.settings.link_angle / self.settings.steps_per_link,
            _ => self.settings.bang_step_rad,
        };
        if spin > 0.0 {
            (turn / spin).min(self.settings.max_dt)
        } else {
            self.settings.max_dt
        }
    }

    /// Advances the model by one adaptive step and reports the state.
    pub fn step(&mut self) -> Observation {
        let dt = self.next_dt();
        self.world.integration_parameters.dt = dt;
        let before = self.accounts.energy_j;
        let states: Vec<BodyState> = if self.phase == Phase::Bang {
            self.chain
                .free
                .iter()
                .map(|l| BodyState::of(&self.world.bodies[l.body]))
                .collect()
        } else {
            Vec::new()
        };
        let moving = self.snapshot();
        // The floor's contact impulses of the step, read once for the forces and the ledger.
        let contacts: Vec<(RigidBodyHandle, work::FloorImpulse)> = if self.on_exact_chain() {
            self.step_exact(dt)
        } else {
            self.world.step();
            work::floor_impulses(&self.world.narrow_phase, &self.world.colliders, self.floor)
                .collect()
        };
        self.t += dt;
        self.last_dt = dt;
        self.accounts.impulses = self.step_impulses(&moving, &contacts, dt);
        self.accounts.moved_angular_momentum = self.moved_angular_momentum(&moving, dt);
        let (kinetic, potential) = self.energy();
        self.accounts.step_energy = Some((self.energy_key(), kinetic, potential));
        let after = kinetic + potential;
        match self.phase {
            Phase::Rolling => self.accounts.ledger.step_j += before - after,
            _ => self.book_bang_step(&states, &contacts, before - after, kinetic, dt),
        }

        if let Some(coil) = self.coil.body {
            let angle = self.world.bodies[coil].rotation().angle();
            let mut d = angle - self.coil.angle;
            d -= (d / (2.0 * PI)).round() * 2.0 * PI;
            self.coil.angle += d;
            self.coil.psi_low = self
                .coil
                .spiral
                .lowest_psi(self.coil.angle - self.coil.angle_offset, self.coil.psi_low)
                .clamp(self.coil.spiral.psi_in, self.coil.spiral.psi_out);
            while self.shedding
                && self.coil.first_attached + 1 < self.chain.len()
                && self.coil.psi_low <= self.near_node_psi(self.coil.first_attached)
            {
                self.detach_outermost();
            }
            self.refit_ball();
            if self.laid_fraction() >= self.settings.bang_fraction
                || self.coil.first_attached + 1 >= self.chain.len()
            {
                self.release_coil();
            }
        }
        if self.phase == Phase::Rolling && self.settings.friction == 0.0 {
            self.join_laid();
        } else {
            self.freeze_settled();
        }
        if self.phase == Phase::Bang && self.t - self.bang.started_s >= self.settings.bang_cap_s {
            self.end_bang(BangEnd::Cap);
        }
        self.observe()
    }

    /// The state that [`Accounts::step_energy`] was read at.
    fn energy_key(&self) -> parts::EnergyKey {
        (
            self.phase,
            self.coil.first_attached,
            self.chain.free.len(),
            self.chain.frozen_nodes.len(),
        )
    }

    /// Whether the exact chain steps the model now: in the bang, if the scene says so.
    fn on_exact_chain(&self) -> bool {
        self.phase == Phase::Bang && self.settings.bang_engine == BangEngine::Exact
    }

    fn near_node_psi(&self, k: usize) -> f64 {
        self.coil.near_node_psi(k, self.settings.link_angle)
    }

    /// Laid mass fraction along the continuous spiral up to the lowest point.
    pub fn laid_fraction(&self) -> f64 {
        self.coil.laid_fraction()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The yoga mat: R = 0.06 m, b = 0.005 m, M = 1.5 kg, pushed at 0.3 m/s.
    pub(crate) fn yoga() -> Scene {
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
