//! The constraint forces and the torque paradox of a finished run: the simulation's window
//! means beside the exact-geometry model's and the paper's forms, their gaps and spread,
//! eq. (11) against eq. (30) (ERRATA A6), and the torque balance about the origin against
//! eqs. (14) and (16) (ERRATA C1). It formats; it runs nothing.

use std::f64::consts::PI;
use std::fmt::Write as _;

use crate::output::table::Table;
use crate::run::{RunReport, Sample};
use crate::scene::Scene;
use crate::theory::forces::{force_reference, sign_change_fraction};
use crate::theory::rivals::Case;

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

/// Mean and standard deviation about a least-squares line in `f` of `value` over the
/// rolling-phase samples within `half` of `f`: the spread that is not the trend.
pub fn window_spread(
    samples: &[Sample],
    f: f64,
    half: f64,
    value: impl Fn(&Sample) -> f64,
) -> Option<(f64, f64)> {
    let points: Vec<(f64, f64)> = samples
        .iter()
        .filter(|s| (s.laid_fraction - f).abs() <= half)
        .map(|s| (s.laid_fraction, value(s)))
        .filter(|p| p.1.is_finite())
        .collect();
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let ss: f64 = points
        .iter()
        .map(|p| (p.1 - my - slope * (p.0 - mx)).powi(2))
        .sum();
    Some((my, (ss / (n - 2.0)).sqrt()))
}

/// The forces compared, each as (simulation's column, exact model's column): `N_tot`,
/// `F_tot`, `F`, `F_int`.
type ForcePair = (fn(&Sample) -> f64, fn(&Sample) -> f64);

const FORCE_PAIRS: [ForcePair; 4] = [
    (|s| s.n_tot_n, |s| s.n_tot_geo_n),
    (|s| s.f_tot_n, |s| s.f_tot_geo_n),
    (|s| s.f_floor_n, |s| s.f_floor_geo_n),
    (|s| s.f_int_n, |s| s.f_int_geo_n),
];

/// The constraint-force table of one run: the simulation's `N_tot`, `F_tot` (momentum
/// balance of the moving part), the floor's `F` on the coil and the laid tape's `F_int`
/// beside the exact-geometry model's and the paper's forms; their gaps and spread in
/// units of `M g`; eq. (11) against eq. (30) on a level floor.
pub fn force_table(report: &RunReport, samples: &[Sample]) -> String {
    let mut o = String::new();
    let scene = &report.scene;
    let forces = force_reference(scene);
    let has_geo = samples.iter().any(|s| s.n_tot_geo_n.is_finite());
    if forces.is_none() && !has_geo {
        let _ = writeln!(
            o,
            "Constraint forces: no reference for this case (a frictionless floor exerts no \
             horizontal force; a fixed axis has no floor)."
        );
        return o;
    }
    let _ = writeln!(
        o,
        "Constraint forces (N), the simulation's averaged over f +- {FORCE_WINDOW}: the \
         simulation (sim), the exact-geometry model (exact) and the paper's form (paper: eq. 9 \
         per ERRATA A4, eq. 11 = eq. 30 line 1 per A6, or the case's own).\n"
    );
    let mut table = Table::new([
        "f",
        "N_tot sim",
        "exact",
        "paper",
        "F_tot sim",
        "exact",
        "paper",
        "F sim",
        "exact",
        "F_int sim",
        "exact",
    ]);
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.4}"));
    for f in FORCE_FRACTIONS {
        let mean = |g: fn(&Sample) -> f64| show(window_mean(samples, f, FORCE_WINDOW, g));
        let paper = forces.as_ref().and_then(|r| r(f));
        let [n, fx, fl, fi] = FORCE_PAIRS.map(|(sim, geo)| (mean(sim), mean(geo)));
        table.push([
            f.to_string(),
            n.0,
            n.1,
            show(paper.map(|r| r.0)),
            fx.0,
            fx.1,
            show(paper.map(|r| r.1)),
            fl.0,
            fl.1,
            fi.0,
            fi.1,
        ]);
    }
    o.push_str(&table.markdown());
    o.push_str(&force_gaps(scene, samples));
    o.push_str(&force_notes(report, samples));
    let last = report
        .milestones
        .iter()
        .filter_map(|m| m.t_sim_s.map(|_| m.laid_fraction))
        .fold(0.0, f64::max)
        .min(0.95);
    if let Some(forces) = &forces {
        let _ = writeln!(
            o,
            "F_tot changes sign at f = {} in the simulation and at f = {} in the paper's form.",
            show(sim_sign_change(samples, last)),
            show(sign_change_fraction(forces, last)),
        );
    }
    if matches!(Case::of(scene), Case::Coil) {
        o.push_str(&eq11_against_eq30(report, samples));
    }
    o
}

