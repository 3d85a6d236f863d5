//! Health of a run: the guards that stop a run which blows up (energy rising above E0,
//! joints separating, bodies sinking through the floor or leaving the world, a non-finite
//! state), and the points where the references stop applying (slip, bunching, skid,
//! lift-off, r ~ b). It reads the model's observations; it steps nothing and writes nothing.
//!
//! The bounds are stated here and copied into `report.json` (`bounds`), so a reader of a
//! report knows what "stopped" was measured against.

use serde::Serialize;

use crate::model::{Health, Observation, Phase};
use crate::run::stop::{GuardKind, GuardTrip};
use crate::scene::Scene;
use crate::spiral::Spiral;
use crate::theory::exact::ExactGeometry;

/// A run stops when its total energy rises above E0 by this fraction of the scene's energy
/// scale, the largest of |E0|, M g R and, on a slope, M g sin(slope) L (what the whole tape
/// of length L can release along it): every loss in the model dissipates, so a rise
/// beyond rounding is the engine adding energy. (E0 alone is no scale: a tape hanging from
/// an axis starts with E0 ~ 0, and a mat rolling 30 degrees downhill gains ten times E0.)
pub const ENERGY_RISE_TOLERANCE: f64 = 0.01;
/// A run stops when a joint separates by more than this many tape thicknesses b (the midline
/// broken at the tape's own scale) and by more than [`JOINT_GAP_PER_LINK`] of the outermost
/// link (the chain stretched by that much): a spool's tape is microns thick, its links
/// millimetres long, and a joint compliant by a micron tears nothing.
pub const JOINT_GAP_PER_THICKNESS: f64 = 1.0;
/// See [`JOINT_GAP_PER_THICKNESS`].
pub const JOINT_GAP_PER_LINK: f64 = 0.01;
/// A run stops when a collider sinks into the floor deeper than this fraction of the outer
/// radius R, or a body's centre of mass falls that far below the floor.
pub const PENETRATION_PER_RADIUS: f64 = 0.25;
/// A run stops when a body's centre of mass is farther from the start of the tape than this
/// many times the tape's length plus R (plus the distance the push alone covers in
/// `stop.max_time_s`).
pub const WORLD_PER_LENGTH: f64 = 10.0;
/// The rolling contact slips when the coil's material point there moves faster than this
/// fraction of the contact-line speed (or of the push speed, if larger).
pub const SLIP_FRACTION: f64 = 0.05;
/// The contact line has left the laid tape when the two differ by more than this fraction
/// of the laid length, plus one thickness b.
pub const LAID_MISMATCH_FRACTION: f64 = 0.02;
/// The simulation has left the exact-geometry model once its contact-line speed differs
/// from the model's, at the same laid fraction, by more than this fraction.
pub const LEAVES_EXACT_FRACTION: f64 = 0.05;
/// A condition of the references counts as broken once it holds for this many consecutive
/// steps (single steps at a detach or a contact change are noise).
pub const CONSECUTIVE_STEPS: u32 = 20;
/// Eq. (7) treats the coil as a continuum, with an error O(b/r): it is flagged once the
/// coil's outer radius is below this many thicknesses.
pub const CONTINUUM_RADIUS_PER_THICKNESS: f64 = 3.0;

/// The guards' bounds for one scene, in the scene's units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Largest allowed rise of the total energy above E0 (J).
    pub energy_rise_j: f64,
    /// Largest allowed joint separation (m).
    pub joint_gap_m: f64,
    /// Largest allowed floor penetration, and depth of a centre of mass below the floor (m).
    pub penetration_m: f64,
    /// Largest allowed distance of a body from the start of the tape (m).
    pub world_radius_m: f64,
    /// Whether the tape can reach the floor (not on a fixed axis, where it hangs): only
    /// then does a centre of mass below it mean a body fell through.
    pub floor_in_reach: bool,
}

