//! Outputs of a run: `samples.csv` (written as the run goes), `report.json`, and the
//! readable summary. Files are written under a temporary name (`.partial`), flushed to disk
//! and renamed when complete, and a finished file of an earlier run into the same folder is
//! removed when a run starts, so a killed run never leaves a file that looks finished. This
//! module does no physics.

pub mod compare;
pub mod inspect;
pub mod mcap;

use std::fmt::Write as _;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use crate::output::compare::cell;
use crate::run::stop::Status;
use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;
use crate::theory::rivals::{Case, rivals};

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
    #[allow(clippy::cast_precision_loss)]
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

fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{:+.2}%", 100.0 * v))
}

fn secs(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.4}"))
}

/// The level coil's times: the exact geometry it converges to, eq. (7) and eq. (17), with
/// the simulation's error and the continuum model's own.
fn coil_times(o: &mut String, report: &RunReport) {
    let _ = writeln!(
        o,
        "Time to reach each radius (compared at equal laid mass fraction f = 1 - (r/R)^2):"
    );
    let _ = writeln!(
        o,
        "  {:<6} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "r", "f", "sim s", "exact s", "eq.7 s", "eq.17 s", "sim/ex", "sim/eq7", "ex/eq7"
    );
    for m in &report.milestones {
        let _ = writeln!(
            o,
            "  {:<6} {:>7.4} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
            m.label,
            m.laid_fraction,
            secs(m.t_sim_s),
            secs(m.t_geo_s),
            secs(m.t_eq7_s),
            secs(m.t_eq17_s),
            pct(m.err_vs_geo),
            pct(m.err_vs_eq7),
            pct(m.geo_vs_eq7)
        );
    }
    let _ = writeln!(
        o,
        "  sim/ex: the simulation's error against the exact-geometry model it converges to;"
    );
    let _ = writeln!(
        o,
        "  ex/eq7: the continuum model's own idealisation (O(b/r)); eq. 17 ignores gravity."
    );
}

/// Any other case's times against the rivals the paper gives for it (`uncoil compare`'s
/// table as plain text).
fn rival_times(o: &mut String, report: &RunReport) {
    let rv = rivals(&report.scene);
    let _ = writeln!(
        o,
        "Time to reach each laid fraction f, against the analyses of {} (the rival's time over the \
         simulation's, minus 1; * = the reference the simulation must converge to):",
        Case::of(&report.scene).section()
    );
    let mut head = format!("  {:<6} {:>7} {:>9}", "", "f", "sim s");
    for r in &rv {
        let star = if r.valid { " *" } else { "" };
        let _ = write!(head, " {:>22}", format!("{}{star} s", r.label));
    }
    let _ = writeln!(o, "{head}");
    for m in &report.milestones {
        let mut row = format!(
            "  {:<6} {:>7.4} {:>9}",
            m.label,
            m.laid_fraction,
            secs(m.t_sim_s)
        );
        for r in &rv {
            let _ = write!(row, " {:>22}", cell(r, m.laid_fraction, m.t_sim_s));
        }
        let _ = writeln!(o, "{row}");
    }
    for r in &rv {
        let _ = writeln!(o, "  {}: {}", r.label, r.description);
    }
}

/// The final bang's part of the summary: what it received, where that energy went by
/// mechanism, how violent it was and where the tape ended.
fn bang_summary(o: &mut String, report: &RunReport, bang: &crate::run::BangReport) {
    let l = &report.ledger;
    let end = match bang.ended_by {
        Some(crate::model::BangEnd::Rest) => "came to rest",
        Some(crate::model::BangEnd::Cap) => "reached its cap (stop.bang_cap_s)",
        None => "was cut short",
    };
    let _ = writeln!(
        o,
        "The final bang ({end} {:.4} s after the release at t = {} s):",
        bang.duration_s,
        secs(l.bang_time_s)
    );
    let _ = writeln!(
        o,
        "  received {:.5} J of kinetic energy; fastest point {:.4} m/s; peak floor force {:.4e} N; \
         floor impulse {:.4e} N s",
        bang.kinetic_in_j, bang.top_speed_m_s, bang.peak_floor_force_n, bang.floor_impulse_n_s
    );
    let d = l.dissipated_by_bang_j;
    let b = &l.bang;
    if l.bang_split_meaningful() {
        let of = |x: f64| 100.0 * x / d;
        let _ = writeln!(
            o,
            "  dissipated {d:.5} J, measured where it happened: floor impacts {:.5} J ({:.1} %), \
             floor friction {:.5} J ({:.1} %), freezing {:.5} J ({:.2} %);",
            b.floor_normal_j,
            of(b.floor_normal_j),
            b.floor_friction_j,
            of(b.floor_friction_j),
            b.freeze_j,
            of(b.freeze_j)
        );
        let _ = writeln!(
            o,
            "  numerical (zero for ideal joints and an exact step): joints {:.5} J ({:.1} %), \
             residual {:.5} J ({:.1} %)",
            b.joints_j,
            of(b.joints_j),
            b.residual_j,
            of(b.residual_j)
        );
    } else {
        let _ = writeln!(
            o,
            "  dissipated {d:.5} J ({:.3} % of S): too little to split by mechanism (under {} %)",
            100.0 * d / l.energy_scale_j,
            100.0 * crate::run::BANG_SPLIT_MIN_OF_SCALE
        );
    }
    if report.scene.fixed_axis {
        let _ = writeln!(
            o,
            "  the tape hangs from its axis with no floor to stop it: still moving {:.3e} J",
            bang.still_moving_j
        );
        return;
    }
    let short = bang.laid_length_m - bang.end_x_m;
    let _ = writeln!(
        o,
        "  the tape's free end lies at x = {:.4} m, {:.4} m {} its flat length {:.4} m; still moving \
         {:.3e} J ({:.3} % of what the bang received)",
        bang.end_x_m,
        short.abs(),
        if short >= 0.0 { "short of" } else { "beyond" },
        bang.laid_length_m,
        bang.still_moving_j,
        100.0 * bang.still_moving_j / bang.kinetic_in_j.max(f64::MIN_POSITIVE)
    );
}

