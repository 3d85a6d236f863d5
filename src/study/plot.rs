//! Pictures as SVG (plotters, no system fonts needed): a run's motion and energy ledger
//! against the references, read back from its `samples.csv` and `report.json`, and a
//! sweep's Pareto plot and convergence plots from a [`SweepAnalysis`]. It computes nothing
//! new: every number drawn is in those files or in the analysis.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use crate::study::analysis::{BANG_OBSERVABLES, BangStudy, PowerFit, SweepAnalysis};
use crate::study::sweep::SweepTable;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A log-log chart on an SVG area.
type LogChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;
/// A linear chart on an SVG area.
type LinChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

const FONT: &str = "sans-serif";

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::anyhow!("cannot draw: {e}")
}

/// Finite `(x, y)` pairs.
fn pairs(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect()
}

/// The range of the finite values of `vs`, widened by 5% (or by 1 if flat).
fn range(vs: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vs
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
    (lo - pad, hi + pad)
}

/// The range of the finite positive values of `vs`, widened by a factor 1.3 each way.
fn log_range(vs: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vs
        .into_iter()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.1, 1.0);
    }
    (lo / 1.3, hi * 1.3)
}

/// One curve of a line chart.
struct Curve<'a> {
    label: &'a str,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

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

fn line_chart(
    area: &Area<'_>,
    caption: &str,
    x_desc: &str,
    y_desc: &str,
    curves: &[Curve<'_>],
    legend_at: SeriesLabelPosition,
    extra: impl FnOnce(&mut LinChart<'_, '_>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let (x0, x1) = range(curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)));
    let (y0, y1) = range(curves.iter().flat_map(|c| c.points.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    for c in curves {
        let color = c.color;
        let style = color.stroke_width(2);
        if c.dashed {
            chart
                .draw_series(DashedLineSeries::new(c.points.iter().copied(), 8, 5, style))
                .map_err(err)?
        } else {
            chart
                .draw_series(LineSeries::new(c.points.iter().copied(), style))
                .map_err(err)?
        }
        .label(c.label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    extra(&mut chart)?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend_at)
        .label_font((FONT, 14))
        .draw()
        .map_err(err)?;
    Ok(())
}

const SIM: RGBColor = RGBColor(0, 0, 0);
const EXACT: RGBColor = RGBColor(31, 119, 180);
const EQ7: RGBColor = RGBColor(214, 39, 40);

/// Draws, from the run's `samples.csv` and `report.json`: `dir/motion.svg` (r and x'
/// against time, with the exact-geometry model and eq. (7), up to the final bang),
/// `dir/energy.svg` (kinetic, potential and lost energy over the whole run, with MgR, E0
/// and the drop at the bang; below, the bang alone, with what it dissipated split by
/// mechanism) and `dir/approach.svg` (x' against r, log-log, over the unroll, with the
/// references, eq. (7)'s x' ~ 1/r, and where the references stop applying) and
/// `dir/forces.svg` (`N_tot`, and `F_tot` with its split into `F` and `F_int`, against the
/// laid fraction up to 0.95, with the exact-geometry model's). Returns the files written.
pub fn plot_run(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let samples = SweepTable::read(&dir.join("samples.csv"))?;
    let report_path = dir.join("report.json");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&report_path)
            .with_context(|| format!("cannot read {}", report_path.display()))?,
    )
    .with_context(|| format!("{} is not JSON", report_path.display()))?;
    let ledger = &report["ledger"];
    let num = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .with_context(|| format!("{}: no number `{what}`", report_path.display()))
    };
    let mgr = num(&ledger["mgr_j"], "ledger.mgr_j")?;
    let e0 = num(&ledger["e0_j"], "ledger.e0_j")?;
    let bang_j = num(
        &ledger["dissipated_by_bang_j"],
        "ledger.dissipated_by_bang_j",
    )?;
    let bang_t = ledger["bang_time_s"].as_f64();
    let name = report["scene"]["name"].as_str().unwrap_or("run").to_owned();
    let col = |c: &str| {
        samples
            .numbers(c)
            .with_context(|| format!("samples.csv has no `{c}` column"))
    };
    let t = col("t_s")?;
    let upto = t
        .iter()
        .position(|&ti| bang_t.is_some_and(|b| ti > b))
        .unwrap_or(t.len());
    let tr = &t[..upto];
    let cut = |c: &str| col(c).map(|v| v[..upto].to_vec());

    let motion = dir.join("motion.svg");
    {
        let root = SVGBackend::new(&motion, (900, 800)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let panels = root.split_evenly((2, 1));
        let r = [cut("r_m")?, cut("r_geo_m")?, cut("r_ref_m")?];
        line_chart(
            &panels[0],
            &format!("{name}: equivalent coil radius r = R sqrt(1 - laid fraction)"),
            "t (s)",
            "r (m)",
            &against_references(tr, &r),
            SeriesLabelPosition::UpperLeft,
            |_| Ok(()),
        )?;
        let v = [cut("xdot_m_s")?, cut("xdot_geo_m_s")?, cut("xdot_ref_m_s")?];
        line_chart(
            &panels[1],
            &format!("{name}: contact-line speed x', up to the final bang"),
            "t (s)",
            "x' (m/s)",
            &against_references(tr, &v),
            SeriesLabelPosition::UpperLeft,
            |_| Ok(()),
        )?;
        root.present().map_err(err)?;
    }

    let energy = dir.join("energy.svg");
    {
        let height = if bang_t.is_some() { 950 } else { 500 };
        let root = SVGBackend::new(&energy, (900, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (whole, zoom) = if bang_t.is_some() {
            let (a, b) = root.split_vertically(500);
            (a, Some(b))
        } else {
            (root.clone(), None)
        };
        let k = col("kinetic_j")?;
        let p = col("potential_j")?;
        let d = col("dissipated_j")?;
        let (t0, t1) = (
            t.first().copied().unwrap_or(0.0),
            t.last().copied().unwrap_or(1.0),
        );
        let caption = match bang_t {
            Some(b) => format!(
                "{name}: energy ledger; the final bang at t = {b:.3} s dissipates {bang_j:.3} J = {:.2} MgR",
                bang_j / mgr
            ),
            None => format!("{name}: energy ledger (no final bang reached)"),
        };
        line_chart(
            &whole,
            &caption,
            "t (s)",
            "energy (J)",
            &[
                Curve {
                    label: "kinetic",
                    points: pairs(&t, &k),
                    color: EXACT,
                    dashed: false,
                },
                Curve {
                    label: "potential (above the floor)",
                    points: pairs(&t, &p),
                    color: RGBColor(44, 160, 44),
                    dashed: false,
                },
                Curve {
                    label: "lost so far",
                    points: pairs(&t, &d),
                    color: EQ7,
                    dashed: false,
                },
                Curve {
                    label: "MgR",
                    points: vec![(t0, mgr), (t1, mgr)],
                    color: RGBColor(127, 127, 127),
                    dashed: true,
                },
                Curve {
                    label: "E0",
                    points: vec![(t0, e0), (t1, e0)],
                    color: SIM,
                    dashed: true,
                },
            ],
            SeriesLabelPosition::MiddleLeft,
            |chart| {
                if let Some(b) = bang_t {
                    let (y0, y1) = range(k.iter().chain(&p).chain(&d).copied().chain([e0, mgr]));
                    let c = RGBColor(148, 103, 189);
                    chart
                        .draw_series(DashedLineSeries::new(
                            [(b, y0), (b, y1)],
                            4,
                            4,
                            c.stroke_width(1),
                        ))
                        .map_err(err)?
                        .label("final bang begins")
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1))
                        });
                }
                Ok(())
            },
        )?;
        if let (Some(area), Some(b)) = (zoom, bang_t) {
            bang_panel(&area, &samples, b, &name)?;
        }
        root.present().map_err(err)?;
    }

    let approach = dir.join("approach.svg");
    approach_plot(&approach, &samples, &report, upto, &name)?;

    let forces = dir.join("forces.svg");
    forces_plot(&forces, &cut, &name)?;
    Ok(vec![motion, energy, approach, forces])
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
    let panels: [(String, &str, Vec<Spec>, SeriesLabelPosition); 2] = [
        (
            format!("{name}: upward force on the moving part, N_tot (link-period means)"),
            "N_tot (N)",
            vec![
                ("simulation", "n_tot_n", SIM, false),
                ("exact-geometry model", "n_tot_geo_n", EXACT, true),
                ("paper (eq. 9, A4)", "n_tot_ref_n", EQ7, true),
            ],
            SeriesLabelPosition::UpperRight,
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
            SeriesLabelPosition::LowerLeft,
        ),
    ];
    let root = SVGBackend::new(path, (900, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let areas = root.split_evenly((2, 1));
    let f = cut("laid_fraction")?;
    for (area, (caption, y_desc, specs, legend_at)) in areas.iter().zip(panels) {
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
            legend_at,
            |_| Ok(()),
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
    let curves = [
        ("kinetic", part("kinetic_j")?, SIM, false),
        (
            "floor: normal impacts",
            part("bang_floor_normal_j")?,
            EXACT,
            false,
        ),
        (
            "floor: friction",
            part("bang_floor_friction_j")?,
            RGBColor(44, 160, 44),
            false,
        ),
        ("joints (numerical)", part("bang_joints_j")?, EQ7, true),
        (
            "residual (numerical)",
            part("bang_residual_j")?,
            RGBColor(148, 103, 189),
            true,
        ),
        (
            "freezing",
            part("bang_freeze_j")?,
            RGBColor(127, 127, 127),
            true,
        ),
    ];
    let (x0, x1) = log_range(since.iter().copied());
    let (y0, y1) = range(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{name}: the final bang, from its release; dissipated so far, by mechanism"),
            (FONT, 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time since the release (s), log scale")
        .y_desc("energy (J)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    for (label, points, color, dashed) in curves {
        let style = color.stroke_width(2);
        if dashed {
            chart
                .draw_series(DashedLineSeries::new(points, 8, 5, style))
                .map_err(err)?
        } else {
            chart
                .draw_series(LineSeries::new(points, style))
                .map_err(err)?
        }
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::MiddleLeft)
        .label_font((FONT, 14))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// `approach.svg`: the contact-line speed against the equivalent radius over the unroll
/// (the first `upto` samples), log-log, with the exact-geometry model, eq. (7) and its
/// x' ~ 1/r, and a mark where each reference stops applying and at the release.
fn approach_plot(
    path: &Path,
    samples: &SweepTable,
    report: &serde_json::Value,
    upto: usize,
    name: &str,
) -> anyhow::Result<()> {
    let col = |c: &str| {
        samples
            .numbers(c)
            .map(|v| v[..upto].to_vec())
            .with_context(|| format!("samples.csv has no `{c}` column"))
    };
    let positive = |x: Vec<f64>, y: Vec<f64>| -> Vec<(f64, f64)> {
        pairs(&x, &y)
            .into_iter()
            .filter(|(a, b)| *a > 0.0 && *b > 0.0)
            .collect()
    };
    let sim = positive(col("r_m")?, col("xdot_m_s")?);
    // The references' own x'(r), down to the bang radius (report.json's `approach`).
    let curve = |key: &str| -> Vec<(f64, f64)> {
        report["approach"][key]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|p| Some((p[0].as_f64()?, p[1].as_f64()?)))
            .filter(|(a, b)| *a > 0.0 && *b > 0.0)
            .collect()
    };
    let exact = curve("exact_curve");
    let eq7 = curve("eq7_curve");
    let t = col("t_s")?;
    let r = col("r_m")?;
    let root = SVGBackend::new(path, (900, 650)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let all = sim.iter().chain(&exact).chain(&eq7);
    let mut chart = log_chart(
        &root,
        &format!("{name}: contact-line speed against the equivalent radius r = R sqrt(1 - f)"),
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
    for (label, pts, c, dashed) in series {
        let style = c.stroke_width(2);
        if dashed {
            chart
                .draw_series(DashedLineSeries::new(pts.iter().copied(), 8, 5, style))
                .map_err(err)?
        } else {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))
                .map_err(err)?
        }
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    // Eq. (7)'s divergence, x' ~ 1/r, through its curve's point at the smallest r.
    if let (Some(&(r0, v0)), Some(&(r1, _))) = (
        eq7.iter().min_by(|a, b| a.0.total_cmp(&b.0)),
        eq7.iter().max_by(|a, b| a.0.total_cmp(&b.0)),
    ) {
        let c = RGBColor(127, 127, 127);
        chart
            .draw_series(DashedLineSeries::new(
                [(r0, v0), (r1, v0 * r0 / r1)],
                3,
                3,
                c.stroke_width(1),
            ))
            .map_err(err)?
            .label("x' ~ 1/r (eq. 7 as r -> 0)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1)));
    }
    // Marks: where each reference stops applying, and the release; at the simulation's
    // equivalent radius at that time.
    let r_at = |time: f64| {
        t.iter()
            .position(|&ti| ti >= time)
            .and_then(|i| r.get(i).copied())
    };
    let mut marks: Vec<(String, f64)> = report["reference_limits"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|l| l["kind"] != "few-turns")
        .filter_map(|l| {
            let time = l["t_s"].as_f64()?;
            Some((l["kind"].as_str()?.replace('-', " "), r_at(time)?))
        })
        .collect();
    if let Some(peak) = report["approach"]["peak_r_m"].as_f64()
        && report["bang"].is_object()
    {
        marks.push(("the release (last link)".into(), peak));
    }
    let (y0, y1) = (
        sim.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
        sim.iter().map(|p| p.1).fold(0.0_f64, f64::max),
    );
    for (i, (label, at)) in marks.into_iter().enumerate() {
        if !(at > 0.0 && y0.is_finite() && y1 > 0.0) {
            continue;
        }
        let c = color(i + 3);
        chart
            .draw_series(LineSeries::new([(at, y0), (at, y1)], c.stroke_width(1)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1)));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(err)?;
    Ok(())
}

fn log_chart<'a, 'b>(
    area: &'a Area<'b>,
    caption: &str,
    x_desc: &str,
    y_desc: &str,
    xs: impl IntoIterator<Item = f64>,
    ys: impl IntoIterator<Item = f64>,
) -> anyhow::Result<LogChart<'a, 'b>> {
    let (x0, x1) = log_range(xs);
    let (y0, y1) = log_range(ys);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(20)
        .y_labels(20)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>,
    pos: SeriesLabelPosition,
) -> anyhow::Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(pos)
        .label_font((FONT, 13))
        .draw()
        .map_err(|e| anyhow::anyhow!("cannot draw: {e}"))
}

fn color(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    C[i % C.len()]
}

/// `p ± se` of a fit.
fn order(f: &PowerFit) -> String {
    if f.order_se.is_finite() {
        format!("{:.2} ± {:.2}", f.order, f.order_se)
    } else {
        format!("{:.2}", f.order)
    }
}

/// Draws a fitted power law over `[h0, h1]` and names its order in the legend.
fn fit_line<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>,
    fit: &PowerFit,
    h: &[f64],
    label: String,
    c: RGBColor,
) -> anyhow::Result<()> {
    let (lo, hi) = h
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return Ok(());
    }
    chart
        .draw_series(DashedLineSeries::new(
            [(lo, fit.eval(lo)), (hi, fit.eval(hi))],
            6,
            4,
            c.stroke_width(1),
        ))
        .map_err(|e| anyhow::anyhow!("cannot draw: {e}"))?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(1)));
    Ok(())
}

/// Draws a sweep's pictures into `dir`: `pareto.svg` (error against cost, log-log, one
/// series per contact model / solver setting, the front joined) and, per varied numeric
/// key, `convergence-<key>.svg` (error and energy lost before the bang against the step
/// size with the fitted orders, and the wall time per step against links). Returns the
/// files written.
pub fn plot_sweep(a: &SweepAnalysis, dir: &Path, title: &str) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let mut written = Vec::new();

    let pareto = dir.join("pareto.svg");
    {
        let root = SVGBackend::new(&pareto, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let idx: Vec<usize> = (0..a.cost.len())
            .filter(|&i| a.cost[i].is_finite() && a.err[i].is_finite() && a.err[i] > 0.0)
            .collect();
        let mut chart = log_chart(
            &root,
            &format!("{title}: error against wall time"),
            &format!("wall time, {} (s)", a.cost_column),
            &format!("max |time error| vs {}", a.reference.label()),
            idx.iter().map(|&i| a.cost[i]).chain(a.target.map(|t| t.1)),
            idx.iter().map(|&i| a.err[i]).chain(a.target.map(|t| t.0)),
        )?;
        let mut names: Vec<&String> = idx.iter().map(|&i| &a.series[i]).collect();
        names.sort();
        names.dedup();
        for (si, name) in names.iter().enumerate() {
            let c = color(si);
            let pts: Vec<(f64, f64)> = idx
                .iter()
                .filter(|&&i| &&a.series[i] == name)
                .map(|&i| (a.cost[i], a.err[i]))
                .collect();
            let label = if name.is_empty() {
                "runs".to_owned()
            } else {
                (*name).clone()
            };
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
        }
        let front: Vec<(f64, f64)> = a
            .front
            .iter()
            .filter(|&&i| a.err[i] > 0.0)
            .map(|&i| (a.cost[i], a.err[i]))
            .collect();
        chart
            .draw_series(LineSeries::new(front, BLACK.stroke_width(1)))
            .map_err(err)?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        if let Some((e, c)) = a.target {
            let (x0, _) = log_range(idx.iter().map(|&i| a.cost[i]).chain([c]));
            let (y0, _) = log_range(idx.iter().map(|&i| a.err[i]).chain([e]));
            let grey = RGBColor(127, 127, 127);
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, e), (c, e), (c, y0)],
                    6,
                    4,
                    grey.stroke_width(2),
                ))
                .map_err(err)?
                .label(format!("target: <= {:.2}% in <= {c} s", 100.0 * e))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        root.present().map_err(err)?;
    }
    written.push(pareto);

    let mut keys: Vec<&String> = a.studies.iter().map(|s| &s.key).collect();
    keys.dedup();
    for key in keys {
        let studies: Vec<_> = a.studies.iter().filter(|s| &s.key == key).collect();
        let path = dir.join(format!("convergence-{key}.svg"));
        let root = SVGBackend::new(&path, (900, 1200)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let panels = root.split_evenly((3, 1));
        let h_desc = format!("step h of {key} (1/value unless the key is in s or m)");
        for (panel, which) in panels.iter().take(2).zip(0..) {
            let (ys, fits): (Vec<&Vec<f64>>, Vec<Option<PowerFit>>) = studies
                .iter()
                .map(|s| {
                    if which == 0 {
                        (&s.err, s.err_fit)
                    } else {
                        (&s.lost, s.lost_fit)
                    }
                })
                .unzip();
            let caption = if which == 0 {
                format!("{title}: max |time error| vs {}", a.reference.label())
            } else {
                format!("{title}: energy lost before the bang")
            };
            let mut chart = log_chart(
                panel,
                &caption,
                &h_desc,
                if which == 0 { "error" } else { "lost / E0" },
                studies.iter().flat_map(|s| s.h.iter().copied()),
                ys.iter().flat_map(|y| y.iter().copied()).chain(
                    studies
                        .iter()
                        .filter(|_| which == 0)
                        .flat_map(|s| s.self_err.iter().copied()),
                ),
            )?;
            for (si, (s, (y, fit))) in studies.iter().zip(ys.iter().zip(&fits)).enumerate() {
                let c = color(si);
                let pts: Vec<(f64, f64)> = pairs(&s.h, y)
                    .into_iter()
                    .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                    .collect();
                let group = if s.group.is_empty() || studies.len() == 1 {
                    String::new()
                } else {
                    format!("{}: ", s.group)
                };
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                    .map_err(err)?
                    .label(format!("{group}runs"))
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
                if let Some(f) = fit {
                    fit_line(
                        &mut chart,
                        f,
                        &s.h,
                        format!("{group}fit: order {} (R² {:.3})", order(f), f.r2),
                        c,
                    )?;
                }
                if which == 0 {
                    let pts: Vec<(f64, f64)> = pairs(&s.h, &s.self_err)
                        .into_iter()
                        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                        .collect();
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.stroke_width(1))))
                        .map_err(err)?
                        .label(format!("{group}change from the finest run"))
                        .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.stroke_width(1)));
                    if let Some(f) = &s.self_fit {
                        fit_line(
                            &mut chart,
                            f,
                            &s.h,
                            format!(
                                "{group}self-convergence: order {} (R² {:.3})",
                                order(f),
                                f.r2
                            ),
                            c,
                        )?;
                    }
                }
            }
            legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        }
        let mut chart = log_chart(
            &panels[2],
            &format!("{title}: wall time per step against links"),
            "links",
            "wall time per step (s)",
            studies.iter().flat_map(|s| s.links.iter().copied()),
            studies
                .iter()
                .flat_map(|s| s.wall_per_step_s.iter().copied()),
        )?;
        for (si, s) in studies.iter().enumerate() {
            let c = color(si);
            let pts = pairs(&s.links, &s.wall_per_step_s);
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map_err(err)?
                .label(if s.group.is_empty() || studies.len() == 1 {
                    "runs".to_owned()
                } else {
                    s.group.clone()
                })
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
            if let Some(f) = &s.cost_fit {
                fit_line(
                    &mut chart,
                    f,
                    &s.links,
                    format!("slope {} (R² {:.3})", order(f), f.r2),
                    c,
                )?;
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        root.present().map_err(err)?;
        written.push(path.clone());
    }
    // The final bang's ensembles: one picture per study (per key, if only one group).
    let keys: Vec<&str> = a.bang.iter().map(|b| b.key.as_str()).collect();
    for (i, b) in a.bang.iter().enumerate() {
        let alone = keys.iter().filter(|k| **k == b.key).count() == 1;
        let stem = if alone {
            format!("bang-{}", b.key)
        } else {
            format!("bang-{}-{i}", b.key)
        };
        let path = dir.join(format!("{stem}.svg"));
        bang_study_plot(&path, b, title)?;
        written.push(path);
    }
    Ok(written)
}

