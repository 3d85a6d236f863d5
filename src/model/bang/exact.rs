//! The final bang on the exact chain (`solver.bang_engine = "exact"`): each step the moving
//! pieces are handed to [`ExactChain`] (their mass, inertia, pose, velocity and nodes, the
//! joints' anchors, the pin, the floor), stepped there instead of in the engine, and handed
//! back; the engine's bodies stay the pieces' record, so freezing, pins, observations and
//! frames read them as in the engine's bang. The chain is rebuilt from them when the moving
//! pieces change (a freeze), and refreshed from them otherwise.

use super::*;
use crate::model::exact_chain::{
    self, Body, ErrorBound, ExactChain, Floor, Joint, Layers, Outline, Pin, SolveStats, StepError,
    Surface, Tolerance,
};

/// Two points of the tape closer than this many thicknesses along it never meet as layers:
/// `pi / 2`, the midline of the tightest fold a tape of thickness b can make (a half circle
/// of radius b/2). Points closer along the tape are within one fold and cannot face each
/// other; points farther apart can, so a fold between two pieces is held open by their far
/// parts meeting. A coreless coil's innermost turn (its midline starts at radius b/2) does
/// not overlap itself beyond it.
const LAYER_EXCLUSION_PER_THICKNESS: f64 = std::f64::consts::FRAC_PI_2;

/// The account the bang's tolerance is kept on (see [`Model::error_bound`]).
#[derive(Debug, Clone, Copy, Default)]
struct Budget {
    /// The joints' work over the bang's steps so far, each step's
    /// [`exact_chain::StepReport::joint_error_j`] (J; positive: given to the tape).
    spent_j: f64,
}

/// The exact chain of the bang's moving pieces, and how its steps went.
pub(in crate::model) struct ExactBang {
    chain: ExactChain,
    /// The pieces' bodies along the chain, and the pin's anchors (world, body frame), as the
    /// chain was built from them.
    bodies: Vec<RigidBodyHandle>,
    pin: Option<(Vector, Vector)>,
    /// Each body's centre of mass in its own frame (m).
    centres: Vec<Vector>,
    /// How the steps were solved.
    pub(in crate::model) stats: SolveStats,
    /// The deepest a contact point ended below the floor in the last step (m).
    pub(in crate::model) penetration_m: f64,
    /// The deepest two layers overlapped at the end of the last step (m).
    pub(in crate::model) overlap_m: f64,
    /// The failure that stopped it, if any.
    pub(in crate::model) failed: Option<StepError>,
    /// The error budget's account, kept across rebuilds (see [`Model::error_bound`]).
    budget: Budget,
    /// Gravity's work over the last step (J).
    pub(in crate::model) gravity_work_j: f64,
    /// What the joints took in the last step when they were made rigid (J).
    pub(in crate::model) caught_j: f64,
    /// The work of the contacts between the tape's layers in the last step: their normal
    /// and friction impulses' (J; negative: taken from the tape).
    pub(in crate::model) layers_work_j: [f64; 2],
    /// Each body's nodes in its own axes, from its centre of mass (m).
    nodes: Vec<Vec<[f64; 2]>>,
    /// The bodies before the last step that was solved, and that step's length (s): with
    /// the bodies now, the motion the step realised, which freezing reads (see
    /// [`Model::moved_speed`]). Empty until a step is solved.
    before: (Vec<Body>, f64),
    /// The bodies before the step being taken (a buffer reused from step to step).
    pending: Vec<Body>,
    /// Each engine body's pose and velocity as the last step left it: a body still so is
    /// not read back (the engine's pose rounds the chain's angle), so the chain's own state
    /// carries on exactly, and its factorisation at that pose serves the next step.
    written: Vec<(Pose, Vector, f64)>,
}

