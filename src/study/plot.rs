//! Pictures as SVG (plotters, no system fonts needed): a run's motion and energy ledger
//! against the references, read back from its `samples.csv` and `report.json`, and a
//! sweep's Pareto plot and convergence plots from a
//! [`SweepAnalysis`](crate::study::analysis::SweepAnalysis). It computes nothing new: every
//! number drawn is in those files or in the analysis.
//!
//! This file holds what both kinds of picture share (ranges, colours, text sizes, the line
//! chart, the log-log chart, and the legend, placed where it hides least of what is drawn:
//! `legend_spot`); a run's pictures are in `run`, a sweep's in `sweep`.

mod bang;
mod run;
mod shares;
mod sweep;
mod ticks;

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use self::ticks::{LogAxis, LogTicks};

pub use self::bang::{BANG_PANELS, BANG_SVG, BangPicture};
pub use self::run::{RunPlots, plot_run};
pub use self::sweep::plot_sweep;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A point in a drawing backend's pixels (plotters' `BackendCoord`).
type BackendCoord = (i32, i32);

/// A log-log chart on an SVG area.
type LogChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogAxis, LogAxis>>;
/// A linear chart on an SVG area.
type LinChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

const FONT: &str = "sans-serif";

/// Tick labels' height on the page (px), on canvases 900-1000 px wide.
const TICK_PX: f64 = 16.0;
/// Axis descriptions' and panel captions' height on the page (px).
const DESC_PX: f64 = 18.0;
/// Legend labels' height on the page (px).
const LEGEND_PX: f64 = 14.0;
/// Height of the area below a chart (px): the tick (5 px), its gap (10), a tick label, a
/// gap and the axis description, none cut off.
const X_LABEL_AREA_PX: u32 = 62;
/// Width of the area left of a chart (px): the description turned upright, a gap, tick
/// labels up to 6 characters ("-0.005"), their gap (10) and the tick.
const Y_LABEL_AREA_PX: u32 = 100;
/// Space around a chart (px).
const MARGIN_PX: u32 = 12;

/// A font about `px` pixels high on the page: plotters' SVG writes a size s as s / 1.24 px
/// (and lays text out by the same rule), and takes whole sizes only, so it is given the
/// whole number nearest 1.24 `px` (16 px: 20, written 16.1 px; 18 px: 22, 17.7 px).
fn font(px: f64) -> (&'static str, f64) {
    (FONT, (1.24 * px).round())
}

/// The plotting area's size (px) a chart built on `area` with this module's margins and
/// label areas will have, `caption` or not: what the ticks are chosen for, before the
/// chart is built.
fn plot_size(area: &Area<'_>, caption: bool) -> (u32, u32) {
    let (w, h) = area.dim_in_pixel();
    let caption_px = if caption { (1.5 * DESC_PX) as u32 } else { 0 };
    (
        w.saturating_sub(2 * MARGIN_PX + Y_LABEL_AREA_PX),
        h.saturating_sub(2 * MARGIN_PX + X_LABEL_AREA_PX + caption_px),
    )
}

/// The room a tick label needs along an x axis (px): five characters and a gap.
const X_TICK_ROOM_PX: f64 = 3.5 * TICK_PX;
/// The room a tick label needs along a y axis (px): its height and a gap.
const Y_TICK_ROOM_PX: f64 = 1.5 * TICK_PX;

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

/// What a chart has drawn that its legend must not hide, and the legend's labels:
/// [`draw_line`] and [`draw_markers`] add to it, [`legend`] places the legend by it.
#[derive(Debug, Default)]
struct Drawn {
    /// Each line drawn (a marker: a line of one point), in the backend's pixels.
    ink: Vec<Vec<BackendCoord>>,
    /// The legend's labels, in order.
    labels: Vec<String>,
}

