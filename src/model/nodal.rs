//! The nodal chain: rigid pieces joined end to end, in natural coordinates, stepped by the
//! energy-consistent midpoint rule with the floor's contacts in the same step. Pure `f64`:
//! it names no engine, and knows nothing of coils or ledgers.
//!
//! The unknowns are the chain's joint points, its nodes `x_0 ... x_N`: piece `i` is rigid
//! between `x_i` and `x_{i+1}`, and a joint is a node two pieces share, so the joints are
//! not constraints at all. A material point of piece `i` (its centre of mass, a contact
//! point) sits at fixed coordinates `(alpha, beta)` in its chord's frame:
//!
//! ```text
//! d_i = x_{i+1} - x_i,      p = x_i + alpha d_i + beta J d_i      (J: a quarter turn)
//! ```
//!
//! linear in the nodes. So the kinetic energy is `v^T M v / 2` with a constant mass matrix
//! `M`, block-tridiagonal in 2 by 2 node blocks (each piece's 4 by 4 block from its mass,
//! first moment and second moment about its near node), gravity's potential is linear,
//! `V = -f . x`, and the only constraints are the pieces' rigidity, quadratic:
//! `c_i(x) = (|d_i|^2 - l_i^2) / 2 = 0`. A pin holds `x_0`. A step of length `h` from
//! `(x, v)`, with `x_mid = (x + x+) / 2` (Gonzalez 1996):
//!
//! ```text
//! x+ = x + h (v + v+) / 2
//! M (v+ - v) = h f + sum_i Lambda_i grad c_i(x_mid) / l_i + C^T P
//! c_i(x+) = 0
//! ```
//!
//! Because `c_i` is quadratic, `c_i(x+) - c_i(x) = grad c_i(x_mid) . (x+ - x)` exactly: the
//! rigidity's impulses do no work over a step of any length, once the constraints hold at
//! both ends. Gravity's work is `f . (x+ - x)`, exactly the fall of the potential. A contact
//! point is linear in the nodes, `p = C x`, so the floor's impulse `P` does exactly the work
//! `P . C (v + v+) / 2`, which is what the step reports. Energy is therefore kept to the
//! Newton tolerance, and whatever the floor takes is booked where it is taken. The rigidity's
//! impulses are central between the nodes, and the midpoint rule keeps every quadratic
//! invariant: the angular momentum is kept exactly as well (with no floor and no gravity).
//!
//! Each Newton iteration solves one banded system, linear in the pieces: the blocks hold a
//! node's velocity with the rigidity row and the contact rows of the piece before it
//! (`newton.rs`). The floor's contacts are inelastic with Coulomb friction, each point's
//! normal velocity at the step's end held at its target and its tangential velocity at
//! zero (sticking) or its friction at `mu` times its normal impulse against the slip
//! (sliding), chosen by Alart and Curnier's rule within the same iterations
//! (`contact.rs`). The targets never let the floor give energy: a point that lands stops
//! (its work half its normal impulse times its approach speed), a point above the floor
//! that would pass it arrives at it, and a point that was leaving the floor and is pulled
//! back leaves the step as fast as it came. A point that a landing takes below the floor
//! (the midpoint rule moves it by its mean velocity) is moved out by position after the
//! step, the rigidity kept: the potential energy that costs is reported apart
//! ([`StepReport::projection_j`]).
//!
//! What the step does not hold is the end velocities' tangency: the chords' mean stretching
//! rate is zero, the end's is not, and it flips its sign from step to step (the midpoint
//! rule damps nothing). Its kinetic energy is a share of the chain's that grows with the
//! step (4e-10 at 0.02 rad a step, 3e-6 at 0.1, 8e-3 at 0.3 on a flexing chain), and which
//! the floor's impulses, acting through the mean velocities, never take: on a landing tape
//! it stays in the pieces until they freeze. docs/final-bang.md has the measurements; the
//! coil's bang does not ship this step.
//!
//! References: O. Gonzalez, "Time integration and discrete Hamiltonian systems", J.
//! Nonlinear Sci. 6, 449 (1996); P. Betsch and S. Leyendecker, "The discrete null space
//! method for the energy consistent integration of constrained mechanical systems, Part II:
//! multibody dynamics", Int. J. Numer. Meth. Eng. 67, 499 (2006) (natural coordinates); P.
//! Alart and A. Curnier, "A mixed formulation for frictional contact problems prone to
//! Newton like solution methods", Comput. Methods Appl. Mech. Eng. 92, 353 (1991); D.
//! Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996.

