//! Scene files: parses a TOML scene description and validates it into a [`Scene`] of plain
//! numbers; it does not simulate anything, derive physical quantities, or re-check a `Scene`
//! after construction (a `Scene` that exists is valid).
//!
//! The TOML is read into a private serde mirror (`file`: every section
//! `deny_unknown_fields`, defaults filled by serde), then every value is checked once, in
//! dependency order (`validate`), and the run the scene asks for is held to the budgets of
//! `budget`; the first violation is reported as [`SceneError::Invalid`] naming the key with
//! its section path, the offending value and the rule. This file holds the public types and
//! the entry points.

mod budget;
mod file;
pub mod folded;
pub mod overrides;
mod rules;
pub mod shipped;
mod validate;

use std::path::{Path, PathBuf};

use serde::Serialize;

pub use budget::{
    BANG_TURN_RAD, MAX_ENGINE_STEPS, MAX_FRAME_NODES, MAX_LINKS, MAX_SAMPLES, MIN_BANG_STEP_RAD,
};
pub use file::SCENE_KEYS;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error(
        "cannot read scene file {}: {source} (a shipped scene can be named instead: {}; \
         `uncoil scenes` lists them all, the hard cases too)",
        path.display(),
        shipped::names().join(", ")
    )]
    Read {
        /// Path of the file that could not be read.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// The text is not valid TOML or does not match the scene schema (unknown key, wrong
    /// type, missing required key).
    #[error("cannot parse scene {name}: {message}")]
    Parse {
        /// Name of the scene (file stem, or the name passed to [`Scene::from_toml_str`]).
        name: String,
        /// The TOML parser's message, with line and column.
        message: String,
    },
    /// A value is out of its allowed range.
    #[error("{key} = {value}: {rule}")]
    Invalid {
        /// Key with its section path, e.g. `tape.thickness_m`.
        key: String,
        /// The offending value as written by `Display` (`NaN`, `inf`, `-0.001`, ...).
        value: String,
        /// The rule the value breaks.
        rule: String,
    },
}

/// The tape and its winding.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tape {
    /// Outer radius R of the wound coil (outer surface), m (required, no default).
    pub outer_radius_m: f64,
    /// Tape thickness b, which is also the spiral pitch, m (required, no default).
    pub thickness_m: f64,
    /// Total tape mass M, kg (required, no default).
    pub mass_kg: f64,
    /// Inner radius of the winding (a hollow, massless core), m (default: 0.0).
    pub core_radius_m: f64,
    /// Coulomb's coefficient between the tape's own layers in the final bang, where they
    /// strike and rub each other, dimensionless (default: `floor.friction`: one coefficient
    /// for the tape's face wherever it meets, so that a scene that sets only the floor's sets
    /// both, and a frictionless scene stays frictionless).
    pub self_friction: f64,
}