/// The largest gap of each simulated force to the exact model's over the table's laid
/// fractions, and its largest spread about a line over a window, in units of `M g` (with
/// no gravity, of the largest force simulated).
fn force_gaps(scene: &Scene, samples: &[Sample]) -> String {
    let (mg, unit) = if scene.gravity.g_m_s2 > 0.0 {
        (scene.tape.mass_kg * scene.gravity.g_m_s2, "M g")
    } else {
        let n = FORCE_FRACTIONS
            .iter()
            .flat_map(|&f| {
                FORCE_PAIRS[..2]
                    .iter()
                    .map(move |&(sim, _)| window_mean(samples, f, FORCE_WINDOW, sim))
            })
            .flatten()
            .fold(0.0_f64, |a, n| a.max(n.abs()));
        (n.max(f64::MIN_POSITIVE), "the largest force")
    };
    // A sticky floor holds the coil by a joint, which the simulation books in F_int.
    let pairs = if scene.floor.sticky { 2 } else { 4 };
    let (mut gap, mut spread) = ([None::<f64>; 4], [None::<f64>; 4]);
    for f in FORCE_FRACTIONS {
        for (k, &(sim, geo)) in FORCE_PAIRS.iter().enumerate().take(pairs) {
            let mean = |g: fn(&Sample) -> f64| window_mean(samples, f, FORCE_WINDOW, g);
            if let (Some(a), Some(b)) = (mean(sim), mean(geo)) {
                gap[k] = Some(gap[k].unwrap_or(0.0).max((a - b).abs() / mg));
            }
            if let Some((_, sd)) = window_spread(samples, f, FORCE_WINDOW, sim) {
                spread[k] = Some(spread[k].unwrap_or(0.0).max(sd / mg));
            }
        }
    }
    let pct = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.2} %", 100.0 * v));
    format!(
        "\nAgainst the exact model, the largest gap at these f in units of {unit}: N_tot {}, \
         F_tot {} (target 1 %); F {}, F_int {} (target 2 %; the rigid model cannot split \
         F_tot, its split is the least pull in the laid tape). Spread of the simulation about \
         a line over each window: N_tot {}, F_tot {}, F {}, F_int {} (target 1 %).\n",
        pct(gap[0]),
        pct(gap[1]),
        pct(gap[2]),
        pct(gap[3]),
        pct(spread[0]),
        pct(spread[1]),
        pct(spread[2]),
        pct(spread[3]),
    )
}

/// Where the force comparison stops: a sticky floor's hold, the exact model's hop, where its
/// laid tape must pull.
fn force_notes(report: &RunReport, samples: &[Sample]) -> String {
    let scene = &report.scene;
    let mut o = String::new();
    if scene.floor.sticky {
        let _ = writeln!(
            o,
            "On a sticky floor the hold is a joint, not a contact: the simulation books it in \
             F_int, so F and F_int are not compared."
        );
    }
    if let (Some(f), false) = (report.geo_hop_fraction, scene.floor.sticky) {
        let _ = writeln!(
            o,
            "The exact model needs a floor that pulls (N_tot < 0) from f = {f:.4} on: there it \
             stops applying."
        );
    }
    if let Some(s) = samples
        .iter()
        .find(|s| s.f_int_geo_n.is_finite() && s.f_int_geo_n != 0.0)
    {
        let _ = writeln!(
            o,
            "From f = {:.4} on, |F_tot| exceeds the floor's grip mu N_tot: the exact model's laid \
             tape must pull.",
            s.laid_fraction
        );
    }
    o
}

