//! The paradox table: for each scene, the time to reach its milestones in the simulation
//! and in every competing analytic equation of motion the paper gives for it, with the
//! relative differences. It formats a finished [`RunReport`]; it does not run anything.

use std::f64::consts::PI;
use std::fmt::Write as _;

use crate::forces::{force_reference, sign_change_fraction};
use crate::rivals::{Case, Rival, SpoolGeometry, rivals, spool_spins};
use crate::run::{Observer, RunReport, Sample};
use crate::scene::Scene;

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

/// Laid fractions of the force table.
const FORCE_FRACTIONS: [f64; 5] = [0.1, 0.25, 0.5, 0.75, 0.9];
/// Half-width of the laid-fraction window the simulated forces are averaged over.
const FORCE_WINDOW: f64 = 0.01;

/// Mean of `value` over the rolling-phase samples with laid fraction within `half` of `f`.
pub fn window_mean(
    samples: &[Sample],
    f: f64,
    half: f64,
    value: impl Fn(&Sample) -> f64,
) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0u32);
    for s in samples
        .iter()
        .filter(|s| (s.laid_fraction - f).abs() <= half)
    {
        let v = value(s);
        if v.is_finite() {
            sum += v;
            n += 1;
        }
    }
    (n > 0).then(|| sum / f64::from(n))
}

/// The first laid fraction up to `f_max` at which the simulated `F_tot`, averaged over
/// windows of 0.02,
/// changes sign.
pub fn sim_sign_change(samples: &[Sample], f_max: f64) -> Option<f64> {
    let mut prev: Option<(f64, f64)> = None;
    let mut f = FORCE_WINDOW;
    while f <= f_max {
        if let Some(v) = window_mean(samples, f, FORCE_WINDOW, |s| s.f_tot_n) {
            if let Some((f0, v0)) = prev
                && v0.signum() != v.signum()
            {
                return Some(f0 + (f - f0) * v0 / (v0 - v));
            }
            prev = Some((f, v));
        }
        f += 2.0 * FORCE_WINDOW;
    }
    None
}

/// The constraint-force table of one run: the simulation's `N_tot`, `F_tot` (momentum
/// balance) and floor contact forces beside the case's analytic forms.
pub fn force_table(report: &RunReport, samples: &[Sample]) -> String {
    let mut o = String::new();
    let Some(forces) = force_reference(&report.scene) else {
        let _ = writeln!(
            o,
            "Constraint forces: no analytic form for this case (a frictionless floor exerts no \
             horizontal force; a fixed axis has no floor)."
        );
        return o;
    };
    let _ = writeln!(
        o,
        "| f | N_tot sim N | N_tot ref N | F_tot sim N | F_tot ref N | floor contact N, F (sim) N |"
    );
    let _ = writeln!(o, "|---|---|---|---|---|---|");
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.4}"));
    for f in FORCE_FRACTIONS {
        let mean = |g: fn(&Sample) -> f64| window_mean(samples, f, FORCE_WINDOW, g);
        let reference = forces(f);
        let _ = writeln!(
            o,
            "| {f} | {} | {} | {} | {} | {}, {} |",
            show(mean(|s| s.n_tot_n)),
            show(reference.map(|r| r.0)),
            show(mean(|s| s.f_tot_n)),
            show(reference.map(|r| r.1)),
            show(mean(|s| s.normal_n)),
            show(mean(|s| s.friction_n)),
        );
    }
    let last = report
        .milestones
        .iter()
        .filter_map(|m| m.t_sim_s.map(|_| m.laid_fraction))
        .fold(0.0, f64::max)
        .min(0.95);
    let _ = writeln!(
        o,
        "\nSimulated forces are averaged over laid fractions f +- {FORCE_WINDOW}. F_tot changes sign \
         at f = {} in the simulation and at f = {} in the reference.",
        show(sim_sign_change(samples, last)),
        show(sign_change_fraction(&forces, last)),
    );
    o
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
    let mut head = String::from("| turns | f | sim |");
    let mut rule = String::from("|---|---|---|");
    for (label, _) in &spins {
        let _ = write!(head, " {label} |");
        rule.push_str("---|");
    }
    let _ = writeln!(o, "{head}\n{rule}");
    for k in SPIN_TURNS {
        let theta = 2.0 * PI * k;
        let f = sg.r_m * theta / sg.l_m;
        if f > 0.9 {
            break;
        }
        let Some(w) = spin_at_theta(samples, theta) else {
            break;
        };
        let mut row = format!("| {k} | {f:.4} | {w:.4} |");
        for (_, spin) in &spins {
            let wr = spin(theta);
            let _ = write!(row, " {wr:.4} ({:+.2}%) |", 100.0 * (wr / w - 1.0));
        }
        let _ = writeln!(o, "{row}");
    }
    let _ = writeln!(o);
    o
}

/// `t / t_sim - 1` as a signed percentage, or a dash.
fn rel(t: Option<f64>, t_sim: Option<f64>) -> String {
    match (t, t_sim) {
        (Some(t), Some(s)) if s > 0.0 => format!("{:+.2}%", 100.0 * (t / s - 1.0)),
        _ => "-".into(),
    }
}

/// One rival's time at `f` with its difference to the simulation, or why it has none.
pub fn cell(rival: &Rival, f: f64, t_sim: Option<f64>) -> String {
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

/// The markdown table of one scene's run against its rivals, then its force table.
pub fn table(report: &RunReport, samples: &[Sample]) -> String {
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
    o
}
