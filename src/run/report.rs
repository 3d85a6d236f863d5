//! What a run produced, [`RunReport`], with its parts: the milestones, the energy ledger,
//! the final bang's observables and the approach to it. Plain data for JSON, the summary
//! and the tables; built by the loop at the run's end.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::model::exact_chain::SolveStats;
use crate::model::{BangEnd, EnergyLedger};
use crate::run::guard::Bounds;
use crate::run::limits::ReferenceLimit;
use crate::run::stop::StopReason;
use crate::scene::Scene;
use crate::theory::References;

/// Which milestone a time is taken at; its text is its label (`0.5R`, `2b`, `f=0.25`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MilestoneKey {
    /// The equivalent radius at this fraction of the outer radius R (`0.5R`).
    OfRadius(f64),
    /// Two thicknesses, `r = 2b` (`2b`): the last milestone before the bang.
    TwoB,
    /// A spool's laid fraction (`f=0.25`).
    Laid(f64),
}

impl fmt::Display for MilestoneKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let label = match self {
            Self::OfRadius(k) => format!("{k}R"),
            Self::TwoB => "2b".to_owned(),
            Self::Laid(x) => format!("f={x}"),
        };
        f.pad(&label)
    }
}

/// One milestone: the coil at a given continuum-equivalent radius.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Milestone {
    /// Which milestone.
    pub key: MilestoneKey,
    /// Its label, e.g. `0.5R` or `2b` (the key's text).
    pub label: String,
    /// Equivalent radius (m).
    pub r_m: f64,
    /// Laid fraction `1 - (r/R)^2`.
    pub laid_fraction: f64,
    /// Simulation time to reach it (s), `None` if the run never got there.
    pub t_sim_s: Option<f64>,
    /// Exact-geometry model's time (s).
    pub t_geo_s: Option<f64>,
    /// Eq. (7)'s time (s).
    pub t_eq7_s: Option<f64>,
    /// Eq. (17)'s time (s).
    pub t_eq17_s: Option<f64>,
    /// `t_sim / t_geo - 1`: the simulation's own error.
    pub err_vs_geo: Option<f64>,
    /// `t_sim / t_eq7 - 1`.
    pub err_vs_eq7: Option<f64>,
    /// `t_geo / t_eq7 - 1`: the continuum model's own idealisation.
    pub geo_vs_eq7: Option<f64>,
    /// Contact-line speed in the simulation (m/s).
    pub xdot_sim_m_s: Option<f64>,
    /// Eq. (7)'s contact-line speed (m/s).
    pub xdot_eq7_m_s: Option<f64>,
    /// Simulation kinetic energy (J).
    pub kinetic_j: Option<f64>,
    /// Simulation potential energy (J).
    pub potential_j: Option<f64>,
    /// Simulation energy dissipated so far (J), before the bang: where the step that
    /// crosses the milestone also releases the coil (the thin tape's 2b), what the release
    /// and the bang took in it is left out, so that it is never more than the loss before
    /// the bang.
    pub dissipated_j: Option<f64>,
}

/// Where the energy went over the whole run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ledger {
    /// Initial energy, kinetic plus potential above the floor (J).
    pub e0_j: f64,
    /// `M g R`, the potential energy the paradox is about (J).
    pub mgr_j: f64,
    /// The energy scale the run's percentages are taken against: the largest of |E0|,
    /// `M g R` and the kinetic energy carried into the bang (J). E0 alone is no scale: a
    /// tape hanging from an axis starts with E0 ~ 0.
    pub energy_scale_j: f64,
    /// Potential energy of the tape lying flat, midline at `b/2` (J).
    pub flat_potential_j: f64,
    /// Energy lost before the final bang, by where it was lost.
    pub before_bang: EnergyLedger,
    /// Lost before the bang, in total (J).
    pub lost_before_bang_j: f64,
    /// Kinetic energy carried into the bang (J).
    pub kinetic_into_bang_j: f64,
    /// Mechanical energy above the flat rest state at the bang (J).
    pub available_at_bang_j: f64,
    /// Dissipated during the bang, as measured (J).
    pub dissipated_by_bang_j: f64,
    /// What the bang dissipated, by mechanism (J).
    pub bang: crate::model::BangLedger,
    /// Left at the end: kinetic plus potential above the flat rest state (J).
    pub left_j: f64,
    /// Time the bang began (s).
    pub bang_time_s: Option<f64>,
}