impl Model {
    /// One step of the bang on the exact chain; returns the floor's impulses, each beside the
    /// body it acted on. A failed solve leaves the pieces where they were and is kept for
    /// [`Model::health`].
    pub(in crate::model) fn step_exact(
        &mut self,
        dt: f64,
    ) -> Vec<(RigidBodyHandle, work::FloorImpulse)> {
        self.sync_exact();
        let gravity = self.world.gravity;
        let bound = self
            .settings
            .bang_tolerance
            .map(|tolerance| self.error_bound(tolerance, self.energy().0));
        let Some(exact) = self.exact.as_mut() else {
            return Vec::new();
        };
        exact.pending.clear();
        exact.pending.extend_from_slice(exact.chain.bodies());
        let g = [gravity.x, gravity.y];
        let stepped = match bound {
            Some(bound) => exact.chain.step_bounded(dt, g, bound),
            None => exact.chain.step(dt, g),
        };
        match stepped {
            Ok(report) => {
                exact.budget.spent_j += report.joint_error_j();
                std::mem::swap(&mut exact.before.0, &mut exact.pending);
                exact.before.1 = dt;
                exact.stats.add(&report);
                exact.penetration_m = report.penetration_m;
                exact.overlap_m = report.overlap_m;
                exact.gravity_work_j = report.gravity_work_j;
                exact.caught_j = report.caught_j;
            }
            Err(e) => {
                exact.failed = Some(e);
                return Vec::new();
            }
        }
        for ((b, &h), &c) in exact
            .chain
            .bodies()
            .iter()
            .zip(&exact.bodies)
            .zip(&exact.centres)
        {
            write_body(&mut self.world.bodies[h], b, c);
        }
        exact.written.clear();
        exact.written.extend(
            exact
                .bodies
                .iter()
                .map(|&h| engine_state(&self.world.bodies[h])),
        );
        self.bang.solve = exact.stats;
        exact.layers_work_j = exact.chain.layers_work_j();
        exact
            .chain
            .contacts()
            .iter()
            .filter(|c| c.on == Surface::Floor)
            .map(|c| {
                let impulse =
                    work::FloorImpulse::of_chain(c.normal_n_s, c.friction_n_s, c.arm_m, c.work_j);
                (exact.bodies[c.body], impulse)
            })
            .collect()
    }

    /// The error the bang's next step may make, within `tolerance` (`solver.bang_tolerance`)
    /// with `kinetic_j` still moving. The error, the joints' work
    /// ([`exact_chain::StepReport::joint_error_j`], the ledger's numerical part), summed
    /// over the bang's steps, is held within the tolerance times the energy in play: what the bang
    /// has dissipated and what still moves. At rest nothing moves, and the sum's share of
    /// what the bang dissipated is within the tolerance; before the first impacts the
    /// budget is already the tolerance of what they will dissipate (the yoga mat's joints
    /// make their error in the steps before its first impacts, while it has dissipated
    /// under 1 % of what it will; the thin tape's, in its first impacts, within 0.1 ms of
    /// its release: docs/final-bang.md). A step past that budget still
    /// stands if its error is within the tolerance of the energy it moved itself
    /// ([`ErrorBound::holds`]), so a spent budget does not ask the impossible of the steps
    /// after it; the sum may then pass the budget, and the ledger says by how much.
    fn error_bound(&self, tolerance: f64, kinetic_j: f64) -> ErrorBound {
        let dissipated = self.accounts.ledger.bang_j;
        let spent = self.exact.as_ref().map_or(0.0, |e| e.budget.spent_j);
        let budget = tolerance * (dissipated + kinetic_j).max(0.0);
        let limit = budget.max(spent.abs());
        ErrorBound {
            least_j: (-limit - spent).min(0.0),
            most_j: (limit - spent).max(0.0),
            tolerance,
        }
    }

    /// How fast `piece`'s fastest node moves (m/s), for freezing. On the exact chain it is the
    /// motion the last step realised, its nodes' displacement over the step's length: the
    /// velocity it holds at a whole step is not that. A piece resting on the floor ends each
    /// of RATTLE's steps (see [`ExactChain`]) with the second half of gravity's kick still in
    /// its velocity, which the next step's floor impulses take back before it moves: where
    /// the kick turns it about a contact point rather than pressing it into the floor, the
    /// end-of-step impulses leave it there, and the piece, at rest, would read a few mm/s.
    pub(in crate::model) fn moved_speed(&self, piece: Piece) -> f64 {
        let body = &self.world.bodies[piece.body];
        let realised = self
            .exact
            .as_ref()
            .filter(|_| self.on_exact_chain())
            .and_then(|ex| {
                let i = ex.bodies.iter().position(|&h| h == piece.body)?;
                let (before, dt) = &ex.before;
                let (now, was) = (ex.chain.bodies().get(i)?, before.get(i)?);
                let moved = ex.nodes[i].iter().map(|&n| {
                    let (a, b) = (now.point(n), was.point(n));
                    (a[0] - b[0]).hypot(a[1] - b[1]) / dt
                });
                Some(moved.fold(0.0, f64::max))
            });
        if let Some(speed) = realised {
            return speed;
        }
        let pose = *body.position();
        self.piece_nodes(piece)
            .map(|n| body.velocity_at_point(pose.transform_point(n)).length())
            .fold(0.0, f64::max)
    }

