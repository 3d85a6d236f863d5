//! Scene overrides by dotted key (`discretisation.links_per_turn=16`): sets values in the
//! scene's TOML before it is deserialised, so an overridden value meets exactly the same
//! schema and validation as one written in the file. It does not know the schema itself:
//! an unknown key or a bad value is reported by [`Scene`]'s own [`SceneError`].

use std::fmt;
use std::str::FromStr;

use crate::scene::file::ALTERNATIVES;
use crate::scene::folded::{self, FoldedChain};
use crate::scene::{AnyScene, Scene, SceneError};

/// One `KEY=VALUE` override. The value is read as a TOML value (`16`, `0.001`, `"spiral"`,
/// `true`); a word that is not valid TOML is taken as a string, so `contact.model=spiral`
/// works without quotes.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// Dotted key with its section path, e.g. `solver.max_dt_s`.
    pub key: String,
    /// The value as written on the command line.
    pub raw: String,
    /// The value as TOML.
    pub value: toml::Value,
}

/// A malformed `KEY=VALUE` argument.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{arg}`: {rule}")]
pub struct OverrideSyntaxError {
    /// The argument as given.
    pub arg: String,
    /// What is wrong with it.
    pub rule: String,
}

/// Reads `text` as one TOML value, or as a plain string if it is not valid TOML.
pub fn parse_value(text: &str) -> toml::Value {
    let doc = format!("v = {text}");
    match toml::from_str::<toml::Table>(&doc) {
        Ok(mut t) => t.remove("v").unwrap_or_else(|| text.into()),
        Err(_) => toml::Value::String(text.to_owned()),
    }
}

/// Checks that `key` is a dotted path of bare TOML keys (`a.b`, no empty part).
pub fn check_key(key: &str) -> Result<(), String> {
    let ok_part = |p: &str| {
        !p.is_empty()
            && p.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    if key.split('.').all(ok_part) {
        Ok(())
    } else {
        Err("the key must be a dotted path of bare TOML keys, e.g. solver.max_dt_s".into())
    }
}

impl Override {
    /// An override of `key` by `raw` (read with [`parse_value`]).
    pub fn new(key: &str, raw: &str) -> Self {
        Self {
            key: key.to_owned(),
            raw: raw.to_owned(),
            value: parse_value(raw),
        }
    }
}

impl FromStr for Override {
    type Err = OverrideSyntaxError;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let fail = |rule: String| OverrideSyntaxError {
            arg: arg.to_owned(),
            rule,
        };
        let (key, raw) = arg
            .split_once('=')
            .ok_or_else(|| fail("expected KEY=VALUE, e.g. solver.max_dt_s=0.0005".into()))?;
        let key = key.trim();
        check_key(key).map_err(fail)?;
        let raw = raw.trim();
        if raw.is_empty() {
            return Err(fail("the value is empty".into()));
        }
        Ok(Self::new(key, raw))
    }
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}", self.key, self.raw)
    }
}

/// Sets `key` (dotted) to `value` in `table`, creating missing sections.
fn set(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), SceneError> {
    let parts: Vec<&str> = key.split('.').collect();
    let (last, sections) = parts.split_last().expect("split yields at least one part");
    let mut t = table;
    for (i, part) in sections.iter().enumerate() {
        let entry = t
            .entry((*part).to_owned())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            other => {
                return Err(SceneError::Invalid {
                    key: key.to_owned(),
                    value: value.to_string(),
                    rule: format!(
                        "`{}` is a value ({other}), not a section",
                        parts[..=i].join(".")
                    ),
                });
            }
        };
    }
    t.insert((*last).to_owned(), value);
    Ok(())
}

/// Parses scene TOML `text`, applies `overrides` in order, and validates the result as
/// [`Scene::from_toml_str`] does (`name` is the fallback scene name). The scene's
/// `source_text` is the original text followed by one `# override:` comment per override.
pub fn scene_with_overrides(
    text: &str,
    name: &str,
    overrides: &[Override],
) -> Result<Scene, SceneError> {
    if overrides.is_empty() {
        return Scene::from_toml_str(text, name);
    }
    let parse = |t: &str| Scene::from_toml_str(t, name);
    let set = edited(text, name, overrides)?;
    let mut scene =
        parse(&set).map_err(|e| after(e, overrides, |o| alone_error(text, name, o, parse)))?;
    scene.source_text = noted(text, overrides);
    Ok(scene)
}

/// Reads the scene file at `path` and applies `overrides` (see [`scene_with_overrides`]);
/// the scene name defaults to the file stem.
pub fn scene_file_with_overrides(
    path: &std::path::Path,
    overrides: &[Override],
) -> Result<Scene, SceneError> {
    let (text, stem) = crate::scene::read_scene_file(path)?;
    scene_with_overrides(&text, &stem, overrides).map_err(|e| e.in_file(path))
}

