//! Hard cases: guards that stop a run with a stated reason and sound outputs, the limits of
//! the references on slippery and weightless floors, durable output when a run is killed,
//! determinism, and the `uncoil check` command. The long hard runs (thin tapes, the
//! 10 m/s push, the 10^4 rad/s bang) are left to `uncoil check`; these use the quick ones
//! or shorten them with `stop.max_time_s`.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use assert_cmd::Command;
use predicates::prelude::*;
use uncoil::run::limits::LimitKind;
use uncoil::run::stop::Status;
use uncoil::run::{RunReport, run};
use uncoil::scene::Scene;
use uncoil::study::check::verify_outputs;

fn hard_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/hard")
        .join(format!("{name}.toml"))
}

/// The text of `scenes/hard/<name>.toml` with `stop.max_time_s` set to `max_time_s`.
fn shortened(name: &str, max_time_s: f64) -> String {
    let text = std::fs::read_to_string(hard_path(name)).unwrap();
    let mut out = String::new();
    let mut in_stop = false;
    for line in text.lines() {
        if line.starts_with('[') {
            in_stop = line == "[stop]";
        }
        if in_stop && line.starts_with("max_time_s") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
        if in_stop && line == "[stop]" {
            out.push_str(&format!("max_time_s = {max_time_s}\n"));
        }
    }
    if !text.contains("[stop]") {
        out.push_str(&format!("[stop]\nmax_time_s = {max_time_s}\n"));
    }
    out
}

fn kinds(report: &RunReport) -> Vec<LimitKind> {
    report.reference_limits.iter().map(|l| l.kind).collect()
}

#[test]
fn a_torn_chain_is_stopped_by_a_guard_with_everything_logged() {
    // 0.1 s steps with one solver iteration: the chain tears in the second step (gap 10 mm)
    // and the joint guard (one thickness, 5 mm) stops the run.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("run")
        .arg(hard_path("coarse-step"))
        .arg("--out")
        .arg(&out)
        .assert()
        .code(3)
        .stdout(predicate::str::contains(
            "STOPPED by a guard: joints separating at t = ",
        ))
        .stderr(predicate::str::contains(
            "error: the run was stopped by a guard: joints separating at t = 0.074017 s",
        ));
    assert_eq!(verify_outputs(&out), Vec::<String>::new());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // The report names the guard with the value it measured and its bound.
    let stop = &report["stop"];
    assert_eq!(stop["reason"], "guard", "{stop}");
    assert_eq!(stop["guard"], "joint-gap", "{stop}");
    assert!(
        (stop["bound"].as_f64().unwrap() - 5.0e-3).abs() < 1e-12,
        "{stop}"
    );
    assert!(stop["value"].as_f64().unwrap() > 5.0e-3, "{stop}");
    assert!(
        (stop["t_s"].as_f64().unwrap() - 0.074017).abs() < 1e-6,
        "{stop}"
    );
    // The CSV ends at the step that tripped the guard, and holds the steps before it.
    let csv = std::fs::read_to_string(out.join("samples.csv")).unwrap();
    assert!(csv.lines().count() >= 3, "{csv}");
    let last_t: f64 = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let sim_time = report["sim_time_s"].as_f64().unwrap();
    // The CSV keeps 10 significant digits.
    assert!(
        (last_t / sim_time - 1.0).abs() < 1e-9,
        "last row t = {last_t}, run ended at {sim_time}"
    );
}