/// Below this fraction of the energy scale, what the bang dissipated is too little to split
/// by mechanism: the shares would be ratios of rounding (a tape swinging from an axis
/// dissipates ~1e-4 of it).
pub const BANG_SPLIT_MIN_OF_SCALE: f64 = 0.01;

impl Ledger {
    /// Whether the bang dissipated enough, against the energy scale, for its split by
    /// mechanism to mean something ([`BANG_SPLIT_MIN_OF_SCALE`]).
    #[must_use]
    pub fn bang_split_meaningful(&self) -> bool {
        self.dissipated_by_bang_j.abs() >= BANG_SPLIT_MIN_OF_SCALE * self.energy_scale_j
    }
}

/// The final bang: what it received, how violent it was, how long it took, where the tape
/// ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BangReport {
    /// Kinetic energy of the tape at the release (J).
    pub kinetic_in_j: f64,
    /// Fastest speed of any point of the tape during the bang (m/s).
    pub top_speed_m_s: f64,
    /// Simulated time from the release to the end of the bang (s).
    pub duration_s: f64,
    /// Largest floor normal force on the moving tape, its normal impulse over one step (N).
    pub peak_floor_force_n: f64,
    /// Normal impulse of the floor on the moving tape during the bang (N s).
    pub floor_impulse_n_s: f64,
    /// Where the tape's free (inner) end lies at the end (m, along the floor from the
    /// start of the tape).
    pub end_x_m: f64,
    /// The tape's midline length: where a tape laid flat would end (m).
    pub laid_length_m: f64,
    /// Kinetic energy still moving at the end (J).
    pub still_moving_j: f64,
    /// What ended the bang; `None` if the run stopped first (guard, `stop.max_time_s`,
    /// interrupted).
    pub ended_by: Option<BangEnd>,
    /// How the exact chain solved the bang's steps (all zero on the engine's).
    #[serde(default)]
    pub solve: SolveStats,
    /// Whether the tape's layers met each other in the bang: only where the released coil's
    /// chords stand off their arcs (`chord_sag_m`, m) by less than half the thickness.
    #[serde(default)]
    pub layers: bool,
    /// How far the released coil's links stand off the arcs they stand for, `l phi / 8` for
    /// a link of length `l` turning by the link angle `phi` (m).
    #[serde(default)]
    pub chord_sag_m: f64,
    /// The ratio the handover scaled every speed by at the release, for the pieces'
    /// thickness: the energy the unroll brought kept, the pieces turning with their own
    /// inertia `m b^2 / 12` more than their midlines'.
    #[serde(default)]
    pub thickness_speed_ratio: f64,
}

/// The approach to the bang: how far the contact line's speed diverged before the coil was
/// released (eq. 7's x' ~ 1/r as r -> 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Approach {
    /// Fastest contact-line speed while the coil rolled (m/s).
    pub peak_xdot_m_s: f64,
    /// Continuum-equivalent radius `R sqrt(1 - f)` there (m).
    pub peak_r_m: f64,
    /// The exact-geometry model's contact-line speed at the same laid fraction (m/s); `None`
    /// on a frictionless floor, where the model slides and has no rolling contact line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_xdot_geo_m_s: Option<f64>,
    /// The exact-geometry model's contact-line speed against the equivalent radius,
    /// `[r (m), x' (m/s)]`, down to the bang radius (empty on a frictionless floor, where
    /// the contact line slides).
    pub exact_curve: Vec<[f64; 2]>,
    /// Eq. (7)'s contact-line speed against the radius, `[r (m), x' (m/s)]`, down to the
    /// bang radius.
    pub eq7_curve: Vec<[f64; 2]>,
}

