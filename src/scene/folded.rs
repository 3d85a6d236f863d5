//! The falling folded chain (`kind = "folded-chain"`): a chain of rigid links hanging from a
//! pin with both ends level, one end released, the benchmark with a known answer for the
//! joints of the final bang. Its file, defaults and validation, as for a coil's scene: every
//! value checked once, the first violation reported as `key = value: rule`.
//!
//! The chain's start: `links` links of length `l = L / links` (an even count), the left arm
//! hanging straight down from the pin at `(0, pin.height_m)`, the right arm its mirror image
//! rising to the free end at `(separation_m, pin.height_m)`; the two lowest links meet at
//! the fold, tilted to span the separation (so `0 <= separation_m <= 2 l`). The plane
//! `y = 0` is the floor, solid when `floor.enabled`.
//!
//! Or, with `start.shape = "hanging"`, Cayley's chain: upright from the floor, its links
//! tilted `start.tilt_rad` alternately either way, let go at rest (no pin). With
//! `chain.thickness_m` the links meet the floor at their faces and each other as the tape's
//! layers do (the exact chain only).

use serde::{Deserialize, Serialize};

use crate::scene::budget::MAX_ENGINE_STEPS;
use crate::scene::rules::{MIDPOINT_RETIRED, Shown, check, check_int, invalid, name};
use crate::scene::{Gravity, SceneError};

/// The value of the top-level key `kind` that selects this scene kind.
pub const KIND: &str = "folded-chain";

/// Every key a folded chain's file may set (`section.key`), in the file's order.
pub const FOLDED_KEYS: &[&str] = &[
    "kind",
    "name",
    "chain.length_m",
    "chain.links",
    "chain.mass_kg",
    "chain.separation_m",
    "chain.thickness_m",
    "start.shape",
    "start.tilt_rad",
    "pin.height_m",
    "floor.enabled",
    "floor.friction",
    "gravity.g_m_s2",
    "solver.dt_s",
    "solver.substeps",
    "solver.relax_iterations",
    "solver.joint_hz",
    "solver.contact_hz",
    "solver.joints",
    "stop.tip_fraction",
    "stop.max_time_s",
    "stop.rest_fraction",
    "output.sample_interval_s",
];

/// The shortest link the engine is given (m): below it the engine's fixed tolerances, not
/// the chain, set the motion.
const MIN_LINK_M: f64 = 1.0e-6;
/// The largest pin height and chain length (m).
const MAX_SIZE_M: f64 = 1.0e3;

/// A validated folded chain.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoldedChain {
    /// Scene name (default: the file stem).
    pub name: String,
    /// The chain (`[chain]`).
    pub chain: Chain,
    /// How the chain starts (`[start]`).
    pub start: Start,
    /// Height of the pin above the plane `y = 0` (m; `[pin] height_m`); for a hanging
    /// start, which has no pin, the height of the chain's top at the start.
    pub pin_height_m: f64,
    /// The floor `y = 0` (`[floor]`).
    pub floor: ChainFloor,
    /// Gravity (`[gravity]`).
    pub gravity: Gravity,
    /// The engine's settings (`[solver]`).
    pub solver: ChainSolver,
    /// When the run ends (`[stop]`).
    pub stop: ChainStop,
    /// Time between rows of `samples.csv` (s; 0 = every step; `[output]`).
    pub sample_interval_s: f64,
    /// The TOML text as read, for the report.
    pub source_text: String,
}

/// `[chain]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Chain {
    /// L: the chain's length (m). Default 1.
    pub length_m: f64,
    /// Links, an even count (4..=4096). Default 200.
    pub links: u32,
    /// The chain's mass (kg). Default 0.1.
    pub mass_kg: f64,
    /// Horizontal separation of the two ends at the start (m, 0..=2 L / links). Default
    /// 2 L / links: the two lowest links lie flat, so the free arm stands on the end of a
    /// link free to turn. Nearer 0 the free arm starts balanced on the fold, an unstable
    /// equilibrium it leaves only by buckling, and the fall lags the closed form.
    pub separation_m: f64,
    /// The links' thickness (m, 0 to a link's length). Default 0, a chain of lines: with a
    /// thickness each link is every point within half of it of its axis, meeting the floor
    /// at its face and the other links as the tape's layers meet (the exact chain only), and
    /// its rotary inertia is `m (l^2 + b^2) / 12`.
    pub thickness_m: f64,
}

/// How the chain starts (`[start]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Start {
    /// `shape = "fold"`: hanging from the pin in its fold, the free end released level with
    /// the pin. The default.
    Fold,
    /// `shape = "hanging"`: Cayley's chain, upright from the floor, each link tilted
    /// `tilt_rad` from the vertical, alternately either way, released at rest.
    Hanging {
        /// Each link's tilt from the vertical (rad, 0..=0.5). Default 0.05.
        tilt_rad: f64,
    },
}

