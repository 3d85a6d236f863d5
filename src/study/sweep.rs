//! Parameter sweeps: the product grid of `--vary KEY=V1,V2,...` over a scene, run in
//! parallel (rayon), one row per finished run appended and flushed to `sweep.csv`, shards
//! (`K/N`) for batch schedulers and the merge of shard files. It does no physics and draws
//! nothing: each run is [`run`] on a scene built by
//! [`scene_with_overrides`]; reports are in
//! [`analysis`](crate::study::analysis) and [`plot`](crate::study::plot).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead, BufReader, IsTerminal, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::Context as _;
use rayon::prelude::*;

use crate::output::write_atomic;
use crate::run::limits::LimitKind;
use crate::run::milestones::MilestoneKey;
use crate::run::stop::StopReason;
use crate::run::{RunReport, milestone_radii, run};
use crate::scene::overrides::{Override, OverrideSyntaxError, check_key, scene_with_overrides};
use crate::scene::{Scene, SceneError};

/// The first column of `sweep.csv`: the combination's place in the full grid (0-based,
/// last `--vary` key fastest), the same in every shard.
pub const INDEX_COLUMN: &str = "index";
/// The last column of `sweep.csv`, a [`RowStatus`].
pub const STATUS_COLUMN: &str = "status";

/// How a sweep's run ended, as its `status` cell says it: `ok` (the bang ended),
/// `max_time` (`stop.max_time_s` reached first), `interrupted`, `stopped: <guard>` (a
/// guard stopped it, with the guard's value and bound) or `failed: <error>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RowStatus {
    /// The final bang ended, at rest or at its cap.
    Ok,
    /// `stop.max_time_s` was reached before the bang ended.
    MaxTime,
    /// The run was asked to stop.
    Interrupted,
    /// A guard stopped the run; what it said.
    Stopped(String),
    /// The run failed or panicked; its error.
    Failed(String),
}

impl RowStatus {
    /// The status of a run that ended.
    pub fn of(stop: &StopReason) -> Self {
        match stop {
            StopReason::AtRest { .. } | StopReason::BangCap { .. } => Self::Ok,
            StopReason::MaxTime { .. } => Self::MaxTime,
            StopReason::Interrupted { .. } => Self::Interrupted,
            StopReason::Guard(trip) => Self::Stopped(one_line(&trip.to_string())),
        }
    }

    /// Whether the run's figures enter a sweep's fits: it ran to its bang's end or to its
    /// time limit, unstopped.
    pub fn fits(&self) -> bool {
        matches!(self, Self::Ok | Self::MaxTime)
    }
}

fn one_line(text: &str) -> String {
    text.replace(['\n', '\r'], " ")
}

impl std::fmt::Display for RowStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Ok => f.write_str("ok"),
            Self::MaxTime => f.write_str("max_time"),
            Self::Interrupted => f.write_str("interrupted"),
            Self::Stopped(why) => write!(f, "stopped: {why}"),
            Self::Failed(why) => write!(f, "failed: {why}"),
        }
    }
}

impl FromStr for RowStatus {
    type Err = String;

    fn from_str(cell: &str) -> Result<Self, String> {
        match cell {
            "ok" => Ok(Self::Ok),
            "max_time" => Ok(Self::MaxTime),
            "interrupted" => Ok(Self::Interrupted),
            _ => {
                if let Some(why) = cell.strip_prefix("stopped: ") {
                    Ok(Self::Stopped(why.to_owned()))
                } else if let Some(why) = cell.strip_prefix("failed: ") {
                    Ok(Self::Failed(why.to_owned()))
                } else {
                    Err(format!(
                        "status `{cell}`: expected ok, max_time, interrupted, stopped: ... or failed: ..."
                    ))
                }
            }
        }
    }
}

/// One `--vary KEY=V1,V2,...`: a key and the values it takes.
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// Dotted scene key.
    pub key: String,
    /// The values, in the order given.
    pub values: Vec<Override>,
}

