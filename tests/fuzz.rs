//! Property tests of scene loading: arbitrary text, mutated scene files, every key of
//! [`SCENE_KEYS`] over wide ranges (zero, negative, NaN, infinities, huge and tiny values)
//! and the keys that set the size of a run over many orders of magnitude. Loading never
//! panics, a rejection names a real key (or is a parse error), and every accepted scene
//! keeps the invariants the model relies on and the run-size budgets. Case counts: see
//! [`cases`].

use std::f64::consts::PI;

use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use uncoil::scene::overrides::{Override, scene_with_overrides};
use uncoil::scene::{
    MAX_ENGINE_STEPS, MAX_FRAME_NODES, MAX_LINKS, MAX_SAMPLES, MIN_BANG_STEP_RAD, SCENE_KEYS,
    Scene, SceneError,
};
use uncoil::spiral::Spiral;

/// The valid value each key takes in [`scene_text`]: the yoga mat's, and the default of the
/// keys its file leaves out. Every key of [`SCENE_KEYS`] must have one (a test checks it).
fn valid_value(key: &str) -> Option<String> {
    let yoga: toml::Table = toml::from_str(YOGA).unwrap();
    let (section, name) = key
        .split_once('.')
        .map_or((None, key), |(s, k)| (Some(s), k));
    let table = match section {
        Some(s) => yoga.get(s).and_then(toml::Value::as_table),
        None => Some(&yoga),
    };
    if let Some(v) = table.and_then(|t| t.get(name)) {
        return Some(v.to_string());
    }
    let default = match key {
        "floor.slope_deg" => "0.0",
        "floor.sticky" | "axis.fixed" => "false",
        // Left to its default (the floor's coefficient) by the shipped scenes.
        "tape.self_friction" => "1.0",
        // Kept so older files load; the shipped scenes no longer set it.
        "contact.model" => "\"spiral\"",
        // Off by default; the yoga mat's file shows it commented out.
        "solver.bang_tolerance" => "1e-3",
        // The yoga mat gives these in thicknesses (solver.bang_piece_b, stop.bang_radius_b).
        "solver.bang_piece_m" | "stop.bang_radius_m" => "0.005",
        _ => return None,
    };
    Some(default.to_owned())
}

const YOGA: &str = include_str!("../scenes/yoga-mat.toml");

/// Loads `text`; panics (failing the property) only through the invariant checks.
fn load_and_check(text: &str) -> Result<(), TestCaseError> {
    match Scene::from_toml_str(text, "fuzz") {
        Ok(scene) => check_invariants(&scene),
        Err(SceneError::Invalid { key, value, rule }) => {
            prop_assert!(
                SCENE_KEYS.contains(&key.as_str()),
                "unknown key {key} in the error"
            );
            prop_assert!(!value.is_empty() && !rule.is_empty());
            Ok(())
        }
        Err(SceneError::Parse { message, .. }) => {
            prop_assert!(!message.is_empty());
            Ok(())
        }
        Err(e @ SceneError::Read { .. }) => Err(TestCaseError::fail(format!("read error {e}"))),
    }
}

