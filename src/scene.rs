//! Scene files: parses a TOML scene description and validates it into a [`Scene`] of plain
//! numbers; it does not simulate anything, derive physical quantities, or re-check a `Scene`
//! after construction (a `Scene` that exists is valid).
//!
//! The TOML is read into a private serde mirror (`SceneFile`, every section
//! `deny_unknown_fields`, defaults filled by serde), then every value is checked once, in
//! dependency order, and the first violation is reported as [`SceneError::Invalid`] naming
//! the key with its section path, the offending value and the rule.

pub mod overrides;

use std::fmt::Display;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

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
/// Default `solver.contact_hz`.
const DEFAULT_CONTACT_HZ: f64 = 1.0e4;
/// Default `solver.joint_hz`.
const DEFAULT_JOINT_HZ: f64 = 1.0e7;
/// Default `solver.bang_joint_hz`.
const DEFAULT_BANG_JOINT_HZ: f64 = 1.0e9;
/// Default `stop.max_time_s`.
const DEFAULT_MAX_TIME_S: f64 = 60.0;
/// Default `solver.bang_iterations`.
const DEFAULT_BANG_ITERATIONS: i64 = 24;
/// Default `stop.bang_cap_s`.
const DEFAULT_BANG_CAP_S: f64 = 2.0;
/// Default `stop.rest_fraction`.
const DEFAULT_REST_FRACTION: f64 = 0.001;
/// Default `output.sample_interval_s`.
const DEFAULT_SAMPLE_INTERVAL_S: f64 = 0.001;
/// Default `output.scene_rate_hz`: 100 drawings per simulated second, enough to watch the
/// final bang (0.05 s) over a few frames.
const DEFAULT_SCENE_RATE_HZ: f64 = 100.0;

/// Bounds of `discretisation.links_per_turn`.
const LINKS_PER_TURN_RANGE: std::ops::RangeInclusive<i64> = 3..=4096;
/// Bounds of `solver.iterations`.
const ITERATIONS_RANGE: std::ops::RangeInclusive<i64> = 1..=1000;
/// Bounds of `tape.outer_radius_m` (m): the engine's tolerances scale with R (its length
/// unit is R/10), and they were tuned for coils from a millimetre to metres.
const OUTER_RADIUS_RANGE_M: std::ops::RangeInclusive<f64> = 0.001..=100.0;
/// Upper bound of `tape.mass_kg` (kg).
const MAX_MASS_KG: f64 = 1.0e6;
/// Upper bound of the number of links of a tape (turns times `links_per_turn`): the model
/// keeps every link's geometry in memory.
const MAX_LINKS: f64 = 1.0e6;
/// Upper bound of `solver.steps_per_link`.
const MAX_STEPS_PER_LINK: f64 = 1000.0;
/// Upper bound of `stop.max_time_s` (s).
const MAX_MAX_TIME_S: f64 = 1.0e4;
/// Upper bound of `gravity.g_m_s2` (m/s²).
const MAX_G_M_S2: f64 = 1000.0;
/// Upper bound of `push.contact_speed_m_s` (m/s).
const MAX_CONTACT_SPEED_M_S: f64 = 1000.0;
/// Upper bound of `solver.max_dt_s` (s).
const MAX_MAX_DT_S: f64 = 0.1;
/// Bound of `floor.slope_deg` (degrees, either sign).
const MAX_SLOPE_DEG: f64 = 45.0;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file {}: {source}", path.display())]
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

/// How the links of the coil touch each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactModel {
    /// Contacts between neighbouring turns of the spiral (`"spiral"`).
    #[default]
    Spiral,
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
    /// Rapier solver iterations per step in the final bang, count (default: 24). Its impacts
    /// must travel along the chain within a step: with too few, the joints give way and
    /// absorb part of each impact.
    pub bang_iterations: u32,
    /// Shortest rigid piece the remaining wound links are joined into when the final bang
    /// begins, m (default: `tape.thickness_m`; 0 keeps every link its own body). A tape is
    /// the flexible midline the model assumes only on scales longer than its thickness; the
    /// innermost links are far shorter, and would only add spin the step must resolve.
    pub bang_piece_m: f64,
    /// Natural frequency of the engine's soft floor contact, Hz (default: 1e4). The coil
    /// rests on it as on a damped spring and sinks g / (2 pi f)^2 into the floor: rapier's
    /// 60 Hz lets it sink 69 um, and that sinking is lost energy.
    pub contact_hz: f64,
    /// Natural frequency of the engine's soft joints, Hz (default: 1e7). Links pass the
    /// floor at up to ~10^6 per second in the last turns: joints softer than that act as
    /// damped springs there (thin tape: rapier's 1 MHz loses 15.4 % of E0 before r = 2b),
    /// and much stiffer ones push energy in (1e8: E0 + 0.35 % at r = 2b).
    pub joint_hz: f64,
    /// Natural frequency of the joints in the final bang, Hz (default: 1e9, rigid at the
    /// bang's steps). The bang's tension grows as the tape's speed squared, and a soft joint
    /// stretches under it and damps the stretch away: at `joint_hz`'s 1e7 the thin tape
    /// loses 50 % of what the bang received to its joints within 20 us of the release, with
    /// no floor touched (1e9: 20 %, and 3 % at a bang step of 0.05 rad), and the spool's
    /// numerical share is 9.5 % (1e9: 0.1 %). While rolling, a joint that stiff pushes
    /// energy in (see `joint_hz`); in the bang the step follows the spin and it does not.
    pub bang_joint_hz: f64,
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

