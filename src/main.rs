//! The `uncoil` command line: `uncoil run SCENE [--out DIR] [--set KEY=VALUE]... [--no-mcap]
//! [--live [ADDR] [--pace X]]`,
//! `uncoil inspect RUN.mcap`, `uncoil check`, `uncoil compare`, `uncoil sweep`,
//! `uncoil sweep-report`, `uncoil plot`, `uncoil scenes`.
//!
//! Results go to stdout, diagnostics to stderr. Exit codes (`cli/exit.rs`): 0 success, 1 a
//! failure during the work (e.g. an output file could not be written), 2 bad input (a scene,
//! an argument, a path missing or of the wrong kind), 3 a guard stopped the run (a blow-up: its reason is on stderr and in
//! `report.json`, and the outputs hold everything logged up to the stop), 130, 143 or 129 a
//! run stopped by SIGINT (Ctrl-C), SIGTERM or SIGHUP (its outputs are complete up to
//! there, the signal named).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use anyhow::Context as _;
use clap::{Parser, Subcommand};

use uncoil::output::compare::{SampleLog, table};
use uncoil::output::files::{self, RunFiles};
use uncoil::output::folded::{chain_summary, take_folder, write_chain_run};
use uncoil::output::summary;
use uncoil::output::view::ViewObserver;
use uncoil::run::run;
use uncoil::run::stop::{Status, StopReason};
use uncoil::scene::folded::FoldedChain;
use uncoil::scene::overrides::{Override, any_scene_file_with_overrides};
use uncoil::scene::{AnyScene, Scene, shipped};
use uncoil::study::check;

/// What a scene argument takes, in every command's help.
const SCENE_HELP: &str = "A scene file (TOML), e.g. scenes/yoga-mat.toml, or a shipped \
                          scene's name, e.g. yoga-mat (`uncoil scenes` lists them)";

#[derive(Parser)]
#[command(
    name = "uncoil",
    version,
    about = "A coiled tape uncoiling on a floor, contact-resolved in rapier2d and held against the continuum theory"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene: simulate, compare with the references, write samples.csv, report.json and
    /// run.mcap (the Foxglove log, with foxglove-layout.json beside it) into the output
    /// folder. A folded chain (`folded-chain`) writes samples.csv and report.json.
    Run {
        #[arg(help = SCENE_HELP)]
        scene: PathBuf,
        /// Output folder (default: runs/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value, one word, e.g. `--set discretisation.links_per_turn=64`
        /// (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
        /// Do not write run.mcap.
        #[arg(long)]
        no_mcap: bool,
        /// Serve the run live to Foxglove (WebSocket) at ADDR while it goes [default ADDR:
        /// 127.0.0.1:8765].
        #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = LIVE_ADDR,
              value_parser = parse_live)]
        live: Option<std::net::SocketAddr>,
        /// With --live: hold simulated time to X times real time (0.1: ten times slower).
        #[arg(long, value_name = "X", requires = "live", value_parser = parse_pace)]
        pace: Option<f64>,
        /// Land it from N pushes, its own and those just above it, side by side on the
        /// cores, into one folder (default: runs/<scene name>-ensemble; each run's files in
        /// run-<index>/, sweep.csv, ensemble.csv and report.md), and print the milestones'
        /// times as mean ± spread and the bang's every share as mean ± standard error: a
        /// landing is chaotic.
        #[arg(long, value_name = "N", value_parser = parse_ensemble,
              conflicts_with = "live")]
        ensemble: Option<usize>,
        /// With --ensemble: keep the runs of an earlier call that ended by themselves and run
        /// the rest (as `uncoil sweep --resume`).
        #[arg(long, requires = "ensemble")]
        resume: bool,
    },
    /// Read a run's MCAP log back: channels, message counts, time range, metadata, ledger;
    /// then the final bang's drawings: how many, and in how many the tape crosses itself.
    Inspect {
        /// The MCAP file, e.g. runs/yoga-mat/run.mcap.
        file: PathBuf,
    },
    /// Run a scene over the product grid of the varied keys, one row per run in sweep.csv.
    Sweep(cli::sweep::SweepArgs),
    /// Report on a sweep: Pareto and convergence plots (SVG) and report.md (also on stdout).
    SweepReport(cli::sweep::ReportArgs),
    /// Draw a run's motion.svg, energy.svg, approach.svg and forces.svg into its folder,
    /// from its samples.csv and report.json, and bang.svg, the tape's shape through the
    /// final bang, from its run.mcap (skipped, saying why, without one).
    Plot {
        /// A run's output folder, e.g. runs/yoga-mat.
        dir: PathBuf,
    },
    /// Run the hard cases, verify the outputs, print a table (about 23 minutes on a 2-core
    /// machine, most of it thin-1000's bang; `hard/NAME` runs one); or, given a run's output folder (one with a
    /// report.json), verify that its files are sound and belong to one run; or, given a
    /// killed run's folder, say what it left. Exit 0 when every case ends with a stated
    /// reason and sound outputs, else 1.
    Check {
        /// A folder of scene files, one scene (a file, or a shipped name such as
        /// hard/thin-300), `hard` (the hard cases, built in; the default, read from
        /// scenes/hard/ where that folder exists), or a run's output folder.
        dir: Option<PathBuf>,
        /// Output folder, one subfolder per case (default: runs/check).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Given a killed run's folder (`kill -9`, a crash): keep what it wrote. The samples
        /// are cut after their last complete row, the log is finished as far as it reads, and
        /// a report.json of kind "salvaged" says how far they go and what was lost.
        #[arg(long, requires = "dir")]
        salvage: bool,
    },
    /// Run scenes and print the paradox table: milestone times of the simulation and of
    /// every competing equation of motion for each scene, as markdown.
    Compare {
        /// Scene files (TOML), e.g. scenes/*.toml, or shipped scenes' names, e.g. yoga-mat.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Override a value of every scene, one word, e.g. `--set push.contact_speed_m_s=0.4`
        /// (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
    },
    /// List the shipped scenes, which every command takes by name: each one's name and kind.
    Scenes,
}