mod contact;
mod newton;
mod plane;
mod system;

use plane::{add, cross, dot, norm, quarter, scale, sub};

use super::exact_chain::{Body, Floor, SolveStats, StepError, Tolerance};

/// A rigid piece between two neighbouring nodes, in its chord's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// Mass (kg, > 0).
    pub mass_kg: f64,
    /// The centre of mass `(alpha, beta)`: along the chord from the near node and across it
    /// (a quarter turn counter-clockwise), as fractions of the chord.
    pub centre: [f64; 2],
    /// The second moment about the near node, `integral (alpha^2 + beta^2) dm`, over the mass.
    pub gyration: f64,
    /// The chord's length (m, > 0).
    pub length_m: f64,
    /// The chord's direction in the piece's own axes (rad): its body's angle is the chord's
    /// less this.
    pub chord_angle_rad: f64,
}

impl Piece {
    /// The piece of a rigid body of `mass_kg` and moment of inertia `inertia_kg_m2` about its
    /// centre of mass, whose near and far nodes sit at `near` and `far` from that centre in
    /// its own axes (m).
    pub fn of_body(mass_kg: f64, inertia_kg_m2: f64, near: [f64; 2], far: [f64; 2]) -> Self {
        let chord = sub(far, near);
        let length_m = norm(chord);
        let centre = chord_coordinates(near, far, [0.0, 0.0]);
        Self {
            mass_kg,
            centre,
            gyration: inertia_kg_m2 / (mass_kg * length_m * length_m)
                + centre[0] * centre[0]
                + centre[1] * centre[1],
            length_m,
            chord_angle_rad: chord[1].atan2(chord[0]),
        }
    }

    /// The moment of inertia about the centre of mass (kg m^2).
    pub fn inertia_kg_m2(&self) -> f64 {
        let [a, b] = self.centre;
        self.mass_kg * self.length_m.powi(2) * (self.gyration - a * a - b * b)
    }

    /// The piece's 4 by 4 mass matrix in `(v_near, v_far)` as `[a, b, c, e]`: `a I` on the
    /// near node, `b I` on the far node, `c I + e J` from near to far (kg).
    fn mass_blocks(&self) -> [f64; 4] {
        let m = self.mass_kg;
        let j = m * self.gyration;
        let [alpha, beta] = self.centre;
        [m - 2.0 * m * alpha + j, j, m * alpha - j, m * beta]
    }
}

/// The coordinates `(alpha, beta)` of the point `p` in the frame of the chord from `near`
/// to `far` (all three in one frame, m).
pub fn chord_coordinates(near: [f64; 2], far: [f64; 2], p: [f64; 2]) -> [f64; 2] {
    let chord = sub(far, near);
    let l2 = dot(chord, chord);
    let r = sub(p, near);
    [dot(r, chord) / l2, dot(r, quarter(chord)) / l2]
}

/// The floor's impulse at one contact point over a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactImpulse {
    /// The piece's index along the chain.
    pub piece: usize,
    /// The point's index among the piece's contact points.
    pub vertex: usize,
    /// Along the floor's normal (N s).
    pub normal_n_s: [f64; 2],
    /// Along its surface: friction (N s).
    pub friction_n_s: [f64; 2],
    /// Where it acted, at the step's midpoint (world, m).
    pub point_m: [f64; 2],
    /// From the piece's centre of mass to that point, at the step's midpoint (m).
    pub arm_m: [f64; 2],
    /// The work of the normal and the friction impulse: each times its point's mean
    /// velocity over the step, exactly what the step did (J; negative: taken).
    pub work_j: [f64; 2],
}

