//! The final bang on the nodal chain (`solver.bang_engine = "midpoint"`): from the first
//! step after the release the chain owns the moving pieces' state (their nodes and the
//! nodes' velocities); the engine's bodies are written from it after every step and stay
//! the pieces' record, which observations, frames and the end of the bang read. A freeze
//! takes the chain's first piece off it and pins its next node where it is; nothing is
//! rebuilt, so no velocity is handed back and forth.

use super::*;
use crate::model::exact_chain::{SolveStats, StepError};
use crate::model::nodal::{self, NodalChain, StepReport};

/// The nodal chain of the bang's moving pieces, and how its steps went.
pub(in crate::model) struct NodalBang {
    chain: NodalChain,
    /// The pieces' bodies along the chain.
    bodies: Vec<RigidBodyHandle>,
    /// Each body's centre of mass in its own frame (m).
    centres: Vec<Vector>,
    /// Each piece's nodes in its chord's frame: where freezing reads its motion.
    nodes: Vec<Vec<[f64; 2]>>,
    /// The chain's nodes before the last step, and its length (s).
    before: (Vec<[f64; 2]>, f64),
    /// How the steps were solved.
    pub(in crate::model) stats: SolveStats,
    /// The last step's report.
    pub(in crate::model) last: StepReport,
    /// The failure that stopped it, if any.
    pub(in crate::model) failed: Option<StepError>,
    /// What making the chain took in the last step (J): the joints made rigid and shared
    /// at the release; booked as the model's discard, as joining the pieces is.
    pub(in crate::model) caught_j: f64,
}

impl Model {
    /// Whether the nodal chain steps the model now: in the bang, if the scene says so.
    pub(in crate::model) fn on_nodal_chain(&self) -> bool {
        self.phase == Phase::Bang && self.settings.bang_engine == BangEngine::Midpoint
    }

    /// One step of the bang on the nodal chain; returns the floor's impulses, each beside the
    /// body it acted on. A failed solve leaves the pieces where they were and is kept for
    /// [`Model::health`].
    pub(in crate::model) fn step_nodal(
        &mut self,
        dt: f64,
    ) -> Vec<(RigidBodyHandle, work::FloorImpulse)> {
        let gravity = [self.world.gravity.x, self.world.gravity.y];
        if let Err(e) = self.sync_nodal() {
            if let Some(nb) = self.nodal.as_mut() {
                nb.failed = Some(e);
            }
            return Vec::new();
        }
        let Some(nb) = self.nodal.as_mut() else {
            return Vec::new();
        };
        nb.before.0.clear();
        nb.before.0.extend_from_slice(nb.chain.nodes());
        nb.before.1 = dt;
        match nb.chain.step(dt, gravity) {
            Ok(report) => {
                report.add_to(&mut nb.stats);
                nb.last = report;
            }
            Err(e) => {
                nb.failed = Some(e);
                nb.last = StepReport::default();
                return Vec::new();
            }
        }
        for (i, (&h, &c)) in nb.bodies.iter().zip(&nb.centres).enumerate() {
            exact::write_body(&mut self.world.bodies[h], &nb.chain.body(i), c);
        }
        self.bang.solve = nb.stats;
        nb.chain
            .contacts()
            .iter()
            .map(|c| {
                let impulse =
                    work::FloorImpulse::of_chain(c.normal_n_s, c.friction_n_s, c.arm_m, c.work_j);
                (nb.bodies[c.piece], impulse)
            })
            .collect()
    }

    /// The work of the last step on the nodal chain, as the bang books it: the floor's, as
    /// the chain measured it; the joints', the rigidity's exact work less what making the
    /// chain took (booked apart, as the model's discard). Returns it and that discard (J).
    pub(in crate::model) fn nodal_step_work(&mut self) -> Option<(work::StepWork, f64)> {
        let on = self.on_nodal_chain();
        let nb = self.nodal.as_mut().filter(|_| on)?;
        let caught = std::mem::take(&mut nb.caught_j);
        let r = &nb.last;
        Some((
            work::StepWork {
                normal_j: r.floor_work_j[0],
                friction_j: r.floor_work_j[1],
                joints_j: r.joint_work_j - caught,
            },
            caught,
        ))
    }

    /// The kinetic and potential energy of the moving pieces as the nodal chain holds them
    /// (J), once it does (and after the bang: the engine's bodies are only its record).
    pub(in crate::model) fn nodal_energy(&self) -> Option<(f64, f64)> {
        let held =
            self.phase != Phase::Rolling && self.settings.bang_engine == BangEngine::Midpoint;
        let nb = self.nodal.as_ref().filter(|_| held)?;
        let gravity = [self.world.gravity.x, self.world.gravity.y];
        Some((nb.chain.kinetic_j(), nb.chain.potential_j(gravity)))
    }

    /// The deepest a contact point of the nodal chain ended below the floor in the last step.
    pub(in crate::model) fn nodal_penetration(&self) -> Option<f64> {
        let nb = self.nodal.as_ref().filter(|_| self.on_nodal_chain())?;
        Some(nb.last.penetration_m)
    }

