//! What a study of the bang across tapes needs of `uncoil sweep` and `sweep-report`: keys
//! varied together, a range of pushes, a core varied (whose milestones differ), the pushes
//! pooled as each setting's ensemble by default, on the yoga mat at 8 links a turn.

use std::path::Path;

use assert_cmd::Command;

use uncoil::study::sweep::SweepTable;

fn uncoil() -> Command {
    Command::cargo_bin("uncoil").unwrap()
}

/// 8 cheap runs: two frictions, a solid and a cored mat (its release radius varied with
/// its core), two pushes.
fn study(out: &Path) {
    uncoil()
        .args(["sweep", "yoga-mat", "--jobs", "1", "--quiet"])
        .args(["--vary", "discretisation.links_per_turn=8"])
        .args(["--vary", "floor.friction=0.3,1.0"])
        .args([
            "--vary",
            "tape.core_radius_m:stop.bang_radius_m=0:0.005,0.02:0.03",
        ])
        .args(["--vary", "push.contact_speed_m_s=0.3..0.301/2"])
        .arg("--out")
        .arg(out)
        .assert()
        .success();
}

fn report(out: &Path, extra: &[&str]) -> String {
    let a = uncoil()
        .arg("sweep-report")
        .arg(out)
        .args(extra)
        .assert()
        .success();
    String::from_utf8(a.get_output().stdout.clone()).unwrap()
}

#[test]
fn keys_varied_together_a_push_range_and_a_core_make_one_readable_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    study(&out);
    // Every row has a cell under every column, though a core changes the milestones.
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    assert_eq!(t.rows.len(), 8);
    assert!(t.rows.iter().all(|r| r.len() == t.header.len()));
    let cell = |r: usize, c: &str| t.rows[r][t.column(c).unwrap()].clone();
    let core = |r: usize| cell(r, "tape.core_radius_m").parse::<f64>().unwrap();
    for r in 0..8 {
        let (radius, fraction) = (cell(r, "err_geo_0.5R"), cell(r, "err_geo_f=0.5"));
        if core(r) > 0.0 {
            assert!(radius.is_empty() && !fraction.is_empty(), "row {r}");
            assert_eq!(cell(r, "stop.bang_radius_m"), "0.03");
        } else {
            assert!(!radius.is_empty() && fraction.is_empty(), "row {r}");
            assert_eq!(cell(r, "stop.bang_radius_m"), "0.005");
        }
    }
    let pushes: Vec<String> = (0..2).map(|r| cell(r, "push.contact_speed_m_s")).collect();
    assert_eq!(pushes, ["0.3", "0.301"]);

    // The pushes are each setting's ensemble; the release radius goes with the core.
    let text = report(&out, &[]);
    assert!(
        text.contains("Pooled as the repetitions of each setting: `push.contact_speed_m_s`"),
        "{text}"
    );
    assert!(text.contains("### `floor.friction` ("), "{text}");
    assert!(
        text.contains("### `tape.core_radius_m`, varied together with `stop.bang_radius_m` ("),
        "{text}"
    );
    assert!(!text.contains("### `stop.bang_radius_m`"), "{text}");
    assert!(!text.contains("### `push.contact_speed_m_s`"), "{text}");
    assert!(
        !text.contains("stop.bang_radius_m=0.03"),
        "grouped by a tied key: {text}"
    );
    let svg = std::fs::read_to_string(out.join("shares-floor.friction.svg")).unwrap();
    for panel in [
        "floor impacts share",
        "freezing share",
        "still moving / kinetic in",
    ] {
        assert!(svg.contains(panel), "{panel}");
    }
    let swatches = crate::support::check_legends(&svg);
    assert_eq!(swatches.len(), 2, "{swatches:?}");
    // The front ranks settings, each at its pushes' means: no push is a setting to choose.
    let front = &text[text.find("## Pareto front").unwrap()..text.find("## All runs").unwrap()];
    assert!(front.contains("`push.contact_speed_m_s` pooled"), "{front}");
    let head = front.lines().find(|l| l.starts_with("| ")).unwrap();
    assert_eq!(
        head,
        "| discretisation.links_per_turn | floor.friction | tape.core_radius_m | \
         stop.bang_radius_m | runs | cost s | error |"
    );
    let err = |r: usize| cell(r, "max_err_geo").parse::<f64>().unwrap();
    let cost = |r: usize| cell(r, "wall_rolling_s").parse::<f64>().unwrap();
    let rows: Vec<&str> = front
        .lines()
        .filter(|l| l.starts_with("| ") && l != &head && !l.starts_with("|---"))
        .collect();
    assert!(!rows.is_empty(), "{front}");
    for row in rows {
        let c: Vec<&str> = row.trim_matches('|').split(" | ").map(str::trim).collect();
        let mine: Vec<usize> = (0..8)
            .filter(|&r| cell(r, "floor.friction") == c[1] && cell(r, "tape.core_radius_m") == c[2])
            .collect();
        assert_eq!(c[4], mine.len().to_string(), "{row}");
        let mean = |f: &dyn Fn(usize) -> f64| mine.iter().map(|&r| f(r)).sum::<f64>() / 2.0;
        assert_eq!(c[5], format!("{:.4}", mean(&cost)), "{row}");
        assert_eq!(c[6], format!("{:.3}%", 100.0 * mean(&err)), "{row}");
    }

    // `none` pools nothing: the pushes are a key of their own.
    let text = report(&out, &["--repeat-key", "none"]);
    assert!(text.contains("### `push.contact_speed_m_s`"), "{text}");
    assert!(!text.contains("Pooled as"), "{text}");
    uncoil()
        .args(["sweep-report"])
        .arg(&out)
        .args(["--repeat-key", "none", "--repeat-key", "floor.friction"])
        .assert()
        .code(2);
}