/// How a step went, and where its energy went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations taken (each one banded solve).
    pub iterations: u32,
    /// Whether the iterations met the tolerance with the contacts' modes settled.
    pub converged: bool,
    /// The largest error of a piece's length at the step's end (m).
    pub joint_gap_m: f64,
    /// The deepest a contact point ended below the floor, after the projection (m).
    pub penetration_m: f64,
    /// Gravity's work, `f . (x+ - x)` (J).
    pub gravity_work_j: f64,
    /// The floor's work: normal, friction (J; negative: taken from the chain).
    pub floor_work_j: [f64; 2],
    /// The rigidity's work, `sum Lambda_i (c_i(x+) - c_i(x)) / (h l_i)`: zero but for the
    /// tolerance (J).
    pub joint_work_j: f64,
    /// The change of potential energy the projection out of the floor made (J; positive:
    /// raised).
    pub projection_j: f64,
    /// The change of kinetic energy over the step (J).
    pub kinetic_change_j: f64,
    /// The largest angle a piece turned (rad).
    pub max_turn_rad: f64,
    /// The pieces the step was taken in: 1, or more where it was halved.
    pub pieces: u32,
    /// Of those, the pieces taken without friction (where Coulomb's law had no solution even
    /// in the smallest piece).
    pub frictionless: u32,
}

impl StepReport {
    /// Adds the step to a run's solve statistics (its rigidity's work in the drift's place:
    /// the midpoint step has one stage).
    pub fn add_to(&self, stats: &mut SolveStats) {
        stats.steps += 1;
        stats.iterations += u64::from(self.iterations);
        stats.max_iterations = stats.max_iterations.max(self.iterations);
        stats.missed_steps += u64::from(!self.converged);
        stats.halvings += u64::from(self.pieces.saturating_sub(1));
        stats.joint_work_j[1] += self.joint_work_j;
        stats.max_joint_gap_m = stats.max_joint_gap_m.max(self.joint_gap_m);
        stats.max_penetration_m = stats.max_penetration_m.max(self.penetration_m);
    }

    fn merge(first: Self, second: Self) -> Self {
        Self {
            iterations: first.iterations + second.iterations,
            converged: first.converged && second.converged,
            joint_gap_m: first.joint_gap_m.max(second.joint_gap_m),
            penetration_m: first.penetration_m.max(second.penetration_m),
            gravity_work_j: first.gravity_work_j + second.gravity_work_j,
            floor_work_j: [0, 1].map(|k| first.floor_work_j[k] + second.floor_work_j[k]),
            joint_work_j: first.joint_work_j + second.joint_work_j,
            projection_j: first.projection_j + second.projection_j,
            kinetic_change_j: first.kinetic_change_j + second.kinetic_change_j,
            max_turn_rad: first.max_turn_rad.max(second.max_turn_rad),
            pieces: first.pieces + second.pieces,
            frictionless: first.frictionless + second.frictionless,
        }
    }
}

/// The chain: its nodes and their velocities, its pieces, the pin, the floor.
#[derive(Debug)]
pub struct NodalChain {
    nodes: Vec<[f64; 2]>,
    velocities: Vec<[f64; 2]>,
    pieces: Vec<Piece>,
    /// Whether node 0 is held where it is.
    pinned: bool,
    floor: Option<Floor>,
    /// Every piece's contact points in its chord's frame, piece by piece.
    points: Vec<[f64; 2]>,
    /// Where piece `i`'s points start in `points` (one more entry than pieces).
    point_at: Vec<usize>,
    tolerance: Tolerance,
    /// Each point's mode and impulses in the last step: the next one's first guess.
    warm: Vec<contact::Warm>,
    /// Each piece's rigidity impulse in the last step, per second of step.
    tension: Vec<f64>,
    /// Whether the step now being taken ignores friction (see [`Self::step`]).
    frictionless: bool,
    contacts: Vec<ContactImpulse>,
    scratch: newton::Scratch,
    system: super::blocks::BlockTridiag,
}

impl NodalChain {
    /// A chain of `pieces` between `nodes` (one more), moving at `velocities` (one per
    /// node), node 0 held where it is if `pinned`, solved to `tolerance`. No point touches
    /// anything until [`Self::set_floor`]. A pinned node's velocity is taken as zero.
    ///
    /// # Panics
    /// If there is not one node more than pieces, or one velocity per node.
    pub fn new(
        nodes: Vec<[f64; 2]>,
        mut velocities: Vec<[f64; 2]>,
        pieces: Vec<Piece>,
        pinned: bool,
        tolerance: Tolerance,
    ) -> Self {
        assert_eq!(nodes.len(), pieces.len() + 1, "one node more than pieces");
        assert_eq!(velocities.len(), nodes.len(), "one velocity per node");
        if pinned {
            velocities[0] = [0.0, 0.0];
        }
        let n = pieces.len();
        Self {
            nodes,
            velocities,
            pieces,
            pinned,
            floor: None,
            points: Vec::new(),
            point_at: vec![0; n + 1],
            tolerance,
            warm: Vec::new(),
            tension: vec![0.0; n],
            frictionless: false,
            contacts: Vec::new(),
            scratch: newton::Scratch::default(),
            system: super::blocks::BlockTridiag::default(),
        }
    }

