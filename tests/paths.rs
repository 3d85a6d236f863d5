//! Every subcommand given each kind of bad path, as a user would, from a folder outside the
//! repository: a path that is missing, a folder for a file, a file for a folder, a file of
//! the wrong kind. Each exits 2, writes nothing, and says the path and what was expected.

use std::path::Path;

use assert_cmd::Command;

/// A folder outside the repository with one thing of each kind in it.
struct Place {
    dir: tempfile::TempDir,
}

impl Place {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let at = dir.path();
        std::fs::create_dir(at.join("folder")).unwrap();
        std::fs::write(at.join("notes.txt"), "not a scene, a log or a sweep\n").unwrap();
        std::fs::write(at.join("table.csv"), "a,b\n1,2\n").unwrap();
        Self { dir }
    }

    /// `uncoil ARGS` run in this folder: (exit code, stderr).
    fn run(&self, args: &[&str]) -> (Option<i32>, String) {
        let out = Command::cargo_bin("uncoil")
            .unwrap()
            .current_dir(self.dir.path())
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }

    /// The names in this folder, sorted.
    fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

/// (arguments, the path the message must name, what it must say was expected)
type Case = (&'static [&'static str], &'static str, &'static str);

const CASES: &[Case] = &[
    // A scene: missing, a folder, a file that is not a scene.
    (
        &["run", "no-such-scene"],
        "no-such-scene",
        "a shipped scene can be named",
    ),
    (&["run", "folder"], "folder", "cannot read scene file"),
    (&["run", "notes.txt"], "notes.txt: ", "cannot parse scene"),
    (
        &["compare", "no-such-scene"],
        "no-such-scene",
        "a shipped scene can be named",
    ),
    (&["compare", "folder"], "folder", "cannot read scene file"),
    (
        &["compare", "table.csv"],
        "table.csv: ",
        "cannot parse scene",
    ),
    (
        &["compare", "folded-chain"],
        "folded-chain",
        "expected a coil's scene",
    ),
    (
        &["sweep", "no-such-scene"],
        "no-such-scene",
        "a shipped scene can be named",
    ),
    (&["sweep", "folder"], "folder", "cannot read scene file"),
    (&["sweep", "notes.txt"], "notes.txt: ", "cannot parse scene"),
    (
        &["sweep", "folded-chain"],
        "folded-chain",
        "expected a coil's scene",
    ),
    (&["check", "notes.txt"], "notes.txt: ", "cannot parse scene"),
    // A value that is not of its key's kind, or a name that is a path.
    (
        &["run", "yoga-mat", "--set", "discretisation=12"],
        "discretisation=12",
        "expected a section",
    ),
    (
        &["run", "yoga-mat", "--set", "name=../esc"],
        "../esc",
        "must be a plain name, not a path",
    ),
    (
        &["sweep", "yoga-mat", "--vary", "tape.mass_kg=1,1.0"],
        "tape.mass_kg",
        "given twice",
    ),
    (
        &["sweep", "yoga-mat", "--jobs", "0"],
        "`0`",
        "a whole number >= 1",
    ),
    (
        &["run", "yoga-mat", "--live", "nowhere"],
        "nowhere",
        "IP:PORT or HOST:PORT",
    ),
    (
        &["sweep", "yoga-mat", "--allow-partial"],
        "--allow-partial",
        "goes with --merge",
    ),
    // An output folder that is a file, or inside one.
    (
        &["run", "yoga-mat", "--out", "notes.txt"],
        "notes.txt",
        "expected an output folder",
    ),
    (
        &["run", "yoga-mat", "--out", "notes.txt/x"],
        "notes.txt is a file",
        "expected an output folder",
    ),
    (
        &["run", "folded-chain", "--out", "notes.txt"],
        "notes.txt",
        "expected an output folder",
    ),
    (
        &["sweep", "yoga-mat", "--out", "notes.txt"],
        "notes.txt",
        "expected an output folder",
    ),
    (
        &["check", "folder", "--out", "notes.txt"],
        "notes.txt",
        "expected an output folder",
    ),
    (
        &["sweep-report", "table.csv", "--out", "notes.txt"],
        "table.csv",
        "expected a sweep's folder",
    ),
    // A log: missing, a folder, a file that is not MCAP.
    (
        &["inspect", "missing.mcap"],
        "missing.mcap",
        "no such file or folder; expected an MCAP log",
    ),
    (
        &["inspect", "folder"],
        "folder",
        "a folder; expected an MCAP log",
    ),
    (&["inspect", "notes.txt"], "notes.txt", "not MCAP"),
    // A run's folder: missing, a file, a folder with no run.
    (
        &["plot", "missing"],
        "missing",
        "no such file or folder; expected a coil's run's output folder",
    ),
    (
        &["plot", "notes.txt"],
        "notes.txt",
        "a file; expected a coil's run's output folder",
    ),
    (
        &["plot", "folder"],
        "folder",
        "a folder with no report.json",
    ),
    // A sweep: missing, a folder with no sweep, a file that is not one.
    (
        &["sweep-report", "missing"],
        "missing",
        "no such file or folder; expected a sweep's folder",
    ),
    (
        &["sweep-report", "folder"],
        "folder",
        "a folder with no sweep.csv",
    ),
    (&["sweep-report", "table.csv"], "table.csv", "not a sweep's"),
    (
        &["sweep", "--merge", "missing.csv"],
        "missing.csv",
        "expected a sweep's shard file",
    ),
    (
        &["sweep", "--merge", "folder"],
        "folder",
        "a folder; expected a sweep's shard file",
    ),
    (
        &["sweep", "--merge", "table.csv"],
        "table.csv",
        "not a sweep's",
    ),
    // A folder to check or salvage: missing, a file, a folder of neither.
    (
        &["check", "missing"],
        "missing",
        "no such file or folder; expected a folder of scene files",
    ),
    (
        &["check", "folder"],
        "folder",
        "a folder with no scene files",
    ),
    (
        &["check", "missing", "--salvage"],
        "missing",
        "expected a killed run's output folder",
    ),
    (
        &["check", "notes.txt", "--salvage"],
        "notes.txt",
        "a file; expected a killed run's",
    ),
    (
        &["check", "folder", "--salvage"],
        "folder",
        "not a killed run's folder",
    ),
];

