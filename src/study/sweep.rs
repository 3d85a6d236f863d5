//! Parameter sweeps: the product grid of `--vary KEY=V1,V2,...` over a scene, run in
//! parallel (rayon), one row per finished run appended and flushed to `sweep.csv`, shards
//! (`K/N`) for batch schedulers and the merge of shard files. It does no physics and draws
//! nothing: each run is [`run_until`] (with the sweep's stop flag) on a scene built by
//! [`scene_with_overrides`](crate::scene::overrides::scene_with_overrides); reports are in
//! [`analysis`](crate::study::analysis) and [`plot`](crate::study::plot).
//!
//! This file runs the sweep; the grid and its shards are in `grid`, the columns and cells
//! of a row in `row`, the CSV text, the table and the merge in `table`.

mod grid;
mod row;
mod table;
mod vary;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{IsTerminal, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::Context as _;
use rayon::prelude::*;

pub use self::grid::{
    Combination, CombinationError, GridFile, Shard, Vary, file_name, grid, scenes,
};
pub use self::row::{
    Col, ERR_EQ7_PREFIX, ERR_GEO_PREFIX, INDEX_COLUMN, RowStatus, STATUS_COLUMN, T_SIM_PREFIX,
    header, result_cells, result_columns,
};
pub use self::table::{Merged, Missing, NotOneSweep, SweepTable, csv_line, merge, write_merged};

use self::grid::settings;
use self::row::one_line;
use crate::output::files::{RunFiles, View};
use crate::run::{RunReport, milestone_radii, run_until, run_until_with};
use crate::scene::Scene;
use crate::theory::References;

/// What a sweep did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepOutcome {
    /// The file written.
    pub path: PathBuf,
    /// Combinations in the whole grid.
    pub grid: usize,
    /// Runs in this shard.
    pub runs: usize,
    /// Rows written this time: `runs`, less those a signal kept from starting.
    pub written: usize,
    /// Runs a signal stopped (`interrupted`).
    pub interrupted: usize,
    /// Rows kept from the shard's file by `--resume` (not run again).
    pub kept: usize,
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
    /// Once set, runs that have not started are skipped and running ones stop (status
    /// `interrupted`).
    pub stop: Arc<AtomicBool>,
    /// Keep the rows of this shard's existing file whose run ended by itself (`ok`,
    /// `max_time`, `stopped: ...`: a rerun would give the same, the runs being
    /// deterministic) and run only the others (`interrupted`, `failed: ...`, or no row).
    pub resume: bool,
    /// Each run's own files (`samples.csv`, `report.json`, and with [`View::File`] its
    /// `run.mcap`) in `DIR/`[`run_folder`]`(index)`, as `uncoil run` writes them; `None`:
    /// the rows alone.
    pub run_files: Option<View>,
}

/// The folder a sweep that keeps its runs' files writes run `index` into, inside its own.
pub fn run_folder(index: usize) -> String {
    format!("run-{index}")
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            shard: Shard::ALL,
            jobs: None,
            progress: true,
            stop: Arc::new(AtomicBool::new(false)),
            resume: false,
            run_files: None,
        }
    }
}

/// A sweep ready to run: the grid, validated (every combination's scene built).
pub struct Sweep {
    keys: Vec<String>,
    combos: Vec<Combination>,
    scenes: Vec<Scene>,
    /// The grid as its files state it (its shard set by each run).
    grid: GridFile,
}

