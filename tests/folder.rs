//! A run owns its output folder: a second run into a folder another run holds is refused
//! (exit 2, naming the folder and the holder), a run leaves no earlier run's file beside its
//! own, and `uncoil check DIR` tells a folder whose files belong to one run from one whose
//! files do not.

use std::path::Path;

use assert_cmd::Command;
use predicates::prelude::*;
use uncoil::output::folder::{RunFolder, run_id};

fn yoga() -> &'static str {
    concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/yoga-mat.toml")
}

fn run_into(dir: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("uncoil")
        .unwrap()
        .args([
            "run",
            yoga(),
            "--set",
            "discretisation.links_per_turn=12",
            "--out",
        ])
        .arg(dir)
        .args(extra)
        .assert()
}

#[test]
fn a_folder_another_run_holds_is_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("run");
    let holder = RunFolder::take(&dir, &run_id("other", "text"), "other").unwrap();
    run_into(&dir, &[])
        .code(2)
        .stdout("")
        .stderr(predicate::str::contains(format!(
            "{} is being written by another run (run {} of scene other, process {})",
            dir.display(),
            holder.run_id(),
            std::process::id()
        )));
    assert!(!dir.join("samples.csv").exists() && !dir.join("report.json").exists());
    drop(holder);
    run_into(&dir, &[]).success();
}

#[test]
fn a_run_leaves_no_earlier_runs_file_and_check_reads_the_folder_as_one_run() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("run");
    run_into(&dir, &[]).success();
    assert!(dir.join("run.mcap").exists());
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("plot")
        .arg(&dir)
        .assert()
        .success();
    let first = std::fs::read(dir.join("samples.csv")).unwrap();
    // A second run into the folder, without a log: the first run's log and pictures go.
    run_into(&dir, &["--no-mcap", "--set", "push.contact_speed_m_s=0.4"]).success();
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, [".uncoil.lock", "report.json", "samples.csv"]);
    let check = || {
        Command::cargo_bin("uncoil")
            .unwrap()
            .arg("check")
            .arg(&dir)
            .assert()
    };
    check()
        .success()
        .stdout(predicate::str::contains("belong to one run"));
    // The first run's samples beside the second run's report.
    std::fs::write(dir.join("samples.csv"), first).unwrap();
    check().code(1).stdout(predicate::str::contains(
        "samples.csv is not the one report.json was written with",
    ));
}
