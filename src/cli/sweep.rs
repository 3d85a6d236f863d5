//! The `sweep` and `sweep-report` subcommands of the binary: arguments, output folders and
//! messages around [`uncoil::study::sweep`], [`uncoil::study::analysis`] and
//! [`uncoil::study::plot`]; their exits are [`Exit`]'s. No sweep logic lives here.

use std::path::{Path, PathBuf};

use crate::cli::exit::{Exit, Usage};
use crate::cli::paths::{self, PathError};

use clap::{Args, ValueEnum};

use uncoil::output::files::View;
use uncoil::output::folder::{LOG, REPORT, SAMPLES};
use uncoil::output::{shell_word, write_atomic};
use uncoil::run::signals;
use uncoil::scene::overrides::{Override, scene_with_overrides};
use uncoil::scene::read_scene_file;
use uncoil::scene::shipped;
use uncoil::study::analysis::{Ensemble, Reference, SweepAnalysis};
use uncoil::study::sweep::{
    Col, GridFile, Shard, Sweep, SweepOptions, SweepOutcome, SweepTable, Vary, merge, read_grid,
    run_folder, write_merged,
};

/// Arguments of `uncoil sweep`.
#[derive(Args)]
pub struct SweepArgs {
    /// The coil's scene to vary: a scene file (TOML), e.g. scenes/yoga-mat.toml, or a
    /// shipped scene's name, e.g. yoga-mat.
    #[arg(required_unless_present = "merge")]
    scene: Option<PathBuf>,
    /// A key and its values, e.g. `--vary discretisation.links_per_turn=16,32,64`; an even
    /// range, `A..B/N` (N values from A to B), e.g. `push.contact_speed_m_s=0.100..0.107/8`;
    /// or keys varied together, their values side by side, e.g.
    /// `tape.thickness_m:solver.bang_piece_m=0.003:0.015,0.001:0.005`. Several give the
    /// product grid (the last varies fastest). One value fixes a key.
    #[arg(long = "vary", value_name = "KEY=V1,V2,...")]
    vary: Vec<Vary>,
    /// Run only the K-th of N interleaved slices of the grid (for array jobs), into
    /// sweep.K-of-N.csv.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Runs at once (default: one per core). Wall times are per run, so runs sharing the
    /// cores slow each other down: use --jobs 1 for timings.
    #[arg(long, value_parser = parse_jobs)]
    jobs: Option<usize>,
    /// Output folder (default: sweeps/<scene name>; with --merge, the first file's folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// No progress on stderr.
    #[arg(long)]
    quiet: bool,
    /// Keep the rows of this shard's existing file whose run ended by itself (ok, max_time,
    /// stopped) and run only the rest (interrupted, failed, or missing): a task that hit its
    /// time limit goes on where it stopped.
    #[arg(long)]
    resume: bool,
    /// Join shard files (sweep.K-of-N.csv) into OUT/sweep.csv instead of running. A shard
    /// not given, a combination in no file or a file cut mid-row is an error (exit 1,
    /// nothing written) unless --allow-partial.
    #[arg(long, num_args = 1.., value_name = "FILES", conflicts_with_all = ["scene", "vary", "shard", "jobs"])]
    merge: Vec<PathBuf>,
    /// With --merge: write what the files hold even if some is missing, and say what is
    /// missing on stdout and in OUT/sweep.missing.txt.
    #[arg(long, requires = "merge")]
    allow_partial: bool,
}

/// Which error a report uses.
#[derive(Clone, Copy, ValueEnum)]
enum RefArg {
    /// The exact-geometry model: the simulation's own error.
    Exact,
    /// The continuum eq. (7).
    Eq7,
}

/// Which wall time is the cost.
#[derive(Clone, Copy, ValueEnum)]
enum CostArg {
    /// The unroll, up to the final bang (`wall_rolling_s`).
    Unroll,
    /// The whole run, bang included (`wall_s`).
    Total,
}