impl Drawn {
    /// Books `points` of `chart`'s data as drawn, as one line or as `markers`, under `label`.
    fn book<DB, CT>(
        &mut self,
        chart: &ChartContext<'_, DB, CT>,
        points: &[CT::From],
        markers: bool,
        label: String,
    ) where
        DB: DrawingBackend,
        CT: CoordTranslate,
    {
        let px = points.iter().map(|p| chart.as_coord_spec().translate(p));
        if markers {
            self.ink.extend(px.map(|p| vec![p]));
        } else {
            self.ink.push(px.collect());
        }
        self.labels.push(label);
    }

    /// Books `points` of `chart`'s data as drawn ink with no legend entry of their own (an
    /// error bar's ends).
    fn book_ink<DB, CT>(&mut self, chart: &ChartContext<'_, DB, CT>, points: &[CT::From])
    where
        DB: DrawingBackend,
        CT: CoordTranslate,
    {
        let px = points.iter().map(|p| chart.as_coord_spec().translate(p));
        self.ink.extend(px.map(|p| vec![p]));
    }
}

/// Draws `points` as `line` on `chart` under `label`, with a legend swatch drawn as the
/// line is: one stroke for a solid line, the same dashes for a dashed one; books it in
/// `drawn`.
fn draw_line<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    drawn: &mut Drawn,
    points: Vec<CT::From>,
    line: Line,
    label: impl Into<String>,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    CT: CoordTranslate,
    CT::From: Clone + 'static,
{
    let label = label.into();
    drawn.book(chart, &points, false, label.clone());
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

/// Draws `points` as circles of 4 px in `style` (filled or an outline) on `chart` under
/// `label`, the legend's marker the same; books them in `drawn`.
fn draw_markers(
    chart: &mut LogChart<'_, '_>,
    drawn: &mut Drawn,
    points: &[(f64, f64)],
    style: ShapeStyle,
    label: String,
) -> anyhow::Result<()> {
    drawn.book(chart, points, true, label.clone());
    chart
        .draw_series(points.iter().map(|&p| Circle::new(p, 4, style)))
        .map_err(err)?
        .label(label)
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, style));
    Ok(())
}

/// Where a chart's legend goes so that it hides no curve: of plotters' nine places in the
/// plotting area `(xs, ys)` (its pixel ranges), the one whose box of `size` (w, h px),
/// widened by 4 px, covers the fewest points of `ink` (the chart's lines as drawn, in
/// pixels, each walked in steps of at most 2 px, so that a line counts by its length, not
/// by its samples; a marker is one point); if none is free, still the one with fewest. On a
/// tie the first of: the corners (upper right, upper left, lower right, lower left), the
/// sides' middles, the centre.
fn legend_spot(
    (xs, ys): (Range<i32>, Range<i32>),
    (w, h): (i32, i32),
    ink: &[Vec<BackendCoord>],
) -> SeriesLabelPosition {
    use SeriesLabelPosition::*;
    // plotters' layout: 5 px in from the area's sides, or centred.
    let (aw, ah) = (xs.end - xs.start, ys.end - ys.start);
    let places = [
        (UpperRight, aw - w - 5, 5),
        (UpperLeft, 5, 5),
        (LowerRight, aw - w - 5, ah - h - 5),
        (LowerLeft, 5, ah - h - 5),
        (MiddleRight, aw - w - 5, (ah - h) / 2),
        (MiddleLeft, 5, (ah - h) / 2),
        (UpperMiddle, (aw - w) / 2, 5),
        (LowerMiddle, (aw - w) / 2, ah - h - 5),
        (MiddleMiddle, (aw - w) / 2, (ah - h) / 2),
    ];
    let boxes: Vec<[f64; 4]> = places
        .iter()
        .map(|(_, x, y)| {
            let (x0, y0) = (f64::from(xs.start + x - 4), f64::from(ys.start + y - 4));
            [x0, y0, x0 + f64::from(w + 8), y0 + f64::from(h + 8)]
        })
        .collect();
    let mut covered = vec![0_usize; places.len()];
    let mut count = |(x, y): (f64, f64)| {
        for (n, b) in covered.iter_mut().zip(&boxes) {
            *n += usize::from(x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3]);
        }
    };
    let at = |p: &BackendCoord| (f64::from(p.0), f64::from(p.1));
    for line in ink {
        if let Some(first) = line.first() {
            count(at(first));
        }
        for pair in line.windows(2) {
            let ((x0, y0), (x1, y1)) = (at(&pair[0]), at(&pair[1]));
            let steps = ((x1 - x0).hypot(y1 - y0) / 2.0).ceil().min(4000.0);
            for k in 1..steps as usize {
                let s = k as f64 / steps;
                count((x0 + s * (x1 - x0), y0 + s * (y1 - y0)));
            }
            count((x1, y1));
        }
    }
    let best = (0..places.len()).min_by_key(|&i| covered[i]).unwrap_or(0);
    places[best].0.clone()
}