impl Sweep {
    /// Builds the grid of `varies` over scene `text` and validates every combination.
    pub fn new(text: &str, name: &str, varies: &[Vary]) -> Result<Self, CombinationError> {
        let combos = grid(varies);
        let scenes = scenes(text, name, &combos)?;
        Ok(Self {
            keys: varies.iter().flat_map(|v| v.keys.iter().cloned()).collect(),
            combos,
            scenes,
            grid: GridFile::new(text, name, varies, Shard::ALL),
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
    /// run ends, and at the end puts the rows in the grid's order whatever the runs' order
    /// ([`in_grid_order`]). A run that fails or panics gets a `failed: ...` row; the sweep
    /// goes on.
    pub fn run(&self, dir: &Path, opts: &SweepOptions) -> anyhow::Result<SweepOutcome> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create output folder {}", dir.display()))?;
        let path = dir.join(file_name(opts.shard));
        // Every milestone any combination has, in the order first met: a core changes them
        // (laid fractions instead of radii).
        let mut labels: Vec<String> = Vec::new();
        for l in self.scenes.iter().flat_map(milestone_radii) {
            let l = l.0.to_string();
            if !labels.contains(&l) {
                labels.push(l);
            }
        }
        let header = header(&self.keys, &labels);
        let grid = self.grid.clone().for_shard(opts.shard);
        let grid_path = GridFile::beside(&path);
        if opts.resume && grid_path.exists() {
            let theirs = read_grid(&grid_path)?;
            if !theirs.same_grid(&grid) {
                return Err(NotOneSweep(format!(
                    "{} is of another grid ({}; the file's first, this sweep's second): --resume \
                     continues only the sweep that wrote it (remove it to start again)",
                    path.display(),
                    theirs.difference(&grid)
                ))
                .into());
            }
        }
        let kept = if opts.resume && path.exists() {
            finished_rows(&path, &header)?
        } else {
            BTreeMap::new()
        };
        let grid_text = serde_json::to_string_pretty(&grid).context("cannot write the grid")?;
        crate::output::write_atomic(&grid_path, grid_text.as_bytes())?;
        let file = start_file(&path, &header, kept.values())?;

        let mine: Vec<usize> = (0..self.combos.len())
            .filter(|&i| opts.shard.contains(i) && !kept.contains_key(&i))
            .collect();
        let pool = worker_pool(opts.jobs)?;
        let runner = Runner {
            sweep: self,
            dir,
            run_files: opts.run_files,
            path: &path,
            header: &header,
            labels: &labels,
            file: Mutex::new(file),
            jobs: pool.current_num_threads(),
            total: mine.len(),
            bar: progress_bar(opts.progress, mine.len()),
            progress: opts.progress,
            done: Mutex::new(0),
            failed: Mutex::new(0),
            stopped: Mutex::new(0),
            interrupted: Mutex::new(0),
            stop: &opts.stop,
        };
        let result: anyhow::Result<()> = if runner.jobs == 1 {
            runner.run_in_turn(&mine)
        } else {
            pool.install(|| mine.par_iter().try_for_each(|&i| runner.run_one(i, None)))
        };
        let Runner {
            bar,
            done,
            failed,
            stopped,
            interrupted,
            ..
        } = runner;
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        result?;
        in_grid_order(&path)?;
        Ok(SweepOutcome {
            path,
            grid: self.combos.len(),
            runs: mine.len(),
            written: done.into_inner().expect("no panic holds the lock"),
            interrupted: interrupted.into_inner().expect("no panic holds the lock"),
            kept: kept.len(),
            failed: failed.into_inner().expect("no panic holds the lock"),
            stopped: stopped.into_inner().expect("no panic holds the lock"),
        })
    }
}

/// Reads the grid a sweep's file states (see [`GridFile`]).
pub fn read_grid(path: &Path) -> anyhow::Result<GridFile> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not a sweep's grid", path.display()))
}

/// Rewrites the sweep file at `path` (atomically) with its rows in the grid's order, by
/// their index; a file already in order is left as it is. Rows are appended as runs end,
/// so that a killed sweep keeps every finished one; this orders them once all have ended.
pub fn in_grid_order(path: &Path) -> anyhow::Result<()> {
    let mut table = SweepTable::read(path)?;
    let index = |row: &Vec<String>| row.first().and_then(|i| i.parse::<usize>().ok());
    if table.rows.is_sorted_by_key(index) {
        return Ok(());
    }
    table.rows.sort_by_key(index);
    let mut text = csv_line(&table.header) + "\n";
    for row in &table.rows {
        text.push_str(&csv_line(row));
        text.push('\n');
    }
    crate::output::write_atomic(path, text.as_bytes())
}

/// Creates `path` and writes the header line and the `kept` rows, flushed.
fn start_file<'a>(
    path: &Path,
    header: &[String],
    kept: impl Iterator<Item = &'a Vec<String>>,
) -> anyhow::Result<File> {
    let mut file =
        File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut text = csv_line(header) + "\n";
    for row in kept {
        text.push_str(&csv_line(row));
        text.push('\n');
    }
    file.write_all(text.as_bytes())
        .and_then(|()| file.flush())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(file)
}

