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

/// A column of `sweep.csv` other than the varied keys and the milestones' errors: the one
/// place its name is spelt and its cell is made, so the header and the cells cannot drift
/// apart, and a reader names the column it wants by this type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Col {
    /// The combination's place in the full grid: [`INDEX_COLUMN`].
    Index,
    /// Links in the chain.
    Links,
    /// Engine steps taken.
    Steps,
    /// Runs the sweep ran at once.
    Jobs,
    /// The run's engine time (s).
    Wall,
    /// Its part before the final bang (s).
    WallRolling,
    /// Simulated time (s).
    SimTime,
    /// When the bang began (s).
    BangTime,
    /// Largest milestone time error against the exact-geometry model.
    MaxErrGeo,
    /// Largest milestone time error against eq. (7).
    MaxErrEq7,
    /// The energy at the start (J).
    E0,
    /// Lost before the bang (J).
    LostBeforeBang,
    /// Lost before the bang, of the energy at the start.
    LostBeforeBangOfE0,
    /// Lost before r = 2b, of the energy at the start.
    LostBefore2bOfE0,
    /// The largest energy rise in a step, relative.
    MaxEnergyRiseRel,
    /// The approach's peak contact-line speed (m/s).
    PeakXdot,
    /// The radius at that peak (m).
    PeakR,
    /// Where the coil lifted off (m).
    LiftOffR,
    /// Where the motion left the exact model's (m).
    LeavesExactR,
    /// Where the exact model predicts a hop (m).
    ExactHopsR,
    /// The kinetic energy the bang received (J).
    BangKineticIn,
    /// What the bang dissipated (J).
    BangDissipated,
    /// Its share to floor impacts.
    BangFloorNormalOf,
    /// Its share to floor friction.
    BangFloorFrictionOf,
    /// Its share to the layers' impacts on each other.
    BangLayersNormalOf,
    /// Its share to the layers' friction on each other.
    BangLayersFrictionOf,
    /// Its share to the joints.
    BangJointsOf,
    /// Its share to frozen links.
    BangFreezeOf,
    /// Its residual share.
    BangResidualOf,
    /// Its numerical share (joints and residual).
    BangNumericalOf,
    /// The bang's top speed (m/s).
    BangTopSpeed,
    /// The bang's duration (s).
    BangDuration,
    /// The bang's peak floor force (N).
    BangPeakFloorForce,
    /// The bang's floor impulse (N s).
    BangFloorImpulse,
    /// Where the free end came to rest (m).
    BangEndX,
    /// Tape laid by the bang (m).
    BangLaidLength,
    /// Still moving at the bang's end, of what it received.
    BangStillMovingOf,
    /// The bang's engine time (s).
    BangWall,
    /// What ended the bang: `rest` or `cap`.
    BangEndedBy,
    /// How the run ended: [`STATUS_COLUMN`], a [`RowStatus`].
    Status,
}

impl Col {
    /// The columns before the milestones' errors.
    const HEAD: [Self; 7] = [
        Self::Links,
        Self::Steps,
        Self::Jobs,
        Self::Wall,
        Self::WallRolling,
        Self::SimTime,
        Self::BangTime,
    ];
    /// The columns after them, the bang's and the status excepted.
    const MID: [Self; 12] = [
        Self::MaxErrGeo,
        Self::MaxErrEq7,
        Self::E0,
        Self::LostBeforeBang,
        Self::LostBeforeBangOfE0,
        Self::LostBefore2bOfE0,
        Self::MaxEnergyRiseRel,
        Self::PeakXdot,
        Self::PeakR,
        Self::LiftOffR,
        Self::LeavesExactR,
        Self::ExactHopsR,
    ];
    /// The final bang's columns (empty cells for a run stopped before the bang): what it
    /// received and dissipated, the split of what it dissipated by mechanism (fractions), its
    /// observables, and what ended it.
    pub const BANG: [Self; 19] = [
        Self::BangKineticIn,
        Self::BangDissipated,
        Self::BangFloorNormalOf,
        Self::BangFloorFrictionOf,
        Self::BangLayersNormalOf,
        Self::BangLayersFrictionOf,
        Self::BangJointsOf,
        Self::BangFreezeOf,
        Self::BangResidualOf,
        Self::BangNumericalOf,
        Self::BangTopSpeed,
        Self::BangDuration,
        Self::BangPeakFloorForce,
        Self::BangFloorImpulse,
        Self::BangEndX,
        Self::BangLaidLength,
        Self::BangStillMovingOf,
        Self::BangWall,
        Self::BangEndedBy,
    ];

