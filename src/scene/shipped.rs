//! The scenes shipped with `uncoil`, built into the binary and the Python package, so that a
//! scene's name (`yoga-mat`) works wherever `uncoil` runs, not only in the repository.
//! A file of that name in the current folder is read first; a name is looked up here only
//! when no such file exists.

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
];

/// The shipped scenes' names, the main job's first.
pub fn names() -> Vec<&'static str> {
    SHIPPED.iter().map(|(name, _)| *name).collect()
}

/// The text of the shipped scene `name`.
pub fn text(name: &str) -> Option<&'static str> {
    SHIPPED.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
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
        assert_eq!(files.len(), SHIPPED.len());
        for path in files {
            let stem = path.file_stem().unwrap().to_str().unwrap();
            let shipped = text(stem).unwrap_or_else(|| panic!("{stem} is not shipped"));
            assert_eq!(shipped, std::fs::read_to_string(&path).unwrap(), "{stem}");
        }
    }
}