/// Eq. (11) against eq. (30) on a level floor: their approximate forms for `r >> b`,
/// eq. (11)'s `M g b (5 r^3 - 2 R^3) / (3 pi r^2 R^2)` with ERRATA A7's push term and
/// eq. (30)'s printed `M g b (7 r^3 - 10 R^3) / (3 pi r^2 R^2)`, beside the simulation.
/// ERRATA A6: line 1 of (30) is (11) exactly; the printed line 2 slips a sign.
fn eq11_against_eq30(report: &RunReport, samples: &[Sample]) -> String {
    let scene = &report.scene;
    let (big_r, b, m, g) = (
        scene.tape.outer_radius_m,
        scene.tape.thickness_m,
        scene.tape.mass_kg,
        scene.gravity.g_m_s2,
    );
    let rdot0 = b * scene.push.contact_speed_m_s / (2.0 * PI * big_r);
    let mut o = String::new();
    let _ = writeln!(
        o,
        "\nEq. (11) against eq. (30), approximate forms (N): the simulation says which is right.\n"
    );
    let _ = writeln!(
        o,
        "| f | F_tot sim | eq. (11) with A7 | eq. (30) as printed |"
    );
    let _ = writeln!(o, "|---|---|---|---|");
    let (mut worst11, mut worst30) = (0.0_f64, 0.0_f64);
    for f in FORCE_FRACTIONS {
        let Some(sim) = window_mean(samples, f, FORCE_WINDOW, |s| s.f_tot_n) else {
            continue;
        };
        let r = big_r * (1.0 - f).sqrt();
        let k = m * g * b / (3.0 * PI * r * r * big_r * big_r);
        let eq11 = k * (5.0 * r.powi(3) - 2.0 * big_r.powi(3))
            - 2.0 * PI * m * big_r * big_r * rdot0 * rdot0 / (b * r * r);
        let eq30 = k * (7.0 * r.powi(3) - 10.0 * big_r.powi(3));
        worst11 = worst11.max((sim - eq11).abs() / (m * g));
        worst30 = worst30.max((sim - eq30).abs() / (m * g));
        let _ = writeln!(o, "| {f} | {sim:.4} | {eq11:.4} | {eq30:.4} |");
    }
    let _ = writeln!(
        o,
        "\nLargest gap in units of M g: eq. (11) {:.2} %, eq. (30) as printed {:.2} %. ERRATA \
         A6: line 1 of (30) is (11); its line 2 slips a sign.",
        100.0 * worst11,
        100.0 * worst30
    );
    o
}

/// The torque paradox term by term, for a solid coil: the moving part's angular momentum
/// about the origin and the torque of the external forces at their points, the identity
/// between them, and eq. (14)'s `L_O` and eq. (16)'s `tau_O` beside them, with what eq.
/// (16) misses of gravity's torque; on a slope, ERRATA C1's couple.
pub fn torque_table(report: &RunReport, samples: &[Sample]) -> String {
    let scene = &report.scene;
    let mut o = String::new();
    let slope = scene.floor.slope_deg.to_radians();
    let _ = writeln!(
        o,
        "\nThe torque paradox about the origin (the laid tape's outer end), counter-clockwise, \
         averaged over f +- {FORCE_WINDOW}: L_O (kg m^2/s) of the moving part against the \
         exact-geometry model's and eq. (14)'s at the simulation's r and r'; dL_O/dt and the torque tau_O of gravity, the floor and \
         the laid tape at their points (N m); eq. (16)'s placement of the same forces \
         (gravity and the vertical forces at the contact line); what that misses of gravity's \
         torque, the spiral's centre of mass being off the contact line; the rest.\n"
    );
    let c1 = slope != 0.0;
    let mut table = Table::new([
        "f",
        "L_O sim",
        "exact",
        "eq. (14)",
        "dL_O/dt",
        "tau_O",
        "identity gap",
        "eq. (16)",
        "off-centre mass",
        "rest",
    ]);
    if c1 {
        table.header.push("C1 couple".into());
    }
    let show = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.5}"));
    let rows: Vec<TorqueRow> = FORCE_FRACTIONS
        .iter()
        .filter_map(|&f| TorqueRow::at(samples, f))
        .collect();
    for r in &rows {
        let mut row = vec![
            r.f.to_string(),
            show(Some(r.l)),
            show(r.l_geo),
            show(Some(r.l14)),
            show(Some(r.dl)),
            show(Some(r.tau)),
            show(Some(r.dl - r.tau)),
            show(Some(r.t16)),
            show(Some(r.off)),
            show(Some(r.tau - r.t16 - r.off)),
        ];
        if c1 {
            // ERRATA C1: the laid tape's weight along the slope at height b/2, its friction
            // at y = 0.
            let m = scene.tape.mass_kg;
            row.push(format!(
                "{:.5}",
                -m * r.f * scene.gravity.g_m_s2 * scene.tape.thickness_m * slope.sin() / 2.0
            ));
        }
        table.push(row);
    }
    o.push_str(&table.markdown());
    o.push_str(&torque_verdict(scene, samples, &rows));
    o
}