/// Reads the scene file at `path`, of either kind (its top-level `kind`), and applies
/// `overrides` as [`scene_with_overrides`] does.
pub fn any_scene_file_with_overrides(
    path: &std::path::Path,
    overrides: &[Override],
) -> Result<AnyScene, SceneError> {
    any_scene_text(path, overrides).map_err(|e| e.in_file(path))
}

/// [`any_scene_file_with_overrides`], its parse errors naming the scene by its name.
fn any_scene_text(path: &std::path::Path, overrides: &[Override]) -> Result<AnyScene, SceneError> {
    let (text, stem) = crate::scene::read_scene_file(path)?;
    match crate::scene::declared_kind(&text) {
        None => scene_with_overrides(&text, &stem, overrides).map(|s| AnyScene::Coil(Box::new(s))),
        Some(toml::Value::String(k)) if k == folded::KIND => {
            let parse = |t: &str| FoldedChain::from_toml_str(t, &stem);
            let set = edited(&text, &stem, overrides)?;
            let mut chain = parse(&set)
                .map_err(|e| after(e, overrides, |o| alone_error(&text, &stem, o, parse)))?;
            chain.source_text = noted(&text, overrides);
            Ok(AnyScene::FoldedChain(chain))
        }
        Some(other) => Err(SceneError::Invalid {
            key: "kind".into(),
            value: other.to_string(),
            rule: format!("must be \"{}\", or absent for a coil", folded::KIND),
        }),
    }
}

/// `text` with `overrides` set in it, written back as TOML.
fn edited(text: &str, name: &str, overrides: &[Override]) -> Result<String, SceneError> {
    if overrides.is_empty() {
        return Ok(text.to_owned());
    }
    let mut table: toml::Table = toml::from_str(text).map_err(|e| SceneError::Parse {
        name: name.to_owned(),
        message: e.to_string(),
    })?;
    // A length given on the command line one way replaces the file's other way of giving
    // it (two on the command line are refused by the scene's rules).
    for o in overrides {
        let other = ALTERNATIVES.iter().find_map(|&(a, b)| {
            (o.key == a)
                .then_some(b)
                .or_else(|| (o.key == b).then_some(a))
        });
        if let Some((section, key)) = other.and_then(|k| k.split_once('.'))
            && let Some(toml::Value::Table(t)) = table.get_mut(section)
        {
            t.remove(key);
        }
    }
    for o in overrides {
        set(&mut table, &o.key, o.value.clone())?;
    }
    toml::to_string(&table).map_err(|e| SceneError::Parse {
        name: name.to_owned(),
        message: format!("cannot write the overridden scene back as TOML: {e}"),
    })
}

/// A parse error of the edited text, naming the override that causes it (the one whose own
/// error, `alone`, is the same), or else the overrides it came after. The parser's location
/// (a line of the scene as rewritten with the overrides, a text the user never wrote) is
/// dropped; its message is kept.
fn after(
    e: SceneError,
    overrides: &[Override],
    alone: impl Fn(&Override) -> Option<String>,
) -> SceneError {
    match e {
        SceneError::Parse { name, message } if !overrides.is_empty() => {
            let core = core(&message);
            let message = match overrides
                .iter()
                .find(|o| alone(o).is_some_and(|own| own == core))
            {
                Some(o) => format!("{o}: {core}"),
                None => format!("{core} (after the overrides {})", list(overrides)),
            };
            SceneError::Parse { name, message }
        }
        other => other,
    }
}

/// A parser's message without its location: the lines after the one that points (`^`).
fn core(message: &str) -> String {
    let lines: Vec<&str> = message
        .lines()
        .skip_while(|l| !l.contains('^'))
        .skip(1)
        .collect();
    if lines.is_empty() {
        message.trim_end().to_owned()
    } else {
        lines.join("\n")
    }
}

/// The schema error (not a rule's) of `text` with the one override `o`, as `parse` reads
/// it, without its location; `None` if it parses.
fn alone_error<T>(
    text: &str,
    name: &str,
    o: &Override,
    parse: impl Fn(&str) -> Result<T, SceneError>,
) -> Option<String> {
    match edited(text, name, std::slice::from_ref(o)).and_then(|t| parse(&t)) {
        Err(SceneError::Parse { message, .. }) => Some(core(&message)),
        _ => None,
    }
}

/// The file's text followed by one `# override:` comment per override.
fn noted(text: &str, overrides: &[Override]) -> String {
    let mut source = text.to_owned();
    if overrides.is_empty() {
        return source;
    }
    if !source.ends_with('\n') {
        source.push('\n');
    }
    for o in overrides {
        source.push_str(&format!("# override: {} = {}\n", o.key, o.value));
    }
    source
}

