//! One `--vary` argument ([`Vary`]): a key and its values (`KEY=V1,V2,...`), an even range
//! of them (`KEY=A..B/N`), or several keys varied together, their values side by side
//! (`KEY1:KEY2=A1:A2,B1:B2`). It parses; the product of several is
//! [`grid`](super::grid::grid).

use std::str::FromStr;

use crate::scene::overrides::{Override, OverrideSyntaxError, check_key};

/// The most values a range `A..B/N` makes: a sweep of more runs is a typo.
const MAX_RANGE: usize = 10_000;

/// One `--vary`: its keys (one, or several varied together) and their settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// Dotted scene keys, in the order given; several are varied together.
    pub keys: Vec<String>,
    /// The settings in the order given, each one override per key (in `keys`' order).
    pub values: Vec<Vec<Override>>,
}

impl Vary {
    /// The keys as given, joined by `:`.
    pub fn name(&self) -> String {
        self.keys.join(":")
    }

    /// One setting's values as given, joined by `:`.
    pub fn raw(setting: &[Override]) -> String {
        setting
            .iter()
            .map(|o| o.raw.as_str())
            .collect::<Vec<_>>()
            .join(":")
    }
}

impl FromStr for Vary {
    type Err = OverrideSyntaxError;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let fail = |rule: String| OverrideSyntaxError {
            arg: arg.to_owned(),
            rule,
        };
        let (keys, list) = arg.split_once('=').ok_or_else(|| {
            fail(
                "expected KEY=V1,V2,..., KEY=A..B/N or KEY1:KEY2=A1:A2,B1:B2, e.g. \
                  solver.iterations=2,4,8"
                    .into(),
            )
        })?;
        let keys: Vec<String> = keys.split(':').map(|k| k.trim().to_owned()).collect();
        for key in &keys {
            check_key(key).map_err(fail)?;
        }
        if let Some(k) = keys
            .iter()
            .enumerate()
            .find(|(i, k)| keys[..*i].contains(k))
        {
            return Err(fail(format!("{} is named twice", k.1)));
        }
        let mut values = Vec::new();
        for item in split_top_level(list, ',') {
            let item = item.trim();
            if item.is_empty() {
                return Err(fail("empty value in the list".into()));
            }
            if let Some(range) = range(item).map_err(&fail)? {
                if keys.len() > 1 {
                    return Err(fail(format!(
                        "{item}: a range A..B/N takes one key, not {}",
                        keys.len()
                    )));
                }
                values.extend(range.iter().map(|v| vec![Override::new(&keys[0], v)]));
                continue;
            }
            let parts = split_top_level(item, ':');
            if parts.len() != keys.len() {
                return Err(fail(format!(
                    "{item}: {} values for {} keys; keys varied together take one value \
                     each, joined by `:` as the keys are",
                    parts.len(),
                    keys.len()
                )));
            }
            let mut setting = Vec::new();
            for (key, raw) in keys.iter().zip(parts) {
                let raw = raw.trim();
                if raw.is_empty() {
                    return Err(fail(format!("{item}: an empty value for {key}")));
                }
                setting.push(Override::new(key, raw));
            }
            values.push(setting);
        }
        Ok(Self { keys, values })
    }
}

/// `A..B/N`: `N` values evenly from `A` to `B`, both included (`None` if `item` is no
/// range). Whole numbers where both ends are and the step is whole; else each value at
/// twelve significant digits, written as short as it reads back.
fn range(item: &str) -> Result<Option<Vec<String>>, String> {
    let quoted = item.starts_with(['"', '\'', '[', '{']);
    let Some((a, rest)) = item.split_once("..").filter(|_| !quoted) else {
        return Ok(None);
    };
    let bad = |why: &str| format!("{item}: {why}; a range is A..B/N, e.g. 0.100..0.107/8");
    let (b, n) = rest.split_once('/').ok_or_else(|| bad("no /N"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| bad("N must be a whole number"))?;
    if !(2..=MAX_RANGE).contains(&n) {
        return Err(bad(&format!("N must be 2 to {MAX_RANGE}")));
    }
    let (a, b) = (a.trim(), b.trim());
    if let (Ok(i), Ok(j)) = (a.parse::<i64>(), b.parse::<i64>()) {
        let span = j.checked_sub(i).ok_or_else(|| bad("too wide"))?;
        if span % (n as i64 - 1) == 0 && span != 0 {
            let step = span / (n as i64 - 1);
            return Ok(Some(
                (0..n as i64).map(|k| (i + k * step).to_string()).collect(),
            ));
        }
    }
    let (x, y) = match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => (x, y),
        _ => return Err(bad("A and B must be finite numbers")),
    };
    if x == y {
        return Err(bad("A and B must differ"));
    }
    let value = |k: usize| {
        let v = x + (y - x) * k as f64 / (n - 1) as f64;
        let v: f64 = format!("{v:.11e}").parse().expect("a number written back");
        let s = v.to_string();
        if s.contains(['.', 'e', 'i', 'N']) {
            s
        } else {
            format!("{s}.0")
        }
    };
    Ok(Some((0..n).map(value).collect()))
}

