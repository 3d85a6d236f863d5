//! What the exact chain reports of its steps: each contact's impulse and where it acted,
//! how a step was solved, a run's steps summed, and why a step could not be taken.

/// What a contact's impulse acted between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// The floor.
    Floor,
    /// The laid tape that no longer moves.
    Laid,
    /// Another body of the chain, by its index: the impulse acted on it equal and opposite.
    Body(usize),
}

/// A contact's impulse on one body during a step, where it acted: the floor's, the laid
/// tape's, or another body's (which took the same impulse reversed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactImpulse {
    /// The body's index along the chain.
    pub body: usize,
    /// The vertex's index among the body's contact points (the floor's); 0 for the layers.
    pub vertex: usize,
    /// What pushed on the body.
    pub on: Surface,
    /// Along the contact's normal (N s).
    pub normal_n_s: [f64; 2],
    /// Along its surface: friction (N s).
    pub friction_n_s: [f64; 2],
    /// From the body's centre of mass to the contact point, at the stage's pose (m).
    pub arm_m: [f64; 2],
    /// From the other body's centre of mass to the contact point, where `on` is a body (m).
    pub other_arm_m: [f64; 2],
    /// The work of the normal and the friction impulse, each times the mean relative
    /// velocity of the points it acted on over its stage (J; negative: taken from the
    /// chain). Where `on` is a body this is the pair's work, both bodies' together.
    pub work_j: [f64; 2],
}

/// How a step was solved.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations taken (each one direct solve).
    pub iterations: u32,
    /// Whether the drift closed the joints and the contacts' solve met its tolerance.
    pub converged: bool,
    /// Whether the drift closed the joints within the iteration cap.
    pub drift_closed: bool,
    /// The widest joint gap left at the step's end (m).
    pub joint_gap_m: f64,
    /// The deepest a contact point ended below the floor (m; 0 if none).
    pub penetration_m: f64,
    /// The deepest two layers (bodies not joined to each other, or a body and the laid
    /// tape) overlap at the step's end (m; 0 if none, and without [`super::Layers`]).
    pub overlap_m: f64,
    /// Gravity's work over the step, each half kick's impulse times the mean velocity over
    /// it (J).
    pub gravity_work_j: f64,
    /// The largest angle a body turned in the drift (rad).
    pub max_turn_rad: f64,
    /// The pieces the step was taken in: 1, or more where it was halved.
    pub pieces: u32,
    /// Solves thrown away to take it: 0, or one for each time it, or a part of it, was
    /// taken again in halves.
    pub retries: u32,
    /// The joints' work in each stage: the impulses at the start, the drift, the impulses at
    /// the end (J; positive: given to the chain). Where the numerical part is made.
    pub joint_work_j: [f64; 3],
    /// What the joints took at the start of the chain's first step, when they were made
    /// rigid: the relative motion its starting velocities had at the joints and the pin (J;
    /// 0 after the first step). It is part of the joints' work in `joint_work_j[0]`.
    pub caught_j: f64,
    /// The energy the step moved: the work of each stage's joints and of each contact's
    /// impulse, each counted whole, and the kinetic energy at its start times the turn of
    /// its fastest body over a whole turn (J, >= 0): the scale of a step's own error,
    /// which RATTLE makes in proportion to the energy moving and grows with the turn.
    pub moved_j: f64,
    /// What holding the drift's velocity to the joints took where the step moved the bodies
    /// out of the floor or out of each other by position (J; negative: taken from the
    /// chain). Part of the joints' work in `joint_work_j[1]`, and no error of its own: it is
    /// mostly the drift's velocity across the joints at the step's end (RATTLE's secant),
    /// which the drift booked as gained and the end's impulses would take back anyway, so
    /// it and the drift's stage cancel to the step's error (docs/final-bang.md, "A
    /// tolerance on the bang's steps").
    pub projection_j: f64,
    /// How far a body's outline ended beyond the margin the step found the layers'
    /// features within (m; 0: within it, and without [`super::Layers`]). The search covers
    /// what the drift can move a body; a move by position out of the floor or out of
    /// another layer may take it further, to touches the step never measured. A step
    /// that does is taken again in halves.
    pub beyond_reach_m: f64,
}

impl StepReport {
    /// The joints' work in the step, less what they took when they were made rigid
    /// (`caught_j`, a discard the caller books, not an error): joints held exactly do no
    /// work, so this is the step's numerical error (J; positive: given to the chain).
    pub fn joint_error_j(&self) -> f64 {
        self.joint_work_j.iter().sum::<f64>() + self.caught_j
    }
}

/// The joint work a step may do ([`StepReport::joint_error_j`]): a step outside both the
/// range and its share of the energy it moved is taken again in halves (see
/// [`super::ExactChain::step_bounded`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorBound {
    /// The least joint work the step may do (J, <= 0).
    pub least_j: f64,
    /// The most (J, >= 0).
    pub most_j: f64,
    /// The caller's tolerance: a step whose joints' work is within this share of the
    /// energy it moved ([`StepReport::moved_j`]) holds whatever the range.
    pub tolerance: f64,
}

