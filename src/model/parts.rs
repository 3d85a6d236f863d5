//! The model's state in owned parts: what the scene fixed ([`Settings`]), the wound coil
//! ([`Coil`]), the tape's links off it ([`Chain`]) and the energy's books ([`Accounts`]).
//! [`Model`](super::Model) holds one of each beside the engine's world, its phase and clock.

use std::collections::VecDeque;

use rapier2d_f64::prelude::*;

use super::build::{CoilSums, Link, Piece};
use super::impulses::StepImpulses;
use super::{EnergyLedger, Phase};
use crate::spiral::{Spiral, SpiralMoments};

/// What the scene fixed: the steps' rules, the bang's settings, gravity and the tape's
/// constants. Set once in [`Model::new`](super::Model::new), never changed.
pub(super) struct Settings {
    pub(super) link_angle: f64,
    pub(super) steps_per_link: f64,
    pub(super) max_dt: f64,
    pub(super) freeze_speed: f64,
    pub(super) bang_step_rad: f64,
    /// The bound on the bang's steps' error, if any (see `Solver::bang_tolerance`).
    pub(super) bang_tolerance: Option<f64>,
    /// Shortest piece the remaining wound links are grouped into at the release (m).
    pub(super) bang_piece_m: f64,
    /// How far above the floor's contact plane a piece is pinned in the bang (m).
    pub(super) pin_lift_m: f64,
    /// Softness of every joint (see `Solver::joint_hz`).
    pub(super) joint_softness: SpringCoefficients<Real>,
    /// Softness of every joint from the release on (see `Solver::bang_joint_hz`).
    pub(super) bang_joint_softness: SpringCoefficients<Real>,
    pub(super) friction: f64,
    /// Gravity across the floor, `g cos(alpha)`, pulling towards it (m/s^2).
    pub(super) g: f64,
    /// Gravity along the floor, `g sin(alpha)`, towards +x (m/s^2); 0 on a level floor.
    pub(super) g_along: f64,
    /// First moment `sum m_k x_k` of the tape lying flat from `x = 0` (kg m).
    pub(super) flat_first_moment: f64,
    pub(super) half_b: f64,
    pub(super) bang_fraction: f64,
    pub(super) bang_iterations: usize,
    pub(super) bang_relax_iterations: usize,
    /// What solves the bang.
    pub(super) bang_engine: crate::scene::BangEngine,
    /// Coulomb's coefficient between the tape's layers in the bang.
    pub(super) self_friction: f64,
    pub(super) bang_cap_s: f64,
    pub(super) rest_fraction: f64,
    pub(super) total_mass: f64,
}

/// The wound coil: its spiral, its body (until the release), the ball it touches the floor
/// with, and where on the spiral it stands.
pub(super) struct Coil {
    pub(super) spiral: Spiral,
    pub(super) moments: SpiralMoments,
    /// The coil's body, until the release.
    pub(super) body: Option<RigidBodyHandle>,
    /// The ball it touches the floor with, refitted every step.
    pub(super) ball: Option<ColliderHandle>,
    /// A sticky floor's hold on the coil, moved every step: no slip at the contact line
    /// (x locked) and the contact ball's centre at its height (y locked).
    pub(super) stick: Option<[ImpulseJointHandle; 2]>,
    /// The wound links' mass properties.
    pub(super) sums: CoilSums,
    /// Index of the outermost link still in the coil.
    pub(super) first_attached: usize,
    /// Unwrapped rotation angle of the coil (rad).
    pub(super) angle: f64,
    /// The coil's rotation minus that of a rolling coil with the same point leaving it:
    /// 0 on the floor, pi/2 on a fixed axis, where the tape leaves at the side (rad).
    pub(super) angle_offset: f64,
    /// The spiral's angle at the coil's lowest point (rad).
    pub(super) psi_low: f64,
    /// A link's chord over its arc, which sizes the contact ball.
    pub(super) chord_ratio: f64,
}

impl Coil {
    /// The spiral's angle at link `k`'s near node.
    pub(super) fn near_node_psi(&self, k: usize, link_angle: f64) -> f64 {
        if k == 0 {
            self.spiral.psi_out
        } else {
            self.far_node_psi(k - 1, link_angle)
        }
    }