fn list(overrides: &[Override]) -> String {
    overrides
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const YOGA: &str = include_str!("../../scenes/yoga-mat.toml");

    fn ov(arg: &str) -> Override {
        arg.parse().unwrap()
    }

    #[test]
    fn values_are_read_as_toml() {
        assert_eq!(parse_value("16"), toml::Value::Integer(16));
        assert_eq!(parse_value("0.5"), toml::Value::Float(0.5));
        assert_eq!(parse_value("spiral"), toml::Value::String("spiral".into()));
        assert_eq!(
            parse_value("\"spiral\""),
            toml::Value::String("spiral".into())
        );
        assert_eq!(parse_value("1e-4"), toml::Value::Float(1e-4));
    }

    #[test]
    fn good_overrides_change_the_scene() {
        let s = scene_with_overrides(
            YOGA,
            "y",
            &[
                ov("discretisation.links_per_turn=16"),
                ov("solver.max_dt_s=5e-4"),
                ov("contact.model=spiral"),
                ov("stop.bang_cap_s = 0"),
            ],
        )
        .unwrap();
        assert_eq!(s.discretisation.links_per_turn, 16);
        assert!((s.solver.max_dt_s - 5e-4).abs() < 1e-18);
        assert!(s.stop.bang_cap_s.abs() < 1e-18);
        assert!(s.source_text.starts_with(YOGA));
        assert!(
            s.source_text
                .contains("# override: discretisation.links_per_turn = 16")
        );
        // Everything else is as in the file.
        let base = Scene::from_toml_str(YOGA, "y").unwrap();
        assert_eq!(s.tape, base.tape);
        assert_eq!(s.name, base.name);
    }

    #[test]
    fn an_integer_is_accepted_for_a_float_key() {
        let s = scene_with_overrides(YOGA, "y", &[ov("gravity.g_m_s2=10")]).unwrap();
        assert!((s.gravity.g_m_s2 - 10.0).abs() < 1e-12);
    }

    #[test]
    fn a_missing_section_is_created() {
        let text = "[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\nmass_kg = 1.5\n";
        let s = scene_with_overrides(text, "t", &[ov("push.contact_speed_m_s=0.2")]).unwrap();
        assert!((s.push.contact_speed_m_s - 0.2).abs() < 1e-12);
    }

    #[test]
    fn a_bad_value_gets_the_scene_rule() {
        let e = scene_with_overrides(YOGA, "y", &[ov("discretisation.links_per_turn=5000")])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "discretisation.links_per_turn = 5000: must be >= 3 and <= 4096"
        );
        let e = scene_with_overrides(YOGA, "y", &[ov("solver.max_dt_s=-1")])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("solver.max_dt_s = -1: must be > 0"), "{e}");
    }

    #[test]
    fn an_unknown_key_is_named() {
        let e = scene_with_overrides(YOGA, "y", &[ov("solver.max_dt=0.001")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `max_dt`"), "{e}");
        assert!(e.contains(": solver.max_dt=0.001: "), "{e}");
        // No line of the rewritten text the user never wrote.
        assert!(!e.contains("parse error at line"), "{e}");
        let e = scene_with_overrides(YOGA, "y", &[ov("colour.hue=1")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `colour`"), "{e}");
    }

    #[test]
    fn a_wrong_type_is_named() {
        let e = scene_with_overrides(YOGA, "y", &[ov("contact.model=glue")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown variant `glue`"), "{e}");
    }

    /// A type error names the override that made it, among others, with its types in
    /// words.
    #[test]
    fn a_type_error_names_its_override_in_words() {
        let overrides = [
            ov("push.contact_speed_m_s=0.2"),
            ov("tape.thickness_m=abc"),
            ov("discretisation.links_per_turn=1.5"),
        ];
        let e = scene_with_overrides(YOGA, "y", &overrides[..2])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "cannot parse scene y: tape.thickness_m=abc: invalid type: the text \"abc\", \
             expected a number"
        );
        let e = scene_with_overrides(YOGA, "y", &overrides)
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with(
                ": discretisation.links_per_turn=1.5: invalid type: the number \
                         `1.5`, expected a whole number"
            ),
            "{e}"
        );
    }

    #[test]
    fn a_value_is_not_a_section() {
        let e = scene_with_overrides(YOGA, "y", &[ov("tape.mass_kg.x=1")])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "tape.mass_kg.x = 1: `tape.mass_kg` is a value (1.5), not a section"
        );
    }

    #[test]
    fn malformed_arguments_are_rejected() {
        for (arg, rule) in [
            ("links", "expected KEY=VALUE"),
            ("=3", "dotted path"),
            ("a..b=3", "dotted path"),
            ("a b=3", "dotted path"),
            ("solver.max_dt_s=", "the value is empty"),
        ] {
            let e = arg.parse::<Override>().unwrap_err().to_string();
            assert!(e.contains(rule), "{arg}: {e}");
        }
    }
}
