//! The paradox table: for each scene, the time to reach its milestones in the simulation
//! and in every competing analytic equation of motion the paper gives for it, with the
//! relative differences. It formats a finished [`RunReport`]; it does not run anything.

use std::fmt::Write as _;

use crate::rivals::{Case, Rival, rivals};
use crate::run::RunReport;

/// `t / t_sim - 1` as a signed percentage, or a dash.
fn rel(t: Option<f64>, t_sim: Option<f64>) -> String {
    match (t, t_sim) {
        (Some(t), Some(s)) if s > 0.0 => format!("{:+.2}%", 100.0 * (t / s - 1.0)),
        _ => "-".into(),
    }
}

fn cell(rival: &Rival, f: f64, t_sim: Option<f64>) -> String {
    match rival.time_at_fraction(f) {
        Some(t) => format!("{t:.4} ({})", rel(Some(t), t_sim)),
        None => match rival.stall_fraction {
            Some(s) if f > s => format!("stops at f={s:.4}"),
            _ => "not reached".into(),
        },
    }
}

/// The largest `|t_sim / t_valid - 1|` over the milestones where both exist, with the
/// label of the valid reference; `None` if the case has no valid reference.
pub fn worst_error_vs_valid(report: &RunReport) -> Option<(String, f64)> {
    let rv = rivals(&report.scene);
    let valid = rv.iter().find(|r| r.valid)?;
    let worst = report
        .milestones
        .iter()
        .filter_map(|m| {
            let t = valid.time_at_fraction(m.laid_fraction)?;
            Some((m.t_sim_s? / t - 1.0).abs())
        })
        .fold(0.0, f64::max);
    Some((valid.label.clone(), worst))
}

/// The markdown table of one scene's run against its rivals.
pub fn table(report: &RunReport) -> String {
    let scene = &report.scene;
    let case = Case::of(scene);
    let rv = rivals(scene);
    let mut o = String::new();
    let _ = writeln!(
        o,
        "#### {} ({}; R = {} m, b = {} m, core {} m, push {} m/s, friction {}, slope {} deg, g = {})\n",
        scene.name,
        case.section(),
        scene.tape.outer_radius_m,
        scene.tape.thickness_m,
        scene.tape.core_radius_m,
        scene.push_speed_m_s,
        scene.friction,
        scene.slope_deg,
        scene.g_m_s2,
    );
    let mut head = String::from("| milestone | f | sim s |");
    let mut rule = String::from("|---|---|---|");
    for r in &rv {
        let star = if r.valid { " *" } else { "" };
        let _ = write!(head, " {}{star} s |", r.label);
        rule.push_str("---|");
    }
    let _ = writeln!(o, "{head}\n{rule}");
    for m in &report.milestones {
        let mut row = format!(
            "| {} | {:.4} | {} |",
            m.label,
            m.laid_fraction,
            m.t_sim_s
                .map_or("not reached".into(), |t| format!("{t:.4}"))
        );
        for r in &rv {
            let _ = write!(row, " {} |", cell(r, m.laid_fraction, m.t_sim_s));
        }
        let _ = writeln!(o, "{row}");
    }
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "Percentages: the rival's time over the simulation's, minus 1. * = the reference the \
         simulation must converge to."
    );
    for r in &rv {
        let _ = writeln!(o, "- `{}`: {}", r.label, r.description);
    }
    let l = &report.ledger;
    let _ = writeln!(
        o,
        "- energy: E0 = {:.4} J, lost before the bang {:.5} J ({:.2}% of E0), kinetic into the bang {:.4} J",
        l.e0_j,
        l.lost_before_bang_j,
        100.0 * l.lost_before_bang_j / l.e0_j,
        l.kinetic_into_bang_j
    );
    o
}