/// The invariants an accepted scene guarantees (see `src/scene.rs`).
fn check_invariants(s: &Scene) -> Result<(), TestCaseError> {
    let t = &s.tape;
    let all = [
        t.outer_radius_m,
        t.thickness_m,
        t.mass_kg,
        t.core_radius_m,
        s.floor.friction,
        s.floor.slope_deg,
        s.gravity.g_m_s2,
        s.push.contact_speed_m_s,
        s.solver.max_dt_s,
        s.solver.steps_per_link,
        s.solver.freeze_speed_m_s,
        s.solver.bang_step_rad,
        s.solver.bang_piece_m,
        s.solver.contact_hz,
        s.solver.joint_hz,
        s.solver.bang_joint_hz,
        s.stop.bang_radius_m,
        s.stop.max_time_s,
        s.stop.bang_cap_s,
        s.stop.rest_fraction,
        s.output.sample_interval_s,
        s.output.scene_rate_hz,
    ];
    prop_assert!(
        all.iter().all(|v| v.is_finite()),
        "non-finite value in {s:?}"
    );
    let (r, b, core) = (t.outer_radius_m, t.thickness_m, t.core_radius_m);
    prop_assert!((0.001..=100.0).contains(&r));
    prop_assert!(b > 0.0 && b < r / 2.0);
    prop_assert!(t.mass_kg > 0.0 && t.mass_kg <= 1e6);
    prop_assert!(core >= 0.0 && core + 2.0 * b <= r);
    prop_assert!((3..=4096).contains(&s.discretisation.links_per_turn));
    let n = f64::from(s.discretisation.links_per_turn);
    prop_assert!(
        2.0 * PI * (r - b / 2.0) / n <= r,
        "outer link longer than R"
    );
    let links = (r - core - b) / b * n;
    prop_assert!(links <= MAX_LINKS, "too many links");
    prop_assert!(s.floor.friction >= 0.0);
    prop_assert!(s.floor.slope_deg.abs() < 45.0);
    prop_assert!((0.0..=1000.0).contains(&s.gravity.g_m_s2));
    prop_assert!(s.push.contact_speed_m_s > 0.0 && s.push.contact_speed_m_s <= 1000.0);
    prop_assert!(s.solver.max_dt_s > 0.0 && s.solver.max_dt_s <= 0.1);
    prop_assert!((1.0..=1000.0).contains(&s.solver.steps_per_link));
    prop_assert!((1..=1000).contains(&s.solver.iterations));
    prop_assert!(s.solver.freeze_speed_m_s >= 0.0);
    prop_assert!(core < s.stop.bang_radius_m && s.stop.bang_radius_m < r);
    prop_assert!(s.stop.max_time_s > 0.0 && s.stop.max_time_s <= 1e4);
    prop_assert!(s.stop.bang_cap_s >= 0.0 && s.output.sample_interval_s >= 0.0);
    prop_assert!(s.stop.rest_fraction > 0.0 && s.stop.rest_fraction < 1.0);
    prop_assert!(s.solver.bang_piece_m >= 0.0);
    prop_assert!((1..=1000).contains(&s.solver.bang_iterations));
    prop_assert!((1..=1000).contains(&s.solver.bang_relax_iterations));
    prop_assert!(s.solver.bang_step_rad >= MIN_BANG_STEP_RAD && s.solver.bang_step_rad <= 1.0);
    prop_assert!(s.solver.bang_tolerance.is_none_or(|t| t > 0.0 && t <= 1.0));
    prop_assert!(s.solver.contact_hz > 0.0 && s.solver.joint_hz > 0.0);
    prop_assert!(s.solver.bang_joint_hz > 0.0 && s.output.scene_rate_hz >= 0.0);
    prop_assert!(!s.name.trim().is_empty());
    // The run it asks for is within the budgets.
    let (t_max, dt) = (s.stop.max_time_s, s.solver.max_dt_s);
    prop_assert!(t_max / dt <= MAX_ENGINE_STEPS, "steps at max_dt_s");
    prop_assert!(
        links * s.solver.steps_per_link <= MAX_ENGINE_STEPS,
        "steps per link"
    );
    prop_assert!(
        t_max / s.output.sample_interval_s.max(dt) <= MAX_SAMPLES,
        "samples"
    );
    prop_assert!(
        t_max * s.output.scene_rate_hz.min(1.0 / dt) * (links + 1.0) <= MAX_FRAME_NODES,
        "drawn nodes"
    );
    // The geometry the model builds from it is finite and has at least one link per turn.
    let spiral = Spiral::wound(r, b, core);
    prop_assert!(spiral.length().is_finite() && spiral.length() > 0.0);
    let nodes = spiral.link_nodes(s.discretisation.links_per_turn);
    prop_assert!(nodes.len() >= 2 && nodes.iter().all(|p| p.is_finite()));
    Ok(())
}

