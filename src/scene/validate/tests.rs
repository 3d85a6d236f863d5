//! The scene rules' tests: each key's range, its boundary values, and the errors' words.

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
    let s =
        scene_with_overrides(&text, "t", &[Override::new("solver.bang_piece_m", "0.007")]).unwrap();
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
fn the_bang_s_tolerance_is_a_share_or_off() {
    let tolerance = |value: &str| {
        let text = with("solver", "bang_tolerance", value);
        Scene::from_toml_str(&text, "t")
            .unwrap()
            .solver
            .bang_tolerance
    };
    assert_eq!(tolerance("1e-3"), Some(1e-3));
    assert_eq!(tolerance("\"off\""), None);
    // 1e-3 by default.
    assert_eq!(
        Scene::from_toml_str(MINIMAL, "t")
            .unwrap()
            .solver
            .bang_tolerance,
        Some(1e-3)
    );
    let msg = rejects("solver", "bang_tolerance", "\"on\"");
    assert_eq!(
        msg,
        "solver.bang_tolerance = \"on\": must be > 0 and <= 1, or \"off\""
    );
    let msg = rejects("solver", "bang_tolerance", "0.0");
    assert_eq!(
        msg,
        "solver.bang_tolerance = 0: must be > 0 and <= 1, or \"off\""
    );
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
        msg.starts_with("discretisation.links_per_turn = 32: the tape would have 1919968 links"),
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
