//! The rows of `sweep.csv`: its columns, the result cells of a finished run and the
//! status cell ([`RowStatus`]). It runs nothing and reads or writes no file: the CSV text
//! and the table are in [`table`](super::table), the runs in [`Sweep`](super::Sweep).

use std::str::FromStr;

use crate::run::RunReport;
use crate::run::limits::LimitKind;
use crate::run::report::MilestoneKey;
use crate::run::stop::StopReason;

/// The first column of `sweep.csv`: the combination's place in the full grid (0-based,
/// last `--vary` key fastest), the same in every shard.
pub const INDEX_COLUMN: &str = "index";
/// The last column of `sweep.csv`, a [`RowStatus`].
pub const STATUS_COLUMN: &str = "status";

/// How a sweep's run ended, as its `status` cell says it: `ok` (the bang ended),
/// `max_time` (`stop.max_time_s` reached first), `interrupted`, `stopped: <guard>` (a
/// guard stopped it, with the guard's value and bound) or `failed: <error>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RowStatus {
    /// The final bang ended, at rest or at its cap.
    Ok,
    /// `stop.max_time_s` was reached before the bang ended.
    MaxTime,
    /// The run was asked to stop.
    Interrupted,
    /// A guard stopped the run; what it said.
    Stopped(String),
    /// The run failed or panicked; its error.
    Failed(String),
}

impl RowStatus {
    /// The status of a run that ended.
    pub fn of(stop: &StopReason) -> Self {
        match stop {
            StopReason::AtRest { .. } | StopReason::BangCap { .. } => Self::Ok,
            StopReason::MaxTime { .. } => Self::MaxTime,
            StopReason::Interrupted { .. } => Self::Interrupted,
            StopReason::Guard(trip) => Self::Stopped(one_line(&trip.to_string())),
        }
    }

    /// Whether the run's figures enter a sweep's fits: it ran to its bang's end or to its
    /// time limit, unstopped.
    pub fn fits(&self) -> bool {
        matches!(self, Self::Ok | Self::MaxTime)
    }
}
pub(super) fn one_line(text: &str) -> String {
    text.replace(['\n', '\r'], " ")
}

impl std::fmt::Display for RowStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Ok => f.write_str("ok"),
            Self::MaxTime => f.write_str("max_time"),
            Self::Interrupted => f.write_str("interrupted"),
            Self::Stopped(why) => write!(f, "stopped: {why}"),
            Self::Failed(why) => write!(f, "failed: {why}"),
        }
    }
}

impl FromStr for RowStatus {
    type Err = String;

    fn from_str(cell: &str) -> Result<Self, String> {
        match cell {
            "ok" => Ok(Self::Ok),
            "max_time" => Ok(Self::MaxTime),
            "interrupted" => Ok(Self::Interrupted),
            _ => {
                if let Some(why) = cell.strip_prefix("stopped: ") {
                    Ok(Self::Stopped(why.to_owned()))
                } else if let Some(why) = cell.strip_prefix("failed: ") {
                    Ok(Self::Failed(why.to_owned()))
                } else {
                    Err(format!(
                        "status `{cell}`: expected ok, max_time, interrupted, stopped: ... or failed: ..."
                    ))
                }
            }
        }
    }
}

/// Column names after the varied keys, for a scene's milestone labels.
pub fn result_columns(milestone_labels: &[String]) -> Vec<String> {
    let mut c: Vec<String> = [
        "links",
        "steps",
        "jobs",
        "wall_s",
        "wall_rolling_s",
        "sim_time_s",
        "bang_time_s",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    for l in milestone_labels {
        c.push(format!("err_geo_{l}"));
    }
    for l in milestone_labels {
        c.push(format!("err_eq7_{l}"));
    }
    c.extend(
        [
            "max_err_geo",
            "max_err_eq7",
            "e0_j",
            "lost_before_bang_j",
            "lost_before_bang_of_e0",
            "lost_before_2b_of_e0",
            "max_energy_rise_rel",
            "peak_xdot_m_s",
            "peak_r_m",
            "lift_off_r_m",
            "leaves_exact_r_m",
            "exact_hops_r_m",
        ]
        .iter()
        .map(|s| (*s).to_owned()),
    );
    c.extend(BANG_COLUMNS.iter().map(|s| (*s).to_owned()));
    c.extend([STATUS_COLUMN].iter().map(|s| (*s).to_owned()));
    c
}

/// The final bang's columns of `sweep.csv` (empty cells for a run stopped before the
/// bang): what it received and dissipated, the split of what it dissipated by mechanism
/// (fractions), its observables, and what ended it.
pub const BANG_COLUMNS: [&str; 17] = [
    "bang_kinetic_in_j",
    "bang_dissipated_j",
    "bang_floor_normal_of",
    "bang_floor_friction_of",
    "bang_joints_of",
    "bang_freeze_of",
    "bang_residual_of",
    "bang_numerical_of",
    "bang_top_speed_m_s",
    "bang_duration_s",
    "bang_peak_floor_force_n",
    "bang_floor_impulse_n_s",
    "bang_end_x_m",
    "bang_laid_length_m",
    "bang_still_moving_of",
    "bang_wall_s",
    "bang_ended_by",
];

/// The header of `sweep.csv`: index, the varied keys, then [`result_columns`].
pub fn header(keys: &[String], milestone_labels: &[String]) -> Vec<String> {
    let mut h = vec![INDEX_COLUMN.to_owned()];
    h.extend(keys.iter().cloned());
    h.extend(result_columns(milestone_labels));
    h
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6e}")
    } else {
        String::new()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, num)
}