    /// The chain of rigid `bodies`, each with its near and far node `ends` (its own axes,
    /// from its centre of mass, m): node `i + 1` is body `i`'s far node, where body `i + 1`'s
    /// near node is taken to be; each node's velocity is the one that keeps the bodies'
    /// momentum and angular momentum and loses the least kinetic energy (their anchors'
    /// velocities may differ a little). Returns the chain and that loss (J).
    pub fn of_bodies(
        bodies: &[Body],
        ends: &[[[f64; 2]; 2]],
        pinned: bool,
        tolerance: Tolerance,
    ) -> Result<(Self, f64), StepError> {
        assert_eq!(bodies.len(), ends.len(), "ends per body");
        let pieces: Vec<Piece> = bodies
            .iter()
            .zip(ends)
            .map(|(b, e)| Piece::of_body(b.mass_kg, b.inertia_kg_m2, e[0], e[1]))
            .collect();
        // The nodes from the first body's near node on, each piece at its body's angle.
        let mut nodes = Vec::with_capacity(bodies.len() + 1);
        if let (Some(b), Some(e)) = (bodies.first(), ends.first()) {
            nodes.push(b.point(e[0]));
        }
        for (b, p) in bodies.iter().zip(&pieces) {
            let last = nodes[nodes.len() - 1];
            let angle = b.angle_rad + p.chord_angle_rad;
            let (s, c) = angle.sin_cos();
            nodes.push([last[0] + p.length_m * c, last[1] + p.length_m * s]);
        }
        let n = nodes.len();
        let mut chain = Self::new(nodes, vec![[0.0; 2]; n], pieces, pinned, tolerance);
        let before: f64 = bodies.iter().map(Body::kinetic_j).sum();
        // Each body's own node velocities, tangent to its rigidity, summed through M.
        let mut momenta = vec![[0.0; 2]; n];
        for (i, (b, e)) in bodies.iter().zip(ends).enumerate() {
            let [near, far] = [e[0], e[1]].map(|p| b.velocity_at(b.arm(p)));
            let [a, bb, c, ee] = chain.pieces[i].mass_blocks();
            let m_near = add(scale(a, near), add(scale(c, far), scale(ee, quarter(far))));
            let m_far = add(
                scale(bb, far),
                sub(scale(c, near), scale(ee, quarter(near))),
            );
            momenta[i] = add(momenta[i], m_near);
            momenta[i + 1] = add(momenta[i + 1], m_far);
        }
        chain.velocities = system::solve_mass(&mut chain, &momenta)?;
        let lost = before - chain.kinetic_j();
        Ok((chain, lost))
    }

    /// Puts the chain on `floor`, piece `i` touching it at the points `points[i]` (its
    /// chord's frame, `(alpha, beta)`; see [`chord_coordinates`]). A node two pieces share
    /// should belong to one of them.
    ///
    /// # Panics
    /// If `points` does not have one entry per piece.
    pub fn set_floor(&mut self, floor: Floor, points: &[Vec<[f64; 2]>]) {
        assert_eq!(points.len(), self.pieces.len(), "contact points per piece");
        self.floor = Some(floor);
        self.points.clear();
        self.point_at.clear();
        for p in points {
            self.point_at.push(self.points.len());
            self.points.extend_from_slice(p);
        }
        self.point_at.push(self.points.len());
        self.warm = vec![contact::Warm::default(); self.points.len()];
    }

    /// The nodes (world, m).
    pub fn nodes(&self) -> &[[f64; 2]] {
        &self.nodes
    }

    /// The nodes' velocities (m/s).
    pub fn velocities(&self) -> &[[f64; 2]] {
        &self.velocities
    }