/// The rows of the shard file at `path` whose run ended by itself, by combination index (a
/// last row cut mid-row is left out). The file must be of this sweep: its header `header`.
fn finished_rows(path: &Path, header: &[String]) -> anyhow::Result<BTreeMap<usize, Vec<String>>> {
    let (table, _) = SweepTable::read_cut(path)?;
    if table.header != header {
        return Err(NotOneSweep(format!(
            "{}: its columns are not this sweep's: it cannot be resumed (remove it to start again)",
            path.display()
        ))
        .into());
    }
    let status = table.column(STATUS_COLUMN).expect("the header has it");
    Ok(table
        .rows
        .into_iter()
        .filter(|r| {
            r[status].parse::<RowStatus>().is_ok_and(|s| {
                matches!(
                    s,
                    RowStatus::Ok | RowStatus::MaxTime | RowStatus::Stopped(_)
                )
            })
        })
        .filter_map(|r| Some((r[0].parse().ok()?, r)))
        .collect())
}

/// The worker threads: `jobs` of them, or one per core.
fn worker_pool(jobs: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(j) = jobs {
        b = b.num_threads(j);
    }
    b.build().context("cannot start the worker threads")
}

/// What the worker threads share while a sweep runs: the output file, the progress and
/// the counts.
struct Runner<'a> {
    sweep: &'a Sweep,
    /// The sweep's folder.
    dir: &'a Path,
    /// Each run's own files, if kept ([`SweepOptions::run_files`]).
    run_files: Option<View>,
    path: &'a Path,
    header: &'a [String],
    /// The milestones' labels the header's error columns are for.
    labels: &'a [String],
    file: Mutex<File>,
    /// Worker threads, recorded in each row.
    jobs: usize,
    /// Runs in this shard.
    total: usize,
    bar: Option<indicatif::ProgressBar>,
    progress: bool,
    done: Mutex<usize>,
    interrupted: Mutex<usize>,
    failed: Mutex<usize>,
    stopped: Mutex<usize>,
    stop: &'a AtomicBool,
}

