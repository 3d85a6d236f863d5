//! Outputs of a run: `samples.csv` (written as the run goes), `report.json`, and the
//! readable summary. Files are written under a temporary name (`.partial`), flushed to disk
//! and renamed when complete, and a finished file of an earlier run into the same folder is
//! removed when a run starts, so a killed run never leaves a file that looks finished. This
//! module does no physics.

pub mod compare;
pub mod inspect;
pub mod mcap;
pub mod summary;
pub mod table;

pub use summary::summary;

use std::fmt::Write as _;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;

/// Column names of `samples.csv`, in order.
pub const CSV_COLUMNS: [&str; 56] = [
    "t_s",
    "laid_fraction",
    "r_m",
    "x_m",
    "xdot_m_s",
    "omega_rad_s",
    "kinetic_j",
    "potential_j",
    "dissipated_j",
    "normal_n",
    "friction_n",
    "lost_step_j",
    "lost_detach_j",
    "lost_freeze_j",
    "lost_bang_j",
    "bang_floor_normal_j",
    "bang_floor_friction_j",
    "bang_joints_j",
    "bang_freeze_j",
    "bang_residual_j",
    "r_ref_m",
    "x_ref_m",
    "xdot_ref_m_s",
    "kinetic_ref_j",
    "normal_ref_n",
    "friction_ref_n",
    "r_geo_m",
    "x_geo_m",
    "xdot_geo_m_s",
    "kinetic_geo_j",
    "r_ft_m",
    "laid_fraction_ref",
    "theta_rad",
    "theta_ref_rad",
    "n_tot_n",
    "f_tot_n",
    "n_floor_n",
    "f_floor_n",
    "n_int_n",
    "f_int_n",
    "n_tot_geo_n",
    "f_tot_geo_n",
    "f_floor_geo_n",
    "f_int_geo_n",
    "l_o",
    "l_o_eq14",
    "l_o_geo",
    "dl_o_dt_n_m",
    "tau_o_n_m",
    "tau_o_eq16_n_m",
    "tau_offcentre_n_m",
    "n_tot_ref_n",
    "f_tot_ref_n",
    "active_bodies",
    "max_joint_gap_m",
    "max_penetration_m",
];

fn sample_values(s: &Sample) -> [f64; 56] {
    let bodies = s.active_bodies as f64;
    [
        s.t_s,
        s.laid_fraction,
        s.r_m,
        s.x_m,
        s.xdot_m_s,
        s.omega_rad_s,
        s.kinetic_j,
        s.potential_j,
        s.dissipated_j,
        s.normal_n,
        s.friction_n,
        s.lost_step_j,
        s.lost_detach_j,
        s.lost_freeze_j,
        s.lost_bang_j,
        s.bang_floor_normal_j,
        s.bang_floor_friction_j,
        s.bang_joints_j,
        s.bang_freeze_j,
        s.bang_residual_j,
        s.r_ref_m,
        s.x_ref_m,
        s.xdot_ref_m_s,
        s.kinetic_ref_j,
        s.normal_ref_n,
        s.friction_ref_n,
        s.r_geo_m,
        s.x_geo_m,
        s.xdot_geo_m_s,
        s.kinetic_geo_j,
        s.r_ft_m,
        s.laid_fraction_ref,
        s.theta_rad,
        s.theta_ref_rad,
        s.n_tot_n,
        s.f_tot_n,
        s.n_floor_n,
        s.f_floor_n,
        s.n_int_n,
        s.f_int_n,
        s.n_tot_geo_n,
        s.f_tot_geo_n,
        s.f_floor_geo_n,
        s.f_int_geo_n,
        s.l_o,
        s.l_o_eq14,
        s.l_o_geo,
        s.dl_o_dt_n_m,
        s.tau_o_n_m,
        s.tau_o_eq16_n_m,
        s.tau_offcentre_n_m,
        s.n_tot_ref_n,
        s.f_tot_ref_n,
        bodies,
        s.max_joint_gap_m,
        s.max_penetration_m,
    ]
}

/// Writes `path` atomically: into `path.partial`, flushed to disk, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = partial_path(path);
    let mut file =
        File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    file.write_all(bytes)
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    drop(file);
    fs::rename(&tmp, path).with_context(|| format!("cannot rename to {}", path.display()))?;
    Ok(())
}

/// Removes a finished output left by an earlier run into the same folder, so that a run
/// killed before it finishes leaves only `.partial` files, never an older complete-looking
/// file beside them.
pub(crate) fn remove_stale(path: &Path) -> anyhow::Result<()> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot remove the earlier {}", path.display()))
        }
        _ => Ok(()),
    }
}

fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// Streams samples into `samples.csv`. A reference past its tabulated end (or a
/// quantity that does not exist in a phase) is an empty cell, never `NaN`.
pub struct CsvObserver {
    path: PathBuf,
    out: Option<BufWriter<File>>,
}

impl CsvObserver {
    /// An observer writing `dir/samples.csv`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join("samples.csv"),
            out: None,
        }
    }
}

impl Observer for CsvObserver {
    fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
        remove_stale(&self.path)?;
        let tmp = partial_path(&self.path);
        let file =
            File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut out = BufWriter::new(file);
        writeln!(out, "{}", CSV_COLUMNS.join(","))?;
        self.out = Some(out);
        Ok(())
    }

    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        let Some(out) = self.out.as_mut() else {
            return Ok(());
        };
        let mut line = String::with_capacity(400);
        for (i, v) in sample_values(sample).iter().enumerate() {
            if i > 0 {
                line.push(',');
            }
            if v.is_finite() {
                write!(line, "{v:.9e}")?;
            }
        }
        writeln!(out, "{line}")?;
        Ok(())
    }

    fn observe_final(&mut self, _report: &RunReport) -> anyhow::Result<()> {
        if let Some(out) = self.out.take() {
            let file = out
                .into_inner()
                .map_err(|e| e.into_error())
                .with_context(|| format!("cannot write {}", self.path.display()))?;
            file.sync_all()
                .with_context(|| format!("cannot write {}", self.path.display()))?;
            drop(file);
            fs::rename(partial_path(&self.path), &self.path)
                .with_context(|| format!("cannot rename to {}", self.path.display()))?;
        }
        Ok(())
    }
}

/// Writes `report.json` at the end of the run.
pub struct ReportObserver {
    path: PathBuf,
}

impl ReportObserver {
    /// An observer writing `dir/report.json`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join("report.json"),
        }
    }
}

impl Observer for ReportObserver {
    fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
        remove_stale(&self.path)
    }
    fn observe_sample(&mut self, _sample: &Sample) -> anyhow::Result<()> {
        Ok(())
    }
    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()> {
        let mut text = serde_json::to_string_pretty(report)?;
        text.push('\n');
        write_atomic(&self.path, text.as_bytes())
    }
}