    /// The pieces.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// Piece `i`'s contact points (its chord's frame).
    pub fn points(&self, i: usize) -> &[[f64; 2]] {
        &self.points[self.point_at[i]..self.point_at[i + 1]]
    }

    /// The floor's impulses of the last step, contact point by contact point.
    pub fn contacts(&self) -> &[ContactImpulse] {
        &self.contacts
    }

    /// The world position of the point `(alpha, beta)` of piece `i` (m).
    pub fn point(&self, i: usize, local: [f64; 2]) -> [f64; 2] {
        material(&self.nodes, i, local)
    }

    /// The velocity of the point `(alpha, beta)` of piece `i` (m/s).
    pub fn point_velocity(&self, i: usize, local: [f64; 2]) -> [f64; 2] {
        material(&self.velocities, i, local)
    }

    /// Piece `i` as a rigid body about its centre of mass: its pose, the velocity of its
    /// centre and its spin about it (the chord's rate of turning).
    pub fn body(&self, i: usize) -> Body {
        let p = &self.pieces[i];
        let d = sub(self.nodes[i + 1], self.nodes[i]);
        let dv = sub(self.velocities[i + 1], self.velocities[i]);
        Body {
            mass_kg: p.mass_kg,
            inertia_kg_m2: p.inertia_kg_m2(),
            position_m: self.point(i, p.centre),
            angle_rad: d[1].atan2(d[0]) - p.chord_angle_rad,
            velocity_m_s: self.point_velocity(i, p.centre),
            spin_rad_s: cross(d, dv) / dot(d, d),
        }
    }

