//! Validation of a scene file's values into a [`Scene`]: every value checked once, section by
//! section in the file's order (later rules may rely on earlier values being valid), the
//! first violation reported as `key = value: rule`. It reads only the serde mirror's values;
//! it does not parse TOML, fill defaults other than the ones derived from the tape
//! (`solver.bang_piece_m`, `stop.bang_radius_m`), or bound the size of the run (that is
//! `budget`'s, checked last).

use std::ops::RangeInclusive;

use crate::scene::budget::{self, MAX_LINKS};
use crate::scene::file::{
    DiscretisationFile, FloorFile, OutputFile, PushFile, SceneFile, SolverFile, StopFile,
    TOLERANCE_OFF, TapeFile, ToleranceFile,
};
use crate::scene::rules::{MIDPOINT_RETIRED, Shown, check, check_int, invalid, name};
use crate::scene::{
    Axis, BangEngine, Discretisation, Floor, Gravity, Output, Push, Scene, SceneError, Solver,
    Stop, Tape,
};

/// Bounds of `discretisation.links_per_turn`.
const LINKS_PER_TURN_RANGE: RangeInclusive<i64> = 3..=4096;
/// Bounds of `solver.iterations`.
const ITERATIONS_RANGE: RangeInclusive<i64> = 1..=1000;
/// Bounds of `tape.outer_radius_m` (m): the engine's tolerances scale with R (its length
/// unit is R/10), and they were tuned for coils from a millimetre to metres.
const OUTER_RADIUS_RANGE_M: RangeInclusive<f64> = 0.001..=100.0;
/// Upper bound of `tape.mass_kg` (kg).
const MAX_MASS_KG: f64 = 1.0e6;
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

impl Scene {
    /// Checks every value of `file` once, in dependency order (later rules may rely on
    /// earlier values being valid), then the size of the run it asks for.
    pub(super) fn validate(
        file: SceneFile,
        default_name: &str,
        text: &str,
    ) -> Result<Scene, SceneError> {
        let name = name(file.name, default_name)?;
        let tape = tape(&file.tape)?;
        let links_per_turn = discretisation(&file.discretisation, &tape)?;
        let (friction, slope_deg) = floor(&file.floor)?;
        let tape = Tape {
            self_friction: self_friction(file.tape.self_friction, friction)?,
            ..tape
        };
        let g_m_s2 = check(
            "gravity.g_m_s2",
            file.gravity.g_m_s2,
            (0.0..=MAX_G_M_S2).contains(&file.gravity.g_m_s2),
            format!("must be >= 0 and <= {MAX_G_M_S2}"),
        )?;
        let push_speed_m_s = push(&file.push, g_m_s2)?;
        let solver = solver(&file.solver, &tape)?;
        let stop = stop(&file.stop, &tape)?;
        let (sample_interval_s, scene_rate_hz) = output(&file.output)?;
        let scene = Scene {
            name,
            tape,
            discretisation: Discretisation { links_per_turn },
            floor: Floor {
                friction,
                slope_deg,
                sticky: file.floor.sticky,
            },
            gravity: Gravity { g_m_s2 },
            push: Push {
                contact_speed_m_s: push_speed_m_s,
            },
            axis: Axis {
                fixed: file.axis.fixed,
            },
            solver,
            stop,
            output: Output {
                sample_interval_s,
                scene_rate_hz,
            },
            source_text: text.to_owned(),
        };
        budget::check(&scene)?;
        Ok(scene)
    }
}

/// `[tape]`: R in its range, 0 < b < R/2, the mass, and a core leaving at least one turn.
fn tape(t: &TapeFile) -> Result<Tape, SceneError> {
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
    Ok(Tape {
        outer_radius_m: r,
        thickness_m: b,
        mass_kg: mass,
        core_radius_m: core,
        // Set once the floor's coefficient, its default, is known (`self_friction`).
        self_friction: 0.0,
    })
}