impl FromStr for Vary {
    type Err = OverrideSyntaxError;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let fail = |rule: &str| OverrideSyntaxError {
            arg: arg.to_owned(),
            rule: rule.to_owned(),
        };
        let (key, list) = arg
            .split_once('=')
            .ok_or_else(|| fail("expected KEY=V1,V2,..., e.g. solver.iterations=2,4,8"))?;
        let key = key.trim();
        check_key(key).map_err(|r| fail(&r))?;
        let mut values = Vec::new();
        for raw in list.split(',') {
            let raw = raw.trim();
            if raw.is_empty() {
                return Err(fail("empty value in the list"));
            }
            values.push(Override::new(key, raw));
        }
        Ok(Self {
            key: key.to_owned(),
            values,
        })
    }
}

/// `--shard K/N`: the K-th (1-based) of N slices of the grid; combination `i` belongs to
/// shard `i mod N + 1`, so slices are interleaved and of nearly equal cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This slice, 1..=`n`.
    pub k: usize,
    /// Number of slices.
    pub n: usize,
}

impl Shard {
    /// The whole grid.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Whether combination `index` belongs to this shard.
    pub fn contains(self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}

impl FromStr for Shard {
    type Err = OverrideSyntaxError;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let fail = || OverrideSyntaxError {
            arg: arg.to_owned(),
            rule: "expected K/N with 1 <= K <= N, e.g. 3/8".into(),
        };
        let (k, n) = arg.split_once('/').ok_or_else(fail)?;
        let k: usize = k.trim().parse().map_err(|_| fail())?;
        let n: usize = n.trim().parse().map_err(|_| fail())?;
        if k == 0 || k > n {
            return Err(fail());
        }
        Ok(Self { k, n })
    }
}

/// One point of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// Place in the full grid (0-based).
    pub index: usize,
    /// One override per varied key, in `--vary` order.
    pub overrides: Vec<Override>,
}

/// The product grid of `varies`, last key fastest. No keys give one empty combination
/// (the scene as it is).
pub fn grid(varies: &[Vary]) -> Vec<Combination> {
    let mut combos: Vec<Vec<Override>> = vec![Vec::new()];
    for v in varies {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                v.values.iter().map(move |o| {
                    let mut c = c.clone();
                    c.push(o.clone());
                    c
                })
            })
            .collect();
    }
    combos
        .into_iter()
        .enumerate()
        .map(|(index, overrides)| Combination { index, overrides })
        .collect()
}

/// A bad combination: names it and carries the scene's own error.
#[derive(Debug, thiserror::Error)]
#[error("combination {index} ({settings}): {source}")]
pub struct CombinationError {
    /// Place in the grid.
    pub index: usize,
    /// Its overrides, `k=v k=v`.
    pub settings: String,
    /// The scene's error.
    pub source: SceneError,
}

/// Builds and validates the scene of every combination, so that a bad value stops the
/// sweep before any run starts.
pub fn scenes(
    text: &str,
    name: &str,
    combos: &[Combination],
) -> Result<Vec<Scene>, CombinationError> {
    combos
        .iter()
        .map(|c| {
            scene_with_overrides(text, name, &c.overrides).map_err(|source| CombinationError {
                index: c.index,
                settings: settings(&c.overrides),
                source,
            })
        })
        .collect()
}