/// One laid fraction of [`torque_table`]: the window means of its columns.
struct TorqueRow {
    f: f64,
    l: f64,
    l_geo: Option<f64>,
    l14: f64,
    dl: f64,
    tau: f64,
    t16: f64,
    off: f64,
}

impl TorqueRow {
    fn at(samples: &[Sample], f: f64) -> Option<Self> {
        let mean = |g: fn(&Sample) -> f64| window_mean(samples, f, FORCE_WINDOW, g);
        Some(Self {
            f,
            l: mean(|s| s.l_o)?,
            l_geo: mean(|s| s.l_o_geo),
            l14: mean(|s| s.l_o_eq14)?,
            dl: mean(|s| s.dl_o_dt_n_m)?,
            tau: mean(|s| s.tau_o_n_m)?,
            t16: mean(|s| s.tau_o_eq16_n_m)?,
            off: mean(|s| s.tau_offcentre_n_m)?,
        })
    }
}

/// What [`torque_table`]'s rows say: how well the identity holds, how far eqs. (14) and
/// (16) are off and how much of eq. (16)'s gap the off-centre mass makes.
fn torque_verdict(scene: &Scene, samples: &[Sample], rows: &[TorqueRow]) -> String {
    let mut o = String::new();
    // Torques change sign during the unroll: gaps are in units of the largest |tau_O|.
    let scale = FORCE_FRACTIONS
        .iter()
        .filter_map(|&f| window_mean(samples, f, FORCE_WINDOW, |s| s.tau_o_n_m))
        .fold(0.0_f64, |a, t| a.max(t.abs()))
        .max(f64::MIN_POSITIVE);
    let worst = |e: &dyn Fn(&TorqueRow) -> f64| {
        rows.iter()
            .map(|r| (r.f, e(r)))
            .fold(None::<(f64, f64)>, |w, x| match w {
                Some(w) if x.1.abs() <= w.1.abs() => Some(w),
                _ => Some(x),
            })
    };
    let (Some((f14, e14)), Some((f16, e16))) = (
        worst(&|r| r.l14 / r.l - 1.0),
        worst(&|r| (r.t16 - r.tau) / scale),
    ) else {
        return o;
    };
    let worst_gap = rows
        .iter()
        .map(|r| (r.dl - r.tau).abs() / scale)
        .fold(0.0_f64, f64::max);
    let worst_geo = rows
        .iter()
        .filter_map(|r| Some((r.l / r.l_geo? - 1.0).abs()))
        .reduce(f64::max);
    let explained = rows.iter().map(|r| r.off / (r.tau - r.t16));
    let share = |k: fn(f64, f64) -> f64| explained.clone().fold(f64::NAN, k);
    let _ = writeln!(
        o,
        "\nThe identity dL_O/dt = tau_O holds in the simulation to {:.1} % of the largest \
         |tau_O| (the engine moves a body on a resting contact by a velocity that is not the \
         one it reports after the step, which keeps the last substep's pull of gravity: \
         the lever arm's change over the step against the reported momentum makes the \
         gap). The \
         simulation's L_O is the exact model's to {}. Eq. (14) is off it by up to {:+.1} % \
         (f = {f14}); eq. (16) off its tau_O by up to {:+.1} % of the largest |tau_O| \
         (f = {f16}).{}",
        100.0 * worst_gap,
        worst_geo.map_or("-".into(), |w| format!("{:.2} %", 100.0 * w)),
        100.0 * e14,
        100.0 * e16,
        if scene.gravity.g_m_s2 > 0.0 {
            format!(
                " The spiral's off-centre mass makes {:.0}-{:.0} % of eq. (16)'s gap; the \
                 rest is the floor's and the laid tape's forces at their own points.",
                100.0 * share(f64::min),
                100.0 * share(f64::max)
            )
        } else {
            " With no gravity, nothing is off-centre in eq. (16): what it misses is the \
             floor's and the laid tape's forces at their own points."
                .to_string()
        },
    );
    if scene.floor.slope_deg != 0.0 {
        let _ = writeln!(
            o,
            "C1's couple acts on the laid tape, not on the moving part: the simulation's \
             floor is the laid tape's midline plane, where its weight along the slope and \
             the friction that holds it act on one line, so it has no such couple."
        );
    }
    o
}