/// A validated scene: every value is finite and within its documented range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Scene name (default: the file stem, or the name passed to [`Scene::from_toml_str`]).
    pub name: String,
    /// The tape and its winding (section `[tape]`, required).
    pub tape: Tape,
    /// Links per full turn of the spiral, count (default: 32). Link length scales with the
    /// local radius, so every turn is resolved to the same angle.
    pub links_per_turn: u32,
    /// Coulomb friction coefficient between tape and floor, dimensionless (default: 1.0).
    pub friction: f64,
    /// Slope of the floor, degrees, positive when the rolling direction (+x) is downhill
    /// (default: 0.0). The floor stays the plane `y = 0` of the simulation frame and gravity
    /// is tilted instead: `g = g (sin alpha, -cos alpha)`.
    pub slope_deg: f64,
    /// Whether the tape sticks to the floor where it touches it (sec. 2.1 remark for g = 0):
    /// the coil is then held at its contact line, pulled as well as pushed (default: false).
    pub sticky: bool,
    /// Whether the coil turns about a fixed horizontal axis through the spiral's centre,
    /// the tape hanging from it (App. E), instead of rolling on the floor (default: false).
    pub fixed_axis: bool,
    /// Gravitational acceleration, m/s² (default: 9.81).
    pub g_m_s2: f64,
    /// Initial speed of the contact line, m/s (default: 0.0, which is rejected: a scene
    /// must set it > 0).
    pub push_speed_m_s: f64,
    /// Time-stepping and solver settings.
    pub solver: Solver,
    /// How the links of the coil touch each other (default: [`ContactModel::Spiral`]).
    pub contact_model: ContactModel,
    /// When the simulation ends.
    pub stop: Stop,
    /// Time between rows of `samples.csv`, s; 0 samples every step (default: 0.001).
    pub sample_interval_s: f64,
    /// Drawings of the scene (links and ghost coils) per simulated second, Hz; 0 draws
    /// none (default: 100.0). Samples are not affected.
    pub scene_rate_hz: f64,
    /// The TOML text as read, for logging.
    pub source_text: String,
}

