//! `uncoil sweep`, `sweep --merge`, `sweep-report`, `plot` and `run --set` end to end, on
//! the yoga mat at coarse resolutions (a run takes well under a second).

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use predicates::prelude::*;

use uncoil::study::analysis::{Reference, SweepAnalysis};
use uncoil::study::sweep::{RowStatus, SweepTable};

fn yoga() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/yoga-mat.toml")
}

fn uncoil() -> Command {
    Command::cargo_bin("uncoil").unwrap()
}

/// Two cheap runs: 8 and 16 links per turn, no time given to the final bang.
const VARY: [&str; 4] = [
    "--vary",
    "discretisation.links_per_turn=8,16",
    "--vary",
    "stop.bang_cap_s=0",
];

fn sweep(out: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(VARY)
        .arg("--out")
        .arg(out)
        .args(["--jobs", "1"])
        .args(extra)
        .assert()
}

fn cell(t: &SweepTable, row: usize, col: &str) -> String {
    t.rows[row][t.column(col).unwrap_or_else(|| panic!("no column {col}"))].clone()
}

fn number(t: &SweepTable, row: usize, col: &str) -> f64 {
    cell(t, row, col)
        .parse()
        .unwrap_or_else(|_| panic!("{col} of row {row} is not a number"))
}

/// The columns that must agree between two runs of the same combination (all but the
/// wall times and the worker count).
fn deterministic(t: &SweepTable) -> Vec<Vec<String>> {
    let skip = ["wall_s", "wall_rolling_s", "jobs"];
    t.rows
        .iter()
        .map(|r| {
            r.iter()
                .zip(&t.header)
                .filter(|(_, h)| !skip.contains(&h.as_str()))
                .map(|(c, _)| c.clone())
                .collect()
        })
        .collect()
}

