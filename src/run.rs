//! The run loop: steps the contact-resolved model, puts the analytic references beside it,
//! and feeds samples to observers; it builds the [`RunReport`]. It times only the model's
//! step, and it never names a file format (outputs are [`Observer`]s).

pub mod force_window;
pub mod frame;
pub mod guard;
pub mod stop;

use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::Serialize;

use crate::model::{BangEnd, EnergyLedger, Model, Observation, Phase};
use crate::run::force_window::{ForceWindow, WindowMean};
use crate::run::frame::{Event, Frame, GhostDisc, GhostSpiral};
use crate::run::guard::{Applicability, Bounds, Guard, ReferenceLimit};
use crate::run::stop::StopReason;
use crate::scene::Scene;
use crate::theory::References;

/// One row of output: the simulation and its references at the same instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Simulated time (s).
    pub t_s: f64,
    /// Mass on the floor over the total mass.
    pub laid_fraction: f64,
    /// Continuum-equivalent coil radius `R sqrt(1 - laid_fraction)` (m).
    pub r_m: f64,
    /// Contact-line position (m).
    pub x_m: f64,
    /// Contact-line speed (m/s), from the change of `x_m` over the last step.
    pub xdot_m_s: f64,
    /// Clockwise spin of the coil (rad/s).
    pub omega_rad_s: f64,
    /// Kinetic energy of everything that moves (J).
    pub kinetic_j: f64,
    /// Potential energy of the whole tape above the floor (J).
    pub potential_j: f64,
    /// Energy dissipated so far, `E0 - kinetic - potential` (J).
    pub dissipated_j: f64,
    /// Floor normal force on everything that moves (the coil and the laid links not yet
    /// frozen), its contact impulses summed over the sample interval over the interval (N).
    pub normal_n: f64,
    /// Floor horizontal force on everything that moves, +x positive, likewise (N).
    pub friction_n: f64,
    /// Loss inside engine steps while rolling (J).
    pub lost_step_j: f64,
    /// Loss at detach events (J).
    pub lost_detach_j: f64,
    /// Kinetic energy discarded by freezing laid links while rolling (J).
    pub lost_freeze_j: f64,
    /// Loss since the final bang began (J).
    pub lost_bang_j: f64,
    /// Final bang: dissipated against the floor's normal impulses so far (J).
    pub bang_floor_normal_j: f64,
    /// Final bang: dissipated against the floor's friction impulses so far (J).
    pub bang_floor_friction_j: f64,
    /// Final bang: dissipated against the joint impulses so far, numerical (J).
    pub bang_joints_j: f64,
    /// Final bang: kinetic energy the model discarded so far, joining the links into pieces
    /// at the release and freezing pieces at rest (J).
    pub bang_freeze_j: f64,
    /// Final bang: dissipated but not explained by the parts above, numerical (J).
    pub bang_residual_j: f64,
    /// Eq. (7): coil radius at this time (m).
    pub r_ref_m: f64,
    /// Eq. (7): contact position (m).
    pub x_ref_m: f64,
    /// Eq. (7): contact-line speed (m/s).
    pub xdot_ref_m_s: f64,
    /// Eq. (7): kinetic energy (J).
    pub kinetic_ref_j: f64,
    /// Eq. (9), exact form (ERRATA A4): floor normal force on the coil (N).
    pub normal_ref_n: f64,
    /// Eq. (11): horizontal force on the coil (N).
    pub friction_ref_n: f64,
    /// Exact-geometry model: equivalent radius (m).
    pub r_geo_m: f64,
    /// Exact-geometry model: contact position (m).
    pub x_geo_m: f64,
    /// Exact-geometry model: contact-line speed (m/s).
    pub xdot_geo_m_s: f64,
    /// Exact-geometry model: kinetic energy (J).
    pub kinetic_geo_j: f64,
    /// Eq. (17): coil radius (m).
    pub r_ft_m: f64,
    /// The scene's valid reference (see `rivals`): laid fraction at this time, `NaN` where
    /// it has none or past its end.
    pub laid_fraction_ref: f64,
    /// Spools: angle unrolled, `theta = f l / r` (rad); `NaN` for a solid coil.
    pub theta_rad: f64,
    /// Spools: the valid reference's `theta` at this time (rad).
    pub theta_ref_rad: f64,
    /// Total upward force on the moving part (the coil and the link hanging from it), from
    /// its momentum balance summed over the sample interval, `dP_y/dt + m g cos(a)` (N);
    /// `NaN` once the coil is released.
    pub n_tot_n: f64,
    /// Total horizontal force on the moving part, `dP_x/dt - m g sin(a)`, +x positive (N).
    pub f_tot_n: f64,
    /// The floor's upward force on the coil, its contact impulses over the interval (N).
    pub n_floor_n: f64,
    /// The floor's horizontal force on the coil, `F` of sec. 2.2, +x positive (N).
    pub f_floor_n: f64,
    /// The laid tape's upward force on the moving part, through its end: `n_tot - n_floor`
    /// (N).
    pub n_int_n: f64,
    /// The laid tape's horizontal force on the moving part, `F_int` of sec. 2.2:
    /// `f_tot - f_floor` (N).
    pub f_int_n: f64,
    /// Exact-geometry model at the simulation's laid fraction: `N_tot` from the momentum of
    /// the rolling spiral (N).
    pub n_tot_geo_n: f64,
    /// Exact-geometry model: `F_tot` from the momentum of the rolling spiral (N).
    pub f_tot_geo_n: f64,
    /// Exact-geometry model: the floor's horizontal force on the spiral, `F` (N).
    pub f_floor_geo_n: f64,
    /// Exact-geometry model: the laid tape's horizontal force on the spiral, `F_int` (N).
    pub f_int_geo_n: f64,
    /// Angular momentum of the moving part about the origin (the laid tape's outer end, on
    /// the contact plane) over the last step, from how far it moved, counter-clockwise
    /// (kg m^2/s).
    pub l_o: f64,
    /// Eq. (14) at the simulation's r and r' (from x' by constraint (1)): the coil as a disc
    /// (kg m^2/s).
    pub l_o_eq14: f64,
    /// The exact-geometry model's `L_O` at the simulation's laid fraction (kg m^2/s).
    pub l_o_geo: f64,
    /// Rate of change of the moving part's `L_O` over the force window, from the velocities
    /// the engine reports after each step (N m).
    pub dl_o_dt_n_m: f64,
    /// Torque about the origin of every external force on the moving part, gravity, the
    /// floor and the laid tape's pull, at the points where they act (N m).
    pub tau_o_n_m: f64,
    /// Eq. (16)'s placement of the same forces: gravity and the vertical forces at the
    /// contact line, the horizontal ones in the floor's plane (N m).
    pub tau_o_eq16_n_m: f64,
    /// What eq. (16) misses of gravity's torque: the spiral's centre of mass is not over the
    /// contact line (N m).
    pub tau_offcentre_n_m: f64,
    /// The case's analytic `N_tot` at the simulation's laid fraction (see `forces`) (N).
    pub n_tot_ref_n: f64,
    /// The case's analytic `F_tot` at the simulation's laid fraction (N).
    pub f_tot_ref_n: f64,
    /// Bodies in the engine.
    pub active_bodies: usize,
    /// Largest joint separation (m).
    pub max_joint_gap_m: f64,
    /// Deepest floor penetration (m).
    pub max_penetration_m: f64,
}

