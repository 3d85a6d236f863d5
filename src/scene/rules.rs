//! The vocabulary of the scene rules, shared by every scene kind: the error for
//! `key = value: rule`, a float as a message shows it, and checks that reject NaN and
//! infinities before their own rule.

use std::fmt::Display;
use std::ops::RangeInclusive;

use crate::scene::SceneError;

/// The error for `key = value` breaking `rule`.
pub(super) fn invalid(key: &str, value: impl Display, rule: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        key: key.to_owned(),
        value: value.to_string(),
        rule: rule.into(),
    }
}

/// The rule a scene breaks where it names `"midpoint"` (`solver.bang_engine`, or a folded
/// chain's `solver.joints`): the nodal chain's midpoint step it named no longer exists.
pub(super) const MIDPOINT_RETIRED: &str = "the midpoint (nodal) chain was retired: use \"exact\" \
     (the default); its results are kept in docs/history.md";

/// The schema error of scene `name` from the TOML parser, its types said in words
/// ([`plain_types`]).
pub(crate) fn parse_error(name: &str, error: &impl Display) -> SceneError {
    SceneError::Parse {
        name: name.to_owned(),
        message: plain_types(&error.to_string()),
    }
}

/// A parser's message with its Rust type names said in words: `expected f64` as `expected a
/// number`, `expected i64` (or any integer type) as `expected a whole number`, and what was
/// found (`string "abc"`, ``floating point `1.5` ``) as `the text "abc"`, `the number 1.5`.
pub(crate) fn plain_types(message: &str) -> String {
    const WORDS: &[(&str, &str)] = &[
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected i64", "expected a whole number"),
        ("expected u64", "expected a whole number"),
        ("expected u32", "expected a whole number"),
        ("expected i32", "expected a whole number"),
        ("expected usize", "expected a whole number"),
        ("expected a boolean", "expected true or false"),
        ("invalid type: string ", "invalid type: the text "),
        ("invalid type: floating point ", "invalid type: the number "),
        ("invalid type: integer ", "invalid type: the whole number "),
        ("invalid type: boolean ", "invalid type: the boolean "),
        ("invalid type: sequence", "invalid type: a list"),
        ("invalid type: map", "invalid type: a table"),
    ];
    let mut plain = message.to_owned();
    for (rust, words) in WORDS {
        plain = plain.replace(rust, words);
    }
    // `expected struct TapeFile`: a section, whose keys are set one by one.
    while let Some(at) = plain.find("expected struct ") {
        let rest = &plain[at + "expected struct ".len()..];
        let end = rest
            .find(|c: char| !c.is_alphanumeric() && c != '_')
            .unwrap_or(rest.len());
        let tail = rest[end..].to_owned();
        plain.truncate(at);
        plain.push_str("expected a section: set one of its keys, section.key=VALUE");
        plain.push_str(&tail);
    }
    plain
}

/// A float as written in messages: plainly, or in exponent form when huge or tiny (so that
/// `1e300` does not print 301 digits).
pub(super) struct Shown(pub(super) f64);

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
pub(super) fn check(
    key: &str,
    value: f64,
    ok: bool,
    rule: impl Into<String>,
) -> Result<f64, SceneError> {
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
pub(super) fn check_int(
    key: &str,
    value: i64,
    range: &RangeInclusive<i64>,
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

/// `name`: the file's, else `default_name`; not blank.
pub(super) fn name(name: Option<String>, default_name: &str) -> Result<String, SceneError> {
    let name = name.unwrap_or_else(|| default_name.to_owned());
    if name.trim().is_empty() {
        return Err(invalid("name", format!("{name:?}"), "must not be empty"));
    }
    // The name names the run's folder (runs/<name>), whose earlier files a run removes.
    if name.contains(['/', '\\'])
        || name == "."
        || name == ".."
        || name.chars().any(char::is_control)
    {
        return Err(invalid(
            "name",
            format!("{name:?}"),
            "must be a plain name, not a path: it names the run's folder, runs/<name>",
        ));
    }
    Ok(name)
}