#[test]
fn sweep_shards_merge_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    sweep(&full, &["--quiet"])
        .success()
        .stdout(predicate::str::contains(
            "2 runs (0 failed, 0 stopped by a guard) of 2 combinations",
        ));
    let t = SweepTable::read(&full.join("sweep.csv")).unwrap();
    assert_eq!(
        t.varied_keys(),
        ["discretisation.links_per_turn", "stop.bang_cap_s"]
    );
    assert_eq!(t.rows.len(), 2, "one row per run");
    let mut by_index = t.clone();
    by_index
        .rows
        .sort_by_key(|r| r[0].parse::<usize>().unwrap());
    let t = by_index;
    assert_eq!(cell(&t, 0, "discretisation.links_per_turn"), "8");
    assert_eq!(cell(&t, 1, "discretisation.links_per_turn"), "16");
    for r in 0..2 {
        assert_eq!(cell(&t, r, "status"), "ok");
        assert_eq!(cell(&t, r, "jobs"), "1");
        assert!(number(&t, r, "wall_rolling_s") <= number(&t, r, "wall_s"));
        assert!(number(&t, r, "steps") > 100.0);
    }
    // 11 turns of the yoga mat: 88 and 176 links.
    assert_eq!(cell(&t, 0, "links"), "88");
    assert_eq!(cell(&t, 1, "links"), "176");
    // Physics: doubling the resolution brings the run closer to the exact-geometry model
    // (README: about 2.6% at 8 links per turn, 0.6% at 16) and loses less energy.
    let (e8, e16) = (number(&t, 0, "max_err_geo"), number(&t, 1, "max_err_geo"));
    assert!(
        e16 < 0.5 * e8 && e16 < 0.02,
        "max |error| vs exact: {e8:.4} at 8, {e16:.4} at 16 links per turn; expected a halving at least"
    );
    let (l8, l16) = (
        number(&t, 0, "lost_before_bang_of_e0"),
        number(&t, 1, "lost_before_bang_of_e0"),
    );
    assert!(
        l16 < l8,
        "energy lost before the bang: {l8:.4} at 8, {l16:.4} at 16"
    );
    // Eq. (7) is ~7% slow for this thick mat at any resolution.
    let e7 = number(&t, 1, "max_err_eq7");
    assert!(
        (0.03..0.12).contains(&e7),
        "max |error| vs eq. 7 {e7:.4}, expected ~0.07"
    );

    // Two shards into one folder, then merged: the same rows as the full sweep.
    let shards = dir.path().join("shards");
    sweep(&shards, &["--quiet", "--shard", "1/2"])
        .success()
        .stdout(predicate::str::contains(
            "1 run (0 failed, 0 stopped by a guard) of 2 combinations",
        ));
    sweep(&shards, &["--quiet", "--shard", "2/2"]).success();
    let s1 = shards.join("sweep.1-of-2.csv");
    let s2 = shards.join("sweep.2-of-2.csv");
    assert_eq!(SweepTable::read(&s1).unwrap().rows[0][0], "0");
    assert_eq!(SweepTable::read(&s2).unwrap().rows[0][0], "1");
    uncoil()
        .args(["sweep", "--merge"])
        .arg(&s2)
        .arg(&s1)
        .assert()
        .success()
        .stdout(predicate::str::contains("merged 2 runs into"));
    let merged = SweepTable::read(&shards.join("sweep.csv")).unwrap();
    assert_eq!(merged.header, t.header);
    // Each file states its grid beside it; the merge states the whole grid, as the full
    // sweep's does.
    let grid = |p: &Path| uncoil::study::sweep::read_grid(&p.join("sweep.grid.json")).unwrap();
    assert_eq!(grid(&shards), grid(&full));
    assert_eq!(grid(&full).combinations, 2);
    let shard_grid = uncoil::study::sweep::read_grid(&shards.join("sweep.2-of-2.grid.json"));
    assert_eq!(shard_grid.unwrap().shard, Some([2, 2]));
    assert_eq!(
        deterministic(&merged),
        deterministic(&t),
        "shards + merge differ from the full sweep"
    );
    // A sweep killed while writing its last row, then resumed: that run goes again, the
    // other is kept, and the table is the uninterrupted one's.
    let resumed = dir.path().join("resumed");
    std::fs::create_dir_all(&resumed).unwrap();
    let text = std::fs::read_to_string(full.join("sweep.csv")).unwrap();
    let cut = &text.trim_end()[..text.trim_end().len() - 5];
    std::fs::write(resumed.join("sweep.csv"), cut).unwrap();
    sweep(&resumed, &["--quiet", "--resume"])
        .success()
        .stdout(predicate::str::contains(
            "1 run (0 failed, 0 stopped by a guard, 1 kept from before) of 2 combinations",
        ));
    let again = SweepTable::read(&resumed.join("sweep.csv")).unwrap();
    assert_eq!(
        deterministic(&again),
        deterministic(&t),
        "a resumed sweep differs from the uninterrupted one"
    );
    // --resume of another grid into the folder is refused and changes nothing.
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(["--vary", "discretisation.links_per_turn=8,12"])
        .args([
            "--vary",
            "stop.bang_cap_s=0",
            "--resume",
            "--quiet",
            "--out",
        ])
        .arg(&resumed)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "is of another grid (--vary discretisation.links_per_turn=8,16",
        ));
    let after = SweepTable::read(&resumed.join("sweep.csv")).unwrap();
    assert_eq!(after, again, "a refused resume changed the file");
    // A shard not given: refused, naming it, nothing written; written with --allow-partial,
    // which says what is missing.
    let partial = dir.path().join("partial");
    uncoil()
        .args(["sweep", "--merge"])
        .arg(&s1)
        .arg("--out")
        .arg(&partial)
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "missing, of the 2 shards: shard 2 (sweep.2-of-2.csv)",
        ));
    assert!(!partial.join("sweep.csv").exists());
    uncoil()
        .args(["sweep", "--merge"])
        .arg(&s1)
        .args(["--allow-partial", "--out"])
        .arg(&partial)
        .assert()
        .success()
        .stdout(predicate::str::contains("merged 1 run into"))
        .stdout(predicate::str::contains(
            "missing, of the 2 shards: shard 2",
        ));
    let note = std::fs::read_to_string(partial.join("sweep.missing.txt")).unwrap();
    assert!(note.contains("missing, of the 2 shards: shard 2"), "{note}");
    // A combination found twice is refused: not shards of one sweep, bad input.
    uncoil()
        .args(["sweep", "--merge"])
        .arg(&s1)
        .arg(&s1)
        .arg("--out")
        .arg(dir.path().join("twice"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("combination 0 is in both"));

    // The report: Markdown on stdout and in report.md, and the SVGs.
    uncoil()
        .arg("sweep-report")
        .arg(full.join("sweep.csv"))
        .args(["--title", "tiny"])
        .assert()
        .success()
        .stdout(predicate::str::starts_with("# tiny\n"))
        .stdout(predicate::str::contains(
            "| `discretisation.links_per_turn` |",
        ));
    for f in [
        "report.md",
        "pareto.svg",
        "convergence-discretisation.links_per_turn.svg",
    ] {
        let text = std::fs::read_to_string(full.join(f)).unwrap();
        assert!(!text.is_empty(), "{f} is empty");
    }
    assert!(
        std::fs::read_to_string(full.join("pareto.svg"))
            .unwrap()
            .contains("<svg")
    );
    for f in [
        "pareto.svg",
        "convergence-discretisation.links_per_turn.svg",
    ] {
        let svg = std::fs::read_to_string(full.join(f)).unwrap();
        crate::support::check_legends(&svg);
    }
}