/// The readable summary printed after a run.
pub fn summary(report: &RunReport, out_dir: &Path) -> String {
    let s = &report.scene;
    let l = &report.ledger;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "uncoil: {} (R = {} m, b = {} m, M = {} kg, push {} m/s, friction {})",
        s.name,
        s.tape.outer_radius_m,
        s.tape.thickness_m,
        s.tape.mass_kg,
        s.push_speed_m_s,
        s.friction
    );
    let _ = writeln!(
        o,
        "  {} links ({} per turn), {} steps, {:.3} s simulated in {:.3} s wall ({:.3} s to the bang); {}: {}",
        report.links,
        s.links_per_turn,
        report.steps,
        report.sim_time_s,
        report.wall_time_s,
        report.wall_time_rolling_s,
        match report.stop.status() {
            Status::Completed => "completed",
            Status::Interrupted => "INTERRUPTED",
            Status::Stopped => "STOPPED by a guard",
        },
        report.stop
    );
    let _ = writeln!(o);
    if Case::of(s) == Case::Coil {
        coil_times(&mut o, report);
    } else {
        rival_times(&mut o, report);
    }
    if let Some(f) = report.geo_hop_fraction {
        let _ = writeln!(
            o,
            "  The exact-geometry model needs a floor that pulls (N < 0) from f = {f:.4} on."
        );
    }
    let _ = writeln!(o);
    let pc = |x: f64| 100.0 * x / l.energy_scale_j;
    let _ = writeln!(
        o,
        "Energy ledger (E0 = {:.4} J; MgR = {:.4} J; flat tape at rest keeps {:.4} J; percentages \
         of the energy scale S = {:.4} J, the largest of |E0|, MgR and the kinetic energy into the \
         bang):",
        l.e0_j, l.mgr_j, l.flat_potential_j, l.energy_scale_j
    );
    let b = &l.before_bang;
    let _ = writeln!(
        o,
        "  lost before the bang   {:>9.5} J ({:>6.2}% of S): steps {:.5}, detach {:.5}, freeze {:.5}",
        l.lost_before_bang_j,
        pc(l.lost_before_bang_j),
        b.step_j,
        b.detach_j,
        b.freeze_j
    );
    if let Some(d) = report
        .milestones
        .iter()
        .find(|m| m.label == "2b")
        .and_then(|m| m.dissipated_j)
    {
        let _ = writeln!(
            o,
            "  lost before r = 2b     {:>9.5} J ({:>6.2}% of S)",
            d,
            pc(d)
        );
    }
    let _ = writeln!(
        o,
        "  kinetic into the bang  {:>9.5} J ({:>6.2}% of S){}",
        l.kinetic_into_bang_j,
        pc(l.kinetic_into_bang_j),
        l.bang_time_s
            .map_or_else(String::new, |t| format!(", at t = {t:.4} s"))
    );
    let _ = writeln!(
        o,
        "  dissipated by the bang {:>9.5} J ({:>6.2}% of S)",
        l.dissipated_by_bang_j,
        pc(l.dissipated_by_bang_j)
    );
    let _ = writeln!(
        o,
        "  left at the end        {:>9.5} J ({:>6.2}% of S, above the flat rest state)",
        l.left_j,
        pc(l.left_j)
    );
    if let Some(bang) = &report.bang {
        let _ = writeln!(o);
        bang_summary(&mut o, report, bang);
    }
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "Max joint separation {:.2e} m (bound {:.2e}), max floor penetration {:.2e} m (bound {:.2e}).",
        report.max_joint_gap_m,
        report.bounds.joint_gap_m,
        report.max_penetration_m,
        report.bounds.penetration_m
    );
    let _ = writeln!(
        o,
        "Max energy rise above E0 {:+.2e} of S (the guard's bound {:.3e} J); fastest spin {:.4e} rad/s.",
        report.max_energy_rise_rel, report.bounds.energy_rise_j, report.max_spin_rad_s
    );
    if !report.reference_limits.is_empty() {
        let _ = writeln!(o, "Where the references stop applying:");
        for l in &report.reference_limits {
            let _ = writeln!(
                o,
                "  {:<10} t = {:>9} s, r = {:.4e} m: {}",
                crate::run::guard::label(l.kind),
                secs(l.t_s),
                l.r_m,
                l.detail
            );
        }
    }
    let _ = writeln!(
        o,
        "Wrote {} and {}",
        out_dir.join("samples.csv").display(),
        out_dir.join("report.json").display()
    );
    o
}
