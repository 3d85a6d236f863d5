//! The scenes shipped with `uncoil`, built into the binary and the Python package, so that a
//! scene's name (`yoga-mat`) works wherever `uncoil` runs, not only in the repository.
//! A file of that name in the current folder is read first; a name is looked up here only
//! when no such file exists. The hard cases of `scenes/hard/` travel too, named
//! `hard/<stem>` (`uncoil check hard` runs them all).

/// Each shipped scene's name (its file's stem) and its file's text.
const SHIPPED: &[(&str, &str)] = &[
    ("yoga-mat", include_str!("../../scenes/yoga-mat.toml")),
    ("thin-tape", include_str!("../../scenes/thin-tape.toml")),
    ("single-turn", include_str!("../../scenes/single-turn.toml")),
    ("slope-down", include_str!("../../scenes/slope-down.toml")),
    ("slope-up", include_str!("../../scenes/slope-up.toml")),
    ("zero-g", include_str!("../../scenes/zero-g.toml")),
    ("spool", include_str!("../../scenes/spool.toml")),
    (
        "frictionless-spool",
        include_str!("../../scenes/frictionless-spool.toml"),
    ),
    (
        "frictionless-coil",
        include_str!("../../scenes/frictionless-coil.toml"),
    ),
    ("vertical", include_str!("../../scenes/vertical.toml")),
    (
        "folded-chain",
        include_str!("../../scenes/validation/folded-chain.toml"),
    ),
    (
        "cayley-chain",
        include_str!("../../scenes/validation/cayley-chain.toml"),
    ),
];

/// The hard cases (`scenes/hard/`): each one's name, `hard/` and its file's stem, and its
/// file's text, in the order of their names.
const HARD: &[(&str, &str)] = &[
    (
        "hard/bang-1e4",
        include_str!("../../scenes/hard/bang-1e4.toml"),
    ),
    (
        "hard/big-core",
        include_str!("../../scenes/hard/big-core.toml"),
    ),
    (
        "hard/coarse-step",
        include_str!("../../scenes/hard/coarse-step.toml"),
    ),
    (
        "hard/coarsest-links",
        include_str!("../../scenes/hard/coarsest-links.toml"),
    ),
    (
        "hard/friction-0.05",
        include_str!("../../scenes/hard/friction-0.05.toml"),
    ),
    (
        "hard/frictionless",
        include_str!("../../scenes/hard/frictionless.toml"),
    ),
    (
        "hard/one-link-per-turn",
        include_str!("../../scenes/hard/one-link-per-turn.toml"),
    ),
    (
        "hard/push-10",
        include_str!("../../scenes/hard/push-10.toml"),
    ),
    (
        "hard/slope-down-30",
        include_str!("../../scenes/hard/slope-down-30.toml"),
    ),
    (
        "hard/slope-up-10",
        include_str!("../../scenes/hard/slope-up-10.toml"),
    ),
    (
        "hard/thin-1000",
        include_str!("../../scenes/hard/thin-1000.toml"),
    ),
    (
        "hard/thin-300",
        include_str!("../../scenes/hard/thin-300.toml"),
    ),
    (
        "hard/zero-gravity",
        include_str!("../../scenes/hard/zero-gravity.toml"),
    ),
];

/// The shipped scenes' names, the main job's first (the hard cases are [`hard_names`]).
pub fn names() -> Vec<&'static str> {
    SHIPPED.iter().map(|(name, _)| *name).collect()
}

/// The hard cases' names (`hard/bang-1e4`, ...), in order.
pub fn hard_names() -> Vec<&'static str> {
    HARD.iter().map(|(name, _)| *name).collect()
}

/// The text of the shipped scene or hard case `name`.
pub fn text(name: &str) -> Option<&'static str> {
    SHIPPED
        .iter()
        .chain(HARD)
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
}

/// The kind of a shipped scene's text: `folded-chain` for a folded chain's (a top-level
/// `kind`), else `coil`.
pub fn kind(text: &str) -> &'static str {
    match super::declared_kind(text) {
        Some(toml::Value::String(k)) if k == super::folded::KIND => super::folded::KIND,
        _ => "coil",
    }
}

/// Every shipped scene, the scenes then the hard cases, with its kind: what `uncoil
/// scenes` prints and `uncoil.scenes()` returns.
pub fn listed() -> Vec<(&'static str, &'static str)> {
    SHIPPED
        .iter()
        .chain(HARD)
        .map(|&(name, text)| (name, kind(text)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every scene file of `scenes/` is shipped, under its stem, with its file's text.
    #[test]
    fn every_scene_file_is_shipped_as_it_is() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.push(format!("{dir}/validation/folded-chain.toml").into());
        files.push(format!("{dir}/validation/cayley-chain.toml").into());
        assert_eq!(files.len(), SHIPPED.len());
        for path in files {
            let stem = path.file_stem().unwrap().to_str().unwrap();
            let shipped = text(stem).unwrap_or_else(|| panic!("{stem} is not shipped"));
            assert_eq!(shipped, std::fs::read_to_string(&path).unwrap(), "{stem}");
        }
        assert_eq!(kind(text("yoga-mat").unwrap()), "coil");
        assert_eq!(kind(text("folded-chain").unwrap()), "folded-chain");
        assert_eq!(kind(text("cayley-chain").unwrap()), "folded-chain");
    }

    /// Every hard case of `scenes/hard/` is shipped, as `hard/<stem>`, with its file's text.
    #[test]
    fn every_hard_case_is_shipped_as_it_is() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/hard");
        let files: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        assert_eq!(files.len(), HARD.len());
        for path in files {
            let name = format!("hard/{}", path.file_stem().unwrap().to_str().unwrap());
            let shipped = text(&name).unwrap_or_else(|| panic!("{name} is not shipped"));
            assert_eq!(shipped, std::fs::read_to_string(&path).unwrap(), "{name}");
        }
    }
}