/// Points of [`Approach`]'s curves, spaced evenly in log r.
const APPROACH_POINTS: u32 = 96;

impl Approach {
    /// The references' `x'(r)` from R down to the bang radius, for the approach plot.
    pub(crate) fn curves(&mut self, scene: &Scene, refs: &References) {
        let big_r = scene.tape.outer_radius_m;
        let r_end = scene.stop.bang_radius_m;
        let radii = (0..=APPROACH_POINTS)
            .map(|i| big_r * (r_end / big_r).powf(f64::from(i) / f64::from(APPROACH_POINTS)));
        for r in radii {
            let f = 1.0 - (r / big_r).powi(2);
            let exact = refs.exact.xdot_at_psi(refs.exact.psi_at_fraction(f));
            if exact.is_finite() {
                self.exact_curve.push([r, exact]);
            }
            let eq7 = refs.continuum.state_at_radius(r, 0.0).xdot_m_s;
            if eq7.is_finite() {
                self.eq7_curve.push([r, eq7]);
            }
        }
    }
}

/// One of the paper's rivals for the scene's case at the run's milestones: the theory's
/// verdict, computed once with the run's references and carried to the tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RivalTimes {
    /// Short column label, e.g. `eq.72 A11`.
    pub label: String,
    /// What it is, with the equation numbers and ERRATA ids.
    pub description: String,
    /// The reference the simulation must converge to.
    pub valid: bool,
    /// Laid fraction at which this motion stops, if it does (left out if it does not).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stall_fraction: Option<f64>,
    /// Its time to each milestone's laid fraction (s), in the milestones' order; `None`
    /// where it never gets there.
    pub t_s: Vec<Option<f64>>,
}

/// Everything a run produced, for JSON and the summary.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunReport {
    /// The validated scene.
    pub scene: Scene,
    /// Links of the tape.
    pub links: usize,
    /// Engine steps taken.
    pub steps: u64,
    /// Wall time of the engine steps alone (s).
    pub wall_time_s: f64,
    /// Wall time of the steps of the rolling phase, the unroll up to the bang (s).
    pub wall_time_rolling_s: f64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Why the run stopped.
    pub stop: StopReason,
    /// The guards' bounds the run was held to.
    pub bounds: Bounds,
    /// Largest rise of the total energy above E0 over the run, over the energy scale
    /// ([`Ledger::energy_scale_j`]; 0 if it never rose).
    pub max_energy_rise_rel: f64,
    /// Fastest spin of any body over the run (rad/s).
    pub max_spin_rad_s: f64,
    /// Where the references stop applying (slip, bunching, lift-off, r ~ b, ...).
    pub reference_limits: Vec<ReferenceLimit>,
    /// Milestones at 0.75R, 0.5R, 0.25R, 0.1R and 2b (a spool: at laid fractions 0.25 to 0.9).
    pub milestones: Vec<Milestone>,
    /// The paper's rivals for the case, timed at the milestones.
    pub rivals: Vec<RivalTimes>,
    /// The energy ledger.
    pub ledger: Ledger,
    /// The approach to the bang: the peak contact-line speed.
    pub approach: Approach,
    /// The final bang's observables, if it began.
    pub bang: Option<BangReport>,
    /// Laid fraction from which the exact-geometry model needs a floor that pulls.
    pub geo_hop_fraction: Option<f64>,
    /// Largest joint separation seen (m).
    pub max_joint_gap_m: f64,
    /// Deepest floor penetration seen (m).
    pub max_penetration_m: f64,
    /// Deepest two layers of the tape overlapped at the end of a step (m): pieces not
    /// joined to each other, or a piece and the laid tape.
    #[serde(default)]
    pub max_overlap_m: f64,
}