#[test]
fn every_command_refuses_a_bad_path_with_exit_2_naming_it_and_what_it_expected() {
    let place = Place::new();
    let before = place.names();
    let mut failures = Vec::new();
    for (args, path, expected) in CASES {
        let (code, stderr) = place.run(args);
        if code != Some(2) || !stderr.contains(path) || !stderr.contains(expected) {
            failures.push(format!(
                "uncoil {}: exit {code:?}, stderr: {stderr}",
                args.join(" ")
            ));
        }
        assert_eq!(place.names(), before, "uncoil {} wrote", args.join(" "));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_value_given_as_a_separate_word_gets_the_key_value_hint() {
    let place = Place::new();
    for flag in ["--set", "--vary"] {
        let command = if flag == "--set" { "run" } else { "sweep" };
        let (code, stderr) = place.run(&[command, "yoga-mat", flag, "tape.thickness_m", "0.004"]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!(
                "{flag} takes KEY=VALUE as one word: {flag} tape.thickness_m=0.004"
            )),
            "{stderr}"
        );
    }
    let (code, stderr) = place.run(&["run", "yoga-mat", "--set", "floor.friction", "-1"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("--set floor.friction=-1"), "{stderr}");
    let (code, stderr) = place.run(&[
        "run",
        "yoga-mat",
        "--set",
        "discretisation.links_per_turn=1.5",
    ]);
    assert_eq!(code, Some(2));
    assert!(
        stderr.contains("discretisation.links_per_turn=1.5: invalid type: the number `1.5`, expected a whole number"),
        "{stderr}"
    );
}

/// Every command that takes a scene takes a shipped name outside the repository, of every
/// kind it can run; the hard cases travel too.
#[test]
fn shipped_names_work_in_every_command_outside_the_repository() {
    let place = Place::new();
    let at = place.dir.path();
    let ok = |args: &[&str]| {
        let (code, stderr) = place.run(args);
        assert_eq!(code, Some(0), "uncoil {}: {stderr}", args.join(" "));
    };
    // A folder of a shipped scene's name does not hide the scene.
    std::fs::create_dir(at.join("folded-chain")).unwrap();
    ok(&[
        "run",
        "folded-chain",
        "--set",
        "chain.links=20",
        "--out",
        "chain",
    ]);
    ok(&[
        "sweep",
        "yoga-mat",
        "--vary",
        "discretisation.links_per_turn=12,16",
        "--out",
        "sweep",
        "--quiet",
    ]);
    ok(&["sweep-report", "sweep", "--no-convergence"]);
    assert!(at.join("sweep/report.md").is_file());
    // One hard case by its shipped name, checked: its outputs under runs/check.
    ok(&["check", "hard/coarsest-links"]);
    assert!(at.join("runs/check/coarsest-links/report.json").is_file());
    let listed = Command::cargo_bin("uncoil")
        .unwrap()
        .current_dir(at)
        .arg("scenes")
        .output()
        .unwrap();
    let listed = String::from_utf8_lossy(&listed.stdout);
    assert!(
        listed
            .lines()
            .any(|l| l.split_whitespace().eq(["folded-chain", "folded-chain"]))
    );
    assert_eq!(
        listed.lines().filter(|l| l.starts_with("hard/")).count(),
        13
    );
    // A run's hint names the Foxglove layout beside its log, a file that exists here.
    let out = Command::cargo_bin("uncoil")
        .unwrap()
        .current_dir(at)
        .args([
            "run",
            "yoga-mat",
            "--set",
            "discretisation.links_per_turn=12",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let layout = Path::new("runs/yoga-mat/foxglove-layout.json");
    assert!(
        stdout.contains(&format!("with the layout {}", layout.display())),
        "{stdout}"
    );
    assert!(at.join(layout).is_file());
    // A run's folder is checked where it is: an --out is refused, not ignored.
    let (code, stderr) = place.run(&["check", "runs/yoga-mat", "--out", "elsewhere"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("checked where they are"), "{stderr}");
    assert!(!at.join("elsewhere").exists());
}

/// A live server that cannot start (its port taken) leaves no lock or layout behind: the
/// folder is not read afterwards as a run's that was killed.
#[cfg(feature = "live")]
#[test]
fn a_live_server_that_cannot_start_leaves_no_run_behind() {
    let place = Place::new();
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let (code, stderr) = place.run(&["run", "yoga-mat", "--live", &addr, "--out", "live"]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("cannot serve the live view on {addr}")),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(place.dir.path().join("live"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}