/// One panel per bang observable: its ensemble mean ± standard error against the step h
/// of the study's key (log h).
fn bang_study_plot(path: &Path, b: &BangStudy, title: &str) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (1000, 1400)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (head, body) = root.split_vertically(40);
    head.draw(&Text::new(
        format!(
            "{title}: the final bang against {}{} (ensemble mean ± standard error)",
            b.key,
            if b.group.is_empty() {
                String::new()
            } else {
                format!(", {}", b.group)
            }
        ),
        (20, 12),
        (FONT, 18),
    ))
    .map_err(err)?;
    let panels = body.split_evenly((5, 2));
    let (h0, h1) = log_range(b.h.iter().copied());
    for (k, panel) in panels.iter().enumerate().take(BANG_OBSERVABLES.len()) {
        let (m, se) = (&b.mean[k], &b.se[k]);
        let lo = m.iter().zip(se).map(|(m, s)| m - s.max(0.0));
        let hi = m.iter().zip(se).map(|(m, s)| m + s.max(0.0));
        let (y0, y1) = range(lo.chain(hi));
        let mut chart = ChartBuilder::on(panel)
            .caption(BANG_OBSERVABLES[k].0, (FONT, 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d((h0..h1).log_scale(), y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(format!("h of {}", b.key))
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(err)?;
        let pts = pairs(&b.h, m);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), SIM.stroke_width(1)))
            .map_err(err)?;
        chart
            .draw_series(
                b.h.iter()
                    .zip(m)
                    .zip(se)
                    .filter(|((h, m), s)| h.is_finite() && m.is_finite() && s.is_finite())
                    .map(|((&h, &m), &s)| {
                        ErrorBar::new_vertical(h, m - s, m, m + s, EXACT.filled(), 6)
                    }),
            )
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