    /// The spiral's angle at link `k`'s far node: nodes step inward by one link angle from
    /// the outer end.
    pub(super) fn far_node_psi(&self, k: usize, link_angle: f64) -> f64 {
        let psi = self.spiral.psi_out - link_angle * (k + 1) as f64;
        psi.max(self.spiral.psi_in)
    }

    /// Laid mass fraction along the continuous spiral up to the lowest point.
    pub(super) fn laid_fraction(&self) -> f64 {
        1.0 - self.moments.at(self.psi_low)[0] / self.spiral.length()
    }
}

/// The tape as links: every link's geometry, the moving pieces off the coil, and the frozen
/// links' remains.
pub(super) struct Chain {
    pub(super) links: Vec<Link>,
    /// Each link's near and far node in the frame of the body that holds it (m): the
    /// spiral's coordinates while it is wound or in a piece spawned from the coil, the
    /// world's in a piece joined from moving links.
    pub(super) local: Vec<[Vector; 2]>,
    /// The moving pieces, from the laid end inward.
    pub(super) free: VecDeque<Piece>,
    /// The frozen links' potential energy (J).
    pub(super) frozen_potential_j: f64,
    /// Near node of each frozen link, from the outer end, and the far node of the last one
    /// (world frame, m): frozen links have no body left to ask.
    pub(super) frozen_nodes: Vec<[f64; 2]>,
    /// Each node's arc length along the tape from its outer end: link `k`'s near node at
    /// `arc_m[k]`, its far node at `arc_m[k + 1]` (m).
    pub(super) arc_m: Vec<f64>,
}

impl Chain {
    /// The links of `links`, each in the coil's frame, none moving or frozen yet.
    pub(super) fn wound(links: Vec<Link>) -> Self {
        let local = links
            .iter()
            .map(|l| {
                [
                    Vector::new(l.near[0], l.near[1]),
                    Vector::new(l.far[0], l.far[1]),
                ]
            })
            .collect();
        let arc_m = std::iter::once(0.0)
            .chain(links.iter().scan(0.0, |s, l| {
                *s += l.length_m;
                Some(*s)
            }))
            .collect();
        Self {
            links,
            local,
            free: VecDeque::new(),
            frozen_potential_j: 0.0,
            frozen_nodes: Vec::new(),
            arc_m,
        }
    }

    /// Number of links of the tape.
    pub(super) fn len(&self) -> usize {
        self.links.len()
    }

    /// The tape's length, the sum of its links' (m).
    pub(super) fn length_m(&self) -> f64 {
        self.links.iter().map(|l| l.length_m).sum()
    }

    /// `piece`'s nodes in its body's frame, from its near node inward.
    pub(super) fn piece_nodes(&self, piece: Piece) -> impl Iterator<Item = Vector> + '_ {
        std::iter::once(self.local[piece.first][0])
            .chain(self.local[piece.first..=piece.last].iter().map(|l| l[1]))
    }
}

/// The energy's books: the ledger, the energy at the last observation, and the last step's
/// impulses and angular momentum that the forces are read from.
#[derive(Default)]
pub(super) struct Accounts {
    pub(super) ledger: EnergyLedger,
    /// Kinetic plus potential energy at the last observation, the next step's start (J).
    pub(super) energy_j: f64,
    /// The last step's impulses on the moving part.
    pub(super) impulses: StepImpulses,
    /// The moving part's angular momentum about the origin over the last step, from how
    /// far it moved (kg m^2/s): see `Model::moved_angular_momentum`.
    pub(super) moved_angular_momentum: f64,
    /// The kinetic and potential energy the last step ended with (J), and the state they
    /// were read at: an observation of that same state reads them instead of summing every
    /// body again.
    pub(super) step_energy: Option<(EnergyKey, f64, f64)>,
}

/// What changes the set of bodies or their masses between a step's end and its observation:
/// the phase, the links shed, the pieces moving, the links frozen.
pub(super) type EnergyKey = (Phase, usize, usize, usize);