#[test]
fn a_bad_range_or_a_setting_short_of_its_keys_exits_2_and_runs_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for (vary, says) in [
        ("push.contact_speed_m_s=0.3..0.31", "no /N"),
        ("push.contact_speed_m_s=0.3..0.31/1", "N must be 2 to"),
        ("push.contact_speed_m_s=0.3..0.3/4", "A and B must differ"),
        (
            "floor.friction:push.contact_speed_m_s=0.3:0.3,1.0",
            "1 values for 2 keys",
        ),
        (
            "floor.friction:push.contact_speed_m_s=0..1/3",
            "a range A..B/N takes one key",
        ),
        ("floor.friction:floor.friction=1:2", "named twice"),
    ] {
        let out = dir.path().join("bad");
        uncoil()
            .args(["sweep", "yoga-mat", "--vary", vary, "--out"])
            .arg(&out)
            .assert()
            .code(2)
            .stderr(predicates::str::contains(says));
        assert!(!out.exists(), "{vary}: ran");
    }
    // A key in two --vary, one of them with another key.
    uncoil()
        .args(["sweep", "yoga-mat"])
        .args([
            "--vary",
            "floor.friction:push.contact_speed_m_s=0.3:0.3,1.0:0.3",
        ])
        .args(["--vary", "floor.friction=0.5"])
        .arg("--out")
        .arg(dir.path().join("twice"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("varied twice"));
}