/// Arguments of `uncoil sweep-report`.
#[derive(Args)]
pub struct ReportArgs {
    /// A sweep's folder (with its sweep.csv), e.g. sweeps/yoga-mat, or a sweep file.
    sweep: PathBuf,
    /// Output folder for report.md and the SVGs (default: the sweep file's folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The error's reference.
    #[arg(long, value_enum, default_value = "exact")]
    reference: RefArg,
    /// The wall time used as the cost.
    #[arg(long, value_enum, default_value = "unroll")]
    cost: CostArg,
    /// Title of the report and plots (default: the name of the sweep's folder).
    #[arg(long)]
    title: Option<String>,
    /// Fit convergence only in these varied keys (repeatable; default: every numeric one).
    #[arg(long, value_name = "KEY", conflicts_with = "no_convergence")]
    converge: Vec<String>,
    /// A target to mark and report: the largest error (a fraction, e.g. 0.003) and the
    /// largest wall time in s, e.g. `--target 0.003,0.3`.
    #[arg(long, value_name = "ERROR,WALL_S", value_parser = parse_target)]
    target: Option<(f64, f64)>,
    /// A varied key whose values are repetitions (e.g. `--vary name=rep1,rep2,rep3`): runs
    /// that differ only in it are pooled as one setting's ensemble (repeatable). Default:
    /// push.contact_speed_m_s, the pushes of an ensemble (a sweep of the pushes alone is one
    /// ensemble); `none` pools nothing, each run its own row.
    #[arg(long, value_name = "KEY")]
    repeat_key: Vec<String>,
    /// No convergence fits or plots: the Pareto plot and the table only.
    #[arg(long)]
    no_convergence: bool,
}