/// Draws `chart`'s legend, of `drawn`'s labels, where it hides least of what `drawn` holds
/// ([`legend_spot`]), its box as plotters lays it out (labels at [`LEGEND_PX`], a margin of
/// 10 px, 30 px for the swatches).
fn legend<'a, DB, CT>(chart: &mut ChartContext<'a, DB, CT>, drawn: &Drawn) -> anyhow::Result<()>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    let style = TextStyle::from(font(LEGEND_PX).into_font());
    let mut text = MultiLineText::<BackendCoord, &str>::new((0, 0), &style);
    for label in &drawn.labels {
        text.push_line(label.as_str());
    }
    let (w, h) = text.estimate_dimension().map_err(err)?;
    let (margin, swatches) = (10, 30);
    let size = (w + swatches + 2 * margin, h + 2 * margin);
    let at = legend_spot(chart.plotting_area().get_pixel_range(), size, &drawn.ink);
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(at)
        .margin(margin)
        .legend_area_size(swatches)
        .label_font(font(LEGEND_PX))
        .draw()
        .map_err(err)
}

/// The house style of a chart's mesh: tick labels and axis descriptions in the plots' fonts,
/// no light grid lines.
trait HouseStyle {
    /// Applies the house style.
    fn house_style(&mut self) -> &mut Self;
}

impl<X, Y, DB> HouseStyle for plotters::chart::MeshStyle<'_, '_, X, Y, DB>
where
    X: Ranged,
    Y: Ranged,
    DB: DrawingBackend,
{
    fn house_style(&mut self) -> &mut Self {
        self.label_style(font(TICK_PX))
            .axis_desc_style(font(DESC_PX))
            .light_line_style(WHITE.mix(0.0))
    }
}

/// One curve of a line chart.
struct Curve<'a> {
    label: &'a str,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

/// A line chart of `curves` on `area`, with what `extra` draws on it (booked in the
/// [`Drawn`] it is given), and its legend where it hides least ([`legend`]).
fn line_chart(
    area: &Area<'_>,
    caption: &str,
    x_desc: &str,
    y_desc: &str,
    curves: &[Curve<'_>],
    extra: impl FnOnce(&mut LinChart<'_, '_>, &mut Drawn) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let (x0, x1) = range(curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)));
    let (y0, y1) = range(curves.iter().flat_map(|c| c.points.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, font(DESC_PX))
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(Y_LABEL_AREA_PX)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .house_style()
        .draw()
        .map_err(err)?;
    let mut drawn = Drawn::default();
    for c in curves {
        draw_line(
            &mut chart,
            &mut drawn,
            c.points.clone(),
            Line::curve(c.color, c.dashed),
            c.label,
        )?;
    }
    extra(&mut chart, &mut drawn)?;
    legend(&mut chart, &drawn)
}

const SIM: RGBColor = RGBColor(0, 0, 0);
const EXACT: RGBColor = RGBColor(31, 119, 180);
const EQ7: RGBColor = RGBColor(214, 39, 40);