// ---------------------------------------------------------------------------------------
// Serde mirror of the file. Integers are read as i64 so that out-of-range values reach
// validation and get the same `key = value: rule` message as floats.

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    tape: TapeFile,
    #[serde(default)]
    discretisation: DiscretisationFile,
    #[serde(default)]
    floor: FloorFile,
    #[serde(default)]
    gravity: GravityFile,
    #[serde(default)]
    push: PushFile,
    #[serde(default)]
    solver: SolverFile,
    #[serde(default)]
    contact: ContactFile,
    #[serde(default)]
    stop: StopFile,
    #[serde(default)]
    axis: AxisFile,
    #[serde(default)]
    output: OutputFile,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TapeFile {
    outer_radius_m: f64,
    thickness_m: f64,
    mass_kg: f64,
    #[serde(default)]
    core_radius_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct DiscretisationFile {
    links_per_turn: i64,
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
struct FloorFile {
    friction: f64,
    slope_deg: f64,
    sticky: bool,
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
struct GravityFile {
    g_m_s2: f64,
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
struct PushFile {
    contact_speed_m_s: f64,
}

impl Default for PushFile {
    fn default() -> Self {
        Self {
            contact_speed_m_s: DEFAULT_CONTACT_SPEED_M_S,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct SolverFile {
    max_dt_s: f64,
    steps_per_link: f64,
    iterations: i64,
    freeze_speed_m_s: f64,
    bang_step_rad: f64,
    bang_iterations: i64,
    /// `None` means "the tape's thickness" (see [`Solver::bang_piece_m`]).
    bang_piece_m: Option<f64>,
    contact_hz: f64,
    joint_hz: f64,
    bang_joint_hz: f64,
}

impl Default for SolverFile {
    fn default() -> Self {
        Self {
            max_dt_s: DEFAULT_MAX_DT_S,
            steps_per_link: DEFAULT_STEPS_PER_LINK,
            iterations: DEFAULT_ITERATIONS,
            freeze_speed_m_s: DEFAULT_FREEZE_SPEED_M_S,
            bang_step_rad: DEFAULT_BANG_STEP_RAD,
            bang_iterations: DEFAULT_BANG_ITERATIONS,
            bang_piece_m: None,
            contact_hz: DEFAULT_CONTACT_HZ,
            joint_hz: DEFAULT_JOINT_HZ,
            bang_joint_hz: DEFAULT_BANG_JOINT_HZ,
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ContactFile {
    model: ContactModel,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct StopFile {
    /// `None` means "derive from the tape" (see [`Stop::bang_radius_m`]).
    bang_radius_m: Option<f64>,
    max_time_s: f64,
    bang_cap_s: f64,
    rest_fraction: f64,
}

impl Default for StopFile {
    fn default() -> Self {
        Self {
            bang_radius_m: None,
            max_time_s: DEFAULT_MAX_TIME_S,
            bang_cap_s: DEFAULT_BANG_CAP_S,
            rest_fraction: DEFAULT_REST_FRACTION,
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct AxisFile {
    fixed: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct OutputFile {
    sample_interval_s: f64,
    scene_rate_hz: f64,
}

impl Default for OutputFile {
    fn default() -> Self {
        Self {
            sample_interval_s: DEFAULT_SAMPLE_INTERVAL_S,
            scene_rate_hz: DEFAULT_SCENE_RATE_HZ,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Validation helpers.

fn invalid(key: &str, value: impl Display, rule: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        key: key.to_owned(),
        value: value.to_string(),
        rule: rule.into(),
    }
}

/// A float as written in messages: plainly, or in exponent form when huge or tiny (so that
/// `1e300` does not print 301 digits).
struct Shown(f64);

impl Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0.abs();
        if v >= 1e15 || (v > 0.0 && v < 1e-6) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Rejects NaN and infinities, then returns `value` if `ok`, else an error with `rule`.
/// `ok` is evaluated by the caller; for a non-finite value the finiteness error wins.
/// The text of the scene file at `path` and its stem, the scene's default name.
pub(crate) fn read_scene_file(path: &Path) -> Result<(String, String), SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
        path: path.to_owned(),
        source,
    })?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok((text, stem))
}

fn check(key: &str, value: f64, ok: bool, rule: impl Into<String>) -> Result<f64, SceneError> {
    if !value.is_finite() {
        return Err(invalid(key, value, "must be finite"));
    }
    if ok {
        Ok(value)
    } else {
        Err(invalid(key, Shown(value), rule))
    }
}

/// Returns `value` as `u32` if it lies in `range`, else an error with `rule`.
fn check_int(
    key: &str,
    value: i64,
    range: &std::ops::RangeInclusive<i64>,
) -> Result<u32, SceneError> {
    match u32::try_from(value) {
        Ok(v) if range.contains(&value) => Ok(v),
        _ => Err(invalid(
            key,
            value,
            format!("must be >= {} and <= {}", range.start(), range.end()),
        )),
    }
}

impl Scene {
    /// Reads and validates the scene file at `path`; the scene name defaults to the file
    /// stem.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let (text, stem) = read_scene_file(path.as_ref())?;
        Self::from_toml_str(&text, &stem)
    }

    /// Parses and validates scene TOML `text`; `name` is used when the text has no
    /// top-level `name` key.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            name: name.to_owned(),
            message: e.to_string(),
        })?;
        Self::validate(file, name, text)
    }

    /// Checks every value of `file` once, in dependency order (later rules may rely on
    /// earlier values being valid).
    fn validate(file: SceneFile, default_name: &str, text: &str) -> Result<Scene, SceneError> {
        let name = file.name.unwrap_or_else(|| default_name.to_owned());
        if name.trim().is_empty() {
            return Err(invalid("name", format!("{name:?}"), "must not be empty"));
        }

        // [tape]
        let t = &file.tape;
        let r = check(
            "tape.outer_radius_m",
            t.outer_radius_m,
            OUTER_RADIUS_RANGE_M.contains(&t.outer_radius_m),
            format!(
                "must be >= {} and <= {}",
                OUTER_RADIUS_RANGE_M.start(),
                OUTER_RADIUS_RANGE_M.end()
            ),
        )?;
        let b = check(
            "tape.thickness_m",
            t.thickness_m,
            t.thickness_m > 0.0 && t.thickness_m < r / 2.0,
            format!(
                "must be > 0 and < tape.outer_radius_m / 2 (= {}): at least one full turn",
                r / 2.0
            ),
        )?;
        let mass = check(
            "tape.mass_kg",
            t.mass_kg,
            t.mass_kg > 0.0 && t.mass_kg <= MAX_MASS_KG,
            format!("must be > 0 and <= {MAX_MASS_KG}"),
        )?;
        let core = check(
            "tape.core_radius_m",
            t.core_radius_m,
            // Relative slack of 1e-12: 0.050001 - 2 * 1e-6 is 0.049998999999999995 in f64,
            // and a core written as 0.049999 must pass.
            t.core_radius_m >= 0.0 && t.core_radius_m + 2.0 * b <= r * (1.0 + 1e-12),
            format!(
                "must be >= 0 and <= tape.outer_radius_m - 2 * tape.thickness_m (= {}): \
                 must leave at least one full turn of the tape's midline",
                r - 2.0 * b
            ),
        )?;
        let tape = Tape {
            outer_radius_m: r,
            thickness_m: b,
            mass_kg: mass,
            core_radius_m: core,
        };

        // [discretisation]
        // A link must be shorter than the outer radius: 2 pi (R - b/2) / n <= R. Values
        // from 1 up get this rule (one link per turn would be a chord of a whole turn), the
        // range check only catches what no tape allows.
        let key = "discretisation.links_per_turn";
        let raw = file.discretisation.links_per_turn;
        let outer_arc_m = 2.0 * std::f64::consts::PI * (r - b / 2.0);
        #[allow(clippy::cast_possible_truncation)]
        let coarsest = ((outer_arc_m / r).ceil() as i64).max(*LINKS_PER_TURN_RANGE.start());
        #[allow(clippy::cast_precision_loss)]
        let too_long = |n: i64| {
            let outer_link_m = outer_arc_m / n as f64;
            invalid(
                key,
                n,
                format!(
                    "a link must be shorter than the outer radius (outermost link {outer_link_m} m \
                     > tape.outer_radius_m = {r} m): the coarsest this tape allows is \
                     {coarsest} links per turn"
                ),
            )
        };
        if (1..coarsest).contains(&raw) {
            return Err(too_long(raw));
        }
        let links_per_turn = check_int(key, raw, &LINKS_PER_TURN_RANGE)?;
        if outer_arc_m / f64::from(links_per_turn) > r {
            return Err(too_long(raw));
        }
        let links = (r - core - b) / b * f64::from(links_per_turn);
        if links > MAX_LINKS {
            return Err(invalid(
                key,
                links_per_turn,
                format!(
                    "the tape would have {links:.0} links ({:.0} turns), more than {MAX_LINKS:.0}: \
                     use fewer links per turn or a thicker tape",
                    (r - core - b) / b
                ),
            ));
        }

        // [floor], [gravity], [push]
        let friction = check(
            "floor.friction",
            file.floor.friction,
            file.floor.friction >= 0.0,
            "must be >= 0",
        )?;
        let slope = file.floor.slope_deg;
        let slope_deg = check(
            "floor.slope_deg",
            slope,
            slope.abs() < MAX_SLOPE_DEG,
            format!("must be > -{MAX_SLOPE_DEG} and < {MAX_SLOPE_DEG}"),
        )?;
        let g = file.gravity.g_m_s2;
        let g = check(
            "gravity.g_m_s2",
            g,
            (0.0..=MAX_G_M_S2).contains(&g),
            format!("must be >= 0 and <= {MAX_G_M_S2}"),
        )?;
        let key = "push.contact_speed_m_s";
        let v = file.push.contact_speed_m_s;
        let push = check(
            key,
            v,
            (0.0..=MAX_CONTACT_SPEED_M_S).contains(&v),
            format!("must be > 0 and <= {MAX_CONTACT_SPEED_M_S}"),
        )?;
        if push <= 0.0 {
            let rule = if g <= 0.0 {
                "must be > 0 when gravity.g_m_s2 = 0: nothing would move"
            } else {
                "must be > 0: a coil at rest on a level floor stays at rest"
            };
            return Err(invalid(key, push, rule));
        }

        // [solver]
        let s = &file.solver;
        let solver = Solver {
            max_dt_s: check(
                "solver.max_dt_s",
                s.max_dt_s,
                s.max_dt_s > 0.0 && s.max_dt_s <= MAX_MAX_DT_S,
                format!("must be > 0 and <= {MAX_MAX_DT_S}"),
            )?,
            steps_per_link: check(
                "solver.steps_per_link",
                s.steps_per_link,
                (1.0..=MAX_STEPS_PER_LINK).contains(&s.steps_per_link),
                format!("must be >= 1 and <= {MAX_STEPS_PER_LINK}"),
            )?,
            iterations: check_int("solver.iterations", s.iterations, &ITERATIONS_RANGE)?,
            freeze_speed_m_s: check(
                "solver.freeze_speed_m_s",
                s.freeze_speed_m_s,
                s.freeze_speed_m_s >= 0.0,
                "must be >= 0",
            )?,
            bang_step_rad: check(
                "solver.bang_step_rad",
                s.bang_step_rad,
                s.bang_step_rad > 0.0 && s.bang_step_rad <= 1.0,
                "must be > 0 and <= 1",
            )?,
            bang_iterations: check_int(
                "solver.bang_iterations",
                s.bang_iterations,
                &ITERATIONS_RANGE,
            )?,
            bang_piece_m: check(
                "solver.bang_piece_m",
                s.bang_piece_m.unwrap_or(b),
                s.bang_piece_m.unwrap_or(b) >= 0.0,
                "must be >= 0",
            )?,
            contact_hz: check(
                "solver.contact_hz",
                s.contact_hz,
                s.contact_hz > 0.0,
                "must be > 0",
            )?,
            joint_hz: check(
                "solver.joint_hz",
                s.joint_hz,
                s.joint_hz > 0.0,
                "must be > 0",
            )?,
            bang_joint_hz: check(
                "solver.bang_joint_hz",
                s.bang_joint_hz,
                s.bang_joint_hz > 0.0,
                "must be > 0",
            )?,
        };

        // [contact]
        let contact_model = file.contact.model;

        // [stop]
        let st = &file.stop;
        let (bang, defaulted) = match st.bang_radius_m {
            Some(v) => (v, ""),
            None => (
                core + 2.0 * b,
                " (defaulted to tape.core_radius_m + 2 * tape.thickness_m; set it explicitly)",
            ),
        };
        let stop = Stop {
            bang_radius_m: check(
                "stop.bang_radius_m",
                bang,
                core < bang && bang < r,
                format!(
                    "must be > tape.core_radius_m (= {core}) \
                     and < tape.outer_radius_m (= {r}){defaulted}"
                ),
            )?,
            max_time_s: check(
                "stop.max_time_s",
                st.max_time_s,
                st.max_time_s > 0.0 && st.max_time_s <= MAX_MAX_TIME_S,
                format!("must be > 0 and <= {MAX_MAX_TIME_S}"),
            )?,
            bang_cap_s: check(
                "stop.bang_cap_s",
                st.bang_cap_s,
                st.bang_cap_s >= 0.0,
                "must be >= 0",
            )?,
            rest_fraction: check(
                "stop.rest_fraction",
                st.rest_fraction,
                st.rest_fraction > 0.0 && st.rest_fraction < 1.0,
                "must be > 0 and < 1",
            )?,
        };

        // [output]
        let sample_interval_s = check(
            "output.sample_interval_s",
            file.output.sample_interval_s,
            file.output.sample_interval_s >= 0.0,
            "must be >= 0",
        )?;
        let scene_rate_hz = check(
            "output.scene_rate_hz",
            file.output.scene_rate_hz,
            file.output.scene_rate_hz >= 0.0,
            "must be >= 0",
        )?;

        Ok(Scene {
            name,
            tape,
            links_per_turn,
            friction,
            slope_deg,
            sticky: file.floor.sticky,
            fixed_axis: file.axis.fixed,
            g_m_s2: g,
            push_speed_m_s: push,
            solver,
            contact_model,
            stop,
            sample_interval_s,
            scene_rate_hz,
            source_text: text.to_owned(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const MINIMAL: &str = "
[tape]
outer_radius_m = 0.06
thickness_m = 0.005
mass_kg = 1.5

[push]
contact_speed_m_s = 0.3
";

    fn shipped(name: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(format!("{name}.toml"));
        Scene::from_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// Error text of loading `text`, which must fail.
    fn err(text: &str) -> String {
        match Scene::from_toml_str(text, "test") {
            Ok(s) => panic!("expected an error, got {s:?}"),
            Err(e) => e.to_string(),
        }
    }

    /// `MINIMAL` with `key = value` set in `[section]` (replacing an existing key).
    fn with(section: &str, key: &str, value: &str) -> String {
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
    fn rejects(section: &str, key: &str, value: &str) -> String {
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
        assert_eq!(s.links_per_turn, 32);
        assert_relative_eq!(s.friction, 1.0);
        assert_relative_eq!(s.g_m_s2, 9.81);
        assert_relative_eq!(s.push_speed_m_s, 0.3);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_eq!(s.contact_model, ContactModel::Spiral);
        assert_relative_eq!(s.stop.bang_radius_m, 0.005);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.scene_rate_hz, 100.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.stop.rest_fraction, 0.001);
        assert_relative_eq!(s.sample_interval_s, 0.001);
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
        assert_eq!(s.links_per_turn, 40);
        assert_relative_eq!(s.friction, 1.0);
        assert_relative_eq!(s.g_m_s2, 9.81);
        assert_relative_eq!(s.push_speed_m_s, 0.1);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_eq!(s.contact_model, ContactModel::Spiral);
        assert_relative_eq!(s.stop.bang_radius_m, 0.0002);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.solver.bang_piece_m, 0.0001);
        assert_relative_eq!(s.sample_interval_s, 0.001);
    }

    #[test]
    fn shipped_scenes_equal_their_defaults() {
        // The shipped files write out default values; dropping them must not change the scene.
        // The yoga mat sets one value off its default: it rolls on to r = b.
        let s = shipped("yoga-mat");
        let text = format!("{MINIMAL}[stop]\nbang_radius_m = 0.005\n");
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
        assert_relative_eq!(s.slope_deg, 0.0);
        assert!(!s.sticky && !s.fixed_axis);
        assert_relative_eq!(shipped("slope-down").slope_deg, 5.0);
        assert_relative_eq!(shipped("slope-up").slope_deg, -2.0);
        assert!(shipped("zero-g").sticky);
        assert!(shipped("vertical").fixed_axis);
        for name in ["single-turn", "spool", "frictionless-spool"] {
            assert!(shipped(name).tape.core_radius_m > 0.0, "{name}");
        }
        for name in ["frictionless-spool", "frictionless-coil"] {
            assert_relative_eq!(shipped(name).friction, 0.0);
        }
    }

    #[test]
    fn defaults_applied() {
        let s = Scene::from_toml_str(MINIMAL, "fallback").unwrap();
        assert_eq!(s.name, "fallback");
        assert_relative_eq!(s.tape.core_radius_m, 0.0);
        assert_eq!(s.links_per_turn, 32);
        assert_relative_eq!(s.friction, 1.0);
        assert_relative_eq!(s.g_m_s2, 9.81);
        assert_relative_eq!(s.solver.max_dt_s, 0.001);
        assert_relative_eq!(s.solver.steps_per_link, 4.0);
        assert_eq!(s.solver.iterations, 4);
        assert_relative_eq!(s.solver.freeze_speed_m_s, 0.001);
        assert_eq!(s.contact_model, ContactModel::Spiral);
        assert_relative_eq!(s.stop.bang_radius_m, 2.0 * 0.005);
        assert_relative_eq!(s.stop.max_time_s, 60.0);
        assert_relative_eq!(s.stop.bang_cap_s, 2.0);
        assert_relative_eq!(s.stop.rest_fraction, 0.001);
        assert_relative_eq!(s.sample_interval_s, 0.001);
        assert_eq!(s.source_text, MINIMAL);
    }

    #[test]
    fn name_key_overrides_fallback() {
        let s = Scene::from_toml_str(&format!("name = \"mine\"\n{MINIMAL}"), "fallback").unwrap();
        assert_eq!(s.name, "mine");
        assert!(err(&format!("name = \" \"\n{MINIMAL}")).starts_with("name = "));
    }

    #[test]
    fn integer_literal_accepted_for_float() {
        let s = Scene::from_toml_str(&with("tape", "mass_kg", "2"), "t").unwrap();
        assert_relative_eq!(s.tape.mass_kg, 2.0);
    }

    #[test]
    fn default_bang_radius_follows_core() {
        let s = Scene::from_toml_str(&with("tape", "core_radius_m", "0.02"), "t").unwrap();
        assert_relative_eq!(s.stop.bang_radius_m, 0.03);
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
    fn read_error_names_path() {
        let e = Scene::from_file("/nonexistent/scene.toml").unwrap_err();
        assert!(matches!(e, SceneError::Read { .. }));
        assert!(e.to_string().contains("/nonexistent/scene.toml"), "{e}");
    }

    #[test]
    fn non_finite_rejected() {
        for (section, key) in [
            ("tape", "outer_radius_m"),
            ("tape", "thickness_m"),
            ("tape", "mass_kg"),
            ("tape", "core_radius_m"),
            ("floor", "friction"),
            ("gravity", "g_m_s2"),
            ("push", "contact_speed_m_s"),
            ("solver", "max_dt_s"),
            ("solver", "steps_per_link"),
            ("solver", "freeze_speed_m_s"),
            ("solver", "bang_step_rad"),
            ("solver", "bang_piece_m"),
            ("solver", "contact_hz"),
            ("solver", "joint_hz"),
            ("solver", "bang_joint_hz"),
            ("stop", "bang_radius_m"),
            ("stop", "max_time_s"),
            ("stop", "bang_cap_s"),
            ("stop", "rest_fraction"),
            ("output", "sample_interval_s"),
            ("output", "scene_rate_hz"),
        ] {
            let msg = rejects(section, key, "nan");
            assert_eq!(msg, format!("{section}.{key} = NaN: must be finite"));
            let msg = rejects(section, key, "inf");
            assert_eq!(msg, format!("{section}.{key} = inf: must be finite"));
        }
    }

    #[test]
    fn numeric_rules() {
        let msg = rejects("tape", "thickness_m", "-0.001");
        assert!(
            msg.starts_with("tape.thickness_m = -0.001: must be > 0 and < tape.outer_radius_m / 2"),
            "{msg}"
        );
        for (section, key, bad) in [
            ("tape", "outer_radius_m", "0.0"),
            ("tape", "outer_radius_m", "-1.0"),
            ("tape", "thickness_m", "0.0"),
            ("tape", "thickness_m", "0.03"),
            ("tape", "mass_kg", "0.0"),
            ("tape", "core_radius_m", "-0.01"),
            ("tape", "core_radius_m", "0.0501"),
            ("discretisation", "links_per_turn", "2"),
            ("discretisation", "links_per_turn", "-1"),
            ("discretisation", "links_per_turn", "4097"),
            ("discretisation", "links_per_turn", "5"),
            ("floor", "friction", "-0.1"),
            ("floor", "slope_deg", "45.0"),
            ("floor", "slope_deg", "-45.0"),
            ("gravity", "g_m_s2", "-9.81"),
            ("gravity", "g_m_s2", "1000.1"),
            ("push", "contact_speed_m_s", "-0.3"),
            ("push", "contact_speed_m_s", "1000.1"),
            ("push", "contact_speed_m_s", "0.0"),
            ("solver", "max_dt_s", "0.0"),
            ("solver", "max_dt_s", "0.2"),
            ("solver", "steps_per_link", "0.5"),
            ("solver", "iterations", "0"),
            ("solver", "iterations", "1001"),
            ("solver", "iterations", "-4"),
            ("solver", "freeze_speed_m_s", "-0.001"),
            ("solver", "bang_step_rad", "0.0"),
            ("solver", "bang_step_rad", "1.5"),
            ("solver", "contact_hz", "0.0"),
            ("solver", "joint_hz", "-1.0"),
            ("solver", "bang_joint_hz", "0.0"),
            ("stop", "bang_radius_m", "0.0"),
            ("stop", "bang_radius_m", "0.06"),
            ("stop", "max_time_s", "0.0"),
            ("stop", "bang_cap_s", "-0.01"),
            ("stop", "rest_fraction", "0.0"),
            ("stop", "rest_fraction", "1.0"),
            ("solver", "bang_piece_m", "-0.001"),
            ("solver", "bang_iterations", "0"),
            ("solver", "bang_iterations", "1001"),
            ("output", "sample_interval_s", "-0.001"),
            ("tape", "outer_radius_m", "100.1"),
            ("tape", "outer_radius_m", "0.0009"),
            ("tape", "mass_kg", "1e7"),
            ("solver", "steps_per_link", "1001"),
            ("stop", "max_time_s", "1e5"),
            ("output", "scene_rate_hz", "-1.0"),
        ] {
            let msg = rejects(section, key, bad);
            assert!(msg.contains(": must") || msg.contains(": a link"), "{msg}");
        }
    }

    #[test]
    fn boundary_values_accepted() {
        for (section, key, ok) in [
            ("tape", "core_radius_m", "0.0499"),
            ("discretisation", "links_per_turn", "4096"),
            ("floor", "friction", "0.0"),
            ("floor", "slope_deg", "44.9"),
            ("floor", "slope_deg", "-44.9"),
            ("gravity", "g_m_s2", "0.0"),
            ("gravity", "g_m_s2", "1000.0"),
            ("push", "contact_speed_m_s", "1000.0"),
            ("solver", "max_dt_s", "0.1"),
            ("solver", "steps_per_link", "1.0"),
            ("solver", "iterations", "1"),
            ("solver", "iterations", "1000"),
            ("solver", "freeze_speed_m_s", "0.0"),
            ("stop", "bang_cap_s", "0.0"),
            ("solver", "bang_piece_m", "0.0"),
            ("solver", "bang_iterations", "1"),
            ("output", "sample_interval_s", "0.0"),
            ("output", "scene_rate_hz", "0.0"),
        ] {
            // core_radius_m = R - 2b leaves no room for the default bang radius: set it.
            let text = if key == "core_radius_m" {
                MINIMAL.replace("mass_kg = 1.5", &format!("mass_kg = 1.5\n{key} = {ok}"))
                    + "[stop]\nbang_radius_m = 0.055\n"
            } else {
                with(section, key, ok)
            };
            if let Err(e) = Scene::from_toml_str(&text, "t") {
                panic!("{section}.{key} = {ok} rejected: {e}");
            }
        }
    }

    #[test]
    fn link_must_fit_outer_turn() {
        // Thin tape: the outermost link at 6 links per turn is ~1.047 R.
        let msg = err(&with("discretisation", "links_per_turn", "6"));
        assert!(
            msg.starts_with(
                "discretisation.links_per_turn = 6: a link must be shorter than the outer radius"
            ),
            "{msg}"
        );
        assert!(Scene::from_toml_str(&with("discretisation", "links_per_turn", "7"), "t").is_ok());
    }

    #[test]
    fn one_link_per_turn_names_the_geometric_rule_and_the_coarsest_value() {
        for n in ["1", "2", "6"] {
            let msg = err(&with("discretisation", "links_per_turn", n));
            assert!(
                msg.starts_with(&format!(
                    "discretisation.links_per_turn = {n}: a link must be shorter than the outer radius"
                )) && msg.ends_with("the coarsest this tape allows is 7 links per turn"),
                "{msg}"
            );
        }
    }

    #[test]
    fn too_many_links_rejected() {
        // 0.06 m of 1 um tape is ~60k turns, 1.9M links at 32 per turn.
        let msg = err(&with("tape", "thickness_m", "1e-6"));
        assert!(
            msg.starts_with(
                "discretisation.links_per_turn = 32: the tape would have 1919968 links"
            ),
            "{msg}"
        );
    }

    #[test]
    fn push_rules() {
        let msg = rejects("push", "contact_speed_m_s", "0.0");
        assert!(
            msg.ends_with("must be > 0: a coil at rest on a level floor stays at rest"),
            "{msg}"
        );
        let text = with("push", "contact_speed_m_s", "0.0") + "[gravity]\ng_m_s2 = 0.0\n";
        let msg = err(&text);
        assert_eq!(
            msg,
            "push.contact_speed_m_s = 0: must be > 0 when gravity.g_m_s2 = 0: nothing would move"
        );
        // A push without gravity is a valid scene.
        let text = format!("{MINIMAL}[gravity]\ng_m_s2 = 0.0\n");
        assert!(Scene::from_toml_str(&text, "t").is_ok());
    }

    #[test]
    fn defaulted_bang_radius_error_says_so() {
        // core = R - 2b (exact in binary): the default bang radius equals R.
        let text = "[tape]\nouter_radius_m = 1.0\nthickness_m = 0.25\nmass_kg = 1.0\n\
                    core_radius_m = 0.5\n[push]\ncontact_speed_m_s = 0.3\n";
        let msg = err(text);
        assert!(msg.starts_with("stop.bang_radius_m = 1: "), "{msg}");
        assert!(msg.contains("defaulted"), "{msg}");
    }

    #[test]
    fn scene_serialises() {
        let json = serde_json::to_value(shipped("yoga-mat")).unwrap();
        assert_eq!(json["contact_model"], "spiral");
        assert_eq!(json["tape"]["mass_kg"], 1.5);
    }
}
