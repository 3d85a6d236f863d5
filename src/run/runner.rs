//! The loop's state between two steps, and what one step does with the model's
//! observation: the guards, the events, the milestones, the approach, a sample and a frame
//! for the observers, and at the end the [`RunReport`]. Only the model's step is timed.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::model::{BangEnd, Model, Observation, Phase};
use crate::run::Observer;
use crate::run::force_window::ForceWindow;
use crate::run::frame::{Event, Frame, GhostDisc, GhostSpiral, SpiralGrid};
use crate::run::guard::GuardTrip;
use crate::run::guard::{self, Guard};
use crate::run::limits::Applicability;
use crate::run::milestones::Milestones;
use crate::run::report::{Approach, BangReport, Ledger, RunReport};
use crate::run::sample::SampleInputs;
use crate::run::stop::StopReason;
use crate::scene::Scene;
use crate::theory::References;

/// In the final bang, each sample's time since the release is at least this factor times
/// the last one's (and at most one `output.sample_interval_s` later).
const BANG_SAMPLE_GROWTH: f64 = 1.1;

/// The final bang is drawn at its own pace, by its steps (a step is drawn at its end:
/// frames are never interpolated). Its first [`BANG_DRAWN_STEPS`] steps are each drawn:
/// the bang's steps are shortest where its impacts are, at its start. After them a step is
/// drawn once the time since the release has grown by the factor [`bang_frame_growth`] since
/// the bang's last drawing, [`BANG_FRAMES_PER_DECADE`] a decade, or when a frame of
/// `output.scene_rate_hz` is due (those are all still drawn), and at the run's last step. At
/// the scene rate alone the bang's impacts, over in its first millisecond, would go undrawn.
/// (The samples' pace in the bang, `BANG_SAMPLE_GROWTH`, is separate.)
pub const BANG_DRAWN_STEPS: u32 = 200;

/// After the bang's first [`BANG_DRAWN_STEPS`] steps, its drawings a decade of the time since
/// the release: log pacing, so that its settling, a tenth of a second, is drawn as finely
/// in proportion as its start. Where the bang's steps grow the time since the release by more
/// than the factor [`bang_frame_growth`], every step is drawn.
pub const BANG_FRAMES_PER_DECADE: f64 = 100.0;

/// The factor by which the time since the release grows from one drawing of the bang to the
/// next after its first [`BANG_DRAWN_STEPS`] steps, `10^(1 / BANG_FRAMES_PER_DECADE)` (2.3 %).
pub fn bang_frame_growth() -> f64 {
    10f64.powf(BANG_FRAMES_PER_DECADE.recip())
}

/// Points per turn of the exact-geometry ghost spiral.
const GHOST_POINTS_PER_TURN: u32 = 32;

/// The loop's state: the model, its references, and what the run has seen so far.
pub(crate) struct Runner<'s> {
    scene: &'s Scene,
    refs: Arc<References>,
    model: Model,
    initial: Observation,
    e0: f64,
    milestones: Milestones,
    guard: Guard,
    limits: Applicability,
    approach: Approach,
    /// The impulses on the tape, for each sample's mean forces.
    window: ForceWindow,
    /// Wall time of the engine steps (s), and of those up to the bang.
    wall: f64,
    wall_rolling: Option<f64>,
    steps: u64,
    prev: Option<Observation>,
    /// Whether `prev` went out as a sample.
    prev_logged: bool,
    /// The contact-line speed, from the last rolling step (m/s).
    xdot: f64,
    next_sample: f64,
    /// The release: its time and the last rolling step.
    bang: Option<(f64, Observation)>,
    max_gap: f64,
    max_pen: f64,
    max_overlap: f64,
    frame_interval: f64,
    next_frame: f64,
    /// The bang's drawings so far, and the time since the release of its last one (s).
    bang_frames: (u32, f64),
    /// The exact model's spiral for its ghost, once frames are drawn.
    ghost_grid: Option<SpiralGrid>,
}

