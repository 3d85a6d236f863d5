//! Where the references stop applying: slip, bunching, skid, lift-off, fewer than a few
//! turns (eq. 7's O(b/r)), the exact model's hop and its outer turn loosening, and the
//! contact line leaving the exact model's speed; judged against the rolling or, on a
//! frictionless floor, the sliding exact model. It reads the model's observations; it stops
//! nothing and writes nothing.

use serde::{Deserialize, Serialize};

use crate::model::{Health, Observation, Phase};
use crate::run::guard::tape_length_m;
use crate::scene::Scene;
use crate::spiral::Spiral;
use crate::theory::exact::ExactGeometry;

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

/// Why a reference stops describing the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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
    /// The exact-geometry model's outer turn needs more tension at the coil's top than the
    /// laid tape's pull gives (`ExactGeometry::loosen_onset_fraction`): from here on a tape
    /// with no bending stiffness would lift off its coil, and the rigid coil stands for one
    /// stiff enough to stay wound.
    Loosens,
}

/// Where and why a reference stops applying.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    loosen_fraction: Option<f64>,
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
            push_speed_m_s: scene.push.contact_speed_m_s,
            outer_radius_m: t.outer_radius_m,
            on_floor: !scene.axis.fixed,
            sliding: exact.is_sliding().then(|| exact.clone()),
            rolling: (!exact.is_sliding()).then(|| exact.clone()),
            leave_steps: 0,
            hop_fraction: exact.hop_onset_fraction(),
            loosen_fraction: exact.loosen_onset_fraction(scene.floor.friction),
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
        if let Some(f) = self.loosen_fraction
            && obs.laid_fraction >= f
        {
            self.note(LimitKind::Loosens, obs, loosen_detail(f));
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

    /// The limits, in the order they were met; the exact-geometry model's hop and its
    /// loosening are listed with no time if the run never reached them.
    pub fn finish(mut self) -> Vec<ReferenceLimit> {
        let unreached = [
            (
                LimitKind::ExactModelHops,
                self.hop_fraction,
                hop_detail as fn(f64) -> String,
            ),
            (LimitKind::Loosens, self.loosen_fraction, loosen_detail),
        ];
        for (kind, fraction, detail) in unreached {
            if let Some(f) = fraction.filter(|_| !self.seen(kind)) {
                self.limits.push(ReferenceLimit {
                    kind,
                    t_s: None,
                    r_m: self.outer_radius_m * (1.0 - f).max(0.0).sqrt(),
                    detail: detail(f),
                });
            }
        }
        self.limits
    }
}

fn hop_detail(f: f64) -> String {
    format!(
        "from laid fraction {f:.4} on, the exact-geometry model needs a floor that pulls (N < 0)"
    )
}

fn loosen_detail(f: f64) -> String {
    format!(
        "from laid fraction {f:.4} on, the exact-geometry model's outer turn needs more \
         tension at the coil's top than the laid tape's pull gives: a tape with no bending \
         stiffness would lift off its coil there"
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
        LimitKind::Loosens => "loosens",
        LimitKind::LeavesExact => "leaves exact",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::guard::tests::{calm, step, yoga};

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
                LimitKind::ExactModelHops,
                LimitKind::Loosens
            ]
        );
        assert_eq!(limits[2].t_s, None, "the hop at f = 0.5 was never reached");
        assert_eq!(limits[3].t_s, None, "nor the loosening at f = 0.26");
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
