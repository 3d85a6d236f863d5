//! The rolling phase: the coil's contact ball refitted to the spiral's lowest point, links
//! shed at the floor into pieces joined by revolute joints, laid and pinned, and settled
//! pieces frozen out of the engine.

use super::*;

/// How close to the laid tape's level, in thicknesses, a laid piece's nodes must lie for it
/// to be joined to the laid tape on a frictionless floor ([`Model::join_laid`]). Joining
/// only the pieces that move with the laid tape within the freeze speed left light links
/// between the laid tape and the coil: at b/R = 1/300 and on the frictionless spool at 4
/// solver iterations they folded up until the joint guard stopped the run. On the thin
/// tapes 0.05 and 0.2 lost the same energy before the bang to the printed digit.
const FLAT_B: f64 = 0.05;

impl Model {
    pub(super) fn refit_ball(&mut self) {
        self.coil.chord_ratio =
            self.chain.links[self.coil.first_attached.min(self.chain.len() - 1)].chord_ratio;
        let (Some(handle), true) = (self.coil.ball, self.phase == Phase::Rolling) else {
            return;
        };
        let c = self.coil.spiral.curvature_centre(self.coil.psi_low);
        let collider = &mut self.world.colliders[handle];
        collider.set_shape(SharedShape::ball(
            self.coil.spiral.curvature_radius(self.coil.psi_low) * self.coil.chord_ratio,
        ));
        collider.set_position_wrt_parent(Pose::from_translation(Vector::new(c[0], c[1])));
        self.restick();
    }

    /// Moves a sticky floor's hold to the coil's current contact: x is locked at the material
    /// point under the ball's centre (no slip: a rolling contact point has zero velocity and
    /// zero horizontal acceleration), y at the ball's centre (its height is fixed, while the
    /// contact point itself accelerates upward, so pinning it in y would brake the roll).
    pub(super) fn restick(&mut self) {
        let (Some([hold_x, hold_y]), Some(coil)) = (self.coil.stick, self.coil.body) else {
            return;
        };
        let c = self.coil.spiral.curvature_centre(self.coil.psi_low);
        let rho = self.coil.spiral.curvature_radius(self.coil.psi_low) * self.coil.chord_ratio;
        let pose = *self.world.bodies[coil].position();
        let centre = pose.transform_point(Vector::new(c[0], c[1]));
        let contact = Vector::new(centre.x, self.settings.half_b);
        let under = pose.inverse_transform_point(Vector::new(centre.x, centre.y - rho));
        if let Some(joint) = self.world.impulse_joints.get_mut(hold_x, false) {
            joint.data.set_local_anchor1(contact);
            joint.data.set_local_anchor2(under);
        }
        if let Some(joint) = self.world.impulse_joints.get_mut(hold_y, false) {
            joint
                .data
                .set_local_anchor1(Vector::new(centre.x, self.settings.half_b + rho));
            joint.data.set_local_anchor2(Vector::new(c[0], c[1]));
        }
    }

