//! `shares-KEY.svg`: where the final bang's energy goes against a physical key's own
//! values: what it dissipated, each mechanism's share, and what is left moving, one line
//! per setting of the other keys, each point an ensemble's mean with its standard error.
//! A point whose numerical share exceeds [`NUMERICAL_MARK`] is ringed, never dropped.

use std::path::Path;

use plotters::prelude::*;

use plotters::coord::types::RangedCoordf64;

use super::{
    DESC_PX, Drawn, HouseStyle, LEGEND_PX, Line, LogTicks, X_LABEL_AREA_PX, X_TICK_ROOM_PX,
    Y_LABEL_AREA_PX, color, draw_line, err, font, legend, log_range, plot_size, range,
};
use crate::study::analysis::{BANG_OBSERVABLES, BangStudy, NUMERICAL_MARK, Reading};
use crate::study::sweep::Col;

/// The observables drawn, one panel each: what the bang dissipated of what it received,
/// its shares by mechanism (the floor's impacts, its friction, the model's discards, the
/// numerical part), and what is still moving at its end.
const PANELS: [Reading; 6] = [
    Reading::DissipatedOfKineticIn,
    Reading::Column(Col::BangFloorNormalOf),
    Reading::Column(Col::BangFloorFrictionOf),
    Reading::Column(Col::BangFreezeOf),
    crate::study::analysis::NUMERICAL,
    Reading::Column(Col::BangStillMovingOf),
];

/// The dash of the `i`-th value of the second key (solid first).
fn dash(i: usize, c: RGBColor) -> Line {
    match i % 3 {
        0 => Line::solid(c, 2),
        1 => Line::dashed(c, 2, 8, 5),
        _ => Line::dashed(c, 2, 2, 4),
    }
}

/// Each study's line and label: the colour by the settings of every other key but the
/// last, the dash by the last one's (`k=v k=v` groups), a key every study shares the
/// setting of left out of the labels.
fn styles(studies: &[&BangStudy]) -> Vec<(Line, String)> {
    let parts = |b: &&BangStudy| -> Vec<String> {
        b.group
            .split(' ')
            .filter(|p| !p.is_empty())
            .map(str::to_owned)
            .collect()
    };
    let all: Vec<Vec<String>> = studies.iter().map(parts).collect();
    let shared = |p: &String| all.iter().all(|g| g.contains(p));
    let index = |seen: &mut Vec<String>, v: String| {
        seen.iter().position(|s| *s == v).unwrap_or_else(|| {
            seen.push(v);
            seen.len() - 1
        })
    };
    let (mut colours, mut dashes) = (Vec::new(), Vec::new());
    all.iter()
        .map(|g| {
            let own: Vec<String> = g.iter().filter(|p| !shared(p)).cloned().collect();
            let label = if own.is_empty() {
                "runs".to_owned()
            } else {
                own.join(" ")
            };
            let line = match own.split_last() {
                Some((last, head)) if !head.is_empty() => {
                    let c = color(index(&mut colours, head.join(" ")));
                    dash(index(&mut dashes, last.clone()), c)
                }
                _ => Line::solid(color(index(&mut colours, label.clone())), 2),
            };
            (line, label)
        })
        .collect()
}

/// The picture's title and what its points and rings mean.
fn draw_head(
    head: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    key: &str,
    studies: &[&BangStudy],
    title: &str,
) -> anyhow::Result<()> {
    let marked = studies
        .iter()
        .any(|b| (0..b.values.len()).any(|i| b.numerical_marked(i)));
    let with = studies
        .first()
        .filter(|b| !b.tied.is_empty())
        .map(|b| format!(" (with {})", b.tied.join(", ")))
        .unwrap_or_default();
    head.draw(&Text::new(
        format!("{title}: where the bang's energy goes against {key}{with}"),
        (20, 8),
        font(DESC_PX),
    ))
    .map_err(err)?;
    head.draw(&Text::new(
        format!(
            "each point the mean ± standard error of its ensemble{}",
            if marked {
                format!(
                    "; ringed in red: the numerical share exceeds {} %",
                    100.0 * NUMERICAL_MARK
                )
            } else {
                String::new()
            }
        ),
        (20, 36),
        font(LEGEND_PX),
    ))
    .map_err(err)?;
    Ok(())
}

