//! The folded chain's scene: its defaults, its rules, and every key it lists.

use super::*;

fn load(extra: &str) -> Result<FoldedChain, SceneError> {
    FoldedChain::from_toml_str(&format!("kind = \"folded-chain\"\n{extra}"), "test")
}

fn rule(extra: &str) -> String {
    load(extra).expect_err("must be rejected").to_string()
}

#[test]
fn defaults_are_the_benchmark() {
    let s = load("").unwrap();
    assert_eq!(s.chain.links, 200);
    assert!((s.chain.separation_m - 0.01).abs() < 1e-15);
    assert_eq!(s.name, "test");
    assert!(!s.floor.enabled);
    assert!((s.chain.fold_depth_m() - 0.495).abs() < 1e-12);
}

#[test]
fn bad_input_names_key_value_and_rule() {
    assert!(rule("[chain]\nseparation_m = -0.001").starts_with("chain.separation_m = -0.001:"));
    assert!(rule("[chain]\nseparation_m = 0.5").contains("two links' length"));
    assert!(rule("[chain]\nlinks = 201").contains("must be even"));
    assert!(rule("[chain]\nlinks = 2").starts_with("chain.links = 2:"));
    assert!(rule("[chain]\nlength_m = 1e-4\nlinks = 400").contains("too short for its"));
    assert!(rule("[pin]\nheight_m = -1").starts_with("pin.height_m = -1:"));
    assert!(rule("[pin]\nheight_m = 0.3\n[floor]\nenabled = true").contains("below the world"));
    assert!(rule("[solver]\ndt_s = nan").contains("must be finite"));
    assert!(rule("[stop]\ntip_fraction = 1").starts_with("stop.tip_fraction = 1:"));
    assert!(rule("[chain]\nlinkz = 4").starts_with("cannot parse scene test"));
    assert!(rule("[solver]\njoints = \"ball\"").starts_with("solver.joints = \"ball\":"));
    // Cayley's start and the thickness.
    let hanging = "[floor]\nenabled = true\n[start]\nshape = \"hanging\"\n";
    assert!(rule("[start]\nshape = \"lying\"").starts_with("start.shape = \"lying\":"));
    assert!(rule("[start]\ntilt_rad = 0.1").contains("only a hanging start is tilted"));
    assert!(rule(&format!("{hanging}[chain]\nseparation_m = 0.01")).contains("has no fold"));
    assert!(rule(&format!("{hanging}[pin]\nheight_m = 1")).contains("has no pin"));
    assert!(rule("[start]\nshape = \"hanging\"").starts_with("floor.enabled = false:"));
    assert!(
        rule(&format!("{hanging}[solver]\njoints = \"impulse\"")).contains("must be \"exact\"")
    );
    assert!(rule("[chain]\nthickness_m = 0.006").starts_with("chain.thickness_m = 0.006:"));
    assert!(rule("[chain]\nthickness_m = -1").contains("must be >= 0"));
    let tilt = |t: &str| rule(&format!("{hanging}tilt_rad = {t}"));
    assert!(tilt("0.6").contains("must be >= 0 and <= 0.5"));
    assert!(tilt("nan").contains("must be finite"));
}

#[test]
fn a_hanging_chain_stands_on_the_floor_with_its_top_at_its_length() {
    let s = load(
        "[chain]\nlinks = 7\nthickness_m = 0.002\n[start]\nshape = \"hanging\"\n\
         tilt_rad = 0.1\n[floor]\nenabled = true",
    )
    .unwrap();
    assert_eq!(s.start, Start::Hanging { tilt_rad: 0.1 });
    // An odd count is allowed: no fold to split.
    assert_eq!(s.chain.links, 7);
    assert!((s.pin_height_m - (0.001 + 0.1f64.cos())).abs() < 1e-15);
}

#[test]
fn the_key_list_is_what_the_file_accepts() {
    for key in FOLDED_KEYS
        .iter()
        .filter(|k| **k != "kind" && **k != "name")
    {
        let (section, k) = key.split_once('.').unwrap();
        let value = match k {
            "links" | "substeps" | "relax_iterations" => "4",
            "enabled" => "false",
            "joints" => "\"multibody\"",
            "separation_m" => "0",
            "height_m" => "2.0",
            "tip_fraction" | "rest_fraction" => "0.5",
            _ => "0.001",
        };
        let text = match k {
            "shape" => "[start]\nshape = \"fold\"".to_owned(),
            "tilt_rad" => "[start]\nshape = \"hanging\"\ntilt_rad = 0.1\n[floor]\n\
                           enabled = true"
                .to_owned(),
            _ => format!("[{section}]\n{k} = {value}"),
        };
        load(&text).unwrap_or_else(|e| panic!("{key}: {e}"));
    }
}
