//! The Python extension module `uncoil._uncoil` (cargo feature `python`; maturin builds it
//! from `pyproject.toml`). It loads scenes and runs them for the Python package in
//! `src/python/uncoil`, which turns what it returns into numpy arrays and dicts. It adds no
//! physics and no output of its own: a run here is the command line's `uncoil run`, with its
//! files written only when an output folder is given.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::output::fields::fields;
use crate::output::files::{RunFiles, View};
use crate::output::folded::{chain_report_json, take_folder, write_chain_run};
use crate::run::folded::run_chain;
use crate::run::{Observer, RunReport, Sample, run_until};
use crate::scene::folded::FoldedChain;
use crate::scene::overrides::{Override, any_scene_file_with_overrides};
use crate::scene::{AnyScene, Scene, shipped};

// Raised as `uncoil.SceneError`: the package re-exports it, and a traceback names it so.
pyo3::create_exception!(
    uncoil,
    SceneError,
    PyValueError,
    "A scene file or an override that is not valid: the command line's `key = value: rule`."
);

/// A validated scene, of either kind: a coil's or a folded chain's.
#[pyclass(frozen, name = "Scene", module = "uncoil._uncoil")]
struct PyScene {
    inner: AnyScene,
}

impl PyScene {
    /// The coil's scene, or a `SceneError` saying that `what` takes one.
    fn coil(&self, what: &str) -> PyResult<&Scene> {
        match &self.inner {
            AnyScene::Coil(scene) => Ok(scene),
            AnyScene::FoldedChain(chain) => Err(SceneError::new_err(format!(
                "{}: a folded chain's scene; {what} takes a coil's",
                chain.name
            ))),
        }
    }
}

#[pymethods]
impl PyScene {
    /// The scene's name.
    #[getter]
    fn name(&self) -> &str {
        match &self.inner {
            AnyScene::Coil(scene) => &scene.name,
            AnyScene::FoldedChain(chain) => &chain.name,
        }
    }

    /// The scene's kind: `coil` or `folded-chain`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// The scene file's text, with one `# override:` line per override.
    #[getter]
    fn source_text(&self) -> &str {
        match &self.inner {
            AnyScene::Coil(scene) => &scene.source_text,
            AnyScene::FoldedChain(chain) => &chain.source_text,
        }
    }

    /// Every value of the scene, defaults filled in, as JSON.
    fn to_json(&self) -> PyResult<String> {
        match &self.inner {
            AnyScene::Coil(scene) => serde_json::to_string(scene),
            AnyScene::FoldedChain(chain) => serde_json::to_string(chain),
        }
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        format!("Scene({:?})", self.name())
    }
}

/// Reads the scene file at `path` (or the shipped scene of that name) and applies
/// `overrides`, each `(key, value)` with the value in TOML (`("solver.max_dt_s",
/// "0.0005")`), as `uncoil run --set` does. Either kind of scene.
#[pyfunction]
#[pyo3(signature = (path, overrides = Vec::new()))]
fn load_scene(path: PathBuf, overrides: Vec<(String, String)>) -> PyResult<PyScene> {
    let overrides = overrides
        .iter()
        .map(|(k, v)| format!("{k}={v}").parse::<Override>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| SceneError::new_err(e.to_string()))?;
    any_scene_file_with_overrides(&path, &overrides)
        .map(|inner| PyScene { inner })
        .map_err(|e| SceneError::new_err(e.to_string()))
}

/// Every shipped scene `load_scene` and `run` take instead of a path, with its kind (`coil`
/// or `folded-chain`): the scenes, then the hard cases (`hard/...`).
#[pyfunction]
fn scenes() -> Vec<(&'static str, &'static str)> {
    shipped::listed()
}

/// The samples of a run, column by column, in `samples.csv`'s order.
#[derive(Default)]
struct Columns {
    names: Vec<&'static str>,
    values: Vec<Vec<f64>>,
}

impl Columns {
    /// Adds a row: a sample's fields, in order (a coil's `Sample` or a chain's).
    fn push(&mut self, sample: &impl serde::Serialize) -> anyhow::Result<()> {
        let row = fields(sample)?;
        if self.names.is_empty() {
            self.names = row.iter().map(|(name, _)| *name).collect();
            self.values = vec![Vec::new(); row.len()];
        }
        for (column, (_, value)) in self.values.iter_mut().zip(row) {
            column.push(value);
        }
        Ok(())
    }
}

impl Observer for Columns {
    fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
        Ok(())
    }

    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        self.push(sample)
    }

    fn observe_final(&mut self, _report: &RunReport) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Runs `scene` and the observers that `out` and `mcap` ask for; stops early once `stop` is
