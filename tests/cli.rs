//! The `uncoil` binary on bad input: pins the error text on stderr, the exit code (2 for a
//! bad scene, 1 for a run-time failure), an empty stdout, and that no output is written.

use std::path::Path;

use assert_cmd::Command;
use predicates::prelude::*;

/// The base scene (the yoga mat); each case edits it.
const BASE: &str = r#"name = "case"
[tape]
outer_radius_m = 0.06
thickness_m = 0.005
mass_kg = 1.5
[push]
contact_speed_m_s = 0.3
"#;

/// How a case changes [`BASE`].
#[derive(Clone, Copy)]
enum Edit {
    /// Replace the exact line `.0` (which must occur in `BASE`) with `.1` (may be several
    /// lines, or empty to delete the line).
    Replace(&'static str, &'static str),
    /// Append these lines (e.g. a new section) to the end of the file.
    Append(&'static str),
}

impl Edit {
    fn apply(self, case: &str) -> String {
        match self {
            Edit::Replace(from, to) => {
                let from_line = format!("{from}\n");
                assert!(
                    BASE.contains(&from_line),
                    "case {case}: `{from}` is not a line of BASE"
                );
                let to_line = if to.is_empty() {
                    String::new()
                } else {
                    format!("{to}\n")
                };
                BASE.replacen(&from_line, &to_line, 1)
            }
            Edit::Append(text) => format!("{BASE}{text}\n"),
        }
    }
}

/// Bad scenes: (case name, edit of [`BASE`], substrings stderr must contain). Each must exit
/// with code 2 before any output is written. The scene file is always `case.toml`, so a
/// parse error names the scene `case`.
const BAD_SCENES: &[(&str, Edit, &[&str])] = &[
    (
        "unknown key in [tape]",
        Edit::Replace("mass_kg = 1.5", "mass_kg = 1.5\ncolour = 1"),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "line 6, column 1",
            "unknown field `colour`",
            "expected one of `outer_radius_m`, `thickness_m`, `mass_kg`, `core_radius_m`",
        ],
    ),
    (
        "wrong type",
        Edit::Replace("mass_kg = 1.5", "mass_kg = \"heavy\""),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "line 5, column 11",
            "mass_kg = \"heavy\"",
            "invalid type: the text \"heavy\", expected a number",
        ],
    ),
    (
        "missing required key",
        Edit::Replace("mass_kg = 1.5", ""),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "missing field `mass_kg`",
        ],
    ),
    (
        "negative thickness",
        Edit::Replace("thickness_m = 0.005", "thickness_m = -0.005"),
        &[
            "tape.thickness_m = -0.005: ",
            "must be > 0 and < tape.outer_radius_m / 2 (= 0.03): at least one full turn",
        ],
    ),
    (
        "zero mass",
        Edit::Replace("mass_kg = 1.5", "mass_kg = 0.0"),
        &["tape.mass_kg = 0: must be > 0"],
    ),
    (
        "NaN outer radius",
        Edit::Replace("outer_radius_m = 0.06", "outer_radius_m = nan"),
        &["tape.outer_radius_m = NaN: must be finite"],
    ),
    (
        "thickness of half the radius",
        Edit::Replace("thickness_m = 0.005", "thickness_m = 0.03"),
        &[
            "tape.thickness_m = 0.03: ",
            "must be > 0 and < tape.outer_radius_m / 2",
            "at least one full turn",
        ],
    ),
    (
        "core leaving less than one turn",
        Edit::Replace("mass_kg = 1.5", "mass_kg = 1.5\ncore_radius_m = 0.055"),
        &[
            "tape.core_radius_m = 0.055: ",
            "must be >= 0 and <= tape.outer_radius_m - 2 * tape.thickness_m",
            "must leave at least one full turn of the tape's midline",
        ],
    ),
    (
        "two links per turn",
        Edit::Append("[discretisation]\nlinks_per_turn = 2"),
        &["discretisation.links_per_turn = 2: a link must be shorter than the outer radius"],
    ),
    (
        "negative friction",
        Edit::Append("[floor]\nfriction = -0.5"),
        &["floor.friction = -0.5: must be >= 0"],
    ),
    (
        "slope of 45 degrees",
        Edit::Append("[floor]\nslope_deg = 45.0"),
        &["floor.slope_deg = 45: must be > -45 and < 45"],
    ),
    (
        "zero solver iterations",
        Edit::Append("[solver]\niterations = 0"),
        &["solver.iterations = 0: must be >= 1 and <= 1000"],
    ),
    (
        "zero push",
        Edit::Replace("contact_speed_m_s = 0.3", "contact_speed_m_s = 0.0"),
        &[
            "push.contact_speed_m_s = 0: ",
            "must be > 0: a coil at rest on a level floor stays at rest",
        ],
    ),
    (
        "huge push",
        Edit::Replace("contact_speed_m_s = 0.3", "contact_speed_m_s = 1e9"),
        &["push.contact_speed_m_s = 1000000000: must be > 0 and <= 1000"],
    ),
    // Unknown keys and sections.
    (
        "unknown top-level key",
        Edit::Replace("name = \"case\"", "name = \"case\"\ncolour = \"red\""),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "unknown field `colour`",
            "`tape`",
        ],
    ),
    (
        "unknown section",
        Edit::Append("[wind]\nspeed_m_s = 3.0"),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "unknown field `wind`",
            "`discretisation`",
        ],
    ),
    (
        "misspelt key",
        Edit::Append("[solver]\nmax_dt = 0.001"),
        &["unknown field `max_dt`", "`max_dt_s`"],
    ),
    // Wrong types.
    (
        "fractional link count",
        Edit::Append("[discretisation]\nlinks_per_turn = 32.5"),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "invalid type: the number `32.5`, expected a whole number",
        ],
    ),
    (
        "boolean mass",
        Edit::Replace("mass_kg = 1.5", "mass_kg = true"),
        &["invalid type: the boolean `true`, expected a number"],
    ),
    (
        "array radius",
        Edit::Replace("outer_radius_m = 0.06", "outer_radius_m = [0.06]"),
        &["invalid type: a list, expected a number"],
    ),
    (
        "unknown contact model",
        Edit::Append("[contact]\nmodel = \"bristle\""),
        &["unknown variant `bristle`, expected `spiral`"],
    ),
    (
        "not TOML at all",
        Edit::Append("this is not toml"),
        &[
            "cannot parse scene ",
            "case.toml: ",
            "line 8, column 6",
            "key with no value, expected `=`",
        ],
    ),
    // Negative, zero, NaN and infinite values.
    (
        "negative core",
        Edit::Replace("mass_kg = 1.5", "mass_kg = 1.5\ncore_radius_m = -0.01"),
        &["tape.core_radius_m = -0.01: must be >= 0"],
    ),
    (
        "negative gravity",
        Edit::Append("[gravity]\ng_m_s2 = -9.81"),
        &["gravity.g_m_s2 = -9.81: must be >= 0 and <= 1000"],
    ),
    (
        "zero outer radius",
        Edit::Replace("outer_radius_m = 0.06", "outer_radius_m = 0.0"),
        &["tape.outer_radius_m = 0: must be >= 0.001 and <= 100"],
    ),
    (
        "zero time step",
        Edit::Append("[solver]\nmax_dt_s = 0.0"),
        &["solver.max_dt_s = 0: must be > 0 and <= 0.1"],
    ),
    (
        "NaN push",
        Edit::Replace("contact_speed_m_s = 0.3", "contact_speed_m_s = nan"),
        &["push.contact_speed_m_s = NaN: must be finite"],
    ),
    (
        "infinite mass",
        Edit::Replace("mass_kg = 1.5", "mass_kg = inf"),
        &["tape.mass_kg = inf: must be finite"],
    ),
    (
        "negative infinite friction",
        Edit::Append("[floor]\nfriction = -inf"),
        &["floor.friction = -inf: must be finite"],
    ),
    // Huge and tiny values.
    (
        "huge radius",
        Edit::Replace("outer_radius_m = 0.06", "outer_radius_m = 1e300"),
        &["tape.outer_radius_m = 1e300: must be >= 0.001 and <= 100"],
    ),
    (
        "huge mass",
        Edit::Replace("mass_kg = 1.5", "mass_kg = 1e300"),
        &["tape.mass_kg = 1e300: must be > 0 and <= 1000000"],
    ),
    (
        "link count beyond i64",
        Edit::Append("[discretisation]\nlinks_per_turn = 99999999999999999999"),
        &["cannot parse scene ", "case.toml: ", "line 9"],
    ),
    (
        "huge link count",
        Edit::Append("[discretisation]\nlinks_per_turn = 5000"),
        &["discretisation.links_per_turn = 5000: must be >= 3 and <= 4096"],
    ),
    (
        "tape too thin for its links",
        Edit::Replace("thickness_m = 0.005", "thickness_m = 1e-9"),
        &[
            "discretisation.links_per_turn = 32: the tape would have ",
            "more than 1000000: use fewer links per turn or a thicker tape",
        ],
    ),
    (
        "huge gravity",
        Edit::Append("[gravity]\ng_m_s2 = 1e6"),
        &["gravity.g_m_s2 = 1000000: must be >= 0 and <= 1000"],
    ),
    (
        "huge steps per link",
        Edit::Append("[solver]\nsteps_per_link = 1e9"),
        &["solver.steps_per_link = 1000000000: must be >= 1 and <= 1000"],
    ),
    (
        "huge max time",
        Edit::Append("[stop]\nmax_time_s = 1e9"),
        &["stop.max_time_s = 1000000000: must be > 0 and <= 10000"],
    ),
    // Values that pass their own range but would make the run endless.
    (
        "tiny time step",
        Edit::Append("[solver]\nmax_dt_s = 1e-308"),
        &[
            "solver.max_dt_s = 1e-308: must be >= stop.max_time_s / 1e8 (= 6e-7): ",
            "a run may take at most 1e8 engine steps",
        ],
    ),
    (
        "tiny bang step",
        Edit::Append("[solver]\nbang_step_rad = 1e-300"),
        &[
            "solver.bang_step_rad = 1e-300: must be >= 0.0001: a run may take at most 1e8 engine steps",
        ],
    ),
    // Inconsistent geometry.
    (
        "one link per turn",
        Edit::Append("[discretisation]\nlinks_per_turn = 1"),
        &[
            "discretisation.links_per_turn = 1: a link must be shorter than the outer radius",
            "the coarsest this tape allows is 7 links per turn",
        ],
    ),
    (
        "bang radius beyond the coil",
        Edit::Append("[stop]\nbang_radius_m = 0.07"),
        &[
            "stop.bang_radius_m = 0.07: must be > tape.core_radius_m (= 0) and < tape.outer_radius_m (= 0.06)",
        ],
    ),
    (
        "bang radius inside the core",
        Edit::Replace(
            "mass_kg = 1.5",
            "mass_kg = 1.5\ncore_radius_m = 0.02\n[stop]\nbang_radius_m = 0.01",
        ),
        &["stop.bang_radius_m = 0.01: must be > tape.core_radius_m (= 0.02)"],
    ),
    (
        "zero push without gravity",
        Edit::Replace(
            "contact_speed_m_s = 0.3",
            "contact_speed_m_s = 0.0\n[gravity]\ng_m_s2 = 0.0",
        ),
        &["push.contact_speed_m_s = 0: must be > 0 when gravity.g_m_s2 = 0: nothing would move"],
    ),
    (
        "the retired midpoint chain",
        Edit::Append("[solver]\nbang_engine = \"midpoint\""),
        &[
            "solver.bang_engine = \"midpoint\": the midpoint (nodal) chain was retired: use \
             \"exact\" (the default); its results are kept in docs/history.md\n",
        ],
    ),
];

