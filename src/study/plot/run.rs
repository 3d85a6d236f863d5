//! A run's pictures, read back from its `samples.csv` and `report.json`: its motion, its
//! energy ledger with the bang by mechanism, its approach to the bang and its forces, each
//! against the references. It reads the run's files and runs nothing.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use plotters::prelude::*;

use super::bang::{BANG_SVG, BangPicture, bang_plot};
use super::{
    Area, Curve, DESC_PX, Drawn, EQ7, EXACT, HouseStyle, LinChart, Line, LogChart, LogTicks,
    MARGIN_PX, SIM, X_LABEL_AREA_PX, X_TICK_ROOM_PX, Y_LABEL_AREA_PX, color, draw_line, err, font,
    legend, line_chart, log_chart, log_range, pairs, plot_size, positive_pairs, range,
};
use crate::output::folder::{REPORT, SAMPLES};
use crate::run::RunReport;
use crate::run::limits::LimitKind;
use crate::study::sweep::SweepTable;

/// The simulation, the exact-geometry model and eq. (7) as three curves over `t`, from the
/// columns `[sim, exact, eq7]`.
fn against_references<'a>(t: &[f64], columns: &[Vec<f64>; 3]) -> [Curve<'a>; 3] {
    let curve = |label, i: usize, color, dashed| Curve {
        label,
        points: pairs(t, &columns[i]),
        color,
        dashed,
    };
    [
        curve("simulation", 0, SIM, false),
        curve("exact-geometry model", 1, EXACT, true),
        curve("eq. (7)", 2, EQ7, true),
    ]
}

/// Draws, from the run's `samples.csv` and `report.json`: `dir/motion.svg` (r and x'
/// against time, with the exact-geometry model and eq. (7), up to the final bang),
/// `dir/energy.svg` (kinetic, potential and lost energy over the whole run, with MgR, E0
/// and the drop at the bang; below, the bang alone, with what it dissipated split by
/// mechanism) and `dir/approach.svg` (x' against r, log-log, over the unroll, with the
/// references, eq. (7)'s x' ~ 1/r, and where the references stop applying) and
/// `dir/forces.svg` (`N_tot`, and `F_tot` with its split into `F` and `F_int`, against the
/// laid fraction up to 0.95, with the exact-geometry model's), and `dir/bang.svg` from
/// `dir/run.mcap` (the tape's shape through the bang, or why not: [`BangPicture`]).
pub fn plot_run(dir: &Path) -> anyhow::Result<RunPlots> {
    let run = WrittenRun::read(dir)?;
    let motion = dir.join("motion.svg");
    motion_plot(&motion, &run)?;
    let energy = dir.join("energy.svg");
    energy_plot(&energy, &run)?;
    let approach = dir.join("approach.svg");
    approach_plot(&approach, &run)?;
    let forces = dir.join("forces.svg");
    forces_plot(&forces, &|c| run.cut(c), &run.name)?;
    let mut written = vec![motion, energy, approach, forces];
    let mut skipped = Vec::new();
    match bang_plot(dir, run.bang_t, &run.name)? {
        BangPicture::Drawn(path) => written.push(path),
        BangPicture::Skipped(why) => skipped.push((dir.join(BANG_SVG), why)),
    }
    Ok(RunPlots { written, skipped })
}

/// What [`plot_run`] did: the files written, and each picture skipped with why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunPlots {
    /// The files written.
    pub written: Vec<PathBuf>,
    /// The pictures not drawn, each with its reason.
    pub skipped: Vec<(PathBuf, String)>,
}

/// A run's files read back: its samples, its report and what the pictures take from it.
struct WrittenRun {
    samples: SweepTable,
    report: RunReport,
    /// MgR (J).
    mgr: f64,
    /// The initial energy (J).
    e0: f64,
    /// What the final bang dissipated (J).
    bang_j: f64,
    /// When the final bang began, if it did.
    bang_t: Option<f64>,
    /// The scene's name.
    name: String,
    /// The samples' times (s).
    t: Vec<f64>,
    /// The samples of the unroll: those up to the final bang.
    upto: usize,
}