/// set.
fn run_scene(
    scene: &Scene,
    out: Option<&PathBuf>,
    mcap: bool,
    stop: &AtomicBool,
) -> anyhow::Result<(Columns, RunReport)> {
    let mut columns = Columns::default();
    let Some(dir) = out else {
        let report = run_until(scene, &mut [&mut columns], stop)?;
        return Ok((columns, report));
    };
    // The folder is the run's while it runs, as for `uncoil run` (`output::files`).
    let view = if mcap { View::File } else { View::Off };
    let report = RunFiles::take(dir, scene, view)?.run(scene, Some(&mut columns), stop)?;
    Ok((columns, report))
}

/// Runs the folded chain `chain`, into `out` if given (its `samples.csv` and
/// `report.json`); returns its samples by column and its report as `report.json` has it.
fn run_folded(
    chain: &FoldedChain,
    out: Option<&PathBuf>,
    stop: &AtomicBool,
) -> anyhow::Result<(Columns, String)> {
    let mut columns = Columns::default();
    let mut each = |s: &crate::run::folded::ChainSample| columns.push(s);
    let report = match out {
        None => run_chain(chain, &mut each, stop)?,
        Some(dir) => write_chain_run(chain, &take_folder(chain, dir)?, &mut each, stop)?,
    };
    Ok((columns, chain_report_json(chain, &report)?))
}

/// A sample column's name and its values as little-endian `float64` bytes.
type NamedBytes = (String, Py<PyBytes>);

/// Runs `scene` (a coil's or a folded chain's) without the GIL: returns the sample columns
/// as `(name, float64 bytes)` pairs and the report as JSON, as `report.json` has it. Files
/// are written only into `out`, `run.mcap` only with `mcap` (a coil's).
/// Ctrl-C stops the run with its files finished and raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (scene, out = None, mcap = false))]
fn run(
    py: Python<'_>,
    scene: &PyScene,
    out: Option<PathBuf>,
    mcap: bool,
) -> PyResult<(Vec<NamedBytes>, String)> {
    if mcap && out.is_none() {
        return Err(PyValueError::new_err(
            "mcap=True needs an output folder (out=...)",
        ));
    }
    let stop = AtomicBool::new(false);
    let (columns, report) = match &scene.inner {
        AnyScene::Coil(coil) => {
            let (columns, report) =
                without_gil(py, &stop, || run_scene(coil, out.as_ref(), mcap, &stop))?;
            let report = serde_json::to_string(&report)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            (columns, report)
        }
        AnyScene::FoldedChain(chain) => {
            if mcap {
                return Err(PyValueError::new_err(
                    "mcap=True: a folded chain writes no run.mcap",
                ));
            }
            without_gil(py, &stop, || run_folded(chain, out.as_ref(), &stop))?
        }
    };
    let columns = columns
        .names
        .iter()
        .zip(&columns.values)
        .map(|(name, values)| {
            let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            ((*name).to_owned(), PyBytes::new(py, &bytes).unbind())
        })
        .collect();
    Ok((columns, report))
}

/// A reference of the continuum theory or of the exact-geometry model for `scene`, at each
/// of `at` (radii in m, or laid fractions), `NaN` where it is not defined:
/// - `eq7_time_at_radius`: eq. (7) with the corrected energy integral (ERRATA A1-A3), from
///   the scene's push (s);
/// - `eq7_time_from_rest`: its closed form from rest, `2 pi sqrt(R^3 - r^3) / (b sqrt(3 g))`
///   (s);
/// - `eq17_time_at_radius`: eq. (17)'s closed form (ERRATA C2) (s);
/// - `exact_time_at_fraction`, `exact_speed_at_fraction`: the exact-geometry model's time (s)
///   and contact-line speed (m/s) at a laid mass fraction.
#[pyfunction]
fn theory(scene: &PyScene, quantity: &str, at: Vec<f64>) -> PyResult<Vec<f64>> {
    use crate::theory::{References, continuum::continuum_time_from_rest, params};
    let coil = scene.coil("theory")?;
    let refs = References::new(coil);
    let p = params(coil);
    let value = |x: f64| -> PyResult<f64> {
        Ok(match quantity {
            "eq7_time_at_radius" => refs.continuum.time_at_radius(x).unwrap_or(f64::NAN),
            "eq7_time_from_rest" => continuum_time_from_rest(&p, x),
            "eq17_time_at_radius" => refs.force_torque.time_at_radius(x),
            "exact_time_at_fraction" => refs.exact.time_at_fraction(x).unwrap_or(f64::NAN),
            "exact_speed_at_fraction" => refs.exact.xdot_at_psi(refs.exact.psi_at_fraction(x)),
            other => return Err(PyValueError::new_err(format!("no quantity {other:?}"))),
        })
    };
    at.into_iter().map(value).collect()
}