/// Whether two values of a key are one: equal, or the same number (`1` and `1.0`).
fn same(a: &toml::Value, b: &toml::Value) -> bool {
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    match (number(a), number(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// `n` things, `thing` in the singular or the plural as `n` asks.
fn counted(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}

fn parse_jobs(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("`{s}`: runs at once, a whole number >= 1")),
    }
}

fn parse_target(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("`{s}`: expected ERROR,WALL_S with both > 0, e.g. 0.003,0.3");
    let (e, w) = s.split_once(',').ok_or_else(bad)?;
    let e: f64 = e.trim().parse().map_err(|_| bad())?;
    let w: f64 = w.trim().parse().map_err(|_| bad())?;
    if e > 0.0 && w > 0.0 && e.is_finite() && w.is_finite() {
        Ok((e, w))
    } else {
        Err(bad())
    }
}

fn folder_of(p: &Path) -> PathBuf {
    p.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// `uncoil sweep --merge`: 0 merged (whole, or partial with `--allow-partial`), 1 a file
/// could not be read or written, or something is missing without `--allow-partial`, 2 a
/// path that is not a sweep file, files that are not of one sweep.
fn merge_command(files: &[PathBuf], dir: &Path, allow_partial: bool) -> anyhow::Result<Exit> {
    for file in files {
        paths::sweep_csv(
            file,
            "a sweep's shard file, e.g. sweeps/big/sweep.1-of-8.csv",
        )?;
    }
    paths::out_folder(dir)?;
    let merged = merge(files)?;
    let (table, missing) = (&merged.table, &merged.missing);
    let note = dir.join("sweep.missing.txt");
    if !missing.is_empty() && !allow_partial {
        eprint!(
            "error: the merge is incomplete, nothing written (--allow-partial to write it):\n{missing}"
        );
        return Ok(Exit::Failed);
    }
    let p = write_merged(&merged, dir)?;
    if missing.is_empty() {
        uncoil::output::remove_stale(&note)?;
    } else {
        uncoil::output::write_atomic(&note, missing.to_string().as_bytes())?;
    }
    println!(
        "merged {} into {}",
        counted(table.rows.len(), "run"),
        p.display()
    );
    if !missing.is_empty() {
        print!("partial, as {} says:\n{missing}", note.display());
    }
    println!(
        "draw its report with: uncoil sweep-report {}",
        shell_word(dir)
    );
    Ok(Exit::Ok)
}

/// `uncoil sweep`: 0 every run ended, 1 a run failed or a file could not be written,
/// 2 bad input (a scene or a path missing or of the wrong kind, a combination's scene
/// invalid; files that are not of one sweep, to merge or resume), 3 a guard stopped a run
/// (and none failed), 130, 143 or 129 a signal stopped it (SIGINT, SIGTERM, SIGHUP: the
/// runs in progress are rows marked `interrupted`, which `--resume` runs again).
pub fn sweep(args: SweepArgs) -> anyhow::Result<Exit> {
    sweep_keeping(args, None)
}

/// [`sweep`], each run's own files kept in its folder if `run_files` says so
/// ([`SweepOptions::run_files`]).
fn sweep_keeping(args: SweepArgs, run_files: Option<View>) -> anyhow::Result<Exit> {
    if !args.merge.is_empty() {
        let dir = args.out.unwrap_or_else(|| folder_of(&args.merge[0]));
        return merge_command(&args.merge, &dir, args.allow_partial);
    }
    if args.allow_partial {
        return Err(Usage("--allow-partial goes with --merge FILES".into()).into());
    }
    let scene_path = args.scene.expect("clap requires SCENE without --merge");
    let (text, stem) = read_scene_file(&scene_path)?;
    // The scene itself first, so that its own error is not a combination's.
    if shipped::kind(&text) == "coil" {
        scene_with_overrides(&text, &stem, &[]).map_err(|e| e.in_file(&scene_path))?;
    }
    if shipped::kind(&text) != "coil" {
        return Err(PathError {
            path: scene_path,
            found: "a folded chain's scene".into(),
            expected: "a coil's scene: a sweep varies a coil (`uncoil run` runs a folded \
                       chain, `--set` varies it)"
                .into(),
        }
        .into());
    }
    // A key varied twice would be two columns of one name in sweep.csv, and a grid no merge
    // could check.
    let keys: Vec<&String> = args.vary.iter().flat_map(|v| &v.keys).collect();
    if let Some((_, twice)) = keys
        .iter()
        .enumerate()
        .find(|(k, v)| keys[..*k].contains(v))
    {
        return Err(Usage(format!(
            "--vary {twice}: varied twice; give all its values in one --vary"
        ))
        .into());
    }
    // A value given twice would be two runs of one combination, which no merge takes.
    for v in &args.vary {
        let same_setting =
            |a: &[Override], b: &[Override]| a.iter().zip(b).all(|(x, y)| same(&x.value, &y.value));
        if let Some((_, twice)) = v
            .values
            .iter()
            .enumerate()
            .find(|(k, x)| v.values[..*k].iter().any(|y| same_setting(x, y)))
        {
            return Err(Usage(format!(
                "--vary {}: the value {} is given twice",
                v.name(),
                Vary::raw(twice)
            ))
            .into());
        }
    }
    let sweep = Sweep::new(&text, &stem, &args.vary)?;
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from("sweeps").join(&stem));
    paths::out_folder(&dir)?;
    let opts = SweepOptions {
        shard: args.shard.unwrap_or(Shard::ALL),
        jobs: args.jobs,
        progress: !args.quiet,
        resume: args.resume,
        // A signal stops the runs in progress (their rows say `interrupted`) and starts no
        // other; `--resume` runs them and the rest.
        stop: crate::stop_flag(),
        run_files,
    };
    if opts.progress {
        eprintln!(
            "sweeping {} ({}{}) into {} ...",
            scene_path.display(),
            counted(sweep.len(), "combination"),
            if opts.shard == Shard::ALL {
                String::new()
            } else {
                format!(", shard {}/{}", opts.shard.k, opts.shard.n)
            },
            dir.display()
        );
    }
    let all = opts.shard == Shard::ALL;
    Ok(ended(&sweep.run(&dir, &opts)?, all))
}

/// `uncoil run SCENE --ensemble N`: the scene with its overrides, landed from `n` pushes
/// (its own and those just above it, as the main job's hint spreads them), run as a sweep
/// into `out` (default `runs/<scene>-ensemble`): `sweep.csv`, each run's own files in
/// `run-<index>/` (its `run.mcap` unless `no_mcap`), `report.md`, and `ensemble.csv`, the
/// milestones' times as mean and spread and the bang's every observable as mean and
/// standard error, which it prints. Signals, `--resume` and the exit are the sweep's; a
/// folder that holds another run's or another sweep's files is refused (exit 2).
pub fn ensemble(
    scene: &Path,
    set: &[Override],
    n: usize,
    out: Option<PathBuf>,
    resume: bool,
    no_mcap: bool,
) -> anyhow::Result<Exit> {
    let (text, stem) = read_scene_file(scene)?;
    if shipped::kind(&text) != "coil" {
        return Err(Usage(
            "--ensemble: a folded chain lands the same way from every push; an ensemble is a \
             coil's"
                .into(),
        )
        .into());
    }
    let built = scene_with_overrides(&text, &stem, set).map_err(|e| e.in_file(scene))?;
    let (first, last) = uncoil::output::summary::ensemble_pushes(built.push.contact_speed_m_s, n);
    let mut vary = Vec::new();
    for o in set.iter().filter(|o| o.key != PUSH_KEY) {
        vary.push(format!("{}={}", o.key, o.raw).parse::<Vary>()?);
    }
    vary.push(format!("{PUSH_KEY}={first}..{last}/{n}").parse::<Vary>()?);
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{stem}-ensemble")));
    ensemble_folder(&dir, &GridFile::new(&text, &stem, &vary, Shard::ALL))?;
    let view = if no_mcap { View::Off } else { View::File };
    let exit = sweep_keeping(
        SweepArgs {
            scene: Some(scene.to_path_buf()),
            vary,
            shard: None,
            jobs: None,
            out: Some(dir.clone()),
            quiet: false,
            resume,
            merge: Vec::new(),
            allow_partial: false,
        },
        Some(view),
    )?;
    let csv = dir.join("sweep.csv");
    if signals::received().is_none() && csv.exists() {
        let args = ReportArgs {
            sweep: csv.clone(),
            out: None,
            reference: RefArg::Exact,
            cost: CostArg::Unroll,
            title: None,
            converge: Vec::new(),
            target: None,
            repeat_key: Vec::new(),
            no_convergence: true,
        };
        write_report(&args, &csv)?;
        let pooled = Ensemble::new(&SweepTable::read(&csv)?);
        write_atomic(&dir.join(ENSEMBLE_CSV), pooled.csv().as_bytes())?;
        print!("{}", pooled.summary(&first, &last));
        println!(
            "Each run's files: {} and on, one folder a push (`uncoil plot` draws one); the \
             table above: {}; the report: {}",
            shell_word(&dir.join(run_folder(0))),
            shell_word(&dir.join(ENSEMBLE_CSV)),
            shell_word(&dir.join("report.md"))
        );
    }
    Ok(exit)
}

/// The pooled table an ensemble writes beside its `sweep.csv`.
const ENSEMBLE_CSV: &str = "ensemble.csv";

/// An ensemble's folder `dir` is new, or holds only files of the ensemble `grid` (an
/// earlier call's, which it runs again, or with `--resume` continues): a run's files, or a
/// sweep's of another grid, would be read as this ensemble's.
fn ensemble_folder(dir: &Path, grid: &GridFile) -> Result<(), PathError> {
    paths::out_folder(dir)?;
    let expected = "an ensemble's folder: new, or one an earlier `--ensemble` of the same \
                    scene, overrides and N wrote";
    let refuse = |found: String| Err(PathError::new(dir, found, expected));
    if let Some(name) = [REPORT, SAMPLES, LOG]
        .into_iter()
        .find(|f| dir.join(f).exists())
    {
        return refuse(format!("a run's files ({name})"));
    }
    let csv = dir.join("sweep.csv");
    let grid_path = GridFile::beside(&csv);
    if grid_path.exists() {
        return match read_grid(&grid_path) {
            Ok(theirs) if theirs.same_grid(grid) => Ok(()),
            Ok(theirs) => refuse(format!(
                "another sweep's files ({}; theirs first, this ensemble's second)",
                theirs.difference(grid)
            )),
            Err(_) => refuse("a sweep.grid.json that is not a sweep's grid".into()),
        };
    }
    if csv.exists() {
        return refuse("a sweep.csv with no grid beside it".into());
    }
    Ok(())
}

/// What a sweep's end prints, and its exit (see [`sweep`]); `all` says whether it ran the
/// whole grid (a shard's file is merged before its report is drawn).
fn ended(o: &SweepOutcome, all: bool) -> Exit {
    let kept = if o.kept > 0 {
        format!(", {} kept from before", o.kept)
    } else {
        String::new()
    };
    let ran = if o.written == o.runs {
        counted(o.runs, "run")
    } else {
        format!("{} of {}", o.written, counted(o.runs, "run"))
    };
    let interrupted = if o.interrupted > 0 {
        format!(", {} interrupted", o.interrupted)
    } else {
        String::new()
    };
    println!(
        "{ran} ({} failed, {} stopped by a guard{interrupted}{kept}) of {} written to {}",
        o.failed,
        o.stopped,
        counted(o.grid, "combination"),
        o.path.display()
    );
    if let Some(signal) = signals::received() {
        eprintln!(
            "interrupted by {signal}: the runs it stopped are rows marked interrupted; \
             the same command with --resume runs them and the rest"
        );
    } else {
        let dir = folder_of(&o.path);
        if all {
            println!(
                "draw its report with: uncoil sweep-report {}",
                shell_word(&dir)
            );
        } else {
            println!(
                "once every shard has run, join them with: uncoil sweep --merge \
                 {}/sweep.*-of-*.csv",
                shell_word(&dir)
            );
        }
    }
    Exit::of_sweep(o)
}

/// `uncoil sweep-report`: 0 written, 1 a file could not be read or written, 2 a path that
/// is not a sweep's folder or file.
pub fn report(args: &ReportArgs) -> anyhow::Result<Exit> {
    let sweep = paths::sweep_file(&args.sweep)?;
    let name = sweep.file_name().unwrap_or_default().to_string_lossy();
    if name.contains("-of-") {
        eprintln!(
            "note: {} is one shard's file; the whole sweep's report needs them joined first: \
             uncoil sweep --merge FILES",
            sweep.display()
        );
    }
    if let Some(out) = &args.out {
        paths::out_folder(out)?;
    }
    print!("{}", write_report(args, &sweep)?);
    Ok(Exit::Ok)
}

/// The key whose values are an ensemble's pushes, pooled by default.
const PUSH_KEY: &str = "push.contact_speed_m_s";

/// The keys pooled as repetitions: those given (`none`: no key), or by default the pushes
/// (a sweep of the pushes alone is one ensemble).
fn repeat_keys(given: &[String], varied: &[String]) -> anyhow::Result<Vec<String>> {
    if given.iter().any(|k| k == "none") {
        if given.len() > 1 {
            anyhow::bail!(Usage(
                "--repeat-key none: no key is a repetition; give it alone".into()
            ));
        }
        return Ok(Vec::new());
    }
    if let Some(k) = given.iter().find(|k| !varied.contains(k)) {
        anyhow::bail!(Usage(format!(
            "--repeat-key {k}: not a varied key of this sweep (varied: {})",
            varied.join(", ")
        )));
    }
    if given.is_empty() && varied.iter().any(|k| k == PUSH_KEY) {
        return Ok(vec![PUSH_KEY.to_owned()]);
    }
    Ok(given.to_vec())
}

fn write_report(args: &ReportArgs, sweep: &Path) -> anyhow::Result<String> {
    let table = SweepTable::read(sweep)?;
    let reference = match args.reference {
        RefArg::Exact => Reference::Exact,
        RefArg::Eq7 => Reference::Eq7,
    };
    let cost = match args.cost {
        CostArg::Unroll => Col::WallRolling.name(),
        CostArg::Total => Col::Wall.name(),
    };
    let dir = args.out.clone().unwrap_or_else(|| folder_of(sweep));
    let title = args.title.clone().unwrap_or_else(|| {
        std::fs::canonicalize(folder_of(sweep))
            .ok()
            .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "sweep".into())
    });
    let varied = table.varied_keys();
    let repeats = repeat_keys(&args.repeat_key, &varied)?;
    let mut analysis = SweepAnalysis::new(table, reference, cost, &repeats)?;
    analysis.target = args.target;
    if args.no_convergence {
        analysis.studies.clear();
    } else if !args.converge.is_empty() {
        let varied = analysis.table.varied_keys();
        if let Some(k) = args.converge.iter().find(|k| !varied.contains(k)) {
            anyhow::bail!(Usage(format!(
                "--converge {k}: not a varied key of this sweep (varied: {})",
                varied.join(", ")
            )));
        }
        analysis.studies.retain(|s| args.converge.contains(&s.key));
    }
    let files = uncoil::study::plot::plot_sweep(&analysis, &dir, &title)?;
    let mut md = analysis.markdown(&title);
    md.push_str("\nPlots: ");
    md.push_str(
        &files
            .iter()
            .map(|f| {
                let name = f.file_name().unwrap_or_default().to_string_lossy();
                format!("[{name}]({name})")
            })
            .collect::<Vec<_>>()
            .join(", "),
    );
    md.push('\n');
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    Ok(md)
}