fn settings(overrides: &[Override]) -> String {
    overrides
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

/// Column names after the varied keys, for a scene's milestone labels.
pub fn result_columns(milestone_labels: &[String]) -> Vec<String> {
    let mut c: Vec<String> = [
        "links",
        "steps",
        "jobs",
        "wall_s",
        "wall_rolling_s",
        "sim_time_s",
        "bang_time_s",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    for l in milestone_labels {
        c.push(format!("err_geo_{l}"));
    }
    for l in milestone_labels {
        c.push(format!("err_eq7_{l}"));
    }
    c.extend(
        [
            "max_err_geo",
            "max_err_eq7",
            "e0_j",
            "lost_before_bang_j",
            "lost_before_bang_of_e0",
            "lost_before_2b_of_e0",
            "max_energy_rise_rel",
            "peak_xdot_m_s",
            "peak_r_m",
            "lift_off_r_m",
            "leaves_exact_r_m",
            "exact_hops_r_m",
        ]
        .iter()
        .map(|s| (*s).to_owned()),
    );
    c.extend(BANG_COLUMNS.iter().map(|s| (*s).to_owned()));
    c.extend([STATUS_COLUMN].iter().map(|s| (*s).to_owned()));
    c
}

/// The final bang's columns of `sweep.csv` (empty cells for a run stopped before the
/// bang): what it received and dissipated, the split of what it dissipated by mechanism
/// (fractions), its observables, and what ended it.
pub const BANG_COLUMNS: [&str; 17] = [
    "bang_kinetic_in_j",
    "bang_dissipated_j",
    "bang_floor_normal_of",
    "bang_floor_friction_of",
    "bang_joints_of",
    "bang_freeze_of",
    "bang_residual_of",
    "bang_numerical_of",
    "bang_top_speed_m_s",
    "bang_duration_s",
    "bang_peak_floor_force_n",
    "bang_floor_impulse_n_s",
    "bang_end_x_m",
    "bang_laid_length_m",
    "bang_still_moving_of",
    "bang_wall_s",
    "bang_ended_by",
];

/// The header of `sweep.csv`: index, the varied keys, then [`result_columns`].
pub fn header(keys: &[String], milestone_labels: &[String]) -> Vec<String> {
    let mut h = vec![INDEX_COLUMN.to_owned()];
    h.extend(keys.iter().cloned());
    h.extend(result_columns(milestone_labels));
    h
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6e}")
    } else {
        String::new()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, num)
}

/// Largest `|e|` over all milestones, `None` if any milestone was not reached.
fn max_abs(errs: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    errs.map(|e| e.map(f64::abs))
        .try_fold(0.0_f64, |m, e| e.map(|e| m.max(e)))
}

/// The result cells of a finished run, in [`result_columns`] order.
pub fn result_cells(report: &RunReport, jobs: usize) -> Vec<String> {
    let l = &report.ledger;
    let mut c = vec![
        report.links.to_string(),
        report.steps.to_string(),
        jobs.to_string(),
        num(report.wall_time_s),
        num(report.wall_time_rolling_s),
        num(report.sim_time_s),
        opt(l.bang_time_s),
    ];
    c.extend(report.milestones.iter().map(|m| opt(m.err_vs_geo)));
    c.extend(report.milestones.iter().map(|m| opt(m.err_vs_eq7)));
    c.push(opt(max_abs(report.milestones.iter().map(|m| m.err_vs_geo))));
    c.push(opt(max_abs(report.milestones.iter().map(|m| m.err_vs_eq7))));
    c.push(num(l.e0_j));
    c.push(num(l.lost_before_bang_j));
    c.push(num(l.lost_before_bang_j / l.e0_j));
    c.push(opt(report
        .milestones
        .iter()
        .find(|m| m.key == MilestoneKey::TwoB)
        .and_then(|m| m.dissipated_j)
        .map(|d| d / l.e0_j)));
    c.push(num(report.max_energy_rise_rel));
    c.push(num(report.approach.peak_xdot_m_s));
    c.push(num(report.approach.peak_r_m));
    for kind in [
        LimitKind::LiftOff,
        LimitKind::LeavesExact,
        LimitKind::ExactModelHops,
    ] {
        let r = report
            .reference_limits
            .iter()
            .find(|l| l.kind == kind && l.t_s.is_some())
            .map(|l| l.r_m);
        c.push(opt(r));
    }
    c.extend(bang_cells(report));
    c.push(RowStatus::of(&report.stop).to_string());
    c
}