/// Time-stepping and rapier solver settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Solver {
    /// Largest time step, s (default: 0.001).
    pub max_dt_s: f64,
    /// Adaptive step rule: at least this many steps while the coil turns by one link angle,
    /// dimensionless (default: 4.0).
    pub steps_per_link: f64,
    /// Rapier solver iterations per step, count (default: 4).
    pub iterations: u32,
    /// A laid link slower than this is frozen (removed from the engine), m/s
    /// (default: 0.001).
    pub freeze_speed_m_s: f64,
    /// In the final bang, the largest rotation of any body in one step, rad (default: 0.15).
    /// No link is shed there, so the rolling rule (`steps_per_link`) no longer applies.
    pub bang_step_rad: f64,
    /// A bound on the error of the final bang's steps on the exact chain, as a share of
    /// energy (default: 1e-3; none, written `"off"`, leaves the steps unbounded). The joints of an ideal
    /// chain do no work, so the work they do in a step is its error: a step whose error
    /// would take the bang's sum past this share of the energy in play (what it has
    /// dissipated and what still moves), and is over this share of the energy the step
    /// itself moved, is taken again in halves; `bang_step_rad` stays the longest step
    /// (docs/final-bang.md, "A tolerance on the bang's steps", with its cost).
    /// Dimensionless, > 0 and <= 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bang_tolerance: Option<f64>,
    /// Rapier solver iterations per step in the final bang, count (default: 24). Its impacts
    /// must travel along the chain within a step: with too few, the joints give way and
    /// absorb part of each impact.
    pub bang_iterations: u32,
    /// Relax sweeps per substep in the final bang, count (default: 1): the engine's
    /// `num_internal_stabilization_iterations`, Gauss-Seidel sweeps without position bias
    /// after each substep's position update. A contact that starts within a substep is
    /// resolved there: with one sweep an impact's friction and a landing kink's joint are
    /// left unconverged, whatever the substeps; a few sweeps give the exact split (the
    /// figures: `model::work`'s tests and docs/final-bang.md).
    pub bang_relax_iterations: u32,
    /// Shortest rigid piece the remaining wound links are joined into when the final bang
    /// begins, m (default: `tape.thickness_m`; 0 keeps every link its own body). A tape is
    /// the flexible midline the model assumes only on scales longer than its thickness; the
    /// innermost links are far shorter, and would only add spin the step must resolve.
    pub bang_piece_m: f64,
    /// Natural frequency of the engine's soft floor contact, Hz (default: 1e4). The coil
    /// rests on it as on a damped spring and sinks g / (2 pi f)^2 into the floor, and that
    /// sinking is lost energy: rapier's own 60 Hz is far too soft (docs/model.md).
    pub contact_hz: f64,
    /// Natural frequency of the engine's soft joints, Hz (default: 1e7). Links pass the
    /// floor at up to ~10^6 per second in the last turns: joints softer than that act as
    /// damped springs there and lose energy, and much stiffer ones push energy in (the
    /// thin tape's figures, with their commands: docs/model.md).
    pub joint_hz: f64,
    /// Natural frequency of the joints in the final bang, Hz (default: 1e9, rigid at the
    /// bang's steps). The bang's tension grows as the tape's speed squared, and a soft joint
    /// stretches under it and damps the stretch away (the thin tape's figures:
    /// docs/final-bang.md). While rolling, a joint that stiff pushes energy in (see
    /// `joint_hz`); in the bang the step follows the spin and it does not.
    pub bang_joint_hz: f64,
    /// What solves the final bang (default: `"exact"`; `"rapier"` is the cross-check).
    pub bang_engine: BangEngine,
}

/// What solves the final bang (`solver.bang_engine`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BangEngine {
    /// `"exact"`: the exact chain (`model::exact_chain`): the pieces' joints solved
    /// directly at every step, in time linear in the pieces, and the floor's contacts to a
    /// stated tolerance; one solve a step (`bang_iterations`, `bang_relax_iterations` and
    /// `bang_joint_hz` are the engine's and do not apply).
    Exact,
    /// `"rapier"`: the engine's impulse joints, solved by Gauss-Seidel sweeps with the
    /// contacts (`bang_iterations` substeps, `bang_relax_iterations` relax sweeps): the
    /// cross-check.
    Rapier,
}

/// When the simulation ends.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stop {
    /// Coil radius at which the rolling phase ends and the final bang begins, m
    /// (default: `tape.core_radius_m + 2 * tape.thickness_m`, i.e. `2 * thickness_m` for a
    /// solid coil).
    pub bang_radius_m: f64,
    /// Hard stop on simulated time, s (default: 60.0).
    pub max_time_s: f64,
    /// The longest simulated time the final bang may take, s (default: 2.0); 0 ends the run
    /// at the release.
    pub bang_cap_s: f64,
    /// The final bang has come to rest, and the run ends, once the kinetic energy of the
    /// moving tape is below this fraction of the kinetic energy it carried into the bang and
    /// every moving piece touches the floor, dimensionless (default: 0.001).
    pub rest_fraction: f64,
}

/// A validated scene: every value is finite and within its documented range, and the run it
/// asks for is within the budgets ([`MAX_ENGINE_STEPS`], [`MIN_BANG_STEP_RAD`],
/// [`MAX_LINKS`], [`MAX_SAMPLES`], [`MAX_FRAME_NODES`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Scene name (default: the file stem, or the name passed to [`Scene::from_toml_str`]).
    pub name: String,
    /// The tape and its winding (section `[tape]`, required).
    pub tape: Tape,
    /// How finely the tape is cut into links (`[discretisation]`).
    pub discretisation: Discretisation,
    /// The floor (`[floor]`).
    pub floor: Floor,
    /// Gravity (`[gravity]`).
    pub gravity: Gravity,
    /// How the coil is set going (`[push]`).
    pub push: Push,
    /// A fixed axis instead of the floor (`[axis]`).
    pub axis: Axis,
    /// Time-stepping and solver settings (`[solver]`).
    pub solver: Solver,
    /// When the simulation ends (`[stop]`).
    pub stop: Stop,
    /// What is written (`[output]`).
    pub output: Output,
    /// The TOML text as read, for logging.
    pub source_text: String,
}

