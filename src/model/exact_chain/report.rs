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
    /// The joints' work in each stage: the impulses at the start, the drift, the impulses at
    /// the end (J; positive: given to the chain). Where the numerical part is made.
    pub joint_work_j: [f64; 3],
    /// What the joints took at the start of the chain's first step, when they were made
    /// rigid: the relative motion its starting velocities had at the joints and the pin (J;
    /// 0 after the first step). It is part of the joints' work in `joint_work_j[0]`.
    pub caught_j: f64,
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
}