#[test]
fn a_frictionless_floor_slides_as_the_sliding_model_says() {
    // Nothing makes it roll: it spins faster than it travels and the laid tape slides back.
    // Its reference is the exact spiral sliding at zero momentum, so that is no departure:
    // no slip, bunching or skid is reported, and the contact line trails the laid length as
    // the centre of mass stays put (x ~ laid^2 / 2L); rolling would put it at the laid length.
    let scene = Scene::from_toml_str(&shortened("frictionless", 0.3), "frictionless").unwrap();
    let (samples, report) = crate::support::run_kept(&scene);
    assert_eq!(report.stop.status(), Status::Completed, "{}", report.stop);
    let k = kinds(&report);
    for kind in [LimitKind::Slip, LimitKind::Bunching, LimitKind::Skid] {
        assert!(!k.contains(&kind), "{:#?}", report.reference_limits);
    }
    let last = samples.last().unwrap();
    let laid = last.laid_fraction * uncoil::spiral::Spiral::wound(0.06, 0.005, 0.0).length();
    assert!(laid > 0.05, "laid {laid} m");
    assert!(
        last.x_m < 0.5 * laid,
        "x = {} m with {laid} m laid",
        last.x_m
    );
    assert!(
        (last.x_m - last.x_geo_m).abs() < 1e-3 * laid,
        "x = {} m, sliding model {} m",
        last.x_m,
        last.x_geo_m
    );
}

#[test]
fn zero_gravity_floats_on_the_floor_and_says_so() {
    // No weight: the exact model would need a floor that pulls from the start, and the
    // floor carries next to nothing (the mat would weigh 14.7 N under 1 g); the kinetic
    // energy is all the energy there is, and it stays.
    let scene = Scene::from_toml_str(&shortened("zero-gravity", 0.1), "zero-gravity").unwrap();
    let (samples, report) = crate::support::run_kept(&scene);
    let max_normal_n = samples.iter().map(|s| s.normal_n.abs()).fold(0.0, f64::max);
    assert_eq!(report.stop.status(), Status::Completed, "{}", report.stop);
    assert!(
        kinds(&report).contains(&LimitKind::ExactModelHops),
        "{:#?}",
        report.reference_limits
    );
    assert!(max_normal_n < 0.01, "floor force up to {} N", max_normal_n);
    let k0 = samples[0].kinetic_j;
    for k in samples.iter().map(|s| s.kinetic_j) {
        assert!(
            (k - k0).abs() < 1e-3 * k0,
            "kinetic energy {k} J from {k0} J"
        );
    }
    assert!(report.max_energy_rise_rel <= uncoil::run::guard::ENERGY_RISE_TOLERANCE);
}

#[test]
fn a_slippery_floor_run_writes_the_same_bytes_when_repeated() {
    let text = shortened("friction-0.05", 0.4);
    let scene = Scene::from_toml_str(&text, "friction-0.05").unwrap();
    let dirs = [tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap()];
    let mut csvs = Vec::new();
    let mut mcaps = Vec::new();
    let mut reports = Vec::new();
    for d in &dirs {
        let mut csv = uncoil::output::CsvObserver::new(d.path());
        let mut json = uncoil::output::ReportObserver::new(d.path());
        let mut log = uncoil::output::view::ViewObserver::new(d.path());
        run(&scene, &mut [&mut csv, &mut json, &mut log]).unwrap();
        csvs.push(std::fs::read(d.path().join("samples.csv")).unwrap());
        mcaps.push(std::fs::read(d.path().join("run.mcap")).unwrap());
        let mut v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.path().join("report.json")).unwrap()).unwrap();
        // Wall times are the only fields that may differ.
        let m = v.as_object_mut().unwrap();
        m.remove("wall_time_s");
        m.remove("wall_time_rolling_s");
        reports.push(v);
    }
    assert!(csvs[0].len() > 10_000, "{} bytes", csvs[0].len());
    assert!(csvs[0] == csvs[1], "two runs wrote different CSV bytes");
    assert!(mcaps[0].len() > 10_000, "{} bytes", mcaps[0].len());
    assert!(mcaps[0] == mcaps[1], "two runs wrote different MCAP bytes");
    assert_eq!(reports[0], reports[1], "two runs wrote different reports");
}

