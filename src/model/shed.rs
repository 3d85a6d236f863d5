//! The rolling phase: the coil's contact ball refitted to the spiral's lowest point, links
//! shed at the floor into pieces joined by revolute joints, laid and pinned, and settled
//! pieces frozen out of the engine.

use super::*;

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
        for k in piece.first..=piece.last {
            let [near, far] = self.chain.local[k];
            let half = 0.5 * (near - far).length();
            let inset = self.inset_m(k);
            self.world.insert_collider(
                ColliderBuilder::segment(Vector::new(-half, -inset), Vector::new(half, -inset))
                    .position(Pose::new(0.5 * (near + far), (near - far).to_angle()))
                    .density(0.0)
                    .friction(self.settings.friction)
                    .collision_groups(Self::tape_groups()),
                Some(piece.body),
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