/// One milestone: the coil at a given continuum-equivalent radius.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Milestone {
    /// Label, e.g. `0.5R` or `2b`.
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
    /// Simulation energy dissipated so far (J).
    pub dissipated_j: Option<f64>,
}

/// Where the energy went over the whole run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
}

/// The approach to the bang: how far the contact line's speed diverged before the coil was
/// released (eq. 7's x' ~ 1/r as r -> 0).
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    fn curves(&mut self, scene: &Scene, refs: &References) {
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

/// Everything a run produced, for JSON and the summary.
#[derive(Debug, Clone, Serialize)]
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
}

/// An output fed by the run loop.
pub trait Observer {
    /// Called once before the first step.
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()>;
    /// Called for every sample.
    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()>;
    /// Called once with the final report.
    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()>;
    /// Whether this observer draws frames; frames are built only if one does (default:
    /// no).
    fn wants_frames(&self) -> bool {
        false
    }
    /// Called `output.scene_rate_hz` times per simulated second with the geometry, and
    /// at the first and last step, if [`Observer::wants_frames`] (default: ignored).
    fn observe_frame(&mut self, _frame: &Frame) -> anyhow::Result<()> {
        Ok(())
    }
    /// Called for every event, in time order (default: ignored).
    fn observe_event(&mut self, _event: &Event) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Laid fractions of the milestones of a spool (a scene with a core).
pub const SPOOL_FRACTIONS: [f64; 4] = [0.25, 0.5, 0.75, 0.9];

/// The milestone radii of a scene with their labels.
pub fn milestone_radii(scene: &Scene) -> Vec<(String, f64)> {
    let big_r = scene.tape.outer_radius_m;
    if scene.tape.core_radius_m > 0.0 {
        // On a spool the radius hardly changes: milestones at laid fractions f, given as
        // the continuum-equivalent radius R sqrt(1 - f) the loop converts back.
        return SPOOL_FRACTIONS
            .iter()
            .map(|f| (format!("f={f}"), big_r * (1.0 - f).sqrt()))
            .collect();
    }
    let mut v: Vec<(String, f64)> = [0.75, 0.5, 0.25, 0.1]
        .iter()
        .map(|k| (format!("{k}R"), k * big_r))
        .collect();
    v.push(("2b".into(), 2.0 * scene.tape.thickness_m));
    v
}

struct MilestoneHit {
    t_s: f64,
    xdot: f64,
    kinetic: f64,
    potential: f64,
}

/// Runs a scene to its end and returns the report; every sample goes to the observers.
pub fn run(scene: &Scene, observers: &mut [&mut dyn Observer]) -> anyhow::Result<RunReport> {
    run_until(scene, observers, &AtomicBool::new(false))
}

/// Like [`run`], but stops early, with every observer finalised, once `stop` is set (e.g.
/// by a Ctrl-C handler); the flag is polled after every step.
pub fn run_until(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    stop: &AtomicBool,
) -> anyhow::Result<RunReport> {
    let refs = References::new(scene);
    let mut model = Model::new(scene);
    for o in observers.iter_mut() {
        o.observe_init(scene)?;
    }
    let initial = model.observe();
    let e0 = initial.kinetic_j + initial.potential_j;
    let radii = milestone_radii(scene);
    let big_r = scene.tape.outer_radius_m;
    let fractions: Vec<f64> = radii
        .iter()
        .map(|(_, r)| 1.0 - (r / big_r).powi(2))
        .collect();
    let mut hits: Vec<Option<MilestoneHit>> = radii.iter().map(|_| None).collect();
    let mut guard = Guard::new(scene, e0);
    let mut limits = Applicability::new(scene, &refs.exact);
    let mut approach = Approach {
        peak_xdot_m_s: scene.push_speed_m_s,
        peak_r_m: big_r,
        peak_xdot_geo_m_s: (!refs.exact.is_sliding()).then_some(scene.push_speed_m_s),
        exact_curve: Vec::new(),
        eq7_curve: Vec::new(),
    };
    let mut prev_logged = false;

    let mut wall = 0.0;
    let mut steps = 0u64;
    let mut prev: Option<Observation> = None;
    let mut xdot = scene.push_speed_m_s;
    let mut next_sample = 0.0;
    let mut bang: Option<(f64, Observation)> = None;
    let mut wall_rolling = None;
    let mut max_gap: f64 = 0.0;
    let mut max_pen: f64 = 0.0;
    // The impulses on the tape, for each sample's mean forces.
    let mut window = ForceWindow::default();
    let frame_interval = if scene.scene_rate_hz > 0.0 && observers.iter().any(|o| o.wants_frames())
    {
        1.0 / scene.scene_rate_hz
    } else {
        f64::INFINITY
    };
    let mut next_frame = frame_interval;
    if frame_interval.is_finite() {
        let frame = make_frame(scene, &model, &refs, 0.0, 0.0);
        for o in observers.iter_mut() {
            o.observe_frame(&frame)?;
        }
    }
    if let Some(f) = refs.exact.hop_onset_fraction() {
        let event = Event::Warning {
            t_s: 0.0,
            message: format!(
                "the exact-geometry model needs a floor that pulls (N < 0) from laid fraction {f:.4} on"
            ),
        };
        for o in observers.iter_mut() {
            o.observe_event(&event)?;
        }
    }
    let stop_reason;
    loop {
        let start = Instant::now();
        let obs = model.step();
        wall += start.elapsed().as_secs_f64();
        steps += 1;
        let detached = prev.map_or(0, |p| p.detached) < obs.detached;
        window.push(
            obs.t_s,
            obs.dt_s,
            &obs.impulses,
            obs.laid_fraction,
            detached,
        );
        let health = model.health();
        let tripped = guard.check(&obs, &health);
        if let Some(reason) = tripped.as_ref()
            && !crate::run::guard::is_finite(&obs, &health)
        {
            // Keep the last finite step as the end of the run, logged: no NaN reaches a
            // table.
            if let (Some(p), false) = (prev, prev_logged) {
                let sample = make_sample(&p, xdot, e0, &refs);
                for o in observers.iter_mut() {
                    o.observe_sample(&sample)?;
                }
            }
            stop_reason = StopReason::Guard(reason.clone());
            break;
        }
        max_gap = max_gap.max(obs.max_joint_gap_m);
        max_pen = max_pen.max(obs.max_penetration_m);
        let mut events = Vec::new();
        let (detached_before, detach_j_before) =
            prev.map_or((0, 0.0), |p| (p.detached, p.ledger.detach_j));
        if obs.detached > detached_before && obs.phase == Phase::Rolling {
            events.push(Event::Detach {
                t_s: obs.t_s,
                first_link: detached_before,
                links: obs.detached - detached_before,
                detached: obs.detached,
                energy_lost_j: obs.ledger.detach_j - detach_j_before,
            });
        }
        if let Some(p) = prev {
            if obs.phase == Phase::Rolling && obs.dt_s > 0.0 {
                xdot = (obs.x_m - p.x_m) / obs.dt_s;
            }
            for (k, &f) in fractions.iter().enumerate() {
                if hits[k].is_none() && p.laid_fraction < f && obs.laid_fraction >= f {
                    let s = (f - p.laid_fraction) / (obs.laid_fraction - p.laid_fraction);
                    hits[k] = Some(MilestoneHit {
                        t_s: p.t_s + s * (obs.t_s - p.t_s),
                        xdot,
                        kinetic: obs.kinetic_j,
                        potential: obs.potential_j,
                    });
                }
            }
            if p.phase == Phase::Rolling && obs.phase != Phase::Rolling {
                bang = Some((p.t_s, p));
                wall_rolling = Some(wall);
                events.push(Event::BangStart {
                    t_s: p.t_s,
                    kinetic_j: p.kinetic_j,
                    available_j: p.kinetic_j + p.potential_j - model.flat_potential_j(),
                });
            }
        }
        limits.observe(&obs, &health, xdot);
        if obs.phase == Phase::Rolling && prev.is_some() && xdot > approach.peak_xdot_m_s {
            approach.peak_xdot_m_s = xdot;
            approach.peak_r_m = big_r * (1.0 - obs.laid_fraction).max(0.0).sqrt();
            approach.peak_xdot_geo_m_s =
                (!refs.exact.is_sliding()).then(|| refs.exact.xdot_at_psi(obs.psi_low));
        }
        let done = obs.phase == Phase::Done;
        let timed_out = obs.t_s >= scene.stop.max_time_s;
        let interrupted = stop.load(Ordering::Relaxed);
        let ending = ending(scene, &obs, tripped, timed_out, interrupted);
        let last_step = ending.is_some();
        if done {
            events.push(Event::BangEnd {
                t_s: obs.t_s,
                started_s: bang.map_or(obs.t_s, |(t, _)| t),
                dissipated_j: obs.ledger.bang_j,
                ended_by: obs.bang.end.unwrap_or(BangEnd::Cap),
            });
        }
        if let Some(message) = ending.as_ref().and_then(early_end_warning) {
            events.push(Event::Warning {
                t_s: obs.t_s,
                message,
            });
        }
        for event in &events {
            for o in observers.iter_mut() {
                o.observe_event(event)?;
            }
        }
        let released =
            obs.phase != Phase::Rolling && prev.is_some_and(|p| p.phase == Phase::Rolling);
        prev_logged = obs.t_s >= next_sample || last_step || released;
        if prev_logged {
            let mut sample = make_sample(&obs, xdot, e0, &refs);
            if let Some(mean) = window.sample(obs.phase == Phase::Rolling) {
                set_forces(&mut sample, &mean, obs.phase == Phase::Rolling, &refs);
            }
            for o in observers.iter_mut() {
                o.observe_sample(&sample)?;
            }
            next_sample = obs.t_s + scene.sample_interval_s;
            // The bang is over in a few milliseconds of its start: sample it at times since
            // the release growing geometrically from one step, up to the sample interval.
            if let Some((t_bang, _)) = bang {
                let since = obs.t_s - t_bang;
                next_sample = next_sample.min(t_bang + since * BANG_SAMPLE_GROWTH);
            }
        }
        if obs.t_s >= next_frame || (last_step && frame_interval.is_finite()) {
            let frame = make_frame(scene, &model, &refs, obs.t_s, obs.x_m);
            for o in observers.iter_mut() {
                o.observe_frame(&frame)?;
            }
            next_frame += frame_interval * ((obs.t_s - next_frame) / frame_interval + 1.0).floor();
        }
        prev = Some(obs);
        if let Some(end) = ending {
            stop_reason = end;
            break;
        }
    }
    // A run stopped at its first step ends where it began.
    let last = prev.unwrap_or(initial);
    let flat = model.flat_potential_j();
    let (bang_time, before, kinetic_into, available) = match bang {
        Some((t, o)) => (
            Some(t),
            o.ledger,
            last.bang.kinetic_in_j,
            o.kinetic_j + o.potential_j - flat,
        ),
        None => (
            None,
            last.ledger,
            last.kinetic_j,
            last.kinetic_j + last.potential_j - flat,
        ),
    };
    let mgr_j = scene.tape.mass_kg * scene.g_m_s2 * big_r;
    let ledger = Ledger {
        e0_j: e0,
        mgr_j,
        energy_scale_j: e0.abs().max(mgr_j).max(kinetic_into),
        flat_potential_j: flat,
        before_bang: before,
        lost_before_bang_j: before.total_j(),
        kinetic_into_bang_j: kinetic_into,
        available_at_bang_j: available,
        dissipated_by_bang_j: last.ledger.bang_j,
        bang: last.bang.ledger,
        left_j: last.kinetic_j + last.potential_j - flat,
        bang_time_s: bang_time,
    };
    let milestones = radii
        .iter()
        .zip(fractions.iter())
        .zip(hits.iter())
        .map(|(((label, r), &f), hit)| {
            let t_geo = refs.exact.time_at_fraction(f);
            let t_eq7 = refs.continuum.time_at_radius(*r);
            let t_sim = hit.as_ref().map(|h| h.t_s);
            let rel = |a: Option<f64>, b: Option<f64>| a.zip(b).map(|(a, b)| a / b - 1.0);
            Milestone {
                label: label.clone(),
                r_m: *r,
                laid_fraction: f,
                t_sim_s: t_sim,
                t_geo_s: t_geo,
                t_eq7_s: t_eq7,
                t_eq17_s: Some(refs.force_torque.time_at_radius(*r)),
                err_vs_geo: rel(t_sim, t_geo),
                err_vs_eq7: rel(t_sim, t_eq7),
                geo_vs_eq7: rel(t_geo, t_eq7),
                xdot_sim_m_s: hit.as_ref().map(|h| h.xdot),
                xdot_eq7_m_s: t_eq7.map(|_| refs.continuum.state_at_radius(*r, 0.0).xdot_m_s),
                kinetic_j: hit.as_ref().map(|h| h.kinetic),
                potential_j: hit.as_ref().map(|h| h.potential),
                dissipated_j: hit.as_ref().map(|h| e0 - h.kinetic - h.potential),
            }
        })
        .collect();
    let report = RunReport {
        scene: scene.clone(),
        links: model.link_count(),
        steps,
        wall_time_s: wall,
        wall_time_rolling_s: wall_rolling.unwrap_or(wall),
        sim_time_s: last.t_s,
        stop: stop_reason,
        bounds: guard.bounds,
        max_energy_rise_rel: guard.max_energy_rise_j / ledger.energy_scale_j,
        max_spin_rad_s: guard.max_spin_rad_s,
        reference_limits: limits.finish(),
        milestones,
        ledger,
        approach: {
            approach.curves(scene, &refs);
            approach
        },
        bang: bang.map(|_| BangReport {
            kinetic_in_j: last.bang.kinetic_in_j,
            top_speed_m_s: last.bang.top_speed_m_s,
            duration_s: last.t_s - last.bang.started_s,
            peak_floor_force_n: last.bang.peak_floor_force_n,
            floor_impulse_n_s: last.bang.floor_impulse_n_s,
            end_x_m: model.tape_end_x_m(),
            laid_length_m: model.tape_length_m(),
            still_moving_j: last.kinetic_j,
            ended_by: last.bang.end,
        }),
        geo_hop_fraction: refs.exact.hop_onset_fraction(),
        max_joint_gap_m: max_gap,
        max_penetration_m: max_pen,
    };
    for o in observers.iter_mut() {
        o.observe_final(&report)?;
    }
    Ok(report)
}

/// In the final bang, each sample's time since the release is at least this factor times
/// the last one's (and at most one `output.sample_interval_s` later).
const BANG_SAMPLE_GROWTH: f64 = 1.1;

/// Points per turn of the exact-geometry ghost spiral.
const GHOST_POINTS_PER_TURN: u32 = 32;

/// How this step ends the run, if it does: a guard first, then the bang's end, the time
/// limit and an interruption.
fn ending(
    scene: &Scene,
    obs: &Observation,
    tripped: Option<crate::run::stop::GuardTrip>,
    timed_out: bool,
    interrupted: bool,
) -> Option<StopReason> {
    if let Some(trip) = tripped {
        return Some(StopReason::Guard(trip));
    }
    if obs.phase == Phase::Done {
        let still_moving = obs.kinetic_j / obs.bang.kinetic_in_j.max(f64::MIN_POSITIVE);
        return Some(match obs.bang.end {
            Some(BangEnd::Rest) => StopReason::AtRest {
                t_s: obs.t_s,
                still_moving,
                rest_fraction: scene.stop.rest_fraction,
            },
            _ => StopReason::BangCap {
                t_s: obs.t_s,
                still_moving,
                bang_cap_s: scene.stop.bang_cap_s,
            },
        });
    }
    if timed_out {
        return Some(StopReason::MaxTime {
            t_s: obs.t_s,
            max_time_s: scene.stop.max_time_s,
        });
    }
    interrupted.then_some(StopReason::Interrupted { t_s: obs.t_s })
}

/// The warning event of a run that ends before its bang does.
fn early_end_warning(end: &StopReason) -> Option<String> {
    match end {
        StopReason::Guard(trip) => Some(format!("stopped by a guard: {trip}")),
        StopReason::MaxTime { max_time_s, .. } => Some(format!(
            "stop.max_time_s = {max_time_s} reached before the bang ended"
        )),
        StopReason::Interrupted { .. } => Some("interrupted: the run stopped early".into()),
        StopReason::AtRest { .. } | StopReason::BangCap { .. } => None,
    }
}

fn make_frame(
    scene: &Scene,
    model: &Model,
    refs: &References,
    t_s: f64,
    contact_x_m: f64,
) -> Frame {
    let (off_coil_m, on_coil_m) = model.link_nodes();
    let b = scene.tape.thickness_m;
    Frame {
        t_s,
        contact_x_m,
        off_coil_m,
        on_coil_m,
        eq7: GhostDisc::at(&refs.continuum, b, t_s),
        exact: GhostSpiral::at(&refs.exact, b, t_s, GHOST_POINTS_PER_TURN),
    }
}

/// A sample's forces: the mean over its window (see [`ForceWindow`]) of the floor's on
/// everything that moves always; while the coil rolls, those on the moving part, with the
/// references at the window's mean laid fraction.
fn set_forces(sample: &mut Sample, mean: &WindowMean, rolling: bool, refs: &References) {
    let f = &mean.forces;
    sample.normal_n = f.floor_on_moving[1];
    sample.friction_n = f.floor_on_moving[0];
    if !rolling {
        return;
    }
    let laid = f.laid();
    sample.n_tot_n = f.total[1];
    sample.f_tot_n = f.total[0];
    sample.n_floor_n = f.floor_on_coil[1];
    sample.f_floor_n = f.floor_on_coil[0];
    sample.n_int_n = laid[1];
    sample.f_int_n = laid[0];
    let a = &f.about_origin;
    sample.dl_o_dt_n_m = a.change;
    sample.tau_o_n_m = a.gravity + a.floor + a.laid;
    sample.tau_o_eq16_n_m = a.gravity_at_contact_line + a.others_at_contact_line;
    sample.tau_offcentre_n_m = a.gravity - a.gravity_at_contact_line;
    let nan = f64::NAN;
    let paper = refs.forces.as_ref().and_then(|r| r(mean.laid_fraction));
    sample.n_tot_ref_n = paper.map_or(nan, |p| p.0);
    sample.f_tot_ref_n = paper.map_or(nan, |p| p.1);
    let psi = refs.exact.psi_at_fraction(mean.laid_fraction);
    if let Some(geo) = refs.floor_grip.and_then(|mu| refs.exact.forces(psi, mu)) {
        sample.n_tot_geo_n = geo.n_tot_n;
        sample.f_tot_geo_n = geo.f_tot_n;
        sample.f_floor_geo_n = geo.f_floor_n;
        sample.f_int_geo_n = geo.f_int_n;
    }
}

/// Eq. (14), `L_O = M pi r^2 r' (R^2 + 2 r^2) / (b R^2)`, counter-clockwise, at the laid
/// fraction `f` and contact-line speed `x'`, with `r' = -b x' / (2 pi r)` from constraint
/// (1), `x = pi (R^2 - r^2) / b` (kg m^2/s).
fn eq14_angular_momentum(refs: &References, f: f64, xdot: f64) -> f64 {
    let p = refs.continuum.params();
    let (big_r, b, m) = (p.outer_radius_m, p.thickness_m, p.mass_kg);
    let r = big_r * (1.0 - f).max(0.0).sqrt();
    let rdot = -b * xdot / (2.0 * PI * r);
    m * PI * r * r * rdot * (big_r * big_r + 2.0 * r * r) / (b * big_r * big_r)
}

fn make_sample(obs: &Observation, xdot: f64, e0: f64, refs: &References) -> Sample {
    let nan = f64::NAN;
    let c = refs.continuum.state_at_time(obs.t_s);
    let g = refs.exact.state_at_time(obs.t_s);
    let r_ref = c.map_or(nan, |s| s.r_m);
    let f_ref = refs
        .valid
        .as_ref()
        .and_then(|r| r.fraction_at_time(obs.t_s))
        .unwrap_or(nan);
    let forces = refs.forces.as_ref().and_then(|f| f(obs.laid_fraction));
    let rolling = obs.phase == Phase::Rolling;
    let l_o_eq14 = match (rolling, refs.theta_per_fraction) {
        (true, None) => eq14_angular_momentum(refs, obs.laid_fraction, xdot),
        _ => nan,
    };
    Sample {
        t_s: obs.t_s,
        laid_fraction: obs.laid_fraction,
        r_m: (1.0 - obs.laid_fraction).max(0.0).sqrt() * refs.continuum.outer_radius_m(),
        x_m: obs.x_m,
        xdot_m_s: xdot,
        omega_rad_s: obs.omega_rad_s,
        kinetic_j: obs.kinetic_j,
        potential_j: obs.potential_j,
        dissipated_j: e0 - obs.kinetic_j - obs.potential_j,
        normal_n: obs.normal_n,
        friction_n: obs.friction_n,
        lost_step_j: obs.ledger.step_j,
        lost_detach_j: obs.ledger.detach_j,
        lost_freeze_j: obs.ledger.freeze_j,
        lost_bang_j: obs.ledger.bang_j,
        bang_floor_normal_j: obs.bang.ledger.floor_normal_j,
        bang_floor_friction_j: obs.bang.ledger.floor_friction_j,
        bang_joints_j: obs.bang.ledger.joints_j,
        bang_freeze_j: obs.bang.ledger.freeze_j,
        bang_residual_j: obs.bang.ledger.residual_j,
        r_ref_m: r_ref,
        x_ref_m: c.map_or(nan, |s| s.x_m),
        xdot_ref_m_s: c.map_or(nan, |s| s.xdot_m_s),
        kinetic_ref_j: c.map_or(nan, |s| s.kinetic_j),
        normal_ref_n: c.map_or(nan, |s| refs.continuum.normal_force_n(s.r_m)),
        friction_ref_n: c.map_or(nan, |s| refs.continuum.horizontal_force_n(s.r_m)),
        r_geo_m: g.map_or(nan, |s| s.r_m),
        x_geo_m: g.map_or(nan, |s| s.x_m),
        xdot_geo_m_s: g.map_or(nan, |s| s.xdot_m_s),
        kinetic_geo_j: g.map_or(nan, |s| s.kinetic_j),
        r_ft_m: refs.force_torque.radius_at_time(obs.t_s).unwrap_or(nan),
        laid_fraction_ref: f_ref,
        theta_rad: refs
            .theta_per_fraction
            .map_or(nan, |k| k * obs.laid_fraction),
        theta_ref_rad: refs.theta_per_fraction.map_or(nan, |k| k * f_ref),
        n_tot_n: nan,
        f_tot_n: nan,
        n_floor_n: nan,
        f_floor_n: nan,
        n_int_n: nan,
        f_int_n: nan,
        n_tot_geo_n: nan,
        f_tot_geo_n: nan,
        f_floor_geo_n: nan,
        f_int_geo_n: nan,
        l_o: if rolling { obs.angular_momentum_o } else { nan },
        l_o_eq14,
        l_o_geo: if rolling && refs.floor_grip.is_some() {
            refs.exact
                .angular_momentum_o(refs.exact.psi_at_fraction(obs.laid_fraction))
                .unwrap_or(nan)
        } else {
            nan
        },
        dl_o_dt_n_m: nan,
        tau_o_n_m: nan,
        tau_o_eq16_n_m: nan,
        tau_offcentre_n_m: nan,
        n_tot_ref_n: forces.map_or(nan, |f| f.0),
        f_tot_ref_n: forces.map_or(nan, |f| f.1),
        active_bodies: obs.active_bodies,
        max_joint_gap_m: obs.max_joint_gap_m,
        max_penetration_m: obs.max_penetration_m,
    }
}
