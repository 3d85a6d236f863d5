//! The shipped scene files' comments against the code: each key's comment that states a
//! plain default ("Default 0.001.", "Default \"exact\".") states the one the code applies
//! when the key is left out. Defaults that depend on other keys ("Default: tape.thickness_m")
//! and the required keys are not plain, and are skipped.

use std::path::Path;

use uncoil::scene::Scene;

/// The keys a scene must give (their comments say "Required", or name a default the
/// loader rejects).
const REQUIRED: [&str; 4] = [
    "tape.outer_radius_m",
    "tape.thickness_m",
    "tape.mass_kg",
    "push.contact_speed_m_s",
];

/// A scene of the required keys alone: every other key at its default.
const MINIMAL: &str = "[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\nmass_kg = 1.5\n\
                       [push]\ncontact_speed_m_s = 0.3\n";

/// Each `section.key` of a scene file with the plain default its comment states.
fn stated_defaults(text: &str) -> Vec<(String, String)> {
    let mut section = String::new();
    let mut comment: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if let Some(c) = line.strip_prefix('#') {
            comment.push(c.trim());
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            section = name.to_owned();
        } else if let Some((key, _)) = line.split_once('=') {
            let joined = comment.join(" ");
            if let Some(at) = joined.find("Default ") {
                let stated = joined[at + "Default ".len()..]
                    .split([' ', ',', ';', ':'])
                    .next()
                    .unwrap_or("")
                    .trim_end_matches('.')
                    .to_owned();
                let key = if section.is_empty() {
                    key.trim().to_owned()
                } else {
                    format!("{section}.{}", key.trim())
                };
                out.push((key, stated));
            }
        }
        comment.clear();
    }
    out
}

/// Whether `stated` (a comment's word) is `value` (the default, as JSON).
fn same(stated: &str, value: &serde_json::Value) -> Option<bool> {
    if let Some(s) = stated.strip_prefix('"').and_then(|s| s.strip_suffix('"')) {
        return Some(value.as_str() == Some(s));
    }
    if let Ok(b) = stated.parse::<bool>() {
        return Some(value.as_bool() == Some(b));
    }
    let x = stated.parse::<f64>().ok()?;
    let v = value.as_f64()?;
    Some((x - v).abs() <= 1e-12 * v.abs().max(1e-300))
}

#[test]
fn every_plain_default_in_a_scene_file_is_the_codes() {
    let defaults = serde_json::to_value(Scene::from_toml_str(MINIMAL, "minimal").unwrap()).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<_> = ["", "hard"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(root.join(dir)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let mut checked = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (key, stated) in stated_defaults(&text) {
            // A length given in thicknesses (`solver.bang_piece_b`, `stop.bang_radius_b`)
            // resolves into its key in metres; its comment states that key's default.
            if REQUIRED.contains(&key.as_str()) || key.ends_with("_b") {
                continue;
            }
            let value = key
                .split('.')
                .try_fold(&defaults, |v, part| v.get(part))
                .unwrap_or_else(|| panic!("{}: {key} is no key of a scene", file.display()));
            if let Some(ok) = same(&stated, value) {
                assert!(
                    ok,
                    "{}: {key}'s comment says \"Default {stated}\", the code's is {value}",
                    file.display()
                );
                checked += 1;
            }
        }
    }
    // The yoga mat's and the thin tape's files comment every key.
    assert!(checked >= 40, "only {checked} stated defaults found");
}

#[test]
fn a_stated_default_is_read_from_the_comment_above_its_key() {
    let text =
        "[solver]\n# A step (s). Default 0.001.\nmax_dt_s = 0.002\n# No default.\niterations = 4\n";
    assert_eq!(
        stated_defaults(text),
        [("solver.max_dt_s".to_owned(), "0.001".to_owned())]
    );
}