/// `tape.self_friction`: >= 0, or the floor's coefficient `floor_friction` where not set.
fn self_friction(value: Option<f64>, floor_friction: f64) -> Result<f64, SceneError> {
    match value {
        None => Ok(floor_friction),
        Some(mu) => check("tape.self_friction", mu, mu >= 0.0, "must be >= 0"),
    }
}

/// `[discretisation]`: links shorter than R, within the count range, at most
/// [`MAX_LINKS`] in all.
fn discretisation(d: &DiscretisationFile, tape: &Tape) -> Result<u32, SceneError> {
    // A link must be shorter than the outer radius: 2 pi (R - b/2) / n <= R. Values from 1
    // up get this rule (one link per turn would be a chord of a whole turn), the range
    // check only catches what no tape allows.
    let (r, b) = (tape.outer_radius_m, tape.thickness_m);
    let key = "discretisation.links_per_turn";
    let raw = d.links_per_turn;
    let outer_arc_m = 2.0 * std::f64::consts::PI * (r - b / 2.0);
    let coarsest = ((outer_arc_m / r).ceil() as i64).max(*LINKS_PER_TURN_RANGE.start());
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
    let links = budget::links(tape, links_per_turn);
    if links > MAX_LINKS {
        return Err(invalid(
            key,
            links_per_turn,
            format!(
                "the tape would have {links:.0} links ({:.0} turns), more than {MAX_LINKS:.0}: \
                 use fewer links per turn or a thicker tape",
                budget::turns(tape)
            ),
        ));
    }
    Ok(links_per_turn)
}

/// `[floor]`: the friction coefficient and the slope; returns `(friction, slope_deg)`.
fn floor(f: &FloorFile) -> Result<(f64, f64), SceneError> {
    let friction = check(
        "floor.friction",
        f.friction,
        f.friction >= 0.0,
        "must be >= 0",
    )?;
    let slope_deg = check(
        "floor.slope_deg",
        f.slope_deg,
        f.slope_deg.abs() < MAX_SLOPE_DEG,
        format!("must be > -{MAX_SLOPE_DEG} and < {MAX_SLOPE_DEG}"),
    )?;
    Ok((friction, slope_deg))
}

/// `[push]`: a speed in its range, and > 0 (what it says depends on gravity `g`).
fn push(p: &PushFile, g: f64) -> Result<f64, SceneError> {
    let key = "push.contact_speed_m_s";
    let v = p.contact_speed_m_s;
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
    Ok(push)
}

/// `[solver]`: each setting in its range; the pieces are given in metres
/// (`bang_piece_m`) or in the tape's thicknesses (`bang_piece_b`), not both, and default to
/// its thickness.
fn solver(s: &SolverFile, tape: &Tape) -> Result<Solver, SceneError> {
    let b = tape.thickness_m;
    let piece = match (s.bang_piece_m, s.bang_piece_b) {
        (Some(m), Some(_)) => return Err(both("solver.bang_piece", m)),
        (Some(m), None) => check("solver.bang_piece_m", m, m >= 0.0, "must be >= 0")?,
        (None, Some(k)) => check("solver.bang_piece_b", k, k >= 0.0, "must be >= 0")? * b,
        (None, None) => b,
    };
    let positive = |key: &str, v: f64| check(key, v, v > 0.0, "must be > 0");
    Ok(Solver {
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
        bang_tolerance: tolerance(&s.bang_tolerance)?,
        bang_iterations: check_int(
            "solver.bang_iterations",
            s.bang_iterations,
            &ITERATIONS_RANGE,
        )?,
        bang_relax_iterations: check_int(
            "solver.bang_relax_iterations",
            s.bang_relax_iterations,
            &ITERATIONS_RANGE,
        )?,
        bang_piece_m: piece,
        contact_hz: positive("solver.contact_hz", s.contact_hz)?,
        joint_hz: positive("solver.joint_hz", s.joint_hz)?,
        bang_joint_hz: positive("solver.bang_joint_hz", s.bang_joint_hz)?,
        bang_engine: match s.bang_engine.as_str() {
            "exact" => BangEngine::Exact,
            "rapier" => BangEngine::Rapier,
            "midpoint" => {
                return Err(invalid(
                    "solver.bang_engine",
                    "\"midpoint\"",
                    MIDPOINT_RETIRED,
                ));
            }
            other => {
                return Err(invalid(
                    "solver.bang_engine",
                    format!("{other:?}"),
                    "must be \"exact\" or \"rapier\"",
                ));
            }
        },
    })
}