    /// Creates the body of the links `first..=last` with the coil's velocity field, in the
    /// coil's frame.
    pub(super) fn spawn_piece(
        &mut self,
        first: usize,
        last: usize,
        coil: RigidBodyHandle,
    ) -> Piece {
        let mut sums = CoilSums::default();
        for link in &self.chain.links[first..=last] {
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
    pub(super) fn inset_m(&self, k: usize) -> f64 {
        match self.phase {
            Phase::Rolling => self.chain.links[k].inset_m,
            _ => 0.0,
        }
    }

    /// Height of the centre of mass of the links `first..=last` lying flat on the floor:
    /// each link's node line sits its collider's inset above the contact plane `y = b/2` (m).
    pub(super) fn rest_height_m(&self, first: usize, last: usize) -> f64 {
        let mass: f64 = self.chain.links[first..=last]
            .iter()
            .map(|l| l.mass_kg)
            .sum();
        (first..=last)
            .map(|k| self.chain.links[k].mass_kg * (self.settings.half_b + self.inset_m(k)))
            .sum::<f64>()
            / mass
    }

    /// The piece's nodes in its body frame, from its near node inward.
    pub(super) fn piece_nodes(&self, piece: Piece) -> impl Iterator<Item = Vector> + '_ {
        self.chain.piece_nodes(piece)
    }

    /// Gives a laid piece its floor contact: one segment per link. While the coil rolls a
    /// segment lies its link's inset below the node line, so that the link lies on the
    /// floor as the coil laid it; in the bang it lies on the node line, which a piece turned
    /// over its pinned node would otherwise push into the floor at the pin, where neither
    /// can give. A link hanging from the coil needs none: its near node rests on the
    /// previous link and its far node is carried by the coil, which stands on its own curved
    /// contact; a collider there would touch the floor just before the node arrives, a
    /// corner impact on every link.
    pub(super) fn lay_piece(&mut self, piece: Piece) {
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
                    .friction(self.settings.friction)
                    .collision_groups(Self::tape_groups()),
                Some(piece.body),
            );
            return;
        }
        self.lay_links(piece.body, piece.first, piece.last);
    }

    /// Gives `body` one floor segment per link of `first..=last` (the rolling phase's, see
    /// [`Self::lay_piece`]), from the links' nodes in that body's frame.
    fn lay_links(&mut self, body: RigidBodyHandle, first: usize, last: usize) {
        for k in first..=last {
            let [near, far] = self.chain.local[k];
            let half = 0.5 * (near - far).length();
            let inset = self.inset_m(k);
            self.world.insert_collider(
                ColliderBuilder::segment(Vector::new(-half, -inset), Vector::new(half, -inset))
                    .position(Pose::new(0.5 * (near + far), (near - far).to_angle()))
                    .density(0.0)
                    .friction(self.settings.friction)
                    .collision_groups(Self::tape_groups()),
                Some(body),
            );
        }
    }

    /// Joins the near node of `piece` to whatever holds it: the previous free piece, or the
    /// world if that one is frozen, or nothing for the tape's outer end.
    pub(super) fn join_near_node(&mut self, piece: Piece) {
        let near = self.chain.local[piece.first][0];
        if let Some(prev) = self.chain.free.back().copied() {
            let joint = RevoluteJointBuilder::new()
                .local_anchor1(self.chain.local[prev.last][1])
                .local_anchor2(near)
                .contacts_enabled(false)
                .softness(self.settings.joint_softness);
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
    pub(super) fn pin_to_world(&mut self, piece: Piece) {
        let near = self.chain.local[piece.first][0];
        let mut node = self.world.bodies[piece.body]
            .position()
            .transform_point(near);
        if self.phase != Phase::Rolling {
            // Just above the contact plane: on or below it, the floor pushes the pinned node
            // out while the pin holds it, and the solver's two impulses grow against each
            // other without bound.
            node.y = node.y.max(self.settings.half_b + self.settings.pin_lift_m);
        }
        let joint = RevoluteJointBuilder::new()
            .local_anchor1(node)
            .local_anchor2(near)
            .contacts_enabled(self.phase != Phase::Rolling)
            .softness(self.settings.joint_softness);
        self.world
            .insert_impulse_joint(self.ground, piece.body, joint);
    }

    /// Removes the joints between a free link and the coil.
    pub(super) fn unpin_from_coil(&mut self, link: RigidBodyHandle, coil: RigidBodyHandle) {
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

    pub(super) fn detach_outermost(&mut self) {
        let Some(coil) = self.coil.body else { return };
        let before = self.total_energy();
        let k = self.coil.first_attached;
        if let Some(prev) = self.chain.free.back().copied() {
            self.lay_piece(prev);
        }
        let piece = self.spawn_piece(k, k, coil);
        // The previous free link was pinned to the coil at this link's near node.
        if let Some(prev) = self.chain.free.back().copied() {
            self.unpin_from_coil(prev.body, coil);
        }
        self.join_near_node(piece);
        if k == 0 {
            // The tape's free end has no previous link to rest on: without a floor contact
            // it would droop below the floor until laid, and be pushed out then.
            self.lay_piece(piece);
        }
        self.chain.free.push_back(piece);
        // Both bodies are in the coil's frame: the far node has the same coordinates in each.
        let far = self.chain.links[k].far;
        let far = Vector::new(far[0], far[1]);
        self.world.insert_impulse_joint(
            piece.body,
            coil,
            RevoluteJointBuilder::new()
                .local_anchor1(far)
                .local_anchor2(far)
                .contacts_enabled(false)
                .softness(self.settings.joint_softness),
        );
        // Remove the link's mass from the coil, keeping the velocity field.
        let link = self.chain.links[k];
        self.coil.sums.add(&link, -1.0);
        self.coil.first_attached += 1;
        let body = &mut self.world.bodies[coil];
        let (v_old, w, com_old) = (body.linvel(), body.angvel(), body.center_of_mass());
        body.set_additional_mass_properties(self.coil.sums.mass_properties(), true);
        body.recompute_mass_properties_from_colliders(&self.world.colliders);
        let r = body.center_of_mass() - com_old;
        body.set_linvel(v_old + Vector::new(-w * r.y, w * r.x), true);
        self.accounts.ledger.detach_j += before - self.total_energy();
    }

    /// Joins laid pieces into the laid tape on a frictionless floor, from the laid end.
    ///
    /// There nothing holds the laid tape where it lies: pinning it, as
    /// [`Self::freeze_settled`] does where friction holds it, would give the floor a grip it
    /// has not. Lying flat, held by the floor across it and by its joints along it, the
    /// laid tape slides as one rigid body, the exact-geometry model's flat tape. So a laid
    /// piece that does not hold the coil and lies flat beside the laid tape's body (every
    /// node within [`FLAT_B`] of a thickness of its level) or moves with it (within the
    /// freeze speed) is joined to it, with their momentum along the floor; what that takes,
    /// the piece's landing, is booked as freezing's. A freeze speed of 0 joins none.
    ///
    /// The coil's pull then reaches the laid tape through one body and one joint, not through
    /// a joint per link: the engine's four solver iterations cannot carry it along a thousand
    /// links, and a tape of 1160 links gained 0.45 % of its energy before its bang that way
    /// (`docs/limits.md`, "The frictionless floor's laid tape").
    pub(super) fn join_laid(&mut self) {
        let holding = usize::from(self.coil.body.is_some());
        while self.chain.free.len() > 1 + holding {
            let (laid, next) = (self.chain.free[0], self.chain.free[1]);
            if self.world.bodies[next.body].colliders().is_empty()
                || self.settings.freeze_speed == 0.0
                || (self.speed_against(next, laid) >= self.settings.freeze_speed
                    && !self.lies_flat(next, laid))
            {
                break;
            }
            let (a, b) = (&self.world.bodies[laid.body], &self.world.bodies[next.body]);
            let before = a.kinetic_energy() + b.kinetic_energy();
            let (ma, mb) = (a.mass(), b.mass());
            let mass = ma + mb;
            // Held flat, the joined body keeps only its momentum along the floor.
            let momentum = a.linvel().x * ma + b.linvel().x * mb;
            let pose = *a.position();
            let relative = pose.inverse() * *b.position();
            let mprops = a.mass_properties().local_mprops
                + b.mass_properties().local_mprops.transform_by(&relative);
            for k in next.first..=next.last {
                self.chain.local[k] = self.chain.local[k].map(|n| relative.transform_point(n));
            }
            // The joint that held the piece after `next` now holds it to the laid tape, where
            // its near node is now (as a pin at a freeze), with the impulse it carried: the
            // solver starts from the tension it had, not from none.
            if let Some(following) = self.chain.free.get(2).copied() {
                let at = self.world.bodies[following.body]
                    .position()
                    .transform_point(self.chain.local[following.first][0]);
                let handles: Vec<_> = self
                    .world
                    .impulse_joints
                    .joints_between(next.body, following.body)
                    .map(|(h, _)| h)
                    .collect();
                for h in handles {
                    let joints = &mut self.world.impulse_joints;
                    if let Some(joint) = joints.set_bodies(h, laid.body, following.body, true) {
                        let mut frame = relative * joint.data.local_frame1;
                        frame.translation = pose.inverse_transform_point(at);
                        joint.data.set_local_frame1(frame);
                    }
                }
            }
            self.world.remove_body(next.body);
            self.hold_flat(laid.body);
            let body = &mut self.world.bodies[laid.body];
            body.set_additional_mass_properties(mprops, true);
            body.recompute_mass_properties_from_colliders(&self.world.colliders);
            body.set_linvel(Vector::new(momentum / mass, 0.0), true);
            body.set_angvel(0.0, true);
            let after = body.kinetic_energy();
            self.chain.free.remove(1);
            let joined = Piece {
                last: next.last,
                rest_y_m: self.rest_height_m(laid.first, next.last),
                ..laid
            };
            self.chain.free[0] = joined;
            self.accounts.ledger.freeze_j += before - after;
        }
    }

    /// Parts the laid tape's body held flat by [`Self::join_laid`], if there is one, into a
    /// body per link moving as it moved: a tape bends where the whip lands on it, and a
    /// body metres long, lifted at its inner end, rose off the floor whole in the bang (on
    /// the thin tape at b/R = 1/300 it rose 0.45 mm in 5 ms, and the floor took 99 % of what
    /// the bang dissipated). The bang then joins the links into its pieces, as it does the
    /// rest of the tape, and freezes those that move slower than the freeze speed.
    pub(super) fn part_laid(&mut self) {
        let Some(laid) = self.chain.free.front().copied() else {
            return;
        };
        if self.world.bodies[laid.body].locked_axes().is_empty() {
            return;
        }
        let body = &self.world.bodies[laid.body];
        let pose = *body.position();
        let (com, linvel, angvel) = (body.center_of_mass(), body.linvel(), body.angvel());
        let mut parts = Vec::with_capacity(laid.last - laid.first + 1);
        for k in laid.first..=laid.last {
            let [near, far] = self.chain.local[k];
            let link = &self.chain.links[k];
            let centre = 0.5 * (near + far);
            let r = pose.transform_point(centre) - com;
            let handle = self.world.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(pose)
                    .additional_mass_properties(MassProperties::new(
                        centre,
                        link.mass_kg,
                        link.mass_kg * link.length_m * link.length_m / 12.0,
                    ))
                    .linvel(linvel + Vector::new(-angvel * r.y, angvel * r.x))
                    .angvel(angvel)
                    .can_sleep(false)
                    .user_data(k as u128),
            );
            self.world.bodies[handle]
                .recompute_mass_properties_from_colliders(&self.world.colliders);
            parts.push(Piece {
                first: k,
                last: k,
                body: handle,
                rest_y_m: self.rest_height_m(k, k),
            });
        }
        self.world.remove_body(laid.body);
        self.chain.free.pop_front();
        for part in parts.into_iter().rev() {
            self.chain.free.push_front(part);
        }
    }

    /// Holds the laid tape's body flat on the floor: it slides along the floor, neither
    /// rising nor turning, as a straight tape lying on a level floor does. The floor's
    /// support is then exact, with no contact to solve: a contact per link, or a soft
    /// contact at each of its two ends, cost the engine's solver as much as the joints the
    /// body saved, and the soft contacts traded energy with the body's weight.
    fn hold_flat(&mut self, body: RigidBodyHandle) {
        let colliders = self.world.bodies[body].colliders().to_vec();
        for c in colliders {
            self.world.remove_collider(c);
        }
        let body = &mut self.world.bodies[body];
        body.set_locked_axes(
            LockedAxes::TRANSLATION_LOCKED_Y | LockedAxes::ROTATION_LOCKED,
            true,
        );
    }

    /// Whether every node of `piece` lies within [`FLAT_B`] thicknesses of the height of
    /// the laid tape's last node, `laid`'s: lying flat on the floor beside it.
    fn lies_flat(&self, piece: Piece, laid: Piece) -> bool {
        let within = FLAT_B * 2.0 * self.settings.half_b;
        let held = &self.world.bodies[laid.body];
        let level = held
            .position()
            .transform_point(self.chain.local[laid.last][1])
            .y;
        let pose = *self.world.bodies[piece.body].position();
        self.piece_nodes(piece)
            .all(|n| (pose.transform_point(n).y - level).abs() < within)
    }

    /// How fast `piece`'s fastest node moves against the motion of `other`'s body at that
    /// point (m/s).
    fn speed_against(&self, piece: Piece, other: Piece) -> f64 {
        let (body, frame) = (
            &self.world.bodies[piece.body],
            &self.world.bodies[other.body],
        );
        let pose = *body.position();
        self.piece_nodes(piece)
            .map(|n| {
                let p = pose.transform_point(n);
                (body.velocity_at_point(p) - frame.velocity_at_point(p)).length()
            })
            .fold(0.0, f64::max)
    }

    /// Freezes settled pieces from the laid end: a piece whose nodes all move slower than
    /// the freeze speed ([`Model::moved_speed`]) and that is not holding the coil is removed
    /// from the engine.
    pub(super) fn freeze_settled(&mut self) {
        let min_free = usize::from(self.coil.body.is_some());
        while self.chain.free.len() > min_free {
            let oldest = self.chain.free[0];
            if self.moved_speed(oldest) >= self.settings.freeze_speed {
                break;
            }
            let body = &self.world.bodies[oldest.body];
            let pose = *body.position();
            let nodes: Vec<Vector> = self
                .piece_nodes(oldest)
                .map(|n| pose.transform_point(n))
                .collect();
            let kinetic = body.kinetic_energy();
            self.chain.frozen_potential_j += self.potential_of(body);
            // The last entry was the previous frozen piece's far node: this one's near node.
            self.chain.frozen_nodes.pop();
            self.chain
                .frozen_nodes
                .extend(nodes.iter().map(|p| [p.x, p.y]));
            self.world.remove_body(oldest.body);
            self.chain.free.pop_front();
            // Pin the next piece where its near node is now, not where the frozen piece's
            // far node was: a joint stretched by tension would otherwise hand its stretch to
            // the anchor at every freeze, and the laid tape would creep.
            if let Some(next) = self.chain.free.front().copied() {
                self.pin_to_world(next);
            }
            match self.phase {
                Phase::Rolling => self.accounts.ledger.freeze_j += kinetic,
                _ => {
                    self.accounts.ledger.bang_j += kinetic;
                    self.bang.ledger.freeze_j += kinetic;
                    self.close_pin_gap();
                }
            }
        }
    }
}
