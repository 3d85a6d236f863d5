//! The guards that stop a run which blows up: energy rising above E0, joints separating,
//! bodies sinking through the floor or leaving the world, a non-finite state. It reads the
//! model's observations; it steps nothing and writes nothing. Where the references stop
//! applying is [`limits`](crate::run::limits).
//!
//! The bounds are stated here and copied into `report.json` (`bounds`), so a reader of a
//! report knows what "stopped" was measured against.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::model::exact_chain::StepError;
use crate::model::{Health, Observation};
use crate::scene::Scene;
use crate::spiral::Spiral;

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
/// A run stops when two layers of the tape overlap by more than this many thicknesses b:
/// beyond half a thickness a piece's node lies nearer the far face of the layer it meets
/// than the near one, and the two layers can pass through each other.
pub const OVERLAP_PER_THICKNESS: f64 = 0.5;
/// A run stops when a body's centre of mass is farther from the start of the tape than this
/// many times the tape's length plus R (plus the distance the push alone covers in
/// `stop.max_time_s`).
pub const WORLD_PER_LENGTH: f64 = 10.0;

/// The guards' bounds for one scene, in the scene's units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Largest allowed rise of the total energy above E0 (J).
    pub energy_rise_j: f64,
    /// Largest allowed joint separation (m).
    pub joint_gap_m: f64,
    /// Largest allowed floor penetration, and depth of a centre of mass below the floor (m).
    pub penetration_m: f64,
    /// Largest allowed overlap of two layers of the tape (m).
    #[serde(default)]
    pub overlap_m: f64,
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
                    .max(t.mass_kg * scene.gravity.g_m_s2 * t.outer_radius_m)
                    .max(
                        t.mass_kg
                            * scene.gravity.g_m_s2
                            * scene.floor.slope_deg.to_radians().sin().abs()
                            * length,
                    ),
            joint_gap_m: (JOINT_GAP_PER_THICKNESS * t.thickness_m)
                .max(JOINT_GAP_PER_LINK * outer_link_m(scene)),
            penetration_m: PENETRATION_PER_RADIUS * t.outer_radius_m,
            overlap_m: OVERLAP_PER_THICKNESS * t.thickness_m,
            world_radius_m: WORLD_PER_LENGTH * (length + t.outer_radius_m)
                + scene.push.contact_speed_m_s * scene.stop.max_time_s,
            floor_in_reach: !scene.axis.fixed,
        }
    }
}

/// Length of the outermost link, a chord of the outer midline turn (m).
fn outer_link_m(scene: &Scene) -> f64 {
    let t = &scene.tape;
    2.0 * (t.outer_radius_m - 0.5 * t.thickness_m)
        * (std::f64::consts::PI / f64::from(scene.discretisation.links_per_turn)).sin()
}

/// Midline length of the scene's tape (m).
pub(crate) fn tape_length_m(scene: &Scene) -> f64 {
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
        if let Some(e) = health.unsolved {
            let why = match e {
                StepError::Inaccurate { .. } => format!("{e} (solver.bang_tolerance)"),
                _ => e.to_string(),
            };
            return trip(GuardKind::Unsolved(why), 0.0, 0.0);
        }
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
        if obs.max_overlap_m > b.overlap_m {
            return trip(GuardKind::Overlap, obs.max_overlap_m, b.overlap_m);
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
        ("max_overlap_m", obs.max_overlap_m),
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

/// Which guard stopped a run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GuardKind {
    /// A quantity of the state is not finite (its name); value and bound are 0.
    NonFinite(String),
    /// The exact chain could not solve a step of the bang (why); value and bound are 0. The
    /// step was not taken.
    Unsolved(String),
    /// The total energy rose above E0 by more than the bound (J).
    EnergyRise,
    /// A joint separated by more than the bound (m).
    JointGap,
    /// A body sank into the floor deeper than the bound (m).
    Penetration,
    /// Two layers of the tape overlapped by more than the bound (m): it is passing through
    /// itself.
    Overlap,
    /// A body's centre of mass fell below the floor by more than the bound (m); the value
    /// is its height.
    FellThrough,
    /// A body went farther from the start of the tape than the bound (m).
    LeftWorld,
}

/// A guard's verdict: which guard, when, the value it measured and its bound.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GuardTrip {
    /// The guard.
    pub guard: GuardKind,
    /// When it tripped (s).
    pub t_s: f64,
    /// The value it measured, in the bound's unit.
    pub value: f64,
    /// Its bound.
    pub bound: f64,
}

impl GuardTrip {
    /// A short name of the guard, for tables and a sweep's status.
    pub fn name(&self) -> &'static str {
        match self.guard {
            GuardKind::NonFinite(_) => "non-finite",
            GuardKind::Unsolved(_) => "unsolved",
            GuardKind::EnergyRise => "energy-rise",
            GuardKind::JointGap => "joint-gap",
            GuardKind::Penetration => "penetration",
            GuardKind::Overlap => "overlap",
            GuardKind::FellThrough => "fell-through",
            GuardKind::LeftWorld => "left-world",
        }
    }
}

impl fmt::Display for GuardTrip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (t, v, b) = (self.t_s, self.value, self.bound);
        match &self.guard {
            GuardKind::NonFinite(name) => {
                write!(f, "blow-up at t = {t:.6} s: {name} is not finite")
            }
            GuardKind::Unsolved(why) => write!(f, "unsolved step at t = {t:.6} s: {why}"),
            GuardKind::EnergyRise => write!(
                f,
                "energy rising at t = {t:.6} s: E - E0 = {v:.4e} J, above the bound {b:.4e} J \
                 ({} % of the energy scale: the largest of |E0|, M g R, M g L sin(slope))",
                100.0 * ENERGY_RISE_TOLERANCE
            ),
            GuardKind::JointGap => write!(
                f,
                "joints separating at t = {t:.6} s: gap {v:.4e} m, above the bound {b:.4e} m \
                 (the larger of {JOINT_GAP_PER_THICKNESS} b and {} % of the outermost link)",
                100.0 * JOINT_GAP_PER_LINK
            ),
            GuardKind::Penetration => write!(
                f,
                "floor penetration at t = {t:.6} s: {v:.4e} m, above the bound {b:.4e} m \
                 ({PENETRATION_PER_RADIUS} R)"
            ),
            GuardKind::Overlap => write!(
                f,
                "layers overlapping at t = {t:.6} s: {v:.4e} m, above the bound {b:.4e} m \
                 ({OVERLAP_PER_THICKNESS} b): the tape is passing through itself"
            ),
            GuardKind::FellThrough => write!(
                f,
                "a body fell through the floor at t = {t:.6} s: centre of mass at y = {v:.4e} m, \
                 below the bound -{b:.4e} m ({PENETRATION_PER_RADIUS} R)"
            ),
            GuardKind::LeftWorld => write!(
                f,
                "a body left the world at t = {t:.6} s: {v:.4e} m from the start, beyond the \
                 bound {b:.4e} m"
            ),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{BangRecord, EnergyLedger, Phase};

    pub(crate) use crate::model::tests::yoga;

    /// A calm rolling step with energy `e_j` (all potential).
    pub(crate) fn step(e_j: f64) -> Observation {
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
            max_overlap_m: 0.0,
            dt_s: 1e-3,
            angular_momentum_o: 0.0,
            impulses: crate::model::StepImpulses::default(),
        }
    }

    pub(crate) fn calm() -> Health {
        Health {
            slip_m_s: Some(0.0),
            farthest_m: 0.3,
            lowest_m: 0.002,
            max_spin_rad_s: 5.0,
            finite: true,
            unsolved: None,
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
}