/// A scene read back (from a report) is parsed again from its own text and name, so it meets
/// the same validation as one loaded from its file: parse, don't validate.
impl<'de> serde::Deserialize<'de> for Scene {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        /// What a serialised scene carries that makes it: its name and its file's text.
        #[derive(serde::Deserialize)]
        struct Written {
            name: String,
            source_text: String,
        }
        let w = Written::deserialize(d)?;
        Scene::from_toml_str(&w.source_text, &w.name).map_err(serde::de::Error::custom)
    }
}

/// `[discretisation]`: how finely the tape is cut into links.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Discretisation {
    /// Links per full turn of the spiral, count (default: 32). Link length scales with the
    /// local radius, so every turn is resolved to the same angle.
    pub links_per_turn: u32,
}

/// `[floor]`: the floor the tape is laid on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Floor {
    /// Coulomb friction coefficient between tape and floor, dimensionless (default: 1.0).
    pub friction: f64,
    /// Slope of the floor, degrees, positive when the rolling direction (+x) is downhill
    /// (default: 0.0). The floor stays the plane `y = 0` of the simulation frame and gravity
    /// is tilted instead: `g = g (sin alpha, -cos alpha)`.
    pub slope_deg: f64,
    /// Whether the tape sticks to the floor where it touches it (sec. 2.1 remark for g = 0):
    /// the coil is then held at its contact line, pulled as well as pushed (default: false).
    pub sticky: bool,
}

/// `[gravity]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Gravity {
    /// Gravitational acceleration, m/s² (default: 9.81).
    pub g_m_s2: f64,
}

/// `[push]`: how the coil is set going.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Push {
    /// Initial speed of the contact line, m/s (default: 0.0, which is rejected: a scene
    /// must set it > 0).
    pub contact_speed_m_s: f64,
}

/// `[axis]`: a fixed axis instead of the floor (App. E).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Axis {
    /// Whether the coil turns about a fixed horizontal axis through the spiral's centre,
    /// the tape hanging from it, instead of rolling on the floor (default: false).
    pub fixed: bool,
}

/// `[output]`: what a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Output {
    /// Time between rows of `samples.csv`, s; 0 samples every step (default: 0.001).
    pub sample_interval_s: f64,
    /// Drawings of the scene (links and ghost coils) per simulated second, Hz; 0 draws
    /// none (default: 100.0), the final bang's own drawings included. Samples are not
    /// affected.
    pub scene_rate_hz: f64,
}

/// A scene of either kind: a coil's (no top-level `kind`) or a folded chain's
/// (`kind = "folded-chain"`).
#[derive(Debug, Clone)]
pub enum AnyScene {
    /// A coil uncoiling on a floor: the product's scene.
    Coil(Box<Scene>),
    /// The falling folded chain: the joints' benchmark.
    FoldedChain(folded::FoldedChain),
}

impl AnyScene {
    /// Its kind, as a file declares it: `coil` or `folded-chain`.
    pub fn kind(&self) -> &'static str {
        match self {
            AnyScene::Coil(_) => "coil",
            AnyScene::FoldedChain(_) => folded::KIND,
        }
    }
}

/// The top-level `kind` a scene's text declares, if it reads as TOML and has one.
pub(crate) fn declared_kind(text: &str) -> Option<toml::Value> {
    toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|mut t| t.remove("kind"))
}

/// The text of the scene file at `path` and its stem, the scene's default name; when no
/// such file exists (or a folder is of that name) and `path` is a shipped scene's name
/// (`yoga-mat`), that scene's.
pub fn read_scene_file(path: &Path) -> Result<(String, String), SceneError> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    match std::fs::read_to_string(path) {
        Ok(text) => Ok((text, stem)),
        Err(source) => match path.to_str().and_then(shipped::text) {
            // No such file, or a folder of that name: the name is the shipped scene's.
            Some(text) if source.kind() == std::io::ErrorKind::NotFound || path.is_dir() => {
                Ok((text.to_owned(), stem))
            }
            _ => Err(SceneError::Read {
                path: path.to_owned(),
                source,
            }),
        },
    }
}