/// The [`BANG_COLUMNS`] cells of a finished run.
fn bang_cells(report: &RunReport) -> Vec<String> {
    let Some(b) = &report.bang else {
        return vec![String::new(); BANG_COLUMNS.len()];
    };
    let l = &report.ledger;
    let d = l.dissipated_by_bang_j;
    let of = |x: f64| num(x / d);
    let split = &l.bang;
    vec![
        num(b.kinetic_in_j),
        num(d),
        of(split.floor_normal_j),
        of(split.floor_friction_j),
        of(split.joints_j),
        of(split.freeze_j),
        of(split.residual_j),
        of(split.numerical_j()),
        num(b.top_speed_m_s),
        num(b.duration_s),
        num(b.peak_floor_force_n),
        num(b.floor_impulse_n_s),
        num(b.end_x_m),
        num(b.laid_length_m),
        num(b.still_moving_j / b.kinetic_in_j),
        num(report.wall_time_s - report.wall_time_rolling_s),
        b.ended_by.map_or_else(String::new, |e| {
            match e {
                crate::model::BangEnd::Rest => "rest",
                crate::model::BangEnd::Cap => "cap",
            }
            .to_owned()
        }),
    ]
}

/// Quotes a CSV cell if it holds a comma, a quote or a line break (RFC 4180).
pub fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// Joins cells into one CSV line (no line break).
pub fn csv_line(cells: &[String]) -> String {
    cells
        .iter()
        .map(|c| csv_cell(c))
        .collect::<Vec<_>>()
        .join(",")
}

/// Splits one CSV line (RFC 4180 quoting, no embedded line breaks) into cells.
pub fn split_csv_line(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(ch) = chars.next() {
        match (quoted, ch) {
            (true, '"') if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if cur.is_empty() => quoted = true,
            (false, ',') => cells.push(std::mem::take(&mut cur)),
            _ => cur.push(ch),
        }
    }
    cells.push(cur);
    cells
}

/// A sweep file in memory: header and rows of cells.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepTable {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl SweepTable {
    /// Reads a sweep (or any header-first) CSV file; a row of the wrong length is an error.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let file = File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
        let mut lines = BufReader::new(file).lines();
        let header = split_csv_line(
            &lines
                .next()
                .with_context(|| format!("{} is empty", path.display()))??,
        );
        let mut rows = Vec::new();
        for (i, line) in lines.enumerate() {
            let line = line?;
            if line.trim().is_empty() {
                continue;
            }
            let row = split_csv_line(&line);
            anyhow::ensure!(
                row.len() == header.len(),
                "{} line {}: {} cells, the header has {}",
                path.display(),
                i + 2,
                row.len(),
                header.len()
            );
            rows.push(row);
        }
        Ok(Self { header, rows })
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The cells of column `name` parsed as numbers (`NaN` where empty or not a number).
    pub fn numbers(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.column(name)?;
        Some(
            self.rows
                .iter()
                .map(|r| r[c].parse().unwrap_or(f64::NAN))
                .collect(),
        )
    }

    /// The varied keys: the columns between `index` and `links`.
    pub fn varied_keys(&self) -> Vec<String> {
        let end = self.column("links").unwrap_or(self.header.len());
        self.header
            .iter()
            .take(end)
            .skip(1)
            .cloned()
            .collect::<Vec<_>>()
    }

    /// The text of the table as CSV.
    pub fn to_csv(&self) -> String {
        let mut s = csv_line(&self.header);
        s.push('\n');
        for r in &self.rows {
            s.push_str(&csv_line(r));
            s.push('\n');
        }
        s
    }
}