impl Chain {
    /// One link's length (m).
    pub fn link_m(&self) -> f64 {
        self.length_m / f64::from(self.links)
    }

    /// Depth of the fold below the pin at the start (m).
    pub fn fold_depth_m(&self) -> f64 {
        let l = self.link_m();
        let half = 0.5 * self.separation_m;
        f64::from(self.links / 2 - 1) * l + (l * l - half * half).max(0.0).sqrt()
    }
}

/// `[floor]`: the plane `y = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ChainFloor {
    /// Whether the plane is solid: the chain lands on it. Default false.
    pub enabled: bool,
    /// Coulomb friction between chain and floor (>= 0). Default 0.5.
    pub friction: f64,
}

/// `[solver]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ChainSolver {
    /// The engine's step (s, > 0 and <= 0.01). Default 5e-5.
    pub dt_s: f64,
    /// Substeps per step, each one biased Gauss-Seidel sweep (1..=1000). Default 24, the
    /// final bang's.
    pub substeps: u32,
    /// Relax sweeps per substep (1..=1000). Default 1, the engine's and the bang's.
    pub relax_iterations: u32,
    /// Natural frequency of the joints (Hz, > 0). Default 1e9, the bang's: rigid.
    pub joint_hz: f64,
    /// Natural frequency of the floor contact (Hz, > 0). Default 1e4, the coil's.
    pub contact_hz: f64,
    /// How the links are joined. Default the exact chain, the coil's bang engine: the
    /// benchmark's known answer is met there; the engine's joints are the comparison.
    pub joints: ChainJoints,
}

/// How a folded chain's links are joined (`solver.joints`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChainJoints {
    /// `"impulse"`: the engine's impulse joints, solved iteratively with the contacts, as
    /// in the final bang; they can drift, and the iterations leave them partly open.
    Impulse,
    /// `"multibody"`: one reduced-coordinate multibody rooted at the pin, the links'
    /// angles its coordinates; its joints cannot open and do no work, and its dense solve
    /// grows as the cube of the links. No damping is applied to its angles.
    Multibody,
    /// `"exact"`: the exact chain (`model::exact_chain`), the joints solved directly at
    /// every step in time linear in the links, the floor's contacts to a stated tolerance;
    /// one solve a step (`solver.substeps`, `relax_iterations`, `joint_hz` and `contact_hz`
    /// are the engine's and do not apply).
    Exact,
}

/// `[stop]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ChainStop {
    /// Without a floor, the run ends when the free end has fallen this fraction of L
    /// (0 < f < 1). Default 0.95.
    pub tip_fraction: f64,
    /// The longest simulated time (s). Default 2.
    pub max_time_s: f64,
    /// With a floor, the run ends at rest: kinetic energy below this fraction of the
    /// energy released (0 < f < 1). Default 1e-3.
    pub rest_fraction: f64,
}