mod cli {
    //! The subcommands that are more than a call into the library, the checks of the paths
    //! they are given, and the exit codes.
    pub mod exit;
    pub mod paths;
    pub mod sweep;
}

use cli::exit::{Exit, Usage, fail};
use cli::paths;

fn main() -> ExitCode {
    let args: Vec<OsString> = std::env::args_os().collect();
    if let Some(hint) = split_value(&args) {
        eprintln!("error: {hint}");
        return Exit::BadInput.into();
    }
    let cli = Cli::parse_from(args);
    let done = match cli.command {
        Command::Check { dir, out, salvage } => match (salvage, dir) {
            (true, Some(dir)) => salvage_run(&dir),
            (_, dir) => check(dir, out),
        },
        Command::Sweep(args) => cli::sweep::sweep(args),
        Command::SweepReport(args) => cli::sweep::report(&args),
        Command::Plot { dir } => plot(&dir),
        Command::Inspect { file } => inspect(&file),
        Command::Run {
            scene,
            out,
            set,
            no_mcap,
            live,
            pace,
            ensemble,
            resume,
        } => {
            if let Some(n) = ensemble {
                cli::sweep::ensemble(&scene, &set, n, out, resume, no_mcap)
            } else {
                let view = View {
                    file: !no_mcap,
                    live,
                    pace,
                };
                run_any(&scene, &set, out, &view)
            }
        }
        Command::Compare { scenes, set } => compare(&scenes, &set),
        Command::Scenes => {
            list_scenes();
            Ok(Exit::Ok)
        }
    };
    match done {
        Ok(exit) => exit.into(),
        Err(e) => fail(e),
    }
}

/// A `--set` or `--vary` whose value came as a separate word (`--set tape.thickness_m
/// 0.004`), said with the one word it should be; clap would only call the value an
/// unexpected argument.
fn split_value(args: &[OsString]) -> Option<String> {
    args.windows(3).find_map(|w| {
        let [flag, key, value] = w else { return None };
        let flag = flag.to_str()?;
        let (key, value) = (key.to_str()?, value.to_str()?);
        let split = matches!(flag, "--set" | "--vary")
            && !key.contains('=')
            && !key.starts_with('-')
            && (!value.starts_with('-')
                || value.split(',').all(|v| v.trim().parse::<f64>().is_ok()))
            && shipped::text(value).is_none()
            && !Path::new(value).exists();
        split.then(|| {
            format!(
                "{flag} {key} {value}: {flag} takes KEY=VALUE as one word: {flag} {key}={value}"
            )
        })
    })
}