/// A value for a float key: mostly the yoga mat's `valid` value (so that later rules are
/// reached), else ordinary magnitudes of either sign, zero, and the edges of f64.
fn float_value(valid: String) -> impl Strategy<Value = String> {
    prop_oneof![
        12 => Just(valid),
        1 => (-12i32..4, 1.0f64..10.0, any::<bool>())
            .prop_map(|(e, m, neg)| format!("{}{m}e{e}", if neg { "-" } else { "" })),
        1 => prop::sample::select(vec![
            "0.0", "-0.0", "nan", "-nan", "inf", "-inf", "1e308", "-1e308", "5e-324", "1.7976931348623157e308",
            "0", "1", "-1", "32", "\"1.0\"", "true", "[1.0]", "{ a = 1 }",
        ])
        .prop_map(str::to_owned),
    ]
}

/// A value for an integer key: mostly `valid`, else any count or a wrong form.
fn int_value(valid: String) -> impl Strategy<Value = String> {
    prop_oneof![
        12 => Just(valid),
        1 => (-10i64..5000).prop_map(|v| v.to_string()),
        1 => prop::sample::select(vec![
            "0", "-1", "4096", "4097", "9223372036854775807", "-9223372036854775808",
            "99999999999999999999", "3.0", "\"7\"", "nan",
        ])
        .prop_map(str::to_owned),
    ]
}

/// Any of a few values of the wrong form or out of range for a boolean, string or enum key.
fn other_value(valid: String, odd: Vec<&'static str>) -> BoxedStrategy<String> {
    let odd: Vec<String> = odd.into_iter().map(str::to_owned).collect();
    prop_oneof![8 => Just(valid), 1 => prop::sample::select(odd)].boxed()
}

/// A value for `key` by the form of its valid value: float, integer, boolean or string.
fn value_for(key: &str) -> BoxedStrategy<String> {
    let valid = valid_value(key).unwrap_or_else(|| panic!("no valid value for {key}"));
    match toml::from_str::<toml::Table>(&format!("v = {valid}")).unwrap()["v"] {
        toml::Value::Float(_) => float_value(valid).boxed(),
        toml::Value::Integer(_) => int_value(valid).boxed(),
        toml::Value::Boolean(_) => other_value(valid, vec!["true", "false", "1", "\"yes\""]),
        _ if key == "contact.model" => other_value(valid, vec!["\"bristle\"", "1", "\"\""]),
        _ => other_value(valid, vec!["\" \"", "\"\"", "1", "\"\\u00e9\""]),
    }
}

/// A scene with every key of [`SCENE_KEYS`] set (each one left out with some probability).
fn scene_text() -> impl Strategy<Value = String> {
    let values: Vec<BoxedStrategy<String>> = SCENE_KEYS.iter().map(|k| value_for(k)).collect();
    let present = prop::collection::vec(prop::bool::weighted(0.85), SCENE_KEYS.len());
    (values, present).prop_map(|(values, present)| {
        let mut top = String::new();
        let mut sections: Vec<(&str, String)> = Vec::new();
        for ((key, value), on) in SCENE_KEYS.iter().zip(values).zip(present) {
            if !on {
                continue;
            }
            match key.split_once('.') {
                None => top.push_str(&format!("{key} = {value}\n")),
                Some((section, name)) => {
                    let line = format!("{name} = {value}\n");
                    match sections.iter_mut().find(|(s, _)| *s == section) {
                        Some((_, body)) => body.push_str(&line),
                        None => sections.push((section, line)),
                    }
                }
            }
        }
        for (section, body) in sections {
            top.push_str(&format!("[{section}]\n{body}"));
        }
        top
    })
}

