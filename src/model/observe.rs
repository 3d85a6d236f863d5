//! What the model shows of itself after a step: the [`Observation`](super::Observation), the
//! link nodes for a frame, where the tape ends, and its health for the guards. It moves
//! nothing.

use super::*;

impl Model {
    pub(super) fn max_joint_gap(&self) -> f64 {
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

    pub(super) fn max_penetration(&self) -> f64 {
        if let (true, Some(exact)) = (self.on_exact_chain(), &self.exact) {
            return exact.penetration_m;
        }
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
        // The step's own sums where nothing was shed, released or frozen since: the same
        // bodies in the same state, so the same bits.
        let (kinetic_j, potential_j) = match self.accounts.step_energy.take() {
            Some((key, kinetic, potential)) if key == self.energy_key() => (kinetic, potential),
            _ => self.energy(),
        };
        self.accounts.energy_j = kinetic_j + potential_j;
        // The floor's force on everything that moves over the last step.
        let (normal_n, friction_n) = if self.last_dt > 0.0 {
            let f = self.accounts.impulses.floor_on_moving;
            (f[1] / self.last_dt, f[0] / self.last_dt)
        } else {
            (0.0, 0.0)
        };
        let (x_m, omega) = match self.coil.body {
            Some(coil) => {
                let body = &self.world.bodies[coil];
                let p = self.coil.spiral.point(self.coil.psi_low);
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
            psi_low: self.coil.psi_low,
            x_m,
            omega_rad_s: omega,
            kinetic_j,
            potential_j,
            normal_n,
            friction_n,
            ledger: self.accounts.ledger,
            bang: self.bang,
            detached: self.coil.first_attached,
            active_bodies: self.world.bodies.len() - 1,
            max_joint_gap_m: self.max_joint_gap(),
            max_penetration_m: self.max_penetration(),
            max_overlap_m: self
                .exact
                .as_ref()
                .filter(|_| self.on_exact_chain())
                .map_or(0.0, |e| e.overlap_m),
            dt_s: self.last_dt,
            angular_momentum_o: self.accounts.moved_angular_momentum,
            impulses: self.accounts.impulses,
        }
    }

    /// The nodes of the links that left the coil, in the world frame (m), for drawing: from
    /// the tape's outer end through the frozen and the moving links. Consecutive nodes bound
    /// one link; empty while no link has left.
    pub fn off_coil_nodes(&self) -> Vec<[f64; 2]> {
        let mut off = self.chain.frozen_nodes.clone();
        for (i, &piece) in self.chain.free.iter().enumerate() {
            if i == 0 {
                // The first moving piece's near node replaces the last frozen far node.
                off.pop();
            }
            let pose = self.world.bodies[piece.body].position();
            let nodes = self.piece_nodes(piece).map(|n| pose.transform_point(n));
            // Each piece's far node is the next one's near node.
            let skip_far = usize::from(i + 1 < self.chain.free.len());
            let count = piece.last - piece.first + 2 - skip_far;
            off.extend(nodes.take(count).map(|p| [p.x, p.y]));
        }
        off
    }

    /// The nodes of the links still wound, in the coil's body frame (the spiral's) from the
    /// innermost node outward, placed where the coil is; `None` once the coil is released.
    /// The coil is one rigid body, so the nodes stay the same while it rolls, and a drawing
    /// of them changes only where the tape leaves it.
    pub fn wound_nodes(&self) -> Option<Placed> {
        let coil = self.coil.body?;
        let body = &self.world.bodies[coil];
        let attached = &self.chain.links[self.coil.first_attached..];
        let points_m = attached
            .iter()
            .rev()
            .map(|l| l.far)
            .chain(attached.first().map(|l| l.near))
            .collect();
        let origin = body.translation();
        Some(Placed {
            origin_m: [origin.x, origin.y],
            rotation_rad: body.rotation().angle(),
            points_m,
        })
    }

    /// Where the tape's free (inner) end is: x of its innermost node (m).
    pub fn tape_end_x_m(&self) -> f64 {
        if let Some(&piece) = self.chain.free.back() {
            let pose = self.world.bodies[piece.body].position();
            return pose.transform_point(self.chain.local[piece.last][1]).x;
        }
        if self.coil.body.is_none()
            && let Some(n) = self.chain.frozen_nodes.last()
        {
            return n[0];
        }
        self.wound_nodes()
            .and_then(|w| w.points_m.first().map(|&p| w.to_world(p)[0]))
            .unwrap_or(0.0)
    }

    /// The tape's midline length as the links lay it: the sum of their lengths (m).
    pub fn tape_length_m(&self) -> f64 {
        self.chain.length_m()
    }

    /// Potential energy of the tape lying flat, midline at `b/2`, from `x = 0` on (J).
    pub fn flat_potential_j(&self) -> f64 {
        self.settings.total_mass * self.settings.g * self.settings.half_b
            - self.settings.g_along * self.settings.flat_first_moment
    }

    /// What the run's guards read after a step: slip at the rolling contact, how far the
    /// bodies have gone, their fastest spin, and whether every body state is finite.
    pub fn health(&self) -> Health {
        let slip_m_s = self.coil.body.map(|coil| {
            let body = &self.world.bodies[coil];
            let p = self.coil.spiral.point(self.coil.psi_low);
            let contact = body.position().transform_point(Vector::new(p[0], p[1]));
            body.velocity_at_point(contact).x
        });
        let mut health = Health {
            slip_m_s,
            farthest_m: 0.0,
            lowest_m: 0.0,
            max_spin_rad_s: 0.0,
            finite: true,
            unsolved: self.exact.as_ref().and_then(|e| e.failed),
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