/// A run a guard stops is recorded as stopped, the sweep exits 3 as `uncoil run` does, and
/// the report leaves the run out of its fits and lists it.
#[test]
fn a_guard_stop_is_recorded_as_stopped_and_left_out_of_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("coarse");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hard/coarse-step.toml");
    uncoil()
        .arg("sweep")
        .arg(&scene)
        .args(["--vary", "solver.iterations=1", "--jobs", "1", "--quiet"])
        .arg("--out")
        .arg(&out)
        .assert()
        .code(3)
        .stdout(predicate::str::contains(
            "1 run (0 failed, 1 stopped by a guard) of 1 combination",
        ));
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    let status = cell(&t, 0, "status");
    assert!(
        status.starts_with("stopped: joints separating at t = 0.074017 s"),
        "{status}"
    );
    assert_eq!(
        status.parse::<RowStatus>().unwrap(),
        RowStatus::Stopped(status["stopped: ".len()..].to_owned())
    );
    let analysis = SweepAnalysis::new(t, Reference::Exact, "wall_s", &[]).unwrap();
    assert_eq!(analysis.fits, [false]);
    assert!(analysis.front.is_empty(), "{:?}", analysis.front);
    uncoil()
        .arg("sweep-report")
        .arg(out.join("sweep.csv"))
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "Left out of the fits, the front and the target",
        ))
        .stdout(predicate::str::contains(
            "- #0 solver.iterations=1: stopped: joints separating",
        ));
}

#[test]
fn sweep_with_a_bad_value_exits_2_and_runs_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(["--vary", "solver.max_dt_s=0.001,0.5"])
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(predicate::str::contains(
            "error: combination 1 (solver.max_dt_s=0.5): solver.max_dt_s = 0.5: must be > 0 and <= 0.1",
        ));
    assert!(!out.exists(), "output folder {} was created", out.display());
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(["--vary", "solver.max_dt=0.001"])
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("unknown field `max_dt`"));
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(["--shard", "3/2"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("expected K/N with 1 <= K <= N"));
}

#[test]
fn run_with_set_then_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    uncoil()
        .arg("run")
        .arg(yoga())
        .args(["--set", "discretisation.links_per_turn=12"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::contains("132 links (12 per turn)"));
    uncoil()
        .arg("plot")
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::contains("motion.svg"))
        .stdout(predicate::str::contains("energy.svg"))
        .stdout(predicate::str::contains("bang.svg"));
    // The bang's filmstrip: one panel per time, each captioned with its time and crossings.
    let bang = std::fs::read_to_string(out.join("bang.svg")).unwrap();
    let panels = bang.matches(" after the release, ").count();
    assert_eq!(
        panels,
        uncoil::study::plot::BANG_PANELS,
        "bang.svg's panels"
    );
    assert!(
        bang.contains("b = 5 mm"),
        "bang.svg states the tape's thickness"
    );
    let energy = std::fs::read_to_string(out.join("energy.svg")).unwrap();
    assert!(energy.starts_with("<svg"), "not an SVG");
    assert!(energy.contains("MgR"), "the energy plot names MgR");
    assert!(
        std::fs::read_to_string(out.join("motion.svg"))
            .unwrap()
            .contains("exact-geometry model")
    );
    // Every legend swatch is drawn as its line: the references dashed, the simulation not.
    for f in ["motion.svg", "energy.svg", "approach.svg", "forces.svg"] {
        let svg = std::fs::read_to_string(out.join(f)).unwrap();
        let swatches = crate::support::check_legends(&svg);
        assert!(
            swatches.iter().any(|s| s.2) && swatches.iter().any(|s| !s.2),
            "{f}: {swatches:?}"
        );
        for (label, _, dashed) in &swatches {
            let reference = label == "exact-geometry model"
                || label == "eq. (7)"
                || label.ends_with(" exact")
                || label.ends_with("exact (least pull)");
            if label.contains("simulation") || reference {
                assert_eq!(
                    *dashed, reference,
                    "{f}: {label}: simulation solid, references dashed"
                );
            }
        }
    }
    uncoil()
        .arg("run")
        .arg(yoga())
        .args(["--set", "discretisation.links_per_turn=5000"])
        .arg("--out")
        .arg(dir.path().join("bad"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "discretisation.links_per_turn = 5000: must be >= 3 and <= 4096",
        ));
}