impl ErrorBound {
    /// Whether a step's error, its joints' work ([`StepReport::joint_error_j`], the
    /// realignment after a move by position included), is within the bound: in the range,
    /// or within the tolerance of the energy the step moved.
    pub fn holds(&self, r: &StepReport) -> bool {
        let error_j = r.joint_error_j();
        (self.least_j..=self.most_j).contains(&error_j)
            || error_j.abs() <= self.tolerance * r.moved_j
    }

    /// The bound left for the rest of a step whose first part did `spent_j`. The range
    /// keeps zero in it: a first part within its share of what it moved may have spent
    /// past the range, and the rest is not asked to give it back.
    pub fn less(&self, spent_j: f64) -> Self {
        Self {
            least_j: (self.least_j - spent_j).min(0.0),
            most_j: (self.most_j - spent_j).max(0.0),
            ..*self
        }
    }
}

/// How a run's steps were solved, summed step by step.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolveStats {
    /// Steps solved.
    pub steps: u64,
    /// Newton iterations over all steps (each one direct solve).
    pub iterations: u64,
    /// The most iterations one step took.
    pub max_iterations: u32,
    /// Steps that reached the iteration cap before the tolerance.
    pub missed_steps: u64,
    /// Extra pieces steps were halved into (0 if none was).
    #[serde(default)]
    pub halvings: u64,
    /// Solves thrown away: steps, or parts of steps, taken again in halves (their drift
    /// did not hold, or their joints' error was outside its bound).
    #[serde(default)]
    pub retries: u64,
    /// What moves by position cost the joints over the steps, where the steps were bounded
    /// ([`StepReport::projection_j`]), J: part of `joint_work_j[1]`.
    #[serde(default)]
    pub projection_j: f64,
    /// The joints' work in each stage over the steps (see [`StepReport::joint_work_j`]), J.
    #[serde(default)]
    pub joint_work_j: [f64; 3],
    /// The widest joint gap any step left (m).
    pub max_joint_gap_m: f64,
    /// The deepest any contact point ended below the floor (m).
    pub max_penetration_m: f64,
    /// The deepest two layers overlapped at any step's end (m).
    #[serde(default)]
    pub max_overlap_m: f64,
}

impl SolveStats {
    /// Adds one step's report.
    pub fn add(&mut self, r: &StepReport) {
        self.steps += 1;
        self.iterations += u64::from(r.iterations);
        self.max_iterations = self.max_iterations.max(r.iterations);
        self.missed_steps += u64::from(!r.converged);
        self.halvings += u64::from(r.pieces.saturating_sub(1));
        self.retries += u64::from(r.retries);
        self.projection_j += r.projection_j;
        for k in 0..3 {
            self.joint_work_j[k] += r.joint_work_j[k];
        }
        self.max_joint_gap_m = self.max_joint_gap_m.max(r.joint_gap_m);
        self.max_penetration_m = self.max_penetration_m.max(r.penetration_m);
        self.max_overlap_m = self.max_overlap_m.max(r.overlap_m);
    }

    /// Iterations per step, on average.
    pub fn mean_iterations(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.iterations as f64 / self.steps as f64
        }
    }
}

/// Why a step could not be taken. The chain is left as it was before the step.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The constraints' system was singular at block `block` (the body of that index).
    #[error("the exact chain's system is singular at body {block}")]
    Singular {
        /// The block whose pivot vanished.
        block: usize,
    },
    /// The solve gave a non-finite impulse or velocity.
    #[error("the exact chain's solve gave a non-finite value")]
    NonFinite,
    /// A step did not converge, even halved ten times: its Newton iterations, or the
    /// floor's contacts' modes, never settled.
    #[error("the exact chain's step did not converge, even halved ten times")]
    Unconverged,
    /// The layers' search found more features than its bound
    /// (`FEATURES_PER_NODE` a node): a body's reach this step, what its velocity can
    /// carry it, outgrew the tape, as a velocity that has diverged does.
    #[error(
        "the tape's layers would be measured at {features} or more features, a body \
         reaching {reach_m:.3e} m in one step: the step's velocity diverged, even halved \
         ten times"
    )]
    Unbounded {
        /// Features found when the search stopped.
        features: usize,
        /// The farthest a body's margin reached (m).
        reach_m: f64,
    },
    /// A step's joints did work outside the caller's bound ([`ErrorBound`]) even halved
    /// ten times.
    #[error(
        "a step's joints did {error_j:.3e} J of work, outside the {least_j:.3e}..{most_j:.3e} J \
         that a tolerance of {tolerance:e} leaves it and over that share of the {moved_j:.3e} J \
         the step moved, even halved ten times"
    )]
    Inaccurate {
        /// The joints' work in the last piece tried (J).
        error_j: f64,
        /// The energy that piece moved (J).
        moved_j: f64,
        /// The bound's least (J).
        least_j: f64,
        /// The bound's most (J).
        most_j: f64,
        /// The tolerance it stood for.
        tolerance: f64,
    },
}