/// The command `uncoil run <scene> --out <out>`.
fn run_command(scene: &Path, out: &Path) -> Command {
    let mut cmd = Command::cargo_bin("uncoil").unwrap();
    cmd.arg("run").arg(scene).arg("--out").arg(out);
    cmd
}

/// `uncoil run <scene> --out <out>`, returning (exit code, stdout, stderr).
fn run(scene: &Path, out: &Path) -> (Option<i32>, String, String) {
    let output = run_command(scene, out).output().unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn bad_scenes_exit_2_with_message_and_no_output() {
    let mut failures = Vec::new();
    for &(case, edit, expected) in BAD_SCENES {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("case.toml");
        let out = dir.path().join("out");
        std::fs::write(&scene, edit.apply(case)).unwrap();
        let (code, stdout, stderr) = run(&scene, &out);

        let mut problems = Vec::new();
        if code != Some(2) {
            problems.push(format!("exit code {code:?}, expected Some(2)"));
        }
        if !stderr.starts_with("error: ") {
            problems.push("stderr does not start with `error: `".to_owned());
        }
        for want in expected.iter() {
            if !stderr.contains(want) {
                problems.push(format!("stderr lacks `{want}`"));
            }
        }
        if !stdout.is_empty() {
            problems.push(format!("stdout is not empty: {stdout:?}"));
        }
        if out.exists() {
            problems.push(format!("output folder {} was created", out.display()));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "case `{case}`:\n  - {}\n  stderr:\n{stderr}",
                problems.join("\n  - ")
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} bad-scene cases failed:\n\n{}",
        failures.len(),
        BAD_SCENES.len(),
        failures.join("\n")
    );
}

/// Hostile overrides of a shipped scene: each is refused at once, before the run starts,
/// naming the key and the budget it would break, or the retired engine it names.
const HOSTILE_OVERRIDES: &[(&[&str], &[&str])] = &[
    (
        &["solver.max_dt_s=1e-308"],
        &[
            "error: solver.max_dt_s = 1e-308: must be >= stop.max_time_s / 1e8 (= 6e-7): \
             a run may take at most 1e8 engine steps, and stop.max_time_s = 60 s at this step \
             is more than 1e308",
        ],
    ),
    (
        &["solver.max_dt_s=1e-7", "stop.max_time_s=1e4"],
        &["error: solver.max_dt_s = 1e-7: must be >= stop.max_time_s / 1e8 (= 0.0001): "],
    ),
    (
        &["solver.bang_step_rad=1e-300"],
        &["error: solver.bang_step_rad = 1e-300: must be >= 0.0001: "],
    ),
    (
        &["solver.max_dt_s=1e-6", "output.sample_interval_s=0"],
        &[
            "error: output.sample_interval_s = 0: must be >= stop.max_time_s / 1e7 \
             (= 0.000006): a run may write at most 1e7 samples",
        ],
    ),
    (
        &["stop.max_time_s=1e300"],
        &["error: stop.max_time_s = 1e300: must be > 0 and <= 10000"],
    ),
    (
        &["solver.bang_engine=midpoint"],
        &[
            "error: solver.bang_engine = \"midpoint\": the midpoint (nodal) chain was retired: \
             use \"exact\" (the default); its results are kept in docs/history.md\n",
        ],
    ),
];

#[test]
fn hostile_overrides_exit_2_at_once() {
    let yoga = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/yoga-mat.toml");
    for (sets, expected) in HOSTILE_OVERRIDES {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let mut cmd = run_command(&yoga, &out);
        cmd.arg("--no-mcap");
        for set in *sets {
            cmd.args(["--set", set]);
        }
        let start = std::time::Instant::now();
        let output = cmd
            .timeout(std::time::Duration::from_secs(60))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{sets:?}: {stderr}");
        assert!(
            start.elapsed().as_secs_f64() < 10.0,
            "{sets:?} took {:?}",
            start.elapsed()
        );
        assert!(output.stdout.is_empty(), "{sets:?}");
        for want in *expected {
            assert!(
                stderr.contains(want),
                "{sets:?}: stderr lacks `{want}`: {stderr}"
            );
        }
        assert!(!out.exists(), "{sets:?}: output folder created");
    }
}

#[test]
fn missing_scene_file_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("does-not-exist.toml");
    let out = dir.path().join("out");
    run_command(&scene, &out)
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(predicate::str::starts_with(
            "error: cannot read scene file ",
        ))
        .stderr(predicate::str::contains(scene.display().to_string()));
    assert!(!out.exists(), "output folder {} was created", out.display());
}