/// Runs `f` on its own thread with the GIL released, polling for Ctrl-C: on one it sets
/// `stop`, waits for `f` to wind down and returns the `KeyboardInterrupt`.
fn without_gil<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    f: impl FnOnce() -> anyhow::Result<T> + Send,
) -> PyResult<T> {
    let (result, interrupted) = std::thread::scope(|s| {
        let worker = s.spawn(f);
        let mut interrupted = None;
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(Duration::from_millis(20)));
            if interrupted.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::SeqCst);
                interrupted = Some(e);
            }
        }
        (worker.join(), interrupted)
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    result
        .map_err(|_| PyRuntimeError::new_err("the run panicked"))?
        .map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))
}

/// A folder of this process's own under the system's temporary folder, for a sweep that
/// writes no files of the user's.
fn temporary_folder() -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::SeqCst);
    std::env::temp_dir().join(format!("uncoil-sweep-{}-{n}", std::process::id()))
}

/// A sweep of `scene` over the product grid of `vary` (`(key, [TOML values])`, the last
/// varying fastest), `jobs` runs at once (default one per core), written into `out` or a
/// temporary folder: `sweep.csv`'s header and rows (in the grid's order), as text.
#[pyfunction]
#[pyo3(signature = (scene, vary, jobs = None, out = None))]
fn sweep(
    py: Python<'_>,
    scene: &PyScene,
    vary: Vec<(String, Vec<String>)>,
    jobs: Option<usize>,
    out: Option<PathBuf>,
) -> PyResult<(Vec<String>, Vec<Vec<String>>)> {
    use crate::study::sweep::{Sweep, SweepOptions, SweepTable, Vary};
    let varies = vary
        .iter()
        .map(|(key, values)| format!("{key}={}", values.join(",")).parse::<Vary>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| SceneError::new_err(e.to_string()))?;
    let coil = scene.coil("sweep")?;
    let grid = Sweep::new(&coil.source_text, &coil.name, &varies)
        .map_err(|e| SceneError::new_err(e.to_string()))?;
    let (dir, temporary) = match out {
        Some(dir) => (dir, false),
        None => (temporary_folder(), true),
    };
    let opts = SweepOptions {
        jobs,
        progress: false,
        ..SweepOptions::default()
    };
    let stop = std::sync::Arc::clone(&opts.stop);
    let result = without_gil(py, &stop, || {
        let outcome = grid.run(&dir, &opts)?;
        SweepTable::read(&outcome.path)
    });
    if temporary {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let table = result?;
    Ok((table.header, table.rows))
}

/// An ensemble's first and last push from `v` (m/s) for `n` landings, as written
/// ([`ensemble_pushes`](crate::output::summary::ensemble_pushes): `uncoil run --ensemble`'s).
#[pyfunction]
fn ensemble_pushes(v: f64, n: usize) -> (String, String) {
    crate::output::summary::ensemble_pushes(v, n)
}

/// One pooled quantity as Python gets it: its key, the runs, mean, standard deviation,
/// standard error, least and greatest.
type PooledRow = (String, usize, f64, f64, f64, f64, f64);

/// A sweep's table (`header`, `rows`, as [`sweep`] gives them) pooled as one setting's
/// ensemble ([`Ensemble`](crate::study::analysis::Ensemble)): the milestones' times (by
/// label, then `release` and `bang ends`) and the bang's observables (by their `sweep.csv`
/// column where they are one, else by label).
#[pyfunction]
fn pool(header: Vec<String>, rows: Vec<Vec<String>>) -> (Vec<PooledRow>, Vec<PooledRow>) {
    use crate::study::analysis::{BANG_OBSERVABLES, Ensemble, Pooled, Reading};
    use crate::study::sweep::SweepTable;
    let e = Ensemble::new(&SweepTable { header, rows });
    let row = |key: String, p: &Pooled| (key, p.n, p.mean, p.sd, p.se, p.min, p.max);
    let milestones = e
        .milestones
        .iter()
        .map(|p| row(p.label.clone(), p))
        .collect();
    let bang = e
        .bang
        .iter()
        .zip(BANG_OBSERVABLES)
        .map(|(p, (label, reading))| match reading {
            Reading::Column(c) => row(c.name().to_owned(), p),
            _ => row(label.to_owned(), p),
        })
        .collect();
    (milestones, bang)
}

/// The module `uncoil._uncoil`.
#[pymodule]
fn _uncoil(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(theory, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(pool, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_pushes, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