    /// The column's name in `sweep.csv`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Index => INDEX_COLUMN,
            Self::Links => "links",
            Self::Steps => "steps",
            Self::Jobs => "jobs",
            Self::Wall => "wall_s",
            Self::WallRolling => "wall_rolling_s",
            Self::SimTime => "sim_time_s",
            Self::BangTime => "bang_time_s",
            Self::MaxErrGeo => "max_err_geo",
            Self::MaxErrEq7 => "max_err_eq7",
            Self::E0 => "e0_j",
            Self::LostBeforeBang => "lost_before_bang_j",
            Self::LostBeforeBangOfE0 => "lost_before_bang_of_e0",
            Self::LostBefore2bOfE0 => "lost_before_2b_of_e0",
            Self::MaxEnergyRiseRel => "max_energy_rise_rel",
            Self::PeakXdot => "peak_xdot_m_s",
            Self::PeakR => "peak_r_m",
            Self::LiftOffR => "lift_off_r_m",
            Self::LeavesExactR => "leaves_exact_r_m",
            Self::ExactHopsR => "exact_hops_r_m",
            Self::BangKineticIn => "bang_kinetic_in_j",
            Self::BangDissipated => "bang_dissipated_j",
            Self::BangFloorNormalOf => "bang_floor_normal_of",
            Self::BangFloorFrictionOf => "bang_floor_friction_of",
            Self::BangLayersNormalOf => "bang_layers_normal_of",
            Self::BangLayersFrictionOf => "bang_layers_friction_of",
            Self::BangJointsOf => "bang_joints_of",
            Self::BangFreezeOf => "bang_freeze_of",
            Self::BangResidualOf => "bang_residual_of",
            Self::BangNumericalOf => "bang_numerical_of",
            Self::BangTopSpeed => "bang_top_speed_m_s",
            Self::BangDuration => "bang_duration_s",
            Self::BangPeakFloorForce => "bang_peak_floor_force_n",
            Self::BangFloorImpulse => "bang_floor_impulse_n_s",
            Self::BangEndX => "bang_end_x_m",
            Self::BangLaidLength => "bang_laid_length_m",
            Self::BangStillMovingOf => "bang_still_moving_of",
            Self::BangWall => "bang_wall_s",
            Self::BangEndedBy => "bang_ended_by",
            Self::Status => STATUS_COLUMN,
        }
    }

    /// The column's cell for a finished run of a sweep that ran `jobs` at once; empty where
    /// the run has no such figure. The index is the grid's, not the run's: empty here.
    fn cell(self, report: &RunReport, jobs: usize) -> String {
        let l = &report.ledger;
        let milestones = &report.milestones;
        let limit = |kind: LimitKind| {
            report
                .reference_limits
                .iter()
                .find(|l| l.kind == kind && l.t_s.is_some())
                .map(|l| l.r_m)
        };
        match self {
            Self::Index => String::new(),
            Self::Links => report.links.to_string(),
            Self::Steps => report.steps.to_string(),
            Self::Jobs => jobs.to_string(),
            Self::Wall => num(report.wall_time_s),
            Self::WallRolling => num(report.wall_time_rolling_s),
            Self::SimTime => num(report.sim_time_s),
            Self::BangTime => opt(l.bang_time_s),
            Self::MaxErrGeo => opt(max_abs(milestones.iter().map(|m| m.err_vs_geo))),
            Self::MaxErrEq7 => opt(max_abs(milestones.iter().map(|m| m.err_vs_eq7))),
            Self::E0 => num(l.e0_j),
            Self::LostBeforeBang => num(l.lost_before_bang_j),
            Self::LostBeforeBangOfE0 => num(l.lost_before_bang_j / l.e0_j),
            Self::LostBefore2bOfE0 => opt(milestones
                .iter()
                .find(|m| m.key == MilestoneKey::TwoB)
                .and_then(|m| m.dissipated_j)
                .map(|d| d / l.e0_j)),
            Self::MaxEnergyRiseRel => num(report.max_energy_rise_rel),
            Self::PeakXdot => num(report.approach.peak_xdot_m_s),
            Self::PeakR => num(report.approach.peak_r_m),
            Self::LiftOffR => opt(limit(LimitKind::LiftOff)),
            Self::LeavesExactR => opt(limit(LimitKind::LeavesExact)),
            Self::ExactHopsR => opt(limit(LimitKind::ExactModelHops)),
            Self::Status => RowStatus::of(&report.stop).to_string(),
            bang => bang.bang_cell(report),
        }
    }

    /// A [`Col::BANG`] cell of a finished run.
    fn bang_cell(self, report: &RunReport) -> String {
        let Some(b) = &report.bang else {
            return String::new();
        };
        let l = &report.ledger;
        let of = |x: f64| num(x / l.dissipated_by_bang_j);
        let split = &l.bang;
        match self {
            Self::BangKineticIn => num(b.kinetic_in_j),
            Self::BangDissipated => num(l.dissipated_by_bang_j),
            Self::BangFloorNormalOf => of(split.floor_normal_j),
            Self::BangFloorFrictionOf => of(split.floor_friction_j),
            Self::BangLayersNormalOf => of(split.layers_normal_j),
            Self::BangLayersFrictionOf => of(split.layers_friction_j),
            Self::BangJointsOf => of(split.joints_j),
            Self::BangFreezeOf => of(split.freeze_j),
            Self::BangResidualOf => of(split.residual_j),
            Self::BangNumericalOf => of(split.numerical_j()),
            Self::BangTopSpeed => num(b.top_speed_m_s),
            Self::BangDuration => num(b.duration_s),
            Self::BangPeakFloorForce => num(b.peak_floor_force_n),
            Self::BangFloorImpulse => num(b.floor_impulse_n_s),
            Self::BangEndX => num(b.end_x_m),
            Self::BangLaidLength => num(b.laid_length_m),
            Self::BangStillMovingOf => num(b.still_moving_j / b.kinetic_in_j),
            Self::BangWall => num(report.wall_time_s - report.wall_time_rolling_s),
            Self::BangEndedBy => b.ended_by.map_or_else(String::new, |e| {
                match e {
                    crate::model::BangEnd::Rest => "rest",
                    crate::model::BangEnd::Cap => "cap",
                }
                .to_owned()
            }),
            _ => unreachable!("{self:?} is not a bang column"),
        }
    }
}

