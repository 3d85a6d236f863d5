//! The final bang: the release of the remaining coil as rigid pieces at least
//! `bang_piece_m` long, each step's energy booked by mechanism, and its end at rest or at
//! its cap.

use super::*;

pub(super) mod exact;

impl Model {
    /// Joins the moving links, in order along the tape, into rigid pieces at least
    /// `bang_piece_m` long (a short remainder joins the last piece). Each piece moves with
    /// its parts' momentum and angular momentum; the kinetic energy of their relative
    /// motion is lost, and returned (J), with the ratio the thickness scaled every speed by.
    ///
    /// A piece turns with its thickness: each link, a rectangle of length `l` and thickness
    /// `b`, has `m b^2 / 12` of its own inertia more than its midline's `m l^2 / 12`. The
    /// rolling coil, like the exact-geometry model, turns as its thin midline. A real tape
    /// brings to the bang the energy the unroll gave it (gravity's, less what the unroll
    /// dissipated), only turning with more inertia for it: so the handover keeps the energy
    /// and the shape of the motion, and scales every piece's velocity and spin by one ratio,
    /// `sqrt(K_line / K)`, where `K` is the kinetic energy of the same motion with the
    /// thickness. A common ratio keeps the joints' relative velocities zero; keeping each
    /// piece's angular momentum instead would not, and would take, on the yoga mat, 2.9 % of
    /// what the bang received at the handover and 2.5 % more as the joints caught up.
    pub(super) fn join_pieces(&mut self) -> (f64, f64) {
        let before = self.energy().0;
        let b = 2.0 * self.settings.half_b;
        let parts: Vec<Piece> = self.chain.free.drain(..).collect();
        let mut groups: Vec<std::ops::Range<usize>> = Vec::new();
        let (mut start, mut length) = (0, 0.0);
        for (i, p) in parts.iter().enumerate() {
            length += self.chain.links[p.first..=p.last]
                .iter()
                .map(|l| l.length_m)
                .sum::<f64>();
            if length >= self.settings.bang_piece_m {
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
        // Each group's mass, centre of mass, momentum, and its midline's inertia and angular
        // momentum about the centre of mass (world frame).
        let joined: Vec<(f64, Vector, Vector, f64, f64)> = groups
            .iter()
            .map(|g| {
                let group = &parts[g.clone()];
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
                (mass, com, momentum, inertia, spin)
            })
            .collect();
        let (mut line_j, mut thick_j) = (0.0, 0.0);
        for &(mass, _, momentum, inertia, spin) in &joined {
            let (moving, omega) = (0.5 * momentum.length_squared() / mass, spin / inertia);
            line_j += moving + 0.5 * inertia * omega * omega;
            thick_j += moving + 0.5 * (inertia + mass * b * b / 12.0) * omega * omega;
        }
        let ratio = if thick_j > 0.0 {
            (line_j / thick_j).sqrt()
        } else {
            1.0
        };
        for (group, (mass, com, momentum, inertia, spin)) in groups.into_iter().zip(joined) {
            let group = &parts[group];
            // The new body's frame is the world's: its nodes are where they are now.
            for part in group {
                let pose = *self.world.bodies[part.body].position();
                for k in part.first..=part.last {
                    self.chain.local[k] = self.chain.local[k].map(|n| pose.transform_point(n));
                }
                self.world.remove_body(part.body);
            }
            let first = group[0].first;
            let body = self.world.insert_body(
                RigidBodyBuilder::dynamic()
                    .additional_mass_properties(MassProperties::new(
                        com,
                        mass,
                        inertia + mass * b * b / 12.0,
                    ))
                    .linvel(momentum / mass * ratio)
                    .angvel(spin / inertia * ratio)
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
            self.chain.free.push_back(piece);
        }
        (before - self.energy().0, ratio)
    }

    /// Releases the remaining wound links as a free chain: the final bang begins.
    pub(super) fn release_coil(&mut self) {
        let Some(coil) = self.coil.body else { return };
        let (kinetic_in, potential_in) = self.energy();
        let before = kinetic_in + potential_in;
        self.phase = Phase::Bang;
        // From here on every joint, old and new, has the bang's softness.
        self.settings.joint_softness = self.settings.bang_joint_softness;
        for (_, j) in self.world.impulse_joints.iter_mut() {
            j.data.softness = self.settings.bang_joint_softness;
        }
        if let Some(prev) = self.chain.free.back().copied() {
            self.unpin_from_coil(prev.body, coil);
        }
        // The piece pinned to the world may swing in the bang: let it touch the floor.
        if let Some(first) = self.chain.free.front().copied() {
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
        let longest = self.chain.links[self.coil.first_attached..]
            .iter()
            .map(|l| l.length_m)
            .fold(0.0, f64::max);
        self.bang.chord_sag_m = longest * self.settings.link_angle / 8.0;
        self.bang.layers =
            self.bang.chord_sag_m < LAYERS_RESOLVED_PER_THICKNESS * 2.0 * self.settings.half_b;
        for k in self.coil.first_attached..self.chain.len() {
            let piece = self.spawn_piece(k, k, coil);
            self.join_near_node(piece);
            self.chain.free.push_back(piece);
        }
        self.world.remove_body(coil);
        self.coil.body = None;
        self.coil.ball = None;
        self.coil.first_attached = self.chain.len();
        // The laid tape that slid as one body on a frictionless floor (`join_laid`) bends in
        // the bang: its links move on their own again.
        self.part_laid();
        // The engine leaves the joints a few microns apart under tension; closing those gaps
        // later, under the bang's far larger tension, would do work on the tape. Close them
        // now, by position alone, then join the links into the bang's pieces. Joining pins
        // the first piece above the floor's contact plane (`pin_to_world`), while its node
        // lies where the coil laid it, up to its inset below that plane: close that gap too.
        self.close_gaps();
        let (joined_j, ratio) = self.join_pieces();
        self.bang.thickness_speed_ratio = ratio;
        self.close_gaps();
        self.bang.ledger.freeze_j += joined_j;
        let params = &mut self.world.integration_parameters;
        params.num_solver_iterations = self.settings.bang_iterations;
        params.num_internal_stabilization_iterations = self.settings.bang_relax_iterations;
        let (kinetic, potential) = self.energy();
        self.bang.started_s = self.t;
        self.bang.kinetic_in_j = kinetic_in;
        // Spawning copies the velocity field, so this is the joining's loss, but for closing
        // the gaps, which moves the links by microns.
        let release_j = before - kinetic - potential;
        self.accounts.ledger.bang_j += release_j;
        self.bang.ledger.residual_j += release_j - joined_j;
    }

    /// Books one step of the final bang: the work of the floor (its `contacts`) and the joints
    /// on the moving pieces (from their states `before` it, in the order of `free`) into the
    /// bang's ledger, with `lost_j` what the step dissipated and `kinetic` the kinetic energy
    /// after it; the fastest point, the floor's impulse; and ends the bang once it has come to
    /// rest.
    pub(super) fn book_bang_step(
        &mut self,
        before: &[BodyState],
        contacts: &[(RigidBodyHandle, work::FloorImpulse)],
        lost_j: f64,
        kinetic: f64,
        dt: f64,
    ) {
        self.accounts.ledger.bang_j += lost_j;
        if self.chain.free.is_empty() {
            // Everything is frozen: at rest.
            self.bang.ledger.residual_j += lost_j;
            self.end_bang(BangEnd::Rest);
            return;
        }
        let bodies = work::moved(
            &self.world.bodies,
            self.chain.free.iter().map(|p| p.body),
            before,
        );
        let floor: Vec<_> = contacts
            .iter()
            .filter_map(|&(body, c)| {
                let k = self.world.bodies.get(body)?.user_data as usize;
                let i = self.chain.free.binary_search_by_key(&k, |p| p.first).ok()?;
                Some((i, c))
            })
            .collect();
        // What the exact chain took when it made the joints rigid (at the release, and at a
        // freeze's new pin) is the model's discard, as joining the pieces is: not the joints'.
        let exact = self.exact.as_ref().filter(|_| self.on_exact_chain());
        let gravity_work = exact.map(|e| e.gravity_work_j);
        let caught = exact.map_or(0.0, |e| e.caught_j);
        let layers = exact.map_or([0.0; 2], |e| e.layers_work_j);
        let work = work::step_work(
            &bodies,
            &floor,
            self.world.gravity,
            dt,
            (gravity_work, layers[0] + layers[1]),
        );
        let impulse: f64 = floor.iter().map(|(_, c)| c.normal.length()).sum();
        // Potential energy above lying flat on the floor: the weight across the floor times
        // the centre of mass's height above where it would lie (never negative: on a fixed
        // axis the tape hangs far above a floor it cannot reach). On the exact chain, where
        // the tape has its thickness, a piece that rests on another layer cannot lie flat:
        // only the pieces that touched nothing in the step count.
        let touched = exact.map(|e| e.touched()).unwrap_or_default();
        let raised_j: f64 = self
            .chain
            .free
            .iter()
            .filter(|p| !touched.contains(&p.body))
            .map(|p| {
                let body = &self.world.bodies[p.body];
                body.mass() * self.settings.g * (body.center_of_mass().y - p.rest_y_m).max(0.0)
            })
            .sum();
        let top_speed = self
            .chain
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
        b.ledger.layers_normal_j -= layers[0];
        b.ledger.layers_friction_j -= layers[1];
        b.ledger.joints_j -= work.joints_j + caught;
        b.ledger.freeze_j += caught;
        b.ledger.residual_j +=
            lost_j + work.normal_j + work.friction_j + layers[0] + layers[1] + work.joints_j;
        b.top_speed_m_s = b.top_speed_m_s.max(top_speed);
        b.floor_impulse_n_s += impulse;
        if dt > 0.0 {
            b.peak_floor_force_n = b.peak_floor_force_n.max(impulse / dt);
        }
        if kinetic + raised_j < self.settings.rest_fraction * b.kinetic_in_j {
            self.end_bang(BangEnd::Rest);
        }
    }

    /// Ends the final bang: nothing more is simulated.
    pub(super) fn end_bang(&mut self, why: BangEnd) {
        self.bang.end = Some(why);
        self.phase = Phase::Done;
    }

    /// Closes the gap a new pin in the bang leaves: `pin_to_world` pins a piece above the
    /// floor's contact plane, while a piece lying on the floor has its node on it or below
    /// it. A rigid joint would close that gap within one substep, at the gap over the
    /// substep's length, a kick that grows as the square of the substeps
    /// (docs/final-bang.md gives the measurement). The chain is moved instead, by position
    /// alone; the change of its potential energy is booked as the bang's residual.
    pub(super) fn close_pin_gap(&mut self) {
        let before = self.total_energy();
        self.close_gaps();
        let moved_j = before - self.total_energy();
        self.accounts.ledger.bang_j += moved_j;
        self.bang.ledger.residual_j += moved_j;
    }

    /// Closes the joints' gaps along the chain by translating each piece, from the laid end
    /// on, so that its near node meets what holds it; velocities are untouched.
    pub(super) fn close_gaps(&mut self) {
        // The first piece meets the world pin's anchor, if it has one.
        let mut target: Option<Vector> = self.chain.free.front().and_then(|first| {
            self.world
                .impulse_joints
                .joints_between(self.ground, first.body)
                .map(|(_, j)| j.data.local_anchor1())
                .last()
        });
        for i in 0..self.chain.free.len() {
            let piece = self.chain.free[i];
            let [near, far] = [
                self.chain.local[piece.first][0],
                self.chain.local[piece.last][1],
            ];
            let body = &mut self.world.bodies[piece.body];
            let pose = *body.position();
            if let Some(t) = target {
                let d = t - pose.transform_point(near);
                body.set_translation(pose.translation + d, false);
            }
            target = Some(body.position().transform_point(far));
        }
    }
}