/// Joins shard files into one table sorted by `index`. Every file must have the same
/// header; an index found twice is an error (a shard run twice, or the same file given
/// twice).
pub fn merge(inputs: &[PathBuf]) -> anyhow::Result<SweepTable> {
    anyhow::ensure!(!inputs.is_empty(), "nothing to merge");
    let mut merged: Option<SweepTable> = None;
    let mut seen: BTreeMap<usize, PathBuf> = BTreeMap::new();
    for path in inputs {
        let t = SweepTable::read(path)?;
        let ic = t
            .column(INDEX_COLUMN)
            .with_context(|| format!("{}: no `{INDEX_COLUMN}` column", path.display()))?;
        if let Some(m) = &merged {
            anyhow::ensure!(
                m.header == t.header,
                "{}: its columns differ from those of {} (not shards of one sweep)",
                path.display(),
                inputs[0].display()
            );
        }
        for r in &t.rows {
            let i: usize = r[ic].parse().with_context(|| {
                format!("{}: `{}` is not a combination index", path.display(), r[ic])
            })?;
            if let Some(first) = seen.insert(i, path.clone()) {
                anyhow::bail!(
                    "combination {i} is in both {} and {}",
                    first.display(),
                    path.display()
                );
            }
        }
        match &mut merged {
            None => merged = Some(t),
            Some(m) => m.rows.extend(t.rows),
        }
    }
    let mut m = merged.expect("at least one input");
    let ic = m.column(INDEX_COLUMN).expect("checked above");
    m.rows
        .sort_by_key(|r| r[ic].parse::<usize>().unwrap_or(usize::MAX));
    Ok(m)
}

/// What a sweep did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepOutcome {
    /// The file written.
    pub path: PathBuf,
    /// Combinations in the whole grid.
    pub grid: usize,
    /// Runs in this shard.
    pub runs: usize,
    /// Runs whose status is `failed: ...`.
    pub failed: usize,
    /// Runs a guard stopped (`stopped: ...`).
    pub stopped: usize,
}

/// How to run a sweep.
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// This shard (default: the whole grid).
    pub shard: Shard,
    /// Worker threads (default: one per core).
    pub jobs: Option<usize>,
    /// A progress bar on stderr if it is a terminal, else one line per finished run.
    pub progress: bool,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            shard: Shard::ALL,
            jobs: None,
            progress: true,
        }
    }
}

/// The file name of a shard's output: `sweep.csv`, or `sweep.K-of-N.csv`.
pub fn file_name(shard: Shard) -> String {
    if shard == Shard::ALL {
        "sweep.csv".into()
    } else {
        format!("sweep.{}-of-{}.csv", shard.k, shard.n)
    }
}

/// A sweep ready to run: the grid, validated (every combination's scene built).
pub struct Sweep {
    keys: Vec<String>,
    combos: Vec<Combination>,
    scenes: Vec<Scene>,
}

impl Sweep {
    /// Builds the grid of `varies` over scene `text` and validates every combination.
    pub fn new(text: &str, name: &str, varies: &[Vary]) -> Result<Self, CombinationError> {
        let combos = grid(varies);
        let scenes = scenes(text, name, &combos)?;
        Ok(Self {
            keys: varies.iter().map(|v| v.key.clone()).collect(),
            combos,
            scenes,
        })
    }

    /// Number of combinations in the grid.
    pub fn len(&self) -> usize {
        self.combos.len()
    }

    /// Whether the grid is empty (it never is: no keys give one combination).
    pub fn is_empty(&self) -> bool {
        self.combos.is_empty()
    }

    /// Runs this shard's combinations, appending one row to `dir/`[`file_name`] as each
    /// run ends. A run that fails or panics gets a `failed: ...` row; the sweep goes on.
    pub fn run(&self, dir: &Path, opts: &SweepOptions) -> anyhow::Result<SweepOutcome> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create output folder {}", dir.display()))?;
        let path = dir.join(file_name(opts.shard));
        let labels: Vec<String> = milestone_radii(&self.scenes[0])
            .into_iter()
            .map(|(l, _)| l.to_string())
            .collect();
        let header = header(&self.keys, &labels);
        let mut file =
            File::create(&path).with_context(|| format!("cannot create {}", path.display()))?;
        writeln!(file, "{}", csv_line(&header))?;
        file.flush()?;
        let file = Mutex::new(file);

