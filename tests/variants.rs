//! Every variant of the paper as a scene: the run against its valid reference, the energy
//! ledger, and what the paradox table shows (the competing equations that it does not follow).

use crate::support::run_kept;
use uncoil::output::compare::{SPIN_TURNS, sim_sign_change, spin_at_theta, window_mean};
use uncoil::run::stop::Status;
use uncoil::run::{RunReport, Sample};
use uncoil::scene::Scene;
use uncoil::theory::forces::{force_reference, sign_change_fraction};
use uncoil::theory::rivals::{Rival, rivals, spool_spins};

fn scene(name: &str) -> Scene {
    Scene::from_file(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn rival<'a>(rv: &'a [Rival], label: &str) -> &'a Rival {
    rv.iter()
        .find(|r| r.label == label)
        .unwrap_or_else(|| panic!("no rival {label}"))
}

/// `t_rival / t_sim - 1` at every milestone the simulation and the rival both reach.
fn errors(report: &RunReport, r: &Rival) -> Vec<(String, f64)> {
    report
        .milestones
        .iter()
        .filter_map(|m| {
            let t = r.time_at_fraction(m.laid_fraction)?;
            Some((m.label.clone(), t / m.t_sim_s? - 1.0))
        })
        .collect()
}

/// The simulation's spin against an energy integral `theta'(theta)` at the turns of
/// [`SPIN_TURNS`] up to 90 % laid: `(turns, spin_ref / spin_sim - 1)`.
fn spin_errors(s: &Scene, samples: &[Sample], spin: &dyn Fn(f64) -> f64) -> Vec<(f64, f64)> {
    let sg = uncoil::theory::rivals::SpoolGeometry::of(s);
    SPIN_TURNS
        .iter()
        .map(|&k| (k, 2.0 * std::f64::consts::PI * k))
        .take_while(|&(_, theta)| sg.r_m * theta / sg.l_m <= 0.9)
        .map(|(k, theta)| {
            let w = spin_at_theta(samples, theta).expect("reached");
            (k, spin(theta) / w - 1.0)
        })
        .collect()
}

/// Whole turns within `tol` of the integral; inside the first turn, off by more than `ripple`.
fn assert_spin_at_whole_turns(errs: &[(f64, f64)], tol: f64, ripple: f64, label: &str) {
    assert!(errs.len() >= 9, "{errs:?}");
    for &(k, e) in errs {
        if k.fract() == 0.0 {
            assert!(
                e.abs() < tol,
                "{label} after {k} turns: {:+.2} %",
                100.0 * e
            );
        }
    }
    let first = errs.iter().filter(|(k, _)| *k < 1.0).map(|(_, e)| e.abs());
    assert!(first.fold(0.0, f64::max) > ripple, "{label}: {errs:?}");
}

/// The target of the issue: within 1 % of the valid reference at every milestone.
fn assert_converges(report: &RunReport, r: &Rival, milestones: usize) {
    assert!(r.valid, "{} is not the scene's valid reference", r.label);
    let errs = errors(report, r);
    assert_eq!(errs.len(), milestones, "milestones reached: {errs:?}");
    for (label, e) in &errs {
        assert!(
            e.abs() <= 0.01,
            "{}: {label}: {} off by {:+.3} %",
            report.scene.name,
            r.label,
            100.0 * e
        );
    }
}

/// `N_tot` within `n_tol` (relative) of the analytic force at the given laid fractions, and
/// `F_tot` within `f_tol` of `N_tot`'s scale, both averaged over f +- 0.01.
fn assert_forces_follow(s: &Scene, samples: &[Sample], fractions: &[f64], n_tol: f64, f_tol: f64) {
    let forces = force_reference(s).expect("an analytic force");
    for &f in fractions {
        let (n_ref, f_ref) = forces(f).unwrap();
        let n = window_mean(samples, f, 0.01, |s| s.n_tot_n).unwrap();
        let fx = window_mean(samples, f, 0.01, |s| s.f_tot_n).unwrap();
        assert!(
            (n / n_ref - 1.0).abs() < n_tol,
            "{}: f = {f}: N_tot {n:.5} N, reference {n_ref:.5} N",
            s.name
        );
        assert!(
            (fx - f_ref).abs() < f_tol * n_ref,
            "{}: f = {f}: F_tot {fx:.5} N, reference {f_ref:.5} N",
            s.name
        );
    }
}