/// Starts `uncoil run SCENE --out OUT EXTRA...`, its output discarded.
fn spawn_run(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Child {
    std::process::Command::new(assert_cmd::cargo::cargo_bin("uncoil"))
        .arg("run")
        .arg(scene)
        .args(extra)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

/// Waits until the run `child` has written `bytes` of `out/samples.csv.partial`, and
/// fails if it ends first or writes nothing for two minutes.
fn wait_for_samples(child: &mut std::process::Child, out: &Path, bytes: u64) {
    let partial = out.join("samples.csv.partial");
    let start = Instant::now();
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) < bytes {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it could be stopped"
        );
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no rows written"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn a_killed_run_leaves_only_partial_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Finished files of an earlier run must not survive beside a killed one.
    std::fs::write(out.join("samples.csv"), "an earlier run\n").unwrap();
    std::fs::write(out.join("report.json"), "{}\n").unwrap();
    std::fs::write(out.join("run.mcap"), "an earlier log\n").unwrap();
    let mut child = spawn_run(&hard_path("thin-300"), &out, &[]);
    // Wait until a few rows are on disk (the thin tape runs for tens of seconds).
    wait_for_samples(&mut child, &out, 20_000);
    let partial = out.join("samples.csv.partial");
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("samples.csv").exists(), "samples.csv exists");
    assert!(!out.join("report.json").exists(), "report.json exists");
    assert!(!out.join("run.mcap").exists(), "run.mcap exists");
    let text = std::fs::read_to_string(&partial).unwrap();
    assert!(text.starts_with("t_s,laid_fraction,"), "{}", &text[..40]);
    assert!(text.lines().count() > 10);
    // `uncoil check` on the folder says what the killed run left, not "no scene files":
    // the partial files, the complete rows and their last time, the log, the stale lock.
    let complete = text.matches('\n').count() - 1;
    let assert = Command::cargo_bin("uncoil")
        .unwrap()
        .arg("check")
        .arg(&out)
        .assert()
        .code(1);
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout).into_owned();
    for said in [
        "an interrupted run: no report.json; partial files: samples.csv.partial",
        &format!("samples.csv.partial: {complete} complete rows, up to t = "),
        "run.mcap.partial: ",
        "stale: its process is gone",
    ] {
        assert!(stdout.contains(said), "{said:?} not in:\n{stdout}");
    }
}

#[test]
fn a_second_signal_ends_the_run_at_once_and_leaves_its_partial_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = spawn_run(&hard_path("thin-300"), &out, &[]);
    wait_for_samples(&mut child, &out, 20_000);
    let partial = out.join("samples.csv.partial");
    // Two different signals, sent back to back, are both delivered (two of the same may
    // merge into one): the first raises the stop flag, the second, finding it up, ends the
    // process before it finishes its files, as a user's second Ctrl-C means.
    let sent = std::process::Command::new("sh")
        .args(["-c", "kill -INT $0; kill -TERM $0"])
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(sent.success());
    let code = child.wait().unwrap().code();
    assert!(matches!(code, Some(130 | 143)), "exit {code:?}");
    assert!(partial.exists() && out.join("run.mcap.partial").exists());
    for name in ["samples.csv", "report.json", "run.mcap"] {
        assert!(!out.join(name).exists(), "{name} was finished");
    }
}

/// Each topic's messages of a finished `run.mcap`: (log time, bytes), in order.
fn messages_by_topic(path: &Path) -> std::collections::BTreeMap<String, Vec<(u64, Vec<u8>)>> {
    let bytes = std::fs::read(path).unwrap();
    let mut by_topic: std::collections::BTreeMap<String, Vec<(u64, Vec<u8>)>> =
        std::collections::BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        by_topic
            .entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, m.data.into_owned()));
    }
    by_topic
}