/// The prefix of the milestones' time errors against the exact-geometry model:
/// `err_geo_<label>`.
pub const ERR_GEO_PREFIX: &str = "err_geo_";
/// The prefix of the milestones' time errors against eq. (7): `err_eq7_<label>`.
pub const ERR_EQ7_PREFIX: &str = "err_eq7_";
/// The prefix of the milestones' simulated times (s): `t_sim_<label>`.
pub const T_SIM_PREFIX: &str = "t_sim_";

/// Column names after the varied keys, for a scene's milestone labels.
pub fn result_columns(milestone_labels: &[String]) -> Vec<String> {
    let names = |cols: &[Col]| cols.iter().map(|c| c.name().to_owned()).collect::<Vec<_>>();
    let mut c = names(&Col::HEAD);
    c.extend(
        milestone_labels
            .iter()
            .map(|l| format!("{ERR_GEO_PREFIX}{l}")),
    );
    c.extend(
        milestone_labels
            .iter()
            .map(|l| format!("{ERR_EQ7_PREFIX}{l}")),
    );
    c.extend(
        milestone_labels
            .iter()
            .map(|l| format!("{T_SIM_PREFIX}{l}")),
    );
    c.extend(names(&Col::MID));
    c.extend(names(&Col::BANG));
    c.push(Col::Status.name().to_owned());
    c
}

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

/// The result cells of a finished run, in [`result_columns`] order for the sweep's
/// milestone `labels` (a milestone the run's scene does not have is an empty cell).
pub fn result_cells(report: &RunReport, jobs: usize, labels: &[String]) -> Vec<String> {
    let cells = |cols: &[Col]| {
        cols.iter()
            .map(|c| c.cell(report, jobs))
            .collect::<Vec<_>>()
    };
    let milestone = |l: &String| report.milestones.iter().find(|m| m.key.to_string() == *l);
    let mut c = cells(&Col::HEAD);
    c.extend(
        labels
            .iter()
            .map(|l| opt(milestone(l).and_then(|m| m.err_vs_geo))),
    );
    c.extend(
        labels
            .iter()
            .map(|l| opt(milestone(l).and_then(|m| m.err_vs_eq7))),
    );
    c.extend(
        labels
            .iter()
            .map(|l| opt(milestone(l).and_then(|m| m.t_sim_s))),
    );
    c.extend(cells(&Col::MID));
    c.extend(cells(&Col::BANG));
    c.push(Col::Status.cell(report, jobs));
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_has_a_cell_under_every_column() {
        let scene = crate::scene::tests::short_yoga(0.02);
        let report = crate::run::run(&scene, &mut []).unwrap();
        let labels: Vec<String> = report.milestones.iter().map(|m| m.label.clone()).collect();
        let columns = result_columns(&labels);
        let cells = result_cells(&report, 1, &labels);
        assert_eq!(columns.len(), cells.len());
        let at = |c: Col| cells[columns.iter().position(|n| n == c.name()).unwrap()].clone();
        assert_eq!(at(Col::Links), report.links.to_string());
        assert_eq!(at(Col::Status).parse::<RowStatus>(), Ok(RowStatus::MaxTime));
        // Stopped before the bang: every bang cell empty.
        assert!(Col::BANG.iter().all(|&c| at(c).is_empty()));
    }

    #[test]
    fn max_abs_needs_every_milestone() {
        assert_eq!(
            max_abs([Some(-0.2), Some(0.1)].into_iter()),
            Some(0.2_f64.abs())
        );
        assert_eq!(max_abs([Some(0.1), None].into_iter()), None);
    }
}