impl<'s> Runner<'s> {
    /// Builds the model and the references, and opens the observers with the first frame
    /// and the exact model's warning.
    pub(crate) fn new(
        scene: &'s Scene,
        refs: Arc<References>,
        observers: &mut [&mut dyn Observer],
    ) -> anyhow::Result<Self> {
        let mut model = Model::new(scene);
        for o in observers.iter_mut() {
            o.observe_init(scene)?;
            if o.makes_samples() {
                o.observe_references(&refs)?;
            }
        }
        let initial = model.observe();
        let e0 = initial.kinetic_j + initial.potential_j;
        let frame_interval =
            if scene.output.scene_rate_hz > 0.0 && observers.iter().any(|o| o.wants_frames()) {
                1.0 / scene.output.scene_rate_hz
            } else {
                f64::INFINITY
            };
        let ghost_grid = frame_interval
            .is_finite()
            .then(|| SpiralGrid::new(&refs.exact, GHOST_POINTS_PER_TURN));
        let runner = Self {
            scene,
            milestones: Milestones::new(scene),
            guard: Guard::new(scene, e0),
            limits: Applicability::new(scene, &refs.exact),
            approach: Approach {
                peak_xdot_m_s: scene.push.contact_speed_m_s,
                peak_r_m: scene.tape.outer_radius_m,
                peak_xdot_geo_m_s: (!refs.exact.is_sliding())
                    .then_some(scene.push.contact_speed_m_s),
                exact_curve: Vec::new(),
                eq7_curve: Vec::new(),
            },
            refs,
            model,
            initial,
            e0,
            window: ForceWindow::default(),
            wall: 0.0,
            wall_rolling: None,
            steps: 0,
            prev: None,
            prev_logged: false,
            xdot: scene.push.contact_speed_m_s,
            next_sample: 0.0,
            bang: None,
            max_gap: 0.0,
            max_pen: 0.0,
            max_overlap: 0.0,
            ghost_grid,
            frame_interval,
            next_frame: frame_interval,
            bang_frames: (0, 0.0),
        };
        if frame_interval.is_finite() {
            let frame = runner.frame(0.0, 0.0);
            for o in observers.iter_mut() {
                o.observe_frame(&frame)?;
            }
        }
        if let Some(f) = runner.refs.exact.hop_onset_fraction() {
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
        Ok(runner)
    }

    /// Takes one step and feeds it to the observers; returns why the run ends if it does.
    pub(crate) fn step(
        &mut self,
        observers: &mut [&mut dyn Observer],
        stop: &AtomicBool,
    ) -> anyhow::Result<Option<StopReason>> {
        let start = Instant::now();
        let obs = self.model.step();
        self.wall += start.elapsed().as_secs_f64();
        self.steps += 1;
        let detached = self.prev.map_or(0, |p| p.detached) < obs.detached;
        let impulses = &obs.impulses;
        self.window
            .push(obs.t_s, obs.dt_s, impulses, obs.laid_fraction, detached);
        let health = self.model.health();
        let tripped = self.guard.check(&obs, &health);
        if let Some(trip) = tripped.as_ref()
            && !guard::is_finite(&obs, &health)
        {
            // Keep the last finite step as the end of the run, logged: no NaN reaches a
            // table.
            if let (Some(p), false) = (self.prev, self.prev_logged) {
                let step = SampleInputs::new(&p, self.xdot, self.e0, None);
                self.send_sample(&step, observers)?;
            }
            return Ok(Some(StopReason::Guard(trip.clone())));
        }
        self.max_gap = self.max_gap.max(obs.max_joint_gap_m);
        self.max_pen = self.max_pen.max(obs.max_penetration_m);
        self.max_overlap = self.max_overlap.max(obs.max_overlap_m);
        let mut events = self.follow(&obs);
        self.limits.observe(&obs, &health, self.xdot);
        self.track_peak(&obs);
        let timed_out = obs.t_s >= self.scene.stop.max_time_s;
        let interrupted = stop.load(Ordering::Relaxed);
        let ending = ending(self.scene, &obs, tripped, timed_out, interrupted);
        if obs.phase == Phase::Done {
            events.push(Event::BangEnd {
                t_s: obs.t_s,
                started_s: self.bang.map_or(obs.t_s, |(t, _)| t),
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
        self.log(&obs, ending.is_some(), observers)?;
        self.prev = Some(obs);
        Ok(ending)
    }

    /// Follows the motion from the last step to `obs`: the contact-line speed, the
    /// milestones crossed and the release; returns the detach and release events.
    fn follow(&mut self, obs: &Observation) -> Vec<Event> {
        let mut events = Vec::new();
        let (detached_before, detach_j_before) = self
            .prev
            .map_or((0, 0.0), |p| (p.detached, p.ledger.detach_j));
        if obs.detached > detached_before && obs.phase == Phase::Rolling {
            events.push(Event::Detach {
                t_s: obs.t_s,
                first_link: detached_before,
                links: obs.detached - detached_before,
                detached: obs.detached,
                energy_lost_j: obs.ledger.detach_j - detach_j_before,
            });
        }
        let Some(p) = self.prev else {
            return events;
        };
        if obs.phase == Phase::Rolling && obs.dt_s > 0.0 {
            self.xdot = (obs.x_m - p.x_m) / obs.dt_s;
        }
        self.milestones.observe(&p, obs, self.xdot);
        if p.phase == Phase::Rolling && obs.phase != Phase::Rolling {
            self.bang = Some((p.t_s, p));
            self.wall_rolling = Some(self.wall);
            events.push(Event::BangStart {
                t_s: p.t_s,
                kinetic_j: p.kinetic_j,
                available_j: p.kinetic_j + p.potential_j - self.model.flat_potential_j(),
            });
        }
        events
    }

    /// The fastest contact line while rolling, with the exact model's speed there.
    fn track_peak(&mut self, obs: &Observation) {
        let a = &mut self.approach;
        if obs.phase == Phase::Rolling && self.prev.is_some() && self.xdot > a.peak_xdot_m_s {
            a.peak_xdot_m_s = self.xdot;
            a.peak_r_m = self.scene.tape.outer_radius_m * (1.0 - obs.laid_fraction).max(0.0).sqrt();
            a.peak_xdot_geo_m_s =
                (!self.refs.exact.is_sliding()).then(|| self.refs.exact.xdot_at_psi(obs.psi_low));
        }
    }

    /// Sends `obs` out as a sample when one is due (every `output.sample_interval_s`, at
    /// the release, at the last step; in the bang at geometrically growing times), and as
    /// a frame when one is due.
    fn log(
        &mut self,
        obs: &Observation,
        last_step: bool,
        observers: &mut [&mut dyn Observer],
    ) -> anyhow::Result<()> {
        let rolling = obs.phase == Phase::Rolling;
        let released = !rolling && self.prev.is_some_and(|p| p.phase == Phase::Rolling);
        self.prev_logged = obs.t_s >= self.next_sample || last_step || released;
        if self.prev_logged {
            // The window is read (and trimmed) at every sample, watched or not.
            let forces = self.window.sample(rolling).map(|mean| (mean, rolling));
            // A run nobody watches (a sweep's) makes no samples: the report does not need
            // them.
            if !observers.is_empty() {
                let step = SampleInputs::new(obs, self.xdot, self.e0, forces);
                self.send_sample(&step, observers)?;
            }
            self.next_sample = obs.t_s + self.scene.output.sample_interval_s;
            // The bang is over in a few milliseconds of its start: sample it at times since
            // the release growing geometrically from one step, up to the sample interval.
            if let Some((t_bang, _)) = self.bang {
                let since = obs.t_s - t_bang;
                self.next_sample = self.next_sample.min(t_bang + since * BANG_SAMPLE_GROWTH);
            }
        }
        let in_bang = self.bang_frame_due(obs.t_s);
        if obs.t_s >= self.next_frame || (last_step && self.frame_interval.is_finite()) || in_bang {
            let frame = self.frame(obs.t_s, obs.x_m);
            for o in observers.iter_mut() {
                o.observe_frame(&frame)?;
            }
            // Behind by less than one interval (a frame of the bang's drawn early): the next
            // ordinary frame stays due when it was.
            let behind = ((obs.t_s - self.next_frame) / self.frame_interval + 1.0).floor();
            self.next_frame += self.frame_interval * behind.max(0.0);
            if let Some((t_bang, _)) = self.bang {
                self.bang_frames = (self.bang_frames.0 + 1, obs.t_s - t_bang);
            }
        }
        Ok(())
    }

    /// Whether a step at `t_s` is a frame of the bang's own (see [`BANG_DRAWN_STEPS`]): frames
    /// are drawn, the bang has begun, and this is one of its first steps or the time since the
    /// release has grown by [`bang_frame_growth`] since its last drawing.
    fn bang_frame_due(&self, t_s: f64) -> bool {
        let Some((t_bang, _)) = self.bang else {
            return false;
        };
        let (drawn, last) = self.bang_frames;
        self.frame_interval.is_finite()
            && (drawn < BANG_DRAWN_STEPS || t_s - t_bang >= last * bang_frame_growth())
    }

    /// Hands a sample to the observers: what it is made from to those that make their own,
    /// the sample, made once, to the others.
    fn send_sample(
        &self,
        step: &SampleInputs,
        observers: &mut [&mut dyn Observer],
    ) -> anyhow::Result<()> {
        let mut made = None;
        for o in observers.iter_mut() {
            if o.makes_samples() {
                o.observe_step(step)?;
            } else {
                o.observe_sample(made.get_or_insert_with(|| step.sample(&self.refs)))?;
            }
        }
        Ok(())
    }

    fn frame(&self, t_s: f64, contact_x_m: f64) -> Frame {
        let b = self.scene.tape.thickness_m;
        Frame {
            t_s,
            contact_x_m,
            off_coil_m: self.model.off_coil_nodes(),
            on_coil: self.model.wound_nodes().unwrap_or_default(),
            eq7: GhostDisc::at(&self.refs.continuum, b, t_s),
            exact: self
                .ghost_grid
                .as_ref()
                .and_then(|grid| GhostSpiral::at(&self.refs.exact, grid, b, t_s)),
        }
    }

    /// The report of the run, which ended for `stop`; the observers get it last.
    pub(crate) fn finish(
        mut self,
        stop: StopReason,
        observers: &mut [&mut dyn Observer],
    ) -> anyhow::Result<RunReport> {
        // A run stopped at its first step ends where it began.
        let last = self.prev.unwrap_or(self.initial);
        let ledger = self.ledger(&last);
        self.approach.curves(self.scene, &self.refs);
        let report = RunReport {
            scene: self.scene.clone(),
            links: self.model.link_count(),
            steps: self.steps,
            wall_time_s: self.wall,
            wall_time_rolling_s: self.wall_rolling.unwrap_or(self.wall),
            sim_time_s: last.t_s,
            stop,
            bounds: self.guard.bounds,
            max_energy_rise_rel: self.guard.max_energy_rise_j / ledger.energy_scale_j,
            max_spin_rad_s: self.guard.max_spin_rad_s,
            reference_limits: self.limits.finish(),
            milestones: self.milestones.finish(&self.refs, self.e0),
            rivals: self.milestones.rivals(&self.refs),
            ledger,
            approach: self.approach,
            bang: self.bang.map(|_| BangReport {
                kinetic_in_j: last.bang.kinetic_in_j,
                top_speed_m_s: last.bang.top_speed_m_s,
                duration_s: last.t_s - last.bang.started_s,
                peak_floor_force_n: last.bang.peak_floor_force_n,
                floor_impulse_n_s: last.bang.floor_impulse_n_s,
                end_x_m: self.model.tape_end_x_m(),
                laid_length_m: self.model.tape_length_m(),
                still_moving_j: last.kinetic_j,
                ended_by: last.bang.end,
                solve: last.bang.solve,
                thickness_speed_ratio: last.bang.thickness_speed_ratio,
                layers: last.bang.layers,
                chord_sag_m: last.bang.chord_sag_m,
            }),
            geo_hop_fraction: self.refs.exact.hop_onset_fraction(),
            max_joint_gap_m: self.max_gap,
            max_penetration_m: self.max_pen,
            max_overlap_m: self.max_overlap,
        };
        for o in observers.iter_mut() {
            o.observe_final(&report)?;
        }
        Ok(report)
    }

    /// Where the energy went, with `last` the run's last step.
    fn ledger(&self, last: &Observation) -> Ledger {
        let flat = self.model.flat_potential_j();
        let (bang_time, before, kinetic_into, available) = match self.bang {
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
        let t = &self.scene.tape;
        let mgr_j = t.mass_kg * self.scene.gravity.g_m_s2 * t.outer_radius_m;
        Ledger {
            e0_j: self.e0,
            mgr_j,
            energy_scale_j: self.e0.abs().max(mgr_j).max(kinetic_into),
            flat_potential_j: flat,
            before_bang: before,
            lost_before_bang_j: before.total_j(),
            kinetic_into_bang_j: kinetic_into,
            available_at_bang_j: available,
            dissipated_by_bang_j: last.ledger.bang_j,
            bang: last.bang.ledger,
            left_j: last.kinetic_j + last.potential_j - flat,
            bang_time_s: bang_time,
        }
    }
}

/// How this step ends the run, if it does: a guard first, then the bang's end, the time
/// limit and an interruption.
fn ending(
    scene: &Scene,
    obs: &Observation,
    tripped: Option<GuardTrip>,
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
    interrupted.then_some(StopReason::Interrupted {
        t_s: obs.t_s,
        signal: crate::run::signals::received(),
    })
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
