//! The paradox table: for each scene, the time to reach its milestones in the simulation
//! and in every competing analytic equation of motion the paper gives for it, with the
//! relative differences. It formats a finished [`RunReport`]; it does not run anything.

use std::f64::consts::PI;
use std::fmt::Write as _;

mod forces;

pub use forces::{force_table, sim_sign_change, torque_table, window_mean, window_spread};

use crate::output::table::Table;
use crate::run::{Observer, RivalTimes, RunReport, Sample};
use crate::scene::Scene;
use crate::theory::rivals::{Case, SpoolGeometry, spool_spins};

/// Keeps the samples of a run, for the force table.
#[derive(Debug, Default)]
pub struct SampleLog {
    /// Every sample, in order.
    pub samples: Vec<Sample>,
}

impl Observer for SampleLog {
    fn observe_init(&mut self, _scene: &Scene) -> anyhow::Result<()> {
        Ok(())
    }
    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()> {
        self.samples.push(*sample);
        Ok(())
    }
    fn observe_final(&mut self, _report: &RunReport) -> anyhow::Result<()> {
        Ok(())
    }
}

/// The simulation's spin `|theta'|` where its unrolled angle first reaches `theta`
/// (linear between samples), `None` if it never does.
pub fn spin_at_theta(samples: &[Sample], theta: f64) -> Option<f64> {
    let i = samples.iter().position(|s| s.theta_rad >= theta)?;
    let b = &samples[i];
    let Some(a) = i.checked_sub(1).map(|j| &samples[j]) else {
        return Some(b.omega_rad_s.abs());
    };
    let w = (theta - a.theta_rad) / (b.theta_rad - a.theta_rad);
    Some(a.omega_rad_s.abs() + w * (b.omega_rad_s.abs() - a.omega_rad_s.abs()))
}

/// Turns at which [`spin_table`] reads the spin: three inside the first turn, where the
/// outer partial turn's weight modulates it most, then whole turns.
pub const SPIN_TURNS: [f64; 12] = [
    0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 40.0,
];

/// For the spool cases, the simulation's spin against each energy integral at
/// [`SPIN_TURNS`] (up to 90 % laid); empty for the other cases.
pub fn spin_table(report: &RunReport, samples: &[Sample]) -> String {
    let scene = &report.scene;
    let spins = spool_spins(scene);
    let mut o = String::new();
    if spins.is_empty() {
        return o;
    }
    let sg = SpoolGeometry::of(scene);
    let _ = writeln!(
        o,
        "Spin theta' (rad/s) after a number of turns: the energy integrals centre the wound tape \
         on the axis, the spiral's outer partial turn is off it except at whole turns.\n"
    );
    let mut table = Table::new(["turns", "f", "sim"]);
    table
        .header
        .extend(spins.iter().map(|(label, _)| label.clone()));
    for k in SPIN_TURNS {
        let theta = 2.0 * PI * k;
        let f = sg.r_m * theta / sg.l_m;
        if f > 0.9 {
            break;
        }
        let Some(w) = spin_at_theta(samples, theta) else {
            break;
        };
        let mut row = vec![k.to_string(), format!("{f:.4}"), format!("{w:.4}")];
        row.extend(spins.iter().map(|(_, spin)| {
            let wr = spin(theta);
            format!("{wr:.4} ({:+.2}%)", 100.0 * (wr / w - 1.0))
        }));
        table.push(row);
    }
    o.push_str(&table.markdown());
    let _ = writeln!(o);
    o
}

/// `t_sim / t - 1` as a signed percentage (the simulation against the rival `t`), or a dash.
fn rel(t: Option<f64>, t_sim: Option<f64>) -> String {
    match (t, t_sim) {
        (Some(t), Some(s)) if t > 0.0 => format!("{:+.2}%", 100.0 * (s / t - 1.0)),
        _ => "-".into(),
    }
}

/// One rival's time `t` at the laid fraction `f` with its difference to the
/// simulation's, or why it has none.
pub fn cell(rival: &RivalTimes, t: Option<f64>, f: f64, t_sim: Option<f64>) -> String {
    match t {
        Some(t) => format!("{t:.4} ({})", rel(Some(t), t_sim)),
        None => match rival.stall_fraction {
            Some(s) if f > s => format!("stops at f={s:.4}"),
            _ => "not reached".into(),
        },
    }
}

/// The paradox table of a run: each milestone's time in the simulation and in every rival
/// the paper gives for its case, with the simulation's time over the rival's minus 1 (as
/// `uncoil run` prints sim/ex: negative where the simulation is ahead); `*`
/// marks the reference the simulation must converge to.
pub fn paradox(report: &RunReport) -> Table {
    let rv = &report.rivals;
    let mut table = Table::new(["milestone", "f", "sim s"]);
    table.header.extend(
        rv.iter()
            .map(|r| format!("{}{} s", r.label, if r.valid { " *" } else { "" })),
    );
    for (k, m) in report.milestones.iter().enumerate() {
        let mut row = vec![
            m.label.clone(),
            format!("{:.4}", m.laid_fraction),
            m.t_sim_s
                .map_or("not reached".into(), |t| format!("{t:.4}")),
        ];
        row.extend(
            rv.iter()
                .map(|r| cell(r, r.t_s[k], m.laid_fraction, m.t_sim_s)),
        );
        table.push(row);
    }
    table
}

/// The markdown table of one scene's run against its rivals, then its force table.
pub fn table(report: &RunReport, samples: &[Sample]) -> String {
    let scene = &report.scene;
    let case = Case::of(scene);
    let rv = &report.rivals;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "#### {} ({}; R = {} m, b = {} m, core {} m, push {} m/s, friction {}, slope {} deg, g = {})\n",
        scene.name,
        case.section(),
        scene.tape.outer_radius_m,
        scene.tape.thickness_m,
        scene.tape.core_radius_m,
        scene.push.contact_speed_m_s,
        scene.floor.friction,
        scene.floor.slope_deg,
        scene.gravity.g_m_s2,
    );
    o.push_str(&paradox(report).markdown());
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "Percentages: the simulation's time over the rival's, minus 1 (negative: the simulation \
         is ahead). * = the reference the \
         simulation must converge to."
    );
    for r in rv {
        let _ = writeln!(o, "- `{}`: {}", r.label, r.description);
    }
    let l = &report.ledger;
    let _ = writeln!(
        o,
        "- energy: E0 = {:.4} J, lost before the bang {:.5} J ({:.2}% of what the bang would \
         otherwise receive), kinetic into the bang {:.4} J",
        l.e0_j,
        l.lost_before_bang_j,
        100.0 * l.lost_before_bang_j / (l.lost_before_bang_j + l.kinetic_into_bang_j),
        l.kinetic_into_bang_j
    );
    let _ = writeln!(o);
    o.push_str(&spin_table(report, samples));
    o.push_str(&force_table(report, samples));
    if matches!(Case::of(scene), Case::Coil | Case::Slope | Case::ZeroG) {
        o.push_str(&torque_table(report, samples));
    }
    o
}