/// Largest `|e|` over all milestones, `None` if any milestone was not reached.
fn max_abs(errs: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    errs.map(|e| e.map(f64::abs))
        .try_fold(0.0_f64, |m, e| e.map(|e| m.max(e)))
}

/// The result cells of a finished run, in [`result_columns`] order.
pub fn result_cells(report: &RunReport, jobs: usize) -> Vec<String> {
    let l = &report.ledger;
    let mut c = vec![
        report.links.to_string(),
        report.steps.to_string(),
        jobs.to_string(),
        num(report.wall_time_s),
        num(report.wall_time_rolling_s),
        num(report.sim_time_s),
        opt(l.bang_time_s),
    ];
    c.extend(report.milestones.iter().map(|m| opt(m.err_vs_geo)));
    c.extend(report.milestones.iter().map(|m| opt(m.err_vs_eq7)));
    c.push(opt(max_abs(report.milestones.iter().map(|m| m.err_vs_geo))));
    c.push(opt(max_abs(report.milestones.iter().map(|m| m.err_vs_eq7))));
    c.push(num(l.e0_j));
    c.push(num(l.lost_before_bang_j));
    c.push(num(l.lost_before_bang_j / l.e0_j));
    c.push(opt(report
        .milestones
        .iter()
        .find(|m| m.key == MilestoneKey::TwoB)
        .and_then(|m| m.dissipated_j)
        .map(|d| d / l.e0_j)));
    c.push(num(report.max_energy_rise_rel));
    c.push(num(report.approach.peak_xdot_m_s));
    c.push(num(report.approach.peak_r_m));
    for kind in [
        LimitKind::LiftOff,
        LimitKind::LeavesExact,
        LimitKind::ExactModelHops,
    ] {
        let r = report
            .reference_limits
            .iter()
            .find(|l| l.kind == kind && l.t_s.is_some())
            .map(|l| l.r_m);
        c.push(opt(r));
    }
    c.extend(bang_cells(report));
    c.push(RowStatus::of(&report.stop).to_string());
    c
}

/// The [`BANG_COLUMNS`] cells of a finished run.
fn bang_cells(report: &RunReport) -> Vec<String> {
    let Some(b) = &report.bang else {
        return vec![String::new(); BANG_COLUMNS.len()];
    };
    let l = &report.ledger;
    let d = l.dissipated_by_bang_j;
    let of = |x: f64| num(x / d);
    let split = &l.bang;
    vec![
        num(b.kinetic_in_j),
        num(d),
        of(split.floor_normal_j),
        of(split.floor_friction_j),
        of(split.joints_j),
        of(split.freeze_j),
        of(split.residual_j),
        of(split.numerical_j()),
        num(b.top_speed_m_s),
        num(b.duration_s),
        num(b.peak_floor_force_n),
        num(b.floor_impulse_n_s),
        num(b.end_x_m),
        num(b.laid_length_m),
        num(b.still_moving_j / b.kinetic_in_j),
        num(report.wall_time_s - report.wall_time_rolling_s),
        b.ended_by.map_or_else(String::new, |e| {
            match e {
                crate::model::BangEnd::Rest => "rest",
                crate::model::BangEnd::Cap => "cap",
            }
            .to_owned()
        }),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_abs_needs_every_milestone() {
        assert_eq!(
            max_abs([Some(-0.2), Some(0.1)].into_iter()),
            Some(0.2_f64.abs())
        );
        assert_eq!(max_abs([Some(0.1), None].into_iter()), None);
    }
}