    /// Kinetic energy, `v^T M v / 2` (J).
    pub fn kinetic_j(&self) -> f64 {
        let v = &self.velocities;
        self.pieces
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let [a, b, c, e] = p.mass_blocks();
                let (u, w) = (v[i], v[i + 1]);
                0.5 * (a * dot(u, u) + b * dot(w, w)) + c * dot(u, w) + e * dot(u, quarter(w))
            })
            .sum()
    }

    /// Potential energy in `gravity` (m/s^2) from the world's origin (J).
    pub fn potential_j(&self, gravity: [f64; 2]) -> f64 {
        (0..self.pieces.len())
            .map(|i| {
                let p = &self.pieces[i];
                -p.mass_kg * dot(gravity, self.point(i, p.centre))
            })
            .sum()
    }

    /// Momentum and angular momentum about the world's origin (kg m/s, kg m^2/s).
    pub fn momentum(&self) -> [f64; 3] {
        let generalised = system::times_mass(&self.pieces, &self.velocities);
        let mut p = [0.0; 3];
        for (x, q) in self.nodes.iter().zip(&generalised) {
            p[0] += q[0];
            p[1] += q[1];
            p[2] += cross(*x, *q);
        }
        p
    }

    /// The largest error of a piece's length (m).
    pub fn length_error_m(&self) -> f64 {
        self.pieces
            .iter()
            .enumerate()
            .map(|(i, p)| (norm(sub(self.nodes[i + 1], self.nodes[i])) - p.length_m).abs())
            .fold(0.0, f64::max)
    }

    /// The position tolerance a step is solved to now: the chain's, or 4096 roundings of its
    /// largest coordinate if that is wider (m).
    pub fn position_tolerance_m(&self) -> f64 {
        let largest = self
            .nodes
            .iter()
            .flatten()
            .fold(0.0, |m: f64, x| m.max(x.abs()));
        self.tolerance
            .position_m
            .max(4096.0 * f64::EPSILON * largest)
    }

    /// Advances the chain by `h` (s) under `gravity` (m/s^2). On an error the chain is left
    /// as it was.
    ///
    /// A step whose iterations do not converge (within [`Tolerance::max_iterations`], with
    /// the contacts' modes settled), that turns a piece by more than
    /// [`Tolerance::max_turn_rad`], or whose solve fails, is taken again as two halves, down
    /// to 1/1024 of it; the report sums the halves. At that depth a converged step is kept
    /// however far it turns; one that did not converge is taken once more without friction
    /// (Coulomb's law can have no solution: Painleve's paradox; counted in
    /// [`StepReport::frictionless`]), and failing that is an error
    /// ([`StepError::Unconverged`]), as a failed solve is: an unconverged step's impulses
    /// are not a solution, and could give energy.
    pub fn step(&mut self, h: f64, gravity: [f64; 2]) -> Result<StepReport, StepError> {
        self.step_within(h, gravity, 0)
    }

    fn step_within(
        &mut self,
        h: f64,
        gravity: [f64; 2],
        depth: u32,
    ) -> Result<StepReport, StepError> {
        const MAX_DEPTH: u32 = 10;
        let saved = (
            self.nodes.clone(),
            self.velocities.clone(),
            self.warm.clone(),
            self.tension.clone(),
        );
        let result = newton::step(self, h, gravity);
        let fits = |r: &StepReport| r.converged && r.max_turn_rad <= self.tolerance.max_turn_rad;
        match result {
            Ok(report) if fits(&report) => return Ok(report),
            Ok(report) if depth >= MAX_DEPTH && report.converged => return Ok(report),
            Ok(_) if depth >= MAX_DEPTH => {
                // Coulomb's law can have no solution in a step (Painleve's paradox: a
                // point's friction would lift it off the floor that gives it): the
                // smallest step is then taken without friction, and counted.
                (self.nodes, self.velocities, self.warm, self.tension) = saved.clone();
                self.frictionless = true;
                let retry = newton::step(self, h, gravity);
                self.frictionless = false;
                if let Some(report) = retry.ok().filter(|r| r.converged) {
                    return Ok(StepReport {
                        frictionless: 1,
                        ..report
                    });
                }
                (self.nodes, self.velocities, self.warm, self.tension) = saved;
                return Err(StepError::Unconverged);
            }
            Err(e) if depth >= MAX_DEPTH => {
                (self.nodes, self.velocities, self.warm, self.tension) = saved;
                return Err(e);
            }
            _ => {}
        }
        (self.nodes, self.velocities, self.warm, self.tension) = saved;
        let first = self.step_within(0.5 * h, gravity, depth + 1)?;
        let contacts = std::mem::take(&mut self.contacts);
        let second = self.step_within(0.5 * h, gravity, depth + 1)?;
        let mut all = contacts;
        all.append(&mut self.contacts);
        self.contacts = all;
        Ok(StepReport::merge(first, second))
    }

    /// Holds node 0 where it is from now on, its velocity taken away by an impulse there
    /// (the least kinetic energy lost: a pin catching it). Returns the energy lost (J).
    pub fn pin_first(&mut self) -> Result<f64, StepError> {
        let before = self.kinetic_j();
        if self.pieces.is_empty() {
            self.velocities.fill([0.0; 2]);
        } else if !self.pinned {
            system::catch_first(self)?;
            self.pinned = true;
        }
        Ok(before - self.kinetic_j())
    }

    /// Removes the first piece: node 1 becomes node 0, held where it is (see
    /// [`Self::pin_first`]). Returns the kinetic energy the removed piece's share of the
    /// chain had (J, by the chain's energy before less after, the pin's catch included).
    ///
    /// # Panics
    /// If the chain has no piece.
    pub fn remove_first(&mut self) -> Result<f64, StepError> {
        assert!(!self.pieces.is_empty(), "a piece to remove");
        let before = self.kinetic_j();
        self.nodes.remove(0);
        self.velocities.remove(0);
        self.pieces.remove(0);
        self.tension.remove(0);
        if !self.points.is_empty() || self.floor.is_some() {
            let cut = self.point_at[1];
            self.points.drain(..cut);
            self.warm.drain(..cut);
            self.point_at.remove(0);
            for at in &mut self.point_at {
                *at -= cut;
            }
        } else {
            self.point_at.remove(0);
        }
        self.pinned = false;
        self.pin_first()?;
        Ok(before - self.kinetic_j())
    }
}

/// The point `(alpha, beta)` of piece `i` of the values `x` at the nodes (positions or
/// velocities): `x_i + alpha d + beta J d`.
fn material(x: &[[f64; 2]], i: usize, [alpha, beta]: [f64; 2]) -> [f64; 2] {
    let d = sub(x[i + 1], x[i]);
    let j = quarter(d);
    [
        x[i][0] + alpha * d[0] + beta * j[0],
        x[i][1] + alpha * d[1] + beta * j[1],
    ]
}

#[cfg(test)]
mod tests;