/// A scene whose run-size keys range over many orders of magnitude (log-uniform), so that
/// the budgets on engine steps, samples and drawings decide.
fn run_size_scene_text() -> impl Strategy<Value = String> {
    let log = |lo: f64, hi: f64| (lo..hi).prop_map(|e: f64| 10f64.powf(e));
    (
        (
            log(-12.0, -1.0),
            log(-3.0, 4.0),
            log(0.0, 3.0),
            log(-10.0, 0.0),
        ),
        (
            log(-8.0, -1.0),
            log(-2.0, 12.0),
            3u32..4096,
            log(-4.6, -1.7),
        ),
    )
        .prop_map(|((dt, t_max, per_link, bang_step), (sample, rate, n, b))| {
            format!(
                "[tape]\nouter_radius_m = 0.03\nthickness_m = {b:e}\nmass_kg = 0.2\n\
                 [discretisation]\nlinks_per_turn = {n}\n[push]\ncontact_speed_m_s = 0.1\n\
                 [solver]\nmax_dt_s = {dt:e}\nsteps_per_link = {per_link:e}\n\
                 bang_step_rad = {bang_step:e}\n[stop]\nmax_time_s = {t_max:e}\n\
                 [output]\nsample_interval_s = {sample:e}\nscene_rate_hz = {rate:e}\n"
            )
        })
}

/// A physically plausible scene: every value inside its range, so that the geometric
/// rules (b < R/2, core + 2b <= R, link length, link count, bang radius) decide.
fn plausible_scene_text() -> impl Strategy<Value = String> {
    (
        0.001f64..100.0,
        1e-6f64..0.6,
        0.0f64..1.0,
        1u32..64,
        prop::option::of(0.0f64..1.0),
    )
        .prop_map(|(r, b_over_r, core_frac, n, bang_frac)| {
            let b = r * b_over_r;
            let core = core_frac * (r - 2.0 * b).max(0.0);
            let mut text = format!(
                "[tape]\nouter_radius_m = {r:e}\nthickness_m = {b:e}\nmass_kg = 1.0\n\
                 core_radius_m = {core:e}\n[discretisation]\nlinks_per_turn = {n}\n\
                 [push]\ncontact_speed_m_s = 0.3\n"
            );
            if let Some(k) = bang_frac {
                text.push_str(&format!(
                    "[stop]\nbang_radius_m = {:e}\n",
                    core + k * (r - core)
                ));
            }
            text
        })
}

/// The yoga mat's file with one edit: a byte range replaced by arbitrary text.
fn mutated_scene() -> impl Strategy<Value = String> {
    (0..YOGA.len(), 0usize..40, ".{0,12}").prop_map(|(at, len, insert)| {
        let mut at = at;
        while !YOGA.is_char_boundary(at) {
            at -= 1;
        }
        let mut end = (at + len).min(YOGA.len());
        while !YOGA.is_char_boundary(end) {
            end -= 1;
        }
        format!("{}{insert}{}", &YOGA[..at], &YOGA[end..])
    })
}

/// Cases per property: `PROPTEST_CASES` if set, else 2000 (12,000 in all, about a second).
fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000)
}

proptest! {
    // Failing cases are kept in proptest-regressions/fuzz.txt (commit it) and rerun first.
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/fuzz.txt",
        ))),
        ..ProptestConfig::with_cases(cases())
    })]

    #[test]
    fn arbitrary_text_never_panics(text in any::<String>()) {
        load_and_check(&text)?;
    }

    #[test]
    fn toml_like_text_never_panics(text in "([a-z_\\[\\]]{0,12} ?= ?[-0-9.e+naif\"]{0,10}\n){0,12}") {
        load_and_check(&text)?;
    }

    #[test]
    fn mutated_scene_never_panics(text in mutated_scene()) {
        load_and_check(&text)?;
    }

    #[test]
    fn every_key_over_wide_ranges(text in scene_text()) {
        load_and_check(&text)?;
    }

    #[test]
    fn plausible_geometry_accepted_scenes_keep_their_invariants(text in plausible_scene_text()) {
        load_and_check(&text)?;
    }

    #[test]
    fn run_size_keys_accepted_scenes_keep_their_budgets(text in run_size_scene_text()) {
        load_and_check(&text)?;
    }
}

#[test]
fn every_scene_key_has_a_valid_value_that_loads() {
    for key in SCENE_KEYS {
        let value = valid_value(key).unwrap_or_else(|| panic!("no valid value for {key}"));
        if let Err(e) = scene_with_overrides(YOGA, "fuzz", &[Override::new(key, &value)]) {
            panic!("{key} = {value}: {e}");
        }
    }
}
