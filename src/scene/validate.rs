//! Validation of a scene file's values into a [`Scene`]: every value checked once, section by
//! section in the file's order (later rules may rely on earlier values being valid), the
//! first violation reported as `key = value: rule`. It reads only the serde mirror's values;
//! it does not parse TOML, fill defaults other than the ones derived from the tape
//! (`solver.bang_piece_m`, `stop.bang_radius_m`), or bound the size of the run (that is
//! `budget`'s, checked last).

use std::ops::RangeInclusive;

use crate::scene::budget::{self, MAX_LINKS};
use crate::scene::file::{
    DiscretisationFile, FloorFile, OutputFile, PushFile, SceneFile, SolverFile, StopFile, TapeFile,
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
        bang_tolerance: s
            .bang_tolerance
            .map(|t| {
                check(
                    "solver.bang_tolerance",
                    t,
                    t > 0.0 && t <= 1.0,
                    "must be > 0 and <= 1",
                )
            })
            .transpose()?,
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
mod tests {
    use crate::scene::Scene;
    use crate::scene::tests::{MINIMAL, err, rejects, with};
    use approx::assert_relative_eq;

    #[test]
    fn name_key_overrides_fallback() {
        let s = Scene::from_toml_str(&format!("name = \"mine\"\n{MINIMAL}"), "fallback").unwrap();
        assert_eq!(s.name, "mine");
        assert!(err(&format!("name = \" \"\n{MINIMAL}")).starts_with("name = "));
    }

    #[test]
    fn lengths_in_thicknesses_follow_the_thickness() {
        // The pieces and the bang radius in thicknesses keep the model's proportions when
        // the thickness changes; in metres they do not.
        use crate::scene::overrides::{Override, scene_with_overrides};
        let text = format!("{MINIMAL}[solver]\nbang_piece_b = 2.0\n[stop]\nbang_radius_b = 3.0\n");
        for b in [0.005, 0.002, 0.0005] {
            let thickness = b.to_string();
            let s = scene_with_overrides(
                &text,
                "t",
                &[
                    Override::new("tape.thickness_m", &thickness),
                    Override::new("tape.core_radius_m", "0.01"),
                ],
            )
            .unwrap();
            assert_relative_eq!(s.solver.bang_piece_m, 2.0 * b);
            assert_relative_eq!(s.stop.bang_radius_m, 0.01 + 3.0 * b);
        }
        for (section, stem) in [("solver", "bang_piece"), ("stop", "bang_radius")] {
            let text = format!("{MINIMAL}[{section}]\n{stem}_m = 0.01\n{stem}_b = 2.0\n");
            let msg = err(&text);
            assert_eq!(
                msg,
                format!(
                    "{section}.{stem}_m = 0.01: give {section}.{stem}_m (metres) or \
                     {section}.{stem}_b (the tape's thicknesses), not both"
                )
            );
        }
        // On the command line, one way replaces the file's other.
        let s = scene_with_overrides(&text, "t", &[Override::new("solver.bang_piece_m", "0.007")])
            .unwrap();
        assert_relative_eq!(s.solver.bang_piece_m, 0.007);
        let e = scene_with_overrides(
            &text,
            "t",
            &[
                Override::new("stop.bang_radius_m", "0.02"),
                Override::new("stop.bang_radius_b", "1"),
            ],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("not both"), "{e}");
        let msg = rejects("stop", "bang_radius_b", "12");
        assert!(
            msg.starts_with("stop.bang_radius_b = 12: must put the bang radius"),
            "{msg}"
        );
    }

    #[test]
    fn default_bang_radius_follows_core() {
        let s = Scene::from_toml_str(&with("tape", "core_radius_m", "0.02"), "t").unwrap();
        assert_relative_eq!(s.stop.bang_radius_m, 0.03);
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
            ("solver", "bang_tolerance"),
            ("solver", "bang_piece_m"),
            ("solver", "bang_piece_b"),
            ("solver", "contact_hz"),
            ("solver", "joint_hz"),
            ("solver", "bang_joint_hz"),
            ("stop", "bang_radius_m"),
            ("stop", "bang_radius_b"),
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
            ("solver", "bang_tolerance", "0.0"),
            ("solver", "bang_tolerance", "-1e-3"),
            ("solver", "bang_tolerance", "1.5"),
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
            ("solver", "bang_piece_b", "-1"),
            ("stop", "bang_radius_b", "0.0"),
            ("stop", "bang_radius_b", "12"),
            ("solver", "bang_iterations", "0"),
            ("solver", "bang_iterations", "1001"),
            ("solver", "bang_relax_iterations", "0"),
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
            ("solver", "bang_piece_b", "0.0"),
            ("stop", "bang_radius_b", "11.9"),
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
}
