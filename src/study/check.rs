//! The stability check: runs every scene of a folder (the hard cases of `scenes/hard`),
//! writes each run's outputs, verifies them (present under their final names, every CSV
//! row complete, no NaN or infinity anywhere) and tabulates the outcome, the health maxima
//! and where the references stop applying. It adds no physics and no output format.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use anyhow::Context as _;

use crate::output::files::{RunFiles, View};
use crate::output::table::Table;
use crate::output::{CSV_COLUMNS, folder};
use crate::run::RunReport;
use crate::run::folded::{ChainReport, ChainSample};
use crate::run::limits::label;
use crate::run::stop::{Status, StopReason};
use crate::scene::Scene;
use crate::scene::folded;

mod crashed;
pub mod salvage;

pub use crashed::crashed_run;

/// How one case ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The scene was rejected when loaded, with this message.
    Rejected(String),
    /// The run ended, for this reason (as planned, interrupted, or stopped by a guard).
    Ended(StopReason),
    /// The run failed (an output could not be written), with this error.
    Failed(String),
}

impl Outcome {
    /// One word for the table.
    pub fn word(&self) -> &'static str {
        match self {
            Outcome::Rejected(_) => "rejected",
            Outcome::Ended(stop) => match stop.status() {
                Status::Completed => "completed",
                Status::Interrupted => "interrupted",
                Status::Stopped => "stopped",
            },
            Outcome::Failed(_) => "FAILED",
        }
    }

    /// The stated reason or message.
    pub fn reason(&self) -> String {
        match self {
            Outcome::Rejected(s) | Outcome::Failed(s) => s.clone(),
            Outcome::Ended(stop) => stop.to_string(),
        }
    }
}

/// The result of one case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The scene file's stem.
    pub name: String,
    /// How it ended.
    pub outcome: Outcome,
    /// The run's report, if it ran.
    pub report: Option<RunReport>,
    /// What is wrong with the written outputs (empty when they are sound).
    pub output_problems: Vec<String>,
}

impl Case {
    /// A case passes when it ended with a stated reason (completed, stopped by a guard, or
    /// rejected with a message) and its outputs are sound.
    pub fn passed(&self) -> bool {
        !matches!(self.outcome, Outcome::Failed(_)) && self.output_problems.is_empty()
    }
}

/// A simulated time as a message says it: to the microsecond, trailing zeros dropped
/// (`29.75`, not the `29.750000000000004` a sum of steps leaves).
pub(crate) fn seconds(t: f64) -> String {
    let text = format!("{t:.6}");
    let text = text.trim_end_matches('0');
    text.strip_suffix('.').unwrap_or(text).to_owned()
}

/// The scene files (`*.toml`) of `dir`, sorted by name.
pub fn scene_files(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read scene folder {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    Ok(files)
}

/// Loads and runs one scene file, writing its outputs into `out_root/<name>`, and verifies
/// them. Its name is the file's without `.toml`; a shipped name (`hard/friction-0.05`) is
/// kept whole, dots and all.
pub fn check_scene(path: &Path, out_root: &Path) -> Case {
    let name = match path.extension() {
        Some(x) if x == "toml" => path.file_stem(),
        _ => path.file_name(),
    }
    .map(|s| s.to_string_lossy().into_owned())
    .unwrap_or_default();
    let scene = match Scene::from_file(path) {
        Ok(s) => s,
        Err(e) => {
            return Case {
                name,
                outcome: Outcome::Rejected(e.to_string()),
                report: None,
                output_problems: Vec::new(),
            };
        }
    };
    let dir = out_root.join(&name);
    match run_into(&scene, &dir) {
        Ok(report) => Case {
            name,
            outcome: Outcome::Ended(report.stop.clone()),
            output_problems: verify_outputs(&dir),
            report: Some(report),
        },
        Err(e) => Case {
            name,
            outcome: Outcome::Failed(format!("{e:#}")),
            report: None,
            output_problems: Vec::new(),
        },
    }
}

fn run_into(scene: &Scene, dir: &Path) -> anyhow::Result<RunReport> {
    RunFiles::take(dir, scene, View::Off)?.run(scene, None, &AtomicBool::new(false))
}

/// What is wrong with the outputs in `dir`, a coil's run or a folded chain's (as its
/// `report.json` says): a missing `samples.csv` or `report.json`, a leftover `.partial`
/// file, a CSV row with the wrong number of cells or a cell that is not a finite number
/// (empty cells are allowed), a `NaN` or infinity in the JSON, files of different runs.
pub fn verify_outputs(dir: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    for name in [folder::SAMPLES, folder::REPORT] {
        let partial = crate::output::partial_path(&dir.join(name));
        if partial.exists() {
            problems.push(format!("{} left behind", partial.display()));
        }
    }
    let report = std::fs::read_to_string(dir.join(folder::REPORT));
    let kind = report
        .as_ref()
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(text).ok())
        .map(|v| ReportKind::of(&v))
        .unwrap_or(ReportKind::Coil);
    let columns: Vec<String> = if matches!(
        kind,
        ReportKind::Chain | ReportKind::Salvaged { chain: true }
    ) {
        chain_columns()
    } else {
        CSV_COLUMNS.iter().map(|c| (*c).to_owned()).collect()
    };
    match std::fs::read_to_string(dir.join(folder::SAMPLES)) {
        Ok(text) => problems.extend(csv_problems(&text, &columns)),
        Err(e) => problems.push(format!("{}: {e}", folder::SAMPLES)),
    }
    match report {
        Ok(text) => problems.extend(match kind {
            ReportKind::Coil => report_problem(&text),
            ReportKind::Chain => chain_report_problem(&text),
            ReportKind::Salvaged { .. } => salvage_report_problem(&text),
        }),
        Err(e) => problems.push(format!("{}: {e}", folder::REPORT)),
    }
    problems.extend(folder::mismatches(dir));
    problems
}