impl Bounds {
    /// The bounds of `scene` for a run starting with energy `e0_j`.
    pub fn new(scene: &Scene, e0_j: f64) -> Self {
        let t = &scene.tape;
        let length = tape_length_m(scene);
        Self {
            energy_rise_j: ENERGY_RISE_TOLERANCE
                * e0_j
                    .abs()
                    .max(t.mass_kg * scene.g_m_s2 * t.outer_radius_m)
                    .max(
                        t.mass_kg
                            * scene.g_m_s2
                            * scene.slope_deg.to_radians().sin().abs()
                            * length,
                    ),
            joint_gap_m: (JOINT_GAP_PER_THICKNESS * t.thickness_m)
                .max(JOINT_GAP_PER_LINK * outer_link_m(scene)),
            penetration_m: PENETRATION_PER_RADIUS * t.outer_radius_m,
            world_radius_m: WORLD_PER_LENGTH * (length + t.outer_radius_m)
                + scene.push_speed_m_s * scene.stop.max_time_s,
            floor_in_reach: !scene.fixed_axis,
        }
    }
}

/// Length of the outermost link, a chord of the outer midline turn (m).
fn outer_link_m(scene: &Scene) -> f64 {
    let t = &scene.tape;
    2.0 * (t.outer_radius_m - 0.5 * t.thickness_m)
        * (std::f64::consts::PI / f64::from(scene.links_per_turn)).sin()
}

/// Midline length of the scene's tape (m).
fn tape_length_m(scene: &Scene) -> f64 {
    let t = &scene.tape;
    Spiral::wound(t.outer_radius_m, t.thickness_m, t.core_radius_m).length()
}

/// Checks every step against the [`Bounds`] and keeps the largest energy rise.
#[derive(Debug, Clone)]
pub struct Guard {
    /// The bounds checked.
    pub bounds: Bounds,
    e0_j: f64,
    /// Largest `E - E0` seen so far (J); 0 if the energy never rose.
    pub max_energy_rise_j: f64,
    /// Fastest spin of any body seen so far (rad/s).
    pub max_spin_rad_s: f64,
}

impl Guard {
    /// A guard for `scene` with initial energy `e0_j`.
    pub fn new(scene: &Scene, e0_j: f64) -> Self {
        Self {
            bounds: Bounds::new(scene, e0_j),
            e0_j,
            max_energy_rise_j: 0.0,
            max_spin_rad_s: 0.0,
        }
    }

    /// The reason to stop after this step, if any. A non-finite state is reported before
    /// anything else (the other checks would compare NaN).
    pub fn check(&mut self, obs: &Observation, health: &Health) -> Option<GuardTrip> {
        let trip = |guard, value, bound| {
            Some(GuardTrip {
                guard,
                t_s: obs.t_s,
                value,
                bound,
            })
        };
        if let Some(name) = non_finite(obs, health) {
            return trip(GuardKind::NonFinite(name.to_owned()), 0.0, 0.0);
        }
        self.max_spin_rad_s = self.max_spin_rad_s.max(health.max_spin_rad_s);
        let b = &self.bounds;
        let rise = obs.kinetic_j + obs.potential_j - self.e0_j;
        self.max_energy_rise_j = self.max_energy_rise_j.max(rise);
        if rise > b.energy_rise_j {
            return trip(GuardKind::EnergyRise, rise, b.energy_rise_j);
        }
        if obs.max_joint_gap_m > b.joint_gap_m {
            return trip(GuardKind::JointGap, obs.max_joint_gap_m, b.joint_gap_m);
        }
        if obs.max_penetration_m > b.penetration_m {
            return trip(
                GuardKind::Penetration,
                obs.max_penetration_m,
                b.penetration_m,
            );
        }
        if b.floor_in_reach && -health.lowest_m > b.penetration_m {
            return trip(GuardKind::FellThrough, health.lowest_m, b.penetration_m);
        }
        if health.farthest_m > b.world_radius_m {
            return trip(GuardKind::LeftWorld, health.farthest_m, b.world_radius_m);
        }
        None
    }
}

/// Whether every quantity of a step is finite.
pub fn is_finite(obs: &Observation, health: &Health) -> bool {
    non_finite(obs, health).is_none()
}

/// The first non-finite quantity of a step, by name.
fn non_finite(obs: &Observation, health: &Health) -> Option<&'static str> {
    let named = [
        ("t_s", obs.t_s),
        ("laid_fraction", obs.laid_fraction),
        ("x_m", obs.x_m),
        ("omega_rad_s", obs.omega_rad_s),
        ("kinetic_j", obs.kinetic_j),
        ("potential_j", obs.potential_j),
        ("normal_n", obs.normal_n),
        ("friction_n", obs.friction_n),
        ("max_joint_gap_m", obs.max_joint_gap_m),
        ("max_penetration_m", obs.max_penetration_m),
    ];
    if let Some((name, _)) = named.iter().find(|(_, v)| !v.is_finite()) {
        return Some(name);
    }
    if !health.finite {
        return Some("a body's position or velocity");
    }
    if health.slip_m_s.is_some_and(|s| !s.is_finite()) {
        return Some("the contact slip speed");
    }
    None
}