/// The pushes alone, the other keys fixed: one setting's ensemble, pooled into its mean and
/// standard error, with no Pareto front of the pushes; `--repeat-key none` keeps each run
/// its own row, the pushes a key.
#[test]
fn a_sweep_of_the_pushes_alone_is_one_ensemble() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pushes");
    uncoil()
        .args(["sweep", "yoga-mat", "--jobs", "1", "--quiet"])
        .args(["--vary", "discretisation.links_per_turn=8"])
        .args(["--vary", "push.contact_speed_m_s=0.3..0.303/4"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let text = report(&out, &[]);
    assert!(
        text.contains("### The ensemble: `push.contact_speed_m_s` pooled"),
        "{text}"
    );
    assert!(text.contains("None: every run is a repetition"), "{text}");
    assert!(!out.join("pareto.svg").exists());
    // The floor's impacts as the mean and standard error of sweep.csv's four runs.
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    let c = t.column("bang_floor_normal_of").unwrap();
    let x: Vec<f64> = t.rows.iter().map(|r| r[c].parse().unwrap()).collect();
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let se = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    let row = text
        .lines()
        .find(|l| l.starts_with("| 4 | "))
        .unwrap_or_else(|| panic!("a row of the 4 runs pooled: {text}"));
    let cell = row.split(" | ").nth(2).unwrap();
    assert_eq!(cell, format!("{mean:.3e} ± {se:.1e}"), "{row}");

    let text = report(&out, &["--repeat-key", "none"]);
    assert!(text.contains("### `push.contact_speed_m_s`"), "{text}");
    assert!(!text.contains("The ensemble"), "{text}");
    assert!(!text.contains("None: every run is a repetition"), "{text}");
    assert!(out.join("pareto.svg").exists());
}

/// `uncoil run SCENE --ensemble N`: N pushes from the scene's own, its overrides kept, one
/// folder with each run's files, the milestones printed as the mean and spread and the
/// bang's shares as the mean and standard error of its sweep.csv, both in ensemble.csv.
#[test]
fn an_ensemble_is_one_command_and_prints_its_mean_and_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ensemble");
    let a = uncoil()
        .args(["run", "yoga-mat", "--ensemble", "3"])
        .args(["--set", "discretisation.links_per_turn=8"])
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let printed = String::from_utf8(a.get_output().stdout.clone()).unwrap();
    let t = SweepTable::read(&out.join("sweep.csv")).unwrap();
    let cell = |r: usize, c: &str| t.rows[r][t.column(c).unwrap()].clone();
    let pushes: Vec<String> = (0..3).map(|r| cell(r, "push.contact_speed_m_s")).collect();
    assert_eq!(pushes, ["0.3", "0.301", "0.302"]);
    assert!((0..3).all(|r| cell(r, "discretisation.links_per_turn") == "8"));
    let x: Vec<f64> = (0..3)
        .map(|r| cell(r, "bang_floor_normal_of").parse().unwrap())
        .collect();
    let mean = x.iter().sum::<f64>() / 3.0;
    let se = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 2.0 / 3.0).sqrt();
    let want = format!(
        "floor impacts share          {:.1} ± {:.1} %",
        100.0 * mean,
        100.0 * se
    );
    assert!(printed.contains(&want), "{want}\n{printed}");
    assert!(
        printed.contains("The final bang over 3 landings"),
        "{printed}"
    );
    assert!(out.join("report.md").exists());
    // ensemble.csv holds what it printed, and each run's own files are kept.
    let pooled = SweepTable::read(&out.join("ensemble.csv")).unwrap();
    let row = |q: &str| {
        pooled
            .rows
            .iter()
            .find(|r| r[0] == q)
            .unwrap_or_else(|| panic!("`{q}` in ensemble.csv"))
            .clone()
    };
    let floor = row("floor impacts share");
    let (m, s): (f64, f64) = (floor[3].parse().unwrap(), floor[5].parse().unwrap());
    assert!(
        (m - mean).abs() <= 1e-9 * mean && (s - se).abs() <= 1e-6 * se,
        "{floor:?}"
    );
    assert_eq!(floor[2], "3");
    // The milestones as mean ± spread (the sample standard deviation), in the runs' order.
    let t: Vec<f64> = (0..3)
        .map(|r| cell(r, "t_sim_0.5R").parse().unwrap())
        .collect();
    let tm = t.iter().sum::<f64>() / 3.0;
    let sd = (t.iter().map(|v| (v - tm).powi(2)).sum::<f64>() / 2.0).sqrt();
    let half = row("t 0.5R");
    assert!(
        (half[3].parse::<f64>().unwrap() - tm).abs() < 1e-9,
        "{half:?}"
    );
    assert!(
        (half[4].parse::<f64>().unwrap() - sd).abs() < 1e-9,
        "{half:?}"
    );
    let want = format!("  0.5R       {tm:>9.4} ± {sd:.4} s");
    assert!(printed.contains(&want), "{want}\n{printed}");
    let first = printed.find("  0.75R").unwrap();
    assert!(first < printed.find("  2b").unwrap() && printed.find("  2b") < printed.find("  0.1R"));
    for k in 0..3 {
        let run = out.join(format!("run-{k}"));
        for f in ["report.json", "samples.csv", "run.mcap"] {
            assert!(run.join(f).exists(), "{}", run.join(f).display());
        }
    }
    uncoil()
        .args(["run", "yoga-mat", "--ensemble", "1"])
        .arg("--out")
        .arg(dir.path().join("one"))
        .assert()
        .code(2);
    // A folder of another ensemble, or of one run, is refused before anything runs.
    uncoil()
        .args(["run", "yoga-mat", "--ensemble", "2"])
        .args(["--set", "discretisation.links_per_turn=8"])
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("another sweep's files"));
    std::fs::write(dir.path().join("report.json"), "{}").unwrap();
    uncoil()
        .args(["run", "yoga-mat", "--ensemble", "2"])
        .arg("--out")
        .arg(dir.path())
        .assert()
        .code(2)
        .stderr(predicates::str::contains("a run's files (report.json)"));
    assert!(!dir.path().join("sweep.csv").exists());
}

/// The main job's hint names the ensemble of the run it ends, its overrides kept.
#[test]
fn the_main_job_s_hint_names_its_own_ensemble() {
    let dir = tempfile::tempdir().unwrap();
    let a = uncoil()
        .args(["run", "yoga-mat", "--no-mcap"])
        .args(["--set", "discretisation.links_per_turn=8"])
        .arg("--out")
        .arg(dir.path().join("run"))
        .assert()
        .success();
    let printed = String::from_utf8(a.get_output().stdout.clone()).unwrap();
    assert!(
        printed
            .contains("`uncoil run yoga-mat --ensemble 8 --set discretisation.links_per_turn=8`"),
        "{printed}"
    );
}
