//! The `uncoil` command line: `uncoil run SCENE [--out DIR] [--set KEY=VALUE]... [--no-mcap]
//! [--live [ADDR] [--pace X]]`,
//! `uncoil inspect RUN.mcap`, `uncoil check`, `uncoil compare`, `uncoil sweep`,
//! `uncoil sweep-report`, `uncoil plot`.
//!
//! Results go to stdout, diagnostics to stderr. Exit codes: 0 success, 1 a failure during
//! the run (e.g. an output file could not be written) or an unreadable MCAP file, 2 bad input
//! (scene or usage), 3 a guard stopped the run (a blow-up: its reason is on stderr and in
//! `report.json`, and the outputs hold everything logged up to the stop), 130, 143 or 129 a
//! run stopped by SIGINT (Ctrl-C), SIGTERM or SIGHUP (its outputs are complete up to
//! there, the signal named).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use clap::{Parser, Subcommand};

use uncoil::output::compare::{SampleLog, table};
use uncoil::output::files::{self, RunFiles};
use uncoil::output::folded::{chain_summary, write_chain_run};
use uncoil::output::folder::{FolderError, RunFolder, run_id};
use uncoil::output::summary;
use uncoil::output::view::ViewObserver;
use uncoil::run::folded::ChainEnd;
use uncoil::run::run;
use uncoil::run::stop::{Status, StopReason};
use uncoil::scene::AnyScene;
use uncoil::scene::Scene;
use uncoil::scene::folded::FoldedChain;
use uncoil::scene::overrides::{Override, any_scene_file_with_overrides};
use uncoil::study::check;

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
    /// run.mcap (the Foxglove log) into the output folder. A folded chain
    /// (scenes/validation/) writes samples.csv and report.json.
    Run {
        /// The scene file (TOML), e.g. scenes/yoga-mat.toml.
        scene: PathBuf,
        /// Output folder (default: runs/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value, e.g. `--set discretisation.links_per_turn=64` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
        /// Do not write run.mcap.
        #[arg(long)]
        no_mcap: bool,
        /// Serve the run live to Foxglove (WebSocket) at ADDR while it goes [default ADDR:
        /// 127.0.0.1:8765].
        #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = LIVE_ADDR)]
        live: Option<std::net::SocketAddr>,
        /// With --live: hold simulated time to X times real time (0.1: ten times slower).
        #[arg(long, value_name = "X", requires = "live", value_parser = parse_pace)]
        pace: Option<f64>,
    },
    /// Read a run's MCAP log back: channels, message counts, time range, metadata, ledger.
    Inspect {
        /// The MCAP file, e.g. runs/yoga-mat/run.mcap.
        file: PathBuf,
    },
    /// Run a scene over the product grid of the varied keys, one row per run in sweep.csv.
    Sweep(cli::sweep::SweepArgs),
    /// Report on a sweep: Pareto and convergence plots (SVG) and report.md (also on stdout).
    SweepReport(cli::sweep::ReportArgs),
    /// Draw a run's motion.svg, energy.svg, approach.svg and forces.svg into its folder,
    /// from its samples.csv and report.json.
    Plot {
        /// A run's output folder, e.g. runs/yoga-mat.
        dir: PathBuf,
    },
    /// Run every scene of a folder (the hard cases), verify the outputs, print a table; or,
    /// given a run's output folder (one with a report.json), verify that its files are sound
    /// and belong to one run; or, given a killed run's folder, say what it left. Exit 0 when
    /// every case ends with a stated reason and sound outputs, else 1.
    Check {
        /// Folder of scene files (default: scenes/hard), or a run's output folder.
        dir: Option<PathBuf>,
        /// Output folder, one subfolder per case (default: runs/check).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Given a killed run's folder (`kill -9`, a crash): keep what it wrote. The samples
        /// are cut after their last complete row, the log is finished as far as it reads, and
        /// a report.json of kind "salvaged" says how far they go and what was lost.
        #[arg(long)]
        salvage: bool,
    },
    /// Run scenes and print the paradox table: milestone times of the simulation and of
    /// every competing equation of motion for each scene, as markdown.
    Compare {
        /// The scene files (TOML), e.g. scenes/*.toml.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
    },
}

mod cli {
    //! The subcommands that are more than a call into the library, and the exit codes.
    pub mod exit;
    pub mod sweep;
}

