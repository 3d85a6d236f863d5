//! The scene file's serde mirror: the sections and keys a scene file may hold, each section
//! `deny_unknown_fields`, and the default of every optional key. It checks only the TOML's
//! form (unknown key, wrong type, missing required key); no value's range or any rule
//! between values (that is `validate`'s), and it derives nothing from the tape.
//!
//! Integers are read as `i64` so that out-of-range values reach validation and get the
//! same `key = value: rule` message as floats.

use serde::Deserialize;

/// Every key a scene file may set, with its section path (`section.key`), in the order of
/// the file's sections: the one list the fuzz tests and the override tests draw from. A
/// test checks that it equals the keys the serde mirror accepts.
pub const SCENE_KEYS: &[&str] = &[
    "name",
    "tape.outer_radius_m",
    "tape.thickness_m",
    "tape.mass_kg",
    "tape.core_radius_m",
    "tape.self_friction",
    "discretisation.links_per_turn",
    "floor.friction",
    "floor.slope_deg",
    "floor.sticky",
    "gravity.g_m_s2",
    "push.contact_speed_m_s",
    "solver.max_dt_s",
    "solver.steps_per_link",
    "solver.iterations",
    "solver.freeze_speed_m_s",
    "solver.bang_step_rad",
    "solver.bang_tolerance",
    "solver.bang_iterations",
    "solver.bang_relax_iterations",
    "solver.bang_piece_m",
    "solver.bang_piece_b",
    "solver.contact_hz",
    "solver.joint_hz",
    "solver.bang_joint_hz",
    "solver.bang_engine",
    "contact.model",
    "stop.bang_radius_m",
    "stop.bang_radius_b",
    "stop.max_time_s",
    "stop.bang_cap_s",
    "stop.rest_fraction",
    "axis.fixed",
    "output.sample_interval_s",
    "output.scene_rate_hz",
];

/// The keys that give one length two ways, in metres and in the tape's thicknesses: a file
/// gives one of each pair, and a value on the command line for one replaces the file's other.
pub(crate) const ALTERNATIVES: [(&str, &str); 2] = [
    ("solver.bang_piece_m", "solver.bang_piece_b"),
    ("stop.bang_radius_m", "stop.bang_radius_b"),
];