/// Whose `report.json` a folder has, as its `kind` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ReportKind {
    /// A coil's run (no `kind`).
    Coil,
    /// A folded chain's run.
    Chain,
    /// A killed run's, salvaged ([`salvage`]): its samples a folded chain's or not, as
    /// `samples_of` says.
    Salvaged {
        /// Whether the samples are a folded chain's.
        chain: bool,
    },
}

impl ReportKind {
    fn of(report: &serde_json::Value) -> Self {
        match report.get("kind").and_then(|k| k.as_str()) {
            Some(folded::KIND) => Self::Chain,
            Some(salvage::KIND) => Self::Salvaged {
                chain: report.get("samples_of").and_then(|k| k.as_str()) == Some(folded::KIND),
            },
            _ => Self::Coil,
        }
    }
}

/// Why a salvaged run's `report.json` does not read back as a [`salvage::SalvageReport`].
fn salvage_report_problem(text: &str) -> Option<String> {
    serde_json::from_str::<salvage::SalvageReport>(text)
        .err()
        .map(|e| format!("report.json: a salvaged run's report does not read back: {e}"))
}

/// Why `report.json`'s text does not read back as a [`RunReport`], naming the field: serde
/// writes a NaN or an infinity as `null`, which only an optional value may be.
fn report_problem(text: &str) -> Option<String> {
    let mut de = serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize::<_, RunReport>(&mut de)
        .err()
        .map(|e| {
            format!(
                "report.json: {} does not read back: {}",
                e.path(),
                e.inner()
            )
        })
}

/// The columns of a folded chain's `samples.csv`: [`ChainSample`]'s fields as the `csv`
/// crate writes them.
fn chain_columns() -> Vec<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = w
        .serialize(ChainSample::default())
        .ok()
        .and_then(|()| w.into_inner().ok())
        .and_then(|bytes| String::from_utf8(bytes).ok())
        .unwrap_or_default();
    header
        .lines()
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_owned)
        .collect()
}

/// Why a folded chain's `report.json` does not read back: its `report` as a [`ChainReport`].
fn chain_report_problem(text: &str) -> Option<String> {
    let value: serde_json::Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => return Some(format!("report.json: {e}")),
    };
    let report = value.get("report").cloned().unwrap_or_default();
    serde_json::from_value::<ChainReport>(report)
        .err()
        .map(|e| format!("report.json: report does not read back: {e}"))
}