use cli::exit::Exit;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { dir, out, salvage } => match (salvage, dir) {
            (true, Some(dir)) => salvage_run(&dir),
            (true, None) => {
                eprintln!(
                    "error: --salvage needs a killed run's folder: uncoil check DIR --salvage"
                );
                Exit::BadInput.into()
            }
            (false, dir) => check(dir, out),
        },
        Command::Sweep(args) => cli::sweep::sweep(args),
        Command::SweepReport(args) => cli::sweep::report(&args),
        Command::Plot { dir } => match uncoil::study::plot::plot_run(&dir) {
            Ok(files) => {
                for f in files {
                    println!("wrote {}", f.display());
                }
                Exit::Ok.into()
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                Exit::Failed.into()
            }
        },
        Command::Inspect { file } => match uncoil::output::inspect::read_inventory(&file) {
            Ok(inv) => {
                print!("{}", uncoil::output::inspect::describe(&file, &inv));
                Exit::Ok.into()
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                Exit::Failed.into()
            }
        },
        Command::Run {
            scene,
            out,
            set,
            no_mcap,
            live,
            pace,
        } => {
            let view = View {
                file: !no_mcap,
                live,
                pace,
            };
            match any_scene_file_with_overrides(&scene, &set) {
                Ok(AnyScene::Coil(scene)) => run_command(&scene, out, &view),
                Ok(AnyScene::FoldedChain(chain)) => run_chain_command(&chain, out, &view),
                Err(e) => {
                    eprintln!("error: {e}");
                    Exit::BadInput.into()
                }
            }
        }
        Command::Compare { scenes } => compare(&scenes),
    }
}

/// `uncoil run` on a coil's scene.
fn run_command(scene: &Scene, out: Option<PathBuf>, view: &View) -> ExitCode {
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&scene.name));
    let shown = match (view.file, view.live) {
        (true, _) => files::View::File,
        (false, Some(_)) => files::View::Unwritten,
        (false, None) => files::View::Off,
    };
    let mut files = match RunFiles::take(&dir, scene, shown) {
        Ok(f) => f,
        Err(e) => return folder_refused(e),
    };
    let stop = stop_flag();
    match run_scene(scene, &mut files, view, &stop) {
        Ok((text, end)) => {
            print!("{text}");
            match end.status() {
                Status::Completed => {}
                Status::Interrupted => {
                    eprintln!("{end}: the outputs end at the last step taken");
                }
                Status::Stopped => eprintln!("error: the run was stopped by a guard: {end}"),
            }
            Exit::of(end.status()).into()
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            Exit::Failed.into()
        }
    }
}

/// `uncoil run` on a folded chain: no Foxglove view, its summary on stdout.
fn run_chain_command(chain: &FoldedChain, out: Option<PathBuf>, view: &View) -> ExitCode {
    if view.live.is_some() {
        eprintln!("error: --live: a folded chain has no Foxglove view");
        return Exit::BadInput.into();
    }
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&chain.name));
    let folder = match RunFolder::take(&dir, &run_id(&chain.name, &chain.source_text), &chain.name)
    {
        Ok(f) => f,
        Err(e) => return folder_refused(e),
    };
    let stop = stop_flag();
    eprintln!("running {} into {} ...", chain.name, dir.display());
    match write_chain_run(chain, &folder, &stop) {
        Ok(report) => {
            print!("{}", chain_summary(chain, &report));
            println!("Wrote {0}/samples.csv and {0}/report.json", dir.display());
            match report.end {
                ChainEnd::Interrupted => Exit::Interrupted.into(),
                ChainEnd::NotFinite | ChainEnd::Unsolved => Exit::Stopped.into(),
                _ => Exit::Ok.into(),
            }
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            Exit::Failed.into()
        }
    }
}

/// The flag a stopping signal raises (SIGINT, SIGTERM, SIGHUP: `uncoil::run::signals`): the
/// first asks the run to stop and finish its files; a second one ends the process at once.
pub(crate) fn stop_flag() -> Arc<AtomicBool> {
    uncoil::run::signals::listen().unwrap_or_else(|e| {
        eprintln!("warning: a signal will not finish the files: {e}");
        Arc::new(AtomicBool::new(false))
    })
}

