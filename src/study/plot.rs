//! Pictures as SVG (plotters, no system fonts needed): a run's motion and energy ledger
//! against the references, read back from its `samples.csv` and `report.json`, and a
//! sweep's Pareto plot and convergence plots from a
//! [`SweepAnalysis`](crate::study::analysis::SweepAnalysis). It computes nothing new: every
//! number drawn is in those files or in the analysis.
//!
//! This file holds what both kinds of picture share (ranges, colours, the line chart, the
//! log-log chart and its legend); a run's pictures are in `run`, a sweep's in `sweep`.

mod run;
mod sweep;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

pub use self::run::plot_run;
pub use self::sweep::plot_sweep;

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

/// The finite pairs of `x` and `y` where both are positive (for a log-log chart).
fn positive_pairs(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    pairs(x, y)
        .into_iter()
        .filter(|(a, b)| *a > 0.0 && *b > 0.0)
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

/// How a line is drawn: its colour, its width and its dash (dash and gap, px; none for a
/// solid line). Its series and its legend swatch are both drawn from it ([`draw_line`]), so
/// a swatch always looks like its line.
#[derive(Debug, Clone, Copy)]
struct Line {
    color: RGBColor,
    width: u32,
    dash: Option<(u32, u32)>,
}

impl Line {
    /// A solid line.
    const fn solid(color: RGBColor, width: u32) -> Self {
        Self {
            color,
            width,
            dash: None,
        }
    }

    /// A dashed line: dashes of `dash` px with gaps of `gap` px.
    const fn dashed(color: RGBColor, width: u32, dash: u32, gap: u32) -> Self {
        Self {
            color,
            width,
            dash: Some((dash, gap)),
        }
    }

    /// The references' dash and the simulation's solid line, at width 2.
    const fn curve(color: RGBColor, dashed: bool) -> Self {
        if dashed {
            Self::dashed(color, 2, 8, 5)
        } else {
            Self::solid(color, 2)
        }
    }

    fn style(self) -> ShapeStyle {
        self.color.stroke_width(self.width)
    }
}

/// Length of a legend swatch (px).
const SWATCH_PX: u32 = 20;

/// Draws `points` as `line` on `chart` under `label`, with a legend swatch drawn as the
/// line is: one stroke for a solid line, the same dashes for a dashed one.
fn draw_line<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    points: Vec<CT::From>,
    line: Line,
    label: impl Into<String>,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    CT: CoordTranslate,
    CT::From: Clone + 'static,
{
    let style = line.style();
    let anno = match line.dash {
        None => chart.draw_series(LineSeries::new(points, style)),
        Some((dash, gap)) => chart.draw_series(DashedLineSeries::new(points, dash, gap, style)),
    }
    .map_err(err)?;
    // A solid swatch is one dash as long as the swatch.
    let (dash, gap) = line.dash.unwrap_or((SWATCH_PX, SWATCH_PX));
    anno.label(label).legend(move |(x, y)| {
        DashedPathElement::new(vec![(x, y), (x + SWATCH_PX as i32, y)], dash, gap, style)
    });
    Ok(())
}

/// One curve of a line chart.
struct Curve<'a> {
    label: &'a str,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
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
        draw_line(
            &mut chart,
            c.points.clone(),
            Line::curve(c.color, c.dashed),
            c.label,
        )?;
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