/// `uncoil scenes`: each shipped scene's name and kind, then the hard cases'.
fn list_scenes() {
    for (name, kind) in shipped::listed() {
        println!("{name:<26} {kind}");
    }
}

/// `uncoil run` on a scene of either kind.
fn run_any(
    scene: &Path,
    set: &[Override],
    out: Option<PathBuf>,
    view: &View,
) -> anyhow::Result<Exit> {
    let scene = any_scene_file_with_overrides(scene, set)?;
    if let Some(out) = &out {
        paths::out_folder(out)?;
    }
    let overrides: Vec<String> = set.iter().map(|o| format!("{}={}", o.key, o.raw)).collect();
    match scene {
        AnyScene::Coil(scene) => run_command(&scene, out, view, &overrides),
        AnyScene::FoldedChain(chain) => run_chain_command(&chain, out, view),
    }
}

/// `uncoil plot DIR`.
fn plot(dir: &Path) -> anyhow::Result<Exit> {
    paths::run_folder(dir)?;
    let plots = uncoil::study::plot::plot_run(dir)?;
    for f in &plots.written {
        println!("wrote {}", f.display());
    }
    for (f, why) in &plots.skipped {
        eprintln!("skipped {}: {why}", f.display());
    }
    Ok(Exit::Ok)
}

/// `uncoil inspect FILE`.
fn inspect(file: &Path) -> anyhow::Result<Exit> {
    paths::mcap_file(file)?;
    let (inv, bang) = uncoil::output::inspect::read_with_bang(file)?;
    print!("{}", uncoil::output::inspect::describe(file, &inv));
    if let Some(bang) = bang {
        println!();
        print!("{}", uncoil::output::inspect::bang::describe(&bang));
    }
    Ok(Exit::Ok)
}

/// `uncoil run` on a coil's scene.
fn run_command(
    scene: &Scene,
    out: Option<PathBuf>,
    view: &View,
    overrides: &[String],
) -> anyhow::Result<Exit> {
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&scene.name));
    let shown = match (view.file, view.live) {
        (true, _) => files::View::File,
        (false, Some(_)) => files::View::Unwritten,
        (false, None) => files::View::Off,
    };
    let mut files = RunFiles::take(&dir, scene, shown)?;
    let layout = files.layout_path().unwrap_or_default();
    if let Some(log) = files.view_mut()
        && let Err(e) = serve(log, view, &layout)
    {
        files.abandon();
        return Err(e);
    }
    let stop = stop_flag();
    let (text, end) = run_scene(scene, &mut files, &layout, &stop, overrides)?;
    print!("{text}");
    match end.status() {
        Status::Completed => {}
        Status::Interrupted => {
            eprintln!("{end}: the outputs end at the last step taken");
        }
        Status::Stopped => eprintln!("error: the run was stopped by a guard: {end}"),
    }
    Ok(Exit::of(end.status()))
}

/// `uncoil run` on a folded chain: no Foxglove view, its summary on stdout.
fn run_chain_command(
    chain: &FoldedChain,
    out: Option<PathBuf>,
    view: &View,
) -> anyhow::Result<Exit> {
    if view.live.is_some() {
        anyhow::bail!(Usage(format!(
            "--live: {} is a folded chain, which has no Foxglove view",
            chain.name
        )));
    }
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&chain.name));
    let folder = take_folder(chain, &dir)?;
    let stop = stop_flag();
    eprintln!("running {} into {} ...", chain.name, dir.display());
    let report = write_chain_run(chain, &folder, &mut |_| Ok(()), &stop)?;
    print!("{}", chain_summary(chain, &report));
    println!("Wrote {0}/samples.csv and {0}/report.json", dir.display());
    Ok(Exit::of_chain(report.end))
}

/// The flag a stopping signal raises (SIGINT, SIGTERM, SIGHUP: `uncoil::run::signals`): the
/// first asks the run to stop and finish its files; a second one ends the process at once.
pub(crate) fn stop_flag() -> Arc<AtomicBool> {
    uncoil::run::signals::listen().unwrap_or_else(|e| {
        eprintln!("warning: a signal will not finish the files: {e}");
        Arc::new(AtomicBool::new(false))
    })
}