impl SceneError {
    /// This error of the scene read from `path`: a parse error names the file as given,
    /// where it is a file (a shipped scene's keeps its name).
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            SceneError::Parse { message, .. } if path.is_file() => SceneError::Parse {
                name: path.display().to_string(),
                message,
            },
            other => other,
        }
    }
}

impl Scene {
    /// Reads and validates the scene file at `path`; the scene name defaults to the file
    /// stem.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let (text, stem) = read_scene_file(path.as_ref())?;
        Self::from_toml_str(&text, &stem).map_err(|e| e.in_file(path.as_ref()))
    }

    /// Parses and validates scene TOML `text`; `name` is used when the text has no
    /// top-level `name` key.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Scene, SceneError> {
        let file: file::SceneFile =
            toml::from_str(text).map_err(|e| rules::parse_error(name, &e))?;
        Self::validate(file, name, text)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    //! Loading the shipped scenes; the helpers the scene layer's tests share.

    use super::*;
    use approx::assert_relative_eq;

    /// The smallest valid scene: the yoga mat's required keys, everything else defaulted.
    pub(crate) const MINIMAL: &str = "
[tape]
outer_radius_m = 0.06
thickness_m = 0.005
mass_kg = 1.5

[push]
contact_speed_m_s = 0.3
";

    /// The yoga mat run for `max_time_s` of simulated time and drawn never: a short run for
    /// the tests of what a run hands its observers.
    pub(crate) fn short_yoga(max_time_s: f64) -> Scene {
        let text = format!("{MINIMAL}\n[stop]\nmax_time_s = {max_time_s}\n");
        let mut scene = Scene::from_toml_str(&text, "short").expect("a valid scene");
        scene.output.scene_rate_hz = 0.0;
        scene
    }

    pub(crate) fn shipped(name: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(format!("{name}.toml"));
        Scene::from_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// Error text of loading `text`, which must fail.
    pub(crate) fn err(text: &str) -> String {
        match Scene::from_toml_str(text, "test") {
            Ok(s) => panic!("expected an error, got {s:?}"),
            Err(e) => e.to_string(),
        }
    }

    /// `MINIMAL` with `key = value` set in `[section]` (replacing an existing key).
    pub(crate) fn with(section: &str, key: &str, value: &str) -> String {
        let mut out = String::new();
        let mut in_section = false;
        let mut done = false;
        for line in MINIMAL.lines() {
            if line.starts_with('[') {
                if in_section && !done {
                    out.push_str(&format!("{key} = {value}\n"));
                    done = true;
                }
                in_section = line == format!("[{section}]");
            }
            if in_section && line.split('=').next().map(str::trim) == Some(key) {
                out.push_str(&format!("{key} = {value}\n"));
                done = true;
                continue;
            }
            out.push_str(line);
            out.push('\n');
        }
        if !done {
            if !in_section {
                out.push_str(&format!("[{section}]\n"));
            }
            out.push_str(&format!("{key} = {value}\n"));
        }
        out
    }

    /// Asserts that setting `section.key = value` is rejected with a message naming the key.
    pub(crate) fn rejects(section: &str, key: &str, value: &str) -> String {
        let msg = err(&with(section, key, value));
        assert!(
            msg.starts_with(&format!("{section}.{key} = ")),
            "{section}.{key} = {value}: message does not name the key: {msg}"
        );
        msg
    }

    #[test]
    fn yoga_mat_loads() {
        let s = shipped("yoga-mat");
        assert_eq!(s.name, "yoga-mat");
        assert_relative_eq!(s.tape.outer_radius_m, 0.06);
        assert_relative_eq!(s.tape.thickness_m, 0.005);
        assert_relative_eq!(s.tape.mass_kg, 1.5);
        assert_relative_eq!(s.tape.core_radius_m, 0.0);
        assert_eq!(s.discretisation.links_per_turn, 32);
        assert_relative_eq!(s.floor.friction, 1.0);
        assert_relative_eq!(s.gravity.g_m_s2, 9.81);
        assert_relative_eq!(s.push.contact_speed_m_s, 0.3);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_relative_eq!(s.stop.bang_radius_m, 0.005);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.output.scene_rate_hz, 100.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.stop.rest_fraction, 0.001);
        assert_relative_eq!(s.output.sample_interval_s, 0.001);
        assert!(s.source_text.contains("[tape]"));
    }

    #[test]
    fn thin_tape_loads() {
        let s = shipped("thin-tape");
        assert_eq!(s.name, "thin-tape");
        assert_relative_eq!(s.tape.outer_radius_m, 0.03);
        assert_relative_eq!(s.tape.thickness_m, 0.0001);
        assert_relative_eq!(s.tape.mass_kg, 0.2);
        assert_relative_eq!(s.tape.core_radius_m, 0.0);
        assert_eq!(s.discretisation.links_per_turn, 40);
        assert_relative_eq!(s.floor.friction, 1.0);
        assert_relative_eq!(s.gravity.g_m_s2, 9.81);
        assert_relative_eq!(s.push.contact_speed_m_s, 0.1);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_relative_eq!(s.stop.bang_radius_m, 0.0002);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.solver.bang_piece_m, 0.0005);
        assert_eq!(s.solver.bang_engine, BangEngine::Exact);
        assert_relative_eq!(s.output.sample_interval_s, 0.001);
    }

    #[test]
    fn shipped_scenes_equal_their_defaults() {
        // The shipped files write out default values; dropping them must not change the scene.
        // The yoga mat sets two values off their defaults: it rolls on to r = b (given in
        // thicknesses), and its bang is on the exact chain.
        let s = shipped("yoga-mat");
        let text =
            format!("{MINIMAL}[solver]\nbang_engine = \"exact\"\n[stop]\nbang_radius_m = 0.005\n");
        let d = Scene::from_toml_str(&text, "yoga-mat").unwrap();
        assert_eq!(
            Scene {
                source_text: String::new(),
                ..s
            },
            Scene {
                source_text: String::new(),
                ..d
            }
        );
    }

    #[test]
    fn variant_keys_default_off_and_the_variant_scenes_set_them() {
        let s = Scene::from_toml_str(MINIMAL, "t").unwrap();
        assert_relative_eq!(s.floor.slope_deg, 0.0);
        assert!(!s.floor.sticky && !s.axis.fixed);
        assert_relative_eq!(shipped("slope-down").floor.slope_deg, 5.0);
        assert_relative_eq!(shipped("slope-up").floor.slope_deg, -2.0);
        assert!(shipped("zero-g").floor.sticky);
        assert!(shipped("vertical").axis.fixed);
        for name in ["single-turn", "spool", "frictionless-spool"] {
            assert!(shipped(name).tape.core_radius_m > 0.0, "{name}");
        }
        for name in ["frictionless-spool", "frictionless-coil"] {
            assert_relative_eq!(shipped(name).floor.friction, 0.0);
        }
    }

    #[test]
    fn read_error_names_path() {
        let e = Scene::from_file("/nonexistent/scene.toml").unwrap_err();
        assert!(matches!(e, SceneError::Read { .. }));
        assert!(e.to_string().contains("/nonexistent/scene.toml"), "{e}");
    }

    #[test]
    fn scene_serialises() {
        let json = serde_json::to_value(shipped("yoga-mat")).unwrap();
        // The scene serialises with its file's sections and keys.
        assert_eq!(json["tape"]["mass_kg"], 1.5);
        assert_eq!(json["push"]["contact_speed_m_s"], 0.3);
        assert_eq!(json["discretisation"]["links_per_turn"], 32);
        assert_eq!(json["axis"]["fixed"], false);
        assert!(json.get("contact_model").is_none());
    }
    #[test]
    fn every_shipped_scene_loads_but_the_one_rejected_on_purpose() {
        // scenes/hard/one-link-per-turn.toml is a hard case that no tape allows: `uncoil
        // check` reports it as rejected (see its comment).
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut loaded = 0;
        for dir in [root.clone(), root.join("hard")] {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_none_or(|e| e != "toml") {
                    continue;
                }
                let result = Scene::from_file(&path);
                if path.ends_with("hard/one-link-per-turn.toml") {
                    let e = result.unwrap_err().to_string();
                    assert!(
                        e.starts_with("discretisation.links_per_turn = 1: a link must be shorter"),
                        "{e}"
                    );
                } else {
                    result.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                    loaded += 1;
                }
            }
        }
        assert!(loaded >= 22, "only {loaded} scenes found");
    }
}