#[test]
fn yoga_mat_constraint_forces_follow_the_exact_model_and_change_sign_as_a7_says() {
    // The momentum balance of the moving part against the exact-geometry model's, the
    // floor's N on the coil against the exact model's (the laid tape pulls along the floor,
    // N_int = 0), F_tot against eq. (11) (= eq. 30 corrected, A6); with the push, F_tot
    // changes sign earlier than (2/5)^(1/3) R (f = 0.457), as A7 says.
    let s = scene("yoga-mat");
    let (samples, _) = run_kept(&s);
    let mg = s.tape.mass_kg * s.gravity.g_m_s2;
    for f in [0.1, 0.25, 0.5, 0.75, 0.9] {
        let mean = |g: fn(&Sample) -> f64| window_mean(&samples, f, 0.01, g).unwrap();
        for (what, sim, geo) in [
            ("N_tot", mean(|s| s.n_tot_n), mean(|s| s.n_tot_geo_n)),
            ("F_tot", mean(|s| s.f_tot_n), mean(|s| s.f_tot_geo_n)),
        ] {
            // The target: within 1 % of M g.
            assert!(
                (sim - geo).abs() < 0.01 * mg,
                "f = {f}: {what} {sim:.5} N, exact model {geo:.5} N"
            );
        }
        if f <= 0.75 {
            let (n, n_geo) = (mean(|s| s.n_floor_n), mean(|s| s.n_tot_geo_n));
            assert!(
                (n / n_geo - 1.0).abs() < 0.01,
                "f = {f}: floor's N {n:.5} N, exact model {n_geo:.5} N"
            );
        }
    }
    // The continuum's F_tot is an O(b/R) = 8 % idealisation of this thick mat, whose motion
    // follows the exact spiral: the simulated F_tot is 5 % (1.2 % of N_tot) above eq. (11)
    // at f = 0.75.
    let forces = force_reference(&s).unwrap();
    for f in [0.1, 0.25, 0.5, 0.75] {
        let (n_ref, f_ref) = forces(f).unwrap();
        let fx = window_mean(&samples, f, 0.01, |s| s.f_tot_n).unwrap();
        assert!(
            (fx - f_ref).abs() < 0.02 * n_ref,
            "f = {f}: F_tot {fx:.5} N, eq. (11) {f_ref:.5} N"
        );
    }
    let f_sim = sim_sign_change(&samples, 0.9).expect("F_tot changes sign");
    let f_ref = sign_change_fraction(&forces, 0.9).unwrap();
    assert!(
        (f_sim - f_ref).abs() < 0.01,
        "sim {f_sim}, eq. (11) {f_ref}"
    );
    assert!(
        f_ref < 1.0 - 0.4f64.powf(2.0 / 3.0) - 0.02,
        "eq. (11) {f_ref}"
    );
    // The torque identity about the origin holds in the simulation, tau_O = dL_O/dt, within
    // 5 % of the largest |tau_O| (measured 4.3 %: the floor's contact points are read at
    // the step's start); eq. (16) misses the spiral's off-centre mass, which is most of its
    // gap.
    let mean = |f: f64, g: fn(&Sample) -> f64| window_mean(&samples, f, 0.01, g).unwrap();
    let fs = [0.1, 0.25, 0.5, 0.75, 0.9];
    let scale = fs
        .iter()
        .map(|&f| mean(f, |s| s.tau_o_n_m).abs())
        .fold(0.0, f64::max);
    for f in fs {
        let (dl, tau) = (mean(f, |s| s.dl_o_dt_n_m), mean(f, |s| s.tau_o_n_m));
        assert!(
            (dl - tau).abs() < 0.05 * scale,
            "f = {f}: dL_O/dt {dl:.5} N m, tau_O {tau:.5} N m"
        );
        let (t16, off) = (
            mean(f, |s| s.tau_o_eq16_n_m),
            mean(f, |s| s.tau_offcentre_n_m),
        );
        assert!(
            (tau - t16 - off).abs() < 0.2 * (tau - t16).abs(),
            "f = {f}: eq. (16) {t16:.5}, off-centre {off:.5}, tau_O {tau:.5} N m"
        );
    }
}