    /// The pin of the first moving piece, if it has one: its anchor in the world and in the
    /// piece's frame.
    pub(super) fn first_pin(&self) -> Option<(Vector, Vector)> {
        let first = self.chain.free.front()?;
        self.world
            .impulse_joints
            .joints_between(self.ground, first.body)
            .map(|(_, j)| (j.data.local_anchor1(), j.data.local_anchor2()))
            .last()
    }

    /// Brings the exact chain up to the engine's bodies: rebuilt if the moving pieces or the
    /// pin changed, else each body's state refreshed.
    fn sync_exact(&mut self) {
        let handles: Vec<RigidBodyHandle> = self.chain.free.iter().map(|p| p.body).collect();
        let pin = self.first_pin();
        let (stats, failed, budget) = match &mut self.exact {
            Some(ex) if ex.bodies == handles && ex.pin == pin => {
                let written = std::mem::take(&mut ex.written);
                for (i, ((b, &h), &c)) in ex
                    .chain
                    .bodies_mut()
                    .iter_mut()
                    .zip(&handles)
                    .zip(&ex.centres)
                    .enumerate()
                {
                    let body = &self.world.bodies[h];
                    if written.get(i) != Some(&engine_state(body)) {
                        *b = exact_body(body, c);
                    }
                }
                return;
            }
            Some(ex) => (ex.stats, ex.failed, ex.budget),
            None => (SolveStats::default(), None, Budget::default()),
        };
        let mut built = self.build_exact(handles, pin);
        built.stats = stats;
        built.failed = failed;
        built.budget = budget;
        self.exact = Some(built);
    }

    /// The exact chain of the moving pieces `handles` (those of `chain.free`), pinned by
    /// `pin`, on the floor.
    fn build_exact(
        &self,
        handles: Vec<RigidBodyHandle>,
        pin: Option<(Vector, Vector)>,
    ) -> ExactBang {
        let free = &self.chain.free;
        let (centres, bodies) = self.chain_bodies(&handles);
        let at = |v: Vector| [v.x, v.y];
        let joints: Vec<Joint> = (1..free.len())
            .map(|i| Joint {
                prev: at(self.chain.local[free[i - 1].last][1] - centres[i - 1]),
                next: at(self.chain.local[free[i].first][0] - centres[i]),
            })
            .collect();
        let mut chain = ExactChain::new(
            bodies,
            joints,
            pin.map(|(world, local)| Pin {
                anchor: at(local - centres[0]),
                at_m: at(world),
            }),
            self.chain_tolerance(),
        );
        let nodes: Vec<Vec<[f64; 2]>> = free
            .iter()
            .zip(&centres)
            .map(|(&p, &c)| self.piece_nodes(p).map(|n| at(n - c)).collect())
            .collect();
        // The floor's contact plane is the laid tape's midline: with the tape's thickness the
        // chain meets the floor itself at the pieces' faces, half a thickness lower.
        let mut floor = self.chain_floor();
        floor.point_m[1] -= self.settings.half_b;
        chain.set_floor(floor, &contact_points(&nodes, pin.is_some()));
        if self.bang.layers {
            chain.set_layers(self.layers(&nodes));
        }
        ExactBang {
            nodes,
            before: (Vec::new(), 0.0),
            pending: Vec::new(),
            written: Vec::new(),
            chain,
            bodies: handles,
            pin,
            centres,
            stats: SolveStats::default(),
            penetration_m: 0.0,
            overlap_m: 0.0,
            failed: None,
            budget: Budget::default(),
            gravity_work_j: 0.0,
            caught_j: 0.0,
            layers_work_j: [0.0; 2],
        }
    }
}

impl Model {
    /// The tape's thickness as the exact chain takes it: each moving piece's midline (its
    /// `nodes`, from its centre of mass) and the frozen tape's, each node with its arc along
    /// the tape.
    fn layers(&self, nodes: &[Vec<[f64; 2]>]) -> Layers {
        let arc = &self.chain.arc_m;
        let outlines = self
            .chain
            .free
            .iter()
            .zip(nodes)
            .map(|(p, n)| Outline {
                nodes: n.clone(),
                arc_m: arc[p.first..=p.last + 1].to_vec(),
            })
            .collect();
        let frozen = &self.chain.frozen_nodes;
        Layers {
            radius_m: self.settings.half_b,
            friction: self.settings.self_friction,
            exclusion_m: LAYER_EXCLUSION_PER_THICKNESS * 2.0 * self.settings.half_b,
            outlines,
            laid: Outline {
                nodes: frozen.clone(),
                arc_m: arc[..frozen.len()].to_vec(),
            },
        }
    }

