//! The `uncoil` command line: `uncoil run SCENE [--out DIR] [--no-mcap]` and
//! `uncoil inspect RUN.mcap`.
//!
//! Results go to stdout, diagnostics to stderr. Exit codes: 0 success, 1 a failure during
//! the run (e.g. an output file could not be written) or an unreadable MCAP file, 2 bad input
//! (scene or usage), 130 a run stopped by Ctrl-C (its outputs are complete up to there).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context as _;
use clap::{Parser, Subcommand};

use uncoil::mcap_log::McapObserver;
use uncoil::output::{CsvObserver, ReportObserver, summary};
use uncoil::run::{Observer, run_until};
use uncoil::scene::Scene;

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
    /// Run a scene: simulate, compare with the references, write samples.csv, report.json
    /// and run.mcap. Ctrl-C stops the run early and still finishes every file.
    Run {
        /// The scene file (TOML), e.g. scenes/yoga-mat.toml.
        scene: PathBuf,
        /// Output folder (default: runs/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Do not write run.mcap.
        #[arg(long)]
        no_mcap: bool,
    },
    /// Read a run's MCAP log back: channels, message counts, time range, metadata, ledger.
    Inspect {
        /// The MCAP file, e.g. runs/yoga-mat/run.mcap.
        file: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Inspect { file } => match uncoil::inspect::read_inventory(&file) {
            Ok(inv) => {
                print!("{}", uncoil::inspect::describe(&file, &inv));
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        Command::Run {
            scene,
            out,
            no_mcap,
        } => {
            let scene = match Scene::from_file(&scene) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            let stop = Arc::new(AtomicBool::new(false));
            let flag = Arc::clone(&stop);
            // The first Ctrl-C asks the run to stop and finish its files; a second one ends
            // the process at once.
            let handler = ctrlc::set_handler(move || {
                if flag.swap(true, Ordering::SeqCst) {
                    std::process::exit(130);
                }
            });
            if let Err(e) = handler {
                eprintln!("warning: Ctrl-C will not finish the files: {e}");
            }
            match run_scene(&scene, out, !no_mcap, &stop) {
                Ok(text) => {
                    print!("{text}");
                    if stop.load(Ordering::SeqCst) {
                        eprintln!("interrupted: the outputs end at the last step taken");
                        ExitCode::from(130)
                    } else {
                        ExitCode::SUCCESS
                    }
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
    }
}

fn run_scene(
    scene: &Scene,
    out: Option<PathBuf>,
    mcap: bool,
    stop: &AtomicBool,
) -> anyhow::Result<String> {
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&scene.name));
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    eprintln!("running {} into {} ...", scene.name, dir.display());
    let mut csv = CsvObserver::new(&dir);
    let mut report = ReportObserver::new(&dir);
    let mut log = McapObserver::new(&dir);
    let mut observers: Vec<&mut dyn Observer> = vec![&mut csv, &mut report];
    if mcap {
        observers.push(&mut log);
    }
    let report = run_until(scene, &mut observers, stop)?;
    let mut text = summary(&report, &dir);
    if mcap {
        text.push_str(&format!("Wrote {}\n", log.path().display()));
    }
    Ok(text)
}