fn check(dir: Option<PathBuf>, out: Option<PathBuf>) -> ExitCode {
    let dir = dir.unwrap_or_else(|| PathBuf::from("scenes/hard"));
    if dir.join(uncoil::output::folder::REPORT).exists() {
        let problems = check::verify_outputs(&dir);
        for p in &problems {
            println!("{}: {p}", dir.display());
        }
        if problems.is_empty() {
            println!(
                "{}: the files are sound and belong to one run",
                dir.display()
            );
            if let Some(line) = check::salvage::describe(&dir) {
                println!("{}: {line}", dir.display());
            }
            return Exit::Ok.into();
        }
        return Exit::Failed.into();
    }
    if let Some(lines) = check::crashed_run(&dir) {
        for line in lines {
            println!("{}: {line}", dir.display());
        }
        return Exit::Failed.into();
    }
    let out = out.unwrap_or_else(|| PathBuf::from("runs/check"));
    let files = match check::scene_files(&dir) {
        Ok(f) if f.is_empty() => {
            eprintln!("error: no scene files (*.toml) in {}", dir.display());
            return Exit::BadInput.into();
        }
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e:#}");
            return Exit::BadInput.into();
        }
    };
    let mut cases = Vec::new();
    for file in &files {
        eprintln!("checking {} ...", file.display());
        let case = check::check_scene(file, &out);
        eprintln!("  {}: {}", case.outcome.word(), case.outcome.reason());
        cases.push(case);
    }
    print!("{}", check::table(&cases));
    if cases.iter().all(check::Case::passed) {
        Exit::Ok.into()
    } else {
        Exit::Failed.into()
    }
}

/// `uncoil check DIR --salvage`: keeps what a killed run wrote (see
/// [`check::salvage`]). Exit 0 when salvaged, 2 when `DIR` is not a killed run's folder,
/// 1 when there is nothing to keep or a file could not be written.
fn salvage_run(dir: &Path) -> ExitCode {
    use check::salvage::SalvageError;
    match check::salvage::salvage(dir) {
        Ok(s) => {
            for f in &s.written {
                println!("wrote {}", f.display());
            }
            if let Some(line) = check::salvage::describe(dir) {
                println!("{}: {line}", dir.display());
            }
            for line in &s.report.lost {
                println!("{}: lost: {line}", dir.display());
            }
            Exit::Ok.into()
        }
        Err(e @ SalvageError::NotKilled(_)) => {
            eprintln!("error: {e}");
            Exit::BadInput.into()
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            Exit::Failed.into()
        }
    }
}

/// Loads every scene first (a bad one fails before anything runs), then runs each and
/// prints its table as soon as it is done.
fn compare(paths: &[PathBuf]) -> ExitCode {
    let mut scenes = Vec::with_capacity(paths.len());
    for path in paths {
        match Scene::from_file(path) {
            Ok(s) => scenes.push(s),
            Err(e) => {
                eprintln!("error: {e}");
                return Exit::BadInput.into();
            }
        }
    }
    for scene in &scenes {
        eprintln!("running {} ...", scene.name);
        let mut log = SampleLog::default();
        match run(scene, &mut [&mut log]) {
            Ok(report) => println!("{}", table(&report, &log.samples)),
            Err(e) => {
                eprintln!("error: {e:#}");
                return Exit::Failed.into();
            }
        }
    }
    Exit::Ok.into()
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

fn parse_pace(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!(
            "{text}: a pace is a positive number, simulated seconds per real second"
        )),
    }
}

/// Starts the live server of `log`, if asked for.
fn serve(log: &mut ViewObserver, view: &View) -> anyhow::Result<()> {
    let Some(addr) = view.live else {
        return Ok(());
    };
    #[cfg(feature = "live")]
    {
        let at = log.serve(addr)?;
        eprintln!(
            "serving the run live at ws://{at}: open it in Foxglove (Open connection -> \
             Foxglove WebSocket) with the layout tools/foxglove-layout.json"
        );
        if let Some(x) = view.pace {
            log.pace(x);
        }
        Ok(())
    }
    #[cfg(not(feature = "live"))]
    {
        let _ = (log, view.pace);
        anyhow::bail!("--live {addr}: this uncoil was built without the `live` feature")
    }
}

/// Why a folder could not be taken for a run, said, and its exit: 2 if another run holds it,
/// 1 if it cannot be made.
fn folder_refused(e: FolderError) -> ExitCode {
    eprintln!("error: {e:#}");
    match e {
        FolderError::Busy { .. } => Exit::BadInput.into(),
        FolderError::Io(_) => Exit::Failed.into(),
    }
}

/// Runs `scene` into its files; returns the summary and why the run stopped.
fn run_scene(
    scene: &Scene,
    files: &mut RunFiles,
    view: &View,
    stop: &AtomicBool,
) -> anyhow::Result<(String, StopReason)> {
    if let Some(log) = files.view_mut() {
        serve(log, view)?;
    }
    eprintln!("running {} into {} ...", scene.name, files.dir().display());
    let report = files.run(scene, None, stop)?;
    let mut text = summary(&report, files.dir());
    if let Some(path) = files.log_path() {
        text.push_str(&format!(
            "Wrote {0}: open it in Foxglove with the layout tools/foxglove-layout.json, or list \
             it with `uncoil inspect {0}`\n",
            path.display()
        ));
    }
    Ok((text, report.stop))
}