#[test]
fn plot_without_a_log_skips_the_bang_s_filmstrip_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    uncoil()
        .arg("run")
        .arg(yoga())
        .args(["--set", "discretisation.links_per_turn=12", "--no-mcap"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    uncoil()
        .arg("plot")
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::contains("forces.svg"))
        .stdout(predicate::str::contains("bang.svg").not())
        .stderr(predicate::str::contains("skipped"))
        .stderr(predicate::str::contains("bang.svg"))
        .stderr(predicate::str::contains(
            "has no run.mcap (a run with --no-mcap)",
        ));
    assert!(out.join("forces.svg").exists() && !out.join("bang.svg").exists());
}

/// One run at a time, each one's references built while the run before it steps, gives the
/// table that runs side by side on a pool give.
#[test]
fn one_at_a_time_and_side_by_side_give_one_table() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    sweep(&one, &["--quiet"]).success();
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(VARY)
        .arg("--out")
        .arg(&two)
        .args(["--jobs", "2", "--quiet"])
        .assert()
        .success();
    // Rows are in the grid's order, whatever order the runs ended in.
    let read = |d: &Path| SweepTable::read(&d.join("sweep.csv")).unwrap();
    let (a, b) = (read(&one), read(&two));
    assert_eq!(a.rows.len(), 2);
    for t in [&a, &b] {
        let order: Vec<&str> = t.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(order, ["0", "1"]);
    }
    assert_eq!(deterministic(&a), deterministic(&b));
}

#[test]
fn a_key_varied_twice_exits_2_and_runs_nothing() {
    let dir = tempfile::tempdir().unwrap();
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args([
            "--vary",
            "solver.iterations=2,4",
            "--vary",
            "solver.iterations=8",
        ])
        .arg("--out")
        .arg(dir.path())
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "--vary solver.iterations: varied twice",
        ));
    assert!(!dir.path().join("sweep.csv").exists());
}

/// The yoga mat stepped at 1e-5 s for 2.5 s: about 4 s a run on a 2-core machine.
const SLOW_SCENE: &str = "name = \"slow\"\n[tape]\nouter_radius_m = 0.06\nthickness_m = 0.005\n\
                          mass_kg = 1.5\n[push]\ncontact_speed_m_s = 0.3\n[solver]\n\
                          max_dt_s = 0.00001\n[stop]\nmax_time_s = 2.5\n";