impl WrittenRun {
    /// Reads `dir/samples.csv` and `dir/report.json`.
    fn read(dir: &Path) -> anyhow::Result<Self> {
        let samples = SweepTable::read(&dir.join(SAMPLES))?;
        let report_path = dir.join(REPORT);
        let text = std::fs::read_to_string(&report_path)
            .with_context(|| format!("cannot read {}", report_path.display()))?;
        anyhow::ensure!(
            crate::study::check::salvage::describe(dir).is_none(),
            "{}: a killed run's, salvaged: the pictures need what a run books at its end (its \
             ledger, bang and references); its {SAMPLES} reads as any run's",
            report_path.display()
        );
        let mut de = serde_json::Deserializer::from_str(&text);
        let report: RunReport = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            anyhow::anyhow!(
                "{}: {} does not read back as a report of this version: {}",
                report_path.display(),
                e.path(),
                e.inner()
            )
        })?;
        let ledger = &report.ledger;
        let (mgr, e0, bang_j) = (ledger.mgr_j, ledger.e0_j, ledger.dissipated_by_bang_j);
        let bang_t = ledger.bang_time_s;
        let name = report.scene.name.clone();
        let t = column(&samples, "t_s")?;
        let upto = t
            .iter()
            .position(|&ti| bang_t.is_some_and(|b| ti > b))
            .unwrap_or(t.len());
        Ok(Self {
            samples,
            report,
            mgr,
            e0,
            bang_j,
            bang_t,
            name,
            t,
            upto,
        })
    }

    /// Column `c` of the samples.
    fn col(&self, c: &str) -> anyhow::Result<Vec<f64>> {
        column(&self.samples, c)
    }

    /// Column `c` of the samples of the unroll.
    fn cut(&self, c: &str) -> anyhow::Result<Vec<f64>> {
        self.col(c).map(|v| v[..self.upto].to_vec())
    }
}

/// Column `c` of `samples.csv`.
fn column(samples: &SweepTable, c: &str) -> anyhow::Result<Vec<f64>> {
    samples
        .numbers(c)
        .with_context(|| format!("samples.csv has no `{c}` column"))
}