    /// The moving pieces `handles` as the bang's exact chain takes them: each
    /// body's centre of mass in its own frame, and its state about it.
    pub(super) fn chain_bodies(&self, handles: &[RigidBodyHandle]) -> (Vec<Vector>, Vec<Body>) {
        let centres: Vec<Vector> = handles
            .iter()
            .map(|&h| {
                self.world.bodies[h]
                    .mass_properties()
                    .local_mprops
                    .local_com
            })
            .collect();
        let bodies = handles
            .iter()
            .zip(&centres)
            .map(|(&h, &c)| exact_body(&self.world.bodies[h], c))
            .collect();
        (centres, bodies)
    }

    /// The bang's exact chain's tolerance: the chain's for its shortest moving piece, a
    /// body turning at most twice the step rule's turn in a step (room for an impact's
    /// spin-up).
    pub(super) fn chain_tolerance(&self) -> Tolerance {
        let shortest = self
            .chain
            .free
            .iter()
            .map(|p| {
                self.chain.links[p.first..=p.last]
                    .iter()
                    .map(|l| l.length_m)
                    .sum::<f64>()
            })
            .fold(f64::INFINITY, f64::min);
        Tolerance {
            max_turn_rad: 2.0 * self.settings.bang_step_rad,
            ..exact_chain::tolerance_for(shortest)
        }
    }

    /// The floor as the bang's exact chain sees it.
    pub(super) fn chain_floor(&self) -> Floor {
        Floor {
            point_m: [0.0, self.world.colliders[self.floor].translation().y],
            normal: [0.0, 1.0],
            friction: self.settings.friction,
        }
    }
}

/// Each piece's contact points, from its `nodes`: the corners of their hull
/// (`exact_chain::hull_corners`). A node two pieces share (or the pin's, if `pinned`)
/// belongs to the piece before it, which keeps it if it is a corner of either.
pub(super) fn contact_points(nodes: &[Vec<[f64; 2]>], pinned: bool) -> Vec<Vec<[f64; 2]>> {
    let corners: Vec<Vec<bool>> = nodes.iter().map(|n| exact_chain::hull_corners(n)).collect();
    nodes
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let skip = i > 0 || pinned;
            let next_first = corners.get(i + 1).is_some_and(|c| c[0]);
            (0..n.len())
                .filter(|&j| !(skip && j == 0))
                .filter(|&j| corners[i][j] || (j + 1 == n.len() && next_first))
                .map(|j| n[j])
                .collect()
        })
        .collect()
}

/// Writes a chain's state `b` of a piece back to its engine body, whose centre of mass
/// sits at `centre` in the body's own frame.
pub(super) fn write_body(body: &mut RigidBody, b: &Body, centre: Vector) {
    let arm = rotate([centre.x, centre.y], b.angle_rad);
    let origin = Vector::new(b.position_m[0] - arm[0], b.position_m[1] - arm[1]);
    body.set_position(Pose::new(origin, b.angle_rad), false);
    body.set_linvel(Vector::new(b.velocity_m_s[0], b.velocity_m_s[1]), false);
    body.set_angvel(b.spin_rad_s, false);
}

/// An engine body's pose and velocity.
fn engine_state(body: &RigidBody) -> (Pose, Vector, f64) {
    (*body.position(), body.linvel(), body.angvel())
}

/// An engine body as the exact chain holds it, about its centre of mass `centre` (its own
/// frame).
pub(super) fn exact_body(body: &RigidBody, centre: Vector) -> Body {
    let pose = body.position();
    let com = pose.transform_point(centre);
    let v = body.linvel();
    Body {
        mass_kg: body.mass(),
        inertia_kg_m2: body.mass_properties().effective_angular_inertia(),
        position_m: [com.x, com.y],
        angle_rad: body.rotation().angle(),
        velocity_m_s: [v.x, v.y],
        spin_rad_s: body.angvel(),
    }
}

impl ExactBang {
    /// The pieces a contact pressed or rubbed in the last step, the floor, the laid tape or
    /// another piece.
    pub(in crate::model) fn touched(&self) -> std::collections::HashSet<RigidBodyHandle> {
        let mut touched = std::collections::HashSet::new();
        for c in self.chain.contacts() {
            touched.insert(self.bodies[c.body]);
            if let Surface::Body(o) = c.on {
                touched.insert(self.bodies[o]);
            }
        }
        touched
    }
}