#[test]
fn a_killed_run_is_salvaged_into_a_prefix_of_the_run_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let thin = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/thin-tape.toml");
    // The thin tape to 25 s simulated: a few seconds, and logs of several chunks.
    let run = |out: &Path| spawn_run(&thin, out, &["--set", "stop.max_time_s=25"]);
    let full = dir.path().join("full");
    assert!(run(&full).wait().unwrap().success());
    let full_samples = std::fs::read(full.join("samples.csv")).unwrap();
    let full_log = messages_by_topic(&full.join("run.mcap"));
    // Killed at three random moments, early, midway and late: when the samples first pass
    // a size drawn from each third of the file, the last 2 MB short of its end (the draw is
    // printed, so that a failure can be repeated with it).
    let seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos();
    let third = full_samples.len() as u64 / 3;
    let mut logs_kept = 0;
    for i in 0..3_u64 {
        // SplitMix64 of the seed and the moment's number.
        let mut z = u64::from(seed).wrapping_add((i + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        let at = i * third + 500_000 + (z ^ (z >> 31)) % (third - 2_500_000);
        println!("kill {i}: once the samples pass {at} bytes (seed {seed})");
        let out = dir.path().join(format!("killed-{i}"));
        let mut child = run(&out);
        wait_for_samples(&mut child, &out, at);
        child.kill().unwrap();
        child.wait().unwrap();
        let assert = Command::cargo_bin("uncoil")
            .unwrap()
            .args(["check", "--salvage"])
            .arg(&out)
            .assert()
            .code(0);
        let said = String::from_utf8_lossy(&assert.get_output().stdout).into_owned();
        assert!(said.contains("a killed run, salvaged: "), "{said}");
        // Every byte kept is the uninterrupted run's, to the end of a row.
        let kept = std::fs::read(out.join("samples.csv")).unwrap();
        assert!(
            kept.len() as u64 >= at - 100_000,
            "{} bytes kept",
            kept.len()
        );
        assert!(kept.len() < full_samples.len() && kept.ends_with(b"\n"));
        assert!(kept == full_samples[..kept.len()], "kill {i}: not a prefix");
        // Every message kept is the uninterrupted run's, each topic from its start; a run
        // killed before its log finished a chunk keeps none, and says so.
        let log = messages_by_topic(&out.join("run.mcap"));
        logs_kept += usize::from(!log.is_empty());
        if log.is_empty() {
            let needle = "before the log finished its first chunk";
            assert!(said.contains(needle), "kill {i}: {said}");
        }
        for (topic, messages) in &log {
            let whole = &full_log[topic];
            assert!(messages.len() < whole.len(), "{topic}");
            assert!(messages[..] == whole[..messages.len()], "kill {i}: {topic}");
        }
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
        assert_eq!(report["kind"], "salvaged");
        let rows = kept.iter().filter(|&&b| b == b'\n').count() - 1;
        assert_eq!(report["rows"], rows);
        assert_eq!(verify_outputs(&out), Vec::<String>::new());
        let left: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".partial") || n.ends_with(".salvage"))
            .collect();
        assert!(left.is_empty(), "{left:?} left behind");
        // `uncoil check` on it: sound, and says what it is.
        let assert = Command::cargo_bin("uncoil")
            .unwrap()
            .arg("check")
            .arg(&out)
            .assert()
            .code(0);
        let said = String::from_utf8_lossy(&assert.get_output().stdout).into_owned();
        assert!(said.contains("sound and belong to one run"), "{said}");
        // A second salvage is refused: the run has its report now, and says so.
        Command::cargo_bin("uncoil")
            .unwrap()
            .args(["check", "--salvage"])
            .arg(&out)
            .assert()
            .code(2)
            .stderr(predicate::str::contains("was salvaged already"));
    }
    assert!(
        logs_kept >= 2,
        "only {logs_kept} of the killed runs kept messages"
    );
}