/// Where the hard cases are read from: a folder of that name where it exists, else the
/// ones built in.
const HARD: &str = "scenes/hard";

/// What `uncoil check` takes.
const CHECK_TAKES: &str =
    "a folder of scene files, a scene, `hard` (the hard cases), or a run's output folder";

/// `uncoil check [DIR]`: a run's folder verified, a killed run's described, or a folder of
/// scenes (the hard cases by default) run and verified.
fn check(dir: Option<PathBuf>, out: Option<PathBuf>) -> anyhow::Result<Exit> {
    let dir = dir.unwrap_or_else(|| PathBuf::from(HARD));
    // What the folder holds, read once. It holds work to check if it has a run's report, a
    // killed run's files or scenes; one that does not (missing, or empty) does not hide a
    // shipped name.
    let is_folder = dir.is_dir();
    let report = is_folder && dir.join(uncoil::output::folder::REPORT).exists();
    let crashed = is_folder.then(|| check::crashed_run(&dir)).flatten();
    let scenes = is_folder.then(|| check::scene_files(&dir));
    let has_scenes = matches!(&scenes, Some(Ok(f)) if !f.is_empty());
    let work = dir.is_file() || report || crashed.is_some() || has_scenes;
    let built_in = !work && (dir == Path::new(HARD) || dir == Path::new("hard"));
    if let Some(out) = &out {
        paths::out_folder(out)?;
    }
    let one_scene = dir.is_file() || (!work && dir.to_str().and_then(shipped::text).is_some());
    let files = if built_in {
        let names = shipped::hard_names();
        eprintln!(
            "checking the {} hard cases built in (no {} here holds them) ...",
            names.len(),
            dir.display()
        );
        names.into_iter().map(PathBuf::from).collect()
    } else if one_scene {
        coil_scene(&dir, &[])?;
        vec![dir]
    } else {
        paths::folder(&dir, CHECK_TAKES)?;
        if report {
            if out.is_some() {
                anyhow::bail!(Usage(format!(
                    "--out: {} is a run's folder, whose files are checked where they are",
                    dir.display()
                )));
            }
            return Ok(verify_run(&dir));
        }
        if let Some(lines) = crashed {
            for line in lines {
                println!("{}: {line}", dir.display());
            }
            return Ok(Exit::Failed);
        }
        let files = scenes.unwrap_or_else(|| Ok(Vec::new()))?;
        if files.is_empty() {
            anyhow::bail!(paths::PathError {
                path: dir,
                found: "a folder with no scene files (*.toml), no run's files".into(),
                expected: CHECK_TAKES.into(),
            });
        }
        files
    };
    let out = out.unwrap_or_else(|| PathBuf::from("runs/check"));
    let mut cases = Vec::new();
    for file in &files {
        eprintln!("checking {} ...", file.display());
        let case = check::check_scene(file, &out);
        eprintln!("  {}: {}", case.outcome.word(), case.outcome.reason());
        cases.push(case);
    }
    print!("{}", check::table(&cases));
    Ok(if cases.iter().all(check::Case::passed) {
        Exit::Ok
    } else {
        Exit::Failed
    })
}

/// `uncoil check DIR` on a run's folder: 0 when its files are sound and of one run, else 1.
fn verify_run(dir: &Path) -> Exit {
    let problems = check::verify_outputs(dir);
    for p in &problems {
        println!("{}: {p}", dir.display());
    }
    if !problems.is_empty() {
        return Exit::Failed;
    }
    println!(
        "{}: the files are sound and belong to one run",
        dir.display()
    );
    if let Some(line) = check::salvage::describe(dir) {
        println!("{}: {line}", dir.display());
    }
    Exit::Ok
}

/// `uncoil check DIR --salvage`: keeps what a killed run wrote (see
/// [`check::salvage`]). Exit 0 when salvaged, 2 when `DIR` is not a killed run's folder,
/// 1 when there is nothing to keep or a file could not be written.
fn salvage_run(dir: &Path) -> anyhow::Result<Exit> {
    paths::folder(dir, "a killed run's output folder")?;
    let s = check::salvage::salvage(dir)?;
    for f in &s.written {
        println!("wrote {}", f.display());
    }
    if let Some(line) = check::salvage::describe(dir) {
        println!("{}: {line}", dir.display());
    }
    for line in &s.report.lost {
        println!("{}: lost: {line}", dir.display());
    }
    Ok(Exit::Ok)
}