/// Problems of a `samples.csv` text against its `columns`: header, cell count, non-finite
/// cells; at most about ten. Read with the `csv` crate, as every other reader of the file
/// reads it (quoting included).
pub fn csv_problems(text: &str, columns: &[String]) -> Vec<String> {
    let mut problems = Vec::new();
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    match reader.headers() {
        Ok(header) if header.iter().eq(columns.iter().map(String::as_str)) => {}
        _ => problems.push("samples.csv: header differs from the documented columns".to_owned()),
    }
    let mut rows = 0usize;
    for (i, record) in reader.records().enumerate() {
        rows += 1;
        if problems.len() > 10 {
            problems.push("samples.csv: more problems not listed".to_owned());
            break;
        }
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                problems.push(format!("samples.csv row {}: {e}", i + 1));
                continue;
            }
        };
        if record.len() != columns.len() {
            problems.push(format!(
                "samples.csv row {}: {} cells, expected {}",
                i + 1,
                record.len(),
                columns.len()
            ));
            continue;
        }
        for (cell, column) in record.iter().zip(columns.iter()) {
            if cell.is_empty() || problems.len() > 10 {
                continue;
            }
            if !cell.parse::<f64>().is_ok_and(f64::is_finite) {
                problems.push(format!(
                    "samples.csv row {}: {column} = {cell:?} is not a finite number",
                    i + 1
                ));
            }
        }
    }
    if rows == 0 {
        problems.push("samples.csv has no rows".to_owned());
    }
    problems
}

fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// The final bang of each case that had one: what still moves at the end, what ended it,
/// where what it dissipated went (percent of it), and its wall time over the unroll's.
fn bang_table(o: &mut String, cases: &[Case]) {
    let rows: Vec<_> = cases
        .iter()
        .filter_map(|c| Some((c, c.report.as_ref()?, c.report.as_ref()?.bang?)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(o);
    let mut table = Table::new([
        "final bang",
        "moving %",
        "ended",
        "normal",
        "frict.",
        "joints",
        "freeze",
        "resid.",
        "numer.",
        "bang/unroll",
    ]);
    for (c, r, b) in rows {
        let d = r.ledger.dissipated_by_bang_j;
        let split = r.ledger.bang_split_meaningful();
        let pc = |x: f64| {
            if split {
                format!("{:.1}", 100.0 * x / d)
            } else {
                "-".to_owned()
            }
        };
        let l = &r.ledger.bang;
        let ended = match b.ended_by {
            Some(crate::model::BangEnd::Rest) => "rest",
            Some(crate::model::BangEnd::Cap) => "cap",
            None => "cut",
        };
        let unroll = r.wall_time_rolling_s;
        table.push([
            c.name.clone(),
            format!("{:.3}", 100.0 * b.still_moving_j / b.kinetic_in_j),
            ended.to_owned(),
            pc(l.floor_normal_j),
            pc(l.floor_friction_j),
            pc(l.joints_j),
            pc(l.freeze_j),
            pc(l.residual_j),
            pc(l.numerical_j()),
            format!("{:.2}", (r.wall_time_s - unroll) / unroll),
        ]);
    }
    o.push_str(&table.text(""));
    let _ = writeln!(
        o,
        "moving %: kinetic energy still moving at the end, percent of what the bang received; \
         ended: rest (stop.rest_fraction), cap (stop.bang_cap_s) or cut (the run stopped \
         first); normal .. resid.: what the bang dissipated by mechanism, percent of it (-: \
         under 1 % of the energy scale, too little to split); \
         numer.: |joints| + |resid.|; bang/unroll: the bang's engine wall time over the unroll's."
    );
}

/// The table of cases, then each case's stated reason and where its references stop
/// applying, then any output problem.
pub fn table(cases: &[Case]) -> String {
    let mut o = String::new();
    let mut table = Table::new([
        "case",
        "outcome",
        "joint m",
        "penetr. m",
        "E drift",
        "wall s",
        "spin rad/s",
        "references stop applying",
    ]);
    for c in cases {
        let (gap, pen, drift, wall, spin, limits) = match &c.report {
            Some(r) => (
                sci(r.max_joint_gap_m),
                sci(r.max_penetration_m),
                format!("{:+.1e}", r.max_energy_rise_rel),
                format!("{:.2}", r.wall_time_s),
                sci(r.max_spin_rad_s),
                r.reference_limits
                    .iter()
                    .map(|l| match l.t_s {
                        Some(_) => format!("{} (r={:.2e})", label(l.kind), l.r_m),
                        None => format!("{} (not reached)", label(l.kind)),
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
            None => Default::default(),
        };
        let dash = |s: String| if s.is_empty() { "-".to_owned() } else { s };
        table.push([
            c.name.clone(),
            c.outcome.word().to_owned(),
            dash(gap),
            dash(pen),
            dash(drift),
            dash(wall),
            dash(spin),
            dash(limits),
        ]);
    }
    o.push_str(&table.text(""));
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "joint m, penetr. m: largest joint separation and floor penetration; E drift: largest \
         E - E0 over the energy scale (the largest of |E0|, MgR and the kinetic energy into the \
         bang; 0: the energy never rose); wall s: wall time of the engine steps; spin: fastest \
         body spin."
    );
    bang_table(&mut o, cases);
    for c in cases {
        let _ = writeln!(
            o,
            "{}: {}: {}",
            c.name,
            c.outcome.word(),
            c.outcome.reason()
        );
        for p in &c.output_problems {
            let _ = writeln!(o, "{}: OUTPUT PROBLEM: {p}", c.name);
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(cells: &[&str]) -> String {
        let mut v: Vec<String> = cells.iter().map(|s| (*s).to_owned()).collect();
        v.resize(CSV_COLUMNS.len(), "1.0e0".to_owned());
        v.join(",")
    }

    /// A coil's columns.
    fn coil() -> Vec<String> {
        CSV_COLUMNS.iter().map(|c| (*c).to_owned()).collect()
    }

    #[test]
    fn a_case_is_named_by_its_file_without_toml_and_a_shipped_name_whole() {
        let out = tempfile::tempdir().unwrap();
        let missing = out.path().join("missing");
        for (path, name) in [
            (missing.join("friction-0.05.toml"), "friction-0.05"),
            (missing.join("friction-0.05"), "friction-0.05"),
            (missing.join("thin-300.toml"), "thin-300"),
        ] {
            let case = check_scene(&path, out.path());
            assert_eq!(case.name, name, "{}", path.display());
            assert!(matches!(case.outcome, Outcome::Rejected(_)), "{case:?}");
        }
    }

    #[test]
    fn a_folded_chains_folder_is_checked_as_a_chains() {
        let chain = crate::scene::folded::FoldedChain::from_toml_str(
            "kind = \"folded-chain\"\n[chain]\nlinks = 10\n[stop]\nmax_time_s = 0.01\n",
            "fc",
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let folder = folder::RunFolder::take(dir.path(), "id", "fc").unwrap();
        let stop = AtomicBool::new(false);
        crate::output::folded::write_chain_run(&chain, &folder, &mut |_| Ok(()), &stop).unwrap();
        assert_eq!(verify_outputs(dir.path()), Vec::<String>::new());
        // A samples file that is not the one the report was written with.
        let samples = dir.path().join(folder::SAMPLES);
        let text = std::fs::read_to_string(&samples).unwrap();
        std::fs::write(&samples, format!("{text}{}", text.lines().last().unwrap())).unwrap();
        let p = verify_outputs(dir.path());
        assert!(
            p.len() == 1 && p[0].contains("is not the one report.json was written with"),
            "{p:?}"
        );
    }

    #[test]
    fn sound_csv_has_no_problems() {
        let text = format!(
            "{}\n{}\n{}\n",
            CSV_COLUMNS.join(","),
            row(&[]),
            row(&["", ""])
        );
        assert_eq!(csv_problems(&text, &coil()), Vec::<String>::new());
    }

    #[test]
    fn nan_short_row_and_empty_table_are_problems() {
        let header = CSV_COLUMNS.join(",");
        let p = csv_problems(&format!("{header}\n{}\n", row(&["NaN"])), &coil());
        assert!(p.len() == 1 && p[0].contains("t_s = \"NaN\""), "{p:?}");
        let p = csv_problems(&format!("{header}\n{}\n", row(&["0", "inf"])), &coil());
        assert!(p.len() == 1 && p[0].contains("laid_fraction"), "{p:?}");
        let p = csv_problems(&format!("{header}\n1,2,3\n"), &coil());
        assert!(p.len() == 1 && p[0].contains("3 cells"), "{p:?}");
        let p = csv_problems(&format!("{header}\n"), &coil());
        assert_eq!(p, vec!["samples.csv has no rows".to_owned()]);
        let p = csv_problems("a,b\n", &coil());
        assert!(p[0].contains("header"), "{p:?}");
    }

    #[test]
    fn a_report_reads_back_unless_a_number_is_null() {
        let scene = crate::scene::tests::short_yoga(0.05);
        let report = crate::run::run(&scene, &mut []).unwrap();
        let mut v = serde_json::to_value(&report).unwrap();
        assert_eq!(report_problem(&v.to_string()), None);
        // An optional value may be null; a number may not (a NaN written out).
        v["geo_hop_fraction"] = serde_json::Value::Null;
        assert_eq!(report_problem(&v.to_string()), None);
        v["ledger"]["e0_j"] = serde_json::Value::Null;
        let p = report_problem(&v.to_string()).expect("a null number is a problem");
        assert!(p.contains("ledger.e0_j"), "{p}");
    }
}