/// A log-log chart on `area` spanning `xs` and `ys`, its mesh drawn, its ticks labelled by
/// [`LogTicks`].
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
    let (w, h) = plot_size(area, true);
    let x_ticks = LogTicks::new((x0, x1), w, X_TICK_ROOM_PX);
    let y_ticks = LogTicks::new((y0, y1), h, Y_TICK_ROOM_PX);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, font(DESC_PX))
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(Y_LABEL_AREA_PX)
        .build_cartesian_2d(x_ticks.axis((x0, x1)), y_ticks.axis((y0, y1)))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(x_ticks.values.len().max(1))
        .y_labels(y_ticks.values.len().max(1))
        .x_label_formatter(&LogTicks::label)
        .y_label_formatter(&LogTicks::label)
        .house_style()
        .draw()
        .map_err(err)?;
    Ok(chart)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A plotting area of 800 x 300 px at (100, 50), as [`legend_spot`] takes it.
    fn area() -> (Range<i32>, Range<i32>) {
        (100..900, 50..350)
    }

    #[test]
    fn the_legend_leaves_a_curve_s_start_free() {
        // A falling curve from the upper left, as r(t): the upper left holds its start, the
        // upper right is free.
        let falling = vec![vec![(100, 55), (500, 150), (900, 345)]];
        let at = legend_spot(area(), (200, 80), &falling);
        assert_eq!(at, SeriesLabelPosition::UpperRight);
        // A rising curve from the lower left, as x'(t) near its end: the upper left is free.
        let rising = vec![vec![(100, 345), (700, 300), (900, 55)]];
        let at = legend_spot(area(), (200, 80), &rising);
        assert_eq!(at, SeriesLabelPosition::UpperLeft);
    }

    #[test]
    fn a_line_counts_by_its_length_not_its_samples() {
        // Two samples only, across the top: both upper corners are covered between them.
        let across = vec![vec![(100, 60), (900, 60)]];
        let at = legend_spot(area(), (200, 80), &across);
        assert_eq!(at, SeriesLabelPosition::LowerRight);
    }

    #[test]
    fn with_no_place_free_the_legend_takes_the_least_covered() {
        // Markers everywhere, thinner in the lower left.
        let mut ink = Vec::new();
        for x in (100..900).step_by(10) {
            for y in (50..350).step_by(10) {
                if x > 350 || y < 250 || (x + y) % 40 == 0 {
                    ink.push(vec![(x, y)]);
                }
            }
        }
        let at = legend_spot(area(), (200, 80), &ink);
        assert_eq!(at, SeriesLabelPosition::LowerLeft);
    }

    #[test]
    fn a_line_chart_s_legend_is_drawn_off_its_curve() {
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (900, 400)).into_drawing_area();
            let falling: Vec<(f64, f64)> = (0..=100)
                .map(|i| (f64::from(i), 1.0 - (f64::from(i) / 100.0).powi(4)))
                .collect();
            let curve = Curve {
                label: "simulation",
                points: falling,
                color: SIM,
                dashed: false,
            };
            line_chart(&root, "r", "t (s)", "r (m)", &[curve], |_, _| Ok(())).unwrap();
            root.present().unwrap();
        }
        // The legend's box (drawn at opacity 0.85) and the curve's first point (the one
        // line of width 2).
        let tag_at = |mark: &str, open: &str| {
            let i = svg
                .find(mark)
                .unwrap_or_else(|| panic!("no {mark} in {svg}"));
            let start = svg[..i].rfind(open).unwrap();
            svg[start..].split_once('>').unwrap().0.to_owned()
        };
        let rect = tag_at("opacity=\"0.85\"", "<rect");
        let line = tag_at("stroke-width=\"2\"", "<polyline");
        let num = |key: &str| -> f64 {
            let v = rect.split(&format!(" {key}=\"")).nth(1).unwrap();
            v.split('"').next().unwrap().parse().unwrap()
        };
        let first = line.split("points=\"").nth(1).unwrap();
        let (x, y) = first
            .split_whitespace()
            .next()
            .unwrap()
            .split_once(',')
            .unwrap();
        let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
        let [bx, by, bw, bh] = ["x", "y", "width", "height"].map(num);
        assert!(
            !(x >= bx && x <= bx + bw && y >= by && y <= by + bh),
            "the legend ({bx}, {by}, {bw} x {bh}) covers the curve's start ({x}, {y})"
        );
    }
}