/// The ledger closes at every sample: its parts add up to `E0 - K - P`.
fn assert_ledger_closes(samples: &[Sample]) {
    for s in samples {
        let parts = s.lost_step_j + s.lost_detach_j + s.lost_freeze_j + s.lost_bang_j;
        assert!(
            (parts - s.dissipated_j).abs() < 1e-9,
            "t = {}: ledger parts {parts} J, dissipated {} J",
            s.t_s,
            s.dissipated_j
        );
    }
}

/// Energy lost before the last milestone, over the mechanical energy the motion releases
/// down to the flat rest state (`E0 - flat`): on a slope the laid tape's own potential
/// energy is most of it.
fn lost_share_before(report: &RunReport, label: &str) -> f64 {
    let m = report.milestones.iter().find(|m| m.label == label).unwrap();
    let l = &report.ledger;
    m.dissipated_j.unwrap() / (l.e0_j - l.flat_potential_j)
}

#[test]
fn slope_down_follows_the_exact_model_not_the_torque_form() {
    let s = scene("slope-down");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 5);
    assert_ledger_closes(&samples);
    let lost = lost_share_before(&report, "2b");
    assert!(lost < 0.01, "lost {:.3} % before r = 2b", 100.0 * lost);
    // Eq. (72) (A11) is the continuum limit of the same energy: O(b/R) = 8 % away for the
    // thick mat. The torque form (68) and eq. (73) are further out.
    for (label, lo, hi) in [
        ("eq.72 A11", 0.02, 0.09),
        ("eq.68", 0.09, 0.25),
        ("eq.73 A12", 0.2, 0.4),
    ] {
        for (m, e) in errors(&report, rival(&rv, label)) {
            assert!((lo..hi).contains(&e), "{label} at {m}: {:+.2} %", 100.0 * e);
        }
    }
}

#[test]
fn slope_up_creeps_to_the_end_while_the_torque_form_stops() {
    let s = scene("slope-up");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 5);
    assert_ledger_closes(&samples);
    let lost = lost_share_before(&report, "2b");
    assert!(lost < 0.01, "lost {:.3} % before r = 2b", 100.0 * lost);
    // The torque forms (68) and (73) say the 0.01 m/s push dies out within the first
    // millimetres: the mat does not climb. The energy forms let it climb.
    for label in ["eq.68", "eq.73 A12"] {
        let f = rival(&rv, label).stall_fraction;
        assert!(f.is_some_and(|f| f < 0.01), "{label} stalls at {f:?}");
    }
    assert!(rival(&rv, "eq.72 A11").stall_fraction.is_none());
}

#[test]
fn single_turn_follows_eq45_not_the_variable_mass_lagrangian() {
    let s = scene("single-turn");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "eq.45"), 4);
    assert_ledger_closes(&samples);
    let lost = lost_share_before(&report, "f=0.9");
    assert!(lost < 0.01, "lost {:.3} % before f = 0.9", 100.0 * lost);
    // Footnote 15's eq. (62), corrected per A8, runs 1.7 % to 3.4 % ahead.
    for (m, e) in errors(&report, rival(&rv, "eq.62 A8")) {
        if m != "f=0.25" {
            assert!(e < -0.015, "eq. 62 at {m}: {:+.2} %", 100.0 * e);
        }
    }
}