impl Runner<'_> {
    /// Runs the combinations `mine` one at a time, each one's references tabulated on a
    /// thread of their own while the run before it steps: the second core, idle otherwise,
    /// takes the one part of a run that does not depend on the run before.
    fn run_in_turn(&self, mine: &[usize]) -> anyhow::Result<()> {
        let scenes = &self.sweep.scenes;
        std::thread::scope(|s| {
            let tabulate = |i: usize| s.spawn(move || Arc::new(References::new(&scenes[i])));
            let mut ahead = mine.first().map(|&i| tabulate(i));
            let mut result = Ok(());
            for (k, &i) in mine.iter().enumerate() {
                if self.stop.load(Ordering::SeqCst) {
                    break;
                }
                // A tabulation that panicked is redone in the run, which reports it.
                let refs = ahead.take().and_then(|t| t.join().ok());
                ahead = mine.get(k + 1).map(|&j| tabulate(j));
                result = self.run_one(i, refs);
                if result.is_err() {
                    break;
                }
            }
            // A tabulation left over (stopped, or an error) is waited for here, and a panic
            // in it is not the sweep's.
            if let Some(t) = ahead {
                let _ = t.join();
            }
            result
        })
    }

    /// Runs combination `i` (with its references, if already built), appends its row and
    /// reports it.
    fn run_one(&self, i: usize, refs: Option<Arc<References>>) -> anyhow::Result<()> {
        if self.stop.load(Ordering::SeqCst) {
            return Ok(());
        }
        let combo = &self.sweep.combos[i];
        let scene = &self.sweep.scenes[i];
        let started = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| match (self.run_files, refs) {
            (Some(view), refs) => {
                let dir = self.dir.join(run_folder(combo.index));
                RunFiles::take(&dir, scene, view)?.run_with(scene, refs, None, self.stop)
            }
            (None, Some(refs)) => run_until_with(scene, refs, &mut [], self.stop),
            (None, None) => run_until(scene, &mut [], self.stop),
        }));
        let result = match outcome {
            Ok(Ok(report)) => Ok(report),
            Ok(Err(e)) => Err(format!("{e:#}")),
            Err(p) => Err(panic_text(p.as_ref())),
        };
        let mut row = vec![combo.index.to_string()];
        row.extend(combo.overrides.iter().map(|o| o.raw.clone()));
        let note = match &result {
            Ok(report) => self.finished_row(&mut row, report),
            Err(e) => self.failed_row(&mut row, e),
        };
        {
            let mut f = self.file.lock().expect("no panic holds the lock");
            writeln!(f, "{}", csv_line(&row))
                .and_then(|()| f.flush())
                .with_context(|| format!("cannot write {}", self.path.display()))?;
        }
        self.print_progress(combo, &note, started);
        Ok(())
    }

    /// Completes the row of a run that ended and returns its progress note.
    fn finished_row(&self, row: &mut Vec<String>, report: &RunReport) -> String {
        row.extend(result_cells(report, self.jobs, self.labels));
        if report.stop.guard().is_some() {
            *self.stopped.lock().expect("no panic holds the lock") += 1;
        }
        if report.stop.status() == crate::run::stop::Status::Interrupted {
            *self.interrupted.lock().expect("no panic holds the lock") += 1;
        }
        let status = row.last().cloned().unwrap_or_default();
        let err = report
            .milestones
            .iter()
            .filter_map(|m| m.err_vs_geo)
            .map(f64::abs)
            .reduce(f64::max);
        let wall = if report.ledger.bang_time_s.is_some() {
            format!("{:.3} s wall to the bang", report.wall_time_rolling_s)
        } else {
            format!("{:.3} s wall, no bang", report.wall_time_s)
        };
        let err = err.map_or_else(
            || "no milestone reached".to_owned(),
            |e| format!("max |err vs exact| {:.3}%", 100.0 * e),
        );
        format!("{status}, {wall}, {err}")
    }

    /// Completes the row of a run that failed with `e` (empty result cells, a `failed: ...`
    /// status) and returns its progress note.
    fn failed_row(&self, row: &mut Vec<String>, e: &str) -> String {
        *self.failed.lock().expect("no panic holds the lock") += 1;
        let n = self.header.len() - row.len() - 1;
        row.extend(std::iter::repeat_n(String::new(), n));
        let msg = RowStatus::Failed(one_line(e)).to_string();
        row.push(msg.clone());
        msg
    }

    /// One progress line for a finished run, on the bar or on stderr.
    fn print_progress(&self, combo: &Combination, note: &str, started: Instant) {
        let mut d = self.done.lock().expect("no panic holds the lock");
        *d += 1;
        let line = format!(
            "[{}/{}] #{} {} : {} ({:.1} s)",
            *d,
            self.total,
            combo.index,
            settings(&combo.overrides),
            note,
            started.elapsed().as_secs_f64()
        );
        match &self.bar {
            Some(b) => {
                b.println(line);
                b.inc(1);
            }
            None if self.progress => eprintln!("{line}"),
            None => {}
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_value_stops_the_sweep_before_it_runs() {
        let text = include_str!("../../scenes/yoga-mat.toml");
        let vary: Vary = "discretisation.links_per_turn=16,5000".parse().unwrap();
        let e = Sweep::new(text, "y", &[vary])
            .err()
            .expect("5000 links per turn is invalid")
            .to_string();
        assert_eq!(
            e,
            "combination 1 (discretisation.links_per_turn=5000): \
             discretisation.links_per_turn = 5000: must be >= 3 and <= 4096"
        );
    }

    /// Rows written as runs ended (2, 0, 1) come back in the grid's order; a file already in
    /// order is not rewritten.
    #[test]
    fn rows_are_put_in_the_grid_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sweep.csv");
        std::fs::write(
            &path,
            "index,x,status\n2,c,ok\n0,\"a,b\",ok\n1,b,failed: x\n",
        )
        .unwrap();
        in_grid_order(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "index,x,status\n0,\"a,b\",ok\n1,b,failed: x\n2,c,ok\n"
        );
        let before = std::fs::metadata(&path).unwrap().modified().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        in_grid_order(&path).unwrap();
        assert_eq!(
            std::fs::metadata(&path).unwrap().modified().unwrap(),
            before
        );
    }
}
