//! A step taken in halves: where its drift does not hold, where its solve fails, where a
//! move by position carries a body beyond what its search for the layers covered, or,
//! bounded ([`ExactChain::step_bounded`]), where its joints' error is outside its bound;
//! down to 1/1024 of it, the halves' reports summed.

use super::*;

impl ExactChain {
    /// Whether a step's drift may stand: it closed the joints and turned no body further
    /// than [`Tolerance::max_turn_rad`]. A step whose drift may not is taken again in halves.
    pub(super) fn drift_holds(&self, r: &StepReport) -> bool {
        r.drift_closed && r.max_turn_rad <= self.tolerance.max_turn_rad
    }

    pub(super) fn step_within(
        &mut self,
        h: f64,
        gravity: [f64; 2],
        depth: u32,
        bound: Option<ErrorBound>,
    ) -> Result<StepReport, StepError> {
        const MAX_DEPTH: u32 = 10;
        if bound.is_some() && depth < self.start_depth.min(MAX_DEPTH) {
            return self.halves(h, gravity, depth, bound, 0);
        }
        let (bodies, warm) = (self.bodies.clone(), self.warm.clone());
        let layer_warm = self.layer_warm.clone();
        let result = solve::step(self, h, gravity, depth < MAX_DEPTH).map(|mut r| {
            r.moved_j = moved_j(&r, &self.contacts, &bodies);
            r
        });
        // A contact solve that missed its tolerance is counted, not halved: a shorter step
        // does not make a stiff contact set converge. But a step that leaves a joint open
        // wider than the contacts' slop (the projection out of the floor could not hold
        // them: a step that took many points deep at once) is taken again in halves, as is
        // one whose move by position carried a body beyond the margin its layers' features
        // were found within ([`StepReport::beyond_reach_m`]): touches it never measured may
        // lie a thickness deep at its end.
        let open = solve::SLOP * self.tolerance.position_m;
        let fits = |r: &StepReport| {
            self.drift_holds(r) && r.joint_gap_m <= open && r.beyond_reach_m == 0.0
        };
        let accurate = |r: &StepReport| bound.is_none_or(|b| b.holds(r));
        match result {
            Ok(report) if accurate(&report) && (fits(&report) || depth >= MAX_DEPTH) => {
                self.fresh = false;
                self.deepest = self.deepest.max(depth);
                return Ok(report);
            }
            Ok(report) if depth >= MAX_DEPTH => {
                let b = bound.expect("only a bound refuses a step at the last depth");
                self.bodies = bodies;
                self.warm = warm;
                self.layer_warm = layer_warm;
                return Err(StepError::Inaccurate {
                    error_j: report.joint_error_j(),
                    moved_j: report.moved_j,
                    least_j: b.least_j,
                    most_j: b.most_j,
                    tolerance: b.tolerance,
                });
            }
            Err(e) if depth >= MAX_DEPTH => return Err(e),
            _ => {}
        }
        self.bodies = bodies;
        self.warm = warm;
        self.layer_warm = layer_warm;
        self.halves(h, gravity, depth, bound, 1)
    }

    /// A step of `h` taken as two halves at `depth + 1`, the second bounded by what the
    /// first left; `retried` counts a solve of the whole thrown away (0 or 1).
    fn halves(
        &mut self,
        h: f64,
        gravity: [f64; 2],
        depth: u32,
        bound: Option<ErrorBound>,
        retried: u32,
    ) -> Result<StepReport, StepError> {
        let first = self.step_within(0.5 * h, gravity, depth + 1, bound)?;
        let contacts = std::mem::take(&mut self.contacts);
        let rest = bound.map(|b| b.less(first.joint_error_j()));
        let second = self.step_within(0.5 * h, gravity, depth + 1, rest)?;
        let mut all = contacts;
        all.append(&mut self.contacts);
        self.contacts = all;
        Ok(StepReport {
            iterations: first.iterations + second.iterations,
            converged: first.converged && second.converged,
            drift_closed: first.drift_closed && second.drift_closed,
            joint_gap_m: first.joint_gap_m.max(second.joint_gap_m),
            penetration_m: first.penetration_m.max(second.penetration_m),
            overlap_m: first.overlap_m.max(second.overlap_m),
            gravity_work_j: first.gravity_work_j + second.gravity_work_j,
            max_turn_rad: first.max_turn_rad.max(second.max_turn_rad),
            pieces: first.pieces + second.pieces,
            retries: retried + first.retries + second.retries,
            joint_work_j: [0, 1, 2].map(|k| first.joint_work_j[k] + second.joint_work_j[k]),
            caught_j: first.caught_j + second.caught_j,
            moved_j: first.moved_j + second.moved_j,
            projection_j: first.projection_j + second.projection_j,
            beyond_reach_m: first.beyond_reach_m.max(second.beyond_reach_m),
        })
    }
}

/// The energy a step moved ([`StepReport::moved_j`]) from its report, its contacts and the
/// bodies at its start: each stage's joints' work and each contact's, counted whole, and
/// the kinetic energy at its start times the turn of its fastest body over a whole turn.
fn moved_j(r: &StepReport, contacts: &[ContactImpulse], bodies: &[Body]) -> f64 {
    let joints: f64 = r.joint_work_j.iter().map(|w| w.abs()).sum();
    let contacts: f64 = contacts
        .iter()
        .map(|c| c.work_j[0].abs() + c.work_j[1].abs())
        .sum();
    let kinetic: f64 = bodies.iter().map(Body::kinetic_j).sum();
    joints + contacts + kinetic * r.max_turn_rad / std::f64::consts::TAU
}