/// The file's serde mirror: sections `deny_unknown_fields`, every key defaulted.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FoldedFile {
    #[allow(dead_code)]
    kind: String,
    name: Option<String>,
    #[serde(default)]
    chain: ChainFile,
    #[serde(default)]
    start: StartFile,
    #[serde(default)]
    pin: PinFile,
    #[serde(default)]
    floor: FloorFile,
    #[serde(default)]
    gravity: GravityFile,
    #[serde(default)]
    solver: SolverFile,
    #[serde(default)]
    stop: StopFile,
    #[serde(default)]
    output: OutputFile,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ChainFile {
    length_m: f64,
    links: i64,
    mass_kg: f64,
    separation_m: Option<f64>,
    thickness_m: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct StartFile {
    shape: String,
    tilt_rad: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct PinFile {
    height_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct FloorFile {
    enabled: bool,
    friction: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct GravityFile {
    g_m_s2: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct SolverFile {
    dt_s: f64,
    substeps: i64,
    relax_iterations: i64,
    joint_hz: f64,
    contact_hz: f64,
    joints: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct StopFile {
    tip_fraction: f64,
    max_time_s: f64,
    rest_fraction: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct OutputFile {
    sample_interval_s: f64,
}

impl Default for ChainFile {
    fn default() -> Self {
        Self {
            length_m: 1.0,
            links: 200,
            mass_kg: 0.1,
            separation_m: None,
            thickness_m: 0.0,
        }
    }
}

impl Default for StartFile {
    fn default() -> Self {
        Self {
            shape: "fold".into(),
            tilt_rad: None,
        }
    }
}

impl Default for FloorFile {
    fn default() -> Self {
        Self {
            enabled: false,
            friction: 0.5,
        }
    }
}

impl Default for GravityFile {
    fn default() -> Self {
        Self { g_m_s2: 9.81 }
    }
}

impl Default for SolverFile {
    fn default() -> Self {
        Self {
            dt_s: 5e-5,
            substeps: 24,
            relax_iterations: 1,
            joint_hz: 1e9,
            contact_hz: 1e4,
            joints: "exact".into(),
        }
    }
}

impl Default for StopFile {
    fn default() -> Self {
        Self {
            tip_fraction: 0.95,
            max_time_s: 2.0,
            rest_fraction: 1e-3,
        }
    }
}

impl Default for OutputFile {
    fn default() -> Self {
        Self {
            sample_interval_s: 1e-3,
        }
    }
}

/// `value` if it is finite and positive, at most `max`.
fn positive(key: &str, value: f64, max: f64) -> Result<f64, SceneError> {
    check(
        key,
        value,
        value > 0.0 && value <= max,
        format!("must be > 0 and <= {}", Shown(max)),
    )
}

/// `value` if it is finite and strictly between 0 and 1.
fn fraction(key: &str, value: f64) -> Result<f64, SceneError> {
    check(
        key,
        value,
        value > 0.0 && value < 1.0,
        "must be > 0 and < 1",
    )
}

impl FoldedChain {
    /// Parses and validates a folded chain's TOML `text`; `name` is used when the text has
    /// no top-level `name`.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Self, SceneError> {
        let file: FoldedFile =
            toml::from_str(text).map_err(|e| crate::scene::rules::parse_error(name, &e))?;
        Self::validate(file, name, text)
    }

    fn validate(file: FoldedFile, default_name: &str, text: &str) -> Result<Self, SceneError> {
        let start = start(&file)?;
        let name = name(file.name.clone(), default_name)?;
        let chain = chain(&file.chain, start)?;
        let friction = check(
            "floor.friction",
            file.floor.friction,
            file.floor.friction >= 0.0,
            "must be >= 0",
        )?;
        let pin_height_m = pin_height(&file, start, &chain)?;
        let g_m_s2 = positive("gravity.g_m_s2", file.gravity.g_m_s2, 1000.0)?;
        let s = &file.solver;
        let solver = ChainSolver {
            dt_s: positive("solver.dt_s", s.dt_s, 0.01)?,
            substeps: check_int("solver.substeps", s.substeps, &(1..=1000))?,
            relax_iterations: check_int(
                "solver.relax_iterations",
                s.relax_iterations,
                &(1..=1000),
            )?,
            joint_hz: positive("solver.joint_hz", s.joint_hz, f64::MAX)?,
            contact_hz: positive("solver.contact_hz", s.contact_hz, f64::MAX)?,
            joints: match s.joints.as_str() {
                "impulse" => ChainJoints::Impulse,
                "multibody" => ChainJoints::Multibody,
                "exact" => ChainJoints::Exact,
                "midpoint" => {
                    return Err(invalid("solver.joints", "\"midpoint\"", MIDPOINT_RETIRED));
                }
                other => {
                    return Err(invalid(
                        "solver.joints",
                        format!("{other:?}"),
                        "must be \"impulse\", \"multibody\" or \"exact\"",
                    ));
                }
            },
        };
        let stop = ChainStop {
            tip_fraction: fraction("stop.tip_fraction", file.stop.tip_fraction)?,
            max_time_s: positive("stop.max_time_s", file.stop.max_time_s, 100.0)?,
            rest_fraction: fraction("stop.rest_fraction", file.stop.rest_fraction)?,
        };
        let steps = stop.max_time_s / solver.dt_s * f64::from(chain.links);
        if steps > MAX_ENGINE_STEPS * 100.0 {
            return Err(invalid(
                "stop.max_time_s",
                Shown(stop.max_time_s),
                format!(
                    "the run would take {} link-steps (max_time_s / dt_s x links), over the \
                     budget of {}",
                    Shown(steps),
                    Shown(MAX_ENGINE_STEPS * 100.0)
                ),
            ));
        }
        let interval = file.output.sample_interval_s;
        let sample_interval_s = check(
            "output.sample_interval_s",
            interval,
            interval >= 0.0,
            "must be >= 0",
        )?;
        if (start != Start::Fold || chain.thickness_m > 0.0) && solver.joints != ChainJoints::Exact
        {
            return Err(invalid(
                "solver.joints",
                format!("{:?}", file.solver.joints),
                "must be \"exact\" for a hanging start or a chain with a thickness: only the \
                 exact chain has links that meet each other",
            ));
        }
        Ok(Self {
            name,
            chain,
            start,
            pin_height_m,
            floor: ChainFloor {
                enabled: file.floor.enabled,
                friction,
            },
            gravity: Gravity { g_m_s2 },
            solver,
            stop,
            sample_interval_s,
            source_text: text.to_owned(),
        })
    }
}

/// The pin's height: in a fold, the file's (default 1 m) above the fold's start where the
/// floor is solid; a hanging start has no pin, and stands on the floor, which it needs: the
/// top's height.
fn pin_height(file: &FoldedFile, start: Start, chain: &Chain) -> Result<f64, SceneError> {
    Ok(match start {
        Start::Fold => {
            let h = positive("pin.height_m", file.pin.height_m.unwrap_or(1.0), MAX_SIZE_M)?;
            if file.floor.enabled && h <= chain.fold_depth_m() + 0.5 * chain.thickness_m {
                return Err(invalid(
                    "pin.height_m",
                    Shown(h),
                    format!(
                        "the pin is below the world: with the floor enabled it must be \
                         above the fold's start and half the thickness, {} m below it",
                        Shown(chain.fold_depth_m() + 0.5 * chain.thickness_m)
                    ),
                ));
            }
            h
        }
        Start::Hanging { tilt_rad } => {
            if let Some(h) = file.pin.height_m {
                return Err(invalid(
                    "pin.height_m",
                    Shown(h),
                    "a hanging start has no pin: its top is let go with the rest",
                ));
            }
            if !file.floor.enabled {
                return Err(invalid(
                    "floor.enabled",
                    "false",
                    "a hanging start falls onto the floor: it must be true",
                ));
            }
            0.5 * chain.thickness_m + chain.length_m * tilt_rad.cos()
        }
    })
}

/// `[start]`: the fold, or hanging with a tilt (only there).
fn start(file: &FoldedFile) -> Result<Start, SceneError> {
    let st = &file.start;
    match st.shape.as_str() {
        "fold" => match st.tilt_rad {
            Some(t) => Err(invalid(
                "start.tilt_rad",
                Shown(t),
                "only a hanging start is tilted (start.shape = \"hanging\")",
            )),
            None => Ok(Start::Fold),
        },
        "hanging" => {
            let t = st.tilt_rad.unwrap_or(0.05);
            let tilt_rad = check(
                "start.tilt_rad",
                t,
                (0.0..=0.5).contains(&t),
                "must be >= 0 and <= 0.5",
            )?;
            if let Some(d) = file.chain.separation_m {
                return Err(invalid(
                    "chain.separation_m",
                    Shown(d),
                    "a hanging start has no fold whose ends it separates",
                ));
            }
            Ok(Start::Hanging { tilt_rad })
        }
        other => Err(invalid(
            "start.shape",
            format!("{other:?}"),
            "must be \"fold\" or \"hanging\"",
        )),
    }
}

/// `[chain]`: length, a number of links no shorter than [`MIN_LINK_M`] (even in a fold),
/// the mass, a separation the two lowest links can span, a thickness no more than a link's
/// length.
fn chain(c: &ChainFile, start: Start) -> Result<Chain, SceneError> {
    let length_m = positive("chain.length_m", c.length_m, MAX_SIZE_M)?;
    let links = check_int("chain.links", c.links, &(4..=4096))?;
    if links % 2 != 0 && start == Start::Fold {
        return Err(invalid(
            "chain.links",
            links,
            "must be even: two arms of equal length",
        ));
    }
    let link_m = length_m / f64::from(links);
    if link_m < MIN_LINK_M {
        return Err(invalid(
            "chain.length_m",
            Shown(length_m),
            format!(
                "a chain too short for its {links} links: each would be {} m, under {} m",
                Shown(link_m),
                Shown(MIN_LINK_M)
            ),
        ));
    }
    let mass_kg = positive("chain.mass_kg", c.mass_kg, 1.0e6)?;
    let separation_m = c.separation_m.unwrap_or(2.0 * link_m);
    let separation_m = check(
        "chain.separation_m",
        separation_m,
        (0.0..=2.0 * link_m).contains(&separation_m),
        format!(
            "must be >= 0 and <= two links' length, 2 L / links = {} m",
            Shown(2.0 * link_m)
        ),
    )?;
    let thickness_m = check(
        "chain.thickness_m",
        c.thickness_m,
        (0.0..=link_m).contains(&c.thickness_m),
        format!(
            "must be >= 0 and <= a link's length, L / links = {} m: a link thicker than it \
             is long is not a link",
            Shown(link_m)
        ),
    )?;
    Ok(Chain {
        length_m,
        links,
        mass_kg,
        separation_m,
        thickness_m,
    })
}

#[cfg(test)]
mod tests;