#[test]
fn spool_follows_the_exact_spiral_and_eq79_only_on_average() {
    let s = scene("spool");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 4);
    assert_ledger_closes(&samples);
    let lost = lost_share_before(&report, "f=0.9");
    assert!(lost < 0.01, "lost {:.3} % before f = 0.9", 100.0 * lost);
    // Eq. (79) averages the torque of the unbalanced outer partial turn (0.79 of a turn
    // for l = 5 m on r = 0.02 m) over each turn; from a near-rest start the real first
    // turn pulls harder: the spiral, and the simulation, run 3-5 % ahead of eq. (79).
    for (m, e) in errors(&report, rival(&rv, "eq.79")) {
        assert!(
            (0.02..0.06).contains(&e),
            "eq. 79 at {m}: {:+.2} %",
            100.0 * e
        );
    }
    // Its energy balance is eq. (78)'s: after every whole turn, when the partial turn's
    // weight is back where it started, the spin is eq. (79)'s (measured within 0.26 %);
    // inside the first turn that weight moves it by up to 22 %.
    let spins = spool_spins(&s);
    let errs = spin_errors(&s, &samples, &spins[0].1);
    assert_spin_at_whole_turns(&errs, 0.01, 0.1, "eq. 79");
    // Constraint forces: N = m g (85) and F_tot of (86) corrected per ERRATA A16, which
    // changes sign where half the tape is laid, r theta = l/2.
    assert_forces_follow(&s, &samples, &[0.1, 0.25, 0.5, 0.75], 0.01, 0.05);
    let f_sim = sim_sign_change(&samples, 0.9).expect("F_tot changes sign");
    assert!(
        (f_sim - 0.5).abs() < 0.01,
        "F_tot changes sign at f = {f_sim}"
    );
    // The printed closed form (81)-(82) is off by the factor l/r (ERRATA A14).
    for (m, e) in errors(&report, rival(&rv, "(81) print")) {
        assert!(e < -0.99, "(81) as printed at {m}: {:+.2} %", 100.0 * e);
    }
}