        let mine: Vec<usize> = (0..self.combos.len())
            .filter(|&i| opts.shard.contains(i))
            .collect();
        let pool = {
            let mut b = rayon::ThreadPoolBuilder::new();
            if let Some(j) = opts.jobs {
                b = b.num_threads(j);
            }
            b.build().context("cannot start the worker threads")?
        };
        let jobs = pool.current_num_threads();
        let bar = progress_bar(opts.progress, mine.len());
        let done = Mutex::new(0usize);
        let failed = Mutex::new(0usize);
        let stopped = Mutex::new(0usize);
        let result: anyhow::Result<()> = pool.install(|| {
            mine.par_iter().try_for_each(|&i| {
                let combo = &self.combos[i];
                let scene = &self.scenes[i];
                let started = Instant::now();
                let outcome = catch_unwind(AssertUnwindSafe(|| run(scene, &mut [])));
                let result = match outcome {
                    Ok(Ok(report)) => Ok(report),
                    Ok(Err(e)) => Err(format!("{e:#}")),
                    Err(p) => Err(panic_text(p.as_ref())),
                };
                let mut row = vec![combo.index.to_string()];
                row.extend(combo.overrides.iter().map(|o| o.raw.clone()));
                let note = match &result {
                    Ok(report) => {
                        row.extend(result_cells(report, jobs));
                        if report.stop.guard().is_some() {
                            *stopped.lock().expect("no panic holds the lock") += 1;
                        }
                        let status = row.last().cloned().unwrap_or_default();
                        let err = report
                            .milestones
                            .iter()
                            .filter_map(|m| m.err_vs_geo)
                            .fold(0.0_f64, |a, e| a.max(e.abs()));
                        format!(
                            "{status}, {:.3} s wall to the bang, max |err vs exact| {:.3}%",
                            report.wall_time_rolling_s,
                            100.0 * err
                        )
                    }
                    Err(e) => {
                        *failed.lock().expect("no panic holds the lock") += 1;
                        let n = header.len() - row.len() - 1;
                        row.extend(std::iter::repeat_n(String::new(), n));
                        let msg = RowStatus::Failed(one_line(e)).to_string();
                        row.push(msg.clone());
                        msg
                    }
                };
                {
                    let mut f = file.lock().expect("no panic holds the lock");
                    writeln!(f, "{}", csv_line(&row))
                        .and_then(|()| f.flush())
                        .with_context(|| format!("cannot write {}", path.display()))?;
                }
                let mut d = done.lock().expect("no panic holds the lock");
                *d += 1;
                let line = format!(
                    "[{}/{}] #{} {} : {} ({:.1} s)",
                    *d,
                    mine.len(),
                    combo.index,
                    settings(&combo.overrides),
                    note,
                    started.elapsed().as_secs_f64()
                );
                match &bar {
                    Some(b) => {
                        b.println(line);
                        b.inc(1);
                    }
                    None if opts.progress => eprintln!("{line}"),
                    None => {}
                }
                Ok(())
            })
        });
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        result?;
        Ok(SweepOutcome {
            path,
            grid: self.combos.len(),
            runs: mine.len(),
            failed: failed.into_inner().expect("no panic holds the lock"),
            stopped: stopped.into_inner().expect("no panic holds the lock"),
        })
    }
}

fn progress_bar(wanted: bool, len: usize) -> Option<indicatif::ProgressBar> {
    if !wanted || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} runs, eta {eta}",
        )
        .expect("the template is valid")
        .progress_chars("=> "),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(500));
    Some(bar)
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    let msg = p
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    let mut s = String::new();
    let _ = write!(s, "panic: {msg}");
    s
}

