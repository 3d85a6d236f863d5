//! The `uncoil` command line: `uncoil run SCENE [--out DIR] [--set KEY=VALUE]...`,
//! `uncoil sweep`, `uncoil sweep-report`, `uncoil plot`.
//!
//! Results go to stdout, diagnostics to stderr. Exit codes: 0 success, 1 a failure during
//! the run (e.g. an output file could not be written), 2 bad input (scene or usage).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Parser, Subcommand};

use uncoil::output::{CsvObserver, ReportObserver, summary};
use uncoil::overrides::{Override, scene_file_with_overrides};
use uncoil::run::{Observer, run};
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
    /// Run a scene: simulate, compare with the references, write samples.csv and report.json.
    Run {
        /// The scene file (TOML), e.g. scenes/yoga-mat.toml.
        scene: PathBuf,
        /// Output folder (default: runs/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value, e.g. `--set discretisation.links_per_turn=64` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
    },
    /// Run a scene over the product grid of the varied keys, one row per run in sweep.csv.
    Sweep(sweep_cmd::SweepArgs),
    /// Report on a sweep: Pareto and convergence plots (SVG) and report.md (also on stdout).
    SweepReport(sweep_cmd::ReportArgs),
    /// Draw a run's motion.svg and energy.svg from its samples.csv and report.json.
    Plot {
        /// A run's output folder, e.g. runs/yoga-mat.
        dir: PathBuf,
    },
}

mod sweep_cmd;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Sweep(args) => sweep_cmd::sweep(args),
        Command::SweepReport(args) => sweep_cmd::report(&args),
        Command::Plot { dir } => match uncoil::plot::plot_run(&dir) {
            Ok(files) => {
                for f in files {
                    println!("wrote {}", f.display());
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        Command::Run { scene, out, set } => {
            let scene = match scene_file_with_overrides(&scene, &set) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            match run_scene(&scene, out) {
                Ok(text) => {
                    print!("{text}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
    }
}

fn run_scene(scene: &Scene, out: Option<PathBuf>) -> anyhow::Result<String> {
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&scene.name));
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    eprintln!("running {} into {} ...", scene.name, dir.display());
    let mut csv = CsvObserver::new(&dir);
    let mut report = ReportObserver::new(&dir);
    let observers: &mut [&mut dyn Observer] = &mut [&mut csv, &mut report];
    let report = run(scene, observers)?;
    Ok(summary(&report, &dir))
}