/// `uncoil ARGS`, sent SIGTERM half a second in (what Slurm sends at a time limit), run to
/// its end.
fn terminated(args: &[String]) -> std::process::Output {
    let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("uncoil"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait_with_output().unwrap()
}

#[test]
fn sigterm_stops_a_sweep_its_running_row_says_interrupted_and_resume_finishes_it() {
    // What Slurm sends a task at its time limit or on scancel. Two runs of about 4 s each
    // (on a 2-core machine), one at a time: the signal, half a second in, reaches the first
    // while it runs.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("slow.toml");
    std::fs::write(&scene, SLOW_SCENE).unwrap();
    let out = dir.path().join("out");
    let args = |resume: bool| {
        let mut a = vec![
            "sweep".to_owned(),
            scene.display().to_string(),
            "--vary".to_owned(),
            "push.contact_speed_m_s=0.3,0.31".to_owned(),
            "--jobs".to_owned(),
            "1".to_owned(),
            "--quiet".to_owned(),
            "--out".to_owned(),
            out.display().to_string(),
        ];
        if resume {
            a.push("--resume".to_owned());
        }
        a
    };
    let output = terminated(&args(false));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(143), "stderr: {stderr}");
    assert!(
        stderr.contains("interrupted by SIGTERM") && stderr.contains("--resume"),
        "stderr: {stderr}"
    );
    // No run finished: what rows there are say interrupted, and none is left partial; the
    // closing line counts them, not the runs planned.
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    assert!(t.rows.len() <= 1, "{:?}", t.rows);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = format!(
        "{} of 2 runs (0 failed, 0 stopped by a guard{}) of 2 combinations",
        t.rows.len(),
        if t.rows.is_empty() {
            ""
        } else {
            ", 1 interrupted"
        }
    );
    assert!(stdout.contains(&line), "stdout lacks `{line}`: {stdout}");
    for row in 0..t.rows.len() {
        assert_eq!(cell(&t, row, "status"), "interrupted");
    }
    // Resumed, every combination runs to its end (its bang at rest, or the time limit).
    uncoil()
        .args(args(true))
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "2 runs (0 failed, 0 stopped by a guard)",
        ));
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    assert_eq!(t.rows.len(), 2);
    for row in 0..2 {
        let status = cell(&t, row, "status");
        assert!(
            status == "ok" || status == "max_time",
            "row {row}: {status}"
        );
    }
}

/// A physical key (the floor's friction) is no resolution: the report fits nothing against
/// it, draws no convergence plot for it, and draws the bang's shares against its own values,
/// the pushes pooled as the ensemble.
#[test]
fn a_physical_key_is_drawn_on_its_own_axis_not_fitted_as_a_step() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("friction");
    uncoil()
        .arg("sweep")
        .arg(yoga())
        .args(["--vary", "discretisation.links_per_turn=8"])
        .args(["--vary", "floor.friction=0.3,1.0"])
        .args(["--vary", "push.contact_speed_m_s=0.3,0.301"])
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "1", "--quiet"])
        .assert()
        .success();
    let report = uncoil()
        .arg("sweep-report")
        .arg(&out)
        .args(["--repeat-key", "push.contact_speed_m_s"])
        .assert()
        .success();
    let text = String::from_utf8(report.get_output().stdout.clone()).unwrap();
    assert!(text.contains("### `floor.friction`"), "{text}");
    assert!(
        !text.contains("| `floor.friction` |"),
        "fitted as a step: {text}"
    );
    assert!(!text.contains("order of the change"), "{text}");
    assert!(!out.join("convergence-floor.friction.svg").exists());
    assert!(!out.join("bang-floor.friction.svg").exists());
    let svg = std::fs::read_to_string(out.join("shares-floor.friction.svg")).unwrap();
    assert!(svg.contains("floor friction share") && !svg.contains("h of"));
    crate::support::check_legends(&svg);
}

/// `run --ensemble` stops on SIGTERM as a sweep does (exit 143, no pooled figures from
/// runs cut short), and `--resume` finishes it: every run's folder complete, the pooled table
/// written.
#[test]
fn sigterm_stops_an_ensemble_and_resume_finishes_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("slow.toml");
    std::fs::write(&scene, SLOW_SCENE).unwrap();
    let out = dir.path().join("out");
    let args = |resume: bool| {
        let mut a = vec!["run".to_owned(), scene.display().to_string()];
        a.extend(["--ensemble", "2", "--no-mcap", "--out"].map(String::from));
        a.push(out.display().to_string());
        if resume {
            a.push("--resume".to_owned());
        }
        a
    };
    let output = terminated(&args(false));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(143), "stdout: {stdout}");
    assert!(!stdout.contains("The final bang over"), "{stdout}");
    assert!(!out.join("ensemble.csv").exists());
    uncoil()
        .args(args(true))
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "2 of 2 runs (pushes 0.300..0.301 m/s)",
        ));
    assert!(out.join("ensemble.csv").exists());
    for k in 0..2 {
        let run = out.join(format!("run-{k}"));
        assert!(run.join("report.json").exists() && run.join("samples.csv").exists());
        assert!(!run.join("samples.csv.partial").exists());
    }
}