/// Writes a merged table to `dir/sweep.csv` (atomically) and returns the path.
pub fn write_merged(table: &SweepTable, dir: &Path) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let path = dir.join(file_name(Shard::ALL));
    write_atomic(&path, table.to_csv().as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vary(arg: &str) -> Vary {
        arg.parse().unwrap()
    }

    #[test]
    fn vary_parses_a_list() {
        let v = vary("discretisation.links_per_turn=8, 16,32");
        assert_eq!(v.key, "discretisation.links_per_turn");
        let raws: Vec<&str> = v.values.iter().map(|o| o.raw.as_str()).collect();
        assert_eq!(raws, ["8", "16", "32"]);
        assert_eq!(v.values[1].value, toml::Value::Integer(16));
        assert!("a=1,,2".parse::<Vary>().is_err());
        assert!("a".parse::<Vary>().is_err());
    }

    #[test]
    fn grid_is_the_product_last_key_fastest() {
        let g = grid(&[vary("a=1,2"), vary("b=x,y,z")]);
        assert_eq!(g.len(), 6);
        let s: Vec<String> = g.iter().map(|c| settings(&c.overrides)).collect();
        assert_eq!(s[0], "a=1 b=x");
        assert_eq!(s[1], "a=1 b=y");
        assert_eq!(s[3], "a=2 b=x");
        assert_eq!(s[5], "a=2 b=z");
        assert!(g.iter().enumerate().all(|(i, c)| c.index == i));
        assert_eq!(grid(&[]).len(), 1);
    }

    #[test]
    fn shards_partition_the_grid() {
        for n in 1..=7 {
            for len in [0, 1, 5, 6, 7, 23] {
                let mut count = vec![0; len];
                for k in 1..=n {
                    let s: Shard = format!("{k}/{n}").parse().unwrap();
                    for (i, c) in count.iter_mut().enumerate() {
                        if s.contains(i) {
                            *c += 1;
                        }
                    }
                }
                assert!(
                    count.iter().all(|&c| c == 1),
                    "n = {n}, len = {len}: {count:?}"
                );
            }
        }
        for bad in ["0/3", "4/3", "3", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn csv_cells_round_trip() {
        let cells: Vec<String> = ["a", "b,c", "say \"hi\"", "", "failed: x, y"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        assert_eq!(split_csv_line(&csv_line(&cells)), cells);
    }

    #[test]
    fn max_abs_needs_every_milestone() {
        assert_eq!(
            max_abs([Some(-0.2), Some(0.1)].into_iter()),
            Some(0.2_f64.abs())
        );
        assert_eq!(max_abs([Some(0.1), None].into_iter()), None);
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn merge_sorts_by_index_and_refuses_mismatches() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = write(d, "a.csv", "index,k,status\n2,x,ok\n0,y,\"failed: a, b\"\n");
        let b = write(d, "b.csv", "index,k,status\n1,z,ok\n");
        let m = merge(&[a.clone(), b.clone()]).unwrap();
        let idx: Vec<&str> = m.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(idx, ["0", "1", "2"]);
        assert_eq!(m.rows[0][2], "failed: a, b");
        let out = write_merged(&m, &d.join("out")).unwrap();
        assert_eq!(SweepTable::read(&out).unwrap(), m);

        let other = write(d, "c.csv", "index,j,status\n3,z,ok\n");
        let e = merge(&[a.clone(), other]).unwrap_err().to_string();
        assert!(e.contains("its columns differ"), "{e}");
        let e = merge(&[a.clone(), b, a]).unwrap_err().to_string();
        assert!(e.contains("combination 2 is in both"), "{e}");
        let short = write(d, "d.csv", "index,k,status\n4,z\n");
        let e = merge(&[short]).unwrap_err().to_string();
        assert!(e.contains("line 2: 2 cells, the header has 3"), "{e}");
    }

    #[test]
    fn a_bad_value_stops_the_sweep_before_it_runs() {
        let text = include_str!("../../scenes/yoga-mat.toml");
        let e = Sweep::new(text, "y", &[vary("discretisation.links_per_turn=16,5000")])
            .err()
            .expect("5000 links per turn is invalid")
            .to_string();
        assert_eq!(
            e,
            "combination 1 (discretisation.links_per_turn=5000): \
             discretisation.links_per_turn = 5000: must be >= 3 and <= 4096"
        );
    }
}