/// Why a reference stops describing the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LimitKind {
    /// The rolling contact slips: the references assume rolling without slip.
    Slip,
    /// The contact line lags the laid tape: the tape is laid in less floor than its length.
    Bunching,
    /// The contact line runs ahead of the laid tape: the coil skids over the floor.
    Skid,
    /// No floor force on the moving tape: the coil has left the floor.
    LiftOff,
    /// Fewer than a few turns left: eq. (7)'s continuum idealisation (error O(b/r)) fails.
    FewTurns,
    /// The exact-geometry model needs a floor that pulls (N < 0) from here on: a real rigid
    /// spiral hops.
    ExactModelHops,
    /// The contact-line speed leaves the exact-geometry model's: the divergence of x' as
    /// r -> 0 is cut off here.
    LeavesExact,
}

/// Where and why a reference stops applying.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceLimit {
    /// Which condition.
    pub kind: LimitKind,
    /// Simulated time at which it was first met (s); `None` if the run never got there.
    pub t_s: Option<f64>,
    /// Coil outer radius there (m).
    pub r_m: f64,
    /// What was measured.
    pub detail: String,
}

/// Watches the rolling phase for the first time each reference assumption breaks.
#[derive(Debug, Clone)]
pub struct Applicability {
    length_m: f64,
    thickness_m: f64,
    a_m: f64,
    push_speed_m_s: f64,
    outer_radius_m: f64,
    /// Whether the tape lays onto a floor; the notes below all assume one (a tape hanging
    /// from a fixed axis, App. E, has references of its own).
    on_floor: bool,
    /// The exact model sliding on a frictionless floor, for where its contact line is.
    sliding: Option<ExactGeometry>,
    /// The exact model rolling, for its contact-line speed.
    rolling: Option<ExactGeometry>,
    leave_steps: u32,
    hop_fraction: Option<f64>,
    slip_steps: u32,
    lift_off_steps: u32,
    mismatch_steps: u32,
    limits: Vec<ReferenceLimit>,
}

impl Applicability {
    /// A watcher for `scene` against its exact-geometry model `exact`.
    pub fn new(scene: &Scene, exact: &ExactGeometry) -> Self {
        let t = &scene.tape;
        Self {
            length_m: tape_length_m(scene),
            thickness_m: t.thickness_m,
            a_m: Spiral::wound(t.outer_radius_m, t.thickness_m, t.core_radius_m).a_m,
            push_speed_m_s: scene.push_speed_m_s,
            outer_radius_m: t.outer_radius_m,
            on_floor: !scene.fixed_axis,
            sliding: exact.is_sliding().then(|| exact.clone()),
            rolling: (!exact.is_sliding()).then(|| exact.clone()),
            leave_steps: 0,
            hop_fraction: exact.hop_onset_fraction(),
            slip_steps: 0,
            lift_off_steps: 0,
            mismatch_steps: 0,
            limits: Vec::new(),
        }
    }

    fn seen(&self, kind: LimitKind) -> bool {
        self.limits.iter().any(|l| l.kind == kind)
    }

    fn note(&mut self, kind: LimitKind, obs: &Observation, detail: String) {
        if !self.seen(kind) {
            self.limits.push(ReferenceLimit {
                kind,
                t_s: Some(obs.t_s),
                r_m: self.radius_m(obs),
                detail,
            });
        }
    }

    /// Outer radius of the coil: the midline radius at the lowest point plus b/2 (m).
    fn radius_m(&self, obs: &Observation) -> f64 {
        self.a_m * obs.psi_low + 0.5 * self.thickness_m
    }