#[test]
fn an_output_folder_inside_a_file_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("case.toml");
    std::fs::write(&scene, BASE).unwrap();
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "a regular file, not a folder").unwrap();
    let out = blocker.join("sub");
    run_command(&scene, &out)
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(format!(
            "error: {}: {} is a file; expected an output folder (made if missing)\n",
            out.display(),
            blocker.display()
        ));
    assert!(blocker.is_file(), "the blocking file was replaced");
}

#[test]
fn help_exits_0_and_lists_run() {
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("--help")
        .assert()
        .success()
        .stdout(predicate::str::contains("run"))
        .stdout(predicate::str::contains("Usage: uncoil"));
}

#[test]
fn unreadable_scene_files_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // (file name, contents or None for a folder, stderr must contain)
    type Case<'a> = (&'a str, Option<&'a [u8]>, &'a [&'a str]);
    let cases: [Case; 3] = [
        (
            "folder.toml",
            None,
            &["error: cannot read scene file ", "folder.toml"],
        ),
        (
            "latin1.toml",
            Some(b"name = \"caf\xe9\"\n"),
            &[
                "error: cannot read scene file ",
                "stream did not contain valid UTF-8",
            ],
        ),
        (
            "empty.toml",
            Some(b""),
            &[
                "error: cannot parse scene ",
                "empty.toml: ",
                "missing field `tape`",
            ],
        ),
    ];
    for (name, contents, expected) in cases {
        let path = dir.path().join(name);
        match contents {
            Some(bytes) => std::fs::write(&path, bytes).unwrap(),
            None => std::fs::create_dir_all(&path).unwrap(),
        }
        let (code, stdout, stderr) = run(&path, &out);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(stdout.is_empty(), "{name}: {stdout}");
        for want in expected {
            assert!(
                stderr.contains(want),
                "{name}: stderr lacks `{want}`: {stderr}"
            );
        }
        assert!(!out.exists(), "{name}: output folder created");
    }
}

#[test]
fn output_folder_that_is_a_file_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("case.toml");
    std::fs::write(&scene, BASE).unwrap();
    let out = dir.path().join("out");
    std::fs::write(&out, "a regular file").unwrap();
    run_command(&scene, &out)
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(format!(
            "error: {}: a file; expected an output folder (made if missing)\n",
            out.display()
        ));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "a regular file");
}

#[test]
fn unwritable_output_file_exits_1_without_a_complete_looking_file() {
    // The CSV's temporary name is taken by a folder: the run cannot write it. (Permission
    // bits would not stop root, who runs CI here; this does.)
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("case.toml");
    std::fs::write(&scene, BASE).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("samples.csv.partial")).unwrap();
    run_command(&scene, &out)
        .assert()
        .code(1)
        .stdout(predicate::str::is_empty())
        // The run takes the folder first and clears what an earlier run left: the folder
        // in the way is named with what could not be done to it.
        .stderr(predicate::str::contains(format!(
            "error: cannot remove the earlier {}: Is a directory",
            out.join("samples.csv.partial").display()
        )));
    assert!(!out.join("samples.csv").exists());
    assert!(!out.join("report.json").exists());
}