/// Largest `|x_sim - x_ref|` over the samples before 90 % laid (m).
fn worst_x(samples: &[Sample], x_ref: impl Fn(f64) -> f64) -> f64 {
    samples
        .iter()
        .filter(|s| s.laid_fraction < 0.9)
        .map(|s| (s.x_m - x_ref(s.laid_fraction)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn frictionless_spool_follows_the_sliding_spiral_and_pushes_the_laid_tape_flat() {
    // No friction: the centre of mass stays put, so the contact line must move as
    // x = l u^2 / 2 (eq. 100), the laid tape sliding back as a whole under compression.
    // Had it bunched up at the start (footnote 22), x would stay near 0.
    let s = scene("frictionless-spool");
    let (samples, report) = run_kept(&s);
    // The exact spiral sliding at zero momentum, its flat tape moving with the material
    // velocity of the peel point (ERRATA A18), is the reference; A18's thin-tape form
    // averages the outer partial turn (as eq. 79 does with friction) and runs 9-15 % ahead.
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 4);
    for (m, e) in errors(&report, rival(&rv, "A18")) {
        assert!(
            (-0.2..-0.05).contains(&e),
            "A18 at {m}: {:+.2} %",
            100.0 * e
        );
    }
    // After every whole turn the spin is A18's (measured within 0.43 %); the printed
    // centroid velocity of eqs. (104)-(105) is off by 3.9-8.3 % from the second turn on.
    let spins = spool_spins(&s);
    assert_eq!(spins[0].0, "A18");
    let errs = spin_errors(&s, &samples, &spins[0].1);
    assert_spin_at_whole_turns(&errs, 0.01, 0.1, "A18");
    for (k, e) in spin_errors(&s, &samples, &spins[1].1) {
        if k >= 2.0 {
            assert!(e > 0.03, "eq. 104 after {k} turns: {:+.2} %", 100.0 * e);
        }
    }
    let l = uncoil::theory::rivals::SpoolGeometry::of(&s).l_m;
    // Measured: at most 1.6 mm off; the contact line travels 0.8 m by 90 % laid, and a
    // bunched-up tape would leave it near 0. Allow 0.2 % of l.
    let worst = worst_x(&samples, |u| 0.5 * l * u * u);
    assert!(worst < 0.002 * l, "x off eq. (100) by {worst:.2e} m");
    assert_ledger_closes(&samples);
    assert!(report.milestones.iter().all(|m| m.t_sim_s.is_some()));
    // 16 solver iterations: 0.13 % of E0 lost before the bang (1.27 % at 4).
    let lost = lost_share_before(&report, "f=0.9");
    assert!(lost < 0.01, "lost {:.3} % before f = 0.9", 100.0 * lost);
}

#[test]
fn frictionless_coil_follows_the_sliding_spiral_and_keeps_its_centre_of_mass() {
    // Eq. (106) with the centre of mass fixed, x = f^2 L / 2 for a tape of length L, here
    // the midline length of the spiral (8 % shorter than pi R^2 / b for this thick mat).
    let s = scene("frictionless-coil");
    let (samples, report) = run_kept(&s);
    // The exact spiral sliding at zero momentum is the reference; the continuum form with
    // the material velocity (ERRATA A19-A20) is its O(b/R) idealisation, 7 % slower.
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 5);
    for (m, e) in errors(&report, rival(&rv, "A19-A20")) {
        assert!(
            (0.05..0.09).contains(&e),
            "A19-A20 at {m}: {:+.2} %",
            100.0 * e
        );
    }
    let t = &s.tape;
    let len = uncoil::spiral::Spiral::wound(t.outer_radius_m, t.thickness_m, 0.0).length();
    let worst = worst_x(&samples, |f| 0.5 * len * f * f);
    // The coil's centre of mass is not over the contact line (the spiral is off-centre by
    // about b / pi): allow 1 % of L.
    assert!(
        worst < 0.01 * len,
        "x off eq. (106) by {worst:.2e} m (L = {len:.3} m)"
    );
    assert_ledger_closes(&samples);
    // The bang comes to rest: the floor conserves the zero horizontal momentum, so the
    // impacts can take everything (measured 97 % of what it dissipated).
    assert_eq!(report.stop.status(), Status::Completed, "{}", report.stop);
    let l = &report.ledger;
    assert!(l.dissipated_by_bang_j > 0.5 * l.e0_j, "{l:?}");
    // A sliding model has no rolling contact-line speed to set beside the peak: the report
    // leaves it out rather than writing null.
    assert_eq!(report.approach.peak_xdot_geo_m_s, None);
    let json = serde_json::to_string(&report).unwrap();
    assert!(!json.contains("null"), "null in report.json: {json}");
}

/// The thin tape's coil with b = 1 mm (1160 links) on a frictionless floor, its bang cut
/// at `bang_cap_s`.
fn frictionless_thin_tape(bang_cap_s: f64) -> Scene {
    let text = format!(
        "[tape]\nouter_radius_m = 0.03\nthickness_m = 0.001\nmass_kg = 0.2\n\
         [discretisation]\nlinks_per_turn = 40\n[floor]\nfriction = 0.0\n\
         [push]\ncontact_speed_m_s = 0.1\n[stop]\nbang_cap_s = {bang_cap_s}\n"
    );
    Scene::from_toml_str(&text, "frictionless-thin").unwrap()
}

#[test]
fn a_frictionless_floor_s_laid_tape_slides_as_one_body_and_gains_no_energy() {
    // Nothing holds a laid tape on a frictionless floor: it slides, flat, as one body. Left
    // a joint per link, the engine's four solver iterations could not carry the coil's pull
    // along it: this tape of 1160 links gained 0.45 % of its energy by its release, up to
    // 4.5e-3 of the energy scale, with 1084 bodies moving. Joined into one body held flat it
    // rose at most 1.1e-4 of it, with at most 39 bodies moving (measured).
    let s = frictionless_thin_tape(0.0);
    let (samples, report) = run_kept(&s);
    assert_eq!(report.stop.status(), Status::Completed, "{}", report.stop);
    assert!(
        report.max_energy_rise_rel < 1e-3,
        "rose {:.2e} of the energy scale",
        report.max_energy_rise_rel
    );
    let rolling = samples.iter().filter(|s| s.omega_rad_s > 0.0);
    let most = rolling.map(|s| s.active_bodies).max().unwrap();
    assert!(most < 100, "{most} bodies moving at once");
    // It still slides as the exact spiral at zero momentum says, to the release.
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 5);
    assert_ledger_closes(&samples);
}

#[test]
fn a_frictionless_laid_tape_that_slid_as_one_body_bends_in_the_bang() {
    // The laid tape slides as one body while the coil unrolls, and is parted into its links
    // at the release: the bang joins them into its pieces, as it does the rest. Kept as one
    // body, metres long and lifted at its inner end, it rose off the floor whole.
    let s = frictionless_thin_tape(0.0002);
    let (samples, report) = run_kept(&s);
    assert_eq!(report.stop.status(), Status::Completed, "{}", report.stop);
    let rolling = samples.iter().filter(|s| s.omega_rad_s > 0.0);
    let most_rolling = rolling.map(|s| s.active_bodies).max().unwrap();
    let in_bang = samples.last().unwrap().active_bodies;
    // 1160 links, 1148 laid by the release, pieces of one thickness (one link each here).
    assert!(most_rolling < 100, "{most_rolling} bodies while it rolled");
    assert!(in_bang > 1000, "{in_bang} bodies in the bang");
}