    /// Reads one step; `xdot_m_s` is the contact-line speed. Only the rolling phase on a
    /// floor is judged: the references end where the final bang begins.
    pub fn observe(&mut self, obs: &Observation, health: &Health, xdot_m_s: f64) {
        if obs.phase != Phase::Rolling || !self.on_floor {
            return;
        }
        let b = self.thickness_m;
        // On a frictionless floor the references slide by construction: no slip to flag.
        if let Some(slip) = health.slip_m_s.filter(|_| self.sliding.is_none()) {
            let scale = xdot_m_s.abs().max(self.push_speed_m_s);
            if slip.abs() > SLIP_FRACTION * scale {
                self.slip_steps += 1;
            } else {
                self.slip_steps = 0;
            }
            if self.slip_steps == CONSECUTIVE_STEPS {
                let detail = format!(
                    "the coil slips at its contact: {slip:+.3e} m/s against a contact-line \
                     speed of {xdot_m_s:.3e} m/s (bound {} %), for {CONSECUTIVE_STEPS} steps",
                    100.0 * SLIP_FRACTION
                );
                self.note(LimitKind::Slip, obs, detail);
            }
        }
        let laid = obs.laid_fraction * self.length_m;
        // Where the contact line should be: rolling lays the tape where it goes; sliding
        // keeps the centre of mass, x ~ laid^2 / (2 L) (eqs. 100, 106).
        let expected = self
            .sliding
            .as_ref()
            .and_then(|e| e.sliding_contact_x(obs.psi_low))
            .unwrap_or(laid);
        let mismatch = obs.x_m - expected;
        if mismatch.abs() > LAID_MISMATCH_FRACTION * laid + b {
            self.mismatch_steps += 1;
        } else {
            self.mismatch_steps = 0;
        }
        if self.mismatch_steps == CONSECUTIVE_STEPS {
            let kind = if mismatch < 0.0 {
                LimitKind::Bunching
            } else {
                LimitKind::Skid
            };
            let detail = format!(
                "the contact line is at x = {:.4} m, expected {expected:.4} m with {laid:.4} m \
                 of tape laid (bound {} % + b)",
                obs.x_m,
                100.0 * LAID_MISMATCH_FRACTION
            );
            self.note(kind, obs, detail);
        }
        if obs.normal_n <= 0.0 {
            self.lift_off_steps += 1;
        } else {
            self.lift_off_steps = 0;
        }
        if self.lift_off_steps == CONSECUTIVE_STEPS {
            let detail =
                format!("no upward floor force on the moving tape for {CONSECUTIVE_STEPS} steps");
            self.note(LimitKind::LiftOff, obs, detail);
        }
        if let Some(f) = self.hop_fraction
            && obs.laid_fraction >= f
        {
            self.note(LimitKind::ExactModelHops, obs, hop_detail(f));
        }
        if let Some(exact) = &self.rolling
            && obs.laid_fraction > 0.0
        {
            let model = exact.xdot_at_psi(obs.psi_low);
            let off = xdot_m_s / model - 1.0;
            if off.abs() > LEAVES_EXACT_FRACTION {
                self.leave_steps += 1;
            } else {
                self.leave_steps = 0;
            }
            if self.leave_steps == CONSECUTIVE_STEPS {
                let detail = format!(
                    "the contact-line speed {xdot_m_s:.4e} m/s is {:+.1} % from the exact \
                     model's {model:.4e} m/s at the same laid fraction (bound {} %), for \
                     {CONSECUTIVE_STEPS} steps",
                    100.0 * off,
                    100.0 * LEAVES_EXACT_FRACTION
                );
                self.note(LimitKind::LeavesExact, obs, detail);
            }
        }
        let r = self.radius_m(obs);
        if r < CONTINUUM_RADIUS_PER_THICKNESS * b {
            let detail = format!(
                "r = {r:.4e} m < {CONTINUUM_RADIUS_PER_THICKNESS} b: eq. (7)'s continuum \
                 error O(b/r) is tens of percent"
            );
            self.note(LimitKind::FewTurns, obs, detail);
        }
    }

    /// The limits met so far, in the order they were met.
    pub fn limits(&self) -> &[ReferenceLimit] {
        &self.limits
    }

    /// The limits, in the order they were met; the exact-geometry model's hop is listed
    /// with no time if the run never reached it.
    pub fn finish(mut self) -> Vec<ReferenceLimit> {
        if let (Some(f), false) = (self.hop_fraction, self.seen(LimitKind::ExactModelHops)) {
            self.limits.push(ReferenceLimit {
                kind: LimitKind::ExactModelHops,
                t_s: None,
                r_m: self.outer_radius_m * (1.0 - f).max(0.0).sqrt(),
                detail: hop_detail(f),
            });
        }
        self.limits
    }
}

fn hop_detail(f: f64) -> String {
    format!(
        "from laid fraction {f:.4} on, the exact-geometry model needs a floor that pulls (N < 0)"
    )
}

