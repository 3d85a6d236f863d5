//! A run's files, wired in one place. `uncoil run`, `uncoil check` and `uncoil.run(out=...)`
//! all write a coil's run through [`RunFiles`]: the folder taken for the run
//! ([`RunFolder`]), then `samples.csv`, `report.json` and, when asked, the Foxglove view,
//! in that order (the report stamps the finished samples; the view's `run.mcap` closes last),
//! on a thread beside the run's.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::output::background::Background;
use crate::output::folder::{FolderError, LAYOUT, RunFolder, run_id};
use crate::output::view::{FOXGLOVE_LAYOUT, ViewObserver};
use crate::output::{CsvObserver, ReportObserver};
use crate::run::{Observer, RunReport, run_until_with};
use crate::scene::Scene;
use crate::theory::References;

/// Whether a run has a Foxglove view, and whether it is written to `run.mcap`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// No view.
    Off,
    /// The view, written to `run.mcap` (and served live, if the caller starts a server).
    File,
    /// The view without a file: its channels reach only a live server.
    Unwritten,
}

/// The observers that write one run's files into the folder taken for it.
pub struct RunFiles {
    folder: RunFolder,
    csv: CsvObserver,
    report: ReportObserver,
    view: Option<ViewObserver>,
}

impl RunFiles {
    /// Takes `dir` for a run of `scene` (see [`RunFolder::take`]) and wires its files; a
    /// run with a view gets the Foxglove layout beside it (`foxglove-layout.json`).
    pub fn take(dir: &Path, scene: &Scene, view: View) -> Result<Self, FolderError> {
        let folder = RunFolder::take(dir, &run_id(&scene.name, &scene.source_text), &scene.name)?;
        let dir = folder.dir();
        if view != View::Off {
            crate::output::write_atomic(&dir.join(LAYOUT), FOXGLOVE_LAYOUT.as_bytes())?;
        }
        let view = match view {
            View::Off => None,
            View::File => Some(ViewObserver::new(dir)),
            View::Unwritten => Some(ViewObserver::without_file()),
        };
        Ok(Self {
            csv: CsvObserver::new(dir),
            report: ReportObserver::new(dir),
            view,
            folder,
        })
    }

    /// Gives the folder up before the run starts (a live server that could not start): the
    /// layout and the lock are removed ([`RunFolder::abandon`]).
    pub fn abandon(self) {
        self.folder.abandon(&[LAYOUT]);
    }

    /// The Foxglove layout written beside the view, if the run has one.
    pub fn layout_path(&self) -> Option<std::path::PathBuf> {
        self.view.as_ref().map(|_| self.folder.dir().join(LAYOUT))
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        self.folder.dir()
    }

    /// The Foxglove view, to start a live server on before the run.
    pub fn view_mut(&mut self) -> Option<&mut ViewObserver> {
        self.view.as_mut()
    }

    /// Where `run.mcap` is written, if it is.
    pub fn log_path(&self) -> Option<&Path> {
        self.view.as_ref().and_then(ViewObserver::path)
    }

    /// Runs `scene` into the files, with `first` observing before them (the Python
    /// package's columns); stops early once `stop` is set. The files are written on a
    /// thread of their own ([`Background`]), but for a view served live, which holds the
    /// run to its pace and stays on the run's thread.
    pub fn run<'a>(
        &'a mut self,
        scene: &Scene,
        first: Option<&'a mut dyn Observer>,
        stop: &AtomicBool,
    ) -> anyhow::Result<RunReport> {
        self.run_with(scene, None, first, stop)
    }

    /// [`RunFiles::run`] with the scene's references, if already built (by a sweep while
    /// its previous run stepped).
    pub fn run_with<'a>(
        &'a mut self,
        scene: &Scene,
        refs: Option<Arc<References>>,
        first: Option<&'a mut dyn Observer>,
        stop: &AtomicBool,
    ) -> anyhow::Result<RunReport> {
        let refs = refs.unwrap_or_else(|| Arc::new(References::new(scene)));
        if self.view.as_ref().is_some_and(ViewObserver::is_live) {
            let mut observers: Vec<&mut dyn Observer> = Vec::with_capacity(4);
            observers.extend(first);
            observers.push(&mut self.csv);
            observers.push(&mut self.report);
            observers.extend(self.view.as_mut().map(|v| v as &mut dyn Observer));
            return run_until_with(scene, refs, &mut observers, stop);
        }
        std::thread::scope(|scope| {
            let mut files: Vec<&mut (dyn Observer + Send)> = vec![&mut self.csv, &mut self.report];
            files.extend(self.view.as_mut().map(|v| v as &mut (dyn Observer + Send)));
            let mut background = Background::spawn(scope, files);
            let mut observers: Vec<&mut dyn Observer> = Vec::with_capacity(2);
            if let Some(first) = first {
                observers.push(first);
            }
            observers.push(&mut background);
            run_until_with(scene, refs, &mut observers, stop)
        })
    }
}