/// The coil's scene at `path` (a file or a shipped name) with `set` applied; a folded
/// chain's is bad input.
fn coil_scene(path: &Path, set: &[Override]) -> anyhow::Result<Box<Scene>> {
    match any_scene_file_with_overrides(path, set)? {
        AnyScene::Coil(scene) => Ok(scene),
        AnyScene::FoldedChain(_) => Err(paths::PathError {
            path: path.to_owned(),
            found: "a folded chain's scene, which the paper's equations do not describe".into(),
            expected: "a coil's scene (`uncoil run` runs a folded chain)".into(),
        }
        .into()),
    }
}

/// Loads every scene first (a bad one fails before anything runs), then runs each and
/// prints its table as soon as it is done.
fn compare(paths: &[PathBuf], set: &[Override]) -> anyhow::Result<Exit> {
    let scenes = paths
        .iter()
        .map(|p| coil_scene(p, set))
        .collect::<anyhow::Result<Vec<_>>>()?;
    for scene in &scenes {
        eprintln!("running {} ...", scene.name);
        let mut log = SampleLog::default();
        let report = run(scene, &mut [&mut log]).with_context(|| scene.name.clone())?;
        println!("{}", table(&report, &log.samples));
    }
    Ok(Exit::Ok)
}

/// What of a run Foxglove sees.
struct View {
    /// Write run.mcap.
    file: bool,
    /// Serve the run live here.
    live: Option<std::net::SocketAddr>,
    /// Simulated seconds per real second.
    pace: Option<f64>,
}

/// `--live`'s default address.
#[cfg(feature = "live")]
const LIVE_ADDR: &str = uncoil::output::view::live::DEFAULT_ADDR;
#[cfg(not(feature = "live"))]
const LIVE_ADDR: &str = "127.0.0.1:8765";

fn parse_live(text: &str) -> Result<std::net::SocketAddr, String> {
    use std::net::ToSocketAddrs as _;
    text.to_socket_addrs()
        .ok()
        .and_then(|mut addrs| addrs.next())
        .ok_or_else(|| {
            format!("`{text}`: an address to serve at, IP:PORT or HOST:PORT, e.g. 127.0.0.1:8765")
        })
}

fn parse_ensemble(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (2..=1000).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{text}`: the landings of an ensemble, a whole number from 2 to 1000"
        )),
    }
}

fn parse_pace(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!(
            "{text}: a pace is a positive number, simulated seconds per real second"
        )),
    }
}

/// Starts the live server of `log`, if asked for; `layout` is the Foxglove layout's file.
fn serve(log: &mut ViewObserver, view: &View, layout: &Path) -> anyhow::Result<()> {
    let Some(addr) = view.live else {
        return Ok(());
    };
    #[cfg(feature = "live")]
    {
        let at = log.serve(addr)?;
        eprintln!(
            "serving the run live at ws://{at}: open it in Foxglove (Open connection -> \
             Foxglove WebSocket) with the layout {layout}",
            layout = layout.display()
        );
        if let Some(x) = view.pace {
            log.pace(x);
        }
        Ok(())
    }
    #[cfg(not(feature = "live"))]
    {
        let _ = (log, view.pace, layout);
        anyhow::bail!("--live {addr}: this uncoil was built without the `live` feature")
    }
}

/// Runs `scene` into its files (`layout`: the Foxglove layout beside its log); returns the
/// summary and why the run stopped.
fn run_scene(
    scene: &Scene,
    files: &mut RunFiles,
    layout: &Path,
    stop: &AtomicBool,
    overrides: &[String],
) -> anyhow::Result<(String, StopReason)> {
    eprintln!("running {} into {} ...", scene.name, files.dir().display());
    let report = files.run(scene, None, stop)?;
    let mut text = summary(&report, files.dir(), overrides);
    if let Some(path) = files.log_path() {
        text.push_str(&format!(
            "Wrote {}: open it in Foxglove with the layout {}, or list it with `uncoil \
             inspect {}`\n",
            path.display(),
            layout.display(),
            uncoil::output::shell_word(path)
        ));
    }
    Ok((text, report.stop))
}