/// `solver.bang_tolerance`: a share of energy, > 0 and <= 1, or `"off"` for steps whose
/// error is not bounded (`None`).
fn tolerance(t: &ToleranceFile) -> Result<Option<f64>, SceneError> {
    const RULE: &str = "must be > 0 and <= 1, or \"off\"";
    match t {
        ToleranceFile::Share(t) => {
            check("solver.bang_tolerance", *t, *t > 0.0 && *t <= 1.0, RULE).map(Some)
        }
        ToleranceFile::Word(w) if w == TOLERANCE_OFF => Ok(None),
        ToleranceFile::Word(w) => Err(invalid("solver.bang_tolerance", format!("{w:?}"), RULE)),
    }
}

/// The error for a length given both in metres (`{stem}_m`, its value `m`) and in the
/// tape's thicknesses (`{stem}_b`).
fn both(stem: &str, m: f64) -> SceneError {
    invalid(
        &format!("{stem}_m"),
        Shown(m),
        format!("give {stem}_m (metres) or {stem}_b (the tape's thicknesses), not both"),
    )
}

/// `[stop]`: a bang radius between the core and R, given in metres or in thicknesses above
/// the core, not both (by default two thicknesses above the core), the time limits and the
/// rest fraction.
fn stop(st: &StopFile, tape: &Tape) -> Result<Stop, SceneError> {
    let (core, r, b) = (tape.core_radius_m, tape.outer_radius_m, tape.thickness_m);
    let within = |v: f64| core < v && v < r;
    let rule = format!("must be > tape.core_radius_m (= {core}) and < tape.outer_radius_m (= {r})");
    let bang = match (st.bang_radius_m, st.bang_radius_b) {
        (Some(m), Some(_)) => return Err(both("stop.bang_radius", m)),
        (Some(v), None) => check("stop.bang_radius_m", v, within(v), rule)?,
        (None, Some(k)) => {
            let v = core + k * b;
            check(
                "stop.bang_radius_b",
                k,
                within(v),
                format!(
                    "must put the bang radius, tape.core_radius_m + stop.bang_radius_b * \
                     tape.thickness_m (= {v} m), > tape.core_radius_m (= {core}) and < \
                     tape.outer_radius_m (= {r})"
                ),
            )?;
            v
        }
        (None, None) => check(
            "stop.bang_radius_m",
            core + 2.0 * b,
            within(core + 2.0 * b),
            format!(
                "{rule} (defaulted to tape.core_radius_m + 2 * tape.thickness_m; set it \
                 explicitly)"
            ),
        )?,
    };
    Ok(Stop {
        bang_radius_m: bang,
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
    })
}

/// `[output]`: the sample interval and the drawing rate, both >= 0; returns
/// `(sample_interval_s, scene_rate_hz)`.
fn output(o: &OutputFile) -> Result<(f64, f64), SceneError> {
    let sample_interval_s = check(
        "output.sample_interval_s",
        o.sample_interval_s,
        o.sample_interval_s >= 0.0,
        "must be >= 0",
    )?;
    let scene_rate_hz = check(
        "output.scene_rate_hz",
        o.scene_rate_hz,
        o.scene_rate_hz >= 0.0,
        "must be >= 0",
    )?;
    Ok((sample_interval_s, scene_rate_hz))
}

#[cfg(test)]
mod tests;
