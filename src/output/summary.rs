//! The readable summary printed after a run: the scene, how the run ended, the times
//! against the references, the energy ledger, the final bang, the guards' maxima and where
//! the references stop applying. It reads a [`RunReport`]; it writes no file.

use std::fmt::Write as _;
use std::path::Path;

use crate::output::compare::paradox;
use crate::output::folder::{REPORT, SAMPLES};
use crate::run::RunReport;
use crate::run::report::MilestoneKey;
use crate::run::stop::Status;
use crate::theory::rivals::Case;

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
    // In the order the run reaches them: 2b comes before 0.1R on a thick tape.
    let mut milestones: Vec<_> = report.milestones.iter().collect();
    milestones.sort_by(|a, b| a.laid_fraction.total_cmp(&b.laid_fraction));
    for m in milestones {
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
    let _ = writeln!(
        o,
        "Time to reach each laid fraction f, against the analyses of {} (the simulation's time over \
         the rival's, minus 1, as sim/ex elsewhere; * = the reference the simulation must converge to):",
        Case::of(&report.scene).section()
    );
    o.push_str(&paradox(report).text("  "));
    for r in &report.rivals {
        let _ = writeln!(o, "  {}: {}", r.label, r.description);
    }
}

/// The final bang's part of the summary: what it received, where that energy went by
/// mechanism, how violent it was and where the tape ended.
fn bang_summary(
    o: &mut String,
    report: &RunReport,
    bang: &crate::run::BangReport,
    overrides: &[String],
) {
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
        "  received {:.5} J of kinetic energy, every speed scaled by {:.4} at the release for \
         the pieces' thickness (the energy kept); fastest point {:.4} m/s; peak floor force \
         {:.4e} N; floor impulse {:.4e} N s",
        bang.kinetic_in_j,
        bang.thickness_speed_ratio,
        bang.top_speed_m_s,
        bang.peak_floor_force_n,
        bang.floor_impulse_n_s
    );
    let d = l.dissipated_by_bang_j;
    let b = &l.bang;
    if l.bang_split_meaningful() {
        let of = |x: f64| 100.0 * x / d;
        let _ = writeln!(
            o,
            "  dissipated {d:.5} J, measured where it happened (shares of what it dissipated): \
             floor impacts {:.5} J ({:.1} %), floor friction {:.5} J ({:.1} %), layers' impacts \
             {:.5} J ({:.1} %), layers' friction {:.5} J ({:.1} %), freezing {:.5} J ({:.2} %);",
            b.floor_normal_j,
            of(b.floor_normal_j),
            b.floor_friction_j,
            of(b.floor_friction_j),
            b.layers_normal_j,
            of(b.layers_normal_j),
            b.layers_friction_j,
            of(b.layers_friction_j),
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
        let _ = writeln!(
            o,
            "  one landing: a landing is chaotic, and the split's mean and its standard error \
             come from an ensemble of pushes: `{}`",
            ensemble_command(report, overrides)
        );
    } else {
        let _ = writeln!(
            o,
            "  dissipated {d:.5} J ({:.3} % of S): too little to split by mechanism (under {} %)",
            100.0 * d / l.energy_scale_j,
            100.0 * crate::run::BANG_SPLIT_MIN_OF_SCALE
        );
    }
    if report.scene.axis.fixed {
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

/// The readable summary printed after a run; `overrides` are the run's `--set` arguments
/// (`KEY=VALUE`), which the commands it suggests repeat.
pub fn summary(report: &RunReport, out_dir: &Path, overrides: &[String]) -> String {
    let s = &report.scene;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "uncoil: {} (R = {} m, b = {} m, M = {} kg, push {} m/s, friction {})",
        s.name,
        s.tape.outer_radius_m,
        s.tape.thickness_m,
        s.tape.mass_kg,
        s.push.contact_speed_m_s,
        s.floor.friction
    );
    let _ = writeln!(
        o,
        "  {} links ({} per turn), {} steps, {:.3} s simulated in {:.3} s wall ({:.3} s to the bang); {}: {}",
        report.links,
        s.discretisation.links_per_turn,
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
    ledger_summary(&mut o, report);
    if let Some(bang) = &report.bang {
        let _ = writeln!(o);
        bang_summary(&mut o, report, bang, overrides);
    }
    let _ = writeln!(o);
    health_summary(&mut o, report);
    let _ = writeln!(
        o,
        "Wrote {} and {}",
        out_dir.join(SAMPLES).display(),
        out_dir.join(REPORT).display()
    );
    o
}

/// The command that lands this scene, with the run's `overrides`, from its push and the
/// seven just above it (`uncoil run --ensemble`), and prints the split's mean and error. A
/// shipped scene by its name; another by a placeholder for its file.
fn ensemble_command(report: &RunReport, overrides: &[String]) -> String {
    let name = &report.scene.name;
    let scene = if crate::scene::shipped::text(name).is_some() {
        name.clone()
    } else {
        "SCENE.toml".to_owned()
    };
    let mut command = format!("uncoil run {scene} --ensemble 8");
    for o in overrides {
        command.push_str(" --set ");
        command.push_str(&crate::output::shell_word(Path::new(o)));
    }
    command
}

/// An ensemble's `n` pushes from `v` (m/s), its first and last as written: steps of a
/// hundredth of the push's decade (0.300, 0.301, ... for 0.3 m/s), a third of a percent
/// apart, so that the landings differ and the unrolls hardly do.
pub fn ensemble_pushes(v: f64, n: usize) -> (String, String) {
    let decimals = (2.0 - v.log10().floor()).clamp(0.0, 12.0);
    let step = 10f64.powf(-decimals);
    let push = |k: f64| format!("{:.*}", decimals as usize, v + step * k);
    (push(0.0), push(n.saturating_sub(1) as f64))
}

/// The energy ledger: E0, what was lost before the bang and where, what the bang received
/// and dissipated, what is left.
fn ledger_summary(o: &mut String, report: &RunReport) {
    let l = &report.ledger;
    let pc = |x: f64| 100.0 * x / l.energy_scale_j;
    let _ = writeln!(
        o,
        "Energy ledger (E0 = {:.4} J; MgR = {:.4} J; flat tape at rest keeps {:.4} J). Three \
         bases, each named where used: the ledger's percentages are of the energy scale S = {:.4} \
         J, the largest of |E0|, MgR and the kinetic energy into the bang; the bang's split is in \
         shares of what the bang dissipated; what is left moving, of what the bang received:",
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
        .find(|m| m.key == MilestoneKey::TwoB)
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
}

/// The guards' maxima against their bounds, and where the references stop applying.
fn health_summary(o: &mut String, report: &RunReport) {
    let _ = writeln!(
        o,
        "Max joint separation {:.2e} m (bound {:.2e}), max floor penetration {:.2e} m (bound {:.2e}).",
        report.max_joint_gap_m,
        report.bounds.joint_gap_m,
        report.max_penetration_m,
        report.bounds.penetration_m
    );
    if let Some(bang) = &report.bang {
        let b = report.scene.tape.thickness_m;
        if bang.layers {
            let _ = writeln!(
                o,
                "Deepest overlap of the tape's layers in the bang {:.2e} m ({:.3} % of b; bound {:.2e} m).",
                report.max_overlap_m,
                100.0 * report.max_overlap_m / b,
                report.bounds.overlap_m
            );
        } else {
            let _ = writeln!(
                o,
                "The tape's layers did not meet in the bang, which may pass through itself: the \
                 released coil's links stand {:.2e} m ({:.0} b) off their arcs, more than {} b, so \
                 its turns overlap before anything moves; more links a turn resolve it.",
                bang.chord_sag_m,
                bang.chord_sag_m / b,
                crate::model::LAYERS_RESOLVED_PER_THICKNESS
            );
        }
    }
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
                crate::run::limits::label(l.kind),
                secs(l.t_s),
                l.r_m,
                l.detail
            );
        }
    }
}