/// Default `discretisation.links_per_turn`.
const DEFAULT_LINKS_PER_TURN: i64 = 32;
/// Default `floor.friction`.
const DEFAULT_FRICTION: f64 = 1.0;
/// Default `gravity.g_m_s2`.
const DEFAULT_G_M_S2: f64 = 9.81;
/// Default `push.contact_speed_m_s`.
const DEFAULT_CONTACT_SPEED_M_S: f64 = 0.0;
/// Default `solver.max_dt_s`.
const DEFAULT_MAX_DT_S: f64 = 0.001;
/// Default `solver.steps_per_link`.
const DEFAULT_STEPS_PER_LINK: f64 = 4.0;
/// Default `solver.iterations`.
const DEFAULT_ITERATIONS: i64 = 4;
/// Default `solver.freeze_speed_m_s`.
const DEFAULT_FREEZE_SPEED_M_S: f64 = 0.001;
/// Default `solver.bang_step_rad`.
const DEFAULT_BANG_STEP_RAD: f64 = 0.15;
/// Default `solver.bang_tolerance`.
const DEFAULT_BANG_TOLERANCE: f64 = 1e-3;
/// The word for `solver.bang_tolerance` that leaves the bang's steps unbounded.
pub(super) const TOLERANCE_OFF: &str = "off";
/// Default `solver.contact_hz`.
const DEFAULT_CONTACT_HZ: f64 = 1.0e4;
/// Default `solver.joint_hz`.
const DEFAULT_JOINT_HZ: f64 = 1.0e7;
/// Default `solver.bang_joint_hz`.
const DEFAULT_BANG_JOINT_HZ: f64 = 1.0e9;
/// Default `solver.bang_engine`.
const DEFAULT_BANG_ENGINE: &str = "exact";
/// Default `stop.max_time_s`.
const DEFAULT_MAX_TIME_S: f64 = 60.0;
/// Default `solver.bang_iterations`.
const DEFAULT_BANG_ITERATIONS: i64 = 24;
/// Default `solver.bang_relax_iterations`: the engine's own.
const DEFAULT_BANG_RELAX_ITERATIONS: i64 = 1;
/// Default `stop.bang_cap_s`.
const DEFAULT_BANG_CAP_S: f64 = 2.0;
/// Default `stop.rest_fraction`.
const DEFAULT_REST_FRACTION: f64 = 0.001;
/// Default `output.sample_interval_s`.
const DEFAULT_SAMPLE_INTERVAL_S: f64 = 0.001;
/// Default `output.scene_rate_hz`: 100 drawings per simulated second, enough to watch the
/// unroll; the final bang, over in a tenth of a second, is drawn at its own pace besides
/// (the run's `BANG_DRAWN_STEPS`).
const DEFAULT_SCENE_RATE_HZ: f64 = 100.0;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    pub(super) tape: TapeFile,
    #[serde(default)]
    pub(super) discretisation: DiscretisationFile,
    #[serde(default)]
    pub(super) floor: FloorFile,
    #[serde(default)]
    pub(super) gravity: GravityFile,
    #[serde(default)]
    pub(super) push: PushFile,
    #[serde(default)]
    pub(super) solver: SolverFile,
    /// Read so that older files load, and checked, but it selects nothing.
    #[serde(default, rename = "contact")]
    pub(super) _contact: ContactFile,
    #[serde(default)]
    pub(super) stop: StopFile,
    #[serde(default)]
    pub(super) axis: AxisFile,
    #[serde(default)]
    pub(super) output: OutputFile,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TapeFile {
    pub(super) outer_radius_m: f64,
    pub(super) thickness_m: f64,
    pub(super) mass_kg: f64,
    #[serde(default)]
    pub(super) core_radius_m: f64,
    #[serde(default)]
    pub(super) self_friction: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct DiscretisationFile {
    pub(super) links_per_turn: i64,
}

impl Default for DiscretisationFile {
    fn default() -> Self {
        Self {
            links_per_turn: DEFAULT_LINKS_PER_TURN,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct FloorFile {
    pub(super) friction: f64,
    pub(super) slope_deg: f64,
    pub(super) sticky: bool,
}

impl Default for FloorFile {
    fn default() -> Self {
        Self {
            friction: DEFAULT_FRICTION,
            slope_deg: 0.0,
            sticky: false,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct GravityFile {
    pub(super) g_m_s2: f64,
}

impl Default for GravityFile {
    fn default() -> Self {
        Self {
            g_m_s2: DEFAULT_G_M_S2,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct PushFile {
    pub(super) contact_speed_m_s: f64,
}

impl Default for PushFile {
    fn default() -> Self {
        Self {
            contact_speed_m_s: DEFAULT_CONTACT_SPEED_M_S,
        }
    }
}

/// `solver.bang_tolerance` as written: a number, or a word (only [`TOLERANCE_OFF`] is
/// valid).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub(super) enum ToleranceFile {
    Share(f64),
    Word(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct SolverFile {
    pub(super) max_dt_s: f64,
    pub(super) steps_per_link: f64,
    pub(super) iterations: i64,
    pub(super) freeze_speed_m_s: f64,
    pub(super) bang_step_rad: f64,
    /// A share of energy, or [`TOLERANCE_OFF`] (any other word is refused by validation).
    pub(super) bang_tolerance: ToleranceFile,
    pub(super) bang_iterations: i64,
    pub(super) bang_relax_iterations: i64,
    /// `None` means "the tape's thickness" (see [`crate::scene::Solver::bang_piece_m`]).
    pub(super) bang_piece_m: Option<f64>,
    /// The pieces in the tape's thicknesses, in place of `bang_piece_m`.
    pub(super) bang_piece_b: Option<f64>,
    pub(super) contact_hz: f64,
    pub(super) joint_hz: f64,
    pub(super) bang_joint_hz: f64,
    pub(super) bang_engine: String,
}

impl Default for SolverFile {
    fn default() -> Self {
        Self {
            max_dt_s: DEFAULT_MAX_DT_S,
            steps_per_link: DEFAULT_STEPS_PER_LINK,
            iterations: DEFAULT_ITERATIONS,
            freeze_speed_m_s: DEFAULT_FREEZE_SPEED_M_S,
            bang_step_rad: DEFAULT_BANG_STEP_RAD,
            bang_tolerance: ToleranceFile::Share(DEFAULT_BANG_TOLERANCE),
            bang_iterations: DEFAULT_BANG_ITERATIONS,
            bang_relax_iterations: DEFAULT_BANG_RELAX_ITERATIONS,
            bang_piece_m: None,
            bang_piece_b: None,
            contact_hz: DEFAULT_CONTACT_HZ,
            joint_hz: DEFAULT_JOINT_HZ,
            bang_joint_hz: DEFAULT_BANG_JOINT_HZ,
            bang_engine: DEFAULT_BANG_ENGINE.into(),
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct ContactFile {
    pub(super) model: ContactModel,
}

/// `[contact] model`, kept so that older scene files load: the coil always touches the
/// floor through the curved contact refitted to the spiral (see the model), and
/// `"spiral"`, the only value, selects nothing. Any other value is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub(super) enum ContactModel {
    /// The curved contact on the spiral (`"spiral"`).
    #[default]
    Spiral,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct StopFile {
    /// `None` means "derive from the tape" (see [`crate::scene::Stop::bang_radius_m`]).
    pub(super) bang_radius_m: Option<f64>,
    /// The bang radius in the tape's thicknesses above the core, in place of
    /// `bang_radius_m`.
    pub(super) bang_radius_b: Option<f64>,
    pub(super) max_time_s: f64,
    pub(super) bang_cap_s: f64,
    pub(super) rest_fraction: f64,
}

impl Default for StopFile {
    fn default() -> Self {
        Self {
            bang_radius_m: None,
            bang_radius_b: None,
            max_time_s: DEFAULT_MAX_TIME_S,
            bang_cap_s: DEFAULT_BANG_CAP_S,
            rest_fraction: DEFAULT_REST_FRACTION,
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct AxisFile {
    pub(super) fixed: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct OutputFile {
    pub(super) sample_interval_s: f64,
    pub(super) scene_rate_hz: f64,
}

impl Default for OutputFile {
    fn default() -> Self {
        Self {
            sample_interval_s: DEFAULT_SAMPLE_INTERVAL_S,
            scene_rate_hz: DEFAULT_SCENE_RATE_HZ,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::scene::overrides::{Override, scene_with_overrides};
    use crate::scene::tests::{MINIMAL, err, with};
    use crate::scene::{Scene, SceneError};
    use approx::assert_relative_eq;

    #[test]
    fn defaults_applied() {
        let s = Scene::from_toml_str(MINIMAL, "fallback").unwrap();
        assert_eq!(s.name, "fallback");
        assert_relative_eq!(s.tape.core_radius_m, 0.0);
        assert_eq!(s.discretisation.links_per_turn, 32);
        assert_relative_eq!(s.floor.friction, 1.0);
        assert_relative_eq!(s.gravity.g_m_s2, 9.81);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_relative_eq!(s.stop.bang_radius_m, 2.0 * 0.005);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.stop.rest_fraction, 0.001);
        assert_relative_eq!(s.output.sample_interval_s, 0.001);
        assert_eq!(s.source_text, MINIMAL);
    }

    #[test]
    fn integer_literal_accepted_for_float() {
        let s = Scene::from_toml_str(&with("tape", "mass_kg", "2"), "t").unwrap();
        assert_relative_eq!(s.tape.mass_kg, 2.0);
    }

    #[test]
    fn unknown_key_named_with_expected_keys() {
        let msg = err(&with("tape", "colour", "\"red\""));
        assert!(msg.contains("unknown field `colour`"), "{msg}");
        assert!(msg.contains("outer_radius_m"), "{msg}");
        assert!(msg.contains("core_radius_m"), "{msg}");

        let msg = err(&format!("{MINIMAL}\n[wind]\nspeed = 1.0\n"));
        assert!(msg.contains("unknown field `wind`"), "{msg}");
        assert!(msg.contains("discretisation"), "{msg}");

        let msg = err(&with("solver", "dt", "0.1"));
        assert!(msg.contains("unknown field `dt`"), "{msg}");
        assert!(msg.contains("max_dt_s"), "{msg}");
    }

    #[test]
    fn missing_required_key() {
        let msg =
            err("[tape]\nouter_radius_m = 0.06\nmass_kg = 1.5\n[push]\ncontact_speed_m_s = 0.3\n");
        assert!(msg.contains("thickness_m"), "{msg}");
        let msg = err("[push]\ncontact_speed_m_s = 0.3\n");
        assert!(msg.contains("tape"), "{msg}");
    }

    #[test]
    fn wrong_type_rejected() {
        let msg = err(&with("tape", "mass_kg", "\"heavy\""));
        assert!(msg.contains("invalid type"), "{msg}");
        let msg = err(&with("discretisation", "links_per_turn", "32.5"));
        assert!(msg.contains("invalid type"), "{msg}");
        let msg = err(&with("contact", "model", "\"bristle\""));
        assert!(msg.contains("unknown variant `bristle`"), "{msg}");
        assert!(msg.contains("spiral"), "{msg}");
    }

    #[test]
    fn an_older_file_with_its_contact_model_still_loads_to_the_same_scene() {
        let old = Scene::from_toml_str(&with("contact", "model", "\"spiral\""), "t").unwrap();
        let new = Scene::from_toml_str(MINIMAL, "t").unwrap();
        assert_eq!(
            Scene {
                source_text: String::new(),
                ..old
            },
            Scene {
                source_text: String::new(),
                ..new
            }
        );
    }

    /// The keys serde names as expected when `key` (dotted) is unknown: the fields of its
    /// section.
    fn expected_keys(key: &str) -> Vec<String> {
        let e = scene_with_overrides(MINIMAL, "t", &[Override::new(key, "1")]).unwrap_err();
        let SceneError::Parse { message, .. } = e else {
            panic!("{key}: {e}");
        };
        assert!(message.contains("unknown field"), "{key}: {message}");
        let list = message
            .split("expected one of ")
            .nth(1)
            .or_else(|| message.split("expected ").nth(1))
            .unwrap_or_else(|| panic!("{key}: {message}"));
        list.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_owned)
            .collect()
    }

    #[test]
    fn scene_keys_are_the_keys_the_file_accepts() {
        // Read the accepted keys off the serde mirror itself: an unknown key at the top level
        // lists the sections (and `name`), one in a section lists that section's keys.
        let mut accepted = BTreeSet::new();
        for top in expected_keys("no_such_key") {
            if top == "name" {
                accepted.insert(top);
                continue;
            }
            for key in expected_keys(&format!("{top}.no_such_key")) {
                accepted.insert(format!("{top}.{key}"));
            }
        }
        let listed: BTreeSet<String> = SCENE_KEYS.iter().map(|k| (*k).to_owned()).collect();
        assert_eq!(listed.len(), SCENE_KEYS.len(), "a key is listed twice");
        assert_eq!(listed, accepted);
    }

    #[test]
    fn every_listed_key_can_be_set_and_an_unknown_one_is_rejected() {
        // Each key set to its default (or, for the required ones, the minimal scene's value)
        // through the override mechanism loads and gives the minimal scene back.
        let base = Scene::from_toml_str(MINIMAL, "t").unwrap();
        for key in SCENE_KEYS {
            let value = match *key {
                "name" => "t",
                "tape.outer_radius_m" => "0.06",
                "tape.thickness_m" => "0.005",
                "tape.mass_kg" => "1.5",
                "tape.core_radius_m" | "floor.slope_deg" => "0.0",
                "discretisation.links_per_turn" => "32",
                "floor.friction" | "tape.self_friction" => "1.0",
                "floor.sticky" | "axis.fixed" => "false",
                "gravity.g_m_s2" => "9.81",
                "push.contact_speed_m_s" => "0.3",
                "solver.max_dt_s" | "solver.freeze_speed_m_s" | "stop.rest_fraction" => "0.001",
                "output.sample_interval_s" => "0.001",
                "solver.steps_per_link" | "solver.iterations" => "4",
                "solver.bang_step_rad" => "0.15",
                "solver.bang_tolerance" => "1e-3",
                "solver.bang_iterations" => "24",
                "solver.bang_relax_iterations" => "1",
                "solver.bang_piece_m" => "0.005",
                "solver.bang_piece_b" => "1",
                "solver.contact_hz" => "1e4",
                "solver.joint_hz" => "1e7",
                "solver.bang_joint_hz" => "1e9",
                "solver.bang_engine" => "exact",
                "contact.model" => "spiral",
                "stop.bang_radius_m" => "0.01",
                "stop.bang_radius_b" => "2",
                "stop.max_time_s" => "60",
                "stop.bang_cap_s" => "2",
                "output.scene_rate_hz" => "100",
                other => panic!("no value for {other}: add it here"),
            };
            let s = scene_with_overrides(MINIMAL, "t", &[Override::new(key, value)])
                .unwrap_or_else(|e| panic!("{key} = {value}: {e}"));
            assert_eq!(
                Scene {
                    source_text: String::new(),
                    ..s
                },
                Scene {
                    source_text: String::new(),
                    ..base.clone()
                },
                "{key} = {value}"
            );
        }
        let msg = err(&with("floor", "slope", "1.0"));
        assert!(msg.contains("unknown field `slope`"), "{msg}");
    }
}