/// `path`: r and x' against time, with the exact-geometry model and eq. (7), up to the
/// final bang.
fn motion_plot(path: &Path, run: &WrittenRun) -> anyhow::Result<()> {
    let name = &run.name;
    let tr = &run.t[..run.upto];
    let root = SVGBackend::new(path, (900, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((2, 1));
    let r = [run.cut("r_m")?, run.cut("r_geo_m")?, run.cut("r_ref_m")?];
    line_chart(
        &panels[0],
        &format!("{name}: equivalent coil radius r = R sqrt(1 - laid fraction)"),
        "t (s)",
        "r (m)",
        &against_references(tr, &r),
        |_, _| Ok(()),
    )?;
    let v = [
        run.cut("xdot_m_s")?,
        run.cut("xdot_geo_m_s")?,
        run.cut("xdot_ref_m_s")?,
    ];
    line_chart(
        &panels[1],
        &format!("{name}: contact-line speed x', up to the final bang"),
        "t (s)",
        "x' (m/s)",
        &against_references(tr, &v),
        |_, _| Ok(()),
    )?;
    root.present().map_err(err)?;
    Ok(())
}

/// `path`: kinetic, potential and lost energy over the whole run, with MgR, E0 and the
/// start of the final bang; below, if there was one, the bang alone ([`bang_panel`]).
fn energy_plot(path: &Path, run: &WrittenRun) -> anyhow::Result<()> {
    let (name, t, bang_t) = (&run.name, &run.t, run.bang_t);
    let height = if bang_t.is_some() { 950 } else { 500 };
    let root = SVGBackend::new(path, (900, height)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (whole, zoom) = if bang_t.is_some() {
        let (a, b) = root.split_vertically(500);
        (a, Some(b))
    } else {
        (root.clone(), None)
    };
    let k = run.col("kinetic_j")?;
    let p = run.col("potential_j")?;
    let d = run.col("dissipated_j")?;
    let caption = match bang_t {
        Some(b) => format!(
            "{name}: energy ledger; the final bang at t = {b:.3} s dissipates {:.3} J = {:.2} MgR",
            run.bang_j,
            run.bang_j / run.mgr
        ),
        None => format!("{name}: energy ledger (no final bang reached)"),
    };
    line_chart(
        &whole,
        &caption,
        "t (s)",
        "energy (J)",
        &ledger_curves(run, t, &k, &p, &d),
        |chart, drawn| match bang_t {
            Some(b) => {
                let y = range(
                    k.iter()
                        .chain(&p)
                        .chain(&d)
                        .copied()
                        .chain([run.e0, run.mgr]),
                );
                mark_bang_start(chart, drawn, b, y)
            }
            None => Ok(()),
        },
    )?;
    if let (Some(area), Some(b)) = (zoom, bang_t) {
        bang_panel(&area, &run.samples, b, name)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The energy ledger's curves over `t`: kinetic `k`, potential `p`, lost so far `d`, and
/// the levels MgR and E0.
fn ledger_curves<'a>(
    run: &WrittenRun,
    t: &[f64],
    k: &[f64],
    p: &[f64],
    d: &[f64],
) -> [Curve<'a>; 5] {
    let (t0, t1) = (
        t.first().copied().unwrap_or(0.0),
        t.last().copied().unwrap_or(1.0),
    );
    [
        Curve {
            label: "kinetic",
            points: pairs(t, k),
            color: EXACT,
            dashed: false,
        },
        Curve {
            label: "potential (above the floor)",
            points: pairs(t, p),
            color: RGBColor(44, 160, 44),
            dashed: false,
        },
        Curve {
            label: "lost so far",
            points: pairs(t, d),
            color: EQ7,
            dashed: false,
        },
        Curve {
            label: "MgR",
            points: vec![(t0, run.mgr), (t1, run.mgr)],
            color: RGBColor(127, 127, 127),
            dashed: true,
        },
        Curve {
            label: "E0",
            points: vec![(t0, run.e0), (t1, run.e0)],
            color: SIM,
            dashed: true,
        },
    ]
}

/// A dashed vertical line at `b`, the start of the final bang, over `(y0, y1)`, booked in
/// `drawn`.
fn mark_bang_start(
    chart: &mut LinChart<'_, '_>,
    drawn: &mut Drawn,
    b: f64,
    (y0, y1): (f64, f64),
) -> anyhow::Result<()> {
    let c = RGBColor(148, 103, 189);
    draw_line(
        chart,
        drawn,
        vec![(b, y0), (b, y1)],
        Line::dashed(c, 1, 4, 4),
        "final bang begins",
    )
}

/// `path`: `N_tot` above, `F_tot` with its split into `F` and `F_int` below, against the
/// laid fraction up to 0.95 (the forces grow without bound as the coil runs out), the
/// simulation's beside the exact model's; `cut` reads a column of the unroll.
fn forces_plot(
    path: &Path,
    cut: &dyn Fn(&str) -> anyhow::Result<Vec<f64>>,
    name: &str,
) -> anyhow::Result<()> {
    type Spec = (&'static str, &'static str, RGBColor, bool);
    let panels: [(String, &str, Vec<Spec>); 2] = [
        (
            format!("{name}: upward force on the moving part, N_tot (link-period means)"),
            "N_tot (N)",
            vec![
                ("simulation", "n_tot_n", SIM, false),
                ("exact-geometry model", "n_tot_geo_n", EXACT, true),
                ("paper (eq. 9, A4)", "n_tot_ref_n", EQ7, true),
            ],
        ),
        (
            format!("{name}: F_tot = F (floor) + F_int (laid tape), +x positive"),
            "force (N)",
            vec![
                ("F_tot simulation", "f_tot_n", SIM, false),
                ("F_tot exact", "f_tot_geo_n", SIM, true),
                ("F simulation", "f_floor_n", EXACT, false),
                ("F exact (least pull)", "f_floor_geo_n", EXACT, true),
                ("F_int simulation", "f_int_n", EQ7, false),
                ("F_int exact (least pull)", "f_int_geo_n", EQ7, true),
            ],
        ),
    ];
    let root = SVGBackend::new(path, (900, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let areas = root.split_evenly((2, 1));
    let f = cut("laid_fraction")?;
    for (area, (caption, y_desc, specs)) in areas.iter().zip(panels) {
        let mut curves = Vec::new();
        for (label, column, color, dashed) in specs {
            let mut points = pairs(&f, &cut(column)?);
            points.retain(|p| p.0 <= 0.95);
            curves.push(Curve {
                label,
                points,
                color,
                dashed,
            });
        }
        line_chart(
            area,
            &caption,
            "laid fraction f",
            y_desc,
            &curves,
            |_, _| Ok(()),
        )?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The bang alone, from its release `bang_t` on, on a log time axis (its impacts take a
/// millisecond, its settling a tenth of a second): the kinetic energy and, cumulatively,
/// what it dissipated by mechanism (`samples.csv`'s `bang_*` columns).
fn bang_panel(
    area: &Area<'_>,
    samples: &SweepTable,
    bang_t: f64,
    name: &str,
) -> anyhow::Result<()> {
    let col = |c: &str| {
        samples
            .numbers(c)
            .with_context(|| format!("samples.csv has no `{c}` column"))
    };
    let t = col("t_s")?;
    let from = t.iter().position(|&ti| ti > bang_t).unwrap_or(t.len());
    let since: Vec<f64> = t[from..].iter().map(|ti| ti - bang_t).collect();
    let part = |c: &str| col(c).map(|v| pairs(&since, &v[from..]));
    // Each mechanism's label and column, and its colour; the numerical parts and the
    // model's discards are drawn dashed.
    let parts = [
        ("kinetic", "kinetic_j"),
        ("floor: normal impacts", "bang_floor_normal_j"),
        ("floor: friction", "bang_floor_friction_j"),
        ("layers: impacts", "bang_layers_normal_j"),
        ("layers: friction", "bang_layers_friction_j"),
        ("joints (numerical)", "bang_joints_j"),
        ("residual (numerical)", "bang_residual_j"),
        ("freezing", "bang_freeze_j"),
    ];
    let colors = [
        SIM,
        EXACT,
        RGBColor(44, 160, 44),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        EQ7,
        RGBColor(148, 103, 189),
        RGBColor(127, 127, 127),
    ];
    let curves = parts
        .into_iter()
        .zip(colors)
        .map(|((label, column), color)| {
            let dashed = label.contains("numerical") || label == "freezing";
            Ok((label, part(column)?, color, dashed))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let (x0, x1) = log_range(since.iter().copied());
    let (y0, y1) = range(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1)));
    let ticks = LogTicks::new((x0, x1), plot_size(area, true).0, X_TICK_ROOM_PX);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{name}: the final bang, from its release; dissipated so far, by mechanism"),
            font(DESC_PX),
        )
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(Y_LABEL_AREA_PX)
        .build_cartesian_2d(ticks.axis((x0, x1)), y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time since the release (s), log scale")
        .y_desc("energy (J)")
        .x_labels(ticks.values.len().max(1))
        .x_label_formatter(&LogTicks::label)
        .house_style()
        .draw()
        .map_err(err)?;
    let mut drawn = Drawn::default();
    for (label, points, color, dashed) in curves {
        let line = Line::curve(color, dashed);
        draw_line(&mut chart, &mut drawn, points, line, label)?;
    }
    legend(&mut chart, &drawn)
}

/// `approach.svg`: the contact-line speed against the equivalent radius over the unroll
/// (the samples up to the final bang), log-log, with the exact-geometry model, eq. (7) and its
/// x' ~ 1/r, and a mark where each reference stops applying and at the release.
fn approach_plot(path: &Path, run: &WrittenRun) -> anyhow::Result<()> {
    let sim = positive_pairs(&run.cut("r_m")?, &run.cut("xdot_m_s")?);
    let exact = reference_curve(&run.report.approach.exact_curve);
    let eq7 = reference_curve(&run.report.approach.eq7_curve);
    let t = run.cut("t_s")?;
    let r = run.cut("r_m")?;
    let root = SVGBackend::new(path, (900, 650)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let all = sim.iter().chain(&exact).chain(&eq7);
    let mut chart = log_chart(
        &root,
        &format!(
            "{}: contact-line speed against the equivalent radius r = R sqrt(1 - f)",
            run.name
        ),
        "r (m)",
        "x' (m/s)",
        all.clone().map(|p| p.0),
        all.map(|p| p.1),
    )?;
    let series = [
        ("simulation", &sim, SIM, false),
        ("exact-geometry model", &exact, EXACT, true),
        ("eq. (7)", &eq7, EQ7, true),
    ];
    let mut drawn = Drawn::default();
    for (label, pts, c, dashed) in series {
        let line = Line::curve(c, dashed);
        draw_line(&mut chart, &mut drawn, pts.clone(), line, label)?;
    }
    one_over_r(&mut chart, &mut drawn, &eq7)?;
    let marks = approach_marks(&run.report, &t, &r);
    draw_marks(&mut chart, &mut drawn, marks, &sim)?;
    legend(&mut chart, &drawn)?;
    root.present().map_err(err)?;
    Ok(())
}

/// A reference's own x'(r), down to the bang radius (the report's `approach` curves), where
/// both are positive.
fn reference_curve(curve: &[[f64; 2]]) -> Vec<(f64, f64)> {
    curve
        .iter()
        .map(|p| (p[0], p[1]))
        .filter(|(a, b)| *a > 0.0 && *b > 0.0)
        .collect()
}

/// Eq. (7)'s divergence, x' ~ 1/r, through its curve's point at the smallest r, booked in
/// `drawn`.
fn one_over_r(
    chart: &mut LogChart<'_, '_>,
    drawn: &mut Drawn,
    eq7: &[(f64, f64)],
) -> anyhow::Result<()> {
    if let (Some(&(r0, v0)), Some(&(r1, _))) = (
        eq7.iter().min_by(|a, b| a.0.total_cmp(&b.0)),
        eq7.iter().max_by(|a, b| a.0.total_cmp(&b.0)),
    ) {
        let c = RGBColor(127, 127, 127);
        draw_line(
            chart,
            drawn,
            vec![(r0, v0), (r1, v0 * r0 / r1)],
            Line::dashed(c, 1, 3, 3),
            "x' ~ 1/r (eq. 7 as r -> 0)",
        )?;
    }
    Ok(())
}

/// Where each reference stops applying, and the release, each at the simulation's
/// equivalent radius at that time (`t` and `r`: the samples of the unroll).
fn approach_marks(report: &RunReport, t: &[f64], r: &[f64]) -> Vec<(String, f64)> {
    let r_at = |time: f64| {
        t.iter()
            .position(|&ti| ti >= time)
            .and_then(|i| r.get(i).copied())
    };
    let mut marks: Vec<(String, f64)> = report
        .reference_limits
        .iter()
        .filter(|l| l.kind != LimitKind::FewTurns)
        .filter_map(|l| {
            let kind = serde_json::to_value(l.kind).ok()?;
            Some((kind.as_str()?.replace('-', " "), r_at(l.t_s?)?))
        })
        .collect();
    if report.bang.is_some() {
        marks.push(("the release (last link)".into(), report.approach.peak_r_m));
    }
    merged(marks)
}

/// Marks at the same radius (events within one sample of each other: the thin tape lifts
/// off where the exact model hops) as one line naming them all: one drawn over another
/// would hide it and leave its legend entry pointing at nothing.
fn merged(marks: Vec<(String, f64)>) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for (label, at) in marks {
        match out.iter_mut().find(|(_, r)| (*r / at - 1.0).abs() < 1e-9) {
            Some((names, _)) => *names = format!("{names}, {label} (the same sample)"),
            None => out.push((label, at)),
        }
    }
    out
}

/// The `marks` as vertical lines spanning the simulation's x' (`sim`), booked in `drawn`.
fn draw_marks(
    chart: &mut LogChart<'_, '_>,
    drawn: &mut Drawn,
    marks: Vec<(String, f64)>,
    sim: &[(f64, f64)],
) -> anyhow::Result<()> {
    let (y0, y1) = (
        sim.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
        sim.iter().map(|p| p.1).fold(0.0_f64, f64::max),
    );
    for (i, (label, at)) in marks.into_iter().enumerate() {
        if !(at > 0.0 && y0.is_finite() && y1 > 0.0) {
            continue;
        }
        let c = color(i + 3);
        let line = Line::solid(c, 1);
        draw_line(chart, drawn, vec![(at, y0), (at, y1)], line, label)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::merged;

    #[test]
    fn marks_at_one_radius_are_one_line_naming_both() {
        let marks = vec![
            ("lift off".to_owned(), 1.2e-3),
            ("exact model hops".to_owned(), 1.2e-3),
            ("the release (last link)".to_owned(), 2e-4),
        ];
        assert_eq!(
            merged(marks),
            [
                (
                    "lift off, exact model hops (the same sample)".to_owned(),
                    1.2e-3
                ),
                ("the release (last link)".to_owned(), 2e-4)
            ]
        );
    }
}