#[test]
fn compare_prints_the_paradox_table_and_rejects_a_bad_scene_first() {
    use assert_cmd::Command;
    use predicates::prelude::*;
    let good = format!("{}/scenes/single-turn.toml", env!("CARGO_MANIFEST_DIR"));
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["compare", &good])
        .assert()
        .success()
        .stdout(predicate::str::contains("#### single-turn (App. A;"))
        .stdout(predicate::str::contains(
            "| milestone | f | sim s | eq.45 * s |",
        ))
        .stdout(predicate::str::contains(
            "| f | N_tot sim | exact | paper |",
        ));
    // A bad scene anywhere in the list stops everything before the first run.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[tape]\nouter_radius_m = 0.06\n").unwrap();
    Command::cargo_bin("uncoil")
        .unwrap()
        .args(["compare", &good])
        .arg(&bad)
        .assert()
        .code(2)
        .stdout(predicate::str::is_empty())
        .stderr(predicate::str::contains("missing field `thickness_m`"));
}

#[test]
fn zero_g_coil_on_a_sticky_floor_rolls_on_its_push_alone() {
    // With g = 0 the rolling spiral needs a floor that pulls from the start; the sticky
    // floor holds the coil bilaterally. Energy is then kinetic alone and conserved: the
    // exact model holds, and eq. (7) with g = 0 is 9 % slower (O(b/R)).
    let s = scene("zero-g");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "exact"), 5);
    for (m, e) in errors(&report, rival(&rv, "eq.7")) {
        assert!(
            (0.07..0.11).contains(&e),
            "eq. 7 at {m}: {:+.2} %",
            100.0 * e
        );
    }
    assert_ledger_closes(&samples);
    let m = report.milestones.iter().find(|m| m.label == "2b").unwrap();
    let lost = m.dissipated_j.unwrap() / report.ledger.e0_j;
    assert!(
        lost < 0.01,
        "lost {:.3} % of E0 before r = 2b",
        100.0 * lost
    );
}

#[test]
fn vertical_tape_follows_eq115_and_leaves_at_its_exit_speed() {
    let s = scene("vertical");
    let (samples, report) = run_kept(&s);
    let rv = rivals(&s);
    assert_converges(&report, rival(&rv, "eq.115"), 4);
    assert_ledger_closes(&samples);
    // Energy is conserved to 0.1 % of the kinetic energy reached at f = 0.9.
    let m = report
        .milestones
        .iter()
        .find(|m| m.label == "f=0.9")
        .unwrap();
    let lost = m.dissipated_j.unwrap().abs() / m.kinetic_j.unwrap();
    assert!(lost < 0.001, "lost {:.3} % of K by f = 0.9", 100.0 * lost);
    // The tape speed r theta' follows eq. (115)'s integral; at theta = 2 pi it would be
    // sqrt(2 pi g r + r^2 theta0'^2) (B17). Checked where 95 % hangs.
    let sg = uncoil::theory::rivals::SpoolGeometry::of(&s);
    let spin = uncoil::theory::rivals::vertical_spin(sg.r_m, s.gravity.g_m_s2, sg.spin0_rad_s);
    let at = samples
        .iter()
        .find(|x| x.laid_fraction >= 0.95)
        .expect("95 % reached");
    let want = spin(2.0 * std::f64::consts::PI * at.laid_fraction);
    let got = at.omega_rad_s;
    assert!(
        (got / want - 1.0).abs() < 0.01,
        "theta' at f = {:.4}: {got:.3} rad/s, eq. (115) {want:.3} rad/s",
        at.laid_fraction
    );
    let exit =
        (2.0 * std::f64::consts::PI * 9.81 * sg.r_m + (sg.r_m * sg.spin0_rad_s).powi(2)).sqrt();
    assert!((sg.r_m * spin(2.0 * std::f64::consts::PI) / exit - 1.0).abs() < 1e-12);
    // The control-volume Lagrangian (124) runs 2-4 % ahead.
    for (m, e) in errors(&report, rival(&rv, "eq.124")) {
        assert!(e < -0.015, "eq. 124 at {m}: {:+.2} %", 100.0 * e);
    }
}