/// One point of a line: the setting's value, the mean, its standard error (0 where it has
/// none) and the setting's place in its study.
type Point = (f64, f64, f64, usize);

/// `shares-KEY.svg` for the `studies` of one physical `key` (one per setting of the others).
/// Values spanning a decade or more, all positive, go on a log axis.
pub(super) fn shares_plot(
    path: &Path,
    key: &str,
    studies: &[&BangStudy],
    title: &str,
) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (1100, 1250)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (head, body) = root.split_vertically(64);
    draw_head(&head, key, studies, title)?;
    let lines = styles(studies);
    let (x0, x1) = range(studies.iter().flat_map(|b| b.values.iter().copied()));
    let (lo, hi) = studies
        .iter()
        .flat_map(|b| b.values.iter().copied())
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let log = lo > 0.0 && hi >= 10.0 * lo;
    for (panel, reading) in body.split_evenly((3, 2)).iter().zip(PANELS) {
        let k = BANG_OBSERVABLES
            .iter()
            .position(|o| o.1 == reading)
            .expect("a panel's observable is observed");
        let points: Vec<Vec<Point>> = studies
            .iter()
            .map(|b| {
                (0..b.values.len())
                    .map(|i| {
                        let s = b.se[k][i];
                        let s = if s.is_finite() { s } else { 0.0 };
                        (b.values[i], b.mean[k][i], s, i)
                    })
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .collect()
            })
            .collect();
        let (y0, y1) = range(points.iter().flatten().flat_map(|p| [p.1 - p.2, p.1 + p.2]));
        let builder = || {
            let mut b = ChartBuilder::on(panel);
            b.caption(BANG_OBSERVABLES[k].0, font(DESC_PX))
                .margin(8)
                .x_label_area_size(X_LABEL_AREA_PX)
                .y_label_area_size(Y_LABEL_AREA_PX);
            b
        };
        let first = reading == PANELS[0];
        if log {
            let (h0, h1) = log_range([lo, hi]);
            let ticks = LogTicks::new((h0, h1), plot_size(panel, true).0, X_TICK_ROOM_PX);
            let mut chart = builder()
                .build_cartesian_2d(ticks.axis((h0, h1)), y0..y1)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(key)
                .y_labels(6)
                .x_labels(ticks.values.len().max(1))
                .x_label_formatter(&LogTicks::label)
                .house_style()
                .draw()
                .map_err(err)?;
            draw_series(&mut chart, studies, &lines, &points, first)?;
        } else {
            let mut chart = builder().build_cartesian_2d(x0..x1, y0..y1).map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(key)
                .y_labels(6)
                .house_style()
                .draw()
                .map_err(err)?;
            draw_series(&mut chart, studies, &lines, &points, first)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Each study's line, error bars and rings on `chart`, and, on the `first` panel, the one
/// legend: every panel draws the same lines.
fn draw_series<'a, X>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, RangedCoordf64>>,
    studies: &[&BangStudy],
    lines: &[(Line, String)],
    points: &[Vec<Point>],
    first: bool,
) -> anyhow::Result<()>
where
    X: Ranged<ValueType = f64>,
{
    let mut drawn = Drawn::default();
    for ((b, (line, label)), pts) in studies.iter().zip(lines).zip(points) {
        let c = line.color;
        let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
        draw_line(chart, &mut drawn, xy, *line, label.clone())?;
        let ends: Vec<(f64, f64)> = pts
            .iter()
            .flat_map(|&(x, m, s, _)| [(x, m - s), (x, m + s)])
            .collect();
        drawn.book_ink(chart, &ends);
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, m, s, _)| ErrorBar::new_vertical(x, m - s, m, m + s, c.filled(), 6)),
            )
            .map_err(err)?;
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| b.numerical_marked(p.3))
                    .map(|&(x, m, _, _)| Circle::new((x, m), 8, RED.stroke_width(2))),
            )
            .map_err(err)?;
    }
    if first {
        legend(chart, &drawn)?;
    }
    Ok(())
}