/// Short label of a limit kind for tables.
pub fn label(kind: LimitKind) -> &'static str {
    match kind {
        LimitKind::Slip => "slip",
        LimitKind::Bunching => "bunching",
        LimitKind::Skid => "skid",
        LimitKind::LiftOff => "lift-off",
        LimitKind::FewTurns => "r<3b",
        LimitKind::ExactModelHops => "exact hops",
        LimitKind::LeavesExact => "leaves exact",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BangRecord, EnergyLedger};

    /// The yoga mat: R = 0.06 m, b = 0.005 m.
    fn yoga() -> Scene {
        Scene::from_toml_str(
            "[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\nmass_kg = 1.5\n\
             [push]\ncontact_speed_m_s = 0.3\n",
            "yoga",
        )
        .expect("valid scene")
    }

    /// A calm rolling step with energy `e_j` (all potential).
    fn step(e_j: f64) -> Observation {
        Observation {
            t_s: 0.5,
            phase: Phase::Rolling,
            laid_fraction: 0.1,
            psi_low: 60.0,
            x_m: 0.207,
            omega_rad_s: 5.0,
            kinetic_j: 0.0,
            potential_j: e_j,
            normal_n: 14.0,
            friction_n: 0.1,
            ledger: EnergyLedger::default(),
            bang: BangRecord::default(),
            detached: 3,
            active_bodies: 4,
            max_joint_gap_m: 1e-5,
            max_penetration_m: 1e-5,
            dt_s: 1e-3,
            angular_momentum_o: 0.0,
            impulses: crate::model::StepImpulses::default(),
        }
    }

    fn calm() -> Health {
        Health {
            slip_m_s: Some(0.0),
            farthest_m: 0.3,
            lowest_m: 0.002,
            max_spin_rad_s: 5.0,
            finite: true,
        }
    }

    #[test]
    fn bounds_follow_the_scene() {
        let b = Bounds::new(&yoga(), 2.0);
        assert!((b.energy_rise_j - 0.02).abs() < 1e-12, "{b:?}");
        assert!((b.joint_gap_m - 0.005).abs() < 1e-12, "{b:?}");
        assert!((b.penetration_m - 0.015).abs() < 1e-12, "{b:?}");
        // Tape length ~2.07 m: 10 (2.07 + 0.06) + 0.3 m/s * 60 s.
        assert!((b.world_radius_m - 39.3).abs() < 0.1, "{b:?}");
    }

    #[test]
    fn a_calm_step_passes_and_each_blow_up_is_named() {
        let scene = yoga();
        let mut guard = Guard::new(&scene, 1.0);
        assert_eq!(guard.check(&step(0.99), &calm()), None);
        assert_eq!(guard.check(&step(1.009), &calm()), None, "within 1 %");
        assert!((guard.max_energy_rise_j - 0.009).abs() < 1e-9);

        let cases: [(&str, Observation, Health); 7] = [
            ("energy rising", step(1.011), calm()),
            (
                "joints separating",
                Observation {
                    max_joint_gap_m: 0.0051,
                    ..step(1.0)
                },
                calm(),
            ),
            (
                "floor penetration",
                Observation {
                    max_penetration_m: 0.016,
                    ..step(1.0)
                },
                calm(),
            ),
            (
                "fell through the floor",
                step(1.0),
                Health {
                    lowest_m: -0.016,
                    ..calm()
                },
            ),
            (
                "left the world",
                step(1.0),
                Health {
                    farthest_m: 40.0,
                    ..calm()
                },
            ),
            (
                "kinetic_j is not finite",
                Observation {
                    kinetic_j: f64::NAN,
                    ..step(1.0)
                },
                calm(),
            ),
            (
                "a body's position or velocity is not finite",
                step(1.0),
                Health {
                    finite: false,
                    ..calm()
                },
            ),
        ];
        for (want, obs, health) in cases {
            let got = Guard::new(&scene, 1.0).check(&obs, &health);
            assert!(
                got.as_ref().is_some_and(|r| r.to_string().contains(want)),
                "expected `{want}`, got {got:?}"
            );
        }
    }

    #[test]
    fn limits_need_consecutive_steps_and_are_noted_once() {
        let scene = yoga();
        let exact = crate::theory::exact_geometry(&scene);
        let mut a = Applicability::new(&scene, &exact);
        let slipping = Health {
            slip_m_s: Some(0.1),
            ..calm()
        };
        // The contact line moves as the exact model's does there.
        let v = exact.xdot_at_psi(step(1.0).psi_low);
        // One noisy step, then a calm one: nothing.
        a.observe(&step(1.0), &slipping, v);
        a.observe(&step(1.0), &calm(), v);
        assert!(a.limits().is_empty());
        for _ in 0..2 * CONSECUTIVE_STEPS {
            a.observe(&step(1.0), &slipping, v);
        }
        let kinds: Vec<LimitKind> = a.limits().iter().map(|l| l.kind).collect();
        assert_eq!(kinds, vec![LimitKind::Slip]);

        // Contact line 0.1 m behind 0.207 m of laid tape: bunching; lifted off the floor.
        let mut a = Applicability::new(&scene, &exact);
        a.hop_fraction = Some(0.5);
        let behind = Observation {
            x_m: 0.1,
            normal_n: 0.0,
            ..step(1.0)
        };
        for _ in 0..CONSECUTIVE_STEPS {
            a.observe(&behind, &calm(), v);
        }
        let limits = a.finish();
        let kinds: Vec<LimitKind> = limits.iter().map(|l| l.kind).collect();
        assert_eq!(
            kinds,
            vec![
                LimitKind::Bunching,
                LimitKind::LiftOff,
                LimitKind::ExactModelHops
            ]
        );
        assert_eq!(limits[2].t_s, None, "the hop at f = 0.5 was never reached");
    }

    #[test]
    fn a_contact_line_off_the_exact_model_s_speed_is_noted() {
        let scene = yoga();
        let exact = crate::theory::exact_geometry(&scene);
        let v = exact.xdot_at_psi(step(1.0).psi_low);
        let mut a = Applicability::new(&scene, &exact);
        // 4 % off: within the bound.
        for _ in 0..2 * CONSECUTIVE_STEPS {
            a.observe(&step(1.0), &calm(), 1.04 * v);
        }
        assert!(a.limits().is_empty(), "{:?}", a.limits());
        // 6 % off for one step short of the count, then for the count.
        for _ in 0..CONSECUTIVE_STEPS - 1 {
            a.observe(&step(1.0), &calm(), 1.06 * v);
        }
        assert!(a.limits().is_empty());
        a.observe(&step(1.0), &calm(), 1.06 * v);
        let kinds: Vec<LimitKind> = a.limits().iter().map(|l| l.kind).collect();
        assert_eq!(kinds, vec![LimitKind::LeavesExact]);
    }

    #[test]
    fn a_sliding_coil_is_judged_against_the_sliding_contact_line() {
        let scene = Scene::from_toml_str(
            "[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\nmass_kg = 1.5\n\
             [floor]\nfriction = 0.0\n[push]\ncontact_speed_m_s = 0.3\n",
            "sliding",
        )
        .expect("valid scene");
        let exact = crate::theory::exact_geometry(&scene);
        let psi = exact.psi_at_fraction(0.5);
        let x = exact.sliding_contact_x(psi).expect("sliding");
        let laid = exact.spiral().arc(psi, exact.spiral().psi_out);
        // Zero momentum: about laid^2 / (2 L) (eq. 106), well short of the laid length.
        let l = exact.spiral().length();
        assert!(
            (x / (laid * laid / (2.0 * l)) - 1.0).abs() < 0.1,
            "{x} {laid}"
        );
        let at = |x_m: f64| Observation {
            laid_fraction: 0.5,
            psi_low: psi,
            x_m,
            ..step(1.0)
        };
        let slipping = Health {
            slip_m_s: Some(0.3),
            ..calm()
        };
        // Where the sliding model puts it, slipping as sliding does: nothing to say.
        let mut a = Applicability::new(&scene, &exact);
        for _ in 0..2 * CONSECUTIVE_STEPS {
            a.observe(&at(x), &slipping, 0.3);
        }
        assert!(a.limits().is_empty(), "{:?}", a.limits());
        // Where rolling would put it: the coil has skidded ahead of the sliding model.
        let mut a = Applicability::new(&scene, &exact);
        for _ in 0..CONSECUTIVE_STEPS {
            a.observe(&at(laid), &slipping, 0.3);
        }
        let kinds: Vec<LimitKind> = a.limits().iter().map(|l| l.kind).collect();
        assert_eq!(kinds, vec![LimitKind::Skid]);
    }
}