/// `list` split at each `sep` outside brackets, braces and quotes: a TOML array or table,
/// or a quoted string with a `sep` in it, is one value.
fn split_top_level(list: &str, sep: char) -> Vec<&str> {
    let (mut parts, mut start, mut depth, mut quote) = (Vec::new(), 0, 0i32, None);
    for (i, c) in list.char_indices() {
        match (quote, c) {
            (Some(q), _) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, c) if c == sep && depth == 0 => {
                parts.push(&list[start..i]);
                start = i + sep.len_utf8();
            }
            _ => {}
        }
    }
    parts.push(&list[start..]);
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vary(arg: &str) -> Vary {
        arg.parse().unwrap()
    }

    fn raws(v: &Vary) -> Vec<String> {
        v.values.iter().map(|s| Vary::raw(s)).collect()
    }

    #[test]
    fn vary_parses_a_list() {
        let v = vary("discretisation.links_per_turn=8, 16,32");
        assert_eq!(v.keys, ["discretisation.links_per_turn"]);
        assert_eq!(raws(&v), ["8", "16", "32"]);
        assert_eq!(v.values[1][0].value, toml::Value::Integer(16));
        assert!("a=1,,2".parse::<Vary>().is_err());
        assert!("a".parse::<Vary>().is_err());
    }

    #[test]
    fn a_range_is_n_even_values_both_ends_included() {
        let v = vary("push.contact_speed_m_s=0.100..0.107/8");
        assert_eq!(
            raws(&v),
            [
                "0.1", "0.101", "0.102", "0.103", "0.104", "0.105", "0.106", "0.107"
            ]
        );
        assert_eq!(v.values[0][0].value, toml::Value::Float(0.1));
        assert_eq!(raws(&vary("a=16..64/4")), ["16", "32", "48", "64"]);
        assert_eq!(raws(&vary("a=1..2/3")), ["1.0", "1.5", "2.0"]);
        assert_eq!(raws(&vary("a=0.3,1..2/2")), ["0.3", "1", "2"]);
        assert_eq!(raws(&vary("a=2..1/2")), ["2", "1"]);
        for bad in [
            "a=1..2",
            "a=1..2/1",
            "a=1..2/x",
            "a=1..1/3",
            "a=x..2/3",
            "a=1..2/20000",
            "a:b=1..2/3",
        ] {
            let e = bad.parse::<Vary>().unwrap_err();
            assert!(e.to_string().contains(bad), "{bad}: {e}");
        }
    }

    #[test]
    fn keys_varied_together_take_one_value_each() {
        let v = vary("tape.thickness_m:solver.bang_piece_m=0.003:0.015, 0.001 : 0.005");
        assert_eq!(v.keys, ["tape.thickness_m", "solver.bang_piece_m"]);
        assert_eq!(v.name(), "tape.thickness_m:solver.bang_piece_m");
        assert_eq!(raws(&v), ["0.003:0.015", "0.001:0.005"]);
        assert_eq!(v.values[1][1].key, "solver.bang_piece_m");
        assert_eq!(v.values[1][1].value, toml::Value::Float(0.005));
        let e = "a:b=1:2,3".parse::<Vary>().unwrap_err().to_string();
        assert!(e.contains("1 values for 2 keys"), "{e}");
        assert!("a:b=1:,3:4".parse::<Vary>().is_err());
        assert!(
            "a:a=1:2"
                .parse::<Vary>()
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
        assert!("a:=1:2".parse::<Vary>().is_err());
        assert_eq!(raws(&vary("a:b=\"x:y\":[1, 2]")), ["\"x:y\":[1, 2]"]);
    }

    #[test]
    fn a_list_splits_only_at_its_top_level_commas() {
        assert_eq!(split_top_level("8, 16,32", ','), ["8", " 16", "32"]);
        assert_eq!(
            split_top_level("[1, 2],[3,4], {a = 1, b = 2}", ','),
            ["[1, 2]", "[3,4]", " {a = 1, b = 2}"]
        );
        assert_eq!(
            split_top_level("\"a,b\",'c,d',e", ','),
            ["\"a,b\"", "'c,d'", "e"]
        );
    }
}