#[test]
fn check_runs_a_folder_and_tabulates_every_outcome() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = dir.path().join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    for name in ["coarse-step", "coarsest-links", "one-link-per-turn"] {
        std::fs::copy(hard_path(name), scenes.join(format!("{name}.toml"))).unwrap();
    }
    std::fs::write(
        scenes.join("frictionless.toml"),
        shortened("frictionless", 0.2),
    )
    .unwrap();
    let out = dir.path().join("out");
    let assert = Command::cargo_bin("uncoil")
        .unwrap()
        .arg("check")
        .arg(&scenes)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(0);
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout).into_owned();
    // The table's rows: the case, then its outcome.
    for (case, outcome) in [
        ("coarse-step", "stopped"),
        ("coarsest-links", "completed"),
        ("frictionless", "completed"),
        ("one-link-per-turn", "rejected"),
    ] {
        let row: Vec<&str> = stdout
            .lines()
            .map(|l| l.split_whitespace().collect::<Vec<_>>())
            .find(|w| w.first() == Some(&case))
            .unwrap_or_else(|| panic!("no row for {case}:\n{stdout}"));
        assert_eq!(row[1], outcome, "{case}:\n{stdout}");
    }
    for want in [
        "slip (r=",
        "coarse-step: stopped: joints separating",
        "one-link-per-turn: rejected: discretisation.links_per_turn = 1: a link must be shorter \
         than the outer radius",
        "the coarsest this tape allows is 7 links per turn",
    ] {
        assert!(stdout.contains(want), "stdout lacks `{want}`:\n{stdout}");
    }
    assert!(out.join("frictionless/samples.csv").is_file());

    let empty = dir.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("check")
        .arg(&empty)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "empty: a folder with no scene files (*.toml)",
        ));
    Command::cargo_bin("uncoil")
        .unwrap()
        .arg("check")
        .arg(dir.path().join("missing"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "missing: no such file or folder; expected a folder of scene files",
        ));
}

/// Largest |omega_rad_s| (the coil's spin) in a written `samples.csv`.
fn max_coil_spin(csv: &Path) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "omega_rad_s").unwrap();
    lines
        .filter_map(|l| l.split(',').nth(col).and_then(|v| v.parse::<f64>().ok()))
        .fold(0.0, |m, v| m.max(v.abs()))
}

#[test]
#[ignore = "every hard case, a few minutes in release: cargo test --release -- --ignored"]
fn every_hard_case_ends_with_a_stated_reason() {
    let out = tempfile::tempdir().unwrap();
    let files = uncoil::study::check::scene_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hard"),
    )
    .unwrap();
    let cases: Vec<_> = files
        .iter()
        .map(|f| uncoil::study::check::check_scene(f, out.path()))
        .collect();
    println!("{}", uncoil::study::check::table(&cases));
    let case = |name: &str| cases.iter().find(|c| c.name == name).unwrap();
    for c in &cases {
        assert!(
            c.passed(),
            "{}: {:?} {:?}",
            c.name,
            c.outcome,
            c.output_problems
        );
        if let Some(r) = &c.report {
            assert!(
                r.max_energy_rise_rel <= 0.001,
                "{}: energy rose by {:e} of the energy scale",
                c.name,
                r.max_energy_rise_rel
            );
        }
    }
    for name in [
        "thin-300",
        "push-10",
        "friction-0.05",
        "zero-gravity",
        "big-core",
        "coarsest-links",
        "bang-1e4",
        "slope-down-30",
        "slope-up-10",
    ] {
        assert!(
            case(name).outcome.word() == "completed",
            "{name}: {:?}",
            case(name).outcome
        );
    }
    assert!(matches!(
        case("one-link-per-turn").outcome,
        uncoil::study::check::Outcome::Rejected(_)
    ));
    assert_eq!(case("coarse-step").outcome.word(), "stopped");
    let spin = max_coil_spin(&out.path().join("bang-1e4/samples.csv"));
    assert!(
        spin > 1e4,
        "bang-1e4: the coil spins at most {spin:.0} rad/s"
    );
}