    /// The failure that stopped the nodal chain, if any.
    pub(in crate::model) fn nodal_failure(&self) -> Option<StepError> {
        self.nodal.as_ref().and_then(|nb| nb.failed)
    }

    /// How fast `piece`'s fastest node moved over the nodal chain's last step (m/s), if the
    /// chain holds it.
    pub(in crate::model) fn nodal_moved_speed(&self, piece: Piece) -> Option<f64> {
        let nb = self.nodal.as_ref().filter(|_| self.on_nodal_chain())?;
        let i = nb.bodies.iter().position(|&h| h == piece.body)?;
        let (before, dt) = &nb.before;
        if before.len() != nb.chain.nodes().len() {
            return None;
        }
        let moved = nb.nodes[i].iter().map(|&n| {
            let now = nb.chain.point(i, n);
            let was = material(before, i, n);
            (now[0] - was[0]).hypot(now[1] - was[1]) / dt
        });
        Some(moved.fold(0.0, f64::max))
    }

    /// Takes the nodal chain's first piece off it (a freeze), its next node pinned where it
    /// is; returns the kinetic energy that took (J): the piece's share, and the pin's catch
    /// of the node. `None` if the chain does not hold that piece first.
    pub(in crate::model) fn nodal_freeze_first(&mut self, body: RigidBodyHandle) -> Option<f64> {
        let on = self.on_nodal_chain();
        let nb = self.nodal.as_mut().filter(|_| on)?;
        if nb.bodies.first() != Some(&body) {
            return None;
        }
        let lost = match nb.chain.remove_first() {
            Ok(lost) => lost,
            Err(e) => {
                nb.failed = Some(e);
                return None;
            }
        };
        nb.bodies.remove(0);
        nb.centres.remove(0);
        nb.nodes.remove(0);
        nb.before.0.clear();
        Some(lost)
    }

    /// Makes the nodal chain from the engine's moving pieces at the release, or again if the
    /// pieces it holds are no longer the moving ones.
    fn sync_nodal(&mut self) -> Result<(), StepError> {
        let handles: Vec<RigidBodyHandle> = self.chain.free.iter().map(|p| p.body).collect();
        let (stats, failed) = match &self.nodal {
            Some(nb) if nb.bodies == handles => return Ok(()),
            Some(nb) => (nb.stats, nb.failed),
            None => (SolveStats::default(), None),
        };
        let mut built = self.build_nodal(handles)?;
        built.stats = stats;
        built.failed = failed;
        self.nodal = Some(built);
        Ok(())
    }

    /// The nodal chain of the moving pieces `handles` (those of `chain.free`), pinned at its
    /// first node if the engine pins the first piece, on the floor; what making it took is
    /// its `caught_j`.
    fn build_nodal(&self, handles: Vec<RigidBodyHandle>) -> Result<NodalBang, StepError> {
        let free = &self.chain.free;
        let (centres, bodies) = self.chain_bodies(&handles);
        let at = |v: Vector| [v.x, v.y];
        let ends: Vec<[[f64; 2]; 2]> = free
            .iter()
            .zip(&centres)
            .map(|(p, &c)| {
                [
                    at(self.chain.local[p.first][0] - c),
                    at(self.chain.local[p.last][1] - c),
                ]
            })
            .collect();
        let tolerance = self.chain_tolerance();
        let pinned = self.first_pin().is_some();
        let potential_before: f64 = handles
            .iter()
            .map(|&h| self.potential_of(&self.world.bodies[h]))
            .sum();
        let (mut chain, lost) = NodalChain::of_bodies(&bodies, &ends, pinned, tolerance)?;
        let gravity = [self.world.gravity.x, self.world.gravity.y];
        // Laying the nodes from the first along the bodies' angles closes the engine's
        // joints' gaps (microns): that moves the potential by as little.
        let moved = potential_before - chain.potential_j(gravity);
        // Each piece touches the floor at the corners of its nodes' hull, as on the exact
        // chain (`exact::contact_points`).
        let nodes: Vec<Vec<[f64; 2]>> = free
            .iter()
            .zip(&centres)
            .zip(&ends)
            .map(|((&p, &c), e)| {
                self.piece_nodes(p)
                    .map(|n| nodal::chord_coordinates(e[0], e[1], at(n - c)))
                    .collect()
            })
            .collect();
        chain.set_floor(self.chain_floor(), &exact::contact_points(&nodes, pinned));
        Ok(NodalBang {
            chain,
            bodies: handles,
            centres,
            nodes,
            before: (Vec::new(), 0.0),
            stats: SolveStats::default(),
            last: StepReport::default(),
            failed: None,
            caught_j: lost + moved,
        })
    }
}

/// The point `(alpha, beta)` of piece `i` of the nodes `x` (m).
fn material(x: &[[f64; 2]], i: usize, [alpha, beta]: [f64; 2]) -> [f64; 2] {
    let d = [x[i + 1][0] - x[i][0], x[i + 1][1] - x[i][1]];
    [
        x[i][0] + alpha * d[0] - beta * d[1],
        x[i][1] + alpha * d[1] + beta * d[0],
    ]
}
